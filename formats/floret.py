"""Floret key-pose file ``.floret``: reader, writer, compatibility check, symmetry expansion.

A floret (thesis ch. 2) is one or more organs (whorls: lily sepals and petals, a disk floret's
corolla and stamen tube). Each organ is the clamped B-spline control mesh of ONE petal in the
floret's local frame (+Y the floret axis ``up``, +X ``right``), replicated by n-fold radial
symmetry, optionally given as half a petal and mirrored (bilateral symmetry), with the first k
control points of each lateral boundary fused to the neighbours (thesis 2.2). ``floret-animate``
reads two or more key poses and writes one ``.floret`` per frame; ``polygonize`` reads those frames.
The spec page is ``formats/floret.md``.

The geometric meaning of the symmetry fields is implemented once, here, in :func:`full_petal` and
:func:`petals`, so the tools and the spec cannot drift apart.
"""
from __future__ import annotations

import math
import os
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from inflo.tools.common import linalg as la

from .atomic import write_text_atomic
from .errors import FormatError, InputError, did_you_mean, parse_float, parse_int, read_lines, shorten

__all__ = [
    "FORMAT_VERSION",
    "MAX_DEGREE",
    "Floret",
    "Organ",
    "check_compatible",
    "format_floret",
    "full_petal",
    "petal_angles_deg",
    "petals",
    "read_floret",
    "write_floret",
]

FORMAT_VERSION = 1
MAX_DEGREE = 5
#: the largest tilt of a petal (degrees): a turn either way; 1e308 would be a finite garbage angle
MAX_TILT = 360
#: the most petals of one organ (symmetry n): polygonize replicates the petal n times
MAX_SYMMETRY = 10_000
#: the largest material id: the 256 material definitions of the material map (SCN ``mtl:``)
MAX_MATERIAL = 255
MAX_COORDINATE = 1e12
"""Largest control-point coordinate accepted: interpolating and meshing squares coordinates, so
1e300 overflowed (exit 1) instead of being refused."""

_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.+-]*$")
_NUMBER = re.compile(r"^[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?$")
_NAME_RULE = "a name of letters, digits, '_', '.', '+', '-'"
_TRUE = {"on", "true", "yes", "1"}
_FALSE = {"off", "false", "no", "0"}



# --------------------------------------------------------------------------------------------------
# Data model
# --------------------------------------------------------------------------------------------------


def _sampling_problem(name: str, value) -> tuple[str, str] | None:
    """(expected, found) when a ``lambda``/``eta`` value is invalid, else None."""
    if value is None:
        return None
    if isinstance(value, Path):
        if not value.name.lower().endswith(".func"):
            return ("a .func file", shorten(str(value)))
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return (f"a number or a .func path for {name}", shorten(repr(value)))
    v = float(value)
    if name == "lambda" and not (math.isfinite(v) and v > 0.0):
        return ("lambda > 0 (or a .func file)", repr(v))
    if name == "eta" and not (math.isfinite(v) and v >= 1.0):
        return ("eta >= 1 (or a .func file)", repr(v))
    return None


class _InvalidOrgan(ValueError):
    """Raised by Organ() for a broken invariant; ``.problem`` is (file key, expected, found)."""

    def __init__(self, name, problem):
        self.problem = problem
        key, expected, found = problem
        super().__init__(f"organ {name!r}, {key}: expected {expected}, found {found}")


