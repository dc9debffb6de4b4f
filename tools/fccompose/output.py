"""What a run of :func:`.compose.compose_canopy` writes besides its log: the canopy as
``OUT/frame_NNNN.obj`` (vertex text precise enough to stay collision-free as written), and next
to every written frame the :class:`.model.State` that ``--resume`` reads back (``OUT/state/``),
with the fingerprint of the parameters and inputs it was computed from.
"""
from __future__ import annotations

import hashlib
import io
import json
from pathlib import Path

import numpy as np

from inflo.formats.atomic import frame_name, write_bytes_atomic, write_text_atomic
from inflo.formats.errors import InputError
from inflo.formats.fcc import CanopyParams
from inflo.formats.obj import ObjMesh, write_obj
from inflo.tools.collide.written import WRITE_FORMATS as WRITE_FORMATS
from inflo.tools.collide.written import written_format as written_format
from inflo.tools.collide.written import written_text

from .model import Model, State


def _input_hashes(params: CanopyParams) -> dict:
    """sha256 of every file the run reads besides the templates (scene files, RBA frames, weight
    and petal weight files), keyed by the path as the ``.fcc`` names it (an RBA folder: ``folder/NNNN.rba`` each),
    so that ``--resume`` can name the input that changed."""
    out = {}
    paths = [(f.raw, f.resolved) for f in params.scene_files]
    for r in params.rigid_body_animations:
        paths.append((r.scene_path.raw, r.scene_path.resolved))
        folder = Path(r.rba_folder.resolved)
        if folder.is_dir():
            paths += [(f"{r.rba_folder.raw.rstrip('/')}/{p.name}", p) for p in sorted(folder.glob("*.rba"))]
    paths += [(f.raw, f.resolved) for f in params.weights.values()]
    paths += [(f.raw, f.resolved) for f in params.petal_weights.values()]
    for raw, path in paths:
        path = Path(path)
        if path.is_file() and raw not in out:
            out[raw] = hashlib.sha256(path.read_bytes()).hexdigest()
    return out


def _fingerprint(params: CanopyParams, model: Model, inputs: dict | None = None) -> str:
    """One hash of the parameter file, the templates (positions and triangles) and ``inputs``
    (:func:`_input_hashes`): a resumed run must have read the same."""
    h = hashlib.sha256()
    if params.source is not None and Path(params.source).is_file():
        h.update(Path(params.source).read_bytes())
    h.update(model.template_x.tobytes())
    h.update(model.tri_indices.tobytes())
    for raw, digest in sorted((inputs or {}).items()):
        h.update(raw.encode("utf-8") + b"\0" + digest.encode("ascii"))
    if params.solver_scheme != "default":  # --scheme: a resumed run must go on with the same
        h.update(b"solver scheme\0" + params.solver_scheme.encode("ascii"))
    return h.hexdigest()


def _write_frame(out: Path, model: Model, x: np.ndarray, k: int, tri_on: np.ndarray | None = None,
                 exact: bool = True) -> Path:
    """The canopy at frame ``k``: every vertex (stable numbering), the faces of the florets
    present (``tri_on``: a mask over the model's triangles; None: all); the obstacles' vertices
    and faces left out. ``exact``: the coordinates with as many digits as keep the written frame
    collision-free (:func:`written_format`)."""
    mats, face_material = model.face_materials
    faces, face_group = model.tri_indices, model.tri_floret.copy()
    if tri_on is not None:
        faces, face_group = faces[tri_on], face_group[tri_on]
        if face_material is not None:
            face_material = face_material[tri_on]
    hidden = model.obstacle_vertices
    if hidden is not None:
        # obstacles collide but are not written: their faces and vertices go, the rest renumbered
        keep = ~hidden[faces[:, 0]]
        faces, face_group = faces[keep], face_group[keep]
        if face_material is not None:
            face_material = face_material[keep]
        renumber = np.cumsum(~hidden) - 1
        x, faces = x[~hidden], renumber[faces].astype(faces.dtype)
    fmt, text = written_text(x, faces, tri_part=face_group) if exact else (WRITE_FORMATS[0], None)
    present = len(np.unique(face_group))
    mesh = ObjMesh(
        vertices=x,
        faces=faces,
        groups=[f"floret_{fl.index}" for fl in model.florets],
        face_group=face_group,
        materials=mats,
        face_material=face_material,
    )
    path = out / frame_name(k, "frame_", ".obj", 4)
    florets = (f"{len(model.florets)} florets" if tri_on is None
               else f"{present} of {len(model.florets)} florets emerged")
    if hidden is not None:
        n_obstacles = len(model.obstacles)
        florets = f"{len(model.florets) - n_obstacles} florets and {n_obstacles} obstacles (not written)"
    write_obj(path, mesh, header=f"fccompose canopy, frame {k}: {florets}, {len(faces)} triangles", fmt=fmt,
              vertex_text=text)
    return path


