"""``canopy-render``: headless, CPU-only pictures of OBJ meshes and OBJ sequences.

Usage::

    canopy-render IN.obj|IN_DIR|'GLOB' [...] -o OUT.png|OUT.gif|OUT.mp4 [options]

Each input is an OBJ file (drawn in every frame) or a sequence: a folder of OBJ frames or a quoted
glob. Several inputs are drawn together (e.g. a canopy sequence and its branches); sequences drawn
together need the same number of frames. Many OBJ files given one by one (a shell-expanded glob)
are taken as the frames of one sequence when the output is an animation or a sheet, or with
``--sequence``.

Outputs, by the suffix of ``-o``:

- ``OUT.png``: a still of one frame (``--frame N``, default the last);
- ``OUT.png`` with ``--sheet 1,10,20,...`` or ``--sheet-every 10``: a contact sheet, the frames
  in a grid with their numbers (like Ijiri et al. 2008, fig. 1);
- ``OUT.gif`` / ``OUT.mp4``: an animation of every frame (``--fps``).

Frame numbers count from 1 (frame 1 is the first file); -1 is the last frame.

Camera: automatic framing (every frame of an animation, so it does not jump) from a named view,
``--view iso`` (default: azimuth 30, elevation 25), ``front``, ``side``, ``back``, ``top``,
``bottom``; ``--azimuth``/``--elevation`` in degrees about the up axis (+Y; ``--up-axis z`` for
Z-up files); ``--fcc PARAMS.fcc`` takes the thesis viewer's ``camera position``, ``camera
lookat``, ``camera up``, ``camera fov``, ``near plane``, ``far plane`` and ``light position``.

Textures: ``--texture [MATERIAL=]IMAGE.png`` or ``--mtl-textures`` (the ``.mtl`` ``map_Kd``) draw
faces with an image at their ``vt`` coordinates (see :mod:`.texture`); e.g. a venation blade::

    canopy-render out/blade.obj --mtl-textures --view front --ortho -o leaf.png

Colours: the OBJ's vertex colours; else ``--color`` per input; else its ``usemtl`` materials
(``--colors FILE.toml``, then the built-in botanical palette by SCN ``mtl:`` id or organ word);
else an automatic colour per input. See ``inflo.formats.colors``.

Examples::

    canopy-render build/lily/smooth/ -o lily.png
    canopy-render build/lily/canopy/ --sheet-every 10 -o lily_sheet.png
    canopy-render build/yarrow/canopy/ build/yarrow/branches.obj --view top -o yarrow_top.png
    canopy-render build/lily/canopy/ -o lily.mp4 --fps 30 --size 1280x720

Bounds (bad input, one line, exit 2, before drawing): ``--size`` up to 16384x16384 and what the
GL can allocate at ``--samples`` (llvmpipe: about 8192x8192 at 4 samples); a sheet's or GIF's
frames x width x height at most 2**29 pixels (held in memory; an MP4 streams); float options
finite; ``--label`` fields ``{n}``, ``{index}``, ``{name}``; the ``.fcc`` camera keys within
formats/fcc.md's canopy-render ranges.

Needs Mesa's EGL (``apt-get install -y libegl1 libegl-mesa0 libgl1-mesa-dri libgl1``); without it
the run stops with exit code 1 and says so. Bad input exits with code 2.
"""
from __future__ import annotations

import re
from pathlib import Path

import click

from inflo.formats.colors import load_color_file, parse_color
from inflo.tools.common.cli import inflo_command

from .camera import DEFAULT_FOV, DEFAULT_MARGIN, VIEWS
from .render import RenderOptions

__all__ = ["main"]


def _size(ctx, param, value):
    if value is None:
        return None
    m = re.fullmatch(r"\s*(\d+)\s*[xX*,]\s*(\d+)\s*", value)
    if not m or not (1 <= int(m.group(1)) <= 16384 and 1 <= int(m.group(2)) <= 16384):
        raise click.BadParameter(f"expected WIDTHxHEIGHT in pixels (1..16384), e.g. 1024x768; found {value!r}")
    return int(m.group(1)), int(m.group(2))


def _color(ctx, param, value):
    if value is None:
        return None
    if isinstance(value, tuple):
        return tuple(_color(ctx, param, v) for v in value)
    try:
        return parse_color(value, "colour")
    except ValueError as exc:
        raise click.BadParameter(str(exc)) from None


