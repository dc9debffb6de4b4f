"""Set floret types and sizes in a scene (thesis ch. 6): the library behind the ``dimorph`` CLI."""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from inflo.formats.errors import InputError
from inflo.formats.scn import MAX_FRAME, Scene
from inflo.tools.common import linalg as la

from .cones import FATE_DISK, FATE_RAY, FATE_SMALL_RAY, d_min, fates

__all__ = ["DimorphOptions", "group_centres", "dimorph_scene"]

TYPE_LABELS = {FATE_DISK: "disk", FATE_RAY: "ray", FATE_SMALL_RAY: "small_ray"}
FATE_BRACT = -1


@dataclass
class DimorphOptions:
    """Flags of ``dimorph`` (see its ``--help``).

    alpha : cone opening angle, degrees (full angle unless ``half_angle``)
    thresholds : () ray iff no floret in the cone; (Th,) ray iff d_min > Th; (Th_a, Th_b) large ray
        iff d_min > Th_b, small ray iff Th_a < d_min <= Th_b (fig. 6.4c)
    ray_id, disk_id, small_ray_id : floret type ids written into the placements
    ray_scale, disk_scale : factors applied to each placement's scale by fate; a small ray floret
        gets ``small_ray_scale * d_min / Th_b`` (size proportional to the available space, fig.
        6.4c; ``small_ray_scale`` None: ``ray_scale``, so the small rays' sizes run up to the large
        ones')
    centre : ``group`` (the floret's own head/umbellet) or ``top`` (its top-level group)
    ray_lead : frames by which ray and small ray florets develop ahead of the others: their
        ``frameStart`` and ``frameEnd`` both move that much earlier (negative: later), rounded to
        whole frames, ``frameStart`` kept >= 0 and ``frameEnd`` >= ``frameStart + 1``
    ray_development_frames, disk_development_frames : None, or N > 0: ``frameEnd = frameStart + N``
        for ray and small ray (resp. disk) florets, before the lead is applied
    bract_development_frames : None, or N > 0: ``frameEnd = frameStart + N`` for the involucral
        bracts (no lead). A head's bracts and rays are its first primordia; with windows longer
        than the disk florets' they open with the head, round florets to surround, instead of
        standing open round a naked meristem (thesis fig. 9.6: the involucre and the rays unfold
        as the outer disk florets reach anthesis)
    bracts : the ``bracts`` outermost placements of each head (by distance from its centre O; ties by
        placement order) are involucral bracts: type ``bract``, id ``bract_id``, scale factor
        ``bract_scale``, their windows set by ``bract_development_frames`` only. They are leaves,
        not florets: the cone
        test (eq. 6.1) of the other placements ignores them, so the florets just inside the
        involucre are the ones whose cones can be empty (the bracts of a capitulum are its first,
        outermost primordia, formed in the same phyllotactic sequence as the florets)
    petal_size : the ray and small ray florets' size factors (``ray_scale``, ``ray_scale * d_min /
        Th_b``) go to their ``#@ petal:`` factor instead of their scale: fccompose grows only the
        template's petals (its ``petal weight`` file) by it, not the whole floret (fig. 6.4c:
        "the size of the enlarged petals is proportional to the amount of available space")
    orient_rays : ``none``, ``group`` or ``top``: turn each (large) ray floret about its ``up`` axis
        so that its local +X (the outward petal of a zygomorphic floret) points away from its
        group's or its top-level group's centre (the periphery of the whole inflorescence, fig.
        6.4c). With ``top``, a ray floret whose cone axis (away from its own group's centre: where
        its free space is) points towards the top-level centre, e.g. one facing a gap inside the
        inflorescence, is turned along its cone axis instead. Placements whose orientation comes
        from RBA files (``rba``) are refused
    marginal : 0, or N > 0: only the N outermost placements of each head after its bracts (by
        distance from its centre O, as ``bracts``) may be ray or small ray florets; the others are
        disk florets whatever their cones (the ray florets of a capitulum are its marginal ones:
        a head at the rim of a corymb, whose cones point into open space on one whole side, still
        keeps its inner florets disk florets)
    Windows are changed only on placements that have one (``ca``, ``ta``, ``ra``, ``rba``).
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
    ray_lead: float = 0.0
    ray_development_frames: int | None = None
    disk_development_frames: int | None = None
    bracts: int = 0
    bract_id: int = 2
    bract_scale: float = 1.0
    petal_size: bool = False
    orient_rays: str = "none"
    small_ray_scale: float | None = None
    marginal: int = 0
    bract_development_frames: int | None = None


def orient_outward(p, centre) -> bool:
    """Turn placement ``p`` about its ``up`` so that ``right`` points away from ``centre`` (the
    component of ``pos - centre`` orthogonal to ``up``); False (unchanged) where that is ~0."""
    up = la.normalize(np.asarray(p.up, float))
    d = np.asarray(p.pos, float) - np.asarray(centre, float)
    d = d - la.dot(d, up) * up
    n = la.norm(d)
    if n <= 1e-12 * max(1.0, la.norm(p.pos)):
        return False
    p.right = d / n
    return True


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


WINDOW_KINDS = ("ca", "ta", "ra", "rba")


def _round_frame(x: float) -> int:
    return int(math.floor(x + 0.5))


def shift_window(p, development_frames: int | None, lead: float) -> bool:
    """Set ``p``'s developmental window in place (see :class:`DimorphOptions`); True if it has one."""
    if p.kind not in WINDOW_KINDS or p.frame_start is None or p.frame_end is None:
        return False
    start, end = int(p.frame_start), int(p.frame_end)
    if development_frames is not None:
        end = start + int(development_frames)
    if lead:
        start, end = _round_frame(start - lead), _round_frame(end - lead)
        start = max(start, 0)
        end = max(end, start + 1)
    if end > MAX_FRAME:
        raise InputError(f"expected developmental windows that end by frame {MAX_FRAME} (as a scene's frames), "
                         f"found frameEnd {end} for placement id {p.id} (frames {p.frame_start} {p.frame_end})")
    p.frame_start, p.frame_end = start, end
    return True


