"""Petal templates and floret meshes of constant topology (thesis 2.4, 8 c)).

A :class:`PetalTemplate` is the polygonization of one organ's petal in its (u, v) parameter
space, computed **once** for a whole frame sequence: the samples of :mod:`.sampling`, their
Delaunay triangulation (``scipy.spatial.Delaunay``) and the B-spline weights that map a control
net to the samples. The Delaunay triangulation is computed on the half u <= 1/2 and mirrored to
the other half (index by index: row i, column c - 1 - k), which keeps the midline u = 1/2 a chain
of edges (no triangle straddles it, the reason eta is odd) and gives a bilateral petal a
mirror-symmetric mesh. The parameter plane is scaled by a fixed aspect (u by ``aspect``) before
the triangulation so that triangles of a long, narrow petal are not needlessly thin; an affine
scaling keeps every frame's topology the same.

A :class:`FloretMesher` assembles the organs of a floret: every petal copy of an organ
(n-fold symmetry) is one OBJ group ``ORGAN_k`` with material ``mtl<material>``; where the organ is
fused (2.2), the seam vertices of adjacent copies are **welded**: the boundary curve u = 0 of copy
k and u = 1 of copy k + 1 coincide for v in [0, v_f], v_f = the v-knot ``tau_K`` of the fused count
K (all control points that influence the boundary there lie on the symmetry plane; K = nv: the
whole boundary), and the two samples become one vertex. Evaluating a frame is one matrix product
per organ; the vertex order and faces never change.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import Delaunay

from inflo.formats.floret import Floret, Organ, petals
from inflo.formats.obj import ObjMesh
from inflo.tools.bspline import basis_matrix, clamped_knots, surface_weights
from inflo.tools.common import linalg as la

from .sampling import Profile, row_counts, row_parameters, row_points

__all__ = [
    "PetalTemplate",
    "FloretMesher",
    "triangulate_rows",
    "fused_v",
    "triangle_angles",
    "triangle_areas",
    "quality",
]

COLLAPSE_TOL = 1e-9
"""A row whose surface points all lie within this fraction of the petal's size is a point."""


def fused_v(organ: Organ) -> float:
    """v_f: the fused boundary lies on the symmetry plane for v in [0, v_f] (-1: not fused).

    The boundary curve over v in [tau_s, tau_{s+1}) depends on control points s - p .. s; it lies
    on the plane when all of them are among the fused rows 0 .. K - 1, i.e. for v <= tau_K.
    """
    k = organ.fused
    if k <= 0:
        return -1.0
    if k >= organ.nv:
        return 1.0
    return float(clamped_knots(organ.nv, organ.degree_v)[k])


