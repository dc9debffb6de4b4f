"""Command-line front end of ``fccompose``: parse the ``.fcc``, compose, report."""
from __future__ import annotations

import dataclasses
import os

import click

from inflo.formats.atomic import output_lock
from inflo.formats.fcc import SCHEMES, read_fcc
from inflo.tools.common.cli import inflo_command, progress

from .compose import compose_canopy


@inflo_command("fccompose", help="Floral Canopy Composer: grow the canopy by PBD with continuous collision "
                                 "handling (thesis ch. 3-4). Writes OUT_DIR/frame_NNNN.obj per output frame, "
                                 "OUT_DIR/log.csv and OUT_DIR/state/ (for --resume).")
@click.argument("params", type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Folder for the canopy OBJ frames.")
@click.option("--resume", is_flag=True, help="Continue from the last complete output frame of an earlier run.")
@click.option("--strict", is_flag=True, help="Stop (exit 1) when collisions remain after the retries "
                                             "or the sanity check finds intersections.")
@click.option("--allow-initial-intersections", is_flag=True,
              help="Go on even when the first frame is not collision-free.")
@click.option("--frames", "frames", type=click.IntRange(min=0, max=100_000), default=None, metavar="N",
              help="Frames to simulate; overrides the file's 'run for number of frames' (a pipeline's "
                   "draft and final builds share one .fcc).")
@click.option("--updates", "updates", type=click.IntRange(min=1, max=1000), default=None, metavar="N",
              help="Simulation steps per frame; overrides the file's 'updates per frame'.")
@click.option("--scheme", "scheme", type=click.Choice(SCHEMES), default=None,
              help="Iteration scheme; overrides the file's 'solver scheme' (default: as the goldens were made; "
                   "fast: fewer projections for the same quality figures, results not identical).")
def main(params, output, resume, strict, allow_initial_intersections, frames, updates, scheme, quiet, debug):
    p = read_fcc(params)
    if scheme is not None:
        p = dataclasses.replace(p, solver_scheme=scheme)
    if frames is not None:
        p = dataclasses.replace(p, run_frames=int(frames))
    if updates is not None:
        p = dataclasses.replace(p, updates_per_frame=int(updates))
    _refuse_output_holding_inputs(params, p, output)
    warn = (lambda msg: None) if quiet else (lambda msg: click.echo(f"fccompose: warning: {msg}", err=True))
    with output_lock(output, "fccompose"):  # a second run into the folder is refused
        res = compose_canopy(
            p, output, resume=resume, strict=strict, allow_initial_intersections=allow_initial_intersections,
            progress=lambda total: progress(length=total, label="fccompose", quiet=quiet, unit="frames"), warn=warn,
        )
    if not quiet:
        click.echo(f"fccompose: {len(res.frames_written)} frames written to {output} "
                   f"({res.n_triangles} triangles, {res.steps} steps, {res.seconds:.1f} s)", err=True)


def _refuse_output_holding_inputs(source, p, output) -> None:
    """Bad input (one line, exit 2) when the output folder is, or holds, a file or folder the run
    reads: fccompose removes the frames of earlier runs from its output folder, so ``-o anim``
    where ``anim`` is an input animation would delete its own inputs."""
    from pathlib import Path

    from inflo.formats.atomic import check_output_path
    from inflo.formats.errors import InputError

    check_output_path(output, folder=True)
    out = Path(os.path.realpath(output))
    inputs = [(e.path, "animation" if e.kind == "animation" else "obj") for e in p.animations]
    inputs += [(r.rba_folder, "rigid body animation") for r in p.rigid_body_animations]
    inputs += [(r.scene_path, "rigid body animation") for r in p.rigid_body_animations]
    inputs += [(f, "scene file path") for f in p.scene_files]
    inputs += [(f, "weight") for f in p.weights.values()]
    inputs += [(f, "petal weight") for f in p.petal_weights.values()]
    for fp, key in inputs:
        path = Path(os.path.realpath(fp.resolved))
        if path == out or out in path.parents:
            where = f"{source}:{fp.line}: " if fp.line else f"{source}: "
            raise InputError(f"{where}expected an output folder that holds none of the inputs, found -o {output} "
                             f"holding the '{key}' input {fp.raw}")
