"""SCN and RBA files: thesis app. C.2/C.3, the placement frame convention, extensions, errors."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import no_partial_files
from hypothesis import given, settings
from hypothesis import strategies as st

from inflo.formats.errors import FormatError
from inflo.formats.placement import format_preamble, frame_axes, placement_matrix
from inflo.formats.rba import RbaFrame, rba_bytes, read_rba, read_rba_sequence, write_rba, write_rba_sequence
from inflo.formats.scn import Group, Placement, Scene, read_scn, write_scn

DEC = st.integers(-10**7, 10**7).map(lambda k: k / 1e6)
NONZERO = DEC.filter(lambda x: x != 0)
UNIT_AXES = [(0, 1, 0), (1, 0, 0), (0, 0, 1), (0.6, 0.8, 0), (0, -0.6, 0.8)]


@st.composite
def frames(draw):
    up = draw(st.sampled_from(UNIT_AXES))
    right = draw(st.sampled_from([a for a in UNIT_AXES if abs(np.dot(a, up)) < 0.99]))
    pos = [draw(DEC) for _ in range(3)]
    scale = [draw(NONZERO) for _ in range(3)]
    return pos, scale, up, right


@st.composite
def placements(draw, n_groups):
    kind = draw(st.sampled_from(["o", "ca", "i", "ta", "ra", "rba"]))
    pos, scale, up, right = draw(frames())
    p = Placement(kind, draw(st.integers(0, 20)), pos, scale, up, right)
    if kind in ("ca", "ta", "ra", "rba"):
        p.frame_start = draw(st.integers(0, 50))
        p.frame_end = p.frame_start + draw(st.integers(0, 50))
    if kind == "i":
        p.interpolation = draw(st.integers(0, 10**6)) / 1e6
    if kind == "ta":
        p.translate = np.array([draw(DEC) for _ in range(3)])
    if kind == "ra":
        p.axis = np.array(draw(st.sampled_from(UNIT_AXES)), dtype=float)
        p.angle = draw(DEC)
    if n_groups and draw(st.booleans()):
        p.group = draw(st.integers(0, n_groups - 1))
    if draw(st.booleans()):
        p.emergence = abs(draw(DEC))
    if draw(st.booleans()):
        p.type = draw(st.sampled_from(["ray", "disk", "tubular"]))
    if draw(st.booleans()):
        p.extra = {"note": "hand placed"}
    return p


@st.composite
def scenes(draw):
    n_groups = draw(st.integers(0, 3))
    groups = {g: Group(g, [draw(DEC) for _ in range(3)], -1 if g == 0 else draw(st.integers(-1, g - 1)))
              for g in range(n_groups)}
    pl = draw(st.lists(placements(n_groups), max_size=12))
    material = None
    for p in pl:
        if draw(st.integers(0, 3)) == 0:
            material = draw(st.integers(0, 255))
        p.material = material
    return Scene(pl, groups)


def assert_same_scene(a: Scene, b: Scene):
    assert len(a) == len(b)
    assert sorted(a.groups) == sorted(b.groups)
    for g in a.groups:
        np.testing.assert_array_equal(a.groups[g].centre, b.groups[g].centre)
        assert a.groups[g].parent == b.groups[g].parent
    for p, q in zip(a.placements, b.placements):
        for name in ("kind", "id", "frame_start", "frame_end", "interpolation", "angle", "material", "group",
                     "emergence", "type", "extra"):
            assert getattr(p, name) == getattr(q, name), name
        for name in ("pos", "scale", "up", "right", "translate", "axis"):
            x, y = getattr(p, name), getattr(q, name)
            assert (x is None) == (y is None)
            if x is not None:
                np.testing.assert_array_equal(x, y)


@settings(max_examples=60, deadline=None)
@given(scene=scenes())
def test_scn_round_trip(tmp_path_factory, scene):
    path = tmp_path_factory.mktemp("scn") / "scene.scn"
    write_scn(path, scene)
    back = read_scn(path)
    assert_same_scene(scene, back)
    text = path.read_text()
    write_scn(path, back)
    assert path.read_text() == text


def test_thesis_example_restored(write):
    """The C.2 example, its lost characters restored."""
    p = write("s1.scn", (
        "# Constraint animation with ID 0, corresponding to\n"
        "# an animation listed in the FCComposer parameter file.\n"
        "# ca: ID Position Scale Up Left FrameStart FrameEnd\n"
        "ca: 0 0 0 0 1 1 1 0 1 0 1 0 0 0 1000\n"
        "# Material 3 applied to the following scene placements\n"
        "mtl: 3\n"
        "ca: 0 5 0 0 1 1 1 0 1 0 1 0 0 0 1000\n"
        "o: 2 0 10 0 5 5 1 0 0 1 1 0 0\n"
    ))
    s = read_scn(p)
    assert [q.kind for q in s.placements] == ["ca", "ca", "o"]
    assert [q.material for q in s.placements] == [None, 3, 3]
    assert s.placements[0].frame_end == 1000
    np.testing.assert_array_equal(s.placements[2].pos, [0, 10, 0])


def test_mtl_applies_to_following_until_next(write):
    pre = "0 0 0 1 1 1 0 1 0 1 0 0"
    s = read_scn(write("m.scn", f"o: 0 {pre}\nmtl: 1\no: 0 {pre}\no: 0 {pre}\nmtl: 7\no: 0 {pre}\n"))
    assert [q.material for q in s.placements] == [None, 1, 1, 7]


def test_frame_convention_local_axes():
    """Local +Y -> up, +X -> right (orthogonalized), +Z -> right x up; scale then translate."""
    up, right = np.array([0.0, 0.0, 2.0]), np.array([1.0, 0.0, 1.0])  # right not orthogonal to up
    M = placement_matrix([1, 2, 3], [2, 3, 4], up, right)
    apply = lambda v: (M @ np.append(v, 1.0))[:3]
    np.testing.assert_allclose(apply([0, 0, 0]), [1, 2, 3])
    np.testing.assert_allclose(apply([0, 1, 0]), [1, 2, 3 + 3])        # sy * unit(up)
    np.testing.assert_allclose(apply([1, 0, 0]), [1 + 2, 2, 3])        # sx * right projected off up
    np.testing.assert_allclose(apply([0, 0, 1]), [1, 2 - 4, 3])        # sz * (right x up) = x cross z = -y
    axes = frame_axes(up, right)
    np.testing.assert_allclose(axes @ axes.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(axes) > 0


def test_extensions_groups_and_unknown_keys(write):
    pre = "0 0 0 1 1 1 0 1 0 1 0 0"
    s = read_scn(write("e.scn", (
        "#@ note: generated by hand\n#@ groupdef: 4 1 2 3 -1\n#@ groupdef: 5 0 0 0 4\n"
        f"rba: 1 {pre} 0 10\n#@ group: 5\n#@ emergence: 3.5\n#@ type: ray\n#@ wish: keep me\n"
        f"rba: 0 {pre} 2 10\n"
    )))
    a, b = s.placements
    assert (a.group, a.emergence, a.type, a.extra) == (5, 3.5, "ray", {"wish": "keep me"})
    assert b.group is None and b.emergence is None
    assert s.groups[5].parent == 4 and s.extra == [("note", "generated by hand")]
    arr = s.arrays()
    np.testing.assert_array_equal(arr["group"], [5, -1])
    np.testing.assert_array_equal(arr["group_centre"][0], [0, 0, 0])
    assert np.isnan(arr["group_centre"][1]).all() and np.isnan(arr["emergence"][1])


PRE = "0 0 0 1 1 1 0 1 0 1 0 0"


@pytest.mark.parametrize(
    "text, line, expected, found",
    [
        (f"o: 0 {PRE}\nxx: 0 {PRE}\n", 2, "a placement", "'xx: 0"),
        ("12 3 4\n", 1, "a placement", "'12 3 4'"),
        ("o: 0 0 0 0 1 1 1 0 1 0\n", 1, "13 values after 'o:'", "10 values"),
        (f"ca: 0 {PRE}\n", 1, "15 values after 'ca:'", "13 values"),
        (f"ca: 0 {PRE} 10 5\n", 1, "0 <= frameStart <= frameEnd", "10 5"),
        (f"ca: 0 {PRE} -1 5\n", 1, "0 <= frameStart", "-1 5"),
        (f"ca: 0 {PRE} 0 5.5\n", 1, "an integer frameEnd", "'5.5'"),
        (f"i: 0 {PRE} 1.5\n", 1, "an interpolation value in [0, 1]", "'1.5'"),
        (f"ra: 0 {PRE} 0 5 0 0 0 30\n", 1, "a non-zero rotation axis", "0 0 0"),
        (f"ta: 0 {PRE} 0 5 0 nan 0\n", 1, "a translation component (finite)", "'nan'"),
        ("o: x 0 0 0 1 1 1 0 1 0 1 0 0\n", 1, "an integer id", "'x'"),
        ("o: -2 0 0 0 1 1 1 0 1 0 1 0 0\n", 1, "a non-negative id", "'-2'"),
        ("o: 0 0 0 inf 1 1 1 0 1 0 1 0 0\n", 1, "(finite)", "'inf'"),
        ("o: 0 0 0 0 1 0 1 0 1 0 1 0 0\n", 1, "non-zero scale components", "1 0 1"),
        ("o: 0 0 0 0 1 1 1 0 0 0 1 0 0\n", 1, "a non-zero up vector", "0 0 0"),
        ("o: 0 0 0 0 1 1 1 0 1 0 0 0 0\n", 1, "a non-zero right vector", "0 0 0"),
        ("o: 0 0 0 0 1 1 1 0 1 0 0 -3 0\n", 1, "a right vector not parallel to up", "up 0 1 0 and right 0 -3 0"),
        ("mtl: 256\n", 1, "a material id in 0..255", "'256'"),
        ("mtl: 1 2\n", 1, "one material id", "2 values"),
        ("mtl: red\n", 1, "an integer material id", "'red'"),
        (f"o: 0 {PRE}\n#@ group: 3\n", 2, "a group declared by an earlier", "'3'"),
        ("#@ groupdef: 1 0 0 0 -1\n#@ groupdef: 1 0 0 0 -1\n", 2, "a new non-negative group id", "'1'"),
        ("#@ groupdef: 1 0 0 0 7\n", 1, "a parent group declared before", "'7'"),
        ("#@ groupdef: 1 0 0\n", 1, "'#@ groupdef: G cx cy cz parent'", "3 values"),
        (f"o: 0 {PRE}\n#@ emergence: -1\n", 2, "a non-negative emergence frame", "'-1'"),
        (f"o: 0 {PRE}\n#@ emergence: soon\n", 2, "an emergence frame", "'soon'"),
        (f"o: 0 {PRE}\n#@ type: big ray\n", 2, "'#@ type: label' (one word)", "'big ray'"),
        ("#@ nothing here\n", 1, "an extension line", "'#@ nothing here'"),
    ],
)
def test_scn_malformed(write, text, line, expected, found):
    p = write("bad.scn", text)
    with pytest.raises(FormatError) as err:
        read_scn(p)
    e = err.value
    assert e.line == line and expected in e.expected and found in e.found, str(e)


def scene_with(kinds):
    return Scene([Placement(k, 0, [0, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0],
                            frame_start=0 if k == "rba" else None, frame_end=9 if k == "rba" else None)
                  for k in kinds])


@settings(max_examples=40, deadline=None)
@given(rows=st.lists(frames(), max_size=8), data=st.data())
def test_rba_round_trip(tmp_path_factory, rows, data):
    ids = data.draw(st.permutations(range(len(rows))))
    fr = RbaFrame(ids, [r[0] for r in rows], [r[1] for r in rows], [r[2] for r in rows], [r[3] for r in rows])
    path = tmp_path_factory.mktemp("rba") / "0000.rba"
    write_rba(path, fr)
    back = read_rba(path, scene_with(["rba"] * len(rows)))
    for name in ("ids", "pos", "scale", "up", "right"):
        np.testing.assert_array_equal(getattr(fr, name), getattr(back, name))


def test_rba_fast_path_is_byte_identical_to_python(tmp_path):
    """write_rba's numba path (phyllotaxis's million-row frames) writes the Python path's bytes."""
    rng = np.random.default_rng(3)
    n = 400
    vals = rng.normal(size=(n, 12)) * rng.choice([1e-7, 1e-3, 1.0, 1e3, 1e6], size=(n, 12))
    vals[::5, 2] = rng.integers(-500, 500, size=len(vals[::5])) / 128.0  # exact ties of %.6f
    vals[::7, 4] = -0.0
    vals[::9, 5] = -4e-7
    vals[0, 0] = 3e13  # beyond the kernel's range: formatted by Python
    fr = RbaFrame(np.arange(n), vals[:, 0:3], vals[:, 3:6] + 10, vals[:, 6:9], vals[:, 9:12])
    write_rba(tmp_path / "ref.rba", fr, fast=False)
    got = rba_bytes(fr.ids, fr.pos, fr.scale, fr.up, fr.right).decode("ascii")
    assert got == (tmp_path / "ref.rba").read_text()
    assert got.splitlines()[1] == format_preamble(1, fr.pos[1], fr.scale[1], fr.up[1], fr.right[1])
    write_rba(tmp_path / "fast.rba", fr, header="two\nlines", fast=True)
    write_rba(tmp_path / "slow.rba", fr, header="two\nlines", fast=False)
    assert (tmp_path / "fast.rba").read_bytes() == (tmp_path / "slow.rba").read_bytes()
    # rows the kernel does not take (NaN, inf, a negative id) go to Python, the rest stay its own
    odd = RbaFrame([5, -1, 7], [[np.nan, 0, 1], [0, 0, 0], [np.inf, -np.inf, 2]], np.ones((3, 3)),
                   [[0, 1, 0]] * 3, [[1, 0, 0]] * 3)
    write_rba(tmp_path / "odd_slow.rba", odd, fast=False)
    write_rba(tmp_path / "odd_fast.rba", odd, fast=True)
    assert (tmp_path / "odd_fast.rba").read_bytes() == (tmp_path / "odd_slow.rba").read_bytes()
    big = RbaFrame(np.arange(1000), rng.normal(size=(1000, 3)), np.ones((1000, 3)), [[0, 1, 0]] * 1000,
                   [[1, 0, 0]] * 1000)
    write_rba(tmp_path / "big_auto.rba", big)  # 1000 rows: the fast path by default
    write_rba(tmp_path / "big_slow.rba", big, fast=False)
    assert (tmp_path / "big_auto.rba").read_bytes() == (tmp_path / "big_slow.rba").read_bytes()
    with pytest.raises(ValueError, match="fast RBA path"):
        write_rba(tmp_path / "x.rba", fr, fmt="%.3f", fast=True)
    with pytest.raises(ValueError, match="repeated ids"):
        write_rba(tmp_path / "x.rba", RbaFrame([1, 1], np.zeros((2, 3)), np.ones((2, 3)), [[0, 1, 0]] * 2,
                                               [[1, 0, 0]] * 2), fast=True)


