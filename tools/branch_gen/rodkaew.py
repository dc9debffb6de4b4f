"""Extended Rodkaew algorithm: branching structures grown from the florets down (thesis ch. 7, 8 g).

One particle per floret is born at the floret's position at its emergence time and moves toward
the base of its hierarchy level by a step length per simulation step along (eq. 7.1)

    H' = (w_a A + w_b B + w_h H) / (w_a + w_b + w_h),

A the unit vector toward the base, B the unit vector toward the nearest node of another tree
(another particle's current node or any node of a branch traced before: "attraction to
branches"), H the particle's previous direction. ``w_b`` may be a function of the distance d to
that neighbour (``.func`` file, fig. 7.4). Every particle is the root of its own tree of nodes
(8 g); a particle closer than the merge distance to another tree grafts its tree onto it, and the
branch id of that tree propagates through the grafted one (fig. 7.5) -- here by a union-find over
branch ids -- so a tree never attracts or merges with itself. A particle within one step or the
merge distance of its base joins it (a closer criterion lets a particle with much inertia w_h
circle its base).

Nearest-neighbour queries go through a spatial hash of the tree nodes (Teschner et al., as in the
thesis), searched in rings of cells around the particle and updated as nodes are created.

Hierarchy levels (fig. 7.2b): florets of a group (umbellet, head) converge on the group's centre;
the group centres are particles of the level above, born when the first floret of the group
emerges, converging on their parent group's centre or on the base.

Growth (7.2 "Growth"): at every frame boundary the whole space (nodes, particles, targets) is
scaled about the base by S(f+1)/S(f) (:func:`~inflo.tools.branch_gen.skeleton.growth_scale`), so a
floret born at frame f starts at base + (pos - base) S(f)/S(end) and ends exactly at its position.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from inflo.formats.errors import InputError
from inflo.tools.common import linalg as la

from .skeleton import Skeleton, growth_scale

__all__ = ["RodkaewInput", "grow_rodkaew", "grow_level", "Level", "heading"]

_NO_PARENT = -1
_NOT_LINKED = np.iinfo(np.int64).max  # link step of a node not yet linked to a parent


# --------------------------------------------------------------------------------------------
# what the kernels share (NamedTuples of arrays: numba passes them as one argument, its fields
# typed separately; every field has one dtype and layout, so a kernel compiles once)


class Nodes(NamedTuple):
    """The nodes v of one level's trees (capacity rows; the first n_nodes are in use; 0 is the root)."""

    pos: np.ndarray  # (cap, 3) float64
    parent: np.ndarray  # (cap,) int64: the next node toward the base, -1 none (yet)
    branch: np.ndarray  # (cap,) int64: the particle whose tree made the node, -1 for the root
    step: np.ndarray  # (cap,) int64: simulation step of its creation
    link_step: np.ndarray  # (cap,) int64: step at which it got its parent (_NOT_LINKED: not yet)


class Particles(NamedTuple):
    """The particles i of one level (one per tree)."""

    head: np.ndarray  # (k,) int64: the particle's current node, -1 before birth
    dir: np.ndarray  # (k, 3) float64: its previous direction H (unit)
    active: np.ndarray  # (k,) bool: born and still moving
    uf: np.ndarray  # (k,) int64: union-find over tree ids; _find(uf, i) labels particle i's tree


class HashGrid(NamedTuple):
    """The spatial hash of the nodes: cells of side h, chains ``head[bucket]`` -> ``next[v]`` -> ... -> -1."""

    head: np.ndarray  # (mask + 1,) int64: first node of each bucket
    next: np.ndarray  # (cap,) int64: next node in the same bucket
    mask: int  # buckets - 1 (a power of two minus one)
    h: float  # cell side
    inv_h: float  # 1 / h


