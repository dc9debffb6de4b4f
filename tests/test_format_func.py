"""Graphically-defined functions (.func, .fset): reading, writing, and lpfg's evaluation.

The evaluator is checked against an independent reference built from scipy: a clamped
scipy.interpolate.BSpline, X(t) = x solved with scipy.optimize.brentq, then the same
linear interpolation between the samples x_i = i / (samples - 1).
"""
from __future__ import annotations

import numpy as np
import pytest
from conftest import no_partial_files
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.interpolate import BSpline
from scipy.optimize import brentq

from inflo.formats.errors import FormatError, InputError
from inflo.formats.func import (
    Function,
    clamped_bspline,
    format_func,
    read_fset,
    read_func,
    write_fset,
    write_func,
)

RHO = """fver 1 1
name: rho
samples: 100
flip: off
points: 4
0.000000 0.121930
0.348503 0.140375
0.695455 0.103748
1.000000 0.021930
"""


# ---------------------------------------------------------------------------------------------
# independent reference


def scipy_curve(ctrl: np.ndarray) -> BSpline:
    """Clamped uniform B-spline of degree min(3, m-1) on [0, 1], built with scipy."""
    m = len(ctrl)
    k = min(3, m - 1)
    spans = m - k
    knots = np.concatenate([np.zeros(k), np.arange(spans + 1), np.full(k, spans)]) / spans
    return BSpline(knots, ctrl, k)


def reference_table(fn: Function) -> tuple[np.ndarray, np.ndarray]:
    ctrl = np.repeat(fn.points, fn.multiplicities, axis=0)
    curve = scipy_curve(ctrl)
    s = min(max(fn.samples, 10), 1000)
    xs = np.arange(s) / (s - 1)
    ys = np.empty(s)
    for i, x in enumerate(xs):
        if i == 0:
            t = 0.0
        elif i == s - 1:
            t = 1.0
        else:
            t = brentq(lambda tt, x=x: curve(tt)[0] - x, 0.0, 1.0, xtol=1e-15, rtol=1e-15)
        ys[i] = curve(t)[1]
    return xs, ys


def random_function(rng, n: int, samples: int = 100) -> Function:
    """Strictly increasing x (so X(t) = x has one root) and random y and multiplicities."""
    x = np.concatenate([[0.0], np.sort(rng.uniform(0.02, 0.98, n - 2)), [1.0]])
    y = rng.uniform(-2.0, 3.0, n)
    mult = rng.integers(1, 4, n)
    return Function.from_points(np.column_stack([x, y]), mult, samples=samples)


# ---------------------------------------------------------------------------------------------
# the worked example of docs/vlab_formats.md


def test_rho_example_reads_and_evaluates(write):
    fn = read_func(write("rho.func", RHO))
    assert fn.name == "rho" and fn.samples == 100 and fn.flip is False
    assert fn.points.shape == (4, 2) and fn.points.dtype == np.float64
    np.testing.assert_array_equal(fn.points[:, 0], [0.0, 0.348503, 0.695455, 1.0])
    np.testing.assert_array_equal(fn.multiplicities, [1, 1, 1, 1])
    assert fn(0.0) == 0.121930 and fn(1.0) == 0.021930
    # four points: one cubic Bezier; at t = 1/2 the Bernstein weights are 1/8, 3/8, 3/8, 1/8
    x_half = (0.0 + 3 * 0.348503 + 3 * 0.695455 + 1.0) / 8  # 0.51648425
    y_half = (0.121930 + 3 * 0.140375 + 3 * 0.103748 + 0.021930) / 8  # 0.109528625
    assert fn(x_half) == pytest.approx(y_half, abs=5e-6)  # linear interpolation of 100 samples
    xs, ys = fn.sampled()
    rx, ry = reference_table(fn)
    np.testing.assert_array_equal(xs, rx)
    np.testing.assert_allclose(ys, ry, rtol=0, atol=1e-12)
    assert format_func(fn) == RHO  # the writer reproduces the editor's text


def test_exactly_four_points_is_one_cubic_bezier():
    p = np.array([[0.0, 0.3], [0.1, 1.7], [0.8, -0.9], [1.0, 0.4]])
    t = np.linspace(0.0, 1.0, 101)
    bern = np.stack([(1 - t) ** 3, 3 * t * (1 - t) ** 2, 3 * t**2 * (1 - t), t**3], axis=1)
    np.testing.assert_allclose(Function.from_points(p).curve(t), bern @ p, atol=1e-14)


