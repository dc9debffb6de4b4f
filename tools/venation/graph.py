"""The venation graph: vein widths (Murray's law / the pipe model, secs. 3.2.3, 4.2.5, 4.3), vein
orders, loops, and the graph as polylines.

The graph is the growth forest (every node joined to the node it grew from; the initial nodes are
the roots, at the leaf base) plus the anastomosis edges of closed patterns. Widths run from the
veinlets to the base over the forest: a node with no children (a vein tip) has the tip width w_0,
and every node

    w(v)^n = sum over the children c of v of w(c)^n  (+ a w_0^n)                 (eq. 3.5)

where n is Murray's exponent (2 in all of the thesis's leaves, table 4.1) and ``a`` the optional
increment of sec. 4.2.5 ("we additionally increase the width of primary and secondary veins at
each node, to approximate the influence of veinlets that are not modeled explicitly"). The width
of node v is that of the segment from v to the node it grew from. Every child contributes equally
(sec. 4.3); an anastomosis edge carries no flow of its own and is drawn at the thinner width of its
two ends.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from inflo.tools.branch_gen.pipe import basipetal_order, chains
from inflo.tools.common import linalg as la

__all__ = ["vein_widths", "strahler_orders", "cycle_rank", "polylines", "check_forest", "elongation_widths",
           "refine_veins"]


@njit(cache=True)
def _widths(order, parent, leaf, w0n, add, n):
    acc = np.zeros(parent.shape[0])
    for k in range(order.shape[0]):
        v = order[k]
        if leaf[v]:
            acc[v] += w0n
        acc[v] += add * w0n
        q = parent[v]
        if q >= 0:
            acc[q] += acc[v]
    return acc ** (1.0 / n)


def vein_widths(node_parent, tip_width: float, exponent: float = 2.0, increment: float = 0.0) -> np.ndarray:
    """(n,) float64: the width of every node's segment by eq. 3.5 (module docstring)."""
    parent = np.ascontiguousarray(node_parent, dtype=np.int64)
    n = len(parent)
    if n == 0:
        return np.zeros(0)
    order = basipetal_order(parent)
    has_child = np.zeros(n, bool)
    has_child[parent[parent >= 0]] = True
    return _widths(order, parent, ~has_child, float(tip_width) ** exponent, float(increment), float(exponent))


@njit(cache=True)
def _strahler(order, parent, leaf):
    n = parent.shape[0]
    best = np.zeros(n, np.int64)  # highest order among the children
    count = np.zeros(n, np.int64)  # children with that order
    out = np.zeros(n, np.int64)
    for k in range(order.shape[0]):
        v = order[k]
        if leaf[v]:
            out[v] = 1
        else:
            out[v] = best[v] + (1 if count[v] >= 2 else 0)
        q = parent[v]
        if q >= 0:
            if out[v] > best[q]:
                best[q] = out[v]
                count[q] = 1
            elif out[v] == best[q]:
                count[q] += 1
    return out


def strahler_orders(node_parent) -> np.ndarray:
    """(n,) int64: the Horton-Strahler order of every node's segment over the growth forest (1 at
    the veinlets; two children of the same order make the next one): the hierarchy of vein orders
    of fig. 4.19."""
    parent = np.ascontiguousarray(node_parent, dtype=np.int64)
    n = len(parent)
    if n == 0:
        return np.zeros(0, np.int64)
    has_child = np.zeros(n, bool)
    has_child[parent[parent >= 0]] = True
    return _strahler(basipetal_order(parent), parent, ~has_child)


def cycle_rank(n_nodes: int, node_parent, extra_edges) -> int:
    """Independent loops of the graph: edges - nodes + connected components (0 for a tree)."""
    parent = np.asarray(node_parent, dtype=np.int64)
    extra = np.asarray(extra_edges, dtype=np.int64).reshape(-1, 2)
    root = np.arange(n_nodes)

    def find(a):
        while root[a] != a:
            root[a] = root[root[a]]
            a = root[a]
        return a

    edges = [(v, int(parent[v])) for v in np.flatnonzero(parent >= 0)] + [tuple(e) for e in extra.tolist()]
    comps = n_nodes
    for a, b in edges:
        ra, rb = find(a), find(b)
        if ra != rb:
            root[ra] = rb
            comps -= 1
    return len(edges) - n_nodes + comps


