"""venation: open and closed leaf venation patterns (Runions ch. 4)."""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from conftest import no_partial_files, run_cli
from scipy.spatial import cKDTree

from inflo.formats.contour import Contour, write_con, write_cset
from inflo.formats.errors import FormatError
from inflo.formats.func import Function, write_func
from inflo.formats.obj import read_obj
from inflo.tools.venation.blade import Growth, _ear_clip, blade_from_points, polygon_area, triangulate_blade
from inflo.tools.venation.graph import (
    check_forest,
    cycle_rank,
    elongation_widths,
    refine_veins,
    strahler_orders,
    vein_widths,
)
from inflo.tools.venation.neighbourhood import (
    NEAREST,
    RELATIVE,
    URQUHART,
    delaunay_neighbours,
    neighbourhoods,
    relative_neighbourhood_brute,
    relative_neighbourhood_delaunay,
    urquhart_delaunay,
)
from inflo.tools.venation.params import load_inputs, parse_params
from inflo.tools.venation.simulate import SimParams, simulate


def _leaf(n=160, length=60.0):
    """An ovate leaf, base at the origin, tip at (0, length)."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[0.6 * np.sin(t) * np.sin(t / 2) ** 0.5, 1 - np.cos(t)] * (length / 2)


LEAF = blade_from_points(_leaf())


def _run(pattern="open", kind="marginal", seed=1, **kw):
    growth = {"marginal": Growth("marginal", (0.2, 0.2), (1.0, 1.0), (0.01, 0.01)),
              "uniform": Growth("uniform", (0.2, 0.2), (1.0, 1.0), (0.01, 0.01)),
              "anisotropic": Growth("anisotropic", (0.3, 0.2), (1.0, 1.0), (0.01, 0.008)),
              "none": Growth("none")}[kind]
    sp = SimParams(pattern=pattern, step=1.0, kill_distance=kw.pop("kill_distance", 1.0 if pattern == "closed" else 2.0),
                   birth_source=2.5, birth_vein=2.5, darts=0.1, seed=seed, **kw)
    return simulate(LEAF, growth, sp)


# --------------------------------------------------------------------------------------------
# neighbourhoods (eq. 4.1, sec. 4.4.2)


def _random_sets(n_sets=40, seed=5):
    rng = np.random.default_rng(seed)
    for _ in range(n_sets):
        n = int(rng.integers(3, 160))
        nodes = rng.random((n, 2)) * [3.0, 2.0]
        srcs = rng.random((12, 2)) * [3.4, 2.4] - 0.2
        yield nodes, srcs, float(rng.choice([0.05, 0.2, 1.0]))


def test_relative_neighbourhood_matches_brute_force():
    """The fast relative neighbourhood equals eq. 4.1 over every pair, and the thesis's
    computation (Delaunay neighbours of s in V ∪ {s}, each checked against every node)."""
    checked = 0
    for nodes, srcs, h in _random_sets():
        fast = neighbourhoods(srcs, nodes, RELATIVE, h)
        for i, (s, got) in enumerate(zip(srcs, fast)):
            ref = relative_neighbourhood_brute(s, nodes)
            assert np.array_equal(got, ref), (s, got, ref)
            if i % 4 == 0:
                assert np.array_equal(relative_neighbourhood_delaunay(s, nodes), ref)
            checked += 1
    assert checked == 40 * 12


def test_urquhart_between_relative_neighbourhood_and_delaunay():
    """Urquhart ⊆ Delaunay neighbourhood and ⊇ relative neighbourhood (sec. 4.4.2), and on these
    sets it equals the Delaunay-neighbours-tested-against-each-other of scipy's triangulation."""
    strict = 0
    for nodes, srcs, h in _random_sets(seed=6):
        fast = neighbourhoods(srcs, nodes, URQUHART, h)
        for s, got in zip(srcs, fast):
            rn = set(relative_neighbourhood_brute(s, nodes).tolist())
            dn = set(delaunay_neighbours(s, nodes).tolist())
            assert rn <= set(got.tolist()) <= dn
            assert set(got.tolist()) == set(urquhart_delaunay(s, nodes).tolist())
            strict += len(set(got.tolist()) - rn)
    assert strict > 0  # the approximation does differ somewhere (fig. 4.13)


