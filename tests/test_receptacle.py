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


# ---- the phyllaries of the underside and the stem's stump ----------------------------------------

CLOTHED = dict(segments=40, rings=8, underside_rings=5, depth=0.3, stem=0.22, inset=0.003, stem_length=0.8,
               phyllary_rows=5, phyllaries=21, phyllary_length=0.5, phyllary_width=0.92, phyllary_gap=0.006,
               phyllary_spread=0.04)


def _split(mesh):
    body = mesh.face_group == mesh.groups.index("receptacle")
    return mesh.faces[body], mesh.faces[~body]


@pytest.mark.parametrize("curve", ["disk", "sphere_cap", "paraboloid", "cone"])
@pytest.mark.parametrize("spread", [0.0, 0.04, 0.2])
def test_phyllaries_touch_neither_one_another_nor_the_receptacle(curve, spread):
    from inflo.tools.collide.tritri import intersecting_pairs
    prof = builtin_curve(curve, radius=1.0, height=0.3, angle=70.0, samples=512)
    mesh = receptacle_mesh(prof, ReceptacleOptions(**{**CLOTHED, "phyllary_spread": spread}))
    assert mesh.groups == ["receptacle", "phyllaries"] and mesh.materials == ["mtl5", "mtl4"]
    body, ph = _split(mesh)
    assert len(ph) == 5 * 21 * len(_phyllary_faces())
    # the receptacle with its stump is still a closed outward solid
    tm = trimesh.Trimesh(mesh.vertices, body, process=False)
    tm.remove_unreferenced_vertices()
    assert tm.is_watertight and tm.volume > 0
    assert len(intersecting_pairs(mesh.vertices, mesh.faces)) == 0


def _phyllary_faces():
    from inflo.tools.phyllotaxis.receptacle import _phyllary_faces as faces
    return faces()


def test_phyllaries_brute_force_on_a_small_tight_head():
    """Few, wide bracts on a shallow underside (the sag near its bound), varied the most: the exact
    all-pairs test."""
    from inflo.tools.collide.tritri import intersecting_pairs_brute
    from inflo.tools.phyllotaxis.receptacle import phyllary_sagitta
    opts = ReceptacleOptions(segments=12, rings=3, underside_rings=3, depth=0.2, stem=0.3, phyllary_rows=3,
                             phyllaries=5, phyllary_length=0.6, phyllary_width=0.99, phyllary_gap=0.0055,
                             phyllary_spread=0.1, phyllary_variation=0.3)
    assert phyllary_sagitta(opts) < 0.5 * opts.phyllary_gap
    mesh = receptacle_mesh(builtin_curve("disk", radius=1.0, samples=256), opts)
    assert len(intersecting_pairs_brute(mesh.vertices, mesh.faces)) == 0


