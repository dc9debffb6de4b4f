"""Command-line front end of ``dimorph`` (stage not built yet: issue 4)."""
from __future__ import annotations

import click

from inflo.tools.common.cli import inflo_command, not_implemented


@inflo_command("dimorph", help="Set floret types and sizes by cones (thesis ch. 6).")
@click.argument("scene", type=click.Path())
@click.option("--alpha", type=float, required=True, help="Cone opening angle in degrees.")
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output scene file.")
def main(scene, alpha, output, quiet, debug):
    not_implemented("dimorph", 4)
