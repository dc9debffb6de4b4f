"""Sweeps of the PBD constraint kernels over structure-of-arrays constraint sets (thesis 3, Alg. 1).

Positions are ``vertex_x (n, 3) float64`` (C-contiguous), inverse masses ``vertex_inv_mass (n,)
float64``. Constraint sets are index arrays plus per-constraint rest values and stiffness:

- distance: ``edge_indices (e, 2) int32``, ``edge_rest_length (e,)``, ``edge_stiffness (e,)``;
- bending: ``hinge_indices (h, 4) int32`` as (p1, p2, p3, p4) of eq. 3.12, ``hinge_rest_angle
  (h,)`` radians, ``hinge_stiffness (h,)``.

:func:`project_distance_constraints` and :func:`project_bending_constraints` are the serial
non-linear Gauss-Seidel sweeps of section 3 (constraints projected one after another in array
order, each seeing the positions updated by the previous ones): deterministic. The ``_coloured``
variants sweep colour by colour (:func:`colour_constraints`: no two constraints of a colour share a
vertex), each colour with ``prange``; their result does not depend on thread timing, but differs
from the serial sweep's (another order). Use them only where they measure faster (bench_pbd).

The arithmetic of the sweeps is that of :func:`~inflo.tools.pbd.constraints.solve_distance_constraint`
and :func:`~inflo.tools.pbd.constraints.solve_bending_constraint`, inlined on scalars for speed;
tests check them against a loop over the pure kernels.

:func:`project_internal_by_part` runs whole solves (``iterations`` sweeps of distance then bending
constraints) part by part, where a part is a set of vertices no constraint links to another part
(in ``fccompose`` a floret: internal constraints never join two florets). The parts are solved in
parallel (``prange``; no vertex is shared, so the result does not depend on thread timing and
equals the serial sweep's part by part), and each part stops as soon as one of its sweeps moved no
vertex by more than ``tolerance``: florets no collision touched, which their prediction already put
at rest, cost one sweep instead of ``iterations``.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .constraints import BENDING_DAMPING, bounded_bending_scale, signed_dihedral_angle, wrap_angle

__all__ = [
    "mesh_edges",
    "mesh_hinges",
    "colour_constraints",
    "project_distance_constraints",
    "project_distance_constraints_coloured",
    "project_bending_constraints",
    "project_bending_constraints_coloured",
    "project_internal_by_part",
    "project_internal_of_parts",
    "project_internal_by_part_serial",
    "project_internal_of_parts_serial",
    "solve_parts",
    "part_offsets",
    "edge_lengths",
    "edge_stretch_range",
    "parts_out_of_bounds",
    "hinge_angles",
    "distance_residual",
    "bending_residual",
]


# --------------------------------------------------------------------------------------------------
# Topology
# --------------------------------------------------------------------------------------------------


def mesh_edges(tri_indices: np.ndarray) -> np.ndarray:
    """Unique undirected edges of a triangle mesh.

    Parameters
    ----------
    tri_indices : (m, 3) int
        Triangles.

    Returns
    -------
    (e, 2) int32
        Edges ``(i, j)`` with ``i < j``, sorted lexicographically.
    """
    t = np.asarray(tri_indices, dtype=np.int64).reshape(-1, 3)
    if len(t) == 0:
        return np.zeros((0, 2), np.int32)
    e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    e.sort(axis=1)
    e = np.unique(e, axis=0)
    return np.ascontiguousarray(e, dtype=np.int32)


def mesh_hinges(tri_indices: np.ndarray) -> np.ndarray:
    """Hinges (pairs of triangles sharing an edge) for bending constraints (eq. 3.12, fig. 3.1b).

    For an edge shared by triangle ``(a, b, c)`` (with the directed edge a -> b) and a second
    triangle with third vertex ``d``, the hinge is ``(p1, p2, p3, p4) = (a, b, c, d)``: triangles
    (p1, p2, p3) and (p1, p4, p2), canonical edge ``e = p2 - p1``. On a consistently oriented
    mesh a flat hinge has angle 0. An edge with k > 2 triangles (non-manifold) gives k - 1 hinges
    (consecutive triangles in face order).

    Returns
    -------
    (h, 4) int32
        Sorted by the (undirected) edge, then face order: deterministic.
    """
    t = np.asarray(tri_indices, dtype=np.int64).reshape(-1, 3)
    m = len(t)
    if m == 0:
        return np.zeros((0, 4), np.int32)
    # directed edges (a -> b) with opposite vertex c, per face
    a = np.concatenate([t[:, 0], t[:, 1], t[:, 2]])
    b = np.concatenate([t[:, 1], t[:, 2], t[:, 0]])
    c = np.concatenate([t[:, 2], t[:, 0], t[:, 1]])
    face = np.concatenate([np.arange(m)] * 3)
    lo = np.minimum(a, b)
    hi = np.maximum(a, b)
    order = np.lexsort((face, hi, lo))
    lo, hi, a, b, c = lo[order], hi[order], a[order], b[order], c[order]
    same = (lo[1:] == lo[:-1]) & (hi[1:] == hi[:-1])
    k = np.nonzero(same)[0]
    h = np.stack([a[k], b[k], c[k], c[k + 1]], axis=1)
    return np.ascontiguousarray(h, dtype=np.int32)


@njit(cache=True)
def _colour_greedy(indices, n_vertices):
    n, k = indices.shape
    colour = np.empty(n, np.int32)
    # per vertex: bitmask of colours used (up to 64 per word; extra words as needed)
    used = np.zeros((n_vertices, 4), np.uint64)
    n_colours = 0
    for c in range(n):
        chosen = -1
        for word in range(4):
            mask = np.uint64(0)
            for j in range(k):
                mask |= used[indices[c, j], word]
            if mask != np.uint64(0xFFFFFFFFFFFFFFFF):
                for bit in range(64):
                    if (mask >> np.uint64(bit)) & np.uint64(1) == np.uint64(0):
                        chosen = word * 64 + bit
                        break
            if chosen >= 0:
                break
        if chosen < 0:
            chosen = 255  # more than 256 colours would need more words; cannot happen for meshes
        colour[c] = chosen
        for j in range(k):
            used[indices[c, j], chosen // 64] |= np.uint64(1) << np.uint64(chosen % 64)
        if chosen + 1 > n_colours:
            n_colours = chosen + 1
    return colour, n_colours


def colour_constraints(indices: np.ndarray, n_vertices: int) -> tuple[np.ndarray, np.ndarray]:
    """Greedy graph colouring: no two constraints of one colour share a vertex.

    Parameters
    ----------
    indices : (n, k) int32
        Vertex indices of each constraint (k = 2 for distance, 4 for bending).
    n_vertices : int

    Returns
    -------
    order : (n,) int64
        Constraint indices grouped by colour (ascending index within a colour).
    colour_offsets : (n_colours + 1,) int64
        Colour ``c`` is ``order[colour_offsets[c]:colour_offsets[c + 1]]``.
    """
    idx = np.ascontiguousarray(indices, dtype=np.int32)
    if len(idx) == 0:
        return np.zeros(0, np.int64), np.zeros(1, np.int64)
    colour, n_colours = _colour_greedy(idx, int(n_vertices))
    order = np.argsort(colour, kind="stable").astype(np.int64)
    counts = np.bincount(colour, minlength=n_colours)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    return order, offsets


# --------------------------------------------------------------------------------------------------
# Distance constraints (eq. 3.11)
# --------------------------------------------------------------------------------------------------


@njit(cache=True, inline="always")
def _distance_one(x, w, i, j, rest, k):
    w0 = w[i]
    w1 = w[j]
    wsum = w0 + w1
    if wsum <= 0.0:
        return 0.0
    dx = x[i, 0] - x[j, 0]
    dy = x[i, 1] - x[j, 1]
    dz = x[i, 2] - x[j, 2]
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    if length <= 1e-300:
        return 0.0
    s = k * (length - rest) / (length * wsum)
    a = w0 * s
    b = w1 * s
    x[i, 0] -= a * dx
    x[i, 1] -= a * dy
    x[i, 2] -= a * dz
    x[j, 0] += b * dx
    x[j, 1] += b * dy
    x[j, 2] += b * dz
    return abs(s) * length * wsum


@njit(cache=True)
def project_distance_constraints(vertex_x, vertex_inv_mass, edge_indices, edge_rest_length,
                                 edge_stiffness):
    """One Gauss-Seidel sweep of every distance constraint (eq. 3.11), in array order, in place.

    Returns the largest ``k |C|`` of the sweep (scene units)."""
    m = 0.0
    for e in range(edge_indices.shape[0]):
        d = _distance_one(vertex_x, vertex_inv_mass, edge_indices[e, 0], edge_indices[e, 1],
                          edge_rest_length[e], edge_stiffness[e])
        if d > m:
            m = d
    return m


@njit(cache=True, parallel=True)
def project_distance_constraints_coloured(vertex_x, vertex_inv_mass, edge_indices, edge_rest_length,
                                          edge_stiffness, order, colour_offsets):
    """One sweep of the distance constraints colour by colour, each colour in parallel (in place)."""
    for c in range(colour_offsets.shape[0] - 1):
        start = colour_offsets[c]
        stop = colour_offsets[c + 1]
        for q in prange(start, stop):
            e = order[q]
            _distance_one(vertex_x, vertex_inv_mass, edge_indices[e, 0], edge_indices[e, 1],
                          edge_rest_length[e], edge_stiffness[e])


# --------------------------------------------------------------------------------------------------
# Bending constraints (eq. 3.13, appendix A)
# --------------------------------------------------------------------------------------------------


@njit(cache=True, inline="always")
def _bending_one(x, w, i1, i2, i3, i4, rest, k):
    """Scalar form of solve_bending_constraint (one pass: angle, gradients, update).

    Returns the largest correction applied (0 when skipped)."""
    ex = x[i2, 0] - x[i1, 0]
    ey = x[i2, 1] - x[i1, 1]
    ez = x[i2, 2] - x[i1, 2]
    ax = x[i3, 0] - x[i1, 0]
    ay = x[i3, 1] - x[i1, 1]
    az = x[i3, 2] - x[i1, 2]
    bx = x[i4, 0] - x[i1, 0]
    by = x[i4, 1] - x[i1, 1]
    bz = x[i4, 2] - x[i1, 2]
    n1x = ay * ez - az * ey
    n1y = az * ex - ax * ez
    n1z = ax * ey - ay * ex
    n2x = ey * bz - ez * by
    n2y = ez * bx - ex * bz
    n2z = ex * by - ey * bx
    q1 = n1x * n1x + n1y * n1y + n1z * n1z
    q2 = n2x * n2x + n2y * n2y + n2z * n2z
    le2 = ex * ex + ey * ey + ez * ez
    if q1 <= 1e-300 or q2 <= 1e-300 or le2 <= 1e-300:
        return 0.0
    le = math.sqrt(le2)
    cx = n1y * n2z - n1z * n2y
    cy = n1z * n2x - n1x * n2z
    cz = n1x * n2y - n1y * n2x
    phi = math.atan2((cx * ex + cy * ey + cz * ez) / le, n1x * n2x + n1y * n2y + n1z * n2z)
    c = phi - rest
    if c >= math.pi or c < -math.pi:  # difference modulo 2 pi (rest angles lie in [-pi, pi])
        c = wrap_angle(c)
    if c == 0.0:
        return 0.0
    f3 = le / q1
    f4 = le / q2
    s3 = (ax * ex + ay * ey + az * ez) / le2
    s4 = (bx * ex + by * ey + bz * ez) / le2
    # |grad|^2: g3 = f3 n1, g4 = f4 n2, g1 = -((1-s3) g3 + (1-s4) g4), g2 = -(s3 g3 + s4 g4)
    g3x = f3 * n1x
    g3y = f3 * n1y
    g3z = f3 * n1z
    g4x = f4 * n2x
    g4y = f4 * n2y
    g4z = f4 * n2z
    g1x = -((1.0 - s3) * g3x + (1.0 - s4) * g4x)
    g1y = -((1.0 - s3) * g3y + (1.0 - s4) * g4y)
    g1z = -((1.0 - s3) * g3z + (1.0 - s4) * g4z)
    g2x = -(s3 * g3x + s4 * g4x)
    g2y = -(s3 * g3y + s4 * g4y)
    g2z = -(s3 * g3z + s4 * g4z)
    wa = w[i1]
    wb = w[i2]
    wc = w[i3]
    wd = w[i4]
    u1 = g1x * g1x + g1y * g1y + g1z * g1z
    u2 = g2x * g2x + g2y * g2y + g2z * g2z
    u3 = g3x * g3x + g3y * g3y + g3z * g3z
    u4 = g4x * g4x + g4y * g4y + g4z * g4z
    d1 = wa * u1
    d2 = wb * u2
    d3 = wc * u3
    d4 = wd * u4
    denom = d1 + d2 + d3 + d4
    if denom <= 1e-300:
        return 0.0
    # damped where the movable vertices barely change the angle (constraints.BENDING_DAMPING)
    sc = -k * c / (denom + BENDING_DAMPING * max(max(u1, u2), max(u3, u4)))
    # no vertex moves by more than BENDING_STEP_BOUND x the hinge's size (constraints.py)
    sc = bounded_bending_scale(sc, max(wa * d1, wb * d2, wc * d3, wd * d4), le2, q1, q2)
    t = sc * wa
    x[i1, 0] += t * g1x
    x[i1, 1] += t * g1y
    x[i1, 2] += t * g1z
    t = sc * wb
    x[i2, 0] += t * g2x
    x[i2, 1] += t * g2y
    x[i2, 2] += t * g2z
    t = sc * wc
    x[i3, 0] += t * g3x
    x[i3, 1] += t * g3y
    x[i3, 2] += t * g3z
    t = sc * wd
    x[i4, 0] += t * g4x
    x[i4, 1] += t * g4y
    x[i4, 2] += t * g4z
    return abs(sc) * math.sqrt(denom)


@njit(cache=True)
def project_bending_constraints(vertex_x, vertex_inv_mass, hinge_indices, hinge_rest_angle,
                                hinge_stiffness):
    """One Gauss-Seidel sweep of every bending constraint (eq. 3.13), in array order, in place.

    Returns a measure of the largest correction of the sweep (``|s| sqrt(sum w |grad|^2)``,
    scene units; 0 when every hinge is at its rest angle)."""
    m = 0.0
    for h in range(hinge_indices.shape[0]):
        d = _bending_one(vertex_x, vertex_inv_mass, hinge_indices[h, 0], hinge_indices[h, 1],
                         hinge_indices[h, 2], hinge_indices[h, 3], hinge_rest_angle[h],
                         hinge_stiffness[h])
        if d > m:
            m = d
    return m


@njit(cache=True, parallel=True)
def project_bending_constraints_coloured(vertex_x, vertex_inv_mass, hinge_indices, hinge_rest_angle,
                                         hinge_stiffness, order, colour_offsets):
    """One sweep of the bending constraints colour by colour, each colour in parallel (in place)."""
    for c in range(colour_offsets.shape[0] - 1):
        start = colour_offsets[c]
        stop = colour_offsets[c + 1]
        for q in prange(start, stop):
            h = order[q]
            _bending_one(vertex_x, vertex_inv_mass, hinge_indices[h, 0], hinge_indices[h, 1],
                         hinge_indices[h, 2], hinge_indices[h, 3], hinge_rest_angle[h],
                         hinge_stiffness[h])


# --------------------------------------------------------------------------------------------------
# Whole solves part by part (florets), parts in parallel
# --------------------------------------------------------------------------------------------------


def part_offsets(indices: np.ndarray, vertex_part: np.ndarray, n_parts: int) -> np.ndarray | None:
    """(n_parts + 1,) int64 offsets of each part's constraints in ``indices``, or None when the
    constraints are not grouped by part (their first vertex's part must not decrease along the
    array) or some constraint joins two parts."""
    idx = np.asarray(indices)
    if len(idx) == 0:
        return np.zeros(n_parts + 1, np.int64)
    part = np.asarray(vertex_part)[idx]
    if (part != part[:, :1]).any():
        return None
    first = part[:, 0]
    if (np.diff(first) < 0).any():
        return None
    return np.searchsorted(first, np.arange(n_parts + 1), side="left").astype(np.int64)


@njit(cache=True, inline="always")
def _solve_part(vertex_x, vertex_inv_mass, edge_indices, edge_rest_length, edge_stiffness, edge_offsets,
                hinge_indices, hinge_rest_angle, hinge_stiffness, hinge_offsets, f, iterations, tolerance):
    """Up to ``iterations`` sweeps of part ``f``'s constraints, stopping after the first whose
    largest correction is ``<= tolerance``; returns the sweeps run."""
    n = 0
    for _ in range(iterations):
        m = 0.0
        for e in range(edge_offsets[f], edge_offsets[f + 1]):
            d = _distance_one(vertex_x, vertex_inv_mass, edge_indices[e, 0], edge_indices[e, 1],
                              edge_rest_length[e], edge_stiffness[e])
            if d > m:
                m = d
        for h in range(hinge_offsets[f], hinge_offsets[f + 1]):
            d = _bending_one(vertex_x, vertex_inv_mass, hinge_indices[h, 0], hinge_indices[h, 1],
                             hinge_indices[h, 2], hinge_indices[h, 3], hinge_rest_angle[h],
                             hinge_stiffness[h])
            if d > m:
                m = d
        n += 1
        if m <= tolerance:
            break
    return n


@njit(cache=True, parallel=True)
def project_internal_by_part(vertex_x, vertex_inv_mass, edge_indices, edge_rest_length, edge_stiffness,
                             edge_offsets, hinge_indices, hinge_rest_angle, hinge_stiffness,
                             hinge_offsets, iterations, tolerance, sweeps):
    """Up to ``iterations`` Gauss-Seidel sweeps (distance eq. 3.11, then bending eq. 3.13) of each
    part's constraints, parts in parallel, in place.

    Part ``f`` owns edges ``edge_offsets[f]:edge_offsets[f+1]`` and hinges likewise
    (:func:`part_offsets`); no constraint may touch two parts. A part stops after the first sweep
    whose largest correction is ``<= tolerance``. ``sweeps[f]`` receives the sweeps part f ran.
    """
    n_parts = edge_offsets.shape[0] - 1
    for f in prange(n_parts):
        sweeps[f] = _solve_part(vertex_x, vertex_inv_mass, edge_indices, edge_rest_length, edge_stiffness,
                                edge_offsets, hinge_indices, hinge_rest_angle, hinge_stiffness,
                                hinge_offsets, f, iterations, tolerance)


@njit(cache=True, parallel=True)
def project_internal_of_parts(vertex_x, vertex_inv_mass, edge_indices, edge_rest_length, edge_stiffness,
                              edge_offsets, hinge_indices, hinge_rest_angle, hinge_stiffness,
                              hinge_offsets, parts, iterations, tolerance):
    """:func:`project_internal_by_part` over the listed ``parts`` only ((k,) int64 part indices,
    each at most once), in place; returns the total number of sweeps run.

    fccompose relaxes the florets a collision round moved with it, between the rounds of the
    collision response (thesis Alg. 1 solves collision and internal constraints together), so that
    the florets keep their shape while their contacts are resolved.
    """
    sweeps = np.zeros(parts.shape[0], np.int64)
    for k in prange(parts.shape[0]):
        sweeps[k] = _solve_part(vertex_x, vertex_inv_mass, edge_indices, edge_rest_length, edge_stiffness,
                                edge_offsets, hinge_indices, hinge_rest_angle, hinge_stiffness,
                                hinge_offsets, parts[k], iterations, tolerance)
    return sweeps.sum()


@njit(cache=True)
def project_internal_by_part_serial(vertex_x, vertex_inv_mass, edge_indices, edge_rest_length, edge_stiffness,
                                    edge_offsets, hinge_indices, hinge_rest_angle, hinge_stiffness,
                                    hinge_offsets, iterations, tolerance, sweeps):
    """:func:`project_internal_by_part` on one thread (the same result: parts share no
    constraint), for systems too small to pay for waking the thread pool."""
    for f in range(edge_offsets.shape[0] - 1):
        sweeps[f] = _solve_part(vertex_x, vertex_inv_mass, edge_indices, edge_rest_length, edge_stiffness,
                                edge_offsets, hinge_indices, hinge_rest_angle, hinge_stiffness,
                                hinge_offsets, f, iterations, tolerance)


@njit(cache=True)
def project_internal_of_parts_serial(vertex_x, vertex_inv_mass, edge_indices, edge_rest_length, edge_stiffness,
                                     edge_offsets, hinge_indices, hinge_rest_angle, hinge_stiffness,
                                     hinge_offsets, parts, iterations, tolerance):
    """:func:`project_internal_of_parts` on one thread (the same result)."""
    n = 0
    for k in range(parts.shape[0]):
        n += _solve_part(vertex_x, vertex_inv_mass, edge_indices, edge_rest_length, edge_stiffness,
                         edge_offsets, hinge_indices, hinge_rest_angle, hinge_stiffness,
                         hinge_offsets, parts[k], iterations, tolerance)
    return n


#: below this many constraints (edges + hinges) in the parts a call solves, the serial kernels run:
#: waking the thread pool costs more than the work (a small canopy's step, a collision round's
#: relaxation of the few florets it moved; milliseconds per launch on a loaded 2-core machine)
SERIAL_CONSTRAINTS_BELOW = 20000


def solve_parts(vertex_x, vertex_inv_mass, edge_indices, edge_rest_length, edge_stiffness, edge_offsets,
                hinge_indices, hinge_rest_angle, hinge_stiffness, hinge_offsets, iterations, tolerance,
                sweeps, parts=None):
    """Every part's internal constraints (``parts`` None: :func:`project_internal_by_part`, sweeps
    per part into ``sweeps``) or the listed parts' (:func:`project_internal_of_parts`; returns the
    sweeps run), in parallel or, below :data:`SERIAL_CONSTRAINTS_BELOW` constraints, serially --
    the same positions either way."""
    args = (vertex_x, vertex_inv_mass, edge_indices, edge_rest_length, edge_stiffness, edge_offsets,
            hinge_indices, hinge_rest_angle, hinge_stiffness, hinge_offsets)
    if parts is None:
        small = len(edge_indices) + len(hinge_indices) < SERIAL_CONSTRAINTS_BELOW
        run = project_internal_by_part_serial if small else project_internal_by_part
        run(*args, iterations, tolerance, sweeps)
        return int(sweeps.sum())
    work = int((edge_offsets[parts + 1] - edge_offsets[parts]).sum()
               + (hinge_offsets[parts + 1] - hinge_offsets[parts]).sum())
    run = project_internal_of_parts_serial if work < SERIAL_CONSTRAINTS_BELOW else project_internal_of_parts
    return int(run(*args, parts, iterations, tolerance))


# --------------------------------------------------------------------------------------------------
# Rest values and residuals
# --------------------------------------------------------------------------------------------------


@njit(cache=True)
def edge_lengths(vertex_x, edge_indices):
    """(e,) float64: current length of every edge (rest lengths when given template positions)."""
    n = edge_indices.shape[0]
    out = np.empty(n)
    for e in range(n):
        i = edge_indices[e, 0]
        j = edge_indices[e, 1]
        dx = vertex_x[i, 0] - vertex_x[j, 0]
        dy = vertex_x[i, 1] - vertex_x[j, 1]
        dz = vertex_x[i, 2] - vertex_x[j, 2]
        out[e] = math.sqrt(dx * dx + dy * dy + dz * dz)
    return out


@njit(cache=True)
def hinge_angles(vertex_x, hinge_indices):
    """(h,) float64: signed dihedral angle (eq. 3.13) of every hinge, radians."""
    n = hinge_indices.shape[0]
    out = np.empty(n)
    for h in range(n):
        out[h] = signed_dihedral_angle(vertex_x[hinge_indices[h, 0]], vertex_x[hinge_indices[h, 1]],
                                       vertex_x[hinge_indices[h, 2]], vertex_x[hinge_indices[h, 3]])
    return out


@njit(cache=True)
def distance_residual(vertex_x, edge_indices, edge_rest_length):
    """RMS of ``|p_i - p_j| - d`` over all edges (scene units); 0 for no edges."""
    n = edge_indices.shape[0]
    if n == 0:
        return 0.0
    cur = edge_lengths(vertex_x, edge_indices)
    acc = 0.0
    for e in range(n):
        d = cur[e] - edge_rest_length[e]
        acc += d * d
    return math.sqrt(acc / n)


@njit(cache=True)
def overstretched_edges(vertex_x, edge_indices, edge_rest_length, factor, floor):
    """Indices of the edges longer than ``factor`` x their rest length (rest lengths below
    ``floor`` count as ``floor``): a floret torn apart, the sign of a diverging solve."""
    cur = edge_lengths(vertex_x, edge_indices)
    hit = np.zeros(cur.shape[0], np.bool_)
    for e in range(cur.shape[0]):
        if not cur[e] <= factor * max(edge_rest_length[e], floor):  # NaN counts too
            hit[e] = True
    return np.nonzero(hit)[0]


@njit(cache=True, inline="always")
def _edge_ratio(vertex_x, edge_indices, e, rest):
    """Length of edge ``e`` over ``rest``."""
    i = edge_indices[e, 0]
    j = edge_indices[e, 1]
    dx = vertex_x[i, 0] - vertex_x[j, 0]
    dy = vertex_x[i, 1] - vertex_x[j, 1]
    dz = vertex_x[i, 2] - vertex_x[j, 2]
    return math.sqrt(dx * dx + dy * dy + dz * dz) / rest


@njit(cache=True)
def edge_stretch_range(vertex_x, edge_indices, edge_rest_length, floor):
    """(smallest, largest) ratio of an edge's length to its rest length over the edges whose rest
    length is at least ``floor`` (shorter ones, e.g. the collapsed tip of a bud, have no meaningful
    ratio); (1, 1) when there are none. NaN lengths give NaN. The believability bounds of a canopy
    are [0.5, 1.5] (ARCHITECTURE: every edge within [0.5, 1.5] x its rest length)."""
    lo = 1.0
    hi = 1.0
    for e in range(edge_indices.shape[0]):
        r = edge_rest_length[e]
        if not r >= floor:
            continue
        q = _edge_ratio(vertex_x, edge_indices, e, r)
        if q != q:
            return q, q
        if q < lo:
            lo = q
        if q > hi:
            hi = q
    return lo, hi


@njit(cache=True)
def parts_out_of_bounds(vertex_x, edge_indices, edge_rest_length, vertex_part, n_parts, lo, hi, floor):
    """(n_parts,) bool: the part (floret) has an edge (rest length >= ``floor``) shorter than ``lo``
    or longer than ``hi`` times its rest length, or a non-finite one."""
    out = np.zeros(n_parts, np.bool_)
    for e in range(edge_indices.shape[0]):
        r = edge_rest_length[e]
        if not r >= floor:
            continue
        q = _edge_ratio(vertex_x, edge_indices, e, r)
        if not (q >= lo and q <= hi):
            out[vertex_part[edge_indices[e, 0]]] = True
    return out


@njit(cache=True)
def bending_residual(vertex_x, hinge_indices, hinge_rest_angle):
    """RMS of the wrapped signed dihedral angle error over all hinges (radians); 0 for none."""
    n = hinge_indices.shape[0]
    if n == 0:
        return 0.0
    cur = hinge_angles(vertex_x, hinge_indices)
    acc = 0.0
    for h in range(n):
        d = wrap_angle(cur[h] - hinge_rest_angle[h])
        acc += d * d
    return math.sqrt(acc / n)
