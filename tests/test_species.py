"""A species is data (formats/species.md): every species folder has a valid species.toml that its
Makefile, the tests, the Blender test and ``make bench`` read; the reader refuses malformed files
with one line; the make variables are what the Makefiles used to spell out."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from conftest import REPO, file_digests, project_copy

from inflo.formats.errors import FormatError, InputError
from inflo.formats.species import find_species, make_variables, read_species

PIPELINES = REPO / "pipelines"
SPECIES = [p.parent.name for p in sorted(PIPELINES.glob("*/Makefile")) if p.parent.name != "examples"]
WITHOUT_USD = {}


def test_every_species_folder_has_a_species_file():
    assert len(SPECIES) >= 10
    assert [s.name for s in find_species(PIPELINES)] == SPECIES


@pytest.mark.parametrize("name", SPECIES)
def test_species_has_its_goldens_bench_row_and_usd_stage(name):
    sp = read_species(PIPELINES / name / "species.toml")
    assert sp.title and sp.family and sp.stages
    assert (REPO / "tests" / "golden" / name / "manifest.toml").is_file()
    assert sp.bench and sp.bench["anchor_value"] > 0
    if name in WITHOUT_USD:
        assert "usd" not in sp.stages, f"{name} has a USD stage now: drop it from WITHOUT_USD"
    else:
        assert "usd" in sp.stages and sp.usd_parts
    makefile = (PIPELINES / name / "Makefile").read_text()
    assert "include $(ROOT)/pipelines/species.mk" in makefile and "include $(ROOT)/pipelines/common.mk" in makefile
    assert "ifeq ($(QUALITY)" not in makefile, "quality settings belong in species.toml"
    assert sorted(sp.settings["draft"]) == sorted(sp.settings["final"])
    # every stage is a target (make -n knows how to make it)
    res = subprocess.run(["make", "-n", "-C", str(PIPELINES / name), "QUALITY=draft", *sp.stages],
                         capture_output=True, text=True)
    assert res.returncode == 0, res.stderr[-2000:]


def test_make_species_lists_every_species():
    res = subprocess.run([sys.executable, "-m", "inflo.tools.species", "list"], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert [ln.split()[0] for ln in lines] == SPECIES
    assert any("Sunflower (thesis figs. 9.5, 9.6); head; make sunflower" in ln for ln in lines)


GOOD = """\
name = "daisy"
title = "Oxeye daisy"
figures = ["9.5"]
family = "head"
stages = ["frames", "canopy", "usd"]
[usd]
parts = { florets = "canopy", receptacle = "head/receptacle" }
[bench]
anchor = "thesis table 4.1: 10 min"
anchor_value = 10
[settings]
alpha = 53
[draft]
template_frames = 30
ray_scale = 1.4
still_size = "900x700"
sheet = [1, 6, 12]
[final]
template_frames = 60
ray_scale = 2.6
still_size = "1400x1100"
sheet = [1, 12, 24]
"""


def _file(tmp_path, text, name="daisy") -> Path:
    path = tmp_path / name / "species.toml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def test_make_variables(tmp_path):
    sp = read_species(_file(tmp_path, GOOD))
    assert sp.setting("final", "RAY_SCALE") == 2.6 and sp.setting("draft", "alpha") == 53
    text = make_variables(sp, "draft")
    assert "\nALPHA := 53\nTEMPLATE_FRAMES := 30\nRAY_SCALE := 1.4\nSTILL_SIZE := 900x700\nSHEET := 1,6,12\n" in text
    assert "USD_PARTS := florets=$(B)/canopy receptacle=$(B)/head/receptacle\n" in text
    with pytest.raises(InputError, match="QUALITY must be draft or final, found 'best'"):
        make_variables(sp, "best")


@pytest.mark.parametrize("change, line, match", [
    (('name = "daisy"', 'name = "Daisy"'), 1, "lower-case name"),
    (('name = "daisy"', 'name = "aster"'), 1, "the folder's name 'daisy'"),
    (('family = "head"', 'family = "umbel"'), 4, "one of head, compound"),
    (('"canopy", "usd"]', '"canopy", "usd", "bake"]'), 5, "stage names"),
    (('ray_scale = 1.4\n', 'ray_scale = true\n'), 15, "a number, a string or a list"),
    (('ray_scale = 2.6\n', ''), 15, "the same settings in \\[draft\\] and \\[final\\]"),
    (('[settings]\nalpha = 53', '[settings]\nray_scale = 53'), 12, "not both"),
    (('anchor_value = 10', 'anchor_value = "ten"'), 10, "\\[bench\\] keys"),
    (('title = "Oxeye daisy"', 'title = "Oxeye daisy"\ncolour = "white"'), 3, "one of the keys"),
    (('[usd]\nparts = { florets = "canopy", receptacle = "head/receptacle" }\n', ''), 5, "\\[usd\\] parts"),
    (('template_frames = 30', 'template_frames = 30 30'), 14, "TOML"),
])
def test_malformed_species_files_get_one_line(tmp_path, change, line, match):
    path = _file(tmp_path, GOOD.replace(*change))
    with pytest.raises(FormatError, match=match) as exc:
        read_species(path)
    assert exc.value.line == line, str(exc.value)
    assert "\n" not in str(exc.value)


def test_species_makefile_stops_on_a_bad_quality_or_file(tmp_path):
    res = subprocess.run(["make", "-n", "-C", str(PIPELINES / "gaillardia"), "QUALITY=best"], capture_output=True,
                         text=True)
    assert res.returncode != 0 and "QUALITY must be draft or final, found 'best'" in res.stderr


# -- make new-species ------------------------------------------------------------------------------


def test_scaffold_refuses_bad_names(tmp_path):
    from inflo.tools.species.scaffold import scaffold

    root = project_copy(tmp_path / "repo", goldens=True)
    with pytest.raises(InputError, match="lower-case name"):
        scaffold(root, "Daisy2", "sunflower")
    with pytest.raises(InputError, match="exists already"):
        scaffold(root, "lily", "sunflower")
    with pytest.raises(InputError, match="expected a species .*sunflower.*, found 'aster'"):
        scaffold(root, "daisy2", "aster")
    assert not list((root / "pipelines").glob(".*.tmp"))


@pytest.mark.slow
@pytest.mark.skipif(not (REPO / ".venv" / "bin" / "fccompose").exists(), reason="needs the .venv (make test)")
def test_a_scaffolded_species_builds_and_checks(tmp_path):
    """make new-species NAME=aster FROM=daisy in a copy of the project: a folder of its own (and a
    golden manifest), the daisy untouched, and `make aster` at draft quality builds the canopy,
    passes the shared head check and writes its USD file."""
    root = project_copy(tmp_path / "repo", goldens=True)
    before = file_digests(root / "pipelines" / "daisy")
    res = subprocess.run([sys.executable, "-m", "inflo.tools.species", "new", "aster", "--from", "daisy", "--title",
                          "New England aster", "--repo", str(root)], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert file_digests(root / "pipelines" / "daisy") == before
    sp = read_species(root / "pipelines" / "aster" / "species.toml")
    assert (sp.name, sp.title) == ("aster", "New England aster")
    assert (root / "pipelines" / "aster" / "aster.fcc").is_file() and not (root / "pipelines" / "aster" / "daisy.fcc").exists()
    assert "../../build/aster/" in (root / "pipelines" / "aster" / "aster.fcc").read_text()
    assert (root / "tests" / "golden" / "aster" / "manifest.toml").is_file()
    res = subprocess.run(["make", "-s", "-C", str(root / "pipelines" / "aster"), "QUALITY=draft", "check", "usd"],
                         capture_output=True, text=True)
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    build = root / "build" / "aster"
    assert (build / "check.txt").read_text().rstrip().endswith("OK")
    assert "ray florets: 21 (expected 21)" in (build / "check.txt").read_text()
    assert (build / "aster.usdc").stat().st_size > 0
    assert not (REPO / "build" / "aster").exists() and not (REPO / "pipelines" / "aster").exists()
