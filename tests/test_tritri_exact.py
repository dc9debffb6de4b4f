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


def test_exact_fallback_agrees_with_rational_arithmetic_across_magnitudes():
    """The integer evaluation (one power-of-two scale for both triangles) decides as rational
    arithmetic does, with coordinates of very different magnitudes in one pair (tiny offsets on
    large coordinates, subnormal-sized ones), touching, coplanar and coincident cases; a
    non-finite coordinate shares no point."""
    from fractions import Fraction

    def rational(p0, p1, p2, q0, q1, q2):  # the same predicates on Fractions, as a reference
        import inflo.tools.collide.exact as ex
        P = [tuple(Fraction(float(c)) for c in v) for v in (p0, p1, p2)]
        Q = [tuple(Fraction(float(c)) for c in v) for v in (q0, q1, q2)]
        s = [ex._orient3d(*P, q) for q in Q]
        if min(s) > 0 or max(s) < 0:
            return False
        t = [ex._orient3d(*Q, p) for p in P]
        if min(t) > 0 or max(t) < 0:
            return False
        return (any(ex._seg_tri(P[k], P[(k + 1) % 3], *Q) for k in range(3))
                or any(ex._seg_tri(Q[k], Q[(k + 1) % 3], *P) for k in range(3)))

    rng = np.random.default_rng(3)
    hits = 0
    for k in range(600):
        x = rng.integers(-2, 3, (6, 3)).astype(float) * rng.choice([1.0, 1e-9, 1e6, 1e-300])
        if k % 4 == 0:
            x[3] = x[0]  # a coincident vertex
        if k % 4 == 1:
            x[:, 2] = 0.0  # coplanar
        if k % 4 == 2:
            x[3:] += rng.choice([0.0, 2.0 ** -40])  # a tiny offset on the second triangle
        want = rational(*x)
        assert triangles_intersect_exact(*x) == want
        hits += want
    assert 0 < hits < 600
    x = np.zeros((6, 3))
    x[1, 0] = x[2, 1] = x[4, 0] = x[5, 1] = 1.0
    assert triangles_intersect_exact(*x)
    x[0, 0] = np.nan
    assert not triangles_intersect_exact(*x)


def test_separating_plane_decides_pairs_the_edge_determinants_cannot():
    """Two concentric cylinders with aligned seams: their vertical edges are coplanar with each
    other (edge-edge orient3d exactly 0), so the pairs are not 'certified'; the plane of one
    triangle still certainly separates the other, so the float filter decides them (disjoint),
    in agreement with the exact test, and none reaches the slow exact fallback."""
    import numpy as np

    from inflo.tools.collide.exact import triangles_intersect_exact
    from inflo.tools.collide.tritri import certified, separated

    def cylinder(r, n=10, h=1.0):
        a = 2 * np.pi * np.arange(n) / n
        v = np.concatenate([np.stack([r * np.cos(a), np.zeros(n), r * np.sin(a)], 1),
                            np.stack([r * np.cos(a), np.full(n, h), r * np.sin(a)], 1)])
        k = np.arange(n)
        f = np.concatenate([np.stack([k, (k + 1) % n, n + k], 1), np.stack([(k + 1) % n, n + (k + 1) % n, n + k], 1)])
        return v, f

    vo, fo = cylinder(0.1)
    vi, fi = cylinder(0.035)
    undecided = 0
    for a in fo:
        for b in fi:
            P, Q = vo[a], vi[b]
            exact = triangles_intersect_exact(*P, *Q)
            assert not exact
            if not certified(*P, *Q):
                undecided += 1
                assert separated(*P, *Q)
    assert undecided > 0  # the case the separating plane is there for
    # and a pair that does intersect is never called separated
    rng = np.random.default_rng(2)
    for _ in range(2000):
        P, Q = rng.normal(size=(3, 3)), rng.normal(size=(3, 3))
        if separated(*P, *Q):
            assert not triangles_intersect_exact(*P, *Q)


