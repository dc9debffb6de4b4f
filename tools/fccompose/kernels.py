"""The model's kernels: template positions, rest values (edge lengths, eq. 3.11; signed dihedral
angles, eq. 3.13) at the florets' developmental times, and the prediction of a growth step.
:class:`~.system.Model` launches them with keyword wrappers that take a :class:`~.system.Schedule`.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from inflo.tools.pbd.constraints import signed_dihedral_angle, wrap_angle


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


@njit(cache=True)
def ramped_petals(frames, weight, factor, lo, hi, out):
    """A template's frames with its petals grown by a petal factor that takes effect with the
    floret's development (fcc ``petal ramp``): local vertex v of frame s (of F) scaled by
    ``1 + w_v (factor - 1) g(u)`` about the floret's origin, ``u = s / (F - 1)`` (1 for a single
    frame), ``g`` the smoothstep ``3t^2 - 2t^3`` of ``t = (u - lo) / (hi - lo)`` clamped to [0, 1]:
    the bud (u <= lo) as read, the open floret (u >= hi) grown by the whole factor.

    ``frames`` (F, nv, 3), ``weight`` (nv,) petal weights in [0, 1], ``0 <= lo < hi <= 1``;
    writes ``out`` (F, nv, 3)."""
    nf = frames.shape[0]
    nv = frames.shape[1]
    for s in range(nf):
        u = 1.0 if nf < 2 else s / (nf - 1.0)
        t = (u - lo) / (hi - lo)
        if t < 0.0:
            t = 0.0
        elif t > 1.0:
            t = 1.0
        g = t * t * (3.0 - 2.0 * t)
        for v in range(nv):
            grow = 1.0 + weight[v] * (factor - 1.0) * g
            for d in range(3):
                out[s, v, d] = frames[s, v, d] * grow
