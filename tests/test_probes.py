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
    (tmp_path / "fcc" / "wide.fcc").write_text(fcc.replace("spacing: 0.01", "spacing: 1e6"))
    (tmp_path / "fcc" / "iters.fcc").write_text(fcc.replace("solver iterations: 50", "solver iterations: 1" + "0" * 23))
    for name, line in [("sscale", "scene scale factor: 1e308 1 1"), ("lattice", "lattice size multiply: 1e308 1 1"),
                       ("origin", "origin: 1e308 0 0"), ("dims", "dimensions: 1 1e308 1")]:
        (tmp_path / "fcc" / f"{name}.fcc").write_text(fcc + line + "\n")
    dup = tmp_path / "fcc" / "dup"  # a template with a duplicated (unwelded) vertex in every frame
    dup.mkdir()
    for f in sorted((tmp_path / "fcc" / "anim").glob("frame_*.obj")):
        lines = f.read_text().splitlines()
        vs = [i for i, l in enumerate(lines) if l.startswith("v ")]
        lines[vs[178]] = lines[vs[177]]
        (dup / f.name).write_text("\n".join(lines) + "\n")
    (tmp_path / "fcc" / "dup.fcc").write_text(fcc.replace(" anim\n", " dup\n"))
    (tmp_path / "step.toml").write_text("[rodkaew]\nstep = 1e-9\n")
    write_scn(tmp_path / "far.scn", Scene(placements=scene.placements[1:]))  # the writer refuses 1e300: by hand
    (tmp_path / "far.scn").write_text("o: 0 1e300 0 0 0.1 0.1 0.1 0 1 0 1 0 0\n" + (tmp_path / "far.scn").read_text())
    return tmp_path


