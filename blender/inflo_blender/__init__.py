"""inflo for Blender: build a species of the inflo project and import its growth animation.

The only part of inflo that knows Blender's API (docs/blender.md). It imports nothing of inflo:
it reads the project's TOML files itself (``core.py``, standard library) and runs the pipeline
with the project's own ``.venv`` through ``make`` in a subprocess.

- Sidebar (N) > inflo: the project folder, its species (with their titles), quality, Build and
  Import build.
- ``bpy.ops.inflo.build(species="lily", quality="draft", project="/path/to/inflo")``: the
  species' make stages in a subprocess; in the UI a modal operator (progress in the status bar,
  Esc cancels: the process group is ended, and the project's outputs are written atomically so
  nothing half-written stays), in background mode (``blender -b``, ``bpy`` as a module) it runs
  to the end before it returns. Then it imports the build.
- ``bpy.ops.inflo.import_build(directory="/path/to/inflo/build/lily")``: the build's USD as
  animated objects (Mesh Sequence Cache) in a collection ``inflo <species>``, the scene's frame
  range and fps from the file, Principled BSDF materials in the species' colours (petals
  translucent, with subsurface), smooth shading, and a camera and lights framing it when the
  scene has none. Importing again replaces the earlier import.
"""
import math
import os
import re
import subprocess
from pathlib import Path

import bpy
from bpy.props import BoolProperty, EnumProperty, PointerProperty, StringProperty
from mathutils import Vector

from . import core

bl_info = {
    "name": "inflo",
    "author": "inflo project",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "View3D > Sidebar > inflo",
    "description": "Build and import inflo's growing inflorescences (lily, sunflower, yarrow...)",
    "category": "Import-Export",
}

RIG_COLLECTION = "inflo rig"
QUALITY_ITEMS = [("draft", "Draft", "The quick build (seconds to minutes)"),
                 ("final", "Final", "The full build (minutes; hours for the largest species)")]
SCOPE_ITEMS = [("usd", "For Blender", "Only the stages the USD needs (no canopy-render pictures, no check)"),
               ("all", "Every stage", "make <species>: every stage, its pictures and its check included")]


# ------------------------------------------------------------------------------------ settings

def _prefs():
    addon = bpy.context.preferences.addons.get(__package__)
    return addon.preferences if addon else None


def default_project() -> str:
    prefs = _prefs()
    if prefs is not None and prefs.project:
        return prefs.project
    return os.environ.get("INFLO_PROJECT", "")


def project_of(settings) -> str:
    p = settings.project if settings is not None and settings.project else default_project()
    return bpy.path.abspath(p) if p else ""


_species_cache: dict = {}  # (project, mtime) -> enum items: Blender needs the strings kept alive


def species_items(self, context):
    settings = getattr(context.scene, "inflo", None) if context and context.scene else None
    project = project_of(settings)
    try:
        key = (project, os.stat(Path(project) / "pipelines").st_mtime_ns)
    except OSError:
        key = (project, None)
    items = _species_cache.get(key)
    if items is None:
        species, _ = core.find_species(project) if key[1] is not None else ([], [])
        items = [(s.name, s.title, f"{s.title} ({s.family}): make {s.name}") for s in species]
        if not items:
            items = [("NONE", "(no species)", "Pick the inflo project folder first")]
        _species_cache.clear()
        _species_cache[key] = items
    return items


class InfloPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    project: StringProperty(name="Project folder", subtype="DIR_PATH",
                            description="The inflo repository (its Makefile, pipelines/ and .venv)")

    def draw(self, context):
        self.layout.prop(self, "project")


class InfloSettings(bpy.types.PropertyGroup):
    project: StringProperty(name="Project", subtype="DIR_PATH",
                            description="The inflo repository (empty: the add-on's preferences)")
    species: EnumProperty(name="Species", items=species_items)
    quality: EnumProperty(name="Quality", items=QUALITY_ITEMS, default="draft")
    scope: EnumProperty(name="Build", items=SCOPE_ITEMS, default="usd")


