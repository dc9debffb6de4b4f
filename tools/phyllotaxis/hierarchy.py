"""Hierarchical and recursive phyllotaxis (thesis sec. 5.4, fig. 5.3).

Recursive segregation in a flat, uniformly (exponentially) growing space: every area grows at
the relative rate ``rho`` per frame. A meristem of level L (the root is level 0) has a naked
inner region that grows with the space; when it exceeds ``production_threshold[L]`` a new
element of area ``element_area[L]`` forms at the meristem's centre and the inner region loses
that area (segregation, sec. 5.3). Older elements are pushed outward: element k of a meristem sits
at the area coordinate

    u_k(t) = a_in(t) + sum_{j newer than k} A_j(t) + A_k(t) / 2,   r_k = sqrt(u_k / pi),

at the angle ``theta_0 + k * divergence``. An element of level L + 1 < ``levels`` becomes a meristem
of its own when its area reaches ``meristem_threshold[L]``; its first element is placed as far as
possible from the grandparent's centre (Hofmeister's rule: ``theta_0`` points from the parent
meristem's centre to the new meristem's centre). Only last-level elements are florets. Since
all areas grow at the same rate, an element's own sub-pattern fills exactly its area.

Times are in frames; event times are solved in closed form (``ln(T / a) / rho``), so a threshold
that is never reached ends the production instead of looping.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from inflo.formats.errors import InputError
from inflo.formats.scn import Group, Placement, Scene

from .development import age_window
from .params import per_level
from .ridley import diameter_of_area

__all__ = ["Hierarchy", "grow_hierarchy", "hierarchy_state", "hierarchy_scene"]


@dataclass
class Hierarchy:
    """Elements of a recursive pattern as structure of arrays (index 0 is the root meristem).

    Attributes
    ----------
    element_level : (e,) int64  0 for the root, L + 1 for an element of a level-L meristem
    element_parent : (e,) int64  the producing meristem's element index (-1 for the root)
    element_birth : (e,) float64  frame at which the element formed
    element_area0 : (e,) float64  area at birth
    element_rank : (e,) int64  k: the element's index among its parent's elements
    meristem_start : (e,) float64  frame at which it became a meristem (inf: never)
    meristem_theta0 : (e,) float64  angle of its first element (radians)
    children : list of (c,) int64 arrays  each meristem's elements in order of formation
    events : list of (times, inner_after) arrays per meristem: its start and inner area then,
        followed by each segregation event and the inner area right after it
    """

    element_level: np.ndarray
    element_parent: np.ndarray
    element_birth: np.ndarray
    element_area0: np.ndarray
    element_rank: np.ndarray
    meristem_start: np.ndarray
    meristem_theta0: np.ndarray
    children: list
    events: list
    rho: float
    divergence: float
    levels: int
    frames: float
    messages: list = field(default_factory=list)

    @property
    def florets(self) -> np.ndarray:
        """(f,) int64: indices of the last-level elements (the florets), in order of formation."""
        return np.nonzero(self.element_level == self.levels)[0]


def _segregation_events(a0: float, t0: float, threshold: float, area: float, rho: float, t_end: float,
                        budget: int) -> tuple[list, list]:
    """Times of the elements a meristem forms and its inner area right after each (closed form)."""
    times, after = [], []
    a, t = a0, t0
    while len(times) < budget:
        if a >= threshold:
            a -= area
            times.append(t)
            after.append(a)
            continue
        if rho <= 0:
            break
        dt = math.log(threshold / a) / rho
        if t + dt > t_end:
            break
        t += dt
        a = threshold
    return times, after


def grow_hierarchy(*, levels: int, frames: float, growth_rate: float, initial_area: float,
                   element_area, production_threshold, meristem_threshold,
                   divergence: float = 137.50776405003785, max_count: int = 200_000) -> Hierarchy:
    """Simulate recursive segregation up to time ``frames`` (sec. 5.4, fig. 5.3).

    Per-level parameters are lists (the last value repeats). Returns a :class:`Hierarchy`;
    ``messages`` holds warnings, e.g. a meristem threshold never reached (with the largest size
    reached).

    Raises
    ------
    InputError
        More than ``max_count`` elements, or no floret at all.
    """
    A = per_level(element_area, levels)
    T = per_level(production_threshold, levels)
    M = per_level(meristem_threshold, levels)
    rho = float(growth_rate)
    phi = math.radians(divergence)
    lev, par, birth, area0, rank = [0], [-1], [0.0], [initial_area], [0]
    mstart, theta0 = [0.0], [0.0]
    children: list = [None]
    events: list = [None]
    largest = [0.0] * (levels + 1)
    queue = [0]
    head = 0
    while head < len(queue):
        m = queue[head]
        head += 1
        L = lev[m]
        a0 = area0[m] * (math.exp(rho * (mstart[m] - birth[m])) if m else 1.0)
        budget = max_count + 1 - len(lev)
        times, after = _segregation_events(a0, mstart[m], T[L], A[L], rho, frames, budget)
        if len(lev) + len(times) > max_count:
            raise InputError(f"more than hierarchy.max_count = {max_count} pattern elements would form "
                             f"by frame {frames}; lower frames or growth_rate, or raise max_count")
        # (time, inner area after it): the meristem's start, then each segregation event
        events[m] = (np.array([mstart[m], *times]), np.array([a0, *after]))
        kids = []
        for k, tb in enumerate(times):
            e = len(lev)
            lev.append(L + 1)
            par.append(m)
            birth.append(tb)
            area0.append(A[L])
            rank.append(k)
            children.append(None)
            events.append(None)
            kids.append(e)
            size_end = A[L] * math.exp(rho * (frames - tb))
            largest[L + 1] = max(largest[L + 1], size_end)
            start = math.inf
            if L + 1 < levels:
                thr = M[L]
                if A[L] >= thr:
                    start = tb
                elif rho > 0:
                    start = tb + math.log(thr / A[L]) / rho
                if start > frames:
                    start = math.inf
            mstart.append(start)
            theta0.append(0.0)
            if math.isfinite(start):
                queue.append(e)
        children[m] = np.array(kids, dtype=np.int64)
    h = Hierarchy(np.array(lev, np.int64), np.array(par, np.int64), np.array(birth), np.array(area0),
                  np.array(rank, np.int64), np.array(mstart), np.array(theta0), children, events, rho,
                  phi, levels, float(frames))
    for L in range(levels - 1):
        sub = (h.element_level == L + 1)
        if sub.any() and not np.isfinite(h.meristem_start[sub]).any():
            h.messages.append(
                f"hierarchy level {L + 1}: meristem_threshold {M[L]:g} never reached by frame {frames:g}; "
                f"the largest level-{L + 1} element reached area {largest[L + 1]:.6g}")
    if len(h.florets) == 0:
        reached = max(largest) if any(largest) else initial_area
        raise InputError(
            f"the recursive pattern forms no floret by frame {frames:g} (levels = {levels}); "
            + ("; ".join(h.messages) if h.messages else
               f"the root's inner region never reaches production_threshold {T[0]:g} (reached {reached:.6g})"))
    _hofmeister(h)
    return h


def _centres(h: Hierarchy, t: float, *, theta0: np.ndarray | None = None):
    """Centres (e, 3) of every element at time t (NaN for elements not yet formed) and areas (e,)."""
    e = len(h.element_level)
    pos = np.full((e, 3), np.nan)
    pos[0] = 0.0
    area = h.element_area0 * np.exp(h.rho * (t - h.element_birth))
    th0 = h.meristem_theta0 if theta0 is None else theta0
    for m in range(e):
        kids = h.children[m]
        if kids is None or len(kids) == 0 or not np.isfinite(pos[m, 0]):
            continue
        born = kids[h.element_birth[kids] <= t + 1e-12]
        if len(born) == 0:
            continue
        times, after = h.events[m]
        j = np.searchsorted(times, t + 1e-12, side="right") - 1
        a_in = after[j] * math.exp(h.rho * (t - times[j]))
        a = area[born]
        # newest innermost: cumulative area from the newest element outward
        rev = a[::-1]
        u = (a_in + np.cumsum(rev) - 0.5 * rev)[::-1]
        r = np.sqrt(u / np.pi)
        th = th0[m] + h.element_rank[born] * h.divergence
        pos[born, 0] = pos[m, 0] + r * np.cos(th)
        pos[born, 1] = pos[m, 1]
        pos[born, 2] = pos[m, 2] + r * np.sin(th)
    return pos, area


def _offset(h: Hierarchy, e: int, t: float) -> np.ndarray:
    """Position of element ``e`` relative to its producing meristem's centre at time ``t``."""
    m = h.element_parent[e]
    kids = h.children[m]
    newer = kids[(h.element_rank[kids] > h.element_rank[e]) & (h.element_birth[kids] <= t + 1e-12)]
    times, after = h.events[m]
    j = np.searchsorted(times, t + 1e-12, side="right") - 1
    a_in = after[j] * math.exp(h.rho * (t - times[j]))
    grow = np.exp(h.rho * (t - h.element_birth))
    u = a_in + float(np.sum(h.element_area0[newer] * grow[newer])) + 0.5 * h.element_area0[e] * grow[e]
    r = math.sqrt(u / math.pi)
    th = h.meristem_theta0[m] + h.element_rank[e] * h.divergence
    return np.array([r * math.cos(th), 0.0, r * math.sin(th)])


