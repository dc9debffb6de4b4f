"""phyllotaxis: Ridley's model (thesis 5.2, eq. 5.1-5.2), dynamics (5.3), recursion (5.4), the CLI."""
from __future__ import annotations

import dataclasses
import math
from collections import Counter

import numpy as np
import pytest
from conftest import no_partial_files, run_cli
from scipy.spatial import cKDTree

from inflo.formats.contour import Contour, write_con
from inflo.formats.errors import FormatError, InputError
from inflo.formats.func import Function, write_func
from inflo.formats.rba import read_rba_sequence
from inflo.formats.scn import read_scn
from inflo.tools.phyllotaxis.dynamics import frame_state, simulate
from inflo.tools.phyllotaxis.hierarchy import grow_hierarchy, hierarchy_state
from inflo.tools.phyllotaxis.params import parse_params
from inflo.tools.phyllotaxis.ridley import AreaFunction, area_function, ridley_positions, static_pattern
from inflo.tools.phyllotaxis.surface import builtin_curve, load_curve, profile_from_points

FIB = {1, 2, 3, 5, 8, 13, 21, 34, 55, 89, 144}


# ---------------------------------------------------------------- Ridley (5.2)

def test_disk_with_constant_area_is_vogels_spiral():
    prof = builtin_curve("disk", radius=1.0, samples=8192)
    A = 0.002
    pat = static_pattern(prof, AreaFunction(A, prof.length), count=400)
    r = np.hypot(pat.pos[:, 0], pat.pos[:, 2])
    i = np.arange(400)
    np.testing.assert_allclose(r, np.sqrt(i * A / np.pi), atol=2e-4)  # r_i = sqrt(i A / pi)
    ang = np.arctan2(pat.pos[1:, 2], pat.pos[1:, 0])
    d = np.mod(np.diff(ang[:50]), 2 * np.pi)
    np.testing.assert_allclose(np.degrees(d), 137.50776405, atol=1e-6)


def _parastichies(pos2d):
    """The two commonest index differences between a floret and its two nearest neighbours."""
    tree = cKDTree(pos2d)
    n = len(pos2d)
    _, idx = tree.query(pos2d, k=3)
    diffs = Counter()
    for i in range(n // 2, n - n // 10):  # the outer half, away from the rim
        for j in idx[i, 1:]:
            diffs[abs(int(j) - i)] += 1
    return sorted(d for d, _ in diffs.most_common(2))


def test_parastichy_numbers_of_a_500_floret_disk_are_consecutive_fibonacci():
    prof = builtin_curve("disk", samples=8192)
    pat = static_pattern(prof, AreaFunction(math.pi / 501, prof.length), count=500)
    a, b = _parastichies(pat.pos[:, [0, 2]])
    fib = sorted(FIB)
    assert a in FIB and b in FIB and fib.index(b) == fib.index(a) + 1, (a, b)
    # a rational divergence breaks it: 120 deg gives 3 straight spokes, not two spiral families
    pat2 = static_pattern(prof, AreaFunction(math.pi / 501, prof.length), count=500, divergence=120.0)
    assert _parastichies(pat2.pos[:, [0, 2]])[0] == 3 and len(_parastichies(pat2.pos[:, [0, 2]])) == 1


@pytest.mark.parametrize("curve,kw", [("sphere_cap", {"angle": 80}), ("cone", {"height": 0.7}),
                                      ("paraboloid", {"height": 0.4})])
def test_primordium_areas_tile_the_band_they_cover(tmp_path, curve, kw):
    prof = builtin_curve(curve, radius=1.0, **kw)
    fn = Function.from_points([[0, 0.004], [0.3, 0.002], [0.7, 0.006], [1, 0.003]])
    write_func(tmp_path / "a.func", fn)
    area = area_function(str(tmp_path / "a.func"), prof.length)
    s = ridley_positions(prof, area, start=0.05)
    n = len(s) - 1
    band = np.interp(s[-1], prof.s, prof.area) - np.interp(s[0], prof.s, prof.area)
    assert n > 200
    assert abs(area(s[:-1]).sum() - band) / band < 0.02
    # and the band between s_0 and the last primordium is the rim (filled to the end)
    assert prof.length - s[-1] < 3 * math.sqrt(area(prof.length) / math.pi)


def test_frames_are_surface_normal_and_meridian_tangent():
    R = 2.0
    prof = builtin_curve("sphere_cap", radius=R, angle=70)
    pat = static_pattern(prof, AreaFunction(0.02, prof.length), count=300)
    centre = np.array([0.0, -R, 0.0])
    radial = (pat.pos - centre) / R
    np.testing.assert_allclose(np.linalg.norm(pat.pos - centre, axis=1), R, atol=1e-6)
    np.testing.assert_allclose(pat.up, radial, atol=2e-3)  # outward normal of the sphere
    np.testing.assert_allclose(np.sum(pat.up * pat.right, axis=1), 0, atol=1e-9)
    # right lies in the meridian plane: perpendicular to the circumferential direction
    circ = np.stack([-pat.pos[:, 2], 0 * pat.pos[:, 0], pat.pos[:, 0]], axis=1)
    ok = np.linalg.norm(circ, axis=1) > 1e-6
    assert np.all(np.abs(np.sum(pat.right[ok] * circ[ok], axis=1)) < 1e-6)
    assert np.all(pat.right[1:, 1] < 0)  # pointing away from the apex, downhill


def test_curve_crossing_the_axis_or_doubling_back_is_rejected(tmp_path):
    cross = [[0.0, 0.0], [0.5, 0.1], [-0.3, 0.3], [0.8, 0.0]]
    with pytest.raises(FormatError, match="axis"):
        profile_from_points(cross)
    back = [[0.0, 0.0], [0.5, 0.0], [1.0, 0.0], [0.6, 0.0001], [1.2, 0.3]]
    with pytest.raises(FormatError, match="double back"):
        profile_from_points(back)
    loop = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.5, -0.5], [0.2, 0.8]]
    with pytest.raises(FormatError, match="double back"):
        profile_from_points(loop)
    con = Contour.from_points([[0, 0, 0], [0.4, 0.2, 0], [-0.4, 0.4, 0], [-0.2, 0.8, 0], [0.6, 1.0, 0]], type="oe")
    write_con(tmp_path / "c.con", con)
    with pytest.raises(FormatError) as exc:
        load_curve(str(tmp_path / "c.con"))
    assert "c.con" in str(exc.value)