class RodkaewConstants(NamedTuple):
    """The scalars of a level's run: step length, merge distance, eq. 7.1 weights, w_b(d), the search."""

    step: float  # step length per simulation step
    merge: float  # merge distance (fig. 7.5b)
    w_a: float  # eq. 7.1 weight of A
    w_b: float  # eq. 7.1 weight of B (times w_b(d) from wb_table)
    w_h: float  # eq. 7.1 weight of H
    wb_table: np.ndarray  # (s,) float64: samples of w_b(d) over d / w_b_range in [0, 1] (fig. 7.4)
    w_b_range: float
    perception: float  # B is the nearest other tree within this distance (inf allowed)
    rmax: int  # rings of cells the nearest-other-tree search may visit


# --------------------------------------------------------------------------------------------
# kernels


@njit(cache=True)
def _hash(ix, iy, iz, mask):
    return ((ix * 73856093) ^ (iy * 19349663) ^ (iz * 83492791)) & mask


@njit(cache=True)
def _cell(x, inv_h):
    return np.int64(math.floor(x * inv_h))


@njit(cache=True)
def _grid_insert(v, node_pos, inv_h, grid_head, grid_next, mask):
    b = _hash(_cell(node_pos[v, 0], inv_h), _cell(node_pos[v, 1], inv_h), _cell(node_pos[v, 2], inv_h), mask)
    grid_next[v] = grid_head[b]
    grid_head[b] = v


@njit(cache=True)
def _grid_rebuild(n_nodes, node_branch, node_pos, inv_h, grid_head, grid_next, mask):
    grid_head[:] = -1
    for v in range(n_nodes):
        if node_branch[v] >= 0:
            _grid_insert(v, node_pos, inv_h, grid_head, grid_next, mask)


@njit(cache=True)
def _find(uf, a):
    root = a
    while uf[root] != root:
        root = uf[root]
    while uf[a] != root:
        nxt = uf[a]
        uf[a] = root
        a = nxt
    return root


@njit(cache=True)
def _nearest_other(p, label, node_pos, node_branch, uf, grid_head, grid_next, mask, h, inv_h, radius, rmax,
                   n_nodes):
    """Nearest node whose tree (find(branch)) differs from ``label``, within ``radius``.

    Rings of cells at Chebyshev distance r = 0, 1, ... around p's cell; a node in ring r is at
    least (r - 1) h away, which ends the search once a node that near is found. When the rings
    would visit more cells than there are nodes (sparse early stages), the remaining search is a
    scan of all nodes instead. Returns (node or -1, squared distance).
    """
    cx = _cell(p[0], inv_h)
    cy = _cell(p[1], inv_h)
    cz = _cell(p[2], inv_h)
    r2 = radius * radius if radius < 1e150 else 1e300
    best = r2
    best_q = -1
    r_cap = int(0.5 * n_nodes ** (1.0 / 3.0)) + 2
    if r_cap > rmax:
        r_cap = rmax
    done = False
    for r in range(r_cap + 1):
        lb = (r - 1) * h
        if r >= 2 and lb * lb >= best:
            done = True
            break
        for dx in range(-r, r + 1):
            for dy in range(-r, r + 1):
                edge = r == 0 or abs(dx) == r or abs(dy) == r
                dz = -r
                while dz <= r:
                    v = grid_head[_hash(cx + dx, cy + dy, cz + dz, mask)]
                    while v >= 0:
                        if _find(uf, node_branch[v]) != label:
                            ex = node_pos[v, 0] - p[0]
                            ey = node_pos[v, 1] - p[1]
                            ez = node_pos[v, 2] - p[2]
                            d2 = ex * ex + ey * ey + ez * ez
                            if d2 < best or (d2 == best and best_q >= 0 and v < best_q):
                                best = d2
                                best_q = v
                        v = grid_next[v]
                    if edge:
                        dz += 1
                    else:
                        dz += 2 * r
    if not done and r_cap < rmax:
        lb = r_cap * h
        if not (lb * lb >= best):
            for v in range(n_nodes):
                if node_branch[v] < 0:
                    continue
                ex = node_pos[v, 0] - p[0]
                ey = node_pos[v, 1] - p[1]
                ez = node_pos[v, 2] - p[2]
                d2 = ex * ex + ey * ey + ez * ez
                if d2 < best or (d2 == best and best_q >= 0 and v < best_q):
                    if _find(uf, node_branch[v]) != label:
                        best = d2
                        best_q = v
    return best_q, best


