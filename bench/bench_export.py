"""canopy-export: USD export time and size against the OBJ sequences; Blender import.

- ``export_lily``: the draft lily's ``lily.usdc`` (tepals and column, 100 frames) from
  ``build/lily`` (built with ``make -C pipelines/lily usd`` when missing): export seconds and the
  file's size, against the OBJ sequences' size (ratio: USD / OBJ bytes).
- ``export_350k``: a synthetic canopy of the yarrow's size, 1,060 five-petal florets of 330
  triangles (349,800 triangles; :mod:`inflo.tools.testing.florets`, placed on a grid, one
  ``g`` group and material per floret as fccompose writes them), over ``FRAMES_350K`` frames
  (10; 2 with ``--quick``): export seconds against writing the same OBJ frames, and the size
  against the OBJ frames'. The note extrapolates both to 100 frames (points are per frame, the
  faces once, so both grow linearly).
- ``export_glb_lily``, ``export_glb_head``, ``export_glb_350k``: the same as one binary glTF
  (``.glb``, morph targets, 16-bit quantized; formats/gltf.md): the draft lily, a draft head (the
  gaillardia's canopy, ``make -C pipelines/gaillardia canopy`` when missing) and the synthetic
  350k canopy; seconds and the file's size against the goals (lily 4 MB, a draft head 20 MB).
- ``blender_import_*``: when a Python with ``bpy`` is found (``make test-blender`` makes
  ``.venv-blender``), the seconds Blender 4.5 takes to import each USD file
  (``bpy.ops.wm.usd_import``) and, in the note, to evaluate every frame through its Mesh
  Sequence Cache (``tools/canopy_export/blender_probe.py``); skipped otherwise.
"""
from __future__ import annotations

import json
import os
import subprocess
import time
from pathlib import Path

import numpy as np

from inflo.formats.obj import ObjMesh, list_obj_sequence, write_obj
from inflo.tools.canopy_export.export import ExportOptions, export_canopy
from inflo.tools.canopy_export.parts import resolve_parts
from inflo.tools.testing.florets import opening_floret

from .harness import BenchContext, Result

REPO = Path(__file__).resolve().parent.parent
FRAMES_350K = 10
N_FLORETS = 1060


def _blender_python() -> str | None:
    exe = os.environ.get("INFLO_BLENDER_PYTHON") or str(REPO / ".venv-blender" / "bin" / "python")
    if not Path(exe).exists():
        return None
    return exe if subprocess.run([exe, "-c", "import bpy"], capture_output=True).returncode == 0 else None


def _blender(ctx: BenchContext, name: str, usd: Path, n_frames: int) -> list[Result]:
    exe = _blender_python()
    if exe is None:
        return []
    stem = ctx.workdir / f"{name}_probe"
    r = subprocess.run([exe, str(REPO / "tools" / "canopy_export" / "blender_probe.py"), str(usd), "-o", str(stem),
                        "--no-arrays"],
                       capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"blender_probe failed: {r.stderr.strip()[-500:]}")
    rep = json.loads(Path(f"{stem}.json").read_text())
    return [Result(f"blender_import_{name}", rep["seconds_import"], "s", "", None,
                   f"Blender {rep['blender']} usd_import of {usd.name}; evaluating all {n_frames} frames "
                   f"(Mesh Sequence Cache) {rep['seconds_frames']:.2f} s")]


def _size(paths) -> int:
    return sum(Path(p).stat().st_size for p in paths)


def export_lily(ctx: BenchContext) -> list[Result]:
    build = REPO / "build" / "lily"
    if not (build / "column_obj").is_dir() or not list_obj_sequence(build / "canopy"):
        subprocess.run(["make", "-C", str(REPO / "pipelines" / "lily"), "QUALITY=draft", "canopy", "column"],
                       check=True, capture_output=True)
    parts = resolve_parts([f"tepals={build / 'canopy'}", f"column={build / 'column_obj'}"])
    out = ctx.workdir / "lily.usdc"
    seconds, report = ctx.timed(export_canopy, parts, out, options=ExportOptions(), repeat=2)
    obj_bytes = _size(p for part in parts for p in part.paths)
    note = (f"{report.n_frames} frames, tepals + column; OBJ sequences {obj_bytes / 1e6:.1f} MB, "
            f"USD {report.n_bytes / 1e6:.2f} MB")
    return [
        Result("export_lily", seconds, "s", "", None, note),
        Result("export_lily_size", report.n_bytes / 1e6, "MB", "the OBJ sequences' size", obj_bytes / 1e6, note),
        *_blender(ctx, "lily", out, report.n_frames),
    ]