def test_area_function_not_positive_is_rejected(tmp_path):
    write_func(tmp_path / "bad.func", Function.from_points([[0, 0.01], [0.4, -0.02], [0.6, -0.02], [1, 0.01]]))
    prof = builtin_curve("disk")
    with pytest.raises(FormatError, match=r"A\(s\) > 0"):
        ridley_positions(prof, area_function(str(tmp_path / "bad.func"), prof.length))


# ---------------------------------------------------------------- parameters

def test_unknown_key_names_closest_known_key_and_line():
    text = "[surface]\ncurve = 'disk'\n\n[primordia]\narea = 0.01\ndivergance = 137.5\n"
    with pytest.raises(FormatError) as exc:
        parse_params(text, "p.toml")
    msg = str(exc.value)
    assert msg.startswith("p.toml:6:") and "did you mean 'divergence'" in msg


@pytest.mark.parametrize("text,expected", [
    ("[primordia]\ndivergence = 360.0\n", "divergence"),
    ("[primordia]\ndivergence = 0\n", "divergence"),
    ("[primordia]\narea = -0.01\n", "area"),
    ("[surface]\ncurve = 'disc'\n", "curve"),
    ("[dynamics]\nmode = 'centripetall'\n", "did you mean 'centripetal'"),
    ("[dynamics]\nmode = 'segregation'\nthreshold = 0.001\nprimordium_area = 0.01\n", "threshold"),
    ("[surfaces]\n", "did you mean 'surface'"),
    ("[dynamics]\nmode = 'segregation'\nthreshold = 0.02\nprimordium_area = 0.01\nclose_apex = true\n",
     "close_apex"),
])
def test_bad_parameters_are_rejected(text, expected, tmp_path):
    if "disc" in text:  # not a built-in: read as a .con path that does not exist
        p = parse_params(text, tmp_path / "p.toml")
        with pytest.raises(InputError):
            load_curve(p.surface.curve)
        return
    with pytest.raises(FormatError, match=expected):
        parse_params(text, "p.toml")


