"""The venation simulation loop (Runions secs. 4.2-4.3, fig. 4.8, fig. 4.10).

Every iteration runs the three processes of fig. 4.8 in turn:

1. **Leaf-blade growth** (sec. 4.2.3): the blade's scale sigma_t follows the growth schedule.
   Marginal growth scales the margin about the base and leaves sources and vein nodes where they
   are. Uniform (isogonic) growth scales everything; as the thesis does, the blade, the sources
   and the veins stay put in *internal* coordinates and the unit distance shrinks instead,
   lambda_t = lambda_0 sigma_0 / sigma_t (D, d_k, b_s and b_v are multiplied by lambda_t; real
   positions are base + (p - base) / lambda_t). Anisotropic growth (fig. 4.2d) moves every source
   and vein node with the blade, per axis.
2. **Auxin sources** by dart throwing: rho darts per unit (real) leaf area per step, uniform in
   the current blade (``region`` "blade") or only in the band of blade that marginal growth added
   this step (``region`` "margin": "for marginal growth, new sources appear only on the margin",
   sec. 4.2.3; the thesis includes a precomputed set as the contour reaches it); a dart becomes a
   source when it is farther than b_s from every source and farther than b_v from every vein node.
3. **Vein development**: each source s influences a set of vein nodes, its closest one (open
   patterns, fig. 4.10b) or its relative neighbourhood V(s) (closed patterns, eq. 4.1-4.2; or the
   Urquhart approximation); each influenced node v grows one new node v' = v + D n^ with
   n^ the normalized sum of the unit vectors toward its sources (eq. 3.1, no tropism in leaves).
   *Open*: a source is removed as soon as a vein node is closer than d_k. *Closed* (sec. 4.3):
   when a node first comes within d_k of s, the nodes of V(s) are tagged; tags pass to the
   nodes they grow; s is removed when every tagged vein in V(s) has reached it (is within d_k)
   or left V(s); the veins that reached it are joined (an anastomosis edge from each to the one
   closest to s), so the venation graph holds the loops. Nodes within d_k of a source no longer
   grow toward it.

Runions ch. 5 (secs. 5.2.3-5.2.5, the *areole algorithm*): after the iteration ``blind_after``
("the event leading to blindly terminating veins", sec. 5.2.4) a new closed-pattern source stores
its relative neighbourhood, only its closest neighbour grows toward it (fig. 5.5 c-d), and when
that vein reaches it the vein bifurcates toward the stored neighbours (:func:`grow_sprouts`,
fig. 5.5 e-g), stopping short of each: a blindly terminating vein (fig. 5.4 i). With ``inside``
the veins are kept in the blade (for dissected leaves, :func:`grow_veins`).

Runions ch. 5 also gives the loop deterministic source placement (sec. 5.2.2, ``placement``
"largest_empty_circle", :mod:`.placement`: sources at the centres of the largest circles empty of
vein nodes and sources, while they support one) and local-to-global growth (sec. 5.2.1, eq. 5.1,
growth kind "local_to_global", :class:`.blade.LocalToGlobal`: vein nodes and sources are kept by
their positions at t0 and moved to the blade's each step). The developmental events (sources, the
midvein, loops closed, blind vein ends) are collected as they happen (``events``).

Two guards keep the graph clean. A node whose new direction repeats its last one (its sources
unchanged) grows toward its closest source instead (branch-gen's SCA does the same); a new node
that would come closer than D/2 to an existing node grows toward the closest source instead, and
not at all if that is too close as well. In an open pattern only a node grown earlier in the same
iteration can stop the fallback (any older node within D/2 of v + D (s - v)/|s - v| would be
nearer to s than v is, given d_k >= D), and the next iteration gives s to that node. In a closed
pattern a node stopped by it is within 1.5 D of its source; there a node that is influenced but
does not grow counts, in the next iteration, as having reached its sources (so a source whose
veins are all stopped is removed instead of waiting for ever: a vein that stepped just past its
source, or one the Urquhart approximation keeps in V(s) although a node it did not test lies in
the lune); such removals are counted (``sources_stalled``).

The loop stops after the blade has stopped growing, when no source is left and no dart has been
accepted for ``settle`` iterations (or at ``max_iterations`` / ``max_nodes``); with veins kept
inside the blade (``inside``), when no vein node has been added for ``settle`` iterations.
"""
from __future__ import annotations

import heapq
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numba import njit

from .blade import Blade, Growth, _inside, inside_blade, polygon_area
from .neighbourhood import (
    HULL_DIRECTIONS,
    MAX_NEIGHBOURS,
    NEAREST,
    RELATIVE,
    URQUHART,
    Grid,
    grid_insert,
    grid_insert_idx,
    grid_rebuild,
    grid_remove_cells,
    hull_support,
    make_grid,
    nearest_incremental,
    relative_neighbourhoods,
)
from .placement import largest_empty_circles

__all__ = ["SimParams", "VenationResult", "simulate", "Snapshot"]

NEIGHBOURHOODS = {"nearest": NEAREST, "relative": RELATIVE, "urquhart": URQUHART}


@dataclass(frozen=True)
class SimParams:
    """What the loop needs (lengths at lambda = 1, in blade units; see formats/venation.md).

    pattern : "open" or "closed"
    neighbourhood : "relative" (exact, eq. 4.1) or "urquhart" (closed patterns only)
    step : D, the length of a vein segment
    kill_distance : d_k
    birth_source, birth_vein : b_s, b_v
    darts : rho, darts per unit leaf area per step
    roots : (r, 2) initial vein nodes (scale-1 blade coordinates)
    region : "blade" (darts anywhere in the blade) or "margin" (only in the blade new this step:
        sec. 4.2.3's marginal growth, where new sources appear only on the margin)
    settle : iterations without a new source after growth before the run stops
    blind_after : closed patterns: the iteration of "the event leading to blindly terminating
        veins" (sec. 5.2.4); sources placed from then on follow the areole algorithm (secs.
        5.2.3-5.2.5) and their veins stop short of the nodes they head for; -1: never
    blind_gap : the extending vein of an areole source stops when closer than ``blind_gap`` x D
        to the relative neighbour it heads for (sec. 5.2.5: "less than D")
    inside : veins stay in the blade (a new node and the middle of its segment inside it); an open
        source whose closest node is stopped by this is removed (for dissected leaves)
    placement : "darts" (dart throwing, sec. 4.2.3) or "largest_empty_circle" (sec. 5.2.2: each
        iteration, sources at the centres of the largest empty circles while they support one)
    """

    pattern: str = "open"
    neighbourhood: str = "relative"
    step: float = 1.0
    kill_distance: float = 1.0
    birth_source: float = 2.0
    birth_vein: float = 2.0
    darts: float = 0.01
    roots: tuple = ()
    region: str = "blade"
    settle: int = 10
    blind_after: int = -1
    blind_gap: float = 1.0
    inside: bool = False
    placement: str = "darts"
    max_iterations: int = 100_000
    max_nodes: int = 2_000_000
    seed: int = 1


