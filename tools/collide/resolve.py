"""The collision-resolution loop of a step (thesis 4.2-4.3, Alg. 1 lines 10-20).

:func:`resolve_collisions` runs the retries of the ``max collision retries`` key: detect
(:mod:`.detect`: the step's broad phase, the narrow phase of :mod:`.contacts`), add the new
collision constraints to the set, solve the set for ``collision iterations`` sweeps
(:mod:`.response`), re-detect. Pairs sharing a vertex are skipped (a triangle's own vertices, two
edges of one triangle fan): self-collisions within one floret count like any other. The rounds
stop early when the crossing pairs stall (``STALL_ROUNDS``) or run away (``RUNAWAY_FACTOR``), and
then end on the positions of their best round (fewest pairs crossing), not their last. Pairs
still crossing are reported and, so that the output stays collision-free, their vertices are put
back where they were at the start of the step (``x0`` is collision-free; repeated while crossings
are left, at most 10 times, then the whole step is put back). Used by ``fccompose`` (growth) and
``subdivide`` (from the in-plane quadrisected mesh to the Loop positions). ``fccompose`` uses the
whole-part fallback instead (``fallback="parts"``, :mod:`.retreat`), with a relaxation of the
internal constraints between rounds and repair passes for parts left out of shape, so that a
floret is never torn by the fallback.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .contacts import Contacts, _narrow, default_tolerance
from .detect import _changed, _ProbedBroadPhase, step_broad_phase
from .probe import can_probe
from .response import project_collision_constraints
from .retreat import _retreat_fallback

__all__ = ["CollisionResult", "resolve_collisions"]

#: repair passes for parts left out of shape (``fallback="parts"`` with ``relax``), and the
#: relaxations (each ``relax`` call's sweeps) of one pass
REPAIR_PASSES = 2
REPAIR_RELAXATIONS = 4
#: detect/solve rounds without fewer crossing pairs after which the retries stop early
STALL_ROUNDS = 4
#: a round that finds more crossing pairs than the first round did and more than this many times
#: the fewest of the rounds before it ends the retries at once: the response is diverging (florets
#: squeezed with no room, each round undoing the last: a squeezed head's rounds went 2,659 -> 110
#: -> 4,548 -> ... -> 426,428 pairs, each round slower than the one before); the rounds then end
#: on their best round's positions. (The factor alone also cut converging rounds short: the 350k
#: benchmark canopy's 6,819 -> 72 -> 1 -> 11 -> ... -> 0.)
RUNAWAY_FACTOR = 8


# --------------------------------------------------------------------------------------------------
# Algorithm 1, collision part
# --------------------------------------------------------------------------------------------------


@dataclass
class CollisionResult:
    """What :func:`resolve_collisions` did in one step.

    Attributes
    ----------
    rounds : int
        Detection rounds run (1 when the step was free at once).
    found : list of int
        Pairs needing a response found in each round.
    constraints : int
        Collision constraints in the set at the end.
    remaining : Contacts
        Pairs still crossing after ``max_retries`` (reported; their vertices were reverted).
    reverted : int
        Vertices put back to their start-of-step position by the fallback.
    stats : dict
        Broad/narrow phase counts of the first round.
    """

    rounds: int = 0
    found: list = field(default_factory=list)
    constraints: int = 0
    remaining: Contacts = field(default_factory=Contacts.empty)
    reverted: int = 0
    stats: dict = field(default_factory=dict)
    relaxed: int = 0
    """rounds whose collision response was followed by a relaxation of the internal constraints"""
    retreated: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    """parts the ``"parts"`` fallback moved back (:func:`retreat_parts`; fccompose: florets)"""
    whole_step: bool = False
    repairs: int = 0
    """passes that relaxed parts left out of shape and resolved what that moved"""
    misshapen: int = 0
    """parts (``fallback="parts"``) still out of shape at the end: their carried shape crosses
    something, and so does each smaller shape ``parts.shrink`` offers, so they keep the
    collision-free shape the solve gave them (reported; fccompose does not redo such a step:
    halving it made squeezed canopies 9 x slower)"""
    shrunk: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """(n_parts,) the scale each part was put at by the ``"parts"`` fallback's last resort for parts
    out of shape (``parts.shrink``): 1 where none; empty when the fallback did not run"""


def resolve_collisions(x0: np.ndarray, x1: np.ndarray, vertex_inv_mass: np.ndarray,
                       tri_indices: np.ndarray, edge_indices: np.ndarray, *, thickness: float,
                       stiffness: float = 1.0, iterations: int = 10, max_retries: int = 20,
                       tolerance: float | None = None, cell_size: float | None = None,
                       relax=None, relax_rounds: int | None = None,
                       fallback: str = "vertices", parts=None, vertex_part=None,
                       probe: bool = True) -> CollisionResult:
    """Move ``x1`` (in place) until the step from ``x0`` is collision-free (Alg. 1 lines 10-20).

    Parameters
    ----------
    x0 : (n, 3) float64
        Collision-free positions at the start of the step.
    x1 : (n, 3) float64
        Predicted positions (after the internal constraints); corrected in place.
    vertex_inv_mass : (n,) float64
        Inverse masses (0: fixed; collision constraints do not move those vertices).
    tri_indices : (m, 3) int32
    edge_indices : (e, 2) int32
    thickness : float
        ``h`` (``spacing``): distance the constraints keep (at least twice the tolerance).
    stiffness : float
        ``kCollision``.
    iterations : int
        ``collision iterations``: sweeps over the collision constraints per round.
    max_retries : int
        ``max collision retries``: detect/solve rounds after the first. The rounds stop early
        when the number of crossing pairs has not gone down for ``STALL_ROUNDS`` (4) rounds, or
        at once when a round finds more than the first round and more than ``RUNAWAY_FACTOR`` (8)
        times the fewest so far.
        Rounds that end with more pairs crossing than their best round had end on that round's
        positions (``x1`` as it was detected then; ``remaining`` its pairs): the retries never
        leave the step worse than they found it.
    tolerance : float or None
        Inside-test tolerance; None: :func:`default_tolerance`.
    cell_size : float or None
        Broad-phase cell size.
    relax : callable or None
        ``relax(x1, moved)``: called after the collision constraints of a round were projected,
        with ``moved`` the (n,) bool mask of the vertices they moved; it re-solves the internal constraints of what they moved, in place (the collision and
        internal constraints are then solved together, as in Alg. 1, rather than the collision
        response having the last word on the florets' shape). The next round's detection checks
        what it moved.
    relax_rounds : int or None
        Rounds that call ``relax`` (the first ones); the later rounds are the plain collision
        response, so that the loop converges where the two disagree. None: half the rounds.
    fallback : str
        What to do with pairs still crossing after the last round: ``"vertices"`` puts their
        vertices back to ``x0`` (the module doc); ``"none"`` leaves ``x1`` as the last round left
        it and only reports them in ``remaining`` (the caller resolves them, e.g. by
        :func:`retreat_parts`); ``"parts"``: :func:`retreat_parts` with ``parts``, on this step's
        broad phase (incremental, as the rounds).
    parts : :class:`.retreat.Parts` or None
        For ``fallback="parts"``: the parts (``vertex_part``, ``n_parts``) and the caller's policy
        for those left crossing or out of shape (``carried``, ``misshapen``, ``crossing``,
        ``shrink`` at ``shrink_scales``, ``intersecting``, ``blockers``, ``scaled``; fccompose: the
        carried shape scaled about each floret's base for the florets whose carried shape is in
        shape, the rest shape scaled for all), tried as :func:`.retreat._retreat_fallback` says
        (``CollisionResult.shrunk``).
    vertex_part : (n,) int or None
        The part of every vertex (default: ``parts.vertex_part``): where parts are carried far
        over the step, pairs within a part are found in its moving frame (:func:`step_broad_phase`;
        the same contacts, found faster); where the parts are grouped (:func:`.probe.can_probe`),
        round 0 is detected part by part without a pair list (:func:`.probe.probe_contacts`:
        the same contacts) and the retry rounds' broad phase is built only if a retry comes.
    probe : bool
        Allow that round-0 probe (a caller whose last step found contacts in round 0 expects
        retries, which need the pair lists anyway, and passes False).

    Returns
    -------
    CollisionResult
    """
    if fallback not in ("vertices", "none", "parts"):
        raise ValueError(f"fallback must be 'vertices', 'none' or 'parts', not {fallback!r}")
    if relax_rounds is None:
        relax_rounds = (max_retries + 1) // 2
    tol = default_tolerance(x0, thickness) if tolerance is None else float(tolerance)
    h = max(float(thickness), 2.0 * tol)
    res = CollisionResult()
    w = np.ascontiguousarray(vertex_inv_mass, dtype=np.float64)
    tri = np.ascontiguousarray(tri_indices, dtype=np.int32)
    edges = np.ascontiguousarray(edge_indices, dtype=np.int32)
    x0 = np.ascontiguousarray(x0, dtype=np.float64)
    vp = parts.vertex_part if parts is not None else None
    if vertex_part is None:
        vertex_part = vp
    broad = step_broad_phase(x0, np.ascontiguousarray(x1, dtype=np.float64), tri, edges, 0.5 * tol, cell_size,
                             vertex_part)
    if probe and can_probe(tri, edges, vertex_part):
        broad = _ProbedBroadPhase(broad, x0, tri, edges, 0.5 * tol, tol, vertex_part)
    state = {"constraints": Contacts.empty()}
    # vertices put back to an earlier round's positions (run_rounds' end): active in the next
    # detection, whatever its caller names (the broad phase anchors only what it saw move)
    restored = np.zeros(len(x1), np.bool_)

    def again(xs, active):
        if restored.any():
            active = active | restored
            restored[:] = False
        return broad.again(xs, active)

    def detect(active):
        if active is None and isinstance(broad, _ProbedBroadPhase):
            return broad.round0(x1)
        pairs = broad.first(x1) if active is None else again(x1, active)
        return _narrow(x0, x1, tri, edges, pairs[0], pairs[1], tol)

    def run_rounds(active):
        """Detect/solve rounds from ``active`` (None: everything); returns the pairs still crossing."""
        best, stalled = None, 0
        best_x = best_found = None
        found = Contacts.empty()
        for r in range(max_retries + 1):
            found, stats = detect(active)
            res.rounds += 1
            res.found.append(len(found))
            if active is None and r == 0:
                res.stats = stats
            if len(found) == 0 or r == max_retries:
                break
            if r == 0:
                first = len(found)
            elif len(found) > max(RUNAWAY_FACTOR * best, first):
                break  # the response diverges: more rounds only cost more
            if best is None or len(found) < best:
                best, stalled = len(found), 0
            else:
                stalled += 1
                if stalled >= STALL_ROUNDS:  # the same pairs keep crossing: retrying will not help
                    break
            constraints = state["constraints"] = state["constraints"].concat(found)
            before = x1.copy()
            if len(found) == best:  # (``before``: this round's detected positions)
                best_x, best_found = before, found
            project_collision_constraints(x1, w, constraints.indices, constraints.coef,
                                          constraints.normal, h, float(stiffness),
                                          int(iterations), constraints.reach)
            if relax is not None and r < relax_rounds:
                relax(x1, _changed(x1, before))
                res.relaxed += 1
                # and the collision constraints again, so that the round ends on them
                project_collision_constraints(x1, w, constraints.indices, constraints.coef,
                                              constraints.normal, h, float(stiffness),
                                              int(iterations), constraints.reach)
            moved = _changed(x1, before)
            # still-crossing pairs whose vertices did not move are re-found too
            moved[found.indices.ravel()] = True
            active = moved
        if best is not None and len(found) > best:
            # the rounds end on the positions of their best round (fewest pairs crossing): its
            # pairs are all the pairs crossing there (each round detects the pairs with a vertex
            # moved since the last and those still crossing), the caller's fallback has the fewest
            # florets to move back
            restored[:] |= _changed(x1, best_x)
            x1[:] = best_x
            found = best_found
        return found

    found = run_rounds(None)
    misshapen = parts.misshapen if (fallback == "parts" and parts is not None) else None
    if relax is not None and misshapen is not None:
        # repair: relax the florets the rounds left out of shape harder, and resolve what that moved
        vp = np.asarray(parts.vertex_part)
        for _ in range(REPAIR_PASSES):
            bad = np.asarray(misshapen(x1), dtype=bool) if not len(found) else None
            if bad is None or not bad.any():
                break
            before = x1.copy()
            for _ in range(REPAIR_RELAXATIONS):
                relax(x1, bad[vp])
            moved = _changed(x1, before)
            if not moved.any():
                break
            res.repairs += 1
            found = run_rounds(moved)
    constraints = state["constraints"]
    res.constraints = len(constraints)
    res.remaining = found
    if fallback == "parts":
        _retreat_fallback(res, x0, x1, tri, edges, tol, parts,
                          lambda xs, act: _narrow(x0, xs, tri, edges, *again(xs, act), tol)[0])
        return res
    if fallback == "none" or len(found) == 0:
        return res
    # fallback: put the vertices of the pairs still crossing back to their start positions
    reverted = np.zeros(len(x1), np.bool_)
    for _ in range(10):
        verts = np.unique(found.indices)
        reverted[verts] = True
        x1[verts] = x0[verts]
        active = np.zeros(len(x1), np.bool_)
        active[verts] = True
        found, _ = detect(active)
        if len(found) == 0:
            break
    else:
        x1[:] = x0
        reverted[:] = True
    res.reverted = int(np.count_nonzero(reverted))
    return res
