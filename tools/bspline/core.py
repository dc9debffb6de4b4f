"""Clamped uniform B-spline basis, curves and tensor-product surfaces (thesis 2.2: petals are
clamped B-spline surfaces).

Everything is expressed through **basis matrices**: for parameters ``t`` (k values) and a curve of
``n`` control points, ``basis_matrix`` returns the dense ``(k, n)`` matrix ``N[a, i] = N_i(t_a)``,
so a curve is ``N @ P`` and a surface sampled at scattered ``(u, v)`` points is ``W @ P.reshape(-1, 3)``
with ``W = surface_weights(...)``. ``polygonize`` builds ``W`` once per organ (its (u, v) samples
never change) and evaluates every frame, every petal copy, with one matrix product: vectorized
numpy, no per-point Python loop and nothing to compile. The products are
:func:`inflo.tools.common.linalg.matmul`'s fixed-order sums, not BLAS, so a surface has the same
bits on every processor.

Knot vectors are clamped (end-point interpolating) and uniform on [0, 1]: ``p + 1`` zeros, the
interior knots ``i / (n - p)``, ``i = 1 .. n - p - 1``, then ``p + 1`` ones (formats/floret.md,
``degree``). The last knot span is closed on the right, so ``t = 1`` gives the last control point
(a half-open basis would vanish there).
"""
from __future__ import annotations

import numpy as np

from inflo.tools.common import linalg as la

__all__ = [
    "MAX_DEGREE",
    "clamped_knots",
    "basis_matrix",
    "curve_points",
    "surface_weights",
    "surface_points",
    "surface_grid",
]

MAX_DEGREE = 5


def _check(n_ctrl: int, degree: int) -> None:
    if not 1 <= int(degree) <= MAX_DEGREE:
        raise ValueError(f"B-spline degree must be in 1..{MAX_DEGREE}, got {degree}")
    if int(n_ctrl) < int(degree) + 1:
        raise ValueError(f"a degree-{degree} B-spline needs at least {degree + 1} control points, got {n_ctrl}")


def clamped_knots(n_ctrl: int, degree: int) -> np.ndarray:
    """Clamped uniform knot vector on [0, 1] for ``n_ctrl`` control points.

    Returns
    -------
    (n_ctrl + degree + 1,) float64
        ``degree + 1`` zeros, ``i / (n_ctrl - degree)`` for ``i = 1 .. n_ctrl - degree - 1``,
        ``degree + 1`` ones.
    """
    _check(n_ctrl, degree)
    p, n = int(degree), int(n_ctrl)
    spans = n - p
    interior = np.arange(1, spans, dtype=np.float64) / spans
    return np.concatenate([np.zeros(p + 1), interior, np.ones(p + 1)])


def basis_matrix(n_ctrl: int, degree: int, t) -> np.ndarray:
    """Dense B-spline basis ``N[a, i] = N_{i,p}(t_a)`` of the clamped uniform knot vector.

    Cox-de Boor recursion (Piegl & Tiller, algorithm A2.2), vectorized over ``t``. Each row sums
    to 1 (partition of unity) and has at most ``degree + 1`` non-zeros.

    Parameters
    ----------
    n_ctrl : int
        Number of control points (> degree).
    degree : int
        1..5.
    t : (k,) array_like of float
        Parameters; clamped to [0, 1].

    Returns
    -------
    (k, n_ctrl) float64
    """
    _check(n_ctrl, degree)
    p, n = int(degree), int(n_ctrl)
    knots = clamped_knots(n, p)
    t = np.clip(np.asarray(t, dtype=np.float64).reshape(-1), 0.0, 1.0)
    # span index s with knots[s] <= t < knots[s + 1], the last span closed: p <= s <= n - 1
    span = np.clip(np.searchsorted(knots, t, side="right") - 1, p, n - 1)
    k = len(t)
    nz = np.zeros((k, p + 1))
    nz[:, 0] = 1.0
    left = np.zeros((k, p + 1))
    right = np.zeros((k, p + 1))
    for j in range(1, p + 1):
        left[:, j] = t - knots[span + 1 - j]
        right[:, j] = knots[span + j] - t
        saved = np.zeros(k)
        for r in range(j):
            denom = right[:, r + 1] + left[:, j - r]
            temp = np.divide(nz[:, r], denom, out=np.zeros(k), where=denom != 0.0)
            nz[:, r] = saved + right[:, r + 1] * temp
            saved = left[:, j - r] * temp
        nz[:, j] = saved
    out = np.zeros((k, n))
    cols = span[:, None] - p + np.arange(p + 1)[None, :]
    np.put_along_axis(out, cols, nz, axis=1)
    return out


def curve_points(control, degree: int, t) -> np.ndarray:
    """Points of the clamped uniform B-spline curve over ``control`` ((n, d)) at ``t`` ((k,))."""
    c = np.asarray(control, dtype=np.float64)
    return la.matmul(basis_matrix(len(c), degree, t), c)


def surface_weights(nv: int, nu: int, degree_u: int, degree_v: int, u, v) -> np.ndarray:
    """Weights mapping a ``(nv, nu)`` control net to surface points at scattered ``(u, v)``.

    ``S(u, v) = sum_j sum_i N_j(v) M_i(u) P[j, i]``: rows of control points run in v (base to
    tip), columns in u (formats/floret.md).

    Parameters
    ----------
    nv, nu : int
        Control points in v and in u.
    degree_u, degree_v : int
    u, v : (k,) array_like
        Parameters of the k samples.

    Returns
    -------
    (k, nv * nu) float64
        ``W @ P.reshape(nv * nu, 3)`` gives the k points.
    """
    bu = basis_matrix(nu, degree_u, u)
    bv = basis_matrix(nv, degree_v, v)
    if bu.shape[0] != bv.shape[0]:
        raise ValueError("u and v must have the same length")
    return (bv[:, :, None] * bu[:, None, :]).reshape(len(bu), nv * nu)


def surface_points(control_net, degree_u: int, degree_v: int, u, v) -> np.ndarray:
    """Surface points at scattered parameters.

    Parameters
    ----------
    control_net : (nv, nu, d) or (c, nv, nu, d) array_like
        One control net, or c nets of the same shape (e.g. the petal copies of an organ).
    u, v : (k,) array_like

    Returns
    -------
    (k, d) or (c, k, d) float64
    """
    net = np.asarray(control_net, dtype=np.float64)
    nv, nu, d = net.shape[-3:]
    w = surface_weights(nv, nu, degree_u, degree_v, u, v)
    if net.ndim == 3:
        return la.matmul(w, net.reshape(nv * nu, d))
    return la.matmul(w[None], net.reshape(-1, nv * nu, d))


def surface_grid(control_net, degree_u: int, degree_v: int, us, vs) -> np.ndarray:
    """Surface points on the isoparametric grid ``vs x us``.

    Returns
    -------
    (len(vs), len(us), d) float64
        ``out[b, a] = S(us[a], vs[b])``.
    """
    net = np.asarray(control_net, dtype=np.float64)
    nv, nu = net.shape[:2]
    bu = basis_matrix(nu, degree_u, us)
    bv = basis_matrix(nv, degree_v, vs)
    # sum over i (u) first, then over j (v), each in index order
    rows = la.matmul(bu, net)  # (nv, len(us), d): the u-curves of every control row
    return la.matmul(bv, rows.reshape(nv, -1)).reshape(len(bv), len(bu), -1)
