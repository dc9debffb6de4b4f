"""A lily plant (Ijiri et al. 2008, fig. 15): a stem with leaves carrying five of `make lily`'s
opening flowers, each offset in age, on one timeline (the `plant` target of the Makefile).

Usage: python plant.py LILY_BUILD OUT_DIR      (LILY_BUILD = build/lily, OUT_DIR = build/lily_plant)

Nothing is simulated again: a flower of age offset k shows the built lily's frame clamp(f - k) at
plant frame f (tepals from ``canopy/``, pistil, stamens and receptacle from ``column_obj/``; for the
pictures the smoothed, painted ``painted/N.obj`` and ``column_keyframes/N.obj``), moved rigidly
onto its place at the end of its pedicel. The stem, leaves and pedicels are made here as simple
meshes (pure numpy, no randomness: the same bytes on every run):

- the stem: a generalized cylinder from the ground (y = 0) to its apex, tapering and bent a little
  in the x-y plane, closed by a cap at each end;
- leaves: linear-lanceolate, sessile, spirally arranged (golden angle) along the stem below the
  flowers, each a curved, pointed strip with its margins raised along a midrib fold, arching away
  from the stem, 5-10 units (cm) long, the longest half-way up;
- pedicels: tubes (cubic Bezier centre lines) from the stem to each flower's receptacle stub,
  leaving the stem ascending and ending along the flower's axis;
- the flowers in an umbel-like raceme at the top, the lowest the oldest, facing outward and up.

Writes under OUT_DIR:

- ``body.obj``: stem, leaves and pedicels (groups ``stem``, ``leaf_NN``, ``pedicel_K``; materials
  ``mtl10`` stem, ``mtl11`` leaves, ``mtl12`` pedicels), static;
- ``flower_K/frame_NNNN.obj`` (K = 1 lowest ... 5 top, 100 frames each): tepals (group ``tepals``)
  and column (group ``column``) of flower K in plant coordinates, the built lily's materials;
- ``sheet_tepals/N.obj``, ``sheet_columns/N.obj`` (N = 1, 10, ..., 100): every flower's smoothed,
  painted tepals (vertex colours) and columns at plant frame N, groups ``fK_tepals``/``fK_column``;
- ``plant.toml``: the layout (offsets, places, axes) and the counts, which check_plant.py reads.

Units are the lily's (1 unit = 1 cm: the open flower is about 9 across); +Y is up.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from inflo.formats.obj import list_obj_sequence, read_obj, write_obj
from inflo.tools import plant as P

FRAMES = 100
SHEET = (1, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100)

# -- the stem ------------------------------------------------------------------------------------
STEM_HEIGHT = 43.0        # apex (cm)
STEM_R0, STEM_R1 = 0.55, 0.30   # radius at the ground and at the apex
STEM_BEND = 1.6           # sideways (+x) offset of the apex: a slight curve, x = bend * (y / H)^2
STEM_SIDES, STEM_RINGS = 12, 64

# -- the leaves: spirally arranged (golden angle), sessile, linear-lanceolate ----------------------
LEAF_COUNT = 34
LEAF_Y0, LEAF_Y1 = 3.0, 33.0     # heights of the lowest and highest leaf
LEAF_ROWS, LEAF_ACROSS = 14, 5   # rows along (the tip row is one vertex), vertices across
GOLDEN = 137.50776405

# -- the flowers: (age offset in frames, node height, azimuth deg, reach, rise, axis tilt deg,
#    pedicel's starting angle from vertical deg, spin about the axis deg); the lowest is the oldest.
#    Offsets are multiples of 10 so that the contact sheet's frames (1, 10, ..., 100) show the
#    built lily's smoothed, painted keyframes.
FLOWERS = (
    dict(offset=0, node=37.0, azimuth=0.0, reach=6.0, rise=5.5, tilt=50.0, start=35.0, spin=0.0),
    dict(offset=20, node=38.5, azimuth=144.0, reach=5.5, rise=6.0, tilt=45.0, start=32.0, spin=20.0),
    dict(offset=40, node=40.0, azimuth=288.0, reach=5.0, rise=6.5, tilt=40.0, start=28.0, spin=40.0),
    dict(offset=70, node=41.5, azimuth=72.0, reach=3.5, rise=6.5, tilt=30.0, start=24.0, spin=10.0),
    dict(offset=90, node=42.5, azimuth=216.0, reach=1.8, rise=5.5, tilt=15.0, start=15.0, spin=30.0),
)
PEDICEL_R0, PEDICEL_R1 = 0.22, 0.15   # radius at the stem and under the flower
PEDICEL_END = -0.45     # the pedicel ends on the flower axis this far below the receptacle (inside its stub)
PEDICEL_SIDES, PEDICEL_RINGS = 10, 28

# stage names of a flower by its (0-based) lily frame: closed bud, opening, open (tepals spread)
STAGES = ((0, "bud"), (15, "opening"), (40, "open"))

MTL_STEM, MTL_LEAF, MTL_PEDICEL = "mtl10", "mtl11", "mtl12"


def stage(frame0: int) -> str:
    return P.stage(frame0, STAGES)


def age(plant_frame0: int, offset: int) -> int:
    """The built lily's 0-based frame a flower of age ``offset`` shows at 0-based plant frame f."""
    return P.age(plant_frame0, offset, FRAMES)


