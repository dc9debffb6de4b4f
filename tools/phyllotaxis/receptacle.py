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
``stem · rim radius`` at ``depth · rim radius`` below the rim, closed by a disc (with
``stem_length`` > 0, at the end of a stump of the stem that long, in rim radii). Rings of the top
are spaced evenly in arc length; ``segments`` vertices per ring.

With ``phyllary_rows`` > 0 the underside carries the **phyllaries** of the involucre's outer
series: the back of a sunflower or gaillardia head, clothed in overlapping bracts (the thesis's
Gaillardia "incorporates involucral bracts: specialized leaves that surround the head and protect
it in its early development", ch. 9, with fig. 9.4; the canopy's bracts are one ring at the rim).
Rows of ovate, acuminate bracts lie on the underside, each row on its own offset surface along
the normal (``phyllary_gap`` apart, the row nearest the stem outermost), staggered half a spacing
against the next, its bracts narrower than their spacing, its tips overlapping the bases of the
row above like roof tiles and lifting off (``phyllary_spread``) only where no row lies over them.
Every distance is a fraction of the rim radius, so the bracts grow with the head and never touch
one another or the receptacle (:func:`phyllaries`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from inflo.formats.obj import ObjMesh

from .surface import Profile

__all__ = [
    "PHYLLARY_VERTICES",
    "ReceptacleOptions",
    "phyllaries",
    "phyllary_sagitta",
    "receptacle_mesh",
    "receptacle_topology",
]


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
    stem_length: float = 0.0
    phyllary_rows: int = 0
    phyllaries: int = 21
    phyllary_length: float = 0.45
    phyllary_width: float = 0.85
    phyllary_gap: float = 0.006
    phyllary_spread: float = 0.0
    phyllary_top: float = 0.0
    phyllary_variation: float = 0.1
    phyllary_seed: int = 1
    phyllary_material: int = 4


def receptacle_topology(opts: ReceptacleOptions) -> np.ndarray:
    """(m, 3) int32 triangles (outward facing) of the closed receptacle; the same every frame.

    Vertex layout: 0 = apex; then ``rings`` top rings (the last is the rim), ``underside_rings``
    rings of the underside (the last is the stem's rim), with ``stem_length`` > 0 one more ring
    (the stem's cut end), then the centre of the bottom disc.
    Every ring has ``segments`` vertices, angle ``2 pi k / segments`` from +X toward +Z.
    """
    n = int(opts.segments)
    nr = int(opts.rings) + int(opts.underside_rings) + (1 if opts.stem_length > 0 else 0)
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
    """The closed receptacle of generating curve ``prof`` (already scaled to the frame's size),
    with the phyllaries on its underside when ``opts.phyllary_rows`` > 0 (their vertices after the
    receptacle's, group ``phyllaries``, ``usemtl mtl<phyllary_material>``)."""
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
    r_low, y_low = _underside(phi, rim_r, rim_y, stem_r, opts.depth * size)
    if opts.stem_length > 0:  # a stump of the stem: its cut end stem_length x size below
        r_low = np.concatenate([r_low, [stem_r]])
        y_low = np.concatenate([y_low, [y_low[-1] - opts.stem_length * size]])
    rr = np.concatenate([r_top, r_low])
    yy = np.concatenate([y_top, y_low])
    ring = np.empty((len(rr), n, 3))
    ring[:, :, 0] = rr[:, None] * c[None, :]
    ring[:, :, 1] = yy[:, None]
    ring[:, :, 2] = rr[:, None] * s[None, :]
    verts = np.concatenate([[[0.0, apex_y, 0.0]], ring.reshape(-1, 3), [[0.0, float(y_low[-1]), 0.0]]])
    faces = receptacle_topology(opts)
    if opts.phyllary_rows <= 0:
        return ObjMesh(verts, faces, groups=["receptacle"], face_group=np.zeros(len(faces), np.int32),
                       materials=[f"mtl{int(opts.material)}"], face_material=np.zeros(len(faces), np.int32))
    pv, pf = phyllaries(rim_r, rim_y, stem_r, opts.depth * size, size, opts)
    part = np.concatenate([np.zeros(len(faces), np.int32), np.ones(len(pf), np.int32)])
    return ObjMesh(np.concatenate([verts, pv]), np.concatenate([faces, pf + len(verts)]).astype(np.int32),
                   groups=["receptacle", "phyllaries"], face_group=part,
                   materials=[f"mtl{int(opts.material)}", f"mtl{int(opts.phyllary_material)}"], face_material=part)


def _underside(phi, rim_r: float, rim_y: float, stem_r: float, depth: float):
    """(r, y) of the underside's quarter ellipse at parameter ``phi`` (0 at the rim, pi/2 at the
    stem): semi-axes ``rim_r - stem_r`` across and ``depth`` down, centred at (stem_r, rim_y)."""
    return stem_r + (rim_r - stem_r) * np.cos(phi), rim_y - depth * np.sin(phi)


def _underside_arc(rim_r: float, rim_y: float, stem_r: float, depth: float):
    """The underside's parameter (0 at the rim, pi/2 at the stem: 1025 samples) and the arc
    length from the rim at each (a table :func:`numpy.interp` inverts)."""
    phi = np.linspace(0.0, 0.5 * math.pi, 1025)
    r, y = _underside(phi, rim_r, rim_y, stem_r, depth)
    return phi, np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(r), np.diff(y)))])