def triangulate_rows(u, v, row, col, counts, aspect: float = 1.0) -> np.ndarray:
    """Delaunay triangulation of row samples, on the half u <= 1/2 and mirrored.

    Parameters
    ----------
    u, v, row, col : (k,) arrays from :func:`.sampling.row_points`
    counts : (n + 1,) int, odd
    aspect : float
        u is scaled by this before the triangulation.

    Returns
    -------
    (t, 3) int64
        Triangles as sample indices, counter-clockwise in (u, v).
    """
    counts = np.asarray(counts)
    offsets = np.concatenate([[0], np.cumsum(counts)[:-1]])
    left = np.flatnonzero(col <= (counts[row] - 1) // 2)
    pts = np.column_stack([u[left] * aspect, v[left]])
    tri = Delaunay(pts)
    if len(tri.coplanar):
        raise RuntimeError("Delaunay dropped coincident samples; rows too close together")
    simp = left[tri.simplices]
    a, b, c = simp[:, 0], simp[:, 1], simp[:, 2]
    area = 0.5 * ((u[b] - u[a]) * (v[c] - v[a]) - (u[c] - u[a]) * (v[b] - v[a]))
    flip = area < 0
    simp[flip] = simp[flip][:, [0, 2, 1]]
    area = np.abs(area)
    simp = simp[area > 1e-14]
    # mirror: sample (row i, col j) <-> (row i, col c_i - 1 - j); orientation reverses
    mcol = counts[row] - 1 - col
    mirror = offsets[row] + mcol
    right = mirror[simp][:, [0, 2, 1]]
    on_mid = (mcol == col)[simp].all(axis=1)  # cannot happen (zero area), kept for safety
    right = right[~on_mid]
    tris = np.concatenate([simp, right])
    # coverage check: the triangles must tile the hull of the samples
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    total = 0.5 * np.sum((u[b] - u[a]) * (v[c] - v[a]) - (u[c] - u[a]) * (v[b] - v[a]))
    from scipy.spatial import ConvexHull

    hull = ConvexHull(np.column_stack([u, v])).volume
    if not math.isclose(total, hull, rel_tol=1e-9):
        raise RuntimeError(f"triangulation does not tile the parameter domain ({total} vs {hull})")
    return tris


class PetalTemplate:
    """The fixed polygonization of one organ (see the module docstring).

    Attributes
    ----------
    v_rows : (n + 1,) row parameters; lambda_scale: c of eq. 2.1's adjustment
    counts : (n + 1,) vertices per row (odd)
    u, v, row, col : (k,) the samples
    triangles : (t, 3) int64 sample indices
    weights : (k, nv * nu_full) B-spline weights of the full petal
    """

    def __init__(self, organ: Organ, lam: Profile, eta: Profile, collapsed=None, aspect: float = 1.0):
        self.v_rows, self.lambda_scale = row_parameters(lam)
        self.counts = row_counts(eta, self.v_rows, collapsed)
        self.u, self.v, self.row, self.col = row_points(self.v_rows, self.counts)
        self.aspect = float(aspect)
        self.triangles = triangulate_rows(self.u, self.v, self.row, self.col, self.counts, aspect)
        self.weights = surface_weights(organ.nv, organ.nu_full, organ.degree_u, organ.degree_v,
                                       self.u, self.v)

    @property
    def n_samples(self) -> int:
        return len(self.u)


def collapsed_rows(organs_over_frames, v_rows, degree_u: int, degree_v: int) -> np.ndarray:
    """Rows that collapse to a point in any frame: (n + 1,) bool.

    ``organs_over_frames`` is an iterable of (nv, nu_full, 3) full-petal control nets.
    """
    v_rows = np.asarray(v_rows)
    us = np.linspace(0.0, 1.0, 9)
    out = np.zeros(len(v_rows), dtype=bool)
    bu = bv = None
    for net in organs_over_frames:
        if bu is None:
            bu = basis_matrix(net.shape[1], degree_u, us)
            bv = basis_matrix(net.shape[0], degree_v, v_rows)
        pts = la.matmul(bv, la.matmul(bu, net).reshape(len(net), -1)).reshape(len(bv), len(us), 3)  # (rows, 9, 3)
        size = max(float(np.ptp(net.reshape(-1, 3), axis=0).max()), 1e-300)
        ext = np.ptp(pts, axis=1).max(axis=1)
        out |= ext <= COLLAPSE_TOL * size
    return out


@dataclass
class _OrganPart:
    organ_index: int
    template: PetalTemplate
    n_copies: int
    src_a: np.ndarray  # (m,) raw sample ids averaged into each vertex (welded: two ids)
    src_b: np.ndarray
    faces: np.ndarray  # (n_copies * t, 3) vertex ids (global)
    vertex_offset: int


class FloretMesher:
    """Builds the constant-topology mesh of a floret from its frames.

    Parameters
    ----------
    reference : Floret
        A frame (for the organs' structure); all frames must be compatible with it.
    lambdas, etas : list of Profile
        Per organ.
    collapsed : list of (n + 1,) bool or None
        Per organ, rows that collapse to a point (see :func:`collapsed_rows`).
    aspects : list of float
        Per organ, the u scaling of the Delaunay triangulation.
    """

    def __init__(self, reference: Floret, lambdas, etas, collapsed=None, aspects=None):
        self.reference = reference
        n_org = len(reference.organs)
        collapsed = collapsed or [None] * n_org
        aspects = aspects or [1.0] * n_org
        self.parts: list[_OrganPart] = []
        self.groups: list[str] = []
        self.materials: list[str] = []
        face_group, face_material, faces = [], [], []
        offset = 0
        for oi, organ in enumerate(reference.organs):
            tpl = PetalTemplate(organ, lambdas[oi], etas[oi], collapsed[oi], aspects[oi])
            n, k = organ.symmetry_n, tpl.n_samples
            raw = np.arange(n * k).reshape(n, k)
            canon = raw.copy()
            vf = fused_v(organ)
            if vf >= 0.0:
                last = tpl.counts[tpl.row] - 1
                welded_rows = (tpl.v <= vf + 1e-12) & (tpl.counts[tpl.row] > 1)
                first_ids = np.flatnonzero(welded_rows & (tpl.col == 0))
                last_ids = np.flatnonzero(welded_rows & (tpl.col == last))
                # the u = 1 boundary of copy c is the u = 0 boundary of copy c - 1
                for c in range(n):
                    prev = (c - 1) % n
                    a = raw[c, last_ids]
                    b = raw[prev, first_ids]
                    m = np.minimum(a, b)
                    canon[c, last_ids] = m
                    canon[prev, first_ids] = m
            flat = canon.reshape(-1)
            uniq, compact = np.unique(flat, return_inverse=True)
            # vertices in raw order (copy by copy, row by row) of their first sample; a welded
            # vertex averages its two samples (equal up to rounding)
            rid = np.arange(n * k)
            src_a = uniq
            src_b = uniq.copy()
            second = flat != rid
            src_b[compact[second]] = rid[second]
            vid = compact.reshape(n, k) + offset
            part_faces = np.concatenate([vid[c][tpl.triangles] for c in range(n)])
            for c in range(n):
                self.groups.append(f"{organ.name}_{c}")
                face_group.append(np.full(len(tpl.triangles), len(self.groups) - 1, np.int32))
                mname = f"mtl{organ.material}"
                if mname not in self.materials:
                    self.materials.append(mname)
                face_material.append(np.full(len(tpl.triangles), self.materials.index(mname), np.int32))
            self.parts.append(_OrganPart(oi, tpl, n, src_a, src_b, part_faces, offset))
            faces.append(part_faces)
            offset += len(src_a)
        self.n_vertices = offset
        self.faces = np.concatenate(faces).astype(np.int32)
        self.face_group = np.concatenate(face_group)
        self.face_material = np.concatenate(face_material)

    @property
    def n_triangles(self) -> int:
        return len(self.faces)

    def vertices(self, frame: Floret) -> np.ndarray:
        """(n_vertices, 3) vertex positions of a frame."""
        out = np.empty((self.n_vertices, 3))
        for part in self.parts:
            organ = frame.organs[part.organ_index]
            nets = petals(organ)  # (n, nv, nu_full, 3)
            w = part.template.weights
            raw = la.matmul(w[None], nets.reshape(part.n_copies, -1, 3)).reshape(-1, 3)
            out[part.vertex_offset:part.vertex_offset + len(part.src_a)] = 0.5 * (
                raw[part.src_a] + raw[part.src_b])
        return out

    def mesh(self, frame: Floret) -> ObjMesh:
        """The OBJ mesh of a frame: groups per petal copy, ``usemtl mtl<material>``."""
        return ObjMesh(
            vertices=self.vertices(frame),
            faces=self.faces,
            groups=list(self.groups),
            face_group=self.face_group,
            materials=list(self.materials),
            face_material=self.face_material,
        )


def triangle_areas(vertices, faces) -> np.ndarray:
    """(m,) areas of the triangles."""
    p = vertices[faces]
    return 0.5 * la.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)


