"""Rigid placements shared by SCN and RBA files: ``id pos scale up right`` (thesis app. C.2, C.3).

A floret's local frame has its axis along +Y; a placement maps local +X to ``right``, +Y to ``up``
and +Z to ``right x up`` (``right`` first made orthogonal to ``up``), then scales by ``scale``
(per local axis), then translates by ``pos`` (docs/architecture.md "Frames of reference").
"""
from __future__ import annotations

import numpy as np

from inflo.tools.common import linalg as la

from .errors import FormatError, parse_float, parse_int, shorten

__all__ = ["PREAMBLE_FIELDS", "parse_preamble", "format_preamble", "format_nonzero", "placement_matrix", "frame_axes", "FLOAT_FMT"]

FLOAT_FMT = "%.6f"
PREAMBLE_FIELDS = 13  # id, pos(3), scale(3), up(3), right(3)
_PARALLEL_TOL = 1e-9


def frame_axes(up, right) -> np.ndarray:
    """Orthonormal local axes as the rows of a (3, 3) array: X (right), Y (up), Z = X x Y.

    Parameters
    ----------
    up, right : (3,) float
        Need not be unit or orthogonal; ``right`` is projected off ``up`` (Gram-Schmidt).
    """
    u = np.asarray(up, dtype=np.float64)
    u = u / la.norm(u)
    r = np.asarray(right, dtype=np.float64)
    r = r - la.dot(r, u) * u
    r = r / la.norm(r)
    return np.stack([r, u, np.cross(r, u)])


def placement_matrix(pos, scale, up, right) -> np.ndarray:
    """The (4, 4) float64 matrix taking local floret coordinates to the scene.

    ``M @ [x, y, z, 1]`` = pos + sx*x*right + sy*y*up + sz*z*(right x up).
    """
    axes = frame_axes(up, right)
    m = np.eye(4)
    m[:3, :3] = (axes * np.asarray(scale, dtype=np.float64)[:, None]).T
    m[:3, 3] = pos
    return m


def parse_preamble(tokens, path, line, what: str = "placement"):
    """Parse ``id px py pz sx sy sz ux uy uz rx ry rz`` -> (id, pos, scale, up, right).

    Rejects non-numbers, NaN/inf, a negative id, a zero scale component, a zero ``up`` or ``right``
    and ``right`` parallel to ``up``.
    """
    if len(tokens) < PREAMBLE_FIELDS:
        raise FormatError(path, line, f"{PREAMBLE_FIELDS} values 'id pos(3) scale(3) up(3) right(3)' in the {what}",
                          f"{len(tokens)} values")
    pid = parse_int(tokens[0], path, line, f"an integer id in the {what}")
    if pid < 0:
        raise FormatError(path, line, "a non-negative id", shorten(tokens[0]))
    vals = [parse_float(t, path, line, f"a number in the {what}") for t in tokens[1:PREAMBLE_FIELDS]]
    pos, scale, up, right = (np.array(vals[k:k + 3]) for k in (0, 3, 6, 9))
    if np.any(scale == 0):
        raise FormatError(path, line, "non-zero scale components", " ".join(tokens[4:7]))
    nu, nr = la.norm(up), la.norm(right)
    if nu == 0:
        raise FormatError(path, line, "a non-zero up vector", " ".join(tokens[7:10]))
    if nr == 0:
        raise FormatError(path, line, "a non-zero right vector", " ".join(tokens[10:13]))
    if la.norm(np.cross(up / nu, right / nr)) < _PARALLEL_TOL:
        raise FormatError(path, line, "a right vector not parallel to up",
                          f"up {' '.join(tokens[7:10])} and right {' '.join(tokens[10:13])}")
    return pid, pos, scale, up, right


def format_nonzero(x: float, fmt: str = FLOAT_FMT) -> str:
    """``fmt % x``, except that a non-zero ``x`` the fixed format would print as zero is written in
    exponent form (``%.6e``): a valid scale of 4e-7 must not come back as 0, which readers refuse."""
    s = fmt % float(x)
    if x != 0 and float(s) == 0:
        return "%.6e" % float(x)
    return s


def format_preamble(pid: int, pos, scale, up, right, fmt: str = FLOAT_FMT) -> str:
    """``id pos scale up right`` with fixed-format numbers.

    Positions are written in ``fmt`` (absolute precision). A scale component, and an up or right
    vector, that must not be zero keeps a tiny non-zero value in exponent form
    (:func:`format_nonzero`): a scale component on its own, a vector when all of its components
    would print as zero.
    """
    out = [fmt % float(x) for x in pos]
    out += [format_nonzero(x, fmt) for x in scale]
    for vec in (up, right):
        text = [fmt % float(x) for x in vec]
        if all(float(t) == 0 for t in text) and any(x != 0 for x in vec):
            text = [format_nonzero(x, fmt) for x in vec]
        out += text
    return f"{int(pid)} " + " ".join(out)
