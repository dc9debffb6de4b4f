"""Regional growth (Ijiri et al. 2008, sec. 4): new rest edge lengths and rest dihedral angles.

Each reference triangle T is rebuilt in its own plane from the current rest lengths of its three
edges (the rest shape the previous steps gave it), scaled about its barycentre by the e-growth
rate along the growth direction D and by the w-growth rate across it (fig. 9, eq. 2:
``rate = 1 + dg * map(T)``), and each grown edge's length is that triangle's new rest length
(eq. 3); an edge shared by two triangles takes the mean of the two.

The inner reference triangle T_in (fig. 10) is T with each edge moved perpendicularly inwards by
``s = thickness * tan(theta0 / 2)`` (``theta0`` the edge's current rest angle, 0 on the petal's
border), the moved edges intersected (the lift by ``thickness`` changes nothing in the plane); it
is grown about its own barycentre by the inner rates (e-growth_in, w-growth_in) along the same D.
``s'`` is the signed distance from the grown edge ``(x'_i, x'_j)`` to the midpoint of the grown
inner edge, positive towards the inside of T, and the triangle's share of the new rest angle is
``atan(s' / thickness)`` (eq. 4); the edge's rest angle is the sum of its two triangles' shares.

Angle convention here: ``theta`` is the curl of the hinge towards the inner (adaxial) side, the
side the triangles' normals (right-hand rule) point to: positive when the surface is concave seen
from the inner side (a bud petal curled round the flower axis). Inner growth larger than outer
gives ``s' < 0``: the surface bends away from the inner side (reflexes). The project's signed
dihedral angle (:func:`inflo.tools.pbd.signed_dihedral_angle`, hinges of
:func:`inflo.tools.pbd.mesh_hinges`) of the same hinge is ``-theta`` (:data:`HINGE_SIGN`).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["grow_rest_state", "HINGE_SIGN", "MAX_THETA"]

HINGE_SIGN = -1.0
"""``phi = HINGE_SIGN * theta``: a hinge curled towards its triangles' normals has a negative signed
dihedral angle in :mod:`inflo.tools.pbd` (checked in tests/test_petal_grow.py)."""

MAX_THETA = math.radians(170.0)
"""Rest angles are kept within +-170 degrees (tan(theta/2) stays finite)."""


@njit(cache=True, inline="always")
def _grow_about_barycentre(px, py, dx, dy, e, w):
    """Scale the 2D triangle (px, py: (3,) arrays) about its barycentre by ``e`` along (dx, dy)
    (unit) and ``w`` across it (fig. 9); returns new (qx, qy)."""
    cx = (px[0] + px[1] + px[2]) / 3.0
    cy = (py[0] + py[1] + py[2]) / 3.0
    qx = np.empty(3)
    qy = np.empty(3)
    for k in range(3):
        rx = px[k] - cx
        ry = py[k] - cy
        a = rx * dx + ry * dy  # along D
        bx = rx - a * dx
        by = ry - a * dy  # across D
        qx[k] = cx + e * a * dx + w * bx
        qy[k] = cy + e * a * dy + w * by
    return qx, qy


@njit(cache=True)
def grow_rest_state(tri_indices, tri_edges, tri_uv, edge_rest_length, edge_rest_theta, edge_interior,
                    tri_dir, tri_e, tri_w, tri_e_in, tri_w_in, tri_dg, tri_thickness,
                    new_rest_length, new_rest_theta):
    """One regional growth step (sec. 4.2, eqs. 2-4) over every triangle.

    Parameters
    ----------
    tri_indices : (m, 3) int32
    tri_edges : (m, 3) int64
        Edge index of each triangle's edges (k: corners k -> k+1).
    tri_uv : (m, 3, 2) float64
        uv of each corner (the direction map lives in uv).
    edge_rest_length, edge_rest_theta : (e,) float64
        Current rest lengths and rest angles (``theta``: curl towards the inner side, radians).
    edge_interior : (e,) bool
        The edge has two triangles (a hinge); border edges keep theta 0.
    tri_dir : (m, 2) float64
        Unit growth direction in uv per triangle (eq. 1 averages).
    tri_e, tri_w, tri_e_in, tri_w_in : (m,) float64
        Map values per triangle (eq. 1); the rates are ``1 + dg * value`` (eq. 2).
    tri_dg, tri_thickness : (m,) float64
        The organ's maximum rate ``dg`` and ``thickness`` per triangle.
    new_rest_length, new_rest_theta : (e,) float64
        Output (overwritten).
    """
    ne = edge_rest_length.shape[0]
    count = np.zeros(ne)
    for i in range(ne):
        new_rest_length[i] = 0.0
        new_rest_theta[i] = 0.0
    px = np.empty(3)
    py = np.empty(3)
    ix = np.empty(3)
    iy = np.empty(3)
    s = np.empty(3)
    for t in range(tri_indices.shape[0]):
        e0 = tri_edges[t, 0]
        e1 = tri_edges[t, 1]
        e2 = tri_edges[t, 2]
        l0 = edge_rest_length[e0]  # corner 0 -> 1
        l1 = edge_rest_length[e1]  # corner 1 -> 2
        l2 = edge_rest_length[e2]  # corner 2 -> 0
        # T in its plane from its rest lengths, counter-clockwise (normal = +z = inner side)
        px[0] = 0.0
        py[0] = 0.0
        px[1] = l0
        py[1] = 0.0
        xx = (l0 * l0 + l2 * l2 - l1 * l1) / (2.0 * l0) if l0 > 0.0 else 0.0
        yy2 = l2 * l2 - xx * xx
        px[2] = xx
        py[2] = math.sqrt(yy2) if yy2 > 1e-24 * (l0 * l0 + l2 * l2) else 1e-12 * (l0 + l2)
        # growth direction D: the uv direction mapped by the uv -> plane Jacobian
        u1 = tri_uv[t, 1, 0] - tri_uv[t, 0, 0]
        v1 = tri_uv[t, 1, 1] - tri_uv[t, 0, 1]
        u2 = tri_uv[t, 2, 0] - tri_uv[t, 0, 0]
        v2 = tri_uv[t, 2, 1] - tri_uv[t, 0, 1]
        det = u1 * v2 - u2 * v1
        du = tri_dir[t, 0]
        dv = tri_dir[t, 1]
        if abs(det) > 1e-300:
            # J = P Q^-1 with P = [p1-p0, p2-p0], Q = [uv1-uv0, uv2-uv0]
            a = (v2 * du - u2 * dv) / det
            b = (-v1 * du + u1 * dv) / det
            dx = a * px[1] + b * px[2]
            dy = a * py[1] + b * py[2]
        else:
            dx = 1.0
            dy = 0.0
        dn = math.sqrt(dx * dx + dy * dy)
        if dn > 0.0:
            dx /= dn
            dy /= dn
        else:
            dx = 1.0
            dy = 0.0
        dg = tri_dg[t]
        ge = 1.0 + dg * tri_e[t]
        gw = 1.0 + dg * tri_w[t]
        ge_in = 1.0 + dg * tri_e_in[t]
        gw_in = 1.0 + dg * tri_w_in[t]
        qx, qy = _grow_about_barycentre(px, py, dx, dy, ge, gw)
        # eq. 3: grown edge lengths
        for k in range(3):
            j = (k + 1) % 3
            ek = tri_edges[t, k]
            new_rest_length[ek] += math.sqrt((qx[j] - qx[k]) ** 2 + (qy[j] - qy[k]) ** 2)
            count[ek] += 1.0
        # T_in: each edge moved inwards by s = thickness tan(theta0 / 2) (fig. 10a)
        th = tri_thickness[t]
        area2 = px[1] * py[2] - px[2] * py[1]
        perim = l0 + l1 + l2
        inradius = area2 / perim if perim > 0.0 else 0.0
        for k in range(3):
            ek = tri_edges[t, k]
            if edge_interior[ek]:
                s[k] = th * math.tan(0.5 * edge_rest_theta[ek])
            else:
                s[k] = 0.0
            if s[k] > 0.9 * inradius:
                s[k] = 0.9 * inradius
        # inner vertex k lies on the moved edges k-1 (corner k-1 -> k) and k (corner k -> k+1)
        ok = True
        for k in range(3):
            km = (k + 2) % 3
            # line of edge m: point p_m + s_m n_m, direction t_m; inward normal n = (-ty, tx)
            ax, ay, atx, aty = _moved_line(px, py, km, s[km])
            bx, by, btx, bty = _moved_line(px, py, k, s[k])
            den = atx * bty - aty * btx
            if abs(den) < 1e-300:
                ok = False
                break
            lam = ((bx - ax) * bty - (by - ay) * btx) / den
            ix[k] = ax + lam * atx
            iy[k] = ay + lam * aty
        if not ok:
            for k in range(3):
                ix[k] = px[k]
                iy[k] = py[k]
        rx, ry = _grow_about_barycentre(ix, iy, dx, dy, ge_in, gw_in)
        # eq. 4: s' from the grown edge to the grown inner edge's midpoint, positive inwards
        for k in range(3):
            j = (k + 1) % 3
            ek = tri_edges[t, k]
            if not edge_interior[ek]:
                continue
            tx = qx[j] - qx[k]
            ty = qy[j] - qy[k]
            tl = math.sqrt(tx * tx + ty * ty)
            if tl <= 0.0:
                continue
            nx = -ty / tl
            ny = tx / tl
            mx = 0.5 * (rx[k] + rx[j]) - qx[k]
            my = 0.5 * (ry[k] + ry[j]) - qy[k]
            sp = mx * nx + my * ny
            new_rest_theta[ek] += math.atan(sp / th) if th > 0.0 else 0.0
    for i in range(ne):
        if count[i] > 0.0:
            new_rest_length[i] /= count[i]
        else:
            new_rest_length[i] = edge_rest_length[i]
        if not edge_interior[i]:
            new_rest_theta[i] = 0.0
        elif new_rest_theta[i] > MAX_THETA:
            new_rest_theta[i] = MAX_THETA
        elif new_rest_theta[i] < -MAX_THETA:
            new_rest_theta[i] = -MAX_THETA


@njit(cache=True, inline="always")
def _moved_line(px, py, k, s):
    """Edge k (corner k -> k+1) of a counter-clockwise triangle moved inwards by ``s``:
    (point x, point y, direction x, direction y)."""
    j = (k + 1) % 3
    tx = px[j] - px[k]
    ty = py[j] - py[k]
    tl = math.sqrt(tx * tx + ty * ty)
    if tl <= 0.0:
        return px[k], py[k], 1.0, 0.0
    nx = -ty / tl
    ny = tx / tl
    return px[k] + s * nx, py[k] + s * ny, tx, ty
