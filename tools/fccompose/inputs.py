"""The files a ``.fcc`` names, read for the model (:func:`load_inputs`): SCN files, RBA folders, and
each ``animation``/``obj`` entry's OBJs and weight files as a :class:`~.system.Template`, read on
its first lookup. :func:`~.assemble.assemble_model` reads no files.
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

from inflo.formats.atomic import first_missing_frame
from inflo.formats.errors import FormatError, InputError
from inflo.formats.fcc import CanopyParams
from inflo.formats.obj import read_obj, read_obj_sequence
from inflo.formats.rba import read_rba_sequence
from inflo.formats.scn import read_scn
from inflo.formats.weights import read_petal_weight_file, read_weight_file

from .system import Template


def coincident_vertices(frames: np.ndarray, faces: np.ndarray):
    """The first frame and pair of distinct vertices (0-based, both used by triangles) at exactly the
    same point, or None (as in a template with a duplicated, unwelded vertex).

    Zero-area triangles whose corners are distinct points (collinear corners, slivers) are accepted:
    the collision core treats them as their longest edge. Coincident distinct vertices are not:
    the triangles around them touch, so the exact test of the first frame would refuse the canopy
    anyway, naming only florets.
    """
    used = np.unique(np.asarray(faces).ravel())
    for k in range(frames.shape[0]):
        x = frames[k, used]
        _, first, inverse, counts = np.unique(x, axis=0, return_index=True, return_inverse=True, return_counts=True)
        if np.any(counts > 1):
            g = int(np.argmax(counts > 1))
            pair = np.sort(used[np.flatnonzero(inverse.ravel() == g)[:2]])
            return k, int(pair[0]), int(pair[1])
    return None


def _load_template(params: CanopyParams, entry) -> Template:
    if entry.kind == "obj":
        mesh = read_obj(entry.path.resolved)
        frames = mesh.vertices[None]
    else:
        paths, meshes = read_obj_sequence(entry.path.resolved)
        gap = first_missing_frame(paths)
        if gap is not None:
            raise FormatError(params.source, entry.line, f"an OBJ sequence without a gap in {entry.path.raw} (a "
                              "missing frame would re-time the animation)", f"{gap} missing")
        frames = np.stack([m.vertices for m in meshes])
        mesh = meshes[0]
    faces = mesh.faces
    if len(faces) == 0:
        raise FormatError(entry.path.resolved, None, "triangles (f lines)", "none")
    bad = coincident_vertices(frames, faces)
    if bad is not None:
        k, i, j = bad
        where = entry.path.resolved if entry.kind == "obj" else paths[k]
        raise FormatError(where, None, "distinct points for distinct vertices of the triangles (the triangles at two "
                          "coincident vertices touch, which no collision-free canopy allows: weld them into one "
                          "vertex or move them apart)", f"vertices {i + 1} and {j + 1} at the same point "
                          f"({' '.join(f'{c:g}' for c in frames[k, i])})")
    frames = frames * np.asarray(entry.scale, float)
    nv = frames.shape[1]
    fixed = None
    if entry.id in params.weights:
        fixed = read_weight_file(params.weights[entry.id].resolved, nv)
    k_stretch, k_bend = params.stiffness(entry.id)
    t = Template.from_frames(entry.id, frames, faces, fixed=fixed, k_stretch=k_stretch, k_bend=k_bend,
                             source=str(entry.path.raw), materials=mesh.materials,
                             face_material=mesh.face_material)
    if entry.id in params.petal_weights:
        t.petal_weight = read_petal_weight_file(params.petal_weights[entry.id].resolved, nv)
        t.petal_ramp = params.petal_ramps.get(entry.id)
    return t


class RbaSequence(NamedTuple):
    """One ``rigid body animation`` entry's RBA files, read against its scene."""

    paths: list
    """the RBA files, in frame order"""
    frames: list
    """their :class:`~inflo.formats.rba.RbaFrame` objects"""
    scale: np.ndarray
    """(3,) the entry's scale, multiplying every RBA row's"""


class Inputs(NamedTuple):
    """What :func:`load_inputs` read for :func:`assemble_model`."""

    scenes: dict
    """scene path -> :class:`~inflo.formats.scn.Scene`, in the order the florets are numbered"""
    templates: Mapping
    """animation/obj id -> :class:`Template`, iterated in the ``.fcc``'s entry order"""
    rbas: dict
    """scene path -> :class:`RbaSequence` of the scenes with a ``rigid body animation`` line"""


class _TemplateFiles(Mapping):
    """The ``animation``/``obj`` entries of a ``.fcc`` as id -> :class:`Template`, each read from
    its files on its first lookup: only placed templates are read, in placement order (so the
    first bad file named is the first a placement needs). Iterates over the ids in entry order."""

    def __init__(self, params: CanopyParams):
        self._params = params
        self._entries = {e.id: e for e in params.animations}
        self._read: dict = {}

    def __contains__(self, id) -> bool:
        return id in self._entries

    def __getitem__(self, id) -> Template:
        if id not in self._read:
            self._read[id] = _load_template(self._params, self._entries[id])
        return self._read[id]

    def __iter__(self):
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)


def load_inputs(params: CanopyParams) -> Inputs:
    """Read the SCN files and RBA folders ``params`` names; the OBJ sequences, OBJs and weight
    files of its entries are read as :func:`assemble_model` looks their templates up.

    Raises
    ------
    FormatError, InputError
        Unreadable or malformed inputs; no scene file; a second ``rigid body animation`` line for
        a scene; an RBA folder without RBA files; an RBA id that is not an ``rba:`` placement of
        its scene.
    """
    if not params.scene_files and not params.rigid_body_animations:
        raise InputError(f"{params.source}: expected at least one 'scene file path', found none")

    # scene files (listed ones first, then those only named by rigid body animation lines)
    scene_paths = [f.resolved for f in params.scene_files]
    for r in params.rigid_body_animations:
        if r.scene_path.resolved not in scene_paths:
            scene_paths.append(r.scene_path.resolved)
    scenes = {p: read_scn(p) for p in scene_paths}
    rbas = {}
    for r in params.rigid_body_animations:
        sp = r.scene_path.resolved
        if sp in rbas:
            raise FormatError(params.source, r.line, "one 'rigid body animation' line per scene file",
                              f"a second one for {r.scene_path.raw}")
        paths, frames = read_rba_sequence(r.rba_folder.resolved, scenes[sp])
        if not paths:
            raise FormatError(params.source, r.line, "a folder with RBA files", f"none in {r.rba_folder.raw}")
        gap = first_missing_frame(paths, start=0)
        if gap is not None:
            raise FormatError(params.source, r.line, f"RBA files numbered from 0 without a gap (file NNNN is frame "
                              f"NNNN) in {r.rba_folder.raw}", f"{gap} missing")
        for k in range(1, len(frames)):
            # placements do not vanish: an empty (0-byte) file after a frame with placements is a
            # truncated frame, which would make its florets emerge a frame late
            if len(frames[k]) == 0 and len(frames[k - 1]) > 0 and paths[k].stat().st_size == 0:
                raise FormatError(paths[k], None, f"the placements of the frame before ({len(frames[k - 1])}) "
                                  "or more", "an empty file (a truncated frame?)")
        rbas[sp] = RbaSequence(paths, frames, np.asarray(r.scale, float))
    return Inputs(scenes, _TemplateFiles(params), rbas)
