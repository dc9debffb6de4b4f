"""Constraint kernels of position based dynamics (thesis ch. 3, eqs. 3.7-3.13, appendix A).

Every ``solve_*`` kernel is a pure numba function in the style of Bender's
``PositionBasedDynamics.cpp``: positions ``p_i`` ((3,) float64) and inverse masses ``w_i`` in,
corrections ``corr_i`` ((3,) float64, written in place) out, ``False`` returned for a degenerate
case (zero total inverse mass, zero-length edge, collapsed triangle) with the corrections zeroed.
Nothing here writes a position: the caller adds the corrections.

The projection is the PBD step of eq. 3.10,

    dp_i = -k * w_i * C(p) / sum_j (w_j |grad_j C|^2) * grad_i C,

with ``k`` the stiffness in [0, 1] (eqs. 3.7-3.9). Because the gradients of an internal constraint
sum to zero (translation invariance) and ``dp_i`` is weighted by ``w_i = 1/m_i``, the corrections
conserve linear momentum (eq. 3.3); because the constraint is invariant under rotation, they
conserve angular momentum as well (eq. 3.4).
"""
from __future__ import annotations

import math

from numba import njit

__all__ = [
    "wrap_angle",
    "init_distance_constraint",
    "solve_distance_constraint",
    "signed_dihedral_angle",
    "dihedral_angle_gradients",
    "init_bending_constraint",
    "solve_bending_constraint",
    "bounded_bending_scale",
    "BENDING_STEP_BOUND",
    "BENDING_DAMPING",
    "solve_attachment_constraint",
]

_EPS = 1e-300


@njit(cache=True)
def wrap_angle(a):
    """``a`` taken modulo 2 pi into [-pi, pi) (angle differences, docs/vlab_formats.md pitfalls)."""
    two_pi = 2.0 * math.pi
    r = (a + math.pi) % two_pi
    if r < 0.0:
        r += two_pi
    return r - math.pi


@njit(cache=True)
def init_distance_constraint(p0, p1):
    """Rest length ``d`` of the distance constraint of eq. 3.11: ``|p0 - p1|``."""
    dx = p0[0] - p1[0]
    dy = p0[1] - p1[1]
    dz = p0[2] - p1[2]
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True)
def solve_distance_constraint(p0, w0, p1, w1, rest_length, stiffness, corr0, corr1):
    """Project the distance constraint C = |p0 - p1| - d (eq. 3.11) once.

    Parameters
    ----------
    p0, p1 : (3,) float64
        Positions of the edge's two vertices.
    w0, w1 : float
        Inverse masses (0: fixed vertex, never moved).
    rest_length : float
        ``d``, scene units.
    stiffness : float
        ``k`` in [0, 1]; with k = 1 and equal masses one projection restores ``d`` exactly.
    corr0, corr1 : (3,) float64
        Output corrections (overwritten).

    Returns
    -------
    bool
        False when ``w0 + w1 == 0`` or the edge has zero length (corrections zero).
    """
    corr0[:] = 0.0
    corr1[:] = 0.0
    wsum = w0 + w1
    if wsum <= 0.0:
        return False
    dx = p0[0] - p1[0]
    dy = p0[1] - p1[1]
    dz = p0[2] - p1[2]
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    if length <= _EPS:
        return False
    s = stiffness * (length - rest_length) / (length * wsum)
    for c, d in ((0, dx), (1, dy), (2, dz)):
        corr0[c] = -w0 * s * d
        corr1[c] = w1 * s * d
    return True


@njit(cache=True)
def signed_dihedral_angle(p1, p2, p3, p4):
    """Signed dihedral angle phi of the hinge (p1, p2, p3), (p1, p4, p2) (eq. 3.13, fig. 3.1b).

    ``n1 = (p3 - p1) x (p2 - p1)``, ``n2 = (p2 - p1) x (p4 - p1)`` (eq. 3.12), canonical edge
    ``e = p2 - p1``; ``phi = sgn(e . (n1 x n2)) arccos(n1 . n2)``, computed as
    ``atan2(e_hat . (n1 x n2), n1 . n2)`` on unit normals (same value, no loss of precision near
    0 and 180 degrees). 0 for a flat hinge; the sign tells the mirror configurations of fig. 3.2
    apart. Range [-pi, pi] (+pi and -pi are the same folded-flat hinge). Returns 0 for a collapsed
    triangle.
    """
    ex = p2[0] - p1[0]
    ey = p2[1] - p1[1]
    ez = p2[2] - p1[2]
    ax = p3[0] - p1[0]
    ay = p3[1] - p1[1]
    az = p3[2] - p1[2]
    bx = p4[0] - p1[0]
    by = p4[1] - p1[1]
    bz = p4[2] - p1[2]
    # n1 = a x e, n2 = e x b
    n1x = ay * ez - az * ey
    n1y = az * ex - ax * ez
    n1z = ax * ey - ay * ex
    n2x = ey * bz - ez * by
    n2y = ez * bx - ex * bz
    n2z = ex * by - ey * bx
    l1 = math.sqrt(n1x * n1x + n1y * n1y + n1z * n1z)
    l2 = math.sqrt(n2x * n2x + n2y * n2y + n2z * n2z)
    le = math.sqrt(ex * ex + ey * ey + ez * ez)
    if l1 <= _EPS or l2 <= _EPS or le <= _EPS:
        return 0.0
    cx = n1y * n2z - n1z * n2y
    cy = n1z * n2x - n1x * n2z
    cz = n1x * n2y - n1y * n2x
    sin_t = (cx * ex + cy * ey + cz * ez) / (le * l1 * l2)
    cos_t = (n1x * n2x + n1y * n2y + n1z * n2z) / (l1 * l2)
    return math.atan2(sin_t, cos_t)


