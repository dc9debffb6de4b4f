"""Wavefront OBJ meshes and OBJ sequences, read without merging or reordering vertices.

The vertex order of an OBJ file is the identity of each vertex across the frames of a sequence
(docs/architecture.md "OBJ"), so this reader keeps every ``v`` line, in order, used or not (trimesh
merges or drops vertices; see docs/vlab_formats.md). Spec: ``formats/obj.md``.

Supported statements: ``v x y z [r g b]``, ``vn``, ``vt`` (skipped), ``f`` with ``i``, ``i/t``,
``i//n``, ``i/t/n`` references (1-based or negative), polygons fan-triangulated, ``l`` polylines,
``o``/``g`` (face groups), ``usemtl`` (face materials), ``mtllib``/``s`` (ignored), ``#`` comments.
The writer adds ``mtllib materials.mtl`` to a mesh with materials and ``s 1`` (smooth shading)
before the faces, for viewers such as Blender; :func:`write_mtl` writes that material library.
"""
from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .atomic import atomic_write, frame_name, list_sequence
from .errors import FormatError, InputError, decode_lines, read_bytes, shorten

__all__ = [
    "ObjMesh",
    "read_obj",
    "write_obj",
    "read_obj_sequence",
    "write_obj_sequence",
    "list_obj_sequence",
    "as_written",
    "written_vertices",
    "write_mtl",
    "FLOAT_FMT",
    "MTL_NAME",
]

FLOAT_FMT = "%.6f"
"""Coordinates are written with six decimals: stable text for diffs (docs/architecture.md)."""
MAX_WRITTEN = 1e12  # the largest coordinate a writer puts in an OBJ file

MTL_NAME = "materials.mtl"
"""The material library a written OBJ with ``usemtl`` names (``mtllib``), beside it in its folder;
``canopy-export --mtl`` writes it from a colour file (formats/obj.md)."""

_IGNORED = {"vt", "vp", "s", "mtllib", "usemap", "maplib", "shadow_obj", "trace_obj", "lod", "bevel",
            "c_interp", "d_interp", "cstype", "deg", "curv", "surf", "end", "p"}


@dataclass
class ObjMesh:
    """A triangle mesh with optional polylines, as stored in one OBJ file.

    Attributes
    ----------
    vertices : (n, 3) float64
        Positions, in file order.
    faces : (m, 3) int32
        Triangles as 0-based vertex indices (polygons of the file fan-triangulated).
    normals : (n, 3) float64 or None
        Per-vertex normals, kept only when the file gives one ``vn`` per vertex and every face
        uses normal index == vertex index (what :func:`write_obj` writes); otherwise None.
    vertex_colors : (n, 3) float64 or None
        ``v x y z r g b`` colours in [0, 1] when every vertex has them.
    lines : list of (k,) int32
        Polylines (``l`` statements), 0-based vertex indices; used for skeletons.
    groups : list of str
        Names of ``o``/``g`` groups in order of first appearance.
    face_group : (m,) int32 or None
        Index into ``groups`` per face (-1 before any group), None when the file has no groups.
    materials : list of str
        Names given by ``usemtl``.
    face_material : (m,) int32 or None
        Index into ``materials`` per face (-1 before any ``usemtl``), None when none is used.
    """

    vertices: np.ndarray
    faces: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.int32))
    normals: np.ndarray | None = None
    vertex_colors: np.ndarray | None = None
    lines: list = field(default_factory=list)
    groups: list = field(default_factory=list)
    face_group: np.ndarray | None = None
    materials: list = field(default_factory=list)
    face_material: np.ndarray | None = None

    def __post_init__(self):
        self.vertices = np.ascontiguousarray(self.vertices, dtype=np.float64).reshape(-1, 3)
        self.faces = np.ascontiguousarray(self.faces, dtype=np.int32).reshape(-1, 3)
        self.lines = [np.asarray(l, dtype=np.int32) for l in self.lines]

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    @property
    def n_faces(self) -> int:
        return len(self.faces)

    def same_topology(self, other: ObjMesh) -> bool:
        """Same vertex count, same faces and polylines in the same order."""
        return (
            self.n_vertices == other.n_vertices
            and np.array_equal(self.faces, other.faces)
            and len(self.lines) == len(other.lines)
            and all(np.array_equal(a, b) for a, b in zip(self.lines, other.lines))
        )


