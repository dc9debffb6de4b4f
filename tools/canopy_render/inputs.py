"""The inputs of ``canopy-render``: OBJ files and OBJ sequences drawn together, frame by frame.

Each input is a *layer*: an OBJ file (drawn in every frame), or a sequence (a folder or a glob of
OBJ files, docs/architecture.md "Sequences") that gives the layer's mesh in each frame. All sequences
drawn together must have the same number of frames. Frames are read once; consecutive frames of a
layer with the same topology share their face, material and polyline arrays, so a long sequence
costs little more memory than its vertex positions.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from inflo.formats.errors import InputError
from inflo.formats.obj import ObjMesh, list_obj_sequence, read_obj

MAX_COORDINATE = 1e15
"""Largest coordinate canopy-render frames (the camera fit squares coordinates: 1e308 overflowed)."""

__all__ = ["Layer", "resolve_inputs", "sequence_length", "FrameReader", "count_primitives"]


@dataclass
class Layer:
    """One input: its name as given and its OBJ files in frame order (one file: static)."""

    source: str
    paths: list[Path]

    @property
    def is_static(self) -> bool:
        return len(self.paths) == 1

    def path(self, frame: int) -> Path:
        """The file of 0-based ``frame`` (the only file of a static layer)."""
        return self.paths[0] if self.is_static else self.paths[frame]


def resolve_inputs(inputs: Sequence[str], *, as_sequence: bool = False) -> list[Layer]:
    """Layers of the command-line inputs.

    Parameters
    ----------
    inputs : list of str
        OBJ files, folders of OBJ files, or glob patterns.
    as_sequence : bool
        Treat all inputs, in order, as the frames of one sequence (what a shell-expanded glob
        ``frames/*.obj`` gives).

    Raises
    ------
    InputError
        A missing file or folder, a folder without OBJ files, a pattern that matches nothing.
    """
    if not inputs:
        raise InputError("no input: give an OBJ file, a folder of OBJ frames or a glob")
    if as_sequence:
        paths = []
        for src in inputs:
            paths.extend(list_obj_sequence(src))
        return [Layer(source=f"{inputs[0]} ... ({len(paths)} files)" if len(inputs) > 1 else inputs[0], paths=paths)]
    return [Layer(source=src, paths=list_obj_sequence(src)) for src in inputs]


def sequence_length(layers: Sequence[Layer]) -> int:
    """Number of frames of the layers drawn together (1 when every layer is static).

    Raises
    ------
    InputError
        When two sequences differ in length.
    """
    lengths = {(l.source, len(l.paths)) for l in layers if not l.is_static}
    if not lengths:
        return 1
    first = next(l for l in layers if not l.is_static)
    for l in layers:
        if not l.is_static and len(l.paths) != len(first.paths):
            raise InputError(
                f"{l.source}: {len(l.paths)} frames, but {first.source} has {len(first.paths)}; sequences drawn "
                f"together need the same number of frames (a single OBJ file is drawn in every frame)"
            )
    return len(first.paths)


def count_primitives(mesh: ObjMesh) -> tuple[int, int]:
    """(triangles, polyline segments) of a mesh."""
    return len(mesh.faces), sum(max(len(l) - 1, 0) for l in mesh.lines)


def _share(prev: ObjMesh | None, cur: ObjMesh) -> ObjMesh:
    """``cur`` with ``prev``'s topology arrays when they are equal (saves memory over long sequences)."""
    if prev is None or prev.n_vertices != cur.n_vertices:
        return cur
    if np.array_equal(prev.faces, cur.faces):
        cur.faces = prev.faces
    if prev.face_material is not None and cur.face_material is not None and prev.materials == cur.materials \
            and np.array_equal(prev.face_material, cur.face_material):
        cur.face_material, cur.materials = prev.face_material, prev.materials
    if len(prev.lines) == len(cur.lines) and all(np.array_equal(a, b) for a, b in zip(prev.lines, cur.lines)):
        cur.lines = prev.lines
    return cur


class FrameReader:
    """Reads the scene (one mesh per layer) of any frame, each file once.

    Parameters
    ----------
    layers : list of Layer
    textures : .texture.TextureSpec or None
        Texture maps to apply to the meshes read (``--texture``, ``--mtl-textures``).
    """

    def __init__(self, layers: Sequence[Layer], textures=None):
        self.layers = list(layers)
        self.textures = textures  # a .texture.TextureSpec, or None
        self.n_frames = sequence_length(self.layers)
        self._cache: dict[tuple[int, int], ObjMesh] = {}
        self._last: dict[int, ObjMesh] = {}

    def _mesh(self, layer: int, frame: int) -> ObjMesh:
        lay = self.layers[layer]
        key = (layer, 0 if lay.is_static else frame)
        mesh = self._cache.get(key)
        if mesh is None:
            path = lay.path(frame)
            mesh = _share(self._last.get(layer), read_obj(path))
            if self.textures is not None and self.textures.active:
                from .texture import apply_textures

                mesh = apply_textures(mesh, path, self.textures)
            if len(mesh.vertices) and np.abs(mesh.vertices).max() > MAX_COORDINATE:
                raise InputError(f"{path}: expected coordinates within +-{MAX_COORDINATE:g} (a renderable scene), "
                                 f"found {float(np.abs(mesh.vertices).max()):g}")
            self._cache[key] = mesh
            self._last[layer] = mesh
        return mesh

    def scene(self, frame: int) -> list[ObjMesh]:
        """The meshes of 0-based ``frame``, one per layer."""
        if not 0 <= frame < self.n_frames:
            raise IndexError(f"frame index {frame} outside 0..{self.n_frames - 1}")
        return [self._mesh(i, frame) for i in range(len(self.layers))]

    def scenes(self, frames: Sequence[int], on_frame: Callable[[int], None] | None = None) -> list[list[ObjMesh]]:
        """The scenes of several frames, in the order given; ``on_frame(i)`` after each one is read."""
        out = []
        for f in frames:
            out.append(self.scene(f))
            if on_frame is not None:
                on_frame(f)
        return out

    def file_stem(self, frame: int) -> str:
        """The file name (without .obj) of the first sequence layer in ``frame`` (for labels)."""
        lay = next((l for l in self.layers if not l.is_static), self.layers[0])
        return lay.path(frame).stem
