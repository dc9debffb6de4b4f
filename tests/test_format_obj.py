"""OBJ reader/writer: order-preserving reads, round trips, sequences, malformed input."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh
from conftest import no_partial_files
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from inflo.formats.errors import FormatError, InputError
from inflo.formats.obj import ObjMesh, list_obj_sequence, read_obj, read_obj_sequence, write_obj, write_obj_sequence

SIX_DECIMALS = st.integers(-10**7, 10**7).map(lambda k: k / 1e6)


@st.composite
def meshes(draw):
    n = draw(st.integers(3, 30))
    v = draw(hnp.arrays(np.float64, (n, 3), elements=SIX_DECIMALS))
    m = draw(st.integers(0, 40))
    f = draw(hnp.arrays(np.int32, (m, 3), elements=st.integers(0, n - 1)))
    n_lines = draw(st.integers(0, 3))
    lines = [draw(hnp.arrays(np.int32, draw(st.integers(2, 6)), elements=st.integers(0, n - 1))) for _ in range(n_lines)]
    normals = draw(st.one_of(st.none(), hnp.arrays(np.float64, (n, 3), elements=SIX_DECIMALS)))
    colors = draw(st.one_of(st.none(), hnp.arrays(np.float64, (n, 3), elements=st.integers(0, 10**6).map(lambda k: k / 1e6))))
    groups = materials = []
    face_group = face_material = None
    if m and draw(st.booleans()):
        groups = ["floret_0", "floret_1"]
        face_group = np.sort(draw(hnp.arrays(np.int32, m, elements=st.integers(0, 1))))
        # a group listed first must be used first for the round trip to keep its index
        if face_group[0] == 1:
            face_group[:] = 0
        if 1 not in face_group:
            groups = ["floret_0"]
    if m and draw(st.booleans()):
        materials = ["mtl3"]
        face_material = np.zeros(m, np.int32)
    return ObjMesh(v, f, normals=normals, vertex_colors=colors, lines=lines, groups=groups,
                   face_group=face_group, materials=materials, face_material=face_material)


def assert_same(a: ObjMesh, b: ObjMesh):
    np.testing.assert_array_equal(a.vertices, b.vertices)
    np.testing.assert_array_equal(a.faces, b.faces)
    assert (a.normals is None) == (b.normals is None)
    if a.normals is not None:
        np.testing.assert_array_equal(a.normals, b.normals)
    assert (a.vertex_colors is None) == (b.vertex_colors is None)
    if a.vertex_colors is not None:
        np.testing.assert_array_equal(a.vertex_colors, b.vertex_colors)
    assert len(a.lines) == len(b.lines) and all(np.array_equal(x, y) for x, y in zip(a.lines, b.lines))
    assert a.groups == b.groups and a.materials == b.materials
    for x, y in ((a.face_group, b.face_group), (a.face_material, b.face_material)):
        assert (x is None) == (y is None)
        if x is not None:
            np.testing.assert_array_equal(x, y)


@settings(max_examples=60, deadline=None)
@given(mesh=meshes())
def test_round_trip(tmp_path_factory, mesh):
    path = tmp_path_factory.mktemp("obj") / "m.obj"
    write_obj(path, mesh)
    back = read_obj(path)
    assert_same(mesh, back)
    text = path.read_text()
    write_obj(path, back)
    assert path.read_text() == text  # stable text


def test_unused_and_duplicate_vertices_kept_in_order(write):
    p = write("a.obj", "v 1 0 0\nv 0 0 0\nv 0 0 0\nv 5 5 5\nv 0 1 0\nf 2 1 5\n")
    m = read_obj(p)
    assert m.n_vertices == 5  # the duplicate (3) and the unused (4) vertex stay
    np.testing.assert_array_equal(m.vertices[3], [5, 5, 5])
    np.testing.assert_array_equal(m.faces, [[1, 0, 4]])
    # trimesh's default load would merge/drop: our reader is the reference for vertex identity
    t = trimesh.load(p, process=True)
    assert len(t.vertices) < m.n_vertices


def test_matches_trimesh_order_preserving_load(tmp_path):
    mesh = trimesh.creation.icosphere(subdivisions=2)
    mesh.export(tmp_path / "ico.obj")
    ours = read_obj(tmp_path / "ico.obj")
    ref = trimesh.load(tmp_path / "ico.obj", process=False, maintain_order=True)
    np.testing.assert_allclose(ours.vertices, ref.vertices, atol=1e-7)
    np.testing.assert_array_equal(ours.faces, ref.faces)


def test_references_polygons_negative_and_slashes(write):
    text = (
        "# comment\nmtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n"
        "o petal\nusemtl mtl2\ns off\nf 1/1/1 2//1 3/1 4\nf -4 -3 -1\nl 1 2 3\n"
    )
    m = read_obj(write("p.obj", text))
    np.testing.assert_array_equal(m.faces, [[0, 1, 2], [0, 2, 3], [0, 1, 3]])
    assert m.groups == ["petal"] and m.materials == ["mtl2"]
    np.testing.assert_array_equal(m.face_group, [0, 0, 0])
    assert m.normals is None  # one vn for four vertices: not per-vertex
    np.testing.assert_array_equal(m.lines[0], [0, 1, 2])


def test_groups_and_materials_per_face(write):
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\ng a\nusemtl m1\nf 1 2 3\ng b\nf 1 2 3\nusemtl m2\nf 1 2 3\ng a\nf 1 2 3\n"
    m = read_obj(write("g.obj", text))
    np.testing.assert_array_equal(m.face_group, [-1, 0, 1, 1, 0])
    np.testing.assert_array_equal(m.face_material, [-1, 0, 0, 1, 1])


def test_vertex_colors_and_w(write):
    m = read_obj(write("c.obj", "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n"))
    np.testing.assert_array_equal(m.vertex_colors, np.eye(3))
    m = read_obj(write("w.obj", "v 0 0 0 1\nv 1 0 0 1\nv 0 1 0 1\nf 1 2 3\n"))
    assert m.vertices.shape == (3, 3) and m.vertex_colors is None


@pytest.mark.parametrize(
    "text, line, expected, found",
    [
        ("v 0 0\n", 1, "3 or 4 or 6 numbers after 'v'", "2"),
        ("v 0 0 0\nv 0 x 0\n", 2, "a number after 'v'", "'x'"),
        ("v 0 0 0\nv 0 nan 0\n", 2, "a finite number after 'v'", "'nan'"),
        ("v 0 0 0\nv 0 0 inf\n", 2, "finite", "'inf'"),
        ("v 0 0 0\nv 0 0 0 1 1 1\n", 2, "3 numbers after 'v' as on the other lines", "6"),
        ("v 0 0 0\nv 1 0 0\nf 1 2\n", 3, "at least 3 vertex references", "'f 1 2'"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", 4, "a vertex index in 1..3", "'4'"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", 4, "a vertex index in 1..3", "'0'"),
        ("v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n", 3, "a vertex index in 1..2 (defined so far)", "'3'"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", 4, "a vertex index in 1..3", "'-4'"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 a\n", 4, "integer vertex references", "'a'"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n", 4, "a vertex reference", "'1/1/1/1'"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//2 2 3\n", 4, "a normal index in 1..0", "'1//2'"),
        ("v 0 0 0\nl 1\n", 2, "at least 2 vertex references after 'l'", "'l 1'"),
        ("v 0 0 0\nv 1 1 1\nl 1 3\n", 3, "a vertex index in 1..2", "'3'"),
        ("v 0 0 0\nbogus 1 2\n", 2, "an OBJ statement", "'bogus'"),
        ("v 0 0 0\nvn 0 1\n", 2, "3 numbers after 'vn'", "2"),
        ("v 0 0 0\nusemtl\n", 2, "a material name", "'usemtl'"),
    ],
)
def test_malformed(write, text, line, expected, found):
    p = write("bad.obj", text)
    with pytest.raises(FormatError) as err:
        read_obj(p)
    e = err.value
    assert e.line == line and expected in e.expected and found in e.found, str(e)
    assert str(e).startswith(f"{p}:{line}: expected ")


def test_not_text_and_missing(tmp_path):
    p = tmp_path / "bin.obj"
    p.write_bytes(b"v 0 0 0\n\xff\xfe\x00")
    with pytest.raises(FormatError, match=r"bin.obj:2: expected UTF-8 text"):
        read_obj(p)
    with pytest.raises(InputError, match="no such file"):
        read_obj(tmp_path / "none.obj")


def test_sequence_round_trip_and_order(tmp_path):
    base = trimesh.creation.icosphere(subdivisions=1)
    frames = [ObjMesh(np.round(base.vertices * (1 + 0.1 * k), 6), base.faces) for k in range(12)]
    paths = write_obj_sequence(tmp_path / "seq", frames)
    assert [p.name for p in paths][:2] == ["frame_0000.obj", "frame_0001.obj"]
    got_paths, got = read_obj_sequence(tmp_path / "seq")
    assert got_paths == paths
    for a, b in zip(frames, got):
        np.testing.assert_array_equal(a.vertices, b.vertices)
    # a glob selects a sub-range, in natural order
    sub = list_obj_sequence(str(tmp_path / "seq" / "frame_001*.obj"))
    assert [p.name for p in sub] == ["frame_0010.obj", "frame_0011.obj"]
    assert no_partial_files(tmp_path / "seq")


def test_sequence_topology_mismatch_names_frame(tmp_path):
    base = trimesh.creation.icosphere(subdivisions=1)
    write_obj(tmp_path / "s" / "frame_0000.obj", ObjMesh(base.vertices, base.faces))
    write_obj(tmp_path / "s" / "frame_0001.obj", ObjMesh(base.vertices, base.faces[::-1]))
    with pytest.raises(FormatError, match=r"frame_0001.obj: expected the same faces"):
        read_obj_sequence(tmp_path / "s")
    write_obj(tmp_path / "s" / "frame_0001.obj", ObjMesh(base.vertices[:-1], base.faces[:3]))
    with pytest.raises(FormatError, match=r"frame_0001.obj: expected 42 vertices"):
        read_obj_sequence(tmp_path / "s")


def test_empty_sequence_folder(tmp_path):
    with pytest.raises(InputError, match="no .obj files"):
        list_obj_sequence(tmp_path)
    with pytest.raises(InputError, match="no such file or folder"):
        list_obj_sequence(tmp_path / "nothing_*.obj")


def test_failed_write_leaves_no_file(tmp_path):
    bad = ObjMesh(np.array([[0, 0, np.nan], [1, 0, 0], [0, 1, 0]]), [[0, 1, 2]])
    with pytest.raises(ValueError):
        write_obj(tmp_path / "x.obj", bad)
    assert not (tmp_path / "x.obj").exists() and no_partial_files(tmp_path)