# ---------------------------------------------------------------------------------------------
# evaluation against the independent scipy reference


@pytest.mark.parametrize("seed", range(6))
def test_matches_scipy_reference(seed):
    rng = np.random.default_rng(seed)
    fn = random_function(rng, n=int(rng.integers(4, 12)), samples=int(rng.choice([10, 57, 100, 400])))
    xs, ys = fn.sampled()
    rx, ry = reference_table(fn)
    np.testing.assert_array_equal(xs, rx)
    np.testing.assert_allclose(ys, ry, rtol=0, atol=1e-10)
    x = rng.uniform(-0.2, 1.2, 500)
    np.testing.assert_allclose(fn(x), np.interp(np.clip(x, 0, 1), rx, ry), rtol=0, atol=1e-10)
    # and the spline itself equals scipy's at any parameter
    t = rng.uniform(0, 1, 200)
    np.testing.assert_allclose(fn.curve(t), scipy_curve(fn.control_points())(t), atol=1e-12)


def test_clamped_bspline_matches_scipy_for_every_size():
    rng = np.random.default_rng(7)
    t = np.concatenate([[0.0, 1.0], rng.uniform(0, 1, 100)])
    for m in range(2, 12):
        c = rng.normal(size=(m, 3))
        np.testing.assert_allclose(clamped_bspline(c, t), scipy_curve(c)(t), atol=1e-12)
    assert clamped_bspline([[2.0, 5.0]], [0.3, 0.9]).tolist() == [[2.0, 5.0], [2.0, 5.0]]
    assert clamped_bspline(np.ones((5, 2)), np.zeros((2, 3))).shape == (2, 3, 2)


def test_end_point_trap():
    """t = 1 is the last control point exactly; f(1) and f(0) are the end points' y."""
    p = np.array([[0.0, 0.25], [0.2, 3.0], [0.5, -1.0], [0.7, 2.0], [1.0, 7.5]])
    fn = Function.from_points(p, [1, 2, 1, 1, 1])
    np.testing.assert_array_equal(fn.curve(1.0), [1.0, 7.5])
    np.testing.assert_array_equal(fn.curve(0.0), [0.0, 0.25])
    assert fn(1.0) == 7.5 and fn(0.0) == 0.25
    assert fn.sampled()[1][-1] == 7.5
    # a half-open basis (N_k,1 = 1 on [u_k, u_k+1)) gives the zero vector at u = end: not us
    assert fn.curve(np.array([1.0 - 1e-12, 1.0]))[1, 1] == 7.5


def test_clamps_x_outside_unit_interval():
    fn = random_function(np.random.default_rng(3), 6)
    assert fn(-0.5) == fn(0.0) and fn(-1e9) == fn(0.0)
    assert fn(1.5) == fn(1.0) and fn(7.0) == fn(1.0)
    np.testing.assert_array_equal(fn(np.array([-3.0, 4.0])), [fn(0.0), fn(1.0)])
    with pytest.raises(ValueError, match="finite"):
        fn(np.nan)


def test_scalar_and_array_results():
    fn = Function.constant(2.5)
    assert isinstance(fn(0.3), float) and fn(0.3) == pytest.approx(2.5)
    out = fn(np.zeros((3, 4)))
    assert isinstance(out, np.ndarray) and out.shape == (3, 4) and out.dtype == np.float64
    np.testing.assert_allclose(fn(np.linspace(0, 1, 33)), 2.5, rtol=0, atol=1e-12)
    assert fn([0.1, 0.2]).shape == (2,)


def test_multiplicity_repeats_points_and_curve_passes_through_triple_point():
    pts = np.array([[0.0, 0.0], [0.5, 1.0], [1.0, 0.0]])
    fn = Function.from_points(pts, [1, 3, 1], samples=101)
    repeated = Function.from_points(np.array([[0, 0], [0.5, 1], [0.5, 1], [0.5, 1], [1, 0]], float), samples=101)
    np.testing.assert_array_equal(fn.control_points(), repeated.control_points())
    np.testing.assert_array_equal(fn.sampled()[1], repeated.sampled()[1])
    assert fn.sampled()[0][50] == 0.5
    assert fn(0.5) == pytest.approx(1.0, abs=1e-12)  # a cubic passes through a triple point
    assert Function.from_points(pts, [1, 1, 1], samples=101)(0.5) < 0.9  # a single one it does not