def _parse_ref(tok: str, n_v: int, n_vn: int, path, lineno):
    """One face/line reference ``i``, ``i/t``, ``i//n`` or ``i/t/n`` -> (0-based vertex, 0-based normal or -1)."""
    parts = tok.split("/")
    if len(parts) > 3 or parts[0] == "":
        raise FormatError(path, lineno, "a vertex reference i, i/t, i//n or i/t/n", shorten(tok))
    try:
        vi = int(parts[0])
        ni = int(parts[2]) if len(parts) == 3 and parts[2] != "" else 0
    except ValueError:
        raise FormatError(path, lineno, "integer vertex references", shorten(tok)) from None
    if vi < 0:
        vi = n_v + vi + 1
    if not 1 <= vi <= n_v:
        raise FormatError(path, lineno, f"a vertex index in 1..{n_v} (defined so far)", shorten(tok))
    if ni < 0:
        ni = n_vn + ni + 1
    if ni and not 1 <= ni <= n_vn:
        raise FormatError(path, lineno, f"a normal index in 1..{n_vn}", shorten(tok))
    return vi - 1, ni - 1


def _floats(rows, want, path, linenos, what):
    """Convert token rows (lists of str, keyword stripped) to a float array, naming the first bad line."""
    try:
        arr = np.array(rows, dtype=np.float64)
    except ValueError:
        arr = None
    if arr is not None and arr.ndim == 2 and arr.shape[1] in want and np.isfinite(arr).all():
        return arr
    for toks, ln in zip(rows, linenos):
        if len(toks) not in want:
            raise FormatError(path, ln, f"{' or '.join(map(str, sorted(want)))} numbers after '{what}'",
                              f"{len(toks)}: {shorten(' '.join(toks))}")
        for t in toks:
            try:
                x = float(t)
            except ValueError:
                raise FormatError(path, ln, f"a number after '{what}'", shorten(t)) from None
            if not np.isfinite(x):
                raise FormatError(path, ln, f"a finite number after '{what}'", shorten(t))
    # rows of differing (allowed) lengths: the first line sets the width
    width = len(rows[0])
    for toks, ln in zip(rows, linenos):
        if len(toks) != width:
            raise FormatError(path, ln, f"{width} numbers after '{what}' as on the other lines", str(len(toks)))
    raise AssertionError("unreachable")  # pragma: no cover


FAST_BYTES = 1 << 18
"""Files of about this many bytes or more are read and written by the numba kernels of
:mod:`._objtext` (the same result; on smaller ones the kernels save less than they cost to load):
see :func:`_fast`."""

_text_seen = 0
"""Bytes / numbers this process has asked :func:`_fast` about (every OBJ read and write)."""


def _fast(size: int) -> bool:
    """Whether a file / array of ``size`` bytes / numbers goes to the kernels: from
    :data:`FAST_BYTES` where numba is imported already (every numerical tool), from 16 times that
    where importing it is part of the cost.

    The kernels' load is paid once a process: a file of any size goes to them once the process
    has read and written :data:`FAST_BYTES` in all (numba imported), so that a sequence of small
    frames (the lily's 100 frames of 120 kB: 10 ms a frame in Python, 1 ms in the kernel) is read
    by the kernel after its first frames."""
    global _text_seen
    _text_seen += size
    if "numba" in sys.modules:
        return size >= FAST_BYTES or _text_seen >= 2 * FAST_BYTES
    return size >= 16 * FAST_BYTES