def test_defaults_are_filled_and_paths_resolved(tmp_path):
    p = parse_params("[primordia]\narea = 'a.func'\n", tmp_path / "p.toml")
    assert p.primordia.area == str(tmp_path / "a.func")
    assert p.primordia.divergence == pytest.approx(137.50776405)
    assert p.dynamics is None and p.compound is None and p.hierarchy is None and p.receptacle is None
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.primordia.count = 3


# ---------------------------------------------------------------- dynamics (5.3)

def _radius(state):
    return np.hypot(state["pos"][:, 0], state["pos"][:, 2])


def test_centripetal_fractionation_proceeds_from_the_rim_inward():
    disk = builtin_curve("disk")
    pat = simulate(mode="centripetal", frames=60, interval=0.5, primordium_area=0.004, inner_area=0.5,
                   profiles=[disk])
    np.testing.assert_allclose(np.diff(pat.emergence), 0.5)  # fixed intervals
    st = frame_state(pat, 59)
    assert np.all(np.diff(_radius(st)) < 0)  # radius decreasing with emergence time
    # it stops when the inner region is smaller than one primordium
    assert len(pat) == 119 and pat.inner[-1] > 0.004  # t = 0, 0.5, ..., 59
    full = simulate(mode="centripetal", frames=200, interval=0.5, primordium_area=0.004, inner_area=0.502,
                    profiles=[disk])
    assert len(full) == 125 and full.inner[-1] == pytest.approx(0.002)
    # the surface is scaled to the sum of the regions: a disk of area 0.502
    st = frame_state(full, 199)
    assert st["profile"].total_area == pytest.approx(0.502, rel=1e-9)
    assert st["area"].sum() == pytest.approx(0.5, rel=1e-9)


def test_close_apex_leaves_no_naked_top():
    disk = builtin_curve("disk")
    kw = dict(mode="centripetal", frames=200, interval=0.5, primordium_area=0.004, profiles=[disk])
    # 0.5025 = 125 primordia and 0.0025 left over (more than half of one): a last, apical primordium
    naked = simulate(inner_area=0.5025, **kw)
    closed = simulate(inner_area=0.5025, close_apex=True, **kw)
    assert len(naked) == 125 and naked.inner[-1] == pytest.approx(0.0025)
    assert len(closed) == 126 and closed.emergence[-1] == pytest.approx(62.5)
    assert closed.inner[-1] == 0.0 and np.all(closed.inner[64:] == 0.0)
    np.testing.assert_array_equal(closed.emergence[:125], naked.emergence)
    st = frame_state(closed, 199)  # the surface is the primordia's alone: nothing left at the apex
    assert st["profile"].total_area == pytest.approx(0.504, rel=1e-9)
    assert _radius(st)[-1] < _radius(st)[-2]  # the last one innermost
    # 0.0015 left (less than half a primordium): no primordium, but the top is used up all the same
    short = simulate(inner_area=0.5015, close_apex=True, **kw)
    assert len(short) == 125 and short.inner[-1] == 0.0
    # relative growth of the inner region keeps it empty
    grown = simulate(inner_area=0.5025, close_apex=True, inner_growth=0.01, **kw)
    assert grown.inner[-1] == 0.0


def test_terminal_primordium_stands_on_the_apex_and_the_apex_tapers():
    disk = builtin_curve("disk")
    kw = dict(mode="centripetal", frames=200, interval=0.5, primordium_area=0.004, profiles=[disk])
    closed = simulate(inner_area=0.5025, close_apex=True, **kw)
    assert closed.terminal
    st = frame_state(closed, 199)
    assert _radius(st)[-1] == pytest.approx(0.0, abs=1e-12)  # on the apex itself, its up the axis
    np.testing.assert_allclose(st["up"][-1], [0.0, 1.0, 0.0], atol=1e-9)
    assert not simulate(inner_area=0.5015, close_apex=True, **kw).terminal  # no terminal primordium
    # the apex tapers: once less than 1 / 0.4 primordia are left, each takes 0.4 of what is left
    taper = simulate(inner_area=0.5025, close_apex=True, apex_taper=0.4, apex_smallest=0.15, **kw)
    born = taper.born
    assert np.all(born[:120] == 0.004) and len(taper) > len(closed)
    tail = born[born < 0.004]
    assert np.all(np.diff(tail[:-1]) < 0) and tail[-2] >= 0.15 * 0.004  # smaller toward the apex
    assert born.sum() == pytest.approx(0.5025, rel=1e-9)  # the terminal one takes what is left
    st = frame_state(taper, 199)
    assert st["profile"].total_area == pytest.approx(0.5025, rel=1e-9)
    assert _radius(st)[-1] == pytest.approx(0.0, abs=1e-12)
    assert np.all(np.diff(st["scale"][len(taper) - len(tail) - 1:, 0][:-1]) < 0)  # smaller florets


