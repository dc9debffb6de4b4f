"""Position based dynamics for constraint-based growth (thesis ch. 3, appendix A).

- :mod:`.constraints`: pure numba kernels, one constraint at a time (Bender's ``solve_X`` style):
  positions and inverse masses in, corrections out.
- :mod:`.solver`: loops of those kernels over structure-of-arrays constraint sets (Gauss-Seidel in a
  fixed order), graph colouring for the optional parallel sweep, and the mesh helpers that build
  edge and hinge (bending) topology.
"""
from .constraints import (
    dihedral_angle_gradients,
    init_bending_constraint,
    init_distance_constraint,
    signed_dihedral_angle,
    solve_attachment_constraint,
    solve_bending_constraint,
    solve_distance_constraint,
    wrap_angle,
)
from .solver import (
    bending_residual,
    colour_constraints,
    distance_residual,
    mesh_edges,
    mesh_hinges,
    part_offsets,
    project_bending_constraints,
    project_bending_constraints_coloured,
    project_distance_constraints,
    project_distance_constraints_coloured,
    project_internal_by_part,
)

__all__ = [
    "dihedral_angle_gradients",
    "init_bending_constraint",
    "init_distance_constraint",
    "signed_dihedral_angle",
    "solve_attachment_constraint",
    "solve_bending_constraint",
    "solve_distance_constraint",
    "wrap_angle",
    "colour_constraints",
    "mesh_edges",
    "mesh_hinges",
    "project_bending_constraints",
    "project_bending_constraints_coloured",
    "project_distance_constraints",
    "project_distance_constraints_coloured",
    "project_internal_by_part",
    "part_offsets",
    "bending_residual",
    "distance_residual",
]
