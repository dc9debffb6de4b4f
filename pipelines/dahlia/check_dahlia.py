"""Checks of the dahlia build (the `check` stage of the Makefile).

Usage: python check_dahlia.py BUILD_DIR   (BUILD_DIR = build/dahlia)

Prints, and fails (exit 1) on any of, for both runs with collision handling (``canopy/``, the
ball; ``packed/``, the tightly packed variant of fig. 9.1):

- **intersections**: intersecting triangle pairs (inflo.tools.collide, exact static test; touching
  counts) of every canopy frame, and between every frame and the receptacle under them
  (head/receptacle/, not simulated: the florets must stand clear of it);
- **shape**: an output frame whose edges leave [0.5, 1.5] x their rest length (fccompose's log.csv,
  ``min_edge_stretch``/``max_edge_stretch``);
- **florets missing**: a placement of the head that is not in the last frame;

and, of the species (thesis ch. 9, figs. 9.1, 9.2):

- **almost only ray florets**: every placement but the involucral bracts a ray floret;
- **closed from above**: the last frame seen from above (Y) covers at least TOP_COVER of its
  silhouette's convex hull (inflo.tools.species.checks.view_coverage) and leaves at most APEX of
  the receptacle in view; seen obliquely (55 degrees from above, the README's hero still) at most
  OBLIQUE of it and from the side (8 degrees above the horizontal) at most SIDE (guards: the
  florets on the flank point at the eye, and their narrow feet leave the receptacle showing
  between them, README "Noticed and left"). The receptacle's share in view is depth-buffered
  (inflo.tools.species.checks.region_in_view: a floret behind it hides none of it), the mean of
  four views round the ball (azimuths 20, 110, 200 and 290 degrees);
- **round from the side**: the ball's upper half (the faces above its mid-height) seen from the
  side covers at least OUTLINE of its silhouette's convex hull, the least over four azimuths
  (inflo.tools.species.checks.view_coverage of the projection): a crown of erect quills over a
  waist, the top leaning in alike, measured 0.804 at draft and 0.845 final;
- **smooth florets**: the median over the last frame's florets of each floret's largest angle
  between two adjacent faces (degrees) at most SMOOTH (the old faceted cones: about 130);
- **a ball**: the open head at least BALL (0.75) times as high (from the lowest bract's base to
  the top) as it is wide, not a flat head;
- **opening from the base to the top** (the phase effect): at two thirds of the run, the ray
  florets' heights above the receptacle (floret units) fall with their order of formation (first
  at the base, last at the top): Spearman rank correlation below -0.5, and the last fifth formed
  at most LAG (0.8) times as high as the first fifth on average (still opening);
- **florets that touch and accommodate**: the ball's florets meet (collisions found), the packed
  variant's florets press (at least PRESS times the ball's collisions: 0.8, a guard; the top's
  florets leaning in over the apex, whorl.py, press alike in both runs and make most of either
  count), and without collision handling (``packed_off/``) the packed florets intersect (the
  comparison of the picture is real).
"""
from __future__ import annotations

import csv
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from scipy.stats import spearmanr

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.formats.species import species_of
from inflo.tools.collide import intersecting_pairs
from inflo.tools.common import linalg as la
from inflo.tools.species.checks import (
    check_head,
    floret_faces,
    floret_heights,
    region_in_view,
    view_axes,
    view_coverage,
)

# the species' facts: the [check] table of species.toml (formats/species.md)
CHECK = species_of(__file__).check
BALL = CHECK["ball"]
LAG = CHECK["lag"]
PRESS = CHECK["press"]
TOP_COVER = CHECK["top_cover"]
APEX = CHECK["apex"]
OBLIQUE = CHECK["oblique"]
SIDE = CHECK["side"]
#: the views round the ball the receptacle in view is averaged over (degrees of azimuth)
AROUND = (20.0, 110.0, 200.0, 290.0)
SMOOTH = CHECK["smooth"]
OUTLINE = CHECK["outline"]


def crease(mesh) -> float:
    """The median over the mesh's florets of each floret's largest angle (degrees) between the
    normals of two faces sharing an edge."""
    v, f = mesh.vertices, mesh.faces
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n /= np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
    worst = []
    for faces in floret_faces(mesh).values():
        tri = f[faces]
        edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
        owner = np.tile(faces, 3)
        order = np.lexsort((edges[:, 1], edges[:, 0]))
        e, o = edges[order], owner[order]
        same = np.all(e[1:] == e[:-1], axis=1)  # an interior edge: two consecutive rows
        if same.any():
            cos = np.einsum("ij,ij->i", n[o[:-1][same]], n[o[1:][same]])
            worst.append(float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))).max()))
    return float(np.median(worst)) if worst else 0.0


def upper_outline(mesh, azimuths=AROUND) -> float:
    """The least, over side views from ``azimuths`` (degrees), of the share of the convex hull of
    the silhouette of the mesh's upper half (its faces wholly above its mid-height) that the
    silhouette covers: 1 for a dome, less where the outline pinches in (a waist) or stands in
    spikes."""
    v = np.asarray(mesh.vertices, np.float64)
    mid = 0.5 * (v[:, 1].min() + v[:, 1].max())
    upper = mesh.faces[np.all(v[mesh.faces][:, :, 1] >= mid, axis=1)]
    least = 1.0
    for az in azimuths:
        right, up = view_axes(az, 0.0)
        screen = la.matmul(v, np.stack([right, up, np.cross(right, up)], axis=1))
        least = min(least, view_coverage(SimpleNamespace(vertices=screen, faces=upper), 2))
    return least


