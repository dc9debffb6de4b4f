"""branch-gen: extended Rodkaew (thesis ch. 7), pipe model, generalized cylinders, CLI."""
from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import no_partial_files, run_cli
from scipy.spatial import cKDTree

from inflo.formats.errors import FormatError
from inflo.formats.obj import read_obj
from inflo.tools.branch_gen.cylinders import generalized_cylinders, parallel_transport
from inflo.tools.branch_gen.params import params_from_dict, read_params
from inflo.tools.branch_gen.pipe import basipetal_order, chains, check_forest, decimate, pipe_radii, subdivide
from inflo.tools.branch_gen.rodkaew import Level, RodkaewInput, grow_level, grow_rodkaew
from inflo.tools.branch_gen.skeleton import growth_scale

UP = np.array([0.0, 1.0, 0.0])


def _params(**rodkaew):
    return params_from_dict({"rodkaew": rodkaew})


def _disc(n, seed=0, y=1.0, radius=0.5):
    rng = np.random.default_rng(seed)
    r = radius * np.sqrt(rng.random(n))
    th = 2 * np.pi * rng.random(n)
    return np.c_[r * np.cos(th), np.full(n, y), r * np.sin(th)]


def _input(pos, emergence=None, group=None, groups=None):
    n = len(pos)
    return RodkaewInput(pos=pos, up=np.tile(UP, (n, 1)),
                        emergence=np.zeros(n) if emergence is None else np.asarray(emergence, float),
                        group=np.full(n, -1, np.int32) if group is None else np.asarray(group, np.int32),
                        groups=groups or {})


def _unit(v):
    return v / np.linalg.norm(v)


def _path_to_root(parent, v, limit=10**7):
    seen = 0
    while parent[v] >= 0:
        v = parent[v]
        seen += 1
        assert seen < limit
    return v


# --------------------------------------------------------------------------------------------
# eq. 7.1


def test_branch_gen_eq_7_1_two_particles():
    """One step of two particles: each moves by `step` along (w_a A + w_b B + w_h H) / sum(w)."""
    p0, p1 = np.array([-0.1, 1.0, 0.0]), np.array([0.1, 1.0, 0.05])
    w_a, w_b, w_h, step = 1.0, 0.7, 0.4, 0.01
    params = _params(step=step, merge_distance=0.011, w_a=w_a, w_b=w_b, w_h=w_h, max_steps=1, steps_per_frame=1)
    level = Level(target=np.zeros(3), start=np.array([p0, p1]), birth_frame=np.zeros(2), birth_pos=None,
                  initial_dir=np.array([-UP, -UP]))
    with pytest.warns(UserWarning, match="max_steps"):
        res = grow_level(level, params, base=np.zeros(3), end_frame=0.0)
    moved = [int(np.nonzero((res.node_branch == i) & (np.arange(len(res.node_branch)) != res.tip_node[i]))[0][0])
             for i in (0, 1)]
    # particle 0 moves first: B toward particle 1's floret (its only node)
    a0, b0 = _unit(-p0), _unit(p1 - p0)
    h0 = (w_a * a0 + w_b * b0 + w_h * -UP) / (w_a + w_b + w_h)
    np.testing.assert_allclose(res.node_pos[moved[0]], p0 + step * _unit(h0), atol=1e-12)
    # particle 1 then sees particle 0's new node (nearer than its floret)
    q0 = res.node_pos[moved[0]]
    a1, b1 = _unit(-p1), _unit(q0 - p1)
    h1 = (w_a * a1 + w_b * b1 + w_h * -UP) / (w_a + w_b + w_h)
    np.testing.assert_allclose(res.node_pos[moved[1]], p1 + step * _unit(h1), atol=1e-12)


