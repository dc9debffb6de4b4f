"""Golden stage outputs: every species with ``tests/golden/<species>/manifest.toml`` is
built at draft quality (``make -C pipelines/<species> QUALITY=draft <targets>``, once per session,
incremental) and each golden file is compared with the build by the tolerance-aware diff of
``inflo.tools.golden`` (structure exact, coordinates within 1e-5 x scene size, timings
ignored; tests/golden/README.md). A failure prints the diff's report; after an intended change:

    .venv/bin/python -m inflo.tools.golden refresh SPECIES

``INFLO_GOLDEN_REBUILD=1`` makes the session build use ``make -B`` (make does not see changes of
the tools' code), ``INFLO_GOLDEN_NO_BUILD=1`` compares build/<species> as it is.

The first part tests the diff itself on small synthetic files: a vertex moved beyond the
tolerance fails and within it passes, a changed face / group / material / id / type fails, a
missing or extra frame fails, CSV timing columns are ignored and counts are exact.
"""
from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO

from inflo.formats.floret import read_floret, write_floret
from inflo.formats.rba import RbaFrame, write_rba
from inflo.formats.scn import Placement, Scene, write_scn
from inflo.tools import golden as G

TOL = G.Tolerance()

# --------------------------------------------------------------------------------------------------
# The diff on synthetic files
# --------------------------------------------------------------------------------------------------

OBJ = """\
# a unit square and a polyline (scene size sqrt(2))
v 0.000000 0.000000 0.000000
v 1.000000 0.000000 0.000000
v 1.000000 1.000000 0.000000
v 0.000000 1.000000 0.000000
g leaf
usemtl mtl3
f 1 2 3
g stem
usemtl mtl4
f 1 3 4
l 1 2 3
"""


def _pair(tmp_path, golden_text, found_text, name="x.obj"):
    g, f = tmp_path / "golden" / name, tmp_path / "found" / name
    g.parent.mkdir(parents=True, exist_ok=True)
    f.parent.mkdir(parents=True, exist_ok=True)
    g.write_text(golden_text)
    f.write_text(found_text)
    return g, f


def _diff(tmp_path, golden_text, found_text, name="x.obj", **kw):
    g, f = _pair(tmp_path, golden_text, found_text, name)
    return G.diff_files(g, f, name, **kw)


def _moved(text, vertex, dx):
    """``text`` with vertex ``vertex`` (1-based) moved by dx along x, written %.6f."""
    lines = text.splitlines(keepends=True)
    vs = [i for i, l in enumerate(lines) if l.startswith("v ")]
    x, y, z = map(float, lines[vs[vertex - 1]].split()[1:])
    lines[vs[vertex - 1]] = f"v {x + dx:.6f} {y:.6f} {z:.6f}\n"
    return "".join(lines)


def test_obj_identical_is_same(tmp_path):
    d = _diff(tmp_path, OBJ, OBJ)
    assert d.status == "same" and d.ok


def test_obj_vertex_within_tolerance_passes(tmp_path):
    size = np.sqrt(2.0)
    d = _diff(tmp_path, OBJ, _moved(OBJ, 2, 0.5 * TOL.coord_rel * size))
    assert d.status == "ok", d.format()
    assert "largest vertex move" in " ".join(d.notes)


def test_obj_vertex_beyond_tolerance_fails_with_a_readable_report(tmp_path):
    d = _diff(tmp_path, OBJ, _moved(OBJ, 3, 3.2e-3))
    assert d.status == "differs"
    text = d.format()
    assert "1 of 4 vertices moved beyond tolerance" in text
    assert "scene size 1.414" in text
    assert "vertex 3 moved 0.0032: golden (1.000000 1.000000 0.000000), found (1.003200 1.000000 0.000000)" in text
    assert text.startswith("x.obj: ")


