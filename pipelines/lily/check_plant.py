"""Exact static intersection test of the lily plant (the `plant` target's check).

Usage: python check_plant.py PLANT_BUILD [FRAME ...]   (PLANT_BUILD = build/lily_plant; frames 1-based,
                                                        default: every written frame and the sheet's)

The shared plant check, :mod:`inflo.tools.plant.check`, on the lily plant: every written plant
frame (the five flowers' ``flower_K/`` frames with ``body.obj``: stem, leaves, pedicels) and every
frame of the contact sheet (the smoothed, painted tepals of ``sheet_tepals/`` and the columns of
``sheet_columns/`` with the body) as one mesh, exact test, touching counts; only the pairs of
parts joined by construction are not counted (a column with itself, a column with its own
pedicel, the stem with a pedicel or a leaf). Exits 1 on any intersecting pair.
"""
from __future__ import annotations

import sys
from pathlib import Path

from inflo.tools.plant.check import main

if __name__ == "__main__":
    if len(sys.argv) < 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1]), [int(a) for a in sys.argv[2:]] or None))
