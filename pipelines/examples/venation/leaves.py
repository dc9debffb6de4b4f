"""The contours of the species leaves: ``sunflower.con`` and ``yarrow.con`` (closed VLab contours,
``cver 1 3``, type ``cr``; one unit long, the petiole's attachment at the origin, the tip up +y).

    .venv/bin/python pipelines/examples/venation/leaves.py [OUT_DIR]     # default: this folder

- **Sunflower** (*Helianthus annuus*): a broad ovate blade with a shallow cordate base (the
  petiole sits in the notch), an acuminate tip and a serrate margin: forward-pointing teeth, two
  control points each (a sharp tip of multiplicity 2 and the sinus on the smooth outline), largest
  at mid-blade, none in the basal notch and at the apex.
- **Yarrow** (*Achillea millefolium*): a long, narrow, pinnately dissected ("feathery") leaf: a
  thin rachis carrying 16 pairs of primary segments (pinnae), longest in the upper middle, each
  cut into forward-pointing linear lobes on both sides. The outline is traced once around the
  whole tree of lobes (:func:`lobe_outline`: out along the right side of each lobe, round its tip
  and back along its left side, with the side lobes visited in passing), so it is one simple
  polygon; its vertices are the contour's control points.

Both are checked to enclose an area without crossing themselves (:func:`inflo.tools.venation.blade.self_intersections`).
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from inflo.formats.contour import Contour, write_con
from inflo.tools.common import linalg as la
from inflo.tools.venation.blade import polygon_area, self_intersections

HERE = Path(__file__).resolve().parent


# ------------------------------------------------------------------------------------------------
# sunflower


SUNFLOWER_RIGHT = [  # right half of the smooth outline, from the basal notch to the apex
    (0.0, 0.0), (0.10, -0.05), (0.28, -0.055), (0.43, 0.04), (0.51, 0.19), (0.51, 0.37), (0.45, 0.55),
    (0.33, 0.70), (0.19, 0.83), (0.08, 0.93), (0.025, 1.0), (0.0, 1.07),
]


def sunflower(teeth: int = 14, depth: float = 0.03) -> Contour:
    """The serrate, cordate-ovate sunflower blade (module docstring)."""
    right = np.asarray(SUNFLOWER_RIGHT, float)
    pts = np.vstack([right, right[-2:0:-1] * [-1.0, 1.0]])
    mult = np.ones(len(pts), np.int64)
    mult[0], mult[len(right) - 1] = 2, 3
    smooth = Contour.from_points(pts, mult, type="cr", name="sunflower_smooth")
    dense = smooth.sample(4000)[:, :2]
    dense = np.roll(dense, -int(np.argmin(la.norm(dense, axis=1))), axis=0)  # start at the notch
    if polygon_area(dense) < 0:
        dense = np.vstack([dense[:1], dense[:0:-1]])  # counter-clockwise: up the right side first
    # arc length of the dense outline, the half from the notch to the apex
    seg = la.norm(np.diff(np.vstack([dense, dense[:1]]), axis=0), axis=1)
    s = np.r_[0.0, np.cumsum(seg)][:-1]
    total = s[-1] + seg[-1]
    apex = int(np.argmax(dense[:, 1]))
    half = s[apex]
    out, m = [(0.0, 0.0)], [2]

    def at(arc):
        i = int(np.searchsorted(s, arc % total)) % len(dense)
        p = dense[i]
        q = dense[(i + 1) % len(dense)]
        t = (q - p) / max(la.norm(q - p), 1e-12)
        return p, t

    teeth_at = []
    for side in (0, 1):
        lo, hi = (0.2 * half, 0.86 * half) if side == 0 else (half + 0.14 * half, half + 0.8 * half)
        arcs = np.linspace(lo, hi, teeth + 1)
        for k in range(teeth):
            f = (arcs[k] - lo) / (hi - lo)
            f = 1.0 - f if side == 0 else f  # teeth largest at mid-blade on both sides
            teeth_at.append((arcs[k], arcs[k + 1], depth * (0.45 + 0.55 * math.sin(math.pi * min(max(f, 0.0), 1.0)))))
    arc = 0.0
    plain = 0.035  # smooth control points every this much arc between the toothed stretches
    for a0, a1, amp in teeth_at + [(total, total, 0.0)]:
        while arc + plain < a0 - 0.5 * plain:
            arc += plain
            if abs(arc - half) < 0.5 * plain or arc < 0.08 or arc > total - 0.08:
                continue  # the apex and the basal notch have their own control points
            out.append(tuple(at(arc)[0]))
            m.append(1)
        if out and arc < half <= a0:
            out.append((0.0, float(dense[apex, 1])))  # the acuminate apex
            m.append(3)
        if a1 <= a0:
            break
        p0, _ = at(a0)
        pt, tan = at(a0 + 0.75 * (a1 - a0))  # the tooth leans toward the apex
        normal = np.array([tan[1], -tan[0]])  # outward for a counter-clockwise outline
        out += [tuple(p0), tuple(pt + amp * normal)]
        m += [1, 2]
        arc = a1 - plain
    pts = np.asarray(out)
    return Contour.from_points(pts, np.asarray(m), type="cr", name="sunflower")


# ------------------------------------------------------------------------------------------------
# yarrow


def _rot(d, ang):
    c, s = math.cos(ang), math.sin(ang)
    return np.array([c * d[0] - s * d[1], s * d[0] + c * d[1]])


def lobe_outline(p0, d, length, w0, w1, children, out):
    """Append to ``out`` the outline of a lobe from ``p0`` along unit ``d``, ``length`` long, half
    width ``w0`` at its base tapering to ``w1`` at its tip, interior on the left (counter-clockwise
    for the whole leaf): out along its right side, round the tip, back along its left side.
    ``children``: (t, side, spec) with t in (0, 1) along the lobe, side -1 right / +1 left, spec a
    dict of lobe_outline's keywords for the side lobe (its direction turned ``angle`` off ``d``
    toward its side)."""
    d = np.asarray(d, float) / la.norm(d)
    r = np.array([d[1], -d[0]])
    width = lambda t: w0 + (w1 - w0) * t

    def edge(t, side):
        return p0 + t * length * d + side * width(t) * (-r)

    right = sorted((c for c in children if c[1] < 0), key=lambda c: c[0])
    left = sorted((c for c in children if c[1] > 0), key=lambda c: -c[0])
    out.append(edge(0.0, -1))
    for t, _side, spec in right:
        cd = _rot(d, -spec["angle"])
        half = spec["w0"] / max(abs(la.dot(_rot(cd, math.pi / 2), d)), 0.3)
        out.append(edge(t - half / length, -1))
        base = edge(t, -1) - spec["w0"] * 0.0 * r
        lobe_outline(base - cd * width(t) * 0.5, cd, spec["length"], spec["w0"], spec["w1"], spec.get("children", []),
                     out)
        out.append(edge(t + half / length, -1))
    out.append(edge(1.0, -1))
    out.append(p0 + (length + w1) * d)  # the tip
    out.append(edge(1.0, 1))
    for t, _side, spec in left:
        cd = _rot(d, spec["angle"])
        half = spec["w0"] / max(abs(la.dot(_rot(cd, math.pi / 2), d)), 0.3)
        out.append(edge(t + half / length, 1))
        lobe_outline(edge(t, 1) - cd * width(t) * 0.5, cd, spec["length"], spec["w0"], spec["w1"],
                     spec.get("children", []), out)
        out.append(edge(t - half / length, 1))
    out.append(edge(0.0, 1))


def yarrow(pairs: int = 16) -> Contour:
    """The pinnately dissected yarrow leaf (module docstring)."""
    pinnae = []
    for k in range(pairs):
        for side in (-1, 1):
            t = 0.06 + 0.86 * (k + (0.5 if side > 0 else 0.0)) / pairs
            size = math.sin(math.pi * min(t / 0.95, 1.0) ** 0.8)  # longest in the upper middle
            L = 0.035 + 0.085 * size
            lobes = []
            n_lobes = 2 if L < 0.07 else 3
            for j in range(n_lobes):
                tl = 0.25 + 0.55 * j / max(n_lobes - 1, 1)
                for s2 in (-1, 1):
                    lobes.append((tl + (0.08 if s2 > 0 else 0.0), s2,
                                  dict(angle=math.radians(42), length=0.016 + 0.011 * size * (1 - 0.4 * tl),
                                       w0=0.0045, w1=0.0022)))
            pinnae.append((t, side, dict(angle=math.radians(58), length=L, w0=0.007, w1=0.0035, children=lobes)))
    out: list = []
    lobe_outline(np.array([0.0, 0.0]), np.array([0.0, 1.0]), 0.93, 0.011, 0.004, pinnae, out)
    pts = np.asarray(out)
    # the petiole's attachment: a point of multiplicity 3 (the curve passes through it) below the
    # rachis's two base corners
    pts = np.vstack([[0.0, -0.006], pts])
    keep = np.r_[True, la.norm(np.diff(pts, axis=0), axis=1) > 1e-6]
    pts = pts[keep]
    m = np.ones(len(pts), np.int64)
    m[0] = 3
    return Contour.from_points(pts, m, type="cr", name="yarrow")


def check(contour: Contour, n: int = 6000) -> np.ndarray:
    """The contour sampled as a polygon; raises ValueError when it crosses itself or has no area."""
    poly = contour.sample(n)[:, :2]
    if polygon_area(poly) <= 0:
        raise ValueError(f"{contour.name}: the outline runs clockwise or encloses no area")
    hit = self_intersections(poly)
    if hit is not None:
        raise ValueError(f"{contour.name}: the outline crosses itself near {poly[hit[0]]}")
    return poly


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    out = Path(argv[0]) if argv else HERE
    for c in (sunflower(), yarrow()):
        check(c)
        write_con(out / f"{c.name}.con", c)
        print(f"wrote {out / (c.name + '.con')} ({len(c.points)} control points)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
