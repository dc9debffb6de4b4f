"""Command-line front end of ``phyllotaxis`` (stage not built yet: issue 4)."""
from __future__ import annotations

import click

from inflo.tools.common.cli import inflo_command, not_implemented


@inflo_command("phyllotaxis", help="Place florets by Ridley phyllotaxis (thesis ch. 5): scene.scn and, when dynamic, rba/NNNN.rba.")
@click.argument("params", type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output folder.")
def main(params, output, quiet, debug):
    not_implemented("phyllotaxis", 4)
