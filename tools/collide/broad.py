"""Broad phase: candidate pairs of overlapping boxes on a hashed uniform grid (thesis 4.2.1).

The thesis's collision lattice (app. C.1 keys ``origin``, ``dimensions``, ``divisions``) is a
uniform grid over the scene; here the grid is unbounded and hashed (Teschner et al. 2003, spatial
hashing), so geometry outside the lattice box is still found: the lattice keys only choose the
cell size (:func:`lattice_cell_size`). Each element is given its axis-aligned box (swept over the
step for continuous detection: the box of its positions at t = 0 and t = 1, grown by a pad);
boxes of one set are inserted into every cell they overlap, the other set's boxes look up their
cells. A pair found in several cells is reported once: only in the cell that holds the minimum
corner of the two boxes' intersection. Output pairs are sorted, so the result does not depend on
thread timing; two passes (count, then fill) over the queries run in parallel.

Boxes are ``(k, 6) float64`` rows ``[min_x, min_y, min_z, max_x, max_y, max_z]``.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

__all__ = [
    "vertex_boxes",
    "edge_boxes",
    "triangle_boxes",
    "box_pairs",
    "box_pairs_brute",
    "BoxGrid",
    "PARTS_ANY",
    "PARTS_SAME",
    "PARTS_CROSS",
    "lattice_cell_size",
    "parts_grouped",
]


@njit(cache=True)
def vertex_boxes(x0, x1, pad):
    """(n, 6): box of every vertex's segment from ``x0`` to ``x1``, grown by ``pad``."""
    n = x0.shape[0]
    out = np.empty((n, 6))
    for i in range(n):
        for d in range(3):
            out[i, d] = min(x0[i, d], x1[i, d]) - pad
            out[i, d + 3] = max(x0[i, d], x1[i, d]) + pad
    return out


@njit(cache=True, inline="always")
def _element_range(x0, x1, indices, e, d):
    """Smallest and largest coordinate ``d`` of element ``e``'s vertices (row ``e`` of
    ``indices``) at t = 0 and t = 1."""
    lo = np.inf
    hi = -np.inf
    for k in range(indices.shape[1]):
        v = indices[e, k]
        lo = min(lo, x0[v, d], x1[v, d])
        hi = max(hi, x0[v, d], x1[v, d])
    return lo, hi


@njit(cache=True)
def _element_boxes(x0, x1, indices, pad):
    """(k, 6): box of each element's vertices (a row of ``indices``) at t = 0 and t = 1, grown by ``pad``."""
    n = indices.shape[0]
    out = np.empty((n, 6))
    for e in range(n):
        for d in range(3):
            lo, hi = _element_range(x0, x1, indices, e, d)
            out[e, d] = lo - pad
            out[e, d + 3] = hi + pad
    return out


def edge_boxes(x0, x1, edge_indices, pad):
    """(e, 6): box of each edge's two vertices at t = 0 and t = 1, grown by ``pad``."""
    return _element_boxes(x0, x1, edge_indices, pad)


def triangle_boxes(x0, x1, tri_indices, pad):
    """(m, 6): box of each triangle's three vertices at t = 0 and t = 1, grown by ``pad``."""
    return _element_boxes(x0, x1, tri_indices, pad)


#: the hashed grid's cell is at most this many mean element extents (:func:`lattice_cell_size`)
MAX_CELL_EXTENTS = 5.0


def lattice_cell_size(lattice, bounds_min, bounds_max, boxes) -> float:
    """Cell size of the hashed grid from the collision lattice keys (app. C.1).

    With ``auto_bounds`` the lattice box is the geometry's bounding box times ``size_multiply``
    (a cube of its largest side with ``make_cube``), else ``dimensions``; the cell is the box over
    ``divisions``, largest axis. It is never taken below the mean box extent of the elements
    (smaller cells only multiply the cells each element visits), nor above ``MAX_CELL_EXTENTS``
    times it (coarser cells only multiply the candidate pairs of each cell: on the final yarrow,
    whose lattice box is the whole corymb, the lattice's cell is 8.8 x the mean extent, and capping
    it at 5 x made its canopy stage 10 % faster with the same frames; the broad phase is exact, so
    the cell size never changes a result).
    """
    lo = np.asarray(bounds_min, float)
    hi = np.asarray(bounds_max, float)
    if lattice.auto_bounds:
        dims = (hi - lo) * np.asarray(lattice.size_multiply, float)
        if lattice.make_cube:
            dims = np.full(3, dims.max())
    else:
        dims = np.asarray(lattice.dimensions, float)
    cell = float(np.max(dims / np.asarray(lattice.divisions, float)))
    mean = _mean_extent(boxes)
    return min(max(cell, mean), MAX_CELL_EXTENTS * mean)


