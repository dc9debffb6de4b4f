"""Exact static intersection test of the yarrow build (the `check` stage of the Makefile).

Usage: python check_yarrow.py BUILD_DIR   (BUILD_DIR = build/yarrow)

Prints the number of intersecting triangle pairs (inflo.tools.collide.intersecting_pairs; touching
counts) of the head canopy's last frame, of every canopy frame (every tenth listed), and of the
smoothed last frame; and, for information, the triangle pairs between the canopy's last frame and
the branches (the peduncles end at the heads' receptacle centres, under the florets). Exits 1 when
any canopy frame checked has an intersection.
"""
from __future__ import annotations

import sys
from pathlib import Path

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.tools.collide import intersecting_pairs, intersecting_pairs_between


def count(mesh) -> int:
    return len(intersecting_pairs(mesh.vertices, mesh.faces))


def cross_pairs(a, b) -> int:
    """Intersecting triangle pairs with one triangle in ``a`` and the other in ``b``."""
    return len(intersecting_pairs_between(a.vertices, a.faces, b.vertices, b.faces))


def main(build: Path) -> int:
    bad = 0
    head = list_obj_sequence(build / "head_canopy")
    mesh = read_obj(head[-1])
    n = count(mesh)
    bad += n
    print(f"head canopy, frame {len(head)}: {len(mesh.faces)} triangles, {n} intersecting pairs")
    canopy = list_obj_sequence(build / "canopy")
    print(f"canopy: {len(canopy)} frames")
    for i, path in enumerate(canopy):  # every written frame is tested; every tenth listed
        mesh = read_obj(path)
        n = count(mesh)
        bad += n
        if i % 10 and i != len(canopy) - 1 and not n:
            continue
        print(f"  frame {i + 1:3d}: {len(mesh.faces)} triangles, {len(mesh.groups)} heads, {n} intersecting pairs")
    last = mesh
    print(f"every canopy frame ({len(canopy)}) tested")
    smooth = read_obj(build / "smooth" / "final.obj")
    n = count(smooth)
    bad += n
    print(f"smooth/final.obj: {len(smooth.faces)} triangles, {n} intersecting pairs")
    branches = build / "branches" / "branches.obj"
    if branches.is_file():
        br = read_obj(branches)
        print(f"branches.obj: {len(br.faces)} triangles; {cross_pairs(last, br)} pairs with the last canopy "
              f"frame (information)")
    print("OK: no intersecting triangle pairs" if bad == 0 else f"FAILED: {bad} intersecting pairs")
    return 0 if bad == 0 else 1


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1])))
