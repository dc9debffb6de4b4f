"""PBD constraint kernels (thesis ch. 3, eqs. 3.3-3.13, appendix A) on tiny cases, and the sweeps."""
from __future__ import annotations

import math

import numpy as np
import pytest

from inflo.tools.pbd import (
    colour_constraints,
    dihedral_angle_gradients,
    init_bending_constraint,
    mesh_edges,
    mesh_hinges,
    project_bending_constraints,
    project_bending_constraints_coloured,
    project_distance_constraints,
    project_distance_constraints_coloured,
    signed_dihedral_angle,
    solve_attachment_constraint,
    solve_bending_constraint,
    solve_distance_constraint,
    wrap_angle,
)
from inflo.tools.pbd.solver import hinge_angles, overstretched_edges


def hinge(angle_deg: float) -> np.ndarray:
    """Hinge (p1, p2, p3, p4) on the edge p1 = 0 -> p2 = +X, with signed dihedral angle ``angle``."""
    a = math.radians(angle_deg)
    p1 = np.array([0.0, 0.0, 0.0])
    p2 = np.array([1.0, 0.0, 0.0])
    p3 = np.array([0.5, 1.0, 0.0])  # wing of triangle (p1, p2, p3)
    # wing of (p1, p4, p2): the mirror of p3 across the edge, turned about +X by the angle
    p4 = np.array([0.5, -math.cos(a), -math.sin(a)])
    return np.array([p1, p2, p3, p4])


def test_stretched_edge_returns_to_rest_length_in_one_projection():
    p0, p1 = np.array([0.0, 0.0, 0.0]), np.array([2.0, 0.0, 0.0])
    c0, c1 = np.zeros(3), np.zeros(3)
    assert solve_distance_constraint(p0, 1.0, p1, 1.0, 1.0, 1.0, c0, c1)
    q0, q1 = p0 + c0, p1 + c1
    assert np.linalg.norm(q1 - q0) == pytest.approx(1.0, abs=1e-15)
    np.testing.assert_allclose(c0, [0.5, 0, 0])
    np.testing.assert_allclose(c1, [-0.5, 0, 0])


def test_fixed_vertex_never_moves():
    rng = np.random.default_rng(1)
    c = [np.zeros(3) for _ in range(4)]
    for _ in range(20):
        p = rng.normal(size=(4, 3))
        solve_distance_constraint(p[0], 0.0, p[1], 1.0, 0.3, 1.0, c[0], c[1])
        assert not c[0].any() and c[1].any()
        solve_bending_constraint(p[0], 0.0, p[1], 1.0, p[2], 0.0, p[3], 2.0, 0.7, 1.0, *c)
        assert not c[0].any() and not c[2].any()
    # both fixed: degenerate, reported as such
    assert not solve_distance_constraint(p[0], 0.0, p[1], 0.0, 0.3, 1.0, c[0], c[1])
    assert not c[0].any() and not c[1].any()


def test_attachment_constraint_moves_only_fixed_vertices():
    corr = np.zeros(3)
    assert solve_attachment_constraint(np.zeros(3), 0.0, np.array([1.0, 2.0, 3.0]), corr)
    np.testing.assert_array_equal(corr, [1, 2, 3])
    assert not solve_attachment_constraint(np.zeros(3), 1.0, np.array([1.0, 2.0, 3.0]), corr)
    assert not corr.any()


@pytest.mark.parametrize("angle", [-170.0, -90.0, -30.0, 0.0, 15.0, 90.0, 135.0, 179.0])
def test_signed_dihedral_angle_measures_the_hinge(angle):
    p = hinge(angle)
    assert math.degrees(signed_dihedral_angle(*p)) == pytest.approx(angle, abs=1e-9)


def test_mirror_configurations_have_opposite_signs():
    """Fig. 3.2: the unsigned angle of eq. 3.12 cannot tell them apart, eq. 3.13 can."""
    a, b = hinge(40.0), hinge(-40.0)
    n = lambda p, q, r: np.cross(q - p, r - p) / np.linalg.norm(np.cross(q - p, r - p))
    unsigned = lambda h: math.acos(np.dot(n(h[0], h[2], h[1]), n(h[0], h[1], h[3])))
    assert unsigned(a) == pytest.approx(unsigned(b))
    assert signed_dihedral_angle(*a) == pytest.approx(-signed_dihedral_angle(*b))


