"""Checks of the lilac build (the `check` stage of the Makefile).

Usage: python check_lilac.py BUILD_DIR   (BUILD_DIR = build/lilac)

Prints, and fails (exit 1) on any of (inflo.tools.species.checks' shared report first):

- **intersections**: intersecting triangle pairs (inflo.tools.collide, exact static test; touching
  counts) in any written canopy frame, within the canopy and **between the florets and the
  branches** (thyrse/branches.obj);
- **shape**: an output frame whose edges leave [0.5, 1.5] x their rest length (fccompose's log);
- **florets missing**: a placement of the thyrse's scene that is not in the last frame;
- **the species' facts** (thesis sec. 4.5, figs. 4.9, 4.10; the [check] table of species.toml):
  - florets stay on their pedicels: every floret's base row (its lowest template row, fixed by
    floret.weights) within 1e-5 of its placement's position in the last frame;
  - every floret has its calyx (faces of the calyx material, 1);
  - the florets face out of the panicle: for the florets on its surface (their base within
    ``surface`` floret sizes of the convex hull of the last frame's canopy), the median angle
    between the floret's axis and the hull's outward normal at most ``facing`` degrees;
  - a dense panicle: the florets of the last frame cover at least ``coverage`` of their convex
    hull seen from the front and from the side (:func:`view_coverage`);
  - individual florets: the florets' sizes vary (coefficient of variation at least
    ``size_cv``) and so do the starts of florets at one height (``start_variation`` frames);
  - development is acropetal (the lower florets open first): at the middle of the run, the
    florets' limb spread (farthest petal vertex from the floret's axis, in floret units) falls
    with their height (Spearman rank correlation < -0.5); in the last frame every floret of the
    lower half is open (spread at least ``open``) and the topmost ones are still in bud (spread
    under ``bud``: at least ``tip_buds`` of the florets in the top tenth of the heights);
  - collisions deform petals: contacts found in at least half the frames after the first third.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
from scipy.spatial import ConvexHull
from scipy.stats import spearmanr

from inflo.formats.obj import read_obj
from inflo.formats.species import species_of
from inflo.tools.collide import intersecting_pairs_between
from inflo.tools.species.checks import check_head, floret_faces, frames_with_contacts, view_coverage

# the species' facts: the [check] table of species.toml (formats/species.md)
CHECK = species_of(__file__).check
#: the calyx's material (make_keys.py)
CALYX = "mtl1"


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


def facing_angles(mesh, scene, surface: float) -> np.ndarray:
    """Degrees between each surface floret's axis (its placement's ``up``) and the outward normal
    of the convex hull of the canopy's vertices nearest to it; a floret is on the surface when its
    base lies within ``surface`` floret sizes of the hull (distance to a convex hull = the least
    distance to its facets' planes, the nearest facet the one that attains it)."""
    used = np.unique(mesh.faces)
    hull = ConvexHull(mesh.vertices[used])
    n, c = hull.equations[:, :3], hull.equations[:, 3]
    out = []
    for pid in floret_faces(mesh):
        p = scene.placements[pid]
        depth = -(n @ p.pos + c)
        k = int(np.argmin(depth))
        if depth[k] > surface * float(p.scale[0]):
            continue
        up = p.up / np.linalg.norm(p.up)
        out.append(math.degrees(math.acos(min(1.0, max(-1.0, float(up @ n[k]))))))
    return np.asarray(out)


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
    # the florets: the scene's placements less the branches' obstacle (simulated, not written)
    fl = np.array([p.type != "obstacle" for p in scene.placements])
    placed = [p for p in scene.placements if p.type != "obstacle"]
    print(f"thyrse: {fl.sum()} florets, heights {height[fl].min():.3f}-{height[fl].max():.3f}; development windows "
          f"{min(p.frame_start for p in placed)}-{max(p.frame_end for p in placed)}; "
          f"{len(scene) - fl.sum()} obstacle placements")
    worst_frame = int(np.argmax(with_branches))
    print(f"florets x branches: {max(with_branches)} intersecting pairs at most (frame {worst_frame}), "
          f"{sum(1 for k in with_branches if k)} frames with any, {with_branches[-1]} in the last frame")
    if max(with_branches):
        failures.append(f"florets intersect the branches in {sum(1 for k in with_branches if k)} frames "
                        f"({max(with_branches)} pairs at most)")

    # florets on their pedicels: the base row stays at the placement's position; each has its calyx
    last = read_obj(canopy[-1])
    weights = np.array([int(t) for line in (build / "floret.weights").read_text().splitlines()
                        if line and not line.startswith("#") for t in line.split()])
    template = read_obj(sorted((build / "floret_obj").glob("frame_*.obj"))[-1]).vertices
    nv = len(template)
    worst = 0.0
    calyx = last.materials.index(CALYX) if CALYX in last.materials else -2
    no_calyx = 0
    for pid, faces in floret_faces(last).items():
        first = int(last.faces[faces].min())
        if int(last.faces[faces].max()) - first + 1 != nv:
            failures.append(f"floret {pid}: {int(last.faces[faces].max()) - first + 1} vertices, the template has {nv}")
            continue
        no_calyx += int(not np.any(last.face_material[faces] == calyx))
        m = scene.placements[pid].matrix()
        expected = template[weights] @ m[:3, :3].T + m[:3, 3]
        worst = max(worst, float(np.linalg.norm(last.vertices[first + weights] - expected, axis=1).max()))
    print(f"florets on their pedicels: base rows within {worst:.2e} of where their placements put them; "
          f"florets without a calyx: {no_calyx}")
    if worst > 1e-5:
        failures.append(f"a floret's base row left its pedicel ({worst:.2e})")
    if no_calyx:
        failures.append(f"{no_calyx} florets without a calyx")

    # the florets face out of the panicle; the panicle is dense
    ang = facing_angles(last, scene, CHECK["surface"])
    print(f"facing: {len(ang)} florets on the surface, angle of their axis to the outward normal: median "
          f"{np.median(ang):.1f} deg, {np.mean(ang > 45):.0%} beyond 45 deg")
    if not np.median(ang) <= CHECK["facing"]:
        failures.append(f"the florets do not face out (median {np.median(ang):.1f} deg > {CHECK['facing']})")
    cover = {name: view_coverage(last, axis) for name, axis in (("front", 2), ("side", 0))}
    print("coverage of the florets' hull: " + ", ".join(f"{k} view {v:.3f}" for k, v in cover.items()))
    if min(cover.values()) < CHECK["coverage"]:
        failures.append(f"the panicle is open: coverage {min(cover.values()):.3f} < {CHECK['coverage']}")

    # individual florets: size and start vary
    size = a["scale"][fl, 0]
    cv = float(size.std() / size.mean())
    start = np.array([p.frame_start for p in placed], float)
    order = np.argsort(height[fl])
    jitter = float(np.abs(np.diff(start[order])).mean())
    print(f"individual florets: size CV {cv:.3f}; mean start difference of florets next in height {jitter:.2f} frames")
    if cv < CHECK["size_cv"]:
        failures.append(f"the florets are clones in size (CV {cv:.3f} < {CHECK['size_cv']})")

    # the lower florets open first; the lower half open at the end, the top still in bud
    mid = read_obj(canopy[len(canopy) // 2])
    s_mid = spreads(mid, scene)
    ids = sorted(s_mid)
    rho = float(spearmanr([height[k] for k in ids], [s_mid[k] for k in ids])[0])
    s_end = spreads(last, scene)
    lower = [k for k in s_end if height[k] <= np.median(height[fl])]
    top = [k for k in s_end if height[k] >= np.quantile(height[fl], 0.9)]
    buds = sum(s_end[k] < CHECK["bud"] for k in top)
    print(f"development at frame {len(canopy) // 2}: rank correlation of the florets' spread with their height "
          f"{rho:.2f}; last frame: lower half spread {min(s_end[k] for k in lower):.2f}-"
          f"{max(s_end[k] for k in lower):.2f} floret units, {buds} of the top {len(top)} in bud "
          f"({sum(v >= CHECK['open'] for v in s_end.values())} of {len(s_end)} open)")
    if not rho < -0.5:
        failures.append(f"the lower florets do not open first (rank correlation {rho:.2f}, expected < -0.5)")
    if min(s_end[k] for k in lower) < CHECK["open"]:
        failures.append(f"{sum(s_end[k] < CHECK['open'] for k in lower)} florets of the lower half not open at the "
                        f"end (spread < {CHECK['open']})")
    if buds < CHECK["tip_buds"] * len(top):
        failures.append(f"only {buds} of the top {len(top)} florets in bud at the end")

    # collisions deform petals
    contacts, later = frames_with_contacts(head.canopy_dir)
    if contacts < later / 2:
        failures.append(f"contacts in only {contacts} of {later} frames after the first third")

    print("OK" if not failures else "FAILED:\n  " + "\n  ".join(failures))
    return 0 if not failures else 1


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("build/lilac")))