@njit(cache=True)
def dihedral_angle_gradients(p1, p2, p3, p4, g1, g2, g3, g4):
    """Gradients of :func:`signed_dihedral_angle` with respect to p1..p4 (appendix A).

    With ``e = p2 - p1`` of length L and the unnormalized normals ``n1``, ``n2`` of eq. 3.12, the
    wing vertices move along their triangle's normal, ``grad_3 = L n1/|n1|^2``,
    ``grad_4 = L n2/|n2|^2``, and the edge vertices take the rest so that the four gradients sum
    to zero: ``grad_1 = -((1 - s3) grad_3 + (1 - s4) grad_4)``, ``grad_2 = -(s3 grad_3 + s4 grad_4)``
    with ``s_i = (p_i - p1) . e / L^2`` (Bridson et al. 2003). The gradient is continuous through the
    flat (0) configuration, which is what lets the projection push a hinge through 0 to the side
    of a signed rest angle (the case appendix A treats separately with arccos).

    Returns False (gradients zero) for a collapsed triangle or edge.
    """
    ex = p2[0] - p1[0]
    ey = p2[1] - p1[1]
    ez = p2[2] - p1[2]
    ax = p3[0] - p1[0]
    ay = p3[1] - p1[1]
    az = p3[2] - p1[2]
    bx = p4[0] - p1[0]
    by = p4[1] - p1[1]
    bz = p4[2] - p1[2]
    n1x = ay * ez - az * ey
    n1y = az * ex - ax * ez
    n1z = ax * ey - ay * ex
    n2x = ey * bz - ez * by
    n2y = ez * bx - ex * bz
    n2z = ex * by - ey * bx
    q1 = n1x * n1x + n1y * n1y + n1z * n1z
    q2 = n2x * n2x + n2y * n2y + n2z * n2z
    le2 = ex * ex + ey * ey + ez * ez
    for c in range(3):
        g1[c] = 0.0
        g2[c] = 0.0
        g3[c] = 0.0
        g4[c] = 0.0
    if q1 <= _EPS or q2 <= _EPS or le2 <= _EPS:
        return False
    le = math.sqrt(le2)
    f3 = le / q1
    f4 = le / q2
    g3[0] = f3 * n1x
    g3[1] = f3 * n1y
    g3[2] = f3 * n1z
    g4[0] = f4 * n2x
    g4[1] = f4 * n2y
    g4[2] = f4 * n2z
    s3 = (ax * ex + ay * ey + az * ez) / le2
    s4 = (bx * ex + by * ey + bz * ez) / le2
    for c in range(3):
        g1[c] = -((1.0 - s3) * g3[c] + (1.0 - s4) * g4[c])
        g2[c] = -(s3 * g3[c] + s4 * g4[c])
    return True


BENDING_STEP_BOUND = math.pi
"""A bending projection moves no vertex by more than this times the hinge's size (the longest of
its shared edge and its two wing heights). The linearized step ``C / |grad C|`` grows without bound
when the only movable vertices barely change the angle (an edge vertex whose wing vertices project
onto the other end of the edge, a nearly degenerate wing); a step of the linearized projection of
a well-shaped hinge turns a wing by at most pi, i.e. moves a vertex by at most pi x its height, so
the bound only trims those runaway steps."""


BENDING_DAMPING = 1e-12
"""The bending projection's denominator ``sum_i w_i |grad_i|^2`` gets ``BENDING_DAMPING x
max_i |grad_i|^2`` (over all four vertices, movable or not) added: a damped (Levenberg-Marquardt)
step. It changes the step of a hinge whose movable vertices carry a fair share of the gradient by
about 1e-12 (nothing), and it stops the one case the linearized step cannot take: a hinge whose
only movable vertices are edge vertices with a (nearly) vanishing gradient, e.g. the wing vertices
fixed and projecting onto the ends of the shared edge (a one-segment cylinder standing on a fixed
base ring). There ``C / |grad C|^2`` turns a round-off angle error of 1e-14 at rest into a move the
size of the floret."""


@njit(cache=True, inline="always")
def _sq(g):
    return g[0] * g[0] + g[1] * g[1] + g[2] * g[2]