def polylines(node_parent, extra_edges) -> list[np.ndarray]:
    """The graph as polylines: the growth forest's chains between joints (roots, branch points,
    tips), each from its basal end, then one two-node line per anastomosis edge."""
    parent = np.ascontiguousarray(node_parent, dtype=np.int64)
    out = list(chains(parent, np.zeros(len(parent), bool))) if len(parent) else []
    out.extend(np.asarray(e, dtype=np.int64) for e in np.asarray(extra_edges, dtype=np.int64).reshape(-1, 2))
    return out


def check_forest(node_parent) -> bool:
    """True when every node reaches a root by its parents (no cycle in the growth forest)."""
    parent = np.asarray(node_parent, dtype=np.int64)
    order = basipetal_order(parent)
    return len(order) == len(parent)


# --------------------------------------------------------------------------------------------
# Runions ch. 5 refinements: widths by elongation, adaptive corner cutting


def elongation_widths(node_pos, node_parent, step: float, tip_width: float) -> np.ndarray:
    """(n,) float64: widths by elongation (sec. 5.2: "the width of each vein node v increases in
    proportion to the elongation of the vein segments containing v", instead of the pipe model).

    Every segment is D long when it forms; its elongation is its final length over D (the blade's
    growth stretched it), and w(v) = w_0 max(1, |v - parent(v)| / D). An initial node takes its
    longest child segment's width. Marginal growth stretches no vein: every width is w_0."""
    pos = np.asarray(node_pos, dtype=np.float64).reshape(-1, 2)
    parent = np.asarray(node_parent, dtype=np.int64)
    n = len(parent)
    e = np.ones(n)
    has = parent >= 0
    e[has] = la.norm(pos[has] - pos[parent[has]], axis=1) / float(step)
    roots = np.flatnonzero(~has)
    if len(roots) and has.any():
        best = np.zeros(n)
        np.maximum.at(best, parent[has], e[has])
        e[roots] = np.where(best[roots] > 0, best[roots], 1.0)
    return float(tip_width) * np.maximum(e, 1.0)


@njit(cache=True)
def _seed(s):
    np.random.seed(s)


@njit(cache=True)
def _cut_corners(pts, owner, thr, alpha, jitter):
    """Adaptive Chaikin corner cutting of one polyline with fixed ends (sec. 5.2.6, fig. 5.6):
    an interior vertex P2 whose two segments are together longer than ``thr`` is replaced by
    P_n1 = (1 - alpha) P1 + alpha P2 and P_n2 = (1 - alpha) P3 + alpha P2 (eqs. 5.3, 5.4), each
    moved by up to ``jitter`` times |P_n1 - P_n2| in a random direction; sweeps repeat until no
    corner is cut (at most 64). Returns (points, original index or -1, owner index)."""
    m = pts.shape[0]
    p = pts.copy()
    own = owner.copy()
    keep = np.arange(m)
    for _ in range(64):
        if m < 3:
            break
        q = np.empty((2 * m, 2))
        qo = np.empty(2 * m, np.int64)
        qk = np.empty(2 * m, np.int64)
        q[0] = p[0]
        qo[0] = own[0]
        qk[0] = keep[0]
        j = 1
        changed = False
        for i in range(1, m - 1):
            ax, ay = q[j - 1, 0], q[j - 1, 1]
            bx, by = p[i, 0], p[i, 1]
            cx, cy = p[i + 1, 0], p[i + 1, 1]
            ln = math.sqrt((bx - ax) ** 2 + (by - ay) ** 2) + math.sqrt((cx - bx) ** 2 + (cy - by) ** 2)
            if ln > thr:
                x1, y1 = (1.0 - alpha) * ax + alpha * bx, (1.0 - alpha) * ay + alpha * by
                x2, y2 = (1.0 - alpha) * cx + alpha * bx, (1.0 - alpha) * cy + alpha * by
                if jitter > 0.0:
                    r = jitter * math.sqrt((x2 - x1) ** 2 + (y2 - y1) ** 2)
                    for t in range(2):
                        ang = 2.0 * math.pi * np.random.random()
                        rr = r * math.sqrt(np.random.random())
                        if t == 0:
                            x1 += rr * math.cos(ang)
                            y1 += rr * math.sin(ang)
                        else:
                            x2 += rr * math.cos(ang)
                            y2 += rr * math.sin(ang)
                q[j, 0], q[j, 1] = x1, y1
                q[j + 1, 0], q[j + 1, 1] = x2, y2
                qo[j] = own[i]
                qo[j + 1] = own[i]
                qk[j] = -1
                qk[j + 1] = -1
                j += 2
                changed = True
            else:
                q[j] = p[i]
                qo[j] = own[i]
                qk[j] = keep[i]
                j += 1
        q[j] = p[m - 1]
        qo[j] = own[m - 1]
        qk[j] = keep[m - 1]
        j += 1
        p, own, keep, m = q[:j].copy(), qo[:j].copy(), qk[:j].copy(), j
        if not changed:
            break
    return p, keep, own


