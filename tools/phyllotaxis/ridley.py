"""Ridley's phyllotaxis on a surface of revolution (thesis sec. 5.2, eq. 5.1-5.2, fig. 5.1).

Primordium i sits at arc length s_i of the generating curve C and at angle ``i * phi`` about the
axis. Consecutive positions solve eq. 5.2,

    int_{s_i}^{s_{i+1}} 2 pi r(s) / A(s) ds = 1,

so with ``G(s) = int_0^s 2 pi r / A ds`` (monotone, since r > 0 and A > 0) the positions are
``s_i = G^{-1}(G(s_0) + i)``: one inversion of a cumulative table, no iteration. With r(s) = s (a
disk) and constant A this is Vogel's spiral ``r_i = sqrt((G(s_0) + i) A / pi)``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from inflo.formats.errors import FormatError, InputError
from inflo.formats.func import read_func
from inflo.formats.scn import Group, Placement, Scene

from .surface import Profile

__all__ = ["AreaFunction", "area_function", "ridley_positions", "surface_frames", "RidleyPattern",
           "static_pattern", "pattern_scene", "diameter_of_area"]


class AreaFunction:
    """A(s): primordium area as a function of arc length s (a constant or a ``.func``).

    A ``.func`` is evaluated at the arc-length fraction ``s / length`` in [0, 1] (its x axis).
    """

    def __init__(self, value, length: float, path: str | None = None):
        self.path = path
        self.length = float(length)
        if isinstance(value, (int, float)):
            self.const = float(value)
            self.fn = None
        else:
            self.const = None
            self.fn = value

    def __call__(self, s) -> np.ndarray:
        s = np.asarray(s, dtype=np.float64)
        if self.fn is None:
            return np.full(s.shape, self.const)
        return np.asarray(self.fn(np.clip(s / self.length, 0.0, 1.0)), dtype=np.float64)


def area_function(spec, length: float) -> AreaFunction:
    """An :class:`AreaFunction` from a number or a ``.func`` path (read with ``read_func``)."""
    if isinstance(spec, str):
        return AreaFunction(read_func(spec), length, spec)
    return AreaFunction(float(spec), length)


def ridley_positions(profile: Profile, area: AreaFunction, *, start: float = 0.0, count: int = 0,
                     max_count: int = 1_000_000) -> np.ndarray:
    """Arc lengths s_i of the primordia by eq. 5.2.

    Parameters
    ----------
    profile : Profile
        The generating curve C.
    area : AreaFunction
        A(s) > 0 on the whole curve.
    start : float
        s_0 as a fraction of the curve length, in [0, 1).
    count : int
        How many primordia; 0 places every primordium that fits before the rim.

    Returns
    -------
    s : (n,) float64, increasing.

    Raises
    ------
    FormatError
        A(s) <= 0 somewhere on the curve.
    InputError
        ``count`` exceeds the primordia that fit, or more than ``max_count`` would be placed.
    """
    a = area(profile.s)
    from .params import MIN_AREA

    if np.any(~np.isfinite(a)) or np.any(a < MIN_AREA):
        k = int(np.argmax(~(a >= MIN_AREA)))
        raise FormatError(area.path or "primordia.area", None, f"A(s) > 0 along the whole curve (at least {MIN_AREA:g})",
                          f"A = {a[k]:.6g} at s = {profile.s[k]:.6g} (fraction {profile.s[k] / profile.length:.3f})")
    integrand = 2.0 * np.pi * profile.r / a
    G = np.concatenate([[0.0], np.cumsum(0.5 * (integrand[1:] + integrand[:-1]) * np.diff(profile.s))])
    g0 = float(np.interp(start * profile.length, profile.s, G))
    fits = int(math.floor(G[-1] - g0 + 1e-9)) + 1
    n = fits if count == 0 else count
    if count > fits:
        raise InputError(f"primordia.count = {count} primordia do not fit on the curve: "
                         f"{fits} fit between s_0 and the rim (make A(s) smaller or the surface larger)")
    if n > max_count:
        many = str(n) if n < 10**12 else f"about 1e{len(str(n)) - 1}"
        raise InputError(f"{many} primordia would be placed, more than primordia.max_count = {max_count}")
    targets = g0 + np.arange(n, dtype=np.float64)
    return np.interp(targets, G, profile.s)


def surface_frames(profile: Profile, s: np.ndarray, theta: np.ndarray) -> dict:
    """Positions and frames of points (s, theta) of the surface of revolution.

    Returns ``pos``, ``up`` (the surface normal), ``right`` (the meridian tangent, pointing away
    from the apex), each ``(n, 3) float64``; the axis is +Y and ``theta`` is measured from +X
    towards +Z.
    """
    q = profile.at(s)
    c, sn = np.cos(theta), np.sin(theta)
    pos = np.stack([q["r"] * c, q["y"], q["r"] * sn], axis=1)
    up = np.stack([q["nr"] * c, q["ny"], q["nr"] * sn], axis=1)
    right = np.stack([q["tr"] * c, q["ty"], q["tr"] * sn], axis=1)
    return {"pos": pos, "up": up, "right": right}


def diameter_of_area(area) -> np.ndarray:
    """Diameter of a disc of the given area: ``2 sqrt(A / pi)``."""
    return 2.0 * np.sqrt(np.asarray(area, dtype=np.float64) / np.pi)


@dataclass
class RidleyPattern:
    """A static pattern as structure of arrays (n primordia, in order of index i).

    Attributes
    ----------
    s : (n,) float64  arc length along C
    theta : (n,) float64  angle about the axis, radians (``i * divergence``)
    area : (n,) float64  A(s_i)
    pos, up, right : (n, 3) float64
    centre : (3,) float64  the apex (the head's centre O for dimorph)
    """

    s: np.ndarray
    theta: np.ndarray
    area: np.ndarray
    pos: np.ndarray
    up: np.ndarray
    right: np.ndarray
    centre: np.ndarray


def static_pattern(profile: Profile, area: AreaFunction, *, divergence: float = 137.50776405003785,
                   start: float = 0.0, count: int = 0, max_count: int = 1_000_000) -> RidleyPattern:
    """Ridley's static pattern (eq. 5.2 and the divergence angle in degrees)."""
    if not 0.0 < divergence < 360.0:
        raise InputError(f"divergence angle {divergence} outside (0, 360) degrees")
    s = ridley_positions(profile, area, start=start, count=count, max_count=max_count)
    theta = np.radians(divergence) * np.arange(len(s), dtype=np.float64)
    fr = surface_frames(profile, s, theta)
    apex = np.array([0.0, float(profile.y[0]), 0.0])
    return RidleyPattern(s, theta, area(s), fr["pos"], fr["up"], fr["right"], apex)


def pattern_scene(pattern: RidleyPattern, *, floret_id: int = 0, size_factor: float = 1.0,
                  kind: str = "o", frame_start: int = 0, frame_end: int = 100) -> Scene:
    """A :class:`Scene` of the pattern: one placement per primordium, group 0 = the head.

    The scale is ``size_factor * 2 sqrt(A / pi)`` on every axis (a floret of unit diameter fills
    its primordium's disc).
    """
    scene = Scene()
    scene.groups[0] = Group(0, pattern.centre, -1)
    d = size_factor * diameter_of_area(pattern.area)
    for k in range(len(pattern.s)):
        kw = {"frame_start": frame_start, "frame_end": frame_end} if kind == "ca" else {}
        scene.placements.append(Placement(kind, int(floret_id), pattern.pos[k], np.full(3, d[k]),
                                          pattern.up[k], pattern.right[k], group=0, **kw))
    return scene
