"""The growth-map lily (Ijiri et al. 2008, sec. 6.1, figs. 1, 2, 7, table 1): its bud
meshes and its petal-grow parameter file.

Usage: python growth_keys.py -o OUT_DIR            (OUT_DIR/petal.obj, OUT_DIR/sepal.obj)
       python growth_keys.py --params -o DIR        (DIR/growth.toml; the committed copy is this folder's)

Tepals are grids of (s, t) in [0, 1]^2 -- u = s across (right = 1 seen from outside), v = t from
the base -- with alternating diagonals: petal 11 x 35 particles = 680 triangles, 1064 edges
(the paper: 388 / 685 / 1082), average edge 1.3; sepal 9 x 36 = 560 triangles (323 / 567 / 889),
average edge 1.4 (table 1). In the bud (an elongated, pointed egg round +Y) the three sepals stand
at 0, 120, 240 degrees and the three petals between them, 0.5 further in: the petals inside the
sepals (fig. 12a). Faces wind counter-clockwise seen from the axis (the inner side).
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from inflo.tools.petal_grow.bud import BudMesh, grid_bud, write_bud_obj

# (particles across, along, length, widest angular span, radial offset inwards)
SCALE = 1.2  # average edges 1.3 (petal) and 1.4 (sepal), table 1
TEPALS = {
    "petal": dict(nu=11, nv=35, length=40.0 * SCALE, span=math.radians(112.0), inset=0.55 * SCALE),
    "sepal": dict(nu=9, nv=36, length=42.0 * SCALE, span=math.radians(116.0), inset=0.0),
}
R_MAX = 6.3 * SCALE
R_BASE = 1.6 * SCALE
R_TIP = 1.8 * SCALE


def width_fraction(t):
    """Lanceolate: a narrow claw, widest at t = 0.45, broad shoulders, a pointed tip."""
    t = np.asarray(t, dtype=np.float64)
    return np.where(t <= 0.45, 0.30 + 0.70 * np.sin(np.pi * t / 0.9), 0.12 + 0.88 * np.cos(0.5 * np.pi * (t - 0.45) / 0.55) ** 0.6)


def bud_radius(t):
    """An elongated egg, pointed at the top."""
    t = np.asarray(t, dtype=np.float64)
    return R_BASE + (R_MAX - R_BASE) * np.sin(np.pi * np.clip(t, 0, 1) ** 0.75) * (1 - 0.35 * t) + (R_TIP - R_BASE) * t ** 3


def tepal(kind: str) -> BudMesh:
    p = TEPALS[kind]
    nu, nv = p["nu"], p["nv"]
    s, t = np.meshgrid(np.linspace(0, 1, nu), np.linspace(0, 1, nv))
    s, t = s.ravel(), t.ravel()
    ang = -(s - 0.5) * p["span"] * width_fraction(t)
    r = bud_radius(t) - p["inset"] * np.minimum(1.0, 4 * t + 0.3)
    x = np.stack([r * np.cos(ang), p["length"] * t, r * np.sin(ang)], axis=1)
    return grid_bud(x, s, t, nu, nv)


# Growth maps (fig. 2, sec. 6.1): three regions by uv -- the midrib (|u - 1/2| < 0.12), the lamina,
# the bottom (v < 0.08). e-growth elongates midrib and lamina equally; early (steps 1-30) e_in is
# much larger than e on the midrib and slightly larger on the lamina (the midrib reflexes and pulls
# the lamina); late (40-100) e_in = e everywhere (the warping stops; the shape still settles into
# the rest angles gathered early, PBD converging over the following keyframes); blended over 30-40.
# w-growth rises on the lamina and w_in more (0.6 early, 0.05 late): the bud's curl across unrolls
# until the lamina's cross-section is flat. Once open (late) the whole tepal widens, the lamina
# three times as fast as the midrib (w 1.0 + 2.0 lamina): the tepals open broad, as in fig. 1
# (length over developed width 3.0 sepals, 3.3 petals at keyframe 100; with the early w kept they
# stayed straps of 4.4 / 4.8 that twisted 37 degrees along their tips). The midrib is harder
# (stretch and bend maps).
MIDRIB = "(1 - smoothstep(0.1, 0.22, abs(u - 0.5)))"
LAMINA = f"(1 - {MIDRIB})"
BOTTOM = "smoothstep(0.04, 0.12, v)"
GROWTH = {
    "early": dict(e=f"1.0 * {BOTTOM}", w=f"(0.3 + 0.2 * {LAMINA}) * {BOTTOM}",
                  e_in=f"(1.0 + 0.4 * {MIDRIB} + 0.125 * {LAMINA}) * {BOTTOM}",
                  w_in=f"(0.3 + 0.2 * {LAMINA} + 0.6 * {LAMINA}) * {BOTTOM}"),
    "late": dict(e=f"1.0 * {BOTTOM}", w=f"(1.0 + 2.0 * {LAMINA}) * {BOTTOM}",
                 e_in=f"(1.0 + 0.0 * {LAMINA}) * {BOTTOM}",
                 w_in=f"(1.0 + 2.0 * {LAMINA} + 0.05 * {LAMINA}) * {BOTTOM}"),
}
STRETCH = f"0.7 + 0.3 * {MIDRIB}"
BEND = f"0.9 + 0.6 * {MIDRIB}"


def growth_toml(mesh_dir: str) -> str:
    out = ["# The growth-map lily (Ijiri et al. 2008, sec. 6.1, figs. 1, 2, 7, table 1): petal-grow parameters",
           "# (formats/petal_grow.md). Written by growth_keys.py --params; edit GROWTH there.", "",
           "[flower]", "keyframes = 100", "iterations = 100", "match_every = 5", "length_sweeps = 10", "base_v = 0.06",
           "collision_distance = 0.08", "# the joint angle grows by 23 degrees from step 1 to 60, then stays",
           "joint = [[1, 0.0], [60, 23.0]]"]
    for stage, g in GROWTH.items():
        out += ["", f"[growth.{stage}]", "dg = 0.003", "thickness = 0.2", "K_s = 20", "K_b = 20", 'direction = "0, 1"']
        out += [f'{k} = "{g[k]}"' for k in ("e", "w", "e_in", "w_in")]
        out += [f'stretch = "{STRETCH}"', f'bend = "{BEND}"']
    for kind, mat, layer, phase in (("sepal", "3", 1, 0), ("petal", "4", 0, 60)):
        for k in range(3):
            out += ["", "[[organ]]", f'name = "{kind}_{k}"', f'mesh = "{mesh_dir}/{kind}.obj"', f'material = "{mat}"',
                    f"rotate = {phase + 120 * k}", f"layer = {layer}",
                    'growth = [[0, "early"], [30, "early"], [40, "late"]]']
    return "\n".join(out) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", required=True, type=Path)
    ap.add_argument("--params", action="store_true", help="write DIR/growth.toml instead of the bud meshes")
    ap.add_argument("--mesh-dir", default="../../build/lily/growth_bud", help="the bud folder as growth.toml names it")
    a = ap.parse_args()
    a.output.mkdir(parents=True, exist_ok=True)
    if a.params:
        (a.output / "growth.toml").write_text(growth_toml(a.mesh_dir))
        return
    for kind in TEPALS:
        m = tepal(kind)
        write_bud_obj(a.output / f"{kind}.obj", m, header=f"lily {kind} bud ({len(m.vertices)} particles, "
                      f"{len(m.faces)} triangles); written by pipelines/lily/growth_keys.py")


if __name__ == "__main__":
    main()
