"""Continuous collision narrow phase: queries per second, inflo vs ipctk in the same run (issue 5).

Random queries (four points in [-1, 1]^3 each moving by up to 1 per axis; about 7% of them
collide), the same for both libraries:

- ``ccd_vertex_triangle_queries`` / ``ccd_edge_edge_queries``: inflo's cubic + culling + roots +
  inside tests (:func:`inflo.tools.collide.vertex_triangle_ccd`), looped in numba;
- ``ccd_..._ipctk``: ``ipctk.TightInclusionCCD`` (default tolerance), called per query from Python
  (ipctk has no batch call; the Python call overhead is part of its figure);
- the note gives the ratio and the agreement on hits: ``missed`` counts ipctk hits inflo does not
  report that are real contacts (closest approach over the step, on a 20001-point time grid,
  <= 1e-6; must be 0); ipctk's conservative near misses (it reports pairs that come within its
  tolerance band) are listed with their closest approach; ``extra``: inflo hits ipctk does not report.
"""
from __future__ import annotations

import time

import numpy as np
from numba import njit

from inflo.tools.collide.ccd import edge_edge_ccd, vertex_triangle_ccd

from .harness import BenchContext, Result

ANCHOR = "ipctk TightInclusionCCD, same queries, same run"


@njit(cache=True)
def _batch_vt(p0, p1, tol, hits):
    out = np.empty(4)
    for k in range(p0.shape[0]):
        hits[k] = vertex_triangle_ccd(p0[k, 0], p0[k, 1], p0[k, 2], p0[k, 3],
                                      p1[k, 0], p1[k, 1], p1[k, 2], p1[k, 3], tol, out)


@njit(cache=True)
def _batch_ee(p0, p1, tol, hits):
    out = np.empty(4)
    for k in range(p0.shape[0]):
        hits[k] = edge_edge_ccd(p0[k, 0], p0[k, 1], p0[k, 2], p0[k, 3],
                                p1[k, 0], p1[k, 1], p1[k, 2], p1[k, 3], tol, out)


def _min_distance(kind: str, p0, p1, samples: int = 20001) -> float:
    """Closest approach of the pair over the step, on a fine time grid (for disagreements only)."""
    from inflo.tools.collide.ccd import point_triangle_distance, segment_segment_distance

    buf = np.zeros(3)
    best = np.inf
    for t in np.linspace(0.0, 1.0, samples):
        x = p0 + t * (p1 - p0)
        if kind == "vertex_triangle":
            d = point_triangle_distance(x[0], x[1], x[2], x[3], buf)
        else:
            d = segment_segment_distance(x[0], x[1], x[2], x[3], buf[:2])
        best = min(best, d)
    return float(best)


def ccd_queries(ctx: BenchContext) -> list[Result]:
    import ipctk

    n = 2000 if ctx.quick else 20000
    rng = np.random.default_rng(0)
    p0 = rng.uniform(-1, 1, (n, 4, 3))
    p1 = p0 + rng.uniform(-1, 1, (n, 4, 3))
    tol = 1e-9
    ccd = ipctk.TightInclusionCCD()
    results = []
    for name, batch, theirs_fn in (
        ("vertex_triangle", _batch_vt, ccd.point_triangle_ccd),
        ("edge_edge", _batch_ee, ccd.edge_edge_ccd),
    ):
        hits = np.zeros(n, np.int32)
        batch(p0[:10], p1[:10], tol, hits[:10])  # compile / load cache
        t_ours, _ = ctx.timed(batch, p0, p1, tol, hits, repeat=3)
        t0 = time.perf_counter()
        theirs = np.array([theirs_fn(*p0[k], *p1[k])[0] for k in range(n)], dtype=bool)
        t_theirs = time.perf_counter() - t0
        ours = hits > 0
        only_theirs = np.nonzero(theirs & ~ours)[0]
        gaps = [_min_distance(name, p0[k], p1[k]) for k in only_theirs]
        missed = sum(g <= 1e-6 for g in gaps)  # real contacts inflo did not report
        extra = int(np.count_nonzero(ours & ~theirs))
        q_ours, q_theirs = n / t_ours, n / t_theirs
        agree = (f"{int(theirs.sum())} ipctk hits, {int(ours.sum())} inflo hits; missed {missed}; "
                 f"{len(gaps) - missed} ipctk-only near misses (closest approach "
                 f"{', '.join(f'{g:.1e}' for g in gaps)}); extra {extra}")
        results.append(Result(f"ccd_{name}_queries", q_ours, "queries/s", ANCHOR, q_theirs,
                              f"{n} random queries; {q_ours / q_theirs:.0f}x ipctk; {agree}"))
        results.append(Result(f"ccd_{name}_queries_ipctk", q_theirs, "queries/s", "", None,
                              "ipctk per-query Python calls"))
    return results


BENCHMARKS = [ccd_queries]
