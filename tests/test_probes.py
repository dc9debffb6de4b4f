"""Bad numbers are one-line errors with exit 2 and no output ("Every bad number is a clear
error"): one row per probe -- the command, the message fragment expected, the output that must not
exist afterwards. Probes that used to hang, exhaust memory, crash with exit 1 or accept garbage."""
from __future__ import annotations

import pytest
from conftest import REPO, run_cli

from inflo.formats.obj import ObjMesh, write_obj
from inflo.formats.scn import Placement, Scene, write_scn
from inflo.tools.dimorph.sweep import simple_head

FLORET = REPO / "pipelines" / "sunflower" / "draft" / "ray_bud.floret"


@pytest.fixture()
def inputs(tmp_path):
    import numpy as np

    tri = ObjMesh(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.2]]), np.array([[0, 1, 2], [1, 3, 2]], np.int32))
    write_obj(tmp_path / "tri.obj", tri)
    (tmp_path / "empty.obj").write_text("# nothing\n")
    seq = tmp_path / "seq"
    seq.mkdir()
    write_obj(seq / "frame_0000.obj", tri)
    write_obj(seq / "frame_0001.obj", ObjMesh(np.vstack([tri.vertices, [[2.0, 0, 0]]]), tri.faces))
    scene = Scene(placements=[Placement("o", 0, p, [0.1] * 3, [0, 1, 0], [1, 0, 0]) for p in simple_head(40)])
    write_scn(tmp_path / "head.scn", scene)
    text = FLORET.read_text().splitlines()
    k = text.index("points:") + 1
    text[k] = "1e300 " + " ".join(text[k].split()[1:])
    (tmp_path / "big.floret").write_text("\n".join(text) + "\n")
    text = FLORET.read_text().splitlines()
    k = text.index("points:") + 1
    while k < len(text) and text[k].startswith("  "):
        text[k] = "  " + "   ".join(["0 0 0"] * (len(text[k].split()) // 3))
        k += 1
    (tmp_path / "point.floret").write_text("\n".join(text) + "\n")
    (tmp_path / "garbage.toml").write_bytes(bytes(range(128, 256)) * 2)
    import shutil
    shutil.copytree(REPO / "pipelines" / "examples" / "fccompose", tmp_path / "fcc")
    (tmp_path / "huge.obj").write_text("v 0 0 0\nv 1e308 0 0\nv 0 1 0\nf 1 2 3\n")
    (tmp_path / "samples.toml").write_text("[surface]\nsamples = 1000000000000\n")
    (tmp_path / "frames.toml").write_text("[dynamics]\nframes = 100000000\n")
    (tmp_path / "interval.toml").write_text("[dynamics]\ninterval = 1e-9\n")
    fcc = (tmp_path / "fcc" / "dense.fcc").read_text()
    (tmp_path / "fcc" / "wide.fcc").write_text(fcc.replace("spacing: 0.01", "spacing: 1e300"))
    (tmp_path / "fcc" / "iters.fcc").write_text(fcc.replace("solver iterations: 50", "solver iterations: 1" + "0" * 23))
    dup = tmp_path / "fcc" / "dup"  # a template with a duplicated (unwelded) vertex in every frame
    dup.mkdir()
    for f in sorted((tmp_path / "fcc" / "anim").glob("frame_*.obj")):
        lines = f.read_text().splitlines()
        vs = [i for i, l in enumerate(lines) if l.startswith("v ")]
        lines[vs[178]] = lines[vs[177]]
        (dup / f.name).write_text("\n".join(lines) + "\n")
    (tmp_path / "fcc" / "dup.fcc").write_text(fcc.replace(" anim\n", " dup\n"))
    (tmp_path / "step.toml").write_text("[rodkaew]\nstep = 1e-9\n")
    far = Scene(placements=[Placement("o", 0, [1e300, 0, 0], [0.1] * 3, [0, 1, 0], [1, 0, 0])] + scene.placements[1:])
    write_scn(tmp_path / "far.scn", far)
    return tmp_path


# (command, arguments with {d} the inputs folder, message fragment, output that must not exist)
PROBES = [
    ("fccompose", ["{d}/fcc/dense.fcc", "-o", "{d}/fcc/anim"], "holding the 'animation' input anim", "{d}/fcc/anim/log.csv"),
    ("fccompose", ["{d}/fcc/wide.fcc", "-o", "{d}/fcc/o1"], "at most 4 x the largest floret's extent", "{d}/fcc/o1"),
    ("fccompose", ["{d}/fcc/iters.fcc", "-o", "{d}/fcc/o2"], "an integer in [0, 10000]", "{d}/fcc/o2"),
    ("fccompose", ["{d}/fcc/dup.fcc", "-o", "{d}/fcc/o3"], "vertices 178 and 179 at the same point", "{d}/fcc/o3"),
    ("canopy-render", ["{d}/huge.obj", "-o", "{d}/r1.png"], "coordinates within +-1e+15", "{d}/r1.png"),
    ("floret-animate", ["{d}/big.floret", REPO / "pipelines" / "sunflower" / "draft" / "ray_open.floret", "-o", "{d}/f1"],
     "coordinates within +-1e+12", "{d}/f1"),
    ("floret-animate", ["{d}/point.floret", REPO / "pipelines" / "sunflower" / "draft" / "ray_open.floret", "-o", "{d}/f3"],
     "found all 40 at 0 0 0", "{d}/f3"),
    ("floret-animate", [REPO / "pipelines" / "examples" / "lu_bud.floret", "--lu", "{d}/garbage.toml", "-o", "{d}/f2"],
     "expected TOML (UTF-8 text)", "{d}/f2"),
    ("branch-gen", ["{d}/head.scn", "--base", "nan", "nan", "nan", "-o", "{d}/b1"], "--base must be three finite numbers",
     "{d}/b1"),
    ("branch-gen", ["{d}/head.scn", "{d}/step.toml", "-o", "{d}/b2"], "rodkaew.step: expected a step >= ", "{d}/b2"),
    ("branch-gen", ["{d}/far.scn", "-o", "{d}/b3"], "positions within +-1e+12, found 1e+300", "{d}/b3"),
    ("phyllotaxis", ["{d}/samples.toml", "-o", "{d}/h1"], "surface.samples in [16, 10000000]", "{d}/h1"),
    ("phyllotaxis", ["{d}/frames.toml", "-o", "{d}/h2"], "dynamics.frames in [1, 100000]", "{d}/h2"),
    ("phyllotaxis", ["{d}/interval.toml", "-o", "{d}/h3"], "dynamics.interval >= 0.001", "{d}/h3"),
    ("polygonize", [FLORET, "--eta", "1e9", "-o", "{d}/p1"], "eta(v) <= 10000", "{d}/p1"),
    ("polygonize", [FLORET, "--lambda", "1e-7", "-o", "{d}/p2"], "at most 10000 rows", "{d}/p2"),
    ("polygonize", [FLORET, "--aspect", "inf", "-o", "{d}/p3"], "--aspect", "{d}/p3"),
    ("polygonize", [FLORET, "--aspect", "1e-300", "-o", "{d}/p4"], "--aspect", "{d}/p4"),
    ("subdivide", ["{d}/tri.obj", "--spacing", "nan", "-o", "{d}/s1.obj"], "--spacing must be a finite number", "{d}/s1.obj"),
    ("subdivide", ["{d}/tri.obj", "--spacing", "inf", "-o", "{d}/s2.obj"], "--spacing must be a finite number", "{d}/s2.obj"),
    ("subdivide", ["{d}/empty.obj", "-o", "{d}/s3.obj"], "expected a mesh with triangles", "{d}/s3.obj"),
    ("subdivide", ["{d}/seq", "-o", "{d}/s4"], "expected 4 vertices like frame_0000.obj", "{d}/s4"),
    ("dimorph", ["{d}/head.scn", "--alpha", "200", "-o", "{d}/t1.scn"], "outside (0, 180] degrees", "{d}/t1.scn"),
    ("dimorph", ["{d}/head.scn", "--alpha", "100", "--half-angle", "-o", "{d}/t2.scn"], "outside (0, 90] degrees",
     "{d}/t2.scn"),
    ("dimorph", ["{d}/head.scn", "--alpha", "90", "--ray-scale", "1e-320", "-o", "{d}/t3.scn"],
     "--ray-scale must be", "{d}/t3.scn"),
]


@pytest.mark.parametrize("cli,args,fragment,absent", PROBES, ids=[f"{p[0]}-{i}" for i, p in enumerate(PROBES)])
def test_bad_number_is_a_one_line_error(inputs, cli, args, fragment, absent):
    args = [str(a).format(d=inputs) for a in args]
    r = run_cli(cli, *args)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert fragment in r.stderr, r.stderr
    lines = [l for l in r.stderr.splitlines() if l.strip()]
    assert len(lines) <= 3 and "Traceback" not in r.stderr  # click's usage errors take 3 lines
    from pathlib import Path
    assert not Path(absent.format(d=inputs)).exists()
    if cli == "fccompose":  # the input frames it would have removed as stale are still there
        assert (inputs / "fcc" / "anim" / "frame_0000.obj").exists()
