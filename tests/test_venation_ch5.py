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


CLOSED = """seed = 3
[blade]
polygon = [[0,0],[10,3],[12,12],[5,20],[-5,20],[-12,12],[-10,3]]
[growth]
type = "uniform"
initial = 0.3
rate = 0.05
[veins]
pattern = "closed"
step = 0.5
kill_distance = 0.5
{veins}
[sources]
birth_source = 1.5
birth_vein = 1.5
{sources}
"""


def _run(tmp_path, veins="", sources="", name="p.toml"):
    f = tmp_path / name
    f.write_text(CLOSED.format(veins=veins, sources=sources))
    out = tmp_path / ("out_" + name)
    r = CliRunner().invoke(main, [str(f), "-o", str(out), "-q"])
    assert r.exit_code == 0, r.output
    return out


def _events(out):
    lines = (out / "events.csv").read_text().splitlines()
    assert lines[0] == "iteration,event,index,x,y,measure,order,midvein"
    rows = [ln.split(",") for ln in lines[1:]]
    return [(int(r[0]), r[1], int(r[2]), float(r[3]), float(r[4]), float(r[5]) if r[5] else None,
             int(r[6]) if r[6] else None) for r in rows]


@pytest.mark.parametrize("sources", ["", 'placement = "largest_empty_circle"'])
def test_events_loops_in_order_with_positive_areas(tmp_path, sources):
    ev = _events(_run(tmp_path, sources=sources))
    its = [e[0] for e in ev]
    assert its == sorted(its)
    loops = [e for e in ev if e[1] == "loop"]
    assert len(loops) >= 3
    assert [e[2] for e in loops] == list(range(1, len(loops) + 1))
    assert all(e[5] > 0 for e in loops)
    assert all(e[6] >= 1 for e in loops) and max(e[6] for e in loops) >= 2  # loops inside earlier loops
    assert all(e[6] is None for e in ev if e[1] != "loop")
    mid = [e for e in ev if e[1] == "midvein"]
    assert len(mid) == 1 and mid[0][5] > 0
    assert ev.index(mid[0]) < ev.index(loops[0])
    placed = [e for e in ev if e[1] == "source"]
    assert len(placed) >= 3
    if sources:
        assert all(e[5] > 1.5 - 1e-7 for e in placed)  # every circle supports a source (radius > b_s)
    else:
        assert all(e[5] is None for e in placed)


def test_events_blind_ends(tmp_path):
    ev = _events(_run(tmp_path, veins="blind_after = 8"))
    blind = [e for e in ev if e[1] == "blind_end"]
    assert blind and all(e[0] >= 8 and e[5] >= 0 for e in blind)
    assert [e[2] for e in blind] == list(range(1, len(blind) + 1))


def test_largest_empty_circle_run_is_deterministic(tmp_path):
    a = _run(tmp_path, sources='placement = "largest_empty_circle"', name="a.toml")
    b = _run(tmp_path, sources='placement = "largest_empty_circle"', name="b.toml")
    for f in ("veins.obj", "events.csv", "veins.widths"):
        assert (a / f).read_bytes() == (b / f).read_bytes()


def _refused(tmp_path, text, name="bad.toml"):
    f = tmp_path / name
    f.write_text(text)
    out = tmp_path / "out"
    out.mkdir(exist_ok=True)
    (out / "keep.txt").write_text("earlier")
    r = CliRunner().invoke(main, [str(f), "-o", str(out), "-q"])
    assert r.exit_code == 2, r.output
    err = r.output.strip()
    assert len(err.splitlines()) == 1 and "error:" in err, err
    assert sorted(p.name for p in out.iterdir()) == ["keep.txt"]
    return err


@pytest.mark.parametrize("sources,expect", [
    ('placement = "largest"', "placement"),
    ('placement = 3', "placement"),
    ('placement = "largest_empty_circle"\nbirth_source = 0.001', "birth_source"),
    ('placement = "largest_empty_circle"\nbirth_vein = 0.001', "birth_vein"),
])
def test_placement_refusals(tmp_path, sources, expect):
    text = CLOSED.format(veins="", sources=sources)
    if "birth_" in sources:
        key = sources.split("\n")[1].split(" =")[0]
        text = text.replace(f"{key} = 1.5\n", "")
    assert expect in _refused(tmp_path, text)


