"""Exact triangle-triangle intersection in integer arithmetic (the fallback of :mod:`.tritri`).

Every float64 is an integer times a power of two: the six points of a pair, scaled by one
power of two (a positive factor, which changes the sign of no orientation determinant and the
order of no coordinates), are integer points, and the determinants evaluated with Python's
integers have their true sign (as with :class:`fractions.Fraction`, without its normalisations:
several times faster). The numba test in :mod:`.tritri` evaluates the
same predicates in float64 with a forward error bound (Shewchuk's static filter for orient3d /
orient2d); pairs where some sign is not certified are decided here. Slow (tens of microseconds a
pair) but called only for nearly degenerate configurations: coplanar or touching triangles.
"""
from __future__ import annotations

import math

__all__ = ["triangles_intersect_exact"]


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
