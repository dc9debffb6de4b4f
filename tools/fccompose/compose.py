"""The Floral Canopy Composer: constraint-based growth with continuous collision handling.

:func:`compose_canopy` is Algorithm 1 of the thesis (section 8 f) over the model of
:mod:`.model`. For every simulation step (``updates per frame`` per frame):

1. ``applyAnimation``: each floret's developmental time and placement at the new time give the
   rest values of its constraints (edge lengths, signed dihedral angles; :func:`.model.rest_values`)
   and the attachment targets of its fixed vertices;
2. prediction (:func:`.model.predict`): every vertex is carried rigidly with its floret's
   placement change (a floret moved by ``ta``/``ra``/``rba`` moves with it) and moved by its
   template's displacement over the step (the growth "velocity": an undeformed floret lands on
   its template exactly, so rest values need not drag long petals round by Gauss-Seidel sweeps
   alone); fixed vertices (inverse mass 0) are put on their targets (attachment constraints);
3. ``solverIterations`` Gauss-Seidel sweeps over the distance (eq. 3.11) then bending (eq. 3.13)
   constraints;
4. continuous collision detection from the collision-free positions of the previous step to the
   predicted ones, collision constraints C_vt/C_ee (eqs. 4.6-4.7) solved for ``collision
   iterations``, re-detected up to ``max collision retries`` times
   (:func:`inflo.tools.collide.resolve_collisions`). After each of the first ``RELAX_ROUNDS``
   rounds the florets it moved get ``relax iterations`` internal sweeps (collision and internal
   constraints solved together, as Alg. 1 intends), and florets left outside the ``edge stretch
   bounds`` get repair passes. A step that leaves pairs crossing is redone as two half steps, up
   to ``max substeps`` deep; where the deepest still leaves some, they are reported by floret and
   frame and those florets moved back whole along their own motion
   (:func:`inflo.tools.collide.retreat_parts`; so the canopy stays collision-free), or the run
   stops with ``strict``; florets still out of shape are put on their carried start-of-step shape
   where that crosses nothing, else on a smaller shape (``crowded scales``) from which they grow
   back as emerging florets do (formats/fcc.md, "Crowding");
5. the positions are accepted.

**Emergence.** A floret of an ``rba:`` placement emerges at the first RBA frame that lists it
(:attr:`.model.Floret.birth_frame`): until then it is not part of the canopy (its triangles and
edges take part in no collision test and it has no faces in the output; its vertices wait, still
numbered, at its first RBA pose). At the end of the first step that reaches its frame it appears
there, at its developmental time, provided it intersects nothing: the exact static test of its
triangles against the canopy's (:func:`inflo.tools.collide.intersecting_pairs_with`) keeps the
positions collision-free, so the continuous detection that follows starts from a valid state. A
floret with no room at its own size is tried at each of the ``emergence scales`` and emerges at
the first that fits, then grows back to its own size over ``emergence growth frames``
(:meth:`Simulation.size_factor`); one that fits at none waits and is tried again after every step
("first available space"); florets due at the same step are taken in placement order. ``log.csv`` counts the florets present and
those waiting.

The canopy is written as ``OUT/frame_NNNN.obj`` (frame 0 is the initial state) every output
period and at the last frame, one OBJ group ``floret_<index>`` per floret and per triangle the
``usemtl`` of its template OBJ (a floret's organs keep their materials), else ``mtl<id>`` from the
SCN ``mtl:`` lines (:attr:`.model.Model.face_materials`). ``OUT/log.csv`` (:mod:`.log`) has a row per frame. Next to every
written frame ``OUT/state/`` keeps the run's :class:`.model.State` (``frame_NNNN.npy``: the exact
float64 positions; ``run.json``: the frame, the inputs' fingerprint and which florets have emerged,
at what size) so that ``resume`` continues bit-identically from the last complete frame.

The split of :mod:`.model`: :class:`.model.Model` is what never changes, :class:`.model.State`
what a frame hands to the next, and :class:`Simulation` the control (solver settings, rest
values, the present florets' collision system, caches) that moves the state one step at a time.
"""
from __future__ import annotations

import contextlib
import hashlib
import io
import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numba
import numpy as np

