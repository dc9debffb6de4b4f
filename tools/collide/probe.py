"""Round 0 of a step without a pair list: does anything touch at all?

Most steps of a growing head before its florets meet (and many of a crowded canopy's emergence)
find no contact in their first detection round. The step's broad phase
(:func:`.detect.step_broad_phase`) nonetheless builds its grids, pairs every element's box grown
by the retry rounds' slack and keeps the pairs for the rounds that never come; in the dense
growing head, where a folded bud's triangles overlap a dozen of their own neighbours each, that was
two thirds of the step.

:func:`probe_contacts` answers round 0's question directly. The mesh is taken floret by floret
(the parts, grouped: :func:`.broad.parts_grouped`): the pairs of one floret are found by sweep and
prune in the floret's own box, the pairs of two florets only where their boxes overlap (the
elements of each that reach into the other's box), and each overlapping pair is tested at once by the
same continuous tests as the narrow phase (:func:`.ccd.vertex_triangle_ccd`,
:func:`.ccd.edge_edge_ccd`), without writing the pair. The candidate pairs are exactly round 0's
(the same boxes, the same filters: a shared vertex, within / across parts, the floret's moving
frame of :class:`.detect._SplitBroadPhase`), so where the probe finds no contact round 0 finds
none, and its counts are round 0's log figures; the pairs it finds crossing are round 0's contacts
(in their order). The retry rounds' broad phase is then started from round 0's positions only if a
retry comes (:class:`.detect._ProbedBroadPhase`).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, prange

from .broad import (
    PART_SWEEP_MAX_ELEMENTS,
    PARTS_ANY,
    PARTS_CROSS,
    _overlapping_parts,
    _part_boxes,
    _part_starts,
    _share_vertex,
    _sorted_pairs,
    edge_boxes,
    parts_grouped,
    triangle_boxes,
    vertex_boxes,
)
from .ccd import edge_edge_ccd, edge_edge_culled, vertex_triangle_ccd, vertex_triangle_culled
from .tripair import _decide, _pair_flag
from .tripair import _share_vertex as _tri_share_vertex

__all__ = ["probe_contacts", "can_probe", "intersecting_pairs_by_part"]

#: per-part counters of :func:`_probe_kernel` (the last three: where the part writes its crossing
#: pairs, and how many it may write there)
_VT_CAND, _EE_CAND, _VT_HIT, _EE_HIT, _VT_EVEN, _EE_EVEN, _VT_ODD, _EE_ODD, _VT_AT, _EE_AT, _CAP = range(11)
_N_COUNTERS = 11
#: crossing pairs of each kind a part may write in the first pass (a part with more is run again)
_PART_CAP = 16


# what the kernels share (NamedTuples of arrays, as tools/branch_gen's kernels take them: numba
# passes each as one argument, its fields typed separately)


class _Mesh(NamedTuple):
    """The step's mesh, as the continuous tests read it."""

    x0: np.ndarray  # (n, 3) float64: positions at the start of the step
    x1: np.ndarray  # (n, 3) float64: at its end
    tri: np.ndarray  # (m, 3) int32
    edges: np.ndarray  # (e, 2) int32
    tol: float  # the continuous tests' tolerance


class _Elements(NamedTuple):
    """One kind of element (vertices, triangles or edges), grouped by part, with their boxes in one
    frame (a part's own moving frame, or the scene's)."""

    boxes: np.ndarray  # (k, 6) float64: every element's box
    parts: np.ndarray  # (n_parts, 6) float64: every part's box (the box of its elements')
    starts: np.ndarray  # (n_parts + 1,) int64: the first element of every part


class _Neighbours(NamedTuple):
    """The parts each part's pairs across parts are sought with (:func:`.broad._overlapping_parts`:
    part p's are ``nbr[start[p]:start[p + 1]]``)."""

    vt_start: np.ndarray  # its vertices against their triangles
    vt_nbr: np.ndarray
    ee_start: np.ndarray  # its edges against their edges
    ee_nbr: np.ndarray