@dataclass(frozen=True, eq=False)
class Organ:
    """One organ (whorl) of a floret: the control mesh of one petal and how it is replicated.

    Parameters
    ----------
    name : str
        Organ name, unique in the floret: letters, digits, ``_ . + -``, not starting with
        ``. + -`` (it becomes an OBJ group name).
    degree_u, degree_v : int
        B-spline degree across the petal (u) and from base to tip (v), each in 1..5, smaller than
        the number of control points in that direction (for a bilateral organ, of the mirrored
        full petal: ``2 * nu - 1``). Knots are clamped and uniform.
    control_points : (nv, nu, 3) float64 array
        ``control_points[j, i]`` is the point in row j (v, j = 0 at the petal base, nv - 1 at the
        tip) and column i (u across the petal, from its -Z side to its +Z side), as x, y, z in the
        floret's local frame, for the petal at angle 0 (midline pointing to +X, midplane z = 0),
        before tilt. For a bilateral organ only the +Z half: column 0 is the midline (its z is taken
        as 0), column nu - 1 the lateral boundary. Stored as a read-only copy.
    symmetry_n : int
        n-fold radial symmetry: copies at angles ``phase + k * 360 / n`` about +Y, n >= 1.
    symmetry_phase_deg : float
        Angle of copy 0 about +Y, degrees (right-handed: +X turns toward -Z).
    bilateral : bool
        The control points are half a petal, mirrored across the petal's midplane z = 0.
    fused : int
        k, 0 <= k <= nv: the first k control points (rows 0..k-1) of each lateral boundary
        column lie on the symmetry plane between adjacent petals. k > 0 needs ``bilateral`` and
        ``symmetry_n >= 2`` (the thesis implements fusion for dihedral symmetry).
    tilt_deg : float
        Rotation of the petal about the axis parallel to +Z through its base (see
        :func:`full_petal`), degrees; positive leans the petal outward (+Y toward +X).
    material : int
        Material / colour id (>= 0), as SCN ``mtl:`` ids; ``polygonize`` writes it to the OBJ.
    lambda_ : float or pathlib.Path or None
        Row spacing function lambda(v) for ``polygonize`` (thesis eq. 2.1): a constant > 0 or an
        absolute path to a ``.func`` file. None: the polygonize default.
    eta : float or pathlib.Path or None
        Vertices per row eta(v) (ceil taken, made odd): a constant >= 1 or a ``.func`` path.
        None: the polygonize default.
    """

    name: str
    degree_u: int
    degree_v: int
    control_points: np.ndarray
    symmetry_n: int = 1
    symmetry_phase_deg: float = 0.0
    bilateral: bool = False
    fused: int = 0
    tilt_deg: float = 0.0
    material: int = 0
    lambda_: float | Path | None = None
    eta: float | Path | None = None

    def __post_init__(self):
        cp = np.array(self.control_points, dtype=np.float64)
        cp.setflags(write=False)
        object.__setattr__(self, "control_points", cp)
        for name in ("lambda_", "eta"):
            v = getattr(self, name)
            if isinstance(v, str):
                object.__setattr__(self, name, Path(v))
            elif isinstance(v, (int, float)) and not isinstance(v, bool):
                object.__setattr__(self, name, float(v))
        problem = self.problem()
        if problem is not None:
            raise _InvalidOrgan(self.name, problem)

    # -- shape -------------------------------------------------------------------------------

    @property
    def nv(self) -> int:
        """Control points from base to tip (rows)."""
        return int(self.control_points.shape[0])

    @property
    def nu(self) -> int:
        """Control points across the petal as stored (half a petal when bilateral)."""
        return int(self.control_points.shape[1])

    @property
    def nu_full(self) -> int:
        """Control points across the whole petal: ``2 * nu - 1`` when bilateral, else ``nu``."""
        return 2 * self.nu - 1 if self.bilateral else self.nu

    def problem(self) -> tuple[str, str, str] | None:
        """The first broken invariant as (file key, expected, found), or None when valid."""
        if not isinstance(self.name, str) or not _NAME.match(self.name):
            return ("organ", _NAME_RULE, shorten(str(self.name)))
        cp = self.control_points
        if cp.ndim != 3 or cp.shape[2] != 3 or cp.shape[0] < 1 or cp.shape[1] < 1:
            return ("grid", "control points of shape (nv, nu, 3)", f"shape {cp.shape}")
        if not np.isfinite(cp).all():
            return ("points", "finite coordinates", "NaN or inf")
        if np.abs(cp).max() > MAX_COORDINATE:
            return ("points", f"coordinates within +-{MAX_COORDINATE:g} (floret units)",
                    f"{float(np.abs(cp).max()):g}")
        for key, deg in (("degree", self.degree_u), ("degree", self.degree_v)):
            if isinstance(deg, bool) or not isinstance(deg, (int, np.integer)):
                return (key, "integer degrees", repr(deg))
            if not 1 <= deg <= MAX_DEGREE:
                return (key, f"degrees in 1..{MAX_DEGREE}", str(int(deg)))
        if not self.degree_u < self.nu_full:
            what = f"{self.nu_full} mirrored" if self.bilateral else str(self.nu_full)
            return (
                "degree",
                f"degree u < control points in u ({what})",
                f"degree u {self.degree_u}",
            )
        if not self.degree_v < self.nv:
            return ("degree", f"degree v < control points in v ({self.nv})",
                    f"degree v {self.degree_v}")
        if isinstance(self.symmetry_n, bool) or not isinstance(self.symmetry_n, (int, np.integer)):
            return ("symmetry", "an integer n", repr(self.symmetry_n))
        if self.symmetry_n < 1:
            return ("symmetry", "n >= 1", str(self.symmetry_n))
        if self.symmetry_n > MAX_SYMMETRY:
            return ("symmetry", f"n <= {MAX_SYMMETRY} (petals of one whorl)", str(self.symmetry_n))
        if not math.isfinite(self.symmetry_phase_deg):
            return ("symmetry", "a finite phase angle", repr(self.symmetry_phase_deg))
        if not isinstance(self.bilateral, (bool, np.bool_)):
            return ("bilateral", "on or off", repr(self.bilateral))
        if isinstance(self.fused, bool) or not isinstance(self.fused, (int, np.integer)):
            return ("fused", "an integer", repr(self.fused))
        if not 0 <= self.fused <= self.nv:
            return ("fused", f"0 <= fused <= nv ({self.nv})", str(self.fused))
        if self.fused > 0 and not (self.bilateral and self.symmetry_n >= 2):
            return (
                "fused",
                "fused 0 unless 'bilateral: on' and symmetry n >= 2 (fusion needs dihedral "
                "symmetry, thesis 2.2)",
                str(self.fused),
            )
        if not (math.isfinite(self.tilt_deg) and abs(self.tilt_deg) <= MAX_TILT):
            return ("tilt", f"a finite angle within +-{MAX_TILT} degrees", repr(self.tilt_deg))
        if isinstance(self.material, bool) or not isinstance(self.material, (int, np.integer)):
            return ("material", "an integer id", repr(self.material))
        if self.material < 0:
            return ("material", "an id >= 0", str(self.material))
        if self.material > MAX_MATERIAL:
            return ("material", f"an id <= {MAX_MATERIAL} (the material map's ids, as SCN 'mtl:')", str(self.material))
        for key, value in (("lambda", self.lambda_), ("eta", self.eta)):
            p = _sampling_problem(key, value)
            if p is not None:
                return (key, *p)
        return None

    def __eq__(self, other):
        if not isinstance(other, Organ):
            return NotImplemented
        return (
            self.name == other.name
            and self.degree_u == other.degree_u
            and self.degree_v == other.degree_v
            and self.control_points.shape == other.control_points.shape
            and bool(np.array_equal(self.control_points, other.control_points))
            and self.symmetry_n == other.symmetry_n
            and self.symmetry_phase_deg == other.symmetry_phase_deg
            and bool(self.bilateral) == bool(other.bilateral)
            and self.fused == other.fused
            and self.tilt_deg == other.tilt_deg
            and self.material == other.material
            and self.lambda_ == other.lambda_
            and self.eta == other.eta
        )

    __hash__ = None  # type: ignore[assignment]


