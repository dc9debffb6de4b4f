"""Individual florets: each floret of a ``variation`` id gets its own deformed copy of its template.

formats/fcc.md, "Individual florets", is the specification. A floret's draws
(:func:`floret_draws`) depend on the line's seed and the floret's index only; its template's
every frame is deformed by one pure kernel (:func:`vary_frames`), so that its rest lengths and
angles, which the solver keeps (thesis eqs. 3.11, 3.13), are its own at every stage: the collision
shaping of the thesis's fig. 9.8 then starts from florets that already differ, as real ones do.
"""
from __future__ import annotations

import copy
import math

import numpy as np
from numba import njit

from inflo.formats.variation import FIELDS, Variation

#: scale factors are kept within these bounds
SCALE_BOUNDS = (0.5, 2.0)
_SQRT3 = math.sqrt(3.0)


def floret_draws(variation: Variation, index: int) -> dict:
    """Floret ``index``'s values of every field: ``z = sqrt(3) (u1 + u2 + u3 + u4 - 2)`` from four
    uniforms of PCG64 seeded ``(seed, index)`` per field in :data:`FIELDS` order (Irwin-Hall: mean
    0, variance 1, |z| <= 3.46; sums and products only, the same bits on every machine), times the
    field's spread. Scale fields give factors ``1 + sigma z`` within :data:`SCALE_BOUNDS`, angles
    degrees, timing frames."""
    rng = np.random.Generator(np.random.PCG64([int(variation.seed), int(index)]))
    u = rng.random(4 * len(FIELDS)).reshape(len(FIELDS), 4)
    out = {}
    for k, (name, sigma) in enumerate(zip(FIELDS, variation.spreads())):
        z = _SQRT3 * ((((u[k, 0] + u[k, 1]) + u[k, 2]) + u[k, 3]) - 2.0)
        if FIELDS[name][1] == "fraction":
            out[name] = min(max(1.0 + sigma * z, SCALE_BOUNDS[0]), SCALE_BOUNDS[1])
        else:
            out[name] = sigma * z
    return out


@njit(cache=True)
def vary_frames(frames, scale, axis, twist, droop, rho_max, along_max):
    """A copy of ``frames`` ((F, nv, 3) local positions) deformed, vertex by vertex:

    1. scaled by ``scale`` (3,) along local X, Y, Z (about the base, the origin);
    2. twisted about the unit ``axis`` (3,) through the origin by ``twist * s / along_max``
       radians, ``s`` the vertex's coordinate along the axis (0 where s <= 0);
    3. bent about local Z by ``droop * rho / rho_max`` radians downwards (+X towards -Y for a
       positive ``droop``), ``rho = sqrt(x^2 + y^2)``.

    ``rho_max``, ``along_max`` > 0 are the template's own (the largest over its frames), so the
    bend and twist grow with the organ. Pure; no allocation but the result."""
    nf, nv = frames.shape[0], frames.shape[1]
    out = np.empty_like(frames)
    for f in range(nf):
        for v in range(nv):
            x = frames[f, v, 0] * scale[0]
            y = frames[f, v, 1] * scale[1]
            z = frames[f, v, 2] * scale[2]
            if twist != 0.0:
                s = x * axis[0] + y * axis[1] + z * axis[2]
                if s > 0.0:
                    a = twist * s / along_max
                    c, sn = math.cos(a), math.sin(a)
                    # Rodrigues: p c + (k x p) s + k (k . p)(1 - c)
                    kx = axis[1] * z - axis[2] * y
                    ky = axis[2] * x - axis[0] * z
                    kz = axis[0] * y - axis[1] * x
                    x, y, z = (x * c + kx * sn + axis[0] * s * (1.0 - c),
                               y * c + ky * sn + axis[1] * s * (1.0 - c),
                               z * c + kz * sn + axis[2] * s * (1.0 - c))
            if droop != 0.0:
                rho = math.sqrt(x * x + y * y)
                a = -droop * rho / rho_max
                c, sn = math.cos(a), math.sin(a)
                x, y = x * c - y * sn, x * sn + y * c
            out[f, v, 0] = x
            out[f, v, 1] = y
            out[f, v, 2] = z
    return out


def template_axis(frames: np.ndarray) -> np.ndarray:
    """Unit vector from the base (origin) to the centroid of the last frame; +Y where that is ~0."""
    c = frames[-1].mean(axis=0)
    n = math.sqrt(float(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]))
    return np.array([0.0, 1.0, 0.0]) if n <= 1e-12 else c / n


def varied(template, variation: Variation, index: int, petal: float = 1.0):
    """Floret ``index``'s own copy of ``template`` (``inflo.tools.fccompose.model.Template``, as
    read: the petal factor ``petal`` of its placement is applied here, times the drawn one), and
    its timing shift in frames. The copy's key is ``(id, "floret", index)``."""
    d = floret_draws(variation, index)
    factor = float(petal) * (d["petal"] if variation.petal else 1.0)
    base = template.with_petals(factor) if factor != 1.0 else template
    frames = base.frames
    scale = np.array([d["size"] * d["length"], d["size"] * d["height"], d["size"] * d["width"]])
    scaled = frames * scale
    axis = template_axis(scaled)
    rho = np.sqrt(scaled[..., 0] ** 2 + scaled[..., 1] ** 2)
    along = scaled[..., 0] * axis[0] + scaled[..., 1] * axis[1] + scaled[..., 2] * axis[2]
    rho_max, along_max = max(float(rho.max()), 1e-300), max(float(along.max()), 1e-300)
    out = copy.copy(base)
    out.frames = vary_frames(np.ascontiguousarray(frames, np.float64), scale, axis,
                             math.radians(d["twist"]), math.radians(d["droop"]), rho_max, along_max)
    out.key = (template.id, "floret", int(index))
    return out, float(d["timing"])
