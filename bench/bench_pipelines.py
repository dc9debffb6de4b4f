"""Whole species pipelines (issue 8): ``make lily`` and ``make yarrow QUALITY=final``.

Each runs the species Makefile from scratch (``make -B``: every stage rebuilt, numba caches warm)
into the repository's ``build/<species>/`` (the same files ``make lily`` writes), with the
virtual environment's tools first on PATH:

- ``pipeline_lily``: the whole draft lily (key poses to pictures and the exact intersection check);
  anchor: Ijiri et al.'s 11.5 min for their lily; goal under 30 s;
- ``pipeline_lily_fccompose``: the fccompose stage alone, rerun with ``make -W lily.fcc canopy``
  (what-if the parameter file changed); goal under 10 s;
- ``pipeline_yarrow_final``: the whole yarrow at ``QUALITY=final`` (about 350k canopy triangles);
  anchor: the thesis's 60 min for the yarrow canopy alone (table 4.1); goal under 10 min. Skipped
  in ``--quick`` runs (draft quality instead) and while pipelines/yarrow does not exist;
- ``pipeline_sunflower_final``: the whole sunflower at ``QUALITY=final`` (874 florets, about 118k
  canopy triangles, 100 frames, pictures, check and USD export); anchor: the thesis's 10 min
  (CPU/CUDA, table 4.1) for its ~130k-triangle model; goal under 5 min (issue 16), peak memory of
  any stage under 4 GB; ``pipeline_sunflower_final_fccompose``: its canopy stage alone;
- ``pipeline_gaillardia_final``: the whole gaillardia at ``QUALITY=final`` (about 28k canopy
  triangles); anchor: the thesis's 10 min (CUDA, table 4.1) for its ~25k-triangle model; goal under
  2 min (issue 16); ``pipeline_gaillardia_final_fccompose``: its canopy stage alone.
- ``pipeline_dahlia_final``: the whole dahlia at ``QUALITY=final`` (about 29k canopy triangles,
  the ball and the packed variant with and without collisions; thesis table 4.1: 20 min CPU);
  ``pipeline_dahlia_final_fccompose``: the ball's canopy stage alone (goal under 1 min, issue 17).
- ``pipeline_dyssodia_final``: the whole Dyssodia at ``QUALITY=final`` (six heads; thesis table
  4.1: ~100k triangles, 10 min CUDA); ``pipeline_dyssodia_final_fccompose``: its canopy stage
  alone (goal under 3 min, issue 18).
- ``pipeline_orlaya_final``: the whole Orlaya at ``QUALITY=final`` (a compound umbel; thesis table
  4.1: ~120k triangles, 45 min CPU); ``pipeline_orlaya_final_fccompose``: its canopy stage alone
  (goal under 3 min, issue 18).
- ``pipeline_lilac_final``: the whole lilac at ``QUALITY=final`` (a branching-first thyrse; thesis
  table 4.1: ~200k triangles, 120 min CPU); ``pipeline_lilac_final_fccompose``: its canopy stage
  alone (goal under 3 min, issue 20).
"""
from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

from .harness import REPO, BenchContext, Result