def test_linear_interpolation_between_coarse_samples():
    fn = Function.from_points([[0.0, 0.0], [0.3, 1.0], [0.6, -1.0], [1.0, 0.5]], samples=10)
    xs, ys = fn.sampled()
    assert len(xs) == 10
    mids = 0.5 * (xs[:-1] + xs[1:])
    np.testing.assert_allclose(fn(mids), 0.5 * (ys[:-1] + ys[1:]), rtol=0, atol=1e-14)
    quarter = xs[:-1] + 0.25 * np.diff(xs)
    np.testing.assert_allclose(fn(quarter), 0.75 * ys[:-1] + 0.25 * ys[1:], rtol=0, atol=1e-14)
    # the true curve is not piecewise linear: a finer table gives different values between samples
    fine = Function.from_points(fn.points, samples=1000)
    assert np.max(np.abs(fine(mids) - fn(mids))) > 1e-3
    np.testing.assert_allclose(fine(xs), ys, atol=1e-12)  # but the same values at the samples


@pytest.mark.parametrize("stored, used", [(0, 10), (3, 10), (10, 10), (11, 11), (1000, 1000), (5000, 1000)])
def test_samples_clamped_to_10_1000(stored, used):
    fn = Function.from_points([[0.0, 0.0], [1.0, 1.0]], samples=stored)
    assert fn.samples == stored and fn.effective_samples == used and len(fn.sampled()[0]) == used


def test_fewer_than_four_points():
    line = Function.from_points([[0.0, 1.0], [1.0, 3.0]])  # degree 1: a straight segment
    x = np.linspace(0, 1, 37)
    np.testing.assert_allclose(line(x), 1.0 + 2.0 * x, rtol=0, atol=1e-12)
    quad = Function.from_points([[0.0, 0.0], [0.2, 1.0], [1.0, 0.0]])  # degree 2: quadratic Bezier
    rx, ry = reference_table(quad)
    np.testing.assert_allclose(quad.sampled()[1], ry, atol=1e-12)
    t = np.linspace(0, 1, 11)
    bern = np.stack([(1 - t) ** 2, 2 * t * (1 - t), t**2], axis=1)
    np.testing.assert_allclose(quad.curve(t), bern @ quad.points, atol=1e-14)


def test_vertical_step_function():
    """Repeated x (a jump, as funcedit draws steps) keeps X(t) monotone; f jumps near the step."""
    fn = Function.from_points([[0.0, 0.0], [0.5, 0.0], [0.5, 0.0], [0.5, 1.0], [0.5, 1.0], [1.0, 1.0]], samples=1000)
    assert fn(0.2) == pytest.approx(0.0, abs=1e-3) and fn(0.8) == pytest.approx(1.0, abs=1e-3)
    assert np.all(np.diff(fn(np.linspace(0, 1, 200))) >= -1e-12)


def test_bad_control_arrays_and_foreign_equality():
    with pytest.raises(ValueError, match=r"\(m, d\)"):
        clamped_bspline(np.zeros(4), 0.5)
    assert Function.constant(1.0) != "constant" and Function.constant(1.0) == Function.constant(1.0)


