"""Floret fate by cones (thesis ch. 6, eq. 6.1-6.2, figs. 6.1-6.4).

Each floret P has a cone K(P) with its apex at P, pointing away from the centre O of P's head or
umbellet, with opening angle alpha. Eq. 6.1 sets d(P, Q) = |Q - P| when Q is inside K(P) and
infinity otherwise; eq. 6.2 takes d_min(P) = min_Q d(P, Q). Q is inside the cone when the angle
between PQ and OP is below the cone's half-angle:

    (Q - P)^ . (P - O)^ > cos(half_angle),   half_angle = alpha / 2  (alpha: full opening angle).

The thesis's eq. 6.1 as printed compares with ``cos alpha`` (alpha read as a half-angle);
``half_angle=True`` follows that reading. With the full-angle reading the ray counts of a
82-floret head over alpha = 20..120 degrees run through the Fibonacci plateaus 55, 34, 21 of
fig. 6.3; with the half-angle reading they fall to 0 above about 105 degrees.

Fates (fig. 6.4): with no threshold P is a ray floret iff d_min(P) is infinite (fig. 6.2, 6.3);
with one threshold Th iff d_min(P) > Th (fig. 6.4a, b); with two thresholds Th_a < Th_b, a large
ray floret iff d_min > Th_b, a small one iff Th_a < d_min <= Th_b (size proportional to d_min,
fig. 6.4c), a disk floret otherwise.

Search: d_min is found on a cKDTree by querying the k nearest neighbours in order of distance,
doubling k for the florets not yet resolved; the first neighbour inside the cone gives d_min
exactly. A threshold bounds the query radius (``distance_upper_bound``), so each floret looks at
its neighbours within the threshold only: O(n log n) expected. Without a threshold a floret with
an empty cone (a ray floret) is only resolved when every floret was examined, O(n) each; rays
are the rim florets, about sqrt(n) of them.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy.spatial import cKDTree

from inflo.tools.common import linalg as la

__all__ = ["FATE_DISK", "FATE_RAY", "FATE_SMALL_RAY", "cone_directions", "first_in_cone", "d_min",
           "d_min_reference", "fates"]

FATE_DISK = 0
FATE_RAY = 1
FATE_SMALL_RAY = 2


def cone_directions(pos: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Unit cone axes ``(P - O)^`` (n, 3) float64; a zero row where P coincides with O."""
    d = np.asarray(pos, dtype=np.float64) - np.asarray(centre, dtype=np.float64)
    n = la.norm(d, axis=1)
    out = np.zeros_like(d)
    ok = n > 1e-12
    out[ok] = d[ok] / n[ok, None]
    return out


@njit(cache=True)
def first_in_cone(pos, axis, rows, nbr_idx, nbr_dist, cos_half, dmin, resolved):
    """For each floret ``rows[i]``, the first neighbour (in order of distance) inside its cone.

    Parameters
    ----------
    pos : (n, 3) float64  floret positions
    axis : (n, 3) float64  unit cone axes (zero: the floret sits at its centre O)
    rows : (m,) int64  the florets queried
    nbr_idx : (m, k) int64  their k nearest neighbours, nearest first (n = missing)
    nbr_dist : (m, k) float64  the distances (inf = missing)
    cos_half : float  cosine of the cone's half-angle
    dmin : (n,) float64  output: d_min (eq. 6.2) of resolved florets
    resolved : (n,) bool  output: True once d_min is known (a hit, or no neighbour left)

    A floret whose axis is zero gets d_min = 0 (no outward direction: a disk floret). The list
    is complete when its last entry is missing (fewer neighbours within the search radius) or
    when ``complete`` -- that is left to the caller through ``nbr_idx``'s width.
    """
    n = pos.shape[0]
    for i in range(rows.shape[0]):
        p = rows[i]
        ax, ay, az = axis[p, 0], axis[p, 1], axis[p, 2]
        if ax == 0.0 and ay == 0.0 and az == 0.0:
            dmin[p] = 0.0
            resolved[p] = True
            continue
        for j in range(nbr_idx.shape[1]):
            q = nbr_idx[i, j]
            if q >= n:  # no more neighbours within the search radius
                dmin[p] = math.inf
                resolved[p] = True
                break
            d = nbr_dist[i, j]
            if q == p or d <= 0.0:
                continue
            c = ((pos[q, 0] - pos[p, 0]) * ax + (pos[q, 1] - pos[p, 1]) * ay + (pos[q, 2] - pos[p, 2]) * az) / d
            if c > cos_half:
                dmin[p] = d
                resolved[p] = True
                break