def test_obj_tolerance_scales_with_the_scene(tmp_path):
    # the same absolute move passes in a scene 1000 times larger
    big = "".join(f"v {float(l.split()[1]) * 1000:.6f} {float(l.split()[2]) * 1000:.6f} 0.000000\n"
                  if l.startswith("v ") else l for l in OBJ.splitlines(keepends=True))
    assert _diff(tmp_path, big, _moved(big, 3, 3.2e-3)).ok
    assert not _diff(tmp_path, OBJ, _moved(OBJ, 3, 3.2e-3)).ok
    # and a manifest tolerance overrides the default
    assert _diff(tmp_path, OBJ, _moved(OBJ, 3, 3.2e-3), tol=TOL.updated({"coord_rel": 1e-2})).ok


def test_obj_changed_face_fails(tmp_path):
    d = _diff(tmp_path, OBJ, OBJ.replace("f 1 3 4", "f 1 4 3"))
    assert not d.ok
    assert "faces differ from face 2: golden 1 3 4, found 1 4 3 (1 of 2 faces differ)" in d.format()


def test_obj_changed_counts_groups_materials_polylines_fail(tmp_path):
    d = _diff(tmp_path, OBJ, OBJ + "v 2.0 2.0 2.0\n")
    assert "vertex count: golden 4, found 5" in d.format()
    d = _diff(tmp_path, OBJ, OBJ.replace("f 1 3 4\n", "f 1 3 4\nf 2 3 4\n"))
    assert "face count: golden 2, found 3" in d.format()
    d = _diff(tmp_path, OBJ, OBJ.replace("usemtl mtl4", "usemtl mtl3"))
    assert not d.ok and "materials: golden ['mtl3', 'mtl4'] (2), found ['mtl3'] (1)" in d.format()
    assert "face 2: golden 'mtl4', found 'mtl3'" in d.format()
    d = _diff(tmp_path, OBJ, OBJ.replace("g stem\n", ""))
    assert not d.ok and "groups:" in d.format() and "face 2: golden 'stem', found 'leaf'" in d.format()
    d = _diff(tmp_path, OBJ, OBJ.replace("l 1 2 3", "l 1 2 4"))
    assert not d.ok and "polyline 1: golden 1 2 3, found 1 2 4" in d.format()


def test_obj_unreadable_and_missing(tmp_path):
    d = _diff(tmp_path, OBJ, OBJ.replace("f 1 3 4", "f 1 3 9"))
    assert d.status == "unreadable" and "cannot compare" in d.format()
    g, _ = _pair(tmp_path, OBJ, OBJ)
    d = G.diff_files(g, tmp_path / "found" / "nope.obj", "nope.obj")
    assert d.status == "missing" and "missing file" in d.format()
    d = G.diff_files(tmp_path / "golden" / "nope.obj", g, "nope.obj")
    assert d.status == "no golden" and not d.ok


def _scene(**changes):
    a = dict(kind="o", id=0, pos=[0, 0, 0], scale=[1, 1, 1], up=[0, 1, 0], right=[1, 0, 0], material=3,
             type="ray")
    b = dict(kind="ca", id=1, pos=[10, 0, 0], scale=[1, 1, 1], up=[0, 1, 0], right=[1, 0, 0], frame_start=0,
             frame_end=9, material=4, type="disk")
    b.update(changes)
    return Scene([Placement(**a), Placement(**b)])


def test_scn_structure_exact_numbers_within_tolerance(tmp_path):
    g = tmp_path / "g.scn"
    write_scn(g, _scene())

    def diff(**changes):
        f = tmp_path / "f.scn"
        write_scn(f, _scene(**changes))
        return G.diff_files(g, f, "scene.scn")

    assert diff().status == "same"
    assert diff(pos=[10 + 5e-5, 0, 0]).ok  # scene size 10: tolerance 1e-4
    d = diff(pos=[10.01, 0, 0])
    assert not d.ok and "placement position 1 moved 0.01" in d.format()
    d = diff(id=2)
    assert not d.ok and "id differs at 1 of 2 placements, from placement 1" in d.format()
    assert "placement 1: golden 1, found 2" in d.format()
    d = diff(type="ray")
    assert not d.ok and "floret type" in d.format() and "golden 'disk', found 'ray'" in d.format()
    assert not diff(material=5).ok
    assert not diff(frame_end=8).ok
    d = diff(kind="rba")
    assert not d.ok and "placement kind" in d.format()
    assert not diff(up=[0, 1, 0.01]).ok


