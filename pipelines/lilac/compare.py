"""The lilac without and with collision handling, side by side (the `pictures` stage; thesis fig.
4.9: "intersections that occur without collision handling ... removed by displacing individual
florets and deforming their petals").

Usage: python compare.py BUILD_DIR WxH OUT.png   (BUILD_DIR = build/lilac)

Takes the last frame of ``canopy_off/`` (fccompose with ``collisions: off``: the same florets
growing through each other) and of ``canopy/`` (collisions on), picks two florets that
intersect each other without collision handling and face out of the panicle (:func:`worst_pair`),
cuts out them and their neighbours (the florets within ZOOM_RADIUS floret sizes of the pair, less
those in front of it), false-colours the two (materials 8 and 9 of colors.toml) and renders both
cut-outs with canopy-render looking down the pair's mean axis at 45 degrees from the side. Under each:
its count of intersecting triangle pairs (the exact static test of inflo.tools.collide; touching
counts) in the whole canopy and between the two florets. The renders and their layout follow
pipelines/dahlia/compare.py (fig. 9.1).
"""
from __future__ import annotations

import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from inflo.formats.obj import ObjMesh, list_obj_sequence, read_obj, write_obj
from inflo.formats.scn import read_scn
from inflo.tools.canopy_render.output import write_png
from inflo.tools.collide import intersecting_pairs

HERE = Path(__file__).resolve().parent
#: neighbours of the highlighted pair: florets within this many floret sizes of its midpoint
ZOOM_RADIUS = 1.3
#: the camera: along the pair's mean axis tilted this much (tan) to the side of the line between
#: them, so their lobes' crossing shows in profile
SIDE = 1.0
#: the false colours (colors.toml)
MARK = ("mtl8", "mtl9")


def floret_of_face(mesh) -> np.ndarray:
    """(m,) placement index of each face (-1 outside a floret_<k> group)."""
    ids = np.array([int(g.split("_")[1]) if g.startswith("floret_") else -1 for g in mesh.groups])
    return ids[mesh.face_group]


def worst_pair(mesh, pos, up) -> tuple:
    """Two florets that intersect each other without collision handling and can be seen: of the
    pairs with at least a fifth of the largest count of triangle pairs between them, the one whose
    florets face most directly out of the panicle (the smaller of their ``up`` . outward, outward
    the horizontal direction from the main axis to their midpoint, tilted 30 degrees up), times
    its count. ``pos``, ``up``: the placements'. Returns (the pair or None, all pairs' count)."""
    pairs = np.asarray(intersecting_pairs(mesh.vertices, mesh.faces, tri_part=mesh.face_group)).reshape(-1, 2)
    of = floret_of_face(mesh)
    a, b = of[pairs[:, 0]], of[pairs[:, 1]]
    keep = a != b
    if not keep.any():
        return None, len(pairs)
    key = np.sort(np.stack([a[keep], b[keep]], axis=1), axis=1)
    uniq, count = np.unique(key, axis=0, return_counts=True)
    good = count >= 0.2 * count.max()
    uniq, count = uniq[good], count[good]
    mid = 0.5 * (pos[uniq[:, 0]] + pos[uniq[:, 1]])
    out = mid * np.array([1.0, 0.0, 1.0])
    out = out / np.maximum(np.linalg.norm(out, axis=1), 1e-12)[:, None] + np.array([0.0, math.tan(math.radians(30)), 0.0])
    out /= np.linalg.norm(out, axis=1)[:, None]
    u = up / np.linalg.norm(up, axis=1)[:, None]
    facing = np.minimum(np.einsum("ij,ij->i", u[uniq[:, 0]], out), np.einsum("ij,ij->i", u[uniq[:, 1]], out))
    best = uniq[np.argmax(count * np.clip(facing, 0.0, None) + 1e-9 * count)]
    return tuple(int(x) for x in best), len(pairs)


