"""Grow a bud into an opening flower (Ijiri et al. 2008, fig. 6): the simulation loop.

Per step k = 1 .. keyframes-1 (frame 0 is the bud):

1. **Regional growth** (sec. 4, :func:`.growth.grow_rest_state`): each organ's growth maps at step
   k (its key growth sets interpolated linearly in time, fig. 16) grow every triangle's rest shape:
   new rest edge lengths (eq. 3) and rest dihedral angles (eq. 4).
2. **Global shape** (sec. 5): the position-based dynamics of :mod:`inflo.tools.pbd` in place of the
   paper's implicit Euler + conjugate gradient minimization of eqs. 5-7 (see "PBD instead of
   implicit Euler" in formats/petal_grow.md): ``iterations`` Gauss-Seidel sweeps of the distance
   (eq. 3.11 of the thesis) and signed dihedral bending constraints (eq. 3.13), stiffness from the
   stretch and bend maps weighted by triangle area (sec. 5.1, ``k = a K c_uv``), started from the
   previous keyframe (a static solve: no velocities, sec. 3).
3. **Attachment** (sec. 5.3, fig. 11): every ``match_every`` sweeps, each organ is moved by the
   rigid transformation (shape matching, Mueller et al. 2005) that best maps its base particles
   (uv ``v <= base_v``) onto the bud's base particles turned by the joint angle of step k about
   the organ's joint axis. No particle is fixed.
4. **Collisions** (sec. 5.3, fig. 12): the step from the previous keyframe is made collision-free
   by the project's continuous collision detection and response
   (:func:`inflo.tools.collide.resolve_collisions`, as fccompose and subdivide use it) over all
   organs together: since the bud is intersection-free and every step is, the organs keep the
   order they have in the bud (petals inside sepals; each petal's right side beneath its
   neighbour) without the paper's tracking points.
5. The keyframe is written (constant topology and vertex order) with enough decimals that the
   written numbers are intersection-free too, and tested exactly (``check_every``).
"""
from __future__ import annotations

import csv
import io
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numba
import numpy as np
from numba import njit

from inflo.formats.atomic import frame_name, remove_stale_frames, write_text_atomic
from inflo.formats.errors import InputError
from inflo.formats.obj import ObjMesh, as_written, write_obj
from inflo.tools.collide import intersecting_pairs, resolve_collisions
from inflo.tools.common import linalg as la
from inflo.tools.pbd import mesh_edges, mesh_hinges, project_bending_constraints, project_distance_constraints
from inflo.tools.pbd.solver import bending_residual, distance_residual, edge_lengths, edge_stretch_range, hinge_angles

from .bud import read_bud_obj
from .growth import HINGE_SIGN, grow_rest_state
from .maps import checked_values, triangle_directions, triangle_values
from .params import Params

__all__ = ["Model", "build_model", "Simulation", "run", "GrowResult", "WRITE_FORMATS", "rotation_matrix",
           "shape_match", "joint_angle_at", "LOG_COLUMNS"]

WRITE_FORMATS = ("%.6f", "%.9f", "%.12f", "%.17g")
"""Coordinate formats of a keyframe, tried in turn until the written frame is intersection-free."""

LOG_COLUMNS = ["frame", "step", "joint_deg", "growth", "min_edge_stretch", "max_edge_stretch",
               "distance_rms", "bending_rms_deg", "collisions_found", "collision_rounds", "reverted_vertices",
               "intersecting_pairs", "t_step_s"]