def test_rba_ids_exact_positions_within_tolerance(tmp_path):
    def frame(ids=(0, 1, 2), dx=0.0):
        pos = np.array([[0, 0, 0], [4, 0, 0], [0, 4, 0]], float)
        pos[1, 0] += dx
        n = len(ids)
        return RbaFrame(list(ids), pos[:n], np.ones((n, 3)), np.tile([0, 1, 0], (n, 1)), np.tile([1, 0, 0], (n, 1)))

    g = tmp_path / "0000.rba"
    write_rba(g, frame())
    f = tmp_path / "f" / "0000.rba"
    write_rba(f, frame(dx=1e-5))
    assert G.diff_files(g, f).ok
    write_rba(f, frame(dx=1e-2))
    d = G.diff_files(g, f)
    assert not d.ok and "floret position id 1 (row 2) moved 0.01" in d.format()
    write_rba(f, frame(ids=(0, 2, 1)))
    d = G.diff_files(g, f)
    assert not d.ok and "row 2: golden id 1, found 2" in d.format()
    write_rba(f, frame(ids=(0, 1)))
    assert "floret count: golden 3, found 2" in G.diff_files(g, f).format()


def test_floret_structure_exact_control_points_within_tolerance(tmp_path):
    key = read_floret(REPO / "pipelines" / "lily" / "key_bud.floret")
    g = tmp_path / "g.floret"
    write_floret(g, key)

    def diff(organ_changes=None, dy=0.0, **floret_changes):
        organs = []
        for k, o in enumerate(key.organs):
            cp = np.array(o.control_points)
            if k == 1:
                cp[2, 1, 1] += dy
            organs.append(dataclasses.replace(o, control_points=cp, **((organ_changes or {}) if k == 1 else {})))
        f = tmp_path / "f.floret"
        write_floret(f, dataclasses.replace(key, organs=tuple(organs), **floret_changes))
        return G.diff_files(g, f, "frame.floret")

    assert diff().status == "same"
    assert diff(dy=1e-7).ok
    d = diff(dy=1e-2)
    assert not d.ok and "organ 'petals' control point row 2 column 1 moved 0.01" in d.format()
    d = diff({"material": 9})
    assert not d.ok and "organ 'petals' material id: golden 4, found 9" in d.format()
    assert not diff({"symmetry_n": 4}).ok
    assert not diff({"tilt_deg": 1.0}).ok
    assert not diff(key_time=0.5).ok
    assert not diff(name="tulip").ok


LOG = """\
frame,steps,rms_edge_error,collisions_found,remaining_florets,t_rest_s,t_collide_s
0,0,0.000000e+00,0,,0.0000,0.0658
1,1,6.779704e-18,12,,0.0048,0.1244
2,1,8.759040e-06,3,,0.0012,0.0850
"""


