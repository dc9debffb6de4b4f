"""Continuous collision narrow phase: queries per second, inflo vs ipctk in the same run.

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
- ``ccd_canopy_pairs``: the narrow phase as fccompose runs it, on one thread, over the candidate
  pairs of a canopy's step (a grid of opening florets, every floret's petals pressed down through
  its neighbours': the broad phase's vertex-triangle and edge-edge pairs of one step, most of them
  neighbours within a floret that the cubic's cull rejects); queries/s per core, goal 3e6.
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


def ccd_canopy_pairs(ctx: BenchContext) -> list[Result]:
    from inflo.tools.collide.contacts import _narrow_ee_serial, _narrow_vt_serial
    from inflo.tools.collide.detect import step_broad_phase
    from inflo.tools.pbd import mesh_edges
    from inflo.tools.testing.florets import opening_floret

    frames, faces, _ = opening_floret(10)
    side = 4 if ctx.quick else 10
    rng = np.random.default_rng(1)
    x0s, x1s, tris = [], [], []
    for k in range(side * side):
        off = np.array([1.6 * (k % side), 0.0, 1.6 * (k // side)]) + rng.normal(0, 0.05, 3)
        x0s.append(frames[6] + off)
        x1s.append(frames[8] + off + rng.normal(0, 0.01, frames[8].shape))
        tris.append(faces + k * len(frames[0]))
    x0, x1 = np.concatenate(x0s), np.concatenate(x1s)
    tri = np.concatenate(tris).astype(np.int32)
    edges = mesh_edges(tri)
    part = np.repeat(np.arange(side * side), len(frames[0])).astype(np.int32)
    pad = 1e-4
    vt, ee = step_broad_phase(x0, x1, tri, edges, pad, None, part).first(x1)
    n = len(vt) + len(ee)
    hv = np.zeros(len(vt), np.int32)
    he = np.zeros(len(ee), np.int32)
    iv = np.zeros((len(vt), 4))
    ie = np.zeros((len(ee), 4))

    def run():
        _narrow_vt_serial(x0, x1, tri, vt, 2 * pad, hv, iv)
        _narrow_ee_serial(x0, x1, edges, ee, 2 * pad, he, ie)

    run()
    seconds, _ = ctx.timed(run, repeat=3)
    hits = int(np.count_nonzero(hv) + np.count_nonzero(he))
    return [Result("ccd_canopy_pairs", n / seconds, "queries/s", "3e6 queries/s per core", 3e6,
                   f"{len(tri):,} triangles, {len(vt):,} vertex-triangle + {len(ee):,} edge-edge candidate "
                   f"pairs of one step, one thread; {hits} crossing")]


BENCHMARKS = [ccd_queries, ccd_canopy_pairs]