def test_rba_sequence_and_lookup(tmp_path):
    scene = scene_with(["rba", "rba", "o"])
    f0 = RbaFrame([0], [[0, 0, 0]], [[1, 1, 1]], [[0, 1, 0]], [[1, 0, 0]])
    f1 = RbaFrame([0, 1], [[0, 1, 0], [2, 0, 0]], [[1, 1, 1], [2, 2, 2]], [[0, 1, 0]] * 2, [[1, 0, 0]] * 2)
    paths = write_rba_sequence(tmp_path / "rba", [f0, f1])
    assert [p.name for p in paths] == ["0000.rba", "0001.rba"]
    got_paths, got = read_rba_sequence(tmp_path / "rba", scene)
    assert got_paths == paths and got[1].index(1) == 1 and got[0].index(1) is None
    np.testing.assert_allclose(got[1].matrix(1) @ [0, 1, 0, 1], [2, 2, 0, 1])
    assert no_partial_files(tmp_path)


@pytest.mark.parametrize(
    "text, line, expected, found",
    [
        ("0 0 0 0 1 1 1 0 1 0 1 0\n", 1, "13 values", "12 values"),
        (f"0 {PRE}\n0 {PRE}\n", 2, "each id once (id 0 is on line 1)", "'0'"),
        (f"5 {PRE}\n", 1, "an id of the scene's placements (0..2)", "'5'"),
        (f"2 {PRE}\n", 1, "the id of an 'rba:' placement", "2, a 'o:' placement"),
        ("# frame 3\n1 0 0 0 1 1 1 0 1 0 0 1 0\n", 2, "a right vector not parallel to up", "up"),
        ("1 0 0 0 1 1 1 0 1 0 1 0 nan\n", 1, "(finite)", "'nan'"),
    ],
)
def test_rba_malformed(write, text, line, expected, found):
    p = write("0003.rba", text)
    with pytest.raises(FormatError) as err:
        read_rba(p, scene_with(["rba", "rba", "o"]))
    e = err.value
    assert e.line == line and expected in e.expected and found in e.found, str(e)