def test_csv_timings_ignored_counts_exact_floats_within_tolerance(tmp_path):
    timings = LOG.replace("0.0048,0.1244", "0.9000,3.1000")
    d = _diff(tmp_path, LOG, timings, "log.csv")
    assert d.ok and "ignored columns t_rest_s, t_collide_s" in " ".join(d.notes)
    d = _diff(tmp_path, LOG, LOG.replace("1,1,6.779704e-18,12", "1,1,6.779704e-18,13"), "log.csv")
    assert not d.ok
    assert "column collisions_found differs in 1 of 3 rows, from row 2 (frame 1)" in d.format()
    assert "golden '12', found '13'" in d.format()
    # floats: within num_abs + num_rel * |golden| (the absolute floor 2e-6 is the precision of the
    # coordinates the error measures are made of)
    assert _diff(tmp_path, LOG, LOG.replace("8.759040e-06", "8.859040e-06"), "log.csv").ok
    d = _diff(tmp_path, LOG, LOG.replace("8.759040e-06", "1.875904e-05"), "log.csv")
    assert not d.ok and "row 3 (frame 2): golden '8.759040e-06', found '1.875904e-05'" in d.format()
    assert "row count: golden 3, found 2" in _diff(tmp_path, LOG, LOG.rsplit("2,1", 1)[0], "log.csv").format()
    d = _diff(tmp_path, LOG, LOG.replace("collisions_found", "collisions"), "log.csv")
    assert not d.ok and "columns differ (new collisions; gone collisions_found)" in d.format()
    # a manifest can make a timing column count, or give a column its own tolerance
    d = _diff(tmp_path, LOG, timings, "log.csv", options={"exact_columns": ["t_rest_s"]})
    assert not d.ok and "column t_rest_s" in d.format()
    d = _diff(tmp_path, LOG, LOG.replace("8.759040e-06", "8.859040e-06"), "log.csv",
              options={"column_tolerance": {"rms_edge_error": 1e-8}})
    assert not d.ok and "column rms_edge_error" in d.format()


def test_chaotic_tolerance_lets_counts_and_positions_drift_but_keeps_zeros_and_words(tmp_path):
    """A ``chaotic = true`` stage (fccompose's crowded frames): counts within 25 %, numbers within
    10 %, coordinates within 1 % of the scene; a zero, a word, a face stay exact."""
    chaos = G.CHAOTIC
    text = "frames with contacts: 32 of 32; 0 intersecting pairs; stretch 0.509-1.425\nOK\n"
    assert _diff(tmp_path, text, text.replace("32 of 32", "28 of 32"), "check.txt", tol=chaos).ok
    assert not _diff(tmp_path, text, text.replace("32 of 32", "20 of 32"), "check.txt", tol=chaos).ok
    assert not _diff(tmp_path, text, text.replace("; 0 inter", "; 1 inter"), "check.txt", tol=chaos).ok
    assert _diff(tmp_path, text, text.replace("0.509", "0.540"), "check.txt", tol=chaos).ok
    assert not _diff(tmp_path, text, text.replace("0.509", "0.600"), "check.txt", tol=chaos).ok
    assert not _diff(tmp_path, text, text.replace("OK", "FAILED"), "check.txt", tol=chaos).ok
    assert not _diff(tmp_path, text, text.replace("32 of 32", "31 of 32"), "check.txt").ok  # exact by default
    assert _diff(tmp_path, OBJ, _moved(OBJ, 2, 0.01), tol=chaos).ok  # 0.7 % of sqrt(2)
    assert not _diff(tmp_path, OBJ, _moved(OBJ, 2, 0.02), tol=chaos).ok
    assert not _diff(tmp_path, OBJ, OBJ.replace("f 1 3 4", "f 1 4 3"), tol=chaos).ok


def test_manifest_chaotic_key(tmp_path):
    repo = _fake_repo(tmp_path)
    path = repo / "tests" / "golden" / "fake" / "manifest.toml"
    path.write_text('[[golden]]\nfiles = "log.csv"\nchaotic = true\n[[golden]]\nfiles = "seq/frame_*.obj"\n'
                    '[[golden]]\nfiles = "x.txt"\nchaotic = true\ntolerance = { int_rel = 0.5 }\n')
    log, seq, txt = G.load_species("fake", repo).entries
    assert log.tolerance == G.CHAOTIC and seq.tolerance == G.DEFAULT
    assert txt.tolerance.int_rel == 0.5 and txt.tolerance.coord_rel == G.CHAOTIC.coord_rel
    assert "chaotic" not in log.options
    path.write_text('[[golden]]\nfiles = "log.csv"\nchaotic = "yes"\n')
    with pytest.raises(ValueError, match="chaotic must be true or false"):
        G.load_species("fake", repo)