# -- the stem ---------------------------------------------------------------------------------------

def stem_point(y):
    y = np.asarray(y, dtype=np.float64)
    return np.stack([STEM_BEND * (y / STEM_HEIGHT) ** 2, y, np.zeros_like(y)], axis=-1)


def stem_radius(y):
    return STEM_R0 + (STEM_R1 - STEM_R0) * np.asarray(y, dtype=np.float64) / STEM_HEIGHT


def make_stem():
    y = STEM_HEIGHT * (np.arange(STEM_RINGS) / (STEM_RINGS - 1)) ** 1.0
    pts = stem_point(y)
    r = stem_radius(y)
    # a rounded apex: the last rings narrow over the last few millimetres
    top = STEM_HEIGHT + 0.25
    return P.tube(pts, r, STEM_SIDES, cap0=stem_point(0.0), cap1=stem_point(top))


# -- leaves -------------------------------------------------------------------------------------------

def make_leaves():
    out = []
    for j in range(LEAF_COUNT):
        t = j / (LEAF_COUNT - 1)
        y = LEAF_Y0 + (LEAF_Y1 - LEAF_Y0) * t
        psi = math.radians(GOLDEN * j)
        e_out = np.array([math.cos(psi), 0.0, math.sin(psi)])
        length = 5.5 + 4.5 * math.sin(math.pi * min(1.0, 0.25 + 0.9 * t))   # 5.5-10 cm, longest half-way
        half = 0.065 * length + 0.05
        angle0 = 52.0 - 22.0 * t          # the upper leaves more ascending
        base = stem_point(y) + 0.45 * stem_radius(y) * e_out
        out.append(P.leaf_mesh(base, e_out, length, half, angle0, curl=38.0 - 10.0 * t, fold=0.35,
                               rows=LEAF_ROWS, across=LEAF_ACROSS))
    return out


# -- flowers and pedicels ----------------------------------------------------------------------------

def flower_frame(fl: dict):
    """(origin, basis) of a flower: its receptacle (the lily's origin) at the end of its pedicel,
    its axis (the lily's +Y) tilted outward by ``tilt`` from vertical, spun by ``spin``."""
    phi = math.radians(fl["azimuth"])
    e_r = np.array([math.cos(phi), 0.0, math.sin(phi)])
    origin = stem_point(fl["node"]) + fl["reach"] * e_r + fl["rise"] * np.array([0.0, 1.0, 0.0])
    return origin, P.flower_basis(fl["azimuth"], fl["tilt"], fl["spin"])


def make_pedicel(fl: dict):
    origin, basis = flower_frame(fl)
    axis = basis[1]
    phi, g = math.radians(fl["azimuth"]), math.radians(fl["start"])
    p0 = stem_point(fl["node"])
    d0 = np.array([math.sin(g) * math.cos(phi), math.cos(g), math.sin(g) * math.sin(phi)])
    p3 = origin + PEDICEL_END * axis
    span = float(np.sqrt(np.sum((p3 - p0) ** 2)))
    p1 = p0 + 0.4 * span * d0
    p2 = p3 - 0.4 * span * axis
    pts = P.bezier(p0, p1, p2, p3, PEDICEL_RINGS)
    r = PEDICEL_R0 + (PEDICEL_R1 - PEDICEL_R0) * (np.arange(PEDICEL_RINGS) / (PEDICEL_RINGS - 1))
    return P.tube(pts, r, PEDICEL_SIDES, cap0=p0, cap1=p3 + 0.05 * axis)