# (command, arguments with {d} the inputs folder, message fragment, output that must not exist)
PROBES = [
    ("fccompose", ["{d}/fcc/dense.fcc", "-o", "{d}/fcc/anim"], "holding the 'animation' input anim", "{d}/fcc/anim/log.csv"),
    ("fccompose", ["{d}/fcc/wide.fcc", "-o", "{d}/fcc/o1"], "at most 4 x the largest floret's extent", "{d}/fcc/o1"),
    ("fccompose", ["{d}/fcc/iters.fcc", "-o", "{d}/fcc/o2"], "an integer in [0, 10000]", "{d}/fcc/o2"),
    ("fccompose", ["{d}/fcc/sscale.fcc", "-o", "{d}/fcc/o4"], "magnitude at most 1e+06", "{d}/fcc/o4"),
    ("fccompose", ["{d}/fcc/lattice.fcc", "-o", "{d}/fcc/o5"], "magnitude at most 1e+06", "{d}/fcc/o5"),
    ("fccompose", ["{d}/fcc/origin.fcc", "-o", "{d}/fcc/o6"], "magnitude at most 1e+12", "{d}/fcc/o6"),
    ("fccompose", ["{d}/fcc/dims.fcc", "-o", "{d}/fcc/o7"], "magnitude at most 1e+12", "{d}/fcc/o7"),
    ("fccompose", ["{d}/fcc/dup.fcc", "-o", "{d}/fcc/o3"], "vertices 178 and 179 at the same point", "{d}/fcc/o3"),
    ("canopy-render", ["{d}/huge.obj", "-o", "{d}/r1.png"], "coordinates within +-1e+15", "{d}/r1.png"),
    ("floret-animate", ["{d}/big.floret", REPO / "pipelines" / "sunflower" / "draft" / "ray_open.floret", "-o", "{d}/f1"],
     "coordinates within +-1e+12", "{d}/f1"),
    ("floret-animate", ["{d}/point.floret", REPO / "pipelines" / "sunflower" / "draft" / "ray_open.floret", "-o", "{d}/f3"],
     "found all 40 at 0 0 0", "{d}/f3"),
    ("floret-animate", [REPO / "pipelines" / "examples" / "lu_bud.floret", "--lu", "{d}/garbage.toml", "-o", "{d}/f2"],
     "expected TOML (UTF-8 text)", "{d}/f2"),
    ("branch-gen", ["{d}/head.scn", "--base", "nan", "nan", "nan", "-o", "{d}/b1"], "'--base': expected a finite number",
     "{d}/b1"),
    ("branch-gen", ["{d}/head.scn", "{d}/step.toml", "-o", "{d}/b2"], "expected a step >= ", "{d}/b2"),
    ("branch-gen", ["{d}/far.scn", "-o", "{d}/b3"], "positions within +-1e+12, found 1e+300", "{d}/b3"),
    ("phyllotaxis", ["{d}/samples.toml", "-o", "{d}/h1"], "surface.samples in [16, 10000000]", "{d}/h1"),
    ("phyllotaxis", ["{d}/frames.toml", "-o", "{d}/h2"], "dynamics.frames in [1, 100000]", "{d}/h2"),
    ("phyllotaxis", ["{d}/interval.toml", "-o", "{d}/h3"], "dynamics.interval >= 0.001", "{d}/h3"),
    ("polygonize", [FLORET, "--eta", "1e9", "-o", "{d}/p1"], "eta(v) <= 10000", "{d}/p1"),
    ("polygonize", [FLORET, "--lambda", "1e-7", "-o", "{d}/p2"], "at most 10000 rows", "{d}/p2"),
    ("polygonize", [FLORET, "--aspect", "inf", "-o", "{d}/p3"], "--aspect", "{d}/p3"),
    ("polygonize", [FLORET, "--aspect", "1e-300", "-o", "{d}/p4"], "--aspect", "{d}/p4"),
    ("subdivide", ["{d}/tri.obj", "--spacing", "nan", "-o", "{d}/s1.obj"], "'--spacing': expected a finite number", "{d}/s1.obj"),
    ("subdivide", ["{d}/tri.obj", "--spacing", "inf", "-o", "{d}/s2.obj"], "'--spacing': expected a finite number", "{d}/s2.obj"),
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
    assert len(lines) == 1 and "Traceback" not in r.stderr
    from pathlib import Path
    assert not Path(absent.format(d=inputs)).exists()
    if cli == "fccompose":  # the input frames it would have removed as stale are still there
        assert (inputs / "fcc" / "anim" / "frame_0000.obj").exists()


# ---------------------------------------------------------------------------------------------
# the newer tools and keys as a hostile user would use them: bounds on the work implied, outputs
# that never eat inputs, paths that cannot be written, seeds, nested scenes

PETAL_FLOWER = """
[flower]
keyframes = 3
iterations = 5
base_v = 0.2

[growth.g]
dg = 0.05
e = 1
w = 0.5
e_in = "{e_in}"

[[organ]]
name = "a"
mesh = "petal.obj"
material = "petal"
growth = [[0, "g"]]
"""

VENATION = """seed = 1
[blade]
polygon = [[0, 0], [1, 0], [1, 1], [0, 1]]
size = {size}
[growth]
type = "uniform"
initial = 0.5
final = 1.0
rate = {rate}
[veins]
step = {step}
kill_distance = {kill}
[sources]
birth_source = {kill}
birth_vein = {kill}
darts = {darts}
[texture]
size = {tex}
supersample = {ss}
"""


def _venation(d, name, size=100.0, rate=0.01, step=1.0, kill=4.0, darts=0.01, tex=256, ss=1):
    (d / name).write_text(VENATION.format(size=size, rate=rate, step=step, kill=kill, darts=darts, tex=tex, ss=ss))


def _scn_line(kind, pid, extra=""):
    return f"{kind}: {pid} 0 0 0 1 1 1 0 1 0 1 0 0{extra}\n"


def _bilevel_png(path, w, h):
    """A black 1-bit PNG of w x h written row by row (no image in memory)."""
    import struct
    import zlib

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    z = zlib.compressobj(9)
    row = b"\x00" * (1 + (w + 7) // 8)
    idat = b"".join(z.compress(row) for _ in range(h)) + z.flush()
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 1, 0, 0, 0, 0))
                     + chunk(b"IDAT", idat) + chunk(b"IEND", b""))


