"""Collision detection and response (thesis ch. 4, appendix B): narrow phase on hand-built cases with
known time of impact, cross-checks against brute-force references and the ipctk CCD, broad phase,
the exact static triangle-triangle test, collision constraints and the resolution loop."""
from __future__ import annotations

import numpy as np
import pytest

from inflo.tools.collide import (
    box_pairs,
    cubic_roots_01,
    cubic_vertex_triangle,
    cull_cubic,
    detect_collisions,
    edge_edge_ccd,
    intersecting_pairs,
    intersecting_pairs_between,
    intersecting_pairs_brute,
    intersecting_pairs_with,
    resolve_collisions,
    solve_ee_collision_constraint,
    solve_vt_collision_constraint,
    triangle_boxes,
    triangles_intersect,
    vertex_triangle_ccd,
)
from inflo.tools.collide.broad import box_pairs_brute, lattice_cell_size
from inflo.tools.pbd import mesh_edges

A = np.array([0.0, 0.0, 0.0])
B = np.array([1.0, 0.0, 0.0])
C = np.array([0.0, 1.0, 0.0])
TOL = 1e-9


def v(*xs):
    return np.array(xs, dtype=float)


def vt(p0, p1, a0=A, b0=B, c0=C, a1=None, b1=None, c1=None, tol=TOL):
    out = np.zeros(4)
    n = vertex_triangle_ccd(p0, a0, b0, c0, p1, a0 if a1 is None else a1, b0 if b1 is None else b1,
                            c0 if c1 is None else c1, tol, out)
    return n, out


def ee(a0, b0, c0, d0, a1, b1, c1, d1, tol=TOL):
    out = np.zeros(4)
    n = edge_edge_ccd(a0, b0, c0, d0, a1, b1, c1, d1, tol, out)
    return n, out


# -- narrow phase: hand-built cases ------------------------------------------------------------------


def test_vertex_through_face_centre():
    n, out = vt(v(1 / 3, 1 / 3, 1.0), v(1 / 3, 1 / 3, -3.0))
    assert n == 1
    assert out[0] == pytest.approx(0.25, abs=1e-14)
    np.testing.assert_allclose(out[1:], [1 / 3, 1 / 3, 1 / 3], atol=1e-12)


def test_vertex_missing_the_face_and_moving_triangle():
    assert vt(v(2.0, 2.0, 1.0), v(2.0, 2.0, -1.0))[0] == 0
    # the triangle moves up through a resting vertex: impact at t = 0.4
    n, out = vt(v(0.2, 0.2, 0.4), v(0.2, 0.2, 0.4), a1=A + [0, 0, 1], b1=B + [0, 0, 1], c1=C + [0, 0, 1])
    assert n == 1 and out[0] == pytest.approx(0.4, abs=1e-14)


def test_edge_crossing_edge():
    # edge ab sweeps down through the fixed edge cd at t = 1/3
    a0, b0 = v(-1, 0.5, 1), v(1, 0.5, 1)
    c0, d0 = v(0, -1, 0), v(0, 1, 0)
    n, out = ee(a0, b0, c0, d0, a0 - [0, 0, 3], b0 - [0, 0, 3], c0, d0)
    assert n == 1
    assert out[0] == pytest.approx(1 / 3, abs=1e-14)
    np.testing.assert_allclose(out[1:3], [0.5, 0.75], atol=1e-12)
    # passing beside the other edge's end: no collision
    assert ee(a0 + [0, 5, 0], b0 + [0, 5, 0], c0, d0, a0 + [0, 5, -3], b0 + [0, 5, -3], c0, d0)[0] == 0


def test_grazing_within_the_tolerance_but_not_beyond():
    """A vertex crossing the triangle's plane just outside its edge counts as touching when it is
    within the inside-test tolerance (app. B.2) of the triangle, and not when it is farther."""
    tol = 1e-3
    for gap, hit in ((0.5e-3, 1), (2e-3, 0)):
        n, _ = vt(v(0.5, -gap, 1.0), v(0.5, -gap, -1.0), tol=tol)
        assert n == hit, gap


def test_tangential_touch_is_a_crossing():
    """A coplanarity cubic that touches zero without changing sign (a double root: the vertex
    reaches the plane and turns back) yields one root, so the pair counts as crossing once (odd)
    and gets a response."""
    roots = np.zeros(6)
    n = cubic_roots_01(0.25, -1.0, 1.0, 0.0, roots)  # (t - 1/2)^2
    assert n == 1 and roots[0] == pytest.approx(0.5, abs=1e-6)


def test_parallel_edges():
    # coplanar parallel edges sliding into overlap within their common plane (degenerate cubic)
    a0, b0 = v(0, 0, 0), v(1, 0, 0)
    c0, d0 = v(3, 0.5, 0), v(4, 0.5, 0)
    n, out = ee(a0, b0, c0, d0, a0, b0, c0 + [-3.5, -0.5, 0], d0 + [-3.5, -0.5, 0])
    assert n == 1
    # parallel edges in parallel planes moving side by side: never touch
    assert ee(a0, b0, c0 + [0, 0, 1], d0 + [0, 0, 1], a0, b0, c0 + [-3.5, 0, 1], d0 + [-3.5, 0, 1])[0] == 0
    # parallel edges, one passing through the other (crossing planes)
    n, out = ee(a0, b0, v(0.2, 1, 0.0), v(0.8, 1, 0.0), a0, b0, v(0.2, -1, 0.0), v(0.8, -1, 0.0))
    assert n == 1 and out[0] == pytest.approx(0.5, abs=1e-9)


def test_degenerate_triangle():
    # all three corners on one line: the cubic vanishes identically; the vertex through the segment
    a, b, c = v(0, 0, 0), v(1, 0, 0), v(2, 0, 0)
    n, out = vt(v(0.5, 0, 1), v(0.5, 0, -1), a, b, c)
    assert n == 1 and out[0] == pytest.approx(0.5, abs=1e-12)
    assert vt(v(0.5, 1, 1), v(0.5, 1, -1), a, b, c)[0] == 0
    # a point-sized triangle and a zero-length edge do not crash
    assert vt(v(0.5, 0, 1), v(0.5, 0, -1), a, a, a)[0] == 0
    assert ee(a, a, c, c, a, a, c, c)[0] == 0
    # two coincident corners (once raised ZeroDivisionError): the triangle is edge ac
    n, out = vt(v(1.5, 0, 1), v(1.5, 0, -1), a, a, c)
    assert n == 1 and out[0] == pytest.approx(0.5, abs=1e-12)
    np.testing.assert_allclose(out[1] * a + out[2] * a + out[3] * c, [1.5, 0, 0], atol=1e-12)
    assert vt(v(1.5, 0.1, 1), v(1.5, 0.1, -1), a, a, c)[0] == 0


def test_enter_and_leave_within_one_step_is_even():
    p0 = np.array([[0.72, 0.08, -0.63], [-0.13, -0.29, 0.16], [0.4, 0.81, -0.31], [-0.14, 0.82, -0.89]])
    p1 = np.array([[-0.76, 1.07, 0.42], [-0.09, 0.29, -0.29], [1.44, 1.17, -1.28], [-0.38, 1.91, 1.08]])
    n, out = vt(p0[0], p1[0], p0[1], p0[2], p0[3], p1[1], p1[2], p1[3])
    assert n == 2  # in and out again: no response needed (4.2.2.3)
    assert reference_vt_crossings(p0, p1) == 2
    assert 0.0 < out[0] < 1.0


def test_tiny_motions():
    for z in (0.5e-9, 1e-9 / 3):
        n, out = vt(v(0.3, 0.3, z), v(0.3, 0.3, z - 1e-9))
        assert n == 1 and out[0] == pytest.approx(z / 1e-9, rel=1e-6)
    assert vt(v(0.3, 0.3, 2e-9), v(0.3, 0.3, 1e-9))[0] == 0


