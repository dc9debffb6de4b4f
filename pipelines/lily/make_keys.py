"""Write the lily's tepal key poses (key_*.floret) from a few numbers per pose.

The .floret files in this folder are the pipeline's inputs and are committed; this script only
documents how their control points were laid out and regenerates them after a change of the
numbers below (``python make_keys.py`` in this folder; ``python make_keys.py OUT_DIR`` writes
them elsewhere, which the tests use to check the committed files are up to date). See README.md for the modelling choices.

Every tepal is a bilateral half of 4 columns (midrib .. lateral edge) by 9 rows (base .. tip),
bicubic. Rows 0, 1 and 2 (the claw at the receptacle) are the same in every pose, so the measured
joint angle between the tepal and the flower axis changes only by the pose's ``tilt``.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from inflo.tools.common import linalg as la

HERE = Path(__file__).resolve().parent
OUT = HERE  # where the files are written (python make_keys.py [OUT_DIR])
NV, NU = 9, 4
KEEP = 3  # rows 0..KEEP-1 (the claw) are the same in every pose
U = np.linspace(0.0, 1.0, NU)

# ---- the closed bud: tepals lie on two nested surfaces of revolution --------------------------------
# sepal (outer whorl): radius of the bud and height at each row, half the angle it wraps around
SEPAL_Y = np.array([0.00, 0.275, 0.55, 1.15, 1.75, 2.35, 2.95, 3.50, 3.95])
SEPAL_R = np.array([0.30, 0.43, 0.55, 0.72, 0.75, 0.68, 0.52, 0.30, 0.085])
SEPAL_HALF = np.radians([40, 42, 44, 45, 45, 45, 43, 36, 20])
# petal (inner whorl, turned by 60 degrees): inside the sepals, a little shorter, broader
PETAL_Y = np.array([0.06, 0.32, 0.58, 1.15, 1.72, 2.28, 2.84, 3.34, 3.74])
PETAL_GAP = np.array([0.05, 0.045, 0.04, 0.035, 0.035, 0.035, 0.035, 0.035, 0.035])
PETAL_HALF = np.radians([48, 51, 54, 55, 55, 55, 52, 42, 22])


def sepal_radius_at(y):
    return np.interp(y, SEPAL_Y, SEPAL_R)


def bud_net(ys, rs, half):
    """Half tepal on the surface of revolution r(y): column i wraps u_i * half around the axis."""
    pts = np.zeros((NV, NU, 3))
    for j in range(NV):
        a = U * half[j]
        pts[j, :, 0] = rs[j] * np.cos(a)
        pts[j, :, 1] = ys[j]
        pts[j, :, 2] = rs[j] * np.sin(a)
    return pts


def open_net(bud, angles_deg, length_scale, width_scale, channel):
    """Rows KEEP.. rebuilt from the midrib's segment directions (degrees from the axis, toward +X).

    The lamina is flat across (z = u w) and, with ``channel`` > 0, lags behind the midrib: its
    edges sit on the adaxial (inner) side by channel * u^2 * w (thesis ch. 2 control net).
    """
    pts = bud.copy()
    mid = bud[:, 0, :2]
    seg = la.norm(np.diff(mid, axis=0), axis=1)
    half_w = la.norm(bud[:, -1] - bud[:, 0], axis=1)  # chord of the half cross-section
    p = mid[KEEP - 1].copy()
    for j in range(KEEP - 1, NV - 1):
        a = j - (KEEP - 1)
        phi = math.radians(angles_deg[a])
        d = np.array([math.sin(phi), math.cos(phi)])
        p = p + seg[j] * length_scale * d
        k = j + 1
        # inner normal of the segment arriving at row k, averaged with the next one
        phin = math.radians(angles_deg[min(a + 1, len(angles_deg) - 1)])
        ph = 0.5 * (phi + phin)
        n = np.array([-math.cos(ph), math.sin(ph)])
        w = half_w[k] * width_scale
        for i, u in enumerate(U):
            off = channel * u * u * w
            pts[k, i, 0] = p[0] + off * n[0]
            pts[k, i, 1] = p[1] + off * n[1]
            pts[k, i, 2] = u * w
    return pts


SEPAL_BUD = bud_net(SEPAL_Y, SEPAL_R, SEPAL_HALF)
PETAL_BUD = bud_net(PETAL_Y, sepal_radius_at(PETAL_Y) - PETAL_GAP, PETAL_HALF)

# directions of the midrib segments from row KEEP-1 on (degrees from the flower axis, before the tilt)
OPEN_ANGLES = np.array([24, 36, 50, 64, 78, 92])       # reached at frame 60 and kept
EARLY_ANGLES = np.array([30, 48, 70, 90, 106, 118])     # frame 40: the midrib reflexed hard
# per pose: frame (1-based), tilt = joint angle added (23 deg over frames 1-60, then held), length and
# width of the lamina relative to the bud, channel = how far the lamina edges lag behind the midrib
POSES = {
    "bud": dict(frame=1, tilt=0.0),
    "early": dict(frame=40, tilt=23.0 * 39 / 59, length=1.10, width=1.00, channel=0.45),
    "mid": dict(frame=60, tilt=23.0, length=1.16, width=1.08, channel=0.18),
    "open": dict(frame=100, tilt=23.0, length=1.22, width=1.15, channel=0.06),
}
# petal midrib angles this much smaller than the sepal's: early on the petals lead (-12 deg) and press
# on the sepals that overlap them (fccompose resolves those contacts); from frame 60 they stay 3 deg
# less reflexed, so the open petals lie just inside (above) the sepals
PETAL_LAG = {"early": -12.0, "mid": 3.0, "open": 3.0}


def fmt_rows(pts):
    return "\n".join("  " + "   ".join(f"{x:.4f} {y:.4f} {z:.4f}" for x, y, z in row) for row in pts)


def organ_block(name, material, phase, tilt, eta, lam, pts):
    return (f"organ: {name}\nmaterial: {material}\ndegree: 3 3\ngrid: {NU} {NV}\n"
            f"symmetry: 3 {phase}\nbilateral: on\ntilt: {tilt:.4f}\nlambda: {lam}\neta: {eta}\n"
            f"points:\n{fmt_rows(pts)}\n")


def main():
    for key, p in POSES.items():
        if key == "bud":
            sep, pet = SEPAL_BUD, PETAL_BUD
        else:
            ang = OPEN_ANGLES if key in ("mid", "open") else EARLY_ANGLES
            sep = open_net(SEPAL_BUD, ang, p["length"], p["width"], p["channel"])
            pet = open_net(PETAL_BUD, ang - PETAL_LAG[key], p["length"], p["width"],
                           p["channel"])
        t = (p["frame"] - 1) / 99.0
        text = (f"# lily key pose '{key}' (frame {p['frame']} of 100); written by make_keys.py\n"
                f"floret 1\nname: lily\ntime: {t:.6f}\n\n"
                + organ_block("sepals", 3, 0, p["tilt"], 17, 0.0556, sep) + "\n"
                + organ_block("petals", 4, 60, p["tilt"], 19, 0.0526, pet))
        (OUT / f"key_{key}.floret").write_text(text)



# ---- pistil, six stamens with anthers, receptacle: closed tubes ------------------------------------
# A ring of 9 control columns (the last = the first: closed around) by rows along the tube; the
# first and last rows are collapsed to one point on the tube's axis (radius 0), so the clamped
# cubic surface closes there in a rounded end (its tangent at the pole is radial): no open end.
RING = np.linspace(0.0, 2.0 * math.pi, 9)


def tube(centres, radii, *, base_cap=True, tip_cap=True):
    """(rows, 9, 3) control points of a tube around a centre line in the xy-plane (horizontal
    rings), closed at the base and/or tip by a pole row on the centre line."""
    centres, radii = list(centres), list(radii)
    if base_cap:
        centres, radii = [centres[0], *centres], [0.0, *radii]
    if tip_cap:
        centres, radii = [*centres, centres[-1]], [*radii, 0.0]
    pts = np.zeros((len(centres), len(RING), 3))
    for j, ((cx, cy), r) in enumerate(zip(centres, radii)):
        pts[j, :, 0] = cx + r * np.cos(RING)
        pts[j, :, 1] = cy
        pts[j, :, 2] = r * np.sin(RING)
    pts[:, -1] = pts[:, 0]
    return pts


def capsule(centre, axis, length, radius, across=(1.0, 0.0, 0.0)):
    """(6, 9, 3) control points of a closed capsule (an anther): poles at centre +- length/2 along
    ``axis``, rings across it widening to ``radius``. Each ring starts on ``across`` (made
    perpendicular to the axis): two poses with the same ``across`` and axes turned about it
    interpolate as a capsule turning (shortened at most by cos 45 deg half-way for a quarter
    turn), not as rings twisting flat."""
    c, a = np.asarray(centre, float), np.asarray(axis, float)
    a = a / la.norm(a)
    e1 = np.asarray(across, float) - la.dot(across, a) * a
    e1 /= la.norm(e1)
    e2 = np.cross(a, e1)
    rows = [(-0.5, 0.0), (-0.5, 0.8), (-0.25, 1.0), (0.25, 1.0), (0.5, 0.8), (0.5, 0.0)]
    pts = np.zeros((len(rows), len(RING), 3))
    for j, (t, r) in enumerate(rows):
        pts[j] = c + t * length * a + radius * r * (np.cos(RING)[:, None] * e1 + np.sin(RING)[:, None] * e2)
    pts[:, -1] = pts[:, 0]
    return pts


# the receptacle and a stub of the pedicel under the tepals' claws (the same in every pose), closed
# on top (a pole on the axis) and under the stub. Its top lies just inside the claws (a sepal's row 0
# on r = 0.30 at y = 0, a petal's on r = 0.28 at y = 0.06), and a collar just under them (r up to
# 0.39 at y = -0.07, below every claw) fills the view between the claws and the receptacle from above
# and from the side: the tepals grow out of it, with no background showing between them.
RECEPTACLE = tube([(0, 0.21), (0, 0.20), (0, 0.15), (0, 0.08), (0, 0.03), (0, -0.02), (0, -0.05),
                   (0, -0.08), (0, -0.12), (0, -0.16), (0, -0.26), (0, -0.45), (0, -1.1), (0, -1.2)],
                  [0.0, 0.12, 0.215, 0.25, 0.265, 0.27, 0.33, 0.40, 0.40, 0.34, 0.20, 0.13, 0.09, 0.09],
                  base_cap=False)

# versatile anthers (lily anthers are dorsifixed: the filament's tip enters the anther's back near
# its middle, and the anther swings on it): the anther's axis, in the stamen's radial plane, is turned
# from the filament's tip direction by this many degrees (outward and downward) at the column's key
# times 0, 0.25, 0.5, 0.75 and 1: along the filament in the bud, crosswise (a T) in the open flower.
# Five poses keep each turn to 22.5 degrees: floret-animate blends each control column in its own
# frame, which carries a capsule turning about one axis shortened by the cosine of half the turn
# half-way between two poses and its rings distorted by as much (two poses and a quarter turn
# flattened the anthers half-way; three, 45 degrees apiece, still showed paddles between poses).
ANTHER_TURN = {"bud": 5.0, "early": 27.5, "mid": 50.0, "late": 72.5, "open": 95.0}
# a three-lobed stigma (Lilium: three carpels, three stigma lobes): three capsules (symmetry 3)
# spreading from the top of the style, each lobe's inner pole inside the style's tip
STIGMA = {"bud": dict(centre=(0.035, 1.93), axis=(0.45, 0.89), length=0.20, radius=0.05),
          "open": dict(centre=(0.075, 4.02), axis=(0.62, 0.78), length=0.34, radius=0.085)}


def filament_tip(stamens):
    """Tip (x, y) of a filament tube and the unit direction of its last segment."""
    c = stamens[:, :-1, :2].mean(axis=1)  # ring centres (a ring's last point repeats its first)
    tip, prev = c[-1], c[-3]
    d = tip - prev
    return tip, d / la.norm(d)


def anther(stamens, turn_deg, length, radius):
    """A versatile anther on the filament's tip: its centre a little beyond the tip (the tip ends
    inside it, near its middle, on its back), its axis turned by ``turn_deg`` from the filament's
    direction about the tangential axis (z), so the anther stays in the stamen's radial plane."""
    tip, d = filament_tip(stamens)
    t = math.radians(-turn_deg)
    a = np.array([d[0] * math.cos(t) - d[1] * math.sin(t), d[0] * math.sin(t) + d[1] * math.cos(t), 0.0])
    # the centre lies off the tip along the anther's normal in the radial plane, on the side the
    # filament points to, so the tip sits 0.4 radius inside the anther's back, near its middle
    n = np.array([-a[1], a[0], 0.0])
    if la.dot(n[:2], d) < 0:
        n = -n
    centre = np.array([tip[0], tip[1], 0.0]) + 0.4 * radius * n
    return capsule(centre, a, length, radius, across=(0.0, 0.0, 1.0))


