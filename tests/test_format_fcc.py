"""Canopy composer parameter file (.fcc, thesis app. C.1): reader, writer, reference check."""
from __future__ import annotations

import dataclasses
import re
import tempfile
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from inflo.formats import fcc as fcc_module
from inflo.formats.errors import FormatError, InputError
from inflo.formats.fcc import (
    ALIASES,
    KEYS,
    KNOWN_KEYS,
    AnimationEntry,
    CameraParams,
    CanopyParams,
    FilePath,
    LatticeParams,
    MissingReferenceError,
    RigidBodyAnimationEntry,
    check_references,
    format_fcc,
    read_fcc,
    write_fcc,
)
from inflo.formats.variation import Variation

SPEC = Path(__file__).resolve().parent.parent / "formats" / "fcc.md"


def spec_example() -> str:
    """The reconstructed thesis example, read out of formats/fcc.md (the first code block)."""
    blocks = re.findall(r"```\n(.*?)```", SPEC.read_text(), re.S)
    assert blocks, "formats/fcc.md has no example block"
    return blocks[0]


# ----------------------------------------------------------------------------------------------
# The thesis example
# ----------------------------------------------------------------------------------------------


def test_thesis_example_parses(write, tmp_path):
    p = read_fcc(write("lily.fcc", spec_example()))
    assert p.solver_iterations == 50
    assert p.collision_iterations == 10  # spelled "collision iterations" in the example
    assert p.max_collision_retries == 20
    assert (p.k_stretch, p.k_bend, p.k_collision) == (0.99, 0.99, 1.0)  # "0.99f", "1.f"
    assert p.spacing == 0.005
    assert p.updates_per_frame == 1
    assert p.run_frames == 1
    assert p.sanity_check_every == 50
    assert [f.raw for f in p.scene_files] == ["./Scenes/s1.sce"]
    assert p.scene_files[0].resolved == tmp_path / "Scenes" / "s1.sce"
    assert [(e.id, e.scale, e.path.raw, e.kind) for e in p.animations] == [
        (0, (1.0, 1.0, 1.0), "./lilyAnimation/", "animation"),
        (1, (2.0, 2.0, 2.0), "./daisyAnimation/", "animation"),
        (2, (0.5, 1.0, 0.5), "./singleRose.obj", "obj"),
    ]
    assert p.lattice == LatticeParams(
        size_multiply=(1.5, 1.5, 1.5),
        make_cube=False,
        origin=(-5, -5, -5),
        divisions=(100, 100, 100),
        dimensions=(10, 10, 10),
        auto_bounds=True,
    )
    assert p.color_map.raw == "./Color/colormap.map"
    assert p.material_map.resolved == tmp_path / "Material" / "material.mat"
    assert p.camera.light_position == (-10.0, 10.0, 10.0)
    assert p.camera.shadow_frustum == (-1.0, 1.0, -1.0, 1.0, -10.0, 10.0)
    assert p.camera.position == (0.0, 0.0, -1.0)
    assert p.camera.up == (0.0, 1.0, 0.0)
    assert p.camera.lookat == (0.0, 0.0, 0.0)
    assert p.lines["kStretch"] == 5
    assert p.animations[1].line == 19


# ----------------------------------------------------------------------------------------------
# Every key
# ----------------------------------------------------------------------------------------------

EVERY_KEY = """\
solver iterations: 7
collision solver iterations: 3
max collision retries: 4
kStretch: 0.5
kBend: 0.25
kCollision: 0.75
spacing: 0.01
scene scale factor: 1, 2, 3
updates per frame: 2
run for number of frames: 120
sanity check per frames: 10
max substeps: 2
edge stretch bounds: 0.6 1.4
relax iterations: 3
emergence scales: 1 0.5 0.2
emergence growth frames: 4.5
crowded scales: 0.9 0.6
output animation frames number: 5
output animation obj per frames: 4
lattice size multiply: 1.1, 1.2, 1.3
lattice make cube: true
origin: -1, -2, -3
divisions: 10, 20, 30
dimensions: 2, 4, 6
lattice auto bounds: false
color map file location: maps/colour.map
material map file location: maps/material.mat
scene file path: head1.scn
scene file path: head2.scn
animation: 0 1 1 1 disk/
obj: 1 0.5 0.5 0.5 ray.obj
rigid body animation: 2 1 1 1 rba/ heads.scn
weight: 0 disk.weights
petal weight: 1 ray.petals
petal ramp: 1 0.25 0.75
bending stiffness: 1 0.3
distance stiffness: 0 0.9
variation: 0 size 0.1 droop 8 seed 3
animation output folder location: out/
obj output file path: out/frame.obj
camera position: 0, 1, 5
camera up: 0, 0, 1
camera lookat: 0, 1, 0
camera pan speed: 0.1
camera zoom speed: 0.2
camera rotate speed: 0.3
near plane: 0.01
far plane: 100
camera fov: 30
light position: 4, 5, 6
shadow frustrum: -2, 2, -3, 3, -4, 4
collisions: off
solver scheme: fast
"""


