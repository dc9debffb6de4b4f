"""Command-line front end of ``dimorph`` (thesis ch. 6).

``dimorph SCENE.scn --alpha DEG -o OUT.scn`` types the florets of a scene; ``dimorph sweep -o DIR``
writes the canalization curves of figs. 6.2-6.3. A first argument that is not a subcommand is
the scene file (the minimal invocation).
"""
from __future__ import annotations

from pathlib import Path

import click

from inflo.formats.atomic import check_output_path, refuse_output_over_inputs, staged_output
from inflo.formats.scn import MAX_WRITTEN, read_scn, write_scn
from inflo.tools.common.cli import InfloGroup, inflo_command

from .dimorph import DimorphOptions, check_window_options, dimorph_scene
from .sweep import MAX_SWEEP_WORK, sweep_work, write_sweep

#: a floret type id: the scene arrays hold ids as int32
MAX_ID = 2**31 - 1
#: --bracts and --marginal: placements of one head (phyllotaxis places at most a million)
MAX_COUNT = 1_000_000


def refuse_far_placements(path, sc) -> None:
    """InputError for a placement whose position or scale lies beyond +-MAX_WRITTEN (the most a scene
    writer puts in a file): the cone tests would overflow, and the typed scene could not be written."""
    from inflo.formats.errors import InputError

    for k, p in enumerate(sc.placements):
        big = max(abs(float(x)) for v in (p.pos, p.scale) for x in v)
        if not big <= MAX_WRITTEN:
            raise InputError(f"{path}: expected placements with positions and scales within +-{MAX_WRITTEN:g} "
                             f"(inputs of a sensible size), found {big:g} in placement {k} (id {p.id})")


@inflo_command("dimorph", help="Set floret types and sizes by cones (thesis ch. 6), and optionally each type's "
                                "developmental window (--ray-lead, --ray/--disk-development-frames).",
               short_help="Type the florets of SCENE.scn (the default command).")
@click.argument("scene", type=click.Path())
@click.option("--alpha", type=float, required=True, help="Cone opening angle in degrees.")
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output scene file.")
@click.option("--threshold", "thresholds", type=float, multiple=True,
              help="Distance threshold(s): once: ray iff d_min > Th (fig. 6.4a,b); twice: Th_a < Th_b, "
                   "large rays above Th_b, small rays (size ~ d_min) between (fig. 6.4c); each in [0, 1e12]. Default: ray iff the cone is empty.")
@click.option("--ray-id", type=int, default=1, show_default=True, help="Floret type id of ray florets (ids: 0 .. 2^31-1).")
@click.option("--disk-id", type=int, default=0, show_default=True, help="Floret type id of disk florets.")
@click.option("--small-ray-id", type=int, default=None, help="Type id of small ray florets (default: --ray-id).")
@click.option("--ray-scale", type=float, default=1.0, show_default=True, help="Scale factor of ray florets.")
@click.option("--small-ray-scale", type=float, default=None,
              help="With two thresholds: a small ray floret's factor is this x d_min / Th_b (default: --ray-scale).")
@click.option("--disk-scale", type=float, default=1.0, show_default=True, help="Scale factor of disk florets.")
@click.option("--centre", type=click.Choice(["group", "top"]), default="group", show_default=True,
              help="Cone axis away from the floret's own head/umbellet centre, or its top-level group's.")
@click.option("--half-angle", is_flag=True, help="Read --alpha as the cone's half-angle (eq. 6.1 as printed).")
@click.option("--ray-lead", type=float, default=0.0, show_default=True, metavar="FRAMES",
              help="Ray and small ray florets develop this many frames ahead of the disk florets: their "
                   "frameStart and frameEnd move that much earlier (negative: later), rounded to whole "
                   "frames (within +-1e7), frameStart kept >= 0 and frameEnd >= frameStart + 1 (a window ending past frame 1e7 "
                   "is refused). Only placements with a "
                   "window (ca, ta, ra, rba); o and i are untouched.")
@click.option("--ray-development-frames", type=int, default=None, metavar="N",
              help="Ray and small ray florets: frameEnd = frameStart + N, N in 1..1e7 (applied before --ray-lead).")
@click.option("--disk-development-frames", type=int, default=None, metavar="N",
              help="Disk florets: frameEnd = frameStart + N, N in 1..1e7.")
@click.option("--bract-development-frames", type=int, default=None, metavar="N",
              help="Involucral bracts: frameEnd = frameStart + N (they open with the head, not round a naked "
                   "meristem).")
