"""Checks of the lilac build (the `check` stage of the Makefile).

Usage: python check_lilac.py BUILD_DIR   (BUILD_DIR = build/lilac)

Prints, and fails (exit 1) on any of (inflo.tools.species.checks' shared report first):

- **intersections**: intersecting triangle pairs (inflo.tools.collide, exact static test; touching
  counts) in any written canopy frame;
- **shape**: an output frame whose edges leave [0.5, 1.5] x their rest length (fccompose's log);
- **florets missing**: a placement of the thyrse's scene that is not in the last frame;
- **the species' facts** (thesis sec. 4.5, figs. 4.9, 4.10):
  - florets stay on their pedicels: every floret's base row (its lowest template row, fixed by
    floret.weights) within 1e-5 of its placement's position in the last frame;
  - the lower florets open first: at the middle of the run, the florets' limb spread (farthest
    petal vertex from the floret's axis, in floret units) falls with their height on the axis
    (Spearman rank correlation < -0.5);
  - all open at the end: every floret's spread in the last frame at least 0.3 floret units (the
    open limb's lobes reach 0.49; a floret pressed by its neighbours a little less);
  - collisions deform petals: contacts found in at least half the frames after the first third.

Also printed, not failed: the florets' intersections with the branches (fccompose does not
collide the florets with the branch mesh, whose tubes meet inside each other at the joints).
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from inflo.formats.obj import read_obj
from inflo.formats.species import species_of
from inflo.tools.collide import intersecting_pairs_between
from inflo.tools.species.checks import check_head, floret_faces, frames_with_contacts

# the species' facts: the [check] table of species.toml (formats/species.md)
CHECK = species_of(__file__).check
OPEN = CHECK["open"]


def spreads(mesh, scene) -> dict:
    """Per floret: the farthest vertex from its axis (through its position, along ``up``), in
    floret units."""
    out = {}
    for pid, faces in floret_faces(mesh).items():
        p = scene.placements[pid]
        up = p.up / np.linalg.norm(p.up)
        v = mesh.vertices[np.unique(mesh.faces[faces])] - p.pos
        radial = v - np.outer(v @ up, up)
        out[pid] = float(np.linalg.norm(radial, axis=1).max()) / float(p.scale[0])
    return out


def main(build: Path) -> int:
    build = Path(build).resolve()
    failures: list = []
    branches = read_obj(build / "thyrse" / "branches.obj")
    with_branches = []

    def per_frame(i, mesh):
        with_branches.append(len(intersecting_pairs_between(mesh.vertices, mesh.faces, branches.vertices,
                                                            branches.faces)))

    # the thyrse has no receptacle: its skeleton's polylines stand in (no triangles, nothing to meet)
    head = check_head(build, rays=None, failures=failures, per_frame=per_frame, scene="scene.scn",
                      folder="thyrse", receptacle="skeleton.obj")
    scene = head.scene
    canopy = head.canopy
    a = scene.arrays()
    height = a["pos"][:, 1]
    print(f"thyrse: {len(scene)} florets, heights {height.min():.3f}-{height.max():.3f}; development windows "
          f"{min(p.frame_start for p in scene.placements)}-{max(p.frame_end for p in scene.placements)}")
    print(f"florets x branches (not collided by fccompose): {max(with_branches)} intersecting pairs at most, "
          f"{with_branches[-1]} in the last frame")

    # florets on their pedicels: the base row stays at the placement's position
    last = read_obj(canopy[-1])
    weights = np.array([int(t) for line in (build / "floret.weights").read_text().splitlines()
                        if line and not line.startswith("#") for t in line.split()])
    template = read_obj(sorted((build / "floret_obj").glob("frame_*.obj"))[-1]).vertices
    nv = len(template)
    worst = 0.0
    for pid, faces in floret_faces(last).items():
        first = int(last.faces[faces].min())
        if int(last.faces[faces].max()) - first + 1 != nv:
            failures.append(f"floret {pid}: {int(last.faces[faces].max()) - first + 1} vertices, the template has {nv}")
            continue
        m = scene.placements[pid].matrix()
        expected = template[weights] @ m[:3, :3].T + m[:3, 3]
        worst = max(worst, float(np.linalg.norm(last.vertices[first + weights] - expected, axis=1).max()))
    print(f"florets on their pedicels: base rows within {worst:.2e} of where their placements put them")
    if worst > 1e-5:
        failures.append(f"a floret's base row left its pedicel ({worst:.2e})")

    # the lower florets open first; all open at the end
    mid = read_obj(canopy[len(canopy) // 2])
    s_mid = spreads(mid, scene)
    ids = sorted(s_mid)
    rho = float(spearmanr([height[k] for k in ids], [s_mid[k] for k in ids])[0])
    s_end = spreads(last, scene)
    print(f"development at frame {len(canopy) // 2}: rank correlation of the florets' spread with their height "
          f"{rho:.2f}; last frame: spread {min(s_end.values()):.2f}-{max(s_end.values()):.2f} floret units")
    if not rho < -0.5:
        failures.append(f"the lower florets do not open first (rank correlation {rho:.2f}, expected < -0.5)")
    if min(s_end.values()) < OPEN:
        failures.append(f"{sum(v < OPEN for v in s_end.values())} florets not open at the end (spread < {OPEN})")

    # collisions deform petals
    contacts, later = frames_with_contacts(head.canopy_dir)
    if contacts < later / 2:
        failures.append(f"contacts in only {contacts} of {later} frames after the first third")

    print("OK" if not failures else "FAILED:\n  " + "\n  ".join(failures))
    return 0 if not failures else 1


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("build/lilac")))
