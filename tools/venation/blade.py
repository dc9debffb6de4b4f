"""The leaf blade (Runions sec. 4.2.2): a closed polygon with the point where it attaches to the
petiole, its growth (secs. 4.2.3, 4.3; fig. 4.2) and its triangle mesh.

The blade is given at scale 1 (a contour sampled by arc length, or a polygon) and grows about its
base B: at step t its margin is ``B + diag(sigma_t) (P - B)``, with sigma_t the growth
schedule's scale (:class:`Growth`). Points are tested against the scale-1 polygon after undoing
the scale, through a band structure (the polygon's edges sorted into horizontal bands), so a test
costs a few edges.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from inflo.tools.common import linalg as la

__all__ = ["Blade", "BladeBands", "Growth", "KeyFrames", "LocalToGlobal", "blade_from_points", "inside_blade", "triangulate_blade",
           "polygon_area", "self_intersections", "GROWTH_TYPES"]

GROWTH_TYPES = ("none", "marginal", "uniform", "anisotropic", "local_to_global", "key_frames")
"""``none``: the blade does not grow; ``marginal``: the margin is scaled about the base, veins and
sources stay (sec. 4.2.3); ``uniform``: isogonic growth, everything is scaled (by scaling the unit
distance down instead, lambda_t = lambda_0 sigma_0 / sigma_t); ``anisotropic``: uniform
anisotropic growth (fig. 4.2d), a scale per axis applied to the blade, the veins and the sources;
``local_to_global``: relative elementary rates of growth of the initial height (sec. 5.2.1, eq. 5.1);
``key_frames``: key-frame interpolation of blade surfaces (sec. 5.2.1, eq. 5.2, fig. 5.9)."""


class BladeBands(NamedTuple):
    """The polygon's edges sorted into ``nb`` horizontal bands of height 1 / ``inv_dy`` from ``y0``:
    the edges overlapping band b are ``edge[start[b]:start[b + 1]]`` (edge i runs from vertex i to
    vertex i + 1)."""

    poly: np.ndarray  # (m, 2) float64
    y0: float
    inv_dy: float
    nb: int
    start: np.ndarray  # (nb + 1,) int64
    edge: np.ndarray  # (E,) int64


def polygon_area(poly) -> float:
    """Signed area (positive counter-clockwise) of the closed polygon ``poly`` (m, 2)."""
    p = np.asarray(poly, dtype=np.float64)
    x, y = p[:, 0], p[:, 1]
    return 0.5 * (la.dot(x, np.roll(y, -1)) - la.dot(np.roll(x, -1), y))


def self_intersections(poly) -> tuple[int, int] | None:
    """A pair of non-adjacent edges (i, j) of the closed polygon that cross, or None."""
    p = np.asarray(poly, dtype=np.float64)
    m = len(p)
    a, b = p, np.roll(p, -1, axis=0)
    lo = np.minimum(a, b)
    hi = np.maximum(a, b)
    order = np.argsort(lo[:, 0], kind="stable")
    for oi, i in enumerate(order):
        for j in order[oi + 1:]:
            if lo[j, 0] > hi[i, 0]:
                break
            if abs(i - j) in (1, m - 1) or lo[j, 1] > hi[i, 1] or hi[j, 1] < lo[i, 1]:
                continue
            if _segments_cross(a[i], b[i], a[j], b[j]):
                return (int(min(i, j)), int(max(i, j)))
    return None


def _segments_cross(p1, p2, q1, q2) -> bool:
    def orient(a, b, c):
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    d1, d2 = orient(q1, q2, p1), orient(q1, q2, p2)
    d3, d4 = orient(p1, p2, q1), orient(p1, p2, q2)
    return (d1 * d2 < 0) and (d3 * d4 < 0)


def _bands(poly: np.ndarray) -> BladeBands:
    m = len(poly)
    y = poly[:, 1]
    y0, y1 = float(y.min()), float(y.max())
    nb = max(1, min(4096, m))
    dy = (y1 - y0) / nb or 1.0
    inv = 1.0 / dy
    e_lo = np.minimum(y, np.roll(y, -1))
    e_hi = np.maximum(y, np.roll(y, -1))
    b0 = np.clip(np.floor((e_lo - y0) * inv).astype(np.int64), 0, nb - 1)
    b1 = np.clip(np.floor((e_hi - y0) * inv).astype(np.int64), 0, nb - 1)
    rows = [np.arange(a, b + 1) for a, b in zip(b0, b1)]
    band_of = np.concatenate(rows)
    edge_of = np.repeat(np.arange(m), [len(r) for r in rows])
    order = np.lexsort((edge_of, band_of))
    band_of, edge_of = band_of[order], edge_of[order]
    counts = np.bincount(band_of, minlength=nb)
    start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    return BladeBands(np.ascontiguousarray(poly), y0, inv, nb, start, edge_of.astype(np.int64))


@njit(cache=True)
def _inside(x, y, poly, y0, inv_dy, nb, start, edge):
    """Crossing-number test of (x, y) against the polygon, using the band of y."""
    b = np.int64(math.floor((y - y0) * inv_dy))
    if b < 0 or b >= nb:
        return False
    m = poly.shape[0]
    inside = False
    for k in range(start[b], start[b + 1]):
        i = edge[k]
        j = i + 1 if i + 1 < m else 0
        yi, yj = poly[i, 1], poly[j, 1]
        if (yi > y) != (yj > y):
            xc = poly[i, 0] + (y - yi) * (poly[j, 0] - poly[i, 0]) / (yj - yi)
            if x < xc:
                inside = not inside
    return inside


@njit(cache=True)
def inside_blade(pts, base, scale, bands, out):
    """``out[i]`` = point ``pts[i]`` lies inside the blade scaled by ``scale`` (2,) about ``base``."""
    poly, y0, inv_dy, nb, start, edge = bands.poly, bands.y0, bands.inv_dy, bands.nb, bands.start, bands.edge
    for i in range(pts.shape[0]):
        x = base[0] + (pts[i, 0] - base[0]) / scale[0]
        y = base[1] + (pts[i, 1] - base[1]) / scale[1]
        out[i] = _inside(x, y, poly, y0, inv_dy, nb, start, edge)


@dataclass(frozen=True)
class Blade:
    """A leaf blade at scale 1.

    Attributes
    ----------
    polygon : (m, 2) float64
        The margin, counter-clockwise, not closed (the last vertex joins the first).
    base : (2,) float64
        The attachment point to the petiole: the centre of growth and the default initial vein node.
    bands : BladeBands
    area : float
        Area at scale 1.
    """

    polygon: np.ndarray
    base: np.ndarray
    bands: BladeBands
    area: float

    @property
    def lo(self) -> np.ndarray:
        return self.polygon.min(axis=0)

    @property
    def hi(self) -> np.ndarray:
        return self.polygon.max(axis=0)

    def scaled(self, scale) -> np.ndarray:
        """(m, 2): the margin at ``scale`` (a number or (sx, sy)) about the base."""
        s = np.broadcast_to(np.asarray(scale, dtype=np.float64), (2,))
        return self.base + (self.polygon - self.base) * s

    def contains(self, pts, scale=1.0) -> np.ndarray:
        """(n,) bool: points (n, 2) inside the blade at ``scale``."""
        p = np.ascontiguousarray(pts, dtype=np.float64).reshape(-1, 2)
        out = np.zeros(len(p), np.bool_)
        inside_blade(p, self.base, np.broadcast_to(np.asarray(scale, float), (2,)).copy(), self.bands, out)
        return out

    def distance_to_margin(self, pts, scale=1.0) -> np.ndarray:
        """(n,) distances of points to the margin at ``scale``."""
        poly = self.scaled(scale)
        a, b = poly, np.roll(poly, -1, axis=0)
        p = np.asarray(pts, dtype=np.float64).reshape(-1, 1, 2)
        ab = b - a
        t = np.clip(la.rowdot(p - a, ab) / np.maximum(la.rowdot(ab, ab), 1e-300), 0, 1)  # (n, m) / (m,)
        q = a + t[..., None] * ab
        return np.sqrt(((p - q) ** 2).sum(-1)).min(axis=1)


def blade_from_points(points, base=None) -> Blade:
    """A :class:`Blade` from margin points (m, 2) (either orientation, not closed).

    ``base`` defaults to the lowest point of the margin (least y; among equals the one nearest the
    middle in x). Raises ``ValueError`` for fewer than 3 points, a zero area or a self-crossing margin.
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if len(p) > 1 and np.allclose(p[0], p[-1]):
        p = p[:-1]
    if len(p) < 3:
        raise ValueError(f"a blade needs at least 3 margin points, got {len(p)}")
    a = polygon_area(p)
    ext = float(np.ptp(p, axis=0).max())
    if not abs(a) > 1e-12 * max(ext, 1e-300) ** 2:
        raise ValueError("the margin encloses no area")
    if a < 0:
        p = p[::-1].copy()
        a = -a
    hit = self_intersections(p)
    if hit is not None:
        raise ValueError(f"the margin crosses itself (edges {hit[0]} and {hit[1]})")
    if base is None:
        ymin = p[:, 1].min()
        low = np.flatnonzero(p[:, 1] <= ymin + 1e-9 * ext)
        mid = 0.5 * (p[:, 0].min() + p[:, 0].max())
        b = p[low[np.argmin(np.abs(p[low, 0] - mid))]]
    else:
        b = np.asarray(base, dtype=np.float64).reshape(2)
    p.setflags(write=False)
    b = b.copy()
    b.setflags(write=False)
    return Blade(polygon=p, base=b, bands=_bands(np.ascontiguousarray(p)), area=float(a))


