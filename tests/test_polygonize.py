"""polygonize: sampling by lambda/eta (thesis 2.4, eq. 2.1), Delaunay once, symmetry, welded
fused seams, no degenerate triangles, CLI."""
from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import REPO, run_cli
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from inflo.formats.errors import InputError
from inflo.formats.floret import Floret, Organ, read_floret, write_floret
from inflo.formats.func import Function, write_func
from inflo.formats.obj import read_obj_sequence
from inflo.tools.floret_animate.animate import FloretAnimator
from inflo.tools.polygonize.mesh import fused_v, triangle_areas
from inflo.tools.polygonize.run import polygonize_frames
from inflo.tools.polygonize.sampling import load_profile, row_counts, row_parameters

EXAMPLES = REPO / "pipelines" / "examples"


# ----------------------------------------------------------------------------------------------
# sampling
# ----------------------------------------------------------------------------------------------


def test_constant_lambda_rows():
    v, scale = row_parameters(load_profile(0.125, "lambda"))
    np.testing.assert_allclose(v, np.arange(9) / 8, atol=1e-15)
    assert scale == 1.0 and v[-1] == 1.0
    v, scale = row_parameters(load_profile(0.3, "lambda"))  # 1/0.3 = 3.33 -> 3 intervals
    np.testing.assert_allclose(v, [0, 1 / 3, 2 / 3, 1])
    assert scale == pytest.approx((1 / 0.3) / 3)


@pytest.mark.parametrize("points", [
    [(0, 0.02), (1, 0.2)],                       # linear (a straight segment)
    [(0, 0.1), (0.4, 0.03), (0.7, 0.03), (1, 0.12)],
    [(0, 0.05), (0.5, 0.05), (1, 0.05)],
])
def test_lambda_function_intervals_integrate_to_one(points):
    fn = Function.from_points(points, name="lambda", samples=200)
    lam = load_profile(fn, "lambda")
    v, scale = row_parameters(lam)
    assert v[0] == 0.0 and v[-1] == 1.0 and (np.diff(v) > 0).all()
    for a, b in zip(v[:-1], v[1:]):
        x = np.linspace(a, b, 4001)
        integral = np.trapezoid(1.0 / (scale * fn(x)), x)
        assert integral == pytest.approx(1.0, abs=1e-4)
    # the adjustment that lands the last row on the tip is small: |scale - 1| <= 1 / (2 n)
    n = len(v) - 1
    assert abs(scale - 1.0) <= 0.5 / n + 1e-9


def test_eta_counts_odd():
    eta = load_profile(Function.from_points([(0, 1), (0.5, 6.2), (1, 4)], name="eta"), "eta")
    v = np.linspace(0, 1, 21)
    c = row_counts(eta, v)
    assert (c % 2 == 1).all() and (c >= 1).all()
    np.testing.assert_array_equal(row_counts(load_profile(4.0, "eta"), [0, 1]), [5, 5])
    np.testing.assert_array_equal(row_counts(load_profile(5.0, "eta"), [0, 1]), [5, 5])
    np.testing.assert_array_equal(row_counts(load_profile(5.2, "eta"), [0, 1]), [7, 7])
    collapsed = np.zeros(21, bool)
    collapsed[-1] = True
    assert row_counts(eta, v, collapsed)[-1] == 1


def test_bad_lambda_eta(tmp_path):
    with pytest.raises(InputError, match="lambda"):
        load_profile(0.0, "lambda")
    with pytest.raises(InputError, match="lambda"):
        load_profile(Function.from_points([(0, 0.1), (0.5, -0.3), (1, 0.1)], name="l"), "lambda")
    with pytest.raises(InputError, match="eta"):
        load_profile(0.5, "eta")
    p = tmp_path / "eta.func"
    write_func(p, Function.from_points([(0, 3), (1, 0.2)], name="eta"))
    with pytest.raises(InputError, match="eta.func.*eta"):
        load_profile(str(p), "eta")


# ----------------------------------------------------------------------------------------------
# meshes
# ----------------------------------------------------------------------------------------------


def flat_petal(tip_collapsed=False, nu=3, nv=5):
    """A flat bilateral half petal in the XY plane direction: width grows then shrinks."""
    rows = []
    for j in range(nv):
        y = j / (nv - 1)
        w = 0.0 if (tip_collapsed and j == nv - 1) else 0.15 + 0.2 * math.sin(math.pi * y * 0.8)
        rows.append([[0.2 + 0.1 * y, y, w * i / (nu - 1)] for i in range(nu)])
    return np.array(rows)


def one_petal_floret(cp, **kw):
    kw.setdefault("symmetry_n", 1)
    return Floret("f", (Organ("petal", 3, 3, cp, bilateral=True, **kw),), 0.0)


def test_default_sampling_is_the_isoparametric_grid():
    f = one_petal_floret(flat_petal())
    (mesh,), rep = polygonize_frames([f])
    assert mesh.n_vertices == 121 and mesh.n_faces == 200  # 11 x 11 grid, two triangles per cell
    # every triangle is half a grid cell: in (row, col) it spans one row step and one column step
    idx = mesh.faces
    r, c = idx // 11, idx % 11
    assert ((r.max(1) - r.min(1)) == 1).all() and ((c.max(1) - c.min(1)) == 1).all()
    assert rep.triangles_per_organ == {"petal": 200}


