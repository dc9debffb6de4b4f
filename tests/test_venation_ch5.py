"""Runions ch. 5 in ``venation``: source placement at the centre of the largest empty circle (sec.
5.2.2), the events file, local-to-global growth (sec. 5.2.1, eq. 5.1)."""
from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from inflo.tools.venation.blade import blade_from_points
from inflo.tools.venation.cli import main
from inflo.tools.venation.placement import largest_empty_circles

SQUARE = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
HEX = np.array([[0.0, 0.0], [6.0, 2.0], [8.0, 8.0], [3.0, 12.0], [-3.0, 12.0], [-8.0, 8.0], [-6.0, 2.0]])


def _brute(poly, pts, h):
    """The largest circle empty of ``pts`` centred in the polygon, by a grid of centres ``h`` apart
    (margin included, by its sampled edges)."""
    blade = blade_from_points(poly)
    lo, hi = poly.min(0), poly.max(0)
    xs, ys = np.meshgrid(np.arange(lo[0], hi[0] + h, h), np.arange(lo[1], hi[1] + h, h))
    g = np.column_stack([xs.ravel(), ys.ravel()])
    g = g[blade.contains(g)]
    q = np.roll(poly, -1, axis=0)
    t = np.linspace(0, 1, 200, endpoint=False)
    edge = np.vstack([p + (b - p) * t[:, None] for p, b in zip(poly, q)])
    g = np.vstack([g, edge])
    d = np.sqrt(((g[:, None, :] - pts[None]) ** 2).sum(-1)).min(1)
    i = int(np.argmax(d))
    return d[i], g[i]


@pytest.mark.parametrize("poly,seed,n", [(SQUARE, 1, 12), (SQUARE, 2, 3), (HEX, 3, 20), (HEX, 4, 1), (HEX, 5, 2)])
def test_largest_empty_circle_matches_brute_force(poly, seed, n):
    rng = np.random.default_rng(seed)
    blade = blade_from_points(poly)
    lo, hi = poly.min(0), poly.max(0)
    pts = lo + (hi - lo) * rng.random((4 * n, 2))
    pts = pts[blade.contains(pts)][:n]
    nodes, srcs = pts[: (len(pts) + 1) // 2], pts[(len(pts) + 1) // 2:]
    got = largest_empty_circles(poly, blade.contains, nodes, srcs, 0.01, 0.01, 1)
    assert got.shape == (1, 3)
    want, _ = _brute(poly, pts, 0.02)
    # the circle is empty, centred in (or on) the blade, and as large as the brute force's within the grid
    d = np.sqrt(((pts - got[0, :2]) ** 2).sum(1)).min()
    assert got[0, 2] == pytest.approx(d)
    assert got[0, 2] >= want - 0.03
    assert got[0, 2] <= want + 0.03


def test_largest_empty_circles_repeat_until_too_small():
    blade = blade_from_points(SQUARE)
    got = largest_empty_circles(SQUARE, blade.contains, np.array([[5.0, 0.0]]), np.zeros((0, 2)), 2.0, 2.0, 10_000)
    assert len(got) > 3
    assert np.all(np.diff(got[:, 2]) <= 1e-12)  # largest first
    assert got[-1, 2] > 2.0
    pts = np.vstack([[[5.0, 0.0]], got[:, :2]])
    d = np.sqrt(((pts[:, None] - pts[None]) ** 2).sum(-1)) + np.eye(len(pts)) * 1e9
    assert d.min() > 2.0
    # nothing more fits: the brute force finds no circle over b_s
    left, _ = _brute(SQUARE, pts, 0.05)
    assert left <= 2.0 + 0.05
    again = largest_empty_circles(SQUARE, blade.contains, np.array([[5.0, 0.0]]), np.zeros((0, 2)), 2.0, 2.0, 10_000)
    assert np.array_equal(got, again)  # deterministic
