"""What ``venation`` writes (formats/venation.md): the venation graph as OBJ polylines with a width
per node, the blade as a textured triangle mesh, the veins drawn by width into a PNG texture over
the blade, and frames of the pattern forming.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from inflo.formats.atomic import atomic_write, frame_name, remove_stale_frames
from inflo.formats.obj import FLOAT_FMT, ObjMesh, write_obj

from .blade import triangulate_blade
from .graph import polylines

__all__ = ["TextureStyle", "render_texture", "write_graph", "write_widths", "write_blade_mesh", "write_margin",
           "format_widths", "texture_box", "WIDTH_FMT", "format_events", "write_events", "EVENTS_HEADER"]

WIDTH_FMT = "%.8f"


@dataclass(frozen=True)
class TextureStyle:
    """How the texture is drawn: ``size`` pixels along the longer side of the blade's box, colours
    as (r, g, b) in 0..255, ``width_scale`` times the vein widths, ``supersample`` x supersampling
    (anti-aliasing), ``background`` None for transparent outside the blade."""

    size: int = 1024
    blade_color: tuple = (92, 140, 58)
    vein_color: tuple = (222, 232, 170)
    background: tuple | None = None
    width_scale: float = 1.0
    min_width_px: float = 0.75
    supersample: int = 3
    show_sources: bool = False
    source_color: tuple = (200, 40, 40)


def texture_box(margin) -> tuple[np.ndarray, np.ndarray]:
    """The box the texture covers (and the uv map spans): the margin's bounding box."""
    m = np.asarray(margin, dtype=np.float64)
    lo, hi = m.min(0), m.max(0)
    ext = np.maximum(hi - lo, 1e-12)
    return lo, lo + ext


def render_texture(node_pos, node_parent, widths, extra_edges, margin, style: TextureStyle = TextureStyle(), *,
                   box=None, sources=None):
    """The veins drawn by width over the blade: a PIL RGBA image covering ``box`` (default
    :func:`texture_box` of ``margin``), x to the right, y up; transparent outside the blade unless
    ``style.background``. Thin veins are drawn first, so the main veins run on top."""
    from PIL import Image, ImageDraw

    lo, hi = texture_box(margin) if box is None else (np.asarray(box[0], float), np.asarray(box[1], float))
    ext = hi - lo
    ppu = style.size / float(max(ext))
    w_px = max(1, int(round(ext[0] * ppu)))
    h_px = max(1, int(round(ext[1] * ppu)))
    ss = max(1, int(style.supersample))
    W, H = w_px * ss, h_px * ss
    k = ppu * ss

    def px(p):
        p = np.asarray(p, dtype=np.float64).reshape(-1, 2)
        return np.column_stack([(p[:, 0] - lo[0]) * k, (hi[1] - p[:, 1]) * k])

    blade_mask = Image.new("L", (W, H), 0)
    ImageDraw.Draw(blade_mask).polygon([tuple(q) for q in px(margin).tolist()], fill=255)
    vein_mask = Image.new("L", (W, H), 0)
    draw = ImageDraw.Draw(vein_mask)
    pos = px(node_pos)
    parent = np.asarray(node_parent, dtype=np.int64)
    wid = np.asarray(widths, dtype=np.float64) * style.width_scale * k
    wid = np.maximum(wid, style.min_width_px * ss)
    edges = [(v, int(parent[v]), wid[v]) for v in np.flatnonzero(parent >= 0)]
    for a, b in np.asarray(extra_edges, dtype=np.int64).reshape(-1, 2):
        edges.append((int(a), int(b), min(wid[a], wid[b])))
    edges.sort(key=lambda e: e[2])
    for a, b, w in edges:
        pa, pb = tuple(pos[a]), tuple(pos[b])
        draw.line([pa, pb], fill=255, width=max(1, int(round(w))))
        r = 0.5 * w
        if r >= 1.0:  # round joints
            for q in (pa, pb):
                draw.ellipse([q[0] - r, q[1] - r, q[0] + r, q[1] + r], fill=255)
    if ss > 1:
        blade_mask = blade_mask.resize((w_px, h_px), Image.Resampling.BOX)
        vein_mask = vein_mask.resize((w_px, h_px), Image.Resampling.BOX)
    bm = np.asarray(blade_mask, dtype=np.float64) / 255.0
    vm = np.asarray(vein_mask, dtype=np.float64) / 255.0
    blade_rgb = np.asarray(style.blade_color, dtype=np.float64)
    vein_rgb = np.asarray(style.vein_color, dtype=np.float64)
    rgb = blade_rgb * (1.0 - vm[..., None]) + vein_rgb * vm[..., None]
    if style.background is None:
        alpha = bm
    else:
        bg = np.asarray(style.background, dtype=np.float64)
        rgb = bg * (1.0 - bm[..., None]) + rgb * bm[..., None]
        alpha = np.ones_like(bm)
    img = np.dstack([rgb, alpha * 255.0])
    out = Image.fromarray(np.clip(np.rint(img), 0, 255).astype(np.uint8), "RGBA")
    if style.show_sources and sources is not None and len(sources):
        d = ImageDraw.Draw(out)
        r = max(1.5, 0.004 * style.size)
        sp = np.column_stack([(np.asarray(sources)[:, 0] - lo[0]) * ppu, (hi[1] - np.asarray(sources)[:, 1]) * ppu])
        for x, y in sp.tolist():
            d.ellipse([x - r, y - r, x + r, y + r], fill=tuple(style.source_color) + (255,))
    return out


