"""Exact static intersection test of a written plant (the `plant` targets' check).

Usage: python -m inflo.tools.plant.check PLANT_BUILD [FRAME ...]   (frames 1-based; default: every
                                                                  written frame and the sheet's)

PLANT_BUILD holds ``plant.toml`` (the layout: ``frames``, ``stages``, one ``[[flower]]`` table per
flower with its ``name`` and ``offset``; optionally ``sheet`` and ``sheet_parts``), ``body.obj``
(groups ``stem``, ``leaf_*``, ``pedicel_K``: flower K's stalk) and a folder of OBJ frames per
flower (two groups: its perianth, then ``column``). Every written plant frame (each flower's frame
with the body) and every frame of the contact sheet (``sheet_parts`` folders, groups named
``fK_<part>``) is tested as one mesh with :func:`inflo.tools.collide.intersecting_pairs` (touching
counts). Counted are all intersecting triangle pairs except where two parts are joined by
construction: a flower's column with itself (its closed tubes start inside each other), a
flower's column with its own pedicel (the pedicel ends inside the receptacle's stub), the stem
with a pedicel or a leaf, and a pedicel with another it branches from (``branch_of`` in the
flower's table). Flowers against flowers, petals against petals, a flower against the stem, the
leaves and every other pedicel, leaves against leaves and pedicels: all must be zero. Prints the
figures (pairs per frame, every tenth listed, with the flowers' frames and stages) and exits 1
on any intersecting pair.
"""
from __future__ import annotations

import sys
import time
import tomllib
from pathlib import Path

import numpy as np

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.tools.collide import intersecting_pairs

from . import age, stage

__all__ = ["joined", "test_mesh", "main"]


def joined(a: str, b: str, branches: dict | None = None) -> bool:
    """Whether parts ``a`` and ``b`` are joined by construction (their pairs not counted)."""
    branches = branches or {}
    for x, y in ((a, b), (b, a)):
        if x.endswith("_column") and x == y:
            return True
        if x.endswith("_column") and y.startswith("pedicel_") and x.split("_")[0] == "f" + y.split("_")[1]:
            return True
        if x == "stem" and (y.startswith("pedicel_") or y.startswith("leaf_")):
            return True
        if x.startswith("pedicel_") and y.startswith("pedicel_") and branches.get(x) == y:
            return True
    return False


def test_mesh(meshes_names, branches: dict | None = None):
    """[(mesh, part name of each of its groups)] -> (counted pairs, {part pair: count}, triangles)."""
    names: list[str] = []
    xs, ts, ps = [], [], []
    n = 0
    for m, group_names in meshes_names:
        ids = []
        for g in group_names:
            if g not in names:
                names.append(g)
            ids.append(names.index(g))
        xs.append(m.vertices)
        ts.append(m.faces + n)
        ps.append(np.asarray(ids, np.int64)[np.asarray(m.face_group)])
        n += m.n_vertices
    x, tri, part = np.vstack(xs), np.vstack(ts), np.concatenate(ps)
    ok = np.array([[joined(a, b, branches) for b in names] for a in names], dtype=bool)
    # pairs of joined parts are not tested at all (their touching, coplanar joints are the costly,
    # exactly decided pairs)
    pairs = np.asarray(intersecting_pairs(x, tri, tri_part=part, skip_parts=ok), dtype=np.int64).reshape(-1, 2)
    pa, pb = part[pairs[:, 0]], part[pairs[:, 1]]
    bad = ~ok[pa, pb]
    found: dict = {}
    for a, b in zip(pa[bad], pb[bad]):
        key = tuple(sorted((names[a], names[b])))
        found[key] = found.get(key, 0) + 1
    return int(bad.sum()), found, len(tri)


def main(build: Path, only: list[int] | None = None) -> int:
    t0 = time.perf_counter()
    lay = tomllib.loads((build / "plant.toml").read_text())
    flowers, stages, n_lay = lay["flower"], [tuple(s) for s in lay["stages"]], lay["frames"]
    branches = {f"pedicel_{k + 1}": fl["branch_of"] for k, fl in enumerate(flowers) if fl.get("branch_of")}
    body = read_obj(build / "body.obj")
    seqs = [list_obj_sequence(build / fl["name"]) for fl in flowers]
    n_frames = len(seqs[0])
    if any(len(s) != n_frames for s in seqs) or n_frames != n_lay:
        print(f"FAILED: flower sequences of {[len(s) for s in seqs]} frames, expected {n_lay}")
        return 1
    frames = only or list(range(1, n_frames + 1))
    print(f"{lay.get('title', 'plant')}: {len(flowers)} flowers, age offsets {[fl['offset'] for fl in flowers]} "
          f"frames, {lay['leaves']} leaves; body {body.n_faces} triangles, a flower {lay['flower_triangles']}")
    bad_total, tested, most = 0, 0, (0, 0)
    for f in frames:
        parts = [(body, list(body.groups))]
        for k, s in enumerate(seqs):
            m = read_obj(s[f - 1])
            parts.append((m, [f"f{k + 1}_{g}" for g in m.groups]))
        bad, found, n_tri = test_mesh(parts, branches)
        bad_total += bad
        tested += 1
        ages = [age(f - 1, fl["offset"], n_lay) for fl in flowers]
        st = [stage(a, stages) for a in ages]
        if len(set(st)) > most[0]:
            most = (len(set(st)), f)
        if bad or f % 10 == 0 or f == 1 or only:
            print(f"  frame {f:3d}: {n_tri} triangles, {bad} intersecting pairs; flower frames "
                  f"{[a + 1 for a in ages]} ({', '.join(st)})" + (f"; {found}" if bad else ""))
    print(f"every plant frame tested: {tested}" if not only else f"plant frames tested: {tested}")
    print(f"most distinct stages at one frame: {most[0]} (first at frame {most[1]})")
    if not only and lay.get("sheet_parts"):
        for n in lay["sheet"]:
            parts = [(body, list(body.groups))]
            for sub in lay["sheet_parts"]:
                m = read_obj(build / sub / f"{n}.obj")
                parts.append((m, list(m.groups)))
            bad, found, n_tri = test_mesh(parts, branches)
            bad_total += bad
            print(f"  sheet frame {n:3d} ({', '.join(lay['sheet_parts'])}): {n_tri} triangles, "
                  f"{bad} intersecting pairs" + (f"; {found}" if bad else ""))
    print(f"check time {time.perf_counter() - t0:.1f} s")
    print("OK: no intersecting triangle pairs" if bad_total == 0 else f"FAILED: {bad_total} intersecting pairs")
    return 0 if bad_total == 0 else 1


if __name__ == "__main__":
    if len(sys.argv) < 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1]), [int(a) for a in sys.argv[2:]] or None))
