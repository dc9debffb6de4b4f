"""The USD writer of ``canopy-export`` (spec: ``formats/usd.md``), through ``usd-core`` (``pxr``).

:class:`UsdBuilder` collects the frames of every part in an in-memory stage; :meth:`UsdBuilder.save`
writes it once, atomically (``.usdc`` binary crate, ``.usda`` text, ``.usd`` binary). The layout::

    /<root>                   Xform, the stage's default prim (named after the output file)
        /<part>               Mesh: points, extent (time-sampled), faceVertexCounts/Indices
                              (once, or sampled where the faces change), optional normals,
                              an xformOp:translate where --translate moves the part
            /<material>       GeomSubset, family materialBind, the faces of one OBJ usemtl
        /Materials/<material> Material with a UsdPreviewSurface (diffuseColor in linear RGB)

Frame ``k`` of the sequences (0-based) is time code ``start_frame + k``.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from inflo.formats.atomic import atomic_path
from inflo.formats.obj import ObjMesh
from inflo.tools.common import linalg as la

__all__ = ["USD_SUFFIXES", "SUBSET_MODES", "srgb_to_linear", "vertex_normals", "points_extent", "UsdBuilder"]

USD_SUFFIXES = (".usdc", ".usda", ".usd")
"""Output suffixes: binary crate, text, binary (usd-core's default for ``.usd``)."""

SUBSET_MODES = ("material", "floret")
"""``--subsets``: GeomSubsets per material of a part only, or also one per OBJ group (floret)."""

FLORET_FAMILY = "floret"
"""The family name of the per-floret subsets (``--subsets floret``)."""

RGB = tuple[float, float, float]


def srgb_to_linear(rgb) -> np.ndarray:
    """sRGB colour components in 0..1 -> linear (the IEC 61966-2-1 transfer function)."""
    c = np.asarray(rgb, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals ``(n, 3) float32``; zero for a vertex of no (or only
    zero-area) faces, so degenerate input divides by nothing."""
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    acc = np.zeros_like(v)
    if len(f):
        fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
        # each face's normal added to its corners', corner 0 of every face first, then 1, then 2:
        # bincount sums in that order, as ``np.add.at`` per corner would, so the same bits, faster
        corners = f.T.reshape(-1)
        for c in range(3):
            acc[:, c] = np.bincount(corners, weights=np.tile(fn[:, c], 3), minlength=len(v))
    length = la.norm(acc, axis=1, keepdims=True)
    out = np.divide(acc, length, out=np.zeros_like(acc), where=length > 0)
    return out.astype(np.float32)


def points_extent(points: np.ndarray) -> np.ndarray:
    """The bounding box of ``points`` ``(n, 3) float32``: ``(2, 3) float32``, its min and max
    corners (zeros for no points), the Mesh's ``extent``."""
    if not len(points):
        return np.zeros((2, 3), np.float32)
    # per coordinate over a contiguous row: some 40 times faster than reducing (n, 3) along
    # axis 0, the transposed copy included (min and max are exact, so the same values)
    rows = np.ascontiguousarray(np.asarray(points, dtype=np.float32).T)
    return np.stack([rows.min(axis=1), rows.max(axis=1)])


@dataclass
class _Topology:
    """One sample of a part's faces: from ``frame`` on (0-based)."""

    frame: int
    counts: np.ndarray  # (m,) int32
    indices: np.ndarray  # (3m,) int32
    subsets: dict = field(default_factory=dict)  # material name -> (k,) int32 face indices
    florets: dict = field(default_factory=dict)  # OBJ group name -> (k,) int32 face indices
    face_material: np.ndarray | None = None  # (m,) int32 index into the part's materials, -1 none
    unbound: bool = False  # some faces have no material


@dataclass
class _PartState:
    name: str
    static: bool
    default_color: RGB
    topology: list = field(default_factory=list)
    materials: list = field(default_factory=list)  # names in order of first appearance
    groups: list = field(default_factory=list)  # OBJ group names with faces (--subsets floret), in order


class UsdBuilder:
    """A USD stage of one export, filled frame by frame.

    Parameters
    ----------
    root_name : str
        Name of the root Xform (a valid prim name).
    part_names : list of str
        The Mesh prims, in order (valid, unique prim names).
    static : list of bool
        Per part: a static part has one mesh (points and faces written once, not time-sampled).
    material_color : callable
        ``material_color(name) -> (r, g, b)`` sRGB in 0..1, the colour of an OBJ material.
    default_colors : list of (r, g, b)
        Per part, the sRGB colour of faces without a material.
    n_frames, start_frame, fps, meters_per_unit : number
        Time range (``start_frame`` .. ``start_frame + n_frames - 1``), time codes per second,
        the stage's metres per unit.
    normals : bool
        Also write per-vertex normals (time-sampled with the points).
    subsets : {"material", "floret"}
        ``material``: one GeomSubset per OBJ material (family ``materialBind``, bound to it);
        ``floret``: also one per OBJ group (``g``, a floret of a canopy), family ``floret``,
        bound to nothing (Blender 4.5 gives every materialBind subset a slot of its own and
        leaves all but the first of a material empty, so per-floret binding broke its colours).
    translate : dict
        Part name -> (x, y, z): an ``xformOp:translate`` on that part's Mesh prim.
    """

    def __init__(self, root_name: str, part_names: Sequence[str], static: Sequence[bool], *,
                 material_color, default_colors: Sequence[RGB], n_frames: int, start_frame: float = 1.0,
                 fps: float = 24.0, meters_per_unit: float = 0.01, normals: bool = False,
                 subsets: str = "material", translate=None):
        from pxr import Gf, Sdf, Usd, UsdGeom

        if subsets not in SUBSET_MODES:
            raise ValueError(f"subsets must be one of {', '.join(SUBSET_MODES)}, got {subsets!r}")
        self.subset_mode = subsets

        self._material_color = material_color
        self.n_frames = int(n_frames)
        self.start_frame = float(start_frame)
        self.normals = normals
        self.stage = stage = Usd.Stage.CreateInMemory()
        stage.GetRootLayer().documentation = "inflo canopy-export: growth animation (formats/usd.md)"
        UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
        UsdGeom.SetStageMetersPerUnit(stage, float(meters_per_unit))
        stage.SetStartTimeCode(self.start_frame)
        stage.SetEndTimeCode(self.start_frame + self.n_frames - 1)
        stage.SetTimeCodesPerSecond(float(fps))
        stage.SetFramesPerSecond(float(fps))
        self.root = Sdf.Path("/" + root_name)
        root = UsdGeom.Xform.Define(stage, self.root)
        stage.SetDefaultPrim(root.GetPrim())
        self._parts = [
            _PartState(name=n, static=bool(s), default_color=tuple(c))
            for n, s, c in zip(part_names, static, default_colors)
        ]
        self._meshes = []
        self._finished = False
        self.material_names: list[str] = []
        """The materials written (OBJ material names; ``<part>_default`` for faces without one)."""
        for st in self._parts:
            mesh = UsdGeom.Mesh.Define(stage, self.root.AppendChild(st.name))
            mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
            mesh.CreateDoubleSidedAttr(True)
            mesh.CreateOrientationAttr(UsdGeom.Tokens.rightHanded)
            if st.name in (translate or {}):
                mesh.AddTranslateOp().Set(Gf.Vec3d(*map(float, translate[st.name])))
            self._meshes.append(mesh)

    def time(self, frame: int) -> float:
        """The time code of 0-based ``frame``."""
        return self.start_frame + frame

    def add_frame(self, frame: int, meshes: Sequence[ObjMesh | None], changed: Sequence[bool]) -> None:
        """Add 0-based ``frame``: one mesh per part (None: a static part after frame 0), and per
        part whether its faces or materials changed since the previous frame."""
        from pxr import Usd, Vt

        for st, usd_mesh, mesh, change in zip(self._parts, self._meshes, meshes, changed):
            if mesh is None:
                continue
            t = Usd.TimeCode.Default() if st.static else Usd.TimeCode(self.time(frame))
            pts = np.ascontiguousarray(mesh.vertices, dtype=np.float32)
            usd_mesh.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy(pts), t)
            usd_mesh.GetExtentAttr().Set(Vt.Vec3fArray.FromNumpy(points_extent(pts)), t)
            if self.normals:
                if mesh.normals is not None:
                    nrm = np.ascontiguousarray(mesh.normals, dtype=np.float32)
                else:
                    nrm = vertex_normals(mesh.vertices, mesh.faces)
                usd_mesh.GetNormalsAttr().Set(Vt.Vec3fArray.FromNumpy(nrm), t)
            if change:
                topo = self._topology(st, frame, mesh)
                self._florets(st, topo, mesh)
                st.topology.append(topo)

    def _topology(self, st: _PartState, frame: int, mesh: ObjMesh) -> _Topology:
        m = mesh.n_faces
        topo = _Topology(frame=frame, counts=np.full(m, 3, np.int32),
                         indices=np.ascontiguousarray(mesh.faces, dtype=np.int32).reshape(-1))
        if mesh.face_material is None or not np.any(mesh.face_material >= 0):
            topo.unbound = m > 0  # the part's default material, bound on the Mesh
            return topo
        # faces before any usemtl, among faces with one, take the part's default material in a
        # subset of their own (Blender ignores a Mesh's own binding once it has subsets)
        names = [*mesh.materials, default_material(st.name)]
        face_mat = np.where(mesh.face_material < 0, len(mesh.materials), mesh.face_material)
        for k, name in enumerate(names):
            if name not in st.materials and np.any(face_mat == k):
                st.materials.append(name)
        # the face's material as an index into the part's materials (order of first appearance)
        remap = np.array([st.materials.index(n) if n in st.materials else -1 for n in names], np.int32)
        topo.face_material = remap[face_mat]
        mesh = replace(mesh, materials=names, face_material=face_mat.astype(np.int32))
        for k, name in enumerate(mesh.materials):
            faces = np.flatnonzero(mesh.face_material == k).astype(np.int32)
            if len(faces):
                topo.subsets[name] = faces
        return topo

    def _florets(self, st: _PartState, topo: _Topology, mesh: ObjMesh) -> None:
        """``--subsets floret``: the faces of each OBJ group (a canopy's floret), in ``topo.florets``."""
        if self.subset_mode != "floret" or mesh.face_group is None:
            return
        order = np.argsort(mesh.face_group, kind="stable")
        bounds = np.flatnonzero(np.diff(mesh.face_group[order])) + 1
        for run in np.split(order, bounds):
            if len(run) and mesh.face_group[run[0]] >= 0:
                name = mesh.groups[int(mesh.face_group[run[0]])]
                topo.florets[name] = np.sort(run).astype(np.int32)
                if name not in st.groups:
                    st.groups.append(name)

    def _write_topology(self) -> None:
        """Faces and subsets of every part and the materials they bind (once, after the last
        frame); sets :attr:`material_names`."""
        from pxr import Usd, UsdGeom, UsdShade, Vt

        if self._finished:
            return
        self._finished = True

        materials: dict[str, object] = {}
        prim_names: dict[str, str] = {}

        def material(name: str, rgb_srgb: RGB):
            if name not in materials:
                base = _unique(_prim_name(name), set(prim_names.values()))
                prim_names[name] = base
                materials[name] = _define_material(self.stage, self.root.AppendPath(f"Materials/{base}"),
                                                   srgb_to_linear(rgb_srgb))
            return materials[name]

        UsdGeom.Scope.Define(self.stage, self.root.AppendChild("Materials"))
        for st, usd_mesh in zip(self._parts, self._meshes):
            samples = st.topology
            one = len(samples) == 1
            times = [Usd.TimeCode.Default() if one else Usd.TimeCode(self.time(s.frame)) for s in samples]
            counts_attr = usd_mesh.GetFaceVertexCountsAttr()
            index_attr = usd_mesh.GetFaceVertexIndicesAttr()
            for s, t in zip(samples, times):
                counts_attr.Set(Vt.IntArray.FromNumpy(s.counts), t)
                index_attr.Set(Vt.IntArray.FromNumpy(s.indices), t)
            prim = usd_mesh.GetPrim()
            if any(s.unbound for s in samples):
                key = default_material(st.name)
                mat = material(key, st.default_color)
                UsdShade.MaterialBindingAPI.Apply(prim).Bind(mat)
            used: set[str] = set()
            if st.materials:
                self._write_material_subsets(st, usd_mesh, samples, one, times, used, material)
            for group in st.groups:  # --subsets floret: selection sets, bound to nothing
                sub_name = _unique(_prim_name(group), used)
                used.add(sub_name)
                subset = UsdGeom.Subset.Define(self.stage, prim.GetPath().AppendChild(sub_name))
                subset.CreateElementTypeAttr(UsdGeom.Tokens.face)
                subset.CreateFamilyNameAttr(FLORET_FAMILY)
                ind = subset.CreateIndicesAttr()
                for s, t in zip(samples, times):
                    ind.Set(Vt.IntArray.FromNumpy(s.florets.get(group, np.zeros(0, np.int32))), t)
            if st.groups:
                UsdGeom.Subset.SetFamilyType(usd_mesh, FLORET_FAMILY, UsdGeom.Tokens.nonOverlapping)
        self.material_names = list(materials)

    def _write_material_subsets(self, st, usd_mesh, samples, one, times, used, material) -> None:
        """A part's materialBind subsets, and where its faces change the material_index primvar."""
        from pxr import Sdf, UsdGeom, UsdShade, Vt

        prim = usd_mesh.GetPrim()
        binding = UsdShade.MaterialBindingAPI.Apply(prim)
        # subsets in the order of their material's first appearance, which is the order in
        # which Blender numbers its material slots
        for name in st.materials:
            sub_name = _unique(_prim_name(name), used)
            used.add(sub_name)
            subset = UsdGeom.Subset.Define(self.stage, prim.GetPath().AppendChild(sub_name))
            subset.CreateElementTypeAttr(UsdGeom.Tokens.face)
            subset.CreateFamilyNameAttr(UsdShade.Tokens.materialBind)
            ind = subset.CreateIndicesAttr()
            for s, t in zip(samples, times):
                ind.Set(Vt.IntArray.FromNumpy(s.subsets.get(name, np.zeros(0, np.int32))), t)
            rgb = st.default_color if name == default_material(st.name) else self._material_color(name)
            UsdShade.MaterialBindingAPI.Apply(subset.GetPrim()).Bind(material(name, rgb))
        binding.SetMaterialBindSubsetsFamilyType(UsdGeom.Tokens.nonOverlapping)
        if not one:
            # Blender's Mesh Sequence Cache reads the subsets once, at import, and keeps those
            # face numbers in every frame; where the faces change, each face's material also
            # goes as a per-face primvar that it reads every frame (its attribute material_index)
            pv = UsdGeom.PrimvarsAPI(prim).CreatePrimvar(
                "material_index", Sdf.ValueTypeNames.IntArray, UsdGeom.Tokens.uniform)
            for s, t in zip(samples, times):
                fm = s.face_material if s.face_material is not None else np.zeros(len(s.counts), np.int32)
                pv.Set(Vt.IntArray.FromNumpy(np.ascontiguousarray(fm, dtype=np.int32)), t)

    def save(self, path) -> None:
        """Write the stage to ``path`` atomically (format by suffix, :data:`USD_SUFFIXES`)."""
        self._write_topology()
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix not in USD_SUFFIXES:
            raise ValueError(f"{path}: expected a {', '.join(USD_SUFFIXES)} file name")
        from pxr import Sdf

        with atomic_path(path) as tmp:
            # the temporary name ends .part (inflo's atomic writes), so the format is given, not guessed
            layer = Sdf.Layer.New(Sdf.FileFormat.FindByExtension(suffix.lstrip(".")), tmp)
            layer.TransferContent(self.stage.GetRootLayer())
            if not layer.Save():
                raise OSError(f"{path}: USD could not write the file")
            del layer

    def to_string(self) -> str:
        """The stage as USDA text (for tests and diffs)."""
        self._write_topology()
        return self.stage.GetRootLayer().ExportToString()


def default_material(part: str) -> str:
    """The material of a part's faces without ``usemtl`` (canopy-render's colour of the part's input)."""
    return f"{part}_default"


def _prim_name(text: str) -> str:
    from .parts import prim_name

    return prim_name(text)


def _unique(name: str, taken: set[str]) -> str:
    if name not in taken:
        return name
    k = 1
    while f"{name}_{k}" in taken:
        k += 1
    return f"{name}_{k}"


def _define_material(stage, path, linear_rgb):
    """A Material at ``path`` whose surface is a UsdPreviewSurface of diffuse colour ``linear_rgb``."""
    from pxr import Gf, Sdf, UsdShade

    mat = UsdShade.Material.Define(stage, path)
    shader = UsdShade.Shader.Define(stage, path.AppendChild("PreviewSurface"))
    shader.CreateIdAttr("UsdPreviewSurface")
    shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*map(float, linear_rgb)))
    shader.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(0.6)
    shader.CreateInput("metallic", Sdf.ValueTypeNames.Float).Set(0.0)
    mat.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    return mat
