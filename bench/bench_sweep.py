"""inflo-sweep: the canalization sweep's throughput (heads per second) on 1 vs 2 Dask
workers, and a small yarrow-variants sweep's wall time against the same builds one after another.

- ``sweep_canalization_heads_per_s_1w`` / ``_2w``: pipelines/examples/sweeps/canalization.toml
  on a slice of its grid (n 10..1000 step 10 x alpha 20..160 step 20 = 800 heads; quick: step 40
  x 4 angles = 100 heads), ``phyllotaxis`` + ``dimorph`` per head, in the workers' processes,
  batched; wall time of the whole ``inflo-sweep`` command (cluster start included);
- ``sweep_canalization_speedup_2w``: the ratio (anchor: 2.0 = linear on 2 cores);
- ``sweep_yarrow_2w_vs_serial`` (skipped in quick mode: four draft yarrow builds are minutes):
  the wall time of yarrow_variants.toml on 2 workers over the sum of its variants' own times.

Anchor: the goal of using the machine's cores; 2.0 = perfect scaling on 2 workers.
"""
from __future__ import annotations

import csv
import subprocess
import sys
import time
from pathlib import Path

from .harness import REPO, BenchContext, Result

EXAMPLES = REPO / "pipelines" / "examples" / "sweeps"
CLI = str(Path(sys.executable).parent / "inflo-sweep")


def _canalization_file(ctx: BenchContext) -> Path:
    text = (EXAMPLES / "canalization.toml").read_text()
    if ctx.quick:
        text = text.replace("range = [10, 1000, 10]", "range = [10, 1000, 40]").replace(
            "range = [20, 160, 10]", "range = [20, 160, 40]")
    else:
        text = text.replace("range = [20, 160, 10]", "range = [20, 160, 20]")
    d = ctx.workdir / "sweep"
    d.mkdir(parents=True, exist_ok=True)
    (d / "vogel.toml").write_text((EXAMPLES / "vogel.toml").read_text())
    p = d / "canalization.toml"
    p.write_text(text)
    return p


def _run(sweep: Path, out: Path, workers: int) -> tuple[float, list[dict]]:
    t0 = time.perf_counter()
    subprocess.run([CLI, str(sweep), "-o", str(out), "--workers", str(workers), "--dashboard", ":0", "-q",
                    "--force"], check=False, capture_output=True, text=True, timeout=3600)
    dt = time.perf_counter() - t0
    with open(out / "results.csv", newline="") as fh:
        return dt, list(csv.DictReader(fh))


def canalization(ctx: BenchContext) -> list[Result]:
    sweep = _canalization_file(ctx)
    out = []
    rates = {}
    for w in (1, 2):
        dt, rows = _run(sweep, ctx.workdir / f"canalization_{w}w", w)
        ok = sum(r["status"] == "ok" for r in rows)
        rates[w] = ok / dt
        fib = sum(r["rays"] in {"1", "2", "3", "5", "8", "13", "21", "34", "55", "89", "144", "233"} for r in rows)
        out.append(Result(f"sweep_canalization_heads_per_s_{w}w", rates[w], "heads/s", "", None,
                          f"{ok} of {len(rows)} heads in {dt:.1f} s on {w} worker(s) (cluster start included); "
                          f"{fib} ray counts are Fibonacci numbers"))
    out.append(Result("sweep_canalization_speedup_2w", rates[2] / rates[1], "x",
                      "2.0 = linear on 2 workers", 2.0, "heads/s on 2 workers over 1"))
    return out


def yarrow(ctx: BenchContext) -> list[Result]:
    if ctx.quick:
        return []
    outdir = ctx.workdir / "yarrow_variants"
    dt, rows = _run(EXAMPLES / "yarrow_variants.toml", outdir, 2)
    serial = sum(float(r["wall_s"]) for r in rows)
    return [Result("sweep_yarrow_2w_vs_serial", dt / serial if serial else float("nan"), "x",
                   "0.5 = two builds at a time", 0.5,
                   f"{len(rows)} draft yarrows: {dt:.0f} s on 2 workers, {serial:.0f} s one after another "
                   "(the sum of the variants' own times)")]


BENCHMARKS = [canalization, yarrow]