def test_branch_gen_w_b_function_scales_attraction():
    """w_b(d) from a table: a table of zeros makes B vanish (the step is eq. 7.1 with w_b = 0)."""
    p0, p1 = np.array([-0.1, 1.0, 0.0]), np.array([0.1, 1.0, 0.0])
    params = _params(step=0.01, merge_distance=0.011, w_a=1.0, w_b=5.0, w_h=0.0, max_steps=1)
    level = Level(np.zeros(3), np.array([p0, p1]), np.zeros(2), None, np.array([-UP, -UP]))
    with pytest.warns(UserWarning):
        res = grow_level(level, params, base=np.zeros(3), end_frame=0.0, wb_table=np.zeros(11))
    moved = np.nonzero((res.node_branch == 0) & (np.arange(len(res.node_branch)) != res.tip_node[0]))[0][0]
    np.testing.assert_allclose(res.node_pos[moved], p0 + 0.01 * _unit(-p0), atol=1e-12)


# --------------------------------------------------------------------------------------------
# structure invariants


def _check_supported(sk, pos):
    check_forest(sk.node_parent)
    roots = np.nonzero(sk.node_parent < 0)[0]
    assert list(roots) == [0], "the only root is the base"
    np.testing.assert_array_equal(sk.node_pos[0], np.zeros(3))
    tips = np.nonzero(sk.node_tip)[0]
    assert sorted(sk.node_floret[tips]) == list(range(len(pos)))
    # tips exactly at the florets
    assert np.array_equal(sk.node_pos[tips], pos[sk.node_floret[tips]])
    for t in tips:
        assert _path_to_root(sk.node_parent, t) == 0


def test_branch_gen_every_floret_connected_to_base():
    pos = _disc(80, seed=1)
    sk = grow_rodkaew(_input(pos, emergence=np.linspace(0, 20, 80)), _params(steps_per_frame=3))
    _check_supported(sk, pos)
    # grafts happened (a branching structure, not an umbel)
    start, _ = np.unique(sk.node_parent[sk.node_parent >= 0], return_counts=True)
    assert np.sum(np.bincount(sk.node_parent[sk.node_parent >= 0]) >= 2) > 10


def test_branch_gen_grafting_never_merges_a_tree_with_itself():
    """Two florets closer than the merge distance: the first grafts onto the second; the second
    must then ignore the grafted nodes (its id propagated, fig. 7.5), or it would graft back and
    close a cycle. A lone particle likewise never merges with its own trail."""
    pos = np.array([[0.0, 1.0, 0.0], [0.004, 1.0, 0.0], [0.3, 1.0, 0.0]])
    sk = grow_rodkaew(_input(pos), _params(step=0.01, merge_distance=0.015))
    _check_supported(sk, pos)
    one = np.array([[0.2, 1.0, 0.1]])
    sk1 = grow_rodkaew(_input(one), _params(step=0.01, merge_distance=0.03, w_h=5.0))
    _check_supported(sk1, one)
    assert len(chains(sk1.node_parent, sk1.node_tip)) == 1
    length = np.linalg.norm(np.diff(sk1.node_pos[chains(sk1.node_parent, sk1.node_tip)[0]], axis=0), axis=1).sum()
    assert length >= np.linalg.norm(one[0]) - 1e-9


def test_branch_gen_w_b_zero_is_an_umbel():
    """Fig. 7.3a: with w_b = 0 (and w_h = 0) every particle runs straight to the base -- also with
    uniform growth of space, which scales about the base."""
    pos = _disc(40, seed=2)
    for growth in ({}, {"mode": "uniform", "rate": 0.05}):
        p = params_from_dict({"rodkaew": {"w_b": 0.0, "w_h": 0.0, "initial_direction": "base",
                                          "steps_per_frame": 2}, "growth": growth})
        sk = grow_rodkaew(_input(pos, emergence=np.arange(40) * 0.5), p)
        _check_supported(sk, pos)
        own = sk.node_branch >= 0
        f = pos[sk.node_branch[own]]
        x = sk.node_pos[own]
        # distance of each node from the line base -> its floret
        d = np.linalg.norm(np.cross(x, _unit_rows(f)), axis=1)
        assert d.max() < 1e-9
        s = np.einsum("ij,ij->i", x, _unit_rows(f))
        assert s.min() > -1e-12 and np.all(s <= np.linalg.norm(f, axis=1) + 1e-12)