def can_probe(tri: np.ndarray, edges: np.ndarray, vertex_part) -> bool:
    """Whether :func:`probe_contacts` applies: every element within one part, the vertices,
    triangles and edges grouped by part, no part over :data:`.broad.PART_SWEEP_MAX_ELEMENTS`."""
    if vertex_part is None or len(tri) == 0:
        return False
    vp = np.asarray(vertex_part)
    if not parts_grouped(vp):
        return False
    tp = vp[tri]
    if (tp != tp[:, :1]).any() or not parts_grouped(tp[:, 0]):
        return False
    ep = vp[edges] if len(edges) else None
    if ep is not None and ((ep != ep[:, :1]).any() or not parts_grouped(ep[:, 0])):
        return False
    most = max(int(np.bincount(tp[:, 0]).max()), int(np.bincount(vp).max()),
               int(np.bincount(ep[:, 0]).max()) if len(edges) else 0)
    return most <= PART_SWEEP_MAX_ELEMENTS


def probe_contacts(x0: np.ndarray, x1: np.ndarray, tri: np.ndarray, edges: np.ndarray, pad: float,
                   tolerance: float, vertex_part: np.ndarray,
                   shift: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, dict]:
    """Round 0's contacts of a step: its crossing pairs and its candidate and hit counts.

    Parameters
    ----------
    x0, x1 : (n, 3) float64
        Positions at the start and the end of the step.
    tri, edges : (m, 3), (e, 2) int32
    pad : float
        Box pad (the step broad phase's: half the tolerance).
    tolerance : float
        The continuous tests' tolerance.
    vertex_part : (n,) int
        Part (floret) of every vertex; :func:`can_probe` must hold.
    shift : (n, 3) float64 or None
        Each vertex's part's mean motion where pairs within a part are found in its moving frame
        (:class:`.detect._SplitBroadPhase`), else None.

    Returns
    -------
    (vt, ee, stats)
        ``vt``, ``ee``: (k, 2) int32 vertex-triangle and edge-edge pairs crossing an odd number of
        times (round 0's contacts), sorted; ``stats``: the counts of :func:`.contacts._narrow`
        (candidates, hits, even hits).
    """
    x0 = np.ascontiguousarray(x0, dtype=np.float64)
    x1 = np.ascontiguousarray(x1, dtype=np.float64)
    tri = np.ascontiguousarray(tri, dtype=np.int32)
    edges = np.ascontiguousarray(edges, dtype=np.int32).reshape(-1, 2)
    vp = np.ascontiguousarray(vertex_part, dtype=np.int64)
    n_parts = int(vp.max()) + 1
    tp = np.ascontiguousarray(vp[tri[:, 0]])
    ep = np.ascontiguousarray(vp[edges[:, 0]]) if len(edges) else np.zeros(0, np.int64)
    vb = vertex_boxes(x0, x1, pad)
    tb = triangle_boxes(x0, x1, tri, pad)
    eb = edge_boxes(x0, x1, edges, pad)
    if shift is None:
        vb_l, tb_l, eb_l = vb, tb, eb
    else:
        xl = np.ascontiguousarray(x1 - shift)
        vb_l = vertex_boxes(x0, xl, pad)
        tb_l = triangle_boxes(x0, xl, tri, pad)
        eb_l = edge_boxes(x0, xl, edges, pad)
    sv = _part_starts(vp, n_parts)
    st = _part_starts(tp, n_parts)
    se = _part_starts(ep, n_parts)
    # within a part (its moving frame's boxes) and across parts (the scene's)
    pv_l, pt_l, pe_l = _part_boxes(vb_l, sv), _part_boxes(tb_l, st), _part_boxes(eb_l, se)
    pv, pt, pe = _part_boxes(vb, sv), _part_boxes(tb, st), _part_boxes(eb, se)
    vt_start, vt_nbr = _overlapping_parts(pv, pt, False, PARTS_CROSS)
    ee_start, ee_nbr = _overlapping_parts(pe, pe, True, PARTS_CROSS)
    args = (_Mesh(x0, x1, tri, edges, float(tolerance)),
            _Elements(vb_l, pv_l, sv), _Elements(tb_l, pt_l, st), _Elements(eb_l, pe_l, se),
            _Elements(vb, pv, sv), _Elements(tb, pt, st), _Elements(eb, pe, se),
            _Neighbours(vt_start, vt_nbr, ee_start, ee_nbr))
    # each part writes up to _PART_CAP crossing pairs of a kind into its own slots
    start = np.zeros((n_parts, _N_COUNTERS), np.int64)
    start[:, _VT_AT] = start[:, _EE_AT] = np.arange(n_parts) * _PART_CAP
    start[:, _CAP] = _PART_CAP
    slots_vt = np.zeros((n_parts * _PART_CAP, 2), np.int32)
    slots_ee = np.zeros((n_parts * _PART_CAP, 2), np.int32)
    counts = _probe_kernel(*args, np.ones(n_parts, np.bool_), slots_vt, slots_ee, start)
    total = counts.sum(axis=0)
    n_vt = np.minimum(counts[:, _VT_ODD], _PART_CAP)
    n_ee = np.minimum(counts[:, _EE_ODD], _PART_CAP)
    keep = np.arange(_PART_CAP)[None, :]
    vt = slots_vt.reshape(n_parts, _PART_CAP, 2)[keep < n_vt[:, None]]
    ee = slots_ee.reshape(n_parts, _PART_CAP, 2)[keep < n_ee[:, None]]
    over = (counts[:, _VT_ODD] > _PART_CAP) | (counts[:, _EE_ODD] > _PART_CAP)
    if over.any():  # those parts again, with room for all theirs
        n_over = int(over.sum())
        big = int(max(counts[over, _VT_ODD].max(), counts[over, _EE_ODD].max()))
        again = np.zeros((n_parts, _N_COUNTERS), np.int64)
        again[over, _VT_AT] = again[over, _EE_AT] = np.arange(n_over) * big
        again[:, _CAP] = big
        more_vt = np.zeros((n_over * big, 2), np.int32)
        more_ee = np.zeros((n_over * big, 2), np.int32)
        redo = _probe_kernel(*args, over, more_vt, more_ee, again)[over]
        keep = np.arange(big)[None, :]
        vt = np.concatenate([vt[~np.repeat(over, n_vt)],
                             more_vt.reshape(n_over, big, 2)[keep < redo[:, _VT_ODD][:, None]]])
        ee = np.concatenate([ee[~np.repeat(over, n_ee)],
                             more_ee.reshape(n_over, big, 2)[keep < redo[:, _EE_ODD][:, None]]])
    vt = _sorted_pairs(vt)
    ee = _sorted_pairs(ee)
    stats = {
        "vt_candidates": int(total[_VT_CAND]),
        "ee_candidates": int(total[_EE_CAND]),
        "vt_hits": int(total[_VT_HIT]),
        "ee_hits": int(total[_EE_HIT]),
        "vt_even": int(total[_VT_EVEN]),
        "ee_even": int(total[_EE_EVEN]),
    }
    return vt, ee, stats


