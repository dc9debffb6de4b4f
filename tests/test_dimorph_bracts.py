"""dimorph --bracts: the outermost primordia of a head are involucral bracts, left out of the cone
test (thesis ch. 9 on gaillardia's involucral bracts)."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import run_cli

from inflo.formats.scn import Group, Placement, Scene, read_scn
from inflo.tools.dimorph.dimorph import DimorphOptions, dimorph_scene, outermost
from inflo.tools.dimorph.sweep import simple_head


def _head(n=300, groups=1):
    scene = Scene()
    for g in range(groups):
        off = np.array([10.0 * g, 0.0, 0.0])
        scene.groups[g] = Group(g, off, -1)
        for p in simple_head(n):
            scene.placements.append(Placement("rba", 0, p + off, [1.0] * 3, [0, 1, 0], [1, 0, 0],
                                              frame_start=3, frame_end=30, group=g))
    return scene


def test_bracts_are_the_outermost_placements_of_each_head():
    scene = _head(groups=2)
    out, counts = dimorph_scene(scene, DimorphOptions(120.0, bracts=34, bract_id=2, bract_scale=1.5))
    assert counts["bract"] == 68
    arr = scene.arrays()
    for g in (0, 1):
        rows = np.nonzero(arr["group"] == g)[0]
        d = np.linalg.norm(arr["pos"][rows] - scene.groups[g].centre, axis=1)
        is_bract = np.array([out.placements[k].type == "bract" for k in rows])
        assert is_bract.sum() == 34
        assert d[is_bract].min() >= d[~is_bract].max()
    for a, b in zip(scene.placements, out.placements):
        if b.type == "bract":
            assert b.id == 2 and b.scale[0] == pytest.approx(1.5)
            assert (b.frame_start, b.frame_end) == (a.frame_start, a.frame_end)


def test_bracts_are_left_out_of_the_cone_test():
    """Without bracts the outermost ring is the rays; with that ring made bracts, the next ring's
    cones are empty (bracts are not florets) and a ray count appears again, just inside them."""
    scene = _head(n=300)
    plain, c0 = dimorph_scene(scene, DimorphOptions(120.0))
    with_b, c1 = dimorph_scene(scene, DimorphOptions(120.0, bracts=34))
    assert c0["ray"] > 0 and c1["ray"] > 0
    d = np.linalg.norm(scene.arrays()["pos"], axis=1)
    rays = np.array([p.type == "ray" for p in with_b.placements])
    bracts = np.array([p.type == "bract" for p in with_b.placements])
    assert d[rays].min() < d[bracts].min()  # the rays are inside the involucre
    # and they are exactly the rays of the head without its bracts
    inner = [k for k in range(len(scene)) if not bracts[k]]
    sub = Scene(placements=[scene.placements[k] for k in inner], groups=dict(scene.groups))
    ref, _ = dimorph_scene(sub, DimorphOptions(120.0))
    assert [p.type for p in ref.placements] == [with_b.placements[k].type for k in inner]


def test_outermost_ties_go_by_placement_order():
    pos = np.array([[1.0, 0, 0], [0, 0, 1.0], [-1.0, 0, 0], [0.5, 0, 0]])
    sel = outermost(pos, np.zeros((4, 3)), np.zeros(4, np.int32), 2)
    assert sel.tolist() == [True, True, False, False]
    assert not outermost(pos, np.zeros((4, 3)), np.zeros(4, np.int32), 0).any()
    assert outermost(pos, np.zeros((4, 3)), np.zeros(4, np.int32), 10).all()


def test_cli_bracts_and_bad_values(tmp_path):
    from inflo.formats.scn import write_scn
    write_scn(tmp_path / "h.scn", _head(n=120))
    r = run_cli("dimorph", str(tmp_path / "h.scn"), "--alpha", "120", "--bracts", "21", "-o", str(tmp_path / "t.scn"))
    assert r.returncode == 0, r.stderr
    assert "21 bracts" in r.stderr
    assert sum(p.type == "bract" for p in read_scn(tmp_path / "t.scn").placements) == 21
    r = run_cli("dimorph", str(tmp_path / "h.scn"), "--alpha", "120", "--bracts", "-1", "-o", str(tmp_path / "u.scn"))
    assert r.returncode == 2 and "--bracts must be >= 0" in r.stderr and not (tmp_path / "u.scn").exists()
    r = run_cli("dimorph", str(tmp_path / "h.scn"), "--alpha", "120", "--bract-scale", "0", "-o", str(tmp_path / "u.scn"))
    assert r.returncode == 2 and "--bract-scale must be > 0" in r.stderr


def test_marginal_keeps_the_rays_to_the_outermost_florets_of_each_head():
    """--marginal N: a floret may be a ray only among the N outermost of its head (after the
    bracts); inside that rim the fates are the cones' own, elsewhere every floret is a disk floret
    (a corymb's rim head, open on one whole side, keeps its inner florets disk florets)."""
    scene = _head(n=300, groups=2)
    plain, c0 = dimorph_scene(scene, DimorphOptions(120.0))
    capped, c1 = dimorph_scene(scene, DimorphOptions(120.0, marginal=10))
    arr = scene.arrays()
    rim = outermost(arr["pos"], np.array([scene.groups[g].centre for g in arr["group"]]), arr["group"], 10)
    ray0 = np.array([p.type == "ray" for p in plain.placements])
    ray1 = np.array([p.type == "ray" for p in capped.placements])
    assert c0["ray"] > 20  # more rays than the cap allows
    assert ray1.tolist() == (ray0 & rim).tolist() and 0 < c1["ray"] <= 20
    assert c1["disk"] == len(scene) - c1["ray"]
    # with bracts the rim is the N florets just inside them
    both, c2 = dimorph_scene(scene, DimorphOptions(120.0, bracts=34, marginal=10))
    types = [p.type for p in both.placements]
    ref, _ = dimorph_scene(scene, DimorphOptions(120.0, bracts=34))
    rim2 = outermost(arr["pos"], np.array([scene.groups[g].centre for g in arr["group"]]), arr["group"], 44)
    expect = [t if (t != "ray" or r) else "disk" for t, r in zip((p.type for p in ref.placements), rim2)]
    assert types == expect and c2["bract"] == 68 and c2["ray"] > 0
    r = run_cli("dimorph", "x.scn", "--alpha", "120", "--marginal", "-1", "-o", "y.scn")
    assert r.returncode == 2 and "--marginal must be >= 0" in r.stderr
