"""The yarrow's stem leaves (thesis fig. 9.9: the corymb on a leafy stem; issue 43).

Usage: python stem_leaves.py LEAF_DIR BRANCHES_DIR FRAMES COUNT LENGTH OUT_DIR

LEAF_DIR is a ``venation`` run of ``pipelines/examples/venation/yarrow.toml`` (the pinnately
dissected yarrow leaf, Runions ch. 4: ``blade.obj``, its outline triangulated, with ``vt``
coordinates into ``texture.png``, the blade with its open venation). BRANCHES_DIR is branch-gen's
output (``skeleton.obj``, ``skeleton.radii``, ``frames/branches_NNNN.obj``): the main stem is the
chain of the skeleton that starts at the base (its lowest node) and ends at the first branch point.

COUNT leaves stand alternately (a divergence of 137.5 degrees, the yarrow's spiral phyllotaxis) along
the main stem, evenly from 0.15 to 0.75 of its length; sessile, each leaf's base on the stem's
surface (the stem's largest radius + a small gap), its rachis leaving the stem at 50 degrees above
the horizontal and arching out to 10 degrees at its tip (a ruled surface: the blade's width stays
horizontal, so the flat blade stays flat and free of itself). Lengths fall upward from LENGTH to
0.6 LENGTH (the stem leaves of *A. millefolium* get smaller toward the corymb).

On the canopy's clock: a leaf appears in the first frame whose branch mesh reaches its place on the
stem (the branches grow from the heads down, branch-gen) and from which, growing, it crosses no
branch of any later frame (a path that passes its place early may graft elsewhere later), at 0.4
of its length, and grows to its full length over GROW frames.

Writes ``OUT_DIR/frame_NNNN.obj`` (FRAMES files, one group ``leaf_K`` per leaf, the same vertices,
``vt`` and triangles in every frame; before a leaf appears its faces are left out and its vertices
rest at its base), ``OUT_DIR/leaves.mtl`` (material ``mtl9``, the vein texture as ``map_Kd``/``map_d``)
and ``OUT_DIR/texture.png`` (copied). Pure numpy, no randomness.
"""
from __future__ import annotations

import math
import shutil
import sys
from pathlib import Path

import numpy as np

from inflo.formats.atomic import write_text_atomic
from inflo.formats.obj import read_obj, written_vertices

# imported here, before the branch frames are read, so that they are read by the OBJ reader's
# numba kernels (formats/obj.py: without numba loaded, frames under 16 MB are read in Python)
from inflo.tools.collide import intersecting_pairs_between

#: the leaves' material (colors.toml 9; the texture in leaves.mtl)
MATERIAL = 9
GROW = 8
DIVERGENCE = math.radians(137.5)
ELEV_BASE, ELEV_TIP = math.radians(50.0), math.radians(10.0)
GAP = 0.03


def read_blade(path: Path):
    """The blade's vertices (n, 2: x across, y along the rachis from its base), vt rows (m, 2),
    and faces (k, 3, 2: vertex and vt indices, 0-based)."""
    v, vt, f = [], [], []
    for line in path.read_text().splitlines():
        t = line.split()
        if not t:
            continue
        if t[0] == "v":
            v.append((float(t[1]), float(t[2])))
        elif t[0] == "vt":
            vt.append((float(t[1]), float(t[2])))
        elif t[0] == "f":
            if len(t) != 4:
                raise SystemExit(f"{path}: expected triangles, found a face of {len(t) - 1} vertices")
            f.append([(int(c.split("/")[0]) - 1, int(c.split("/")[1]) - 1) for c in t[1:]])
    return np.array(v, float), np.array(vt, float), np.array(f, np.int64)