def test_nearest_is_the_closest_node():
    rng = np.random.default_rng(2)
    nodes = rng.random((500, 2)) * 10
    srcs = rng.random((50, 2)) * 12 - 1
    got = neighbourhoods(srcs, nodes, NEAREST, 0.3)
    for s, g in zip(srcs, got):
        assert g[0] == np.argmin(((nodes - s) ** 2).sum(1))


def test_incremental_nearest_equals_a_full_search():
    from inflo.tools.venation.neighbourhood import grid_insert, make_grid, nearest_incremental

    rng = np.random.default_rng(4)
    nodes = rng.random((900, 2)) * 20
    srcs = rng.random((60, 2)) * 20
    g = make_grid([0, 0], [20, 20], 0.7, len(nodes))
    near, near_d2 = np.full(60, -1, np.int64), np.full(60, np.inf)
    out, cnt = np.zeros((60, 8), np.int64), np.zeros(60, np.int64)
    done = 0
    for n in (1, 30, 31, 400, 900):  # nodes arrive in batches
        grid_insert(g, nodes, done, n)
        nearest_incremental(srcs, np.arange(60), near, near_d2, nodes, done, n, g, out, cnt)
        done = n
        full = neighbourhoods(srcs, nodes[:n], NEAREST)
        assert [f[0] for f in full] == out[:, 0].tolist()


def test_relative_neighbourhood_far_and_degenerate_cases():
    """A source far outside the nodes, collinear nodes (no triangulation), a single node."""
    line = np.c_[np.arange(20.0), np.zeros(20)]
    for s in ([5.3, 2.0], [-30.0, 0.5], [100.0, -40.0]):
        assert np.array_equal(neighbourhoods([s], line, RELATIVE, 1.0)[0], relative_neighbourhood_brute(s, line))
    assert neighbourhoods([[3.0, 3.0]], [[0.0, 0.0]], RELATIVE)[0].tolist() == [0]


# --------------------------------------------------------------------------------------------
# patterns


@pytest.mark.parametrize("kind", ["marginal", "uniform", "anisotropic", "none"])
def test_open_pattern_is_a_tree_from_the_base(kind):
    r = _run("open", kind)
    assert r.stopped == "finished"
    assert r.n_nodes > 150
    assert len(r.extra_edges) == 0
    assert check_forest(r.node_parent)
    roots = np.flatnonzero(r.node_parent < 0)
    assert roots.tolist() == [0] and np.allclose(r.node_pos[0], LEAF.base)  # one tree, rooted at the base
    assert cycle_rank(r.n_nodes, r.node_parent, r.extra_edges) == 0
    assert r.sources_left == 0 and r.sources_placed > 50  # every source removed
    assert len(cKDTree(r.node_pos).query_pairs(0.5 - 1e-9)) == 0  # no vein node closer than D/2
    seg = np.linalg.norm(r.node_pos[1:] - r.node_pos[r.node_parent[1:]], axis=1)
    if kind in ("marginal", "none"):
        assert np.allclose(seg, 1.0)  # segments of length D (they grow with the blade otherwise)
    else:
        assert seg.min() >= 1.0 - 1e-9


def test_open_sources_are_removed_at_the_kill_distance():
    r = _run("open", "marginal")
    tree = cKDTree(r.node_pos)
    d, _ = tree.query(r.source_pos)
    assert np.all(d < 2.0 + 1e-9)  # each removed source had a vein node within d_k
    assert r.sources_stalled == 0


@pytest.mark.parametrize("neighbourhood", ["relative", "urquhart"])
@pytest.mark.parametrize("kind", ["uniform", "marginal"])
def test_closed_pattern_has_loops(kind, neighbourhood):
    r = _run("closed", kind, neighbourhood=neighbourhood)
    assert r.stopped == "finished" and r.sources_left == 0
    assert check_forest(r.node_parent)  # the growth graph is a forest; loops come from anastomoses
    loops = cycle_rank(r.n_nodes, r.node_parent, r.extra_edges)
    assert loops == len(r.extra_edges) > 20
    e = r.extra_edges
    assert np.all(e[:, 0] < e[:, 1]) and len(np.unique(e, axis=0)) == len(e)
    gap = np.linalg.norm(r.node_pos[e[:, 0]] - r.node_pos[e[:, 1]], axis=1)
    # joined at a source: each end within d_k = 1 of it, or stopped by the D/2 guard within 1.5 D
    # (stretched since by uniform growth from 0.2)
    assert gap.max() < (2.5 if kind == "marginal" else 2.5 / 0.2)
    assert len(cKDTree(r.node_pos).query_pairs(0.5 - 1e-9)) == 0