class _Statements:
    """The statements other than ``v``/``vn``/``f`` of one file, in file order: groups, materials,
    polylines (kept as tokens until the vertex lines are known); unknown keywords raise."""

    def __init__(self, path):
        self.path = path
        self.groups, self.group_index, self.materials, self.mat_index = [], {}, [], {}
        self.group_changes, self.mat_changes = [(-1, -1)], [(-1, -1)]  # (line index, value)
        self.polylines = []  # (line index, tokens)

    def take(self, i: int, line: str) -> str | None:
        """Handle line ``i``; returns ``"v"``, ``"vn"`` or ``"f"`` for those (the caller's), else None."""
        toks = line.split()
        if not toks or toks[0][0] == "#":
            return None
        tag, lineno = toks[0], i + 1
        if tag in ("v", "vn", "f"):
            return tag
        if tag in ("o", "g"):
            name = " ".join(toks[1:]) or "default"
            if name not in self.group_index:
                self.group_index[name] = len(self.groups)
                self.groups.append(name)
            self.group_changes.append((i, self.group_index[name]))
        elif tag == "usemtl":
            name = " ".join(toks[1:])
            if not name:
                raise FormatError(self.path, lineno, "a material name after 'usemtl'", shorten(line))
            if name not in self.mat_index:
                self.mat_index[name] = len(self.materials)
                self.materials.append(name)
            self.mat_changes.append((i, self.mat_index[name]))
        elif tag == "l":
            if len(toks) < 3:
                raise FormatError(self.path, lineno, "at least 2 vertex references after 'l'", shorten(line))
            self.polylines.append((i, toks[1:]))
        elif tag not in _IGNORED:
            raise FormatError(self.path, lineno,
                              "an OBJ statement (v, vn, vt, f, l, o, g, usemtl, s, mtllib, #)", shorten(tag))
        return None

    def polyline_refs(self, v_line, vn_line) -> list:
        """The polylines' 0-based vertex indices (``v_line``, ``vn_line``: the lines of the
        ``v`` and ``vn`` statements, for negative references)."""
        polylines = []
        for i, toks in self.polylines:
            n_v, n_vn = int(np.searchsorted(v_line, i)), int(np.searchsorted(vn_line, i))
            polylines.append([_parse_ref(t, n_v, n_vn, self.path, i + 1)[0] for t in toks])
        return polylines

    def mesh(self, vertices, colors, vn, polylines, faces, face_nrm, face_line) -> ObjMesh:
        normals = None
        if vn is not None and len(vn) == len(vertices) and (
            face_nrm.size == 0 or np.array_equal(face_nrm, faces)
        ):
            normals = vn

        def per_face(changes):
            at = np.array([c[0] for c in changes], dtype=np.int64)
            val = np.array([c[1] for c in changes], dtype=np.int32)
            return val[np.searchsorted(at, face_line, side="right") - 1]

        return ObjMesh(
            vertices=vertices,
            faces=faces,
            normals=normals,
            vertex_colors=colors,
            lines=polylines,
            groups=self.groups,
            face_group=per_face(self.group_changes) if self.groups else None,
            materials=self.materials,
            face_material=per_face(self.mat_changes) if self.materials else None,
        )


