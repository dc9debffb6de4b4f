"""canopy-export: OBJ sequences + colours -> one USD file, read back with pxr.

A tiny synthetic build: a 3-frame sequence whose third frame gains a vertex and a face (a floret
emerging), and a static part (one OBJ file without materials). The USD is opened with
``Usd.Stage.Open`` and checked against the OBJ frames: points per time code (float32 rounding),
time range and fps, faces sampled only where they change, subsets and linear material colours,
upAxis and metersPerUnit; bad input exits 2 with one line and leaves no file.
"""
from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

pxr = pytest.importorskip("pxr")
from conftest import no_partial_files  # noqa: E402
from pxr import Usd, UsdGeom, UsdShade  # noqa: E402

from inflo.formats.obj import read_obj  # noqa: E402
from inflo.formats.pc2 import encode_pc2, read_pc2  # noqa: E402
from inflo.tools.canopy_export import cli as export_cli  # noqa: E402
from inflo.tools.canopy_export.usd import points_extent, srgb_to_linear, vertex_normals  # noqa: E402

# frame k: the quad's far corner rises; frame 2 adds face (2, 5, 3), material mtl4 (vertex 5 unused before)
_BASE = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 1.0, 0.0)]


def _frame_text(k: int) -> str:
    verts = [list(v) for v in _BASE]
    verts[2][2] = 0.1234567 * k
    faces = [("mtl3", (1, 2, 3)), ("mtl4", (1, 3, 4))]
    verts.append([0.5, 1.5, 0.3333333])  # in every frame (vertex k is one point throughout), used from frame 2
    if k == 2:
        faces.append(("mtl4", (3, 5, 4)))
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in verts]
    current = None
    for mtl, f in faces:
        if mtl != current:
            lines.append(f"usemtl {mtl}")
            current = mtl
        lines.append("f " + " ".join(map(str, f)))
    return "\n".join(lines) + "\n"


@pytest.fixture
def build(tmp_path):
    seq = tmp_path / "canopy"
    seq.mkdir()
    for k in range(3):
        (seq / f"frame_{k:04d}.obj").write_text(_frame_text(k))
    static = tmp_path / "stem.obj"
    static.write_text("v 0 0 0\nv 0 -1 0\nv 0.1 -1 0\nf 1 2 3\n")
    colors = tmp_path / "colors.toml"
    colors.write_text('3 = [0.5, 0.25, 1.0]\nmtl4 = "#ff8000"\n')
    return tmp_path, seq, static, colors


def _run(*args):
    return CliRunner().invoke(export_cli.main, ["-q", *map(str, args)])


def _error_line(res) -> str:
    lines = [l for l in res.stderr.splitlines() if l.strip()]
    assert len(lines) == 1, res.stderr
    return lines[0]


