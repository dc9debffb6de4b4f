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

import sys
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from inflo.formats.species import species_of
from inflo.tools.species.checks import check_head, check_phase, floret_faces
from make_keys import GAP, M_LIMB, M_TUBE

# the species' facts: the [check] table of species.toml (formats/species.md)
CHECK = species_of(__file__).check
RAYS = CHECK["rays"]
LIMB_GAP = tuple(CHECK["limb_gap"])
GROWTH = CHECK["growth"]
BUD = CHECK["bud"]


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
    gaps = []
    from inflo.formats.rba import read_rba
    from inflo.formats.scn import read_scn

    scene = read_scn(Path(build) / "head" / "typed.scn")
    rays = {k for k, p in enumerate(scene.placements) if p.type == "ray"}
    rba = sorted((Path(build) / "head" / "rba").glob("*.rba"))

    def limbs_on_tubes(i, mesh):
        g = limb_gaps(mesh, read_rba(rba[min(i, len(rba) - 1)]), scene, rays)
        if len(g):
            gaps.append(g)

    head = check_head(build, rays=RAYS, failures=failures, per_frame=limbs_on_tubes)
    g = np.concatenate(gaps) if gaps else np.zeros(0)
    if len(g):
        print(f"limb to tube (floret units, the key poses' gap {GAP}): {g.min():.4f}-{g.max():.4f}")
        if g.min() < LIMB_GAP[0] * GAP or g.max() > LIMB_GAP[1] * GAP:
            failures.append(f"a ray floret's limb {g.min():.4f}-{g.max():.4f} floret units from its tube, "
                            f"outside [{LIMB_GAP[0]}, {LIMB_GAP[1]}] x {GAP}")
    else:
        failures.append("no ray floret's limb found in the checked frames")
    check_phase(head, bud=BUD, failures=failures)

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