def test_sample_table_is_cached_and_immutable():
    fn = random_function(np.random.default_rng(1), 5)
    assert fn.sampled() is fn.sampled()
    with pytest.raises(ValueError):
        fn.points[0, 1] = 5.0
    with pytest.raises(ValueError):
        fn.sampled()[1][0] = 1.0
    with pytest.raises(AttributeError):
        fn.samples = 5


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(points=[[0.1, 0.0], [1.0, 1.0]]), "x must run from 0 to 1"),
        (dict(points=[[0.0, 0.0], [0.9, 1.0]]), "x must run from 0 to 1"),
        (dict(points=[[0.0, 0.0], [0.6, 0.0], [0.5, 0.0], [1.0, 1.0]]), "must not decrease"),
        (dict(points=[[0.0, 0.0]]), r"n >= 2"),
        (dict(points=[[0.0, np.inf], [1.0, 0.0]]), "finite"),
        (dict(points=[[0.0, 0.0], [1.0, 1.0]], multiplicities=[1, 0]), ">= 1"),
        (dict(points=[[0.0, 0.0], [1.0, 1.0]], multiplicities=[1.5, 1]), "integers"),
        (dict(points=[[0.0, 0.0], [1.0, 1.0]], multiplicities=[1, 1, 1]), "shape"),
        (dict(points=[[0.0, 0.0], [1.0, 1.0]], samples=-1), "samples"),
        (dict(points=[[0.0, 0.0], [1.0, 1.0]], name=""), "name"),
        (dict(points=[[0.0, 0.0], [1.0, 1.0]], name="a\nb"), "name"),
        (dict(points=[[0.0, 0.0], [1.0, 1.0]], background_xy=(1.0, np.nan)), "background_xy"),
        (dict(points=[[0.0, 0.0], [1.0, 1.0]], markers=("m1 0 0", "")), "markers"),
    ],
)
def test_constructor_rejects(kwargs, match):
    kwargs.setdefault("name", "f")
    with pytest.raises(ValueError, match=match):
        Function(**kwargs)


# ---------------------------------------------------------------------------------------------
# reading and writing


SIX = st.integers(-10**7, 10**7).map(lambda k: k / 1e6)
NAME = st.text(st.characters(min_codepoint=33, max_codepoint=126), min_size=1, max_size=12)


@st.composite
def functions(draw):
    n = draw(st.integers(2, 12))
    inner = sorted(draw(st.lists(st.integers(0, 10**6), min_size=n - 2, max_size=n - 2)))
    x = [0.0] + [k / 1e6 for k in inner] + [1.0]
    y = draw(st.lists(SIX, min_size=n, max_size=n))
    mult = draw(st.lists(st.integers(1, 3), min_size=n, max_size=n))
    background = draw(st.one_of(st.none(), NAME))
    bxy = draw(st.one_of(st.none(), st.tuples(SIX, SIX)))
    markers = tuple(f"m{i} {draw(SIX):.6f} {draw(SIX):.6f}" for i in range(draw(st.integers(0, 2))))
    return Function(draw(NAME), np.column_stack([x, y]), mult, samples=draw(st.integers(0, 2000)),
                    flip=draw(st.booleans()), background=background, background_xy=bxy, markers=markers)


@settings(max_examples=60, deadline=None)
@given(fn=functions())
def test_round_trip(tmp_path_factory, fn):
    path = tmp_path_factory.mktemp("func") / "f.func"
    write_func(path, fn)
    back = read_func(path)
    assert back == fn
    text = path.read_text()
    write_func(path, back)
    assert path.read_text() == text


@settings(max_examples=20, deadline=None)
@given(fns=st.lists(functions(), max_size=4))
def test_fset_round_trip(tmp_path_factory, fns):
    path = tmp_path_factory.mktemp("fset") / "functions.fset"
    write_fset(path, fns)
    assert read_fset(path) == fns
    assert no_partial_files(path.parent)


def test_fset_example_and_multiplicity_column(write):
    p = write("functions.fset", """funcgalleryver 1 1
items: 2
fver 1 1
name: _fruit_mass
samples: 100
flip: off
points: 4
0.000000 0.000000
0.586364 0.000000
0.586364 0.250000
1.000000 0.250000
fver 1 1
name: leaf_area
samples: 20
background: sketch.png
backgroundXY: 0.100000 -0.200000
flip: on
points: 3
0.000000 0.000000
0.500000 0.500000 3
1.000000 1.000000
""")
    a, b = read_fset(p)
    assert a.name == "_fruit_mass" and a(0.0) == 0.0 and a(1.0) == 0.25
    assert b.name == "leaf_area" and b.flip is True and b.background == "sketch.png"
    assert b.background_xy == (0.1, -0.2)
    np.testing.assert_array_equal(b.multiplicities, [1, 3, 1])
    assert b(0.5) == pytest.approx(0.5)


def test_version_1_0_range_file(write):
    fn = read_func(write("growth.func", "range: 0.0 1.0\npoints: 4\n0 0\n0.3 0.1\n0.7 0.9\n1 1\n"))
    assert fn.name == "growth" and fn.samples == 100 and not fn.flip
    assert fn(0.0) == 0.0 and fn(1.0) == 1.0
    assert format_func(fn).startswith("fver 1 1\nname: growth\nsamples: 100\nflip: off\npoints: 4\n")


