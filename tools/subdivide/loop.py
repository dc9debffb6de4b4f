"""Loop subdivision as linear operators, computed once and applied to every frame (thesis 4.4).

One level of Loop subdivision [Loop 1987] is linear in the vertex positions: the new vertices are
``S @ V`` for a sparse matrix ``S`` that depends only on the connectivity. This module builds, for
one level,

- ``S_mid``  the quadrisection in the plane of each triangle (fig. 4.7a,b): old vertices stay, a new
  vertex at each edge midpoint. The mesh ``M_s = S_mid @ V`` is collision-free when ``V`` is;
- ``S_loop`` the Loop positions ``M_f = S_loop @ V`` (fig. 4.7c) with the standard rules:

  ======================  ==============================================================
  interior odd (edge)     3/8 (v0 + v1) + 1/8 (v2 + v3)   (v2, v3 opposite the edge)
  boundary odd (edge)     1/2 (v0 + v1)
  interior even (vertex)  (1 - k beta) v + beta * sum of its k neighbours,
                          beta = (5/8 - (3/8 + 1/4 cos(2 pi / k))^2) / k  (Loop's weights)
  boundary even (crease)  3/4 v + 1/8 (b0 + b1), b0, b1 its two boundary neighbours
  corner                  v (kept), for a non-manifold vertex (see below)
  ======================  ==============================================================

- the new faces, each triangle (a, b, c) with edge vertices (ab, bc, ca) becoming
  (a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca).

Vertex order of the output: the n old vertices first, in their order, then one new vertex per
edge, edges in order of first appearance along the faces (edges (a,b), (b,c), (c,a) of face 0,
then face 1, ...). The order depends only on the input faces, so every frame of a sequence gets
the same topology and vertex order.

Non-manifold input: an edge shared by more than two triangles is an error naming it. A vertex
whose triangles do not form a single fan (two petals touching at one vertex, or a boundary vertex
with more than two boundary edges) is treated as a **corner**: it keeps its position and the
edges around it follow the rules above. Unused vertices are kept (and stay where they are).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from inflo.formats.errors import InputError

__all__ = ["LoopLevel", "loop_level", "loop_beta", "subdivide_positions", "NonManifoldError"]


class NonManifoldError(InputError):
    """The mesh has an edge shared by more than two triangles."""


def loop_beta(k: np.ndarray) -> np.ndarray:
    """Loop's even-vertex weight beta(k) = (5/8 - (3/8 + 1/4 cos(2 pi / k))^2) / k, k >= 1."""
    k = np.asarray(k, dtype=np.float64)
    return (0.625 - (0.375 + 0.25 * np.cos(2.0 * np.pi / k)) ** 2) / k


@dataclass
class LoopLevel:
    """One level of subdivision of a fixed connectivity.

    Attributes
    ----------
    n_vertices : int
        Vertices before subdivision.
    edges : (e, 2) int64
        Unique edges (sorted pairs) in first-appearance order; new vertex n + i sits on edge i.
    faces : (4 m, 3) int32
        Faces after subdivision.
    S_mid, S_loop : scipy.sparse.csr_matrix, shape (n + e, n)
        Quadrisection in the plane and Loop positions (see the module docstring).
    boundary_edge : (e,) bool
        Edges with one incident triangle.
    corner : (n,) bool
        Non-manifold vertices kept in place.
    """

    n_vertices: int
    edges: np.ndarray
    faces: np.ndarray
    S_mid: sp.csr_matrix
    S_loop: sp.csr_matrix
    boundary_edge: np.ndarray
    corner: np.ndarray

    def midpoints(self, vertices: np.ndarray) -> np.ndarray:
        """``M_s``: the quadrisected mesh's vertices, (n + e, 3) float64."""
        return self.S_mid @ vertices  # fixed-order: scipy.sparse's own CSR loop, no BLAS

    def loop(self, vertices: np.ndarray) -> np.ndarray:
        """``M_f``: the Loop-subdivided vertices, (n + e, 3) float64."""
        return self.S_loop @ vertices  # fixed-order: scipy.sparse's own CSR loop, no BLAS