def test_gradients_match_finite_differences():
    rng = np.random.default_rng(2)
    g = np.zeros((4, 3))
    for _ in range(20):
        p = rng.normal(size=(4, 3))
        dihedral_angle_gradients(p[0], p[1], p[2], p[3], g[0], g[1], g[2], g[3])
        fd = np.zeros((4, 3))
        h = 1e-6
        for i in range(4):
            for c in range(3):
                q = p.copy()
                q[i, c] += h
                f1 = signed_dihedral_angle(*q)
                q[i, c] -= 2 * h
                f0 = signed_dihedral_angle(*q)
                fd[i, c] = wrap_angle(f1 - f0) / (2 * h)
        np.testing.assert_allclose(g, fd, atol=1e-6 * max(1.0, np.abs(fd).max()))


def test_hinge_bent_through_zero_keeps_the_sign_of_its_rest_angle():
    """Mirror case: rest +30 deg, pushed to -10 deg (through flat). The projection must bring it
    back to +30, never to the mirror -30 (which is what the unsigned eq. 3.12 converges to)."""
    rest = math.radians(30.0)
    p = hinge(-10.0)
    c = [np.zeros(3) for _ in range(4)]
    angles = []
    for _ in range(30):
        solve_bending_constraint(p[0], 1.0, p[1], 1.0, p[2], 1.0, p[3], 1.0, rest, 1.0, *c)
        p = p + np.array(c)
        angles.append(math.degrees(signed_dihedral_angle(*p)))
    assert angles[-1] == pytest.approx(30.0, abs=1e-3)
    assert all(a > -10.0 - 1e-9 for a in angles)


def test_bending_takes_the_short_way_round_near_180():
    """Rest +175 deg, current -175 deg: 10 deg apart through 180, not 350 deg through 0."""
    p = hinge(-175.0)
    c = [np.zeros(3) for _ in range(4)]
    solve_bending_constraint(p[0], 1.0, p[1], 1.0, p[2], 1.0, p[3], 1.0, math.radians(175.0), 1.0, *c)
    q = p + np.array(c)
    assert abs(wrap_angle(signed_dihedral_angle(*q) - math.radians(175.0))) < math.radians(10.0)
    assert abs(math.degrees(signed_dihedral_angle(*q))) > 170.0


@pytest.mark.parametrize("kind", ["distance", "bending"])
def test_internal_constraints_conserve_linear_and_angular_momentum(kind):
    """Eqs. 3.3-3.4: sum m_i dp_i = 0 and sum m_i p_i x dp_i = 0."""
    rng = np.random.default_rng(3)
    c = [np.zeros(3) for _ in range(4)]
    for _ in range(50):
        p = rng.normal(size=(4, 3))
        w = rng.uniform(0.2, 3.0, 4)
        if kind == "distance":
            assert solve_distance_constraint(p[0], w[0], p[1], w[1], 0.5, 1.0, c[0], c[1])
            k = 2
        else:
            assert solve_bending_constraint(p[0], w[0], p[1], w[1], p[2], w[2], p[3], w[3],
                                            rng.uniform(-3, 3), 1.0, *c)
            k = 4
        m = 1.0 / w[:k]
        dp = np.array(c[:k])
        lin = (m[:, None] * dp).sum(axis=0)
        ang = (m[:, None] * np.cross(p[:k], dp)).sum(axis=0)
        scale = np.abs(m[:, None] * dp).max()
        assert np.abs(lin).max() <= 1e-12 * max(scale, 1e-300) + 1e-15
        assert np.abs(ang).max() <= 1e-11 * max(scale, 1e-300) + 1e-14


