"""Space colonization (Runions ch. 3; L-Py's words: attractors, kill radius, perception radius).

N attraction points fill the crown envelope (uniform, or overdispersed with minimum distance
b_d: dart throwing). Each iteration every live point is associated with its nearest tree node, if
closer than the radius of influence d_I; a node v influenced by the set S(v) grows a new node
v' = v + D n~ with (eq. 3.1, 3.3)

    n = sum_{s in S(v)} (s - v) / |s - v|,   n^ = n / |n|,   n~ = (n^ + g) / |n^ + g|,

and points within the kill distance d_k of any node die. Several initial nodes compete for the
points (a hedge, fig. 3.20); planes remove points behind them (obstacles).

The nearest node of every point is kept incrementally: it can only change to one of the nodes
created in the last iteration, and a new node w can only become nearest for points s with
|s - w| < d(s), their current nearest distance. The live points sit in a static kd-tree (buckets
of 32, tight boxes) whose every subtree keeps an upper bound of d(s)^2 over its live points; the
new nodes of an iteration get a kd-tree of their own (buckets of 16) cut into clusters of at most
32, and each cluster enters only the subtrees whose box is within that bound of the cluster's box,
then compares a bucket's points only with those of its node buckets whose box is within the
point's d(s) (Runions sec. 3.2.4 reaches the same end with a Voronoi diagram). Killed points
are swap-removed from their bucket and dropped from a compact, index-ordered list of live points,
so dead points cost nothing. The work per iteration is then about proportional to the live points
(each gets about one nearer node per iteration), and the run time grows about linearly in N
(fig. 3.9; the old scan of every live point against every new node grew as ~N^1.5). The result is
bit-identical to that scan in node order (strict improvement, so the lowest node index wins a
tie): a skipped pair could not have won, as the box gaps are computed with the same rounded
operations and never exceed a member's distance. Runions' N = 3000 benchmark and the fitted
exponent are in bench/bench_branch_gen.py.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from inflo.formats.errors import InputError
from inflo.tools.common import linalg as la

from .rodkaew import _cell, _hash
from .skeleton import Skeleton

__all__ = ["attraction_points", "colonize", "ScaResult", "grow_sca"]


# --------------------------------------------------------------------------------------------
# what the kernels share (NamedTuples of arrays: numba passes them as one argument, its fields
# typed separately; every field has one dtype and layout, so a kernel compiles once)


class Points(NamedTuple):
    """The attraction points s and their nearest node (the incrementally kept association)."""

    pos: np.ndarray  # (N, 3) float64
    alive: np.ndarray  # (N,) bool: not killed
    near: np.ndarray  # (N,) int64: nearest node (-1 before any)
    near_d2: np.ndarray  # (N,) float64: squared distance d(s)^2 to it (inf before any)
    live: np.ndarray  # (N,) int64: live[:n_live] the live points in increasing order (compacted)


class Nodes(NamedTuple):
    """The tree nodes v (capacity rows; the first n_nodes are in use)."""

    pos: np.ndarray  # (cap, 3) float64
    parent: np.ndarray  # (cap,) int64, -1 for the initial nodes
    iteration: np.ndarray  # (cap,) int64: iteration that created the node, -1 initial
    last_dir: np.ndarray  # (cap, 3) float64: direction n~ of the node's last growth
    acc: np.ndarray  # (cap, 3) float64: sum of (s - v) / |s - v| over S(v) (eq. 3.1), zeroed after use
    cnt: np.ndarray  # (cap,) int64: |S(v)| this iteration
    closest: np.ndarray  # (cap,) int64: the closest point of S(v) (lowest index among equals)


class KdTree(NamedTuple):
    """A kd-tree over rows of a position array (:func:`_build_kd`).

    Node ``t`` covers the rows ``perm[start[t]:start[t] + size[t]]`` in the box [lo[t], hi[t]];
    a bucket has ``cnt[t]`` = ``size[t]``, an inner node ``cnt[t]`` = -1 and children ``left[t]``
    and ``left[t] + 1``, both numbered after it.
    """

    perm: np.ndarray  # (n,) int64
    lo: np.ndarray  # (T, 3) float64
    hi: np.ndarray  # (T, 3) float64
    start: np.ndarray  # (T,) int64
    cnt: np.ndarray  # (T,) int64
    left: np.ndarray  # (T,) int64
    size: np.ndarray  # (T,) int64


class PointTree(NamedTuple):
    """The kd-tree of the live points with what the nearest-node update keeps per bucket.

    Slot ``i`` holds point ``perm[i]``, its position ``slot_pos[i]`` and ``slot_d2[i]`` = its
    ``near_d2`` (copies in bucket order); a bucket's live points fill the front of its slots
    (``cnt`` counts them); ``maxd2[t]`` bounds ``near_d2`` over the live points below ``t`` (-1
    when none); point s sits in slot ``slot_of[s]`` of bucket ``leaf_of[s]``. ``perm``, ``lo``,
    ``hi``, ``start``, ``cnt`` and ``left`` as in :class:`KdTree`.
    """

    perm: np.ndarray  # (n,) int64
    lo: np.ndarray  # (T, 3) float64
    hi: np.ndarray  # (T, 3) float64
    start: np.ndarray  # (T,) int64
    cnt: np.ndarray  # (T,) int64
    left: np.ndarray  # (T,) int64
    maxd2: np.ndarray  # (T,) float64
    slot_pos: np.ndarray  # (n, 3) float64
    slot_d2: np.ndarray  # (n,) float64
    slot_of: np.ndarray  # (N,) int64
    leaf_of: np.ndarray  # (N,) int64


class ScaConstants(NamedTuple):
    """The scalars of a run (eq. 3.1, 3.3): squared d_I and d_k, the step D, the tropism g."""

    d_i2: float  # d_I^2 (inf allowed)
    d_k2: float  # d_k^2
    step: float  # D
    g: np.ndarray  # (3,) float64


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
            cand = cand[np.all(la.matmul(cand, planes[:, :3].T) <= planes[:, 3], axis=1)]
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
    """Nearest node of every live point among its old one and the nodes ``n_from:n_to`` (a scan).

    Used only for points added during the run (against the nodes that exist when they appear).
    """
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


POINT_LEAF = 32  # live points per bucket of the point kd-tree
#: tree nodes a run may make (about 100 bytes each, and a copy while the arrays grow)
MAX_NODES = 10_000_000
#: iterations without a point reached after which a growing tree is taken to grow away from them (at least)
STALL_ITERATIONS = 1000
NODE_LEAF = 16  # new nodes per bucket of that iteration's node kd-tree
NODE_CLUSTER = 32  # new nodes per cluster (subtree of the node kd-tree) walking the point kd-tree


@njit(cache=True)
def _build_kd(pos, idx, leaf_size):
    """kd-tree over the rows ``idx`` of ``pos``: median splits on the widest axis, tight boxes (a :class:`KdTree`)."""
    n = idx.shape[0]
    cap = 2 * (n // max(1, leaf_size // 2)) + 3
    perm = idx.copy()
    t_lo = np.empty((cap, 3))
    t_hi = np.empty((cap, 3))
    t_start = np.zeros(cap, np.int64)
    t_end = np.zeros(cap, np.int64)
    t_left = np.full(cap, -1, np.int64)
    t_cnt = np.full(cap, -1, np.int64)
    t_end[0] = n
    n_t = 1
    stack = np.empty(cap, np.int64)
    stack[0] = 0
    sp = 1
    while sp > 0:
        sp -= 1
        t = stack[sp]
        a, b = t_start[t], t_end[t]
        for k in range(3):
            t_lo[t, k] = np.inf
            t_hi[t, k] = -np.inf
        for i in range(a, b):
            for k in range(3):
                c = pos[perm[i], k]
                t_lo[t, k] = min(t_lo[t, k], c)
                t_hi[t, k] = max(t_hi[t, k], c)
        if b - a <= leaf_size:
            t_cnt[t] = b - a
            continue
        ax = 0
        for k in range(1, 3):
            if t_hi[t, k] - t_lo[t, k] > t_hi[t, ax] - t_lo[t, ax]:
                ax = k
        seg = perm[a:b].copy()
        order = np.argsort(pos[seg, ax])
        for i in range(b - a):
            perm[a + i] = seg[order[i]]
        mid = (a + b) // 2
        t_left[t] = n_t
        t_start[n_t], t_end[n_t] = a, mid
        t_start[n_t + 1], t_end[n_t + 1] = mid, b
        stack[sp] = n_t
        stack[sp + 1] = n_t + 1
        sp += 2
        n_t += 2
    return KdTree(perm, t_lo[:n_t].copy(), t_hi[:n_t].copy(), t_start[:n_t].copy(), t_cnt[:n_t].copy(),
                  t_left[:n_t].copy(), t_end[:n_t] - t_start[:n_t])


@njit(cache=True)
def _point_tree(points, leaf_size):
    """The :class:`PointTree` (buckets of ``leaf_size``) of ``points.live``, every entry a live point."""
    near_d2 = points.near_d2
    perm, t_lo, t_hi, t_start, t_cnt, t_left, _ = _build_kd(points.pos, points.live, leaf_size)
    n = perm.shape[0]
    slot_pos = np.empty((n, 3))
    slot_d2 = np.empty(n)
    slot_of = np.full(points.pos.shape[0], -1, np.int64)
    leaf_of = np.full(points.pos.shape[0], -1, np.int64)
    for i in range(n):
        s = perm[i]
        slot_pos[i] = points.pos[s]
        slot_d2[i] = near_d2[s]
        slot_of[s] = i
    t_maxd2 = np.full(t_cnt.shape[0], -1.0)
    for t in range(t_cnt.shape[0]):
        for i in range(t_start[t], t_start[t] + max(t_cnt[t], 0)):
            t_maxd2[t] = max(t_maxd2[t], slot_d2[i])
            leaf_of[perm[i]] = t
    _refit(t_maxd2, t_cnt, t_left)
    return PointTree(perm, t_lo, t_hi, t_start, t_cnt, t_left, t_maxd2, slot_pos, slot_d2, slot_of, leaf_of)


@njit(cache=True)
def _refit(t_maxd2, t_cnt, t_left):
    """Inner-node bounds from their children, bottom up (buckets keep their own)."""
    for t in range(t_maxd2.shape[0] - 1, -1, -1):
        if t_cnt[t] < 0:
            t_maxd2[t] = max(t_maxd2[t_left[t]], t_maxd2[t_left[t] + 1])


@njit(cache=True)
def _gap2(lo_a, hi_a, lo_b, hi_b):
    """Squared gap between the intervals [lo_a, hi_a] and [lo_b, hi_b] along one axis (0 if they meet).

    Rounded subtraction is monotone, so this never exceeds fl(x - y) ** 2 for x in one interval
    and y in the other: summed over the axes in order it bounds the squared distance exactly as
    the distance is computed.
    """
    if hi_a < lo_b:
        return (lo_b - hi_a) ** 2
    if lo_a > hi_b:
        return (lo_a - hi_b) ** 2
    return 0.0


@njit(cache=True)
def _update_nearest_tree(points, node_pos, n_from, n_to, tree, stack, work):
    """Nearest node of every live point (``points``, in ``tree``) among its old one and the nodes ``n_from:n_to``.

    The result of comparing every live point with the new nodes in index order (strict ``<``):
    the least distance, the lowest node index among equals (old nodes all precede the new ones).
    The new nodes get a kd-tree of their own (buckets of NODE_LEAF) whose subtrees of at most
    NODE_CLUSTER nodes are clusters. A cluster enters only the point-tree subtrees whose squared
    gap to its box does not exceed their bound on ``near_d2``; in a point bucket, a point is
    compared with the nodes of the cluster's buckets that are no farther from it (by box) than
    its nearest node. ``work[0]`` counts point-node distance evaluations, ``work[1]`` point-tree
    nodes entered (``stack``: room for a path through the point tree).
    """
    if n_to <= n_from:
        return
    near, near_d2 = points.near, points.near_d2
    perm, t_lo, t_hi, t_start, t_cnt, t_left = tree.perm, tree.lo, tree.hi, tree.start, tree.cnt, tree.left
    t_maxd2, slot_pos, slot_d2 = tree.maxd2, tree.slot_pos, tree.slot_d2
    order, c_lo, c_hi, c_start, c_cnt, c_left, c_size = _build_kd(node_pos, np.arange(n_from, n_to), NODE_LEAF)
    n_eval = 0
    n_visit = 0
    # the cluster's nodes (contiguous) and its buckets: first node, count, box
    cx = np.empty(NODE_CLUSTER)
    cy = np.empty(NODE_CLUSTER)
    cz = np.empty(NODE_CLUSTER)
    cv = np.empty(NODE_CLUSTER, np.int64)
    q_first = np.empty(NODE_CLUSTER, np.int64)
    q_cnt = np.empty(NODE_CLUSTER, np.int64)
    q_box = np.empty((NODE_CLUSTER, 6))
    c_stack = np.empty(c_cnt.shape[0] + 2, np.int64)
    c_stack[0] = 0
    csp = 1
    while csp > 0:
        csp -= 1
        c = c_stack[csp]
        if c_size[c] > NODE_CLUSTER:
            c_stack[csp] = c_left[c]
            c_stack[csp + 1] = c_left[c] + 1
            csp += 2
            continue
        if c_size[c] == 0:
            continue
        # cluster c: gather its buckets (in node order) below it
        c0 = c_start[c]
        nq = 0
        q_stack = c_stack[csp:]
        q_stack[0] = c
        qsp = 1
        while qsp > 0:
            qsp -= 1
            q = q_stack[qsp]
            if c_cnt[q] < 0:
                q_stack[qsp] = c_left[q] + 1
                q_stack[qsp + 1] = c_left[q]
                qsp += 2
                continue
            q_first[nq] = c_start[q] - c0
            q_cnt[nq] = c_cnt[q]
            for k in range(3):
                q_box[nq, k] = c_lo[q, k]
                q_box[nq, 3 + k] = c_hi[q, k]
            nq += 1
        for j in range(c_size[c]):
            v = order[c0 + j]
            cv[j] = v
            cx[j], cy[j], cz[j] = node_pos[v, 0], node_pos[v, 1], node_pos[v, 2]
        lx, ly, lz = c_lo[c, 0], c_lo[c, 1], c_lo[c, 2]
        hx, hy, hz = c_hi[c, 0], c_hi[c, 1], c_hi[c, 2]
        stack[0] = 0
        sp = 1
        while sp > 0:
            sp -= 1
            t = stack[sp]
            n_visit += 1
            # a lower bound of every cluster-node-to-point distance below t: b > bound means no
            # point below t can get nearer or tie
            b = _gap2(lx, hx, t_lo[t, 0], t_hi[t, 0]) + _gap2(ly, hy, t_lo[t, 1], t_hi[t, 1]) \
                + _gap2(lz, hz, t_lo[t, 2], t_hi[t, 2])
            if b > t_maxd2[t]:
                continue
            if t_cnt[t] < 0:
                stack[sp] = t_left[t]
                stack[sp + 1] = t_left[t] + 1
                sp += 2
                continue
            m = -1.0
            for i in range(t_start[t], t_start[t] + t_cnt[t]):
                best = slot_d2[i]
                if best >= b:
                    px, py, pz = slot_pos[i, 0], slot_pos[i, 1], slot_pos[i, 2]
                    e = _gap2(lx, hx, px, px) + _gap2(ly, hy, py, py) + _gap2(lz, hz, pz, pz)
                    if best >= e:
                        bq = -1  # the current nearest node, read when first needed
                        changed = False
                        for q in range(nq):
                            e = _gap2(q_box[q, 0], q_box[q, 3], px, px) + _gap2(q_box[q, 1], q_box[q, 4], py, py) \
                                + _gap2(q_box[q, 2], q_box[q, 5], pz, pz)
                            if e > best:
                                continue
                            n_eval += q_cnt[q]
                            for j in range(q_first[q], q_first[q] + q_cnt[q]):
                                d2 = (cx[j] - px) ** 2 + (cy[j] - py) ** 2 + (cz[j] - pz) ** 2
                                if d2 <= best:
                                    if bq < 0:
                                        bq = near[perm[i]]
                                    if d2 < best or cv[j] < bq:
                                        best = d2
                                        bq = cv[j]
                                        changed = True
                        if changed:
                            s = perm[i]
                            slot_d2[i] = best
                            near_d2[s] = best
                            near[s] = bq
                m = max(m, best)
            t_maxd2[t] = m
    work[0] += n_eval
    work[1] += n_visit


@njit(cache=True)
def _kill(s, tree):
    """Swap-remove point ``s`` from its bucket of ``tree`` (its slot moves past the bucket's live ones)."""
    perm, slot_of, slot_pos, slot_d2, cnt = tree.perm, tree.slot_of, tree.slot_pos, tree.slot_d2, tree.cnt
    leaf = tree.leaf_of[s]
    last = tree.start[leaf] + cnt[leaf] - 1
    i = slot_of[s]
    o = perm[last]
    perm[i], perm[last] = o, s
    slot_of[o], slot_of[s] = i, last
    for k in range(3):
        slot_pos[i, k], slot_pos[last, k] = slot_pos[last, k], slot_pos[i, k]
    slot_d2[i], slot_d2[last] = slot_d2[last], slot_d2[i]
    cnt[leaf] -= 1
    if cnt[leaf] == 0:
        tree.maxd2[leaf] = -1.0


@njit(cache=True)
def _biased(nx, ny, nz, g, out):
    """Eq. 3.1 and 3.3 into ``out``: n^ = n / |n|, n~ = (n^ + g) / |n^ + g| (zero when undefined)."""
    nn = math.sqrt(nx ** 2 + ny ** 2 + nz ** 2)
    if nn < 1e-12:
        out[:] = 0.0
        return
    ux, uy, uz = nx / nn + g[0], ny / nn + g[1], nz / nn + g[2]
    un = math.sqrt(ux ** 2 + uy ** 2 + uz ** 2)
    if un < 1e-12:
        out[:] = 0.0
        return
    out[0], out[1], out[2] = ux / un, uy / un, uz / un


@njit(cache=True)
def _iterate(max_iter, it0, n_nodes, n_new_from, n_live, points, nodes, tree, const, work):
    """Space colonization iterations (eq. 3.1, 3.3) until no node grows, ``max_iter``, or capacity runs short.

    ``points.live[:n_live]`` are the live points in increasing order (compacted as points die),
    all in the point kd-tree ``tree`` (``_point_tree``); ``nodes`` has ``n_nodes`` nodes in use,
    the last batch from ``n_new_from``; ``const`` holds d_I^2, d_k^2, D and g; ``work`` counts
    as in ``_update_nearest_tree``.
    Returns (iterations done, node count, first node of the last batch, live count, status) with
    status 0 = finished (no growth), 1 = max_iter reached, 2 = needs more node capacity.
    """
    pts, alive, near, near_d2, live = points.pos, points.alive, points.near, points.near_d2, points.live
    node_pos, node_parent, node_iter, last_dir = nodes.pos, nodes.parent, nodes.iteration, nodes.last_dir
    acc, cnt, closest = nodes.acc, nodes.cnt, nodes.closest
    d_i2, d_k2, step, g = const.d_i2, const.d_k2, const.step, const.g
    cap = node_pos.shape[0]
    it = it0
    touched = np.empty(pts.shape[0], np.int64)
    stack = np.empty(tree.maxd2.shape[0] + 2, np.int64)
    u = np.empty(3)
    while it < max_iter:
        _update_nearest_tree(points, node_pos, n_new_from, n_nodes, tree, stack, work)
        n_alive = 0
        for j in range(n_live):
            s = live[j]
            if near_d2[s] < d_k2:
                alive[s] = False
                _kill(s, tree)
            else:
                live[n_alive] = s
                n_alive += 1
        n_live = n_alive
        _refit(tree.maxd2, tree.cnt, tree.left)
        if n_nodes + n_alive > cap:
            return it, n_nodes, n_new_from, n_live, 2
        n_new_from = n_nodes
        nt = 0
        for j in range(n_live):
            s = live[j]
            if near_d2[s] >= d_i2:
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
                acc[v, k] += (pts[s, k] - node_pos[v, k]) / d
        grown = 0
        for j in range(nt):
            v = touched[j]
            _biased(acc[v, 0], acc[v, 1], acc[v, 2], g, u)
            acc[v, :] = 0.0
            cnt[v] = 0
            # S(v) unchanged since v last grew (points symmetric about the new node, which stays
            # farther from them than v) or n = 0: grow toward the closest point of S(v) instead,
            # which breaks the symmetry deterministically
            if u[0] * last_dir[v, 0] + u[1] * last_dir[v, 1] + u[2] * last_dir[v, 2] > 1.0 - 1e-12:
                c = closest[v]
                dx, dy, dz = pts[c, 0] - node_pos[v, 0], pts[c, 1] - node_pos[v, 1], pts[c, 2] - node_pos[v, 2]
                _biased(dx, dy, dz, g, u)
                if u[0] * last_dir[v, 0] + u[1] * last_dir[v, 1] + u[2] * last_dir[v, 2] > 1.0 - 1e-12:
                    continue
            if u[0] == 0.0 and u[1] == 0.0 and u[2] == 0.0:
                continue
            w = n_nodes
            n_nodes += 1
            for k in range(3):
                node_pos[w, k] = node_pos[v, k] + step * u[k]
                last_dir[v, k] = u[k]
            node_parent[w] = v
            node_iter[w] = it
            grown += 1
        it += 1
        if grown == 0:
            return it, n_nodes, n_new_from, n_live, 0
    return it, n_nodes, n_new_from, n_live, 1


class Stalled(InputError):
    """A space colonization that would not end: its tree grows without reaching its points."""

    def __init__(self, expected: str, found: str):
        self.expected, self.found = expected, found
        super().__init__(f"expected {expected}, found {found}")


def _new_nodes(cap: int) -> Nodes:
    """Room for ``cap`` tree nodes (no parent, initial iteration, nothing accumulated)."""
    return Nodes(pos=np.zeros((cap, 3)), parent=np.full(cap, -1, np.int64), iteration=np.full(cap, -1, np.int64),
                 last_dir=np.zeros((cap, 3)), acc=np.zeros((cap, 3)), cnt=np.zeros(cap, np.int64),
                 closest=np.zeros(cap, np.int64))


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
    distance_evaluations : int
        Point-node distances computed by the nearest-node updates (the run's main work).
    tree_visits : int
        kd-tree nodes entered by those updates.
    """

    node_pos: np.ndarray
    node_parent: np.ndarray
    node_iter: np.ndarray
    points: np.ndarray
    alive: np.ndarray
    near_d: np.ndarray
    iterations: int
    distance_evaluations: int = 0
    tree_visits: int = 0


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
    nodes = _new_nodes(cap)
    n_nodes = len(roots)
    nodes.pos[:n_nodes] = roots
    points = Points(pos=pts, alive=np.ones(len(pts), np.bool_), near=np.full(len(pts), -1, np.int64),
                    near_d2=np.full(len(pts), np.inf), live=np.arange(len(pts), dtype=np.int64))
    d_i2 = influence_radius ** 2 if math.isfinite(influence_radius) else math.inf
    const = ScaConstants(d_i2=float(d_i2), d_k2=float(kill_distance ** 2), step=float(step),
                         g=np.ascontiguousarray(tropism, dtype=np.float64))
    it, new_from = 0, 0
    n_live = len(pts)
    killed_before = 0
    work = np.zeros(2, np.int64)
    tree = _point_tree(points, POINT_LEAF)
    # a tree that grows for many times the iterations it needs to cross the points' box without
    # reaching a point never will (it grows away from them): refused rather than run to max_iterations
    box = np.vstack([pts, roots])
    span = float(la.norm(box.max(axis=0) - box.min(axis=0))) if len(box) else 0.0
    patience = max(STALL_ITERATIONS, 10 * int(math.ceil(min(span / step, 1e9))))
    last_kill, dead_before = 0, 0
    while True:
        limit = min(max_iterations, it + 1) if (add_points is not None and it < add_iterations) else max_iterations
        limit = min(limit, it + patience)
        it, n_nodes, new_from, n_live, status = _iterate(limit, it, n_nodes, new_from, n_live, points, nodes, tree,
                                                         const, work)
        killed = int((~points.alive).sum())
        if progress is not None:
            progress(killed - killed_before)
            killed_before = killed
        if killed > dead_before:
            last_kill, dead_before = it, killed
        elif status != 0 and n_live and it - last_kill >= patience:
            raise Stalled("a space colonization that reaches its attraction points (a tropism that does not lead "
                          "away from them)", f"none reached in {it - last_kill} iterations while the tree grew to "
                          f"{n_nodes} nodes, {n_live} points alive")
        if status == 1 and it < max_iterations and not (add_points is not None and it <= add_iterations):
            continue
        if status == 2:
            if cap >= MAX_NODES:
                raise Stalled(f"a space colonization tree of at most {MAX_NODES} nodes (a tropism that does not "
                              f"lead away from the points)", f"more after {it} iterations, {n_live} points alive")
            nodes = Nodes(*(np.concatenate([a, b]) for a, b in zip(nodes, _new_nodes(cap))))
            cap *= 2
            continue
        if add_points is not None and it <= add_iterations and it < max_iterations:
            new = np.asarray(add_points(it, points.pos[points.alive]), dtype=np.float64).reshape(-1, 3)
            if len(new):
                m = len(new)
                pos = np.vstack([points.pos, new])
                alive = np.concatenate([points.alive, np.ones(m, np.bool_)])
                near = np.concatenate([points.near, np.full(m, -1, np.int64)])
                near_d2 = np.concatenate([points.near_d2, np.full(m, np.inf)])
                # the new points see every node, not only the newest (a scan: added points are few)
                sub_alive = np.zeros(len(pos), np.bool_)
                sub_alive[-m:] = True
                _update_nearest(pos, sub_alive, near, near_d2, nodes.pos, 0, new_from)
                work[0] += m * new_from
                live = np.flatnonzero(alive).astype(np.int64)
                points = Points(pos=pos, alive=alive, near=near, near_d2=near_d2, live=live)
                n_live = len(live)
                tree = _point_tree(points, POINT_LEAF)
            if it < add_iterations:
                continue
            if status == 0 and not len(new):
                break
            continue
        break
    return ScaResult(nodes.pos[:n_nodes].copy(), nodes.parent[:n_nodes].copy(), nodes.iteration[:n_nodes].copy(),
                     points.pos, points.alive, np.sqrt(points.near_d2), it, int(work[0]), int(work[1]))


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
    from .params import key_error

    try:
        res = colonize(pts, sp.roots, step=sp.step, kill_distance=sp.kill_distance,
                       influence_radius=sp.influence_radius, tropism=sp.tropism, max_iterations=sp.max_iterations,
                       add_points=add, add_iterations=sp.add_iterations, progress=progress)
    except Stalled as exc:
        raise key_error(params, "sca", "tropism", exc.expected, exc.found) from None
    if len(res.node_pos) == len(sp.roots):
        raise key_error(params, "sca", "influence_radius", "a space colonization tree that grows (an attraction "
                        "point within the radius of influence of a root)", f"{sp.influence_radius:g} and no node grown")
    n = len(res.node_pos)
    link = res.node_iter.astype(np.float64)
    link[res.node_parent < 0] = np.inf
    sk = Skeleton(node_pos=res.node_pos, node_parent=res.node_parent, node_tip=np.zeros(n, bool),
                  node_floret=np.full(n, -1, np.int64), node_frame=np.maximum(res.node_iter, 0).astype(float),
                  node_link_frame=link, node_branch=np.full(n, -1, np.int64),
                  base=np.asarray(params.base, dtype=np.float64))
    return sk, res
