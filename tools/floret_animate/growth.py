"""Growth-function mode (Lu, Willis, Paddon, "Perceptually realistic flower generation").

A petal is a bicubic Bezier patch: an organ with a 4 x 4 control grid of degree 3 3 (a clamped
B-spline with 4 control points per direction is one Bezier segment; not bilateral). It grows from
the initial pose by **growth-rate functions** in three directions of the petal,

    f(t) = a t^2 + b t + c        (their eq. 3: the rate of growth, length units per time unit)

and the growth over a time interval is the integral of the rate (eq. 2, 4):

    G(t0, t1) = integral_{t0}^{t1} f(t) dt = a (t1^3 - t0^3) / 3 + b (t1^2 - t0^2) / 2 + c (t1 - t0).

The rate may change at any moment (sec. 2.3): the parameter file gives a list of pieces, each
with its start time; a piece holds until the next one starts. The growth may be negative.

Directions, in the petal's frame at angle 0 (formats/floret.md): **length** L along the petal
(from the mean of the base row to the mean of the top row of the initial pose), **width** W = +Z
across the petal (made orthogonal to L), **depth** D = L x W (its normal). Control point (row j,
column i) moves by

    G_len(0, t) r_j L + G_wid(0, t) r_j w_i W + G_dep(0, t) r_j D,

with the **row growth factors** r_j (sec. 2.4: the top row grows 1 unit, the next 2/3, then 1/3,
the base 0; or user-given) and the lateral position ``w_i = (2 i - (nu - 1)) / (nu - 1)`` in
[-1, 1] (the petal widens symmetrically about its midline). Per-control-point **overrides** replace
the rates or scale the factors of single points (asymmetric petals, sec. 3.1). A seeded random
**perturbation** multiplies each petal's rates by ``1 + perturbation * N(0, 1)`` (clipped to
[0.5, 1.5]) and each point's by ``1 + perturbation / 2 * N(0, 1)``, so the n petals of a flower
differ (sec. 1: "non-deterministic"); to hold n different petals the grown organ is written as n
organs ``NAME_k`` with 1-fold symmetry and phase ``phase + k 360 / n``.

Frames: frame i of F has frame time tau_i = i / (F - 1); its growth time is ``duration * g(tau_i)``
(g the optional growth function of the timing, default linear). The written ``.floret`` frames are
the same as floret-animate's interpolation mode writes, so polygonize and the rest of the pipeline
do not change.

Parameter file (TOML; reference page: formats/lu_growth.md)::

    duration = 1.0                 # growth time of the last frame
    organ = "petal"                # the organ that grows (default: every 4 x 4 bicubic organ)
    row_factors = [0, 0.3333, 0.6667, 1]   # base -> top (default as in the paper)
    perturbation = 0.0             # relative random variation between petals (seeded: --seed)

    [[rate]]                       # growth-rate pieces; `start` 0 for the first
    start = 0.0
    length = [0.0, 0.0, 0.8]       # a b c of f(t) = a t^2 + b t + c
    width = [0.0, 0.0, 0.6]
    depth = [0.0, 0.0, 0.2]

    [[override]]                   # optional, per control point
    row = 3                        # 0 = base .. 3 = top
    col = 0                        # 0 .. 3 across
    factor = [1.0, 1.5, 1.0]       # multiplies the (length, width, depth) growth of this point
    depth = [0.0, 0.0, -0.3]       # replaces the depth rate of this point (also length, width)
"""
from __future__ import annotations

import dataclasses
import math
import os
import tomllib

import numpy as np

from inflo.formats.errors import InputError
from inflo.formats.floret import Floret, Organ
from inflo.formats.func import Function
from inflo.tools.common import linalg as la

from .animate import frame_times

__all__ = ["LuParams", "RatePiece", "read_lu_params", "parse_lu_params", "growth_integral",
           "lu_frames", "grow_organ"]

COMPONENTS = ("length", "width", "depth")
DEFAULT_ROW_FACTORS = (0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0)


@dataclasses.dataclass(frozen=True)
class RatePiece:
    """f(t) = a t^2 + b t + c per component, from ``start`` until the next piece."""

    start: float
    coeffs: np.ndarray  # (3 components, 3 coefficients a b c)


@dataclasses.dataclass(frozen=True)
class LuParams:
    rates: tuple  # of RatePiece, starts increasing, the first at 0
    duration: float = 1.0
    organ: str | None = None
    row_factors: tuple = DEFAULT_ROW_FACTORS
    perturbation: float = 0.0
    overrides: tuple = ()  # of (row, col, factor (3,), coeff overrides {component index: (3,)})


def growth_integral(coeffs, t0, t1):
    """Integral of a t^2 + b t + c from t0 to t1 (Lu et al. eq. 4); coeffs (..., 3)."""
    c = np.asarray(coeffs, dtype=np.float64)
    return (c[..., 0] * (t1 ** 3 - t0 ** 3) / 3.0 + c[..., 1] * (t1 ** 2 - t0 ** 2) / 2.0
            + c[..., 2] * (t1 - t0))


