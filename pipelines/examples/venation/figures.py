"""The venation pictures of the docs, from the examples of this folder.

    .venv/bin/python pipelines/examples/venation/figures.py [OUT_DIR]     # default: docs/

- ``venation_open.png``: open patterns with marginal growth, the kill distance d_k varied as in
  Runions fig. 4.14 a-e (open_marginal.toml with d_k = 16, 8, 4, 2, 1), and the Ginkgo fan of
  fig. 4.15 (ginkgo.toml);
- ``venation_closed.png``: the closed, reticulate poplar-like leaf of figs. 4.21/4.23 grown
  isogonically (poplar.toml), with the exact relative neighbourhood and with the Urquhart
  approximation, as the two models of fig. 4.23.
- ``venation_leaves.png``: the species leaves: the sunflower leaf (sunflower.toml: closed, with the
  ch. 5 refinements), a close-up of its areoles with and without the blind veinlets of sec. 5.2.4
  (the same run with ``veins.blind_after = -1``), and the yarrow leaf (yarrow.toml: open, veins
  kept inside the dissected blade);
- ``venation_arabidopsis.png``: the first leaf of Arabidopsis as it develops (Runions sec. 5.3):
  the development sheets (development.py) of the key-frame run (arabidopsis_kf.toml, figs.
  5.9-5.11) over the local-to-global run (arabidopsis_ltg.toml, fig. 5.7);
- ``venation_textured.png``: the two leaves' ``blade.obj`` drawn by ``canopy-render
  --mtl-textures`` (the vein texture on the blade mesh, lit), face-on and tilted.

Each panel is the run's ``texture.png`` (the veins drawn by width over the blade) on white, with a
caption of the run's figures; 64-colour PNGs. The runs go to a temporary folder.
"""
from __future__ import annotations

import math
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
    if not overrides:
        out = work / name
    r = run_venation(p, load_inputs(p), out)
    return r, Image.open(out / "texture.png").convert("RGBA")


def _panel(img: Image.Image, height: int, caption: str, font) -> Image.Image:
    w = round(img.width * height / img.height)
    leaf = img.resize((w, height), Image.Resampling.LANCZOS)
    pad = 16
    cap_h = 44
    text_w = max(int(math.ceil(font.getlength(line))) for line in caption.splitlines()) if hasattr(font, "getlength") else 0
    width = max(w + 2 * pad, text_w + 2 * pad)
    panel = Image.new("RGB", (width, height + cap_h + 2 * pad), "white")
    panel.paste(leaf, ((width - w) // 2, pad), leaf)
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
    if len(argv) > 1 and argv[1] == "leaves":  # only the species leaves' pictures
        leaves(out_dir, font)
        return 0
    if len(argv) > 1 and argv[1] == "arabidopsis":  # only the development sheets
        arabidopsis(out_dir, font)
        return 0
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
    leaves(out_dir, font)
    arabidopsis(out_dir, font)
    return 0


def arabidopsis(out_dir: Path, font) -> None:
    """The two development sheets, key frames over local-to-global, each under a title line."""
    sys.path.insert(0, str(HERE))
    from development import sheet

    sheets = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for name, its, title in (
                ("arabidopsis_kf", [30, 70, 100, 130, 160, 190, 210, 230],
                 "key frames (sec. 5.3.2, figs. 5.9-5.11): the midvein, three pairs of loops in turn, "
                 "then higher orders, blind veins"),
                ("arabidopsis_ltg", [10, 20, 40, 60, 70, 80, 90, 110],
                 "local-to-global growth (sec. 5.3.1, fig. 5.7): the loops form together, as the thesis reports")):
            r, _ = run(name, work, **{"output.frame_step": 10})
            png = sheet(work / f"{name}_frame_step10", work / f"{name}.png", its)
            img = Image.open(png).convert("RGB")
            head = Image.new("RGB", (img.width, 48), "white")
            ImageDraw.Draw(head).multiline_text((8, 4), f"{title}\n{_figures(r)}", fill=(20, 20, 20), font=font)
            sheets += [head, img]
            print(f"{name}: {_figures(r)}, {r.result.seconds:.2f} s", flush=True)
    _save(_column(sheets), out_dir / "venation_arabidopsis.png")


def _crop(img: Image.Image, box) -> Image.Image:
    """The part (x0, y0, x1, y1 as fractions, y down) of a texture, on white."""
    w, h = img.size
    c = img.crop((int(box[0] * w), int(box[1] * h), int(box[2] * w), int(box[3] * h)))
    out = Image.new("RGBA", c.size, "white")
    out.alpha_composite(c)
    return out


def leaves(out_dir: Path, font) -> None:
    """``venation_leaves.png`` and ``venation_textured.png`` (module docstring)."""
    from inflo.tools.canopy_render.job import RenderJob, run_job
    from inflo.tools.canopy_render.render import RenderOptions

    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        sun, sun_img = run("sunflower", work)
        closed, closed_img = run("sunflower", work, **{"veins.blind_after": -1})
        yar, yar_img = run("yarrow", work)
        for name, r in (("sunflower", sun), ("sunflower closed", closed), ("yarrow", yar)):
            print(f"{name}: {_figures(r)}, {r.result.blind_ends} blind veins, {r.result.seconds:.2f} s", flush=True)
        box = (0.60, 0.46, 0.74, 0.59)
        panels = [
            _panel(sun_img, 820, f"sunflower (closed, sec. 4.3 + ch. 5)\n{_figures(sun)}", font),
            _panel(_crop(closed_img, box), 400, "areoles, ch. 4: every vein joins", font),
            _panel(_crop(sun_img, box), 400, f"ch. 5: blind veinlets (sec. 5.2.4)\n{sun.result.blind_ends:,} blind ends",
                   font),
            _panel(yar_img, 820, f"yarrow (open, inside the blade)\n{_figures(yar)}", font),
        ]
        top = _row(panels[:1] + [_column(panels[1:3])] + panels[3:])
        _save(top, out_dir / "venation_leaves.png")
        shots = []
        for name, view, size in (("sunflower", "front", (700, 700)), ("sunflower", "iso", (700, 700)),
                                 ("yarrow", "iso", (360, 700))):
            png = work / f"{name}_{view}.png"
            job = RenderJob(inputs=[str(work / name / "blade.obj")], output=png, size=size, view=view,
                            ortho=view == "front", mtl_textures=True, quiet=True,
                            options=RenderOptions(background=(1.0, 1.0, 1.0)))
            print(run_job(job), flush=True)
            shots.append(_panel(Image.open(png).convert("RGBA"), size[1],
                                f"{name}: blade.obj + texture.png\ncanopy-render --mtl-textures --view {view}", font))
        _save(_row(shots), out_dir / "venation_textured.png")


def _column(panels) -> Image.Image:
    w = max(p.width for p in panels)
    out = Image.new("RGB", (w, sum(p.height for p in panels)), "white")
    y = 0
    for p in panels:
        out.paste(p, (0, y))
        y += p.height
    return out


if __name__ == "__main__":
    sys.exit(main())