# ----------------------------------------------------------------------------------- importing

def usd_of(directory: Path) -> Path | None:
    for ext in (".usdc", ".usda", ".usd"):
        p = directory / f"{directory.name}{ext}"
        if p.is_file():
            return p
    found = sorted(p for ext in ("*.usdc", "*.usda") for p in directory.glob(ext))
    return found[0] if len(found) == 1 else None


def project_of_build(directory: Path) -> Path | None:
    """``<project>/build/<species>`` -> ``<project>`` where that is an inflo project."""
    root = directory.parent.parent
    if directory.parent.name == "build" and (root / "pipelines" / directory.name).is_dir():
        return root
    return None


def usd_timing(usd: Path, project: Path | None) -> tuple[float, float, float] | None:
    """(fps, first, last time code) of a USD file, read by the project's Python (pxr, which
    canopy-export writes with; Blender's Python has none); None where it cannot be read."""
    py = project / ".venv" / "bin" / "python" if project else None
    if py is None or not py.is_file():
        return None
    code = ("import sys; from pxr import Usd; s = Usd.Stage.Open(sys.argv[1]); "
            "print(s.GetTimeCodesPerSecond(), s.GetStartTimeCode(), s.GetEndTimeCode())")
    try:
        r = subprocess.run([str(py), "-c", code, str(usd)], capture_output=True, text=True, timeout=120,
                           env=core.build_env(project))
        fps, first, last = (float(v) for v in r.stdout.split())
    except (OSError, ValueError, subprocess.SubprocessError):
        return None
    return fps, first, last


def remove_import(species: str) -> None:
    """Remove an earlier import of ``species``: its collection, objects, meshes, materials and
    cache file (nothing else: the user's objects and the camera rig stay)."""
    coll = bpy.data.collections.get(f"inflo {species}")
    caches = set()
    if coll is not None:
        for obj in list(coll.all_objects):
            for mod in obj.modifiers:
                if mod.type == "MESH_SEQUENCE_CACHE" and mod.cache_file is not None:
                    caches.add(mod.cache_file)
            data = obj.data
            bpy.data.objects.remove(obj, do_unlink=True)
            if data is not None and data.users == 0:
                if isinstance(data, bpy.types.Mesh):
                    bpy.data.meshes.remove(data)
        for child in list(coll.children):
            bpy.data.collections.remove(child)
        bpy.data.collections.remove(coll)
    stale = [c for c in caches if c.users == 0]
    if stale:  # bpy.data.cache_files has no remove()
        bpy.data.batch_remove(stale)
    for mat in list(bpy.data.materials):
        if mat.get("inflo_species") == species and mat.users == 0:
            bpy.data.materials.remove(mat)


def _linear(rgb):
    return (*core.srgb_to_linear(rgb), 1.0)


def _set(node, name, value):
    sock = node.inputs.get(name)
    if sock is not None:
        sock.default_value = value


# how each kind of organ is shaded: roughness, subsurface weight, translucency (Translucent BSDF mixed in)
SHADING = {
    "petal": (0.45, 0.25, 0.35),
    "leaf": (0.55, 0.05, 0.15),
    "stem": (0.6, 0.0, 0.0),
    "reproductive": (0.5, 0.1, 0.0),
}