def _cos_half(alpha: float, half_angle: bool) -> float:
    half = alpha if half_angle else 0.5 * alpha
    return math.cos(math.radians(half))


def d_min(pos, centre, alpha: float, *, radius: float = math.inf, half_angle: bool = False,
          k0: int = 16) -> np.ndarray:
    """d_min(P) of eq. 6.2 for every floret (inf: no floret in the cone within ``radius``).

    Parameters
    ----------
    pos : (n, 3) float  floret positions
    centre : (n, 3) float  the centre O of each floret's head or umbellet
    alpha : float  cone opening angle in degrees (full angle unless ``half_angle``)
    radius : float  search radius; florets farther than it are ignored (a threshold)

    Returns
    -------
    (n,) float64
    """
    pos = np.ascontiguousarray(pos, dtype=np.float64).reshape(-1, 3)
    n = len(pos)
    dmin = np.full(n, np.inf)
    if n == 0:
        return dmin
    axis = cone_directions(pos, np.broadcast_to(centre, pos.shape))
    cos_half = _cos_half(alpha, half_angle)
    tree = cKDTree(pos)
    resolved = np.zeros(n, dtype=bool)
    rows = np.arange(n, dtype=np.int64)
    k = min(k0, n)
    bound = radius * (1.0 + 1e-12) if math.isfinite(radius) else np.inf
    while len(rows):
        dist, idx = tree.query(pos[rows], k=k, distance_upper_bound=bound)
        dist = np.asarray(dist, dtype=np.float64).reshape(len(rows), k)
        idx = np.asarray(idx, dtype=np.int64).reshape(len(rows), k)
        if k >= n:  # every floret examined: append a 'missing' column so unresolved rows end
            idx = np.hstack([idx, np.full((len(rows), 1), n, np.int64)])
            dist = np.hstack([dist, np.full((len(rows), 1), np.inf)])
        first_in_cone(pos, axis, rows, idx, dist, cos_half, dmin, resolved)
        rows = rows[~resolved[rows]]
        k = min(2 * k, n)
    return dmin


def d_min_reference(pos, centre, alpha: float, *, half_angle: bool = False) -> np.ndarray:
    """Eq. 6.1-6.2 by brute force over all pairs (slow, obviously correct; for tests)."""
    pos = np.asarray(pos, dtype=np.float64).reshape(-1, 3)
    axis = cone_directions(pos, np.broadcast_to(centre, pos.shape))
    cos_half = _cos_half(alpha, half_angle)
    out = np.full(len(pos), np.inf)
    for p in range(len(pos)):
        if not axis[p].any():
            out[p] = 0.0
            continue
        v = pos - pos[p]
        d = la.norm(v, axis=1)
        other = d > 0  # Q = P (or a floret at the same point) has no direction
        inside = np.zeros(len(pos), dtype=bool)
        inside[other] = la.matmul(v[other], axis[p]) / d[other] > cos_half
        if inside.any():
            out[p] = d[inside].min()
    return out


def fates(dmin: np.ndarray, thresholds=()) -> np.ndarray:
    """(n,) int8 fate per floret from d_min (module docstring): FATE_DISK, FATE_RAY, FATE_SMALL_RAY."""
    dmin = np.asarray(dmin, dtype=np.float64)
    th = sorted(float(t) for t in thresholds)
    out = np.full(dmin.shape, FATE_DISK, dtype=np.int8)
    if not th:
        out[np.isinf(dmin)] = FATE_RAY
    elif len(th) == 1:
        out[dmin > th[0]] = FATE_RAY
    else:
        out[(dmin > th[0]) & (dmin <= th[1])] = FATE_SMALL_RAY
        out[dmin > th[1]] = FATE_RAY
    return out
