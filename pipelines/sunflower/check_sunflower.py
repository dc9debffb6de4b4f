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
  with the distance from the centre > 0.5), and some inner florets must still be in bud;
- **development the right way round**: the first ray or bract half open before ``emerged`` of the
  disk florets have emerged (checks.check_development);
- **clones**: a floret type whose extents in the last frame vary (CV) less than ``individual_cv``
  (the .fcc's ``variation`` lines; checks.check_individuals);
- **the disk floret in proportion** (not a bed of pins): in the last template frame (disk_obj/),
  the anther tube's width over the corolla's (the widest ring of each organ) below
  ``anther_width``, or its exserted length (anther top over corolla top) over the corolla's height
  outside ``anther_exserted``; in the last canopy frame, the disk florets seen from above cover
  less than ``disk_cover`` of their silhouette's convex hull (checks.view_coverage: the corollas'
  mouths must touch, a carpet);
- **a bare back**: in the last frame, the receptacle's underside left in view by its phyllaries
  (checks.underside_in_view) from 30 degrees below, the worst of four azimuths, over
  ``back_in_view`` (an involucre of imbricate phyllaries in several series clothes the head's back).
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.formats.species import species_of
from inflo.tools.species.checks import (
    check_back,
    check_development,
    check_head,
    check_individuals,
    check_phase,
    floret_faces,
    view_coverage,
)

# the species' facts: the [check] table of species.toml (formats/species.md)
CHECK = species_of(__file__).check
RAYS = CHECK["rays"]
BUD = CHECK["bud"]


def disk_proportions(build: Path) -> dict:
    """The open disk floret (the last template frame, local frame: +Y its axis): the largest radius
    and the top of its corolla and of its anther tube."""
    mesh = read_obj(list_obj_sequence(build / "disk_obj")[-1])
    organ = np.array([mesh.groups[g].rsplit("_", 1)[0] for g in mesh.face_group])
    out = {}
    for name in ("corolla", "anthers"):
        v = mesh.vertices[np.unique(mesh.faces[organ == name])]
        out[name] = (float(np.hypot(v[:, 0], v[:, 2]).max()), float(v[:, 1].max()))
    return out


def disk_cover(head) -> float:
    """Share of the disk florets' silhouette (its convex hull) seen from above (+Y) that they
    cover in the last canopy frame."""
    mesh = read_obj(head.canopy[-1])
    faces = [f for pid, f in floret_faces(mesh).items() if head.types[pid] == "disk"]
    mesh.faces = mesh.faces[np.concatenate(faces)]
    return view_coverage(mesh, 1, pixels=800)


def check_disk(build: Path, head, failures: list) -> None:
    p = disk_proportions(build)
    (rc, yc), (ra, ya) = p["corolla"], p["anthers"]
    width, exserted = ra / rc, (ya - yc) / yc
    lo, hi = CHECK["anther_exserted"]
    cover = disk_cover(head)
    print(f"disk floret (open): anther tube {2 * ra:.2f} wide, corolla {2 * rc:.2f} (ratio {width:.2f}, "
          f"at least {CHECK['anther_width']}); anthers exserted {ya - yc:.2f} over a corolla {yc:.2f} high "
          f"({exserted:.2f}, {lo}-{hi}); disk florets from above cover {cover:.3f} of the disk "
          f"(at least {CHECK['disk_cover']})")
    if width < CHECK["anther_width"]:
        failures.append(f"disk floret: anther tube {width:.2f} of the corolla's width (pins)")
    if not lo <= exserted <= hi:
        failures.append(f"disk floret: anthers exserted {exserted:.2f} of the corolla's height")
    if cover < CHECK["disk_cover"]:
        failures.append(f"disk florets cover {cover:.3f} of the disk from above (no carpet)")


def main(build: Path) -> int:
    failures = []
    head = check_head(build, rays=RAYS, failures=failures)
    check_phase(head, bud=BUD, failures=failures)
    check_development(head, failures=failures, emerged=CHECK["emerged"])
    check_individuals(head, failures=failures, least=CHECK["individual_cv"])
    check_disk(build, head, failures)
    check_back(head, CHECK["back_in_view"], failures)
    print("OK" if not failures else "FAILED: " + "; ".join(failures))
    return 0 if not failures else 1


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1])))