def collisions(folder: Path) -> int:
    with open(folder / "log.csv", newline="") as fh:
        return sum(int(r["collisions_found"]) for r in csv.DictReader(fh))


def main(build: Path) -> int:
    build = Path(build)
    failures: list = []
    heads = {}
    for canopy, scene in (("canopy", "typed.scn"), ("packed", "packed.scn")):
        print(f"== {canopy}/ ==")
        fail: list = []
        heads[canopy] = head = check_head(build, rays=None, failures=fail, canopy=canopy, scene=scene)
        failures += [f"{canopy}: {f}" for f in fail]
        kinds = set(head.types)
        if kinds - {"ray", "bract"}:
            failures.append(f"{canopy}: florets other than ray florets and bracts: {sorted(kinds)}")

    head = heads["canopy"]
    last = read_obj(head.canopy[-1])
    v = last.vertices
    height = float(v[:, 1].max() - v[:, 1].min())
    width = float(max(np.ptp(v[:, 0]), np.ptp(v[:, 2])))
    print(f"the open ball: {width:.3f} wide, {height:.3f} high ({height / width:.2f})")
    if height < BALL * width:
        failures.append(f"not a ball: {height:.3f} high, {width:.3f} wide (expected >= {BALL} x)")

    receptacle = read_obj(head.receptacle[-1])
    cover = view_coverage(last, 1)
    apex, oblique, side = (float(np.mean([region_in_view(last, receptacle, az, el) for az in AROUND]))
                           for el in (90.0, 55.0, 8.0))
    smooth = crease(last)
    outline = upper_outline(last)
    print(f"from the side: the upper half covers {outline:.3f} of its outline's hull (the least of four views)")
    if outline < OUTLINE:
        failures.append(f"the top is not round from the side: {outline:.3f} of its hull (expected >= {OUTLINE})")
    print(f"from above: {cover:.3f} of the silhouette's hull covered, {apex:.3f} of the receptacle in view; "
          f"at 55 degrees: {oblique:.3f} in view; from the side (8 degrees): {side:.3f} in view; "
          f"florets' largest angle between adjacent faces, median {smooth:.1f} degrees")
    if oblique > OBLIQUE:
        failures.append(f"the receptacle shows at 55 degrees: {oblique:.3f} in view (expected <= {OBLIQUE})")
    if side > SIDE:
        failures.append(f"the receptacle shows from the side: {side:.3f} in view (expected <= {SIDE})")
    if cover < TOP_COVER:
        failures.append(f"the ball is open from above: {cover:.3f} covered (expected >= {TOP_COVER})")
    if apex > APEX:
        failures.append(f"the receptacle shows from above: {apex:.3f} in view (expected <= {APEX})")
    if smooth > SMOOTH:
        failures.append(f"faceted florets: {smooth:.1f} degrees between adjacent faces (expected <= {SMOOTH})")

    k = (2 * len(head.canopy)) // 3
    heights = floret_heights(read_obj(head.canopy[k]), head.rba_frame(k), head.scene)
    rays = sorted(p for p in heights if head.types[p] == "ray")
    h = np.array([heights[p] for p in rays])
    rho = float(spearmanr(rays, h).statistic) if len(rays) > 2 else float("nan")
    fifth = max(1, len(h) // 5)
    lag = float(h[-fifth:].mean() / h[:fifth].mean()) if len(h) else float("nan")
    print(f"phase effect at frame {k}: {len(rays)} ray florets, height {h.min():.2f}-{h.max():.2f} floret units, "
          f"rank correlation with the order of formation {rho:.2f}; the last fifth formed {lag:.2f} x as high "
          f"as the first fifth")
    if not rho < -0.5:
        failures.append(f"no phase effect at frame {k}: rank correlation {rho:.2f}")
    if not lag <= LAG:
        failures.append(f"the top of the ball is not behind its base at frame {k}: {lag:.2f} x (expected <= {LAG})")

    ball, packed = collisions(build / "canopy"), collisions(build / "packed")
    off = read_obj(list_obj_sequence(build / "packed_off")[-1])
    n_off = len(intersecting_pairs(off.vertices, off.faces, tri_part=off.face_group))
    print(f"collisions found: ball {ball}, packed {packed} ({packed / max(ball, 1):.1f} x); packed without "
          f"collision handling, last frame: {n_off} intersecting pairs")
    if ball == 0:
        failures.append("the ball's florets never touch")
    if packed < PRESS * ball:
        failures.append(f"the packed florets press less than {PRESS} x the ball's ({packed} vs {ball} collisions)")
    if n_off == 0:
        failures.append("the packed florets do not intersect without collision handling")

    print("OK" if not failures else "FAILED: " + "; ".join(failures))
    return 0 if not failures else 1


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1])))
