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

The run lives in rooms of one concern each: this module runs the frames (:func:`compose_canopy`:
the first frame, the frame loop, logging, reports) and is the import path of the names below;
:mod:`.simulation` holds the control, :class:`Simulation` (one step, its retries and the
collision policy); :mod:`.output` writes the frames and the resume state.
"""
from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from inflo.formats.atomic import begin_sequence, end_sequence, frame_name
from inflo.formats.errors import InputError
from inflo.formats.fcc import CanopyParams, check_references
from inflo.tools.pbd.solver import bending_residual, distance_residual

from .log import FrameLog, read_log, write_log
from .model import Model, build_model
from .output import WRITE_FORMATS as WRITE_FORMATS
from .output import _fingerprint, _input_hashes, _load_state, _save_state, _write_frame
from .output import written_format as written_format
from .output import written_text as written_text
from .simulation import DIVERGED_STRETCH as DIVERGED_STRETCH
from .simulation import RELAX_ROUNDS as RELAX_ROUNDS
from .simulation import Present as Present
from .simulation import Simulation, SimulationDiverged, _ids_text
from .simulation import _merged as _merged
from .simulation import _undo_runaway as _undo_runaway

__all__ = ["ComposeResult", "CollisionError", "InitialIntersectionError", "SimulationDiverged", "compose_canopy",
           "Simulation"]


class InitialIntersectionError(InputError):
    """The first frame is not collision-free (exit 2 in the CLI)."""


class CollisionError(RuntimeError):
    """``strict``: pairs still crossing after the retries, or the sanity check found intersections."""


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
    every = params.output_every
    planned = [frame_name(k, "frame_", ".obj", 4) for k in range(n + 1) if k % every == 0 or k == n]
    if state is not None:
        run.log_rows = [r for r in read_log(out / "log.csv") if r and int(r[0]) <= state.frame]
        result.first_frame = state.frame + 1
    else:
        # an older run's frames go before this one writes any: interrupted, it leaves a shorter
        # sequence of its own frames (which --resume continues), never a mix of two runs; only
        # fccompose's own frames go (its manifest), never a user's file named like one
        begin_sequence(out, "fccompose", planned, ".obj")
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
    # frames of an earlier, longer run of its own in the same folder are not part of this one
    end_sequence(out, "fccompose", planned, ".obj")
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
