"""The involucral bracts of the orlaya umbel (thesis ch. 9, figs. 9.11-9.13): an involucre under the
umbel, where its rays meet the peduncle, and an involucel under every umbellet, where its pedicels
meet its ray; appended to the typed scene as placements of their own type, so that fccompose
simulates them with the florets (they collide with each other and with every floret).

Usage: python involucres.py TYPED.scn LOWERED.scn BRANCHES.obj OUT.scn [UMBEL_BRACTS UMBELLET_BRACTS]

TYPED.scn is dimorph's scene (the florets), LOWERED.scn the same with its group centres moved down to
where each level's rays meet (umbel_centres.py: branch-gen's input), BRANCHES.obj branch-gen's mesh.
Each group centre gets a whorl of bracts (default 7 under the umbel, 5 under each umbellet; Orlaya
grandiflora has 5-8 and 5-6), placement id 3, ``#@ type: bract``, ``#@ group:`` the group; they come
after every floret (the florets keep their indices). A bract's base stands on a ring round the
branch where the rays meet: BASE_DROP bract lengths below the meeting point and out from the axis to
MARGIN plus the farthest branch vertex at that height (the peduncle's or the ray's tube), measured
on BRANCHES.obj; its blade (bract_*.floret: +X along the blade) points radially outward and rises a
little, below every ray leaving the meeting point (they leave upward, within about 45 degrees of the
axis). Bract length: UMBELLET_LENGTH x the umbellet's radius (its farthest floret), UMBEL_LENGTH x
the umbel's. Every bract develops (bud -> open key pose) over the first BRACT_FRAMES frames.
"""
from __future__ import annotations

import sys

import numpy as np

from inflo.formats.obj import read_obj
from inflo.formats.scn import Placement, read_scn, write_scn
from inflo.tools.common import linalg as la

BRACT_ID = 3
UMBEL_LENGTH, UMBELLET_LENGTH = 0.22, 0.55
BASE_DROP = 0.06
MARGIN = 0.25  # bract lengths beyond the branch's tube
BRACT_FRAMES = 6


def branch_radius(branch_v: np.ndarray, centre: np.ndarray, y: float, band: float, reach: float) -> float:
    """The farthest branch vertex from the vertical axis through ``centre`` within ``band`` of height
    ``y`` and ``reach`` of the axis (the tube there), 0 where none."""
    d = branch_v - centre
    r = np.hypot(d[:, 0], d[:, 2])
    near = (np.abs(branch_v[:, 1] - y) <= band) & (r <= reach)
    return float(r[near].max()) if near.any() else 0.0


def add_involucres(typed, lowered, branch_v: np.ndarray, umbel_bracts: int = 7, umbellet_bracts: int = 5):
    a = typed.arrays()
    pos, group = a["pos"], a["group"]
    out = typed
    for gid, g in sorted(lowered.groups.items()):
        if g.parent == -1:
            radius = float(la.norm(pos[:, [0, 2]] - g.centre[[0, 2]], axis=1).max())
            length, count = UMBEL_LENGTH * radius, umbel_bracts
        else:
            members = pos[group == gid]
            if not len(members):
                continue
            radius = float(la.norm(members[:, [0, 2]] - g.centre[[0, 2]], axis=1).max())
            length, count = UMBELLET_LENGTH * radius, umbellet_bracts
        c = g.centre
        y = c[1] - BASE_DROP * length
        ring = branch_radius(branch_v, c, y, 0.1 * length, 0.5 * length) + MARGIN * length
        turn = np.radians(360.0 / count)
        phase = (gid * 0.61803398875 % 1.0) * turn  # the whorls not all aligned
        for k in range(count):
            t = phase + k * turn
            out_dir = np.array([np.cos(t), 0.0, np.sin(t)])
            out.placements.append(Placement(
                kind="ca", id=BRACT_ID, pos=np.array([c[0], y, c[2]]) + ring * out_dir,
                scale=np.full(3, length), up=np.array([0.0, 1.0, 0.0]), right=out_dir,
                frame_start=0, frame_end=BRACT_FRAMES, group=gid, type="bract"))
    return out


def main(argv) -> int:
    if len(argv) not in (4, 6):
        print(__doc__.strip().splitlines()[4], file=sys.stderr)
        return 2
    counts = (int(argv[4]), int(argv[5])) if len(argv) == 6 else (7, 5)
    scene = add_involucres(read_scn(argv[0]), read_scn(argv[1]), read_obj(argv[2]).vertices, *counts)
    write_scn(argv[3], scene, header="orlaya umbel: florets and involucral bracts (involucres.py)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