def test_frames_do_not_change_the_run():
    growth = Growth("uniform", (0.2, 0.2), (1.0, 1.0), (0.01, 0.01))
    sp = SimParams(pattern="closed", birth_source=2.5, birth_vein=2.5, darts=0.1, seed=8)
    snaps = []
    a = simulate(LEAF, growth, sp)
    b = simulate(LEAF, growth, sp, on_frame=snaps.append, frame_step=7)
    assert np.array_equal(a.node_pos, b.node_pos) and np.array_equal(a.extra_edges, b.extra_edges)
    assert [s.iteration for s in snaps][:3] == [0, 7, 14] and snaps[-1].iteration == b.iterations - 1
    assert np.array_equal(snaps[-1].node_pos, b.node_pos)
    assert all(len(s.node_pos) <= len(t.node_pos) for s, t in zip(snaps, snaps[1:]))


def test_simulation_is_deterministic_and_seeded():
    a, b, c = _run("closed", "uniform", seed=3), _run("closed", "uniform", seed=3), _run("closed", "uniform", seed=4)
    assert np.array_equal(a.node_pos, b.node_pos) and np.array_equal(a.extra_edges, b.extra_edges)
    assert a.n_nodes != c.n_nodes or not np.array_equal(a.node_pos, c.node_pos)


# --------------------------------------------------------------------------------------------
# widths, orders, blade mesh


def test_widths_follow_murrays_law():
    r = _run("open", "marginal")
    w = vein_widths(r.node_parent, 0.25, 2.5, 0.0)
    parent = r.node_parent
    kids = [[] for _ in range(r.n_nodes)]
    for v in np.flatnonzero(parent >= 0):
        kids[parent[v]].append(v)
    for v in range(r.n_nodes):
        want = 0.25 ** 2.5 if not kids[v] else sum(w[c] ** 2.5 for c in kids[v])
        assert math.isclose(w[v] ** 2.5, want, rel_tol=1e-9)
    assert w[0] == w.max()
    w2 = vein_widths(r.node_parent, 0.25, 2.0, 1.0)  # sec. 4.2.5's increment at every node
    assert w2[0] ** 2 == pytest.approx(0.25 ** 2 * (r.n_nodes + (np.bincount(parent[parent >= 0], minlength=r.n_nodes) == 0).sum()))


def test_strahler_orders_form_a_hierarchy():
    r = _run("open", "none")
    o = strahler_orders(r.node_parent)
    assert o.min() == 1 and o[0] == o.max() >= 3
    assert np.all(o[r.node_parent[1:]] >= o[1:])  # order never decreases toward the base


def test_blade_mesh_covers_the_blade():
    verts, faces = triangulate_blade(LEAF.polygon)
    a = verts[faces]
    cross = (a[:, 1, 0] - a[:, 0, 0]) * (a[:, 2, 1] - a[:, 0, 1]) - (a[:, 1, 1] - a[:, 0, 1]) * (a[:, 2, 0] - a[:, 0, 0])
    assert np.all(cross > 0)
    assert 0.5 * cross.sum() == pytest.approx(polygon_area(LEAF.polygon), rel=1e-9)
    assert len(verts) > 4 * len(LEAF.polygon)


# --------------------------------------------------------------------------------------------
# the CLI


POLY = "[[0, 0], [10, 4], [14, 16], [9, 30], [0, 36], [-9, 30], [-14, 16], [-10, 4]]"


def _params(tmp_path, body, name="p.toml"):
    path = tmp_path / name
    path.write_text(body)
    return path


def _closed_toml(extra=""):
    return f"""seed = 2
[blade]
polygon = {POLY}
[growth]
type = "uniform"
initial = 0.3
rate = 0.02
[veins]
pattern = "closed"
[sources]
birth_source = 2.5
birth_vein = 2.5
darts = 0.05
[texture]
size = 160
{extra}"""