def test_text_numbers_within_the_written_precision(tmp_path):
    text = "frame  11: 3780 triangles, joint angle 28.78 deg\nOK: no intersecting triangle pairs\n"
    assert _diff(tmp_path, text, text.replace("28.78", "28.79"), "check.txt").ok  # one unit of 2 decimals
    assert not _diff(tmp_path, text, text.replace("28.78", "28.81"), "check.txt").ok
    assert not _diff(tmp_path, text, text.replace("3780", "3781"), "check.txt").ok  # integers exact
    d = _diff(tmp_path, text, text.replace("OK: no", "FAILED: 3"), "check.txt")
    assert not d.ok and "line 2: golden 'OK: no intersecting triangle pairs'" in d.format()
    assert _diff(tmp_path, text, text.replace("frame  11", "frame 11"), "check.txt").ok


def test_toml_and_json_values(tmp_path):
    assert _diff(tmp_path, "a = 1.0\n[b]\nc = [1, 2]\n", "a = 1.000001\n[b]\nc = [1, 2]\n", "p.toml").ok
    assert not _diff(tmp_path, "a = 1.0\n[b]\nc = [1, 2]\n", "a = 1.0\n[b]\nc = [1, 3]\n", "p.toml").ok
    d = _diff(tmp_path, '{"frame": 99, "x": 0.5}', '{"frame": 98, "x": 0.5}', "run.json")
    assert not d.ok and "frame: golden 99, found 98" in d.format()


def test_report_lists_the_first_few_and_counts_the_rest(tmp_path):
    many = "".join(f"v {i:.6f} 0.000000 0.000000\n" for i in range(20))
    moved = "".join(f"v {i + 0.5:.6f} 0.000000 0.000000\n" for i in range(20))
    d = _diff(tmp_path, many, moved)
    text = d.format()
    assert "20 of 20 vertices moved" in text
    assert text.count("moved 0.5: golden") == G.MAX_DETAILS
    assert f"... and {20 - G.MAX_DETAILS} more" in text
    # a run of files with the same kinds of difference (every frame of a sequence) is shown once
    for i in range(4):
        _pair(tmp_path, OBJ, OBJ.replace("usemtl mtl4", "usemtl mtl5"), f"frame_{i:04d}.obj")
    report = G.format_report(G.diff_trees(tmp_path / "golden", tmp_path / "found"), "seq")
    assert report.startswith("seq: 5 files, 5 differ")
    assert report.count("materials: golden ['mtl3', 'mtl4']") == 1
    assert "... and 3 more files with the same kinds of difference: frame_0001.obj ... frame_0003.obj" in report
    assert "x.obj: 20 of 20 vertices moved" in report


# --------------------------------------------------------------------------------------------------
# Species machinery on a fake species (no make): manifest, refresh, listing, missing/extra frames
# --------------------------------------------------------------------------------------------------


def _fake_repo(tmp_path, n=5):
    repo = tmp_path / "repo"
    (repo / "pipelines" / "fake").mkdir(parents=True)
    (repo / "tests" / "golden" / "fake").mkdir(parents=True)
    (repo / "tests" / "golden" / "fake" / "manifest.toml").write_text(
        'targets = ["all"]\n'
        '[[golden]]\nfiles = "seq/frame_*.obj"\npick = ["first", "middle", "last"]\n'
        '[[golden]]\nfiles = "log.csv"\n')
    seq = repo / "build" / "fake" / "seq"
    seq.mkdir(parents=True)
    for i in range(n):
        (seq / f"frame_{i:04d}.obj").write_text(_moved(OBJ, 1, 0.1 * i))
    (repo / "build" / "fake" / "log.csv").write_text(LOG)
    return repo


def _check(spec):
    return {d.name: d for d in G.check_species(spec)}