def _label(ctx, param, value):
    """A sheet label template: fields ``{n}``, ``{index}``, ``{name}`` only (no attribute or item
    access), and a format spec of at most three-digit widths (a label, not megabytes of padding)."""
    import string

    if not value:
        return value
    try:
        fields = [(f, spec) for _, f, spec, _ in string.Formatter().parse(value) if f is not None]
    except ValueError as exc:
        raise click.BadParameter(f"expected a label with {{n}}, {{index}} or {{name}}, found {value!r} ({exc})") from None
    for f, spec in fields:
        if f not in ("n", "index", "name") or "{" in (spec or "") or re.search(r"\d{4,}", spec or ""):
            raise click.BadParameter(f"expected a label with {{n}}, {{index}} or {{name}} (a format spec of widths "
                                     f"below 1000), found {value!r}")
    try:
        value.format(n=1, index=0, name="frame_0000")
    except (ValueError, TypeError) as exc:
        raise click.BadParameter(f"expected a label with {{n}}, {{index}} or {{name}}, found {value!r} ({exc})") from None
    return value


def _frames(ctx, param, value):
    if value is None:
        return None
    from .sheet import parse_frame_list

    try:
        return parse_frame_list(value)
    except ValueError as exc:
        raise click.BadParameter(str(exc)) from None


@inflo_command(
    "canopy-render",
    help="Render OBJ meshes or OBJ sequences headless to a PNG still, a contact sheet, or a GIF/MP4 animation.",
    epilog="Frame numbers count from 1; -1 is the last frame. See the module docstring of "
           "inflo.tools.canopy_render.cli for the colour rules and examples.",
)
@click.argument("inputs", nargs=-1, required=True, type=click.Path())
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False, path_type=Path),
              help="OUT.png (still or sheet), OUT.gif or OUT.mp4 (animation).")
@click.option("--frame", type=int, default=None,
              help="Frame of a sequence for a .png still (1-based; negative from the end) [the last].")
@click.option("--sheet", "sheet_frames", callback=_frames, metavar="N,N,...",
              help="Contact sheet of these frames, e.g. 1,10,20,30 (output .png).")
@click.option("--sheet-every", type=click.IntRange(min=1), metavar="N",
              help="Contact sheet of frames 1, N, 2N, ... and the last (output .png).")
@click.option("--columns", type=click.IntRange(min=1), help="Columns of a contact sheet [at most 6 a row].")
@click.option("--label", "label_format", default="frame {n}", show_default=True, callback=_label,
              help="Sheet label per frame: {n} frame number, {index} 0-based, {name} file stem; '' for none.")
@click.option("--title", help="A title line above a contact sheet.")
@click.option("--fps", type=click.FloatRange(min=0.1, max=100), default=25.0, show_default=True,
              help="Frames per second of an animation.")
@click.option("--size", callback=_size, metavar="WxH",
              help="Image size (per tile for a sheet) [still and MP4 1024x768, GIF 480x360, sheet tile 400x400].")
@click.option("--view", type=click.Choice(list(VIEWS)), default=None,
              help="Named view direction [iso: azimuth 30, elevation 25].")
@click.option("--azimuth", type=float, help="Degrees about the up axis, from +Z towards +X (overrides --view's).")
@click.option("--elevation", type=click.FloatRange(-90, 90), help="Degrees above the horizontal (overrides --view's).")
@click.option("--up-axis", type=click.Choice(["y", "z"]), default="y", show_default=True,
              help="The world's up axis (+Y is the floret axis in inflo files).")
@click.option("--fov", type=click.FloatRange(1, 170), default=DEFAULT_FOV, show_default=True,
              help="Vertical field of view, degrees.")
@click.option("--ortho", is_flag=True, help="Orthographic projection (e.g. for --view top/side figures).")
@click.option("--zoom", type=click.FloatRange(min=0.01, max=100), default=1.0, show_default=True,
              help="> 1 moves closer than the automatic framing, < 1 leaves more room.")
@click.option("--margin", type=click.FloatRange(0, 0.45), default=DEFAULT_MARGIN, show_default=True,
              help="Free border of the automatic framing, as a fraction of each half-size.")
@click.option("--fcc", type=click.Path(), metavar="PARAMS.fcc",
              help="Take camera and light from a canopy parameter file's viewer keys (a --view/--azimuth/"
                   "--elevation given keeps the automatic camera and takes only the light).")
@click.option("--fit-all", is_flag=True,
              help="Frame a still or sheet on every frame of the sequence (the animation's scale).")
@click.option("--background", callback=_color, default="white", show_default=True,
              help="Background colour: a name, #rrggbb or r,g,b in 0..1.")
@click.option("--color", "colors_per_input", multiple=True, callback=_color,
              help="Colour of an input (repeat: one per input, in order); overrides its materials.")
@click.option("--colors", "color_file", type=click.Path(), metavar="FILE.toml",
              help="Material colours: lines like  3 = [0.95, 0.8, 0.1]  or  disk = \"#6b4a1f\".")
@click.option("--no-vertex-colors", is_flag=True, help="Ignore the OBJ's vertex colours.")
@click.option("--wireframe", is_flag=True, help="Draw triangle edges over the surfaces.")
@click.option("--wireframe-color", callback=_color, default="0.1,0.1,0.1", show_default=True)
@click.option("--lines/--no-lines", "draw_lines", default=True, show_default=True,
              help="Draw the OBJ 'l' polylines (skeletons).")
