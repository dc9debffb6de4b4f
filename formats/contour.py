"""Contours: VLab ``.con`` files and ``.cset`` galleries (cuspy, lpfg).

A contour is a planar (or 3-D) cubic B-spline curve given by control points with multiplicities.
inflo uses contours for the generating curves C of receptacles and meristems (thesis sec. 5.2,
fig. 5.1, eq. 5.1-5.2; interpolated between key shapes in sec. 5.3), for the generating curves
of envelopes (Runions sec. 3.2.1) and for generalized-cylinder cross sections. Spec:
``formats/contour.md``.

Evaluation follows lpfg (docs/vlab_formats.md): ``type: or``/``cr`` ("regular") are uniform cubic
B-splines, a closed one periodic (the last 3 control points repeated at the front); ``type: oe``
/``ce`` ("end-point") are clamped cubic B-splines that interpolate their end points, a closed one
with its first control point repeated at the end. :meth:`Contour.point_at` re-parametrizes by
arc length, as lpfg does before it samples a contour.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from inflo.tools.common import linalg as la

from ._vlab import _Cursor, _fmt, read_gallery
from .atomic import write_text_atomic
from .errors import parse_float, parse_int, read_lines, shorten
from .func import (  # shared B-spline evaluator and editor-line parsers of the VLab text readers
    _check_markers,
    _check_name,
    _parse_background,
    _parse_markers,
    _parse_name,
    clamped_bspline,
)

__all__ = [
    "Contour",
    "read_con",
    "write_con",
    "read_cset",
    "write_cset",
    "format_con",
    "format_cset",
    "uniform_bspline",
    "CONTOUR_TYPES",
    "DEFAULT_SAMPLES",
    "MIN_CONTROL_POINTS",
]

DEFAULT_SAMPLES = 8
"""``samples:`` (sides of a generalized cylinder) of files older than ``cver 1 3``."""
MIN_CONTROL_POINTS = 4
"""lpfg refuses a contour with fewer control points, multiplicities counted."""

CONTOUR_TYPES = {
    "or": (False, False),
    "cr": (True, False),
    "oe": (False, True),
    "ce": (True, True),
    "open": (False, False),
    "closed": (True, False),
}
"""``type:`` value -> (closed, end_point). ``open``/``closed`` are the ``cver 1 1`` spellings."""

_ARC_STEPS_PER_SPAN = 128
_ARC_STEPS_MIN = 2048


def uniform_bspline(control, t) -> np.ndarray:
    """Points of the uniform (unclamped) cubic B-spline over ``control`` at parameters ``t``.

    Span ``i`` (of ``m - 3``) blends control points ``i .. i + 3`` with the uniform cubic basis
    ``((1-w)^3, 3w^3 - 6w^2 + 4, -3w^3 + 3w^2 + 3w + 1, w^3) / 6``; ``t`` in [0, 1] is scaled onto
    the ``m - 3`` spans. The curve starts at ``(c0 + 4 c1 + c2) / 6`` and ends at
    ``(c[m-3] + 4 c[m-2] + c[m-1]) / 6``: it passes through an end point only when that point
    is repeated 3 times.

    Parameters
    ----------
    control : (m, d) array_like of float, m >= 4
    t : float or array_like of float, any shape; clamped to [0, 1]

    Returns
    -------
    (..., d) float64
    """
    c = np.asarray(control, dtype=np.float64)
    if c.ndim != 2 or c.shape[0] < 4:
        raise ValueError(f"control points must be an (m, d) array with m >= 4, got shape {c.shape}")
    t = np.asarray(t, dtype=np.float64)
    shape = t.shape
    spans = c.shape[0] - 3
    u = np.clip(t.reshape(-1), 0.0, 1.0) * spans
    i = np.minimum(np.floor(u).astype(np.intp), spans - 1)
    w = u - i
    w2 = w * w
    w3 = w2 * w
    basis = np.stack([(1.0 - w) ** 3, 3.0 * w3 - 6.0 * w2 + 4.0, -3.0 * w3 + 3.0 * w2 + 3.0 * w + 1.0, w3], axis=1) / 6.0
    idx = i[:, None] + np.arange(4)[None, :]
    pts = c[idx]
    out = basis[:, 0, None] * pts[:, 0]
    for j in range(1, 4):  # sum the four weighted control points in the order j = 0, 1, 2, 3
        out = out + basis[:, j, None] * pts[:, j]
    return out.reshape(shape + (c.shape[1],))


@dataclass(frozen=True, eq=False)
class Contour:
    """A contour (a cuspy ``.con`` item).

    Attributes
    ----------
    name : str
        The ``name:`` line (one line of text, not empty).
    points : (n, 3) float64, read-only
        Distinct control points ``x y z`` (z is usually 0). An (n, 2) input gets z = 0.
    multiplicities : (n,) int64, read-only
        Repetition count per point (>= 1; default 1); the total must be >= 4.
    closed : bool
        Closed curve (``c?`` types) or open (``o?``).
    end_point : bool
        ``?e`` types: clamped, end-point interpolating B-spline; else ``?r`` "regular" uniform.
    samples : int
        ``samples:`` (>= 0): number of sides of a generalized cylinder built on the contour; 0
        means unspecified (lpfg then uses its own default).
    background, background_xy, markers
        cuspy's editor data (``background:``, ``backgroundXY:``, ``markers:``), kept as read.

    Notes
    -----
    Immutable, so the arc-length table built on first use never goes stale. Equality compares
    every field.
    """

    name: str
    points: np.ndarray
    multiplicities: np.ndarray | None = None
    closed: bool = False
    end_point: bool = False
    samples: int = DEFAULT_SAMPLES
    background: str | None = None
    background_xy: tuple[float, float] | None = None
    markers: tuple[str, ...] = ()

    def __post_init__(self):
        pts = np.array(self.points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] not in (2, 3) or pts.shape[0] < 1:
            raise ValueError(f"points must be an (n, 3) or (n, 2) array with n >= 1, got shape {pts.shape}")
        if pts.shape[1] == 2:
            pts = np.column_stack([pts, np.zeros(len(pts))])
        if not np.all(np.isfinite(pts)):
            raise ValueError("points must be finite")
        if self.multiplicities is None:
            mult = np.ones(len(pts), dtype=np.int64)
        else:
            raw = np.asarray(self.multiplicities)
            if raw.shape != (len(pts),):
                raise ValueError(f"multiplicities must have shape ({len(pts)},), got {raw.shape}")
            if raw.dtype.kind not in "iu" and not np.all(np.equal(np.mod(raw, 1), 0)):
                raise ValueError("multiplicities must be integers")
            mult = raw.astype(np.int64)
        if np.any(mult < 1):
            raise ValueError("multiplicities must be >= 1")
        if int(mult.sum()) < MIN_CONTROL_POINTS:
            raise ValueError(f"a contour needs at least {MIN_CONTROL_POINTS} control points "
                             f"(multiplicities counted), got {int(mult.sum())}")
        samples = int(self.samples)
        if samples != self.samples or samples < 0:
            raise ValueError(f"samples must be an integer >= 0, got {self.samples!r}")
        bxy = None
        if self.background_xy is not None:
            bxy = tuple(float(v) for v in self.background_xy)
            if len(bxy) != 2 or not all(np.isfinite(bxy)):
                raise ValueError("background_xy must be two finite numbers")
        pts.setflags(write=False)
        mult.setflags(write=False)
        object.__setattr__(self, "name", _check_name(self.name))
        object.__setattr__(self, "points", pts)
        object.__setattr__(self, "multiplicities", mult)
        object.__setattr__(self, "closed", bool(self.closed))
        object.__setattr__(self, "end_point", bool(self.end_point))
        object.__setattr__(self, "samples", samples)
        object.__setattr__(self, "background", None if self.background is None else _check_name(self.background))
        object.__setattr__(self, "background_xy", bxy)
        object.__setattr__(self, "markers", _check_markers(self.markers))

    @classmethod
    def from_points(cls, points, multiplicities=None, *, type: str = "or", name: str = "unnamed",
                    samples: int = DEFAULT_SAMPLES) -> Contour:
        """A contour of the given ``type`` (``or``, ``cr``, ``oe``, ``ce``, ``open``, ``closed``).

        Parameters
        ----------
        points : (n, 3) or (n, 2) array_like of float
        multiplicities : (n,) array_like of int, optional
        """
        if type not in CONTOUR_TYPES:
            raise ValueError(f"type must be one of {sorted(CONTOUR_TYPES)}, got {type!r}")
        closed, end_point = CONTOUR_TYPES[type]
        return cls(name, points, multiplicities, closed=closed, end_point=end_point, samples=samples)

    @property
    def type(self) -> str:
        """The ``cver 1 3`` type code: ``or``, ``cr``, ``oe`` or ``ce``."""
        return ("c" if self.closed else "o") + ("e" if self.end_point else "r")

    def control_points(self) -> np.ndarray:
        """(m, 3) float64: the control polygon lpfg evaluates.

        Points repeated by multiplicity; then, for ``cr``, the last 3 repeated at the front
        (periodic uniform spline); for ``ce``, the first repeated at the end.
        """
        c = np.repeat(self.points, self.multiplicities, axis=0)
        if self.closed and not self.end_point:
            c = np.concatenate([c[-3:], c])
        elif self.closed:
            c = np.concatenate([c, c[:1]])
        return c

    def evaluate(self, t) -> np.ndarray:
        """(..., 3) float64: points at spline parameters ``t`` in [0, 1] (not arc length).

        ``or``/``cr``: :func:`uniform_bspline` (a closed one returns at ``t = 1`` exactly to its
        ``t = 0`` point); ``oe``/``ce``: :func:`clamped_bspline` (``t = 0`` and ``t = 1`` give the
        first and last control points exactly).
        """
        t = np.asarray(t, dtype=np.float64)
        if self.end_point:
            return clamped_bspline(self.control_points(), t)
        ctrl = self.control_points()
        flat = uniform_bspline(ctrl, t.reshape(-1))
        if self.closed:
            flat[t.reshape(-1) >= 1.0] = uniform_bspline(ctrl, 0.0)
        return flat.reshape(t.shape + (3,))

    def _arc_table(self) -> tuple[np.ndarray, np.ndarray]:
        table = self.__dict__.get("_arc")
        if table is None:
            m = len(self.control_points())
            n = max(_ARC_STEPS_MIN, _ARC_STEPS_PER_SPAN * m) + 1
            t = np.linspace(0.0, 1.0, n)
            p = self.evaluate(t)
            cum = np.concatenate([[0.0], np.cumsum(la.norm(np.diff(p, axis=0), axis=1))])
            table = (t, cum)
            object.__setattr__(self, "_arc", table)
        return table

    @property
    def length(self) -> float:
        """Arc length of the curve (of the whole loop for a closed one)."""
        return float(self._arc_table()[1][-1])

    def point_at(self, s) -> np.ndarray:
        """(..., 3) float64: points at arc-length fractions ``s`` in [0, 1] (clamped).

        The arc length is measured on a polyline of at least 2048 (128 per span) curve points;
        ``t(s)`` is interpolated from it and the point evaluated on the curve itself, so points
        lie exactly on the spline and their spacing is uniform to about 1e-5 of the length.
        ``s = 0`` and ``s = 1`` are the curve's ends (the same point for a closed contour).
        """
        s = np.clip(np.asarray(s, dtype=np.float64), 0.0, 1.0)
        t_grid, cum = self._arc_table()
        if cum[-1] <= 0.0:
            return self.evaluate(s)
        return self.evaluate(np.interp(s * cum[-1], cum, t_grid))

    def sample(self, n: int) -> np.ndarray:
        """(n, 3) float64: ``n`` points equally spaced in arc length.

        Open: ``s = i / (n - 1)``, both ends included (n >= 2). Closed: ``s = i / n``, the start
        point not repeated (n >= 3), e.g. the ``samples`` sides of a generalized cylinder.
        """
        n = int(n)
        if self.closed:
            if n < 3:
                raise ValueError("a closed contour needs n >= 3 samples")
            return self.point_at(np.arange(n) / n)
        if n < 2:
            raise ValueError("an open contour needs n >= 2 samples")
        return self.point_at(np.linspace(0.0, 1.0, n))

    def __eq__(self, other):
        if not isinstance(other, Contour):
            return NotImplemented
        return (
            self.name == other.name
            and np.array_equal(self.points, other.points)
            and np.array_equal(self.multiplicities, other.multiplicities)
            and self.closed == other.closed
            and self.end_point == other.end_point
            and self.samples == other.samples
            and self.background == other.background
            and self.background_xy == other.background_xy
            and self.markers == other.markers
        )

    __hash__ = object.__hash__


# --------------------------------------------------------------------------------------------
# Reading

_TYPE_EXPECTED = "type 'or', 'cr', 'oe' or 'ce' (or 'open', 'closed')"


def _parse_rows_xyzm(cur: _Cursor, n: int, with_multiplicity: bool = True):
    what = "'x y z multiplicity'" if with_multiplicity else "'x y z'"
    pts = np.empty((n, 3), dtype=np.float64)
    mult = np.ones(n, dtype=np.int64)
    for i in range(n):
        line, text = cur.take(f"point {i + 1} of {n} ({what})")
        tokens = text.split()
        if len(tokens) != (4 if with_multiplicity else 3):
            raise cur.error(line, f"point {i + 1} of {n} ({what})", shorten(text))
        pts[i] = [parse_float(tok, cur.path, line, "a number (coordinate)") for tok in tokens[:3]]
        if with_multiplicity:
            m = parse_int(tokens[3], cur.path, line, "an integer multiplicity")
            if m < 1:
                raise cur.error(line, "a multiplicity >= 1", shorten(tokens[3]))
            mult[i] = m
    return pts, mult


def _check_total(cur: _Cursor, line: int, total: int, found: str) -> None:
    if total < MIN_CONTROL_POINTS:
        raise cur.error(line, f"at least {MIN_CONTROL_POINTS} control points, multiplicities counted", found)


def _parse_cver(cur: _Cursor, line: int, text: str) -> Contour:
    path = cur.path
    tokens = text.split()
    if len(tokens) != 3 or tokens[1] != "1" or tokens[2] not in ("1", "2", "3"):
        raise cur.error(line, "'cver 1 1', 'cver 1 2' or 'cver 1 3'", shorten(text))
    minor = int(tokens[2])
    name = _parse_name(cur, "contour")
    points_line, value = cur.field("points", "'points: N1 N2'")
    counts = value.split()
    if len(counts) != 2:
        raise cur.error(points_line, "2 integers after 'points:' (points, total with multiplicities)", shorten(value))
    n1 = parse_int(counts[0], path, points_line, "an integer point count")
    n2 = parse_int(counts[1], path, points_line, "an integer total count")
    if n1 < 1:
        raise cur.error(points_line, "at least 1 point", shorten(counts[0]))
    _check_total(cur, points_line, n2, shorten(counts[1]))
    type_line, value = cur.field("type", f"'type: ...' ({_TYPE_EXPECTED})")
    if value not in CONTOUR_TYPES:
        raise cur.error(type_line, _TYPE_EXPECTED, shorten(value))
    closed, end_point = CONTOUR_TYPES[value]
    samples = DEFAULT_SAMPLES
    if minor >= 3:
        samples_line, value = cur.field("samples", "'samples: N'")
        samples = parse_int(value, path, samples_line, "an integer after 'samples:'")
        if samples < 0:
            raise cur.error(samples_line, "a sample count >= 0", shorten(value))
    background, background_xy = _parse_background(cur)
    markers = _parse_markers(cur)
    pts, mult = _parse_rows_xyzm(cur, n1)
    if int(mult.sum()) != n2:
        raise cur.error(points_line, f"total {int(mult.sum())} (the sum of the multiplicities) after 'points: {n1}'",
                        shorten(counts[1]))
    return Contour(name, pts, mult, closed=closed, end_point=end_point, samples=samples,
                   background=background, background_xy=background_xy, markers=markers)


def _parse_v14(cur: _Cursor, default_name: str) -> Contour:
    """``version: 1.4``: contact/end/heading/up/size (checked, not kept), points, range, dimension."""
    path = cur.path
    for key in ("contact", "end", "heading", "up"):
        line, value = cur.field(key, f"'{key}: x y z'")
        tokens = value.split()
        if len(tokens) != 3:
            raise cur.error(line, f"3 numbers after '{key}:'", str(len(tokens)))
        for tok in tokens:
            parse_float(tok, path, line, f"a number after '{key}:'")
    line, text = cur.take("'size: S'")
    tokens = text.replace(":", " ").split()
    if len(tokens) != 2 or tokens[0] != "size":
        raise cur.error(line, "'size: S'", shorten(text))
    parse_float(tokens[1], path, line, "a number after 'size'")
    points_line, value = cur.field("points", "'points: N'")
    n = parse_int(value, path, points_line, "an integer after 'points:'")
    if n < 1:
        raise cur.error(points_line, "at least 1 point", shorten(value))
    line, value = cur.field("range", "'range: a b'")
    tokens = value.split()
    if len(tokens) != 2:
        raise cur.error(line, "2 numbers after 'range:'", str(len(tokens)))
    for tok in tokens:
        parse_float(tok, path, line, "a number after 'range:'")
    line, value = cur.field("dimension", "'dimension: 3' or 'dimension: 4'")
    if value not in ("3", "4"):
        raise cur.error(line, "'dimension: 3' or 'dimension: 4'", shorten(value))
    with_multiplicity = value == "4"
    line, value = cur.field("type", "'type: bspline'")
    if value != "bspline":
        raise cur.error(line, "'type: bspline'", shorten(value))
    pts, mult = _parse_rows_xyzm(cur, n, with_multiplicity)
    _check_total(cur, points_line, int(mult.sum()), str(int(mult.sum())))
    return Contour(default_name, pts, mult)


def _parse_v10(cur: _Cursor, line: int, text: str, default_name: str) -> Contour:
    """Version 1.0: ``N DIM open|closed`` then N rows of DIM numbers, repeats written out."""
    path = cur.path
    tokens = text.split()
    n = parse_int(tokens[0], path, line, "a point count")
    dim = parse_int(tokens[1], path, line, "a dimension (2 or 3)")
    if dim not in (2, 3):
        raise cur.error(line, "a dimension 2 or 3", shorten(tokens[1]))
    if tokens[2] not in ("open", "closed"):
        raise cur.error(line, "'open' or 'closed'", shorten(tokens[2]))
    _check_total(cur, line, n, shorten(tokens[0]))
    rows = []
    for i in range(n):
        row_line, row = cur.take(f"point {i + 1} of {n} ({dim} numbers)")
        vals = row.split()
        if len(vals) != dim:
            raise cur.error(row_line, f"point {i + 1} of {n} ({dim} numbers)", shorten(row))
        rows.append([parse_float(v, path, row_line, "a number (coordinate)") for v in vals] + [0.0] * (3 - dim))
    pts, mult = [], []
    for r in rows:  # consecutive repeats become a multiplicity, as cuspy reads them
        if pts and r == pts[-1]:
            mult[-1] += 1
        else:
            pts.append(r)
            mult.append(1)
    return Contour(default_name, pts, mult, closed=tokens[2] == "closed")


_FIRST = "'cver 1 N' (or an old 'version: 1.4' or 'N DIM open|closed' header)"


def _parse_contour(cur: _Cursor, default_name: str | None) -> Contour:
    """One contour; ``default_name`` is None inside a gallery (only ``cver`` blocks there)."""
    line, text = cur.take("'cver 1 N'" if default_name is None else _FIRST)
    tokens = text.split()
    if tokens and tokens[0] == "cver":
        return _parse_cver(cur, line, text)
    if default_name is not None:
        if cur.key_of(text) == "version":
            if text.partition(":")[2].strip() != "1.4":
                raise cur.error(line, "'version: 1.4'", shorten(text))
            return _parse_v14(cur, default_name)
        if len(tokens) == 3 and tokens[0].lstrip("+-").isdigit():
            return _parse_v10(cur, line, text, default_name)
    raise cur.error(line, "'cver 1 N'" if default_name is None else _FIRST, shorten(text))


def read_con(path) -> Contour:
    """Read a contour file: ``cver 1 1|2|3``, or the older ``version: 1.4`` and version 1.0 forms.

    Old forms have no name (the file's stem is used) and no ``samples`` (8). Raises
    :class:`FormatError` for malformed input; see ``formats/contour.md``.
    """
    cur = _Cursor(path, read_lines(path))
    contour = _parse_contour(cur, Path(os.fspath(path)).stem or "unnamed")
    cur.end(f"end of file after the {len(contour.points)} points")
    return contour


def read_cset(path) -> list[Contour]:
    """Read a contour gallery: ``contourgalleryver 1 1``, ``items: N``, then N ``cver`` blocks."""
    return read_gallery(path, "contourgalleryver 1 1", lambda cur: _parse_contour(cur, None))


# --------------------------------------------------------------------------------------------
# Writing


def format_con(contour: Contour) -> str:
    """The ``cver 1 3`` text of ``contour`` (coordinates ``%.6f``)."""
    out = [
        "cver 1 3",
        f"name: {contour.name}",
        f"points: {len(contour.points)} {int(contour.multiplicities.sum())}",
        f"type: {contour.type}",
        f"samples: {contour.samples}",
    ]
    if contour.background is not None:
        out.append(f"background: {contour.background}")
    if contour.background_xy is not None:
        out.append(f"backgroundXY: {_fmt(contour.background_xy[0])} {_fmt(contour.background_xy[1])}")
    if contour.markers:
        out.append(f"markers: {len(contour.markers)}")
        out.extend(contour.markers)
    for (x, y, z), m in zip(contour.points, contour.multiplicities):
        out.append(f"{_fmt(x)} {_fmt(y)} {_fmt(z)} {m}")
    return "\n".join(out) + "\n"


def format_cset(contours) -> str:
    """The ``contourgalleryver 1 1`` text of a list of contours."""
    contours = list(contours)
    return f"contourgalleryver 1 1\nitems: {len(contours)}\n" + "".join(format_con(c) for c in contours)


def write_con(path, contour: Contour) -> None:
    """Write ``contour`` as a ``cver 1 3`` file, atomically."""
    write_text_atomic(path, format_con(contour))


def write_cset(path, contours) -> None:
    """Write a contour gallery (``.cset``), atomically."""
    write_text_atomic(path, format_cset(contours))
