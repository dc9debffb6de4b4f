"""Dynamics of phyllotaxis: fractionation and segregation (thesis sec. 5.3, fig. 5.2).

The meristem is divided into three regions along its generating curve, measured as surface area
from the apex: the naked inner region ``[0, a_in]``, the primordium-carrying region (the sum of
the current primordium areas) and the naked outer region. Three modes:

- **centripetal fractionation** (fig. 5.2a): no outer region; beginning at the rim, a primordium
  forms every ``interval`` frames at the inner boundary, taking its area from the inner region,
  until the inner region is smaller than one primordium;
- **divergent fractionation** (fig. 5.2b): inner and outer regions; every ``interval`` frames a
  primordium forms at each front (inner and outer boundary of the primordium region) while that
  region still has room, so the pattern grows inward and outward at once;
- **segregation** (fig. 5.2c): a small inner region grows; a primordium forms when its area
  exceeds ``threshold``, and the inner region loses the primordium's area; the period is set by
  the inner region's growth rate: ``ln(T / (T - A)) / rate`` at a constant relative rate.

Growth: regions grow at relative rates (per frame) that are functions of the meristem age
``t / frames``; each primordium's relative growth rate is a function of its own age
``age / frames``. The supporting surface is the (interpolated) generating curve scaled so that
its area equals the sum of the regions; primordium i sits at the area coordinate
``u_i = a_in + sum_{j before i} A_j + A_i / 2`` (Ridley's eq. 5.1 with the current areas).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numba import njit

from inflo.formats.atomic import frame_name
from inflo.formats.errors import InputError
from inflo.formats.rba import RbaFrame, write_rba
from inflo.formats.scn import Group, Placement, Scene

from .development import age_window
from .surface import Profile, blend_profiles

__all__ = ["MODE_CODES", "simulate_regions", "DynamicPattern", "simulate", "frame_state",
           "dynamic_scene", "write_frames"]

MODE_CODES = {"centripetal": 0, "divergent": 1, "segregation": 2}


@njit(cache=True)
def simulate_regions(mode, frames, substeps, interval, primordium_area, inner0, outer0,
                     inner_rate, outer_rate, threshold, max_count, close_apex=False, apex_taper=0.0,
                     apex_smallest=0.25):
    """The region bookkeeping of sec. 5.3 (a pure kernel).

    Parameters
    ----------
    mode : int  0 centripetal, 1 divergent, 2 segregation (:data:`MODE_CODES`)
    frames, substeps : int  time runs over ``frames`` frames in steps of ``1 / substeps``
    interval : float  frames between primordia of a front (fractionation)
    primordium_area : float  area of a new primordium
    inner0, outer0 : float  initial areas of the inner and outer regions
    inner_rate, outer_rate : (frames * substeps,) float64  relative growth rates per frame at
        each step's time
    threshold : float  inner-region area that triggers a primordium (segregation)
    max_count : int  stop (and report) past this many primordia
    close_apex : bool  fractionation: once the inner region holds less than one primordium, the
        next primordium of the inner front takes what is left if that is at least half a
        primordium, and the inner region is used up either way (zero from then on: relative
        growth keeps it zero), so no naked apex remains (the terminal primordium of a head)
    apex_taper : float  fractionation, 0 (off) or in (0, 1): once the inner region holds less than
        ``1 / apex_taper`` primordia, a primordium of the inner front takes ``apex_taper`` of what is
        left, not a whole primordium (smaller and smaller primordia toward the apex), while that is
        at least ``apex_smallest`` primordia; then the inner front stops, or closes the apex
    apex_smallest : float  the smallest tapered primordium, a fraction of ``primordium_area``

    Returns
    -------
    emergence : (k,) float64  emergence time of each primordium (frames), in order of formation
    side : (k,) int8  -1 formed at the inner front, +1 at the outer front
    born : (k,) float64  each primordium's area at its formation (``primordium_area`` but where the
        apex tapers; the terminal primordium's: what it took of the apex, at least half of the
        smallest primordium of the front)
    terminal : bool  True when the last primordium is the terminal one (``close_apex``: on the apex)
    inner, outer : (frames,) float64  region areas at each frame's time (after its events)
    overflow : bool  True when ``max_count`` stopped the simulation
    """
    cap = max_count + 2
    emergence = np.empty(cap, np.float64)
    side = np.empty(cap, np.int8)
    born = np.empty(cap, np.float64)
    terminal = False
    smallest = primordium_area
    inner = np.empty(frames, np.float64)
    outer = np.empty(frames, np.float64)
    a_in = inner0
    a_out = outer0
    k = 0
    next_emit = 0.0
    dt = 1.0 / substeps
    overflow = False
    for f in range(frames):
        for sub in range(substeps):
            t = f + sub * dt
            if mode == 2:
                while a_in > threshold and not overflow:
                    if k >= max_count:
                        overflow = True
                        break
                    emergence[k] = t
                    side[k] = -1
                    born[k] = primordium_area
                    k += 1
                    a_in -= primordium_area
            else:
                while next_emit <= t + 1e-12 and not overflow:
                    made = False
                    take = primordium_area
                    if apex_taper > 0.0 and apex_taper * a_in < primordium_area:
                        take = apex_taper * a_in  # smaller primordia toward the apex
                        if take < apex_smallest * primordium_area:
                            take = math.inf  # too small: the inner front makes no more (but the terminal one)
                    if a_in >= take:
                        if k >= max_count:
                            overflow = True
                            break
                        emergence[k] = next_emit
                        side[k] = -1
                        born[k] = take
                        smallest = min(smallest, take)
                        k += 1
                        a_in -= take
                        made = True
                    elif close_apex and a_in > 0.0:
                        if a_in >= 0.5 * smallest:
                            if k >= max_count:
                                overflow = True
                                break
                            emergence[k] = next_emit
                            side[k] = -1
                            born[k] = a_in if apex_taper > 0.0 else primordium_area
                            terminal = True
                            k += 1
                            made = True
                        a_in = 0.0
                    if mode == 1 and a_out >= primordium_area:
                        if k >= max_count:
                            overflow = True
                            break
                        emergence[k] = next_emit
                        side[k] = 1
                        born[k] = primordium_area
                        k += 1
                        a_out -= primordium_area
                        made = True
                    next_emit += interval
                    if not made:
                        next_emit = 1e300  # both fronts exhausted: fractionation is over
            if sub == 0:
                inner[f] = a_in
                outer[f] = a_out
            j = f * substeps + sub
            a_in *= math.exp(inner_rate[j] * dt)
            a_out *= math.exp(outer_rate[j] * dt)
    return emergence[:k], side[:k], born[:k], terminal, inner, outer, overflow


@dataclass
class DynamicPattern:
    """Result of a dynamic simulation (k primordia in order of formation, F frames).

    Attributes
    ----------
    emergence : (k,) float64  emergence time (frames)
    side : (k,) int8  -1 inner front, +1 outer front
    theta : (k,) float64  angle about the axis (radians)
    order : (k,) int64  primordium indices sorted from the apex outward
    inner, outer : (F,) float64  region areas per frame
    age_grid, age_area : (m,) float64  primordium area as a function of age (table), for a
        primordium born at ``primordium_area``; one born smaller (``born``) in proportion
    born : (k,) float64  each primordium's area at its formation
    terminal : bool  the last primordium is the terminal one, centred on the apex (``close_apex``)
    profiles, curve_times : the generating curves and their times (fractions of the run)
    """

    emergence: np.ndarray
    side: np.ndarray
    theta: np.ndarray
    order: np.ndarray
    inner: np.ndarray
    outer: np.ndarray
    age_grid: np.ndarray
    age_area: np.ndarray
    profiles: list
    curve_times: list
    frames: int
    born: np.ndarray | None = None
    terminal: bool = False

    def __len__(self) -> int:
        return len(self.emergence)


def _rate_table(rate, times: np.ndarray, frames: int) -> np.ndarray:
    """Relative growth rates at ``times`` (frames); ``rate`` is a number or a Function of t/frames."""
    if isinstance(rate, (int, float)):
        return np.full(times.shape, float(rate))
    return np.asarray(rate(np.clip(times / frames, 0.0, 1.0)), dtype=np.float64)


def simulate(*, mode: str, frames: int, interval: float, primordium_area: float, inner_area: float,
             outer_area: float = 0.0, inner_growth=0.0, outer_growth=0.0, primordium_growth=0.0,
             threshold: float = 0.0, divergence: float = 137.50776405003785, profiles: list,
             curve_times: list | None = None, substeps: int = 0, max_count: int = 1_000_000,
             close_apex: bool = False, apex_taper: float = 0.0, apex_smallest: float = 0.25) -> DynamicPattern:
    """Run the region model (:func:`simulate_regions`) and assign angles and spatial order.

    Parameters are those of ``[dynamics]`` (``formats/phyllotaxis.md``); growth arguments are
    numbers or :class:`inflo.formats.func.Function` objects of normalized age. ``profiles`` are
    :class:`~.surface.Profile` generating curves, blended over ``curve_times`` (fractions of
    the run; one curve: fixed shape).
    """
    if not 0.0 < divergence < 360.0:
        raise InputError(f"divergence angle {divergence} outside (0, 360) degrees")
    if substeps <= 0:
        substeps = int(min(64, max(1, math.ceil(2.0 / interval)))) if mode != "segregation" else 8
    steps = frames * substeps
    t = np.arange(steps, dtype=np.float64) / substeps
    rin = _rate_table(inner_growth, t, frames)
    rout = _rate_table(outer_growth, t, frames)
    age_grid = np.arange(frames * substeps + 1, dtype=np.float64) / substeps
    grow = _rate_table(primordium_growth, age_grid, frames)
    # an area grows at most MAX_GROWTH-fold over the run (exp of the rate's integral): a larger
    # growth overflows to inf and 0/0 (checked before any work, .func rates included)
    from .params import MAX_GROWTH, MAX_LOG_GROWTH

    for key, table in (("inner_growth", rin), ("outer_growth", rout), ("primordium_growth", grow)):
        total = float(np.max(np.abs(np.cumsum(table)))) / substeps if len(table) else 0.0
        if not total <= MAX_LOG_GROWTH:
            raise InputError(f"expected dynamics.{key} whose integral over the run is within +-{MAX_LOG_GROWTH:.4g} "
                             f"(an area grows or shrinks at most {MAX_GROWTH:g}-fold), found {total:.4g}")
    emergence, side, born, terminal, inner, outer, overflow = simulate_regions(
        MODE_CODES[mode], int(frames), int(substeps), float(interval), float(primordium_area),
        float(inner_area), float(outer_area), rin, rout, float(threshold), int(max_count),
        bool(close_apex) and mode != "segregation", float(apex_taper) if mode != "segregation" else 0.0,
        float(apex_smallest))
    keep = emergence <= frames - 1 + 1e-9  # the last frame's substeps run past the end
    terminal = bool(terminal) and bool(keep.all())
    emergence, side, born = emergence[keep], side[keep], born[keep]
    if overflow:
        raise InputError(f"more than dynamics.max_count = {max_count} primordia would form; "
                         "raise max_count or slow the growth")
    if len(emergence) == 0:
        raise InputError("no primordium forms: the inner region never holds one primordium "
                         f"(dynamics.inner_area = {inner_area}, primordium_area = {primordium_area}"
                         + (f", threshold = {threshold}" if mode == "segregation" else "") + ")")
    phi = math.radians(divergence)
    inner_rank = np.cumsum(side == -1) - 1
    outer_rank = np.cumsum(side == 1) - 1
    theta = np.where(side == -1, -inner_rank * phi, (outer_rank + 1) * phi)
    key = np.where(side == -1, -(inner_rank + 1), outer_rank).astype(np.int64)
    order = np.argsort(key, kind="stable")
    logs = np.concatenate([[0.0], np.cumsum(0.5 * (grow[1:] + grow[:-1]) * np.diff(age_grid))])
    age_area = primordium_area * np.exp(logs)
    return DynamicPattern(emergence, side, theta, order, inner, outer, age_grid, age_area,
                          list(profiles), list(curve_times or [0.0] * len(profiles)), int(frames),
                          born, terminal)


@njit(cache=True)
def place_primordia(order, areas, theta, a_in, prof_area, prof_s, prof_r, prof_y, prof_tr, prof_ty,
                    size_factor, pos, up, right, scale, pole=False):
    """Place primordia along a surface of revolution by their area coordinate (eq. 5.1).

    Parameters
    ----------
    order : (k,) int64  primordium indices from the apex outward (a permutation of 0..k-1)
    areas : (k,) float64  their current areas, in ``order``
    theta : (n,) float64  angle of every primordium about the axis (indexed by primordium)
    a_in : float  area of the inner naked region
    prof_* : (m,) float64  the scaled generating curve: cumulative area, arc length, r, y, tangent
    size_factor : float  scale = size_factor * 2 sqrt(A / pi)
    pos, up, right, scale : (k, 3) float64  outputs, row = primordium index
    pole : bool  ``order[0]`` is the terminal primordium: it holds the apex's disc ``[0, areas[0]]``
        and stands on the apex itself (u = 0), its up the axis

    Primordium ``order[j]`` sits at area coordinate ``u = a_in + sum_{i<j} areas[i] + areas[j] / 2``;
    u increases along ``order``, so one forward walk over the curve's samples finds every segment.
    """
    m = prof_area.shape[0]
    seg = 0
    u = a_in
    for j in range(order.shape[0]):
        a = areas[j]
        uj = u + 0.5 * a
        if pole and j == 0:
            uj = 0.0
        u += a
        while seg < m - 2 and prof_area[seg + 1] < uj:
            seg += 1
        da = prof_area[seg + 1] - prof_area[seg]
        w = (uj - prof_area[seg]) / da if da > 0 else 0.0
        w = min(max(w, 0.0), 1.0)
        r = prof_r[seg] + w * (prof_r[seg + 1] - prof_r[seg])
        y = prof_y[seg] + w * (prof_y[seg + 1] - prof_y[seg])
        tr = prof_tr[seg] + w * (prof_tr[seg + 1] - prof_tr[seg])
        ty = prof_ty[seg] + w * (prof_ty[seg + 1] - prof_ty[seg])
        tn = math.sqrt(tr * tr + ty * ty)
        if tn > 0:
            tr /= tn
            ty /= tn
        k = order[j]
        c = math.cos(theta[k])
        s = math.sin(theta[k])
        pos[k, 0] = r * c
        pos[k, 1] = y
        pos[k, 2] = r * s
        up[k, 0] = -ty * c  # normal = tangent turned +90 degrees: (nr, ny) = (-ty, tr)
        up[k, 1] = tr
        up[k, 2] = -ty * s
        right[k, 0] = tr * c
        right[k, 1] = ty
        right[k, 2] = tr * s
        d = size_factor * 2.0 * math.sqrt(a / math.pi)
        scale[k, 0] = d
        scale[k, 1] = d
        scale[k, 2] = d


def frame_state(pattern: DynamicPattern, frame: int, *, size_factor: float = 1.0) -> dict:
    """Positions of every primordium emerged by ``frame``.

    Returns
    -------
    dict with ``ids (k,) int64`` (indices in order of formation, ascending: the emerged primordia
    are always the first k), ``pos``, ``scale``, ``up``, ``right`` ``(k, 3) float64``,
    ``area (k,)``, ``centre (3,)`` (the apex) and ``profile`` (the scaled generating curve).
    """
    k = int(np.searchsorted(pattern.emergence, frame + 1e-9, side="right"))
    order = pattern.order[pattern.order < k]
    ages = frame - pattern.emergence[order]
    areas = np.interp(ages, pattern.age_grid, pattern.age_area)
    if pattern.born is not None:
        areas = areas * (pattern.born[order] / pattern.age_area[0])
    pole = bool(pattern.terminal) and k == len(pattern) and k > 0 and int(order[0]) == k - 1
    a_in, a_out = pattern.inner[frame], pattern.outer[frame]
    total = a_in + areas.sum() + a_out
    unit = blend_profiles(pattern.profiles, pattern.curve_times, frame / max(pattern.frames - 1, 1))
    prof: Profile = unit.scaled(math.sqrt(total / unit.total_area))
    pos, up, right, scale = (np.empty((k, 3)) for _ in range(4))
    place_primordia(order, areas, pattern.theta, float(a_in), prof.area, prof.s, prof.r, prof.y, prof.tr,
                    prof.ty, float(size_factor), pos, up, right, scale, pole)
    area_rows = np.empty(k)
    area_rows[order] = areas
    return {"ids": np.arange(k, dtype=np.int64), "pos": pos, "up": up, "right": right, "scale": scale,
            "area": area_rows, "centre": np.array([0.0, float(prof.y[0]), 0.0]), "profile": prof}


def dynamic_scene(pattern: DynamicPattern, final: dict, *, floret_id: int = 0,
                  development_frames: int | None = None) -> Scene:
    """The SCN of a dynamic pattern: one ``rba:`` placement per primordium in order of formation.

    The preamble holds the floret's position and frame at the last frame, with scale 1 1 1: an
    ``rba:`` placement's SCN scale multiplies every RBA row's scale (the rows carry the primordium
    sizes; dimorph's factors go into the SCN scale). ``frameStart`` is the emergence frame (rounded
    up); ``frameEnd`` the last frame, or ``frameStart + development_frames`` when that is given
    (not clamped: a late floret is still developing at the end, the phase effect);
    ``#@ emergence:`` the exact time; group 0 is the head with its centre at the final apex.
    """
    scene = Scene()
    scene.groups[0] = Group(0, final["centre"], -1)
    last = pattern.frames - 1
    for k in range(len(pattern)):
        start, end = age_window(min(int(math.ceil(pattern.emergence[k] - 1e-9)), last), last, development_frames)
        scene.placements.append(Placement(
            "rba", int(floret_id), final["pos"][k], np.ones(3), final["up"][k], final["right"][k],
            frame_start=start, frame_end=end, group=0, emergence=float(pattern.emergence[k])))
    return scene


def write_frames(pattern: DynamicPattern, folder, *, size_factor: float = 1.0, bar=None,
                 receptacle=None) -> dict:
    """Write ``folder/0000.rba ...`` (one file per frame, every emerged floret); returns the last state.

    ``receptacle``: None, or ``(options, out_folder)``: also write the frame's supporting surface
    as ``out_folder/frame_NNNN.obj`` (:func:`.receptacle.receptacle_mesh`, same topology every frame).
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    if receptacle is not None:
        from inflo.formats.obj import write_obj

        from .receptacle import receptacle_mesh
        rec_opts, rec_dir = receptacle[0], Path(receptacle[1])
        rec_dir.mkdir(parents=True, exist_ok=True)
    state = None
    for f in range(pattern.frames):
        state = frame_state(pattern, f, size_factor=size_factor)
        write_rba(folder / frame_name(f, "", ".rba", 4),
                  RbaFrame(state["ids"], state["pos"], state["scale"], state["up"], state["right"]), fast=True)
        if receptacle is not None:
            write_obj(rec_dir / frame_name(f, "frame_", ".obj", 4), receptacle_mesh(state["profile"], rec_opts),
                      header=f"receptacle of frame {f} (phyllotaxis [receptacle])")
        if bar is not None:
            bar.update(1)
    return state
