"""The gaillardia pipeline (pipelines/gaillardia): its inputs, its head at both qualities,
and the draft build's checks.

What is checked (Owens thesis ch. 9, figs. 9.3, 9.4; ch. 6, figs. 6.2, 6.3; fig. 5.2a):

- the committed key poses (draft/ and final/) are what ``make_keys.py`` writes, compatible within
  each organ type, and the two qualities differ only in their polygonization;
- the ray floret of 'Oranges and Lemons' is tubular: one bilateral organ of symmetry 1 per colour,
  ``tube`` (orange-red) and ``limb`` (the flared mouth, yellow), each row's cross-section an arc
  of more than 270 degrees with a slit on the upper side whose edges stay well apart; lying
  outward (+X) and rising a little when open, short and erect in bud; the tube widens toward its
  mouth (a trumpet); the limb's base ring is tucked into the tube's mouth (inside its wall, behind
  its rim, close to it: no gap shows) and never touches the tube in any template frame; in every
  template frame the limb's base ring lies behind the tube's rim and inside its wall (no line of
  background between the colours from any side; a limb moved out of the mouth is caught); only
  the tube's base ring and its ``floor`` (closing the tube at its base, clear of the tube) are on
  the receptacle (the vertices ``python -m inflo.tools.species.weights base`` fixes);
- the disk floret is five-fold with its corolla fused almost to the tips, the anther tube and then
  the pistil rising above it (the sunflower's design); its bud pose held to a quarter of its
  window;
- the head at both qualities, typed as the Makefile types it (its ALPHA and BRACTS): exactly 21
  ray florets (emergent from the cone model), on the margin just inside the involucral bracts;
  the same 21 for ALPHA - 10 and ALPHA + 10 (numerical canalization, fig. 6.3); ray florets
  develop ahead of the disk florets; rays and bracts open with the head (not before the outer disk
  florets are half through their development), every ray open at the hero frame;
- the phase effect by age: disk florets emerge centripetally, each over the same window;
- the receptacle changes size and shape (fig. 9.4): it grows at least three times in diameter
  and flattens from a high dome to a lower one;
- the final canopy's size is that of the thesis's model (table 4.1: about 25k triangles);
- if the draft build exists (the golden test builds it): check_gaillardia.py's report says OK, and
  its figures (the receptacle left in view from above, at most 4 %, the limb's attachment to the tube, when the
  rays and bracts open, the rays open at the hero frame) are within species.toml [check].
"""
from __future__ import annotations

import dataclasses
import importlib.util
import re
import subprocess
import sys
import tomllib

import numpy as np
import pytest
from conftest import REPO, run_cli, species_setting

from inflo.formats.floret import check_compatible, full_petal, read_floret
from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.formats.scn import read_scn
from inflo.tools.collide import intersecting_pairs

GAI = REPO / "pipelines" / "gaillardia"
BUILD = REPO / "build" / "gaillardia"
KEYS = {"disk": ("bud", "hold", "open", "late"),
        "ray": ("bud", "s125", "early", "s375", "mid", "s625", "late", "s875", "open"),
        "bract": ("bud", "closed", "open")}
RAYS = 21
CHECK = tomllib.loads((GAI / "species.toml").read_text())["check"]