@njit(cache=True)
def heading(a, b, h, w_a, w_b, w_h):
    """Eq. 7.1: H' = (w_a A + w_b B + w_h H) / (w_a + w_b + w_h), A, B, H unit (3,) vectors."""
    return (w_a * a + w_b * b + w_h * h) / (w_a + w_b + w_h)


@njit(cache=True)
def _wb_of(d, w_b, wb_table, w_b_range):
    s = wb_table.shape[0]
    x = d / w_b_range
    if x < 0.0:
        x = 0.0
    if x > 1.0:
        x = 1.0
    idx = x * (s - 1)
    i = int(math.floor(idx))
    if i > s - 2:
        i = s - 2
    t = idx - i
    return w_b * ((1.0 - t) * wb_table[i] + t * wb_table[i + 1])


@njit(cache=True)
def _advance(step_begin, step_end, n_nodes, target, root_node, nodes, parts, grid, const):
    """Move every active particle (in index order) for steps [step_begin, step_end) (eq. 7.1, fig. 7.5).

    A particle within a step or the merge distance of ``target`` links to ``root_node``; one within
    the merge distance of another tree grafts onto it; the others step along H' (eq. 7.1), each
    step a new node of its tree (``nodes``, hashed into ``grid``).
    Returns (next step, node count, active count). Stops early when no particle is active.
    """
    node_pos, node_parent, node_branch = nodes.pos, nodes.parent, nodes.branch
    node_step, node_link_step = nodes.step, nodes.link_step
    part_head, part_dir, part_active, uf = parts.head, parts.dir, parts.active, parts.uf
    grid_head, grid_next, mask, h, inv_h = grid.head, grid.next, grid.mask, grid.h, grid.inv_h
    step_len, merge, w_a, w_b, w_h = const.step, const.merge, const.w_a, const.w_b, const.w_h
    wb_table, w_b_range, perception, rmax = const.wb_table, const.w_b_range, const.perception, const.rmax
    n_part = part_head.shape[0]
    n_active = 0
    reach = max(step_len, merge)
    s = step_begin
    while s < step_end:
        n_active = 0
        for i in range(n_part):
            if not part_active[i]:
                continue
            v = part_head[i]
            p = node_pos[v].copy()
            to_t = target - p
            dt = np.sqrt(to_t[0] ** 2 + to_t[1] ** 2 + to_t[2] ** 2)
            if dt <= reach:  # reached the base of its level (within a step or the merge distance)
                node_parent[v] = root_node
                node_link_step[v] = s
                part_active[i] = False
                continue
            a = to_t / dt
            label = _find(uf, i)
            q, d2 = _nearest_other(p, label, node_pos, node_branch, uf, grid_head, grid_next, mask, h, inv_h,
                                   perception, rmax, n_nodes)
            bvec = np.zeros(3)
            wb = 0.0
            if q >= 0:
                d = np.sqrt(d2)
                if d <= merge:  # graft onto the other tree (fig. 7.5b); its id propagates
                    node_parent[v] = q
                    node_link_step[v] = s
                    part_active[i] = False
                    uf[label] = _find(uf, node_branch[q])
                    continue
                bvec = (node_pos[q] - p) / d
                wb = _wb_of(d, w_b, wb_table, w_b_range)
            hd = heading(a, bvec, part_dir[i], w_a, wb, w_h)
            nrm = np.sqrt(hd[0] ** 2 + hd[1] ** 2 + hd[2] ** 2)
            u = a if nrm < 1e-12 else hd / nrm
            n = n_nodes
            n_nodes += 1
            node_pos[n] = p + step_len * u
            node_parent[n] = -1
            node_branch[n] = i
            node_step[n] = s
            node_parent[v] = n
            node_link_step[v] = s
            _grid_insert(n, node_pos, inv_h, grid_head, grid_next, mask)
            part_head[i] = n
            part_dir[i] = u
            n_active += 1
        s += 1
        if n_active == 0:
            break
    return s, n_nodes, n_active


