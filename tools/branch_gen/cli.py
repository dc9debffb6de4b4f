"""Command-line front end of ``branch-gen`` (stage not built yet: issue 7)."""
from __future__ import annotations

import click

from inflo.tools.common.cli import inflo_command, not_implemented


@inflo_command("branch-gen", help="Grow the branching structure under the florets (thesis ch. 7) or a space-colonization tree.")
@click.argument("scene", type=click.Path())
@click.argument("params", required=False, type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output folder.")
def main(scene, params, output, quiet, debug):
    not_implemented("branch-gen", 7)