def _unit_rows(v):
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def test_branch_gen_flat_canopy_stays_supported_in_its_plane():
    pos = _disc(60, seed=4)
    p = _params(w_b=1.0, w_h=1.0)
    sk = grow_rodkaew(_input(pos, emergence=np.linspace(0, 30, 60)[::-1]), p)
    _check_supported(sk, pos)
    assert np.all(sk.node_pos[sk.node_tip, 1] == 1.0)
    assert sk.node_pos[~sk.node_tip, 1].max() < 1.0, "branches stay below the canopy plane"


def test_branch_gen_hierarchy_levels_converge_on_group_centres():
    """Fig. 7.2b: umbellet florets reach their centre; the centres reach the base."""
    centres = {0: (np.array([-0.2, 0.8, 0.0]), -1), 1: (np.array([0.2, 0.8, 0.0]), -1)}
    pos, group = [], []
    for g, (c, _) in centres.items():
        for k in range(10):
            th = 2 * np.pi * k / 10
            pos.append(c + [0.06 * np.cos(th), 0.1, 0.06 * np.sin(th)])
            group.append(g)
    pos = np.array(pos)
    sk = grow_rodkaew(_input(pos, group=group, groups=centres), _params(w_b=0.3))
    _check_supported(sk, pos)
    for g, (c, _) in centres.items():
        hits = np.nonzero(np.all(sk.node_pos == c, axis=1))[0]
        assert len(hits) == 1, "one node at each group centre"
        centre_node = hits[0]
        for t in np.nonzero(sk.node_tip)[0]:
            v, on_path = t, False
            while v >= 0:
                on_path |= v == centre_node
                v = sk.node_parent[v]
            assert on_path == (group[sk.node_floret[t]] == g)


def test_branch_gen_deterministic():
    pos = _disc(50, seed=5)
    inp = _input(pos, emergence=np.linspace(0, 10, 50))
    a = grow_rodkaew(inp, _params())
    b = grow_rodkaew(inp, _params())
    assert np.array_equal(a.node_pos, b.node_pos) and np.array_equal(a.node_parent, b.node_parent)


# --------------------------------------------------------------------------------------------
# pipe model and post-processing


def _pipe_reference(parent, tip, r0, p):
    n = len(parent)
    kids = [[] for _ in range(n)]
    for v, q in enumerate(parent):
        if q >= 0:
            kids[q].append(v)

    def r(v):
        s = sum(r(c) ** p for c in kids[v])
        if tip[v] or not kids[v]:
            s += r0 ** p
        return s ** (1.0 / p)

    import sys
    sys.setrecursionlimit(100000)
    return np.array([r(v) for v in range(n)])


def test_branch_gen_pipe_model_holds_at_every_node():
    pos = _disc(40, seed=6)
    sk = grow_rodkaew(_input(pos, emergence=np.linspace(0, 10, 40)), _params())
    p, r0 = 2.5, 0.003
    r = pipe_radii(sk.node_parent, sk.node_tip, r0, p)
    # d^p = d_1^p + ... + d_m^p at every branching node (terminal segments have diameter 2 r0)
    for v in range(sk.n_nodes):
        kids = np.nonzero(sk.node_parent == v)[0]
        if len(kids):
            own = r0 ** p if sk.node_tip[v] else 0.0
            assert r[v] ** p == pytest.approx(own + np.sum(r[kids] ** p), rel=1e-12)
        else:
            assert r[v] == pytest.approx(r0, rel=1e-12)
    np.testing.assert_allclose(r, _pipe_reference(sk.node_parent, sk.node_tip, r0, p), rtol=1e-12)
    # with p = 2 the base carries the summed cross-sections of all tips
    r2 = pipe_radii(sk.node_parent, sk.node_tip, r0, 2.0)
    assert r2[0] == pytest.approx(r0 * math.sqrt(len(pos)), rel=1e-12)


def test_branch_gen_cycle_is_rejected():
    with pytest.raises(ValueError, match="cycle"):
        basipetal_order(np.array([-1, 2, 1]))


def test_branch_gen_decimation_fig_3_8():
    """tau_d = 0.035 on a straight branch with nodes 0.01 apart keeps every 4th node and the ends."""
    n = 21
    pos = np.c_[np.zeros(n), np.arange(n) * 0.01, np.zeros(n)]
    parent = np.arange(-1, n - 1)
    tip = np.zeros(n, bool)
    p2, par2, tip2, kept = decimate(pos, parent, tip, 0.035)
    assert list(kept) == [0, 4, 8, 12, 16, 20]
    check_forest(par2)
    assert list(par2) == [-1, 0, 1, 2, 3, 4]