@njit(cache=True, inline="always")
def bounded_bending_scale(s, m, le2, q1, q2):
    """The bending step scale ``s = -k C / sum_i w_i |grad_i|^2`` reduced so that no vertex moves
    by more than :data:`BENDING_STEP_BOUND` x the hinge's size.

    ``m`` is ``max_i w_i^2 |grad_i|^2`` (the largest displacement is ``|s| sqrt(m)``), ``le2`` the
    squared length of the shared edge, ``q1``, ``q2`` the squared norms of the unnormalized
    normals (``|n_i| = |e| h_i``, so ``h_i^2 = q_i / le2``)."""
    size2 = max(le2, max(q1, q2) / le2)
    lim2 = BENDING_STEP_BOUND * BENDING_STEP_BOUND * size2
    if s * s * m > lim2:
        return math.copysign(math.sqrt(lim2 / m), s)
    return s


@njit(cache=True)
def init_bending_constraint(p1, p2, p3, p4):
    """Rest angle phi of the bending constraint of the hinge (p1, p2, p3), (p1, p4, p2) (eq. 3.13)."""
    return signed_dihedral_angle(p1, p2, p3, p4)


@njit(cache=True)
def solve_bending_constraint(p1, w1, p2, w2, p3, w3, p4, w4, rest_angle, stiffness,
                             corr1, corr2, corr3, corr4):
    """Project the signed dihedral bending constraint once (eq. 3.13, appendix A).

    ``C = wrap(phi(p1, p2, p3, p4) - rest_angle)`` with the difference taken modulo 2 pi into
    [-pi, pi) (so a hinge near +-180 degrees does not take the long way round), projected with
    eq. 3.10 on the gradients of :func:`dihedral_angle_gradients`. A hinge on the wrong side of the
    flat configuration is rotated through 0 towards the sign of its rest angle, never into the
    mirror configuration (fig. 3.2).

    Parameters
    ----------
    p1, p2 : (3,) float64
        The shared edge, canonical direction ``e = p2 - p1``.
    p3, p4 : (3,) float64
        Wing vertices of triangles (p1, p2, p3) and (p1, p4, p2).
    w1..w4 : float
        Inverse masses.
    rest_angle : float
        Signed rest angle phi, radians, from :func:`init_bending_constraint`.
    stiffness : float
        ``k`` in [0, 1].
    corr1..corr4 : (3,) float64
        Output corrections (overwritten).

    Returns
    -------
    bool
        False for a degenerate hinge or zero total inverse mass (corrections zero).
    """
    ok = dihedral_angle_gradients(p1, p2, p3, p4, corr1, corr2, corr3, corr4)
    if not ok:
        return False
    c = wrap_angle(signed_dihedral_angle(p1, p2, p3, p4) - rest_angle)
    d1 = w1 * (corr1[0] * corr1[0] + corr1[1] * corr1[1] + corr1[2] * corr1[2])
    d2 = w2 * (corr2[0] * corr2[0] + corr2[1] * corr2[1] + corr2[2] * corr2[2])
    d3 = w3 * (corr3[0] * corr3[0] + corr3[1] * corr3[1] + corr3[2] * corr3[2])
    d4 = w4 * (corr4[0] * corr4[0] + corr4[1] * corr4[1] + corr4[2] * corr4[2])
    denom = d1 + d2 + d3 + d4
    if denom <= _EPS:
        for i in range(3):
            corr1[i] = 0.0
            corr2[i] = 0.0
            corr3[i] = 0.0
            corr4[i] = 0.0
        return False
    g_max = max(max(_sq(corr1), _sq(corr2)), max(_sq(corr3), _sq(corr4)))
    s = -stiffness * c / (denom + BENDING_DAMPING * g_max)
    e = p2 - p1
    le2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2]
    # |n_i|^2 = le2 / |grad_i|^2 for the wing vertices (|grad_3| = |e| / |n1|)
    g3 = corr3[0] * corr3[0] + corr3[1] * corr3[1] + corr3[2] * corr3[2]
    g4 = corr4[0] * corr4[0] + corr4[1] * corr4[1] + corr4[2] * corr4[2]
    s = bounded_bending_scale(s, max(w1 * d1, w2 * d2, w3 * d3, w4 * d4), le2, le2 / g3, le2 / g4)
    for i in range(3):
        corr1[i] *= s * w1
        corr2[i] *= s * w2
        corr3[i] *= s * w3
        corr4[i] *= s * w4
    return True


@njit(cache=True)
def solve_attachment_constraint(p, w, target, corr):
    """Attachment constraint of a fixed vertex (inverse mass 0, thesis 3.x and ch. 5).

    A vertex with ``w == 0`` is placed on ``target`` (its template position carried by the
    floret's placement); a free vertex (``w > 0``) is not attached and gets no correction.

    Returns
    -------
    bool
        True when a correction was written.
    """
    if w != 0.0:
        corr[:] = 0.0
        return False
    for i in range(3):
        corr[i] = target[i] - p[i]
    return True
