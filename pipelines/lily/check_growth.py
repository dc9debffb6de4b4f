"""Exact checks of the growth-map lily (the `growth-check` stage; Ijiri et al. sec. 6.1).

Usage: python check_growth.py FRAMES_DIR [COLUMN_DIR]
       (FRAMES_DIR = build/lily/growth/canopy, COLUMN_DIR = build/lily/growth/column_obj)

Every keyframe: the exact static triangle-triangle test (inflo.tools.collide.intersecting_pairs;
touching counts) must find no pair, and the topology must be the bud's. Listed at frames 1, 20,
40, 60, 100: the joint angle (rotation of each tepal's base rows from the bud, rigid fit: +23 deg
from step 1 to 60, then constant), the midrib tip's elevation (degrees above the horizontal, mean
over the tepals: the bud's tips point up, the reflexed midrib's down) and the lamina's
cross-section at its widest row (signed sagitta / chord: 0 is flat, > 0 curled towards the
inner side as in the bud, < 0 curled backwards). With COLUMN_DIR, every keyframe's tepals are
also tested against the receptacle, pistil, stigma, stamens and anthers of the same frame (no
pair). Exits 1 on any intersection.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numba
import numpy as np
from growth_keys import TEPALS

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.tools.collide import intersecting_pairs, intersecting_pairs_between
from inflo.tools.petal_grow.simulate import shape_match

LISTED = (1, 20, 40, 60, 100)


def grids(mesh):
    """(kind, vertex ids as an (nv, nu) grid) of each tepal, from its group name."""
    for g, name in enumerate(mesh.groups):
        kind = name.split("_")[0]
        ids = np.unique(mesh.faces[mesh.face_group == g])
        yield kind, ids.reshape(TEPALS[kind]["nv"], TEPALS[kind]["nu"])


def measures(bud, x, tepals):
    joint, tip, sag = [], [], []
    for _kind, grid in tepals:
        base = grid[:3].ravel()
        r, _ = shape_match(bud[base], x[base])
        joint.append(math.degrees(math.acos(np.clip((np.trace(r) - 1) / 2, -1, 1))))
        mid = grid[:, grid.shape[1] // 2]
        d = x[mid[-1]] - x[mid[-4]]
        tip.append(math.degrees(math.asin(np.clip(d[1] / np.linalg.norm(d), -1, 1))))
        j = int(0.45 * (grid.shape[0] - 1))
        row = x[grid[j]]
        chord = row[-1] - row[0]
        c = chord / np.linalg.norm(chord)
        off = (row - row[0]) - np.outer((row - row[0]) @ c, c)
        # the inner side: the midrib's direction along the tepal crossed with the chord (u right, v up,
        # counter-clockwise seen from inside), so that a curl towards the inner side counts positive
        along = x[grid[j + 1, grid.shape[1] // 2]] - x[grid[j - 1, grid.shape[1] // 2]]
        inner = np.cross(c, along)
        inner /= np.linalg.norm(inner)
        k = np.argmax(np.abs(off @ inner))
        sag.append(float(off[k] @ inner) / np.linalg.norm(chord))
    return np.array(joint), np.array(tip), np.array(sag)


def main(frames: Path, column: Path | None = None) -> int:
    numba.set_num_threads(1)  # small meshes: one thread is faster (tools/petal_grow/simulate.py, run)
    paths = list_obj_sequence(frames)
    first = read_obj(paths[0])
    tepals = list(grids(first))
    cols = list_obj_sequence(column) if column is not None else []
    if column is not None and len(cols) != len(paths):
        print(f"FAILED: {len(cols)} column frames for {len(paths)} keyframes")
        return 1
    col_pairs = 0
    bad = 0
    for i, p in enumerate(paths):
        m = read_obj(p)
        n = len(intersecting_pairs(m.vertices, m.faces, tri_part=m.face_group))
        same = m.same_topology(first)
        if cols:
            c = read_obj(cols[i])
            k = len(intersecting_pairs_between(m.vertices, m.faces, c.vertices, c.faces))
            col_pairs += k
            n += k
        bad += n + (not same)
        if i + 1 in LISTED or n or not same:
            j, t, s = measures(first.vertices, m.vertices, tepals)
            print(f"frame {i + 1:3d}: {n} intersecting pairs; joint angle {j.mean():.2f} deg (sepals {j[:3].mean():.2f}, "
                  f"petals {j[3:].mean():.2f}); midrib tip elevation {t.mean():.1f} deg; lamina sagitta/chord "
                  f"{s.mean():.3f}" + ("" if same else "; TOPOLOGY CHANGED"))
    print(f"every keyframe ({len(paths)}, {len(first.faces)} triangles) tested"
          + (f"; tepals against the column: {col_pairs} intersecting pairs" if cols else ""))
    print(f"FAILED: {bad} intersecting pairs or changes" if bad else "OK: no intersecting triangle pairs")
    return int(bad > 0)


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3):
        sys.exit("usage: python check_growth.py FRAMES_DIR [COLUMN_DIR]")
    sys.exit(main(*map(Path, sys.argv[1:])))