def _mean_extent(boxes) -> float:
    if len(boxes) == 0:
        return 1.0
    ext = (boxes[:, 3:] - boxes[:, :3]).max(axis=1)
    m = float(ext.mean())
    return m if m > 0 else 1.0


@njit(cache=True, inline="always")
def _hash(ix, iy, iz, mask):
    h = (ix * np.int64(73856093)) ^ (iy * np.int64(19349663)) ^ (iz * np.int64(83492791))
    return h & mask


@njit(cache=True, inline="always")
def _cell(v, o, inv):
    return np.int64(math.floor((v - o) * inv))


@njit(cache=True)
def _build(boxes, origin, inv):
    """Hash every box into the cells it overlaps. Returns ``starts`` (bucket offsets), and per
    entry, in bucket order: the element, its cell key and a copy of its box (so that a query scans
    a bucket's entries in contiguous memory), and the hash mask."""
    n = boxes.shape[0]
    total = 0
    lo = np.full(3, np.iinfo(np.int64).max)
    hi = np.full(3, np.iinfo(np.int64).min)
    for i in range(n):
        c = 1
        for d in range(3):
            a = _cell(boxes[i, d], origin[d], inv)
            b = _cell(boxes[i, d + 3], origin[d], inv)
            c *= b - a + 1
            lo[d] = min(lo[d], a)
            hi[d] = max(hi[d], b)
        total += c
    # buckets for the cells, not the entries: many boxes share a cell (the 100k benchmark canopy's
    # edges: 310k entries in some 40k cells of the lattice), and a table sized by the entries
    # (2^20 buckets there) spends its time zeroing, summing and missing the cache
    cells = total
    if n:
        span = 1.0
        for d in range(3):
            span *= float(hi[d] - lo[d] + 1)
        cells = min(total, np.int64(min(span, 1e15)))
    size = 1
    while size < 2 * cells:
        size *= 2
    mask = np.int64(size - 1)
    counts = np.zeros(size + 1, np.int64)
    for i in range(n):
        lx = _cell(boxes[i, 0], origin[0], inv)
        ly = _cell(boxes[i, 1], origin[1], inv)
        lz = _cell(boxes[i, 2], origin[2], inv)
        hx = _cell(boxes[i, 3], origin[0], inv)
        hy = _cell(boxes[i, 4], origin[1], inv)
        hz = _cell(boxes[i, 5], origin[2], inv)
        for ix in range(lx, hx + 1):
            for iy in range(ly, hy + 1):
                for iz in range(lz, hz + 1):
                    counts[_hash(ix, iy, iz, mask) + 1] += 1
    for h in range(size):
        counts[h + 1] += counts[h]
    fill = counts[:-1].copy()
    elem = np.empty(total, np.int32)
    key = np.empty(total, np.int64)
    ebox = np.empty((total, 6))
    for i in range(n):
        lx = _cell(boxes[i, 0], origin[0], inv)
        ly = _cell(boxes[i, 1], origin[1], inv)
        lz = _cell(boxes[i, 2], origin[2], inv)
        hx = _cell(boxes[i, 3], origin[0], inv)
        hy = _cell(boxes[i, 4], origin[1], inv)
        hz = _cell(boxes[i, 5], origin[2], inv)
        for ix in range(lx, hx + 1):
            for iy in range(ly, hy + 1):
                for iz in range(lz, hz + 1):
                    h = _hash(ix, iy, iz, mask)
                    k = fill[h]
                    elem[k] = i
                    key[k] = _key(ix, iy, iz)
                    for d in range(6):
                        ebox[k, d] = boxes[i, d]
                    fill[h] = k + 1
    return counts, elem, key, ebox, mask


@njit(cache=True, inline="always")
def _key(ix, iy, iz):
    """The cell as one int64 (21 bits an axis, wrapping): two cells may share a key only when
    2^21 cells apart, and a wrong match is then rejected by the exact box test."""
    m = np.int64(0x1FFFFF)
    return ((ix & m) << np.int64(42)) | ((iy & m) << np.int64(21)) | (iz & m)


