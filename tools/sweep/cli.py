"""Command-line front end of ``inflo-sweep`` (the sweep file: formats/sweep.md).

``inflo-sweep SWEEP.toml -o OUT_DIR [--scheduler ADDRESS] [--workers N]`` runs every variant of
the sweep as Dask tasks (a LocalCluster of N workers, or the scheduler at ADDRESS), each in
``OUT_DIR/variants/<id>/``, and writes ``OUT_DIR/results.csv``, ``contact_sheet.png`` and, for a
2-D numeric grid, ``heatmap.png``. A rerun skips the variants done before. Exit 0 when every
variant succeeded, 1 when any failed (they are listed), 2 for a bad sweep file (nothing written).
"""
from __future__ import annotations

import sys

import click

from inflo.tools.common.cli import inflo_command

from .spec import read_sweep
from .sweep import check_runnable, run_sweep


@inflo_command("inflo-sweep", help="Run the variants of SWEEP.toml (a pipeline or CLI stages over a grid or random "
                                    "samples of parameters) as Dask tasks; results.csv, contact sheet, heat map.")
@click.argument("sweep_file", metavar="SWEEP.toml", type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output folder (OUT_DIR).")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="A running Dask scheduler (tcp://HOST:8786); default: a LocalCluster on this machine.")
@click.option("--workers", type=click.IntRange(min=1), default=None, metavar="N",
              help="LocalCluster: N worker processes (default: the CPU count); with --scheduler: wait for N workers.")
@click.option("--force", is_flag=True, help="Run every variant again, done or not (make still skips what is up to date).")
@click.option("--dry-run", is_flag=True, help="Write the variants' inputs and list what would run; run nothing.")
@click.option("--dashboard", default=":8787", show_default=True, metavar="ADDRESS",
              help="LocalCluster: the dashboard's address (':0': any free port).")
def main(sweep_file, output, scheduler, workers, force, dry_run, dashboard, quiet, debug):
    sweep = read_sweep(sweep_file)
    check_runnable(sweep)
    _refuse_output_inside_inputs(sweep, sweep_file, output)

    def echo(msg):
        click.echo(msg, err=True)

    summary = run_sweep(sweep, output, scheduler=scheduler, workers=workers, quiet=quiet, force=force,
                        dry_run=dry_run, dashboard=dashboard, echo=echo)
    if dry_run:
        return
    fails = summary.failures
    if not quiet:
        ok = len(summary.results) - len(fails)
        echo(f"inflo-sweep: {ok} of {len(summary.results)} variants ok ({summary.ran} run, {summary.cached} done before)"
             + "".join(f"; wrote {p}" for p in summary.paths))
    if fails:
        echo(f"inflo-sweep: {len(fails)} of {len(summary.results)} variants failed:")
        for r in fails:
            label = ", ".join(f"{k}={v}" for k, v in r["params"])
            echo(f"  {r['id']} ({label}): {r['error']} (exit {r['exit_code']})")
        sys.exit(1)


def _refuse_output_inside_inputs(sweep, sweep_file, output) -> None:
    """Bad input (one line) when OUT_DIR lies inside a folder every variant copies (the pipeline
    folder or an input folder): each variant would copy the earlier variants' folders, growing the
    disk used with every run."""
    import os
    from pathlib import Path

    from inflo.formats.errors import InputError

    out = Path(os.path.realpath(output))
    copied = [sweep.pipeline.path] if sweep.pipeline is not None else [sweep.folder / rel for rel in sweep.inputs]
    for src in copied:
        real = Path(os.path.realpath(src))
        if real.is_dir() and (out == real or real in out.parents):
            raise InputError(f"{sweep_file}: expected an output folder outside the folders each variant copies, "
                             f"found -o {output} inside {src}")