def _hofmeister(h: Hierarchy) -> None:
    """Set each meristem's first-element angle away from its grandparent's centre (in place).

    At the time meristem m starts, its offset from its parent's centre is the direction away from
    the grandparent (the parent meristem of level n - 1 seen from the new meristem of level n).
    Meristems are processed in order of start, so every ancestor's angle is already set.
    """
    order = np.argsort(h.meristem_start, kind="stable")
    for m in order:
        if m == 0 or not np.isfinite(h.meristem_start[m]):
            continue
        d = _offset(h, int(m), float(h.meristem_start[m]))
        if math.hypot(d[0], d[2]) > 0:
            h.meristem_theta0[m] = math.atan2(d[2], d[0])


def hierarchy_state(h: Hierarchy, t: float, *, size_factor: float = 1.0) -> dict:
    """Florets formed by time ``t``: ``ids`` (indices among :attr:`Hierarchy.florets`), ``pos``,
    ``scale``, ``up``, ``right`` ``(k, 3)``, ``group`` (the producing meristem's element index),
    and ``centres (e, 3)`` of all elements."""
    pos, area = _centres(h, t)
    fl = h.florets
    ok = h.element_birth[fl] <= t + 1e-12
    ids = np.nonzero(ok)[0]
    el = fl[ids]
    p = pos[el]
    grp = h.element_parent[el]
    radial = p - pos[grp]
    norm = np.hypot(radial[:, 0], radial[:, 2])
    right = np.where(norm[:, None] > 1e-12, radial / np.where(norm > 1e-12, norm, 1.0)[:, None],
                     np.array([1.0, 0.0, 0.0]))
    right[:, 1] = 0.0
    up = np.tile([0.0, 1.0, 0.0], (len(el), 1))
    d = size_factor * diameter_of_area(area[el])
    return {"ids": ids.astype(np.int64), "pos": p, "up": up, "right": right,
            "scale": np.repeat(d[:, None], 3, axis=1), "group": grp, "centres": pos}


