"""What ``stem-veins`` writes (formats/stem_veins.md): the 3-D pattern, the unrolled idealized
diagram, the traces' joins and the connectivity.

- ``graph.obj``: the venation graph (vein nodes as ``v``, segments as ``l``), stem frame (z up);
- ``veins.obj``: the veins as generalized cylinders whose diameter decreases linearly with height,
  the primordia as spheres offset from the cylinder's surface (sec. 6.2.2), groups ``veins`` and
  ``primordia``;
- ``unrolled.obj`` and ``diagram.png``: the stem split along azimuth 0 and unrolled (eq. 6.3,
  fig. 6.4): a node (x, y, z) maps to (R phi, z, 0) with phi = atan2(y, x) in [0, 2 pi) (the thesis
  writes (phi, z, 0); the arc length R phi keeps the diagram's proportions); a segment across the cut
  is drawn on both sides of it, dashed in the picture, as in fig. 6.8;
- with a growth map (fig. 6.5), ``veins_grown.obj``, ``unrolled_grown.obj`` and
  ``diagram_grown.png``: every node's height h mapped to ``top g(h / top)`` (internodal growth as
  post-processing, fig. 6.6);
- ``traces.csv``: one row per pair of traces that joined: the iteration, the later primordium, the
  one whose trace it joins (0: the base ring), their difference and whether it is a Fibonacci number;
- ``connectivity.txt``: each primordium's joins to later ones (the connectivity (a, b) of sec. 6.3)
  and the share of joins between primordia whose index difference is a Fibonacci number.
"""
from __future__ import annotations

import collections
import math

import numpy as np

from inflo.tools.common.linalg import norm

from .model import StemRun, fibonacci_numbers

__all__ = ["connectivity", "unrolled", "vein_mesh", "write_outputs", "summary_lines", "OUTPUT_FILES"]

OUTPUT_FILES = (r"graph\.obj", r"veins\.obj", r"unrolled\.obj", r"diagram\.png", r"veins_grown\.obj",
                r"unrolled_grown\.obj", r"diagram_grown\.png", r"traces\.csv", r"connectivity\.txt")


# ---------------------------------------------------------------------------------------------
# connectivity (sec. 6.3)


def connectivity(run: StemRun, skip: int = 0) -> dict:
    """The joins between primordia and their Fibonacci share.

    Returns ``{"per": {n: [later primordia joining n's trace]}, "differences": Counter,
    "fibonacci_share": float, "mode": (a, b) or None}``; ``skip`` leaves out the joins whose earlier
    primordium is among the first ``skip`` (the irregular base, sec. 6.3).
    """
    per: dict[int, list[int]] = collections.defaultdict(list)
    diffs: collections.Counter = collections.Counter()
    for _, lo, hi in run.joins:
        if lo <= skip:
            continue
        per[lo].append(hi)
        diffs[hi - lo] += 1
    total = sum(diffs.values())
    fib = fibonacci_numbers(max(diffs, default=1))
    share = sum(v for k, v in diffs.items() if k in fib) / total if total else float("nan")
    pairs = collections.Counter(tuple(sorted(b - n for b in v))[:2] for n, v in per.items() if len(v) >= 2)
    mode = pairs.most_common(1)[0][0] if pairs else None
    return {"per": dict(per), "differences": diffs, "fibonacci_share": share, "mode": mode}


def summary_lines(run: StemRun, skip: int = 3) -> list[str]:
    c = connectivity(run, skip)
    d = ", ".join(f"{k}: {v}" for k, v in sorted(c["differences"].items()))
    mode = f"({c['mode'][0]}, {c['mode'][1]})" if c["mode"] else "none"
    missing = int((run.primordium_node < 0).sum())
    return [f"{len(run.pos)} vein nodes, {len(run.edges)} segments, {len(run.primordium_node)} primordia"
            f"{f' ({missing} not reached)' if missing else ''}, "
            f"{run.iterations} iterations{'' if run.settled else ' (stopped at max_iterations)'}",
            f"joins between primordia (after the first {skip}) by index difference: {d or 'none'}",
            f"most common connectivity {mode}; Fibonacci share {c['fibonacci_share']:.2f}"]


