"""The venation pictures of the docs, from the examples of this folder.

    .venv/bin/python pipelines/examples/venation/figures.py [OUT_DIR]     # default: docs/

- ``venation_open.png``: open patterns with marginal growth, the kill distance d_k varied as in
  Runions fig. 4.14 a-e (open_marginal.toml with d_k = 16, 8, 4, 2, 1), and the Ginkgo fan of
  fig. 4.15 (ginkgo.toml);
- ``venation_closed.png``: the closed, reticulate poplar-like leaf of figs. 4.21/4.23 grown
  isogonically (poplar.toml), with the exact relative neighbourhood and with the Urquhart
  approximation, as the two models of fig. 4.23.

Each panel is the run's ``texture.png`` (the veins drawn by width over the blade) on white, with a
caption of the run's figures; 64-colour PNGs. The runs go to a temporary folder.
"""
from __future__ import annotations

import sys
import tempfile
import tomllib
from pathlib import Path

from PIL import Image, ImageDraw, ImageFont

from inflo.tools.venation.generate import run_venation
from inflo.tools.venation.params import load_inputs, parse_params

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent.parent


def _toml(value) -> str:
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(value)


def run(name: str, work: Path, **overrides):
    """Run ``name``.toml of this folder with ``section.key`` overrides; returns (run, texture)."""
    data = tomllib.loads((HERE / f"{name}.toml").read_text())
    for dotted, value in overrides.items():
        section, key = dotted.split(".")
        data.setdefault(section, {})[key] = value
    lines = [f"{k} = {_toml(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for section, table in data.items():
        if isinstance(table, dict):
            lines.append(f"[{section}]")
            lines += [f"{k} = {_toml(v)}" for k, v in table.items()]
    p = parse_params("\n".join(lines) + "\n", HERE / f"{name}.toml")
    out = work / (name + "".join(f"_{k.split('.')[1]}{v}" for k, v in overrides.items()))
    r = run_venation(p, load_inputs(p), out)
    return r, Image.open(out / "texture.png").convert("RGBA")


def _panel(img: Image.Image, height: int, caption: str, font) -> Image.Image:
    w = round(img.width * height / img.height)
    leaf = img.resize((w, height), Image.Resampling.LANCZOS)
    pad = 16
    cap_h = 44
    panel = Image.new("RGB", (w + 2 * pad, height + cap_h + 2 * pad), "white")
    panel.paste(leaf, (pad, pad), leaf)
    d = ImageDraw.Draw(panel)
    for i, line in enumerate(caption.splitlines()):
        d.text((pad, height + pad + 6 + 18 * i), line, fill=(40, 40, 40), font=font)
    return panel


def _row(panels) -> Image.Image:
    w = sum(p.width for p in panels)
    h = max(p.height for p in panels)
    out = Image.new("RGB", (w, h), "white")
    x = 0
    for p in panels:
        out.paste(p, (x, 0))
        x += p.width
    return out


def _save(img: Image.Image, path: Path) -> None:
    """A 64-colour PNG (the pictures are a few greens and white)."""
    img.quantize(colors=64, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE).save(path, optimize=True)
    print(f"wrote {path}", flush=True)


def _font(size=15):
    for name in ("DejaVuSans.ttf", "Arial.ttf"):
        try:
            return ImageFont.truetype(name, size)
        except OSError:
            continue
    return ImageFont.load_default()


def _figures(r) -> str:
    res = r.result
    loops = f", {r.loops:,} loops" if r.loops else ""
    return f"{res.n_nodes:,} vein nodes{loops}, {res.iterations} iterations"


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    out_dir = Path(argv[0]) if argv else REPO / "docs"
    font = _font()
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        panels = []
        for dk in (16.0, 8.0, 4.0, 2.0, 1.0):
            r, img = run("open_marginal", work, **{"veins.kill_distance": dk, "texture.size": 700})
            panels.append(_panel(img, 520, f"open, marginal: d_k = {dk:g}\n{_figures(r)}", font))
            print(f"open_marginal d_k {dk:g}: {_figures(r)}, {r.result.seconds:.2f} s", flush=True)
        r, img = run("ginkgo", work, **{"texture.size": 900})
        panels.append(_panel(img, 520, f"Ginkgo fan (fig. 4.15)\n{_figures(r)}", font))
        print(f"ginkgo: {_figures(r)}, {r.result.seconds:.2f} s", flush=True)
        _save(_row(panels), out_dir / "venation_open.png")
        panels = []
        for nb, what in (("relative", "exact relative neighbourhood"), ("urquhart", "Urquhart approximation")):
            r, img = run("poplar", work, **{"veins.neighbourhood": nb, "texture.size": 1100})
            panels.append(_panel(img, 820, f"closed, isogonic growth: {what}\n{_figures(r)}", font))
            print(f"poplar {nb}: {_figures(r)}, {r.result.seconds:.2f} s", flush=True)
        _save(_row(panels), out_dir / "venation_closed.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