class Nodes(NamedTuple):
    """Vein nodes (capacity rows; internal coordinates)."""

    pos: np.ndarray  # (cap, 2) float64
    parent: np.ndarray  # (cap,) int64, -1 for the initial nodes
    iteration: np.ndarray  # (cap,) int64 that created the node (-1 initial)
    last_dir: np.ndarray  # (cap, 2) direction of the node's last growth
    acc: np.ndarray  # (cap, 2) sum of unit vectors toward its sources (eq. 3.1), zeroed after use
    cnt: np.ndarray  # (cap,) int64 |S(v)| this iteration
    closest: np.ndarray  # (cap,) int64 closest source of S(v)
    closest_d2: np.ndarray  # (cap,) float64
    stalled: np.ndarray  # (cap,) int64 last iteration in which the node was influenced but did not grow, NEVER_STALLED


#: ``Nodes.stalled`` of a node that has never stalled: no iteration (the test is ``stalled == it - 1``,
#: so -1 would read as stalled in iteration 0 and remove every source of the first iteration)
NEVER_STALLED = -(2 ** 62)


class Sources(NamedTuple):
    """Auxin sources (capacity rows; every source ever placed, internal coordinates)."""

    pos: np.ndarray  # (cap, 2)
    alive: np.ndarray  # (cap,) bool
    born: np.ndarray  # (cap,) int64 iteration
    died: np.ndarray  # (cap,) int64 iteration (-1 alive)
    tag_iter: np.ndarray  # (cap,) int64 iteration of tagging (closed), -1
    tags: np.ndarray  # (cap, MAX_NEIGHBOURS) int64 the tagged nodes V(s)
    ntag: np.ndarray  # (cap,) int64
    near: np.ndarray  # (cap,) int64 nearest vein node (open patterns), -1 before the first search
    near_d2: np.ndarray  # (cap,) float64 squared distance to it
    areole: np.ndarray  # (cap,) bool: placed after the event of sec. 5.2.4 (the areole algorithm)


def _new_nodes(cap):
    return Nodes(np.zeros((cap, 2)), np.full(cap, -1, np.int64), np.full(cap, -1, np.int64), np.zeros((cap, 2)),
                 np.zeros((cap, 2)), np.zeros(cap, np.int64), np.full(cap, -1, np.int64), np.zeros(cap),
                 np.full(cap, NEVER_STALLED, np.int64))


def _new_sources(cap):
    return Sources(np.zeros((cap, 2)), np.zeros(cap, np.bool_), np.full(cap, -1, np.int64),
                   np.full(cap, -1, np.int64), np.full(cap, -1, np.int64),
                   np.full((cap, MAX_NEIGHBOURS), -1, np.int64), np.zeros(cap, np.int64),
                   np.full(cap, -1, np.int64), np.full(cap, np.inf), np.zeros(cap, np.bool_))


def _grow_rows(tup, cap):
    """The NamedTuple of arrays with room for ``cap`` rows (contents kept)."""
    fresh = type(tup)(*(_new_nodes(cap) if isinstance(tup, Nodes) else _new_sources(cap)))
    for a, b in zip(tup, fresh):
        b[: len(a)] = a
    return fresh


# --------------------------------------------------------------------------------------------
# kernels


@njit(cache=True)
def _first_within(x, y, r2, pos, grid, skip):
    """A point of ``grid`` closer than sqrt(r2) to (x, y), other than ``skip``, or -1."""
    geom = grid.geom
    h = geom[2]
    nx, ny = np.int64(geom[3]), np.int64(geom[4])
    reach = np.int64(math.ceil(math.sqrt(r2) / h))
    cx = np.int64(math.floor((x - geom[0]) / h))
    cy = np.int64(math.floor((y - geom[1]) / h))
    for iy in range(max(cy - reach, 0), min(cy + reach, ny - 1) + 1):
        for ix in range(max(cx - reach, 0), min(cx + reach, nx - 1) + 1):
            v = grid.head[ix + nx * iy]
            while v >= 0:
                if v != skip and (pos[v, 0] - x) ** 2 + (pos[v, 1] - y) ** 2 < r2:
                    return v
                v = grid.nxt[v]
    return -1


@njit(cache=True)
def throw_darts(cand, base, scale, prev_scale, bands, src, n_src, src_grid, bs2, nodes, node_grid, bv2, it,
                known_inside):
    """Dart throwing (sec. 4.2.3): candidates ``cand`` (c, 2) in order; one inside the blade (at
    ``scale`` about ``base``) and, when ``prev_scale[0]`` > 0, outside the blade at ``prev_scale``
    (new sources only on the margin), farther than b_s from every live source and farther than b_v
    from every vein node becomes source ``n_src`` (inserted into ``src_grid``). Returns the new
    count. ``known_inside`` (c,), when given (not empty), says instead which candidates lie in the
    blade (a blade that is no scaled copy: local-to-global growth)."""
    inside = np.zeros(cand.shape[0], np.bool_)
    if known_inside.shape[0] == cand.shape[0] and cand.shape[0] > 0:
        inside[:] = known_inside
    else:
        inside_blade(cand, base, scale, bands, inside)
    before = np.zeros(cand.shape[0], np.bool_)
    if prev_scale[0] > 0.0:
        inside_blade(cand, base, prev_scale, bands, before)
    for c in range(cand.shape[0]):
        if not inside[c] or before[c]:
            continue
        x, y = cand[c, 0], cand[c, 1]
        if _first_within(x, y, bs2, src.pos, src_grid, -1) >= 0:
            continue
        if _first_within(x, y, bv2, nodes.pos, node_grid, -1) >= 0:
            continue
        s = n_src
        _init_source(src, src_grid, s, x, y, it)
        n_src += 1
    return n_src


@njit(cache=True)
def _init_source(src, src_grid, s, x, y, it):
    """Source row ``s``: a live source at (x, y) placed in iteration ``it``, in ``src_grid``."""
    src.pos[s, 0], src.pos[s, 1] = x, y
    src.alive[s] = True
    src.born[s] = it
    src.died[s] = -1
    src.tag_iter[s] = -1
    src.ntag[s] = 0
    src.near[s] = -1
    src.near_d2[s] = np.inf
    src.areole[s] = False
    grid_insert(src_grid, src.pos, s, s + 1)


@njit(cache=True)
def _tag_root(v, s, src, nodes):
    """The tagged node of source s that node v descends from (v itself included), or -1."""
    w = v
    t0 = src.tag_iter[s]
    while w >= 0:
        for k in range(src.ntag[s]):
            if src.tags[s, k] == w:
                return w
        if nodes.iteration[w] < t0:
            return -1
        w = nodes.parent[w]
    return -1


