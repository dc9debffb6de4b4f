"""Nested scenes in fccompose (thesis ch. 8: "a SCN file instantiates a rigid body
animation of an inflorescence described in another SCN file").

- a two-level scene (an outer scene of placements naming a ``rigid body animation`` entry, whose
  scene is a small dynamic head) gives the same canopy as the equivalent flat scene written out by
  hand (every inner floret's RBA rows composed with its outer placement), frame by frame, with
  collisions between florets of the two sub-inflorescences;
- the inner scene's clock starts at the outer placement's ``frameStart``: a sub-inflorescence
  placed with ``ca: 3 ...`` emerges and develops three frames late;
- three levels compose (outer ``o:`` of a middle scene of ``o:`` placements of an inner head);
- a scene that contains itself is refused with a one-line error (exit 2).
"""
from __future__ import annotations

import numpy as np
from conftest import run_cli

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.formats.placement import placement_matrix
from inflo.formats.rba import RbaFrame, write_rba_sequence
from inflo.formats.scn import Placement
from inflo.tools.testing.florets import opening_floret, write_fcc_text, write_floret_animation, write_scene

N_FRAMES = 6


def _axes(angle_deg):
    """(up, right) of a placement turned by angle about +Y... tilted: up in the x-y plane."""
    a = np.radians(angle_deg)
    up = np.array([np.sin(a), np.cos(a), 0.0])
    right = np.array([np.cos(a), -np.sin(a), 0.0])
    return up, right


def _inner(n_frames=N_FRAMES):
    """An inner head: 3 rba: florets 1.5 apart along z, growing 1 -> 1.2, emerging at frames 0, 0, 2."""
    pl = [Placement("rba", 0, [0, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0], frame_start=s, frame_end=s + n_frames - 1)
          for s in (0, 0, 2)]
    frames = []
    for f in range(n_frames):
        ids = [0, 1] + ([2] if f >= 2 else [])
        s = 1.0 + 0.2 * f / (n_frames - 1)
        frames.append(RbaFrame(ids, [[0.0, 0.0, 1.5 * i] for i in ids], [[s, s, s]] * len(ids),
                               [[0, 1, 0]] * len(ids), [[1, 0, 0]] * len(ids)))
    return pl, frames


# the outer placements: position, uniform scale, tilt (degrees)
OUTER = [([0.0, 0.0, 0.0], 1.0, 0.0), ([0.0, 0.35, 4.2], 0.9, 20.0)]


def _compose(outer_m, fr, row):
    """The flat RBA row of an inner row ``row`` of frame ``fr`` under the outer matrix."""
    m = outer_m @ placement_matrix(fr.pos[row], fr.scale[row], fr.up[row], fr.right[row])
    s = outer_m[:3, :3].dot([1.0, 0, 0])
    k = float(np.linalg.norm(s))  # the outer scale (uniform)
    up = m[:3, 1] / np.linalg.norm(m[:3, 1])
    right = m[:3, 0] / np.linalg.norm(m[:3, 0])
    return m[:3, 3], fr.scale[row] * k, up, right


def _setup(tmp_path):
    frames, faces, fixed = opening_floret(N_FRAMES)
    write_floret_animation(tmp_path / "anim", frames, faces, fixed, tmp_path / "petal_base.txt")
    inner_pl, inner_frames = _inner()
    write_scene(tmp_path / "inner.scn", inner_pl)
    write_rba_sequence(tmp_path / "rba_inner", inner_frames)
    outer = []
    for pos, s, tilt in OUTER:
        up, right = _axes(tilt)
        outer.append(Placement("o", 7, pos, [s, s, s], up, right))
    write_scene(tmp_path / "outer.scn", outer)
    write_fcc_text(tmp_path / "nested.fcc", scene="outer.scn", spacing=0.005,
                   extra="rigid body animation: 7 1 1 1 rba_inner inner.scn\n")
    # the same canopy written out flat: outer placement j's copy of inner floret i is floret 3 j + i
    flat_pl, flat_frames = [], []
    for _ in OUTER:
        for p in inner_pl:
            flat_pl.append(Placement("rba", 0, [0, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0],
                                     frame_start=p.frame_start, frame_end=p.frame_end))
    for fr in inner_frames:
        ids, rows = [], []
        for j, (pos, s, tilt) in enumerate(OUTER):
            up, right = _axes(tilt)
            om = placement_matrix(pos, [s, s, s], up, right)
            for r, i in enumerate(fr.ids):
                ids.append(3 * j + int(i))
                rows.append(_compose(om, fr, r))
        flat_frames.append(RbaFrame(ids, [r[0] for r in rows], [r[1] for r in rows], [r[2] for r in rows],
                                    [r[3] for r in rows]))
    write_scene(tmp_path / "flat.scn", flat_pl)
    write_rba_sequence(tmp_path / "rba_flat", flat_frames)
    write_fcc_text(tmp_path / "flat.fcc", scene="flat.scn", spacing=0.005,
                   extra="rigid body animation: 7 1 1 1 rba_flat flat.scn\n")
    return tmp_path / "nested.fcc", tmp_path / "flat.fcc"