def test_no_triangle_straddles_the_midline():
    eta = Function.from_points([(0, 3), (0.5, 9), (1, 5)], name="eta")
    f = one_petal_floret(flat_petal(), eta=None)
    (mesh,), _ = polygonize_frames([f], eta=eta, lam=0.07)
    # the organ's midline is z = 0 (a flat petal: z is the across coordinate)
    z = mesh.vertices[:, 2][mesh.faces]
    assert ((z <= 1e-12).all(axis=1) | (z >= -1e-12).all(axis=1)).all()
    # and the mesh is mirror-symmetric
    mirrored = mesh.vertices * [1, 1, -1]
    d, _ = cKDTree(mesh.vertices).query(mirrored)
    assert d.max() < 1e-12


def test_collapsed_tip_has_no_degenerate_triangle():
    a = one_petal_floret(flat_petal(tip_collapsed=True))
    cp2 = flat_petal(tip_collapsed=True) * [1.3, 1.2, 1.5]
    b = Floret("f", (Organ("petal", 3, 3, cp2, bilateral=True),), 1.0)
    frames = list(FloretAnimator([a, b]).frames(5))
    meshes, rep = polygonize_frames(frames, eta=7, lam=0.1)
    assert rep.degenerate == 0 and "petal" in rep.collapsed
    for m in meshes:
        assert triangle_areas(m.vertices, m.faces).min() > 1e-6
        tree = cKDTree(m.vertices)
        assert not tree.query_pairs(1e-9)  # no coincident vertices: the tip is one vertex
    assert rep.min_angle > 5.0


def test_example_constant_topology_welded_seams_and_report(tmp_path):
    bud = read_floret(EXAMPLES / "disk_bud.floret")
    op = read_floret(EXAMPLES / "disk_open.floret")
    frames = list(FloretAnimator([bud, op]).frames(12))
    meshes, rep = polygonize_frames(frames)
    first = meshes[0]
    for m in meshes[1:]:
        assert m.same_topology(first) and m.groups == first.groups
    assert first.groups == [f"corolla_{k}" for k in range(5)] + [f"stamens_{k}" for k in range(5)]
    assert first.materials == ["mtl1", "mtl6"]
    assert rep.degenerate == 0 and rep.min_angle > 5.0
    corolla = bud.organs[0]
    assert fused_v(corolla) == 0.75  # fused 6 of 7 rows, cubic: knot tau_6
    for m in meshes:
        # no coincident duplicate vertices anywhere (the seams are welded, not doubled)
        assert not cKDTree(m.vertices).query_pairs(1e-7)
        assert triangle_areas(m.vertices, m.faces).min() > 1e-9
    # the fused corolla is one connected mesh; so is the (fully fused) stamen tube
    for organ, lo, hi in (("corolla", 0, 5), ("stamens", 5, 10)):
        faces = first.faces[(first.face_group >= lo) & (first.face_group < hi)]
        used = np.unique(faces)
        e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
        g = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(first.n_vertices,) * 2)
        n, labels = connected_components(g, directed=False)
        assert len(np.unique(labels[used])) == 1, organ
    # the stamen tube is closed around: no boundary edge runs along v (only the two rims)
    faces = first.faces[first.face_group >= 5]
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    uniq, counts = np.unique(e, axis=0, return_counts=True)
    boundary = uniq[counts == 1]
    y = first.vertices[:, 1]
    assert np.allclose(y[boundary[:, 0]], y[boundary[:, 1]], atol=1e-9)


def test_cli_minimal_invocation_and_errors(tmp_path):
    frames = tmp_path / "frames"
    res = run_cli("floret-animate", EXAMPLES / "disk_bud.floret", EXAMPLES / "disk_open.floret",
                  "-o", frames, "--frames", "6", "-q")
    assert res.returncode == 0, res.stderr
    out = tmp_path / "obj"
    res = run_cli("polygonize", frames, "-o", out)
    assert res.returncode == 0, res.stderr
    assert "triangles per floret" in res.stdout and "minimum angle" in res.stdout
    assert "under 10 deg" in res.stdout
    paths, meshes = read_obj_sequence(out)
    assert [p.name for p in paths] == [f"frame_{i:04d}.obj" for i in range(6)]
    text = paths[0].read_text()
    assert "g corolla_0" in text and "usemtl mtl1" in text and "usemtl mtl6" in text

    res = run_cli("polygonize", frames, "-o", tmp_path / "o2", "--lambda", "0")
    assert res.returncode == 2 and "lambda" in res.stderr and len(res.stderr.strip().splitlines()) == 1
    res = run_cli("polygonize", frames, "-o", tmp_path / "o3", "--eta", "0.5")
    assert res.returncode == 2 and "eta" in res.stderr
    res = run_cli("polygonize", tmp_path / "nothing", "-o", tmp_path / "o4")
    assert res.returncode == 2

    # frames that do not share a control-mesh topology
    write_floret(frames / "frame_0009.floret", one_petal_floret(flat_petal()))
    res = run_cli("polygonize", frames, "-o", tmp_path / "o5")
    assert res.returncode == 2 and "frame_0009.floret" in res.stderr