def read_obj(path) -> ObjMesh:
    """Read one OBJ file without merging, dropping or reordering vertices.

    Faces keep file order; a polygon with k > 3 vertices becomes k - 2 fan triangles in place.
    Files of :data:`FAST_BYTES` or more in the common form (``v``, ``vn``, ``f a b c`` or
    ``f a//n b//n c//n``, ``\\n`` line ends) are parsed by a numba kernel with the same result.

    Raises
    ------
    FormatError
        Unknown statement, wrong number of coordinates, NaN/inf, a face or polyline index out of
        range (or referring to a vertex not yet defined), a face with fewer than 3 vertices.
    """
    path = os.fspath(path)
    data = read_bytes(path)
    if _fast(len(data)):
        mesh = _read_fast(path, data)
        if mesh is not None:
            return mesh
    lines = decode_lines(path, data)
    heads = [l[:2] for l in lines]
    h = np.array(heads) if heads else np.zeros(0, "U2")
    v_idx = np.nonzero((h == "v ") | (h == "v\t"))[0].tolist()
    f_idx = np.nonzero((h == "f ") | (h == "f\t"))[0].tolist()
    vn_idx = []

    # the other statements, in file order: groups, materials, polylines, unknown keywords
    st = _Statements(path)
    late_v = late_f = False
    for i, h in enumerate(heads):
        if h in ("v ", "f ", "v\t", "f\t") or h[:1] == "#":
            continue
        tag = st.take(i, lines[i])
        if tag == "vn":
            vn_idx.append(i)
        elif tag == "v":  # indented or otherwise unusual v/f lines
            v_idx.append(i)
            late_v = True
        elif tag == "f":
            f_idx.append(i)
            late_f = True
    if late_v:
        v_idx.sort()
    if late_f:
        f_idx.sort()
    v_line = np.asarray(v_idx, dtype=np.int64)
    vn_line = np.asarray(vn_idx, dtype=np.int64)

    vertices, colors = np.zeros((0, 3)), None
    if v_idx:
        v = _bulk_floats(lines, v_idx, {3, 4, 6}, path, "v")
        vertices = v[:, :3]
        if v.shape[1] == 6:
            colors = v[:, 3:6].copy()
    vn = _bulk_floats(lines, vn_idx, {3}, path, "vn") if vn_idx else None
    polylines = st.polyline_refs(v_line, vn_line)
    faces, face_nrm, face_line = _read_faces(lines, f_idx, v_line, vn_line, path)
    return st.mesh(vertices, colors, vn, polylines, faces, face_nrm, face_line)


def _read_fast(path, data: bytes) -> ObjMesh | None:
    """:func:`read_obj` by the kernel of :mod:`._objtext`; None where the file is outside its
    form or holds an error (the Python reader then reads it and names the error)."""
    from ._objtext import parse_obj

    raw = np.frombuffer(data, dtype=np.uint8)
    ok, v, v_line, vn, vn_line, faces, face_n, face_line, face_nv, face_nvn, other = parse_obj(raw)
    if not ok:
        return None
    if len(raw) and int(raw.max()) >= 0x80:
        try:
            data.decode("utf-8")
        except UnicodeDecodeError:
            return None
    st = _Statements(path)
    for i, s0, s1 in other.tolist():
        if st.take(i, data[s0:s1].decode("utf-8")) is not None:
            return None  # an indented or bare v / vn / f line: the Python reader's
    try:
        polylines = st.polyline_refs(v_line, vn_line)
    except FormatError:
        return None
    n_v = face_nv[:, None]
    tri = np.where(faces < 0, faces + n_v + 1, faces)
    if ((tri < 1) | (tri > n_v)).any():
        return None
    n_vn = face_nvn[:, None]
    nrm = np.where(face_n < 0, face_n + n_vn + 1, face_n)
    if ((nrm != 0) & ((nrm < 1) | (nrm > n_vn))).any():
        return None
    colors = v[:, 3:6].copy() if v.shape[1] == 6 else None
    vertices = v[:, :3] if len(v) else np.zeros((0, 3))
    return st.mesh(vertices, colors, vn if len(vn_line) else None, polylines,
                   (tri - 1).astype(np.int32), nrm - 1, face_line)


def _bulk_tokens(lines, idx, width, forbid: str | None = None):
    """Tokens of the lines ``idx`` as a flat list when every line has exactly ``width`` tokens
    (and none contains ``forbid``); None otherwise."""
    text = " ".join([lines[i] for i in idx])
    if forbid is not None and forbid in text:
        return None
    toks = text.split()
    n = len(idx)
    if len(toks) != n * width:
        return None
    key = toks[0]
    if toks[0::width].count(key) != n:
        return None
    return toks


def _bulk_floats(lines, idx, want, path, what):
    """Numbers after the keyword of the lines ``idx`` as an (n, k) float64 array, k in ``want``."""
    for width in sorted(want):
        toks = _bulk_tokens(lines, idx, width + 1)
        if toks is None:
            continue
        try:
            arr = np.array(toks, dtype=object).reshape(len(idx), width + 1)[:, 1:].astype(np.float64)
        except ValueError:
            break
        if np.isfinite(arr).all():
            return arr
        break
    return _floats([lines[i].split()[1:] for i in idx], want, path, [i + 1 for i in idx], what)