def rotation_matrix(axis, degrees: float) -> np.ndarray:
    """(3, 3) rotation by ``degrees`` about the unit ``axis`` (right-hand rule)."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / la.norm(a)
    t = math.radians(degrees)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(t) * k + (1 - math.cos(t)) * la.matmul(k, k)


def joint_angle_at(schedule, step: float) -> float:
    """Joint angle (degrees) of a ``[(step, degrees), ...]`` schedule: linear between its points,
    constant before the first and after the last (the paper: +23 deg from step 1 to 60, fig. 7)."""
    s = [p[0] for p in schedule]
    d = [p[1] for p in schedule]
    return float(np.interp(step, s, d))


def shape_match(current: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rigid (R, t) minimizing ``sum |R current_i + t - target_i|^2`` (Kabsch; shape matching of
    Mueller et al. 2005 with equal masses, sec. 5.3). ``current``, ``target``: (k, 3).

    Solved by Horn's quaternion form (:func:`inflo.tools.common.linalg.kabsch`), not LAPACK's SVD,
    so a keyframe has the same bits on every processor; a proper rotation for coplanar rings."""
    return la.kabsch(current, target)


@dataclass
class OrganData:
    """One organ in the flower's arrays: its vertex range, base particles, joint and growth keys."""

    name: str
    material: str
    v0: int
    v1: int
    t0: int
    t1: int
    base: np.ndarray            # global vertex ids of the base particles
    base_rest: np.ndarray       # their bud positions
    pivot: np.ndarray
    axis: np.ndarray
    joint: list
    keys: list                  # [(step, dict of per-triangle/edge arrays)]
    layer: int
    beneath: str


@dataclass
class Model:
    """The flower: all organs in one structure-of-arrays mesh (organs share no vertex)."""

    vertex_x: np.ndarray        # (n, 3) bud positions
    vertex_uv: np.ndarray       # (n, 2)
    tri_indices: np.ndarray     # (m, 3) int32
    tri_uv: np.ndarray          # (m, 3, 2)
    edge_indices: np.ndarray    # (e, 2) int32
    tri_edges: np.ndarray       # (m, 3) int64
    edge_interior: np.ndarray   # (e,) bool
    edge_tris: np.ndarray       # (e, 2) int64, -1 for none
    hinge_indices: np.ndarray   # (h, 4) int32
    hinge_edge: np.ndarray      # (h,) int64
    organs: list = field(default_factory=list)
    materials: list = field(default_factory=list)
    face_material: np.ndarray | None = None
    face_group: np.ndarray | None = None


def _placement(o) -> np.ndarray:
    return rotation_matrix([0.0, 1.0, 0.0], o.rotate)


