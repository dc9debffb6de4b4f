"""canopy-render speed: a 400k-triangle synthetic canopy to PNG (goal: under 10 s).

- ``render_400k_triangles_cli``: the ``canopy-render`` command end to end in a fresh process
  (imports, GL context, reading the 15 MB OBJ, framing, drawing, PNG), best of 3.
- ``render_400k_triangles_warm``: :meth:`Renderer.render` of the same mesh, already read, in a
  process whose GL context and shaders exist (what each later frame of a sequence costs), best of 5.
- ``render_400k_triangles_first``: the first frame of a fresh :class:`Renderer` in this process
  (context creation, shader compilation, first upload).

The mesh is :func:`inflo.tools.testing.flowers.canopy`: 50 heads of 20 curved petals, 401,200
triangles, two materials, rendered at 1024x768 with 4x multisampling.
"""
from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

from inflo.formats.obj import write_obj
from inflo.tools.canopy_render.camera import fit_camera
from inflo.tools.canopy_render.render import Renderer, RenderOptions, scene_points
from inflo.tools.testing.flowers import canopy

from .harness import BenchContext, Result

ANCHOR = "10 s goal"


def _cli() -> str:
    return str(Path(sys.executable).parent / "canopy-render")


def render_400k(ctx: BenchContext) -> list[Result]:
    mesh = canopy(10 if ctx.quick else 50)
    n_tri = mesh.n_faces
    obj = ctx.workdir / "canopy.obj"
    out = ctx.workdir / "canopy.png"
    write_obj(obj, mesh)
    note = f"{n_tri:,} triangles, 1024x768, 4x MSAA, llvmpipe"

    cli_times = []
    for _ in range(1 if ctx.quick else 3):
        t0 = time.perf_counter()
        res = subprocess.run([_cli(), str(obj), "-o", str(out), "-q"], capture_output=True, text=True)
        cli_times.append(time.perf_counter() - t0)
        if res.returncode != 0:
            raise RuntimeError(f"canopy-render failed ({res.returncode}): {res.stderr.strip()}")

    opts = RenderOptions(size=(1024, 768))
    cam = fit_camera(scene_points([mesh]), aspect=1024 / 768)
    t0 = time.perf_counter()
    renderer = Renderer()
    renderer.render([mesh], cam, opts)
    t_first = time.perf_counter() - t0
    try:
        t_warm, _ = ctx.timed(renderer.render, [mesh], cam, opts, repeat=2 if ctx.quick else 5)
        info = renderer.info
    finally:
        renderer.release()
    return [
        Result("render_400k_triangles_cli", min(cli_times), "s", ANCHOR, 10.0,
               f"canopy-render OBJ -> PNG in a fresh process (read {obj.stat().st_size / 1e6:.0f} MB OBJ included); {note}"),
        Result("render_400k_triangles_warm", t_warm, "s", ANCHOR, 10.0,
               f"Renderer.render, context and shaders warm (per frame of a sequence); {note}; {info}"),
        Result("render_400k_triangles_first", t_first, "s", ANCHOR, 10.0,
               f"new Renderer + first frame in a warm process; {note}"),
    ]


BENCHMARKS = [render_400k]
