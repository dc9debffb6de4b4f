"""An Eustoma plant (issue 46, after Ijiri et al. 2008, fig. 15): a branched stem with opposite
leaves carrying five flowers of one cultivar, each offset in age, on one timeline (the `plant`
target of the Makefile; `make eustoma-plant`).

Usage: python plant.py EUSTOMA_BUILD OUT_DIR [--cultivar NAME]
       (EUSTOMA_BUILD = build/eustoma, OUT_DIR = build/eustoma_plant, NAME = mellow_yellow)

Nothing is grown again: a flower of age offset k shows the built cultivar's frame clamp(f - k) at
plant frame f (petals from ``<cultivar>/``, calyx, pistil and stamens from ``column_obj/``), moved
rigidly onto the end of its branch. Eustoma grandiflorum branches in its upper part, each branch
ending in a long-stalked flower, the terminal flower on the main stem first (a cyme); its leaves
are opposite and decussate, sessile, ovate-oblong, glaucous. Units are the build's (1 unit = 1 mm:
an open flower is 6-9 cm across); +Y is up. The shared meshes, placing and check are
:mod:`inflo.tools.plant`.

Writes under OUT_DIR: ``body.obj`` (groups ``stem``, ``leaf_NN``, ``pedicel_K``: the branch of
flower K; materials ``mtl20`` stem, ``mtl21`` leaves, ``mtl22`` branches), ``flower_K/frame_NNNN.obj``
(K = 1 terminal ... 5; petals, group ``petals``, and calyx with column, group ``column``, in plant
coordinates) and ``plant.toml`` (the layout, read by ``python -m inflo.tools.plant.check``).
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from inflo.formats.obj import list_obj_sequence, read_obj, write_obj
from inflo.tools import plant as P

FRAMES = 100
STEM_HEIGHT = 400.0            # the apex, where the terminal flower's stalk starts (mm)
STEM_R0, STEM_R1 = 3.0, 2.0
STEM_BEND = 12.0
STEM_SIDES, STEM_RINGS = 12, 48

# opposite, decussate leaves: pairs at these heights, each pair turned 90 degrees from the last
LEAF_PAIRS = (30.0, 70.0, 110.0, 150.0, 190.0, 230.0, 270.0)
LEAF_ROWS, LEAF_ACROSS = 12, 7

# the flowers: terminal first (the oldest), then the branches from the top down, pairs opposite
# (age offset in frames, node height, azimuth deg, reach, rise, axis tilt deg, branch's starting
# angle from vertical deg, spin deg)
FLOWERS = (
    dict(offset=0, node=400.0, azimuth=0.0, reach=0.0, rise=70.0, tilt=0.0, start=0.0, spin=0.0),
    dict(offset=20, node=340.0, azimuth=90.0, reach=85.0, rise=95.0, tilt=30.0, start=35.0, spin=18.0),
    dict(offset=40, node=340.0, azimuth=270.0, reach=85.0, rise=75.0, tilt=30.0, start=35.0, spin=36.0),
    dict(offset=60, node=300.0, azimuth=0.0, reach=100.0, rise=85.0, tilt=38.0, start=40.0, spin=9.0),
    dict(offset=80, node=300.0, azimuth=180.0, reach=100.0, rise=70.0, tilt=38.0, start=40.0, spin=27.0),
)
PEDICEL_R0, PEDICEL_R1 = 1.1, 0.8
# a pair's branches leave the stem from opposite sides: each starts this far (x the stem's radius)
# off its axis, inside it, so the two do not meet
PEDICEL_OFF = 0.5
PEDICEL_END = -5.0      # the branch ends on the flower axis this far below the receptacle (inside its stub)
PEDICEL_SIDES, PEDICEL_RINGS = 10, 32

# stage names by the cultivar's 0-based frame (mellow_yellow: closed to frame 35, open from 65)
STAGES = ((0, "bud"), (35, "opening"), (65, "open"))
MTL_STEM, MTL_LEAF, MTL_PEDICEL = "mtl20", "mtl21", "mtl22"


def stem_point(y):
    y = np.asarray(y, dtype=np.float64)
    return np.stack([STEM_BEND * (y / STEM_HEIGHT) ** 2, y, np.zeros_like(y)], axis=-1)


def stem_radius(y):
    return STEM_R0 + (STEM_R1 - STEM_R0) * np.asarray(y, dtype=np.float64) / STEM_HEIGHT


def make_stem():
    y = STEM_HEIGHT * np.arange(STEM_RINGS) / (STEM_RINGS - 1)
    return P.tube(stem_point(y), stem_radius(y), STEM_SIDES, cap0=stem_point(0.0), cap1=stem_point(STEM_HEIGHT + 1.0))


def make_leaves():
    out = []
    for i, y in enumerate(LEAF_PAIRS):
        t = i / (len(LEAF_PAIRS) - 1)
        length = 45.0 + 25.0 * math.sin(math.pi * min(1.0, 0.3 + 0.8 * t))     # 45-70 mm
        for side in (0, 1):
            psi = math.radians(90.0 * i + 180.0 * side + 45.0)
            e_out = np.array([math.cos(psi), 0.0, math.sin(psi)])
            base = stem_point(y) + 0.7 * stem_radius(y) * e_out
            out.append(P.leaf_mesh(base, e_out, length, 0.26 * length, 45.0 - 10.0 * t, curl=35.0, fold=0.25,
                                   rows=LEAF_ROWS, across=LEAF_ACROSS, widest=0.35, base_width=0.35,
                                   tip_power=0.7))
    return out


def flower_frame(fl: dict):
    phi = math.radians(fl["azimuth"])
    e_r = np.array([math.cos(phi), 0.0, math.sin(phi)])
    origin = stem_point(fl["node"]) + fl["reach"] * e_r + fl["rise"] * np.array([0.0, 1.0, 0.0])
    return origin, P.flower_basis(fl["azimuth"], fl["tilt"], fl["spin"])


def make_pedicel(fl: dict):
    origin, basis = flower_frame(fl)
    axis = basis[1]
    phi, g = math.radians(fl["azimuth"]), math.radians(fl["start"])
    e_r = np.array([math.cos(phi), 0.0, math.sin(phi)])
    p0 = stem_point(fl["node"]) + PEDICEL_OFF * stem_radius(fl["node"]) * e_r
    d0 = np.array([math.sin(g) * math.cos(phi), math.cos(g), math.sin(g) * math.sin(phi)])
    p3 = origin + PEDICEL_END * axis
    span = float(np.sqrt(np.sum((p3 - p0) ** 2)))
    pts = P.bezier(p0, p0 + 0.4 * span * d0, p3 - 0.4 * span * axis, p3, PEDICEL_RINGS)
    r = PEDICEL_R0 + (PEDICEL_R1 - PEDICEL_R0) * (np.arange(PEDICEL_RINGS) / (PEDICEL_RINGS - 1))
    return P.tube(pts, r, PEDICEL_SIDES, cap0=p0, cap1=p3 + 0.5 * axis)


def main(build: Path, out: Path, cultivar: str = "mellow_yellow") -> int:
    petals = list_obj_sequence(build / cultivar)
    column = list_obj_sequence(build / "column_obj")
    if len(petals) != FRAMES or len(column) != FRAMES:
        print(f"plant.py: {build} has {len(petals)} {cultivar} and {len(column)} column frames, "
              f"expected {FRAMES} (run make eustoma first)", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    frames = [flower_frame(fl) for fl in FLOWERS]
    parts = [("stem", MTL_STEM, make_stem())]
    leaves = make_leaves()
    parts += [(f"leaf_{j + 1:02d}", MTL_LEAF, lf) for j, lf in enumerate(leaves)]
    parts += [(f"pedicel_{k + 1}", MTL_PEDICEL, make_pedicel(fl)) for k, fl in enumerate(FLOWERS)]
    body = P.join(parts)
    write_obj(out / "body.obj", body, header="Eustoma plant: stem, leaves, branches (pipelines/eustoma/plant.py)")
    pet = [read_obj(p) for p in petals]
    col = [read_obj(p) for p in column]
    for k, fl in enumerate(FLOWERS):
        P.write_flower_frames(out, k, [pet, col], ["petals", "column"], *frames[k], fl["offset"], FRAMES,
                              lambda t, f, k=k, fl=fl: f"Eustoma plant flower {k + 1} ({cultivar}, age offset "
                                                       f"{fl['offset']}): frame {t + 1} at plant frame {f + 1}")
    lines = ["# the Eustoma plant's layout (written by pipelines/eustoma/plant.py; read by inflo.tools.plant.check)",
             'title = "Eustoma plant"', f'cultivar = "{cultivar}"', f"frames = {FRAMES}",
             f"stem_height = {STEM_HEIGHT}", f"leaves = {len(leaves)}", f"body_triangles = {body.n_faces}",
             f"flower_triangles = {pet[0].n_faces + col[0].n_faces}", f"stages = {[[s, n] for s, n in STAGES]}", ""]
    for k, fl in enumerate(FLOWERS):
        o, b = frames[k]
        lines += ["[[flower]]", f'name = "flower_{k + 1}"'] + [f"{key} = {val}" for key, val in fl.items()]
        lines += [f"origin = [{o[0]:.4f}, {o[1]:.4f}, {o[2]:.4f}]", f"axis = [{b[1][0]:.4f}, {b[1][1]:.4f}, {b[1][2]:.4f}]", ""]
    (out / "plant.toml").write_text("\n".join(lines))
    print(f"plant.py: {len(FLOWERS)} {cultivar} flowers x {FRAMES} frames, offsets {[fl['offset'] for fl in FLOWERS]}; "
          f"body {body.n_faces} triangles ({len(leaves)} leaves); written to {out}")
    return 0


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument("build", type=Path)
    ap.add_argument("out", type=Path)
    ap.add_argument("--cultivar", default="mellow_yellow", choices=["mellow_yellow", "maite_lady", "pinocchio"])
    a = ap.parse_args()
    sys.exit(main(a.build, a.out, a.cultivar))
