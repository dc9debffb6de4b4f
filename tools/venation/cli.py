"""Command-line front end of ``venation`` (Runions ch. 4).

    venation PARAMS.toml -o OUT_DIR [--seed N] [--frame-step N] [--frame-textures]

Writes ``OUT_DIR/veins.obj`` (the venation graph as ``l`` polylines), ``OUT_DIR/veins.widths``,
``OUT_DIR/blade.obj`` + ``blade.mtl`` (the blade, textured), ``OUT_DIR/texture.png`` (the veins by
width over the blade) and, with a frame step, ``OUT_DIR/frames/``. Parameters and files:
``formats/venation.md``.
"""
from __future__ import annotations

import click

from inflo.tools.common.cli import inflo_command, progress

from .generate import run_venation, summary
from .params import load_inputs, read_params


@inflo_command("venation", help="Grow open or closed leaf venation patterns in a growing blade (Runions ch. 4).")
@click.argument("params", type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output folder.")
@click.option("--seed", type=int, default=None, help="Override the parameter file's seed.")
@click.option("--frame-step", type=click.IntRange(min=0), default=None,
              help="Write the pattern every N iterations into OUT_DIR/frames (0: none; default: the file's).")
@click.option("--frame-textures/--no-frame-textures", default=None,
              help="Also draw each frame's texture_NNNN.png (default: the file's output.frame_textures).")
def main(params, output, seed, frame_step, frame_textures, quiet, debug):
    p = read_params(params)
    inputs = load_inputs(p)
    limit = max(p.run.max_iterations, 1)
    with progress(length=min(limit, max(inputs.growth.steps, 1) + 50), label="venation", quiet=quiet) as bar:
        run = run_venation(p, inputs, output, seed=seed, frame_step=frame_step, frame_textures=frame_textures,
                           progress=bar.update)
    if not quiet:
        click.echo(summary(run, output), err=True)