def test_rba_fast_reader_equals_the_line_reader(tmp_path, monkeypatch):
    """read_rba parses well-formed frames at once (numpy) and falls back to the line-by-line reader
    otherwise: the same frame for good files, the same one-line error for bad ones."""
    import inflo.formats.rba as rba_mod
    from inflo.formats.errors import FormatError
    from inflo.formats.scn import Placement, Scene

    rng = np.random.default_rng(5)
    n = 40
    good = [f"{k} " + " ".join(f"{v:.6f}" for v in np.concatenate([rng.normal(size=3), rng.uniform(0.1, 2, 3),
                                                                    [0, 1, 0], [1, 0, 0]]))
            for k in range(n)]
    scene = Scene(placements=[Placement("rba" if k != 7 else "o", 0, [0, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0],
                                        frame_start=0, frame_end=1) if k != 7 else
                              Placement("o", 0, [0, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0]) for k in range(n)])
    variants = {
        "good": good, "comments": ["# header", ""] + good[:5] + ["  # c"],
        "short": good[:3] + [" ".join(good[3].split()[:-1])], "nan": good[:2] + [good[2].replace(good[2].split()[1], "nan")],
        "zero_scale": good[:1] + [" ".join(good[1].split()[:4] + ["0"] + good[1].split()[5:])],
        "parallel": good[:1] + [" ".join(good[1].split()[:10] + ["0", "2", "0"])],
        "repeat": good[:3] + [good[1]], "neg_id": ["-1" + good[0][1:]], "float_id": ["1.0" + good[1][1:]],
        "word": good[:1] + [good[1].replace(good[1].split()[2], "abc")], "exp": [good[0].replace(" 1.000000 ", " 1e0 ", 1)],
        "underscore": [good[0].replace(good[0].split()[1], "1_0")], "empty": [],
    }
    for name, rows in variants.items():
        for sc in (None, scene):
            p = tmp_path / f"{name}.rba"
            p.write_text("\n".join(rows) + "\n")
            results = []
            for fast in (True, False):
                if not fast:
                    monkeypatch.setattr(rba_mod, "_read_rba_fast", lambda lines, scene: None)
                try:
                    results.append(read_rba(p, sc))
                except FormatError as exc:
                    results.append(str(exc))
                monkeypatch.undo()
            a, b = results
            if isinstance(a, str) or isinstance(b, str):
                assert a == b, (name, a, b)
            else:
                assert a.ids.tolist() == b.ids.tolist() and a.ids.dtype == b.ids.dtype
                for f in ("pos", "scale", "up", "right"):
                    np.testing.assert_array_equal(getattr(a, f), getattr(b, f))


