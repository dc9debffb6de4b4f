"""Contours (.con, .cset): reading every version, writing cver 1 3, and lpfg's evaluation.

References are independent: scipy.interpolate.BSpline with uniform (regular types) or clamped
(end-point types) knots, and scipy.integrate.quad of the speed for arc lengths.
"""
from __future__ import annotations

import numpy as np
import pytest
from conftest import no_partial_files
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad
from scipy.interpolate import BSpline

from inflo.formats.contour import Contour, format_con, read_con, read_cset, uniform_bspline, write_con, write_cset
from inflo.formats.errors import FormatError, InputError

CALYX = """cver 1 3
name: calyx.con
points: 5 9
type: or
samples: 8
-2.227160 3.164609 0.000000 3
-1.358025 4.106174 0.000000 1
0.120043 4.521461 0.000000 1
1.358025 4.214815 0.000000 1
2.236717 3.117330 0.000000 3
"""

# a smooth, convex closed outline (a squashed octagon)
OCTAGON = np.array([[np.cos(a) * 2.0, np.sin(a), 0.0] for a in np.linspace(0, 2 * np.pi, 8, endpoint=False)])


def scipy_uniform(ctrl: np.ndarray) -> BSpline:
    """Uniform cubic B-spline on knots 0..m+3, valid on [3, m]; reparametrized below to [0, 1]."""
    m = len(ctrl)
    return BSpline(np.arange(m + 4, dtype=float), ctrl, 3)


def scipy_clamped(ctrl: np.ndarray) -> BSpline:
    m = len(ctrl)
    spans = m - 3
    knots = np.concatenate([np.zeros(3), np.arange(spans + 1), np.full(3, spans)]) / spans
    return BSpline(knots, ctrl, 3)


def reference_curve(c: Contour):
    """t in [0, 1] -> points, from the cuspy description (not from Contour.control_points)."""
    pts = np.repeat(c.points, c.multiplicities, axis=0)
    if c.end_point:
        ctrl = np.vstack([pts, pts[:1]]) if c.closed else pts
        return scipy_clamped(ctrl)
    ctrl = np.vstack([pts[-3:], pts]) if c.closed else pts
    spl = scipy_uniform(ctrl)
    m = len(ctrl)
    return lambda t: spl(3.0 + np.asarray(t) * (m - 3))


def test_calyx_example(write):
    c = read_con(write("calyx.con", CALYX))
    assert c.name == "calyx.con" and c.type == "or" and c.samples == 8
    assert not c.closed and not c.end_point
    assert c.points.shape == (5, 3) and c.points.dtype == np.float64
    np.testing.assert_array_equal(c.multiplicities, [3, 1, 1, 1, 3])
    assert format_con(c) == CALYX
    # open regular with triple end points: passes through both ends
    np.testing.assert_allclose(c.evaluate(0.0), c.points[0], atol=1e-12)
    np.testing.assert_allclose(c.evaluate(1.0), c.points[-1], atol=1e-12)
    np.testing.assert_allclose(c.point_at([0.0, 1.0]), c.points[[0, -1]], atol=1e-12)


@pytest.mark.parametrize("type_", ["or", "cr", "oe", "ce"])
@pytest.mark.parametrize("seed", range(3))
def test_evaluation_matches_scipy(type_, seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(4, 9))
    c = Contour.from_points(rng.normal(size=(n, 3)), rng.integers(1, 4, n), type=type_)
    t = np.concatenate([[0.0, 1.0], rng.uniform(0, 1, 300)])
    np.testing.assert_allclose(c.evaluate(t), reference_curve(c)(t), atol=1e-12)


def test_open_end_point_type_interpolates_ends_and_regular_does_not():
    pts = np.array([[0, 0, 0], [1, 2, 0], [3, 2, 0], [4, 0, 0], [5, 1, 0]], float)
    oe = Contour.from_points(pts, type="oe")
    np.testing.assert_array_equal(oe.evaluate([0.0, 1.0]), pts[[0, -1]])  # exactly (end-point trap)
    orr = Contour.from_points(pts, type="or")
    np.testing.assert_allclose(orr.evaluate(0.0), (pts[0] + 4 * pts[1] + pts[2]) / 6, atol=1e-14)
    assert np.linalg.norm(orr.evaluate(0.0) - pts[0]) > 0.5
    # with the ends tripled (what cuspy users do) the regular curve reaches them too
    tripled = Contour.from_points(pts, [3, 1, 1, 1, 3], type="or")
    np.testing.assert_allclose(tripled.evaluate([0.0, 1.0]), pts[[0, -1]], atol=1e-14)