@pytest.fixture()
def hostile(tmp_path):
    import shutil

    import numpy as np
    from PIL import Image

    from inflo.tools.petal_grow.bud import grid_bud, write_bud_obj

    d = tmp_path
    # venation
    (d / "ven").mkdir()
    _venation(d / "ven", "ok.toml")
    _venation(d / "ven", "step.toml", step=1e-5, kill=4e-5)
    _venation(d / "ven", "darts.toml", darts=1e9)
    _venation(d / "ven", "tex.toml", tex=16384, ss=8)
    _venation(d / "ven", "slow.toml", rate=1e-300)
    (d / "ven" / "mesh.toml").write_text((d / "ven" / "ok.toml").read_text() + "[output]\nmesh_spacing = 1e-300\n")
    (d / "ven" / "wide.toml").write_text((d / "ven" / "ok.toml").read_text() + "[width]\ntip = 1e300\n")
    _venation(d / "ven", "bigtex.toml", tex=16384)  # frame textures of 16384^2 pixels: 32 at most
    (d / "ven" / "frametex.toml").write_text((d / "ven" / "bigtex.toml").read_text()
                                             + "[output]\nframe_step = 1\nframe_textures = true\n")
    # petal-grow: a small petal, its bud named like a frame in one folder
    pg = d / "pg"
    pg.mkdir()
    s, t = np.meshgrid(np.linspace(0, 1, 4), np.linspace(0, 1, 5))
    s, t = s.ravel(), t.ravel()
    x = np.stack([2.0 + 0.5 * s, 6.0 * t, 0.3 * s], axis=1)
    write_bud_obj(pg / "petal.obj", grid_bud(x, s, t, 4, 5))
    (pg / "ok.toml").write_text(PETAL_FLOWER.format(e_in="1 + 0.5 * v"))
    (pg / "pow.toml").write_text(PETAL_FLOWER.format(e_in="9**9**9"))
    (pg / "exp.toml").write_text(PETAL_FLOWER.format(e_in="exp(u * 1000)"))
    (pg / "iters.toml").write_text(PETAL_FLOWER.format(e_in="1").replace("iterations = 5", "iterations = 1000000000000"))
    (pg / "keys.toml").write_text(PETAL_FLOWER.format(e_in="1").replace("keyframes = 3", "keyframes = 1000000000000"))
    Image.new("L", (5000, 5000)).save(pg / "big.png")
    (pg / "png.toml").write_text(PETAL_FLOWER.format(e_in="big.png"))
    _bilevel_png(pg / "bomb.png", 20000, 20000)  # 400 M pixels in a few kB: beyond what PIL opens
    (pg / "bomb.toml").write_text(PETAL_FLOWER.format(e_in="bomb.png"))
    framed = d / "pgf"
    framed.mkdir()
    write_bud_obj(framed / "frame_0000.obj", grid_bud(x, s, t, 4, 5))
    (framed / "f.toml").write_text(PETAL_FLOWER.format(e_in="1").replace('"petal.obj"', '"frame_0000.obj"'))
    # thyrse
    (d / "thyrse_nodes.toml").write_text("[thyrse]\nnodes = 1000000000000\n")
    (d / "thyrse_dense.toml").write_text("[thyrse]\nnodes = 40\norder = 5.0\ndensity = 900000.0\n"
                                         "lateral_length = 0.9\n")
    (d / "thyrse_long.toml").write_text("[thyrse]\nlength = 1e300\n")
    (d / "thyrse_reach.toml").write_text("[thyrse]\nreach = 1e300\nmin_distance = 1\n")
    (d / "thyrse_tropism.toml").write_text("[thyrse]\ntropism = 1e300\n")
    # phyllotaxis
    (d / "rings.toml").write_text("[receptacle]\nsegments = 100000\nrings = 100000\n")
    (d / "radius.toml").write_text("[surface]\nradius = 1e300\n")
    (d / "room.toml").write_text("[hierarchy]\nroom_iterations = 1000000000000\n")
    (d / "head.toml").write_text("[compound]\nhead_height = 1e300\n")
    (d / "area.toml").write_text("[primordia]\narea = 1e300\n")
    (d / "size.toml").write_text("[primordia]\nsize_factor = 1e300\n")
    (d / "tiny.toml").write_text("[primordia]\narea = 1e-300\n")
    # fccompose: nested scenes, frame numbers, RBA frames, petal factors, petal weights
    f = d / "fcc"
    shutil.copytree(REPO / "pipelines" / "examples" / "fccompose", f)
    base = (f / "dense.fcc").read_text()
    lines = (f / "scene.scn").read_text()
    (f / "far.scn").write_text(lines.replace(" 0 19", " 1000000000000 1000000000001"))
    (f / "far.fcc").write_text(base.replace("scene.scn", "far.scn"))
    (f / "petal.scn").write_text(lines + "#@ petal: 1.5\n")
    (f / "petal.fcc").write_text(base.replace("scene.scn", "petal.scn"))
    (f / "pw").mkdir()
    (f / "pw" / "petal.weights").write_text("# petal weights\n" + "0\n" * 10)
    (f / "pw.fcc").write_text(base + "petal weight: 0 pw/petal.weights\n")
    (f / "rba_e").mkdir()
    (f / "rba_e" / "0000.rba").write_text("")
    for depth, width, name in ((7, 2, "deep"), (5, 20, "wide")):
        rbas = ""
        for k in range(depth):
            (f / f"{name}{k}.scn").write_text(_scn_line("o", 10 + k) * width)
            rbas += f"rigid body animation: {10 + k} 1 1 1 rba_e {name}{k + 1}.scn\n"
        (f / f"{name}{depth}.scn").write_text(_scn_line("ca", 0, " 0 19") * width)
        (f / f"{name}.fcc").write_text(base.replace("scene.scn", f"{name}0.scn") + rbas)
    (f / "rbaseq").mkdir()
    row = "0 0 0 0 1 1 1 0 1 0 1 0 0\n"
    for k, text in enumerate([row, "", row]):
        (f / "rbaseq" / f"{k:04d}.rba").write_text(text)
    (f / "rb.scn").write_text(_scn_line("rba", 0, " 0 2"))
    (f / "rb.fcc").write_text(base.replace("scene file path: scene.scn\n", "")
                              + "rigid body animation: 5 1 1 1 rbaseq rb.scn\n")
    # floret-animate: a key pose named like a frame in the output folder
    keys = d / "keys"
    keys.mkdir()
    shutil.copy(FLORET, keys / "frame_0005.floret")
    # subdivide
    seq = d / "sub"
    seq.mkdir()
    from inflo.formats.obj import ObjMesh, write_obj
    tri = ObjMesh(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.2]]), np.array([[0, 1, 2], [1, 3, 2]], np.int32))
    write_obj(seq / "frame_0000.obj", tri)
    write_obj(d / "one.obj", tri)
    (d / "afile").write_text("x\n")
    write_scn(d / "head.scn", Scene(placements=[Placement("o", 0, q, [0.1] * 3, [0, 1, 0], [1, 0, 0])
                                                for q in simple_head(20)]))
    (d / "bgseed.toml").write_text("seed = -3\n")
    # inflo-sweep with its output inside the folder every variant copies
    sw = d / "sw"
    (sw / "inp").mkdir(parents=True)
    shutil.copy(REPO / "pipelines" / "examples" / "sweeps" / "vogel.toml", sw / "inp" / "vogel.toml")
    (sw / "in.toml").write_text('[sweep]\nname = "x"\ninputs = ["inp"]\n[axes]\n'
                                'n = { target = "inp/vogel.toml:primordia.count", values = [20] }\n'
                                '[[stage]]\ncli = "phyllotaxis"\nargs = ["{inputs}/inp/vogel.toml", "-o", "{out}/h"]\n')
    return d


