"""Command-line front end of ``stem-veins`` (Runions ch. 6: vascular patterns in stems).

    stem-veins PARAMS.toml -o OUT_DIR [--seed N]

Grows the closed venation model in a cylindrical stem to which primordia are added at a constant
plastochron, and writes the pattern (``graph.obj``, ``veins.obj``), the unrolled idealized diagram
(``unrolled.obj``, ``diagram.png``, and their versions after a growth map), which primordium's trace
joins which (``traces.csv``) and the connectivity (``connectivity.txt``). Parameters and files:
``formats/stem_veins.md``.
"""
from __future__ import annotations

import click

from inflo.formats.atomic import staged_output
from inflo.tools.common.cli import SEED, inflo_command, progress, stall_notice

from .model import simulate
from .output import OUTPUT_FILES, summary_lines, write_outputs
from .params import check_growth_map, read_params, seed_override


@inflo_command("stem-veins", help="Grow the vascular pattern of a stem as primordia are added at its top "
                                  "(Runions ch. 6): 3-D veins, the unrolled diagram, the traces' joins.")
@click.argument("params", type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output folder.")
@click.option("--seed", type=SEED, default=None, help="Override the parameter file's seed (primordium jitter).")
def main(params, output, seed, quiet, debug):
    p = seed_override(read_params(params), seed)
    growth = check_growth_map(p)
    inputs = [(params, "input")] + ([(p.diagram.growth_map, "growth map")] if p.diagram.growth_map else [])
    m = p.model
    expected = -(-m.count // m.whorl) * m.plastochron + 100  # the last whorl plus settling, about
    with staged_output(output, "stem-veins", stale_patterns=OUTPUT_FILES, inputs=inputs) as stage, \
            stall_notice("stem-veins") as tick, \
            progress(length=expected, label="stem-veins", quiet=quiet) as bar:
        done = [0]

        def advance(n):
            bar.update(n)
            done[0] += n
            tick(done[0], max(expected, done[0]), "iterations")

        run = simulate(m, progress=advance)
        write_outputs(stage, run, p, growth)
    if not quiet:
        for line in summary_lines(run):
            click.echo(f"stem-veins: {line}", err=True)


if __name__ == "__main__":
    main()