def build_model(params: Params) -> Model:
    """Read the bud meshes, place them, build the constraint topology and the per-triangle
    growth-map values of every key growth set (eq. 1). Raises InputError/FormatError."""
    xs, uvs, tris, organs = [], [], [], []
    nv = nt = 0
    cache = {}
    for o in params.organs:
        key = str(o.mesh)
        if key not in cache:
            cache[key] = read_bud_obj(o.mesh)
        bud = cache[key]
        x = la.matmul(bud.vertices, _placement(o).T) + np.asarray(o.translate)
        xs.append(x)
        uvs.append(bud.uv)
        tris.append(bud.faces + nv)
        base = np.nonzero(bud.uv[:, 1] <= o.base_v + 1e-12)[0]
        if len(base) < 3:
            raise InputError(f"{o.mesh}: organ {o.name!r} has {len(base)} base particles (uv v <= base_v = "
                             f"{o.base_v:g}); expected at least 3 (raise base_v)")
        bx = x[base]
        if o.joint_pivot is not None:
            pivot = np.asarray(o.joint_pivot, dtype=np.float64)
        else:
            pivot = bx.mean(axis=0)
        if o.joint_axis is not None:
            axis = np.asarray(o.joint_axis, dtype=np.float64)
        else:  # the tangent of the receptacle at the organ: +joint angle turns its tip outwards
            radial = np.array([pivot[0], 0.0, pivot[2]])
            if la.norm(radial) < 1e-9:
                radial = np.array([bx[:, 0].mean() - x[:, 0].mean(), 0.0, bx[:, 2].mean() - x[:, 2].mean()])
                radial = -radial if la.norm(radial) > 1e-9 else np.array([1.0, 0.0, 0.0])
            radial /= la.norm(radial)
            axis = np.cross([0.0, 1.0, 0.0], radial)
        if la.norm(axis) < 1e-12:
            raise InputError(f"{params.source}: organ {o.name!r}: joint_axis must not be zero")
        organs.append(OrganData(o.name, o.material, nv, nv + len(x), nt, nt + len(bud.faces), base + nv, bx.copy(),
                                pivot, axis / la.norm(axis), o.joint, [], o.layer, o.beneath))
        nv += len(x)
        nt += len(bud.faces)
    x = np.ascontiguousarray(np.concatenate(xs))
    _check_lengths(params, x)
    uv = np.concatenate(uvs)
    tri = np.ascontiguousarray(np.concatenate(tris), dtype=np.int32)
    edges = mesh_edges(tri)
    # triangle -> edge ids (edge k: corner k -> k+1)
    lut = {}
    for i, (a, b) in enumerate(edges.tolist()):
        lut[(a, b)] = i
    tri_edges = np.empty((len(tri), 3), np.int64)
    edge_tris = np.full((len(edges), 2), -1, np.int64)
    cnt = np.zeros(len(edges), np.int64)
    for t, (a, b, c) in enumerate(tri.tolist()):
        for k, (p, q) in enumerate(((a, b), (b, c), (c, a))):
            e = lut[(p, q) if p < q else (q, p)]
            tri_edges[t, k] = e
            if cnt[e] < 2:
                edge_tris[e, cnt[e]] = t
            cnt[e] += 1
    if (cnt > 2).any():
        raise InputError(f"{params.source}: an organ mesh has an edge shared by {int(cnt.max())} triangles "
                         "(expected a manifold surface)")
    hinges = mesh_hinges(tri)
    lo = np.minimum(hinges[:, 0], hinges[:, 1])
    hi = np.maximum(hinges[:, 0], hinges[:, 1])
    hinge_edge = np.array([lut[(a, b)] for a, b in zip(lo.tolist(), hi.tolist())], np.int64)
    interior = cnt == 2
    tri_uv = uv[tri]
    materials = sorted({o.material for o in organs}, key=[o.material for o in organs].index)
    face_material = np.empty(len(tri), np.int32)
    face_group = np.empty(len(tri), np.int32)
    for i, o in enumerate(organs):
        face_material[o.t0:o.t1] = materials.index(o.material)
        face_group[o.t0:o.t1] = i
    _check_orientation(tri, edge_tris, edges, interior, params.source)
    model = Model(x, uv, tri, np.ascontiguousarray(tri_uv), edges, tri_edges, interior, edge_tris,
                  hinges, hinge_edge, organs, materials, face_material, face_group)
    for o_par, o in zip(params.organs, organs):
        for step, name in o_par.growth:
            o.keys.append((step, _organ_values(model, o, params.growth[name])))
    return model


def _check_lengths(params: Params, x: np.ndarray) -> None:
    """FormatError for a ``collision_distance`` or a growth set's ``thickness`` longer than the placed
    bud's extent (its bounding box diagonal): a gap or a thickness wider than the flower (formats/
    petal_grow.md, "Bounds")."""
    from inflo.formats.errors import FormatError

    extent = la.norm(x.max(axis=0) - x.min(axis=0))
    checks = [("flower", "collision_distance", params.flower.collision_distance)]
    checks += [(f"growth.{name}", "thickness", g.thickness) for name, g in params.growth.items()]
    for table, key, value in checks:
        if not value <= extent:
            raise FormatError(params.source, params.lines.get((table, key)),
                              f"{key}: at most the bud's extent = {extent:.6g} (its bounding box diagonal)",
                              f"{value:g}")


