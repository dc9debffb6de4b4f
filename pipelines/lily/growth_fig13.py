"""Ijiri et al. 2008, fig. 13: one petal of the growth-map lily at its 75th keyframe, seen from the
side (a) and from the top (b): the "slightly swollen petal shape caused by midrib warping"
(sec. 6.1: the large difference between e-growth and e-growth_in on the midrib).

Usage: python growth_fig13.py CANOPY_DIR -o OUT.png [--keyframe 75] [--organ petal_0]

The petal (its OBJ group) is taken out of the keyframe and turned about the flower's axis so that
its midrib points along +X: panel (a) looks at it along -Z (its profile: the midrib arching back,
the lamina standing above it), panel (b) from above (along -Y, its inner face). The caption gives
the petal's cross-section at 0.3, 0.5 and 0.7 of its length (signed sagitta over chord, > 0 the
lamina raised towards the inner side about a reflexing midrib: the swelling).
"""
from __future__ import annotations

import argparse
import io
import math
import sys
import tempfile
from pathlib import Path

import numpy as np
from check_growth import row_sagitta
from growth_beside import still
from growth_keys import TEPALS
from PIL import Image, ImageDraw, ImageFont

from inflo.formats.atomic import write_bytes_atomic
from inflo.formats.obj import ObjMesh, list_obj_sequence, read_obj, write_obj


def petal(mesh: ObjMesh, organ: str) -> tuple[ObjMesh, np.ndarray]:
    """The organ's own mesh, turned so its midrib points along +X; and its (nv, nu) grid of ids."""
    g = mesh.groups.index(organ)
    faces = mesh.faces[mesh.face_group == g]
    ids = np.unique(faces)
    kind = organ.split("_")[0]
    grid = np.arange(len(ids)).reshape(TEPALS[kind]["nv"], TEPALS[kind]["nu"])
    x = mesh.vertices[ids]
    remap = np.full(len(mesh.vertices), -1, np.int64)
    remap[ids] = np.arange(len(ids))
    mid = x[grid[:, grid.shape[1] // 2]]
    d = mid[-1] - mid[0]
    a = math.atan2(d[2], d[0])
    c, s = math.cos(a), math.sin(a)
    # turn by -a about +Y: the midrib's end lands on +X
    rx = c * x[:, 0] + s * x[:, 2]
    rz = -s * x[:, 0] + c * x[:, 2]
    x = np.stack([rx, x[:, 1], rz], axis=1)
    out = ObjMesh(vertices=x, faces=remap[faces].astype(np.int32), groups=[organ],
                  face_group=np.zeros(len(faces), np.int32), materials=mesh.materials[:1] or ["4"],
                  face_material=np.zeros(len(faces), np.int32))
    return out, grid


def cross_sections(x: np.ndarray, grid: np.ndarray, at=(0.3, 0.5, 0.7)) -> list[float]:
    """Signed sagitta / chord of the rows at these fractions of the length (inner side > 0)."""
    return [row_sagitta(x, grid, int(round(f * (grid.shape[0] - 1)))) for f in at]


def render(obj: Path, view: str, out: Path) -> Image.Image:
    return still([obj], ["--view", view, "--ortho", "--size", "560x420"], out)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("canopy", type=Path)
    ap.add_argument("-o", "--output", required=True, type=Path)
    ap.add_argument("--keyframe", type=int, default=75, help="1-based keyframe [75, as fig. 13]")
    ap.add_argument("--organ", default="petal_0")
    a = ap.parse_args()
    paths = list_obj_sequence(a.canopy)
    if not 1 <= a.keyframe <= len(paths):
        sys.exit(f"{a.canopy}: keyframe {a.keyframe} not in 1..{len(paths)}")
    mesh, grid = petal(read_obj(paths[a.keyframe - 1]), a.organ)
    sag = cross_sections(mesh.vertices, grid)
    with tempfile.TemporaryDirectory() as tmp:
        obj = Path(tmp) / "petal.obj"
        write_obj(obj, mesh, mtllib=None)
        ims = [render(obj, "front", Path(tmp) / "a.png"), render(obj, "top", Path(tmp) / "b.png")]
    w, h = ims[0].width, ims[0].height
    out = Image.new("RGB", (2 * w, h + 64), "white")
    draw = ImageDraw.Draw(out)
    font = ImageFont.load_default(size=18)
    for k, (im, label) in enumerate(zip(ims, ("(a) side", "(b) top"))):
        out.paste(im, (k * w, 30))
        draw.text((k * w + 12, 6), label, fill=(0, 0, 0), font=font)
    draw.text((12, h + 36), f"{a.organ}, keyframe {a.keyframe}: cross-section sagitta/chord at 0.3, 0.5, 0.7 of "
              f"the length {sag[0]:+.3f}, {sag[1]:+.3f}, {sag[2]:+.3f}", fill=(0, 0, 0), font=font)
    buf = io.BytesIO()
    out.save(buf, format="PNG")
    write_bytes_atomic(a.output, buf.getvalue())
    print(f"{a.output}: sagitta/chord {sag[0]:+.3f} {sag[1]:+.3f} {sag[2]:+.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