def strip(nu=6, nv=4, rng=None):
    """A bumpy grid mesh and its topology."""
    u, v = np.meshgrid(np.linspace(0, 1, nu), np.linspace(0, 0.6, nv), indexing="ij")
    x = np.stack([u, v, 0.1 * np.sin(3 * u) * np.cos(2 * v)], -1).reshape(-1, 3)
    if rng is not None:
        x = x + rng.normal(scale=0.01, size=x.shape)
    from inflo.tools.testing.flowers import grid_faces

    tri = grid_faces(nu, nv)
    return x, tri


def test_mesh_hinges_flat_grid_is_zero_and_matches_init():
    from inflo.tools.testing.flowers import grid_faces

    tri = grid_faces(4, 3)
    u, v = np.meshgrid(np.arange(4.0), np.arange(3.0), indexing="ij")
    x = np.stack([u, v, 0 * u], -1).reshape(-1, 3)
    h = mesh_hinges(tri)
    e = mesh_edges(tri)
    assert len(e) == 3 * 2 + 4 * 2 + 6 + 3 * 2 * 1 - 3  # grid edges + diagonals
    assert len(h) == len(e) - (2 * 3 + 2 * 2)  # interior edges
    np.testing.assert_allclose(hinge_angles(x, h), 0.0, atol=1e-15)
    for k in range(len(h)):
        assert init_bending_constraint(*x[h[k]]) == pytest.approx(0.0, abs=1e-15)