def cut_out(mesh, keep: set, mark: tuple) -> ObjMesh:
    """The faces of the florets in ``keep``; the two of ``mark`` get the materials MARK."""
    of = floret_of_face(mesh)
    faces = np.nonzero(np.isin(of, sorted(keep)))[0]
    mats = list(mesh.materials) + [m for m in MARK if m not in mesh.materials]
    fm = mesh.face_material[faces].copy()
    for k, name in zip(mark, MARK):
        fm[of[faces] == k] = mats.index(name)
    used = np.unique(mesh.faces[faces])
    remap = np.full(len(mesh.vertices), -1, np.int64)
    remap[used] = np.arange(len(used))
    return ObjMesh(vertices=mesh.vertices[used], faces=remap[mesh.faces[faces]], materials=mats, face_material=fm)


def pair_count(mesh, mark: tuple) -> int:
    sub = cut_out(mesh, set(mark), mark)
    return len(intersecting_pairs(sub.vertices, sub.faces, tri_part=sub.face_group))


def main(build: Path, size: str, out: Path) -> int:
    w, h = (int(v) for v in size.split("x"))
    render = Path(sys.executable).parent / "canopy-render"
    scene = read_scn(build / "thyrse" / "scene.scn")
    off = read_obj(list_obj_sequence(build / "canopy_off")[-1])
    on = read_obj(list_obj_sequence(build / "canopy")[-1])
    arr = scene.arrays()
    pos, up = arr["pos"], arr["up"]
    mark, _ = worst_pair(off, pos, up)
    if mark is None:
        mark = (0, 1)
    mid = 0.5 * (pos[mark[0]] + pos[mark[1]])
    size_ = float(scene.placements[mark[0]].scale[0])
    # the camera looks down the pair's mean axis, from the side (SIDE); the neighbours within
    # ZOOM_RADIUS floret sizes, less those in front of the pair (between it and the camera)
    axis = up[mark[0]] / np.linalg.norm(up[mark[0]]) + up[mark[1]] / np.linalg.norm(up[mark[1]])
    axis /= np.linalg.norm(axis)
    side = np.cross(axis, pos[mark[1]] - pos[mark[0]])
    side = side / np.linalg.norm(side) if np.linalg.norm(side) > 1e-12 else np.zeros(3)
    if side @ mid < 0:  # from outside the panicle
        side = -side
    view = axis + SIDE * side
    view /= np.linalg.norm(view)
    near = np.linalg.norm(pos - mid, axis=1) < ZOOM_RADIUS * size_
    front = (pos - mid) @ view > 0.3 * size_
    keep = set(np.nonzero(near & ~front)[0].tolist()) | set(mark)
    azimuth = math.degrees(math.atan2(view[0], view[2]))
    elevation = math.degrees(math.asin(max(-1.0, min(1.0, view[1]))))
    panels = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, mesh, title in (("off", off, "collisions off"), ("on", on, "collisions on")):
            n = len(intersecting_pairs(mesh.vertices, mesh.faces, tri_part=mesh.face_group))
            obj = Path(tmp) / f"{name}.obj"
            write_obj(obj, cut_out(mesh, keep, mark))
            png = Path(tmp) / f"{name}.png"
            subprocess.run([str(render), "-q", "--background", "0.20,0.26,0.18", "--colors", str(HERE / "colors.toml"),
                            str(obj), "--azimuth", f"{azimuth:.1f}", "--elevation", f"{elevation:.1f}", "--size", f"{w // 2}x{h}",
                            "-o", str(png)], check=True)
            panels.append((Image.open(png).convert("RGB"),
                           f"{title}: {n} intersecting triangle pairs\n({pair_count(mesh, mark)} between the two "
                           "coloured florets)"))
    sheet = Image.new("RGB", (w, h + 56), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    font = ImageFont.load_default(size=16)
    for i, (img, caption) in enumerate(panels):
        sheet.paste(img, (i * (w // 2), 0))
        draw.multiline_text((i * (w // 2) + 10, h + 8), caption, fill=(0, 0, 0), font=font)
    write_png(out, np.asarray(sheet))
    print(f"{out}: florets {mark[0]} and {mark[1]}; " + "; ".join(c.replace("\n", " ") for _, c in panels))
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 4:
        print(__doc__.strip().splitlines()[3], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1]), sys.argv[2], Path(sys.argv[3])))