def _check_orientation(tri, edge_tris, edges, interior, source) -> None:
    """Both triangles of an interior edge must pass it in opposite directions (consistent winding:
    the inner side is the same side everywhere)."""
    for e in np.nonzero(interior)[0]:
        a, b = edges[e]
        dirs = []
        for t in edge_tris[e]:
            f = tri[t].tolist()
            i = f.index(a)
            dirs.append(f[(i + 1) % 3] == b)
        if dirs[0] == dirs[1]:
            raise InputError(f"{source}: the organ meshes must be consistently wound (faces counter-clockwise "
                             f"seen from the inner side); edge {a + 1}-{b + 1} is passed the same way by both its triangles")


def _organ_values(model: Model, o: OrganData, g) -> dict:
    """Per-triangle (eq. 1) and per-edge/per-hinge map values of one growth set for one organ."""
    tuv = model.tri_uv[o.t0:o.t1]
    vuv = model.vertex_uv
    e_lo = np.nonzero(model.edge_indices[:, 0] >= o.v0)[0]
    e_sel = e_lo[model.edge_indices[e_lo, 0] < o.v1]
    h_sel = np.nonzero((model.hinge_indices[:, 0] >= o.v0) & (model.hinge_indices[:, 0] < o.v1))[0]
    st = checked_values(g.stretch, vuv, g.stretch(vuv))
    bd = checked_values(g.bend, vuv, g.bend(vuv))
    ed = model.edge_indices
    hg = model.hinge_indices
    return {
        "dir": triangle_directions(g.direction, tuv),
        "e": triangle_values(g.e, tuv), "w": triangle_values(g.w, tuv),
        "e_in": triangle_values(g.e_in, tuv), "w_in": triangle_values(g.w_in, tuv),
        "dg": g.dg, "thickness": g.thickness, "K_s": g.K_s, "K_b": g.K_b,
        "edges": e_sel, "hinges": h_sel,
        "c_s": 0.5 * (st[ed[e_sel, 0]] + st[ed[e_sel, 1]]),
        "c_b": 0.5 * (bd[hg[h_sel, 0]] + bd[hg[h_sel, 1]]),
    }


def _blend(keys: list, step: float) -> dict:
    """The organ's growth values at ``step``: its key sets interpolated linearly (fig. 16)."""
    if step <= keys[0][0] or len(keys) == 1:
        return keys[0][1]
    if step >= keys[-1][0]:
        return keys[-1][1]
    for (s0, a), (s1, b) in zip(keys[:-1], keys[1:]):
        if s0 <= step <= s1:
            f = (step - s0) / (s1 - s0)
            if f == 0.0:
                return a
            out = dict(a)
            for k in ("dir", "e", "w", "e_in", "w_in", "dg", "thickness", "K_s", "K_b", "c_s", "c_b"):
                out[k] = (1 - f) * np.asarray(a[k]) + f * np.asarray(b[k])
            d = out["dir"]
            out["dir"] = d / np.maximum(la.norm(d, axis=1, keepdims=True), 1e-12)
            return out
    return keys[-1][1]


@njit(cache=True)
def _rest_thetas_from(vertex_x, hinge_indices, hinge_edge, n_edges, sign):
    out = np.zeros(n_edges)
    ang = hinge_angles(vertex_x, hinge_indices)
    for h in range(hinge_indices.shape[0]):
        out[hinge_edge[h]] = ang[h] * sign
    return out


@njit(cache=True)
def _triangle_areas(vertex_x, tri):
    out = np.empty(tri.shape[0])
    for t in range(tri.shape[0]):
        a = vertex_x[tri[t, 0]]
        b = vertex_x[tri[t, 1]]
        c = vertex_x[tri[t, 2]]
        ux, uy, uz = b[0] - a[0], b[1] - a[1], b[2] - a[2]
        vx, vy, vz = c[0] - a[0], c[1] - a[1], c[2] - a[2]
        nx = uy * vz - uz * vy
        ny = uz * vx - ux * vz
        nz = ux * vy - uy * vx
        out[t] = 0.5 * math.sqrt(nx * nx + ny * ny + nz * nz)
    return out