# ---------------------------------------------------------------------------------------------
# geometry


def _grow_heights(z: np.ndarray, top: float, growth) -> np.ndarray:
    if growth is None or top <= 0:
        return z
    h = np.clip(z / top, 0.0, None)
    inside = h <= 1.0
    g = np.empty_like(h)
    g[inside] = np.asarray(growth.evaluate(h[inside]), dtype=float)
    g[~inside] = np.asarray(growth.evaluate(np.ones(1)), dtype=float)[0] + (h[~inside] - 1.0)
    return top * g


def unrolled(run: StemRun, radius: float, heights: np.ndarray | None = None):
    """The idealized diagram's segments (eq. 6.3): ``(segments (k, 2, 2), crosses (k,) bool)``.

    A segment whose ends lie more than half a turn apart in azimuth crosses the cut at phi = 0 and is
    returned twice, continued past either side of the strip (``crosses`` True), as fig. 6.8 draws it.
    """
    z = run.pos[:, 2] if heights is None else heights
    phi = np.mod(np.arctan2(run.pos[:, 1], run.pos[:, 0]), 2 * math.pi)
    x = radius * phi
    a, b = run.edges[:, 0], run.edges[:, 1]
    xa, xb = x[a], x[b]
    width = 2 * math.pi * radius
    cross = np.abs(xa - xb) > width / 2
    seg = np.stack([np.column_stack([xa, z[a]]), np.column_stack([xb, z[b]])], axis=1)
    out = [seg[~cross]]
    flags = [np.zeros(int((~cross).sum()), bool)]
    if cross.any():
        s = seg[cross].copy()
        lo = s[:, :, 0].argmin(axis=1)
        left = s.copy()
        left[np.arange(len(s)), lo, 0] += width     # the low end continued past the right edge
        right = s.copy()
        right[np.arange(len(s)), 1 - lo, 0] -= width  # the high end continued past the left edge
        out += [left, right]
        flags += [np.ones(len(s), bool)] * 2
    return np.concatenate(out), np.concatenate(flags)


def _frusta(p0, p1, r0, r1, sides):
    """Open truncated cones along segments p0 -> p1 (k, 3), radii r0, r1: vertices, faces."""
    k = len(p0)
    if k == 0:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    axis = p1 - p0
    length = norm(axis, axis=1)
    axis = axis / np.maximum(length, 1e-300)[:, None]
    ref = np.where(np.abs(axis[:, 2:3]) < 0.9, np.array([[0.0, 0.0, 1.0]]), np.array([[1.0, 0.0, 0.0]]))
    u = np.cross(axis, ref)
    u /= norm(u, axis=1)[:, None]
    w = np.cross(axis, u)
    ang = 2 * math.pi * np.arange(sides) / sides
    ring = np.cos(ang)[None, :, None] * u[:, None, :] + np.sin(ang)[None, :, None] * w[:, None, :]
    v0 = p0[:, None, :] + r0[:, None, None] * ring
    v1 = p1[:, None, :] + r1[:, None, None] * ring
    verts = np.concatenate([v0, v1], axis=1).reshape(-1, 3)
    base = (np.arange(k) * 2 * sides)[:, None]
    i = np.arange(sides)
    j = (i + 1) % sides
    f = np.concatenate([np.stack([i, j, sides + j], 1), np.stack([i, sides + j, sides + i], 1)])
    faces = (base[:, None, :] + f[None, :, :]).reshape(-1, 3)
    return verts, faces


def _spheres(centres, radii):
    """Icospheres (42 vertices) at ``centres`` with ``radii``."""
    import trimesh
    s = trimesh.creation.icosphere(subdivisions=1, radius=1.0)
    sv, sf = np.asarray(s.vertices), np.asarray(s.faces)
    k = len(centres)
    verts = (centres[:, None, :] + radii[:, None, None] * sv[None]).reshape(-1, 3)
    faces = (np.arange(k)[:, None, None] * len(sv) + sf[None]).reshape(-1, 3)
    return verts, faces


