"""One triangle pair's static test, shared by the static tests over pair lists (:mod:`.tritri`)
and the floret-by-floret static test (:func:`.probe.intersecting_pairs_by_part`).

Orientation predicates (``orient3d``, ``orient2d``) evaluated in float64 with Shewchuk's forward
error bound certifying each sign; :func:`triangles_intersect`, exact when :func:`certified` holds;
:func:`separated`, a certain "disjoint" where it is not; :func:`_pair_flag`, which combines them
into 0 (disjoint), 1 (intersecting) or 2 (undecided in float64) for a pair of a mesh's triangles;
and :func:`_decide`, which settles the undecided pairs in rational arithmetic
(:func:`inflo.tools.collide.exact.triangles_intersect_exact`). :mod:`.tritri` describes the test.
"""
from __future__ import annotations

import numpy as np
from numba import njit

_EPS = 2.0 ** -53
_O3D_ERRBOUND = (7.0 + 56.0 * _EPS) * _EPS


@njit(cache=True, inline="always")
def _orient3d_with_bound(a, b, c, d):
    """(det[b - a, c - a, d - a], Shewchuk's forward error bound of its float evaluation)."""
    bx = b[0] - a[0]
    by = b[1] - a[1]
    bz = b[2] - a[2]
    cx = c[0] - a[0]
    cy = c[1] - a[1]
    cz = c[2] - a[2]
    dx = d[0] - a[0]
    dy = d[1] - a[1]
    dz = d[2] - a[2]
    det = bx * (cy * dz - cz * dy) + by * (cz * dx - cx * dz) + bz * (cx * dy - cy * dx)
    perm = (abs(bx) * (abs(cy * dz) + abs(cz * dy)) + abs(by) * (abs(cz * dx) + abs(cx * dz))
            + abs(bz) * (abs(cx * dy) + abs(cy * dx)))
    return det, _O3D_ERRBOUND * perm


@njit(cache=True, inline="always")
def orient3d(a, b, c, d):
    """``det[b - a, c - a, d - a]``: > 0 when d is on the side of abc's normal (b-a)x(c-a)."""
    return _orient3d_with_bound(a, b, c, d)[0]


@njit(cache=True, inline="always")
def _o2(ax, ay, bx, by, cx, cy):
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@njit(cache=True, inline="always")
def _sgn(x):
    return 1 if x > 0.0 else (-1 if x < 0.0 else 0)


@njit(cache=True)
def _seg_seg_2d(p, q, r, s, i, j):
    """Closed segments pq and rs (coordinates i, j) share a point."""
    d1 = _sgn(_o2(r[i], r[j], s[i], s[j], p[i], p[j]))
    d2 = _sgn(_o2(r[i], r[j], s[i], s[j], q[i], q[j]))
    d3 = _sgn(_o2(p[i], p[j], q[i], q[j], r[i], r[j]))
    d4 = _sgn(_o2(p[i], p[j], q[i], q[j], s[i], s[j]))
    if d1 * d2 < 0 and d3 * d4 < 0:
        return True
    if d1 == 0 and d2 == 0 and d3 == 0 and d4 == 0:
        # collinear: overlap of the projections on both axes
        for k in (i, j):
            lo1 = min(p[k], q[k])
            hi1 = max(p[k], q[k])
            lo2 = min(r[k], s[k])
            hi2 = max(r[k], s[k])
            if hi1 < lo2 or hi2 < lo1:
                return False
        return True
    if d1 == 0 and _on_seg(r, s, p, i, j):
        return True
    if d2 == 0 and _on_seg(r, s, q, i, j):
        return True
    if d3 == 0 and _on_seg(p, q, r, i, j):
        return True
    if d4 == 0 and _on_seg(p, q, s, i, j):
        return True
    return False


@njit(cache=True, inline="always")
def _on_seg(a, b, p, i, j):
    return (min(a[i], b[i]) <= p[i] <= max(a[i], b[i])) and (min(a[j], b[j]) <= p[j] <= max(a[j], b[j]))


@njit(cache=True)
def _point_in_tri_2d(p, a, b, c, i, j):
    d1 = _sgn(_o2(a[i], a[j], b[i], b[j], p[i], p[j]))
    d2 = _sgn(_o2(b[i], b[j], c[i], c[j], p[i], p[j]))
    d3 = _sgn(_o2(c[i], c[j], a[i], a[j], p[i], p[j]))
    has_neg = d1 < 0 or d2 < 0 or d3 < 0
    has_pos = d1 > 0 or d2 > 0 or d3 > 0
    return not (has_neg and has_pos)


@njit(cache=True)
def _drop_axes(a, b, c):
    nx = (b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1])
    ny = (b[2] - a[2]) * (c[0] - a[0]) - (b[0] - a[0]) * (c[2] - a[2])
    nz = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    ax, ay, az = abs(nx), abs(ny), abs(nz)
    if ax >= ay and ax >= az:
        return 1, 2
    if ay >= az:
        return 0, 2
    return 0, 1


