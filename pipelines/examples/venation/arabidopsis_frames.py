"""The key frames of the first leaf of Arabidopsis thaliana (Runions sec. 5.3.2, fig. 5.9): six
blade surfaces, youngest to oldest, written as one-patch Bezier surfaces (``.s``) for
``arabidopsis_kf.toml``.

    .venv/bin/python pipelines/examples/venation/arabidopsis_frames.py [OUT_DIR]   # default: this folder

Each key frame is a bicubic patch in the blade plane: row 0 is the base (collapsed to the contact
point, the origin), row 3 the tip (collapsed to a point on the midrib, +y), rows 1 and 2 the
margin's two inner control points on each side, the columns spread evenly across the blade (so v
runs from the left margin to the right one, u from the base to the tip, and the midrib is
v = 1/2). The progression follows the text of sec. 5.3.1 and fig. 5.9: a small narrow protrusion
(a) elongates (b); the distal half widens first (c, obovate), then the middle (d), then the base
(e), until the blade is almost circular (f); the shapes are to scale, as in fig. 5.9.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from inflo.formats.bezier_surface import BezierPatch, BezierSurface, write_bezier_surface

HERE = Path(__file__).resolve().parent

#: (name, height h, row 1 half-width w1 at y1, row 2 half-width w2 at y2): the margin of each side
#: is the cubic Bezier (0, 0), (w1, y1), (w2, y2), (0, h)
FRAMES = [
    ("a", 0.35, 0.08, 0.10, 0.08, 0.25, 0.00),
    ("b", 1.00, 0.14, 0.25, 0.18, 0.75, 0.00),
    ("c", 1.50, 0.20, 0.40, 0.90, 1.30, 0.00),
    ("d", 1.90, 0.70, 0.50, 1.10, 1.60, 0.00),
    ("e", 2.50, 1.40, 0.30, 1.45, 2.05, 0.12),
    ("f", 5.00, 2.90, 0.30, 3.00, 4.30, 0.30),
]


def control_net(h, w1, y1, w2, y2, lift) -> np.ndarray:
    """(4, 4, 3): the patch of one key frame (z = 0). The inner columns of row 2 sit
    ``lift`` x h below the margin's: the blade near the midrib lags behind the margin, so a line
    of tissue drawn straight across the young blade is bowed up towards the margin later (veins
    arching up to the margin, as the secondary veins of fig. 5.10 do)."""
    rows = [(0.0, 0.0), (w1, y1), (w2, y2), (0.0, h)]
    net = np.zeros((4, 4, 3))
    for i, (w, y) in enumerate(rows):
        for j in range(4):
            inner = j in (1, 2) and i in (1, 2)
            net[i, j] = (w * (-1.0 + 2.0 * j / 3.0), y - (lift * h * (1.0 if i == 2 else y / h) if inner else 0.0), 0.0)
    return net


def surface(name, net) -> BezierSurface:
    return BezierSurface(patches=(BezierPatch(name=f"blade_{name}", control_points=net, top_color=1, top_diffuse=0.7,
                                              bottom_color=1, bottom_diffuse=0.7),),
                         contact=np.zeros(3), end=np.array([0.0, 1.0, 0.0]), heading=np.array([0.0, 1.0, 0.0]),
                         up=np.array([0.0, 0.0, 1.0]), size=1.0)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    out = Path(argv[0]) if argv else HERE
    out.mkdir(parents=True, exist_ok=True)
    for name, *shape in FRAMES:
        write_bezier_surface(out / f"arabidopsis_{name}.s", surface(name, control_net(*shape)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