def vein_mesh(run: StemRun, radius: float, veins, heights: np.ndarray | None = None):
    """The 3-D model (sec. 6.2.2): ``[(group, vertices, faces), ...]`` for the veins and primordia."""
    pos = run.pos.copy()
    if heights is not None:
        pos[:, 2] = heights
    prim = run.primordium_node[run.primordium_node >= 0]
    top = max(float(pos[prim, 2].max()) if len(prim) else float(pos[:, 2].max(initial=0.0)), 1e-9)
    width = veins.base_width + (veins.tip_width - veins.base_width) * np.clip(pos[:, 2] / top, 0.0, 1.0)
    a, b = run.edges[:, 0], run.edges[:, 1]
    fv, ff = _frusta(pos[a], pos[b], width[a] / 2, width[b] / 2, veins.sides)
    used = np.unique(run.edges)
    jv, jf = _spheres(pos[used], width[used] / 2)
    vv = np.concatenate([fv, jv])
    vf = np.concatenate([ff, jf + len(fv)])
    groups = [("veins", vv, vf)]
    if veins.primordium_radius > 0 and len(prim):
        p = pos[prim]
        rr = np.hypot(p[:, 0], p[:, 1])
        out = p.copy()
        scale = (radius + veins.primordium_radius) / np.maximum(rr, 1e-12)
        out[:, :2] *= scale[:, None]
        pv, pf = _spheres(out, np.full(len(out), veins.primordium_radius))
        groups.append(("primordia", pv, pf))
    return groups


# ---------------------------------------------------------------------------------------------
# writing


def _obj_groups(path, groups, header):
    lines = [f"# {h}" for h in header.splitlines()]
    off = 1
    for name, v, f in groups:
        lines.append(f"g {name}")
        lines += [f"v {x:.6g} {y:.6g} {z:.6g}" for x, y, z in v]
        lines += [f"f {a + off} {b + off} {c + off}" for a, b, c in f]
        off += len(v)
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(lines) + "\n")


def _obj_lines(path, points, segments, header):
    lines = [f"# {h}" for h in header.splitlines()]
    lines += [f"v {p[0]:.6g} {p[1]:.6g} {p[2]:.6g}" for p in points]
    lines += [f"l {a + 1} {b + 1}" for a, b in segments]
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        fh.write("\n".join(lines) + "\n")


