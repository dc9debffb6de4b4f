"""The static intersection test is exact: certified float signs, rational fallback otherwise."""
from __future__ import annotations

import numpy as np
import pytest

from inflo.tools.collide.exact import triangles_intersect_exact
from inflo.tools.collide.tritri import certified, intersecting_pairs, intersecting_pairs_brute, triangles_intersect

TWO = np.array([[0, 1, 2], [3, 4, 5]], dtype=np.int32)


@pytest.mark.parametrize("A, B", [
    # nearly coplanar, apart: float64 determinants alone said "intersecting" (found by the lily build)
    ([[2.410994, 1.061861, -0.380031], [2.611765, 1.040205, -0.285624], [2.611765, 1.040205, -0.367197]],
     [[2.611765, 1.040205, -0.218215], [2.410994, 1.061861, -0.295605], [2.410994, 1.061861, -0.225838]]),
    # from a Loop-subdivided corrugated strip: one vertex on the other's plane, outside it
    ([[1.75, 0.5, -6.938893903907228e-18], [2.0, 0.75, 0.14999999999999997], [1.75, 0.75, 0.0]],
     [[1.5, 0.75, -0.14999999999999997], [1.75, 1.0, 0.0], [1.5, 1.0, -0.14999999999999997]]),
])
def test_nearly_coplanar_disjoint_triangles_are_not_reported(A, B):
    x = np.vstack([A, B]).astype(np.float64)
    assert not certified(*x)
    assert not triangles_intersect_exact(*x)
    assert len(intersecting_pairs(x, TWO)) == 0 and len(intersecting_pairs_brute(x, TWO)) == 0


def test_coplanar_overlapping_and_touching_triangles_are_reported():
    overlap = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 0], [2, 0.2, 0], [0.2, 2, 0]], float)
    touch = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.5, 0.5, 0], [1, 1, 0], [0.5, 1.5, 0]], float)
    apart = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.6, 0.6, 0], [1, 1, 0], [0.6, 1.5, 0]], float)
    assert len(intersecting_pairs(overlap, TWO)) == 1
    assert len(intersecting_pairs(touch, TWO)) == 1  # closed triangles: a shared point counts
    assert len(intersecting_pairs(apart, TWO)) == 0


def test_float_path_agrees_with_rational_arithmetic_on_random_pairs():
    rng = np.random.default_rng(7)
    decided = 0
    for _ in range(400):
        x = rng.normal(size=(6, 3))
        if rng.random() < 0.3:  # snap to a grid: many exact coincidences and coplanarities
            x = np.round(x * 2) / 2
        got = len(intersecting_pairs_brute(x, TWO)) == 1
        assert got == triangles_intersect_exact(*x)
        if certified(*x):
            decided += 1
            assert triangles_intersect(*x) == got
    assert decided > 200