@njit(cache=True, inline="always")
def _overlap(a, i, b, j):
    for d in range(3):
        if a[i, d] > b[j, d + 3] or b[j, d] > a[i, d + 3]:
            return False
    return True


#: part filters of the grid queries (:class:`BoxGrid`)
PARTS_ANY = 0
PARTS_SAME = 1
PARTS_CROSS = 2


@njit(cache=True)
def _query_one(a, boxes_a, same, skip_b, verts_a, verts_b, part_a, part_b, mode, origin,
               inv, starts, elem, key, ebox, mask, out, base, limit):
    """Count query ``a``'s pairs; write them at ``out[base:]`` while below row ``limit``.

    ``mode`` filters by part (``part_a[a]``, ``part_b[b]``): :data:`PARTS_ANY` none,
    :data:`PARTS_SAME` pairs within one part only, :data:`PARTS_CROSS` pairs of two parts only."""
    lx = _cell(boxes_a[a, 0], origin[0], inv)
    ly = _cell(boxes_a[a, 1], origin[1], inv)
    lz = _cell(boxes_a[a, 2], origin[2], inv)
    hx = _cell(boxes_a[a, 3], origin[0], inv)
    hy = _cell(boxes_a[a, 4], origin[1], inv)
    hz = _cell(boxes_a[a, 5], origin[2], inv)
    n = 0
    for ix in range(lx, hx + 1):
        for iy in range(ly, hy + 1):
            for iz in range(lz, hz + 1):
                h = _hash(ix, iy, iz, mask)
                ck = _key(ix, iy, iz)
                for k in range(starts[h], starts[h + 1]):
                    if key[k] != ck:
                        continue
                    b = elem[k]
                    # first: in a same-set query half the entries are earlier elements (a prefix
                    # of each bucket, which _build fills in element order), rejected without
                    # reading their boxes: the edges' round-0 query of the 100k benchmark canopy's
                    # last frame about 30 % faster, the same pairs (bisecting the prefix: no faster)
                    if same and b <= a:
                        continue
                    if mode != PARTS_ANY and (part_a[a] == part_b[b]) != (mode == PARTS_SAME):
                        continue
                    if not _overlap(boxes_a, a, ebox, k):
                        continue
                    if skip_b.shape[0] and skip_b[b]:
                        continue
                    # report once: in the cell of the intersection box's minimum corner
                    if _cell(max(boxes_a[a, 0], ebox[k, 0]), origin[0], inv) != ix:
                        continue
                    if _cell(max(boxes_a[a, 1], ebox[k, 1]), origin[1], inv) != iy:
                        continue
                    if _cell(max(boxes_a[a, 2], ebox[k, 2]), origin[2], inv) != iz:
                        continue
                    if verts_a.shape[0] and _share_vertex(verts_a, a, verts_b, b):
                        continue
                    if base + n < limit:
                        out[base + n, 0] = a
                        out[base + n, 1] = b
                    n += 1
    return n


@njit(cache=True, inline="always")
def _sort_partners(out, base, n):
    """Sort one query's partners ``out[base:base+n, 1]`` (few: insertion sort), so the output is in
    (a, b) order without a global sort."""
    for i in range(base + 1, base + n):
        b = out[i, 1]
        j = i - 1
        while j >= base and out[j, 1] > b:
            out[j + 1, 1] = out[j, 1]
            j -= 1
        out[j + 1, 1] = b


