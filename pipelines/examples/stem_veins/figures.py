"""Compose the docs pictures of the stem vasculature examples (run by ``make figures``).

    figures.py BUILD_DIR DOCS_DIR

- ``stem_veins_diagrams.png``: the unrolled diagrams of the golden-angle row (R/H from 11.5 to 1.2:
  connectivity (5, 8), (3, 5), (2, 3), (1, 1), as fig. 6.8), the Lucas angle, the open pattern, the
  decussate and the distichous stems, each titled with its connectivity;
- ``stem_veins_3d.png``: the (5, 8) stem in 3-D beside its diagram after internodal growth.
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from PIL import Image, ImageDraw

ROWS = [["golden_5_8", "golden_3_5", "golden_2_3", "golden_1_1"],
        ["lucas_4_7", "open_golden", "decussate", "distichous"]]


def _tile(folder: Path, width: int) -> Image.Image:
    img = Image.open(folder / "diagram.png").convert("RGB")
    img = img.resize((width, max(1, round(img.height * width / img.width))))
    summary = (folder / "connectivity.txt").read_text().splitlines()
    out = Image.new("RGB", (width, img.height + 44), "white")
    out.paste(img, (0, 44))
    d = ImageDraw.Draw(out)
    d.text((6, 4), folder.name.replace("_", " "), fill=(0, 0, 0))
    d.text((6, 22), summary[2] if len(summary) > 2 else "", fill=(60, 60, 60))
    return out


def main(build: str, docs: str) -> None:
    build_dir, docs_dir = Path(build), Path(docs)
    width = 520
    rows = [[_tile(build_dir / name, width) for name in row] for row in ROWS]
    height = [max(t.height for t in row) for row in rows]
    sheet = Image.new("RGB", (width * 4, sum(height)), "white")
    y = 0
    for row, h in zip(rows, height):
        for k, tile in enumerate(row):
            sheet.paste(tile, (k * width, y))
        y += h
    sheet.save(docs_dir / "stem_veins_diagrams.png")
    hero = build_dir / "golden_5_8"
    render = build_dir / "golden_5_8_3d.png"
    subprocess.run([str(Path(sys.executable).parent / "canopy-render"), str(hero / "veins.obj"), "-o", str(render),
                    "--up-axis", "z", "--elevation", "20", "--size", "700x900", "-q"], check=True)
    left = Image.open(render).convert("RGB")
    right = Image.open(hero / "diagram_grown.png").convert("RGB")
    right = right.resize((round(right.width * 900 / right.height), 900)) if right.height > 900 else right
    both = Image.new("RGB", (left.width + right.width, max(left.height, right.height)), "white")
    both.paste(left, (0, 0))
    both.paste(right, (left.width, (both.height - right.height) // 2))
    both.save(docs_dir / "stem_veins_3d.png")


if __name__ == "__main__":
    main(*sys.argv[1:3])
