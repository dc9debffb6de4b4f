"""canopy-export's USD opened in real Blender: ``bpy``, Blender 4.5 LTS as a Python module.

bpy is a large install (a 370 MB wheel, about 950 MB installed), so it lives in its own venv,
``.venv-blender/`` (``make test-blender`` makes it and runs this file); inflo's venv stays without
it. The tests run ``tools/canopy_export/blender_probe.py`` with that Python (or the one named by
``INFLO_BLENDER_PYTHON``) and are skipped when no Python with bpy is found. CI's ``make test``
does not run them: CI is near its time budget (README, "Open it in Blender").

- The draft lily's ``build/lily/lily.usdc`` (``make -C pipelines/lily usd``; built here when
  missing or stale), imported as File > Import > Universal Scene Description does: the scene's
  frame range is the file's (1-100 at 24 fps), each part is one mesh object with a Mesh Sequence
  Cache, Y-up turned to Blender's Z-up and centimetres to metres; at every frame the evaluated
  vertex positions equal the OBJ frame's vertices rounded to float32, the polygons are the OBJ's
  triangles, each polygon's material is its OBJ ``usemtl`` and each material's base colour is the
  colour file's, linear; one Cycles render of the last frame (8 samples) has the silhouette of
  canopy-render's still through the same camera.
- One OBJ frame of the lily imported with File > Import > Wavefront (.obj): its ``mtllib``
  library (``materials.mtl``, written by the usd stage's ``canopy-export --mtl``) gives each
  material the colour file's colour, linear, and ``s 1`` makes every polygon smooth.
- Every other species' USD where it has been built (``make <species>``), at its first, middle
  and last frame.
- A small build whose faces change (a floret emerging, with faces of no material and two
  groups, ``--subsets floret``): Blender follows the changing faces and keeps every polygon's
  material in every frame.
"""
from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from conftest import REPO, run_cli, silhouette_iou

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.formats.species import find_species

pytestmark = pytest.mark.blender

PROBE = REPO / "tools" / "canopy_export" / "blender_probe.py"
LILY = REPO / "pipelines" / "lily"


def blender_python() -> str | None:
    """A Python that imports bpy: ``INFLO_BLENDER_PYTHON``, else ``.venv-blender/bin/python``."""
    exe = os.environ.get("INFLO_BLENDER_PYTHON") or str(REPO / ".venv-blender" / "bin" / "python")
    if not Path(exe).exists():
        return None
    ok = subprocess.run([exe, "-c", "import bpy"], capture_output=True, timeout=120).returncode == 0
    return exe if ok else None


@pytest.fixture(scope="module")
def bpy_python():
    exe = blender_python()
    if exe is None:
        pytest.skip("no Python with bpy (make test-blender installs Blender 4.5 into .venv-blender)")
    return exe


