"""Drive the inflo Blender add-on in real Blender and report what it made (tests/test_blender_addon.py).

Run with the Python that has ``bpy`` (``.venv-blender/``), with BLENDER_USER_SCRIPTS and
BLENDER_USER_CONFIG set to a scratch folder (the zip is installed there as a user would)::

    python tests/blender_addon_probe.py --zip build/inflo_blender.zip -o report.json \\
        [--import BUILD_DIR ...] [--build SPECIES --project P --quality draft] \\
        [--bad-build PROJECT SPECIES] [--bad-import DIR] [--render PNG --size 240x180 --samples 4]

Every operator call is recorded: its result, or the RuntimeError Blender turns its error report
into (the message). After each import: the scene (frame range, fps, camera, lights), every
object of the import (collection, modifiers and cache file, materials with their node types,
base colour and organ) and, at the first, middle and last frame, each mesh's vertex count,
whether every polygon is smooth, its bounding box and the share of its vertices the camera sees.
Imports nothing of inflo.
"""
import argparse
import json
import math
import sys
import time

import bpy
import numpy as np
from bpy_extras.object_utils import world_to_camera_view


def _args(argv):
    p = argparse.ArgumentParser()
    p.add_argument("--zip", required=True)
    p.add_argument("-o", "--output", required=True)
    p.add_argument("--import", dest="imports", action="append", default=[])
    p.add_argument("--build", default=None)
    p.add_argument("--project", default="")
    p.add_argument("--quality", default="draft")
    p.add_argument("--bad-build", nargs=2, action="append", default=[], metavar=("PROJECT", "SPECIES"))
    p.add_argument("--bad-import", action="append", default=[])
    p.add_argument("--render", default=None)
    p.add_argument("--size", default="240x180")
    p.add_argument("--samples", type=int, default=4)
    return p.parse_args(argv)


def call(op, **kw):
    t = time.perf_counter()
    try:
        result = op(**kw)
        return {"result": sorted(result), "seconds": time.perf_counter() - t}
    except RuntimeError as exc:
        return {"error": str(exc), "seconds": time.perf_counter() - t}


def base_color(mat):
    for node in mat.node_tree.nodes if mat.node_tree else ():
        if node.type == "BSDF_PRINCIPLED":
            return [float(c) for c in node.inputs["Base Color"].default_value[:3]]
    return None


def principled_input(mat, name):
    for node in mat.node_tree.nodes if mat.node_tree else ():
        if node.type == "BSDF_PRINCIPLED" and name in node.inputs:
            return float(node.inputs[name].default_value)
    return None


def surface_node(mat):
    for node in mat.node_tree.nodes if mat.node_tree else ():
        if node.type == "OUTPUT_MATERIAL" and node.inputs["Surface"].is_linked:
            return node.inputs["Surface"].links[0].from_node.type
    return None


