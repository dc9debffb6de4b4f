"""Loop subdivision operators (thesis 4.4): agreement with trimesh, limits, boundaries, errors."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh

from inflo.tools.subdivide.loop import NonManifoldError, loop_beta, loop_level, subdivide_positions


def grid(nx=6, ny=5, bump=0.2):
    xs, ys = np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 1, ny))
    V = np.c_[xs.ravel(), ys.ravel(), bump * np.sin(3 * xs.ravel())]
    F = []
    for j in range(ny - 1):
        for i in range(nx - 1):
            a = j * nx + i
            F += [[a, a + 1, a + nx + 1], [a, a + nx + 1, a + nx]]
    return V, np.array(F)


def trimesh_by_edge(V, F):
    """trimesh's Loop result, its new vertices looked up by the edge they sit on."""
    tv, tf = trimesh.remesh.subdivide_loop(V, F, 1)
    tf = tf.reshape(-1, 4, 3)  # (f0, o0, o2), (o0, f1, o1), (o2, o1, f2), (o0, o1, o2)
    odd = {}
    for fi, (a, b, c) in enumerate(F):
        for (x, y), o in zip(((a, b), (b, c), (c, a)), (tf[fi, 0, 1], tf[fi, 1, 2], tf[fi, 0, 2])):
            odd[(min(x, y), max(x, y))] = tv[o]
    return tv[: len(V)], odd


def assert_matches_trimesh(V, F, skip_even=()):
    lv = loop_level(F, len(V))
    mine = lv.loop(V)
    even, odd = trimesh_by_edge(V, F)
    keep = np.setdiff1d(np.arange(len(V)), np.asarray(skip_even, dtype=int))
    np.testing.assert_allclose(mine[keep], even[keep], atol=1e-12)
    for i, (a, b) in enumerate(lv.edges):
        np.testing.assert_allclose(mine[len(V) + i], odd[(a, b)], atol=1e-12)


def test_closed_mesh_matches_trimesh():
    ico = trimesh.creation.icosphere(subdivisions=2)
    assert_matches_trimesh(ico.vertices, ico.faces)
    rng = np.random.default_rng(3)
    torus = trimesh.creation.torus(1.0, 0.3, major_sections=12, minor_sections=8)
    assert_matches_trimesh(torus.vertices + rng.normal(0, 0.01, torus.vertices.shape), torus.faces)


def test_open_mesh_matches_trimesh_and_where_trimesh_is_wrong():
    """On an open grid every edge vertex and every vertex agree with trimesh except the boundary
    vertices that trimesh mistakes for having three boundary neighbours: those joined to another
    boundary vertex by an interior edge (4-11, 11-18, 18-25 here). There the crease rule,
    3/4 v + 1/8 (b0 + b1) over the two boundary-edge neighbours, is the right one."""
    V, F = grid()
    suspicious = [4, 11, 18, 25]
    assert_matches_trimesh(V, F, skip_even=suspicious)
    mine = loop_level(F, len(V)).loop(V)
    np.testing.assert_allclose(mine[11], 0.75 * V[11] + 0.125 * (V[5] + V[17]), atol=1e-12)
    even, _ = trimesh_by_edge(V, F)
    assert np.abs(even[11] - mine[11]).max() > 1e-3  # trimesh adds vertex 4 or 18 as a third neighbour


def test_flat_grid_stays_flat_and_boundary_follows_boundary_curve():
    V, F = grid(bump=0.0)
    W, G = subdivide_positions(V, F, levels=2)
    assert np.abs(W[:, 2]).max() == 0.0
    # boundary vertices stay on the boundary square (the boundary curve of a straight edge is the edge)
    lv = loop_level(F, len(V))
    b = np.unique(lv.edges[lv.boundary_edge])
    on_edge = (np.isclose(V[b, 0], 0) | np.isclose(V[b, 0], 1) | np.isclose(V[b, 1], 0) | np.isclose(V[b, 1], 1))
    assert on_edge.all()
    W1 = lv.loop(V)
    new_b = len(V) + np.nonzero(lv.boundary_edge)[0]
    x, y = W1[new_b, 0], W1[new_b, 1]
    assert (np.isclose(x, 0) | np.isclose(x, 1) | np.isclose(y, 0) | np.isclose(y, 1)).all()