def make_material(mat, species: str, usd_name: str, colors, comments) -> str:
    """Rebuild an imported material as the organ it is: Principled BSDF in the species' colour
    (colors.toml, canopy-render's rules), petals with subsurface and a Translucent BSDF mixed in
    (light through a petal), the viewport's solid colour the same. Returns the organ kind."""
    base = None
    if mat.node_tree is not None:
        for node in mat.node_tree.nodes:
            if node.type == "BSDF_PRINCIPLED":
                base = tuple(node.inputs["Base Color"].default_value)
    if usd_name.endswith("_default") and base is not None:
        color = base  # a part without materials: canopy-export's colour of the part (already linear)
    else:
        color = _linear(core.material_color(usd_name, colors))
    kind = core.organ_kind(usd_name, core.material_comment(usd_name, comments))
    rough, sss, translucent = SHADING[kind]
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.location = (600, 0)
    bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")
    bsdf.location = (0, 0)
    _set(bsdf, "Base Color", color)
    _set(bsdf, "Roughness", rough)
    _set(bsdf, "Subsurface Weight", sss)
    _set(bsdf, "Subsurface Radius", (1.0, 0.35, 0.2))
    _set(bsdf, "Subsurface Scale", 0.002)  # metres: a petal is a fraction of a millimetre thick
    _set(bsdf, "Sheen Weight", 0.15 if kind == "petal" else 0.0)
    if translucent > 0:
        tr = nt.nodes.new("ShaderNodeBsdfTranslucent")
        tr.location = (0, -420)
        _set(tr, "Color", color)
        mix = nt.nodes.new("ShaderNodeMixShader")
        mix.location = (350, 0)
        mix.inputs["Fac"].default_value = translucent
        nt.links.new(bsdf.outputs["BSDF"], mix.inputs[1])
        nt.links.new(tr.outputs["BSDF"], mix.inputs[2])
        nt.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    else:
        nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    mat.diffuse_color = color
    mat.roughness = rough
    mat["inflo_species"] = species
    mat["inflo_material"] = usd_name
    mat["inflo_organ"] = kind
    mat.name = f"{species} {usd_name}"
    return kind