def test_divergent_fractionation_has_two_fronts():
    disk = builtin_curve("disk")
    pat = simulate(mode="divergent", frames=40, interval=1.0, primordium_area=0.004, inner_area=0.2,
                   outer_area=0.3, profiles=[disk])
    st = frame_state(pat, 39)
    r = _radius(st)
    inner, outer = pat.side == -1, pat.side == 1
    assert inner.sum() == outer.sum() == 40
    assert np.all(np.diff(r[inner]) < 0) and np.all(np.diff(r[outer]) > 0)
    boundary = math.sqrt(0.2 / math.pi)  # where the first two primordia formed
    assert r[inner].max() < boundary + 0.01 < r[outer].min() + 0.02


def test_segregation_period_is_set_by_the_inner_growth_rate():
    disk = builtin_curve("disk")
    A, T = 0.01, 0.03
    for rate in (0.02, 0.05):
        pat = simulate(mode="segregation", frames=400, interval=1.0, primordium_area=A, inner_area=0.02,
                       threshold=T, inner_growth=rate, profiles=[disk], substeps=64)
        period = np.diff(pat.emergence)[2:].mean()
        assert period == pytest.approx(math.log(T / (T - A)) / rate, abs=1 / 64)
        st = frame_state(pat, 399)
        assert np.all(np.diff(_radius(st)[5:]) < 0)  # the newest is innermost


def test_dynamic_cli_writes_rba_frames_with_every_emerged_floret(tmp_path, write):
    params = write("dyn.toml", "[surface]\ncurve = 'sphere_cap'\nangle = 60\n[dynamics]\nmode = 'centripetal'\n"
                               "frames = 12\ninterval = 0.5\nprimordium_area = 0.01\ninner_area = 0.6\n"
                               "primordium_growth = 0.02\ncurves = ['sphere_cap', 'disk']\ncurve_times = [0, 1]\n")
    out = tmp_path / "out"
    res = run_cli("phyllotaxis", params, "-o", out, "--quiet")
    assert res.returncode == 0, res.stderr
    scene = read_scn(out / "scene.scn")
    paths, frames = read_rba_sequence(out / "rba", scene)
    assert len(paths) == 12 and paths[0].name == "0000.rba"
    em = np.array([p.emergence for p in scene.placements])
    for f, fr in enumerate(frames):
        assert fr.ids.tolist() == np.nonzero(em <= f + 1e-9)[0].tolist()
    assert all(p.kind == "rba" and p.group == 0 and p.frame_end == 11 for p in scene.placements)
    # the last frame is the scene's placement; older florets are larger (primordium growth)
    np.testing.assert_allclose(frames[-1].pos, np.array([p.pos for p in scene.placements]), atol=1e-6)
    assert frames[-1].scale[0, 0] > frames[-1].scale[-1, 0]
    # the receptacle flattens from the dome to the disk
    assert abs(frames[-1].pos[:, 1]).max() < 1e-6 < abs(frames[0].pos[:, 1]).max() + 1
    res2 = run_cli("phyllotaxis", params, "-o", tmp_path / "again", "--quiet")
    assert res2.returncode == 0
    assert (tmp_path / "again/scene.scn").read_bytes() == (out / "scene.scn").read_bytes()
    assert (tmp_path / "again/rba/0011.rba").read_bytes() == (out / "rba/0011.rba").read_bytes()
    # the header names the parameter file the same way however it was typed (an absolute
    # path once made two checkouts' scenes differ)
    (tmp_path / "sub").mkdir()
    res3 = run_cli("phyllotaxis", "./sub/../dyn.toml", "-o", "rel", "--quiet", cwd=tmp_path)
    assert res3.returncode == 0, res3.stderr
    assert (tmp_path / "rel/scene.scn").read_bytes() == (out / "scene.scn").read_bytes()
    assert (out / "scene.scn").read_text().splitlines()[0] == "# phyllotaxis dyn.toml"


# ---------------------------------------------------------------- hierarchy (5.4)

