"""Elements that grow into the room around them: a closed canopy from a recursive pattern.

Recursive segregation (sec. 5.4, fig. 5.3) gives every element the area it was born with, grown
with the space; an element's sub-pattern fills exactly its area *in area coordinates*, but the
discs of a ring of elements do not tile the ring, and the loss compounds over the levels: a
three-level corymb covers only about half of its outline, and its top view reads as islands of
heads with wide gaps between the clusters. A real corymb is one continuous, flat-topped canopy
(thesis fig. 9.10): heads grow on flexible peduncles into the room their neighbours leave them.

:func:`fill_room` models that at the end of the run. The canopy's outline is the union of the
elements' discs, each grown by ``margin`` of its radius (so gaps narrower than that close, and the
irregular outline of the pattern stays). Within it each element owns the points nearest to it in
the multiplicatively weighted distance ``|x - p| / d`` (a big head claims proportionally more
room than a small one); ``iterations`` Lloyd steps move each element to the centroid of its cell
and give it the diameter of the disc of its cell's area, within ``scale_range`` x its own. Last,
no two elements of different ages may overlap more than they did in the pattern (a young head
forms in the room between older ones; an old head grown over that place would leave the young
head's florets no room to emerge); elements of one age (a cohort that forms at once) may.

:func:`apply_room` carries the result over the pattern's development: an element keeps its
diameter factor from birth on and is displaced by its final displacement scaled as the space has
grown (``d(t) / d(final)``; every area grows at the same rate, so that is one factor for all), so
every frame is the final layout's growth history and the pattern's own order of emergence stays.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from inflo.tools.common import linalg as la

__all__ = ["fill_room", "apply_room"]

#: the most raster cells the outline is sampled with (the cell size follows from it and from the
#: smallest element: at least 6 cells across its radius when that fits)
MAX_CELLS = 2_000_000


def fill_room(pos: np.ndarray, diameter: np.ndarray, *, margin: float = 1.0, iterations: int = 1,
              scale_range: tuple = (0.9, 1.5), neighbours: int = 12,
              birth: np.ndarray | None = None, weight: str = "size",
              outline: str = "discs") -> tuple[np.ndarray, np.ndarray]:
    """Positions (n, 2) and diameters (n,) of elements grown into their room (see module doc).

    Parameters
    ----------
    pos : (n, 2) centres in the plane of the pattern (x, z)
    diameter : (n,) the elements' disc diameters (the pattern's sizes)
    margin : the outline is within ``(1 + margin) x radius`` of some element
    iterations : Lloyd steps (each: cells, centroids, sizes)
    scale_range : (lo, hi) the new diameter stays within [lo, hi] x the element's own
    neighbours : how many nearest elements a raster point's owner is chosen among
    birth : (n,) formation times, optional: the overlap bound then holds only between elements of
        different ages (without it, between every two)
    weight : ``"size"`` (the cells of the weighted distance ``|x - p| / d``: a big element claims
        proportionally more room) or ``"equal"`` (the plain distance: Lloyd's steps even the cells
        out, so elements of any age end alike in size, as the heads of a real corymb, whose size is
        the head's own and not its age's; widen ``scale_range`` for it)
    outline : ``"discs"`` (the union of the grown discs: the pattern's own irregular outline) or
        ``"hull"`` (their convex hull: one convex cap, the room between the lobes of the pattern
        given to the elements beside it)

    Returns ``(pos, diameter)``, new arrays; deterministic (no randomness, no threads).
    """
    p = np.asarray(pos, float).reshape(-1, 2)
    d0 = np.asarray(diameter, float).reshape(-1)
    n = len(p)
    if n < 2 or iterations <= 0:
        return p.copy(), d0.copy()
    r = 0.5 * d0
    reach = (1.0 + margin) * r
    lo = (p - reach[:, None]).min(axis=0)
    hi = (p + reach[:, None]).max(axis=0)
    box = float(np.prod(hi - lo))
    h = max(float(r.min()) / 6.0, (box / MAX_CELLS) ** 0.5)
    xs = np.arange(lo[0] + 0.5 * h, hi[0], h)
    zs = np.arange(lo[1] + 0.5 * h, hi[1], h)
    X, Z = np.meshgrid(xs, zs)
    P = np.column_stack([X.ravel(), Z.ravel()])
    k = min(neighbours, n)
    if outline == "hull":
        P = P[_in_hull(p, reach, P)]
    else:
        dist, idx = cKDTree(p).query(P, k)
        P = P[(dist < reach[idx]).any(axis=1)]
    q, w = p.copy(), d0.copy()
    for _ in range(iterations):
        dist, idx = cKDTree(q).query(P, k)
        scale = w[idx] if weight == "size" else 1.0
        own = idx[np.arange(len(P)), np.argmin(dist / scale, axis=1)]
        count = np.bincount(own, minlength=n).astype(float)
        has = count > 0
        cx = np.bincount(own, P[:, 0], n)
        cz = np.bincount(own, P[:, 1], n)
        q[has] = np.column_stack([cx[has], cz[has]]) / count[has, None]
        room = 2.0 * np.sqrt(count * h * h / np.pi)
        w = np.where(has, np.clip(room, scale_range[0] * d0, scale_range[1] * d0), w)
    return q, _no_new_overlap(p, d0, q, w, scale_range[0] * d0, birth)


def _in_hull(p: np.ndarray, reach: np.ndarray, P: np.ndarray, sides: int = 64) -> np.ndarray:
    """Which raster points ``P`` lie in the convex hull of the discs (centres ``p``, radii
    ``reach``), the hull of ``sides`` points on each disc's circle."""
    from scipy.spatial import ConvexHull, Delaunay

    a = np.linspace(0.0, 2.0 * np.pi, sides, endpoint=False)
    ring = np.column_stack([np.cos(a), np.sin(a)])
    pts = (p[:, None, :] + reach[:, None, None] * ring[None]).reshape(-1, 2)
    hull = pts[ConvexHull(pts).vertices]
    return Delaunay(hull).find_simplex(P) >= 0


def _no_new_overlap(p, d0, q, w, floor, birth=None, sweeps: int = 100):
    """Diameters ``w`` reduced (not below ``floor``) so that no two discs overlap more than they
    did in the pattern: ``(w_i + w_j) / 2 <= |q_i - q_j| x max(1, (d_i + d_j) / (2 |p_i - p_j|))``.

    A cell's equivalent disc reaches beyond an elongated cell, and a big element's weighted cell
    borders a small neighbour closely: unchecked, a grown head would cover a younger neighbour's
    place (its florets then find no room to emerge). Each violated pair gives up its excess in
    proportion to how much each of the two can still shrink (Jacobi sweeps, monotone)."""
    n = len(q)
    w = w.copy()
    reach = float(w.max())
    pairs = cKDTree(q).query_pairs(reach, output_type="ndarray")
    if len(pairs) == 0:
        return w
    if birth is not None:
        pairs = pairs[birth[pairs[:, 0]] != birth[pairs[:, 1]]]
        if len(pairs) == 0:
            return w
    i, j = pairs[:, 0], pairs[:, 1]
    dq = la.norm(q[i] - q[j], axis=1)
    dp = la.norm(p[i] - p[j], axis=1)
    allow = np.full(len(i), np.inf)  # coincident in the pattern: no bound to keep
    ok = dp > 0
    allow[ok] = dq[ok] * np.maximum(1.0, 0.5 * (d0[i] + d0[j])[ok] / dp[ok])
    for _ in range(sweeps):
        excess = 0.5 * (w[i] + w[j]) - allow
        bad = excess > 1e-12 * reach
        if not bad.any():
            break
        gi = np.maximum(w[i] - floor[i], 0.0)
        gj = np.maximum(w[j] - floor[j], 0.0)
        tot = gi + gj
        share = np.where(tot > 0, 2.0 * excess / np.where(tot > 0, tot, 1.0), 0.0)
        cut = np.zeros(n)
        np.maximum.at(cut, i[bad], (share * gi)[bad])
        np.maximum.at(cut, j[bad], (share * gj)[bad])
        w = np.maximum(w - cut, floor)
    return w


def apply_room(state: dict, final: dict, shift: np.ndarray, factor: np.ndarray) -> dict:
    """``state`` (a :func:`hierarchy_state` dict) with its florets grown into their room.

    ``final`` is the unchanged state at the end of the run, ``shift`` (f, 3) and ``factor`` (f,)
    the displacement and diameter factor of every floret of ``final`` (rows of ``final["ids"]``).
    A floret's displacement at time t is ``shift x d(t) / d(final)``.
    """
    row = np.searchsorted(final["ids"], state["ids"])
    grown = state["scale"][:, 0] / final["scale"][row, 0]
    out = dict(state)
    out["pos"] = state["pos"] + shift[row] * grown[:, None]
    out["scale"] = state["scale"] * factor[row, None]
    return out