def world_points(objects, scene, frames):
    """The objects' evaluated vertices over ``frames``, world space, as an (n, 3) numpy array
    (numpy ships with Blender), at most ~200k of them (evenly thinned beyond)."""
    import numpy as np

    keep = scene.frame_current
    chunks = []
    for f in frames:
        scene.frame_set(f)
        dg = bpy.context.evaluated_depsgraph_get()
        for obj in objects:
            ev = obj.evaluated_get(dg)
            me = ev.to_mesh()
            try:
                co = np.empty(len(me.vertices) * 3, np.float32)
                me.vertices.foreach_get("co", co)
            finally:
                ev.to_mesh_clear()
            co = co.reshape(-1, 3).astype(np.float64)
            step = max(1, len(co) * len(frames) * len(objects) // 200_000)
            m = np.array(ev.matrix_world)
            chunks.append(co[::step] @ m[:3, :3].T + m[:3, 3])
    scene.frame_set(keep)
    pts = np.concatenate(chunks) if chunks else np.empty((0, 3))
    return pts[np.all(np.isfinite(pts), axis=1)]


def camera_fit(points, direction: Vector, tan_h: float, tan_v: float, margin: float = 1.08):
    """Where a camera looking along ``-direction`` sees every point with a margin: returns
    (aim point, distance from it). The aim is set so the points' picture is centred."""
    import numpy as np

    d = np.array(direction, float)
    fwd = -d
    right = np.cross(fwd, [0.0, 0.0, 1.0])
    right = right / np.linalg.norm(right) if np.linalg.norm(right) > 1e-9 else np.array([1.0, 0.0, 0.0])
    up = np.cross(right, fwd)
    centre = (points.min(axis=0) + points.max(axis=0)) / 2
    for _ in range(3):
        v = points - centre
        toward = v @ d
        dist = float(np.max(toward + margin * np.maximum(np.abs(v @ right) / tan_h, np.abs(v @ up) / tan_v)))
        dist = max(dist, 1e-3)
        depth = dist - toward  # > 0: in front of the camera
        x = (v @ right) / depth
        y = (v @ up) / depth
        shift = right * (x.max() + x.min()) / 2 + up * (y.max() + y.min()) / 2
        if np.linalg.norm(shift) * dist < 1e-4 * dist:
            break
        centre = centre + shift * dist
    return Vector(centre), dist


def rig_collection(scene):
    coll = bpy.data.collections.get(RIG_COLLECTION)
    if coll is None:
        coll = bpy.data.collections.new(RIG_COLLECTION)
    if coll.name not in scene.collection.children:
        scene.collection.children.link(coll)
    return coll


def frame_scene(scene, points, azimuth=30.0, elevation=35.0, fov=30.0) -> list[str]:
    """A camera and a three-light rig framing ``points`` (world space) where the scene has
    none (or where they are this add-on's, re-aimed at what was imported last). Returns what it
    added or moved."""
    done = []
    lo, hi = Vector(points.min(axis=0)), Vector(points.max(axis=0))
    centre, radius = (lo + hi) / 2, max((hi - lo).length / 2, 1e-4)
    az, el = math.radians(azimuth), math.radians(elevation)
    direction = Vector((math.cos(el) * math.sin(az), -math.cos(el) * math.cos(az), math.sin(el)))
    cam = scene.camera
    if cam is None or cam.get("inflo_rig"):
        if cam is None:
            data = bpy.data.cameras.new("inflo camera")
            cam = bpy.data.objects.new("inflo camera", data)
            cam["inflo_rig"] = True
            rig_collection(scene).objects.link(cam)
            scene.camera = cam
            done.append("camera")
        data = cam.data
        data.type = "PERSP"
        data.sensor_fit = "VERTICAL"
        data.angle_y = math.radians(fov)
        aspect = (scene.render.resolution_x * scene.render.pixel_aspect_x) / max(
            1, scene.render.resolution_y * scene.render.pixel_aspect_y)
        tan_v = math.tan(math.radians(fov) / 2)
        centre, dist = camera_fit(points, direction, tan_v * aspect, tan_v)
        cam.location = centre + direction * dist
        cam.rotation_mode = "QUATERNION"
        cam.rotation_quaternion = (-direction).to_track_quat("-Z", "Y")
        data.clip_start = dist / 1000
        data.clip_end = dist * 100
        data.dof.focus_distance = dist
        if "camera" not in done:
            done.append("camera re-aimed")
    has_light = any(o.type == "LIGHT" and not o.get("inflo_rig") for o in scene.objects)
    if not has_light:
        rig = [("inflo key", 0.0, 40.0, 2.5, 1.0), ("inflo fill", 110.0, 15.0, 3.0, 0.35),
               ("inflo rim", 200.0, 55.0, 2.5, 0.8)]
        for name, daz, elv, far, share in rig:
            obj = bpy.data.objects.get(name)
            if obj is None or obj.type != "LIGHT":
                light = bpy.data.lights.new(name, "AREA")
                obj = bpy.data.objects.new(name, light)
                obj["inflo_rig"] = True
                rig_collection(scene).objects.link(obj)
                done.append(name)
            a, e = math.radians(azimuth + daz - 40.0), math.radians(elv)
            d = Vector((math.cos(e) * math.sin(a), -math.cos(e) * math.cos(a), math.sin(e)))
            dist = far * radius * 2
            obj.location = centre + d * dist
            obj.rotation_mode = "QUATERNION"
            obj.rotation_quaternion = (-d).to_track_quat("-Z", "Y")
            obj.data.shape = "DISK"
            obj.data.size = radius * 2.0
            # the light on the flower the same whatever its size: power grows with distance squared
            obj.data.energy = 30.0 * share * dist * dist
    if scene.world is None:
        world = bpy.data.worlds.new("inflo sky")
        world.use_nodes = True
        bg = world.node_tree.nodes.get("Background")
        if bg is not None:
            bg.inputs["Color"].default_value = (0.42, 0.55, 0.72, 1.0)
            bg.inputs["Strength"].default_value = 0.35
        world["inflo_rig"] = True
        scene.world = world
        done.append("world")
    return done


def import_build(context, directory, frame: bool = True) -> tuple[str, str]:
    """Import ``directory`` (a species build): returns (report level, one line)."""
    d = Path(bpy.path.abspath(str(directory))).expanduser()
    if not str(directory).strip():
        return "ERROR", "no build folder given (build/<species> of the inflo project)"
    if not d.is_dir():
        return "ERROR", f"{d}: no such build folder (build it first: Build, or make {d.name})"
    usd = usd_of(d)
    if usd is None:
        return "ERROR", f"{d}: no {d.name}.usdc in it (the build's usd stage: make -C pipelines/{d.name} usd)"
    species = d.name
    project = project_of_build(d)
    colors, comments = {}, {}
    if project is not None:
        try:
            colors, comments = core.load_colors(project / "pipelines" / species / "colors.toml")
        except ValueError as exc:
            return "ERROR", str(exc)
    scene = context.scene
    remove_import(species)
    coll = bpy.data.collections.new(f"inflo {species}")
    scene.collection.children.link(coll)
    coll["inflo_species"] = species
    coll["inflo_usd"] = str(usd)
    view_layer = context.view_layer
    previous = view_layer.active_layer_collection
    view_layer.active_layer_collection = view_layer.layer_collection.children[coll.name]
    objs_before = set(bpy.data.objects)
    mats_before = set(bpy.data.materials)
    try:
        result = bpy.ops.wm.usd_import(filepath=str(usd), set_frame_range=True, import_materials=True,
                                       read_mesh_uvs=True, read_mesh_colors=True)
    except RuntimeError as exc:
        err = str(exc).strip().splitlines()[-1] if str(exc).strip() else "import failed"
        return "ERROR", f"{usd}: Blender's USD import failed: {err}"
    finally:
        view_layer.active_layer_collection = previous
    if "FINISHED" not in result:
        return "ERROR", f"{usd}: Blender's USD import failed"
    new = [o for o in bpy.data.objects if o not in objs_before]
    for obj in new:
        if coll not in obj.users_collection:
            for other in list(obj.users_collection):
                other.objects.unlink(obj)
            coll.objects.link(obj)
    meshes = [o for o in new if o.type == "MESH"]
    kinds = {}
    for mat in [m for m in bpy.data.materials if m not in mats_before]:
        usd_name = re.sub(r"\.\d{3}$", "", mat.name)
        kinds[usd_name] = make_material(mat, species, usd_name, colors, comments)
    for obj in meshes:
        obj.data.shade_smooth()
        obj["inflo_species"] = species
    timing = usd_timing(usd, project)
    if timing is not None:
        fps, first, last = timing
        scene.render.fps = max(1, round(fps))
        scene.render.fps_base = scene.render.fps / fps
        scene.frame_start, scene.frame_end = int(round(first)), int(round(last))
    scene.frame_set(scene.frame_start)
    added = []
    if frame and meshes:
        mid = (scene.frame_start + scene.frame_end) // 2
        points = world_points(meshes, scene, sorted({scene.frame_start, mid, scene.frame_end}))
        if len(points):
            added = frame_scene(scene, points)
    for obj in view_layer.objects:
        obj.select_set(obj in new)
    roots = [o for o in new if o.parent is None]
    if roots:
        view_layer.objects.active = roots[0]
    fps = scene.render.fps / scene.render.fps_base
    petals = sum(1 for k in kinds.values() if k == "petal")
    msg = (f"inflo: imported {species}: {len(meshes)} animated part(s), {len(kinds)} material(s) "
           f"({petals} translucent), frames {scene.frame_start}-{scene.frame_end} at {fps:g} fps")
    if added:
        msg += f"; added {', '.join(added)}"
    return "INFO", msg


class INFLO_OT_import_build(bpy.types.Operator):
    """Import an inflo build (build/<species>): its USD animation, materials, camera and lights"""

    bl_idname = "inflo.import_build"
    bl_label = "Import inflo build"
    bl_options = {"REGISTER", "UNDO"}

    directory: StringProperty(name="Build folder", subtype="DIR_PATH",
                              description="build/<species> of the inflo project")
    frame: BoolProperty(name="Camera and lights", default=True,
                        description="Add a camera and lights framing it when the scene has none")

    def invoke(self, context, event):
        if not self.directory:
            settings = context.scene.inflo
            project = project_of(settings)
            if project and settings.species not in ("", "NONE"):
                self.directory = str(core.build_dir(project, settings.species))
            else:
                context.window_manager.fileselect_add(self)
                return {"RUNNING_MODAL"}
        return self.execute(context)

    def execute(self, context):
        level, msg = import_build(context, self.directory, self.frame)
        self.report({level}, msg)
        if level != "INFO":
            return {"CANCELLED"}
        if bpy.app.background:
            print(msg)
        return {"FINISHED"}


# ------------------------------------------------------------------------------------ building

_running: dict = {}  # the one build at a time: {"build": core.BuildProcess}


class INFLO_OT_build(bpy.types.Operator):
    """Build an inflo species with the project's make (a subprocess), then import it. Esc cancels"""

    bl_idname = "inflo.build"
    bl_label = "Build inflo species"
    bl_options = {"REGISTER"}

    species: StringProperty(name="Species", description="A folder of pipelines/ (empty: the panel's)")
    quality: EnumProperty(name="Quality", items=QUALITY_ITEMS, default="draft")
    project: StringProperty(name="Project", subtype="DIR_PATH",
                            description="The inflo repository (empty: the panel's or the preferences')")
    scope: EnumProperty(name="Build", items=SCOPE_ITEMS, default="usd")
    import_after: BoolProperty(name="Import", default=True, description="Import the build when it is done")

    _timer = None

    def _resolve(self, context):
        settings = getattr(context.scene, "inflo", None)
        project = bpy.path.abspath(self.project) if self.project else project_of(settings)
        name = self.species or (settings.species if settings is not None else "")
        if name in ("", "NONE"):
            err = core.project_error(project)
            raise ValueError(err or "no species given")
        return project, core.species_by_name(project, name)

    def invoke(self, context, event):
        settings = context.scene.inflo
        if not self.properties.is_property_set("quality"):
            self.quality = settings.quality
        if not self.properties.is_property_set("scope"):
            self.scope = settings.scope
        return self.execute(context)

    def execute(self, context):
        if _running.get("build") is not None:
            self.report({"ERROR"}, "inflo: a build is running already (Esc cancels it)")
            return {"CANCELLED"}
        try:
            project, species = self._resolve(context)
            build = core.BuildProcess(project, species, self.quality, self.scope)
        except ValueError as exc:
            self.report({"ERROR"}, f"inflo: {exc}")
            return {"CANCELLED"}
        if bpy.app.background or context.window is None:
            return self._run_sync(context, build)
        try:
            build.start()
        except OSError as exc:
            self.report({"ERROR"}, f"inflo: cannot run make: {exc}")
            return {"CANCELLED"}
        _running["build"] = build
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.25, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0, 1000)
        self._status(context, build)
        return {"RUNNING_MODAL"}

    def _run_sync(self, context, build):
        last = [""]

        def on_line(stream, line):
            line = line.rstrip("\n")
            if stream == "err" and line:
                print(line)
            text = build.progress.text()
            if text != last[0]:
                last[0] = text
                print(f"inflo: {text}", flush=True)

        try:
            build.run(on_line)
        except OSError as exc:
            self.report({"ERROR"}, f"inflo: cannot run make: {exc}")
            return {"CANCELLED"}
        return self._finish(context, build)

    def _status(self, context, build):
        text = f"inflo: {build.progress.text()} — Esc to cancel"
        context.workspace.status_text_set(text)
        context.window_manager.progress_update(int(1000 * build.progress.fraction()))
        for area in context.screen.areas if context.screen else ():
            if area.type == "VIEW_3D":
                area.tag_redraw()

    def modal(self, context, event):
        build = _running.get("build")
        if build is None:
            return self._end(context, {"CANCELLED"})
        if event.type == "ESC" and event.value == "PRESS":
            build.cancel()
            self.report({"WARNING"}, f"inflo: {build.species.name} build cancelled at "
                                     f"{build.progress.text()} (finished stages are kept)")
            return self._end(context, {"CANCELLED"})
        if event.type == "TIMER":
            changed, _ = build.pump()
            if build.done:
                result = self._finish(context, build)
                return self._end(context, result)
            if changed:
                self._status(context, build)
        return {"PASS_THROUGH"}

    def _end(self, context, result):
        _running.pop("build", None)
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)
        return result

    def _finish(self, context, build):
        secs = f"{build.progress.species} ({build.quality}) in {_duration(build)}"
        if build.returncode != 0:
            if build.cancelled:
                self.report({"WARNING"}, f"inflo: build cancelled: {secs}")
            else:
                self.report({"ERROR"}, f"inflo: {build.species.name} failed at {build.progress.stage}: "
                                       f"{build.error()}")
            return {"CANCELLED"}
        msg = f"inflo: built {secs}"
        if self.import_after:
            level, imported = import_build(context, core.build_dir(build.project, build.species.name))
            self.report({level}, f"{msg}; {imported.removeprefix('inflo: ')}")
            if level != "INFO":
                return {"CANCELLED"}
        else:
            self.report({"INFO"}, msg)
        if bpy.app.background:
            print(msg)
        return {"FINISHED"}


