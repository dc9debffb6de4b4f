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
  narrow tube with five short lobes spread outward at the throat.
- **Ray floret** (yarrow: a short, broad, three-toothed ligule): one organ ``ligule``, symmetry 1,
  bilateral half of 5 columns x 6 rows (9 columns mirrored), quadratic across so the three lobes
  of the tip stay visible: the tip row reaches furthest at the midline (the middle lobe) and at
  the lateral lobe, and recedes at the notches between them and at the rounded edge. Bud: small,
  erect and cupped around the floret axis; mid: tilted out by about 45 degrees; open: spread
  almost level, pointing away from the head centre, the tip a little down.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
OUT = HERE

# ---- disk floret: corolla rows (radius, height) and the half angle each row spans -----------------
DISK_NU, DISK_NV, DISK_FUSED = 3, 6, 4
DISK = {
    # time, radius per row, height per row, half angle per row (degrees; 36 = the symmetry plane)
    "bud": dict(time=0.0,
                r=[0.18, 0.23, 0.26, 0.26, 0.20, 0.05],
                y=[0.00, 0.13, 0.26, 0.38, 0.48, 0.55],
                half=[36, 36, 36, 36, 30, 10]),
    "open": dict(time=1.0,
                 r=[0.18, 0.20, 0.22, 0.25, 0.36, 0.56],
                 y=[0.00, 0.17, 0.34, 0.50, 0.60, 0.58],
                 half=[36, 36, 36, 36, 28, 6]),
}

# ---- ray floret: the ligule's midrib (x outward, y up), half width per row, tip lobes -------------
RAY_NU, RAY_NV = 5, 6
U_RAY = np.linspace(0.0, 1.0, RAY_NU)  # across the half ligule: midline .. edge
# how far each column of the tip row falls short of the midline's tip, as a fraction of the tip
# row's half width: the middle lobe (u = 0, 0.25), a notch (0.5), the lateral lobe (0.75), the edge
TIP_RECESS = np.array([0.0, 0.06, 0.42, 0.10, 0.55])
BASE_R = 0.12  # radius of the arc of the ligule's base row around the floret axis
RAY = {
    "bud": dict(time=0.0,
                mid=[(0.10, 0.00), (0.14, 0.18), (0.17, 0.36), (0.17, 0.52), (0.14, 0.64), (0.09, 0.72)],
                half=[0.06, 0.09, 0.12, 0.13, 0.12, 0.10],
                cup=0.9),
    "mid": dict(time=0.5,
                mid=[(0.10, 0.00), (0.17, 0.27), (0.32, 0.50), (0.60, 0.68), (0.90, 0.80), (1.15, 0.84)],
                half=[0.07, 0.15, 0.30, 0.42, 0.48, 0.48],
                cup=0.35),
    "open": dict(time=1.0,
                 mid=[(0.10, 0.00), (0.22, 0.24), (0.45, 0.44), (0.88, 0.56), (1.35, 0.55), (1.72, 0.46)],
                 half=[0.08, 0.30, 0.52, 0.66, 0.72, 0.72],
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
    """Half ligule: column i at u_i of the row's half width, bent up (cupped) toward the edge."""
    mid = np.array(p["mid"], float)
    pts = np.zeros((RAY_NV, RAY_NU, 3))
    for j in range(RAY_NV):
        # the midrib's direction at row j and the in-plane normal (the ligule's upper side)
        a = mid[min(j + 1, RAY_NV - 1)] - mid[max(j - 1, 0)]
        t = a / np.linalg.norm(a)
        n = np.array([-t[1], t[0]])  # turned +90 degrees: toward the head centre / up
        w = p["half"][j]
        if j == 0:
            # the base row wraps around the floret axis (an arc of radius BASE_R through the
            # midrib's base), never a straight, collinear row of fixed vertices
            th = U_RAY * w / BASE_R
            pts[0, :, 0] = mid[0, 0] - BASE_R * (1.0 - np.cos(th))
            pts[0, :, 1] = mid[0, 1]
            pts[0, :, 2] = BASE_R * np.sin(th)
            continue
        for i, u in enumerate(U_RAY):
            back = TIP_RECESS[i] * w if j == RAY_NV - 1 else 0.0
            lift = p["cup"] * w * u * u * 0.5  # cupped: the edges curl to the upper side
            xy = mid[j] - back * t + lift * n
            pts[j, i] = (xy[0], xy[1], u * w)
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


if __name__ == "__main__":
    if len(sys.argv) > 1:
        OUT = Path(sys.argv[1])
        OUT.mkdir(parents=True, exist_ok=True)
    write_disk()
    write_ray()