@njit(cache=True)
def update_sources(closed, live, nbr, nbr_n, src, nodes, dk2, it, extra, n_extra, sprouts, n_sprouts, gap2,
                   open_stall):
    """Source removal (open: a node within d_k; closed: sec. 4.3's tagging) after the
    neighbourhoods ``nbr`` of the ``live`` sources were found. In a closed pattern a node that was
    influenced in the previous iteration but did not grow (a guard of :func:`grow_veins` stopped
    it) counts as having reached its sources. Joins the veins that reached a removed closed-pattern source (``extra``
    rows from ``n_extra``).

    An areole source (sec. 5.2.5, fig. 5.5) stores its relative neighbourhood when first seen (c)
    and only its closest node grows toward it (d; ``nbr_n`` is set to 1); when that vein comes
    within d_k (or cannot grow) the source is removed and the vein bifurcates toward the stored
    neighbours (e-f): a ``sprouts`` row (tip node, target node) for every stored neighbour but the
    one the vein came from and those already within the gap. Returns (removed, removed with no
    node within d_k, n_extra, n_sprouts)."""
    removed = 0
    stalled = 0
    reps = np.empty(MAX_NEIGHBOURS, np.int64)
    roots = np.empty(MAX_NEIGHBOURS, np.int64)
    for j in range(live.shape[0]):
        s = live[j]
        n = nbr_n[j]
        if n == 0:
            continue
        sx, sy = src.pos[s, 0], src.pos[s, 1]
        v0 = nbr[j, 0]
        d0 = (nodes.pos[v0, 0] - sx) ** 2 + (nodes.pos[v0, 1] - sy) ** 2
        if src.areole[s]:
            if src.tag_iter[s] < 0:  # (c) the relative neighbourhood at placement, stored
                src.tag_iter[s] = it
                src.ntag[s] = n
                for k in range(n):
                    src.tags[s, k] = nbr[j, k]
            nbr_n[j] = 1  # (d) the closest relative neighbour wins
            if d0 < dk2 or nodes.stalled[v0] == it - 1:
                src.alive[s] = False
                src.died[s] = it
                removed += 1
                if d0 >= dk2:
                    stalled += 1
                came = _tag_root(v0, s, src, nodes)
                for k in range(src.ntag[s]):
                    u = src.tags[s, k]
                    if u == came or u == v0 or n_sprouts >= sprouts.shape[0]:
                        continue
                    du = (nodes.pos[u, 0] - nodes.pos[v0, 0]) ** 2 + (nodes.pos[u, 1] - nodes.pos[v0, 1]) ** 2
                    if du < gap2:
                        continue
                    sprouts[n_sprouts, 0] = v0
                    sprouts[n_sprouts, 1] = u
                    n_sprouts += 1
            continue
        if not closed:
            # with veins kept inside the blade, an open source whose closest node cannot grow
            # toward it (across a gap of the blade) is given up, as in a closed pattern
            if d0 < dk2 or (open_stall and nodes.stalled[v0] == it - 1):
                src.alive[s] = False
                src.died[s] = it
                removed += 1
            continue
        if src.tag_iter[s] < 0:
            reached = False
            for k in range(n):
                v = nbr[j, k]
                if nodes.stalled[v] == it - 1 or (nodes.pos[v, 0] - sx) ** 2 + (nodes.pos[v, 1] - sy) ** 2 < dk2:
                    reached = True
            if not reached:
                continue
            src.tag_iter[s] = it
            src.ntag[s] = n
            for k in range(n):
                src.tags[s, k] = nbr[j, k]
        keep = False
        nr = 0
        for k in range(n):
            v = nbr[j, k]
            d2 = (nodes.pos[v, 0] - sx) ** 2 + (nodes.pos[v, 1] - sy) ** 2
            reached = d2 < dk2 or nodes.stalled[v] == it - 1
            t = _tag_root(v, s, src, nodes)
            if t < 0:
                continue
            if not reached:
                keep = True
                break
            # the closest reached node of each tagged vein
            found = False
            for q in range(nr):
                if roots[q] == t:
                    found = True
                    u = reps[q]
                    du = (nodes.pos[u, 0] - sx) ** 2 + (nodes.pos[u, 1] - sy) ** 2
                    if d2 < du:
                        reps[q] = v
            if not found:
                roots[nr] = t
                reps[nr] = v
                nr += 1
        if keep:
            continue
        src.alive[s] = False
        src.died[s] = it
        removed += 1
        if d0 >= dk2:
            stalled += 1
        if nr >= 2:
            best = 0
            bd = np.inf
            for q in range(nr):
                u = reps[q]
                du = (nodes.pos[u, 0] - sx) ** 2 + (nodes.pos[u, 1] - sy) ** 2
                if du < bd:
                    bd, best = du, q
            r0 = reps[best]
            for q in range(nr):
                r = reps[q]
                if r == r0 or nodes.parent[r] == r0 or nodes.parent[r0] == r:
                    continue
                dup = False
                for e in range(n_extra):
                    if (extra[e, 0] == r and extra[e, 1] == r0) or (extra[e, 0] == r0 and extra[e, 1] == r):
                        dup = True
                        break
                if not dup and n_extra < extra.shape[0]:
                    extra[n_extra, 0] = min(r, r0)
                    extra[n_extra, 1] = max(r, r0)
                    n_extra += 1
    return removed, stalled, n_extra, n_sprouts


@njit(cache=True)
def grow_sprouts(sprouts, n_sprouts, nodes, n_nodes, step, gap2, grid, it, ended_out):
    """The veins of removed areole sources extending toward their stored relative neighbours
    (sec. 5.2.5, fig. 5.5 f-g): each sprout's tip grows one node D toward its target; a sprout
    closer than the gap to its target, or whose next node would come within D/2 of another node,
    stops there without joining it (after the event of sec. 5.2.4: a blindly terminating vein,
    fig. 5.4 i). Finished sprouts are dropped; ``ended_out`` (n_sprouts, 2) gets a row (tip, target)
    per vein that ended. Returns (n_nodes, n_sprouts, veins ended)."""
    half2 = 0.25 * step * step
    kept = 0
    ended = 0
    for q in range(n_sprouts):
        t, u = sprouts[q, 0], sprouts[q, 1]
        dx, dy = nodes.pos[u, 0] - nodes.pos[t, 0], nodes.pos[u, 1] - nodes.pos[t, 1]
        d2 = dx * dx + dy * dy
        if d2 < gap2 or d2 <= 0.0:
            ended_out[ended, 0], ended_out[ended, 1] = t, u
            ended += 1
            continue
        d = math.sqrt(d2)
        wx, wy = nodes.pos[t, 0] + step * dx / d, nodes.pos[t, 1] + step * dy / d
        if _first_within(wx, wy, half2, nodes.pos, grid, t) >= 0:
            ended_out[ended, 0], ended_out[ended, 1] = t, u
            ended += 1
            continue
        w = _add_node(nodes, n_nodes, wx, wy, t, it, grid)
        n_nodes += 1
        sprouts[kept, 0] = w
        sprouts[kept, 1] = u
        kept += 1
    return n_nodes, kept, ended