def _synthetic_350k(ctx: BenchContext):
    """The synthetic yarrow-sized canopy's OBJ frames; returns (folder, seconds writing them, triangles)."""
    n_frames = 2 if ctx.quick else FRAMES_350K
    n_fl = 60 if ctx.quick else N_FLORETS
    frames, faces, _ = opening_floret(n_frames, nu=12, nv=4)
    side = int(np.ceil(np.sqrt(n_fl)))
    offsets = np.array([(1.6 * (i % side), 0.0, 1.6 * (i // side)) for i in range(n_fl)])
    nv = len(frames[0])
    all_faces = np.vstack([faces + k * nv for k in range(n_fl)])
    groups = [f"floret_{k}" for k in range(n_fl)]
    face_group = np.repeat(np.arange(n_fl, dtype=np.int32), len(faces))
    face_material = np.repeat((np.arange(n_fl, dtype=np.int32) % 3), len(faces))
    seq = ctx.workdir / "canopy_350k"
    seq.mkdir(parents=True, exist_ok=True)
    t_obj = 0.0
    for k, v in enumerate(frames):
        mesh = ObjMesh((v[None, :, :] + offsets[:, None, :]).reshape(-1, 3), all_faces, groups=groups,
                       face_group=face_group, materials=["mtl1", "mtl2", "mtl3"], face_material=face_material)
        t0 = time.perf_counter()
        write_obj(seq / f"frame_{k:04d}.obj", mesh)
        t_obj += time.perf_counter() - t0
    return seq, t_obj, len(all_faces)


def export_350k(ctx: BenchContext) -> list[Result]:
    n_frames = 2 if ctx.quick else FRAMES_350K
    seq, t_obj, tris = _synthetic_350k(ctx)
    parts = resolve_parts([str(seq)])
    out = ctx.workdir / "canopy_350k.usdc"
    seconds, report = ctx.timed(export_canopy, parts, out, options=ExportOptions())
    obj_bytes = _size(parts[0].paths)
    scale = 100 / n_frames
    note = (f"{tris:,} triangles x {n_frames} frames; OBJ {obj_bytes / 1e6:.0f} MB, USD {report.n_bytes / 1e6:.1f} MB; "
            f"at 100 frames about: export {seconds * scale:.0f} s, USD {report.n_bytes * scale / 1e9:.2f} GB, "
            f"OBJ {obj_bytes * scale / 1e9:.2f} GB")
    name = "export_350k" if not ctx.quick else "export_quick"
    return [
        Result(name, seconds, "s", "writing the same OBJ frames (same run)", t_obj, note),
        Result(f"{name}_size", report.n_bytes / 1e6, "MB", "the OBJ frames' size", obj_bytes / 1e6, note),
        *_blender(ctx, "350k" if not ctx.quick else "quick", out, n_frames),
    ]


def _glb(ctx: BenchContext, name: str, specs: list[str], goal_mb: float | None, what: str) -> list[Result]:
    parts = resolve_parts(specs)
    out = ctx.workdir / f"{name}.glb"
    seconds, report = ctx.timed(export_canopy, parts, out, options=ExportOptions(), repeat=2 if goal_mb else 1)
    obj_bytes = _size(p for part in parts for p in part.paths)
    note = (f"{what}: {report.n_frames} frames; OBJ {obj_bytes / 1e6:.1f} MB, .glb {report.n_bytes / 1e6:.2f} MB "
            f"(16-bit quantized morph targets)")
    size = Result(f"export_glb_{name}_size", report.n_bytes / 1e6, "MB", "the goal" if goal_mb else "", goal_mb, note)
    return [Result(f"export_glb_{name}", seconds, "s", "", None, note), size]


def export_glb_lily(ctx: BenchContext) -> list[Result]:
    build = REPO / "build" / "lily"
    if not (build / "column_obj").is_dir() or not list_obj_sequence(build / "canopy"):
        subprocess.run(["make", "-C", str(REPO / "pipelines" / "lily"), "QUALITY=draft", "canopy", "column"],
                       check=True, capture_output=True)
    return _glb(ctx, "lily", [f"tepals={build / 'canopy'}", f"column={build / 'column_obj'}"], 4.0, "draft lily")


def export_glb_head(ctx: BenchContext) -> list[Result]:
    build = REPO / "build" / "gaillardia"
    quality = (build / "quality.txt").read_text().strip() if (build / "quality.txt").exists() else ""
    if quality != "draft" or not (build / "canopy").is_dir():
        subprocess.run(["make", "-C", str(REPO / "pipelines" / "gaillardia"), "QUALITY=draft", "canopy"],
                       check=True, capture_output=True)
    return _glb(ctx, "head", [f"florets={build / 'canopy'}"], 20.0, "draft gaillardia head")


def export_glb_350k(ctx: BenchContext) -> list[Result]:
    seq, _, tris = _synthetic_350k(ctx)
    return _glb(ctx, "350k" if not ctx.quick else "quick", [str(seq)], None, f"synthetic canopy, {tris:,} triangles")


BENCHMARKS = [export_lily, export_350k, export_glb_lily, export_glb_head, export_glb_350k]