KEY_OPEN = REPO / "pipelines" / "sunflower" / "draft" / "ray_open.floret"

# (command, arguments with {d} the inputs folder, message fragment, path that must not exist)
HOSTILE = [
    ("venation", ["{d}/ven/step.toml", "-o", "{d}/v1"], "veins.step >= the final blade's extent", "{d}/v1"),
    ("venation", ["{d}/ven/darts.toml", "-o", "{d}/v2"], "at most 1000000 darts a step", "{d}/v2"),
    ("venation", ["{d}/ven/tex.toml", "-o", "{d}/v3"], "texture.size x texture.supersample <= 16384", "{d}/v3"),
    ("venation", ["{d}/ven/slow.toml", "-o", "{d}/v4"], "growth that reaches its final size", "{d}/v4"),
    ("venation", ["{d}/ven/ok.toml", "--seed", "-1", "-o", "{d}/v5"], "--seed", "{d}/v5"),
    ("venation", ["{d}/ven/mesh.toml", "-o", "{d}/v6"], "output.mesh_spacing >= the final blade's extent", "{d}/v6"),
    ("venation", ["{d}/ven/wide.toml", "-o", "{d}/v7"], "width.tip <= 1e6", "{d}/v7"),
    ("venation", ["{d}/ven/frametex.toml", "-o", "{d}/v8"], "expected output.frame_step: a frame step of at most",
     "{d}/v8"),
    ("venation", ["{d}/ven/bigtex.toml", "--frame-step", "1", "--frame-textures", "-o", "{d}/v9"],
     "--frame-step: expected a frame step of at most 10000 frames and 8589934592 texture pixels", "{d}/v9"),
    ("venation", ["{d}/ven/ok.toml", "--frame-step", "0", "-o", "{d}/afile"], "expected an output folder", "{d}/afile/x"),
    ("venation", ["{d}/ven/ok.toml", "-o", "{d}/afile"], "expected an output folder, found a file", "{d}/afile/x"),
    ("venation", ["{d}/ven/ok.toml", "-o", "{d}/ven/ok.toml"], "expected an output folder, found a file",
     "{d}/ven/veins.obj"),
    ("venation", ["{d}/ven/ok.toml", "-o", "{d}/afile/sub"], "whose parents are folders", "{d}/afile/sub"),
    ("petal-grow", ["{d}/pg/pow.toml", "-o", "{d}/p1"], "constant exponents within +-1024", "{d}/p1"),
    ("petal-grow", ["{d}/pg/exp.toml", "-o", "{d}/p7"], "expected values within +-1e+06 over the organ", "{d}/p7"),
    ("petal-grow", ["{d}/pg/iters.toml", "-o", "{d}/p2"], "iterations: an integer in [0, 10000]", "{d}/p2"),
    ("petal-grow", ["{d}/pg/keys.toml", "-o", "{d}/p3"], "keyframes: an integer in [1, 10000]", "{d}/p3"),
    ("petal-grow", ["{d}/pg/png.toml", "-o", "{d}/p4"], "a PNG of at most 16777216 pixels", "{d}/p4"),
    ("petal-grow", ["{d}/pg/ok.toml", "--keyframes", "1000000000000", "-o", "{d}/p5"], "--keyframes", "{d}/p5"),
    ("petal-grow", ["{d}/pg/bomb.toml", "-o", "{d}/p6"], "a PNG of at most 16777216 pixels", "{d}/p6"),
    ("petal-grow", ["{d}/pgf/f.toml", "-o", "{d}/pgf"], "holds the bud mesh of organ 'a'", "{d}/pgf/log.csv"),
    ("petal-grow", ["{d}/pgf/f.toml", "-o", "{d}/pgf/frame_0000.obj"], "expected an output folder, found a file",
     "{d}/pgf/log.csv"),
    ("thyrse", ["{d}/thyrse_nodes.toml", "-o", "{d}/t1"], "an integer in [0, 10000]", "{d}/t1"),
    ("thyrse", ["{d}/thyrse_dense.toml", "-o", "{d}/t2"], "at most 1000000 nodes", "{d}/t2"),
    ("thyrse", ["{d}/thyrse_long.toml", "-o", "{d}/t3"], "a length in (0, 1e+06]", "{d}/t3"),
    ("thyrse", ["{d}/thyrse_reach.toml", "-o", "{d}/t4"], "a reach in [0, 1e6]", "{d}/t4"),
    ("thyrse", ["{d}/thyrse_tropism.toml", "-o", "{d}/t5"], "a weight in [0, 1e6]", "{d}/t5"),
    ("phyllotaxis", ["{d}/rings.toml", "-o", "{d}/h1"], "receptacle.segments <= 4096", "{d}/h1"),
    ("phyllotaxis", ["{d}/radius.toml", "-o", "{d}/h2"], "surface.radius in (0, 1e6]", "{d}/h2"),
    ("phyllotaxis", ["{d}/room.toml", "-o", "{d}/h3"], "hierarchy.room_iterations in [1, 1000]", "{d}/h3"),
    ("phyllotaxis", ["{d}/head.toml", "-o", "{d}/h7"], "compound.head_height within +-1000", "{d}/h7"),
    ("phyllotaxis", ["{d}/area.toml", "-o", "{d}/h4"], "primordia.area > 0 (A(s) is a primordium area), in [1e-12, 1e12]", "{d}/h4"),
    ("phyllotaxis", ["{d}/size.toml", "-o", "{d}/h5"], "primordia.size_factor in (0, 1e6]", "{d}/h5"),
    ("phyllotaxis", ["{d}/tiny.toml", "-o", "{d}/h6"], "primordia.area > 0 (A(s) is a primordium area), in [1e-12", "{d}/h6"),
    ("phyllotaxis", [REPO / "pipelines" / "examples" / "sweeps" / "vogel.toml", "-o", "{d}/afile/h"],
     "expected a", "{d}/afile/h"),
    ("fccompose", ["{d}/fcc/deep.fcc", "-o", "{d}/fcc/o1"], "nested at most 6 deep", "{d}/fcc/o1"),
    ("fccompose", ["{d}/fcc/wide.fcc", "-o", "{d}/fcc/o2"], "at most 200000 florets", "{d}/fcc/o2"),
    ("fccompose", ["{d}/fcc/far.fcc", "-o", "{d}/fcc/o3"], "frames in 0..10000000", "{d}/fcc/o3"),
    ("fccompose", ["{d}/fcc/petal.fcc", "-o", "{d}/fcc/o4"], "expected a 'petal weight' line", "{d}/fcc/o4"),
    ("fccompose", ["{d}/fcc/pw.fcc", "-o", "{d}/fcc/pw"], "holding the 'petal weight' input", "{d}/fcc/pw/log.csv"),
    ("fccompose", ["{d}/fcc/rb.fcc", "-o", "{d}/fcc/o5"], "an empty file (a truncated frame?)", "{d}/fcc/o5"),
    ("fccompose", ["{d}/fcc/dense.fcc", "-o", "{d}/afile"], "expected an output folder, found a file",
     "{d}/afile/log.csv"),
    ("floret-animate", ["{d}/keys/frame_0005.floret", KEY_OPEN, "-o", "{d}/keys"], "holds the key pose",
     "{d}/keys/frame_0000.floret"),
    ("floret-animate", [FLORET, KEY_OPEN, "--seed", "-1", "-o", "{d}/fa1"], "--seed", "{d}/fa1"),
    ("floret-animate", [FLORET, KEY_OPEN, "-o", "{d}/afile"], "is a file",
     "{d}/afile/frame_0000.floret"),
    ("subdivide", ["{d}/one.obj", "-o", "{d}/one.obj"], "that is the input mesh", "{d}/one.obj.bak"),
    ("subdivide", ["{d}/sub", "-o", "{d}/sub"], "that holds the input mesh", "{d}/sub/frame_0001.obj"),
    ("subdivide", ["{d}/one.obj", "-o", "{d}/afile/s.obj"], "whose parents are folders", "{d}/afile/s.obj"),
    ("dimorph", ["{d}/head.scn", "--alpha", "90", "-o", "{d}/head.scn"], "that is the input scene",
     "{d}/head.scn.bak"),
    ("dimorph", ["{d}/head.scn", "--alpha", "90", "-o", "{d}/afile/t.scn"], "whose parents are folders",
     "{d}/afile/t.scn"),
    ("branch-gen", ["{d}/head.scn", "-o", "{d}/afile"], "expected an output folder, found a file",
     "{d}/afile/branches.obj"),
    ("branch-gen", ["{d}/head.scn", "--seed", "-5", "-o", "{d}/b1"], "--seed", "{d}/b1"),
    ("branch-gen", ["{d}/head.scn", "{d}/bgseed.toml", "-o", "{d}/b2"], "a seed in [0, 4294967295]", "{d}/b2"),
    ("inflo-sweep", ["{d}/sw/in.toml", "-o", "{d}/sw/inp/out"], "outside the folders each variant copies",
     "{d}/sw/inp/out"),
]


