"""Command-line front end of ``petal-grow`` (Ijiri et al. 2008).

    petal-grow PARAMS.toml -o OUT_DIR [--keyframes N] [--no-collisions]

Writes ``OUT_DIR/frame_0000.obj`` (the bud) ... ``frame_NNNN.obj`` (one keyframe per growth step,
constant topology and vertex order, ``g``/``usemtl`` per organ) and ``OUT_DIR/log.csv``.
Parameters and files: ``formats/petal_grow.md``.
"""
from __future__ import annotations

from pathlib import Path

import click

from inflo.formats.atomic import staged_output
from inflo.tools.common.cli import inflo_command, progress

from .params import read_params
from .simulate import build_model, run


@inflo_command("petal-grow", help="Grow a bud into an opening flower by growth maps (Ijiri et al. 2008).")
@click.argument("params", type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output folder (OBJ keyframes).")
@click.option("--keyframes", type=click.IntRange(1, 10_000), default=None,
              help="Keyframes to write, the bud included (default: the file's flower.keyframes).")
@click.option("--collisions/--no-collisions", default=None, help="Override flower.collisions.")
def main(params, output, keyframes, collisions, quiet, debug):
    p = read_params(params)
    model = build_model(p)
    n = (keyframes or p.flower.keyframes) - 1
    # a rerun replaces the earlier run's keyframes and log only when it completes; a second run into
    # the folder is refused; the bud meshes and PNG maps are never overwritten
    with staged_output(output, "petal-grow", stale_patterns=(r"frame_\d+\.obj", r"log\.csv"),
                       inputs=_inputs(params, p)) as stage, \
            progress(length=max(n, 1), label="petal-grow", quiet=quiet, unit="frames") as bar:
        res = run(p, stage, keyframes=keyframes, collisions=collisions, progress=bar.update, model=model)
        res.frames = [Path(output) / f.name for f in res.frames]
    if res.intersecting:
        raise RuntimeError(f"{res.intersecting} intersecting triangle pairs in the written keyframes")
    if not quiet:
        last = res.log[-1]
        click.echo(f"petal-grow: {len(res.frames)} keyframes in {res.seconds:.2f} s -> {output} "
                   f"(growth x{last['growth']:.3f}, joint {last['joint_deg']:.1f} deg, "
                   f"edge stretch {last['min_edge_stretch']:.3f}-{last['max_edge_stretch']:.3f})", err=True)


def _inputs(params, p) -> list:
    """Every file the run reads: the parameter file, the organs' bud meshes, the PNG growth maps."""
    base = Path(params).resolve().parent
    out = [(params, "parameter file")] + [(o.mesh, f"bud mesh of organ '{o.name}'") for o in p.organs]
    for gset in p.growth.values():
        for m in vars(gset).values():
            src = getattr(m, "source", None)
            if isinstance(src, str) and src.strip().lower().endswith(".png"):
                out.append((base / src.strip(), "growth map"))
    return out
