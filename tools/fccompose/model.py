"""The canopy as a constraint system: static Model, changing State (Warp's split; thesis 3, 8 f).

:func:`build_model` reads everything a ``.fcc`` file names (:func:`load_inputs`: OBJ sequences,
single OBJs, weight files, SCN files, RBA folders), then :func:`assemble_model`, which reads no
files, instances every placement and concatenates the florets into one structure-of-arrays system:

- ``Model`` (static): ``tri_indices``, ``edge_indices``, ``hinge_indices`` (global vertex ids),
  per-constraint stiffness, ``vertex_inv_mass`` (0 for the fixed vertices of the weight files),
  ``vertex_floret``, the template frames of every animation (``template_x``, local coordinates,
  scaled by the entry's initial scale) and per-floret tables; plus :meth:`Model.schedule`, which
  gives at any (fractional) frame each floret's developmental time and placement matrix (a
  :class:`Schedule`), and keyword wrappers of the kernels below that take a ``Schedule``
  (:meth:`Model.template_positions`, :meth:`Model.rest_values`, :meth:`Model.predict`).
- ``State`` (changing): the positions ``vertex_x``, the last frame completed and which florets
  have emerged, at what size and when; what ``fccompose --resume`` saves and loads
  (:mod:`.compose`). The solver's settings and caches (the control) are
  :class:`inflo.tools.fccompose.compose.Simulation`'s.

Rest values at a time (edge lengths, eq. 3.11; signed dihedral angles, eq. 3.13) are computed
from the two template frames around the floret's developmental time, each mapped through the
linear part of its placement (scale, scene scale; rotation does not change them), and
interpolated linearly (angles along the shorter way, modulo 2 pi).

Placement kinds (SCN, app. C.2) and developmental time u in [0, 1] (template frame u (F - 1)):

- ``ca start end``: u = (frame - start) / (end - start), clamped; static placement.
- ``i value``: u = value for all frames; static placement.
- ``o``: u = 0 (first template frame); static placement.
- ``ta start end x y z``: translated by s (x, y, z), s = (frame - start)/(end - start) clamped;
  develops like ``ca`` over the same frames.
- ``ra start end x y z angle``: rotated by s * angle degrees about the axis (x, y, z) through the
  placement position; develops like ``ca``.
- ``rba start end``: placement of each frame from the RBA files (linear interpolation between
  frames and of sub-steps; a floret absent from a frame takes the nearest frame where it is
  present); develops like ``ca``. The ``rigid body animation`` entry's scale and the placement's
  own SCN scale (a factor: the floret's size relative to its primordium, e.g. ``dimorph``'s ray
  scale; ``phyllotaxis`` writes 1) multiply the RBA scales. The floret *emerges* at the first RBA frame that lists it (:attr:`Floret.birth_frame`,
  the primordium's formation in a dynamic phyllotaxis): before that it is not part of the canopy
  (no collisions, no faces in the output; :class:`inflo.tools.fccompose.compose.Simulation`).

Nested scenes (formats/fcc.md): a placement whose id is a ``rigid body animation`` entry's
instances that entry's scene (a :class:`Level`); its florets carry the chain of outer levels
(:attr:`Floret.outer`) and read their own windows on the inner clock (``frame - shift``, the outer
placements' ``frameStart``). Their matrices are composed in :meth:`Model.matrix` (per floret, not
in the vectorized RBA tables of the top-level ``rba:`` florets).

Weight files list fixed vertex ids: 0-based indices in the OBJ's vertex order, separated by blanks,
commas or line breaks; ``#`` starts a comment.
"""
from __future__ import annotations

import copy
import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from inflo.formats.atomic import first_missing_frame
from inflo.formats.errors import FormatError, InputError
from inflo.formats.fcc import CanopyParams
from inflo.formats.obj import read_obj, read_obj_sequence
from inflo.formats.placement import placement_matrix
from inflo.formats.rba import read_rba_sequence
from inflo.formats.scn import read_scn
from inflo.formats.weights import read_petal_weight_file, read_weight_file
from inflo.tools.common import linalg as la
from inflo.tools.pbd.constraints import signed_dihedral_angle, wrap_angle
from inflo.tools.pbd.solver import mesh_edges, mesh_hinges

from .variation import varied

