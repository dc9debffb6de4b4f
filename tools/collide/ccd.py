"""Continuous collision detection, narrow phase (thesis 4.2.2, appendix B).

Vertices move linearly over a step, ``x(t) = x0 + t (x1 - x0)`` for t in [0, 1]. A vertex and a
triangle (or two edges) can only meet at a moment when their four vertices are coplanar: a real
root in [0, 1] of a cubic (eqs. 4.2-4.3 for vertex-triangle, 4.4-4.5 for edge-edge), whose
coefficients come from expanding the moving cross product as a quadratic (appendix B.1,
:func:`cubic_vertex_triangle`, :func:`cubic_edge_edge`). Before root finding the cubic goes
through coefficient culling (4.2.2.3, :func:`cull_cubic`); its real roots in [0, 1] are found by
the hybrid Newton-bisection method on the brackets between the critical points
(:func:`cubic_roots_01`); each root is then checked with an inside test with tolerance
(appendix B.2 point in triangle, :func:`point_triangle_distance`; appendix B.3 segment-segment
distance, :func:`segment_segment_distance`).

:func:`vertex_triangle_ccd` and :func:`edge_edge_ccd` return the number of verified crossings
and the first time of impact. An even number of crossings in a step leaves the pair on the side
it started on and needs no response (4.2.2.3); callers respond to odd counts.

Coplanar motion. When the four points stay (nearly) coplanar over the whole step the
cubic vanishes identically (or is rounding noise) and its roots say nothing. Contact is then
decided exactly as in the plane: the first moment of contact is t = 0 or a moment when a vertex
lies on an edge of the other element (a point can only enter a triangle through its boundary, two
segments can only start to touch with an endpoint on the other), i.e. a root of a component of
the quadratic ``(w - u)(t) x (p - u)(t)`` (p on the line uw), or the moment two vertices pass
closest. :func:`_vt_coplanar` / :func:`_ee_coplanar` collect these candidate instants (roots by
the stable quadratic formula plus the parabola's vertex, so a double root lost to rounding is
still tried) and run the inside test at each, earliest first. The same test is the fallback of
the cubic path when the cubic is ill-conditioned (coefficients below ``_ILL_REL L^3``) and it
found nothing. A hit is only ever reported at an instant where the distance is <= tol.

Degenerate elements: a triangle with coincident vertices, collinear corners or a
zero-length edge is its longest edge (or its point) for :func:`point_triangle_distance`; no
kernel here divides by zero.

Every function is a pure numba kernel on (3,) float64 points.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = [
    "cubic_vertex_triangle",
    "cubic_edge_edge",
    "cull_cubic",
    "cubic_roots_01",
    "point_triangle_distance",
    "segment_segment_distance",
    "vertex_triangle_ccd",
    "edge_edge_ccd",
    "vertex_triangle_culled",
    "edge_edge_culled",
]

# relative size below which all cubic coefficients count as zero (coplanar motion)
_COPLANAR_REL = 1e-13
# relative |f| at a critical point that counts as a double root (tangential touch)
_TOUCH_REL = 1e-12
# relative size of the cubic below which its roots are ill-conditioned: when the cubic path finds
# no contact, the coplanar candidate test runs as well
_ILL_REL = 1e-9
# |ab x ac|^2 <= _DEGEN_REL * (longest edge)^4: the triangle is a segment or a point
_DEGEN_REL = 1e-28


@njit(cache=True, inline="always")
def _cubic_coeffs(p0, pv, b0, bv, c0, cv):
    """Coefficients (k0, k1, k2, k3), ascending powers, of ``p(t) . (b(t) x c(t))`` (appendix B.1).

    ``b(t) x c(t) = Q t^2 + R t + S`` with ``Q = bv x cv``, ``R = bv x c0 + b0 x cv``,
    ``S = b0 x c0`` (eq. B.2), then dotted with ``p(t) = p0 + t pv``.
    """
    Sx = b0[1] * c0[2] - b0[2] * c0[1]
    Sy = b0[2] * c0[0] - b0[0] * c0[2]
    Sz = b0[0] * c0[1] - b0[1] * c0[0]
    Rx = (bv[1] * c0[2] - bv[2] * c0[1]) + (b0[1] * cv[2] - b0[2] * cv[1])
    Ry = (bv[2] * c0[0] - bv[0] * c0[2]) + (b0[2] * cv[0] - b0[0] * cv[2])
    Rz = (bv[0] * c0[1] - bv[1] * c0[0]) + (b0[0] * cv[1] - b0[1] * cv[0])
    Qx = bv[1] * cv[2] - bv[2] * cv[1]
    Qy = bv[2] * cv[0] - bv[0] * cv[2]
    Qz = bv[0] * cv[1] - bv[1] * cv[0]
    k0 = p0[0] * Sx + p0[1] * Sy + p0[2] * Sz
    k1 = p0[0] * Rx + p0[1] * Ry + p0[2] * Rz + pv[0] * Sx + pv[1] * Sy + pv[2] * Sz
    k2 = p0[0] * Qx + p0[1] * Qy + p0[2] * Qz + pv[0] * Rx + pv[1] * Ry + pv[2] * Rz
    k3 = pv[0] * Qx + pv[1] * Qy + pv[2] * Qz
    return k0, k1, k2, k3


@njit(cache=True)
def cubic_vertex_triangle(p0, a0, b0, c0, p1, a1, b1, c1):
    """Coplanarity cubic of a moving vertex p and triangle abc (eqs. 4.2-4.3).

    ``f(t) = pa(t) . (ba(t) x ca(t))`` with ``pa = p - a``, ``ba = b - a``, ``ca = c - a``.

    Parameters
    ----------
    p0, a0, b0, c0 : (3,) float64
        Positions at the start of the step (t = 0).
    p1, a1, b1, c1 : (3,) float64
        Positions at the end of the step (t = 1).

    Returns
    -------
    k0, k1, k2, k3 : float
        ``f(t) = k0 + k1 t + k2 t^2 + k3 t^3``.
    """
    # tuples, not arrays: no allocation per query (the narrow phase runs millions)
    pa0 = (p0[0] - a0[0], p0[1] - a0[1], p0[2] - a0[2])
    ba0 = (b0[0] - a0[0], b0[1] - a0[1], b0[2] - a0[2])
    ca0 = (c0[0] - a0[0], c0[1] - a0[1], c0[2] - a0[2])
    pav = ((p1[0] - a1[0]) - pa0[0], (p1[1] - a1[1]) - pa0[1], (p1[2] - a1[2]) - pa0[2])
    bav = ((b1[0] - a1[0]) - ba0[0], (b1[1] - a1[1]) - ba0[1], (b1[2] - a1[2]) - ba0[2])
    cav = ((c1[0] - a1[0]) - ca0[0], (c1[1] - a1[1]) - ca0[1], (c1[2] - a1[2]) - ca0[2])
    return _cubic_coeffs(pa0, pav, ba0, bav, ca0, cav)


@njit(cache=True)
def cubic_edge_edge(a0, b0, c0, d0, a1, b1, c1, d1):
    """Coplanarity cubic of moving edges ab and cd (eqs. 4.4-4.5).

    ``f(t) = ca(t) . (da(t) x ba(t))`` with ``ca = c - a``, ``da = d - a``, ``ba = b - a``.

    Returns
    -------
    k0, k1, k2, k3 : float
        Ascending coefficients, as :func:`cubic_vertex_triangle`.
    """
    ca0 = (c0[0] - a0[0], c0[1] - a0[1], c0[2] - a0[2])
    da0 = (d0[0] - a0[0], d0[1] - a0[1], d0[2] - a0[2])
    ba0 = (b0[0] - a0[0], b0[1] - a0[1], b0[2] - a0[2])
    cav = ((c1[0] - a1[0]) - ca0[0], (c1[1] - a1[1]) - ca0[1], (c1[2] - a1[2]) - ca0[2])
    dav = ((d1[0] - a1[0]) - da0[0], (d1[1] - a1[1]) - da0[1], (d1[2] - a1[2]) - da0[2])
    bav = ((b1[0] - a1[0]) - ba0[0], (b1[1] - a1[1]) - ba0[1], (b1[2] - a1[2]) - ba0[2])
    return _cubic_coeffs(ca0, cav, da0, dav, ba0, bav)


@njit(cache=True)
def cull_cubic(k0, k1, k2, k3):
    """True when ``k0 + k1 t + k2 t^2 + k3 t^3`` certainly has no root in [0, 1] (4.2.2.3).

    The thesis's criteria: all coefficients of one strict sign; 1) ``k0, k1 > 0`` and
    ``k0 + k1 > |k2| + |k3|``; 2) ``k0, k1 < 0`` and ``k0 + k1 < -|k2| - |k3|``;
    3) ``|k0| > |k1| + |k2| + |k3|``. Added: the Bernstein coefficients on [0, 1]
    (``k0``, ``k0 + k1/3``, ``k0 + 2k1/3 + k2/3``, ``k0 + k1 + k2 + k3``) all of one strict sign
    (convex hull property). Each criterion only ever culls cubics without a root in [0, 1].
    """
    if k0 > 0.0 and k1 > 0.0 and k2 > 0.0 and k3 > 0.0:
        return True
    if k0 < 0.0 and k1 < 0.0 and k2 < 0.0 and k3 < 0.0:
        return True
    a2 = abs(k2)
    a3 = abs(k3)
    if k0 > 0.0 and k1 > 0.0 and k0 + k1 > a2 + a3:
        return True
    if k0 < 0.0 and k1 < 0.0 and k0 + k1 < -a2 - a3:
        return True
    if abs(k0) > abs(k1) + a2 + a3:
        return True
    b1 = k0 + k1 / 3.0
    b2 = k0 + (2.0 * k1 + k2) / 3.0
    b3 = k0 + k1 + k2 + k3
    if k0 > 0.0 and b1 > 0.0 and b2 > 0.0 and b3 > 0.0:
        return True
    if k0 < 0.0 and b1 < 0.0 and b2 < 0.0 and b3 < 0.0:
        return True
    return False


@njit(cache=True, inline="always")
def _horner(k0, k1, k2, k3, t):
    return k0 + t * (k1 + t * (k2 + t * k3))


@njit(cache=True, inline="always")
def _horner_d(k1, k2, k3, t):
    return k1 + t * (2.0 * k2 + t * 3.0 * k3)


@njit(cache=True)
def _hybrid_root(k0, k1, k2, k3, lo, hi, flo):
    """Root of the cubic in the bracket [lo, hi] (sign change): Newton steps, bisection when a
    Newton step leaves the bracket (the thesis's hybrid method, 4.2.2.3)."""
    t = 0.5 * (lo + hi)
    for _ in range(100):
        f = _horner(k0, k1, k2, k3, t)
        if f == 0.0:
            return t
        if (f < 0.0) == (flo < 0.0):
            lo = t
            flo = f
        else:
            hi = t
        if hi - lo <= 1e-16:
            break
        d = _horner_d(k1, k2, k3, t)
        tn = t - f / d if d != 0.0 else 0.5 * (lo + hi)
        if not (tn > lo and tn < hi):
            tn = 0.5 * (lo + hi)
        if abs(tn - t) <= 1e-17:
            t = tn
            break
        t = tn
    return t


@njit(cache=True)
def cubic_roots_01(k0, k1, k2, k3, roots):
    """Real roots in [0, 1] of ``k0 + k1 t + k2 t^2 + k3 t^3`` (4.2.2.3), ascending.

    [0, 1] is split at the critical points (roots of the derivative, a quadratic) into intervals
    on which the cubic is monotone; an interval with a sign change holds exactly one root, found
    by :func:`_hybrid_root`. A critical point where ``|f|`` is below ``1e-12`` times the size of the
    coefficients counts as a (double) root: a tangential touch. Evaluation by Horner's method.

    Parameters
    ----------
    roots : (>= 5,) float64
        Output buffer.

    Returns
    -------
    int
        Number of roots written to ``roots``.
    """
    scale = abs(k0) + abs(k1) + abs(k2) + abs(k3)
    n = 0
    if scale == 0.0:
        return 0
    touch = _TOUCH_REL * scale
    # critical points in (0, 1)
    pts = np.empty(4)
    npts = 0
    pts[npts] = 0.0
    npts += 1
    qa = 3.0 * k3
    qb = 2.0 * k2
    qc = k1
    c1 = -1.0
    c2 = -1.0
    if qa != 0.0:
        disc = qb * qb - 4.0 * qa * qc
        if disc >= 0.0:
            sq = math.sqrt(disc)
            qq = -0.5 * (qb + math.copysign(sq, qb))
            r1 = qq / qa
            r2 = qc / qq if qq != 0.0 else r1
            c1 = min(r1, r2)
            c2 = max(r1, r2)
    elif qb != 0.0:
        c1 = -qc / qb
    if c1 > 0.0 and c1 < 1.0:
        pts[npts] = c1
        npts += 1
    if c2 > 0.0 and c2 < 1.0 and c2 != c1:
        pts[npts] = c2
        npts += 1
    pts[npts] = 1.0
    npts += 1
    found_before = False  # a sign-change root was found in the previous interval
    for s in range(npts - 1):
        lo = pts[s]
        hi = pts[s + 1]
        flo = _horner(k0, k1, k2, k3, lo)
        fhi = _horner(k0, k1, k2, k3, hi)
        # a root at the left end: f(0) == 0 exactly, or a critical point where f touches 0
        at_lo = (flo == 0.0) if s == 0 else (abs(flo) <= touch)
        if at_lo:
            if not found_before:
                roots[n] = lo
                n += 1
            found_before = False
        elif (flo < 0.0 < fhi) or (fhi < 0.0 < flo):
            roots[n] = _hybrid_root(k0, k1, k2, k3, lo, hi, flo)
            n += 1
            found_before = True
        else:
            found_before = False
    f1 = _horner(k0, k1, k2, k3, 1.0)
    if f1 == 0.0 and not found_before:
        roots[n] = 1.0
        n += 1
    return n


@njit(cache=True, inline="always")
def _point_segment_param(px, py, pz, ux, uy, uz, wx, wy, wz):
    """Parameter s in [0, 1] of the point of segment uw closest to p (0 for a zero-length one)."""
    ex = wx - ux
    ey = wy - uy
    ez = wz - uz
    ee = ex * ex + ey * ey + ez * ez
    if not ee > 0.0:
        return 0.0
    s = ((px - ux) * ex + (py - uy) * ey + (pz - uz) * ez) / ee
    return min(max(s, 0.0), 1.0)


@njit(cache=True)
def _degenerate_triangle_bary(p, a, b, c, bary):
    """Barycentric weights of the point closest to p on the longest edge of abc (a
    collapsed triangle, collinear corners or coincident vertices, is that segment or point)."""
    lab = (b[0] - a[0]) ** 2 + (b[1] - a[1]) ** 2 + (b[2] - a[2]) ** 2
    lbc = (c[0] - b[0]) ** 2 + (c[1] - b[1]) ** 2 + (c[2] - b[2]) ** 2
    lca = (a[0] - c[0]) ** 2 + (a[1] - c[1]) ** 2 + (a[2] - c[2]) ** 2
    if lab >= lbc and lab >= lca:
        s = _point_segment_param(p[0], p[1], p[2], a[0], a[1], a[2], b[0], b[1], b[2])
        bary[0] = 1.0 - s
        bary[1] = s
        bary[2] = 0.0
    elif lbc >= lca:
        s = _point_segment_param(p[0], p[1], p[2], b[0], b[1], b[2], c[0], c[1], c[2])
        bary[0] = 0.0
        bary[1] = 1.0 - s
        bary[2] = s
    else:
        s = _point_segment_param(p[0], p[1], p[2], c[0], c[1], c[2], a[0], a[1], a[2])
        bary[0] = s
        bary[1] = 0.0
        bary[2] = 1.0 - s


@njit(cache=True)
def point_triangle_distance(p, a, b, c, bary):
    """Distance from point p to triangle abc (appendix B.2, "is p in the triangle", with tolerance).

    The thesis writes the coplanar point as ``a + r (b - a) + s (c - a)`` and tests
    ``r, s >= 0, r + s <= 1``; with a tolerance that becomes "closest point of the triangle within
    tol". The closest point is found by Voronoi regions (Ericson, Real-Time Collision Detection
    5.1.5). A degenerate triangle (``|ab x ac|^2 <= 1e-28`` times its longest edge to the fourth:
    coincident vertices, collinear corners, a zero-length edge) is its longest edge, or its point
    when all three corners coincide; no division by zero on any input.

    Parameters
    ----------
    bary : (3,) float64
        Output: barycentric weights of the closest point (sum 1, each >= 0).

    Returns
    -------
    float
        The distance.
    """
    abx = b[0] - a[0]
    aby = b[1] - a[1]
    abz = b[2] - a[2]
    acx = c[0] - a[0]
    acy = c[1] - a[1]
    acz = c[2] - a[2]
    nx = aby * acz - abz * acy
    ny = abz * acx - abx * acz
    nz = abx * acy - aby * acx
    lab = abx * abx + aby * aby + abz * abz
    lac = acx * acx + acy * acy + acz * acz
    lbc = (c[0] - b[0]) ** 2 + (c[1] - b[1]) ** 2 + (c[2] - b[2]) ** 2
    emax = max(lab, lac, lbc)
    degenerate = not (nx * nx + ny * ny + nz * nz > _DEGEN_REL * emax * emax)
    u = 1.0
    v = 0.0
    w = 0.0
    if not degenerate:
        apx = p[0] - a[0]
        apy = p[1] - a[1]
        apz = p[2] - a[2]
        d1 = abx * apx + aby * apy + abz * apz
        d2 = acx * apx + acy * apy + acz * apz
        if d1 <= 0.0 and d2 <= 0.0:
            u, v, w = 1.0, 0.0, 0.0
        else:
            bpx = p[0] - b[0]
            bpy = p[1] - b[1]
            bpz = p[2] - b[2]
            d3 = abx * bpx + aby * bpy + abz * bpz
            d4 = acx * bpx + acy * bpy + acz * bpz
            cpx = p[0] - c[0]
            cpy = p[1] - c[1]
            cpz = p[2] - c[2]
            d5 = abx * cpx + aby * cpy + abz * cpz
            d6 = acx * cpx + acy * cpy + acz * cpz
            vc = d1 * d4 - d3 * d2
            vb = d5 * d2 - d1 * d6
            va = d3 * d6 - d5 * d4
            if d3 >= 0.0 and d4 <= d3:
                u, v, w = 0.0, 1.0, 0.0
            elif vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
                den = d1 - d3  # |ab|^2 > 0 for a non-degenerate triangle, guarded all the same
                t = min(max(d1 / den, 0.0), 1.0) if den > 0.0 else 0.0
                u, v, w = 1.0 - t, t, 0.0
            elif d6 >= 0.0 and d5 <= d6:
                u, v, w = 0.0, 0.0, 1.0
            elif vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
                den = d2 - d6  # |ac|^2
                t = min(max(d2 / den, 0.0), 1.0) if den > 0.0 else 0.0
                u, v, w = 1.0 - t, 0.0, t
            elif va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
                den = (d4 - d3) + (d5 - d6)  # |bc|^2
                t = min(max((d4 - d3) / den, 0.0), 1.0) if den > 0.0 else 0.0
                u, v, w = 0.0, 1.0 - t, t
            else:
                den = va + vb + vc
                if den > 0.0:
                    v = vb / den
                    w = vc / den
                    u = 1.0 - v - w
                else:  # rounding in a near-sliver: take it as its longest edge
                    degenerate = True
    if degenerate:
        _degenerate_triangle_bary(p, a, b, c, bary)
        u = bary[0]
        v = bary[1]
        w = bary[2]
    bary[0] = u
    bary[1] = v
    bary[2] = w
    dx = p[0] - (u * a[0] + v * b[0] + w * c[0])
    dy = p[1] - (u * a[1] + v * b[1] + w * c[1])
    dz = p[2] - (u * a[2] + v * b[2] + w * c[2])
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True)
def segment_segment_distance(p1, q1, p2, q2, st):
    """Minimum distance between segments p1q1 and p2q2 (appendix B.3).

    Closest points ``p1 + s (q1 - p1)`` and ``p2 + t (q2 - p2)`` with s, t in [0, 1] (Ericson 5.1.9),
    parallel and zero-length segments included.

    Parameters
    ----------
    st : (2,) float64
        Output: the parameters s and t of the closest points.
    """
    d1x = q1[0] - p1[0]
    d1y = q1[1] - p1[1]
    d1z = q1[2] - p1[2]
    d2x = q2[0] - p2[0]
    d2y = q2[1] - p2[1]
    d2z = q2[2] - p2[2]
    rx = p1[0] - p2[0]
    ry = p1[1] - p2[1]
    rz = p1[2] - p2[2]
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    eps = 1e-300
    s = 0.0
    t = 0.0
    if a <= eps and e <= eps:
        s = 0.0
        t = 0.0
    elif a <= eps:
        s = 0.0
        t = min(max(f / e, 0.0), 1.0)
    else:
        c = d1x * rx + d1y * ry + d1z * rz
        if e <= eps:
            t = 0.0
            s = min(max(-c / a, 0.0), 1.0)
        else:
            b = d1x * d2x + d1y * d2y + d1z * d2z
            denom = a * e - b * b
            if denom > 1e-14 * a * e:
                s = min(max((b * f - c * e) / denom, 0.0), 1.0)
            else:
                s = 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(max(-c / a, 0.0), 1.0)
            elif t > 1.0:
                t = 1.0
                s = min(max((b - c) / a, 0.0), 1.0)
    st[0] = s
    st[1] = t
    dx = (p1[0] + s * d1x) - (p2[0] + t * d2x)
    dy = (p1[1] + s * d1y) - (p2[1] + t * d2y)
    dz = (p1[2] + s * d1z) - (p2[2] + t * d2z)
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True, inline="always")
def _lerp(out, x0, x1, t):
    for i in range(3):
        out[i] = x0[i] + t * (x1[i] - x0[i])