def scene_report():
    scene = bpy.context.scene
    cam = scene.camera
    rep = {
        "frame_start": scene.frame_start, "frame_end": scene.frame_end,
        "fps": scene.render.fps / scene.render.fps_base,
        "collections": sorted(c.name for c in bpy.data.collections),
        "counts": {"objects": len(bpy.data.objects), "meshes": len(bpy.data.meshes),
                   "materials": len(bpy.data.materials), "cache_files": len(bpy.data.cache_files),
                   "collections": len(bpy.data.collections), "cameras": len(bpy.data.cameras),
                   "lights": len(bpy.data.lights)},
        "lights": sorted(o.name for o in scene.objects if o.type == "LIGHT"),
        "camera": None, "objects": {},
    }
    if cam is not None:
        rep["camera"] = {"name": cam.name, "rig": bool(cam.get("inflo_rig")),
                         "matrix_world": [list(r) for r in cam.matrix_world],
                         "angle_y": cam.data.angle_y, "sensor_fit": cam.data.sensor_fit,
                         "focus_distance": cam.data.dof.focus_distance}
    frames = sorted({scene.frame_start, (scene.frame_start + scene.frame_end) // 2, scene.frame_end})
    for coll in bpy.data.collections:
        if not coll.name.startswith("inflo ") or coll.name == "inflo rig":
            continue
        for obj in coll.all_objects:
            o = {"type": obj.type, "collection": coll.name, "matrix_world": [list(r) for r in obj.matrix_world],
                 "modifiers": [{"type": m.type, "cache": bpy.path.abspath(m.cache_file.filepath) if getattr(
                     m, "cache_file", None) else None, "object_path": getattr(m, "object_path", None)}
                     for m in obj.modifiers],
                 "materials": [], "frames": {}}
            if obj.type == "MESH":
                for m in obj.data.materials:
                    o["materials"].append({
                        "name": m.name, "usd": m.get("inflo_material"), "organ": m.get("inflo_organ"),
                        "base_color": base_color(m), "surface": surface_node(m),
                        "nodes": sorted(n.type for n in m.node_tree.nodes),
                        "subsurface": principled_input(m, "Subsurface Weight"),
                        "diffuse_color": list(m.diffuse_color)[:3]})
            rep["objects"][obj.name] = o
    meshes = [bpy.data.objects[n] for n, o in rep["objects"].items() if o["type"] == "MESH"]
    for f in frames:
        scene.frame_set(f)
        dg = bpy.context.evaluated_depsgraph_get()
        for obj in meshes:
            ev = obj.evaluated_get(dg)
            me = ev.to_mesh()
            co = np.empty(len(me.vertices) * 3, np.float32)
            me.vertices.foreach_get("co", co)
            smooth = np.zeros(len(me.polygons), bool)
            me.polygons.foreach_get("use_smooth", smooth)
            ev.to_mesh_clear()
            m = np.array(ev.matrix_world)
            w = co.reshape(-1, 3).astype(np.float64) @ m[:3, :3].T + m[:3, 3]
            seen = None
            if cam is not None:
                from mathutils import Vector

                step = max(1, len(w) // 5000)
                ndc = np.array([tuple(world_to_camera_view(scene, cam, Vector(p))) for p in w[::step]])
                inside = (ndc[:, 0] >= 0) & (ndc[:, 0] <= 1) & (ndc[:, 1] >= 0) & (ndc[:, 1] <= 1) & (ndc[:, 2] > 0)
                seen = {"share": float(inside.mean()), "x": [float(ndc[:, 0].min()), float(ndc[:, 0].max())],
                        "y": [float(ndc[:, 1].min()), float(ndc[:, 1].max())]}
            rep["objects"][obj.name]["frames"][str(f)] = {
                "vertices": len(co) // 3, "polygons": int(len(smooth)), "smooth": bool(len(smooth) and smooth.all()),
                "bbox": [w.min(axis=0).tolist(), w.max(axis=0).tolist()], "seen": seen}
    scene.frame_set(scene.frame_start)
    return rep


def render(args, report):
    scene = bpy.context.scene
    w, h = (int(v) for v in args.size.lower().split("x"))
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = args.samples
    scene.cycles.use_denoising = False
    scene.render.film_transparent = True
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGBA"
    scene.render.filepath = args.render
    scene.frame_set(scene.frame_end)
    t = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    report["render"] = {"seconds": time.perf_counter() - t, "frame": scene.frame_end, "size": [w, h]}


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    args = _args(argv)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    w, h = (int(v) for v in args.size.lower().split("x"))
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = w, h, 100
    report = {"blender": bpy.app.version_string, "background": bpy.app.background}
    report["install"] = call(bpy.ops.preferences.addon_install, filepath=args.zip, overwrite=True)
    report["enable"] = call(bpy.ops.preferences.addon_enable, module="inflo_blender")
    report["registered"] = {"operators": sorted(n for n in dir(bpy.types) if n.startswith("INFLO_OT_")),
                            "panel": hasattr(bpy.types, "VIEW3D_PT_inflo"),
                            "scene_settings": hasattr(bpy.types.Scene, "inflo")}
    if report["registered"]["scene_settings"] and args.project:
        import inflo_blender  # the installed add-on: the panel's species list

        scene.inflo.project = args.project
        report["species_items"] = [list(i[:2]) for i in inflo_blender.species_items(None, bpy.context)]
    report["imports"] = []
    for d in args.imports:
        r = call(bpy.ops.inflo.import_build, directory=d)
        r["scene"] = scene_report()
        report["imports"].append(r)
    if args.build:
        r = call(bpy.ops.inflo.build, species=args.build, quality=args.quality, project=args.project)
        r["scene"] = scene_report()
        report["build"] = r
    report["bad"] = [call(bpy.ops.inflo.build, species=sp, quality="draft", project=p) for p, sp in args.bad_build]
    report["bad"] += [call(bpy.ops.inflo.import_build, directory=d) for d in args.bad_import]
    if args.render:
        render(args, report)
    with open(args.output, "w") as fh:
        json.dump(report, fh, indent=1, default=lambda x: None if isinstance(x, float) and math.isnan(x) else str(x))
    return 0


if __name__ == "__main__":
    sys.exit(main())
