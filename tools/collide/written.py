"""The written-frame guarantee: a collision-free mesh stays collision-free as written.

Coordinates are written with six decimals (formats/obj.md); rounding can make two faces that lie
closer than the rounding intersect. :func:`written_text` picks the first of :data:`WRITE_FORMATS`
whose written numbers, parsed back, have no intersecting pair (the exact static test), and hands
on the ``v`` lines in it. ``fccompose`` applies it to every frame it writes, ``subdivide`` to
every frame where its collision response left pairs closer than the spacing.
"""
from __future__ import annotations

import numpy as np

from inflo.formats.obj import written_vertices

from .tritri import intersecting_pairs

__all__ = ["WRITE_FORMATS", "written_format", "written_text"]

#: Coordinate formats of the written frames, tried in turn (:func:`written_format`).
WRITE_FORMATS = ("%.6f", "%.9f", "%.12f", "%.17g")


def written_format(x: np.ndarray, faces: np.ndarray, formats=WRITE_FORMATS, tri_part: np.ndarray | None = None) -> str:
    """The first of ``formats`` whose written coordinates keep the canopy as collision-free as
    ``x`` is: rounding to 6 decimals can make two petals that lie flat on each other, closer than
    the rounding, cross (a written-frame guarantee). The written numbers are parsed back
    and tested exactly (:func:`intersecting_pairs`, touching counts); where ``x`` itself has
    intersecting pairs (the sanity check reports them), more digits cannot help and the first
    format is kept. ``tri_part``: the floret of each face (the exact test goes floret by floret)."""
    return written_text(x, faces, formats, tri_part)[0]


def written_text(x: np.ndarray, faces: np.ndarray, formats=WRITE_FORMATS,
                 tri_part: np.ndarray | None = None) -> tuple[str, str]:
    """(:func:`written_format`, the ``v`` lines of ``x`` in it): the frame's vertices formatted
    once, for the check and the file."""
    n = None
    first = None
    for fmt in formats:
        xr, text = written_vertices(x, fmt)
        if first is None:
            first = (fmt, text)
        if fmt == formats[-1]:
            return fmt, text
        found = len(intersecting_pairs(xr, faces, tri_part=tri_part))
        if found == 0:
            return fmt, text
        if n is None:
            n = len(intersecting_pairs(x, faces, tri_part=tri_part))
            if n >= found:
                return first
    return first