def test_cli_writes_every_output(tmp_path):
    p = _params(tmp_path, _closed_toml("[output]\nframe_step = 10\n"))
    out = tmp_path / "out"
    res = run_cli("venation", p, "-o", out)
    assert res.returncode == 0, res.stderr
    assert "vein nodes" in res.stderr and "loops" in res.stderr
    g = read_obj(out / "veins.obj")
    widths = [float(x) for x in (out / "veins.widths").read_text().splitlines() if not x.startswith("#")]
    assert len(widths) == g.n_vertices > 100
    # every edge once: the chains hold the n - 1 forest edges, then one line per anastomosis
    edges = {tuple(sorted((int(a), int(b)))) for l in g.lines for a, b in zip(l[:-1], l[1:])}
    assert len(edges) == sum(len(l) - 1 for l in g.lines)
    loops = int(res.stderr.split(" loops")[0].rsplit(" ", 1)[-1])
    assert len(edges) == g.n_vertices - 1 + loops and loops > 5
    blade = read_obj(out / "blade.obj")
    assert blade.n_faces > 50 and np.allclose(blade.vertices[:, 2], 0)
    assert "map_Kd texture.png" in (out / "blade.mtl").read_text()
    from PIL import Image

    img = Image.open(out / "texture.png")
    assert img.mode == "RGBA" and max(img.size) == 160
    alpha = np.asarray(img)[..., 3]
    assert alpha.min() == 0 and alpha.max() == 255  # transparent outside the blade
    frames = sorted((out / "frames").glob("veins_*.obj"))
    assert len(frames) >= 3 and frames[0].name == "veins_0000.obj"
    counts = [read_obj(f).n_vertices for f in frames]
    assert counts == sorted(counts) and counts[-1] == g.n_vertices
    margins = sorted((out / "frames").glob("blade_*.obj"))
    ext = [np.ptp(read_obj(f).vertices[:, 1]) for f in margins]
    assert ext[0] < ext[-1] and ext[-1] == pytest.approx(36.0, rel=1e-6)  # the blade grew to scale 1
    assert no_partial_files(out)


def test_cli_is_deterministic_under_seed(tmp_path):
    p = _params(tmp_path, _closed_toml())
    outs = []
    for name, seed in (("a", "5"), ("b", "5"), ("c", "6")):
        res = run_cli("venation", p, "-o", tmp_path / name, "--seed", seed, "-q")
        assert res.returncode == 0 and res.stderr == "", res.stderr
        outs.append({f.name: f.read_bytes() for f in sorted((tmp_path / name).iterdir())})
    assert outs[0] == outs[1]  # byte-identical, PNG included
    assert outs[0]["veins.obj"] != outs[2]["veins.obj"]


def test_cli_reads_a_closed_contour_and_rejects_an_open_one(tmp_path):
    pts = _leaf(12, 1.0)
    write_con(tmp_path / "leaf.con", Contour.from_points(pts, type="cr", name="leaf"))
    write_con(tmp_path / "open.con", Contour.from_points(pts, type="or", name="open"))
    body = ('[blade]\ncontour = "{}"\nsize = 25.0\nsamples = 128\n[growth]\ntype = "marginal"\ninitial = 0.3\n'
            'rate = 0.02\n[veins]\nkill_distance = 2.0\n[sources]\ndarts = 0.05\n[texture]\nsize = 64\n')
    ok = _params(tmp_path, body.format("leaf.con"), "ok.toml")
    res = run_cli("venation", ok, "-o", tmp_path / "ok", "-q")
    assert res.returncode == 0, res.stderr
    assert read_obj(tmp_path / "ok" / "veins.obj").n_vertices > 30
    bad = _params(tmp_path, body.format("open.con"), "bad.toml")
    res = run_cli("venation", bad, "-o", tmp_path / "bad")
    assert res.returncode == 2
    assert res.stderr.count("\n") == 1 and "bad.toml:2:" in res.stderr and "closed contour" in res.stderr
    assert not (tmp_path / "bad").exists()


def test_blade_from_a_contour_gallery(tmp_path):
    small = Contour.from_points(_leaf(12, 1.0), type="cr", name="small")
    big = Contour.from_points(_leaf(12, 2.0), type="ce", name="big leaf")
    write_cset(tmp_path / "leaves.cset", [small, big])
    body = '[blade]\ncontour = "leaves.cset"\ncontour_name = "{}"\nsize = 10.0\n'
    b = load_inputs(parse_params(body.format("big leaf"), tmp_path / "p.toml")).blade
    assert np.ptp(b.polygon[:, 1]) == pytest.approx(20.0, rel=0.05)  # not the small one (10)
    with pytest.raises(FormatError, match="did you mean 'big leaf'"):
        load_inputs(parse_params(body.format("big lef"), tmp_path / "p.toml"))