def test_separated_never_claims_an_intersecting_pair_and_decides_flat_facets():
    """Coplanar pairs (two triangles of one flat facet, touching or not) and random near-degenerate
    pairs: whenever ``separated`` says disjoint, the exact test agrees; disjoint triangles of one
    plane are decided without the exact fallback."""
    import numpy as np

    from inflo.tools.collide.exact import triangles_intersect_exact
    from inflo.tools.collide.tritri import separated

    rng = np.random.default_rng(11)
    decided = 0
    for _ in range(3000):
        # a random plane, two random triangles in it (on a grid so touching cases occur)
        o, u, v = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
        pts = rng.integers(0, 4, size=(6, 2)).astype(float)
        P = [o + a * u + b * v for a, b in pts[:3]]
        Q = [o + a * u + b * v for a, b in pts[3:]]
        if separated(*P, *Q):
            decided += 1
            assert not triangles_intersect_exact(*P, *Q)
    assert decided > 300
    # a flat facet's two disjoint triangles (rows of a straight cylinder column)
    P = [np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])]
    Q = [np.array([2.0, 1.0, 0.0]), np.array([3.0, 1.0, 0.0]), np.array([2.0, 2.0, 0.0])]
    assert separated(*P, *Q) and not triangles_intersect_exact(*P, *Q)
    # touching at a vertex: not separated
    Q = [np.array([1.0, 0.0, 0.0]), np.array([2.0, 0.0, 0.0]), np.array([1.0, 1.0, 0.0])]
    assert not separated(*P, *Q) and triangles_intersect_exact(*P, *Q)
    for _ in range(3000):
        P = rng.normal(size=(3, 3))
        Q = P[rng.integers(0, 3, 3)] + rng.normal(size=(3, 3)) * 10.0 ** rng.integers(-12, 0)
        if separated(*P, *Q):
            assert not triangles_intersect_exact(*P, *Q)


@pytest.mark.parametrize("below", [10**9, 0], ids=["serial", "parallel"])
def test_serial_and_parallel_float_tests_find_the_same_pairs(below, monkeypatch):
    """intersecting_pairs runs the float test serially below SERIAL_TEST_BELOW candidate pairs;
    both kernels report the brute-force pairs of a random soup."""
    from inflo.tools.collide import tritri

    monkeypatch.setattr(tritri, "SERIAL_TEST_BELOW", below)
    rng = np.random.default_rng(21)
    x = rng.uniform(0, 1, (300, 3))
    tri = np.arange(300, dtype=np.int32).reshape(100, 3)
    x[tri[:, 1]] = x[tri[:, 0]] + rng.normal(scale=0.15, size=(100, 3))
    x[tri[:, 2]] = x[tri[:, 0]] + rng.normal(scale=0.15, size=(100, 3))
    got = intersecting_pairs(x, tri)
    assert len(got) > 10
    np.testing.assert_array_equal(got, intersecting_pairs_brute(x, tri))


def test_skip_parts_leaves_out_joined_parts_only():
    """Three parts, each a triangle, all crossing each other's: with ``skip_parts`` marking parts 0
    and 1 as joined, their pair is not reported; the others are, as without it."""
    rng = np.random.default_rng(3)
    x = np.array([[-1, 0, -1], [1, 0, -1], [0, 0, 1],      # part 0: in the plane y = 0
                  [0, -1, -1], [0, 1, -1], [0, 0.2, 1],    # part 1: crossing it along x = 0
                  [-1, -1, 0], [1, -1, 0], [0, 1, 0.1]],   # part 2: crossing both
                 dtype=np.float64)
    tri = np.arange(9, dtype=np.int32).reshape(3, 3)
    part = np.array([0, 1, 2])
    full = intersecting_pairs(x, tri, tri_part=part)
    assert full.tolist() == [[0, 1], [0, 2], [1, 2]]
    skip = np.zeros((3, 3), bool)
    skip[0, 1] = skip[1, 0] = True
    assert intersecting_pairs(x, tri, tri_part=part, skip_parts=skip).tolist() == [[0, 2], [1, 2]]
    # the same with the triangles' vertices jittered and the parts in any order
    xj = x + 1e-9 * rng.standard_normal(x.shape)
    assert intersecting_pairs(xj, tri, tri_part=part[::-1].copy(), skip_parts=skip).tolist() == [[0, 1], [0, 2]]
