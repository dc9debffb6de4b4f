"""Vascular patterns in the stem (Runions ch. 6): the closed venation model in a cylinder.

The model (sec. 6.2): a non-elongating cylinder of radius R stands on the z = 0 plane. It starts
with a closed ring of vein nodes at its base (the hypocotyl's vascular ring). Primordia are added at the
top with a constant plastochron: primordium k (k = 1, 2, ...) at height ``first + (k - 1) H`` and
azimuth ``(k - 1) theta`` on the cylinder's surface, each with a vein node, the tip of its leaf trace
entering the stem.

Every vein node is a source (sec. 6.2.1). The set of nodes that select a node v is

    S(v) = { s in V - N(v) | v in V(s) }                                          (eq. 6.2)

where V(s) is the relative neighbourhood of s among all vein nodes (eq. 4.1, computed exactly: no
Urquhart approximation) and N(v) the nodes joined to v by an edge (eq. 6.1). As the relative
neighbourhood is symmetric, S(v) is v's relative neighbours that are not its graph neighbours.

Each iteration:

1. every pair of relative neighbours closer than D and not yet joined is joined by a segment (the
   thesis joins a new node v' to the nodes of S(v') closer than D; joining old pairs too keeps a node
   from overshooting a neighbour closer than one step);
2. every node v with S(v) not empty grows a new node ``v' = v + D n / |n|`` with
   ``n = sum over s in S(v) of (s - v) / |s - v|`` (eq. 3.1), joined to v and kept inside the
   cylinder (radius at most R); v' belongs to v's trace;
3. every ``plastochron`` iterations the next primordium's node is added.

Veins from a primordium grow down and veins of the older vasculature grow up towards it until the
two meet (fig. 6.2). A segment that joins nodes of two traces is a *join*: the later primordium's
trace connects to the earlier one's. The connectivity (a, b) of sec. 6.3 is read from these joins:
primordium n connects to n + a and n + b above it; with the golden angle the differences are
consecutive Fibonacci numbers, their index growing with R/H (figs. 6.8, 6.9).

The relative neighbourhood graph is a subgraph of the Delaunay triangulation (sec. 4.3.1): its pairs
are found among the Delaunay edges (scipy's qhull), each tested against every node in its lune
(a k-d tree query of the ball around the edge's midpoint that holds the lune). Sets too small or
too flat for a 3-D triangulation (the base ring alone) are tested pair by pair.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit
from scipy.spatial import Delaunay, QhullError, cKDTree

from inflo.tools.common.linalg import norm

__all__ = [
    "StemModel",
    "StemRun",
    "relative_neighbour_pairs",
    "relative_neighbour_pairs_brute",
    "simulate",
    "fibonacci_numbers",
]

_REL = 1e-12  # relative slack of the lune test: a node on the lune's boundary does not block


@dataclass(frozen=True)
class StemModel:
    """The parameters of the stem model, in units of D unless said (formats/stem_veins.md)."""

    radius: float = 11.5            # R
    base_nodes: int | None = None   # the hypocotyl ring (None: one node per D of circumference)
    count: int = 30                 # primordia
    step: float = 1.0               # H
    divergence: float = 137.5       # theta, degrees
    first: float | None = None      # height of primordium 1 (None: H)
    plastochron: int = 10           # iterations between primordia
    whorl: int = 1                  # primordia per node (2 with divergence 90: decussate)
    jitter: float = 0.0             # random shift of each primordium's node, in D
    pattern: str = "closed"         # "closed" (sec. 6.2) or "open" (the open model of sec. 4.2)
    seed: int = 0
    D: float = 1.0
    max_iterations: int = 100_000   # the run stops earlier when no vein grows

    @property
    def ring(self) -> int:
        """Nodes of the base ring."""
        if self.base_nodes is not None:
            return self.base_nodes
        return max(3, math.ceil(2 * math.pi * self.radius / self.D))

    @property
    def first_height(self) -> float:
        return self.step if self.first is None else self.first


@dataclass
class StemRun:
    """The pattern: vein nodes, segments, traces and joins."""

    pos: np.ndarray                      # (n, 3) node positions
    trace: np.ndarray                    # (n,) the trace a node belongs to: 0 the base ring, k primordium k
    born: np.ndarray                     # (n,) iteration a node was added
    edges: np.ndarray                    # (m, 2) segments, i < j
    edge_born: np.ndarray                # (m,) iteration a segment was added
    primordium_node: np.ndarray          # (count,) the node of primordium k at index k - 1 (-1: not reached)
    joins: list = field(default_factory=list)   # (iteration, earlier trace, later trace), first join of each pair
    iterations: int = 0
    settled: bool = False                # no vein grew in the last iteration


# ---------------------------------------------------------------------------------------------
# the relative neighbourhood (eq. 4.1)


def relative_neighbour_pairs_brute(pos: np.ndarray) -> np.ndarray:
    """Pairs (i < j) of relative neighbours, every pair against every node: O(n^3), the reference.

    v is a relative neighbour of s iff no other node u has max(|u - s|, |u - v|) < |s - v|.
    """
    pos = np.asarray(pos, dtype=np.float64)
    n = len(pos)
    if n < 2:
        return np.zeros((0, 2), np.int64)
    d = np.sqrt(((pos[:, None, :] - pos[None, :, :]) ** 2).sum(-1))
    out = []
    for i in range(n):
        for j in range(i + 1, n):
            lim = d[i, j] * (1.0 - _REL)
            far = np.maximum(d[i], d[j])
            far[i] = far[j] = np.inf
            if d[i, j] > 0 and not (far < lim).any():
                out.append((i, j))
    return np.array(out, dtype=np.int64).reshape(-1, 2)


@njit(cache=True)
def _lune_empty(pos, pairs, cand_ptr, cand):
    """For each pair (i, j): True when no candidate u (other than i, j) lies strictly inside the
    lune of i and j, max(|u - i|, |u - j|) < |i - j| (1 - rel)."""
    m = pairs.shape[0]
    keep = np.ones(m, np.bool_)
    for e in range(m):
        i = pairs[e, 0]
        j = pairs[e, 1]
        dij = 0.0
        for c in range(3):
            dij += (pos[i, c] - pos[j, c]) ** 2
        dij = math.sqrt(dij)
        if dij == 0.0:
            keep[e] = False
            continue
        lim = dij * (1.0 - 1e-12)
        lim2 = lim * lim
        for k in range(cand_ptr[e], cand_ptr[e + 1]):
            u = cand[k]
            if u == i or u == j:
                continue
            a = 0.0
            b = 0.0
            for c in range(3):
                a += (pos[u, c] - pos[i, c]) ** 2
                b += (pos[u, c] - pos[j, c]) ** 2
            if a < lim2 and b < lim2:
                keep[e] = False
                break
    return keep


def _delaunay_pairs(pos: np.ndarray) -> np.ndarray | None:
    """The Delaunay edges (i < j) that are not the strictly longest side of any Delaunay triangle:
    the Urquhart graph, a superset of the relative neighbourhood graph (the third corner of a
    triangle lies in the lune of its strictly longest side). None when qhull cannot triangulate."""
    try:
        tri = Delaunay(pos)
    except (QhullError, ValueError):
        return None
    s = np.sort(tri.simplices.astype(np.int64), axis=1)
    faces = np.concatenate([s[:, [0, 1, 2]], s[:, [0, 1, 3]], s[:, [0, 2, 3]], s[:, [1, 2, 3]]])
    sides = np.stack([faces[:, [0, 1]], faces[:, [0, 2]], faces[:, [1, 2]]], axis=1)   # (f, 3, 2)
    length = norm(pos[sides[:, :, 0]] - pos[sides[:, :, 1]], axis=2)
    order = np.sort(length, axis=1)
    strict = order[:, 2] > order[:, 1] * (1.0 + 1e-12)
    longest = sides[np.arange(len(sides)), length.argmax(axis=1)][strict]
    n = np.int64(len(pos))
    flat = sides.reshape(-1, 2).astype(np.int64)
    keys = np.unique(flat[:, 0] * n + flat[:, 1])
    if len(longest):
        keys = np.setdiff1d(keys, longest[:, 0].astype(np.int64) * n + longest[:, 1], assume_unique=False)
    return np.column_stack([keys // n, keys % n])


def relative_neighbour_pairs(pos: np.ndarray, tree: cKDTree | None = None) -> np.ndarray:
    """Pairs (i < j) of relative neighbours among ``pos`` (eq. 4.1), exact.

    Candidates are the Delaunay edges (the relative neighbourhood graph is their subgraph); each is
    tested against every node of the ball around its midpoint of radius sqrt(3)/2 |ij|, which holds
    the lune. Fewer than 8 nodes, or nodes qhull cannot triangulate in 3-D (all in one plane), are
    tested pair by pair.
    """
    pos = np.ascontiguousarray(pos, dtype=np.float64)
    n = len(pos)
    pairs = _delaunay_pairs(pos) if n >= 8 else None
    if pairs is None:
        if n > 4000:
            raise ValueError(f"{n} vein nodes qhull cannot triangulate in 3-D")
        return relative_neighbour_pairs_brute(pos)
    tree = cKDTree(pos) if tree is None else tree
    mid = 0.5 * (pos[pairs[:, 0]] + pos[pairs[:, 1]])
    length = norm(pos[pairs[:, 0]] - pos[pairs[:, 1]], axis=1)
    lists = tree.query_ball_point(mid, r=length * (math.sqrt(3.0) / 2.0) * (1.0 + 1e-9), return_sorted=True)
    counts = np.fromiter((len(x) for x in lists), dtype=np.int64, count=len(lists))
    ptr = np.zeros(len(lists) + 1, np.int64)
    np.cumsum(counts, out=ptr[1:])
    cand = np.fromiter((u for x in lists for u in x), dtype=np.int64, count=int(ptr[-1]))
    keep = _lune_empty(pos, pairs.astype(np.int64), ptr, cand)
    return pairs[keep]


# ---------------------------------------------------------------------------------------------
# the simulation


def fibonacci_numbers(limit: int) -> set[int]:
    """The Fibonacci numbers 1, 2, 3, 5, 8, ... up to ``limit``."""
    out, a, b = set(), 1, 2
    out.add(1)
    while b <= limit:
        out.add(b)
        a, b = b, a + b
    return out


def primordia(model: StemModel) -> tuple[np.ndarray, np.ndarray]:
    """Where and when the primordia appear: ``(positions (count, 3), iteration (count,))``.

    Primordia come in whorls of ``whorl`` (1: spiral or distichous; 2 with divergence 90:
    decussate): whorl w (from 0) appears at iteration ``w * plastochron``, at height
    ``first + w H`` and azimuth ``w theta`` (its members a full turn / whorl apart), on the cylinder's
    surface, each shifted by up to ``jitter`` D at random (seeded). They are numbered in order, from 1.
    """
    rng = np.random.default_rng(model.seed)
    k = np.arange(model.count)
    w, j = k // model.whorl, k % model.whorl
    phi = np.radians(model.divergence) * w + 2 * math.pi * j / model.whorl
    p = np.column_stack([model.radius * np.cos(phi), model.radius * np.sin(phi), model.first_height + w * model.step])
    if model.jitter > 0:
        p = p + rng.uniform(-model.jitter, model.jitter, p.shape) * model.D
    return _inside(p, model.radius), (w * model.plastochron).astype(np.int64)


def _inside(p: np.ndarray, radius: float) -> np.ndarray:
    """Points moved radially into the cylinder (radius at most R) and above its base."""
    p = p.copy()
    r = np.hypot(p[:, 0], p[:, 1])
    out = r > radius
    p[out, :2] *= (radius / r[out])[:, None]
    p[:, 2] = np.maximum(p[:, 2], 0.0)
    return p


def _coincident(P: np.ndarray, new: np.ndarray, tol: float) -> np.ndarray:
    """For each new point: the index of an existing point within ``tol`` of it, or of an earlier new
    point (as ``len(P) + k``) within ``tol``, or -1."""
    out = np.full(len(new), -1, np.int64)
    if len(P):
        d, j = cKDTree(P).query(new, k=1, distance_upper_bound=tol)
        hit = np.isfinite(d)
        out[hit] = j[hit]
    if len(new) > 1:
        for a, b in sorted(cKDTree(new).query_pairs(tol)):
            if out[b] < 0:
                out[b] = out[a] if out[a] >= 0 else len(P) + a
    return out


class _Graph:
    """The growing venation graph: nodes, their traces, segments and the joins between traces."""

    def __init__(self, model: StemModel):
        ring = model.ring
        a = 2 * math.pi * np.arange(ring) / ring
        self.P = np.column_stack([model.radius * np.cos(a), model.radius * np.sin(a), np.zeros(ring)])
        self.T = np.zeros(ring, np.int64)
        self.born = [np.zeros(ring, np.int64)]
        self.edges: set[tuple[int, int]] = set()
        self.edge_list: list[tuple[int, int, int]] = []
        self.joined: set[tuple[int, int]] = set()
        self.joins: list[tuple[int, int, int]] = []
        # the hypocotyl's vascular ring: the base nodes joined in a closed ring from the start (the
        # thesis's base nodes "quickly connect into a solid ring", sec. 6.3)
        for k in range(ring):
            self.join(k, (k + 1) % ring, 0)

    def add(self, points: np.ndarray, traces: np.ndarray, iteration: int) -> np.ndarray:
        start = len(self.P)
        self.P = np.vstack([self.P, points])
        self.T = np.concatenate([self.T, traces])
        self.born.append(np.full(len(points), iteration, np.int64))
        return np.arange(start, len(self.P))

    def join(self, i: int, j: int, iteration: int) -> None:
        i, j = (i, j) if i < j else (j, i)
        if i == j or (i, j) in self.edges:
            return
        self.edges.add((i, j))
        self.edge_list.append((i, j, iteration))
        ti, tj = int(self.T[i]), int(self.T[j])
        if ti != tj:
            key = (min(ti, tj), max(ti, tj))
            if key not in self.joined:
                self.joined.add(key)
                self.joins.append((iteration, key[0], key[1]))

    def grow(self, idx: np.ndarray, acc: np.ndarray, model: StemModel, iteration: int,
             traces: np.ndarray | None = None) -> None:
        """Nodes ``idx`` grow one node each, D along ``acc`` (eq. 3.1), kept inside the cylinder; a
        new node on an existing one (or on another new one) is that node. The new nodes belong to
        ``traces`` (default: their parents' traces)."""
        size = norm(acc, axis=1)
        ok = size > 1e-12 * max(len(self.P), 1)
        idx, acc, size = idx[ok], acc[ok], size[ok]
        traces = self.T[idx] if traces is None else np.asarray(traces)[ok]
        if not len(idx):
            return
        new = _inside(self.P[idx] + model.D * acc / size[:, None], model.radius)
        same = _coincident(self.P, new, 1e-6 * model.D)
        keep = same < 0
        start = len(self.P)
        self.add(new[keep], traces[keep], iteration)
        where = np.where(keep, start + np.cumsum(keep) - 1, same)
        for k, v in enumerate(idx):
            target = int(where[k]) if keep[k] or same[k] < start else int(where[same[k] - start])
            self.join(int(v), target, iteration)


def simulate(model: StemModel, progress=None) -> StemRun:
    """Run the stem model until every primordium is placed and no vein grows, or ``max_iterations``.

    ``pattern = "closed"``: every vein node is a source, S(v) by eq. 6.2 (sec. 6.2.1). ``"open"``: the
    open model of sec. 4.2 in the stem: a primordium is a source until a vein reaches it; each
    iteration the vein node closest to each source grows towards it (eq. 3.1), and a source within
    D of a vein node becomes a vein node joined to it, so every trace joins exactly one older trace.
    ``progress(n)`` is called with the iterations done since the last call.
    """
    at, when = primordia(model)
    g = _Graph(model)
    prim_nodes = np.full(model.count, -1, np.int64)
    placed = 0
    pending: list[int] = []          # open pattern: primordia not reached yet
    settled = False
    it = 0
    while it < model.max_iterations:
        new_prims = []
        while placed < model.count and when[placed] <= it:
            new_prims.append(placed)
            placed += 1
        if model.pattern == "closed":
            for k in new_prims:
                prim_nodes[k] = g.add(at[k][None, :], np.array([k + 1]), it)[0]
            active = _closed_step(g, model, it)
        else:
            pending += new_prims
            active = _open_step(g, model, it, at, pending, prim_nodes)
        it += 1
        if progress is not None:
            progress(1)
        if placed >= model.count and not active:
            settled = True
            break
    el = np.array(g.edge_list, dtype=np.int64).reshape(-1, 3)
    return StemRun(pos=g.P, trace=g.T, born=np.concatenate(g.born), edges=el[:, :2], edge_born=el[:, 2],
                   primordium_node=prim_nodes, joins=g.joins, iterations=it, settled=settled)


def _closed_step(g: _Graph, model: StemModel, it: int) -> bool:
    """One iteration of the closed model (eq. 6.2): joins, then growth. True when anything changed."""
    D = model.D
    P = g.P
    pairs = relative_neighbour_pairs(P)
    if not len(pairs):
        return False
    length = norm(P[pairs[:, 0]] - P[pairs[:, 1]], axis=1)
    free = np.fromiter(((int(i), int(j)) not in g.edges for i, j in pairs), dtype=bool, count=len(pairs))
    # 1. relative neighbours not yet joined and at most D apart are joined
    close = free & (length <= D)
    for e in np.nonzero(close)[0]:
        g.join(int(pairs[e, 0]), int(pairs[e, 1]), it)
    free &= ~close
    # 2. every node with S(v) not empty grows one node (eq. 3.1)
    grow = pairs[free]
    if len(grow):
        u = (P[grow[:, 1]] - P[grow[:, 0]]) / length[free][:, None]
        acc = np.zeros_like(P)
        np.add.at(acc, grow[:, 0], u)
        np.add.at(acc, grow[:, 1], -u)
        idx = np.unique(grow)
        g.grow(idx, acc[idx], model, it + 1)
    return bool(close.any() or len(grow))


def _open_step(g: _Graph, model: StemModel, it: int, at, pending: list, prim_nodes) -> bool:
    """One iteration of the open model (sec. 4.2): the closest vein node of each source grows
    towards it; a source within D of a vein node is reached. True while sources wait."""
    if not pending:
        return False
    D = model.D
    src = at[pending]
    tree = cKDTree(g.P)
    _, near = tree.query(src, k=1)
    acc = np.zeros((len(g.P), 3))
    d = src - g.P[near]
    dist = norm(d, axis=1)
    unit = d / np.maximum(dist, 1e-300)[:, None]
    np.add.at(acc, near, unit)
    # a node pulled by sources on opposite sides may step closer to none of them (and then again to
    # the same place): such a node grows towards its closest source instead
    order = np.lexsort((dist, near))
    first = order[np.r_[True, near[order][1:] != near[order][:-1]]]
    for k in first:
        v = near[k]
        a = acc[v]
        na = norm(a)
        step = g.P[v] + D * a / na if na > 0 else g.P[v]
        mine = near == v
        if na == 0 or not (norm(src[mine] - step, axis=1) < dist[mine] - 1e-9 * D).any():
            acc[v] = unit[k]
    # the vein grown towards a primordium is its leaf trace: a new node belongs to the trace of its
    # parent's closest source
    far = dist > D
    owner = {}
    for k in order:
        if far[k] and near[k] not in owner:
            owner[near[k]] = pending[k] + 1
    idx = np.array(sorted(owner), dtype=np.int64)
    g.grow(idx, acc[idx], model, it + 1, np.array([owner[v] for v in idx], dtype=np.int64))
    # sources within D of a vein node become vein nodes of their own trace, joined to it
    dist, near = cKDTree(g.P).query(src, k=1)
    reached = [k for k, dd in zip(pending, dist) if dd <= D]
    for k, n in zip(pending, near):
        if k in reached:
            node = g.add(at[k][None, :], np.array([k + 1]), it + 1)[0]
            prim_nodes[k] = node
            g.join(int(n), int(node), it + 1)
    pending[:] = [k for k in pending if k not in reached]
    return True