# -- narrow phase: references -----------------------------------------------------------------------


def reference_vt_crossings(p0, p1, samples=200001, tol=1e-6):
    """Sign changes of the coplanarity volume on a fine grid whose crossing point lies in the triangle."""
    t = np.linspace(0.0, 1.0, samples)[:, None]
    x = p0[None] + t[:, :, None] * (p1 - p0)[None]
    vol = np.einsum("ij,ij->i", x[:, 0] - x[:, 1], np.cross(x[:, 2] - x[:, 1], x[:, 3] - x[:, 1]))
    idx = np.nonzero(np.sign(vol[1:]) != np.sign(vol[:-1]))[0]
    hits = 0
    for i in idx:
        q, a, b, c = x[i]
        n = np.cross(b - a, c - a)
        n2 = n @ n
        if n2 == 0:
            continue
        q = q - ((q - a) @ n) / n2 * n
        w1 = np.cross(c - b, q - b) @ n / n2
        w2 = np.cross(a - c, q - c) @ n / n2
        w3 = 1 - w1 - w2
        if min(w1, w2, w3) >= -tol:
            hits += 1
    return hits


def test_cubic_against_direct_evaluation_and_roots_against_numpy():
    rng = np.random.default_rng(0)
    roots = np.zeros(6)
    for _ in range(300):
        p0, p1 = rng.normal(size=(4, 3)), rng.normal(size=(4, 3))
        k = np.array(cubic_vertex_triangle(p0[0], p0[1], p0[2], p0[3], p1[0], p1[1], p1[2], p1[3]))
        for t in (0.0, 0.3, 1.0):
            x = p0 + t * (p1 - p0)
            direct = (x[0] - x[1]) @ np.cross(x[2] - x[1], x[3] - x[1])
            assert np.polyval(k[::-1], t) == pytest.approx(direct, abs=1e-12)
        n = cubic_roots_01(*k, roots)
        ref = np.sort([r.real for r in np.roots(k[::-1]) if abs(r.imag) < 1e-9 and -1e-12 <= r.real <= 1 + 1e-12])
        assert n == len(ref)
        np.testing.assert_allclose(roots[:n], ref, atol=1e-8)
        if cull_cubic(*k):
            assert len(ref) == 0


def test_culling_never_culls_a_cubic_with_a_root():
    rng = np.random.default_rng(1)
    culled = 0
    for _ in range(3000):
        k = rng.normal(size=4) * rng.choice([1e-3, 1.0, 1e3], size=4)
        r = [x.real for x in np.roots(k[::-1]) if abs(x.imag) < 1e-12 and 0.0 <= x.real <= 1.0]
        if cull_cubic(*k):
            culled += 1
            assert not r, k
    assert culled > 500  # and it culls a good share


def test_randomized_against_ipctk_misses_nothing():
    ipctk = pytest.importorskip("ipctk")
    ccd = ipctk.TightInclusionCCD()
    rng = np.random.default_rng(7)
    hits = missed = 0
    for _ in range(1500):
        p0 = rng.uniform(-1, 1, (4, 3))
        p1 = p0 + rng.uniform(-1, 1, (4, 3))
        ours = vt(p0[0], p1[0], p0[1], p0[2], p0[3], p1[1], p1[2], p1[3])[0]
        theirs, _ = ccd.point_triangle_ccd(p0[0], p0[1], p0[2], p0[3], p1[0], p1[1], p1[2], p1[3])
        hits += theirs
        missed += bool(theirs) and ours == 0
        ours = ee(*p0, *p1)[0]
        theirs, _ = ccd.edge_edge_ccd(*p0, *p1)
        hits += theirs
        missed += bool(theirs) and ours == 0
    assert hits > 100
    assert missed == 0


# -- broad phase and static test --------------------------------------------------------------------


def random_soup(n, rng, size=0.3, extent=3.0):
    x = rng.uniform(0, extent, (n, 1, 3)) + size * rng.uniform(-1, 1, (n, 3, 3))
    return x.reshape(-1, 3), np.arange(3 * n, dtype=np.int32).reshape(n, 3)


@pytest.fixture(params=["serial", "parallel"])
def query_kernel(request, monkeypatch):
    """Both query kernels: box_pairs runs the serial one below SERIAL_QUERY_BELOW query boxes."""
    from inflo.tools.collide import broad

    monkeypatch.setattr(broad, "SERIAL_QUERY_BELOW", 10**9 if request.param == "serial" else 0)
    return request.param


def test_box_pairs_match_brute_force(query_kernel):
    rng = np.random.default_rng(3)
    x, tri = random_soup(250, rng)
    b = triangle_boxes(x, x + rng.normal(scale=0.05, size=x.shape), tri, 0.01)
    for cell in (None, 0.05, 0.5, 5.0):
        np.testing.assert_array_equal(box_pairs(b, None, cell_size=cell), box_pairs_brute(b, b, True))
        np.testing.assert_array_equal(box_pairs(b[:40], b, cell_size=cell), box_pairs_brute(b[:40], b, False))


def test_box_pairs_in_a_crowded_cell_match_brute_force(query_kernel):
    """Hundreds of boxes on top of each other (far more pairs per query than the parallel query's
    per-block scratch space holds: its recount path) next to sparse ones."""
    rng = np.random.default_rng(8)
    crowd = np.concatenate([rng.uniform(0, 0.1, (300, 3)), rng.uniform(0.2, 0.3, (300, 3))], axis=1)
    sparse = np.concatenate([rng.uniform(5, 50, (300, 3)), np.zeros((300, 3))], axis=1)
    sparse[:, 3:] = sparse[:, :3] + 0.5
    b = np.concatenate([crowd, sparse])
    pairs = box_pairs(b, None, cell_size=0.3)
    assert len(pairs) >= 300 * 299 // 2  # every crowd box meets every other
    np.testing.assert_array_equal(pairs, box_pairs_brute(b, b, True))
    np.testing.assert_array_equal(box_pairs(b, b[::7], cell_size=0.3), box_pairs_brute(b, b[::7], False))


def test_triangles_intersect_hand_cases():
    t = [v(0, 0, 0), v(1, 0, 0), v(0, 1, 0)]
    assert triangles_intersect(*t, v(0.2, 0.2, -1), v(0.2, 0.2, 1), v(0.3, 0.9, 1))  # pierced
    assert not triangles_intersect(*t, v(2, 2, -1), v(2, 2, 1), v(3, 2, 1))  # beside
    assert not triangles_intersect(*t, v(0, 0, 0.1), v(1, 0, 0.1), v(0, 1, 0.1))  # parallel above
    assert triangles_intersect(*t, v(0.5, 0.5, 0), v(0.5, 0.5, 1), v(1, 1, 1))  # touching at a point
    assert triangles_intersect(*t, v(0.2, 0.1, 0), v(2, 0.1, 0), v(0.2, 2, 0))  # coplanar overlap
    assert not triangles_intersect(*t, v(2, 2, 0), v(3, 2, 0), v(2, 3, 0))  # coplanar apart
    assert triangles_intersect(*t, v(0.1, 0.1, 0), v(0.2, 0.1, 0), v(0.1, 0.2, 0))  # coplanar inside


def test_intersecting_pairs_match_brute_force():
    rng = np.random.default_rng(4)
    x, tri = random_soup(300, rng)
    tri[5] = [0, 1, 17]  # shares vertices with triangles 0 and 5: skipped
    fast = intersecting_pairs(x, tri)
    np.testing.assert_array_equal(fast, intersecting_pairs_brute(x, tri))
    assert len(fast) > 10