def test_bending_step_is_bounded_when_the_movable_vertex_barely_changes_the_angle():
    """Only p1 may move and both wings project (almost) onto p2: grad_1 = -((1 - s3) grad_3 +
    (1 - s4) grad_4) is ~1e-9 of the wings' gradients, so the linearized step C / |grad_1| would
    throw p1 ~1e9 hinge sizes away. The bound keeps every move within pi x the hinge's size, in
    the pure kernel and in the sweep alike; well-shaped hinges are untouched (the other tests)."""
    d = 1e-9
    p = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0 - d, 1.0, 0.0], [1.0 - d, -0.6, -0.8]])
    w = np.array([1.0, 0.0, 0.0, 0.0])
    rest = init_bending_constraint(*p) + 0.5
    c = [np.zeros(3) for _ in range(4)]
    g = [np.zeros(3) for _ in range(4)]
    assert dihedral_angle_gradients(*p, *g)
    assert np.linalg.norm(g[0]) < 1e-8 * np.linalg.norm(g[2])  # the runaway case
    assert solve_bending_constraint(p[0], w[0], p[1], w[1], p[2], w[2], p[3], w[3], rest, 1.0, *c)
    size = max(1.0, np.linalg.norm(np.cross(p[1] - p[0], p[2] - p[0])), np.linalg.norm(np.cross(p[1] - p[0], p[3] - p[0])))
    move = np.linalg.norm(c[0])
    assert 0.0 < move <= math.pi * size * (1 + 1e-12)
    assert not c[1].any() and not c[2].any() and not c[3].any()
    # the sweep does the same
    x = p.copy()
    project_bending_constraints(x, w, np.array([[0, 1, 2, 3]]), np.array([rest]), np.array([1.0]))
    np.testing.assert_allclose(x[0], p[0] + c[0], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(x[1:], p[1:])


def test_sweeps_equal_a_loop_over_the_pure_kernels():
    rng = np.random.default_rng(4)
    x, tri = strip(rng=rng)
    e, h = mesh_edges(tri), mesh_hinges(tri)
    w = rng.uniform(0.0, 2.0, len(x))
    w[:3] = 0.0
    rest_l = rng.uniform(0.1, 0.3, len(e))
    rest_a = rng.uniform(-1, 1, len(h))
    k_e, k_h = np.full(len(e), 0.9), np.full(len(h), 0.8)
    fast = x.copy()
    project_distance_constraints(fast, w, e, rest_l, k_e)
    project_bending_constraints(fast, w, h, rest_a, k_h)
    ref = x.copy()
    c = [np.zeros(3) for _ in range(4)]
    for i, (a, b) in enumerate(e):
        solve_distance_constraint(ref[a], w[a], ref[b], w[b], rest_l[i], 0.9, c[0], c[1])
        ref[a] += c[0]
        ref[b] += c[1]
    for i, q in enumerate(h):
        solve_bending_constraint(ref[q[0]], w[q[0]], ref[q[1]], w[q[1]], ref[q[2]], w[q[2]], ref[q[3]], w[q[3]],
                                 rest_a[i], 0.8, *c)
        for j in range(4):
            ref[q[j]] += c[j]
    np.testing.assert_allclose(fast, ref, rtol=0, atol=1e-13)


def test_colouring_separates_constraints_and_coloured_sweeps_converge_deterministically():
    rng = np.random.default_rng(5)
    x, tri = strip(8, 5, rng=rng)
    e, h = mesh_edges(tri), mesh_hinges(tri)
    for idx in (e, h):
        order, offsets = colour_constraints(idx, len(x))
        assert sorted(order.tolist()) == list(range(len(idx)))
        for c in range(len(offsets) - 1):
            members = idx[order[offsets[c]:offsets[c + 1]]].ravel()
            assert len(np.unique(members)) == len(members)
    target_l = np.linalg.norm(x[e[:, 0]] - x[e[:, 1]], axis=1)
    target_a = hinge_angles(x, h)
    w = np.ones(len(x))
    w[:5] = 0.0
    start = x + rng.normal(scale=0.02, size=x.shape)
    start[:5] = x[:5]
    runs = []
    for _ in range(2):
        y = start.copy()
        ce, ch = colour_constraints(e, len(x)), colour_constraints(h, len(x))
        for _ in range(200):
            project_distance_constraints_coloured(y, w, e, target_l, np.ones(len(e)), *ce)
            project_bending_constraints_coloured(y, w, h, target_a, np.ones(len(h)), *ch)
        runs.append(y)
    np.testing.assert_array_equal(runs[0], runs[1])
    assert np.abs(np.linalg.norm(runs[0][e[:, 0]] - runs[0][e[:, 1]], axis=1) - target_l).max() < 1e-4


def _strips(n, nu, nv, rng):
    """``n`` disjoint random strips (parts) 5 apart: positions, part per vertex, edges, hinges and
    their rest lengths and angles (the positions given)."""
    xs, tris = [], []
    for p in range(n):
        x, tri = strip(nu, nv, rng=rng)
        tris.append(tri + sum(len(a) for a in xs))
        xs.append(x + [0.0, 0.0, 5.0 * p])
    x = np.concatenate(xs)
    part = np.repeat(np.arange(n), [len(a) for a in xs])
    e = np.concatenate([mesh_edges(t) for t in tris]).astype(np.int32)
    h = np.concatenate([mesh_hinges(t) for t in tris]).astype(np.int32)
    return x, part, e, h, np.linalg.norm(x[e[:, 0]] - x[e[:, 1]], axis=1), hinge_angles(x, h)


def test_solving_part_by_part_equals_the_serial_sweeps_and_stops_parts_at_rest():
    """project_internal_by_part on three disjoint strips (parts) gives, part by part, exactly the
    serial Gauss-Seidel sweeps; a part already at rest stops after one sweep; part_offsets refuses
    constraints that are not grouped by part or that join two parts."""
    from inflo.tools.pbd import part_offsets, project_internal_by_part

    rng = np.random.default_rng(11)
    x, part, e, h, rest_l, rest_a = _strips(3, 6, 4, rng)
    w = np.ones(len(x))
    start = x.copy()
    moved = part != 1  # part 1 stays at rest
    start[moved] += rng.normal(scale=0.05, size=(int(moved.sum()), 3))
    eo, ho = part_offsets(e, part, 3), part_offsets(h, part, 3)
    assert eo.tolist()[0] == 0 and eo[-1] == len(e)
    k_e, k_h = np.full(len(e), 0.9), np.full(len(h), 0.7)
    got = start.copy()
    sweeps = np.zeros(3, np.int64)
    project_internal_by_part(got, w, e, rest_l, k_e, eo, h, rest_a, k_h, ho, 7, 1e-12, sweeps)
    ref = start.copy()
    for _ in range(7):
        project_distance_constraints(ref, w, e, rest_l, k_e)
        project_bending_constraints(ref, w, h, rest_a, k_h)
    assert sweeps.tolist() == [7, 1, 7]
    np.testing.assert_allclose(got[part == 1], start[part == 1], rtol=0, atol=1e-12)
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-14)
    # not grouped by part, or joining two parts: no offsets
    assert part_offsets(e[::-1], part, 3) is None
    joined = e.copy()
    joined[0, 1] = len(x) - 1
    assert part_offsets(joined, part, 3) is None