@dataclass(frozen=True)
class Floret:
    """A floret key pose (or one frame of an animation): named organs and an optional key time.

    Parameters
    ----------
    name : str
        Floret name (same character rules as organ names).
    organs : tuple of Organ
        One or more organs with distinct names, in file order (which is also the order
        ``polygonize`` writes them).
    key_time : float or None
        Developmental time of this pose, in the units of the growth function's output (by
        convention 0 for the first key pose, 1 for the last). None: not given (floret-animate
        spaces poses evenly).
    source : pathlib.Path or None
        The file read (not compared).
    """

    name: str
    organs: tuple[Organ, ...]
    key_time: float | None = None
    source: Path | None = field(default=None, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "organs", tuple(self.organs))
        if self.key_time is not None:
            object.__setattr__(self, "key_time", float(self.key_time))
        problem = self.problem()
        if problem is not None:
            raise ValueError(f"floret {self.name!r}: expected {problem[1]}, found {problem[2]}")

    def problem(self) -> tuple[str, str, str] | None:
        """The first broken floret-level invariant as (key, expected, found), or None."""
        if not isinstance(self.name, str) or not _NAME.match(self.name):
            return ("name", _NAME_RULE, shorten(str(self.name)))
        if self.key_time is not None and not math.isfinite(self.key_time):
            return ("time", "a finite key time", repr(self.key_time))
        if not self.organs:
            return ("organ", "at least one organ", "none")
        seen = set()
        for organ in self.organs:
            if not isinstance(organ, Organ):
                return ("organ", "Organ objects", repr(type(organ).__name__))
            if organ.name in seen:
                return ("organ", "distinct organ names", repr(organ.name))
            seen.add(organ.name)
        return None

    def organ(self, name: str) -> Organ:
        """The organ called ``name`` (KeyError if none)."""
        for o in self.organs:
            if o.name == name:
                return o
        raise KeyError(name)


