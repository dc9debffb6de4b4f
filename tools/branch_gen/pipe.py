"""Skeleton forests: topology helpers, the pipe model and skeleton post-processing.

A skeleton is a forest stored as structure of arrays:

- ``node_pos (n, 3) float64``: positions;
- ``node_parent (n,) int64``: the basal neighbour of each node (toward the base), -1 at a root;
- ``node_tip (n,) bool``: the node carries a floret (Rodkaew) -- it keeps its position in every
  post-processing step and adds one terminal pipe to the pipe model.

Edges run from a node to its parent. Thesis 7.2 "Branch width" and Runions eq. 3.5 (pipe model),
fig. 3.8 (decimation), fig. 3.1 f-g (relocation, subdivision).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from inflo.tools.common import linalg as la

__all__ = [
    "children_csr",
    "basipetal_order",
    "pipe_radii",
    "chains",
    "decimate",
    "relocate",
    "subdivide",
    "check_forest",
]


@njit(cache=True)
def _children_csr(parent):
    n = parent.shape[0]
    count = np.zeros(n + 1, np.int64)
    for i in range(n):
        if parent[i] >= 0:
            count[parent[i] + 1] += 1
    for i in range(n):
        count[i + 1] += count[i]
    start = count.copy()
    child = np.empty(start[n], np.int64)
    fill = start[:n].copy()
    for i in range(n):
        q = parent[i]
        if q >= 0:
            child[fill[q]] = i
            fill[q] += 1
    return start, child


def children_csr(node_parent):
    """Children lists in CSR form: ``child[start[i]:start[i+1]]`` (ascending node order).

    Returns
    -------
    start : (n + 1,) int64
    child : (n - roots,) int64
    """
    return _children_csr(np.ascontiguousarray(node_parent, dtype=np.int64))


@njit(cache=True)
def _acropetal(parent, start, child):
    n = parent.shape[0]
    order = np.empty(n, np.int64)
    k = 0
    for i in range(n):
        if parent[i] < 0:
            order[k] = i
            k += 1
    head = 0
    while head < k:
        v = order[head]
        head += 1
        for j in range(start[v], start[v + 1]):
            order[k] = child[j]
            k += 1
    return order[:k]


def basipetal_order(node_parent) -> np.ndarray:
    """(n,) int64: every node after all its descendants (tips first, roots last).

    Raises
    ------
    ValueError
        When the parent links contain a cycle (some node is not reachable from a root).
    """
    parent = np.ascontiguousarray(node_parent, dtype=np.int64)
    start, child = _children_csr(parent)
    acro = _acropetal(parent, start, child)
    if len(acro) != len(parent):
        raise ValueError(f"skeleton has a cycle: {len(parent) - len(acro)} nodes not reachable from a root")
    return acro[::-1].copy()


@njit(cache=True)
def _pipe(order, parent, tip, leaf, r0p, p):
    n = parent.shape[0]
    acc = np.zeros(n)
    for k in range(order.shape[0]):
        v = order[k]
        if tip[v] or leaf[v]:
            acc[v] += r0p
        q = parent[v]
        if q >= 0:
            acc[q] += acc[v]
    return acc ** (1.0 / p)


def pipe_radii(node_parent, node_tip, tip_radius: float, exponent: float) -> np.ndarray:
    """Branch radii by the pipe model (thesis 7.2 "Branch width"; Runions eq. 3.5).

    ``r^p = [tip] r_0^p + sum over children r_c^p`` at every node, with every leaf (and every floret
    tip, leaf or not) contributing one terminal pipe of radius ``r_0``. The radius of node ``v`` is
    the radius of the edge from ``v`` to its parent (the branch just basal of ``v``).

    Parameters
    ----------
    node_parent : (n,) int
    node_tip : (n,) bool
    tip_radius : float
        r_0 (half the terminal diameter of the thesis).
    exponent : float
        p (thesis) or n (Runions).

    Returns
    -------
    (n,) float64
    """
    parent = np.ascontiguousarray(node_parent, dtype=np.int64)
    order = basipetal_order(parent)
    start, _ = _children_csr(parent)
    leaf = (start[1:] - start[:-1]) == 0
    tip = np.ascontiguousarray(node_tip, dtype=np.bool_)
    return _pipe(order, parent, tip, leaf, float(tip_radius) ** exponent, float(exponent))


@njit(cache=True)
def _chains(parent, tip, start, child, order):
    n = parent.shape[0]
    nchild = start[1:] - start[:-1]
    joint = np.zeros(n, np.bool_)
    for i in range(n):
        if parent[i] < 0 or nchild[i] != 1 or tip[i]:
            joint[i] = True
    # each chain starts at a joint and follows children until the next joint
    idx = np.empty(2 * n + 1, np.int64)
    off = np.zeros(n + 1, np.int64)
    m = 0
    k = 0
    for t in range(order.shape[0]):
        v = order[t]
        if not joint[v]:
            continue
        for j in range(start[v], start[v + 1]):
            idx[k] = v
            k += 1
            w = child[j]
            while True:
                idx[k] = w
                k += 1
                if joint[w]:
                    break
                w = child[start[w]]
            m += 1
            off[m] = k
    return idx[:k], off[: m + 1]


def chains(node_parent, node_tip) -> list[np.ndarray]:
    """The skeleton as polylines between joints, each listed from its basal end to its distal end.

    Joints are roots, branch points (not exactly one child), floret tips. Every edge is in exactly
    one chain; chains come in acropetal order (a chain after the chain it grows from).

    Returns
    -------
    list of (k,) int64, k >= 2
    """
    parent = np.ascontiguousarray(node_parent, dtype=np.int64)
    start, child = _children_csr(parent)
    order = basipetal_order(parent)[::-1].copy()
    idx, off = _chains(parent, np.ascontiguousarray(node_tip, dtype=np.bool_), start, child, order)
    return [idx[off[i]:off[i + 1]] for i in range(len(off) - 1)]


def _compact(keep, node_parent, *arrays):
    """Drop nodes not in ``keep`` (a bool mask), re-linking each kept node to its nearest kept ancestor."""
    parent = np.asarray(node_parent, dtype=np.int64)
    n = len(parent)
    order = basipetal_order(parent)[::-1]
    anc = np.full(n, -1, np.int64)  # nearest kept node at or above each node
    for v in order:  # acropetal: parents first
        q = parent[v]
        up = -1 if q < 0 else anc[q]
        anc[v] = v if keep[v] else up
    new_index = np.cumsum(keep) - 1
    kept = np.nonzero(keep)[0]
    new_parent = np.array([-1 if parent[v] < 0 or anc[parent[v]] < 0 else new_index[anc[parent[v]]]
                           for v in kept], dtype=np.int64)
    return (new_parent,) + tuple(a[kept] for a in arrays)


def decimate(node_pos, node_parent, node_tip, tau_d: float):
    """Decimation with threshold tau_d (Runions fig. 3.8).

    Along every chain from base to tip, distances between consecutive nodes accumulate in d_A; a
    node is removed while d_A < tau_d, else kept and d_A reset. Joints (roots, branch points,
    floret tips) are always kept.

    Returns
    -------
    node_pos (m, 3), node_parent (m,), node_tip (m,), kept (m,) int64 (indices into the input)
    """
    pos = np.asarray(node_pos, dtype=np.float64)
    keep = np.ones(len(pos), bool)
    if tau_d > 0:
        for ch in chains(node_parent, node_tip):
            d_a = 0.0
            for a, b in zip(ch[:-2], ch[1:-1]):
                d_a += la.norm(pos[b] - pos[a])
                if d_a < tau_d:
                    keep[b] = False
                else:
                    d_a = 0.0
    ids = np.arange(len(pos))
    parent, pos2, tip2, ids2 = _compact(keep, node_parent, pos, np.asarray(node_tip, bool), ids)
    return pos2, parent, tip2, ids2


def relocate(node_pos, node_parent, node_tip):
    """Move every node except roots and floret tips half way toward its basal neighbour, in
    parallel (Runions fig. 3.1 f): reduces branching angles."""
    pos = np.asarray(node_pos, dtype=np.float64)
    parent = np.asarray(node_parent, dtype=np.int64)
    move = (parent >= 0) & ~np.asarray(node_tip, bool)
    out = pos.copy()
    out[move] = 0.5 * (pos[move] + pos[parent[move]])
    return out


def subdivide(node_pos, node_parent, node_tip, levels: int = 1):
    """Cubic B-spline curve subdivision extended to branching structures (Runions fig. 3.1 g).

    Each edge gets a midpoint node; every node with a parent and exactly one child (not a floret
    tip) moves to ``(a + 6 v + b) / 8`` of its neighbours; joints stay where they are.

    Returns
    -------
    node_pos (m, 3), node_parent (m,), node_tip (m,)
    """
    pos = np.asarray(node_pos, dtype=np.float64)
    parent = np.asarray(node_parent, dtype=np.int64)
    tip = np.asarray(node_tip, bool)
    for _ in range(levels):
        n = len(pos)
        start, child = children_csr(parent)
        nchild = np.diff(start)
        smooth = (parent >= 0) & (nchild == 1) & ~tip
        new = pos.copy()
        if len(child) == 0:
            break
        only_child = np.where(smooth, child[np.minimum(start[:-1], len(child) - 1)], 0)
        a = pos[np.where(smooth, parent, 0)]
        b = pos[only_child]
        new[smooth] = (a[smooth] + 6.0 * pos[smooth] + b[smooth]) / 8.0
        has = np.nonzero(parent >= 0)[0]  # edges v -> parent[v]: midpoint m, v -> m -> parent
        mid = 0.5 * (pos[has] + pos[parent[has]])
        mid_index = n + np.arange(len(has))
        new_parent = parent.copy()
        mid_parent = parent[has].copy()
        new_parent[has] = mid_index
        pos = np.vstack([new, mid])
        parent = np.concatenate([new_parent, mid_parent])
        tip = np.concatenate([tip, np.zeros(len(has), bool)])
    return pos, parent, tip


def check_forest(node_parent) -> None:
    """Raise ValueError unless the parent links form a forest (no cycles, indices in range)."""
    parent = np.asarray(node_parent, dtype=np.int64)
    if len(parent) and (parent.max() >= len(parent) or parent.min() < -1):
        raise ValueError("parent index out of range")
    basipetal_order(parent)
