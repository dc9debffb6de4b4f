"""Open a USD file in Blender (``bpy``, Blender as a Python module) as a user would, and report.

Run with the Python that has ``bpy`` (``make test-blender`` makes ``.venv-blender/``), not with
inflo's venv: this script imports nothing of inflo, so inflo's venv stays without the 370 MB
wheel. ``tests/test_blender.py`` and ``bench/bench_export.py`` run it in a subprocess::

    .venv-blender/bin/python tools/canopy_export/blender_probe.py build/lily/lily.usdc -o probe \\
        [--frames all|none|1,50,100] [--faces] [--render PNG --camera CAM.json --size 320x240 --samples 8]

It imports the file with File > Import > Universal Scene Description's defaults
(``bpy.ops.wm.usd_import``: the scene's frame range set from the file; an ``.obj`` file with
File > Import > Wavefront's, ``bpy.ops.wm.obj_import``), then writes

- ``probe.json``: Blender's version, the scene's frame range and fps, the seconds the import,
  the frame evaluation and the render took, and per mesh object its name, world matrix,
  modifiers, materials (name, the Principled BSDF's base colour, linear) and per evaluated frame
  the vertex and polygon counts and whether every polygon is shaded smooth;
- ``probe.npz``: per mesh object and evaluated frame ``<object>/co/<frame>``, the evaluated
  vertex positions (object space: the USD points), ``<object>/mat/<frame>`` the material index of
  each polygon, and with ``--faces`` ``<object>/faces/<frame>`` (polygon corner vertex indices,
  every polygon a triangle) wherever the polygons differ from the previous frame's.

With ``--render`` it renders one frame (``--render-frame``, default the last) with Cycles on the
CPU at ``--samples`` samples, film transparent (the silhouette is the alpha), through a
perspective camera given in the file's own coordinates (``CAM.json``: ``eye``, ``target``,
``up``, ``fov`` vertical degrees; the same numbers canopy-render's camera has) and carried into
Blender's world by the imported root object's transform (Y-up to Z-up, the unit scale).
"""
from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np


def _args(argv):
    p = argparse.ArgumentParser(prog="blender_probe.py")
    p.add_argument("usd")
    p.add_argument("-o", "--output", required=True, help="output stem: STEM.json and STEM.npz")
    p.add_argument("--frames", default="all", help="all, none, or a comma list of scene frames")
    p.add_argument("--faces", action="store_true", help="also store polygons where they change")
    p.add_argument("--no-arrays", action="store_true", help="write the JSON report only (timings, counts)")
    p.add_argument("--render", default=None, help="render a PNG of one frame with Cycles")
    p.add_argument("--render-frame", type=int, default=None, help="scene frame to render [the last]")
    p.add_argument("--camera", default=None, help="JSON camera: eye, target, up, fov (file coordinates)")
    p.add_argument("--size", default="320x240")
    p.add_argument("--samples", type=int, default=8)
    return p.parse_args(argv)


def _base_color(mat):
    if mat is None or not mat.use_nodes or mat.node_tree is None:
        return None
    for node in mat.node_tree.nodes:
        if node.type == "BSDF_PRINCIPLED":
            return [float(c) for c in node.inputs["Base Color"].default_value[:3]]
    return None


def _camera_matrix(eye, target, up):
    """A Blender camera's world matrix: it looks along its -Z with +Y up (4, 4)."""
    f = target - eye
    f = f / np.linalg.norm(f)
    r = np.cross(f, up)
    r = r / np.linalg.norm(r)
    u = np.cross(r, f)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = r, u, -f, eye
    return m