def _run(fcc, out):
    res = run_cli("fccompose", "-q", fcc, "-o", out)
    assert res.returncode == 0, res.stderr
    return [read_obj(p) for p in list_obj_sequence(out)]


def test_two_level_scene_gives_the_flat_scenes_canopy(tmp_path):
    """Compared with ``collisions: off`` (the composition of the placements alone: with contacts,
    rounding differences of the two compositions grow through the collision response), then run
    with collisions: the sub-inflorescences' florets collide."""
    nested, flat = _setup(tmp_path)
    on = nested.read_text()
    for f in (nested, flat):
        f.write_text(f.read_text() + "collisions: off\n")
    a = _run(nested, tmp_path / "out_nested_off")
    b = _run(flat, tmp_path / "out_flat")
    nested.write_text(on)
    _run(nested, tmp_path / "out_nested")
    assert len(a) == len(b) >= N_FRAMES
    for ma, mb in zip(a, b):
        np.testing.assert_array_equal(ma.faces, mb.faces)
        assert ma.groups == mb.groups
        np.testing.assert_allclose(ma.vertices, mb.vertices, atol=2e-6)
    # the late floret of each copy emerges at frame 2: its faces are absent before
    assert len(a[1].faces) < len(a[2].faces)
    # the two sub-inflorescences meet: their florets collide (the log counts contacts)
    import csv
    with open(tmp_path / "out_nested" / "log.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert sum(int(r["collisions_found"]) for r in rows) > 0


def test_inner_clock_starts_at_the_outer_placements_frame_start(tmp_path):
    nested, _ = _setup(tmp_path)
    # the second copy placed with ca: 3 ...: its florets emerge 3 frames late and develop late
    text = (tmp_path / "outer.scn").read_text().splitlines()
    lines = [ln for ln in text if ln.startswith("o:")]
    second = lines[1].replace("o:", "ca:", 1) + " 3 20"
    (tmp_path / "outer.scn").write_text("\n".join([ln for ln in text if ln != lines[1]] + [second]) + "\n")
    meshes = _run(nested, tmp_path / "out")
    groups_at = [set(m.groups) for m in meshes]
    assert "floret_3" not in groups_at[2] and "floret_3" in groups_at[3]  # emerges at 0 + 3
    assert "floret_5" not in groups_at[4] and "floret_5" in groups_at[5]  # emerges at 2 + 3
    assert "floret_2" in groups_at[2]  # the first copy's late floret: at its own frame 2


def test_three_levels_compose(tmp_path):
    frames, faces, fixed = opening_floret(2)
    write_floret_animation(tmp_path / "anim", frames, faces, fixed, tmp_path / "petal_base.txt")
    write_scene(tmp_path / "inner.scn", [Placement("o", 0, [0.5, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0])])
    write_scene(tmp_path / "middle.scn", [Placement("o", 8, [0, 0, 3.0 * k], [0.5, 0.5, 0.5], [0, 1, 0], [1, 0, 0])
                                          for k in range(2)])
    write_scene(tmp_path / "outer.scn", [Placement("o", 9, [10.0 * k, 0, 0], [2, 2, 2], [0, 1, 0], [1, 0, 0])
                                         for k in range(2)])
    write_rba_sequence(tmp_path / "rba_e", [RbaFrame()] * 2)
    write_fcc_text(tmp_path / "three.fcc", scene="outer.scn",
                   extra="rigid body animation: 8 1 1 1 rba_e inner.scn\nrigid body animation: 9 1 1 1 rba_e middle.scn\n")
    meshes = _run(tmp_path / "three.fcc", tmp_path / "out")
    m = meshes[0]
    assert len(m.groups) == 4  # 2 outer x 2 middle x 1 inner
    tpl = frames[0]
    nv = len(tpl)
    for k, (ox, mz) in enumerate([(0.0, 0.0), (0.0, 3.0), (10.0, 0.0), (10.0, 3.0)]):
        # outer scale 2, middle scale 0.5: the floret at its own size, at outer + 2 (middle + 0.5 inner)
        expect = tpl + [ox + 2 * 0.5 * 0.5, 0.0, 2 * mz]
        np.testing.assert_allclose(m.vertices[k * nv:(k + 1) * nv], expect, atol=1e-5)


def test_a_scene_containing_itself_is_refused(tmp_path):
    frames, faces, fixed = opening_floret(2)
    write_floret_animation(tmp_path / "anim", frames, faces, fixed, tmp_path / "petal_base.txt")
    write_scene(tmp_path / "loop.scn", [Placement("o", 8, [0, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0])])
    write_scene(tmp_path / "outer.scn", [Placement("o", 8, [0, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0])])
    write_rba_sequence(tmp_path / "rba_e", [RbaFrame()] * 2)
    write_fcc_text(tmp_path / "loop.fcc", scene="outer.scn", extra="rigid body animation: 8 1 1 1 rba_e loop.scn\n")
    res = run_cli("fccompose", "-q", tmp_path / "loop.fcc", "-o", tmp_path / "out")
    assert res.returncode == 2, res.stderr
    line = res.stderr.strip()
    assert len(line.splitlines()) == 1 and "inside itself" in line and "loop.scn" in line