BAD = [
    ("[veins]\nkill_distance = -1.0\n", "p.toml:", "veins.kill_distance > 0"),
    ("[veins]\nstep = -0.5\n", "p.toml:", "veins.step > 0"),
    ("[sources]\nbirth_source = -2.0\n", "p.toml:", "sources.birth_source > 0"),
    ("[sources]\nbirth_vein = 0\n", "p.toml:", "sources.birth_vein > 0"),
    ("[sources]\ndarts = -1\n", "p.toml:", "sources.darts > 0"),
    ("[veins]\nkill_distnce = 2.0\n", "p.toml:", "did you mean 'kill_distance'"),
    ("[vein]\nstep = 1.0\n", "p.toml:", "did you mean 'veins'"),
    ("sed = 3\n", "p.toml:1:", "did you mean 'seed'"),
    ("[veins]\npattern = \"closd\"\n", "p.toml:", "did you mean 'closed'"),
    ("[veins]\nkill_distance = 0.5\n", "p.toml:", ">= veins.step"),
    ("[veins]\nroots = [[50.0, 50.0]]\n", "p.toml:", "inside the blade"),
    ("[growth]\ntype = \"uniform\"\ninitial = 0.5\nfinal = 0.2\n", "p.toml:", ">= growth.initial"),
    ("[growth]\ntype = \"marginal\"\nrate = [0.1, 0.2]\n", "p.toml:", "anisotropic"),
    ("[width]\ntip = 0\n", "p.toml:", "width.tip > 0"),
]


@pytest.mark.parametrize("extra, where, what", BAD)
def test_cli_rejects_bad_parameters(tmp_path, extra, where, what):
    body = f"[blade]\npolygon = {POLY}\n" + extra if not extra.startswith("[blade]") else extra
    if extra.startswith("sed"):
        body = extra + f"[blade]\npolygon = {POLY}\n"
    p = _params(tmp_path, body)
    out = tmp_path / "out"
    res = run_cli("venation", p, "-o", out)
    assert res.returncode == 2, res.stderr
    assert res.stderr.count("\n") == 1 and res.stderr.startswith("venation: error: ")
    assert where in res.stderr and what in res.stderr, res.stderr
    assert "Traceback" not in res.stderr
    assert not out.exists()


def test_bad_blades_are_one_line_errors(tmp_path):
    cases = [
        ("[blade]\npolygon = [[0, 0], [10, 0], [10, 10], [3, -2], [0, 10]]\n", "crosses itself"),
        ("[blade]\npolygon = [[0, 0], [1, 1]]\n", "at least 3 points"),
        ("[blade]\npolygon = [[0, 0], [1, 1], [2, 2]]\n", "no area"),
        ("[growth]\ntype = \"none\"\n", "a blade"),
        (f"[blade]\npolygon = {POLY}\ncontour = \"x.con\"\n", "one blade"),
        (f"[blade]\npolygon = {POLY}\nbase = [40.0, 0.0]\n", "blade.base inside"),
    ]
    for body, what in cases:
        with pytest.raises(FormatError, match=what):
            load_inputs(parse_params(body, tmp_path / "p.toml"))


def test_growth_function_file(tmp_path):
    write_func(tmp_path / "sigma.func", Function.from_points([[0, 0.3], [0.5, 0.5], [1, 1.0]], name="sigma"))
    p = parse_params(f"[blade]\npolygon = {POLY}\n[growth]\ntype = \"uniform\"\nscale = \"sigma.func\"\nsteps = 40\n",
                     tmp_path / "p.toml")
    g = load_inputs(p).growth
    assert g.steps == 40
    assert g.scale_at(0)[0] == pytest.approx(0.3) and g.scale_at(40)[0] == pytest.approx(1.0)
    assert g.scale_at(100)[0] == pytest.approx(1.0)
    write_func(tmp_path / "down.func", Function.from_points([[0, 1.0], [1, 0.5]], name="down"))
    p = parse_params(f"[blade]\npolygon = {POLY}\n[growth]\ntype = \"uniform\"\nscale = \"down.func\"\nsteps = 4\n",
                     tmp_path / "p.toml")
    with pytest.raises(FormatError, match="non-decreasing"):
        load_inputs(p)


def test_cli_help():
    res = run_cli("venation", "--help")
    assert res.returncode == 0 and "Usage:" in res.stdout and "--seed" in res.stdout


