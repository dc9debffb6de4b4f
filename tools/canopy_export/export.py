"""``canopy-export`` as a library function: OBJ sequences + colours -> one USD file (+ PC2 caches).

:func:`export_canopy` reads the parts frame by frame (:mod:`.parts`), fills a USD stage in memory
(:mod:`.usd`) and writes it once at the end, atomically, so bad input (found while reading any
frame) leaves no output file. With ``pc2_dir`` it also writes one PC2 point cache per animated
part (formats/pc2.md), for parts whose faces and vertex count never change.
"""
from __future__ import annotations

import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from inflo.formats.atomic import check_output_path, refuse_output_over_inputs
from inflo.formats.errors import InputError
from inflo.formats.obj import MTL_NAME, write_mtl
from inflo.formats.pc2 import write_pc2

from .parts import Part, frame_count, iter_frames, prim_name

__all__ = ["ExportOptions", "ExportReport", "export_canopy", "check_mtl_targets", "UNITS", "parse_units"]

UNITS: dict[str, float] = {"m": 1.0, "dm": 0.1, "cm": 0.01, "mm": 0.001, "in": 0.0254, "ft": 0.3048}
"""Unit names accepted by ``--units`` and their metres per unit."""


def parse_units(text: str) -> float:
    """Metres per unit from a unit name of :data:`UNITS` or a positive number (metres per unit)."""
    key = str(text).strip().lower()
    if key in UNITS:
        return UNITS[key]
    try:
        value = float(key)
    except ValueError:
        value = float("nan")
    if not np.isfinite(value) or value <= 0:
        raise ValueError(f"expected a unit ({', '.join(UNITS)}) or metres per unit (a positive number), "
                         f"found {text!r}")
    return value


@dataclass
class ExportOptions:
    """How the export is written.

    Attributes
    ----------
    fps : float
        Frames (time codes) per second.
    start_frame : int
        The time code of the first frame (Blender's first frame is 1).
    meters_per_unit : float
        The stage's ``metersPerUnit``: inflo's lily is about 15 units across, a flower of 15 cm, so
        the default is 0.01 (one unit is a centimetre).
    normals : bool
        Write per-vertex normals (the OBJ's own, else area-weighted ones), time-sampled.
    constant_topology : bool
        Fail (bad input) when any frame's faces or vertex count differ from the first frame's.
    subsets : str
        ``"material"``: one GeomSubset per OBJ material of a part (bound to it); ``"floret"``:
        also one per OBJ group (a floret of a canopy), family ``floret``, bound to nothing.
    mtl : bool
        Also write ``materials.mtl`` (the name the OBJ frames' ``mtllib`` gives) beside each
        part's OBJ files: its materials with ``Kd`` the colour file's colour, linear.
    translate : dict
        Part name -> (x, y, z): the part's Mesh prim is moved by this (an ``xformOp:translate``;
        its points stay as in the OBJ files), e.g. to stand flowers built at one place side by side.
    """

    fps: float = 24.0
    start_frame: int = 1
    meters_per_unit: float = 0.01
    normals: bool = False
    constant_topology: bool = False
    subsets: str = "material"
    mtl: bool = False
    translate: dict = field(default_factory=dict)
    quantize: bool = True
    """glTF only: positions and morph deltas as normalized 16-bit integers (KHR_mesh_quantization)."""
    extras: dict = field(default_factory=dict)
    """glTF only: written as the scene's extras (the viewer page's title and figures)."""


MTL_HEADER = ("canopy-export: the materials of the OBJ files in this folder, Kd in linear RGB "
              "(formats/obj.md)")


def check_mtl_targets(folders) -> None:
    """Refuse to replace a ``materials.mtl`` that canopy-export did not write (a hand-written one is
    an input of the OBJ files, never an output); checked before anything is written."""
    for folder in folders:
        target = Path(folder) / MTL_NAME
        if not target.exists():
            continue
        try:
            with open(target, encoding="utf-8", errors="replace") as fh:
                first = fh.readline()
        except OSError as exc:
            raise InputError(f"{target}: expected a materials.mtl canopy-export may replace, found it unreadable "
                             f"({exc.strerror or exc})") from None
        if not first.startswith("# " + MTL_HEADER.split(":")[0] + ":"):
            raise InputError(f"{target}: expected no materials.mtl or one canopy-export wrote (--mtl), found one "
                             f"written by hand or by another tool; it is kept: move it away or drop --mtl")