from inflo.formats.atomic import frame_name, remove_stale_frames, write_bytes_atomic, write_text_atomic
from inflo.formats.errors import InputError
from inflo.formats.fcc import CanopyParams, check_references
from inflo.formats.obj import ObjMesh, write_obj, written_vertices
from inflo.tools.collide.broad import lattice_cell_size, triangle_boxes
from inflo.tools.collide.contacts import default_tolerance
from inflo.tools.collide.resolve import CollisionResult, resolve_collisions
from inflo.tools.collide.tritri import intersecting_pairs, intersecting_pairs_with
from inflo.tools.common import linalg as la
from inflo.tools.pbd.solver import (
    bending_residual,
    colour_constraints,
    distance_residual,
    edge_stretch_range,
    overstretched_edges,
    part_offsets,
    parts_out_of_bounds,
    project_bending_constraints_coloured,
    project_distance_constraints_coloured,
    solve_parts,
)

from .log import FrameLog, read_log, write_log
from .model import Model, Schedule, State, build_model, carry

__all__ = ["ComposeResult", "CollisionError", "InitialIntersectionError", "SimulationDiverged", "compose_canopy",
           "Simulation"]


#: collision rounds of a step followed by a relaxation of the florets they moved (the first ones)
RELAX_ROUNDS = 3


class InitialIntersectionError(InputError):
    """The first frame is not collision-free (exit 2 in the CLI)."""


class CollisionError(RuntimeError):
    """``strict``: pairs still crossing after the retries, or the sanity check found intersections."""


class SimulationDiverged(RuntimeError):
    """Florets torn apart (edges far beyond their rest length): the run stops at that frame."""


DIVERGED_STRETCH = 50.0
"""A frame in which an edge is longer than this many times its rest length stops the run
(:class:`SimulationDiverged`) before that frame is written: the last guard against a constraint
solve running away (to coordinates of 1e11 and more within a frame or two) on florets squeezed
far harder than the collision response can resolve. (The per-vertex revert fallback, which tore
florets carried by their RBA motion, is gone: florets are moved back whole.)"""


@dataclass
class ComposeResult:
    """Summary of a run."""

    frames_written: list = field(default_factory=list)
    first_frame: int = 0
    last_frame: int = 0
    n_triangles: int = 0
    n_vertices: int = 0
    steps: int = 0
    remaining_reports: list = field(default_factory=list)
    seconds: float = 0.0
    waiting: list = field(default_factory=list)
    """florets due to emerge that found no room by the last frame (placement indices)"""


def _pairs_by_floret(model: Model, tri_pairs: np.ndarray) -> list[tuple[int, int]]:
    fl = model.tri_floret[tri_pairs]
    fl.sort(axis=1)
    return sorted({(int(a), int(b)) for a, b in fl.tolist()})