def _yarrow(**kw):
    args = dict(levels=3, frames=150.0, growth_rate=0.05, initial_area=1.0, element_area=[1.0],
                production_threshold=[6.0], meristem_threshold=[12.0])
    args.update(kw)
    return grow_hierarchy(**args)


def test_recursive_segregation_periods_and_meristem_onset():
    h = _yarrow()
    root_kids = h.children[0]
    period = np.diff(h.element_birth[root_kids])[1:]
    np.testing.assert_allclose(period, math.log(6.0 / 5.0) / 0.05, rtol=1e-9)
    starts = h.meristem_start[root_kids]
    ok = np.isfinite(starts)
    np.testing.assert_allclose(starts[ok] - h.element_birth[root_kids][ok], math.log(12.0) / 0.05)
    assert h.element_level.max() == 3 and len(h.florets) > 50


def test_hofmeister_first_element_points_away_from_the_grandparent():
    h = _yarrow()
    checked = 0
    for m in np.nonzero(np.isfinite(h.meristem_start) & (h.element_level == 1))[0]:
        kids = h.children[m]
        if len(kids) == 0:
            continue
        st = hierarchy_state(h, h.frames)
        pos = st["centres"]
        first = pos[kids[0]] - pos[m]
        away = pos[m] - pos[0]
        cos = np.dot(first, away) / np.linalg.norm(first) / np.linalg.norm(away)
        assert cos > 0.5  # roughly away (later siblings and growth turn it a little)
        checked += 1
    assert checked >= 3


def test_florets_of_a_meristem_stay_within_its_area():
    h = _yarrow()
    st = hierarchy_state(h, h.frames)
    area = h.element_area0 * np.exp(h.rho * (h.frames - h.element_birth))
    for g in np.unique(st["group"]):
        rows = st["group"] == g
        d = np.linalg.norm(st["pos"][rows] - st["centres"][g], axis=1)
        assert d.max() <= math.sqrt(area[g] / math.pi) * 1.05


def test_unreachable_hierarchy_threshold_is_reported_not_looped(tmp_path, write):
    params = write("h.toml", "[hierarchy]\nlevels = 3\nframes = 50\ngrowth_rate = 0.01\n"
                             "production_threshold = 1.2\nmeristem_threshold = 1000\n")
    res = run_cli("phyllotaxis", params, "-o", tmp_path / "o")
    assert res.returncode == 2
    assert "never reached" in res.stderr and "reached area" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "o" / "scene.scn").exists()


# ---------------------------------------------------------------- CLI

def test_static_cli_writes_a_loadable_scene(tmp_path, write):
    params = write("p.toml", "[surface]\ncurve = 'paraboloid'\nheight = 0.2\n[primordia]\narea = 0.01\n"
                             "floret_id = 3\nplacement = 'ca'\nframe_end = 50\n")
    res = run_cli("phyllotaxis", params, "-o", tmp_path / "o", "--quiet")
    assert res.returncode == 0, res.stderr
    sc = read_scn(tmp_path / "o/scene.scn")
    assert len(sc) > 250 and all(p.kind == "ca" and p.id == 3 and p.frame_end == 50 for p in sc.placements)
    assert sc.groups[0].centre[1] == pytest.approx(0.2)
    d = np.array([p.scale[0] for p in sc.placements])
    np.testing.assert_allclose(d, 2 * math.sqrt(0.01 / math.pi), rtol=1e-5)
    assert no_partial_files(tmp_path / "o")


def test_yarrow_cli_writes_groups_with_parents(tmp_path, write):
    params = write("y.toml", "[hierarchy]\nlevels = 3\nframes = 150\nproduction_threshold = 6.0\n"
                             "meristem_threshold = 12.0\n")
    res = run_cli("phyllotaxis", params, "-o", tmp_path / "o", "--quiet")
    assert res.returncode == 0, res.stderr
    sc = read_scn(tmp_path / "o/scene.scn")
    groups = {p.group for p in sc.placements}
    assert len(groups) > 3
    for g in groups:
        parent = sc.groups[g].parent
        grand = sc.groups[parent].parent
        assert parent != -1 and grand == 0 and sc.groups[0].parent == -1  # umbellet -> branch -> root
    assert all(p.emergence is not None for p in sc.placements)