@njit(cache=True, inline="always")
def _max_extent(a0, b0, c0, d0, a1, b1, c1, d1):
    """Largest coordinate difference to a0 over both ends: the length scale of a query."""
    m = 0.0
    for i in range(3):
        for v in (b0[i], c0[i], d0[i], a1[i], b1[i], c1[i], d1[i]):
            m = max(m, abs(v - a0[i]))
    return m


@njit(cache=True, inline="always")
def _push_time(cand, n, t):
    """Append t to the candidate instants when it lies in [0, 1] (NaN and inf never do)."""
    if t >= 0.0 and t <= 1.0:
        cand[n] = t
        return n + 1
    return n


@njit(cache=True, inline="always")
def _quadratic_times(qa, qb, qc, cand, n):
    """Append the real roots in [0, 1] of ``qa t^2 + qb t + qc`` and the parabola's vertex.

    Roots by the stable formula (no cancellation between ``-qb`` and the square root); the vertex
    ``-qb / (2 qa)`` is the double root when rounding has made a touching parabola's discriminant
    slightly negative. No division by zero: each quotient is guarded.
    """
    if qa != 0.0:
        n = _push_time(cand, n, -qb / (2.0 * qa))
        disc = qb * qb - 4.0 * qa * qc
        if disc >= 0.0:
            qq = -0.5 * (qb + math.copysign(math.sqrt(disc), qb))
            n = _push_time(cand, n, qq / qa)
            if qq != 0.0:
                n = _push_time(cand, n, qc / qq)
    elif qb != 0.0:
        n = _push_time(cand, n, -qc / qb)
    return n


