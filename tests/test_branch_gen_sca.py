"""branch-gen --algorithm sca: space colonization and envelopes (Runions ch. 3)."""
from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import run_cli
from scipy.spatial import cKDTree

from inflo.formats.contour import Contour, write_con
from inflo.formats.errors import FormatError
from inflo.formats.obj import read_obj
from inflo.tools.branch_gen.envelope import HERMITE, Envelope, catmull_rom, profile_from_contour
from inflo.tools.branch_gen.params import params_from_dict
from inflo.tools.branch_gen.pipe import check_forest, pipe_radii
from inflo.tools.branch_gen.sca import attraction_points, colonize, grow_sca


def test_branch_gen_sca_kill_distance_removes_points():
    rng = np.random.default_rng(0)
    env = Envelope("sphere", (0, 0, 0), radius=1.0)
    pts = attraction_points(env, 600, rng)
    d_k = 0.05
    res = colonize(pts, [[0.0, 0.0, 0.0]], step=0.02, kill_distance=d_k)
    check_forest(res.node_parent)
    d, _ = cKDTree(res.node_pos).query(res.points)
    # dead <=> some node came within d_k (exact, against a fresh kd-tree of all nodes)
    assert np.all(d[~res.alive] < d_k)
    assert np.all(d[res.alive] >= d_k)
    np.testing.assert_allclose(res.near_d[res.alive], d[res.alive], rtol=1e-12, atol=1e-15)
    # with d_I = inf every point is reached in the end
    assert not res.alive.any()
    # segments are exactly D long
    kids = np.nonzero(res.node_parent >= 0)[0]
    seg = np.linalg.norm(res.node_pos[kids] - res.node_pos[res.node_parent[kids]], axis=1)
    np.testing.assert_allclose(seg, 0.02, rtol=1e-12)


def test_branch_gen_sca_points_out_of_reach_stay():
    """Points farther than d_I from every node never influence growth."""
    rng = np.random.default_rng(1)
    env = Envelope("sphere", (0, 0, 0), radius=1.0)
    pts = attraction_points(env, 400, rng)
    res = colonize(pts, [[0.0, 0.0, 0.0]], step=0.02, kill_distance=0.05, influence_radius=0.25)
    live = res.alive
    assert np.all(res.near_d[live] >= 0.05)
    assert np.all(res.near_d[live] >= 0.25), "killed or out of reach"
    assert 0 < live.sum() < len(pts)


def test_branch_gen_sca_tree_stays_inside_envelope():
    p = params_from_dict({"algorithm": "sca", "seed": 3,
                          "sca": {"n_points": 800, "step": 0.02, "kill_distance": 0.04, "roots": [[0.0, 0.0, 0.0]]},
                          "envelope": {"shape": "ellipsoid", "centre": [0.0, 0.5, 0.0], "radii": [0.5, 0.5, 0.3]}})
    env = Envelope("ellipsoid", (0, 0.5, 0), radii=(0.5, 0.5, 0.3))
    sk, res = grow_sca(p, env)
    assert sk.n_nodes > 200
    # no node outside the envelope by more than D: test points D inward of each node's
    # projection... simpler and stricter: the node shrunk toward the centre by D is inside
    c = np.array([0.0, 0.5, 0.0])
    q = (sk.node_pos - c) / np.array([0.5, 0.5, 0.3])
    rad = np.linalg.norm(q, axis=1)
    pulled = c + (sk.node_pos - c) * np.clip((rad - 0.02 / 0.3) / np.maximum(rad, 1e-12), 0, 1)[:, None]
    assert np.all(env.contains(pulled) | (rad <= 1.0))
    assert np.all(env.contains(res.points))


def test_branch_gen_sca_tropism_bends_as_fig_3_4():
    """One root, one attraction point: g up bends the branch above the straight path, g down the
    mirror image below it; both reach the point."""
    pts = np.array([[1.0, 0.0, 0.0]])
    paths = {}
    for sign in (1, -1):
        res = colonize(pts, [[0.0, 0.0, 0.0]], step=0.01, kill_distance=0.02, tropism=(0.0, 0.35 * sign, 0.0))
        assert not res.alive[0]
        paths[sign] = res.node_pos
    assert paths[1][:, 1].max() > 0.05 and paths[1][:, 1].min() >= -1e-12
    mirror = paths[-1] * [1, -1, 1]
    np.testing.assert_allclose(paths[1], mirror, atol=1e-12)
    straight = colonize(pts, [[0.0, 0.0, 0.0]], step=0.01, kill_distance=0.02).node_pos
    assert np.abs(straight[:, 1]).max() < 1e-12


