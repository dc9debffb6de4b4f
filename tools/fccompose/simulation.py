"""The control of Algorithm 1 (thesis 8 f): :class:`Simulation`, which moves the canopy's changing
:class:`.model.State` one step at a time over the static :class:`.model.Model` (the solver
settings, rest values, the present florets' collision system and caches), with the step's retry
policy (:meth:`Simulation.step`: half steps, :meth:`Simulation._attempt`: the collision rounds,
relaxation, repair and crowding) and the guard against a run that diverges. :mod:`.compose`
describes the algorithm step by step and runs it frame by frame.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numba
import numpy as np

from inflo.tools.collide.broad import lattice_cell_size, triangle_boxes
from inflo.tools.collide.contacts import default_tolerance
from inflo.tools.collide.resolve import CollisionResult, resolve_collisions
from inflo.tools.collide.retreat import Parts
from inflo.tools.collide.tritri import intersecting_pairs, intersecting_pairs_with
from inflo.tools.common import linalg as la
from inflo.tools.pbd.solver import (
    colour_constraints,
    edge_stretch_range,
    overstretched_edges,
    part_offsets,
    parts_out_of_bounds,
    project_bending_constraints_coloured,
    project_distance_constraints_coloured,
    solve_parts,
)

from .model import Model, Schedule, State, carry

#: collision rounds of a step followed by a relaxation of the florets they moved (the first ones)
RELAX_ROUNDS = 3


#: ``solver scheme: fast`` (formats/fcc.md, "Solver scheme"): a floret's projections stop after
#: the first sweep whose largest correction is at most this fraction of the canopy's median rest
#: edge length (the default scheme: 1e-9 of the scene's size, i.e. in practice all ``solver
#: iterations`` for every floret in contact)
FAST_TOLERANCE = 1e-1
# (over-relaxation of the internal sweeps was measured for the fast scheme and not kept: on the
# 100k benchmark canopy a factor 1.2 ran 2 % more sweeps, not fewer; formats/fcc.md)
#: ``solver scheme: fast``: at most this many internal sweeps a step (None: ``solver iterations``);
#: a floret the collision response deformed is drawn back to its template over the next steps
#: (the prediction carries the deformation) rather than within one
FAST_MAX_SWEEPS = 15


class SimulationDiverged(RuntimeError):
    """Florets torn apart (edges far beyond their rest length): the run stops at that frame."""


DIVERGED_STRETCH = 50.0
"""A frame in which an edge is longer than this many times its rest length stops the run
(:class:`SimulationDiverged`) before that frame is written: the last guard against a constraint
solve running away (to coordinates of 1e11 and more within a frame or two) on florets squeezed
far harder than the collision response can resolve. (The per-vertex revert fallback, which tore
florets carried by their RBA motion, is gone: florets are moved back whole.)"""


def _ids_text(ids, most: int = 20) -> str:
    """Placement indices for a message: the first ``most``, then ``...``."""
    ids = list(ids)
    return ", ".join(map(str, ids[:most])) + (" ..." if len(ids) > most else "")


@dataclass(frozen=True)
class Present:
    """The collision system of the florets present (:meth:`Simulation.set_born`): the model's
    own arrays, and None for the masks and renumbering, when every floret is present."""

    tri_on: np.ndarray | None
    """(m,) bool over the model's triangles: those of present florets"""
    tri_ids: np.ndarray | None
    """(k,) int32: their indices"""
    tri: np.ndarray
    """(k, 3) int32: their triangles (global vertex ids)"""
    vertex_ids: np.ndarray | None
    """the present florets' vertices (global ids)"""
    tri_local: np.ndarray
    """(k, 3) int32: their triangles, numbered in ``vertex_ids``"""
    edge_on: np.ndarray | None
    """(e,) bool over the model's edges: those of present florets"""
    edge_local: np.ndarray
    """their edges, numbered in ``vertex_ids``"""

    @classmethod
    def of(cls, model: Model, born: np.ndarray) -> Present:
        """The system of the florets of the (nf,) bool mask ``born``."""
        m = model
        if born.all():
            return cls(None, None, m.tri_indices, None, m.tri_indices, None, m.edge_indices)
        tri_on = born[m.tri_floret]
        tri = np.ascontiguousarray(m.tri_indices[tri_on])
        # the collision system of the present florets alone: their vertices, renumbered
        vertex_ids = np.nonzero(born[m.vertex_floret])[0]
        local = np.full(m.n_vertices, -1, np.int32)
        local[vertex_ids] = np.arange(len(vertex_ids), dtype=np.int32)
        e_on = born[m.vertex_floret[m.edge_indices[:, 0]]]
        return cls(tri_on, np.nonzero(tri_on)[0].astype(np.int32), tri, vertex_ids,
                   np.ascontiguousarray(local[tri]), e_on, np.ascontiguousarray(local[m.edge_indices[e_on]]))