def test_examples_parse():
    folder = Path(__file__).resolve().parent.parent / "pipelines" / "examples" / "venation"
    tomls = sorted(folder.glob("*.toml"))
    assert len(tomls) >= 3
    for t in tomls:
        from inflo.tools.venation.params import read_params

        load_inputs(read_params(t))


# --------------------------------------------------------------------------------------------
# Runions ch. 5 refinements: areoles with blindly terminating veins, widths by elongation,
# adaptive corner cutting; and veins kept inside a dissected blade


def test_areole_algorithm_makes_blind_veinlets_and_only_after_the_event():
    closed = _run("closed", "uniform", seed=2)
    never = _run("closed", "uniform", seed=2, blind_after=10 ** 6)
    assert np.array_equal(closed.node_pos, never.node_pos) and np.array_equal(closed.extra_edges, never.extra_edges)
    blind = _run("closed", "uniform", seed=2, blind_after=0)  # every source after the event (sec. 5.2.4)
    assert blind.stopped == "finished" and blind.sources_left == 0
    assert len(blind.extra_edges) == 0 and cycle_rank(blind.n_nodes, blind.node_parent, blind.extra_edges) == 0
    assert check_forest(blind.node_parent) and blind.blind_ends > 20
    # a blind vein ends near, but not on, the node it headed for: its tip is within 1.5 D of
    # another vein (the gap D plus the D/2 guard) that is not its own parent
    parent = blind.node_parent
    tips = np.setdiff1d(np.flatnonzero(parent >= 0), parent[parent >= 0])
    d, j = cKDTree(blind.node_pos).query(blind.node_pos[tips], k=2)
    near = (d[:, 1] < 1.5 + 1e-9) & (j[:, 1] != parent[tips])
    assert near.sum() > 20
    assert len(cKDTree(blind.node_pos).query_pairs(0.5 - 1e-9)) == 0
    late = _run("closed", "uniform", seed=2, blind_after=60)  # loops first, blind veinlets later
    assert 0 < len(late.extra_edges) < len(closed.extra_edges) and late.blind_ends > 0


def test_widths_by_elongation():
    pos = np.array([[0, 0], [0, 3], [0, 4], [2, 3]], float)
    parent = np.array([-1, 0, 1, 1])
    w = elongation_widths(pos, parent, 1.0, 0.5)
    assert w.tolist() == [1.5, 1.5, 0.5, 1.0]  # w0 max(1, |v - parent| / D); the root: its longest child
    marginal = _run("open", "marginal")  # marginal growth stretches no vein
    assert np.allclose(elongation_widths(marginal.node_pos, marginal.node_parent, 1.0, 0.3), 0.3)
    uni = _run("open", "uniform")
    wu = elongation_widths(uni.node_pos, uni.node_parent, 1.0, 0.3)
    assert wu.max() == pytest.approx(0.3 / 0.2, rel=0.05)  # the first segments grew from sigma 0.2 to 1
    born = uni.node_iter[uni.node_parent >= 0]
    wv = wu[uni.node_parent >= 0]
    assert wv[born < 10].mean() > 2 * wv[born > 60].mean()  # older veins are wider


def test_corner_cutting_follows_eqs_5_3_and_5_4():
    pos = np.array([[0, 0], [2, 2], [4, 0]], float)
    p, par, ext, own = refine_veins(pos, [-1, 0, 1], np.zeros((0, 2)), 3.5, alpha=0.75)  # one cut: 2.1 + 1 < 3.5
    assert len(p) == 4 and np.allclose(p[0], [0, 0]) and np.allclose(p[1], [4, 0])  # the ends stay
    assert np.allclose(p[2], 0.25 * pos[0] + 0.75 * pos[1]) and np.allclose(p[3], 0.25 * pos[2] + 0.75 * pos[1])
    assert par.tolist() == [-1, 3, 0, 2] and own.tolist() == [0, 2, 1, 1]
    r = _run("closed", "uniform", seed=5)
    thr = 3.0
    p, par, ext, own = refine_veins(r.node_pos, r.node_parent, r.extra_edges, thr, alpha=0.75)
    assert len(p) > r.n_nodes and check_forest(par)
    assert cycle_rank(len(p), par, ext) == cycle_rank(r.n_nodes, r.node_parent, r.extra_edges)
    # every joint (root, branch point, tip, anastomosis end) keeps its position
    kids = np.bincount(r.node_parent[r.node_parent >= 0], minlength=r.n_nodes)
    joint = (kids != 1) | (r.node_parent < 0)
    joint[r.extra_edges.ravel()] = True
    assert np.allclose(p[ext], r.node_pos[r.extra_edges])
    kept_joints = np.flatnonzero(joint)
    assert all(np.any(np.all(np.isclose(p, r.node_pos[j]), axis=1)) for j in kept_joints[:200])
    # afterwards no interior corner of a chain is longer than the threshold over its two segments
    kids2 = np.bincount(par[par >= 0], minlength=len(p))
    joint2 = (kids2 != 1) | (par < 0)
    joint2[ext.ravel()] = True
    inner = np.flatnonzero(~joint2)
    child = np.full(len(p), -1)
    child[par[par >= 0]] = np.flatnonzero(par >= 0)
    a, b, c = p[par[inner]], p[inner], p[child[inner]]
    assert np.all(np.linalg.norm(b - a, axis=1) + np.linalg.norm(c - b, axis=1) <= thr + 1e-9)
    # stretched veins were cut; a pattern without stretching is left as it is
    m = _run("open", "marginal")
    q = refine_veins(m.node_pos, m.node_parent, m.extra_edges, 2.5)
    assert np.array_equal(q[0], m.node_pos) and np.array_equal(q[1], m.node_parent)