def test_phyllaries_are_imbricate_rows_that_hide_the_underside():
    """Each row on its own offset (the rows nearer the stem outermost), bracts of a row apart,
    facing out; from below and from the side the underside is mostly hidden, and the mesh grows
    with the head (every length a fraction of the rim radius)."""
    from inflo.formats.obj import ObjMesh
    from inflo.tools.species.checks import region_in_view
    prof = builtin_curve("disk", radius=1.0, samples=512)
    opts = ReceptacleOptions(**{**CLOTHED, "phyllary_spread": 0.0})
    mesh = receptacle_mesh(prof, opts)
    body, ph = _split(mesh)
    per = len(_phyllary_faces())
    first = int(body.max()) + 1
    pv = mesh.vertices[first:].reshape(5, 21, -1, 3)  # rows x bracts x vertices
    # distance of every bract vertex from the underside's quarter ellipse (rim r = 1, y = -inset)
    rim_r, rim_y, stem_r = 1.0, -0.003, 0.22
    phi = np.linspace(0.0, 0.5 * np.pi, 20001)
    ell = np.stack([stem_r + (rim_r - stem_r) * np.cos(phi), rim_y - 0.3 * np.sin(phi)], axis=1)
    tree = __import__("scipy.spatial", fromlist=["cKDTree"]).cKDTree(ell)
    for j in range(5):
        v = pv[j].reshape(-1, 3)
        d, _ = tree.query(np.stack([np.hypot(v[:, 0], v[:, 2]), v[:, 1]], axis=1))
        assert d.min() == pytest.approx((j + 1) * 0.006, abs=2e-4)
        assert d.max() <= (j + 1.25) * 0.006 + 2e-4
        # within a row, every bract inside its own slot of 2 pi / 21 (so the spans are disjoint),
        # at most 0.92 of the slot wide, and no two alike (seeded variation)
        ang = np.arctan2(pv[j, :, :, 2], pv[j, :, :, 0])
        centre = 2 * np.pi * (np.arange(21) + 0.5 * (j % 2)) / 21
        off = (ang - centre[:, None] + np.pi) % (2 * np.pi) - np.pi
        assert np.abs(off).max() < np.pi / 21
        span = off.max(axis=1) - off.min(axis=1)
        assert span.max() <= 2 * 0.92 * np.pi / 21 + 1e-9
        assert np.std(span) > 0.01 * span.mean()
    # faces point away from the receptacle: down or outward
    tri = mesh.vertices[ph]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    c = tri.mean(axis=1)
    outward = n[:, 0] * c[:, 0] + n[:, 2] * c[:, 2] - n[:, 1]
    assert (outward > 0).all()
    # the underside (no stump, no disc) from below and from the side, with and without bracts
    v, f = mesh.vertices, mesh.faces
    nrm = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    rad = np.hypot(v[:, 0], v[:, 2])
    body_mask = mesh.face_group == 0
    under = body_mask & (nrm[:, 1] < -0.2 * np.linalg.norm(nrm, axis=1)) & (rad[f].min(axis=1) > 1e-9)
    region = ObjMesh(v, f[under])
    assert region_in_view(ObjMesh(v, ph), region, 0.0, -90.0) < 0.15
    assert region_in_view(ObjMesh(v, ph), region, 20.0, -35.0) < 0.2
    assert region_in_view(ObjMesh(v, ph[:0]), region, 20.0, -35.0) == pytest.approx(1.0)
    # the same head twice the size: the same mesh, twice as large
    big = receptacle_mesh(builtin_curve("disk", radius=2.0, samples=512),
                          ReceptacleOptions(**{**CLOTHED, "phyllary_spread": 0.0, "inset": 0.006}))
    np.testing.assert_allclose(big.vertices, 2 * mesh.vertices, atol=1e-9)
    assert np.array_equal(big.faces, mesh.faces)
    assert per * 105 == len(ph)
    # the variation is seeded: the same bracts again; another seed, other bracts; none, all alike
    again = receptacle_mesh(prof, ReceptacleOptions(**{**CLOTHED, "phyllary_spread": 0.0}))
    np.testing.assert_array_equal(again.vertices, mesh.vertices)
    other = receptacle_mesh(prof, ReceptacleOptions(**{**CLOTHED, "phyllary_spread": 0.0, "phyllary_seed": 2}))
    assert not np.allclose(other.vertices, mesh.vertices)
    alike = receptacle_mesh(prof, ReceptacleOptions(**{**CLOTHED, "phyllary_spread": 0.0, "phyllary_variation": 0.0}))
    a = alike.vertices[first:].reshape(5, 21, -1, 3)
    radius = np.hypot(a[..., 0], a[..., 2])
    np.testing.assert_allclose(radius, np.broadcast_to(radius[:, :1], radius.shape), atol=1e-12)  # all alike


def test_stem_stump_hangs_below_the_underside():
    prof = builtin_curve("disk", radius=1.0, samples=256)
    bare = receptacle_mesh(prof, ReceptacleOptions(segments=16, rings=4, underside_rings=3, depth=0.3, stem=0.2))
    stump = receptacle_mesh(prof, ReceptacleOptions(segments=16, rings=4, underside_rings=3, depth=0.3, stem=0.2,
                                                    stem_length=1.5))
    assert len(stump.vertices) == len(bare.vertices) + 16
    assert stump.vertices[:, 1].min() == pytest.approx(bare.vertices[:, 1].min() - 1.5)
    low = stump.vertices[-17:-1]
    np.testing.assert_allclose(np.hypot(low[:, 0], low[:, 2]), 0.2)
    tm = trimesh.Trimesh(stump.vertices, stump.faces, process=False)
    assert tm.is_watertight and tm.volume > 0


