"""The ``variation`` line of a ``.fcc`` file: seeded differences between the florets of one type.

``variation: id field value [field value ...]`` (formats/fcc.md, "Individual florets") gives the
spread of each field for the placements of ``animation``/``obj`` ``id``; ``fccompose`` gives every
such floret its own copy of the template, deformed by its own draws
(``inflo.tools.fccompose.variation``). This module holds the line's data and its syntax only.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

#: field -> (largest spread, unit, what it varies): the order of the draws too (a floret's draws
#: are taken for every field in this order, so one field's spread never changes another's values).
FIELDS = {
    "size": (0.5, "fraction", "the whole floret's scale about its base"),
    "length": (0.5, "fraction", "the scale along local +X (a ray's ligule length)"),
    "height": (0.5, "fraction", "the scale along local +Y (the floret's axis)"),
    "width": (0.5, "fraction", "the scale along local Z (a ligule's width)"),
    "droop": (45.0, "degrees", "a bend about local Z growing with the distance from the base: a ray's "
                               "ligule droops or rises, an upright floret leans"),
    "twist": (45.0, "degrees", "a twist about the template's own axis (base to centroid) growing with "
                               "the distance along it"),
    "petal": (0.5, "fraction", "the petal factor (its 'petal weight' file's vertices: lobes, ligules)"),
    "timing": (1000.0, "frames", "the developmental window moved later (or earlier)"),
}


@dataclass(frozen=True)
class Variation:
    """The spreads of one ``variation`` line (each the standard deviation of its field's draws;
    0: the field does not vary) and the seed of its draws."""

    size: float = 0.0
    length: float = 0.0
    height: float = 0.0
    width: float = 0.0
    droop: float = 0.0
    twist: float = 0.0
    petal: float = 0.0
    timing: float = 0.0
    seed: int = 0

    def spreads(self) -> tuple[float, ...]:
        """The spreads in :data:`FIELDS` order."""
        return tuple(float(getattr(self, f)) for f in FIELDS)

    def text(self) -> str:
        """The line's value after the id, as the writer writes it (fields that vary, then the seed)."""
        parts = [f"{f} {getattr(self, f)!r}" for f in FIELDS if getattr(self, f)]
        return " ".join(parts + [f"seed {int(self.seed)}"])


def parse_variation(tokens: list[str], number: Callable[[str], float] = float) -> Variation:
    """A :class:`Variation` from the tokens after the id (``field value`` pairs); ``number`` reads
    one value (the ``.fcc`` reader passes its own, which takes C float suffixes and refuses NaN).

    Raises
    ------
    ValueError
        ``(expected, found)``: an odd count, an unknown or repeated field, a value that is not a
        finite number in the field's range, a seed that is not an integer >= 0.
    """
    if not tokens or len(tokens) % 2:
        raise ValueError("field value pairs after the id (" + ", ".join(list(FIELDS) + ["seed"]) + ")",
                         " ".join(tokens) if tokens else "nothing")
    got: dict = {}
    for name, value in zip(tokens[::2], tokens[1::2]):
        key = name.lower()
        if key not in FIELDS and key != "seed":
            raise ValueError("a field among " + ", ".join(list(FIELDS) + ["seed"]), repr(name))
        if key in got:
            raise ValueError(f"each field once ('{key}' is given twice)", repr(name))
        if key == "seed":
            if not value.isdigit():
                raise ValueError("an integer seed >= 0", repr(value))
            got[key] = int(value)
            continue
        try:
            v = number(value)
        except ValueError:
            raise ValueError(f"a number for '{key}'", repr(value)) from None
        top, unit = FIELDS[key][:2]
        if not math.isfinite(v) or not 0.0 <= v <= top:
            raise ValueError(f"'{key}' in [0, {top:g}] ({unit})", repr(value))
        got[key] = v
    return Variation(**got)
