"""Exact static intersection test of the lily plant (the `plant` target's check).

Usage: python check_plant.py PLANT_BUILD [FRAME ...]   (PLANT_BUILD = build/lily_plant; frames 1-based,
                                                        default: every written frame)

Every written plant frame (the flowers' ``flower_K/`` frames with ``body.obj``) and every frame of
the contact sheet (``sheet_tepals/``, ``sheet_columns/`` with ``body.obj``) is tested as one mesh
with :func:`inflo.tools.collide.intersecting_pairs` (touching counts). Its parts: each flower's
tepals and column, the stem, every leaf and every pedicel. Counted are all intersecting triangle
pairs except where two parts are joined by construction: a flower's column with itself (its closed
tubes touch where they start inside each other, as in check_lily.py), a flower's column with its
own pedicel (the pedicel ends inside the receptacle's stub), and the stem with a pedicel or a leaf
(both start inside it). Flowers against flowers, tepals against tepals, a flower against the stem,
the leaves and every pedicel, leaves against leaves and pedicels, pedicels against each other: all
must be zero. Prints the figures (pairs per frame, every tenth listed; the flowers' lily frames
and stages at those frames) and exits 1 on any intersecting pair.
"""
from __future__ import annotations

import sys
import time
import tomllib
from pathlib import Path

import numpy as np

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.tools.collide import intersecting_pairs


def stage(frame0: int, stages) -> str:
    name = stages[0][1]
    for start, s in stages:
        if frame0 >= start:
            name = s
    return name


def classify(names: list[str]) -> np.ndarray:
    """(p, p) bool: part pairs joined by construction (their pairs not counted)."""
    p = len(names)
    ok = np.zeros((p, p), bool)
    for i, a in enumerate(names):
        for j, b in enumerate(names):
            if a.endswith("_column") and a == b:
                ok[i, j] = True
            ka = a.split("_")[0]
            if a.endswith("_column") and b.startswith("pedicel_") and ka == "f" + b.split("_")[1]:
                ok[i, j] = ok[j, i] = True
            if a == "stem" and (b.startswith("pedicel_") or b.startswith("leaf_")):
                ok[i, j] = ok[j, i] = True
    return ok


def test_mesh(meshes_parts, names):
    """Meshes (each with its per-face part indices into names) -> (counted pairs, by part pair)."""
    xs, ts, ps = [], [], []
    n = 0
    for m, part in meshes_parts:
        xs.append(m.vertices)
        ts.append(m.faces + n)
        ps.append(part)
        n += m.n_vertices
    x, tri, part = np.vstack(xs), np.vstack(ts), np.concatenate(ps)
    order = np.argsort(part, kind="stable")           # parts contiguous, as the part-by-part sweep wants
    tri, part = tri[order], part[order]
    pairs = intersecting_pairs(x, tri, tri_part=part)
    ok = classify(names)
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    pa, pb = part[pairs[:, 0]], part[pairs[:, 1]]
    bad = ~ok[pa, pb]
    found = {}
    for a, b in zip(pa[bad], pb[bad]):
        key = tuple(sorted((names[a], names[b])))
        found[key] = found.get(key, 0) + 1
    return int(bad.sum()), found, len(tri)


def main(build: Path, only: list[int] | None = None) -> int:
    t0 = time.perf_counter()
    lay = tomllib.loads((build / "plant.toml").read_text())
    flowers, stages = lay["flower"], [tuple(s) for s in lay["stages"]]
    body = read_obj(build / "body.obj")
    names = [f"f{k + 1}_{w}" for k in range(len(flowers)) for w in ("tepals", "column")] + list(body.groups)
    body_part = np.asarray(body.face_group) + 2 * len(flowers)
    seqs = [list_obj_sequence(build / fl["name"]) for fl in flowers]
    n_frames = len(seqs[0])
    if any(len(s) != n_frames for s in seqs) or n_frames != lay["frames"]:
        print(f"FAILED: flower sequences of {[len(s) for s in seqs]} frames, expected {lay['frames']}")
        return 1
    frames = only or list(range(1, n_frames + 1))
    print(f"lily plant: {len(flowers)} flowers, age offsets {[fl['offset'] for fl in flowers]} frames, "
          f"{lay['leaves']} leaves; body {body.n_faces} triangles, a flower {lay['flower_triangles']}")
    bad_total, tested, most = 0, 0, (0, 0)
    for f in frames:
        parts = [(body, body_part)]
        for k, s in enumerate(seqs):
            m = read_obj(s[f - 1])
            parts.append((m, np.asarray(m.face_group) + 2 * k))     # groups: tepals 0, column 1
        bad, found, n_tri = test_mesh(parts, names)
        bad_total += bad
        tested += 1
        ages = [min(max(f - 1 - fl["offset"], 0), lay["frames"] - 1) for fl in flowers]
        st = [stage(a, stages) for a in ages]
        if len(set(st)) > most[0]:
            most = (len(set(st)), f)
        if bad or f % 10 == 0 or f == 1 or only:
            print(f"  frame {f:3d}: {n_tri} triangles, {bad} intersecting pairs; lily frames "
                  f"{[a + 1 for a in ages]} ({', '.join(st)})" + (f"; {found}" if bad else ""))
    print(f"every plant frame tested: {tested}" if not only else f"plant frames tested: {tested}")
    print(f"most distinct stages at one frame: {most[0]} (first at frame {most[1]})")
    if not only:
        sheet_t = {p.stem: p for p in (build / "sheet_tepals").glob("*.obj")}
        sheet_c = {p.stem: p for p in (build / "sheet_columns").glob("*.obj")}
        for n in lay["sheet"]:
            t, c = read_obj(sheet_t[str(n)]), read_obj(sheet_c[str(n)])
            parts = [(body, body_part), (t, 2 * np.asarray(t.face_group)), (c, 2 * np.asarray(c.face_group) + 1)]
            bad, found, n_tri = test_mesh(parts, names)
            bad_total += bad
            print(f"  sheet frame {n:3d} (smoothed tepals): {n_tri} triangles, {bad} intersecting pairs"
                  + (f"; {found}" if bad else ""))
    print(f"check time {time.perf_counter() - t0:.1f} s")
    print("OK: no intersecting triangle pairs" if bad_total == 0 else f"FAILED: {bad_total} intersecting pairs")
    return 0 if bad_total == 0 else 1


if __name__ == "__main__":
    if len(sys.argv) < 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1]), [int(a) for a in sys.argv[2:]] or None))