@njit(cache=True, inline="always")
def _on_line_times(p0, p1, u0, u1, w0, w1, cand, n):
    """Append the instants in [0, 1] when the moving point p may lie on the moving line uw.

    ``(w - u)(t) x (p - u)(t) = Q t^2 + R t + S`` vanishes exactly then; every component does, and
    the roots of the component with the largest coefficients (the plane normal's, when the motion
    stays in one plane) are the best conditioned. Spurious roots are harmless: every candidate
    instant goes through the inside test.
    """
    e0x = w0[0] - u0[0]
    e0y = w0[1] - u0[1]
    e0z = w0[2] - u0[2]
    evx = (w1[0] - u1[0]) - e0x
    evy = (w1[1] - u1[1]) - e0y
    evz = (w1[2] - u1[2]) - e0z
    r0x = p0[0] - u0[0]
    r0y = p0[1] - u0[1]
    r0z = p0[2] - u0[2]
    rvx = (p1[0] - u1[0]) - r0x
    rvy = (p1[1] - u1[1]) - r0y
    rvz = (p1[2] - u1[2]) - r0z
    sx = e0y * r0z - e0z * r0y
    sy = e0z * r0x - e0x * r0z
    sz = e0x * r0y - e0y * r0x
    rx = (evy * r0z - evz * r0y) + (e0y * rvz - e0z * rvy)
    ry = (evz * r0x - evx * r0z) + (e0z * rvx - e0x * rvz)
    rz = (evx * r0y - evy * r0x) + (e0x * rvy - e0y * rvx)
    qx = evy * rvz - evz * rvy
    qy = evz * rvx - evx * rvz
    qz = evx * rvy - evy * rvx
    mx = abs(qx) + abs(rx) + abs(sx)
    my = abs(qy) + abs(ry) + abs(sy)
    mz = abs(qz) + abs(rz) + abs(sz)
    if mx >= my and mx >= mz:
        return _quadratic_times(qx, rx, sx, cand, n)
    if my >= mz:
        return _quadratic_times(qy, ry, sy, cand, n)
    return _quadratic_times(qz, rz, sz, cand, n)