@pytest.mark.parametrize("keys, message", [
    ("phyllary_rows = 3\nphyllary_width = 1.0\n", "receptacle.phyllary_width in (0, 1)"),
    ("phyllary_rows = 13\n", "receptacle.phyllary_rows in [0, 12]"),
    ("stem = 0.0\nstem_length = 1.0\n", "receptacle.stem_length 0 when receptacle.stem is 0"),
    ("depth = 0.05\nphyllary_rows = 3\n", "receptacle.phyllary_gap at least"),
])
def test_phyllary_keys_are_checked(tmp_path, keys, message):
    (tmp_path / "p.toml").write_text(DYNAMIC + "[receptacle]\nsegments = 16\nrings = 4\n" + keys)
    r = run_cli("phyllotaxis", "-q", str(tmp_path / "p.toml"), "-o", str(tmp_path / "out"))
    assert r.returncode == 2 and message in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_phyllaries_follow_the_growing_head(tmp_path):
    (tmp_path / "p.toml").write_text(DYNAMIC + "[receptacle]\nsegments = 16\nrings = 4\nstem_length = 0.5\n"
                                     "phyllary_rows = 3\nphyllaries = 8\nphyllary_spread = 0.03\n")
    r = run_cli("phyllotaxis", "-q", str(tmp_path / "p.toml"), "-o", str(tmp_path / "out"))
    assert r.returncode == 0, r.stderr
    meshes = [read_obj(f) for f in list_obj_sequence(tmp_path / "out" / "receptacle")]
    assert all(np.array_equal(m.faces, meshes[0].faces) for m in meshes)
    from inflo.tools.collide.tritri import intersecting_pairs
    assert all(len(intersecting_pairs(m.vertices, m.faces)) == 0 for m in meshes)
    assert meshes[-1].materials == ["mtl5", "mtl4"]


def test_species_checks_measure_the_back_and_find_the_body():
    """checks.underside_in_view: 1.0 bare, well under it clothed, lower still with something in
    front; receptacle_body drops the phyllaries, also in a mesh of several heads (groups
    receptacle_k, phyllaries_k, as the dyssodia's compose_heads.py writes them)."""
    from inflo.formats.obj import ObjMesh
    from inflo.tools.species.checks import receptacle_body, underside_in_view
    prof = builtin_curve("sphere_cap", radius=1.0, angle=60.0, samples=512)
    bare = receptacle_mesh(prof, ReceptacleOptions(**{**CLOTHED, "phyllary_rows": 0}))
    clothed = receptacle_mesh(prof, ReceptacleOptions(**CLOTHED))
    assert underside_in_view(bare) == (1.0, 1.0)
    below, side = underside_in_view(clothed)
    assert below < 0.2 and side < 0.3
    # a disc under the head hides its whole underside from straight below
    disc = ObjMesh(np.array([[-3.0, -2.0, -3.0], [3.0, -2.0, -3.0], [3.0, -2.0, 3.0], [-3.0, -2.0, 3.0]]),
                   np.array([[0, 1, 2], [0, 2, 3]], np.int32))
    assert underside_in_view(clothed, disc)[0] == pytest.approx(0.0, abs=1e-3)
    body = receptacle_body(clothed)
    np.testing.assert_array_equal(body.faces, bare.faces)
    assert receptacle_body(bare) is bare
    # two heads in one mesh, their groups numbered
    n = len(clothed.vertices)
    two = ObjMesh(np.vstack([clothed.vertices, clothed.vertices + [5.0, 0.0, 0.0]]),
                  np.vstack([clothed.faces, clothed.faces + n]),
                  groups=["receptacle_0", "phyllaries_0", "receptacle_1", "phyllaries_1"],
                  face_group=np.concatenate([clothed.face_group, clothed.face_group + 2]).astype(np.int32))
    assert len(receptacle_body(two).faces) == 2 * len(bare.faces)
    assert underside_in_view(two)[0] < 0.25  # (the raster is coarser on two heads: 0.15 against 0.13)
