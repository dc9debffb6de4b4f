"""The binary glTF 2.0 writer of ``canopy-export`` (spec: ``formats/gltf.md``), numpy only.

:class:`GltfBuilder` collects every frame of every part and :meth:`GltfBuilder.save` writes one
``.glb`` at the end, atomically. A part is one node and one mesh; its faces are the union of the
faces of every frame, one primitive per material (all primitives share the part's POSITION and
morph targets); frame 0 is the base shape and frame *k* (k >= 1) is morph target *k - 1*, whose
weight one animation ("growth") drives: at time *k / fps* target *k - 1* has weight 1 and every
other 0, linear in between. Faces that are not yet in a frame (florets emerging) are hidden by
collapsing the vertices no face of that frame uses onto one point per connected piece of the
mesh, so their triangles have no area; they grow out of that point as the weights blend.

With ``quantize`` (the default) positions and morph deltas are normalized 16-bit integers
(``KHR_mesh_quantization``), the part's node carrying the offset and scale that restore them.
"""
from __future__ import annotations

import json
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from inflo.formats.atomic import atomic_write
from inflo.formats.errors import InputError

__all__ = ["GLTF_SUFFIXES", "GltfBuilder", "glb_chunks"]

GLTF_SUFFIXES = (".glb",)

_FLOAT, _SHORT, _USHORT, _UINT = 5126, 5122, 5123, 5125
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963


@dataclass
class _Part:
    name: str
    static: bool
    default_color: tuple
    positions: list = field(default_factory=list)  # per frame (n, 3) float64
    samples: list = field(default_factory=list)  # (frame, faces (m,3) int64, material name per face)


def glb_chunks(data: bytes) -> tuple[dict, bytes]:
    """Split a ``.glb`` into its JSON document and BIN chunk (raises ValueError when malformed)."""
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    if magic != b"glTF" or version != 2 or length != len(data):
        raise ValueError("not a glTF 2.0 binary (magic, version or length)")
    n, kind = struct.unpack_from("<I4s", data, 12)
    if kind != b"JSON":
        raise ValueError("first chunk is not JSON")
    doc = json.loads(data[20:20 + n].decode("utf-8"))
    pos = 20 + n
    binary = b""
    if pos < len(data):
        m, kind = struct.unpack_from("<I4s", data, pos)
        if kind != b"BIN\x00":
            raise ValueError("second chunk is not BIN")
        binary = data[pos + 8:pos + 8 + m]
    return doc, binary


