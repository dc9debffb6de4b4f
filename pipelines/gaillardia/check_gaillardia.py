"""Checks of the gaillardia build (the `check` stage of the Makefile).

Usage: python check_gaillardia.py BUILD_DIR   (BUILD_DIR = build/gaillardia)

Prints, and fails (exit 1) on any of:

- **intersections**: intersecting triangle pairs (inflo.tools.collide, exact static test; touching
  counts) of every canopy frame, and between every frame and the receptacle
  under them (head/receptacle/, not simulated: the florets must stand clear of it);
- **shape**: an output frame whose edges leave [0.5, 1.5] x their rest length (fccompose's log.csv,
  ``min_edge_stretch``/``max_edge_stretch``);
- **florets missing**: a placement of the head that is not in the last frame;
- **the species' facts**: not 21 ray florets (thesis ch. 9: "The emergent number of ray florets in
  the model (21) is consistent with their numerical canalization in real Gaillardia heads"); a ray
  floret not on the margin (closer to the centre than the outermost tenth of the disk florets); a
  ray floret's limb (its flared yellow mouth, not fixed) that has come off its tube, or touches
  it: in the checked frames the smallest distance between the two, in floret units, must stay
  within [0.3, 2] x the key poses' gap (make_keys.GAP); no phase effect: at two thirds of the
  run, the disk florets' height above the receptacle (in floret units: bud 0.8, open with the
  anthers up 1.1, late with the pistil up 1.5) must fall from the rim to the centre (Spearman rank
  correlation with the distance from the centre > 0.5), and some inner florets must still be in
  bud (lower than 1.0: the anther tube not yet risen above the corolla);
- **growth**: the head (its outermost floret bases) must grow at least three times in diameter
  from the first frame with florets to the last (fig. 9.4: "the dramatic, yet stable change in
  size due to the dynamic phyllotaxis").
"""
from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree
from scipy.stats import spearmanr

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.formats.rba import read_rba
from inflo.formats.scn import read_scn
from inflo.tools.collide import intersecting_pairs, intersecting_pairs_between

sys.path.insert(0, str(Path(__file__).resolve().parent))
from make_keys import GAP, M_LIMB, M_TUBE  # noqa: E402

RAYS = 21
BOUNDS = (0.5, 1.5)
LIMB_GAP = (0.3, 2.0)
GROWTH = 3.0
# a disk floret is in bud below this height (floret units): the bud is 0.78 high, the anther tube
# rises above the corolla (0.9) to 1.12 by the open key pose (developmental time 0.55)
BUD = 1.0


def floret_faces(mesh) -> dict:
    """Face indices of each floret_<placement> group."""
    out = {}
    for g, name in enumerate(mesh.groups):
        if name.startswith("floret_"):
            out[int(name.split("_")[1])] = np.nonzero(mesh.face_group == g)[0]
    return out


def floret_heights(mesh, frame_rba, scene) -> dict:
    """Height of each floret's highest vertex above its base, along its axis, in floret units."""
    rows = {int(i): k for k, i in enumerate(frame_rba.ids)}
    out = {}
    for pid, faces in floret_faces(mesh).items():
        if pid not in rows or scene.placements[pid].kind != "rba":
            continue
        r = rows[pid]
        v = mesh.vertices[np.unique(mesh.faces[faces])]
        up = frame_rba.up[r] / np.linalg.norm(frame_rba.up[r])
        scale = float(frame_rba.scale[r, 1]) * float(scene.placements[pid].scale[1])
        out[pid] = float(((v - frame_rba.pos[r]) @ up).max()) / scale
    return out