@njit(cache=True)
def _add_node(nodes, w, x, y, parent, it, grid):
    """Vein node ``w`` at (x, y), grown from ``parent`` in iteration ``it``, in ``grid``; returns w."""
    nodes.pos[w, 0], nodes.pos[w, 1] = x, y
    nodes.parent[w] = parent
    nodes.iteration[w] = it
    nodes.last_dir[w, 0] = 0.0
    nodes.last_dir[w, 1] = 0.0
    nodes.stalled[w] = NEVER_STALLED
    grid_insert(grid, nodes.pos, w, w + 1)
    return w


@njit(cache=True)
def grow_veins(closed, live, nbr, nbr_n, src, nodes, n_nodes, step, dk2, grid, it, inside, base, bscale, bands):
    """Vein development (eq. 3.1): every node influenced by a live source grows one node D along
    the normalized sum of the unit vectors toward its sources (with the guards of the module
    docstring). With ``inside``, a new node, and the middle of its segment, must lie in the blade
    (scaled by ``bscale`` about ``base``): veins do not cross the gaps of a dissected leaf. New
    nodes are inserted into ``grid``; returns the node count."""
    touched = np.empty(nbr.shape[0] * MAX_NEIGHBOURS + 1, np.int64)
    nt = 0
    for j in range(live.shape[0]):
        s = live[j]
        if not src.alive[s]:
            continue
        sx, sy = src.pos[s, 0], src.pos[s, 1]
        for k in range(nbr_n[j]):
            v = nbr[j, k]
            dx, dy = sx - nodes.pos[v, 0], sy - nodes.pos[v, 1]
            d2 = dx * dx + dy * dy
            if d2 <= 0.0 or (closed and d2 < dk2):
                continue
            d = math.sqrt(d2)
            if nodes.cnt[v] == 0:
                touched[nt] = v
                nt += 1
                nodes.closest[v] = s
                nodes.closest_d2[v] = d2
            elif d2 < nodes.closest_d2[v] or (d2 == nodes.closest_d2[v] and s < nodes.closest[v]):
                nodes.closest[v] = s
                nodes.closest_d2[v] = d2
            nodes.cnt[v] += 1
            nodes.acc[v, 0] += dx / d
            nodes.acc[v, 1] += dy / d
    order = np.sort(touched[:nt])
    half2 = 0.25 * step * step
    for q in range(nt):
        v = order[q]
        ax, ay = nodes.acc[v, 0], nodes.acc[v, 1]
        nodes.acc[v, 0] = 0.0
        nodes.acc[v, 1] = 0.0
        nodes.cnt[v] = 0
        c = nodes.closest[v]
        vx, vy = nodes.pos[v, 0], nodes.pos[v, 1]
        grown = False
        for attempt in range(2):
            if attempt == 0:
                nn = math.sqrt(ax * ax + ay * ay)
                if nn < 1e-12:
                    continue
                ux, uy = ax / nn, ay / nn
            else:
                ux, uy = src.pos[c, 0] - vx, src.pos[c, 1] - vy
                nn = math.sqrt(ux * ux + uy * uy)
                if nn <= 0.0:
                    continue
                ux, uy = ux / nn, uy / nn
            if ux * nodes.last_dir[v, 0] + uy * nodes.last_dir[v, 1] > 1.0 - 1e-12:
                continue
            wx, wy = vx + step * ux, vy + step * uy
            if inside:
                out = False
                for f in (1.0, 0.5):
                    x = base[0] + (vx + f * step * ux - base[0]) / bscale[0]
                    y = base[1] + (vy + f * step * uy - base[1]) / bscale[1]
                    if not _inside(x, y, bands.poly, bands.y0, bands.inv_dy, bands.nb, bands.start, bands.edge):
                        out = True
                if out:
                    continue
            u = _first_within(wx, wy, half2, nodes.pos, grid, v)
            if u >= 0:
                continue
            _add_node(nodes, n_nodes, wx, wy, v, it, grid)
            n_nodes += 1
            nodes.last_dir[v, 0], nodes.last_dir[v, 1] = ux, uy
            grown = True
            break
        if not grown:
            nodes.stalled[v] = it
    return n_nodes


def _add_sources(src, n_src, src_grid, pts, it):
    """Sources at ``pts`` (k, 2) placed in iteration ``it`` (as :func:`throw_darts` makes them);
    returns the new count."""
    for x, y in pts:
        s = n_src
        _init_source(src, src_grid, s, x, y, it)
        n_src += 1
    return n_src


@njit(cache=True)
def _forest_root(parent, v):
    while parent[v] >= 0:
        v = parent[v]
    return v


@njit(cache=True)
def _shortest_path(pos, parent, n, extra, e, a, b):
    """The shortest path (by length) from node a to node b over the growth forest's edges and the
    anastomoses ``extra[:e]`` (Dijkstra); the nodes from b back to a, or empty when none."""
    deg = np.zeros(n + 1, np.int64)
    for v in range(n):
        if parent[v] >= 0:
            deg[v + 1] += 1
            deg[parent[v] + 1] += 1
    for k in range(e):
        deg[extra[k, 0] + 1] += 1
        deg[extra[k, 1] + 1] += 1
    start = np.cumsum(deg)
    fill = start[:-1].copy()
    adj = np.empty(start[-1], np.int64)
    for v in range(n):
        u = parent[v]
        if u >= 0:
            adj[fill[v]] = u
            fill[v] += 1
            adj[fill[u]] = v
            fill[u] += 1
    for k in range(e):
        u, v = extra[k, 0], extra[k, 1]
        adj[fill[u]] = v
        fill[u] += 1
        adj[fill[v]] = u
        fill[v] += 1
    dist = np.full(n, np.inf)
    pred = np.full(n, -1, np.int64)
    done = np.zeros(n, np.bool_)
    dist[a] = 0.0
    heap = [(0.0, a)]
    while len(heap):
        d, v = heapq.heappop(heap)
        if done[v]:
            continue
        done[v] = True
        if v == b:
            break
        for q in range(start[v], start[v + 1]):
            u = adj[q]
            if done[u]:
                continue
            nd = d + math.sqrt((pos[u, 0] - pos[v, 0]) ** 2 + (pos[u, 1] - pos[v, 1]) ** 2)
            if nd < dist[u]:
                dist[u] = nd
                pred[u] = v
                heapq.heappush(heap, (nd, u))
    if not done[b]:
        return np.zeros(0, np.int64)
    m = 1
    w = b
    while w != a:
        w = pred[w]
        m += 1
    path = np.empty(m, np.int64)
    w = b
    for k in range(m):
        path[k] = w
        w = pred[w]
    return path


def _midvein_event(events, it, src, n_src, nodes, n_nodes, lam, real, dk2):
    """The midvein (fig. 5.1b, 5.7c): the first source reached by a vein, in iteration ``it``; the
    event gives the reaching node and the vein's length from its initial node. Returns the
    midvein's nodes (from the reaching node to the initial node) once seen, else None."""
    if not n_nodes:
        return None
    for s in np.flatnonzero(src.died[:n_src] == it).tolist():
        d = ((nodes.pos[:n_nodes] - src.pos[s]) ** 2).sum(1)
        v = int(np.argmin(d))
        if not d[v] < dk2 or nodes.parent[v] < 0:  # removed unreached, or no vein grew to it
            continue
        length = 0.0
        w = v
        chain = [v]
        while nodes.parent[w] >= 0:
            length += math.dist(nodes.pos[w], nodes.pos[nodes.parent[w]])
            w = int(nodes.parent[w])
            chain.append(w)
        p = real(nodes.pos[v], lam)
        events.append((it, "midvein", s, float(p[0]), float(p[1]), length / lam))
        return np.asarray(chain, np.int64)
    return None