@njit(cache=True)
def _rays_hit(origins, directions, vertex_x, tri):
    """Number of rays (origin + s direction, s > 0) that hit any triangle of ``tri`` (Moeller-Trumbore)."""
    hits = 0
    for r in range(origins.shape[0]):
        o = origins[r]
        d = directions[r]
        for t in range(tri.shape[0]):
            a = vertex_x[tri[t, 0]]
            e1 = vertex_x[tri[t, 1]] - a
            e2 = vertex_x[tri[t, 2]] - a
            px = d[1] * e2[2] - d[2] * e2[1]
            py = d[2] * e2[0] - d[0] * e2[2]
            pz = d[0] * e2[1] - d[1] * e2[0]
            det = e1[0] * px + e1[1] * py + e1[2] * pz
            if abs(det) < 1e-14:
                continue
            inv = 1.0 / det
            sx, sy, sz = o[0] - a[0], o[1] - a[1], o[2] - a[2]
            u = (sx * px + sy * py + sz * pz) * inv
            if u < 0.0 or u > 1.0:
                continue
            qx = sy * e1[2] - sz * e1[1]
            qy = sz * e1[0] - sx * e1[2]
            qz = sx * e1[1] - sy * e1[0]
            v = (d[0] * qx + d[1] * qy + d[2] * qz) * inv
            if v < 0.0 or u + v > 1.0:
                continue
            s = (e2[0] * qx + e2[1] * qy + e2[2] * qz) * inv
            if s > 1e-9:
                hits += 1
                break
    return hits


def arrangement_violations(model: Model, x: np.ndarray) -> list[tuple[str, str, int]]:
    """The declared arrangement checked on positions ``x``: for every ordered pair (inner, outer)
    -- a lower ``layer`` inside a higher one, an organ ``beneath`` another -- the rays from the
    outer organ's vertices away from the flower axis (horizontal) must not hit the inner organ.
    Returns [(inner, outer, rays that hit)] for the pairs that fail."""
    pairs = []
    by_name = {o.name: o for o in model.organs}
    for a in model.organs:
        for b in model.organs:
            if a is not b and a.layer < b.layer:
                pairs.append((a, b))
        if a.beneath:
            pairs.append((a, by_name[a.beneath]))
    out = []
    for inner, outer in pairs:
        o = np.ascontiguousarray(x[outer.v0:outer.v1])
        d = o.copy()
        d[:, 1] = 0.0
        n = la.norm(d, axis=1)
        keep = n > 1e-9
        d = np.ascontiguousarray(d[keep] / n[keep, None])
        tri = np.ascontiguousarray(model.tri_indices[inner.t0:inner.t1])
        hits = _rays_hit(np.ascontiguousarray(o[keep]), d, x, tri)
        if hits:
            out.append((inner.name, outer.name, int(hits)))
    return out


@dataclass
class GrowResult:
    frames: list
    log: list
    seconds: float
    intersecting: int