@pytest.mark.parametrize("cli,args,fragment,absent", HOSTILE, ids=[f"{p[0]}-{i}" for i, p in enumerate(HOSTILE)])
def test_hostile_input_is_a_one_line_error(hostile, cli, args, fragment, absent):
    import hashlib
    from pathlib import Path

    def snapshot():
        return {p: hashlib.sha1(p.read_bytes()).hexdigest() for p in hostile.rglob("*") if p.is_file()}

    before = snapshot()
    args = [str(a).format(d=hostile) for a in args]
    r = run_cli(cli, *args)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert fragment in r.stderr, r.stderr
    lines = [l for l in r.stderr.splitlines() if l.strip()]
    assert len(lines) == 1 and "Traceback" not in r.stderr
    assert not Path(absent.format(d=hostile)).exists()
    assert snapshot() == before  # nothing written, nothing removed, no input changed


def test_a_second_run_into_a_folder_being_written_is_refused(hostile):
    from inflo.formats.atomic import output_lock

    out = hostile / "locked"
    with output_lock(out, "test"):
        r = run_cli("venation", hostile / "ven" / "ok.toml", "-o", out)
    assert r.returncode == 2, r.stderr
    assert "found another run writing it now" in r.stderr
    assert list(out.iterdir()) == []


def test_a_failed_rerun_leaves_the_earlier_output_whole(hostile):
    """A run through the staging folder that fails (or is killed) leaves the earlier run's files
    as they were; the next complete run replaces only its own files (by manifest), never a user's."""
    from inflo.formats.atomic import read_manifest, staged_output

    out = hostile / "staged"
    with staged_output(out, "tool", stale_patterns=(r"frame_\d+\.obj",)) as st:
        for k in range(3):
            (st / f"frame_{k:04d}.obj").write_text(f"first {k}\n")
    (out / "notes.txt").write_text("mine\n")
    with pytest.raises(RuntimeError), staged_output(out, "tool") as st:
        (st / "frame_0000.obj").write_text("second 0\n")
        raise RuntimeError("killed")
    assert sorted(p.name for p in out.iterdir()) == [".inflo-tool.manifest", "frame_0000.obj", "frame_0001.obj",
                                                     "frame_0002.obj", "notes.txt"]
    assert (out / "frame_0000.obj").read_text() == "first 0\n"
    with staged_output(out, "tool") as st:
        (st / "frame_0000.obj").write_text("third 0\n")
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == ["frame_0000.obj", "notes.txt"]
    assert read_manifest(out, "tool") == ["frame_0000.obj"]


