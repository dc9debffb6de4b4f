"""Write the Eustoma column and calyx (column_*.floret): receptacle, five sepals, a pistil with a
two-lobed stigma and five stamens, the same for the three cultivars (their petals alone differ,
by growth maps).

Usage: python make_column.py [OUT_DIR]   (default: this folder; the files are committed inputs)

Eustoma grandiflorum: a calyx of five narrow, keeled, lanceolate sepals, free almost to the base,
erect against the corolla tube; five stamens alternating with the corolla lobes, filaments on the
tube, oblong yellow anthers; a long style with a two-lobed, flattened stigma (Ijiri et al. 2008,
sec. 6.2 and fig. 14 model only the corolla). Closed tubes (a ring of 9 control columns, degree 1
across, cubic along), as the lily's column (pipelines/lily/make_keys.py).

The petals grow by petal-grow and are not known here: the sepals stay outside them by following
an envelope of the three cultivars' corollas, measured once on the draft build (`ENVELOPE`: the
largest distance from the axis of any petal point at heights 0-10, per key frame, each the
largest over the frames from the previous key pose to the next one, so that the linear blend
between two poses stays outside every frame between them), plus a margin. check_eustoma.py tests
every keyframe of every cultivar, petals against the column, by the exact test.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from inflo.tools.common import linalg as la

OUT = Path(__file__).resolve().parent
RING = np.linspace(0.0, 2.0 * math.pi, 9)

# heights (flower units, the bud is 40.8 tall; the petals' base lies at y = 0, r = 1.6-2.7)
ENV_Y = np.array([0.0, 1.0, 2.0, 4.0, 6.0, 8.0, 10.0])
# key frames (0-based, of 100) and the corolla envelope there: max distance from the axis of the
# three cultivars' petals at ENV_Y, the max over the frames between the neighbouring key frames
KEY_FRAMES = [0, 20, 40, 60, 80, 99]
ENVELOPE = {
    0: [3.7, 4.7, 5.9, 7.5, 9.0, 9.9, 11.1],
    20: [3.7, 5.0, 6.4, 8.5, 10.6, 12.0, 14.2],
    40: [3.7, 5.7, 7.4, 9.4, 11.9, 14.1, 15.9],
    60: [4.3, 6.0, 7.8, 9.9, 12.2, 14.6, 16.8],
    80: [5.9, 8.5, 9.6, 12.8, 16.9, 20.3, 24.2],
    99: [5.9, 8.5, 9.6, 12.8, 16.9, 20.3, 24.2],
}
MARGIN = 1.2  # sepal axis outside the envelope by this much (its half-thickness is 0.15)
SEPAL_HALF_WIDTH = [0.5, 0.8, 0.9, 0.9, 0.85, 0.7, 0.45, 0.2]


def ring_tube(centres, a, b, *, base_cap=True, tip_cap=True, axis=None):
    """(rows, 9, 3) control points round a centre line in the xy-plane: each ring perpendicular
    to the line (or to ``axis``, when given), half-axes ``a`` (in the xy-plane, across the line)
    and ``b`` (along z)."""
    c = np.asarray(centres, float)
    a, b = list(a), list(b)
    t = np.gradient(c, axis=0) if axis is None else np.tile(np.asarray(axis, float), (len(c), 1))
    t /= la.norm(t, axis=1, keepdims=True)
    n = np.stack([t[:, 1], -t[:, 0]], axis=1)  # in-plane normal
    rows = []
    for (cx, cy), (nx, ny), ai, bi in zip(c, n, a, b):
        pts = np.zeros((len(RING), 3))
        pts[:, 0] = cx + ai * np.cos(RING) * nx
        pts[:, 1] = cy + ai * np.cos(RING) * ny
        pts[:, 2] = bi * np.sin(RING)
        rows.append(pts)
    pts = np.array(rows)
    if base_cap:
        pts = np.concatenate([np.repeat(np.array([[c[0, 0], c[0, 1], 0.0]]), len(RING), 0)[None], pts])
    if tip_cap:
        pts = np.concatenate([pts, np.repeat(np.array([[c[-1, 0], c[-1, 1], 0.0]]), len(RING), 0)[None]])
    pts[:, -1] = pts[:, 0]
    return pts


def capsule(centre, axis, length, ra, rb):
    """(6, 9, 3) a closed capsule in the xy-plane: poles at centre +- length/2 along ``axis``,
    half-axes ``ra`` (in the plane) and ``rb`` (along z) of its widest rings."""
    c, ax = np.asarray(centre, float), np.asarray(axis, float)
    ax = ax / la.norm(ax)
    prof = [(-0.5, 0.0), (-0.5, 0.8), (-0.25, 1.0), (0.25, 1.0), (0.5, 0.8), (0.5, 0.0)]
    cen = [c + s * length * ax for s, _ in prof]
    return ring_tube(cen, [ra * w for _, w in prof], [rb * w for _, w in prof], base_cap=False, tip_cap=False,
                     axis=ax)


def sepal(frame):
    """A sepal's centre line: from inside the receptacle (r 1.6 at y -0.9) out round the corolla
    envelope of this key frame."""
    env = np.array(ENVELOPE[frame]) + MARGIN
    pts = [(1.6, -0.9)] + [(r, y) for r, y in zip(env, ENV_Y)]
    return ring_tube(pts, [0.15] * len(pts), SEPAL_HALF_WIDTH[:len(pts)])


RECEPTACLE_ROWS = [(0, 0.35), (0, 0.2), (0, -0.3), (0, -0.9), (0, -1.3), (0, -1.9), (0, -3.0), (0, -7.0), (0, -8.0)]
RECEPTACLE_RADII = [0.9, 1.25, 1.7, 2.3, 3.3, 1.5, 0.9, 0.8, 0.8]
RECEPTACLE = ring_tube(RECEPTACLE_ROWS, RECEPTACLE_RADII, RECEPTACLE_RADII)


def pose(frame):
    """The column at this key frame: growth of the pistil and stamens linear in time."""
    f = frame / 99.0
    style_top = 17.0 + 6.0 * f
    fil_top = (2.4 + 0.8 * f, 14.0 + 4.0 * f)
    pistil = ring_tube([(0, 0.0), (0, 0.3), (0, 4.0), (0, 10.0), (0, style_top)],
                       [0.9, 0.9, 0.45, 0.3, 0.3], [0.9, 0.9, 0.45, 0.3, 0.3])
    # two-lobed stigma: flattened lobes (thin along z, in the plane of the pair) spreading 35 deg
    spread = math.radians(20.0 + 20.0 * f)
    lobe_len = 1.8 + 1.0 * f
    ax = (math.sin(spread), math.cos(spread))
    stigma = capsule((ax[0] * lobe_len * 0.4, style_top + ax[1] * lobe_len * 0.4 - 0.1), ax, lobe_len,
                     0.55, 0.3)
    stamens = ring_tube([(0.6, 0.0), (0.9, 0.3), (1.6, 6.0), (2.2, 11.0), fil_top],
                        [0.2, 0.2, 0.18, 0.16, 0.16], [0.2, 0.2, 0.18, 0.16, 0.16])
    d = np.array([fil_top[0] - 2.2, fil_top[1] - 11.0])
    d /= la.norm(d)
    anther_len = 2.6 + 0.6 * f
    anthers = capsule((fil_top[0] + d[0] * 0.45 * anther_len, fil_top[1] + d[1] * 0.45 * anther_len), d,
                      anther_len, 0.5, 0.45)
    return {"receptacle": RECEPTACLE, "sepals": sepal(frame), "pistil": pistil, "stigma": stigma,
            "stamens": stamens, "anthers": anthers}


# organ: material, symmetry, phase (degrees). Petal k is centred at 72 k degrees: the sepals and
# stamens alternate with the corolla lobes (phase 36), the stigma's two lobes lie in one plane
# materials (colors.toml): 10 calyx and receptacle, 11 pistil, 12 stigma, 13 filaments, 14 anthers
ORGANS = [("receptacle", 10, 1, 0), ("sepals", 10, 5, 36), ("pistil", 11, 1, 0),
          ("stigma", 12, 2, 0), ("stamens", 13, 5, 36), ("anthers", 14, 5, 36)]


def fmt_rows(pts):
    return "\n".join("  " + "   ".join(f"{x:.4f} {y:.4f} {z:.4f}" for x, y, z in row) for row in pts)


def write(out: Path) -> None:
    for frame in KEY_FRAMES:
        p = pose(frame)
        blocks = [f"organ: {name}\nmaterial: {mat}\ndegree: 1 3\ngrid: 9 {len(p[name])}\n"
                  f"symmetry: {n} {phase}\nlambda: 0.12\neta: 9\npoints:\n{fmt_rows(p[name])}\n"
                  for name, mat, n, phase in ORGANS]
        text = (f"# Eustoma calyx and column at frame {frame + 1}; written by make_column.py\n"
                f"floret 1\nname: column\ntime: {frame / 99.0:.6f}\n\n" + "\n".join(blocks))
        (out / f"column_{frame + 1:03d}.floret").write_text(text)


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else OUT
    out.mkdir(parents=True, exist_ok=True)
    write(out)
