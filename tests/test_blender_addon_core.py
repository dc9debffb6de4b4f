"""The Blender add-on's parts that need no Blender (blender/inflo_blender/core.py), run with
inflo's Python in ``make test``; tests/test_blender_addon.py runs the add-on in real Blender.

- the species list (every pipelines/*/species.toml, its title: what inflo's own reader finds),
  a project folder that is not one gets one line;
- the build's steps (make venv, then the species' stages, usd last), its progress lines (tool
  command lines, stall notices, frame files written), the error line of a failed build;
- a build of a toy project run, failed and cancelled (the process group ends, nothing left);
- the colours: canopy-render's rules, copied, give the same colour for every material of every
  species; organ kinds; sRGB to linear as canopy-export;
- the zip (``make blender-addon``'s script): one folder ``inflo_blender/`` with bl_info and a
  manifest that agree, and no module of the add-on imports inflo.
"""
from __future__ import annotations

import ast
import importlib.util
import os
import subprocess
import sys
import time
import tomllib
import zipfile
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

ADDON = REPO / "blender" / "inflo_blender"


def _load(name: str, path: Path):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod  # dataclasses look their module up
    spec.loader.exec_module(mod)
    return mod


core = _load("inflo_blender_core", ADDON / "core.py")
make_zip = _load("inflo_blender_make_zip", REPO / "blender" / "make_zip.py")


def test_species_list_is_inflos():
    from inflo.formats.species import find_species

    found, errors = core.find_species(REPO)
    assert errors == []
    want = {sp.name: sp for sp in find_species(REPO / "pipelines")}
    assert [s.name for s in found] == sorted(want)
    for s in found:
        assert s.title == want[s.name].title
        assert list(s.stages) == list(want[s.name].stages)
        assert s.folder == REPO / "pipelines" / s.name
    assert core.project_error(REPO) is None
    assert core.species_by_name(REPO, "lily").title == "Opening Asiatic lily"


def test_bad_project_folders(tmp_path):
    assert "no project folder" in core.project_error("")
    assert "no such folder" in core.project_error(tmp_path / "nowhere")
    (tmp_path / "f").write_text("x")
    assert "is a file" in core.project_error(tmp_path / "f")
    assert "not an inflo project" in core.project_error(tmp_path)
    (tmp_path / "Makefile").write_text("all:\n")
    (tmp_path / "pipelines" / "bad").mkdir(parents=True)
    (tmp_path / "pipelines" / "bad" / "species.toml").write_text('name = "bad"\ntitle = [\n')
    err = core.project_error(tmp_path)
    assert err.startswith(f"{tmp_path}: no species") and "species.toml" in err and "\n" not in err
    with pytest.raises(ValueError, match="no species"):
        core.species_by_name(tmp_path, "bad")
    (tmp_path / "pipelines" / "bad" / "species.toml").write_text('name = "other"\n')
    assert core.find_species(tmp_path)[1] == [f"{tmp_path}/pipelines/bad/species.toml: expected name = 'bad', "
                                              f"found 'other'"]
    with pytest.raises(ValueError, match="no species 'rose'"):
        core.species_by_name(REPO, "rose")


def test_build_steps():
    lily = core.species_by_name(REPO, "lily")
    steps = core.build_steps(REPO, lily, "draft")
    assert steps[0] == core.Step("venv", ("make", "-C", str(REPO), "--no-print-directory", "venv"))
    assert steps[1].argv[-1] == str(REPO / "build" / "lily" / "quality.txt")
    assert [s.label for s in steps[2:]] == ["frames", "obj", "column", "canopy", "usd"]
    assert steps[-1].argv == ("make", "-C", str(REPO / "pipelines" / "lily"), "--no-print-directory",
                              "QUALITY=draft", "usd")
    assert [s.label for s in core.build_steps(REPO, lily, "final", "all")[2:]] == list(lily.stages)
    with pytest.raises(ValueError, match="draft or final"):
        core.build_steps(REPO, lily, "best")
    # every stage a [usd] part is under is built (its folder), whatever its name
    for sp in core.find_species(REPO)[0]:
        labels = [s.label for s in core.build_steps(REPO, sp, "draft")]
        assert labels[-1] == "usd" and not {"pictures", "check"} & set(labels)
        assert {p.split("/")[0] for p in sp.usd_parts} & set(sp.stages) <= set(labels)
    assert lily.usd_parts == ("canopy", "column_obj")
    env = core.build_env(REPO, {"PATH": "/usr/bin", "PYTHONHOME": "/blender/python", "PYTHONPATH": "x"})
    assert env == {"PATH": f"{REPO}/.venv/bin{os.pathsep}/usr/bin"}


