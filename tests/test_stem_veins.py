"""stem-veins: the vascular pattern of a stem (Runions ch. 6)."""
from __future__ import annotations

import hashlib
import math
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner

from inflo.tools.stem_veins import cli as stem_cli
from inflo.tools.stem_veins.model import (
    StemModel,
    _lune_empty,
    fibonacci_numbers,
    primordia,
    relative_neighbour_pairs,
    relative_neighbour_pairs_brute,
    simulate,
)
from inflo.tools.stem_veins.output import connectivity, unrolled
from inflo.tools.stem_veins.params import params_from_toml

# ---------------------------------------------------------------------------------------------
# the relative neighbourhood (eq. 4.1), exact


def test_lune_kernel_on_three_nodes():
    pos = np.array([[0.0, 0, 0], [2.0, 0, 0], [1.0, 0.5, 0]])
    pairs = np.array([[0, 1], [0, 2], [1, 2]], np.int64)
    ptr = np.array([0, 3, 6, 9], np.int64)
    cand = np.array([0, 1, 2] * 3, np.int64)
    # node 2 lies in the lune of 0 and 1 (closer to both than they are to each other)
    assert _lune_empty(pos, pairs, ptr, cand).tolist() == [False, True, True]
    # on the lune's boundary it does not block: an equilateral triangle keeps all three sides
    pos[2] = [1.0, math.sqrt(3.0), 0.0]
    assert _lune_empty(pos, pairs, ptr, cand).tolist() == [True, True, True]


@pytest.mark.parametrize("case", ["random", "coplanar ring", "grid", "coincident", "line"])
def test_relative_neighbours_match_the_brute_force_definition(case):
    rng = np.random.default_rng(3)
    if case == "random":
        pos = rng.normal(size=(120, 3))
    elif case == "coplanar ring":   # the base ring alone: qhull cannot triangulate it in 3-D
        a = 2 * np.pi * np.arange(30) / 30
        pos = np.column_stack([np.cos(a), np.sin(a), np.zeros(30)])
    elif case == "grid":            # cospherical and coplanar quadruples everywhere
        pos = np.stack(np.meshgrid(np.arange(4.0), np.arange(4.0), np.arange(3.0)), -1).reshape(-1, 3)
    elif case == "coincident":
        pos = rng.normal(size=(40, 3))
        pos[5] = pos[6]
    else:
        pos = np.column_stack([np.arange(12.0), np.zeros(12), np.zeros(12)])
    fast = relative_neighbour_pairs(pos)
    brute = relative_neighbour_pairs_brute(pos)
    if case == "grid":
        # degenerate ties (a node exactly on a lune's boundary) may be resolved differently by the
        # triangulation; every pair found is a relative-neighbour pair and the axis steps are found
        assert set(map(tuple, fast)) <= set(map(tuple, brute))
        assert len(fast) >= 0.9 * len(brute)
    elif case == "coincident":
        # the model never keeps two nodes on one point (a new node there is that node); the other
        # nodes' pairs are unaffected
        def others(pairs):
            return {tuple(p) for p in pairs.tolist() if 5 not in p and 6 not in p}
        assert others(fast) == others(brute)
    else:
        assert np.array_equal(fast, brute)
    if case == "line":
        assert fast.tolist() == [[i, i + 1] for i in range(11)]


# ---------------------------------------------------------------------------------------------
# the model (sec. 6.2)


def test_primordia_spiral_and_whorls():
    at, when = primordia(StemModel(radius=10.0, step=2.0, count=5, divergence=137.5, plastochron=4))
    assert np.allclose(np.hypot(at[:, 0], at[:, 1]), 10.0)
    assert np.allclose(at[:, 2], [2, 4, 6, 8, 10]) and when.tolist() == [0, 4, 8, 12, 16]
    phi = np.degrees(np.arctan2(at[:, 1], at[:, 0]))
    assert np.allclose(np.mod(np.diff(phi), 360.0), 137.5)
    at, when = primordia(StemModel(radius=10.0, step=2.0, count=4, divergence=90.0, whorl=2, plastochron=3))
    assert when.tolist() == [0, 0, 3, 3] and np.allclose(at[:, 2], [2, 2, 4, 4])
    assert np.allclose(at[1, :2], -at[0, :2]) and abs(at[0, :2] @ at[2, :2]) < 1e-9  # decussate: 90 deg on


@pytest.fixture(scope="module")
def golden_run():
    return simulate(StemModel(radius=11.5, step=1.0, count=16, plastochron=8))


def test_golden_angle_traces_join_along_consecutive_fibonacci_numbers(golden_run):
    run = golden_run
    assert run.settled and (run.primordium_node >= 0).all()
    c = connectivity(run, skip=3)
    assert c["fibonacci_share"] >= 0.8, c["differences"]
    a, b = c["mode"]
    fib = sorted(fibonacci_numbers(100))
    assert a in fib and b == fib[fib.index(a) + 1], c["mode"]
    # every segment is between nodes at most D (plus rounding) apart, and inside the cylinder
    length = np.linalg.norm(run.pos[run.edges[:, 0]] - run.pos[run.edges[:, 1]], axis=1)
    assert length.max() <= 1.0 + 1e-9
    assert np.hypot(run.pos[:, 0], run.pos[:, 1]).max() <= 11.5 + 1e-9 and run.pos[:, 2].min() >= 0


def test_a_taller_step_joins_older_primordia():
    """Sec. 6.3: as R/H decreases, primordia connect to older and older primordia."""
    low = connectivity(simulate(StemModel(radius=11.5, step=1.0, count=14, plastochron=8)), skip=3)
    high = connectivity(simulate(StemModel(radius=11.5, step=2.3, count=14, plastochron=8)), skip=3)
    mean = [sum(k * v for k, v in c["differences"].items()) / sum(c["differences"].values()) for c in (low, high)]
    assert mean[1] < mean[0], (low["differences"], high["differences"])


