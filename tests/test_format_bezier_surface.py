"""Bezier surfaces (.s): reading, writing, bicubic patch evaluation and the turtle-frame transform."""
from __future__ import annotations

from math import comb

import numpy as np
import pytest
from conftest import no_partial_files
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from inflo.formats.bezier_surface import (
    NEIGHBOUR_KEYS,
    BezierPatch,
    BezierSurface,
    bezier_patch,
    format_bezier_surface,
    read_bezier_surface,
    write_bezier_surface,
)
from inflo.formats.errors import FormatError, InputError

PETAL = """-0.70 0.70   0.00 0.30   0.00 1.00
CONTACT POINT  X: 0.00 Y: 0.00 Z: 0.00
END POINT  X: 0.00 Y: 0.00 Z: 1.00
HEADING  X: 0.00 Y: 0.00 Z: 1.00
UP  X: 0.00 Y: 1.00 Z: 0.00
SIZE: 1.00
petal
TOP COLOR: 1 DIFFUSE: 0.70 BOTTOM COLOR: 2 DIFFUSE: 0.50
AL: ~ A: ~ AR: ~
L: ~ R: ~
BL: ~ B: ~ BR: ~
-0.02 0.00 1.00  0.00 0.00 1.00  0.00 0.00 1.00  0.02 0.00 1.00
-0.40 0.10 0.75  -0.15 0.30 0.30  0.15 0.30 0.30  0.40 0.10 0.75
-0.70 0.00 0.20  -0.25 0.00 0.20  0.25 0.00 0.20  0.70 0.00 0.20
-0.01 0.00 0.00  -0.01 0.00 0.00  0.01 0.00 0.00  0.01 0.00 0.00
"""


def reference_patch(cp: np.ndarray, u: float, v: float) -> np.ndarray:
    """Tensor-product Bernstein sum written out with math.comb."""
    out = np.zeros(3)
    for i in range(4):
        for j in range(4):
            bu = comb(3, i) * u**i * (1 - u) ** (3 - i)
            bv = comb(3, j) * v**j * (1 - v) ** (3 - j)
            out += bu * bv * cp[i, j]
    return out


def test_petal_example(write):
    s = read_bezier_surface(write("petal.s", PETAL))
    assert len(s.patches) == 1 and s.size == 1.0 and s.precision is None and not s.stedit
    p = s.patches[0]
    assert p.name == "petal" and (p.top_color, p.top_diffuse, p.bottom_color, p.bottom_diffuse) == (1, 0.7, 2, 0.5)
    assert p.neighbours == ("~",) * 8
    assert p.control_points.shape == (4, 4, 3)
    np.testing.assert_array_equal(p.control_points[1, 2], [0.15, 0.30, 0.30])
    np.testing.assert_array_equal(s.heading, [0, 0, 1])
    np.testing.assert_array_equal(s.end, [0, 0, 1])
    # corners of the patch are corner control points
    np.testing.assert_array_equal(s.evaluate(0.0, 0.0), p.control_points[0, 0])
    np.testing.assert_array_equal(s.evaluate(1.0, 1.0), p.control_points[3, 3])
    np.testing.assert_array_equal(s.evaluate(0.0, 1.0), p.control_points[0, 3])
    np.testing.assert_array_equal(s.evaluate(1.0, 0.0), p.control_points[3, 0])


def test_evaluation_matches_bernstein_reference():
    rng = np.random.default_rng(0)
    cp = rng.normal(size=(4, 4, 3))
    u, v = rng.uniform(0, 1, 50), rng.uniform(0, 1, 50)
    got = bezier_patch(cp, u, v)
    assert got.shape == (50, 3)
    np.testing.assert_allclose(got, [reference_patch(cp, a, b) for a, b in zip(u, v)], atol=1e-13)
    grid = bezier_patch(cp, u[:, None], v[None, :7])  # broadcasting
    assert grid.shape == (50, 7, 3)
    np.testing.assert_allclose(grid[3, 5], reference_patch(cp, u[3], v[5]), atol=1e-13)
    assert bezier_patch(cp, 0.5, 0.5).shape == (3,)
    with pytest.raises(ValueError):
        bezier_patch(np.zeros((3, 4, 3)), 0, 0)


def test_bilinear_control_net_gives_a_plane_with_linear_parametrization():
    a, b = np.meshgrid(np.arange(4) / 3, np.arange(4) / 3, indexing="ij")
    cp = np.stack([2.0 * a, 5.0 * b, np.zeros_like(a)], axis=-1)  # evenly spaced: linear precision
    u, v = np.random.default_rng(1).uniform(0, 1, (2, 30))
    np.testing.assert_allclose(bezier_patch(cp, u, v), np.column_stack([2 * u, 5 * v, 0 * u]), atol=1e-14)