def test_intersecting_pairs_floret_by_floret_match_brute_force():
    """With the triangles' parts (grouped), the exact static test goes part by part: the same
    pairs as the brute force, within parts and across them, including coplanar touching ones; an
    ungrouped part list falls back to the grid."""
    rng = np.random.default_rng(6)
    x, tri = random_soup(400, rng)
    tri[5] = [0, 1, 17]
    # two coplanar triangles touching along a shared-free edge overlap: an exact (undecided) case
    x = np.concatenate([x, [[0, 0, 0.5], [1, 0, 0.5], [0, 1, 0.5], [1, 1, 0.5], [0.5, 0.5, 0.5], [0, 1.2, 0.5]]])
    n = len(x)
    tri = np.concatenate([tri, [[n - 6, n - 5, n - 4], [n - 3, n - 2, n - 1]]]).astype(np.int32)
    part = np.sort(rng.integers(0, 9, len(tri))).astype(np.int32)
    ref = intersecting_pairs_brute(x, tri)
    by_part = intersecting_pairs(x, tri, tri_part=part)
    np.testing.assert_array_equal(by_part, ref)
    np.testing.assert_array_equal(intersecting_pairs(x, tri, tri_part=part[::-1].copy()), ref)
    same = part[ref[:, 0]] == part[ref[:, 1]]
    assert same.any() and (~same).any()
    assert (len(tri) - 2, len(tri) - 1) in set(map(tuple, ref.tolist()))


def test_intersecting_pairs_between_two_meshes_match_the_cross_pairs_of_their_union():
    rng = np.random.default_rng(9)
    xa, ta = random_soup(200, rng)
    xb, tb = random_soup(150, rng)
    got = intersecting_pairs_between(xa, ta, xb, tb)
    union = intersecting_pairs_brute(np.vstack([xa, xb]), np.vstack([ta, tb + len(xa)]))
    cross = union[(union[:, 0] < len(ta)) & (union[:, 1] >= len(ta))]
    want = np.stack([cross[:, 0], cross[:, 1] - len(ta)], axis=1)
    np.testing.assert_array_equal(got, want)
    assert len(got) > 5
    # a mesh against itself moved far away: nothing; an empty mesh: nothing
    assert len(intersecting_pairs_between(xa, ta, xa + 100.0, ta)) == 0
    assert intersecting_pairs_between(xa, ta, xb, tb[:0]).shape == (0, 2)


def test_intersecting_pairs_with_a_subset_are_the_brute_force_pairs_touching_it():
    rng = np.random.default_rng(11)
    x, tri = random_soup(300, rng)
    tri[7] = [0, 1, 40]  # shares vertices with triangle 0 (skipped)
    which = np.array([0, 7, 13, 150, 299])
    allp = intersecting_pairs_brute(x, tri)
    want = allp[np.isin(allp[:, 0], which) | np.isin(allp[:, 1], which)]
    got = intersecting_pairs_with(x, tri, which)
    np.testing.assert_array_equal(got, want)
    assert len(got) > 3
    # with the triangles' parts (some parts empty, some far away): the same pairs
    part = rng.integers(0, 12, len(tri)) * 2
    far = part == 10
    x2 = x.copy()
    x2[np.unique(tri[far])] += 50.0
    allp = intersecting_pairs_brute(x2, tri)
    want = allp[np.isin(allp[:, 0], which) | np.isin(allp[:, 1], which)]
    np.testing.assert_array_equal(intersecting_pairs_with(x2, tri, which, tri_part=part), want)
    np.testing.assert_array_equal(intersecting_pairs_with(x2, tri, which), want)
    assert intersecting_pairs_with(x, tri, []).shape == (0, 2)


# -- collision constraints and the resolution loop -------------------------------------------------


def test_vt_constraint_pushes_to_the_thickness_and_conserves_momentum():
    q, a, b, c = v(0.3, 0.3, -0.1), A.copy(), B.copy(), C.copy()
    bary = np.array([0.4, 0.3, 0.3])
    n = v(0, 0, 1)  # q came from above
    w = np.array([1.0, 2.0, 0.5, 1.0])
    corr = [np.zeros(3) for _ in range(4)]
    assert solve_vt_collision_constraint(q, w[0], a, w[1], b, w[2], c, w[3], bary, n, 0.01, 1.0, *corr)
    q2, a2, b2, c2 = q + corr[0], a + corr[1], b + corr[2], c + corr[3]
    tri_pt = bary[0] * a2 + bary[1] * b2 + bary[2] * c2
    assert (q2 - tri_pt) @ n == pytest.approx(0.01, abs=1e-15)
    np.testing.assert_allclose(sum(c_ / w_ for c_, w_ in zip(corr, w)), 0.0, atol=1e-15)
    # satisfied constraint: nothing to do; fixed triangle: only q moves
    assert not solve_vt_collision_constraint(q2, 1, a2, 1, b2, 1, c2, 1, bary, n, 0.0, 1.0, *corr)
    assert solve_vt_collision_constraint(q, 1.0, a, 0.0, b, 0.0, c, 0.0, bary, n, 0.01, 1.0, *corr)
    assert not corr[1].any() and corr[0][2] == pytest.approx(0.11)


def test_ee_constraint_separates_the_edges():
    a, b, c, d = v(-1, 0, -0.05), v(1, 0, -0.05), v(0, -1, 0), v(0, 1, 0)
    corr = [np.zeros(3) for _ in range(4)]
    assert solve_ee_collision_constraint(a, 1, b, 1, c, 1, d, 1, 0.5, 0.5, v(0, 0, 1), 0.02, 1.0, *corr)
    mid_ab = 0.5 * (a + corr[0] + b + corr[1])
    mid_cd = 0.5 * (c + corr[2] + d + corr[3])
    assert (mid_ab - mid_cd)[2] == pytest.approx(0.02, abs=1e-15)


def sheets(nx=6, gap=0.05, shift=0.0):
    """Two parallel grid sheets, the upper one above the lower by ``gap``."""
    from inflo.tools.testing.flowers import grid_faces

    u, w = np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 1, nx), indexing="ij")
    lower = np.stack([u, w, 0 * u], -1).reshape(-1, 3)
    upper = np.stack([u + shift, w + 0.5 * shift, 0 * u + gap], -1).reshape(-1, 3)
    tri = grid_faces(nx, nx)
    return np.concatenate([lower, upper]), np.concatenate([tri, tri + nx * nx]).astype(np.int32)


def _sheets_pushed_through():
    """Two sheets, the middle of the upper one pushed down through the lower one over the step:
    ``(x0, x1, tri, edges, n)``, ``n`` the vertices of one sheet."""
    rng = np.random.default_rng(5)
    x0, tri = sheets(gap=0.05, shift=0.03)
    n = len(x0) // 2
    x1 = x0.copy()
    r2 = ((x0[n:, :2] - 0.5) ** 2).sum(axis=1)
    x1[n:, 2] -= 0.15 * np.exp(-r2 / 0.08) + 0.01 * rng.uniform(size=n)
    return x0, x1, tri, mesh_edges(tri), n


def test_resolve_collisions_leaves_the_step_collision_free():
    x0, x1, tri, edges, n = _sheets_pushed_through()
    w = np.ones(len(x0))
    w[:6] = 0.0
    assert len(intersecting_pairs(x0, tri)) == 0
    assert len(intersecting_pairs(x1, tri)) > 0
    before, _ = detect_collisions(x0, x1, tri, edges, tolerance=1e-9)
    assert len(before) > 0
    res = resolve_collisions(x0, x1, w, tri, edges, thickness=0.005, iterations=10, max_retries=20)
    after, _ = detect_collisions(x0, x1, tri, edges, tolerance=1e-9)
    assert len(after) == 0
    assert len(intersecting_pairs(x1, tri)) == 0
    assert res.found[0] == len(before) and res.constraints > 0
    np.testing.assert_array_equal(x1[:6], x0[:6])  # fixed vertices never move


