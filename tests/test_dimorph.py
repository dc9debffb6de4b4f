"""dimorph: cones K(P), d_min (thesis eq. 6.1-6.2), fates (figs. 6.2-6.4), the CLI and sweep."""
from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import no_partial_files, run_cli

from inflo.formats.scn import Group, Placement, Scene, read_scn, write_scn
from inflo.tools.dimorph.cones import FATE_DISK, FATE_RAY, FATE_SMALL_RAY, d_min, d_min_reference, fates
from inflo.tools.dimorph.dimorph import DimorphOptions, dimorph_scene
from inflo.tools.dimorph.sweep import simple_head, sweep_alpha, sweep_n

FIB = {1, 2, 3, 5, 8, 13, 21, 34, 55, 89, 144}


def _at(deg, r=1.0):
    a = math.radians(deg)
    return [1.0 + r * math.cos(a), 0.0, r * math.sin(a)]


@pytest.mark.parametrize("alpha", [60.0, 90.0, 120.0])
def test_neighbour_just_inside_and_just_outside_the_cone(alpha):
    # P at (1, 0, 0), head centre O at the origin: the cone axis is +X, half-angle alpha / 2
    half = alpha / 2
    inside = np.array([[1.0, 0, 0], _at(half - 0.5)])
    outside = np.array([[1.0, 0, 0], _at(half + 0.5)])
    assert d_min(inside, np.zeros(3), alpha)[0] == pytest.approx(1.0)
    assert math.isinf(d_min(outside, np.zeros(3), alpha)[0])
    # eq. 6.1 as printed (alpha a half-angle): the same florets at twice the angle
    assert d_min(np.array([[1.0, 0, 0], _at(alpha - 0.5)]), np.zeros(3), alpha, half_angle=True)[0] == pytest.approx(1.0)
    # a floret behind P never counts, and the nearest one inside the cone wins (eq. 6.2)
    pts = np.array([[1.0, 0, 0], [0.9, 0, 0], _at(0, 2.0), _at(half - 1, 1.5)])
    assert d_min(pts, np.zeros(3), alpha)[0] == pytest.approx(1.5)


def test_kdtree_search_matches_brute_force_eq_6_1_6_2():
    rng = np.random.default_rng(7)
    for _ in range(3):
        pos = rng.normal(size=(300, 3)) * [1.0, 0.05, 1.0]
        centre = rng.normal(size=3) * 0.1
        for alpha in (30.0, 75.0, 150.0):
            ref = d_min_reference(pos, centre, alpha)
            got = d_min(pos, centre, alpha)
            assert np.array_equal(np.isinf(got), np.isinf(ref))
            np.testing.assert_allclose(got[np.isfinite(ref)], ref[np.isfinite(ref)], rtol=1e-12)
            bounded = d_min(pos, centre, alpha, radius=0.25)  # a threshold bounds the search
            ref_b = np.where(ref <= 0.25, ref, np.inf)
            assert np.array_equal(np.isinf(bounded), np.isinf(ref_b))
            np.testing.assert_allclose(bounded[np.isfinite(ref_b)], ref_b[np.isfinite(ref_b)], rtol=1e-12)


def test_ray_counts_of_simple_heads_are_fibonacci_numbers():
    # fig. 6.3: n = 82 at alpha = 75 deg; fig. 6.2: a head whose rays number 21
    assert sweep_n([82], 75.0)[0] == 34
    assert sweep_n([50], 75.0)[0] == 21
    counts = sweep_n(range(10, 301, 7), 75.0)
    assert np.mean([c in FIB for c in counts]) > 0.6  # canalization: most heads on Fibonacci numbers
    assert np.all(np.diff(counts) >= 0)
    by_alpha = sweep_alpha(82, np.arange(20.0, 120.1, 2.0))
    assert np.mean([c in FIB for c in by_alpha]) > 0.6
    assert {21, 34, 55} <= set(by_alpha.tolist())
    assert np.all(np.diff(by_alpha) <= 0)  # wider cones: fewer rays


def test_fate_rules():
    dmin = np.array([0.1, 0.5, 1.0, 2.0, np.inf])
    assert fates(dmin).tolist() == [FATE_DISK] * 4 + [FATE_RAY]
    assert fates(dmin, [0.7]).tolist() == [FATE_DISK, FATE_DISK, FATE_RAY, FATE_RAY, FATE_RAY]
    assert fates(dmin, [1.5, 0.4]).tolist() == [FATE_DISK, FATE_SMALL_RAY, FATE_SMALL_RAY, FATE_RAY, FATE_RAY]


def _compound(n=40, ring=2.6):
    """A central head and six around it (fig. 6.4): groups 1..7 with parent 0."""
    head = simple_head(n)
    scene = Scene()
    scene.groups[0] = Group(0, [0, 0, 0], -1)
    centres = [np.zeros(3)] + [ring * np.array([math.cos(a), 0, math.sin(a)])
                               for a in np.radians(np.arange(0, 360, 60))]
    for g, c in enumerate(centres, 1):
        scene.groups[g] = Group(g, c, 0)
        for p in head:
            scene.placements.append(Placement("o", 0, p + c, [0.1, 0.1, 0.1], [0, 1, 0], [1, 0, 0], group=g))
    return scene, np.array(centres)


