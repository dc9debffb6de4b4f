"""Exact static intersection test of the lily build (the `check` stage of the Makefile).

Usage: python check_lily.py BUILD_DIR   (BUILD_DIR = build/lily)

Prints, for every canopy frame (every tenth listed) and for every smoothed frame, the number of intersecting
triangle pairs (inflo.tools.collide.intersecting_pairs; touching counts) -- among the tepals and
between the tepals and the pistil/stamens/receptacle -- and the tepal joint angles; exits 1 when
any of those frames has an intersection.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.tools.collide import intersecting_pairs, intersecting_pairs_between

# polygonize's vertex order: sepals (3 copies of 19 rows x 17), then petals (3 copies of 20 x 19)
TEPALS = [(c * 323, 17) for c in range(3)] + [(969 + c * 380, 19) for c in range(3)]


def joint_angles(vertices: np.ndarray) -> np.ndarray:
    """Angle (degrees) between the flower axis (+Y) and each tepal's claw: the midrib from row 0
    to row 1 (both fixed on the receptacle by lily.weights; at v = 0 the B-spline surface is
    tangent to the first control segment, which the key poses keep and `tilt` turns)."""
    out = []
    for off, per_row in TEPALS:
        mid = per_row // 2
        a = vertices[off + mid]
        b = vertices[off + per_row + mid]
        d = (b - a) / np.linalg.norm(b - a)
        out.append(math.degrees(math.acos(np.clip(d[1], -1.0, 1.0))))
    return np.array(out)


def cross_pairs(a, b) -> int:
    """Intersecting triangle pairs between the tepals and the pistil/stamens/receptacle (which are
    drawn with the canopy but not simulated: they must stay clear of the tepals)."""
    return len(intersecting_pairs_between(a.vertices, a.faces, b.vertices, b.faces))


def main(build: Path) -> int:
    bad = 0
    canopy = list_obj_sequence(build / "canopy")
    column = list_obj_sequence(build / "column_obj")
    print(f"canopy: {len(canopy)} frames")
    tested = 0
    for i, path in enumerate(canopy):  # every written frame is tested; every tenth (and 60) listed
        mesh = read_obj(path)
        n = len(intersecting_pairs(mesh.vertices, mesh.faces, tri_part=mesh.face_group))
        c = cross_pairs(mesh, read_obj(column[i]))
        bad += n + c
        tested += 1
        if i % 10 and i != len(canopy) - 1 and i != 59 and not (n or c):
            continue
        ang = joint_angles(mesh.vertices)
        print(f"  frame {i + 1:3d}: {len(mesh.faces)} triangles, {n} intersecting pairs, {c} with the column, "
              f"joint angle {ang.mean():.2f} deg (sepals {ang[:3].mean():.2f}, petals {ang[3:].mean():.2f})")
    print(f"every canopy frame ({tested}) tested")
    smooth = list_obj_sequence(build / "smooth")
    print(f"smooth: {len(smooth)} frames")
    for path in smooth:
        mesh = read_obj(path)
        n = len(intersecting_pairs(mesh.vertices, mesh.faces, tri_part=mesh.face_group))
        bad += n
        print(f"  {path.name}: {len(mesh.faces)} triangles, {n} intersecting pairs")
    print("OK: no intersecting triangle pairs" if bad == 0 else f"FAILED: {bad} intersecting pairs")
    return 0 if bad == 0 else 1


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1])))
