"""The canopy's constraint system: the static :class:`Model` and the changing :class:`State`
(Warp's split; thesis 3, 8 f), the :class:`Template` s, :class:`Floret` s and :class:`Level` s the
model is made of, and each placement's matrix over time (:meth:`Model.matrix`,
:meth:`Model.schedule`). :mod:`.model` describes them and builds them; import them from there.
"""
from __future__ import annotations

import copy
import functools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from inflo.formats.fcc import CanopyParams
from inflo.formats.placement import placement_matrix
from inflo.tools.common import linalg as la
from inflo.tools.pbd.solver import mesh_edges, mesh_hinges

from .kernels import predict, ramped_petals, rest_values, template_positions

#: the SCN ``#@ type:`` of an obstacle placement: simulated (it collides with the florets), not written
OBSTACLE = "obstacle"


@dataclass
class Template:
    """One ``animation``/``obj`` entry: the floret's OBJ frames in its local frame.

    Attributes
    ----------
    id : int
    frames : (F, nv, 3) float64
        Local positions, multiplied by the entry's initial scale.
    tri_indices : (m, 3) int32
    edge_indices : (e, 2) int32
    hinge_indices : (h, 4) int32
    fixed : (k,) int32
        Fixed vertex ids (weight file), sorted.
    k_stretch, k_bend : float
        Distance and bending stiffness (per-id or global).
    source : str
        What was read (for messages).
    materials : list of str
        ``usemtl`` names of the template's OBJ (first frame), e.g. one per organ.
    face_material : (m,) int32 or None
        Index into ``materials`` per triangle (-1: none), None when the OBJ uses no ``usemtl``.
    petal_weight : (nv,) float64 or None
        Per-vertex petal weights in [0, 1] (``petal weight`` file), None without one.
    petal : float
        The petal factor f this template's frames were grown by (:meth:`with_petals`; 1: as read).
    petal_ramp : (float, float) or None
        The ``petal ramp`` (from, to) of its id: the factor takes effect with the frames'
        development (:meth:`with_petals`); None: every frame grown by the whole factor.
    key : hashable
        Identifies the frames in ``Model.template_x``: ``id`` as read, ``(id, f)`` once grown.
    """

    id: int
    frames: np.ndarray
    tri_indices: np.ndarray
    edge_indices: np.ndarray
    hinge_indices: np.ndarray
    fixed: np.ndarray
    k_stretch: float
    k_bend: float
    source: str = ""
    materials: list = None
    face_material: np.ndarray | None = None
    petal_weight: np.ndarray | None = None
    petal: float = 1.0
    key: object = None
    petal_ramp: tuple | None = None

    def __post_init__(self):
        if self.key is None:
            self.key = self.id

    def with_petals(self, factor: float) -> Template:
        """This template with its petals grown by ``factor`` (thesis fig. 6.4c: a small ray
        floret's enlarged petals sized by the available space, the rest of the floret as it is):
        local vertex v of every frame scaled by ``1 + w_v (factor - 1)`` about the floret's origin
        (its attachment point), ``w`` the petal weights. Edges and hinges are shared; rest values
        follow from the grown frames. With a :attr:`petal_ramp` (from, to) the factor takes effect
        with the development: frame s of F by ``1 + w_v (factor - 1) g(s / (F - 1))``, g a
        smoothstep from 0 at ``from`` to 1 at ``to`` (:func:`.kernels.ramped_petals`). Returns
        ``self`` for a factor of 1 or a template without petal weights."""
        if self.petal_weight is None or factor == 1.0:
            return self
        out = copy.copy(self)
        if self.petal_ramp is None:
            grow = 1.0 + self.petal_weight * (float(factor) - 1.0)
            out.frames = np.ascontiguousarray(self.frames * grow[None, :, None])
        else:
            lo, hi = self.petal_ramp
            out.frames = np.empty(self.frames.shape)
            ramped_petals(np.ascontiguousarray(self.frames, np.float64),
                          np.ascontiguousarray(self.petal_weight, np.float64), float(factor), float(lo), float(hi),
                          out.frames)
        out.petal, out.key = float(factor), (self.id, float(factor))
        return out

    @property
    def n_vertices(self) -> int:
        return self.frames.shape[1]

    @classmethod
    def from_frames(cls, id: int, frames, faces, *, fixed=None, k_stretch: float = 0.99, k_bend: float = 0.99,
                    source: str = "", materials=None, face_material=None) -> Template:
        """A template of ``frames`` ((F, nv, 3) local positions, already scaled) and triangles
        ``faces`` (m, 3): its edges and hinges are those of the triangles (:func:`mesh_edges`,
        :func:`mesh_hinges`), ``fixed`` the vertex ids of its weight file (None: none)."""
        tri = np.ascontiguousarray(faces, dtype=np.int32)
        fixed = np.zeros(0, np.int32) if fixed is None else np.asarray(fixed, np.int32)
        return cls(id, np.ascontiguousarray(frames, dtype=np.float64), tri, mesh_edges(tri), mesh_hinges(tri),
                   fixed, float(k_stretch), float(k_bend), source, list(materials or []),
                   None if face_material is None else np.asarray(face_material, np.int32))


