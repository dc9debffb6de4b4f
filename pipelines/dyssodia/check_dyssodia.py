"""Checks of the Dyssodia build (the `check` stage of the Makefile).

Usage: python check_dyssodia.py BUILD_DIR   (BUILD_DIR = build/dyssodia)

Prints, and fails (exit 1) on any of:

- **intersections**: intersecting triangle pairs (inflo.tools.collide, exact static test; touching
  counts) of every canopy frame, and between every frame and the six receptacles
  (head/receptacles.obj, not simulated);
- **shape**: an output frame whose edges leave [0.5, 1.5] x their rest length (fccompose's log);
- **florets missing**: a placement that is not in the last frame;
- **the species' facts** (thesis ch. 9, figs. 9.7, 9.8, 6.4b): six heads; ray florets decided at
  the level of the whole inflorescence, so on its outer margin: none on the central head, every
  one on the outer side of its own head (farther from the inflorescence's centre than its head's
  centre) and at least 4 of the 5 outer heads with some; the disk florets pressed by their
  neighbours (collisions found between florets of one head, in at least half the frames after
  the first third); the phase effect in every head: at two thirds of the run, its disk florets'
  heights above their bases (floret units) fall from its rim to its centre (Spearman rank
  correlation with the distance from the head's centre > 0.5);
- **the look**, with the thresholds of species.toml [check]: the group crowds (the last
  frame from above covers at least ``coverage_min`` of its silhouette's convex hull,
  view_coverage along Y); the disk florets are reshaped by their neighbours (fig. 9.8: at least
  ``reshaped_min`` of them deviate from their template by more than ``reshaped_by``, see
  :func:`deviations`); the rays spread outward (their mean angle below the horizontal, base to
  ligule tip, at most ``ray_droop_max`` degrees); the heads' backs clothed (their phyllaries
  and the florets leave at most ``back_in_view`` of the six undersides in view from 30 degrees
  below, checks.check_back; no phyllary crosses another, a receptacle or a floret in any frame).
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.formats.placement import placement_matrix
from inflo.formats.species import species_of
from inflo.tools.species.checks import (
    check_back,
    check_head,
    check_individuals,
    floret_faces,
    frames_with_contacts,
    view_coverage,
)

# the species' facts: the [check] table of species.toml (formats/species.md)
CHECK = species_of(__file__).check
HEADS = CHECK["heads"]


def heights(mesh, scene) -> dict:
    """Height of each floret's highest vertex above its base along its axis, in floret units."""
    out = {}
    for pid, faces in floret_faces(mesh).items():
        p = scene.placements[pid]
        v = mesh.vertices[np.unique(mesh.faces[faces])]
        up = p.up / np.linalg.norm(p.up)
        out[pid] = float(((v - p.pos) @ up).max()) / float(p.scale[1])
    return out


def _ramp(frame: float, start, end) -> float:
    """A ``ca`` placement's developmental time u in [0, 1] at ``frame`` (as fccompose's model)."""
    if end <= start:
        return 1.0 if frame >= start else 0.0
    return min(max((frame - start) / (end - start), 0.0), 1.0)


def deviations(build: Path, mesh, frame: int, scene) -> dict:
    """Per disk floret of ``mesh`` (canopy frame ``frame``): how far it is reshaped by its
    neighbours. Its vertices are mapped back into its placement's frame (the inverse of its
    local-to-scene map: position, orientation, scale) and compared with its template (the OBJ
    frames under disk_obj/, interpolated at its developmental time, as fccompose does): the largest
    vertex displacement over the template's bounding-box diagonal at that time. 0 for a floret
    that is exactly its template (its base rows are fixed, so any displacement is a bend)."""
    tpl = [read_obj(f).vertices for f in list_obj_sequence(Path(build) / "disk_obj")]
    out = {}
    for pid, faces in floret_faces(mesh).items():
        p = scene.placements[pid]
        if p.type != "disk":
            continue
        v = mesh.vertices[np.unique(mesh.faces[faces])]
        m = placement_matrix(p.pos, p.scale, p.up, p.right)
        local = (v - m[:3, 3]) @ np.linalg.inv(m[:3, :3]).T
        u = _ramp(frame, p.frame_start, p.frame_end) * (len(tpl) - 1)
        a = int(np.floor(u))
        b = min(a + 1, len(tpl) - 1)
        t = tpl[a] * (1.0 - (u - a)) + tpl[b] * (u - a)
        if len(t) != len(local):
            continue
        out[pid] = float(np.linalg.norm(local - t, axis=1).max() / np.linalg.norm(t.max(axis=0) - t.min(axis=0)))
    return out


def ray_droop(mesh, scene) -> list:
    """Per ray floret of ``mesh``: the angle (degrees) below the horizontal of the line from its
    base to its farthest vertex (the ligule's tip); negative above it."""
    out = []
    for pid, faces in floret_faces(mesh).items():
        p = scene.placements[pid]
        if p.type != "ray":
            continue
        v = mesh.vertices[np.unique(mesh.faces[faces])] - p.pos
        d = v[np.argmax(np.linalg.norm(v, axis=1))]
        out.append(float(np.degrees(np.arcsin(-d[1] / np.linalg.norm(d)))))
    return out