@njit(cache=True, inline="always")
def _tally(h, a, b, c, out, hit, even, odd, at):
    """Count the test's result ``h`` (crossings) of pair (a, b) into the counters ``c`` (columns
    ``hit``, ``even``, ``odd``); a pair crossing an odd number of times is written to ``out`` at
    the part's cursor (column ``at``) while the part has written fewer than its cap."""
    if h > 0:
        c[hit] += 1
        if h % 2 == 0:
            c[even] += 1
        else:
            c[odd] += 1
            if c[odd] <= c[_CAP]:
                out[c[at], 0] = a
                out[c[at], 1] = b
                c[at] += 1


@njit(cache=True, inline="always")
def _test(kind, a, b, x0, x1, tri, edges, tol, out, c, out_vt, out_ee):
    """The continuous test of pair (a, b): kind 0 vertex a / triangle b, 1 edges a and b
    (:func:`_tally`)."""
    if kind == 0:
        p = tri[b, 0]
        q = tri[b, 1]
        r = tri[b, 2]
        c[_VT_CAND] += 1
        if vertex_triangle_culled(x0, x1, a, p, q, r):
            return
        h = vertex_triangle_ccd(x0[a], x0[p], x0[q], x0[r], x1[a], x1[p], x1[q], x1[r], tol, out)
        _tally(h, a, b, c, out_vt, _VT_HIT, _VT_EVEN, _VT_ODD, _VT_AT)
    else:
        c[_EE_CAND] += 1
        if edge_edge_culled(x0, x1, edges[a, 0], edges[a, 1], edges[b, 0], edges[b, 1]):
            return
        h = edge_edge_ccd(x0[edges[a, 0]], x0[edges[a, 1]], x0[edges[b, 0]], x0[edges[b, 1]],
                          x1[edges[a, 0]], x1[edges[a, 1]], x1[edges[b, 0]], x1[edges[b, 1]], tol, out)
        _tally(h, a, b, c, out_ee, _EE_HIT, _EE_EVEN, _EE_ODD, _EE_AT)


