"""branch-gen: space colonization (Runions sec. 3.2.4) and extended Rodkaew (thesis ch. 7) run times.

Anchors: Runions' run-time experiment (N = 3000 attraction points in a unit sphere, one tree node
at the origin, D = 0.01, d_k = 2D; "a few seconds or minutes"), with a goal of 1 s; the
growth of run time with N (fig. 3.9: about linear); the extended Rodkaew algorithm for 5,000
florets with timed emergence (goal: 5 s); and the spatial-hash nearest-other-tree query
against an all-pairs scan of the same nodes (same run).
"""
from __future__ import annotations

import numpy as np

from inflo.tools.branch_gen.envelope import Envelope
from inflo.tools.branch_gen.params import params_from_dict
from inflo.tools.branch_gen.rodkaew import RodkaewInput, grow_rodkaew
from inflo.tools.branch_gen.sca import attraction_points, colonize

from .harness import BenchContext, Result


def _sca(n, seed=0):
    rng = np.random.default_rng(seed)
    pts = attraction_points(Envelope("sphere", (0, 0, 0), radius=1.0), n, rng)
    return colonize(pts, [[0.0, 0.0, 0.0]], step=0.01, kill_distance=0.02)


def sca_runions(ctx: BenchContext) -> list[Result]:
    _sca(200)  # compile
    t, res = ctx.timed(_sca, 3000, repeat=1 if ctx.quick else 3)
    note = (f"{len(res.node_pos)} nodes, {res.iterations} iterations, {int(res.alive.sum())} points left, "
            f"{res.distance_evaluations} point-node distances")
    out = [Result("sca_n3000_unit_sphere", t, "s", "goal 1 s (Runions sec. 3.2.4: seconds to minutes)",
                  1.0, note)]
    sizes = [1000, 3000, 10000] if ctx.quick else [1000, 3000, 10000, 30000]
    times, evals = [], []
    for n in sizes:
        tn, rn = ctx.timed(_sca, n, repeat=1 if ctx.quick else 2)
        times.append(tn)
        evals.append(rn.distance_evaluations)
    slope = float(np.polyfit(np.log(sizes), np.log(times), 1)[0])
    work = float(np.polyfit(np.log(sizes), np.log(evals), 1)[0])
    out.append(Result("sca_runtime_exponent_in_N", slope, "", "1.0 = linear (Runions fig. 3.9)", 1.0,
                      "fitted exponent of t ~ N^a over N = " + ", ".join(map(str, sizes))
                      + "; times " + ", ".join(f"{x:.3f}" for x in times) + " s; point-node distances "
                      + ", ".join(map(str, evals)) + f" (exponent {work:.2f})"))
    return out


def _florets(n, seed=1):
    """A flat-topped corymb of n florets on a golden-angle spiral, emerging from the rim inward."""
    k = np.arange(n)[::-1]
    r = 0.5 * np.sqrt((k + 0.5) / n)
    th = k * np.pi * (3 - np.sqrt(5))
    pos = np.c_[r * np.cos(th), np.ones(n), r * np.sin(th)]
    return RodkaewInput(pos=pos, up=np.tile([0.0, 1.0, 0.0], (n, 1)), emergence=np.linspace(0, 50, n),
                        group=np.full(n, -1, np.int32), groups={})


def rodkaew_5000(ctx: BenchContext) -> Result:
    n = 1000 if ctx.quick else 5000
    params = params_from_dict({"rodkaew": {"step": 0.005, "merge_distance": 0.006, "steps_per_frame": 4}})
    grow_rodkaew(_florets(50), params)  # compile
    t, sk = ctx.timed(grow_rodkaew, _florets(n), params, repeat=1)
    return Result(f"rodkaew_{n}_florets", t, "s", "goal 5 s", 5.0,
                  f"{sk.n_nodes} nodes, emergence over 50 frames, 4 steps per frame")


def nearest_query(ctx: BenchContext) -> Result:
    """Mean time of one nearest-other-tree query: spatial hash vs an all-pairs scan."""
    from inflo.tools.branch_gen import rodkaew as rk

    rng = np.random.default_rng(3)
    n = 50_000 if ctx.quick else 200_000
    pos = rng.random((n, 3))
    branch = rng.integers(0, 1000, n).astype(np.int64)
    uf = np.arange(1000, dtype=np.int64)
    h = 0.02
    mask = (1 << 20) - 1
    head = np.full(mask + 1, -1, np.int64)
    nxt = np.full(n, -1, np.int64)
    rk._grid_rebuild(n, branch, pos, 1.0 / h, head, nxt, mask)
    queries = rng.random((200, 3))

    def grid():
        return [rk._nearest_other(q, 0, pos, branch, uf, head, nxt, mask, h, 1.0 / h, 1e300, 2**30, n)[0]
                for q in queries]

    def brute():
        out = []
        for q in queries:
            d = np.einsum("ij,ij->i", pos - q, pos - q)
            d[branch == 0] = np.inf
            out.append(int(np.argmin(d)))
        return out

    grid()
    t_grid, a = ctx.timed(grid, repeat=3)
    t_brute, b = ctx.timed(brute, repeat=1)
    assert a == b
    return Result("rodkaew_nearest_query", t_grid / len(queries), "s",
                  "numpy all-pairs scan of the same nodes (same run)", t_brute / len(queries),
                  f"{n} nodes, 1000 trees, 200 queries")


BENCHMARKS = [sca_runions, rodkaew_5000, nearest_query]
