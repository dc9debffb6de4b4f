"""The lilac pipeline (issue 20, pipelines/lilac): a branching-first thyrse with its collisions
resolved (thesis sec. 4.5, figs. 4.9, 4.10, table 4.1).

- make_keys.py writes the committed key poses (both qualities); the floret is four petals fused
  into a tube (the seam fused over the tube) with a four-lobed limb, flat and perpendicular to the
  axis when open, closed over the tube's mouth in bud; the tube's foot is one ring in every pose;
- the Makefile's FRAMES is each quality's [development] frames (fccompose runs to the last window);
- both qualities' thyrses: decussate laterals, the lower florets first, every window inside the
  run; the final one about the thesis's size (table 4.1: ~200k triangles, with the final floret);
- compare.py picks the worst intersecting pair and false-colours it (on a tiny two-floret canopy);
- if the draft build exists (the golden test builds it): check_lilac.py's report says OK.
"""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from inflo.formats.floret import read_floret
from inflo.formats.obj import ObjMesh
from inflo.tools.thyrse.generate import thyrse
from inflo.tools.thyrse.params import read_params

from conftest import REPO, species_module, species_setting

LIL = REPO / "pipelines" / "lilac"
BUILD = REPO / "build" / "lilac"
_compare = species_module("lilac", "compare")
cut_out, worst_pair = _compare.cut_out, _compare.worst_pair


def _make_var(name: str, quality: str) -> str:
    """A setting of species.toml (formats/species.md), as the Makefile sees it."""
    return species_setting("lilac", quality, name)


def test_key_poses_are_up_to_date(tmp_path):
    r = subprocess.run([sys.executable, str(LIL / "make_keys.py"), str(tmp_path)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    for q in ("draft", "final"):
        names = sorted(f.name for f in (LIL / q).glob("*.floret"))
        assert names == ["floret_bud.floret", "floret_mid.floret", "floret_open.floret"]
        for name in names:
            assert (tmp_path / q / name).read_text() == (LIL / q / name).read_text(), f"{q}/{name}: rerun make_keys.py"


def test_the_lilac_floret_shape():
    poses = {k: read_floret(LIL / "draft" / f"floret_{k}.floret") for k in ("bud", "mid", "open")}
    organs = {k: f.organs for k, f in poses.items()}
    for k, orgs in organs.items():
        assert len(orgs) == 1
        o = orgs[0]
        assert o.symmetry_n == 4 and o.bilateral and o.fused > o.degree_v  # a tube fused past its v degree
    pts = {k: np.asarray(orgs[0].control_points) for k, orgs in organs.items()}
    # the foot of the tube: the same ring on y = 0 in every pose (fixed on the pedicel)
    for k in pts:
        np.testing.assert_array_equal(pts[k][0], pts["open"][0])
        assert np.all(pts[k][0][:, 1] == 0.0)
    op, bud = pts["open"], pts["bud"]
    radius = np.linalg.norm(op[:, 0][:, [0, 2]], axis=1)
    # open: a narrow tube (rows 0-3 within 0.08 of the axis), a flat limb (the lobes' rows level
    # within 0.02) reaching about half a unit
    assert radius[:4].max() < 0.08 and 0.45 < radius[-1] < 0.55
    assert np.ptp(op[5:, 0, 1]) < 0.02 and op[5:, 0, 1].min() > op[3, 0, 1]
    # bud: the lobes closed over the mouth (the tip row near the axis, above the throat)
    assert np.linalg.norm(bud[-1, 0][[0, 2]]) < 0.05 and bud[-1, 0, 1] > bud[4, 0, 1]


@pytest.mark.parametrize("quality", ["draft", "final"])
def test_thyrse_parameters_match_the_makefile_and_develop_from_below(quality):
    p = read_params(LIL / quality / "thyrse.toml")
    assert int(_make_var("FRAMES", quality)) == p.development.frames
    res = thyrse(p)
    sc = res.scene
    start = np.array([q.frame_start for q in sc.placements])
    end = np.array([q.frame_end for q in sc.placements])
    h = res.layout.floret_pos[:, 1]
    assert start.min() >= 0 and end.max() == p.development.frames - 1
    # the lower florets open first: the lowest fifth starts before the highest fifth
    lo, hi = h <= np.quantile(h, 0.2), h >= np.quantile(h, 0.8)
    assert start[lo].max() < start[hi].min()
    if quality == "final":
        # the thesis's size: ~200k canopy triangles with the final floret (800 triangles)
        assert 150_000 < 800 * len(sc) < 250_000


def test_compare_picks_the_intersecting_pair_and_colours_it():
    # three one-triangle "florets": 0 and 1 cross, 2 is apart
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0],
                  [0.2, 0.2, -0.5], [0.2, 0.2, 0.5], [0.8, 0.8, 0.0],
                  [5, 0, 0], [6, 0, 0], [5, 1, 0]], float)
    mesh = ObjMesh(vertices=v, faces=[[0, 1, 2], [3, 4, 5], [6, 7, 8]], groups=["floret_0", "floret_1", "floret_2"],
                   face_group=np.array([0, 1, 2]), materials=["mtl0"], face_material=np.zeros(3, np.int32))
    pos = np.array([[0.3, 0.3, 0], [0.4, 0.4, 0], [5.3, 0.3, 0]])
    pair, n = worst_pair(mesh, pos, np.tile([0.0, 0.0, 1.0], (3, 1)))
    assert pair == (0, 1) and n == 1
    sub = cut_out(mesh, {0, 1, 2}, pair)
    assert [sub.materials[m] for m in sub.face_material] == ["mtl8", "mtl9", "mtl0"]


def test_draft_build_check_says_ok():
    report = BUILD / "check.txt"
    if not report.is_file() or (BUILD / "quality.txt").read_text().strip() != "draft":
        pytest.skip("no draft lilac build (make lilac, or the golden test, makes one)")
    text = report.read_text()
    assert text.rstrip().endswith("OK"), text[-2000:]
    assert "0 intersecting pairs" in text
