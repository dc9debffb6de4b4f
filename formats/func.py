"""Graphically-defined functions: VLab ``.func`` files and ``.fset`` galleries (funcedit, lpfg).

A function is a planar cubic B-spline through control points ``(x, y)`` with ``x`` running from 0
to 1; it is evaluated the way lpfg does it (docs/vlab_formats.md): the spline is sampled at
``samples`` equally spaced abscissae, and ``f(x)`` interpolates linearly between the samples.
The thesis uses such functions for the polygonization densities lambda(v) and eta(v) (sec. 2.4,
eq. 2.1), the floret growth timing (sec. 2.3, ch. 8 b), primordium area A(s) (sec. 5.2, eq. 5.2),
growth rates of meristem regions and primordia (sec. 5.3) and the branch weight w_b(d)
(sec. 7.2, fig. 7.4). Spec: ``formats/func.md``.

The B-spline evaluator :func:`clamped_bspline` is shared with :mod:`inflo.formats.contour`.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ._vlab import _Cursor, _fmt, read_gallery
from .atomic import write_text_atomic
from .errors import parse_float, parse_int, read_lines, shorten

__all__ = [
    "Function",
    "read_func",
    "write_func",
    "read_fset",
    "write_fset",
    "format_func",
    "format_fset",
    "clamped_bspline",
    "DEFAULT_SAMPLES",
    "MIN_SAMPLES",
    "MAX_SAMPLES",
]

DEFAULT_SAMPLES = 100
"""``samples:`` of a new function (funcedit's default) and of a version 1.0 (``range:``) file."""
MIN_SAMPLES = 10
MAX_SAMPLES = 1000
"""lpfg clamps ``samples`` to ``MIN_SAMPLES..MAX_SAMPLES`` before it builds the sample table."""

_BISECTION_STEPS = 64  # halves [0, 1] down to below double precision
_FLIP = {"on": True, "yes": True, "off": False, "no": False}


# --------------------------------------------------------------------------------------------
# B-spline evaluation


def clamped_bspline(control, t) -> np.ndarray:
    """Points of the clamped uniform B-spline curve over ``control`` at parameters ``t``.

    The degree is ``min(3, m - 1)`` for ``m`` control points: a cubic (order 4) curve as in lpfg
    when ``m >= 4`` (exactly 4 points: one cubic Bezier), a quadratic Bezier for 3 points, the
    segment for 2, the point itself for 1. The knot vector is clamped and uniform, lpfg's
    ``Uk(j)``: ``p + 1`` zeros, ``1, 2, ..., m - p - 1``, then ``p + 1`` copies of ``m - p``, and
    the curve parameter ``t`` in [0, 1] is scaled onto it. Evaluation is de Boor's algorithm,
    vectorized over ``t``. The last knot span is closed on the right, and ``t = 1`` returns the
    last control point exactly (a half-open basis would return 0 there: docs/vlab_formats.md's end
    point trap); ``t = 0`` returns the first one.

    Parameters
    ----------
    control : (m, d) array_like of float
        Control points, multiplicities already expanded (repeated points).
    t : float or array_like of float, any shape
        Curve parameters; values outside [0, 1] are clamped.

    Returns
    -------
    (..., d) float64
        ``t.shape + (d,)`` points on the curve.
    """
    c = np.asarray(control, dtype=np.float64)
    if c.ndim != 2 or c.shape[0] < 1:
        raise ValueError(f"control points must be an (m, d) array with m >= 1, got shape {c.shape}")
    t = np.asarray(t, dtype=np.float64)
    shape = t.shape
    tt = np.clip(t.reshape(-1), 0.0, 1.0)
    m, d = c.shape
    if m == 1:
        return np.broadcast_to(c[0], shape + (d,)).copy()
    p = min(3, m - 1)
    spans = m - p
    knots = np.concatenate([np.zeros(p), np.arange(spans + 1, dtype=np.float64), np.full(p, float(spans))])
    u = tt * spans
    k = np.minimum(np.floor(u).astype(np.intp), spans - 1) + p  # knots[k] <= u <= knots[k + 1]
    pts = c[k[:, None] - p + np.arange(p + 1)[None, :]]  # (n, p + 1, d)
    for r in range(1, p + 1):
        for j in range(p, r - 1, -1):
            lo = knots[j + k - p]
            alpha = ((u - lo) / (knots[j + 1 + k - r] - lo))[:, None]
            pts[:, j] = (1.0 - alpha) * pts[:, j - 1] + alpha * pts[:, j]
    out = pts[:, p]
    out[tt == 0.0] = c[0]
    out[tt == 1.0] = c[-1]
    return out.reshape(shape + (d,))


# --------------------------------------------------------------------------------------------
# The function object


def _check_name(name) -> str:
    if not isinstance(name, str) or not name.strip() or "\n" in name or "\r" in name:
        raise ValueError(f"a name must be a non-empty single line of text, got {name!r}")
    return name.strip()


def _check_markers(markers) -> tuple[str, ...]:
    out = tuple(str(m).strip() for m in markers)
    if any(not m or "\n" in m or "\r" in m for m in out):
        raise ValueError("markers must be non-empty single lines")
    return out


def _as_multiplicities(multiplicities, n: int) -> np.ndarray:
    if multiplicities is None:
        mult = np.ones(n, dtype=np.int64)
    else:
        raw = np.asarray(multiplicities)
        if raw.shape != (n,):
            raise ValueError(f"multiplicities must have shape ({n},), got {raw.shape}")
        if raw.dtype.kind not in "iu" and not np.all(np.equal(np.mod(raw, 1), 0)):
            raise ValueError("multiplicities must be integers")
        mult = raw.astype(np.int64)
    if np.any(mult < 1):
        raise ValueError("multiplicities must be >= 1")
    return mult


@dataclass(frozen=True, eq=False)
class Function:
    """A graphically-defined function y = f(x), x in [0, 1] (a funcedit ``.func`` item).

    Attributes
    ----------
    name : str
        The ``name:`` line (one line of text, not empty).
    points : (n, 2) float64, read-only
        Control points ``(x, y)``, ``n >= 2``; ``x[0] == 0``, ``x[-1] == 1``, ``x`` non-decreasing.
    multiplicities : (n,) int64, read-only
        How many times each point is repeated before evaluation (>= 1; default all 1).
    samples : int
        The ``samples:`` value as stored (>= 0); evaluation uses :attr:`effective_samples`.
    flip : bool
        funcedit's ``flip:`` display flag. Display only: points are always stored as (x, y).
    background : str or None
        ``background:`` image file of the editor, if any.
    background_xy : (float, float) or None
        ``backgroundXY:`` offset of that image, if any.
    markers : tuple of str
        The lines after an (experimental) ``markers: N`` line, kept verbatim.

    Notes
    -----
    Instances are immutable (frozen, arrays read-only) so the sample table built on first use
    (:meth:`sampled`) never goes stale. Equality compares every field.
    """

    name: str
    points: np.ndarray
    multiplicities: np.ndarray | None = None
    samples: int = DEFAULT_SAMPLES
    flip: bool = False
    background: str | None = None
    background_xy: tuple[float, float] | None = None
    markers: tuple[str, ...] = ()

    def __post_init__(self):
        pts = np.array(self.points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 2:
            raise ValueError(f"points must be an (n, 2) array with n >= 2, got shape {pts.shape}")
        if not np.all(np.isfinite(pts)):
            raise ValueError("points must be finite")
        x = pts[:, 0]
        if x[0] != 0.0 or x[-1] != 1.0:
            raise ValueError(f"x must run from 0 to 1, got {x[0]!r} .. {x[-1]!r}")
        if np.any(np.diff(x) < 0.0):
            raise ValueError("x must not decrease")
        mult = _as_multiplicities(self.multiplicities, len(pts))
        samples = int(self.samples)
        if samples != self.samples or samples < 0:
            raise ValueError(f"samples must be an integer >= 0, got {self.samples!r}")
        bxy = None
        if self.background_xy is not None:
            bxy = tuple(float(v) for v in self.background_xy)
            if len(bxy) != 2 or not all(np.isfinite(bxy)):
                raise ValueError("background_xy must be two finite numbers")
        background = None
        if self.background is not None:
            background = _check_name(self.background)
        pts.setflags(write=False)
        mult.setflags(write=False)
        object.__setattr__(self, "name", _check_name(self.name))
        object.__setattr__(self, "points", pts)
        object.__setattr__(self, "multiplicities", mult)
        object.__setattr__(self, "samples", samples)
        object.__setattr__(self, "flip", bool(self.flip))
        object.__setattr__(self, "background", background)
        object.__setattr__(self, "background_xy", bxy)
        object.__setattr__(self, "markers", _check_markers(self.markers))

    # -- constructors -------------------------------------------------------------------------

    @classmethod
    def from_points(cls, points, multiplicities=None, *, name: str = "unnamed",
                    samples: int = DEFAULT_SAMPLES, flip: bool = False) -> Function:
        """A function with the given control points.

        Parameters
        ----------
        points : (n, 2) array_like of float
            ``(x, y)`` control points, ``x`` from 0 to 1, non-decreasing, ``n >= 2``.
        multiplicities : (n,) array_like of int, optional
            Repetition count per point (default 1).
        """
        return cls(name, points, multiplicities, samples=samples, flip=flip)

    @classmethod
    def constant(cls, value: float, *, name: str = "constant", samples: int = DEFAULT_SAMPLES) -> Function:
        """f(x) = ``value`` everywhere: funcedit's default four points, all at height ``value``."""
        v = float(value)
        return cls(name, [[0.0, v], [1.0 / 3.0, v], [2.0 / 3.0, v], [1.0, v]], samples=samples)

    # -- evaluation ---------------------------------------------------------------------------

    @property
    def effective_samples(self) -> int:
        """``samples`` clamped to ``MIN_SAMPLES..MAX_SAMPLES`` (10..1000), as lpfg does."""
        return min(max(self.samples, MIN_SAMPLES), MAX_SAMPLES)

    def control_points(self) -> np.ndarray:
        """(m, 2) float64: the points repeated by their multiplicities, m = multiplicities.sum()."""
        return np.repeat(self.points, self.multiplicities, axis=0)

    def curve(self, t) -> np.ndarray:
        """(..., 2) float64: points (X(t), Y(t)) of the B-spline at curve parameters ``t`` in [0, 1].

        See :func:`clamped_bspline` (cubic for 4 or more control points after repetition,
        quadratic for 3, linear for 2).
        """
        return clamped_bspline(self.control_points(), t)

    def sampled(self) -> tuple[np.ndarray, np.ndarray]:
        """The sample table lpfg builds, computed once and cached.

        For ``s = effective_samples`` abscissae ``x_i = i / (s - 1)`` the curve parameter ``t_i``
        with ``X(t_i) = x_i`` is found by bisection on [0, 1] (64 halvings, i.e. to double
        precision; lpfg stops at an error of 0.01 / samples), keeping the largest ``t`` with
        ``X(t) <= x_i``; ``t_0 = 0`` and ``t_{s-1} = 1`` exactly, so ``f(0)`` and ``f(1)`` are
        the first and last control points' ``y``. ``X(t)`` is non-decreasing because the control
        ``x`` are.

        Returns
        -------
        xs : (s,) float64, read-only
            ``i / (s - 1)``.
        ys : (s,) float64, read-only
            ``Y(t_i)``.
        """
        table = self.__dict__.get("_table")
        if table is None:
            s = self.effective_samples
            xs = np.arange(s, dtype=np.float64) / (s - 1)
            ctrl = self.control_points()
            lo = np.zeros(s)
            hi = np.ones(s)
            for _ in range(_BISECTION_STEPS):
                mid = 0.5 * (lo + hi)
                above = clamped_bspline(ctrl[:, :1], mid)[:, 0] > xs
                hi = np.where(above, mid, hi)
                lo = np.where(above, lo, mid)
            t = 0.5 * (lo + hi)
            t[0], t[-1] = 0.0, 1.0
            ys = clamped_bspline(ctrl[:, 1:], t)[:, 0]
            xs.setflags(write=False)
            ys.setflags(write=False)
            table = (xs, ys)
            object.__setattr__(self, "_table", table)
        return table

    def evaluate(self, x):
        """f(x), as lpfg's ``func(id, x)``: ``x`` clamped to [0, 1], linear between samples.

        Parameters
        ----------
        x : float or array_like of float (finite)

        Returns
        -------
        float for a scalar ``x``, else a float64 array of ``x``'s shape.
        """
        _, ys = self.sampled()
        xa = np.asarray(x, dtype=np.float64)
        if not np.all(np.isfinite(xa)):
            raise ValueError("x must be finite")
        s = len(ys)
        index = np.clip(xa, 0.0, 1.0) * (s - 1)
        i = np.minimum(np.floor(index).astype(np.intp), s - 2)
        w = index - i
        out = (1.0 - w) * ys[i] + w * ys[i + 1]
        if out.ndim == 0:
            return float(out)
        return out

    __call__ = evaluate

    # -- comparison ---------------------------------------------------------------------------

    def __eq__(self, other):
        if not isinstance(other, Function):
            return NotImplemented
        return (
            self.name == other.name
            and np.array_equal(self.points, other.points)
            and np.array_equal(self.multiplicities, other.multiplicities)
            and self.samples == other.samples
            and self.flip == other.flip
            and self.background == other.background
            and self.background_xy == other.background_xy
            and self.markers == other.markers
        )

    __hash__ = object.__hash__


def _parse_flag_value(cur: _Cursor, line: int, value: str, key: str) -> bool:
    flag = _FLIP.get(value.lower())
    if flag is None:
        raise cur.error(line, f"'on' or 'off' after '{key}:'", shorten(value))
    return flag


def _parse_background(cur: _Cursor):
    """Optional ``background: FILE`` and ``backgroundXY: x y`` lines (funcedit, cuspy)."""
    background = background_xy = None
    if cur.at_key("background"):
        line, background = cur.field("background")
        if not background:
            raise cur.error(line, "an image file name after 'background:'", "nothing")
    if cur.at_key("backgroundXY"):
        line, value = cur.field("backgroundXY")
        tokens = value.split()
        if len(tokens) != 2:
            raise cur.error(line, "2 numbers after 'backgroundXY:'", str(len(tokens)))
        background_xy = tuple(parse_float(t, cur.path, line, "a number after 'backgroundXY:'") for t in tokens)
    return background, background_xy


def _parse_markers(cur: _Cursor) -> tuple[str, ...]:
    """Optional ``markers: N`` line followed by N marker lines, kept verbatim."""
    if not cur.at_key("markers"):
        return ()
    line, value = cur.field("markers")
    n = parse_int(value, cur.path, line, "an integer after 'markers:'")
    if n < 0:
        raise cur.error(line, "a marker count >= 0", shorten(value))
    return tuple(cur.take(f"marker line {i + 1} of {n}")[1] for i in range(n))


def _parse_name(cur: _Cursor, what: str) -> str:
    line, name = cur.field("name", "'name: NAME'")
    if not name:
        raise cur.error(line, f"a {what} name after 'name:'", "nothing")
    return name


# --------------------------------------------------------------------------------------------
# Reading


def _parse_func_rows(cur: _Cursor) -> tuple[np.ndarray, np.ndarray]:
    """``points: N`` and N rows ``x y [multiplicity]``, checked for x = 0 .. 1, non-decreasing."""
    path = cur.path
    line, value = cur.field("points", "'points: N'")
    n = parse_int(value, path, line, "an integer after 'points:'")
    if n < 2:
        raise cur.error(line, "at least 2 points", shorten(value))
    pts = np.empty((n, 2), dtype=np.float64)
    mult = np.ones(n, dtype=np.int64)
    for i in range(n):
        row_line, text = cur.take(f"point {i + 1} of {n} ('x y' or 'x y multiplicity')")
        tokens = text.split()
        if len(tokens) not in (2, 3):
            raise cur.error(row_line, f"point {i + 1} of {n} ('x y' or 'x y multiplicity')", shorten(text))
        x = parse_float(tokens[0], path, row_line, "a number (x)")
        y = parse_float(tokens[1], path, row_line, "a number (y)")
        if len(tokens) == 3:
            m = parse_int(tokens[2], path, row_line, "an integer multiplicity")
            if m < 1:
                raise cur.error(row_line, "a multiplicity >= 1", shorten(tokens[2]))
            mult[i] = m
        if i == 0 and x != 0.0:
            raise cur.error(row_line, "x = 0 on the first point", shorten(tokens[0]))
        if i > 0 and x < pts[i - 1, 0]:
            raise cur.error(row_line, f"x >= {pts[i - 1, 0]:g} (x must not decrease)", shorten(tokens[0]))
        if i == n - 1 and x != 1.0:
            raise cur.error(row_line, "x = 1 on the last point", shorten(tokens[0]))
        pts[i] = x, y
    return pts, mult


def _parse_func(cur: _Cursor, default_name: str | None) -> Function:
    """One function block; ``default_name`` is None inside a gallery (no version 1.0 there)."""
    path = cur.path
    first = "'fver 1 1'" if default_name is None else "'fver 1 1' (or a version 1.0 'range: 0 1' line)"
    line, text = cur.take(first)
    if default_name is not None and cur.key_of(text) == "range":
        tokens = text.partition(":")[2].split()
        if len(tokens) != 2:
            raise cur.error(line, "2 numbers after 'range:'", str(len(tokens)))
        lo, hi = (parse_float(t, path, line, "a number after 'range:'") for t in tokens)
        if (lo, hi) != (0.0, 1.0):
            raise cur.error(line, "'range: 0 1' (lpfg's functions are defined on [0, 1])", shorten(text))
        pts, mult = _parse_func_rows(cur)
        return Function(default_name, pts, mult, samples=DEFAULT_SAMPLES)
    if text.split() != ["fver", "1", "1"]:
        raise cur.error(line, first, shorten(text))
    name = _parse_name(cur, "function")
    line, value = cur.field("samples", "'samples: N'")
    samples = parse_int(value, path, line, "an integer after 'samples:'")
    if samples < 0:
        raise cur.error(line, "a sample count >= 0", shorten(value))
    background, background_xy = _parse_background(cur)
    markers = _parse_markers(cur)
    line, value = cur.field("flip", "'flip: on' or 'flip: off'")
    flip = _parse_flag_value(cur, line, value, "flip")
    pts, mult = _parse_func_rows(cur)
    return Function(name, pts, mult, samples=samples, flip=flip, background=background,
                    background_xy=background_xy, markers=markers)


def read_func(path) -> Function:
    """Read a function file (``fver 1 1``, or version 1.0 starting with ``range: 0 1``).

    A version 1.0 file has no name and no sample count: the name is the file's stem and
    ``samples`` is :data:`DEFAULT_SAMPLES`. Raises :class:`FormatError` (file, line, expected,
    found) for malformed input; see ``formats/func.md`` for what is rejected.
    """
    cur = _Cursor(path, read_lines(path))
    fn = _parse_func(cur, Path(os.fspath(path)).stem or "unnamed")
    cur.end(f"end of file after the {len(fn.points)} points")
    return fn


def read_fset(path) -> list[Function]:
    """Read a function gallery: ``funcgalleryver 1 1``, ``items: N``, then N ``fver 1 1`` blocks."""
    return read_gallery(path, "funcgalleryver 1 1", lambda cur: _parse_func(cur, None))


# --------------------------------------------------------------------------------------------
# Writing


def format_func(fn: Function) -> str:
    """The ``fver 1 1`` text of ``fn`` (numbers ``%.6f``; multiplicity written only when > 1)."""
    out = ["fver 1 1", f"name: {fn.name}", f"samples: {fn.samples}"]
    if fn.background is not None:
        out.append(f"background: {fn.background}")
    if fn.background_xy is not None:
        out.append(f"backgroundXY: {_fmt(fn.background_xy[0])} {_fmt(fn.background_xy[1])}")
    if fn.markers:
        out.append(f"markers: {len(fn.markers)}")
        out.extend(fn.markers)
    out.append(f"flip: {'on' if fn.flip else 'off'}")
    out.append(f"points: {len(fn.points)}")
    for (x, y), m in zip(fn.points, fn.multiplicities):
        out.append(f"{_fmt(x)} {_fmt(y)}" + (f" {m}" if m != 1 else ""))
    return "\n".join(out) + "\n"


def format_fset(functions) -> str:
    """The ``funcgalleryver 1 1`` text of a list of functions."""
    functions = list(functions)
    return f"funcgalleryver 1 1\nitems: {len(functions)}\n" + "".join(format_func(f) for f in functions)


def write_func(path, fn: Function) -> None:
    """Write ``fn`` as a ``fver 1 1`` function file, atomically."""
    write_text_atomic(path, format_func(fn))


def write_fset(path, functions) -> None:
    """Write a function gallery (``.fset``), atomically."""
    write_text_atomic(path, format_fset(functions))
