"""Crown envelopes for space colonization (Runions sec. 3.2.1, 3.2.2).

A generalized surface of revolution Q(theta, z) = CatmullRom(z, theta) (cos theta, sin theta, z)
interpolates generating curves C_i(z) placed at angles theta_i with Catmull-Rom splines
(eq. 3.4); a point with cylindrical coordinates (r, theta, z) is inside when
CatmullRom(z, theta) >= r (chi_Q). inflo's vertical axis is +Y (docs/architecture.md): Runions' z is
the height ``y - centre_y`` and theta is measured from +X toward +Z about the axis through
``centre``. A generating curve is a ``.con`` contour drawn with x = radius and y = height; it must
be a function of height (its y never turns back). Built-ins: sphere, ellipsoid, cone (base disc at
``centre``, apex ``height`` above), cylinder (``height`` tall above ``centre``).
"""
from __future__ import annotations

import numpy as np

from inflo.formats.contour import read_con
from inflo.formats.errors import FormatError

__all__ = ["Envelope", "catmull_rom", "HERMITE", "envelope_from_params", "profile_from_contour"]

_PROFILE_SAMPLES = 512


def HERMITE(t):
    """(h1, h2, h3, h4)(t) of eq. 3.4, each an array like ``t``."""
    t = np.asarray(t, dtype=np.float64)
    t2, t3 = t * t, t * t * t
    return 2 * t3 - 3 * t2 + 1, -2 * t3 + 3 * t2, t3 - 2 * t2 + t, t3 - t2


def catmull_rom(values, angles, theta):
    """CatmullRom(z, theta) of eq. 3.4 for given C_i(z) values.

    Parameters
    ----------
    values : (n, m) float64
        C_i(z) for the n generating curves (sorted by angle) at m heights.
    angles : (n,) float64
        theta_i in radians, increasing, within [0, 2 pi).
    theta : (m,) float64
        Angle of each point (any value; taken modulo 2 pi).

    Returns
    -------
    (m,) float64
    """
    c = np.asarray(values, dtype=np.float64)
    ang = np.asarray(angles, dtype=np.float64)
    n = len(ang)
    th = np.mod(np.asarray(theta, dtype=np.float64), 2 * np.pi)
    if n == 1:
        return c[0].copy()
    # i such that theta_i <= theta < theta_{i+1} (cyclically)
    i = np.searchsorted(ang, th, side="right") - 1
    wrap = i < 0
    i = np.where(wrap, n - 1, i)
    th = np.where(wrap, th + 2 * np.pi, th)
    nxt_angle = np.where(i + 1 < n, ang[np.minimum(i + 1, n - 1)], ang[0] + 2 * np.pi)
    t = (th - ang[i]) / (nxt_angle - ang[i])
    h1, h2, h3, h4 = HERMITE(t)
    cols = np.arange(c.shape[1])
    ci = c[i, cols]
    cip1 = c[(i + 1) % n, cols]
    cim1 = c[(i - 1) % n, cols]
    cip2 = c[(i + 2) % n, cols]
    return ci * h1 + cip1 * h2 + 0.5 * (cip1 - cim1) * h3 + 0.5 * (cip2 - ci) * h4


def profile_from_contour(contour, path=None):
    """(heights (s,), radii (s,)) of a generating curve, heights increasing.

    Raises
    ------
    FormatError
        When the curve is not a function of height (its y turns back).
    """
    pts = contour.point_at(np.linspace(0.0, 1.0, _PROFILE_SAMPLES))
    y, x = pts[:, 1], pts[:, 0]
    dy = np.diff(y)
    tol = 1e-9 * max(float(np.ptp(y)), 1e-12)
    if np.all(dy <= tol):
        y, x, dy = y[::-1], x[::-1], -dy[::-1]
    if not np.all(dy >= -tol) or np.ptp(y) <= 0:
        k = int(np.argmin(dy)) if np.any(dy < -tol) else 0
        raise FormatError(path or contour.name, None,
                          "a generating curve that is a function of height (y never turning back)",
                          f"y turning back near ({x[k]:.4g}, {y[k]:.4g})")
    keep = np.concatenate([[True], np.diff(y) > tol])
    return y[keep], np.maximum(x[keep], 0.0)


