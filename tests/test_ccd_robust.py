"""Narrow phase at the edges: coplanar motion decided against rational arithmetic, and
degenerate triangles and edges (coincident pair, all three coincident, collinear, zero-length
edge, zero motion) without an exception.

Coplanar queries are built on a lattice embedded in a tilted plane (integer points, so every float
is exact and the eight positions are exactly in one plane): random motions, and constructed
contacts (a vertex exactly on an edge of the other element at a dyadic instant t*: a vertex
crossing a triangle's edge in its plane, an edge sliding through another edge in their common
plane). The exact answer comes from :func:`inflo.tools.collide.exact.coplanar_ccd_exact`; every
exact contact must be reported (zero misses), and every reported contact must have an exact gap
<= tol at the reported time of impact (false positives only below the tolerance).
"""
from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from inflo.tools.collide import edge_edge_ccd, point_triangle_distance, segment_segment_distance, vertex_triangle_ccd
from inflo.tools.collide.exact import coplanar_ccd_exact, coplanar_gap_sq_exact

TOL = 1e-9


def ccd(kind, x0, x1, tol=TOL):
    out = np.zeros(4)
    fn = vertex_triangle_ccd if kind == "vt" else edge_edge_ccd
    n = fn(x0[0], x0[1], x0[2], x0[3], x1[0], x1[1], x1[2], x1[3], tol, out)
    return n, out


def random_plane(rng):
    """Integer origin and two independent integer directions: (i, j) -> o + i U + j V."""
    while True:
        U, V = rng.integers(-3, 4, (2, 3))
        if np.any(np.cross(U, V)):
            return rng.integers(-20, 21, 3).astype(float), U.astype(float), V.astype(float)


def embed(plane, ij):
    o, U, V = plane
    return o[None] + ij[:, :1] * U[None] + ij[:, 1:] * V[None]