class Simulation:
    """The state of one run: rest values, stiffness, positions (the Model/State split: what is fixed apart from what moves)."""

    def __init__(self, model: Model, params: Params):
        self.m = model
        self.p = params
        f = params.flower
        self.x = model.vertex_x.copy()
        self.w = np.ones(len(self.x))
        self.edge_rest_length = edge_lengths(self.x, model.edge_indices)
        self.edge_rest_theta = _rest_thetas_from(self.x, model.hinge_indices, model.hinge_edge,
                                                 len(model.edge_indices), HINGE_SIGN)
        self.rest0 = self.edge_rest_length.copy()
        areas = _triangle_areas(self.x, model.tri_indices)
        self.mean_area = float(areas.mean())
        et = model.edge_tris
        self.edge_area = np.where(et[:, 1] >= 0, 0.5 * (areas[et[:, 0]] + areas[np.maximum(et[:, 1], 0)]),
                                  areas[et[:, 0]])
        self._last_blend = None
        ne, nh, nt = len(model.edge_indices), len(model.hinge_indices), len(model.tri_indices)
        self.edge_stiffness = np.ones(ne)
        self.hinge_stiffness = np.ones(nh)
        self.tri = {k: np.zeros(nt) for k in ("e", "w", "e_in", "w_in", "dg", "thickness")}
        self.tri_dir = np.zeros((nt, 2))
        self.hinge_rest_angle = HINGE_SIGN * self.edge_rest_theta[model.hinge_edge]
        self.step = 0
        self.flower = f

    # ---- 1. regional growth ------------------------------------------------------------------
    def _set_growth(self, step: int) -> None:
        """The per-triangle growth values and the constraint stiffnesses of step ``step``; unchanged
        (not recomputed) while every organ is on one key set."""
        m = self.m
        blends = [_blend(o.keys, step) for o in m.organs]
        ids = tuple(id(g) for g in blends)
        if ids == self._last_blend and all(g is o.keys[0][1] or g is o.keys[-1][1] or
                                           any(g is k[1] for k in o.keys) for g, o in zip(blends, m.organs)):
            return
        self._last_blend = ids
        for o, g in zip(m.organs, blends):
            sl = slice(o.t0, o.t1)
            for k in ("e", "w", "e_in", "w_in"):
                self.tri[k][sl] = g[k]
            self.tri["dg"][sl] = g["dg"]
            self.tri["thickness"][sl] = g["thickness"]
            self.tri_dir[sl] = g["dir"]
            # sec. 5.1: k = a K c_uv as PBD stiffnesses in [0, 1] (formats/petal_grow.md, "Stiffness"):
            # distance: K_s c_uv / K_max (a PBD distance projection already scales with the edge);
            # bending: K_b c_uv a / (K_max mean area), so small hinges do not dominate (the bud's areas)
            kmax = max(float(g["K_s"]), float(g["K_b"]), 1e-300)
            ks = float(g["K_s"]) * g["c_s"] / kmax
            hb = m.hinge_edge[g["hinges"]]
            kb = float(g["K_b"]) * g["c_b"] * self.edge_area[hb] / (kmax * self.mean_area)
            self.edge_stiffness[g["edges"]] = np.clip(ks, 0.0, 1.0)
            self.hinge_stiffness[g["hinges"]] = np.clip(kb, 0.0, 1.0)

    def grow(self, step: int) -> None:
        """Regional growth of step ``step`` (sec. 4): new rest lengths and rest angles."""
        self._set_growth(step)
        m = self.m
        nl = np.empty_like(self.edge_rest_length)
        nth = np.empty_like(self.edge_rest_theta)
        grow_rest_state(m.tri_indices, m.tri_edges, m.tri_uv, self.edge_rest_length, self.edge_rest_theta,
                        m.edge_interior, self.tri_dir, self.tri["e"], self.tri["w"], self.tri["e_in"],
                        self.tri["w_in"], self.tri["dg"], self.tri["thickness"], nl, nth)
        self.edge_rest_length = nl
        self.edge_rest_theta = nth
        self.hinge_rest_angle = np.ascontiguousarray(HINGE_SIGN * nth[m.hinge_edge])

    # ---- 2. + 3. global shape and attachment -------------------------------------------------
    def sweep(self, x: np.ndarray, n: int) -> None:
        m = self.m
        for _ in range(n):
            project_distance_constraints(x, self.w, m.edge_indices, self.edge_rest_length, self.edge_stiffness)
            project_bending_constraints(x, self.w, m.hinge_indices, self.hinge_rest_angle, self.hinge_stiffness)

    def targets(self, step: int) -> list:
        """Each organ's base-particle targets at ``step``: the bud's turned by the joint angle."""
        return [la.matmul(o.base_rest - o.pivot, rotation_matrix(o.axis, joint_angle_at(o.joint, step)).T) + o.pivot
                for o in self.m.organs]

    def attach(self, x: np.ndarray, targets: list) -> None:
        """Shape matching of each organ's base particles to its targets (sec. 5.3, fig. 11)."""
        for o, target in zip(self.m.organs, targets):
            r, t = shape_match(x[o.base], target)
            x[o.v0:o.v1] = la.matmul(x[o.v0:o.v1], r.T) + t

    def solve(self, step: int) -> np.ndarray:
        f = self.flower
        x = self.x.copy()
        targets = self.targets(step)
        left = f.iterations
        while left > 0:
            n = min(f.match_every, left)
            self.sweep(x, n)
            left -= n
            self.attach(x, targets)
        if f.iterations == 0:
            self.attach(x, targets)
        elif f.length_sweeps:
            # the stiff part last: rest lengths (growth proper) over rest angles (bending), so that a
            # rest state the surface cannot take bends less rather than stretching edges
            m = self.m
            for _ in range(f.length_sweeps):
                project_distance_constraints(x, self.w, m.edge_indices, self.edge_rest_length, self.edge_stiffness)
            self.attach(x, targets)
        return x

    # ---- 4. collisions -------------------------------------------------------------------------
    def collide(self, x1: np.ndarray):
        f = self.flower
        m = self.m

        def relax(xr, moved):
            self.sweep(xr, 1)

        return resolve_collisions(self.x, x1, self.w, m.tri_indices, m.edge_indices,
                                  thickness=f.collision_distance, iterations=f.collision_iterations,
                                  max_retries=f.collision_retries, relax=relax, fallback="vertices",
                                  cell_size=broad_cell(self.x, m.edge_indices))

    def advance(self) -> dict:
        """One step: grow, solve, attach, collide; returns the log row (without the exact check)."""
        t0 = time.perf_counter()
        self.step += 1
        k = self.step
        self.grow(k)
        x1 = self.solve(k)
        found = rounds = reverted = 0
        if self.flower.collisions:
            res = self.collide(x1)
            found, rounds, reverted = int(sum(res.found)), res.rounds, res.reverted
        self.x = x1
        return self._row(k, found, rounds, reverted, time.perf_counter() - t0)

    def _row(self, k, found, rounds, reverted, dt) -> dict:
        m = self.m
        lo, hi = edge_stretch_range(self.x, m.edge_indices, self.edge_rest_length, 0.0)
        return {
            "frame": k, "step": k,
            "joint_deg": float(np.mean([joint_angle_at(o.joint, k) for o in m.organs])),
            "growth": float(np.mean(self.edge_rest_length / self.rest0)),
            "min_edge_stretch": float(lo), "max_edge_stretch": float(hi),
            "distance_rms": float(distance_residual(self.x, m.edge_indices, self.edge_rest_length)),
            "bending_rms_deg": math.degrees(bending_residual(self.x, m.hinge_indices, self.hinge_rest_angle)),
            "collisions_found": found, "collision_rounds": rounds, "reverted_vertices": reverted,
            "intersecting_pairs": -1, "t_step_s": dt,
        }


