"""Collision detection and response shared by ``fccompose`` and ``subdivide`` (thesis ch. 4).

- :mod:`.ccd`: continuous narrow phase (coplanarity cubic, culling, roots, inside tests).
- :mod:`.broad`: broad phase on a hashed uniform grid.
- :mod:`.tritri`: exact static triangle-triangle intersection test.
- :mod:`.response`: collision constraints C_vt (eq. 4.6) and C_ee (eq. 4.7).
- :mod:`.contacts`: collision contacts and the narrow phase over candidate pairs.
- :mod:`.detect`: detection over a mesh, and the broad phase of a step's rounds.
- :mod:`.resolve`: the retry loop of Algorithm 1.
- :mod:`.retreat`: the fallback that keeps parts (florets) whole.
- :mod:`.probe`: round 0's contacts from the last step's, without grids.
"""
from .broad import box_pairs, edge_boxes, lattice_cell_size, triangle_boxes, vertex_boxes
from .ccd import (
    cubic_edge_edge,
    cubic_roots_01,
    cubic_vertex_triangle,
    cull_cubic,
    edge_edge_ccd,
    point_triangle_distance,
    segment_segment_distance,
    vertex_triangle_ccd,
)
from .contacts import Contacts, default_tolerance
from .detect import detect_collisions
from .resolve import CollisionResult, resolve_collisions
from .response import (
    project_collision_constraints,
    solve_collision_constraint,
    solve_ee_collision_constraint,
    solve_vt_collision_constraint,
)
from .retreat import Parts
from .tritri import (
    intersecting_pairs,
    intersecting_pairs_between,
    intersecting_pairs_brute,
    intersecting_pairs_with,
    triangles_intersect,
)

__all__ = [
    "box_pairs", "edge_boxes", "lattice_cell_size", "triangle_boxes", "vertex_boxes",
    "cubic_edge_edge", "cubic_roots_01", "cubic_vertex_triangle", "cull_cubic", "edge_edge_ccd",
    "point_triangle_distance", "segment_segment_distance", "vertex_triangle_ccd",
    "CollisionResult", "Contacts", "Parts", "default_tolerance", "detect_collisions", "resolve_collisions",
    "project_collision_constraints", "solve_collision_constraint", "solve_ee_collision_constraint",
    "solve_vt_collision_constraint",
    "intersecting_pairs", "intersecting_pairs_between", "intersecting_pairs_brute", "intersecting_pairs_with",
    "triangles_intersect",
]
