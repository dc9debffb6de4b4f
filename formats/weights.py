"""Weight files: the fixed vertices of an ``.fcc`` file's ``weight`` key. Spec: ``formats/weights.md``.

Plain text listing vertex ids, 0-based in OBJ vertex order, separated by blanks, commas or line
breaks; ``#`` starts a comment. The vertices listed stay fixed (inverse mass 0) in ``fccompose``.
"""
from __future__ import annotations

import re

import numpy as np

from .errors import FormatError, read_lines, shorten

__all__ = ["read_weight_file"]


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