@njit(cache=True, parallel=True)
def _query(boxes_a, same, skip_b, verts_a, verts_b, part_a, part_b, mode, origin, inv, starts, elem,
           key, ebox, mask):
    """Pairs of every query box with the grid's boxes, in (a, b) order, in one scan.

    The queries are cut into blocks solved in parallel; each writes its pairs into its block's
    slab of a scratch buffer as it finds them; the slabs are then copied out in block order. A
    block whose pairs overflow its slab is redone by counting first.
    """
    na = boxes_a.shape[0]
    nblk = max(1, min(na, 256))
    per = (na + nblk - 1) // nblk
    cap = 8 * per + 64
    buf = np.empty((nblk * cap, 2), np.int32)
    cnt = np.zeros(nblk, np.int64)
    over = np.zeros(nblk, np.bool_)
    dummy = np.empty((0, 2), np.int32)
    for blk in prange(nblk):
        base = blk * cap
        n = 0
        for a in range(blk * per, min(na, (blk + 1) * per)):
            k = _query_one(a, boxes_a, same, skip_b, verts_a, verts_b, part_a, part_b, mode, origin,
                           inv, starts, elem, key, ebox, mask, buf, base + n, base + cap)
            if n + k > cap:
                over[blk] = True
                break
            _sort_partners(buf, base + n, k)
            n += k
        cnt[blk] = n
    for blk in prange(nblk):
        if over[blk]:
            n = 0
            for a in range(blk * per, min(na, (blk + 1) * per)):
                n += _query_one(a, boxes_a, same, skip_b, verts_a, verts_b, part_a, part_b, mode, origin,
                                inv, starts, elem, key, ebox, mask, dummy, 0, 0)
            cnt[blk] = n
    offsets = np.zeros(nblk + 1, np.int64)
    for blk in range(nblk):
        offsets[blk + 1] = offsets[blk] + cnt[blk]
    out = np.empty((offsets[nblk], 2), np.int32)
    for blk in prange(nblk):
        o = offsets[blk]
        if over[blk]:
            for a in range(blk * per, min(na, (blk + 1) * per)):
                k = _query_one(a, boxes_a, same, skip_b, verts_a, verts_b, part_a, part_b, mode, origin,
                               inv, starts, elem, key, ebox, mask, out, o, offsets[blk + 1])
                _sort_partners(out, o, k)
                o += k
        else:
            base = blk * cap
            for i in range(cnt[blk]):
                out[o + i, 0] = buf[base + i, 0]
                out[o + i, 1] = buf[base + i, 1]
    return out


@njit(cache=True)
def _query_serial(boxes_a, same, skip_b, verts_a, verts_b, part_a, part_b, mode, origin, inv, starts,
                  elem, key, ebox, mask):
    """:func:`_query` on one thread (same output): for the few boxes of a retry round, where waking
    the thread pool costs more than the queries (milliseconds on a loaded 2-core machine). Pairs
    are written as found; a query that overflows the buffer is redone after growing it."""
    na = boxes_a.shape[0]
    out = np.empty((max(64, 4 * na), 2), np.int32)
    n = 0
    for a in range(na):
        k = _query_one(a, boxes_a, same, skip_b, verts_a, verts_b, part_a, part_b, mode, origin,
                       inv, starts, elem, key, ebox, mask, out, n, out.shape[0])
        if n + k > out.shape[0]:
            grown = np.empty((max(2 * out.shape[0], n + k), 2), np.int32)
            grown[:n] = out[:n]
            out = grown
            _query_one(a, boxes_a, same, skip_b, verts_a, verts_b, part_a, part_b, mode, origin,
                       inv, starts, elem, key, ebox, mask, out, n, out.shape[0])
        _sort_partners(out, n, k)
        n += k
    return out[:n].copy()


#: below this many query boxes the serial query is used
SERIAL_QUERY_BELOW = 20000


@njit(cache=True)
def _extent(a, b):
    """Common origin (min corner over both box sets) and the largest box side."""
    origin = np.full(3, np.inf)
    span = 0.0
    for boxes in (a, b):
        for i in range(boxes.shape[0]):
            for d in range(3):
                origin[d] = min(origin[d], boxes[i, d])
                span = max(span, boxes[i, d + 3] - boxes[i, d])
    return origin, span


def box_pairs(boxes_a: np.ndarray, boxes_b: np.ndarray | None = None, *,
              cell_size: float | None = None) -> np.ndarray:
    """All pairs of overlapping boxes (closed boxes: touching counts).

    Parameters
    ----------
    boxes_a : (na, 6) float64
    boxes_b : (nb, 6) float64 or None
        None: pairs within ``boxes_a`` (``i < j``).
    cell_size : float or None
        Grid cell edge; None: the mean largest box extent.

    Returns
    -------
    (k, 2) int32
        ``(i, j)``: box i of ``boxes_a`` overlaps box j of ``boxes_b``; sorted, no duplicates.
    """
    a = np.ascontiguousarray(boxes_a, dtype=np.float64).reshape(-1, 6)
    same = boxes_b is None
    b = a if same else np.ascontiguousarray(boxes_b, dtype=np.float64).reshape(-1, 6)
    return _box_pairs(a, b, same, cell_size, True)


