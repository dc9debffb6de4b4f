"""The inputs of ``canopy-export``: named parts, each an OBJ sequence (or one static OBJ file).

A part is given as ``[NAME=]PATH``: a folder of OBJ frames, a quoted glob, or one OBJ file (a
static part, the same in every frame). Without ``NAME=`` the part is named after its folder (or
the file's stem). Every sequence exported together must have the same number of frames; frame
*k* of each (0-based, in natural file order) is frame *k* of the export, whatever the files are
called (``frame_0000.obj`` ... or ``1.obj`` ...).

:func:`iter_frames` reads the frames one at a time and checks each part's topology as it goes: a
frame may change the faces (florets emerging, branches growing) and with them the vertex count,
but a frame with the previous frame's faces must also have its vertex count (vertex *k* is the
same point in every frame, formats/obj.md). Sequences follow fccompose's rules: numbered without a gap,
no empty frame file; coordinates must fit float32.
"""
from __future__ import annotations

import os
import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from inflo.formats.atomic import first_missing_frame
from inflo.formats.errors import FormatError, InputError
from inflo.formats.obj import ObjMesh, list_obj_sequence, read_obj

__all__ = ["Part", "prim_name", "parse_part", "resolve_parts", "check_sequence", "check_coordinates",
           "frame_count", "iter_frames"]


@dataclass
class Part:
    """One exported mesh: its prim name, its source as given, its OBJ files in frame order."""

    name: str
    source: str
    paths: list[Path]

    @property
    def is_static(self) -> bool:
        """One file: the same mesh in every frame."""
        return len(self.paths) == 1 and os.path.isfile(self.source)

    def path(self, frame: int) -> Path:
        return self.paths[0] if self.is_static else self.paths[frame]


_NOT_IDENT = re.compile(r"[^A-Za-z0-9_]")


def prim_name(text: str) -> str:
    """A USD prim name (an identifier: letters, digits, ``_``, not starting with a digit) from ``text``."""
    name = _NOT_IDENT.sub("_", text.strip()) or "_"
    return "_" + name if name[0].isdigit() else name


def parse_part(spec: str) -> tuple[str | None, str]:
    """``"NAME=PATH"`` -> (NAME, PATH); ``"PATH"`` -> (None, PATH). A spec that exists as a path
    is a path even if it contains ``=``."""
    if "=" in spec and not os.path.exists(spec):
        name, path = spec.split("=", 1)
        if not name.strip():
            raise InputError(f"{spec}: expected NAME=PATH or PATH, found an empty name")
        return name.strip(), path
    return None, spec


def _default_name(source: str) -> str:
    p = Path(source.rstrip("/\\") or source)
    if os.path.isfile(source):
        return p.stem
    if os.path.isdir(source):
        return p.name
    # a glob: the last folder without a wildcard, else the pattern's leading text
    for parent in [p.parent, *p.parent.parents]:
        if parent.name and not any(c in parent.name for c in "*?["):
            return parent.name
    return re.split(r"[*?\[]", p.name)[0] or "part"


def resolve_parts(specs: Sequence[str]) -> list[Part]:
    """The parts of the command-line inputs, with unique prim names.

    Raises
    ------
    InputError
        No input; a missing file or folder, a folder without OBJ files, a glob matching nothing;
        two parts with the same name.
    """
    if not specs:
        raise InputError("no input: give one or more OBJ sequences (folders or globs) or OBJ files")
    parts, seen = [], {}
    for spec in specs:
        name, source = parse_part(spec)
        paths = list_obj_sequence(source)
        check_sequence(spec, paths)
        pname = prim_name(name if name is not None else _default_name(source))
        if pname in seen:
            raise InputError(f"{spec}: expected a part name of its own, found {pname!r} again (named after "
                             f"{seen[pname]!r}); name the parts: NAME=PATH")
        seen[pname] = spec
        parts.append(Part(name=pname, source=source, paths=paths))
    return parts


def check_sequence(spec: str, paths: Sequence[Path]) -> None:
    """The sequence rules fccompose keeps for its OBJ sequences: numbered frames without a gap (a
    missing frame would re-time the animation) and no empty (0-byte) frame file.

    Raises
    ------
    InputError
        Naming the first missing frame or the empty file.
    """
    gap = first_missing_frame(paths)
    if gap is not None:
        raise InputError(f"{spec}: expected an OBJ sequence without a gap (a missing frame would re-time the "
                         f"animation), found {gap} missing")
    for p in paths:
        try:
            empty = os.path.getsize(p) == 0
        except OSError as exc:
            raise InputError(f"{p}: expected a readable OBJ file, found {exc.strerror or exc}") from None
        if empty:
            raise InputError(f"{p}: expected an OBJ frame, found an empty (0-byte) file")


