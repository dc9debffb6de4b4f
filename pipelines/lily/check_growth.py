"""Exact checks of the growth-map lily (the `growth-check` stage; Ijiri et al. sec. 6.1).

Usage: python check_growth.py FRAMES_DIR [COLUMN_DIR]
       (FRAMES_DIR = build/lily/growth/canopy, COLUMN_DIR = build/lily/growth/column_obj)

Every keyframe: the exact static triangle-triangle test (inflo.tools.collide.intersecting_pairs;
touching counts) must find no pair, and the topology must be the bud's. Listed at frames 1, 20,
40, 60, 100: the joint angle (rotation of each tepal's base rows from the bud, rigid fit: +23 deg
from step 1 to 60, then constant), the midrib tip's elevation (degrees above the horizontal, mean
over the tepals: the bud's tips point up, the reflexed midrib's down) and the lamina's
cross-section at its widest row (signed sagitta / chord: 0 is flat, > 0 curled towards the
inner side as in the bud, < 0 curled backwards), the tepal's slenderness (midrib length over the
widest row's developed width) and twist (the largest turn of a row's chord about the midrib from
the widest row to 0.9 of the length). The open tepals must be broad and untwisted as in fig. 1:
at the last keyframe slenderness at most SLENDER and twist at most TWIST for every tepal. With COLUMN_DIR, every keyframe's tepals are
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

LISTED = (1, 20, 40, 60, 75, 100)
SLENDER = 3.6  # an Asiatic lily's tepal is about 3 times as long as wide
TWIST = 25.0  # degrees


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
        sag.append(row_sagitta(x, grid, int(0.45 * (grid.shape[0] - 1))))
    return np.array(joint), np.array(tip), np.array(sag)


def row_sagitta(x, grid, j) -> float:
    """Signed sagitta over chord of the tepal's row j (0 flat, > 0 curled towards the inner side)."""
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
    return float(off[k] @ inner) / float(np.linalg.norm(chord))


def _chord_across(x, grid, mid, j):
    """Row j's chord, unit, with the midrib's tangent there projected out; and the tangent."""
    t = mid[min(j + 1, len(mid) - 1)] - mid[max(j - 1, 0)]
    t = t / np.linalg.norm(t)
    c = x[grid[j, -1]] - x[grid[j, 0]]
    c = c - (c @ t) * t
    return c / np.linalg.norm(c), t


def breadth(x, tepals):
    """Per tepal: (slenderness, twist in degrees). Slenderness is the midrib's arc length over the
    widest row's arc length across; twist the largest angle between a row's chord and the widest
    row's chord (each taken across the midrib's tangent at its row), rows from the widest to 0.9
    of the length: a flat or evenly curved tepal 0, a ribbon's tip tens of degrees."""
    out = []
    for _kind, grid in tepals:
        nv, nu = grid.shape
        mid = x[grid[:, nu // 2]]
        length = np.linalg.norm(np.diff(mid, axis=0), axis=1).sum()
        widths = np.array([np.linalg.norm(np.diff(x[grid[j]], axis=0), axis=1).sum() for j in range(nv)])
        jw = int(np.argmax(widths))
        c0, _ = _chord_across(x, grid, mid, jw)
        twist = 0.0
        for j in range(jw, int(0.9 * (nv - 1)) + 1):
            c, t = _chord_across(x, grid, mid, j)
            a = c0 - (c0 @ t) * t
            a = a / np.linalg.norm(a)
            twist = max(twist, math.degrees(math.acos(np.clip(a @ c, -1.0, 1.0))))
        out.append((length / widths[jw], twist))
    return np.array(out)


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
            b = breadth(m.vertices, tepals)
            print(f"frame {i + 1:3d}: {n} intersecting pairs; joint angle {j.mean():.2f} deg (sepals {j[:3].mean():.2f}, "
                  f"petals {j[3:].mean():.2f}); midrib tip elevation {t.mean():.1f} deg; lamina sagitta/chord "
                  f"{s.mean():.3f}; slenderness {b[:, 0].max():.2f}, twist {b[:, 1].max():.0f} deg"
                  + ("" if same else "; TOPOLOGY CHANGED"))
    print(f"every keyframe ({len(paths)}, {len(first.faces)} triangles) tested"
          + (f"; tepals against the column: {col_pairs} intersecting pairs" if cols else ""))
    b = breadth(read_obj(paths[-1]).vertices, tepals)
    broad = b[:, 0].max() <= SLENDER and b[:, 1].max() <= TWIST
    print(f"open tepals (last keyframe): slenderness {b[:, 0].min():.2f}-{b[:, 0].max():.2f} (at most {SLENDER}), "
          f"twist {b[:, 1].min():.0f}-{b[:, 1].max():.0f} deg (at most {TWIST:.0f})")
    if bad:
        print(f"FAILED: {bad} intersecting pairs or changes")
    elif not broad:
        print("FAILED: the open tepals are straps or ribbons, not broad and untwisted (fig. 1)")
    else:
        print("OK: no intersecting triangle pairs; broad, untwisted tepals")
    return int(bad > 0 or not broad)


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3):
        sys.exit("usage: python check_growth.py FRAMES_DIR [COLUMN_DIR]")
    sys.exit(main(*map(Path, sys.argv[1:])))