class Envelope:
    """The crown: a built-in shape or a generalized surface of revolution.

    Parameters
    ----------
    shape : str
    centre : (3,) float
    radius, radii, height
        Built-in dimensions.
    profiles : list of (heights, radii) arrays, angles : (n,) degrees
        Generating curves for ``shape = "contours"``.
    """

    def __init__(self, shape="sphere", centre=(0.0, 0.0, 0.0), radius=1.0, radii=(1.0, 1.0, 1.0), height=1.0,
                 profiles=None, angles=None):
        self.shape = shape
        self.centre = np.asarray(centre, dtype=np.float64)
        self.radius = float(radius)
        self.radii = np.asarray(radii, dtype=np.float64)
        self.height = float(height)
        if shape == "contours":
            order = np.argsort(np.mod(np.radians(angles), 2 * np.pi), kind="stable")
            self.angles = np.mod(np.radians(np.asarray(angles, dtype=np.float64)), 2 * np.pi)[order]
            self.profiles = [profiles[k] for k in order]
            self.z_lo = min(float(p[0][0]) for p in self.profiles)
            self.z_hi = max(float(p[0][-1]) for p in self.profiles)

    def profile_values(self, z):
        """(n, m) float64: C_i(z) for every generating curve (0 outside its height range)."""
        z = np.asarray(z, dtype=np.float64)
        return np.array([np.interp(z, h, r, left=0.0, right=0.0) for h, r in self.profiles])

    def surface_radius(self, theta, z):
        """CatmullRom(z, theta) (eq. 3.4): the envelope's radius at angle theta and height z."""
        return catmull_rom(self.profile_values(z), self.angles, theta)

    def contains(self, points) -> np.ndarray:
        """chi_Q: (m,) bool, True for points inside the envelope (boundary included)."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3) - self.centre
        x, y, z = p[:, 0], p[:, 1], p[:, 2]
        r = np.hypot(x, z)
        if self.shape == "sphere":
            return x * x + y * y + z * z <= self.radius ** 2
        if self.shape == "ellipsoid":
            a, b, c = self.radii
            return (x / a) ** 2 + (y / b) ** 2 + (z / c) ** 2 <= 1.0
        if self.shape == "cylinder":
            return (r <= self.radius) & (y >= 0) & (y <= self.height)
        if self.shape == "cone":
            return (y >= 0) & (y <= self.height) & (r <= self.radius * (1.0 - y / self.height))
        theta = np.arctan2(z, x)
        inside_z = (y >= self.z_lo) & (y <= self.z_hi)
        cr = self.surface_radius(theta, y)
        return inside_z & (cr >= r) & (cr > 0)

    def bounds(self):
        """(lo (3,), hi (3,)): an axis-aligned box around the envelope."""
        c = self.centre
        if self.shape == "sphere":
            e = np.full(3, self.radius)
            return c - e, c + e
        if self.shape == "ellipsoid":
            return c - self.radii, c + self.radii
        if self.shape in ("cylinder", "cone"):
            return c + [-self.radius, 0, -self.radius], c + [self.radius, self.height, self.radius]
        zs = np.linspace(self.z_lo, self.z_hi, 257)
        th = np.linspace(0, 2 * np.pi, 361)
        rmax = 0.0
        for z in zs:
            rmax = max(rmax, float(np.max(self.surface_radius(th, np.full_like(th, z)))))
        return c + [-rmax, self.z_lo, -rmax], c + [rmax, self.z_hi, rmax]


def envelope_from_params(params) -> Envelope:
    """The envelope of ``params.envelope`` (contour files relative to the parameter file)."""
    from .params import check_file

    e = params.envelope
    if e.shape != "contours":
        return Envelope(e.shape, e.centre, e.radius, e.radii, e.height)
    profiles, angles = [], []
    for spec in e.contours:
        path = check_file(params, "envelope", "contours", spec.file)
        profiles.append(profile_from_contour(read_con(path), path))
        angles.append(spec.angle)
    if len(set(np.round(np.mod(angles, 360.0), 9))) != len(angles):
        raise FormatError(params.source or "<params>", None, "generating curves at distinct angles",
                          f"angles {angles}")
    return Envelope("contours", e.centre, profiles=profiles, angles=angles)