@njit(cache=True)
def _seg_tri_coplanar(p, q, a, b, c, i, j):
    if _point_in_tri_2d(p, a, b, c, i, j) or _point_in_tri_2d(q, a, b, c, i, j):
        return True
    return (_seg_seg_2d(p, q, a, b, i, j) or _seg_seg_2d(p, q, b, c, i, j)
            or _seg_seg_2d(p, q, c, a, i, j))


@njit(cache=True)
def _seg_tri(p, q, a, b, c):
    """Closed segment pq and closed triangle abc share a point."""
    dp = _sgn(orient3d(a, b, c, p))
    dq = _sgn(orient3d(a, b, c, q))
    if dp * dq > 0:
        return False
    if dp == 0 and dq == 0:
        i, j = _drop_axes(a, b, c)
        return _seg_tri_coplanar(p, q, a, b, c, i, j)
    s1 = _sgn(orient3d(p, q, a, b))
    s2 = _sgn(orient3d(p, q, b, c))
    s3 = _sgn(orient3d(p, q, c, a))
    if (s1 >= 0 and s2 >= 0 and s3 >= 0) or (s1 <= 0 and s2 <= 0 and s3 <= 0):
        if s1 == 0 and s2 == 0 and s3 == 0:  # degenerate triangle on the segment's line
            i, j = _drop_axes(p, q, a)
            return _seg_tri_coplanar(p, q, a, b, c, i, j)
        return True
    return False


@njit(cache=True)
def triangles_intersect(p0, p1, p2, q0, q1, q2):
    """True when closed triangles p0p1p2 and q0q1q2 share a point (touching counts).

    Parameters
    ----------
    p0, p1, p2, q0, q1, q2 : (3,) float64
    """
    s0 = _sgn(orient3d(p0, p1, p2, q0))
    s1 = _sgn(orient3d(p0, p1, p2, q1))
    s2 = _sgn(orient3d(p0, p1, p2, q2))
    if (s0 > 0 and s1 > 0 and s2 > 0) or (s0 < 0 and s1 < 0 and s2 < 0):
        return False
    t0 = _sgn(orient3d(q0, q1, q2, p0))
    t1 = _sgn(orient3d(q0, q1, q2, p1))
    t2 = _sgn(orient3d(q0, q1, q2, p2))
    if (t0 > 0 and t1 > 0 and t2 > 0) or (t0 < 0 and t1 < 0 and t2 < 0):
        return False
    return (_seg_tri(p0, p1, q0, q1, q2) or _seg_tri(p1, p2, q0, q1, q2)
            or _seg_tri(p2, p0, q0, q1, q2) or _seg_tri(q0, q1, p0, p1, p2)
            or _seg_tri(q1, q2, p0, p1, p2) or _seg_tri(q2, q0, p0, p1, p2))


@njit(cache=True, inline="always")
def _orient3d_certain(a, b, c, d):
    """True when the float sign of orient3d(a, b, c, d) is the exact sign (Shewchuk's bound)."""
    det, bound = _orient3d_with_bound(a, b, c, d)
    return abs(det) > bound


@njit(cache=True, inline="always")
def _certainly_one_side(a, b, c, p, q, r):
    """True when p, q, r are all strictly on one side of the plane abc, every sign certified: the
    triangles cannot share a point (the plane separates them), whatever the other determinants."""
    d0, e0 = _orient3d_with_bound(a, b, c, p)
    if not abs(d0) > e0:
        return False
    d1, e1 = _orient3d_with_bound(a, b, c, q)
    if not abs(d1) > e1 or (d1 > 0) != (d0 > 0):
        return False
    d2, e2 = _orient3d_with_bound(a, b, c, r)
    return abs(d2) > e2 and (d2 > 0) == (d0 > 0)


_O2D_ERRBOUND = (3.0 + 16.0 * 2.0 ** -53) * 2.0 ** -53  # Shewchuk's ccwerrboundA


@njit(cache=True, inline="always")
def _orient2d_sign(ax, ay, bx, by, cx, cy):
    """Sign of the 2-D orientation of (a, b, c), or 0 where float64 cannot certify it (Shewchuk)."""
    left = (ax - cx) * (by - cy)
    right = (ay - cy) * (bx - cx)
    det = left - right
    if abs(det) > _O2D_ERRBOUND * (abs(left) + abs(right)):
        return 1 if det > 0 else -1
    return 0


@njit(cache=True, inline="always")
def _edge_separates(a, b, c, p, q, r, i, j):
    """The line through edge ab of triangle abc, in the projection onto axes (i, j), certainly has
    c on one side and p, q, r strictly on the other."""
    sc = _orient2d_sign(a[i], a[j], b[i], b[j], c[i], c[j])
    if sc == 0:
        return False
    for v in (p, q, r):
        if _orient2d_sign(a[i], a[j], b[i], b[j], v[i], v[j]) != -sc:
            return False
    return True