def probe(exe: str, usd: Path, out: Path, *args) -> tuple[dict, dict]:
    r = subprocess.run([exe, str(PROBE), str(usd), "-o", str(out), *map(str, args)],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    report = json.loads(Path(f"{out}.json").read_text())
    with np.load(f"{out}.npz") as z:
        arrays = {k: z[k] for k in z.files}
    return report, arrays


def assert_float32_equal(found, obj_vertices, what: str) -> None:
    """Blender's float32 positions are the OBJ's six-decimal numbers rounded to float32."""
    want = np.asarray(obj_vertices, dtype=np.float32)
    assert found.shape == want.shape, f"{what}: {found.shape} vs {want.shape}"
    err = np.abs(found.astype(np.float64) - want.astype(np.float64))
    ulp = np.spacing(np.abs(want)).astype(np.float64)
    assert np.all(err <= ulp), f"{what}: {int(np.sum(err > ulp))} coordinates off by more than 1 ulp"


def srgb_linear(rgb):
    from inflo.tools.canopy_export.usd import srgb_to_linear

    return srgb_to_linear(rgb)


def check_frames(report: dict, arrays: dict, parts: dict, colors: dict, frames=None, start: int = 1):
    """Every part's evaluated vertices, polygons and polygon materials against its OBJ frames.

    ``parts``: part name -> its OBJ frames (a list) or one OBJ file (a static part, the same in
    every frame); ``frames``: the scene frames to check (default: every frame of the probe)."""
    from inflo.formats.colors import material_color

    frames = frames or sorted(int(f) for f in next(iter(report["objects"].values()))["frames"])
    for name, source in parts.items():
        obj = report["objects"][name]
        static = not isinstance(source, list)
        assert obj["modifiers"] == ([] if static else ["MESH_SEQUENCE_CACHE"]), (name, obj["modifiers"])
        slots = [m["name"] for m in obj["materials"]]
        assert all(slots) and len(set(slots)) == len(slots), f"{name}: material slots {slots[:8]}"
        for m in obj["materials"]:
            if not m["name"].endswith("_default"):
                np.testing.assert_allclose(m["base_color"], srgb_linear(material_color(m["name"], colors)),
                                           atol=1e-6, err_msg=f"{name}: material {m['name']}")
        faces = None
        for f in frames:
            mesh = read_obj(source if static else source[f - start])
            assert_float32_equal(arrays[f"{name}/co/{f}"], mesh.vertices, f"{name} frame {f}")
            faces = arrays.get(f"{name}/faces/{f}", faces)
            np.testing.assert_array_equal(faces, mesh.faces, err_msg=f"{name} frame {f}: polygons")
            fm = mesh.face_material if mesh.face_material is not None else np.full(mesh.n_faces, -1)
            want = [f"{name}_default" if m < 0 else mesh.materials[m] for m in fm]
            got = [slots[i] for i in arrays[f"{name}/mat/{f}"]] if slots else [f"{name}_default"] * mesh.n_faces
            assert got == want, f"{name} frame {f}: polygon materials differ at polygon " \
                                f"{next(i for i, (a, b) in enumerate(zip(got, want)) if a != b)}"


def make_usd(species: str, quality: str = "draft") -> Path:
    """``make -C pipelines/<species> QUALITY=<quality> usd`` (incremental: quick when current)."""
    env = dict(os.environ, PATH=f"{REPO / '.venv' / 'bin'}{os.pathsep}{os.environ.get('PATH', '')}")
    r = subprocess.run(["make", "-C", str(REPO / "pipelines" / species), f"QUALITY={quality}", "usd"],
                       capture_output=True, text=True, timeout=900, env=env)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    return REPO / "build" / species


@pytest.fixture(scope="module")
def lily_build():
    """build/lily at draft quality with its USD."""
    return make_usd("lily")


def test_lily_usd_in_blender(bpy_python, lily_build, tmp_path):
    from inflo.formats.colors import load_color_file
    from inflo.tools.canopy_render.render import GLUnavailable, RenderOptions, auto_camera, render_meshes

    colors = load_color_file(LILY / "colors.toml")
    parts = {"tepals": list_obj_sequence(lily_build / "canopy"), "column": list_obj_sequence(lily_build / "column_obj")}
    last = [read_obj(p[-1]) for p in parts.values()]
    options = RenderOptions(size=(320, 240), material_colors=colors)
    cam = auto_camera([last], options, azimuth=30.0, elevation=35.0)
    (tmp_path / "cam.json").write_text(json.dumps({"eye": cam.eye, "target": cam.target, "up": cam.up, "fov": cam.fov}))
    png = tmp_path / "blender.png"
    report, arrays = probe(bpy_python, lily_build / "lily.usdc", tmp_path / "probe", "--faces", "--render", png,
                           "--camera", tmp_path / "cam.json", "--size", "320x240", "--samples", "8")
    assert report["blender"].startswith(("4.2", "4.5"))  # the LTS versions the add-on supports
    assert (report["frame_start"], report["frame_end"], report["fps"]) == (1, 100, 24.0)
    assert sorted(report["objects"]) == ["column", "tepals"]
    # Y-up (OBJ) to Z-up (Blender), centimetres to metres: the file's +Y is Blender's +Z, x 0.01
    m = np.array(report["objects"]["tepals"]["matrix_world"])
    np.testing.assert_allclose(m[:3, :3] @ [0, 1, 0], [0, 0, 0.01], atol=1e-8)
    np.testing.assert_allclose(m[:3, :3] @ [1, 0, 0], [0.01, 0, 0], atol=1e-8)
    assert all(f["smooth"] for o in report["objects"].values() for f in o["frames"].values())
    check_frames(report, arrays, parts, colors)
    # the tepals open: frame 100 is not frame 1 (a cache that did not play would pass the above
    # only if the OBJ frames were equal)
    assert not np.array_equal(arrays["tepals/co/1"], arrays["tepals/co/100"])

    # silhouette of the Cycles render vs canopy-render's still through the same camera
    from PIL import Image

    try:
        still = render_meshes(last, cam, options)
    except GLUnavailable as exc:
        pytest.skip(f"Blender part passed; no headless OpenGL for canopy-render's still ({exc})")
    Image.fromarray(still).save(tmp_path / "still.png")
    iou, share = silhouette_iou(png, still)
    assert share > 0.05, "Blender drew (almost) nothing"
    assert iou > 0.9, f"silhouettes differ: intersection over union {iou:.3f}"


def test_obj_frame_in_blender(bpy_python, lily_build, tmp_path):
    from inflo.formats.colors import load_color_file, material_color

    colors = load_color_file(LILY / "colors.toml")
    for folder in ("canopy", "column_obj"):
        path = list_obj_sequence(lily_build / folder)[-1]
        report, _ = probe(bpy_python, path, tmp_path / folder, "--frames", "1")
        (obj,) = report["objects"].values()
        mesh = read_obj(path)
        assert obj["frames"]["1"] == {"vertices": mesh.n_vertices, "polygons": mesh.n_faces, "smooth": True}
        assert [m["name"] for m in obj["materials"]] == mesh.materials
        for m in obj["materials"]:
            np.testing.assert_allclose(m["base_color"], srgb_linear(material_color(m["name"], colors)), atol=2e-6,
                                       err_msg=f"{folder}: {m['name']} (Blender's default grey: no materials.mtl?)")


# the parts of every other species' usd stage, from its species.toml [usd] parts (formats/species.md):
# name -> sequence folder or OBJ file under build/<species>/ (the lily has its own test above)
SPECIES_PARTS = {sp.name: sp.usd_parts for sp in find_species(REPO / "pipelines")
                 if sp.usd_parts and sp.name != "lily"}


@pytest.mark.parametrize("species", sorted(SPECIES_PARTS))
def test_species_usd_in_blender(bpy_python, species, tmp_path):
    """Another species' build/<species>/<species>.usdc, where it has been built (``make
    <species>``; not built from scratch here: minutes each, but brought up to date): first, middle
    and last frame as in the lily test, faces that change (florets emerging) included."""
    from inflo.formats.colors import load_color_file

    build = REPO / "build" / species
    usd = build / f"{species}.usdc"
    if not usd.is_file():
        pytest.skip(f"{usd.relative_to(REPO)} not built (make {species})")
    # brought up to date at the quality it was built at (a stage rerun since would not match)
    make_usd(species, (build / "quality.txt").read_text().strip())
    parts = {name: (build / src if src.endswith(".obj") else list_obj_sequence(build / src))
             for name, src in SPECIES_PARTS[species].items()}
    n = max(len(p) for p in parts.values() if isinstance(p, list))
    frames = sorted({1, n // 2, n})
    report, arrays = probe(bpy_python, usd, tmp_path / "probe", "--faces", "--frames", ",".join(map(str, frames)))
    assert (report["frame_start"], report["frame_end"]) == (1, n)
    assert sorted(report["objects"]) == sorted(parts)
    check_frames(report, arrays, parts, load_color_file(REPO / "pipelines" / species / "colors.toml"), frames)


def _frame(k: int) -> str:
    """Frame k of a two-floret build: floret_1 emerges at frame 2 (faces of mtl4 and of no material
    on vertices 5 and 6, which every frame has, as fccompose writes them); floret_0's first face
    has no usemtl."""
    v = [[0, 0, 0], [1, 0, 0], [1, 1, 0.1234567 * k], [0, 1, 0], [0.5, 1.5, 0.3333333 * k], [1.5, 1.5, 0.25]]
    text = ["g floret_0", "f 1 2 3", "usemtl mtl4", "f 1 3 4"]
    if k >= 2:
        text += ["g floret_1", "usemtl mtl3", "f 3 5 4", "f 3 6 5"]
    return "\n".join([*(f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in v), *text]) + "\n"


def test_changing_faces_in_blender(bpy_python, tmp_path):
    seq = tmp_path / "canopy"
    seq.mkdir()
    for k in range(4):
        (seq / f"frame_{k:04d}.obj").write_text(_frame(k))
    (tmp_path / "colors.toml").write_text('3 = [0.5, 0.25, 1.0]\nmtl4 = "#ff8000"\n')
    out = tmp_path / "grow.usdc"
    r = run_cli("canopy-export", "-q", seq, "--colors", tmp_path / "colors.toml", "--subsets", "floret", "-o", out)
    assert r.returncode == 0, r.stderr
    report, arrays = probe(bpy_python, out, tmp_path / "probe", "--faces")
    assert (report["frame_start"], report["frame_end"]) == (1, 4)
    assert [report["objects"]["canopy"]["frames"][str(f)]["polygons"] for f in (1, 2, 3, 4)] == [2, 2, 4, 4]
    from inflo.formats.colors import load_color_file

    check_frames(report, arrays, {"canopy": list_obj_sequence(seq)}, load_color_file(tmp_path / "colors.toml"))
