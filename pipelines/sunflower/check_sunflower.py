"""Checks of the sunflower build (the `check` stage of the Makefile).

Usage: python check_sunflower.py BUILD_DIR   (BUILD_DIR = build/sunflower)

Prints, and fails (exit 1) on any of:

- **intersections**: intersecting triangle pairs (inflo.tools.collide, exact static test; touching
  counts) of every canopy frame, and between every frame and the receptacle
  under them (head/receptacle/, not simulated: the florets must stand clear of it);
- **shape**: an output frame whose edges leave [0.5, 1.5] x their rest length (fccompose's log.csv,
  ``min_edge_stretch``/``max_edge_stretch``);
- **florets missing**: a placement of the head that is not in the last frame;
- **the species' facts**: not 34 ray florets (thesis ch. 9: "the emergent number of ray florets in
  the model (34) is a Fibonacci number"); a ray floret not on the margin (closer to the centre than
  the outermost tenth of the disk florets); no phase effect: at two thirds of the run, the disk
  florets' height above the receptacle (in floret units: bud 0.8, open with the anthers up 1.1,
  late with the pistil up 1.5) must fall from the rim to the centre (Spearman rank correlation
  with the distance from the centre > 0.5), and some inner florets must still be in bud.
"""
from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.formats.rba import read_rba
from inflo.formats.scn import read_scn
from inflo.tools.collide import intersecting_pairs, intersecting_pairs_between

RAYS = 34
BOUNDS = (0.5, 1.5)


def floret_heights(mesh, frame_rba, scene) -> dict:
    """Height of each floret's highest vertex above its base, along its axis, in floret units."""
    rows = {int(i): k for k, i in enumerate(frame_rba.ids)}
    out = {}
    faces_of = {}
    for g, name in enumerate(mesh.groups):
        if name.startswith("floret_"):
            faces_of[int(name.split("_")[1])] = np.nonzero(mesh.face_group == g)[0]
    for pid, faces in faces_of.items():
        if pid not in rows or scene.placements[pid].kind != "rba":
            continue
        r = rows[pid]
        v = mesh.vertices[np.unique(mesh.faces[faces])]
        up = frame_rba.up[r] / np.linalg.norm(frame_rba.up[r])
        scale = float(frame_rba.scale[r, 1]) * float(scene.placements[pid].scale[1])
        out[pid] = float(((v - frame_rba.pos[r]) @ up).max()) / scale
    return out


def main(build: Path) -> int:
    failures = []
    scene = read_scn(build / "head" / "typed.scn")
    types = [p.type for p in scene.placements]
    canopy = list_obj_sequence(build / "canopy")
    receptacle = list_obj_sequence(build / "head" / "receptacle")
    print(f"canopy: {len(canopy)} frames; head: {len(scene)} placements "
          f"({types.count('disk')} disk, {types.count('ray')} ray, {types.count('bract')} bracts)")

    # intersections, within the canopy and with the receptacle
    # every written frame is tested (the written file is what is promised collision-free); every
    # tenth frame, the last and any frame with an intersection are listed
    total_pairs = total_rec = 0
    for i, path in enumerate(canopy):
        mesh = read_obj(path)
        n = len(intersecting_pairs(mesh.vertices, mesh.faces))
        rec = read_obj(receptacle[min(i, len(receptacle) - 1)])
        nr = len(intersecting_pairs_between(mesh.vertices, mesh.faces, rec.vertices, rec.faces))
        total_pairs += n
        total_rec += nr
        if n or nr or i % 10 == 0 or i == len(canopy) - 1:
            print(f"  frame {i:3d}: {len(mesh.faces)} triangles, {len(mesh.groups)} florets, {n} intersecting pairs, "
                  f"{nr} with the receptacle")
        if n or nr:
            failures.append(f"frame {i}: {n} intersecting pairs, {nr} with the receptacle")
    last = mesh
    print(f"every frame ({len(canopy)}) tested: {total_pairs} intersecting pairs, {total_rec} with the receptacle")

    # shape: fccompose's per-frame stretch figures
    with open(build / "canopy" / "log.csv", newline="") as fh:
        log = list(csv.DictReader(fh))
    lo = min(float(r["min_edge_stretch"]) for r in log)
    hi = max(float(r["max_edge_stretch"]) for r in log)
    out = [r["frame"] for r in log if float(r["min_edge_stretch"]) < BOUNDS[0] or float(r["max_edge_stretch"]) > BOUNDS[1]]
    print(f"edge stretch over all frames: {lo:.3f}-{hi:.3f} x rest; frames outside [{BOUNDS[0]}, {BOUNDS[1]}]: {len(out)}")
    if out:
        failures.append(f"{len(out)} frames with edges outside {BOUNDS} x rest (frames {', '.join(out[:5])} ...)")

    # every floret present at the end
    present = {int(g.split("_")[1]) for g in last.groups if g.startswith("floret_")}
    missing = sorted(set(range(len(scene))) - present)
    print(f"florets in the last frame: {len(present)} of {len(scene)}")
    if missing:
        failures.append(f"{len(missing)} florets missing at the end (e.g. {missing[:5]})")

    # the species' facts: 34 rays, on the margin
    pos = scene.arrays()["pos"]
    centre = scene.groups[0].centre if 0 in scene.groups else pos.mean(axis=0)
    radius = np.linalg.norm((pos - centre)[:, [0, 2]], axis=1)
    t = np.array(types)
    n_rays = int((t == "ray").sum())
    disk_r = radius[t == "disk"]
    rim = float(np.quantile(disk_r, 0.9))
    inner_rays = int((radius[t == "ray"] < rim).sum())
    print(f"ray florets: {n_rays} (expected {RAYS}); closest to the centre at {radius[t == 'ray'].min():.3f}, "
          f"the outermost tenth of the disk florets from {rim:.3f}")
    if n_rays != RAYS:
        failures.append(f"{n_rays} ray florets, expected {RAYS}")
    if inner_rays:
        failures.append(f"{inner_rays} ray florets inside the outermost tenth of the disk florets")

    # the phase effect at two thirds of the run
    k = (2 * len(canopy)) // 3
    frame_rba = read_rba(build / "head" / "rba" / f"{min(k, len(list((build / 'head' / 'rba').glob('*.rba'))) - 1):04d}.rba")
    heights = floret_heights(read_obj(canopy[k]), frame_rba, scene)
    disk = [p for p in heights if types[p] == "disk"]
    h = np.array([heights[p] for p in disk])
    rho = float(spearmanr(radius[disk], h).statistic) if len(disk) > 2 else float("nan")
    buds = int((h < 0.95).sum())
    print(f"phase effect at frame {k}: {len(disk)} disk florets, height {h.min():.2f}-{h.max():.2f} floret units, "
          f"rank correlation with the distance from the centre {rho:.2f}, {buds} still in bud (height < 0.95)")
    if not rho > 0.5:
        failures.append(f"no phase effect at frame {k}: rank correlation {rho:.2f}")
    if buds == 0:
        failures.append(f"no disk floret in bud at frame {k}")

    print("OK" if not failures else "FAILED: " + "; ".join(failures))
    return 0 if not failures else 1


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1])))
