"""Collision detection: one sweep (:func:`detect_collisions`) and the broad phase of a step's rounds
(thesis 4.2.1, Alg. 1 lines 10-20).

:func:`detect_collisions` runs the broad phase (:mod:`.broad`) and the narrow phase
(:func:`.contacts._narrow`) once over a mesh moving linearly from ``x0`` to ``x1``.

Every round of :func:`.resolve.resolve_collisions` asks which vertex-triangle and edge-edge pairs
may cross between ``x0`` and the round's ``x1``. Round 0 builds box grids over the whole mesh
(:mod:`.broad`) with its boxes grown by ``BROAD_SLACK``; the retries only pair again the elements
that left their round-0 boxes (:class:`_StepBroadPhase`). Parts moving far over a step (florets
carried by a growing head) have their pairs found in their own moving frame
(:class:`_SplitBroadPhase`), and where the probe (:mod:`.probe`) has already found round 0's
contacts the grids wait for the first retry (:class:`_ProbedBroadPhase`).
:func:`step_broad_phase` picks among them.
"""
from __future__ import annotations

import numpy as np
from numba import njit

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
from .contacts import Contacts, _narrow
from .probe import probe_contacts

#: slack of the round-0 broad-phase boxes, in mean triangle box extents (:class:`_StepBroadPhase`;
#: about what a collision round moves a vertex: more slack keeps more vertices inside their round-0
#: boxes but pairs more boxes; flat, densely packed florets (the yarrow's) pair many more; the 100k
#: benchmark canopy's collision time, --scheme fast, one session: 0.02 24.6 s, 0.05 22.2 s, 0.15
#: about 26 s, 0.3 41.1 s. A vertex that left once re-anchored with 3 x the slack, so that it
#: leaves less often: 27.3 s against 24.3 s, not kept)
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
    an active vertex); in their order.

    (An index of the pairs by element, so that a retry round tests only the pairs of its active
    elements, was measured on the final yarrow and not kept: the rounds after a relaxation, which
    moves whole florets, have 60-100 % of the pairs active, and there the box tests, not the scan of
    the flags, are the cost: 2.1 M edge-edge pairs, 81 ms either way with every pair active, 6 ms
    against 10 ms with 0.2 % active; the phase as a whole 5.1 s against 5.3 s over two frames.)"""
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