__all__ = ["Template", "Floret", "Model", "Schedule", "State", "RbaSequence", "Inputs", "build_model",
           "load_inputs", "assemble_model", "read_weight_file"]


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

    def __post_init__(self):
        if self.key is None:
            self.key = self.id

    def with_petals(self, factor: float) -> Template:
        """This template with its petals grown by ``factor`` (thesis fig. 6.4c: a small ray
        floret's enlarged petals sized by the available space, the rest of the floret as it is):
        local vertex v of every frame scaled by ``1 + w_v (factor - 1)`` about the floret's origin
        (its attachment point), ``w`` the petal weights. Edges and hinges are shared; rest values
        follow from the grown frames. Returns ``self`` for a factor of 1 or a template without
        petal weights."""
        if self.petal_weight is None or factor == 1.0:
            return self
        grow = 1.0 + self.petal_weight * (float(factor) - 1.0)
        out = copy.copy(self)
        out.frames = np.ascontiguousarray(self.frames * grow[None, :, None])
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


def coincident_vertices(frames: np.ndarray, faces: np.ndarray):
    """The first frame and pair of distinct vertices (0-based, both used by triangles) at exactly the
    same point, or None (as in a template with a duplicated, unwelded vertex).

    Zero-area triangles whose corners are distinct points (collinear corners, slivers) are accepted:
    the collision core treats them as their longest edge. Coincident distinct vertices are not:
    the triangles around them touch, so the exact test of the first frame would refuse the canopy
    anyway, naming only florets.
    """
    used = np.unique(np.asarray(faces).ravel())
    for k in range(frames.shape[0]):
        x = frames[k, used]
        _, first, inverse, counts = np.unique(x, axis=0, return_index=True, return_inverse=True, return_counts=True)
        if np.any(counts > 1):
            g = int(np.argmax(counts > 1))
            pair = np.sort(used[np.flatnonzero(inverse.ravel() == g)[:2]])
            return k, int(pair[0]), int(pair[1])
    return None


def _load_template(params: CanopyParams, entry) -> Template:
    if entry.kind == "obj":
        mesh = read_obj(entry.path.resolved)
        frames = mesh.vertices[None]
    else:
        paths, meshes = read_obj_sequence(entry.path.resolved)
        gap = first_missing_frame(paths)
        if gap is not None:
            raise FormatError(params.source, entry.line, f"an OBJ sequence without a gap in {entry.path.raw} (a "
                              "missing frame would re-time the animation)", f"{gap} missing")
        frames = np.stack([m.vertices for m in meshes])
        mesh = meshes[0]
    faces = mesh.faces
    if len(faces) == 0:
        raise FormatError(entry.path.resolved, None, "triangles (f lines)", "none")
    bad = coincident_vertices(frames, faces)
    if bad is not None:
        k, i, j = bad
        where = entry.path.resolved if entry.kind == "obj" else paths[k]
        raise FormatError(where, None, "distinct points for distinct vertices of the triangles (the triangles at two "
                          "coincident vertices touch, which no collision-free canopy allows: weld them into one "
                          "vertex or move them apart)", f"vertices {i + 1} and {j + 1} at the same point "
                          f"({' '.join(f'{c:g}' for c in frames[k, i])})")
    frames = frames * np.asarray(entry.scale, float)
    nv = frames.shape[1]
    fixed = None
    if entry.id in params.weights:
        fixed = read_weight_file(params.weights[entry.id].resolved, nv)
    k_stretch, k_bend = params.stiffness(entry.id)
    t = Template.from_frames(entry.id, frames, faces, fixed=fixed, k_stretch=k_stretch, k_bend=k_bend,
                             source=str(entry.path.raw), materials=mesh.materials,
                             face_material=mesh.face_material)
    if entry.id in params.petal_weights:
        t.petal_weight = read_petal_weight_file(params.petal_weights[entry.id].resolved, nv)
    return t


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


def _rba_rows(frames, n_placements: int) -> np.ndarray:
    """(n_placements, n_frames) int64: the row of each placement in each RBA frame, -1 if absent."""
    table = np.full((n_placements, len(frames)), -1, np.int64)
    for i, fr in enumerate(frames):
        ids = np.asarray(fr.ids, np.int64)
        ok = (ids >= 0) & (ids < n_placements)
        table[ids[ok], i] = np.nonzero(ok)[0]
    return table


