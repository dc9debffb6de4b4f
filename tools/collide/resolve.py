"""Continuous collision detection over a mesh and the collision-resolution loop (thesis 4.2-4.3, Alg. 1).

:func:`detect_collisions` runs the broad phase (:mod:`.broad`) and the narrow phase (:mod:`.ccd`) for
every vertex-triangle and edge-edge pair of a triangle mesh moving linearly from ``x0`` to ``x1``
and returns the pairs that need a response (an odd number of crossings, 4.2.2.3) as collision
constraints (:mod:`.response`). Pairs sharing a vertex are skipped (a triangle's own vertices, two
edges of one triangle fan): self-collisions within one floret count like any other.

:func:`resolve_collisions` is lines 10-20 of Algorithm 1 with the retries of the ``max collision
retries`` key: detect, add the new collision constraints to the set, solve the set for
``collision iterations`` sweeps, re-detect. The rounds stop early when the crossing pairs stall
(``STALL_ROUNDS``) or run away (``RUNAWAY_FACTOR``), and then end on the positions of their best
round (fewest pairs crossing), not their last. Pairs still crossing are reported and, so that the
output stays collision-free, their vertices are put back where they were at the start of the step
(``x0`` is collision-free; repeated while crossings are left, at most 10 times, then the whole
step is put back). Used by
``fccompose`` (growth) and ``subdivide`` (from the in-plane quadrisected mesh to the Loop positions).
``fccompose`` uses the whole-part fallback instead (``fallback="parts"``, :func:`retreat_parts`,
:func:`reshape_parts`), with a relaxation of the internal constraints between rounds and repair
passes for parts left out of shape, so that a floret is never torn by the fallback.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit, prange

from .broad import (
    PARTS_ANY,
    PARTS_CROSS,
    PARTS_SAME,
    BoxGrid,
    _element_range,
    _sorted_pairs,
    box_pairs,
    edge_boxes,
    triangle_boxes,
    vertex_boxes,
)
from .ccd import edge_edge_ccd, edge_edge_culled, vertex_triangle_ccd, vertex_triangle_culled
from .probe import can_probe, probe_contacts
from .response import project_collision_constraints

__all__ = ["Contacts", "CollisionResult", "detect_collisions", "resolve_collisions", "default_tolerance",
           "retreat_parts", "RetreatResult"]

KIND_VT = 0
KIND_EE = 1
#: repair passes for parts left out of shape (``fallback="parts"`` with ``relax``), and the
#: relaxations (each ``relax`` call's sweeps) of one pass
REPAIR_PASSES = 2
REPAIR_RELAXATIONS = 4
#: detect/solve rounds without fewer crossing pairs after which the retries stop early
STALL_ROUNDS = 4
#: a round that finds more crossing pairs than the first round did and more than this many times
#: the fewest of the rounds before it ends the retries at once: the response is diverging (florets
#: squeezed with no room, each round undoing the last: a squeezed head's rounds went 2,659 -> 110
#: -> 4,548 -> ... -> 426,428 pairs, each round slower than the one before); the rounds then end
#: on their best round's positions. (The factor alone also cut converging rounds short: the 350k
#: benchmark canopy's 6,819 -> 72 -> 1 -> 11 -> ... -> 0.)
RUNAWAY_FACTOR = 8
#: slack of the round-0 broad-phase boxes, in mean triangle box extents (:class:`_StepBroadPhase`;
#: about what a collision round moves a vertex: more slack keeps more vertices inside their round-0
#: boxes but pairs more boxes; flat, densely packed florets (the yarrow's) pair many more)
BROAD_SLACK = 0.05
#: parts (florets) whose mean motion over a step is over this many times the mean triangle box
#: extent have their own pairs found in the part's moving frame (:class:`_SplitBroadPhase`)
SPLIT_MOTION = 0.25
#: the retry rounds' grids over the elements that left their round-0 boxes are rebuilt in full
#: when those re-anchored since are more than this fraction of them (:meth:`_StepBroadPhase._moved_grids`)
REBUILD_FRACTION = 0.25
#: round 0 with pair lists pairs the grown boxes of every element at once (False: the true boxes,
#: the grown ones of each element the first round it is active)
ROUND0_GROWN_PAIRS = True


@dataclass
class Contacts:
    """Collision constraints as structure of arrays (one row per colliding pair).

    Attributes
    ----------
    kind : (k,) int8
        0 vertex-triangle (C_vt, eq. 4.6), 1 edge-edge (C_ee, eq. 4.7).
    indices : (k, 4) int32
        (q, a, b, c) for vertex q and triangle abc; (a, b, c, d) for edges ab and cd.
    coef : (k, 4) float64
        Constraint coefficients (see :mod:`.response`).
    normal : (k, 3) float64
        Unit contact normals, pointing to the side the first element came from.
    toi : (k,) float64
        First time of impact in the step.
    element : (k, 2) int32
        (vertex, triangle) or (edge, edge) indices of the pair.
    reach : (k,) float64
        Deepest violation the constraint may correct (beyond 2 h): four times the largest motion
        of its vertices over the step, plus four tolerances (see
        :func:`.response.project_collision_constraints`).
    """

    kind: np.ndarray
    indices: np.ndarray
    coef: np.ndarray
    normal: np.ndarray
    toi: np.ndarray
    element: np.ndarray
    reach: np.ndarray

    def __len__(self) -> int:
        return len(self.kind)

    @staticmethod
    def empty() -> Contacts:
        return Contacts(np.zeros(0, np.int8), np.zeros((0, 4), np.int32), np.zeros((0, 4)),
                        np.zeros((0, 3)), np.zeros(0), np.zeros((0, 2), np.int32), np.zeros(0))

    def concat(self, other: Contacts) -> Contacts:
        """Rows of ``self`` then the new rows of ``other``; a pair already in ``self`` (same kind
        and indices) found again takes ``other``'s newer normal, coefficients and time of impact
        (the one it was found with may point the wrong way once the elements have turned)."""
        if len(other) == 0:
            return self
        if len(self) == 0:
            return other
        inv = _row_groups(np.concatenate([self.kind, other.kind]),
                          np.concatenate([self.indices, other.indices]))
        row = np.full(len(inv), -1, np.int64)
        row[inv[: len(self)]] = np.arange(len(self))  # the rows of self are distinct pairs
        where = row[inv[len(self):]]
        new = where < 0
        old = ~new
        merged = Contacts(*(getattr(self, f).copy() for f in _FIELDS))
        for f in ("coef", "normal", "toi", "element", "reach"):
            getattr(merged, f)[where[old]] = getattr(other, f)[old]
        return Contacts(*(np.concatenate([getattr(merged, f), getattr(other, f)[new]])
                          for f in _FIELDS))


_FIELDS = ("kind", "indices", "coef", "normal", "toi", "element", "reach")


def _row_groups(kind: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """(k,) int64: one id per distinct (kind, indices) row, equal for equal rows (the inverse of
    ``np.unique(rows, axis=0)``, from a sort of two int64 keys: the kind and two indices, the
    other two; unique over rows of five columns sorts them as bytes, several times slower)."""
    ind = np.asarray(indices, dtype=np.int64)
    k = np.asarray(kind, dtype=np.int64)
    if len(ind) == 0 or ind.min() < 0 or k.min() < 0 or k.max() > 1:
        rows = np.concatenate([k[:, None], ind], axis=1)
        return np.unique(rows, axis=0, return_inverse=True)[1].ravel().astype(np.int64)
    k1 = (k << np.int64(62)) | (ind[:, 0] << np.int64(31)) | ind[:, 1]
    k2 = (ind[:, 2] << np.int64(31)) | ind[:, 3]
    order = np.lexsort((k2, k1))
    s1, s2 = k1[order], k2[order]
    start = np.ones(len(order), bool)
    start[1:] = (s1[1:] != s1[:-1]) | (s2[1:] != s2[:-1])
    inv = np.empty(len(order), np.int64)
    inv[order] = np.cumsum(start) - 1
    return inv


def default_tolerance(x0: np.ndarray, thickness: float) -> float:
    """Inside-test tolerance of the narrow phase: 1e-6 of the scene's size, at most half the
    thickness h.

    The tolerance only absorbs rounding at the moment of coplanarity (a vertex through a triangle's
    edge, two edges crossing end to end); the distance h is kept by the collision constraints,
    which push to ``max(h, 2 tol)``. A tolerance as large as h would report every vertex within h
    of a neighbouring triangle of its own mesh (e.g. near a petal's narrow base) as a collision.
    """
    if len(x0) == 0:
        return 1e-12
    size = float(np.max(x0.max(axis=0) - x0.min(axis=0)))
    tol = max(1e-6 * size, 1e-12)
    if thickness > 0:
        tol = min(tol, 0.5 * float(thickness))
    return tol


# --------------------------------------------------------------------------------------------------
# Narrow phase over candidate pairs
# --------------------------------------------------------------------------------------------------


@njit(cache=True, inline="always")
def _narrow_vt_one(k, x0, x1, tri, pairs, tol, hits, info):
    v = pairs[k, 0]
    t = pairs[k, 1]
    a = tri[t, 0]
    b = tri[t, 1]
    c = tri[t, 2]
    if v == a or v == b or v == c or vertex_triangle_culled(x0, x1, v, a, b, c):
        hits[k] = 0
    else:  # info[k] (zeros) is written only on a hit
        hits[k] = vertex_triangle_ccd(x0[v], x0[a], x0[b], x0[c], x1[v], x1[a], x1[b], x1[c], tol, info[k])


@njit(cache=True, inline="always")
def _narrow_ee_one(k, x0, x1, edges, pairs, tol, hits, info):
    e = pairs[k, 0]
    f = pairs[k, 1]
    a = edges[e, 0]
    b = edges[e, 1]
    c = edges[f, 0]
    d = edges[f, 1]
    if a == c or a == d or b == c or b == d or edge_edge_culled(x0, x1, a, b, c, d):
        hits[k] = 0
    else:
        hits[k] = edge_edge_ccd(x0[a], x0[b], x0[c], x0[d], x1[a], x1[b], x1[c], x1[d], tol, info[k])


@njit(cache=True, parallel=True)
def _narrow_vt(x0, x1, tri, pairs, tol, hits, info):
    for k in prange(pairs.shape[0]):
        _narrow_vt_one(k, x0, x1, tri, pairs, tol, hits, info)


@njit(cache=True, parallel=True)
def _narrow_ee(x0, x1, edges, pairs, tol, hits, info):
    for k in prange(pairs.shape[0]):
        _narrow_ee_one(k, x0, x1, edges, pairs, tol, hits, info)


@njit(cache=True)
def _narrow_vt_serial(x0, x1, tri, pairs, tol, hits, info):
    for k in range(pairs.shape[0]):
        _narrow_vt_one(k, x0, x1, tri, pairs, tol, hits, info)


@njit(cache=True)
def _narrow_ee_serial(x0, x1, edges, pairs, tol, hits, info):
    for k in range(pairs.shape[0]):
        _narrow_ee_one(k, x0, x1, edges, pairs, tol, hits, info)


#: below this many candidate pairs the narrow phase runs on one thread (waking the thread pool
#: costs milliseconds on a loaded 2-core machine; a retry round has a few thousand pairs)
SERIAL_NARROW_BELOW = 20000


@njit(cache=True)
def _build_contacts(x0, x1, kind, idx, coef, toi, normal, ok):
    """Contact normal at the time of impact, oriented to the side the pair started on."""
    n = idx.shape[0]
    p = np.empty((4, 3))
    for k in range(n):
        t = toi[k]
        for j in range(4):
            v = idx[k, j]
            for d in range(3):
                p[j, d] = x0[v, d] + t * (x1[v, d] - x0[v, d])
        # plane normal: triangle (vt, j = 1..3) or the two edges (ee), from coef signs
        if kind[k] == 0:
            ux = p[2, 0] - p[1, 0]
            uy = p[2, 1] - p[1, 1]
            uz = p[2, 2] - p[1, 2]
            wx = p[3, 0] - p[1, 0]
            wy = p[3, 1] - p[1, 1]
            wz = p[3, 2] - p[1, 2]
        else:
            ux = p[1, 0] - p[0, 0]
            uy = p[1, 1] - p[0, 1]
            uz = p[1, 2] - p[0, 2]
            wx = p[3, 0] - p[2, 0]
            wy = p[3, 1] - p[2, 1]
            wz = p[3, 2] - p[2, 2]
        nx = uy * wz - uz * wy
        ny = uz * wx - ux * wz
        nz = ux * wy - uy * wx
        ln = math.sqrt(nx * nx + ny * ny + nz * nz)
        # separation at t = 0 along the closest-point direction (fallback normal)
        sx = 0.0
        sy = 0.0
        sz = 0.0
        vx = 0.0
        vy = 0.0
        vz = 0.0
        for j in range(4):
            v = idx[k, j]
            sx += coef[k, j] * x0[v, 0]
            sy += coef[k, j] * x0[v, 1]
            sz += coef[k, j] * x0[v, 2]
            vx += coef[k, j] * (x1[v, 0] - x0[v, 0])
            vy += coef[k, j] * (x1[v, 1] - x0[v, 1])
            vz += coef[k, j] * (x1[v, 2] - x0[v, 2])
        scale = 0.0
        for j in range(4):
            for d in range(3):
                scale = max(scale, abs(p[j, d] - p[0, d]))
        if ln <= 1e-12 * scale * scale or ln == 0.0:
            ls = math.sqrt(sx * sx + sy * sy + sz * sz)
            if ls == 0.0:
                lv = math.sqrt(vx * vx + vy * vy + vz * vz)
                if lv == 0.0:
                    ok[k] = False
                    continue
                nx, ny, nz, ln = -vx, -vy, -vz, lv
            else:
                nx, ny, nz, ln = sx, sy, sz, ls
        nx /= ln
        ny /= ln
        nz /= ln
        side = sx * nx + sy * ny + sz * nz
        if side < 0.0 or (side == 0.0 and (vx * nx + vy * ny + vz * nz) > 0.0):
            nx = -nx
            ny = -ny
            nz = -nz
        normal[k, 0] = nx
        normal[k, 1] = ny
        normal[k, 2] = nz
        ok[k] = True


def _candidates(x0, x1, tri, edges, pad, cell_size, active):
    vb = vertex_boxes(x0, x1, pad)
    tb = triangle_boxes(x0, x1, tri, pad)
    eb = edge_boxes(x0, x1, edges, pad)
    if active is None:
        return box_pairs(vb, tb, cell_size=cell_size), box_pairs(eb, None, cell_size=cell_size)
    av = np.nonzero(active)[0]
    at = np.nonzero(active[tri].any(axis=1))[0]
    ae = np.nonzero(active[edges].any(axis=1))[0]
    # the grids are built on all elements and queried by the (few) active boxes only
    vt = _merge_vt(box_pairs(vb[av], tb, cell_size=cell_size), av, None,
                   box_pairs(tb[at], vb, cell_size=cell_size), at, active)
    ee = _merge_ee(box_pairs(eb[ae], eb, cell_size=cell_size), ae, None, active[edges].any(axis=1))
    return _sorted_pairs(vt), _sorted_pairs(ee)


def _merge_vt(p_vert, av, t_map, p_tri, at, v_active, v_map=None):
    """Vertex-triangle pairs from the active vertices' query ``p_vert`` (rows: index into ``av``,
    triangle (through ``t_map`` if given)) and the active triangles' query ``p_tri`` (rows: index
    into ``at``, vertex (through ``v_map``)); a pair of an active vertex and an active triangle is in
    both and kept once (from the first)."""
    t = p_vert[:, 1] if t_map is None else t_map[p_vert[:, 1]]
    first = np.stack([av[p_vert[:, 0]], t], axis=1)
    v = p_tri[:, 1] if v_map is None else v_map[p_tri[:, 1]]
    keep = ~v_active[v]
    second = np.stack([v[keep], at[p_tri[keep, 0]]], axis=1)
    return np.ascontiguousarray(np.concatenate([first, second]), dtype=np.int32)


def _merge_ee(p_edge, ae, e_map, e_active):
    """Edge-edge pairs from the active edges' query ``p_edge`` (rows: index into ``ae``, edge
    (through ``e_map``)): no pair of an edge with itself, a pair of two active edges once, each pair
    as (smaller, larger)."""
    e = ae[p_edge[:, 0]]
    f = p_edge[:, 1] if e_map is None else e_map[p_edge[:, 1]]
    keep = (e != f) & (~e_active[f] | (e < f))
    e = e[keep]
    f = f[keep]
    return np.ascontiguousarray(np.stack([np.minimum(e, f), np.maximum(e, f)], axis=1), dtype=np.int32)


@njit(cache=True)
def _touching(flags, idx):
    """(f, k) bool: element k (a row of ``idx``) has a vertex flagged in row i of the (f, n) bool
    ``flags`` (f <= 8; one pass over the elements for every row, the rows packed as bits)."""
    bits = np.zeros(flags.shape[1], np.uint8)
    for i in range(flags.shape[0]):
        for v in range(flags.shape[1]):
            if flags[i, v]:
                bits[v] |= np.uint8(1 << i)
    out = np.zeros((flags.shape[0], idx.shape[0]), np.bool_)
    for k in range(idx.shape[0]):
        b = np.uint8(0)
        for j in range(idx.shape[1]):
            b |= bits[idx[k, j]]
        if b:
            for i in range(flags.shape[0]):
                out[i, k] = (b >> i) & 1
    return out


@njit(cache=True)
def _box_stats(vb, tb, eb):
    """Origin (min corner of the vertex boxes), mean largest side of the triangle boxes, and the
    largest side of any box."""
    origin = np.zeros(3)
    if vb.shape[0]:
        for d in range(3):
            origin[d] = np.inf
    for i in range(vb.shape[0]):
        for d in range(3):
            origin[d] = min(origin[d], vb[i, d])
    span = 0.0
    mean = 0.0
    for k in range(3):
        boxes = vb if k == 0 else (tb if k == 1 else eb)
        for i in range(boxes.shape[0]):
            m = 0.0
            for d in range(3):
                m = max(m, boxes[i, d + 3] - boxes[i, d])
            span = max(span, m)
            if k == 1:
                mean += m
    if tb.shape[0]:
        mean /= tb.shape[0]
    return origin, mean, span


@njit(cache=True, inline="always")
def _element_sides(x0, x1, idx, pad, span):
    """Sum over the elements (rows of ``idx``) of their boxes' largest sides (boxes as
    :func:`.broad.triangle_boxes`: from ``x0`` to ``x1``, grown by ``pad``), and the largest side
    of any, or ``span`` if larger."""
    total = 0.0
    for e in range(idx.shape[0]):
        m = 0.0
        for d in range(3):
            lo, hi = _element_range(x0, x1, idx, e, d)
            m = max(m, (hi + pad) - (lo - pad))
        span = max(span, m)
        total += m
    return total, span


@njit(cache=True)
def _step_box_stats(x0, x1, tri, edges, pad):
    """:func:`_box_stats` of the vertex, triangle and edge boxes from ``x0`` to ``x1`` grown by
    ``pad``, read from the positions without writing the boxes (the same values, bit for bit: the
    same operations in the same order; round 0 of a 350k-triangle step spent 38 ms writing 70 MB of
    boxes that only these figures were taken from)."""
    origin = np.zeros(3)
    if x0.shape[0]:
        for d in range(3):
            origin[d] = np.inf
    span = 0.0
    for i in range(x0.shape[0]):
        m = 0.0
        for d in range(3):
            lo = min(x0[i, d], x1[i, d]) - pad
            hi = max(x0[i, d], x1[i, d]) + pad
            origin[d] = min(origin[d], lo)
            m = max(m, hi - lo)
        span = max(span, m)
    total, span = _element_sides(x0, x1, tri, pad, span)
    _, span = _element_sides(x0, x1, edges, pad, span)
    mean = total / tri.shape[0] if tri.shape[0] else 0.0
    return origin, mean, span


@njit(cache=True)
def _changed(x, before):
    """(n,) bool: row i of ``x`` differs from ``before``."""
    out = np.zeros(x.shape[0], np.bool_)
    for i in range(x.shape[0]):
        out[i] = x[i, 0] != before[i, 0] or x[i, 1] != before[i, 1] or x[i, 2] != before[i, 2]
    return out


class _StepBroadPhase:
    """The broad phase of one step's detection rounds (Alg. 1 lines 10-20).

    Round 0 builds grids over every element's box (from ``x0`` to the predicted ``x1``), grown by
    a slack of ``BROAD_SLACK`` mean triangle extents, and pairs the elements' true boxes against
    them (kept where the true boxes overlap). Later rounds test only pairs with an active element
    (one with a vertex the last round's constraints moved, or in a pair still crossing). A vertex
    that has moved by no more than the slack in any coordinate since round 0 is still inside its
    grown round-0 box, and so are its elements' boxes: the pairs of two such elements are among
    the grown boxes' pairs (kept where an element is active and the current boxes overlap). Those
    pairs are found for an element the first round it is active and kept for the rest of the step
    (:meth:`_extend`): a step's retries touch a small part of a large canopy (a tenth of the final
    yarrow's vertices), and pairing every grown box was half of its collision time. A vertex that
    leaves the slack about its anchor (round 0's ``x1``; few do: the collision response moves
    vertices by about the thickness) is re-anchored where it is, and the elements it belongs to are
    paired afresh by their boxes at the new anchors grown by the slack (:meth:`_reanchor`): against
    round 0's grids for the elements that never left, and against grids over the anchored boxes of
    those that did (rebuilt in full only now and then: :meth:`_moved_grids`). Their pairs are kept
    until one of the two leaves again, so a round's work is that of the vertices that leave in it,
    not of every active element (the final yarrow's 350k canopy: the retry rounds' broad phase
    12.7 -> 9.8 s over six late frames).
    """

    def __init__(self, x0, tri, edges, pad, cell_size, vertex_part=None, parts_mode=PARTS_ANY):
        self.x0 = x0
        self.tri = tri
        self.edges = edges
        self.pad = pad
        self.cell_size = cell_size
        self.moved = np.zeros(len(x0), np.bool_)
        """vertices that have left their round-0 box (the slack), in some round since round 0"""
        self.mode = parts_mode
        """pairs kept: any (``PARTS_ANY``), within one part only, or of two parts only"""
        if parts_mode != PARTS_ANY:
            vp = np.ascontiguousarray(vertex_part, dtype=np.int32)
            self.vpart, self.tpart, self.epart = vp, vp[tri[:, 0]], vp[edges[:, 0]]
        else:
            self.vpart = self.tpart = self.epart = None

    def _parts(self, of, idx=None):
        """The parts of elements (``of``: vpart/tpart/epart; ``idx``: a subset), None for any."""
        if of is None:
            return None
        return of if idx is None else of[idx]

    def _filter(self, pairs_vt, pairs_ee):
        """Pairs found without the part filter (the far-moved fallback), filtered."""
        if self.mode == PARTS_ANY:
            return pairs_vt, pairs_ee
        same = self.mode == PARTS_SAME
        kv = (self.vpart[pairs_vt[:, 0]] == self.tpart[pairs_vt[:, 1]]) == same
        ke = (self.epart[pairs_ee[:, 0]] == self.epart[pairs_ee[:, 1]]) == same
        return np.ascontiguousarray(pairs_vt[kv]), np.ascontiguousarray(pairs_ee[ke])

    def first(self, x1, pairs=True):
        """Round 0: the grown boxes' grids for the later rounds; the pairs of the true boxes
        (None with ``pairs=False``: round 0 was detected otherwise)."""
        x0, tri, edges, pad = self.x0, self.tri, self.edges, self.pad
        origin, mean, span = _step_box_stats(x0, x1, tri, edges, pad)
        cell = self.cell_size
        if cell is None or not cell > 0:
            cell = mean if mean > 0 else 1.0
        if span > 64.0 * cell:  # guard against absurd cell counts (as box_pairs)
            cell = span / 64.0
        self.cell = cell
        self.origin = origin
        self.slack = BROAD_SLACK * (mean if mean > 0 else cell)
        self.ref = x1.copy()
        """each vertex's anchor: round 0's ``x1`` until it leaves the slack about it (then where it is)"""
        grow = pad + self.slack
        self.vb = vertex_boxes(x0, x1, grow)
        self.tb = triangle_boxes(x0, x1, tri, grow)
        self.eb = edge_boxes(x0, x1, edges, grow)
        self.vid = np.arange(len(x0), dtype=np.int32)[:, None]
        m = self.mode
        self.grid_t = BoxGrid(self.tb, cell, self.origin, tri, parts=self.tpart)
        self.grid_e = BoxGrid(self.eb, cell, self.origin, edges, parts=self.epart)
        self.grid_v = None
        # the grown boxes' pairs of the elements active so far (the later rounds'): _extend
        self.vt0 = np.zeros((0, 2), np.int32)
        self.ee0 = np.zeros((0, 2), np.int32)
        self.have_v = np.zeros(len(x0), np.bool_)
        self.have_t = np.zeros(len(tri), np.bool_)
        self.have_e = np.zeros(len(edges), np.bool_)
        # the pairs of the elements that have left (a vertex moved): by their anchors (_reanchor)
        self.mvt = np.zeros((0, 2), np.int32)
        self.mee = np.zeros((0, 2), np.int32)
        self.moved[:] = False
        self.none_v = np.zeros(len(x0), np.bool_)
        self.none_t = np.zeros(len(tri), np.bool_)
        self.none_e = np.zeros(len(edges), np.bool_)
        self.far = False
        self.grids_all = None
        self.stale = (np.zeros(len(x0), np.bool_), np.zeros(len(tri), np.bool_), np.zeros(len(edges), np.bool_))
        if not pairs:
            return None
        # this round's pairs: the grown boxes' pairs (those of the later rounds, all of them at once:
        # a step that asks for round 0's pairs expects retries, whose first round is active over
        # most of a crowded canopy), kept where the true boxes overlap (a grown box holds its true
        # box: none is missed)
        none = np.zeros(len(x0), np.bool_)
        no_t = np.zeros(len(tri), np.bool_)
        no_e = np.zeros(len(edges), np.bool_)
        if ROUND0_GROWN_PAIRS:
            vt = self.vt0 = self.grid_t.query(self.vb, vertices=self.vid, parts=self.vpart, parts_mode=m)
            # (in (a, b) order: the retry rounds scan them, and in order their reads stay local)
            ee = self.ee0 = _sorted_pairs(self.grid_e.self_pairs(vertices=True, parts_mode=m))
            self.have_v[:] = True
            self.have_t[:] = True
            self.have_e[:] = True
        else:
            vb = vertex_boxes(x0, x1, pad)
            vt = self.grid_t.query(vb, vertices=self.vid, parts=self.vpart, parts_mode=m)
            eb = edge_boxes(x0, x1, edges, pad)
            ee = self.grid_e.query(eb, same=True, vertices=edges, parts=self.epart, parts_mode=m)
        vt = _live_pairs(vt, self.vid, tri, x0, x1, pad, none, no_t, none, no_t, False)
        ee = _live_pairs(ee, edges, edges, x0, x1, pad, no_e, no_e, no_e, no_e, False)
        return vt, ee

    def _extend(self, active, active_t, active_e):
        """Add the grown boxes' pairs of the active elements not paired yet to ``vt0``/``ee0``:
        each pair once, by the first of its two elements to be active (by the vertex where a
        vertex and a triangle become active in one round, by the lower edge of two edges)."""
        m, P = self.mode, self._parts
        nv = np.nonzero(active & ~self.have_v)[0]
        nt = np.nonzero(active_t & ~self.have_t)[0]
        ne = np.nonzero(active_e & ~self.have_e)[0]
        vt, ee = [self.vt0], [self.ee0]
        if len(nv):
            p = self.grid_t.query(self.vb[nv], vertices=self.vid[nv], parts=P(self.vpart, nv), parts_mode=m,
                                  skip=self.have_t)
            p[:, 0] = nv[p[:, 0]]
            vt.append(p)
            self.have_v[nv] = True
        if len(nt):
            if self.grid_v is None:
                self.grid_v = BoxGrid(self.vb, self.cell, self.origin, self.vid, parts=self.vpart)
            # vertices paired already (the ones before and this round's new ones) are skipped
            p = self.grid_v.query(self.tb[nt], vertices=self.tri[nt], parts=P(self.tpart, nt), parts_mode=m,
                                  skip=self.have_v)
            vt.append(np.ascontiguousarray(np.stack([p[:, 1], nt[p[:, 0]].astype(np.int32)], axis=1)))
            self.have_t[nt] = True
        if len(ne):
            new_e = np.zeros(len(self.edges), np.bool_)
            new_e[ne] = True
            p = self.grid_e.query(self.eb[ne], vertices=self.edges[ne], parts=P(self.epart, ne), parts_mode=m,
                                  skip=self.have_e)
            a = ne[p[:, 0]].astype(np.int32)
            b = p[:, 1]
            keep = ~new_e[b] | (a < b)
            ee.append(np.ascontiguousarray(np.stack([np.minimum(a, b)[keep], np.maximum(a, b)[keep]], axis=1)))
            self.have_e[ne] = True
        if len(vt) > 1:
            self.vt0 = np.concatenate(vt)
        if len(ee) > 1:
            self.ee0 = np.concatenate(ee)

    def again(self, x1, active):
        x0, tri, edges, pad = self.x0, self.tri, self.edges, self.pad
        # the active vertices now out of their anchor's slack: flagged in ``left`` (this round) and
        # ``moved`` (once out, counted out of the round-0 grids for the rest of the step),
        # re-anchored where they are
        left = _escape(x1, self.ref, active, self.slack, self.moved)
        moved = self.moved
        flags = np.stack([moved, active, left])
        moved_t, active_t, left_t = _touching(flags, tri)
        moved_e, active_e, left_e = _touching(flags, edges)
        self._extend(active, active_t, active_e)
        vt = [_live_pairs(self.vt0, self.vid, tri, x0, x1, pad, active, active_t, moved, moved_t, True)]
        ee = [_live_pairs(self.ee0, edges, edges, x0, x1, pad, active_e, active_e, moved_e, moved_e, True)]
        if not self.far and left.any() and not self._reanchor(left, left_t, left_e, moved_t, moved_e):
            self.far = True
        if self.far:
            # a response moved something far (boxes of many cells): the cell-based grids would
            # take absurd memory; pair the active elements afresh with box_pairs' own cell guard
            return self._filter(*_candidates(x0, x1, tri, edges, pad, self.cell, active))
        if len(self.mvt):
            vt.append(_live_pairs(self.mvt, self.vid, tri, x0, x1, pad, active, active_t, self.none_v,
                                  self.none_t, True))
        if len(self.mee):
            ee.append(_live_pairs(self.mee, edges, edges, x0, x1, pad, active_e, active_e, self.none_e,
                                  self.none_e, True))
        return (_sorted_pairs(np.concatenate(vt)), _sorted_pairs(np.concatenate(ee)))

    def _reanchor(self, left, left_t, left_e, moved_t, moved_e):
        """Pair the elements of the vertices that ``left`` their anchors this round afresh, by
        their boxes at the new anchors grown by the slack: against round 0's grids (partners that
        never left) and against the grids of the elements that have left (:meth:`_moved_grids`);
        their old pairs in ``mvt``/``mee`` are dropped first, so each pair is listed once. False
        (nothing done) where a box spans more than 64 cells."""
        x0, tri, edges, ref = self.x0, self.tri, self.edges, self.ref
        m, P = self.mode, self._parts
        vpart, tpart, epart = self.vpart, self.tpart, self.epart
        cv, ct, ce = np.nonzero(left)[0], np.nonzero(left_t)[0], np.nonzero(left_e)[0]
        grow = self.pad + self.slack
        vb_c = vertex_boxes(x0[cv], ref[cv], grow)
        tb_c = triangle_boxes(x0, ref, tri[ct], grow)
        eb_c = edge_boxes(x0, ref, edges[ce], grow)
        if max(_box_stats(vb_c, tb_c, eb_c)[2], 0.0) > 64.0 * self.cell:
            return False
        if self.grid_v is None:
            self.grid_v = BoxGrid(self.vb, self.cell, self.origin, self.vid, parts=vpart)
        moved = self.moved
        grids = self._moved_grids(left, left_t, left_e, moved_t, moved_e)
        # the old pairs of what left
        vt = [self.mvt[_pairs_without(self.mvt, left, left_t)]]
        ee = [self.mee[_pairs_without(self.mee, left_e, left_e)]]
        # a vertex that left: with the triangles that never left, and with those that did
        p = self.grid_t.query(vb_c, skip=moved_t, vertices=self.vid[cv], parts=P(vpart, cv), parts_mode=m)
        vt.append(np.stack([cv[p[:, 0]], p[:, 1]], axis=1))
        for (_, _, g_t, i_t, s_t, _, _, _), _ in grids:
            if g_t is not None:
                p = g_t.query(vb_c, skip=s_t, vertices=self.vid[cv], parts=P(vpart, cv), parts_mode=m)
                vt.append(np.stack([cv[p[:, 0]], i_t[p[:, 1]]], axis=1))
        # a triangle that left: with the vertices that never left, and with those that left before
        # (the pairs of a vertex and a triangle that both left this round are the vertex's)
        p = self.grid_v.query(tb_c, skip=moved, vertices=tri[ct], parts=P(tpart, ct), parts_mode=m)
        vt.append(np.stack([p[:, 1], ct[p[:, 0]]], axis=1))
        for (g_v, i_v, _, _, _, _, _, _), s_v in grids:
            if g_v is not None:
                p = g_v.query(tb_c, skip=s_v, vertices=tri[ct], parts=P(tpart, ct), parts_mode=m)
                vt.append(np.stack([i_v[p[:, 1]], ct[p[:, 0]]], axis=1))
        # an edge that left: with the edges that never left, with those that did (two that left
        # this round: once, as (smaller, larger))
        p = self.grid_e.query(eb_c, skip=moved_e, vertices=edges[ce], parts=P(epart, ce), parts_mode=m)
        a, b = ce[p[:, 0]], p[:, 1]
        ee.append(np.stack([np.minimum(a, b), np.maximum(a, b)], axis=1))
        for (_, _, _, _, _, g_e, i_e, s_e), _ in grids:
            if g_e is not None:
                p = g_e.query(eb_c, skip=s_e, vertices=edges[ce], parts=P(epart, ce), parts_mode=m)
                a, b = ce[p[:, 0]], i_e[p[:, 1]]
                k = (a != b) & (~left_e[b] | (a < b))
                ee.append(np.stack([np.minimum(a, b)[k], np.maximum(a, b)[k]], axis=1))
        self.mvt = np.ascontiguousarray(np.concatenate(vt), dtype=np.int32)
        self.mee = np.ascontiguousarray(np.concatenate(ee), dtype=np.int32)
        return True

    def _moved_grids(self, left, left_t, left_e, moved_t, moved_e):
        """The grids over the boxes (at their anchors, grown by the slack) of the elements that
        have left, as ``((grid_v, idx_v, grid_t, idx_t, skip_t, grid_e, idx_e, skip_e), skip_v)``
        entries: a grid over all of them built now and then, whose entries re-anchored since are
        skipped (``stale``), and one over those rebuilt every round. A grid is rebuilt in full when
        the re-anchored elements are more than :data:`REBUILD_FRACTION` of it (the work per round
        stays about that of the elements that leave). ``skip_v`` leaves out the vertices that left
        this round (their pairs with the triangles that left are found from the vertices)."""
        x0, tri, edges, ref = self.x0, self.tri, self.edges, self.ref
        P = self._parts
        grow = self.pad + self.slack
        st_v, st_t, st_e = self.stale
        st_v |= left
        st_t |= left_t
        st_e |= left_e
        n_stale = np.count_nonzero(st_v) + np.count_nonzero(st_t) + np.count_nonzero(st_e)
        n_moved = np.count_nonzero(self.moved) + np.count_nonzero(moved_t) + np.count_nonzero(moved_e)

        def build(fv, ft, fe):
            iv, it, ie = np.nonzero(fv)[0], np.nonzero(ft)[0], np.nonzero(fe)[0]
            g_v = BoxGrid(vertex_boxes(x0[iv], ref[iv], grow), self.cell, self.origin, self.vid[iv],
                          parts=P(self.vpart, iv)) if len(iv) else None
            g_t = BoxGrid(triangle_boxes(x0, ref, tri[it], grow), self.cell, self.origin, tri[it],
                          parts=P(self.tpart, it)) if len(it) else None
            g_e = BoxGrid(edge_boxes(x0, ref, edges[ie], grow), self.cell, self.origin, edges[ie],
                          parts=P(self.epart, ie)) if len(ie) else None
            return g_v, iv, g_t, it, None, g_e, ie, None

        if self.grids_all is None or n_stale > REBUILD_FRACTION * n_moved:
            self.grids_all = build(self.moved, moved_t, moved_e)
            st_v[:] = False
            st_t[:] = False
            st_e[:] = False
            g = self.grids_all
            return [(g, left[g[1]])]
        g_v, iv, g_t, it, _, g_e, ie, _ = self.grids_all
        whole = (g_v, iv, g_t, it, st_t[it], g_e, ie, st_e[ie])
        fresh = build(st_v, st_t, st_e)
        return [(whole, st_v[iv]), (fresh, left[fresh[1]])]



class _SplitBroadPhase:
    """The broad phase of a step in which parts (florets) are carried far by their own motion.

    The motion from ``x0`` to ``x1`` is linear in t, so taking the same vector ``t u`` from two
    elements' positions at every t changes no distance between them at any t: whether they come
    within the tolerance is decided as well in any frame that moves by a common ``t u``. Pairs
    within one part are therefore found in the part's moving frame (``x1 - u_part``, ``u_part``
    the part's mean motion over the step): a floret that a head's growth carries several of its
    triangles' widths in a step no longer pairs every triangle with every other along its path
    (the final yarrow's emergence: 99.7 % of the candidate pairs were of one floret). Pairs of
    two parts are found in the scene's frame. The two sets are disjoint; every pair that either
    broad phase alone would report as touching is reported (the same contacts), in (a, b) order.
    """

    def __init__(self, x0, tri, edges, pad, cell_size, vertex_part, shift):
        self.shift = shift
        self.world = _StepBroadPhase(x0, tri, edges, pad, cell_size, vertex_part, PARTS_CROSS)
        self.local = _StepBroadPhase(x0, tri, edges, pad, cell_size, vertex_part, PARTS_SAME)

    def first(self, x1, pairs=True):
        w = self.world.first(x1, pairs)
        loc = self.local.first(x1 - self.shift, pairs)
        return _joined(w, loc) if pairs else None

    def again(self, x1, active):
        return _joined(self.world.again(x1, active), self.local.again(x1 - self.shift, active))


class _ProbedBroadPhase:
    """Round 0 by :func:`.probe.probe_contacts` (the contacts, without the pair lists); the
    step's own broad phase (``broad``) is started, from round 0's positions, only when a later
    round asks for pairs. The contacts and the later rounds' pairs are those of ``broad`` alone."""

    def __init__(self, broad, x0, tri, edges, pad, tol, vertex_part):
        self.broad = broad
        self.x0, self.tri, self.edges, self.pad, self.tol = x0, tri, edges, pad, tol
        self.vertex_part = vertex_part
        self.x1_round0 = None
        self.started = False

    def round0(self, x1):
        self.x1_round0 = x1.copy()
        shift = self.broad.shift if isinstance(self.broad, _SplitBroadPhase) else None
        vt, ee, stats = probe_contacts(self.x0, x1, self.tri, self.edges, self.pad, self.tol, self.vertex_part,
                                       shift)
        found, _ = _narrow(self.x0, x1, self.tri, self.edges, vt, ee, self.tol)
        return found, stats

    def again(self, x1, active):
        if not self.started:
            self.broad.first(self.x1_round0, pairs=False)
            self.started = True
        return self.broad.again(x1, active)


def _joined(a, b):
    return (_sorted_pairs(np.concatenate([a[0], b[0]])), _sorted_pairs(np.concatenate([a[1], b[1]])))


def step_broad_phase(x0, x1, tri, edges, pad, cell_size, vertex_part=None):
    """The broad phase of one step's rounds: :class:`_SplitBroadPhase` where parts (given by the
    (n,) ``vertex_part``, each owning its triangles and edges) move on average more than
    :data:`SPLIT_MOTION` times their triangles' mean box extent over the step, else
    :class:`_StepBroadPhase`. Both report the same pairs in the same order."""
    def plain():
        return _StepBroadPhase(x0, tri, edges, pad, cell_size)

    if vertex_part is None or len(tri) == 0 or len(x0) == 0:
        return plain()
    vp = np.ascontiguousarray(vertex_part, dtype=np.int64)
    if (vp[tri] != vp[tri[:, :1]]).any() or (len(edges) and (vp[edges] != vp[edges[:, :1]]).any()):
        return plain()  # an element joins two parts: no common frame for it
    n_parts = int(vp.max()) + 1
    d = x1 - x0
    count = np.maximum(np.bincount(vp, minlength=n_parts), 1)
    u = np.stack([np.bincount(vp, weights=d[:, k], minlength=n_parts) for k in range(3)], axis=1)
    u /= count[:, None]
    shift = u[vp]
    motion = float(np.sqrt((shift ** 2).sum(axis=1)).mean())
    extent = _step_box_stats(x0, x0, tri, edges[:0], 0.0)[1]
    if not motion > SPLIT_MOTION * extent:
        return plain()
    return _SplitBroadPhase(x0, tri, edges, pad, cell_size, vp, np.ascontiguousarray(shift))


@njit(cache=True)
def _escape(x1, ref, active, slack, moved):
    """The active vertices of ``x1`` more than ``slack`` from their anchor ``ref`` in a coordinate
    ((n,) bool): flagged in ``moved`` too and re-anchored (``ref`` set to ``x1``)."""
    left = np.zeros(x1.shape[0], np.bool_)
    for i in range(x1.shape[0]):
        if active[i]:
            for d in range(3):
                if not abs(x1[i, d] - ref[i, d]) <= slack:
                    left[i] = True
                    moved[i] = True
                    for e in range(3):
                        ref[i, e] = x1[i, e]
                    break
    return left


@njit(cache=True)
def _pairs_without(pairs, flag_a, flag_b):
    """(k,) bool: rows (a, b) of ``pairs`` with neither ``flag_a[a]`` nor ``flag_b[b]``."""
    out = np.empty(pairs.shape[0], np.bool_)
    for k in range(pairs.shape[0]):
        out[k] = not (flag_a[pairs[k, 0]] or flag_b[pairs[k, 1]])
    return out


@njit(cache=True, inline="always")
def _element_box(verts, k, x0, x1, pad, box):
    for d in range(3):
        box[d] = np.inf
        box[d + 3] = -np.inf
    for j in range(verts.shape[1]):
        v = verts[k, j]
        for d in range(3):
            box[d] = min(box[d], x0[v, d], x1[v, d])
            box[d + 3] = max(box[d + 3], x0[v, d], x1[v, d])
    for d in range(3):
        box[d] -= pad
        box[d + 3] += pad


@njit(cache=True)
def _live_pairs(pairs, verts_a, verts_b, x0, x1, pad, act_a, act_b, left_a, left_b, need_active):
    """The rows (a, b) of ``pairs`` whose elements (rows of ``verts_a`` / ``verts_b``) have
    overlapping boxes from ``x0`` to ``x1`` (grown by ``pad``), neither flagged in ``left_a`` /
    ``left_b`` and, with ``need_active``, one flagged in ``act_a`` / ``act_b`` (the elements with
    an active vertex); in their order."""
    keep = np.zeros(pairs.shape[0], np.bool_)
    ba = np.empty(6)
    bb = np.empty(6)
    for k in range(pairs.shape[0]):
        a = pairs[k, 0]
        b = pairs[k, 1]
        if left_a[a] or left_b[b]:
            continue
        if need_active and not (act_a[a] or act_b[b]):
            continue
        _element_box(verts_a, a, x0, x1, pad, ba)
        _element_box(verts_b, b, x0, x1, pad, bb)
        ok = True
        for d in range(3):
            if ba[d] > bb[d + 3] or bb[d] > ba[d + 3]:
                ok = False
        keep[k] = ok
    out = np.empty((np.count_nonzero(keep), 2), np.int32)
    n = 0
    for k in range(pairs.shape[0]):
        if keep[k]:
            out[n, 0] = pairs[k, 0]
            out[n, 1] = pairs[k, 1]
            n += 1
    return out


def detect_collisions(x0: np.ndarray, x1: np.ndarray, tri_indices: np.ndarray, edge_indices: np.ndarray,
                      *, tolerance: float, cell_size: float | None = None,
                      active: np.ndarray | None = None) -> tuple[Contacts, dict]:
    """Continuous collision detection of a triangle mesh moving from ``x0`` to ``x1`` (4.2).

    Parameters
    ----------
    x0, x1 : (n, 3) float64
        Positions at the start (collision-free) and end of the step.
    tri_indices : (m, 3) int32
    edge_indices : (e, 2) int32
        Unique edges of the mesh (:func:`inflo.tools.pbd.mesh_edges`).
    tolerance : float
        Inside-test tolerance (:func:`default_tolerance`); also pads the broad-phase boxes.
    cell_size : float or None
        Broad-phase cell (None: the mean box size).
    active : (n,) bool or None
        Only pairs with at least one active vertex are tested (None: all). The resolution loop
        re-detects only around the vertices its constraints moved: pairs of unmoved vertices
        cannot have changed.

    Returns
    -------
    contacts : Contacts
        Pairs with an odd number of crossings (need a response), vertex-triangle first, in a
        deterministic order.
    stats : dict
        ``vt_candidates``, ``ee_candidates`` (broad phase), ``vt_hits``, ``ee_hits`` (pairs with
        any crossing), ``vt_even``, ``ee_even`` (pairs crossing an even number of times: ignored).
    """
    x0 = np.ascontiguousarray(x0, dtype=np.float64)
    x1 = np.ascontiguousarray(x1, dtype=np.float64)
    tri = np.ascontiguousarray(tri_indices, dtype=np.int32)
    edges = np.ascontiguousarray(edge_indices, dtype=np.int32)
    pad = 0.5 * tolerance
    vt_pairs, ee_pairs = _candidates(x0, x1, tri, edges, pad, cell_size,
                                     None if active is None else np.asarray(active, dtype=bool))
    return _narrow(x0, x1, tri, edges, vt_pairs, ee_pairs, tolerance)


def _narrow(x0, x1, tri, edges, vt_pairs, ee_pairs, tolerance) -> tuple[Contacts, dict]:
    """Narrow phase over candidate pairs and the contacts of those crossing an odd number of times."""
    vt_hits = np.zeros(len(vt_pairs), np.int32)
    vt_info = np.zeros((len(vt_pairs), 4))
    ee_hits = np.zeros(len(ee_pairs), np.int32)
    ee_info = np.zeros((len(ee_pairs), 4))
    if len(vt_pairs):
        run = _narrow_vt_serial if len(vt_pairs) < SERIAL_NARROW_BELOW else _narrow_vt
        run(x0, x1, tri, vt_pairs, float(tolerance), vt_hits, vt_info)
    if len(ee_pairs):
        run = _narrow_ee_serial if len(ee_pairs) < SERIAL_NARROW_BELOW else _narrow_ee
        run(x0, x1, edges, ee_pairs, float(tolerance), ee_hits, ee_info)
    stats = {
        "vt_candidates": int(len(vt_pairs)),
        "ee_candidates": int(len(ee_pairs)),
        "vt_hits": int(np.count_nonzero(vt_hits)),
        "ee_hits": int(np.count_nonzero(ee_hits)),
        "vt_even": int(np.count_nonzero((vt_hits > 0) & (vt_hits % 2 == 0))),
        "ee_even": int(np.count_nonzero((ee_hits > 0) & (ee_hits % 2 == 0))),
    }
    sv = np.nonzero(vt_hits % 2 == 1)[0]
    se = np.nonzero(ee_hits % 2 == 1)[0]
    k = len(sv) + len(se)
    idx = np.zeros((k, 4), np.int32)
    coef = np.zeros((k, 4))
    toi = np.zeros(k)
    element = np.zeros((k, 2), np.int32)
    kind = np.zeros(k, np.int8)
    if len(sv):
        p = vt_pairs[sv]
        idx[: len(sv), 0] = p[:, 0]
        idx[: len(sv), 1:] = tri[p[:, 1]]
        coef[: len(sv), 0] = 1.0
        coef[: len(sv), 1:] = -vt_info[sv, 1:4]
        toi[: len(sv)] = vt_info[sv, 0]
        element[: len(sv)] = p
    if len(se):
        p = ee_pairs[se]
        o = len(sv)
        idx[o:, :2] = edges[p[:, 0]]
        idx[o:, 2:] = edges[p[:, 1]]
        s = ee_info[se, 1]
        t = ee_info[se, 2]
        coef[o:] = np.stack([1.0 - s, s, -(1.0 - t), -t], axis=1)
        toi[o:] = ee_info[se, 0]
        element[o:] = p
        kind[o:] = KIND_EE
    normal = np.zeros((k, 3))
    ok = np.zeros(k, np.bool_)
    if k:
        _build_contacts(x0, x1, kind, idx, coef, toi, normal, ok)
    reach = np.zeros(k)
    if k:
        motion = np.sqrt(((x1[idx] - x0[idx]) ** 2).sum(axis=2)).max(axis=1)
        reach = 4.0 * motion + 4.0 * float(tolerance)
    contacts = Contacts(kind, idx, coef, normal, toi, element, reach)
    if not ok.all():
        stats["degenerate"] = int(np.count_nonzero(~ok))
    return contacts, stats


# --------------------------------------------------------------------------------------------------
# Algorithm 1, collision part
# --------------------------------------------------------------------------------------------------


@dataclass
class CollisionResult:
    """What :func:`resolve_collisions` did in one step.

    Attributes
    ----------
    rounds : int
        Detection rounds run (1 when the step was free at once).
    found : list of int
        Pairs needing a response found in each round.
    constraints : int
        Collision constraints in the set at the end.
    remaining : Contacts
        Pairs still crossing after ``max_retries`` (reported; their vertices were reverted).
    reverted : int
        Vertices put back to their start-of-step position by the fallback.
    stats : dict
        Broad/narrow phase counts of the first round.
    """

    rounds: int = 0
    found: list = field(default_factory=list)
    constraints: int = 0
    remaining: Contacts = field(default_factory=Contacts.empty)
    reverted: int = 0
    stats: dict = field(default_factory=dict)
    relaxed: int = 0
    """rounds whose collision response was followed by a relaxation of the internal constraints"""
    retreated: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    """parts the ``"parts"`` fallback moved back (:func:`retreat_parts`; fccompose: florets)"""
    whole_step: bool = False
    repairs: int = 0
    """passes that relaxed parts left out of shape and resolved what that moved"""
    misshapen: int = 0
    """parts (``fallback="parts"``) still out of shape at the end: their carried shape crosses
    something, and so does each smaller shape ``parts["shrink"]`` offers, so they keep the
    collision-free shape the solve gave them (reported; fccompose does not redo such a step:
    halving it made squeezed canopies 9 x slower)"""
    shrunk: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """(n_parts,) the scale each part was put at by the ``"parts"`` fallback's last resort for parts
    out of shape (``parts["shrink"]``): 1 where none; empty when the fallback did not run"""


def resolve_collisions(x0: np.ndarray, x1: np.ndarray, vertex_inv_mass: np.ndarray,
                       tri_indices: np.ndarray, edge_indices: np.ndarray, *, thickness: float,
                       stiffness: float = 1.0, iterations: int = 10, max_retries: int = 20,
                       tolerance: float | None = None, cell_size: float | None = None,
                       relax=None, relax_rounds: int | None = None,
                       fallback: str = "vertices", parts=None, vertex_part=None,
                       probe: bool = True) -> CollisionResult:
    """Move ``x1`` (in place) until the step from ``x0`` is collision-free (Alg. 1 lines 10-20).

    Parameters
    ----------
    x0 : (n, 3) float64
        Collision-free positions at the start of the step.
    x1 : (n, 3) float64
        Predicted positions (after the internal constraints); corrected in place.
    vertex_inv_mass : (n,) float64
        Inverse masses (0: fixed; collision constraints do not move those vertices).
    tri_indices : (m, 3) int32
    edge_indices : (e, 2) int32
    thickness : float
        ``h`` (``spacing``): distance the constraints keep (at least twice the tolerance).
    stiffness : float
        ``kCollision``.
    iterations : int
        ``collision iterations``: sweeps over the collision constraints per round.
    max_retries : int
        ``max collision retries``: detect/solve rounds after the first. The rounds stop early
        when the number of crossing pairs has not gone down for ``STALL_ROUNDS`` (4) rounds, or
        at once when a round finds more than the first round and more than ``RUNAWAY_FACTOR`` (8)
        times the fewest so far.
        Rounds that end with more pairs crossing than their best round had end on that round's
        positions (``x1`` as it was detected then; ``remaining`` its pairs): the retries never
        leave the step worse than they found it.
    tolerance : float or None
        Inside-test tolerance; None: :func:`default_tolerance`.
    cell_size : float or None
        Broad-phase cell size.
    relax : callable or None
        ``relax(x1, moved)``: called after the collision constraints of a round were projected,
        with ``moved`` the (n,) bool mask of the vertices they moved; it re-solves the internal constraints of what they moved, in place (the collision and
        internal constraints are then solved together, as in Alg. 1, rather than the collision
        response having the last word on the florets' shape). The next round's detection checks
        what it moved.
    relax_rounds : int or None
        Rounds that call ``relax`` (the first ones); the later rounds are the plain collision
        response, so that the loop converges where the two disagree. None: half the rounds.
    fallback : str
        What to do with pairs still crossing after the last round: ``"vertices"`` puts their
        vertices back to ``x0`` (the module doc); ``"none"`` leaves ``x1`` as the last round left
        it and only reports them in ``remaining`` (the caller resolves them, e.g. by
        :func:`retreat_parts`); ``"parts"``: :func:`retreat_parts` with ``parts``, on this step's
        broad phase (incremental, as the rounds).
    parts : dict or None
        For ``fallback="parts"``: ``vertex_part``, ``n_parts``, ``carried`` (a callable giving the
        carried positions, called only when needed), ``misshapen`` (callable or None: parts out of
        shape are moved back too, also when no pair is left), ``crossing`` (bool: also move back
        the parts of pairs still crossing; False leaves those to the caller, e.g. to substep) and,
        optional, ``shrink`` and ``shrink_scales``: ``shrink(s, which)`` gives smaller shapes of
        the parts of the (n_parts,) bool ``which`` at scale ``s``, a list of ``(target, fits)``:
        (n, 3) positions and the (n_parts,) bool parts for which they are a shape within bounds
        (fccompose: the carried shape scaled about each floret's base, for the florets whose
        carried shape is in shape; the rest shape scaled, for all). They are tried in turn, at
        each ``s`` of ``shrink_scales``, for the parts still out of shape whose carried shape
        crosses something or is out of shape too (:func:`reshape_parts`; ``CollisionResult.shrunk``);
        with ``intersecting`` (the exact static test, as :func:`place_parts` takes it) a smaller
        shape that the step's way to it crosses is taken where the shape itself intersects nothing;
        with also ``blockers(x, which)`` (the parts not in ``which`` whose triangles intersect
        those of ``which``) and ``scaled(x, which, s)`` (the shapes of ``which`` in ``x`` scaled by
        ``s`` about their bases), a part that fits at no scale is tried with the neighbours in
        its way made smaller too (:func:`_shrink_with_blockers`).
    vertex_part : (n,) int or None
        The part of every vertex (default: ``parts["vertex_part"]``): where parts are carried far
        over the step, pairs within a part are found in its moving frame (:func:`step_broad_phase`;
        the same contacts, found faster); where the parts are grouped (:func:`.probe.can_probe`),
        round 0 is detected part by part without a pair list (:func:`.probe.probe_contacts`:
        the same contacts) and the retry rounds' broad phase is built only if a retry comes.
    probe : bool
        Allow that round-0 probe (a caller whose last step found contacts in round 0 expects
        retries, which need the pair lists anyway, and passes False).

    Returns
    -------
    CollisionResult
    """
    if fallback not in ("vertices", "none", "parts"):
        raise ValueError(f"fallback must be 'vertices', 'none' or 'parts', not {fallback!r}")
    if relax_rounds is None:
        relax_rounds = (max_retries + 1) // 2
    tol = default_tolerance(x0, thickness) if tolerance is None else float(tolerance)
    h = max(float(thickness), 2.0 * tol)
    res = CollisionResult()
    w = np.ascontiguousarray(vertex_inv_mass, dtype=np.float64)
    tri = np.ascontiguousarray(tri_indices, dtype=np.int32)
    edges = np.ascontiguousarray(edge_indices, dtype=np.int32)
    x0 = np.ascontiguousarray(x0, dtype=np.float64)
    vp = parts.get("vertex_part") if parts else None
    if vertex_part is None:
        vertex_part = vp
    broad = step_broad_phase(x0, np.ascontiguousarray(x1, dtype=np.float64), tri, edges, 0.5 * tol, cell_size,
                             vertex_part)
    if probe and can_probe(tri, edges, vertex_part):
        broad = _ProbedBroadPhase(broad, x0, tri, edges, 0.5 * tol, tol, vertex_part)
    state = {"constraints": Contacts.empty()}
    # vertices put back to an earlier round's positions (run_rounds' end): active in the next
    # detection, whatever its caller names (the broad phase anchors only what it saw move)
    restored = np.zeros(len(x1), np.bool_)

    def again(xs, active):
        if restored.any():
            active = active | restored
            restored[:] = False
        return broad.again(xs, active)

    def detect(active):
        if active is None and isinstance(broad, _ProbedBroadPhase):
            return broad.round0(x1)
        pairs = broad.first(x1) if active is None else again(x1, active)
        return _narrow(x0, x1, tri, edges, pairs[0], pairs[1], tol)

    def run_rounds(active):
        """Detect/solve rounds from ``active`` (None: everything); returns the pairs still crossing."""
        best, stalled = None, 0
        best_x = best_found = None
        found = Contacts.empty()
        for r in range(max_retries + 1):
            found, stats = detect(active)
            res.rounds += 1
            res.found.append(len(found))
            if active is None and r == 0:
                res.stats = stats
            if len(found) == 0 or r == max_retries:
                break
            if r == 0:
                first = len(found)
            elif len(found) > max(RUNAWAY_FACTOR * best, first):
                break  # the response diverges: more rounds only cost more
            if best is None or len(found) < best:
                best, stalled = len(found), 0
            else:
                stalled += 1
                if stalled >= STALL_ROUNDS:  # the same pairs keep crossing: retrying will not help
                    break
            constraints = state["constraints"] = state["constraints"].concat(found)
            before = x1.copy()
            if len(found) == best:  # (``before``: this round's detected positions)
                best_x, best_found = before, found
            project_collision_constraints(x1, w, constraints.indices, constraints.coef,
                                          constraints.normal, h, float(stiffness),
                                          int(iterations), constraints.reach)
            if relax is not None and r < relax_rounds:
                relax(x1, _changed(x1, before))
                res.relaxed += 1
                # and the collision constraints again, so that the round ends on them
                project_collision_constraints(x1, w, constraints.indices, constraints.coef,
                                              constraints.normal, h, float(stiffness),
                                              int(iterations), constraints.reach)
            moved = _changed(x1, before)
            # still-crossing pairs whose vertices did not move are re-found too
            moved[found.indices.ravel()] = True
            active = moved
        if best is not None and len(found) > best:
            # the rounds end on the positions of their best round (fewest pairs crossing): its
            # pairs are all the pairs crossing there (each round detects the pairs with a vertex
            # moved since the last and those still crossing), the caller's fallback has the fewest
            # florets to move back
            restored[:] |= _changed(x1, best_x)
            x1[:] = best_x
            found = best_found
        return found

    found = run_rounds(None)
    misshapen = parts.get("misshapen") if (fallback == "parts" and parts) else None
    if relax is not None and misshapen is not None:
        # repair: relax the florets the rounds left out of shape harder, and resolve what that moved
        vp = np.asarray(parts["vertex_part"])
        for _ in range(REPAIR_PASSES):
            bad = np.asarray(misshapen(x1), dtype=bool) if not len(found) else None
            if bad is None or not bad.any():
                break
            before = x1.copy()
            for _ in range(REPAIR_RELAXATIONS):
                relax(x1, bad[vp])
            moved = _changed(x1, before)
            if not moved.any():
                break
            res.repairs += 1
            found = run_rounds(moved)
    constraints = state["constraints"]
    res.constraints = len(constraints)
    res.remaining = found
    if fallback == "parts":
        _retreat_fallback(res, x0, x1, tri, edges, tol, parts,
                          lambda xs, act: _narrow(x0, xs, tri, edges, *again(xs, act), tol)[0])
        return res
    if fallback == "none" or len(found) == 0:
        return res
    # fallback: put the vertices of the pairs still crossing back to their start positions
    reverted = np.zeros(len(x1), np.bool_)
    for _ in range(10):
        verts = np.unique(found.indices)
        reverted[verts] = True
        x1[verts] = x0[verts]
        active = np.zeros(len(x1), np.bool_)
        active[verts] = True
        found, _ = detect(active)
        if len(found) == 0:
            break
    else:
        x1[:] = x0
        reverted[:] = True
    res.reverted = int(np.count_nonzero(reverted))
    return res


# --------------------------------------------------------------------------------------------------
# The fallback that keeps parts whole
# --------------------------------------------------------------------------------------------------


@dataclass
class RetreatResult:
    """What :func:`retreat_parts` did.

    Attributes
    ----------
    fraction : (n_parts,) float64
        How far along its own motion each part ended (1: where the solve put it; 0: at ``x0``).
    vertices : int
        Vertices of the parts that were moved back.
    rounds : int
        Detection rounds run.
    whole_step : bool
        Every vertex was put back to ``x0`` (the parts kept crossing).
    """

    fraction: np.ndarray
    vertices: int = 0
    rounds: int = 0
    whole_step: bool = False


def _retreat_fallback(res, x0, x1, tri, edges, tol, parts, detect) -> None:
    """``fallback="parts"``: the florets of pairs still crossing are moved back along their own
    motion (:func:`retreat_parts`, down to ``x0`` if need be: the step must end collision-free);
    then the florets out of shape (those moved back included) are put on their carried
    start-of-step shape where that crosses nothing and is in shape (:func:`reshape_parts`); else,
    with ``parts["shrink"]``, on a smaller shape that fits (module doc of fccompose: ``crowded
    scales``; the neighbours in the way made smaller too where nothing else fits,
    :func:`_shrink_with_blockers`); elsewhere they keep the collision-free shape the solve gave
    them (a floret frozen at ``x0`` while its rest values grow would tear later)."""
    vp = np.asarray(parts["vertex_part"])
    n_parts = int(parts["n_parts"])
    misshapen = parts.get("misshapen")
    carried = None
    retreated = np.zeros(n_parts, bool)
    if len(res.remaining):
        if not parts.get("crossing", True):
            return  # the caller redoes the step
        start = np.zeros(n_parts, bool)
        start[np.unique(vp[res.remaining.indices.ravel()])] = True
        carried = parts["carried"]()
        ret = retreat_parts(x0, x1, tri, edges, vp, n_parts, start, tolerance=tol, carried=carried,
                            detect=detect)
        retreated |= ret.fraction < 1.0
        res.reverted += ret.vertices
        res.whole_step = ret.whole_step
        if ret.whole_step:
            res.retreated = np.arange(n_parts)
            return
    res.shrunk = np.ones(n_parts)
    if misshapen is not None:
        bad = np.asarray(misshapen(x1), dtype=bool)
        if bad.any():
            if carried is None:
                carried = parts["carried"]()
            moved, _ = reshape_parts(x0, x1, carried, vp, bad, detect)
            retreated |= moved
            res.reverted += int(np.count_nonzero(moved[vp]))
            still = bad & ~moved
            shrink = parts.get("shrink")
            intersecting = parts.get("intersecting")
            if shrink is not None:
                # a carried shape out of shape itself (the floret started the step so) is no cure
                still |= moved & np.asarray(misshapen(x1), dtype=bool)
                # no room for a shape of its own size: a smaller one (the caller grows it back)
                for s in parts.get("shrink_scales", ()):
                    if not still.any():
                        break
                    for target, fits in shrink(float(s), still.copy()):
                        tried = still & np.asarray(fits, dtype=bool)
                        if not tried.any():
                            continue
                        put, _ = reshape_parts(x0, x1, target, vp, tried, detect)
                        if intersecting is not None and (tried & ~put).any():
                            # the way there crosses something, the smaller shape itself nothing:
                            # a floret with no room changes size in the step, as one emerging
                            put |= place_parts(x1, target, vp, tried & ~put, intersecting)
                        res.shrunk[put] = float(s)
                        retreated |= put
                        res.reverted += int(np.count_nonzero(put[vp]))
                        still &= ~put
                        if not still.any():
                            break
                blockers = parts.get("blockers")
                scales = list(parts.get("shrink_scales", ()))
                if still.any() and blockers is not None and intersecting is not None and scales:
                    _shrink_with_blockers(res, x1, vp, still, retreated, shrink, parts["scaled"], blockers,
                                          intersecting, scales, misshapen)
            res.misshapen = int(np.count_nonzero(still))
    res.retreated = np.nonzero(retreated)[0]


def _shrink_with_blockers(res, x1, vp, still, retreated, shrink, scaled, blockers, intersecting, scales,
                          misshapen):
    """The last resort for parts out of shape that fit at none of the ``scales`` because
    neighbours in shape take their room: each such part, at its rest shape at the smallest scale,
    is tried together with those neighbours (``blockers``) made smaller too (their present shape
    scaled about their base by each of ``scales`` in turn, ``scaled``), as crowded florets make
    room for each other; the first scale at which the whole group fits (exact static test) is
    taken. ``still``, ``retreated`` and ``res`` are updated in place."""
    smin = float(scales[-1])
    in_shape = ~np.asarray(misshapen(x1), dtype=bool)
    for f in np.nonzero(still)[0].tolist():
        one = np.zeros_like(still)
        one[f] = True
        small = shrink(smin, one)[-1][0]  # the rest shape, smallest
        trial = x1.copy()
        sel = one[vp]
        trial[sel] = small[sel]
        b = np.asarray(blockers(trial, one), dtype=bool) & ~one & ~still & in_shape & (res.shrunk >= 1.0)
        if not b.any():
            continue
        group = one | b
        keep = x1.copy()
        for s in scales:
            target = trial.copy()
            bs = b[vp]
            target[bs] = scaled(x1, b, float(s))[bs]
            put = place_parts(x1, target, vp, group, intersecting)
            if (put == group).all():
                res.shrunk[f] = smin
                res.shrunk[b] = float(s)
                retreated |= group
                res.reverted += int(np.count_nonzero(group[vp]))
                still[f] = False
                break
            g = group[vp]
            x1[g] = keep[g]


def place_parts(x1, target, vertex_part, parts, intersecting, max_rounds: int = 8):
    """Put the (n_parts,) bool ``parts`` on ``target`` where the result intersects nothing (the
    exact static test ``intersecting(x1, which) -> (n_parts,) bool``: the parts of ``which`` with
    a triangle intersecting any triangle); those that would intersect stay where they were (``x1``
    on entry intersects nothing, so this ends). Unlike :func:`reshape_parts` the way from ``x0``
    is not tested: the part changes shape within the step as an emerging floret appears. Returns
    the (n_parts,) bool parts now on ``target``."""
    vp = np.asarray(vertex_part)
    keep = x1.copy()
    on = np.asarray(parts, dtype=bool).copy()
    sel = on[vp]
    x1[sel] = target[sel]
    for _ in range(max_rounds):
        if not on.any():
            return on
        bad = np.asarray(intersecting(x1, on.copy()), dtype=bool) & on
        if not bad.any():
            return on
        on &= ~bad
        back = bad[vp]
        x1[back] = keep[back]
    sel = on[vp]
    x1[sel] = keep[sel]
    on[:] = False
    return on


def reshape_parts(x0, x1, carried, vertex_part, parts, detect, max_rounds: int = 8):
    """Put the (n_parts,) bool ``parts`` (out of shape) on their ``carried`` positions (their
    start-of-step shape carried by their own rigid motion) where that crosses nothing; those of a
    pair still crossing go back to where they were (``x1`` on entry is collision-free, so this
    ends). Returns ((n_parts,) bool: the parts now on ``carried``, detection rounds)."""
    vp = np.asarray(vertex_part)
    keep = x1.copy()
    on = np.asarray(parts, dtype=bool).copy()
    changed = on[vp]
    x1[changed] = carried[changed]
    rounds = 0
    while changed.any() and rounds < max_rounds:
        found = detect(x1, changed)
        rounds += 1
        if not len(found):
            return on, rounds
        back = np.zeros_like(on)
        back[np.unique(vp[found.indices.ravel()])] = True
        back &= on
        if not back.any():  # crossing parts all unchanged: cannot be (x1 was free); give up safely
            break
        on &= ~back
        changed = back[vp]
        x1[changed] = keep[changed]
    if changed.any():  # rounds spent: every part back where it was
        x1[on[vp]] = keep[on[vp]]
        on[:] = False
    return on, rounds


def retreat_parts(x0: np.ndarray, x1: np.ndarray, tri_indices: np.ndarray, edge_indices: np.ndarray,
                  vertex_part: np.ndarray, n_parts: int, start: np.ndarray, *, tolerance: float,
                  cell_size: float | None = None, misshapen=None, carried: np.ndarray | None = None,
                  max_rounds: int = 16, detect=None) -> RetreatResult:
    """Move whole parts back along their own motion until the step from ``x0`` is collision-free.

    The fallback of the collision response that keeps every part (floret) whole: instead of putting
    single vertices back to the start of the step, which strands them away from the rest of their
    floret (and, for a floret the RBA motion carries, tears it), each part of ``start`` ((n_parts,)
    bool) is moved back towards ``carried`` (its start-of-step shape carried by its own rigid motion
    over the step: ``x0`` when not given) as ``carried + s (x1 - carried)``, ``s`` halved every
    round (1/2, 1/4, 1/8, then 0), and as a last resort to ``x0`` itself, which is collision-free.
    The parts of any pair still crossing after a round are taken back further in the next. Every
    position tried is a blend of two whole shapes of the part, so the part stays whole; and a part
    that keeps up with its rigid motion (``carried``) keeps its base where its placement puts it
    (a part left at ``x0`` lags one step behind it).

    Parameters
    ----------
    x0, x1 : (n, 3) float64
        Collision-free start of the step, and the positions the solve reached (moved in place).
    tri_indices, edge_indices : the mesh (as :func:`resolve_collisions`).
    vertex_part : (n,) int32
        Part of every vertex.
    n_parts : int
    start : (n_parts,) bool
        Parts to move back first (those of the pairs still crossing; parts out of shape).
    tolerance, cell_size : as :func:`detect_collisions`.
    misshapen : callable or None
        ``misshapen(x1) -> (n_parts,) bool``: parts out of shape; those among the moved-back ones
        go straight to ``carried``.
    carried : (n, 3) float64 or None
        ``x0`` carried rigidly by each part's motion over the step (None: ``x0``).
    max_rounds : int
        Rounds before the whole step is put back (``x1[:] = x0``).
    detect : callable or None
        ``detect(x1, active) -> Contacts`` of the pairs with an active vertex crossing in the step
        from ``x0`` to ``x1`` (e.g. the step's incremental broad phase); None:
        :func:`detect_collisions`.

    Returns
    -------
    RetreatResult
        ``fraction``: 1 where the solve put the part, in (0, 1) a blend, 0 at ``carried``, -1 at
        ``x0``.
    """
    x0 = np.ascontiguousarray(x0, dtype=np.float64)
    base = x0 if carried is None else np.ascontiguousarray(carried, dtype=np.float64)
    last = 0.0 if carried is None else -1.0  # the fraction of the last resort (x0)
    vp = np.asarray(vertex_part)
    target = x1.copy()
    frac = np.ones(n_parts)
    todo = np.asarray(start, dtype=bool).copy()
    out = RetreatResult(frac)
    straight = np.zeros(n_parts, bool)
    if misshapen is not None:
        straight = np.asarray(misshapen(x1), dtype=bool) & todo
    for _ in range(max_rounds):
        if not todo.any():
            break
        f = frac[todo]
        nxt = np.where(f <= 0.125 + 1e-12, 0.0, 0.5 * f)
        nxt = np.where(straight[todo] & (f > 0.0), 0.0, nxt)
        nxt = np.where(f <= 0.0, last, nxt)
        frac[todo] = nxt
        changed = todo[vp]
        s = frac[vp[changed]][:, None]
        at_x0 = s[:, 0] < 0.0
        blend = base[changed] + np.maximum(s, 0.0) * (target[changed] - base[changed])
        blend[at_x0] = x0[changed][at_x0]
        x1[changed] = blend
        if detect is None:
            found, _ = detect_collisions(x0, x1, tri_indices, edge_indices, tolerance=tolerance,
                                         cell_size=cell_size, active=changed)
        else:
            found = detect(x1, changed)
        out.rounds += 1
        todo = np.zeros(n_parts, bool)
        if len(found):
            todo[np.unique(vp[found.indices.ravel()])] = True
        straight[:] = False
        if misshapen is not None:
            bad = np.asarray(misshapen(x1), dtype=bool) & (frac < 1.0) & (frac > 0.0)
            straight |= bad
            todo |= bad
        if todo.any() and (frac[todo] <= last).all():
            # every part named is at x0 already and still crossing (rounding at contact): only
            # putting back the whole step is certain (x0 is collision-free)
            break
    if todo.any():  # rounds exhausted, or nothing left to give way
        x1[:] = x0
        frac[:] = last
        out.whole_step = True
    out.vertices = int(np.count_nonzero(frac[vp] < 1.0))
    return out
