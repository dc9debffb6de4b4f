"""Synthetic flowers for tests, benchmarks and trying the renderer: curved open petal patches.

Nothing here follows the thesis's models; these are cheap meshes with the features that matter to
a renderer (open surfaces seen from both sides, overlapping petals, several materials, many
triangles). +Y is up, as in every inflo scene.
"""
from __future__ import annotations

import math

import numpy as np

from inflo.formats.obj import ObjMesh

__all__ = ["grid_faces", "midrib_directions", "petal_patch", "petal", "flower", "canopy", "merge"]

GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))


def grid_faces(nu: int, nv: int, offset: int = 0) -> np.ndarray:
    """Triangles of an ``nu`` x ``nv`` vertex grid (row-major, u slow), two per cell.

    Returns
    -------
    (2 (nu - 1) (nv - 1), 3) int32
    """
    i, j = np.meshgrid(np.arange(nu - 1), np.arange(nv - 1), indexing="ij")
    a = (i * nv + j).ravel() + offset
    b, c, d = a + nv, a + nv + 1, a + 1
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]).astype(np.int32)


def midrib_directions(phi: float, u: np.ndarray, rise: float, bend: float) -> np.ndarray:
    """Unit directions of a petal's midrib at its parameters ``u`` in [0, 1] (base to tip): in the
    vertical plane at azimuth ``phi`` (radians), ``rise`` degrees above the horizontal at the base,
    turning outwards by ``bend`` degrees towards the tip. Returns (len(u), 3) float64."""
    radial = np.array([math.sin(phi), 0.0, math.cos(phi)])
    up = np.array([0.0, 1.0, 0.0])
    ang = np.radians(rise - bend * u)
    return np.cos(ang)[:, None] * radial + np.sin(ang)[:, None] * up