def test_flip_spellings_markers_and_blank_lines(write):
    body = "points: 2\n0 0\n1 1\n"
    assert read_func(write("a.func", f"fver 1 1\nname: a\nsamples: 5\nflip: yes\n{body}")).flip is True
    assert read_func(write("b.func", f"fver 1 1\nname: b\nsamples: 5\nflip: NO\n{body}")).flip is False
    fn = read_func(write("c.func", f"\nfver 1 1\n\nname: c d\nsamples: 5\nmarkers: 1\nm1 0.5 0.5\nflip: off\n{body}\n\n"))
    assert fn.name == "c d" and fn.markers == ("m1 0.5 0.5",)


def test_writer_text_is_fixed_format(tmp_path):
    fn = Function.from_points([[0.0, -0.0], [1 / 3, 1e-9], [1.0, -1e-9]], [1, 2, 1], name="g", samples=50)
    write_func(tmp_path / "g.func", fn)
    assert (tmp_path / "g.func").read_text() == (
        "fver 1 1\nname: g\nsamples: 50\nflip: off\npoints: 3\n"
        "0.000000 0.000000\n0.333333 0.000000 2\n1.000000 0.000000\n"
    )


def test_failed_write_leaves_no_file(tmp_path):
    with pytest.raises(AttributeError):
        write_func(tmp_path / "x.func", object())
    write_fset(tmp_path / "x.fset", [Function.constant(1.0)])
    before = (tmp_path / "x.fset").read_text()
    with pytest.raises(AttributeError):
        write_fset(tmp_path / "x.fset", [Function.constant(2.0), 3])
    assert not (tmp_path / "x.func").exists()
    assert (tmp_path / "x.fset").read_text() == before  # the old file is untouched
    assert no_partial_files(tmp_path)


HEAD = "fver 1 1\nname: f\nsamples: 10\nflip: off\n"


