"""Lean the youngest florets at the top of the ball in over the apex, all the same way round it.

Usage: python whorl.py RBA_DIR SCENE.scn OUT_DIR COUNT ANGLE DIRECTION [RAMP [FOOT]]

Seen from above, a floret near the apex of the ball is seen along its own axis: its narrow foot
points at the apex and its cup leans out, so the top florets leave the receptacle in view between
their feet (README "Noticed and left"). The last COUNT florets formed (the top of the ball) are
incurved instead: each leans by up to ANGLE degrees toward a direction DIRECTION degrees from the
apex (0: straight in at the apex, 90: sideways, round it), all the same way round the apex, so
that the top closes in a whorl, each floret's back over its inner neighbours' feet (leaning
straight in opens the ring where the cups stood; sideways leaves the apex itself open).

The lean grows along the ball: the j-th of the COUNT florets (1 the first formed, COUNT the last,
on the apex) leans by up to ANGLE (j / COUNT) ** RAMP. With RAMP 0 all lean alike, and the
florets just above the flank stand erect while those below them curl back over the stem: from
the side the top is a crown of long quills over a waist, the receptacle in view between them.
With RAMP 2 over a longer run of florets the lean rises from nothing on the flank to ANGLE on the
apex, so each floret's cup lies a little higher on the ball than the one formed before it and the
ball is round from the side (README "Noticed and left"). The lean also grows with the floret's
development, smoothly (3 w^2 - 2 w^3 of w = its age / its window), so that each floret emerges
erect into the room it finds and leans as it opens. Each floret turns about
the edge of its foot on the side it leans to (FOOT floret units from the foot's centre, 0.34: the
open floret's base row, 0.32, with a margin), so that no part of its foot sinks into the
receptacle.

SCENE.scn gives the florets' order of formation (the RBA ids), emergence, windows and scales
(dimorph's factors times the RBA rows' sizes). Every RBA frame of RBA_DIR is written to OUT_DIR
(the florets not turned unchanged).
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from inflo.formats.rba import RbaFrame, list_rba_sequence, read_rba, write_rba
from inflo.formats.scn import read_scn
from inflo.tools.common import linalg as la


def turn(v: np.ndarray, axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rows of ``v`` turned about the unit rows of ``axis`` by ``angle`` (radians; Rodrigues)."""
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    k_dot_v = la.rowdot(axis, v)[:, None]
    return v * c + np.cross(axis, v) * s + axis * k_dot_v * (1.0 - c)


def main(src: Path, scene_path: Path, dst: Path, count: int, angle: float, direction: float,
         ramp: float = 0.0, foot: float = 0.34) -> int:
    scene = read_scn(scene_path)
    n = len(scene.placements)
    emergence = np.array([p.emergence if p.emergence is not None else p.frame_start for p in scene.placements], float)
    window = np.array([max(p.frame_end - p.frame_start, 1) for p in scene.placements], float)
    size = np.array([float(p.scale[0]) for p in scene.placements])
    first = n - count
    dst.mkdir(parents=True, exist_ok=True)
    for path in list_rba_sequence(src):
        frame = read_rba(path)
        pos, up, right = frame.pos.copy(), frame.up.copy(), frame.right.copy()
        ids = frame.ids.astype(np.int64)
        top = ids >= first
        if top.any():
            i, k = np.nonzero(top)[0], ids[top]
            w = np.clip((int(path.stem) - emergence[k]) / window[k], 0.0, 1.0)
            along = ((k - first + 1) / count) ** ramp  # 1 on the apex, rising along the ball
            a = math.radians(angle) * along * w * w * (3.0 - 2.0 * w)
            u, r = la.normalize(up[i], axis=1), la.normalize(right[i], axis=1)  # right: away from the apex
            # the side each floret leans to: in (-r) and round the apex (r x u), the same way for all
            phi = math.radians(direction)
            d = -r * math.cos(phi) + np.cross(r, u) * math.sin(phi)
            axis = la.normalize(np.cross(u, d), axis=1)  # turning about it by a turns up toward d
            pivot = pos[i] + d * (foot * frame.scale[i, 0] * size[k])[:, None]  # the foot's edge on d
            pos[i] = pivot + turn(pos[i] - pivot, axis, a)
            up[i] = turn(u, axis, a)
            right[i] = turn(r, axis, a)
        write_rba(dst / path.name, RbaFrame(frame.ids, pos, frame.scale, up, right), fast=True)
    return 0


if __name__ == "__main__":
    if len(sys.argv) not in (7, 8, 9):
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3]), int(sys.argv[4]), float(sys.argv[5]),
                  *(float(x) for x in sys.argv[6:])))