@njit(cache=True, inline="always")
def _ok(kind, a, b, ca, i, cb, j, same, tri, edges):
    """Whether elements a (box ``ca[i]``) and b (box ``cb[j]``) are a candidate pair."""
    if same and b <= a:
        return False
    if not _overlap_flat(ca, i, cb, j):
        return False
    if kind == 0:
        return not (tri[b, 0] == a or tri[b, 1] == a or tri[b, 2] == a)
    return not _share_vertex(edges, a, edges, b)


@njit(cache=True)
def _sweep_test(kind, ca, cb, la, lb, na, nb, d, same, x0, x1, tri, edges, tol, out, c, out_vt, out_ee):
    """Sweep and prune of the elements ``la[:na]`` against ``lb[:nb]`` (each sorted by their
    boxes' minimum on axis ``d``; their boxes, in that order, ``ca``, ``cb``: the sweep reads
    contiguous memory), testing every pair whose boxes overlap once (with ``same``, the two lists
    are one set: each pair comes in both orders, kept as ``a < b``)."""
    ia = 0
    ib = 0
    while ia < na and ib < nb:
        if ca[ia, d] <= cb[ib, d]:
            a = la[ia]
            top = ca[ia, d + 3]
            k = ib
            while k < nb and cb[k, d] <= top:
                if _ok(kind, a, lb[k], ca, ia, cb, k, same, tri, edges):
                    _test(kind, a, lb[k], x0, x1, tri, edges, tol, out, c, out_vt, out_ee)
                k += 1
            ia += 1
        else:
            b = lb[ib]
            top = cb[ib, d + 3]
            k = ia
            while k < na and ca[k, d] <= top:
                if _ok(kind, la[k], b, ca, k, cb, ib, same, tri, edges):
                    _test(kind, la[k], b, x0, x1, tri, edges, tol, out, c, out_vt, out_ee)
                k += 1
            ib += 1


@njit(cache=True, inline="always")
def _overlap_flat(a, i, b, j):
    """:func:`.broad._overlap` without branches (one test of six comparisons: in a sweep the
    outcome of each comparison is unpredictable)."""
    return ((a[i, 0] <= b[j, 3]) & (b[j, 0] <= a[i, 3]) & (a[i, 1] <= b[j, 4]) & (b[j, 1] <= a[i, 4])
            & (a[i, 2] <= b[j, 5]) & (b[j, 2] <= a[i, 5]))