# --------------------------------------------------------------------------------------------------
# Symmetry: the geometric meaning of the fields
# --------------------------------------------------------------------------------------------------


def _rot_y(angle_rad: float) -> np.ndarray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def full_petal(organ: Organ) -> np.ndarray:
    """The control net of the whole petal at angle 0, with tilt and fusion applied.

    Steps, in this order (formats/floret.md, "Symmetry"):

    1. Bilateral: column 0 (the midline) gets z = 0; the columns 1..nu-1 are mirrored
       (z -> -z) and put in front, reversed, so the full net runs from the -Z boundary to the
       +Z boundary with ``2 nu - 1`` columns.
    2. Tilt: rotate about the axis parallel to +Z through the pivot, the mean of the base row
       (row 0) with z set to 0, by ``tilt_deg``; positive turns +Y toward +X.
    3. Fusion: rows 0..k-1 of column 0 (the -Z boundary) are projected orthogonally onto the
       plane through the Y axis at 180/n degrees from the midplane on the -Z side (the symmetry
       plane between this copy and copy 1), and the same rows of the last column onto its
       mirror image on the +Z side (between this copy and copy n-1). Adjacent copies then share
       those boundary points (up to rounding).

    Parameters
    ----------
    organ : Organ

    Returns
    -------
    (nv, nu_full, 3) float64 array
        A new, writable array.
    """
    cp = np.array(organ.control_points, dtype=np.float64)
    if organ.bilateral:
        cp[:, 0, 2] = 0.0
        mirrored = cp[:, :0:-1].copy()
        mirrored[..., 2] *= -1.0
        cp = np.concatenate([mirrored, cp], axis=1)
    if organ.tilt_deg != 0.0:
        pivot = cp[0].mean(axis=0)
        pivot[2] = 0.0
        t = math.radians(organ.tilt_deg)
        c, s = math.cos(t), math.sin(t)
        rz = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])  # R_z(-t): +Y toward +X
        cp = la.matmul(cp - pivot, rz.T) + pivot
    k = organ.fused
    if k > 0:
        h = math.pi / organ.symmetry_n
        for col, normal in (
            (0, np.array([math.sin(h), 0.0, math.cos(h)])),  # -Z side, toward copy 1
            (-1, np.array([-math.sin(h), 0.0, math.cos(h)])),  # +Z side, toward copy n-1
        ):
            pts = cp[:k, col]
            cp[:k, col] = pts - np.outer(la.matmul(pts, normal), normal)
    return cp


def petal_angles_deg(organ: Organ) -> np.ndarray:
    """Angles of the n copies about +Y: ``phase + k * 360 / n``, k = 0..n-1.

    Returns
    -------
    (n,) float64 array, degrees
    """
    n = organ.symmetry_n
    return organ.symmetry_phase_deg + np.arange(n, dtype=np.float64) * (360.0 / n)


def petals(organ: Organ) -> np.ndarray:
    """Every copy of the organ's petal in the floret frame.

    Returns
    -------
    (n, nv, nu_full, 3) float64 array
        Copy k is :func:`full_petal` rotated about +Y (right-handed: +X toward -Z) by
        ``petal_angles_deg(organ)[k]``. With fusion, the last column of copy k + 1 equals the
        first column of copy k in rows 0..fused-1 (to rounding).
    """
    net = full_petal(organ)
    out = np.empty((organ.symmetry_n, *net.shape), dtype=np.float64)
    for i, a in enumerate(petal_angles_deg(organ)):
        out[i] = la.matmul(net, _rot_y(math.radians(a)).T)
    return out


# --------------------------------------------------------------------------------------------------
# Reader
# --------------------------------------------------------------------------------------------------


class _At(NamedTuple):
    """Where a key's value is being read: for the parsers' messages."""

    path: str
    line: int
    key: str
    body: str  # the line without its comment
    base: str  # the file's folder (relative .func paths)
    grid: tuple[int, int] | None = None  # the organ's grid, when given before this key

    def err(self, expected: str, found: str) -> FormatError:
        return FormatError(self.path, self.line, expected, found)


