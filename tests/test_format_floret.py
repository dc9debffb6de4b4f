"""Floret key-pose file (.floret): reader, writer, compatibility check, symmetry expansion."""
from __future__ import annotations

import dataclasses
import math
import re
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from inflo.formats.errors import FormatError, InputError
from inflo.formats.floret import (
    FLORET_TABLE,
    ORGAN_TABLE,
    REQUIRED,
    Floret,
    Organ,
    check_compatible,
    format_floret,
    full_petal,
    petal_angles_deg,
    petals,
    read_floret,
    write_floret,
)

SPEC = Path(__file__).resolve().parent.parent / "formats" / "floret.md"


def spec_examples() -> list[str]:
    """The ```floret blocks of formats/floret.md."""
    blocks = re.findall(r"```floret\n(.*?)```", SPEC.read_text(), re.S)
    assert len(blocks) >= 2, "formats/floret.md should hold the disk floret and lily examples"
    return blocks


def square(nv=2, nu=2) -> np.ndarray:
    """A flat (nv, nu, 3) grid: u along z, v along y."""
    v, u = np.meshgrid(np.arange(nv, dtype=float), np.arange(nu, dtype=float), indexing="ij")
    return np.stack([np.ones_like(u), v, u], axis=-1)


# ----------------------------------------------------------------------------------------------
# The spec's examples
# ----------------------------------------------------------------------------------------------


def test_disk_floret_example(write, tmp_path):
    f = read_floret(write("disk.floret", spec_examples()[0]))
    assert f.name == "disk-bud" and f.key_time == 0.0
    assert [o.name for o in f.organs] == ["corolla", "stamens"]
    corolla, stamens = f.organs
    assert corolla.control_points.shape == (5, 3, 3)  # (nv, nu, xyz)
    assert corolla.control_points.dtype == np.float64
    assert (corolla.degree_u, corolla.degree_v) == (3, 3)
    assert (corolla.symmetry_n, corolla.symmetry_phase_deg) == (5, 0.0)
    assert corolla.bilateral and corolla.fused == 3 and corolla.nu_full == 5
    assert corolla.material == 1 and corolla.lambda_ == 0.125 and corolla.eta == 7.0
    np.testing.assert_array_equal(corolla.control_points[4, 0], [0.35, 0.85, 0.0])  # tip midline
    np.testing.assert_array_equal(corolla.control_points[0, 2], [0.0809, 0.0, 0.05878])
    assert (stamens.degree_u, stamens.degree_v, stamens.fused) == (1, 2, 3)
    assert stamens.tilt_deg == 0.0 and stamens.lambda_ is None
    assert f.source == tmp_path / "disk.floret"
    assert f.organ("stamens") is stamens


def test_lily_example(write, tmp_path):
    f = read_floret(write("poses/lily.floret", spec_examples()[1]))
    sepals, petals_ = f.organs
    assert (sepals.symmetry_n, sepals.symmetry_phase_deg) == (3, 0.0)
    assert (petals_.symmetry_n, petals_.symmetry_phase_deg) == (3, 60.0)
    assert petals_.degree_u == 3 and petals_.degree_v == 3  # defaults
    assert petals_.fused == 0 and not isinstance(petals_.eta, float)
    assert petals_.eta == tmp_path / "poses" / "petal_eta.func"  # relative to the file


def test_spec_examples_round_trip(write, tmp_path):
    for i, text in enumerate(spec_examples()):
        f = read_floret(write(f"in/{i}.floret", text))
        out = tmp_path / "frames" / f"{i}.floret"
        write_floret(out, f)
        g = read_floret(out)
        assert g == f
        assert format_floret(g, out.parent) == out.read_text()


def test_relative_func_paths_follow_the_written_file(write, tmp_path):
    f = read_floret(write("keys/lily.floret", spec_examples()[1]))
    write_floret(tmp_path / "build" / "frames" / "frame_0000.floret", f)
    text = (tmp_path / "build" / "frames" / "frame_0000.floret").read_text()
    assert "eta: ../../keys/petal_eta.func\n" in text


def test_comments_blank_lines_crlf_bom(tmp_path):
    text = ("\ufeff# a key pose\r\nfloret 1   # format\r\nname: f\r\n\r\norgan: p # petal\r\n"
            "degree: 1 1\r\ngrid: 2 2\r\npoints:\r\n# base\r\n 0 0 0 1 0 0\r\n\r\n"
            "  0 1 0   1 1 0  # tip\r\n")
    path = tmp_path / "c.floret"
    path.write_bytes(text.encode())
    f = read_floret(path)
    np.testing.assert_array_equal(f.organs[0].control_points[1], [[0, 1, 0], [1, 1, 0]])


