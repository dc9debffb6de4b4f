"""``subdivide``: Loop subdivision of an OBJ or an OBJ sequence that stays collision-free (thesis 4.4).

Usage::

    subdivide IN.obj --levels N -o OUT.obj
    subdivide IN_DIR --levels N -o OUT_DIR        # every frame, same topology and vertex order
    subdivide IN.obj --levels 2 --no-collisions -o OUT.obj   # plain Loop subdivision

For each level every triangle is quadrisected in its plane (collision-free), the Loop positions
are computed, and the vertices move toward them with continuous collision detection and collision
constraints of thickness ``--spacing`` (fig. 4.8c). A summary per level (faces, collision
constraints needed, pairs left) goes to stderr; ``--check`` adds an exact static intersection test
of each output frame as written. A frame where the collision response left pairs closer than the
spacing is written with as many decimals as keep it collision-free (six rounded two such faces
into each other: the yarrow's smoothed final frame), the others with six.
"""
from __future__ import annotations

import contextlib
import math
import os
from pathlib import Path

import click

from inflo.formats.atomic import check_output_path, refuse_output_over_inputs, staged_output
from inflo.formats.obj import FLOAT_FMT, list_obj_sequence, read_obj, read_obj_sequence, write_obj, written_vertices
from inflo.tools.common.cli import inflo_command, progress

from .smooth import subdivide_meshes

__all__ = ["main"]


def topology_runs(meshes) -> list[tuple[int, int]]:
    """(start, stop) of each run of consecutive frames with the same faces (a canopy whose florets
    emerge over time, fccompose's rba: placements, gains faces; its vertex numbering stays)."""
    runs, start = [], 0
    for k in range(1, len(meshes)):
        if not meshes[k].same_topology(meshes[start]):
            runs.append((start, k))
            start = k
    runs.append((start, len(meshes)))
    return runs


#: the most faces a subdivided frame may have (memory and time of every later stage)
MAX_FACES = 20_000_000
#: --collision-iterations and --max-collision-retries (as petal-grow's collision_iterations/retries)
MAX_COLLISION_PASSES = 1_000


@inflo_command("subdivide", help="Loop subdivision that stays collision-free (thesis 4.4).")
@click.argument("source", type=click.Path())
@click.option("--levels", type=click.IntRange(0, 6), default=1, show_default=True, help="Subdivision levels.")
@click.option("-o", "--output", "output", required=True, type=click.Path(),
              help="Output OBJ (single input) or folder (sequence input).")
@click.option("--no-collisions", is_flag=True, help="Plain Loop subdivision, no collision handling.")
@click.option("--spacing", type=click.FloatRange(min=0.0, min_open=True), default=None,
              help="Collision thickness h (the .fcc 'spacing'); default 1/2000 of the bounding-box diagonal.")
@click.option("--collision-iterations", type=int, default=10, show_default=True,
              help="Sweeps over the collision constraints per round, in 1..1000.")
@click.option("--max-collision-retries", type=int, default=20, show_default=True,
              help="Detect/solve rounds after the first, in 0..1000.")
