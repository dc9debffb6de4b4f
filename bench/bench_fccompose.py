"""Whole-canopy growth with collisions (thesis table 4.1).

A synthetic canopy of identical 5-petal florets (:mod:`inflo.tools.testing.florets`, 330
triangles each) on a jittered grid, opening over the frames so that neighbours' petals meet;
``fccompose`` runs end to end in a fresh process (reading, growth, CCD, collision response, sanity
checks every 50 frames, an OBJ every 25 frames):

- ``fccompose_100k``: 300 florets (99,000 triangles), 100 frames;
- ``fccompose_100k_no_crowding``: the same 100k canopy with the crowding work off
  (``relax iterations: 0``, ``edge stretch bounds: 0.01 100``): the florets are then squeezed to
  a few per cent of their edge lengths and stretched several times over, as before that work; the
  difference to ``fccompose_100k`` is what keeping every edge within [0.5, 1.5] x rest costs here
  (the engine itself measured alone: "not slower by more than 10 %");
- ``fccompose_350k``: 1,060 florets (349,800 triangles), the thesis's yarrow size (60 min in
  table 4.1; goal under 6 min on this 2-core machine, memory under 4 GB), 100 frames. (``_run``
  can extrapolate from fewer frames, but collisions start only once the petals open, so the
  early frames' rate underestimates the run.)

Each reports seconds, and ``triangles x steps / s`` so the trend with size is visible; the peak
memory of the process is in the note.
"""
from __future__ import annotations

import csv
import resource
import subprocess
import sys
import time
from pathlib import Path

from inflo.tools.testing.florets import (
    grid_canopy_scene,
    opening_floret,
    write_fcc_text,
    write_floret_animation,
    write_scene,
)

from .harness import BenchContext, Result


def _cli() -> str:
    return str(Path(sys.executable).parent / "fccompose")


#: fcc lines that turn the crowding work off (``fccompose_100k_no_crowding``)
NO_CROWDING = "relax iterations: 0\nedge stretch bounds: 0.01 100\n"


def _setup(folder: Path, n_florets: int, n_frames: int, run_frames: int, extra: str = "") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    frames, faces, fixed = opening_floret(n_frames, nu=12, nv=4)
    write_floret_animation(folder / "anim", frames, faces, fixed, folder / "petal_base.txt")
    write_scene(folder / "scene.scn", grid_canopy_scene(n_florets, n_frames))
    write_fcc_text(folder / "canopy.fcc", solver_iterations=50, collision_iterations=10, retries=20,
                   spacing=0.005, frames=run_frames, sanity_every=50,
                   extra="output animation frames number: 25\n" + extra)
    return folder / "canopy.fcc"