_F32_MAX = float(np.finfo(np.float32).max)


def check_coordinates(path, mesh: ObjMesh) -> None:
    """Refuse coordinates that float32 (USD's points, glTF's positions) cannot hold: they would be
    written as ``inf``."""
    v = np.asarray(mesh.vertices, dtype=np.float64)
    ok = np.isfinite(v).all(axis=1) & (np.abs(v) <= _F32_MAX).all(axis=1)
    if not ok.all():
        i = int(np.flatnonzero(~ok)[0])
        raise FormatError(path, None, f"vertex coordinates within float32's range (|x| <= {_F32_MAX:.4g})",
                          f"vertex {i + 1} at ({', '.join(f'{c:g}' for c in v[i])})")


def frame_count(parts: Sequence[Part]) -> int:
    """Frames of the export: the length of the sequences (1 when every part is a single file).

    Raises
    ------
    InputError
        When two sequences differ in length.
    """
    seqs = [p for p in parts if not p.is_static]
    if not seqs:
        return 1
    first = seqs[0]
    for p in seqs[1:]:
        if len(p.paths) != len(first.paths):
            raise InputError(
                f"{p.source}: expected {len(first.paths)} frames as in {first.source}, found {len(p.paths)}; "
                f"parts exported together need the same number of frames (a single OBJ file is a static part)"
            )
    return len(first.paths)


def _check_topology(part: Part, frame: int, mesh: ObjMesh, prev: ObjMesh, first: ObjMesh,
                    constant_topology: bool) -> bool:
    """Whether ``mesh`` (frame ``frame``) changes the faces of ``prev``; raises on bad input."""
    same_faces = np.array_equal(mesh.faces, prev.faces)
    path = part.path(frame)
    if constant_topology and not (same_faces and mesh.n_vertices == first.n_vertices):
        what = (f"{first.n_vertices} vertices" if mesh.n_vertices != first.n_vertices
                else f"the {first.n_faces} faces")
        found = str(mesh.n_vertices) if mesh.n_vertices != first.n_vertices else "other faces"
        raise FormatError(path, None, f"{what} of {part.paths[0].name} (constant topology)", found)
    if same_faces and mesh.n_vertices != prev.n_vertices:
        # vertex k is the same point in every frame (formats/obj.md): a frame with its predecessor's
        # faces has its vertices too; one whose faces change may add or drop vertices (branches
        # that grow: branch-gen's frames, time-sampled points in USD, padded in a .glb)
        raise FormatError(path, None, f"{prev.n_vertices} vertices as in {part.path(frame - 1).name} (the same "
                          "faces; vertex k is the same point in every frame)", str(mesh.n_vertices))
    return not same_faces


def iter_frames(parts: Sequence[Part], n_frames: int, *, constant_topology: bool = False
                ) -> Iterator[tuple[int, list[ObjMesh | None], list[bool]]]:
    """Read the export frame by frame.

    Yields
    ------
    frame : int
        0-based frame index.
    meshes : list of ObjMesh or None
        One per part; None for a static part after frame 0 (its mesh does not change).
    changed : list of bool
        Per part: the faces or the per-face materials differ from the previous frame (always
        True at frame 0); also where only the faces' groups changed.

    Raises
    ------
    FormatError
        A malformed OBJ; a frame with its predecessor's faces but another vertex count; with
        ``constant_topology``, any frame whose faces or vertex count differ from the first's.
    """
    prev: list[ObjMesh | None] = [None] * len(parts)
    first: list[ObjMesh | None] = [None] * len(parts)
    prev_key: list[tuple] = [()] * len(parts)  # _face_materials(prev[i])
    for k in range(n_frames):
        meshes, changed = [], []
        read: dict[Path, ObjMesh] = {}  # parts drawn from one file (a column placed beside three flowers) read it once
        for i, part in enumerate(parts):
            if part.is_static and k > 0:
                meshes.append(None)
                changed.append(False)
                continue
            path = part.path(k)
            if path not in read:
                read[path] = read_obj(path)
                check_coordinates(path, read[path])
            mesh = read[path]
            key = _face_materials(mesh)
            if prev[i] is None:
                first[i] = mesh
                change = True
            else:
                change = _check_topology(part, k, mesh, prev[i], first[i], constant_topology)
                change = change or key != prev_key[i]
            meshes.append(mesh)
            changed.append(change)
            prev[i], prev_key[i] = mesh, key
        yield k, meshes, changed


def _face_materials(mesh: ObjMesh) -> tuple:
    """A comparable key of which material and group each face has (names and indices)."""
    mat = () if mesh.face_material is None else (tuple(mesh.materials), mesh.face_material.tobytes())
    grp = () if mesh.face_group is None else (tuple(mesh.groups), mesh.face_group.tobytes())
    return mat, grp
