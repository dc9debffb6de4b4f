"""Bezier surfaces: lpfg/cpfg ``.s`` files of bicubic Bezier patches (L-studio's surface editor).

Petals designed in VLab come in this format (docs/vlab_formats.md); a surface can serve as a floret key
pose after :meth:`BezierSurface.to_turtle_frame` (thesis sec. 2.2-2.3 and Lu et al. model petals
as bicubic Bezier patches). Spec: ``formats/bezier_surface.md``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from inflo.tools.common import linalg as la

from ._vlab import _Cursor, _fmt
from .atomic import write_text_atomic
from .errors import parse_float, parse_int, read_lines, shorten
from .func import _check_name

__all__ = [
    "BezierPatch",
    "BezierSurface",
    "bezier_patch",
    "bernstein3",
    "read_bezier_surface",
    "write_bezier_surface",
    "format_bezier_surface",
    "NEIGHBOUR_KEYS",
]

NEIGHBOUR_KEYS = ("AL", "A", "AR", "L", "R", "BL", "B", "BR")
"""Neighbour slots of a patch (above-left, above, above-right, left, right, below-...), in file order."""
_NEIGHBOUR_LINES = (("AL", "A", "AR"), ("L", "R"), ("BL", "B", "BR"))
_MIN_VECTOR = 1e-3  # lpfg rejects a heading or up vector shorter than this


def bernstein3(s) -> np.ndarray:
    """(..., 4) float64: the cubic Bernstein polynomials ``(1-s)^3, 3s(1-s)^2, 3s^2(1-s), s^3``."""
    s = np.asarray(s, dtype=np.float64)
    r = 1.0 - s
    return np.stack([r * r * r, 3.0 * s * r * r, 3.0 * s * s * r, s * s * s], axis=-1)


def bezier_patch(control, u, v) -> np.ndarray:
    """Points of the bicubic Bezier patch ``S(u, v) = sum_ij B_i(u) B_j(v) P_ij``.

    Parameters
    ----------
    control : (4, 4, 3) array_like of float
        ``P[i, j]``: row ``i`` (the i-th control-point line of a patch in the file) goes with
        ``u``, column ``j`` with ``v`` (lpfg's ``Patch::_Point``).
    u, v : float or array_like of float, broadcastable; the patch is the image of [0, 1]^2

    Returns
    -------
    (..., 3) float64, the broadcast shape of ``u`` and ``v`` plus 3.
    """
    p = np.asarray(control, dtype=np.float64)
    if p.shape != (4, 4, 3):
        raise ValueError(f"control points must have shape (4, 4, 3), got {p.shape}")
    u, v = np.broadcast_arrays(np.asarray(u, dtype=np.float64), np.asarray(v, dtype=np.float64))
    bu, bv = bernstein3(u)[..., None], bernstein3(v)[..., None]
    # sum over i of bu_i * (sum over j of bv_j P[i, j]), each sum in the order 0, 1, 2, 3
    out = None
    for i in range(4):
        row = bv[..., 0, :] * p[i, 0]
        for j in range(1, 4):
            row = row + bv[..., j, :] * p[i, j]
        out = bu[..., i, :] * row if out is None else out + bu[..., i, :] * row
    return out


@dataclass(frozen=True, eq=False)
class BezierPatch:
    """One bicubic patch of a ``.s`` file.

    Attributes
    ----------
    name : str
        Patch name (one token).
    control_points : (4, 4, 3) float64, read-only
        ``P[i, j]``, rows as in the file; see :func:`bezier_patch`.
    top_color, bottom_color : int
        Colour-map indices of the two sides (``TOP COLOR:``, ``BOTTOM COLOR:``).
    top_diffuse, bottom_diffuse : float
        ``DIFFUSE:`` coefficients of the two sides.
    neighbours : tuple of 8 str
        Names of the neighbouring patches in :data:`NEIGHBOUR_KEYS` order, ``~`` for none
        (stedit files add a direction word: ``"petal2 r"``), kept as read.
    """

    name: str
    control_points: np.ndarray
    top_color: int = 0
    top_diffuse: float = 0.0
    bottom_color: int = 0
    bottom_diffuse: float = 0.0
    neighbours: tuple[str, ...] = ("~",) * 8

    def __post_init__(self):
        cp = np.array(self.control_points, dtype=np.float64)
        if cp.shape != (4, 4, 3) or not np.all(np.isfinite(cp)):
            raise ValueError(f"control_points must be a finite (4, 4, 3) array, got shape {cp.shape}")
        name = _check_name(self.name)
        if len(name.split()) != 1:
            raise ValueError(f"a patch name is one token, got {name!r}")
        neighbours = tuple(" ".join(str(n).split()) for n in self.neighbours)
        if len(neighbours) != 8 or not all(neighbours):
            raise ValueError("neighbours must be 8 non-empty names ('~' for none)")
        cp.setflags(write=False)
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "control_points", cp)
        object.__setattr__(self, "top_color", int(self.top_color))
        object.__setattr__(self, "bottom_color", int(self.bottom_color))
        object.__setattr__(self, "top_diffuse", float(self.top_diffuse))
        object.__setattr__(self, "bottom_diffuse", float(self.bottom_diffuse))
        object.__setattr__(self, "neighbours", neighbours)

    def evaluate(self, u, v) -> np.ndarray:
        """(..., 3) float64: :func:`bezier_patch` of this patch."""
        return bezier_patch(self.control_points, u, v)

    def __eq__(self, other):
        if not isinstance(other, BezierPatch):
            return NotImplemented
        return (
            self.name == other.name
            and np.array_equal(self.control_points, other.control_points)
            and (self.top_color, self.top_diffuse, self.bottom_color, self.bottom_diffuse)
            == (other.top_color, other.top_diffuse, other.bottom_color, other.bottom_diffuse)
            and self.neighbours == other.neighbours
        )

    __hash__ = object.__hash__


def _vec3(value, what: str) -> np.ndarray:
    a = np.array(value, dtype=np.float64).reshape(-1)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{what} must be 3 finite numbers")
    a.setflags(write=False)
    return a


def _frame(heading, up) -> np.ndarray:
    """(3, 3) rows (right = heading x up, heading, up), orthonormalized; raises ValueError."""
    h = np.asarray(heading, dtype=np.float64)
    u = np.asarray(up, dtype=np.float64)
    if la.norm(h) < _MIN_VECTOR:
        raise ValueError("the heading vector is (nearly) zero")
    if la.norm(u) < _MIN_VECTOR:
        raise ValueError("the up vector is (nearly) zero")
    h = h / la.norm(h)
    u = u / la.norm(u)
    u = u - la.dot(u, h) * h
    if la.norm(u) < _MIN_VECTOR:
        raise ValueError("the up vector is parallel to the heading")
    u = u / la.norm(u)
    return np.stack([np.cross(h, u), h, u])


@dataclass(frozen=True, eq=False)
class BezierSurface:
    """A ``.s`` surface: its placement header and one or more bicubic Bezier patches.

    Attributes
    ----------
    patches : tuple of BezierPatch (at least one)
    contact : (3,) float64
        ``CONTACT POINT``: where the surface attaches (mapped to the origin of the turtle frame).
    end : (3,) float64
        ``END POINT`` (kept; lpfg does not use it).
    heading, up : (3,) float64
        Directions of the surface that map to the turtle's heading and up (need not be unit).
    size : float
        ``SIZE:`` (> 0); the turtle frame divides lengths by it.
    precision : (int, int) or None
        ``PRECISION S: s T: t`` subdivision counts, if the file has that line.
    stedit : bool
        The file starts with ``VERSION stedit`` (neighbour lines carry direction words).

    The file's bounding-box line is not kept: it is recomputed from the control points on writing.
    """

    patches: tuple
    contact: np.ndarray = (0.0, 0.0, 0.0)
    end: np.ndarray = (0.0, 0.0, 0.0)
    heading: np.ndarray = (0.0, 0.0, 1.0)
    up: np.ndarray = (0.0, 1.0, 0.0)
    size: float = 1.0
    precision: tuple[int, int] | None = None
    stedit: bool = False

    def __post_init__(self):
        patches = tuple(self.patches)
        if not patches or not all(isinstance(p, BezierPatch) for p in patches):
            raise ValueError("a surface needs at least one BezierPatch")
        size = float(self.size)
        if not np.isfinite(size) or size <= 0.0:
            raise ValueError(f"size must be > 0, got {self.size!r}")
        heading = _vec3(self.heading, "heading")
        up = _vec3(self.up, "up")
        _frame(heading, up)  # validates
        precision = None
        if self.precision is not None:
            precision = tuple(int(v) for v in self.precision)
            if len(precision) != 2 or min(precision) < 1:
                raise ValueError("precision must be two integers >= 1")
        object.__setattr__(self, "patches", patches)
        object.__setattr__(self, "contact", _vec3(self.contact, "contact"))
        object.__setattr__(self, "end", _vec3(self.end, "end"))
        object.__setattr__(self, "heading", heading)
        object.__setattr__(self, "up", up)
        object.__setattr__(self, "size", size)
        object.__setattr__(self, "precision", precision)
        object.__setattr__(self, "stedit", bool(self.stedit))

    def control_points(self) -> np.ndarray:
        """(n_patches, 4, 4, 3) float64: every patch's control points, as stored."""
        return np.stack([p.control_points for p in self.patches])

    def frame(self) -> np.ndarray:
        """(3, 3) float64: rows (right, heading, up), orthonormal and right-handed.

        ``heading`` is normalized, ``up`` made perpendicular to it (Gram-Schmidt) and normalized,
        and ``right = heading x up`` (lpfg's ``-left`` with ``left = up x heading``).
        """
        return _frame(self.heading, self.up)

    def to_turtle_frame(self) -> BezierSurface:
        """The surface in the turtle frame: ``p' = R (p - contact) / size`` with ``R = frame()``.

        The contact point goes to the origin, the heading to +Y, up to +Z, right to +X (the
        floret frame of docs/architecture.md: axis along +Y). For the usual header (heading +Z, up +Y)
        this is lpfg's ``(x, y, z) -> (-x, z, y)``; lpfg multiplies by the transpose of R, which
        agrees with it whenever R is symmetric, as there, and differs for other headers.
        """
        r = self.frame()

        def move(p):
            return la.matmul((np.asarray(p) - self.contact) / self.size, r.T)

        patches = tuple(
            BezierPatch(p.name, move(p.control_points), p.top_color, p.top_diffuse, p.bottom_color,
                        p.bottom_diffuse, p.neighbours)
            for p in self.patches
        )
        return BezierSurface(patches, contact=(0.0, 0.0, 0.0), end=move(self.end), heading=(0.0, 1.0, 0.0),
                             up=(0.0, 0.0, 1.0), size=1.0, precision=self.precision, stedit=self.stedit)

    def evaluate(self, u, v, patch: int = 0) -> np.ndarray:
        """(..., 3) float64: points ``S(u, v)`` of patch number ``patch`` (see :func:`bezier_patch`)."""
        return self.patches[patch].evaluate(u, v)

    def grid(self, n_u: int, n_v: int) -> np.ndarray:
        """(n_patches, n_u, n_v, 3) float64: every patch at ``u = linspace(0, 1, n_u)`` x ``v = linspace(0, 1, n_v)``."""
        if n_u < 2 or n_v < 2:
            raise ValueError("n_u and n_v must be >= 2")
        uu, vv = np.meshgrid(np.linspace(0.0, 1.0, n_u), np.linspace(0.0, 1.0, n_v), indexing="ij")
        return np.stack([p.evaluate(uu, vv) for p in self.patches])

    def __eq__(self, other):
        if not isinstance(other, BezierSurface):
            return NotImplemented
        return (
            self.patches == other.patches
            and all(np.array_equal(getattr(self, k), getattr(other, k)) for k in ("contact", "end", "heading", "up"))
            and (self.size, self.precision, self.stedit) == (other.size, other.precision, other.stedit)
        )

    __hash__ = object.__hash__


# --------------------------------------------------------------------------------------------
# Reading


def _labelled(cur: _Cursor, line: int, text: str, words: list[str], labels: list[str], what: str):
    """Parse ``WORDS L1: a L2: b ...`` into floats; ``what`` describes the whole line."""
    tokens = text.split()
    n = len(words)
    if tokens[:n] != words or len(tokens) != n + 2 * len(labels) or tokens[n::2] != [f"{l}:" for l in labels]:
        raise cur.error(line, what, shorten(text))
    return [tokens[n + 1 + 2 * i] for i in range(len(labels))]


def _xyz_line(cur: _Cursor, words: list[str]) -> tuple[int, str, np.ndarray]:
    """``WORDS  X: x Y: y Z: z`` -> (line number, text, (3,) float64)."""
    what = f"'{' '.join(words)}  X: x Y: y Z: z'"
    line, text = cur.take(what)
    values = _labelled(cur, line, text, words, ["X", "Y", "Z"], what)
    xyz = np.array([parse_float(v, cur.path, line, f"a number in the {' '.join(words)} line") for v in values])
    return line, text, xyz


def _parse_patch(cur: _Cursor, name_line: int, name: str, stedit: bool) -> BezierPatch:
    path = cur.path
    if len(name.split()) != 1:
        raise cur.error(name_line, "a patch name (one word)", shorten(name))
    what = "'TOP COLOR: i DIFFUSE: d BOTTOM COLOR: j DIFFUSE: e'"
    line, text = cur.take(what)
    tokens = text.split()
    if len(tokens) != 10 or tokens[0:2] != ["TOP", "COLOR:"] or tokens[3] != "DIFFUSE:" \
            or tokens[5:7] != ["BOTTOM", "COLOR:"] or tokens[8] != "DIFFUSE:":
        raise cur.error(line, what, shorten(text))
    top = parse_int(tokens[2], path, line, "an integer colour index")
    top_d = parse_float(tokens[4], path, line, "a number after 'DIFFUSE:'")
    bottom = parse_int(tokens[7], path, line, "an integer colour index")
    bottom_d = parse_float(tokens[9], path, line, "a number after 'DIFFUSE:'")
    neighbours = []
    for keys in _NEIGHBOUR_LINES:
        what = "'" + " ".join(f"{k}: name" for k in keys) + "' ('~' for none)"
        line, text = cur.take(what)
        found: dict[str, list[str]] = {}
        for tok in text.split():
            if tok.endswith(":"):
                if len(found) == len(keys) or tok != f"{keys[len(found)]}:":
                    raise cur.error(line, what, shorten(text))
                found[tok[:-1]] = []
            elif found:
                found[list(found)[-1]].append(tok)
            else:
                raise cur.error(line, what, shorten(text))
        if len(found) != len(keys) or any(not v or len(v) > (2 if stedit else 1) for v in found.values()):
            raise cur.error(line, what, shorten(text))
        neighbours.extend(" ".join(found[k]) for k in keys)
    rows = []
    for i in range(4):
        what = f"control-point row {i + 1} of 4 (12 numbers: 4 points x y z)"
        line, text = cur.take(what)
        tokens = text.split()
        if len(tokens) != 12:
            raise cur.error(line, what, f"{len(tokens)} numbers in {shorten(text)}")
        rows.append([parse_float(t, path, line, "a number (control-point coordinate)") for t in tokens])
    cp = np.array(rows).reshape(4, 4, 3)
    return BezierPatch(name, cp, top, top_d, bottom, bottom_d, tuple(neighbours))


def read_bezier_surface(path) -> BezierSurface:
    """Read a ``.s`` Bezier surface file (one or more bicubic patches).

    Raises :class:`FormatError` (file, line, expected, found) for malformed input; see
    ``formats/bezier_surface.md`` for the layout and what is rejected.
    """
    cur = _Cursor(path, read_lines(path))
    p = cur.path
    line, text = cur.take("a bounding box 'xmin xmax ymin ymax zmin zmax'")
    stedit = False
    if text.split()[0] == "VERSION":
        if text.split() != ["VERSION", "stedit"]:
            raise cur.error(line, "'VERSION stedit'", shorten(text))
        stedit = True
        line, text = cur.take("a bounding box 'xmin xmax ymin ymax zmin zmax'")
    tokens = text.split()
    if len(tokens) != 6:
        raise cur.error(line, "a bounding box 'xmin xmax ymin ymax zmin zmax' (6 numbers)", shorten(text))
    for tok in tokens:
        parse_float(tok, p, line, "a number in the bounding box")
    precision = None
    nxt = cur.peek()
    if nxt is not None and nxt[1].split()[0] == "PRECISION":
        line, text = cur.take("'PRECISION S: s T: t'")
        values = _labelled(cur, line, text, ["PRECISION"], ["S", "T"], "'PRECISION S: s T: t'")
        precision = tuple(parse_int(v, p, line, "an integer precision") for v in values)
        if min(precision) < 1:
            raise cur.error(line, "precisions >= 1", shorten(text))
    contact = _xyz_line(cur, ["CONTACT", "POINT"])[2]
    end = _xyz_line(cur, ["END", "POINT"])[2]
    line, text, heading = _xyz_line(cur, ["HEADING"])
    if la.norm(heading) < _MIN_VECTOR:
        raise cur.error(line, "a non-zero HEADING vector", shorten(text))
    line, text, up = _xyz_line(cur, ["UP"])
    if la.norm(up) < _MIN_VECTOR:
        raise cur.error(line, "a non-zero UP vector", shorten(text))
    if la.norm(np.cross(heading / la.norm(heading), up / la.norm(up))) < _MIN_VECTOR:
        raise cur.error(line, "an UP vector not parallel to HEADING", shorten(text))
    line, value = cur.field("SIZE", "'SIZE: s'")
    size = parse_float(value, p, line, "a number after 'SIZE:'")
    if size <= 0.0:
        raise cur.error(line, "a size > 0", shorten(value))
    patches = []
    while not cur.at_end():
        name_line, name = cur.take("a patch name")
        patches.append(_parse_patch(cur, name_line, name, stedit))
    if not patches:
        raise cur.error(None, "at least one patch after 'SIZE:'", "end of file")
    return BezierSurface(tuple(patches), contact=contact, end=end, heading=heading, up=up, size=size,
                         precision=precision, stedit=stedit)


# --------------------------------------------------------------------------------------------
# Writing


def _xyz(words: str, v) -> str:
    return f"{words}  X: {_fmt(v[0])} Y: {_fmt(v[1])} Z: {_fmt(v[2])}"


def format_bezier_surface(surface: BezierSurface) -> str:
    """The ``.s`` text of ``surface`` (numbers ``%.6f``; bounding box from the control points)."""
    cp = surface.control_points().reshape(-1, 3)
    lo, hi = cp.min(axis=0), cp.max(axis=0)
    out = ["VERSION stedit"] if surface.stedit else []
    out.append("   ".join(f"{_fmt(lo[k])} {_fmt(hi[k])}" for k in range(3)))
    if surface.precision is not None:
        out.append(f"PRECISION S: {surface.precision[0]} T: {surface.precision[1]}")
    out.append(_xyz("CONTACT POINT", surface.contact))
    out.append(_xyz("END POINT", surface.end))
    out.append(_xyz("HEADING", surface.heading))
    out.append(_xyz("UP", surface.up))
    out.append(f"SIZE: {_fmt(surface.size)}")
    for patch in surface.patches:
        out.append(patch.name)
        out.append(f"TOP COLOR: {patch.top_color} DIFFUSE: {_fmt(patch.top_diffuse)} "
                   f"BOTTOM COLOR: {patch.bottom_color} DIFFUSE: {_fmt(patch.bottom_diffuse)}")
        nb = dict(zip(NEIGHBOUR_KEYS, patch.neighbours))
        for keys in _NEIGHBOUR_LINES:
            out.append(" ".join(f"{k}: {nb[k]}" for k in keys))
        for row in patch.control_points:
            out.append("  ".join(" ".join(_fmt(c) for c in pt) for pt in row))
    return "\n".join(out) + "\n"


def write_bezier_surface(path, surface: BezierSurface) -> None:
    """Write ``surface`` as a ``.s`` file, atomically."""
    write_text_atomic(path, format_bezier_surface(surface))
