"""thyrse as library functions: parameters in, the branching skeleton, the florets' scene and the
generalized cylinders out (branching-first, thesis ch. 7's contrast with the florets-first
branch-gen; sec. 4.5, figs. 4.9, 4.10).

:func:`grow_thyrse` lays out the architecture: a main axis along +Y from ``base`` with
``nodes`` decussate node pairs (opposite laterals, successive pairs turned by ``divergence``);
the lateral at relative height x of the main axis has

- length ``length * lateral_length(x)``, branch angle ``angle(x)`` from its parent axis,
- branching order ``round(order(x))``: a lateral of order k > 0 carries decussate node pairs of
  laterals of order k - 1 (length ``parent_length * lateral_length(t)``, t the node's relative
  position on its parent: the same positional function, self-similarly; angle ``sub_angle(t)``
  when given, else ``angle(x)``), one of order 0 carries node pairs of pedicels with a floret each,
- with ``outward``, a lateral's children that would point towards the main axis not formed (the
  florets fill the panicle's outside),
- with ``min_distance`` > 0, a floret whose limb point (``pos + reach * size * up``) would come
  closer than ``min_distance`` floret sizes to one placed before is not formed (no room: in the
  order of the layout, basal first),
- ``round(L * density(x))`` node pairs on a lateral of length L (the floret density; a lateral
  that carries laterals: ``branch_density(x)`` when given),
- a pedicel with a floret where a lateral of a lateral would be shorter than two pedicels,

and every axis ends in a terminal floret. Positions are the positional information of
Prusinkiewicz et al.'s lilac model (functions of the relative position along the axis, ``.func``
files). :func:`thyrse_scene` places the florets (``ca:`` placements: ``up`` along the pedicel
turned towards +Y by ``tropism`` (the florets face up and out),
``right`` towards the tip of the parent axis, size ``floret_size(h)``, development window from
``start(h)``, h the floret's relative height: the lower florets open first), and
:func:`thyrse` adds the branch meshes with branch-gen's own code
(:func:`inflo.tools.branch_gen.generate.skeleton_geometry`: pipe-model radii, generalized
cylinders) and :func:`write_thyrse` writes them with branch-gen's writer.

The layout is a few thousand nodes at most, built once: plain numpy, no kernel to compile.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from inflo.formats.errors import InputError
from inflo.formats.obj import ObjMesh, write_obj
from inflo.formats.scn import Placement, Scene, write_scn
from inflo.tools.branch_gen.generate import OUTPUT_FILES as BRANCH_GEN_FILES
from inflo.tools.branch_gen.generate import BranchResult, skeleton_geometry, write_branch_gen
from inflo.tools.branch_gen.skeleton import Skeleton
from inflo.tools.common import linalg as la

from .params import Params

__all__ = ["ThyrseLayout", "grow_thyrse", "thyrse_scene", "thyrse", "write_thyrse", "node_directions",
           "SurfaceField", "variation"]

Y = np.array([0.0, 1.0, 0.0])
#: ``outward``: a child whose unit direction steps more than this towards the main axis is not formed
INWARD = math.sin(math.radians(10.0))


@dataclass
class ThyrseLayout:
    """The architecture: a skeleton forest (branch-gen's conventions) and its florets.

    Attributes
    ----------
    node_pos : (n, 3) float64
    node_parent : (n,) int64, -1 at the base
    node_tip : (n,) bool, a floret's attachment point
    node_floret : (n,) int64, the floret index at a tip, -1 elsewhere
    floret_node : (m,) int64
    floret_up : (m, 3) float64, unit: the direction of its stalk turned towards +Y by ``tropism``
    floret_right : (m, 3) float64, unit, orthogonal to ``floret_up``: towards the parent axis' tip
    floret_order : (m,) int64, the order of the axis carrying it (-1: a pedicel's floret)
    node_x : (n,) float64, the main-axis height (positional value) each node inherits
    floret_factor : (m,) float64, the floret's seeded size factor (:func:`variation`)
    floret_offset : (m,) int64, its seeded start offset in frames
    """

    node_pos: np.ndarray
    node_parent: np.ndarray
    node_tip: np.ndarray
    node_floret: np.ndarray
    floret_node: np.ndarray
    floret_up: np.ndarray
    floret_right: np.ndarray
    floret_order: np.ndarray
    node_x: np.ndarray
    floret_factor: np.ndarray = None
    floret_offset: np.ndarray = None

    @property
    def floret_pos(self) -> np.ndarray:
        return self.node_pos[self.floret_node]


def _unit(v):
    return la.normalize(v)


def perpendicular_basis(d):
    """Two unit vectors (e1, e2) with (e1, e2, d) right-handed orthonormal; e1 horizontal where it can be."""
    d = _unit(np.asarray(d, float))
    ref = np.array([0.0, 0.0, 1.0]) if abs(d[1]) > 0.999 else Y
    e1 = _unit(np.cross(ref, d))
    e2 = np.cross(d, e1)
    return e1, e2


def node_directions(axis, angle_deg: float, azimuth_deg: float):
    """The two opposite children of a decussate node: unit directions at ``angle_deg`` from ``axis``,
    at azimuth ``azimuth_deg`` and ``azimuth_deg + 180`` about it (in :func:`perpendicular_basis`)."""
    axis = _unit(np.asarray(axis, float))
    e1, e2 = perpendicular_basis(axis)
    a = math.radians(angle_deg)
    out = []
    for phi in (azimuth_deg, azimuth_deg + 180.0):
        f = math.radians(phi)
        out.append(_unit(math.cos(a) * axis + math.sin(a) * (math.cos(f) * e1 + math.sin(f) * e2)))
    return out


class _Builder:
    """Collects nodes and florets in lists and turns them into arrays once (:meth:`finalize`)."""

    def __init__(self, p: Params, normals=None, spacing: bool = True):
        self.p = p
        self.f = p.functions
        self.normals = normals  # facing = "surface": the outward normal at a point (SurfaceField)
        self.spacing = spacing  # apply min_distance
        self.pos, self.parent, self.x = [], [], []
        self.fl_node, self.fl_up, self.fl_right, self.fl_order = [], [], [], []
        self.limb = []  # (limb point, size) of the florets placed (min_distance)

    def node(self, pos, parent: int, x: float) -> int:
        self.pos.append(np.asarray(pos, float))
        self.parent.append(parent)
        self.x.append(x)
        return len(self.pos) - 1

    def fits(self, pos, up) -> bool:
        """With ``min_distance`` > 0: is this floret's limb point (``pos + reach * size * up``) at
        least ``min_distance`` floret sizes from every limb point placed before? (A floret that
        does not fit is not formed: its pedicel is not either; an axis' terminal floret leaves a
        bare tip.) Records the point when it fits."""
        tp = self.p.thyrse
        if tp.min_distance <= 0 or not self.spacing:
            return True
        h = min(max(la.dot(np.asarray(pos, float) - np.asarray(self.p.base, float), Y) / tp.length, 0.0), 1.0)
        size = float(self.f["floret_size"](h))
        q = np.asarray(pos, float) + tp.reach * size * _unit(np.asarray(up, float))
        if self.limb:
            pts = np.array([a for a, _ in self.limb])
            sz = np.array([b for _, b in self.limb])
            if np.any(la.norm(pts - q, axis=1) < tp.min_distance * 0.5 * (sz + size)):
                return False
        self.limb.append((q, size))
        return True

    def floret(self, node: int, up, axis, fallback, order: int) -> None:
        up = _unit(np.asarray(up, float))
        r = np.asarray(axis, float) - la.dot(axis, up) * up
        if la.norm(r) < 1e-6:
            r = np.asarray(fallback, float) - la.dot(fallback, up) * up
        self.fl_node.append(node)
        self.fl_up.append(up)
        self.fl_right.append(_unit(r))
        self.fl_order.append(order)

    def outward(self, dirs, node: int, main: bool):
        """With ``outward``, a lateral's children that would point towards the main axis (their
        horizontal step towards it more than ``sin(10 deg)``) are not formed: the florets and
        branches fill the panicle's outside, the inside keeps to the main axis."""
        if main or not self.p.thyrse.outward:
            return dirs
        r = self.pos[node] - np.asarray(self.p.base, float)
        r[1] = 0.0
        if la.norm(r) < 1e-12:
            return dirs
        r = r / la.norm(r)
        return [c for c in dirs if la.dot(c, r) > -INWARD]

    def turn_up(self, d, pos):
        """A floret's axis: its stalk's direction (with ``facing = "surface"``: turned towards the
        panicle's outward normal at ``pos`` by ``surface_weight``) turned towards +Y by ``tropism``."""
        tp = self.p.thyrse
        t = tp.tropism
        if self.normals is not None:
            d = _unit(d + tp.surface_weight * self.normals(np.asarray(pos, float)[None, :])[0])
        return _unit(d + t * Y) if t > 0 else d

    def axis(self, start: int, d, length: float, order: int, x: float, phase: float, n_pairs: int,
             node_t=None, main: bool = False) -> None:
        """An axis from node ``start`` along ``d``: its node pairs, their children, its terminal floret."""
        tp = self.p.thyrse
        f = self.f
        p0 = self.pos[start]
        ts = node_t if node_t is not None else [(j + 1) / (n_pairs + 1) for j in range(n_pairs)]
        prev = start
        e1, _ = perpendicular_basis(d)
        for j, t in enumerate(ts):
            xj = t if main else x
            k = self.node(p0 + d * (t * length), prev, xj)
            prev = k
            az = phase + j * tp.divergence
            if main:
                child_order = int(round(f["order"](xj)))
                child_len = length * f["lateral_length"](xj)
                ang = f["angle"](xj)
            else:
                child_order = order - 1
                child_len = length * f["lateral_length"](t)
                ang = f["sub_angle"](t) if "sub_angle" in f else f["angle"](x)
            # pedicels with florets on an order-0 axis, and where a lateral would be shorter than
            # two pedicels (the tip of a branched lateral)
            if child_order < 0 or (not main and child_len < 2.0 * tp.pedicel_length):
                for c in self.outward(node_directions(d, tp.pedicel_angle, az), k, main):
                    end = self.pos[k] + c * tp.pedicel_length
                    u = self.turn_up(c, end)
                    if self.normals is None:
                        if self.fits(end, u):
                            self.floret(self.node(end, k, xj), u, d, e1, -1)
                        continue
                    # facing the surface: the pedicel bends halfway from its direction to the
                    # floret's axis (the tube continues it); one pointing into the panicle (its
                    # floret would face away from its own stalk) is not formed
                    if la.dot(c, u) <= 0.0:
                        continue
                    mid = self.pos[k] + c * (0.5 * tp.pedicel_length)
                    end = mid + u * (0.5 * tp.pedicel_length)
                    if self.fits(end, u):
                        self.floret(self.node(end, self.node(mid, k, xj), xj), u, d, e1, -1)
            else:
                for c in self.outward(node_directions(d, ang, az), k, main):
                    dens = f["branch_density"] if child_order > 0 and "branch_density" in f else f["density"]
                    n = int(round(child_len * dens(xj)))
                    self.axis(k, c, child_len, child_order, xj, az + 90.0, n)
        tip = self.node(p0 + d * length, prev, x if not main else 1.0)
        if self.normals is not None:
            # facing the surface: the floret on a half-pedicel along its axis, beyond the tip
            u = self.turn_up(d, self.pos[tip])
            end = self.pos[tip] + u * (0.5 * tp.pedicel_length)
            if la.dot(d, u) > 0.0 and self.fits(end, u):
                self.floret(self.node(end, tip, self.x[tip]), u, d, e1, order)
            return
        u = self.turn_up(d, self.pos[tip]) if not main else d
        if self.fits(self.pos[tip], u):
            self.floret(tip, u, d, e1, order)

    def finalize(self) -> ThyrseLayout:
        """The arrays; direction components below 1e-12 (rounding noise of the rotations) set to 0."""
        n = len(self.pos)
        for lst in (self.fl_up, self.fl_right):
            for v in lst:
                v[np.abs(v) < 1e-12] = 0.0
        node_floret = np.full(n, -1, np.int64)
        fl = np.asarray(self.fl_node, np.int64)
        node_floret[fl] = np.arange(len(fl))
        return ThyrseLayout(node_pos=np.array(self.pos).reshape(n, 3), node_parent=np.asarray(self.parent, np.int64),
                            node_tip=node_floret >= 0, node_floret=node_floret, floret_node=fl,
                            floret_up=np.array(self.fl_up).reshape(-1, 3),
                            floret_right=np.array(self.fl_right).reshape(-1, 3),
                            floret_order=np.asarray(self.fl_order, np.int64), node_x=np.asarray(self.x, float))


def grow_thyrse(p: Params) -> ThyrseLayout:
    """The architecture of a thyrse (see the module docstring).

    Node 0 is the base; the main axis' node pairs sit at relative heights
    ``first_node + (1 - first_node) j / nodes``, j = 0..nodes-1, its terminal floret at the apex.
    With ``facing = "surface"`` the layout is made twice: first without ``min_distance``, every
    floret position the architecture offers giving the panicle's surface (:class:`SurfaceField`),
    then with each floret's axis its outward normal there (plus ``tropism`` * Y) and
    ``min_distance`` applied to the limb points along those axes.
    """
    tp = p.thyrse
    normals = None
    if tp.facing == "surface":
        first = _layout(_Builder(p, spacing=False))
        if len(first.floret_node) >= 4:
            normals = SurfaceField(first.floret_pos, SURFACE_SIGMA * tp.length)
    lay = _layout(_Builder(p, normals=normals))
    lay.floret_factor, lay.floret_offset = variation(p, len(lay.floret_node))
    return lay


#: the most nodes (axes' nodes, pedicels and florets) a layout may have, checked by counting before
#: any is placed (formats/thyrse.md, "Bounds")
MAX_NODES = 1_000_000


def estimate_nodes(p, limit: int = MAX_NODES) -> int:
    """An upper bound of the nodes :func:`_layout` makes (two directions a node pair, a pedicel two
    nodes), counted without geometry; stops counting past ``limit``."""
    tp, f = p.thyrse, p.functions
    count = [1]

    def add(n):
        count[0] += n
        if count[0] > limit:
            raise OverflowError

    def axis(length, order, x, n_pairs, node_t=None, main=False):
        ts = node_t if node_t is not None else [(j + 1) / (n_pairs + 1) for j in range(n_pairs)]
        for t in ts:
            xj = t if main else x
            add(1)
            if main:
                child_order = int(round(f["order"](xj)))
                child_len = length * f["lateral_length"](xj)
            else:
                child_order = order - 1
                child_len = length * f["lateral_length"](t)
            if child_order < 0 or (not main and child_len < 2.0 * tp.pedicel_length):
                add(4)
            else:
                dens = f["branch_density"] if child_order > 0 and "branch_density" in f else f["density"]
                n = int(round(child_len * dens(xj)))
                for _ in range(2):
                    axis(child_len, child_order, xj, n)
        add(2)

    ts = [tp.first_node + (1 - tp.first_node) * j / max(tp.nodes, 1) for j in range(tp.nodes)]
    try:
        axis(tp.length, 99, 0.0, tp.nodes, node_t=ts, main=True)
    except OverflowError:
        return limit + 1
    return count[0]


def _layout(b: _Builder) -> ThyrseLayout:
    tp = b.p.thyrse
    n = estimate_nodes(b.p)
    if n > MAX_NODES:
        raise InputError(f"{b.p.source or 'thyrse'}: expected a thyrse of at most {MAX_NODES} nodes (thyrse.nodes, "
                         f"order, density and lateral_length together), found more than {MAX_NODES} implied")
    base = b.node(np.asarray(b.p.base, float), -1, 0.0)
    ts = [tp.first_node + (1 - tp.first_node) * j / max(tp.nodes, 1) for j in range(tp.nodes)]
    b.axis(base, Y.copy(), tp.length, 99, 0.0, 0.0, tp.nodes, node_t=ts, main=True)
    return b.finalize()


#: ``facing = "surface"``: the width of the smoothing of the hull's facet normals, in main-axis lengths
SURFACE_SIGMA = 0.2


class SurfaceField:
    """The outward normal of a panicle's surface: the convex hull of ``points`` (every floret
    position the architecture offers, ``scipy.spatial.ConvexHull``); the normal at a point q is
    the mean of the hull's facet normals weighted by the facet's area and a Gaussian of the
    distance from q to the facet's centroid (width ``sigma``): a smooth field over a polyhedral
    hull, florets on one facet not all parallel, those at an edge between two facets in between.
    Points in a plane or on a line (no hull) give +Y everywhere."""

    def __init__(self, points, sigma: float):
        from scipy.spatial import ConvexHull, QhullError

        pts = np.ascontiguousarray(points, dtype=np.float64)
        self.sigma = float(sigma)
        try:
            hull = ConvexHull(pts)
        except (QhullError, ValueError):
            self.normal = None
            return
        tri = pts[hull.simplices]
        self.normal = np.ascontiguousarray(hull.equations[:, :3])
        self.area = 0.5 * la.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
        self.centre = tri.mean(axis=1)

    def __call__(self, q) -> np.ndarray:
        """(k, 3) unit normals at the (k, 3) points ``q``."""
        q = np.asarray(q, dtype=np.float64).reshape(-1, 3)
        out = np.tile(Y, (len(q), 1))
        if self.normal is None:
            return out
        for i in range(len(q)):
            d = self.centre - q[i]
            w = self.area * np.exp(-la.rowdot(d, d) / (self.sigma * self.sigma))
            n = la.matmul(w, self.normal)
            ln = la.norm(n)
            if ln > 1e-12:
                out[i] = n / ln
        return out


def floret_heights(layout: ThyrseLayout, p: Params) -> np.ndarray:
    """Each floret's relative height h = (pos - base) . Y / length, clamped to [0, 1]."""
    h = la.matmul(layout.floret_pos - np.asarray(p.base, float), Y) / p.thyrse.length
    return np.clip(h, 0.0, 1.0)


def variation(p: Params, n: int):
    """The seeded per-floret variation, in floret order: (size factors, start offsets).

    Size factors are uniform in ``[1 - size_variation, 1 + size_variation]``, start offsets
    integers uniform in ``[-start_variation, start_variation]`` frames; both from one
    ``numpy.random.Generator(PCG64(seed))`` (the same numbers on every machine), drawn in this
    order whatever the amplitudes, so changing one leaves the other's draw as it was.
    """
    rng = np.random.Generator(np.random.PCG64(p.thyrse.seed))
    u = rng.random(n)
    k = rng.integers(-p.development.start_variation, p.development.start_variation, n, endpoint=True)
    return 1.0 + p.thyrse.size_variation * (2.0 * u - 1.0), k.astype(np.int64)


def development_windows(h, p: Params, offsets=None):
    """(frameStart, frameEnd) per floret: ``start(h) * span`` rounded (``span`` = frames - 1 -
    window unless given), plus the floret's offset (:func:`variation`), clipped to [0, span]; +
    window. A span past frames - 1 - window lets the last windows end after the run (the florets
    at the tip still in bud in the last frame)."""
    d = p.development
    span = d.span if d.span >= 0 else d.frames - 1 - d.window
    s = np.rint(np.asarray(p.functions["start"](np.asarray(h, float))) * span).astype(np.int64)
    if offsets is not None:
        s = s + np.asarray(offsets, np.int64)
    s = np.clip(s, 0, span)
    return s, s + d.window


def thyrse_scene(layout: ThyrseLayout, p: Params) -> Scene:
    """The florets as ``ca:`` placements in floret order, with ``#@ emergence`` (frameStart) and
    ``#@ type: floret``."""
    h = floret_heights(layout, p)
    factor, offset = layout.floret_factor, layout.floret_offset
    if factor is None:
        factor, offset = variation(p, len(h))
    start, end = development_windows(h, p, offset)
    size = np.asarray(p.functions["floret_size"](h), float).reshape(-1) * factor
    out = []
    for k in range(len(layout.floret_node)):
        s = float(size[k])
        out.append(Placement(kind="ca", id=p.thyrse.floret_id, pos=layout.floret_pos[k], scale=(s, s, s),
                             up=layout.floret_up[k], right=layout.floret_right[k], frame_start=int(start[k]),
                             frame_end=int(end[k]), emergence=float(start[k]), type="floret"))
    return Scene(placements=out)


@dataclass
class ThyrseResult:
    layout: ThyrseLayout
    scene: Scene
    branches: BranchResult
    obstacle: ObjMesh | None = None


#: rounds of :func:`thyrse`'s room test (each drops the florets whose model meets the branches)
ROOM_ROUNDS = 4
#: the room test places every floret's models at once: at most this many triangles (memory)
ROOM_MAX_TRIANGLES = 20_000_000


def room_conflicts(scene: Scene, rooms, branches) -> np.ndarray:
    """(m,) bool: the florets whose model (any of ``rooms``: (vertices, faces) in floret units, the
    floret's local frame, e.g. its bud and its open pose) placed as the scene places it
    intersects the branch mesh ``branches`` (exact static test,
    :func:`inflo.tools.collide.intersecting_pairs_between`), and of two florets whose first model
    (the first pose) intersect, the later one."""
    from inflo.tools.collide import intersecting_pairs, intersecting_pairs_between

    m = len(scene.placements)
    bad = np.zeros(m, bool)
    if m == 0 or branches.n_faces == 0:
        return bad
    mats = [pl.matrix() for pl in scene.placements]
    for r, (v, f) in enumerate(rooms):
        v = np.asarray(v, np.float64)
        f = np.asarray(f, np.int64)
        xs = np.concatenate([la.matmul(v, mk[:3, :3].T) + mk[:3, 3] for mk in mats])
        fs = (f[None, :, :] + (np.arange(m) * len(v))[:, None, None]).reshape(-1, 3).astype(np.int32)
        pairs = intersecting_pairs_between(xs, fs, branches.vertices, branches.faces)
        bad[np.unique(pairs[:, 0] // len(f))] = True
        if r == 0:
            # the first model is the floret's first pose: two florets whose first poses meet could
            # not start (fccompose wants a collision-free first frame): the later one goes
            part = np.repeat(np.arange(m), len(f))
            own = intersecting_pairs(xs, fs, tri_part=part)
            a, b = part[own[:, 0]], part[own[:, 1]]
            bad[np.maximum(a, b)[a != b]] = True
    return bad


def drop_florets(lay: ThyrseLayout, drop: np.ndarray) -> ThyrseLayout:
    """The layout without the florets of the (m,) bool ``drop``: each one's node goes, and the
    nodes above it that carried nothing else (its pedicel; an axis tip left bare), up to the first
    node with other children or a floret."""
    n = len(lay.node_pos)
    keep = np.ones(n, bool)
    children = np.bincount(lay.node_parent[lay.node_parent >= 0], minlength=n)
    for k in np.nonzero(drop)[0]:
        node = int(lay.floret_node[k])
        while node > 0 and children[node] == 0 and keep[node]:
            keep[node] = False
            parent = int(lay.node_parent[node])
            children[parent] -= 1
            if lay.node_floret[parent] >= 0 and not drop[lay.node_floret[parent]]:
                break
            node = parent
    new = np.full(n, -1, np.int64)
    new[keep] = np.arange(int(keep.sum()))
    parent = lay.node_parent[keep]
    parent = np.where(parent >= 0, new[np.maximum(parent, 0)], -1)
    fk = ~drop
    fl_node = new[lay.floret_node[fk]]
    node_floret = np.full(int(keep.sum()), -1, np.int64)
    node_floret[fl_node] = np.arange(len(fl_node))
    return ThyrseLayout(node_pos=lay.node_pos[keep], node_parent=parent, node_tip=node_floret >= 0,
                        node_floret=node_floret, floret_node=fl_node, floret_up=lay.floret_up[fk],
                        floret_right=lay.floret_right[fk], floret_order=lay.floret_order[fk],
                        node_x=lay.node_x[keep], floret_factor=lay.floret_factor[fk],
                        floret_offset=lay.floret_offset[fk])


def _with_obstacle(lay: ThyrseLayout, radius, p: Params, mesh: ObjMesh):
    """The obstacle of the branches (:func:`.obstacle.obstacle_mesh`) and the mesh the room test
    uses: the branches and the obstacle together (the obstacle's tubes may be a little wider)."""
    from .obstacle import obstacle_mesh

    ob = obstacle_mesh(lay.node_pos, lay.node_parent, lay.node_tip, radius, sides=p.branches.cylinder.sides,
                       gap=p.obstacle.gap, margin=p.obstacle.margin)
    both = ObjMesh(vertices=np.concatenate([mesh.vertices, ob.vertices]),
                   faces=np.concatenate([mesh.faces, ob.faces + len(mesh.vertices)]).astype(np.int32))
    return ob, both


def thyrse(p: Params, rooms=()) -> ThyrseResult:
    """Layout, scene and branch geometry (branch-gen's pipe model and generalized cylinders).

    ``rooms``: floret models ((vertices, faces) in floret units, e.g. the bud and the open pose);
    with them, a floret whose model, placed as the scene places it, would meet the branch mesh
    has no room and is not formed (:func:`room_conflicts`, :func:`drop_florets`), and the branches
    are made again without it (their pipe-model widths change), up to ``ROOM_ROUNDS`` times: no
    floret starts inside a branch or grows into one undisturbed.

    With ``[obstacle] id`` >= 0 the branches are also an obstacle for fccompose
    (:mod:`.obstacle`): ``result.obstacle``, placed by the scene's last placement (``o:``, that id,
    at the origin, ``#@ type: obstacle``); the room test then takes the obstacle with the branches.
    """
    lay = grow_thyrse(p)
    bp = p.branches
    obstacle = p.obstacle.id >= 0

    def geometry(lay):
        scene = thyrse_scene(lay, p)
        radius, chain_list, skel, mesh = skeleton_geometry(lay.node_pos, lay.node_parent, lay.node_tip, bp)
        ob, test = _with_obstacle(lay, radius, p, mesh) if obstacle else (None, mesh)
        return scene, radius, chain_list, skel, mesh, ob, test

    scene, radius, chain_list, skel, mesh, ob, test = geometry(lay)
    work = len(lay.floret_node) * sum(len(f) for _, f in rooms)
    if work > ROOM_MAX_TRIANGLES:
        raise InputError(f"--room: expected at most {ROOM_MAX_TRIANGLES:,} placed model triangles, found {work:,} "
                         f"({len(lay.floret_node)} florets x {sum(len(f) for _, f in rooms):,} triangles of the models)")
    for _ in range(ROOM_ROUNDS if rooms else 0):
        bad = room_conflicts(scene, rooms, test)
        if not bad.any():
            break
        lay = drop_florets(lay, bad)
        scene, radius, chain_list, skel, mesh, ob, test = geometry(lay)
    if ob is not None:
        scene.placements.append(Placement(kind="o", id=p.obstacle.id, pos=np.zeros(3), scale=(1.0, 1.0, 1.0),
                                          up=Y.copy(), right=np.array([1.0, 0.0, 0.0]), type="obstacle"))
    n = len(lay.node_pos)
    sk = Skeleton(node_pos=lay.node_pos, node_parent=lay.node_parent, node_tip=lay.node_tip,
                  node_floret=lay.node_floret, node_frame=np.zeros(n), node_link_frame=np.zeros(n),
                  node_branch=np.full(n, -1, np.int64), base=np.asarray(p.base, float))
    tp = p.thyrse
    nf = len(lay.floret_node)
    head = (f"thyrse: length {tp.length:g}, {tp.nodes} decussate node pairs, divergence {tp.divergence:g}; "
            f"{nf} florets, {n} nodes")
    br = BranchResult(skeleton=sk, node_pos=lay.node_pos, node_parent=lay.node_parent, node_tip=lay.node_tip,
                      node_radius=radius, chain_list=chain_list, skeleton_mesh=skel, branches_mesh=mesh, header=head)
    return ThyrseResult(layout=lay, scene=scene, branches=br, obstacle=ob)


#: the files :func:`write_thyrse` writes, as patterns relative to its folder
OUTPUT_FILES = (r"scene\.scn", *BRANCH_GEN_FILES, r"obstacle/frame_0000\.obj")


def write_thyrse(out_dir, result: ThyrseResult, p: Params) -> list:
    """Write ``scene.scn`` and branch-gen's ``skeleton.obj``, ``skeleton.radii``, ``branches.obj``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    d = p.development
    head = (f"{result.branches.header}\nca: placements, frameStart..frameEnd = development window "
            f"({d.window} frames of {d.frames}), lower florets first; written by thyrse")
    write_scn(out / "scene.scn", result.scene, header=head)
    written = [out / "scene.scn"] + write_branch_gen(out, result.branches, p.branches)
    if result.obstacle is not None:
        path = out / "obstacle" / "frame_0000.obj"
        path.parent.mkdir(parents=True, exist_ok=True)
        write_obj(path, result.obstacle, header=f"{result.branches.header}\nthe branches as an fccompose obstacle: "
                  f"{len(result.obstacle.groups)} tubes clear of each other (gap {p.obstacle.gap:g}, margin "
                  f"{p.obstacle.margin:g}); written by thyrse")
        written.append(path)
    return written