# ----------------------------------------------------------------------------------------------
# Malformed input: every error path, with its line
# ----------------------------------------------------------------------------------------------

GOOD = """\
floret 1
name: f
organ: p
grid: 2 2
degree: 1 1
points:
  0 0 0  1 0 0
  0 1 0  1 1 0
"""


def edit(line_no: int, new: str | None, text: str = GOOD) -> str:
    """GOOD with 1-based line ``line_no`` replaced (None: removed)."""
    lines = text.splitlines()
    if new is None:
        del lines[line_no - 1]
    else:
        lines[line_no - 1] = new
    return "\n".join(lines) + "\n"


ORGAN_Q = "organ: q\ngrid: 2 2\ndegree: 1 1\npoints:\n  0 0 0 1 0 0\n  0 1 0 1 1 0\n"

MALFORMED = [
    # (text, line, expected fragment)
    ("", None, "'floret 1' as the first line"),
    ("# only a comment\n\n", None, "'floret 1' as the first line"),
    (edit(1, "floret 2"), 1, "floret format version 1"),
    (edit(1, "flower 1"), 1, "'floret 1' as the first line"),
    (edit(1, "floret"), 1, "'floret 1' as the first line"),
    (edit(2, None), 2, "'name: FLORET-NAME' before the first 'organ:'"),
    ("floret 1\nname: f\n", 2, "at least one 'organ:'"),
    ("floret 1\n", 1, "'name: FLORET-NAME'"),
    (edit(2, "name: two words"), 2, "a floret name"),
    (edit(2, "name:"), 2, "a floret name"),
    (edit(2, "name: f\nname: g"), 3, "once (already on line 2)"),
    (edit(2, "name: f\ntime: x"), 3, "a key time"),
    (edit(2, "name: f\ntime: nan"), 3, "(finite)"),
    (edit(2, "name: f\ntime: 1 2"), 3, "1 number after 'time:'"),
    (edit(2, "name: f\ndegree: 1 1"), 3, "'organ: NAME' before 'degree:'"),
    (edit(4, "grid: 2 2\ntime: 0"), 5, "before the first 'organ:' (it is a floret key)"),
    (edit(5, "degre: 1 1"), 5, "did you mean 'degree'?"),
    (edit(5, "simmetry: 5"), 5, "did you mean 'symmetry'?"),
    (edit(5, "degree 1 1"), 5, "'key: value'"),
    (edit(5, ": 1 1"), 5, "a key before ':'"),
    (edit(3, "organ: a b"), 3, "an organ name"),
    (edit(3, "organ: -p"), 3, "an organ name"),
    (edit(3, "organ:"), 3, "an organ name"),
    (GOOD + "organ: p\n", 9, "a new organ name ('p' is already used on line 3)"),
    (edit(5, "degree: 1 1\ngrid: 2 2"), 6, "once per organ (already on line 4)"),
    (edit(5, "degree: 1"), 5, "2 integers"),
    (edit(5, "degree: 0 1"), 5, "degrees in 1..5"),
    (edit(5, "degree: 1 6"), 5, "degrees in 1..5"),
    (edit(5, "degree: 1.0 1"), 5, "an integer degree"),
    (edit(5, "degree: 2 1"), 5, "degree u < control points in u (2)"),
    (edit(5, "degree: 1 2"), 5, "degree v < control points in v (2)"),
    (edit(5, None), 4, "degree u < control points in u"),  # default degree 3 on a 2 x 2 grid
    (edit(5, "degree: 3 1\nbilateral: on"), 5, "degree u < control points in u (3 mirrored)"),
    (edit(4, "grid: 2"), 4, "2 integers (nu across, nv base to tip)"),
    (edit(4, "grid: 0 2"), 4, "nu >= 1 and nv >= 2"),
    (edit(4, "grid: 2 1"), 4, "nu >= 1 and nv >= 2"),
    (edit(4, "grid: 2 x"), 4, "an integer grid size"),
    (edit(4, None), 5, "'grid: nu nv' before 'points:'"),
    (edit(5, "degree: 1 1\nsymmetry: 0"), 6, "n >= 1"),
    (edit(5, "degree: 1 1\nsymmetry: 5 inf"), 6, "(finite)"),
    (edit(5, "degree: 1 1\nsymmetry: 5 0 1"), 6, "n [phase-degrees]"),
    (edit(5, "degree: 1 1\nsymmetry: 2.5"), 6, "an integer n"),
    (edit(5, "degree: 1 1\nbilateral: maybe"), 6, "on or off"),
    (edit(5, "degree: 1 1\nfused: -1"), 6, "fused >= 0"),
    (edit(5, "degree: 1 1\nfused: 3\nbilateral: on\nsymmetry: 5"), 6, "0 <= fused <= nv (2)"),
    (edit(5, "degree: 1 1\nfused: 1\nsymmetry: 5"), 6, "unless 'bilateral: on'"),
    (edit(5, "degree: 1 1\nfused: 1\nbilateral: on"), 6, "symmetry n >= 2"),
    (edit(5, "degree: 1 1\ntilt: inf"), 6, "(finite)"),
    (edit(5, "degree: 1 1\ntilt: 1 2"), 6, "1 angle in degrees"),
    (edit(5, "degree: 1 1\nmaterial: -1"), 6, "an id >= 0"),
    (edit(5, "degree: 1 1\nmaterial: red"), 6, "an integer material id"),
    (edit(5, "degree: 1 1\nlambda: 0"), 6, "lambda > 0"),
    (edit(5, "degree: 1 1\nlambda: -0.5"), 6, "lambda > 0"),
    (edit(5, "degree: 1 1\neta: 0.5"), 6, "eta >= 1"),
    (edit(5, "degree: 1 1\neta: nan"), 6, "a number or a .func file"),
    (edit(5, "degree: 1 1\nlambda: spacing.txt"), 6, "a number or a .func file"),
    (edit(5, "degree: 1 1\nlambda:"), 6, "a number or a .func file"),
    (edit(6, "points: 1 2"), 6, "nothing after 'points:'"),
    (edit(7, "  0 0 0  1 0"), 7, "row 1 of 2 of organ 'p': 2 points x y z (6 numbers)"),
    (edit(8, "  0 1 0  1 1 0 0"), 8, "row 2 of 2"),
    (edit(7, "  0 0 0  1 nan 0"), 7, "(finite)"),
    (edit(7, "  0 0 0  1 x 0"), 7, "a number in row 1 of 2"),
    (edit(8, None), 6, "2 rows of points for organ 'p'"),
    (edit(8, None) + ORGAN_Q, 8, "row 2 of 2"),
    (GOOD + "tilt: 5\n", 9, "'organ:' or the end of the file"),
    ("floret 1\nname: f\norgan: p\ngrid: 2 2\n" + ORGAN_Q, 3, "a 'points:' block for organ 'p'"),
    ("floret 1\nname: f\norgan: p\ngrid: 2 2\ndegree: 1 1\n", 3, "a 'points:' block for organ"),
]