# --------------------------------------------------------------------------------------------
# growth


class LocalToGlobal:
    """The local-to-global growth model (Runions sec. 5.2.1, eq. 5.1, fig. 5.2).

    The relative elementary rates of growth in the horizontal and vertical directions,
    RERG_x(y0) and RERG_y(y0), are functions of y0, the initial vertical position of a point
    (from the base B, normalized by the initial blade's height H above B: ``fx``, ``fy`` of
    u = y0 / H in [0, 1], clamped). "By solving the equation dx/dt = x RERG_x(y0)", a point at
    x1 at t1 is at x2 = x1 RERG_x(y0)^(t2 - t1) (x from B); in the vertical direction (eq. 5.1)
    y1 = integral from 0 to y0 of RERG_y(y)^(t1 - t0) dy. Points are kept by their material
    coordinates (their position at t0 = 0); a point made at time t is taken back to t0 by solving
    eq. 5.1 for y0 ("a lookup table with precomputed values of integral (5.1)": the trapezoid rule
    on ``samples`` values of u). Below B a point moves with the rates at u = 0, above the blade's
    top with those at u = 1.
    """

    def __init__(self, fx, fy, base, height: float, samples: int = 4097):
        self.base = np.asarray(base, dtype=np.float64).reshape(2)
        self.height = float(height)
        self.u = np.linspace(0.0, 1.0, samples)
        self.rx = np.asarray(fx(self.u), dtype=np.float64)
        self.ry = np.asarray(fy(self.u), dtype=np.float64)
        self._tables: dict = {}

    def table(self, t: float) -> np.ndarray:
        """(samples,) the integral of eq. 5.1 from 0 to u H, at time t."""
        key = float(t)
        tab = self._tables.get(key)
        if tab is None:
            f = self.ry ** key
            du = self.u[1] - self.u[0]
            tab = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * du)]) * self.height
            if len(self._tables) > 4:
                self._tables.clear()
            self._tables[key] = tab
        return tab

    def _rx(self, u, t):
        return np.interp(np.clip(u, 0.0, 1.0), self.u, self.rx) ** t

    def forward(self, mat, t: float) -> np.ndarray:
        """(n, 2) positions at time t of points at ``mat`` (n, 2) at t0 (real coordinates)."""
        m = np.asarray(mat, dtype=np.float64).reshape(-1, 2) - self.base
        u = m[:, 1] / self.height
        tab = self.table(t)
        y = np.interp(np.clip(u, 0.0, 1.0), self.u, tab)
        y = np.where(u > 1.0, tab[-1] + (m[:, 1] - self.height) * self.ry[-1] ** t, y)
        y = np.where(u < 0.0, m[:, 1] * self.ry[0] ** t, y)
        return self.base + np.column_stack([m[:, 0] * self._rx(u, t), y])

    def inverse(self, pos, t: float) -> np.ndarray:
        """(n, 2) positions at t0 of points at ``pos`` (n, 2) at time t (eq. 5.1 solved for y0)."""
        p = np.asarray(pos, dtype=np.float64).reshape(-1, 2) - self.base
        tab = self.table(t)
        u = np.interp(p[:, 1], tab, self.u)
        u = np.where(p[:, 1] > tab[-1], 1.0 + (p[:, 1] - tab[-1]) / (self.height * self.ry[-1] ** t), u)
        u = np.where(p[:, 1] < 0.0, p[:, 1] / (self.height * self.ry[0] ** t), u)
        return self.base + np.column_stack([p[:, 0] / self._rx(u, t), u * self.height])

    def bound(self, t: float) -> np.ndarray:
        """(2,) per-axis stretches no point exceeds at time t: max RERG_x^t, max RERG_y^t."""
        return np.array([float(self.rx.max()) ** t, float(self.ry.max()) ** t])


