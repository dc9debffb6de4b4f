"""One ``canopy-render`` run: inputs -> frames -> camera -> images -> one output file.

:func:`run_job` is what the CLI calls after parsing; pipelines may call it too. The kind of
output follows the suffix of the output path: ``.png`` a still (or, with a sheet selection, a
contact sheet), ``.gif``/``.mp4`` an animation of every frame.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from pathlib import Path

from inflo.formats.errors import InputError
from inflo.tools.common.cli import progress

from .camera import DEFAULT_FOV, DEFAULT_MARGIN, camera_from_fcc
from .inputs import FrameReader, count_primitives, resolve_inputs
from .output import write_gif, write_mp4, write_png
from .render import Renderer, RenderOptions, auto_camera
from .sheet import contact_sheet, every_nth, format_label, frame_index

__all__ = ["RenderJob", "run_job", "output_kind", "DEFAULT_SIZES", "read_fcc_camera"]

DEFAULT_SIZES = {"still": (1024, 768), "sheet": (400, 400), "gif": (480, 360), "mp4": (1024, 768)}
"""Image size (width, height) per output kind when none is given; for a sheet, per tile."""


def output_kind(path, sheet: bool) -> str:
    """``"still"``, ``"sheet"``, ``"gif"`` or ``"mp4"`` from the output suffix.

    Raises
    ------
    ValueError
        Unknown suffix, or a sheet asked for with an animation suffix.
    """
    suffix = Path(path).suffix.lower()
    if suffix == ".png":
        return "sheet" if sheet else "still"
    if suffix in (".gif", ".mp4"):
        if sheet:
            raise ValueError(f"a contact sheet is a .png image, not {suffix}")
        return suffix[1:]
    raise ValueError(f"output {path}: expected a .png, .gif or .mp4 file name")


@dataclass
class RenderJob:
    """Everything one run needs (the CLI's options, parsed).

    Attributes
    ----------
    inputs : list of str
        OBJ files, folders, globs (see :mod:`.inputs`).
    output : pathlib.Path
    options : RenderOptions
        Drawing options; ``options.size`` is replaced by ``size`` or the kind's default.
    size : (int, int) or None
        Image (for a sheet: tile) size; None: :data:`DEFAULT_SIZES`.
    as_sequence : bool
        The inputs are the frames of one sequence.
    frame : int
        1-based frame of a still (negative from the end).
    sheet_frames : list of int or None
        1-based frames of a contact sheet.
    sheet_every : int or None
        Sheet of frames 1, N, 2N, ..., last.
    columns : int or None
    label_format : str
        ``{n}``, ``{index}``, ``{name}``; empty for no labels.
    title : str or None
    fps : float
    view, azimuth, elevation, up_axis, fov, ortho, zoom, margin
        The automatic camera (see :func:`.camera.fit_camera`).
    fcc : path or None
        A ``.fcc`` file whose camera keys set the camera and light.
    fit_all : bool
        Frame a still on every frame of the sequence (same scale as the animation).
    quiet : bool
    textures : list of str
        ``[MATERIAL=]IMAGE.png`` texture maps (:mod:`.texture`).
    mtl_textures : bool
        Take texture maps from the inputs' ``.mtl`` ``map_Kd`` lines.
    """

    inputs: list
    output: Path
    options: RenderOptions = field(default_factory=RenderOptions)
    size: tuple | None = None
    as_sequence: bool = False
    frame: int = -1
    sheet_frames: list | None = None
    sheet_every: int | None = None
    columns: int | None = None
    label_format: str = "frame {n}"
    title: str | None = None
    fps: float = 25.0
    view: str | None = None
    azimuth: float | None = None
    elevation: float | None = None
    up_axis: str = "y"
    fov: float = DEFAULT_FOV
    ortho: bool = False
    zoom: float = 1.0
    margin: float = DEFAULT_MARGIN
    fcc: str | None = None
    fit_all: bool = False
    quiet: bool = False
    textures: list = field(default_factory=list)
    mtl_textures: bool = False


#: the most pixels of the frames a contact sheet or a GIF holds in memory at once (frames x
#: width x height; 1.6 GB as RGB): some 3,000 GIF frames at 480x360 or sheet tiles at 400x400
MAX_HELD_PIXELS = 2**29

#: the ``.fcc`` camera keys canopy-render draws with: field of view in degrees, clip distances
FCC_FOV_RANGE = (0.01, 179.0)
FCC_CLIP_RANGE = (1e-9, 1e15)


def read_fcc_camera(path):
    """The viewer keys (``CameraParams``) of a ``.fcc`` file; :class:`FormatError` when it is malformed
    or a key is beyond what a picture can be drawn with: a position, look-at point, up vector or light
    beyond +-1e15 (the coordinates of a renderable scene), ``camera fov`` outside [0.01, 179]
    degrees, ``near plane``/``far plane`` outside [1e-9, 1e15] (the projection's numbers overflow
    or underflow beyond them)."""
    from inflo.formats.errors import FormatError
    from inflo.formats.fcc import read_fcc

    from .inputs import MAX_COORDINATE

    cam = read_fcc(path).camera
    for key, v in (("camera position", cam.position), ("camera lookat", cam.lookat), ("camera up", cam.up),
                   ("light position", cam.light_position)):
        if v is not None and not all(abs(float(x)) <= MAX_COORDINATE for x in v):
            raise FormatError(path, None, f"{key} within +-{MAX_COORDINATE:g}", " ".join(f"{float(x):g}" for x in v))
    lo, hi = FCC_FOV_RANGE
    if not lo <= float(cam.fov_deg) <= hi:
        raise FormatError(path, None, f"camera fov in [{lo:g}, {hi:g}] degrees", f"{float(cam.fov_deg):g}")
    lo, hi = FCC_CLIP_RANGE
    for key, v in (("near plane", cam.near), ("far plane", cam.far)):
        if v is not None and not lo <= float(v) <= hi:
            raise FormatError(path, None, f"{key} in [{lo:g}, {hi:g}]", f"{float(v):g}")
    return cam


def run_job(job: RenderJob) -> str:
    """Render and write ``job.output``; returns a one-line summary.

    Raises
    ------
    InputError
        Missing or malformed input, a frame that does not exist, nothing to draw.
    GLUnavailable
        No OpenGL context (the message names the packages to install).
    """
    t0 = time.perf_counter()
    kind = output_kind(job.output, bool(job.sheet_frames or job.sheet_every))
    layers = resolve_inputs(job.inputs, as_sequence=job.as_sequence)
    spec = None
    if job.textures or job.mtl_textures:
        from .texture import TextureSpec, parse_texture_option

        spec = TextureSpec(use_mtl=job.mtl_textures)
        for value in job.textures:
            try:
                mat, img = parse_texture_option(value)
            except ValueError as exc:
                raise InputError(f"--texture: {exc}") from None
            if mat is None:
                spec.everything = img
            else:
                spec.by_material[mat] = img
    reader = FrameReader(layers, spec)
    n = reader.n_frames
    options = replace(job.options, size=tuple(job.size or DEFAULT_SIZES[kind]))

    # which frames to draw, which to frame the camera on
    if kind == "still":
        shown = [frame_index(job.frame, n)]
    elif kind == "sheet":
        numbers = job.sheet_frames or every_nth(job.sheet_every, n)
        shown = [frame_index(k, n) for k in numbers]
    else:
        shown = list(range(n))
    framed = list(range(n)) if (job.fit_all or kind in ("gif", "mp4")) else sorted(set(shown))
    w, h = options.size
    if kind in ("sheet", "gif") and len(shown) * w * h > MAX_HELD_PIXELS:  # their frames are held in memory
        raise InputError(f"{job.output}: expected a {kind} of at most {MAX_HELD_PIXELS:,} pixels in all (frames x "
                         f"--size), found {len(shown)} frames of {w}x{h} = {len(shown) * w * h:,}")

    fcc_camera = read_fcc_camera(job.fcc) if job.fcc is not None else None
    renderer = Renderer()  # before the reading: a missing GL fails fast
    try:
        needed = sorted(set(framed) | set(shown))
        with progress(length=len(needed), label="reading  ", quiet=job.quiet or len(needed) < 3) as bar:
            scenes = dict(zip(needed, reader.scenes(needed, on_frame=lambda _: bar.update(1))))
        n_tri = max(sum(count_primitives(m)[0] for m in scenes[i]) for i in shown)
        if spec is not None:
            for name in list(spec.by_material) + ([""] if spec.everything else []):
                if name not in spec.used:
                    raise InputError(
                        f"--texture {name + '=' if name else ''}...: expected "
                        + (f"faces of material {name!r} (usemtl) in an input" if name else
                           "an input with 'vt' texture coordinates") + ", found none")
        if all(sum(sum(count_primitives(m)) for m in scenes[i]) == 0 for i in framed):
            raise InputError(f"{layers[0].source}: nothing to draw (no faces and no 'l' polylines)")
        camera = auto_camera(
            [scenes[i] for i in framed], options, view=job.view, azimuth=job.azimuth, elevation=job.elevation,
            up_axis=job.up_axis, fov=job.fov, ortho=job.ortho, zoom=job.zoom, margin=job.margin,
        )
        if fcc_camera is not None:
            if job.view is not None or job.azimuth is not None or job.elevation is not None:
                if fcc_camera.light_position is not None:  # an explicit view keeps the automatic camera
                    camera = camera.with_light(fcc_camera.light_position)
            else:
                try:
                    camera = camera_from_fcc(fcc_camera, camera)
                except ValueError as exc:  # e.g. camera up along the view direction
                    raise InputError(f"{job.fcc}: {exc}") from None

        def images():
            with progress(length=len(shown), label="rendering", quiet=job.quiet or len(shown) < 3) as bar:
                for i in shown:
                    yield renderer.render(scenes[i], camera, options)
                    bar.update(1)

        w, h = options.size
        if kind == "still":
            write_png(job.output, next(images()))
            what = f"{w}x{h}, frame {shown[0] + 1} of {n}"
        elif kind == "sheet":
            tiles = list(images())
            labels = [format_label(job.label_format, i + 1, i, reader.file_stem(i)) for i in shown] \
                if job.label_format else None
            sheet = contact_sheet(tiles, labels, columns=job.columns, background=options.background,
                                  title=job.title)
            write_png(job.output, sheet)
            what = f"{sheet.shape[1]}x{sheet.shape[0]} sheet of {len(shown)} frames"
        elif kind == "gif":
            count = write_gif(job.output, images(), job.fps)
            what = f"{w}x{h}, {count} frames at {job.fps:g} fps"
        else:
            count = write_mp4(job.output, images(), job.fps)
            what = f"{w}x{h}, {count} frames at {job.fps:g} fps"
    finally:
        renderer.release()
    return f"wrote {job.output} ({what}, {n_tri:,} triangles, {time.perf_counter() - t0:.2f} s)"