@dataclass
class ExportReport:
    """What :func:`export_canopy` wrote."""

    output: Path
    parts: list[str]
    n_frames: int
    start_frame: int
    fps: float
    topology_samples: dict[str, int]
    """Per part, how many face lists were written (1: constant topology)."""
    materials: list[str]
    n_bytes: int
    seconds: float
    pc2: list[Path] = field(default_factory=list)
    mtl: list[Path] = field(default_factory=list)
    polyline_parts: list[str] = field(default_factory=list)
    """Parts whose OBJ files have ``l`` polylines, which are not exported."""
    faces_not_hidden: int = 0
    """.glb: the most faces of one frame that are not in it yet could not be hidden (formats/gltf.md)."""

    def summary(self) -> str:
        topo = ", ".join(f"{p} {n} face list{'s' if n != 1 else ''}" for p, n in self.topology_samples.items())
        line = (f"{self.output}: {len(self.parts)} part{'s' if len(self.parts) != 1 else ''} ({topo}), "
                f"{self.n_frames} frames ({self.start_frame}-{self.start_frame + self.n_frames - 1} at "
                f"{self.fps:g} fps), {len(self.materials)} materials, {self.n_bytes / 1e6:.2f} MB, "
                f"{self.seconds:.1f} s")
        if self.pc2:
            line += f"; PC2: {', '.join(str(p) for p in self.pc2)}"
        if self.mtl:
            line += f"; MTL: {', '.join(str(p) for p in self.mtl)}"
        if self.polyline_parts:
            line += f"; polylines not exported ({', '.join(self.polyline_parts)})"
        if self.faces_not_hidden:
            line += (f"; up to {self.faces_not_hidden} faces a frame shown before they appear (they share vertices "
                     f"with faces of that frame)")
        return line


def _mtl_folders(parts: Sequence[Part], materials: Mapping[str, list]) -> dict[Path, list[str]]:
    """Per folder holding a part's OBJ files, the materials its parts use (order of appearance)."""
    out: dict[Path, list[str]] = {}
    for p in parts:
        names = out.setdefault(p.paths[0].parent, [])
        names.extend(n for n in materials[p.name] if n not in names)
    return {k: v for k, v in out.items() if v}