def test_usd_matches_the_obj_frames(build):
    tmp, seq, static, colors = build
    out = tmp / "out" / "flower.usdc"
    res = _run(f"petals={seq}", static, "--colors", colors, "--fps", 30, "--units", "mm", "-o", out)
    assert res.exit_code == 0, res.output
    assert out.read_bytes()[:8] == b"PXR-USDC"
    stage = Usd.Stage.Open(str(out))
    assert UsdGeom.GetStageUpAxis(stage) == "Y"
    assert UsdGeom.GetStageMetersPerUnit(stage) == pytest.approx(0.001)
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (1.0, 3.0)
    assert stage.GetTimeCodesPerSecond() == 30.0 and stage.GetFramesPerSecond() == 30.0
    assert stage.GetDefaultPrim().GetPath() == "/flower"

    mesh = UsdGeom.Mesh.Get(stage, "/flower/petals")
    assert mesh and mesh.GetSubdivisionSchemeAttr().Get() == "none" and mesh.GetDoubleSidedAttr().Get()
    assert mesh.GetPointsAttr().GetTimeSamples() == [1.0, 2.0, 3.0]
    for k in range(3):
        obj = read_obj(seq / f"frame_{k:04d}.obj")
        pts = np.asarray(mesh.GetPointsAttr().Get(1.0 + k))
        np.testing.assert_array_equal(pts, obj.vertices.astype(np.float32))
        ext = np.asarray(mesh.GetExtentAttr().Get(1.0 + k))
        np.testing.assert_array_equal(ext, [pts.min(0), pts.max(0)])
        np.testing.assert_array_equal(np.asarray(mesh.GetFaceVertexIndicesAttr().Get(1.0 + k)), obj.faces.ravel())
        assert list(mesh.GetFaceVertexCountsAttr().Get(1.0 + k)) == [3] * obj.n_faces
    # faces written where they change (frames 1 and 3), not at every frame
    assert mesh.GetFaceVertexIndicesAttr().GetTimeSamples() == [1.0, 3.0]
    assert mesh.GetFaceVertexCountsAttr().GetTimeSamples() == [1.0, 3.0]
    assert not mesh.GetNormalsAttr().HasAuthoredValue()

    # one subset per usemtl, bound to a UsdPreviewSurface of the colour file's colour, linear
    subsets = {s.GetPrim().GetName(): s for s in UsdShade.MaterialBindingAPI(mesh.GetPrim()).GetMaterialBindSubsets()}
    assert set(subsets) == {"mtl3", "mtl4"}
    assert list(subsets["mtl3"].GetIndicesAttr().Get(1.0)) == [0]
    assert list(subsets["mtl4"].GetIndicesAttr().Get(2.0)) == [1]
    assert list(subsets["mtl4"].GetIndicesAttr().Get(3.0)) == [1, 2]
    assert UsdGeom.Subset.GetFamilyType(mesh, "materialBind") == "nonOverlapping"
    assert UsdGeom.Subset.ValidateFamily(mesh, UsdGeom.Tokens.face, "materialBind") == (True, "")
    srgb_to_lin = lambda c: c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4
    want = {"mtl3": (0.5, 0.25, 1.0), "mtl4": (1.0, 128 / 255, 0.0)}
    for name, rgb in want.items():
        mat, _ = UsdShade.MaterialBindingAPI(subsets[name].GetPrim()).ComputeBoundMaterial()
        shader = mat.ComputeSurfaceSource()[0]
        assert shader.GetIdAttr().Get() == "UsdPreviewSurface"
        got = tuple(shader.GetInput("diffuseColor").Get())
        assert got == pytest.approx([srgb_to_lin(c) for c in rgb], abs=1e-6)
    assert tuple(shader.GetInput("diffuseColor").Get())[1] == pytest.approx(0.2158605, abs=1e-6)

    # the static part: written once, no time samples, its faces bound to a default material
    stem = UsdGeom.Mesh.Get(stage, "/flower/stem")
    assert stem.GetPointsAttr().GetTimeSamples() == [] and stem.GetFaceVertexIndicesAttr().GetTimeSamples() == []
    np.testing.assert_array_equal(np.asarray(stem.GetPointsAttr().Get(2.0)),
                                  np.float32([[0, 0, 0], [0, -1, 0], [0.1, -1, 0]]))
    mat, _ = UsdShade.MaterialBindingAPI(stem.GetPrim()).ComputeBoundMaterial()
    assert mat and mat.GetPrim().GetName() == "stem_default"


def test_constant_topology_is_written_once_and_text_output(build):
    tmp, seq, static, colors = build
    (seq / "frame_0002.obj").write_text(_frame_text(1).replace("0.123457", "0.25"))
    out = tmp / "flower.usda"
    res = _run(seq, "--normals", "--start-frame", 0, "-o", out)
    assert res.exit_code == 0, res.output
    assert out.read_text().startswith("#usda 1.0")
    stage = Usd.Stage.Open(str(out))
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (0.0, 2.0)
    assert UsdGeom.GetStageMetersPerUnit(stage) == pytest.approx(0.01)  # --units cm, the default
    assert stage.GetTimeCodesPerSecond() == 24.0
    mesh = UsdGeom.Mesh.Get(stage, "/flower/canopy")  # named after its folder
    assert mesh.GetFaceVertexIndicesAttr().GetTimeSamples() == []
    assert list(mesh.GetFaceVertexIndicesAttr().Get()) == [0, 1, 2, 0, 2, 3]
    assert mesh.GetPointsAttr().GetTimeSamples() == [0.0, 1.0, 2.0]
    nrm = np.asarray(mesh.GetNormalsAttr().Get(0.0))
    np.testing.assert_allclose(nrm, [[0, 0, 1]] * 4 + [[0, 0, 0]], atol=1e-7)  # vertex 5: in no face yet
    assert mesh.GetNormalsAttr().GetTimeSamples() == [0.0, 1.0, 2.0]


