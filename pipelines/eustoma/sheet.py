"""Contact sheet of the three Eustoma cultivars, one row each (Ijiri et al. 2008, fig. 17).

Usage: python sheet.py BUILD_DIR --frames 1,10,...,100 [--tile WxH] [--elevation DEG] -o OUT.png

Each row is canopy-render's sheet of one cultivar's keyframes (BUILD_DIR/<cultivar>/) with the
calyx and column (BUILD_DIR/column_obj/), coloured by colors.toml (the petals' material is the
cultivar's name), framed on all its frames; the rows are stacked with a title.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from inflo.tools.canopy_render.output import write_png

HERE = Path(__file__).resolve().parent
CULTIVARS = {"mellow_yellow": "Mellow Yellow (bell)", "maite_lady": "Maite Lady (funnel)",
             "pinocchio": "Pinocchio (shallow ball)"}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("build", type=Path)
    ap.add_argument("--frames", default="1,10,20,30,40,50,60,70,80,90,100")
    ap.add_argument("--tile", default="240x240")
    ap.add_argument("--elevation", default="15")
    ap.add_argument("-o", "--output", required=True, type=Path)
    a = ap.parse_args()
    render = Path(sys.executable).parent / "canopy-render"
    rows = []
    frames = a.frames.split(",")
    with tempfile.TemporaryDirectory() as tmp:
        # the three cultivars' renders run side by side (each a process of its own; the rows are
        # assembled in the cultivars' order, so the sheet does not depend on which ends first)
        jobs = []
        for name in CULTIVARS:
            out = Path(tmp) / f"{name}.png"
            cmd = [str(render), "-q", str(a.build / name), str(a.build / "column_obj"),
                   "--colors", str(HERE / "colors.toml"), "--elevation", a.elevation,
                   "--size", a.tile, "--fit-all", "-o", str(out), "--label", "" if len(frames) == 1 else "frame {n}"]
            cmd += ["--frame", frames[0]] if len(frames) == 1 else ["--sheet", a.frames, "--columns", str(len(frames))]
            jobs.append((out, subprocess.Popen(cmd)))
        failed = [p.args for _, p in jobs if p.wait() != 0]
        if failed:
            raise subprocess.CalledProcessError(1, failed[0])
        for (out, _), title in zip(jobs, CULTIVARS.values()):
            im = Image.open(out).convert("RGB")
            band = Image.new("RGB", (im.width, im.height + 40), "white")
            band.paste(im, (0, 40))
            ImageDraw.Draw(band).text((12, 6), title, fill=(0, 0, 0), font=ImageFont.load_default(size=28))
            rows.append(band)
    if len(a.frames.split(",")) == 1:  # the open flowers side by side
        sheet = Image.new("RGB", (sum(r.width for r in rows), max(r.height for r in rows)), "white")
        x = 0
        for r in rows:
            sheet.paste(r, (x, 0))
            x += r.width
    else:
        sheet = Image.new("RGB", (max(r.width for r in rows), sum(r.height for r in rows)), "white")
        y = 0
        for r in rows:
            sheet.paste(r, (0, y))
            y += r.height
    a.output.parent.mkdir(parents=True, exist_ok=True)
    write_png(a.output, np.asarray(sheet.convert("RGB")))
    return 0


if __name__ == "__main__":
    sys.exit(main())
