"""Hostile input to the organ tools (dimorph, petal-grow, venation, subdivide, a floret's tilt and a
.fcc animation's scale) is a one-line error with exit code 2 that leaves the output folder as it
was: one row per probe -- the command, the message fragment expected. Probes that used to accept
garbage (exit 0), crash (exit 1) or leave partial output behind."""
from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, run_cli

from inflo.formats.obj import ObjMesh, write_obj
from inflo.formats.scn import Placement, Scene, write_scn
from inflo.tools.dimorph.sweep import simple_head
from inflo.tools.petal_grow.bud import grid_bud, write_bud_obj

EXAMPLES = REPO / "pipelines" / "examples"

PETAL = """
[flower]
keyframes = 3
iterations = 5
base_v = 0.2
{flower}
[growth.g]
dg = 0.05
e = 1
w = 0.5
e_in = "{e_in}"
{growth}
[[organ]]
name = "a"
mesh = "petal.obj"
material = "petal"
growth = [[0, "g"]]
{organ}
"""

BLADE = """seed = 1
[blade]
polygon = [[0,0],[10,0],[10,10],[0,10]]
base = [5.0, 0.0]
size = {size}
[veins]
{veins}
[sources]
darts = 0.05
[texture]
size = 64
supersample = 1
"""


def _petal(d: Path, name: str, e_in: str = "1 + 0.5 * v", flower: str = "", growth: str = "", organ: str = ""):
    (d / name).write_text(PETAL.format(e_in=e_in.replace('"', '\\"'), flower=flower, growth=growth, organ=organ))


@pytest.fixture()
def probes(tmp_path):
    d = tmp_path
    scene = Scene(placements=[Placement("ca", 0, p, [0.1] * 3, [0, 1, 0], [1, 0, 0]) for p in simple_head(60)])
    for p in scene.placements:
        p.frame_start, p.frame_end = 5, 5
    write_scn(d / "head.scn", scene)
    (d / "far.scn").write_text("o: 0 1e300 0 0 0.1 0.1 0.1 0 1 0 1 0 0\n" + (d / "head.scn").read_text())
    # petal-grow
    pg = d / "pg"
    pg.mkdir()
    s, t = np.meshgrid(np.linspace(0, 1, 4), np.linspace(0, 1, 5))
    s, t = s.ravel(), t.ravel()
    write_bud_obj(pg / "petal.obj", grid_bud(np.stack([2.0 + 0.5 * s, 6.0 * t, 0.3 * s], axis=1), s, t, 4, 5))
    _petal(pg, "dirnan.toml", growth='direction = "u/0, 1"')
    _petal(pg, "long.toml", e_in="+".join(["u"] * 20000))
    _petal(pg, "deep.toml", e_in="sin(" * 150 + "u" + ")" * 150)
    _petal(pg, "powbomb.toml", e_in="((9**1024)**1024)**1024")
    _petal(pg, "cdist.toml", flower="collision_distance = 1e308")
    _petal(pg, "thick.toml", growth="thickness = 1e308")
    _petal(pg, "rot.toml", organ="rotate = 1e308")
    _petal(pg, "trans.toml", organ="translate = [1e308, 0, 0]")
    _petal(pg, "axis.toml", organ="joint_axis = [1e300, 0, 0]")
    _petal(pg, "stretch.toml", growth='stretch = "1/(v - v)"')
    # venation
    ven = d / "ven"
    ven.mkdir()
    (ven / "ok.toml").write_text(BLADE.format(size=1.0, veins=""))
    (ven / "size.toml").write_text(BLADE.format(size=1e308, veins=""))
    (ven / "poly.toml").write_text(BLADE.format(size=1.0, veins="").replace("[10,10]", "[1e308,10]"))
    (ven / "kill.toml").write_text(BLADE.format(size=1.0, veins="kill_distance = 1e300"))
    roots = ", ".join(f"[5, {k * 0.001:.3f}]" for k in range(5000))
    (ven / "roots.toml").write_text(BLADE.format(size=1.0, veins=f"step = 1.0\nkill_distance = 1.0\nroots = [{roots}]"))
    v = ven / "v"
    v.mkdir()
    (v / "frames").write_text("mine\n")
    # fccompose and floret-animate
    shutil.copytree(EXAMPLES / "fccompose", d / "fcc")
    fcc = (d / "fcc" / "dense.fcc").read_text()
    (d / "fcc" / "scale.fcc").write_text(fcc.replace("animation: 0 1 1 1", "animation: 0 1e308 1 1"))
    text = (EXAMPLES / "disk_bud.floret").read_text()
    (d / "tilt.floret").write_text(text.replace("tilt: 0.0", "tilt: 1e308", 1))
    (d / "petals.floret").write_text(text.replace("symmetry: 5", "symmetry: 1000000000", 1))
    (d / "material.floret").write_text(text.replace("material: 1", "material: 99999999999999999999", 1))
    # subdivide
    tri = ObjMesh(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.2]]), np.array([[0, 1, 2], [1, 3, 2]], np.int32))
    write_obj(d / "tri.obj", tri)
    return d


