"""subdivide: collision-free Loop subdivision of canopies (thesis 4.4, fig. 4.8), CLI and sequences."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import REPO, no_partial_files, run_cli

from inflo.formats.obj import ObjMesh, read_obj, read_obj_sequence, write_obj, write_obj_sequence
from inflo.tools.collide import intersecting_pairs
from inflo.tools.subdivide.collisions import collision_resolver
from inflo.tools.subdivide.loop import loop_level
from inflo.tools.subdivide.smooth import plan_subdivision, subdivide_frames, subdivide_meshes


def corrugated_strip(nx, ny, amp, dz, refine=1, width=1.0, length=4.0):
    """A strip folded in a zigzag across x (nx coarse folds); ``refine`` splits it linearly, so a
    refined strip has exactly the coarse one's shape with more vertices."""
    xs_coarse = np.linspace(0, length, nx + 1)
    zs_coarse = np.where(np.arange(nx + 1) % 2 == 0, amp, -amp)
    xs = np.linspace(0, length, nx * refine + 1)
    zs = np.interp(xs, xs_coarse, zs_coarse)
    ys = np.linspace(0, width, ny * refine + 1)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    V = np.c_[X.ravel(), Y.ravel(), (np.broadcast_to(zs[:, None], X.shape) + dz).ravel()]
    n1 = len(ys)
    F = []
    for i in range(len(xs) - 1):
        for j in range(n1 - 1):
            a = i * n1 + j
            F += [[a, a + n1, a + n1 + 1], [a, a + n1 + 1, a + 1]]
    return V, np.array(F, dtype=np.int32)


def interlocking_petals(gap=0.08):
    """Fig. 4.8a: two coarse petals nested into each other's folds, collision-free. The lower one
    is finer, so plain Loop smoothing flattens the upper one's folds more and they cross."""
    A, FA = corrugated_strip(8, 2, 0.3, 0.0)
    B, FB = corrugated_strip(8, 2, 0.3, -gap, refine=2)
    return np.vstack([A, B]), np.vstack([FA, FB + len(A)]).astype(np.int32), len(FA)


def test_fig_4_8_interlocking_petals():
    V, F, _ = interlocking_petals()
    assert len(intersecting_pairs(V, F)) == 0  # (a) collision-free coarse arrangement
    plan = plan_subdivision(F, len(V), 2)
    plain, _ = subdivide_frames([V], plan)
    assert len(intersecting_pairs(plain[0], plan.faces)) > 0  # (b) plain Loop: new intersections
    handled, reports = subdivide_frames([V], plan, resolve=collision_resolver(spacing=0.004))
    assert len(intersecting_pairs(handled[0], plan.faces)) == 0  # (c) with collision handling
    assert sum(r.collision_constraints for r in reports) > 0
    # collision handling only changes what it must: most vertices reach their Loop positions
    moved = np.linalg.norm(handled[0] - plain[0], axis=1)
    assert np.mean(moved < 1e-9) > 0.5


def test_sequence_keeps_topology_and_vertex_order(tmp_path):
    V, F = corrugated_strip(4, 2, 0.2, 0.0)
    frames = [ObjMesh(np.round(V * (1 + 0.1 * k), 6), F, groups=["petal"], face_group=np.zeros(len(F), np.int32))
              for k in range(3)]
    write_obj_sequence(tmp_path / "in", frames)
    res = run_cli("subdivide", tmp_path / "in", "--levels", 2, "-o", tmp_path / "out", "--no-collisions", "-q")
    assert res.returncode == 0, res.stderr
    paths, out = read_obj_sequence(tmp_path / "out")
    assert [p.name for p in paths] == ["frame_0000.obj", "frame_0001.obj", "frame_0002.obj"]
    assert len(out[0].faces) == 16 * len(F) and all(m.same_topology(out[0]) for m in out)
    assert out[0].groups == ["petal"] and (out[0].face_group == 0).all()
    # frame k is frame 0 scaled: subdivision is linear, so it commutes with the scaling
    np.testing.assert_allclose(out[2].vertices, out[0].vertices * 1.2, atol=2e-6)
    assert no_partial_files(tmp_path / "out")


