"""Command-line front end of ``branch-gen`` (thesis ch. 7 and 8 g, Runions ch. 3).

    branch-gen SCENE.scn [PARAMS.toml] -o OUT_DIR [--rba DIR] [--algorithm rodkaew|sca] [--seed N]
               [--base X Y Z]

Writes ``OUT_DIR/skeleton.obj`` (``l`` polylines), ``OUT_DIR/skeleton.radii``,
``OUT_DIR/branches.obj`` (generalized cylinders) and, with ``--rba``,
``OUT_DIR/frames/branches_NNNN.obj``. Parameters: ``formats/branch_gen.md``.
"""
from __future__ import annotations

import math
import warnings

import click

from inflo.formats.atomic import staged_output
from inflo.formats.rba import read_rba_sequence
from inflo.formats.scn import read_scn
from inflo.formats.toml_params import referenced_files
from inflo.tools.common.cli import SEED, inflo_command, progress

from .generate import OUTPUT_FILES, branch_gen, write_branch_gen
from .params import read_params


@inflo_command("branch-gen", help="Grow the branching structure under the florets (thesis ch. 7) or a "
                                  "space-colonization tree (--algorithm sca).")
@click.argument("scene", type=click.Path())
@click.argument("params", required=False, type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output folder.")
@click.option("--rba", "rba", type=click.Path(), default=None,
              help="RBA frames folder of the canopy: emergence from first appearance, one branches OBJ per frame.")
@click.option("--frame-step", type=click.IntRange(min=1), default=1, show_default=True,
              help="With --rba: write every N-th frame (and the last).")
@click.option("--algorithm", type=click.Choice(["rodkaew", "sca"]), default=None,
              help="Override the parameter file's algorithm.")
@click.option("--seed", type=SEED, default=None, help="Override the parameter file's seed.")
@click.option("--base", type=float, nargs=3, default=None, help="Inflorescence base point (default 0 0 0).")
def main(scene, params, output, rba, frame_step, algorithm, seed, base, quiet, debug):
    with warnings.catch_warnings():
        warnings.simplefilter("always", UserWarning)
        warnings.showwarning = _one_line_warning
        _run(scene, params, output, rba, frame_step, algorithm, seed, base, quiet)


def _one_line_warning(message, category, filename, lineno, file=None, line=None):
    click.echo(f"branch-gen: warning: {message}", err=True)


def _run(scene, params, output, rba, frame_step, algorithm, seed, base, quiet):
    p = read_params(params)
    if seed is not None:
        p.seed = seed
    if base is not None:
        if not all(math.isfinite(b) and abs(b) < 1e12 for b in base):
            from inflo.formats.errors import InputError
            raise InputError(f"--base must be three finite numbers (|x| < 1e12), found {' '.join(map(str, base))}")
        p.base = list(base)
    algo = algorithm or p.algorithm
    sc = read_scn(scene) if algo == "rodkaew" else None
    frames = read_rba_sequence(rba, sc)[1] if rba and algo == "rodkaew" else None
    total = len(sc) if sc is not None else p.sca.n_points
    inputs = [(scene, "scene"), (params, "parameter file"), (rba, "RBA folder")]
    inputs += [(f, "input") for f in (referenced_files(params) if params else [])]
    # a rerun replaces the earlier run's files only when it completes (never new branches with an
    # old run's frames)
    with staged_output(output, "branch-gen", stale_patterns=OUTPUT_FILES, inputs=inputs) as stage:
        with progress(length=max(total, 1), label="branch-gen", quiet=quiet) as bar:
            result = branch_gen(sc, p, rba_frames=frames, algorithm=algo, frame_step=frame_step,
                                progress=bar.update)
        write_branch_gen(stage, result, p)
    if not quiet:
        click.echo(f"branch-gen: {result.node_pos.shape[0]} skeleton nodes, {len(result.chain_list)} branches, "
                   f"{result.branches_mesh.n_faces} triangles -> {output}", err=True)