def loop_level(faces: np.ndarray, n_vertices: int, name: str = "mesh") -> LoopLevel:
    """Build the subdivision operators of one level for ``faces`` over ``n_vertices`` vertices.

    Parameters
    ----------
    faces : (m, 3) int
    n_vertices : int
    name : str
        Used in error messages (a file name).

    Raises
    ------
    NonManifoldError
        An edge shared by more than two triangles (named by its two 0-based vertex indices), or a
        degenerate triangle (a repeated vertex).
    """
    F = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    n, m = int(n_vertices), len(F)
    bad = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])
    if bad.any():
        k = int(np.argmax(bad))
        raise NonManifoldError(f"{name}: triangle {k} repeats a vertex ({' '.join(map(str, F[k]))})")
    # half-edges in face order: (a,b), (b,c), (c,a) of each face
    he = np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2)      # (3m, 2)
    he_opp = np.roll(F, -2, axis=1).reshape(-1)                              # vertex opposite each half-edge
    key = np.sort(he, axis=1)
    code = key[:, 0] * n + key[:, 1]
    uniq, first, inverse, counts = np.unique(code, return_index=True, return_inverse=True, return_counts=True)
    if (counts > 2).any():
        bad_e = key[first[np.argmax(counts > 2)]]
        raise NonManifoldError(
            f"{name}: edge {bad_e[0]}-{bad_e[1]} (0-based vertex indices) is shared by "
            f"{int(counts.max())} triangles; Loop subdivision needs at most 2")
    # renumber unique edges by first appearance
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    edge_of_he = rank[inverse]                                               # (3m,)
    e = len(uniq)
    edges = key[first[order]]
    boundary_edge = counts[order] == 1

    # --- odd (edge) vertices -------------------------------------------------------------
    rows, cols, vals = [], [], []
    ei = np.arange(e)
    # endpoints
    for c in (0, 1):
        rows.append(n + ei)
        cols.append(edges[:, c])
        vals.append(np.where(boundary_edge, 0.5, 0.375))
    # opposite vertices of interior edges: one per incident half-edge
    he_interior = ~boundary_edge[edge_of_he]
    rows.append(n + edge_of_he[he_interior])
    cols.append(he_opp[he_interior])
    vals.append(np.full(int(he_interior.sum()), 0.125))

    # --- even (old) vertices -------------------------------------------------------------
    # neighbours through unique edges
    nb_a = np.concatenate([edges[:, 0], edges[:, 1]])
    nb_b = np.concatenate([edges[:, 1], edges[:, 0]])
    nb_boundary = np.concatenate([boundary_edge, boundary_edge])
    valence = np.bincount(nb_a, minlength=n)
    n_bnd_edges = np.bincount(nb_a[nb_boundary], minlength=n)
    # fans: a manifold interior vertex has #incident faces == valence; a manifold boundary vertex
    # has exactly 2 boundary edges and #faces == valence - 1
    n_faces_at = np.bincount(F.reshape(-1), minlength=n)
    used = valence > 0
    interior_ok = (n_bnd_edges == 0) & (n_faces_at == valence)
    boundary_ok = (n_bnd_edges == 2) & (n_faces_at == valence - 1)
    corner = used & ~interior_ok & ~boundary_ok
    interior_v = used & interior_ok
    boundary_v = used & boundary_ok
    beta = np.zeros(n)
    beta[interior_v] = loop_beta(valence[interior_v])
    self_w = np.ones(n)
    self_w[interior_v] = 1.0 - valence[interior_v] * beta[interior_v]
    self_w[boundary_v] = 0.75
    rows.append(np.arange(n))
    cols.append(np.arange(n))
    vals.append(self_w)
    sel = interior_v[nb_a]
    rows.append(nb_a[sel])
    cols.append(nb_b[sel])
    vals.append(beta[nb_a[sel]])
    sel = boundary_v[nb_a] & nb_boundary
    rows.append(nb_a[sel])
    cols.append(nb_b[sel])
    vals.append(np.full(int(sel.sum()), 0.125))

    shape = (n + e, n)
    S_loop = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=shape)
    S_loop.sum_duplicates()
    S_mid = sp.csr_matrix(
        (np.concatenate([np.ones(n), np.full(2 * e, 0.5)]),
         (np.concatenate([np.arange(n), n + ei, n + ei]), np.concatenate([np.arange(n), edges[:, 0], edges[:, 1]]))),
        shape=shape)

    # --- new faces ------------------------------------------------------------------------
    E = (edge_of_he.reshape(m, 3) + n)                                       # ab, bc, ca per face
    a, b, c = F[:, 0], F[:, 1], F[:, 2]
    ab, bc, ca = E[:, 0], E[:, 1], E[:, 2]
    new_faces = np.stack([
        np.stack([a, ab, ca], 1), np.stack([ab, b, bc], 1), np.stack([ca, bc, c], 1), np.stack([ab, bc, ca], 1),
    ], axis=1).reshape(-1, 3).astype(np.int32)
    return LoopLevel(n, edges, new_faces, S_mid, S_loop, boundary_edge, corner)


def subdivide_positions(vertices: np.ndarray, faces: np.ndarray, levels: int = 1):
    """Plain Loop subdivision (no collision handling): (vertices (n', 3), faces (m', 3) int32)."""
    V = np.asarray(vertices, dtype=np.float64)
    F = np.asarray(faces)
    for _ in range(levels):
        lv = loop_level(F, len(V))
        V, F = lv.loop(V), lv.faces
    return V, F