def test_refresh_then_check_reports_missing_and_extra_frames(tmp_path):
    repo = _fake_repo(tmp_path)
    spec = G.load_species("fake", repo)
    assert G.species_with_manifest(repo) == ["fake"]
    assert G.check_species(spec)[0].status == "no golden"  # before the first refresh
    out = []
    assert G.refresh_species(spec, out=out.append) == 0
    text = "\n".join(out)
    assert "seq/frame_0000.obj: new" in text and "seq/frame_0002.obj: new" in text
    assert "seq/frame_0004.obj: new" in text and "frame_0001" not in text.split("listed")[0]
    assert (spec.golden / "seq" / "frame_0002.obj").is_file()
    assert not (spec.golden / "seq" / "frame_0001.obj").exists()
    res = _check(spec)
    assert sorted(res) == ["log.csv", "seq/frame_0000.obj", "seq/frame_0002.obj", "seq/frame_0004.obj"]
    assert all(d.status == "same" for d in res.values())

    build = spec.build / "seq"
    (build / "frame_0001.obj").unlink()  # a frame that is not golden: the listing notices
    res = _check(spec)
    assert res["seq/frame_0001.obj"].status == "missing"
    assert "the golden sequence seq/frame_*.obj has 5 files" in res["seq/frame_0001.obj"].format()
    (build / "frame_0004.obj").unlink()  # a golden frame
    assert _check(spec)["seq/frame_0004.obj"].status == "missing"
    (build / "frame_0007.obj").write_text(OBJ)
    assert _check(spec)["seq/frame_0007.obj"].status == "extra"


def test_refresh_reports_changes_and_removes_stale_goldens(tmp_path):
    repo = _fake_repo(tmp_path)
    spec = G.load_species("fake", repo)
    G.refresh_species(spec, out=lambda s: None)
    seq = spec.build / "seq"
    (seq / "frame_0002.obj").write_text(_moved(OBJ, 1, 0.2 + 1e-7))
    (seq / "frame_0004.obj").write_text(OBJ.replace("f 1 3 4", "f 1 4 3"))
    (seq / "frame_0005.obj").write_text(OBJ)
    (seq / "frame_0006.obj").write_text(OBJ)
    out = []
    G.refresh_species(spec, out=out.append)
    text = "\n".join(out)
    assert "seq/frame_0002.obj: changed" not in text  # 0002 is no longer the middle frame
    assert "seq/frame_0003.obj: new" in text  # the middle of 7 frames
    assert "seq/frame_0002.obj: removed" in text
    assert "seq/frame_0004.obj: removed" in text
    assert "seq/frame_0006.obj: new" in text
    assert "seq/frame_*.obj: 5 -> 7 files" in text
    assert sorted(p.name for p in (spec.golden / "seq").iterdir()) == [
        "frame_0000.obj", "frame_0003.obj", "frame_0006.obj"]
    (seq / "frame_0006.obj").write_text(OBJ.replace("f 1 3 4", "f 1 4 3"))
    out = []
    G.refresh_species(spec, out=out.append)
    assert any("seq/frame_0006.obj: changed: faces differ from face 2" in s for s in out)


def test_compressed_goldens_are_kept_gzipped_and_compared_as_their_content(tmp_path):
    repo = _fake_repo(tmp_path)
    man = repo / "tests" / "golden" / "fake" / "manifest.toml"
    man.write_text(man.read_text().replace('pick = ["first", "middle", "last"]\n',
                                           'pick = ["first", "middle", "last"]\ncompress = true\n'))
    spec = G.load_species("fake", repo)
    assert G.refresh_species(spec, out=lambda s: None) == 0
    gz = spec.golden / "seq" / "frame_0002.obj.gz"
    assert gz.is_file() and not (spec.golden / "seq" / "frame_0002.obj").exists()
    assert spec.golden_path("seq/frame_0002.obj") == gz
    first = gz.read_bytes()
    assert all(d.status == "same" for d in G.check_species(spec))
    # a second refresh of the same build writes the same bytes (no time or name in the header)
    out = []
    G.refresh_species(spec, out=out.append)
    assert gz.read_bytes() == first and "nothing changed" in out[-1]
    # a vertex moved beyond the tolerance is found through the compression
    (spec.build / "seq" / "frame_0002.obj").write_text(_moved(OBJ, 2, 0.01))
    res = _check(spec)
    assert res["seq/frame_0002.obj"].status == "differs"
    assert "vertices moved beyond tolerance" in res["seq/frame_0002.obj"].format()
    # switching compression off replaces the .gz copies by plain ones
    man.write_text(man.read_text().replace("compress = true\n", ""))
    spec = G.load_species("fake", repo)
    out = []
    G.refresh_species(spec, out=out.append)
    assert (spec.golden / "seq" / "frame_0002.obj").is_file() and not gz.exists()
    assert any("frame_0002.obj.gz: removed" in line for line in out)
    man.write_text(man.read_text() + 'compress = "yes"\n')
    with pytest.raises(ValueError, match="compress must be true or false"):
        G.load_species("fake", repo)