@pytest.mark.parametrize(
    "text, line, expected, found",
    [
        ("", None, "'fver 1 1'", "end of file"),
        ("fver 1 2\n", 1, "'fver 1 1'", "'fver 1 2'"),
        ("hello\n", 1, "'fver 1 1' (or a version 1.0 'range: 0 1' line)", "'hello'"),
        ("fver 1 1\nnom: f\n", 2, "'name: NAME'", "'nom: f'"),
        ("fver 1 1\nname:\n", 2, "a function name after 'name:'", "nothing"),
        ("fver 1 1\nname: f\nflip: off\n", 3, "'samples: N'", "'flip: off'"),
        ("fver 1 1\nname: f\nsamples: many\n", 3, "an integer after 'samples:'", "'many'"),
        ("fver 1 1\nname: f\nsamples: -4\n", 3, "a sample count >= 0", "'-4'"),
        ("fver 1 1\nname: f\nsamples: 10\nflip: maybe\n", 4, "'on' or 'off' after 'flip:'", "'maybe'"),
        ("fver 1 1\nname: f\nsamples: 10\npoints: 2\n", 4, "'flip: on' or 'flip: off'", "'points: 2'"),
        ("fver 1 1\nname: f\nsamples: 10\nbackground:\n", 4, "an image file name after 'background:'", "nothing"),
        ("fver 1 1\nname: f\nsamples: 10\nbackgroundXY: 1\n", 4, "2 numbers after 'backgroundXY:'", "1"),
        ("fver 1 1\nname: f\nsamples: 10\nbackgroundXY: 1 nan\n", 4, "a number after 'backgroundXY:' (finite)", "'nan'"),
        ("fver 1 1\nname: f\nsamples: 10\nmarkers: x\n", 4, "an integer after 'markers:'", "'x'"),
        ("fver 1 1\nname: f\nsamples: 10\nmarkers: -1\n", 4, "a marker count >= 0", "'-1'"),
        ("fver 1 1\nname: f\nsamples: 10\nmarkers: 2\nm1 0 0\n", None, "marker line 2 of 2", "end of file"),
        (HEAD + "point: 2\n", 5, "'points: N'", "'point: 2'"),
        (HEAD + "points: two\n", 5, "an integer after 'points:'", "'two'"),
        (HEAD + "points: 1\n0 0\n", 5, "at least 2 points", "'1'"),
        (HEAD + "points: 3\n0 0\n1 1\n", None, "point 3 of 3", "end of file"),
        (HEAD + "points: 2\n0 0\n1 1\n1 1\n", 8, "end of file after the 2 points", "'1 1'"),
        (HEAD + "points: 2\n0\n1 1\n", 6, "point 1 of 2 ('x y' or 'x y multiplicity')", "'0'"),
        (HEAD + "points: 2\n0 0 1 1\n1 1\n", 6, "point 1 of 2", "'0 0 1 1'"),
        (HEAD + "points: 2\n0 zero\n1 1\n", 6, "a number (y)", "'zero'"),
        (HEAD + "points: 2\nx 0\n1 1\n", 6, "a number (x)", "'x'"),
        (HEAD + "points: 2\n0 inf\n1 1\n", 6, "a number (y) (finite)", "'inf'"),
        (HEAD + "points: 2\n0 0 1.5\n1 1\n", 6, "an integer multiplicity", "'1.5'"),
        (HEAD + "points: 2\n0 0 0\n1 1\n", 6, "a multiplicity >= 1", "'0'"),
        (HEAD + "points: 2\n0.1 0\n1 1\n", 6, "x = 0 on the first point", "'0.1'"),
        (HEAD + "points: 3\n0 0\n0.5 1\n0.4 1\n", 8, "x >= 0.5 (x must not decrease)", "'0.4'"),
        (HEAD + "points: 3\n0 0\n0.5 1\n0.999 1\n", 8, "x = 1 on the last point", "'0.999'"),
        ("range: 0 1 2\n", 1, "2 numbers after 'range:'", "3"),
        ("range: 0 one\n", 1, "a number after 'range:'", "'one'"),
        ("range: 0 2\n", 1, "'range: 0 1'", "'range: 0 2'"),
        ("range: 0 1\npoints: 2\n0 0\n2 1\n", 4, "x = 1 on the last point", "'2'"),
    ],
)
def test_malformed_func(write, text, line, expected, found):
    p = write("bad.func", text)
    with pytest.raises(FormatError) as err:
        read_func(p)
    e = err.value
    assert e.line == line and expected in e.expected and found in e.found, str(e)
    where = f"{p}:{line}" if line is not None else f"{p}"
    assert str(e).startswith(f"{where}: expected ")


@pytest.mark.parametrize(
    "text, line, expected, found",
    [
        ("funcgalleryver 1 2\n", 1, "'funcgalleryver 1 1'", "'funcgalleryver 1 2'"),
        ("funcgalleryver 1 1\nitem: 1\n", 2, "'items: N'", "'item: 1'"),
        ("funcgalleryver 1 1\nitems: x\n", 2, "an integer after 'items:'", "'x'"),
        ("funcgalleryver 1 1\nitems: -2\n", 2, "an item count >= 0", "'-2'"),
        ("funcgalleryver 1 1\nitems: 1\n", None, "'fver 1 1'", "end of file"),
        ("funcgalleryver 1 1\nitems: 1\nrange: 0 1\n", 3, "'fver 1 1'", "'range: 0 1'"),
        ("funcgalleryver 1 1\nitems: 1\n" + HEAD + "points: 2\n0 0\n1 1\n" + HEAD, 10, "end of file after 1 items", "'fver 1 1'"),
        ("funcgalleryver 1 1\nitems: 2\n" + HEAD + "points: 2\n0 0\n1 1\n" + HEAD + "points: 2\n0 0\n1 2 0\n", 16,
         "a multiplicity >= 1", "'0'"),
    ],
)
def test_malformed_fset(write, text, line, expected, found):
    p = write("bad.fset", text)
    with pytest.raises(FormatError) as err:
        read_fset(p)
    e = err.value
    assert e.line == line and expected in e.expected and found in e.found, str(e)


def test_missing_and_binary_files(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_func(tmp_path / "none.func")
    p = tmp_path / "bin.func"
    p.write_bytes(b"fver 1 1\n\xff\x00")
    with pytest.raises(FormatError, match=r"bin.func:2: expected UTF-8 text"):
        read_func(p)
