"""Collision response constraints (thesis 4.3, eqs. 4.6-4.7), projected as PBD constraints.

Both constraints are unilateral (``C >= 0``) and act on four vertices along one contact normal:

- vertex-triangle ``C_vt(q, a, b, c) = (q - a) . n - h`` (eq. 4.6), with ``n`` the triangle's
  unit normal flipped to the side q came from;
- edge-edge ``C_ee(a, b, c, d) = (a - b) . n - h`` (eq. 4.7), ``n`` the normal of the
  pseudo-triangle (b, c, d), i.e. of the plane spanned by the two edges at contact.

inflo evaluates the point of the triangle (or of each edge) that the contact happened at rather
than the triangle's corner ``a`` (for the plane through a, b, c the two agree; they differ once the
triangle turns), and keeps ``n`` fixed for the iterations of one collision round (it is recomputed
at the next detection round). Both constraints then read

    C(x) = sum_i c_i (x_i . n) - h,    c = (1, -w_a, -w_b, -w_c)   (vertex q, triangle a b c, eq. 4.6)
                                       c = (1 - s, s, -(1 - t), -t) (edges ab, cd, eq. 4.7)

with ``w`` the barycentric weights of the contact point on the triangle and s, t the parameters of
the closest points of the two edges. The coefficients sum to zero, so the projection (eq. 3.10)
conserves linear momentum like the internal constraints do.
"""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "solve_vt_collision_constraint",
    "solve_ee_collision_constraint",
    "solve_collision_constraint",
    "project_collision_constraints",
    "collision_constraint_value",
]


@njit(cache=True)
def solve_collision_constraint(p0, w0, p1, w1, p2, w2, p3, w3, coef, normal, thickness, stiffness,
                               corr0, corr1, corr2, corr3):
    """Project ``C = sum_i coef_i (p_i . n) - h >= 0`` once (the common form of eqs. 4.6, 4.7).

    Parameters
    ----------
    p0..p3 : (3,) float64
        The four vertices.
    w0..w3 : float
        Inverse masses.
    coef : (4,) float64
        Coefficients ``c_i`` (sum zero).
    normal : (3,) float64
        Unit contact normal ``n``.
    thickness : float
        ``h`` (the ``spacing`` key).
    stiffness : float
        ``kCollision`` in [0, 1].
    corr0..corr3 : (3,) float64
        Output corrections (overwritten).

    Returns
    -------
    bool
        True when the constraint was violated (C < 0) and corrections were written.
    """
    for d in range(3):
        corr0[d] = 0.0
        corr1[d] = 0.0
        corr2[d] = 0.0
        corr3[d] = 0.0
    c = -thickness
    for d in range(3):
        c += normal[d] * (coef[0] * p0[d] + coef[1] * p1[d] + coef[2] * p2[d] + coef[3] * p3[d])
    if c >= 0.0:
        return False
    denom = (w0 * coef[0] * coef[0] + w1 * coef[1] * coef[1] + w2 * coef[2] * coef[2]
             + w3 * coef[3] * coef[3])
    if denom <= 0.0:
        return False
    s = -stiffness * c / denom
    for d in range(3):
        corr0[d] = s * w0 * coef[0] * normal[d]
        corr1[d] = s * w1 * coef[1] * normal[d]
        corr2[d] = s * w2 * coef[2] * normal[d]
        corr3[d] = s * w3 * coef[3] * normal[d]
    return True


@njit(cache=True)
def solve_vt_collision_constraint(q, wq, a, wa, b, wb, c, wc, bary, normal, thickness, stiffness,
                                  corr_q, corr_a, corr_b, corr_c):
    """Vertex-triangle collision constraint C_vt (eq. 4.6), projected once.

    ``bary`` (3,) are the barycentric weights of the contact point on triangle abc; ``normal`` the
    unit triangle normal oriented towards the side q came from. Returns True when C < 0 and
    corrections were written.
    """
    coef = np.empty(4)
    coef[0] = 1.0
    coef[1] = -bary[0]
    coef[2] = -bary[1]
    coef[3] = -bary[2]
    return solve_collision_constraint(q, wq, a, wa, b, wb, c, wc, coef, normal, thickness,
                                      stiffness, corr_q, corr_a, corr_b, corr_c)


