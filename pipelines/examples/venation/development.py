"""A development sheet of a growing leaf's venation (as Runions figs. 5.7 and 5.10): the frames of
a run written with ``--frame-step``, each with its blade, its veins (drawn by width) and the events
of events.csv (a red ring where the midvein reached its source, in the panel where it did; the
loops of secondary veins numbered in red, by the order of their formation), captioned with its
iteration and the events since the last panel.

    .venv/bin/python pipelines/examples/venation/development.py RUN_DIR OUT.png [ITERATIONS...]

RUN_DIR is a venation output folder with ``frames/`` and ``events.csv``. Without ITERATIONS the
panels are eight frames evenly spread over the run. Panels share one scale per row; each row is
scaled to fit the largest blade of that row, with a scale bar of 0.5 blade units, as fig. 5.10's
rows are.
"""
from __future__ import annotations

import csv
import sys
from pathlib import Path

from PIL import Image, ImageDraw, ImageFont

PANEL = 300  # pixels per panel side
PER_ROW = 4


def read_lines_obj(path: Path):
    """(vertices [(x, y)], polylines [[i, ...]]) of an OBJ of ``v`` and ``l`` lines (0-based)."""
    vs, ls = [], []
    for line in path.read_text().splitlines():
        if line.startswith("v "):
            x, y = line.split()[1:3]
            vs.append((float(x), float(y)))
        elif line.startswith("l "):
            ls.append([int(w) - 1 for w in line.split()[1:]])
    return vs, ls


def read_widths(path: Path) -> list[float]:
    return [float(w) for w in path.read_text().split("\n") if w and not w.startswith("#")]


def read_events(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _font(size=14):
    for name in ("DejaVuSans.ttf", "Arial.ttf"):
        try:
            return ImageFont.truetype(name, size)
        except OSError:
            continue
    return ImageFont.load_default()


def frames_of(run: Path) -> dict[int, Path]:
    return {int(p.stem.split("_")[1]): p for p in sorted((run / "frames").glob("veins_*.obj"))}


def caption(events, lo: int, hi: int) -> str:
    """The events in (lo, hi], in words."""
    words = []
    for e in events:
        it = int(e["iteration"])
        if not lo < it <= hi:
            continue
        if e["event"] == "midvein":
            words.append("midvein")
        elif e["event"] == "loop":
            side = "L" if float(e["x"]) < 0 else "R"
            kind = "secondary" if e.get("midvein") == "1" else f"order-{e['order']}"
            words.append(f"loop {e['index']} ({kind} {side})")
        elif e["event"] == "blind_end":
            words.append("blind vein")
    n_src = sum(1 for e in events if e["event"] == "source" and lo < int(e["iteration"]) <= hi)
    if n_src:
        words.insert(0, f"{n_src} source{'s' if n_src > 1 else ''}")
    return ", ".join(words) if words else "growth"


def sheet(run: Path, out: Path, iterations=None) -> Path:
    run = Path(run)
    frames = frames_of(run)
    if not frames:
        raise SystemExit(f"{run}: no frames/ (run venation with --frame-step)")
    events = read_events(run / "events.csv")
    its = sorted(frames)
    if iterations:
        its = [min(its, key=lambda f: abs(f - int(i))) for i in iterations]
    elif len(its) > 8:
        its = [its[round(k * (len(its) - 1) / 7)] for k in range(8)]
    font = _font()
    rows = [its[k:k + PER_ROW] for k in range(0, len(its), PER_ROW)]
    cap_h = 58
    img = Image.new("RGB", (PANEL * PER_ROW, (PANEL + cap_h) * len(rows)), "white")
    d = ImageDraw.Draw(img)
    prev = -1
    for r, row in enumerate(rows):
        data = []
        for it in row:
            blade, _ = read_lines_obj(run / "frames" / f"blade_{it:04d}.obj")
            vs, ls = read_lines_obj(frames[it])
            wpath = frames[it].with_suffix(".widths")
            ws = read_widths(wpath) if wpath.exists() else [0.0] * len(vs)
            data.append((it, blade, vs, ls, ws))
        span = max(max(max(x for x, _ in b) - min(x for x, _ in b), max(y for _, y in b) - min(y for _, y in b))
                   for _, b, *_ in data)
        s = 0.86 * PANEL / max(span, 1e-12)
        for c, (it, blade, vs, ls, ws) in enumerate(data):
            ox, oy = c * PANEL + PANEL / 2, r * (PANEL + cap_h) + PANEL * 0.94
            cx = 0.5 * (max(x for x, _ in blade) + min(x for x, _ in blade))
            y0 = min(y for _, y in blade)

            def px(p, ox=ox, oy=oy, cx=cx, y0=y0, s=s):
                return (ox + (p[0] - cx) * s, oy - (p[1] - y0) * s)

            d.polygon([px(p) for p in blade], fill=(222, 240, 210), outline=(90, 140, 70))
            for poly in ls:
                for a, b in zip(poly, poly[1:]):
                    w = max(1, round(max(ws[a], ws[b]) * s)) if ws else 1
                    d.line([px(vs[a]), px(vs[b])], fill=(30, 80, 30), width=w)
            mid = [e for e in events if e["event"] == "midvein" and prev < int(e["iteration"]) <= it]
            for e in mid:
                q = px((float(e["x"]), float(e["y"])))
                d.ellipse([q[0] - 4, q[1] - 4, q[0] + 4, q[1] + 4], outline=(200, 30, 30), width=2)
            for e in events:
                if e["event"] == "loop" and int(e["iteration"]) <= it and e.get("midvein") == "1" and e["order"] == "1":
                    q = px((float(e["x"]), float(e["y"])))
                    d.text((q[0] - 4, q[1] - 7), e["index"], fill=(180, 40, 40), font=font)
            bar = 0.5 * s
            d.line([(c * PANEL + 10, r * (PANEL + cap_h) + 12), (c * PANEL + 10 + bar, r * (PANEL + cap_h) + 12)],
                   fill=(0, 0, 0), width=3)
            text = f"iteration {it}\n" + _wrap(caption(events, prev, it), 40)
            d.multiline_text((c * PANEL + 8, r * (PANEL + cap_h) + PANEL + 2), text, fill=(40, 40, 40), font=font,
                             spacing=2)
            prev = it
    out.parent.mkdir(parents=True, exist_ok=True)
    img.quantize(colors=64, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE).save(out, optimize=True)
    return out


def _wrap(text: str, width: int) -> str:
    out, line = [], ""
    for word in text.split(" "):
        if len(line) + len(word) + 1 > width and line:
            out.append(line)
            line = word
        else:
            line = f"{line} {word}".strip()
    out.append(line)
    return "\n".join(out[:2]) + ("…" if len(out) > 2 else "")


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    print(f"wrote {sheet(Path(argv[0]), Path(argv[1]), argv[2:] or None)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