@njit(cache=True)
def _separated_in_projection(p0, p1, p2, q0, q1, q2):
    """Disjoint projections onto the coordinate plane most nearly parallel to p0p1p2 (a separating
    edge line of either triangle, every sign certified): then the triangles are disjoint too. Decides
    coplanar pairs, where every plane-side determinant is zero (two triangles of one flat facet)."""
    nx = (p1[1] - p0[1]) * (p2[2] - p0[2]) - (p1[2] - p0[2]) * (p2[1] - p0[1])
    ny = (p1[2] - p0[2]) * (p2[0] - p0[0]) - (p1[0] - p0[0]) * (p2[2] - p0[2])
    nz = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0])
    ax, ay, az = abs(nx), abs(ny), abs(nz)
    if ax >= ay and ax >= az:
        i, j = 1, 2
    elif ay >= az:
        i, j = 0, 2
    else:
        i, j = 0, 1
    return (_edge_separates(p0, p1, p2, q0, q1, q2, i, j) or _edge_separates(p1, p2, p0, q0, q1, q2, i, j)
            or _edge_separates(p2, p0, p1, q0, q1, q2, i, j) or _edge_separates(q0, q1, q2, p0, p1, p2, i, j)
            or _edge_separates(q1, q2, q0, p0, p1, p2, i, j) or _edge_separates(q2, q0, q1, p0, p1, p2, i, j))


@njit(cache=True)
def separated(p0, p1, p2, q0, q1, q2):
    """True when the triangles are certainly disjoint, decided in float64 even where
    :func:`certified` is not: one triangle's plane separates the other (e.g. parallel edges of two
    concentric cylinders, whose edge-edge determinants are exactly zero), or their projections onto
    a coordinate plane are separated by an edge line (coplanar triangles of one flat facet)."""
    return (_certainly_one_side(p0, p1, p2, q0, q1, q2) or _certainly_one_side(q0, q1, q2, p0, p1, p2)
            or _separated_in_projection(p0, p1, p2, q0, q1, q2))


@njit(cache=True)
def certified(p0, p1, p2, q0, q1, q2):
    """True when every orientation the float test may evaluate has a certified sign.

    Those are the six vertex-against-plane determinants and the nine edge-against-edge ones
    (``orient3d(p, q, a, b)`` for an edge pq of one triangle and ab of the other). With all of them
    certified non-zero, no coplanar branch is taken and :func:`triangles_intersect` is exact.
    """
    P = (p0, p1, p2)
    Q = (q0, q1, q2)
    for k in range(3):
        if not _orient3d_certain(p0, p1, p2, Q[k]) or not _orient3d_certain(q0, q1, q2, P[k]):
            return False
    for k in range(3):
        for l in range(3):
            if not _orient3d_certain(P[k], P[(k + 1) % 3], Q[l], Q[(l + 1) % 3]):
                return False
    return True


@njit(cache=True, inline="always")
def _share_vertex(tri, i, j):
    for a in range(3):
        for b in range(3):
            if tri[i, a] == tri[j, b]:
                return True
    return False


@njit(cache=True)
def _pair_flag(x, tri, i, j):
    """0 disjoint, 1 intersecting, 2 undecided in float64, for triangles i and j. The corners are
    tuples, not row views of ``x`` (a reference count each, more than the test of most pairs),
    and a plane that certainly separates the two is tried first: most candidate pairs are
    neighbours in one floret, one on one side of the other (the same flag either way: a certain
    side is what :func:`certified` + :func:`triangles_intersect` or :func:`separated` find)."""
    a0 = (x[tri[i, 0], 0], x[tri[i, 0], 1], x[tri[i, 0], 2])
    a1 = (x[tri[i, 1], 0], x[tri[i, 1], 1], x[tri[i, 1], 2])
    a2 = (x[tri[i, 2], 0], x[tri[i, 2], 1], x[tri[i, 2], 2])
    b0 = (x[tri[j, 0], 0], x[tri[j, 0], 1], x[tri[j, 0], 2])
    b1 = (x[tri[j, 1], 0], x[tri[j, 1], 1], x[tri[j, 1], 2])
    b2 = (x[tri[j, 2], 0], x[tri[j, 2], 1], x[tri[j, 2], 2])
    if _certainly_one_side(a0, a1, a2, b0, b1, b2) or _certainly_one_side(b0, b1, b2, a0, a1, a2):
        return 0
    if certified(a0, a1, a2, b0, b1, b2):
        return 1 if triangles_intersect(a0, a1, a2, b0, b1, b2) else 0
    if separated(a0, a1, a2, b0, b1, b2):
        return 0
    return 2


def _decide(x, tri, pairs, flags) -> np.ndarray:
    """Resolve undecided pairs exactly; returns the intersecting pairs."""
    from .exact import triangles_intersect_exact

    for k in np.nonzero(flags == 2)[0]:
        i, j = pairs[k]
        flags[k] = triangles_intersect_exact(*x[tri[i]], *x[tri[j]])
    return pairs[flags == 1]