DISSECTED = np.array([[0, 0], [4, 0], [4, 30], [12, 50], [16, 50], [6, 28], [6, 0], [10, 0], [10, -4],
                      [-6, -4], [-6, 0], [-2, 0], [-2, 28], [-12, 50], [-8, 50], [0, 30]], float)


def test_veins_stay_inside_a_dissected_blade():
    """Two narrow lobes, 8 D apart at their tips: without the constraint veins cut across the gap."""
    blade = blade_from_points(DISSECTED, base=(2.0, -2.0))
    growth = Growth("uniform", (0.3, 0.3), (1.0, 1.0), (0.01, 0.01))

    def outside(r):
        mid = 0.5 * (r.node_pos[1:] + r.node_pos[r.node_parent[1:]])
        return int((~blade.contains(np.vstack([mid, r.node_pos]))).sum())

    kw = dict(pattern="open", kill_distance=2.0, birth_source=1.5, birth_vein=1.5, darts=0.2, seed=3)
    inside = simulate(blade, growth, SimParams(inside=True, **kw))
    assert inside.stopped == "finished" and outside(inside) == 0 and inside.n_nodes > 40
    assert check_forest(inside.node_parent)
    assert outside(simulate(blade, growth, SimParams(**kw))) > 0


def test_ear_clipping_a_dissected_margin():
    t = np.linspace(0, 2 * np.pi, 3000, endpoint=False)
    r = 1 + 0.6 * np.sin(41 * t)
    poly = np.c_[r * np.cos(t), r * np.sin(t)]
    f = _ear_clip(poly)
    a = poly[f]
    cross = (a[:, 1, 0] - a[:, 0, 0]) * (a[:, 2, 1] - a[:, 0, 1]) - (a[:, 1, 1] - a[:, 0, 1]) * (a[:, 2, 0] - a[:, 0, 0])
    assert len(f) == len(poly) - 2 and np.all(cross > 0)
    assert 0.5 * cross.sum() == pytest.approx(polygon_area(poly), rel=1e-9)


@pytest.mark.parametrize("extra, what", [
    ("[veins]\nblind_after = 5\n", "pattern = 'open'"),
    ("[veins]\npattern = \"closed\"\nblind_after = -3\n", "veins.blind_after >= 0"),
    ("[veins]\npattern = \"closed\"\nblind_gap = 0.2\n", "veins.blind_gap in [0.5, 100]"),
    ("[refine]\nthreshold = 1.5\n", ">= 2 x veins.step"),
    ("[refine]\nthreshold = 3\nalpha = 1.2\n", "refine.alpha in [0.5, 1)"),
    ("[refine]\nthreshold = 3\njitter = -0.1\n", "refine.jitter in [0, 0.5]"),
    ("[width]\nmodel = \"murray\"\n", "pipe"),
    ("[veins]\ninside = 1\n", "veins.inside"),
])
def test_bad_chapter_5_parameters(tmp_path, extra, what):
    with pytest.raises(FormatError, match=re.escape(what)) as exc:
        parse_params(f"[blade]\npolygon = {POLY}\n" + extra, tmp_path / "p.toml")
    assert "p.toml:" in str(exc.value) and "\n" not in str(exc.value)
