"""Clamped uniform B-spline curves and surfaces (any degree 1..5), evaluated as basis matrices.

Shared numerical core of ``polygonize`` (thesis 2.4) and anything else that evaluates a floret's
petal surfaces. See :mod:`inflo.tools.bspline.core`.
"""
from .core import (
    MAX_DEGREE,
    basis_matrix,
    clamped_knots,
    curve_points,
    surface_grid,
    surface_points,
    surface_weights,
)

__all__ = [
    "MAX_DEGREE",
    "basis_matrix",
    "clamped_knots",
    "curve_points",
    "surface_grid",
    "surface_points",
    "surface_weights",
]