def limb_gaps(mesh, frame_rba, scene, rays) -> np.ndarray:
    """Smallest distance between each ray floret's limb and its tube, in floret units."""
    rows = {int(i): k for k, i in enumerate(frame_rba.ids)}
    mat = np.array([int(m.replace("mtl", "")) if m.startswith("mtl") else -1 for m in mesh.materials])
    fmat = mat[mesh.face_material]
    out = []
    for pid, faces in floret_faces(mesh).items():
        if pid not in rays or pid not in rows:
            continue
        tube = np.unique(mesh.faces[faces[fmat[faces] == M_TUBE]])
        limb = np.unique(mesh.faces[faces[fmat[faces] == M_LIMB]])
        d = cKDTree(mesh.vertices[tube]).query(mesh.vertices[limb])[0].min()
        out.append(d / (float(frame_rba.scale[rows[pid], 0]) * float(scene.placements[pid].scale[0])))
    return np.array(out)


def main(build: Path) -> int:
    failures = []
    scene = read_scn(build / "head" / "typed.scn")
    types = [p.type for p in scene.placements]
    rays = {k for k, t in enumerate(types) if t == "ray"}
    canopy = list_obj_sequence(build / "canopy")
    receptacle = list_obj_sequence(build / "head" / "receptacle")
    rba = sorted((build / "head" / "rba").glob("*.rba"))
    print(f"canopy: {len(canopy)} frames; head: {len(scene)} placements "
          f"({types.count('disk')} disk, {types.count('ray')} ray, {types.count('bract')} bracts)")

    # intersections, within the canopy and with the receptacle; the limbs on their tubes
    gaps = []
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
        g = limb_gaps(mesh, read_rba(rba[min(i, len(rba) - 1)]), scene, rays)
        if len(g):
            gaps.append(g)
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

    # the species' facts: 21 rays, on the margin, their limbs on their tubes
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
    g = np.concatenate(gaps) if gaps else np.zeros(0)
    if len(g):
        print(f"limb to tube (floret units, the key poses' gap {GAP}): {g.min():.4f}-{g.max():.4f}")
        if g.min() < LIMB_GAP[0] * GAP or g.max() > LIMB_GAP[1] * GAP:
            failures.append(f"a ray floret's limb {g.min():.4f}-{g.max():.4f} floret units from its tube, "
                            f"outside [{LIMB_GAP[0]}, {LIMB_GAP[1]}] x {GAP}")
    else:
        failures.append("no ray floret's limb found in the checked frames")

    # the phase effect at two thirds of the run
    k = (2 * len(canopy)) // 3
    frame_rba = read_rba(rba[min(k, len(rba) - 1)])
    heights = floret_heights(read_obj(canopy[k]), frame_rba, scene)
    disk = [p for p in heights if types[p] == "disk"]
    h = np.array([heights[p] for p in disk])
    rho = float(spearmanr(radius[disk], h).statistic) if len(disk) > 2 else float("nan")
    buds = int((h < BUD).sum())
    print(f"phase effect at frame {k}: {len(disk)} disk florets, height {h.min():.2f}-{h.max():.2f} floret units, "
          f"rank correlation with the distance from the centre {rho:.2f}, {buds} still in bud (height < {BUD})")
    if not rho > 0.5:
        failures.append(f"no phase effect at frame {k}: rank correlation {rho:.2f}")
    if buds == 0:
        failures.append(f"no disk floret in bud at frame {k}")

    # the head's growth: rim radius of the floret bases from the first frame with florets to the last
    rims = []
    for path in (rba[1], rba[-1]):
        f = read_rba(path)
        rims.append(float(np.hypot(f.pos[:, 0], f.pos[:, 2]).max()))
    print(f"head diameter (floret bases): {2 * rims[0]:.3f} at frame 1, {2 * rims[1]:.3f} at the end "
          f"({rims[1] / rims[0]:.1f} x)")
    if rims[1] < GROWTH * rims[0]:
        failures.append(f"the head grew {rims[1] / rims[0]:.1f} x in diameter, expected >= {GROWTH}")

    print("OK" if not failures else "FAILED: " + "; ".join(failures))
    return 0 if not failures else 1


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1])))
