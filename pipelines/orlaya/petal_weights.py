"""Petal weight files (formats/weights.md) of the orlaya florets: which vertices grow, and how much,
with a placement's petal factor (dimorph --petal-size; fccompose scales local vertex v by
1 + w_v (f - 1) about the floret's origin: only the petals grow, thesis fig. 6.4c).

Usage: python petal_weights.py OPEN.obj EXPONENT OUT.weights
       python petal_weights.py --fixed FIRST.obj OUT.weights

The second form writes the floret's fixed vertices (formats/weights.md, fccompose's ``weight:``):
its base rows (every organ's row 0 lies on y = 0: the claws, the stamens' feet, the stylopodium's
base) and the whole stylopodium (material ``mtl1``), which stands on the pedicel's tip: left free,
large petals lying over it pressed it flat into the pedicel below (draft, frames 9-10).

OPEN.obj is the floret's open frame (polygonize output, local frame: +Y the axis, +X outward).
Each vertex's weight is ``ramp(r) * ((1 + cos theta) / 2) ** EXPONENT``:

- only the petals' vertices (material ``mtl0``): the stamens and the stylopodium weigh 0;
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


def petal_weights(vertices: np.ndarray, exponent: float, petal: np.ndarray | None = None) -> np.ndarray:
    """``petal``: a mask of the petals' vertices (the others, stamens and stylopodium, weigh 0)."""
    r = np.hypot(vertices[:, 0], vertices[:, 2])
    s = np.clip((r - R0) / (R1 - R0), 0.0, 1.0)
    ramp = s * s * (3.0 - 2.0 * s)
    cos = np.divide(vertices[:, 0], r, out=np.ones_like(r), where=r > 1e-12)
    w = ramp * ((1.0 + cos) / 2.0) ** float(exponent)
    return w if petal is None else np.where(petal, w, 0.0)


def petal_mask(mesh) -> np.ndarray:
    """The vertices of the petals' faces (material ``mtl0``, make_keys.py): the stamens (which reach
    past the claws) and the stylopodium never grow."""
    mask = np.zeros(len(mesh.vertices), bool)
    if "mtl0" in list(mesh.materials):
        k = list(mesh.materials).index("mtl0")
        mask[np.unique(mesh.faces[mesh.face_material == k])] = True
    return mask


def fixed_ids(mesh) -> np.ndarray:
    """The base rows (the lowest vertices) and every stylopodium vertex (material ``mtl1``)."""
    y = mesh.vertices[:, 1]
    keep = y <= y.min() + 1e-9 * max(float(np.ptp(mesh.vertices, axis=0).max()), 1.0)
    if "mtl1" in list(mesh.materials):
        k = list(mesh.materials).index("mtl1")
        keep[np.unique(mesh.faces[mesh.face_material == k])] = True
    return np.nonzero(keep)[0]


def main(argv) -> int:
    if len(argv) == 3 and argv[0] == "--fixed":
        ids = fixed_ids(read_obj(argv[1]))
        rows = [" ".join(str(int(i)) for i in ids[k:k + 20]) for k in range(0, len(ids), 20)]
        write_text_atomic(argv[2], f"# base rows and stylopodium ({len(ids)} vertices, fixed); written by "
                          f"petal_weights.py --fixed\n" + "\n".join(rows) + "\n")
        return 0
    if len(argv) != 3:
        print(__doc__.strip().splitlines()[4], file=sys.stderr)
        return 2
    mesh = read_obj(argv[0])
    v = mesh.vertices
    w = petal_weights(v, float(argv[1]), petal_mask(mesh))
    rows = [f"{i} {x:.6f}" for i, x in enumerate(w) if x > 0.0]
    write_text_atomic(argv[2], f"# petal weights (exponent {argv[1]}) of {len(v)} vertices; written by "
                      f"petal_weights.py\n" + "\n".join(rows) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