def test_branch_gen_subdivision_keeps_joints_and_tips():
    pos = _disc(20, seed=7)
    sk = grow_rodkaew(_input(pos), _params())
    p2, par2, tip2 = subdivide(sk.node_pos, sk.node_parent, sk.node_tip, 1)
    check_forest(par2)
    assert len(p2) == 2 * sk.n_nodes - 1
    assert np.array_equal(p2[: sk.n_nodes][sk.node_tip], sk.node_pos[sk.node_tip])
    nkids = np.bincount(sk.node_parent[sk.node_parent >= 0], minlength=sk.n_nodes)
    joints = (nkids != 1) | (sk.node_parent < 0)
    assert np.array_equal(p2[: sk.n_nodes][joints], sk.node_pos[joints])


# --------------------------------------------------------------------------------------------
# generalized cylinders


def _edge_counts(faces):
    e = np.sort(np.vstack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    return counts


def test_branch_gen_cylinders_watertight_outward_tips_at_florets():
    pos = _disc(30, seed=8)
    sk = grow_rodkaew(_input(pos), _params())
    r = pipe_radii(sk.node_parent, sk.node_tip, 0.002, 2.5)
    ch = chains(sk.node_parent, sk.node_tip)
    verts, faces, vstart, normals = generalized_cylinders(sk.node_pos, sk.node_parent, ch, r, sides=6)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, rtol=1e-12)
    assert len(vstart) == len(ch) + 1
    fstart = np.cumsum([0] + [(len(c) - 1) * 12 + 12 for c in ch])
    assert fstart[-1] == len(faces)
    for c in range(len(ch)):
        f = faces[fstart[c]:fstart[c + 1]]
        assert f.min() >= vstart[c] and f.max() < vstart[c + 1], "each tube uses its own vertices"
        assert np.all(_edge_counts(f) == 2), "each tube is closed (every edge in two triangles)"
        v = verts
        vol = np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]])).sum() / 6.0
        assert vol > 0, "outward orientation"
        # distal cap centre is the chain's end node; at a floret tip exactly the floret position
        end = ch[c][-1]
        assert np.array_equal(verts[vstart[c + 1] - 1], sk.node_pos[end])
        if sk.node_tip[end]:
            assert np.array_equal(verts[vstart[c + 1] - 1], pos[sk.node_floret[end]])


def test_branch_gen_parallel_transport_does_not_twist():
    # straight line: every frame equal
    line = np.c_[np.zeros(10), np.linspace(0, 1, 10), np.zeros(10)]
    t, n = parallel_transport(line)
    assert np.allclose(n, n[0], atol=1e-15)
    # planar arc: a normal perpendicular to the plane stays so (no twist), perpendicular to t
    a = np.linspace(0, 2.0, 50)
    arc = np.c_[np.cos(a), np.sin(a), np.zeros(50)]
    t, n = parallel_transport(arc)
    assert np.allclose(n, n[0], atol=1e-12) and abs(n[0, 2]) == pytest.approx(1.0)
    assert np.abs(np.einsum("ij,ij->i", n, t)).max() < 1e-12
    # helix: agrees with a slow rotation-minimizing reference (rotate by the tangent change)
    s = np.linspace(0, 4 * np.pi, 2000)
    helix = np.c_[np.cos(s), 0.3 * s, np.sin(s)]
    t, n = parallel_transport(helix)
    ref = [n[0]]
    for i in range(len(s) - 1):
        axis = np.cross(t[i], t[i + 1])
        sn = np.linalg.norm(axis)
        cs = float(np.dot(t[i], t[i + 1]))
        if sn < 1e-15:
            ref.append(ref[-1])
            continue
        k = axis / sn
        v = ref[-1]
        ref.append(v * cs + np.cross(k, v) * sn + k * np.dot(k, v) * (1 - cs))
    ref = np.array(ref)
    assert np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", n, ref), -1, 1))).max() < 0.5


# --------------------------------------------------------------------------------------------
# growth