def test_open_pattern_each_trace_joins_one_older_trace_along_fibonacci_numbers():
    run = simulate(StemModel(radius=23.0, step=2.0, count=16, plastochron=6, pattern="open"))
    assert run.settled and (run.primordium_node >= 0).all()
    later = [hi for _, lo, hi in run.joins]
    assert sorted(later) == list(range(1, 17))        # one join per primordium: a tree
    assert len(run.edges) == len(run.pos)             # a tree on the base ring (one cycle)
    c = connectivity(run, skip=3)
    assert c["fibonacci_share"] == 1.0, c["differences"]


def test_unrolled_diagram_has_the_graph_topology(golden_run):
    run, R = golden_run, 11.5
    seg, cross = unrolled(run, R)
    width = 2 * math.pi * R
    phi = np.mod(np.arctan2(run.pos[:, 1], run.pos[:, 0]), 2 * math.pi)
    key = {(round(R * phi[i], 6), round(run.pos[i, 2], 6)): i for i in range(len(run.pos))}

    def node(p):
        return key[(round(p[0] % width if p[0] >= width or p[0] < 0 else p[0], 6), round(p[1], 6))]

    found = {tuple(sorted((node(s[0]), node(s[1])))) for s in seg}
    assert found == {tuple(e) for e in run.edges.tolist()}
    assert cross.sum() % 2 == 0 and len(seg) == len(run.edges) + cross.sum() // 2
    # no drawn segment spans more than half the strip
    assert (np.abs(seg[:, 0, 0] - seg[:, 1, 0]) <= width / 2 + 1e-9).all()


# ---------------------------------------------------------------------------------------------
# the parameter file and the CLI

SMALL = """
[stem]
radius = 6.0
[primordia]
count = 6
step = 1.0
plastochron = 6
[diagram]
size = 200
"""


def _digest(folder):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir()) if p.is_file()}


def test_cli_writes_every_file_and_reruns_byte_identical(tmp_path):
    (tmp_path / "s.toml").write_text(SMALL + 'growth_map = "g.func"\n')
    (tmp_path / "g.func").write_text("fver 1 1\nname: g\nsamples: 100\nflip: off\npoints: 3\n0 0\n0.5 0.2\n1 1\n")
    out = tmp_path / "out"
    res = CliRunner().invoke(stem_cli.main, [str(tmp_path / "s.toml"), "-o", str(out), "-q"])
    assert res.exit_code == 0, res.output
    names = set(_digest(out))
    assert {"graph.obj", "veins.obj", "unrolled.obj", "diagram.png", "veins_grown.obj", "unrolled_grown.obj",
            "diagram_grown.png", "traces.csv", "connectivity.txt"} <= names
    first = _digest(out)
    res = CliRunner().invoke(stem_cli.main, [str(tmp_path / "s.toml"), "-o", str(out), "-q"])
    assert res.exit_code == 0 and _digest(out) == first
    rows = (out / "traces.csv").read_text().splitlines()
    assert rows[0] == "iteration,primordium,joins,difference,fibonacci" and len(rows) > 6
    assert "g veins" in (out / "veins.obj").read_text() and "g primordia" in (out / "veins.obj").read_text()


@pytest.mark.parametrize("text, words", [
    ("[stem]\nradius = -1\n", "stem.radius"),
    ("[stem]\nradius = nan\n", "stem.radius"),
    ("[primordia]\ncount = 1e20\n", "primordia.count"),
    ("[primordia]\nwhorls = 2\n", "whorl"),
    ("[model]\npattern = \"opn\"\n", "open"),
    ("[stem]\nradius = 5000.0\n[primordia]\ncount = 5000\nstep = 10.0\n", "200,000"),
    ("[diagram]\ngrowth_map = \"missing.func\"\n", "missing.func"),
    ("[veins]\nsides = 100000\n", "veins.sides"),
])
def test_bad_parameters_are_one_line_exit_2_and_nothing_written(tmp_path, text, words):
    (tmp_path / "s.toml").write_text(text)
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, "-m", "inflo.tools.stem_veins.cli", str(tmp_path / "s.toml"), "-o", str(out)],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and words in r.stderr, r.stderr
    assert not out.exists() or not any(out.iterdir())


def test_decreasing_growth_map_is_refused(tmp_path):
    (tmp_path / "g.func").write_text("fver 1 1\nname: g\nsamples: 100\nflip: off\npoints: 2\n0 1\n1 0\n")
    (tmp_path / "s.toml").write_text(SMALL + 'growth_map = "g.func"\n')
    res = CliRunner().invoke(stem_cli.main, [str(tmp_path / "s.toml"), "-o", str(tmp_path / "o")])
    assert res.exit_code == 2 and "non-decreasing" in res.output


def test_params_defaults_and_whorl_height():
    p = params_from_toml({"primordia": {"whorl": 2, "count": 10, "divergence": 90.0}})
    assert p.model.whorl == 2 and p.model.pattern == "closed" and p.model.radius == 11.5


def test_lucas_angle_traces_join_along_consecutive_lucas_numbers():
    """Sec. 6.3, fig. 6.10: with the Lucas angle (99.5 deg) the joins follow 1, 3, 4, 7, 11, ..."""
    c = connectivity(simulate(StemModel(radius=11.5, step=1.0, count=16, plastochron=8, divergence=99.5)), skip=3)
    lucas = [1, 3, 4, 7, 11, 18]
    assert set(c["differences"]) <= set(lucas), c["differences"]
    a, b = c["mode"]
    assert b == lucas[lucas.index(a) + 1], c["mode"]
