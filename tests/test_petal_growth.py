"""Petals that grow with a floret's petal factor (thesis fig. 6.4c: "the size of the enlarged petals
is proportional to the amount of available space", only the petals, not the whole floret):
formats (fcc ``petal weight``, SCN ``#@ petal:``, petal weight files), fccompose's grown template
copies, and dimorph's ``--petal-size`` and ``--orient-rays``."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import run_cli

from inflo.formats.errors import FormatError, InputError
from inflo.formats.fcc import read_fcc, write_fcc
from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.formats.scn import Group, Placement, Scene, read_scn, write_scn
from inflo.formats.weights import read_petal_weight_file
from inflo.tools.dimorph.dimorph import DimorphOptions, dimorph_scene
from inflo.tools.fccompose.model import Template
from inflo.tools.testing.florets import opening_floret, write_fcc_text, write_floret_animation, write_scene

N_FRAMES = 6


def test_petal_weight_file_reads_ids_and_weights(tmp_path):
    p = tmp_path / "w.petals"
    p.write_text("# petals\n0 0.5\n3 1   # tip\n\n2 0\n")
    np.testing.assert_array_equal(read_petal_weight_file(p, 5), [0.5, 0.0, 0.0, 1.0, 0.0])


@pytest.mark.parametrize("text, expected", [
    ("0 1.5\n", "a weight in [0, 1]"),
    ("0 -0.1\n", "a weight in [0, 1]"),
    ("0 nan\n", "a weight in [0, 1]"),
    ("7 0.5\n", "a vertex id in 0..4"),
    ("1 0.5\n1 0.2\n", "each vertex id once"),
    ("1\n", "'vertex_id weight'"),
    ("x 0.5\n", "a vertex id (integer)"),
    ("1 heavy\n", "a weight (number in [0, 1])"),
])
def test_petal_weight_file_rejects_bad_lines(tmp_path, text, expected):
    p = tmp_path / "w.petals"
    p.write_text(text)
    with pytest.raises(FormatError, match=expected.replace("(", r"\(").replace(")", r"\)").replace("[", r"\[")
                       .replace("]", r"\]")):
        read_petal_weight_file(p, 5)


def test_fcc_petal_weight_key_round_trips(tmp_path):
    (tmp_path / "a.fcc").write_text("animation: 0 1 1 1 anim\nanimation: 1 1 1 1 anim\npetal weight: 1 big.petals\n"
                                    "scene file path: s.scn\n")
    params = read_fcc(tmp_path / "a.fcc")
    assert set(params.petal_weights) == {1}
    assert params.petal_weights[1].raw == "big.petals"
    write_fcc(tmp_path / "b.fcc", params)
    assert "petal weight: 1 big.petals" in (tmp_path / "b.fcc").read_text()
    assert read_fcc(tmp_path / "b.fcc").petal_weights[1].raw == "big.petals"


def test_fcc_petal_weight_for_an_unknown_id_is_refused(tmp_path):
    with pytest.raises(FormatError, match="petal weight"):
        (tmp_path / "a.fcc").write_text("animation: 0 1 1 1 anim\npetal weight: 3 big.petals\n")
        read_fcc(tmp_path / "a.fcc")


def test_scn_petal_factor_round_trips_and_is_checked(tmp_path):
    sc = Scene([Placement("o", 0, [0, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0], petal=2.5)])
    write_scn(tmp_path / "a.scn", sc)
    assert "#@ petal: 2.5" in (tmp_path / "a.scn").read_text()
    assert read_scn(tmp_path / "a.scn").placements[0].petal == pytest.approx(2.5)
    (tmp_path / "b.scn").write_text("o: 0 0 0 0 1 1 1 0 1 0 1 0 0\n#@ petal: 0\n")
    with pytest.raises(FormatError, match="a petal factor in"):
        read_scn(tmp_path / "b.scn")


def test_with_petals_scales_weighted_vertices_about_the_origin():
    frames = np.array([[[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]]])
    t = Template.from_frames(0, frames, [[0, 1, 2]])
    t.petal_weight = np.array([1.0, 0.5, 0.0])
    g = t.with_petals(3.0)
    np.testing.assert_allclose(g.frames[0], [[3.0, 0, 0], [0, 4.0, 0], [0, 0, 3.0]])
    assert g.key == (0, 3.0) and t.key == 0
    assert t.with_petals(1.0) is t
    np.testing.assert_array_equal(g.edge_indices, t.edge_indices)


def _floret_files(tmp_path):
    frames, faces, fixed = opening_floret(N_FRAMES)
    write_floret_animation(tmp_path / "anim", frames, faces, fixed, tmp_path / "petal_base.txt")
    # petal weights: 0 at the fixed base rows, rising to 1 at the tips (by distance from the axis)
    v = frames[-1]
    r = np.hypot(v[:, 0], v[:, 2])
    w = np.clip((r - r.min()) / (r.max() - r.min()), 0.0, 1.0)
    w[fixed] = 0.0
    (tmp_path / "anim.petals").write_text("\n".join(f"{i} {x:.6f}" for i, x in enumerate(w)) + "\n")
    return frames, faces, fixed, w


def petal_against_pre_grown(tmp_path, faces, grown, extra: str = "") -> dict:
    """Two canopies of two florets each over N_FRAMES (the animation of :func:`_floret_files` in
    ``tmp_path``): "petal", floret 0 with '#@ petal: 1.8', its weights and the fcc lines ``extra``;
    "pre", floret 0 a plain placement of the animation ``grown`` (its frames grown beforehand);
    floret 1 plain in both. Returns each canopy's OBJ frames."""
    write_floret_animation(tmp_path / "grown", grown, faces)
    up, right, end = [0, 1, 0], [1, 0, 0], N_FRAMES - 1
    write_scene(tmp_path / "petal.scn", [
        Placement("ca", 0, [0, 0, 0], [1, 1, 1], up, right, frame_start=0, frame_end=end, petal=1.8),
        Placement("ca", 0, [3.5, 0, 0], [1, 1, 1], up, right, frame_start=0, frame_end=end)])
    write_scene(tmp_path / "pre.scn", [
        Placement("ca", 1, [0, 0, 0], [1, 1, 1], up, right, frame_start=0, frame_end=end),
        Placement("ca", 0, [3.5, 0, 0], [1, 1, 1], up, right, frame_start=0, frame_end=end)])
    write_fcc_text(tmp_path / "petal.fcc", scene="petal.scn", extra="petal weight: 0 anim.petals\n" + extra)
    write_fcc_text(tmp_path / "pre.fcc", scene="pre.scn",
                   extra="animation: 1 1 1 1 grown\nweight: 1 petal_base.txt\n")
    out = {}
    for name in ("petal", "pre"):
        res = run_cli("fccompose", "-q", tmp_path / f"{name}.fcc", "-o", tmp_path / f"out_{name}")
        assert res.returncode == 0, res.stderr
        out[name] = [read_obj(p) for p in list_obj_sequence(tmp_path / f"out_{name}")]
    assert len(out["petal"]) == len(out["pre"]) == N_FRAMES
    return out


