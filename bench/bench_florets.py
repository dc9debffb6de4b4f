"""floret-animate + polygonize speed (goal: under 1 s for 100 frames after numba's compile).

Workload: the example disk floret's corolla (pipelines/examples: 5 fused petals, closed bud ->
open), polygonized with the example's kind of lambda(v) and eta(v) functions, refined to about
500 triangles per petal (2,500 per floret), 100 frames.

- ``florets_100_frames_files``: the two stages as library calls with their files: read the two
  key poses, write 100 ``.floret`` frames, read them back, write 100 OBJ files (best of 3, in a
  process whose numba kernels are compiled).
- ``florets_100_frames_memory``: the same computation without files (interpolation, B-spline
  evaluation, welding, quality report), best of 5.
- ``florets_100_frames_cli``: ``floret-animate`` then ``polygonize`` as commands, each in a fresh
  process (Python, numpy/scipy/numba imports and the kernel cache load included), best of 3.
- ``florets_numba_compile``: compiling the interpolation kernels in a fresh process with an empty
  ``NUMBA_CACHE_DIR`` (what the very first run on a machine pays; later runs load the cache).
"""
from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

from inflo.formats.floret import Floret, read_floret, write_floret
from inflo.formats.func import Function, write_func
from inflo.tools.floret_animate.animate import FloretAnimator
from inflo.tools.floret_animate.run import animate_files
from inflo.tools.polygonize.run import polygonize_files, polygonize_frames

from .harness import REPO, BenchContext, Result

ANCHOR = "1 s goal"
EXAMPLES = REPO / "pipelines" / "examples"
LAMBDA_POINTS = [(0, 0.032), (0.6, 0.04), (0.75, 0.032), (1, 0.032)]
ETA_POINTS = [(0, 7), (0.6, 9), (0.8, 15), (1, 3)]


def _poses(workdir: Path) -> list[Path]:
    """The example key poses reduced to the corolla, with the benchmark's sampling."""
    lam, eta = workdir / "lambda.func", workdir / "eta.func"
    write_func(lam, Function.from_points(LAMBDA_POINTS, name="lambda"))
    write_func(eta, Function.from_points(ETA_POINTS, name="eta"))
    out = []
    for name in ("disk_bud", "disk_open"):
        f = read_floret(EXAMPLES / f"{name}.floret")
        corolla = dataclasses.replace(f.organs[0], lambda_=lam.resolve(), eta=eta.resolve())
        p = workdir / f"{name}.floret"
        write_floret(p, Floret(f.name, (corolla,), f.key_time))
        out.append(p)
    return out


def _compile_seconds() -> float:
    code = textwrap.dedent("""
        import time, numpy as np
        t0 = time.perf_counter()
        from inflo.tools.floret_animate.interpolate import blend_polylines
        t1 = time.perf_counter()
        blend_polylines(np.random.rand(2, 5, 3), np.random.rand(2, 5, 3), 0.5)
        t2 = time.perf_counter()
        print(t1 - t0, t2 - t1)
    """)
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                             check=True)
    return float(res.stdout.split()[1])


def florets_100_frames(ctx: BenchContext) -> list[Result]:
    n_frames = 20 if ctx.quick else 100
    poses = _poses(ctx.workdir)
    frames_dir, obj_dir = ctx.workdir / "frames", ctx.workdir / "obj"

    def files():
        animate_files(poses, frames_dir, n_frames=n_frames)
        return polygonize_files(frames_dir, obj_dir)

    files()  # compiles (or loads) the kernels, warms the caches
    t_files, report = ctx.timed(files, repeat=1 if ctx.quick else 3)

    keys = [read_floret(p) for p in poses]

    def memory():
        frames = list(FloretAnimator(keys, poses).frames(n_frames))
        return polygonize_frames(frames)

    t_mem, (meshes, rep) = ctx.timed(memory, repeat=2 if ctx.quick else 5)
    per_petal = rep.n_triangles // 5
    note = (f"{n_frames} frames, 5 fused petals, {rep.n_triangles:,} triangles per floret "
            f"({per_petal} per petal), min angle {rep.min_angle:.1f} deg, "
            f"{rep.under_10_worst} under 10 deg in the worst frame")
    results = [
        Result("florets_100_frames_files", t_files, "s", ANCHOR, 1.0,
               "floret-animate + polygonize as library calls, with all .floret and OBJ files; " + note),
        Result("florets_100_frames_memory", t_mem, "s", ANCHOR, 1.0,
               "the same without files (interpolate, evaluate, weld, report); " + note),
    ]
    cli_times = []
    for _ in range(1 if ctx.quick else 3):
        t0 = time.perf_counter()
        for cmd in (["floret-animate", *map(str, poses), "-o", str(frames_dir), "--frames", str(n_frames), "-q"],
                    ["polygonize", str(frames_dir), "-o", str(obj_dir), "-q"]):
            res = subprocess.run([str(Path(sys.executable).parent / cmd[0]), *cmd[1:]],
                                 capture_output=True, text=True)
            if res.returncode != 0:
                raise RuntimeError(f"{cmd[0]} failed ({res.returncode}): {res.stderr.strip()}")
        cli_times.append(time.perf_counter() - t0)
    results.append(Result("florets_100_frames_cli", min(cli_times), "s", ANCHOR, 1.0,
                          "both commands in fresh processes (interpreter start, imports, numba "
                          "cache load included); " + note))
    if not ctx.quick:
        results.append(Result("florets_numba_compile", _compile_seconds(), "s", "", None,
                              "first compile of the interpolation kernels, fresh process, empty "
                              "NUMBA_CACHE_DIR (paid once; later runs load the cache)"))
    return results


BENCHMARKS = [florets_100_frames]