def test_branch_gen_growth_scale():
    s = growth_scale("allometric", 0.0, [0.1, 0.0, -0.05], 3, 10)
    np.testing.assert_allclose(s, [1.1 ** -7, 1.0, 0.95 ** -7])
    assert np.array_equal(growth_scale("uniform", 0.2, None, 12, 10), np.ones(3))
    assert np.array_equal(growth_scale("none", 0.2, None, 0, 10), np.ones(3))


# --------------------------------------------------------------------------------------------
# CLI


SCN = """# three florets in a plane
o: 0 -0.2 1.0 0.0 0.02 0.02 0.02 0 1 0 1 0 0
#@ emergence: 0
o: 0 0.2 1.0 0.05 0.02 0.02 0.02 0 1 0 1 0 0
#@ emergence: 2
o: 0 0.0 1.0 -0.2 0.02 0.02 0.02 0 1 0 1 0 0
#@ emergence: 4
"""


def test_branch_gen_cli_outputs_deterministic(tmp_path, write):
    scn = write("s.scn", SCN)
    prm = write("p.toml", "seed = 3\n[rodkaew]\nstep = 0.01\nmerge_distance = 0.02\n[cylinder]\nsides = 6\n")
    out1, out2 = tmp_path / "o1", tmp_path / "o2"
    for out in (out1, out2):
        r = run_cli("branch-gen", scn, prm, "-o", out, "-q")
        assert r.returncode == 0, r.stderr
    for name in ("skeleton.obj", "skeleton.radii", "branches.obj"):
        assert (out1 / name).read_bytes() == (out2 / name).read_bytes()
    skel = read_obj(out1 / "skeleton.obj")
    radii = [float(x) for x in (out1 / "skeleton.radii").read_text().splitlines() if not x.startswith("#")]
    assert len(radii) == skel.n_vertices and len(skel.lines) >= 3
    assert min(radii) == pytest.approx(0.002)
    br = read_obj(out1 / "branches.obj")
    florets = np.array([[-0.2, 1, 0], [0.2, 1, 0.05], [0, 1, -0.2]])
    d, _ = cKDTree(br.vertices).query(florets)
    assert np.all(d < 1e-6), "a branch tip vertex at every floret"
    # minimal invocation: no parameter file
    r = run_cli("branch-gen", scn, "-o", tmp_path / "o3", "-q")
    assert r.returncode == 0, r.stderr


def test_branch_gen_cli_rba_frames(tmp_path, write):
    pos = np.array([[-0.2, 1.0, 0.0], [0.2, 1.0, 0.05], [0.0, 1.0, -0.2]])
    lines = []
    for p in pos:
        lines.append("rba: 0 %.3f %.3f %.3f 0.02 0.02 0.02 0 1 0 1 0 0 0 5" % tuple(p))
    scn = write("s.scn", "\n".join(lines) + "\n")
    for f in range(6):
        present = [k for k in range(3) if f >= 2 * k]
        write(f"rba/{f:04d}.rba", "".join("%d %.3f %.3f %.3f 0.02 0.02 0.02 0 1 0 1 0 0\n" % (k, *(pos[k] * (0.5 + 0.1 * f)))
                                         for k in present))
    prm = write("p.toml", "[rodkaew]\nsteps_per_frame = 30\n[growth]\nmode = \"uniform\"\nrate = 0.1\n")
    out = tmp_path / "out"
    r = run_cli("branch-gen", scn, prm, "--rba", tmp_path / "rba", "-o", out, "-q")
    assert r.returncode == 0, r.stderr
    frames = sorted((out / "frames").glob("branches_*.obj"))
    assert [p.name for p in frames] == [f"branches_{f:04d}.obj" for f in range(6)]
    n_faces = [read_obj(p).n_faces for p in frames]
    assert n_faces[0] < n_faces[-1]
    last = read_obj(frames[-1])
    d, _ = cKDTree(last.vertices).query(pos)
    assert np.all(d < 1e-6), "in the last frame the tips sit on the florets of that frame"
    assert no_partial_files(out)
    # a rerun replaces the earlier run's own files, never mixes them, and keeps a user's file
    (out / "frames" / "notes.txt").write_text("mine\n")
    r = run_cli("branch-gen", scn, prm, "--rba", tmp_path / "rba", "--frame-step", "4", "-o", out, "-q")
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in (out / "frames").iterdir()) == ["branches_0000.obj", "branches_0004.obj",
                                                                  "branches_0005.obj", "notes.txt"]
    r = run_cli("branch-gen", scn, prm, "-o", out, "-q")
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in (out / "frames").iterdir()) == ["notes.txt"]
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == [
        "branches.obj", "frames", "skeleton.obj", "skeleton.radii"]


