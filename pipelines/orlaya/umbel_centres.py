"""The branch-gen input of the orlaya umbel (fig. 7.2b, 9.13 bottom): the typed scene with its
hierarchy groups' centres moved below the canopy, where each level's rays meet.

Usage: python umbel_centres.py SCENE.scn UMBELLET_DEPTH UMBEL_DEPTH OUT.scn

In the pattern (phyllotaxis [compound]) every group's centre lies in the canopy plane: group 0 the
umbel's apex, groups 1.. the umbellets'. branch-gen's hierarchy mode (formats/branch_gen.md) makes
a level's particles converge on their group's centre, so this script lowers (along -Y, the umbel's
axis) each umbellet's centre by UMBELLET_DEPTH times the umbellet's radius (its farthest floret)
and the umbel's centre by UMBEL_DEPTH times the umbel's radius: the rays of each umbellet meet at
the top of its ray of the main umbel, the main umbel's rays at the top of the peduncle. Floret
positions are unchanged (every tip ends on its floret).
"""
from __future__ import annotations

import sys

import numpy as np

from inflo.formats.scn import read_scn, write_scn
from inflo.tools.common import linalg as la


def lower_centres(scene, umbellet_depth: float, umbel_depth: float):
    a = scene.arrays()
    pos, group = a["pos"], a["group"]
    for g in scene.groups.values():
        if g.parent == -1:
            radius = float(la.norm((pos - g.centre)[:, [0, 2]], axis=1).max())
            depth = umbel_depth
        else:
            members = pos[group == g.id]
            radius = float(la.norm((members - g.centre)[:, [0, 2]], axis=1).max()) if len(members) else 0.0
            depth = umbellet_depth
        g.centre = g.centre - np.array([0.0, depth * radius, 0.0])
    return scene


def main(argv) -> int:
    if len(argv) != 4:
        print(__doc__.strip().splitlines()[3], file=sys.stderr)
        return 2
    scene = lower_centres(read_scn(argv[0]), float(argv[1]), float(argv[2]))
    write_scn(argv[3], scene, header="orlaya umbel: group centres lowered for branch-gen (umbel_centres.py)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