def random_coplanar_query(rng):
    """Four points in one (tilted or axis) plane at both ends of the step, small dyadic lattice
    coordinates: many touch, graze a vertex or stay collinear by chance."""
    plane = random_plane(rng) if rng.random() < 0.8 else (np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
    den = rng.choice([1, 2, 8])
    ij0 = rng.integers(-6, 7, (4, 2)) / den
    ij1 = ij0 + rng.integers(-8, 9, (4, 2)) / den
    return embed(plane, ij0), embed(plane, ij1)


def constructed_contact(rng, kind):
    """A query with a vertex exactly on an edge of the other element at t* = k/16 (so the exact
    answer is a contact), random in-plane velocities; returns (x0, x1, t*)."""
    plane = random_plane(rng)
    ts = rng.integers(0, 17) / 16
    at = rng.integers(-6, 7, (4, 2)).astype(float)
    s = rng.integers(0, 9) / 8  # 0 and 1: touching at a corner
    if kind == "vt":  # rows p, a, b, c: p on edge ab at t*
        at[0] = at[1] + s * (at[2] - at[1])
    else:  # rows a, b, c, d: c on edge ab at t* (an endpoint sliding through the other edge)
        at[2] = at[0] + s * (at[1] - at[0])
    vel = rng.integers(-8, 9, (4, 2)).astype(float)
    if rng.random() < 0.25:  # the touching vertex moves along with the edge's end: sliding contact
        j = 0 if kind == "vt" else 2
        vel[j] = vel[1 if kind == "vt" else 0]
    ij0 = at - ts * vel
    ij1 = ij0 + vel
    return embed(plane, ij0), embed(plane, ij1), ts


def check_query(kind, x0, x1, tol=TOL):
    """(exact contact, reported crossings); asserts that a reported contact is within tol then."""
    truth = coplanar_ccd_exact(kind, x0, x1)
    n, out = ccd(kind, x0, x1, tol)
    if n:
        assert 0.0 <= out[0] <= 1.0
        gap2 = coplanar_gap_sq_exact(kind, x0, x1, out[0])
        assert gap2 <= Fraction(tol) ** 2 * Fraction(1 + 1e-6), (kind, x0.tolist(), x1.tolist(), out, float(gap2))
    return truth, n


@pytest.mark.parametrize("kind", ["vt", "ee"])
def test_random_coplanar_motion_has_no_miss(kind):
    rng = np.random.default_rng(14 if kind == "vt" else 15)
    contacts = missed = 0
    for _ in range(3000):
        x0, x1 = random_coplanar_query(rng)
        truth, n = check_query(kind, x0, x1)
        contacts += truth
        missed += truth and n == 0
    assert contacts > 500  # a good share of contacts, and of no contacts
    assert contacts < 2900
    assert missed == 0


@pytest.mark.parametrize("kind", ["vt", "ee"])
def test_constructed_coplanar_contacts_are_all_found(kind):
    """A vertex crossing a triangle's edge in its plane / an edge sliding through another edge in
    their common plane, the contact exact at t* (often between the old 33 samples, often only a
    touch at a corner)."""
    rng = np.random.default_rng(140 if kind == "vt" else 150)
    for _ in range(2000):
        x0, x1, ts = constructed_contact(rng, kind)
        truth, n = check_query(kind, x0, x1)
        assert truth, (x0.tolist(), x1.tolist())
        assert n >= 1, (kind, x0.tolist(), x1.tolist(), ts)
        out = ccd(kind, x0, x1)[1]
        assert out[0] <= ts + 1e-9  # the first contact, not a later one


def test_coplanar_contacts_between_the_old_samples_are_found():
    """Hand cases the old fallback (33 instants, every 1/32) missed: a vertex grazing a triangle's
    corner in its plane, one cutting the corner (inside for 1/512 of the step), and an edge's end
    touching another edge's end in their plane, all at t* = 3/128 (between the samples 0, 1/32)."""
    a, b, c = np.array([0.0, 0, 0]), np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    ts = 3 / 128
    for start in ([1.0, 0, 0], [1 - 1 / 256, 0, 0]):  # through the corner b / into edge ab
        x0 = np.array([np.array(start) - ts * np.array([1.0, 1, 0]), a, b, c])
        x1 = x0.copy()
        x1[0] += [1.0, 1, 0]
        truth, n = check_query("vt", x0, x1)
        assert truth and n == 1
        assert ccd("vt", x0, x1)[1][0] == pytest.approx(ts, abs=1e-12)
    # edge ab (parallel to x) translates by (1, 1); its end b meets the end d of cd only at t*
    x0 = np.array([[-2.0, 1 - ts, 0], [-1.0 - ts, 1 - ts, 0], [-1.0, -1, 0], [-1.0, 1, 0]])
    x1 = x0.copy()
    x1[:2] += [1.0, 1, 0]
    truth, n = check_query("ee", x0, x1)
    assert truth and n == 1
    assert ccd("ee", x0, x1)[1][0] == pytest.approx(ts, abs=1e-12)


@pytest.mark.parametrize("kind", ["vt", "ee"])
def test_nearly_coplanar_contacts_within_the_tolerance_are_found(kind):
    """The constructed contacts moved off their plane by rounding-sized noise (1e-14 to 1e-11, the
    cubic then ill-conditioned, not zero): a pair that comes within tol / 2 on a fine time grid is
    reported (the old path missed 4 in 5 of them at 1e-11), and a reported one is within tol."""
    rng = np.random.default_rng(146 if kind == "vt" else 147)
    for it in range(600):
        x0, x1, _ = constructed_contact(rng, kind)
        eps = (1e-14, 1e-12, 1e-11)[it % 3]
        x0 = x0 + eps * rng.normal(size=x0.shape)
        x1 = x1 + eps * rng.normal(size=x1.shape)
        n, out = ccd(kind, x0, x1)
        if n:
            assert distance_at(kind, x0, x1, out[0]) <= TOL * (1 + 1e-6)
        else:
            closest = min(distance_at(kind, x0, x1, t) for t in np.linspace(0.0, 1.0, 20001))
            assert closest > TOL / 2, (kind, eps, x0.tolist(), x1.tolist(), closest)


def distance_at(kind, x0, x1, t):
    x = x0 + t * (x1 - x0)
    if kind == "vt":
        return point_triangle_distance(x[0], x[1], x[2], x[3], np.zeros(3))
    return segment_segment_distance(x[0], x[1], x[2], x[3], np.zeros(2))


# -- degenerate elements ----------------------------------------------------------------------------


def ref_point_segment(p, u, w):
    e = w - u
    ee = e @ e
    s = 0.0 if ee == 0 else min(max((p - u) @ e / ee, 0.0), 1.0)
    return float(np.linalg.norm(p - (u + s * e)))


def degenerate_triangles(rng):
    """Every degenerate configuration, in every vertex order."""
    a, b, q = rng.normal(size=(3, 3))
    yield "coincident pair", (a, a.copy(), b)
    yield "coincident pair", (a, b, b.copy())
    yield "coincident pair", (b, a, b.copy())
    yield "all three coincident", (a, a.copy(), a.copy())
    for m in (0.0, 0.3, 1.0, 1.7, -0.4):  # collinear, the third corner between or beyond
        c = a + m * (b - a)
        yield "collinear", (a, b, c)
        yield "collinear", (c, a, b)
        yield "collinear", (b, c, a)


def test_point_triangle_distance_on_degenerate_triangles_is_the_longest_edge():
    rng = np.random.default_rng(140)
    bary = np.zeros(3)
    for _ in range(50):
        for name, (a, b, c) in degenerate_triangles(rng):
            p = rng.normal(size=3)
            for q in (p, a, 0.5 * (a + b), b + 1e-3 * rng.normal(size=3)):
                d = point_triangle_distance(q, a, b, c, bary)
                ref = min(ref_point_segment(q, u, w) for u, w in ((a, b), (b, c), (c, a)))
                assert d == pytest.approx(ref, rel=1e-9, abs=1e-12), name
                assert np.all(bary >= 0.0) and bary.sum() == pytest.approx(1.0)
                closest = bary[0] * a + bary[1] * b + bary[2] * c
                assert np.linalg.norm(q - closest) == pytest.approx(d, rel=1e-9, abs=1e-12)
    # a zero-length edge in a proper triangle is just a corner
    a, b = np.zeros(3), np.array([1.0, 0, 0])
    assert point_triangle_distance(np.array([0.0, 0, 1]), a, a, b, bary) == pytest.approx(1.0)


def test_segment_distance_with_zero_length_segments():
    st = np.zeros(2)
    a, b = np.zeros(3), np.array([1.0, 0, 0])
    q = np.array([0.5, 2.0, 0])
    assert segment_segment_distance(a, a, q, q, st) == pytest.approx(math.hypot(0.5, 2.0))
    assert segment_segment_distance(q, q, a, b, st) == pytest.approx(2.0)
    assert segment_segment_distance(a, b, q, q, st) == pytest.approx(2.0)
    assert segment_segment_distance(a, b, 2 * b, 3 * b, st) == pytest.approx(1.0)  # collinear


def test_vertex_through_degenerate_triangles_out_of_plane():
    """A vertex moving perpendicularly through a collapsed triangle (a segment or a point) hits it
    where it crosses the segment, misses it beside; no exception in any configuration."""
    rng = np.random.default_rng(141)
    for _ in range(30):
        for name, (a, b, c) in degenerate_triangles(rng):
            lab, lbc, lca = np.linalg.norm(b - a), np.linalg.norm(c - b), np.linalg.norm(a - c)
            u, w = max(((a, b, lab), (b, c, lbc), (c, a, lca)), key=lambda e: e[2])[:2]
            n_dir = np.cross(w - u, rng.normal(size=3))
            if np.linalg.norm(n_dir) < 1e-6:
                continue
            n_dir /= np.linalg.norm(n_dir)
            target = u + rng.uniform(0.1, 0.9) * (w - u)  # on the segment (or the point)
            x0 = np.array([target + n_dir, a, b, c])
            x1 = np.array([target - 3 * n_dir, a, b, c])
            n, out = ccd("vt", x0, x1)
            assert n == 1 and out[0] == pytest.approx(0.25, abs=1e-9), name
            off = np.cross(n_dir, w - u)
            off = off / np.linalg.norm(off) if np.linalg.norm(off) > 0 else np.cross(n_dir, [1.0, 0, 0])
            x0[0] = target + 0.1 * off + n_dir
            x1[0] = target + 0.1 * off - 3 * n_dir
            assert ccd("vt", x0, x1)[0] == 0, name


@pytest.mark.parametrize("kind", ["vt", "ee"])
def test_degenerate_coplanar_queries_match_exact(kind):
    """Coincident pairs, all three coincident, collinear corners, zero-length edges, zero motion of
    some or all points, in coplanar motion: the exact answer, no exception."""
    rng = np.random.default_rng(142 if kind == "vt" else 143)
    contacts = missed = 0
    for it in range(1500):
        x0, x1 = random_coplanar_query(rng)
        mode = it % 5
        if mode == 0:  # coincident pair (vt: two corners; ee: a zero-length edge)
            i, j = (1, 2) if kind == "vt" else (0, 1)
            x0[j], x1[j] = x0[i], x1[i]
        elif mode == 1:  # all three corners coincident / both edges zero-length
            if kind == "vt":
                x0[2] = x0[3] = x0[1]
                x1[2] = x1[3] = x1[1]
            else:
                x0[1], x1[1], x0[3], x1[3] = x0[0], x1[0], x0[2], x1[2]
        elif mode == 2:  # collinear corners (vt) / collinear edges (ee), at both ends
            for x in (x0, x1):
                m = rng.choice([-1.0, 0.5, 2.0])
                if kind == "vt":
                    x[3] = x[1] + m * (x[2] - x[1])
                else:
                    x[2] = x[0] + m * (x[1] - x[0])
                    x[3] = x[0] + rng.choice([-2.0, 1.5, 3.0]) * (x[1] - x[0])
        elif mode == 3:  # zero motion of everything
            x1 = x0.copy()
        else:  # zero motion of the triangle / of one edge
            x1[1:] = x0[1:] if kind == "vt" else x1[1:]
            if kind == "ee":
                x1[2:] = x0[2:]
        truth, n = check_query(kind, x0, x1)
        contacts += truth
        missed += truth and n == 0
    assert contacts > 100
    assert missed == 0


def test_degenerate_queries_in_general_motion_do_not_raise():
    """Degenerate elements moving out of any common plane: no exception, and a reported contact is
    within the tolerance at the reported time."""
    rng = np.random.default_rng(144)
    for it in range(3000):
        x0 = rng.integers(-3, 4, (4, 3)).astype(float)
        x1 = x0 + rng.integers(-3, 4, (4, 3))
        mode = it % 4
        if mode == 0:
            x0[2], x1[2] = x0[1], x1[1]
        elif mode == 1:
            x0[2] = x0[3] = x0[1]
            x1[2] = x1[3] = x1[1]
        elif mode == 2:
            x0[3] = 2 * x0[2] - x0[1]
            x1[3] = 2 * x1[2] - x1[1]
        else:
            x1 = x0.copy() if it % 8 == 3 else x1
        for kind in ("vt", "ee"):
            n, out = ccd(kind, x0, x1)
            assert n >= 0
            if n:
                t = out[0]
                x = x0 + t * (x1 - x0)
                if kind == "vt":
                    d = point_triangle_distance(x[0], x[1], x[2], x[3], np.zeros(3))
                else:
                    d = segment_segment_distance(x[0], x[1], x[2], x[3], np.zeros(2))
                assert 0.0 <= t <= 1.0 and d <= TOL * (1 + 1e-6)


def test_zero_motion():
    a, b, c = np.array([0.0, 0, 0]), np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    x = np.array([[0.25, 0.25, 0], a, b, c])  # resting in the triangle: contact at t = 0
    n, out = ccd("vt", x, x.copy())
    assert n == 1 and out[0] == 0.0
    x[0, 2] = 1e-3  # resting above it: none
    assert ccd("vt", x, x.copy())[0] == 0
    pts = np.zeros((4, 3))  # everything at one point: a contact, no exception
    assert ccd("vt", pts, pts.copy())[0] == 1 and ccd("ee", pts, pts.copy())[0] == 1
    e = np.array([a, b, [0.5, -1, 0], [0.5, 1, 0]])  # crossing, resting
    assert ccd("ee", e, e.copy())[0] == 1
    e[2:, 2] = 1.0  # resting apart
    assert ccd("ee", e, e.copy())[0] == 0