def _nearest_present(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each RBA frame, the frame whose row places the floret (itself when present, else the
    nearest frame where it is, the earlier on a tie) and that row."""
    present = np.nonzero(rows >= 0)[0]
    i = np.arange(len(rows))
    j = np.searchsorted(present, i)
    lo = present[np.clip(j - 1, 0, len(present) - 1)]
    hi = present[np.clip(j, 0, len(present) - 1)]
    src = np.where(np.abs(i - lo) <= np.abs(hi - i), lo, hi)
    src = np.where(rows >= 0, i, src)
    return src, rows[src]


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


# --------------------------------------------------------------------------------------------------
# Building
# --------------------------------------------------------------------------------------------------


class RbaSequence(NamedTuple):
    """One ``rigid body animation`` entry's RBA files, read against its scene."""

    paths: list
    """the RBA files, in frame order"""
    frames: list
    """their :class:`~inflo.formats.rba.RbaFrame` objects"""
    scale: np.ndarray
    """(3,) the entry's scale, multiplying every RBA row's"""


class Inputs(NamedTuple):
    """What :func:`load_inputs` read for :func:`assemble_model`."""

    scenes: dict
    """scene path -> :class:`~inflo.formats.scn.Scene`, in the order the florets are numbered"""
    templates: Mapping
    """animation/obj id -> :class:`Template`, iterated in the ``.fcc``'s entry order"""
    rbas: dict
    """scene path -> :class:`RbaSequence` of the scenes with a ``rigid body animation`` line"""


class _TemplateFiles(Mapping):
    """The ``animation``/``obj`` entries of a ``.fcc`` as id -> :class:`Template`, each read from
    its files on its first lookup: only placed templates are read, in placement order (so the
    first bad file named is the first a placement needs). Iterates over the ids in entry order."""

    def __init__(self, params: CanopyParams):
        self._params = params
        self._entries = {e.id: e for e in params.animations}
        self._read: dict = {}

    def __contains__(self, id) -> bool:
        return id in self._entries

    def __getitem__(self, id) -> Template:
        if id not in self._read:
            self._read[id] = _load_template(self._params, self._entries[id])
        return self._read[id]

    def __iter__(self):
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)


def load_inputs(params: CanopyParams) -> Inputs:
    """Read the SCN files and RBA folders ``params`` names; the OBJ sequences, OBJs and weight
    files of its entries are read as :func:`assemble_model` looks their templates up.

    Raises
    ------
    FormatError, InputError
        Unreadable or malformed inputs; no scene file; a second ``rigid body animation`` line for
        a scene; an RBA folder without RBA files; an RBA id that is not an ``rba:`` placement of
        its scene.
    """
    if not params.scene_files and not params.rigid_body_animations:
        raise InputError(f"{params.source}: expected at least one 'scene file path', found none")

    # scene files (listed ones first, then those only named by rigid body animation lines)
    scene_paths = [f.resolved for f in params.scene_files]
    for r in params.rigid_body_animations:
        if r.scene_path.resolved not in scene_paths:
            scene_paths.append(r.scene_path.resolved)
    scenes = {p: read_scn(p) for p in scene_paths}
    rbas = {}
    for r in params.rigid_body_animations:
        sp = r.scene_path.resolved
        if sp in rbas:
            raise FormatError(params.source, r.line, "one 'rigid body animation' line per scene file",
                              f"a second one for {r.scene_path.raw}")
        paths, frames = read_rba_sequence(r.rba_folder.resolved, scenes[sp])
        if not paths:
            raise FormatError(params.source, r.line, "a folder with RBA files", f"none in {r.rba_folder.raw}")
        gap = first_missing_frame(paths, start=0)
        if gap is not None:
            raise FormatError(params.source, r.line, f"RBA files numbered from 0 without a gap (file NNNN is frame "
                              f"NNNN) in {r.rba_folder.raw}", f"{gap} missing")
        for k in range(1, len(frames)):
            # placements do not vanish: an empty (0-byte) file after a frame with placements is a
            # truncated frame, which would make its florets emerge a frame late
            if len(frames[k]) == 0 and len(frames[k - 1]) > 0 and paths[k].stat().st_size == 0:
                raise FormatError(paths[k], None, f"the placements of the frame before ({len(frames[k - 1])}) "
                                  "or more", "an empty file (a truncated frame?)")
        rbas[sp] = RbaSequence(paths, frames, np.asarray(r.scale, float))
    return Inputs(scenes, _TemplateFiles(params), rbas)


