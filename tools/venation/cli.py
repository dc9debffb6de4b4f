"""Command-line front end of ``venation`` (Runions ch. 4).

    venation PARAMS.toml -o OUT_DIR [--seed N] [--frame-step N] [--frame-textures]

Writes ``OUT_DIR/veins.obj`` (the venation graph as ``l`` polylines), ``OUT_DIR/veins.widths``,
``OUT_DIR/blade.obj`` + ``blade.mtl`` (the blade, textured), ``OUT_DIR/texture.png`` (the veins by
width over the blade), ``OUT_DIR/events.csv`` (the developmental events in order: sources, the
midvein, loops, blind vein ends) and, with a frame step, ``OUT_DIR/frames/``. Parameters and files:
``formats/venation.md``.
"""
from __future__ import annotations

import click

from inflo.formats.atomic import staged_output
from inflo.formats.toml_params import referenced_files
from inflo.tools.common.cli import SEED, inflo_command, progress, stall_notice

from .generate import run_venation, summary
from .params import check_frames, load_inputs, read_params


@inflo_command("venation", help="Grow open or closed leaf venation patterns in a growing blade (Runions ch. 4).")
@click.argument("params", type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output folder.")
@click.option("--seed", type=SEED, default=None, help="Override the parameter file's seed.")
@click.option("--frame-step", type=click.IntRange(min=0), default=None,
              help="Write the pattern every N iterations into OUT_DIR/frames (0: none; default: the file's).")
@click.option("--frame-textures/--no-frame-textures", default=None,
              help="Also draw each frame's texture_NNNN.png (default: the file's output.frame_textures).")
def main(params, output, seed, frame_step, frame_textures, quiet, debug):
    p = read_params(params)
    inputs = load_inputs(p)
    step = p.output.frame_step if frame_step is None else frame_step
    check_frames(p, inputs, step, p.output.frame_textures if frame_textures is None else frame_textures,
                 option=frame_step is not None)
    limit = max(p.run.max_iterations, 1)
    files = [params] + ([p.blade.contour] if p.blade.contour else [])
    for named in (p.growth.scale, p.growth.rerg):
        files += (named if isinstance(named, list) else [named]) if named else []
    # the earlier run's files are replaced only when this one completes (no new veins on an old texture)
    stale = (r"veins\.obj", r"veins\.widths", r"events\.csv", r"blade\.obj", r"blade\.mtl", r"texture\.png",
             r"frames/(veins|blade|texture)_\d+\.(obj|widths|png|mtl)")
    with staged_output(output, "venation", stale_patterns=stale, inputs=[(f, "input") for f in files + referenced_files(params)],
                        subfolders=("frames",) if step else ()) as stage, \
            stall_notice("venation") as tick, \
            progress(length=min(limit, max(inputs.growth.steps, 1) + 50), label="venation", quiet=quiet) as bar:
        done = [0]

        def advance(n):
            bar.update(n)
            done[0] += n
            tick(done[0], limit, "iterations")

        run = run_venation(p, inputs, stage, seed=seed, frame_step=frame_step, frame_textures=frame_textures,
                           progress=advance)
    if not quiet:
        click.echo(summary(run, output), err=True)