def main(lily: Path, out: Path) -> int:
    canopy = list_obj_sequence(lily / "canopy")
    column = list_obj_sequence(lily / "column_obj")
    if len(canopy) != FRAMES or len(column) != FRAMES:
        print(f"plant.py: {lily} has {len(canopy)} canopy and {len(column)} column frames, "
              f"expected {FRAMES} (run make lily first)", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    frames = [(o, b) for o, b in map(flower_frame, FLOWERS)]

    # the body: stem, leaves, pedicels (static)
    parts = [("stem", MTL_STEM, make_stem())]
    leaves = make_leaves()
    parts += [(f"leaf_{j + 1:02d}", MTL_LEAF, lf) for j, lf in enumerate(leaves)]
    parts += [(f"pedicel_{k + 1}", MTL_PEDICEL, make_pedicel(fl)) for k, fl in enumerate(FLOWERS)]
    body = P.join(parts)
    write_obj(out / "body.obj", body, header="lily plant: stem, leaves, pedicels (pipelines/lily/plant.py)")

    # every flower's frames in plant coordinates: tepals + column
    tep = [read_obj(p) for p in canopy]
    col = [read_obj(p) for p in column]
    for k, fl in enumerate(FLOWERS):
        P.write_flower_frames(out, k, [tep, col], ["tepals", "column"], *frames[k], fl["offset"], FRAMES,
                              lambda t, f, k=k, fl=fl: f"lily plant flower {k + 1} (age offset {fl['offset']}): "
                                                       f"lily frame {t + 1} at plant frame {f + 1}")

    # the contact sheet's frames: smoothed, painted tepals and the columns of the same lily frames
    for sub in ("sheet_tepals", "sheet_columns"):
        (out / sub).mkdir(exist_ok=True)
    for n in SHEET:
        ts, cs = [], []
        for k, fl in enumerate(FLOWERS):
            t1 = age(n - 1, fl["offset"]) + 1
            o, b = frames[k]
            ts.append(P.placed(read_obj(lily / "painted" / f"{t1}.obj"), o, b))
            cs.append(P.placed(read_obj(lily / "column_keyframes" / f"{t1}.obj"), o, b))
        write_obj(out / "sheet_tepals" / f"{n}.obj", P.merge(ts, [f"f{k + 1}_tepals" for k in range(len(ts))], True))
        write_obj(out / "sheet_columns" / f"{n}.obj", P.merge(cs, [f"f{k + 1}_column" for k in range(len(cs))]))

    # the layout, for the check and the record
    lines = ["# the lily plant's layout (written by pipelines/lily/plant.py; read by check_plant.py)",
             'title = "lily plant"', f"frames = {FRAMES}", f"sheet = {list(SHEET)}",
             'sheet_parts = ["sheet_tepals", "sheet_columns"]', f"stem_height = {STEM_HEIGHT}",
             f"leaves = {LEAF_COUNT}", f"body_triangles = {body.n_faces}",
             f"flower_triangles = {tep[0].n_faces + col[0].n_faces}",
             f"stages = {[[s, n] for s, n in STAGES]}", ""]
    for k, fl in enumerate(FLOWERS):
        o, b = frames[k]
        lines += ["[[flower]]", f"name = \"flower_{k + 1}\""]
        lines += [f"{key} = {val}" for key, val in fl.items()]
        lines += [f"origin = [{o[0]:.4f}, {o[1]:.4f}, {o[2]:.4f}]",
                  f"axis = [{b[1][0]:.4f}, {b[1][1]:.4f}, {b[1][2]:.4f}]", ""]
    (out / "plant.toml").write_text("\n".join(lines))
    print(f"plant.py: {len(FLOWERS)} flowers x {FRAMES} frames, offsets {[fl['offset'] for fl in FLOWERS]}; "
          f"body {body.n_faces} triangles ({LEAF_COUNT} leaves); written to {out}")
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1]), Path(sys.argv[2])))