#: key-frame growth: margin samples per side of the (u, v) square, the inversion's start grid
KF_SIDE_SAMPLES = 64
KF_GRID = 65


def _bernstein(s):
    """(n, 4) cubic Bernstein values and (n, 4) their derivatives at s (n,)."""
    r = 1.0 - s
    b = np.stack([r * r * r, 3.0 * s * r * r, 3.0 * s * s * r, s * s * s], axis=-1)
    d = np.stack([-3.0 * r * r, 3.0 * r * r - 6.0 * s * r, 6.0 * s * r - 3.0 * s * s, 3.0 * s * s], axis=-1)
    return b, d


def bezier_eval(control, u, v, derivatives: bool = False):
    """The bicubic patch ``control`` (4, 4, 2) at (u, v) (n,): positions (n, 2) and, with
    ``derivatives``, dQ/du and dQ/dv (n, 2) each. Sums in a fixed order (no BLAS)."""
    bu, du = _bernstein(np.asarray(u, dtype=np.float64))
    bv, dv = _bernstein(np.asarray(v, dtype=np.float64))
    q = np.zeros(bu.shape[:-1] + (2,))
    qu = np.zeros_like(q)
    qv = np.zeros_like(q)
    for i in range(4):
        for j in range(4):
            c = control[i, j]
            w = (bu[..., i] * bv[..., j])[..., None]
            q += w * c
            if derivatives:
                qu += (du[..., i] * bv[..., j])[..., None] * c
                qv += (bu[..., i] * dv[..., j])[..., None] * c
    return (q, qu, qv) if derivatives else q