def refine_veins(node_pos, node_parent, extra_edges, threshold: float, alpha: float = 0.75, jitter: float = 0.0,
                 seed: int = 1):
    """Adaptive vein refinement (Runions sec. 5.2.6, fig. 5.6, eqs. 5.3-5.4) of the final graph:
    corner cutting along every chain of the growth forest between joints (initial nodes, branch
    points, tips, the ends of anastomoses), which stay where they are; a corner is cut when its two
    segments are together longer than ``threshold`` (blade units), so only the veins that growth
    stretched are smoothed (the thesis cuts them as they stretch; here the cuts are made on the
    finished pattern, so the new nodes take no part in the simulation).

    Returns
    -------
    pos (n', 2), parent (n',), extra (e, 2), owner (n',)
        The refined graph: the nodes kept first, in their old order, then the new ones chain by
        chain; ``owner[i]`` is the old node whose segment node i's segment replaces (for widths
        and creation iterations).
    """
    pos = np.asarray(node_pos, dtype=np.float64).reshape(-1, 2)
    parent = np.asarray(node_parent, dtype=np.int64)
    extra = np.asarray(extra_edges, dtype=np.int64).reshape(-1, 2)
    n = len(parent)
    if n == 0 or threshold <= 0:
        return pos.copy(), parent.copy(), extra.copy(), np.arange(n)
    joint = np.zeros(n, bool)
    joint[extra.ravel()] = True
    _seed(int(seed) % (2 ** 31))
    removed = np.zeros(n, bool)
    new_pts, new_owner, _new_parent_ref = [], [], []  # new_parent_ref: ('old', i) or ('new', k) encoded
    links = []  # (child ref, parent ref) for every edge inside refined chains
    for c in chains(parent, joint):
        if len(c) < 3:
            continue
        p, keep, own = _cut_corners(pos[c], c.astype(np.int64), float(threshold), float(alpha), float(jitter))
        if len(p) == len(c) and np.array_equal(keep, np.arange(len(c))):
            continue
        removed[c[1:-1]] = True
        refs = []
        for k in range(len(p)):
            if keep[k] >= 0:
                old = int(c[keep[k]])
                removed[old] = False
                refs.append(old)
            else:
                refs.append(n + len(new_pts))
                new_pts.append(p[k])
                new_owner.append(int(own[k]))
        for a, b in zip(refs[:-1], refs[1:]):
            links.append((b, a))
    kept = np.flatnonzero(~removed)
    index = np.full(n + len(new_pts), -1, np.int64)
    index[kept] = np.arange(len(kept))
    index[n:] = len(kept) + np.arange(len(new_pts))
    out_pos = np.concatenate([pos[kept], np.asarray(new_pts, np.float64).reshape(-1, 2)])
    par_full = np.concatenate([parent, np.full(len(new_pts), -1, np.int64)])
    for child, par in links:
        par_full[child] = par
    keep_all = np.r_[kept, n + np.arange(len(new_pts))]
    out_parent = np.where(par_full[keep_all] >= 0, index[np.maximum(par_full[keep_all], 0)], -1)
    owner = np.r_[kept, np.asarray(new_owner, np.int64)]
    return out_pos, out_parent.astype(np.int64), index[extra], owner