def save_png(img, path) -> None:
    """Write a PIL image as PNG atomically."""
    with atomic_write(path, "wb") as fh:
        img.save(fh, format="PNG", optimize=False)


def format_widths(widths, header: str = "") -> str:
    lines = [f"# {h}\n" for h in header.splitlines() if h]
    lines.append("# one width per 'v' line of the venation OBJ, in order (blade units)\n")
    fmt = WIDTH_FMT + "\n"
    lines.extend(fmt % w for w in np.asarray(widths, dtype=np.float64).tolist())
    return "".join(lines)


def write_widths(path, widths, header: str = "") -> None:
    with atomic_write(path) as fh:
        fh.write(format_widths(widths, header))


EVENTS_HEADER = "iteration,event,index,x,y,measure,order,midvein"


def format_events(events) -> str:
    """``events.csv``: one row per developmental event (iteration, event, index, x, y, measure and,
    for a loop, its order and whether it runs along the midvein), in the order they happened; an
    unknown measure, order or flag is empty."""
    lines = [EVENTS_HEADER + "\n"]
    for e in events:
        it, name, index, x, y, m = e[:6]
        order = "" if len(e) < 7 or e[6] is None else str(int(e[6]))
        mid = "" if len(e) < 8 or e[7] is None else str(int(e[7]))
        ms = "" if m is None or not np.isfinite(m) else "%.8f" % m
        lines.append(f"{int(it)},{name},{int(index)},{x:.8f},{y:.8f},{ms},{order},{mid}\n")
    return "".join(lines)


def write_events(path, events) -> None:
    with atomic_write(path) as fh:
        fh.write(format_events(events))


def write_graph(path, node_pos, node_parent, extra_edges, header: str = "") -> None:
    """The venation graph as OBJ: one ``v x y 0`` per node (in node order), one ``l`` polyline per
    chain of the growth forest (from its basal end), then one ``l a b`` per anastomosis."""
    pos = np.asarray(node_pos, dtype=np.float64).reshape(-1, 2)
    mesh = ObjMesh(vertices=np.column_stack([pos, np.zeros(len(pos))]), lines=polylines(node_parent, extra_edges))
    write_obj(path, mesh, header=header or None)


def write_margin(path, margin, header: str = "") -> None:
    """The margin as a closed ``l`` polyline (first vertex repeated at the end)."""
    m = np.asarray(margin, dtype=np.float64).reshape(-1, 2)
    line = np.concatenate([np.arange(len(m)), [0]])
    write_obj(path, ObjMesh(vertices=np.column_stack([m, np.zeros(len(m))]), lines=[line]), header=header or None)


def write_blade_mesh(path, margin, *, texture_name: str | None = "texture.png", header: str = "",
                     box=None, spacing: float | None = None) -> tuple[int, int]:
    """The blade as a triangle mesh in the z = 0 plane with uv = position in the texture's box,
    normals +z, and (``texture_name``) a ``.mtl`` beside it that maps the texture. Returns
    (vertices, triangles)."""
    path = Path(path)
    verts, faces = triangulate_blade(margin, spacing)
    lo, hi = texture_box(margin) if box is None else box
    uv = (verts - lo) / (hi - lo)
    parts = [f"# {h}\n" for h in header.splitlines() if h]
    if texture_name:
        parts.append(f"mtllib {path.stem}.mtl\n")
    row = f"v {FLOAT_FMT} {FLOAT_FMT} {FLOAT_FMT}\n"
    parts.append("".join(row % (x, y, 0.0) for x, y in verts.tolist()))
    parts.append("".join(f"vt {FLOAT_FMT} {FLOAT_FMT}\n" % (u, v) for u, v in uv.tolist()))
    parts.append("vn 0 0 1\n" * len(verts))
    if texture_name:
        parts.append("usemtl blade\n")
    parts.append("".join("f %d/%d/%d %d/%d/%d %d/%d/%d\n" % (a, a, a, b, b, b, c, c, c)
                         for a, b, c in (faces.astype(np.int64) + 1).tolist()))
    with atomic_write(path) as fh:
        fh.write("".join(parts))
    if texture_name:
        with atomic_write(path.with_suffix(".mtl")) as fh:
            fh.write("# the blade with its vein texture (venation)\nnewmtl blade\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\n"
                     f"map_Kd {texture_name}\nmap_d {texture_name}\n")
    return len(verts), len(faces)


def stale_frames(folder, keep) -> None:
    """Remove frames of an earlier run that this run did not write."""
    folder = Path(folder)
    if not folder.is_dir():
        return
    for prefix, suffix in (("veins_", ".obj"), ("veins_", ".widths"), ("blade_", ".obj"), ("texture_", ".png")):
        remove_stale_frames(folder, [frame_name(i, prefix=prefix, suffix=suffix) for i in keep], suffix, prefix=prefix)