@pytest.mark.parametrize("text, line, expected", MALFORMED)
def test_malformed_input_names_file_line_and_expectation(write, text, line, expected):
    path = write("bad.floret", text)
    with pytest.raises(FormatError) as info:
        read_floret(path)
    err = info.value
    assert err.line == line, str(err)
    assert expected in err.expected, err.expected
    where = f"{path}:{line}" if line is not None else f"{path}"
    assert str(err).startswith(f"{where}: expected ")


def test_the_good_base_case_parses(write):
    f = read_floret(write("good.floret", GOOD))
    assert f.organs[0].control_points.shape == (2, 2, 3)
    f2 = read_floret(write("two.floret", GOOD + ORGAN_Q))
    assert [o.name for o in f2.organs] == ["p", "q"]


def test_unknown_key_message_reads_well(write):
    path = write("u.floret", edit(5, "degre: 1 1"))
    with pytest.raises(FormatError) as info:
        read_floret(path)
    assert str(info.value) == (
        f"{path}:5: expected a known key (did you mean 'degree'?), found 'degre'"
    )


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_floret(tmp_path / "nope.floret")


def spec_table(heading: str) -> dict[str, list[str]]:
    """The rows of the table under ``### heading`` in formats/floret.md: key -> other cells."""
    section = SPEC.read_text().split(f"### {heading}\n", 1)[1].split("\n#", 1)[0]
    rows = {}
    for line in section.splitlines():
        m = re.match(r"^\| `([^`]+)` \|(.*)\|$", line)
        if m:
            rows[m.group(1)] = [c.strip() for c in m.group(2).split("|")]
    return rows