@click.option("--bracts", type=int, default=0, show_default=True, metavar="N",
              help="The N outermost placements of each head (N at most 1e6) are involucral bracts (type 'bract', "
                   "--bract-id), left out of the other florets' cone tests.")
@click.option("--bract-id", type=int, default=2, show_default=True, help="Type id of involucral bracts.")
@click.option("--bract-scale", type=float, default=1.0, show_default=True, help="Scale factor of bracts.")
@click.option("--marginal", type=int, default=0, show_default=True, metavar="N",
              help="Only the N outermost florets of each head (after its bracts; N at most 1e6) may be ray florets, as "
                   "in Asteraceae, whose ray florets are marginal; the others are disk florets whatever "
                   "their cones. 0: any floret.")
@click.option("--petal-size", is_flag=True,
              help="Ray and small ray size factors grow the petals only ('#@ petal: f'; fccompose scales the "
                   "template's 'petal weight' vertices), not the whole floret (fig. 6.4c).")
@click.option("--orient-rays", type=click.Choice(["none", "group", "top"]), default="none", show_default=True,
              help="Turn each ray floret about its axis so that its local +X (a zygomorphic floret's outward "
                   "petal) points away from its group's or top-level group's centre.")
def run(*, scene, alpha, output, thresholds, ray_id, disk_id, small_ray_id, ray_scale, small_ray_scale, disk_scale, centre,
        half_angle, ray_lead, ray_development_frames, disk_development_frames, bracts, bract_id, bract_scale,
        petal_size, orient_rays, marginal, bract_development_frames, quiet, debug):
    from inflo.formats.errors import InputError

    if len(thresholds) > 2:
        raise InputError(f"--threshold given {len(thresholds)} times; expected at most 2")
    for name, v, top in (("--ray-id", ray_id, MAX_ID), ("--disk-id", disk_id, MAX_ID),
                         ("--small-ray-id", small_ray_id, MAX_ID), ("--bracts", bracts, MAX_COUNT),
                         ("--bract-id", bract_id, MAX_ID), ("--marginal", marginal, MAX_COUNT)):
        if v is not None and v < 0:
            raise InputError(f"{name} must be >= 0, found {v}")
        if v is not None and v > top:
            raise InputError(f"{name} must be in [0, {top}], found {v}")
    if any(t > MAX_WRITTEN for t in thresholds):  # NaN and negative ones: dimorph_scene
        raise InputError(f"--threshold must be in [0, {MAX_WRITTEN:g}] (a distance in scene units), "
                         f"found {max(thresholds):g}")
    for name, v in (("--ray-scale", ray_scale), ("--disk-scale", disk_scale), ("--bract-scale", bract_scale),
                    ("--small-ray-scale", ray_scale if small_ray_scale is None else small_ray_scale)):
        if not v > 0:
            raise InputError(f"{name} must be > 0, found {v}")
        if not 1e-6 <= v <= 1e6:
            raise InputError(f"{name} must be in [1e-06, 1e+06], found {v:g}")
    opts = DimorphOptions(alpha, tuple(thresholds), ray_id, disk_id, small_ray_id, ray_scale, disk_scale,
                          centre, half_angle, ray_lead, ray_development_frames, disk_development_frames,
                          bracts, bract_id, bract_scale, petal_size, orient_rays, small_ray_scale, marginal,
                          bract_development_frames)
    check_window_options(opts)
    check_output_path(output, folder=False)
    refuse_output_over_inputs(output, [(scene, "input scene")], folder=False)
    sc = read_scn(scene)
    refuse_far_placements(scene, sc)
    out, counts = dimorph_scene(sc, opts)
    write_scn(output, out)
    if not quiet:
        windows = f", {counts['windows']} developmental windows set" if counts["windows"] else ""
        bract_note = f", {counts['bract']} bracts" if counts["bract"] else ""
        click.echo(f"dimorph: {counts['ray']} ray, {counts['small_ray']} small ray, {counts['disk']} disk florets"
                   f"{bract_note}{windows} -> {output}", err=True)


@inflo_command("sweep", help="Ray floret counts vs head size (fig. 6.2) and vs cone angle (fig. 6.3): CSV + PNG.",
               short_help="Ray counts vs n and vs alpha (figs. 6.2, 6.3): CSV + PNG.")
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output folder.")
@click.option("--alpha", type=float, default=75.0, show_default=True, help="Cone angle of the n sweep (fig. 6.2).")
@click.option("--n-min", type=int, default=10, show_default=True, help="Smallest head of the n sweep (fig. 6.2).")
@click.option("--n-max", type=int, default=300, show_default=True,
              help="Largest head of the n sweep, at most 100000.")