@pytest.mark.parametrize("toml, match", [
    ("[rodkaew]\nmerge_distanse = 0.1\n", "did you mean 'merge_distance'"),
    ("[rodkaw]\nstep = 0.1\n", "did you mean 'rodkaew'"),
    ("[rodkaew]\nstep = -0.01\n", "step length > 0"),
    ("[rodkaew]\nmerge_distance = 0.0\n", "merge distance > 0"),
    ("[rodkaew]\nw_b = nan\n", "finite number"),
    ("[rodkaew]\nw_a = inf\n", "finite number"),
    ("[rodkaew]\nstep = \"big\"\n", "a number"),
    ("[sca]\nroots = [[0, 0]]\n", "list of 3 numbers"),
])
def test_branch_gen_bad_parameters(write, toml, match):
    prm = write("p.toml", "# params\n" + toml)
    with pytest.raises(FormatError) as err:
        read_params(prm)
    assert match in str(err.value)
    assert err.value.line in (2, 3)


def test_branch_gen_cli_bad_parameters_one_line(tmp_path, write):
    scn = write("s.scn", SCN)
    prm = write("p.toml", "# params\n[rodkaew]\nmerge_distanse = 0.1\n")
    r = run_cli("branch-gen", scn, prm, "-o", tmp_path / "out")
    assert r.returncode == 2, r.stderr
    assert "p.toml:3" in r.stderr and "did you mean 'merge_distance'" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_branch_gen_cli_empty_scene_and_step_warning(tmp_path, write):
    scn = write("empty.scn", "# nothing\n")
    r = run_cli("branch-gen", scn, "-o", tmp_path / "out")
    assert r.returncode == 2 and "no florets" in r.stderr
    assert not (tmp_path / "out").exists()
    prm = write("p.toml", "[rodkaew]\nstep = 0.03\nmerge_distance = 0.02\n")
    r = run_cli("branch-gen", write("s.scn", SCN), prm, "-o", tmp_path / "o2", "-q")
    assert r.returncode == 0 and "larger than merge_distance" in r.stderr


def test_branch_gen_w_b_func_file_and_library_call(tmp_path, write):
    """A .func file for w_b(d) (fig. 7.4) is read relative to the parameter file; a zero
    function turns the corymb into an umbel (straight rays)."""
    from inflo.formats.func import Function, write_func
    from inflo.formats.scn import read_scn
    from inflo.tools.branch_gen.generate import branch_gen

    write_func(tmp_path / "wb.func", Function.constant(0.0, name="wb"))
    prm = write("p.toml", "[rodkaew]\nw_b = 3.0\nw_h = 0.0\ninitial_direction = \"base\"\nw_b_func = \"wb.func\"\n")
    res = branch_gen(read_scn(write("s.scn", SCN)), read_params(prm))
    sk = res.skeleton
    own = sk.node_branch >= 0
    f = np.array([[-0.2, 1, 0], [0.2, 1, 0.05], [0, 1, -0.2]])[sk.node_branch[own]]
    assert np.linalg.norm(np.cross(sk.node_pos[own], _unit_rows(f)), axis=1).max() < 1e-9
    bad = write("q.toml", "[rodkaew]\nw_b_func = \"missing.func\"\n")
    from inflo.formats.errors import InputError
    with pytest.raises(InputError, match="missing.func"):
        branch_gen(read_scn(write("s.scn", SCN)), read_params(bad))