def test_key_tables_match_the_spec_tables():
    """The reader's key tables (formats/floret.py) and the spec's field tables name the same keys,
    with the same defaults, and the wrong-count rule of the spec matches their counts."""
    floret_rows, organ_rows = spec_table("Floret"), spec_table("Organ")
    del floret_rows["floret 1"]  # the format line, not a key
    assert set(floret_rows) == set(FLORET_TABLE)
    assert set(organ_rows) == {"organ", *ORGAN_TABLE}
    for table, rows in ((FLORET_TABLE, floret_rows), (ORGAN_TABLE, organ_rows)):
        for key, spec in table.items():
            default = rows[key][1]
            if spec.default == REQUIRED:
                assert default == "required", key
            elif spec.default is None:
                assert default.startswith("("), (key, default)  # "(none)", "(polygonize default)"
            elif isinstance(spec.default, bool):
                assert default == ("on" if spec.default else "off"), key
            else:
                vals = spec.default if isinstance(spec.default, tuple) else (spec.default,)
                assert default == " ".join(f"{v:g}" for v in vals), (key, default)
    # "a wrong count of values (`degree` 2, `grid` 2, `symmetry` 1 or 2, others 1)"
    rule = re.search(r"a wrong count of values \((.*?)\)", SPEC.read_text()).group(1)
    named = {k: v for k, v in re.findall(r"`(\w+)` ([^,]+)", rule)}
    assert re.search(r"others 1$", rule)
    for key, spec in {**FLORET_TABLE, **ORGAN_TABLE}.items():
        if spec.counts is None:
            continue
        lo, hi = spec.counts
        assert named.get(key, "1") == (str(lo) if lo == hi else f"{lo} or {hi}"), key
    assert set(named) <= set(ORGAN_TABLE)


# ----------------------------------------------------------------------------------------------
# Objects built in code validate themselves the same way
# ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "changes, fragment",
    [
        ({"name": "a b"}, "a name of"),
        ({"control_points": np.zeros((2, 2))}, "shape (nv, nu, 3)"),
        ({"control_points": np.full((2, 2, 3), np.nan)}, "finite coordinates"),
        ({"degree_u": 0}, "degrees in 1..5"),
        ({"degree_v": 2}, "degree v <"),
        ({"symmetry_n": 0}, "n >= 1"),
        ({"fused": 3}, "0 <= fused <= nv"),
        ({"fused": 1}, "fused 0 unless"),
        ({"material": -2}, "an id >= 0"),
        ({"lambda_": 0.0}, "lambda > 0"),
        ({"eta": Path("/x/eta.txt")}, "a .func file"),
        ({"tilt_deg": math.inf}, "a finite angle"),
    ],
)
def test_organ_rejects_broken_invariants(changes, fragment):
    fields = dict(name="p", degree_u=1, degree_v=1, control_points=square())
    fields.update(changes)
    with pytest.raises(ValueError, match=re.escape(fragment)):
        Organ(**fields)


def test_floret_rejects_broken_invariants():
    p = Organ("p", 1, 1, square())
    with pytest.raises(ValueError, match="at least one organ"):
        Floret("f", ())
    with pytest.raises(ValueError, match="distinct organ names"):
        Floret("f", (p, p))
    with pytest.raises(ValueError, match="a finite key time"):
        Floret("f", (p,), key_time=math.nan)
    with pytest.raises(ValueError, match="a name of"):
        Floret("", (p,))


def test_organ_points_are_a_read_only_copy():
    cp = square()
    o = Organ("p", 1, 1, cp)
    cp[0, 0, 0] = 99.0
    assert o.control_points[0, 0, 0] == 1.0
    with pytest.raises(ValueError):
        o.control_points[0, 0, 0] = 5.0


def test_writer_refuses_what_it_cannot_read_back(tmp_path):
    bad = Floret("f", (Organ("p", 1, 1, square(), eta=Path("/a#b/eta.func")),))
    with pytest.raises(ValueError, match="cannot write eta path"):
        write_floret(tmp_path / "x.floret", bad)
    assert not (tmp_path / "x.floret").exists()


# ----------------------------------------------------------------------------------------------
# Compatibility of key poses
# ----------------------------------------------------------------------------------------------


def test_compatible_poses_pass(write):
    bud = read_floret(write("bud.floret", spec_examples()[0]))
    opened = dataclasses.replace(
        bud,
        key_time=1.0,
        name="disk-open",
        organs=tuple(dataclasses.replace(o, control_points=o.control_points * 2.0, tilt_deg=30.0,
                                         symmetry_phase_deg=10.0) for o in bud.organs),
    )
    check_compatible(bud, opened, "bud.floret", "open.floret")