def test_petal_grow_rerun_replaces_its_own_frames_only(hostile):
    out = hostile / "pgo"
    r = run_cli("petal-grow", "-q", hostile / "pg" / "ok.toml", "-o", out)
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in out.glob("*.obj")) == ["frame_0000.obj", "frame_0001.obj", "frame_0002.obj"]
    (out / "mine.obj").write_text("# a user's file\n")
    r = run_cli("petal-grow", "-q", hostile / "pg" / "ok.toml", "--keyframes", "2", "-o", out)
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in out.glob("*.obj")) == ["frame_0000.obj", "frame_0001.obj", "mine.obj"]
    assert not any(p.name.startswith(".staging") for p in out.iterdir())


def test_subdivide_rerun_replaces_its_own_frames_only(hostile):
    """A sequence rerun into the folder of an earlier one: its frames replace the earlier run's
    (a shorter sequence leaves none of the earlier frames behind), a user's file stays, no
    staging folder is left."""
    import shutil

    seq = hostile / "sub"
    shutil.copy(seq / "frame_0000.obj", seq / "frame_0001.obj")
    out = hostile / "subo"
    r = run_cli("subdivide", "-q", seq, "--no-collisions", "-o", out)
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in out.glob("*.obj")) == ["frame_0000.obj", "frame_0001.obj"]
    (out / "mine.obj").write_text("# a user's file\n")
    (seq / "frame_0001.obj").unlink()
    r = run_cli("subdivide", "-q", seq, "--no-collisions", "--levels", "2", "-o", out)
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in out.glob("*.obj")) == ["frame_0000.obj", "mine.obj"]
    assert sum(line.startswith("f ") for line in (out / "frame_0000.obj").read_text().splitlines()) == 32
    assert not any(p.name.startswith(".staging") for p in out.iterdir())