@njit(cache=True, inline="always")
def _closest_pass_time(p0, p1, u0, u1, cand, n):
    """Append the instant in [0, 1] when the moving points p and u are closest (vertex-vertex)."""
    dv = 0.0
    vv = 0.0
    for i in range(3):
        d0 = p0[i] - u0[i]
        dd = (p1[i] - u1[i]) - d0
        dv += d0 * dd
        vv += dd * dd
    if vv > 0.0:
        n = _push_time(cand, n, -dv / vv)
    return n


@njit(cache=True, inline="always")
def _sort_times(cand, n):
    for i in range(1, n):
        x = cand[i]
        j = i - 1
        while j >= 0 and cand[j] > x:
            cand[j + 1] = cand[j]
            j -= 1
        cand[j + 1] = x


@njit(cache=True)
def _vt_coplanar(p0, a0, b0, c0, p1, a1, b1, c1, tol, out):
    """Vertex-triangle contact when the four points stay (nearly) coplanar over the step.

    The first moment p is within the (closed) triangle is t = 0 or a moment it lies on an edge,
    a root of :func:`_on_line_times` for the edges ab, bc, ca; passing a corner is also a root of
    :func:`_closest_pass_time`. The inside test (:func:`point_triangle_distance` <= tol) runs at
    t = 0, 1 and every candidate instant, earliest first; the first hit is the time of impact.

    Returns
    -------
    int
        1 (a contact; ``out`` as :func:`vertex_triangle_ccd`) or 0.
    """
    cand = np.empty(16)
    cand[0] = 0.0
    cand[1] = 1.0
    n = 2
    n = _on_line_times(p0, p1, a0, a1, b0, b1, cand, n)
    n = _on_line_times(p0, p1, b0, b1, c0, c1, cand, n)
    n = _on_line_times(p0, p1, c0, c1, a0, a1, cand, n)
    n = _closest_pass_time(p0, p1, a0, a1, cand, n)
    n = _closest_pass_time(p0, p1, b0, b1, cand, n)
    n = _closest_pass_time(p0, p1, c0, c1, cand, n)
    _sort_times(cand, n)
    tmp = np.empty(4)
    for r in range(n):
        if r > 0 and cand[r] == cand[r - 1]:
            continue
        if _vt_inside(p0, a0, b0, c0, p1, a1, b1, c1, cand[r], tol, tmp):
            out[0] = cand[r]
            out[1] = tmp[1]
            out[2] = tmp[2]
            out[3] = tmp[3]
            return 1
    return 0


