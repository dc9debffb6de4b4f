"""Cycles pictures of inflo species through the Blender add-on (docs/blender/<species>.png).

Run with a Blender Python (``bpy`` as a module, ``.venv-blender/`` of ``make test-blender``) or
Blender itself::

    .venv-blender/bin/python blender/render_species.py [SPECIES ...] [--quality final] [-o docs/blender]
    blender -b -P blender/render_species.py -- lily --quality draft --samples 16 -o /tmp/pictures

For each species (default: every species of the project) it loads the add-on (``--zip
build/inflo_blender.zip`` installs and enables it as a user would; else from ``blender/``),
builds the species with ``bpy.ops.inflo.build`` where ``build/<species>`` is missing or of
another quality (``--no-build``: skip those), imports it with ``bpy.ops.inflo.import_build``
(camera and lights of the add-on) and renders the hero frame (species.toml ``hero`` of the
quality, else the last frame; ``--frame`` overrides) with Cycles on the CPU to
``<out>/<species>.png``. A species that fails is reported in one line and the others go on;
the exit status is 1 when any failed.
"""
import argparse
import os
import sys
import time
import tomllib
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


def _args(argv):
    p = argparse.ArgumentParser(prog="render_species.py", description=__doc__.splitlines()[0])
    p.add_argument("species", nargs="*", help="species names (default: every species of the project)")
    p.add_argument("--project", default=str(ROOT), help="the inflo repository [this one]")
    p.add_argument("--quality", choices=("draft", "final"), default="final")
    p.add_argument("-o", "--output", default=str(ROOT / "docs" / "blender"), help="folder of the PNGs")
    p.add_argument("--size", default="1280x960", help="WxH pixels [1280x960]")
    p.add_argument("--samples", type=int, default=128, help="Cycles samples [128]")
    p.add_argument("--frame", type=int, default=None, help="scene frame [the species' hero frame, else the last]")
    p.add_argument("--zip", default=None, help="install and enable this add-on zip (build/inflo_blender.zip)")
    p.add_argument("--no-build", action="store_true", help="skip species not built at this quality")
    p.add_argument("--transparent", action="store_true", help="film transparent (no sky behind)")
    p.add_argument("--view-transform", default="AgX", help="Blender's view transform [AgX]; Standard: colours as given")
    return p.parse_args(argv)


def load_addon(bpy, zip_path):
    if zip_path:
        bpy.ops.preferences.addon_install(filepath=str(Path(zip_path).resolve()), overwrite=True)
        bpy.ops.preferences.addon_enable(module="inflo_blender")
        return
    sys.path.insert(0, str(HERE))
    import inflo_blender

    if not hasattr(bpy.types.Scene, "inflo"):
        inflo_blender.register()
        return inflo_blender
    return None


def hero_frame(project: Path, species: str, quality: str):
    with open(project / "pipelines" / species / "species.toml", "rb") as fh:
        data = tomllib.load(fh)
    for table in (data.get(quality, {}), data.get("settings", {})):
        if isinstance(table.get("hero"), int):
            return table["hero"]
    return None


def render_one(bpy, args, project: Path, species: str) -> str:
    build = project / "build" / species
    q = build / "quality.txt"
    built = q.read_text().strip() if q.is_file() else None
    usd = build / f"{species}.usdc"
    t0 = time.perf_counter()
    if built != args.quality or not usd.is_file():
        if args.no_build:
            return f"skipped: build/{species} is {built or 'not built'}, not {args.quality}"
        bpy.ops.inflo.build(species=species, quality=args.quality, project=str(project), import_after=False)
    t_build = time.perf_counter() - t0
    bpy.ops.wm.read_homefile(use_empty=True)  # an empty scene; the add-on stays enabled (factory settings would not)
    scene = bpy.context.scene
    w, h = (int(v) for v in args.size.lower().split("x"))
    scene.render.resolution_x, scene.render.resolution_y = w, h
    scene.render.resolution_percentage = 100
    bpy.ops.inflo.import_build(directory=str(build))
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = args.samples
    scene.cycles.use_denoising = args.samples >= 32
    scene.render.film_transparent = args.transparent
    scene.view_settings.view_transform = args.view_transform
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGBA" if args.transparent else "RGB"
    frame = args.frame or hero_frame(project, species, args.quality) or scene.frame_end
    scene.frame_set(min(max(frame, scene.frame_start), scene.frame_end))
    out = Path(args.output) / f"{species}.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.stem}.part.png")
    scene.render.filepath = str(tmp)
    t1 = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    os.replace(tmp, out)
    return (f"{out} (frame {scene.frame_current}, {w}x{h}, {args.samples} samples; build {t_build:.0f} s, "
            f"render {time.perf_counter() - t1:.0f} s)")


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if "--" in argv:
        argv = argv[argv.index("--") + 1:]
    args = _args(argv)
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    registered = load_addon(bpy, args.zip)
    project = Path(args.project).resolve()
    names = args.species or sorted(p.parent.name for p in (project / "pipelines").glob("*/species.toml"))
    failed = 0
    for name in names:
        try:
            line = render_one(bpy, args, project, name)
        except (RuntimeError, OSError, ValueError) as exc:
            failed += 1
            line = f"failed: {str(exc).strip().splitlines()[-1] if str(exc).strip() else exc}"
        print(f"render_species: {name}: {line}", flush=True)
    if registered is not None:
        # bpy 4.5 as a module hangs at exit while a Python class it registered is still registered
        registered.unregister()
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
