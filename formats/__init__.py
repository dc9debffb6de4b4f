"""Readers and writers for every inflo file format; each has a spec page ``formats/<name>.md``.

The registry :data:`FORMATS` maps a file suffix to its reader and writer, so generic code (a
round-trip check, a converter) can dispatch on the suffix::

    from inflo.formats import read_any
    scene = read_any("build/yarrow/scene.scn")
"""
from __future__ import annotations

import os

from .errors import FormatError, InputError

__all__ = ["FormatError", "InputError", "FORMATS", "read_any", "write_any"]


def _registry() -> dict:
    from . import bezier_surface, contour, fcc, floret, func, obj, rba, scn

    return {
        ".obj": (obj.read_obj, obj.write_obj),
        ".scn": (scn.read_scn, scn.write_scn),
        ".rba": (rba.read_rba, rba.write_rba),
        ".floret": (floret.read_floret, floret.write_floret),
        ".func": (func.read_func, func.write_func),
        ".fset": (func.read_fset, func.write_fset),
        ".con": (contour.read_con, contour.write_con),
        ".cset": (contour.read_cset, contour.write_cset),
        ".s": (bezier_surface.read_bezier_surface, bezier_surface.write_bezier_surface),
        ".fcc": (fcc.read_fcc, fcc.write_fcc),
    }


FORMATS = _registry()
"""suffix -> (reader(path), writer(path, value))"""


def _lookup(path):
    suffix = os.path.splitext(os.fspath(path))[1].lower()
    if suffix not in FORMATS:
        raise InputError(f"{os.fspath(path)}: unknown file type {suffix!r}; known: {', '.join(sorted(FORMATS))}")
    return FORMATS[suffix]


def read_any(path):
    """Read ``path`` with the reader registered for its suffix."""
    return _lookup(path)[0](path)


def write_any(path, value) -> None:
    """Write ``value`` to ``path`` with the writer registered for its suffix (atomic)."""
    _lookup(path)[1](path, value)