def test_sequence_whose_faces_grow_keeps_every_frame_like_its_own_subdivision(tmp_path):
    """A canopy whose florets emerge (fccompose rba: placements) keeps its vertices and gains
    faces: each run of frames of one topology is subdivided by its own plan, and each output frame
    equals the subdivision of that frame alone; a vertex no face uses yet stays where it is."""
    V, F = corrugated_strip(4, 2, 0.2, 0.0)
    W = V + [0.0, 2.0, 0.0]  # a second strip beside it, "emerging" at frame 2
    both = np.vstack([V, W])
    F2 = np.vstack([F, F + len(V)]).astype(np.int32)
    frames = [ObjMesh(np.round(both * (1 + 0.1 * k), 6), F if k < 2 else F2) for k in range(4)]
    write_obj_sequence(tmp_path / "in", frames)
    res = run_cli("subdivide", tmp_path / "in", "--levels", 1, "-o", tmp_path / "out", "--check")
    assert res.returncode == 0, res.stderr
    assert "level 1: %d faces" % (4 * len(F2)) in res.stderr
    _, out = read_obj_sequence(tmp_path / "out", same_topology=False)
    assert [len(m.faces) for m in out] == [4 * len(F)] * 2 + [4 * len(F2)] * 2
    for k in (1, 3):
        alone = tmp_path / f"alone_{k}.obj"
        res = run_cli("subdivide", tmp_path / "in" / f"frame_{k:04d}.obj", "--levels", 1, "-o", alone, "-q")
        assert res.returncode == 0, res.stderr
        one = read_obj(alone)
        np.testing.assert_array_equal(one.faces, out[k].faces)
        np.testing.assert_allclose(one.vertices, out[k].vertices, atol=2e-6)
    # the second strip's vertices, used by no face in frame 1, are not moved by the smoothing
    np.testing.assert_allclose(out[1].vertices[len(V):len(both)], frames[1].vertices[len(V):], atol=2e-6)


def test_cli_single_file_with_collisions_and_check(tmp_path):
    V, F, n_a = interlocking_petals()
    group = np.r_[np.zeros(n_a, np.int32), np.ones(len(F) - n_a, np.int32)]
    write_obj(tmp_path / "petals.obj", ObjMesh(V, F, groups=["floret_0", "floret_1"], face_group=group))
    res = run_cli("subdivide", tmp_path / "petals.obj", "--levels", 2, "--spacing", 0.004, "--check",
                  "-o", tmp_path / "smooth.obj")
    assert res.returncode == 0, res.stderr
    assert "level 2: 2560 faces" in res.stderr and "intersecting triangle pairs per frame: max 0" in res.stderr
    m = read_obj(tmp_path / "smooth.obj")
    assert m.n_faces == 2560 and len(intersecting_pairs(m.vertices, m.faces)) == 0
    assert m.groups == ["floret_0", "floret_1"] and (np.bincount(m.face_group) == [16 * n_a, 16 * (len(F) - n_a)]).all()


def test_cli_non_manifold_error_and_no_output(tmp_path):
    write_obj(tmp_path / "nm.obj", ObjMesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], float),
                                           [[0, 1, 2], [1, 0, 3], [0, 1, 4]]))
    res = run_cli("subdivide", tmp_path / "nm.obj", "--levels", 1, "--no-collisions", "-o", tmp_path / "o.obj")
    assert res.returncode == 2
    assert "nm.obj: edge 0-1 (0-based vertex indices) is shared by 3 triangles" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "o.obj").exists()


def test_matches_plain_loop_when_no_collisions_arise():
    """Far-apart petals: the collision step leaves the Loop positions untouched."""
    A, FA = corrugated_strip(4, 2, 0.2, 0.0)
    V = np.vstack([A, A + [0, 0, 5.0]])
    F = np.vstack([FA, FA + len(A)])
    lv = loop_level(F, len(V))
    out, rep = subdivide_frames([V], plan_subdivision(F, len(V), 1), resolve=collision_resolver(spacing=0.01))
    np.testing.assert_array_equal(out[0], lv.loop(V))
    assert rep[0].collision_constraints == 0


# ---------------------------------------------------------------- duplicated vertices