def _piecewise_growth(pieces_coeffs, starts, t):
    """Growth from 0 to t of piecewise quadratic rates; pieces_coeffs (k, ..., 3)."""
    total = 0.0
    for i, s in enumerate(starts):
        end = starts[i + 1] if i + 1 < len(starts) else math.inf
        if t <= s:
            break
        total = total + growth_integral(pieces_coeffs[i], s, min(t, end))
    return total


def parse_lu_params(data: dict, path="parameters") -> LuParams:
    """Validate a parsed TOML table (see the module docstring)."""
    where = os.fspath(path)

    def fail(expected, found):
        raise InputError(f"{where}: expected {expected}, found {found}")

    allowed = {"duration", "organ", "row_factors", "perturbation", "rate", "override"}
    unknown = sorted(set(data) - allowed)
    if unknown:
        fail(f"only the keys {', '.join(sorted(allowed))}", f"{unknown[0]!r}")

    def number(v, what):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            fail(what, repr(v))
        return float(v)

    def triple(v, what):
        if not isinstance(v, list) or len(v) != 3:
            fail(f"{what} as 3 numbers [a, b, c] of f(t) = a t^2 + b t + c", repr(v))
        return np.array([number(x, f"numbers in {what}") for x in v])

    duration = number(data.get("duration", 1.0), "a duration > 0")
    if duration <= 0:
        fail("a duration > 0", repr(duration))
    perturbation = number(data.get("perturbation", 0.0), "a perturbation >= 0")
    if perturbation < 0:
        fail("a perturbation >= 0", repr(perturbation))
    organ = data.get("organ")
    if organ is not None and not isinstance(organ, str):
        fail("an organ name", repr(organ))
    rf = data.get("row_factors", list(DEFAULT_ROW_FACTORS))
    if not isinstance(rf, list) or len(rf) != 4:
        fail("row_factors as 4 numbers (base -> top)", repr(rf))
    rf = tuple(number(x, "numbers in row_factors") for x in rf)
    rates = data.get("rate")
    if not isinstance(rates, list) or not rates:
        fail("at least one [[rate]] table", "none")
    pieces = []
    for k, r in enumerate(rates):
        if not isinstance(r, dict):
            fail("[[rate]] tables", repr(r))
        bad = sorted(set(r) - {"start", *COMPONENTS})
        if bad:
            fail("rate keys start, length, width, depth", repr(bad[0]))
        start = number(r.get("start", 0.0 if k == 0 else None), f"'start' in rate {k + 1}")
        if k == 0 and start != 0.0:
            fail("the first [[rate]] to start at 0", repr(start))
        if pieces and not start > pieces[-1].start:
            fail(f"rate starts in increasing order (rate {k + 1})", repr(start))
        coeffs = np.stack([triple(r[c], f"rate {k + 1} {c}") if c in r else np.zeros(3)
                           for c in COMPONENTS])
        pieces.append(RatePiece(start, coeffs))
    overrides = []
    for o in data.get("override", []):
        if not isinstance(o, dict):
            fail("[[override]] tables", repr(o))
        bad = sorted(set(o) - {"row", "col", "factor", *COMPONENTS})
        if bad:
            fail("override keys row, col, factor, length, width, depth", repr(bad[0]))
        row, col = o.get("row"), o.get("col")
        for name, v in (("row", row), ("col", col)):
            if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= 3:
                fail(f"an override {name} in 0..3", repr(v))
        factor = o.get("factor", [1.0, 1.0, 1.0])
        if not isinstance(factor, list) or len(factor) != 3:
            fail("an override factor of 3 numbers (length, width, depth)", repr(factor))
        factor = np.array([number(x, "numbers in factor") for x in factor])
        repl = {i: triple(o[c], f"override {c}") for i, c in enumerate(COMPONENTS) if c in o}
        overrides.append((row, col, factor, repl))
    return LuParams(tuple(pieces), duration, organ, rf, perturbation, tuple(overrides))


def read_lu_params(path) -> LuParams:
    """Read a growth-mode TOML file (InputError for a missing file, bad TOML or bad values)."""
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except OSError as exc:
        raise InputError(f"{os.fspath(path)}: cannot read ({exc.strerror})") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{os.fspath(path)}: expected TOML, found an error: {exc}") from None
    except UnicodeDecodeError as exc:
        raise InputError(f"{os.fspath(path)}: expected TOML (UTF-8 text), found byte 0x{exc.object[exc.start]:02x} "
                         f"at offset {exc.start}") from None
    return parse_lu_params(data, path)