#: nested scenes: the deepest nesting and the most florets they may expand to (formats/fcc.md,
#: "Nested scenes"), checked by counting before any floret is made
MAX_NEST_DEPTH = 6
MAX_FLORETS = 200_000


def _check_nesting(scenes, top, templates, nested, source) -> None:
    """Bad input (one line) when nested scenes go deeper than :data:`MAX_NEST_DEPTH` or expand to
    more than :data:`MAX_FLORETS` florets (ten placements of a scene of ten, seven levels deep, is
    ten million florets from a few small files)."""
    memo: dict = {}

    def count(sp, depth, chain):
        """(florets, nesting height) of scene ``sp`` reached ``depth`` levels down."""
        if sp not in memo:
            n, h = 0, 0
            for p in scenes[sp].placements:
                if p.id in templates:
                    n += 1
                elif p.id in nested and nested[p.id] not in chain and nested[p.id] in scenes:
                    m, g = count(nested[p.id], depth + 1, chain + [nested[p.id]])
                    n, h = n + m, max(h, g + 1)
                if n > MAX_FLORETS:
                    raise InputError(f"{source}: expected nested scenes of at most {MAX_FLORETS} florets in all, "
                                     f"found more in {Path(sp).name}")
            memo[sp] = (n, h)
        n, h = memo[sp]
        if depth + h > MAX_NEST_DEPTH:
            raise InputError(f"{sp}: expected scenes nested at most {MAX_NEST_DEPTH} deep, found {depth + h} "
                             f"(through {' > '.join(Path(c).name for c in chain)})")
        return n, h

    total = 0
    for sp in top:
        total += count(sp, 0, [sp])[0]
        if total > MAX_FLORETS:
            raise InputError(f"{source}: expected scenes of at most {MAX_FLORETS} florets in all, found more")