def test_boundary_curve_is_cubic_bspline_of_the_boundary_polygon():
    """The crease rules make the boundary a uniform cubic B-spline of the boundary polygon: an open
    strip's boundary vertex after one level is (v_{i-1} + 6 v_i + v_{i+1}) / 8."""
    rng = np.random.default_rng(0)
    V, F = grid(nx=7, ny=3, bump=0.0)
    V = V + rng.normal(0, 0.02, V.shape)
    W = loop_level(F, len(V)).loop(V)
    for i in range(1, 6):  # bottom row, interior of the boundary chain
        np.testing.assert_allclose(W[i], (V[i - 1] + 6 * V[i] + V[i + 1]) / 8, atol=1e-12)


def test_icosphere_converges_to_a_smooth_sphere_like_limit():
    """Each level moves the existing vertices less (geometric convergence to the limit surface),
    and the limit of an icosahedron is sphere-like: radii within 2 % of their mean."""
    ico = trimesh.creation.icosahedron()
    V, F = ico.vertices, ico.faces
    moves = []
    for _ in range(5):
        W, G = subdivide_positions(V, F, 1)
        moves.append(np.abs(W[: len(V)] - V).max())
        V, F = W, G
    assert all(b < 0.5 * a for a, b in zip(moves, moves[1:])), moves
    r = np.linalg.norm(V, axis=1)
    assert (r.max() - r.min()) / r.mean() < 0.02
    assert trimesh.Trimesh(V, F, process=False).is_watertight


def test_vertex_order_and_faces_depend_only_on_connectivity():
    ico = trimesh.creation.icosphere(1)
    lv = loop_level(ico.faces, len(ico.vertices))
    np.testing.assert_array_equal(lv.midpoints(ico.vertices)[: len(ico.vertices)], ico.vertices)
    lv2 = loop_level(ico.faces.copy(), len(ico.vertices))
    np.testing.assert_array_equal(lv.faces, lv2.faces)
    assert len(lv.faces) == 4 * len(ico.faces)
    # quadrisection in the plane: every new vertex is its edge's midpoint
    M = lv.midpoints(ico.vertices)
    np.testing.assert_allclose(M[len(ico.vertices):], ico.vertices[lv.edges].mean(axis=1))


def test_loop_weights():
    np.testing.assert_allclose(loop_beta(6), 1 / 16)
    np.testing.assert_allclose(loop_beta(3), 3 / 16)
    # rows of the operators are affine combinations
    V, F = grid()
    lv = loop_level(F, len(V))
    np.testing.assert_allclose(np.asarray(lv.S_loop.sum(axis=1)).ravel(), 1.0)
    np.testing.assert_allclose(np.asarray(lv.S_mid.sum(axis=1)).ravel(), 1.0)


def test_non_manifold_edge_is_an_error_naming_it():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], float)
    F = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    with pytest.raises(NonManifoldError, match=r"edge 0-1 .* shared by 3 triangles"):
        loop_level(F, len(V), name="canopy.obj")


def test_bowtie_vertex_is_a_corner_kept_in_place():
    """Two petals touching at one vertex: the shared vertex is a documented corner and stays."""
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [-1, 0, 0.5], [-1, -1, 0.5]], float)
    F = np.array([[0, 1, 2], [0, 3, 4]])
    lv = loop_level(F, len(V))
    assert lv.corner.tolist() == [True, False, False, False, False]
    np.testing.assert_array_equal(lv.loop(V)[0], V[0])


def test_degenerate_triangle_is_an_error():
    with pytest.raises(NonManifoldError, match="repeats a vertex"):
        loop_level(np.array([[0, 1, 1]]), 3)
