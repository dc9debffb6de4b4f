"""Spread the ray florets of the typed scene outward from the group (the `dimorph` stage's last step).

Usage: python spread_rays.py TYPED.scn DROOP LENGTH WIDTH LIFT OBSTACLES.scn OUT.scn

The rays sit on the heads' rims, where the dome's normal leans 40 degrees (the cap) plus the
outer heads' tilt away from the vertical; the ray template's ligule opens along the floret's
local +X, nearly square to its axis, so placed along the normal the ligules hang down like a
skirt. Real heads of *Dyssodia* / *Thymophylla* hold their rays out, spreading from the group
(thesis fig. 9.7). This turns each ray floret (type "ray") so that its local +X points outward in the horizontal plane,
halfway between away from the inflorescence's centre (group 0) and away from its own head's centre
(so each outer head's rays fan out over the group's margin and fill the notches between heads) and its axis leans DROOP degrees
outward from the vertical (the ligule then DROOP degrees below the horizontal, less the few
degrees the template's ligule rises); scales its local X (the ligule's length) by LENGTH and its
local Z (the ligule's width) by WIDTH (broad, short rays, as in the plant; 1 1 keeps dimorph's
uniform ray scale); and moves its base LIFT scene units along its old axis (off the dome: the
turned base would otherwise dip into the receptacle on the head's inner side). Every other
placement is copied unchanged, and the placements of OBSTACLES.scn (compose_heads.py: the six
receptacles) are appended after them (so every floret keeps its index). Written atomically.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from inflo.formats.scn import read_scn, write_scn
from inflo.tools.common import linalg as la

UP = np.array([0.0, 1.0, 0.0])


def spread(scene, droop: float, length: float, width: float, lift: float) -> int:
    """Turn, scale and lift the ray placements of ``scene`` in place; returns how many."""
    centre = scene.groups[0].centre if 0 in scene.groups else scene.arrays()["pos"].mean(axis=0)
    d = np.radians(droop)
    n = 0
    for p in scene.placements:
        if p.type != "ray":
            continue
        out = np.zeros(3)
        for c in (centre, scene.groups[p.group].centre if p.group in scene.groups else centre):
            d_ = (p.pos - c) * np.array([1.0, 0.0, 1.0])
            out += d_ / max(la.norm(d_), 1e-12)
        if la.norm(out) < 1e-9:
            continue
        out /= la.norm(out)
        old_up = p.up / la.norm(p.up)
        p.pos = p.pos + lift * old_up
        p.up = np.cos(d) * UP + np.sin(d) * out
        p.right = np.cos(d) * out - np.sin(d) * UP
        p.scale = p.scale * np.array([length, 1.0, width])
        n += 1
    return n


def main(src: Path, droop: float, length: float, width: float, lift: float, obstacles: Path, dst: Path) -> int:
    scene = read_scn(src)
    n = spread(scene, droop, length, width, lift)
    scene.placements.extend(read_scn(obstacles).placements)
    write_scn(dst, scene, header=f"{src.name} with its {n} ray florets spread outward (spread_rays.py, droop {droop:g}, "
                                 f"length {length:g}, width {width:g}, lift {lift:g})")
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 8:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    a = sys.argv
    sys.exit(main(Path(a[1]), float(a[2]), float(a[3]), float(a[4]), float(a[5]), Path(a[6]), Path(a[7])))