def test_progress_lines(tmp_path):
    p = core.Progress("lily", "draft", n_steps=7)
    p.start_step(4, "canopy")
    assert p.text() == "lily (draft): 5/7 canopy"
    assert not p.feed("make[1]: Entering directory '/x'\n")
    out = tmp_path / "canopy"
    out.mkdir()
    (out / "frame_0000.obj").write_text("")
    os.utime(out / "frame_0000.obj", (0, 0))  # an earlier build's frame: not counted
    assert p.feed(f"/work/.venv/bin/fccompose -q --strict lily.fcc -o {out}\n")
    assert (p.tool, p.output) == ("fccompose", str(out))
    assert p.text() == "lily (draft): 5/7 canopy · fccompose"
    assert not p.poll()
    for k in range(1, 4):
        (out / f"frame_{k:04d}.obj").write_text("")
    (out / ".frame_0004.obj.part").write_text("")
    (out / "log.csv").write_text("")
    assert p.poll() and p.frames == 3 and not p.poll()
    assert p.text() == "lily (draft): 5/7 canopy · fccompose · frame 3"
    assert p.fraction() == pytest.approx(4 / 7)
    # stall notices (tools/common/cli.py), with or without --quiet
    assert p.feed("fccompose: still running, 42 of 100 frames after 90 s\n")
    assert (p.frames, p.of, p.unit) == (42, 100, "frames")
    assert p.text() == "lily (draft): 5/7 canopy · fccompose · frame 42 of 100"
    assert p.fraction() == pytest.approx((4 + 0.42) / 7)
    assert p.feed("venation: still running, 12 of 40 steps done, none in the last 120 s")
    assert (p.tool, p.frames, p.of, p.unit) == ("venation", 12, 40, "steps")
    assert p.feed("/x/.venv/bin/python paint_tepals.py /x/build/lily")
    assert p.tool == "paint_tepals.py" and p.output is None and p.frames is None


def test_error_line():
    assert core.error_line([
        "fccompose: error: lily.fcc:7: expected an integer for 'solver iterations', found 'nonsense'",
        "make: *** [Makefile:58: /x/build/lily/canopy/frame_0099.obj] Error 2",
    ]) == "fccompose: error: lily.fcc:7: expected an integer for 'solver iterations', found 'nonsense'"
    assert core.error_line(["/x/pipelines/species.mk:27: *** species.toml: QUALITY must be draft or final, "
                            "found 'x'.  Stop."]) == "species.toml: QUALITY must be draft or final, found 'x'"
    assert core.error_line(["make: *** No rule to make target 'petals'.  Stop."]) == \
        "make: *** No rule to make target 'petals'.  Stop."
    assert core.error_line([], 2) == "the build failed (exit status 2)"


TOY_SPECIES = 'name = "toy"\ntitle = "A toy"\nfamily = "head"\nstages = ["frames", "check", "usd"]\n'
TOY_MAKEFILE = """\
%/quality.txt:
\t@mkdir -p $(@D) && echo $(QUALITY) > $@
frames:
\t@mkdir -p out && for i in 0 1 2; do touch out/frame_000$$i.obj; done
\tfloret-animate -q a.floret -o out
check:
\t@echo checked
usd:
\t@if [ -f fail ]; then echo 'canopy-export: error: colors.toml:3: expected a colour, found "x"' >&2; exit 2; fi
\t@if [ -f slow ]; then sleep 30 & echo $$! > sleeper.pid; wait; fi
\t@touch done
"""


