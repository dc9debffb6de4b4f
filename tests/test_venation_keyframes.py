"""Runions sec. 5.2.1's key-frame interpolation of blade surfaces in ``venation`` (eq. 5.2, figs.
5.3, 5.9) and the first leaf of *Arabidopsis* by key frames (sec. 5.3.2, figs. 5.10-5.11): the
interpolation and the point inversion against their analytic forms, the refusals, and the
developmental order of the example against the observed one."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from inflo.formats.bezier_surface import BezierPatch, BezierSurface, write_bezier_surface
from inflo.tools.venation.blade import KeyFrames, bezier_eval
from inflo.tools.venation.cli import main
from inflo.tools.venation.events import departures, read_events, secondary_pairs

EXAMPLES = Path(__file__).resolve().parents[1] / "pipelines" / "examples" / "venation"


def _affine(origin, du, dv):
    """(4, 4, 2): the control net of the affine patch Q(u, v) = origin + u du + v dv."""
    g = np.linspace(0.0, 1.0, 4)
    return np.array([[np.asarray(origin) + a * np.asarray(du) + b * np.asarray(dv) for b in g] for a in g], float)


def _leaf(h, w1, y1, w2, y2):
    net = np.zeros((4, 4, 2))
    for i, (w, y) in enumerate([(0.0, 0.0), (w1, y1), (w2, y2), (0.0, h)]):
        for j in range(4):
            net[i, j] = (w * (-1.0 + 2.0 * j / 3.0), y)
    return net


def test_affine_key_frames_interpolate_linearly():
    a = _affine([0.0, 0.0], [0.0, 1.0], [1.0, 0.0])
    b = _affine([1.0, 0.0], [0.0, 3.0], [2.0, 1.0])
    kf = KeyFrames([a, b], [0, 10])
    uv = np.random.default_rng(0).random((200, 2))
    for t in (0.0, 2.5, 7.0, 10.0):
        s = t / 10.0
        want = (1 - s) * (uv[:, [1]] * [1.0, 0.0] + uv[:, [0]] * [0.0, 1.0]) + s * (
            np.array([1.0, 0.0]) + uv[:, [0]] * [0.0, 3.0] + uv[:, [1]] * [2.0, 1.0])
        assert np.allclose(kf.forward(uv, t), want, atol=1e-12)
    # before the first and after the last key frame the blade is that key frame
    assert np.allclose(kf.forward(uv, -5), kf.forward(uv, 0))
    assert np.allclose(kf.forward(uv, 50), kf.forward(uv, 10))
    # the margin is the image of the square: the parallelogram's area
    m = kf.margin(10)
    x, y = m[:, 0], m[:, 1]
    assert 0.5 * abs((x * np.roll(y, -1) - np.roll(x, -1) * y).sum()) == pytest.approx(6.0, rel=1e-12)


@pytest.mark.parametrize("t", [0.0, 3.0, 10.0])
def test_point_inversion_recovers_u_v_on_a_leaf(t):
    """eq. 5.2: E_P(u, v) = 0 at the pre-image, away from the collapsed base and tip rows."""
    kf = KeyFrames([_leaf(1.0, 0.14, 0.25, 0.18, 0.75), _leaf(3.0, 1.6, 0.4, 1.8, 2.4)], [0, 10])
    rng = np.random.default_rng(1)
    uv = np.column_stack([0.03 + 0.94 * rng.random(500), rng.random(500)])
    p = kf.forward(uv, t)
    back = kf.inverse(p, t)
    assert np.abs(kf.forward(back, t) - p).max() < 1e-9
    assert np.abs(back - uv).max() < 1e-6
    # a point outside the blade goes to its nearest point of the blade (on the margin)
    out = kf.inverse([[5.0, 0.5 * kf.forward([[0.5, 0.0]], t)[0, 1] + 0.4]], t)
    assert out.min() >= 0.0 and out.max() <= 1.0
    assert min(out[0, 1], 1.0 - out[0, 1]) < 1e-6 or out[0, 0] in (0.0, 1.0)


def test_bezier_derivatives_match_differences():
    net = _leaf(2.0, 0.9, 0.5, 1.2, 1.5)
    u, v, h = np.array([0.3, 0.7]), np.array([0.2, 0.9]), 1e-6
    _, qu, qv = bezier_eval(net, u, v, derivatives=True)
    assert np.allclose(qu, (bezier_eval(net, u + h, v) - bezier_eval(net, u - h, v)) / (2 * h), atol=1e-6)
    assert np.allclose(qv, (bezier_eval(net, u, v + h) - bezier_eval(net, u, v - h)) / (2 * h), atol=1e-6)


def _write_s(path, net):
    cp = np.concatenate([net, np.zeros((4, 4, 1))], axis=2)
    write_bezier_surface(path, BezierSurface(patches=(BezierPatch(name="blade", control_points=cp),),
                                             heading=np.array([0.0, 1.0, 0.0]), up=np.array([0.0, 0.0, 1.0])))


KF = """seed = 1
[blade]
[growth]
type = "key_frames"
key_frames = ["a.s", "b.s"]
times = [0, 30]
[veins]
pattern = "closed"
step = 0.05
kill_distance = 0.05
[sources]
birth_source = 0.4
birth_vein = 0.4
placement = "largest_empty_circle"
"""


def _kf_files(tmp_path, b=None):
    _write_s(tmp_path / "a.s", _leaf(0.6, 0.2, 0.2, 0.25, 0.45))
    _write_s(tmp_path / "b.s", _leaf(2.0, 0.9, 0.5, 1.1, 1.5) if b is None else b)


def test_key_frame_run_moves_veins_with_the_blade(tmp_path):
    _kf_files(tmp_path)
    f = tmp_path / "kf.toml"
    f.write_text(KF)
    out = tmp_path / "out"
    r = CliRunner().invoke(main, [str(f), "-o", str(out), "--frame-step", "10"])
    assert r.exit_code == 0, r.output
    assert "key_frames (2 blade surfaces interpolated" in (out / "veins.widths").read_text()
    nodes = np.array([[float(w) for w in ln.split()[1:3]] for ln in (out / "veins.obj").read_text().splitlines()
                      if ln.startswith("v ")])
    blade = np.array([[float(w) for w in ln.split()[1:3]] for ln in (out / "frames" / "blade_0030.obj").read_text()
                      .splitlines() if ln.startswith("v ")])
    assert np.ptp(blade[:, 1]) == pytest.approx(2.0, rel=1e-6)  # the last key frame's height
    assert nodes[:, 1].max() > 1.2  # the veins went up with the blade (the first frame is 0.6 high)
    from matplotlib.path import Path as MPath

    inside = MPath(blade).contains_points(nodes, radius=0.05) | MPath(blade).contains_points(nodes, radius=-0.05)
    assert inside.mean() > 0.97
    # deterministic
    out2 = tmp_path / "out2"
    r = CliRunner().invoke(main, [str(f), "-o", str(out2), "-q"])
    assert r.exit_code == 0
    assert (out / "veins.obj").read_bytes() == (out2 / "veins.obj").read_bytes()


def _refused(tmp_path, text):
    f = tmp_path / "bad.toml"
    f.write_text(text)
    out = tmp_path / "out"
    out.mkdir(exist_ok=True)
    (out / "keep.txt").write_text("earlier")
    r = CliRunner().invoke(main, [str(f), "-o", str(out), "-q"])
    assert r.exit_code == 2, r.output
    err = r.output.strip()
    assert len(err.splitlines()) == 1 and "error:" in err, err
    assert sorted(p.name for p in out.iterdir()) == ["keep.txt"]
    return err


@pytest.mark.parametrize("old,new,expect", [
    ("times = [0, 30]", "times = [0]", "times"),
    ("times = [0, 30]", "times = [5, 30]", "increasing from 0"),
    ("times = [0, 30]", "times = [0, 30.5]", "whole iterations"),
    ("times = [0, 30]\n", "", "times"),
    ('key_frames = ["a.s", "b.s"]', 'key_frames = ["a.s"]', "at least two"),
    ('key_frames = ["a.s", "b.s"]', 'key_frames = ["a.s", "missing.s"]', "missing.s"),
    ("[blade]\n", "[blade]\npolygon = [[0, 0], [1, 0], [0, 1]]\n", "first key"),
    ('type = "key_frames"', 'type = "uniform"', "a blade"),
    ('[blade]\n[growth]\ntype = "key_frames"', '[blade]\npolygon = [[0, 0], [1, 0], [0, 1]]\n[growth]\ntype = "uniform"',
     "absent unless"),
    ('pattern = "closed"', 'pattern = "closed"\ninside = true', "inside"),
    ("times = [0, 30]", "times = [0, 30]\nsteps = 30", "steps"),
])
def test_key_frame_refusals(tmp_path, old, new, expect):
    _kf_files(tmp_path)
    assert old in KF
    assert expect in _refused(tmp_path, KF.replace(old, new))


def test_folded_and_crossing_key_frames_refused(tmp_path):
    folded = _leaf(2.0, 0.9, 1.8, 1.1, -1.0)  # row 2 below the base: the patch folds over itself
    _kf_files(tmp_path, b=folded)
    assert "fold" in _refused(tmp_path, KF)
    two = BezierSurface(patches=(BezierPatch(name="p", control_points=np.zeros((4, 4, 3)) + np.arange(4)[:, None, None]),
                                 BezierPatch(name="q", control_points=np.zeros((4, 4, 3)))))
    write_bezier_surface(tmp_path / "b.s", two)
    assert "one Bezier patch" in _refused(tmp_path, KF)


def _run_example(tmp_path, name):
    out = tmp_path / name
    r = CliRunner().invoke(main, [str(EXAMPLES / f"{name}.toml"), "-o", str(out), "-q"])
    assert r.exit_code == 0, r.output
    return read_events(out / "events.csv")


def test_arabidopsis_key_frames_follow_the_observed_order(tmp_path):
    """Sec. 5.3.2: the midvein, then the first pair of loops, a second pair, a third near the base,
    then higher-order veins and blind veinlets, in that order (Scarpella et al. as the thesis
    recounts them); the frames of the example are its own (pipelines/examples/venation)."""
    ev = _run_example(tmp_path, "arabidopsis_kf")
    assert departures(ev) == []
    kinds = [e.event for e in ev]
    mid = kinds.index("midvein")
    assert mid < kinds.index("loop")
    pairs, single = secondary_pairs(ev)
    assert len(pairs) == 3  # three pairs of secondary loops at the end
    ends = [max(a.iteration, b.iteration) for a, b in pairs]
    starts = [min(a.iteration, b.iteration) for a, b in pairs]
    assert starts[1] > ends[0] + 5 and starts[2] > ends[1] + 5  # one pair after another, not together
    ys = [0.5 * (a.y + b.y) for a, b in pairs]
    assert ys[2] < min(ys[:2])  # the third near the base
    higher = [e for e in ev if e.event == "blind_end" or (e.event == "loop" and (e.order or 1) > 1)]
    assert higher and min(e.iteration for e in higher) > ends[2]
    assert any(e.event == "blind_end" for e in ev)


def test_arabidopsis_local_to_global_departs_as_the_thesis_reports(tmp_path):
    """Sec. 5.3.1: with local-to-global growth "the upper half of the first pair of loops and the
    second pair of loops form simultaneously": the run's report says so."""
    ev = _run_example(tmp_path, "arabidopsis_ltg")
    dep = departures(ev)
    assert any("formed with pair 1" in d for d in dep), dep


def test_example_key_frames_are_the_generated_ones(tmp_path):
    """The committed .s files are what arabidopsis_frames.py writes."""
    import runpy

    mod = runpy.run_path(str(EXAMPLES / "arabidopsis_frames.py"))
    mod["main"]([str(tmp_path)])
    for f in sorted(tmp_path.glob("arabidopsis_*.s")):
        assert f.read_bytes() == (EXAMPLES / f.name).read_bytes(), f.name
    assert len(list(tmp_path.glob("arabidopsis_*.s"))) == 6