class KeySpec(NamedTuple):
    """One key of the ``.floret`` table (``formats/floret.md``, "Fields").

    counts : (int, int) or None
        Fewest and most values after the colon (blank-separated); None: the rest of the line is one
        value (a name, a number or ``.func`` path, nothing).
    what : str
        The values in words, for the wrong-count message (``expected 2 integers (...) after 'grid:'``).
    parse : callable
        ``parse(tokens, value, at)`` -> the key's value; checks its range (:class:`FormatError`).
    default
        The value when the key is absent; :data:`REQUIRED` when it may not be, None when absent
        means "not given".
    """

    counts: tuple[int, int] | None
    what: str
    parse: Callable
    default: object = None


REQUIRED = "required"  # KeySpec.default of a key a file (floret) or organ must give


def _ints(what: str, *, low: int | None = None, high: int | None = None, out_of_range: str = "",
          one: bool = False):
    """Integers (all parsed, then each checked against ``low..high``); ``one``: the single value."""
    def parse(toks, value, at):
        vals = tuple(parse_int(t, at.path, at.line, what) for t in toks)
        for t, v in zip(toks, vals):
            if (low is not None and v < low) or (high is not None and v > high):
                raise at.err(out_of_range, shorten(t))
        return vals[0] if one else vals
    return parse


def _float(what: str):
    def parse(toks, value, at):
        return parse_float(toks[0], at.path, at.line, what)
    return parse


def _name(what: str):
    def parse(toks, value, at):
        if not _NAME.match(value):
            raise at.err(f"{what} of letters, digits, '_', '.', '+', '-'", shorten(value) if value else "nothing")
        return value
    return parse


def _time(toks, value, at):
    if len(toks) != 1:  # the floret keys word a wrong count without the organ keys' "N values:"
        raise at.err("1 number after 'time:'", shorten(value) if value else "nothing")
    return parse_float(toks[0], at.path, at.line, "a key time")


def _grid(toks, value, at):
    nu, nv = (parse_int(t, at.path, at.line, "an integer grid size") for t in toks)
    if nu < 1 or nv < 2:
        raise at.err("nu >= 1 and nv >= 2", shorten(value))
    return (nu, nv)


def _symmetry(toks, value, at):
    n = parse_int(toks[0], at.path, at.line, "an integer n")
    if n < 1:
        raise at.err("n >= 1 (n-fold radial symmetry)", shorten(toks[0]))
    phase = parse_float(toks[1], at.path, at.line, "a phase angle") if len(toks) == 2 else 0.0
    return (n, phase)


def _on_off(toks, value, at):
    low = toks[0].lower()
    if low not in _TRUE | _FALSE:
        raise at.err(f"on or off after '{at.key}:'", shorten(toks[0]))
    return low in _TRUE


def _sampling(low: float, *, strict: bool):
    """``lambda``/``eta``: a number (> low when ``strict``, else >= low) or a ``.func`` path."""
    def parse(toks, value, at):
        key = at.key
        if not value:
            raise at.err(f"a number or a .func file after '{key}:'", "nothing")
        if _NUMBER.match(value):
            x = parse_float(value, at.path, at.line, f"a number for '{key}'")
            if (x <= low) if strict else (x < low):
                raise at.err(f"{key} {'>' if strict else '>='} {low:g}", shorten(value))
            return x
        if value.lower().endswith(".func"):
            return Path(os.path.abspath(os.path.join(at.base, value)))
        raise at.err(f"a number or a .func file after '{key}:'", shorten(value))
    return parse


def _points(toks, value, at):
    if value:
        raise at.err("nothing after 'points:' (the rows follow on their own lines)", shorten(value))
    if at.grid is None:
        raise at.err("'grid: nu nv' before 'points:'", shorten(at.body))
    return at.line  # the line of 'points:'; the rows that follow are read by read_floret


_ORGAN_NAME = _name("an organ name")

#: The keys before the first ``organ:`` (spec table "Floret").
FLORET_TABLE: Mapping[str, KeySpec] = MappingProxyType({
    "name": KeySpec(None, "", _name("a floret name"), REQUIRED),
    "time": KeySpec((1, 1), "1 number", _time),
})

