"""The fallback that keeps parts whole (fccompose's florets; thesis 4.3).

When a step's collision rounds leave pairs crossing, :func:`.resolve.resolve_collisions` with
``fallback="parts"`` does not put single vertices back (that tears a floret): the parts of those
pairs are moved back along their own motion (:func:`retreat_parts`), parts out of shape are put
on their carried shape where it fits (:func:`reshape_parts`, :func:`place_parts`), else on a
smaller one, the neighbours in the way made smaller too (:func:`_shrink_with_blockers`).
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from .detect import detect_collisions

# --------------------------------------------------------------------------------------------------
# The fallback that keeps parts whole
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Parts:
    """The parts of a collision system (fccompose: its florets) and the caller's policy for parts
    the collision rounds leave crossing or out of shape: what ``fallback="parts"`` of
    :func:`.resolve.resolve_collisions` works with.

    Attributes
    ----------
    vertex_part : (n,) int
        The part of every vertex.
    n_parts : int
        How many parts.
    carried : callable
        ``carried()`` -> (n, 3): the carried start-of-step positions (called only when needed).
    misshapen : callable or None
        ``misshapen(x)`` -> (n_parts,) bool: the parts out of shape in ``x``.
    crossing : bool
        Also move back the parts of pairs still crossing (False leaves those to the caller, e.g.
        to substep).
    shrink : callable or None
        ``shrink(s, which)`` -> a list of ``(target, fits)``: smaller shapes of the parts of the
        (n_parts,) bool ``which`` at scale ``s`` ((n, 3) positions, and the parts for which they
        are a shape within bounds), tried in turn at each of ``shrink_scales``.
    shrink_scales : sequence of float
        The scales ``shrink`` is tried at, largest first.
    intersecting : callable or None
        The exact static test (as :func:`place_parts` takes it): a smaller shape the step's way to
        it crosses is taken where the shape itself intersects nothing.
    blockers : callable or None
        ``blockers(x, which)`` -> (n_parts,) bool: the parts not in ``which`` whose triangles
        intersect those of ``which``.
    scaled : callable or None
        ``scaled(x, which, s)`` -> (n, 3): the shapes of ``which`` in ``x`` scaled by ``s`` about
        their bases (with ``blockers``: a part that fits at no scale is tried with the neighbours
        in its way made smaller too, :func:`_shrink_with_blockers`).
    """

    vertex_part: np.ndarray
    n_parts: int
    carried: Callable[[], np.ndarray]
    misshapen: Callable[[np.ndarray], np.ndarray] | None = None
    crossing: bool = True
    shrink: Callable | None = None
    shrink_scales: Sequence[float] = ()
    intersecting: Callable | None = None
    blockers: Callable | None = None
    scaled: Callable | None = None


@dataclass
class RetreatResult:
    """What :func:`retreat_parts` did.

    Attributes
    ----------
    fraction : (n_parts,) float64
        How far along its own motion each part ended (1: where the solve put it; 0: at ``x0``).
    vertices : int
        Vertices of the parts that were moved back.
    rounds : int
        Detection rounds run.
    whole_step : bool
        Every vertex was put back to ``x0`` (the parts kept crossing).
    """

    fraction: np.ndarray
    vertices: int = 0
    rounds: int = 0
    whole_step: bool = False


def _retreat_fallback(res, x0, x1, tri, edges, tol, parts, detect) -> None:
    """``fallback="parts"``: the florets of pairs still crossing are moved back along their own
    motion (:func:`retreat_parts`, down to ``x0`` if need be: the step must end collision-free);
    then the florets out of shape (those moved back included) are put on their carried
    start-of-step shape where that crosses nothing and is in shape (:func:`reshape_parts`); else,
    with ``parts.shrink``, on a smaller shape that fits (module doc of fccompose: ``crowded
    scales``; the neighbours in the way made smaller too where nothing else fits,
    :func:`_shrink_with_blockers`); elsewhere they keep the collision-free shape the solve gave
    them (a floret frozen at ``x0`` while its rest values grow would tear later)."""
    vp = np.asarray(parts.vertex_part)
    n_parts = int(parts.n_parts)
    misshapen = parts.misshapen
    carried = None
    retreated = np.zeros(n_parts, bool)
    if len(res.remaining):
        if not parts.crossing:
            return  # the caller redoes the step
        start = np.zeros(n_parts, bool)
        start[np.unique(vp[res.remaining.indices.ravel()])] = True
        carried = parts.carried()
        ret = retreat_parts(x0, x1, tri, edges, vp, n_parts, start, tolerance=tol, carried=carried,
                            detect=detect)
        retreated |= ret.fraction < 1.0
        res.reverted += ret.vertices
        res.whole_step = ret.whole_step
        if ret.whole_step:
            res.retreated = np.arange(n_parts)
            return
    res.shrunk = np.ones(n_parts)
    if misshapen is not None:
        bad = np.asarray(misshapen(x1), dtype=bool)
        if bad.any():
            if carried is None:
                carried = parts.carried()
            moved, _ = reshape_parts(x0, x1, carried, vp, bad, detect)
            retreated |= moved
            res.reverted += int(np.count_nonzero(moved[vp]))
            still = bad & ~moved
            shrink = parts.shrink
            intersecting = parts.intersecting
            if shrink is not None:
                # a carried shape out of shape itself (the floret started the step so) is no cure
                still |= moved & np.asarray(misshapen(x1), dtype=bool)
                # no room for a shape of its own size: a smaller one (the caller grows it back)
                for s in parts.shrink_scales:
                    if not still.any():
                        break
                    for target, fits in shrink(float(s), still.copy()):
                        tried = still & np.asarray(fits, dtype=bool)
                        if not tried.any():
                            continue
                        put, _ = reshape_parts(x0, x1, target, vp, tried, detect)
                        if intersecting is not None and (tried & ~put).any():
                            # the way there crosses something, the smaller shape itself nothing:
                            # a floret with no room changes size in the step, as one emerging
                            put |= place_parts(x1, target, vp, tried & ~put, intersecting)
                        res.shrunk[put] = float(s)
                        retreated |= put
                        res.reverted += int(np.count_nonzero(put[vp]))
                        still &= ~put
                        if not still.any():
                            break
                blockers = parts.blockers
                scales = list(parts.shrink_scales)
                if still.any() and blockers is not None and intersecting is not None and scales:
                    _shrink_with_blockers(res, x1, vp, still, retreated, shrink, parts.scaled, blockers,
                                          intersecting, scales, misshapen)
            res.misshapen = int(np.count_nonzero(still))
    res.retreated = np.nonzero(retreated)[0]


def _shrink_with_blockers(res, x1, vp, still, retreated, shrink, scaled, blockers, intersecting, scales,
                          misshapen):
    """The last resort for parts out of shape that fit at none of the ``scales`` because
    neighbours in shape take their room: each such part, at its rest shape at the smallest scale,
    is tried together with those neighbours (``blockers``) made smaller too (their present shape
    scaled about their base by each of ``scales`` in turn, ``scaled``), as crowded florets make
    room for each other; the first scale at which the whole group fits (exact static test) is
    taken. ``still``, ``retreated`` and ``res`` are updated in place."""
    smin = float(scales[-1])
    in_shape = ~np.asarray(misshapen(x1), dtype=bool)
    for f in np.nonzero(still)[0].tolist():
        one = np.zeros_like(still)
        one[f] = True
        small = shrink(smin, one)[-1][0]  # the rest shape, smallest
        trial = x1.copy()
        sel = one[vp]
        trial[sel] = small[sel]
        b = np.asarray(blockers(trial, one), dtype=bool) & ~one & ~still & in_shape & (res.shrunk >= 1.0)
        if not b.any():
            continue
        group = one | b
        keep = x1.copy()
        for s in scales:
            target = trial.copy()
            bs = b[vp]
            target[bs] = scaled(x1, b, float(s))[bs]
            put = place_parts(x1, target, vp, group, intersecting)
            if (put == group).all():
                res.shrunk[f] = smin
                res.shrunk[b] = float(s)
                retreated |= group
                res.reverted += int(np.count_nonzero(group[vp]))
                still[f] = False
                break
            g = group[vp]
            x1[g] = keep[g]


def place_parts(x1, target, vertex_part, parts, intersecting, max_rounds: int = 8):
    """Put the (n_parts,) bool ``parts`` on ``target`` where the result intersects nothing (the
    exact static test ``intersecting(x1, which) -> (n_parts,) bool``: the parts of ``which`` with
    a triangle intersecting any triangle); those that would intersect stay where they were (``x1``
    on entry intersects nothing, so this ends). Unlike :func:`reshape_parts` the way from ``x0``
    is not tested: the part changes shape within the step as an emerging floret appears. Returns
    the (n_parts,) bool parts now on ``target``."""
    vp = np.asarray(vertex_part)
    keep = x1.copy()
    on = np.asarray(parts, dtype=bool).copy()
    sel = on[vp]
    x1[sel] = target[sel]
    for _ in range(max_rounds):
        if not on.any():
            return on
        bad = np.asarray(intersecting(x1, on.copy()), dtype=bool) & on
        if not bad.any():
            return on
        on &= ~bad
        back = bad[vp]
        x1[back] = keep[back]
    sel = on[vp]
    x1[sel] = keep[sel]
    on[:] = False
    return on


def reshape_parts(x0, x1, carried, vertex_part, parts, detect, max_rounds: int = 8):
    """Put the (n_parts,) bool ``parts`` (out of shape) on their ``carried`` positions (their
    start-of-step shape carried by their own rigid motion) where that crosses nothing; those of a
    pair still crossing go back to where they were (``x1`` on entry is collision-free, so this
    ends). Returns ((n_parts,) bool: the parts now on ``carried``, detection rounds)."""
    vp = np.asarray(vertex_part)
    keep = x1.copy()
    on = np.asarray(parts, dtype=bool).copy()
    changed = on[vp]
    x1[changed] = carried[changed]
    rounds = 0
    while changed.any() and rounds < max_rounds:
        found = detect(x1, changed)
        rounds += 1
        if not len(found):
            return on, rounds
        back = np.zeros_like(on)
        back[np.unique(vp[found.indices.ravel()])] = True
        back &= on
        if not back.any():  # crossing parts all unchanged: cannot be (x1 was free); give up safely
            break
        on &= ~back
        changed = back[vp]
        x1[changed] = keep[changed]
    if changed.any():  # rounds spent: every part back where it was
        x1[on[vp]] = keep[on[vp]]
        on[:] = False
    return on, rounds


def retreat_parts(x0: np.ndarray, x1: np.ndarray, tri_indices: np.ndarray, edge_indices: np.ndarray,
                  vertex_part: np.ndarray, n_parts: int, start: np.ndarray, *, tolerance: float,
                  cell_size: float | None = None, misshapen=None, carried: np.ndarray | None = None,
                  max_rounds: int = 16, detect=None) -> RetreatResult:
    """Move whole parts back along their own motion until the step from ``x0`` is collision-free.

    The fallback of the collision response that keeps every part (floret) whole: instead of putting
    single vertices back to the start of the step, which strands them away from the rest of their
    floret (and, for a floret the RBA motion carries, tears it), each part of ``start`` ((n_parts,)
    bool) is moved back towards ``carried`` (its start-of-step shape carried by its own rigid motion
    over the step: ``x0`` when not given) as ``carried + s (x1 - carried)``, ``s`` halved every
    round (1/2, 1/4, 1/8, then 0), and as a last resort to ``x0`` itself, which is collision-free.
    The parts of any pair still crossing after a round are taken back further in the next. Every
    position tried is a blend of two whole shapes of the part, so the part stays whole; and a part
    that keeps up with its rigid motion (``carried``) keeps its base where its placement puts it
    (a part left at ``x0`` lags one step behind it).

    Parameters
    ----------
    x0, x1 : (n, 3) float64
        Collision-free start of the step, and the positions the solve reached (moved in place).
    tri_indices, edge_indices : the mesh (as :func:`resolve_collisions`).
    vertex_part : (n,) int32
        Part of every vertex.
    n_parts : int
    start : (n_parts,) bool
        Parts to move back first (those of the pairs still crossing; parts out of shape).
    tolerance, cell_size : as :func:`detect_collisions`.
    misshapen : callable or None
        ``misshapen(x1) -> (n_parts,) bool``: parts out of shape; those among the moved-back ones
        go straight to ``carried``.
    carried : (n, 3) float64 or None
        ``x0`` carried rigidly by each part's motion over the step (None: ``x0``).
    max_rounds : int
        Rounds before the whole step is put back (``x1[:] = x0``).
    detect : callable or None
        ``detect(x1, active) -> Contacts`` of the pairs with an active vertex crossing in the step
        from ``x0`` to ``x1`` (e.g. the step's incremental broad phase); None:
        :func:`detect_collisions`.

    Returns
    -------
    RetreatResult
        ``fraction``: 1 where the solve put the part, in (0, 1) a blend, 0 at ``carried``, -1 at
        ``x0``.
    """
    x0 = np.ascontiguousarray(x0, dtype=np.float64)
    base = x0 if carried is None else np.ascontiguousarray(carried, dtype=np.float64)
    last = 0.0 if carried is None else -1.0  # the fraction of the last resort (x0)
    vp = np.asarray(vertex_part)
    target = x1.copy()
    frac = np.ones(n_parts)
    todo = np.asarray(start, dtype=bool).copy()
    out = RetreatResult(frac)
    straight = np.zeros(n_parts, bool)
    if misshapen is not None:
        straight = np.asarray(misshapen(x1), dtype=bool) & todo
    for _ in range(max_rounds):
        if not todo.any():
            break
        f = frac[todo]
        nxt = np.where(f <= 0.125 + 1e-12, 0.0, 0.5 * f)
        nxt = np.where(straight[todo] & (f > 0.0), 0.0, nxt)
        nxt = np.where(f <= 0.0, last, nxt)
        frac[todo] = nxt
        changed = todo[vp]
        s = frac[vp[changed]][:, None]
        at_x0 = s[:, 0] < 0.0
        blend = base[changed] + np.maximum(s, 0.0) * (target[changed] - base[changed])
        blend[at_x0] = x0[changed][at_x0]
        x1[changed] = blend
        if detect is None:
            found, _ = detect_collisions(x0, x1, tri_indices, edge_indices, tolerance=tolerance,
                                         cell_size=cell_size, active=changed)
        else:
            found = detect(x1, changed)
        out.rounds += 1
        todo = np.zeros(n_parts, bool)
        if len(found):
            todo[np.unique(vp[found.indices.ravel()])] = True
        straight[:] = False
        if misshapen is not None:
            bad = np.asarray(misshapen(x1), dtype=bool) & (frac < 1.0) & (frac > 0.0)
            straight |= bad
            todo |= bad
        if todo.any() and (frac[todo] <= last).all():
            # every part named is at x0 already and still crossing (rounding at contact): only
            # putting back the whole step is certain (x0 is collision-free)
            break
    if todo.any():  # rounds exhausted, or nothing left to give way
        x1[:] = x0
        frac[:] = last
        out.whole_step = True
    out.vertices = int(np.count_nonzero(frac[vp] < 1.0))
    return out
