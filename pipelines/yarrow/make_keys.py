"""Write the yarrow floret key poses (ray_*.floret, disk_*.floret) from a few numbers per pose.

The .floret files in this folder are the pipeline's inputs and are committed; this script only
documents how their control points were laid out and regenerates them after a change of the
numbers below (``python make_keys.py`` in this folder; ``python make_keys.py OUT_DIR`` writes them
elsewhere, which the tests use to check that the committed files are up to date). See README.md.

Units: a floret model of unit diameter fills its primordium's disc (formats/phyllotaxis.md), so
the numbers below are in disc diameters; local +Y is the floret axis, +X points away from the head
centre (phyllotaxis sets a placement's ``right`` along the receptacle's meridian, outward).

- **Disk floret** (thesis 2.2, fig. 2.3; sec. 9 "five-fold dihedral symmetry, with petals fused
  into a tubular corolla"): one organ ``corolla``, five-fold, bilateral half petal of 3 columns x 6
  rows, the first 4 rows of each lateral boundary fused (a closed tube up to the throat), the top
  two rows free (the lobes). Bud: a closed barrel whose lobes converge over the top; open: a
  narrow tube with five short, broad lobes spread outward at the throat (each lobe's last two rows
  spanning 34 and 28 of its sector's 36 degrees a side: a carpet of corollas from above, where
  lobes of 28 and 6 degrees left the receptacle in view between them, issue 43).
- **Ray floret** (yarrow: a short, broad, three-toothed ligule): one organ ``ligule``, symmetry 1,
  bilateral half of 5 columns x 6 rows (9 columns mirrored), quadratic across so the three lobes
  of the tip stay visible: the tip row reaches furthest at the midline (the middle lobe) and at
  the lateral lobe, and recedes at the notches between them and at the rounded edge. Bud: small,
  erect and cupped around the floret axis; mid: tilted out by about 45 degrees; open: spread
  almost level, pointing away from the head centre, the tip a little down. The open ligule is
  a little broader than long (2.1 floret units broad, 1.9 long from the tube's mouth: 0.84
  of the receptacle's radius), as in *A. millefolium*, whose ligules (2-3 mm) nearly match the
  involucre's width: a head's five or six rays close most of the ring round its disk and reach
  its neighbours' (issue 43; 1.44 broad and 1.28 long before, which left the room between the
  heads open from above).
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from inflo.tools.common import linalg as la

HERE = Path(__file__).resolve().parent
OUT = HERE

# ---- disk floret: corolla rows (radius, height) and the half angle each row spans -----------------
DISK_NU, DISK_NV, DISK_FUSED = 3, 6, 4
DISK = {
    # time, radius per row, height per row, half angle per row (degrees; 36 = the symmetry plane);
    # the tube narrows to its base on the ovary (0.10; 0.18, then 0.12 before: issue 43, the throat
    # seen from above showed the receptacle down the tube, 0.043 of the corymb's top view at 0.18,
    # 0.027 at 0.12; 0.08 let Loop subdivision fold the narrow base into itself)
    "bud": dict(time=0.0,
                r=[0.10, 0.21, 0.26, 0.26, 0.20, 0.05],
                y=[0.00, 0.13, 0.26, 0.38, 0.48, 0.55],
                half=[36, 36, 36, 36, 30, 10]),
    "open": dict(time=1.0,
                 r=[0.10, 0.17, 0.22, 0.25, 0.36, 0.56],
                 y=[0.00, 0.17, 0.34, 0.50, 0.60, 0.58],
                 half=[36, 36, 36, 36, 34, 28]),  # broad lobes (28, 6 before: issue 43)
}

# ---- ray floret: a short corolla tube rolled from the ligule's base, then the ligule ------------
# Each row j of the half ligule: its midrib point (x outward, y up), half width, and how far it is
# rolled round the floret axis (ROLL, degrees of the half arc: 150 = a tube of 300 degrees, open in
# a slit on its inner side as a ray floret's corolla is; 0 = flat). A rolled row is an arc in the
# horizontal plane through its midrib point, of radius half width / roll; a flat row lies across the
# midrib, cupped toward its upper side. The first rows are the tube: it stands among the disk
# florets to the height of their throats, so that the ligule leaves it at the head's rim, touching
# the lobes of the disk florets beside it (issue 43: no ligule floating off the disk).
RAY_NU, RAY_NV = 5, 8
U_RAY = np.linspace(0.0, 1.0, RAY_NU)  # across the half ligule: midline .. edge
# how far each column of the tip row falls short of the midline's tip, as a fraction of the tip
# row's half width: the middle lobe (u = 0, 0.25), a notch (0.5), the lateral lobe (0.75), the edge
TIP_RECESS = np.array([0.0, 0.06, 0.42, 0.10, 0.55])
TUBE = 165.0  # the tube rows' half arc (degrees): a tube of 330 degrees
RAY = {
    # a closed bud: the tube and the ligule rolled round the axis, the lobes converging on top
    "bud": dict(time=0.0,
                mid=[(0.13, 0.00), (0.15, 0.13), (0.16, 0.26), (0.16, 0.38), (0.15, 0.49), (0.13, 0.58),
                     (0.10, 0.65), (0.07, 0.70)],
                roll=[TUBE, TUBE, TUBE, TUBE, TUBE, TUBE, TUBE, TUBE]),
    # half open: the tube grown to the throat, the ligule unrolling and tilted out by about 45 degrees
    "mid": dict(time=0.5,
                mid=[(0.14, 0.00), (0.18, 0.18), (0.25, 0.36), (0.31, 0.50), (0.45, 0.68), (0.68, 0.86),
                     (0.94, 0.98), (1.17, 1.04)],
                half=[None, None, None, 0.36, 0.40, 0.46, 0.48, 0.48],
                roll=[TUBE, TUBE, TUBE, 110.0, 45.0, 10.0, 0.0, 0.0],
                cup=0.35),
    # open: the tube flared to a throat a little wider than the disk florets' (0.46 at 0.55, theirs 0.36 at
    # 0.6), whose rim meets the lobes of the disk florets beside it; the ligule spread almost level
    # from the tube's mouth, 2.1 broad and 1.9 long, pointing away from the head centre (issue 43:
    # 1.44 x 1.28 before; 2.2 x 2.05 left a floret of a late head with no room to emerge at final,
    # 2.0 x 1.85 a pair of florets stuck at draft)
    "open": dict(time=1.0,
                 mid=[(0.14, 0), (0.24, 0.22), (0.42, 0.44), (0.5, 0.56), (0.751, 0.68), (1.3, 0.722),
                      (1.867, 0.646), (2.434, 0.512)],
                 half=[None, None, None, None, 0.705, 0.975, 1.043, 1.009],
                 roll=[TUBE, TUBE, TUBE, TUBE, 80.0, 10.0, 0.0, 0.0],
                 cup=0.08),
}


def fmt_rows(pts):
    return "\n".join("  " + "   ".join(f"{x:.4f} {y:.4f} {z:.4f}" for x, y, z in row) for row in pts)


def disk_net(p):
    pts = np.zeros((DISK_NV, DISK_NU, 3))
    for j in range(DISK_NV):
        a = np.radians(np.linspace(0.0, p["half"][j], DISK_NU))
        pts[j, :, 0] = p["r"][j] * np.cos(a)
        pts[j, :, 1] = p["y"][j]
        pts[j, :, 2] = p["r"][j] * np.sin(a)
    return pts


def ray_net(p):
    """Half ligule: row j rolled round the floret axis by p["roll"][j] degrees (an arc in the
    horizontal plane through its midrib point) or, unrolled, across the midrib, cupped toward its
    upper side. A row's half width is given, or (None) that of its roll at its midrib point's
    distance from the axis (a tube row: the arc centred on the axis)."""
    mid = np.array(p["mid"], float)
    pts = np.zeros((RAY_NV, RAY_NU, 3))
    for j in range(RAY_NV):
        a = mid[min(j + 1, RAY_NV - 1)] - mid[max(j - 1, 0)]
        t = a / la.norm(a)
        n = np.array([-t[1], t[0]])  # turned +90 degrees: toward the head centre / up
        roll = np.radians(p["roll"][j])
        half = p.get("half", [None] * RAY_NV)[j]
        w = mid[j, 0] * roll if half is None else half
        back = TIP_RECESS * w if j == RAY_NV - 1 else np.zeros(RAY_NU)
        if roll > 1e-9:
            r = w / roll
            th = U_RAY * roll
            pts[j, :, 0] = mid[j, 0] - r * (1.0 - np.cos(th)) - back * t[0]
            pts[j, :, 1] = mid[j, 1] - back * t[1]
            pts[j, :, 2] = r * np.sin(th)
            continue
        for i, u in enumerate(U_RAY):
            lift = p["cup"] * w * u * u * 0.5  # cupped: the edges curl to the upper side
            xy = mid[j] - back[i] * t + lift * n
            pts[j, i] = (xy[0], xy[1], u * w)
    return pts


# ---- involucral bract (phyllary) ---------------------------------------------------------------
# Achillea's phyllaries: small, ovate-oblong, greenish, imbricate in 3-4 rows forming a cup round
# the head. A bract stands on the involucre (involucre.toml: a sphere round the head's receptacle,
# its local +Y the sphere's outward normal, +X down the meridian), so its blade runs up the sphere
# (-X) toward the head's rim, leaving it outward by a little (the bract below overlaps the base of
# the bract above it from outside: imbricate) and following most of its curvature (the sphere's
# radius is SPHERE bract units); concave inside (cupped toward -Y). Broad (0.9 bract units
# across): the bracts of one row nearly touch.
BRACT_NU, BRACT_NV = 4, 6
U_BRACT = np.linspace(0.0, 1.0, BRACT_NU)
BRACT_X = np.array([0.0, -0.2, -0.4, -0.6, -0.8, -1.0])
SPHERE = 2.35  # the involucre's radius in bract units (involucre.toml: 1.06 / 0.451)


def bract_mid(lift, bend):
    """The midrib: up the sphere, ``lift`` per unit length outward, ``bend`` of its curvature."""
    return [(x, lift * abs(x) - bend * x * x / (2.0 * SPHERE)) for x in BRACT_X]


BRACT = {
    # appressed round the young head, following the involucre closely
    "bud": dict(time=0.0, mid=bract_mid(0.04, 1.0), half=[0.14, 0.32, 0.40, 0.39, 0.29, 0.08], cup=0.08),
    # the head open: a little spreading, broad and obtuse (ovate-oblong)
    "open": dict(time=1.0, mid=bract_mid(0.09, 0.8), half=[0.16, 0.36, 0.45, 0.44, 0.33, 0.10], cup=0.1),
}


def bract_net(p):
    """Half bract: column i at u_i of the row's half width (+Z), cupped toward -Y (inside)."""
    mid = np.array(p["mid"], float)
    pts = np.zeros((BRACT_NV, BRACT_NU, 3))
    for j in range(BRACT_NV):
        w = p["half"][j]
        for i, u in enumerate(U_BRACT):
            pts[j, i] = (mid[j, 0], mid[j, 1] - p["cup"] * w * u * u * 0.5, u * w)
    return pts