def test_fallback_reverts_when_retries_run_out():
    x0, tri = sheets(gap=0.05)
    edges = mesh_edges(tri)
    n = len(x0) // 2
    x1 = x0.copy()
    x1[n:, 2] -= 0.2
    res = resolve_collisions(x0, x1, np.ones(len(x0)), tri, edges, thickness=0.005, iterations=0,
                             max_retries=0)
    assert len(res.remaining) > 0 and res.reverted > 0
    assert len(detect_collisions(x0, x1, tri, edges, tolerance=1e-9)[0]) == 0
    assert len(intersecting_pairs(x1, tri)) == 0


def _sheet(n):
    """An n x n grid of vertices over the unit square in z = 0 and its 2 (n-1)^2 triangles."""
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    grid = np.stack([u.ravel(), v.ravel(), np.zeros(n * n)], axis=1)
    quads = [(i * n + j, i * n + j + 1, (i + 1) * n + j, (i + 1) * n + j + 1)
             for i in range(n - 1) for j in range(n - 1)]
    tri = np.array([(a, b, c) for a, b, c, d in quads] + [(b, d, c) for a, b, c, d in quads], np.int32)
    return grid, tri


@pytest.mark.parametrize("fraction, grown", [(0.0, True), (0.5, True), (1e9, True), (0.5, False)])
def test_step_broad_phase_retry_rounds_match_a_fresh_broad_phase(fraction, grown, monkeypatch):
    """The retry rounds' incremental broad phase (round 0's grids of boxes grown by the slack; the
    elements of vertices that left their slack paired again at their new anchors) finds every pair
    a brute-force test of every box pair finds for the active vertices (less those sharing a
    vertex), each once, and none that the boxes grown by twice the slack would not pair, over
    rounds that move different vertices by less and by more than the slack, and the same vertices
    out of their anchors again and again; with the grids over what left rebuilt every round, now
    and then, and only once (their stale entries skipped, a grid over the re-anchored ones); with
    every grown box paired at round 0, or each the first round it is active."""
    from inflo.tools.collide import detect
    from inflo.tools.collide.broad import box_pairs_brute, edge_boxes, triangle_boxes, vertex_boxes
    from inflo.tools.collide.detect import _StepBroadPhase
    from inflo.tools.pbd import mesh_edges

    def _candidates(x0, x1, tri, edges, pad, cell, active):  # brute force reference
        vt = box_pairs_brute(vertex_boxes(x0, x1, pad), triangle_boxes(x0, x1, tri, pad), False)
        eb = edge_boxes(x0, x1, edges, pad)
        ee = box_pairs_brute(eb, eb, True)
        # pairs sharing a vertex are never collisions: the broad phase leaves them out
        vt = vt[~(tri[vt[:, 1]] == vt[:, :1]).any(axis=1)]
        ea, eb_ = edges[ee[:, 0]], edges[ee[:, 1]]
        ee = ee[~((ea[:, :1] == eb_) | (ea[:, 1:] == eb_)).any(axis=1)]
        if active is not None:
            vt = vt[active[vt[:, 0]] | active[tri[vt[:, 1]]].any(axis=1)]
            ee = ee[active[edges[ee[:, 0]]].any(axis=1) | active[edges[ee[:, 1]]].any(axis=1)]
        return vt, ee

    rng = np.random.default_rng(7)
    n = 12
    grid, tri = _sheet(n)
    # two sheets, the second above the first
    x0 = np.concatenate([grid, grid + [0.03, 0.02, 0.05]])
    tri = np.concatenate([tri, tri + n * n]).astype(np.int32)
    edges = mesh_edges(tri)
    x1 = x0 + rng.normal(0, 0.02, x0.shape)
    pad, cell = 1e-4, 0.1
    monkeypatch.setattr(detect, "REBUILD_FRACTION", fraction)
    monkeypatch.setattr(detect, "ROUND0_GROWN_PAIRS", grown)
    bp = _StepBroadPhase(x0, tri, edges, pad, cell)
    grids = []  # the grids over what left, round by round
    vt0, ee0 = bp.first(x1)
    wide = pad + 2.0 * bp.slack
    assert bp.slack > 0

    def within(got, ref, loose):
        got = [tuple(p) for p in got.tolist()]
        assert len(got) == len(set(got))  # no duplicates
        got = set(got)
        assert {tuple(p) for p in ref.tolist()} <= got <= {tuple(p) for p in loose.tolist()}

    ref_vt, ref_ee = _candidates(x0, x1, tri, edges, pad, cell, None)
    loose_vt, loose_ee = _candidates(x0, x1, tri, edges, wide, cell, None)
    within(vt0, ref_vt, loose_vt)
    within(ee0, ref_ee, loose_ee)
    # the same vertices keep moving far (they leave their anchors again and again), with others
    again_and_again = rng.random(len(x0)) < 0.05
    for r, scale in enumerate([0.0003, 0.05, 0.0003, 0.05, 0.001, 0.03, 0.03, 0.0003, 0.03]):
        active = rng.random(len(x0)) < 0.1
        if r >= 5:
            active |= again_and_again
        x1[active] += rng.normal(0, scale, (int(active.sum()), 3))
        vt, ee = bp.again(x1, active)
        ref_vt, ref_ee = _candidates(x0, x1, tri, edges, pad, cell, active)
        loose_vt, loose_ee = _candidates(x0, x1, tri, edges, wide, cell, active)
        within(vt, ref_vt, loose_vt)
        within(ee, ref_ee, loose_ee)
        if r == 0:  # small moves: nothing has left the round-0 boxes yet
            assert not bp.moved.any()
        assert len(ref_vt) and len(ref_ee)
        grids.append(bp.grids_all)
    # rebuilt every round that something left, more than once, once
    builds = sum(g is not None and (k == 0 or g is not grids[k - 1]) for k, g in enumerate(grids))
    assert builds == {0.0: 5, 0.5: 3, 1e9: 1}[fraction]
    # a response that moves vertices far (boxes of more than 64 cells): that round and every later
    # one pair the active elements afresh (with box_pairs, which lists pairs sharing a vertex too:
    # the narrow phase skips those)
    def unshared(vt, ee):
        vt = vt[~(tri[vt[:, 1]] == vt[:, :1]).any(axis=1)]
        ea, eb_ = edges[ee[:, 0]], edges[ee[:, 1]]
        return vt, ee[~((ea[:, :1] == eb_) | (ea[:, 1:] == eb_)).any(axis=1)]

    for far in (True, False):
        active = np.zeros(len(x0), bool)
        if far:
            active[:3] = True
            x1[:3] += 10.0
        else:
            active = rng.random(len(x0)) < 0.1
            x1[active] += rng.normal(0, 0.0003, (int(active.sum()), 3))
        vt, ee = unshared(*bp.again(x1, active))
        assert bp.far
        ref_vt, ref_ee = _candidates(x0, x1, tri, edges, pad, cell, active)
        loose_vt, loose_ee = _candidates(x0, x1, tri, edges, wide, cell, active)
        within(vt, ref_vt, loose_vt)
        within(ee, ref_ee, loose_ee)
        assert len(ref_vt) and len(ref_ee)
    assert bp.have_e.all() == grown  # paired at round 0, or as they became active