def _box_pairs(a, b, same, cell_size, allow_big):
    """:func:`box_pairs` of contiguous box arrays (``allow_big``: pair the big boxes directly)."""
    if len(a) == 0 or len(b) == 0:
        return np.zeros((0, 2), np.int32)
    if cell_size is None or not cell_size > 0:
        cell_size = _mean_extent(b)
    origin, span = _extent(a, b)
    inv = 1.0 / float(cell_size)
    if span * inv > 64.0:
        # boxes spanning more than 64 cells (elements a response moved far, swept over long
        # paths) would visit absurd cell counts: the cell is taken no smaller than the mean box
        # of the two sets
        cell_size = max(float(cell_size), _mean_extent(a), _mean_extent(b))
        inv = 1.0 / cell_size
    if allow_big:
        # the boxes over BIG_BOX_CELLS cells are paired by a grid of their own size (_big_pairs)
        # and the rest by this grid: entered in the grid, each would be met again in every cell of its region by
        # every query there (a squeezed head's swept boxes, 1 % of them across the whole head:
        # 1.2 M pairs found in 2.9 s); where too many are big, the grid takes them all, its cell
        # coarsened to the biggest box if that spans more than 64 (every box then in few, crowded
        # cells)
        big_a = _big_boxes(a, origin, inv, BIG_BOX_CELLS)
        big_b = big_a if same else _big_boxes(b, origin, inv, BIG_BOX_CELLS)
        n_big = int(np.count_nonzero(big_a)) + (0 if same else int(np.count_nonzero(big_b)))
        if n_big and n_big * max(len(a), len(b)) <= BIG_BOX_BUDGET:
            return _pairs_with_big(a, b, same, big_a, big_b, float(cell_size))
    if span * inv > 64.0:
        inv = 64.0 / span
    run = _query_serial if len(a) < SERIAL_QUERY_BELOW else _query
    return run(a, same, _NO_SKIP, _NO_VERTS, _NO_VERTS, _NO_PARTS, _NO_PARTS, PARTS_ANY, origin, inv,
               *_build(b, origin, inv))


@njit(cache=True, inline="always")
def _pair_array(out):
    """(k, 2) int32 from a list of (i, j) tuples (an empty list: shape (0, 2))."""
    res = np.zeros((len(out), 2), np.int32)
    for k in range(len(out)):
        res[k, 0] = out[k][0]
        res[k, 1] = out[k][1]
    return res


#: big boxes times all boxes at most, for the big boxes to be paired apart from the grid
#: (:func:`box_pairs`; past it the grid takes them all)
BIG_BOX_BUDGET = 50_000_000

#: a box over this many grid cells is big (:func:`box_pairs`: paired by a grid of the big boxes' size)
BIG_BOX_CELLS = 512


@njit(cache=True)
def _big_boxes(boxes, origin, inv, limit):
    """(n,) bool: the boxes that overlap more than ``limit`` cells of the grid (``origin``,
    cell ``1 / inv``)."""
    out = np.zeros(boxes.shape[0], np.bool_)
    for i in range(boxes.shape[0]):
        cells = 1.0
        for d in range(3):
            cells *= float(_cell(boxes[i, d + 3], origin[d], inv) - _cell(boxes[i, d], origin[d], inv) + 1)
        out[i] = cells > limit
    return out


def _big_pairs(a, b, same, big_a, big_b):
    """The overlapping pairs (i, j) with a big box, each once (``same``: i < j): the big boxes of
    ``a`` against every box of ``b``, and the other boxes of ``a`` against the big boxes of ``b``,
    each by a grid whose cell is the mean extent of the big boxes (the small boxes then fall in
    a cell or a few; a direct pairing with every box took 0.03 s a call for a hundred leaf
    triangles against a 390k-triangle canopy)."""
    ja = np.nonzero(big_a)[0]
    big = np.ascontiguousarray(a[ja])
    p = _box_pairs(big, b, False, _mean_extent(big), False)
    i, j = ja[p[:, 0]], p[:, 1].astype(np.int64)
    if same:
        keep = (i != j) & (~big_a[j] | (i < j))
        return np.stack([np.minimum(i, j)[keep], np.maximum(i, j)[keep]], axis=1).astype(np.int32)
    out = [np.stack([i, j], axis=1)]
    jb = np.nonzero(big_b)[0]
    ia = np.nonzero(~big_a)[0]
    if len(jb) and len(ia):
        bigb = np.ascontiguousarray(b[jb])
        p = _box_pairs(np.ascontiguousarray(a[ia]), bigb, False, _mean_extent(bigb), False)
        out.append(np.stack([ia[p[:, 0]], jb[p[:, 1]]], axis=1))
    return np.concatenate(out).astype(np.int32)


