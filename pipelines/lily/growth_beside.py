"""The open growth-map lily beside the key-pose lily: one picture, two panels.

Usage: python growth_beside.py BUILD_DIR -o OUT.png     (BUILD_DIR = build/lily)

Left: the last keyframe of petal-grow (BUILD_DIR/growth/canopy) with its column
(BUILD_DIR/growth/column_obj); right: the last smoothed, painted frame of the key-pose lily with
its column (BUILD_DIR/painted, BUILD_DIR/column_keyframes). Each panel
is a canopy-render still with the lily's colours and the same camera.
"""
from __future__ import annotations

import argparse
import io
import subprocess
import sys
import tempfile
from pathlib import Path

from PIL import Image, ImageDraw, ImageFont

from inflo.formats.atomic import write_bytes_atomic

HERE = Path(__file__).resolve().parent
PANELS = (("growth maps (petal-grow, Ijiri et al. 2008)", ("growth/canopy", "growth/column_obj")),
          ("key poses (floret-animate + fccompose)", ("painted", "column_keyframes")))


def still(inputs, options, out: Path) -> Image.Image:
    """A canopy-render still of these inputs in the lily's colours (options: view, size, ...)."""
    render = Path(sys.executable).parent / "canopy-render"
    subprocess.run([str(render), "-q", *map(str, inputs), "--colors", str(HERE / "colors.toml"), *options,
                    "-o", str(out)], check=True)
    return Image.open(out).convert("RGB")


def panel(build: Path, inputs, out: Path) -> Image.Image:
    return still([build / i for i in inputs], ["--frame", "-1", "--azimuth", "0", "--elevation", "35",
                                               "--size", "640x560"], out)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("build", type=Path)
    ap.add_argument("-o", "--output", required=True, type=Path)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        ims = [panel(a.build, inputs, Path(tmp) / f"{k}.png") for k, (_, inputs) in enumerate(PANELS)]
    width = ims[0].width
    out = Image.new("RGB", (width * len(ims), max(i.height for i in ims) + 30), "white")
    for k, im in enumerate(ims):
        out.paste(im, (k * width, 30))
        ImageDraw.Draw(out).text((k * width + 12, 6), PANELS[k][0], fill=(0, 0, 0), font=ImageFont.load_default(size=20))
    buf = io.BytesIO()
    out.save(buf, format="PNG")
    write_bytes_atomic(a.output, buf.getvalue())
    return 0


if __name__ == "__main__":
    sys.exit(main())