def outermost(pos: np.ndarray, centre: np.ndarray, group: np.ndarray, count: int) -> np.ndarray:
    """(n,) bool: the ``count`` placements of each group farthest from their centre O.

    Distances are compared after rounding to 1e-9 of the head's size, so that a pattern's
    floating-point noise does not decide between florets at one distance; ties go by placement
    order (the earlier placement is the outer one, as in a centripetal head's formation order).
    """
    n = len(pos)
    out = np.zeros(n, dtype=bool)
    if count <= 0 or n == 0:
        return out
    d = la.norm(np.asarray(pos, float) - np.asarray(centre, float), axis=1)
    for g in np.unique(group):
        rows = np.nonzero(group == g)[0]
        scale = max(float(d[rows].max()), 1e-300)
        key = np.round(d[rows] / scale * 1e9)
        order = np.lexsort((rows, -key))
        out[rows[order[:count]]] = True
    return out


def check_window_options(opts: DimorphOptions) -> None:
    """InputError (one line) for a non-finite lead or a development window that is not > 0."""
    if not math.isfinite(opts.ray_lead):
        raise InputError(f"--ray-lead must be a finite number of frames, found {opts.ray_lead}")
    if not abs(opts.ray_lead) <= MAX_FRAME:
        raise InputError(f"--ray-lead must be a number of frames within +-{MAX_FRAME}, found {opts.ray_lead:g}")
    for name, v in (("--ray-development-frames", opts.ray_development_frames),
                    ("--disk-development-frames", opts.disk_development_frames),
                    ("--bract-development-frames", opts.bract_development_frames)):
        if v is not None and (isinstance(v, bool) or int(v) != v or v <= 0):
            raise InputError(f"{name} must be an integer > 0, found {v}")
        if v is not None and v > MAX_FRAME:
            raise InputError(f"{name} must be an integer <= {MAX_FRAME} (a scene's frames), found {v}")