def spec_key_rows() -> dict[str, list[str]]:
    """The rows of the key tables of formats/fcc.md ("## Keys"): key -> value, default, meaning."""
    section = SPEC.read_text().split("\n## Keys\n", 1)[1].split("\n## ", 1)[0]
    rows = {}
    for line in section.splitlines():
        m = re.match(r"^\| `([^`]+)` \|(.*)\|$", line)
        if m:
            assert m.group(1) not in rows, f"{m.group(1)} twice in the spec's tables"
            rows[m.group(1)] = [c.strip() for c in m.group(2).split("|")]
    return rows


def test_key_table_matches_the_spec_tables():
    """Every key of the reader's table (KEYS, formats/fcc.py) is in the spec's tables and vice
    versa, each with the spec's "value" column (count, type, range, repeatable) and its aliases."""
    rows = spec_key_rows()
    assert set(rows) == set(KEYS), (sorted(set(KEYS) - set(rows)), sorted(set(rows) - set(KEYS)))
    for key, spec in KEYS.items():
        assert rows[key][0] == spec.spec_value(), key
        assert spec.check == "" or spec.check in fcc_module._CHECKS, key
        assert spec.kind in fcc_module._READ, key
    for alias, key in ALIASES.items():
        assert f"Alias: `{alias}`" in rows[key][2], alias


def test_every_key_of_the_list(write, tmp_path):
    keys_in_text = {line.split(":")[0] for line in EVERY_KEY.splitlines()}
    assert keys_in_text == set(KNOWN_KEYS)  # the fixture covers the whole documented list
    p = read_fcc(write("all.fcc", EVERY_KEY))
    assert p == CanopyParams(
        solver_iterations=7,
        collision_iterations=3,
        max_collision_retries=4,
        k_stretch=0.5,
        k_bend=0.25,
        k_collision=0.75,
        spacing=0.01,
        scene_scale=(1, 2, 3),
        updates_per_frame=2,
        run_frames=120,
        sanity_check_every=10,
        max_substeps=2,
        stretch_bounds=(0.6, 1.4),
        solver_scheme="fast",
        relax_iterations=3,
        collisions=False,
        emergence_scales=(1, 0.5, 0.2),
        emergence_growth_frames=4.5,
        crowded_scales=(0.9, 0.6),
        output_frames_number=5,
        output_obj_skip=4,
        lattice=LatticeParams((1.1, 1.2, 1.3), True, (-1, -2, -3), (10, 20, 30), (2, 4, 6), False),
        color_map=FilePath("maps/colour.map"),
        material_map=FilePath("maps/material.mat"),
        scene_files=(FilePath("head1.scn"), FilePath("head2.scn")),
        animations=(
            AnimationEntry(0, (1, 1, 1), FilePath("disk/"), "animation"),
            AnimationEntry(1, (0.5, 0.5, 0.5), FilePath("ray.obj"), "obj"),
        ),
        rigid_body_animations=(
            RigidBodyAnimationEntry(2, (1, 1, 1), FilePath("rba/"), FilePath("heads.scn")),
        ),
        weights={0: FilePath("disk.weights")},
        petal_weights={1: FilePath("ray.petals")},
        petal_ramps={1: (0.25, 0.75)},
        bending_stiffness={1: 0.3},
        distance_stiffness={0: 0.9},
        variations={0: Variation(size=0.1, droop=8.0, seed=3)},
        animation_output_folder=FilePath("out/"),
        obj_output_file=FilePath("out/frame.obj"),
        camera=CameraParams(
            position=(0, 1, 5),
            up=(0, 0, 1),
            lookat=(0, 1, 0),
            pan_speed=0.1,
            zoom_speed=0.2,
            rotate_speed=0.3,
            near=0.01,
            far=100,
            fov_deg=30,
            light_position=(4, 5, 6),
            shadow_frustum=(-2, 2, -3, 3, -4, 4),
        ),
    )
    assert p.output_every == 5
    assert p.stiffness(0) == (0.9, 0.25)  # own distance stiffness, global kBend
    assert p.stiffness(1) == (0.5, 0.3)
    assert p.entry(2).rba_folder.resolved == tmp_path / "rba"
    assert p.entry(99) is None
    assert p.weights[0].line == 33