def export_canopy(parts: Sequence[Part], output, *, colors: Mapping[str, tuple] | None = None,
                  options: ExportOptions | None = None, pc2_dir=None,
                  on_frame: Callable[[int], None] | None = None) -> ExportReport:
    """Export the parts' OBJ sequences as one USD file.

    Parameters
    ----------
    parts : list of Part
        From :func:`.parts.resolve_parts`; sequences of equal length, or single files (static).
    output : path
        ``.usdc`` (binary), ``.usda`` (text) or ``.usd`` (binary).
    colors : mapping or None
        A colour table (:func:`inflo.formats.colors.load_color_file`): material key ->
        sRGB; material colours follow canopy-render's rules (the table, then the palette).
    options : ExportOptions
    pc2_dir : path or None
        Also write ``pc2_dir/<part>.pc2`` for each animated part (fixed topology required).
    on_frame : callable or None
        Called with the 0-based frame index after each frame is read.

    Raises
    ------
    InputError
        Bad input (missing files, malformed OBJ, sequences of different lengths, a vertex count
        that changes where the faces do not, a changing topology with ``constant_topology`` or a
        PC2 cache); nothing is written then.
    """
    from inflo.formats.colors import INPUT_PALETTE, material_color

    from .gltf import GLTF_SUFFIXES, GltfBuilder
    from .usd import USD_SUFFIXES, UsdBuilder, srgb_to_linear

    t0 = time.perf_counter()
    opts = options or ExportOptions()
    output = Path(output)
    if output.suffix.lower() not in USD_SUFFIXES + GLTF_SUFFIXES:
        raise InputError(f"{output}: expected an output name ending {', '.join(USD_SUFFIXES + GLTF_SUFFIXES)}, "
                         f"found {output.suffix or 'no suffix'!r}")
    if opts.fps is None or not np.isfinite(opts.fps) or opts.fps <= 0:
        raise InputError(f"--fps: expected a finite number above 0, found {opts.fps!r}")
    n_frames = frame_count(parts)
    table = dict(colors or {})
    unknown = sorted(set(opts.translate) - {p.name for p in parts})
    if unknown:
        raise InputError(f"--translate: no part named {unknown[0]!r}; expected one of {', '.join(p.name for p in parts)}")
    inputs = [(q, "OBJ frame") for p in parts for q in p.paths]
    check_output_path(output, folder=False)
    refuse_output_over_inputs(output, inputs, folder=False)
    if pc2_dir is not None:
        names = {f"{p.name}.pc2" for p in parts if not p.is_static}
        check_output_path(pc2_dir, folder=True)
        refuse_output_over_inputs(pc2_dir, inputs, option="--pc2", writes=lambda rel: rel in names)
    if opts.mtl:
        check_mtl_targets({p.paths[0].parent for p in parts})
    if output.suffix.lower() in GLTF_SUFFIXES:
        builder = GltfBuilder(
            prim_name(output.stem), [p.name for p in parts], [p.is_static for p in parts],
            material_color=lambda name: material_color(name, table),
            default_colors=[INPUT_PALETTE[i % len(INPUT_PALETTE)] for i in range(len(parts))],
            n_frames=n_frames, fps=opts.fps, start_frame=opts.start_frame, meters_per_unit=opts.meters_per_unit,
            quantize=opts.quantize, extras=opts.extras, translate=opts.translate)
    else:
        builder = UsdBuilder(
            prim_name(output.stem), [p.name for p in parts], [p.is_static for p in parts],
            material_color=lambda name: material_color(name, table),
            default_colors=[INPUT_PALETTE[i % len(INPUT_PALETTE)] for i in range(len(parts))],
            n_frames=n_frames, start_frame=opts.start_frame, fps=opts.fps,
            meters_per_unit=opts.meters_per_unit, normals=opts.normals, subsets=opts.subsets,
            translate=opts.translate,
        )
    caches = {p.name: [] for p in parts if not p.is_static} if pc2_dir is not None else {}
    topology = {p.name: 0 for p in parts}
    polylines = set()
    part_materials: dict[str, list[str]] = {p.name: [] for p in parts}
    for k, meshes, changed in iter_frames(parts, n_frames, constant_topology=opts.constant_topology):
        builder.add_frame(k, meshes, changed)
        for part, mesh, change in zip(parts, meshes, changed):
            if mesh is None:
                continue
            topology[part.name] += int(change)
            if mesh.lines:
                polylines.add(part.name)
            if change:
                part_materials[part.name].extend(n for n in mesh.materials if n not in part_materials[part.name])
            if part.name in caches:
                if change and k > 0:
                    raise InputError(
                        f"{part.path(k)}: expected the faces of {part.paths[0].name} for a PC2 point cache "
                        f"(--pc2 needs a fixed topology), found other faces or materials")
                caches[part.name].append(np.asarray(mesh.vertices, dtype=np.float32))
        if on_frame is not None:
            on_frame(k)
    builder.save(output)
    written = []
    for name, frames in caches.items():
        target = Path(pc2_dir) / f"{name}.pc2"
        write_pc2(target, np.stack(frames), start_frame=opts.start_frame)
        written.append(target)
    mtl_files = []
    if opts.mtl:
        for folder, names in _mtl_folders(parts, part_materials).items():
            target = folder / MTL_NAME
            write_mtl(target, {n: srgb_to_linear(material_color(n, table)) for n in names},
                      header=MTL_HEADER)
            mtl_files.append(target)
    return ExportReport(
        output=output, parts=[p.name for p in parts], n_frames=n_frames, start_frame=opts.start_frame,
        fps=opts.fps, topology_samples=topology, materials=builder.material_names,
        n_bytes=os.path.getsize(output), seconds=time.perf_counter() - t0, pc2=written, mtl=mtl_files,
        polyline_parts=[p.name for p in parts if p.name in polylines],
        faces_not_hidden=getattr(builder, "faces_not_hidden", 0),
    )