def write_disk():
    for key, p in DISK.items():
        text = (f"# yarrow disk floret, key pose '{key}'; written by make_keys.py\n"
                f"floret 1\nname: disk\ntime: {p['time']}\n\n"
                f"organ: corolla\nmaterial: 8\ndegree: 3 3\ngrid: {DISK_NU} {DISK_NV}\nsymmetry: 5 0\n"
                f"bilateral: on\nfused: {DISK_FUSED}\npoints:\n{fmt_rows(disk_net(p))}\n")
        (OUT / f"disk_{key}.floret").write_text(text)


def write_ray():
    for key, p in RAY.items():
        text = (f"# yarrow ray floret, key pose '{key}'; written by make_keys.py\n"
                f"floret 1\nname: ray\ntime: {p['time']}\n\n"
                f"organ: ligule\nmaterial: 0\ndegree: 2 3\ngrid: {RAY_NU} {RAY_NV}\nsymmetry: 1 0\n"
                f"bilateral: on\npoints:\n{fmt_rows(ray_net(p))}\n")
        (OUT / f"ray_{key}.floret").write_text(text)


def write_bract():
    for key, p in BRACT.items():
        text = (f"# yarrow involucral bract (phyllary), key pose '{key}'; written by make_keys.py\n"
                f"floret 1\nname: bract\ntime: {p['time']}\n\n"
                f"organ: bract\nmaterial: 3\ndegree: 2 3\ngrid: {BRACT_NU} {BRACT_NV}\nsymmetry: 1 0\n"
                f"bilateral: on\npoints:\n{fmt_rows(bract_net(p))}\n")
        (OUT / f"bract_{key}.floret").write_text(text)


if __name__ == "__main__":
    if len(sys.argv) > 1:
        OUT = Path(sys.argv[1])
        OUT.mkdir(parents=True, exist_ok=True)
    write_disk()
    write_ray()
    write_bract()
