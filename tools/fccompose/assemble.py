"""Instancing every placement into one canopy (:func:`assemble_model`, thesis 8 f): florets, nested
scenes (:class:`~.system.Level`), RBA rows, obstacles and per-floret variation, concatenated into
the structure-of-arrays :class:`~.system.Model`; reads no files (:mod:`.inputs` does). Also the
checks made before the florets are made or run: nesting depth and size, the collision spacing.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from inflo.formats.errors import FormatError, InputError
from inflo.formats.fcc import CanopyParams
from inflo.tools.common import linalg as la

from .system import OBSTACLE, Floret, Level, Model
from .variation import varied


def _rba_rows(frames, n_placements: int) -> np.ndarray:
    """(n_placements, n_frames) int64: the row of each placement in each RBA frame, -1 if absent."""
    table = np.full((n_placements, len(frames)), -1, np.int64)
    for i, fr in enumerate(frames):
        ids = np.asarray(fr.ids, np.int64)
        ok = (ids >= 0) & (ids < n_placements)
        table[ids[ok], i] = np.nonzero(ok)[0]
    return table


def _nearest_present(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each RBA frame, the frame whose row places the floret (itself when present, else the
    nearest frame where it is, the earlier on a tie) and that row."""
    present = np.nonzero(rows >= 0)[0]
    i = np.arange(len(rows))
    j = np.searchsorted(present, i)
    lo = present[np.clip(j - 1, 0, len(present) - 1)]
    hi = present[np.clip(j, 0, len(present) - 1)]
    src = np.where(np.abs(i - lo) <= np.abs(hi - i), lo, hi)
    src = np.where(rows >= 0, i, src)
    return src, rows[src]


#: nested scenes: the deepest nesting and the most florets they may expand to (formats/fcc.md,
#: "Nested scenes"), checked by counting before any floret is made
MAX_NEST_DEPTH = 6
MAX_FLORETS = 200_000


def _check_nesting(scenes, top, templates, nested, source) -> None:
    """Bad input (one line) when nested scenes go deeper than :data:`MAX_NEST_DEPTH` or expand to
    more than :data:`MAX_FLORETS` florets (ten placements of a scene of ten, seven levels deep, is
    ten million florets from a few small files)."""
    memo: dict = {}

    def count(sp, depth, chain):
        """(florets, nesting height) of scene ``sp`` reached ``depth`` levels down."""
        if sp not in memo:
            n, h = 0, 0
            for p in scenes[sp].placements:
                if p.id in templates:
                    n += 1
                elif p.id in nested and nested[p.id] not in chain and nested[p.id] in scenes:
                    m, g = count(nested[p.id], depth + 1, chain + [nested[p.id]])
                    n, h = n + m, max(h, g + 1)
                if n > MAX_FLORETS:
                    raise InputError(f"{source}: expected nested scenes of at most {MAX_FLORETS} florets in all, "
                                     f"found more in {Path(sp).name}")
            memo[sp] = (n, h)
        n, h = memo[sp]
        if depth + h > MAX_NEST_DEPTH:
            raise InputError(f"{sp}: expected scenes nested at most {MAX_NEST_DEPTH} deep, found {depth + h} "
                             f"(through {' > '.join(Path(c).name for c in chain)})")
        return n, h

    total = 0
    for sp in top:
        total += count(sp, 0, [sp])[0]
        if total > MAX_FLORETS:
            raise InputError(f"{source}: expected scenes of at most {MAX_FLORETS} florets in all, found more")