def test_deterministic_and_pc2(build):
    tmp, seq, static, colors = build
    (seq / "frame_0002.obj").write_text(_frame_text(1).replace("0.123457", "0.25"))
    a, b = tmp / "a" / "x.usdc", tmp / "b" / "x.usdc"
    assert _run(seq, "--colors", colors, "--pc2", tmp / "pc2", "-o", a).exit_code == 0
    assert _run(seq, "--colors", colors, "-o", b).exit_code == 0
    assert a.read_bytes() == b.read_bytes()
    pts, start, sampling = read_pc2(tmp / "pc2" / "canopy.pc2")
    assert (start, sampling) == (1.0, 1.0) and pts.shape == (3, 5, 3)
    for k in range(3):
        np.testing.assert_array_equal(pts[k], read_obj(seq / f"frame_{k:04d}.obj").vertices.astype(np.float32))
    assert encode_pc2(pts)[:12] == b"POINTCACHE2\x00"


def _assert_bad(res, out, *words):
    assert res.exit_code == 2, res.output
    line = _error_line(res)
    assert line.startswith("canopy-export: error: ")
    for w in words:
        assert w in line, line
    assert not out.exists()
    assert no_partial_files(out.parent) if out.parent.exists() else True
    if out.parent.exists():
        assert not [p for p in out.parent.iterdir() if p.name.startswith(f".{out.name}")]


def test_bad_input_exits_2_without_output(build):
    tmp, seq, static, colors = build
    out = tmp / "flower.usdc"
    _assert_bad(_run(tmp / "nowhere", "-o", out), out, "nowhere", "no such file or folder")
    # a frame with the previous frame's faces but an extra vertex
    (seq / "frame_0001.obj").write_text(_frame_text(1) + "v 9 9 9\n")
    _assert_bad(_run(seq, "-o", out), out, "frame_0001.obj", "expected 5 vertices", "found 6")
    (seq / "frame_0001.obj").write_text(_frame_text(1))
    # faces that change, where the topology is declared constant (or needed by a PC2 cache)
    _assert_bad(_run(seq, "--constant-topology", "-o", out), out, "frame_0002.obj", "expected the 2 faces",
                "constant topology")
    _assert_bad(_run(seq, "--pc2", tmp / "pc2", "-o", out), out, "frame_0002.obj", "PC2")
    assert not (tmp / "pc2").exists()
    # a bad colour file line
    colors.write_text('3 = [0.5, 0.25, 1.0]\n4 = "blurple"\n')
    _assert_bad(_run(seq, "--colors", colors, "-o", out), out, "colors.toml", "'4'", "blurple")
    colors.write_text("3 = [0.5, 0.25\n4 = [0, 0, 0]\n")
    _assert_bad(_run(seq, "--colors", colors, "-o", out), out, "colors.toml", "line 2")
    # sequences of different lengths; a malformed OBJ line
    short = tmp / "short"
    short.mkdir()
    (short / "frame_0000.obj").write_text(_frame_text(0))
    _assert_bad(_run(seq, short, "-o", out), out, "expected 3 frames", "found 1")
    (seq / "frame_0001.obj").write_text(_frame_text(1).replace("f 1 3 4", "f 1 3 x"))
    _assert_bad(_run(seq, "-o", out), out, "frame_0001.obj:", "found")
    # two parts of one name
    (seq / "frame_0001.obj").write_text(_frame_text(1))
    _assert_bad(_run(f"a={seq}", f"a={static}", "-o", out), out, "'a'")


