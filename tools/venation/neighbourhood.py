"""Proximity queries of the venation algorithms (Runions secs. 4.2-4.4): a uniform grid of points,
the nearest vein node of a source (open patterns, fig. 4.10), the relative neighbourhood of a
source among the vein nodes (closed patterns, eq. 4.1, fig. 4.11) and its Urquhart approximation
(fig. 4.13), with slow, obviously-correct references for the tests.

Relative neighbourhood (eq. 4.1): vein node v belongs to V(s), the relative neighbourhood of source
s in A_s = V ∪ {s}, iff for every other node u

    |v - s| < max(|u - s|, |v - u|),

i.e. no u lies in the lune of s and v (both |u - s| <= |v - s| and |v - u| <= |v - s|). The
thesis finds V(s) among the Delaunay neighbours of s in A_s (the relative neighbourhood graph is a
subgraph of the Delaunay triangulation, sec. 4.4.2) and checks each against every node (exact), or
only against the other Delaunay neighbours (Urquhart's approximation).

:func:`relative_neighbourhoods` computes the same sets without a triangulation per source. The
nodes are visited in order of distance from s, ring by ring of grid cells; each visited node u
cuts the convex region C (initially a polygon around the nodes) by its bisector half-plane
{x : |x - s| <= |x - u|}. A node v farther than every node already visited is excluded by some u
exactly when it lies beyond u's bisector, so v is a relative neighbour iff it lies in C (the test
is then repeated with the exact inequality of eq. 4.1 against every visited node, so the answer
is the brute-force one, also under rounding). The search stops when every vertex of C is closer
to s than the ring radius: no unvisited node can lie in C. C is then the Voronoi cell of s in A_s
clipped to that polygon; for the Urquhart approximation the search goes on to twice that radius (the
classical bound for a Voronoi cell), the Delaunay neighbours of s are the nodes whose bisectors
bound C, and each is tested against the other Delaunay neighbours only. Every relative neighbour
is a Delaunay neighbour whose Voronoi edge holds the midpoint of s and v (the Gabriel property),
so with a polygon around A_s the Urquhart set of this module lies between the relative neighbourhood
and the Delaunay neighbourhood, as the thesis states.

C starts as the intersection of 32 support half-planes of the nodes (:func:`hull_support`): a
polygon around their convex hull, so a source near the margin, whose Voronoi cell opens toward the
empty margin, still has a small C. Only nodes near s are visited: the run time grows with the
number of sources, not with sources times nodes (sec. 4.4.2 reaches O(kn) with Voronoi diagrams).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

__all__ = [
    "Grid",
    "make_grid",
    "grid_insert",
    "grid_insert_idx",
    "grid_rebuild",
    "grid_remove_cells",
    "nearest_incremental",
    "relative_neighbourhoods",
    "neighbourhoods",
    "hull_support",
    "HULL_DIRECTIONS",
    "relative_neighbourhood_brute",
    "relative_neighbourhood_delaunay",
    "urquhart_delaunay",
    "delaunay_neighbours",
    "MAX_NEIGHBOURS",
    "NEAREST",
    "RELATIVE",
    "URQUHART",
]

MAX_NEIGHBOURS = 8
"""Room per source for V(s). Two relative neighbours of s subtend at least 60 degrees at s (else the
farther lies in the lune of the nearer), so |V(s)| <= 6; the Urquhart set keeps the same property."""

NEAREST, RELATIVE, URQUHART = 0, 1, 2
"""Neighbourhood kinds: the closest node (open patterns), the exact relative neighbourhood and the
Urquhart approximation (closed patterns)."""

_POLY = 256  # vertices of the clipped region C (a Voronoi cell has a handful)
HULL_DIRECTIONS = 32
"""Directions of the support half-planes around the nodes' convex hull (C's starting polygon)."""
_HULL_DIRS = np.array([[math.cos(2 * math.pi * k / HULL_DIRECTIONS), math.sin(2 * math.pi * k / HULL_DIRECTIONS)]
                       for k in range(HULL_DIRECTIONS)])
_HULL_DIRS[::HULL_DIRECTIONS // 4] = np.round(_HULL_DIRS[::HULL_DIRECTIONS // 4])
_TOL = 1e-9  # relative slack of the region tests (the exact test decides)


class Grid(NamedTuple):
    """A uniform grid of points (cell lists). Point ``i`` is in the list of its cell: ``head[c]``
    is the last point inserted in cell ``c``, ``nxt[i]`` the one before it (-1 ends a list).
    Cells are ``h`` wide, ``nx * ny`` of them from the corner ``(ox, oy)``; points outside lie in
    the border cells (distances bounds stay valid: they are only farther)."""

    head: np.ndarray  # (nx * ny,) int64
    nxt: np.ndarray  # (cap,) int64
    geom: np.ndarray  # (5,) float64: ox, oy, h, nx, ny


def make_grid(lo, hi, h: float, cap: int, max_cells: int = 1 << 20) -> Grid:
    """An empty grid over the box [lo, hi] (2-vectors) with cells of about ``h`` (larger when the
    box would need more than ``max_cells``), for up to ``cap`` points."""
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.asarray(hi, dtype=np.float64)
    ext = np.maximum(hi - lo, 1e-12)
    h = float(h)
    if (ext[0] / h) * (ext[1] / h) > max_cells:
        h = math.sqrt(ext[0] * ext[1] / max_cells) * 1.0001
    nx = max(1, int(math.ceil(ext[0] / h)))
    ny = max(1, int(math.ceil(ext[1] / h)))
    return Grid(np.full(nx * ny, -1, np.int64), np.full(max(cap, 1), -1, np.int64),
                np.array([lo[0], lo[1], h, nx, ny], dtype=np.float64))


@njit(cache=True)
def _cell_of(x, y, geom):
    """Integer cell coordinates of (x, y), not clamped."""
    return np.int64(math.floor((x - geom[0]) / geom[2])), np.int64(math.floor((y - geom[1]) / geom[2]))


@njit(cache=True)
def _clamped(ix, iy, geom):
    nx, ny = np.int64(geom[3]), np.int64(geom[4])
    return min(max(ix, 0), nx - 1) + nx * min(max(iy, 0), ny - 1)


@njit(cache=True)
def grid_insert(grid, pos, i_from, i_to):
    """Insert points ``i_from:i_to`` of ``pos`` (n, 2) into ``grid`` (in order)."""
    head, nxt, geom = grid.head, grid.nxt, grid.geom
    for i in range(i_from, i_to):
        ix, iy = _cell_of(pos[i, 0], pos[i, 1], geom)
        c = _clamped(ix, iy, geom)
        nxt[i] = head[c]
        head[c] = i


@njit(cache=True)
def grid_insert_idx(grid, pos, idx):
    """Insert the points ``idx`` of ``pos`` into ``grid`` (in order)."""
    head, nxt, geom = grid.head, grid.nxt, grid.geom
    for k in range(idx.shape[0]):
        i = idx[k]
        ix, iy = _cell_of(pos[i, 0], pos[i, 1], geom)
        c = _clamped(ix, iy, geom)
        nxt[i] = head[c]
        head[c] = i


@njit(cache=True)
def grid_rebuild(grid, pos, idx):
    """Empty ``grid`` and insert the points ``idx`` of ``pos``."""
    grid.head[:] = -1
    head, nxt, geom = grid.head, grid.nxt, grid.geom
    for k in range(idx.shape[0]):
        i = idx[k]
        ix, iy = _cell_of(pos[i, 0], pos[i, 1], geom)
        c = _clamped(ix, iy, geom)
        nxt[i] = head[c]
        head[c] = i


@njit(cache=True)
def grid_remove_cells(grid, pos, idx):
    """Empty the cells that hold points ``idx`` (cheaper than clearing every cell)."""
    for k in range(idx.shape[0]):
        i = idx[k]
        ix, iy = _cell_of(pos[i, 0], pos[i, 1], grid.geom)
        grid.head[_clamped(ix, iy, grid.geom)] = -1


@njit(cache=True)
def _ring_cells(cx, cy, r, nx, ny, out):
    """Cells at Chebyshev distance ``r`` from (cx, cy) inside the grid, into ``out``; returns the
    count (cells in x-major order of the ring's rows)."""
    k = 0
    if r == 0:
        if 0 <= cx < nx and 0 <= cy < ny:
            out[0] = cx + nx * cy
            return 1
        return 0
    for iy in (cy - r, cy + r):
        if 0 <= iy < ny:
            for ix in range(max(cx - r, 0), min(cx + r, nx - 1) + 1):
                out[k] = ix + nx * iy
                k += 1
    for iy in range(max(cy - r + 1, 0), min(cy + r - 1, ny - 1) + 1):
        for ix in (cx - r, cx + r):
            if 0 <= ix < nx:
                out[k] = ix + nx * iy
                k += 1
    return k


@njit(cache=True)
def _ring_limit(cx, cy, nx, ny):
    """The ring beyond which no cell of the grid lies."""
    return max(max(cx, nx - 1 - cx), max(cy, ny - 1 - cy)) + 1


@njit(cache=True)
def _ring_start(cx, cy, nx, ny):
    """The first ring that holds a cell of the grid (0 when (cx, cy) is in the grid)."""
    return max(max(-cx, cx - (nx - 1)), max(max(-cy, cy - (ny - 1)), 0))


@njit(cache=True)
def _nearest_one(x, y, pos, n_nodes, grid, cells):
    """Index and squared distance of the node nearest to (x, y) (lowest index among equals).

    Rings of cells around (x, y) while they are cheaper than a scan of every node: a node beyond
    ring r is at least r h away (every node lies inside the grid box)."""
    geom = grid.geom
    h = geom[2]
    nx, ny = np.int64(geom[3]), np.int64(geom[4])
    cx, cy = _cell_of(x, y, geom)
    best, bi = np.inf, np.int64(-1)
    limit = _ring_limit(cx, cy, nx, ny)
    scanned = 0
    r = _ring_start(cx, cy, nx, ny)
    while r <= limit:
        m = _ring_cells(cx, cy, r, nx, ny, cells)
        scanned += m
        for j in range(m):
            v = grid.head[cells[j]]
            while v >= 0:
                d2 = (pos[v, 0] - x) ** 2 + (pos[v, 1] - y) ** 2
                if d2 < best or (d2 == best and v < bi):
                    best, bi = d2, v
                v = grid.nxt[v]
        if bi >= 0 and (best < (r * h) ** 2 or r == limit):
            return bi, best
        if scanned > 4 * n_nodes + 64:
            break
        r += 1
    best, bi = np.inf, np.int64(-1)
    for v in range(n_nodes):
        d2 = (pos[v, 0] - x) ** 2 + (pos[v, 1] - y) ** 2
        if d2 < best:
            best, bi = d2, v
    return bi, best


@njit(cache=True)
def nearest_incremental(src_pos, src_idx, near, near_d2, pos, n_from, n_nodes, grid, out, out_n):
    """The nearest node of each source (open patterns, fig. 4.10b), kept up to date: a source with a nearest node (``near[s]`` >= 0, found
    among the nodes ``0:n_from``) only compares the nodes ``n_from:n_nodes`` added since (nodes do
    not move); one without gets a full search. The same answer as a full search (the lowest index
    among equals: older nodes have lower indices). Row j of ``out`` gets source ``src_idx[j]``'s."""
    nx, ny = np.int64(grid.geom[3]), np.int64(grid.geom[4])
    cells = np.empty(8 * (nx + ny) + 8, np.int64)
    for j in range(src_idx.shape[0]):
        s = src_idx[j]
        x, y = src_pos[s, 0], src_pos[s, 1]
        if near[s] < 0:
            near[s], near_d2[s] = _nearest_one(x, y, pos, n_nodes, grid, cells)
        else:
            best, bi = near_d2[s], near[s]
            for v in range(n_from, n_nodes):
                d2 = (pos[v, 0] - x) ** 2 + (pos[v, 1] - y) ** 2
                if d2 < best:
                    best, bi = d2, v
            near[s], near_d2[s] = bi, best
        out[j, 0] = near[s]
        out_n[j] = 1


# --------------------------------------------------------------------------------------------
# the region C: a convex polygon in coordinates relative to s, clipped by bisector half-planes


@njit(cache=True)
def _clip(px, py, po, m, a, b, c, owner, qx, qy, qo):
    """Clip the convex polygon (px, py)[:m] (counter-clockwise; ``po[i]`` owns edge i -> i+1) by
    a x + b y <= c; the result into (qx, qy, qo), returns its vertex count. The new edge along the
    line is owned by ``owner``."""
    k = 0
    for i in range(m):
        j = i + 1 if i + 1 < m else 0
        fi = a * px[i] + b * py[i] - c
        fj = a * px[j] + b * py[j] - c
        if fi <= 0.0:
            qx[k], qy[k], qo[k] = px[i], py[i], po[i]
            k += 1
            if fj > 0.0:
                t = fi / (fi - fj)
                qx[k], qy[k], qo[k] = px[i] + t * (px[j] - px[i]), py[i] + t * (py[j] - py[i]), owner
                k += 1
        elif fj <= 0.0:
            t = fi / (fi - fj)
            qx[k], qy[k], qo[k] = px[i] + t * (px[j] - px[i]), py[i] + t * (py[j] - py[i]), po[i]
            k += 1
        if k >= px.shape[0] - 1:
            break
    return k


@njit(cache=True)
def _exact_rn(v, d2v, sx, sy, pos, cand, n_cand, cand_d2):
    """Eq. 4.1 for node v against the nodes ``cand[:n_cand]`` (every node with |u - s| <= |v - s|
    is among them): True when no u != v has |u - s|^2 <= |v - s|^2 and |v - u|^2 <= |v - s|^2."""
    vx, vy = pos[v, 0], pos[v, 1]
    for k in range(n_cand):
        u = cand[k]
        if u == v or cand_d2[k] > d2v:
            continue
        if (vx - pos[u, 0]) ** 2 + (vy - pos[u, 1]) ** 2 <= d2v:
            return False
    return True


@njit(cache=True)
def _sort_pending(ids, d2, a, b):
    """Sort ids[a:b], d2[a:b] by (d2, id): insertion sort for a ring's few nodes, a merge sort
    (then ties by id) for many."""
    if b - a > 48:
        order = np.argsort(d2[a:b], kind="mergesort")
        si = ids[a:b][order].copy()
        sd = d2[a:b][order].copy()
        ids[a:b] = si
        d2[a:b] = sd
    for i in range(a + 1, b):
        ki, kd = ids[i], d2[i]
        j = i - 1
        while j >= a and (d2[j] > kd or (d2[j] == kd and ids[j] > ki)):
            ids[j + 1] = ids[j]
            d2[j + 1] = d2[j]
            j -= 1
        ids[j + 1] = ki
        d2[j + 1] = kd


@njit(cache=True)
def _neighbourhood_one(sx, sy, pos, n_nodes, grid, sup, kind, cells, ids, dd, mark, stamp, poly, out):
    """V(s) (kind RELATIVE) or the Urquhart set (kind URQUHART) of the source at (sx, sy) among
    the nodes ``0:n_nodes``; into ``out`` (nearest first), returns the count.

    ``sup`` (HULL_DIRECTIONS,): support values (:func:`hull_support`, padded; for URQUHART
    including s) whose half-planes hold every node: C starts as their intersection. ``ids``,
    ``dd``: room for every node; ``mark``: per node, ``stamp`` once processed; ``poly``:
    (6, _POLY) scratch. Every node lies inside the grid box.
    """
    geom = grid.geom
    h = geom[2]
    nx, ny = np.int64(geom[3]), np.int64(geom[4])
    cx, cy = _cell_of(sx, sy, geom)
    limit = _ring_limit(cx, cy, nx, ny)
    px, py, po, qx, qy, qo = poly[0], poly[1], poly[2], poly[3], poly[4], poly[5]
    # C starts as the polygon of the support half-planes, counter-clockwise, relative to s
    K = sup.shape[0]
    x0, x1 = -sup[K // 2] - sx, sup[0] - sx
    y0, y1 = -sup[3 * K // 4] - sy, sup[K // 4] - sy
    px[0], py[0] = x0, y0
    px[1], py[1] = x1, y0
    px[2], py[2] = x1, y1
    px[3], py[3] = x0, y1
    for i in range(4):
        po[i] = -1.0
    m = 4
    hulled = False  # the oblique support half-planes are applied when the box is not enough
    scale = abs(x1 - x0) + abs(y1 - y0) + abs(sx) + abs(sy) + 1e-300
    n_coll = 0  # nodes collected: ids[:n_coll]; the first n_done processed, nearest first
    n_done = 0
    n_out = 0
    scanned = 0
    r = _ring_start(cx, cy, nx, ny)
    everything = False
    while True:
        # collect ring r, or every node not yet processed when rings cost more than a scan
        if r > limit or scanned > 4 * n_nodes + 64:
            everything = True
            n_coll = n_done
            for v in range(n_nodes):
                if mark[v] != stamp:
                    ids[n_coll] = v
                    dd[n_coll] = (pos[v, 0] - sx) ** 2 + (pos[v, 1] - sy) ** 2
                    n_coll += 1
            r_safe2 = np.inf
        else:
            mc = _ring_cells(cx, cy, r, nx, ny, cells)
            scanned += mc
            for j in range(mc):
                v = grid.head[cells[j]]
                while v >= 0:
                    ids[n_coll] = v
                    dd[n_coll] = (pos[v, 0] - sx) ** 2 + (pos[v, 1] - sy) ** 2
                    n_coll += 1
                    v = grid.nxt[v]
            # a node beyond ring r is at least r h away
            r_safe2 = np.inf if r == limit else (r * h) ** 2
        # process the collected nodes closer than that, nearest first
        _sort_pending(ids, dd, n_done, n_coll)
        while n_done < n_coll and dd[n_done] < r_safe2:
            if everything and n_done % 16 == 0 and m >= 3:
                # every node left is at least this far: stop once C lies inside that radius
                rmax2 = 0.0
                for i in range(m):
                    rmax2 = max(rmax2, px[i] * px[i] + py[i] * py[i])
                if kind == URQUHART:
                    rmax2 *= 4.0
                if rmax2 * (1.0 + 1e-6) < dd[n_done]:
                    break
            v = ids[n_done]
            d2v = dd[n_done]
            mark[v] = stamp
            dx, dy = pos[v, 0] - sx, pos[v, 1] - sy
            if kind == RELATIVE and m >= 3 and n_out < MAX_NEIGHBOURS:
                # in C (with slack)? then eq. 4.1 decides
                inside = True
                tol = _TOL * scale * (math.sqrt(d2v) + scale)
                for i in range(m):
                    j = i + 1 if i + 1 < m else 0
                    ex, ey = px[j] - px[i], py[j] - py[i]
                    if ex * (dy - py[i]) - ey * (dx - px[i]) < -tol:
                        inside = False
                        break
                if inside and _exact_rn(v, d2v, sx, sy, pos, ids, n_coll, dd):
                    out[n_out] = v
                    n_out += 1
            if d2v > 0.0 and m >= 3:
                # C := C ∩ {x : x.(v - s) <= |v - s|^2 / 2}, with slack (C only grows)
                cc = 0.5 * d2v + _TOL * scale * (math.sqrt(d2v) + scale)
                m = _clip(px, py, po, m, dx, dy, cc, float(v), qx, qy, qo)
                for i in range(m):
                    px[i], py[i], po[i] = qx[i], qy[i], qo[i]
            n_done += 1
        if everything:
            break
        # stop when no unvisited node can lie in C (URQUHART: can still cut C)
        rmax2 = 0.0
        for i in range(m):
            rmax2 = max(rmax2, px[i] * px[i] + py[i] * py[i])
        if kind == URQUHART:
            rmax2 *= 4.0
        if not (m < 3 or rmax2 * (1.0 + 1e-6) < r_safe2) and not hulled and r >= 3:
            hulled = True
            for k in range(K):
                if k % (K // 4) != 0 and m >= 3:
                    a, b = _HULL_DIRS[k, 0], _HULL_DIRS[k, 1]
                    m = _clip(px, py, po, m, a, b, sup[k] - a * sx - b * sy, -1.0, qx, qy, qo)
                    for i in range(m):
                        px[i], py[i], po[i] = qx[i], qy[i], qo[i]
            rmax2 = 0.0
            for i in range(m):
                rmax2 = max(rmax2, px[i] * px[i] + py[i] * py[i])
            if kind == URQUHART:
                rmax2 *= 4.0
        if m < 3 or rmax2 * (1.0 + 1e-6) < r_safe2:
            break
        r += 1
    if kind == URQUHART:
        # the Delaunay neighbours: owners of C's edges, each tested against the others
        nd = 0
        for i in range(m):
            if po[i] >= 0.0:
                v = np.int64(po[i])
                dup = False
                for k in range(nd):
                    if np.int64(qx[k]) == v:
                        dup = True
                        break
                if not dup:
                    qx[nd] = float(v)
                    nd += 1
        for a in range(nd):
            v = np.int64(qx[a])
            d2v = (pos[v, 0] - sx) ** 2 + (pos[v, 1] - sy) ** 2
            ok = True
            for b in range(nd):
                u = np.int64(qx[b])
                if u == v:
                    continue
                d2u = (pos[u, 0] - sx) ** 2 + (pos[u, 1] - sy) ** 2
                if d2u <= d2v and (pos[v, 0] - pos[u, 0]) ** 2 + (pos[v, 1] - pos[u, 1]) ** 2 <= d2v:
                    ok = False
                    break
            if ok and n_out < MAX_NEIGHBOURS:
                out[n_out] = v
                n_out += 1
        _sort_by_distance(out, n_out, pos, sx, sy)
    return n_out


@njit(cache=True)
def _sort_by_distance(out, n, pos, sx, sy):
    """Sort out[:n] by (distance from (sx, sy), index)."""
    for i in range(1, n):
        v = out[i]
        d2v = (pos[v, 0] - sx) ** 2 + (pos[v, 1] - sy) ** 2
        j = i - 1
        while j >= 0:
            u = out[j]
            d2u = (pos[u, 0] - sx) ** 2 + (pos[u, 1] - sy) ** 2
            if d2u > d2v or (d2u == d2v and u > v):
                out[j + 1] = u
                j -= 1
            else:
                break
        out[j + 1] = v


@njit(cache=True)
def hull_support(pos, i_from, i_to, sup):
    """Raise ``sup`` (HULL_DIRECTIONS,) to the support values max n_k . p of points
    ``pos[i_from:i_to]`` (start from -inf): the half-planes n_k . x <= sup_k hold every point, and
    their intersection is a polygon around the points' convex hull."""
    for i in range(i_from, i_to):
        for k in range(_HULL_DIRS.shape[0]):
            v = _HULL_DIRS[k, 0] * pos[i, 0] + _HULL_DIRS[k, 1] * pos[i, 1]
            if v > sup[k]:
                sup[k] = v


@njit(cache=True)
def relative_neighbourhoods(src_pos, src_idx, pos, n_nodes, grid, kind, support, out, out_n):
    """Neighbourhoods of the sources ``src_idx`` among the nodes ``pos[:n_nodes]``.

    ``kind``: NEAREST (the closest node), RELATIVE (eq. 4.1) or URQUHART. ``support``: the nodes'
    :func:`hull_support`. Row ``j`` of ``out`` (k, MAX_NEIGHBOURS) gets the neighbours of source
    ``src_idx[j]`` nearest first, ``out_n[j]`` their count (0 when there are no nodes).
    """
    if n_nodes == 0:
        out_n[:] = 0
        return
    nx, ny = np.int64(grid.geom[3]), np.int64(grid.geom[4])
    cells = np.empty(8 * (nx + ny) + 8, np.int64)
    ids = np.empty(n_nodes + 8, np.int64)
    dd = np.empty(n_nodes + 8)
    mark = np.full(n_nodes, -1, np.int64)
    poly = np.empty((6, _POLY))
    K = _HULL_DIRS.shape[0]
    sup = np.empty(K)
    ext = support[0] + support[K // 2] + support[K // 4] + support[3 * K // 4]
    row = np.empty(MAX_NEIGHBOURS, np.int64)
    for j in range(src_idx.shape[0]):
        s = src_idx[j]
        sx, sy = src_pos[s, 0], src_pos[s, 1]
        if kind == NEAREST:
            v, _ = _nearest_one(sx, sy, pos, n_nodes, grid, cells)
            out[j, 0] = v
            out_n[j] = 1
            continue
        pad = 1e-6 * (abs(ext) + abs(sx) + abs(sy)) + 1e-12
        for k in range(K):
            sup[k] = support[k] + pad
            if kind == URQUHART:
                sup[k] = max(sup[k], _HULL_DIRS[k, 0] * sx + _HULL_DIRS[k, 1] * sy + pad)
        n = _neighbourhood_one(sx, sy, pos, n_nodes, grid, sup, kind, cells, ids, dd, mark, j, poly, row)
        out_n[j] = n
        for k in range(n):
            out[j, k] = row[k]


def neighbourhoods(src_pos, nodes, kind=RELATIVE, h: float | None = None) -> list[np.ndarray]:
    """Neighbourhoods of every source (k, 2) among ``nodes`` (n, 2), through a fresh grid (cells
    of ``h``, default about the mean node spacing): a list of index arrays, nearest first."""
    src = np.ascontiguousarray(src_pos, dtype=np.float64).reshape(-1, 2)
    p = np.ascontiguousarray(nodes, dtype=np.float64).reshape(-1, 2)
    n = len(p)
    if n == 0:
        return [np.zeros(0, np.int64) for _ in range(len(src))]
    lo, hi = p.min(0), p.max(0)
    if h is None:
        h = max(float(np.max(hi - lo)) / math.sqrt(n), 1e-9 * (1.0 + float(np.abs(p).max())))
    g = make_grid(lo - h, hi + h, h, n)
    grid_insert(g, p, 0, n)
    sup = np.full(HULL_DIRECTIONS, -np.inf)
    hull_support(p, 0, n, sup)
    out = np.zeros((len(src), MAX_NEIGHBOURS), np.int64)
    cnt = np.zeros(len(src), np.int64)
    relative_neighbourhoods(src, np.arange(len(src), dtype=np.int64), p, n, g, kind, sup, out, cnt)
    return [out[j, :cnt[j]].copy() for j in range(len(src))]


# --------------------------------------------------------------------------------------------
# references (tests)


def relative_neighbourhood_brute(s, nodes) -> np.ndarray:
    """V(s) by eq. 4.1 over every pair (O(n^2)): indices into ``nodes`` (n, 2), nearest first."""
    s = np.asarray(s, dtype=np.float64)
    p = np.asarray(nodes, dtype=np.float64).reshape(-1, 2)
    d2s = (p[:, 0] - s[0]) ** 2 + (p[:, 1] - s[1]) ** 2
    out = []
    for v in range(len(p)):
        d2vu = (p[:, 0] - p[v, 0]) ** 2 + (p[:, 1] - p[v, 1]) ** 2
        blocked = (d2s <= d2s[v]) & (d2vu <= d2s[v])
        blocked[v] = False
        if not blocked.any():
            out.append(v)
    out = np.array(out, dtype=np.int64)
    return out[np.lexsort((out, d2s[out]))] if len(out) else out


def delaunay_neighbours(s, nodes) -> np.ndarray:
    """Indices of the Delaunay neighbours of ``s`` in the triangulation of ``nodes`` ∪ {s} (scipy;
    Qhull's ``QJ`` is not used, so degenerate sets raise)."""
    from scipy.spatial import Delaunay

    p = np.vstack([np.asarray(nodes, dtype=np.float64).reshape(-1, 2), np.asarray(s, dtype=np.float64)[None]])
    tri = Delaunay(p)
    indptr, indices = tri.vertex_neighbor_vertices
    k = len(p) - 1
    return np.sort(indices[indptr[k]:indptr[k + 1]]).astype(np.int64)


def relative_neighbourhood_delaunay(s, nodes) -> np.ndarray:
    """V(s) as the thesis computes it (sec. 4.4.2): the Delaunay neighbours of s in A_s (scipy),
    each checked against every node by eq. 4.1. Nearest first."""
    s = np.asarray(s, dtype=np.float64)
    p = np.asarray(nodes, dtype=np.float64).reshape(-1, 2)
    d2s = (p[:, 0] - s[0]) ** 2 + (p[:, 1] - s[1]) ** 2
    out = []
    for v in delaunay_neighbours(s, p):
        d2vu = (p[:, 0] - p[v, 0]) ** 2 + (p[:, 1] - p[v, 1]) ** 2
        blocked = (d2s <= d2s[v]) & (d2vu <= d2s[v])
        blocked[v] = False
        if not blocked.any():
            out.append(v)
    out = np.array(out, dtype=np.int64)
    return out[np.lexsort((out, d2s[out]))] if len(out) else out


def urquhart_delaunay(s, nodes) -> np.ndarray:
    """Urquhart's approximation as the thesis describes it (sec. 4.4.2): the Delaunay neighbours of
    s (scipy) tested only against each other by eq. 4.1. Nearest first."""
    s = np.asarray(s, dtype=np.float64)
    p = np.asarray(nodes, dtype=np.float64).reshape(-1, 2)
    dn = delaunay_neighbours(s, p)
    d2s = (p[:, 0] - s[0]) ** 2 + (p[:, 1] - s[1]) ** 2
    out = []
    for v in dn:
        others = dn[dn != v]
        d2vu = (p[others, 0] - p[v, 0]) ** 2 + (p[others, 1] - p[v, 1]) ** 2
        if not np.any((d2s[others] <= d2s[v]) & (d2vu <= d2s[v])):
            out.append(v)
    out = np.array(out, dtype=np.int64)
    return out[np.lexsort((out, d2s[out]))] if len(out) else out