def _save_state(out: Path, state: State, fingerprint: str, inputs: dict | None = None) -> None:
    """Write ``state`` to ``out/state/``: ``frame_NNNN.npy`` (the exact float64 positions, the
    only one kept) and ``run.json`` (``fingerprint``, ``frame``; ``not_emerged``: the florets not
    yet present, ``emerged_smaller``: [floret, size, frame] of those that emerged smaller, each
    only when there are any)."""
    sdir = out / "state"
    sdir.mkdir(exist_ok=True)
    buf = io.BytesIO()
    np.save(buf, state.vertex_x, allow_pickle=False)
    k = int(state.frame)
    write_bytes_atomic(sdir / frame_name(k, "frame_", ".npy", 4), buf.getvalue())
    info = {"fingerprint": fingerprint, "frame": k}
    if inputs:
        info["inputs"] = inputs
    if not state.born.all():
        info["not_emerged"] = np.nonzero(~state.born)[0].tolist()
    small = np.nonzero(state.emerge_scale < 1.0)[0]
    if len(small):
        info["emerged_smaller"] = [[int(i), float(state.emerge_scale[i]), float(state.emerge_frame[i])]
                                   for i in small]
    write_text_atomic(sdir / "run.json", json.dumps(info) + "\n")
    for old in sorted(sdir.glob("frame_*.npy")):
        if old.name != frame_name(k, "frame_", ".npy", 4):
            old.unlink()


def _load_state(out: Path, fingerprint: str, model: Model, inputs: dict | None = None) -> State | None:
    """The :class:`State` :func:`_save_state` wrote to ``out/state/``; None when there is none or
    its frame's OBJ is missing (nothing to resume: start from frame 0)."""
    sdir = out / "state"
    run = sdir / "run.json"
    if not run.is_file():
        return None
    info = json.loads(run.read_text())
    if info.get("fingerprint") != fingerprint:
        before = info.get("inputs") or {}
        changed = [k for k in sorted(set(before) | set(inputs or {})) if before.get(k) != (inputs or {}).get(k)]
        if changed:
            what = ("removed since" if changed[0] not in (inputs or {}) else
                    "added since" if changed[0] not in before else "changed since")
            raise InputError(f"{run}: expected the inputs of the run to resume, found {changed[0]} {what} it "
                             f"was interrupted{f' (and {len(changed) - 1} more)' if len(changed) > 1 else ''} "
                             f"(delete {out} or run without --resume)")
        raise InputError(f"{run}: expected a run of the same parameters and inputs to resume, "
                         f"found one of different parameters (delete {out} or run without --resume)")
    k = int(info["frame"])
    st = sdir / frame_name(k, "frame_", ".npy", 4)
    obj = out / frame_name(k, "frame_", ".obj", 4)
    if not st.is_file() or not obj.is_file():
        return None
    x = np.load(st, allow_pickle=False)
    if x.shape != (model.n_vertices, 3):
        raise InputError(f"{st}: expected positions of {model.n_vertices} vertices, found shape {x.shape}")
    nf = len(model.florets)
    born = np.ones(nf, bool)
    born[[int(i) for i in info.get("not_emerged", [])]] = False
    emerge_scale, emerge_frame = np.ones(nf), np.zeros(nf)
    for i, size, frame in info.get("emerged_smaller", []):
        emerge_scale[int(i)] = size
        emerge_frame[int(i)] = frame
    return State(x, k, born, emerge_scale, emerge_frame)