@njit(cache=True)
def _sweep_self(ca, la, na, d, x0, x1, tri, edges, tol, out, c, out_vt, out_ee):
    """Sweep and prune of the edges ``la[:na]`` (sorted by their boxes' minimum on axis ``d``, their
    boxes in that order ``ca``) among themselves: every pair whose boxes overlap tested once, as
    (smaller, larger) -- the pairs :func:`_sweep_test` of the list against itself tests, each
    visited once rather than in both orders (half the visits, and no test of the order, which a
    CPU cannot predict: the 350k benchmark canopy's florets' own edges, 33 M visits -> 16 M)."""
    for i in range(na - 1):
        top = ca[i, d + 3]
        a = la[i]
        k = i + 1
        while k < na and ca[k, d] <= top:
            if _overlap_flat(ca, i, ca, k):
                b = la[k]
                lo = min(a, b)
                hi = max(a, b)
                if not _share_vertex(edges, lo, edges, hi):
                    _test(1, lo, hi, x0, x1, tri, edges, tol, out, c, out_vt, out_ee)
            k += 1


@njit(cache=True)
def _region_sorted(boxes, lo, hi, d, r, lst, cb, key, tmp):
    """The elements ``lo:hi`` whose boxes overlap box ``r``, sorted by their boxes' minimum on
    axis ``d`` (stable: ties in element order), into ``lst``, and their boxes in that order into
    ``cb``; returns their number. (``key``, ``tmp``: scratch of the same length as ``lst``.)"""
    n = 0
    for e in range(lo, hi):
        if (boxes[e, 0] <= r[3] and boxes[e, 3] >= r[0] and boxes[e, 1] <= r[4] and boxes[e, 4] >= r[1]
                and boxes[e, 2] <= r[5] and boxes[e, 5] >= r[2]):
            tmp[n] = e
            key[n] = boxes[e, d]
            n += 1
    order = np.argsort(key[:n], kind="mergesort")
    for k in range(n):
        e = tmp[order[k]]
        lst[k] = e
        for j in range(6):
            cb[k, j] = boxes[e, j]
    return n


@njit(cache=True, inline="always")
def _region(pa, p, pb, q, r):
    """The intersection of part p's box (``pa``) and part q's (``pb``) into ``r``; returns the axis of
    its longest side (the sweep's), or -1 where the boxes do not overlap."""
    for d in range(3):
        r[d] = max(pa[p, d], pb[q, d])
        r[d + 3] = min(pa[p, d + 3], pb[q, d + 3])
    if r[0] > r[3] or r[1] > r[4] or r[2] > r[5]:
        return -1
    d = 0
    if r[4] - r[1] > r[3] - r[0]:
        d = 1
    if r[5] - r[2] > max(r[3] - r[0], r[4] - r[1]):
        d = 2
    return d


@njit(cache=True)
def _pair_parts(kind, p, q, a, b, same, mesh, la, lb, ca, cb, key, tmp, r, out, c, out_vt, out_ee):
    """Test the elements of part p (:class:`_Elements` ``a``) against those of part q (``b``) that
    reach into the intersection of the two parts' boxes."""
    d = _region(a.parts, p, b.parts, q, r)
    if d < 0:
        return
    x0, x1, tri, edges, tol = mesh.x0, mesh.x1, mesh.tri, mesh.edges, mesh.tol
    na = _region_sorted(a.boxes, a.starts[p], a.starts[p + 1], d, r, la, ca, key, tmp)
    if same and p == q:  # one list against itself (a part's own edges)
        _sweep_self(ca, la, na, d, x0, x1, tri, edges, tol, out, c, out_vt, out_ee)
        return
    nb = _region_sorted(b.boxes, b.starts[q], b.starts[q + 1], d, r, lb, cb, key, tmp)
    _sweep_test(kind, ca, cb, la, lb, na, nb, d, same, x0, x1, tri, edges, tol, out, c, out_vt, out_ee)