# --------------------------------------------------------------------------------------------
# one hierarchy level


@dataclass
class Level:
    """The particles of one hierarchy level converging on one target.

    Attributes
    ----------
    target : (3,) float64
        Final position of the level's base (inflorescence base or group centre).
    start : (k, 3) float64
        Final positions of the particles' tips (floret positions or child group centres).
    birth_frame : (k,) float64
        Emergence frame of each particle.
    birth_pos : (k, 3) float64 or None
        Actual positions at birth (from RBA); None: ``start`` scaled by the growth of space.
    initial_dir : (k, 3) float64
        Initial direction H of each particle (unit), or NaN rows for "toward the base".
    """

    target: np.ndarray
    start: np.ndarray
    birth_frame: np.ndarray
    birth_pos: np.ndarray | None
    initial_dir: np.ndarray


@dataclass
class LevelResult:
    node_pos: np.ndarray  # (n, 3) final positions; node 0 is the root (target)
    node_parent: np.ndarray
    node_branch: np.ndarray  # particle index, -1 for the root
    node_frame: np.ndarray
    node_link_frame: np.ndarray
    tip_node: np.ndarray  # (k,) node index of each particle's tip


def grow_level(level: Level, params, *, base, end_frame: float, wb_table=None, progress=None) -> LevelResult:
    """Run the extended Rodkaew algorithm on one hierarchy level.

    Parameters
    ----------
    level : Level
    params : Params
        Uses ``params.rodkaew`` and ``params.growth``.
    base : (3,) float64
        Centre of the growth of space.
    end_frame : float
        Frame at which growth stops.
    wb_table : (s,) float64 or None
        Samples of w_b(d) over x = d / w_b_range in [0, 1] (None: constant 1).
    progress : callable(int) or None
        Called with the number of particles that stopped since the last call.
    """
    rp = params.rodkaew
    gp = params.growth
    base = np.asarray(base, dtype=np.float64)
    k = len(level.start)
    spf = rp.steps_per_frame
    birth_step = np.ceil(np.asarray(level.birth_frame, dtype=np.float64) * spf - 1e-9).astype(np.int64)
    birth_step = np.maximum(birth_step, 0)
    order = np.argsort(birth_step, kind="stable")
    wb_table = np.ones(2) if wb_table is None else np.ascontiguousarray(wb_table, dtype=np.float64)

    def scale(frame):
        return growth_scale(gp.mode, gp.rate, gp.rates, frame, end_frame, gp._functions)

    cap = max(1024, 4 * k)
    nodes = _new_nodes(cap)
    parts = Particles(head=np.full(k, -1, np.int64), dir=np.zeros((k, 3)), active=np.zeros(k, np.bool_),
                      uf=np.arange(k, dtype=np.int64))
    tip_node = np.full(k, -1, np.int64)

    h = max(2.0 * rp.step, rp.merge_distance)
    table_bits = 12
    grid = _new_grid(table_bits, np.full(cap, -1, np.int64), h)

    frame0 = 0.0
    target = base + (level.target - base) * scale(frame0)
    nodes.pos[0] = target  # the root
    n_nodes = 1
    extent = float(np.max(np.ptp(np.vstack([level.start, level.target[None]]), axis=0))) if k else 1.0
    extent = max(extent, h)

    reach = min(rp.perception_radius, 1e6 * extent)
    rmax = int(min(math.ceil(reach * grid.inv_h) + 2, 2**31))
    const = RodkaewConstants(step=float(rp.step), merge=float(rp.merge_distance), w_a=float(rp.w_a),
                             w_b=float(rp.w_b), w_h=float(rp.w_h), wb_table=wb_table, w_b_range=float(rp.w_b_range),
                             perception=float(rp.perception_radius), rmax=rmax)

    def ensure(need):
        nonlocal cap, nodes, table_bits, grid
        if need > cap:
            new_cap = max(need, 2 * cap)
            extra = new_cap - cap
            nodes = Nodes(*(np.concatenate([a, b]) for a, b in zip(nodes, _new_nodes(extra))))
            grid = grid._replace(next=np.concatenate([grid.next, np.full(extra, -1, np.int64)]))
            cap = new_cap
        want_bits = min(24, max(12, int(math.ceil(math.log2(max(2 * cap, 2))))))
        if want_bits > table_bits:
            table_bits = want_bits
            grid = _new_grid(table_bits, grid.next, h)
            _rehash(n_nodes, nodes, grid)

    step = 0
    born = 0
    n_active = 0
    while True:
        frame = step // spf
        frame_end_step = (frame + 1) * spf
        # births due now
        while born < k and birth_step[order[born]] <= step:
            i = order[born]
            ensure(n_nodes + 1)
            if level.birth_pos is not None:
                pos = level.birth_pos[i]
            else:
                pos = base + (level.start[i] - base) * scale(frame)
            v = n_nodes
            n_nodes += 1
            nodes.pos[v] = pos
            nodes.branch[v] = i
            nodes.step[v] = step
            tip_node[i] = v
            parts.head[i] = v
            d0 = level.initial_dir[i]
            if not np.all(np.isfinite(d0)):
                d0 = target - pos
                nn = la.norm(d0)
                d0 = d0 / nn if nn > 0 else np.array([0.0, -1.0, 0.0])
            parts.dir[i] = d0
            parts.active[i] = True
            n_active += 1
            _grid_insert(v, nodes.pos, grid.inv_h, grid.head, grid.next, grid.mask)
            born += 1
        next_birth = int(birth_step[order[born]]) if born < k else np.iinfo(np.int64).max
        if (born == k and n_active == 0) or step >= rp.max_steps:
            break
        stop = max(min(frame_end_step, next_birth, rp.max_steps), step + 1)
        if n_active:
            ensure(n_nodes + n_active * (stop - step) + 1)
            step, n_nodes, _ = _advance(step, stop, n_nodes, target, 0, nodes, parts, grid, const)
            now = int(parts.active.sum())
            if progress is not None and now < n_active:
                progress(n_active - now)
            n_active = now
        if n_active == 0:
            step = stop
        if step == frame_end_step and gp.mode != "none" and frame + 1 <= end_frame:
            # growth of space at the frame boundary: nodes, particles and target alike
            k_scale = scale(frame + 1) / scale(frame)
            nodes.pos[:n_nodes] = base + (nodes.pos[:n_nodes] - base) * k_scale
            target = base + (level.target - base) * scale(frame + 1)
            frame0 = frame + 1
            _rehash(n_nodes, nodes, grid)
    if n_active:
        warnings.warn(f"rodkaew.max_steps = {rp.max_steps} reached with {n_active} particles still moving; "
                      "they are joined to their base by straight segments", UserWarning, stacklevel=2)
        for i in np.nonzero(parts.active)[0]:
            nodes.parent[parts.head[i]] = 0
            nodes.link_step[parts.head[i]] = step
    # bring every node to its final place (growth after the simulation ended) and snap the tips
    node_pos = nodes.pos
    if gp.mode != "none":
        k_scale = scale(end_frame) / scale(frame0)
        node_pos[:n_nodes] = base + (node_pos[:n_nodes] - base) * k_scale
    node_pos[0] = level.target
    node_pos[tip_node] = level.start
    n = n_nodes
    link = nodes.link_step[:n].astype(np.float64)
    link[nodes.parent[:n] < 0] = np.inf
    return LevelResult(
        node_pos=node_pos[:n].copy(),
        node_parent=nodes.parent[:n].copy(),
        node_branch=nodes.branch[:n].copy(),
        node_frame=nodes.step[:n] / spf,
        node_link_frame=link / spf,
        tip_node=tip_node,
    )