@njit(cache=True)
def _enclosing(px, py, pos, flat, offs, which):
    """How many of the loops ``which`` (node cycles ``flat[offs[i]:offs[i+1]]``, at the nodes'
    current positions) enclose the point (px, py) (even-odd rule)."""
    count = 0
    for i in which:
        inside = False
        lo, hi = offs[i], offs[i + 1]
        m = hi - lo
        for k in range(m):
            a = flat[lo + k]
            b = flat[lo + (k + 1) % m]
            ax, ay = pos[a, 0], pos[a, 1]
            bx, by = pos[b, 0], pos[b, 1]
            if (ay > py) != (by > py):
                if px < ax + (py - ay) * (bx - ax) / (by - ay):
                    inside = not inside
        if inside:
            count += 1
    return count


class _Loops:
    """Loops closed by anastomoses: an edge (a, b) closes one when a and b are already connected
    (through the growth forest and the earlier anastomoses); the loop is the shortest path from a to
    b (by length) plus the edge, and its polygon gives the area it encloses. Its order is 1 + the
    number of earlier loops that enclose its centroid (the loops it subdivides). A loop that runs
    along the midvein (two or more of its nodes on it) is a loop of secondary veins, as the loops
    of fig. 5.7e-g (``midvein`` 1 in events.csv)."""

    def __init__(self, n_roots: int):
        self.midvein = np.zeros(0, np.int64)  # the midvein's nodes, once it has formed
        self.uf = list(range(n_roots))
        self.count = 0
        self.flat = np.zeros(1024, np.int64)
        self.offs = np.zeros(1025, np.int64)
        self.box = np.zeros((1024, 4))  # each loop's box in coordinates growth does not change

    def _find(self, i):
        while self.uf[i] != i:
            self.uf[i] = self.uf[self.uf[i]]
            i = self.uf[i]
        return i

    def add(self, extra, e, nodes, n_nodes, lam, real, fixed):
        """The event of anastomosis ``extra[e]``: ("loop", index, cx, cy, area) or None."""
        a, b = int(extra[e, 0]), int(extra[e, 1])
        ra = self._find(_forest_root(nodes.parent, a))
        rb = self._find(_forest_root(nodes.parent, b))
        if ra != rb:
            self.uf[ra] = rb
            return None
        pos = nodes.pos[:n_nodes]
        path = _shortest_path(pos, nodes.parent, n_nodes, extra, e, a, b)
        if len(path) < 3:
            return None
        cycle = pos[path]
        c_in = cycle.mean(0)
        poly = real(cycle, lam)
        x, y = poly[:, 0], poly[:, 1]
        cross = x * np.roll(y, -1) - np.roll(x, -1) * y
        area2 = float(cross.sum())
        if area2 == 0.0:
            cx, cy = float(x.mean()), float(y.mean())
        else:
            cx = float(((x + np.roll(x, -1)) * cross).sum() / (3.0 * area2))
            cy = float(((y + np.roll(y, -1)) * cross).sum() / (3.0 * area2))
        nxt = np.roll(cycle, -1, axis=0)
        cr = cycle[:, 0] * nxt[:, 1] - nxt[:, 0] * cycle[:, 1]
        if cr.sum() != 0.0:  # the centroid in the simulation's coordinates (the loops' test)
            c_in = ((cycle + nxt) * cr[:, None]).sum(0) / (3.0 * cr.sum())
        n, end = self.count, self.offs[self.count]
        fc = fixed(np.vstack([c_in[None], cycle]))
        b = self.box[:n]
        which = np.flatnonzero((b[:, 0] <= fc[0, 0]) & (fc[0, 0] <= b[:, 2]) & (b[:, 1] <= fc[0, 1]) & (fc[0, 1] <= b[:, 3]))
        order = 1 + _enclosing(float(c_in[0]), float(c_in[1]), pos, self.flat, self.offs, which)
        if n + 1 > len(self.box):
            self.box = np.vstack([self.box, np.zeros_like(self.box)])
        self.box[n, :2] = fc[1:].min(0)
        self.box[n, 2:] = fc[1:].max(0)
        if end + len(path) > len(self.flat):
            self.flat = np.concatenate([self.flat, np.zeros(len(self.flat) + len(path), np.int64)])
        if n + 2 > len(self.offs):
            self.offs = np.concatenate([self.offs, np.zeros(len(self.offs), np.int64)])
        self.flat[end:end + len(path)] = path
        self.offs[n + 1] = end + len(path)
        self.count += 1
        on_mid = int(np.isin(path, self.midvein).sum() >= 2)
        return ("loop", self.count, cx, cy, abs(area2) / 2.0, order, on_mid)


_NO_MASK = np.zeros(0, np.bool_)

#: sources placed in one iteration by the largest empty circle at most (params bounds the blade's room)
LEC_LIMIT = 1_000_000


# --------------------------------------------------------------------------------------------
# the loop


@dataclass
class Snapshot:
    """The venation at one iteration, in real coordinates (what a frame shows)."""

    iteration: int
    node_pos: np.ndarray  # (n, 2)
    node_parent: np.ndarray  # (n,)
    extra_edges: np.ndarray  # (e, 2) anastomoses
    blade: np.ndarray  # (m, 2) the margin at this iteration
    sources: np.ndarray  # (k, 2) live sources


@dataclass
class VenationResult:
    """A finished run, in real coordinates (the blade at its final size).

    Attributes
    ----------
    node_pos : (n, 2) float64
    node_parent : (n,) int64
        The node each vein node grew from, -1 for the initial nodes.
    node_iter : (n,) int64
        Iteration that created the node (-1 initial).
    extra_edges : (e, 2) int64
        Anastomoses (closed patterns): node pairs joined at a removed source, i < j.
    blade : (m, 2) float64
        The final margin.
    sources_placed, sources_left : int
    source_pos : (k, 2) float64
        Every source placed, at its final real position; ``source_born``/``source_died``
        (died -1: still alive).
    iterations, growth_steps : int
    stopped : str
        Why the loop ended: "finished", "max_iterations" or "max_nodes".
    sources_stalled : int
        Sources removed with no vein node within d_k, because the nodes they influenced could not
        grow (the guards of :func:`grow_veins`).
    blind_ends : int
        Veins of areole sources that stopped short of the node they headed for (sec. 5.2.4).
    events : list of (iteration, event, index, x, y, measure)
        The developmental events in the order they happened (``events.csv``, formats/venation.md;
        a loop's row adds its order):
        ``source`` placed (measure: the radius of its empty circle with the largest-empty-circle
        placement), ``midvein`` (the first source reached by a vein: measure the vein's length from
        its initial node), ``loop`` (an anastomosis that closes a cycle: x, y its centroid, measure
        the area it encloses), ``blind_end`` (measure: the gap left to the node it headed for).
    seconds : float
    """

    node_pos: np.ndarray
    node_parent: np.ndarray
    node_iter: np.ndarray
    extra_edges: np.ndarray
    blade: np.ndarray
    source_pos: np.ndarray
    source_born: np.ndarray
    source_died: np.ndarray
    iterations: int
    growth_steps: int
    stopped: str
    sources_stalled: int = 0
    blind_ends: int = 0
    events: list = field(default_factory=list)
    seconds: float = 0.0
    timings: dict = field(default_factory=dict)

    @property
    def n_nodes(self) -> int:
        return len(self.node_pos)

    @property
    def sources_placed(self) -> int:
        return len(self.source_pos)

    @property
    def sources_left(self) -> int:
        return int((self.source_died < 0).sum())