def assemble_model(params: CanopyParams, scenes: Mapping, templates: Mapping, rbas: Mapping | None = None) -> Model:
    """Instance every placement and concatenate the florets into one system (thesis 8 f); reads
    no files.

    Parameters
    ----------
    params : CanopyParams
        The run's parameters (kept as :attr:`Model.params`; ``run_frames``, ``scene_scale`` and
        ``source`` are used here).
    scenes : mapping of path -> Scene
        Florets are numbered in this order (scenes, then placements in file order).
    templates : mapping of int -> Template
        By animation/obj id; the placed ones' frames are stacked in ``template_x`` in this
        mapping's order, and each is looked up when a placement first names it.
    rbas : mapping of path -> RbaSequence, optional
        The RBA sequences moving the ``rba:`` placements of those scenes.

    Raises
    ------
    FormatError, InputError
        An SCN id with no template; an ``rba:`` placement of a scene without an RBA sequence, or
        listed in none of its RBA files; no placements at all.
    """
    rbas = {} if rbas is None else rbas
    rba_rows = {sp: _rba_rows(seq.frames, len(scenes[sp].placements)) for sp, seq in rbas.items()}
    # nested scenes: a placement whose id names a rigid body animation entry instances that
    # entry's scene (recursively); such scenes are not top-level unless listed as scene files
    nested = {r.id: r.scene_path.resolved for r in params.rigid_body_animations}
    referenced = {nested[p.id] for sc in scenes.values() for p in sc.placements
                  if p.id in nested and p.id not in templates}
    listed = {f.resolved for f in params.scene_files}
    top = [sp for sp in scenes if sp in listed or sp not in referenced]

    florets: list[Floret] = []
    placed: dict = {}
    own: list = []  # the florets' own templates (``variation`` lines), in floret order
    variations = params.variations

    def moved_by_rba(target, sp, k):
        if sp not in rbas:
            raise FormatError(sp, None, "a 'rigid body animation' line for this scene's 'rba:' placements",
                              f"placement {k} and no such line")
        paths, frames, scale = rbas[sp]
        rows = rba_rows[sp][k]
        if not (rows >= 0).any():
            raise FormatError(paths[0].parent, None, f"placement {k} in at least one RBA file", "none")
        target.rba = (paths, frames)
        target.rba_scale = scale
        target.birth_frame = int(np.argmax(rows >= 0))
        target.rba_source, target.rba_row = _nearest_present(rows)

    def instance(sp, outer, chain):
        shift = float(sum(lv.shift for lv in outer))
        # the frame (canopy clock) at which the outer levels have all emerged
        born, t = 0.0, 0.0
        for lv in outer:
            born = max(born, t + lv.birth_frame)
            t += lv.shift
        for k, p in enumerate(scenes[sp].placements):
            if p.id in templates:
                if p.petal is not None and templates[p.id].petal_weight is None:
                    raise InputError(f"{sp}: expected a 'petal weight' line in {params.source} for id {p.id} "
                                     f"(placement {k} has '#@ petal: {p.petal:g}'), found none")
                # a placement's '#@ petal: f' grows the petals of its own copy of the template
                # (one copy per distinct factor; fig. 6.4c)
                key = (p.id, 1.0 if p.petal is None else float(p.petal))
                if key not in placed:
                    base = placed.setdefault((p.id, 1.0), templates[p.id])
                    placed[key] = base.with_petals(key[1])
                fl = Floret(len(florets), p, placed[key], sp, k, p.material, outer=tuple(outer), shift=shift)
                if p.id in variations and p.type != OBSTACLE:
                    var = variations[p.id]
                    if var.petal and templates[p.id].petal_weight is None:
                        raise InputError(f"{params.source}: expected a 'petal weight' line for id {p.id} (its "
                                         f"'variation' varies 'petal'), found none")
                    fl.template, fl.delay = varied(templates[p.id], var, fl.index, key[1])
                    own.append(fl.template)
                if p.kind == "rba":
                    moved_by_rba(fl, sp, k)
                fl.birth_frame = int(math.ceil(max(born, fl.birth_frame + shift) - 1e-9))
                florets.append(fl)
            elif p.id in nested:
                inner = nested[p.id]
                if inner in chain:
                    raise FormatError(sp, None, "nested scenes that do not contain themselves",
                                      f"placement {k} (id {p.id}) instancing {Path(inner).name} inside itself")
                lv = Level(p, sp, k, shift=float(p.frame_start or 0))
                if p.kind == "rba":
                    moved_by_rba(lv, sp, k)
                instance(inner, outer + [lv], chain + [inner])
            else:
                raise FormatError(sp, None, f"placement ids naming an 'animation', 'obj' or 'rigid body "
                                  f"animation' entry of {params.source}", f"id {p.id} (placement {k}, '{p.kind}:')")

    _check_nesting(scenes, top, templates, nested, params.source)
    for sp in top:
        instance(sp, [], [sp])
    if not florets:
        raise InputError(f"{params.source}: expected placements in the scene files, found none")

    # concatenate
    # templates in entry order, each id's grown copies after it by factor (a stable layout)
    order = {i: n for n, i in enumerate(templates)}
    in_use = {id(fl.template) for fl in florets}
    seen, used = set(), []
    for key in sorted(placed, key=lambda kf: (order[kf[0]], kf[1])):
        t = placed[key]
        if t.key not in seen and id(t) in in_use:
            seen.add(t.key)
            used.append(t)
    used.extend(own)
    template_offset, rows = {}, 0
    for t in used:
        template_offset[t.key] = rows
        rows += t.frames.shape[0] * t.n_vertices
    template_x = np.concatenate([t.frames.reshape(-1, 3) for t in used]) if used else np.zeros((0, 3))

    nv_tot = sum(f.template.n_vertices for f in florets)
    inv_mass = np.ones(nv_tot)
    vertex_floret = np.empty(nv_tot, np.int32)
    offsets = np.zeros(len(florets) + 1, np.int64)
    tris, tri_fl, edges, e_k, hinges, h_k, fixed = [], [], [], [], [], [], []
    v_off = t_off = 0
    for k, fl in enumerate(florets):
        t = fl.template
        fl.vertex_offset, fl.tri_offset = v_off, t_off
        vertex_floret[v_off:v_off + t.n_vertices] = k
        # an obstacle placement (formats/fcc.md "Obstacles") is fixed whole, whatever its weight file
        own = np.arange(t.n_vertices, dtype=np.int32) if fl.placement.type == OBSTACLE else t.fixed
        inv_mass[v_off + own] = 0.0
        fixed.append(own + v_off)
        tris.append(t.tri_indices + v_off)
        tri_fl.append(np.full(len(t.tri_indices), k, np.int32))
        edges.append(t.edge_indices + v_off)
        e_k.append(np.full(len(t.edge_indices), t.k_stretch))
        hinges.append(t.hinge_indices + v_off)
        h_k.append(np.full(len(t.hinge_indices), t.k_bend))
        v_off += t.n_vertices
        t_off += len(t.tri_indices)
        offsets[k + 1] = v_off

    check_spacing(params, florets)
    n_frames = params.run_frames
    if n_frames is None:
        ends = [0]
        for fl in florets:
            if fl.placement.frame_end is not None:
                ends.append(int(math.ceil(fl.placement.frame_end + fl.shift)))
        for seq in rbas.values():
            ends.append(len(seq.paths) - 1)
        n_frames = max(ends)

    cat = lambda xs, dt, shape: (np.ascontiguousarray(np.concatenate(xs), dtype=dt)
                                 if xs else np.zeros(shape, dt))
    return Model(
        florets=florets,
        templates={t.key: t for t in used},
        vertex_inv_mass=inv_mass,
        vertex_floret=vertex_floret,
        vertex_fixed=cat(fixed, np.int32, (0,)),
        tri_indices=cat(tris, np.int32, (0, 3)),
        tri_floret=cat(tri_fl, np.int32, (0,)),
        edge_indices=cat(edges, np.int32, (0, 2)),
        edge_stiffness=cat(e_k, np.float64, (0,)),
        hinge_indices=cat(hinges, np.int32, (0, 4)),
        hinge_stiffness=cat(h_k, np.float64, (0,)),
        template_x=np.ascontiguousarray(template_x, dtype=np.float64),
        template_offset=template_offset,
        floret_vertex_offset=offsets,
        n_frames=int(n_frames),
        params=params,
    )


