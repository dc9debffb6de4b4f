"""Whole species pipelines: every species of ``pipelines/`` with a ``[bench]`` table in its
species.toml (formats/species.md), found, not listed.

Each runs the species Makefile from scratch (``make -B``: every stage rebuilt, numba caches warm)
into the repository's ``build/<species>/`` (the same files ``make <species>`` writes), with the
virtual environment's tools first on PATH, at the table's ``quality`` (``final`` by default; every
species at ``draft`` in ``--quick`` runs):

- ``pipeline_<species>_<quality>`` (or the table's ``row``): the whole build, every stage,
  pictures, check and USD, against the table's ``anchor`` (``anchor_value`` in its ``unit``): the
  thesis's table 4.1 times for the heads, umbels, corymb and lilac, Ijiri et al.'s for the lily and
  Eustoma; the note gives the canopy's size and the peak memory of a stage;
- ``..._fccompose``, where the table names ``stage_fcc``: the fccompose stage alone, rerun with
  ``make -W <stage_fcc> canopy`` (what-if the parameter file changed), against ``stage_goal``.
"""
from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

from inflo.formats.species import find_species

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


def _canopy_rows(ctx: BenchContext, sp) -> list[Result]:
    import resource

    b = sp.bench
    quality = "draft" if ctx.quick else b.get("quality", "final")
    unit = b.get("unit", "min")
    scale = 60.0 if unit == "min" else 1.0
    row = b.get("row", f"pipeline_{sp.name}_{quality}")
    folder = f"pipelines/{sp.name}"
    total = _make("-B", "-C", folder, f"QUALITY={quality}")
    peak_gb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 2 ** 20
    size = _canopy_size(REPO / "build" / sp.name / "canopy")
    out = [Result(row, total / scale, unit, b["anchor"], float(b["anchor_value"]),
                  f"make -B, QUALITY={quality}: every stage, pictures, check, USD; {size}; peak RSS of a "
                  f"stage {peak_gb:.2f} GB")]
    if "stage_fcc" in b:
        stage = _make("-C", folder, f"QUALITY={quality}", "-W", b["stage_fcc"], b.get("stage_target", "canopy"))
        out.append(Result(f"{row}_fccompose", stage / scale, unit, b.get("stage_anchor", b["anchor"]),
                          float(b.get("stage_goal", b["anchor_value"])), "the fccompose stage alone (fresh process)"))
    return out


def _benchmark(sp):
    """One benchmark per species, named after it (``python -m bench.run -k lily``)."""
    def run(ctx: BenchContext) -> list[Result]:
        return _canopy_rows(ctx, sp)

    run.__name__ = run.__qualname__ = sp.name
    return run


def _plant(species: str):
    """``pipeline_<species>_plant``: the plant target alone (``make -C pipelines/<species> plant``:
    the stem, leaves and pedicels, the flowers placed from the built species frames, the exact check
    of every frame, pictures and USD), its folder removed first; the species' own build is made
    first (untimed) when it is not there. Goal: under a minute beyond the species' build."""
    def run(ctx: BenchContext) -> list[Result]:
        import shutil

        quality = "draft" if ctx.quick else "final"
        _make("-C", f"pipelines/{species}", f"QUALITY={quality}")  # the flowers (untimed; no-op when built)
        shutil.rmtree(REPO / "build" / f"{species}_plant", ignore_errors=True)
        seconds = _make("-C", f"pipelines/{species}", f"QUALITY={quality}", "plant")
        check = (REPO / "build" / f"{species}_plant" / "check.txt").read_text().strip().splitlines()
        return [Result(f"pipeline_{species}_plant", seconds, "s", "goal 60 s beyond the species' build", 60.0,
                       f"QUALITY={quality}; " + (check[-1] if check else ""))]

    run.__name__ = run.__qualname__ = f"{species}_plant"
    return run


BENCHMARKS = [_benchmark(sp) for sp in find_species(REPO / "pipelines") if sp.bench] + [
    _plant("lily"), _plant("eustoma")]