def test_refresh_refuses_an_incomplete_build(tmp_path):
    repo = _fake_repo(tmp_path)
    (repo / "build" / "fake" / "log.csv").unlink()
    spec = G.load_species("fake", repo)
    out = []
    assert G.refresh_species(spec, out=out.append) == 1
    assert "log.csv: missing from build/fake" in "\n".join(out)
    assert not spec.listing_path().exists()


def test_manifest_errors_are_one_line(tmp_path):
    repo = _fake_repo(tmp_path)
    path = repo / "tests" / "golden" / "fake" / "manifest.toml"
    path.write_text('targts = ["all"]\n[[golden]]\nfiles = "log.csv"\n')
    with pytest.raises(ValueError, match="unknown key.*targts"):
        G.load_species("fake", repo)
    path.write_text('[tolerance]\ncoord = 1\n[[golden]]\nfiles = "log.csv"\n')
    with pytest.raises(ValueError, match="unknown tolerance key"):
        G.load_species("fake", repo)


def test_cli_diff_check_and_refresh(tmp_path):
    repo = _fake_repo(tmp_path)
    py = [sys.executable, "-m", "inflo.tools.golden"]
    run = lambda *a: subprocess.run([*py, *map(str, a)], capture_output=True, text=True, timeout=120)
    r = run("refresh", "fake", "--no-build", "--repo", repo)
    assert r.returncode == 0 and "golden fake: 4 files" in r.stdout, r.stdout + r.stderr
    r = run("check", "all", "--no-build", "--repo", repo)
    assert r.returncode == 0 and "4 identical" in r.stdout, r.stdout + r.stderr
    (repo / "build" / "fake" / "seq" / "frame_0004.obj").write_text(_moved(_moved(OBJ, 1, 0.4), 2, 0.5))
    r = run("check", "fake", "--no-build", "--repo", repo)
    assert r.returncode == 1
    assert "seq/frame_0004.obj: 1 of 4 vertices moved beyond tolerance" in r.stdout
    assert "refresh fake" in r.stdout
    assert run("check", "nosuch", "--no-build", "--repo", repo).returncode == 2
    a, b = _pair(tmp_path, OBJ, OBJ.replace("f 1 3 4", "f 1 4 3"))
    r = run("diff", a, b)
    assert r.returncode == 1 and "faces differ from face 2" in r.stdout
    assert run("diff", a, a).returncode == 0
    assert run("diff", a.parent, a.parent).returncode == 0


def test_make_env_finds_the_tools_and_drops_an_enclosing_make():
    env = G.make_env({"PATH": "/usr/bin", "MAKEFLAGS": "-j2 --jobserver-auth=3,4", "MAKELEVEL": "1",
                      "QUALITY": "final"})
    assert env["PATH"].split(os.pathsep)[0] == str(Path(sys.executable).parent)
    assert (Path(env["PATH"].split(os.pathsep)[0]) / "floret-animate").exists()
    assert not {"MAKEFLAGS", "MAKELEVEL", "QUALITY"} & set(env)


# --------------------------------------------------------------------------------------------------
# The species' goldens: one test per golden file and per golden sequence
# --------------------------------------------------------------------------------------------------