def test_defaults_of_an_empty_file(write):
    p = read_fcc(write("empty.fcc", "# nothing but a comment\n\n"))
    assert p == CanopyParams()
    assert (p.solver_iterations, p.collision_iterations, p.max_collision_retries) == (50, 10, 20)
    assert (p.k_stretch, p.k_bend, p.k_collision, p.spacing) == (0.99, 0.99, 1.0, 0.005)
    assert p.updates_per_frame == 1 and p.run_frames is None and p.sanity_check_every == 50
    assert p.output_every == 1
    assert p.lattice.auto_bounds is True and p.lattice.divisions == (100, 100, 100)
    assert p.camera.position is None and p.camera.up == (0.0, 1.0, 0.0)
    assert p.camera.fov_deg == 45.0
    assert p.scene_files == () and p.animations == () and dict(p.weights) == {}


def test_aliases_and_key_spelling(write):
    text = "Collision  Iterations: 3\nKSTRETCH: 0.5\nshadow frustum: 1 2 3 4 5 6\n"
    p = read_fcc(write("a.fcc", text))
    assert p.collision_iterations == 3 and p.k_stretch == 0.5
    assert p.camera.shadow_frustum == (1, 2, 3, 4, 5, 6)


# ----------------------------------------------------------------------------------------------
# Values
# ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "value", ["-5, -5, -5", "-5 -5 -5", "-5,-5,-5", "-5 ,  -5\t-5", "-5.f, -5f, -5.0F"]
)
def test_commas_and_blanks_separate_values(write, value):
    assert read_fcc(write("o.fcc", f"origin: {value}\n")).lattice.origin == (-5.0, -5.0, -5.0)


@pytest.mark.parametrize(
    "token, value", [("0.99f", 0.99), ("1.f", 1.0), ("1f", 1.0), (".5F", 0.5), ("1e-1f", 0.1)]
)
def test_c_float_suffix(write, token, value):
    assert read_fcc(write("k.fcc", f"kBend: {token}\n")).k_bend == value


def test_divisions_one_value_means_all_three(write):
    assert read_fcc(write("d.fcc", "divisions: 64\n")).lattice.divisions == (64, 64, 64)


@pytest.mark.parametrize(
    "text, value",
    [(t, True) for t in ("true", "TRUE", "1", "yes", "on")]
    + [(t, False) for t in ("false", "False", "0", "no", "off")],
)
def test_booleans(write, text, value):
    assert read_fcc(write("b.fcc", f"lattice make cube: {text}\n")).lattice.make_cube is value


def test_comments_crlf_and_bom(write, tmp_path):
    path = tmp_path / "c.fcc"
    path.write_bytes("\ufeffkBend: 0.5  # trailing comment\r\n# whole line\r\n\r\nspacing: 0\r\n"
                     .encode())
    p = read_fcc(path)
    assert p.k_bend == 0.5 and p.spacing == 0.0


def test_paths_resolve_against_the_fcc_folder(write, tmp_path):
    text = ("scene file path: ../scenes/a.scn\nanimation: 0 1 1 1 ./my frames/\n"
            "obj: 1 1 1 1 /abs/rose.obj\n")
    p = read_fcc(write("sub/p.fcc", text))
    assert p.scene_files[0].raw == "../scenes/a.scn"
    assert p.scene_files[0].resolved == tmp_path / "scenes" / "a.scn"
    assert p.animations[0].path.raw == "./my frames/"  # blanks kept in the last field
    assert p.animations[0].path.resolved == tmp_path / "sub" / "my frames"
    assert p.animations[1].path.resolved == Path("/abs/rose.obj")


