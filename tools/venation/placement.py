"""Deterministic source placement at the centre of the largest empty circle (Runions sec. 5.2.2).

"Sources are placed at the beginning of each iteration by repeatedly placing a source at the
centre of the largest empty circle in the leaf blade (while the circle is large enough to support a
new source)." The circle is empty of vein nodes and sources; its centre lies in the blade. "The
largest empty circle in a bounded region of the plane is either a circumscribed circle or a point
on the boundary": the candidates are the circumcentres of the Delaunay triangulation of the vein
nodes and sources that lie inside the blade, and a set of samples on the margin ("a circle is
generated, centred on each sample point, with radius equal to the distance to the closest point in
the Delaunay triangulation"). After each source is placed the triangulation is updated.

A circle supports a source when its centre is farther than b_s from every source and farther than
b_v from every vein node; of the candidates that do, the largest circle wins (ties: the first
candidate, margin samples in margin order, then triangles in the triangulation's order), so the
placement is deterministic.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.spatial import Delaunay, QhullError, cKDTree

__all__ = ["margin_samples", "circumcentres", "largest_empty_circles", "MAX_MARGIN_SAMPLES"]

#: margin samples (candidate centres on the margin) at most
MAX_MARGIN_SAMPLES = 20_000


def margin_samples(margin: np.ndarray, spacing: float) -> np.ndarray:
    """Points along the closed polygon ``margin`` (m, 2), every edge divided into pieces no longer
    than ``spacing`` (at most :data:`MAX_MARGIN_SAMPLES` points: the spacing grows for a long margin)."""
    p = np.asarray(margin, dtype=np.float64)
    q = np.roll(p, -1, axis=0)
    edge = np.hypot(*(q - p).T)
    per = float(edge.sum())
    h = max(float(spacing), per / MAX_MARGIN_SAMPLES, 1e-300)
    k = np.maximum(1, np.ceil(edge / h - 1e-9).astype(np.int64))
    while int(k.sum()) > MAX_MARGIN_SAMPLES:  # many short edges: one sample each is too many
        h *= 2.0
        k = np.maximum(1, np.ceil(edge / h - 1e-9).astype(np.int64))
        if np.all(k == 1):
            break
    t = np.concatenate([np.arange(n) / n for n in k])
    i = np.repeat(np.arange(len(p)), k)
    return p[i] + (q[i] - p[i]) * t[:, None]


def circumcentres(points: np.ndarray, simplices: np.ndarray) -> np.ndarray:
    """(t, 2) circumcentres of the triangles ``simplices`` (t, 3) of ``points``; degenerate
    triangles give non-finite rows."""
    a = points[simplices[:, 0]]
    b = points[simplices[:, 1]] - a
    c = points[simplices[:, 2]] - a
    d = 2.0 * (b[:, 0] * c[:, 1] - b[:, 1] * c[:, 0])
    b2 = (b * b).sum(1)
    c2 = (c * c).sum(1)
    with np.errstate(divide="ignore", invalid="ignore"):
        ux = (c[:, 1] * b2 - b[:, 1] * c2) / d
        uy = (b[:, 0] * c2 - c[:, 0] * b2) / d
    return a + np.column_stack([ux, uy])


def _triangulate(pts: np.ndarray):
    if len(pts) < 3:
        return None
    try:
        return Delaunay(pts, incremental=True)
    except (QhullError, ValueError):  # collinear or repeated points: no triangle
        return None


def largest_empty_circles(margin: np.ndarray, contains: Callable, node_pos: np.ndarray, src_pos: np.ndarray,
                          bs: float, bv: float, limit: int) -> np.ndarray:
    """The sources of one iteration: (k, 3) rows (x, y, radius) in placement order, each the centre
    of the largest circle, among the candidates, that is empty of vein nodes (``node_pos``), of
    sources (``src_pos`` and those placed before it) and farther than ``bs`` from every source and
    ``bv`` from every vein node; at most ``limit`` of them. ``contains(pts)`` says which points
    lie in the blade, whose margin is the polygon ``margin``."""
    node_pos = np.asarray(node_pos, dtype=np.float64).reshape(-1, 2)
    src_pos = np.asarray(src_pos, dtype=np.float64).reshape(-1, 2)
    msamp = margin_samples(margin, 0.25 * min(bs, bv))
    node_tree = cKDTree(node_pos) if len(node_pos) else None

    def d_nodes(c):
        if node_tree is None:
            return np.full(len(c), np.inf)
        return node_tree.query(c)[0]

    dm_v = d_nodes(msamp)
    dm_s = cKDTree(src_pos).query(msamp)[0] if len(src_pos) else np.full(len(msamp), np.inf)
    allp = np.vstack([node_pos, src_pos])
    tri = _triangulate(allp)
    placed: list = []
    while len(placed) < limit:
        if tri is None and len(placed):
            tri = _triangulate(np.vstack([allp, np.asarray(placed)[:, :2]]))
        cand, dv, ds = msamp, dm_v, dm_s
        if tri is not None:
            cc = circumcentres(tri.points, tri.simplices)
            ok = np.isfinite(cc).all(1)
            cc = cc[ok]
            if len(cc):
                cc = cc[contains(cc)]
            if len(cc):
                cs_v = d_nodes(cc)
                srcs = np.vstack([src_pos, np.asarray(placed)[:, :2]]) if placed else src_pos
                cs_s = cKDTree(srcs).query(cc)[0] if len(srcs) else np.full(len(cc), np.inf)
                cand = np.vstack([msamp, cc])
                dv = np.concatenate([dm_v, cs_v])
                ds = np.concatenate([dm_s, cs_s])
        r = np.minimum(dv, ds)
        r = np.where((ds > bs) & (dv > bv), r, -np.inf)
        i = int(np.argmax(r))
        if not r[i] > 0.0:
            break
        c = cand[i]
        placed.append((float(c[0]), float(c[1]), float(r[i])))
        # the new source in the margin samples' distances and in the triangulation
        dm_s = np.minimum(dm_s, np.hypot(msamp[:, 0] - c[0], msamp[:, 1] - c[1]))
        if tri is not None:
            try:
                tri.add_points(c[None])
            except (QhullError, ValueError):
                tri = None
    if tri is not None:
        tri.close()
    return np.asarray(placed, dtype=np.float64).reshape(-1, 3)
