"""Rigid body animation (RBA) files: thesis appendix C.3 and figure 8.2. Spec: ``formats/rba.md``.

One file per frame (``rba/0000.rba``, ...), one line per floret present in that frame::

    id pos_x pos_y pos_z scale_x scale_y scale_z up_x up_y up_z right_x right_y right_z

``id`` is the index of an ``rba:`` placement in the accompanying scene file (the order of
placements in the SCN file is the identity, fig. 8.2). ``#`` starts a comment line.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from inflo.tools.common import linalg as la

from .atomic import atomic_write, frame_name, list_sequence
from .errors import FormatError, read_lines, shorten
from .placement import _PARALLEL_TOL, FLOAT_FMT, PREAMBLE_FIELDS, format_preamble, parse_preamble, placement_matrix

__all__ = ["RbaFrame", "read_rba", "write_rba", "rba_bytes", "read_rba_sequence", "write_rba_sequence", "list_rba_sequence"]


@dataclass
class RbaFrame:
    """The placements of the florets present in one frame, as structure of arrays.

    Attributes
    ----------
    ids : (k,) int32
        Scene placement indices, in file order (unique).
    pos, scale, up, right : (k, 3) float64
    """

    ids: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32))
    pos: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    scale: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    up: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    right: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    def __post_init__(self):
        self.ids = np.asarray(self.ids, dtype=np.int32).reshape(-1)
        for name in ("pos", "scale", "up", "right"):
            setattr(self, name, np.asarray(getattr(self, name), dtype=np.float64).reshape(-1, 3))

    def __len__(self) -> int:
        return len(self.ids)

    def index(self, pid: int) -> int | None:
        """Row of placement ``pid`` in this frame, or None when the floret is not present."""
        hit = np.nonzero(self.ids == pid)[0]
        return int(hit[0]) if len(hit) else None

    def matrix(self, row: int) -> np.ndarray:
        """(4, 4) local-to-scene matrix of row ``row``."""
        return placement_matrix(self.pos[row], self.scale[row], self.up[row], self.right[row])


def read_rba(path, scene=None) -> RbaFrame:
    """Read one RBA frame.

    Parameters
    ----------
    scene : inflo.formats.scn.Scene, optional
        When given, every id must be the index of an ``rba:`` placement of this scene.

    Raises
    ------
    FormatError
        Wrong number of values, non-numbers, NaN/inf, degenerate frames, a repeated id, or an id
        that is not an ``rba:`` placement of ``scene``.
    """
    lines = read_lines(path)
    fast = _read_rba_fast(lines, scene)
    if fast is not None:
        return fast
    ids, rows, seen = [], [], {}
    for lineno, raw in enumerate(lines, 1):
        s = raw.strip()
        if not s or s[0] == "#":
            continue
        toks = s.split()
        if len(toks) != PREAMBLE_FIELDS:
            raise FormatError(path, lineno, f"{PREAMBLE_FIELDS} values 'id pos(3) scale(3) up(3) right(3)'",
                              f"{len(toks)} values")
        pid, pos, scale, up, right = parse_preamble(toks, path, lineno, "RBA entry")
        if pid in seen:
            raise FormatError(path, lineno, f"each id once (id {pid} is on line {seen[pid]})", shorten(toks[0]))
        seen[pid] = lineno
        if scene is not None:
            if pid >= len(scene.placements):
                raise FormatError(path, lineno, f"an id of the scene's placements (0..{len(scene.placements) - 1})",
                                  shorten(toks[0]))
            kind = scene.placements[pid].kind
            if kind != "rba":
                raise FormatError(path, lineno, "the id of an 'rba:' placement of the scene",
                                  f"{pid}, a '{kind}:' placement")
        ids.append(pid)
        rows.append(np.concatenate([pos, scale, up, right]))
    a = np.array(rows, dtype=np.float64).reshape(-1, 12)
    return RbaFrame(ids, a[:, 0:3], a[:, 3:6], a[:, 6:9], a[:, 9:12])


_PLAIN_NUMBERS = re.compile(r"[0-9eE+\-. \t\n]*")


def _read_rba_fast(lines, scene):
    """The frame of well-formed ``lines`` parsed at once (numpy), or None: then the line-by-line
    reader runs and reports the first bad line exactly. Taken only when every row has 13 plain
    decimal numbers (ids of digits only) and every check of the line-by-line reader passes, so the
    result is the same array for the same file."""
    rows = [s for s in (raw.strip() for raw in lines) if s and s[0] != "#"]
    if not rows:
        return None
    if any(len(r.split()) != PREAMBLE_FIELDS for r in rows):
        return None
    text = "\n".join(rows)
    if not _PLAIN_NUMBERS.fullmatch(text):
        return None
    toks = text.split()
    id_toks = toks[::PREAMBLE_FIELDS]
    if not all(t.isdigit() for t in id_toks):
        return None
    try:
        a = np.array(toks, dtype=np.float64).reshape(-1, PREAMBLE_FIELDS)
    except ValueError:
        return None
    vals = a[:, 1:]
    if not np.isfinite(vals).all():
        return None
    ids = np.array([int(t) for t in id_toks], dtype=np.int64)
    scale, up, right = vals[:, 3:6], vals[:, 6:9], vals[:, 9:12]
    if (scale == 0).any():
        return None
    nu = la.norm(up, axis=1)
    nr = la.norm(right, axis=1)
    if (nu == 0).any() or (nr == 0).any():
        return None
    if (la.norm(np.cross(up / nu[:, None], right / nr[:, None]), axis=1) < _PARALLEL_TOL).any():
        return None
    if len(np.unique(ids)) != len(ids):
        return None
    if scene is not None:
        if ids.max() >= len(scene.placements):
            return None
        if any(scene.placements[int(i)].kind != "rba" for i in ids):
            return None
    return RbaFrame(ids.tolist(), vals[:, 0:3].copy(), scale.copy(), up.copy(), right.copy())


_FAST_MIN_ROWS = 1000
"""Frames of at least this many rows take the fast path by default (below, Python is quick enough
and the numba kernel's one-off import is not worth it)."""


def rba_bytes(ids, pos, scale, up, right) -> bytes:
    """The rows ``id pos scale up right`` exactly as :func:`write_rba` writes them with the default
    format (no header), formatted by the fast path (a numba kernel, ``formats/_rbatext.py``)."""
    from ._rbatext import rba_bytes as fast

    return fast(ids, pos, scale, up, right)


def write_rba(path, frame: RbaFrame, *, header: str | None = None, fmt: str = FLOAT_FMT,
              fast: bool | None = None) -> None:
    """Write one RBA frame atomically, rows in ``frame`` order, fixed-format numbers.

    Parameters
    ----------
    fast : bool, optional
        Format the rows with the numba kernel (:func:`rba_bytes`; the default format only): the same
        bytes as the Python path, many times faster on large frames. None (default): the kernel
        for frames of at least 1000 rows; False: Python's ``fmt % x`` per number.
    """
    ids = frame.ids
    if len(np.unique(ids)) != len(ids):
        raise ValueError(f"{path}: repeated ids in an RBA frame")
    if fast is None:
        fast = fmt == FLOAT_FMT and len(frame) >= _FAST_MIN_ROWS
    elif fast and fmt != FLOAT_FMT:
        raise ValueError(f"the fast RBA path writes {FLOAT_FMT!r} numbers only, not {fmt!r}")
    head = "".join(f"# {h}\n" for h in header.splitlines()) if header else ""
    if fast:
        data = head.encode("utf-8") + rba_bytes(ids, frame.pos, frame.scale, frame.up, frame.right)
        with atomic_write(path, "wb") as fh:
            fh.write(data)
        return
    out = [head]
    for k in range(len(frame)):
        out.append(format_preamble(ids[k], frame.pos[k], frame.scale[k], frame.up[k], frame.right[k], fmt) + "\n")
    with atomic_write(path) as fh:
        fh.write("".join(out))


def list_rba_sequence(source) -> list[Path]:
    """The RBA files of a sequence (folder, glob or single file), in frame order."""
    return list_sequence(source, ".rba")


def read_rba_sequence(source, scene=None) -> tuple[list[Path], list[RbaFrame]]:
    """Read every frame of an RBA sequence (each checked against ``scene`` when given)."""
    paths = list_rba_sequence(source)
    return paths, [read_rba(p, scene) for p in paths]


def write_rba_sequence(folder, frames, *, start: int = 0, digits: int = 4, fmt: str = FLOAT_FMT) -> list[Path]:
    """Write frames as ``folder/0000.rba``, ``folder/0001.rba``, ... (each atomic)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for i, fr in enumerate(frames, start):
        p = folder / frame_name(i, "", ".rba", digits)
        write_rba(p, fr, fmt=fmt)
        paths.append(p)
    return paths