def test_interior_triple_point_is_on_the_curve():
    pts = np.array([[0, 0, 0], [1, 1, 0], [2, 3, 0], [3, 1, 0], [4, 0, 0]], float)
    for type_ in ("or", "oe", "cr"):
        c = Contour.from_points(pts, [1, 1, 3, 1, 1], type=type_)
        d = np.linalg.norm(c.evaluate(np.linspace(0, 1, 20001)) - pts[2], axis=1)
        assert d.min() < 1e-6, type_


def test_closed_regular_is_closed_and_c2():
    c = Contour.from_points(OCTAGON, type="cr")
    np.testing.assert_array_equal(c.evaluate(1.0), c.evaluate(0.0))
    # the reference spline's derivatives at the two sides of the seam (its parameters 3 and m)
    m = len(c.control_points())
    uni = scipy_uniform(np.vstack([OCTAGON[-3:], OCTAGON]))
    for order in (1, 2):
        np.testing.assert_allclose(uni.derivative(order)(3.0), uni.derivative(order)(float(m)), atol=1e-12)
    # and numerically on Contour.evaluate itself: one-sided differences agree across the seam
    h = 1e-4
    p0, p1, p2 = c.evaluate([0.0, h, 2 * h])
    q0, q1, q2 = c.evaluate([1.0, 1.0 - h, 1.0 - 2 * h])
    np.testing.assert_allclose((p1 - p0) / h, (q0 - q1) / h, rtol=0, atol=5e-2 * np.linalg.norm((p1 - p0) / h))
    d2p, d2q = (p2 - 2 * p1 + p0) / h**2, (q2 - 2 * q1 + q0) / h**2
    np.testing.assert_allclose(d2p, d2q, rtol=0, atol=5e-2 * np.linalg.norm(d2p))


def test_closed_end_point_returns_to_its_first_point():
    c = Contour.from_points(OCTAGON, type="ce")
    np.testing.assert_array_equal(c.evaluate([0.0, 1.0]), OCTAGON[[0, 0]])
    assert len(c.control_points()) == len(OCTAGON) + 1


@pytest.mark.parametrize("type_", ["or", "cr", "oe", "ce"])
def test_arc_length_parametrization(type_):
    c = Contour.from_points(OCTAGON * [1.0, 1.0, 0.0] + [0, 0, 0], type=type_)
    spl = reference_curve(c)
    h = 1e-6

    def speed(t):
        lo, hi = max(t - h, 0.0), min(t + h, 1.0)
        return np.linalg.norm(spl(hi) - spl(lo)) / (hi - lo)

    m = len(c.control_points()) - (0 if c.end_point else 3)
    breaks = np.linspace(0, 1, m + 1)
    length = sum(quad(speed, a, b, epsabs=1e-11, limit=200)[0] for a, b in zip(breaks[:-1], breaks[1:]))
    assert c.length == pytest.approx(length, rel=1e-5)
    n = 400
    pts = c.sample(n)
    closed_pts = np.vstack([pts, pts[:1]]) if c.closed else pts
    chords = np.linalg.norm(np.diff(closed_pts, axis=0), axis=1)
    assert chords.std() / chords.mean() < 1e-3  # equal spacing (chords of a smooth curve ~ arcs)
    assert chords.sum() == pytest.approx(length, rel=1e-4)
    assert pts.shape == (n, 3)


