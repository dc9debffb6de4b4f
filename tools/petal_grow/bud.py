"""Bud meshes: one OBJ per organ with a uv coordinate per vertex (``vt``), sec. 3 / fig. 5(b).

The general OBJ reader (:mod:`inflo.formats.obj`) skips ``vt``; growth maps need them, so organ
meshes are read here: ``v x y z``, ``vt u v``, triangles ``f a/ta b/tb c/tc`` (or ``a/ta/na``).
Every vertex must get one uv (all its face corners name the same ``vt`` values); ``vn``, ``g``,
``o``, ``s``, ``usemtl``, ``mtllib`` and comments are ignored. Spec: formats/petal_grow.md.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from inflo.formats.atomic import atomic_write
from inflo.formats.errors import FormatError, read_lines, shorten

__all__ = ["BudMesh", "read_bud_obj", "write_bud_obj", "grid_bud"]

_SKIP = {"vn", "g", "o", "s", "usemtl", "mtllib", "l"}


@dataclass
class BudMesh:
    """vertices (n, 3) float64, uv (n, 2) float64, faces (m, 3) int32 (counter-clockwise seen
    from the organ's inner, adaxial side)."""

    vertices: np.ndarray
    uv: np.ndarray
    faces: np.ndarray


def read_bud_obj(path) -> BudMesh:
    """Read one organ's bud mesh with uv (module doc). Raises FormatError with the line."""
    verts, vts, faces, face_t, face_line = [], [], [], [], []
    for ln, raw in enumerate(read_lines(path), 1):
        s = raw.split("#", 1)[0].split()
        if not s:
            continue
        tag, args = s[0], s[1:]
        if tag in ("v", "vt"):
            want = 3 if tag == "v" else 2
            if len(args) < want:
                raise FormatError(path, ln, f"{want} numbers after '{tag}'", shorten(raw))
            try:
                vals = [float(a) for a in args[:want]]
            except ValueError:
                raise FormatError(path, ln, f"{want} numbers after '{tag}'", shorten(raw)) from None
            if not np.isfinite(vals).all():
                raise FormatError(path, ln, "finite numbers", shorten(raw))
            (verts if tag == "v" else vts).append(vals)
        elif tag == "f":
            if len(args) != 3:
                raise FormatError(path, ln, "a triangle 'f a/ta b/tb c/tc'", shorten(raw))
            vi, ti = [], []
            for tok in args:
                parts = tok.split("/")
                if len(parts) < 2 or not parts[1]:
                    raise FormatError(path, ln, "a uv reference on every corner ('a/ta')", shorten(tok))
                try:
                    a, t = int(parts[0]), int(parts[1])
                except ValueError:
                    raise FormatError(path, ln, "integer references 'a/ta'", shorten(tok)) from None
                a = a - 1 if a > 0 else len(verts) + a
                t = t - 1 if t > 0 else len(vts) + t
                if not (0 <= a < len(verts)) or not (0 <= t < len(vts)):
                    raise FormatError(path, ln, f"a vertex in 1..{len(verts)} and a vt in 1..{len(vts)} "
                                      "defined above", shorten(tok))
                vi.append(a)
                ti.append(t)
            faces.append(vi)
            face_t.append(ti)
            face_line.append(ln)
        elif tag in _SKIP:
            continue
        else:
            raise FormatError(path, ln, "v, vt, f (or vn, g, o, s, usemtl, mtllib, #)", shorten(raw))
    if not faces:
        raise FormatError(path, None, "at least one triangle 'f'", "none")
    v = np.asarray(verts, dtype=np.float64).reshape(-1, 3)
    vt = np.asarray(vts, dtype=np.float64).reshape(-1, 2)
    f = np.asarray(faces, dtype=np.int32)
    ft = np.asarray(face_t, dtype=np.int64)
    uv = np.full((len(v), 2), np.nan)
    for k in range(len(f)):
        for c in range(3):
            a, t = f[k, c], ft[k, c]
            if np.isnan(uv[a, 0]):
                uv[a] = vt[t]
            elif not np.allclose(uv[a], vt[t], atol=1e-9):
                raise FormatError(path, face_line[k], f"one uv per vertex (vertex {a + 1} has "
                                  f"{uv[a, 0]:g} {uv[a, 1]:g} elsewhere)", f"{vt[t, 0]:g} {vt[t, 1]:g}")
    unused = np.isnan(uv[:, 0])
    if unused.any():
        raise FormatError(path, None, "every vertex used by a triangle", f"vertex {int(np.argmax(unused)) + 1} unused")
    if len(np.unique(np.sort(f, axis=1), axis=0)) != len(f) or (f[:, 0] == f[:, 1]).any() \
            or (f[:, 1] == f[:, 2]).any() or (f[:, 0] == f[:, 2]).any():
        raise FormatError(path, None, "distinct triangles of three distinct vertices", "a repeated or degenerate face")
    return BudMesh(v, uv, f)


def write_bud_obj(path, mesh: BudMesh, header: str | None = None) -> None:
    """Write a bud mesh with one ``vt`` per vertex and ``f a/a b/b c/c`` (atomic)."""
    out = []
    if header:
        out.extend(f"# {h}\n" for h in header.splitlines())
    out.extend("v %.6f %.6f %.6f\n" % tuple(p) for p in mesh.vertices.tolist())
    out.extend("vt %.6f %.6f\n" % tuple(t) for t in mesh.uv.tolist())
    out.extend("f %d/%d %d/%d %d/%d\n" % (a, a, b, b, c, c) for a, b, c in (mesh.faces + 1).tolist())
    with atomic_write(path) as fh:
        fh.write("".join(out))


def grid_bud(x: np.ndarray, s: np.ndarray, t: np.ndarray, nu: int, nv: int) -> BudMesh:
    """A bud mesh on an ``nv`` x ``nu`` grid of particles (row-major from the base, ``x`` (nu nv, 3),
    uv = (s, t)) with alternating diagonals (near-isotropic triangles), wound counter-clockwise
    seen from the flower axis (+Y through the origin): the inner side, as petal-grow expects."""
    faces = []
    for j in range(nv - 1):
        for i in range(nu - 1):
            a, b, c, d = j * nu + i, j * nu + i + 1, (j + 1) * nu + i, (j + 1) * nu + i + 1
            faces += [(a, b, d), (a, d, c)] if (i + j) % 2 == 0 else [(a, b, c), (b, d, c)]
    f = np.array(faces, np.int32)
    n = np.cross(x[f[:, 1]] - x[f[:, 0]], x[f[:, 2]] - x[f[:, 0]])
    centre = x[f].mean(axis=1)
    if np.sum(n[:, 0] * -centre[:, 0] + n[:, 2] * -centre[:, 2]) < 0:
        f = np.ascontiguousarray(f[:, [0, 2, 1]])
    return BudMesh(np.asarray(x, dtype=np.float64), np.stack([s, t], axis=1), f)
