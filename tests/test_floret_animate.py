"""floret-animate: intrinsic interpolation (thesis 2.3), timing (8 b)), CLI."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from conftest import REPO, run_cli

from inflo.formats.errors import InputError
from inflo.formats.floret import Floret, Organ, full_petal, petals, read_floret, write_floret
from inflo.formats.func import Function, write_func
from inflo.tools.floret_animate.animate import (
    FloretAnimator,
    check_growth,
    developmental_times,
    frame_times,
    key_times,
)
from inflo.tools.floret_animate.interpolate import (
    blend_polylines,
    decode_polylines,
    encode_polylines,
    rmf_frames,
)

EXAMPLES = REPO / "pipelines" / "examples"


def rot_z(deg):
    t = math.radians(deg)
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def curved_petal_polyline(m=6):
    y = np.linspace(0.0, 1.0, m)
    return np.stack([0.25 * np.sin(2.0 * y) + 0.1, y, np.zeros(m)], axis=-1)


# ----------------------------------------------------------------------------------------------
# rotation-minimizing frames and the encoding
# ----------------------------------------------------------------------------------------------


def test_encode_decode_round_trip():
    rng = np.random.default_rng(3)
    pts = rng.normal(size=(7, 9, 3))
    np.testing.assert_allclose(decode_polylines(encode_polylines(pts)), pts, atol=1e-13)


def test_rmf_of_planar_polyline_has_no_twist():
    # a planar zig-zag polyline in a tilted plane
    rng = np.random.default_rng(5)
    a, b = np.linalg.qr(rng.normal(size=(3, 3)))[0][:, :2].T
    normal = np.cross(a, b)
    s = np.cumsum(rng.uniform(0.2, 1.0, 12))
    pts = (np.outer(s, a) + np.outer(np.sin(3 * s), b))[None]
    frames = rmf_frames(pts)
    tang = frames[0, :, :, 0]
    np.testing.assert_allclose(tang @ normal, 0.0, atol=1e-12)  # tangents stay in the plane
    # the frame turns only about the plane normal: the normal's component along it is constant
    comp = frames[0, :, :, 1] @ normal
    np.testing.assert_allclose(comp, comp[0], atol=1e-12)
    comp_b = frames[0, :, :, 2] @ normal
    np.testing.assert_allclose(comp_b, comp_b[0], atol=1e-12)
    # and the rotations in the moving frame have no component about the tangent (no twist)
    code = encode_polylines(pts)
    np.testing.assert_allclose(code.rots[0, :, 1], 0.0, atol=1e-12)


def test_rmf_of_space_curve_rotates_about_binormals_only():
    t = np.linspace(0, 4 * np.pi, 40)
    helix = np.stack([np.cos(t), np.sin(t), 0.3 * t], axis=-1)[None]
    code = encode_polylines(helix)
    np.testing.assert_allclose(code.rots[0, :, 1], 0.0, atol=1e-12)
    frames = rmf_frames(helix)
    f = frames[0]
    np.testing.assert_allclose(np.einsum("kab,kac->kbc", f, f), np.broadcast_to(np.eye(3), f.shape), atol=1e-12)


def test_swing_open_120_keeps_lengths_linear_blend_shrinks():
    a = curved_petal_polyline()[None]
    b = a @ rot_z(120).T
    la = np.linalg.norm(np.diff(a, axis=1), axis=2)
    for s in (0.25, 0.5, 0.75):
        mid = blend_polylines(a, b, s)
        lm = np.linalg.norm(np.diff(mid, axis=1), axis=2)
        np.testing.assert_allclose(lm, la, rtol=1e-12)  # equal lengths stay equal
        lin = (1 - s) * a + s * b
        ll = np.linalg.norm(np.diff(lin, axis=1), axis=2)
        assert (ll < 0.9 * la).all()  # linear blending of positions shrinks the petal
    # at the midpoint the intrinsic blend is the pose rotated by 60 degrees (the petal rigidly
    # swings), the linear one has chords cos(60) = 0.5 times as long
    mid = blend_polylines(a, b, 0.5)
    np.testing.assert_allclose(mid - mid[:, :1], (a - a[:, :1]) @ rot_z(60).T, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(np.diff((a + b) / 2, axis=1), axis=2), 0.5 * la, rtol=1e-12)


def test_swing_with_growth_lengths_stay_between_poses():
    a = curved_petal_polyline()[None]
    b = 1.6 * (a @ rot_z(120).T)
    la = np.linalg.norm(np.diff(a, axis=1), axis=2)
    lb = np.linalg.norm(np.diff(b, axis=1), axis=2)
    for s in np.linspace(0, 1, 11):
        lm = np.linalg.norm(np.diff(blend_polylines(a, b, s), axis=1), axis=2)
        assert (lm >= np.minimum(la, lb) - 1e-12).all() and (lm <= np.maximum(la, lb) + 1e-12).all()


def test_slerp_endpoints_reproduce_key_poses():
    rng = np.random.default_rng(11)
    a = rng.normal(size=(5, 7, 3))
    b = rng.normal(size=(5, 7, 3))
    np.testing.assert_allclose(blend_polylines(a, b, 0.0), a, atol=1e-12, rtol=0)
    np.testing.assert_allclose(blend_polylines(a, b, 1.0), b, atol=1e-12, rtol=0)


def test_zero_length_segment_and_fold_back():
    pts = np.array([[[0, 0, 0], [0, 1, 0], [0, 1, 0], [0, 2, 0], [0, 1.5, 0]]], float)
    np.testing.assert_allclose(decode_polylines(encode_polylines(pts)), pts, atol=1e-13)


# ----------------------------------------------------------------------------------------------
# florets
# ----------------------------------------------------------------------------------------------


def petal_organ(cp, **kw):
    return Organ("petal", 2, 3, cp, **kw)


def swing_poses(angle=120.0):
    """A flat bilateral petal (half: 3 columns, 5 rows) standing up, then swung open about +Z."""
    rows = []
    for j, y in enumerate(np.linspace(0, 1, 5)):
        rows.append([[0.1, y, 0.0], [0.1, y, 0.1 + 0.05 * j], [0.1, y, 0.2 + 0.05 * j]])
    cp = np.array(rows)
    a = Floret("f", (petal_organ(cp, symmetry_n=5, bilateral=True),), 0.0)
    rotated = (cp - [0.1, 0, 0]) @ rot_z(-angle).T + [0.1, 0, 0]  # +Y toward +X
    b = Floret("f", (petal_organ(rotated, symmetry_n=5, bilateral=True),), 1.0)
    return a, b


def test_animator_endpoints_and_lengths():
    a, b = swing_poses()
    anim = FloretAnimator([a, b])
    f0, f1 = anim.at(0.0), anim.at(1.0)
    np.testing.assert_allclose(f0.organs[0].control_points, a.organs[0].control_points, atol=1e-12, rtol=0)
    np.testing.assert_allclose(f1.organs[0].control_points, b.organs[0].control_points, atol=1e-12, rtol=0)
    cps = [anim.at(t).organs[0].control_points for t in np.linspace(0, 1, 9)]
    la = np.linalg.norm(np.diff(a.organs[0].control_points, axis=0), axis=2)
    for cp in cps:
        np.testing.assert_allclose(np.linalg.norm(np.diff(cp, axis=0), axis=2), la, rtol=1e-9)
    assert f0.key_time == 0.0 and f1.key_time == 1.0


def test_tilt_and_phase_blend_linearly():
    a, b = swing_poses(30)
    a = dataclasses.replace(a, organs=(dataclasses.replace(a.organs[0], tilt_deg=0.0, symmetry_phase_deg=0.0),))
    b = dataclasses.replace(b, organs=(dataclasses.replace(b.organs[0], tilt_deg=40.0, symmetry_phase_deg=10.0),))
    mid = FloretAnimator([a, b]).at(0.25).organs[0]
    assert mid.tilt_deg == pytest.approx(10.0) and mid.symmetry_phase_deg == pytest.approx(2.5)


def test_three_key_poses_use_their_times():
    a, c = swing_poses(90)
    mid_cp = FloretAnimator([a, c]).at(0.5).organs[0].control_points * 1.2
    b = Floret("f", (dataclasses.replace(a.organs[0], control_points=mid_cp),), 0.25)
    anim = FloretAnimator([a, b, c])
    np.testing.assert_array_equal(anim.times, [0.0, 0.25, 1.0])
    np.testing.assert_allclose(anim.at(0.25).organs[0].control_points, mid_cp, atol=1e-12)
    assert anim.segment(0.125) == (0, 0.5)
    k, s = anim.segment(0.625)
    assert k == 1 and s == pytest.approx(0.5)


def test_key_times_evenly_spaced_or_errors():
    a, b = swing_poses()
    a0 = dataclasses.replace(a, key_time=None)
    b0 = dataclasses.replace(b, key_time=None)
    np.testing.assert_array_equal(key_times([a0, b0, b0], ["a", "b", "c"]), [0, 0.5, 1])
    with pytest.raises(InputError, match="every key pose or in none"):
        key_times([a, b0], ["a.floret", "b.floret"])
    with pytest.raises(InputError, match="b.floret.*greater than"):
        key_times([b, a], ["a.floret", "b.floret"])


def test_fused_control_points_lie_on_symmetry_plane_in_every_frame():
    bud = read_floret(EXAMPLES / "disk_bud.floret")
    op = read_floret(EXAMPLES / "disk_open.floret")
    anim = FloretAnimator([bud, op])
    for fr in anim.frames(7):
        for organ in fr.organs:
            n, k = organ.symmetry_n, organ.fused
            h = math.pi / n
            net = full_petal(organ)
            np.testing.assert_allclose(net[:k, 0] @ [math.sin(h), 0, math.cos(h)], 0, atol=1e-12)
            np.testing.assert_allclose(net[:k, -1] @ [-math.sin(h), 0, math.cos(h)], 0, atol=1e-12)
            cps = petals(organ)
            np.testing.assert_allclose(cps[1, :k, -1], cps[0, :k, 0], atol=1e-12)


# ----------------------------------------------------------------------------------------------
# timing
# ----------------------------------------------------------------------------------------------


def test_linear_and_sigmoid_timing():
    taus = frame_times(5)
    np.testing.assert_array_equal(taus, [0, 0.25, 0.5, 0.75, 1])
    np.testing.assert_array_equal(developmental_times(taus, [0.0, 1.0]), taus)
    sig = Function.from_points([(0, 0), (0.3, 0), (0.5, 0.5), (0.7, 1), (1, 1)], name="growth")
    check_growth(sig)
    b = developmental_times(frame_times(101), [0.0, 1.0], sig)
    assert b[0] == 0.0 and b[-1] == 1.0 and (np.diff(b) >= 0).all()
    assert b[25] < 0.1 and b[75] > 0.9  # slow start and end, fast in the middle
    np.testing.assert_allclose(developmental_times([0.0, 0.5, 1.0], [2.0, 6.0]), [2, 4, 6])


def test_non_monotone_growth_is_an_error(tmp_path):
    bad = Function.from_points([(0, 0), (0.3, 0.9), (0.6, 0.1), (1, 1)], [1, 3, 3, 1], name="bad")
    with pytest.raises(InputError, match="non-decreasing"):
        check_growth(bad, "bad.func")
    over = Function.from_points([(0, 0), (0.5, 1.5), (1, 1.6)], name="over")
    with pytest.raises(InputError, match=r"\[0, 1\]"):
        check_growth(over, "over.func")


# ----------------------------------------------------------------------------------------------
# CLI
# ----------------------------------------------------------------------------------------------


def test_cli_default_100_frames(tmp_path):
    out = tmp_path / "frames"
    out.mkdir()
    (out / "frame_0150.floret").write_text("stale")
    res = run_cli("floret-animate", EXAMPLES / "disk_bud.floret", EXAMPLES / "disk_open.floret",
                  "-o", out, "-q")
    assert res.returncode == 0, res.stderr
    files = sorted(out.glob("*.floret"))
    assert len(files) == 100 and files[0].name == "frame_0000.floret" and files[-1].name == "frame_0099.floret"
    f0, f99 = read_floret(files[0]), read_floret(files[-1])
    assert f0.key_time == 0.0 and f99.key_time == 1.0
    bud = read_floret(EXAMPLES / "disk_bud.floret")
    np.testing.assert_allclose(f0.organs[0].control_points, bud.organs[0].control_points, atol=1e-12)
    # lambda/eta .func paths still resolve from the frame folder
    assert f0.organs[0].eta == bud.organs[0].eta


def test_cli_growth_and_errors(tmp_path, write):
    bud, op = EXAMPLES / "disk_bud.floret", EXAMPLES / "disk_open.floret"
    res = run_cli("floret-animate", bud, op, "-o", tmp_path / "f", "--frames", "11", "--growth",
                  EXAMPLES / "sigmoid.func", "-q")
    assert res.returncode == 0, res.stderr
    times = [read_floret(p).key_time for p in sorted((tmp_path / "f").glob("*.floret"))]
    assert len(times) == 11 and times[1] < 0.02 and times[-2] > 0.98 and times[5] == pytest.approx(0.5)

    bad = tmp_path / "bad.func"
    write_func(bad, Function.from_points([(0, 0), (0.3, 0.9), (0.6, 0.1), (1, 1)], [1, 3, 3, 1], name="bad"))
    res = run_cli("floret-animate", bud, op, "-o", tmp_path / "g", "--growth", bad)
    assert res.returncode == 2 and "non-decreasing" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1

    # key poses with different grids
    other = read_floret(bud)
    org = other.organs[0]
    cp = np.concatenate([org.control_points, org.control_points[-1:] + [0, 0.1, 0]])
    other = dataclasses.replace(other, organs=(dataclasses.replace(org, control_points=cp, fused=5), other.organs[1]))
    odd = tmp_path / "odd.floret"
    write_floret(odd, other)
    res = run_cli("floret-animate", bud, odd, "-o", tmp_path / "h")
    assert res.returncode == 2 and "grid" in res.stderr and "odd.floret" in res.stderr

    # a fused count larger than the boundary (the reader rejects it on its line)
    text = bud.read_text().replace("fused: 6", "fused: 9", 1)
    res = run_cli("floret-animate", write("big.floret", text), op, "-o", tmp_path / "i")
    assert res.returncode == 2 and "fused" in res.stderr and "big.floret:" in res.stderr

    res = run_cli("floret-animate", bud, "-o", tmp_path / "j")
    assert res.returncode == 2 and "at least 2 key poses" in res.stderr


# ----------------------------------------------------------------------------------------------
# growth-function mode (Lu et al.)
# ----------------------------------------------------------------------------------------------

from inflo.tools.floret_animate.growth import growth_integral, lu_frames, parse_lu_params  # noqa: E402


def bezier_pose(n=5):
    y = np.linspace(0, 0.3, 4)
    z = np.linspace(-0.05, 0.05, 4)
    cp = np.stack(np.broadcast_arrays(np.full((4, 4), 0.05), y[:, None], z[None, :]), axis=-1)
    return Floret("lu", (Organ("petal", 3, 3, cp, symmetry_n=n),), 0.0)


def test_growth_integral_eq4():
    c = np.array([0.6, -0.4, 0.3])
    x = np.linspace(0.2, 0.9, 20001)
    num = np.trapezoid(c[0] * x ** 2 + c[1] * x + c[2], x)
    assert growth_integral(c, 0.2, 0.9) == pytest.approx(num, rel=1e-8)
    assert growth_integral([0, 0, -1.0], 0, 0.5) == -0.5  # growth may be negative


def test_lu_row_factors_and_directions():
    params = parse_lu_params({"rate": [{"length": [0, 0, 1.0], "width": [0, 0, 0.5], "depth": [0, 0, 0.2]}]})
    pose = bezier_pose(1)
    frames = list(lu_frames(pose, params, n_frames=3))
    assert [f.key_time for f in frames] == [0.0, 0.5, 1.0]
    cp0 = pose.organs[0].control_points
    cp1 = frames[-1].organs[0].control_points
    d = cp1 - cp0
    np.testing.assert_allclose(d[0], 0.0, atol=1e-15)  # the base row stays
    # length along +Y (the petal's axis), scaled 0, 1/3, 2/3, 1 by row
    np.testing.assert_allclose(d[:, 1, 1], np.array([0, 1 / 3, 2 / 3, 1]) * 1.0, atol=1e-12)
    # width: the edges move apart symmetrically, the middle columns less
    np.testing.assert_allclose(d[3, :, 2], 0.5 * np.array([-1, -1 / 3, 1 / 3, 1]), atol=1e-12)
    # depth: along L x W = Y x Z = +X
    np.testing.assert_allclose(d[3, :, 0], 0.2, atol=1e-12)


def test_lu_rate_pieces_and_overrides():
    params = parse_lu_params({
        "rate": [{"start": 0.0, "length": [0, 0, 1.0]}, {"start": 0.5, "length": [0, 0, -1.0]}],
        "override": [{"row": 3, "col": 0, "factor": [2.0, 1.0, 1.0]}],
    })
    frames = list(lu_frames(bezier_pose(1), params, n_frames=5))
    ys = [f.organs[0].control_points[3, 1, 1] for f in frames]
    np.testing.assert_allclose(np.array(ys) - ys[0], [0, 0.25, 0.5, 0.25, 0.0], atol=1e-12)
    d = frames[2].organs[0].control_points - frames[0].organs[0].control_points
    assert d[3, 0, 1] == pytest.approx(2 * d[3, 1, 1])


def test_lu_seeded_perturbation():
    params = parse_lu_params({"rate": [{"length": [0, 0, 1.0]}], "perturbation": 0.1})
    a = list(lu_frames(bezier_pose(), params, n_frames=3, seed=4))
    b = list(lu_frames(bezier_pose(), params, n_frames=3, seed=4))
    c = list(lu_frames(bezier_pose(), params, n_frames=3, seed=5))
    assert [o.name for o in a[-1].organs] == [f"petal_{k}" for k in range(5)]
    assert [o.symmetry_phase_deg for o in a[-1].organs] == [0, 72, 144, 216, 288]
    assert all(x == y for x, y in zip(a[-1].organs, b[-1].organs))
    assert a[-1].organs[0] != c[-1].organs[0]
    assert not np.allclose(a[-1].organs[0].control_points, a[-1].organs[1].control_points)


def test_lu_bad_parameters(tmp_path):
    with pytest.raises(InputError, match="keys"):
        parse_lu_params({"rate": [{"length": [0, 0, 1]}], "speed": 1})
    with pytest.raises(InputError, match="3 numbers"):
        parse_lu_params({"rate": [{"length": [0, 1]}]})
    with pytest.raises(InputError, match="start at 0"):
        parse_lu_params({"rate": [{"start": 0.2, "length": [0, 0, 1]}]})
    params = parse_lu_params({"rate": [{"length": [0, 0, 1]}], "organ": "corolla"})
    bud = read_floret(EXAMPLES / "disk_bud.floret")
    with pytest.raises(InputError, match="bicubic Bezier"):
        list(lu_frames(bud, params, n_frames=2))


def test_lu_cli_example(tmp_path):
    out = tmp_path / "frames"
    res = run_cli("floret-animate", EXAMPLES / "lu_bud.floret", "--lu", EXAMPLES / "lu_growth.toml",
                  "--seed", "1", "--frames", "9", "-o", out, "-q")
    assert res.returncode == 0, res.stderr
    frames = sorted(out.glob("*.floret"))
    assert len(frames) == 9
    res = run_cli("polygonize", out, "-o", tmp_path / "obj", "-q")
    assert res.returncode == 0, res.stderr
    res = run_cli("floret-animate", EXAMPLES / "lu_bud.floret", EXAMPLES / "lu_bud.floret",
                  "--lu", EXAMPLES / "lu_growth.toml", "-o", tmp_path / "x")
    assert res.returncode == 2 and "1 key pose" in res.stderr