def _read_faces(lines, f_idx, v_line, vn_line, path):
    """Triangles of the ``f`` lines, in file order: (faces (m,3), normal refs (m,3), line index (m,))."""
    if not f_idx:
        z = np.zeros((0, 3), np.int32)
        return z, z.astype(np.int64), np.zeros(0, np.int64)
    line = np.asarray(f_idx, dtype=np.int64)
    toks = _bulk_tokens(lines, f_idx, 4, forbid="/")
    if toks is not None:
        try:
            tri = np.array(toks, dtype=object).reshape(-1, 4)[:, 1:].astype(np.int64)
        except ValueError:
            tri = None
        if tri is not None:
            n_v = np.searchsorted(v_line, line)[:, None]  # vertices defined before each face line
            tri = np.where(tri < 0, tri + n_v + 1, tri)
            bad = (tri < 1) | (tri > n_v)
            if not bad.any():
                return (tri - 1).astype(np.int32), np.full_like(tri, -1), line
    # general path: slashes, polygons, or an error to report with its line
    out_tri, out_nrm, out_line = [], [], []
    for i in f_idx:
        r = lines[i].split()
        if len(r) < 4:
            raise FormatError(path, i + 1, "at least 3 vertex references after 'f'", shorten(lines[i]))
        n_v, n_vn = int(np.searchsorted(v_line, i)), int(np.searchsorted(vn_line, i))
        refs = [_parse_ref(t, n_v, n_vn, path, i + 1) for t in r[1:]]
        for k in range(1, len(refs) - 1):
            out_tri.append((refs[0][0], refs[k][0], refs[k + 1][0]))
            out_nrm.append((refs[0][1], refs[k][1], refs[k + 1][1]))
            out_line.append(i)
    return (np.array(out_tri, np.int32).reshape(-1, 3), np.array(out_nrm, np.int64).reshape(-1, 3),
            np.array(out_line, np.int64))


def _fmt_rows(arr: np.ndarray, prefix: str, fmt: str, block: int = 4096) -> str:
    """Rows of ``arr`` as ``prefix x y z\n`` lines; one %-format per block of rows (fast)."""
    if len(arr) == 0:
        return ""
    c = arr.shape[1]
    row = prefix + " ".join([fmt] * c) + "\n"
    flat = np.asarray(arr, dtype=np.float64).ravel().tolist()
    out = []
    for k in range(0, len(arr), block):
        n = min(block, len(arr) - k)
        out.append((row * n) % tuple(flat[k * c:(k + n) * c]))
    return "".join(out)


def _fixed_digits(fmt: str) -> int | None:
    """N for a ``%.Nf`` format with 1 <= N <= 9 (the kernel's), else None."""
    if len(fmt) == 4 and fmt.startswith("%.") and fmt.endswith("f") and fmt[2] in "123456789":
        return int(fmt[2])
    return None


def _rows_text(arr: np.ndarray, prefix: str, fmt: str) -> tuple[str, np.ndarray | None]:
    """(the rows of ``arr`` as ``prefix`` + numbers lines, the numbers as they read back or None):
    by :func:`._objtext.format_fixed` for large arrays in a ``%.Nf`` format (the same text,
    flagged rows formatted again here), else by :func:`_fmt_rows`."""
    digits = _fixed_digits(fmt)
    arr = np.ascontiguousarray(arr, dtype=np.float64)
    if digits is None or arr.ndim != 2 or not _fast(16 * arr.size):
        return _fmt_rows(arr, prefix, fmt), None
    from ._objtext import format_fixed

    buf, flagged, back = format_fixed(np.frombuffer(prefix.encode("ascii"), np.uint8), arr, digits)
    text = buf.tobytes().decode("ascii")
    if flagged.any():
        lines = text.split("\n")
        row = prefix + " ".join([fmt] * arr.shape[1])
        for k in np.nonzero(flagged)[0].tolist():
            lines[k] = row % tuple(arr[k].tolist())
            back[k] = [float(t) for t in lines[k][len(prefix):].split()]
        text = "\n".join(lines)
    return text, back


