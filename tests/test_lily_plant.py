"""The lily and Eustoma plants (pipelines/lily/plant.py, pipelines/eustoma/plant.py, inflo.tools.plant;
`make lily-plant`, `make eustoma-plant`; Ijiri et al. fig. 15).

From the draft lily build of the session (conftest's ``species_build``, shared with the golden-file
tests; its painted and column keyframes made here if missing), plant.py writes the plant into a
temporary folder (about 6 s), and:

- at the last frame five flowers show at least three distinct stages (bud, opening, open), the
  lowest the oldest, each flower's frames the built lily's frame clamp(f - offset), moved rigidly;
- the stem, 34 leaves and five pedicels are in ``body.obj``, the stem from the ground up, every
  leaf 5-10 units long;
- no intersecting triangle pair (exact test, the joined parts excepted: check_plant.py) at plant
  frames 1, 50, 80 and 100 and at the contact sheet's last frame;
- the classification of check_plant.py is not vacuous: leaves and pedicels do reach into the stem
  (pairs it excepts), and a flower moved onto another is caught;
- canopy-export writes the USD with the six parts over 100 frames;
- the Eustoma plant (pipelines/eustoma/plant.py, from the session's eustoma build): five flowers at
  three stages at the last frame, stem, 14 leaves, 5 branches, no intersecting pair at frames 1, 60
  and 100, its USD written.

The whole `plant` target (every frame checked, pictures; about 45 s) is not run here.
"""
from __future__ import annotations

import importlib.util
import shutil
import subprocess
import tomllib

import numpy as np
import pytest
from conftest import REPO, run_cli

from inflo.formats.obj import list_obj_sequence, read_obj

LILY = REPO / "pipelines" / "lily"
BUILD = REPO / "build" / "lily"