@njit(cache=True)
def _ee_coplanar(a0, b0, c0, d0, a1, b1, c1, d1, tol, out):
    """Edge-edge contact when the four points stay (nearly) coplanar over the step.

    Two segments in a plane start to touch at t = 0 or when an endpoint of one lies on the other
    (a crossing of interiors persists backwards in time): the roots of :func:`_on_line_times` for
    a, b on cd and c, d on ab, and the closest passes of the endpoint pairs. The inside test
    (:func:`segment_segment_distance` <= tol) runs at each, earliest first.

    Returns
    -------
    int
        1 (a contact; ``out`` as :func:`edge_edge_ccd`) or 0.
    """
    cand = np.empty(20)
    cand[0] = 0.0
    cand[1] = 1.0
    n = 2
    n = _on_line_times(a0, a1, c0, c1, d0, d1, cand, n)
    n = _on_line_times(b0, b1, c0, c1, d0, d1, cand, n)
    n = _on_line_times(c0, c1, a0, a1, b0, b1, cand, n)
    n = _on_line_times(d0, d1, a0, a1, b0, b1, cand, n)
    n = _closest_pass_time(a0, a1, c0, c1, cand, n)
    n = _closest_pass_time(a0, a1, d0, d1, cand, n)
    n = _closest_pass_time(b0, b1, c0, c1, cand, n)
    n = _closest_pass_time(b0, b1, d0, d1, cand, n)
    _sort_times(cand, n)
    tmp = np.empty(4)
    for r in range(n):
        if r > 0 and cand[r] == cand[r - 1]:
            continue
        if _ee_inside(a0, b0, c0, d0, a1, b1, c1, d1, cand[r], tol, tmp):
            out[0] = cand[r]
            out[1] = tmp[1]
            out[2] = tmp[2]
            return 1
    return 0