def _by_head(out, kind):
    return np.bincount([p.group for p in out.placements if p.type == kind], minlength=8)[1:]


def test_threshold_modes_separate_heads_as_in_fig_6_4():
    scene, centres = _compound()
    th_a, th_b = 0.45, 3.0  # within-head spacing ~0.28 < Th_a < gap between heads ~0.6 < ring < Th_b
    a, _ = dimorph_scene(scene, DimorphOptions(53.0, (th_a,)))
    rays_a = _by_head(a, "ray")
    assert rays_a.min() >= 8 and len(set(rays_a.tolist())) == 1  # every head alike (fig. 6.4a)
    b, _ = dimorph_scene(scene, DimorphOptions(53.0, (th_b,)))
    rays_b = _by_head(b, "ray")
    assert rays_b[0] == 0 and rays_b[1:].min() > 0  # only the periphery (fig. 6.4b)
    for p in b.placements:
        if p.type == "ray":
            c = centres[p.group - 1]
            assert np.dot(p.pos - c, c) > 0  # on the outer side of its head
    c, counts = dimorph_scene(scene, DimorphOptions(53.0, (th_a, th_b), ray_id=2, small_ray_id=1, ray_scale=2.0))
    assert _by_head(c, "ray").tolist() == rays_b.tolist()  # large rays as in 6.4b
    small = [p for p in c.placements if p.type == "small_ray"]
    assert len(small) > 0 and all(p.id == 1 for p in small)
    dm = counts["d_min"]
    for k, p in enumerate(c.placements):
        if p.type == "small_ray":  # size proportional to d_min (fig. 6.4c)
            assert p.scale[0] == pytest.approx(0.1 * 2.0 * dm[k] / th_b)
            assert th_a < dm[k] <= th_b
        elif p.type == "ray":
            assert p.id == 2 and p.scale[0] == pytest.approx(0.2)


def test_cli_minimal_invocation_sets_ids_types_and_keeps_order(tmp_path):
    scene = Scene()
    for p in simple_head(82):  # no group lines: one head, centre = centroid
        scene.placements.append(Placement("ca", 5, p, [0.1] * 3, [0, 1, 0], [1, 0, 0], frame_start=0, frame_end=9))
    write_scn(tmp_path / "in.scn", scene)
    res = run_cli("dimorph", tmp_path / "in.scn", "--alpha", 75, "-o", tmp_path / "out.scn")
    assert res.returncode == 0, res.stderr
    out = read_scn(tmp_path / "out.scn")
    assert len(out) == 82
    np.testing.assert_allclose([p.pos for p in out.placements], [p.pos for p in scene.placements], atol=1e-6)
    rays = [p for p in out.placements if p.type == "ray"]
    assert len(rays) in FIB and all(p.id == 1 for p in rays)
    assert all(p.id == 0 and p.type == "disk" for p in out.placements if p.type != "ray")
    assert all(p.kind == "ca" and p.frame_end == 9 for p in out.placements)
    res = run_cli("dimorph", "run", tmp_path / "in.scn", "--alpha", 75, "-o", tmp_path / "out2.scn",
                  "--ray-id", 7, "--ray-scale", 3)
    assert res.returncode == 0, res.stderr
    out2 = read_scn(tmp_path / "out2.scn")
    assert [p.type for p in out2.placements] == [p.type for p in out.placements]
    assert all(p.id == 7 and p.scale[0] == pytest.approx(0.3) for p in out2.placements if p.type == "ray")


def test_cli_bad_input_exits_2_without_output(tmp_path, write):
    bad = write("bad.scn", "o: 0 0 0 0 1 1 1 0 1 0 1 0\n")
    res = run_cli("dimorph", bad, "--alpha", 75, "-o", tmp_path / "out.scn")
    assert res.returncode == 2 and "bad.scn:1" in res.stderr and len(res.stderr.strip().splitlines()) == 1
    good = write("good.scn", "o: 0 0 0 0 1 1 1 0 1 0 1 0 0\no: 0 1 0 0 1 1 1 0 1 0 1 0 0\n")
    res = run_cli("dimorph", good, "--alpha", 400, "-o", tmp_path / "out.scn")
    assert res.returncode == 2 and "alpha" in res.stderr
    assert not (tmp_path / "out.scn").exists() and no_partial_files(tmp_path)


def test_sweep_cli_writes_csv_and_png(tmp_path):
    res = run_cli("dimorph", "sweep", "-o", tmp_path / "sw", "--n-min", 78, "--n-max", 84,
                  "--alpha-min", 60, "--alpha-max", 80, "--alpha-step", 10, "--quiet")
    assert res.returncode == 0, res.stderr
    lines = (tmp_path / "sw/sweep_n.csv").read_text().splitlines()
    assert lines[1] == "n,rays,fibonacci" and lines[-1] == "84,34,1"
    rows = (tmp_path / "sw/sweep_alpha.csv").read_text().splitlines()[2:]
    assert [r.split(",")[0] for r in rows] == ["60.000000", "70.000000", "80.000000"]
    assert (tmp_path / "sw/sweep_n.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (tmp_path / "sw/sweep_alpha.png").stat().st_size > 1000
