"""Command-line front end of ``petal-grow`` (Ijiri et al. 2008).

    petal-grow PARAMS.toml -o OUT_DIR [--keyframes N] [--no-collisions]

Writes ``OUT_DIR/frame_0000.obj`` (the bud) ... ``frame_NNNN.obj`` (one keyframe per growth step,
constant topology and vertex order, ``g``/``usemtl`` per organ) and ``OUT_DIR/log.csv``.
Parameters and files: ``formats/petal_grow.md``.
"""
from __future__ import annotations

import click

from inflo.tools.common.cli import inflo_command, progress

from .params import read_params
from .simulate import build_model, run


@inflo_command("petal-grow", help="Grow a bud into an opening flower by growth maps (Ijiri et al. 2008).")
@click.argument("params", type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output folder (OBJ keyframes).")
@click.option("--keyframes", type=click.IntRange(min=1), default=None,
              help="Keyframes to write, the bud included (default: the file's flower.keyframes).")
@click.option("--collisions/--no-collisions", default=None, help="Override flower.collisions.")
def main(params, output, keyframes, collisions, quiet, debug):
    p = read_params(params)
    model = build_model(p)
    n = (keyframes or p.flower.keyframes) - 1
    with progress(length=max(n, 1), label="petal-grow", quiet=quiet, unit="frames") as bar:
        res = run(p, output, keyframes=keyframes, collisions=collisions, progress=bar.update, model=model)
    if res.intersecting:
        raise RuntimeError(f"{res.intersecting} intersecting triangle pairs in the written keyframes")
    if not quiet:
        last = res.log[-1]
        click.echo(f"petal-grow: {len(res.frames)} keyframes in {res.seconds:.2f} s -> {output} "
                   f"(growth x{last['growth']:.3f}, joint {last['joint_deg']:.1f} deg, "
                   f"edge stretch {last['min_edge_stretch']:.3f}-{last['max_edge_stretch']:.3f})", err=True)