def _diagram(path, run: StemRun, radius: float, heights, size: int, title: str):
    """The idealized diagram as a picture: veins in the unrolled strip, primordia as numbered boxes
    (fig. 6.8: solid boxes the primordia, dashed lines the segments severed by the cut)."""
    from PIL import Image, ImageDraw
    seg, cross = unrolled(run, radius, heights)
    width = 2 * math.pi * radius
    z = run.pos[:, 2] if heights is None else heights
    ztop = float(z.max()) if len(z) else 1.0
    margin = 0.08
    aspect = max(ztop, 1e-9) / width
    W, H = (size, max(64, int(size * aspect))) if aspect <= 1 else (max(64, int(size / aspect)), size)
    W, H = int(W * (1 + 2 * margin)), int(H * (1 + 2 * margin)) + 24
    img = Image.new("RGB", (W, H), (255, 255, 255))
    d = ImageDraw.Draw(img)
    x0, y0 = W * margin / (1 + 2 * margin), 24 + (H - 24) * margin / (1 + 2 * margin)
    sx = (W - 2 * x0) / width
    sy = (H - 24 - 2 * (y0 - 24)) / max(ztop, 1e-9)

    def xy(p):
        return (x0 + p[0] * sx, H - (y0 - 24) - p[1] * sy)

    (ax, ay), (bx, by) = xy((0, 0)), xy((width, ztop))
    d.rectangle([min(ax, bx), min(ay, by), max(ax, bx), max(ay, by)], outline=(200, 200, 200))
    lw = max(1, size // 600)
    for s, c in zip(seg, cross):
        a, b = xy(s[0]), xy(s[1])
        if c:
            n = max(2, int(math.hypot(b[0] - a[0], b[1] - a[1]) / 6))
            for k in range(0, n, 2):
                t0, t1 = k / n, min(1.0, (k + 1) / n)
                d.line([(a[0] + (b[0] - a[0]) * t0, a[1] + (b[1] - a[1]) * t0),
                        (a[0] + (b[0] - a[0]) * t1, a[1] + (b[1] - a[1]) * t1)], fill=(120, 120, 120), width=lw)
        else:
            d.line([a, b], fill=(20, 90, 20), width=lw)
    box = max(6, size // 90)
    phi = np.mod(np.arctan2(run.pos[:, 1], run.pos[:, 0]), 2 * math.pi)
    for k, node in enumerate(run.primordium_node, start=1):
        if node < 0:
            continue
        cx, cy = xy((radius * phi[node], z[node]))
        d.rectangle([cx - box, cy - box, cx + box, cy + box], outline=(180, 40, 40), width=lw)
        d.text((cx + box + 2, cy - box), str(k), fill=(180, 40, 40))
    d.text((6, 4), title, fill=(0, 0, 0))
    img.save(path)


def write_outputs(folder, run: StemRun, params, growth=None) -> None:
    """Write every file of the run into ``folder`` (a staging folder: the caller moves it in place)."""
    from pathlib import Path
    out = Path(folder)
    m = params.model
    head = (f"stem-veins (Runions ch. 6): R = {m.radius:g}, H = {m.step:g}, theta = {m.divergence:g} deg, "
            f"{m.count} primordia, plastochron {m.plastochron}, D = {m.D:g}")
    _obj_lines(out / "graph.obj", run.pos, run.edges, head + "\nvein nodes (v) and segments (l), stem frame, z up")
    _obj_groups(out / "veins.obj", vein_mesh(run, m.radius, params.veins), head)
    seg, _ = unrolled(run, m.radius)
    _write_unrolled(out / "unrolled.obj", seg, head)
    title = f"R/H = {m.radius / m.step:.3g}" if m.step > 0 else "H = 0"
    _diagram(out / "diagram.png", run, m.radius, None, params.diagram.size, f"unrolled stem, {title}")
    if growth is not None:
        prim = run.primordium_node[run.primordium_node >= 0]
        top = float(run.pos[prim, 2].max()) if len(prim) else float(run.pos[:, 2].max(initial=0.0))
        z = _grow_heights(run.pos[:, 2], top, growth)
        _obj_groups(out / "veins_grown.obj", vein_mesh(run, m.radius, params.veins, z), head + "\nafter the growth map")
        seg, _ = unrolled(run, m.radius, z)
        _write_unrolled(out / "unrolled_grown.obj", seg, head + "\nafter the growth map")
        _diagram(out / "diagram_grown.png", run, m.radius, z, params.diagram.size,
                 f"unrolled stem after internodal growth, {title}")
    fib = fibonacci_numbers(max(m.count, 1))
    rows = ["iteration,primordium,joins,difference,fibonacci"]
    for it, lo, hi in run.joins:
        diff = hi - lo
        rows.append(f"{it},{hi},{lo},{diff if lo > 0 else ''},{'yes' if lo > 0 and diff in fib else 'no' if lo > 0 else ''}")
    (out / "traces.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    c = connectivity(run)
    lines = summary_lines(run) + ["", "primordium: later primordia joining its trace"]
    lines += [f"{n}: {' '.join(str(x) for x in sorted(v))}" for n, v in sorted(c["per"].items())]
    (out / "connectivity.txt").write_text("\n".join(lines) + "\n", encoding="utf-8")


def _write_unrolled(path, seg, head):
    pts = np.concatenate([seg[:, 0], seg[:, 1]]) if len(seg) else np.zeros((0, 2))
    pts3 = np.column_stack([pts, np.zeros(len(pts))])
    k = len(seg)
    _obj_lines(path, pts3, np.column_stack([np.arange(k), np.arange(k) + k]),
               head + "\nunrolled (eq. 6.3): x = R phi, y = height; segments across the cut appear twice")
