"""subdivide: two Loop levels with collision handling on a ~100k-triangle canopy (goal: 30 s).

The canopy: 420 open synthetic 5-petal florets (:mod:`inflo.tools.testing.florets`, 240
triangles each, 100,800 in all) on a jittered grid, neighbours' petal tips a few percent of a petal
apart (collision-free by the exact test); two levels give 1.6M triangles. Reports the library time (operators + Loop positions +
CCD and collision constraints per level), the collision constraints each level needed (the thesis
says few), and the exact static intersection count of the result.
"""
from __future__ import annotations

import math

import numpy as np

from inflo.tools.collide import intersecting_pairs
from inflo.tools.subdivide.collisions import collision_resolver
from inflo.tools.subdivide.smooth import plan_subdivision, subdivide_frames
from inflo.tools.testing.florets import opening_floret

from .harness import BenchContext, Result


def _canopy(n_florets: int, spacing: float = 2.7, seed: int = 0):
    frames, faces, _ = opening_floret(2)
    local = frames[-1]
    rng = np.random.default_rng(seed)
    side = int(math.ceil(math.sqrt(n_florets)))
    verts, tris = [], []
    for k in range(n_florets):
        i, j = divmod(k, side)
        phi = rng.uniform(0, 2 * math.pi)
        c, s = math.cos(phi), math.sin(phi)
        R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
        verts.append(local @ R.T + [i * spacing + rng.uniform(-0.05, 0.05), rng.uniform(0, 0.1),
                                    j * spacing + rng.uniform(-0.05, 0.05)])
        tris.append(faces + k * len(local))
    return np.concatenate(verts), np.concatenate(tris).astype(np.int32)


def subdivide_100k_two_levels(ctx: BenchContext) -> list[Result]:
    V, F = _canopy(40 if ctx.quick else 420)
    assert len(intersecting_pairs(V, F)) == 0
    resolve = collision_resolver(spacing=0.002)

    def run():
        plan = plan_subdivision(F, len(V), 2)
        return plan, subdivide_frames([V], plan, resolve=resolve)

    seconds, (plan, (out, reports)) = ctx.timed(run)
    left = len(intersecting_pairs(out[0], plan.faces))
    per_level = ", ".join(f"level {r.level}: {r.collision_constraints} constraints" for r in reports)
    note = f"{len(F)} -> {len(plan.faces)} triangles; {per_level}; exact static test after: {left} pairs"
    return [Result("subdivide_100k_2_levels_collisions", seconds, "s", "30 s goal", 30.0, note)]


BENCHMARKS = [subdivide_100k_two_levels]
