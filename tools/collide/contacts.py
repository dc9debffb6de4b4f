"""Collision contacts and the narrow phase over candidate pairs (thesis 4.2.2).

:class:`Contacts` holds the pairs that need a response, one row per pair (vertex-triangle or
edge-edge), with the coefficients, normal and time of impact the response (:mod:`.response`)
projects; :func:`_narrow` runs the continuous tests of :mod:`.ccd` over candidate pairs (in
parallel above ``SERIAL_NARROW_BELOW`` pairs) and builds the contacts of those crossing an odd
number of times (4.2.2.3). The broad phase that finds the candidates is :mod:`.broad` and, within
a step's rounds, :mod:`.step_broad`; the loop that uses the contacts is :mod:`.resolve`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit, prange

from .ccd import edge_edge_ccd, edge_edge_culled, vertex_triangle_ccd, vertex_triangle_culled

KIND_VT = 0
KIND_EE = 1


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
