"""The ``.fcc`` writer: :func:`format_fcc` and :func:`write_fcc`, every key in a fixed order, numbers
as the shortest text that reads back to the same float64.
"""
from __future__ import annotations

import math

from ._fccparams import CanopyParams
from .atomic import write_text_atomic


def _num(x: float) -> str:
    """Shortest text that reads back as the same float64 (Python's ``repr``)."""
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"cannot write a non-finite number ({x!r}) to a .fcc file")
    return repr(x)


def _vec(values) -> str:
    return ", ".join(_num(x) for x in values)


def _check_raw(raw: str, key: str, *, no_space: bool = False) -> str:
    bad = "#\n\r" + (" \t," if no_space else "")
    if not raw or raw != raw.strip() or any(c in raw for c in bad):
        raise ValueError(
            f"cannot write path {raw!r} for '{key}': it must be non-empty, without surrounding "
            f"blanks, '#' or line breaks" + (", spaces or commas" if no_space else "")
        )
    return raw


def _bool(b: bool) -> str:
    return "true" if b else "false"


def format_fcc(params: CanopyParams) -> str:
    """The text :func:`write_fcc` writes: every key in a fixed order, unset ones as comments.

    Numbers are written as the shortest text that reads back to the same float64 (``repr``), so
    write -> read -> write is byte-identical.
    """
    p = params
    out: list[str] = [
        "# inflo canopy composer parameters (thesis app. C.1); spec: formats/fcc.md",
        "",
    ]
    add = out.append

    def opt(key: str, value: str | None, unset: str):
        add(f"{key}: {value}" if value is not None else f"# {key}: {unset}")

    add("# constraints")
    add(f"solver iterations: {int(p.solver_iterations)}")
    add(f"collision solver iterations: {int(p.collision_iterations)}")
    add(f"max collision retries: {int(p.max_collision_retries)}")
    add(f"kStretch: {_num(p.k_stretch)}")
    add(f"kBend: {_num(p.k_bend)}")
    add(f"kCollision: {_num(p.k_collision)}")
    add(f"spacing: {_num(p.spacing)}")
    add("")
    add("# simulation")
    add(f"scene scale factor: {_vec(p.scene_scale)}")
    add(f"updates per frame: {int(p.updates_per_frame)}")
    opt("run for number of frames",
        None if p.run_frames is None else str(int(p.run_frames)), "all frames")
    add(f"sanity check per frames: {int(p.sanity_check_every)}")
    add(f"max substeps: {int(p.max_substeps)}")
    add(f"edge stretch bounds: {_num(p.stretch_bounds[0])} {_num(p.stretch_bounds[1])}")
    add(f"relax iterations: {int(p.relax_iterations)}")
    add(f"solver scheme: {p.solver_scheme}")
    add(f"collisions: {_bool(p.collisions)}")
    add("emergence scales: " + " ".join(_num(x) for x in p.emergence_scales))
    add(f"emergence growth frames: {_num(p.emergence_growth_frames)}")
    add("crowded scales: " + " ".join(_num(x) for x in p.crowded_scales))
    opt("output animation frames number",
        None if p.output_frames_number is None else str(int(p.output_frames_number)), "not set")
    opt("output animation obj per frames",
        None if p.output_obj_skip is None else str(int(p.output_obj_skip)), "not set")
    add("")
    add("# collision lattice")
    lat = p.lattice
    add(f"lattice size multiply: {_vec(lat.size_multiply)}")
    add(f"lattice make cube: {_bool(lat.make_cube)}")
    add(f"origin: {_vec(lat.origin)}")
    add(f"divisions: {', '.join(str(int(d)) for d in lat.divisions)}")
    add(f"dimensions: {_vec(lat.dimensions)}")
    add(f"lattice auto bounds: {_bool(lat.auto_bounds)}")
    add("")
    add("# files")
    opt("color map file location",
        None if p.color_map is None else _check_raw(p.color_map.raw, "color map file location"),
        "none")
    opt("material map file location",
        None if p.material_map is None
        else _check_raw(p.material_map.raw, "material map file location"),
        "none")
    if not p.scene_files:
        add("# scene file path: none")
    for f in p.scene_files:
        add(f"scene file path: {_check_raw(f.raw, 'scene file path')}")
    for e in p.animations:
        add(f"{e.kind}: {int(e.id)} {' '.join(_num(s) for s in e.scale)} "
            f"{_check_raw(e.path.raw, e.kind)}")
    for r in p.rigid_body_animations:
        key = "rigid body animation"
        add(f"{key}: {int(r.id)} {' '.join(_num(s) for s in r.scale)} "
            f"{_check_raw(r.rba_folder.raw, key, no_space=True)} "
            f"{_check_raw(r.scene_path.raw, key, no_space=True)}")
    for id_ in sorted(p.weights):
        add(f"weight: {int(id_)} {_check_raw(p.weights[id_].raw, 'weight')}")
    for id_ in sorted(p.petal_weights):
        add(f"petal weight: {int(id_)} {_check_raw(p.petal_weights[id_].raw, 'petal weight')}")
    for id_ in sorted(p.petal_ramps):
        lo, hi = p.petal_ramps[id_]
        add(f"petal ramp: {int(id_)} {_num(lo)} {_num(hi)}")
    for id_ in sorted(p.bending_stiffness):
        add(f"bending stiffness: {int(id_)} {_num(p.bending_stiffness[id_])}")
    for id_ in sorted(p.distance_stiffness):
        add(f"distance stiffness: {int(id_)} {_num(p.distance_stiffness[id_])}")
    for id_ in sorted(p.variations):
        add(f"variation: {int(id_)} {p.variations[id_].text()}")
    opt("animation output folder location",
        None if p.animation_output_folder is None
        else _check_raw(p.animation_output_folder.raw, "animation output folder location"),
        "none (fccompose -o)")
    opt("obj output file path",
        None if p.obj_output_file is None
        else _check_raw(p.obj_output_file.raw, "obj output file path"),
        "none")
    add("")
    add("# viewer: camera and light (canopy-render)")
    c = p.camera
    opt("camera position", None if c.position is None else _vec(c.position), "automatic")
    add(f"camera up: {_vec(c.up)}")
    opt("camera lookat", None if c.lookat is None else _vec(c.lookat), "automatic")
    add(f"camera pan speed: {_num(c.pan_speed)}")
    add(f"camera zoom speed: {_num(c.zoom_speed)}")
    add(f"camera rotate speed: {_num(c.rotate_speed)}")
    opt("near plane", None if c.near is None else _num(c.near), "automatic")
    opt("far plane", None if c.far is None else _num(c.far), "automatic")
    add(f"camera fov: {_num(c.fov_deg)}")
    opt("light position",
        None if c.light_position is None else _vec(c.light_position), "automatic")
    opt("shadow frustrum",
        None if c.shadow_frustum is None else _vec(c.shadow_frustum), "none")
    return "\n".join(out) + "\n"


def write_fcc(path, params: CanopyParams) -> None:
    """Write ``params`` to ``path`` atomically (see :func:`format_fcc` for the layout).

    Paths are written as their ``raw`` text, so they stay relative to the folder of the file they
    came from; write next to the original (or rebuild the :class:`FilePath` values) to keep them
    pointing at the same files. Raises ValueError for a value the format cannot carry (a path with
    ``#`` or a line break, a non-finite number).
    """
    write_text_atomic(path, format_fcc(params))