def main_stem(branches: Path) -> tuple[np.ndarray, float]:
    """The main stem's polyline (from the base up to the first branch point) and the largest
    radius along it."""
    verts, chains = [], []
    for line in (branches / "skeleton.obj").read_text().splitlines():
        t = line.split()
        if t and t[0] == "v":
            verts.append([float(x) for x in t[1:4]])
        elif t and t[0] == "l":
            chains.append([int(x) - 1 for x in t[1:]])
    verts = np.array(verts)
    radii = np.array(_radii(branches / "skeleton.radii"))
    base = int(np.argmin(verts[:, 1]))
    stem = [c for c in chains if c[0] == base]
    if not stem:
        raise SystemExit(f"{branches}/skeleton.obj: expected a chain from the base node, found none")
    c = max(stem, key=len)
    return verts[c], float(radii[c].max())


def _radii(path: Path) -> list:
    out = []
    for line in path.read_text().splitlines():
        s = line.strip()
        if s and not s.startswith("#"):
            out.append(float(s.split()[0]))
    return out


def point_at(poly: np.ndarray, t: float) -> np.ndarray:
    """The point at arc-length fraction t of the polyline."""
    seg = np.sqrt(((poly[1:] - poly[:-1]) ** 2).sum(axis=1))
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    s = t * cum[-1]
    i = min(int(np.searchsorted(cum, s, side="right")) - 1, len(seg) - 1)
    u = (s - cum[i]) / seg[i] if seg[i] > 0 else 0.0
    return poly[i] + u * (poly[i + 1] - poly[i])


def place(blade: np.ndarray, base: np.ndarray, azimuth: float, length: float) -> np.ndarray:
    """The blade (x across, y along its rachis, 0 .. its length) placed: its base at ``base``, its
    rachis an arc in the vertical plane of ``azimuth`` from ELEV_BASE to ELEV_TIP, its width
    horizontal (thesis fig. 9.9's stem leaves, ascending then spreading)."""
    y0, y1 = blade[:, 1].min(), blade[:, 1].max()
    s = np.clip((blade[:, 1] - min(y0, 0.0)) / (y1 - min(y0, 0.0)), 0.0, 1.0)  # 0 base .. 1 tip
    k = length / (y1 - min(y0, 0.0))
    radial = np.array([math.cos(azimuth), 0.0, math.sin(azimuth)])
    side = np.array([-math.sin(azimuth), 0.0, math.cos(azimuth)])
    # the arc: elevation e(s) falls linearly; position = integral of (cos e, sin e) ds
    n = 256
    ss = np.linspace(0.0, 1.0, n + 1)
    e = ELEV_BASE + (ELEV_TIP - ELEV_BASE) * ss
    dh = np.concatenate([[0.0], np.cumsum(0.5 * (np.cos(e[1:]) + np.cos(e[:-1])) / n)])
    dv = np.concatenate([[0.0], np.cumsum(0.5 * (np.sin(e[1:]) + np.sin(e[:-1])) / n)])
    h = np.interp(s, ss, dh) * length
    v = np.interp(s, ss, dv) * length
    return base[None] + h[:, None] * radial[None] + v[:, None] * np.array([0.0, 1.0, 0.0])[None] \
        + (blade[:, 0] * k)[:, None] * side[None]


def appear_frames(branches: Path, frames: int, points: np.ndarray, reach: float) -> list:
    """Per leaf, the first canopy frame whose branch mesh has a vertex within ``reach`` of the
    leaf's point on the stem (the stem has grown down past it)."""
    out = [frames] * len(points)
    for k in range(frames):
        p = branches / "frames" / f"branches_{k:04d}.obj"
        if not p.exists():
            continue
        m = read_obj(p)
        if len(m.faces) == 0:
            continue
        q = m.vertices
        for i, c in enumerate(points):
            if out[i] == frames and (((q - c[None]) ** 2).sum(axis=1) <= reach * reach).any():
                out[i] = k
    return out


def leaf_at(blade, base, azimuth, length, age):
    """The leaf's vertices at ``age`` frames after it appeared (at 0.4 of its length, full after GROW)."""
    g = min(0.4 + 0.6 * age / GROW, 1.0)
    return place(blade, base, azimuth, length * g)