def test_static_hierarchy_honours_ca_placement(tmp_path, write):
    """``[primordia] placement = 'ca'`` gives a static recursive pattern ``ca:`` placements (it was
    silently written as ``o:``); the dynamic pattern keeps ``rba:`` at the same final positions."""
    text = ("[primordia]\nplacement = 'ca'\nframe_start = 2\nframe_end = 40\n[hierarchy]\nlevels = 3\n"
            "frames = 124\nproduction_threshold = [6.0, 8.0, 1.5]\nmeristem_threshold = [12.0, 6.0]\n")
    res = run_cli("phyllotaxis", write("s.toml", text), "-o", tmp_path / "s", "--quiet")
    assert res.returncode == 0, res.stderr
    static = read_scn(tmp_path / "s/scene.scn")
    assert len(static) > 10
    assert all(p.kind == "ca" and (p.frame_start, p.frame_end) == (2, 40) for p in static.placements)
    res = run_cli("phyllotaxis", write("d.toml", text.replace("frames = 124", "frames = 124\ndynamic = true")),
                  "-o", tmp_path / "d", "--quiet")
    assert res.returncode == 0, res.stderr
    dyn = read_scn(tmp_path / "d/scene.scn")
    assert all(p.kind == "rba" for p in dyn.placements)
    np.testing.assert_array_equal(static.arrays()["pos"], dyn.arrays()["pos"])
    res = run_cli("phyllotaxis", write("o.toml", text.replace("placement = 'ca'", "placement = 'o'")),
                  "-o", tmp_path / "o", "--quiet")
    assert all(p.kind == "o" for p in read_scn(tmp_path / "o/scene.scn").placements)


@pytest.mark.parametrize("text,needle", [
    ("[primordia]\ndivergence = 400\n", "divergence"),
    ("[primordia]\narea = 0.01\nbogus = 1\n", "did you mean"),
])
def test_bad_parameter_file_exits_2_with_one_line(tmp_path, write, text, needle):
    res = run_cli("phyllotaxis", write("b.toml", text), "-o", tmp_path / "o")
    assert res.returncode == 2 and needle in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and "b.toml:" in res.stderr
    assert not (tmp_path / "o").exists()


# ---------------------------------------------------------------- two levels, conical heads (fig. 5.4)

def test_compound_heads_carry_their_own_spirals_turned_away_from_the_centre(tmp_path, write):
    params = write("c.toml", "[surface]\ncurve = 'sphere_cap'\nradius = 3.0\nangle = 50\n[primordia]\narea = 0.5\n"
                             "start = 0.03\n[compound]\nhead_height = 0.6\nfloret_fraction = 0.02\n")
    res = run_cli("phyllotaxis", params, "-o", tmp_path / "o", "--quiet")
    assert res.returncode == 0, res.stderr
    sc = read_scn(tmp_path / "o/scene.scn")
    heads = sorted({p.group for p in sc.placements})
    assert len(heads) > 20 and all(sc.groups[g].parent == 0 for g in heads)
    away = 0
    for g in heads:
        rows = [p for p in sc.placements if p.group == g]
        c = sc.groups[g].centre
        d = np.array([np.linalg.norm(p.pos - c) for p in rows])
        assert d.max() <= math.sqrt(0.5 / math.pi) * 1.3  # within its head (a cone, slightly larger)
        assert 40 <= len(rows) <= 60  # about 1 / floret_fraction florets per head
        outward = c - sc.groups[0].centre
        outward[1] = 0
        last = rows[-1].pos - c  # the outermost floret of the head's spiral, seen from the top
        last[1] = 0
        if np.linalg.norm(outward) > 0.5:
            away += np.dot(last, outward) > 0.9 * np.linalg.norm(last) * np.linalg.norm(outward)
    assert away >= 0.9 * (len(heads) - 3)  # Hofmeister: on the side away from the centre
    # each head's floret axes follow the cone: tilted away from the head's own axis
    ups = np.array([p.up for p in sc.placements if p.group == heads[-1]])
    assert np.ptp(ups, axis=0).max() > 0.3