def test_repeatable_keys_accumulate(write):
    text = ("scene file path: a.scn\nanimation: 3 1 1 1 a/\n"
            "scene file path: b.scn\nobj: 5 1 1 1 b.obj\n")
    p = read_fcc(write("r.fcc", text))
    assert [f.raw for f in p.scene_files] == ["a.scn", "b.scn"]
    assert [e.id for e in p.animations] == [3, 5]


def test_output_period(write):
    assert read_fcc(write("o1.fcc", "output animation obj per frames: 3\n")).output_every == 4
    assert read_fcc(write("o2.fcc", "output animation frames number: 2\n")).output_every == 2
    both = "output animation frames number: 4\noutput animation obj per frames: 3\n"
    assert read_fcc(write("o3.fcc", both)).output_every == 4


# ----------------------------------------------------------------------------------------------
# Malformed input: every error path, with its line
# ----------------------------------------------------------------------------------------------

MALFORMED = [
    # (text, line, expected fragment)
    ("kStrech: 0.9\n", 1, "did you mean 'kStretch'?"),
    ("spacing: 0.1\nsolver iteration: 5\n", 2, "did you mean 'solver iterations'?"),
    ("colision iterations: 5\n", 1, "did you mean 'collision iterations'?"),
    ("zzzz: 1\n", 1, "a known key (see formats/fcc.md)"),
    ("kBend 0.5\n", 1, "'key: value'"),
    (": 0.5\n", 1, "a key before ':'"),
    ("kBend: 0.5\n\nkBend: 0.6\n", 3, "already set on line 1"),
    ("collision iterations: 1\ncollision solver iterations: 2\n", 2, "already set on line 1"),
    ("kBend:\n", 1, "1 stiffness in [0, 1]"),
    ("kBend: 0.5 0.6\n", 1, "1 stiffness in [0, 1]"),
    ("kBend: 1.5\n", 1, "a stiffness in [0, 1]"),
    ("kStretch: -0.1\n", 1, "a stiffness in [0, 1]"),
    ("kCollision: nan\n", 1, "(finite)"),
    ("kBend: abc\n", 1, "a stiffness in [0, 1]"),
    ("spacing: -0.005\n", 1, "a number >= 0"),
    ("spacing: inf\n", 1, "(finite)"),
    ("solver iterations: -1\n", 1, "an integer >= 0"),
    ("solver iterations: 5.0\n", 1, "an integer for 'solver iterations'"),
    ("solver iterations: 5f\n", 1, "an integer for 'solver iterations'"),
    ("updates per frame: 0\n", 1, "an integer >= 1"),
    # counts beyond what a run could finish (1e11 hung, 1e23 overflowed a kernel)
    ("solver iterations: 100000000000000000000000\n", 1, "an integer in [0, 10000]"),
    ("collision iterations: 99999999999\n", 1, "an integer in [0, 10000]"),
    ("updates per frame: 1000000000\n", 1, "an integer in [1, 1000]"),
    ("max substeps: 40\n", 1, "an integer in [0, 16]"),
    ("output animation frames number: 1000000\n", 1, "an integer in [1, 100000]"),
    ("edge stretch bounds: 1.2 1.5\n", 1, "two numbers lo <= 1 <= hi"),
    ("emergence scales: 1 0.5 0.7\n", 1, "decreasing numbers"),
    ("emergence scales: 1.5\n", 1, "numbers in (0, 1]"),
    ("emergence growth frames: 0\n", 1, "a number > 0"),
    ("crowded scales: 0.5 0.8\n", 1, "decreasing numbers"),
    ("crowded scales: 0\n", 1, "numbers in (0, 1]"),
    ("run for number of frames: -3\n", 1, "an integer >= 0"),
    ("sanity check per frames: x\n", 1, "an integer"),
    ("output animation frames number: 0\n", 1, "an integer >= 1"),
    ("output animation obj per frames: -1\n", 1, "an integer >= 0"),
    ("output animation frames number: 2\noutput animation obj per frames: 3\n", 2, "+ 1"),
    ("scene scale factor: 1, 1\n", 1, "3 numbers (> 0)"),
    ("scene scale factor: 1, 0, 1\n", 1, "a number > 0"),
    ("light position: -10, 10, \n", 1, "3 numbers"),  # the thesis example's lost character
    ("lattice size multiply: 1 1 -1\n", 1, "a number > 0"),
    ("lattice make cube: maybe\n", 1, "true or false"),
    ("lattice auto bounds: true false\n", 1, "true or false"),
    ("origin: 1 2 3 4\n", 1, "3 numbers"),
    ("divisions: 10 10\n", 1, "1 or 3 integers"),
    ("divisions: 0\n", 1, "an integer >= 1"),
    ("divisions: 10 10 2.5\n", 1, "an integer for 'divisions'"),
    ("dimensions: 10 10 0\n", 1, "a number > 0"),
    ("color map file location:\n", 1, "a path"),
    ("scene file path:   \n", 1, "a path"),
    ("animation: 0 1 1 1\n", 1, "id x y z path"),
    ("animation: x 1 1 1 a/\n", 1, "an integer for 'animation'"),
    ("animation: -1 1 1 1 a/\n", 1, "an integer >= 0"),
    ("obj: 0 1 nan 1 a.obj\n", 1, "(finite)"),
    ("obj: 0 1 0 1 a.obj\n", 1, "a number > 0"),
    ("rigid body animation: 0 1 1 1 rba/\n", 1, "6 values"),
    ("rigid body animation: 0 1 1 1 rba/ a.scn extra\n", 1, "6 values"),
    ("animation: 4 1 1 1 a/\n\nobj: 4 1 1 1 b.obj\n", 3,
     "id 4 already names the 'animation' entry on line 1"),
    ("obj: 4 1 1 1 b.obj\nrigid body animation: 4 1 1 1 r/ s.scn\n", 2,
     "id 4 already names the 'obj' entry on line 1"),
    ("weight: 0\n", 1, "'weight: id path'"),
    ("obj: 0 1 1 1 a.obj\nweight: 0 a.w\nweight: 0 b.w\n", 3, "already has one on line 2"),
    ("weight: 7 a.w\n", 1, "the id of an 'animation' or 'obj' entry"),
    ("rigid body animation: 7 1 1 1 r/ s.scn\nweight: 7 a.w\n", 2, "'animation' or 'obj'"),
    ("bending stiffness: 0\n", 1, "an id and a stiffness"),
    ("obj: 0 1 1 1 a.obj\nbending stiffness: 0 1.2\n", 2, "a stiffness in [0, 1]"),
    ("obj: 0 1 1 1 a.obj\ndistance stiffness: 0 -0.5\n", 2, "a stiffness in [0, 1]"),
    ("obj: 0 1 1 1 a.obj\ndistance stiffness: 0 0.5\ndistance stiffness: 0 0.6\n", 3,
     "already has one on line 2"),
    ("distance stiffness: 3 0.5\n", 1, "'animation' or 'obj'"),
    ("camera up: 0 0 0\n", 1, "a non-zero up vector"),
    ("camera position: 0 0\n", 1, "3 numbers"),
    ("camera pan speed: -1\n", 1, "a number >= 0"),
    ("near plane: 0\n", 1, "a number > 0"),
    ("far plane: 1\nnear plane: 2\n", 2, "far plane > near plane"),
    ("camera fov: 180\n", 1, "a field of view in (0, 180)"),
    ("camera fov: 0\n", 1, "a field of view in (0, 180)"),
    ("shadow frustrum: -1, 1, -1, 1, -10,\n", 1, "6 numbers"),
]


