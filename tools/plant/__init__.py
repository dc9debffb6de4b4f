"""A flower's plant: a stem, leaves and stalks carrying several copies of one built flower, each
offset in age on one timeline (Ijiri et al. 2008, fig. 15; issue 46). Pure numpy, no randomness.

The species' layout lives in its pipeline (pipelines/lily/plant.py, pipelines/eustoma/plant.py);
this module gives what they share:

- :func:`tube`: a generalized cylinder round a centre line (parallel-transport frames, a fan cap
  at each end);
- :func:`leaf_mesh`: a pointed strip along an arching midline with its margins raised along a
  midrib fold (linear-lanceolate to ovate by its width profile);
- :func:`bezier`, :func:`flower_basis`, :func:`transform`: stalks' centre lines and the rigid
  placing of a flower (its +Y axis tilted outward from vertical, spun about itself);
- :func:`age`: the built flower's frame a flower of age offset k shows at plant frame f,
  clamp(f - k);
- :func:`join`, :func:`merge`, :func:`placed`: meshes into one OBJ mesh, a group per part;
- :mod:`inflo.tools.plant.check`: the exact test of a written plant (``python -m
  inflo.tools.plant.check BUILD``).

Every product is an elementwise sum in a fixed order (no BLAS: docs/architecture.md).
"""
from __future__ import annotations

import math

import numpy as np

from inflo.formats.obj import ObjMesh

__all__ = ["age", "stage", "unit", "cross", "transform", "tube", "leaf_mesh", "bezier", "flower_basis",
           "join", "merge", "placed"]


def age(plant_frame0: int, offset: int, frames: int) -> int:
    """The built flower's 0-based frame shown at 0-based plant frame ``plant_frame0`` by a flower of
    age ``offset``: clamp(f - offset, 0, frames - 1)."""
    return int(min(max(plant_frame0 - offset, 0), frames - 1))


def stage(frame0: int, stages) -> str:
    """The name of the last ``(start, name)`` of ``stages`` (ascending starts) that ``frame0`` reaches."""
    name = stages[0][1]
    for start, s in stages:
        if frame0 >= start:
            name = s
    return name


def unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.sqrt(np.sum(v * v, axis=-1, keepdims=True))


def cross(a, b) -> np.ndarray:
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                     a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)