#: ``spacing`` may be at most this many times the largest floret's extent (a spacing ten
#: times the florets' size made every triangle a collision candidate of every other and the run
#: was killed for memory).
SPACING_LIMIT = 4.0


def check_spacing(params: CanopyParams, florets) -> None:
    """Refuse a ``spacing`` (the collision gap, thesis app. C.1) larger than :data:`SPACING_LIMIT`
    times the largest floret: the extent of its template over all frames times its placement's
    largest scale (SCN, RBA rows and entry factors, every nesting level) and the scene scale factor.

    Raises
    ------
    InputError
        Naming the ``.fcc`` file, the spacing and the largest floret's extent.
    """
    if not florets or params.spacing <= 0:
        return
    extent, rba_max = {}, {}

    def rba_factor(holder):
        if holder.rba is None:
            return 1.0
        paths, frames = holder.rba
        key = id(frames)
        if key not in rba_max:
            rba_max[key] = max((float(np.abs(fr.scale).max()) for fr in frames if len(fr)), default=1.0)
        return rba_max[key] * float(np.abs(holder.rba_scale).max())

    biggest = 0.0
    for fl in florets:
        t = fl.template
        if t.key not in extent:
            pts = t.frames.reshape(-1, 3)
            extent[t.key] = la.norm(pts.max(axis=0) - pts.min(axis=0)) if len(pts) else 0.0
        size = extent[t.key] * float(np.abs(fl.placement.scale).max()) * rba_factor(fl)
        for lv in fl.outer:
            size *= float(np.abs(lv.placement.scale).max()) * rba_factor(lv)
        biggest = max(biggest, size)
    biggest *= float(np.max(np.abs(params.scene_scale)))
    if params.spacing > SPACING_LIMIT * biggest:
        raise InputError(f"{params.source}: expected 'spacing' (the collision gap) at most {SPACING_LIMIT:g} x the "
                         f"largest floret's extent = {SPACING_LIMIT * biggest:.6g}, found {params.spacing:g}")