def _grid_h(step, bv, dk):
    """Cell size of the point grids: about the birth distance (the common query radius), at least D."""
    return max(step, 0.5 * bv, 0.5 * dk)


def simulate(blade: Blade, growth: Growth, sp: SimParams, *, on_frame: Callable | None = None,
             frame_step: int = 0, progress: Callable | None = None) -> VenationResult:
    """Run the venation model on ``blade`` growing by ``growth``.

    Parameters
    ----------
    on_frame : callable(Snapshot) or None
        Called every ``frame_step`` iterations (and for the last iteration) when ``frame_step`` > 0.
    progress : callable(int) or None
        Called with the number of iterations done since the last call.
    """
    t_start = time.perf_counter()
    kind = growth.kind
    closed = sp.pattern == "closed"
    nb_kind = NEAREST if not closed else NEIGHBOURHOODS[sp.neighbourhood]
    rng = np.random.default_rng(sp.seed)
    base = np.asarray(blade.base, dtype=np.float64)
    s0 = growth.scale_at(0)
    s_end = growth.final_scale
    # internal coordinates: uniform growth keeps the sigma_0 blade, the others real positions
    roots = np.asarray(sp.roots, dtype=np.float64).reshape(-1, 2) if len(sp.roots) else base[None].copy()
    if kind in ("uniform", "anisotropic"):
        roots = base + (roots - base) * s0
    blade_box_scale = s0 if kind == "uniform" else (s_end if kind != "none" else np.ones(2))
    poly_box = blade.scaled(np.maximum(blade_box_scale, s0) if kind != "uniform" else s0)
    if growth.kf is not None:  # a box holding the blade at every time
        poly_box = np.vstack(growth.kf.extent())
    lo = np.minimum(poly_box.min(0), roots.min(0))
    hi = np.maximum(poly_box.max(0), roots.max(0))
    pad = 2.0 * sp.step + 1e-9 * float(np.max(hi - lo))
    lo, hi = lo - pad, hi + pad

    cap = 4096 if len(roots) <= 4096 else len(roots) + 1024  # room for every initial node
    nodes = _new_nodes(cap)
    n_nodes = len(roots)
    nodes.pos[:n_nodes] = roots
    scap = 4096
    src = _new_sources(scap)
    n_src = 0
    extra = np.zeros((1024, 2), np.int64)
    n_extra = 0
    sprouts = np.zeros((1024, 2), np.int64)
    n_sprouts = 0
    blind_ends = 0
    gap2_1 = (sp.blind_gap * sp.step) ** 2 if closed and sp.blind_after >= 0 else 0.0

    lam = 1.0
    h = _grid_h(sp.step, sp.birth_vein, sp.kill_distance)
    node_grid = make_grid(lo, hi, h, cap)
    grid_insert(node_grid, nodes.pos, 0, n_nodes)
    support = np.full(HULL_DIRECTIONS, -np.inf)
    hull_support(nodes.pos, 0, n_nodes, support)
    src_grid = make_grid(lo, hi, h, scap)
    live = np.zeros(0, np.int64)
    dart_carry = 0.0
    quiet = 0
    prev_scale = s0.copy()
    stopped = "finished"
    timings = {"darts": 0.0, "neighbourhoods": 0.0, "sources": 0.0, "growth": 0.0}
    it = 0
    n_growth = growth.steps

    def real(p, lam_now):
        if kind == "uniform":
            return base + (p - base) / lam_now
        return p.copy()

    def snapshot(it_now, lam_now, sc_now):
        # the live sources of the snapshot only: the loop's own list must stay as it is (its
        # cells are cleared from the source grid at the next iteration)
        alive = np.flatnonzero(src.alive[:n_src])
        margin = blade.scaled(sc_now if kind != "none" else 1.0) if ltg is None else ltg_margin
        return Snapshot(it_now, real(nodes.pos[:n_nodes], lam_now), nodes.parent[:n_nodes].copy(),
                        extra[:n_extra].copy(), margin, real(src.pos[alive], lam_now))

    events: list = []  # (iteration, event, index, x, y, measure), in the order they happen
    midvein_seen = False
    loops = _Loops(len(roots))
    # local-to-global growth (sec. 5.2.1): vein nodes and sources kept by their positions at t0
    # key-frame interpolation (sec. 5.2.1, eq. 5.2): kept by their (u, v) on the blade surface
    ltg = growth.material if kind in ("local_to_global", "key_frames") else None
    kf = growth.kf if kind == "key_frames" else None
    t_ltg = 0
    node_mat = nodes.pos[:n_nodes].copy() if kf is None else kf.inverse(nodes.pos[:n_nodes], 0)
    src_mat = np.zeros((0, 2))

    def mat_margin(t_):
        return kf.margin(t_) if kf is not None else ltg.forward(blade.polygon, t_)

    ltg_margin = blade.polygon if ltg is None else mat_margin(0)
    area_ltg = abs(polygon_area(ltg_margin))

    def ltg_contains(q):
        if kf is not None:
            return kf.contains(q, t_ltg)
        return blade.contains(ltg.inverse(q, t_ltg))

    def fixed(q):
        """Positions in coordinates that growth does not change (the loops' boxes)."""
        if ltg is not None:
            return ltg.inverse(q, t_ltg)
        if kind == "anisotropic":
            return base + (q - base) / prev_scale
        return q

    last_frame = -1
    idle = 0
    stalled_total = 0
    n_searched = 0  # nodes that the sources' nearest nodes were searched among
    while True:
        if it >= sp.max_iterations:
            stopped = "max_iterations"
            break
        if n_nodes >= sp.max_nodes:
            stopped = "max_nodes"
            break
        prev_sc = growth.scale_at(it - 1) if it > 0 else np.zeros(2)
        sc = growth.scale_at(it)
        grid_remove_cells(src_grid, src.pos, live)
        # 1. blade growth
        if kind == "uniform":
            lam = float(s0[0] / sc[0])
            blade_scale = s0
        elif kind == "anisotropic":
            blade_scale = sc
            ratio = sc / prev_scale
            if np.any(ratio != 1.0):
                nodes.pos[:n_nodes] = base + (nodes.pos[:n_nodes] - base) * ratio
                src.pos[:n_src] = base + (src.pos[:n_src] - base) * ratio
                grid_rebuild(node_grid, nodes.pos, np.arange(n_nodes, dtype=np.int64))
                support[:] = -np.inf
                hull_support(nodes.pos, 0, n_nodes, support)
        elif ltg is not None:
            blade_scale = np.ones(2)
            t_now = min(it, n_growth)
            if t_now != t_ltg:
                t_ltg = t_now
                nodes.pos[:n_nodes] = ltg.forward(node_mat[:n_nodes], t_ltg)
                src.pos[:n_src] = ltg.forward(src_mat[:n_src], t_ltg)
                grid_rebuild(node_grid, nodes.pos, np.arange(n_nodes, dtype=np.int64))
                support[:] = -np.inf
                hull_support(nodes.pos, 0, n_nodes, support)
                ltg_margin = mat_margin(t_ltg)
                area_ltg = abs(polygon_area(ltg_margin))
        elif kind == "marginal":
            blade_scale = sc
        else:
            blade_scale = np.ones(2)
        prev_scale = sc
        D = sp.step * lam
        dk2 = (sp.kill_distance * lam) ** 2
        bs2 = (sp.birth_source * lam) ** 2
        bv2 = (sp.birth_vein * lam) ** 2
        h_want = _grid_h(D, sp.birth_vein * lam, sp.kill_distance * lam)
        if h_want < 0.5 * node_grid.geom[2] and node_grid.geom[2] * 0.999 > _min_h(lo, hi):
            node_grid = make_grid(lo, hi, h_want, cap)
            grid_rebuild(node_grid, nodes.pos, np.arange(n_nodes, dtype=np.int64))
            src_grid = make_grid(lo, hi, h_want, scap)
        # the live sources in their grid
        live = np.flatnonzero(src.alive[:n_src]).astype(np.int64)
        grid_insert_idx(src_grid, src.pos, live)

        # 2. auxin sources by dart throwing
        t0 = time.perf_counter()
        area_real = blade.area * float(sc[0] * sc[1]) if kind != "none" else blade.area
        if ltg is not None:
            area_real = area_ltg
        want = sp.darts * area_real + dart_carry
        n_darts = int(math.floor(want))
        dart_carry = want - n_darts
        placed = 0
        first_new = n_src
        margin_only = sp.region == "margin"
        if margin_only and it > 0 and not np.any(sc > prev_sc):
            n_darts = 0  # the margin did not move: no new blade
        if sp.placement == "largest_empty_circle":
            n_darts = 0
            poly_now = blade.scaled(blade_scale) if ltg is None else ltg_margin
            alive_now = np.flatnonzero(src.alive[:n_src])
            contains = ltg_contains if ltg is not None else (lambda q, _s=blade_scale: blade.contains(q, _s))
            new_src = largest_empty_circles(poly_now, contains,
                                            nodes.pos[:n_nodes], src.pos[alive_now], math.sqrt(bs2), math.sqrt(bv2),
                                            LEC_LIMIT)
            if n_src + len(new_src) > scap:
                scap = max(2 * scap, n_src + len(new_src) + 1024)
                src = _grow_rows(src, scap)
                src_grid = Grid(src_grid.head, np.concatenate([src_grid.nxt, np.full(scap - len(src_grid.nxt), -1, np.int64)]),
                                src_grid.geom)
            before = n_src
            n_src = _add_sources(src, n_src, src_grid, new_src[:, :2], it)
            placed = n_src - before
            for k_, (x_, y_, r_) in enumerate(new_src.tolist()):
                p_ = real(np.array([x_, y_]), lam)
                events.append((it, "source", before + k_, float(p_[0]), float(p_[1]), r_ / lam))
            if placed and closed and 0 <= sp.blind_after <= it:
                src.areole[before:n_src] = True
            if placed:
                live = np.concatenate([live, np.arange(before, n_src, dtype=np.int64)])
        if n_darts > 0:
            if margin_only:
                cand = _band_darts(blade, prev_sc if it > 0 else np.zeros(2), sc, n_darts, rng)
                n_draw = len(cand)
            else:
                poly_now = blade.scaled(blade_scale) if ltg is None else ltg_margin
                blo, bhi = poly_now.min(0), poly_now.max(0)
                box_area = float(np.prod(bhi - blo))
                area_int = blade.area * float(blade_scale[0] * blade_scale[1]) if ltg is None else area_ltg
                n_draw = int(math.ceil(n_darts * box_area / max(area_int, 1e-300)))
            if n_src + n_draw > scap:
                scap = max(2 * scap, n_src + n_draw + 1024)
                src = _grow_rows(src, scap)
                src_grid = Grid(src_grid.head, np.concatenate([src_grid.nxt, np.full(scap - len(src_grid.nxt), -1, np.int64)]),
                                src_grid.geom)
            if not margin_only:
                cand = blo + (bhi - blo) * rng.random((n_draw, 2))
            known = ltg_contains(cand) if ltg is not None else _NO_MASK
            prev_arg = np.ascontiguousarray(prev_sc if (margin_only and it > 0) else np.zeros(2), dtype=np.float64)
            before = n_src
            n_src = throw_darts(cand, base, np.ascontiguousarray(blade_scale, dtype=np.float64), prev_arg,
                                blade.bands, src, n_src, src_grid, bs2, nodes, node_grid, bv2, it, known)
            placed = n_src - before
            for k_, p_ in enumerate(real(src.pos[before:n_src], lam).tolist()):
                events.append((it, "source", before + k_, float(p_[0]), float(p_[1]), math.nan))
            if placed and closed and 0 <= sp.blind_after <= it:
                src.areole[before:n_src] = True
            if placed:
                live = np.concatenate([live, np.arange(before, n_src, dtype=np.int64)])
        timings["darts"] += time.perf_counter() - t0

        # 3. neighbourhoods, source removal, vein growth
        t0 = time.perf_counter()
        k = len(live)
        nbr = np.full((k, MAX_NEIGHBOURS), -1, np.int64)
        nbr_n = np.zeros(k, np.int64)
        if k and n_nodes:
            if nb_kind == NEAREST and kind not in ("anisotropic", "local_to_global", "key_frames"):
                # nodes stay where they are: a source's nearest node changes only to a new one
                nearest_incremental(src.pos, live, src.near, src.near_d2, nodes.pos, n_searched, n_nodes,
                                    node_grid, nbr, nbr_n)
            else:
                relative_neighbourhoods(src.pos, live, nodes.pos, n_nodes, node_grid, nb_kind, support, nbr, nbr_n)
        n_searched = n_nodes
        t1 = time.perf_counter()
        timings["neighbourhoods"] += t1 - t0
        if n_extra + k > len(extra):
            extra = np.concatenate([extra, np.zeros((len(extra) + k, 2), np.int64)])
        if n_sprouts + k * MAX_NEIGHBOURS > len(sprouts):
            sprouts = np.concatenate([sprouts, np.zeros((len(sprouts) + k * MAX_NEIGHBOURS, 2), np.int64)])
        gap2 = gap2_1 * lam * lam
        extra_before = n_extra
        _, n_stalled, n_extra, n_sprouts = update_sources(closed, live, nbr, nbr_n, src, nodes, dk2, it, extra,
                                                          n_extra, sprouts, n_sprouts, gap2, sp.inside)
        if not midvein_seen:
            chain = _midvein_event(events, it, src, n_src, nodes, n_nodes, lam, real, dk2)
            if chain is not None:
                midvein_seen = True
                loops.midvein = chain
        for e_ in range(extra_before, n_extra):
            ev = loops.add(extra, e_, nodes, n_nodes, lam, real, fixed)
            if ev is not None:
                events.append((it,) + ev)
        t2 = time.perf_counter()
        timings["sources"] += t2 - t1
        stalled_total += n_stalled
        need = n_nodes + int(nbr_n.sum()) + n_sprouts + 1
        if need > cap:
            cap = max(2 * cap, need + 1024)
            nodes = _grow_rows(nodes, cap)
            node_grid = Grid(node_grid.head, np.concatenate([node_grid.nxt, np.full(cap - len(node_grid.nxt), -1, np.int64)]),
                             node_grid.geom)
        n_before = n_nodes
        n_nodes = grow_veins(closed, live, nbr, nbr_n, src, nodes, n_nodes, D, dk2, node_grid, it, sp.inside, base,
                             np.ascontiguousarray(blade_scale, dtype=np.float64), blade.bands)
        if n_sprouts:
            ended_rows = np.zeros((n_sprouts, 2), np.int64)
            n_nodes, n_sprouts, ended = grow_sprouts(sprouts, n_sprouts, nodes, n_nodes, D, gap2, node_grid, it,
                                                     ended_rows)
            blind_ends += ended
            for k_, (t_, u_) in enumerate(ended_rows[:ended].tolist()):
                p_ = real(nodes.pos[t_], lam)
                events.append((it, "blind_end", blind_ends - ended + k_ + 1, float(p_[0]), float(p_[1]),
                               float(math.dist(nodes.pos[t_], nodes.pos[u_]) / lam)))
        if n_nodes > n_before:
            hull_support(nodes.pos, n_before, n_nodes, support)
            new = nodes.pos[n_before:n_nodes]
            if np.any(new < lo) or np.any(new > hi):
                lo = np.minimum(lo, new.min(0) - pad)
                hi = np.maximum(hi, new.max(0) + pad)
                node_grid = make_grid(lo, hi, node_grid.geom[2], cap)
                grid_rebuild(node_grid, nodes.pos, np.arange(n_nodes, dtype=np.int64))
                src_grid = make_grid(lo, hi, node_grid.geom[2], scap)
                live_now = np.flatnonzero(src.alive[:n_src]).astype(np.int64)
                grid_insert_idx(src_grid, src.pos, live_now)
                live = live_now
        if ltg is not None:  # the new nodes and sources at t0 (eq. 5.1 solved for y0) or their (u, v) (eq. 5.2)
            if n_nodes > len(node_mat):
                node_mat = np.vstack([node_mat, ltg.inverse(nodes.pos[len(node_mat):n_nodes], t_ltg)])
            if n_src > len(src_mat):
                src_mat = np.vstack([src_mat, ltg.inverse(src.pos[len(src_mat):n_src], t_ltg)])
        timings["growth"] += time.perf_counter() - t2
        it += 1
        if progress is not None:
            progress(1)
        n_alive = int(src.alive[:n_src].sum())
        # a source removed in the iteration it was placed in (a dart between b_v and d_k from a
        # vein, when b_v < d_k) did nothing: it does not keep the run going
        quiet = 0 if placed and src.alive[first_new:n_src].any() else quiet + 1
        idle = 0 if n_nodes > n_before else idle + 1
        done = it >= n_growth and n_alive == 0 and n_sprouts == 0 and quiet >= sp.settle
        if sp.inside and it >= n_growth and idle >= max(sp.settle, 2):
            # veins kept in the blade: darts keep landing where no vein can reach (and their
            # sources are given up); the pattern is done when no vein has grown for settle iterations
            done = True
        if on_frame is not None and frame_step > 0 and ((it - 1) % frame_step == 0 or done):
            on_frame(snapshot(it - 1, lam, sc))
            last_frame = it - 1
        if done:
            break
    if on_frame is not None and frame_step > 0 and last_frame != it - 1:
        on_frame(snapshot(it - 1, lam, growth.scale_at(max(it - 1, 0))))
    sc_end = growth.scale_at(max(it - 1, 0))
    margin = blade.scaled(sc_end if kind != "none" else 1.0) if ltg is None else ltg_margin
    return VenationResult(
        node_pos=real(nodes.pos[:n_nodes], lam), node_parent=nodes.parent[:n_nodes].copy(),
        node_iter=nodes.iteration[:n_nodes].copy(), extra_edges=extra[:n_extra].copy(), blade=margin,
        source_pos=real(src.pos[:n_src], lam), source_born=src.born[:n_src].copy(),
        source_died=src.died[:n_src].copy(), iterations=it, growth_steps=n_growth, stopped=stopped,
        sources_stalled=stalled_total, blind_ends=blind_ends, events=events,
        seconds=time.perf_counter() - t_start, timings=timings)