#: The keys of an organ, after its ``organ: NAME`` line (spec table "Organ"), in the writer's order.
ORGAN_TABLE: Mapping[str, KeySpec] = MappingProxyType({
    "material": KeySpec((1, 1), "1 integer id", _ints("an integer material id", one=True), 0),
    "degree": KeySpec((2, 2), "2 integers (degree in u, degree in v)",
                      _ints("an integer degree", low=1, high=MAX_DEGREE,
                            out_of_range=f"degrees in 1..{MAX_DEGREE}"), (3, 3)),
    "grid": KeySpec((2, 2), "2 integers (nu across, nv base to tip)", _grid, REQUIRED),
    "symmetry": KeySpec((1, 2), "n [phase-degrees]", _symmetry, (1, 0.0)),
    "bilateral": KeySpec((1, 1), "on or off", _on_off, False),
    "fused": KeySpec((1, 1), "1 integer", _ints("an integer fused count", low=0, out_of_range="fused >= 0",
                                                 one=True), 0),
    "tilt": KeySpec((1, 1), "1 angle in degrees", _float("a tilt angle"), 0.0),
    "lambda": KeySpec(None, "", _sampling(0.0, strict=True)),
    "eta": KeySpec(None, "", _sampling(1.0, strict=False)),
    "points": KeySpec(None, "", _points, REQUIRED),
})

FLORET_KEYS = tuple(FLORET_TABLE)
ORGAN_KEYS = tuple(ORGAN_TABLE)


class _OrganBuilder:
    def __init__(self, name: str, line: int):
        self.name = name
        self.line = line
        self.key_lines: dict[str, int] = {}
        self.values: dict[str, object] = {}
        self.rows: list[list[float]] = []

    @property
    def grid(self) -> tuple[int, int] | None:
        return self.values.get("grid")

    @property
    def points_line(self) -> int | None:
        return self.values.get("points")

    def get(self, key: str):
        return self.values.get(key, ORGAN_TABLE[key].default)


