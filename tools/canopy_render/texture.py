"""Texture maps for ``canopy-render``: OBJ ``vt`` coordinates, PNG images, ``.mtl`` ``map_Kd``.

``canopy-render --texture [MATERIAL=]IMAGE.png`` (repeatable) or ``--mtl-textures`` draws the
faces of a mesh with a colour image sampled at their uv coordinates instead of a flat colour
(e.g. the vein texture ``venation`` writes over its blade mesh, formats/venation.md). Without
either option nothing here runs and every picture is what it was.

- ``MATERIAL=IMAGE``: the faces after ``usemtl MATERIAL``, in every input that has such faces;
- ``IMAGE`` alone: every face of every input that has ``vt`` coordinates;
- ``--mtl-textures``: each input's ``mtllib`` files (beside the OBJ), ``newmtl NAME`` ...
  ``map_Kd FILE`` (options before the file name are skipped).

The OBJ reader of ``inflo.formats.obj`` skips ``vt``; :func:`read_texcoords` reads them and the
face corners' ``vt`` references, fan-triangulated exactly as :func:`inflo.formats.obj.read_obj`
does, so corner k of triangle j matches ``mesh.faces[j, k]``. A vertex used with one uv
everywhere keeps its index; one used with several (a seam) is copied once per further uv,
appended after the file's vertices (polylines keep their indices; the copies take the vertex's
normal and colour, so the shading across a seam is unchanged).

Images are RGBA; a texel with alpha < 0.5 is not drawn (``map_d``-style cut-outs: the blade's
texture is transparent outside its margin). Transparent texels take the mean colour of the
opaque ones, so filtering at a cut-out's edge does not darken it. Texture v runs up the image
(v = 0 is the bottom row), as in OBJ.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from inflo.formats.errors import FormatError, InputError, read_lines, shorten
from inflo.formats.obj import ObjMesh

__all__ = ["TextureSpec", "TexturedMesh", "read_texcoords", "read_mtl_maps", "load_texture", "apply_textures",
           "parse_texture_option"]


@dataclass
class TexturedMesh(ObjMesh):
    """An :class:`ObjMesh` with texture coordinates and images.

    Attributes
    ----------
    uv : (n, 2) float32
        Texture coordinates per vertex (0 for vertices of untextured faces).
    face_texture : (m,) int32
        Index into ``textures`` per face, -1 for a face drawn with its flat colour.
    textures : list of (H, W, 4) uint8
        RGBA images, first row at the **bottom** (v = 0), transparent texels filled (module doc).
    """

    uv: np.ndarray | None = None
    face_texture: np.ndarray | None = None
    textures: list = field(default_factory=list)


def parse_texture_option(value: str) -> tuple[str | None, str]:
    """``MATERIAL=IMAGE`` -> (material, image); ``IMAGE`` -> (None, image).

    Raises
    ------
    ValueError
        An empty material or image name.
    """
    text = str(value)
    if "=" in text and not Path(text).exists():
        mat, img = text.split("=", 1)
        if not mat.strip() or not img.strip():
            raise ValueError(f"expected [MATERIAL=]IMAGE.png, found {value!r}")
        return mat.strip(), img.strip()
    if not text.strip():
        raise ValueError("expected [MATERIAL=]IMAGE.png, found an empty value")
    return None, text


@dataclass
class TextureSpec:
    """What to texture: images by material name, one image for every textured face, the mtl maps.

    ``images`` caches every image read (by resolved path) for all the frames of a run.
    """

    by_material: dict = field(default_factory=dict)  # name -> image path
    everything: str | None = None
    use_mtl: bool = False
    images: dict = field(default_factory=dict)
    used: set = field(default_factory=set)

    @property
    def active(self) -> bool:
        return bool(self.by_material or self.everything or self.use_mtl)

    def image(self, path) -> tuple[int, np.ndarray]:
        """(index, RGBA array) of an image, read once."""
        key = str(Path(path).resolve())
        if key not in self.images:
            self.images[key] = (len(self.images), load_texture(path))
        return self.images[key]


def load_texture(path) -> np.ndarray:
    """A PNG (or any image PIL reads) as (H, W, 4) uint8 RGBA, bottom row first, transparent texels
    filled with the opaque texels' mean colour.

    Raises
    ------
    InputError
        A missing or unreadable image.
    """
    from PIL import Image, UnidentifiedImageError

    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: texture image not found")
    try:
        with Image.open(p) as im:
            rgba = np.asarray(im.convert("RGBA"), dtype=np.uint8)[::-1].copy()
    except (UnidentifiedImageError, OSError) as exc:
        raise InputError(f"{p}: expected a texture image (PNG), found an unreadable file ({exc})") from None
    clear = rgba[..., 3] < 128
    if clear.any() and not clear.all():
        rgba[clear, :3] = np.round(rgba[~clear, :3].mean(axis=0)).astype(np.uint8)
    return rgba


def read_texcoords(path) -> tuple[np.ndarray, np.ndarray]:
    """The ``vt`` coordinates of an OBJ and its faces' references to them.

    Returns
    -------
    vt : (k, 2) float64
        u, v of every ``vt`` line, in order (a third coordinate is ignored).
    face_vt : (m, 3) int64
        0-based ``vt`` index of every corner of the fan-triangulated faces (as ``read_obj``'s
        ``faces``), -1 for a corner without one.

    Raises
    ------
    FormatError
        A malformed ``vt`` line or reference.
    """
    lines = read_lines(path)
    vt, face_vt = [], []
    for i, line in enumerate(lines):
        toks = line.split()
        if not toks:
            continue
        if toks[0] == "vt":
            try:
                u = [float(x) for x in toks[1:4]]
            except ValueError:
                u = []
            if len(u) < 2 or not np.all(np.isfinite(u)):
                raise FormatError(path, i + 1, "'vt u v [w]' with finite numbers", shorten(line))
            vt.append(u[:2])
        elif toks[0] == "f":
            refs = []
            for t in toks[1:]:
                parts = t.split("/")
                if len(parts) < 2 or parts[1] == "":
                    refs.append(-1)
                    continue
                try:
                    k = int(parts[1])
                except ValueError:
                    raise FormatError(path, i + 1, "a vt index (an integer) in a face reference", shorten(t)) from None
                k = k - 1 if k > 0 else len(vt) + k
                if not 0 <= k < len(vt):
                    raise FormatError(path, i + 1, f"a vt index within 1..{len(vt)} (defined before the face)",
                                      shorten(t))
                refs.append(k)
            for k in range(1, len(refs) - 1):
                face_vt.append((refs[0], refs[k], refs[k + 1]))
    return np.asarray(vt, np.float64).reshape(-1, 2), np.asarray(face_vt, np.int64).reshape(-1, 3)


def read_mtl_maps(obj_path) -> dict[str, Path]:
    """Material name -> its ``map_Kd`` image, from the ``mtllib`` files an OBJ names (paths beside
    the OBJ; a library that is missing is skipped, as viewers do)."""
    obj_path = Path(obj_path)
    out: dict[str, Path] = {}
    for line in read_lines(obj_path):
        toks = line.split()
        if not toks or toks[0] != "mtllib":
            continue
        for name in toks[1:]:
            lib = obj_path.parent / name
            if not lib.is_file():
                continue
            current = None
            for mline in read_lines(lib):
                m = mline.split()
                if not m:
                    continue
                if m[0] == "newmtl":
                    current = " ".join(m[1:])
                elif m[0] == "map_Kd" and current is not None and len(m) >= 2:
                    out[current] = lib.parent / m[-1]
    return out


def apply_textures(mesh: ObjMesh, path, spec: TextureSpec) -> ObjMesh:
    """``mesh`` (read from ``path``) as a :class:`TexturedMesh` when ``spec`` textures any of its
    faces; the mesh itself otherwise.

    Raises
    ------
    InputError
        A textured face without ``vt`` references, a missing image.
    """
    if not spec.active or len(mesh.faces) == 0:
        return mesh
    maps: dict[str, Path | str] = {}
    if spec.use_mtl:
        maps.update(read_mtl_maps(path))
    maps.update(spec.by_material)
    names = list(mesh.materials or [])
    fm = mesh.face_material if mesh.face_material is not None else np.full(len(mesh.faces), -1, np.int32)
    vt, face_vt = None, None
    tex_of_face = np.full(len(mesh.faces), -1, np.int32)
    for mid, name in enumerate(names):
        if name in maps:
            sel = fm == mid
            if sel.any():
                tex_of_face[sel] = spec.image(maps[name])[0]
                spec.used.add(name)
    if spec.everything is not None:
        vt, face_vt = read_texcoords(path)
        if len(vt):
            free = tex_of_face < 0
            tex_of_face[free & np.all(face_vt >= 0, axis=1)] = spec.image(spec.everything)[0]
            spec.used.add("")
    if not (tex_of_face >= 0).any():
        return mesh
    if vt is None:
        vt, face_vt = read_texcoords(path)
    if len(face_vt) != len(mesh.faces):
        raise InputError(f"{path}: {len(face_vt)} triangles with texture references for {len(mesh.faces)} faces")
    textured = tex_of_face >= 0
    missing = textured & np.any(face_vt < 0, axis=1)
    if missing.any():
        j = int(np.flatnonzero(missing)[0])
        mat = names[fm[j]] if fm[j] >= 0 else "(none)"
        raise InputError(f"{path}: expected 'vt' texture coordinates on every face of material {mat!r} "
                         f"(textured), found a face without them (triangle {j + 1})")
    return _with_uv(mesh, vt, face_vt, tex_of_face, spec)


def _with_uv(mesh: ObjMesh, vt, face_vt, tex_of_face, spec: TextureSpec) -> TexturedMesh:
    """The mesh with one uv per vertex (seam vertices copied: module docstring)."""
    from .render import vertex_normals

    faces = np.asarray(mesh.faces, np.int64)
    n = len(mesh.vertices)
    textured = tex_of_face >= 0
    corners_v = faces[textured].ravel()
    corners_t = face_vt[textured].ravel()
    # each (vertex, vt) pair once; a vertex's first pair keeps the vertex
    key = corners_v * (len(vt) + 1) + corners_t
    uniq, first, inv = np.unique(key, return_index=True, return_inverse=True)
    pv, pt = uniq // (len(vt) + 1), uniq % (len(vt) + 1)
    order = np.lexsort((first, pv))  # by vertex, then by first use
    is_first = np.r_[True, pv[order][1:] != pv[order][:-1]]
    new_index = np.empty(len(uniq), np.int64)
    new_index[order[is_first]] = pv[order[is_first]]
    extra = order[~is_first]
    new_index[extra] = n + np.arange(len(extra))
    src = np.r_[np.arange(n), pv[extra]]
    uv = np.zeros((n + len(extra), 2), np.float32)
    uv[new_index] = vt[pt]
    new_faces = faces.copy()
    new_faces[textured] = new_index[inv].reshape(-1, 3)
    normals = mesh.normals if mesh.normals is not None else vertex_normals(mesh.vertices, faces)
    colors = None if mesh.vertex_colors is None else np.asarray(mesh.vertex_colors)[src]
    out = TexturedMesh(vertices=np.asarray(mesh.vertices)[src], faces=new_faces, normals=np.asarray(normals)[src],
                       vertex_colors=colors, lines=mesh.lines, groups=mesh.groups, face_group=mesh.face_group,
                       materials=mesh.materials, face_material=mesh.face_material,
                       uv=uv, face_texture=tex_of_face.astype(np.int32))
    by_index = {i: arr for i, arr in spec.images.values()}
    out.textures = [by_index[i] for i in range(len(by_index))]
    return out