def test_tiny_nonzero_scale_survives_writing(tmp_path):
    """A valid scale of 4e-7 (or an up vector of 1e-8 components) is not written as 0, which the
    readers refuse; other numbers keep the fixed format."""
    from inflo.formats.scn import Placement, Scene, read_scn, write_scn

    sc = Scene(placements=[Placement("o", 0, [1e-7, 0, 0], [4e-7, 1.0, 3e-7], [1e-8, 2e-8, 0], [1, 0, 0])])
    write_scn(tmp_path / "t.scn", sc)
    text = (tmp_path / "t.scn").read_text()
    assert "0.000000 4.000000e-07 1.000000 3.000000e-07 1.000000e-08 2.000000e-08 0.000000 1.000000" in text
    back = read_scn(tmp_path / "t.scn").placements[0]
    assert np.allclose(back.scale, [4e-7, 1.0, 3e-7], rtol=1e-6) and back.pos[0] == 0.0
    n = 1200  # the fast path's size: rows with such values go to Python, byte-identical
    fr = RbaFrame(np.arange(n), np.zeros((n, 3)), np.full((n, 3), 1.0), np.tile([0.0, 1, 0], (n, 1)),
                  np.tile([1.0, 0, 0], (n, 1)))
    fr.scale[7] = [4e-7, 1, 1]
    fr.up[9] = [0, 5e-7, 0]
    fr.up[11] = [5e-7, 0.5, 0]  # a vector that prints non-zero keeps the fixed format
    write_rba(tmp_path / "fast.rba", fr, fast=True)
    write_rba(tmp_path / "slow.rba", fr, fast=False)
    assert (tmp_path / "fast.rba").read_bytes() == (tmp_path / "slow.rba").read_bytes()
    back = read_rba(tmp_path / "fast.rba")
    assert back.scale[7, 0] == pytest.approx(4e-7) and back.up[9, 1] == pytest.approx(5e-7)
    assert (tmp_path / "fast.rba").read_text().splitlines()[11].split()[7:10] == ["0.000000", "0.500000", "0.000000"]