def stigma(p):
    return capsule((p["centre"][0], p["centre"][1], 0.0), (*p["axis"], 0.0), p["length"], p["radius"],
                   across=(0.0, 0.0, 1.0))


def _column_poses():
    bud = dict(time=0.0,
               pistil=tube([(0, 0.10), (0, 0.8), (0, 1.5), (0, 1.8), (0, 1.9)], [0.05, 0.045, 0.045, 0.06, 0.06]),
               stamens=tube([(0.12, 0.10), (0.14, 0.7), (0.16, 1.3), (0.17, 1.6)],
                            [0.025, 0.022, 0.022, 0.025]),
               stigma=stigma(STIGMA["bud"]))
    opn = dict(time=1.0,
               pistil=tube([(0, 0.10), (0, 1.6), (0, 3.2), (0, 3.85), (0, 3.98)], [0.06, 0.05, 0.05, 0.085, 0.085]),
               stamens=tube([(0.12, 0.10), (0.3, 1.4), (0.6, 2.7), (0.85, 3.6)],
                            [0.03, 0.025, 0.025, 0.03]),
               stigma=stigma(STIGMA["open"]))
    # the poses between (key times 0.25, 0.5, 0.75): tubes part-way, the anther part-turned
    poses = {"bud": bud}
    for key, f in (("early", 0.25), ("mid", 0.5), ("late", 0.75)):
        poses[key] = dict(time=f, **{k: (1.0 - f) * bud[k] + f * opn[k] for k in ("pistil", "stamens", "stigma")})
    poses["open"] = opn
    for key, pose in poses.items():
        f = pose["time"]
        pose["anthers"] = anther(pose["stamens"], ANTHER_TURN[key], 0.45 + 0.35 * f, 0.05 + 0.03 * f)
    return poses