def test_phyllotaxis_rerun_is_whole_or_not_at_all(hostile):
    """A rerun that fails keeps the earlier scene and frames; a complete one replaces them and
    leaves the other files of the folder alone."""
    vogel = REPO / "pipelines" / "examples" / "sweeps" / "vogel.toml"
    out = hostile / "ph"
    r = run_cli("phyllotaxis", "-q", vogel, "-o", out)
    assert r.returncode == 0, r.stderr
    first = (out / "scene.scn").read_bytes()
    (out / "mine.txt").write_text("mine\n")
    r = run_cli("phyllotaxis", "-q", hostile / "tiny.toml", "-o", out)  # refused: a huge primordium count
    assert r.returncode == 2, r.stderr
    assert (out / "scene.scn").read_bytes() == first
    small = hostile / "small.toml"
    small.write_text(vogel.read_text().replace("count = 100", "count = 50"))
    r = run_cli("phyllotaxis", "-q", small, "-o", out)
    assert r.returncode == 0, r.stderr
    assert (out / "scene.scn").read_bytes() != first
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == ["mine.txt", "scene.scn"]
    assert not any(p.name.startswith(".staging") for p in out.iterdir())


FUNC = "fver 1 1\nname: f\nsamples: 100\nflip: off\npoints: 2\n0 0.5\n1 0.5\n"
TRI = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"


