"""Command-line front end of ``polygonize`` (stage not built yet: issue 3)."""
from __future__ import annotations

import click

from inflo.tools.common.cli import inflo_command, not_implemented


@inflo_command("polygonize", help="Polygonize a .floret frame sequence (thesis 2.4) into OBJ frames of identical topology.")
@click.argument("frames_dir", type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Folder for the OBJ frames.")
def main(frames_dir, output, quiet, debug):
    not_implemented("polygonize", 3)