def test_a_placements_petal_factor_gives_the_canopy_of_a_pre_grown_template(tmp_path):
    """Floret 0 with '#@ petal: 1.8' and the weights, floret 1 plain: the same canopy as two plain
    placements of two animations, the first one's OBJs grown by 1 + w (1.8 - 1) beforehand."""
    frames, faces, fixed, w = _floret_files(tmp_path)
    out = petal_against_pre_grown(tmp_path, faces, [f * (1.0 + w * 0.8)[:, None] for f in frames])
    for a, b in zip(out["petal"], out["pre"]):
        np.testing.assert_array_equal(a.faces, b.faces)
        np.testing.assert_allclose(a.vertices, b.vertices, atol=2e-6)  # OBJ rounding (6 decimals)
    # and the petals did grow: floret 0 reaches 1.8 x as far from its axis as floret 1 (its own)
    last = out["petal"][-1].vertices
    n = len(frames[0])
    r0 = np.hypot(last[:n, 0], last[:n, 2]).max()
    r1 = np.hypot(last[n:, 0] - 3.5, last[n:, 2]).max()
    assert r0 / r1 == pytest.approx(1.8, rel=1e-5)
    # the fixed base rows did not move with the factor
    np.testing.assert_allclose(last[fixed], frames[-1][fixed], atol=2e-6)