def test_compound_head_start_frees_each_heads_apex(tmp_path, write):
    """head_start = 0 puts a floret on each head's apex and the next about half a floret diameter
    from it (eq. 5.2 near the apex); head_start = 0.2 leaves a fifth of each (flat) head's radius
    free, and its florets farther apart (the orlaya's umbellets)."""
    from inflo.tools.phyllotaxis.generate import generate
    from inflo.tools.phyllotaxis.params import read_params

    for hs in (0.0, 0.2):
        params = write(f"c{hs}.toml", "[surface]\ncurve = 'disk'\n[primordia]\narea = 0.35\nstart = 0.1\n"
                                      "[compound]\nhead_curve = 'disk'\nhead_height = 0.0\nhead_fill = 0.4\n"
                                      f"floret_fraction = 0.04\nhead_start = {hs}\n")
        generate(read_params(params), tmp_path / f"o{hs}")
        sc = read_scn(tmp_path / f"o{hs}/scene.scn")
        a = sc.arrays()
        d = a["scale"][0, 0]
        head_r = math.sqrt(0.4 * 0.35 / math.pi)
        for g in sorted({int(x) for x in a["group"]}):
            m = a["group"] == g
            r = np.linalg.norm(a["pos"][m] - sc.groups[g].centre, axis=1)
            if hs == 0.0:
                assert r.min() < 1e-9
            else:
                assert r.min() > 0.15 * head_r
            pair = np.linalg.norm(a["pos"][m][:, None] - a["pos"][m][None], axis=2)
            np.fill_diagonal(pair, np.inf)
            assert (pair.min() / d > 0.7) == (hs > 0)
    with pytest.raises(FormatError, match="head_start"):
        read_params(write("bad.toml", "[compound]\nhead_start = 1.0\n"))


def test_con_generating_curve_end_to_end(tmp_path, write):
    # a dome drawn from the rim to the apex (reversed on load), end-point interpolating B-spline
    con = Contour.from_points([[1.0, 0, 0], [0.9, 0.35, 0], [0.5, 0.6, 0], [0.0, 0.65, 0]], type="oe")
    write_con(tmp_path / "dome.con", con)
    prof = load_curve(str(tmp_path / "dome.con"), radius=2.0)
    assert prof.r[0] == pytest.approx(0.0, abs=1e-9) and prof.r[-1] == pytest.approx(2.0)
    assert prof.y[0] == pytest.approx(1.3)
    params = write("p.toml", "[surface]\ncurve = 'dome.con'\nradius = 2.0\n[primordia]\narea = 0.02\n")
    res = run_cli("phyllotaxis", params, "-o", tmp_path / "o", "--quiet")
    assert res.returncode == 0, res.stderr
    sc = read_scn(tmp_path / "o/scene.scn")
    total = sum(p.scale[0] ** 2 * math.pi / 4 for p in sc.placements)
    assert total == pytest.approx(prof.total_area, rel=0.02)  # the primordia tile the surface
    bad = Contour.from_points([[0, 0, 0], [0.5, 0.1, 0], [-1.5, 0.3, 0], [-1.5, 0.5, 0], [0.8, 0.7, 0]], type="oe")
    write_con(tmp_path / "bad.con", bad)
    res = run_cli("phyllotaxis", write("b.toml", "[surface]\ncurve = 'bad.con'\n"), "-o", tmp_path / "b")
    assert res.returncode == 2 and "bad.con" in res.stderr and "axis" in res.stderr
    assert not (tmp_path / "b").exists()


@pytest.mark.parametrize("old, new, line_key, expect", [
    ("[dynamics]\n", "[dynamics]\nmax_count = 10\n", "max_count = 10", "dynamics.max_count"),
    ("inner_area = 1.0\n", "inner_area = 0.0001\n", "inner_area = 0.0001", "no primordium forms"),
])
def test_refusals_of_key_combinations_name_the_line(tmp_path, old, new, line_key, expect):
    """A refusal raised by the model for a combination of keys names the file and the line of
    the key its message names (one line, exit 2, no output)."""
    from pathlib import Path

    src = Path(__file__).resolve().parents[1] / "pipelines" / "sunflower" / "draft" / "head.toml"
    text = src.read_text()
    assert old in text
    text = text.replace(old, new, 1)
    f = tmp_path / "head.toml"
    f.write_text(text)
    line = text.splitlines().index(line_key) + 1
    r = run_cli("phyllotaxis", f, "-o", tmp_path / "out", "-q")
    assert r.returncode == 2, r.stderr
    err = r.stderr.strip()
    assert len(err.splitlines()) == 1 and f"{f}:{line}: " in err and expect in err, err
    assert not (tmp_path / "out").exists()