@dataclass
class Floret:
    """One placement instanced in the canopy.

    ``index`` is its position in the composed scene (scene files in ``.fcc`` order, placements in
    file order); output groups are named ``floret_<index>``.
    """

    index: int
    placement: object
    template: Template
    scene_path: Path
    local_index: int
    material: int | None
    vertex_offset: int = 0
    tri_offset: int = 0
    rba: object = None  # (paths, frames) of the RBA sequence moving it, or None
    rba_scale: np.ndarray | None = None
    birth_frame: int = 0  # first RBA frame listing an rba: placement (its emergence); 0 otherwise
    rba_source: np.ndarray | None = None  # per RBA frame: the frame whose row places it (nearest present)
    rba_row: np.ndarray | None = None  # per RBA frame: its row in that frame
    outer: tuple = ()
    """the :class:`Level` s of the placements instancing its scene inside others (nested scenes,
    outermost first); empty for a floret of a top-level scene"""
    shift: float = 0.0
    """the time its own placement's clock runs behind the canopy's: the sum of the outer levels'
    shifts (their placements' ``frameStart``)"""
    delay: float = 0.0
    """frames its developmental window runs late (a ``variation`` line's ``timing`` draw; negative:
    early); its motion keeps its placement's clock"""


@dataclass
class Level:
    """A placement that instances a whole scene (a ``rigid body animation`` entry's) inside
    another (thesis ch. 8: "a SCN file instantiates a rigid body animation of an inflorescence
    described in another SCN file"): its own motion, and the time shift of the scene it carries
    (its ``frameStart``, 0 for ``o:`` and ``i:``), by which the inner scene's clock runs behind its
    own."""

    placement: object
    scene_path: Path
    local_index: int
    rba: object = None  # (paths, frames) when the placement is rba:, else None
    rba_scale: np.ndarray | None = None
    rba_source: np.ndarray | None = None
    rba_row: np.ndarray | None = None
    birth_frame: int = 0  # in its own clock
    shift: float = 0.0


class Schedule(NamedTuple):
    """Per-floret tables at one (fractional) frame for the kernels (:meth:`Model.schedule`)."""

    base_a: np.ndarray
    """(nf,) int64: row of ``template_x`` of the template frame at or before each floret's time"""
    base_b: np.ndarray
    """(nf,) int64: row of ``template_x`` of the template frame after it (the same at the end)"""
    alpha: np.ndarray
    """(nf,) float64: interpolation weight of frame b"""
    matrix: np.ndarray
    """(nf, 3, 4) float64: local-to-scene affine maps (scene scale included)"""


