"""Write the gaillardia key poses (disk_*, ray_*, bract_* .floret) from a few numbers per pose.

The .floret files under draft/ and final/ are the pipeline's inputs and are committed; this script
documents how their control points were laid out and regenerates them after a change of the
numbers below (``python make_keys.py`` in this folder; ``python make_keys.py OUT_DIR`` writes both
sets under OUT_DIR, which the tests use to check that the committed files are up to date). The two
sets differ only in their polygonization (each organ's ``lambda:`` and ``eta:``), so a draft and a
final floret have the same shape. See README.md.

Units: a floret model of unit diameter fills its primordium's disc (formats/phyllotaxis.md), so
the numbers are in disc diameters; local +Y is the floret axis (the receptacle's normal), +X
points away from the head centre along the receptacle's meridian.

- **Ray floret** of *Gaillardia x grandiflora* 'Oranges and Lemons' (thesis ch. 9: "In the variety
  shown, ray florets are tubular"): the ligule is rolled into a trumpet, open in a narrow slit
  along its upper side, its mouth flared into three shallow lobes. One bilateral organ per colour
  (symmetry 1): ``tube`` (orange-red) and ``limb`` (the flared, lobed mouth, yellow). Row j of
  either is an arc of 2 x ARC_HALF = 300 degrees round the tube's centre line: the half petal's
  columns go from the midline at the bottom of the tube (column 0) round the +Z side to the edge
  of the slit, and the bilateral mirror gives the -Z half. The tube's base row is a ring on the
  receptacle (y = 0: tools/species/weights.py fixes the lowest vertices), widened sideways
  (FOOT, less and less up to FOOT_REACH of the tube's length: the ring of rays' tubes hides the
  receptacle between their feet from above); a third organ, ``floor`` (orange-red too), closes
  the tube at its base (the top of the ovary: a flat half ring at y = 0, INSET inside the base
  ring, fixed with it), so the receptacle does not show down the tube through its slit; the tube
  widens toward its mouth (a trumpet). The limb's base ring is
  tucked into the tube's mouth, INSET inside its wall and TUCK behind its rim, and flares beyond
  it: no gap shows between the colours from any side, yet the two organs never touch (fccompose's
  exact test counts touching as intersecting); the limb is not fixed: it moves with the tube's
  animation. Nine key poses (``bud``, ``s125``, ``early``, ``s375``, ``mid``, ``s625``,
  ``late``, ``s875``, ``open``) of one development ``ray_pose(s)`` at key times sqrt(s)
  (ray_time: slow while the head is young): short and erect in bud, the tube lengthening and
  bending outward until it lies outward (+X), rising a little, the mouth flaring. floret-animate
  blends a limb's base points linearly but the tube's end along its intrinsic (arc-length
  keeping) path; nine poses keep the limb clear of the tube between them (five did not; the
  tests check every template frame).
- **Disk floret** (the sunflower's design, pipelines/sunflower/make_keys.py): organ ``corolla``
  (five-fold, bilateral half petal 3 columns x 7 rows, fused to the last row), ``anthers`` (the
  anther tube, a five-fold closed cylinder) and ``pistil``, plumper than the sunflower's so the
  corollas close over the receptacle; ``bud`` (a closed barrel), ``hold`` (the bud held to a
  quarter of the floret's window: the inner florets stay in bud longer, the phase effect), ``open``
  (a tube with five short spreading lobes, the anthers risen above them), ``late`` (the pistil
  risen above the anthers).
- **Involucral bract** (phyllary; ch. 9: "specialized leaves that surround the head and protect
  it in its early development"; the sunflower's design, narrower): organ ``bract``, a broad-based
  lanceolate blade with an acuminate tip; ``bud`` erect and incurved over the young head, held
  (``closed``) to 0.4 of the bract's window; ``open`` spreading
  outward over the rim (on the domed receptacle that points it down), under the ray florets.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from inflo.tools.species.keys import blade_net, cylinder_net, fmt_rows, organ, ring_net  # noqa: F401

HERE = Path(__file__).resolve().parent

# polygonization per quality: (lambda, eta) of each organ; a .func name is written as is (relative
# to the key pose's folder). The corolla's eta falls to 1 vertex at the lobe tips (lobe_eta.func)
# and the bract's at its acuminate tip (bract_eta_*.func; formats/fcc.md "Mesh quality matters").
# The corolla keeps 3 vertices a row at both qualities: with the sunflower's final 5 (its
# lobe_eta_final.func) the rim edges of the tube, where the lobes part, were a third of a median
# edge and this head's crowded disk florets stretched them to 1.47 x rest (a first final build,
# frames 55-71, with florets moved back by fccompose's fallback); the final's extra triangles go
# into the anther tube and the pistil (slivers of aspect 10 and 20 at the draft's rows)
# The tube and limb do not narrow to a point: a constant eta round the 300-degree arc, the rows
# about as far apart as the columns
RES = {
    "draft": {"corolla": ("0.34", "../lobe_eta.func"), "anthers": ("0.5", "3"), "pistil": ("1.0", "3"),
              "tube": ("0.1", "9"), "limb": ("0.34", "9"), "floor": ("1.0", "9"),
              "bract": ("0.34", "../bract_eta_draft.func")},
    "final": {"corolla": ("0.34", "../lobe_eta.func"), "anthers": ("0.34", "3"), "pistil": ("0.5", "3"),
              "tube": ("0.07", "9"), "limb": ("0.25", "9"), "floor": ("1.0", "9"),
              "bract": ("0.2", "../bract_eta_final.func")},
}

# ---- disk floret (the sunflower's) ----------------------------------------------------------------
DISK_NU, DISK_NV, DISK_FUSED = 3, 7, 6
DISK = {
    # corolla: radius, height and half angle (degrees; 36 = the symmetry plane) per row;
    # anthers / pistil: (radius, bottom, top) of the cylinder
    "bud": dict(time=0.0,
                r=[0.14, 0.26, 0.35, 0.39, 0.37, 0.26, 0.06],
                y=[0.00, 0.14, 0.30, 0.46, 0.60, 0.72, 0.78],
                half=[36, 36, 36, 36, 36, 34, 12],
                anthers=(0.115, 0.0, 0.40), pistil=(0.05, 0.0, 0.34)),
    # the bud pose held to a quarter of the window: the inner florets stay in bud longer, so the phase
    # effect shows as the disk crowds (check_gaillardia.py: rank correlation of height with radius)
    "hold": dict(time=0.25,
                r=[0.14, 0.26, 0.35, 0.39, 0.37, 0.26, 0.06],
                y=[0.00, 0.14, 0.30, 0.46, 0.60, 0.72, 0.78],
                half=[36, 36, 36, 36, 36, 34, 12],
                anthers=(0.115, 0.0, 0.40), pistil=(0.05, 0.0, 0.34)),
    # open and late: a wide funnel whose five broad lobes (half angle 26 degrees at the tips) spread
    # over the neighbours' (a dense disk: the receptacle no longer shows between the corollas)
    "open": dict(time=0.55,
                 r=[0.13, 0.22, 0.30, 0.38, 0.45, 0.54, 0.68],
                 y=[0.00, 0.20, 0.42, 0.62, 0.78, 0.86, 0.90],
                 half=[36, 36, 36, 36, 36, 34, 26],
                 anthers=(0.115, 0.0, 1.08), pistil=(0.05, 0.0, 0.96)),
    "late": dict(time=1.0,
                 r=[0.13, 0.22, 0.30, 0.38, 0.45, 0.55, 0.70],
                 y=[0.00, 0.20, 0.42, 0.62, 0.78, 0.85, 0.86],
                 half=[36, 36, 36, 36, 36, 34, 26],
                 anthers=(0.115, 0.0, 1.12), pistil=(0.05, 0.0, 1.32)),
}

# ---- ray floret: a tube of 300 degrees round a centre line, and its flared, three-lobed mouth -------
ARC_HALF = 150.0  # degrees from the bottom midline to the edge of the slit, each side
RAY_NU = 7  # half cross-section columns, ARC_HALF / 6 = 25 degrees apart
TUBE_NV, LIMB_NV = 8, 4
THETA = np.radians(np.linspace(0.0, ARC_HALF, RAY_NU))
# the tube is closed almost all round at its base (a fistulose ray: a corolla tube that opens in
# its slit only as it bends outward): its half arc is ARC_BASE at the base ring, falling to
# ARC_HALF by BASE_ROWS of its rows; the receptacle inside the base ring no longer shows through
# the slit from above
ARC_BASE = 168.0
BASE_ROWS = 3
# the limb's base ring is tucked INSET inside the tube's wall, TUCK back from the tube's rim along the
# centre line (floret units): the yellow mouth continues the orange tube from inside it, so no
# background shows between them from any side, and the two never touch (fccompose's exact test
# counts touching as intersecting); a ray floret of the head is 0.1-0.25 scene units per floret
# unit, so INSET is 0.003-0.008 scene units: 6-15 x fccompose's spacing
INSET = 0.03
# the tube's base ring is this many times wider sideways (+-Z) than along the head's radius, and
# so, less and less, are its rows up to FOOT_REACH of its length (the lower tube flattened: the ring
# of tubes hides more of the receptacle between the rays' feet; FOOT 1.6 left 1 % less in view at
# draft, but the final build then stopped at frame 37 with contacts fccompose could not resolve,
# reaching 0.7 or 0.45 alike)
FOOT = 1.4
FOOT_REACH = 0.7
# the tube's floor (the top of the ovary, closing the tube at its base): a flat ring of
# FLOOR_ARC degrees each side of the bottom midline on the receptacle, from FLOOR_HOLE round the
# centre line to FLOOR_INSET inside the tube's base ring; from above, the receptacle no longer
# shows down the tube (through its slit where it bends outward). Like the base ring it is fixed on
# the receptacle (it is at y = 0: tools/species/weights.py), and it never touches the tube
# (FLOOR_INSET, twice the limb's INSET, leaves the tube's lowest free rows room to be pushed). The
# floor's two halves (the bilateral mirror) are not welded: at its seam on the -X side they stay
# 360 - 2 FLOOR_ARC degrees apart, at FLOOR_HOLE of the floor's radius from the centre line 0.031
# floret units when open (with a
# hole of 0.02 and 170 degrees, 0.007: the two fixed edges came within fccompose's contact
# distance of each other, colliding pairs no step could resolve, and the final build stopped)
FLOOR_ARC = 160.0
FLOOR_HOLE = 0.35
FLOOR_INSET = 0.06
TUCK = 0.08
# the mouth's three shallow lobes: how far each column of the limb's last row falls short of the
# lobes' tips, as a fraction of the limb's length: the middle lobe at the bottom (0 degrees), a
# notch (50), a lateral lobe (100) and the edge of the slit (150)
LOBE_RECESS = np.array([0.0, 0.08, 0.30, 0.14, 0.0, 0.12, 0.36])
# the development stage s of each key pose; its key time is sqrt(s) (ray_time): the ray grows
# slowly while the head is young and opens fast as the outer disk florets reach anthesis
RAY_POSES = {"bud": 0.0, "s125": 0.125, "early": 0.25, "s375": 0.375, "mid": 0.5, "s625": 0.625, "late": 0.75,
             "s875": 0.875, "open": 1.0}


def ray_time(s: float) -> float:
    """The key time (0-1 of the ray's development window) of development stage s."""
    return round(float(np.sqrt(s)), 4)


def _lerp(a, b, s):
    return a + (b - a) * s


def ray_pose(s: float) -> dict:
    """The ray floret's development at stage s in [0, 1] (0 bud, 1 open).

    The tube's length, its bend from erect (0 degrees from +Y) to lying outward (BEND degrees),
    its radius at the base and at the mouth, the limb's length and the radius of its flared mouth.
    """
    grow = s  # lengths grow linearly with the stage
    bend = 64.0 * min(1.0, s / 0.9) ** 1.2  # the tube lies outward, rising 26 degrees, when open
    return dict(length=_lerp(0.45, 1.90, grow), bend=bend,
                r_base=_lerp(0.10, 0.19, s), r_end=_lerp(0.12, 0.36, s),
                limb=_lerp(0.16, 0.60, grow), r_mouth=_lerp(0.13, 0.56, s ** 1.3),
                lobe=_lerp(0.25, 1.0, s))


def centre_line(length: float, bend: float, nv: int, extra=()):
    """Rows of the tube's centre line, evenly spaced in arc length: (nv, 2) points (x, y) and their
    headings (radians from +Y toward +X). The tube rises straight from the base, bends outward by
    ``bend`` degrees between 2 % and 45 % of its length, and runs straight on. ``extra`` arc
    lengths beyond ``length`` (the limb's rows) are returned as a second pair."""
    sig_all = np.concatenate([np.linspace(0.0, length, nv), np.asarray(extra, float)])
    fine = np.linspace(0.0, sig_all.max(), 4001)
    a, b = 0.02 * length, 0.45 * length
    w = np.clip((fine - a) / (b - a), 0.0, 1.0)
    psi = np.radians(bend) * w * w * (3.0 - 2.0 * w)
    dx = np.concatenate([[0.0], np.cumsum(0.5 * (np.sin(psi[1:]) + np.sin(psi[:-1])) * np.diff(fine))])
    dy = np.concatenate([[0.0], np.cumsum(0.5 * (np.cos(psi[1:]) + np.cos(psi[:-1])) * np.diff(fine))])
    pts = np.stack([np.interp(sig_all, fine, dx), np.interp(sig_all, fine, dy)], axis=1)
    heading = np.interp(sig_all, fine, psi)
    return pts[:nv], heading[:nv], pts[nv:], heading[nv:]


def ring_rows(centre, heading, radius, back=None, zscale=None, arc=None):
    """Half cross-sections: row j an arc of radius[j] round centre[j], perpendicular to the heading,
    column i at THETA[i] from the bottom midline toward +Z (or evenly to ``arc[j]`` degrees);
    ``back[j, i]`` moves a point back along the centre line (the lobes); ``zscale[j]`` widens row j
    sideways (+-Z: an elliptic foot)."""
    nv = len(centre)
    pts = np.zeros((nv, RAY_NU, 3))
    for j in range(nv):
        t = np.array([np.sin(heading[j]), np.cos(heading[j])])
        bottom = np.array([t[1], -t[0]])
        theta = THETA if arc is None else np.radians(np.linspace(0.0, arc[j], RAY_NU))
        for i, th in enumerate(theta):
            xy = centre[j] + radius[j] * np.cos(th) * bottom
            if back is not None:
                xy = xy - back[j, i] * t
            pts[j, i] = (xy[0], xy[1], radius[j] * np.sin(th) * (1.0 if zscale is None else zscale[j]))
    return pts


def ray_nets(s: float):
    """(tube, limb) half control nets of the ray floret at stage s."""
    p = ray_pose(s)
    length = p["length"]

    def tube_r(sig):  # the trumpet: the tube widens toward its mouth
        return p["r_base"] + (p["r_end"] - p["r_base"]) * (np.asarray(sig) / length) ** 0.5

    # the limb's rows: its base ring TUCK inside the tube's rim, INSET inside its wall; the next
    # row just past the rim at the rim's radius (the control polygon, and so the limb's surface,
    # clears the rim by about 2/3 INSET), then the flare to the lobed mouth
    limb_sig = length + p["limb"] * np.array([0.0, 0.3, 0.67, 1.0])
    limb_sig[0] = length - TUCK
    c, h, lc, lh = centre_line(length, p["bend"], TUBE_NV, limb_sig)
    # the foot: the tube's lowest rows widened sideways (FOOT x at the base ring), so the ring of
    # rays hides the receptacle between them (the nearest ray is 0.47 floret units away)
    foot = 1.0 + (FOOT - 1.0) * np.clip(1.0 - np.linspace(0.0, 1.0, TUBE_NV) / FOOT_REACH, 0.0, 1.0)
    arc = ARC_HALF + (ARC_BASE - ARC_HALF) * np.clip(1.0 - np.arange(TUBE_NV) / BASE_ROWS, 0.0, 1.0)
    tube = ring_rows(c, h, tube_r(np.linspace(0.0, length, TUBE_NV)), zscale=foot, arc=arc)
    rl = np.array([tube_r(length - TUCK) - INSET, p["r_end"],
                   p["r_end"] + 0.45 * (p["r_mouth"] - p["r_end"]), p["r_mouth"]])
    back = np.zeros((LIMB_NV, RAY_NU))
    back[-1] = LOBE_RECESS * p["lobe"] * p["limb"]
    limb = ring_rows(lc, lh, rl, back)
    return tube, limb


def floor_net(s: float):
    """The ray's floor at stage s: two rows (FLOOR_HOLE of its radius round the centre line, FLOOR_INSET inside
    the tube's base ring, widened sideways as the ring is) of a half ring of FLOOR_ARC degrees at
    y = 0."""
    r = ray_pose(s)["r_base"] - FLOOR_INSET
    hole = FLOOR_HOLE * r
    theta = np.radians(np.linspace(0.0, FLOOR_ARC, RAY_NU))
    pts = np.zeros((2, RAY_NU, 3))
    for j, (rx, rz) in enumerate(((hole, hole), (r, r * FOOT))):
        pts[j, :, 0], pts[j, :, 2] = rx * np.cos(theta), rz * np.sin(theta)
    return pts


# ---- involucral bract (the sunflower's) -------------------------------------------------------------
BRACT_NU, BRACT_NV = 4, 6
U_BRACT = np.linspace(0.0, 1.0, BRACT_NU)
BRACT = {
    # midrib (x outward, y up off the receptacle): erect and incurved over the young head in bud,
    # spreading outward over the rim when open (the receptacle's dome tilts it down), under the ray
    # florets; lanceolate, narrower than the sunflower's ovate bracts
    "bud": dict(time=0.0,
                mid=[(0.00, 0.00), (0.02, 0.26), (-0.02, 0.52), (-0.09, 0.76), (-0.19, 0.98), (-0.31, 1.16)],
                half=[0.17, 0.22, 0.22, 0.18, 0.10, 0.02],
                cup=0.6),
    # the bud pose held to 0.4 of the bract's window: the bracts enclose the young head and spread
    # as it opens
    "closed": dict(time=0.4,
                   mid=[(0.00, 0.00), (0.02, 0.26), (-0.02, 0.52), (-0.09, 0.76), (-0.19, 0.98), (-0.31, 1.16)],
                   half=[0.17, 0.22, 0.22, 0.18, 0.10, 0.02],
                   cup=0.6),
    # broad-based (ovate-lanceolate): the two series of bracts hide the receptacle's rim between
    # the ray florets' feet (a bract's nearest neighbour is 0.48 floret units away)
    "open": dict(time=1.0,
                 mid=[(0.00, 0.00), (0.16, 0.16), (0.44, 0.26), (0.76, 0.24), (1.04, 0.14), (1.28, 0.00)],
                 half=[0.20, 0.27, 0.27, 0.21, 0.12, 0.02],
                 cup=0.25),
}


# material ids (colors.toml)
M_TUBE, M_COROLLA, M_ANTHERS, M_PISTIL, M_BRACT, M_LIMB = 0, 1, 2, 3, 4, 6


def write(out: Path, quality: str) -> None:
    out.mkdir(parents=True, exist_ok=True)
    res = RES[quality]
    head = "# gaillardia {what}, key pose '{key}' ({q}); written by make_keys.py\nfloret 1\nname: {name}\ntime: {t}\n\n"
    for key, p in DISK.items():
        text = head.format(what="disk floret", key=key, q=quality, name="disk", t=p["time"])
        text += organ("corolla", M_COROLLA, "3 3", f"{DISK_NU} {DISK_NV}", "5 0", DISK_FUSED, res["corolla"],
                      ring_net(p["r"], p["y"], p["half"], DISK_NU)) + "\n"
        text += organ("anthers", M_ANTHERS, "1 2", "2 3", "5 0", 3, res["anthers"], cylinder_net(*p["anthers"])) + "\n"
        text += organ("pistil", M_PISTIL, "1 2", "2 3", "5 0", 3, res["pistil"], cylinder_net(*p["pistil"]))
        (out / f"disk_{key}.floret").write_text(text)
    for key, s in RAY_POSES.items():
        tube, limb = ray_nets(s)
        text = head.format(what="tubular ray floret", key=key, q=quality, name="ray", t=ray_time(s))
        text += organ("tube", M_TUBE, "3 3", f"{RAY_NU} {TUBE_NV}", "1 0", 0, res["tube"], tube) + "\n"
        text += organ("limb", M_LIMB, "3 3", f"{RAY_NU} {LIMB_NV}", "1 0", 0, res["limb"], limb) + "\n"
        text += organ("floor", M_TUBE, "1 1", f"{RAY_NU} 2", "1 0", 0, res["floor"], floor_net(s))
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
