"""Exact checks of the Eustoma build (the `check` stage of the Makefile).

Usage: python check_eustoma.py BUILD_DIR   (BUILD_DIR = build/eustoma)

For each cultivar: every keyframe is tested by the exact static triangle-triangle test
(inflo.tools.collide.intersecting_pairs; touching counts) and must have zero intersecting pairs;
the topology must be that of the bud in every frame; the joint angle (the rotation of each petal's
base particles from the bud, by shape matching) is listed at frames 1, 50 and 100 (15 deg from
step 50 on); and the open flower's shape is summarized (rim radius, widest radius, height; the
flare = rim radius / radius at half height: a bell and a funnel flare out, a shallow ball curls
in). The calyx and column (BUILD_DIR/column_obj/: receptacle, five sepals, pistil and two-lobed
stigma, five stamens) are tested against every cultivar's petals in every keyframe by the same
exact test (zero pairs), and each of its keyframes must hold at least three organ materials.
The open corolla's slits are measured as background seen through it: lines along the axis (a view
from above) through a 201 x 41 grid 0.5 apart, and horizontal lines (a view from the side) through
201 x 30 points; in each row of the grid, the points between the first and the last covered one
that no petal covers (the gaps between the petals, and between the lobes' tips, inside the
flower's outline) are counted. These rows count the notches between the lobes' tips too, open to
the outside; what is seen *through* the flower is measured apart (`see_through`): at every fifth
keyframe (5, 10, ..., the last), the corolla with the receptacle (which closes the corolla's foot) is rasterized
orthographically from above, from below and every 30 degrees round at elevations 35, 0 and -35,
and the background enclosed by its silhouette (slits between petals, holes) is counted as a share
of the silhouette; the worst view of keyframes 50, 75, the last and the worst keyframe is listed,
and more than SEE_THROUGH in any fails the check.
Exits 1 on any intersection, changed topology or missing organ.
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numba
import numpy as np

from inflo.formats.obj import ObjMesh, list_obj_sequence, read_obj
from inflo.tools.collide import intersecting_pairs, intersecting_pairs_between
from inflo.tools.petal_grow.simulate import shape_match
from inflo.tools.species.checks import worst_see_through

CULTIVARS = ("mellow_yellow", "maite_lady", "pinocchio")
SEE_THROUGH = 0.0025  # the most background seen through the corolla, as a share of its silhouette
BASE_ROWS = 2  # base particles: the first two rows of each petal (uv v <= 0.1)


def petal_blocks(mesh) -> list[np.ndarray]:
    """Vertex ids of each petal (the faces of one group share no vertex with another's)."""
    out = []
    for g in range(len(mesh.groups)):
        out.append(np.unique(mesh.faces[mesh.face_group == g]))
    return out


def joint_angle(bud: np.ndarray, x: np.ndarray, ids: np.ndarray, per_row: int) -> float:
    """Degrees the petal's base rows turned from the bud (rigid fit)."""
    base = ids[: BASE_ROWS * per_row]
    r, _ = shape_match(bud[base], x[base])
    return math.degrees(math.acos(np.clip((np.trace(r) - 1) / 2, -1, 1)))


def shape(x: np.ndarray, blocks, per_row: int) -> dict:
    """Rim radius (mean distance of the petal tips' row from the axis), widest radius, height,
    radius at half the flower's height."""
    rad = np.hypot(x[:, 0], x[:, 2])
    tips = np.concatenate([b[-per_row:] for b in blocks])
    h = x[:, 1].max() - x[:, 1].min()
    mid = np.abs(x[:, 1] - (x[:, 1].min() + 0.5 * h)) < 0.08 * h
    r_mid = float(rad[mid].max()) if mid.any() else float("nan")
    return {"rim": float(rad[tips].mean()), "widest": float(rad.max()), "height": float(h), "mid": r_mid}


def uncovered(mesh, points, axes) -> np.ndarray:
    """Which 2-D points (coordinates ``axes`` of 3-D space) no triangle covers in that projection."""
    tri = mesh.vertices[mesh.faces][:, :, list(axes)]
    # only triangles whose bounds meet the points' bounds can cover one (a row of points: the
    # triangles crossing its line); the margin is far above the test's tolerance
    lo, hi = points.min(axis=0) - 1e-6, points.max(axis=0) + 1e-6
    near = np.all((tri.min(axis=1) <= hi) & (tri.max(axis=1) >= lo), axis=1)
    tri = tri[near]
    a, v0, v1 = tri[:, 0], tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    den = v0[:, 0] * v1[:, 1] - v0[:, 1] * v1[:, 0]
    keep = np.abs(den) > 1e-12
    a, v0, v1, den = a[keep], v0[keep], v1[keep], den[keep]
    w = points[:, None, :] - a[None]
    s = (w[..., 0] * v1[:, 1] - w[..., 1] * v1[:, 0]) / den
    t = (v0[:, 0] * w[..., 1] - v0[:, 1] * w[..., 0]) / den
    return ~np.any((s >= -1e-9) & (t >= -1e-9) & (s + t <= 1 + 1e-9), axis=1)


def see_through(mesh, rows, axes) -> int:
    """Background points inside the outline: per row, the uncovered points between the first and
    the last covered one."""
    n = 0
    for row in rows:
        miss = uncovered(mesh, row, axes)
        hit = np.flatnonzero(~miss)
        if len(hit):
            n += int(miss[hit[0]:hit[-1] + 1].sum())
    return n


def slits(mesh) -> tuple[int, int]:
    """(from above, from the side) background points seen through the corolla."""
    xs = np.linspace(-50.0, 50.0, 201)
    top = [np.stack([xs, np.full_like(xs, z)], axis=1) for z in np.linspace(-40.0, 40.0, 41)]
    ys = np.linspace(0.5, mesh.vertices[:, 1].max() - 0.5, 30)
    side = [np.stack([xs, np.full_like(xs, y)], axis=1) for y in ys]
    return see_through(mesh, top, (0, 2)), see_through(mesh, side, (0, 1))


def with_receptacle(corolla, column) -> ObjMesh:
    """The corolla with the column's receptacle and pistil (which close its throat) as one mesh."""
    keep = [g for g, name in enumerate(column.groups) if name.startswith(("receptacle", "pistil"))]
    faces = column.faces[np.isin(column.face_group, keep)]
    return ObjMesh(vertices=np.vstack([corolla.vertices, column.vertices]),
                   faces=np.vstack([corolla.faces, faces + len(corolla.vertices)]))


def main(build: Path) -> int:
    numba.set_num_threads(1)  # small meshes: one thread is faster (tools/petal_grow/simulate.py, run)
    bad = 0
    column = list_obj_sequence(build / "column_obj")
    organs = read_obj(column[0]).groups
    print(f"column: {len(column)} keyframes, organs "
          + ", ".join(sorted({g.rsplit('_', 1)[0] for g in organs})))
    for name in CULTIVARS:
        paths = list_obj_sequence(build / name)
        if len(column) != len(paths):
            print(f"  {name}: {len(paths)} keyframes, the column {len(column)}")
            bad += 1
        first = read_obj(paths[0])
        blocks = petal_blocks(first)
        per_row = int(np.sum(np.isclose(first.vertices[blocks[0], 1], first.vertices[blocks[0], 1].min())))
        pairs = []
        col_pairs = []
        min_mats = 99
        angles = {}
        through = {}
        for i, p in enumerate(paths):
            m = read_obj(p)
            if not m.same_topology(first):
                print(f"  {name} {p.name}: topology differs from the bud")
                bad += 1
            n = len(intersecting_pairs(m.vertices, m.faces, tri_part=m.face_group))
            pairs.append(n)
            bad += n
            if i < len(column):
                col = read_obj(column[i])
                c = len(intersecting_pairs_between(m.vertices, m.faces, col.vertices, col.faces))
                col_pairs.append(c)
                bad += c
                col_mats = {col.materials[k] for k in np.unique(col.face_material)}
                mats = len(col_mats | {m.materials[k] for k in np.unique(m.face_material)})
                if len(col_mats) < 3:
                    print(f"  {name} {p.name}: the column has fewer than three organ materials")
                    bad += 1
                min_mats = min(min_mats, mats)
            if i + 1 in (1, 50, len(paths)):
                angles[i + 1] = np.mean([joint_angle(first.vertices, m.vertices, b, per_row) for b in blocks])
            if ((i + 1) % 5 == 0 or i + 1 == len(paths)) and i < len(column):
                through[i + 1] = worst_see_through(with_receptacle(m, col))
            last = m
        s = shape(last.vertices, blocks, per_row)
        s0 = shape(first.vertices, blocks, per_row)
        print(f"{name}: {len(paths)} keyframes, {len(first.faces)} triangles ({len(blocks)} petals), "
              f"intersecting pairs: {sum(pairs)} (max per frame {max(pairs)})")
        print(f"  petals against the calyx and column: {sum(col_pairs)} intersecting pairs in {len(col_pairs)} "
              f"keyframes; organ materials per keyframe (petals included): at least {min_mats}")
        print("  joint angle (deg): " + ", ".join(f"frame {k} {v:.2f}" for k, v in angles.items()))
        print(f"  bud: rim radius {s0['rim']:.2f}, widest {s0['widest']:.2f}, height {s0['height']:.2f}")
        print(f"  open: rim radius {s['rim']:.2f}, widest {s['widest']:.2f}, height {s['height']:.2f}, "
              f"radius at half height {s['mid']:.2f}, flare {s['rim'] / s['mid']:.2f}")
        top, side = slits(last)
        print(f"  open: background inside the outline (lobe notches included): {top} points from above, "
              f"{side} from the side")
        worst = max(through, key=lambda k: through[k][0]) if through else None
        shown = [k for k in through if k in (50, 75, len(paths)) or k == worst]
        print(f"  seen through the corolla (enclosed background, worst of 38 views, every fifth keyframe: "
              f"{len(through)}): " + ", ".join(f"frame {k} {through[k][0]:.4f} at ({through[k][1][0]:.0f}, "
                                              f"{through[k][1][1]:.0f})" + (" (the worst)" if k == worst else "")
                                              for k in shown))
        slit = [k for k, (v, _) in through.items() if v > SEE_THROUGH]
        if slit:
            print(f"  {name}: background seen through the corolla over {SEE_THROUGH} of it at frames {slit}")
            bad += 1
    if bad:
        print(f"FAILED: {bad} intersecting pairs, changes or slits")
        return 1
    print("OK: every keyframe intersection-free")
    return 0


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("build", type=Path, help="build/eustoma")
    sys.exit(main(ap.parse_args().build))
