"""Static triangle-triangle intersection test (fccompose's sanity check and the tests' judge).

Two triangles intersect when they share at least one point. The test is built on orientation
predicates (signs of 3x3 determinants), not on distances with a tolerance: two non-coplanar
triangles intersect if and only if an edge of one meets the other (their intersection segment
ends on edges); segment-triangle and coplanar cases are decided by signs of ``orient3d`` and,
in the plane, ``orient2d``. The determinants are evaluated in float64 and each sign is certified
by Shewchuk's forward error bound for orient3d, ``(7 + 56 eps) eps * permanent``: when every
determinant the test can use has a certified sign, the float answer is exact; otherwise (coplanar
or touching configurations) the pair is decided in rational arithmetic by
:func:`inflo.tools.collide.exact.triangles_intersect_exact`. So :func:`intersecting_pairs` is an
exact test. Triangles that share a vertex index are not tested by the callers (adjacent triangles
touch by construction).

The test of one pair (the predicates, :func:`triangles_intersect`, :func:`certified`,
:func:`separated`) lives in :mod:`.tripair`, which :mod:`.probe` shares; this module runs it over
the candidate pairs its broad phases find.
"""
from __future__ import annotations

import numpy as np
from numba import njit, prange

from .probe import intersecting_pairs_by_part
from .tripair import _decide, _pair_flag, _share_vertex
from .tripair import certified as certified
from .tripair import orient3d as orient3d
from .tripair import separated as separated
from .tripair import triangles_intersect as triangles_intersect

__all__ = ["orient3d", "triangles_intersect", "certified", "intersecting_pairs", "intersecting_pairs_brute"]


@njit(cache=True, inline="always")
def _test_pair(x, tri, pairs, flags, k):
    """flags[k]: 0 disjoint, 1 intersecting (both certified), 2 undecided in float64."""
    i = pairs[k, 0]
    j = pairs[k, 1]
    if _share_vertex(tri, i, j):
        flags[k] = 0
        return
    flags[k] = _pair_flag(x, tri, i, j)


@njit(cache=True, parallel=True)
def _test_pairs(x, tri, pairs, flags):
    """:func:`_test_pair` of every candidate pair, in parallel."""
    for k in prange(pairs.shape[0]):
        _test_pair(x, tri, pairs, flags, k)


@njit(cache=True)
def _test_pairs_serial(x, tri, pairs, flags):
    """:func:`_test_pairs` on one thread (the same flags), for the few pairs of a small canopy."""
    for k in range(pairs.shape[0]):
        _test_pair(x, tri, pairs, flags, k)


#: below this many candidate pairs the float test runs on one thread
SERIAL_TEST_BELOW = 20000


def _exact_pairs(x, tri, pairs) -> np.ndarray:
    """The intersecting ones among candidate ``pairs`` (float test where certified, exact else)."""
    flags = np.zeros(len(pairs), np.int8)
    (_test_pairs_serial if len(pairs) < SERIAL_TEST_BELOW else _test_pairs)(x, tri, pairs, flags)
    return _decide(x, tri, pairs, flags)


def intersecting_pairs(vertex_x: np.ndarray, tri_indices: np.ndarray, *, cell_size: float | None = None,
                       tri_part: np.ndarray | None = None, skip_parts: np.ndarray | None = None) -> np.ndarray:
    """All pairs of intersecting triangles that share no vertex (exact static test).

    Broad phase: :func:`inflo.tools.collide.broad.box_pairs` over the triangles' boxes; with
    ``tri_part`` (the part, a canopy's floret, of every triangle) grouped by part, the part-by-part
    sweep of :func:`inflo.tools.collide.probe.intersecting_pairs_by_part` (the same pairs).

    Parameters
    ----------
    vertex_x : (n, 3) float64
    tri_indices : (m, 3) int32
    tri_part : (m,) int or None
    skip_parts : (p, p) bool or None
        With ``tri_part``: candidate pairs of triangles in parts a and b with ``skip_parts[a, b]``
        are not tested (parts joined by construction, whose pairs a caller would discard: a plant's
        stem and its leaves). The other pairs are found as without it.

    Returns
    -------
    (k, 2) int32
        Pairs ``(i, j)``, ``i < j``, sorted.
    """
    from .broad import PART_SWEEP_MAX_ELEMENTS, box_pairs, parts_grouped, triangle_boxes

    x = np.ascontiguousarray(vertex_x, dtype=np.float64)
    tri = np.ascontiguousarray(tri_indices, dtype=np.int32)
    if len(tri) < 2:
        return np.zeros((0, 2), np.int32)
    if skip_parts is not None and tri_part is not None:
        part = np.asarray(tri_part, np.int64)
        pairs = box_pairs(triangle_boxes(x, x, tri, 0.0), None, cell_size=cell_size)
        pairs = pairs[~np.asarray(skip_parts, bool)[part[pairs[:, 0]], part[pairs[:, 1]]]]
        return _exact_pairs(x, tri, np.ascontiguousarray(pairs))
    if (tri_part is not None and len(tri_part) == len(tri) and parts_grouped(tri_part)
            and int(np.bincount(np.asarray(tri_part)).max()) <= PART_SWEEP_MAX_ELEMENTS):
        return intersecting_pairs_by_part(x, tri, tri_part)
    boxes = triangle_boxes(x, x, tri, 0.0)
    pairs = box_pairs(boxes, None, cell_size=cell_size)
    return _exact_pairs(x, tri, pairs)


