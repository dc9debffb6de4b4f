"""fccompose end to end: template reproduction, the dense two-floret scene stays
intersection-free, --resume is bit-identical, RBA motion, and bad input."""
from __future__ import annotations

import csv
import shutil
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, no_partial_files, run_cli

from inflo.formats.fcc import read_fcc
from inflo.formats.obj import ObjMesh, read_obj, read_obj_sequence, write_obj, write_obj_sequence
from inflo.formats.rba import RbaFrame, write_rba_sequence
from inflo.formats.scn import Placement
from inflo.tools.collide import intersecting_pairs
from inflo.tools.fccompose.compose import compose_canopy
from inflo.tools.testing.florets import (
    opening_floret,
    two_floret_scene,
    write_fcc_text,
    write_floret_animation,
    write_scene,
)

N_FRAMES = 8


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    d = tmp_path_factory.mktemp("fcc_inputs")
    frames, faces, fixed = opening_floret(N_FRAMES)
    write_floret_animation(d / "anim", frames, faces, fixed, d / "petal_base.txt")
    placements = two_floret_scene(N_FRAMES)
    write_scene(d / "scene.scn", placements)
    write_scene(d / "single.scn", placements[:1])
    write_fcc_text(d / "dense.fcc")
    write_fcc_text(d / "single.fcc", scene="single.scn")
    return {"dir": d, "frames": frames, "faces": faces, "fixed": fixed, "placements": placements}