def _pairs_with_big(a, b, same, big_a, big_b, cell_size):
    """:func:`box_pairs` with the big boxes paired by a grid of their own size and the others by
    the grid of ``cell_size``."""
    ia = np.nonzero(~big_a)[0]
    ib = ia if same else np.nonzero(~big_b)[0]
    small = _box_pairs(np.ascontiguousarray(a[ia]), np.ascontiguousarray(a[ia] if same else b[ib]), same,
                       cell_size, False)
    pairs = np.concatenate([np.stack([ia[small[:, 0]], ib[small[:, 1]]], axis=1).astype(np.int32),
                            _big_pairs(a, b, same, big_a, big_b)])
    return _sorted_pairs(pairs)


_NO_SKIP = np.zeros(0, np.bool_)
_NO_VERTS = np.zeros((0, 1), np.int32)
_NO_PARTS = np.zeros(0, np.int32)


@njit(cache=True, inline="always")
def _share_vertex(verts_a, a, verts_b, b):
    for i in range(verts_a.shape[1]):
        for j in range(verts_b.shape[1]):
            if verts_a[a, i] == verts_b[b, j]:
                return True
    return False


@njit(cache=True)
def _join_buckets(lo, hi, starts, elem, key, ebox, origin, inv, verts, parts, mode, out, base, limit):
    """The pairs of entries of buckets ``lo:hi`` that share a cell (:func:`_self_join`): counted,
    written at ``out[base:]`` while below row ``limit``."""
    n = 0
    for h in range(lo, hi):
        e = starts[h + 1]
        for k1 in range(starts[h], e):
            c = key[k1]
            a = elem[k1]
            for k2 in range(k1 + 1, e):
                if key[k2] != c:
                    continue
                b = elem[k2]  # >= a: a bucket is filled in element order
                if b == a:  # (one element twice: two of its cells with one key, 2^21 cells apart)
                    continue
                if mode != PARTS_ANY and (parts[a] == parts[b]) != (mode == PARTS_SAME):
                    continue
                if not _overlap(ebox, k1, ebox, k2):
                    continue
                # report once: in the cell of the intersection box's minimum corner
                if _key(_cell(max(ebox[k1, 0], ebox[k2, 0]), origin[0], inv),
                        _cell(max(ebox[k1, 1], ebox[k2, 1]), origin[1], inv),
                        _cell(max(ebox[k1, 2], ebox[k2, 2]), origin[2], inv)) != c:
                    continue
                if verts.shape[0] and _share_vertex(verts, a, verts, b):
                    continue
                if base + n < limit:
                    out[base + n, 0] = a
                    out[base + n, 1] = b
                n += 1
    return n


@njit(cache=True, parallel=True)
def _self_join(starts, elem, key, ebox, origin, inv, verts, parts, mode):
    """The pairs ``(a, b)``, ``a < b``, of a grid's own boxes that overlap (the query of the grid's
    boxes against it with ``same``, without the query: each cell's entries are paired among
    themselves, each pair of a cell visited once rather than from both sides), grouped by bucket
    (not sorted). Blocks of buckets run in parallel, each writing into its slab of a scratch
    buffer; a block that overflows its slab is counted and redone."""
    size = starts.shape[0] - 1
    nblk = max(1, min(size, 256))
    per = (size + nblk - 1) // nblk
    cnt = np.zeros(nblk, np.int64)
    cap = np.zeros(nblk + 1, np.int64)
    for blk in range(nblk):
        lo = min(size, blk * per)
        hi = min(size, lo + per)
        cap[blk + 1] = cap[blk] + 4 * (starts[hi] - starts[lo]) + 64
    buf = np.empty((cap[nblk], 2), np.int32)
    for blk in prange(nblk):
        lo = min(size, blk * per)
        hi = min(size, lo + per)
        cnt[blk] = _join_buckets(lo, hi, starts, elem, key, ebox, origin, inv, verts, parts, mode, buf,
                                 cap[blk], cap[blk + 1])
    offsets = np.zeros(nblk + 1, np.int64)
    for blk in range(nblk):
        offsets[blk + 1] = offsets[blk] + cnt[blk]
    out = np.empty((offsets[nblk], 2), np.int32)
    for blk in prange(nblk):
        lo = min(size, blk * per)
        hi = min(size, lo + per)
        if cap[blk] + cnt[blk] > cap[blk + 1]:
            _join_buckets(lo, hi, starts, elem, key, ebox, origin, inv, verts, parts, mode, out,
                          offsets[blk], offsets[blk + 1])
        else:
            for i in range(cnt[blk]):
                out[offsets[blk] + i, 0] = buf[cap[blk] + i, 0]
                out[offsets[blk] + i, 1] = buf[cap[blk] + i, 1]
    return out