def test_a_petal_factor_without_petal_weights_is_refused(tmp_path):
    """'#@ petal:' on an id without a 'petal weight' line would be ignored: one line, exit 2."""
    _floret_files(tmp_path)
    write_scene(tmp_path / "a.scn", [Placement("o", 0, [0, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0], petal=2.0)])
    write_fcc_text(tmp_path / "a.fcc", scene="a.scn", frames=1)
    res = run_cli("fccompose", "-q", tmp_path / "a.fcc", "-o", tmp_path / "out")
    assert res.returncode == 2, res.stderr
    assert "expected a 'petal weight' line" in res.stderr and len(res.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def _umbel_scene():
    """Two umbellets (groups 1, 2) of three florets each in the plane y = 0, group 0 the umbel."""
    sc = Scene()
    sc.groups[0] = Group(0, [0, 0, 0], -1)
    sc.groups[1] = Group(1, [-1, 0, 0], 0)
    sc.groups[2] = Group(2, [1, 0, 0], 0)
    for g, cx in ((1, -1.0), (2, 1.0)):
        for dx, dz in ((0.0, 0.0), (0.3, 0.1), (-0.3, 0.2)):
            pos = [cx + dx, 0.0, dz]
            radial = np.array([dx, 0.0, dz])
            right = radial / np.linalg.norm(radial) if np.linalg.norm(radial) else np.array([1.0, 0, 0])
            sc.placements.append(Placement("ca", 0, pos, [0.2] * 3, [0, 1, 0], right, frame_start=0,
                                           frame_end=10, group=g))
    return sc


def test_dimorph_petal_size_moves_the_factors_to_the_petals():
    sc = _umbel_scene()
    plain, _ = dimorph_scene(sc, DimorphOptions(alpha=120, ray_scale=3.0))
    petal, counts = dimorph_scene(sc, DimorphOptions(alpha=120, ray_scale=3.0, petal_size=True))
    assert counts["ray"] > 0
    for a, b in zip(plain.placements, petal.placements):
        if a.type == "ray":
            assert b.petal == pytest.approx(3.0)
            np.testing.assert_allclose(b.scale, [0.2] * 3)
            np.testing.assert_allclose(a.scale, [0.6] * 3)
        else:
            assert b.petal is None


def test_dimorph_orient_rays_turns_rays_away_from_the_top_centre():
    sc = _umbel_scene()
    out, counts = dimorph_scene(sc, DimorphOptions(alpha=120, orient_rays="top"))
    assert counts["oriented"] == counts["ray"] > 0
    for p in out.placements:
        if p.type == "ray":
            away = np.array(p.pos) / np.linalg.norm(p.pos)
            np.testing.assert_allclose(p.right, away, atol=1e-12)
            assert abs(np.dot(p.right, p.up)) < 1e-12
    # the others keep their orientation
    for a, b in zip(sc.placements, out.placements):
        if b.type != "ray":
            np.testing.assert_array_equal(a.right, b.right)


def test_dimorph_orient_rays_refuses_rba_placements():
    sc = _umbel_scene()
    for p in sc.placements:
        p.kind = "rba"
    with pytest.raises(InputError, match="rba"):
        dimorph_scene(sc, DimorphOptions(alpha=120, orient_rays="top"))


def test_dimorph_cli_writes_petal_factors(tmp_path):
    write_scn(tmp_path / "u.scn", _umbel_scene())
    res = run_cli("dimorph", tmp_path / "u.scn", "--alpha", "120", "--ray-scale", "2", "--petal-size",
                  "--orient-rays", "top", "-o", tmp_path / "t.scn")
    assert res.returncode == 0, res.stderr
    text = (tmp_path / "t.scn").read_text()
    assert "#@ petal: 2" in text


def test_dimorph_small_ray_scale_sizes_small_rays_by_the_space():
    """Two thresholds (fig. 6.4c): a small ray floret's factor is small_ray_scale * d_min / Th_b
    (ray_scale without it); the large rays keep ray_scale."""
    sc = _umbel_scene()
    th = (1.0, 2.0)  # d_min: 0 at the centres, 1.40 towards the other umbellet, inf outward
    a, ca = dimorph_scene(sc, DimorphOptions(alpha=120, thresholds=th, ray_scale=5.0, petal_size=True))
    b, cb = dimorph_scene(sc, DimorphOptions(alpha=120, thresholds=th, ray_scale=5.0, small_ray_scale=2.0,
                                             petal_size=True))
    assert ca["small_ray"] == cb["small_ray"] > 0 and ca["ray"] == cb["ray"] > 0
    for k, (p, q) in enumerate(zip(a.placements, b.placements)):
        if p.type == "small_ray":
            assert p.petal == pytest.approx(5.0 * cb["d_min"][k] / th[1])
            assert q.petal == pytest.approx(2.0 * cb["d_min"][k] / th[1])
        elif p.type == "ray":
            assert p.petal == q.petal == pytest.approx(5.0)
    with pytest.raises(InputError, match="small-ray-scale"):
        dimorph_scene(sc, DimorphOptions(alpha=120, thresholds=th, small_ray_scale=0.0))


def test_dimorph_orient_rays_top_keeps_a_ray_facing_an_inner_gap_along_its_cone():
    """A ray floret on the inner side of its umbellet (its free space a gap inside the umbel: here
    d_min 1.40 > Th = 1 towards the other umbellet) points its +X along its cone axis, away from its
    umbellet's centre, not outward into its own umbellet."""
    sc = _umbel_scene()
    out, counts = dimorph_scene(sc, DimorphOptions(alpha=120, thresholds=(1.0,), orient_rays="top"))
    inner = 0
    for p in out.placements:
        if p.type != "ray":
            continue
        own = np.array(p.pos) - sc.groups[p.group].centre
        top = np.array(p.pos)
        expect = own if np.dot(own, top) < 0 else top
        np.testing.assert_allclose(p.right, expect / np.linalg.norm(expect), atol=1e-12)
        inner += np.dot(own, top) < 0
    assert inner == 2  # one in each umbellet faces the other
