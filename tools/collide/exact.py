"""Exact triangle-triangle intersection in integer arithmetic (the fallback of :mod:`.tritri`).

Every float64 is an integer times a power of two: the six points of a pair, scaled by one
power of two (a positive factor, which changes the sign of no orientation determinant and the
order of no coordinates), are integer points, and the determinants evaluated with Python's
integers have their true sign (as with :class:`fractions.Fraction`, without its normalisations:
several times faster). The numba test in :mod:`.tritri` evaluates the
same predicates in float64 with a forward error bound (Shewchuk's static filter for orient3d /
orient2d); pairs where some sign is not certified are decided here. Slow (tens of microseconds a
pair) but called only for nearly degenerate configurations: coplanar or touching triangles.

The same integer arithmetic gives the ground truth of continuous queries whose four points stay
in one plane over the whole step (the tests of :mod:`.ccd`'s coplanar path):
:func:`coplanar_ccd_exact` decides whether a vertex and a triangle (or two edges) moving linearly
in a common plane touch at some t in [0, 1], with the contact times, roots of quadratics, kept as
exact numbers ``(x + y sqrt(D)) / z``; :func:`coplanar_gap_sq_exact` is their squared distance at
a given time, exactly.
"""
from __future__ import annotations

import math
from fractions import Fraction

__all__ = ["triangles_intersect_exact", "coplanar_ccd_exact", "coplanar_gap_sq_exact"]


def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _orient3d(a, b, c, d) -> int:
    bx, by, bz = _sub(b, a)
    cx, cy, cz = _sub(c, a)
    dx, dy, dz = _sub(d, a)
    det = bx * (cy * dz - cz * dy) + by * (cz * dx - cx * dz) + bz * (cx * dy - cy * dx)
    return (det > 0) - (det < 0)


def _orient2d(a, b, c, i, j) -> int:
    det = (b[i] - a[i]) * (c[j] - a[j]) - (b[j] - a[j]) * (c[i] - a[i])
    return (det > 0) - (det < 0)


def _on_seg(a, b, p, i, j) -> bool:
    return min(a[i], b[i]) <= p[i] <= max(a[i], b[i]) and min(a[j], b[j]) <= p[j] <= max(a[j], b[j])


def _seg_seg_2d(p, q, r, s, i, j) -> bool:
    d1, d2 = _orient2d(r, s, p, i, j), _orient2d(r, s, q, i, j)
    d3, d4 = _orient2d(p, q, r, i, j), _orient2d(p, q, s, i, j)
    if d1 * d2 < 0 and d3 * d4 < 0:
        return True
    if d1 == 0 and d2 == 0 and d3 == 0 and d4 == 0:
        return all(not (max(p[k], q[k]) < min(r[k], s[k]) or max(r[k], s[k]) < min(p[k], q[k])) for k in (i, j))
    return ((d1 == 0 and _on_seg(r, s, p, i, j)) or (d2 == 0 and _on_seg(r, s, q, i, j))
            or (d3 == 0 and _on_seg(p, q, r, i, j)) or (d4 == 0 and _on_seg(p, q, s, i, j)))


def _point_in_tri_2d(p, a, b, c, i, j) -> bool:
    d = (_orient2d(a, b, p, i, j), _orient2d(b, c, p, i, j), _orient2d(c, a, p, i, j))
    return not (min(d) < 0 < max(d))


def _projection_axes(a, b, c):
    """The two coordinates kept when projecting a plane containing abc (drop the normal's largest)."""
    n = (
        (b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]),
        (b[2] - a[2]) * (c[0] - a[0]) - (b[0] - a[0]) * (c[2] - a[2]),
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]),
    )
    k = max(range(3), key=lambda t: abs(n[t]))
    return [t for t in range(3) if t != k]