def assemble_model(params: CanopyParams, scenes: Mapping, templates: Mapping, rbas: Mapping | None = None) -> Model:
    """Instance every placement and concatenate the florets into one system (thesis 8 f); reads
    no files.

    Parameters
    ----------
    params : CanopyParams
        The run's parameters (kept as :attr:`Model.params`; ``run_frames``, ``scene_scale`` and
        ``source`` are used here).
    scenes : mapping of path -> Scene
        Florets are numbered in this order (scenes, then placements in file order).
    templates : mapping of int -> Template
        By animation/obj id; the placed ones' frames are stacked in ``template_x`` in this
        mapping's order, and each is looked up when a placement first names it.
    rbas : mapping of path -> RbaSequence, optional
        The RBA sequences moving the ``rba:`` placements of those scenes.

    Raises
    ------
    FormatError, InputError
        An SCN id with no template; an ``rba:`` placement of a scene without an RBA sequence, or
        listed in none of its RBA files; no placements at all.
    """
    rbas = {} if rbas is None else rbas
    rba_rows = {sp: _rba_rows(seq.frames, len(scenes[sp].placements)) for sp, seq in rbas.items()}
    # nested scenes: a placement whose id names a rigid body animation entry instances that
    # entry's scene (recursively); such scenes are not top-level unless listed as scene files
    nested = {r.id: r.scene_path.resolved for r in params.rigid_body_animations}
    referenced = {nested[p.id] for sc in scenes.values() for p in sc.placements
                  if p.id in nested and p.id not in templates}
    listed = {f.resolved for f in params.scene_files}
    top = [sp for sp in scenes if sp in listed or sp not in referenced]

    florets: list[Floret] = []
    placed: dict = {}
    own: list = []  # the florets' own templates (``variation`` lines), in floret order
    variations = params.variations

    def moved_by_rba(target, sp, k):
        if sp not in rbas:
            raise FormatError(sp, None, "a 'rigid body animation' line for this scene's 'rba:' placements",
                              f"placement {k} and no such line")
        paths, frames, scale = rbas[sp]
        rows = rba_rows[sp][k]
        if not (rows >= 0).any():
            raise FormatError(paths[0].parent, None, f"placement {k} in at least one RBA file", "none")
        target.rba = (paths, frames)
        target.rba_scale = scale
        target.birth_frame = int(np.argmax(rows >= 0))
        target.rba_source, target.rba_row = _nearest_present(rows)

    def instance(sp, outer, chain):
        shift = float(sum(lv.shift for lv in outer))
        # the frame (canopy clock) at which the outer levels have all emerged
        born, t = 0.0, 0.0
        for lv in outer:
            born = max(born, t + lv.birth_frame)
            t += lv.shift
        for k, p in enumerate(scenes[sp].placements):
            if p.id in templates:
                if p.petal is not None and templates[p.id].petal_weight is None:
                    raise InputError(f"{sp}: expected a 'petal weight' line in {params.source} for id {p.id} "
                                     f"(placement {k} has '#@ petal: {p.petal:g}'), found none")
                # a placement's '#@ petal: f' grows the petals of its own copy of the template
                # (one copy per distinct factor; fig. 6.4c)
                key = (p.id, 1.0 if p.petal is None else float(p.petal))
                if key not in placed:
                    base = placed.setdefault((p.id, 1.0), templates[p.id])
                    placed[key] = base.with_petals(key[1])
                fl = Floret(len(florets), p, placed[key], sp, k, p.material, outer=tuple(outer), shift=shift)
                if p.id in variations and p.type != OBSTACLE:
                    var = variations[p.id]
                    if var.petal and templates[p.id].petal_weight is None:
                        raise InputError(f"{params.source}: expected a 'petal weight' line for id {p.id} (its "
                                         f"'variation' varies 'petal'), found none")
                    fl.template, fl.delay = varied(templates[p.id], var, fl.index, key[1])
                    own.append(fl.template)
                if p.kind == "rba":
                    moved_by_rba(fl, sp, k)
                fl.birth_frame = int(math.ceil(max(born, fl.birth_frame + shift) - 1e-9))
                florets.append(fl)
            elif p.id in nested:
                inner = nested[p.id]
                if inner in chain:
                    raise FormatError(sp, None, "nested scenes that do not contain themselves",
                                      f"placement {k} (id {p.id}) instancing {Path(inner).name} inside itself")
                lv = Level(p, sp, k, shift=float(p.frame_start or 0))
                if p.kind == "rba":
                    moved_by_rba(lv, sp, k)
                instance(inner, outer + [lv], chain + [inner])
            else:
                raise FormatError(sp, None, f"placement ids naming an 'animation', 'obj' or 'rigid body "
                                  f"animation' entry of {params.source}", f"id {p.id} (placement {k}, '{p.kind}:')")

    _check_nesting(scenes, top, templates, nested, params.source)
    for sp in top:
        instance(sp, [], [sp])
    if not florets:
        raise InputError(f"{params.source}: expected placements in the scene files, found none")

    # concatenate
    # templates in entry order, each id's grown copies after it by factor (a stable layout)
    order = {i: n for n, i in enumerate(templates)}
    in_use = {id(fl.template) for fl in florets}
    seen, used = set(), []
    for key in sorted(placed, key=lambda kf: (order[kf[0]], kf[1])):
        t = placed[key]
        if t.key not in seen and id(t) in in_use:
            seen.add(t.key)
            used.append(t)
    used.extend(own)
    template_offset, rows = {}, 0
    for t in used:
        template_offset[t.key] = rows
        rows += t.frames.shape[0] * t.n_vertices
    template_x = np.concatenate([t.frames.reshape(-1, 3) for t in used]) if used else np.zeros((0, 3))

    nv_tot = sum(f.template.n_vertices for f in florets)
    inv_mass = np.ones(nv_tot)
    vertex_floret = np.empty(nv_tot, np.int32)
    offsets = np.zeros(len(florets) + 1, np.int64)
    tris, tri_fl, edges, e_k, hinges, h_k, fixed = [], [], [], [], [], [], []
    v_off = t_off = 0
    for k, fl in enumerate(florets):
        t = fl.template
        fl.vertex_offset, fl.tri_offset = v_off, t_off
        vertex_floret[v_off:v_off + t.n_vertices] = k
        # an obstacle placement (formats/fcc.md "Obstacles") is fixed whole, whatever its weight file
        own = np.arange(t.n_vertices, dtype=np.int32) if fl.placement.type == OBSTACLE else t.fixed
        inv_mass[v_off + own] = 0.0
        fixed.append(own + v_off)
        tris.append(t.tri_indices + v_off)
        tri_fl.append(np.full(len(t.tri_indices), k, np.int32))
        edges.append(t.edge_indices + v_off)
        e_k.append(np.full(len(t.edge_indices), t.k_stretch))
        hinges.append(t.hinge_indices + v_off)
        h_k.append(np.full(len(t.hinge_indices), t.k_bend))
        v_off += t.n_vertices
        t_off += len(t.tri_indices)
        offsets[k + 1] = v_off

    check_spacing(params, florets)
    n_frames = params.run_frames
    if n_frames is None:
        ends = [0]
        for fl in florets:
            if fl.placement.frame_end is not None:
                ends.append(int(math.ceil(fl.placement.frame_end + fl.shift)))
        for seq in rbas.values():
            ends.append(len(seq.paths) - 1)
        n_frames = max(ends)

    cat = lambda xs, dt, shape: (np.ascontiguousarray(np.concatenate(xs), dtype=dt)
                                 if xs else np.zeros(shape, dt))
    return Model(
        florets=florets,
        templates={t.key: t for t in used},
        vertex_inv_mass=inv_mass,
        vertex_floret=vertex_floret,
        vertex_fixed=cat(fixed, np.int32, (0,)),
        tri_indices=cat(tris, np.int32, (0, 3)),
        tri_floret=cat(tri_fl, np.int32, (0,)),
        edge_indices=cat(edges, np.int32, (0, 2)),
        edge_stiffness=cat(e_k, np.float64, (0,)),
        hinge_indices=cat(hinges, np.int32, (0, 4)),
        hinge_stiffness=cat(h_k, np.float64, (0,)),
        template_x=np.ascontiguousarray(template_x, dtype=np.float64),
        template_offset=template_offset,
        floret_vertex_offset=offsets,
        n_frames=int(n_frames),
        params=params,
    )