def as_written(arr: np.ndarray, fmt: str = FLOAT_FMT) -> np.ndarray:
    """``arr`` (n, c) as :func:`write_obj` writes it with ``fmt`` and a reader reads it back."""
    return written_vertices(arr, fmt)[0]


def written_vertices(arr: np.ndarray, fmt: str = FLOAT_FMT) -> tuple[np.ndarray, str]:
    """(``arr`` as written with ``fmt`` and read back, the ``v`` lines :func:`write_obj` writes
    for it): a caller that checks the written numbers hands the text on (``vertex_text``) rather
    than formatting twice."""
    arr = np.asarray(arr, dtype=np.float64)
    if arr.size == 0:
        return arr.copy(), ""
    text, values = _rows_text(arr, "v ", fmt)
    if values is None:
        values = np.array(text.replace("v ", "").split(), dtype=np.float64)
    return values.reshape(arr.shape), text


def write_obj(path, mesh: ObjMesh, *, header: str | None = None, fmt: str = FLOAT_FMT,
              mtllib: str | None = MTL_NAME, vertex_text: str | None = None) -> None:
    """Write ``mesh`` to ``path`` atomically, vertices in order, faces 1-based.

    Faces are written grouped as stored; a ``g``/``usemtl`` line is emitted where a face's group
    or material changes. Per-vertex normals are written as ``vn`` with ``f a//a b//b c//c``.
    A mesh with materials names the library ``mtllib`` (None: no ``mtllib`` line) after the
    header; ``s 1`` (one smoothing group: smooth shading) comes before the first face.
    ``vertex_text``: the ``v`` lines already formatted (:func:`written_vertices` of the vertices
    with ``fmt``; not with vertex colours).
    """
    _check_mesh(mesh, path)
    parts = []
    if header:
        parts.extend(f"# {h}\n" for h in header.splitlines())
    if mtllib and mesh.face_material is not None and mesh.n_faces and bool(np.any(mesh.face_material >= 0)):
        parts.append(f"mtllib {mtllib}\n")
    if mesh.vertex_colors is not None:
        parts.append(_rows_text(np.hstack([mesh.vertices, mesh.vertex_colors]), "v ", fmt)[0])
    elif vertex_text is not None:
        parts.append(vertex_text)
    else:
        parts.append(_rows_text(mesh.vertices, "v ", fmt)[0])
    if mesh.normals is not None:
        parts.append(_rows_text(mesh.normals, "vn ", fmt)[0])
    parts.append(_face_lines(mesh))
    for pl in mesh.lines:
        parts.append("l " + " ".join(str(int(i) + 1) for i in pl) + "\n")
    with atomic_write(path) as fh:
        fh.write("".join(parts))


def _face_lines(mesh: ObjMesh) -> str:
    """The ``f`` lines, with ``g``/``usemtl`` lines where a face's group or material changes."""
    m = mesh.n_faces
    if m == 0:
        return ""
    row = "f %d//%d %d//%d %d//%d\n" if mesh.normals is not None else "f %d %d %d\n"
    f1 = mesh.faces.astype(np.int64) + 1
    if mesh.normals is not None:
        f1 = np.repeat(f1, 2, axis=1)
    # runs of faces with the same (group, material): a header line before each run that changes
    grp = mesh.face_group if mesh.face_group is not None else np.full(m, -1)
    mat = mesh.face_material if mesh.face_material is not None else np.full(m, -1)
    change = np.ones(m, dtype=bool)
    change[1:] = (grp[1:] != grp[:-1]) | (mat[1:] != mat[:-1])
    starts = np.nonzero(change)[0].tolist() + [m]
    out = ["s 1\n"]
    fast = None
    if _fast(16 * m):
        from ._objtext import format_faces

        buf, offs = format_faces(np.ascontiguousarray(mesh.faces, dtype=np.int64), mesh.normals is not None)
        fast = buf.tobytes().decode("ascii")
    cur_g = cur_m = -1
    for s0, s1 in zip(starts[:-1], starts[1:]):
        g, mt = int(grp[s0]), int(mat[s0])
        if g != cur_g and g >= 0:
            out.append(f"g {mesh.groups[g]}\n")
            cur_g = g
        if mt != cur_m and mt >= 0:
            out.append(f"usemtl {mesh.materials[mt]}\n")
            cur_m = mt
        if fast is not None:
            out.append(fast[offs[s0]:offs[s1]])
            continue
        for k in range(s0, s1, 8192):
            chunk = f1[k:min(s1, k + 8192)]
            out.append((row * len(chunk)) % tuple(chunk.ravel().tolist()))
    return "".join(out)


