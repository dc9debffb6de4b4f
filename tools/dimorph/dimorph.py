"""Set floret types and sizes in a scene (thesis ch. 6): the library behind the ``dimorph`` CLI."""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from inflo.formats.errors import InputError
from inflo.formats.scn import Scene

from .cones import FATE_DISK, FATE_RAY, FATE_SMALL_RAY, d_min, fates

__all__ = ["DimorphOptions", "group_centres", "dimorph_scene"]

TYPE_LABELS = {FATE_DISK: "disk", FATE_RAY: "ray", FATE_SMALL_RAY: "small_ray"}


@dataclass
class DimorphOptions:
    """Flags of ``dimorph`` (see its ``--help``).

    alpha : cone opening angle, degrees (full angle unless ``half_angle``)
    thresholds : () ray iff no floret in the cone; (Th,) ray iff d_min > Th; (Th_a, Th_b) large ray
        iff d_min > Th_b, small ray iff Th_a < d_min <= Th_b (fig. 6.4c)
    ray_id, disk_id, small_ray_id : floret type ids written into the placements
    ray_scale, disk_scale : factors applied to each placement's scale by fate; a small ray floret
        gets ``ray_scale * d_min / Th_b`` (size proportional to the available space, fig. 6.4c)
    centre : ``group`` (the floret's own head/umbellet) or ``top`` (its top-level group)
    """

    alpha: float
    thresholds: tuple = ()
    ray_id: int = 1
    disk_id: int = 0
    small_ray_id: int | None = None
    ray_scale: float = 1.0
    disk_scale: float = 1.0
    centre: str = "group"
    half_angle: bool = False


def group_centres(scene: Scene, how: str = "group") -> np.ndarray:
    """(n, 3) centre O of each placement's head or umbellet.

    Placements without a group share one head whose centre is their centroid (no group lines: one
    head, centre = centroid). ``how = "top"`` uses the top-level ancestor group instead.
    """
    arr = scene.arrays()
    n = len(scene)
    out = np.empty((n, 3))
    no_group = arr["group"] < 0
    if no_group.any():
        out[no_group] = arr["pos"][no_group].mean(axis=0)
    for k in np.nonzero(~no_group)[0]:
        g = scene.groups[int(arr["group"][k])]
        if how == "top":
            while g.parent != -1:
                g = scene.groups[g.parent]
        out[k] = g.centre
    return out


def dimorph_scene(scene: Scene, opts: DimorphOptions) -> tuple[Scene, dict]:
    """A copy of ``scene`` with each placement's id, scale and ``#@ type`` set by its fate.

    Placement order (each floret's identity) is kept. Returns the new scene and counts
    ``{"ray": N, "small_ray": M, "disk": K}`` plus ``d_min`` (n,) float64.
    """
    if not 0.0 < opts.alpha < 360.0:
        raise InputError(f"--alpha {opts.alpha} outside (0, 360) degrees")
    th = tuple(sorted(float(t) for t in opts.thresholds))
    if any(t < 0 or not math.isfinite(t) for t in th) or len(th) > 2:
        raise InputError(f"thresholds must be one or two finite numbers >= 0, found {opts.thresholds}")
    if len(scene) == 0:
        raise InputError("the scene has no placements")
    arr = scene.arrays()
    centre = group_centres(scene, opts.centre)
    radius = max(th) if th else math.inf
    dmin = d_min(arr["pos"], centre, opts.alpha, radius=radius, half_angle=opts.half_angle)
    fate = fates(dmin, th)
    small_id = opts.ray_id if opts.small_ray_id is None else opts.small_ray_id
    out = copy.deepcopy(scene)
    for k, p in enumerate(out.placements):
        f = int(fate[k])
        if f == FATE_RAY:
            p.id, factor = opts.ray_id, opts.ray_scale
        elif f == FATE_SMALL_RAY:
            p.id, factor = small_id, opts.ray_scale * dmin[k] / th[1]
        else:
            p.id, factor = opts.disk_id, opts.disk_scale
        p.scale = p.scale * factor
        p.type = TYPE_LABELS[f]
    counts = {TYPE_LABELS[c]: int(np.sum(fate == c)) for c in TYPE_LABELS}
    return out, {**counts, "d_min": dmin}
