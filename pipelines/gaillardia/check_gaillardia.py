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
  ray floret's limb (its flared yellow mouth, not fixed, tucked into the tube's mouth:
  make_keys.INSET inside the wall, make_keys.TUCK back from the rim) that touches its tube or has
  come off it: in every frame, for every ray floret, the smallest distance between the limb's and
  the tube's vertices must be at least limb_gap[0] and the largest distance from a vertex of the
  limb's base ring to the tube at most limb_gap[1] (floret units); no phase effect: at two thirds
  of the run, the disk florets' height above the receptacle (in floret units: bud 0.8, open with
  the anthers up 1.1, late with the pistil up 1.4) must fall from the rim to the centre (Spearman
  rank correlation with the distance from the centre > 0.5), and some inner florets must still be
  in bud (lower than 1.0: the anther tube not yet risen above the corolla);
- **a dense disk**: the share of the receptacle left in view from above (Y) at the last frame
  (``1 - view_coverage(canopy, axis=1, region=receptacle)``) must be at most receptacle_visible;
- **development the right way round**: no ray floret or bract open (at least ``open`` of its
  development window) before ``open_after`` of the disk florets have emerged; every ray floret
  open at the hero frame (species.toml ``hero``, the phase-effect still);
- **growth**: the head (its outermost floret bases) must grow at least three times in diameter
  from the first frame with florets to the last (fig. 9.4: "the dramatic, yet stable change in
  size due to the dynamic phyllotaxis").
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from make_keys import INSET, M_LIMB, M_TUBE, RES, TUCK
from scipy.spatial import cKDTree

from inflo.formats.obj import read_obj
from inflo.formats.species import species_of
from inflo.tools.species.checks import (
    check_back,
    check_head,
    check_individuals,
    check_phase,
    floret_faces,
    receptacle_body,
    view_coverage,
)

# the species' facts: the [check] table of species.toml (formats/species.md)
SPECIES = species_of(__file__)
CHECK = SPECIES.check
RAYS = CHECK["rays"]
LIMB_GAP = tuple(CHECK["limb_gap"])
RECEPTACLE_VISIBLE = CHECK["receptacle_visible"]
OPEN = CHECK["open"]
OPEN_AFTER = CHECK["open_after"]
GROWTH = CHECK["growth"]
BUD = CHECK["bud"]


def limb_gaps(mesh, frame_rba, scene, rays, ring: int) -> np.ndarray:
    """Per ray floret: (the smallest distance between its limb's and its tube's vertices, the
    largest distance from a vertex of the limb's base ring (its first ``ring`` vertices: the
    polygonized rows come in order) to the tube's vertices), in floret units."""
    rows = {int(i): k for k, i in enumerate(frame_rba.ids)}
    mat = np.array([int(m.replace("mtl", "")) if m.startswith("mtl") else -1 for m in mesh.materials])
    fmat = mat[mesh.face_material]
    out = []
    for pid, faces in floret_faces(mesh).items():
        if pid not in rays or pid not in rows:
            continue
        tube = np.unique(mesh.faces[faces[fmat[faces] == M_TUBE]])
        limb = np.unique(mesh.faces[faces[fmat[faces] == M_LIMB]])
        d = cKDTree(mesh.vertices[tube]).query(mesh.vertices[limb])[0]
        unit = float(frame_rba.scale[rows[pid], 0]) * float(scene.placements[pid].scale[0])
        out.append((d.min() / unit, d[:ring].max() / unit))
    return np.array(out).reshape(-1, 2)


def development(p, frame: int) -> float:
    """A placement's development (0-1 of its window) at a frame."""
    return float(np.clip((frame - p.frame_start) / max(p.frame_end - p.frame_start, 1e-9), 0.0, 1.0))


def main(build: Path) -> int:
    failures = []
    gaps = []
    from inflo.formats.rba import read_rba
    from inflo.formats.scn import read_scn

    scene = read_scn(Path(build) / "head" / "typed.scn")
    rays = {k for k, p in enumerate(scene.placements) if p.type == "ray"}
    rba = sorted((Path(build) / "head" / "rba").glob("*.rba"))

    quality = (Path(build) / "quality.txt").read_text().strip()
    ring = int(RES[quality]["limb"][1])  # the limb's rows have eta vertices

    def limbs_on_tubes(i, mesh):
        g = limb_gaps(mesh, read_rba(rba[min(i, len(rba) - 1)]), scene, rays, ring)
        if len(g):
            gaps.append(g)

    head = check_head(build, rays=RAYS, failures=failures, per_frame=limbs_on_tubes)
    check_individuals(head, failures=failures)  # no clones (gaillardia.fcc's variation lines)
    g = np.concatenate(gaps) if gaps else np.zeros((0, 2))
    if len(g):
        print(f"limb to tube (floret units; the limb's base ring {INSET} inside the tube's wall, {TUCK} inside its "
              f"rim): closest {g[:, 0].min():.4f} (>= {LIMB_GAP[0]}), base ring at most {g[:, 1].max():.4f} from "
              f"the tube (<= {LIMB_GAP[1]})")
        if g[:, 0].min() < LIMB_GAP[0] or g[:, 1].max() > LIMB_GAP[1]:
            failures.append(f"a ray floret's limb {g[:, 0].min():.4f} from its tube (>= {LIMB_GAP[0]}), its base ring "
                            f"up to {g[:, 1].max():.4f} from it (<= {LIMB_GAP[1]})")
    else:
        failures.append("no ray floret's limb found in the checked frames")
    check_phase(head, bud=BUD, failures=failures)

    # a dense disk: the receptacle left in view from above at the last frame
    visible = 1.0 - view_coverage(read_obj(head.canopy[-1]), axis=1, region=receptacle_body(read_obj(head.receptacle[-1])))
    print(f"receptacle in view from above at the last frame: {100 * visible:.1f} % (<= {100 * RECEPTACLE_VISIBLE:.1f} %)")
    if visible > RECEPTACLE_VISIBLE:
        failures.append(f"{100 * visible:.1f} % of the receptacle in view from above, expected <= "
                        f"{100 * RECEPTACLE_VISIBLE:.1f} %")

    check_back(head, CHECK["back_in_view"], failures)

    # development the right way round: rays and bracts open with the head, not round a bare meristem
    disk = [p for p in scene.placements if p.type == "disk"]
    for kind in ("ray", "bract"):
        mine = [p for p in scene.placements if p.type == kind]
        first = next((f for f in range(len(head.canopy)) if any(development(p, f) >= OPEN for p in mine)), None)
        if first is None:
            failures.append(f"no {kind} open (development >= {OPEN}) by the last frame")
            continue
        share = sum(p.emergence <= first for p in disk) / len(disk)
        outer = max(development(p, first) for p in disk)
        print(f"first {kind} open (development >= {OPEN}) at frame {first}: {100 * share:.0f} % of the disk florets "
              f"emerged (>= {100 * OPEN_AFTER:.0f} %), the oldest at {outer:.2f} of its development")
        if share < OPEN_AFTER:
            failures.append(f"a {kind} open at frame {first} with {100 * share:.0f} % of the disk florets emerged")
    hero = int(SPECIES.setting(quality, "hero"))
    closed = sum(development(p, hero) < OPEN for p in scene.placements if p.type == "ray")
    print(f"hero frame {hero}: {RAYS - closed} of {RAYS} ray florets open")
    if closed:
        failures.append(f"{closed} ray florets not open at the hero frame {hero}")

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