def _run(ctx: BenchContext, name: str, n_florets: int, n_frames: int, run_frames: int, extra: str = ""):
    fcc = _setup(ctx.workdir / name, n_florets, n_frames, run_frames, extra)
    out = ctx.workdir / name / "out"
    t0 = time.perf_counter()
    res = subprocess.run([_cli(), str(fcc), "-o", str(out), "-q"], capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    if res.returncode != 0:
        raise RuntimeError(f"fccompose failed ({res.returncode}): {res.stderr.strip()}")
    peak_gb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 2 ** 20  # KiB -> GiB
    with open(out / "log.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    found = sum(int(r["collisions_found"]) for r in rows)
    left = sum(int(r["remaining_pairs"]) for r in rows)
    inter = [int(r["intersecting_pairs"]) for r in rows if int(r["intersecting_pairs"]) >= 0]
    tris = n_florets * 330
    steps = len(rows) - 1
    per_frame = {k: sum(float(r[f"t_{k}_s"]) for r in rows[1:]) / max(steps, 1)
                 for k in ("rest", "internal", "collide", "sanity", "write")}
    phase = ", ".join(f"{k} {v:.3f}" for k, v in per_frame.items())
    lo = min(float(r["min_edge_stretch"]) for r in rows[1:])
    hi = max(float(r["max_edge_stretch"]) for r in rows[1:])
    out_of = sum(1 for r in rows[1:] if float(r["min_edge_stretch"]) < 0.5 or float(r["max_edge_stretch"]) > 1.5)
    note = (f"{tris:,} triangles, {steps} frames; {found} collisions found, {left} left after retries, "
            f"intersecting pairs at sanity checks {max(inter) if inter else 'n/a'}; edge stretch "
            f"{lo:.2f}-{hi:.2f}, {out_of} frames outside [0.5, 1.5]; peak memory "
            f"{peak_gb:.2f} GB (max over benchmark subprocesses so far); s/frame by phase: {phase}")
    return seconds, tris, steps, note


def growth(ctx: BenchContext) -> list[Result]:
    out = []
    if ctx.quick:
        cases = [("fccompose_quick", 20, 10, 10, None, "")]
    else:
        cases = [("fccompose_100k", 300, 100, 100, None, ""),
                 ("fccompose_100k_no_crowding", 300, 100, 100, None, NO_CROWDING),
                 ("fccompose_350k", 1060, 100, 100, None, "")]
    for name, n_fl, n_frames, run_frames, extrapolate, extra in cases:
        seconds, tris, steps, note = _run(ctx, name, n_fl, n_frames, run_frames, extra)
        rate = tris * steps / seconds
        if extrapolate:
            per_frame = seconds / steps
            est = per_frame * extrapolate
            out.append(Result(f"{name}_growth", est / 60, "min", "6 min goal; thesis 60 min (table 4.1)",
                              6.0, f"extrapolated to {extrapolate} frames from {steps} frames in {seconds:.0f} s "
                                   f"(incl. start-up); " + note))
        else:
            big = n_fl >= 1000
            out.append(Result(f"{name}_growth", seconds / 60, "min",
                              "6 min goal; thesis 60 min (table 4.1)" if big else
                              ("thesis table 4.1 (350k tri: 60 min)" if not ctx.quick else ""),
                              6.0 if big else None, note))
        out.append(Result(f"{name}_rate", rate, "triangles*steps/s", "", None, f"{tris:,} triangles x {steps} steps"))
    return out


def dense_head(ctx: BenchContext) -> list[Result]:
    """The dense growing head of ``pipelines/examples/growing_head``: 278 florets of a
    dynamic phyllotaxis with the phase effect, 77,840 triangles, 80 frames; its fccompose stage
    timed, with the crowding figures of its log (edge stretch, florets present). (Before
    2026-12-01 the floret had 5 vertices on its lobe-tip rows too, 320 triangles: 88,960.)"""
    if ctx.quick:
        return []
    bin_dir = Path(sys.executable).parent
    repo = Path(__file__).resolve().parent.parent
    ex = repo / "pipelines" / "examples"
    d = ctx.workdir / "dense_head"
    d.mkdir(parents=True, exist_ok=True)
    run = lambda *a: subprocess.run([str(bin_dir / a[0]), *map(str, a[1:]), "-q"], check=True)
    run("phyllotaxis", ex / "phyllotaxis" / "dense_head.toml", "-o", d / "head")
    run("floret-animate", ex / "disk_bud.floret", ex / "disk_open.floret", "--frames", 30, "-o", d / "frames")
    run("polygonize", d / "frames", "--lambda", 0.25, "--eta", ex / "growing_head" / "lobe_eta.func",
        "-o", d / "obj")
    # the example's .fcc, its paths pointed at this folder
    text = (ex / "growing_head" / "growing.fcc").read_text()
    text = text.replace("../../../build/examples/growing_head/", f"{d}/").replace(
        "weight: 0 floret.weights", f"weight: 0 {ex / 'growing_head' / 'floret.weights'}")
    (d / "growing.fcc").write_text(text)
    out = d / "canopy"
    t0 = time.perf_counter()
    res = subprocess.run([_cli(), str(d / "growing.fcc"), "-o", str(out), "-q"], capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    if res.returncode != 0:
        raise RuntimeError(f"fccompose failed ({res.returncode}): {res.stderr.strip()}")
    with open(out / "log.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    lo = min(float(r["min_edge_stretch"]) for r in rows)
    hi = max(float(r["max_edge_stretch"]) for r in rows)
    outside = sum(float(r["min_edge_stretch"]) < 0.5 or float(r["max_edge_stretch"]) > 1.5 for r in rows)
    inter = [int(r["intersecting_pairs"]) for r in rows if int(r["intersecting_pairs"]) >= 0]
    n_tri = sum(1 for line in open(out / f"frame_{len(rows) - 1:04d}.obj") if line.startswith("f "))
    note = (f"{n_tri:,} triangles, {len(rows) - 1} frames; {sum(int(r['collisions_found']) for r in rows)} "
            f"collisions found, {sum(int(r['remaining_pairs']) for r in rows)} left; intersecting pairs at "
            f"sanity checks {max(inter) if inter else 'n/a'}; edge stretch {lo:.2f}-{hi:.2f}, {outside} frames "
            f"outside [0.5, 1.5]; florets present at the end {rows[-1]['florets_present']}, waiting "
            f"{rows[-1]['florets_waiting']}; florets retreated {sum(int(r['florets_retreated']) for r in rows)}")
    return [Result("fccompose_dense_head", seconds / 60, "min", "", None, note)]


BENCHMARKS = [growth, dense_head]