#: ``spacing`` may be at most this many times the largest floret's extent (a spacing ten
#: times the florets' size made every triangle a collision candidate of every other and the run
#: was killed for memory).
SPACING_LIMIT = 4.0


def check_spacing(params: CanopyParams, florets) -> None:
    """Refuse a ``spacing`` (the collision gap, thesis app. C.1) larger than :data:`SPACING_LIMIT`
    times the largest floret: the extent of its template over all frames times its placement's
    largest scale (SCN, RBA rows and entry factors, every nesting level) and the scene scale factor.

    Raises
    ------
    InputError
        Naming the ``.fcc`` file, the spacing and the largest floret's extent.
    """
    if not florets or params.spacing <= 0:
        return
    extent, rba_max = {}, {}

    def rba_factor(holder):
        if holder.rba is None:
            return 1.0
        paths, frames = holder.rba
        key = id(frames)
        if key not in rba_max:
            rba_max[key] = max((float(np.abs(fr.scale).max()) for fr in frames if len(fr)), default=1.0)
        return rba_max[key] * float(np.abs(holder.rba_scale).max())

    biggest = 0.0
    for fl in florets:
        t = fl.template
        if t.key not in extent:
            pts = t.frames.reshape(-1, 3)
            extent[t.key] = la.norm(pts.max(axis=0) - pts.min(axis=0)) if len(pts) else 0.0
        size = extent[t.key] * float(np.abs(fl.placement.scale).max()) * rba_factor(fl)
        for lv in fl.outer:
            size *= float(np.abs(lv.placement.scale).max()) * rba_factor(lv)
        biggest = max(biggest, size)
    biggest *= float(np.max(np.abs(params.scene_scale)))
    if params.spacing > SPACING_LIMIT * biggest:
        raise InputError(f"{params.source}: expected 'spacing' (the collision gap) at most {SPACING_LIMIT:g} x the "
                         f"largest floret's extent = {SPACING_LIMIT * biggest:.6g}, found {params.spacing:g}")


def build_model(params: CanopyParams) -> Model:
    """Load every file ``params`` names and instance every placement (thesis 8 f):
    :func:`load_inputs`, then :func:`assemble_model`.

    Raises
    ------
    FormatError, InputError
        Unreadable or malformed inputs; an animation whose frames differ in topology (naming the
        first differing frame); an SCN id with no ``animation``/``obj`` entry; an RBA id that is
        not an ``rba:`` placement of its scene; an ``rba:`` placement without a ``rigid body
        animation`` entry for its scene; a scene without placements.
    """
    inputs = load_inputs(params)
    return assemble_model(params, inputs.scenes, inputs.templates, inputs.rbas)