def _render(bpy, args, root_matrix, report):
    from mathutils import Matrix

    cam = json.loads(open(args.camera).read())
    w, h = (int(v) for v in args.size.lower().split("x"))
    scene = bpy.context.scene
    # the camera in the file's coordinates, carried by the root's transform; its scale (metres per
    # unit) applies to positions, not to the angles
    eye = root_matrix @ np.append(np.asarray(cam["eye"], float), 1.0)
    target = root_matrix @ np.append(np.asarray(cam["target"], float), 1.0)
    up = root_matrix[:3, :3] @ np.asarray(cam["up"], float)
    data = bpy.data.cameras.new("probe_camera")
    data.type = "PERSP"
    data.sensor_fit = "VERTICAL"
    data.angle_y = np.radians(float(cam["fov"]))
    dist = float(np.linalg.norm(target[:3] - eye[:3]))
    data.clip_start = dist * 1e-3
    data.clip_end = dist * 1e3
    obj = bpy.data.objects.new("probe_camera", data)
    scene.collection.objects.link(obj)
    obj.matrix_world = Matrix(_camera_matrix(eye[:3], target[:3], up).tolist())
    scene.camera = obj
    light = bpy.data.lights.new("probe_sun", "SUN")
    light.energy = 3.0
    sun = bpy.data.objects.new("probe_sun", light)
    scene.collection.objects.link(sun)
    sun.matrix_world = obj.matrix_world
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = args.samples
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = w, h
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = True
    # colours as the file gives them (Blender's default view transform, AgX, desaturates bright ones)
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGBA"
    scene.render.filepath = args.render
    frame = args.render_frame if args.render_frame is not None else scene.frame_end
    scene.frame_set(frame)
    t = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    report["seconds_render"] = time.perf_counter() - t
    report["render_frame"] = frame


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if "--" in argv:
        argv = argv[argv.index("--") + 1:]
    args = _args(argv)
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    t = time.perf_counter()
    if args.usd.lower().endswith(".obj"):  # one OBJ frame, File > Import > Wavefront (.obj) defaults
        result = bpy.ops.wm.obj_import(filepath=args.usd)
    else:
        result = bpy.ops.wm.usd_import(filepath=args.usd)
    report = {"blender": bpy.app.version_string, "import_result": sorted(result),
              "seconds_import": time.perf_counter() - t}
    scene = bpy.context.scene
    report.update(frame_start=scene.frame_start, frame_end=scene.frame_end,
                  fps=scene.render.fps / scene.render.fps_base)
    meshes = [o for o in bpy.data.objects if o.type == "MESH"]
    roots = [o for o in bpy.data.objects if o.parent is None and o.type != "CAMERA"]
    report["roots"] = [o.name for o in roots]
    if args.frames == "all":
        frames = list(range(scene.frame_start, scene.frame_end + 1))
    elif args.frames == "none":
        frames = []
    else:
        frames = [int(f) for f in args.frames.split(",") if f.strip()]
    objects = {}
    for o in meshes:
        objects[o.name] = {
            "matrix_world": [list(r) for r in o.matrix_world],
            "parent": o.parent.name if o.parent else None,
            "modifiers": [m.type for m in o.modifiers],
            "materials": [{"name": m.name if m else None, "base_color": _base_color(m)} for m in o.data.materials],
            "frames": {},
        }
    arrays = {}
    last_faces = {}
    t = time.perf_counter()
    for f in frames:
        scene.frame_set(f)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        for o in meshes:
            ev = o.evaluated_get(depsgraph)
            me = ev.to_mesh()
            nv, npoly = len(me.vertices), len(me.polygons)
            co = np.empty(nv * 3, np.float32)
            me.vertices.foreach_get("co", co)
            arrays[f"{o.name}/co/{f}"] = co.reshape(-1, 3)
            mat = np.empty(npoly, np.int32)
            me.polygons.foreach_get("material_index", mat)
            arrays[f"{o.name}/mat/{f}"] = mat
            if args.faces:
                corners = np.empty(len(me.loops), np.int32)
                me.loops.foreach_get("vertex_index", corners)
                totals = np.empty(npoly, np.int32)
                me.polygons.foreach_get("loop_total", totals)
                if np.all(totals == 3):
                    faces = corners.reshape(-1, 3)
                else:  # not expected from canopy-export (triangles): keep the flat list with -1 ends
                    faces = np.concatenate([np.append(c, -1) for c in np.split(corners, np.cumsum(totals)[:-1])])
                prev = last_faces.get(o.name)
                if prev is None or prev.shape != faces.shape or not np.array_equal(prev, faces):
                    arrays[f"{o.name}/faces/{f}"] = faces
                    last_faces[o.name] = faces
            smooth = np.zeros(npoly, bool)
            me.polygons.foreach_get("use_smooth", smooth)
            objects[o.name]["frames"][str(f)] = {"vertices": nv, "polygons": npoly,
                                                 "smooth": bool(npoly and smooth.all())}
            ev.to_mesh_clear()
    report["seconds_frames"] = time.perf_counter() - t
    report["objects"] = objects
    if args.render:
        root = next((o for o in roots if o.type == "EMPTY"), None)
        # a mesh object's world matrix is the root's (canopy-export puts parts directly under it)
        some = meshes[0].matrix_world if meshes else (root.matrix_world if root else None)
        matrix = np.array(some) if some is not None else np.eye(4)
        _render(bpy, args, matrix, report)
    np.savez(args.output + ".npz", **({} if args.no_arrays else arrays))
    with open(args.output + ".json", "w") as fh:
        json.dump(report, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