@pytest.mark.parametrize("suffix", [".usdc", ".glb"])
def test_sequence_rules_as_fccompose(build, suffix):
    """A gap in the numbering, a 0-byte frame, a vertex count that changes with the same faces: one line,
    exit 2, no file; a frame with more vertices and more faces is taken."""
    tmp, seq, static, colors = build
    out = tmp / f"flower{suffix}"
    (seq / "frame_0003.obj").write_text(_frame_text(1))
    (seq / "frame_0001.obj").rename(seq / "frame_0004.obj")  # 0, 2, 3, 4: frame_0001 missing
    _assert_bad(_run(seq, "-o", out), out, "without a gap", "frame_0001.obj missing")
    (seq / "frame_0004.obj").rename(seq / "frame_0001.obj")
    (seq / "frame_0003.obj").write_bytes(b"")
    _assert_bad(_run(seq, "-o", out), out, "frame_0003.obj", "empty (0-byte)")
    (seq / "frame_0003.obj").unlink()
    (seq / "frame_0002.obj").write_text(_frame_text(1) + "v 9 9 9\n")  # a vertex more, faces kept
    _assert_bad(_run(seq, "-o", out), out, "frame_0002.obj", "expected 5 vertices", "found 6")
    # a vertex and faces more (a branch growing): taken, time-sampled points in USD, padded in a .glb
    (seq / "frame_0002.obj").write_text(_frame_text(2) + "v 9 9 9\nf 1 2 6\n")
    res = _run(seq, "-o", out)
    assert res.exit_code == 0 and out.is_file(), res.output


@pytest.mark.parametrize("suffix", [".usdc", ".glb"])
def test_float32_range_and_fps(build, suffix):
    tmp, seq, static, colors = build
    out = tmp / f"flower{suffix}"
    (seq / "frame_0001.obj").write_text(_frame_text(1).replace("v 1.000000 0.000000", "v 1e39 0.000000"))
    _assert_bad(_run(seq, "-o", out), out, "frame_0001.obj", "float32", "1e+39")
    (seq / "frame_0001.obj").write_text(_frame_text(1))
    for fps in ("nan", "inf", "-inf", "0", "-3"):
        res = _run(seq, "--fps", fps, "-o", out)
        assert res.exit_code == 2 and "--fps" in res.output and "Traceback" not in res.output, res.output
        assert not out.exists()


def test_mtl_never_replaces_a_hand_written_materials_mtl(build):
    tmp, seq, static, colors = build
    hand = seq / "materials.mtl"
    hand.write_text("# my own\nnewmtl mtl3\nKd 1 0 0\n")
    out = tmp / "flower.usdc"
    _assert_bad(_run(seq, "--mtl", "--colors", colors, "-o", out), out, "materials.mtl", "by hand")
    assert hand.read_text() == "# my own\nnewmtl mtl3\nKd 1 0 0\n"
    hand.unlink()
    assert _run(seq, "--mtl", "--colors", colors, "-o", out).exit_code == 0  # its own: written,
    assert hand.read_text().startswith("# canopy-export:")
    assert _run(seq, "--mtl", "--colors", colors, "-o", out).exit_code == 0  # and replaced on a rerun


def test_usage_errors_and_help():
    res = _run("x", "-o", "out.obj")
    assert res.exit_code == 2 and ".usdc" in res.stderr
    res = _run("x", "--units", "furlong", "-o", "out.usdc")
    assert res.exit_code == 2 and "metres per unit" in res.stderr
    res = CliRunner().invoke(export_cli.main, ["--help"])
    assert res.exit_code == 0 and "Universal Scene Description" in res.output


def test_helpers():
    np.testing.assert_allclose(srgb_to_linear([0.0, 0.04045, 0.5, 1.0]), [0.0, 0.04045 / 12.92, 0.21404114, 1.0])
    # degenerate input: a zero-area face and an unused vertex get zero normals, no NaN
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [5, 5, 5]], float)
    n = vertex_normals(v, np.array([[0, 1, 2]]))
    assert n.dtype == np.float32 and np.all(n == 0)


