"""Space colonization (Runions ch. 3; L-Py's words: attractors, kill radius, perception radius).

N attraction points fill the crown envelope (uniform, or overdispersed with minimum distance
b_d: dart throwing). Each iteration every live point is associated with its nearest tree node, if
closer than the radius of influence d_I; a node v influenced by the set S(v) grows a new node
v' = v + D n~ with (eq. 3.1, 3.3)

    n = sum_{s in S(v)} (s - v) / |s - v|,   n^ = n / |n|,   n~ = (n^ + g) / |n^ + g|,

and points within the kill distance d_k of any node die. Several initial nodes compete for the
points (a hedge, fig. 3.20); planes remove points behind them (obstacles).

The nearest node of every point is kept incrementally: only the nodes created in the last
iteration are compared with the live points, so an iteration costs O(k r) for k live points and
r new nodes (Runions sec. 3.2.4 reaches O(k log n) with a Voronoi diagram). The whole run costs
about N times the number of nodes: 0.15 s for Runions' N = 3000 benchmark, growing as ~N^1.45
(bench/bench_branch_gen.py); a spatial hash of the new nodes measured no faster at these sizes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from inflo.formats.errors import InputError

from .rodkaew import _cell, _hash
from .skeleton import Skeleton

__all__ = ["attraction_points", "colonize", "ScaResult", "grow_sca"]


@njit(cache=True)
def _dart_throw(cand, b_d, accepted, n_acc, want, grid_head, grid_next, mask):
    """Accept candidates farther than b_d from every accepted point (in order) until ``want``."""
    inv_h = 1.0 / b_d
    for c in range(cand.shape[0]):
        if n_acc >= want:
            break
        p = cand[c]
        cx = _cell(p[0], inv_h)
        cy = _cell(p[1], inv_h)
        cz = _cell(p[2], inv_h)
        ok = True
        for dx in range(-1, 2):
            for dy in range(-1, 2):
                for dz in range(-1, 2):
                    v = grid_head[_hash(cx + dx, cy + dy, cz + dz, mask)]
                    while v >= 0 and ok:
                        d2 = ((accepted[v, 0] - p[0]) ** 2 + (accepted[v, 1] - p[1]) ** 2
                              + (accepted[v, 2] - p[2]) ** 2)
                        if d2 < b_d * b_d:
                            ok = False
                        v = grid_next[v]
        if ok:
            accepted[n_acc] = p
            b = _hash(cx, cy, cz, mask)
            grid_next[n_acc] = grid_head[b]
            grid_head[b] = n_acc
            n_acc += 1
    return n_acc


def attraction_points(envelope, n: int, rng, *, min_distance: float = 0.0, obstacles=(), existing=None,
                      max_tries: int = 200) -> np.ndarray:
    """``n`` points inside ``envelope`` (chi_Q), uniform or overdispersed (b_d = min_distance).

    Points on the far side of an obstacle plane ``[nx, ny, nz, c]`` (n . p > c) are not used.
    With ``existing`` points, new ones also keep b_d from them.

    Raises
    ------
    InputError
        When fewer than ``n`` points fit after ``max_tries`` rounds of candidates.
    """
    lo, hi = envelope.bounds()
    planes = np.asarray(obstacles, dtype=np.float64).reshape(-1, 4)
    prior = np.zeros((0, 3)) if existing is None else np.asarray(existing, dtype=np.float64).reshape(-1, 3)
    total = len(prior) + n
    accepted = np.zeros((total, 3))
    accepted[: len(prior)] = prior
    n_acc = len(prior)
    bits = max(10, int(math.ceil(math.log2(2 * total + 2))))
    mask = (1 << bits) - 1
    grid_head = np.full(mask + 1, -1, np.int64)
    grid_next = np.full(total, -1, np.int64)
    if min_distance > 0 and len(prior):
        n_acc = _dart_throw(prior, min_distance, accepted, 0, len(prior), grid_head, grid_next, mask)
        n_acc = len(prior)
    for _ in range(max_tries):
        if n_acc >= total:
            break
        batch = max(64, 2 * (total - n_acc))
        cand = lo + (hi - lo) * rng.random((batch, 3))
        cand = cand[envelope.contains(cand)]
        if len(planes):
            cand = cand[np.all(cand @ planes[:, :3].T <= planes[:, 3], axis=1)]
        if min_distance > 0:
            n_acc = _dart_throw(np.ascontiguousarray(cand), min_distance, accepted, n_acc, total, grid_head,
                                grid_next, mask)
        else:
            take = cand[: total - n_acc]
            accepted[n_acc:n_acc + len(take)] = take
            n_acc += len(take)
    if n_acc < total:
        raise InputError(f"only {n_acc - len(prior)} of {n} attraction points fit in the envelope "
                         f"with min_distance {min_distance}")
    return accepted[len(prior):].copy()


@njit(cache=True)
def _update_nearest(points, alive, near, near_d2, node_pos, n_from, n_to):
    """Nearest node of every live point among its old one and the nodes ``n_from:n_to`` (a scan)."""
    for s in range(points.shape[0]):
        if not alive[s]:
            continue
        best = near_d2[s]
        bq = near[s]
        for v in range(n_from, n_to):
            d2 = ((node_pos[v, 0] - points[s, 0]) ** 2 + (node_pos[v, 1] - points[s, 1]) ** 2
                  + (node_pos[v, 2] - points[s, 2]) ** 2)
            if d2 < best:
                best = d2
                bq = v
        near_d2[s] = best
        near[s] = bq


@njit(cache=True)
def _biased(n, g):
    """Eq. 3.1 and 3.3: n^ = n / |n|, n~ = (n^ + g) / |n^ + g| (zero vector when undefined)."""
    nn = math.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2)
    if nn < 1e-12:
        return np.zeros(3)
    u = n / nn + g
    un = math.sqrt(u[0] ** 2 + u[1] ** 2 + u[2] ** 2)
    if un < 1e-12:
        return np.zeros(3)
    return u / un


@njit(cache=True)
def _iterate(max_iter, it0, points, alive, near, near_d2, node_pos, node_parent, node_iter, n_nodes, n_new_from,
             last_dir, d_i2, d_k2, step, g, acc, cnt, closest):
    """Space colonization iterations until no node grows, ``max_iter``, or capacity runs short.

    Returns (iterations done, node count, first node of the last batch, status) with status 0 =
    finished (no growth), 1 = max_iter reached, 2 = needs more node capacity.
    """
    cap = node_pos.shape[0]
    it = it0
    touched = np.empty(points.shape[0], np.int64)
    while it < max_iter:
        _update_nearest(points, alive, near, near_d2, node_pos, n_new_from, n_nodes)
        n_alive = 0
        for s in range(points.shape[0]):
            if alive[s] and near_d2[s] < d_k2:
                alive[s] = False
            if alive[s]:
                n_alive += 1
        if n_nodes + n_alive > cap:
            return it, n_nodes, n_new_from, 2
        n_new_from = n_nodes
        nt = 0
        for s in range(points.shape[0]):
            if not alive[s] or near_d2[s] >= d_i2:
                continue
            v = near[s]
            d = math.sqrt(near_d2[s])
            if d <= 0.0:
                continue
            if cnt[v] == 0:
                touched[nt] = v
                nt += 1
                closest[v] = s
            elif d < math.sqrt(near_d2[closest[v]]) or (d == math.sqrt(near_d2[closest[v]]) and s < closest[v]):
                closest[v] = s
            cnt[v] += 1
            for k in range(3):
                acc[v, k] += (points[s, k] - node_pos[v, k]) / d
        grown = 0
        for j in range(nt):
            v = touched[j]
            n = acc[v].copy()
            acc[v, :] = 0.0
            cnt[v] = 0
            u = _biased(n, g)
            # S(v) unchanged since v last grew (points symmetric about the new node, which stays
            # farther from them than v) or n = 0: grow toward the closest point of S(v) instead,
            # which breaks the symmetry deterministically
            if u[0] * last_dir[v, 0] + u[1] * last_dir[v, 1] + u[2] * last_dir[v, 2] > 1.0 - 1e-12:
                u = _biased(points[closest[v]] - node_pos[v], g)
                if u[0] * last_dir[v, 0] + u[1] * last_dir[v, 1] + u[2] * last_dir[v, 2] > 1.0 - 1e-12:
                    continue
            if u[0] == 0.0 and u[1] == 0.0 and u[2] == 0.0:
                continue
            w = n_nodes
            n_nodes += 1
            node_pos[w] = node_pos[v] + step * u
            node_parent[w] = v
            node_iter[w] = it
            last_dir[v] = u
            grown += 1
        it += 1
        if grown == 0:
            return it, n_nodes, n_new_from, 0
    return it, n_nodes, n_new_from, 1


@dataclass
class ScaResult:
    """Space colonization output.

    Attributes
    ----------
    node_pos : (n, 3) float64
    node_parent : (n,) int64
    node_iter : (n,) int64
        Iteration that created the node (-1 for the initial nodes).
    points : (N, 3) float64
        All attraction points used.
    alive : (N,) bool
        Points not killed at the end.
    near_d : (N,) float64
        Distance of each point to its nearest node at the end.
    iterations : int
    """

    node_pos: np.ndarray
    node_parent: np.ndarray
    node_iter: np.ndarray
    points: np.ndarray
    alive: np.ndarray
    near_d: np.ndarray
    iterations: int


def colonize(points, roots, *, step: float, kill_distance: float, influence_radius: float = math.inf,
             tropism=(0.0, 0.0, 0.0), max_iterations: int = 100000, add_points=None, add_iterations: int = 0,
             progress=None) -> ScaResult:
    """Run the space colonization algorithm (eq. 3.1, 3.3) from ``roots`` toward ``points``.

    Parameters
    ----------
    points : (N, 3) float64
        Attraction points.
    roots : (r, 3) float64
        Initial tree nodes (several compete: a hedge).
    step, kill_distance, influence_radius
        D, d_k, d_I (inf allowed).
    tropism : (3,) float64
        Bias g.
    add_points : callable(iteration, existing_points) -> (m, 3) or None
        New attraction points for each of the first ``add_iterations`` iterations.
    progress : callable(int) or None
        Called with the number of points killed since the last call.
    """
    pts = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    roots = np.asarray(roots, dtype=np.float64).reshape(-1, 3)
    cap = max(1024, 4 * len(pts) + len(roots))
    node_pos = np.zeros((cap, 3))
    node_parent = np.full(cap, -1, np.int64)
    node_iter = np.full(cap, -1, np.int64)
    last_dir = np.zeros((cap, 3))
    acc = np.zeros((cap, 3))
    cnt = np.zeros(cap, np.int64)
    closest = np.zeros(cap, np.int64)
    n_nodes = len(roots)
    node_pos[:n_nodes] = roots
    alive = np.ones(len(pts), np.bool_)
    near = np.full(len(pts), -1, np.int64)
    near_d2 = np.full(len(pts), np.inf)
    g = np.asarray(tropism, dtype=np.float64)
    d_i2 = influence_radius ** 2 if math.isfinite(influence_radius) else np.inf
    it, new_from = 0, 0
    killed_before = 0
    while True:
        limit = min(max_iterations, it + 1) if (add_points is not None and it < add_iterations) else max_iterations
        it, n_nodes, new_from, status = _iterate(limit, it, pts, alive, near, near_d2, node_pos, node_parent,
                                                 node_iter, n_nodes, new_from, last_dir, d_i2,
                                                 kill_distance ** 2, step, g, acc, cnt, closest)
        if progress is not None:
            killed = int((~alive).sum())
            progress(killed - killed_before)
            killed_before = killed
        if status == 2:
            extra = cap
            node_pos = np.vstack([node_pos, np.zeros((extra, 3))])
            node_parent = np.concatenate([node_parent, np.full(extra, -1, np.int64)])
            node_iter = np.concatenate([node_iter, np.full(extra, -1, np.int64)])
            last_dir = np.vstack([last_dir, np.zeros((extra, 3))])
            acc = np.vstack([acc, np.zeros((extra, 3))])
            cnt = np.concatenate([cnt, np.zeros(extra, np.int64)])
            closest = np.concatenate([closest, np.zeros(extra, np.int64)])
            cap += extra
            continue
        if add_points is not None and it <= add_iterations and it < max_iterations:
            new = np.asarray(add_points(it, pts[alive]), dtype=np.float64).reshape(-1, 3)
            if len(new):
                pts = np.vstack([pts, new])
                alive = np.concatenate([alive, np.ones(len(new), np.bool_)])
                near = np.concatenate([near, np.full(len(new), -1, np.int64)])
                near_d2 = np.concatenate([near_d2, np.full(len(new), np.inf)])
                # the new points see every node, not only the newest
                sub_alive = np.zeros(len(pts), np.bool_)
                sub_alive[-len(new):] = True
                _update_nearest(pts, sub_alive, near, near_d2, node_pos, 0, new_from)
            if it < add_iterations:
                continue
            if status == 0 and not len(new):
                break
            continue
        break
    return ScaResult(node_pos[:n_nodes].copy(), node_parent[:n_nodes].copy(), node_iter[:n_nodes].copy(), pts,
                     alive, np.sqrt(near_d2), it)


def grow_sca(params, envelope, *, progress=None) -> tuple[Skeleton, ScaResult]:
    """Attraction points in ``envelope`` and the colonizing tree of ``params.sca`` (seeded)."""
    sp = params.sca
    rng = np.random.default_rng(params.seed)
    pts = attraction_points(envelope, sp.n_points, rng, min_distance=sp.min_distance, obstacles=sp.obstacles)
    if len(pts) == 0 and sp.add_points == 0:
        raise InputError("space colonization needs attraction points: sca.n_points is 0")
    def more_points(it, existing):
        return attraction_points(envelope, sp.add_points, rng, min_distance=sp.min_distance,
                                 obstacles=sp.obstacles, existing=existing if sp.min_distance > 0 else None)

    add = more_points if sp.add_points > 0 and sp.add_iterations > 0 else None
    res = colonize(pts, sp.roots, step=sp.step, kill_distance=sp.kill_distance,
                   influence_radius=sp.influence_radius, tropism=sp.tropism, max_iterations=sp.max_iterations,
                   add_points=add, add_iterations=sp.add_iterations, progress=progress)
    n = len(res.node_pos)
    link = res.node_iter.astype(np.float64)
    link[res.node_parent < 0] = np.inf
    sk = Skeleton(node_pos=res.node_pos, node_parent=res.node_parent, node_tip=np.zeros(n, bool),
                  node_floret=np.full(n, -1, np.int64), node_frame=np.maximum(res.node_iter, 0).astype(float),
                  node_link_frame=link, node_branch=np.full(n, -1, np.int64),
                  base=np.asarray(params.base, dtype=np.float64))
    return sk, res