# (command, arguments with {d} the inputs folder, message fragment)
PROBES = [
    ("dimorph", ["{d}/head.scn", "--alpha", "90", "--ray-lead", "1e11", "-o", "{d}/t.scn"], "--ray-lead"),
    ("dimorph", ["{d}/head.scn", "--alpha", "90", "--ray-lead", "-1e11", "-o", "{d}/t.scn"], "--ray-lead"),
    ("dimorph", ["{d}/head.scn", "--alpha", "90", "--ray-development-frames", "100000000000000", "-o", "{d}/t.scn"],
     "--ray-development-frames"),
    ("dimorph", ["{d}/head.scn", "--alpha", "90", "--ray-id", "100000000000000000000", "-o", "{d}/t.scn"], "--ray-id"),
    ("dimorph", ["{d}/head.scn", "--alpha", "90", "--bracts", "1000000000000", "-o", "{d}/t.scn"], "--bracts"),
    ("dimorph", ["{d}/head.scn", "--alpha", "90", "--threshold", "1e308", "-o", "{d}/t.scn"], "--threshold"),
    ("dimorph", ["{d}/head.scn", "--alpha", "90", "--ray-development-frames", "9999999", "--ray-lead", "-9999999",
                 "-o", "{d}/t.scn"], "expected developmental windows that end by frame 10000000"),
    ("dimorph", ["{d}/far.scn", "--alpha", "90", "-o", "{d}/t.scn"], "positions and scales within +-1e+12"),
    ("dimorph", ["sweep", "-o", "{d}/sw", "--n", "100000"], "expected a sweep of at most 2e+07 cone tests"),
    ("dimorph", ["sweep", "-o", "{d}/sw", "--n-min", "2", "--n-max", "100000"], "cone tests"),
    ("dimorph", ["sweep", "-o", "{d}/sw", "--n", "1000000000"], "--n"),
    ("petal-grow", ["{d}/pg/dirnan.toml", "-o", "{d}/pg"], "dirnan.toml:12: expected values within +-1e+06 over the "
                                                          "organ for direction 'u/0, 1', found nan, 1 at (u, v)"),
    ("petal-grow", ["{d}/pg/stretch.toml", "-o", "{d}/pg"], "stretch.toml:12: expected values within +-1e+06"),
    ("petal-grow", ["{d}/pg/long.toml", "-o", "{d}/pg"], "an expression of at most 1000 characters"),
    ("petal-grow", ["{d}/pg/deep.toml", "-o", "{d}/pg"], "an expression nested at most 100 deep"),
    ("petal-grow", ["{d}/pg/powbomb.toml", "-o", "{d}/pg"], "expected e_in: constant"),
    ("petal-grow", ["{d}/pg/cdist.toml", "-o", "{d}/pg"], "collision_distance: at most the bud's extent"),
    ("petal-grow", ["{d}/pg/thick.toml", "-o", "{d}/pg"], "thickness: at most the bud's extent"),
    ("petal-grow", ["{d}/pg/rot.toml", "-o", "{d}/pg"], "rotate (degrees): a number in [-360, 360]"),
    ("petal-grow", ["{d}/pg/trans.toml", "-o", "{d}/pg"], "translate: a number in"),
    ("petal-grow", ["{d}/pg/axis.toml", "-o", "{d}/pg"], "joint_axis: a number in"),
    ("venation", ["{d}/ven/ok.toml", "--frame-step", "1", "-o", "{d}/ven/v"],
     "v/frames: expected a path that can be a folder, found a file in the way"),
    ("venation", ["{d}/ven/size.toml", "-o", "{d}/ven/o"], "blade.size <= 1e+06"),
    ("venation", ["{d}/ven/poly.toml", "-o", "{d}/ven/o"], "blade.polygon with coordinates within +-1e+06"),
    ("venation", ["{d}/ven/kill.toml", "-o", "{d}/ven/o"], "veins.kill_distance <= the final blade's extent"),
    ("fccompose", ["{d}/fcc/scale.fcc", "-o", "{d}/fcc/o"], "scales in [1e-06, 1e+06] for 'animation'"),
    ("floret-animate", ["{d}/tilt.floret", EXAMPLES / "disk_open.floret", "-o", "{d}/fa"],
     "a finite angle within +-360 degrees"),
    ("floret-animate", ["{d}/petals.floret", EXAMPLES / "disk_open.floret", "-o", "{d}/fa"], "n <= 10000"),
    ("floret-animate", ["{d}/material.floret", EXAMPLES / "disk_open.floret", "-o", "{d}/fa"], "an id <= 255"),
    ("subdivide", ["{d}/tri.obj", "--collision-iterations", "1000000000", "-o", "{d}/s.obj"], "--collision-iterations"),
    ("subdivide", ["{d}/tri.obj", "--max-collision-retries", "1000000000", "-o", "{d}/s.obj"],
     "--max-collision-retries"),
    ("subdivide", ["{d}/tri.obj", "--spacing", "1e308", "-o", "{d}/s.obj"], "at most the mesh's extent"),
]


