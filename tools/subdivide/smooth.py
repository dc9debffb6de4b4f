"""Subdivide a canopy (one OBJ or a sequence) level by level, staying collision-free (thesis 4.4).

For each level: quadrisect every triangle in its plane (``M_s``, collision-free when the input
is), compute the Loop positions (``M_f``), then move from ``M_s`` toward ``M_f`` with continuous
collision detection and collision constraints (fig. 4.8c) -- the ``resolve`` step, supplied by
the collision core. The subdivision connectivity is computed once and applied to every frame, so
topology and vertex order are the same in every output frame.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from inflo.formats.obj import ObjMesh

from .loop import LoopLevel, loop_level

__all__ = ["LevelReport", "SubdivisionPlan", "plan_subdivision", "subdivide_frames", "subdivide_meshes"]

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


def subdivide_meshes(meshes: Sequence[ObjMesh], levels: int, *, resolve: Resolve | None = None,
                     name: str = "mesh", on_frame=None):
    """Subdivide OBJ meshes of one topology; groups and materials follow their parent faces.

    Returns (list of ObjMesh, list of LevelReport). Polylines and normals are dropped (normals
    would no longer match the smoothed surface).
    """
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