def _new_nodes(cap: int) -> Nodes:
    """Room for ``cap`` nodes (no parent, no particle, not linked)."""
    return Nodes(pos=np.zeros((cap, 3)), parent=np.full(cap, -1, np.int64), branch=np.full(cap, -1, np.int64),
                 step=np.zeros(cap, np.int64), link_step=np.full(cap, _NOT_LINKED, np.int64))


def _new_grid(table_bits: int, next_: np.ndarray, h: float) -> HashGrid:
    """An empty spatial hash of 2^table_bits buckets, cells of side ``h``, over the chain array ``next_``."""
    mask = (1 << table_bits) - 1
    return HashGrid(head=np.full(mask + 1, -1, np.int64), next=next_, mask=mask, h=float(h), inv_h=1.0 / h)


def _rehash(n_nodes: int, nodes: Nodes, grid: HashGrid) -> None:
    """Every tree node of the first ``n_nodes`` into ``grid`` anew (after the nodes moved or the table grew)."""
    _grid_rebuild(n_nodes, nodes.branch, nodes.pos, grid.inv_h, grid.head, grid.next, grid.mask)


# --------------------------------------------------------------------------------------------
# the whole inflorescence


@dataclass
class RodkaewInput:
    """Florets and hierarchy, as structure of arrays.

    Attributes
    ----------
    pos : (n, 3) float64
        Final floret positions (attachment points).
    up : (n, 3) float64
        Floret axes (the initial direction is -up unless ``initial_direction = "base"``).
    emergence : (n,) float64
        Emergence frame of each floret (NaN: 0).
    group : (n,) int32
        Hierarchy group of each floret, -1 none.
    groups : dict int -> (centre (3,), parent int)
    birth_pos : (n, 3) float64 or None
        Positions at emergence (first RBA frame of each floret), None without RBA.
    """

    pos: np.ndarray
    up: np.ndarray
    emergence: np.ndarray
    group: np.ndarray
    groups: dict
    birth_pos: np.ndarray | None = None