def _frame_mesh(model: Model, x: np.ndarray) -> ObjMesh:
    return ObjMesh(vertices=x, faces=model.tri_indices, groups=[o.name for o in model.organs],
                   face_group=model.face_group, materials=list(model.materials), face_material=model.face_material)


def broad_cell(x: np.ndarray, edge_indices: np.ndarray) -> float:
    """Broad-phase cell size for the flower: three mean edge lengths (measured: 5-50 x faster than
    the mean-box default on these meshes of similar triangles)."""
    return 3.0 * float(edge_lengths(x, edge_indices).mean())


def written_frame(model: Model, x: np.ndarray, check: bool) -> tuple[str, int]:
    """The first of :data:`WRITE_FORMATS` whose written coordinates have no intersecting triangle
    pair (exact static test; touching counts), and that count (-1 when not ``check``ed)."""
    if not check:
        return WRITE_FORMATS[0], -1
    n = -1
    cell = broad_cell(x, model.edge_indices)
    for fmt in WRITE_FORMATS:
        n = len(intersecting_pairs(as_written(x, fmt), model.tri_indices, cell_size=cell))
        if n == 0:
            return fmt, 0
    return WRITE_FORMATS[0], n


def run(params: Params, out_dir, *, keyframes: int | None = None, collisions: bool | None = None,
        progress=None, model: Model | None = None, threads: int | None = 1) -> GrowResult:
    """Grow the flower of ``params`` and write ``out_dir/frame_0000.obj`` (the bud) ...
    ``frame_<keyframes-1>.obj`` and ``out_dir/log.csv``. All input is read and checked before
    anything is written.

    ``threads``: numba threads for the parallel kernels of the collision core (None: numba's
    default). A flower has a few thousand triangles, where starting the threads costs more than
    they save: the exact test of a keyframe is 3-20 x slower on two threads than on one. Results
    do not depend on it."""
    old = numba.get_num_threads()
    if threads is not None:
        numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))
    try:
        return _run(params, out_dir, keyframes=keyframes, collisions=collisions, progress=progress, model=model)
    finally:
        numba.set_num_threads(old)