def test_serial_and_parallel_part_solves_give_the_same_positions(monkeypatch):
    """solve_parts picks the serial kernels below SERIAL_CONSTRAINTS_BELOW constraints (waking the
    thread pool costs more than a small system's sweeps); both kinds give identical positions and
    sweep counts, for the whole system and for a list of parts."""
    from inflo.tools.pbd import part_offsets, solver

    rng = np.random.default_rng(5)
    x, part, e, h, rest_l, rest_a = _strips(5, 8, 5, rng)
    start = x + rng.normal(scale=0.05, size=x.shape)
    args = (np.ones(len(x)), e, rest_l, np.full(len(e), 0.9), part_offsets(e, part, 5), h, rest_a,
            np.full(len(h), 0.7), part_offsets(h, part, 5))
    out = {}
    for below in (10**9, 0):  # serial, then parallel
        monkeypatch.setattr(solver, "SERIAL_CONSTRAINTS_BELOW", below)
        a, b = start.copy(), start.copy()
        sweeps = np.zeros(5, np.int64)
        n_all = solver.solve_parts(a, *args, 9, 1e-12, sweeps)
        n_some = solver.solve_parts(b, *args, 9, 1e-12, None, parts=np.array([3, 1], np.int64))
        out[below] = (a, b, sweeps.copy(), n_all, n_some)
    (a1, b1, s1, n1, m1), (a2, b2, s2, n2, m2) = out[10**9], out[0]
    assert np.array_equal(a1, a2) and np.array_equal(b1, b2) and np.array_equal(s1, s2)
    assert (n1, m1) == (n2, m2) == (int(s1.sum()), int(s1[1] + s1[3]))
    assert np.array_equal(b1[part == 0], start[part == 0]) and not np.array_equal(b1[part == 3], start[part == 3])


def test_overstretched_edges_finds_torn_and_non_finite_edges():
    x = np.array([[0.0, 0, 0], [1.0, 0, 0], [0.0, 60.0, 0], [np.nan, 0, 0]])
    e = np.array([[0, 1], [0, 2], [1, 3], [0, 1]], np.int32)
    rest = np.array([1.0, 1.0, 1.0, 0.0])
    np.testing.assert_array_equal(overstretched_edges(x, e, rest, 50.0, 1e-12), [1, 2, 3])
    # a zero rest length counts as the floor: edge 3 (length 1) is fine with a floor of 0.1
    np.testing.assert_array_equal(overstretched_edges(x, e, rest, 50.0, 0.1), [1, 2])


# ----------------------------------------------------------------------------------------------
# Parts, stretch figures
# ----------------------------------------------------------------------------------------------


def _two_triangles():
    """Two separate triangles (parts 0 and 1), each with its three edges."""
    x = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 0, 0], [6, 0, 0], [5, 1, 0]], float)
    edges = np.array([[0, 1], [1, 2], [0, 2], [3, 4], [4, 5], [3, 5]], np.int32)
    rest = np.sqrt(((x[edges[:, 0]] - x[edges[:, 1]]) ** 2).sum(axis=1))
    return x, edges, rest


