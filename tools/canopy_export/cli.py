"""``canopy-export``: OBJ sequences (+ a colour file) -> one USD file for Blender, Houdini, Maya.

Usage::

    canopy-export [NAME=]IN_DIR|'GLOB'|IN.obj [...] -o OUT.usdc|OUT.usda|OUT.glb [options]

Each input is a part: a folder of OBJ frames, a quoted glob, or one OBJ file (static), named
``NAME`` or after its folder. Sequences exported together need the same number of frames;
frame k of each (0-based, natural file order) is time code ``--start-frame + k``. One Mesh prim
per part: points and extent time-sampled, faces written once, or sampled where they change
(florets emerging); a GeomSubset per OBJ ``usemtl`` bound to a UsdPreviewSurface whose
diffuseColor is the material's colour (``--colors FILE.toml``, canopy-render's colour file and
palette) in linear RGB. ``.usdc``/``.usd`` is binary, ``.usda`` text. See formats/usd.md.

Examples::

    canopy-export tepals=build/lily/canopy column=build/lily/column_obj --colors pipelines/lily/colors.toml \\
        -o build/lily/lily.usdc
    canopy-export build/yarrow/canopy build/yarrow/branches --units mm --fps 30 -o yarrow.usda
    canopy-export build/lily/canopy --pc2 build/lily/pc2 -o lily.usdc   # + tepals' point cache
    canopy-export build/yarrow/canopy --subsets floret --mtl -o yarrow.usdc   # + a subset per floret,
                                                             # build/yarrow/canopy/materials.mtl

Open it in Blender: File > Import > Universal Scene Description, press play.

``-o OUT.glb`` writes one binary glTF 2.0 instead (formats/gltf.md): the growth as morph targets,
one per frame, for three.js, model-viewer, Babylon.js and Blender's glTF importer; ``--viewer``
writes the viewer page beside it (``canopy-view DIR`` serves it).
"""
from __future__ import annotations

import math
import os
from pathlib import Path

import click

from inflo.tools.common.cli import inflo_command, progress

from .export import UNITS, ExportOptions, export_canopy, parse_units
from .parts import frame_count, resolve_parts

__all__ = ["main"]


def _units(ctx, param, value):
    try:
        return parse_units(value)
    except ValueError as exc:
        raise click.BadParameter(str(exc)) from None


def _output(ctx, param, value):
    if not value.lower().endswith((".usdc", ".usda", ".usd", ".glb")):
        raise click.BadParameter(f"expected a name ending .usdc, .usda, .usd or .glb, found {value!r}")
    return value


def _fps(ctx, param, value):
    if not math.isfinite(value) or value <= 0:
        raise click.BadParameter(f"expected a finite number of frames per second above 0, found {value!r}")
    return value


def _translate(ctx, param, values):
    out = {}
    for text in values:
        name, _, xyz = text.partition("=")
        try:
            vec = tuple(float(v) for v in xyz.split(","))
        except ValueError:
            vec = ()
        if not name or len(vec) != 3 or not all(math.isfinite(v) for v in vec):
            raise click.BadParameter(f"expected NAME=X,Y,Z (three numbers), found {text!r}")
        out[name] = vec
    return out


@inflo_command("canopy-export", help="OBJ sequences + colours -> one USD growth animation (formats/usd.md).",
               epilog="Open it in Blender: File > Import > Universal Scene Description, press play.")
@click.argument("inputs", nargs=-1, required=True, metavar="[NAME=]IN_DIR|GLOB|IN.obj...")
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False), callback=_output,
              help="Output .usdc (binary), .usda (text), .usd (binary) or .glb (binary glTF 2.0, formats/gltf.md).")
@click.option("--colors", "color_file", type=click.Path(), default=None,
              help="TOML colour file (canopy-render's): material -> colour, sRGB; written linear.")
@click.option("--units", default="cm", show_default=True, callback=_units,
              help=f"What one unit of the OBJ files is: {', '.join(UNITS)} or metres per unit "
                   f"(the stage's metersPerUnit; the lily is about 15 units across).")
@click.option("--fps", type=float, default=24.0, show_default=True, callback=_fps,
              help="Frames per second (timeCodesPerSecond; the glTF animation's clock).")
@click.option("--start-frame", type=int, default=1, show_default=True,
              help="Time code of the first frame.")
@click.option("--normals", is_flag=True, help="Also write per-vertex normals (Blender computes its own).")
@click.option("--constant-topology", is_flag=True,
              help="Bad input if any frame's faces or vertex count differ from the first frame's.")
@click.option("--subsets", type=click.Choice(["material", "floret"]), default="material", show_default=True,
              help="GeomSubsets per material of a part; 'floret': also one per OBJ group (family 'floret').")
@click.option("--mtl", is_flag=True,
              help="Also write materials.mtl (the OBJ files' mtllib) beside each part's OBJ files, Kd linear.")
