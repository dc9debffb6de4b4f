"""Subdivide a canopy (one OBJ or a sequence) level by level, staying collision-free (thesis 4.4).

For each level: quadrisect every triangle in its plane (``M_s``, collision-free when the input
is), compute the Loop positions (``M_f``), then move from ``M_s`` toward ``M_f`` with continuous
collision detection and collision constraints (fig. 4.8c) -- the ``resolve`` step, supplied by
the collision core. The subdivision connectivity is computed once and applied to every frame, so
topology and vertex order are the same in every output frame.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from inflo.formats.obj import ObjMesh

from .loop import LoopLevel, loop_level

__all__ = ["LevelReport", "SubdivisionPlan", "Weld", "plan_subdivision", "subdivide_frames", "subdivide_meshes",
           "weld_coincident"]

# resolve(x_start (n,3), x_target (n,3), faces (m,3) int32) -> (x_end (n,3), n_constraints, n_remaining)
Resolve = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple]


@dataclass
class LevelReport:
    """What one level did to one frame."""

    frame: int
    level: int
    n_faces: int
    collision_constraints: int = 0
    remaining_intersections: int = 0


@dataclass
class SubdivisionPlan:
    """The operators of every level for one connectivity (built once for a whole sequence)."""

    levels: list = field(default_factory=list)  # list[LoopLevel]

    @property
    def faces(self) -> np.ndarray:
        return self.levels[-1].faces

    def face_parent(self) -> np.ndarray:
        """(m_out,) int64: the input face each output face comes from (4 children per level)."""
        idx = np.arange(len(self.levels[0].faces) // 4, dtype=np.int64)
        for _ in self.levels:
            idx = np.repeat(idx, 4)
        return idx


def plan_subdivision(faces: np.ndarray, n_vertices: int, levels: int, name: str = "mesh") -> SubdivisionPlan:
    """Build the Loop operators of ``levels`` levels for ``faces`` (raises on non-manifold edges)."""
    if levels < 0:
        raise ValueError("levels must be >= 0")
    plan = SubdivisionPlan()
    F, n = np.asarray(faces), int(n_vertices)
    for _ in range(levels):
        lv: LoopLevel = loop_level(F, n, name=name)
        plan.levels.append(lv)
        F, n = lv.faces, n + len(lv.edges)
    return plan


def subdivide_frames(frames: Sequence[np.ndarray], plan: SubdivisionPlan, *, resolve: Resolve | None = None,
                     on_frame: Callable[[int], None] | None = None):
    """Apply ``plan`` to every frame's vertices.

    Parameters
    ----------
    frames : sequence of (n, 3) float64
    plan : SubdivisionPlan
    resolve : callable or None
        Collision handling per level (see the module docstring); None gives plain Loop subdivision.
    on_frame : callable(int) or None
        Called after each frame (progress).

    Returns
    -------
    out : list of (n_out, 3) float64
    reports : list of LevelReport
    """
    out, reports = [], []
    for k, V in enumerate(frames):
        V = np.asarray(V, dtype=np.float64)
        for level, lv in enumerate(plan.levels, 1):
            target = lv.loop(V)
            if resolve is None:
                V = target
                reports.append(LevelReport(k, level, len(lv.faces)))
            else:
                V, n_constraints, n_remaining = resolve(lv.midpoints(V), target, lv.faces)
                reports.append(LevelReport(k, level, len(lv.faces), int(n_constraints), int(n_remaining)))
        out.append(V)
        if on_frame is not None:
            on_frame(k)
    return out, reports


@dataclass
class Weld:
    """Coincident vertices welded before subdividing (:func:`weld_coincident`)."""

    keep: np.ndarray
    """(n_out,) int64: the input vertices kept, in input order"""
    faces: np.ndarray
    """(m_out, 3) int64: the faces in the kept vertices' numbering"""
    face_kept: np.ndarray
    """(m_out,) int64: the input face each output face is"""
    welded: int = 0
    """vertices merged into another at the same point"""
    dropped: int = 0
    """faces dropped: a vertex repeated after welding (zero-area triangles made by a duplicated vertex)"""