def _components(n: int, faces: np.ndarray) -> np.ndarray:
    """Connected piece of every vertex (by the faces; a vertex of no face is a piece of its own)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    if not len(faces):
        return np.arange(n)
    a = np.concatenate([faces[:, 0], faces[:, 1]])
    b = np.concatenate([faces[:, 1], faces[:, 2]])
    graph = coo_matrix((np.ones(len(a), np.int8), (a, b)), shape=(n, n))
    return connected_components(graph, directed=False)[1]


class GltfBuilder:
    """A glTF document of one export, filled frame by frame (see the module docstring).

    Parameters
    ----------
    root_name : str
        Name of the root node (its scale is ``meters_per_unit``: glTF's unit is the metre).
    part_names, static : list
        The parts in order; a static part has one mesh and no morph targets.
    material_color : callable
        ``material_color(name) -> (r, g, b)`` sRGB in 0..1.
    default_colors : list
        Per part, the sRGB colour of faces without a material.
    n_frames, fps, start_frame, meters_per_unit : number
    quantize : bool
        Normalized 16-bit positions and deltas (``KHR_mesh_quantization``) instead of float32.
    extras : dict
        Written as the scene's ``extras`` (title, figures: what the viewer page shows).
    translate : dict
        Part name -> (x, y, z) added to its node's translation (``--translate``).
    """

    def __init__(self, root_name, part_names, static, *, material_color, default_colors, n_frames, fps,
                 start_frame=1, meters_per_unit=0.01, quantize=True, extras=None, translate=None):
        self.root_name = root_name
        self.parts = [_Part(n, s, tuple(c)) for n, s, c in zip(part_names, static, default_colors)]
        self.material_color = material_color
        self.n_frames, self.fps, self.start_frame = n_frames, fps, start_frame
        self.meters_per_unit = meters_per_unit
        self.quantize = quantize
        self.extras = dict(extras or {})
        self.translate = dict(translate or {})
        self.material_names: list[str] = []
        self.faces_not_hidden = 0
        """The most faces of one frame that are not in it but share a vertex with one that is (shown)."""

    def add_frame(self, k: int, meshes, changed) -> None:
        for part, mesh, change in zip(self.parts, meshes, changed):
            if mesh is None:
                continue
            v = np.asarray(mesh.vertices, dtype=np.float64)
            part.positions.append(v)
            if change:
                if mesh.face_material is None:
                    names = [None] * len(mesh.faces)
                else:
                    lut = list(mesh.materials)
                    names = [lut[i] if i >= 0 else None for i in mesh.face_material.tolist()]
                part.samples.append((k, np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3), names))

    # -- building ------------------------------------------------------------------------------

    def _material_index(self, part: _Part, name) -> int:
        key = name if name is not None else f"{part.name}_default"
        if key not in self.material_names:
            self.material_names.append(key)
        return self.material_names.index(key)

    def _material_indices(self, part: _Part, names: list) -> np.ndarray:
        """(m,) int64: :meth:`_material_index` of each face's material name, the new names
        numbered in order of first appearance (one lookup a distinct name, not a list search a
        face: a final yarrow's 14.7 million faces over its frames)."""
        lut = {nm: self._material_index(part, nm) for nm in dict.fromkeys(names)}
        return np.array([lut[nm] for nm in names], np.int64)

    def build(self) -> tuple[dict, bytes]:
        """The glTF JSON document and its binary buffer."""
        from .usd import srgb_to_linear

        blob = bytearray()
        views, accessors = [], []

        def add_view(data: bytes, target=None, stride=None) -> int:
            while len(blob) % 4:
                blob.append(0)
            view = {"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)}
            if target is not None:
                view["target"] = target
            if stride is not None:
                view["byteStride"] = stride
            blob.extend(data)
            views.append(view)
            return len(views) - 1

        def add_accessor(view, ctype, count, kind, *, lo=None, hi=None, normalized=False) -> int:
            acc = {"bufferView": view, "componentType": ctype, "count": int(count), "type": kind}
            if normalized:
                acc["normalized"] = True
            if lo is not None:
                acc["min"], acc["max"] = [float(x) for x in lo], [float(x) for x in hi]
            accessors.append(acc)
            return len(accessors) - 1

        def vec3(values: np.ndarray, scale: float | None) -> int:
            """An accessor of (n, 3) values: float32, or normalized int16 of values / scale."""
            if scale is None:
                arr = np.ascontiguousarray(values, dtype=np.float32)
                view = add_view(arr.tobytes(), _ARRAY_BUFFER)
                lo, hi = (arr.min(axis=0), arr.max(axis=0)) if len(arr) else ([0] * 3, [0] * 3)
                return add_accessor(view, _FLOAT, len(arr), "VEC3", lo=lo, hi=hi)
            q = np.zeros((len(values), 4), np.int16)  # each element 4-byte aligned: stride 8
            q[:, :3] = np.clip(np.rint(values / scale * 32767.0), -32767, 32767).astype(np.int16)
            view = add_view(q.tobytes(), _ARRAY_BUFFER, stride=8)
            body = q[:, :3]
            lo, hi = (body.min(axis=0), body.max(axis=0)) if len(body) else ([0] * 3, [0] * 3)
            # min and max of a normalized accessor are its stored integers (readers divide them)
            return add_accessor(view, _SHORT, len(q), "VEC3", lo=lo, hi=hi, normalized=True)

        meshes, nodes, channels, samplers = [], [], [], []
        n_targets_max = 0
        n_triangles = 0
        bounds = []  # per part (min, max) over every frame, moved by --translate
        flips = []  # (node, frame) of the flip-book parts' frame nodes
        for part in self.parts:
            if not part.static and len({len(v) for v in part.positions}) > 1:
                # a part whose vertex count changes (branches that grow, rebuilt every frame: their
                # vertex k is not one point through time) is a flip book: a node per frame holding
                # that frame's mesh, shown (scale 1) at its frame only by a STEP animation of scales
                move = np.asarray(self.translate.get(part.name, (0.0, 0.0, 0.0)), dtype=np.float64)
                starts = [smp[0] for smp in part.samples]
                most = 0
                for k, v in enumerate(part.positions):
                    _, fcs, names = part.samples[int(np.searchsorted(starts, k, side="right")) - 1]
                    if not len(v) or not len(fcs):
                        continue
                    v = np.asarray(v, dtype=np.float64)
                    bounds.append((v.min(axis=0) + move, v.max(axis=0) + move))
                    most = max(most, len(fcs))
                    position = vec3(v, None)
                    mats = self._material_indices(part, names)
                    index_type = _USHORT if len(v) < 65535 else _UINT
                    prims = []
                    for m in sorted(set(mats.tolist())):
                        tri = fcs[mats == m].astype(np.uint16 if index_type == _USHORT else np.uint32)
                        view = add_view(tri.tobytes(), _ELEMENT_ARRAY_BUFFER)
                        prims.append({"attributes": {"POSITION": position}, "mode": 4, "material": int(m),
                                      "indices": add_accessor(view, index_type, tri.size, "SCALAR")})
                    meshes.append({"name": f"{part.name}_{k + 1:04d}", "primitives": prims})
                    node = {"name": f"{part.name}_{k + 1:04d}", "mesh": len(meshes) - 1,
                            "scale": [1.0 if k == 0 else 0.0] * 3, "extras": {"part": part.name, "frame": k + 1}}
                    if move.any():
                        node["translation"] = [float(x) for x in move]
                    nodes.append(node)
                    flips.append((len(nodes) - 1, k))
                part.positions = []
                n_triangles += most
                continue
            frames = np.stack(part.positions)  # (F, n, 3)
            part.positions = []
            nv = frames.shape[1]
            # the union of every sample's faces, each with its material, in order of first appearance
            rows, sample_ids = [], []
            for _, faces, names in part.samples:
                mats = self._material_indices(part, names).reshape(-1, 1)
                rows.append(np.hstack([faces, mats]))
            allrows = np.vstack(rows) if rows else np.zeros((0, 4), np.int64)
            uniq, first, inverse = np.unique(allrows, axis=0, return_index=True, return_inverse=True)
            order = np.argsort(first, kind="stable")
            rank = np.empty(len(order), np.int64)
            rank[order] = np.arange(len(order))
            union = uniq[order]
            pos = 0
            for r in rows:
                sample_ids.append(rank[inverse.reshape(-1)[pos:pos + len(r)]])
                pos += len(r)
            faces = union[:, :3]
            n_triangles += len(faces)
            if len(faces) and (faces.min() < 0 or faces.max() >= nv):
                raise InputError(f"{part.name}: a face refers to a vertex beyond the {nv} vertices")
            # hide the faces a frame does not have: its unused vertices collapsed per piece; a vertex
            # that faces of every frame share with faces of some frames only is copied for the latter
            present = np.zeros((len(part.samples), len(union)), bool)
            for j, ids in enumerate(sample_ids):
                present[j, ids] = True
            if not present.all():
                always = present.all(axis=0)
                fixed = np.zeros(nv, bool)
                fixed[faces[always].reshape(-1)] = True
                some = ~always
                shared = np.unique(faces[some][fixed[faces[some]]])
                if len(shared):
                    copy = np.full(nv, -1, np.int64)
                    copy[shared] = nv + np.arange(len(shared))
                    sub = faces[some]
                    sub = np.where(fixed[sub], copy[sub], sub)
                    faces = faces.copy()
                    faces[some] = sub
                    frames = np.concatenate([frames, frames[:, shared]], axis=1)
                    nv = frames.shape[1]
                comp = _components(nv, faces)
                starts = [s[0] for s in part.samples]
                for k in range(len(frames)):
                    j = int(np.searchsorted(starts, k, side="right")) - 1
                    used = np.zeros(nv, bool)
                    used[faces[sample_ids[j]].reshape(-1)] = True
                    absent = ~used
                    if not absent.any():
                        continue
                    idx = np.flatnonzero(absent)
                    labels = comp[idx]
                    cnt = np.bincount(labels, minlength=comp.max() + 1)
                    sums = np.stack([np.bincount(labels, weights=frames[k, idx, c], minlength=comp.max() + 1)
                                     for c in range(3)], axis=1)
                    centre = sums / np.maximum(cnt, 1)[:, None]
                    frames[k, idx] = centre[labels]
                    shown = ~present[j] & used[faces].any(axis=1)
                    self.faces_not_hidden = max(self.faces_not_hidden, int(shown.sum()))
            move = np.asarray(self.translate.get(part.name, (0.0, 0.0, 0.0)), dtype=np.float64)
            # frame by frame, so no (frames, vertices, 3) temporary beside the frames themselves
            n_fr = 1 if part.static else len(frames)
            base = frames[0]
            scale = offset = None
            if nv:
                lo = np.min([frames[k].min(axis=0) for k in range(n_fr)], axis=0)
                hi = np.max([frames[k].max(axis=0) for k in range(n_fr)], axis=0)
                bounds.append((lo + move, hi + move))
                if self.quantize:
                    offset = (lo + hi) / 2.0
                    reach = float(np.max(hi - lo)) / 2.0
                    for k in range(1, n_fr):
                        reach = max(reach, float(np.abs(frames[k] - base).max()))
                    scale = reach if reach > 0 else 1.0
            position = vec3(base - offset if offset is not None else base, scale)
            targets = [{"POSITION": vec3(frames[k] - base, scale)} for k in range(1, n_fr)]
            # one primitive per material, sharing the positions and targets
            prims = []
            index_type = _USHORT if nv < 65535 else _UINT
            for m in sorted(set(union[:, 3].tolist()), key=lambda x: x):
                tri = faces[union[:, 3] == m].astype(np.uint16 if index_type == _USHORT else np.uint32)
                view = add_view(tri.tobytes(), _ELEMENT_ARRAY_BUFFER)
                prim = {"attributes": {"POSITION": position},
                        "indices": add_accessor(view, index_type, tri.size, "SCALAR"), "material": int(m),
                        "mode": 4}
                if targets:
                    prim["targets"] = targets
                prims.append(prim)
            mesh = {"name": part.name, "primitives": prims}
            if targets:
                mesh["weights"] = [0.0] * len(targets)
                n_targets_max = max(n_targets_max, len(targets))
            meshes.append(mesh)
            node = {"name": part.name, "mesh": len(meshes) - 1}
            if scale is not None:
                node["translation"] = [float(x) for x in offset + move]
                node["scale"] = [scale] * 3
            elif move.any():
                node["translation"] = [float(x) for x in move]
            nodes.append(node)
            if targets:
                samplers.append(len(targets))
                channels.append(len(nodes) - 1)
        materials = []
        part_default = {f"{p.name}_default": p.default_color for p in self.parts}
        for name in self.material_names:
            rgb = part_default[name] if name in part_default else self.material_color(name)
            lin = [float(round(c, 6)) for c in srgb_to_linear(rgb)]
            materials.append({"name": name, "doubleSided": True,
                              "pbrMetallicRoughness": {"baseColorFactor": [*lin, 1.0], "metallicFactor": 0.0,
                                                       "roughnessFactor": 0.6}})
        animations = []
        if channels or flips:
            times = np.arange(self.n_frames, dtype=np.float32) / np.float32(self.fps)
            tview = add_view(times.tobytes())
            tacc = add_accessor(tview, _FLOAT, len(times), "SCALAR", lo=[times[0]], hi=[times[-1]])
            anim = {"name": "growth", "channels": [], "samplers": []}
            for node, k in flips:
                sc = np.zeros((self.n_frames, 3), np.float32)
                sc[k] = 1.0
                out = add_accessor(add_view(sc.tobytes()), _FLOAT, self.n_frames, "VEC3")
                anim["samplers"].append({"input": tacc, "output": out, "interpolation": "STEP"})
                anim["channels"].append({"sampler": len(anim["samplers"]) - 1,
                                         "target": {"node": node, "path": "scale"}})
            out_by_count = {}
            for count, node in zip(samplers, channels):
                if count not in out_by_count:
                    w = np.zeros((self.n_frames, count), np.float32)
                    w[np.arange(1, self.n_frames), np.arange(count)] = 1.0
                    out_by_count[count] = add_accessor(add_view(w.tobytes()), _FLOAT, w.size, "SCALAR")
                anim["samplers"].append({"input": tacc, "output": out_by_count[count], "interpolation": "LINEAR"})
                anim["channels"].append({"sampler": len(anim["samplers"]) - 1,
                                         "target": {"node": node, "path": "weights"}})
            animations.append(anim)
        root = {"name": self.root_name, "children": list(range(len(nodes))),
                "scale": [float(self.meters_per_unit)] * 3}
        nodes.append(root)
        extras = {"frames": self.n_frames, "fps": self.fps, "start_frame": self.start_frame,
                  "meters_per_unit": self.meters_per_unit, "triangles": n_triangles,
                  "parts": ", ".join(p.name for p in self.parts), **self.extras}
        if bounds:
            lo = np.min([b[0] for b in bounds], axis=0)
            hi = np.max([b[1] for b in bounds], axis=0)
            extras["bounds"] = [[float(round(x, 6)) for x in lo], [float(round(x, 6)) for x in hi]]
        doc = {"asset": {"version": "2.0", "generator": "inflo canopy-export"},
               "scene": 0, "scenes": [{"name": self.root_name, "nodes": [len(nodes) - 1], "extras": extras}],
               "nodes": nodes, "meshes": meshes, "materials": materials, "accessors": accessors,
               "bufferViews": views, "buffers": [{"byteLength": 0}]}
        if animations:
            doc["animations"] = animations
        if self.quantize:
            doc["extensionsUsed"] = ["KHR_mesh_quantization"]
            doc["extensionsRequired"] = ["KHR_mesh_quantization"]
        while len(blob) % 4:
            blob.append(0)
        doc["buffers"][0]["byteLength"] = len(blob)
        return doc, bytes(blob)

    def save(self, output) -> None:
        doc, blob = self.build()
        text = json.dumps(doc, separators=(",", ":"), sort_keys=False).encode("utf-8")
        text += b" " * (-len(text) % 4)
        total = 12 + 8 + len(text) + 8 + len(blob)
        with atomic_write(Path(output), "wb") as fh:
            fh.write(struct.pack("<4sII", b"glTF", 2, total))
            fh.write(struct.pack("<I4s", len(text), b"JSON"))
            fh.write(text)
            fh.write(struct.pack("<I4s", len(blob), b"BIN\x00"))
            fh.write(blob)