def _end_frame(inp: RodkaewInput, params, n_frames: int | None) -> float:
    if params.growth.frames >= 0:
        return float(params.growth.frames)
    if n_frames is not None:
        return float(max(n_frames - 1, 0))
    e = np.nan_to_num(inp.emergence, nan=0.0)
    return float(e.max()) if len(e) else 0.0


def grow_rodkaew(inp: RodkaewInput, params, *, wb_table=None, n_frames: int | None = None,
                 progress=None) -> Skeleton:
    """The branching structure supporting the florets (extended Rodkaew algorithm, thesis 7.2).

    With ``params.rodkaew.hierarchy`` and groups in the scene, each group's florets converge on
    the group centre, each group centre (a particle born at the earliest emergence in the group)
    on its parent's centre or on the base (fig. 7.2b); the levels' skeletons are joined at the
    group centres.

    Returns
    -------
    Skeleton
        Node 0 is the base; floret tips are at the floret positions exactly.
    """
    n = len(inp.pos)
    if n == 0:
        raise InputError("the scene has no florets: nothing to support")
    base = np.asarray(params.base, dtype=np.float64)
    end_frame = _end_frame(inp, params, n_frames)
    emergence = np.nan_to_num(np.asarray(inp.emergence, dtype=np.float64), nan=0.0)
    up = np.asarray(inp.up, dtype=np.float64)
    up = up / la.norm(up, axis=1, keepdims=True)
    floret_dir = -up if params.rodkaew.initial_direction == "floret" else np.full((n, 3), np.nan)

    use_groups = params.rodkaew.hierarchy and len(inp.groups) > 0
    group_of = np.where(use_groups, np.asarray(inp.group), -1) if n else np.zeros(0, np.int64)
    # level key: -1 = base, g = group g; members are ("f", i) florets or ("g", g) groups
    members: dict[int, list] = {}
    for i in range(n):
        members.setdefault(int(group_of[i]), []).append(("f", i))
    if use_groups:
        # every group that holds florets (directly or below) is a particle of its parent level
        def parent_key(g):
            par = inp.groups[g][1]
            return par if par in inp.groups else -1

        active = set()
        for g in list(members):
            while g != -1 and g not in active:
                active.add(g)
                g = parent_key(g)
        for g in sorted(active):
            members.setdefault(parent_key(g), []).append(("g", g))
    # emergence of a group: earliest emergence below it
    group_birth: dict[int, float] = {}

    def birth_of(item):
        kind, x = item
        if kind == "f":
            return float(emergence[x])
        if x not in group_birth:
            group_birth[x] = min(birth_of(m) for m in members.get(x, []))
        return group_birth[x]

    def centre(key):
        return base if key == -1 else np.asarray(inp.groups[key][0], dtype=np.float64)

    results = {}
    keys = sorted(members)
    for key in keys:
        items = members[key]
        start = np.array([inp.pos[x] if kd == "f" else centre(x) for kd, x in items], dtype=np.float64).reshape(-1, 3)
        birth = np.array([birth_of(it) for it in items])
        init = np.array([floret_dir[x] if kd == "f" else np.full(3, np.nan) for kd, x in items]).reshape(-1, 3)
        birth_pos = None
        if inp.birth_pos is not None:
            birth_pos = np.array([inp.birth_pos[x] if kd == "f"
                                  else base + (centre(x) - base) * growth_scale(
                                      params.growth.mode, params.growth.rate, params.growth.rates,
                                      math.floor(birth_of((kd, x))), end_frame, params.growth._functions)
                                  for kd, x in items]).reshape(-1, 3)
        level = Level(target=centre(key), start=start, birth_frame=birth, birth_pos=birth_pos, initial_dir=init)
        results[key] = (items, grow_level(level, params, base=base, end_frame=end_frame, wb_table=wb_table,
                                          progress=progress))
    return _join_levels(results, base, n)


