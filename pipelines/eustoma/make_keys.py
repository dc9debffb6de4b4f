"""Write the Eustoma bud (Ijiri et al. 2008, sec. 6.2, fig. 12b): one petal mesh with uv
that ``eustoma_*.toml`` place five times round the flower axis (72 degrees apart).

Usage: python make_keys.py --quality draft|final -o OUT_DIR   (writes OUT_DIR/petal.obj)

The petal is a grid of (s, t) in [0, 1]^2 -- u = s across (0 left, 1 right seen from outside, tip
up), v = t from the base to the tip -- with alternating diagonals (near-isotropic triangles), final
13 x 20 particles = 456 triangles (the paper: 261 particles, 458 triangles, 718 edges, average
edge length 2.0, table 1), draft 7 x 11 = 120 triangles. In the bud the petal wraps round the axis
(cylindrical coordinates about +Y): angle ``phi - (s - 1/2) A(t)``, radius ``R(t) + kappa (angle - phi)``,
height ``H t``: the radius falls towards the right side, so each petal's right side lies beneath
its right-hand neighbour's left side (contorted aestivation, fig. 12b), 72 deg x kappa apart.
Faces wind counter-clockwise seen from the inner (adaxial) side, as petal-grow expects.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from inflo.tools.petal_grow.bud import BudMesh, grid_bud, write_bud_obj

GRID = {"final": (13, 20), "draft": (9, 14)}
SCALE = 1.2       # average edge length 2.0 at final (table 1)
H = 34.0 * SCALE  # bud height
R_MAX = 9.0 * SCALE   # bud radius at its widest
R_BASE = 2.2 * SCALE  # radius of the receptacle where the petals stand
R_TIP = 2.6 * SCALE
A_MAX = math.radians(128.0)   # angular span of a petal at its widest (> 72: neighbours overlap)
KAPPA = 0.32 * SCALE  # radius drop per radian towards the right side (layer gap 72 deg x KAPPA = 0.48)


def width_fraction(t):
    """Petal width over its widest, from the claw (0.55: the claws overlap round the base, as the
    short corolla tube closes it) to the widest at t = 0.7 and the round tip."""
    t = np.asarray(t, dtype=np.float64)
    low = 0.55 + 0.45 * np.sin(np.pi * np.minimum(t, 0.7) / 1.4)
    high = 1.0 - 0.55 * ((t - 0.7) / 0.3) ** 2
    return np.where(t <= 0.7, low, high)


def bud_radius(t):
    """Bud radius at height fraction t: an elongated egg, narrow at the receptacle and the tip."""
    t = np.asarray(t, dtype=np.float64)
    bulge = np.sin(np.pi * np.clip(t, 0, 1) ** 0.85)
    return R_BASE + (R_MAX - R_BASE) * bulge * (1 - 0.25 * t) + (R_TIP - R_BASE) * t * (1 - bulge)


def petal(quality: str) -> BudMesh:
    nu, nv = GRID[quality]
    s, t = np.meshgrid(np.linspace(0, 1, nu), np.linspace(0, 1, nv))
    s, t = s.ravel(), t.ravel()
    ang = -(s - 0.5) * A_MAX * width_fraction(t)
    r = bud_radius(t) + KAPPA * ang
    x = np.stack([r * np.cos(ang), H * t, r * np.sin(ang)], axis=1)
    return grid_bud(x, s, t, nu, nv)


# The three cultivars (sec. 6.2, fig. 16): growth maps as functions of (u, v), an early set (steps
# 0-40) and a late set (60 on), blended in between. D = e_in - e bends the petal lengthwise (> 0:
# outwards), w_in - w across (> 0: flattens its bud curl). Same stretch and bend maps for all three
# (the lower petal is harder, sec. 5.1).
STRETCH = "1"
BEND = "1 - 0.5 * v"
CULTIVARS = {
    # bell: little change early; later the inner/upper region expands most and reflexes (the lower
    # inner side a little more than the outer: the tube widens upwards)
    "mellow_yellow": {
        "title": "Mellow Yellow (bell)",
        "early": dict(direction="0, 1", e="0.6", w="1.2", e_in="0.6 + 0.017", w_in="1.2 + 0.042"),
        "late": dict(direction="0, 1", e="0.8", w="1.8",
                     e_in="0.8 + 0.25 * smoothstep(0.55, 0.9, v) + 0.03 * (1 - smoothstep(0.2, 0.45, v))",
                     w_in="1.8 + 0.017 + 0.125 * smoothstep(0.5, 0.85, v)"),
    },
    # funnel: uniform rates, greater early; the veins fan out from the base (another venation)
    "maite_lady": {
        "title": "Maite Lady (funnel)",
        "early": dict(direction="(u - 0.5) * 0.8, 1", e="1.2", w="1.5", e_in="1.2 + 0.028", w_in="1.5 + 0.075"),
        "late": dict(direction="(u - 0.5) * 0.8, 1", e="0.6", w="0.8", e_in="0.6", w_in="0.8 + 0.008"),
    },
    # shallow ball: uniform; the inner lower/middle regions elongate slightly more
    "pinocchio": {
        "title": "Pinocchio (shallow ball)",
        "early": dict(direction="0, 1", e="1.0", w="1.3",
                      e_in="1.0 + 0.037 * (1 - smoothstep(0.25, 0.45, v)) - 0.042 * smoothstep(0.5, 0.9, v)",
                      w_in="1.3 + 0.025"),
        "late": dict(direction="0, 1", e="1.0", w="1.25",
                     e_in="1.0 + 0.008 * (1 - smoothstep(0.25, 0.45, v))",
                     w_in="1.25 + 0.008"),
    },
}


def cultivar_toml(name: str, mesh: str) -> str:
    c = CULTIVARS[name]
    out = [f"# Eustoma grandiflorum '{c['title']}' (Ijiri et al. 2008, sec. 6.2, figs. 16, 17): petal-grow",
           "# parameters (formats/petal_grow.md). Written by make_keys.py --params; edit CULTIVARS there.", "",
           "[flower]", "keyframes = 100", "iterations = 40", "match_every = 5", "base_v = 0.1",
           "collision_distance = 0.05", "# the joint angle grows by 15 degrees from step 1 to 50",
           "joint = [[1, 0.0], [50, 15.0]]"]
    for stage in ("early", "late"):
        g = c[stage]
        out += ["", f"[growth.{stage}]", "dg = 0.003", "thickness = 0.1", "K_s = 10", "K_b = 10"]
        out += [f'{k} = "{g[k]}"' for k in ("direction", "e", "w", "e_in", "w_in")]
        out += [f'stretch = "{STRETCH}"', f'bend = "{BEND}"']
    for k in range(5):
        # the cultivar's name as the petals' material: its colour in colors.toml (the USD file)
        out += ["", "[[organ]]", f'name = "petal_{k}"', f'mesh = "{mesh}"', f'material = "{name}"',
                f"rotate = {72 * k}", "# contorted: its right side lies beneath the next petal's left side",
                f'beneath = "petal_{(k + 1) % 5}"', 'growth = [[0, "early"], [40, "early"], [60, "late"]]']
    return "\n".join(out) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quality", choices=sorted(GRID), default="draft")
    ap.add_argument("-o", "--output", required=True, type=Path)
    ap.add_argument("--params", action="store_true",
                    help="also write the cultivars' parameter files OUT_DIR/<cultivar>.toml")
    ap.add_argument("--mesh", default="petal.obj", help="the bud mesh as the parameter files name it")
    a = ap.parse_args()
    a.output.mkdir(parents=True, exist_ok=True)
    if a.params:
        for name in CULTIVARS:
            (a.output / f"{name}.toml").write_text(cultivar_toml(name, a.mesh))
        return
    mesh = petal(a.quality)
    write_bud_obj(a.output / "petal.obj", mesh,
                  header=f"Eustoma bud petal ({a.quality}: {len(mesh.vertices)} particles, {len(mesh.faces)} "
                  "triangles); written by pipelines/eustoma/make_keys.py")


if __name__ == "__main__":
    main()