@njit(cache=True)
def vertex_triangle_ccd(p0, a0, b0, c0, p1, a1, b1, c1, tol, out):
    """Continuous vertex-triangle test over one step (4.2.2.1, eqs. 4.2-4.3).

    Parameters
    ----------
    p0, a0, b0, c0, p1, a1, b1, c1 : (3,) float64
        Vertex p and triangle abc at t = 0 and t = 1.
    tol : float
        Inside-test tolerance (appendix B.2): at a coplanar moment p counts as touching the
        triangle when its distance to it is <= tol. Must be > 0 for robustness (callers use the
        collision thickness ``spacing`` plus a small multiple of the scene size).
    out : (4,) float64
        Output: ``[toi, w_a, w_b, w_c]``, the first verified time of impact and the barycentric
        weights of p's closest point on the triangle then (undefined when there is no crossing).

    Returns
    -------
    int
        Number of verified crossings (coplanar moments with p on the triangle). Odd: p ends on the
        other side and needs a response; even (enter and leave within the step): none (4.2.2.3).
        When the four points stay coplanar over the step (the cubic vanishes) the exact in-plane
        test :func:`_vt_coplanar` decides: 1 for a contact, else 0; it also runs when an
        ill-conditioned cubic (below ``_ILL_REL L^3``) gave no verified crossing.
    """
    k0, k1, k2, k3 = cubic_vertex_triangle(p0, a0, b0, c0, p1, a1, b1, c1)
    L = _max_extent(p0, a0, b0, c0, p1, a1, b1, c1)
    if L == 0.0:
        # all eight positions coincide: p is on the (point) triangle for the whole step
        return _vt_coplanar(p0, a0, b0, c0, p1, a1, b1, c1, tol, out)
    big = abs(k0) + abs(k1) + abs(k2) + abs(k3)
    L3 = L * L * L
    if big <= _COPLANAR_REL * L3:
        return _vt_coplanar(p0, a0, b0, c0, p1, a1, b1, c1, tol, out)
    if cull_cubic(k0, k1, k2, k3):
        if big <= _ILL_REL * L3:
            return _vt_coplanar(p0, a0, b0, c0, p1, a1, b1, c1, tol, out)
        return 0
    roots = np.empty(6)
    nr = cubic_roots_01(k0, k1, k2, k3, roots)
    hits = 0
    tmp = np.empty(4)
    for r in range(nr):
        if _vt_inside(p0, a0, b0, c0, p1, a1, b1, c1, roots[r], tol, tmp):
            if hits == 0:
                out[0] = roots[r]
                out[1] = tmp[1]
                out[2] = tmp[2]
                out[3] = tmp[3]
            hits += 1
    if hits == 0 and big <= _ILL_REL * L3:
        return _vt_coplanar(p0, a0, b0, c0, p1, a1, b1, c1, tol, out)
    return hits


