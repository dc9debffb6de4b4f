"""PBD constraint projections per second on a ~100k-triangle canopy.

The canopy: 300 synthetic 5-petal florets (:mod:`inflo.tools.testing.florets`, 330 triangles
each) placed on a grid, half open. Rest values are the current ones scaled by 0.99 (lengths) and
shifted by 0.05 rad (angles), so every projection does its full work. Reported separately:

- ``pbd_distance_projections``: serial Gauss-Seidel sweep of the distance constraints (eq. 3.11);
  anchor: the ~6e7 projections/s a plain numba loop reaches on one core here;
- ``pbd_bending_projections``: serial sweep of the signed dihedral constraints (eq. 3.13);
- ``..._coloured``: the colour-by-colour ``prange`` sweeps on all cores (ratio to serial in the note);
- ``pbd_internal_by_floret``: what fccompose runs, distance then bending sweeps floret by floret,
  florets in parallel (:func:`~inflo.tools.pbd.solver.project_internal_by_part`, no early exit
  here), as (distance + bending) projections per second; the ratio to the serial sweeps in the note.
"""
from __future__ import annotations

import numpy as np

from inflo.tools.pbd import (
    colour_constraints,
    mesh_edges,
    mesh_hinges,
    part_offsets,
    project_bending_constraints,
    project_bending_constraints_coloured,
    project_distance_constraints,
    project_distance_constraints_coloured,
    project_internal_by_part,
)
from inflo.tools.pbd.solver import edge_lengths, hinge_angles
from inflo.tools.testing.florets import grid_canopy_scene, opening_floret

from .harness import BenchContext, Result

ANCHOR = "6e7 projections/s, plain numba loop, one core"


def canopy_arrays(n_florets: int):
    """(x, tri) of ``n_florets`` half-open synthetic florets on a grid."""
    frames, faces, _ = opening_floret(11, nu=12, nv=4)
    local = frames[5]
    xs, tris = [], []
    for k, p in enumerate(grid_canopy_scene(n_florets, 11)):
        m = p.matrix()
        xs.append(local @ m[:3, :3].T + m[:3, 3])
        tris.append(faces + k * len(local))
    return np.ascontiguousarray(np.concatenate(xs)), np.concatenate(tris).astype(np.int32)


def projections(ctx: BenchContext) -> list[Result]:
    n_fl = 30 if ctx.quick else 300
    x, tri = canopy_arrays(n_fl)
    e, h = mesh_edges(tri), mesh_hinges(tri)
    w = np.ones(len(x))
    rest_l = 0.99 * edge_lengths(x, e)
    rest_a = hinge_angles(x, h) + 0.05
    k_e, k_h = np.full(len(e), 0.99), np.full(len(h), 0.99)
    ce, ch = colour_constraints(e, len(x)), colour_constraints(h, len(x))
    sweeps = 3 if ctx.quick else 20
    # warm up (compile / load the cache)
    y = x.copy()
    project_distance_constraints(y, w, e, rest_l, k_e)
    project_bending_constraints(y, w, h, rest_a, k_h)
    project_distance_constraints_coloured(y, w, e, rest_l, k_e, *ce)
    project_bending_constraints_coloured(y, w, h, rest_a, k_h, *ch)

    def run(fn, *args):
        y = x.copy()
        t, _ = ctx.timed(lambda: [fn(y, *args) for _ in range(sweeps)], repeat=3)
        return t

    t_d = run(project_distance_constraints, w, e, rest_l, k_e)
    t_b = run(project_bending_constraints, w, h, rest_a, k_h)
    t_dc = run(project_distance_constraints_coloured, w, e, rest_l, k_e, *ce)
    t_bc = run(project_bending_constraints_coloured, w, h, rest_a, k_h, *ch)
    n_v = len(x) // n_fl
    part = np.arange(len(x)) // n_v
    eo, ho = part_offsets(e, part, n_fl), part_offsets(h, part, n_fl)
    done = np.zeros(n_fl, np.int64)
    y = x.copy()
    project_internal_by_part(y, w, e, rest_l, k_e, eo, h, rest_a, k_h, ho, 1, -1.0, done)  # warm up
    t_p = run(lambda y_: project_internal_by_part(y_, w, e, rest_l, k_e, eo, h, rest_a, k_h, ho, 1, -1.0, done))
    note = f"{len(tri):,} triangles, {len(e):,} edges, {len(h):,} hinges, {sweeps} sweeps, best of 3"
    rd, rb = len(e) * sweeps / t_d, len(h) * sweeps / t_b
    rdc, rbc = len(e) * sweeps / t_dc, len(h) * sweeps / t_bc
    return [
        Result("pbd_distance_projections", rd, "projections/s", ANCHOR, 6e7, note),
        Result("pbd_bending_projections", rb, "projections/s", ANCHOR, 6e7, note),
        Result("pbd_distance_projections_coloured", rdc, "projections/s", ANCHOR, 6e7,
               f"{len(ce[1]) - 1} colours; {rdc / rd:.2f}x the serial sweep"),
        Result("pbd_bending_projections_coloured", rbc, "projections/s", ANCHOR, 6e7,
               f"{len(ch[1]) - 1} colours; {rbc / rb:.2f}x the serial sweep"),
        Result("pbd_internal_by_floret", (len(e) + len(h)) * sweeps / t_p, "projections/s", ANCHOR, 6e7,
               f"{n_fl} florets in parallel; {(t_d + t_b) / t_p:.2f}x the serial distance + bending sweeps"),
    ]


BENCHMARKS = [projections]