@click.option("--translate", "translate", multiple=True, metavar="NAME=X,Y,Z", callback=_translate,
              help="Move part NAME by (X, Y, Z) (an xformOp on its prim; the points are kept). Repeatable.")
@click.option("--pc2", "pc2_dir", type=click.Path(file_okay=False), default=None,
              help="Also write DIR/<part>.pc2 point caches (fixed topology; Blender's Mesh Cache modifier).")
@click.option("--quantize/--no-quantize", default=True, show_default=True,
              help=".glb: positions and morph deltas as 16-bit integers (KHR_mesh_quantization), else float32.")
@click.option("--title", default=None, help=".glb: the title the viewer page shows (default: the file's stem).")
@click.option("--figure", "figures", multiple=True, metavar="TEXT",
              help=".glb: a line of figures the viewer page shows under the title. Repeatable.")
@click.option("--every", type=click.IntRange(min=1), default=1, show_default=True,
              help=".glb: keep every Nth frame (and the last), played at fps/N: a lighter file of a long or large build.")
@click.option("--max-mb", "max_mb", type=click.FloatRange(min=0.1, max=1e6), default=None, metavar="MB",
              help=".glb: at most this many megabytes: frames are thinned (a larger --every) until the file fits.")
@click.option("--viewer", is_flag=True,
              help=".glb: also write the viewer page beside it (index.html and three.js; formats/gltf.md).")
def main(inputs, output, color_file, units, fps, start_frame, normals, constant_topology, subsets, mtl, translate,
         pc2_dir, quantize, title, figures, every, max_mb, viewer, quiet, debug):
    if color_file:  # the colour file is read, never written over
        from inflo.formats.atomic import refuse_output_over_inputs

        refuse_output_over_inputs(output, [(color_file, "colour file")], folder=False)
    if abs(start_frame) > 10_000_000:
        from inflo.formats.errors import InputError

        raise InputError(f"--start-frame: expected a frame within +-10000000, found {start_frame}")
    colors = None
    if color_file:
        from inflo.formats.colors import load_color_file

        colors = load_color_file(color_file)
    glb = output.lower().endswith(".glb")
    if viewer and not glb:
        raise click.BadParameter("--viewer needs a .glb output", param_hint="--viewer")
    for name, given in (("--every", every > 1), ("--max-mb", max_mb is not None)):
        if given and not glb:
            raise click.BadParameter(f"{name} needs a .glb output", param_hint=name)
    parts = resolve_parts(inputs)
    n_frames = frame_count(parts)
    if viewer:
        from inflo.formats.atomic import refuse_output_over_inputs

        page = {"index.html"}
        refuse_output_over_inputs(Path(output).parent, [(q, "OBJ frame") for p in parts for q in p.paths]
                                  + ([(color_file, "colour file")] if color_file else []), option="--viewer",
                                  writes=lambda rel: rel in page or rel.startswith("three/"))
    all_paths = [list(part.paths) for part in parts]
    extras = {"title": title or Path(output).stem, "figures": list(figures)} if glb else {}

    def export(step):
        """Export keeping every ``step``-th frame (and the last), played at fps / step."""
        keep = sorted(set(range(0, n_frames, step)) | {n_frames - 1}) if n_frames > 1 else list(range(n_frames))
        for part, paths in zip(parts, all_paths):
            part.paths = paths if part.is_static else [paths[k] for k in keep]
        options = ExportOptions(fps=fps / step, start_frame=start_frame, meters_per_unit=units, normals=normals,
                                constant_topology=constant_topology, subsets=subsets, mtl=mtl, translate=translate,
                                quantize=quantize, extras=extras)
        with progress(length=len(keep), label="canopy-export", quiet=quiet, unit="frames") as bar:
            return export_canopy(parts, output, colors=colors, options=options, pc2_dir=pc2_dir,
                                 on_frame=lambda k: bar.update(1)), len(keep)

    report, kept = export(every)
    # a size budget: the file grows with the frames kept, so thin them in proportion until it fits
    # (the first and last frame always stay)
    while max_mb is not None and os.path.getsize(output) > max_mb * 1e6 and kept > 2:
        every = max(every + 1, math.ceil(every * os.path.getsize(output) / (max_mb * 1e6)))
        report, kept = export(every)
    if max_mb is not None and os.path.getsize(output) > max_mb * 1e6:
        from inflo.formats.errors import InputError

        size = os.path.getsize(output)
        os.unlink(output)  # no output beyond the budget
        raise InputError(f"{output}: expected a .glb within --max-mb {max_mb:g}, found {size / 1e6:.1f} MB "
                         f"with {kept} frames")
    if viewer:
        from inflo.tools.canopy_view.page import write_viewer

        write_viewer(Path(output).parent, Path(output).name, title=extras["title"])
    if not quiet:
        thinned = f" (every {every}th frame kept for --max-mb {max_mb:g})" if max_mb is not None and every > 1 else ""
        click.echo(f"canopy-export: {report.summary()}{thinned}", err=True)