# --------------------------------------------------------------------------------------------------
# Kernels: template positions, rest values, prediction
# --------------------------------------------------------------------------------------------------


@njit(cache=True, inline="always")
def _tpl_point(template_x, vertex_floret, floret_vertex_offset, base_a, base_b, alpha, v, out):
    f = vertex_floret[v]
    lv = v - floret_vertex_offset[f]
    a = base_a[f] + lv
    b = base_b[f] + lv
    s = alpha[f]
    for d in range(3):
        out[d] = (1.0 - s) * template_x[a, d] + s * template_x[b, d]


@njit(cache=True)
def template_positions(template_x, vertex_floret, floret_vertex_offset, base_a, base_b, alpha, matrix,
                       vertices, out):
    """``out[v] = M_f * template(v)`` for the listed ``vertices`` (attachment targets, initial state)."""
    p = np.empty(3)
    for k in range(vertices.shape[0]):
        v = vertices[k]
        _tpl_point(template_x, vertex_floret, floret_vertex_offset, base_a, base_b, alpha, v, p)
        f = vertex_floret[v]
        for d in range(3):
            out[v, d] = matrix[f, d, 0] * p[0] + matrix[f, d, 1] * p[1] + matrix[f, d, 2] * p[2] + matrix[f, d, 3]


@njit(cache=True, inline="always")
def _mapped(template_x, f, row, matrix, out):
    for d in range(3):
        out[d] = (matrix[f, d, 0] * template_x[row, 0] + matrix[f, d, 1] * template_x[row, 1]
                  + matrix[f, d, 2] * template_x[row, 2])


@njit(cache=True)
def _rest_lengths(template_x, vertex_floret, floret_vertex_offset, base_a, base_b, alpha, matrix,
                  edge_indices, edge_rest_length, lo, hi):
    pa = np.empty((2, 3))
    pb = np.empty((2, 3))
    for e in range(lo, hi):
        i = edge_indices[e, 0]
        j = edge_indices[e, 1]
        f = vertex_floret[i]
        li = i - floret_vertex_offset[f]
        lj = j - floret_vertex_offset[f]
        _mapped(template_x, f, base_a[f] + li, matrix, pa[0])
        _mapped(template_x, f, base_a[f] + lj, matrix, pa[1])
        la = math.sqrt((pa[0, 0] - pa[1, 0]) ** 2 + (pa[0, 1] - pa[1, 1]) ** 2 + (pa[0, 2] - pa[1, 2]) ** 2)
        s = alpha[f]
        if s != 0.0:
            _mapped(template_x, f, base_b[f] + li, matrix, pb[0])
            _mapped(template_x, f, base_b[f] + lj, matrix, pb[1])
            lb = math.sqrt((pb[0, 0] - pb[1, 0]) ** 2 + (pb[0, 1] - pb[1, 1]) ** 2 + (pb[0, 2] - pb[1, 2]) ** 2)
            edge_rest_length[e] = (1.0 - s) * la + s * lb
        else:
            edge_rest_length[e] = la


@njit(cache=True)
def _rest_angles(template_x, vertex_floret, floret_vertex_offset, base_a, base_b, alpha, matrix,
                 hinge_indices, hinge_rest_angle, lo, hi):
    pa = np.empty((4, 3))
    pb = np.empty((4, 3))
    for h in range(lo, hi):
        f = vertex_floret[hinge_indices[h, 0]]
        off = floret_vertex_offset[f]
        for k in range(4):
            _mapped(template_x, f, base_a[f] + hinge_indices[h, k] - off, matrix, pa[k])
        th_a = signed_dihedral_angle(pa[0], pa[1], pa[2], pa[3])
        s = alpha[f]
        if s != 0.0:
            for k in range(4):
                _mapped(template_x, f, base_b[f] + hinge_indices[h, k] - off, matrix, pb[k])
            th_b = signed_dihedral_angle(pb[0], pb[1], pb[2], pb[3])
            hinge_rest_angle[h] = wrap_angle(th_a + s * wrap_angle(th_b - th_a))
        else:
            hinge_rest_angle[h] = th_a


#: blocks of the parallel rest values (each edge or hinge is computed alone: the same values on
#: any number of threads)
_REST_BLOCKS = 64