# pistil on the axis (style, a three-lobed stigma), six stamens (filaments) leaning outward, each
# carrying a versatile anther; five poses at key times 0, 0.25, 0.5, 0.75, 1 (column_growth.func times them)
COLUMN = _column_poses()


def write_column():
    for key, p in COLUMN.items():
        blocks = []
        p = dict(p, receptacle=RECEPTACLE)
        for name, mat, n, phase in (("receptacle", 7, 1, 0), ("pistil", 5, 1, 0), ("stigma", 9, 3, 0),
                                    ("stamens", 6, 6, 30), ("anthers", 8, 6, 30)):
            nv = len(p[name])
            blocks.append(f"organ: {name}\nmaterial: {mat}\ndegree: 1 3\ngrid: 9 {nv}\n"
                          f"symmetry: {n} {phase}\nlambda: 0.1\neta: 9\npoints:\n{fmt_rows(p[name])}\n")
        text = (f"# receptacle, pistil, stigma, stamens and anthers, pose '{key}'; written by make_keys.py\n"
                f"floret 1\nname: column\ntime: {p['time']}\n\n" + "\n".join(blocks))
        (OUT / f"column_{key}.floret").write_text(text)


# the growth-map lily (growth.mk) is about nine times the key-pose lily's size (tepals about 48
# units long, their bases 1.2-1.9 from the axis): the same pistil, stigma, stamens and anthers,
# scaled by GROWTH_SCALE about the receptacle's top, on a receptacle of its own that fits inside
# the tepals' bases (r <= 1.0 above y = 0) with a collar under them (r up to 2.6 at y = -0.9)
GROWTH_SCALE = 9.0
GROWTH_RECEPTACLE = tube([(0, 0.6), (0, 0.55), (0, 0.3), (0, 0.0), (0, -0.35), (0, -0.7), (0, -1.1),
                          (0, -1.6), (0, -3.0), (0, -8.0), (0, -10.0)],
                         [0.0, 0.6, 0.95, 1.0, 1.5, 2.5, 2.6, 2.2, 1.2, 0.8, 0.8], base_cap=False)


