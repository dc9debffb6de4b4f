"""fccompose's Model/State/Control split: assemble_model without files, Schedule,
State and the resume files it is written to and read from."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from inflo.formats.errors import FormatError, InputError
from inflo.formats.fcc import CanopyParams
from inflo.formats.placement import placement_matrix
from inflo.formats.rba import RbaFrame
from inflo.formats.scn import Placement, Scene
from inflo.tools.fccompose.compose import Simulation, _load_state, _save_state
from inflo.tools.fccompose.model import RbaSequence, Schedule, State, Template, assemble_model
from inflo.tools.pbd.constraints import signed_dihedral_angle, wrap_angle

# a unit square of two triangles in its local frame, flat at frame 0 and folded along its
# diagonal at frame 1; vertices 0 and 1 (one edge) are fixed
SQUARE = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]], float)
FOLDED = SQUARE + np.array([[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0.5, 0]])
FACES = np.array([[0, 1, 2], [0, 2, 3]])


def _template(fixed=(0, 1)) -> Template:
    return Template.from_frames(0, np.stack([SQUARE, FOLDED]), FACES, fixed=fixed, k_stretch=0.9, k_bend=0.8)


def _ca(x: float, material: int) -> Placement:
    return Placement("ca", 0, [x, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0], frame_start=0, frame_end=4,
                     material=material)


def _model(**params):
    scenes = {Path("a.scn"): Scene([_ca(0.0, 1), _ca(3.0, 2)])}
    return assemble_model(CanopyParams(**params), scenes, {0: _template()})


def test_assemble_model_without_files():
    m = _model()
    assert m.n_vertices == 8 and m.n_triangles == 4 and m.n_frames == 4  # to the end of the ca: window
    np.testing.assert_array_equal(m.tri_indices, np.concatenate([FACES, FACES + 4]))
    np.testing.assert_array_equal(m.tri_floret, [0, 0, 1, 1])
    np.testing.assert_array_equal(m.vertex_floret, [0] * 4 + [1] * 4)
    np.testing.assert_array_equal(m.floret_vertex_offset, [0, 4, 8])
    np.testing.assert_array_equal(m.vertex_fixed, [0, 1, 4, 5])
    np.testing.assert_array_equal(m.vertex_inv_mass, [0, 0, 1, 1, 0, 0, 1, 1])
    assert len(m.edge_indices) == 10 and len(m.hinge_indices) == 2  # 5 edges and 1 hinge a square
    np.testing.assert_array_equal(m.edge_stiffness, 0.9)
    np.testing.assert_array_equal(m.hinge_stiffness, 0.8)
    assert m.template_offset == {0: 0} and m.template_x.shape == (8, 3)
    assert [fl.index for fl in m.florets] == [0, 1] and m.florets[1].vertex_offset == 4
    names, face = m.face_materials
    assert names == ["mtl1", "mtl2"] and face.tolist() == [0, 0, 1, 1]
    assert _model(run_frames=2).n_frames == 2


def test_schedule_is_a_named_tuple_and_places_the_templates():
    m = _model()
    sched = m.schedule(2.0)  # u = 2/4 of the two template frames
    assert isinstance(sched, Schedule)
    base_a, base_b, alpha, matrix = sched  # unpacks like the tuple it was
    np.testing.assert_array_equal(base_a, [0, 0])
    np.testing.assert_array_equal(base_b, [4, 4])
    np.testing.assert_allclose(alpha, [0.5, 0.5])
    np.testing.assert_allclose(matrix[1], placement_matrix([3, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0])[:3])
    x = np.zeros((8, 3))
    m.template_positions(sched, vertices=np.arange(8, dtype=np.int32), out=x)
    half = 0.5 * (SQUARE + FOLDED)
    np.testing.assert_allclose(x, np.concatenate([half, half + [3, 0, 0]]), atol=1e-15)
    rest_l, rest_a = np.zeros(len(m.edge_indices)), np.zeros(len(m.hinge_indices))
    m.rest_values(sched, edge_rest_length=rest_l, hinge_rest_angle=rest_a)
    # lengths (eq. 3.11) and angles (eq. 3.13) of the two template frames, interpolated
    local = m.edge_indices % 4
    length = lambda p: np.linalg.norm(p[local[:, 0]] - p[local[:, 1]], axis=1)
    np.testing.assert_allclose(rest_l, 0.5 * (length(SQUARE) + length(FOLDED)), rtol=1e-14)
    h = m.hinge_indices[0] % 4
    th_a, th_b = (signed_dihedral_angle(*p[h]) for p in (SQUARE, FOLDED))
    np.testing.assert_allclose(rest_a, wrap_angle(th_a + 0.5 * wrap_angle(th_b - th_a)), rtol=1e-14)
    assert abs(rest_a[0]) > 0.1


def test_simulation_of_an_assembled_model_grows_the_templates():
    """Usable without files: frame 0 is the placed templates; a step onto frame 4, the last
    template frame, puts the two florets, far apart, on their folded templates (the prediction
    lands an undeformed floret on its template, where the rest values hold)."""
    m = _model()
    sim = Simulation(m)
    st = sim.state
    assert isinstance(st, State) and st.frame == 0 and st.born.all()
    np.testing.assert_allclose(st.vertex_x, np.concatenate([SQUARE, SQUARE + [3, 0, 0]]), atol=1e-15)
    np.testing.assert_array_equal(sim.initial_positions(), st.vertex_x)
    res, waiting = sim.advance(0.0, 4.0, {})
    assert waiting == [] and not len(res.remaining)
    np.testing.assert_allclose(sim.state.vertex_x, np.concatenate([FOLDED, FOLDED + [3, 0, 0]]), atol=1e-9)


def test_rba_florets_emerge_at_their_first_listed_frame():
    row = lambda ids: RbaFrame(ids, [[2.0 * i, 0, 0] for i in ids], [[1, 1, 1]] * len(ids),
                               [[0, 1, 0]] * len(ids), [[1, 0, 0]] * len(ids))
    frames = [row([0]), row([0]), row([0, 1])]
    scene = Scene([Placement("rba", 0, [0, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0], frame_start=0, frame_end=2)
                   for _ in range(2)])
    seq = RbaSequence([Path(f"rba/{k:04d}.rba") for k in range(3)], frames, np.ones(3))
    m = assemble_model(CanopyParams(), {Path("s.scn"): scene}, {0: _template()}, {Path("s.scn"): seq})
    np.testing.assert_array_equal(m.floret_birth, [0, 2])
    assert m.n_frames == 2
    st = State.at_start(m)
    np.testing.assert_array_equal(st.born, [True, False])
    np.testing.assert_allclose(st.vertex_x[4:], SQUARE + [2, 0, 0])  # waits at its first RBA pose
    with pytest.raises(FormatError, match="'rigid body animation' line"):
        assemble_model(CanopyParams(), {Path("s.scn"): scene}, {0: _template()})


def test_a_placement_naming_no_template_is_refused():
    scenes = {Path("a.scn"): Scene([_ca(0.0, 1), Placement("ca", 7, [0, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0])])}
    with pytest.raises(FormatError, match=r"a.scn: expected placement ids naming .* found id 7 \(placement 1"):
        assemble_model(CanopyParams(), scenes, {0: _template()})


def test_state_files_keep_their_format(tmp_path):
    """The resume files are written from a State and read into one: the same files and json keys
    as before the State existed (run.json: fingerprint, frame, not_emerged, emerged_smaller; the
    positions as state/frame_NNNN.npy), so a folder an older fccompose wrote still resumes."""
    m = _model()
    nf, n = len(m.florets), m.n_vertices
    x = np.random.default_rng(1).normal(size=(n, 3))
    st = State(x, 3, np.array([True, False]), np.array([0.75, 1.0]), np.array([1.5, 0.0]))
    (tmp_path / "frame_0003.obj").write_text("")
    _save_state(tmp_path, st, "abc")
    assert (tmp_path / "state" / "run.json").read_text() == (
        '{"fingerprint": "abc", "frame": 3, "not_emerged": [1], "emerged_smaller": [[0, 0.75, 1.5]]}\n')
    back = _load_state(tmp_path, "abc", m)
    assert back.frame == 3 and back.vertex_x.tobytes() == x.tobytes()
    np.testing.assert_array_equal(back.born, st.born)
    np.testing.assert_array_equal(back.emerge_scale, st.emerge_scale)
    np.testing.assert_array_equal(back.emerge_frame, st.emerge_frame)
    # everything present at its own size: the two optional keys are left out
    _save_state(tmp_path, State(x, 4, np.ones(nf, bool), np.ones(nf), np.zeros(nf)), "abc")
    assert json.loads((tmp_path / "state" / "run.json").read_text()) == {"fingerprint": "abc", "frame": 4}
    assert sorted(p.name for p in (tmp_path / "state").iterdir()) == ["frame_0004.npy", "run.json"]
    assert _load_state(tmp_path, "abc", m) is None  # frame_0004.obj is missing: nothing to resume
    with pytest.raises(InputError, match="different parameters"):
        _load_state(tmp_path, "other", m)


def test_rest_values_in_parallel_blocks_equal_one_serial_pass():
    """model.rest_values runs blocks of edges and hinges in parallel; every value must be the one
    serial pass gives, bit for bit (florets whose time sits on a template frame, alpha 0, too)."""
    from inflo.tools.fccompose import model as M

    rng = np.random.default_rng(0)
    nf, per = 50, 40
    tx = rng.normal(size=(nf * per * 2, 3))
    vf = np.repeat(np.arange(nf), per).astype(np.int64)
    off = (np.arange(nf) * per).astype(np.int64)
    ba = np.zeros(nf, np.int64)
    bb = np.full(nf, nf * per, np.int64)
    al = rng.random(nf)
    al[::3] = 0.0
    mat = rng.normal(size=(nf, 3, 4))
    e = np.array([(f * per + k, f * per + k + 1) for f in range(nf) for k in range(per - 3)], np.int32)
    h = np.array([(f * per + k, f * per + k + 1, f * per + k + 2, f * per + k + 3)
                  for f in range(nf) for k in range(per - 3)], np.int32)
    lengths, angles = np.empty(len(e)), np.empty(len(h))
    M.rest_values(tx, vf, off, ba, bb, al, mat, e, h, lengths, angles)
    ref_l, ref_a = np.empty(len(e)), np.empty(len(h))
    M._rest_lengths(tx, vf, off, ba, bb, al, mat, e, ref_l, 0, len(e))
    M._rest_angles(tx, vf, off, ba, bb, al, mat, h, ref_a, 0, len(h))
    assert lengths.tobytes() == ref_l.tobytes() and angles.tobytes() == ref_a.tobytes()
    # the lengths are those of the mapped, interpolated template
    # (template rows: the frame's base row + the vertex's index within its floret)
    f, k = 1, 5
    a = (1 - al[f]) * np.linalg.norm(mat[f, :, :3] @ (tx[k] - tx[k + 1])) + al[f] * np.linalg.norm(
        mat[f, :, :3] @ (tx[nf * per + k] - tx[nf * per + k + 1]))
    assert abs(lengths[f * (per - 3) + k] - a) < 1e-12
