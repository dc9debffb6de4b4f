"""The receptacle as a mesh: the supporting surface the pattern lives on (thesis sec. 5.2-5.3).

The florets of a head sit on a surface of revolution of the generating curve C (fig. 5.1); in a
dynamic pattern C is scaled (and blended between key curves) every frame as the receptacle grows
(sec. 5.3, fig. 9.4: "the dramatic, yet stable change in size due to the dynamic phyllotaxis").
``phyllotaxis`` writes that surface when asked (``[receptacle]`` in formats/phyllotaxis.md), so
that a head can be rendered and composed with its receptacle: one OBJ per RBA frame, the same
vertex count and order in every frame (an animation fccompose and canopy-export take as it is).

The mesh is closed: the **top**, C rotated about +Y and moved ``inset`` below the florets' bases
along the surface normal (so that the florets stand on it without touching it), from the apex to
the rim; and the **underside**, a quarter ellipse from the rim in to a stem of radius
``stem · rim radius`` at ``depth · rim radius`` below the rim, closed by a disc. Rings of the top
are spaced evenly in arc length; ``segments`` vertices per ring.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from inflo.formats.obj import ObjMesh

from .surface import Profile

__all__ = ["ReceptacleOptions", "receptacle_mesh", "receptacle_topology"]


@dataclass(frozen=True)
class ReceptacleOptions:
    """``[receptacle]`` keys (formats/phyllotaxis.md)."""

    segments: int = 48
    rings: int = 12
    underside_rings: int = 6
    depth: float = 0.35
    stem: float = 0.25
    inset: float = 0.0
    material: int = 5


def receptacle_topology(opts: ReceptacleOptions) -> np.ndarray:
    """(m, 3) int32 triangles (outward facing) of the closed receptacle; the same every frame.

    Vertex layout: 0 = apex; then ``rings`` top rings (the last is the rim), ``underside_rings``
    rings of the underside (the last is the stem's rim), then the centre of the bottom disc.
    Every ring has ``segments`` vertices, angle ``2 pi k / segments`` from +X toward +Z.
    """
    n = int(opts.segments)
    nr = int(opts.rings) + int(opts.underside_rings)
    faces = []
    k = np.arange(n)
    k1 = (k + 1) % n
    # apex fan: the top faces +Y (counter-clockwise seen from above: apex, next, this)
    first = 1
    faces.append(np.stack([np.zeros(n, int), first + k1, first + k], axis=1))
    for i in range(nr - 1):
        a = 1 + i * n
        b = a + n
        faces.append(np.stack([a + k, a + k1, b + k], axis=1))
        faces.append(np.stack([a + k1, b + k1, b + k], axis=1))
    centre = 1 + nr * n
    last = 1 + (nr - 1) * n
    faces.append(np.stack([np.full(n, centre), last + k, last + k1], axis=1))
    return np.concatenate(faces).astype(np.int32)


def receptacle_mesh(prof: Profile, opts: ReceptacleOptions) -> ObjMesh:
    """The closed receptacle of generating curve ``prof`` (already scaled to the frame's size)."""
    n, nt, nu = int(opts.segments), int(opts.rings), int(opts.underside_rings)
    ang = 2.0 * math.pi * np.arange(n) / n
    c, s = np.cos(ang), np.sin(ang)
    # the top: rings evenly spaced in arc length, the first at one ring spacing from the apex
    sv = np.linspace(0.0, prof.length, nt + 1)[1:]
    at = prof.at(sv)
    r_top = at["r"] - opts.inset * at["nr"]
    y_top = at["y"] - opts.inset * at["ny"]
    apex_y = float(prof.y[0]) - opts.inset
    rim_r, rim_y = float(r_top[-1]), float(y_top[-1])
    size = max(float(prof.r.max()), 1e-12)
    stem_r = opts.stem * size
    phi = np.linspace(0.0, 0.5 * math.pi, nu + 1)[1:]
    r_low = stem_r + (rim_r - stem_r) * np.cos(phi)
    y_low = rim_y - opts.depth * size * np.sin(phi)
    rr = np.concatenate([r_top, r_low])
    yy = np.concatenate([y_top, y_low])
    ring = np.empty((len(rr), n, 3))
    ring[:, :, 0] = rr[:, None] * c[None, :]
    ring[:, :, 1] = yy[:, None]
    ring[:, :, 2] = rr[:, None] * s[None, :]
    verts = np.concatenate([[[0.0, apex_y, 0.0]], ring.reshape(-1, 3), [[0.0, float(y_low[-1]), 0.0]]])
    faces = receptacle_topology(opts)
    return ObjMesh(verts, faces, groups=["receptacle"], face_group=np.zeros(len(faces), np.int32),
                   materials=[f"mtl{int(opts.material)}"], face_material=np.zeros(len(faces), np.int32))