def test_branch_gen_sca_hedge_and_obstacle():
    """Several roots compete for the points (fig. 3.20); a plane removes points behind it."""
    rng = np.random.default_rng(2)
    env = Envelope("cylinder", (-1, 0, -0.2), radius=1.0, height=1.0)
    pts = attraction_points(env, 500, rng, obstacles=[[0.0, 0.0, 1.0, 0.0]])
    assert np.all(pts[:, 2] <= 0.0)
    roots = [[-1.5, 0.0, -0.2], [-1.0, 0.0, -0.2], [-0.5, 0.0, -0.2]]
    res = colonize(pts, roots, step=0.02, kill_distance=0.04)
    root_of = np.arange(len(res.node_pos))
    for _ in range(len(res.node_pos)):
        nxt = np.where(res.node_parent[root_of] >= 0, res.node_parent[root_of], root_of)
        if np.array_equal(nxt, root_of):
            break
        root_of = nxt
    assert set(np.unique(root_of)) == {0, 1, 2}, "every root grows a tree"


def _colonize_brute_force(points, roots, *, step, kill_distance, influence_radius=math.inf, tropism=(0.0, 0.0, 0.0),
                          max_iterations=100000):
    """A slow transcription of the space colonization loop (eq. 3.1, 3.3) for small N: every live
    point is compared with every node of the last iteration, in node order, with a strict ``<``;
    the same floating-point operations in the same order as the library, so results are equal bit
    for bit. Returns (node_pos, node_parent, node_iter, alive, near_d, iterations)."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    g = np.asarray(tropism, dtype=np.float64)
    node_pos = [np.asarray(r, dtype=np.float64) for r in np.asarray(roots, dtype=np.float64).reshape(-1, 3)]
    node_parent = [-1] * len(node_pos)
    node_iter = [-1] * len(node_pos)
    last_dir = {}
    alive = np.ones(len(pts), bool)
    near = np.full(len(pts), -1)
    near_d2 = np.full(len(pts), np.inf)
    d_i2 = influence_radius * influence_radius if math.isfinite(influence_radius) else math.inf
    d_k2 = kill_distance * kill_distance

    def biased(n):
        nn = math.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
        if nn < 1e-12:
            return np.zeros(3)
        u = n / nn + g
        un = math.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
        return np.zeros(3) if un < 1e-12 else u / un

    def dot(a, b):
        return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]

    new_from, it = 0, 0
    while it < max_iterations:
        for v in range(new_from, len(node_pos)):
            q = node_pos[v]
            dx, dy, dz = q[0] - pts[:, 0], q[1] - pts[:, 1], q[2] - pts[:, 2]
            d2 = dx * dx + dy * dy + dz * dz
            better = alive & (d2 < near_d2)
            near_d2[better] = d2[better]
            near[better] = v
        alive &= ~(near_d2 < d_k2)
        new_from = len(node_pos)
        acc, closest, touched = {}, {}, []
        for s in np.flatnonzero(alive):
            if near_d2[s] >= d_i2:
                continue
            v = int(near[s])
            d = math.sqrt(near_d2[s])
            if d <= 0.0:
                continue
            if v not in acc:
                acc[v] = np.zeros(3)
                closest[v] = s
                touched.append(v)
            else:
                dc = math.sqrt(near_d2[closest[v]])
                if d < dc or (d == dc and s < closest[v]):
                    closest[v] = s
            acc[v] += (pts[s] - node_pos[v]) / d
        grown = 0
        for v in touched:
            ld = last_dir.get(v, np.zeros(3))
            u = biased(acc[v])
            if dot(u, ld) > 1.0 - 1e-12:
                u = biased(pts[closest[v]] - node_pos[v])
                if dot(u, ld) > 1.0 - 1e-12:
                    continue
            if not u.any():
                continue
            node_pos.append(node_pos[v] + step * u)
            node_parent.append(v)
            node_iter.append(it)
            last_dir[v] = u
            grown += 1
        it += 1
        if grown == 0:
            break
    return np.array(node_pos), np.array(node_parent), np.array(node_iter), alive, np.sqrt(near_d2), it


def _grid_points():
    """Points on a lattice around the root: many exactly equal distances (ties)."""
    t = np.linspace(-0.5, 0.5, 7)
    return np.stack(np.meshgrid(t, t, t, indexing="ij"), -1).reshape(-1, 3) + [0.013, 0.0, 0.0]


def _plane_points():
    """Points on the plane x = 0 (y, z on a 1/16 lattice, a lopsided subset): each exactly as
    far from the root (-0.5, 0, 0) as from the root (0.5, 0, 0)."""
    t = np.arange(0, 13) / 16
    yz = np.stack(np.meshgrid(t, t, indexing="ij"), -1).reshape(-1, 2)
    yz = yz[np.random.default_rng(12).random(len(yz)) < 0.6]
    return np.c_[np.zeros(len(yz)), yz]


@pytest.mark.parametrize("case", ["sphere", "influence_hedge_tropism", "lattice", "tied_roots", "one_point",
                                  "max_iterations"])
def test_branch_gen_sca_matches_brute_force_reference(case):
    """The incremental nearest-node search (kd-trees, pruning, dead points dropped) gives exactly
    the tree of comparing every live point with every new node."""
    rng = np.random.default_rng(11)
    sphere = Envelope("sphere", (0, 0, 0), radius=1.0)
    kw = dict(step=0.03, kill_distance=0.06)
    roots = [[0.0, 0.0, 0.0]]
    if case == "sphere":
        pts = attraction_points(sphere, 500, rng)
    elif case == "influence_hedge_tropism":
        pts = attraction_points(sphere, 500, rng)
        roots = [[0.0, -1.0, 0.0], [0.3, -1.0, 0.0]]
        kw.update(influence_radius=0.4, tropism=(0.0, 0.2, 0.0))
    elif case == "lattice":
        pts = _grid_points()
        kw = dict(step=0.05, kill_distance=0.1)
    elif case == "tied_roots":
        # every point ties between the two roots in the first iteration: the lower index wins
        pts = _plane_points()
        roots = [[-0.5, 0.0, 0.0], [0.5, 0.0, 0.0]]
        kw = dict(step=0.05, kill_distance=0.1)
    elif case == "one_point":
        pts = np.array([[1.0, 0.0, 0.0]])
        kw = dict(step=0.01, kill_distance=0.02, tropism=(0.0, 0.35, 0.0))
    else:
        pts = attraction_points(sphere, 500, rng)
        kw.update(max_iterations=7)
    res = colonize(pts, roots, **kw)
    node_pos, node_parent, node_iter, alive, near_d, iterations = _colonize_brute_force(pts, roots, **kw)
    assert len(res.node_pos) > 20
    np.testing.assert_array_equal(res.node_pos, node_pos)
    np.testing.assert_array_equal(res.node_parent, node_parent)
    np.testing.assert_array_equal(res.node_iter, node_iter)
    np.testing.assert_array_equal(res.alive, alive)
    np.testing.assert_array_equal(res.near_d, near_d)
    assert res.iterations == iterations


def test_branch_gen_sca_work_grows_about_linearly():
    """Runions fig. 3.9: run time about linear in N. Counted, not timed: the point-node distances
    the nearest-node updates compute (and the kd-tree nodes they enter) for N and 4N points in
    the unit sphere (D = 0.01, d_k = 2D, d_I = inf) grow by less than 4^1.15; comparing every
    live point with every new node grows by about 4^1.5."""
    env = Envelope("sphere", (0, 0, 0), radius=1.0)
    work = []
    for n in (1000, 4000):
        pts = attraction_points(env, n, np.random.default_rng(0))
        res = colonize(pts, [[0.0, 0.0, 0.0]], step=0.01, kill_distance=0.02)
        assert not res.alive.any()
        work.append((res.distance_evaluations, res.tree_visits))
    (e1, v1), (e4, v4) = work
    assert e1 > 0 and v1 > 0
    assert e4 / e1 < 4 ** 1.15, work
    assert (e4 + v4) / (e1 + v1) < 4 ** 1.15, work


def test_branch_gen_overdispersed_points_keep_min_distance():
    rng = np.random.default_rng(4)
    env = Envelope("sphere", (0, 0, 0), radius=1.0)
    pts = attraction_points(env, 500, rng, min_distance=0.1)
    d, _ = cKDTree(pts).query(pts, k=2)
    assert d[:, 1].min() >= 0.1
    assert np.all(env.contains(pts))


# --------------------------------------------------------------------------------------------
# envelopes


def test_branch_gen_catmull_rom_eq_3_4():
    h1, h2, h3, h4 = HERMITE(np.array([0.0, 1.0]))
    np.testing.assert_array_equal(h1, [1, 0])
    np.testing.assert_array_equal(h2, [0, 1])
    np.testing.assert_array_equal(h3, [0, 0])
    np.testing.assert_array_equal(h4, [0, 0])
    angles = np.radians([0.0, 100.0, 200.0, 280.0])
    vals = np.array([[1.0], [2.0], [0.5], [1.5]])
    # interpolates the curves at their angles
    for i, a in enumerate(angles):
        assert catmull_rom(vals, angles, np.array([a]))[0] == pytest.approx(vals[i, 0], abs=1e-12)
    # first-order continuity across every theta_i, including the wrap at 2 pi (eq. 3.4's tangents
    # are in t, so the slope in theta is continuous for equally spaced curves)
    eps = 1e-6
    even = np.radians([0.0, 90.0, 180.0, 270.0])
    for a in even:
        left = (catmull_rom(vals, even, np.array([a])) - catmull_rom(vals, even, np.array([a - eps]))) / eps
        right = (catmull_rom(vals, even, np.array([a + eps])) - catmull_rom(vals, even, np.array([a]))) / eps
        assert left[0] == pytest.approx(right[0], abs=1e-4)
    # a slow scalar transcription of eq. 3.4 at a point between theta_4 and theta_1 + 2 pi
    th = np.radians(330.0)
    t = (th - angles[3]) / (angles[0] + 2 * np.pi - angles[3])
    c = vals[:, 0]
    ref = (c[3] * (2 * t**3 - 3 * t**2 + 1) + c[0] * (-2 * t**3 + 3 * t**2)
           + (c[0] - c[2]) / 2 * (t**3 - 2 * t**2 + t) + (c[1] - c[3]) / 2 * (t**3 - t**2))
    assert catmull_rom(vals, angles, np.array([th]))[0] == pytest.approx(ref, abs=1e-12)


def _profile_contour(radius_scale):
    # x = radius, y = height: a bulb from (0, 0) over radius r to (0, 1)
    pts = [[0.0, 0.0], [0.5 * radius_scale, 0.1], [radius_scale, 0.5], [0.6 * radius_scale, 0.9], [0.0, 1.0]]
    return Contour.from_points(pts, type="oe", name="profile")


def test_branch_gen_surface_of_revolution_contains_generating_points():
    profiles = [profile_from_contour(_profile_contour(s)) for s in (0.5, 0.8, 0.35)]
    angles = [0.0, 120.0, 240.0]
    env = Envelope("contours", (0, 0, 0), profiles=profiles, angles=angles)
    for (hgt, rad), a in zip(profiles, np.radians(angles)):
        sel = slice(20, -20, 10)
        z, r = hgt[sel], rad[sel]
        on = np.c_[r * np.cos(a), z, r * np.sin(a)]
        assert np.all(env.contains(on * [1 - 1e-6, 1, 1 - 1e-6]))
        assert not np.any(env.contains(on * [1 + 1e-3, 1, 1 + 1e-3]))
        np.testing.assert_allclose(env.surface_radius(np.full(len(z), a), z), r, atol=1e-12)
    lo, hi = env.bounds()
    rng = np.random.default_rng(5)
    pts = attraction_points(env, 300, rng)
    assert np.all((pts >= lo) & (pts <= hi))


def test_branch_gen_contour_not_a_function_of_height(tmp_path):
    circle = Contour.from_points([[1, 0], [0, 1], [-1, 0], [0, -1]], type="cr", name="circle")
    with pytest.raises(FormatError, match="function of height"):
        profile_from_contour(circle, tmp_path / "c.con")


def test_branch_gen_cli_sca_with_contours(tmp_path, write):
    for k, s in enumerate((0.5, 0.8, 0.35)):
        write_con(tmp_path / f"c{k}.con", _profile_contour(s))
    prm = write("tree.toml", """algorithm = "sca"