def weld_coincident(frames: Sequence[np.ndarray], faces: np.ndarray) -> Weld:
    """Weld the face vertices that lie at exactly the same point in every frame, and drop the
    triangles that then repeat a vertex.

    Meshes from other tools carry duplicated vertices (an unwelded seam, a sliver triangle made by a
    duplicated vertex): the triangles on either side touch there, which the exact test counts as
    intersecting, and Loop subdivision would keep the seam open as two boundaries. Welded, the seam
    is interior and the output has no touching pair the input did not already cross. Vertices
    coincident in only some frames (a bud tip collapsing to a point) are left as they are; unused
    vertices are kept (they stay unused).
    """
    F = np.asarray(faces, dtype=np.int64)
    n = len(frames[0])
    rep = np.arange(n)
    used = np.unique(F.ravel())
    if len(used):
        x0 = np.asarray(frames[0])[used]
        _, first, inverse = np.unique(x0, axis=0, return_index=True, return_inverse=True)
        cand = used[first[inverse.ravel()]]  # the first used vertex at the same point in frame 0
        same = cand != used
        for V in frames[1:]:
            V = np.asarray(V)
            same &= (V[used] == V[cand]).all(axis=1)
        rep[used[same]] = cand[same]
    welded = int((rep != np.arange(n)).sum())
    if welded == 0:
        return Weld(np.arange(n), F, np.arange(len(F)))
    G = rep[F]
    ok = (G[:, 0] != G[:, 1]) & (G[:, 1] != G[:, 2]) & (G[:, 0] != G[:, 2])
    keep = np.flatnonzero(rep == np.arange(n))
    new = np.full(n, -1, np.int64)
    new[keep] = np.arange(len(keep))
    return Weld(keep, new[G[ok]], np.flatnonzero(ok), welded, int((~ok).sum()))


def subdivide_meshes(meshes: Sequence[ObjMesh], levels: int, *, resolve: Resolve | None = None,
                     name: str = "mesh", on_frame=None, notes: list | None = None):
    """Subdivide OBJ meshes of one topology; groups and materials follow their parent faces.

    Vertices at the same point in every frame are welded first and the zero-area triangles that
    leaves are dropped (:func:`weld_coincident`); ``notes`` (a list) gets a line saying so.

    Returns (list of ObjMesh, list of LevelReport). Polylines and normals are dropped (normals
    would no longer match the smoothed surface).
    """
    if levels:
        w = weld_coincident([m.vertices for m in meshes], meshes[0].faces)
        if w.welded:
            if notes is not None:
                notes.append(f"{name}: welded {w.welded} vertices lying at the same point as another in every frame"
                             + (f", dropped {w.dropped} zero-area triangles" if w.dropped else ""))
            meshes = [_welded(m, w) for m in meshes]
    first = meshes[0]
    plan = plan_subdivision(first.faces, first.n_vertices, levels, name=name)
    verts, reports = subdivide_frames([m.vertices for m in meshes], plan, resolve=resolve, on_frame=on_frame)
    parent = plan.face_parent() if levels else np.arange(first.n_faces)
    faces = plan.faces if levels else first.faces
    out = []
    for m, V in zip(meshes, verts):
        out.append(ObjMesh(
            V, faces,
            groups=list(m.groups), face_group=None if m.face_group is None else m.face_group[parent],
            materials=list(m.materials), face_material=None if m.face_material is None else m.face_material[parent],
        ))
    return out, reports


def _welded(m: ObjMesh, w: Weld) -> ObjMesh:
    return ObjMesh(
        m.vertices[w.keep], w.faces.astype(m.faces.dtype),
        groups=list(m.groups), face_group=None if m.face_group is None else m.face_group[w.face_kept],
        materials=list(m.materials), face_material=None if m.face_material is None else m.face_material[w.face_kept],
    )