@pytest.fixture
def toy(tmp_path):
    (tmp_path / "Makefile").write_text("venv:\n\t@true\n")
    sp = tmp_path / "pipelines" / "toy"
    sp.mkdir(parents=True)
    (sp / "species.toml").write_text(TOY_SPECIES)
    (sp / "Makefile").write_text(TOY_MAKEFILE)
    # floret-animate on PATH is the project's .venv/bin's: a stand-in that says nothing
    (tmp_path / ".venv" / "bin").mkdir(parents=True)
    fake = tmp_path / ".venv" / "bin" / "floret-animate"
    fake.write_text("#!/bin/sh\nexit 0\n")
    fake.chmod(0o755)
    return tmp_path, core.species_by_name(tmp_path, "toy")


def test_build_runs_fails_and_cancels(toy):
    project, sp = toy
    lines = []
    b = core.BuildProcess(project, sp, "draft")
    assert [s.label for s in b.steps] == ["venv", "quality", "frames", "usd"]
    assert b.run(lambda stream, line: lines.append((stream, line.rstrip()))) == 0
    assert (sp.folder / "done").is_file() and ("out", "checked") not in lines
    assert (project / "build" / "toy" / "quality.txt").read_text() == "draft\n"
    assert b.progress.stage == "usd"
    # the frames step's tool and its output folder, relative to the species folder make runs in
    p = core.Progress("toy", "draft", n_steps=3)
    p.start_step(1, "frames", str(sp.folder))
    assert p.feed("floret-animate -q a.floret -o out") and p.output == str(sp.folder / "out")

    (sp.folder / "fail").write_text("")
    b = core.BuildProcess(project, sp, "draft", "all")
    assert b.run() == 2
    assert b.progress.stage == "usd" and b.error() == 'canopy-export: error: colors.toml:3: expected a colour, found "x"'
    (sp.folder / "fail").unlink()

    (sp.folder / "slow").write_text("")
    b = core.BuildProcess(project, sp, "draft")
    b.start()
    t0 = time.monotonic()
    while not (sp.folder / "sleeper.pid").is_file() and time.monotonic() - t0 < 20:
        b.pump()
        time.sleep(0.05)
    pid = int((sp.folder / "sleeper.pid").read_text())
    b.cancel()
    assert b.done and b.cancelled and b.returncode != 0
    assert time.monotonic() - t0 < 15
    # the whole process group ended: make and the sleep it started
    time.sleep(0.2)
    stat = Path(f"/proc/{pid}/stat")
    assert not stat.exists() or stat.read_text().split(")")[-1].split()[0] in ("Z", "X"), "sleep left running"
    assert b.proc.poll() is not None


def test_colors_are_canopy_renders():
    from inflo.tools.canopy_export.usd import srgb_to_linear
    from inflo.tools.canopy_render.colors import load_color_file, material_color

    for path in sorted((REPO / "pipelines").glob("*/colors.toml")):
        colors, comments = core.load_colors(path)
        want = load_color_file(path)
        assert colors == want, path
        names = [f"mtl{k}" if k.isdigit() else k for k in want] + ["mtl17", "petal_default", "stem", "Brown", "x y"]
        for name in names:
            assert core.material_color(name, colors) == material_color(name, want), (path, name)
            np.testing.assert_allclose(core.srgb_to_linear(core.material_color(name, colors)),
                                       srgb_to_linear(material_color(name, want)), rtol=1e-12)
        assert set(comments) <= set(colors), path
    colors, comments = core.load_colors(REPO / "pipelines" / "lily" / "colors.toml")
    kinds = {f"mtl{k}": core.organ_kind(f"mtl{k}", core.material_comment(f"mtl{k}", comments)) for k in colors}
    assert kinds == {"mtl3": "petal", "mtl4": "petal", "mtl5": "reproductive", "mtl6": "reproductive",
                     "mtl7": "stem", "mtl8": "reproductive", "mtl9": "reproductive"}
    _, comments = core.load_colors(REPO / "pipelines" / "gaillardia" / "colors.toml")
    assert [core.organ_kind(f"mtl{k}", core.material_comment(f"mtl{k}", comments)) for k in range(7)] == \
        ["petal", "petal", "reproductive", "reproductive", "leaf", "stem", "petal"]
    _, comments = core.load_colors(REPO / "pipelines" / "eustoma" / "colors.toml")
    assert core.organ_kind("maite_lady", core.material_comment("maite_lady", comments)) == "petal"
    assert core.organ_kind("mtl10", core.material_comment("mtl10", comments)) == "stem"
    assert core.load_colors(REPO / "pipelines" / "nowhere.toml") == ({}, {})


