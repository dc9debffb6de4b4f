"""File-format throughput: OBJ read/write of a 400k-triangle canopy-sized mesh.

Anchors: trimesh's order-preserving OBJ load (``process=False, maintain_order=True``) and its OBJ
export of the same mesh in the same run, the library a user would otherwise reach for (ratio < 1:
faster).
"""
from __future__ import annotations

import numpy as np
import trimesh

from inflo.formats.obj import ObjMesh, read_obj, write_obj

from .harness import BenchContext, Result


def _mesh(quick: bool) -> ObjMesh:
    ico = trimesh.creation.icosphere(subdivisions=6 if quick else 7)  # 82k / 328k triangles
    # ~400k triangles: an icosphere plus a quarter copy, as two groups
    faces = np.vstack([ico.faces, ico.faces[: len(ico.faces) // 4] + len(ico.vertices)])
    verts = np.vstack([ico.vertices, ico.vertices * 0.5 + 2.0])
    return ObjMesh(verts, faces)


def obj_read_write(ctx: BenchContext) -> list[Result]:
    mesh = _mesh(ctx.quick)
    path = ctx.workdir / "canopy.obj"
    t_write, _ = ctx.timed(write_obj, path, mesh, repeat=2)
    t_read, got = ctx.timed(read_obj, path, repeat=3)
    t_trimesh, ref = ctx.timed(trimesh.load, path, process=False, maintain_order=True, repeat=3)
    tm = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    t_trimesh_export, _ = ctx.timed(lambda: (ctx.workdir / "trimesh.obj").write_text(
        trimesh.exchange.obj.export_obj(tm, include_normals=False, include_texture=False)), repeat=2)
    assert got.n_faces == len(ref.faces) == mesh.n_faces
    note = f"{mesh.n_faces} triangles, {mesh.n_vertices} vertices"
    return [
        Result("obj_read_400k", t_read, "s", "trimesh.load(process=False, maintain_order=True), same file, same run",
               t_trimesh, note),
        Result("obj_write_400k", t_write, "s", "trimesh.exchange.obj.export_obj of the same mesh (same run)",
               t_trimesh_export, note),
    ]


BENCHMARKS = [obj_read_write]