@njit(cache=True)
def solve_ee_collision_constraint(a, wa, b, wb, c, wc, d, wd, s, t, normal, thickness, stiffness,
                                  corr_a, corr_b, corr_c, corr_d):
    """Edge-edge collision constraint C_ee (eq. 4.7, pseudo-triangle), projected once.

    Edges ab and cd touched at ``a + s (b - a)`` and ``c + t (d - c)``; ``normal`` is the unit
    normal of the plane of the two edges, oriented from edge cd towards edge ab as they were
    before the step. Returns True when C < 0 and corrections were written.
    """
    coef = np.empty(4)
    coef[0] = 1.0 - s
    coef[1] = s
    coef[2] = -(1.0 - t)
    coef[3] = -t
    return solve_collision_constraint(a, wa, b, wb, c, wc, d, wd, coef, normal, thickness,
                                      stiffness, corr_a, corr_b, corr_c, corr_d)


@njit(cache=True)
def collision_constraint_value(vertex_x, indices, coef, normal, thickness):
    """(k,) float64: value of each collision constraint (>= 0 satisfied)."""
    n = indices.shape[0]
    out = np.empty(n)
    for k in range(n):
        c = -thickness
        for j in range(4):
            v = indices[k, j]
            for d in range(3):
                c += coef[k, j] * normal[k, d] * vertex_x[v, d]
        out[k] = c
    return out


def project_collision_constraints(vertex_x, vertex_inv_mass, indices, coef, normal, thickness,
                                  stiffness, iterations, reach=None):
    """``iterations`` Gauss-Seidel sweeps over the collision constraints (Alg. 1 lines 16-20).

    Parameters
    ----------
    vertex_x : (n, 3) float64
        Positions, updated in place.
    vertex_inv_mass : (n,) float64
    indices : (k, 4) int32
        Vertices of each constraint (q, a, b, c) or (a, b, c, d).
    coef : (k, 4) float64
        Coefficients of each constraint (see the module docstring).
    normal : (k, 3) float64
        Unit contact normals.
    thickness, stiffness : float
        ``h`` and ``kCollision``.
    iterations : int
    reach : (k,) float64 or None
        Deepest violation each constraint may correct, beyond ``2 h`` (None: any). A crossing that
        started collision-free cannot be deeper than the motion of its elements over the step; a
        constraint violated further than that is stale (its elements have moved apart since the
        round that found it, and its plane, kept fixed, would fling a vertex far away): it is
        skipped.

    Returns
    -------
    int
        Projections that found their constraint violated, over all sweeps.
    """
    if reach is None:
        reach = np.full(indices.shape[0], np.inf)
    return _project_collision_constraints(vertex_x, vertex_inv_mass, indices, coef, normal,
                                          float(thickness), float(stiffness), int(iterations),
                                          np.ascontiguousarray(reach, dtype=np.float64))


@njit(cache=True)
def _project_collision_constraints(vertex_x, vertex_inv_mass, indices, coef, normal, thickness,
                                   stiffness, iterations, reach):
    n = indices.shape[0]
    active = 0
    for _ in range(iterations):
        for k in range(n):
            c = -thickness
            for j in range(4):
                v = indices[k, j]
                for d in range(3):
                    c += coef[k, j] * normal[k, d] * vertex_x[v, d]
            if c >= 0.0 or -c > reach[k] + 2.0 * thickness:
                continue
            denom = 0.0
            for j in range(4):
                denom += vertex_inv_mass[indices[k, j]] * coef[k, j] * coef[k, j]
            if denom <= 0.0:
                continue
            active += 1
            s = -stiffness * c / denom
            for j in range(4):
                v = indices[k, j]
                f = s * vertex_inv_mass[v] * coef[k, j]
                for d in range(3):
                    vertex_x[v, d] += f * normal[k, d]
    return active
