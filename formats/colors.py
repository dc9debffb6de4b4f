"""Colours of organs for ``canopy-render``, ``canopy-export`` (USD, glTF, MTL) and the viewer: the
botanical palette, material colours, colour files (each species' ``colors.toml``).

Which colour a face gets, first match wins:

1. the OBJ's vertex colours (``v x y z r g b``), when the file has them;
2. the colour given for its input (``--color``, :attr:`RenderOptions.mesh_colors`);
3. its material (``usemtl NAME``): ``NAME`` in the colour file (``--colors``); else the material
   id (``usemtl 3``, ``usemtl mtl3``, ``usemtl mtl_3``: the SCN ``mtl:`` id, inflo's convention)
   in the colour file; else a known organ word in the name (:data:`KEYWORD_COLORS`: ``stem``,
   ``disk``, ``petal``...); else the id's entry of :data:`MATERIAL_PALETTE`; else a palette colour
   chosen from the name (stable across files and runs);
4. the input's automatic colour (:data:`INPUT_PALETTE`, by input position).

A colour file is TOML with one key per material, the value ``[r, g, b]`` in 0..1 or ``"#rrggbb"``
or a colour name::

    3 = [0.95, 0.80, 0.10]     # material id 3 (usemtl 3 / usemtl mtl3)
    disk = "#6b4a1f"           # usemtl disk
    "mtl 7" = "pink"           # any name, quoted
"""
from __future__ import annotations

import re
import tomllib
import zlib
from collections.abc import Mapping

import numpy as np

from inflo.formats.errors import InputError

__all__ = [
    "MATERIAL_PALETTE",
    "INPUT_PALETTE",
    "KEYWORD_COLORS",
    "NAMED_COLORS",
    "parse_color",
    "load_color_file",
    "material_id",
    "material_color",
]

RGB = tuple[float, float, float]

NAMED_COLORS: dict[str, RGB] = {
    "white": (1.0, 1.0, 1.0),
    "black": (0.0, 0.0, 0.0),
    "grey": (0.5, 0.5, 0.5),
    "gray": (0.5, 0.5, 0.5),
    "cream": (0.96, 0.94, 0.86),
    "petal-white": (0.96, 0.95, 0.90),
    "yellow": (0.98, 0.82, 0.20),
    "gold": (0.93, 0.70, 0.15),
    "orange": (0.96, 0.55, 0.18),
    "pink": (0.93, 0.55, 0.68),
    "red": (0.78, 0.16, 0.18),
    "crimson": (0.70, 0.12, 0.22),
    "lilac": (0.72, 0.60, 0.86),
    "purple": (0.50, 0.28, 0.62),
    "blue": (0.35, 0.50, 0.85),
    "brown": (0.45, 0.28, 0.12),
    "green": (0.35, 0.55, 0.22),
    "leaf": (0.24, 0.45, 0.18),
    "olive": (0.62, 0.62, 0.28),
}
"""Colour names accepted wherever a colour is given (sRGB, 0..1)."""

MATERIAL_PALETTE: tuple[RGB, ...] = (
    (0.96, 0.95, 0.90),  # 0 petal white
    (0.98, 0.82, 0.20),  # 1 petal yellow
    (0.93, 0.55, 0.68),  # 2 petal pink
    (0.45, 0.28, 0.12),  # 3 disk brown
    (0.35, 0.55, 0.22),  # 4 stem green
    (0.72, 0.60, 0.86),  # 5 lilac
    (0.96, 0.55, 0.18),  # 6 orange
    (0.24, 0.45, 0.18),  # 7 leaf green
    (0.78, 0.72, 0.35),  # 8 disk yellow-olive
    (0.70, 0.12, 0.22),  # 9 crimson
)
"""Colour of material id k (``usemtl k`` / ``usemtl mtlk``): entry k modulo the length."""

INPUT_PALETTE: tuple[RGB, ...] = (
    (0.95, 0.88, 0.62),  # first input: a warm petal cream
    (0.35, 0.55, 0.22),  # second: stem green (e.g. branch-gen's branches)
    (0.93, 0.55, 0.68),
    (0.45, 0.28, 0.12),
    (0.72, 0.60, 0.86),
    (0.96, 0.55, 0.18),
)
"""Automatic colour of the i-th input (faces without material, no ``--color``)."""