@njit(cache=True, parallel=True)
def _probe_kernel(mesh, v_own, t_own, e_own, v_scene, t_scene, e_scene, nbr, want, out_vt, out_ee, cursors):
    """Per part (those ``want`` flags): its own pairs (the vertices, triangles and edges with their
    moving-frame boxes, ``*_own``) and its pairs with the parts listed for it (``nbr``; the scene's
    boxes, ``*_scene``); (n_parts, :data:`_N_COUNTERS`) counters, started from ``cursors`` (where
    each part writes its crossing pairs into ``out_vt`` / ``out_ee``, and how many it may write)."""
    sv, st, se = v_scene.starts, t_scene.starts, e_scene.starts
    n_parts = sv.shape[0] - 1
    big = 1
    for p in range(n_parts):
        big = max(big, sv[p + 1] - sv[p], st[p + 1] - st[p], se[p + 1] - se[p])
    counts = np.zeros((n_parts, _N_COUNTERS), np.int64)
    counts[:] = cursors
    for p in prange(n_parts):
        if not want[p]:
            continue
        la = np.empty(big, np.int32)
        lb = np.empty(big, np.int32)
        ca = np.empty((big, 6))
        cb = np.empty((big, 6))
        key = np.empty(big)
        tmp = np.empty(big, np.int32)
        r = np.empty(6)
        out = np.zeros(4)
        c = counts[p]
        _pair_parts(0, p, p, v_own, t_own, False, mesh, la, lb, ca, cb, key, tmp, r, out, c, out_vt, out_ee)
        _pair_parts(1, p, p, e_own, e_own, True, mesh, la, lb, ca, cb, key, tmp, r, out, c, out_vt, out_ee)
        for t in range(nbr.vt_start[p], nbr.vt_start[p + 1]):
            _pair_parts(0, p, nbr.vt_nbr[t], v_scene, t_scene, False, mesh,
                        la, lb, ca, cb, key, tmp, r, out, c, out_vt, out_ee)
        for t in range(nbr.ee_start[p], nbr.ee_start[p + 1]):
            _pair_parts(1, p, nbr.ee_nbr[t], e_scene, e_scene, True, mesh,
                        la, lb, ca, cb, key, tmp, r, out, c, out_vt, out_ee)
    return counts


# --------------------------------------------------------------------------------------------------
# The exact static test, part by part (the written frames' check, the sanity checks)
# --------------------------------------------------------------------------------------------------


def intersecting_pairs_by_part(vertex_x: np.ndarray, tri_indices: np.ndarray, tri_part: np.ndarray) -> np.ndarray:
    """:func:`.tritri.intersecting_pairs` (every pair of intersecting triangles sharing no vertex,
    exact) for triangles grouped by part: the pairs within a part by sweep and prune in the part's
    box, those of two parts where their boxes overlap, each tested as it is found (no pair list:
    in a canopy most candidate pairs are neighbours in one floret, cheaper to test than to write).

    Parameters
    ----------
    vertex_x : (n, 3) float64
    tri_indices : (m, 3) int32
    tri_part : (m,) int
        Non-decreasing (:func:`.broad.parts_grouped`).

    Returns
    -------
    (k, 2) int32
        Pairs ``(i, j)``, ``i < j``, sorted (as :func:`.tritri.intersecting_pairs`).
    """
    x = np.ascontiguousarray(vertex_x, dtype=np.float64)
    tri = np.ascontiguousarray(tri_indices, dtype=np.int32)
    if len(tri) < 2:
        return np.zeros((0, 2), np.int32)
    tp = np.ascontiguousarray(tri_part, dtype=np.int64)
    n_parts = int(tp[-1]) + 1
    tb = triangle_boxes(x, x, tri, 0.0)
    st = _part_starts(tp, n_parts)
    pt = _part_boxes(tb, st)
    start, nbr = _overlapping_parts(pt, pt, True, PARTS_ANY)
    counts = _static_kernel(x, tri, tb, pt, st, start, nbr, np.zeros((0, 2), np.int32),
                            np.zeros(0, np.int64))
    if counts.sum() == 0:
        return np.zeros((0, 2), np.int32)
    at = np.zeros(n_parts + 1, np.int64)
    at[1:] = np.cumsum(counts)
    flagged = np.zeros((int(at[-1]), 2), np.int32)
    want = counts > 0
    _static_kernel(x, tri, tb, pt, st, start, nbr, flagged, np.append(np.where(want, at[:-1], -1), 0))
    flagged = _sorted_pairs(flagged)
    flags = _pair_flags(x, tri, flagged)
    return _decide(x, tri, flagged, flags)