def _make_keys():
    spec = importlib.util.spec_from_file_location("gaillardia_make_keys", GAI / "make_keys.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _make_var(quality: str, name: str) -> str:
    """A setting of species.toml (formats/species.md), as the Makefile sees it."""
    return species_setting("gaillardia", quality, name)


def _dimorph(out, alpha, bracts, *extra):
    r = run_cli("dimorph", "-q", out / "scene.scn", "--alpha", alpha, "--bracts", bracts, "--bract-id", "2",
                *extra, "-o", out / "typed.scn")
    assert r.returncode == 0, r.stderr
    return read_scn(out / "typed.scn")


@pytest.fixture(scope="module", params=["draft", "final"])
def head(request, tmp_path_factory):
    q = request.param
    out = tmp_path_factory.mktemp(f"head_{q}")
    r = run_cli("phyllotaxis", "-q", GAI / q / "head.toml", "-o", out)
    assert r.returncode == 0, r.stderr
    alpha, bracts = _make_var(q, "ALPHA"), _make_var(q, "BRACTS")
    _dimorph(out, alpha, bracts, "--ray-lead", _make_var(q, "RAY_LEAD"),
             "--ray-development-frames", _make_var(q, "RAY_DEVELOPMENT_FRAMES"),
             "--bract-development-frames", _make_var(q, "BRACT_DEVELOPMENT_FRAMES"))
    return q, out, float(alpha), int(bracts)


@pytest.fixture(scope="module")
def ray_frames(tmp_path_factory):
    """The draft ray floret's template OBJs (floret-animate + polygonize, as the Makefile does)."""
    tmp = tmp_path_factory.mktemp("ray")
    keys = [GAI / "draft" / f"ray_{p}.floret" for p in KEYS["ray"]]
    assert run_cli("floret-animate", "-q", *keys, "--frames", int(_make_var("draft", "TEMPLATE_FRAMES")),
                   "-o", tmp / "frames").returncode == 0
    r = run_cli("polygonize", "-q", tmp / "frames", "-o", tmp / "obj")
    assert r.returncode == 0, r.stderr
    paths = list_obj_sequence(tmp / "obj")
    return paths, [read_obj(p) for p in paths]


def test_inputs_are_what_make_keys_writes(tmp_path):
    r = subprocess.run([sys.executable, str(GAI / "make_keys.py"), str(tmp_path)], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 0, r.stderr
    for q in ("draft", "final"):
        written = sorted(p.name for p in (tmp_path / q).iterdir())
        assert written == sorted(p.name for p in (GAI / q).glob("*.floret"))
        for name in written:
            assert (tmp_path / q / name).read_text() == (GAI / q / name).read_text(), \
                f"pipelines/gaillardia/{q}/{name} differs from what make_keys.py writes: rerun it"


def test_key_poses_compatible_and_qualities_differ_only_in_resolution():
    for kind, poses in KEYS.items():
        for q in ("draft", "final"):
            florets = [read_floret(GAI / q / f"{kind}_{p}.floret") for p in poses]
            for a, b in zip(florets, florets[1:]):
                check_compatible(a, b, kind, kind)
            assert florets[0].key_time == 0.0 and florets[-1].key_time == 1.0
            times = [f.key_time for f in florets]
            assert times == sorted(times)
        for p in poses:
            d, f = (read_floret(GAI / q / f"{kind}_{p}.floret") for q in ("draft", "final"))
            for od, of in zip(d.organs, f.organs):
                np.testing.assert_array_equal(od.control_points, of.control_points)


def _circle(points: np.ndarray):
    """A plane and a circle fitted to points in 3D: (centre (3,), in-plane coordinates round it)."""
    c = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - c)
    uv = (points - c) @ vt[:2].T
    a = np.c_[2 * uv, np.ones(len(uv))]
    sol = np.linalg.lstsq(a, (uv ** 2).sum(axis=1), rcond=None)[0]
    return c + sol[:2] @ vt[:2], uv - sol[:2]


def _arc_centre(points: np.ndarray) -> np.ndarray:
    return _circle(points)[0]


def _arc_span(points: np.ndarray) -> float:
    """Angular span (degrees) of points on a circle in 3D: 360 minus the largest angular gap
    between consecutive points round the fitted circle's centre."""
    uv = _circle(points)[1]
    ang = np.sort(np.degrees(np.arctan2(uv[:, 1], uv[:, 0])) % 360.0)
    gaps = np.diff(np.r_[ang, ang[0] + 360.0])
    return 360.0 - gaps.max()


def test_ray_floret_is_a_tube_open_in_a_slit_on_its_upper_side():
    mk = _make_keys()
    for p in KEYS["ray"]:
        ray = read_floret(GAI / "draft" / f"ray_{p}.floret")
        assert [o.name for o in ray.organs] == ["tube", "limb", "floor"]
        for o in ray.organs[:2]:
            assert (o.symmetry_n, o.bilateral, o.fused) == (1, True, 0)
            full = full_petal(o)
            for j, row in enumerate(full):
                assert _arc_span(row) > 270.0, (p, o.name, j, _arc_span(row))
                # the slit: the two lateral boundaries, mirror images across z = 0, stay apart by
                # far more than fccompose's spacing (0.0005 scene units; a floret unit is > 0.03)
                assert np.linalg.norm(row[0] - row[-1]) > 0.05, (p, o.name, j)
        # the slit is on the upper side of the tube's end where the tube lies outward (open), on
        # its inner (-X) side where the tube stands erect (bud): opposite the bottom midline
        last = full_petal(ray.organ("tube"))[-1]
        slit, bottom = last[[0, -1]].mean(axis=0), last[len(last) // 2]
        if p == "open":
            assert slit[1] > bottom[1] + 0.2
        if p == "bud":
            assert slit[0] < bottom[0] - 0.1 and abs(slit[1] - bottom[1]) < 1e-9
    assert mk.ARC_HALF * 2 == pytest.approx(300.0)
    # bud: short and erect; open: lying outward (+X), rising a little, the mouth flared
    bud = read_floret(GAI / "draft" / "ray_bud.floret")
    open_ = read_floret(GAI / "draft" / "ray_open.floret")
    tb = bud.organ("tube").control_points
    assert np.ptp(tb[:, 0, 0]) < 0.05 and tb[-1, 0, 1] < 0.8
    to = open_.organ("tube").control_points
    ends = [_arc_centre(full_petal(open_.organ("tube"))[j]) for j in (-2, -1)]
    assert ends[1][0] > 1.0 and np.hypot(*ends[1][:2]) > 1.5  # about 1.7 floret units from its base
    heading = ends[1] - ends[0]
    elevation = np.degrees(np.arctan2(heading[1], heading[0]))
    assert 5.0 < elevation < 45.0, elevation  # lying outward, rising a little (26 degrees)
    lo = open_.organ("limb").control_points
    r_end = np.linalg.norm(to[-1, 0] - to[-1, -1]) / 2
    r_mouth = np.linalg.norm(lo[-1, 0] - lo[-1, -1]) / 2
    assert r_mouth > 1.4 * r_end
    # a trumpet: the tube widens toward its mouth (its depth from the bottom midline to the slit;
    # the base ring is also widened sideways, a foot)
    rows = full_petal(open_.organ("tube"))
    depth = [np.linalg.norm(r[len(r) // 2] - r[[0, -1]].mean(axis=0)) for r in (rows[0], rows[-1])]
    assert depth[1] > 1.6 * depth[0], depth
    # three shallow lobes at the mouth: its last row recessed between the middle lobe (column 0)
    # and the lateral one
    rec = mk.LOBE_RECESS
    assert rec[0] == 0 and rec[np.argmin(rec[1:]) + 1] == 0 and rec[1:].max() < 0.5
    assert (bud.organ("tube").material, bud.organ("limb").material) == (mk.M_TUBE, mk.M_LIMB)


def test_limb_tucked_into_the_tube_key_poses():
    """The limb's base ring lies inside the tube's mouth: in every key pose it is smaller than the
    tube's top ring, behind it along the centre line, and the largest distance between the two
    rings (control points, column by column) is below 0.12 floret units (TUCK 0.08 along the
    centre line, INSET 0.03 and the trumpet's widening across): no background between them."""
    mk = _make_keys()
    assert 0 < mk.INSET < 0.05 and 0 < mk.TUCK < 0.1
    for q in ("draft", "final"):
        for p in KEYS["ray"]:
            ray = read_floret(GAI / q / f"ray_{p}.floret")
            top = full_petal(ray.organ("tube"))[-1]
            base = full_petal(ray.organ("limb"))[0]
            assert np.linalg.norm(base - top, axis=1).max() < 0.12, (q, p)
            r_top = np.linalg.norm(_circle(top)[1], axis=1).mean()
            r_base = np.linalg.norm(_circle(base)[1], axis=1).mean()
            assert r_base < r_top - 0.5 * mk.INSET, (q, p, r_base, r_top)
            # behind the rim: the limb's base ring is on the tube's side of its top ring's plane
            axis = _arc_centre(top) - _arc_centre(full_petal(ray.organ("tube"))[-2])
            assert np.dot(_arc_centre(base) - _arc_centre(top), axis) < 0, (q, p)


def test_limb_never_touches_the_tube_and_only_the_tube_base_is_fixed(ray_frames):
    mk = _make_keys()
    paths, meshes = ray_frames
    first = meshes[0]
    groups = {n: np.unique(first.faces[first.face_group == g]) for g, n in enumerate(first.groups)}
    tube, limb, floor = groups["tube_0"], groups["limb_0"], groups["floor_0"]
    ring = limb[:int(mk.RES["draft"]["limb"][1])]  # the polygonized limb's first row
    from inflo.tools.species import weights
    for k, mesh in enumerate(meshes):
        x = mesh.vertices
        assert len(intersecting_pairs(x, mesh.faces)) == 0, f"frame {k}: the floret intersects itself"
        d = np.min(np.linalg.norm(x[limb][:, None] - x[tube][None], axis=2), axis=1)
        # clear of the tube, yet its base ring close to it (the check's limb_gap)
        assert d.min() > CHECK["limb_gap"][0], (k, d.min())
        base = np.min(np.linalg.norm(x[ring][:, None] - x[tube][None], axis=2), axis=1)
        assert base.max() < 0.75 * CHECK["limb_gap"][1], (k, base.max())
        y = x[:, 1]
        base = np.nonzero(y <= y.min() + 1e-9)[0]
        assert set(base) <= set(tube) | set(floor) and len(set(base) & set(tube)) >= 5
        assert y[limb].min() > y.min() + 0.2
        # the floor lies on the receptacle inside the base ring, clear of the tube
        assert np.ptp(y[floor]) < 1e-9 and abs(y[floor].min() - y.min()) < 1e-9
        gap = np.min(np.linalg.norm(x[floor][:, None] - x[tube][None], axis=2))
        assert gap > 0.5 * mk.INSET, (k, gap)
        # its two (unwelded) halves stay apart at its seam, its rows in order: no two of its
        # vertices that share no triangle closer than a tenth of its radius (fixed, they could
        # never be pushed apart)
        near = np.linalg.norm(x[floor][:, None] - x[floor][None], axis=2)
        shared = np.zeros_like(near, dtype=bool)
        index = {int(v): i for i, v in enumerate(floor)}
        for f in mesh.faces[np.isin(mesh.faces, floor).all(axis=1)]:
            ids = [index[int(v)] for v in f]
            shared[np.ix_(ids, ids)] = True
        radius = np.hypot(x[floor][:, 0], x[floor][:, 2]).max()
        assert near[~shared].min() > 0.1 * radius, (k, near[~shared].min(), radius)
    # what the Makefile's obj stage fixes (weights.py base of frame 0): the tube's base ring and
    # its floor
    ids = weights.base_ids(paths[0])
    assert set(ids) <= set(tube) | set(floor) and not set(ids) & set(limb) and set(floor) <= set(ids)


def _junction(mesh, eta: int) -> tuple[float, float]:
    """Where a ray floret's limb (the yellow mouth) meets its tube, in floret units: (how far the
    limb's base ring reaches beyond the plane of the tube's rim along the tube's axis, how far it
    reaches outside the rim's circle across it). Both negative: the base ring lies inside the
    tube's mouth, so every line of sight to the join meets the tube's wall or the limb, and no
    background shows between the colours from any side. The polygonized rows come in order, ``eta``
    vertices each: the tube's last row is its rim, the limb's first its base ring."""
    groups = {n: np.unique(mesh.faces[mesh.face_group == g]) for g, n in enumerate(mesh.groups)}
    tube, limb = mesh.vertices[groups["tube_0"]], mesh.vertices[groups["limb_0"]]
    rim, before = tube[-eta:], tube[-2 * eta:-eta]
    centre, uv = _circle(rim)
    radius = np.linalg.norm(uv, axis=1).mean()
    normal = np.linalg.svd(rim - rim.mean(axis=0))[2][2]
    if np.dot(normal, centre - before.mean(axis=0)) < 0:
        normal = -normal
    base = limb[:eta] - centre
    along = base @ normal
    across = np.linalg.norm(base - np.outer(along, normal), axis=1)
    return float(along.max()), float((across - radius).max())


def test_the_mouth_continues_the_tube_with_no_background_line(ray_frames):
    """In every template frame the limb's base ring lies behind the tube's rim (about TUCK) and
    inside its wall (about INSET): the yellow mouth continues the orange tube with no line of
    background between them from any side (the close-ups from the side and from below in the
    README). The limb moved out of the mouth by 0.06 floret units (the gap the key poses once had)
    is caught."""
    mk = _make_keys()
    paths, meshes = ray_frames
    eta = int(mk.RES["draft"]["limb"][1])
    assert eta == int(mk.RES["draft"]["tube"][1])
    for path, mesh in zip(paths, meshes):
        along, across = _junction(mesh, eta)
        assert along < -0.5 * mk.TUCK and across < -0.5 * mk.INSET, (path.name, along, across)
    last = meshes[-1]
    limb = np.unique(last.faces[last.face_group == last.groups.index("limb_0")])
    moved = dataclasses.replace(last, vertices=last.vertices.copy())
    # the open tube lies outward rising 26 degrees: the limb out along that axis, TUCK + 0.06
    moved.vertices[limb] += (mk.TUCK + 0.06) * np.array([np.cos(np.radians(26.0)), np.sin(np.radians(26.0)), 0.0])
    assert _junction(moved, eta)[0] > 0.05


def test_disk_floret_fused_tube_with_organs_rising_in_turn():
    bud, hold, open_, late = (read_floret(GAI / "draft" / f"disk_{p}.floret") for p in KEYS["disk"])
    # the bud held to a quarter of the window (inner florets stay in bud longer: the phase effect)
    assert hold.key_time == pytest.approx(0.25) and bud.key_time == 0.0
    for a, b in zip(bud.organs, hold.organs):
        assert np.allclose(a.control_points, b.control_points)
    corolla = open_.organ("corolla")
    assert (corolla.symmetry_n, corolla.bilateral) == (5, True)
    assert corolla.fused == corolla.control_points.shape[0] - 1

    def top(floret, organ):
        return floret.organ(organ).control_points[..., 1].max()

    assert top(bud, "anthers") < top(bud, "corolla") and top(bud, "pistil") < top(bud, "corolla")
    assert top(open_, "anthers") > top(open_, "corolla") > top(open_, "pistil") - 0.2
    assert top(late, "pistil") > top(late, "anthers") > top(late, "corolla")


def test_head_has_21_rays_on_a_plateau_on_the_margin_inside_the_bracts(head):
    q, out, alpha, bracts = head
    typed = read_scn(out / "typed.scn")
    kinds = np.array([p.type for p in typed.placements])
    assert (kinds == "ray").sum() == RAYS and (kinds == "bract").sum() == bracts
    pos = typed.arrays()["pos"]
    r = np.hypot(pos[:, 0], pos[:, 2])
    assert np.quantile(r[kinds == "bract"], 0.1) > np.quantile(r[kinds == "ray"], 0.9)
    # rays on the margin: every ray floret farther out than 90 % of the disk florets
    assert r[kinds == "ray"].min() > np.quantile(r[kinds == "disk"], 0.9)
    # numerical canalization: the same count for cone angles 10 degrees either side
    for a in (alpha - 10, alpha + 10):
        res = run_cli("dimorph", "-q", out / "scene.scn", "--alpha", a, "--bracts", bracts, "-o", out / "t.scn")
        assert res.returncode == 0, res.stderr
        assert sum(p.type == "ray" for p in read_scn(out / "t.scn").placements) == RAYS, (q, a)


def test_phase_effect_by_age_and_rays_ahead(head):
    from scipy.stats import spearmanr

    q, out, _, _ = head
    typed = read_scn(out / "typed.scn")
    plain = read_scn(out / "scene.scn")
    disk = [k for k, p in enumerate(typed.placements) if p.type == "disk"]
    em = np.array([typed.placements[k].emergence for k in disk])
    r = np.hypot(*typed.arrays()["pos"][disk][:, [0, 2]].T)
    assert spearmanr(r, em).statistic < -0.95
    windows = {typed.placements[k].frame_end - typed.placements[k].frame_start for k in disk}
    assert len(windows) == 1
    lead = float(_make_var(q, "RAY_LEAD"))
    for a, b in zip(plain.placements, typed.placements):
        if b.type == "ray":
            assert b.frame_start == max(0, int(np.floor(a.frame_start - lead + 0.5)))


def test_rays_and_bracts_open_with_the_head(head):
    """Rays and bracts open (reach the end of their windows) only once the outer disk florets are
    half through theirs (anthesis at 0.55), and every ray is open at the hero frame."""
    q, out, _, _ = head
    typed = read_scn(out / "typed.scn")
    disk = [p for p in typed.placements if p.type == "disk"]
    half = min(p.frame_start + 0.5 * (p.frame_end - p.frame_start) for p in disk)
    hero = int(_make_var(q, "HERO"))
    for kind, name in (("ray", "RAY_DEVELOPMENT_FRAMES"), ("bract", "BRACT_DEVELOPMENT_FRAMES")):
        mine = [p for p in typed.placements if p.type == kind]
        # frameEnd = frameStart + N, before a start before frame 0 is clamped to it
        assert max(p.frame_end - p.frame_start for p in mine) == int(_make_var(q, name))
        assert min(p.frame_end for p in mine) >= half, (q, kind, half)
    assert max(p.frame_end for p in typed.placements if p.type == "ray") <= hero, q


def test_receptacle_grows_several_times_and_flattens(head):
    """Fig. 9.4: 'the dramatic, yet stable change in size due to the dynamic phyllotaxis', the
    receptacle changing size and shape: its top's rim radius and height above the rim."""
    q, out, _, _ = head
    frames = list_obj_sequence(out / "receptacle")
    shape = []
    for path in (frames[1], frames[-1]):
        mesh = read_obj(path)
        v = mesh.vertices
        rim = np.hypot(v[:, 0], v[:, 2]).max()
        top = v[:, 1].max()
        rim_y = v[np.argmax(np.hypot(v[:, 0], v[:, 2])), 1]
        shape.append((rim, (top - rim_y) / rim))
    (r0, h0), (r1, h1) = shape
    assert r1 > 3.0 * r0, (q, r0, r1)
    assert h0 > 0.45 and 0.15 < h1 < 0.35 and h1 < 0.7 * h0, (q, h0, h1)


def test_final_canopy_size_is_the_thesis_model(tmp_path):
    """Triangles per floret type at final resolution (polygonize of the key pose sets) times the
    head's florets: the thesis's ~25k (table 4.1), between 20k and 30k."""
    out = tmp_path / "h"
    assert run_cli("phyllotaxis", "-q", GAI / "final" / "head.toml", "-o", out).returncode == 0
    typed = _dimorph(out, _make_var("final", "ALPHA"), _make_var("final", "BRACTS"))
    kinds = [p.type for p in typed.placements]
    tris = {}
    for kind, poses in KEYS.items():
        frames = tmp_path / f"{kind}_frames"
        keys = [GAI / "final" / f"{kind}_{p}.floret" for p in poses]
        assert run_cli("floret-animate", "-q", *keys, "--frames", 2, "-o", frames).returncode == 0
        res = run_cli("polygonize", frames, "-o", tmp_path / f"{kind}_obj")
        assert res.returncode == 0, res.stderr
        tris[kind] = int(re.search(r"(\d+) triangles per floret", res.stderr + res.stdout).group(1))
    total = sum(tris[k] for k in kinds)
    assert 20_000 <= total <= 30_000, (tris, total)


def test_draft_build_checks_pass_if_built(species_build):
    species_build("gaillardia")  # the draft build, made here if no test made it yet
    check = BUILD / "check.txt"
    if not check.is_file() or (BUILD / "quality.txt").read_text().strip() != "draft":
        pytest.skip("no draft gaillardia build (INFLO_GOLDEN_NO_BUILD: build/gaillardia is left as it is)")
    text = check.read_text()
    assert text.strip().endswith("OK"), text
    assert f"ray florets: {RAYS} (expected {RAYS})" in text
    # the figures, against species.toml [check]: the receptacle left in view from above
    seen = float(re.search(r"receptacle in view from above at the last frame: ([\d.]+) %", text).group(1))
    assert CHECK["receptacle_visible"] <= 0.03  # a dense disk: at most 3 % of the receptacle in view (issue 44)
    assert seen <= 100 * CHECK["receptacle_visible"], seen
    # the limb: clear of its tube, its base ring in the tube's mouth
    m = re.search(r"limb to tube .*: closest ([\d.]+) .*, base ring at most ([\d.]+) from", text)
    assert float(m.group(1)) >= CHECK["limb_gap"][0] and float(m.group(2)) <= CHECK["limb_gap"][1], m.group(0)
    # rays and bracts open with the head; every ray open at the hero frame
    for kind in ("ray", "bract"):
        m = re.search(rf"first {kind} open \(development >= [\d.]+\) at frame \d+: (\d+) % of the disk", text)
        assert int(m.group(1)) >= 100 * CHECK["open_after"], m.group(0)
    assert re.search(rf"hero frame \d+: {RAYS} of {RAYS} ray florets open", text)
    assert "0 intersecting pairs, 0 with the receptacle" in text
