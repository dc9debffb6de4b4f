"""The inflo Blender add-on (blender/inflo_blender/, ``make blender-addon``) in real Blender 4.5
(or 4.2: ``INFLO_BLENDER_PYTHON``, docs/blender.md).

Marked ``blender`` like tests/test_blender.py and skipped where no Python with bpy is found
(``make test-blender`` makes ``.venv-blender/``; CI's ``make test`` does not). Each test runs
tests/blender_addon_probe.py with that Python, which installs and enables
build/inflo_blender.zip in a scratch user folder as Edit > Preferences > Add-ons > Install does,
drives the operators and reports; the Blender-free parts are tests/test_blender_addon_core.py.

- ``inflo.import_build`` of the draft lily, twice (the second replaces the first: the same
  objects, materials, cache files): one collection, each part a mesh with a Mesh Sequence Cache
  on the USD file, the frame range and fps of the file, Principled BSDF materials whose base
  colour is the species' colour (linear), petals translucent with subsurface, smooth polygons in
  every checked frame, a camera that sees every vertex from the first frame to the last and three
  lights; a 4-sample Cycles render of the last frame whose silhouette matches canopy-render's
  still through the same camera; the panel's species list with every species' title.
- The same for a head (the draft gaillardia, where built): florets and receptacle, their colours.
- A toy build exported at 30 fps with faces of no material: the scene's fps is the file's.
- ``inflo.build`` of the draft lily from scratch in a scratch project (background mode: it runs
  to the end, then imports), and again with a broken input: one error line, the fccompose line
  of the build's stderr, no traceback, and the earlier build's frames untouched.
- A bad project folder, an unknown species, a folder that is no build: a report, never a traceback.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, run_cli, silhouette_iou
from test_blender import _frame, blender_python, make_usd

from inflo.formats.obj import list_obj_sequence, read_obj

pytestmark = pytest.mark.blender

PROBE = REPO / "tests" / "blender_addon_probe.py"


@pytest.fixture(scope="module")
def bpy_python():
    exe = blender_python()
    if exe is None:
        pytest.skip("no Python with bpy (make test-blender installs Blender 4.5 into .venv-blender)")
    return exe


@pytest.fixture(scope="module")
def addon_zip():
    r = subprocess.run(["make", "-s", "-C", str(REPO), "blender-addon"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    return REPO / "build" / "inflo_blender.zip"


def probe(exe, zip_path, tmp_path, *args, name="report") -> tuple[dict, subprocess.CompletedProcess]:
    user = tmp_path / f"{name}-user"
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(user / "scripts"), BLENDER_USER_CONFIG=str(user / "config"))
    out = tmp_path / f"{name}.json"
    r = subprocess.run([exe, str(PROBE), "--zip", str(zip_path), "-o", str(out), *map(str, args)],
                       capture_output=True, text=True, timeout=900, env=env)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    report = json.loads(out.read_text())
    assert report["install"]["result"] == ["FINISHED"] and report["enable"]["result"] == ["FINISHED"], report
    assert report["registered"] == {"operators": ["INFLO_OT_build", "INFLO_OT_import_build"], "panel": True,
                                    "scene_settings": True}
    assert "Traceback" not in r.stdout + r.stderr, (r.stdout + r.stderr)[-3000:]
    return report, r


def srgb_linear(rgb):
    from inflo.tools.canopy_export.usd import srgb_to_linear

    return srgb_to_linear(rgb)


def check_import(rep: dict, species: str, parts: dict, colors: dict, frames: int, usd=None) -> dict:
    """What every import must give (module docstring); returns the scene report."""
    from inflo.tools.canopy_render.colors import material_color

    assert rep.get("result") == ["FINISHED"], rep.get("error")
    scene = rep["scene"]
    assert (scene["frame_start"], scene["frame_end"]) == (1, frames)
    objs = scene["objects"]
    meshes = {n: o for n, o in objs.items() if o["type"] == "MESH"}
    assert sorted(meshes) == sorted(parts), sorted(objs)
    assert {o["collection"] for o in objs.values()} == {f"inflo {species}"}
    for name, o in meshes.items():
        (mod,) = o["modifiers"]
        assert mod["type"] == "MESH_SEQUENCE_CACHE" and mod["object_path"].endswith(f"/{name}")
        if usd:
            assert mod["cache"] == str(usd)
        assert o["materials"], name
        for m in o["materials"]:
            assert "BSDF_PRINCIPLED" in m["nodes"] and m["name"] == f"{species} {m['usd']}"
            if not m["usd"].endswith("_default"):
                want = srgb_linear(material_color(m["usd"], colors))
                np.testing.assert_allclose(m["base_color"], want, atol=1e-6, err_msg=f"{name}: {m['usd']}")
                np.testing.assert_allclose(m["diffuse_color"], want, atol=1e-6)
            if m["organ"] == "petal":
                assert m["surface"] == "MIX_SHADER" and "BSDF_TRANSLUCENT" in m["nodes"] and m["subsurface"] > 0
        for f, fr in o["frames"].items():
            assert fr["smooth"], f"{name} frame {f}: flat polygons"
            assert fr["seen"]["share"] == 1.0, f"{name} frame {f}: the camera misses part of it ({fr['seen']})"
    cam = scene["camera"]
    assert cam is not None and cam["rig"] and cam["sensor_fit"] == "VERTICAL"
    assert len(scene["lights"]) == 3
    # framed, not lost in the picture: the last frame spans most of the view one way or the other
    last = [o["frames"][str(frames)]["seen"] for o in meshes.values()]
    xs = [min(s["x"][0] for s in last), max(s["x"][1] for s in last)]
    ys = [min(s["y"][0] for s in last), max(s["y"][1] for s in last)]
    assert max(xs[1] - xs[0], ys[1] - ys[0]) > 0.6, (xs, ys)
    return scene


def blender_camera_in_file(scene: dict, root: list) -> dict:
    """The add-on's camera in the USD file's own coordinates (canopy-render's Camera numbers)."""
    m = np.array(scene["camera"]["matrix_world"])
    inv = np.linalg.inv(np.array(root))
    eye_w = m[:3, 3]
    fwd_w, up_w = -m[:3, 2], m[:3, 1]
    dist = scene["camera"]["focus_distance"]
    eye = inv @ np.append(eye_w, 1.0)
    target = inv @ np.append(eye_w + fwd_w * dist, 1.0)
    up = inv[:3, :3] @ up_w
    return {"eye": tuple(eye[:3]), "target": tuple(target[:3]), "up": tuple(up / np.linalg.norm(up)),
            "fov": float(np.degrees(scene["camera"]["angle_y"]))}


def test_addon_imports_the_lily(bpy_python, addon_zip, tmp_path):
    from inflo.tools.canopy_render.camera import Camera
    from inflo.tools.canopy_render.colors import load_color_file
    from inflo.tools.canopy_render.render import GLUnavailable, RenderOptions, render_meshes

    build = make_usd("lily")
    png = tmp_path / "cycles.png"
    report, _ = probe(bpy_python, addon_zip, tmp_path, "--import", build, "--import", build, "--project", REPO,
                      "--render", png, "--size", "240x180", "--samples", "4")
    assert report["blender"].startswith(("4.2", "4.5")) and report["background"]
    from inflo.formats.species import find_species

    assert report["species_items"] == [[sp.name, sp.title] for sp in sorted(find_species(REPO / "pipelines"),
                                                                          key=lambda s: s.name)]
    colors = load_color_file(REPO / "pipelines" / "lily" / "colors.toml")
    first, second = report["imports"]
    parts = {"tepals": list_obj_sequence(build / "canopy"), "column": list_obj_sequence(build / "column_obj")}
    for rep in (first, second):
        scene = check_import(rep, "lily", parts, colors, 100, build / "lily.usdc")
        assert scene["fps"] == 24.0
    # importing again replaced the first import: the same data, no ".001" copies
    assert first["scene"]["counts"] == second["scene"]["counts"]
    assert sorted(second["scene"]["objects"]) == ["Materials", "column", "lily", "tepals"]
    assert second["scene"]["collections"] == ["inflo lily", "inflo rig"]
    organs = {m["usd"]: m["organ"] for o in second["scene"]["objects"].values() for m in o["materials"]}
    assert organs == {"mtl3": "petal", "mtl4": "petal", "mtl5": "reproductive", "mtl6": "reproductive",
                      "mtl7": "stem", "mtl8": "reproductive", "mtl9": "reproductive"}
    objs = second["scene"]["objects"]
    # animated: the tepals open between the first frame and the last
    assert objs["tepals"]["frames"]["1"]["bbox"] != objs["tepals"]["frames"]["100"]["bbox"]
    assert objs["tepals"]["frames"]["100"]["vertices"] == read_obj(parts["tepals"][-1]).n_vertices

    # the silhouette of the Cycles render against canopy-render's still through the same camera
    from PIL import Image

    assert report["render"]["seconds"] < 120
    cam = Camera(**blender_camera_in_file(second["scene"], objs["tepals"]["matrix_world"]))
    try:
        still = render_meshes([read_obj(p[-1]) for p in parts.values()], cam,
                              RenderOptions(size=(240, 180), material_colors=colors))
    except GLUnavailable as exc:
        pytest.skip(f"Blender part passed; no headless OpenGL for canopy-render's still ({exc})")
    Image.fromarray(still).save(tmp_path / "still.png")
    iou, share = silhouette_iou(png, still)
    assert share > 0.1, "Blender drew (almost) nothing"
    assert iou > 0.85, f"silhouettes differ: intersection over union {iou:.3f}"


def test_addon_imports_a_head(bpy_python, addon_zip, tmp_path):
    from inflo.tools.canopy_render.colors import load_color_file

    build = REPO / "build" / "gaillardia"
    if not (build / "gaillardia.usdc").is_file():
        pytest.skip("build/gaillardia not built (make gaillardia)")
    # not rebuilt here (minutes, and others may be building it): the USD as it is, its frame count
    # checked against the canopy's frames where the USD is newer than all of them
    report, _ = probe(bpy_python, addon_zip, tmp_path, "--import", build)
    canopy = list_obj_sequence(build / "canopy")
    current = canopy and max(p.stat().st_mtime for p in canopy) <= (build / "gaillardia.usdc").stat().st_mtime
    colors = load_color_file(REPO / "pipelines" / "gaillardia" / "colors.toml")
    (rep,) = report["imports"]
    check_import(rep, "gaillardia", {"florets": 0, "receptacle": 0}, colors,
                 len(canopy) if current else rep["scene"]["frame_end"], build / "gaillardia.usdc")
    assert rep["scene"]["frame_end"] > 1
    organs = {m["usd"]: m["organ"] for o in rep["scene"]["objects"].values() for m in o["materials"]}
    assert organs["mtl6"] == "petal" and organs["mtl4"] == "leaf" and organs["mtl2"] == "reproductive"


def scratch_project(tmp_path: Path, species: str = "lily") -> Path:
    """A project folder whose Makefile, sources and .venv are this repository's (links) and whose
    pipelines/<species> is a copy: a build there writes tmp/build/<species>, not the repository's."""
    proj = tmp_path / "project"
    (proj / "pipelines").mkdir(parents=True)
    for name in ("Makefile", "pyproject.toml", "tools", "formats", ".venv"):
        (proj / name).symlink_to(REPO / name)
    for mk in (REPO / "pipelines").glob("*.mk"):
        (proj / "pipelines" / mk.name).symlink_to(mk)
    shutil.copytree(REPO / "pipelines" / species, proj / "pipelines" / species, ignore=shutil.ignore_patterns("docs"))
    return proj


def test_addon_fps_of_the_file(bpy_python, addon_zip, tmp_path):
    """A toy build at 30 fps (canopy-export --fps 30), with faces of no material."""
    proj = tmp_path / "toy"
    (proj / "pipelines" / "toy").mkdir(parents=True)
    (proj / ".venv").symlink_to(REPO / ".venv")
    (proj / "pipelines" / "toy" / "colors.toml").write_text('3 = [0.5, 0.25, 1.0]   # ray floret ligule\n'
                                                            'mtl4 = "#ff8000"   # involucral bract\n')
    seq = proj / "build" / "toy" / "canopy"
    seq.mkdir(parents=True)
    for k in range(4):
        (seq / f"frame_{k:04d}.obj").write_text(_frame(k))
    r = run_cli("canopy-export", "-q", seq, "--colors", proj / "pipelines" / "toy" / "colors.toml", "--fps", "30",
                "-o", proj / "build" / "toy" / "toy.usdc")
    assert r.returncode == 0, r.stderr
    from inflo.tools.canopy_render.colors import load_color_file

    report, _ = probe(bpy_python, addon_zip, tmp_path, "--import", proj / "build" / "toy")
    (rep,) = report["imports"]
    scene = check_import(rep, "toy", {"canopy": list_obj_sequence(seq)},
                         load_color_file(proj / "pipelines" / "toy" / "colors.toml"), 4)
    assert scene["fps"] == 30.0
    organs = {m["usd"]: m["organ"] for m in scene["objects"]["canopy"]["materials"]}
    assert organs == {"canopy_default": "petal", "mtl3": "petal", "mtl4": "leaf"}


def test_addon_builds_in_background(bpy_python, addon_zip, tmp_path):
    from inflo.tools.canopy_render.colors import load_color_file

    proj = scratch_project(tmp_path)
    report, r = probe(bpy_python, addon_zip, tmp_path, "--build", "lily", "--project", proj, name="build")
    rep = report["build"]
    build = proj / "build" / "lily"
    assert (build / "lily.usdc").is_file() and (build / "quality.txt").read_text().strip() == "draft"
    assert not (build / "lily_sheet.png").exists(), "a Blender build makes no canopy-render pictures"
    parts = {"tepals": list_obj_sequence(build / "canopy"), "column": list_obj_sequence(build / "column_obj")}
    check_import(rep, "lily", parts, load_color_file(proj / "pipelines" / "lily" / "colors.toml"), 100,
                 build / "lily.usdc")
    assert "inflo: lily (draft): 6/7 canopy · fccompose" in r.stdout, r.stdout[-2000:]
    assert "inflo: built lily (draft)" in r.stdout
    print(f"draft lily built and imported in {rep['seconds']:.1f} s")

    # a broken input: the build stops at the canopy with fccompose's one line, the frames stay
    canopy = sorted(p.stat().st_mtime_ns for p in (build / "canopy").iterdir())
    fcc = proj / "pipelines" / "lily" / "lily.fcc"
    fcc.write_text(fcc.read_text().replace("solver iterations:", "solver iterations: nonsense #", 1))
    report, r = probe(bpy_python, addon_zip, tmp_path, "--build", "lily", "--project", proj, name="broken")
    err = report["build"]["error"].strip()
    assert err.startswith("Error: inflo: lily failed at canopy: fccompose: error: lily.fcc:")
    assert "\n" not in err and "nonsense" in err
    assert sorted(p.stat().st_mtime_ns for p in (build / "canopy").iterdir()) == canopy


def test_addon_bad_folders(bpy_python, addon_zip, tmp_path):
    (tmp_path / "empty").mkdir()
    (tmp_path / "build" / "lily").mkdir(parents=True)
    report, r = probe(bpy_python, addon_zip, tmp_path,
                      "--bad-build", tmp_path / "empty", "lily", "--bad-build", tmp_path / "nowhere", "lily",
                      "--bad-build", REPO, "rose", "--bad-build", "", "lily",
                      "--bad-import", tmp_path / "nowhere", "--bad-import", tmp_path / "build" / "lily")
    errors = [b.get("error", "").strip() for b in report["bad"]]
    assert all(e.startswith("Error: ") and "\n" not in e for e in errors), errors
    assert "not an inflo project" in errors[0]
    assert "no such folder" in errors[1]
    assert "no species 'rose'" in errors[2]
    assert "not an inflo project" in errors[3] or "no project folder" in errors[3]
    assert "no such build folder" in errors[4]
    assert "no lily.usdc" in errors[5]