@njit(cache=True)
def _pair_flags(x, tri, pairs):
    out = np.zeros(pairs.shape[0], np.int8)
    for k in range(pairs.shape[0]):
        out[k] = _pair_flag(x, tri, pairs[k, 0], pairs[k, 1])
    return out


@njit(cache=True, inline="always")
def _static_flag(x, tri, i, j, out, base, n):
    """Count pair (i, j) where the float test does not call it disjoint, writing it at
    ``out[base + n]`` where ``base >= 0``; returns the new count."""
    if _pair_flag(x, tri, i, j) != 0:
        if base >= 0:
            out[base + n, 0] = i
            out[base + n, 1] = j
        n += 1
    return n


@njit(cache=True)
def _static_pair_parts(p, q, x, tri, tb, pt, st, la, lb, ca, cb, key, tmp, r, out, base, n):
    """Test the triangles of part p against those of part q (p <= q) that reach into the
    intersection of their boxes, pairs ``a < b``; a pair the float test does not call disjoint
    (intersecting or undecided) is counted, and written at ``out[base + n]`` where ``base >= 0``.
    Returns the new count. (A part's own pairs by one sweep of its list, as :func:`_sweep_self`.)"""
    d = _region(pt, p, pt, q, r)
    if d < 0:
        return n
    na = _region_sorted(tb, st[p], st[p + 1], d, r, la, ca, key, tmp)
    if p == q:
        for i in range(na - 1):
            top = ca[i, d + 3]
            a = la[i]
            k = i + 1
            while k < na and ca[k, d] <= top:
                if _overlap_flat(ca, i, ca, k):
                    b = la[k]
                    lo = min(a, b)
                    hi = max(a, b)
                    if not _tri_share_vertex(tri, lo, hi):
                        n = _static_flag(x, tri, lo, hi, out, base, n)
                k += 1
        return n
    nb = _region_sorted(tb, st[q], st[q + 1], d, r, lb, cb, key, tmp)
    ia = 0
    ib = 0
    while ia < na and ib < nb:
        first_a = ca[ia, d] <= cb[ib, d]
        top = ca[ia, d + 3] if first_a else cb[ib, d + 3]
        k = ib if first_a else ia
        while True:
            if first_a:
                if k >= nb or cb[k, d] > top:
                    break
                i, j = la[ia], lb[k]
                ok = _overlap_flat(ca, ia, cb, k)
            else:
                if k >= na or ca[k, d] > top:
                    break
                i, j = la[k], lb[ib]
                ok = _overlap_flat(ca, k, cb, ib)
            k += 1
            if j <= i or not ok or _tri_share_vertex(tri, i, j):
                continue
            n = _static_flag(x, tri, i, j, out, base, n)
        if first_a:
            ia += 1
        else:
            ib += 1
    return n


@njit(cache=True, parallel=True)
def _static_kernel(x, tri, tb, pt, st, start, nbr, out, base):
    """Per part p: its own pairs and those with the parts q > p listed for it; (n_parts,) counts
    of pairs not certainly disjoint, written to ``out`` from ``base[p]`` where that is >= 0
    (``base`` empty: count only)."""
    n_parts = st.shape[0] - 1
    big = 1
    for p in range(n_parts):
        big = max(big, st[p + 1] - st[p])
    counts = np.zeros(n_parts, np.int64)
    for p in prange(n_parts):
        b0 = base[p] if base.shape[0] > n_parts else -1
        if base.shape[0] > n_parts and b0 < 0:
            continue
        la = np.empty(big, np.int32)
        lb = np.empty(big, np.int32)
        ca = np.empty((big, 6))
        cb = np.empty((big, 6))
        key = np.empty(big)
        tmp = np.empty(big, np.int32)
        r = np.empty(6)
        n = 0
        for t in range(start[p], start[p + 1]):
            n = _static_pair_parts(p, nbr[t], x, tri, tb, pt, st, la, lb, ca, cb, key, tmp, r, out, b0, n)
        counts[p] = n
    return counts
