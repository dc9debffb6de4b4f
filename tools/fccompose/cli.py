"""Command-line front end of ``fccompose`` (stage not built yet: issue 5)."""
from __future__ import annotations

import click

from inflo.tools.common.cli import inflo_command, not_implemented


@inflo_command("fccompose", help="Floral Canopy Composer: grow the canopy by PBD with continuous collision handling (thesis ch. 3-4).")
@click.argument("params", type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Folder for the canopy OBJ frames.")
def main(params, output, quiet, debug):
    not_implemented("fccompose", 5)