@njit(cache=True)
def _vt_inside(p0, a0, b0, c0, p1, a1, b1, c1, t, tol, out):
    p = np.empty(3)
    a = np.empty(3)
    b = np.empty(3)
    c = np.empty(3)
    _lerp(p, p0, p1, t)
    _lerp(a, a0, a1, t)
    _lerp(b, b0, b1, t)
    _lerp(c, c0, c1, t)
    bary = np.empty(3)
    d = point_triangle_distance(p, a, b, c, bary)
    out[1] = bary[0]
    out[2] = bary[1]
    out[3] = bary[2]
    return d <= tol


@njit(cache=True)
def _ee_inside(a0, b0, c0, d0, a1, b1, c1, d1, t, tol, out):
    a = np.empty(3)
    b = np.empty(3)
    c = np.empty(3)
    d = np.empty(3)
    _lerp(a, a0, a1, t)
    _lerp(b, b0, b1, t)
    _lerp(c, c0, c1, t)
    _lerp(d, d0, d1, t)
    st = np.empty(2)
    dist = segment_segment_distance(a, b, c, d, st)
    out[1] = st[0]
    out[2] = st[1]
    return dist <= tol


@njit(cache=True)
def edge_edge_ccd(a0, b0, c0, d0, a1, b1, c1, d1, tol, out):
    """Continuous edge-edge test over one step (4.2.2.2, eqs. 4.4-4.5).

    Parameters
    ----------
    a0, b0, c0, d0, a1, b1, c1, d1 : (3,) float64
        Edges ab and cd at t = 0 and t = 1.
    tol : float
        Inside-test tolerance: at a coplanar moment the edges touch when their distance
        (appendix B.3) is <= tol.
    out : (4,) float64
        Output: ``[toi, s, t, 0]``: first verified time of impact and the parameters of the closest
        points ``a + s (b - a)``, ``c + t (d - c)`` then.

    Returns
    -------
    int
        Number of verified crossings (odd: needs a response, 4.2.2.3). Coplanar motion and an
        ill-conditioned cubic that gave nothing: :func:`_ee_coplanar` decides, 1 or 0.
    """
    k0, k1, k2, k3 = cubic_edge_edge(a0, b0, c0, d0, a1, b1, c1, d1)
    L = _max_extent(a0, b0, c0, d0, a1, b1, c1, d1)
    if L == 0.0:
        return _ee_coplanar(a0, b0, c0, d0, a1, b1, c1, d1, tol, out)
    big = abs(k0) + abs(k1) + abs(k2) + abs(k3)
    L3 = L * L * L
    if big <= _COPLANAR_REL * L3:
        return _ee_coplanar(a0, b0, c0, d0, a1, b1, c1, d1, tol, out)
    if cull_cubic(k0, k1, k2, k3):
        if big <= _ILL_REL * L3:
            return _ee_coplanar(a0, b0, c0, d0, a1, b1, c1, d1, tol, out)
        return 0
    roots = np.empty(6)
    nr = cubic_roots_01(k0, k1, k2, k3, roots)
    hits = 0
    tmp = np.empty(4)
    for r in range(nr):
        if _ee_inside(a0, b0, c0, d0, a1, b1, c1, d1, roots[r], tol, tmp):
            if hits == 0:
                out[0] = roots[r]
                out[1] = tmp[1]
                out[2] = tmp[2]
            hits += 1
    if hits == 0 and big <= _ILL_REL * L3:
        return _ee_coplanar(a0, b0, c0, d0, a1, b1, c1, d1, tol, out)
    return hits


