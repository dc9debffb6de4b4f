"""The tightly packed dahlia without and with collision handling, side by side (the `pictures`
stage; thesis fig. 9.1, and fig. 4.9's comparison for the lilac).

Usage: python compare.py BUILD_DIR WxH OUT.png   (BUILD_DIR = build/dahlia)

Renders the last frame of ``packed_off/`` (fccompose with ``collisions: off``: the same florets
growing through each other) and of ``packed/`` (collisions on) with canopy-render, and writes them
side by side (the whole ball above, a close-up of its side below), each captioned with its count of intersecting triangle pairs (the exact static test
of inflo.tools.collide; touching counts).
"""
from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.tools.canopy_render.output import write_png
from inflo.tools.collide import intersecting_pairs

HERE = Path(__file__).resolve().parent
#: the whole ball, and a close-up where the florets press on each other
ZOOMS = (1.0, 2.6)


def main(build: Path, size: str, out: Path) -> int:
    w, h = (int(v) for v in size.split("x"))
    render = Path(sys.executable).parent / "canopy-render"
    panels = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, title in (("packed_off", "collisions off"), ("packed", "collisions on")):
            last = list_obj_sequence(build / name)[-1]
            mesh = read_obj(last)
            n = len(intersecting_pairs(mesh.vertices, mesh.faces, tri_part=mesh.face_group))
            tiles = []
            for zoom in ZOOMS:
                png = Path(tmp) / f"{name}_{zoom}.png"
                subprocess.run([str(render), "-q", "--background", "0.55,0.70,0.86", "--colors",
                                str(HERE / "colors.toml"), str(build / name), str(build / "head" / "receptacle"),
                                "--frame", "-1", "--elevation", "30", "--azimuth", "20", "--zoom", str(zoom),
                                "--size", f"{w // 2}x{h // 2}", "-o", str(png)], check=True)
                tiles.append(Image.open(png).convert("RGB"))
            panels.append((tiles, f"{title}: {n} intersecting triangle pairs"))
    sheet = Image.new("RGB", (w, h + 40), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    font = ImageFont.load_default(size=18)
    for i, (tiles, caption) in enumerate(panels):
        for k, img in enumerate(tiles):
            sheet.paste(img, (i * (w // 2), k * (h // 2)))
        draw.text((i * (w // 2) + 12, h + 10), caption, fill=(0, 0, 0), font=font)
    write_png(out, np.asarray(sheet))
    print(f"{out}: " + "; ".join(c for _, c in panels))
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 4:
        print(__doc__.strip().splitlines()[3], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1]), sys.argv[2], Path(sys.argv[3])))