class Simulation:
    """The control of Algorithm 1: solver settings and caches over a static :class:`.model.Model`,
    and the one-step update of its changing :class:`.model.State` (usable without files, e.g.
    benchmarks).

    Parameters
    ----------
    model : Model
    coloured : bool
        Solve internal constraints colour by colour in parallel (see :mod:`inflo.tools.pbd.solver`);
        False (default): the serial Gauss-Seidel sweep.
    state : State or None
        Where to start (e.g. one ``--resume`` read back, :meth:`restore`); None: frame 0
        (:meth:`.model.State.at_start`).

    Attributes
    ----------
    state : State
        Positions, frame and emergence; :meth:`advance` moves it one step.
    present : Present
        The collision system of the florets present (derived from ``state.born``).
    edge_rest_length, hinge_rest_angle : (e,), (h,) float64
        Rest values at the last time :meth:`update_rest` was given.

    The default solve is floret by floret (internal constraints never join two florets), florets
    in parallel, each the serial Gauss-Seidel order of its own constraints
    (:func:`inflo.tools.pbd.solver.project_internal_by_part`): each floret stops before ``solver
    iterations`` once one of its sweeps moved no vertex by more than 1e-9 of the scene's size (its
    constraints already at rest: the usual case for florets no collision touched, since the
    prediction puts them on their templates), so only florets in contact pay for the iterations.
    ``solver scheme: fast`` (issue 51; formats/fcc.md, "Solver scheme") stops a floret once a
    sweep moved no vertex by more than :data:`FAST_TOLERANCE` x the median rest edge length, after
    at most :data:`FAST_MAX_SWEEPS` sweeps, in the solve and in the relaxations between collision
    rounds alike.
    """

    def __init__(self, model: Model, *, coloured: bool = False, state: State | None = None):
        self.model = model
        p = model.params
        self.params = p
        self.edge_rest_length = np.zeros(len(model.edge_indices))
        self.hinge_rest_angle = np.zeros(len(model.hinge_indices))
        self.coloured = coloured
        self.fast = p.solver_scheme == "fast"
        self.solve_tolerance = None
        """the internal solve's stopping tolerance (:data:`FAST_TOLERANCE`; default scheme:
        :attr:`converged_below`)"""
        if coloured:
            self.edge_colours = colour_constraints(model.edge_indices, model.n_vertices)
            self.hinge_colours = colour_constraints(model.hinge_indices, model.n_vertices)
        nf = len(model.florets)
        self.edge_parts = part_offsets(model.edge_indices, model.vertex_floret, nf)
        self.hinge_parts = part_offsets(model.hinge_indices, model.vertex_floret, nf)
        if self.edge_parts is None or self.hinge_parts is None:  # not grouped by floret: one part
            self.edge_parts = np.array([0, len(model.edge_indices)], np.int64)
            self.hinge_parts = np.array([0, len(model.hinge_indices)], np.int64)
        self.one_part = len(self.edge_parts) - 1 != nf
        self._all_vertices = np.arange(model.n_vertices, dtype=np.int64)
        self.sweeps = np.zeros(len(self.edge_parts) - 1, np.int64)
        self._sched = None  # (frame, Schedule) of the last schedule() call
        # measured on the first positions detected from (the module doc of inflo.tools.collide)
        self.cell_size = None
        self.converged_below = None
        self.round0_clear = True
        """the last step's round 0 found no contact (the next one is probed: resolve_collisions)"""
        self.restore(State.at_start(model) if state is None else state)

    def restore(self, state: State) -> None:
        """Go on from ``state``: its florets present, the rest values of its frame."""
        self.state = state
        self._sched = None
        self.set_born(state.born)
        self.update_rest(float(state.frame))

    def set_born(self, born: np.ndarray) -> None:
        """Make the florets of the (nf,) bool mask ``born`` the canopy: only their triangles and
        edges enter collision detection, the sanity checks and the output (see the module doc)."""
        self.state.born = np.asarray(born, dtype=bool).copy()
        self.present = Present.of(self.model, self.state.born)

    def global_tris(self, pairs: np.ndarray) -> np.ndarray:
        """Triangle pairs indexing ``present.tri`` -> indices into the model's triangles."""
        return pairs if self.present.tri_ids is None else self.present.tri_ids[pairs]

    def intersecting(self, x: np.ndarray) -> np.ndarray:
        """Exact static test of the present canopy: intersecting triangle pairs (model indices)."""
        ids = self.present.tri_ids
        part = self.model.tri_floret if ids is None else self.model.tri_floret[ids]
        return self.global_tris(intersecting_pairs(x, self.present.tri, tri_part=part))

    def emerge(self, x: np.ndarray, frame: float) -> tuple[list, list]:
        """Let the florets due by ``frame`` emerge where they intersect nothing (module doc).

        A due floret is tried at each of the ``emergence scales`` in turn (its own size first):
        the first size at which it intersects nothing is the size it emerges at, and it grows back
        to its own size over ``emergence growth frames`` frames, into the room it gets (the
        collision response keeps it there). ``x`` is updated in place for florets that emerged
        smaller. Returns (the florets that emerged, those still waiting), placement indices.
        """
        m = self.model
        st = self.state
        due = ~st.born & (m.floret_birth <= frame + 1e-9)
        if not due.any():
            return [], []
        cand = np.nonzero(due)[0]
        born = st.born.copy()
        out: list = []
        if not self.params.collisions:  # no room needed: every due floret emerges at its own size
            born[cand] = True
            self._sched = None
            self.set_born(born)
            return cand.tolist(), []
        for size in self.params.emergence_scales:
            if not len(cand):
                break
            if size < 1.0:
                self._pose(x, cand, frame, size)
            ids = np.nonzero((born | due)[m.tri_floret])[0]
            which = np.nonzero(due[m.tri_floret[ids]])[0]
            pairs = intersecting_pairs_with(x, m.tri_indices[ids], which, cell_size=self._cell(x),
                                            tri_part=m.tri_floret[ids])
            fl = m.tri_floret[ids[pairs]] if len(pairs) else np.zeros((0, 2), np.int32)
            blocked_by: dict = {}
            for a, b in fl.tolist():
                blocked_by.setdefault(a, set()).add(b)
                blocked_by.setdefault(b, set()).add(a)
            left = []
            for c in cand.tolist():
                others = blocked_by.get(c, ())
                if c in others or any(born[o] for o in others):  # self-intersecting, or no room
                    left.append(c)
                    continue
                born[c] = True
                due[c] = False
                out.append(c)
                if size < 1.0:
                    st.emerge_scale[c] = size
                    st.emerge_frame[c] = frame
            cand = np.array(left, np.int64)
            if size < 1.0 and len(cand):
                self._pose(x, cand, frame, 1.0)  # still waiting: back at their own size
        if out:
            self._sched = None
            self.set_born(born)
            if (st.emerge_scale[out] < 1.0).any():
                self.update_rest(frame)  # the rest values of the smaller florets' size
        return out, cand.tolist()

    def _pose(self, x: np.ndarray, florets, frame: float, size: float) -> None:
        """Put the vertices of ``florets`` on their templates at ``frame``, scaled by ``size``."""
        m = self.model
        sched = self.schedule(frame)
        mats = sched.matrix.copy()
        mats[florets, :, :3] *= size
        off = m.floret_vertex_offset
        verts = np.concatenate([np.arange(off[f], off[f + 1]) for f in florets]).astype(np.int32)
        m.template_positions(sched._replace(matrix=mats), vertices=verts, out=x)

    def size_factor(self, frame: float) -> np.ndarray:
        """(nf,) the size of each floret relative to its own at ``frame``: 1, or growing linearly
        from the size it emerged at to 1 over ``emergence growth frames``."""
        s0 = self.state.emerge_scale
        g = s0 + (1.0 - s0) * (frame - self.state.emerge_frame) / float(self.params.emergence_growth_frames)
        return np.clip(np.where(s0 < 1.0, g, 1.0), 0.0, 1.0)

    def schedule(self, frame: float) -> Schedule:
        """:meth:`.model.Model.schedule` at ``frame``, each floret's placement scaled by
        :meth:`size_factor` (about its base: the floret's local origin)."""
        if self._sched is None or self._sched[0] != frame:
            sched = self.model.schedule(frame)
            if (self.state.emerge_scale < 1.0).any():
                mats = sched.matrix.copy()
                mats[:, :, :3] *= self.size_factor(frame)[:, None, None]
                sched = sched._replace(matrix=mats)
            self._sched = (frame, sched)
        return self._sched[1]

    def initial_positions(self) -> np.ndarray:
        """Positions of frame 0: every floret's template at its time, placed
        (:meth:`.model.State.at_start`); the rest values become frame 0's."""
        x = State.at_start(self.model).vertex_x
        self.update_rest(0.0)
        return x

    def update_rest(self, frame: float) -> None:
        """The rest values (:attr:`edge_rest_length`, :attr:`hinge_rest_angle`) at ``frame``."""
        self.model.rest_values(self.schedule(frame), edge_rest_length=self.edge_rest_length,
                               hinge_rest_angle=self.hinge_rest_angle)

    def advance(self, frame_from: float, frame_to: float, timing: dict) -> tuple[CollisionResult, list]:
        """One step of :attr:`state` from ``frame_from`` to ``frame_to`` (:meth:`step`), then the
        emergence of the florets due by then (:meth:`emerge`). Returns the step's CollisionResult
        and the florets still waiting (placement indices)."""
        st = self.state
        st.vertex_x, res = self.step(st.vertex_x, frame_from, frame_to, timing)
        _, waiting = self.emerge(st.vertex_x, frame_to)
        return res, waiting

    def _cell(self, x: np.ndarray) -> float:
        if self.cell_size is None:
            boxes = triangle_boxes(x, x, self.model.tri_indices, 0.0)
            self.cell_size = lattice_cell_size(self.params.lattice, x.min(axis=0), x.max(axis=0), boxes)
        return self.cell_size

    def check_whole(self, x: np.ndarray, frame: float) -> None:
        """Raise :class:`SimulationDiverged` when an edge is over :data:`DIVERGED_STRETCH` x its
        rest length (``frame``: the frame being computed, for the message)."""
        m = self.model
        torn = overstretched_edges(x, m.edge_indices, self.edge_rest_length, DIVERGED_STRETCH,
                                   float(self.converged_below or 0.0) + 1e-300)
        if len(torn):
            k = int(math.ceil(frame))
            fl = np.unique(m.vertex_floret[m.edge_indices[torn, 0]])
            raise SimulationDiverged(
                f"frame {k}: the simulation diverged: {len(torn)} edges of florets "
                f"{_ids_text(fl.tolist())} are over "
                f"{DIVERGED_STRETCH:g} times their rest length (florets squeezed harder than the collision "
                f"response can resolve; give them room: smaller florets, a larger spacing, more "
                f"updates per frame); frames up to {k - 1} are complete")

    @property
    def stretch_floor(self) -> float:
        """Rest length below which an edge's stretch is not measured: the collision thickness h
        (the response pushes apart by h, so an edge shorter than h cannot keep its length; such
        edges are the collapsed tips of buds and nearly coincident seams)."""
        return max(float(self.params.spacing), float(self.converged_below or 0.0) * 1e3, 1e-300)

    def stretch_range(self, x: np.ndarray) -> tuple[float, float]:
        """(smallest, largest) edge length / rest length of the present florets (log columns)."""
        m = self.model
        on = self.present.edge_on
        if on is None:
            return edge_stretch_range(x, m.edge_indices, self.edge_rest_length, self.stretch_floor)
        return edge_stretch_range(x, m.edge_indices[on], self.edge_rest_length[on], self.stretch_floor)

    def step(self, x: np.ndarray, frame_from: float, frame_to: float, timing: dict, depth: int = 0):
        """One simulation step from ``frame_from`` to ``frame_to``; returns (new x, CollisionResult).

        A step after which pairs still cross is redone as two half steps (recursively, ``max
        substeps`` deep). (Redoing also the steps that leave a floret out of the stretch bounds,
        ``CollisionResult.misshapen``, mended the draft yarrow's 1.55 but made the 100k benchmark
        canopy, whose florets are squeezed out of the bounds in most steps, 9 x slower: not done.)
        Where the deepest half step still leaves pairs crossing, and wherever a
        floret ends a step with an edge outside the ``edge stretch bounds``, the florets concerned
        are moved back along their own motion (:func:`inflo.tools.collide.retreat_parts`), whole:
        a floret with no room to open stays as open as it was (carried by its placement) until
        its neighbours give it room.
        """
        last = depth >= self.params.max_substeps
        xp, res = self._attempt(x, frame_from, frame_to, timing, retreat_crossing=last)
        if len(res.remaining) and not last:
            timing["substeps"] = timing.get("substeps", 0) + 1
            mid = 0.5 * (frame_from + frame_to)
            xm, r1 = self.step(x, frame_from, mid, timing, depth + 1)
            xp, r2 = self.step(xm, mid, frame_to, timing, depth + 1)
            return xp, _merged(res, r1, r2)
        if len(res.remaining) and self.present.vertex_ids is not None:
            res.remaining.indices = self.present.vertex_ids[res.remaining.indices]
        return xp, res

    def _attempt(self, x: np.ndarray, frame_from: float, frame_to: float, timing: dict,
                 retreat_crossing: bool = True):
        """Prediction, internal constraints and collision response of one step, with the
        whole-floret fallback for florets out of the stretch bounds (and, ``retreat_crossing``,
        for those of pairs still crossing). Returns (new x, CollisionResult)."""
        m = self.model
        p = self.params
        t0 = time.perf_counter()
        old = Schedule(*(a.copy() for a in self.schedule(frame_from)))
        new = self.schedule(frame_to)
        self.update_rest(frame_to)
        # rigid carry: D = M_new M_old^-1 per floret
        full_old = np.zeros((len(old.matrix), 4, 4))
        full_old[:, :3] = old.matrix
        full_old[:, 3, 3] = 1.0
        full_new = np.zeros_like(full_old)
        full_new[:, :3] = new.matrix
        full_new[:, 3, 3] = 1.0
        delta = np.ascontiguousarray(la.matmul(full_new, la.inv(full_old))[:, :3])
        xp = np.empty_like(x)
        m.predict(x, delta=delta, old=old, new=new, out=xp)
        m.template_positions(new, vertices=m.vertex_fixed, out=xp)
        t1 = time.perf_counter()
        w = m.vertex_inv_mass
        if self.converged_below is None:
            self.converged_below = 1e-9 * float(np.ptp(x, axis=0).max()) if len(x) else 0.0
        if self.solve_tolerance is None:
            self.solve_tolerance = self.converged_below
            if self.fast and len(self.edge_rest_length):
                self.solve_tolerance = max(FAST_TOLERANCE * float(np.median(self.edge_rest_length)),
                                           self.converged_below)
        if self.coloured:
            for _ in range(p.solver_iterations):
                project_distance_constraints_coloured(xp, w, m.edge_indices, self.edge_rest_length,
                                                      m.edge_stiffness, *self.edge_colours)
                project_bending_constraints_coloured(xp, w, m.hinge_indices, self.hinge_rest_angle,
                                                     m.hinge_stiffness, *self.hinge_colours)
        elif p.solver_iterations > 0:
            predicted = xp.copy()
            # florets in contact need all the sweeps, the others one: hand out florets a few at a
            # time (dynamic schedule) rather than half the canopy to each thread
            with numba.parallel_chunksize(4):
                n = solve_parts(xp, w, m.edge_indices, self.edge_rest_length, m.edge_stiffness, self.edge_parts,
                                m.hinge_indices, self.hinge_rest_angle, m.hinge_stiffness, self.hinge_parts,
                                self._iterations(), float(self.solve_tolerance), self.sweeps)
            timing["sweeps"] = timing.get("sweeps", 0) + n
            if not self.one_part:
                # a floret the collision response left crumpled can send the bending projection
                # off (each hinge may move a vertex by pi x its size): such a floret keeps its
                # prediction (its shape carried by its placement) rather than ending the run
                timing["runaway"] = timing.get("runaway", 0) + _undo_runaway(
                    xp, self._all_vertices, predicted, m.vertex_floret)
        self.check_whole(xp, frame_to)  # a diverged solve: stop before detecting collisions on it
        t2 = time.perf_counter()
        if not p.collisions:  # the growth alone (fcc key ``collisions: off``)
            t3 = time.perf_counter()
            timing["rest"] = timing.get("rest", 0.0) + (t1 - t0)
            timing["internal"] = timing.get("internal", 0.0) + (t2 - t1)
            timing["collide"] = timing.get("collide", 0.0) + (t3 - t2)
            return xp, CollisionResult()
        kw = dict(thickness=p.spacing, stiffness=p.k_collision, iterations=p.collision_iterations,
                  max_retries=p.max_collision_retries, tolerance=default_tolerance(x, p.spacing),
                  cell_size=self._cell(x), fallback="parts")
        present = self.present
        v = present.vertex_ids
        nf = len(m.florets)
        lo, hi = p.stretch_bounds
        # checked with a 1 % margin, so that the written (rounded) frame is within the bounds too
        lo, hi = lo * 1.01, hi * 0.99
        floor = self.stretch_floor
        if v is None:
            x0s, x1s, tri, edges, vp = x, xp, m.tri_indices, m.edge_indices, m.vertex_floret
            rest = self.edge_rest_length
        else:  # florets yet to emerge take no part: solve the present ones' system, then scatter
            x0s, x1s, tri, edges = x[v], xp[v], present.tri_local, present.edge_local
            vp = m.vertex_floret[v]
            rest = self.edge_rest_length[present.edge_on]
        relax = None
        if p.relax_iterations > 0 and p.solver_iterations > 0 and not self.coloured:
            relax = self._relaxer(xp, v, vp, int(p.relax_iterations), timing)

        def misshapen(xs):
            return parts_out_of_bounds(xs, edges, rest, vp, nf, lo, hi, floor)

        def carried():
            out = np.empty_like(x0s)
            carry(x0s, vp, delta, out)
            return out

        def scaled(xs, which, scale):
            """``xs`` with the florets of ``which`` scaled by ``scale`` about their bases (their
            placements' origins at ``frame_to``); the other rows as they are."""
            out = xs.copy()
            sel = which[vp]
            base = np.ascontiguousarray(new.matrix[:, :, 3])[vp[sel]]
            out[sel] = base + scale * (xs[sel] - base)
            return out

        def shrink(scale, which):
            """Smaller shapes of the florets ``which`` (out of shape, no room for their carried
            shape): their carried shape (where that is in shape), then their rest shape, scaled by
            ``scale`` about each floret's base (its placement's origin at ``frame_to``); as
            ``(positions, fits)`` pairs (rows of other florets unused)."""
            c = carried()
            a = scaled(c, which, scale)
            mats = new.matrix.copy()
            mats[:, :, :3] *= scale
            off = m.floret_vertex_offset
            verts = np.concatenate([np.arange(off[f], off[f + 1]) for f in np.nonzero(which)[0]])
            xg = np.zeros((m.n_vertices, 3))
            m.template_positions(new._replace(matrix=mats), vertices=verts.astype(np.int32), out=xg)
            return [(a, ~misshapen(c)), (xg if v is None else xg[v], np.ones(nf, bool))]

        tri_part = vp[tri[:, 0]] if len(tri) else np.zeros(0, np.int64)

        def blockers(xs, which):
            """The florets not in ``which`` with a triangle intersecting one of ``which``'s."""
            ids = np.nonzero(which[tri_part])[0]
            out = np.zeros(nf, bool)
            pairs = intersecting_pairs_with(xs, tri, ids, cell_size=self._cell(x), tri_part=tri_part)
            if len(pairs):
                out[tri_part[pairs.ravel()]] = True
            return out & ~which

        def intersecting(xs, which):
            """The florets of ``which`` with a triangle intersecting another (exact static test);
            of two such florets intersecting each other, only the later is named (the earlier may
            then fit once the later has gone back)."""
            ids = np.nonzero(which[tri_part])[0]
            out = np.zeros(nf, bool)
            pairs = intersecting_pairs_with(xs, tri, ids, cell_size=self._cell(x), tri_part=tri_part)
            if len(pairs):
                a, b = tri_part[pairs[:, 0]], tri_part[pairs[:, 1]]
                both = which[a] & which[b]
                out[np.maximum(a, b)[both]] = True
                out[a[~both]] = True
                out[b[~both]] = True
            return out & which

        parts = Parts(vertex_part=vp, n_parts=nf, misshapen=misshapen, carried=carried,
                      crossing=retreat_crossing, shrink=shrink, intersecting=intersecting,
                      scaled=scaled, blockers=blockers,
                      shrink_scales=[s for s in p.crowded_scales if s < 1.0])
        # round 0 probed without pair lists while the last step's round 0 found nothing (a head
        # before its florets meet); once contacts come, retries follow and need the lists anyway
        res = resolve_collisions(x0s, x1s, w if v is None else w[v], tri, edges, relax=relax,
                                 relax_rounds=RELAX_ROUNDS, parts=parts, probe=self.round0_clear, **kw)
        self.round0_clear = not (res.found and res.found[0] > 0)
        if v is not None:
            xp[v] = x1s
        if len(res.shrunk) and (res.shrunk < 1.0).any():
            # florets put at a smaller size (no room for their own shape): they grow back from it
            # over ``emergence growth frames``, as florets that emerged smaller (size_factor)
            st = self.state
            small = np.nonzero(res.shrunk < 1.0)[0]
            st.emerge_scale[small] = self.size_factor(frame_to)[small] * res.shrunk[small]
            st.emerge_frame[small] = frame_to
            self._sched = None
            self.update_rest(frame_to)
            timing["shrunk"] = timing.get("shrunk", 0) + len(small)
        if res.whole_step:
            timing["whole_steps"] = timing.get("whole_steps", 0) + 1
        t3 = time.perf_counter()
        timing["rest"] = timing.get("rest", 0.0) + (t1 - t0)
        timing["internal"] = timing.get("internal", 0.0) + (t2 - t1)
        timing["collide"] = timing.get("collide", 0.0) + (t3 - t2)
        return xp, res

    def _iterations(self) -> int:
        """The internal solve's sweeps a step: ``solver iterations`` (``fast``: at most
        :data:`FAST_MAX_SWEEPS`)."""
        n = int(self.params.solver_iterations)
        return min(n, FAST_MAX_SWEEPS) if self.fast and FAST_MAX_SWEEPS is not None else n

    def _relaxer(self, xp: np.ndarray, v, vp: np.ndarray, iterations: int, timing: dict):
        """``relax(x1, moved)`` for :func:`resolve_collisions`: a few internal-constraint sweeps
        of the florets whose vertices the collision round moved (``x1``: the collision system's
        positions, the present florets' vertices when ``v`` is not None)."""
        m = self.model
        w = m.vertex_inv_mass

        def relax(x1, moved):
            fl = np.unique(vp[moved])
            if not len(fl):
                return
            parts = np.zeros(1, np.int64) if self.one_part else fl.astype(np.int64)
            xg = x1
            if v is not None:
                xp[v] = x1
                xg = xp
            off = m.floret_vertex_offset
            verts = (np.arange(len(xg)) if self.one_part
                     else np.concatenate([np.arange(off[f], off[f + 1]) for f in fl]))
            before = xg[verts]
            n = solve_parts(xg, w, m.edge_indices, self.edge_rest_length, m.edge_stiffness, self.edge_parts,
                            m.hinge_indices, self.hinge_rest_angle, m.hinge_stiffness, self.hinge_parts,
                            iterations, float(self.solve_tolerance), None, parts=parts)
            timing["relax_sweeps"] = timing.get("relax_sweeps", 0) + n
            _undo_runaway(xg, verts, before, m.vertex_floret[verts])
            if v is not None:
                x1[:] = xp[v]

        return relax