def write_growth_column():
    for key, p in COLUMN.items():
        blocks = []
        for name, mat, n, phase in (("receptacle", 7, 1, 0), ("pistil", 5, 1, 0), ("stigma", 9, 3, 0),
                                    ("stamens", 6, 6, 30), ("anthers", 8, 6, 30)):
            pts = GROWTH_RECEPTACLE if name == "receptacle" else p[name] * GROWTH_SCALE
            blocks.append(f"organ: {name}\nmaterial: {mat}\ndegree: 1 3\ngrid: 9 {len(pts)}\n"
                          f"symmetry: {n} {phase}\nlambda: 0.1\neta: 9\npoints:\n{fmt_rows(pts)}\n")
        text = (f"# the growth-map lily's receptacle, pistil, stigma, stamens and anthers, pose '{key}'; "
                f"written by make_keys.py\nfloret 1\nname: column\ntime: {p['time']}\n\n" + "\n".join(blocks))
        (OUT / f"growth_column_{key}.floret").write_text(text)


def write_weights():
    """Fixed vertices: rows 0 and 1 of every tepal (the claw on the receptacle), in polygonize's
    vertex order (organ by organ, copy by copy, row by row from the base; 17 vertices a row on a
    sepal, 19 on a petal; 19 rows on a sepal, 20 on a petal)."""
    lines = ["# lily.weights: fixed (inverse mass 0) vertices of animation 0 in lily.fcc",
             "# rows 0 and 1 (the claw) of each tepal; written by make_keys.py"]
    offset = 0
    for name, per_row, rows in (("sepals", 17, 19), ("petals", 19, 20)):
        for c in range(3):
            ids = [offset + c * per_row * rows + k for k in range(2 * per_row)]
            lines.append(f"# {name}_{c}")
            lines.append(" ".join(str(i) for i in ids))
        offset += 3 * per_row * rows
    (OUT / "lily.weights").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    if len(sys.argv) > 1:
        OUT = Path(sys.argv[1])
        OUT.mkdir(parents=True, exist_ok=True)
    main()
    write_column()
    write_growth_column()
    write_weights()