def test_grid():
    s = BezierSurface((BezierPatch("a", np.random.default_rng(2).normal(size=(4, 4, 3))),) * 2)
    g = s.grid(5, 3)
    assert g.shape == (2, 5, 3, 3)
    np.testing.assert_allclose(g[1, 4, 2], s.evaluate(1.0, 1.0, patch=1))
    with pytest.raises(ValueError):
        s.grid(1, 3)


def test_turtle_frame_of_the_usual_header_is_lpfgs_swap(write):
    s = read_bezier_surface(write("petal.s", PETAL))
    t = s.to_turtle_frame()
    cp = s.patches[0].control_points
    # lpfg: translate by -contact, scale by 1/SIZE, then (x, y, z) -> (-x, z, y) for heading +Z, up +Y
    np.testing.assert_allclose(t.patches[0].control_points, np.stack([-cp[..., 0], cp[..., 2], cp[..., 1]], -1), atol=1e-15)
    np.testing.assert_array_equal(t.heading, [0, 1, 0])
    np.testing.assert_array_equal(t.up, [0, 0, 1])
    np.testing.assert_array_equal(t.contact, [0, 0, 0])
    assert t.size == 1.0
    np.testing.assert_allclose(t.end, [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(t.frame(), np.eye(3), atol=1e-15)


def test_turtle_frame_general_header():
    rng = np.random.default_rng(5)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    heading, up = q[:, 0] * 3.0, q[:, 1] + 0.4 * q[:, 0]  # not unit, up not perpendicular
    contact = np.array([1.0, -2.0, 0.5])
    cp = rng.normal(size=(4, 4, 3))
    cp[3, 0] = contact
    cp[0, 0] = contact + 2.5 * q[:, 0]  # along the heading, 2.5 away
    cp[0, 1] = contact + 2.5 * q[:, 1]  # along the (perpendicular part of the) up vector
    s = BezierSurface((BezierPatch("p", cp),), contact=contact, heading=heading, up=up, size=2.5)
    r = s.frame()
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(r) == pytest.approx(1.0)
    t = s.to_turtle_frame().patches[0].control_points
    np.testing.assert_allclose(t[3, 0], [0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(t[0, 0], [0, 1, 0], atol=1e-12)  # heading -> +Y, 1/SIZE scaling
    np.testing.assert_allclose(t[0, 1], [0, 0, 1], atol=1e-12)  # up -> +Z
    # distances scale by 1/SIZE, angles are kept
    d0 = np.linalg.norm(cp[1, 1] - cp[2, 2])
    assert np.linalg.norm(t[1, 1] - t[2, 2]) == pytest.approx(d0 / 2.5)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(patches=()), "at least one"),
        (dict(size=0.0), "size"),
        (dict(heading=(0, 0, 0)), "heading"),
        (dict(up=(0, 0, 0)), "up vector"),
        (dict(heading=(0, 1, 0), up=(0, 2, 0)), "parallel"),
        (dict(contact=(0, 1)), "contact"),
        (dict(precision=(0, 3)), "precision"),
    ],
)
def test_surface_constructor_rejects(kwargs, match):
    kwargs.setdefault("patches", (BezierPatch("p", np.zeros((4, 4, 3))),))
    with pytest.raises(ValueError, match=match):
        BezierSurface(**kwargs)


def test_patch_constructor_rejects():
    with pytest.raises(ValueError, match="shape"):
        BezierPatch("p", np.zeros((4, 3, 3)))
    with pytest.raises(ValueError, match="one token"):
        BezierPatch("two words", np.zeros((4, 4, 3)))
    with pytest.raises(ValueError, match="neighbours"):
        BezierPatch("p", np.zeros((4, 4, 3)), neighbours=("~",) * 7)
    p = BezierPatch("p", np.zeros((4, 4, 3)))
    assert p != 1 and BezierSurface((p,)) != 1 and BezierSurface((p,)) == BezierSurface((p,))


# ---------------------------------------------------------------------------------------------
# round trips

SIX = st.integers(-10**7, 10**7).map(lambda k: k / 1e6)
WORD = st.text(st.characters(min_codepoint=33, max_codepoint=126).filter(lambda ch: ch != ":"), min_size=1, max_size=8)


@st.composite
def surfaces(draw):
    stedit = draw(st.booleans())
    patches = []
    for _ in range(draw(st.integers(1, 3))):
        nb = tuple(draw(st.one_of(st.just("~"), WORD, st.tuples(WORD, WORD).map(" ".join) if stedit else WORD))
                   for _ in NEIGHBOUR_KEYS)
        patches.append(BezierPatch(draw(WORD), draw(hnp.arrays(np.float64, (4, 4, 3), elements=SIX)),
                                   draw(st.integers(0, 255)), draw(SIX), draw(st.integers(0, 255)), draw(SIX), nb))
    heading = draw(st.sampled_from([(0, 0, 1), (0, 1, 0), (1, 0.5, 0), (0.25, 0, -1)]))
    up = draw(st.sampled_from([(1, 0, 0), (0, 0.5, 0.5), (-0.75, 0, 0.125)]).filter(
        lambda u: np.linalg.norm(np.cross(u, heading)) > 0.1))
    return BezierSurface(tuple(patches), contact=draw(st.tuples(SIX, SIX, SIX)), end=draw(st.tuples(SIX, SIX, SIX)),
                         heading=heading, up=up, size=draw(st.integers(1, 10**7).map(lambda k: k / 1e6)),
                         precision=draw(st.one_of(st.none(), st.tuples(st.integers(1, 50), st.integers(1, 50)))),
                         stedit=stedit)


@settings(max_examples=25, deadline=None)
@given(s=surfaces())
def test_round_trip(tmp_path_factory, s):
    path = tmp_path_factory.mktemp("s") / "leaf.s"
    write_bezier_surface(path, s)
    back = read_bezier_surface(path)
    assert back == s
    text = path.read_text()
    write_bezier_surface(path, back)
    assert path.read_text() == text
    assert no_partial_files(path.parent)


def test_writer_bounding_box_stedit_and_precision(write):
    s = read_bezier_surface(write("petal.s", PETAL))
    text = format_bezier_surface(s)
    assert text.splitlines()[0] == "-0.700000 0.700000   0.000000 0.300000   0.000000 1.000000"
    assert "CONTACT POINT  X: 0.000000 Y: 0.000000 Z: 0.000000" in text
    st_text = PETAL.replace("AL: ~ A: ~ AR: ~", "AL: ~ ~ A: top b AR: ~ ~")
    s3 = read_bezier_surface(write("st2.s", "VERSION stedit\n" + st_text.replace("SIZE: 1.00", "SIZE: 2.00")))
    assert s3.stedit and s3.patches[0].neighbours[:3] == ("~ ~", "top b", "~ ~") and s3.size == 2.0
    assert format_bezier_surface(s3).startswith("VERSION stedit\n")
    s4 = read_bezier_surface(write("pr.s", PETAL.replace("CONTACT", "PRECISION S: 4 T: 6\nCONTACT")))
    assert s4.precision == (4, 6)
    assert "PRECISION S: 4 T: 6\n" in format_bezier_surface(s4)


# ---------------------------------------------------------------------------------------------
# malformed input

LINES = PETAL.splitlines()


def petal_with(line_no: int, text: str | None) -> str:
    """PETAL with 1-based line ``line_no`` replaced (None: removed, with the rest of the file)."""
    lines = list(LINES)
    if text is None:
        return "\n".join(lines[: line_no - 1]) + "\n"
    lines[line_no - 1] = text
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(
    "text, line, expected, found",
    [
        ("", None, "a bounding box", "end of file"),
        ("VERSION stedit\n", None, "a bounding box", "end of file"),
        ("VERSION 2\n", 1, "'VERSION stedit'", "'VERSION 2'"),
        (petal_with(1, "0 1 0 1 0"), 1, "a bounding box 'xmin xmax ymin ymax zmin zmax' (6 numbers)", "'0 1 0 1 0'"),
        (petal_with(1, "0 1 0 1 0 x"), 1, "a number in the bounding box", "'x'"),
        (petal_with(1, "0 1 0 1 0 1\nPRECISION S: 4"), 2, "'PRECISION S: s T: t'", "'PRECISION S: 4'"),
        (petal_with(1, "0 1 0 1 0 1\nPRECISION S: 4 T: x"), 2, "an integer precision", "'x'"),
        (petal_with(1, "0 1 0 1 0 1\nPRECISION S: 0 T: 3"), 2, "precisions >= 1", "'PRECISION S: 0 T: 3'"),
        (petal_with(2, "CONTACT  X: 0 Y: 0 Z: 0"), 2, "'CONTACT POINT  X: x Y: y Z: z'", "'CONTACT  X: 0 Y: 0 Z: 0'"),
        (petal_with(2, "CONTACT POINT X: 0 Y: 0"), 2, "'CONTACT POINT  X: x Y: y Z: z'", "'CONTACT POINT X: 0 Y: 0'"),
        (petal_with(2, "CONTACT POINT X: 0 Y: a Z: 0"), 2, "a number in the CONTACT POINT line", "'a'"),
        (petal_with(3, "END  X: 0 Y: 0 Z: 0"), 3, "'END POINT  X: x Y: y Z: z'", "'END  X: 0 Y: 0 Z: 0'"),
        (petal_with(4, "HEADING X: 0 Y: 0 Z: 0"), 4, "a non-zero HEADING vector", "'HEADING X: 0 Y: 0 Z: 0'"),
        (petal_with(4, "HEADING X: 0 Y: 0 Z: inf"), 4, "a number in the HEADING line (finite)", "'inf'"),
        (petal_with(5, "UP X: 0 Y: 0 Z: 0"), 5, "a non-zero UP vector", "'UP X: 0 Y: 0 Z: 0'"),
        (petal_with(5, "UP X: 0 Y: 0 Z: -2"), 5, "an UP vector not parallel to HEADING", "'UP X: 0 Y: 0 Z: -2'"),
        (petal_with(6, "SIZE 1.00"), 6, "'SIZE: s'", "'SIZE 1.00'"),
        (petal_with(6, "SIZE: one"), 6, "a number after 'SIZE:'", "'one'"),
        (petal_with(6, "SIZE: 0"), 6, "a size > 0", "'0'"),
        (petal_with(7, None), None, "at least one patch after 'SIZE:'", "end of file"),
        (petal_with(7, "petal one"), 7, "a patch name (one word)", "'petal one'"),
        (petal_with(8, None), None, "'TOP COLOR: i DIFFUSE: d BOTTOM COLOR: j DIFFUSE: e'", "end of file"),
        (petal_with(8, "TOP COLOR: 1 DIFFUSE: 0.7"), 8, "'TOP COLOR: i DIFFUSE: d BOTTOM COLOR: j DIFFUSE: e'",
         "'TOP COLOR: 1 DIFFUSE: 0.7'"),
        (petal_with(8, "TOP COLOR: red DIFFUSE: 0.70 BOTTOM COLOR: 2 DIFFUSE: 0.50"), 8, "an integer colour index", "'red'"),
        (petal_with(8, "TOP COLOR: 1 DIFFUSE: x BOTTOM COLOR: 2 DIFFUSE: 0.50"), 8, "a number after 'DIFFUSE:'", "'x'"),
        (petal_with(9, "AL: ~ A: ~"), 9, "'AL: name A: name AR: name' ('~' for none)", "'AL: ~ A: ~'"),
        (petal_with(9, "AL: ~ AR: ~ A: ~"), 9, "'AL: name A: name AR: name'", "'AL: ~ AR: ~ A: ~'"),
        (petal_with(9, "~ AL: ~ A: ~ AR: ~"), 9, "'AL: name A: name AR: name'", "'~ AL: ~ A: ~ AR: ~'"),
        (petal_with(9, "AL: ~ A: AR: ~"), 9, "'AL: name A: name AR: name'", "'AL: ~ A: AR: ~'"),
        (petal_with(10, "L: ~ ~ R: ~"), 10, "'L: name R: name'", "'L: ~ ~ R: ~'"),  # two words need stedit
        (petal_with(11, "BL: ~ B: ~ BR: ~ X: ~"), 11, "'BL: name B: name BR: name'", "'BL: ~ B: ~ BR: ~ X: ~'"),
        (petal_with(12, "-0.02 0.00 1.00  0.00 0.00 1.00  0.00 0.00 1.00  0.02 0.00"), 12,
         "control-point row 1 of 4 (12 numbers: 4 points x y z)", "11 numbers"),
        (petal_with(14, "-0.70 0.00 0.20  -0.25 0.00 0.20  0.25 0.00 0.20  0.70 0.00 nan"), 14,
         "a number (control-point coordinate) (finite)", "'nan'"),
        (petal_with(15, None), None, "control-point row 4 of 4", "end of file"),
        (PETAL + "second\n", None, "'TOP COLOR: i DIFFUSE: d BOTTOM COLOR: j DIFFUSE: e'", "end of file"),
    ],
)
def test_malformed(write, text, line, expected, found):
    p = write("bad.s", text)
    with pytest.raises(FormatError) as err:
        read_bezier_surface(p)
    e = err.value
    assert e.line == line and expected in e.expected and found in e.found, str(e)
    where = f"{p}:{line}" if line is not None else f"{p}"
    assert str(e).startswith(f"{where}: expected ")


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_bezier_surface(tmp_path / "none.s")
