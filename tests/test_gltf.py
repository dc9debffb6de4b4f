"""canopy-export -o OUT.glb: the binary glTF read back (pygltflib and the chunks by hand).

A tiny synthetic build: a 3-frame sequence whose third frame gains a face (a floret emerging) and a
static part. Checked: the GLB layout, every accessor inside its buffer view and the buffer, one
morph target per frame after the first on the animated part and none on the static one, the
animation's clock and one-hot weights, the materials' linear colours, each frame's positions
restored from the quantized base and deltas (within half a quantization step) or exact float32,
the emerging face of zero area before it emerges, byte-identical reruns and bad input.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from inflo.formats.obj import read_obj
from inflo.tools.canopy_export import cli as export_cli
from inflo.tools.canopy_export.gltf import glb_chunks

_BASE = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 1.0, 0.0), (0.5, 1.5, 0.3333333)]
_SIZES = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}
_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


def _frame_text(k: int) -> str:
    verts = [list(v) for v in _BASE]
    verts[2][2] = 0.1234567 * k
    verts[4][1] = 1.5 + 0.25 * k
    faces = [("mtl3", (1, 2, 3)), ("mtl4", (1, 3, 4))]
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


def _read(doc, binary, index) -> np.ndarray:
    """Accessor ``index`` as float64 values (normalized integers divided), shape (count, n)."""
    acc = doc["accessors"][index]
    view = doc["bufferViews"][acc["bufferView"]]
    n, size = _COMPONENTS[acc["type"]], _SIZES[acc["componentType"]]
    stride = view.get("byteStride", n * size)
    dtype = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}[acc["componentType"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    assert start + stride * (acc["count"] - 1) + n * size <= view["byteOffset"] + view["byteLength"] <= len(binary)
    raw = np.frombuffer(binary, dtype=np.uint8, count=stride * acc["count"] if acc["count"] else 0, offset=start)
    rows = raw.reshape(acc["count"], stride)[:, :n * size].copy().view(dtype).reshape(acc["count"], n)
    out = rows.astype(np.float64)
    if acc.get("normalized"):
        out = np.maximum(out / {5122: 32767.0, 5120: 127.0, 5123: 65535.0, 5121: 255.0}[acc["componentType"]], -1.0)
    if "min" in acc:  # min and max hold the stored values
        assert np.array_equal(rows.min(axis=0), np.asarray(acc["min"], rows.dtype))
        assert np.array_equal(rows.max(axis=0), np.asarray(acc["max"], rows.dtype))
    return out


def _frames(doc, binary, node_index):
    """Every frame's positions of a node's mesh, in the node's parent's space, and its faces."""
    node = doc["nodes"][node_index]
    mesh = doc["meshes"][node["mesh"]]
    prim = mesh["primitives"][0]
    base = _read(doc, binary, prim["attributes"]["POSITION"])
    deltas = [_read(doc, binary, t["POSITION"]) for t in prim.get("targets", [])]
    scale = np.asarray(node.get("scale", [1, 1, 1]))
    shift = np.asarray(node.get("translation", [0, 0, 0]))
    frames = [base] + [base + d for d in deltas]
    faces = np.vstack([_read(doc, binary, p["indices"]).reshape(-1, 3) for p in mesh["primitives"]]).astype(int)
    return [f * scale + shift for f in frames], faces, mesh


def test_glb_structure_frames_materials_and_animation(build):
    pygltflib = pytest.importorskip("pygltflib")
    tmp, seq, static, colors = build
    out = tmp / "out" / "flower.glb"
    res = _run(f"petals={seq}", static, "--colors", colors, "--fps", 30, "--title", "A test", "-o", out)
    assert res.exit_code == 0, res.output
    data = out.read_bytes()
    gl = pygltflib.GLTF2().load_binary(str(out))  # a reader of its own takes it
    assert gl.asset.version == "2.0" and len(gl.meshes) == 2 and len(gl.animations) == 1
    doc, binary = glb_chunks(data)
    assert doc["buffers"][0]["byteLength"] == len(binary) and len(binary) % 4 == 0
    assert doc["extensionsRequired"] == ["KHR_mesh_quantization"]
    for view in doc["bufferViews"]:
        assert view["byteOffset"] % 4 == 0 and view["byteOffset"] + view["byteLength"] <= len(binary)
    # scene: a root node in metres (cm by default) over one node per part
    root = doc["nodes"][doc["scenes"][0]["nodes"][0]]
    assert root["scale"] == [0.01] * 3 and root["children"] == [0, 1]
    extras = doc["scenes"][0]["extras"]
    assert (extras["frames"], extras["fps"], extras["title"], extras["triangles"]) == (3, 30.0, "A test", 4)
    # the animated part: one morph target per frame after the first; frame k restored
    frames, faces, mesh = _frames(doc, binary, 0)
    assert len(mesh["primitives"]) == 2 and all(len(p["targets"]) == 2 for p in mesh["primitives"])
    assert mesh["weights"] == [0.0, 0.0]
    step = doc["nodes"][0]["scale"][0] / 32767
    for k in range(3):  # each face's corners (a vertex shared with the emerging face is copied for it)
        obj = read_obj(seq / f"frame_{k:04d}.obj")
        np.testing.assert_allclose(frames[k][faces[:len(obj.faces)]], obj.vertices[obj.faces], atol=1.01 * step)
    # the emerging face (vertex 5 in no face before frame 2) has no area before it emerges
    new = faces[-1]
    for k in range(2):
        p = frames[k][new]
        assert np.linalg.norm(np.cross(p[1] - p[0], p[2] - p[0])) < 1e-9
    # the static part: no morph targets, no animation channel
    _, _, stem = _frames(doc, binary, 1)
    assert "targets" not in stem["primitives"][0] and "weights" not in stem
    # the animation: times k / fps, weights one-hot on target k - 1, linear
    anim = doc["animations"][0]
    assert [c["target"] for c in anim["channels"]] == [{"node": 0, "path": "weights"}]
    sampler = anim["samplers"][0]
    assert sampler["interpolation"] == "LINEAR"
    np.testing.assert_allclose(_read(doc, binary, sampler["input"]).ravel(), np.arange(3) / 30.0, rtol=1e-6)
    weights = _read(doc, binary, sampler["output"]).reshape(3, 2)
    assert weights.tolist() == [[0, 0], [1, 0], [0, 1]]
    # materials: linear colours of the colour file, double-sided, one per material + the stem's default
    mats = {m["name"]: m for m in doc["materials"]}
    assert set(mats) == {"mtl3", "mtl4", "stem_default"}
    assert mats["mtl3"]["pbrMetallicRoughness"]["baseColorFactor"][:3] == pytest.approx([0.214041, 0.050876, 1.0],
                                                                                       abs=1e-6)
    assert all(m["doubleSided"] for m in mats.values())
    # a rerun writes the same bytes
    again = tmp / "again" / "flower.glb"
    assert _run(f"petals={seq}", static, "--colors", colors, "--fps", 30, "--title", "A test", "-o", again).exit_code == 0
    assert again.read_bytes() == data


def test_float32_without_quantization(build):
    tmp, seq, static, colors = build
    out = tmp / "f.glb"
    assert _run(seq, "--no-quantize", "-o", out).exit_code == 0
    doc, binary = glb_chunks(out.read_bytes())
    assert "extensionsRequired" not in doc
    frames, faces, _ = _frames(doc, binary, 0)
    for k in range(3):
        obj = read_obj(seq / f"frame_{k:04d}.obj")
        # the base exact; a later frame is base + delta, both float32, as a viewer adds them
        np.testing.assert_allclose(frames[k][faces[:len(obj.faces)]], obj.vertices[obj.faces], atol=2e-7,
                                   rtol=0 if k else 1e-9)


def test_viewer_page_is_written_beside_the_glb(build):
    tmp, seq, static, colors = build
    out = tmp / "viewer" / "flower.glb"
    assert _run(seq, "--viewer", "--title", 'Lily "<b>"', "-o", out).exit_code == 0
    page = (tmp / "viewer" / "index.html").read_text()
    config = json.loads(page.split('id="inflo-config">')[1].split("</script>")[0])
    assert config["model"] == "flower.glb" and config["title"] == 'Lily "<b>"'
    assert "<title>Lily &quot;&lt;b&gt;&quot; — inflo</title>" in page
    for rel in ("three.module.min.js", "addons/loaders/GLTFLoader.js", "addons/controls/OrbitControls.js",
                "addons/utils/BufferGeometryUtils.js", "LICENSE"):
        assert (tmp / "viewer" / "three" / rel).is_file(), rel
    assert "http://" not in page and "https://" not in page  # nothing fetched from elsewhere
    res = _run(seq, "--viewer", "-o", tmp / "x.usdc")
    assert res.exit_code == 2 and "--viewer" in res.output


def test_translate_moves_the_node(build):
    tmp, seq, static, colors = build
    out = tmp / "t.glb"
    assert _run(f"a={seq}", f"b={static}", "--translate", "b=2,0,0", "-o", out).exit_code == 0
    doc, binary = glb_chunks(out.read_bytes())
    frames, _, _ = _frames(doc, binary, 1)
    np.testing.assert_allclose(frames[0], read_obj(static).vertices + [2, 0, 0], atol=1e-4)


def test_every_nth_frame_keeps_the_last_and_the_duration(build):
    tmp, seq, static, colors = build
    out = tmp / "e.glb"
    assert _run(seq, "--every", 2, "--fps", 10, "-o", out).exit_code == 0
    doc, binary = glb_chunks(out.read_bytes())
    frames, faces, mesh = _frames(doc, binary, 0)
    assert len(frames) == 2 and doc["scenes"][0]["extras"]["fps"] == 5.0  # frames 0 and 2, same duration
    obj = read_obj(seq / "frame_0002.obj")
    step = doc["nodes"][0]["scale"][0] / 32767
    np.testing.assert_allclose(frames[1][faces], obj.vertices[obj.faces], atol=1.01 * step)
    res = _run(seq, "--every", 2, "-o", tmp / "e.usdc")
    assert res.exit_code == 2 and "--every" in res.output



def test_max_mb_thins_the_frames_until_the_file_fits(tmp_path):
    """--max-mb: a larger --every, in proportion to the size, until the .glb fits; the first and
    last frame kept; a budget that even two frames exceed is one line, exit 2, and no file."""
    from inflo.formats.obj import ObjMesh, write_obj

    seq = tmp_path / "seq"
    seq.mkdir()
    n = 120
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    base = np.column_stack([u.ravel(), v.ravel(), np.zeros(u.size)])
    q = np.arange(n * n).reshape(n, n)[:-1, :-1].ravel()
    faces = np.vstack([np.column_stack([q, q + 1, q + n]), np.column_stack([q + 1, q + n + 1, q + n])]).astype(np.int32)
    for k in range(12):
        write_obj(seq / f"frame_{k:04d}.obj", ObjMesh(base + [0, 0, 0.02 * k] * np.sin(3 * base[:, :1] + k), faces))
    full = tmp_path / "full.glb"
    assert _run(seq, "-o", full).exit_code == 0
    budget = 0.45 * full.stat().st_size / 1e6
    out = tmp_path / "thin.glb"
    assert _run(seq, "--max-mb", budget, "-o", out).exit_code == 0
    assert out.stat().st_size <= budget * 1e6 < full.stat().st_size
    doc, binary = glb_chunks(out.read_bytes())
    frames, fs, _ = _frames(doc, binary, 0)
    assert 2 <= len(frames) < 12
    last = read_obj(seq / "frame_0011.obj")
    step = doc["nodes"][0]["scale"][0] / 32767
    np.testing.assert_allclose(frames[-1][fs], last.vertices[last.faces], atol=1.01 * step + 1e-6)
    res = _run(seq, "--max-mb", 0.1, "-o", tmp_path / "tiny.glb")
    if full.stat().st_size * 2 / 12 > 0.1e6:
        assert res.exit_code == 2 and "within --max-mb 0.1" in res.output
        assert not (tmp_path / "tiny.glb").exists()


def test_a_part_whose_vertex_count_changes_is_a_flip_book(tmp_path):
    """Branches rebuilt every frame (their vertex count changes): one node per frame with that
    frame's mesh, scaled 1 at its frame only by a STEP animation, and an empty first frame left out."""
    from inflo.tools.canopy_export import cli as export_cli
    from inflo.tools.canopy_export.gltf import glb_chunks

    seq = tmp_path / "branches"
    seq.mkdir()
    (seq / "frame_0000.obj").write_text("# empty\n")
    (seq / "frame_0001.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    (seq / "frame_0002.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 2 0\nf 1 2 3\nf 1 3 4\n")
    out = tmp_path / "b.glb"
    res = CliRunner().invoke(export_cli.main, ["-q", str(seq), "-o", str(out)])
    assert res.exit_code == 0, res.output
    doc, blob = glb_chunks(out.read_bytes())
    frames = [n for n in doc["nodes"] if "extras" in n and "frame" in n["extras"]]
    assert [n["extras"]["frame"] for n in frames] == [2, 3]
    assert all(n["scale"] == [0.0, 0.0, 0.0] for n in frames)  # frame 1 (empty) is what shows first
    counts = [doc["accessors"][doc["meshes"][n["mesh"]]["primitives"][0]["attributes"]["POSITION"]]["count"]
              for n in frames]
    assert counts == [3, 4]
    anim = doc["animations"][0]
    steps = [s for s in anim["samplers"] if s["interpolation"] == "STEP"]
    assert len(steps) == 2 and {c["target"]["path"] for c in anim["channels"]} == {"scale"}
    acc = doc["accessors"][steps[1]["output"]]
    view = doc["bufferViews"][acc["bufferView"]]
    sc = np.frombuffer(blob, np.float32, acc["count"] * 3, view.get("byteOffset", 0)).reshape(-1, 3)
    assert sc[:, 0].tolist() == [0.0, 0.0, 1.0]