def _angles_and_double_area(vertices, faces):
    p = vertices[faces]
    e0 = p[:, 1] - p[:, 0]
    e1 = p[:, 2] - p[:, 1]
    e2 = p[:, 0] - p[:, 2]
    n = np.cross(e0, -e2)
    twice_area = np.sqrt(la.rowdot(n, n))
    dots = np.stack([-la.rowdot(e2, e0),  # at vertex 0: between e0 and -e2
                     -la.rowdot(e0, e1),  # at vertex 1
                     -la.rowdot(e1, e2)], axis=1)  # at vertex 2
    return np.degrees(np.arctan2(twice_area[:, None], dots)), twice_area


def triangle_angles(vertices, faces) -> np.ndarray:
    """(m, 3) interior angles in degrees (a degenerate triangle has an angle 0)."""
    return _angles_and_double_area(vertices, faces)[0]


def quality(vertices, faces, area_tol: float = 1e-12) -> dict:
    """Minimum angle, triangles under 10 degrees and degenerate triangles of one frame."""
    ang, twice_area = _angles_and_double_area(vertices, faces)
    mins = ang.min(axis=1)
    scale = float(np.ptp(vertices, axis=0).max()) if len(vertices) else 1.0
    return {
        "min_angle": float(mins.min()) if len(mins) else 180.0,
        "under_10": int((mins < 10.0).sum()),
        "degenerate": int((0.5 * twice_area <= area_tol * scale * scale).sum()),
    }