def _run(params: Params, out_dir, *, keyframes, collisions, progress, model) -> GrowResult:
    t_start = time.perf_counter()
    model = build_model(params) if model is None else model
    f = params.flower
    if keyframes is not None:
        f.keyframes = int(keyframes)
    if collisions is not None:
        f.collisions = bool(collisions)
    n0 = len(intersecting_pairs(model.vertex_x, model.tri_indices,
                                cell_size=broad_cell(model.vertex_x, model.edge_indices)))
    if n0:
        raise InputError(f"{params.source}: the bud's organs intersect ({n0} triangle pairs): the collision "
                         "response needs an intersection-free bud")
    bad = arrangement_violations(model, model.vertex_x)
    if bad:
        inner, outer, hits = bad[0]
        raise InputError(f"{params.source}: the bud does not have the declared arrangement: {inner!r} should lie "
                         f"inside/beneath {outer!r}, but {hits} rays from {outer!r} outwards hit it")
    sim = Simulation(model, params)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    frames, log = [], []
    written = []
    fmt, nx = written_frame(model, sim.x, True)
    p0 = out / frame_name(0)
    write_obj(p0, _frame_mesh(model, sim.x), fmt=fmt, header="petal-grow keyframe 0 (the bud)")
    written.append(p0)
    row0 = sim._row(0, 0, 0, 0, 0.0)
    row0["intersecting_pairs"] = nx
    log.append(row0)
    total_bad = nx
    for k in range(1, f.keyframes):
        row = sim.advance()
        check = f.check_every > 0 and (k % f.check_every == 0 or k == f.keyframes - 1)
        fmt, nx = written_frame(model, sim.x, check)
        row["intersecting_pairs"] = nx
        total_bad += max(nx, 0)
        p = out / frame_name(k)
        write_obj(p, _frame_mesh(model, sim.x), fmt=fmt, header=f"petal-grow keyframe {k}")
        written.append(p)
        log.append(row)
        if progress is not None:
            progress(1)
    remove_stale_frames(out, written, ".obj")
    write_text_atomic(out / "log.csv", _log_text(log))
    frames = written
    return GrowResult(frames, log, time.perf_counter() - t_start, total_bad)


def _log_text(rows: list) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(LOG_COLUMNS)
    for r in rows:
        w.writerow([r[c] if isinstance(r[c], int) else f"{r[c]:.6g}" for c in LOG_COLUMNS])
    return buf.getvalue()