def test_box_grid_part_filter_matches_brute_force():
    """A grid query keeping pairs within one part only, or of two parts only, gives the brute-force
    pairs so filtered; the two together are the unfiltered query."""
    from inflo.tools.collide.broad import PARTS_CROSS, PARTS_SAME, BoxGrid, box_pairs_brute

    rng = np.random.default_rng(3)
    lo = rng.random((300, 3))
    b = np.concatenate([lo, lo + rng.random((300, 3)) * 0.15], axis=1)
    part = rng.integers(0, 7, 300).astype(np.int32)
    grid = BoxGrid(b, 0.1, b[:, :3].min(axis=0), parts=part)
    ref = box_pairs_brute(b, b, True)
    same = ref[part[ref[:, 0]] == part[ref[:, 1]]]
    cross = ref[part[ref[:, 0]] != part[ref[:, 1]]]
    np.testing.assert_array_equal(grid.query(b, same=True, parts=part, parts_mode=PARTS_SAME), same)
    np.testing.assert_array_equal(grid.query(b, same=True, parts=part, parts_mode=PARTS_CROSS), cross)
    np.testing.assert_array_equal(grid.query(b, same=True), ref)
    assert len(same) and len(cross)


def test_split_broad_phase_finds_the_same_contacts():
    """Parts carried far over a step (a head's growth carrying its florets): pairs within a part are
    found in the part's moving frame, pairs of two parts in the scene's (``_SplitBroadPhase``). The
    contacts, in their order, are those of the one-frame broad phase, at round 0 and over retry
    rounds, with far fewer candidate pairs."""
    from inflo.tools.collide.contacts import _narrow
    from inflo.tools.collide.detect import _SplitBroadPhase, _StepBroadPhase, step_broad_phase
    from inflo.tools.pbd import mesh_edges

    rng = np.random.default_rng(11)
    n = 10
    grid, tri = _sheet(n)
    # three sheets (parts), the second just above the first, the third beside them
    x0 = np.concatenate([grid, grid + [0.03, 0.02, 0.04], grid + [1.5, 0.0, 0.0]])
    tri = np.concatenate([tri, tri + n * n, tri + 2 * n * n]).astype(np.int32)
    edges = mesh_edges(tri)
    part = np.repeat(np.arange(3), n * n).astype(np.int32)
    # each sheet carried by about its own width, the second through the first, and crumpled
    carry = np.array([[2.0, 0.5, 0.3], [2.0, 0.5, 0.2], [1.0, -1.0, 0.0]])
    x1 = x0 + carry[part] + rng.normal(0, 0.03, x0.shape)
    pad, cell, tol = 1e-4, 0.15, 2e-4
    plain = _StepBroadPhase(x0, tri, edges, pad, cell)
    split = step_broad_phase(x0, x1, tri, edges, pad, cell, part)
    assert isinstance(split, _SplitBroadPhase)
    assert isinstance(step_broad_phase(x0, x0 + rng.normal(0, 1e-3, x0.shape), tri, edges, pad, cell, part),
                      _StepBroadPhase)  # nothing carried: one frame

    def same(a, b):
        ca, _ = _narrow(x0, x1, tri, edges, a[0], a[1], tol)
        cb, _ = _narrow(x0, x1, tri, edges, b[0], b[1], tol)
        for name in ("kind", "indices", "coef", "normal", "toi", "element"):
            np.testing.assert_array_equal(getattr(ca, name), getattr(cb, name))
        return len(ca)

    rounds = [(plain.first(x1), split.first(x1))]
    # (the two sheets carried together still pair along their common path: a part of two parts)
    assert len(rounds[0][1][0]) + len(rounds[0][1][1]) < 0.7 * (len(rounds[0][0][0]) + len(rounds[0][0][1]))
    found = same(*rounds[0])
    for scale in (0.0003, 0.05, 0.002):
        active = rng.random(len(x0)) < 0.2
        x1[active] += rng.normal(0, scale, (int(active.sum()), 3))
        found += same(plain.again(x1, active), split.again(x1, active))
    assert found > 0
    # the pairs of two parts and of one part both occur among the contacts
    c, _ = _narrow(x0, x1, tri, edges, *split.again(x1, np.ones(len(x0), bool)), tol)
    pa = part[c.indices]
    assert (pa[:, 0] == pa[:, 3]).any() and (pa[:, 0] != pa[:, 3]).any()


def _crowd(seed=2):
    """Six crumpled sheets (parts) in a stack, two of them passing through each other over the step,
    one carried far: contacts within and between parts."""
    from inflo.tools.pbd import mesh_edges

    rng = np.random.default_rng(seed)
    n = 8
    grid, tri1 = _sheet(n)
    offsets = np.array([[0, 0, 0], [0.05, 0.03, 0.02], [0.4, 0.1, 0.05], [0.9, 0, 0], [0.9, 0.05, 0.1], [3, 0, 0]])
    x0 = np.concatenate([grid * 0.8 + o for o in offsets])
    x0 += rng.normal(0, 0.002, x0.shape)
    tri = np.concatenate([tri1 + k * n * n for k in range(len(offsets))]).astype(np.int32)
    part = np.repeat(np.arange(len(offsets)), n * n).astype(np.int32)
    x1 = x0 + rng.normal(0, 0.01, x0.shape)
    x1[part == 1] += [0, 0, -0.06]  # through sheet 0
    x1[part == 5] += [2.0, 0.5, 0.0]  # carried far: its pairs in its moving frame
    # a fold inside sheet 3: its far half swings down through its near half
    fold = (part == 3) & (x0[:, 0] > 1.3)
    x1[fold, 2] -= 0.3 * (x0[fold, 0] - 1.3)
    return x0, x1, tri, mesh_edges(tri), part


def test_probe_finds_round_0s_contacts_and_counts():
    """The round-0 probe (pairs tested as the part-by-part sweep finds them, none written) gives
    the contacts of the step broad phase's round 0 and its log counts, in the one-frame and in the
    moving-frame (split) case, and none where nothing crosses."""
    from inflo.tools.collide.contacts import _narrow
    from inflo.tools.collide.detect import _SplitBroadPhase, step_broad_phase
    from inflo.tools.collide.probe import can_probe, probe_contacts

    x0, x1, tri, edges, part = _crowd()
    pad, cell, tol = 1e-4, 0.1, 2e-4
    assert can_probe(tri, edges, part)
    assert not can_probe(tri, edges, part[::-1].copy())
    kinds = set()
    for xs in (x1, x0 + 1e-6):
        for vp in (part, np.zeros_like(part)):  # six parts (split: one is carried far), one part
            broad = step_broad_phase(x0, xs, tri, edges, pad, cell, vp)
            kinds.add(type(broad).__name__)
            shift = broad.shift if isinstance(broad, _SplitBroadPhase) else None
            ref, ref_stats = _narrow(x0, xs, tri, edges, *broad.first(xs), tol)
            vt, ee, stats = probe_contacts(x0, xs, tri, edges, pad, tol, vp, shift)
            got, _ = _narrow(x0, xs, tri, edges, vt, ee, tol)
            assert stats == ref_stats
            for name in ("kind", "indices", "coef", "normal", "toi", "element"):
                np.testing.assert_array_equal(getattr(got, name), getattr(ref, name))
            if xs is x1:
                assert len(ref) > 20
            else:
                assert len(ref) == 0
    assert kinds == {"_SplitBroadPhase", "_StepBroadPhase"}