class BoxGrid:
    """A hashed grid built once over a set of boxes and queried many times (the collision
    resolution's retry rounds query it with the few boxes that moved).

    Parameters
    ----------
    boxes : (nb, 6) float64
    cell_size : float
        Grid cell edge (> 0).
    origin : (3,) float64
        Grid origin; grids queried together must share it and ``cell_size``.
    vertices : (nb, k) int32 or None
        The mesh vertices of each box's element (a vertex: one column, an edge: two, a triangle:
        three); with them, queries that give theirs skip pairs sharing a vertex (a triangle's own
        vertices, two edges of one fan: never a collision) before they are written.
    parts : (nb,) int32 or None
        The part (floret) of each box's element; with them, queries that give theirs and a
        ``parts_mode`` keep only pairs within one part or only pairs of two parts.
    """

    def __init__(self, boxes: np.ndarray, cell_size: float, origin: np.ndarray,
                 vertices: np.ndarray | None = None, parts: np.ndarray | None = None):
        self.boxes = np.ascontiguousarray(boxes, dtype=np.float64).reshape(-1, 6)
        self.vertices = _NO_VERTS if vertices is None else np.ascontiguousarray(vertices, dtype=np.int32)
        self.origin = np.ascontiguousarray(origin, dtype=np.float64)
        self.parts = _NO_PARTS if parts is None else np.ascontiguousarray(parts, dtype=np.int32)
        self.inv = 1.0 / float(cell_size)
        self.tables = _build(self.boxes, self.origin, self.inv) if len(self.boxes) else None

    def query(self, boxes: np.ndarray, *, skip: np.ndarray | None = None, same: bool = False,
              vertices: np.ndarray | None = None, parts: np.ndarray | None = None,
              parts_mode: int = PARTS_ANY) -> np.ndarray:
        """(k, 2) int32 pairs ``(i, j)``: query box i overlaps grid box j (not ``skip[j]``), in (i, j)
        order; ``same``: the query boxes are the grid's own boxes, pairs ``i < j`` only;
        ``vertices``: the query elements' mesh vertices, pairs sharing one with the grid's element
        are left out (needs the grid's ``vertices``); ``parts`` with ``parts_mode``
        (:data:`PARTS_SAME`, :data:`PARTS_CROSS`): the query elements' parts, pairs of two parts /
        within one part left out (needs the grid's ``parts``)."""
        q = np.ascontiguousarray(boxes, dtype=np.float64).reshape(-1, 6)
        if self.tables is None or len(q) == 0:
            return np.zeros((0, 2), np.int32)
        sk = _NO_SKIP if skip is None else np.ascontiguousarray(skip, dtype=np.bool_)
        va = _NO_VERTS if vertices is None else np.ascontiguousarray(vertices, dtype=np.int32)
        vb = self.vertices if len(va) else _NO_VERTS
        if len(va) and len(vb) != len(self.boxes):
            raise ValueError("vertex filter needs the grid's element vertices")
        pa, pb = _NO_PARTS, _NO_PARTS
        if parts_mode != PARTS_ANY:
            pa = np.ascontiguousarray(parts, dtype=np.int32)
            pb = self.parts
            if len(pa) != len(q) or len(pb) != len(self.boxes):
                raise ValueError("part filter needs the query's and the grid's element parts")
        run = _query_serial if len(q) < SERIAL_QUERY_BELOW else _query
        return run(q, same, sk, va, vb, pa, pb, int(parts_mode), self.origin, self.inv, *self.tables)

    def self_pairs(self, *, vertices: bool = False, parts_mode: int = PARTS_ANY) -> np.ndarray:
        """(k, 2) int32 pairs ``(i, j)``, ``i < j``, of the grid's own boxes that overlap: the pairs
        of ``query(boxes, same=True)`` (with ``vertices``: less those sharing a vertex; with
        ``parts_mode``: the part filter, on the grid's ``parts``), in no particular order."""
        if self.tables is None:
            return np.zeros((0, 2), np.int32)
        starts, elem, key, ebox, _ = self.tables
        return _self_join(starts, elem, key, ebox, self.origin, self.inv,
                          self.vertices if vertices else _NO_VERTS,
                          self.parts if parts_mode != PARTS_ANY else _NO_PARTS, int(parts_mode))