def write_mtl(path, colors, *, header: str | None = None, fmt: str = "%.6f") -> None:
    """Write a Wavefront material library: ``newmtl NAME`` with ``Kd r g b`` per material.

    Parameters
    ----------
    path : path
        Written atomically.
    colors : mapping str -> (3,) float
        Material name -> diffuse colour, written as given (canopy-export gives linear RGB).
    header : str or None
        Comment lines at the top.
    """
    out = [f"# {h}\n" for h in (header or "").splitlines()]
    for name, rgb in colors.items():
        if not name or any(c.isspace() for c in name):
            raise ValueError(f"{path}: material name {name!r} must be one word")
        r, g, b = (float(c) for c in rgb)
        out.append(f"\nnewmtl {name}\nKd {fmt % r} {fmt % g} {fmt % b}\nKa 0 0 0\nKs 0 0 0\nd 1\nillum 1\n")
    with atomic_write(path) as fh:
        fh.write("".join(out))


def _check_mesh(mesh: ObjMesh, path) -> None:
    n = mesh.n_vertices
    big = float(np.abs(mesh.vertices).max()) if mesh.vertices.size else 0.0
    if not big <= MAX_WRITTEN:
        # coordinates that overflowed, or nearly (inputs far beyond any scene's size), are bad input
        raise InputError(f"{path}: expected vertex coordinates to write within +-{MAX_WRITTEN:g} (inputs of a "
                         f"sensible size), found {big:g}")
    if mesh.faces.size and (mesh.faces.min() < 0 or mesh.faces.max() >= n):
        raise ValueError(f"{path}: face index out of range 0..{n - 1}")
    for pl in mesh.lines:
        if len(pl) and (pl.min() < 0 or pl.max() >= n):
            raise ValueError(f"{path}: polyline index out of range 0..{n - 1}")
    if mesh.normals is not None and mesh.normals.shape != mesh.vertices.shape:
        raise ValueError(f"{path}: normals must be (n, 3) like the vertices")


def list_obj_sequence(source) -> list[Path]:
    """The OBJ files of a sequence (folder, glob or single file), in frame order."""
    return list_sequence(source, ".obj")


def read_obj_sequence(source, *, same_topology: bool = True) -> tuple[list[Path], list[ObjMesh]]:
    """Read every frame of an OBJ sequence.

    With ``same_topology`` (default) every frame must have the first frame's vertex count and
    faces, else a :class:`FormatError` names the first frame that differs.
    """
    paths = list_obj_sequence(source)
    meshes = [read_obj(p) for p in paths]
    if same_topology:
        first = meshes[0]
        for p, m in zip(paths[1:], meshes[1:]):
            if m.n_vertices != first.n_vertices:
                raise FormatError(p, None, f"{first.n_vertices} vertices as in {paths[0].name}",
                                  str(m.n_vertices))
            if not m.same_topology(first):
                raise FormatError(p, None, f"the same faces and polylines as {paths[0].name}",
                                  "a different topology")
    return paths, meshes


def write_obj_sequence(folder, frames, *, prefix: str = "frame_", start: int = 0, digits: int = 4,
                       fmt: str = FLOAT_FMT) -> list[Path]:
    """Write meshes as ``folder/frame_0000.obj``, ... (each file atomic); returns the paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for i, mesh in enumerate(frames, start):
        p = folder / frame_name(i, prefix, ".obj", digits)
        write_obj(p, mesh, fmt=fmt)
        out.append(p)
    return out