def test_probe_overflow_of_a_parts_slots(monkeypatch):
    """A part with more crossing pairs than its first-pass slots is run again with room for all."""
    from inflo.tools.collide import probe
    from inflo.tools.collide.contacts import _narrow
    from inflo.tools.collide.detect import step_broad_phase

    x0, x1, tri, edges, part = _crowd()
    pad, cell, tol = 1e-4, 0.1, 2e-4
    full = probe.probe_contacts(x0, x1, tri, edges, pad, tol, part)
    monkeypatch.setattr(probe, "_PART_CAP", 1)
    small = probe.probe_contacts(x0, x1, tri, edges, pad, tol, part)
    np.testing.assert_array_equal(full[0], small[0])
    np.testing.assert_array_equal(full[1], small[1])
    broad = step_broad_phase(x0, x1, tri, edges, pad, cell, part)
    ref, _ = _narrow(x0, x1, tri, edges, *broad.first(x1), tol)
    assert len(ref) == len(full[0]) + len(full[1]) > 5


def test_resolve_collisions_the_same_with_and_without_the_probe():
    """resolve_collisions ends on the same positions whether round 0 is probed (the retry rounds'
    broad phase started later, from round 0's positions) or not."""
    x0, x1, tri, edges, part = _crowd()
    w = np.ones(len(x0))
    out = []
    for probe in (True, False):
        xs = x1.copy()
        res = resolve_collisions(x0, xs, w, tri, edges, thickness=1e-3, max_retries=6, fallback="none",
                                 vertex_part=part, probe=probe)
        out.append((xs, res.rounds, res.found))
    np.testing.assert_array_equal(out[0][0], out[1][0])
    assert out[0][1:] == out[1][1:] and out[0][1] > 1


def test_culled_is_the_full_tests_early_exit():
    """vertex_triangle_culled / edge_edge_culled (the cubic's cull on rows of the position arrays)
    say True only where the full tests return no crossing, and are False wherever those find one."""
    from inflo.tools.collide.ccd import edge_edge_ccd, edge_edge_culled, vertex_triangle_ccd, vertex_triangle_culled

    rng = np.random.default_rng(8)
    culled = crossing = 0
    out = np.zeros(4)
    for _ in range(3000):
        x0 = rng.random((4, 3))
        x1 = x0 + rng.normal(0, rng.choice([0.01, 0.3]), (4, 3))
        if rng.random() < 0.1:
            x1[:] = x0  # no motion
        h = vertex_triangle_ccd(x0[0], x0[1], x0[2], x0[3], x1[0], x1[1], x1[2], x1[3], 1e-6, out)
        c = vertex_triangle_culled(x0, x1, 0, 1, 2, 3)
        assert not (c and h), (x0, x1)
        g = edge_edge_ccd(x0[0], x0[1], x0[2], x0[3], x1[0], x1[1], x1[2], x1[3], 1e-6, out)
        e = edge_edge_culled(x0, x1, 0, 1, 2, 3)
        assert not (e and g), (x0, x1)
        culled += c + e
        crossing += (h > 0) + (g > 0)
    assert culled > 1000 and crossing > 50


# ----------------------------------------------------------------------------------------------
# The whole-part fallback
# ----------------------------------------------------------------------------------------------


def _two_squares(gap):
    """Two unit squares (two triangles each) in planes z = 0 and z = gap; parts 0 and 1."""
    sq = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    x = np.concatenate([sq, sq + [0, 0, gap]])
    tri = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]], np.int32)
    return x, tri, mesh_edges(tri), np.array([0, 0, 0, 0, 1, 1, 1, 1], np.int32)


def test_retreat_parts_moves_whole_parts_back_along_their_motion():
    """Square 1 passes through square 0 in the step; moved back whole, it ends at a blend of its
    start and end (every vertex at the same fraction), the step collision-free, square 0 as it was."""
    from inflo.tools.collide.detect import detect_collisions
    from inflo.tools.collide.retreat import retreat_parts

    x0, tri, edges, vp = _two_squares(0.5)
    x1 = x0.copy()
    x1[4:, 2] = -0.3  # through square 0
    x1[0, 2] = 0.01  # square 0 moves a little
    start = np.array([False, True])
    res = retreat_parts(x0, x1, tri, edges, vp, 2, start, tolerance=1e-9)
    found, _ = detect_collisions(x0, x1, tri, edges, tolerance=1e-9)
    assert len(found) == 0
    s = (x1[4:, 2] - 0.5) / (-0.8)  # fraction of its motion square 1 kept
    assert np.allclose(s, 0.5)  # halfway (z = 0.1) is free
    assert x1[0, 2] == 0.01  # square 0 untouched
    assert res.fraction[0] == 1.0 and res.fraction[1] < 1.0 and not res.whole_step
    assert res.vertices == 4


def test_retreat_parts_keeps_up_with_the_carried_motion():
    """With ``carried`` (the start shape carried by each part's rigid motion), a part moved back
    goes towards that rather than to x0: here the carried square is free, so it ends there."""
    from inflo.tools.collide.detect import detect_collisions
    from inflo.tools.collide.retreat import retreat_parts

    x0, tri, edges, vp = _two_squares(0.5)
    carried = x0.copy()
    carried[4:, 0] += 3.0  # square 1's placement moves it aside
    x1 = carried.copy()
    x1[4:, 0] -= 3.0
    x1[4:, 2] = -0.5  # its solve put it through square 0
    res = retreat_parts(x0, x1, tri, edges, vp, 2, np.array([False, True]), tolerance=1e-9,
                        carried=carried)
    assert len(detect_collisions(x0, x1, tri, edges, tolerance=1e-9)[0]) == 0
    assert res.fraction[1] >= 0.0  # not at x0
    assert np.all(x1[4:, 0] > 1.0)  # moved aside with its placement


def test_a_misshapen_part_without_room_for_its_carried_shape_is_put_at_a_smaller_one():
    """The ``"parts"`` fallback's last resort (``Parts.shrink``): a part the solve left out of
    shape whose carried shape crosses something is put on the first smaller shape offered for it
    that the step reaches collision-free; ``shrunk`` says at which scale. Where none fits (or the
    free one is not offered for that part) it keeps the solve's shape and counts as misshapen."""
    import dataclasses

    from inflo.tools.collide.detect import detect_collisions
    from inflo.tools.collide.resolve import CollisionResult
    from inflo.tools.collide.retreat import Parts, _retreat_fallback

    x0, tri, edges, vp = _two_squares(0.5)
    tol = 1e-9
    x1 = x0.copy()
    x1[6, 2] = 1.5  # the solve left square 1 bent: out of shape, but free
    carried = x0.copy()
    carried[4:, 2] = -0.5  # its carried shape passes through square 0

    def misshapen(xs):
        rest = np.linalg.norm(x0[edges[:, 0]] - x0[edges[:, 1]], axis=1)
        now = np.linalg.norm(xs[edges[:, 0]] - xs[edges[:, 1]], axis=1)
        bad = np.abs(now / rest - 1.0) > 0.2
        return np.bincount(vp[edges[bad, 0]], minlength=2) > 0

    def detect(xs, act):
        return detect_collisions(x0, xs, tri, edges, tolerance=tol, active=act)[0]

    base = x0[4]
    crossing = base + 0.85 * (carried - base)  # smaller, still through square 0
    free = base + 0.85 * (x0 - base)  # smaller, where it was
    asked = []

    def shrink(s, which):
        asked.append((s, which.tolist()))
        every = np.ones(2, bool)
        return [(crossing, every), (free, every)] if s == 0.85 else [(crossing, every)]

    res = CollisionResult()
    parts = Parts(vertex_part=vp, n_parts=2, misshapen=misshapen, carried=lambda: carried, shrink=shrink,
                  shrink_scales=[0.85, 0.7])
    _retreat_fallback(res, x0, x1, tri, edges, tol, parts, detect)
    assert asked == [(0.85, [False, True])]
    assert res.shrunk.tolist() == [1.0, 0.85] and res.misshapen == 0
    assert res.retreated.tolist() == [1]
    np.testing.assert_array_equal(x1[4:], free[4:])
    np.testing.assert_array_equal(x1[:4], x0[:4])  # square 0 untouched
    assert len(detect(x1, np.ones(len(x1), bool))) == 0

    # nothing offered fits: the solve's shape stays, reported misshapen
    x1 = x0.copy()
    x1[6, 2] = 1.5
    res = CollisionResult()
    parts = dataclasses.replace(parts, shrink=lambda s, which: [(crossing, np.ones(2, bool)),
                                                                (free, np.zeros(2, bool))])
    _retreat_fallback(res, x0, x1, tri, edges, tol, parts, detect)
    assert res.shrunk.tolist() == [1.0, 1.0] and res.misshapen == 1
    assert x1[6, 2] == 1.5 and len(res.retreated) == 0