def _undo_runaway(x: np.ndarray, verts: np.ndarray, before: np.ndarray, floret: np.ndarray) -> int:
    """Put back the florets a solve or relaxation moved by more than half their own size: the
    bending projection can run away on a floret the collision response left badly out of shape,
    and one flung vertex would make the next detection round's boxes span the canopy. Returns the
    number of florets put back."""
    if len(verts):
        return int(_undo_runaway_kernel(x, np.ascontiguousarray(verts, dtype=np.int64), before,
                                        np.ascontiguousarray(floret, dtype=np.int64)))
    return 0


@numba.njit(cache=True)
def _undo_runaway_kernel(x, verts, before, floret):
    """:func:`_undo_runaway`: ``verts`` grouped or not, ``floret`` their florets."""
    nf = floret.max() + 1
    worst = np.zeros(nf)
    lo = np.full((nf, 3), np.inf)
    hi = np.full((nf, 3), -np.inf)
    for k in range(verts.shape[0]):
        f = floret[k]
        i = verts[k]
        d = 0.0
        for c in range(3):
            e = x[i, c] - before[k, c]
            d += e * e
            lo[f, c] = min(lo[f, c], before[k, c])
            hi[f, c] = max(hi[f, c], before[k, c])
        d = math.sqrt(d)
        if not d <= worst[f]:
            worst[f] = d if d == d else np.inf
    bad = np.zeros(nf, np.bool_)
    for f in range(nf):
        if worst[f] > 0.0:
            size = 0.0
            for c in range(3):
                size += (hi[f, c] - lo[f, c]) ** 2
            bad[f] = not worst[f] <= 0.5 * math.sqrt(size)
    for k in range(verts.shape[0]):
        if bad[floret[k]]:
            for c in range(3):
                x[verts[k], c] = before[k, c]
    return np.count_nonzero(bad)


def _merged(failed: CollisionResult, a: CollisionResult, b: CollisionResult) -> CollisionResult:
    """The result of a step redone as two half steps ``a`` and ``b`` (``failed``: the first try,
    whose detection work counts too)."""
    out = CollisionResult()
    out.rounds = failed.rounds + a.rounds + b.rounds
    out.found = list(failed.found[:1]) + list(a.found) + list(b.found)
    out.constraints = a.constraints + b.constraints
    out.reverted = a.reverted + b.reverted
    out.relaxed = failed.relaxed + a.relaxed + b.relaxed
    out.stats = dict(failed.stats)
    rem = [r for r in (a.remaining, b.remaining) if len(r)]
    out.remaining = rem[0] if len(rem) == 1 else (rem[0].concat(rem[1]) if rem else a.remaining)
    out.retreated = np.union1d(a.retreated, b.retreated)
    out.misshapen = b.misshapen
    return out
