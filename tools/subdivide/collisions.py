"""The collision step of each subdivision level: from ``M_s`` toward ``M_f`` without new crossings.

Thesis 4.4: "We handle these collisions as described in Sections 4.2 and 4.3, using M_s as the
initial collision-free triangle configuration, and M_f as the desired triangle configuration."
This is one step of the Floral Canopy Composer's collision loop (Alg. 1, lines 10-20) with no
internal constraints, done by :func:`inflo.tools.collide.resolve_collisions`.
"""
from __future__ import annotations

import numpy as np

from inflo.tools.collide import resolve_collisions
from inflo.tools.common import linalg as la
from inflo.tools.pbd.solver import mesh_edges  # re-exported: unique edges (i < j), sorted, (e, 2) int32

__all__ = ["mesh_edges", "collision_resolver", "default_spacing"]


def default_spacing(vertices: np.ndarray) -> float:
    """Default thickness h: 1/2000 of the bounding-box diagonal (documented in the CLI help)."""
    V = np.asarray(vertices)
    return la.norm(V.max(axis=0) - V.min(axis=0)) / 2000.0


def collision_resolver(*, spacing: float, iterations: int = 10, max_retries: int = 20, stiffness: float = 1.0):
    """A ``resolve(x_start, x_target, faces) -> (x_end, n_constraints, n_remaining)`` for
    :func:`inflo.tools.subdivide.smooth.subdivide_frames`.

    Pairs still crossing after ``max_retries`` have their vertices put back toward ``M_s`` by the
    collision core, so the result stays collision-free; their count is reported.
    """

    def resolve(x_start, x_target, faces):
        x_end = np.array(x_target, dtype=np.float64, copy=True)
        inv_mass = np.ones(len(x_end))
        result = resolve_collisions(
            np.ascontiguousarray(x_start, dtype=np.float64), x_end, inv_mass,
            np.ascontiguousarray(faces, dtype=np.int32), mesh_edges(faces),
            thickness=spacing, stiffness=stiffness, iterations=iterations, max_retries=max_retries)
        return x_end, result.constraints, len(result.remaining)

    return resolve