def dimorph_scene(scene: Scene, opts: DimorphOptions) -> tuple[Scene, dict]:
    """A copy of ``scene`` with each placement's id, scale, ``#@ type`` and window set by its fate.

    The scale is multiplied by the fate's factor (for ``rba:`` placements, whose SCN scale is a
    factor on every RBA row's scale, it becomes that factor). Windows: see :class:`DimorphOptions`.
    Placement order (each floret's identity) is kept. Returns the new scene and counts
    ``{"ray": N, "small_ray": M, "disk": K, "bract": B}``, ``windows`` (placements whose window was
    set), ``oriented`` (ray florets turned by ``orient_rays``) plus ``d_min`` (n,) float64 (inf for bracts).
    """
    top = 90.0 if opts.half_angle else 180.0
    if not 0.0 < opts.alpha <= top:
        what = "half-angle" if opts.half_angle else "opening angle"
        raise InputError(f"--alpha {opts.alpha} outside (0, {top:g}] degrees (the cone's {what}; a wider "
                         "'cone' would hold the directions towards the head's centre)")
    small_scale = opts.ray_scale if opts.small_ray_scale is None else float(opts.small_ray_scale)
    for name, v in (("--ray-scale", opts.ray_scale), ("--disk-scale", opts.disk_scale),
                    ("--bract-scale", opts.bract_scale), ("--small-ray-scale", small_scale)):
        if not 1e-6 <= v <= 1e6:
            raise InputError(f"{name} must be in [1e-06, 1e+06], found {v:g}")
    check_window_options(opts)
    if opts.orient_rays not in ("none", "group", "top"):
        raise InputError(f"--orient-rays must be none, group or top, found {opts.orient_rays!r}")
    th = tuple(sorted(float(t) for t in opts.thresholds))
    if any(t < 0 or not math.isfinite(t) for t in th) or len(th) > 2:
        raise InputError(f"thresholds must be one or two finite numbers >= 0, found {opts.thresholds}")
    if len(scene) == 0:
        raise InputError("the scene has no placements")
    arr = scene.arrays()
    centre = group_centres(scene, opts.centre)
    radius = max(th) if th else math.inf
    bract = outermost(arr["pos"], centre, arr["group"], int(opts.bracts))
    dmin = np.full(len(scene), np.inf)
    if (~bract).any():
        dmin[~bract] = d_min(arr["pos"][~bract], centre[~bract], opts.alpha, radius=radius,
                             half_angle=opts.half_angle)
    fate = fates(dmin, th)
    if int(opts.marginal) > 0:
        head = centre if opts.centre == "group" else group_centres(scene, "group")
        rim = outermost(arr["pos"], head, arr["group"], int(opts.bracts) + int(opts.marginal)) & ~bract
        fate[~rim & (fate != FATE_DISK)] = FATE_DISK
    fate[bract] = FATE_BRACT
    small_id = opts.ray_id if opts.small_ray_id is None else opts.small_ray_id
    orient_centre = None if opts.orient_rays == "none" else group_centres(scene, opts.orient_rays)
    own_centre = centre if opts.centre == "group" else group_centres(scene, "group")
    out = copy.deepcopy(scene)
    windows = oriented = 0
    for k, p in enumerate(out.placements):
        f = int(fate[k])
        if f == FATE_BRACT:
            p.id, p.type = opts.bract_id, "bract"
            p.scale = p.scale * opts.bract_scale
            if opts.bract_development_frames is not None and shift_window(p, opts.bract_development_frames, 0.0):
                windows += 1
            continue
        if f == FATE_RAY:
            p.id, factor = opts.ray_id, opts.ray_scale
        elif f == FATE_SMALL_RAY:
            p.id, factor = small_id, small_scale * dmin[k] / th[1]
        else:
            p.id, factor = opts.disk_id, opts.disk_scale
        if opts.petal_size and f != FATE_DISK:
            p.petal = (1.0 if p.petal is None else p.petal) * float(factor)
        else:
            p.scale = p.scale * factor
        if f == FATE_RAY and orient_centre is not None:
            if p.kind == "rba":
                raise InputError(f"--orient-rays: placement {k} is 'rba:' (its orientation comes from the RBA "
                                 "files); orient the rays of a static scene")
            target = orient_centre[k]
            if opts.orient_rays == "top" and la.dot(arr["pos"][k] - own_centre[k], arr["pos"][k] - target) < 0:
                target = own_centre[k]  # its free space faces the inflorescence's inside
            oriented += orient_outward(p, target)
        p.type = TYPE_LABELS[f]
        if f == FATE_DISK:
            n_frames, lead = opts.disk_development_frames, 0.0
        else:
            n_frames, lead = opts.ray_development_frames, float(opts.ray_lead)
        if (n_frames is not None or lead) and shift_window(p, n_frames, lead):
            windows += 1
    counts = {TYPE_LABELS[c]: int(np.sum(fate == c)) for c in TYPE_LABELS}
    counts["bract"] = int(bract.sum())
    return out, {**counts, "windows": windows, "oriented": oriented, "d_min": dmin}
