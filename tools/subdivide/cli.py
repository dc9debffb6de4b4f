"""Command-line front end of ``subdivide`` (stage not built yet: issue 6)."""
from __future__ import annotations

import click

from inflo.tools.common.cli import inflo_command, not_implemented


@inflo_command("subdivide", help="Loop subdivision that stays collision-free (thesis 4.4).")
@click.argument("source", type=click.Path())
@click.option("--levels", type=int, default=1, show_default=True, help="Subdivision levels.")
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output OBJ or folder.")
def main(source, levels, output, quiet, debug):
    not_implemented("subdivide", 6)
