"""Generating curves C and surfaces of revolution (thesis sec. 5.2, fig. 5.1).

A supporting surface (meristem, receptacle) is the rotation of a planar generating curve C about
the scene's +Y axis. C lies in the (r, y) half plane: ``r >= 0`` is the distance from the axis,
``y`` the height. It runs from the axis (the apex, ``r = 0``) to the rim; s is its arc length.

A :class:`Profile` samples C densely by arc length and carries, per sample, r(s), y(s), the unit
tangent and the unit normal in the (r, y) plane (normal = tangent turned +90 degrees, so a flat
disk facing +Y has normal +Y), and the cumulative surface area ``S(s) = int_0^s 2 pi r ds``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from inflo.formats.contour import read_con
from inflo.formats.errors import FormatError, InputError

__all__ = ["Profile", "builtin_curve", "load_curve", "profile_from_points", "blend_profiles"]

_AXIS_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class Profile:
    """A densely sampled generating curve C (all arrays ``(m,) float64``).

    Attributes
    ----------
    s : arc length from the apex end, ``s[0] = 0``, increasing.
    r, y : distance from the axis and height of the curve point.
    tr, ty : unit tangent (direction of increasing s).
    nr, ny : unit normal, the tangent turned +90 degrees (``(-ty, tr)``).
    area : cumulative surface area ``S(s) = int_0^s 2 pi r(s') ds'`` (trapezoid rule).
    name : where the curve came from (for messages).
    """

    s: np.ndarray
    r: np.ndarray
    y: np.ndarray
    tr: np.ndarray
    ty: np.ndarray
    nr: np.ndarray
    ny: np.ndarray
    area: np.ndarray
    name: str = "curve"

    @property
    def length(self) -> float:
        return float(self.s[-1])

    @property
    def total_area(self) -> float:
        return float(self.area[-1])

    def at(self, s) -> dict:
        """Interpolated ``r, y, tr, ty, nr, ny`` at arc lengths ``s`` (array_like, clamped)."""
        s = np.asarray(s, dtype=np.float64)
        out = {k: np.interp(s, self.s, getattr(self, k)) for k in ("r", "y", "tr", "ty", "nr", "ny")}
        tn = np.hypot(out["tr"], out["ty"])
        tn = np.where(tn > 0, tn, 1.0)
        out["tr"], out["ty"] = out["tr"] / tn, out["ty"] / tn
        out["nr"], out["ny"] = -out["ty"], out["tr"]
        return out

    def s_of_area(self, a) -> np.ndarray:
        """Arc length where the cumulative area ``S(s)`` reaches ``a`` (inverse of :attr:`area`)."""
        return np.interp(a, self.area, self.s)

    def scaled(self, factor: float) -> Profile:
        """The same curve scaled by ``factor`` about the origin (areas scale by ``factor**2``)."""
        f = float(factor)
        return Profile(self.s * f, self.r * f, self.y * f, self.tr, self.ty, self.nr, self.ny,
                       self.area * f * f, self.name)


def profile_from_points(points, *, name: str = "curve", samples: int = 2048, path=None) -> Profile:
    """Build a :class:`Profile` from a polyline ``points (k, 2)`` of (r, y), resampled by arc length.

    The polyline is reversed when it starts at the rim (its first r larger than its last r).

    Raises
    ------
    FormatError
        The curve crosses the axis (r < 0 somewhere, or r = 0 away from the apex end), doubles
        back (a cusp: the tangent turns by more than 150 degrees between neighbouring samples,
        or the polyline crosses itself), or has zero length.
    """
    where = path if path is not None else name
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if p[0, 0] > p[-1, 0]:
        p = p[::-1]
    seg = np.diff(p, axis=0)
    seglen = np.hypot(seg[:, 0], seg[:, 1])
    keep = np.concatenate([[True], seglen > 1e-14])
    p = p[keep]
    seg = np.diff(p, axis=0)
    seglen = np.hypot(seg[:, 0], seg[:, 1])
    if len(p) < 2 or seglen.sum() <= 0:
        raise FormatError(where, None, "a generating curve of non-zero length", "a point")
    scale = float(seglen.sum())
    if np.any(p[:, 0] < -_AXIS_TOL * scale):
        k = int(np.argmax(p[:, 0] < -_AXIS_TOL * scale))
        raise FormatError(where, None, "a generating curve on one side of the axis (r >= 0)",
                          f"r = {p[k, 0]:.6g} at curve point {k} (the curve crosses the axis)")
    interior = p[1:-1, 0] <= _AXIS_TOL * scale
    if np.any(interior):
        k = int(np.argmax(interior)) + 1
        raise FormatError(where, None, "a generating curve touching the axis only at its apex end",
                          f"r = 0 at curve point {k} of {len(p)}")
    d = seg / seglen[:, None]
    cosang = np.sum(d[1:] * d[:-1], axis=1)
    if np.any(cosang < np.cos(np.radians(150.0))):
        k = int(np.argmax(cosang < np.cos(np.radians(150.0)))) + 1
        raise FormatError(where, None, "a generating curve that does not double back",
                          f"a cusp (turn of {np.degrees(np.arccos(np.clip(cosang[k - 1], -1, 1))):.0f} deg) "
                          f"at (r, y) = ({p[k, 0]:.6g}, {p[k, 1]:.6g})")
    _check_self_intersection(p, where)
    cum = np.concatenate([[0.0], np.cumsum(seglen)])
    s = np.linspace(0.0, cum[-1], int(samples))
    r = np.maximum(np.interp(s, cum, p[:, 0]), 0.0)
    y = np.interp(s, cum, p[:, 1])
    # tangent: central differences of the dense resampled polyline
    tr, ty = np.gradient(r, s), np.gradient(y, s)
    tn = np.hypot(tr, ty)
    tn[tn == 0] = 1.0
    tr, ty = tr / tn, ty / tn
    area = np.concatenate([[0.0], np.cumsum(np.pi * (r[1:] + r[:-1]) * np.diff(s))])
    return Profile(s, r, y, tr, ty, -ty, tr, area, str(name))


def _check_self_intersection(p: np.ndarray, where) -> None:
    """Raise when the polyline (resampled to <= 256 segments) crosses itself."""
    if len(p) > 257:
        idx = np.linspace(0, len(p) - 1, 257).round().astype(int)
        p = p[idx]
    a, b = p[:-1], p[1:]
    n = len(a)
    if n < 3:
        return
    i, j = np.triu_indices(n, k=2)
    ax, ay, bx, by = a[i, 0], a[i, 1], b[i, 0], b[i, 1]
    cx, cy, dx, dy = a[j, 0], a[j, 1], b[j, 0], b[j, 1]

    def orient(px, py, qx, qy, rx, ry):
        return (qx - px) * (ry - py) - (qy - py) * (rx - px)

    o1, o2 = orient(ax, ay, bx, by, cx, cy), orient(ax, ay, bx, by, dx, dy)
    o3, o4 = orient(cx, cy, dx, dy, ax, ay), orient(cx, cy, dx, dy, bx, by)
    hit = (o1 * o2 < 0) & (o3 * o4 < 0)
    if np.any(hit):
        k = int(np.argmax(hit))
        raise FormatError(where, None, "a generating curve that does not double back",
                          f"the curve crosses itself near (r, y) = ({a[i[k], 0]:.6g}, {a[i[k], 1]:.6g})")


def builtin_curve(name: str, *, radius: float = 1.0, height: float = 0.0, angle: float = 90.0,
                  samples: int = 2048) -> Profile:
    """A built-in generating curve from the apex to the rim.

    - ``disk``: flat, ``y = 0``, r from 0 to ``radius``;
    - ``cone``: apex at ``(0, height)``, rim at ``(radius, 0)`` (height < 0: a funnel);
    - ``sphere_cap``: a sphere of radius ``radius`` centred at ``(0, -radius)`` (apex at the
      origin), polar angle from 0 to ``angle`` degrees;
    - ``paraboloid``: ``y = height * (1 - (r / radius)**2)``.
    """
    k = 1024
    if name == "disk":
        t = np.linspace(0.0, 1.0, 2)
        pts = np.c_[t * radius, 0.0 * t]
    elif name == "cone":
        t = np.linspace(0.0, 1.0, 2)
        pts = np.c_[t * radius, height * (1.0 - t)]
    elif name == "sphere_cap":
        th = np.radians(np.linspace(0.0, angle, k))
        pts = np.c_[radius * np.sin(th), radius * (np.cos(th) - 1.0)]
    elif name == "paraboloid":
        t = np.linspace(0.0, 1.0, k)
        pts = np.c_[t * radius, height * (1.0 - t * t)]
    else:
        raise InputError(f"unknown built-in curve {name!r} (expected disk, cone, sphere_cap or paraboloid)")
    return profile_from_points(pts, name=name, samples=samples)


def load_curve(curve: str, *, radius: float = 1.0, height: float = 0.0, angle: float = 90.0,
               samples: int = 2048) -> Profile:
    """A built-in curve by name, or a VLab ``.con`` contour (its x is r, its y the height).

    A contour is sampled by arc length (:meth:`Contour.point_at`) and scaled by ``radius`` so
    the unit-sized drawings of the contour editor give receptacles of the requested size.
    """
    if curve in ("disk", "cone", "sphere_cap", "paraboloid"):
        return builtin_curve(curve, radius=radius, height=height, angle=angle, samples=samples)
    con = read_con(curve)
    if con.closed:
        raise FormatError(curve, None, "an open contour (a generating curve)", "a closed contour")
    pts = con.point_at(np.linspace(0.0, 1.0, 1025))[:, :2] * float(radius)
    return profile_from_points(pts, name=curve, samples=samples, path=curve)


def blend_profiles(profiles: list, times: list, t: float, samples: int = 1024) -> Profile:
    """Linear interpolation between generating curves given at ``times`` (sec. 5.3).

    Each curve is resampled at the same arc-length fractions, blended point by point with the
    weight of ``t`` between its neighbouring times (clamped outside), and normalized to unit
    arc length (the caller scales it to the meristem's area). The key curves were checked when
    they were loaded; a blend of curves on one side of the axis stays on that side.
    """
    units = [unit_profile(p, samples) for p in profiles]
    if len(units) == 1:
        return units[0]
    times = np.asarray(times, dtype=np.float64)
    t = float(np.clip(t, times[0], times[-1]))
    k = int(np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2))
    w = (t - times[k]) / (times[k + 1] - times[k])
    a, b = units[k], units[k + 1]
    return _from_polyline((1 - w) * a.r + w * b.r, (1 - w) * a.y + w * b.y, "blend", unit=True)


def unit_profile(p: Profile, samples: int = 1024) -> Profile:
    """``p`` resampled at ``samples`` equal arc-length steps and scaled to unit length (cached)."""
    cache = p.__dict__.setdefault("_unit_cache", {})
    if samples not in cache:
        f = np.linspace(0.0, 1.0, samples)
        r = np.interp(f * p.length, p.s, p.r) / p.length
        y = np.interp(f * p.length, p.s, p.y) / p.length
        cache[samples] = _from_polyline(r, y, p.name, unit=True)
    return cache[samples]


def _from_polyline(r: np.ndarray, y: np.ndarray, name: str, unit: bool = False) -> Profile:
    """A Profile straight from a dense polyline (no checks, no resampling)."""
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(r), np.diff(y)))])
    if unit and s[-1] > 0:
        r, y, s = r / s[-1], y / s[-1], s / s[-1]
    tr, ty = np.gradient(r, s), np.gradient(y, s)
    tn = np.hypot(tr, ty)
    tn[tn == 0] = 1.0
    tr, ty = tr / tn, ty / tn
    area = np.concatenate([[0.0], np.cumsum(np.pi * (r[1:] + r[:-1]) * np.diff(s))])
    return Profile(s, r, y, tr, ty, -ty, tr, area, str(name))
