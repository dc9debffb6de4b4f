"""phyllotaxis [receptacle]: the supporting surface as a closed mesh, one per RBA frame."""
from __future__ import annotations

import numpy as np
import pytest
import trimesh
from conftest import run_cli

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.tools.phyllotaxis.receptacle import ReceptacleOptions, receptacle_mesh
from inflo.tools.phyllotaxis.surface import builtin_curve

DYNAMIC = ("[surface]\ncurve = 'sphere_cap'\nangle = 60\n[primordia]\n"
           "[dynamics]\nmode = 'centripetal'\nframes = 8\ninterval = 0.5\nprimordium_area = 0.02\n"
           "inner_area = 0.3\nprimordium_growth = 0.02\ninner_growth = 0.01\n"
           "curves = ['sphere_cap', 'disk']\ncurve_times = [0.0, 1.0]\n")


@pytest.mark.parametrize("curve", ["disk", "sphere_cap", "paraboloid", "cone"])
def test_receptacle_is_a_closed_outward_solid_under_the_surface(curve):
    prof = builtin_curve(curve, radius=1.0, height=0.3, angle=70.0, samples=512)
    opts = ReceptacleOptions(segments=32, rings=10, underside_rings=5, depth=0.3, stem=0.2, inset=0.01)
    mesh = receptacle_mesh(prof, opts)
    tm = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    assert tm.is_watertight and tm.is_winding_consistent
    assert tm.volume > 0  # outward normals
    # the top lies `inset` below the generating curve along its normal: every top vertex is
    # 0.01 from the surface of revolution (distance to the sampled curve in the (r, y) plane)
    n_top = 1 + opts.rings * opts.segments
    v = mesh.vertices[1:n_top]
    ry = np.stack([np.hypot(v[:, 0], v[:, 2]), v[:, 1]], axis=1)
    curve_pts = np.stack([prof.r, prof.y], axis=1)
    dist = np.min(np.linalg.norm(ry[:, None, :] - curve_pts[None, :, :], axis=2), axis=1)
    np.testing.assert_allclose(dist, 0.01, atol=2e-3)
    # the rim is at the curve's end, the stem at 0.2 x its radius
    rim = mesh.vertices[1 + (opts.rings - 1) * opts.segments]
    assert np.hypot(rim[0], rim[2]) == pytest.approx(prof.r[-1] - 0.01 * prof.nr[-1], abs=1e-9)


def test_receptacle_frames_follow_the_growing_pattern_with_one_topology(tmp_path):
    (tmp_path / "p.toml").write_text(DYNAMIC + "[receptacle]\nsegments = 16\nrings = 4\ninset = 0.002\n")
    r = run_cli("phyllotaxis", "-q", str(tmp_path / "p.toml"), "-o", str(tmp_path / "out"))
    assert r.returncode == 0, r.stderr
    frames = list_obj_sequence(tmp_path / "out" / "receptacle")
    assert len(frames) == 8
    meshes = [read_obj(f) for f in frames]
    assert all(np.array_equal(m.faces, meshes[0].faces) for m in meshes)
    radii = [np.hypot(m.vertices[:, 0], m.vertices[:, 2]).max() for m in meshes]
    assert all(b > a for a, b in zip(radii, radii[1:]))  # the head grows
    # every floret of a frame stands on that frame's receptacle: just above its top (inset)
    from inflo.formats.rba import read_rba
    last = read_rba(tmp_path / "out" / "rba" / "0007.rba")
    top = meshes[-1].vertices[1:1 + 4 * 16:16]  # the top rings at angle 0, apex outward
    apex = meshes[-1].vertices[0]
    ring_r = np.concatenate([[0.0], top[:, 0]])
    ring_y = np.concatenate([[apex[1]], top[:, 1]])
    r = np.hypot(last.pos[:, 0], last.pos[:, 2])
    gap = last.pos[:, 1] - np.interp(r, ring_r, ring_y)
    assert (gap > 0).all() and (gap < 0.05).all()
    assert meshes[-1].materials == ["mtl5"]


def test_receptacle_bad_keys_are_one_line_errors(tmp_path):
    (tmp_path / "p.toml").write_text(DYNAMIC + "[receptacle]\nsegments = 2\n")
    r = run_cli("phyllotaxis", "-q", str(tmp_path / "p.toml"), "-o", str(tmp_path / "out"))
    assert r.returncode == 2 and "receptacle.segments >= 3" in r.stderr
    assert not (tmp_path / "out").exists()
    (tmp_path / "p.toml").write_text(DYNAMIC + "[receptacle]\nsegmnts = 20\n")
    r = run_cli("phyllotaxis", "-q", str(tmp_path / "p.toml"), "-o", str(tmp_path / "out"))
    assert r.returncode == 2 and "did you mean 'segments'" in r.stderr
