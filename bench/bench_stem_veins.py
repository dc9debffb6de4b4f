"""stem-veins (Runions ch. 6): the vascular pattern of a stem of 50 primordia at the golden angle.

- ``stem_veins_50_primordia``: the closed model of pipelines/examples/stem_veins/golden_5_8.toml
  (R = 23 D, H = 2 D, plastochron 6) with 50 primordia, the simulation alone (no files); the note
  gives the vein nodes, iterations, the connectivity and the share of Fibonacci joins;
- ``stem_veins_open_50_primordia``: the same stem with the open model.

The thesis gives no time for its stem model (vv with CGAL's 3-D Delaunay triangulation); the goal
is a minute on 2 cores.
"""
from __future__ import annotations

import time
from dataclasses import replace

from inflo.tools.stem_veins.model import simulate
from inflo.tools.stem_veins.output import connectivity
from inflo.tools.stem_veins.params import read_params

from .harness import REPO, BenchContext, Result

EXAMPLE = REPO / "pipelines" / "examples" / "stem_veins" / "golden_5_8.toml"


def _stem(ctx: BenchContext, label: str, pattern: str) -> list[Result]:
    p = read_params(EXAMPLE)
    simulate(replace(p.model, count=3, pattern=pattern))  # compile
    model = replace(p.model, count=20 if ctx.quick else 50, pattern=pattern)
    t = time.perf_counter()
    run = simulate(model)
    seconds = time.perf_counter() - t
    c = connectivity(run, skip=3)
    mode = f"({c['mode'][0]}, {c['mode'][1]})" if c["mode"] else "none"
    note = (f"{model.count} primordia, {len(run.pos)} vein nodes, {len(run.edges)} segments, {run.iterations} "
            f"iterations; joins by difference {dict(sorted(c['differences'].items()))}, connectivity {mode}, "
            f"Fibonacci share {c['fibonacci_share']:.2f}")
    return [Result(f"stem_veins_{label}_primordia", seconds, "s", "goal 60 s on 2 cores", 60.0, note)]


def closed(ctx: BenchContext) -> list[Result]:
    return _stem(ctx, "50" if not ctx.quick else "20", "closed")


def open_pattern(ctx: BenchContext) -> list[Result]:
    return _stem(ctx, "open_50" if not ctx.quick else "open_20", "open")


BENCHMARKS = [closed, open_pattern]