def _seg_tri_coplanar(p, q, a, b, c, i, j) -> bool:
    if _orient2d(a, b, c, i, j) == 0:  # degenerate triangle: its edges
        return _seg_seg_2d(p, q, a, b, i, j) or _seg_seg_2d(p, q, b, c, i, j) or _seg_seg_2d(p, q, c, a, i, j)
    return (_point_in_tri_2d(p, a, b, c, i, j) or _point_in_tri_2d(q, a, b, c, i, j)
            or _seg_seg_2d(p, q, a, b, i, j) or _seg_seg_2d(p, q, b, c, i, j) or _seg_seg_2d(p, q, c, a, i, j))


def _seg_tri(p, q, a, b, c) -> bool:
    dp, dq = _orient3d(a, b, c, p), _orient3d(a, b, c, q)
    if dp * dq > 0:
        return False
    if dp == 0 and dq == 0:
        i, j = _projection_axes(a, b, c) if any(_projection_axes_normal(a, b, c)) else _projection_axes(p, q, a)
        return _seg_tri_coplanar(p, q, a, b, c, i, j)
    s = (_orient3d(p, q, a, b), _orient3d(p, q, b, c), _orient3d(p, q, c, a))
    if min(s) >= 0 or max(s) <= 0:
        if s == (0, 0, 0):
            i, j = _projection_axes(p, q, a)
            return _seg_tri_coplanar(p, q, a, b, c, i, j)
        return True
    return False


def _projection_axes_normal(a, b, c):
    return (
        (b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]),
        (b[2] - a[2]) * (c[0] - a[0]) - (b[0] - a[0]) * (c[2] - a[2]),
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]),
    )


