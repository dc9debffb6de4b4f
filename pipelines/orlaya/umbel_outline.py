"""The umbellets' rays: the peripheral umbellets on one circle round the inner ones (the `dimorph`
stage's first step).

Usage: python umbel_outline.py IN.scn OUT.scn INNER RING

The pattern (phyllotaxis [compound]) places the umbellets' primordia by centripetal fractionation
on the umbel's disc: at radii growing as the square root of their order, turned by the golden
angle. That is the order in which the umbel's rays form (thesis ch. 9: "Both the umbellets within
the main umbel and the individual florets within the umbellets exhibit spiral phyllotaxis"), but
it leaves the outermost umbellets at different distances from the umbel's centre and unevenly
spaced round it: where one stands nearer the centre than its neighbours, the fans of large
petals of the umbellets beside it diverge and leave a notch in the outline, and two that stand
close turn their large florets into each other (issue 43: the largest empty disc inside the
umbel's outline 2.1 floret spacings, the issue asks at most 1.5). In the plant the umbel is
flat-topped with a round outline: its rays are as long as they need to be to carry the
umbellets onto one plane, side by side.

Here the rays' ends are moved, not the order: the INNER umbellets nearest the umbel's centre keep
their places relative to one another, their centroid moved onto the umbel's axis; every other
umbellet goes onto one circle round them, at RING times the mean of their distances from the
centre, evenly spaced round it in the angular order the spiral gave them (the ring turned as a
whole to stay nearest the spiral's angles). Each umbellet moves rigidly, its florets and group
centre with it; everything else of every placement is unchanged. `dimorph`, run after this on the
moved pattern, types and sizes the florets by the room they now have. Written atomically
(formats.scn).
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from inflo.formats.scn import read_scn, write_scn


def ring_shifts(centres: np.ndarray, inner: int, ring: float) -> np.ndarray:
    """(n, 3) shifts of the umbellets whose centres are the (n, 3) rows (the umbel's centre at the
    origin, its axis +Y): the ``inner`` nearest the axis moved together so that their centroid lies
    on it, the others evenly round one circle of ``ring`` times their mean distance from the axis,
    in their angular order, the circle turned to the least squared angular move. Y is kept."""
    n = len(centres)
    shift = np.zeros((n, 3))
    if n == 0:
        return shift
    radius = np.hypot(centres[:, 0], centres[:, 2])
    order = np.argsort(radius, kind="stable")
    inside, outside = order[:inner], order[inner:]
    if len(inside):
        c = centres[inside].mean(axis=0)
        shift[inside, 0] = -c[0]
        shift[inside, 2] = -c[2]
    m = len(outside)
    if m:
        angle = np.arctan2(centres[outside, 2], centres[outside, 0])
        around = np.argsort(angle, kind="stable")
        step = 2.0 * math.pi / m
        # the turn of the evenly spaced circle nearest the spiral's angles (circular mean)
        offset = angle[around] - step * np.arange(m)
        turn = math.atan2(float(np.sin(offset).mean()), float(np.cos(offset).mean()))
        r = ring * float(radius[outside].mean())
        for slot, i in enumerate(around):
            j = outside[i]
            a = turn + step * slot
            shift[j, 0] = r * math.cos(a) - centres[j, 0]
            shift[j, 2] = r * math.sin(a) - centres[j, 2]
    return shift


def main(src: Path, dst: Path, inner: int, ring: float) -> int:
    scene = read_scn(src)
    root = [g for g in scene.groups.values() if g.parent == -1]
    origin = root[0].centre if root else np.zeros(3)
    umbellets = [g for g in scene.groups.values() if g.parent != -1]
    centres = np.array([g.centre - origin for g in umbellets]).reshape(-1, 3)
    shift = ring_shifts(centres, inner, ring)
    by_group = {g.id: shift[k] for k, g in enumerate(umbellets)}
    for g in umbellets:
        g.centre = g.centre + by_group[g.id]
    for p in scene.placements:
        if p.group in by_group:
            p.pos = p.pos + by_group[p.group]
    write_scn(dst, scene, header=f"{src.name} with its umbellets' rays adjusted (umbel_outline.py: {inner} inner, "
                                 f"the other {max(len(umbellets) - inner, 0)} on one circle at {ring:g} x their mean "
                                 "distance)")
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 5:
        print(__doc__.strip().splitlines()[3], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1]), Path(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])))