@pytest.mark.parametrize(
    "change, fragment",
    [
        (lambda o: dataclasses.replace(o, control_points=np.zeros((6, 3, 3))),
         "organ 'corolla' grid (nu x nv) is 3 x 5 in bud.floret but 3 x 6 in open.floret"),
        (lambda o: dataclasses.replace(o, degree_v=2), "organ 'corolla' degree (u v) is 3 3"),
        (lambda o: dataclasses.replace(o, symmetry_n=6), "symmetry n is 5 in bud.floret but 6"),
        (lambda o: dataclasses.replace(o, fused=2), "fused is 3 in bud.floret but 2"),
        (lambda o: dataclasses.replace(o, bilateral=False, fused=0,
                                       control_points=np.zeros((5, 5, 3))), "grid"),
        (lambda o: dataclasses.replace(o, material=9), "material is 1"),
        (lambda o: dataclasses.replace(o, eta=9.0), "eta is 7.0"),
        (lambda o: dataclasses.replace(o, name="tube"), "the list of organs"),
    ],
)
def test_incompatible_poses_name_both_files(write, change, fragment):
    bud = read_floret(write("bud.floret", spec_examples()[0]))
    other = dataclasses.replace(bud, organs=(change(bud.organs[0]), *bud.organs[1:]))
    with pytest.raises(InputError) as info:
        check_compatible(bud, other, "bud.floret", "open.floret")
    msg = str(info.value)
    assert msg.startswith("bud.floret and open.floret are not compatible key poses: ")
    assert fragment in msg


def test_different_organ_count_is_incompatible(write):
    bud = read_floret(write("bud.floret", spec_examples()[0]))
    one = dataclasses.replace(bud, organs=bud.organs[:1])
    with pytest.raises(InputError, match="the list of organs is"):
        check_compatible(bud, one, "a.floret", "b.floret")


# ----------------------------------------------------------------------------------------------
# Symmetry semantics (full_petal, petals)
# ----------------------------------------------------------------------------------------------


def test_bilateral_mirrors_the_plus_z_half_across_z0():
    half = np.array([[[1.0, 0.0, 0.3], [0.9, 0.0, 0.4], [0.8, 0.0, 0.5]],
                     [[2.0, 1.0, 0.1], [1.9, 1.0, 0.6], [1.7, 1.0, 0.9]]])
    o = Organ("p", 3, 1, half, bilateral=True)
    full = full_petal(o)
    assert full.shape == (2, 5, 3)
    np.testing.assert_array_equal(full[:, 2, 2], 0.0)  # midline projected onto z = 0
    np.testing.assert_array_equal(full[:, 3:], half[:, 1:])
    np.testing.assert_array_equal(full[:, :2, :2], half[:, :0:-1, :2])
    np.testing.assert_array_equal(full[:, :2, 2], -half[:, :0:-1, 2])


def test_tilt_turns_up_toward_right_about_the_base():
    cp = np.array([[[0.0, 0.0, -0.1], [0.0, 0.0, 0.1]], [[0.0, 1.0, -0.1], [0.0, 1.0, 0.1]]])
    o = Organ("p", 1, 1, cp, tilt_deg=90.0)
    full = full_petal(o)
    np.testing.assert_allclose(full[0], cp[0], atol=1e-15)  # the base is the pivot
    np.testing.assert_allclose(full[1], [[1.0, 0.0, -0.1], [1.0, 0.0, 0.1]], atol=1e-15)


def test_fused_points_lie_on_the_symmetry_planes_and_seams_coincide(write):
    f = read_floret(write("disk.floret", spec_examples()[0]))
    for o in f.organs:
        tilted = dataclasses.replace(o, tilt_deg=12.0,
                                     control_points=o.control_points + [0.0, 0.0, 0.01])
        full = full_petal(tilted)
        h = math.pi / o.symmetry_n
        k = o.fused
        np.testing.assert_allclose(full[:k, 0] @ [math.sin(h), 0, math.cos(h)], 0.0, atol=1e-15)
        np.testing.assert_allclose(full[:k, -1] @ [-math.sin(h), 0, math.cos(h)], 0.0, atol=1e-15)
        copies = petals(tilted)
        assert copies.shape == (o.symmetry_n, o.nv, o.nu_full, 3)
        for j in range(o.symmetry_n):
            nxt = (j + 1) % o.symmetry_n
            np.testing.assert_allclose(copies[nxt, :k, -1], copies[j, :k, 0], atol=1e-15)
        # unfused rows keep their distance from the plane
        if k < o.nv:
            assert np.abs(full[k:, 0] @ [math.sin(h), 0, math.cos(h)]).max() > 1e-3