def _duration(build) -> str:
    import time

    s = time.monotonic() - build.started
    return f"{s:.0f} s" if s < 120 else f"{s / 60:.1f} min"


# ---------------------------------------------------------------------------------------- panel

class VIEW3D_PT_inflo(bpy.types.Panel):
    bl_label = "inflo"
    bl_idname = "VIEW3D_PT_inflo"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "inflo"

    def draw(self, context):
        layout = self.layout
        settings = context.scene.inflo
        layout.prop(settings, "project")
        project = project_of(settings)
        err = core.project_error(project)
        if err:
            box = layout.box()
            box.label(text=err if len(err) < 90 else err[:87] + "...", icon="ERROR")
            if not settings.project and not default_project():
                box.label(text="Set it here or in the add-on's preferences", icon="INFO")
            return
        if not (Path(project) / ".venv" / "bin" / "python").is_file():
            layout.label(text="No .venv yet: the first build makes it (minutes)", icon="INFO")
        layout.prop(settings, "species")
        row = layout.row(align=True)
        row.prop(settings, "quality", expand=True)
        layout.prop(settings, "scope")
        build = _running.get("build")
        if build is not None:
            col = layout.column()
            col.label(text=build.progress.text(), icon="SORTTIME")
            col.label(text="Esc cancels")
        else:
            op = layout.operator(INFLO_OT_build.bl_idname, text="Build", icon="PLAY")
            op.species = settings.species if settings.species != "NONE" else ""
            op.quality = settings.quality
            op.scope = settings.scope
            op.project = project
        if settings.species not in ("", "NONE"):
            d = core.build_dir(project, settings.species)
            usd = usd_of(d) if d.is_dir() else None
            row = layout.row()
            row.enabled = usd is not None
            op = row.operator(INFLO_OT_import_build.bl_idname, text="Import build", icon="IMPORT")
            op.directory = str(d)
            if usd is None:
                layout.label(text=f"{settings.species} is not built yet", icon="INFO")
            else:
                q = d / "quality.txt"
                built = q.read_text().strip() if q.is_file() else "?"
                layout.label(text=f"built: {built} quality", icon="CHECKMARK")


CLASSES = (InfloPreferences, InfloSettings, INFLO_OT_import_build, INFLO_OT_build, VIEW3D_PT_inflo)


def menu_import(self, context):
    self.layout.operator(INFLO_OT_import_build.bl_idname, text="inflo build (USD + materials)")


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.inflo = PointerProperty(type=InfloSettings)
    bpy.types.TOPBAR_MT_file_import.append(menu_import)


def unregister():
    build = _running.pop("build", None)
    if build is not None:
        build.cancel()
    bpy.types.TOPBAR_MT_file_import.remove(menu_import)
    del bpy.types.Scene.inflo
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