# --------------------------------------------------------------------------------------------------
# The cull alone, on a position array: most candidate pairs end here
# --------------------------------------------------------------------------------------------------


@njit(cache=True, inline="always")
def _row(x, i):
    return (x[i, 0], x[i, 1], x[i, 2])


@njit(cache=True, inline="always")
def _culled(k0, k1, k2, k3, L):
    """The early exit of :func:`vertex_triangle_ccd` / :func:`edge_edge_ccd`: True exactly where
    they return 0 at their cubic's cull (not near-coplanar, not ill-conditioned)."""
    if L == 0.0:
        return False
    big = abs(k0) + abs(k1) + abs(k2) + abs(k3)
    L3 = L * L * L
    if big <= _COPLANAR_REL * L3:
        return False
    if cull_cubic(k0, k1, k2, k3):
        return not big <= _ILL_REL * L3
    return False


@njit(cache=True)
def vertex_triangle_culled(x0, x1, p, a, b, c):
    """True where ``vertex_triangle_ccd(x0[p], x0[a], x0[b], x0[c], x1[p], ...)`` certainly returns
    0 by its cubic's cull: the same arithmetic on the rows of ``x0`` / ``x1`` as tuples. The
    narrow phase calls it first: slicing eight rows into array views for the full test costs a
    reference count each, about ten times the cull itself, and most pairs are culled."""
    p0, a0, b0, c0 = _row(x0, p), _row(x0, a), _row(x0, b), _row(x0, c)
    p1, a1, b1, c1 = _row(x1, p), _row(x1, a), _row(x1, b), _row(x1, c)
    k0, k1, k2, k3 = cubic_vertex_triangle(p0, a0, b0, c0, p1, a1, b1, c1)
    return _culled(k0, k1, k2, k3, _max_extent(p0, a0, b0, c0, p1, a1, b1, c1))


@njit(cache=True)
def edge_edge_culled(x0, x1, a, b, c, d):
    """:func:`vertex_triangle_culled` for :func:`edge_edge_ccd` of edges ab and cd."""
    a0, b0, c0, d0 = _row(x0, a), _row(x0, b), _row(x0, c), _row(x0, d)
    a1, b1, c1, d1 = _row(x1, a), _row(x1, b), _row(x1, c), _row(x1, d)
    k0, k1, k2, k3 = cubic_edge_edge(a0, b0, c0, d0, a1, b1, c1, d1)
    return _culled(k0, k1, k2, k3, _max_extent(a0, b0, c0, d0, a1, b1, c1, d1))