class KeyFrames:
    """Key-frame interpolation of leaf-blade surfaces (Runions sec. 5.2.1, figs. 5.3, 5.9).

    The growing blade is a set of surfaces with times S = {(Q_1, t_1), ..., (Q_n, t_n)}, each
    Q_i(u, v): [0, 1]^2 -> R^2 a bicubic Bezier patch (a B-spline surface of one span: its control
    net ``controls[i]`` (4, 4, 2)); at t_i <= t <= t_(i+1) the blade is
    Q_t = (t_(i+1) - t) / (t_(i+1) - t_i) Q_i + (1 - (t_(i+1) - t) / (t_(i+1) - t_i)) Q_(i+1),
    which, a patch being linear in its control points, is the patch of the interpolated net.
    A vein node or source is kept by its (u, v) (its material coordinates): at time t it is at
    Q_t(u, v). A new point P is embedded by point inversion, minimizing E_P(u, v) = ||Q_t(u, v) - P||
    (eq. 5.2) from the nearest of a grid of samples of Q_t (the thesis starts from the nearest
    embedded point; both are only a start) by damped Gauss-Newton steps kept in [0, 1]^2.
    Before t_1 the blade is Q_1, after t_n it is Q_n. The margin is the image of the square's edges.
    """

    def __init__(self, controls, times):
        self.controls = np.ascontiguousarray(np.asarray(controls, dtype=np.float64).reshape(-1, 4, 4, 2))
        self.times = np.asarray(times, dtype=np.float64).reshape(-1)
        if len(self.times) != len(self.controls) or len(self.times) < 1:
            raise ValueError("one time per key frame")
        if np.any(np.diff(self.times) <= 0):
            raise ValueError("key-frame times must increase")
        s = np.linspace(0.0, 1.0, KF_SIDE_SAMPLES + 1)[:-1]
        one, zero = np.ones_like(s), np.zeros_like(s)
        # the square's boundary, counter-clockwise in (u, v)
        self._edge_uv = np.concatenate([np.column_stack([s, zero]), np.column_stack([one, s]),
                                        np.column_stack([1.0 - s, one]), np.column_stack([zero, 1.0 - s])])
        g = np.linspace(0.0, 1.0, KF_GRID)
        gu, gv = np.meshgrid(g, g, indexing="ij")
        self._grid_uv = np.column_stack([gu.ravel(), gv.ravel()])
        self._cache: dict = {}
        self._extents: dict = {}

    def control_at(self, t: float) -> np.ndarray:
        """(4, 4, 2): the control net of Q_t (the key frames' nets interpolated linearly)."""
        tt = self.times
        if t <= tt[0]:
            return self.controls[0]
        if t >= tt[-1]:
            return self.controls[-1]
        i = int(np.searchsorted(tt, t, side="right")) - 1
        a = (tt[i + 1] - t) / (tt[i + 1] - tt[i])
        return a * self.controls[i] + (1.0 - a) * self.controls[i + 1]

    def forward(self, mat, t: float) -> np.ndarray:
        """(n, 2) positions at time t of the points with material coordinates (u, v) ``mat`` (n, 2)."""
        m = np.asarray(mat, dtype=np.float64).reshape(-1, 2)
        return bezier_eval(self.control_at(t), m[:, 0], m[:, 1])

    def _state(self, t: float):
        key = float(t)
        st = self._cache.get(key)
        if st is None:
            from scipy.spatial import cKDTree

            c = self.control_at(t)
            margin = _dedupe_ring(bezier_eval(c, self._edge_uv[:, 0], self._edge_uv[:, 1]))
            blade = blade_from_points(margin)
            tree = cKDTree(bezier_eval(c, self._grid_uv[:, 0], self._grid_uv[:, 1]))
            if len(self._cache) > 4:
                self._cache.clear()
            st = self._cache[key] = (c, blade, tree)
        return st

    def inverse(self, pos, t: float, iterations: int = 40) -> np.ndarray:
        """(n, 2) material coordinates (u, v) in [0, 1]^2 of points ``pos`` (n, 2) at time t: the
        minimizers of eq. 5.2 (the nearest point of the blade for a point outside it)."""
        p = np.asarray(pos, dtype=np.float64).reshape(-1, 2)
        if not len(p):
            return np.zeros((0, 2))
        c, _, tree = self._state(t)
        _, k = tree.query(p)
        uv = self._grid_uv[k].copy()
        q = bezier_eval(c, uv[:, 0], uv[:, 1])
        err = ((q - p) ** 2).sum(1)
        for _ in range(iterations):
            q, qu, qv = bezier_eval(c, uv[:, 0], uv[:, 1], derivatives=True)
            r = q - p
            # Gauss-Newton on E^2 with Levenberg damping: (J^T J + mu I) d = -J^T r
            a11 = (qu * qu).sum(1)
            a12 = (qu * qv).sum(1)
            a22 = (qv * qv).sum(1)
            g1 = (qu * r).sum(1)
            g2 = (qv * r).sum(1)
            mu = 1e-9 * (a11 + a22) + 1e-300
            det = (a11 + mu) * (a22 + mu) - a12 * a12
            d1 = -((a22 + mu) * g1 - a12 * g2) / det
            d2 = -((a11 + mu) * g2 - a12 * g1) / det
            ok = np.isfinite(d1) & np.isfinite(d2)
            d1 = np.where(ok, d1, 0.0)
            d2 = np.where(ok, d2, 0.0)
            step = 1.0
            cand = uv.copy()
            better = np.zeros(len(p), np.bool_)
            for _h in range(6):  # halve the step until E decreases (steepest-descent safeguard)
                trial = np.clip(uv + step * np.column_stack([d1, d2]), 0.0, 1.0)
                e = ((bezier_eval(c, trial[:, 0], trial[:, 1]) - p) ** 2).sum(1)
                take = ~better & (e < err)
                cand[take] = trial[take]
                err = np.where(take, e, err)
                better |= take
                if better.all():
                    break
                step *= 0.5
            moved = np.abs(cand - uv).max(1) if len(p) else np.zeros(0)
            uv = cand
            if not np.any(better & (moved > 1e-13)):
                break
        return uv

    def margin(self, t: float) -> np.ndarray:
        """(m, 2): the blade's margin at time t, counter-clockwise."""
        return self._state(t)[1].polygon

    def blade_at(self, t: float) -> Blade:
        """The blade at time t (its margin and its base, the image of (0, 0))."""
        return self._state(t)[1]

    def contains(self, pts, t: float) -> np.ndarray:
        """(n,) bool: points (n, 2) inside the blade at time t."""
        return self._state(t)[1].contains(pts)

    def extent(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi): a box holding the blade at every time (Q_t is a convex combination of two key
        frames, whose control nets hold their patches)."""
        pts = self.controls.reshape(-1, 2)
        return pts.min(0), pts.max(0)

    def _extent(self, t: float) -> np.ndarray:
        key = float(t)
        e = self._extents.get(key)
        if e is None:
            c = self.control_at(t)
            e = np.ptp(bezier_eval(c, self._edge_uv[:, 0], self._edge_uv[:, 1]), axis=0)
            if len(self._extents) > 64:
                self._extents.clear()
            self._extents[key] = e
        return e

    def bound(self, t: float) -> np.ndarray:
        """(2,) the extent of the blade at time t over its extent at t_1, per axis (at least 1)."""
        e0 = self._extent(self.times[0])
        return np.maximum(self._extent(t) / np.maximum(e0, 1e-300), 1.0)


def _dedupe_ring(p: np.ndarray) -> np.ndarray:
    """The ring ``p`` without points that repeat their predecessor (a collapsed edge of the square)."""
    ext = float(np.ptp(p, axis=0).max()) if len(p) else 0.0
    nxt = np.roll(p, 1, axis=0)
    keep = np.abs(p - nxt).max(1) > 1e-12 * max(ext, 1e-300)
    return p[keep] if keep.sum() >= 3 else p


@dataclass(frozen=True)
class Growth:
    """The growth schedule: the blade's scale (sx, sy) at every step (sec. 4.2.3).

    ``kind`` is one of :data:`GROWTH_TYPES`. ``scale_at(t)`` is ``initial + rate * t`` per axis until
    ``final`` (``sigma_{t + dt} = sigma_t + delta sigma``), or ``f(t / steps)`` for growth functions
    ``f`` (``.func``, x in [0, 1]); the blade stops growing after :attr:`steps` steps.
    """

    kind: str
    initial: tuple[float, float] = (1.0, 1.0)
    final: tuple[float, float] = (1.0, 1.0)
    rate: tuple[float, float] = (0.0, 0.0)
    functions: tuple | None = None  # (fx, fy): callables of x in [0, 1]
    function_steps: int = 0
    ltg: LocalToGlobal | None = None  # local-to-global growth (sec. 5.2.1); its steps are function_steps
    kf: KeyFrames | None = None  # key-frame interpolation (sec. 5.2.1); its steps are function_steps

    @property
    def material(self):
        """The growth that moves every point by its material coordinates (local-to-global or key
        frames), or None."""
        return self.ltg if self.ltg is not None else self.kf

    @property
    def steps(self) -> int:
        """Growth steps: after these the blade keeps its final size."""
        if self.kind == "none":
            return 0
        if self.functions is not None or self.material is not None:
            return int(self.function_steps)
        n = 0
        for a, b, r in zip(self.initial, self.final, self.rate):
            if b > a:
                n = max(n, int(math.ceil((b - a) / r - 1e-9)))
        return n

    def scale_at(self, t: int) -> np.ndarray:
        """(2,) float64: (sx, sy) at step t (clamped to the end of growth)."""
        if self.kind == "none":
            return np.ones(2)
        if self.ltg is not None:  # the blade is no scaled copy: the stretch that bounds it
            return self.ltg.bound(min(max(t, 0), self.function_steps))
        if self.kf is not None:
            return self.kf.bound(min(max(t, 0), self.function_steps))
        if self.functions is not None:
            x = 1.0 if self.function_steps <= 0 else min(max(t / self.function_steps, 0.0), 1.0)
            return np.array([float(f(x)) for f in self.functions])
        s = np.array(self.initial, dtype=np.float64) + np.array(self.rate, dtype=np.float64) * t
        return np.minimum(s, np.maximum(np.array(self.final, dtype=np.float64), np.array(self.initial)))

    @property
    def final_scale(self) -> np.ndarray:
        return self.scale_at(self.steps)

    def margin(self, blade, t: int) -> np.ndarray:
        """(m, 2): the margin of ``blade`` at step t."""
        if self.kind == "none":
            return blade.scaled(1.0)
        if self.ltg is not None:
            return self.ltg.forward(blade.polygon, min(max(t, 0), self.function_steps))
        if self.kf is not None:
            return self.kf.margin(min(max(t, 0), self.function_steps))
        return blade.scaled(self.scale_at(t))


# --------------------------------------------------------------------------------------------
# triangle mesh


def triangulate_blade(poly, spacing: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """A triangle mesh of the polygon (m, 2): its margin points (edges longer than ``spacing``
    divided) plus interior points on a triangular lattice of ``spacing`` (default: 1/48 of the blade's
    extent), Delaunay-triangulated
    (scipy), keeping the triangles inside the margin. Falls back to ear clipping of the margin
    alone when the triangulation does not respect the margin (the kept area differs from the
    polygon's).

    Returns
    -------
    vertices : (n, 2) float64
        The margin points first, in order, then the interior points.
    faces : (f, 3) int32, counter-clockwise
    """
    from scipy.spatial import Delaunay

    p = np.asarray(poly, dtype=np.float64)
    if polygon_area(p) < 0:
        p = p[::-1]
    edge = la.norm(np.roll(p, -1, axis=0) - p, axis=1)
    h = float(spacing) if spacing else float(np.ptp(p, axis=0).max()) / 48.0
    # margin edges longer than the spacing are divided
    pieces = np.maximum(1, np.ceil(edge / h - 1e-9).astype(np.int64))
    if np.any(pieces > 1):
        q = np.roll(p, -1, axis=0)
        p = np.vstack([p[i] + (q[i] - p[i]) * (np.arange(k)[:, None] / k) for i, k in enumerate(pieces)])
    lo, hi = p.min(0), p.max(0)
    rows = np.arange(lo[1] + 0.5 * h, hi[1], h * math.sqrt(3) / 2)
    pts = []
    for k, y in enumerate(rows):
        xs = np.arange(lo[0] + (0.5 + 0.5 * (k % 2)) * h, hi[0], h)
        pts.append(np.column_stack([xs, np.full(len(xs), y)]))
    inner = np.vstack(pts) if pts else np.zeros((0, 2))
    if len(inner):
        bl = blade_from_points(p, base=p[0])
        inner = inner[bl.contains(inner)]
        if len(inner):
            inner = inner[bl.distance_to_margin(inner) > 0.5 * h]
    verts = np.vstack([p, inner])
    area = polygon_area(p)
    try:
        tri = Delaunay(verts)
        f = tri.simplices.astype(np.int64)
        c = verts[f].mean(axis=1)
        keep = blade_from_points(p, base=p[0]).contains(c)
        f = f[keep]
        a = verts[f]
        cross = (a[:, 1, 0] - a[:, 0, 0]) * (a[:, 2, 1] - a[:, 0, 1]) - (a[:, 1, 1] - a[:, 0, 1]) * (a[:, 2, 0] - a[:, 0, 0])
        f[cross < 0] = f[cross < 0][:, [0, 2, 1]]
        kept = 0.5 * np.abs(cross).sum()
        if abs(kept - area) <= 1e-9 * area:
            return verts, f.astype(np.int32)
    except Exception:  # Qhull on a degenerate set: ear clipping below
        pass
    return p.copy(), _ear_clip(p)


def _ear_clip(p: np.ndarray) -> np.ndarray:
    """Triangles of a simple counter-clockwise polygon by ear clipping (O(m^2) ear tests, each
    against the reflex vertices only; compiled: a dissected leaf has thousands of margin points)."""
    tri, n = _ear_clip_kernel(np.ascontiguousarray(p, dtype=np.float64))
    return tri[:n].astype(np.int32).reshape(-1, 3)


@njit(cache=True)
def _ear_clip_kernel(p):
    m = p.shape[0]
    nxt = np.empty(m, np.int64)
    prv = np.empty(m, np.int64)
    for i in range(m):
        nxt[i] = (i + 1) % m
        prv[i] = (i - 1) % m
    out = np.empty((max(m - 2, 1), 3), np.int64)
    n_out = 0
    left = m
    i = 0
    miss = 0
    while left > 3 and miss < left:
        a, b, c = prv[i], i, nxt[i]
        ax, ay, bx, by, cx, cy = p[a, 0], p[a, 1], p[b, 0], p[b, 1], p[c, 0], p[c, 1]
        ok = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax) > 0.0
        if ok:
            j = nxt[c]
            while j != a:
                qx, qy = p[j, 0], p[j, 1]
                # only a reflex (or flat) vertex can lie in an ear
                pj, nj = prv[j], nxt[j]
                if (p[j, 0] - p[pj, 0]) * (p[nj, 1] - p[pj, 1]) - (p[j, 1] - p[pj, 1]) * (p[nj, 0] - p[pj, 0]) <= 0.0:
                    if ((bx - ax) * (qy - ay) - (by - ay) * (qx - ax) >= 0.0
                            and (cx - bx) * (qy - by) - (cy - by) * (qx - bx) >= 0.0
                            and (ax - cx) * (qy - cy) - (ay - cy) * (qx - cx) >= 0.0):
                        ok = False
                        break
                j = nxt[j]
        if ok:
            out[n_out, 0], out[n_out, 1], out[n_out, 2] = a, b, c
            n_out += 1
            nxt[a] = c
            prv[c] = a
            left -= 1
            i = a
            miss = 0
        else:
            i = nxt[i]
            miss += 1
    if left == 3:
        out[n_out, 0], out[n_out, 1], out[n_out, 2] = prv[i], i, nxt[i]
        n_out += 1
    return out, n_out