def free_from(branches: Path, frames: int, first: int, blade, faces, base, azimuth, length) -> int:
    """The first frame, not before ``first``, from which the leaf (growing from then on) crosses
    no triangle of the frame's branch mesh in any later frame: the branches grow down and graft
    (branch-gen), so a path that passes the leaf's place early may leave it later."""
    tri = faces[:, :, 0]
    meshes = {}
    k = first
    while k < frames:
        ok = True
        for j in range(k, frames):
            if j not in meshes:
                meshes[j] = read_obj(branches / "frames" / f"branches_{j:04d}.obj")
            m = meshes[j]
            if len(m.faces) == 0:
                continue
            v = leaf_at(blade, base, azimuth, length, j - k)
            if len(intersecting_pairs_between(v, tri, m.vertices, m.faces)):
                k, ok = j + 1, False
                break
        if ok:
            return k
    return frames


def main(argv: list) -> int:
    if len(argv) != 6:
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        return 2
    leaf_dir, branches, frames, count, length, out = (Path(argv[0]), Path(argv[1]), int(argv[2]),
                                                      int(argv[3]), float(argv[4]), Path(argv[5]))
    blade, vt, faces = read_blade(leaf_dir / "blade.obj")
    stem, rmax = main_stem(branches)
    # the stem's axis at x = z = 0 (the base under the pattern's centre): leaves at fractions of its length
    ts = np.linspace(0.15, 0.75, count) if count > 1 else np.array([0.4])
    bases, centres, lengths, azim = [], [], [], []
    for i, t in enumerate(ts):
        c = point_at(stem, float(t))
        a = i * DIVERGENCE
        bases.append(c + (rmax + GAP) * np.array([math.cos(a), 0.0, math.sin(a)]))
        centres.append(c)
        lengths.append(length * (1.0 - 0.4 * i / max(count - 1, 1)))
        azim.append(a)
    reach = appear_frames(branches, frames, np.array(centres), 2.0 * rmax + 0.05)
    first = [free_from(branches, frames, reach[i], blade, faces, bases[i], azim[i], lengths[i])
             for i in range(count)]
    out.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(leaf_dir / "texture.png", out / "texture.png")
    write_text_atomic(out / "leaves.mtl", f"# the yarrow stem leaf with its vein texture (venation)\n"
                      f"newmtl mtl{MATERIAL}\nKa 1 1 1\nKd 0.38 0.53 0.29\nKs 0 0 0\n"
                      f"map_Kd texture.png\nmap_d texture.png\n")
    nv, nt = len(blade), len(vt)
    vt_text = "".join(f"vt {u:.6f} {w:.6f}\n" for u, w in vt)
    leaf_faces = []  # a leaf's face lines are the same in every frame it is in
    for i in range(count):
        fv = faces[:, :, 0] + 1 + i * nv
        ft = faces[:, :, 1] + 1 + i * nt
        leaf_faces.append("".join([f"g leaf_{i}\nusemtl mtl{MATERIAL}\n"]
                                  + [f"f {a}/{ta} {b}/{tb} {c}/{tc}\n"
                                     for (a, b, c), (ta, tb, tc) in zip(fv.tolist(), ft.tolist())]))
    for k in range(frames):
        parts = [f"# yarrow stem leaves, canopy frame {k} (stem_leaves.py)\nmtllib leaves.mtl\n"]
        faces_txt = []
        for i in range(count):
            age = k - first[i]
            if age >= 0:
                p = leaf_at(blade, bases[i], azim[i], lengths[i], age)
            else:
                p = np.repeat(bases[i][None], nv, axis=0)
            parts.append(written_vertices(p, "%.6f")[1])  # "v x y z" lines, as "%.6f" writes them
            parts.append(vt_text)
            if age >= 0:
                faces_txt.append(leaf_faces[i])
        write_text_atomic(out / f"frame_{k:04d}.obj", "".join(parts + faces_txt))
    print(f"stem_leaves.py: {count} leaves on the main stem ({len(stem)} nodes, radius up to {rmax:.3f}), "
          f"lengths {lengths[0]:.2f}-{lengths[-1]:.2f}, reached at frames {reach}, appearing at frames {first}; "
          f"{frames} frames -> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
