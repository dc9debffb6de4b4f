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

import numpy as np
from numba import njit

from inflo.tools.branch_gen.pipe import basipetal_order, chains

__all__ = ["vein_widths", "strahler_orders", "cycle_rank", "polylines", "check_forest"]


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