def test_fast_helpers_match_their_plain_versions():
    """points_extent (a transposed copy reduced by rows) and vertex_normals (bincount) give the
    very bits of the plain numpy they replace: min/max along axis 0, np.add.at per corner."""
    rng = np.random.default_rng(7)
    v = rng.normal(size=(500, 3)) * 10
    f = rng.integers(0, 480, size=(900, 3))  # vertices 480.. in no face: zero normals
    pts = v.astype(np.float32)
    ext = points_extent(pts)
    assert ext.dtype == np.float32 and ext.shape == (2, 3)
    assert ext.tobytes() == np.stack([pts.min(axis=0), pts.max(axis=0)]).tobytes()
    assert points_extent(np.zeros((0, 3), np.float32)).tobytes() == np.zeros((2, 3), np.float32).tobytes()
    fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    acc = np.zeros_like(v)
    for j in range(3):
        np.add.at(acc, f[:, j], fn)
    length = np.linalg.norm(acc, axis=1, keepdims=True)
    ref = np.divide(acc, length, out=np.zeros_like(acc), where=length > 0).astype(np.float32)
    assert vertex_normals(v, f).tobytes() == ref.tobytes()


def test_changing_faces_carry_material_index_and_mtl(build):
    """Where faces change, each face's material also goes as the uniform primvar material_index
    (Blender's Mesh Sequence Cache reads subsets once, at import; tests/test_blender.py); faces
    without usemtl among faces with one get the part's default material in a subset of their
    own; --mtl writes materials.mtl (Kd linear) beside the OBJ frames, which name it (mtllib)."""
    tmp, seq, static, colors = build
    (seq / "frame_0001.obj").write_text(_frame_text(1).replace("usemtl mtl3\n", "", 1))
    out = tmp / "flower.usda"
    res = _run(seq, "--colors", colors, "--mtl", "-o", out)
    assert res.exit_code == 0, res.output
    stage = Usd.Stage.Open(str(out))
    mesh = UsdGeom.Mesh.Get(stage, "/flower/canopy")
    pv = UsdGeom.PrimvarsAPI(mesh).GetPrimvar("material_index")
    assert pv.GetInterpolation() == "uniform"
    # materials in order of first appearance: mtl3, mtl4, canopy_default (frame 2's unbound face)
    assert [list(pv.Get(t)) for t in (1.0, 2.0, 3.0)] == [[0, 1], [2, 1], [0, 1, 1]]
    subsets = UsdShade.MaterialBindingAPI(mesh.GetPrim()).GetMaterialBindSubsets()
    assert [s.GetPrim().GetName() for s in subsets] == ["mtl3", "mtl4", "canopy_default"]
    assert list(subsets[2].GetIndicesAttr().Get(2.0)) == [0] and list(subsets[2].GetIndicesAttr().Get(3.0)) == []
    mtl = (seq / "materials.mtl").read_text()
    assert "newmtl mtl3\nKd 0.214041 0.050876 1.000000\n" in mtl and "newmtl mtl4\n" in mtl
    assert "canopy_default" not in mtl  # not an OBJ material

    # the OBJ writer names the library and smooth shading; the reader ignores both
    from inflo.formats.obj import ObjMesh, write_obj

    m = read_obj(seq / "frame_0000.obj")
    write_obj(tmp / "w.obj", m, header="x")
    lines = (tmp / "w.obj").read_text().splitlines()
    assert lines[:2] == ["# x", "mtllib materials.mtl"] and lines[lines.index("s 1") + 1].startswith("usemtl")
    write_obj(tmp / "n.obj", ObjMesh(vertices=m.vertices, faces=m.faces))
    assert "mtllib" not in (tmp / "n.obj").read_text() and "s 1\n" in (tmp / "n.obj").read_text()