def _golden_cases():
    cases = []
    for sp in G.species_with_manifest(REPO):
        try:
            spec = G.load_species(sp, REPO)
        except ValueError as exc:
            cases.append(pytest.param(sp, "manifest", str(exc), id=f"{sp}:manifest"))
            continue
        listing = spec.golden_listing()
        if listing is None:
            cases.append(pytest.param(sp, "not refreshed", "", id=f"{sp}:not-refreshed"))
            continue
        for pattern in listing:
            cases.append(pytest.param(sp, "sequence", pattern, id=f"{sp}:{pattern}"))
        for name, _ in spec.selection(listing):
            cases.append(pytest.param(sp, "file", name, id=f"{sp}/{name}"))
    return cases


@pytest.mark.slow
@pytest.mark.parametrize("species,kind,name", _golden_cases())
def test_golden(species, kind, name, species_build):
    if kind == "manifest":
        pytest.fail(name, pytrace=False)
    spec = species_build(species)
    hint = f"\n(if the change is intended: .venv/bin/python -m inflo.tools.golden refresh {species})"
    if kind == "not refreshed":
        pytest.fail(f"tests/golden/{species} has a manifest but no goldens yet{hint}", pytrace=False)
    listing = spec.golden_listing()
    if kind == "sequence":
        diffs = G.check_listing(spec, name, listing[name])
        if diffs:
            pytest.fail("\n".join(d.format() for d in diffs) + hint, pytrace=False)
        return
    entry = dict(spec.selection(listing))[name]
    d = G.diff_files(spec.golden_path(name), spec.build / name, name, entry.tolerance, entry.options)
    if not d.ok:
        pytest.fail(f"{species}: " + d.format() + hint, pytrace=False)


def test_lily_goldens_are_small_and_complete():
    spec = G.load_species("lily", REPO)
    listing = spec.golden_listing()
    assert listing is not None, "run: python -m inflo.tools.golden refresh lily"
    names = [n for n, _ in spec.selection(listing)]
    assert all((spec.golden / n).is_file() for n in names)
    assert sum((spec.golden / n).stat().st_size for n in names) < 5 * 2**20
    # first, middle and last frame of every sequence stage, the log, the final smoothed frame
    assert {"canopy/frame_0000.obj", "canopy/frame_0049.obj", "canopy/frame_0099.obj", "canopy/log.csv",
            "smooth/100.obj", "frames/frame_0099.floret", "obj/frame_0049.obj"} <= set(names)


def test_yarrow_goldens_are_small_and_complete():
    spec = G.load_species("yarrow", REPO)
    listing = spec.golden_listing()
    assert listing is not None, "run: python -m inflo.tools.golden refresh yarrow"
    names = [n for n, _ in spec.selection(listing)]
    paths = [spec.golden_path(n) for n in names]
    assert all(p.is_file() for p in paths)
    assert sum(p.stat().st_size for p in paths) < 5 * 2**20
    # every stage: key-pose frames, polygons, the head, the growing pattern and the heads and
    # florets on the canopy's clock, dimorph, the canopy, branches, the smoothed final
    # frame, the check
    assert {"ray_frames/frame_0019.floret", "disk_obj/frame_0019.obj", "head/scene.scn", "growth/rba/0070.rba",
            "heads/rba/0031.rba", "corymb/rba/0031.rba", "corymb/scene.scn", "corymb/typed.scn",
            "canopy/frame_0031.obj", "canopy/log.csv", "branches/branches.obj",
            "branches/frames/branches_0015.obj", "smooth/final.obj", "check.txt"} <= set(names)
    # the big frames are kept gzipped
    assert spec.golden_path("smooth/final.obj").name == "final.obj.gz"
    assert listing["canopy/frame_*.obj"][-1] == "canopy/frame_0031.obj" and len(listing["canopy/frame_*.obj"]) == 32
    assert len(listing["branches/frames/branches_*.obj"]) == 32  # one clock