def _join_levels(results, base, n_florets) -> Skeleton:
    """Concatenate the levels; the root of group g's level is the tip of g's particle above."""
    offsets, total = {}, 0
    for key in sorted(results):
        offsets[key] = total
        total += len(results[key][1].node_pos)
    remap = np.arange(total, dtype=np.int64)
    group_tip = {}
    for key in sorted(results):
        items, res = results[key]
        for j, (kd, x) in enumerate(items):
            if kd == "g":
                group_tip[x] = offsets[key] + res.tip_node[j]
    for key in sorted(results):
        if key != -1:
            remap[offsets[key]] = group_tip[key]
    pos, parent, branch, frame, link, tip, floret = [], [], [], [], [], [], []
    for key in sorted(results):
        items, res = results[key]
        o = offsets[key]
        m = len(res.node_pos)
        pos.append(res.node_pos)
        par = np.where(res.node_parent >= 0, remap[np.maximum(res.node_parent, 0) + o], -1)
        parent.append(par)
        branch.append(res.node_branch)
        frame.append(res.node_frame)
        link.append(res.node_link_frame)
        t = np.zeros(m, bool)
        fl = np.full(m, -1, np.int64)
        for j, (kd, x) in enumerate(items):
            if kd == "f":
                t[res.tip_node[j]] = True
                fl[res.tip_node[j]] = x
        tip.append(t)
        floret.append(fl)
    pos = np.vstack(pos)
    parent = np.concatenate(parent)
    keep = remap == np.arange(total)  # drop the level roots that were merged into group tips
    new_index = np.cumsum(keep) - 1
    parent = np.where(parent >= 0, new_index[np.maximum(parent, 0)], -1)
    sel = np.nonzero(keep)[0]
    return Skeleton(
        node_pos=pos[sel],
        node_parent=parent[sel],
        node_tip=np.concatenate(tip)[sel],
        node_floret=np.concatenate(floret)[sel],
        node_frame=np.concatenate(frame)[sel],
        node_link_frame=np.concatenate(link)[sel],
        node_branch=np.concatenate(branch)[sel],
        base=np.asarray(base, dtype=np.float64),
    )
