"""Paint an Asiatic lily's tepal markings as vertex colours (the `painted` stage of the Makefile).

Usage: python paint_tepals.py BUILD_DIR   (BUILD_DIR = build/lily)

Reads the smoothed frames ``smooth/N.obj`` and the unsmoothed canopy frames they came from
(``keyframes/N.obj``, polygonize's vertex order: every tepal a grid of rows from the claw to the
tip, columns from edge to edge), and writes ``painted/N.obj``: the smoothed frame with a colour per
vertex (``v x y z r g b``, which canopy-render draws in place of the material colours):

- the ground colour: orange, a little lighter and yellower toward the claw (sepals slightly deeper
  than petals, as ``colors.toml``'s materials 3 and 4);
- the nectary furrow: a green-yellow groove along the midrib over the lower third of every tepal,
  narrowing toward its end;
- the spots: small dark maroon dots scattered over the lower half of the tepal's middle, densest
  toward the claw and absent from the margins and the tip (the spotted throat of Asiatic lilies).

Every vertex of the smoothed frame takes the tepal coordinates (u across from -1 to 1 at the
edges, v along from 0 at the claw to 1 at the tip) of the nearest canopy vertices of the same
whorl (sepals: material 3, petals: 4), inverse-distance weighted over three. Spots are laid out in
tepal coordinates with a fixed seed, so they ride on the tepal as it opens.

A tepal is one sheet, so a vertex colour shows on both faces; real spots are on the inner
(adaxial) face only. The markings therefore fade in with the opening -- absent while the outer
face is all that shows (frame 1), full from frame 40 on (the midrib reflexed, the inner face
turned to view) -- a rendering compromise; the meshes themselves are not changed.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from inflo.formats.obj import read_obj, write_obj

# polygonize's vertex order: sepals (3 copies of 19 rows x 17), then petals (3 copies of 20 x 19)
WHORLS = {"mtl3": (0, 19, 17), "mtl4": (3 * 19 * 17, 20, 19)}
GROUND = {"mtl3": ((0.93, 0.42, 0.10), (0.98, 0.62, 0.16)),   # (tip, claw) colours
          "mtl4": ((0.98, 0.52, 0.14), (1.00, 0.68, 0.20))}
FURROW = np.array([0.58, 0.66, 0.22])
SPOT = np.array([0.30, 0.05, 0.04])
N_SPOTS = 26
SEED = 7
FULL_FRAME = 40  # markings at full strength from this frame on (1-based), absent at frame 1


def tepal_coords(canopy, material):
    """(n, 3) positions and (n, 3) [copy, u, v] of one whorl's canopy vertices."""
    off, rows, per_row = WHORLS[material]
    n = rows * per_row
    pts = canopy.vertices[off:off + 3 * n]
    k = np.arange(3 * n)
    copy, rest = k // n, k % n
    row, col = rest // per_row, rest % per_row
    half = (per_row - 1) / 2.0
    return pts, np.stack([copy, (col - half) / half, row / (rows - 1)], axis=1).astype(float)


def spots(rng):
    """(N_SPOTS, 3) spots in tepal coordinates: u, v and radius (in units of the half-width)."""
    v = 0.12 + 0.38 * rng.random(N_SPOTS) ** 1.4       # denser toward the claw, none past v = 0.5
    u = (rng.random(N_SPOTS) * 2.0 - 1.0) * (0.15 + 0.5 * (1.0 - v))  # central band, widening down
    u = np.where(np.abs(u) < 0.12, np.sign(u + 1e-9) * 0.12, u)       # off the furrow
    r = 0.08 + 0.05 * rng.random(N_SPOTS)
    return np.stack([u, v, r], axis=1)


def paint(smooth, canopy, strength):
    """(n, 3) vertex colours of the smoothed frame."""
    colors = np.zeros((len(smooth.vertices), 3))
    vmat = np.full(len(smooth.vertices), -1)
    for f, m in zip(smooth.faces, smooth.face_material):
        vmat[f] = m
    rng = np.random.default_rng(SEED)
    layout = {c: spots(rng) for c in range(6)}  # each of the six tepals its own spots
    for mi, name in enumerate(smooth.materials):
        if name not in WHORLS:
            continue
        sel = np.flatnonzero(vmat == mi)
        pts, coords = tepal_coords(canopy, name)
        dist, idx = cKDTree(pts).query(smooth.vertices[sel], k=3)
        w = 1.0 / np.maximum(dist, 1e-9)
        w /= w.sum(axis=1, keepdims=True)
        copy = coords[idx[:, 0], 0].astype(int)
        u = (coords[idx, 1] * w).sum(axis=1)
        v = (coords[idx, 2] * w).sum(axis=1)
        tip, claw = (np.array(c) for c in GROUND[name])
        t = np.clip(v / 0.6, 0.0, 1.0)[:, None]
        col = claw * (1.0 - t) + tip * t
        # nectary furrow: a groove along the midrib, |u| under 0.16 narrowing to 0 at v = 0.35
        fw = 0.16 * np.clip(1.0 - v / 0.35, 0.0, 1.0)
        fur = np.clip(1.0 - np.abs(u) / np.maximum(fw, 1e-9), 0.0, 1.0) * (fw > 0)
        a = (strength * np.clip(fur * 1.6, 0.0, 1.0))[:, None]
        col = col * (1.0 - a) + FURROW * a
        # spots: soft-edged dots (u is in half-widths, v in lengths: a tepal is about 5 half-
        # widths long, so v distances are scaled by 5 to keep the dots round)
        whorl_copy = copy + (3 if name == "mtl4" else 0)
        s = np.zeros(len(sel))
        for c in range(6):
            on = whorl_copy == c
            if not on.any():
                continue
            for su, sv, sr in layout[c]:
                d = np.hypot(u[on] - su, (v[on] - sv) * 5.0) / sr
                s[on] = np.maximum(s[on], np.clip(1.6 - d, 0.0, 1.0))
        a = (strength * s)[:, None]
        colors[sel] = col * (1.0 - a) + SPOT * a
    return np.clip(colors, 0.0, 1.0)


def main(build: Path) -> int:
    out = build / "painted"
    out.mkdir(parents=True, exist_ok=True)
    for path in sorted((build / "smooth").glob("*.obj"), key=lambda p: int(p.stem)):
        n = int(path.stem)
        strength = float(np.clip((n - 1) / (FULL_FRAME - 1), 0.0, 1.0))
        smooth = read_obj(path)
        canopy = read_obj(build / "keyframes" / path.name)
        smooth.vertex_colors = paint(smooth, canopy, strength)
        write_obj(out / path.name, smooth)
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1])))