def test_bad_colors_file(tmp_path):
    (tmp_path / "c.toml").write_text('3 = [0.9, 0.8]\n')
    with pytest.raises(ValueError, match=r"c.toml: key '3': expected r,g,b"):
        core.load_colors(tmp_path / "c.toml")
    (tmp_path / "c.toml").write_text('3 = [0.9, \n')
    with pytest.raises(ValueError, match=r"c.toml: "):
        core.load_colors(tmp_path / "c.toml")


def _bl_info(path: Path) -> dict:
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "bl_info" for t in node.targets):
            return ast.literal_eval(node.value)
    raise AssertionError("no bl_info")


def test_zip_and_manifest(tmp_path):
    out = tmp_path / "inflo_blender.zip"
    names = make_zip.write_zip(out)
    with zipfile.ZipFile(out) as zf:
        assert sorted(zf.namelist()) == sorted(names)
        assert {"inflo_blender/__init__.py", "inflo_blender/core.py",
                "inflo_blender/blender_manifest.toml"} <= set(names)
        assert not any("__pycache__" in n or n.endswith(".pyc") for n in names)
        manifest = tomllib.loads(zf.read("inflo_blender/blender_manifest.toml").decode())
    again = tmp_path / "again.zip"
    make_zip.write_zip(again)
    assert again.read_bytes() == out.read_bytes()
    info = _bl_info(ADDON / "__init__.py")
    assert manifest["id"] == "inflo_blender" and manifest["type"] == "add-on"
    assert manifest["version"] == ".".join(map(str, info["version"]))
    assert manifest["blender_version_min"] == ".".join(map(str, info["blender"]))
    assert info["blender"] == (4, 2, 0)


def test_addon_imports_no_inflo():
    """The add-on runs in Blender's Python: nothing of inflo (nor numpy at module level)."""
    for path in sorted(ADDON.glob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            mods = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""] if isinstance(node, ast.ImportFrom) and node.level == 0 else []
            for m in mods:
                assert not m.startswith("inflo"), f"{path.name} imports {m}"
        for node in tree.body:
            if isinstance(node, ast.Import) or (isinstance(node, ast.ImportFrom) and node.level == 0):
                names = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module]
                assert not any(n.split(".")[0] in ("numpy", "scipy", "trimesh") for n in names), path.name


def test_make_blender_addon_target(tmp_path):
    """``make blender-addon`` writes build/inflo_blender.zip (dry run: the rule, not the file)."""
    r = subprocess.run(["make", "-n", "-B", "-C", str(REPO), "blender-addon"], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 0, r.stderr
    assert "blender/make_zip.py -o build/inflo_blender.zip" in r.stdout



def test_panel_diagram(tmp_path):
    """blender/draw_panel.py: the panel's draw() with a stand-in bpy records the panel's rows in
    order (project, species with its title, quality as toggles, build scope, Build, Import build,
    the build's state); a folder that is no project gets the error box; the diagram is a PNG."""
    draw_panel = _load("draw_panel", REPO / "blender" / "draw_panel.py")
    tree = draw_panel.record(REPO, "lily", "final")
    assert [(i["type"], i.get("name") or i.get("text")) for i in tree[:2]] == [("prop", "project"), ("prop", "species")]
    assert dict(tree[1]["items"]) == {s.name: s.title for s in core.find_species(REPO)[0]}
    quality = tree[2]["items"][0]
    assert (tree[2]["type"], quality["name"], quality["expand"], quality["value"]) == ("row", "quality", True, "final")
    assert tree[3]["name"] == "scope" and tree[4]["text"] == "Build" and tree[4]["icon"] == "PLAY"
    assert tree[5]["items"][0]["text"] == "Import build"
    assert tree[6]["type"] == "label" and ("built:" in tree[6]["text"] or "not built yet" in tree[6]["text"])
    bad = draw_panel.record(tmp_path, "lily")
    assert [i["type"] for i in bad] == ["prop", "box"] and bad[1]["items"][0]["icon"] == "ERROR"
    out = tmp_path / "panel.png"
    draw_panel.draw(tree, out)
    from PIL import Image

    with Image.open(out) as im:
        assert im.width == 660 and im.height > 400