@click.option("--check", is_flag=True, help="Count intersecting triangle pairs of each output frame (exact test).")
def main(source, levels, output, no_collisions, spacing, collision_iterations, max_collision_retries, check,
         quiet, debug):
    from inflo.formats.errors import InputError

    if spacing is not None and not math.isfinite(spacing):
        raise InputError(f"--spacing must be a finite number > 0, found {spacing}")
    for name, v, low in (("--collision-iterations", collision_iterations, 1),
                         ("--max-collision-retries", max_collision_retries, 0)):
        if not low <= v <= MAX_COLLISION_PASSES:
            raise InputError(f"{name} must be in [{low}, {MAX_COLLISION_PASSES}], found {v}")
    paths = list_obj_sequence(source)
    single = os.path.isfile(source)
    # checked before reading: the output never overwrites the input (IN.obj -o IN.obj) and a
    # sequence is not written into its own folder
    check_output_path(output, folder=not single)
    refuse_output_over_inputs(output, [(p, "input mesh") for p in paths], folder=not single)
    if single:
        meshes = [read_obj(paths[0])]
    else:  # a canopy whose florets emerge over time changes its faces between runs of frames
        paths, meshes = read_obj_sequence(source, same_topology=False)
    for p, m in zip(paths, meshes):
        if len(m.faces) == 0:
            raise InputError(f"{p}: expected a mesh with triangles to subdivide, found none")
    n0 = len(meshes[0].vertices)
    for p, m in zip(paths, meshes):
        # a canopy keeps every vertex in every frame (florets not yet emerged included): frames
        # of one sequence with different vertex counts are not one animation
        if len(m.vertices) != n0:
            raise InputError(f"{p}: expected {n0} vertices like {paths[0].name} (frames of one sequence keep "
                             f"their vertices), found {len(m.vertices)}")
    faces = max(len(m.faces) for m in meshes) * 4 ** levels
    if faces > MAX_FACES:
        raise InputError(f"{paths[0]}: expected at most {MAX_FACES} faces a frame after {levels} levels "
                         f"(--levels {levels} x 4 each), found {faces}")
    resolve = None
    if not no_collisions:
        from .collisions import collision_resolver, default_spacing

        if spacing is not None:
            extent = 2000.0 * default_spacing(meshes[0].vertices)
            if not spacing <= extent:
                raise InputError(f"--spacing: expected a collision thickness at most the mesh's extent = {extent:.6g} "
                                 f"(its bounding box diagonal, {paths[0].name}), found {spacing:g}")
        h = spacing if spacing is not None else default_spacing(meshes[0].vertices)
        resolve = collision_resolver(spacing=h, iterations=collision_iterations, max_retries=max_collision_retries)
    notes: list = []
    # a sequence goes through a staging folder: a rerun replaces the earlier run's frames only when
    # it completes (never frames of two runs), and a second run into the folder is refused
    staged = contextlib.nullcontext(None) if single else staged_output(
        output, "subdivide", stale_patterns=(r"frame_\d+\.obj",), inputs=[(p, "input mesh") for p in paths])
    with staged as stage:
        with progress(length=len(meshes), label="subdivide", quiet=quiet) as bar:
            out, reports, at_risk = [], [], set()
            for start, stop in topology_runs(meshes):  # one subdivision plan per topology
                o, r = subdivide_meshes(meshes[start:stop], levels, resolve=resolve, name=str(paths[start]),
                                        on_frame=lambda k: bar.update(1), notes=notes)
                at_risk.update(len(out) + x.frame for x in r if x.remaining_intersections > 0)
                out.extend(o)
                reports.extend(r)
        targets = [Path(output)] if single else [Path(stage) / p.name for p in paths]
        if at_risk:
            from inflo.tools.collide.written import written_text
        if check:
            from inflo.tools.collide import intersecting_pairs
        counts = []
        for k, (t, m) in enumerate(zip(targets, out)):
            # where the resolver left pairs closer than the spacing, rounding them to six decimals
            # can make two of them cross: such a frame is written with as many digits as keep it
            # as collision-free as it is in memory (fccompose's written-frame guarantee)
            fmt = written_text(m.vertices, m.faces, tri_part=m.face_group)[0] if k in at_risk else FLOAT_FMT
            xr, text = written_vertices(m.vertices, fmt)
            write_obj(t, m, fmt=fmt, vertex_text=text)
            if check:  # the written numbers, as a reader gets them
                counts.append(len(intersecting_pairs(xr, m.faces)))
    if not quiet:
        for note in notes:
            click.echo(f"subdivide: {note}", err=True)
        for level in range(1, levels + 1):
            rows = [r for r in reports if r.level == level]
            msg = f"subdivide: level {level}: {max(r.n_faces for r in rows)} faces"
            if resolve is not None:
                msg += (f", collision constraints {sum(r.collision_constraints for r in rows)} "
                        f"(max {max(r.collision_constraints for r in rows)} in a frame), "
                        f"pairs left {sum(r.remaining_intersections for r in rows)}")
            click.echo(msg, err=True)
    if check:
        click.echo(f"subdivide: intersecting triangle pairs per frame: max {max(counts)}, total {sum(counts)}",
                   err=True)
