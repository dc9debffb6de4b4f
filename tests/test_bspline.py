"""The shared B-spline core (tools/bspline) against scipy.interpolate."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import BSpline

from inflo.tools.bspline import (
    basis_matrix,
    clamped_knots,
    curve_points,
    surface_grid,
    surface_points,
    surface_weights,
)


@pytest.mark.parametrize("degree", [1, 2, 3, 4, 5])
@pytest.mark.parametrize("extra", [0, 1, 4])
def test_curve_matches_scipy(degree, extra):
    n = degree + 1 + extra
    rng = np.random.default_rng(degree * 10 + extra)
    c = rng.normal(size=(n, 3))
    t = np.linspace(0.0, 1.0, 53)
    ref = BSpline(clamped_knots(n, degree), c, degree)(t)
    np.testing.assert_allclose(curve_points(c, degree, t), ref, atol=1e-13)


def test_knots_clamped_uniform():
    np.testing.assert_array_equal(clamped_knots(7, 3), [0, 0, 0, 0, 0.25, 0.5, 0.75, 1, 1, 1, 1])
    np.testing.assert_array_equal(clamped_knots(2, 1), [0, 0, 1, 1])


@pytest.mark.parametrize("degree", [1, 3, 5])
def test_basis_partition_of_unity_and_endpoints(degree):
    n = degree + 3
    t = np.linspace(0.0, 1.0, 101)
    b = basis_matrix(n, degree, t)
    np.testing.assert_allclose(b.sum(axis=1), 1.0, atol=1e-14)
    assert (b >= -1e-15).all()
    assert (np.count_nonzero(np.abs(b) > 0, axis=1) <= degree + 1).all()
    # clamped: the curve interpolates its end control points, t = 1 included (closed last span)
    assert b[0, 0] == 1.0 and b[-1, -1] == 1.0


@pytest.mark.parametrize("du,dv", [(1, 1), (2, 3), (3, 3), (4, 2), (5, 5)])
def test_surface_grid_matches_scipy_tensor_product(du, dv):
    nu, nv = du + 2, dv + 3
    rng = np.random.default_rng(du * 7 + dv)
    net = rng.normal(size=(nv, nu, 3))
    us = np.linspace(0.0, 1.0, 17)
    vs = np.linspace(0.0, 1.0, 13)
    # scipy: first along v for each column, then along u
    along_v = BSpline(clamped_knots(nv, dv), net, dv)(vs)  # (len vs, nu, 3)
    ref = BSpline(clamped_knots(nu, du), np.swapaxes(along_v, 0, 1), du)(us)  # (len us, len vs, 3)
    ref = np.swapaxes(ref, 0, 1)
    np.testing.assert_allclose(surface_grid(net, du, dv, us, vs), ref, atol=1e-13)
    # scattered points agree with the grid
    uu, vv = np.meshgrid(us, vs)
    pts = surface_points(net, du, dv, uu.ravel(), vv.ravel()).reshape(len(vs), len(us), 3)
    np.testing.assert_allclose(pts, ref, atol=1e-13)
    # several nets at once
    two = surface_points(np.stack([net, 2 * net]), du, dv, uu.ravel(), vv.ravel())
    np.testing.assert_allclose(two[1], 2 * two[0], atol=1e-12)
    assert surface_weights(nv, nu, du, dv, uu.ravel(), vv.ravel()).shape == (uu.size, nv * nu)


def test_bad_degree():
    with pytest.raises(ValueError):
        clamped_knots(3, 6)
    with pytest.raises(ValueError):
        basis_matrix(3, 3, [0.5])