def main(build: Path) -> int:
    build = Path(build)
    failures: list = []
    head = check_head(build, rays=None, failures=failures, scene="typed.scn", receptacle="receptacles.obj")
    check_individuals(head, failures=failures)  # no clones (dyssodia.fcc's variation line)
    check_back(head, CHECK["back_in_view"], failures)  # the heads' undersides clothed in phyllaries
    scene = head.scene
    groups = np.array([p.group for p in scene.placements])
    types = np.array(head.types)
    pos = scene.arrays()["pos"]
    centre = scene.groups[0].centre
    ids = sorted(g for g in scene.groups if g != 0)
    print(f"heads: {len(ids)}; florets per head: {[int((groups == g).sum()) for g in ids]}")
    if len(ids) != HEADS:
        failures.append(f"{len(ids)} heads, expected {HEADS}")

    # rays on the outer margin of the whole inflorescence
    rays_per_head = {}
    outer_side = 0
    for g in ids:
        hc = scene.groups[g].centre
        r = np.nonzero((groups == g) & (types == "ray"))[0]
        rays_per_head[g] = len(r)
        d_ray = np.linalg.norm((pos[r] - centre)[:, [0, 2]], axis=1)
        outer_side += int((d_ray > np.linalg.norm((hc - centre)[[0, 2]])).sum())
    n_rays = int((types == "ray").sum())
    central = min(ids, key=lambda g: np.linalg.norm(scene.groups[g].centre - centre))
    print(f"ray florets: {n_rays}, per head {[rays_per_head[g] for g in ids]} (central head {central}); "
          f"{outer_side} on the outer side of their heads")
    if rays_per_head[central]:
        failures.append(f"{rays_per_head[central]} ray florets on the central head")
    if outer_side != n_rays:
        failures.append(f"{n_rays - outer_side} ray florets on the inner side of their heads")
    if sum(1 for g in ids if g != central and rays_per_head[g]) < HEADS - 2:
        failures.append("fewer than 4 outer heads with ray florets")

    # neighbours press on each other
    pressed, late = frames_with_contacts(build / "canopy")
    if pressed < late // 2:
        failures.append(f"the florets touch in only {pressed} of the last {late} frames")

    # the phase effect in every head
    k = (2 * len(head.canopy)) // 3
    h = heights(read_obj(head.canopy[k]), scene)
    for g in ids:
        disk = [p for p in h if groups[p] == g and types[p] == "disk"]
        d = np.linalg.norm(pos[disk] - scene.groups[g].centre, axis=1)
        rho = float(spearmanr(d, [h[p] for p in disk]).statistic) if len(disk) > 2 else float("nan")
        print(f"  head {g} at frame {k}: {len(disk)} disk florets, heights "
              f"{min(h[p] for p in disk):.2f}-{max(h[p] for p in disk):.2f} floret units, rank correlation "
              f"with the distance from its centre {rho:.2f}")
        if not rho > 0.5:
            failures.append(f"no phase effect in head {g} at frame {k}: rank correlation {rho:.2f}")

    # the look: crowded heads, disk florets reshaped by their neighbours, rays spreading outward
    last = read_obj(head.canopy[-1])
    cover = view_coverage(last, axis=1)
    print(f"group from above (last frame): covers {cover:.3f} of its silhouette's convex hull "
          f"(at least {CHECK['coverage_min']:g})")
    if not cover >= CHECK["coverage_min"]:
        failures.append(f"the group covers {cover:.3f} of its hull from above, under {CHECK['coverage_min']:g}")
    dev = np.array(list(deviations(build, last, len(head.canopy) - 1, scene).values()))
    share = float((dev > CHECK["reshaped_by"]).mean()) if len(dev) else 0.0
    print(f"disk florets reshaped by their neighbours (last frame): {share:.3f} of {len(dev)} deviate more than "
          f"{CHECK['reshaped_by']:g} of their size from their template (at least {CHECK['reshaped_min']:g}); "
          f"median {np.median(dev):.3f}, largest {dev.max():.3f}")
    if not share >= CHECK["reshaped_min"]:
        failures.append(f"only {share:.3f} of the disk florets reshaped, under {CHECK['reshaped_min']:g}")
    droop = ray_droop(last, scene)
    mean = float(np.mean(droop)) if droop else float("nan")
    print(f"rays (last frame): {mean:.1f} degrees below the horizontal on average ({min(droop):.1f}-{max(droop):.1f}; "
          f"at most {CHECK['ray_droop_max']:g})")
    if not mean <= CHECK["ray_droop_max"]:
        failures.append(f"the rays hang {mean:.1f} degrees below the horizontal, over {CHECK['ray_droop_max']:g}")

    print("OK" if not failures else "FAILED: " + "; ".join(failures))
    return 0 if not failures else 1


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1])))
