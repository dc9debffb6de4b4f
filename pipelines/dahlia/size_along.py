"""Size the ray florets along the ball so that it stays round (the `dimorph` stage's last step).

Usage: python size_along.py IN.scn OUT.scn GAIN POWER

A ball dahlia's receptacle is a dome, not a sphere: with florets of one size standing on it, the
head would be a hemisphere with a flattened top (its last, youngest florets, at the top, are the
least developed). The florets formed later, higher up the dome, are made larger, so that the open
ball is round ("sized along the ball so the ball stays round"): the scale of the k-th of
n ray florets in their order of formation (0 at the base, n - 1 at the top) is multiplied by
``1 + GAIN (k / (n - 1)) ** POWER``. Bracts keep theirs. Written atomically (formats.scn).
"""
from __future__ import annotations

import sys
from pathlib import Path

from inflo.formats.scn import read_scn, write_scn


def main(src: Path, dst: Path, gain: float, power: float) -> int:
    scene = read_scn(src)
    # the terminal floret on the apex itself is a ray floret too: dimorph's cone has no direction
    # at the head's centre (it reads as a disk floret there); a ball dahlia has no disk florets
    for p in scene.placements:
        if p.type == "disk":
            p.type = "ray"
    rays = [p for p in scene.placements if p.type == "ray"]
    n = len(rays)
    for k, p in enumerate(rays):
        f = k / (n - 1) if n > 1 else 0.0
        p.scale = p.scale * (1.0 + gain * f ** power)
    write_scn(dst, scene, header=f"{src.name} with the ray florets sized along the ball "
                                 f"(size_along.py, gain {gain:g}, power {power:g})")
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 5:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1]), Path(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])))