def _integer_points(points):
    """The points (each three floats) as integer points, all scaled by one power of two; None
    when a coordinate is not finite."""
    ratios = []
    for v in points:
        for c in v:
            c = float(c)
            if not math.isfinite(c):
                return None
            ratios.append(c.as_integer_ratio())  # (numerator, 2**k)
    den = max(d for _, d in ratios)
    ints = [n * (den // d) for n, d in ratios]
    return [tuple(ints[3 * k: 3 * k + 3]) for k in range(len(points))]


def triangles_intersect_exact(p0, p1, p2, q0, q1, q2) -> bool:
    """True when the closed triangles share a point, decided in exact rational arithmetic."""
    pts = _integer_points((p0, p1, p2, q0, q1, q2))
    if pts is None:  # a non-finite coordinate: no point in common
        return False
    P, Q = pts[:3], pts[3:]
    s = [_orient3d(*P, q) for q in Q]
    if min(s) > 0 or max(s) < 0:
        return False
    t = [_orient3d(*Q, p) for p in P]
    if min(t) > 0 or max(t) < 0:
        return False
    return (any(_seg_tri(P[k], P[(k + 1) % 3], *Q) for k in range(3))
            or any(_seg_tri(Q[k], Q[(k + 1) % 3], *P) for k in range(3)))


# --------------------------------------------------------------------------------------------------
# Continuous queries in a common plane
# --------------------------------------------------------------------------------------------------


def _sign(x) -> int:
    return (x > 0) - (x < 0)


def _cross3(u, v):
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


def _common_plane_axes(points):
    """Two coordinates onto which the common plane (or line) of the integer points projects one to
    one, or None when the points are not all in one plane."""
    base = points[0]
    dirs = [_sub(q, base) for q in points[1:]]
    d1 = next((d for d in dirs if any(d)), None)
    if d1 is None:  # all coincide
        return [0, 1]
    n = next((c for c in (_cross3(d1, d) for d in dirs) if any(c)), None)
    if n is None:  # all on one line: drop the coordinate along which it runs least
        k = min(range(3), key=lambda t: abs(d1[t]))
        return [t for t in range(3) if t != k]
    if any(n[0] * d[0] + n[1] * d[1] + n[2] * d[2] for d in dirs):
        return None
    k = max(range(3), key=lambda t: abs(n[t]))
    return [t for t in range(3) if t != k]


def _pmul(a, b):
    out = [0] * (len(a) + len(b) - 1)
    for i, x in enumerate(a):
        for j, y in enumerate(b):
            out[i + j] += x * y
    return out


def _psub(a, b):
    n = max(len(a), len(b))
    return [(a[i] if i < len(a) else 0) - (b[i] if i < len(b) else 0) for i in range(n)]


def _padd(a, b):
    return _psub(a, [-c for c in b])


def _peval(a, t):
    return sum(c * t ** i for i, c in enumerate(a))


def _sign_qd(al, be, D) -> int:
    """Sign of ``al + be sqrt(D)`` (integers, D >= 0), exactly."""
    if be == 0 or D == 0:
        return _sign(al)
    sb = _sign(be)
    if al == 0 or _sign(al) == sb:
        return sb
    c = al * al - be * be * D
    return 0 if c == 0 else (_sign(al) if c > 0 else sb)


class _Motion2D:
    """A point moving linearly in the projection plane: coordinate k is ``x0[k] + t v[k]``."""

    def __init__(self, q0, q1, axes):
        self.poly = [[q0[k], q1[k] - q0[k]] for k in axes]


def _orient_poly(u, w, p):
    """``orient2d(u(t), w(t), p(t))`` as a polynomial in t (ascending integer coefficients)."""
    ex, ey = (_psub(w.poly[i], u.poly[i]) for i in range(2))
    rx, ry = (_psub(p.poly[i], u.poly[i]) for i in range(2))
    return _psub(_pmul(ex, ry), _pmul(ey, rx))


def _between_poly(u, w, p):
    """``(p - u) . (p - w)`` as a polynomial in t: <= 0 exactly when p (on the line uw) is on the
    closed segment uw (for u = w: when p = u)."""
    out = [0]
    for i in range(2):
        out = _padd(out, _pmul(_psub(p.poly[i], u.poly[i]), _psub(p.poly[i], w.poly[i])))
    return out


def _point_on_segment_sometime(u, w, p) -> bool:
    """True when there is a t in [0, 1] with p(t) on the closed segment u(t) w(t), exactly."""
    g = (_orient_poly(u, w, p) + [0, 0, 0])[:3]
    m = (_between_poly(u, w, p) + [0, 0, 0])[:3]
    g0, g1, g2 = g
    if g2 != 0:
        D = g1 * g1 - 4 * g2 * g0
        if D < 0:
            return False
        x, z = -g1, 2 * g2
        for y in ((1,) if D == 0 else (1, -1)):
            # t = (x + y sqrt(D)) / z in [0, 1]?
            if _sign_qd(x, y, D) * _sign(z) < 0 or _sign_qd(x - z, y, D) * _sign(z) > 0:
                continue
            # m(t) z^2 = al + be sqrt(D)
            al = m[2] * (x * x + D) + m[1] * z * x + m[0] * z * z
            be = y * (2 * m[2] * x + m[1] * z)
            if _sign_qd(al, be, D) <= 0:
                return True
        return False
    if g1 != 0:
        t = Fraction(-g0, g1)
        return 0 <= t <= 1 and _peval(m, t) <= 0
    if g0 != 0:
        return False
    # p stays on the line uw: is it between u and w at some instant (min of m on [0, 1])?
    times = [Fraction(0), Fraction(1)]
    if m[2] > 0 and 0 < Fraction(-m[1], 2 * m[2]) < 1:
        times.append(Fraction(-m[1], 2 * m[2]))
    return any(_peval(m, t) <= 0 for t in times)


def _at0(q):
    return (q.poly[0][0], q.poly[1][0])


def _o2(a, b, c) -> int:
    return _sign((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))


def _on_seg_2d(u, w, p) -> bool:
    return (_o2(u, w, p) == 0
            and (p[0] - u[0]) * (p[0] - w[0]) + (p[1] - u[1]) * (p[1] - w[1]) <= 0)


def _point_in_closed_triangle_2d(p, a, b, c) -> bool:
    if _o2(a, b, c) == 0:
        return _on_seg_2d(a, b, p) or _on_seg_2d(b, c, p) or _on_seg_2d(c, a, p)
    d = (_o2(a, b, p), _o2(b, c, p), _o2(c, a, p))
    return not (min(d) < 0 < max(d))


def _segments_meet_2d(a, b, c, d) -> bool:
    if _o2(c, d, a) * _o2(c, d, b) < 0 and _o2(a, b, c) * _o2(a, b, d) < 0:
        return True
    return _on_seg_2d(c, d, a) or _on_seg_2d(c, d, b) or _on_seg_2d(a, b, c) or _on_seg_2d(a, b, d)


def _coplanar_setup(x0, x1):
    pts = _integer_points(list(x0) + list(x1))
    if pts is None:
        raise ValueError("non-finite coordinate")
    axes = _common_plane_axes(pts)
    if axes is None:
        raise ValueError("the eight positions are not in one plane")
    return pts, axes


def coplanar_ccd_exact(kind: str, x0, x1) -> bool:
    """Exact answer of a continuous query whose eight positions lie in one plane.

    Parameters
    ----------
    kind : "vt" or "ee"
        ``vt``: rows (p, a, b, c), vertex p against triangle abc; ``ee``: rows (a, b, c, d), edge
        ab against edge cd.
    x0, x1 : (4, 3) floats
        Positions at t = 0 and t = 1 (linear motion between). All eight must be in one plane
        (or line), else ValueError.

    Returns
    -------
    bool
        True when the closed elements share a point at some t in [0, 1]. The first such instant
        is t = 0 or one with a vertex on an edge of the other element (a point enters a triangle
        through its boundary; two segments start to touch with an endpoint on the other): each
        vertex-edge pair is decided from the exact roots of its orientation quadratic.
    """
    pts, axes = _coplanar_setup(x0, x1)
    q = [_Motion2D(pts[k], pts[k + 4], axes) for k in range(4)]
    at0 = [_at0(m) for m in q]
    if kind == "vt":
        p, a, b, c = q
        if _point_in_closed_triangle_2d(*at0):
            return True
        return any(_point_on_segment_sometime(u, w, p) for u, w in ((a, b), (b, c), (c, a)))
    if kind == "ee":
        a, b, c, d = q
        if _segments_meet_2d(*at0):
            return True
        return (_point_on_segment_sometime(c, d, a) or _point_on_segment_sometime(c, d, b)
                or _point_on_segment_sometime(a, b, c) or _point_on_segment_sometime(a, b, d))
    raise ValueError(f"kind must be 'vt' or 'ee', not {kind!r}")


def _point_segment_dist_sq(p, u, w):
    e = [w[i] - u[i] for i in range(3)]
    r = [p[i] - u[i] for i in range(3)]
    ee = sum(x * x for x in e)
    s = Fraction(0) if ee == 0 else min(max(Fraction(sum(r[i] * e[i] for i in range(3))) / ee, Fraction(0)), Fraction(1))
    return sum((r[i] - s * e[i]) ** 2 for i in range(3))


def coplanar_gap_sq_exact(kind: str, x0, x1, t) -> Fraction:
    """Squared distance, exactly, of the pair of :func:`coplanar_ccd_exact` at time t (a float or
    Fraction): 0 when the elements share a point, else the smallest vertex-edge distance."""
    pts, axes = _coplanar_setup(x0, x1)
    scale = Fraction(_integer_scale(x0, x1))
    t = Fraction(t)
    x = [tuple(pts[k][i] + t * (pts[k + 4][i] - pts[k][i]) for i in range(3)) for k in range(4)]
    y = [(v[axes[0]], v[axes[1]]) for v in x]
    if kind == "vt":
        if _point_in_closed_triangle_2d(*y):
            return Fraction(0)
        p, a, b, c = x
        d2 = min(_point_segment_dist_sq(p, u, w) for u, w in ((a, b), (b, c), (c, a)))
    else:
        if _segments_meet_2d(*y):
            return Fraction(0)
        a, b, c, d = x
        d2 = min(_point_segment_dist_sq(a, c, d), _point_segment_dist_sq(b, c, d),
                 _point_segment_dist_sq(c, a, b), _point_segment_dist_sq(d, a, b))
    return d2 / (scale * scale)


def _integer_scale(x0, x1) -> int:
    """The power of two by which :func:`_integer_points` scales these points."""
    return max(float(c).as_integer_ratio()[1] for v in list(x0) + list(x1) for c in v)