def test_placement_margin_region_refused(tmp_path):
    text = CLOSED.format(veins="", sources='placement = "largest_empty_circle"\nregion = "margin"').replace(
        '"uniform"', '"marginal"')
    assert "region" in _refused(tmp_path, text)


# --------------------------------------------------------------------------------------------
# local-to-global growth (sec. 5.2.1, eq. 5.1)


def _lin(a, b):
    from inflo.formats.func import Function

    return Function.from_points([(0.0, a), (1.0, b)])


def test_local_to_global_constant_rates_are_uniform_anisotropic_growth():
    from inflo.tools.venation.blade import LocalToGlobal

    g = LocalToGlobal(_lin(1.02, 1.02), _lin(1.05, 1.05), [1.0, -2.0], 10.0)
    rng = np.random.default_rng(0)
    mat = np.array([1.0, -2.0]) + rng.uniform(-5, 12, (50, 2))
    for t in (0, 1, 7, 30):
        got = g.forward(mat, t)
        want = np.array([1.0, -2.0]) + (mat - [1.0, -2.0]) * [1.02 ** t, 1.05 ** t]
        assert np.allclose(got, want, rtol=1e-12, atol=1e-9)
        assert np.allclose(g.inverse(got, t), mat, atol=1e-9)


@pytest.mark.parametrize("k,t", [(0.1, 5), (0.3, 12), (0.05, 40)])
def test_local_to_global_linear_rerg_y_matches_eq_5_1(k, t):
    from inflo.tools.venation.blade import LocalToGlobal

    h = 8.0
    g = LocalToGlobal(_lin(1.0, 1.0 + k), _lin(1.0, 1.0 + k), [0.0, 0.0], h)
    y0 = np.linspace(0.0, h, 33)
    x0 = np.full_like(y0, 2.0)
    got = g.forward(np.column_stack([x0, y0]), t)
    u = y0 / h
    # eq. 5.1: y1 = integral_0^y0 (1 + k y / h)^t dy
    want_y = h * ((1.0 + k * u) ** (t + 1) - 1.0) / (k * (t + 1))
    assert np.allclose(got[:, 1], want_y, rtol=1e-5)
    assert np.allclose(got[:, 0], 2.0 * (1.0 + k * u) ** t, rtol=1e-12)
    # growing from t1 to t2 goes through t0: eq. 5.1 solved for y0, then eq. 5.1 again
    mid = g.forward(np.column_stack([x0, y0]), t // 2)
    assert np.allclose(g.forward(g.inverse(mid, t // 2), t), got, rtol=1e-6)


LTG = """seed = 2
max_iterations = 400
[blade]
polygon = [[0,0],[1,0.5],[1.2,2],[0.6,3.2],[0,3.5],[-0.6,3.2],[-1.2,2],[-1,0.5]]
[growth]
type = "local_to_global"
rerg = ["rx.func", "ry.func"]
steps = {steps}
[veins]
pattern = "closed"
step = 0.25
kill_distance = 0.25
[sources]
birth_source = 0.8
birth_vein = 0.8
placement = "{placement}"
"""


def _write_ltg(tmp_path, rx=(1.02, 1.02), ry=(1.03, 1.03), steps=40, placement="largest_empty_circle", extra=""):
    from inflo.formats.func import write_func

    write_func(tmp_path / "rx.func", _lin(*rx))
    write_func(tmp_path / "ry.func", _lin(*ry))
    f = tmp_path / "ltg.toml"
    f.write_text(LTG.format(steps=steps, placement=placement) + extra)
    return f


@pytest.mark.parametrize("placement", ["darts", "largest_empty_circle"])
def test_local_to_global_run_grows_the_blade_and_veins(tmp_path, placement):
    f = _write_ltg(tmp_path, placement=placement)
    out = tmp_path / "out"
    r = CliRunner().invoke(main, [str(f), "-o", str(out), "-q"])
    assert r.exit_code == 0, r.output
    v = np.array([[float(x) for x in ln.split()[1:3]] for ln in (out / "blade.obj").read_text().splitlines()
                  if ln.startswith("v ")])
    poly = np.array([[0, 0], [1, 0.5], [1.2, 2], [0.6, 3.2], [0, 3.5], [-0.6, 3.2], [-1.2, 2], [-1, 0.5]], float)
    want = poly * [1.02 ** 40, 1.03 ** 40]  # constant rates: uniform anisotropic growth
    assert all(np.hypot(*(v - w).T).min() < 1e-6 for w in want)  # the margin's corners are mesh vertices
    ev = _events(out)
    assert [e for e in ev if e[1] == "loop"]
    nodes = np.array([[float(x) for x in ln.split()[1:3]] for ln in (out / "veins.obj").read_text().splitlines()
                      if ln.startswith("v ")])
    from matplotlib.path import Path as MPath

    inside = MPath(want).contains_points(nodes, radius=0.3) | MPath(want).contains_points(nodes, radius=-0.3)
    assert inside.mean() > 0.95


@pytest.mark.parametrize("kw,expect", [
    (dict(rx=(1.0, 0.9)), "rerg"),
    (dict(ry=(1.5, 1.5), steps=100), "rerg"),
    (dict(steps=0), "steps"),
    (dict(extra="[sources]\n"), "sources"),
])
def test_local_to_global_refusals(tmp_path, kw, expect):
    f = _write_ltg(tmp_path, **kw)
    text = f.read_text()
    assert expect in _refused(tmp_path, text, name="ltg.toml")


@pytest.mark.parametrize("old,new,expect", [
    ('rerg = ["rx.func", "ry.func"]', 'rerg = "rx.func"', "rerg"),
    ('rerg = ["rx.func", "ry.func"]\n', '', "rerg"),
    ('type = "local_to_global"', 'type = "uniform"', "rerg"),
    ('placement = "largest_empty_circle"', 'placement = "darts"\n[growth.x]', "growth"),
])
def test_local_to_global_key_refusals(tmp_path, old, new, expect):
    f = _write_ltg(tmp_path)
    text = f.read_text()
    assert old in text
    assert expect in _refused(tmp_path, text.replace(old, new), name="ltg.toml")


def test_arabidopsis_example_midvein_before_loops(tmp_path):
    from pathlib import Path

    here = Path(__file__).resolve().parents[1] / "pipelines" / "examples" / "venation" / "arabidopsis_ltg.toml"
    out = tmp_path / "out"
    r = CliRunner().invoke(main, [str(here), "-o", str(out), "-q"])
    assert r.exit_code == 0, r.output
    ev = _events(out)
    kinds = [e[1] for e in ev]
    assert kinds[0] == "source" and ev[0][3] == pytest.approx(0.0, abs=1e-9)  # the tip, on the midline
    mid = kinds.index("midvein")
    first_loop = kinds.index("loop")
    assert mid < first_loop
    assert kinds[mid + 1:first_loop].count("source") >= 2  # margin sources before the first loops


def test_local_to_global_open_pattern_finishes(tmp_path):
    f = _write_ltg(tmp_path, placement="darts")
    f.write_text(f.read_text().replace('pattern = "closed"', 'pattern = "open"'))
    out = tmp_path / "out"
    r = CliRunner().invoke(main, [str(f), "-o", str(out)])
    assert r.exit_code == 0, r.output
    assert "max_iterations" not in r.output and "400 iterations" not in r.output


def test_closed_sources_of_the_first_iteration_draw_veins():
    """A source placed in iteration 0 stays until a vein reaches it (a node's "stalled in the
    last iteration" mark used to read -1 as iteration -1 and removed every first-iteration source
    of a closed pattern at once, with no vein)."""
    from inflo.tools.venation.generate import sim_params
    from inflo.tools.venation.params import load_inputs, parse_params
    from inflo.tools.venation.simulate import simulate

    text = """seed = 3
[blade]
polygon = [[-10.0, 0.0], [10.0, 0.0], [10.0, 20.0], [-10.0, 20.0]]
base = [0.0, 0.0]
[veins]
pattern = "closed"
step = 1.0
kill_distance = 1.0
[sources]
birth_source = 3.0
birth_vein = 3.0
darts = 0.02
"""
    p = parse_params(text)
    inp = load_inputs(p)
    r = simulate(inp.blade, inp.growth, sim_params(p, inp))
    first = np.flatnonzero(r.source_born == 0)
    assert len(first) > 2
    assert np.all(r.source_died[first] > 0)
    # each was reached: a vein node within d_k of where it stood
    d = np.sqrt(((r.node_pos[None] - r.source_pos[first][:, None]) ** 2).sum(-1)).min(1)
    assert np.all(d <= 1.0 + 1e-9)