@pytest.mark.parametrize("text, line, expected", MALFORMED)
def test_malformed_input_names_file_line_and_expectation(write, text, line, expected):
    path = write("bad.fcc", text)
    with pytest.raises(FormatError) as info:
        read_fcc(path)
    err = info.value
    assert err.line == line
    assert expected in err.expected, err.expected
    assert str(err).startswith(f"{path}:{line}: expected ")


def test_unknown_key_message_reads_well(write):
    path = write("u.fcc", "kStrech: 0.9\n")
    with pytest.raises(FormatError) as info:
        read_fcc(path)
    assert str(info.value) == (
        f"{path}:1: expected a known key (did you mean 'kStretch'?), found 'kStrech'"
    )


def test_missing_and_binary_files(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_fcc(tmp_path / "nope.fcc")
    (tmp_path / "bin.fcc").write_bytes(b"kBend: 0.5\n\xff\xfe")
    with pytest.raises(FormatError) as info:
        read_fcc(tmp_path / "bin.fcc")
    assert info.value.line == 2


# ----------------------------------------------------------------------------------------------
# References
# ----------------------------------------------------------------------------------------------

REFS = """\
scene file path: s.scn
animation: 0 1 1 1 frames/
animation: 1 1 1 1 seq/frame_*.obj
obj: 2 1 1 1 rose.obj
rigid body animation: 3 1 1 1 rba/ heads.scn
weight: 0 w.txt
color map file location: c.map
material map file location: m.mat
animation output folder location: not-yet/
"""


def _make_refs(root: Path):
    for name in ("s.scn", "rose.obj", "heads.scn", "w.txt", "c.map", "m.mat", "seq/frame_0000.obj"):
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text("")
    (root / "frames").mkdir()
    (root / "rba").mkdir()


def test_check_references_passes_when_everything_exists(write, tmp_path):
    _make_refs(tmp_path)
    check_references(read_fcc(write("p.fcc", REFS)))  # output folder is not required to exist


def test_check_references_lists_missing_paths_with_lines(write, tmp_path):
    _make_refs(tmp_path)
    (tmp_path / "rose.obj").unlink()
    (tmp_path / "rba").rmdir()
    (tmp_path / "seq" / "frame_0000.obj").unlink()
    path = write("p.fcc", REFS)
    params = read_fcc(path)
    with pytest.raises(MissingReferenceError) as info:
        check_references(params)
    err = info.value
    assert isinstance(err, InputError)
    assert [(line, key) for line, key, _, _ in err.missing] == [
        (3, "animation"),
        (4, "obj"),
        (5, "rigid body animation"),
    ]
    msg = str(err)
    assert msg.startswith(f"{path}:3: 'animation' names 'seq/frame_*.obj'")
    assert "rose.obj" in msg and "and 2 more" in msg


def test_check_references_obj_must_be_a_file(write, tmp_path):
    (tmp_path / "rose.obj").mkdir()
    with pytest.raises(MissingReferenceError, match=r":1: 'obj' names 'rose.obj'.*no such file"):
        check_references(read_fcc(write("p.fcc", "obj: 0 1 1 1 rose.obj\n")))


# ----------------------------------------------------------------------------------------------
# Writing
# ----------------------------------------------------------------------------------------------


def test_write_example_is_stable(write, tmp_path):
    p = read_fcc(write("lily.fcc", spec_example()))
    write_fcc(tmp_path / "again.fcc", p)
    text = (tmp_path / "again.fcc").read_text()
    assert "collision solver iterations: 10\n" in text
    assert "kCollision: 1.0\n" in text
    assert "# near plane: automatic\n" in text
    assert "origin: -5.0, -5.0, -5.0\n" in text
    q = read_fcc(tmp_path / "again.fcc")
    assert q == p
    assert format_fcc(q) == text
    assert not list(tmp_path.glob(".*.part"))


def test_writer_refuses_what_it_cannot_read_back(tmp_path):
    bad = CanopyParams(scene_files=(FilePath("a#b.scn"),))
    with pytest.raises(ValueError, match="cannot write path"):
        write_fcc(tmp_path / "x.fcc", bad)
    bad = CanopyParams(rigid_body_animations=(
        RigidBodyAnimationEntry(0, (1, 1, 1), FilePath("my rba/"), FilePath("s.scn")),))
    with pytest.raises(ValueError, match="spaces or commas"):
        write_fcc(tmp_path / "x.fcc", bad)
    with pytest.raises(ValueError, match="non-finite"):
        write_fcc(tmp_path / "x.fcc", CanopyParams(spacing=float("nan")))
    assert not (tmp_path / "x.fcc").exists()


def test_entry_kind_is_checked():
    with pytest.raises(ValueError, match="'animation' or 'obj'"):
        AnimationEntry(0, (1, 1, 1), FilePath("a"), "mesh")


# ----------------------------------------------------------------------------------------------
# Round trip (hypothesis): numbers with at most 6 decimals so equality is exact
# ----------------------------------------------------------------------------------------------

d6 = st.integers(-10**9, 10**9).map(lambda i: i / 1e6)
pos6 = st.integers(1, 10**9).map(lambda i: i / 1e6)
unit6 = st.integers(0, 10**6).map(lambda i: i / 1e6)
nonneg6 = st.integers(0, 10**9).map(lambda i: i / 1e6)
count = st.integers(0, 10**6)
iters = st.integers(0, 10**4)  # the counts' ranges (formats/fcc.md)
frames = st.integers(0, 10**5)
vec3 = st.tuples(d6, d6, d6)
pos3 = st.tuples(pos6, pos6, pos6)
raw_path = st.from_regex(r"(\./|\.\./)?[a-z][a-z0-9_]{0,5}(/[a-z0-9_]{1,5}){0,2}(\.[a-z]{3})?/?",
                         fullmatch=True).map(FilePath)
spaced_path = st.from_regex(r"[a-z][a-z0-9 _]{0,8}[a-z0-9]", fullmatch=True).map(FilePath)


@st.composite
def canopy_params(draw):
    ids = draw(st.lists(st.integers(0, 10**4), unique=True, max_size=6))
    n_rba = draw(st.integers(0, len(ids)))
    anim_ids, rba_ids = ids[n_rba:], ids[:n_rba]
    animations = tuple(
        AnimationEntry(i, draw(pos3), draw(st.one_of(raw_path, spaced_path)),
                       draw(st.sampled_from(["animation", "obj"])))
        for i in anim_ids
    )
    rbas = tuple(RigidBodyAnimationEntry(i, draw(pos3), draw(raw_path), draw(raw_path))
                 for i in rba_ids)
    some_ids = st.lists(st.sampled_from(anim_ids), unique=True) if anim_ids else st.just([])
    opt = lambda s: st.none() | s
    up = draw(vec3.filter(any))
    near = draw(opt(pos6))
    far = draw(opt(pos6))
    if near is not None and far is not None and not far > near:
        far = near + 1.0
    frames_number = draw(opt(st.integers(1, 10**5)))
    skip = draw(opt(frames))
    if frames_number is not None and skip is not None:
        skip = frames_number - 1
    return CanopyParams(
        solver_iterations=draw(iters),
        collision_iterations=draw(iters),
        max_collision_retries=draw(st.integers(0, 1000)),
        k_stretch=draw(unit6),
        k_bend=draw(unit6),
        k_collision=draw(unit6),
        spacing=draw(nonneg6),
        scene_scale=draw(pos3),
        updates_per_frame=draw(st.integers(1, 1000)),
        run_frames=draw(opt(frames)),
        sanity_check_every=draw(frames),
        output_frames_number=frames_number,
        output_obj_skip=skip,
        lattice=LatticeParams(draw(pos3), draw(st.booleans()), draw(vec3),
                              draw(st.tuples(*[st.integers(1, 4096)] * 3)), draw(pos3),
                              draw(st.booleans())),
        color_map=draw(opt(raw_path)),
        material_map=draw(opt(raw_path)),
        scene_files=tuple(draw(st.lists(st.one_of(raw_path, spaced_path), max_size=3))),
        animations=animations,
        rigid_body_animations=rbas,
        weights={i: draw(raw_path) for i in draw(some_ids)},
        bending_stiffness={i: draw(unit6) for i in draw(some_ids)},
        distance_stiffness={i: draw(unit6) for i in draw(some_ids)},
        animation_output_folder=draw(opt(raw_path)),
        obj_output_file=draw(opt(raw_path)),
        camera=CameraParams(
            position=draw(opt(vec3)),
            up=up,
            lookat=draw(opt(vec3)),
            pan_speed=draw(nonneg6),
            zoom_speed=draw(nonneg6),
            rotate_speed=draw(nonneg6),
            near=near,
            far=far,
            fov_deg=draw(st.integers(1, 179_999_999).map(lambda i: i / 1e6)),
            light_position=draw(opt(vec3)),
            shadow_frustum=draw(opt(st.tuples(*[d6] * 6))),
        ),
    )


@settings(max_examples=40, deadline=None)
@given(canopy_params())
def test_round_trip(params):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "p.fcc"
        write_fcc(path, params)
        first = path.read_bytes()
        back = read_fcc(path)
        assert back == params
        write_fcc(path, back)
        assert path.read_bytes() == first


def test_equality_ignores_resolution_and_lines():
    a = CanopyParams(scene_files=(FilePath.at("s.scn", "/one", line=3),))
    b = CanopyParams(scene_files=(FilePath.at("s.scn", "/two"),))
    assert a == b
    assert dataclasses.replace(a, spacing=0.1) != b