def read_floret(path) -> Floret:
    """Read a ``.floret`` key-pose file.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    Floret
        ``lambda``/``eta`` file paths are made absolute against the file's folder.

    Raises
    ------
    FormatError
        A malformed file: wrong or missing ``floret 1`` line, unknown or repeated key, key out of
        place, bad value (NaN/inf, out of range), wrong number of rows or points per row, degree
        not below the grid size, fused count above the rows, duplicate organ name, no organ.
    InputError
        The file is missing or unreadable.
    """
    path = os.fspath(path)
    base = os.path.dirname(os.path.abspath(path))
    lines = read_lines(path)
    if lines and lines[0].startswith("\ufeff"):
        lines[0] = lines[0][1:]

    def err(line, expected, found):
        return FormatError(path, line, expected, found)

    version_seen = False
    floret_values: dict[str, object] = {}
    floret_lines: dict[str, int] = {}
    organs: list[Organ] = []
    organ_lines: dict[str, int] = {}
    cur: _OrganBuilder | None = None
    closed = False  # the current organ's points block is complete

    def finish_organ(b: _OrganBuilder) -> None:
        if b.points_line is None:
            raise err(b.line, f"a 'points:' block for organ {b.name!r}", "none before the next "
                      "organ or the end of the file")
        du, dv = b.get("degree")
        n, phase = b.get("symmetry")
        cp = np.array(b.rows, dtype=np.float64).reshape(b.grid[1], b.grid[0], 3)
        fields = dict(
            name=b.name,
            degree_u=du,
            degree_v=dv,
            control_points=cp,
            symmetry_n=n,
            symmetry_phase_deg=phase,
            bilateral=b.get("bilateral"),
            fused=b.get("fused"),
            tilt_deg=b.get("tilt"),
            material=b.get("material"),
            lambda_=b.get("lambda"),
            eta=b.get("eta"),
        )
        flat = cp.reshape(-1, 3)
        if len(flat) and (flat == flat[0]).all():  # such a key pose once gave frames of nothing
            raise err(b.key_lines.get("points", b.line), f"control points spanning a surface in organ {b.name!r} (an "
                      "organ whose points all coincide has no size to interpolate or polygonize)",
                      f"all {len(flat)} at {' '.join(f'{c:g}' for c in flat[0])}")
        try:
            organs.append(Organ(**fields))
        except _InvalidOrgan as exc:  # report it on the line of the key at fault
            key, expected, found = exc.problem
            line = b.key_lines.get(key, b.key_lines.get("grid", b.line))
            raise err(line, f"{expected} in organ {b.name!r}", found) from None

    for number, text in enumerate(lines, start=1):
        body = text.split("#", 1)[0].strip()
        if not body:
            continue
        if not version_seen:
            toks = body.split()
            if toks[0] == "floret" and len(toks) == 2:
                if toks[1] != str(FORMAT_VERSION):
                    raise err(number, f"floret format version {FORMAT_VERSION}", shorten(body))
                version_seen = True
                continue
            raise err(number, f"'floret {FORMAT_VERSION}' as the first line", shorten(body))

        # Rows of an open points block.
        if cur is not None and cur.points_line is not None and not closed:
            nu, nv = cur.grid
            row = len(cur.rows) + 1
            toks = body.split()
            what = (f"row {row} of {nv} of organ {cur.name!r}: {nu} points x y z "
                    f"({3 * nu} numbers)")
            if len(toks) != 3 * nu:
                raise err(number, what, f"{len(toks)} values: {shorten(body)}")
            cur.rows.append([parse_float(t, path, number, f"a number in {what}") for t in toks])
            if len(cur.rows) == nv:
                closed = True
            continue

        if ":" not in body:
            raise err(number, "'key: value'", shorten(body))
        raw_key, value = body.split(":", 1)
        key = raw_key.strip().lower()
        value = value.strip()
        at = _At(path, number, key, body, base)

        if key == "organ":
            if "name" not in floret_values:
                raise err(number, "'name: FLORET-NAME' before the first 'organ:'", shorten(body))
            if cur is not None:
                finish_organ(cur)
            name = _ORGAN_NAME(None, value, at)
            if name in organ_lines:
                raise err(number, f"a new organ name ({name!r} is already used on line "
                          f"{organ_lines[name]})", shorten(name))
            organ_lines[name] = number
            cur = _OrganBuilder(name, number)
            closed = False
            continue

        if key in FLORET_TABLE:
            if cur is not None:
                raise err(number, f"'{key}:' before the first 'organ:' (it is a floret key)",
                          shorten(body))
            if key in floret_lines:
                raise err(number, f"'{key}:' once (already on line {floret_lines[key]})",
                          shorten(body))
            floret_lines[key] = number
            floret_values[key] = FLORET_TABLE[key].parse(value.split(), value, at)
            continue

        spec = ORGAN_TABLE.get(key)
        if spec is None:
            if not key:
                raise err(number, "a key before ':'", shorten(body))
            hint = did_you_mean(key, (*FLORET_KEYS, "organ", *ORGAN_KEYS), cutoff=0.6)
            raise err(number, f"a known key{hint}", shorten(raw_key))
        if cur is None:
            raise err(number, f"'organ: NAME' before '{key}:' (an organ key)", shorten(body))
        if closed:
            raise err(number, f"'organ:' or the end of the file (the points block of organ "
                      f"{cur.name!r} ends it)", shorten(body))
        if key in cur.key_lines:
            raise err(number, f"'{key}:' once per organ (already on line {cur.key_lines[key]})",
                      shorten(body))
        cur.key_lines[key] = number
        toks = value.split()
        if spec.counts is not None and not spec.counts[0] <= len(toks) <= spec.counts[1]:
            raise err(number, f"{spec.what} after '{key}:'",
                      f"{len(toks)} values: {shorten(value)}" if value else "nothing")
        cur.values[key] = spec.parse(toks, value, at._replace(grid=cur.grid))

    if not version_seen:
        raise err(None, f"'floret {FORMAT_VERSION}' as the first line", "an empty file")
    if cur is not None and cur.points_line is not None and not closed:
        raise err(cur.points_line, f"{cur.grid[1]} rows of points for organ {cur.name!r}",
                  f"{len(cur.rows)} before the end of the file")
    if "name" not in floret_values:
        raise err(len(lines), "'name: FLORET-NAME' after the 'floret 1' line", "none")
    if cur is None:
        raise err(len(lines), "at least one 'organ:'", "none before the end of the file")
    finish_organ(cur)
    return Floret(floret_values["name"], tuple(organs), floret_values.get("time"),
                  source=Path(os.path.abspath(path)))


# --------------------------------------------------------------------------------------------------
# Writer
# --------------------------------------------------------------------------------------------------


def _num(x) -> str:
    """Shortest text that reads back to the same float64 (Python ``repr``)."""
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"cannot write a non-finite number ({x!r}) to a .floret file")
    return repr(x)


