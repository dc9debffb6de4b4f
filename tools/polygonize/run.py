"""``polygonize`` as a library call: a .floret frame sequence in, an OBJ sequence out (2.4)."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from inflo.formats.atomic import (
    begin_sequence,
    check_output_path,
    frame_name,
    list_sequence,
    output_lock,
    refuse_output_over_inputs,
)
from inflo.formats.errors import InputError
from inflo.formats.floret import check_compatible, full_petal, read_floret
from inflo.formats.obj import write_obj
from inflo.tools.bspline import surface_grid
from inflo.tools.common import linalg as la
from inflo.tools.common.cli import progress

from .mesh import FloretMesher, collapsed_rows, quality
from .sampling import DEFAULT_ETA, DEFAULT_LAMBDA, load_profile, row_parameters

__all__ = ["PolygonizeReport", "build_mesher", "polygonize_frames", "polygonize_files", "auto_aspect"]


@dataclass
class PolygonizeReport:
    """Per-run figures: triangles per floret, minimum angle, triangles under 10 degrees
    in the worst frame, degenerate triangles, closest pair of distinct vertices."""

    n_frames: int = 0
    n_vertices: int = 0
    n_triangles: int = 0
    triangles_per_organ: dict = field(default_factory=dict)
    min_angle: float = 180.0
    min_angle_frame: int = 0
    under_10_worst: int = 0
    under_10_frame: int = 0
    degenerate: int = 0
    degenerate_frame: int = -1
    collapsed: dict = field(default_factory=dict)
    aspects: dict = field(default_factory=dict)

    def add_frame(self, index: int, q: dict) -> None:
        self.n_frames += 1
        if q["min_angle"] < self.min_angle:
            self.min_angle, self.min_angle_frame = q["min_angle"], index
        if q["under_10"] > self.under_10_worst:
            self.under_10_worst, self.under_10_frame = q["under_10"], index
        if q["degenerate"] > 0 and self.degenerate == 0:
            self.degenerate_frame = index
        self.degenerate = max(self.degenerate, q["degenerate"])

    def lines(self) -> list[str]:
        per = ", ".join(f"{k} {v}" for k, v in self.triangles_per_organ.items())
        out = [
            f"{self.n_frames} frames, {self.n_vertices} vertices, {self.n_triangles} triangles per "
            f"floret ({per})",
            f"minimum angle {self.min_angle:.2f} deg (frame {self.min_angle_frame}); "
            f"{self.under_10_worst} triangles under 10 deg in the worst frame"
            + (f" (frame {self.under_10_frame})" if self.under_10_worst else ""),
        ]
        if self.collapsed:
            out.append("rows collapsed to a point (one vertex): " + "; ".join(
                f"{k} v = {v}" for k, v in self.collapsed.items()))
        if self.degenerate:
            out.append(f"WARNING: {self.degenerate} degenerate (zero-area) triangles, first in "
                       f"frame {self.degenerate_frame}")
        return out


def auto_aspect(nets, degree_u: int, degree_v: int) -> float:
    """Width / length of a petal (mean over the given full control nets), in [0.05, 20], rounded to
    6 decimals.

    Width: 3D length of the rows v = 1/4, 1/2, 3/4; length: of the midline u = 1/2.
    """
    ratios = []
    ts = np.linspace(0.0, 1.0, 33)
    for net in nets:
        rows = surface_grid(net, degree_u, degree_v, ts, [0.25, 0.5, 0.75])
        width = la.norm(np.diff(rows, axis=1), axis=2).sum(axis=1).mean()
        mid = surface_grid(net, degree_u, degree_v, [0.5], ts)[:, 0]
        length = la.norm(np.diff(mid, axis=0), axis=1).sum()
        if length > 0 and width > 0:
            ratios.append(width / length)
    # rounded to 6 decimals: the samples of a row grid are cocircular in (aspect u, v), so the
    # Delaunay triangulation's tie-breaks would follow the ratio's last bits (another numpy or
    # libm version); rounded, the faces are the same on every machine
    return round(float(np.clip(np.mean(ratios), 0.05, 20.0)), 6) if ratios else 1.0


def _profile(organ_value, override, default, name, where):
    value = override if override is not None else (organ_value if organ_value is not None else default)
    try:
        return load_profile(value, name)
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None


def build_mesher(frames, paths=None, *, lam=None, eta=None, aspect=None) -> tuple[FloretMesher, PolygonizeReport]:
    """The constant-topology mesher of a frame sequence (after checking the frames agree)."""
    frames = list(frames)
    if not frames:
        raise InputError("no frames to polygonize")
    paths = [os.fspath(p) for p in (paths or [f"frame {i}" for i in range(len(frames))])]
    ref = frames[0]
    for f, p in zip(frames[1:], paths[1:]):
        check_compatible(ref, f, paths[0], p)
    report = PolygonizeReport()
    lambdas, etas, collapsed, aspects = [], [], [], []
    for oi, organ in enumerate(ref.organs):
        where = f"{paths[0]}: organ {organ.name!r}"
        lp = _profile(organ.lambda_, lam, DEFAULT_LAMBDA, "lambda", where)
        ep = _profile(organ.eta, eta, DEFAULT_ETA, "eta", where)
        lambdas.append(lp)
        etas.append(ep)
        nets = [full_petal(f.organs[oi]) for f in frames]
        v_rows, _ = row_parameters(lp)
        col = collapsed_rows(nets, v_rows, organ.degree_u, organ.degree_v)
        collapsed.append(col)
        if col.any():
            report.collapsed[organ.name] = ", ".join(f"{x:.4g}" for x in v_rows[col])
        a = auto_aspect([nets[0], nets[-1]], organ.degree_u, organ.degree_v) if aspect is None else float(aspect)
        aspects.append(a)
        report.aspects[organ.name] = a
    mesher = FloretMesher(ref, lambdas, etas, collapsed, aspects)
    report.n_vertices = mesher.n_vertices
    report.n_triangles = mesher.n_triangles
    for part in mesher.parts:
        o = ref.organs[part.organ_index]
        report.triangles_per_organ[o.name] = len(part.faces)
    return mesher, report


def polygonize_frames(frames, paths=None, *, lam=None, eta=None, aspect=None):
    """Meshes (list of ObjMesh) and the report of a sequence of Floret frames, in memory."""
    frames = list(frames)
    mesher, report = build_mesher(frames, paths, lam=lam, eta=eta, aspect=aspect)
    meshes = []
    for i, f in enumerate(frames):
        m = mesher.mesh(f)
        report.add_frame(i, quality(m.vertices, m.faces))
        meshes.append(m)
    return meshes, report


def polygonize_files(source, output, *, lam=None, eta=None, aspect=None, quiet: bool = True) -> PolygonizeReport:
    """Read the .floret frames of ``source`` (folder, glob or file), write ``output/frame_0000.obj`` ..."""
    paths = list_sequence(os.fspath(source), ".floret")
    frames = [read_floret(p) for p in paths]
    mesher, report = build_mesher(frames, paths, lam=lam, eta=eta, aspect=aspect)
    check_output_path(output, folder=True)
    refuse_output_over_inputs(output, [(p, "floret frame") for p in paths]
                              + [(f, "input") for f in (lam, eta) if isinstance(f, (str, os.PathLike))],
                              writes=lambda rel: rel.endswith(".obj"))
    out = Path(output)
    written = []
    with output_lock(out, "polygonize"), \
            progress(list(enumerate(frames)), label="polygonize", quiet=quiet) as bar:
        # an older run's frames go first: an interrupted run leaves a shorter sequence, never a mix
        begin_sequence(out, "polygonize", [frame_name(i, "frame_", ".obj") for i in range(len(frames))], ".obj")
        for i, f in bar:
            m = mesher.mesh(f)
            report.add_frame(i, quality(m.vertices, m.faces))
            p = out / frame_name(i, "frame_", ".obj")
            write_obj(p, m, header=f"polygonize: {paths[i].name} (time {f.key_time})")
            written.append(p)
    return report