def _florets_text(pairs) -> str:
    return ";".join(f"{a}-{b}" for a, b in pairs)


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
    """

    def __init__(self, model: Model, *, coloured: bool = False, state: State | None = None):
        self.model = model
        p = model.params
        self.params = p
        self.edge_rest_length = np.zeros(len(model.edge_indices))
        self.hinge_rest_angle = np.zeros(len(model.hinge_indices))
        self.coloured = coloured
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
                                int(p.solver_iterations), float(self.converged_below), self.sweeps)
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

        parts = dict(vertex_part=vp, n_parts=nf, misshapen=misshapen, carried=carried,
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
                            iterations, float(self.converged_below), None, parts=parts)
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


def _input_hashes(params: CanopyParams) -> dict:
    """sha256 of every file the run reads besides the templates (scene files, RBA frames, weight
    and petal weight files), keyed by the path as the ``.fcc`` names it (an RBA folder: ``folder/NNNN.rba`` each),
    so that ``--resume`` can name the input that changed."""
    out = {}
    paths = [(f.raw, f.resolved) for f in params.scene_files]
    for r in params.rigid_body_animations:
        paths.append((r.scene_path.raw, r.scene_path.resolved))
        folder = Path(r.rba_folder.resolved)
        if folder.is_dir():
            paths += [(f"{r.rba_folder.raw.rstrip('/')}/{p.name}", p) for p in sorted(folder.glob("*.rba"))]
    paths += [(f.raw, f.resolved) for f in params.weights.values()]
    paths += [(f.raw, f.resolved) for f in params.petal_weights.values()]
    for raw, path in paths:
        path = Path(path)
        if path.is_file() and raw not in out:
            out[raw] = hashlib.sha256(path.read_bytes()).hexdigest()
    return out


def _fingerprint(params: CanopyParams, model: Model, inputs: dict | None = None) -> str:
    """One hash of the parameter file, the templates (positions and triangles) and ``inputs``
    (:func:`_input_hashes`): a resumed run must have read the same."""
    h = hashlib.sha256()
    if params.source is not None and Path(params.source).is_file():
        h.update(Path(params.source).read_bytes())
    h.update(model.template_x.tobytes())
    h.update(model.tri_indices.tobytes())
    for raw, digest in sorted((inputs or {}).items()):
        h.update(raw.encode("utf-8") + b"\0" + digest.encode("ascii"))
    return h.hexdigest()


#: Coordinate formats of the written frames, tried in turn (:func:`written_format`).
WRITE_FORMATS = ("%.6f", "%.9f", "%.12f", "%.17g")


def written_format(x: np.ndarray, faces: np.ndarray, formats=WRITE_FORMATS, tri_part: np.ndarray | None = None) -> str:
    """The first of ``formats`` whose written coordinates keep the canopy as collision-free as
    ``x`` is: rounding to 6 decimals can make two petals that lie flat on each other, closer than
    the rounding, cross (a written-frame guarantee). The written numbers are parsed back
    and tested exactly (:func:`intersecting_pairs`, touching counts); where ``x`` itself has
    intersecting pairs (the sanity check reports them), more digits cannot help and the first
    format is kept. ``tri_part``: the floret of each face (the exact test goes floret by floret)."""
    return written_text(x, faces, formats, tri_part)[0]


def written_text(x: np.ndarray, faces: np.ndarray, formats=WRITE_FORMATS,
                 tri_part: np.ndarray | None = None) -> tuple[str, str]:
    """(:func:`written_format`, the ``v`` lines of ``x`` in it): the frame's vertices formatted
    once, for the check and the file."""
    n = None
    first = None
    for fmt in formats:
        xr, text = written_vertices(x, fmt)
        if first is None:
            first = (fmt, text)
        if fmt == formats[-1]:
            return fmt, text
        found = len(intersecting_pairs(xr, faces, tri_part=tri_part))
        if found == 0:
            return fmt, text
        if n is None:
            n = len(intersecting_pairs(x, faces, tri_part=tri_part))
            if n >= found:
                return first
    return first


def _write_frame(out: Path, model: Model, x: np.ndarray, k: int, tri_on: np.ndarray | None = None,
                 exact: bool = True) -> Path:
    """The canopy at frame ``k``: every vertex (stable numbering), the faces of the florets
    present (``tri_on``: a mask over the model's triangles; None: all); the obstacles' vertices
    and faces left out. ``exact``: the coordinates with as many digits as keep the written frame
    collision-free (:func:`written_format`)."""
    mats, face_material = model.face_materials
    faces, face_group = model.tri_indices, model.tri_floret.copy()
    if tri_on is not None:
        faces, face_group = faces[tri_on], face_group[tri_on]
        if face_material is not None:
            face_material = face_material[tri_on]
    hidden = model.obstacle_vertices
    if hidden is not None:
        # obstacles collide but are not written: their faces and vertices go, the rest renumbered
        keep = ~hidden[faces[:, 0]]
        faces, face_group = faces[keep], face_group[keep]
        if face_material is not None:
            face_material = face_material[keep]
        renumber = np.cumsum(~hidden) - 1
        x, faces = x[~hidden], renumber[faces].astype(faces.dtype)
    fmt, text = written_text(x, faces, tri_part=face_group) if exact else (WRITE_FORMATS[0], None)
    present = len(np.unique(face_group))
    mesh = ObjMesh(
        vertices=x,
        faces=faces,
        groups=[f"floret_{fl.index}" for fl in model.florets],
        face_group=face_group,
        materials=mats,
        face_material=face_material,
    )
    path = out / frame_name(k, "frame_", ".obj", 4)
    florets = (f"{len(model.florets)} florets" if tri_on is None
               else f"{present} of {len(model.florets)} florets emerged")
    if hidden is not None:
        n_obstacles = len(model.obstacles)
        florets = f"{len(model.florets) - n_obstacles} florets and {n_obstacles} obstacles (not written)"
    write_obj(path, mesh, header=f"fccompose canopy, frame {k}: {florets}, {len(faces)} triangles", fmt=fmt,
              vertex_text=text)
    return path


def _save_state(out: Path, state: State, fingerprint: str, inputs: dict | None = None) -> None:
    """Write ``state`` to ``out/state/``: ``frame_NNNN.npy`` (the exact float64 positions, the
    only one kept) and ``run.json`` (``fingerprint``, ``frame``; ``not_emerged``: the florets not
    yet present, ``emerged_smaller``: [floret, size, frame] of those that emerged smaller, each
    only when there are any)."""
    sdir = out / "state"
    sdir.mkdir(exist_ok=True)
    buf = io.BytesIO()
    np.save(buf, state.vertex_x, allow_pickle=False)
    k = int(state.frame)
    write_bytes_atomic(sdir / frame_name(k, "frame_", ".npy", 4), buf.getvalue())
    info = {"fingerprint": fingerprint, "frame": k}
    if inputs:
        info["inputs"] = inputs
    if not state.born.all():
        info["not_emerged"] = np.nonzero(~state.born)[0].tolist()
    small = np.nonzero(state.emerge_scale < 1.0)[0]
    if len(small):
        info["emerged_smaller"] = [[int(i), float(state.emerge_scale[i]), float(state.emerge_frame[i])]
                                   for i in small]
    write_text_atomic(sdir / "run.json", json.dumps(info) + "\n")
    for old in sorted(sdir.glob("frame_*.npy")):
        if old.name != frame_name(k, "frame_", ".npy", 4):
            old.unlink()


def _load_state(out: Path, fingerprint: str, model: Model, inputs: dict | None = None) -> State | None:
    """The :class:`State` :func:`_save_state` wrote to ``out/state/``; None when there is none or
    its frame's OBJ is missing (nothing to resume: start from frame 0)."""
    sdir = out / "state"
    run = sdir / "run.json"
    if not run.is_file():
        return None
    info = json.loads(run.read_text())
    if info.get("fingerprint") != fingerprint:
        before = info.get("inputs") or {}
        changed = [k for k in sorted(set(before) | set(inputs or {})) if before.get(k) != (inputs or {}).get(k)]
        if changed:
            what = ("removed since" if changed[0] not in (inputs or {}) else
                    "added since" if changed[0] not in before else "changed since")
            raise InputError(f"{run}: expected the inputs of the run to resume, found {changed[0]} {what} it "
                             f"was interrupted{f' (and {len(changed) - 1} more)' if len(changed) > 1 else ''} "
                             f"(delete {out} or run without --resume)")
        raise InputError(f"{run}: expected a run of the same parameters and inputs to resume, "
                         f"found one of different parameters (delete {out} or run without --resume)")
    k = int(info["frame"])
    st = sdir / frame_name(k, "frame_", ".npy", 4)
    obj = out / frame_name(k, "frame_", ".obj", 4)
    if not st.is_file() or not obj.is_file():
        return None
    x = np.load(st, allow_pickle=False)
    if x.shape != (model.n_vertices, 3):
        raise InputError(f"{st}: expected positions of {model.n_vertices} vertices, found shape {x.shape}")
    nf = len(model.florets)
    born = np.ones(nf, bool)
    born[[int(i) for i in info.get("not_emerged", [])]] = False
    emerge_scale, emerge_frame = np.ones(nf), np.zeros(nf)
    for i, size, frame in info.get("emerged_smaller", []):
        emerge_scale[int(i)] = size
        emerge_frame[int(i)] = frame
    return State(x, k, born, emerge_scale, emerge_frame)


@dataclass
class _Run:
    """What a run of :func:`compose_canopy` keeps beside its :class:`Simulation`: where it
    writes, how it reports, what it has logged."""

    sim: Simulation
    out: Path
    fingerprint: str
    strict: bool
    warn: Callable
    result: ComposeResult
    log_rows: list = field(default_factory=list)
    inputs: dict = field(default_factory=dict)
    """sha256 of each input file (:func:`_input_hashes`), saved with the state"""


def compose_canopy(params: CanopyParams, out_dir, *, resume: bool = False, strict: bool = False,
                   allow_initial_intersections: bool = False, progress=None, warn=None,
                   coloured: bool = False) -> ComposeResult:
    """Simulate the canopy's development and write it as an OBJ per output frame.

    Parameters
    ----------
    params : CanopyParams
        The ``.fcc`` file (:func:`inflo.formats.fcc.read_fcc`).
    out_dir : path
        Output folder (created).
    resume : bool
        Continue from the last complete output frame of a previous run of the same inputs.
    strict : bool
        Stop (:class:`CollisionError`) when pairs still cross after the retries or the sanity check
        finds intersections, instead of reporting them and continuing.
    allow_initial_intersections : bool
        Accept an initial state that is not collision-free (otherwise
        :class:`InitialIntersectionError` naming the floret pairs).
    progress : callable or None
        ``progress(total_frames)`` returning a context manager whose value has ``update(n)``
        (:func:`inflo.tools.common.cli.progress` fits); None: no progress reporting.
    warn : callable or None
        Called with one line per reported problem.
    coloured : bool
        Parallel colour-by-colour constraint sweeps (see :class:`Simulation`).

    Returns
    -------
    ComposeResult
    """
    t_start = time.perf_counter()
    check_references(params)
    model = build_model(params)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    inputs = _input_hashes(params)
    fp = _fingerprint(params, model, inputs)
    n = model.n_frames
    state = _load_state(out, fp, model, inputs) if resume else None
    run = _Run(Simulation(model, coloured=coloured, state=state), out, fp, strict, warn or (lambda msg: None),
               ComposeResult(n_triangles=model.n_triangles, n_vertices=model.n_vertices, last_frame=n),
               inputs=inputs)
    result = run.result
    if state is not None:
        run.log_rows = [r for r in read_log(out / "log.csv") if r and int(r[0]) <= state.frame]
        result.first_frame = state.frame + 1
    else:
        # an older run's frames go before this one writes any: interrupted, it leaves a shorter
        # sequence of its own frames (which --resume continues), never a mix of two runs
        remove_stale_frames(out, [], ".obj")
        _first_frame(run, allow_initial_intersections)
        result.first_frame = 1

    k0 = run.sim.state.frame
    bar_cm = progress(n - k0) if progress else contextlib.nullcontext(None)
    with bar_cm as bar:
        _run_frames(run, bar)
    if result.waiting:
        ids = result.waiting
        run.warn(f"{len(ids)} florets due to emerge found no room by frame {n} (placement indices "
                 f"{_ids_text(ids)}): each intersects the "
                 f"canopy, or itself, where its RBA files place it")
    # frames of an earlier, longer run in the same folder are not part of this one
    every = params.output_every
    remove_stale_frames(out, [frame_name(k, "frame_", ".obj", 4) for k in range(n + 1)
                              if k % every == 0 or k == n], ".obj")
    result.seconds = time.perf_counter() - t_start
    return result


def _first_frame(run: _Run, allow_initial_intersections: bool) -> None:
    """Frame 0, the initial state: it must be collision-free (thesis 4.2); logged and written."""
    row = FrameLog(0, 0)
    pairs = _end_of_frame(run, row, check=True)
    if len(pairs):
        fl = _pairs_by_floret(run.sim.model, pairs)
        msg = (f"{run.sim.params.source}: expected a collision-free first frame (thesis 4.2), found "
               f"{len(pairs)} intersecting triangle pairs between florets {_florets_text(fl[:20])}"
               + (" ..." if len(fl) > 20 else "")
               + " (placement indices; --allow-initial-intersections to go on)")
        if not allow_initial_intersections and run.sim.params.collisions:
            raise InitialIntersectionError(msg)
        if run.sim.params.collisions:
            run.warn(msg)
    _record(run, row, write=True)


def _run_frames(run: _Run, bar) -> None:
    """Frames ``state.frame + 1`` to the last: ``updates per frame`` steps each, with the
    emergence after every step; the frame's log row; its OBJ and state every output period and
    at the last frame."""
    sim = run.sim
    params, model, st = sim.params, sim.model, sim.state
    upf = params.updates_per_frame
    n, every = model.n_frames, params.output_every
    for k in range(st.frame + 1, n + 1):
        row = FrameLog(k, upf)
        timing: dict = {}
        remaining = []
        retreated: set = set()
        waiting: list = []
        for s in range(upf):
            f_from = (k - 1) + s / upf
            f_to = (k - 1) + (s + 1) / upf
            res, waiting = sim.advance(f_from, f_to, timing)
            run.result.steps += 1
            row["vt_candidates"] += res.stats.get("vt_candidates", 0)
            row["ee_candidates"] += res.stats.get("ee_candidates", 0)
            row["collisions_found"] += res.found[0] if res.found else 0
            row["collision_rounds"] += res.rounds
            row["collision_constraints"] += res.constraints
            row["reverted_vertices"] += res.reverted
            retreated.update(res.retreated.tolist())
            if len(res.remaining):
                row["remaining_pairs"] += len(res.remaining)
                fl = np.unique(np.sort(model.vertex_floret[res.remaining.indices[:, [0, 3]]], axis=1), axis=0)
                remaining.extend((int(a), int(b)) for a, b in fl.tolist())
        if remaining:
            remaining = sorted(set(remaining))
            row["remaining_florets"] = _florets_text(remaining)
            msg = (f"frame {k}: {row['remaining_pairs']} colliding pairs left after "
                   f"{params.max_collision_retries} retries between florets {_florets_text(remaining[:20])}"
                   f" (those florets were moved back along their own motion, whole)")
            run.result.remaining_reports.append((k, remaining))
            if run.strict:
                raise CollisionError(msg)
            run.warn(msg)
        if timing.get("runaway", 0):
            run.warn(f"frame {k}: the internal solve ran away on florets out of shape {timing['runaway']} "
                     f"times (a vertex sent over half its floret's size); each kept its predicted shape for "
                     f"that step")
        sim.check_whole(st.vertex_x, k)
        st.frame = k
        row["substeps"] = timing.get("substeps", 0)
        row["relax_sweeps"] = timing.get("relax_sweeps", 0)
        row["florets_retreated"] = len(retreated)
        row["florets_smaller"] = int(np.count_nonzero(sim.size_factor(float(k)) < 1.0))
        row["t_rest_s"] = timing.get("rest", 0.0)
        row["t_internal_s"] = timing.get("internal", 0.0)
        row["t_collide_s"] = timing.get("collide", 0.0)
        row["florets_waiting"] = len(waiting)
        run.result.waiting = waiting
        check = bool(params.sanity_check_every) and k % params.sanity_check_every == 0
        pairs = _end_of_frame(run, row, check=check)
        if pairs is not None and len(pairs) and params.collisions:  # off: only counted (log.csv)
            fl = _pairs_by_floret(model, pairs)
            msg = (f"frame {k}: sanity check found {len(pairs)} intersecting triangle pairs "
                   f"between florets {_florets_text(fl[:20])}")
            if run.strict:
                raise CollisionError(msg)
            run.warn(msg)
        _record(run, row, write=k % every == 0 or k == n)
        if bar is not None:
            bar.update(1)


def _end_of_frame(run: _Run, row: FrameLog, *, check: bool) -> np.ndarray | None:
    """The log columns of the state at the end of a frame: residuals, stretch, florets present
    and, ``check``, the exact static intersection test. Returns its intersecting triangle pairs
    (model indices), None when not checked."""
    sim = run.sim
    m, x = sim.model, sim.state.vertex_x
    row["min_edge_stretch"], row["max_edge_stretch"] = sim.stretch_range(x)
    row["rms_edge_error"] = distance_residual(x, m.edge_indices, sim.edge_rest_length)
    row["rms_dihedral_error_deg"] = math.degrees(bending_residual(x, m.hinge_indices, sim.hinge_rest_angle))
    row["florets_present"] = int(sim.state.born.sum())
    if not check:
        return None
    t0 = time.perf_counter()
    pairs = sim.intersecting(x)
    row["t_sanity_s"] = time.perf_counter() - t0
    row["intersecting_pairs"] = len(pairs)
    return pairs


def _record(run: _Run, row: FrameLog, *, write: bool) -> None:
    """Log the frame's ``row``; ``write``: write the frame's OBJ and state, then the log."""
    run.log_rows.append(row)
    if write:
        sim = run.sim
        t0 = time.perf_counter()
        run.result.frames_written.append(_write_frame(run.out, sim.model, sim.state.vertex_x, sim.state.frame,
                                                      sim.present.tri_on, exact=sim.params.collisions))
        _save_state(run.out, sim.state, run.fingerprint, run.inputs)
        row["t_write_s"] = time.perf_counter() - t0
        write_log(run.out / "log.csv", run.log_rows)
        # the rows written are final: kept as their text (the log is rewritten every frame)
        run.log_rows = [r.text() if isinstance(r, FrameLog) else r for r in run.log_rows]