def test_project_internal_of_parts_solves_only_the_listed_parts():
    from inflo.tools.pbd.solver import project_internal_by_part, project_internal_of_parts

    x, edges, rest = _two_triangles()
    x[1, 0] = 2.0  # both parts stretched
    x[4, 0] = 7.0
    w = np.ones(6)
    hinges = np.zeros((0, 4), np.int32)
    e_off = np.array([0, 3, 6], np.int64)
    h_off = np.zeros(3, np.int64)
    k = np.ones(6)
    y = x.copy()
    n = project_internal_of_parts(y, w, edges, rest, k, e_off, hinges, np.zeros(0), np.zeros(0), h_off,
                                  np.array([1], np.int64), 50, 1e-12)
    assert n > 1
    assert np.array_equal(y[:3], x[:3])  # part 0 untouched
    assert np.allclose(np.sqrt(((y[edges[3:, 0]] - y[edges[3:, 1]]) ** 2).sum(axis=1)), rest[3:], atol=1e-6)
    # the same arithmetic as the whole-canopy solve, part by part
    z = x.copy()
    project_internal_by_part(z, w, edges, rest, k, e_off, hinges, np.zeros(0), np.zeros(0), h_off, 50, 1e-12,
                             np.zeros(2, np.int64))
    assert np.array_equal(z[3:], y[3:])


def test_edge_stretch_range_and_parts_out_of_bounds():
    from inflo.tools.pbd.solver import edge_stretch_range, parts_out_of_bounds

    x, edges, rest = _two_triangles()
    assert edge_stretch_range(x, edges, rest, 1e-9) == (1.0, 1.0)
    x[4, 0] = 7.0  # edge 3-4 twice its rest length, 4-5 longer too
    lo, hi = edge_stretch_range(x, edges, rest, 1e-9)
    assert hi == pytest.approx(2.0) and lo == 1.0
    vp = np.array([0, 0, 0, 1, 1, 1], np.int32)
    assert parts_out_of_bounds(x, edges, rest, vp, 2, 0.5, 1.5, 1e-9).tolist() == [False, True]
    assert parts_out_of_bounds(x, edges, rest, vp, 2, 0.5, 2.5, 1e-9).tolist() == [False, False]
    # edges shorter than the floor are not measured; a squeezed edge and NaN count
    assert edge_stretch_range(x, edges, rest, 10.0) == (1.0, 1.0)
    x[1] = [0.1, 0.0, 0.0]
    assert parts_out_of_bounds(x, edges, rest, vp, 2, 0.5, 2.5, 1e-9).tolist() == [True, False]
    x[5, 0] = np.nan
    assert parts_out_of_bounds(x, edges, rest, vp, 2, 0.0, 1e9, 1e-9)[1]
    assert math.isnan(edge_stretch_range(x, edges, rest, 1e-9)[1])


def test_bending_at_rest_does_not_move_a_vertex_with_a_vanishing_gradient():
    """A hinge at its rest angle up to round-off (1e-14 rad) whose only movable vertex is an edge
    vertex with a (nearly) vanishing gradient: both wings fixed and projecting onto the other end
    of the edge, as in a one-segment cylinder standing on a fixed base ring (the sunflower's
    pistil). The undamped step C / |grad_1| moved p1 by the floret's size; the damped step
    (constraints.BENDING_DAMPING) leaves it in place, in the pure kernel and in the sweep."""
    d = 1e-15
    p = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0 - d, 1.0, 0.0], [1.0 - d, -0.6, -0.8]])
    w = np.array([1.0, 0.0, 0.0, 0.0])
    rest = init_bending_constraint(*p) + 1e-14
    c = [np.zeros(3) for _ in range(4)]
    solve_bending_constraint(p[0], w[0], p[1], w[1], p[2], w[2], p[3], w[3], rest, 1.0, *c)
    assert np.linalg.norm(c[0]) < 1e-12
    x = p.copy()
    project_bending_constraints(x, w, np.array([[0, 1, 2, 3]]), np.array([rest]), np.array([1.0]))
    assert np.linalg.norm(x - p) < 1e-12
    # a real angle error on a well-shaped hinge is still corrected as before (damping ~1e-12)
    q = hinge(40.0)
    wq = np.ones(4)
    rest = math.radians(50.0)
    y = q.copy()
    for _ in range(50):
        project_bending_constraints(y, wq, np.array([[0, 1, 2, 3]]), np.array([rest]), np.array([1.0]))
    assert signed_dihedral_angle(*y) == pytest.approx(rest, abs=1e-9)
