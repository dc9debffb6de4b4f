"""Petal weight files (formats/weights.md) of the orlaya florets: which vertices grow, and how much,
with a placement's petal factor (dimorph --petal-size; fccompose scales local vertex v by
1 + w_v (f - 1) about the floret's origin: only the petals grow, thesis fig. 6.4c).

Usage: python petal_weights.py OPEN.obj EXPONENT OUT.weights

OPEN.obj is the floret's open frame (polygonize output, local frame: +Y the axis, +X outward).
Each vertex's weight is ``ramp(r) * ((1 + cos theta) / 2) ** EXPONENT``:

- ``r`` its distance from the axis, ``ramp`` a smoothstep from 0 at the petals' claw (r <= R0) to 1
  at R1: the stylopodium and the claws keep their size, the blades grow;
- ``theta`` its angle about the axis from +X: EXPONENT 0 grows the five petals alike (a five-fold
  floret); EXPONENT > 0 grows the outward petal most, the lateral ones less, the inner ones least
  (a zygomorphic floret, bilaterally symmetric about its X-Y plane). The growth is radial (a vertex
  moves along its own direction from the axis), so petals never grow into each other.
"""
from __future__ import annotations

import sys

import numpy as np

from inflo.formats.atomic import write_text_atomic
from inflo.formats.obj import read_obj

R0, R1 = 0.12, 0.30


def petal_weights(vertices: np.ndarray, exponent: float) -> np.ndarray:
    r = np.hypot(vertices[:, 0], vertices[:, 2])
    s = np.clip((r - R0) / (R1 - R0), 0.0, 1.0)
    ramp = s * s * (3.0 - 2.0 * s)
    cos = np.divide(vertices[:, 0], r, out=np.ones_like(r), where=r > 1e-12)
    return ramp * ((1.0 + cos) / 2.0) ** float(exponent)


def main(argv) -> int:
    if len(argv) != 3:
        print(__doc__.strip().splitlines()[4], file=sys.stderr)
        return 2
    v = read_obj(argv[0]).vertices
    w = petal_weights(v, float(argv[1]))
    rows = [f"{i} {x:.6f}" for i, x in enumerate(w) if x > 0.0]
    write_text_atomic(argv[2], f"# petal weights (exponent {argv[1]}) of {len(v)} vertices; written by "
                      f"petal_weights.py\n" + "\n".join(rows) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
