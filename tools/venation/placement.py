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
        return Delaunay(pts)
    except (QhullError, ValueError):  # collinear or repeated points: no triangle
        return None


#: the new triangles of a source lie within this many times its circle's radius (its Delaunay
#: neighbours after insertion bound empty circles no larger than the largest one in the blade)
LOCAL_REACH = 2.5


def largest_empty_circles(margin: np.ndarray, contains: Callable, node_pos: np.ndarray, src_pos: np.ndarray,
                          bs: float, bv: float, limit: int) -> np.ndarray:
    """The sources of one iteration: (k, 3) rows (x, y, radius) in placement order, each the centre
    of the largest circle, among the candidates, that is empty of vein nodes (``node_pos``), of
    sources (``src_pos`` and those placed before it) and farther than ``bs`` from every source and
    ``bv`` from every vein node; at most ``limit`` of them. ``contains(pts)`` says which points
    lie in the blade, whose margin is the polygon ``margin``.

    The triangulation of vein nodes and sources is made once; after each source is placed its
    update is local: the candidates' distances to sources take the new one, and the circumcentres
    of the triangles it makes with its Delaunay neighbours (found among the points within
    :data:`LOCAL_REACH` times its circle's radius) join the candidates. A candidate's radius is
    always its distance to the closest vein node or source, so every circle is empty."""
    node_pos = np.asarray(node_pos, dtype=np.float64).reshape(-1, 2)
    src_pos = np.asarray(src_pos, dtype=np.float64).reshape(-1, 2)
    node_tree = cKDTree(node_pos) if len(node_pos) else None
    src_tree = cKDTree(src_pos) if len(src_pos) else None

    def d_tree(tree, c):
        if tree is None:
            return np.full(len(c), np.inf)
        return tree.query(c)[0]

    cand = [margin_samples(margin, 0.25 * min(bs, bv))]
    allp = np.vstack([node_pos, src_pos])
    tri = _triangulate(allp)
    if tri is not None:
        cc = circumcentres(tri.points, tri.simplices)
        cc = cc[np.isfinite(cc).all(1)]
        if len(cc):
            cand.append(cc[contains(cc)])
    cand = np.vstack(cand)
    dv = d_tree(node_tree, cand)
    ds = d_tree(src_tree, cand)
    placed: list = []
    while len(placed) < limit:
        r = np.where((ds > bs) & (dv > bv), np.minimum(dv, ds), -np.inf)
        i = int(np.argmax(r)) if len(r) else 0
        if not len(r) or not r[i] > 0.0:
            break
        c = cand[i].copy()
        ri = float(r[i])
        placed.append((float(c[0]), float(c[1]), ri))
        ds = np.minimum(ds, np.hypot(cand[:, 0] - c[0], cand[:, 1] - c[1]))
        # the new source's triangles: with its Delaunay neighbours, among the points near it
        reach = LOCAL_REACH * ri
        near = [allp[node_tree.query_ball_point(c, reach)]] if node_tree is not None else []
        if src_tree is not None:
            near.append(src_pos[src_tree.query_ball_point(c, reach)])
        pl = np.asarray(placed)[:-1, :2].reshape(-1, 2)
        if len(pl):
            near.append(pl[np.hypot(pl[:, 0] - c[0], pl[:, 1] - c[1]) <= reach])
        local = np.vstack(near + [c[None]]) if near else c[None]
        lt = _triangulate(local)
        if lt is None:
            continue
        k = len(local) - 1
        mine = lt.simplices[(lt.simplices == k).any(1)]
        cc = circumcentres(lt.points, mine)
        cc = cc[np.isfinite(cc).all(1)]
        if len(cc):
            cc = cc[contains(cc)]
        if not len(cc):
            continue
        srcs = np.asarray(placed)[:, :2]
        ds_new = np.minimum(d_tree(src_tree, cc),
                            np.sqrt(((cc[:, None, :] - srcs[None]) ** 2).sum(-1)).min(1))
        cand = np.vstack([cand, cc])
        dv = np.concatenate([dv, d_tree(node_tree, cc)])
        ds = np.concatenate([ds, ds_new])
    return np.asarray(placed, dtype=np.float64).reshape(-1, 3)
