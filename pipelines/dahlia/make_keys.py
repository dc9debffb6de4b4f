"""Write the dahlia key poses (ray_*, bract_* .floret) from a few numbers per pose.

The .floret files under draft/ and final/ are the pipeline's inputs and are committed; this script
documents how their control points were laid out and regenerates them after a change of the
numbers below (``python make_keys.py`` in this folder; ``python make_keys.py OUT_DIR`` writes both
sets under OUT_DIR, which the tests use to check that the committed files are up to date). The two
sets differ only in their polygonization (each organ's ``lambda:`` and ``eta:``).

Units: a floret model of unit diameter fills its primordium's disc (formats/phyllotaxis.md), so
the numbers are in disc diameters; local +Y is the floret axis (the receptacle's normal), +X
points away from the head's top along the receptacle's meridian (down the ball's side).

- **Ray floret** of the ball dahlia 'Jomanda' (thesis ch. 9, fig. 9.2: "incurved, almost tubular
  ray florets that touch each other and accommodate their shape to the presence of their
  neighbors"): one ligule whose margins are rolled inward into a tube, open in a slit along its
  inner (adaxial) side, the tube widening into a cup whose rim is cut obliquely (the outer,
  abaxial side longest): the cup's mouth faces up the ball, the "honeycomb" of a ball dahlia.
  One bilateral organ (symmetry 1) ``ligule``: row j is an arc of 2 x ``arc`` degrees round the
  tube's centre line, column 0 on the outer midline, the last column at the edge of the roll; the
  mirror gives the other half. The centre line rises along the floret axis, leans outward by
  ``lean`` degrees and curves back in by ``incurve`` near the tip (incurved). Five key poses
  ``bud`` .. ``open`` of one development ``ray_pose(s)``: a short, tightly rolled, erect bud; the
  ligule lengthening, leaning out, its mouth widening into the cup.
- **Involucral bract** (the gaillardia's lanceolate bract, shorter and broader): organ ``bract``;
  ``bud`` erect and incurved over the young head, ``open`` spreading (at the bottom of the ball,
  where the receptacle's normal points down, it hangs round the stem, clear of the receptacle).
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from inflo.tools.species.keys import blade_net, organ

HERE = Path(__file__).resolve().parent

# polygonization per quality: (lambda, eta) of each organ; the ligule keeps a constant eta round
# its arc (it does not narrow to a point), the bract's eta falls to 1 vertex at its tip
RES = {
    "draft": {"ligule": ("../ray_lambda_draft.func", "9"), "bract": ("0.34", "../bract_eta_draft.func")},
    "final": {"ligule": ("../ray_lambda_final.func", "9"), "bract": ("0.2", "../bract_eta_final.func")},
}

# ---- ray floret: a rolled, incurved ligule with a rounded tip ---------------------------------------
RAY_NU, RAY_NV = 6, 10
RAY_POSES = {"bud": 0.0, "early": 0.25, "mid": 0.5, "late": 0.75, "open": 1.0}
# the ligule's rounded tip: seen from its outer side the blade ends in half an ellipse, TIP_DEPTH
# times the cup's radius high (its rows' arcs shrink from the roll's to 90 degrees over the radius
# below it, then as arccos toward the tip), blunt: the tip row keeps TIP_END degrees of the roll.
# So the rolled margins draw back into a rounded lip, no point on an oblique rim
TIP_DEPTH, TIP_END = 0.7, 35.0
# control rows bunch toward the tip (the rounded lip needs them): spacing 1 + ROW_BUNCH at the
# base, 1 - ROW_BUNCH at the tip, times the mean
ROW_BUNCH = 0.5


def _lerp(a, b, s):
    return a + (b - a) * s


def ray_pose(s: float) -> dict:
    """The ray floret's development at stage s in [0, 1] (0 bud, 1 open): its length, lean and
    incurve (degrees), the tube's radius at the base and the cup's at the mouth, and the half
    arc of the roll (degrees; 180 would close the tube), the half arc left at the tip (tip_arc).
    The open ligule leans out and curls back over its own mouth (incurve 55 degrees): seen from
    outside the ball its rounded back, overlapping the next like a scale."""
    return dict(length=_lerp(0.70, 3.50, s), lean=_lerp(0.0, 15.0, s), incurve=_lerp(10.0, 55.0, s),
                r_base=_lerp(0.15, 0.32, s), r_mouth=_lerp(0.15, 1.60, s ** 1.2),
                arc=_lerp(165.0, 150.0, s), tip_end=TIP_END)


def centre_line(length: float, lean: float, incurve: float, nv: int):
    """Rows of the ligule's centre line, spaced in arc length: (nv, 2) points (x, y) and their
    headings (radians from +Y toward +X), closer together toward the tip (ROW_BUNCH). The
    heading rises to ``lean`` by 40 % of the length and falls back by ``incurve`` over the last
    half."""
    x = np.linspace(0.0, 1.0, nv)
    sig = length * (x + ROW_BUNCH * x * (1.0 - x))  # as _row_sig
    fine = np.linspace(0.0, length, 4001)
    w1 = np.clip(fine / (0.4 * length), 0.0, 1.0)
    w2 = np.clip((fine - 0.5 * length) / (0.5 * length), 0.0, 1.0)
    psi = np.radians(lean) * w1 * w1 * (3.0 - 2.0 * w1) - np.radians(incurve) * w2 * w2
    dx = np.concatenate([[0.0], np.cumsum(0.5 * (np.sin(psi[1:]) + np.sin(psi[:-1])) * np.diff(fine))])
    dy = np.concatenate([[0.0], np.cumsum(0.5 * (np.cos(psi[1:]) + np.cos(psi[:-1])) * np.diff(fine))])
    pts = np.stack([np.interp(sig, fine, dx), np.interp(sig, fine, dy)], axis=1)
    return pts, np.interp(sig, fine, psi)


def _row_sig(length: float) -> np.ndarray:
    x = np.linspace(0.0, 1.0, RAY_NV)
    return length * (x + ROW_BUNCH * x * (1.0 - x))


def tip_arc(sig: np.ndarray, length: float, radius: float, arc: float, tip_end: float = TIP_END) -> np.ndarray:
    """Half arc (degrees) of the rows at arc lengths ``sig`` along a ligule of this length whose
    cup has this radius: ``arc`` up to a radius below the rounded tip, 90 where it begins
    (smoothstep between), then arccos of the way across its depth (TIP_DEPTH radii), at least
    ``tip_end`` (TIP_END; 0 closes the tip: a bud's)."""
    depth = TIP_DEPTH * radius
    u = (sig - (length - depth)) / depth
    w = np.clip(-u * depth / radius, 0.0, 1.0)
    below = 90.0 + (arc - 90.0) * w * w * (3.0 - 2.0 * w)
    return np.where(u < 0.0, below, np.maximum(tip_end, np.degrees(np.arccos(np.clip(u, 0.0, 1.0)))))


def ray_net(s: float) -> np.ndarray:
    """Half control net of the ligule at stage s: (RAY_NV, RAY_NU, 3). Row j is an arc round the
    centre line's point, its angle the roll's, drawn back at the tip (tip_arc)."""
    p = ray_pose(s)
    c, h = centre_line(p["length"], p["lean"], p["incurve"], RAY_NV)
    f = np.linspace(0.0, 1.0, RAY_NV)
    radius = p["r_base"] + (p["r_mouth"] - p["r_base"]) * f ** 1.4
    half = tip_arc(_row_sig(p["length"]), p["length"], radius[-1], p["arc"], p["tip_end"])
    pts = np.zeros((RAY_NV, RAY_NU, 3))
    for j in range(RAY_NV):
        t = np.array([np.sin(h[j]), np.cos(h[j])])
        outer = np.array([t[1], -t[0]])  # the abaxial side: +X for an erect ligule
        theta = np.radians(np.linspace(0.0, half[j], RAY_NU))
        for i, th in enumerate(theta):
            xy = c[j] + radius[j] * np.cos(th) * outer
            pts[j, i] = (xy[0], xy[1], radius[j] * np.sin(th))
    return pts


# ---- involucral bract ----------------------------------------------------------------------------------
BRACT_NU, BRACT_NV = 4, 6
U_BRACT = np.linspace(0.0, 1.0, BRACT_NU)
BRACT = {
    "bud": dict(time=0.0,
                mid=[(0.00, 0.00), (0.02, 0.22), (-0.02, 0.44), (-0.08, 0.64), (-0.16, 0.82), (-0.26, 0.96)],
                half=[0.10, 0.20, 0.24, 0.20, 0.11, 0.02],
                cup=0.6),
    "open": dict(time=1.0,
                 mid=[(0.00, 0.00), (0.12, 0.20), (0.30, 0.40), (0.50, 0.57), (0.72, 0.71), (0.94, 0.82)],
                 half=[0.11, 0.23, 0.27, 0.22, 0.12, 0.02],
                 cup=0.25),
}

# material ids (colors.toml)
M_LIGULE, M_BRACT = 0, 4


def write(out: Path, quality: str) -> None:
    out.mkdir(parents=True, exist_ok=True)
    res = RES[quality]
    head = "# dahlia {what}, key pose '{key}' ({q}); written by make_keys.py\nfloret 1\nname: {name}\ntime: {t}\n\n"
    for key, s in RAY_POSES.items():
        text = head.format(what="incurved ray floret", key=key, q=quality, name="ray", t=s)
        text += organ("ligule", M_LIGULE, "3 3", f"{RAY_NU} {RAY_NV}", "1 0", 0, res["ligule"], ray_net(s))
        (out / f"ray_{key}.floret").write_text(text)
    for key, p in BRACT.items():
        text = head.format(what="involucral bract", key=key, q=quality, name="bract", t=p["time"])
        text += organ("bract", M_BRACT, "2 3", f"{BRACT_NU} {BRACT_NV}", "1 0", 0, res["bract"],
                      blade_net(p, BRACT_NU, BRACT_NV, U_BRACT))
        (out / f"bract_{key}.floret").write_text(text)


if __name__ == "__main__":
    root = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE
    for q in RES:
        write(root / q, q)