# a phyllary's half-width along its length (0 = base, 1 = tip), a share of its widest: broadly
# ovate, widest a third of the way up, then narrowed into a long acuminate tip
_OUTLINE_U = np.array([0.0, 0.15, 0.35, 0.55, 0.75, 0.9, 1.0])
_OUTLINE_W = np.array([0.7, 0.92, 1.0, 0.9, 0.55, 0.22, 0.0])
_ALONG = 16  # stations from base to tip (the tip one vertex)
_ACROSS = 5  # vertices across (odd: the midrib in the middle)
#: vertices of one phyllary
PHYLLARY_VERTICES = (_ALONG - 1) * _ACROSS + 1


def phyllaries(rim_r: float, rim_y: float, stem_r: float, depth: float, size: float,
               opts: ReceptacleOptions) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (v, 3) and outward triangles (f, 3) of the ``phyllary_rows`` rows of
    ``phyllaries`` bracts on the underside (the quarter ellipse of :func:`_underside`).

    Row j (0 at the rim) spans the meridian arc ``[t_j, t_j + l]`` of the underside, l =
    ``phyllary_length`` x its arc length, its base toward the stem; the rows are spaced evenly so
    that the first one's tip is ``phyllary_top`` of the arc below the rim (0: at the rim) and the
    last one's base 4 % of the arc above the stem. Row j lies ``(j + 1) x phyllary_gap x size``
    off the underside along its normal, so the rows nearer the stem lie over the bases of those
    above (the outer series of an imbricate involucre); a low midrib (a quarter of the gap) keels
    each bract. Its bracts are centred at angles ``2 pi (k + j/2) / phyllaries`` and at most
    ``phyllary_width`` of that spacing wide. The part of a row that no later row covers (its upper
    ``step``) lifts off the surface towards its tip by up to ``phyllary_spread x size``.

    Each bract is its own (``phyllary_variation`` v, seeded by ``phyllary_seed``, the same in
    every frame): up to v shorter (its base where the row's is), up to v narrower, shifted by up
    to v of its half-slot within the slack of the slot, its tip lifting up to 3v less. It only
    ever gives up room, so what holds for bracts alike holds for these.

    Rows on separate offset surfaces (outward, on the convex side of the underside, so they never
    fold) and bracts apart within a row: the bracts touch neither one another nor the receptacle,
    whatever the size, as long as a bract's flat triangles stray from their offset surface by
    less than the space between two rows (:func:`phyllary_sagitta`, which ``phyllotaxis``
    checks).
    """
    rows, per = int(opts.phyllary_rows), int(opts.phyllaries)
    phi, arc = _underside_arc(rim_r, rim_y, stem_r, depth)
    total = float(arc[-1])
    length = opts.phyllary_length * total
    t0, t_end = opts.phyllary_top * total, 0.96 * total
    step = (t_end - length - t0) / (rows - 1) if rows > 1 else 0.0
    step = max(step, 0.0)
    u = np.linspace(0.0, 1.0, _ALONG)
    half = np.interp(u, _OUTLINE_U, _OUTLINE_W) * opts.phyllary_width * math.pi / per
    v_across = np.linspace(-1.0, 1.0, _ACROSS)
    keel = 0.25 * opts.phyllary_gap * size * (1.0 - v_across ** 2)
    out_v, out_f = [], []
    base_faces = _phyllary_faces()
    nv = PHYLLARY_VERTICES
    count = 0
    # each bract its own (seeded, the same in every frame): shorter, narrower, shifted within its
    # slot, its tip lifting less
    rng = np.random.default_rng(int(opts.phyllary_seed))
    draw = rng.random((rows, per, 4))
    var = float(opts.phyllary_variation)
    for j in range(rows):
        tip = t0 + j * step
        free = 0.7 * step if rows > 1 else 0.7 * length
        for k in range(per):
            shorter, narrower, shift, lifts = draw[j, k]
            own = length * (1.0 - var * shorter)
            a = tip + length - own * u  # arc of each station (base first; the base where the row's is)
            ph = np.interp(a, arc, phi)
            pr, py = _underside(ph, rim_r, rim_y, stem_r, depth)
            # the outward normal of the ellipse (r, y) = (stem + A cos, rim - B sin): (B cos, -A sin)
            nr_, ny_ = depth * np.cos(ph), -(rim_r - stem_r) * np.sin(ph)
            norm = np.hypot(nr_, ny_)
            norm = np.where(norm > 0, norm, 1.0)
            nr_, ny_ = nr_ / norm, ny_ / norm
            spread = opts.phyllary_spread * max(1.0 - 3.0 * var * lifts, 0.0)
            lift = spread * size * np.clip((tip + free - a) / max(free, 1e-300), 0.0, 1.0) ** 2
            off = (j + 1) * opts.phyllary_gap * size + lift  # (stations,)
            # stations x across: offset, radius, height and angle of every vertex; the bract's
            # half-width and shift keep it inside its slot of 2 pi / per
            o = off[:, None] + keel[None, :]
            vr = pr[:, None] + o * nr_[:, None]
            vy = py[:, None] + o * ny_[:, None]
            w = 1.0 - var * narrower
            slack = (1.0 - opts.phyllary_width * w) * math.pi / per
            centre = (2.0 * math.pi * (k + 0.5 * (j % 2)) / per
                      + min(0.9 * slack, var * math.pi / per) * (2.0 * shift - 1.0))
            th = centre + w * half[:, None] * v_across[None, :]
            xyz = np.stack([vr * np.cos(th), vy, vr * np.sin(th)], axis=-1)
            # the tip: one vertex on the midrib
            pts = np.concatenate([xyz[:-1].reshape(-1, 3), xyz[-1:, _ACROSS // 2]])
            out_v.append(pts)
            out_f.append(base_faces + count * nv)
            count += 1
    return np.concatenate(out_v), np.concatenate(out_f).astype(np.int32)


def phyllary_sagitta(opts: ReceptacleOptions) -> float:
    """How far (a fraction of the rim radius) a phyllary's triangle edges along the meridian
    stray inward from the curved offset surface they lie on, at the underside's tightest bend:
    ``d^2 / (8 rho)``, d a station's arc length, rho the least radius of curvature of the quarter
    ellipse (semi-axes ``1 - stem`` and ``depth``: ``min(a^2/b, b^2/a)``). The bracts of two rows
    stay apart while this is under half of ``phyllary_gap`` (a quarter goes to the midrib)."""
    a, b = max(1.0 - opts.stem, 1e-12), max(opts.depth, 1e-12)
    total = float(_underside_arc(1.0, 0.0, 1.0 - a, b)[1][-1])
    station = opts.phyllary_length * total / (_ALONG - 1)
    return station * station / (8.0 * min(a * a / b, b * b / a))


def _phyllary_faces() -> np.ndarray:
    """Triangles of one phyllary: a grid of ``_ALONG - 1`` stations x ``_ACROSS`` vertices (base
    first), then a fan to the tip vertex; wound to face away from the receptacle."""
    faces = []
    for i in range(_ALONG - 2):
        for k in range(_ACROSS - 1):
            a, b = i * _ACROSS + k, i * _ACROSS + k + 1
            c, d = a + _ACROSS, b + _ACROSS
            faces += [(a, c, b), (b, c, d)]
    last, tip = (_ALONG - 2) * _ACROSS, (_ALONG - 1) * _ACROSS
    for k in range(_ACROSS - 1):
        faces.append((last + k, tip, last + k + 1))
    return np.asarray(faces, np.int32)