def test_floret_subsets(build):
    tmp, seq, static, colors = build
    for k in range(3):
        text = _frame_text(k).replace("usemtl mtl3", "g floret_0\nusemtl mtl3")
        (seq / f"frame_{k:04d}.obj").write_text(text.replace("f 3 5 4", "g floret_1\nf 3 5 4"))
    out = tmp / "flower.usda"
    assert _run(seq, "--subsets", "floret", "-o", out).exit_code == 0
    stage = Usd.Stage.Open(str(out))
    mesh = UsdGeom.Mesh.Get(stage, "/flower/canopy")
    # the material subsets as without --subsets floret; the florets as a family of their own,
    # bound to nothing (per-floret material subsets lost their colours in Blender 4.5)
    mats = [s.GetPrim().GetName() for s in UsdShade.MaterialBindingAPI(mesh.GetPrim()).GetMaterialBindSubsets()]
    assert mats == ["mtl3", "mtl4"]
    florets = {s.GetPrim().GetName(): s for s in UsdGeom.Subset.GetGeomSubsets(mesh, familyName="floret")}
    assert list(florets) == ["floret_0", "floret_1"]
    assert list(florets["floret_0"].GetIndicesAttr().Get(3.0)) == [0, 1]
    assert list(florets["floret_1"].GetIndicesAttr().Get(1.0)) == []
    assert list(florets["floret_1"].GetIndicesAttr().Get(3.0)) == [2]
    assert UsdGeom.Subset.ValidateFamily(mesh, UsdGeom.Tokens.face, "floret") == (True, "")
    assert not UsdShade.MaterialBindingAPI(florets["floret_1"].GetPrim()).GetDirectBinding().GetMaterial()
    res = _run(seq, "--subsets", "organ", "-o", out)
    assert res.exit_code == 2


def test_translate_moves_a_part_by_an_xform_op_and_keeps_its_points(build):
    """--translate NAME=X,Y,Z: flowers built at one place (Eustoma's cultivars) stand side by side;
    the part's prim gets an xformOp:translate, its points stay those of the OBJ files."""
    tmp, seq, static, colors = build
    out = tmp / "flower.usda"
    res = _run(f"petals={seq}", f"stem={static}", "--translate", "stem=2.5,0,-1", "-o", out)
    assert res.exit_code == 0, res.output
    stage = Usd.Stage.Open(str(out))
    stem = UsdGeom.Mesh.Get(stage, "/flower/stem")
    ops = stem.GetOrderedXformOps()
    assert [op.GetOpName() for op in ops] == ["xformOp:translate"]
    assert tuple(ops[0].Get()) == (2.5, 0.0, -1.0)
    np.testing.assert_allclose(np.asarray(stem.GetPointsAttr().Get()), read_obj(static).vertices, atol=1e-7)
    world = stem.ComputeLocalToWorldTransform(Usd.TimeCode.Default())
    assert tuple(world.ExtractTranslation()) == (2.5, 0.0, -1.0)
    assert UsdGeom.Mesh.Get(stage, "/flower/petals").GetOrderedXformOps() == []
    for bad, what in (("stem=1,2", "NAME=X,Y,Z"), ("=1,2,3", "NAME=X,Y,Z"), ("stem=1,x,3", "NAME=X,Y,Z"),
                      ("leaf=1,2,3", "no part named 'leaf'")):
        res = _run(f"petals={seq}", f"stem={static}", "--translate", bad, "-o", tmp / "bad.usda")
        assert res.exit_code == 2 and what in res.output, (bad, res.output)
        assert not (tmp / "bad.usda").exists()


def test_outputs_never_overwrite_inputs(build):
    """--viewer writes index.html and three/ beside the .glb: never over an input of that name."""
    tmp, seq, static, colors = build
    page = tmp / "page"
    (page / "three").mkdir(parents=True)
    (page / "index.html").write_text((seq / "frame_0000.obj").read_text())  # an OBJ input named index.html
    res = _run(f"a={page / 'index.html'}", "--viewer", "-o", page / "x.glb")
    assert res.exit_code == 2 and "--viewer" in res.output and "index.html" in res.output, res.output
    assert (page / "index.html").read_text() == (seq / "frame_0000.obj").read_text()
    assert not (page / "x.glb").exists()
    (page / "three" / "petal.obj").write_text((seq / "frame_0000.obj").read_text())
    res = _run(f"a={page / 'three' / 'petal.obj'}", "--viewer", "-o", page / "x.glb")
    assert res.exit_code == 2 and "petal.obj" in res.output and not (page / "x.glb").exists()
