"""Command-line front end of ``polygonize`` (thesis 2.4, 8 c))."""
from __future__ import annotations

import click

from inflo.tools.common.cli import inflo_command


def _aspect(ctx, param, value):
    if value is None or value == "auto":
        return None
    try:
        x = float(value)
    except ValueError:
        raise click.BadParameter(f"expected 'auto' or a number > 0, found {value!r}") from None
    if not (ASPECT_RANGE[0] <= x <= ASPECT_RANGE[1]):
        raise click.BadParameter(f"expected 'auto' or a number in [{ASPECT_RANGE[0]:g}, {ASPECT_RANGE[1]:g}], "
                                 f"found {value!r}")
    return x


ASPECT_RANGE = (1e-6, 1e6)
"""--aspect scales u against v before the Delaunay triangulation: beyond a million to one either
way every triangle is a sliver (inf and 1e-300 crashed the triangulation)."""


@inflo_command(
    "polygonize",
    help=(
        "Polygonize a .floret frame sequence (thesis 2.4) into OBJ frames of identical topology.\n\n"
        "FRAMES is a folder of .floret frames (or a glob, or one file). Rows in v follow "
        "lambda(v) (eq. 2.1), ceil(eta(v)) vertices per row (made odd); the (u, v) samples are "
        "Delaunay-triangulated once. Petal copies become OBJ groups ORGAN_k with usemtl "
        "mtl<material>; fused seams share their vertices. Prints triangles per floret, the "
        "minimum angle and the triangles under 10 degrees in the worst frame. Older "
        "frame_NNNN.obj files in the output folder that this run does not write are removed."
    ),
)
@click.argument("frames_dir", type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(file_okay=False),
              help="Folder for the OBJ frames (frame_0000.obj ...).")
@click.option("--lambda", "lam", default=None, metavar="VALUE|FILE.func",
              help="Row spacing lambda(v) > 0 for every organ (overrides the frames' 'lambda:') "
                   "[organ's, else 0.1].")
@click.option("--eta", "eta", default=None, metavar="VALUE|FILE.func",
              help="Vertices per row eta(v) >= 1 for every organ (overrides 'eta:') "
                   "[organ's, else 11].")
@click.option("--aspect", default=None, callback=_aspect, metavar="auto|VALUE",
              help="Scale of u against v for the Delaunay triangulation [auto: the petal's "
                   "width / length, to 6 decimals].")
def main(frames_dir, output, lam, eta, aspect, quiet, debug):
    from .run import polygonize_files

    report = polygonize_files(frames_dir, output, lam=lam, eta=eta, aspect=aspect, quiet=quiet)
    if not quiet:
        for line in report.lines():
            click.echo(f"polygonize: {line}")