@dataclass
class Model:
    """Static data of the canopy's constraint system (structure of arrays, global vertex ids).

    Attributes
    ----------
    florets : list of Floret
    templates : dict of key -> Template
        By :attr:`Template.key` (the id; ``(id, f)`` for a copy grown by a petal factor f).
    vertex_inv_mass : (n,) float64
    vertex_floret : (n,) int32
    vertex_fixed : (k,) int32
        Global ids of fixed vertices.
    tri_indices : (m, 3) int32
    tri_floret : (m,) int32
    edge_indices : (e, 2) int32
    edge_stiffness : (e,) float64
    hinge_indices : (h, 4) int32
    hinge_stiffness : (h,) float64
    template_x : (T, 3) float64
        All template frames of all templates, concatenated.
    template_offset : dict of key -> int
        Row of ``template_x`` where the template's (by :attr:`Template.key`) frame 0 starts.
    floret_vertex_offset : (nf + 1,) int64
    n_frames : int
        Frames to simulate.
    params : CanopyParams
    """

    florets: list
    templates: dict
    vertex_inv_mass: np.ndarray
    vertex_floret: np.ndarray
    vertex_fixed: np.ndarray
    tri_indices: np.ndarray
    tri_floret: np.ndarray
    edge_indices: np.ndarray
    edge_stiffness: np.ndarray
    hinge_indices: np.ndarray
    hinge_stiffness: np.ndarray
    template_x: np.ndarray
    template_offset: dict
    floret_vertex_offset: np.ndarray
    n_frames: int
    params: CanopyParams

    @property
    def n_vertices(self) -> int:
        return len(self.vertex_inv_mass)

    @property
    def n_triangles(self) -> int:
        return len(self.tri_indices)

    @functools.cached_property
    def obstacles(self) -> list:
        """Indices of the obstacle placements (``#@ type: obstacle``, formats/fcc.md "Obstacles"),
        which take part in collisions and are not written."""
        return [k for k, fl in enumerate(self.florets) if fl.placement.type == OBSTACLE]

    @functools.cached_property
    def obstacle_vertices(self) -> np.ndarray | None:
        """(n,) bool: the vertices of the :attr:`obstacles`; None when there are none."""
        if not self.obstacles:
            return None
        mask = np.zeros(self.n_vertices, bool)
        for k in self.obstacles:
            mask[self.floret_vertex_offset[k]:self.floret_vertex_offset[k + 1]] = True
        return mask

    @functools.cached_property
    def floret_birth(self) -> np.ndarray:
        """(nf,) int64: the frame each floret emerges at (:attr:`Floret.birth_frame`)."""
        return np.array([fl.birth_frame for fl in self.florets], np.int64)

    @functools.cached_property
    def face_materials(self) -> tuple[list, np.ndarray | None]:
        """Material names of the canopy and the index of each triangle's (-1: none).

        A triangle takes its template OBJ's ``usemtl`` material (so a floret's organs keep their own
        colours, e.g. a lily's sepals and petals); a triangle its template gives none takes its
        placement's SCN ``mtl:`` id as ``mtl<id>``. Names are sorted, so the output is stable.
        """
        names: list = []
        per_floret = []
        for fl in self.florets:
            t = fl.template
            own = f"mtl{fl.material}" if fl.material is not None else None
            if t.face_material is not None and t.materials:
                tm = np.asarray(t.materials + [own], dtype=object)[t.face_material]  # -1 -> own
            else:
                tm = np.full(len(t.tri_indices), own, dtype=object)
            per_floret.append(tm)
            names.extend(n for n in set(tm.tolist()) if n is not None)
        mats = sorted(set(names))
        if not mats:
            return [], None
        index = {m: i for i, m in enumerate(mats)}
        index[None] = -1
        face = np.concatenate([np.array([index[n] for n in tm.tolist()], np.int32) for tm in per_floret])
        return mats, face

    # -- schedule ------------------------------------------------------------------------------

    def developmental_time(self, floret: Floret, frame: float) -> float:
        """u in [0, 1] of ``floret`` at (fractional) ``frame`` (see the module docstring); a
        floret of a nested scene reads its window on its scene's clock (``frame - shift``)."""
        p = floret.placement
        frame = frame - floret.shift - floret.delay
        if p.kind == "i":
            return float(min(max(p.interpolation, 0.0), 1.0))
        if p.kind == "o":
            return 0.0
        return _ramp(frame, p.frame_start, p.frame_end)

    def matrix(self, floret: Floret, frame: float) -> np.ndarray:
        """(4, 4) local-to-scene matrix of ``floret`` at ``frame``, scene scale included: the
        matrices of its outer levels (nested scenes), each at its own clock, times its own."""
        m = _level_matrix(floret, frame - floret.shift)
        t = frame
        outer = np.eye(4)
        for lv in floret.outer:
            outer = la.matmul(outer, _level_matrix(lv, t))
            t -= lv.shift
        if floret.outer:
            m = la.matmul(outer, m)
        scale = np.diag(list(self.params.scene_scale) + [1.0])
        return la.matmul(scale, m)

    def schedule(self, frame: float) -> Schedule:
        """Per-floret tables at ``frame`` for the kernels.

        Returns
        -------
        Schedule
            ``base_a``, ``base_b`` ((nf,) int64): rows of ``template_x`` of the two template
            frames around each floret's time; ``alpha`` ((nf,) float64): interpolation weight of
            frame b; ``matrix`` ((nf, 3, 4) float64): local-to-scene affine maps.
        """
        nf = len(self.florets)
        base_a = np.empty(nf, np.int64)
        base_b = np.empty(nf, np.int64)
        alpha = np.empty(nf)
        mats = np.empty((nf, 3, 4))
        rba_ids, rba_mats = self._rba_matrices(frame)
        carried = np.zeros(nf, bool)
        carried[rba_ids] = True
        fixed = self._fixed_matrices()
        for k, fl in enumerate(self.florets):
            tpl = fl.template
            nfr = tpl.frames.shape[0]
            pos = self.developmental_time(fl, frame) * (nfr - 1)
            a = min(int(math.floor(pos)), nfr - 1)
            b = min(a + 1, nfr - 1)
            off = self.template_offset[tpl.key]
            base_a[k] = off + a * tpl.n_vertices
            base_b[k] = off + b * tpl.n_vertices
            alpha[k] = pos - a if b != a else 0.0
            if fixed[k] is not None:
                mats[k] = fixed[k]
            elif not carried[k]:
                mats[k] = self.matrix(fl, frame)[:3]
        mats[rba_ids] = rba_mats
        return Schedule(base_a, base_b, alpha, mats)

    def _fixed_matrices(self) -> list:
        """Per floret its (3, 4) matrix where that does not depend on the frame (placements other
        than ``ta``, ``ra`` and ``rba``, at every level), else None; computed once."""
        if getattr(self, "_fixed", None) is None:
            moving = ("ta", "ra", "rba")
            self._fixed = [None if fl.placement.kind in moving or any(lv.placement.kind in moving for lv in fl.outer)
                           else self.matrix(fl, 0.0)[:3] for fl in self.florets]
        return self._fixed

    # -- kernel launches (keyword arguments; the kernels take the arrays positionally) ----------

    def template_positions(self, schedule: Schedule, *, vertices: np.ndarray, out: np.ndarray) -> None:
        """``out[v] = M_f T_f(v)`` for the listed ``vertices`` ((k,) int32): their templates at the
        schedule's times, placed (:func:`template_positions`)."""
        template_positions(self.template_x, self.vertex_floret, self.floret_vertex_offset, schedule.base_a,
                           schedule.base_b, schedule.alpha, schedule.matrix, vertices, out)

    def rest_values(self, schedule: Schedule, *, edge_rest_length: np.ndarray,
                    hinge_rest_angle: np.ndarray) -> None:
        """Fill ``edge_rest_length`` (e,) and ``hinge_rest_angle`` (h,): rest lengths (eq. 3.11) and
        signed rest angles (eq. 3.13) at the schedule's times (:func:`rest_values`)."""
        rest_values(self.template_x, self.vertex_floret, self.floret_vertex_offset, schedule.base_a,
                    schedule.base_b, schedule.alpha, schedule.matrix, self.edge_indices, self.hinge_indices,
                    edge_rest_length, hinge_rest_angle)

    def predict(self, vertex_x: np.ndarray, *, delta: np.ndarray, old: Schedule, new: Schedule,
                out: np.ndarray) -> None:
        """Predicted positions of a growth step from schedule ``old`` to ``new`` into ``out``
        (:func:`predict`; ``delta`` (nf, 3, 4): each floret's placement change)."""
        predict(vertex_x, self.vertex_floret, self.floret_vertex_offset, delta, self.template_x, old.base_a,
                old.base_b, old.alpha, new.base_a, new.base_b, new.alpha, new.matrix, out)

    @functools.cached_property
    def _rba_tables(self) -> list:
        """Per RBA sequence: (floret indices, (n, F, 12) rows pos|scale|up|right of each floret at
        each frame (its nearest present row), (n, 3) scale factors: the entry's and the SCN's)."""
        groups: dict = {}
        for fl in self.florets:
            if fl.placement.kind == "rba" and not fl.outer:  # nested ones: Model.matrix
                groups.setdefault(id(fl.rba[1]), []).append(fl)
        out = []
        for members in groups.values():
            frames = members[0].rba[1]
            table = np.empty((len(members), len(frames), 12))
            for i, fl in enumerate(members):
                for f, (src, row) in enumerate(zip(fl.rba_source, fl.rba_row)):
                    fr = frames[src]
                    table[i, f] = np.concatenate([fr.pos[row], fr.scale[row], fr.up[row], fr.right[row]])
            factor = np.array([fl.rba_scale * np.asarray(fl.placement.scale, float) for fl in members])
            out.append((np.array([fl.index for fl in members], np.int64), table, factor))
        return out

    def _rba_matrices(self, frame: float):
        """Local-to-scene (n, 3, 4) matrices of every ``rba:`` floret at ``frame`` (scene scale
        included) and their indices: :func:`_rba_matrix` for all of them at once."""
        ids, mats = [np.zeros(0, np.int64)], [np.zeros((0, 3, 4))]
        for idx, table, factor in self._rba_tables:
            nfr = table.shape[1]
            f = min(max(frame, 0.0), nfr - 1.0)
            a = int(math.floor(f))
            b = min(a + 1, nfr - 1)
            s = f - a
            row = (1 - s) * table[:, a] + s * table[:, b]
            u = row[:, 6:9] / np.sqrt((row[:, 6:9] ** 2).sum(axis=1))[:, None]
            r = row[:, 9:12] - (row[:, 9:12] * u).sum(axis=1)[:, None] * u
            r = r / np.sqrt((r ** 2).sum(axis=1))[:, None]
            z = np.cross(r, u)
            scale = row[:, 3:6] * factor
            m = np.empty((len(idx), 3, 4))
            m[:, :, 0] = r * scale[:, 0:1]
            m[:, :, 1] = u * scale[:, 1:2]
            m[:, :, 2] = z * scale[:, 2:3]
            m[:, :, 3] = row[:, 0:3]
            m *= np.asarray(self.params.scene_scale, float)[None, :, None]
            ids.append(idx)
            mats.append(m)
        return np.concatenate(ids), np.concatenate(mats)