def test_point_at_is_on_the_curve_and_monotone(write):
    c = read_con(write("calyx.con", CALYX))
    s = np.linspace(0, 1, 30)
    p = c.point_at(s)
    t = np.linspace(0, 1, 50001)
    dense = c.evaluate(t)
    nearest = np.array([np.argmin(np.linalg.norm(dense - q, axis=1)) for q in p])
    assert np.all(np.diff(nearest) > 0)  # moves forward along the curve
    assert np.max(np.linalg.norm(dense[nearest] - p, axis=1)) < 1e-4
    np.testing.assert_allclose(c.point_at(-1.0), c.point_at(0.0))
    np.testing.assert_allclose(c.point_at(2.0), c.point_at(1.0))
    assert c.point_at(np.zeros((2, 5))).shape == (2, 5, 3)
    assert c.point_at(0.5).shape == (3,)


def test_sample_endpoints_and_counts():
    c = Contour.from_points(OCTAGON, type="oe")
    s = c.sample(5)
    np.testing.assert_array_equal(s[[0, -1]], OCTAGON[[0, -1]])
    closed = Contour.from_points(OCTAGON, type="cr")
    assert closed.sample(8).shape == (8, 3)
    assert not np.allclose(closed.sample(8)[0], closed.sample(8)[-1])  # start not repeated
    with pytest.raises(ValueError):
        closed.sample(2)
    with pytest.raises(ValueError):
        c.sample(1)


def test_degenerate_zero_length_contour():
    c = Contour.from_points(np.zeros((4, 3)), type="oe")
    assert c.length == 0.0
    np.testing.assert_array_equal(c.point_at([0.0, 0.5, 1.0]), np.zeros((3, 3)))


def test_two_dimensional_points_get_z_zero_and_immutable():
    c = Contour.from_points([[0, 0], [1, 0], [1, 1], [0, 1]], type="cr")
    assert c.points.shape == (4, 3) and np.all(c.points[:, 2] == 0)
    with pytest.raises(ValueError):
        c.points[0, 0] = 1.0
    assert c._arc_table() is c._arc_table()


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(points=np.zeros((3, 3))), "at least 4 control points"),
        (dict(points=np.zeros((2, 3)), multiplicities=[2, 1]), "at least 4 control points"),
        (dict(points=np.zeros((4, 4))), "shape"),
        (dict(points=[[0, 0, np.nan]] * 4), "finite"),
        (dict(points=np.zeros((4, 3)), multiplicities=[1, 1, 1, 0]), ">= 1"),
        (dict(points=np.zeros((4, 3)), multiplicities=[1, 1, 1]), "shape"),
        (dict(points=np.zeros((4, 3)), multiplicities=[1, 1, 1, 1.5]), "integers"),
        (dict(points=np.zeros((4, 3)), samples=-1), "samples"),
        (dict(points=np.zeros((4, 3)), name=" "), "name"),
        (dict(points=np.zeros((4, 3)), background_xy=(0.0,)), "background_xy"),
    ],
)
def test_constructor_rejects(kwargs, match):
    kwargs.setdefault("name", "c")
    with pytest.raises(ValueError, match=match):
        Contour(**kwargs)
    with pytest.raises(ValueError, match="type"):
        Contour.from_points(np.zeros((4, 3)), type="xx")


def test_uniform_bspline_needs_four_points():
    with pytest.raises(ValueError):
        uniform_bspline(np.zeros((3, 2)), 0.5)
    c = Contour.from_points(OCTAGON)
    assert c != 5 and c == Contour.from_points(OCTAGON) and c != Contour.from_points(OCTAGON, type="cr")


# ---------------------------------------------------------------------------------------------
# older versions


def test_cver_1_1_and_1_2(write):
    c11 = read_con(write("a.con", "cver 1 1\nname: noname\npoints: 4 4\ntype: closed\n"
                         "0.4 0.4 0.0 1\n0.4 -0.4 0.0 1\n-0.4 -0.4 0.0 1\n-0.4 0.4 0.0 1\n"))
    assert c11.type == "cr" and c11.samples == 8 and c11.name == "noname"
    c12 = read_con(write("b.con", "cver 1 2\nname: b\npoints: 3 5\ntype: oe\n0 0 0 2\n1 1 0 1\n2 0 0 2\n"))
    assert c12.type == "oe" and c12.multiplicities.tolist() == [2, 1, 2]
    assert format_con(c12).startswith("cver 1 3\nname: b\npoints: 3 5\ntype: oe\nsamples: 8\n")