def test_a_part_that_fits_at_no_scale_is_given_room_by_its_neighbours_made_smaller():
    """:func:`_shrink_with_blockers`: a part out of shape whose smallest rest shape still
    intersects a neighbour in shape is put there together with that neighbour scaled about its
    base, at the largest scale at which the two intersect nothing (here 0.4: the neighbour square
    then stops short of the part's plane x = 0.5)."""
    from inflo.tools.collide.resolve import CollisionResult
    from inflo.tools.collide.retreat import _shrink_with_blockers

    sq = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)  # part 0 (base at the origin)
    wall = np.array([[0.5, 0.2, 0.1], [0.5, 0.8, 0.1], [0.5, 0.8, 0.7], [0.5, 0.2, 0.7]])  # part 1
    x1 = np.concatenate([sq, wall])
    tri = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]], np.int32)
    vp = np.array([0, 0, 0, 0, 1, 1, 1, 1])
    small = x1.copy()
    small[4:, 2] -= 0.3  # part 1's smallest shape reaches through part 0's square

    def shrink(s, which):
        return [(x1, np.zeros(2, bool)), (small, np.ones(2, bool))]

    def scaled(xs, which, s):
        out = xs.copy()
        out[which[vp]] *= s
        return out

    def crossing(xs):
        pairs = intersecting_pairs(xs, tri)
        return vp[tri[pairs[:, 0], 0]], vp[tri[pairs[:, 1], 0]]

    def blockers(xs, which):
        out = np.zeros(2, bool)
        for a, b in zip(*crossing(xs)):
            out[[a, b]] |= which[[b, a]]
        return out & ~which

    def intersecting(xs, which):
        out = np.zeros(2, bool)
        for a, b in zip(*crossing(xs)):
            out[max(a, b) if which[a] and which[b] else (a if which[a] else b)] = True
        return out & which

    res = CollisionResult()
    res.shrunk = np.ones(2)
    still = np.array([False, True])
    retreated = np.zeros(2, bool)
    _shrink_with_blockers(res, x1, vp, still, retreated, shrink, scaled, blockers, intersecting,
                          [0.85, 0.7, 0.55, 0.4, 0.25], lambda xs: np.array([False, True]))
    assert not still.any() and retreated.all()
    assert res.shrunk.tolist() == [0.4, 0.25]
    np.testing.assert_allclose(x1[:4], 0.4 * sq)
    np.testing.assert_array_equal(x1[4:], small[4:])
    assert len(intersecting_pairs(x1, tri)) == 0


def test_lattice_cell_size_is_kept_between_one_and_five_mean_extents():
    from inflo.formats.fcc import LatticeParams
    from inflo.tools.collide.broad import MAX_CELL_EXTENTS
    boxes = np.zeros((4, 6))
    boxes[:, 3:] = 0.1  # mean extent 0.1
    lo, hi = np.zeros(3), np.array([100.0, 1.0, 1.0])
    coarse = LatticeParams(divisions=(10, 10, 10))  # 100 / 10 = 10 x the mean extent
    assert lattice_cell_size(coarse, lo, hi, boxes) == pytest.approx(MAX_CELL_EXTENTS * 0.1)
    fine = LatticeParams(divisions=(10_000, 10, 10))  # 0.01: below the mean extent
    assert lattice_cell_size(fine, lo, hi, boxes) == pytest.approx(0.1)
    mid = LatticeParams(divisions=(500, 10, 10))  # 0.2: kept
    assert lattice_cell_size(mid, lo, hi, boxes) == pytest.approx(0.2)
    # the broad phase is exact whatever the cell: the pairs of random boxes at every cell size
    rng = np.random.default_rng(3)
    c = rng.random((300, 3)) * 4
    b = np.hstack([c, c + rng.random((300, 3)) * 0.3])
    ref = box_pairs_brute(b, b, True)
    for cell in (0.1, 0.3, 1.5, 4.0):
        np.testing.assert_array_equal(box_pairs(b, None, cell_size=cell), ref)


@pytest.mark.parametrize("budget", [None, 0])
def test_box_pairs_with_boxes_far_longer_than_the_cell(monkeypatch, budget):
    """Boxes swept far (a response moved their elements) next to small ones, with the canopy's
    small cell: the big ones are paired directly, the cell taken no smaller than the mean box
    (or, past the budget, coarsened to the biggest); the pairs are exactly the brute-force ones."""
    from inflo.tools.collide import broad
    if budget is not None:
        monkeypatch.setattr(broad, "BIG_BOX_BUDGET", budget)
    rng = np.random.default_rng(11)
    for _trial in range(12):
        b = _boxes_with_a_few_long(rng, 300, 5.0, 0.1, (1, 8), 0.0, 10.0)  # a few hundred cells long
        _assert_box_pairs_are_brute_force(b, b[::4], 0.02)


def _boxes_with_a_few_long(rng, n, extent, small, count, long_min, long_span):
    """``n`` boxes up to ``small`` a side in a cube of side ``extent``, ``count`` (a range) of
    them ``long_min`` plus up to ``long_span`` a side."""
    c = rng.random((n, 3)) * extent
    b = np.hstack([c, c + rng.random((n, 3)) * small])
    k = rng.choice(n, rng.integers(*count), replace=False)
    b[k, 3:] = b[k, :3] + long_min + rng.random((len(k), 3)) * long_span
    return b


def _assert_box_pairs_are_brute_force(b, q, cell):
    """box_pairs of ``b`` with itself, of ``q`` with ``b`` and of ``b`` with ``q``: the brute force's."""
    np.testing.assert_array_equal(box_pairs(b, None, cell_size=cell), box_pairs_brute(b, b, True))
    np.testing.assert_array_equal(box_pairs(q, b, cell_size=cell), box_pairs_brute(q, b, False))
    np.testing.assert_array_equal(box_pairs(b, q, cell_size=cell), box_pairs_brute(b, q, False))


@pytest.mark.parametrize("budget", [None, 0])
def test_box_pairs_with_a_few_boxes_over_many_cells_each_side_under_64(monkeypatch, budget):
    """A squeezed head's swept boxes: 1-2 % of them across much of the scene, each side under 64
    cells (no coarsening) but tens of thousands of cells in all. Those over BIG_BOX_CELLS cells are
    paired directly (the grid then holds only the small ones), or, past the budget, entered in the
    grid like the rest; the pairs are exactly the brute-force ones either way."""
    from inflo.tools.collide import broad
    if budget is not None:
        monkeypatch.setattr(broad, "BIG_BOX_BUDGET", budget)
    calls = []
    direct = broad._pairs_with_big
    monkeypatch.setattr(broad, "_pairs_with_big", lambda *a: calls.append(1) or direct(*a))
    rng = np.random.default_rng(12)
    for _trial in range(6):
        b = _boxes_with_a_few_long(rng, 600, 3.0, 0.05, (3, 12), 0.5, 1.5)  # 10-40 cells a side
        _assert_box_pairs_are_brute_force(b, b[::3], 0.05)
    assert (len(calls) == 18) if budget is None else not calls
    calls.clear()
    c = rng.random((600, 3)) * 3
    small = np.hstack([c, c + 0.01])  # no big box: the grid alone
    np.testing.assert_array_equal(box_pairs(small, None, cell_size=0.05), box_pairs_brute(small, small, True))
    assert not calls