@click.option("--n", "n_fixed", type=int, default=82, show_default=True, help="Head size of the alpha sweep (fig. 6.3), in [2, 100000]; a sweep runs at most 2e7 cone tests (the sum over its heads of max(n, 100)^1.5).")
@click.option("--alpha-min", type=float, default=20.0, show_default=True)
@click.option("--alpha-max", type=float, default=120.0, show_default=True)
@click.option("--alpha-step", type=float, default=0.5, show_default=True, help="In [0.001, 180] degrees.")
@click.option("--divergence", type=float, default=137.5, show_default=True, help="Divergence angle (degrees).")
@click.option("--half-angle", is_flag=True, help="Read cone angles as half-angles (eq. 6.1 as printed).")
def sweep(output, alpha, n_min, n_max, n_fixed, alpha_min, alpha_max, alpha_step, divergence, half_angle,
          quiet, debug):
    from inflo.formats.errors import InputError

    if not 2 <= n_min <= n_max <= 100_000:
        raise InputError(f"expected 2 <= --n-min <= --n-max <= 100000, found {n_min}, {n_max}")
    if not 1e-3 <= alpha_step <= 180:
        raise InputError(f"--alpha-step must be in [0.001, 180] degrees, found {alpha_step:g}")
    if not 2 <= n_fixed <= 100_000:
        raise InputError(f"--n must be in [2, 100000], found {n_fixed}")
    top = 90 if half_angle else 180
    if not (0 < alpha_min <= alpha_max <= top and 0 < alpha <= top and alpha_step > 0):
        raise InputError(f"cone angles must lie in (0, {top}] degrees with --alpha-min <= --alpha-max and --alpha-step > 0")
    if not 0 < divergence < 360:
        raise InputError(f"--divergence {divergence} outside (0, 360) degrees")
    work = sweep_work((n_min, n_max), n_fixed, (alpha_min, alpha_max), alpha_step)
    if work > MAX_SWEEP_WORK:
        raise InputError(f"expected a sweep of at most {MAX_SWEEP_WORK:.3g} cone tests (the sum over its heads of "
                         f"max(n, 100)^1.5: --n-min..--n-max, and --n once per alpha step), found {work:.3g}")
    own = (r"sweep_n\.csv", r"sweep_n\.png", r"sweep_alpha\.csv", r"sweep_alpha\.png")
    with staged_output(output, "dimorph-sweep", stale_patterns=own) as stage:  # the four files of one run
        res = write_sweep(stage, alpha=alpha, n_range=(n_min, n_max), n_fixed=n_fixed,
                          alpha_range=(alpha_min, alpha_max), alpha_step=alpha_step, divergence=divergence,
                          half_angle=half_angle)
    if not quiet:
        for p in res["paths"]:
            click.echo(f"dimorph sweep: wrote {Path(output) / Path(p).name}", err=True)


class _SceneOrSubcommand(InfloGroup):
    """A group whose first argument, when it is not a subcommand, is the scene of ``run``.

    Flags given before the subcommand (``dimorph --debug sweep ...``) are passed on to it.
    """

    def parse_args(self, ctx, args):
        if not args or args[0] in ("-h", "--help"):
            return super().parse_args(ctx, args)
        k = next((i for i, a in enumerate(args) if not a.startswith("-")), None)
        if k is not None and args[k] in self.commands:
            args = [args[k], *args[:k], *args[k + 1:]]
        else:
            args = ["run", *args]
        return super().parse_args(ctx, args)


main = _SceneOrSubcommand(
    "dimorph", commands={"run": run, "sweep": sweep},
    params=[click.Option(["--quiet", "-q"], is_flag=True, help="No progress bar or messages (passed to the subcommand)."),
            click.Option(["--debug"], is_flag=True, help="Show a Python traceback on errors (passed to the subcommand).")],
    help="Set floret types and sizes by cones (thesis ch. 6), and each type's developmental window.\n\n"
         "  dimorph SCENE.scn --alpha DEG -o OUT.scn   (same as: dimorph run ...)\n\n"
         "  dimorph sweep -o DIR                       (figs. 6.2-6.3 as CSV + PNG)",
    context_settings={"help_option_names": ["-h", "--help"]})