@njit(cache=True)
def box_pairs_brute(boxes_a, boxes_b, same):
    """Reference for tests: every pair tested, O(na nb)."""
    out = []
    for i in range(boxes_a.shape[0]):
        for j in range(boxes_b.shape[0]):
            if same and j <= i:
                continue
            if _overlap(boxes_a, i, boxes_b, j):
                out.append((i, j))
    return _pair_array(out)


# --------------------------------------------------------------------------------------------------
# Boxes grouped by part (florets): the tables of the part-by-part sweep of :mod:`.probe`
# --------------------------------------------------------------------------------------------------

#: the part-by-part sweep (:mod:`.probe`) is used where no part has more elements than this: a
#: sweep goes along one axis, so a big part's elements each pass many others (the lily, one part
#: of 3,780 triangles, collides about 1.6 x slower with the sweep than with the grid, and still
#: 1.5 x once a part's own edges are swept once rather than in both orders; the dense growing
#: head's florets, 280 triangles, collide 2 x faster with the sweep)
PART_SWEEP_MAX_ELEMENTS = 1500


def parts_grouped(part: np.ndarray | None) -> bool:
    """Whether the (k,) element parts are grouped in non-decreasing order (every part's elements
    contiguous, parts in increasing order), as the part-by-part sweep (:mod:`.probe`) needs."""
    if part is None:
        return False
    p = np.asarray(part)
    return len(p) == 0 or (p.min() >= 0 and bool(np.all(p[1:] >= p[:-1])))


@njit(cache=True)
def _part_starts(part, n_parts):
    starts = np.zeros(n_parts + 1, np.int64)
    for i in range(part.shape[0]):
        starts[part[i] + 1] += 1
    for p in range(n_parts):
        starts[p + 1] += starts[p]
    return starts


@njit(cache=True)
def _part_boxes(boxes, starts):
    """(n_parts, 6): the union of each part's boxes (an empty part: an inverted box)."""
    n = starts.shape[0] - 1
    out = np.empty((n, 6))
    for p in range(n):
        for d in range(3):
            out[p, d] = np.inf
            out[p, d + 3] = -np.inf
        for i in range(starts[p], starts[p + 1]):
            for d in range(3):
                out[p, d] = min(out[p, d], boxes[i, d])
                out[p, d + 3] = max(out[p, d + 3], boxes[i, d + 3])
    return out


@njit(cache=True)
def _overlapping_parts(ba, bb, same, mode):
    """CSR lists: for every part p the parts q whose ``bb`` box overlaps p's ``ba`` box (q == p
    included where the mode keeps pairs within a part; with ``same``, q >= p only)."""
    n = ba.shape[0]
    counts = np.zeros(n + 1, np.int64)
    for rep in range(2):
        if rep == 1:
            for p in range(n):
                counts[p + 1] += counts[p]
            out = np.empty(counts[n], np.int64)
            fill = counts[:-1].copy()
        for p in range(n):
            if not ba[p, 0] <= ba[p, 3]:
                continue
            for q in range(p if same else 0, n):
                if q == p and mode == PARTS_CROSS:
                    continue
                if q != p and mode == PARTS_SAME:
                    continue
                if not _overlap(ba, p, bb, q):
                    continue
                if rep == 0:
                    counts[p + 1] += 1
                else:
                    out[fill[p]] = q
                    fill[p] += 1
    return counts, out


def _sorted_pairs(pairs: np.ndarray) -> np.ndarray:
    """(k, 2) int32 pairs in (a, b) order: the order of the contacts (and so of the Gauss-Seidel
    projection) does not depend on which of the broad phase's lists found a pair."""
    p = np.ascontiguousarray(pairs, dtype=np.int32)
    if len(p) < 2:
        return p
    key = p[:, 0].astype(np.int64) << np.int64(32) | p[:, 1].astype(np.int64)
    return np.ascontiguousarray(p[np.argsort(key, kind="stable")])