def test_branch_gen_nearest_other_tree_matches_brute_force():
    """The spatial-hash query (rings of cells, then a scan when sparse) against all pairs."""
    from inflo.tools.branch_gen import rodkaew as rk

    rng = np.random.default_rng(9)
    for n, spread in ((3000, 1.0), (40, 5.0)):
        pos = rng.random((n, 3)) * spread
        branch = rng.integers(0, 30, n).astype(np.int64)
        branch[0] = -1  # a root is never a neighbour
        uf = np.arange(30, dtype=np.int64)
        uf[5] = 7  # tree 5 grafted onto tree 7: one tree
        h = 0.05
        mask = (1 << 14) - 1
        head = np.full(mask + 1, -1, np.int64)
        nxt = np.full(n, -1, np.int64)
        rk._grid_rebuild(n, branch, pos, 1.0 / h, head, nxt, mask)
        for _ in range(100):
            q = rng.random(3) * spread * 1.2 - 0.1
            label = int(rng.integers(0, 30))
            for radius in (np.inf, 0.3):
                got, d2 = rk._nearest_other(q, rk._find(uf, label), pos, branch, uf, head, nxt, mask, h, 1.0 / h,
                                            radius, 2**30 if np.isinf(radius) else int(radius / h) + 2, n)
                trees = np.array([rk._find(uf, b) if b >= 0 else -2 for b in branch])
                d = np.einsum("ij,ij->i", pos - q, pos - q)
                d[(trees == rk._find(uf, label)) | (branch < 0) | (d > radius * radius)] = np.inf
                want = int(np.argmin(d)) if np.isfinite(d.min()) else -1
                assert got == want


def test_branch_gen_growth_scale_functions(tmp_path, write):
    """Per-axis scale functions (.func): space scaled by S_i(f / end) / S_i(1); scaling about the
    base keeps w_b = 0 rays straight only along axes scaled alike, and tips stay on the florets."""
    from inflo.formats.func import Function, write_func
    from inflo.formats.scn import read_scn
    from inflo.tools.branch_gen.generate import branch_gen

    lin = Function.from_points([[0, 0.5], [1, 1.0]], name="lin")
    write_func(tmp_path / "lin.func", lin)
    write_func(tmp_path / "one.func", Function.constant(1.0, name="one"))
    np.testing.assert_allclose(growth_scale("functions", 0, None, 5, 10, [lin, lin, Function.constant(1.0)]),
                               [0.75, 0.75, 1.0], rtol=1e-12)
    prm = write("p.toml", "[rodkaew]\nsteps_per_frame = 3\n[growth]\nmode = \"functions\"\n"
                          "funcs = [\"lin.func\", \"one.func\", \"lin.func\"]\n")
    res = branch_gen(read_scn(write("s.scn", SCN)), read_params(prm))
    sk = res.skeleton
    florets = np.array([[-0.2, 1, 0], [0.2, 1, 0.05], [0, 1, -0.2]])
    assert np.array_equal(sk.node_pos[sk.node_tip], florets[sk.node_floret[sk.node_tip]])
    check_forest(sk.node_parent)
    with pytest.raises(FormatError, match="three .func"):
        read_params(write("q.toml", "[growth]\nmode = \"functions\"\nfuncs = [\"lin.func\"]\n"))


def test_branch_gen_rodkaew_kernel_compiles_once():
    """The particle kernel takes NamedTuples of arrays: one compiled signature across
    levels, growth of space, w_b tables, birth positions, and node arrays and hash table that grow."""
    from inflo.tools.branch_gen import rodkaew as rk

    pos = _disc(500, seed=6)
    p = params_from_dict({"rodkaew": {"step": 0.01, "merge_distance": 0.012, "steps_per_frame": 10},
                          "growth": {"mode": "uniform", "rate": 0.02}})
    sk = grow_rodkaew(_input(pos, emergence=np.linspace(0, 20, 500)), p)
    _check_supported(sk, pos)
    assert sk.n_nodes > 4 * 500, "the node arrays grew"
    level = Level(target=np.zeros(3), start=pos[:50], birth_frame=np.zeros(50), birth_pos=pos[:50] * 0.9,
                  initial_dir=np.full((50, 3), np.nan))
    grow_level(level, _params(w_b=0.5), base=np.zeros(3), end_frame=0.0, wb_table=np.linspace(0.0, 1.0, 5))
    assert len(rk._advance.signatures) == 1