def _sampling_text(value, folder: str, key: str) -> str:
    if isinstance(value, Path):
        text = os.path.relpath(value, folder) if value.is_absolute() else os.fspath(value)
        if any(c in text for c in "#\n\r") or text != text.strip():
            raise ValueError(f"cannot write {key} path {text!r}: no '#', line breaks or "
                             "surrounding blanks")
        return text
    return _num(value)


def format_floret(floret: Floret, folder=".") -> str:
    """The text :func:`write_floret` writes; ``.func`` paths are made relative to ``folder``.

    Layout: the format line, the floret keys, then per organ every key in the order
    ``organ material degree grid symmetry bilateral fused tilt [lambda] [eta] points`` and one
    line per row of control points (v = 0 first), points separated by three blanks. Numbers are
    written as the shortest text that reads back to the same float64 (``repr``).
    """
    folder = os.path.abspath(os.fspath(folder))
    out = [f"floret {FORMAT_VERSION}", f"name: {floret.name}"]
    if floret.key_time is not None:
        out.append(f"time: {_num(floret.key_time)}")
    for o in floret.organs:
        out += [
            "",
            f"organ: {o.name}",
            f"material: {int(o.material)}",
            f"degree: {int(o.degree_u)} {int(o.degree_v)}",
            f"grid: {o.nu} {o.nv}",
            f"symmetry: {int(o.symmetry_n)} {_num(o.symmetry_phase_deg)}",
            f"bilateral: {'on' if o.bilateral else 'off'}",
            f"fused: {int(o.fused)}",
            f"tilt: {_num(o.tilt_deg)}",
        ]
        if o.lambda_ is not None:
            out.append(f"lambda: {_sampling_text(o.lambda_, folder, 'lambda')}")
        if o.eta is not None:
            out.append(f"eta: {_sampling_text(o.eta, folder, 'eta')}")
        out.append("points:")
        for row in o.control_points:
            out.append("  " + "   ".join(" ".join(_num(c) for c in p) for p in row))
    return "\n".join(out) + "\n"


def write_floret(path, floret: Floret) -> None:
    """Write ``floret`` to ``path`` atomically (layout: :func:`format_floret`).

    ``lambda``/``eta`` file paths are written relative to the folder of ``path``, so a frame
    written elsewhere still points at the same function file. write -> read -> write is
    byte-identical.
    """
    folder = os.path.dirname(os.path.abspath(os.fspath(path)))
    write_text_atomic(path, format_floret(floret, folder))


# --------------------------------------------------------------------------------------------------
# Compatibility of key poses
# --------------------------------------------------------------------------------------------------


def check_compatible(a: Floret, b: Floret, path_a, path_b) -> None:
    """Check that two key poses can be interpolated (thesis 2.3: same control-mesh topology).

    Compatible means: the same organs (names, in the same order) and, organ by organ, the same
    grid (nu, nv), degrees, symmetry count n, bilateral flag, fused count, material and
    ``lambda``/``eta`` (polygonize needs one topology for every frame). The symmetry phase, tilt,
    control point positions and key time may differ: floret-animate interpolates them.

    Raises
    ------
    InputError
        Naming both files and the first difference.
    """
    pa, pb = os.fspath(path_a), os.fspath(path_b)

    def fail(what: str, va, vb):
        raise InputError(
            f"{pa} and {pb} are not compatible key poses: {what} is {va} in {pa} but {vb} in {pb}"
        )

    names_a = [o.name for o in a.organs]
    names_b = [o.name for o in b.organs]
    if names_a != names_b:
        fail("the list of organs", names_a, names_b)
    for oa, ob in zip(a.organs, b.organs):
        checks = (
            ("grid (nu x nv)", f"{oa.nu} x {oa.nv}", f"{ob.nu} x {ob.nv}"),
            ("degree (u v)", f"{oa.degree_u} {oa.degree_v}", f"{ob.degree_u} {ob.degree_v}"),
            ("symmetry n", oa.symmetry_n, ob.symmetry_n),
            ("bilateral", "on" if oa.bilateral else "off", "on" if ob.bilateral else "off"),
            ("fused", oa.fused, ob.fused),
            ("material", oa.material, ob.material),
            ("lambda", oa.lambda_, ob.lambda_),
            ("eta", oa.eta, ob.eta),
        )
        for what, va, vb in checks:
            if va != vb:
                fail(f"organ {oa.name!r} {what}", va, vb)