def transform(v: np.ndarray, basis: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """Local points ``v`` (n, 3) -> ``origin + x * basis[0] + y * basis[1] + z * basis[2]``."""
    return (origin + v[:, 0:1] * basis[0]) + v[:, 1:2] * basis[1] + v[:, 2:3] * basis[2]


def tube(points, radii, sides: int, cap0, cap1):
    """A generalized cylinder: a ring of ``sides`` vertices round each centre-line point, framed by
    parallel transport, closed by a fan to ``cap0`` before the first ring and to ``cap1`` after the
    last. Returns (vertices, triangles)."""
    pts = np.asarray(points, dtype=np.float64)
    k = len(pts)
    seg = unit(np.diff(pts, axis=0))
    tan = np.empty((k, 3))
    tan[0], tan[-1] = seg[0], seg[-1]
    tan[1:-1] = unit(seg[:-1] + seg[1:])
    ref = np.array([0.0, 0.0, 1.0]) if abs(tan[0][2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    n = unit(ref - np.sum(ref * tan[0]) * tan[0])
    ang = 2.0 * math.pi * np.arange(sides) / sides
    ca, sa = np.cos(ang)[:, None], np.sin(ang)[:, None]
    rings = []
    for i in range(k):
        if i:
            n = unit(n - np.sum(n * tan[i]) * tan[i])
        b = cross(tan[i], n)
        rings.append(pts[i] + radii[i] * (ca * n + sa * b))
    v = np.vstack(rings + [np.asarray(cap0, float)[None], np.asarray(cap1, float)[None]])
    c0, c1 = k * sides, k * sides + 1
    f = []
    for i in range(k - 1):
        for j in range(sides):
            a, b = i * sides + j, i * sides + (j + 1) % sides
            f += [(a, b, b + sides), (a, b + sides, a + sides)]
    last = (k - 1) * sides
    for j in range(sides):
        f.append((c0, (j + 1) % sides, j))
        f.append((c1, last + j, last + (j + 1) % sides))
    return v, np.array(f, dtype=np.int32)


def leaf_mesh(base, e_out, length, half_width, angle0, curl, fold, *, rows: int = 14, across: int = 5,
              widest: float = 0.3, base_width: float = 0.45, tip_power: float = 0.9):
    """A leaf: ``rows`` rows along its midline from the base (``base``) to a single tip vertex; the
    midline leaves at ``angle0`` (degrees from vertical) in the plane of +Y and ``e_out`` and bends
    ``curl`` degrees further outward toward the tip; the half-width grows from ``base_width`` x
    ``half_width`` at the base to ``half_width`` at ``widest`` of the length and narrows to the
    point (cosine to the power ``tip_power``); the margins rise ``fold`` x the half-width above
    the midrib (the fold). Returns (vertices, triangles)."""
    up = np.array([0.0, 1.0, 0.0])
    side = cross(up, e_out)
    s = np.arange(rows + 1) / rows
    ang = np.radians(angle0 + curl * s ** 1.6)
    d = np.cos(ang)[:, None] * up + np.sin(ang)[:, None] * e_out          # midline direction
    nrm = np.sin(ang)[:, None] * up - np.cos(ang)[:, None] * e_out        # upper face normal
    ds = length / rows
    mid = np.vstack([base, base + np.cumsum(0.5 * (d[:-1] + d[1:]) * ds, axis=0)])
    w = np.where(s < widest, base_width + (1.0 - base_width) * np.sin(0.5 * math.pi * s / widest),
                 np.cos(0.5 * math.pi * np.clip((s - widest) / (1.0 - widest), 0.0, 1.0)) ** tip_power) * half_width
    u = np.linspace(-1.0, 1.0, across)
    verts = [mid[i] + (u[:, None] * w[i]) * side + (fold * np.abs(u)[:, None] * w[i]) * nrm[i] for i in range(rows)]
    verts.append(mid[-1][None])
    v = np.vstack(verts)
    tip = rows * across
    f = []
    for i in range(rows - 1):
        for j in range(across - 1):
            a = i * across + j
            f += [(a, a + 1, a + 1 + across), (a, a + 1 + across, a + across)]
    last = (rows - 1) * across
    for j in range(across - 1):
        f.append((last + j, last + j + 1, tip))
    return v, np.array(f, dtype=np.int32)


def bezier(p0, p1, p2, p3, n: int) -> np.ndarray:
    """``n`` points of the cubic Bezier curve p0 p1 p2 p3, evenly in its parameter."""
    t = (np.arange(n) / (n - 1))[:, None]
    return ((1 - t) ** 3) * p0 + (3 * t * (1 - t) ** 2) * p1 + (3 * t * t * (1 - t)) * p2 + (t ** 3) * p3


def flower_basis(azimuth: float, tilt: float, spin: float) -> np.ndarray:
    """(3, 3): where a flower's local x, y (its axis) and z go: the axis tilted ``tilt`` degrees from
    vertical toward ``azimuth`` (degrees from +X toward +Z), spun ``spin`` degrees about itself."""
    phi, th, sp = math.radians(azimuth), math.radians(tilt), math.radians(spin)
    e_r = np.array([math.cos(phi), 0.0, math.sin(phi)])
    e_t = np.array([-math.sin(phi), 0.0, math.cos(phi)])
    up = np.array([0.0, 1.0, 0.0])
    a = math.sin(th) * e_r + math.cos(th) * up
    b1 = math.cos(th) * e_r - math.sin(th) * up
    x = math.cos(sp) * b1 + math.sin(sp) * e_t
    z = -math.sin(sp) * b1 + math.cos(sp) * e_t
    return np.stack([x, a, z])


def join(parts) -> ObjMesh:
    """[(name, material, (v, f))] -> one ObjMesh, one group per part."""
    vs, fs, gs, ms, mats = [], [], [], [], []
    n = 0
    for gi, (_name, mat, (v, f)) in enumerate(parts):
        if mat not in mats:
            mats.append(mat)
        vs.append(v)
        fs.append(f + n)
        gs.append(np.full(len(f), gi, np.int32))
        ms.append(np.full(len(f), mats.index(mat), np.int32))
        n += len(v)
    return ObjMesh(vertices=np.vstack(vs), faces=np.vstack(fs), groups=[p[0] for p in parts],
                   face_group=np.concatenate(gs), materials=mats, face_material=np.concatenate(ms))


def merge(meshes, names, colors: bool = False) -> ObjMesh:
    """Meshes -> one ObjMesh, one group per input mesh (``names``), materials by name; ``colors``:
    keep their vertex colours (every mesh has them)."""
    vs, fs, gs, ms, cs, mats = [], [], [], [], [], []
    n = 0
    for gi, m in enumerate(meshes):
        local = []
        for name in m.materials:
            if name not in mats:
                mats.append(name)
            local.append(mats.index(name))
        vs.append(m.vertices)
        fs.append(m.faces + n)
        gs.append(np.full(m.n_faces, gi, np.int32))
        ms.append(np.asarray(local, np.int32)[m.face_material])
        if colors:
            cs.append(m.vertex_colors)
        n += m.n_vertices
    return ObjMesh(vertices=np.vstack(vs), faces=np.vstack(fs), groups=list(names),
                   face_group=np.concatenate(gs), materials=mats, face_material=np.concatenate(ms),
                   vertex_colors=np.vstack(cs) if colors else None)


def placed(mesh: ObjMesh, origin, basis) -> ObjMesh:
    """``mesh`` moved rigidly: its local frame onto ``basis`` at ``origin``."""
    return ObjMesh(vertices=transform(mesh.vertices, basis, origin), faces=mesh.faces,
                   vertex_colors=mesh.vertex_colors, groups=mesh.groups, face_group=mesh.face_group,
                   materials=mesh.materials, face_material=mesh.face_material)


def write_flower_frames(out, k: int, organs, names, origin, basis, offset: int, frames: int, header) -> None:
    """Flower ``k`` (0-based) of a plant as ``out/flower_{k + 1}/frame_NNNN.obj``: at every plant
    frame f the flower's organs (``organs``: per organ, its built frames' meshes) of frame
    :func:`age` (f, ``offset``), placed at ``origin`` with ``basis`` and merged as groups ``names``;
    ``header(t, f)`` is the header of the frame showing built frame t at plant frame f (0-based).
    A built frame shown at several plant frames is placed once."""
    from pathlib import Path

    from inflo.formats.obj import write_obj

    folder = Path(out) / f"flower_{k + 1}"
    folder.mkdir(exist_ok=True)
    cache: dict = {}
    for f in range(frames):
        t = age(f, offset, frames)
        if t not in cache:
            cache[t] = merge([placed(m[t], origin, basis) for m in organs], names)
        write_obj(folder / f"frame_{f:04d}.obj", cache[t], header=header(t, f))
