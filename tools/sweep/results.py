"""What a sweep writes at the end: ``results.csv``, ``contact_sheet.png`` (every
variant's still labelled by its parameters, Pillow) and ``heatmap.png`` (a 2-D numeric grid of a
scalar metric with Fibonacci numbers marked, matplotlib). All written atomically.
"""
from __future__ import annotations

import csv
import io
import math
from pathlib import Path

from inflo.formats.atomic import write_bytes_atomic, write_text_atomic

from .spec import Sweep, format_value

__all__ = ["FIBONACCI", "write_results_csv", "write_contact_sheet", "write_heatmap", "heatmap_metric"]

FIBONACCI = (1, 2, 3, 5, 8, 13, 21, 34, 55, 89, 144, 233, 377, 610, 987, 1597)


def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.6g}"
    return format_value(v)


def write_results_csv(path, sweep: Sweep, results: list[dict]) -> None:
    """One row per variant, in sweep order: id, the parameters, status (ok/failed), ran
    (ran/cached), exit_code, wall_s, peak_mb, the metrics, still, error."""
    names = [a.name for a in sweep.axes]
    metrics = [m.name for m in sweep.metrics]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["id", *names, "status", "ran", "exit_code", "wall_s", "peak_mb", *metrics, "still", "error"])
    for r in sorted(results, key=lambda r: r["index"]):
        p = dict(r["params"])
        m = r.get("metrics", {})
        w.writerow([r["id"], *[_cell(p.get(n)) for n in names], r["status"], r.get("ran", "ran"), r["exit_code"],
                    f"{r['wall_s']:.3f}", f"{r['peak_mb']:.1f}", *[_cell(m.get(n, "")) for n in metrics],
                    r.get("still", ""), r.get("error", "")])
    write_text_atomic(path, buf.getvalue())


def _label(r: dict) -> str:
    text = ", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={format_value(v)}" for k, v in r["params"])
    return text or r["id"]


