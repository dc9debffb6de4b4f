"""Command-line front end of ``phyllotaxis`` (thesis ch. 5; parameters: formats/phyllotaxis.md)."""
from __future__ import annotations

import warnings

import click

from inflo.formats.atomic import staged_output
from inflo.formats.errors import InputError
from inflo.formats.toml_params import referenced_files
from inflo.tools.common.cli import inflo_command, portable_path, progress

from .generate import OUTPUT_FILES, generate
from .params import locate_error, read_params


@inflo_command("phyllotaxis", help="Place florets by Ridley phyllotaxis (thesis ch. 5): scene.scn and, when dynamic, rba/NNNN.rba.")
@click.argument("params", type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output folder.")
@click.option("--png", type=click.Path(), default=None, help="Also save a top view of the final pattern (florets as discs coloured by age).")
def main(params, output, png, quiet, debug):
    # a numerical warning no bound prevented is one line (no source line under it), once per kind
    with warnings.catch_warnings():
        warnings.simplefilter("once")
        warnings.showwarning = _one_line_warning
        _run(params, output, png, quiet)


def _one_line_warning(message, category, filename, lineno, file=None, line=None):
    click.echo(f"phyllotaxis: warning: {message}", err=True)


def _run(params, output, png, quiet):
    p = read_params(params)

    def bar(length, label):
        return progress(length=length, label=label, quiet=quiet)

    # a rerun replaces the earlier run's files only when it completes (never a new scene.scn with
    # an old run's RBA frames)
    with staged_output(output, "phyllotaxis", stale_patterns=OUTPUT_FILES, inputs=[(params, "parameter file")] + [(f, "input") for f in referenced_files(params)]) as stage:
        try:
            summary = generate(p, stage, progress=bar, header=f"phyllotaxis {portable_path(params)}")
        except InputError as exc:  # a combination of keys: the line of the key the message names
            raise locate_error(exc, params) from None
    for msg in summary.messages:
        click.echo(f"phyllotaxis: warning: {msg}", err=True)
    if png:
        from .plot import plot_discs

        pv = summary.preview
        plot_discs(png, pv["pos"], pv["diameter"], pv["age"], title=f"{summary.model}: {summary.florets} florets")
    if not quiet:
        extra = f", {summary.frames} RBA frames" if summary.frames else ""
        click.echo(f"phyllotaxis: {summary.model}: {summary.florets} florets{extra} -> {output}/scene.scn", err=True)
