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

Issue 51, the ``solver scheme`` (formats/fcc.md, "Solver scheme"): ``schemes_100k`` and
``schemes_350k`` run the same canopy with ``--scheme default`` and ``--scheme fast`` one after the
other in one run (the machine is shared and noisy: compare only within a run), each with the exact
test at every written frame (``sanity check per frames: 25``), and put the quality figures side by
side: intersecting pairs at the written frames, the edge stretch range, florets present, and the
RMS edge and dihedral errors against the templates (mean over the frames; the fast scheme's must
be at most 1.2 x the default's); ``schemes_dyssodia`` does the same on the dyssodia's final
canopy (the pipeline's own parameters and sanity checks). ``cold_start`` times a small scene's
first run with an empty kernel cache and a second (warm) one, process start included.
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

from .harness import REPO, BenchContext, Result


def _cli() -> str:
    return str(Path(sys.executable).parent / "fccompose")


#: fcc lines that turn the crowding work off (``fccompose_100k_no_crowding``)
NO_CROWDING = "relax iterations: 0\nedge stretch bounds: 0.01 100\n"


def _setup(folder: Path, n_florets: int, n_frames: int, run_frames: int, extra: str = "",
           sanity_every: int = 50) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    frames, faces, fixed = opening_floret(n_frames, nu=12, nv=4)
    write_floret_animation(folder / "anim", frames, faces, fixed, folder / "petal_base.txt")
    write_scene(folder / "scene.scn", grid_canopy_scene(n_florets, n_frames))
    write_fcc_text(folder / "canopy.fcc", solver_iterations=50, collision_iterations=10, retries=20,
                   spacing=0.005, frames=run_frames, sanity_every=sanity_every,
                   extra="output animation frames number: 25\n" + extra)
    return folder / "canopy.fcc"


def _run(ctx: BenchContext, name: str, n_florets: int, n_frames: int, run_frames: int, extra: str = "",
         args=()):
    fcc = _setup(ctx.workdir / name, n_florets, n_frames, run_frames, extra)
    out = ctx.workdir / name / "out"
    t0 = time.perf_counter()
    res = subprocess.run([_cli(), str(fcc), "-o", str(out), "-q", *args], capture_output=True, text=True)
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


def _quality(log: Path, n_florets: int) -> dict:
    """The quality figures of a run's ``log.csv`` (issue 51): intersecting pairs at the checked
    frames, edge stretch range, florets present at the end, mean RMS edge / dihedral errors, and
    the s/frame phase sums."""
    with open(log, newline="") as fh:
        rows = list(csv.DictReader(fh))
    body = rows[1:]
    col = lambda k: [float(r[k]) for r in body]
    inter = [int(r["intersecting_pairs"]) for r in rows if int(r["intersecting_pairs"]) >= 0]
    return dict(
        inter=max(inter) if inter else -1, checks=len(inter),
        lo=min(col("min_edge_stretch")), hi=max(col("max_edge_stretch")),
        present=int(rows[-1]["florets_present"]), n=n_florets,
        rms_edge=sum(col("rms_edge_error")) / len(body), rms_dih=sum(col("rms_dihedral_error_deg")) / len(body),
        internal=sum(col("t_internal_s")), collide=sum(col("t_collide_s")), rest=sum(col("t_rest_s")),
        relax=int(sum(col("relax_sweeps"))), rounds=int(sum(col("collision_rounds"))),
    )


def _schemes(ctx: BenchContext, name: str, n_florets: int) -> list[Result]:
    """Today's scheme and ``--scheme fast`` on one canopy, one after the other (same run)."""
    frames = 10 if ctx.quick else 100
    q, sec = {}, {}
    for scheme in ("default", "fast"):
        fcc = _setup(ctx.workdir / name, n_florets, 100, frames, sanity_every=25)
        out = ctx.workdir / name / f"out_{scheme}"
        sec[scheme], _ = _timed([_cli(), str(fcc), "-o", str(out), "-q", "--scheme", scheme])
        q[scheme] = _quality(out / "log.csv", n_florets)
    return _compared(name, q, sec, f"{n_florets * 330:,} triangles, {frames} frames")


def _compared(name: str, q: dict, sec: dict, what: str, goal: str = "") -> list[Result]:
    """The ``_fast`` row (the default's seconds its anchor) and the ``_default`` row of one
    comparison, the quality figures of both side by side in the note."""
    d, f = q["default"], q["fast"]
    ok = (f["inter"] == 0 and 0.5 <= f["lo"] and f["hi"] <= 1.5 and f["present"] == f["n"]
          and f["rms_edge"] <= 1.2 * d["rms_edge"] and f["rms_dih"] <= 1.2 * d["rms_dih"])

    def text(k):
        v = q[k]
        return (f"{k}: {sec[k]:.1f} s (internal {v['internal']:.1f}, collide {v['collide']:.1f}, rest "
                f"{v['rest']:.1f} s; relax sweeps {v['relax']}, rounds {v['rounds']}), intersecting pairs "
                f"{v['inter']} at {v['checks']} checks, stretch {v['lo']:.3f}-{v['hi']:.3f}, florets "
                f"{v['present']}/{v['n']}, RMS edge {v['rms_edge']:.4e}, RMS dihedral {v['rms_dih']:.3f} deg")
    def ratio(k):  # (a --quick run's florets may not bend at all: both errors 0)
        return f"{f[k] / d[k]:.2f}" if d[k] > 0 else ("1 (both 0)" if f[k] == 0 else "n/a (default 0)")

    note = (f"{what}; {text('default')}; {text('fast')}; "
            f"fast/default RMS edge {ratio('rms_edge')}, RMS dihedral {ratio('rms_dih')}; quality held: "
            f"{'yes' if ok else 'NO'}{goal}")
    return [Result(f"{name}_fast", sec["fast"], "s", "--scheme default, same canopy, same run", sec["default"], note),
            Result(f"{name}_default", sec["default"], "s", "", None, "see the _fast row")]


def schemes_100k(ctx: BenchContext) -> list[Result]:
    """``--scheme default`` beside ``--scheme fast`` on the 100k canopy (issue 51 goal: under 20 s)."""
    return _schemes(ctx, "fccompose_scheme_100k", 20 if ctx.quick else 300)


def schemes_350k(ctx: BenchContext) -> list[Result]:
    """``--scheme default`` beside ``--scheme fast`` on the 350k canopy (issue 51 goal: under 60 s)."""
    if ctx.quick:
        return []
    return _schemes(ctx, "fccompose_scheme_350k", 1060)


def _timed(cmd: list, env: dict | None = None, cwd=None) -> tuple[float, float]:
    """Run ``cmd`` (its output captured) under ``env`` (None: this process's) in ``cwd``: (wall
    seconds, CPU seconds); fails on a non-zero exit."""
    t0 = time.perf_counter()
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    res = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=cwd)
    seconds = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if res.returncode != 0:
        raise RuntimeError(f"{Path(cmd[0]).name} failed ({res.returncode}): {res.stderr.strip()}")
    return seconds, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def cold_start(ctx: BenchContext) -> list[Result]:
    """A small scene (20 florets, 10 frames) in a fresh process with an empty kernel cache
    (``NUMBA_CACHE_DIR`` a new folder), then again with that cache warm (issue 51 goals: 20 s of
    compiling at most; warm under 1.5 s, process start included); and a fresh machine after the
    install (``make venv``): the kernels compiled ahead by ``python -m inflo.tools.warm`` into
    another empty cache, then the scene's first run."""
    import os
    import shutil

    fcc = _setup(ctx.workdir / "cold", 20, 10, 10)

    def fresh_env(name):
        cache = ctx.workdir / "cold" / name
        shutil.rmtree(cache, ignore_errors=True)
        return dict(os.environ, NUMBA_CACHE_DIR=str(cache))

    def scene(env, label):
        return _timed([_cli(), str(fcc), "-o", str(ctx.workdir / "cold" / f"out_{label}"), "-q", "--scheme", "fast"],
                      env)

    env = fresh_env("numba_cache")
    out = []
    for label in ("cold", "warm"):
        seconds, cpu = scene(env, label)
        goal = 20.0 if label == "cold" else 1.5
        out.append(Result(f"fccompose_small_{label}_cache", seconds, "s", f"issue 51 goal {goal:g} s", goal,
                          f"6,600 triangles, 10 frames, --scheme fast, fresh process; {cpu:.1f} s CPU (the "
                          "figure to compare on a loaded machine)"
                          + (", empty NUMBA_CACHE_DIR" if label == "cold" else ", the cache the cold run filled")))
    env = fresh_env("numba_cache_installed")
    install, _ = _timed([sys.executable, "-m", "inflo.tools.warm", "-q"], env)
    seconds, _ = scene(env, "installed")
    out.append(Result("fccompose_small_after_install", seconds, "s", "issue 51 goal 20 s (first run, fresh machine)",
                      20.0, f"6,600 triangles, 10 frames, --scheme fast, fresh process, first run after the "
                            f"install's `python -m inflo.tools.warm` ({install:.1f} s, into an empty NUMBA_CACHE_DIR)"))
    out.append(Result("kernels_at_install", install, "s", "", None,
                      "python -m inflo.tools.warm into an empty NUMBA_CACHE_DIR (make venv)"))
    return out

def schemes_dyssodia(ctx: BenchContext) -> list[Result]:
    """``--scheme default`` beside ``--scheme fast`` on the dyssodia's final canopy (issue 51 goal:
    under 2 min): the pipeline's inputs built at final quality (``make -C pipelines/dyssodia
    QUALITY=final obj dimorph``, into ``build/dyssodia/``), then its fccompose stage run both ways
    in a fresh process, outside the build; both must end with every placement of the typed
    scene present."""
    if ctx.quick:
        return []
    from inflo.formats.scn import read_scn
    from inflo.formats.species import read_species

    from .bench_pipelines import _make

    folder = REPO / "pipelines" / "dyssodia"
    frames = int(read_species(folder / "species.toml").setting("final", "frames"))
    _make("-C", str(folder), "QUALITY=final", "obj", "dimorph")
    n = len(read_scn(REPO / "build" / "dyssodia" / "head" / "typed.scn").placements)
    q, sec = {}, {}
    for scheme in ("default", "fast"):
        out = ctx.workdir / "schemes_dyssodia" / f"out_{scheme}"
        sec[scheme], _ = _timed([_cli(), "-q", "dyssodia.fcc", "--frames", str(frames - 1), "--scheme", scheme,
                                 "-o", str(out)], cwd=folder)
        q[scheme] = _quality(out / "log.csv", n)
    return _compared("fccompose_scheme_dyssodia", q, sec, f"the dyssodia's final canopy, {frames} frames",
                     f"; issue 51 goal under 2 min: {'met' if sec['fast'] < 120.0 else 'not met'}")


BENCHMARKS = [growth, dense_head, schemes_100k, schemes_350k, schemes_dyssodia, cold_start]