def _band_darts(blade: Blade, s_prev, s_now, n: int, rng) -> np.ndarray:
    """``n`` points uniform in the band the margin swept from scale ``s_prev`` to ``s_now`` (2,)
    (the whole blade when ``s_prev`` is 0): fan triangles (base, m_i, m_i+1) of the margin picked
    by area, a scale s in [s_prev, s_now] with density proportional to s, and a uniform point of the
    scaled edge: x = base + s (m_i + u (m_i+1 - m_i) - base). Uniform for a blade star-shaped from
    its base; :func:`throw_darts` drops points outside the band otherwise."""
    b = blade.base
    m = blade.polygon - b
    q = np.roll(m, -1, axis=0)
    area = 0.5 * (m[:, 0] * q[:, 1] - m[:, 1] * q[:, 0])
    w = np.maximum(area, 0.0)
    if n <= 0 or w.sum() <= 0:
        return np.zeros((0, 2))
    tri = rng.choice(len(m), size=n, p=w / w.sum())
    u = rng.random(n)
    r0 = float(s_prev[0]) / float(s_now[0])  # isotropic: marginal growth
    f = np.sqrt(r0 ** 2 + (1.0 - r0 ** 2) * rng.random(n))  # s / s_now in [r0, 1], density ∝ s
    edge = m[tri] + u[:, None] * (q[tri] - m[tri])
    return np.ascontiguousarray(b + edge * np.asarray(s_now, dtype=np.float64) * f[:, None])


def _min_h(lo, hi, max_cells=1 << 20):
    ext = np.maximum(hi - lo, 1e-12)
    return math.sqrt(ext[0] * ext[1] / max_cells)