def _petal_axes(cp: np.ndarray) -> np.ndarray:
    """(3, 3): rows L (length), W (width), D (depth) of the initial petal."""
    length = cp[-1].mean(axis=0) - cp[0].mean(axis=0)
    if la.norm(length) < 1e-12:
        length = np.array([0.0, 1.0, 0.0])
    length = length / la.norm(length)
    width = np.array([0.0, 0.0, 1.0]) - length[2] * length
    if la.norm(width) < 1e-9:
        width = np.array([1.0, 0.0, 0.0]) - length[0] * length
    width /= la.norm(width)
    depth = np.cross(length, width)
    return np.stack([length, width, depth])


class _GrowingPetal:
    """One petal's growth: per control point, per component, piecewise rates and factors."""

    def __init__(self, cp0: np.ndarray, params: LuParams, rng: np.random.Generator | None):
        self.cp0 = np.array(cp0, dtype=np.float64)
        nv, nu = self.cp0.shape[:2]
        self.axes = _petal_axes(self.cp0)
        self.starts = [p.start for p in params.rates]
        # coefficients per piece, point and component: (k, nv, nu, 3 comps, 3 coeffs)
        base = np.stack([p.coeffs for p in params.rates])  # (k, 3, 3)
        coeffs = np.broadcast_to(base[:, None, None], (len(base), nv, nu, 3, 3)).copy()
        w = (2.0 * np.arange(nu) - (nu - 1)) / (nu - 1)
        factors = np.ones((nv, nu, 3))
        factors *= np.asarray(params.row_factors)[:, None, None]
        factors[..., 1] *= w[None, :]
        for row, col, factor, repl in params.overrides:
            factors[row, col] *= factor
            for comp, c in repl.items():
                coeffs[:, row, col, comp] = c
        if rng is not None and params.perturbation > 0:
            sigma = params.perturbation
            petal = np.clip(1.0 + sigma * rng.standard_normal(3), 0.5, 1.5)
            point = np.clip(1.0 + 0.5 * sigma * rng.standard_normal((nv, nu, 3)), 0.5, 1.5)
            factors *= petal * point
        self.coeffs = coeffs
        self.factors = factors

    def at(self, t: float) -> np.ndarray:
        g = _piecewise_growth(self.coeffs, self.starts, t)  # (nv, nu, 3) per component
        if np.isscalar(g):
            g = np.zeros(self.factors.shape)
        disp = la.matmul(g * self.factors, self.axes)  # sum over components of growth * axis
        return self.cp0 + disp


def _is_bezier_petal(o: Organ) -> bool:
    return o.nu == 4 and o.nv == 4 and o.degree_u == 3 and o.degree_v == 3 and not o.bilateral


def grow_organ(organ: Organ, params: LuParams, times, seed: int = 0, path="key pose"):
    """Control nets of the organ's petals over time: list over times of (n, 4, 4, 3) arrays."""
    if not _is_bezier_petal(organ):
        raise InputError(
            f"{os.fspath(path)}: expected organ {organ.name!r} to be a bicubic Bezier petal for "
            f"--lu (grid 4 4, degree 3 3, bilateral off), found grid {organ.nu} {organ.nv}, "
            f"degree {organ.degree_u} {organ.degree_v}, bilateral {'on' if organ.bilateral else 'off'}")
    rng = np.random.default_rng(seed) if params.perturbation > 0 else None
    petals = [_GrowingPetal(organ.control_points, params, rng) for _ in range(organ.symmetry_n)]
    return [np.stack([p.at(t) for p in petals]) for t in times]


def lu_frames(pose: Floret, params: LuParams, *, n_frames: int = 100,
              growth: Function | None = None, seed: int = 0, path="key pose"):
    """Yield the frames (Floret) of a pose grown by Lu et al.'s growth-rate functions."""
    names = [o.name for o in pose.organs]
    if params.organ is not None and params.organ not in names:
        raise InputError(f"{os.fspath(path)}: expected an organ {params.organ!r} (named in the "
                         f"--lu parameters), found only {', '.join(names)}")
    grow = [o for o in pose.organs
            if (o.name == params.organ if params.organ is not None else _is_bezier_petal(o))]
    if not grow:
        raise InputError(f"{os.fspath(path)}: expected a bicubic Bezier petal organ (grid 4 4, "
                         "degree 3 3, bilateral off) to grow with --lu, found none")
    taus = frame_times(n_frames)
    g = taus if growth is None else np.clip(np.asarray(growth(taus)), 0.0, 1.0)
    times = params.duration * g
    nets = {o.name: grow_organ(o, params, times, seed, path) for o in grow}
    for i, t in enumerate(times):
        organs = []
        for o in pose.organs:
            if o.name not in nets:
                organs.append(o)
                continue
            n = o.symmetry_n
            for k in range(n):
                organs.append(dataclasses.replace(
                    o, name=f"{o.name}_{k}" if n > 1 else o.name, control_points=nets[o.name][i][k],
                    symmetry_n=1, symmetry_phase_deg=o.symmetry_phase_deg + k * 360.0 / n))
        yield Floret(pose.name, tuple(organs), float(t))