def test_touching_flags_the_elements_with_a_flagged_vertex_of_each_set():
    from inflo.tools.collide.detect import _touching

    tri = np.array([[0, 1, 2], [2, 3, 4], [4, 5, 0]], np.int32)
    edges = mesh_edges(tri)
    rng = np.random.default_rng(3)
    for _ in range(20):
        flags = rng.random((3, 6)) < 0.3
        for idx in (tri, edges):
            got = _touching(flags, idx)
            for f, g in zip(flags, got):
                assert (g == f[idx].any(axis=1)).all()


def test_step_box_stats_are_those_of_the_written_boxes():
    """Round 0 reads the grid's origin, mean triangle extent and largest box side from the
    positions (``_step_box_stats``): bit for bit those of the written vertex, triangle and edge
    boxes (``_box_stats``), with signed zeros, a zero pad, flat and empty element sets."""
    from inflo.tools.collide.broad import edge_boxes, triangle_boxes, vertex_boxes
    from inflo.tools.collide.detect import _box_stats, _step_box_stats

    rng = np.random.default_rng(11)
    x0 = rng.normal(size=(40, 3)) * np.array([1.0, 1e-3, 10.0])
    x1 = x0 + rng.normal(size=(40, 3)) * 0.1
    x0[:5] = 0.0
    x1[:5] = -0.0
    x1[5:8, 1] = x0[5:8, 1]  # no motion along y
    tri = rng.integers(0, 40, (60, 3)).astype(np.int32)
    tri[:4] = [0, 1, 2]  # a zero-size triangle
    edges = mesh_edges(tri)
    for pad in (0.0, 1e-3, 0.37):
        for t, e in ((tri, edges), (tri, edges[:0]), (tri[:0], edges), (tri[:0], edges[:0])):
            ref = _box_stats(vertex_boxes(x0, x1, pad), triangle_boxes(x0, x1, t, pad),
                             edge_boxes(x0, x1, e, pad))
            got = _step_box_stats(x0, x1, t, e, pad)
            assert got[0].tobytes() == ref[0].tobytes()
            assert float(got[1]).hex() == float(ref[1]).hex()
            assert float(got[2]).hex() == float(ref[2]).hex()
    empty = np.zeros((0, 3))
    ref = _box_stats(np.zeros((0, 6)), np.zeros((0, 6)), np.zeros((0, 6)))
    got = _step_box_stats(empty, empty, tri[:0], edges[:0], 0.1)
    assert got[0].tobytes() == ref[0].tobytes() and got[1] == ref[1] and got[2] == ref[2]


def test_row_groups_is_the_inverse_of_unique_rows():
    """The contacts' merge groups rows by (kind, indices) from two packed int64 keys: the same ids
    as ``np.unique(rows, axis=0)``'s inverse (ranks of the rows in lexicographic order), with
    repeated rows, large indices, and the fallback for values the keys cannot hold."""
    from inflo.tools.collide.contacts import _row_groups

    rng = np.random.default_rng(5)
    for hi in (4, 1000, 2**31 - 1):
        kind = rng.integers(0, 2, 400).astype(np.int8)
        ind = rng.integers(0, hi, (400, 4)).astype(np.int32)
        ind[200:] = ind[:200][rng.integers(0, 200, 200)]  # repeats
        kind[200:] = kind[:200][rng.integers(0, 200, 200)] if hi == 4 else kind[200:]
        ref = np.unique(np.concatenate([kind[:, None].astype(np.int64), ind], axis=1), axis=0,
                        return_inverse=True)[1].ravel()
        np.testing.assert_array_equal(_row_groups(kind, ind), ref)
    ind[0, 0] = -1  # not packable: np.unique itself
    ref = np.unique(np.concatenate([kind[:, None].astype(np.int64), ind], axis=1), axis=0,
                    return_inverse=True)[1].ravel()
    np.testing.assert_array_equal(_row_groups(kind, ind), ref)
    assert len(_row_groups(np.zeros(0, np.int8), np.zeros((0, 4), np.int32))) == 0


@pytest.mark.parametrize("cell", [0.01, 0.05, 0.3])
def test_box_grid_self_pairs_are_its_same_set_query(cell):
    """A grid's own pairs found cell by cell (each cell's entries paired among themselves) are the
    pairs of the query of its boxes against it (``same``), with the vertex filter and both part
    filters, at cells smaller than the boxes (boxes in many cells) and larger (crowded buckets)."""
    from inflo.tools.collide.broad import PARTS_ANY, PARTS_CROSS, PARTS_SAME, BoxGrid, box_pairs_brute

    rng = np.random.default_rng(17)
    lo = rng.random((400, 3))
    b = np.concatenate([lo, lo + rng.random((400, 3)) * 0.12], axis=1)
    b[5] = b[9]  # coincident boxes
    verts = rng.integers(0, 300, (400, 2)).astype(np.int32)
    part = rng.integers(0, 5, 400).astype(np.int32)
    grid = BoxGrid(b, cell, b[:, :3].min(axis=0), verts, parts=part)

    def rows(p):
        return p[np.lexsort((p[:, 1], p[:, 0]))]

    for mode in (PARTS_ANY, PARTS_SAME, PARTS_CROSS):
        for use_verts in (False, True):
            want = grid.query(b, same=True, vertices=verts if use_verts else None,
                              parts=part if mode != PARTS_ANY else None, parts_mode=mode)
            got = grid.self_pairs(vertices=use_verts, parts_mode=mode)
            np.testing.assert_array_equal(rows(got), want)
            assert len(want) > 20
    np.testing.assert_array_equal(rows(grid.self_pairs()), box_pairs_brute(b, b, True))
    assert BoxGrid(b[:0], cell, b[0, :3]).self_pairs().shape == (0, 2)


@pytest.mark.parametrize("fallback", ["none", "vertices"])
def test_rounds_that_run_away_stop_and_end_on_their_best_round(fallback):
    """A relaxation that undoes the response (the second pushes the whole upper sheet through the
    lower one) makes round 2 find more pairs than round 0 and over RUNAWAY_FACTOR x the fewest so
    far: the rounds stop there and end on the positions of their best round, whose crossing pairs
    are the ones reported (a fresh detection of the step finds exactly those); the fallback then
    makes the step collision-free from there."""
    from inflo.tools.collide.resolve import RUNAWAY_FACTOR

    x0, x1, tri, edges, n = _sheets_pushed_through()
    calls = []

    def relax(x, moved):
        calls.append(1)
        if len(calls) == 1:
            x[n + 14, 2] -= 0.3  # one vertex through: round 1 finds a few pairs
        elif len(calls) == 2:
            x[n:, 2] -= 0.3  # the whole sheet through: round 2 runs away

    res = resolve_collisions(x0, x1, np.ones(len(x0)), tri, edges, thickness=0.005, iterations=10,
                             max_retries=20, relax=relax, fallback=fallback)
    assert len(res.found) == 3 and len(calls) == 2
    best = min(res.found[:2])
    assert 0 < best and res.found[2] > max(RUNAWAY_FACTOR * best, res.found[0])
    fresh, _ = detect_collisions(x0, x1, tri, edges, tolerance=1e-9)
    if fallback == "none":
        assert len(res.remaining) == best == len(fresh)
    else:
        assert len(fresh) == 0 and res.reverted > 0
        assert len(intersecting_pairs(x1, tri)) == 0