@dataclass
class State:
    """Changing data of the canopy: everything a run carries from one frame to the next.

    ``fccompose`` writes it next to every output frame and ``--resume`` reads it back
    (``OUT/state/``, :mod:`.compose`), so a resumed run continues bit-identically.

    Attributes
    ----------
    vertex_x : (n, 3) float64
        Positions after the last step.
    frame : int
        The last frame completed.
    born : (nf,) bool
        The florets that have emerged (the canopy; the others wait at their first RBA pose).
    emerge_scale : (nf,) float64
        The size (a fraction of its own) each floret emerged at: 1, or one of the ``emergence
        scales`` when it had no room at its own size.
    emerge_frame : (nf,) float64
        The (fractional) frame it emerged at that size; it grows back to its own size from there.
    """

    vertex_x: np.ndarray
    frame: int
    born: np.ndarray
    emerge_scale: np.ndarray
    emerge_frame: np.ndarray

    @classmethod
    def at_start(cls, model: Model, vertex_x: np.ndarray | None = None) -> State:
        """Frame 0: the florets whose emergence frame is 0 present at their own size; positions
        ``vertex_x``, by default every floret's template at its time at frame 0, placed."""
        nf = len(model.florets)
        if vertex_x is None:
            vertex_x = np.zeros((model.n_vertices, 3))
            model.template_positions(model.schedule(0.0), vertices=np.arange(model.n_vertices, dtype=np.int32),
                                     out=vertex_x)
        return cls(vertex_x, 0, model.floret_birth <= 0, np.ones(nf), np.zeros(nf))