@click.option("--line-color", callback=_color, default="0.22,0.30,0.12", show_default=True)
@click.option("--line-width", type=click.FloatRange(min=0.1, max=64), default=1.5, show_default=True,
              help="Width of polylines and wireframe edges, pixels.")
@click.option("--samples", type=click.IntRange(1, 16), default=4, show_default=True,
              help="Multisampling antialiasing samples (capped at the GL's maximum).")
@click.option("--texture", "textures", multiple=True, metavar="[MATERIAL=]IMAGE.png",
              help="Draw the faces of MATERIAL (without it: every face with 'vt' coordinates) with this "
                   "texture image at their OBJ 'vt' uv coordinates; texels with alpha < 0.5 are cut out (repeat).")
@click.option("--mtl-textures", is_flag=True,
              help="Take texture images from the inputs' .mtl files (map_Kd) for the faces with 'vt' coordinates.")
@click.option("--sequence", "as_sequence", is_flag=True,
              help="The input files are the frames of one sequence (e.g. a shell-expanded glob).")
def main(*, inputs, output, frame, sheet_frames, sheet_every, columns, label_format, title, fps, size, view,
         azimuth, elevation, up_axis, fov, ortho, zoom, margin, fcc, fit_all, background, colors_per_input,
         color_file, no_vertex_colors, wireframe, wireframe_color, draw_lines, line_color, line_width,
         samples, textures, mtl_textures, as_sequence, quiet, debug):
    from .job import RenderJob, output_kind, run_job

    if frame == 0:
        raise click.BadParameter("frame numbers count from 1 (negative ones from the end)", param_hint="--frame")
    if sheet_frames and sheet_every:
        raise click.UsageError("give either --sheet or --sheet-every, not both")
    try:
        kind = output_kind(output, bool(sheet_frames or sheet_every))
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="-o/--output") from None
    if frame is not None and kind != "still":
        raise click.UsageError(f"--frame chooses the frame of a .png still; a {kind} shows "
                               f"{'the frames of --sheet' if kind == 'sheet' else 'every frame'}")
    _refuse_output_over_inputs(output, inputs, color_file, fcc, textures, mtl_textures)
    files_only = len(inputs) > 1 and all(Path(p).is_file() for p in inputs)
    if not as_sequence and files_only and kind != "still":
        as_sequence = True
        if not quiet:
            click.echo(f"canopy-render: taking the {len(inputs)} input files as the frames of one sequence", err=True)
    n_layers = 1 if as_sequence else len(inputs)
    if len(colors_per_input) > n_layers:
        raise click.UsageError(f"{len(colors_per_input)} --color values for {n_layers} input(s)")

    options = RenderOptions(
        background=background,
        samples=samples,
        wireframe=wireframe,
        wireframe_color=wireframe_color,
        draw_lines=draw_lines,
        line_color=line_color,
        line_width=line_width,
        mesh_colors=tuple(colors_per_input),
        material_colors=load_color_file(color_file) if color_file else None,
        use_vertex_colors=not no_vertex_colors,
    )
    job = RenderJob(
        inputs=list(inputs), output=output, options=options, size=size, as_sequence=as_sequence,
        frame=-1 if frame is None else frame,
        sheet_frames=sheet_frames, sheet_every=sheet_every, columns=columns, label_format=label_format,
        title=title, fps=fps, view=view, azimuth=azimuth, elevation=elevation, up_axis=up_axis, fov=fov,
        ortho=ortho, zoom=zoom, margin=margin, fcc=fcc, fit_all=fit_all, quiet=quiet,
        textures=list(textures), mtl_textures=mtl_textures,
    )
    summary = run_job(job)
    if not quiet:
        click.echo(f"canopy-render: {summary}", err=True)


def _refuse_output_over_inputs(output, inputs, color_file, fcc, textures, mtl_textures) -> None:
    """One line, exit 2, before any work: the picture would replace a file the run reads (an input
    mesh, the colour file, the .fcc, a texture given or named by an input's .mtl)."""
    import re

    from inflo.formats.atomic import refuse_output_over_inputs

    read = [(p, "input") for p in inputs if Path(p).is_file()]
    read += [(color_file, "colour file"), (fcc, ".fcc file")]
    read += [(t.split("=", 1)[1] if "=" in t and not Path(t).exists() else t, "texture") for t in textures]
    if mtl_textures:
        for folder in {Path(p) if Path(p).is_dir() else Path(p).parent for p in inputs}:
            for mtl in sorted(folder.glob("*.mtl")) if folder.is_dir() else ():
                for m in re.finditer(r"^\s*map_Kd\s+(.+?)\s*$", mtl.read_text(errors="replace"), re.M):
                    read.append((mtl.parent / m.group(1), "texture"))
    refuse_output_over_inputs(output, read, folder=False)
