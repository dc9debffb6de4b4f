"""Command-line front end of ``floret-animate`` (stage not built yet: issue 3)."""
from __future__ import annotations

import click

from inflo.tools.common.cli import inflo_command, not_implemented


@inflo_command("floret-animate", help="Interpolate floret key poses (thesis ch. 2.3) into one .floret file per frame.")
@click.argument("key_poses", nargs=-1, required=True, type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Folder for the frame .floret files.")
@click.option("--frames", default=100, show_default=True, help="Number of frames to write.")
def main(key_poses, output, frames, quiet, debug):
    not_implemented("floret-animate", 3)
