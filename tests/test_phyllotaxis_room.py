"""Florets of a recursive pattern grown into their room (``[hierarchy] fill_room``, room.py)."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import run_cli

from inflo.formats.rba import read_rba_sequence
from inflo.formats.scn import read_scn
from inflo.tools.phyllotaxis.hierarchy import grow_hierarchy, hierarchy_state
from inflo.tools.phyllotaxis.room import apply_room, fill_room

CORYMB = """[primordia]
floret_id = 0
[hierarchy]
levels = 3
frames = {frames}
growth_rate = 0.06
element_area = 1.0
production_threshold = [1.6, 1.6, 1.5]
meristem_threshold = [2.0, 8.0]
dynamic = true
{extra}
"""


def covered(pos, d, outline_pos, outline_d, margin=1.0, n=300):
    """Share of the outline (within (1 + margin) radii of an element of the outline layout)
    covered by the discs (pos, d)."""
    r0 = 0.5 * outline_d
    lo = (outline_pos - (1 + margin) * r0[:, None]).min(0)
    hi = (outline_pos + (1 + margin) * r0[:, None]).max(0)
    X, Z = np.meshgrid(np.linspace(lo[0], hi[0], n), np.linspace(lo[1], hi[1], n))
    P = np.column_stack([X.ravel(), Z.ravel()])
    inside = (np.linalg.norm(P[:, None] - outline_pos[None], axis=2) < (1 + margin) * r0).any(1)
    cov = (np.linalg.norm(P[:, None] - pos[None], axis=2) < 0.5 * d).any(1)
    return cov[inside].mean()


def test_two_distant_discs_grow_towards_each_other_within_the_range():
    p = np.array([[0.0, 0.0], [3.0, 0.0]])
    d = np.array([1.0, 1.0])
    q, w = fill_room(p, d, margin=1.0, iterations=1, scale_range=(0.9, 1.5))
    # the outline is two discs of radius 1; each owns its own half: no move along z, equal sizes
    np.testing.assert_allclose(q[:, 1], 0.0, atol=1e-9)
    assert abs(q[0, 0] + (q[1, 0] - 3.0)) < 1e-6  # mirror images
    np.testing.assert_allclose(w, 1.5)  # a cell of area pi (diameter 2) is clipped to 1.5 x
    q2, w2 = fill_room(p, d, margin=1.0, iterations=1, scale_range=(0.5, 10.0))
    np.testing.assert_allclose(w2, 2.0, rtol=0.03)  # the raster's disc of radius 1


def test_a_big_element_claims_more_room_than_a_small_one():
    p = np.array([[0.0, 0.0], [2.0, 0.0]])
    d = np.array([2.0, 1.0])  # touching discs
    q, w = fill_room(p, d, margin=0.5, iterations=1, scale_range=(0.1, 10.0))
    assert w[0] > 1.7 * w[1]
    assert w[0] / d[0] == pytest.approx(w[1] / d[1], rel=0.1)  # the weighted cells keep the ratio


def test_a_tiling_lattice_stays_put_and_degenerate_input_is_returned():
    g = np.array([(i + 0.5 * (j % 2), j * np.sqrt(3) / 2) for j in range(9) for i in range(9)], float)
    d = np.full(len(g), 1.0)
    q, w = fill_room(g, d, margin=0.2, iterations=2)
    interior = np.linalg.norm(g - g.mean(0), axis=1) < 2.5
    assert np.abs(q - g)[interior].max() < 0.05  # a regular tiling's cells are centred already
    # a hexagonal cell of side-to-side spacing 1 has the area of a disc of diameter 1.05, but a
    # grown disc never overlaps a neighbour it did not overlap: the discs grow until they touch
    np.testing.assert_allclose(w[interior], 1.0, rtol=0.02)
    dist = np.linalg.norm(q[:, None] - q[None], axis=2) + np.eye(len(q)) * 9
    assert (0.5 * (w[:, None] + w[None]) <= dist * (1 + 1e-9)).all()
    for pp, dd in ((g[:1], d[:1]), (np.zeros((0, 2)), np.zeros(0))):
        q1, w1 = fill_room(pp, dd)
        np.testing.assert_array_equal(q1, pp)
        np.testing.assert_array_equal(w1, dd)
    # coincident elements: each keeps a diameter within its range and a finite position
    q2, w2 = fill_room(np.zeros((3, 2)), np.ones(3), margin=1.0)
    assert np.isfinite(q2).all() and ((w2 >= 0.9 - 1e-12) & (w2 <= 1.5 + 1e-12)).all()


def test_grown_discs_overlap_no_more_than_in_the_pattern_across_ages():
    # an old big element next to a young small one it already overlaps, and a third far away
    p = np.array([[0.0, 0.0], [1.6, 0.0], [6.0, 0.0]])
    d = np.array([3.0, 1.0, 1.0])
    birth = np.array([0.0, 5.0, 5.0])
    q, w = fill_room(p, d, margin=1.0, birth=birth)
    before = 0.5 * (d[0] + d[1]) / np.linalg.norm(p[0] - p[1])
    after = 0.5 * (w[0] + w[1]) / np.linalg.norm(q[0] - q[1])
    assert before > 1 and after <= before * (1 + 1e-9)
    assert w[2] > 1.2 * d[2]  # room of its own: grows
    # elements of one age (a cohort emerging together) are free to overlap as they crowd
    q2, w2 = fill_room(p, d, margin=1.0, birth=np.zeros(3))
    assert 0.5 * (w2[0] + w2[1]) / np.linalg.norm(q2[0] - q2[1]) > after


def test_a_corymb_grows_into_one_canopy():
    h = grow_hierarchy(levels=3, frames=95, growth_rate=0.06, initial_area=1.0, element_area=[1.0],
                       production_threshold=[1.6, 1.6, 1.5], meristem_threshold=[2.0, 8.0])
    st = hierarchy_state(h, h.frames)
    p, d = st["pos"][:, [0, 2]], st["scale"][:, 0]
    birth = h.element_birth[h.florets[st["ids"]]]
    q, w = fill_room(p, d, birth=birth)
    before, after = covered(p, d, p, d), covered(q, w, p, d)
    assert before < 0.72 and after > before + 0.07
    assert ((w >= 0.9 * d - 1e-9) & (w <= 1.5 * d + 1e-9)).all()
    assert (np.linalg.norm(q - p, axis=1) < 0.6 * d).all()  # moved within its own disc
    q2, w2 = fill_room(p, d, birth=birth)
    np.testing.assert_array_equal(q, q2)  # deterministic
    np.testing.assert_array_equal(w, w2)


def hull_cover(pos, d, n=400):
    """Share of the convex hull of the discs (pos, d) that they cover."""
    from scipy.spatial import ConvexHull, Delaunay
    a = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    pts = (pos[:, None] + 0.5 * d[:, None, None] * np.c_[np.cos(a), np.sin(a)][None]).reshape(-1, 2)
    hull = pts[ConvexHull(pts).vertices]
    lo, hi = pts.min(0), pts.max(0)
    X, Z = np.meshgrid(np.linspace(lo[0], hi[0], n), np.linspace(lo[1], hi[1], n))
    P = np.column_stack([X.ravel(), Z.ravel()])
    inside = Delaunay(hull).find_simplex(P) >= 0
    cov = (np.linalg.norm(P[:, None] - pos[None], axis=2) < 0.5 * d).any(1)
    return cov[inside].mean()


def test_equal_room_over_the_hull_makes_heads_alike_in_one_convex_cap():
    # the final yarrow corymb (pipelines/yarrow/final/corymb.toml): the pattern's heads range 5.6x
    h = grow_hierarchy(levels=3, frames=95, growth_rate=0.06, initial_area=1.0, element_area=[1.0],
                       production_threshold=[1.6, 1.6, 1.5], meristem_threshold=[2.0, 8.0])
    st = hierarchy_state(h, h.frames)
    p, d = st["pos"][:, [0, 2]], st["scale"][:, 0]
    birth = h.element_birth[h.florets[st["ids"]]]
    cv = lambda x: x.std() / x.mean()
    q0, w0 = fill_room(p, d, birth=birth)  # by size, over the discs: the oldest stay largest
    q, w = fill_room(p, d, birth=birth, weight="equal", outline="hull", iterations=60, margin=0.5,
                     scale_range=(0.2, 5.0))
    assert cv(d) > 0.4 and cv(w0) > 0.4
    assert cv(w) < 0.15  # heads alike (issue 43: CV <= 0.15)
    assert hull_cover(q, w) > 0.78 > hull_cover(q0, w0) + 0.05
    # still no two heads of different ages overlap more than in the pattern
    dq = np.linalg.norm(q[:, None] - q[None], axis=2)
    dp = np.linalg.norm(p[:, None] - p[None], axis=2)
    diff = birth[:, None] != birth[None]
    allow = dq * np.maximum(1.0, 0.5 * (d[:, None] + d[None]) / np.where(dp > 0, dp, 1))
    assert (0.5 * (w[:, None] + w[None]) <= allow * (1 + 1e-6) + 1e-9)[diff].all()
    # the default options are unchanged by the new keys
    q1, w1 = fill_room(p, d, birth=birth, weight="size", outline="discs")
    np.testing.assert_array_equal(q0, q1)
    np.testing.assert_array_equal(w0, w1)


def test_apply_room_keeps_the_factor_and_scales_the_shift_with_growth():
    h = grow_hierarchy(levels=2, frames=60, growth_rate=0.06, initial_area=1.0, element_area=[1.0],
                       production_threshold=[1.6], meristem_threshold=[3.0])
    final = hierarchy_state(h, h.frames)
    n = len(final["ids"])
    shift = np.zeros((n, 3))
    shift[:, 0] = np.linspace(-1, 1, n)
    factor = np.linspace(0.9, 1.5, n)
    mid = hierarchy_state(h, 40.0)
    out = apply_room(mid, final, shift, factor)
    row = np.searchsorted(final["ids"], mid["ids"])
    grown = mid["scale"][:, 0] / final["scale"][row, 0]
    assert (grown < 1).all() and np.ptp(grown) < 1e-9  # one growth factor for every element
    np.testing.assert_allclose(out["scale"][:, 0] / mid["scale"][:, 0], factor[row])
    np.testing.assert_allclose(out["pos"] - mid["pos"], shift[row] * grown[:, None])
    np.testing.assert_array_equal(out["ids"], mid["ids"])
    end = apply_room(final, final, shift, factor)
    np.testing.assert_allclose(end["pos"] - final["pos"], shift)


def test_cli_fill_room_on_a_dynamic_corymb(tmp_path):
    runs = {}
    for tag, extra in (("plain", ""), ("room", "fill_room = true")):
        (tmp_path / f"{tag}.toml").write_text(CORYMB.format(frames=80, extra=extra))
        res = run_cli("phyllotaxis", "-q", tmp_path / f"{tag}.toml", "-o", tmp_path / tag)
        assert res.returncode == 0, res.stderr
        runs[tag] = (read_scn(tmp_path / tag / "scene.scn"), read_rba_sequence(tmp_path / tag / "rba")[1])
    (s0, f0), (s1, f1) = runs["plain"], runs["room"]
    assert len(f0) == len(f1) and len(s0) == len(s1) > 20
    assert [p.emergence for p in s0.placements] == [p.emergence for p in s1.placements]
    assert [(p.frame_start, p.frame_end) for p in s0.placements] == [(p.frame_start, p.frame_end) for p in s1.placements]
    ratios = {}
    for a, b in zip(f0, f1):
        np.testing.assert_array_equal(a.ids, b.ids)
        for i, r in zip(a.ids, b.scale[:, 0] / a.scale[:, 0]):
            ratios.setdefault(int(i), []).append(r)
    for r in ratios.values():  # each floret keeps its factor from its birth on
        assert np.ptp(r) < 1e-4 * max(r)
    last0, last1 = f0[-1], f1[-1]
    p0, d0 = last0.pos[:, [0, 2]], last0.scale[:, 0]
    p1, d1 = last1.pos[:, [0, 2]], last1.scale[:, 0]
    assert covered(p1, d1, p0, d0) > covered(p0, d0, p0, d0) + 0.05
    # the scene's placements stand where the last RBA frame puts them
    np.testing.assert_allclose(np.array([p.pos for p in s1.placements])[last1.ids], last1.pos, atol=1e-5)


@pytest.mark.parametrize("line, found", [("room_scale = [2.0, 1.0]", "room_scale"),
                                         ("room_margin = -1", "room_margin"),
                                         ("room_iterations = 0", "room_iterations"),
                                         ('room_weight = "age"', "room_weight"),
                                         ('room_outline = "box"', "room_outline")])
def test_cli_bad_room_keys_exit_2(tmp_path, line, found):
    (tmp_path / "p.toml").write_text(CORYMB.format(frames=40, extra="fill_room = true\n" + line))
    res = run_cli("phyllotaxis", tmp_path / "p.toml", "-o", tmp_path / "o")
    assert res.returncode == 2 and found in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "o" / "scene.scn").exists()