def _snapshot(folder: Path) -> dict:
    return {p: (hashlib.sha1(p.read_bytes()).hexdigest() if p.is_file() else "dir")
            for p in folder.rglob("*")}


@pytest.mark.parametrize("cli,args,fragment", PROBES, ids=[f"{p[0]}-{i}" for i, p in enumerate(PROBES)])
def test_organ_probe_is_a_one_line_error(probes, cli, args, fragment):
    before = _snapshot(probes)
    r = run_cli(cli, *[str(a).format(d=probes) for a in args])
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert fragment in r.stderr, r.stderr
    lines = [line for line in r.stderr.splitlines() if line.strip()]
    assert len(lines) <= 3 and "Traceback" not in r.stderr and "Warning" not in r.stderr, r.stderr
    if len(lines) > 1:  # only click's usage errors take 3 lines
        assert lines[-1].startswith("Error: Invalid value"), r.stderr
    assert _snapshot(probes) == before  # nothing written, nothing removed, no staging folder left


def test_venation_takes_more_than_4096_roots(probes):
    r = run_cli("venation", "-q", probes / "ven" / "roots.toml", "-o", probes / "ven" / "r")
    assert r.returncode == 0, r.stderr
    text = (probes / "ven" / "r" / "veins.obj").read_text()
    assert sum(line.startswith("v ") for line in text.splitlines()) >= 5000


def test_a_blocked_output_file_moves_nothing(tmp_path):
    """A finished staged run whose file's place is taken by a folder refuses before moving any
    file, and removes its staging folder."""
    from inflo.formats.atomic import staged_output
    from inflo.formats.errors import InputError

    out = tmp_path / "out"
    (out / "b.txt").mkdir(parents=True)
    with pytest.raises(InputError, match="b.txt: expected a path that can be a file, found a folder"):
        with staged_output(out, "tool") as st:
            (st / "a.txt").write_text("a")
            (st / "b.txt").write_text("b")
    assert sorted(p.name for p in out.iterdir()) == ["b.txt"]