def read_log(folder) -> list[dict]:
    with open(Path(folder) / "log.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def kabsch_rms(a: np.ndarray, b: np.ndarray) -> float:
    """RMS distance between point sets after the best rigid motion of ``a`` onto ``b``."""
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    u, _, vt = np.linalg.svd((a - ca).T @ (b - cb))
    d = np.sign(np.linalg.det(u @ vt))
    r = u @ np.diag([1, 1, d]) @ vt
    return float(np.sqrt((((a - ca) @ r - (b - cb)) ** 2).sum(axis=1).mean()))


def test_single_floret_reproduces_its_template(inputs, tmp_path):
    out = tmp_path / "single"
    out.mkdir()
    (out / "frame_0099.obj").write_text("a frame of an earlier, longer run\n")
    (out / "notes.txt").write_text("not a frame\n")
    res = run_cli("fccompose", inputs["dir"] / "single.fcc", "-o", out, "-q")
    assert res.returncode == 0, res.stderr
    assert not (out / "frame_0099.obj").exists() and (out / "notes.txt").exists()
    paths, meshes = read_obj_sequence(out)
    assert [p.name for p in paths] == [f"frame_{k:04d}.obj" for k in range(N_FRAMES)]
    size = np.ptp(np.concatenate(inputs["frames"]), axis=0).max()
    for k, mesh in enumerate(meshes):
        np.testing.assert_array_equal(mesh.faces, inputs["faces"])
        assert kabsch_rms(mesh.vertices, inputs["frames"][k]) < 0.01 * size
    log = read_log(out)
    assert [int(r["frame"]) for r in log] == list(range(N_FRAMES))
    assert max(float(r["rms_edge_error"]) for r in log) < 1e-3


@pytest.fixture(scope="module")
def dense_run(inputs, tmp_path_factory):
    out = tmp_path_factory.mktemp("dense") / "out"
    res = run_cli("fccompose", inputs["dir"] / "dense.fcc", "-o", out)
    assert res.returncode == 0, res.stderr
    return out, res


def test_dense_scene_ends_every_frame_without_intersections(inputs, dense_run):
    out, _ = dense_run
    paths, meshes = read_obj_sequence(out)
    assert len(paths) == N_FRAMES
    # the placed templates alone would run through each other: the test is not vacuous
    last = []
    for _k, p in enumerate(inputs["placements"]):
        m = p.matrix()
        last.append(inputs["frames"][-1] @ m[:3, :3].T + m[:3, 3])
    two = np.concatenate([inputs["faces"], inputs["faces"] + len(inputs["frames"][0])])
    assert len(intersecting_pairs(np.concatenate(last), two)) > 10
    for mesh in meshes:
        assert len(intersecting_pairs(mesh.vertices, mesh.faces)) == 0
    log = read_log(out)
    assert all(int(r["intersecting_pairs"]) == 0 for r in log)
    assert sum(int(r["collisions_found"]) for r in log) > 20
    mesh = meshes[-1]
    assert mesh.groups == ["floret_0", "floret_1"]
    assert mesh.materials == ["mtl1", "mtl2"]
    assert no_partial_files(out)


def test_resume_continues_bit_identically(inputs, dense_run, tmp_path):
    out_full, _ = dense_run
    out = tmp_path / "resumed"
    params = read_fcc(inputs["dir"] / "dense.fcc")

    class Interrupt:
        def __init__(self, total):
            self.done = 0

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def update(self, n):
            self.done += n
            if self.done == 3:
                raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        compose_canopy(params, out, progress=Interrupt)
    assert sorted(p.name for p in out.glob("*.obj")) == [f"frame_{k:04d}.obj" for k in range(4)]
    res = run_cli("fccompose", inputs["dir"] / "dense.fcc", "-o", out, "--resume", "-q")
    assert res.returncode == 0, res.stderr
    full = sorted(out_full.glob("*.obj"))
    assert [p.name for p in sorted(out.glob("*.obj"))] == [p.name for p in full]
    for p in full:
        assert (out / p.name).read_bytes() == p.read_bytes(), p.name
    assert len(read_log(out)) == N_FRAMES


def test_rigid_body_animation_moves_the_floret(inputs, tmp_path):
    d = inputs["dir"]
    shutil.copytree(d / "anim", tmp_path / "anim")
    shutil.copy(d / "petal_base.txt", tmp_path / "petal_base.txt")
    write_scene(tmp_path / "rba.scn", [Placement("rba", 0, [0, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0],
                                                 frame_start=0, frame_end=3, material=4)])
    frames = [RbaFrame([0], [[0.5 * k, 0.0, 0.0]], [[1, 1, 1]], [[0, 1, 0]], [[1, 0, 0]]) for k in range(4)]
    write_rba_sequence(tmp_path / "rba", frames)
    write_fcc_text(tmp_path / "rba.fcc", scene="rba.scn",
                   extra="rigid body animation: 7 1 1 1 rba rba.scn\n")
    out = tmp_path / "out"
    res = run_cli("fccompose", tmp_path / "rba.fcc", "-o", out, "-q")
    assert res.returncode == 0, res.stderr
    _, meshes = read_obj_sequence(out)
    assert len(meshes) == 4
    tpl = opening_floret(N_FRAMES)[0]
    u = np.arange(4) / 3 * (N_FRAMES - 1)
    for k, mesh in enumerate(meshes):
        a = int(np.floor(u[k]))
        b = min(a + 1, N_FRAMES - 1)
        expect = (1 - (u[k] - a)) * tpl[a] + (u[k] - a) * tpl[b] + [0.5 * k, 0, 0]
        assert np.abs(mesh.vertices - expect).max() < 0.01  # rest values interpolate, positions do not


def _rba_case(inputs, tmp_path, frames, extra=""):
    """Two rba: placements (0 and 1) of the test floret moved by ``frames`` (RbaFrame list)."""
    d = inputs["dir"]
    shutil.copytree(d / "anim", tmp_path / "anim")
    shutil.copy(d / "petal_base.txt", tmp_path / "petal_base.txt")
    write_scene(tmp_path / "rba.scn", [Placement("rba", 0, [0, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0],
                                                 frame_start=0, frame_end=len(frames) - 1, material=k)
                                       for k in range(2)])
    write_rba_sequence(tmp_path / "rba", frames)
    write_fcc_text(tmp_path / "rba.fcc", scene="rba.scn", extra="rigid body animation: 7 1 1 1 rba rba.scn\n" + extra)
    return tmp_path / "rba.fcc"


def _row(ids, xs):
    n = len(ids)
    return RbaFrame(list(ids), [[x, 0.0, 0.0] for x in xs], [[1, 1, 1]] * n, [[0, 1, 0]] * n, [[1, 0, 0]] * n)


def test_rba_florets_emerge_at_their_first_rba_frame(inputs, tmp_path):
    """Placement 1 is listed from RBA frame 2 on: frames 0 and 1 hold placement 0's faces only;
    every frame keeps all vertices (stable numbering); the log counts the florets present."""
    frames = [_row([0], [0.0]), _row([0], [0.0]), _row([0, 1], [0.0, 10.0]), _row([0, 1], [0.0, 10.0])]
    out = tmp_path / "out"
    res = run_cli("fccompose", _rba_case(inputs, tmp_path, frames), "-o", out, "-q")
    assert res.returncode == 0, res.stderr
    _, meshes = read_obj_sequence(out, same_topology=False)
    nt, nv = len(inputs["faces"]), len(inputs["frames"][0])
    assert [len(m.faces) for m in meshes] == [nt, nt, 2 * nt, 2 * nt]
    assert all(len(m.vertices) == 2 * nv for m in meshes)
    assert meshes[1].faces.max() < nv and meshes[2].faces.max() >= nv  # floret 1's vertices come after
    assert "1 of 2 florets emerged" in (out / "frame_0001.obj").read_text().splitlines()[0]
    # it appears at its first RBA pose, at its developmental time (u = 2/3 of the template)
    tpl = opening_floret(N_FRAMES)[0]
    u = 2 / 3 * (N_FRAMES - 1)
    a = int(u)
    expect = (1 - (u - a)) * tpl[a] + (u - a) * tpl[a + 1] + [10.0, 0, 0]
    assert np.abs(meshes[2].vertices[nv:] - expect).max() < 0.01
    log = read_log(out)
    assert [int(r["florets_present"]) for r in log] == [1, 1, 2, 2]
    assert all(int(r["florets_waiting"]) == 0 for r in log)


def test_a_floret_with_no_room_waits_until_there_is_room(inputs, tmp_path):
    """Placement 1 is listed from frame 1 where placement 0 still stands (they would intersect);
    placement 0 moves away over frame 2, and placement 1 emerges then: every written frame is
    free of intersections (exact test), the log shows the wait, and --resume carries it."""
    frames = [_row([0], [0.0]), _row([0, 1], [0.0, 0.0]), _row([0, 1], [10.0, 0.0]), _row([0, 1], [10.0, 0.0])]
    fcc = _rba_case(inputs, tmp_path, frames, "emergence scales: 1\n")  # no smaller tries
    out = tmp_path / "out"
    res = run_cli("fccompose", fcc, "-o", out, "-q")
    assert res.returncode == 0, res.stderr
    _, meshes = read_obj_sequence(out, same_topology=False)
    nt = len(inputs["faces"])
    assert [len(m.faces) for m in meshes] == [nt, nt, 2 * nt, 2 * nt]
    for m in meshes:
        assert len(intersecting_pairs(m.vertices, m.faces)) == 0
    log = read_log(out)
    assert [int(r["florets_waiting"]) for r in log] == [0, 1, 0, 0]
    assert [int(r["florets_present"]) for r in log] == [1, 1, 2, 2]
    # stopped after frame 1 (placement 1 waiting) and resumed: the same bytes
    class StopAfterFrame1:
        def __init__(self, total):
            pass

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def update(self, n):
            raise KeyboardInterrupt

    part = tmp_path / "part"
    with pytest.raises(KeyboardInterrupt):
        compose_canopy(read_fcc(fcc), part, progress=StopAfterFrame1)
    assert '"not_emerged": [1]' in (part / "state" / "run.json").read_text()
    res = run_cli("fccompose", fcc, "-o", part, "--resume", "-q")
    assert res.returncode == 0, res.stderr
    for q in sorted(out.glob("*.obj")):
        assert (part / q.name).read_bytes() == q.read_bytes(), q.name
    assert [int(r["florets_waiting"]) for r in read_log(part)] == [0, 1, 0, 0]


def test_a_floret_that_never_finds_room_is_reported(inputs, tmp_path):
    frames = [_row([0], [0.0]), _row([0, 1], [0.0, 0.0]), _row([0, 1], [0.0, 0.0])]
    out = tmp_path / "out"
    res = run_cli("fccompose", _rba_case(inputs, tmp_path, frames, "emergence scales: 1\n"), "-o", out)
    assert res.returncode == 0, res.stderr
    assert "1 florets due to emerge found no room by frame 2 (placement indices 1)" in res.stderr
    assert [len(m.faces) for m in read_obj_sequence(out, same_topology=False)[1]] == [len(inputs["faces"])] * 3
    assert [int(r["florets_waiting"]) for r in read_log(out)] == [0, 1, 1]


def test_a_floret_with_too_little_room_emerges_smaller_and_grows_back(inputs, tmp_path):
    """Placement 1 is due at frame 1 so close to placement 0 that at its own size the two
    intersect: it emerges on time at a smaller size (the first of the ``emergence scales`` that
    fits), grows back to its own size over ``emergence growth frames``, collision-free all along,
    every edge within the stretch bounds; nothing waits."""
    tpl = opening_floret(N_FRAMES)[0]
    u = 1 / 5 * (N_FRAMES - 1)  # placement 1's developmental time at frame 1 (window 0-5)
    a = int(u)
    pose = (1 - (u - a)) * tpl[a] + (u - a) * tpl[a + 1]
    reach = float(np.hypot(pose[:, 0], pose[:, 2]).max())
    d = 1.7 * reach  # the two overlap at their own size, not at 3/4 of it
    frames = [_row([0], [0.0])] + [_row([0, 1], [0.0, d])] * 5
    out = tmp_path / "out"
    res = run_cli("fccompose", _rba_case(inputs, tmp_path, frames, "emergence growth frames: 3\n"), "-o", out)
    assert res.returncode == 0, res.stderr
    log = read_log(out)
    assert [int(r["florets_present"]) for r in log] == [1, 2, 2, 2, 2, 2]
    assert all(int(r["florets_waiting"]) == 0 for r in log)
    assert [int(r["florets_smaller"]) for r in log][1:] == [1, 1, 1, 0, 0]
    _, meshes = read_obj_sequence(out, same_topology=False)
    for m in meshes:
        assert len(intersecting_pairs(m.vertices, m.faces)) == 0
    nv = len(inputs["frames"][0])
    size = lambda v: float(np.ptp(v[:, 1]))
    own = size(meshes[1].vertices[:nv])  # floret 0 at frame 1, same stage
    assert size(meshes[1].vertices[nv:]) < 0.9 * own  # emerged smaller
    # grown back: its base (fixed on the receptacle) is placed at its own size again
    base = inputs["fixed"]
    assert np.abs(meshes[-1].vertices[nv + base] - meshes[-1].vertices[base] - [d, 0, 0]).max() < 1e-5
    assert np.abs(meshes[1].vertices[nv + base] - meshes[1].vertices[base] - [d, 0, 0]).max() > 0.01


def test_organ_materials_of_the_template_are_kept(inputs, tmp_path):
    """Triangles keep their template OBJ's usemtl (a floret's organs: a lily's sepals and petals);
    triangles without one take the placement's SCN mtl id."""
    frames, faces = inputs["frames"], inputs["faces"]
    organ = np.where(np.arange(len(faces)) < len(faces) // 2, -1, 0).astype(np.int32)  # none, then mtl9
    write_obj_sequence(tmp_path / "anim", [ObjMesh(v, faces, materials=["mtl9"], face_material=organ)
                                           for v in frames])
    shutil.copy(inputs["dir"] / "petal_base.txt", tmp_path / "petal_base.txt")
    write_scene(tmp_path / "scene.scn", inputs["placements"][:1])  # material 1
    write_fcc_text(tmp_path / "m.fcc", frames=2)
    out = tmp_path / "out"
    res = run_cli("fccompose", tmp_path / "m.fcc", "-o", out, "-q")
    assert res.returncode == 0, res.stderr
    mesh = read_obj(out / "frame_0002.obj")
    assert mesh.materials == ["mtl1", "mtl9"]
    names = np.array(mesh.materials)[mesh.face_material]
    assert (names[: len(faces) // 2] == "mtl1").all() and (names[len(faces) // 2:] == "mtl9").all()


@pytest.mark.parametrize("kind", ["ta", "ra"])
def test_translation_and_rotation_animations_move_the_floret(inputs, tmp_path, kind):
    """ta: the floret is carried by (x, y, z) over frameStart..frameEnd; ra: turned by angle about
    the axis through its position (C.2); its shape follows its template meanwhile."""
    d = inputs["dir"]
    shutil.copytree(d / "anim", tmp_path / "anim")
    shutil.copy(d / "petal_base.txt", tmp_path / "petal_base.txt")
    pos = np.array([1.0, 0.5, -0.25])
    p = Placement(kind, 0, pos, [1, 1, 1], [0, 1, 0], [1, 0, 0], frame_start=0, frame_end=4, material=3)
    if kind == "ta":
        p.translate = np.array([2.0, 0.0, 1.0])
    else:
        p.axis, p.angle = np.array([0.0, 1.0, 0.0]), 90.0
    write_scene(tmp_path / "s.scn", [p])
    write_fcc_text(tmp_path / "s.fcc", scene="s.scn", frames=4)
    out = tmp_path / "out"
    res = run_cli("fccompose", tmp_path / "s.fcc", "-o", out, "-q")
    assert res.returncode == 0, res.stderr
    _, meshes = read_obj_sequence(out)
    assert len(meshes) == 5
    tpl = inputs["frames"]
    size = np.ptp(np.concatenate(tpl), axis=0).max()
    for k, mesh in enumerate(meshes):
        s = k / 4
        if kind == "ta":
            expect_centre = pos + s * np.array([2.0, 0.0, 1.0])
            rot = np.eye(3)
        else:
            a = np.radians(90.0 * s)
            rot = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
            expect_centre = pos
        u = s * (N_FRAMES - 1)
        i0 = int(np.floor(u))
        i1 = min(i0 + 1, N_FRAMES - 1)
        local = (1 - (u - i0)) * tpl[i0] + (u - i0) * tpl[i1]
        expect = local @ rot.T + expect_centre
        assert np.abs(mesh.vertices - expect).max() < 0.02 * size, k
    # the motion is real: the last frame is far from the first placement
    assert np.linalg.norm(meshes[-1].vertices.mean(0) - meshes[0].vertices.mean(0)) > (0.5 if kind == "ta" else 0.0)


# -- bad input ---------------------------------------------------------------------------------------


def bad_case(inputs, tmp_path, *, fcc_extra="", scene=None, edit=None, **fcc):
    d = tmp_path / "case"
    shutil.copytree(inputs["dir"], d, ignore=shutil.ignore_patterns("*.fcc"))
    if scene is not None:
        write_scene(d / "scene.scn", scene)
    if edit:
        edit(d)
    write_fcc_text(d / "p.fcc", extra=fcc_extra, **fcc)
    out = tmp_path / "out"
    res = run_cli("fccompose", d / "p.fcc", "-o", out)
    return res, out


def assert_input_error(res, out, *words):
    assert res.returncode == 2, res.stderr
    line = res.stderr.strip()
    assert len(line.splitlines()) == 1 and "Traceback" not in line
    for w in words:
        assert w in line, line
    assert not out.exists() or not list(out.glob("*.obj"))


def test_topology_change_in_the_animation_names_the_frame(inputs, tmp_path):
    def edit(d):
        p = d / "anim" / "frame_0003.obj"
        m = read_obj(p)
        m.faces = m.faces[::-1].copy()
        write_obj(p, m)

    res, out = bad_case(inputs, tmp_path, edit=edit)
    assert_input_error(res, out, "frame_0003.obj", "topology")


def test_scene_id_without_animation(inputs, tmp_path):
    pl = two_floret_scene(N_FRAMES)
    pl[1].id = 3
    res, out = bad_case(inputs, tmp_path, scene=pl)
    assert_input_error(res, out, "scene.scn", "id 3")


def test_rba_id_missing_from_scene(inputs, tmp_path):
    def edit(d):
        frames = [RbaFrame([5], [[0, 0, 0]], [[1, 1, 1]], [[0, 1, 0]], [[1, 0, 0]])]
        write_rba_sequence(d / "rba", frames)

    res, out = bad_case(inputs, tmp_path, edit=edit, fcc_extra="rigid body animation: 9 1 1 1 rba scene.scn\n")
    assert_input_error(res, out, "0000.rba", "5")


@pytest.mark.parametrize("kw, word", [({"k_stretch": 1.5}, "kStretch"), ({"spacing": -0.1}, "spacing")])
def test_bad_parameters(inputs, tmp_path, kw, word):
    res, out = bad_case(inputs, tmp_path, **kw)
    assert_input_error(res, out, "p.fcc", word)


def test_initial_intersections_are_refused_then_allowed(inputs, tmp_path):
    pl = two_floret_scene(N_FRAMES, distance=0.3)
    res, out = bad_case(inputs, tmp_path, scene=pl)
    assert_input_error(res, out, "collision-free", "0-1")
    write_fcc_text(tmp_path / "case" / "p.fcc", frames=1)
    res = run_cli("fccompose", tmp_path / "case" / "p.fcc", "-o", out, "--allow-initial-intersections", "-q")
    assert res.returncode == 0, res.stderr


def test_collisions_off_counts_intersections_and_moves_nothing_apart(inputs, tmp_path):
    """``collisions: off`` (the comparison of thesis fig. 4.9): the two florets that start
    intersecting, refused with collisions on, run to the end (even with --strict); every frame's
    sanity check counts the intersections in log.csv, nothing is detected or moved apart, and each
    floret is its template carried by its placement (as the single-floret run gives it)."""
    pl = two_floret_scene(N_FRAMES, distance=0.3)
    res, out = bad_case(inputs, tmp_path, scene=pl, fcc_extra="collisions: off\n")
    assert res.returncode == 0, res.stderr
    rows = read_log(out)
    assert len(rows) == N_FRAMES
    assert all(int(r["intersecting_pairs"]) > 0 for r in rows)
    assert all(int(r["collisions_found"]) == 0 and int(r["florets_retreated"]) == 0 for r in rows)
    res2 = run_cli("fccompose", "-q", "--strict", tmp_path / "case" / "p.fcc", "-o", tmp_path / "strict")
    assert res2.returncode == 0, res2.stderr
    on = tmp_path / "on"
    shutil.copytree(tmp_path / "case", on)
    write_fcc_text(on / "p.fcc")
    res3 = run_cli("fccompose", "-q", on / "p.fcc", "-o", tmp_path / "on_out")
    assert res3.returncode == 2 and "collision-free" in res3.stderr


def test_rba_rows_and_nearest_present_frame_match_a_plain_search():
    """A floret absent from an RBA frame takes the nearest frame where it is present (the earlier on
    a tie); the tables fccompose builds once give the same frame and row as searching every frame."""
    from inflo.tools.fccompose.model import _nearest_present, _rba_rows

    rng = np.random.default_rng(3)
    frames = []
    for _ in range(30):
        ids = np.nonzero(rng.random(6) < 0.4)[0]
        rng.shuffle(ids)
        frames.append(_row(ids.tolist(), [0.0] * len(ids)))
    table = _rba_rows(frames, 6)
    for pid in range(6):
        present = [i for i, fr in enumerate(frames) if fr.index(pid) is not None]
        if not present:
            assert (table[pid] == -1).all()
            continue
        src, row = _nearest_present(table[pid])
        for i in range(len(frames)):
            want = i if i in present else min(present, key=lambda j: (abs(j - i), j))
            assert src[i] == want and row[i] == frames[want].index(pid)


def _small_dynamic_head(inputs, tmp_path, scale: float, spacing: float = 0.001) -> Path:
    """phyllotaxis (centripetal fractionation, 33 primordia over frames 0-7 of 20) with the test
    floret scaled ``scale`` x the primordium sizes; returns the .fcc."""
    toml = (REPO / "pipelines" / "examples" / "phyllotaxis" / "dynamic_head.toml").read_text()
    toml = toml.replace("frames = 120", "frames = 20").replace("primordium_area = 0.002", "primordium_area = 0.03")
    (tmp_path / "head.toml").write_text(toml)
    res = run_cli("phyllotaxis", tmp_path / "head.toml", "-o", tmp_path / "head", "-q")
    assert res.returncode == 0, res.stderr
    shutil.copytree(inputs["dir"] / "anim", tmp_path / "anim")
    shutil.copy(inputs["dir"] / "petal_base.txt", tmp_path / "petal_base.txt")
    write_fcc_text(tmp_path / "g.fcc", scene="head/scene.scn", sanity_every=1, spacing=spacing,
                   extra=f"rigid body animation: 1 {scale} {scale} {scale} head/rba head/scene.scn\n")
    return tmp_path / "g.fcc"


def test_a_dynamic_phyllotaxis_head_grows_with_florets_emerging(inputs, tmp_path):
    """phyllotaxis (centripetal fractionation, 33 primordia over frames 0-7) -> fccompose: each
    frame holds exactly the florets its RBA file lists, less those waiting for room; neighbours
    collide as they open, and no frame has an intersecting triangle pair (exact test)."""
    out = tmp_path / "out"
    res = run_cli("fccompose", _small_dynamic_head(inputs, tmp_path, 0.5), "-o", out, "--strict")
    assert res.returncode == 0, res.stderr
    listed = [len((tmp_path / "head" / "rba" / f"{k:04d}.rba").read_text().splitlines()) for k in range(20)]
    assert listed[0] == 1 and listed[-1] == 33 and listed[5] < 33  # the head grows
    log = read_log(out)
    present = [int(r["florets_present"]) for r in log]
    waiting = [int(r["florets_waiting"]) for r in log]
    assert [p + w for p, w in zip(present, waiting)] == listed
    assert all(int(r["intersecting_pairs"]) == 0 for r in log)
    nt = len(inputs["faces"])
    _, meshes = read_obj_sequence(out, same_topology=False)
    assert [len(m.faces) for m in meshes] == [nt * p for p in present]
    assert sum(int(r["collisions_found"]) for r in log) > 100  # neighbours touch as they open



def test_florets_with_no_room_are_made_smaller_not_torn(inputs, tmp_path):
    """The small dynamic head with florets 1.1 x their primordia and h = 0.005: from frame 6 on,
    florets are crowded beyond what the collision response can hold in shape. A floret left out
    of the stretch bounds whose carried shape has no room is put at a smaller size (``crowded
    scales``) and grows back: every frame keeps every edge within [0.5, 1.5] x rest, with no
    intersecting pair and every floret present. With ``crowded scales: 1`` (never) the same
    frames leave florets out of the bounds."""
    fcc = _small_dynamic_head(inputs, tmp_path, 1.1, spacing=0.005)
    text = fcc.read_text() + "run for number of frames: 9\n"

    def run(extra):
        fcc.write_text(text + extra)
        out = tmp_path / ("out" + str(len(extra)))
        res = run_cli("fccompose", fcc, "-o", out, "-q")
        assert res.returncode == 0, res.stderr
        return read_log(out)

    log = run("")
    assert len(log) == 10
    assert all(int(r["intersecting_pairs"]) == 0 for r in log)
    assert all(0.5 <= float(r["min_edge_stretch"]) and float(r["max_edge_stretch"]) <= 1.5 for r in log)
    assert int(log[-1]["florets_present"]) == 33 and int(log[-1]["florets_waiting"]) == 0
    smaller = [int(r["florets_smaller"]) for r in log]
    assert smaller[-1] > smaller[5]  # made smaller after they emerged, not only when emerging
    never = run("crowded scales: 1\n")
    assert any(float(r["min_edge_stretch"]) < 0.5 or float(r["max_edge_stretch"]) > 1.5 for r in never)


@pytest.mark.slow
def test_florets_squeezed_hard_stay_whole(inputs, tmp_path):
    """The same head with florets 1.2 x their primordia and a thickness h of a tenth of a floret
    (before the whole-part fallback the per-vertex revert tore such florets and the solve diverged, to 1e11 units,
    within a few frames of their opening): now the florets of pairs still crossing are moved back
    whole along their own motion, so the run goes on collision-free with nothing torn.

    The collision response diverges here (no room: each round undoes the last), and until the
    retries stopped on a runaway and ended on their best round (resolve.RUNAWAY_FACTOR) the run
    took minutes (frame 8: 90 rounds ending with 426,428 pairs crossing, 160-275 s); now about
    15-25 s, and no step's rounds end with more pairs crossing than their first round found."""
    fcc = _small_dynamic_head(inputs, tmp_path, 1.2, spacing=0.01)
    fcc.write_text(fcc.read_text() + "run for number of frames: 9\n")
    out = tmp_path / "out"
    res = run_cli("fccompose", fcc, "-o", out, "-q")
    assert res.returncode == 0, res.stderr
    log = read_log(out)
    assert len(log) == 10
    assert all(int(r["intersecting_pairs"]) == 0 for r in log)
    # whole and in shape: florets with no room were made smaller (a torn floret: > 50)
    assert all(0.5 <= float(r["min_edge_stretch"]) and float(r["max_edge_stretch"]) <= 1.5 for r in log)
    assert int(log[-1]["florets_present"]) == 33
    assert sum(int(r["collisions_found"]) for r in log) > 100
    assert all(int(r["remaining_pairs"]) < int(r["collisions_found"]) for r in log if int(r["collisions_found"]))
    last = read_obj(sorted(out.glob("frame_*.obj"))[-1])
    assert np.ptp(last.vertices, axis=0).max() < 10.0


def test_a_torn_floret_stops_the_run_with_a_clear_error(inputs):
    """``SimulationDiverged`` names the frame and the florets whose edges are over 50 x their rest
    length (the last guard before anything exploded is written)."""
    from inflo.tools.fccompose.compose import Simulation, SimulationDiverged
    from inflo.tools.fccompose.model import build_model

    sim = Simulation(build_model(read_fcc(inputs["dir"] / "dense.fcc")))
    x = sim.initial_positions()
    sim.check_whole(x, 3.0)  # whole: nothing raised
    nv = len(inputs["frames"][0])
    x[nv + 5] += 1e3  # a vertex of floret 1 torn away
    with pytest.raises(SimulationDiverged, match=r"frame 3: .* florets 1 are over 50 times their rest length"):
        sim.check_whole(x, 3.0)


def test_undo_runaway_puts_back_only_florets_flung_over_half_their_size():
    """The guard after the internal solve (and each relaxation): a floret one of whose vertices the
    solve sent more than half the floret's size away takes back its positions from before the
    solve, every vertex of it; a floret moved less, and the other florets, keep the solve's."""
    from inflo.tools.fccompose.compose import _undo_runaway

    rng = np.random.default_rng(5)
    before = rng.random((30, 3))  # three florets of 10 vertices, each about 1 wide
    floret = np.repeat(np.arange(3), 10)
    x = before + rng.normal(0, 0.01, before.shape)
    solved = x.copy()
    x[3] += [0.2, 0.0, 0.0]  # floret 0: moved, but by less than half its size
    x[15] += [0.0, 5.0, 0.0]  # floret 1: flung
    expect = x.copy()
    expect[10:20] = before[10:20]
    assert _undo_runaway(x, np.arange(30), before, floret) == 1
    np.testing.assert_array_equal(x, expect)
    assert not np.array_equal(x[:10], solved[:10])
    assert _undo_runaway(x, np.arange(0), before[:0], floret[:0]) == 0


def test_phase_effect_each_floret_at_the_stage_its_age_gives(inputs, tmp_path):
    """phyllotaxis with ``development_frames`` -> fccompose: florets that emerged at staggered
    frames each sit, at the last frame, at their own developmental stage: every floret, mapped
    back by its placement, is the template at u = (last - frameStart) / N (florets small enough
    never to touch); the outer (older) florets are further open than the inner ones; and a
    ray/disk scale from the SCN reaches the canopy."""
    from inflo.formats.placement import placement_matrix
    from inflo.formats.rba import read_rba
    from inflo.formats.scn import read_scn, write_scn

    toml = (REPO / "pipelines" / "examples" / "phyllotaxis" / "dynamic_head.toml").read_text()
    toml = toml.replace("frames = 120", "frames = 20").replace("primordium_area = 0.002", "primordium_area = 0.03")
    toml = toml.replace("curve_times = [0.0, 1.0]", "curve_times = [0.0, 1.0]\ndevelopment_frames = 10")
    (tmp_path / "head.toml").write_text(toml)
    res = run_cli("phyllotaxis", tmp_path / "head.toml", "-o", tmp_path / "head", "-q")
    assert res.returncode == 0, res.stderr
    scene = read_scn(tmp_path / "head" / "scene.scn")
    starts = np.array([p.frame_start for p in scene.placements])
    assert all(p.frame_end - p.frame_start == 10 for p in scene.placements)
    assert starts.min() == 0 and starts.max() >= 6  # staggered emergence
    for p in scene.placements[::2]:  # every other floret at 1.5 x (as dimorph's ray scale would)
        p.scale = p.scale * 1.5
    write_scn(tmp_path / "head" / "scene.scn", scene)
    shutil.copytree(inputs["dir"] / "anim", tmp_path / "anim")
    shutil.copy(inputs["dir"] / "petal_base.txt", tmp_path / "petal_base.txt")
    write_fcc_text(tmp_path / "g.fcc", scene="head/scene.scn", sanity_every=5, spacing=0.001,
                   extra="rigid body animation: 1 0.1 0.1 0.1 head/rba head/scene.scn\n"
                         "run for number of frames: 12\n")
    out = tmp_path / "out"
    res = run_cli("fccompose", tmp_path / "g.fcc", "-o", out, "-q", "--strict")
    assert res.returncode == 0, res.stderr
    log = read_log(out)
    assert sum(int(r["collisions_found"]) for r in log) == 0  # apart: shapes are the templates'
    last = read_obj(out / "frame_0012.obj").vertices
    rba = read_rba(tmp_path / "head" / "rba" / "0012.rba", scene)
    tpl = opening_floret(N_FRAMES)[0]
    nv = len(tpl[0])
    opened = []
    for k, p in enumerate(scene.placements):
        u = min(max((12 - p.frame_start) / 10, 0.0), 1.0) * (N_FRAMES - 1)
        a = min(int(u), N_FRAMES - 2)
        local = (1 - (u - a)) * tpl[a] + (u - a) * tpl[a + 1]
        r = list(rba.ids).index(k)
        m = placement_matrix(rba.pos[r], np.asarray(rba.scale[r]) * 0.1 * p.scale, rba.up[r], rba.right[r])
        expect = local @ m[:3, :3].T + m[:3, 3]
        size = float(np.ptp(expect, axis=0).max())
        assert np.abs(last[k * nv:(k + 1) * nv] - expect).max() < 0.01 * size, k  # (stages differ by ~0.1)
        opened.append(u)
    # centripetal: the florets formed first (outer) are the most open
    assert opened[0] == N_FRAMES - 1 and opened[-1] < opened[0]


@pytest.mark.slow
def test_dense_growing_head_stays_in_shape_collision_free_and_whole(tmp_path):
    """The growing_head example made small for CI: the disk floret of
    pipelines/examples (polygonized as the example does), a centripetal dense head from
    phyllotaxis with the phase effect (36 frames, each floret opening over 20), fccompose with the
    example's parameters. Neighbouring corollas touch (collisions are found and resolved), and in
    every frame: no intersecting pair at the sanity checks, every edge within [0.5, 1.5] x its
    rest length, and at the end every floret present and whole (the florets emerge over more than
    half the run, so the outer ones are open at the end and the inner ones not: the phase effect
    itself is checked floret by floret in the test above)."""
    ex = REPO / "pipelines" / "examples"
    gh = ex / "growing_head"
    res = run_cli("floret-animate", ex / "disk_bud.floret", ex / "disk_open.floret", "--frames", "12",
                  "-o", tmp_path / "frames", "-q")
    assert res.returncode == 0, res.stderr
    res = run_cli("polygonize", tmp_path / "frames", "--lambda", "0.25", "--eta", gh / "lobe_eta.func",
                  "-o", tmp_path / "obj", "-q")
    assert res.returncode == 0, res.stderr
    toml = (ex / "phyllotaxis" / "dense_head.toml").read_text()
    assert "frames = 90" in toml and "development_frames = 50" in toml
    toml = toml.replace("frames = 90", "frames = 36").replace("development_frames = 50", "development_frames = 20")
    (tmp_path / "head.toml").write_text(toml)
    res = run_cli("phyllotaxis", tmp_path / "head.toml", "-o", tmp_path / "head", "-q")
    assert res.returncode == 0, res.stderr
    from inflo.formats.scn import read_scn
    scene = read_scn(tmp_path / "head" / "scene.scn")
    starts = np.array([p.frame_start for p in scene.placements])
    assert all(p.frame_end - p.frame_start == 20 for p in scene.placements)
    assert starts.max() - starts.min() > 18 and starts.max() > 36 - 20
    shutil.copy(gh / "floret.weights", tmp_path / "floret.weights")
    fcc = (gh / "growing.fcc").read_text().replace("../../../build/examples/growing_head/", "")
    assert "run for number of frames: 80" in fcc
    (tmp_path / "g.fcc").write_text(fcc.replace("run for number of frames: 80", "run for number of frames: 36"))
    res = run_cli("fccompose", tmp_path / "g.fcc", "-o", tmp_path / "out", "-q", "--strict")
    assert res.returncode == 0, res.stderr
    log = read_log(tmp_path / "out")
    assert len(log) == 37
    assert sum(int(r["collisions_found"]) for r in log) > 500  # crowded: corollas meet
    assert all(int(r["intersecting_pairs"]) in (-1, 0) for r in log)
    assert sum(int(r["intersecting_pairs"]) == 0 for r in log) >= 4  # the sanity checks ran
    lo = min(float(r["min_edge_stretch"]) for r in log)
    hi = max(float(r["max_edge_stretch"]) for r in log)
    assert 0.5 <= lo and hi <= 1.5, (lo, hi)
    last = log[-1]
    assert int(last["florets_waiting"]) == 0 and int(last["florets_smaller"]) == 0
    n = int(last["florets_present"])
    assert n > 100
    # every floret in the last frame, none torn: its own template's triangle count, exact check
    mesh = read_obj(tmp_path / "out" / "frame_0036.obj")
    tpl = read_obj(tmp_path / "obj" / "frame_0000.obj")
    assert len(mesh.faces) == n * len(tpl.faces)
    assert len(intersecting_pairs(mesh.vertices, mesh.faces)) == 0


def test_frames_option_overrides_the_run_length(inputs, tmp_path):
    out = tmp_path / "short"
    res = run_cli("fccompose", inputs["dir"] / "single.fcc", "-o", out, "-q", "--frames", "3")
    assert res.returncode == 0, res.stderr
    assert sorted(p.name for p in out.glob("frame_*.obj")) == [f"frame_{k:04d}.obj" for k in range(4)]
    res = run_cli("fccompose", inputs["dir"] / "single.fcc", "-o", tmp_path / "bad", "-q", "--frames", "-1")
    assert res.returncode == 2 and not (tmp_path / "bad").exists()


def test_updates_option_overrides_the_steps_per_frame(inputs, tmp_path):
    out = tmp_path / "u"
    res = run_cli("fccompose", inputs["dir"] / "single.fcc", "-o", out, "-q", "--frames", "2", "--updates", "3")
    assert res.returncode == 0, res.stderr
    with open(out / "log.csv", newline="") as fh:
        log = list(csv.DictReader(fh))
    assert [int(r["steps"]) for r in log[1:]] == [3, 3]
    res = run_cli("fccompose", inputs["dir"] / "single.fcc", "-o", tmp_path / "bad", "-q", "--updates", "0")
    assert res.returncode == 2 and not (tmp_path / "bad").exists()


def test_rba_matrices_of_all_florets_at_once_equal_the_one_by_one_placement(inputs, tmp_path):
    """Model.schedule places every rba: floret with one vectorized evaluation; it must give each
    floret's placement (:func:`_rba_matrix`: rows interpolated between RBA frames, the nearest
    present row before emergence, SCN and entry scales, Gram-Schmidt frame) to round-off."""
    from inflo.formats.fcc import read_fcc
    from inflo.tools.fccompose.model import build_model

    rng = np.random.default_rng(3)
    frames = []
    for f in range(5):
        ids = [0, 1] if f >= 2 else [0]
        up = rng.normal(size=(len(ids), 3))
        right = rng.normal(size=(len(ids), 3))
        frames.append(RbaFrame(ids, rng.normal(size=(len(ids), 3)), rng.uniform(0.5, 2.0, (len(ids), 3)), up, right))
    m = build_model(read_fcc(_rba_case(inputs, tmp_path, frames)))
    for frame in (0.0, 0.5, 1.0, 2.75, 4.0, 9.0):
        ids, mats = m._rba_matrices(frame)
        assert sorted(ids.tolist()) == [0, 1]
        for k, mat in zip(ids, mats):
            np.testing.assert_allclose(mat, m.matrix(m.florets[k], frame)[:3], rtol=0, atol=1e-13)


def test_resume_refuses_an_input_changed_since_the_interruption(inputs, tmp_path):
    """The resume fingerprint covers every input file: a scene edited between the interrupted run
    and --resume is named in a one-line error, exit 2."""
    d = tmp_path / "case"
    shutil.copytree(inputs["dir"], d)
    out = tmp_path / "out"
    res = run_cli("fccompose", d / "dense.fcc", "-o", out, "-q", "--frames", "2")
    assert res.returncode == 0, res.stderr
    scn = next(p for p in d.glob("*.scn"))
    scn.write_text(scn.read_text() + "# edited\n")
    res = run_cli("fccompose", d / "dense.fcc", "-o", out, "--resume", "-q")
    assert res.returncode == 2
    assert f"found {scn.name} changed since it was interrupted" in res.stderr, res.stderr


def test_a_gap_in_an_input_sequence_is_refused(inputs, tmp_path):
    """File NNNN is frame NNNN: a missing RBA file or animation frame would re-time everything
    after it silently; fccompose names the first missing file."""
    from inflo.formats.atomic import first_missing_frame

    assert first_missing_frame(["a/frame_0000.obj", "a/frame_0001.obj", "a/frame_0003.obj"]) == "frame_0002.obj"
    assert first_missing_frame(["1.obj", "2.obj", "3.obj"]) is None
    assert first_missing_frame(["1.obj", "2.obj"], start=0) == "0.obj"
    assert first_missing_frame(["x.obj", "frame_0002.obj"]) is None  # not one numbered sequence
    d = tmp_path / "case"
    shutil.copytree(inputs["dir"], d)
    frames = sorted((d / "anim").glob("frame_*.obj"))
    frames[5].unlink()
    res = run_cli("fccompose", d / "dense.fcc", "-o", tmp_path / "out", "-q")
    assert res.returncode == 2 and f"{frames[5].name} missing" in res.stderr, res.stderr
    assert not (tmp_path / "out").exists() or not list((tmp_path / "out").glob("*.obj"))


def test_written_frames_get_the_digits_that_keep_them_collision_free():
    """Two flat triangles 2e-7 apart (closer than 6 decimals): written with 6 decimals they would
    touch, so the frame is written with 9; far apart, with 6; crossing in the state, with 6."""
    from inflo.tools.fccompose.compose import written_format
    faces = np.array([[0, 1, 2], [3, 4, 5]])
    low = np.array([[0.1, 0.0000001, 0.1], [0.9, 0.0000001, 0.1], [0.5, 0.0000001, 0.9]])
    for gap, expected in ((2e-7, "%.9f"), (0.01, "%.6f")):
        x = np.vstack([low, low + [0.0, gap, 0.0]])
        assert written_format(x, faces) == expected
    crossing = np.vstack([low, [[0.5, -0.5, 0.5], [0.6, 0.5, 0.5], [0.4, 0.5, 0.45]]])
    assert written_format(crossing, faces) == "%.6f"


def _post(x: float, z: float, half: float = 0.05, y0: float = -0.3, y1: float = 1.5):
    """A closed square post (a stand-in pedicel) standing at (x, z) from y0 to y1."""
    import trimesh

    m = trimesh.creation.box(extents=[2 * half, y1 - y0, 2 * half])
    return ObjMesh(vertices=m.vertices + [x, 0.5 * (y0 + y1), z], faces=m.faces.astype(np.int32))


@pytest.mark.parametrize("obstacle", [True, False])
def test_an_obstacle_deflects_the_petals_and_is_not_written(inputs, tmp_path, obstacle):
    """A placement typed ``obstacle`` collides with the florets but is fixed and not written
    (formats/fcc.md "Obstacles"): an opening floret whose petal would sweep through a post beside
    it is stopped by it; the same post as a plain floret placement would be written (and, with no
    weight file, pushed); with no post the petal sweeps through where it stands."""
    from inflo.formats.scn import read_scn
    from inflo.tools.collide import intersecting_pairs_between
    from inflo.tools.fccompose.model import build_model

    # the post where a petal of the open floret reaches (its farthest tip's azimuth, at 0.75)
    alone = inputs["frames"][-1]
    tip = alone[np.argmax(np.hypot(alone[:, 0], alone[:, 2]))]
    d = tip[[0, 2]] / np.hypot(tip[0], tip[2])
    post = _post(0.75 * d[0], 0.75 * d[1])
    write_obj_sequence(tmp_path / "post", [post])
    shutil.copytree(inputs["dir"] / "anim", tmp_path / "anim")
    shutil.copy(inputs["dir"] / "petal_base.txt", tmp_path / "petal_base.txt")
    floret = inputs["placements"][0]
    holder = Placement("o", 1, [0, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0], material=floret.material,
                       type="obstacle" if obstacle else None)
    write_scene(tmp_path / "scene.scn", [floret, holder])
    write_fcc_text(tmp_path / "o.fcc", extra="animation: 1 1 1 1 post\n")
    out = tmp_path / "out"
    res = run_cli("fccompose", tmp_path / "o.fcc", "-o", out, "-q")
    assert res.returncode == 0, res.stderr
    paths, meshes = read_obj_sequence(out)
    nv = len(inputs["frames"][0])
    if obstacle:
        assert read_scn(tmp_path / "scene.scn").placements[1].type == "obstacle"
        model = build_model(read_fcc(tmp_path / "o.fcc"))
        assert model.obstacle_vertices.sum() == len(post.vertices)
        assert np.all(model.vertex_inv_mass[model.obstacle_vertices] == 0.0)
        for mesh in meshes:  # the floret alone is written, and never crosses the post
            assert len(mesh.vertices) == nv and mesh.faces.max() < nv
            assert len(intersecting_pairs_between(mesh.vertices, mesh.faces, post.vertices, post.faces)) == 0
        assert "1 florets and 1 obstacles (not written)" in (out / "frame_0000.obj").read_text()
    else:
        assert len(meshes[-1].vertices) == nv + len(post.vertices)
    # without the post, the open floret's petal sweeps through where the post stands
    assert len(intersecting_pairs_between(alone, inputs["faces"], post.vertices, post.faces)) > 0
