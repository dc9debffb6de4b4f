"""Command-line front end of ``floret-animate`` (thesis 2.3, 8 b))."""
from __future__ import annotations

import click

from inflo.tools.common.cli import SEED, inflo_command


@inflo_command(
    "floret-animate",
    help=(
        "Interpolate floret key poses (thesis ch. 2.3) into one .floret file per frame.\n\n"
        "KEY_POSES are two or more compatible .floret key poses in time order; the control "
        "polylines are blended intrinsically (rotation-minimizing frames, slerp). With --lu "
        "PARAMS.toml, a single initial pose is grown instead by Lu et al.'s growth-rate "
        "functions. Frames are FRAMES_DIR/frame_0000.floret ...; each frame's 'time:' is its "
        "developmental time. Older frame_NNNN.floret files in FRAMES_DIR that this run does not "
        "write (from a longer earlier run) are removed."
    ),
)
@click.argument("key_poses", nargs=-1, required=True, type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(file_okay=False),
              help="Folder for the frame .floret files.")
@click.option("--frames", default=100, show_default=True, type=click.IntRange(min=1, max=100_000),
              help="Number of frames to write.")
@click.option("--growth", "growth", type=click.Path(), default=None,
              help="Growth function .func: frame time (x in [0, 1]) -> developmental time "
                   "(y in [0, 1] between the first and last key time) [linear].")
@click.option("--lu", "lu_params", type=click.Path(), default=None,
              help="Growth-function mode (Lu et al.): grow the single key pose by the growth rates "
                   "in this TOML file.")
@click.option("--seed", default=0, show_default=True, type=SEED,
              help="Seed of the random petal perturbation in --lu mode.")
def main(key_poses, output, frames, growth, lu_params, seed, quiet, debug):
    from .run import animate_files

    written = animate_files(key_poses, output, n_frames=frames, growth_path=growth,
                            lu_params=lu_params, seed=seed, quiet=quiet)
    if not quiet:
        click.echo(f"floret-animate: wrote {len(written)} frames to {output}", err=True)