@pytest.mark.parametrize("case", ["thyrse", "phyllotaxis", "branch-gen", "render-colors", "render-input",
                                  "export-colors"])
def test_an_output_never_replaces_a_file_the_run_reads(tmp_path, case):
    """A .func a parameter file names, a colour file or an input mesh, named like the output (or
    in the output folder under an output's name): one line, exit 2, the file as it was."""
    if case == "thyrse":
        (tmp_path / "t").mkdir()
        victim = tmp_path / "t" / "scene.scn"
        victim.write_text(FUNC)
        (tmp_path / "t.toml").write_text('[thyrse]\nnodes = 4\nlateral_length = "t/scene.scn"\n')
        args = ["thyrse", "-q", "t.toml", "-o", "t"]
    elif case == "phyllotaxis":
        (tmp_path / "p").mkdir()
        victim = tmp_path / "p" / "scene.scn"
        victim.write_text(FUNC.replace("0.5", "0.003"))
        (tmp_path / "p.toml").write_text('[surface]\ncurve = "disk"\n[primordia]\narea = "p/scene.scn"\ncount = 100\n')
        args = ["phyllotaxis", "-q", "p.toml", "-o", "p"]
    elif case == "branch-gen":
        (tmp_path / "b").mkdir()
        victim = tmp_path / "b" / "branches.obj"
        victim.write_text(FUNC)
        (tmp_path / "b.toml").write_text('[rodkaew]\nw_b_func = "b/branches.obj"\n')
        args = ["branch-gen", "-q", REPO / "pipelines" / "examples" / "branch_gen" / "corymb.scn", "b.toml", "-o", "b"]
    elif case == "render-colors":
        (tmp_path / "m.obj").write_text(TRI)
        victim = tmp_path / "col.png"
        victim.write_text("0 = [1, 0, 0]\n")
        args = ["canopy-render", "-q", "m.obj", "--colors", "col.png", "-o", "col.png"]
    elif case == "render-input":
        victim = tmp_path / "m.png"
        victim.write_text(TRI)
        args = ["canopy-render", "-q", "m.png", "-o", "m.png"]
    else:
        (tmp_path / "s").mkdir()
        (tmp_path / "s" / "frame_0000.obj").write_text(TRI)
        victim = tmp_path / "c.usda"
        victim.write_text("0 = [1, 0, 0]\n")
        args = ["canopy-export", "-q", "s", "--colors", "c.usda", "-o", "c.usda"]
    before = victim.read_bytes()
    r = run_cli(args[0], *args[1:], cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert "expected an output that is no input" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert victim.read_bytes() == before


@pytest.mark.parametrize("args", [
    ["fccompose", REPO / "pipelines" / "examples" / "fccompose" / "dense.fcc", "--frames", "100000000000", "-o", "{d}/o"],
    ["floret-animate", REPO / "pipelines" / "examples" / "disk_bud.floret",
     REPO / "pipelines" / "examples" / "disk_open.floret", "--frames", "100000000000", "-o", "{d}/o"],
    ["dimorph", "sweep", "--n-max", "1000000000000", "-o", "{d}/o"],
    ["dimorph", "sweep", "--alpha-step", "1e-300", "-o", "{d}/o"],
])
def test_counts_asking_for_more_memory_than_a_machine_has_are_refused(tmp_path, args):
    """Frame and sweep counts of 1e11 and more (a MemoryError, exit 1, before): exit 2, nothing written."""
    r = run_cli(args[0], *[str(a).format(d=tmp_path) for a in args[1:]])
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr and "MemoryError" not in r.stderr
    assert not (tmp_path / "o").exists()


def test_a_memory_error_is_one_line_and_exit_2(monkeypatch):
    """The CLI layer's net for a count no bound caught: one line naming the cause, exit 2."""
    import click
    from click.testing import CliRunner

    from inflo.tools.common.cli import inflo_command

    @inflo_command("greedy")
    @click.option("-o", "--output", default=None)
    def greedy(output, quiet, debug):
        raise MemoryError

    r = CliRunner().invoke(greedy, [])
    assert r.exit_code == 2
    assert r.output.strip() == ("greedy: error: expected input whose work fits in memory, found more than this "
                                "machine can allocate (a count or size too large)")