def test_copies_are_rotated_about_y_by_phase_plus_k_360_over_n():
    o = Organ("p", 1, 1, square(), symmetry_n=4, symmetry_phase_deg=30.0)
    np.testing.assert_array_equal(petal_angles_deg(o), [30.0, 120.0, 210.0, 300.0])
    copies = petals(o)
    base = full_petal(o)
    for k, a in enumerate(np.radians(petal_angles_deg(o))):
        # right-handed about +Y: +X turns toward -Z
        expected = np.stack([base[..., 0] * np.cos(a) + base[..., 2] * np.sin(a), base[..., 1],
                             -base[..., 0] * np.sin(a) + base[..., 2] * np.cos(a)], axis=-1)
        np.testing.assert_allclose(copies[k], expected, atol=1e-15)
    np.testing.assert_allclose(petals(dataclasses.replace(o, symmetry_phase_deg=90.0))[0, 0, 0],
                               [0.0, 0.0, -1.0], atol=1e-15)


# ----------------------------------------------------------------------------------------------
# Round trip (hypothesis): numbers with at most 6 decimals so equality is exact
# ----------------------------------------------------------------------------------------------

d6 = st.integers(-10**9, 10**9).map(lambda i: i / 1e6)
NAME = st.from_regex(r"[A-Za-z0-9_][A-Za-z0-9_.+-]{0,10}", fullmatch=True)


@st.composite
def organs(draw, name):
    bilateral = draw(st.booleans())
    nu = draw(st.integers(2, 5))
    nv = draw(st.integers(2, 6))
    nu_full = 2 * nu - 1 if bilateral else nu
    n = draw(st.integers(1, 8))
    cp = np.array(draw(st.lists(d6, min_size=nv * nu * 3, max_size=nv * nu * 3))).reshape(nv, nu, 3)
    if (cp == cp[0, 0]).all():  # an organ of no size is refused by the reader
        cp[-1, -1, 1] += 1.0
    funcs = st.sampled_from(["lam.func", "sub/eta.func", "../up.func"])
    lam = st.none() | st.integers(1, 10**7).map(lambda i: i / 1e6) | funcs
    eta = st.none() | st.integers(10**6, 10**8).map(lambda i: i / 1e6) | funcs
    return dict(
        name=name,
        degree_u=draw(st.integers(1, min(5, nu_full - 1))),
        degree_v=draw(st.integers(1, min(5, nv - 1))),
        control_points=cp,
        symmetry_n=n,
        symmetry_phase_deg=draw(d6),
        bilateral=bilateral,
        fused=draw(st.integers(0, nv)) if bilateral and n >= 2 else 0,
        tilt_deg=draw(st.integers(-360 * 10**6, 360 * 10**6).map(lambda i: i / 1e6)),  # within +-360
        material=draw(st.integers(0, 255)),
        lambda_=draw(lam),
        eta=draw(eta),
    )


@st.composite
def florets(draw):
    names = draw(st.lists(NAME, min_size=1, max_size=3, unique=True))
    return dict(
        name=draw(NAME),
        organs=[draw(organs(n)) for n in names],
        key_time=draw(st.none() | d6),
    )


def build(spec: dict, folder: Path) -> Floret:
    organs_ = []
    for o in spec["organs"]:
        o = dict(o)
        for key in ("lambda_", "eta"):
            if isinstance(o[key], str):  # .func paths come back absolute, against the file's folder
                o[key] = Path(folder.joinpath(o[key]).resolve())
        organs_.append(Organ(**o))
    return Floret(spec["name"], organs_, spec["key_time"])


@settings(max_examples=60, deadline=None)
@given(florets())
def test_round_trip(spec):
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "a"
        floret = build(spec, folder)
        path = folder / "pose.floret"
        write_floret(path, floret)
        first = path.read_bytes()
        back = read_floret(path)
        assert back == floret
        write_floret(path, back)
        assert path.read_bytes() == first


def test_equality_compares_points_exactly():
    a = Floret("f", (Organ("p", 1, 1, square()),))
    b = Floret("f", (Organ("p", 1, 1, square() + 1e-12),))
    assert a != b
    assert a == Floret("f", (Organ("p", 1, 1, square()),), source=Path("/elsewhere"))
