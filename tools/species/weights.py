"""Weight files (fixed vertices, formats/weights.md) of the species builds' fccompose runs.

    python -m inflo.tools.species.weights base FRAME.obj OUT.weights
        the vertices of a floret OBJ (polygonize output, local frame) on its base row: those at the
        lowest local height (every key pose keeps row 0 of each organ at y = 0), so the floret stays
        attached to the receptacle while collisions push its petals;
    python -m inflo.tools.species.weights all FRAME.obj OUT.weights
        every vertex of an OBJ (a part that moves only as its animation says: the sunflower's
        receptacle);
    python -m inflo.tools.species.weights head SCENE.scn OUT.weights ID=FRAME.obj:IDS.weights [ID=...]
        the fixed vertices of the head canopy written by fccompose: the placements of SCENE.scn in
        order, each one the vertices of its id's OBJ, its fixed ids shifted by the vertices before it
        (fccompose's vertex order: scene placements in file order, each template's vertex order).
"""
from __future__ import annotations

import os
import sys

import numpy as np

from inflo.formats.atomic import write_text_atomic
from inflo.formats.obj import read_obj
from inflo.formats.scn import read_scn
from inflo.formats.weights import read_weight_file


def base_ids(obj_path) -> np.ndarray:
    v = read_obj(obj_path).vertices
    y = v[:, 1]
    tol = 1e-9 * max(float(np.ptp(v, axis=0).max()), 1.0)
    return np.nonzero(y <= y.min() + tol)[0]


def _rel(name, out) -> str:
    """``name`` relative to the folder of the output file ``out`` (no absolute path in the file,
    so it reads the same in every checkout; the goldens compare it)."""
    return os.path.relpath(name, os.path.dirname(os.path.abspath(out)))


def write_ids(path, ids, comment: str) -> None:
    rows = [" ".join(str(int(i)) for i in ids[k:k + 20]) for k in range(0, len(ids), 20)]
    write_text_atomic(path, f"# {comment}\n" + "\n".join(rows) + "\n")


def main(argv) -> int:
    if len(argv) >= 3 and argv[0] == "base":
        ids = base_ids(argv[1])
        write_ids(argv[2], ids, f"base row of {_rel(argv[1], argv[2])} ({len(ids)} vertices); written by weights.py")
        return 0
    if len(argv) >= 3 and argv[0] == "all":
        ids = np.arange(len(read_obj(argv[1]).vertices))
        write_ids(argv[2], ids, f"every vertex of {_rel(argv[1], argv[2])} ({len(ids)} vertices); written by weights.py")
        return 0
    if len(argv) >= 4 and argv[0] == "head":
        scene = read_scn(argv[1])
        table = {}
        for spec in argv[3:]:
            pid, rest = spec.split("=", 1)
            obj, wfile = rest.split(":", 1)
            n = len(read_obj(obj).vertices)
            table[int(pid)] = (n, read_weight_file(wfile, n))
        out, offset = [], 0
        for p in scene.placements:
            n, fixed = table[p.id]
            out.append(fixed + offset)
            offset += n
        ids = np.concatenate(out)
        write_ids(argv[2], ids, f"floret bases of the head canopy of {_rel(argv[1], argv[2])} ({len(scene)} florets, "
                                f"{offset} vertices); written by weights.py")
        return 0
    print(__doc__.strip().splitlines()[2], file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
