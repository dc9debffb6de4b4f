"""Command-line front end of ``thyrse`` (thesis sec. 4.5, figs. 4.9, 4.10, ch. 7).

    thyrse [PARAMS.toml] -o OUT_DIR [--base X Y Z] [--room FLORET.obj ...]

Branching first: lays out a thyrse (a main axis with decussate laterals whose length, branching
order and floret density are functions of their position, ``.func`` files) and places the florets
on it. Writes ``OUT_DIR/scene.scn`` (``ca:`` placements, lower florets first) and, as branch-gen
does, ``OUT_DIR/skeleton.obj``, ``OUT_DIR/skeleton.radii`` and ``OUT_DIR/branches.obj``.
Parameters: ``formats/thyrse.md``.
"""
from __future__ import annotations

import math
import warnings

import click
import numpy as np

from inflo.formats.atomic import staged_output
from inflo.formats.errors import InputError
from inflo.formats.obj import read_obj
from inflo.formats.toml_params import referenced_files
from inflo.tools.common.cli import inflo_command

from .generate import OUTPUT_FILES, thyrse, write_thyrse
from .params import read_params


@inflo_command("thyrse", help="Lay out a thyrse (branching first: main axis, decussate laterals from positional "
                              "functions) and place its florets: scene.scn + branch meshes.")
@click.argument("params", required=False, type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output folder.")
@click.option("--base", type=float, nargs=3, default=None, help="Inflorescence base point (default 0 0 0).")
@click.option("--room", "rooms", multiple=True, type=click.Path(),
              help="A floret model OBJ (floret units, local frame; repeatable: e.g. its bud and open pose): a "
                   "floret whose model would meet the branches is not formed.")
def main(params, output, base, rooms, quiet, debug):
    # a numerical warning no bound prevented is one line (no source line under it), once per kind
    with warnings.catch_warnings():
        warnings.simplefilter("once")
        warnings.showwarning = _one_line_warning
        _run(params, output, base, rooms, quiet)


def _one_line_warning(message, category, filename, lineno, file=None, line=None):
    click.echo(f"thyrse: warning: {message}", err=True)


def _run(params, output, base, rooms, quiet):
    p = read_params(params)
    if base is not None:
        if not all(math.isfinite(b) and abs(b) < 1e12 for b in base):
            raise InputError(f"--base must be three finite numbers (|x| < 1e12), found {' '.join(map(str, base))}")
        p.base = list(base)
    models = []
    for path in rooms:
        m = read_obj(path)
        if m.n_faces == 0:
            raise InputError(f"{path}: expected a floret model with triangles (--room), found none")
        models.append((m.vertices, m.faces))
    _check_rooms(rooms, models)
    inputs = [(params, "parameter file")] + [(r, "floret model") for r in rooms]
    inputs += [(f, "input") for f in (referenced_files(params) if params else [])]
    # a rerun replaces the earlier run's files only when it completes
    with staged_output(output, "thyrse", stale_patterns=OUTPUT_FILES, inputs=inputs) as stage:
        result = thyrse(p, models)
        write_thyrse(stage, result, p)
    if not quiet:
        click.echo(f"thyrse: {len(result.layout.floret_node)} florets, {len(result.branches.chain_list)} branches, "
                   f"{result.branches.branches_mesh.n_faces} triangles -> {output}", err=True)


def _check_rooms(rooms, models) -> None:
    """Refuse (one line) a floret model that intersects itself: a floret may not (fccompose's
    first frame), and the room test of every placed copy would pay for its crossings once per
    floret (a branch mesh given as the model took minutes and formed no floret)."""
    from inflo.tools.collide import intersecting_pairs

    for path, (v, f) in zip(rooms, models):
        pairs = intersecting_pairs(np.asarray(v, np.float64), np.asarray(f, np.int32))
        if len(pairs):
            a, b = (int(x) for x in pairs[0])
            raise InputError(f"{path}: expected a floret model that does not intersect itself (--room), found "
                             f"{len(pairs)} intersecting triangle pairs (faces {a + 1} and {b + 1})")


if __name__ == "__main__":  # python -m inflo.tools.thyrse.cli
    main()