def _module(name):
    spec = importlib.util.spec_from_file_location(name, LILY / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def plant(species_build, tmp_path_factory):
    species_build("lily")
    if not (BUILD / "canopy").is_dir():
        pytest.skip("make lily has not been run")
    make = shutil.which("make") or "make"
    r = subprocess.run([make, "-C", str(LILY), "QUALITY=draft", str(BUILD / "painted" / ".done"),
                        str(BUILD / "column_keyframes" / ".done")], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    out = tmp_path_factory.mktemp("lily_plant")
    assert _module("plant").main(BUILD, out) == 0
    return out


def test_flowers_at_distinct_stages(plant):
    lay = tomllib.loads((plant / "plant.toml").read_text())
    mod = _module("plant")
    flowers = lay["flower"]
    assert len(flowers) >= 3
    offsets = [fl["offset"] for fl in flowers]
    assert offsets == sorted(offsets) and offsets[0] == 0          # the lowest the oldest
    assert [fl["node"] for fl in flowers] == sorted(fl["node"] for fl in flowers)
    ages = [mod.age(lay["frames"] - 1, o) for o in offsets]
    stages = {mod.stage(a) for a in ages}
    assert len(stages) >= 3, (ages, stages)
    # a flower's frame is the lily's frame clamp(f - offset), moved rigidly: edge lengths kept
    tep = read_obj(BUILD / "canopy" / "frame_0029.obj")
    k = 3  # flower 4, offset 70: lily frame 30 at plant frame 100
    assert offsets[k] == 70
    m = read_obj(list_obj_sequence(plant / f"flower_{k + 1}")[-1])
    part = np.asarray(m.face_group) == m.groups.index("tepals")
    f_tep = m.faces[part]
    assert np.array_equal(f_tep, tep.faces)
    e = lambda v, f: np.linalg.norm(v[f[:, 0]] - v[f[:, 1]], axis=1)
    assert np.allclose(e(m.vertices, f_tep), e(tep.vertices, tep.faces), atol=3e-6)
    assert len(list_obj_sequence(plant / f"flower_{k + 1}")) == lay["frames"] == 100


def test_body_has_stem_leaves_pedicels(plant):
    body = read_obj(plant / "body.obj")
    g = body.groups
    leaves = [n for n in g if n.startswith("leaf_")]
    assert "stem" in g and len(leaves) == 34 and len([n for n in g if n.startswith("pedicel_")]) == 5
    stem = body.vertices[np.unique(body.faces[np.asarray(body.face_group) == g.index("stem")])]
    assert stem[:, 1].min() == pytest.approx(0.0, abs=0.01) and stem[:, 1].max() > 40
    for name in leaves:
        v = body.vertices[np.unique(body.faces[np.asarray(body.face_group) == g.index(name)])]
        span = np.linalg.norm(v.max(axis=0) - v.min(axis=0))
        assert 4.0 < span < 10.5, (name, span)


def test_no_intersecting_pairs(plant, capsys):
    from inflo.tools.plant.check import main, test_mesh

    assert main(plant, [1, 50, 80, 100]) == 0, capsys.readouterr().out
    lay = tomllib.loads((plant / "plant.toml").read_text())
    body = read_obj(plant / "body.obj")
    t, c = read_obj(plant / "sheet_tepals" / "100.obj"), read_obj(plant / "sheet_columns" / "100.obj")
    bad, found, _ = test_mesh([(body, body.groups), (t, t.groups), (c, c.groups)])
    assert bad == 0, found
    assert lay["sheet"][-1] == 100 and lay["sheet_parts"] == ["sheet_tepals", "sheet_columns"]


def test_check_is_not_vacuous(plant):
    """The joined pairs exist (so the exceptions matter) and a flower moved into another is caught."""
    from inflo.tools.collide import intersecting_pairs
    from inflo.tools.plant.check import joined, test_mesh

    body = read_obj(plant / "body.obj")
    fg = np.asarray(body.face_group)
    pairs = intersecting_pairs(body.vertices, body.faces)
    found = {tuple(sorted((body.groups[fg[a]], body.groups[fg[b]]))) for a, b in pairs}
    assert any(p[0].startswith("leaf_") and p[1] == "stem" for p in found)
    assert any(p[0].startswith("pedicel_") and p[1] == "stem" for p in found)
    assert all(joined(*p) for p in found), found            # and nothing else in the body meets
    assert joined("f2_column", "pedicel_2") and not joined("f2_column", "pedicel_3")
    assert not joined("f1_tepals", "f1_tepals") and not joined("f1_tepals", "pedicel_1")
    m1 = read_obj(list_obj_sequence(plant / "flower_1")[-1])
    m2 = read_obj(list_obj_sequence(plant / "flower_2")[-1])
    shift = m1.vertices[m1.faces].reshape(-1, 3).mean(axis=0) - m2.vertices[m2.faces].reshape(-1, 3).mean(axis=0)
    m2.vertices = m2.vertices + shift + np.array([0.3, 0.2, 0.1])
    parts = [(body, body.groups), (m1, [f"f1_{g}" for g in m1.groups]), (m2, [f"f2_{g}" for g in m2.groups])]
    bad, found, _ = test_mesh(parts)
    assert bad > 0 and any("f1_tepals" in k and "f2_tepals" in k for k in found), found


def test_usd_written(plant, tmp_path):
    parts = [f"flower_{k}={plant / f'flower_{k}'}" for k in range(1, 6)] + [f"body={plant / 'body.obj'}"]
    out = tmp_path / "lily_plant.usdc"
    r = run_cli("canopy-export", "-q", *parts, "--colors", LILY / "plant_colors.toml", "--units", "cm", "-o", out)
    assert r.returncode == 0, r.stderr
    assert out.stat().st_size > 0
    Usd = pytest.importorskip("pxr.Usd")
    stage = Usd.Stage.Open(str(out))
    meshes = {p.GetName() for p in stage.Traverse() if p.GetTypeName() == "Mesh"}
    assert {f"flower_{k}" for k in range(1, 6)} | {"body"} <= meshes
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (1.0, 100.0)


# -- the Eustoma plant (pipelines/eustoma/plant.py, `make eustoma-plant`): the same checks, shorter

EUSTOMA = REPO / "pipelines" / "eustoma"


@pytest.fixture(scope="module")
def eustoma_plant(species_build, tmp_path_factory):
    species_build("eustoma")
    build = REPO / "build" / "eustoma"
    if not (build / "mellow_yellow").is_dir():
        pytest.skip("make eustoma has not been run")
    spec = importlib.util.spec_from_file_location("eustoma_plant", EUSTOMA / "plant.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = tmp_path_factory.mktemp("eustoma_plant")
    assert mod.main(build, out) == 0
    return out


def test_eustoma_plant(eustoma_plant, capsys, tmp_path):
    from inflo.tools.plant import age, stage
    from inflo.tools.plant.check import main

    lay = tomllib.loads((eustoma_plant / "plant.toml").read_text())
    stages = [tuple(s) for s in lay["stages"]]
    ages = [age(99, fl["offset"], 100) for fl in lay["flower"]]
    assert len(lay["flower"]) == 5 and len({stage(a, stages) for a in ages}) >= 3, ages
    body = read_obj(eustoma_plant / "body.obj")
    assert "stem" in body.groups and sum(g.startswith("leaf_") for g in body.groups) == 14
    assert sum(g.startswith("pedicel_") for g in body.groups) == 5
    assert main(eustoma_plant, [1, 60, 100]) == 0, capsys.readouterr().out
    parts = [f"flower_{k}={eustoma_plant / f'flower_{k}'}" for k in range(1, 6)] + [f"body={eustoma_plant / 'body.obj'}"]
    r = run_cli("canopy-export", "-q", *parts, "--colors", EUSTOMA / "plant_colors.toml", "--units", "mm",
                "-o", tmp_path / "eustoma_plant.usdc")
    assert r.returncode == 0 and (tmp_path / "eustoma_plant.usdc").stat().st_size > 0, r.stderr
