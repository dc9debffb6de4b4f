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
  (the .fcc's ``variation`` lines; checks.check_individuals).
"""
from __future__ import annotations

import sys
from pathlib import Path

from inflo.formats.species import species_of
from inflo.tools.species.checks import check_development, check_head, check_individuals, check_phase

# the species' facts: the [check] table of species.toml (formats/species.md)
CHECK = species_of(__file__).check
RAYS = CHECK["rays"]
BUD = CHECK["bud"]


def main(build: Path) -> int:
    failures = []
    head = check_head(build, rays=RAYS, failures=failures)
    check_phase(head, bud=BUD, failures=failures)
    check_development(head, failures=failures, emerged=CHECK["emerged"])
    check_individuals(head, failures=failures, least=CHECK["individual_cv"])
    print("OK" if not failures else "FAILED: " + "; ".join(failures))
    return 0 if not failures else 1


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1])))
