"""Write the sunflower key poses (disk_*, ray_*, bract_* .floret) from a few numbers per pose.

The .floret files under draft/ and final/ are the pipeline's inputs and are committed; this script
documents how their control points were laid out and regenerates them after a change of the
numbers below (``python make_keys.py`` in this folder; ``python make_keys.py OUT_DIR`` writes both
sets under OUT_DIR, which the tests use to check that the committed files are up to date). The two
sets differ only in their polygonization (each organ's ``lambda:`` and ``eta:``), so a draft and a
final floret have the same shape. See README.md.

Units: a floret model of unit diameter fills its primordium's disc (formats/phyllotaxis.md), so
the numbers are in disc diameters; local +Y is the floret axis (the receptacle's normal), +X
points away from the head centre along the receptacle's meridian.

- **Disk floret** (thesis ch. 9: "five-fold dihedral symmetry, with petals fused into a tubular
  corolla almost up to the petal tips. As the flowers open, sexual organs - stamens, then pistils -
  raise above the level of the petals ... modeled summarily as cylinders growing along the central
  axis"): organ ``corolla`` (five-fold, bilateral half petal 3 columns x 7 rows, the first 6 rows of
  each lateral boundary fused: the lobes part only in the last row), organ ``anthers`` (five-fold,
  fused along its whole height, dark: a cone of filaments from the corolla's base, then the anther
  tube, about half the corolla's height long and a little over half its throat wide, as in a real
  floret: a corolla 7-8 mm long, an anther tube 3-4 mm long about as wide as the throat's inside)
  and organ ``pistil`` (two-fold: a style fused over its lower third, parting into two stigma
  branches). Three key poses: ``bud`` (a closed barrel, its lobes converging over the organs
  inside), ``open`` (the corolla opened into a narrow tube and a wide throat under five short
  spreading lobes, their tips 1.24 disc diameters across so that neighbouring mouths touch, the
  anther tube a third of the corolla's height above them) and ``late`` (the style risen through
  the anther tube, its two branches spread).
- **Ray floret** (ch. 9: "Three large fused petals point outward, giving the appearance of a
  single large petal. The remaining two petals are highly reduced. We have only included the
  conspicuous large petals"): organ ``ligule``, symmetry 1, bilateral half of 5 columns x 8 rows,
  quadratic across, the tip row cut into three shallow teeth. ``bud``: short, erect, cupped around
  the axis; ``mid``: half grown, leaning out; ``open``: five disc diameters long, spread almost
  level with a gentle droop at the tip, a shallow channel along the midrib.
- **Involucral bract** (phyllary; ch. 9 on gaillardia: "specialized leaves that surround the head
  and protect it in its early development"): organ ``bract``, symmetry 1, bilateral half of
  4 columns x 6 rows, an ovate blade with a long acuminate tip. The bracts are the first, outermost
  primordia of the head (dimorph --bracts), at the receptacle's rim: ``bud`` erect, clasping the
  young head; ``open`` reflexed outward over the rim and down, under the ray florets.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from inflo.tools.species.keys import blade_net, cylinder_net, fmt_rows, organ, ring_net  # noqa: F401

HERE = Path(__file__).resolve().parent

# polygonization per quality: (lambda, eta) of each organ; a .func name is written as is (relative
# to the key pose's folder). The corolla's eta falls to 1 vertex at the lobe tips (lobe_eta_*.func):
# with as many vertices on the tip row as on the tube's rows, the tips' rim edges are a few percent
# of a median edge between needle triangles, and crowded florets stretch them several times over
# (formats/fcc.md, "Mesh quality matters")
RES = {
    "draft": {"corolla": ("0.34", "../lobe_eta_draft.func"), "anthers": ("0.5", "3"), "pistil": ("0.34", "3"),
              "ligule": ("0.2", "5"), "bract": ("0.34", "3")},
    "final": {"corolla": ("0.34", "../lobe_eta_final.func"), "anthers": ("0.5", "3"), "pistil": ("0.34", "3"),
              "ligule": ("0.1", "9"), "bract": ("0.2", "5")},
}

# ---- disk floret ----------------------------------------------------------------------------------
DISK_NU, DISK_NV, DISK_FUSED = 3, 7, 6
# the pistil: a two-fold bilateral organ (the style and its two branches), half petal of 2 columns
# (the midline, toward +X, and the symmetry plane x = 0) x 5 rows; its first 3 rows' boundary
# points are fused, so the two halves are one style up to a third of its length (v in [0, 1/3]) and
# part above it into the two stigma branches (closed in bud and open, 0.01 apart: two surfaces
# that only touch count as intersecting)
STYLE_NV, STYLE_FUSED = 5, 3
DISK = {
    # corolla: radius, height and half angle (degrees; 36 = the symmetry plane) per row;
    # anthers: (radius, height) of its three rows (a five-fold tube fused along its whole height:
    # the filaments, a cone from the corolla's base, then the anther tube); pistil: (x of the
    # midline, x and z of the boundary point, height) of each of its rows
    "bud": dict(time=0.0,
                r=[0.16, 0.24, 0.31, 0.33, 0.30, 0.20, 0.05],
                y=[0.00, 0.14, 0.30, 0.46, 0.60, 0.72, 0.78],
                half=[36, 36, 36, 36, 36, 34, 12],
                anthers=[(0.08, 0.00), (0.17, 0.30), (0.17, 0.56)],
                pistil=[(0.05, 0.00, 0.05, 0.00), (0.05, 0.00, 0.05, 0.16), (0.05, 0.00, 0.05, 0.30),
                        (0.05, 0.005, 0.05, 0.40), (0.05, 0.005, 0.05, 0.48)]),
    "open": dict(time=0.55,
                 r=[0.15, 0.19, 0.27, 0.37, 0.46, 0.51, 0.62],
                 y=[0.00, 0.20, 0.42, 0.62, 0.78, 0.88, 0.93],
                 half=[36, 36, 36, 36, 36, 34, 10],
                 anthers=[(0.10, 0.00), (0.24, 0.66), (0.24, 1.16)],
                 pistil=[(0.06, 0.00, 0.06, 0.00), (0.06, 0.00, 0.06, 0.36), (0.06, 0.00, 0.06, 0.70),
                         (0.06, 0.005, 0.06, 0.90), (0.06, 0.005, 0.06, 1.04)]),
    "late": dict(time=1.0,
                 r=[0.15, 0.19, 0.27, 0.37, 0.46, 0.52, 0.64],
                 y=[0.00, 0.20, 0.42, 0.62, 0.78, 0.87, 0.90],
                 half=[36, 36, 36, 36, 36, 34, 10],
                 anthers=[(0.10, 0.00), (0.24, 0.66), (0.24, 1.18)],
                 pistil=[(0.06, 0.00, 0.06, 0.00), (0.06, 0.00, 0.06, 0.60), (0.06, 0.00, 0.06, 1.20),
                         (0.08, 0.03, 0.045, 1.34), (0.17, 0.13, 0.03, 1.42)]),
}


def tube_net(rows):
    """Half petal of a five-fold tube fused along its whole height: one (radius, height) per row."""
    a = np.radians([0.0, 36.0])
    return np.array([[(r * np.cos(t), y, r * np.sin(t)) for t in a] for r, y in rows])


def style_net(rows):
    """Half petal of the two-fold style: the midline point (x, y, 0), the boundary point (xb, y, zb)."""
    return np.array([[(x, y, 0.0), (xb, y, zb)] for x, xb, zb, y in rows])


# ---- ray floret: the ligule's midrib (x outward, y up), half width per row, cup ----------------------
RAY_NU, RAY_NV = 5, 8
U_RAY = np.linspace(0.0, 1.0, RAY_NU)
# how far each column of the tip row falls short of the midline's tip, as a fraction of the tip
# row's half width: the middle tooth (u = 0), a notch (0.25), a lateral tooth (0.5), the edge
TIP_RECESS = np.array([0.0, 0.10, 0.02, 0.30, 0.70])
BASE_R = 0.12
RAY = {
    "bud": dict(time=0.0,
                mid=[(0.06, 0.00), (0.08, 0.14), (0.09, 0.30), (0.09, 0.46), (0.08, 0.62), (0.06, 0.76),
                     (0.03, 0.88), (0.00, 0.96)],
                half=[0.05, 0.08, 0.11, 0.13, 0.14, 0.13, 0.11, 0.08],
                cup=0.9),
    "mid": dict(time=0.45,
                mid=[(0.06, 0.00), (0.14, 0.28), (0.34, 0.62), (0.66, 0.92), (1.05, 1.14), (1.46, 1.28),
                     (1.86, 1.36), (2.20, 1.38)],
                half=[0.06, 0.12, 0.21, 0.29, 0.33, 0.34, 0.31, 0.24],
                cup=0.35),
    "open": dict(time=1.0,
                 mid=[(0.06, 0.00), (0.22, 0.30), (0.60, 0.56), (1.30, 0.70), (2.10, 0.74), (2.95, 0.70),
                      (3.80, 0.58), (4.50, 0.42)],
                 half=[0.07, 0.18, 0.36, 0.48, 0.52, 0.50, 0.43, 0.30],
                 cup=0.10),
}

# ---- involucral bract -------------------------------------------------------------------------------
BRACT_NU, BRACT_NV = 4, 6
U_BRACT = np.linspace(0.0, 1.0, BRACT_NU)
BRACT = {
    # midrib (x outward, y up off the receptacle): erect and clasping the young head in bud,
    # reflexed outward over the rim and down when open, under the ray florets
    "bud": dict(time=0.0,
                mid=[(0.00, 0.00), (0.02, 0.26), (0.00, 0.52), (-0.05, 0.78), (-0.12, 1.02), (-0.20, 1.22)],
                half=[0.10, 0.22, 0.26, 0.21, 0.11, 0.02],
                cup=0.6),
    "open": dict(time=1.0,
                 mid=[(0.00, 0.00), (0.16, 0.14), (0.44, 0.20), (0.76, 0.12), (1.04, -0.06), (1.26, -0.28)],
                 half=[0.12, 0.30, 0.34, 0.26, 0.12, 0.02],
                 cup=0.25),
}


def write(out: Path, quality: str) -> None:
    out.mkdir(parents=True, exist_ok=True)
    res = RES[quality]
    head = "# sunflower {what}, key pose '{key}' ({q}); written by make_keys.py\nfloret 1\nname: {name}\ntime: {t}\n\n"
    for key, p in DISK.items():
        text = head.format(what="disk floret", key=key, q=quality, name="disk", t=p["time"])
        text += organ("corolla", 1, "3 3", f"{DISK_NU} {DISK_NV}", "5 0", DISK_FUSED, res["corolla"],
                      ring_net(p["r"], p["y"], p["half"], DISK_NU)) + "\n"
        text += organ("anthers", 2, "1 1", "2 3", "5 0", 3, res["anthers"], tube_net(p["anthers"])) + "\n"
        text += organ("pistil", 3, "1 2", f"2 {STYLE_NV}", "2 0", STYLE_FUSED, res["pistil"], style_net(p["pistil"]))
        (out / f"disk_{key}.floret").write_text(text)
    for key, p in RAY.items():
        text = head.format(what="ray floret", key=key, q=quality, name="ray", t=p["time"])
        text += organ("ligule", 0, "2 3", f"{RAY_NU} {RAY_NV}", "1 0", 0, res["ligule"],
                      blade_net(p, RAY_NU, RAY_NV, U_RAY, TIP_RECESS, BASE_R))
        (out / f"ray_{key}.floret").write_text(text)
    for key, p in BRACT.items():
        text = head.format(what="involucral bract", key=key, q=quality, name="bract", t=p["time"])
        text += organ("bract", 4, "2 3", f"{BRACT_NU} {BRACT_NV}", "1 0", 0, res["bract"],
                      blade_net(p, BRACT_NU, BRACT_NV, U_BRACT))
        (out / f"bract_{key}.floret").write_text(text)


if __name__ == "__main__":
    root = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE
    for q in RES:
        write(root / q, q)