def test_cver_1_3_background_and_markers(write):
    text = ("cver 1 3\nname: rim\npoints: 4 4\ntype: ce\nsamples: 12\nbackground: photo.png\n"
            "backgroundXY: 0.500000 -1.000000\nmarkers: 1\n0 0.5 1.0 2.0\n"
            "0.000000 0.000000 0.000000 1\n1.000000 0.000000 0.000000 1\n"
            "1.000000 1.000000 0.000000 1\n0.000000 1.000000 0.000000 1\n")
    c = read_con(write("rim.con", text))
    assert c.background == "photo.png" and c.background_xy == (0.5, -1.0) and c.markers == ("0 0.5 1.0 2.0",)
    assert c.samples == 12 and c.type == "ce"
    assert format_con(c) == text


def test_version_1_4(write):
    c = read_con(write("old14.con", "version: 1.4\ncontact: 0 0 0\nend: 0 0 0\nheading: 0 1 0\nup: 0 0 -1\n"
                       "size 1\npoints: 4\nrange: 0.0 1.0\ndimension: 4\ntype: bspline\n"
                       "0 0 0 2\n1 1 0 1\n2 1 0 1\n3 0 0 2\n"))
    assert c.name == "old14" and c.type == "or" and c.multiplicities.tolist() == [2, 1, 1, 2]
    c3 = read_con(write("old14b.con", "version: 1.4\ncontact: 0 0 0\nend: 0 0 0\nheading: 0 1 0\nup: 0 0 -1\n"
                        "size: 2\npoints: 4\nrange: 0 1\ndimension: 3\ntype: bspline\n0 0 0\n1 1 0\n2 1 0\n3 0 0\n"))
    assert c3.multiplicities.tolist() == [1, 1, 1, 1]