def hierarchy_scene(h: Hierarchy, final: dict, *, floret_id: int = 0, dynamic: bool = False,
                    kind: str = "o", frame_start: int = 0, frame_end: int = 100,
                    development_frames: int | None = None) -> Scene:
    """The SCN at the end of the run: one placement per floret, groups = the meristems.

    Each meristem that formed florets or sub-meristems is a group (id = its element index) with
    its centre at the final time and its producing meristem as parent. Static: ``o:``
    placements, or ``ca: frame_start frame_end`` with ``kind = "ca"`` (``[primordia] placement``,
    as for the static and compound models); dynamic: ``rba:`` with scale 1 1 1 (the RBA rows
    carry the sizes; the SCN scale multiplies them), ``frameStart`` the emergence frame (rounded
    up) and ``frameEnd`` the last frame, or ``frameStart + development_frames`` when given.
    """
    scene = Scene()
    centres = final["centres"]
    meristems = [m for m in range(len(h.element_level))
                 if h.children[m] is not None and len(h.children[m])]
    for m in meristems:
        parent = int(h.element_parent[m])
        scene.groups[int(m)] = Group(int(m), centres[m], parent if parent >= 0 else -1)
    last = int(math.floor(h.frames))
    fl = h.florets
    for row, k in enumerate(final["ids"]):
        e = fl[k]
        kw = {}
        scale = final["scale"][row]
        if dynamic:
            start, end = age_window(min(int(math.ceil(h.element_birth[e] - 1e-9)), last), last,
                                    development_frames)
            kw = {"frame_start": start, "frame_end": end}
            scale = np.ones(3)
        elif kind == "ca":
            kw = {"frame_start": int(frame_start), "frame_end": int(frame_end)}
        scene.placements.append(Placement(
            "rba" if dynamic else kind, int(floret_id), final["pos"][row], scale,
            final["up"][row], final["right"][row], group=int(final["group"][row]),
            emergence=float(h.element_birth[e]), **kw))
    return scene
