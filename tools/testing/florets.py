"""Synthetic opening florets and scenes for tests, examples and benchmarks (stand-ins until
``polygonize`` output exists).

A floret is a fan of curved petal strips (:func:`inflo.tools.testing.flowers.petal`) whose
bases sit on a small ring around the floret axis (+Y) and which open from an upright bud to a
spread flower over the frames. The base row of every petal is fixed (weight file). Petals of one
floret never touch each other in any frame.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from inflo.formats.atomic import write_text_atomic
from inflo.formats.obj import ObjMesh, write_obj_sequence
from inflo.formats.scn import Placement, Scene, write_scn
from inflo.tools.testing.flowers import midrib_directions, petal_patch

__all__ = ["petal_strip", "opening_floret", "write_floret_animation", "write_scene", "write_fcc_text",
           "two_floret_scene", "grid_canopy_scene"]


def petal_strip(phi: float, *, length: float, width: float, rise: float, bend: float, cup: float, nu: int,
                nv: int, base) -> tuple[np.ndarray, np.ndarray]:
    """One curved petal leaving ``base`` at azimuth ``phi``: the midrib and cross-section of
    ``testing.flowers.petal`` (:func:`~inflo.tools.testing.flowers.petal_patch`), with a base
    as wide as half the petal so that the two fixed base rows hold its orientation, and the midrib
    stepped from the base point itself.

    Returns ``(nu nv, 3)`` vertices (row-major, u along the midrib slow) and the grid's triangles.
    """
    u = np.linspace(0.0, 1.0, nu)
    d_spine = midrib_directions(phi, u, rise, bend)
    step = np.full(nu, length / (nu - 1))
    spine = np.concatenate([[np.zeros(3)], np.cumsum(d_spine[:-1] * step[:-1, None], axis=0)])
    half_w = width * (0.45 + 0.55 * np.sin(np.pi * np.clip(0.5 + 0.5 * u, 0.0, 1.0)) ** 0.5 * (1.0 - 0.6 * u ** 2))
    return petal_patch(phi, spine, d_spine, half_w, cup=cup, nv=nv, base=base)


def opening_floret(n_frames: int = 10, *, n_petals: int = 5, length: float = 1.0, width: float = 0.16,
                   base_radius: float = 0.25, nu: int = 9, nv: int = 4, closed: tuple = (84.0, 4.0),
                   opened: tuple = (10.0, 35.0), cup: float = 0.3):
    """An opening floret as an OBJ sequence in its local frame (axis +Y, base at the origin).

    Parameters
    ----------
    n_frames : int
        Frames of the opening (>= 1).
    n_petals : int
        Petals, evenly spread in azimuth.
    length, width : float
        Petal length and half-width scale (scene units).
    base_radius : float
        Radius of the ring the petal bases sit on.
    nu, nv : int
        Vertices along and across each petal.
    closed, opened : (rise, bend) degrees
        Midrib angle above the horizontal at the base and its outward turn to the tip, for the
        first and last frame (linear in between).
    cup : float
        Cupping of the cross-section.

    Returns
    -------
    frames : list of (n, 3) float64
        Vertex positions per frame (same vertex order).
    faces : (m, 3) int32
    fixed : (k,) int32
        Vertex ids of the petal bases, two rows (the weight file).
    """
    frames = []
    faces = fixed = None
    for f in range(n_frames):
        s = 0.0 if n_frames == 1 else f / (n_frames - 1)
        rise = closed[0] + s * (opened[0] - closed[0])
        bend = closed[1] + s * (opened[1] - closed[1])
        verts, fcs, fxd = [], [], []
        off = 0
        for k in range(n_petals):
            phi = 2.0 * math.pi * k / n_petals
            base = (base_radius * math.sin(phi), 0.0, base_radius * math.cos(phi))
            v, t = petal_strip(phi, length=length, width=width, rise=rise, bend=bend, cup=cup, nu=nu,
                               nv=nv, base=base)
            verts.append(v)
            fcs.append(t + off)
            fxd.append(np.arange(2 * nv) + off)
            off += len(v)
        frames.append(np.concatenate(verts))
        faces = np.concatenate(fcs).astype(np.int32)
        fixed = np.concatenate(fxd).astype(np.int32)
    return frames, faces, fixed


def write_floret_animation(folder, frames, faces, fixed=None, weight_path=None) -> list[Path]:
    """Write the frames as ``folder/frame_0000.obj``... and the fixed ids as a weight file."""
    paths = write_obj_sequence(folder, [ObjMesh(v, faces) for v in frames])
    if weight_path is not None and fixed is not None:
        write_text_atomic(weight_path, "# fixed vertex ids (0-based, OBJ vertex order)\n"
                          + "\n".join(str(int(i)) for i in fixed) + "\n")
    return paths


def write_scene(path, placements) -> None:
    """Write an SCN file of :class:`~inflo.formats.scn.Placement` objects."""
    write_scn(path, Scene(list(placements)))


def write_fcc_text(path, *, scene="scene.scn", animation="anim", weight="petal_base.txt", frames=None,
                   solver_iterations=20, collision_iterations=10, retries=20, spacing=0.01,
                   k_stretch=0.99, k_bend=0.99, updates_per_frame=1, sanity_every=1, extra="") -> None:
    """A ``.fcc`` file for one animation (id 0) placed by ``scene``."""
    lines = [
        "# synthetic canopy (inflo.tools.testing.florets)",
        f"solver iterations: {solver_iterations}",
        f"collision iterations: {collision_iterations}",
        f"max collision retries: {retries}",
        f"kStretch: {k_stretch}",
        f"kBend: {k_bend}",
        "kCollision: 1.0",
        f"spacing: {spacing}",
        f"updates per frame: {updates_per_frame}",
        f"sanity check per frames: {sanity_every}",
        f"scene file path: {scene}",
        f"animation: 0 1 1 1 {animation}",
    ]
    if weight:
        lines.append(f"weight: 0 {weight}")
    if frames is not None:
        lines.append(f"run for number of frames: {frames}")
    write_text_atomic(path, "\n".join(lines) + "\n" + extra)


def two_floret_scene(n_frames: int, *, distance: float = 1.0, lift: float = 0.0, tilt: float = 0.0):
    """Two florets (id 0) opening into each other: the dense test scene.

    The second floret stands ``distance`` away along +X and ``lift`` higher, both tilted towards
    each other by ``tilt`` degrees; the second is turned about its axis so that petals do not
    mirror each other. With the defaults the open templates overlap by some 40 triangle pairs,
    the buds (frame 0) not at all. Materials 1 and 2.
    """
    t = math.radians(tilt)
    a = Placement("ca", 0, [0, 0, 0], [1, 1, 1], [math.sin(t), math.cos(t), 0], [math.cos(t), -math.sin(t), 0],
                  frame_start=0, frame_end=n_frames - 1, material=1)
    b = Placement("ca", 0, [distance, lift, 0.0], [1, 1, 1], [-math.sin(t), math.cos(t), 0], [0.3, 0.0, 1.0],
                  frame_start=0, frame_end=n_frames - 1, material=2)
    return [a, b]


def grid_canopy_scene(n_florets: int, n_frames: int, *, spacing: float = 1.6, seed: int = 0):
    """``n_florets`` florets (id 0) on a jittered square grid, close enough that open petals meet."""
    rng = np.random.default_rng(seed)
    side = int(math.ceil(math.sqrt(n_florets)))
    out = []
    for k in range(n_florets):
        i, j = divmod(k, side)
        pos = [i * spacing + rng.uniform(-0.05, 0.05), rng.uniform(0.0, 0.15), j * spacing + rng.uniform(-0.05, 0.05)]
        phi = rng.uniform(0, 2 * math.pi)
        out.append(Placement("ca", 0, pos, [1, 1, 1], [0, 1, 0], [math.cos(phi), 0, math.sin(phi)],
                             frame_start=0, frame_end=n_frames - 1, material=1 + (k % 3)))
    return out