def test_version_1_0(write):
    c = read_con(write("v10.con", "7 2 closed\n0 0\n0 0\n1 0\n1 1\n1 1\n1 1\n0 1\n"))
    assert c.name == "v10" and c.type == "cr"
    assert c.points.tolist() == [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    assert c.multiplicities.tolist() == [2, 1, 3, 1]
    c3 = read_con(write("v10b.con", "4 3 open\n0 0 1\n1 0 1\n2 0 1\n3 1 1\n"))
    assert c3.type == "or" and np.all(c3.points[:, 2] == 1.0)


def test_cset_example_with_indented_header(write):
    c = read_cset(write("contours.cset", "contourgalleryver 1 1\nitems: 2\n cver 1 1\nname: noname\npoints: 4 4\n"
                        "type: closed\n0.4 0.4 0.0 1\n0.4 -0.4 0.0 1\n-0.4 -0.4 0.0 1\n-0.4 0.4 0.0 1\n" + CALYX))
    assert [x.name for x in c] == ["noname", "calyx.con"] and c[0].closed and not c[1].closed


# ---------------------------------------------------------------------------------------------
# round trips

SIX = st.integers(-10**7, 10**7).map(lambda k: k / 1e6)
NAME = st.text(st.characters(min_codepoint=33, max_codepoint=126), min_size=1, max_size=12)


@st.composite
def contours(draw):
    n = draw(st.integers(1, 10))
    pts = [[draw(SIX) for _ in range(3)] for _ in range(n)]
    mult = draw(st.lists(st.integers(1, 3), min_size=n, max_size=n))
    if sum(mult) < 4:
        mult[0] += 4 - sum(mult)
    return Contour(draw(NAME), pts, mult, closed=draw(st.booleans()), end_point=draw(st.booleans()),
                   samples=draw(st.integers(0, 64)), background=draw(st.one_of(st.none(), NAME)),
                   background_xy=draw(st.one_of(st.none(), st.tuples(SIX, SIX))),
                   markers=tuple(f"{i} 0.5 {draw(SIX):.6f} 0.0" for i in range(draw(st.integers(0, 2)))))


@settings(max_examples=60, deadline=None)
@given(c=contours())
def test_round_trip(tmp_path_factory, c):
    path = tmp_path_factory.mktemp("con") / "c.con"
    write_con(path, c)
    back = read_con(path)
    assert back == c
    text = path.read_text()
    write_con(path, back)
    assert path.read_text() == text


@settings(max_examples=20, deadline=None)
@given(cs=st.lists(contours(), max_size=4))
def test_cset_round_trip(tmp_path_factory, cs):
    path = tmp_path_factory.mktemp("cset") / "contours.cset"
    write_cset(path, cs)
    assert read_cset(path) == cs
    assert no_partial_files(path.parent)


# ---------------------------------------------------------------------------------------------
# malformed input

H13 = "cver 1 3\nname: c\n"
ROWS4 = "0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n"
V14 = "version: 1.4\ncontact: 0 0 0\nend: 0 0 0\nheading: 0 1 0\nup: 0 0 -1\n"


@pytest.mark.parametrize(
    "text, line, expected, found",
    [
        ("", None, "'cver 1 N'", "end of file"),
        ("cver 1 4\n", 1, "'cver 1 1', 'cver 1 2' or 'cver 1 3'", "'cver 1 4'"),
        ("cver 2 1\n", 1, "'cver 1 1', 'cver 1 2' or 'cver 1 3'", "'cver 2 1'"),
        ("contour\n", 1, "'cver 1 N' (or an old 'version: 1.4'", "'contour'"),
        ("cver 1 3\nname:\n", 2, "a contour name after 'name:'", "nothing"),
        ("cver 1 3\ntitle: c\n", 2, "'name: NAME'", "'title: c'"),
        (H13 + "pts: 4 4\n", 3, "'points: N1 N2'", "'pts: 4 4'"),
        (H13 + "points: 4 4\ntype: or\nsamples: 8\nmarkers: 1\n", None, "marker line 1 of 1", "end of file"),
        (H13 + "points: 4 4\ntype: or\nsamples: 8\nmarkers: many\n", 6, "an integer after 'markers:'", "'many'"),
        (H13 + "points: 4\n", 3, "2 integers after 'points:'", "'4'"),
        (H13 + "points: four 4\n", 3, "an integer point count", "'four'"),
        (H13 + "points: 4 x\n", 3, "an integer total count", "'x'"),
        (H13 + "points: 0 4\n", 3, "at least 1 point", "'0'"),
        (H13 + "points: 3 3\n", 3, "at least 4 control points, multiplicities counted", "'3'"),
        (H13 + "points: 4 4\nkind: or\n", 4, "'type: ...'", "'kind: or'"),
        (H13 + "points: 4 4\ntype: ox\n", 4, "type 'or', 'cr', 'oe' or 'ce'", "'ox'"),
        (H13 + "points: 4 4\ntype: or\n" + ROWS4, 5, "'samples: N'", "'0 0 0 1'"),
        (H13 + "points: 4 4\ntype: or\nsamples: x\n", 5, "an integer after 'samples:'", "'x'"),
        (H13 + "points: 4 4\ntype: or\nsamples: -8\n", 5, "a sample count >= 0", "'-8'"),
        (H13 + "points: 4 4\ntype: or\nsamples: 8\nbackgroundXY: a b\n", 6, "a number after 'backgroundXY:'", "'a'"),
        (H13 + "points: 4 4\ntype: or\nsamples: 8\n0 0 0 1\n", None, "point 2 of 4", "end of file"),
        (H13 + "points: 4 4\ntype: or\nsamples: 8\n0 0 1\n", 6, "point 1 of 4 ('x y z multiplicity')", "'0 0 1'"),
        (H13 + "points: 4 4\ntype: or\nsamples: 8\n0 0 z 1\n", 6, "a number (coordinate)", "'z'"),
        (H13 + "points: 4 4\ntype: or\nsamples: 8\n0 0 0 -1\n", 6, "a multiplicity >= 1", "'-1'"),
        (H13 + "points: 4 4\ntype: or\nsamples: 8\n0 0 0 one\n", 6, "an integer multiplicity", "'one'"),
        (H13 + "points: 4 5\ntype: or\nsamples: 8\n" + ROWS4, 3, "total 4 (the sum of the multiplicities)", "'5'"),
        (H13 + "points: 4 4\ntype: or\nsamples: 8\n" + ROWS4 + "2 2 2 1\n", 10, "end of file after the 4 points", "'2 2 2 1'"),
        ("version: 1.5\n", 1, "'version: 1.4'", "'version: 1.5'"),
        ("version: 1.4\ncontact: 0 0\n", 2, "3 numbers after 'contact:'", "2"),
        ("version: 1.4\ncontact: 0 0 x\n", 2, "a number after 'contact:'", "'x'"),
        ("version: 1.4\nend: 0 0 0\n", 2, "'contact: x y z'", "'end: 0 0 0'"),
        (V14 + "sz 1\n", 6, "'size: S'", "'sz 1'"),
        (V14 + "size: big\n", 6, "a number after 'size'", "'big'"),
        (V14 + "size 1\npoints: x\n", 7, "an integer after 'points:'", "'x'"),
        (V14 + "size 1\npoints: 0\n", 7, "at least 1 point", "'0'"),
        (V14 + "size 1\npoints: 4\nrange: 0\n", 8, "2 numbers after 'range:'", "1"),
        (V14 + "size 1\npoints: 4\nrange: 0 q\n", 8, "a number after 'range:'", "'q'"),
        (V14 + "size 1\npoints: 4\nrange: 0 1\ndimension: 2\n", 9, "'dimension: 3' or 'dimension: 4'", "'2'"),
        (V14 + "size 1\npoints: 4\nrange: 0 1\ndimension: 4\ntype: nurbs\n", 10, "'type: bspline'", "'nurbs'"),
        (V14 + "size 1\npoints: 2\nrange: 0 1\ndimension: 4\ntype: bspline\n0 0 0 1\n1 0 0 1\n", 7,
         "at least 4 control points", "2"),
        (V14 + "size 1\npoints: 4\nrange: 0 1\ndimension: 3\ntype: bspline\n0 0 0 1\n", 11, "point 1 of 4 ('x y z')",
         "'0 0 0 1'"),
        ("4 x open\n", 1, "a dimension (2 or 3)", "'x'"),
        ("4 4 open\n", 1, "a dimension 2 or 3", "'4'"),
        ("4 2 shut\n", 1, "'open' or 'closed'", "'shut'"),
        ("3 2 open\n0 0\n1 0\n2 0\n", 1, "at least 4 control points", "'3'"),
        ("4 2 open\n0 0\n1 0 0\n", 3, "point 2 of 4 (2 numbers)", "'1 0 0'"),
        ("4 2 open\n0 0\n1 a\n", 3, "a number (coordinate)", "'a'"),
        ("4 2 open\n0 0\n1 0\n2 0\n", None, "point 4 of 4 (2 numbers)", "end of file"),
    ],
)
def test_malformed_con(write, text, line, expected, found):
    p = write("bad.con", text)
    with pytest.raises(FormatError) as err:
        read_con(p)
    e = err.value
    assert e.line == line and expected in e.expected and found in e.found, str(e)
    where = f"{p}:{line}" if line is not None else f"{p}"
    assert str(e).startswith(f"{where}: expected ")


@pytest.mark.parametrize(
    "text, line, expected, found",
    [
        ("contourgalleryver 2 1\n", 1, "'contourgalleryver 1 1'", "'contourgalleryver 2 1'"),
        ("contourgalleryver 1 1\nitem: 1\n", 2, "'items: N'", "'item: 1'"),
        ("contourgalleryver 1 1\nitems: x\n", 2, "an integer after 'items:'", "'x'"),
        ("contourgalleryver 1 1\nitems: -1\n", 2, "an item count >= 0", "'-1'"),
        ("contourgalleryver 1 1\nitems: 1\n4 2 open\n", 3, "'cver 1 N'", "'4 2 open'"),
        ("contourgalleryver 1 1\nitems: 1\nversion: 1.4\n", 3, "'cver 1 N'", "'version: 1.4'"),
        ("contourgalleryver 1 1\nitems: 0\n" + CALYX, 3, "end of file after 0 items", "'cver 1 3'"),
    ],
)
def test_malformed_cset(write, text, line, expected, found):
    p = write("bad.cset", text)
    with pytest.raises(FormatError) as err:
        read_cset(p)
    e = err.value
    assert e.line == line and expected in e.expected and found in e.found, str(e)


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_con(tmp_path / "none.con")