def _ramp(frame: float, start, end) -> float:
    start = 0 if start is None else start
    end = start if end is None else end
    if end <= start:
        return 1.0 if frame >= start else 0.0
    return float(min(max((frame - start) / (end - start), 0.0), 1.0))


def _rotation(axis, angle: float) -> np.ndarray:
    a = np.asarray(axis, float)
    a = a / la.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * la.matmul(k, k)


def _level_matrix(level, frame: float) -> np.ndarray:
    """(4, 4) matrix of one placement (a :class:`Floret`'s own or a :class:`Level`) at ``frame``
    of its own clock, without the scene scale."""
    p = level.placement
    if p.kind == "rba":
        return _rba_matrix(level, frame)
    m = placement_matrix(p.pos, p.scale, p.up, p.right)
    if p.kind == "ta":
        s = _ramp(frame, p.frame_start, p.frame_end)
        m = m.copy()
        m[:3, 3] += s * np.asarray(p.translate, float)
    elif p.kind == "ra":
        s = _ramp(frame, p.frame_start, p.frame_end)
        r = np.eye(4)
        r[:3, :3] = _rotation(p.axis, math.radians(s * p.angle))
        t1 = np.eye(4)
        t1[:3, 3] = p.pos
        t0 = np.eye(4)
        t0[:3, 3] = -np.asarray(p.pos, float)
        m = la.matmul(t1, la.matmul(r, la.matmul(t0, m)))
    return m


def _rba_matrix(floret: Floret, frame: float) -> np.ndarray:
    _, frames = floret.rba
    f = min(max(frame, 0.0), len(frames) - 1.0)
    a = int(math.floor(f))
    b = min(a + 1, len(frames) - 1)
    s = f - a

    def row(i):
        fr = frames[floret.rba_source[i]]
        r = floret.rba_row[i]
        return fr.pos[r], fr.scale[r], fr.up[r], fr.right[r]

    pa, sa, ua, ra = row(a)
    pb, sb, ub, rb = row(b)
    lerp = lambda x, y: (1 - s) * x + s * y
    # the placement's own scale (SCN, e.g. set by dimorph) multiplies every RBA row's scale
    scale = lerp(sa, sb) * floret.rba_scale * np.asarray(floret.placement.scale, float)
    return placement_matrix(lerp(pa, pb), scale, lerp(ua, ub), lerp(ra, rb))