def write_contact_sheet(path, out_dir, results: list[dict], *, limit: int = 64, cell: int = 240) -> int:
    """A grid of the variants' stills (the first ``limit`` variants in sweep order, those without a
    still as a grey cell saying why), each labelled by its parameters. Returns the cells drawn
    (0: nothing written, no variant has a still)."""
    from PIL import Image, ImageDraw, ImageFont

    rows = sorted(results, key=lambda r: r["index"])[:limit]
    if not rows or not any(r.get("still") for r in rows):
        return 0
    ncols = min(len(rows), max(1, math.ceil(math.sqrt(len(rows)))))
    nrows = math.ceil(len(rows) / ncols)
    label_h = 34
    sheet = Image.new("RGB", (ncols * cell, nrows * (cell + label_h)), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    try:
        font = ImageFont.load_default(size=12)
    except TypeError:  # Pillow < 10.1
        font = ImageFont.load_default()
    for k, r in enumerate(rows):
        x0, y0 = (k % ncols) * cell, (k // ncols) * (cell + label_h)
        img = None
        if r.get("still"):
            try:
                with Image.open(Path(out_dir) / r["still"]) as im:
                    img = im.convert("RGB")
                    img.thumbnail((cell - 8, cell - 8))
            except OSError:
                img = None
        if img is not None:
            sheet.paste(img, (x0 + (cell - img.width) // 2, y0 + (cell - img.height) // 2))
        else:
            draw.rectangle([x0 + 4, y0 + 4, x0 + cell - 4, y0 + cell - 4], fill=(200, 200, 200))
            why = "failed" if r["status"] != "ok" else "no still"
            draw.text((x0 + 12, y0 + cell // 2 - 6), why, fill=(120, 0, 0) if r["status"] != "ok" else (60, 60, 60),
                      font=font)
        label = _label(r)
        lines = [label[i:i + 36] for i in range(0, min(len(label), 72), 36)]
        for j, ln in enumerate(lines):
            draw.text((x0 + 6, y0 + cell + 2 + 14 * j), ln, fill=(0, 0, 0), font=font)
    buf = io.BytesIO()
    sheet.save(buf, format="PNG")
    write_bytes_atomic(path, buf.getvalue())
    return len(rows)


def heatmap_metric(sweep: Sweep) -> str | None:
    """The metric of the heat map: ``heatmap`` of the sweep, else the first metric; None unless
    the sweep is a grid of exactly two numeric axes."""
    if sweep.sampling != "grid" or len(sweep.axes) != 2 or not sweep.metrics:
        return None
    for a in sweep.axes:
        if not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in a.values):
            return None
    return sweep.heatmap or sweep.metrics[0].name


def write_heatmap(path, sweep: Sweep, results: list[dict]) -> bool:
    """The metric over the two axes (x: the first axis, y: the second) as coloured cells; cells
    whose value is a Fibonacci number are outlined and labelled, failed variants hatched.
    Returns False (nothing written) when the sweep is not such a grid or no value is numeric."""
    import numpy as np

    name = heatmap_metric(sweep)
    if name is None:
        return False
    ax_x, ax_y = sweep.axes
    xs, ys = list(ax_x.values), list(ax_y.values)
    grid = np.full((len(ys), len(xs)), np.nan)
    failed = np.zeros_like(grid, dtype=bool)
    ix = {x: i for i, x in enumerate(xs)}
    iy = {y: i for i, y in enumerate(ys)}
    for r in results:
        p = dict(r["params"])
        i, j = iy.get(p.get(ax_y.name)), ix.get(p.get(ax_x.name))
        if i is None or j is None:
            continue
        v = r.get("metrics", {}).get(name, "")
        if r["status"] != "ok":
            failed[i, j] = True
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            grid[i, j] = float(v)
    if not np.isfinite(grid).any():
        return False
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import BoundaryNorm

    fig, ax = plt.subplots(figsize=(min(14, 3 + 0.12 * len(xs) + 3), min(10, 2.5 + 0.25 * len(ys) + 2)))
    finite = grid[np.isfinite(grid)]
    is_int = bool(np.all(finite == np.round(finite)))

    # cells on the grid's indices, labelled by the values (uneven steps stay one cell each)
    ex, ey = np.arange(len(xs) + 1) - 0.5, np.arange(len(ys) + 1) - 0.5

    def ticks(axis_set, vals):
        step = max(1, math.ceil(len(vals) / 12))
        idx = list(range(0, len(vals), step))
        axis_set(idx, [f"{vals[i]:g}" for i in idx])
    cmap = plt.get_cmap("viridis").copy()
    cmap.set_bad((0.85, 0.85, 0.85))
    fibs = [f for f in FIBONACCI if finite.min() <= f <= finite.max()]
    norm = None
    if is_int and fibs:
        bounds = sorted(set([finite.min() - 0.5] + [f + 0.5 for f in fibs] + [finite.max() + 0.5]))
        if len(bounds) >= 2:
            norm = BoundaryNorm(bounds, cmap.N)
    mesh = ax.pcolormesh(ex, ey, np.ma.masked_invalid(grid), cmap=cmap, norm=norm, shading="flat")
    cb = fig.colorbar(mesh, ax=ax)
    cb.set_label(name)
    if fibs:
        cb.set_ticks(fibs)
    fibset = set(FIBONACCI)
    small = len(xs) * len(ys) <= 400
    for i in range(len(ys)):
        for j in range(len(xs)):
            v = grid[i, j]
            xc, yc = (ex[j] + ex[j + 1]) / 2, (ey[i] + ey[i + 1]) / 2
            if failed[i, j]:
                ax.add_patch(plt.Rectangle((ex[j], ey[i]), ex[j + 1] - ex[j], ey[i + 1] - ey[i], fill=False,
                                           hatch="xx", edgecolor="tab:red", lw=0))
            elif np.isfinite(v) and is_int and int(v) in fibset:
                ax.add_patch(plt.Rectangle((ex[j], ey[i]), ex[j + 1] - ex[j], ey[i + 1] - ey[i], fill=False,
                                           edgecolor="white", lw=0.6))
                if small:
                    ax.text(xc, yc, f"{int(v)}", ha="center", va="center", fontsize=6, color="white")
    ticks(ax.set_xticks, xs)
    ticks(ax.set_yticks, ys)
    ax.set_xlabel(ax_x.name)
    ax.set_ylabel(ax_y.name)
    n_fib = int(sum(1 for v in finite if is_int and int(v) in fibset))
    ax.set_title(f"{sweep.name}: {name} over {ax_x.name} x {ax_y.name}; "
                 f"{n_fib} of {finite.size} cells a Fibonacci number (outlined)", fontsize=9)
    buf = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    write_bytes_atomic(path, buf.getvalue())
    return True