def _duplicated(kind):
    """The lily's last canopy frame with one vertex duplicated: 'seam' (half the triangles round it
    use the copy) or 'sliver' (a zero-area triangle between the vertex and its copy)."""
    from inflo.formats.obj import read_obj

    m = read_obj(REPO / "tests" / "golden" / "lily" / "canopy" / "frame_0099.obj")
    V, F = m.vertices.copy(), m.faces.copy()
    a = F[100][0]
    V = np.vstack([V, V[a]])
    a2 = len(V) - 1
    if kind == "seam":
        around = np.flatnonzero((F == a).any(axis=1))
        for t in around[: len(around) // 2]:
            F[t][F[t] == a] = a2
    else:
        _, b, c = F[100]
        F[100] = [a2, b, c]
        F = np.vstack([F, [[a, a2, c]]])
    return ObjMesh(V, F)


@pytest.mark.parametrize("kind", ["seam", "sliver"])
def test_duplicated_vertex_is_welded_and_the_result_collision_free(kind):
    from inflo.tools.collide import intersecting_pairs
    from inflo.tools.subdivide.collisions import collision_resolver, default_spacing

    m = _duplicated(kind)
    assert len(intersecting_pairs(m.vertices, m.faces)) > 0  # the duplicate's triangles touch
    notes = []
    resolve = collision_resolver(spacing=default_spacing(m.vertices))
    (out,), _ = subdivide_meshes([m], 1, resolve=resolve, name="dup.obj", notes=notes)
    assert notes == ["dup.obj: welded 1 vertices lying at the same point as another in every frame"
                     + (", dropped 1 zero-area triangles" if kind == "sliver" else "")]
    assert len(out.faces) == 4 * 3780 and len(intersecting_pairs(out.vertices, out.faces)) == 0


def test_weld_only_vertices_coincident_in_every_frame():
    from inflo.tools.subdivide.smooth import weld_coincident

    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0], [1, 1, 0]], float)
    F = np.array([[0, 1, 2], [3, 4, 2]])
    w = weld_coincident([V, V + 1.0], F)
    assert (w.welded, w.dropped, w.keep.tolist(), w.faces.tolist()) == (1, 0, [0, 1, 2, 4], [[0, 1, 2], [1, 3, 2]])
    V2 = V.copy()
    V2[3] = [2, 0, 0]  # apart in the second frame: a bud tip that opens, not a seam
    w = weld_coincident([V, V2], F)
    assert w.welded == 0 and w.faces.tolist() == F.tolist()


def test_cli_writes_a_frame_with_pairs_left_with_the_digits_that_keep_it_clear(tmp_path, monkeypatch):
    """A frame where the collision response left pairs closer than the spacing is written with as
    many decimals as keep it collision-free: here a triangle's tip 4e-7 above another's face, which
    six decimals would put on it (touching: an intersecting pair for every reader)."""
    from click.testing import CliRunner

    from inflo.tools.subdivide import cli as sub_cli
    from inflo.tools.subdivide.smooth import LevelReport

    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 4e-7], [0.3, 0.2, 1], [0.2, 0.3, 1]], float)
    F = np.array([[0, 1, 2], [3, 4, 5]])
    mesh = ObjMesh(V, F, groups=["floret_0", "floret_1"], face_group=np.array([0, 1], np.int32))
    assert len(intersecting_pairs(V, F)) == 0
    rounded = np.array([[float(f"{x:.6f}") for x in row] for row in V])
    assert len(intersecting_pairs(rounded, F)) == 1  # what six decimals would write
    write_obj(tmp_path / "in.obj", mesh)
    for left, clear in ((1, True), (0, False)):
        monkeypatch.setattr(sub_cli, "subdivide_meshes", lambda meshes, levels, left=left, **kw: (
            [mesh], [LevelReport(0, 1, 2, 1, left)]))
        out = tmp_path / f"out{left}.obj"
        res = CliRunner().invoke(sub_cli.main, [str(tmp_path / "in.obj"), "--check", "-o", str(out)])
        assert res.exit_code == 0, res.output
        m = read_obj(out)
        assert (len(intersecting_pairs(m.vertices, m.faces)) == 0) == clear
        # --check counts the numbers as written
        assert f"pairs per frame: max {0 if clear else 1}" in res.output
