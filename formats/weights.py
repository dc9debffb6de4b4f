"""Weight files: the fixed vertices of an ``.fcc`` file's ``weight`` key, and the per-vertex petal
weights of its ``petal weight`` key. Spec: ``formats/weights.md``.

Plain text listing vertex ids, 0-based in OBJ vertex order, separated by blanks, commas or line
breaks; ``#`` starts a comment. The vertices listed stay fixed (inverse mass 0) in ``fccompose``.
"""
from __future__ import annotations

import re

import numpy as np

from .errors import FormatError, read_lines, shorten

__all__ = ["read_weight_file", "read_petal_weight_file"]


def read_weight_file(path, n_vertices: int) -> np.ndarray:
    """Fixed vertex ids of a ``weight`` file (0-based OBJ vertex order), sorted and unique.

    Raises
    ------
    FormatError
        A token that is not a non-negative integer below ``n_vertices``.
    """
    ids = []
    for lineno, line in enumerate(read_lines(path), 1):
        text = line.split("#", 1)[0]
        for tok in re.split(r"[\s,]+", text.strip()):
            if not tok:
                continue
            try:
                v = int(tok)
            except ValueError:
                raise FormatError(path, lineno, "a vertex id (integer)", shorten(tok)) from None
            if not 0 <= v < n_vertices:
                raise FormatError(path, lineno, f"a vertex id in 0..{n_vertices - 1}", shorten(tok))
            ids.append(v)
    return np.unique(np.array(ids, dtype=np.int32))


def read_petal_weight_file(path, n_vertices: int) -> np.ndarray:
    """(n_vertices,) float64 petal weights of a ``petal weight`` file: lines ``vertex_id weight``
    (0-based OBJ vertex order, weight in [0, 1]); vertices not listed weigh 0, ``#`` starts a
    comment.

    Raises
    ------
    FormatError
        A line that is not an id and a weight, an id outside 0..n_vertices-1 or listed twice, a
        weight outside [0, 1].
    """
    w = np.zeros(n_vertices)
    seen = np.zeros(n_vertices, bool)
    for lineno, line in enumerate(read_lines(path), 1):
        toks = line.split("#", 1)[0].split()
        if not toks:
            continue
        if len(toks) != 2:
            raise FormatError(path, lineno, "'vertex_id weight'", shorten(line.strip()))
        try:
            v = int(toks[0])
        except ValueError:
            raise FormatError(path, lineno, "a vertex id (integer)", shorten(toks[0])) from None
        if not 0 <= v < n_vertices:
            raise FormatError(path, lineno, f"a vertex id in 0..{n_vertices - 1}", shorten(toks[0]))
        if seen[v]:
            raise FormatError(path, lineno, "each vertex id once", f"{v} again")
        try:
            x = float(toks[1])
        except ValueError:
            raise FormatError(path, lineno, "a weight (number in [0, 1])", shorten(toks[1])) from None
        if not 0.0 <= x <= 1.0:
            raise FormatError(path, lineno, "a weight in [0, 1]", shorten(toks[1]))
        w[v], seen[v] = x, True
    return w