def petal_patch(phi: float, spine: np.ndarray, d_spine: np.ndarray, half_width: np.ndarray, *, cup: float,
                nv: int, base=(0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """The open patch around a petal's midrib: at each midrib point ``base + spine[i]`` (direction
    ``d_spine[i]``, :func:`midrib_directions`) ``nv`` points across, ``half_width[i]`` to either side
    along the horizontal tangent of azimuth ``phi`` and cupped by ``cup`` (fraction of the half-width)
    towards the normal in the midrib's plane.

    Returns
    -------
    vertices : (nu nv, 3) float64, ``nu = len(spine)``, row-major (u along the midrib slow)
    faces : (2 (nu - 1)(nv - 1), 3) int32 (:func:`grid_faces`)
    """
    v = np.linspace(-1.0, 1.0, nv)
    tangent = np.array([math.cos(phi), 0.0, -math.sin(phi)])
    normal = np.cross(tangent, d_spine)  # in the plane of radial and up, perpendicular to the midrib
    vv, hw = v[None, :, None], half_width[:, None, None]
    pts = (np.asarray(base, float) + spine[:, None, :] + vv * hw * tangent
           + cup * vv ** 2 * hw * normal[:, None, :])
    return pts.reshape(-1, 3), grid_faces(len(spine), nv)


def petal(phi: float, *, length: float = 1.0, width: float = 0.35, rise: float = 70.0, bend: float = 80.0,
          cup: float = 0.25, nu: int = 12, nv: int = 7, base=(0.0, 0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """One curved petal: an open patch leaving ``base`` at azimuth ``phi`` (radians).

    The midrib leaves at ``rise`` degrees above the horizontal and turns outwards by ``bend``
    degrees towards its tip; the cross-section is cupped by ``cup`` (fraction of the half-width).

    Returns
    -------
    vertices : (nu nv, 3) float64
    faces : (2 (nu - 1)(nv - 1), 3) int32
    """
    u = np.linspace(0.0, 1.0, nu)
    d_spine = midrib_directions(phi, u, rise, bend)
    step = np.gradient(u) * length
    spine = np.cumsum(d_spine * step[:, None], axis=0) - d_spine[0] * step[0]
    half_w = width * np.sin(np.pi * np.clip(u, 0.0, 1.0)) ** 0.7 + 0.02 * width
    return petal_patch(phi, spine, d_spine, half_w, cup=cup, nv=nv, base=base)


def merge(parts: list[tuple[np.ndarray, np.ndarray, int]], material_names: list[str]) -> ObjMesh:
    """One ObjMesh from (vertices, faces, material index) parts."""
    verts, faces, mats, off = [], [], [], 0
    for v, f, m in parts:
        verts.append(v)
        faces.append(f + off)
        mats.append(np.full(len(f), m, np.int32))
        off += len(v)
    return ObjMesh(vertices=np.concatenate(verts), faces=np.concatenate(faces), materials=list(material_names),
                   face_material=np.concatenate(mats))


def _disk(center, radius: float, n: int = 24, height: float = 0.15) -> tuple[np.ndarray, np.ndarray]:
    """A low dome (the head's disk) as a triangle fan."""
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    ring = np.stack([radius * np.sin(t), np.zeros(n), radius * np.cos(t)], 1)
    v = np.vstack([[0.0, height * radius, 0.0], ring]) + np.asarray(center, float)
    f = np.stack([np.zeros(n, int), 1 + np.arange(n), 1 + (np.arange(n) + 1) % n], 1)
    return v, f.astype(np.int32)


def flower(n_petals: int = 8, *, center=(0.0, 0.0, 0.0), scale: float = 1.0, opening: float = 0.5,
           nu: int = 12, nv: int = 7, phase: float = 0.0, with_disk: bool = True) -> ObjMesh:
    """A head of ``n_petals`` overlapping petals around a disk; materials ``mtl1`` (petals), ``mtl3`` (disk).

    ``opening`` in 0..1 goes from a closed cup (petals rising steeply, overlapping) to open.
    """
    c = np.asarray(center, float)
    parts = []
    rise = 80.0 - 50.0 * opening
    bend = 10.0 + 45.0 * opening
    for k in range(n_petals):
        phi = phase + 2.0 * math.pi * k / n_petals
        v, f = petal(phi, length=scale, width=0.3 * scale * 6.0 / max(n_petals, 3), rise=rise, bend=bend,
                     nu=nu, nv=nv, base=c + 0.12 * scale * np.array([math.sin(phi), 0.0, math.cos(phi)]))
        parts.append((v, f, 0))
    if with_disk:
        v, f = _disk(c, 0.2 * scale)
        parts.append((v, f, 1))
    return merge(parts, ["mtl1", "mtl3"])


def canopy(n_heads: int, *, petals: int = 20, nu: int = 21, nv: int = 11, spacing: float = 1.0,
           opening: float = 0.6) -> ObjMesh:
    """Heads on a flat phyllotactic (golden-angle) pattern: ``n_heads * petals * 2 (nu-1)(nv-1)`` petal triangles.

    With the defaults each head has 20 petals of 400 triangles (8,000 per head, plus a 24-triangle
    disk), so 50 heads make 401,200 triangles.
    """
    heads = []
    for i in range(n_heads):
        r = spacing * math.sqrt(i + 0.5)
        a = i * GOLDEN_ANGLE
        heads.append(flower(petals, center=(r * math.sin(a), 0.05 * spacing * math.sqrt(i), r * math.cos(a)),
                            scale=0.75 * spacing, opening=opening, nu=nu, nv=nv, phase=a))
    verts = np.concatenate([h.vertices for h in heads])
    offs = np.cumsum([0] + [len(h.vertices) for h in heads[:-1]])
    faces = np.concatenate([h.faces + o for h, o in zip(heads, offs)])
    mats = np.concatenate([h.face_material for h in heads])
    return ObjMesh(vertices=verts, faces=faces, materials=["mtl1", "mtl3"], face_material=mats)