def _make(*args: str) -> float:
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    for k in ("MAKEFLAGS", "MAKELEVEL", "MFLAGS", "QUALITY"):
        env.pop(k, None)
    t0 = time.perf_counter()
    res = subprocess.run(["make", "--no-print-directory", *args], cwd=REPO, env=env,
                         capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    if res.returncode != 0:
        raise RuntimeError(f"make {' '.join(args)} failed ({res.returncode}): {res.stderr.strip()[-2000:]}")
    return seconds


def _canopy_size(folder: Path) -> str:
    frames = sorted(folder.glob("frame_*.obj"))
    if not frames:
        return "no canopy frames"
    n_tri = sum(1 for line in frames[-1].open() if line.startswith("f "))
    return f"{n_tri:,} canopy triangles, {len(frames)} canopy frames"


def lily(ctx: BenchContext) -> list[Result]:
    total = _make("-B", "-C", "pipelines/lily", "QUALITY=draft")
    stage = _make("-C", "pipelines/lily", "QUALITY=draft", "-W", "lily.fcc", "canopy")
    size = _canopy_size(REPO / "build" / "lily" / "canopy")
    return [
        Result("pipeline_lily", total, "s", "Ijiri et al. 11.5 min (goal under 30 s, issue 8)", 30.0,
               f"make -B, draft: every stage, pictures and check; {size}"),
        Result("pipeline_lily_fccompose", stage, "s", "goal under 10 s (issue 8)", 10.0,
               "the fccompose stage alone (fresh process)"),
    ]


def yarrow(ctx: BenchContext) -> list[Result]:
    if not (REPO / "pipelines" / "yarrow" / "Makefile").is_file():
        return []
    quality = "draft" if ctx.quick else "final"
    total = _make("-B", "-C", "pipelines/yarrow", f"QUALITY={quality}")
    size = _canopy_size(REPO / "build" / "yarrow" / "canopy")
    return [Result(f"pipeline_yarrow_{quality}", total / 60, "min",
                   "thesis table 4.1: 60 min for the canopy alone (goal under 10 min, issue 8)", 10.0,
                   f"make -B, QUALITY={quality}: every stage; {size}")]


def gaillardia(ctx: BenchContext) -> list[Result]:
    return _species(ctx, "gaillardia", "thesis table 4.1: 10 min (CUDA), ~25k triangles (goal under 2 min, issue 16)",
                    "gaillardia.fcc")


def sunflower(ctx: BenchContext) -> list[Result]:
    return _species(ctx, "sunflower", "thesis table 4.1: 10 min, ~130k triangles (goal under 5 min, issue 16)",
                    "sunflower.fcc")


def dahlia(ctx: BenchContext) -> list[Result]:
    return _species(ctx, "dahlia", "thesis table 4.1: 20 min (CPU), ~30k triangles", "dahlia.fcc",
                    stage_anchor="thesis table 4.1: 20 min (goal under 1 min, issue 17)", stage_goal=1.0)


def dyssodia(ctx: BenchContext) -> list[Result]:
    return _species(ctx, "dyssodia", "thesis table 4.1: 10 min (CUDA), ~100k triangles", "dyssodia.fcc",
                    stage_anchor="thesis table 4.1: 10 min (goal under 3 min, issue 18)", stage_goal=3.0)


def _species(ctx: BenchContext, species: str, anchor: str, fcc: str, *,
             stage_anchor: str = "thesis table 4.1: 10 min", stage_goal: float = 10.0,
             anchor_min: float = 10.0) -> list[Result]:
    if not (REPO / "pipelines" / species / "Makefile").is_file():
        return []
    import resource

    quality = "draft" if ctx.quick else "final"
    total = _make("-B", "-C", f"pipelines/{species}", f"QUALITY={quality}")
    peak_gb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 2 ** 20
    stage = _make("-C", f"pipelines/{species}", f"QUALITY={quality}", "-W", fcc, "canopy")
    size = _canopy_size(REPO / "build" / species / "canopy")
    return [
        Result(f"pipeline_{species}_{quality}", total / 60, "min", anchor, anchor_min,
               f"make -B, QUALITY={quality}: every stage, pictures, check, USD; {size}; peak RSS of a "
               f"stage {peak_gb:.2f} GB (goal under 4 GB)"),
        Result(f"pipeline_{species}_{quality}_fccompose", stage / 60, "min", stage_anchor, stage_goal,
               "the fccompose stage alone (fresh process)"),
    ]


def orlaya(ctx: BenchContext) -> list[Result]:
    return _species(ctx, "orlaya", "thesis table 4.1: 45 min (CPU), ~120k triangles", "orlaya.fcc",
                    stage_anchor="thesis table 4.1: 45 min (goal under 3 min, issue 18)", stage_goal=3.0,
                    anchor_min=45.0)


def lilac(ctx: BenchContext) -> list[Result]:
    return _species(ctx, "lilac", "thesis table 4.1: 120 min (CPU), ~200k triangles", "lilac.fcc",
                    stage_anchor="thesis table 4.1: 120 min (goal under 3 min, issue 20)", stage_goal=3.0,
                    anchor_min=120.0)


BENCHMARKS = [lily, yarrow, sunflower, gaillardia, dahlia, dyssodia, orlaya, lilac]