seed = 2
[sca]
n_points = 300
step = 0.03
kill_distance = 0.06
roots = [[0.0, 0.0, 0.0]]
[envelope]
shape = "contours"
centre = [0.0, 0.3, 0.0]
contours = [{file = "c0.con", angle = 0.0}, {file = "c1.con", angle = 120.0}, {file = "c2.con", angle = 240.0}]
[post]
decimate = 0.06
relocate = true
subdivide = 1
""")
    scn = write("empty.scn", "# SCA ignores the florets\n")
    out = tmp_path / "out"
    r = run_cli("branch-gen", scn, prm, "-o", out, "-q")
    assert r.returncode == 0, r.stderr
    skel = read_obj(out / "skeleton.obj")
    radii = np.array([float(x) for x in (out / "skeleton.radii").read_text().splitlines() if x[0] != "#"])
    assert len(radii) == skel.n_vertices and skel.n_vertices > 50
    assert radii.max() > 3 * radii.min()
    # a bad contour is one clear line
    write_con(tmp_path / "c1.con", Contour.from_points([[1, 0], [0, 1], [-1, 0], [0, -1]], type="cr", name="o"))
    r = run_cli("branch-gen", scn, prm, "-o", tmp_path / "bad")
    assert r.returncode == 2 and "function of height" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


def test_branch_gen_sca_pipe_radii_on_tree():
    rng = np.random.default_rng(6)
    env = Envelope("sphere", (0, 1, 0), radius=0.5)
    res = colonize(attraction_points(env, 300, rng), [[0.0, 0.0, 0.0]], step=0.05, kill_distance=0.1)
    r = pipe_radii(res.node_parent, np.zeros(len(res.node_pos), bool), 0.01, 2.0)
    n_leaves = np.sum(np.bincount(res.node_parent[res.node_parent >= 0], minlength=len(r)) == 0)
    assert r[0] == pytest.approx(0.01 * np.sqrt(n_leaves), rel=1e-12)


def test_branch_gen_sca_points_added_during_the_run():
    p = params_from_dict({"algorithm": "sca", "seed": 5,
                          "sca": {"n_points": 200, "step": 0.03, "kill_distance": 0.06, "add_points": 20,
                                  "add_iterations": 5, "min_distance": 0.02},
                          "envelope": {"shape": "sphere", "centre": [0.0, 0.5, 0.0], "radius": 0.5}})
    sk, res = grow_sca(p, Envelope("sphere", (0, 0.5, 0), radius=0.5))
    assert len(res.points) == 300
    assert not res.alive.any()
    check_forest(sk.node_parent)


def test_branch_gen_sca_kernel_compiles_once():
    """The iteration kernel takes NamedTuples of arrays: one compiled signature, whatever
    the caller's scalar types, as the points are added and the node arrays grow."""
    from inflo.tools.branch_gen import sca

    rng = np.random.default_rng(2)
    env = Envelope("sphere", (0, 0, 0), radius=1.0)
    colonize(attraction_points(env, 150, rng), [[0.0, 0.0, 0.0]], step=0.05, kill_distance=0.1)
    # integer D, d_k, d_I, root and tropism; points added during the first iterations
    res = colonize(attraction_points(env, 150, rng) * 100, [[0, 0, 0]], step=2, kill_distance=4,
                   influence_radius=60, tropism=(0, 0, 0), add_iterations=10,
                   add_points=lambda it, existing: attraction_points(env, 100, rng) * 100)
    assert len(res.points) == 1150
    assert len(res.node_pos) > max(1024, 4 * 150 + 1), "the node arrays grew"
    assert len(sca._iterate.signatures) == 1
    assert len(sca._point_tree.signatures) == 1