def intersecting_pairs_with(vertex_x: np.ndarray, tri_indices: np.ndarray, which, *,
                            cell_size: float | None = None, tri_part: np.ndarray | None = None) -> np.ndarray:
    """Intersecting triangle pairs (exact static test, pairs sharing a vertex skipped) in which at
    least one triangle is one of ``which`` (indices into ``tri_indices``); the other may be any.

    What :func:`intersecting_pairs` would report for those triangles, at the cost of a query of
    every triangle's box against the boxes of ``which`` only (fccompose checks a newly emerging
    floret against the canopy this way). With ``tri_part`` ((m,) int >= 0: the part, e.g. the
    floret, of every triangle), only the triangles of parts whose box overlaps the box of a part
    of ``which`` are queried (the same pairs: two triangles' boxes overlap only where their
    parts' do; a crowded 350k canopy: 35 -> 10 ms a call).

    Returns
    -------
    (k, 2) int32
        Pairs ``(i, j)``, ``i < j``, sorted, indices into ``tri_indices``.
    """
    from .broad import box_pairs, triangle_boxes

    x = np.ascontiguousarray(vertex_x, dtype=np.float64)
    tri = np.ascontiguousarray(tri_indices, dtype=np.int32)
    sub = np.asarray(which, dtype=np.int64).reshape(-1)
    if len(sub) == 0 or len(tri) < 2:
        return np.zeros((0, 2), np.int32)
    if tri_part is not None:
        tp = np.ascontiguousarray(tri_part, dtype=np.int64)
        pb = _tri_part_boxes(x, tri, tp, int(tp.max()) + 1)
        mine = np.zeros(len(pb), np.bool_)
        mine[tp[sub]] = True
        ids = np.nonzero(mine)[0]
        present = np.nonzero(pb[:, 0] <= pb[:, 3])[0]  # parts with a triangle
        near = np.zeros(len(pb), np.bool_)
        near[present[box_pairs(np.ascontiguousarray(pb[present]), np.ascontiguousarray(pb[ids]))[:, 0]]] = True
        cand = np.nonzero(near[tp])[0]
    else:
        cand = np.arange(len(tri))
    boxes = triangle_boxes(x, x, np.ascontiguousarray(tri[cand]), 0.0)
    sub_boxes = triangle_boxes(x, x, np.ascontiguousarray(tri[sub]), 0.0)
    pairs = box_pairs(boxes, sub_boxes, cell_size=cell_size)
    g = np.stack([cand[pairs[:, 0]].astype(np.int64), sub[pairs[:, 1]]], axis=1)
    g = g[g[:, 0] != g[:, 1]]
    if len(g) == 0:
        return np.zeros((0, 2), np.int32)
    g = np.sort(g, axis=1)
    key = np.unique(g[:, 0] * np.int64(len(tri)) + g[:, 1])  # the sorted distinct rows, as one int64 each
    g = np.stack([key // len(tri), key % len(tri)], axis=1).astype(np.int32)
    return _exact_pairs(x, tri, g)


@njit(cache=True)
def _tri_part_boxes(x, tri, tri_part, n_parts):
    """(n_parts, 6): the box of every part's triangles (a part without one: an empty box)."""
    out = np.empty((n_parts, 6))
    for p in range(n_parts):
        for d in range(3):
            out[p, d] = np.inf
            out[p, d + 3] = -np.inf
    for k in range(tri.shape[0]):
        p = tri_part[k]
        for j in range(3):
            v = tri[k, j]
            for d in range(3):
                out[p, d] = min(out[p, d], x[v, d])
                out[p, d + 3] = max(out[p, d + 3], x[v, d])
    return out


def intersecting_pairs_between(a_x: np.ndarray, a_tri: np.ndarray, b_x: np.ndarray, b_tri: np.ndarray, *,
                               cell_size: float | None = None) -> np.ndarray:
    """Intersecting triangle pairs with one triangle in mesh ``a`` and the other in mesh ``b``
    (exact static test; two separate meshes share no vertex, so touching counts everywhere).

    Used to check what is drawn with a canopy but not simulated with it (the lily's column, the
    yarrow's branches) against the canopy. Broad phase: :func:`~inflo.tools.collide.broad.box_pairs`
    of a's boxes against b's.

    Returns
    -------
    (k, 2) int32
        Pairs ``(i, j)``: triangle i of ``a`` intersects triangle j of ``b``; sorted.
    """
    from .broad import box_pairs, triangle_boxes

    ax = np.ascontiguousarray(a_x, dtype=np.float64)
    bx = np.ascontiguousarray(b_x, dtype=np.float64)
    at = np.ascontiguousarray(a_tri, dtype=np.int32)
    bt = np.ascontiguousarray(b_tri, dtype=np.int32)
    if len(at) == 0 or len(bt) == 0:
        return np.zeros((0, 2), np.int32)
    pairs = box_pairs(triangle_boxes(ax, ax, at, 0.0), triangle_boxes(bx, bx, bt, 0.0), cell_size=cell_size)
    x = np.vstack([ax, bx])
    tri = np.vstack([at, bt + len(ax)]).astype(np.int32)
    both = np.ascontiguousarray(np.stack([pairs[:, 0], pairs[:, 1] + len(at)], axis=1), dtype=np.int32)
    hit = _exact_pairs(x, tri, both)
    return np.stack([hit[:, 0], hit[:, 1] - len(at)], axis=1).astype(np.int32)


def intersecting_pairs_brute(vertex_x, tri_indices):
    """Reference for tests: every pair tested, O(m^2). Returns (k, 2) int32 sorted."""
    x = np.ascontiguousarray(vertex_x, dtype=np.float64)
    tri = np.ascontiguousarray(tri_indices, dtype=np.int32)
    m = len(tri)
    ii, jj = np.triu_indices(m, 1)
    pairs = np.stack([ii, jj], axis=1).astype(np.int32)
    return _exact_pairs(x, tri, pairs)