KEYWORD_COLORS: tuple[tuple[tuple[str, ...], RGB], ...] = (
    (("stem", "branch", "stalk", "peduncle", "pedicel", "internode", "axis", "receptacle"), NAMED_COLORS["green"]),
    (("leaf", "sepal", "bract", "involucr"), NAMED_COLORS["leaf"]),
    (("disk", "disc"), NAMED_COLORS["brown"]),
    (("stamen", "anther", "pollen"), (0.80, 0.45, 0.15)),
    (("pistil", "stigma", "style", "carpel"), (0.70, 0.80, 0.45)),
    (("petal", "tepal", "ray", "ligule", "corolla"), MATERIAL_PALETTE[0]),
)
"""Organ words in material names (case-insensitive substring) and their colours."""

_ID = re.compile(r"^(?:mtl|mat|material)?[ _-]?(\d+)$", re.IGNORECASE)
_HEX = re.compile(r"^#?([0-9a-fA-F]{6})$")


def parse_color(value, what: str = "colour") -> RGB:
    """A colour from ``"r,g,b"`` (0..1), ``[r, g, b]``, ``"#rrggbb"`` or a name of :data:`NAMED_COLORS`.

    Raises
    ------
    ValueError
        With a message naming ``what`` and the accepted forms.
    """
    if isinstance(value, str):
        text = value.strip().lower()
        if text in NAMED_COLORS:
            return NAMED_COLORS[text]
        m = _HEX.match(text)
        if m and (text.startswith("#") or not re.fullmatch(r"[0-9.,\s]+", text)):
            h = m.group(1)
            return tuple(int(h[i:i + 2], 16) / 255.0 for i in (0, 2, 4))
        parts = [p for p in re.split(r"[,\s]+", text) if p]
    else:
        try:
            parts = list(value)
        except TypeError:
            parts = []
    try:
        rgb = tuple(float(p) for p in parts)
    except (TypeError, ValueError):
        rgb = ()
    if len(rgb) != 3 or not all(np.isfinite(rgb)) or not all(0.0 <= c <= 1.0 for c in rgb):
        raise ValueError(
            f"{what}: expected r,g,b in 0..1, #rrggbb or a colour name ({', '.join(sorted(NAMED_COLORS))}), "
            f"found {value!r}"
        )
    return rgb


def load_color_file(path) -> dict[str, RGB]:
    """Read a TOML colour file (see the module docstring): material key -> RGB.

    Raises
    ------
    InputError
        Missing file, TOML syntax error (with its line), or a value that is not a colour.
    """
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except FileNotFoundError:
        raise InputError(f"{path}: no such colour file") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a folder, expected a TOML colour file") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path}: expected TOML ('3 = [0.9, 0.8, 0.1]'), {exc}") from None
    out = {}
    for key, value in data.items():
        if isinstance(value, dict):
            raise InputError(f"{path}: expected 'material = colour' lines, found a table [{key}]")
        try:
            out[str(key).strip()] = parse_color(value, f"{path}: key {key!r}")
        except ValueError as exc:
            raise InputError(str(exc)) from None
    return out


def material_id(name: str) -> int | None:
    """The SCN ``mtl:`` id in a material name (``3``, ``mtl3``, ``mtl_3``, ``material-3``) or None."""
    m = _ID.match(name.strip())
    return int(m.group(1)) if m else None


def material_color(name: str, table: Mapping[str, RGB] | None = None) -> RGB:
    """The colour of material ``name`` (rule 3 of the module docstring)."""
    table = table or {}
    key = name.strip()
    if key in table:
        return table[key]
    mid = material_id(key)
    if mid is not None:
        for k in (str(mid), f"mtl{mid}"):
            if k in table:
                return table[k]
    low = key.lower()
    if low in table:
        return table[low]
    if mid is None:
        if low in NAMED_COLORS:
            return NAMED_COLORS[low]
        for words, rgb in KEYWORD_COLORS:
            if any(w in low for w in words):
                return rgb
        return MATERIAL_PALETTE[zlib.crc32(key.encode("utf-8")) % len(MATERIAL_PALETTE)]
    return MATERIAL_PALETTE[mid % len(MATERIAL_PALETTE)]