@njit(cache=True, parallel=True)
def rest_values(template_x, vertex_floret, floret_vertex_offset, base_a, base_b, alpha, matrix,
                edge_indices, hinge_indices, edge_rest_length, hinge_rest_angle):
    """Rest lengths (eq. 3.11) and signed rest angles (eq. 3.13) at the floret's developmental time.

    Each is measured on both template frames around the time, mapped by the linear part of the
    floret's placement, and interpolated with weight ``alpha`` (angles modulo 2 pi). Blocks of
    edges and hinges run in parallel; each value is computed on its own (thread-independent).
    """
    ne = edge_indices.shape[0]
    nh = hinge_indices.shape[0]
    per_e = (ne + _REST_BLOCKS - 1) // _REST_BLOCKS
    per_h = (nh + _REST_BLOCKS - 1) // _REST_BLOCKS
    for b in prange(2 * _REST_BLOCKS):
        if b < _REST_BLOCKS:
            lo = b * per_e
            hi = min(ne, lo + per_e)
            if lo < hi:
                _rest_lengths(template_x, vertex_floret, floret_vertex_offset, base_a, base_b, alpha, matrix,
                              edge_indices, edge_rest_length, lo, hi)
        else:
            lo = (b - _REST_BLOCKS) * per_h
            hi = min(nh, lo + per_h)
            if lo < hi:
                _rest_angles(template_x, vertex_floret, floret_vertex_offset, base_a, base_b, alpha, matrix,
                             hinge_indices, hinge_rest_angle, lo, hi)


@njit(cache=True)
def predict(vertex_x, vertex_floret, floret_vertex_offset, delta, template_x, old_a, old_b, old_alpha,
            new_a, new_b, new_alpha, matrix_new, out):
    """Predicted positions of a growth step (the "velocity" of PBD's prediction).

    ``out = D_f x + L_f (T_new(v) - T_old(v))``: the vertex is carried with its floret's placement
    change ``D_f`` (``delta``, (nf, 3, 4)) and moved by the template's own displacement between the
    two developmental times, mapped by the new placement's linear part ``L_f``. An undeformed
    floret (``x = M_old T_old``) lands exactly on its template (``M_new T_new``); a floret deformed
    by collisions keeps its deformation, which the constraints then relax.
    """
    for v in range(vertex_x.shape[0]):
        f = vertex_floret[v]
        lv = v - floret_vertex_offset[f]
        x0 = vertex_x[v, 0]
        x1 = vertex_x[v, 1]
        x2 = vertex_x[v, 2]
        sa = old_alpha[f]
        sb = new_alpha[f]
        g0 = ((1.0 - sb) * template_x[new_a[f] + lv, 0] + sb * template_x[new_b[f] + lv, 0]
              - (1.0 - sa) * template_x[old_a[f] + lv, 0] - sa * template_x[old_b[f] + lv, 0])
        g1 = ((1.0 - sb) * template_x[new_a[f] + lv, 1] + sb * template_x[new_b[f] + lv, 1]
              - (1.0 - sa) * template_x[old_a[f] + lv, 1] - sa * template_x[old_b[f] + lv, 1])
        g2 = ((1.0 - sb) * template_x[new_a[f] + lv, 2] + sb * template_x[new_b[f] + lv, 2]
              - (1.0 - sa) * template_x[old_a[f] + lv, 2] - sa * template_x[old_b[f] + lv, 2])
        for d in range(3):
            out[v, d] = (delta[f, d, 0] * x0 + delta[f, d, 1] * x1 + delta[f, d, 2] * x2 + delta[f, d, 3]
                         + matrix_new[f, d, 0] * g0 + matrix_new[f, d, 1] * g1 + matrix_new[f, d, 2] * g2)


@njit(cache=True)
def carry(vertex_x, vertex_floret, delta, out):
    """``out[v] = D_f x[v]``: positions carried rigidly by each floret's placement change over a
    step (``delta`` (nf, 3, 4)), without growth: the fallback's whole-floret target."""
    for v in range(vertex_x.shape[0]):
        f = vertex_floret[v]
        for d in range(3):
            out[v, d] = (delta[f, d, 0] * vertex_x[v, 0] + delta[f, d, 1] * vertex_x[v, 1]
                         + delta[f, d, 2] * vertex_x[v, 2] + delta[f, d, 3])
