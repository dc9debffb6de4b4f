"""The lily pipeline (pipelines/lily): its inputs and a short run of its stages.

What is checked (Ijiri et al. 2008, sec. 6.1 and 6.3):

- the committed key poses and weight file are what ``make_keys.py`` writes (inputs and generator
  do not drift apart);
- tepal resolution: a petal has 684 triangles (Ijiri: 685), a sepal 576 (Ijiri: 567), within 2 %;
- the bud (frame 1) is closed -- neighbouring sepal and petal overlap around the axis, the petal
  inside -- and collision-free by the exact static test;
- the joint angle between every tepal and the flower axis grows by 23 +- 1 degrees over frames
  1-60, never decreases there, and changes by less than 0.5 degree over frames 60-100;
- the midrib reflexes: the bud's tips lean inward, at frame 40 the tips point well below the
  horizontal, from frame 60 on the midrib keeps its shape, and the lamina, channelled while the
  midrib leads, ends flat across at frame 100 (a slight channel only);
- the fixed vertices of lily.weights are exactly rows 0 and 1 of every tepal in polygonize's output;
- fccompose on the pipeline's own lily.fcc / lily.scn, run for the first 12 frames (where the
  petals press on the sepals in the key-pose animation), finds and resolves collisions and writes
  frames with no intersecting triangle pairs;
- the column (five key poses, timed by column_growth.func): receptacle, pistil, a three-lobed
  stigma, six stamens with versatile anthers -- each anther attached near its middle on its
  filament's tip, along the filament in the bud and turned crosswise (a T) in the open flower,
  tilting steadily between, never flattened -- and none of them touching a tepal in the keyframes;
- the tepals are joined to the receptacle: seen from above and from the side, no background shows
  between the tepal bases and the receptacle (coverage of vertical and horizontal lines there);
- the tepal markings (paint_tepals.py): a green nectary furrow along the midrib at the claw and
  dark spots on the lower half of every tepal, none near the tip, fading in with the opening;
- the pipeline Makefile chains the stages in order;
- if `make lily` has been run, its canopy and smoothed frames are collision-free, and no tepal
  touches the pistil, stamens or receptacle.

The whole pipeline (about 40 s at draft quality) is not run here.
"""
from __future__ import annotations

import csv
import math
import shutil
import subprocess
import sys

import numpy as np
import pytest
from conftest import REPO, run_cli

from inflo.formats.floret import check_compatible, read_floret
from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.tools.collide import intersecting_pairs, intersecting_pairs_between

LILY = REPO / "pipelines" / "lily"
KEYS = [LILY / f"key_{k}.floret" for k in ("bud", "early", "mid", "open")]
COLUMN_KEYS = [LILY / f"column_{k}.floret" for k in ("bud", "early", "mid", "late", "open")]
GROWTH_COLUMN_KEYS = [LILY / f"growth_column_{k}.floret" for k in ("bud", "early", "mid", "late", "open")]
BUILD = REPO / "build" / "lily"

# polygonize's vertex order: organ by organ, copy by copy, row by row from the base
SEPAL = dict(rows=19, per_row=17, copies=3, offset=0)
PETAL = dict(rows=20, per_row=19, copies=3, offset=3 * 19 * 17)


def _tepals():
    for org in (SEPAL, PETAL):
        n = org["rows"] * org["per_row"]
        for c in range(org["copies"]):
            yield org, org["offset"] + c * n


def _load_check_module():
    import importlib.util

    spec = importlib.util.spec_from_file_location("check_lily", LILY / "check_lily.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def tepal_obj(tmp_path_factory):
    """The tepal OBJ sequence of the pipeline's key poses: 100 frames (a few seconds)."""
    out = tmp_path_factory.mktemp("lily")
    r = run_cli("floret-animate", "-q", *KEYS, "-o", out / "frames")
    assert r.returncode == 0, r.stderr
    r = run_cli("polygonize", "-q", out / "frames", "-o", out / "obj")
    assert r.returncode == 0, r.stderr
    paths = list_obj_sequence(out / "obj")
    assert len(paths) == 100
    return out / "obj", paths


def _frame(paths, n):
    """Mesh of 1-based frame n."""
    return read_obj(paths[n - 1])


def test_inputs_are_what_make_keys_writes(tmp_path):
    r = subprocess.run([sys.executable, str(LILY / "make_keys.py"), str(tmp_path)],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    written = sorted(p.name for p in tmp_path.iterdir())
    assert written == sorted([p.name for p in KEYS] + [p.name for p in COLUMN_KEYS] + [p.name for p in GROWTH_COLUMN_KEYS]
                             + ["lily.weights"])
    for name in written:
        assert (tmp_path / name).read_text() == (LILY / name).read_text(), \
            f"pipelines/lily/{name} differs from what make_keys.py writes: rerun it"


def test_key_poses_compatible_and_timed():
    poses = [read_floret(p) for p in KEYS]
    for a, b, pa, pb in zip(poses, poses[1:], KEYS, KEYS[1:]):
        check_compatible(a, b, pa, pb)
    # key times at frames 1, 40, 60, 100 of 100
    assert [round(p.key_time * 99) for p in poses] == [0, 39, 59, 99]
    for p in poses:
        sep, pet = p.organ("sepals"), p.organ("petals")
        assert (sep.symmetry_n, pet.symmetry_n) == (3, 3)
        assert pet.symmetry_phase_deg - sep.symmetry_phase_deg == pytest.approx(60.0)
    # the joint angle is carried by tilt: 23 degrees by frame 60, then held
    tilts = [p.organ("sepals").tilt_deg for p in poses]
    assert tilts[0] == 0.0 and tilts[2] == tilts[3] == pytest.approx(23.0)
    assert tilts[1] == pytest.approx(23.0 * 39 / 59, abs=1e-3)


def test_triangle_counts_near_ijiri(tepal_obj):
    _, paths = tepal_obj
    mesh = _frame(paths, 1)
    counts = {}
    for name in mesh.groups:
        g = mesh.groups.index(name)
        counts[name] = int(np.count_nonzero(np.asarray(mesh.face_group) == g))
    assert sorted(counts) == [f"petals_{c}" for c in range(3)] + [f"sepals_{c}" for c in range(3)]
    for name, n in counts.items():
        target = 685 if name.startswith("petals") else 567
        assert abs(n - target) <= 0.02 * target, (name, n)
    assert len(mesh.faces) == pytest.approx(3800, rel=0.02)  # Ijiri: ~3,800 in the flower
    assert len(mesh.vertices) == 3 * (SEPAL["rows"] * SEPAL["per_row"] + PETAL["rows"] * PETAL["per_row"])


def test_bud_is_closed_and_collision_free(tepal_obj):
    _, paths = tepal_obj
    mesh = _frame(paths, 1)
    x = mesh.vertices
    assert len(intersecting_pairs(x, mesh.faces)) == 0
    # at mid-height, the azimuth span of each tepal and its distance from the axis
    spans = {}
    for org, off in _tepals():
        row = org["rows"] // 2
        ring = x[off + row * org["per_row"]: off + (row + 1) * org["per_row"]]
        az = np.degrees(np.arctan2(-ring[:, 2], ring[:, 0]))  # +X turns toward -Z (floret.md)
        mid = az[len(az) // 2]
        rel = (az - mid + 180.0) % 360.0 - 180.0
        spans[off] = (mid % 360.0, rel.min(), rel.max(), np.linalg.norm(ring[:, [0, 2]], axis=1).mean())
    sepals = [spans[SEPAL["offset"] + c * 323] for c in range(3)]
    petals = [spans[PETAL["offset"] + c * 380] for c in range(3)]
    covered = np.zeros(360, bool)
    for mid, lo, hi, _ in sepals + petals:
        for d in range(int(math.floor(lo)), int(math.ceil(hi)) + 1):
            covered[int(round(mid + d)) % 360] = True
    assert covered.all(), "the bud is not closed at mid-height"
    for mid_s, lo_s, hi_s, r_s in sepals:
        for mid_p, lo_p, hi_p, r_p in petals:
            gap = (mid_p - mid_s + 180.0) % 360.0 - 180.0
            if abs(abs(gap) - 60.0) < 1.0:  # neighbours
                overlap = min(hi_s, gap + hi_p) - max(lo_s, gap + lo_p)
                assert overlap > 20.0, "neighbouring sepal and petal do not overlap"
                assert r_p < r_s, "the petal is not inside the sepal"


def test_joint_angle_grows_23_degrees_then_holds(tepal_obj):
    _, paths = tepal_obj
    check = _load_check_module()
    angles = np.array([check.joint_angles(read_obj(p).vertices) for p in paths])  # (100, 6)
    rise = angles[59] - angles[0]
    assert np.all(np.abs(rise - 23.0) < 1.0), rise
    assert np.all(np.diff(angles[:60], axis=0) > -1e-6)
    assert np.all(np.abs(angles[99] - angles[59]) < 0.5)
    assert np.all(np.ptp(angles[59:], axis=0) < 0.5)


def _tip_and_channel(mesh):
    """Per tepal: the direction of the midrib's last segment (degrees from +Y in the tepal's radial
    plane, positive outward) and the channel
    depth of the widest row (distance of the lateral vertex from the row's chord plane / width)."""
    x = mesh.vertices
    out = []
    for org, off in _tepals():
        pr, mid = org["per_row"], org["per_row"] // 2
        a = x[off + (org["rows"] - 3) * pr + mid]
        b = x[off + (org["rows"] - 1) * pr + mid]
        base = x[off + mid]
        radial = np.array([base[0], 0.0, base[2]]) / math.hypot(base[0], base[2])
        d = b - a
        tip = math.degrees(math.atan2(d @ radial, d[1]))  # signed: > 0 leans outward
        row = x[off + (org["rows"] * 2 // 3) * pr: off + (org["rows"] * 2 // 3 + 1) * pr]
        chord = row[-1] - row[0]
        width = np.linalg.norm(chord)
        sag = np.linalg.norm(np.cross(row[mid] - row[0], chord)) / width
        out.append((tip, sag / width))
    return np.array(out)


def test_midrib_reflexes_early_then_lamina_flattens(tepal_obj):
    _, paths = tepal_obj
    bud, early, mid, last = (_tip_and_channel(_frame(paths, n)) for n in (1, 40, 60, 100))
    assert np.all(bud[:, 0] < 0.0)              # bud: the tips lean in toward the axis
    assert np.all(early[:, 0] > 120.0)          # frame 40: the midrib reflexed hard, tips down
    assert np.all(early[:, 0] > last[:, 0] + 10.0)
    assert np.all((last[:, 0] > 90.0) & (last[:, 0] < 120.0))  # open: tips a little below level
    assert np.all(np.abs(last[:, 0] - mid[:, 0]) < 1.0)  # frames 60-100: the midrib stops warping
    assert np.all(early[:, 1] > 2.0 * last[:, 1])  # lamina lags (channel) early, flat later
    assert np.all(last[:, 1] < 0.06)


def test_weight_file_fixes_the_claws(tepal_obj):
    from inflo.formats.weights import read_weight_file

    _, paths = tepal_obj
    n = len(read_obj(paths[0]).vertices)
    ids = read_weight_file(LILY / "lily.weights", n)
    expect = []
    for org, off in _tepals():
        expect.extend(range(off, off + 2 * org["per_row"]))
    assert ids.tolist() == sorted(expect)
    # rows 0 and 1 are on the receptacle: the lowest vertices of the bud
    y = read_obj(paths[0]).vertices[:, 1]
    assert y[ids].max() < np.delete(y, ids).min() + 0.3


@pytest.mark.slow
def test_fccompose_resolves_the_tepal_contacts(tepal_obj, tmp_path):
    obj_dir, paths = tepal_obj
    # the key-pose animation alone has the petals pressing through the sepals early on
    assert any(len(intersecting_pairs(m.vertices, m.faces)) for m in (read_obj(paths[i]) for i in (6, 9)))
    text = (LILY / "lily.fcc").read_text()
    text = text.replace("../../build/lily/obj", str(obj_dir))
    text = text.replace("scene file path: lily.scn", f"scene file path: {LILY / 'lily.scn'}")
    text = text.replace("weight: 0 lily.weights", f"weight: 0 {LILY / 'lily.weights'}")
    text += "\nrun for number of frames: 12\n"
    fcc = tmp_path / "lily.fcc"
    fcc.write_text(text)
    r = run_cli("fccompose", "-q", "--strict", fcc, "-o", tmp_path / "canopy")
    assert r.returncode == 0, r.stdout + r.stderr
    out = list_obj_sequence(tmp_path / "canopy")
    assert len(out) >= 12
    for p in out:
        m = read_obj(p)
        assert len(intersecting_pairs(m.vertices, m.faces)) == 0, p.name
    with open(tmp_path / "canopy" / "log.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert sum(int(r["collisions_found"]) for r in rows) > 0
    assert all(int(r["remaining_pairs"]) == 0 for r in rows)


@pytest.fixture(scope="module")
def column_obj(tmp_path_factory):
    """The column OBJ sequence (receptacle, pistil, stigma, stamens, anthers): 100 frames."""
    out = tmp_path_factory.mktemp("lily_column")
    r = run_cli("floret-animate", "-q", *COLUMN_KEYS, "--growth", LILY / "column_growth.func",
                "-o", out / "frames")
    assert r.returncode == 0, r.stderr
    r = run_cli("polygonize", "-q", out / "frames", "-o", out / "obj")
    assert r.returncode == 0, r.stderr
    paths = list_obj_sequence(out / "obj")
    assert len(paths) == 100
    return paths


def _part(mesh, name):
    """Vertices and faces (indices into mesh.vertices) of one group."""
    g = mesh.groups.index(name)
    faces = mesh.faces[np.asarray(mesh.face_group) == g]
    return mesh.vertices[np.unique(faces)], faces


def _axis(points):
    """Centre, unit principal axis and extents (largest first) of a point cloud."""
    c = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - c)
    ext = np.ptp((points - c) @ vt.T, axis=0)
    return c, vt[0], ext


def test_column_organs_present(column_obj):
    for n in (1, 40, 60, 100):
        mesh = read_obj(column_obj[n - 1])
        want = (["receptacle_0", "pistil_0"] + [f"stigma_{c}" for c in range(3)]
                + [f"stamens_{c}" for c in range(6)] + [f"anthers_{c}" for c in range(6)])
        assert sorted(mesh.groups) == sorted(want)
        # five organ materials: receptacle, pistil, stigma, filaments, anthers
        assert len(set(np.asarray(mesh.face_material).tolist())) == 5


def test_anthers_are_versatile(column_obj):
    """Each anther sits on its filament's tip near its own middle (dorsifixed), lies along the
    filament in the bud and turns steadily to crosswise (a T) by the open flower, keeping its
    length and slender shape while it turns."""
    turns = []
    for n in (1, 20, 40, 50, 60, 75, 100):
        mesh = read_obj(column_obj[n - 1])
        per = []
        for c in range(6):
            fil, _ = _part(mesh, f"stamens_{c}")
            anth, _ = _part(mesh, f"anthers_{c}")
            tip = fil[np.argmax(fil[:, 1])]
            near = fil[np.linalg.norm(fil - tip, axis=1) < 0.3]
            fc, fd, _ = _axis(near)
            ac, aa, ext = _axis(anth)
            length, width = ext[0], ext[1]
            # attached near its middle: the filament's tip lies inside the anther, within 15 % of
            # its length from the centre along its axis
            assert np.linalg.norm(tip - ac) < 0.6 * width, (n, c)
            assert abs(np.dot(tip - ac, aa)) < 0.15 * length, (n, c)
            assert length > 2.5 * width, (n, c, length, width)  # still a slender capsule
            per.append(math.degrees(math.acos(min(1.0, abs(float(np.dot(fd, aa)))))))
        assert np.ptp(per) < 1.0  # the six stamens alike
        turns.append(float(np.mean(per)))
    assert turns[0] < 15.0, turns       # bud: along the filament
    assert turns[-1] > 75.0, turns      # open: crosswise
    assert all(b >= a - 1.0 for a, b in zip(turns, turns[1:])), turns  # tilting steadily


def test_stigma_has_three_lobes_on_the_style(column_obj):
    for n in (1, 100):
        mesh = read_obj(column_obj[n - 1])
        style, _ = _part(mesh, "pistil_0")
        top = style[:, 1].max()
        azimuths = []
        for c in range(3):
            lobe, _ = _part(mesh, f"stigma_{c}")
            lc, la, ext = _axis(lobe)
            inner = lobe[np.argmin(np.hypot(lobe[:, 0], lobe[:, 2]))]
            # attached: the lobe's inner pole near the axis, at the style's tip
            assert np.hypot(inner[0], inner[2]) < 0.03, (n, c)
            assert abs(inner[1] - top) < 0.15, (n, c)
            assert lc[1] > top - 0.05  # on top of the style, spreading outward
            azimuths.append(math.degrees(math.atan2(lc[2], lc[0])) % 360.0)
        gaps = np.diff(sorted(azimuths + [min(azimuths) + 360.0]))
        assert np.allclose(gaps, 120.0, atol=2.0), azimuths


def test_column_clear_of_the_tepals(tepal_obj, column_obj):
    """No tepal (key-pose template; fccompose keeps the claws on it and stays within about 0.04)
    touches the receptacle, pistil, stigma, filaments or anthers in the keyframes."""
    _, paths = tepal_obj
    for n in (1, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100):
        tep = _frame(paths, n)
        col = read_obj(column_obj[n - 1])
        assert len(intersecting_pairs_between(tep.vertices, tep.faces, col.vertices, col.faces)) == 0, n


def uncovered(meshes, points, axes):
    """Which 2-D points (in the coordinates ``axes`` of 3-D space) no triangle of ``meshes``
    covers in that projection: a line through the point along the third axis misses them all, so
    a view along it shows the background there."""
    tris = np.concatenate([m.vertices[m.faces][:, :, list(axes)] for m in meshes])
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    v0, v1 = b - a, c - a
    den = v0[:, 0] * v1[:, 1] - v0[:, 1] * v1[:, 0]
    keep = np.abs(den) > 1e-12
    a, v0, v1, den = a[keep], v0[keep], v1[keep], den[keep]
    out = np.zeros(len(points), bool)
    for i, p in enumerate(points):
        w = p - a
        s = (w[:, 0] * v1[:, 1] - w[:, 1] * v1[:, 0]) / den
        t = (v0[:, 0] * w[:, 1] - v0[:, 1] * w[:, 0]) / den
        out[i] = not np.any((s >= -1e-9) & (t >= -1e-9) & (s + t <= 1 + 1e-9))
    return out


def see_through(meshes, rows, axes):
    """Background points inside the silhouette: ``rows`` is a list of (k, 2) point rows across the
    view (coordinates ``axes``); in each row, the points between the first and the last covered one
    that no triangle covers (holes a view along the third axis would show)."""
    n = 0
    for row in rows:
        miss = uncovered(meshes, row, axes)
        hit = np.flatnonzero(~miss)
        if len(hit):
            n += int(miss[hit[0]:hit[-1] + 1].sum())
    return n


def test_tepals_joined_to_the_receptacle(tepal_obj, column_obj):
    """Seen from above (lines along the axis through every point within r = 0.45, the claws lying
    at r = 0.27-0.30) and from two sides (horizontal lines along X and along Z, rows where the
    claws meet the receptacle, y = -0.05 .. 0.04), tepals and receptacle leave no background
    showing between them. (Higher up, y = 0.05 - 0.15, the open flower seen along Z still shows a
    slit about 0.01 wide between a sepal's claw and the neighbouring petal's: tepal against tepal,
    from the key poses' claws; see README.md.)"""
    _, paths = tepal_obj
    r, a = np.meshgrid(np.linspace(0.02, 0.45, 24), np.radians(np.arange(0.0, 360.0, 2.0)))
    top = np.stack([(r * np.cos(a)).ravel(), (r * np.sin(a)).ravel()], axis=1)   # (x, z)
    zs = np.linspace(-0.6, 0.6, 121)
    side = [np.stack([zs, np.full_like(zs, y)], axis=1) for y in np.linspace(-0.05, 0.04, 10)]  # (z, y)
    for n in (1, 40, 60, 100):
        meshes = [_frame(paths, n), read_obj(column_obj[n - 1])]
        assert uncovered(meshes, top, (0, 2)).sum() == 0, n
        assert see_through(meshes, side, (2, 1)) == 0, n
        assert see_through(meshes, side, (0, 1)) == 0, n


def _load_paint_module():
    import importlib.util

    spec = importlib.util.spec_from_file_location("paint_tepals", LILY / "paint_tepals.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_tepal_markings(tepal_obj):
    """Painted on the unsmoothed open frame (smooth and canopy the same mesh: every vertex takes its
    own tepal coordinates): furrow, spots where an Asiatic lily has them, fading in."""
    paint = _load_paint_module()
    mesh = _frame(tepal_obj[1], 100)
    col = paint.paint(mesh, mesh, 1.0)
    for org, off in _tepals():
        rows, per_row = org["rows"], org["per_row"]
        grid = col[off:off + rows * per_row].reshape(rows, per_row, 3)
        mid = per_row // 2
        # nectary furrow: the midrib at the claw is green-yellow (green above red)
        assert grid[1, mid, 1] > grid[1, mid, 0] - 0.05, grid[1, mid]
        dark = grid.sum(axis=2) < 0.9  # spot pixels (the ground colour sums over 1.5)
        assert dark[: rows // 2].sum() >= 3, "no spots on the lower half"
        assert not dark[int(0.6 * rows):].any(), "spots near the tip"
        assert not dark[:, 0].any() and not dark[:, -1].any(), "spots on the margins"
    bud = paint.paint(mesh, mesh, 0.0)
    assert (bud.sum(axis=1) > 1.2).all()  # no markings before the inner face shows


def test_growth_lily_has_the_same_column():
    """The growth-map lily's column is the key-pose lily's (same organs, poses and timing) scaled
    nine times, on a receptacle of its own."""
    for key, growth in zip(COLUMN_KEYS, GROWTH_COLUMN_KEYS):
        a, b = read_floret(key), read_floret(growth)
        assert [o.name for o in a.organs] == [o.name for o in b.organs]
        assert a.key_time == b.key_time
        for name in ("pistil", "stigma", "stamens", "anthers"):
            np.testing.assert_allclose(b.organ(name).control_points, 9.0 * a.organ(name).control_points, atol=1e-3)


def test_built_growth_lily_column_clear_of_the_tepals(capsys):
    """If `make lily METHOD=growth` has been run: every keyframe's tepals against the column."""
    canopy, column = BUILD / "growth" / "canopy", BUILD / "growth" / "column_obj"
    if not canopy.is_dir() or not column.is_dir():
        pytest.skip("make lily METHOD=growth has not been run")
    mod = _check_growth_module()
    assert mod.main(canopy, column) == 0, capsys.readouterr().out
    out = capsys.readouterr().out
    assert "tepals against the column: 0 intersecting pairs" in out
    assert "broad, untwisted tepals" in out


def _check_growth_module():
    import importlib.util

    sys.path.insert(0, str(LILY))
    try:
        spec = importlib.util.spec_from_file_location("check_growth", LILY / "check_growth.py")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
    finally:
        sys.path.remove(str(LILY))
    return mod


def _tepal_grid(twist_deg, width=10.0, length=30.0, nu=11, nv=31):
    """A flat strip along y, its rows turned linearly about the axis up to twist_deg at the tip."""
    s, t = np.meshgrid(np.linspace(-0.5, 0.5, nu), np.linspace(0.0, 1.0, nv))
    a = np.radians(twist_deg) * t
    x = np.stack([width * s * np.cos(a), length * t, width * s * np.sin(a)], axis=-1).reshape(-1, 3)
    return x, [("petal", np.arange(nu * nv).reshape(nv, nu))]


def test_growth_check_measures_breadth_and_twist():
    """check_growth.breadth: a flat strip 30 long and 10 wide is 3 times as long as wide and untwisted;
    the same strip turned 60 degrees along its length twists 60 x 0.9 (rows up to 0.9 of it)
    less the widest row's own turn, and fails the check's bound."""
    mod = _check_growth_module()
    x, tepals = _tepal_grid(0.0)
    (slender, twist), = mod.breadth(x, tepals)
    assert slender == pytest.approx(3.0, rel=1e-6) and twist == pytest.approx(0.0, abs=1e-6)
    x, tepals = _tepal_grid(60.0)
    (slender, twist), = mod.breadth(x, tepals)
    assert slender == pytest.approx(3.0, rel=1e-6)
    assert twist > mod.TWIST and twist == pytest.approx(54.0, abs=0.5)


def test_makefile_chains_the_stages():
    make = shutil.which("make")
    if make is None:
        pytest.skip("no make")
    r = subprocess.run([make, "-n", "-B", "-C", str(LILY), "all"], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 0, r.stderr
    order = ["floret-animate", "polygonize", "fccompose", "subdivide", "paint_tepals.py", "canopy-render",
             "check_lily.py"]
    pos = [r.stdout.find(word) for word in order]
    assert all(p >= 0 for p in pos), dict(zip(order, pos))
    assert pos == sorted(pos)
    assert "lily.fcc" in r.stdout and "--levels 1" in r.stdout
    r = subprocess.run([make, "-n", "-B", "-C", str(LILY), "smooth", "QUALITY=final"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and "--levels 2" in r.stdout


def test_built_lily_is_collision_free(capsys, species_build):
    """The exact test over the built canopy (every tenth frame), the smoothed frames, and the
    tepals against the pistil/stamens/receptacle (pipelines/lily/check_lily.py), over the draft
    build of the session (conftest's ``species_build``, shared with the golden-file tests)."""
    species_build("lily")  # the draft build, made here if no test made it yet
    if not (BUILD / "canopy").is_dir() or not (BUILD / "smooth" / ".done").is_file():
        pytest.skip("make lily has not been run")
    check = _load_check_module()
    assert check.main(BUILD) == 0, capsys.readouterr().out


def test_built_lily_viewer_plays_the_opening_in_a_browser(species_build):
    """`make lily` writes build/lily/viewer/ (the `viewer` target; made here when the golden-file
    tests built the lily's stages but not it): served by canopy-view's server
    and opened in headless Chromium, the page draws the lily at frame 1 (the bud) and at frame 100
    (the open flower), and the two differ; the screenshots are kept in build/test-artefacts/."""
    species_build("lily")  # the draft build, made here if no test made it yet
    import urllib.request

    page = BUILD / "viewer" / "index.html"
    if not page.is_file() and (BUILD / "canopy").is_dir():
        # the golden-file tests build the lily's stages they compare, not its viewer: write it
        make = shutil.which("make") or "make"
        r = subprocess.run([make, "-C", str(LILY), "viewer", "QUALITY=draft"], capture_output=True, text=True,
                           timeout=900)
        assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    if not page.is_file():
        pytest.skip("make lily has not been run")
    from conftest import VIEWER_BACKGROUND, browser_screenshot, find_browser, test_artefacts_folder

    browser = find_browser()
    if browser is None:
        pytest.skip("no headless Chromium found: install it as root with 'apt-get install -y chromium-headless-shell'")
    from inflo.tools.canopy_view import cli as view_cli

    server = view_cli.serve(view_cli.viewer_folder(BUILD))
    try:
        base = f"http://127.0.0.1:{server.server_address[1]}/index.html"
        with urllib.request.urlopen(base.replace("index.html", "lily.glb"), timeout=10) as r:
            assert r.read(4) == b"glTF"
        out = test_artefacts_folder()
        bud = browser_screenshot(browser, base + "?frame=1", out / "lily_viewer_frame_1.png")
        open_ = browser_screenshot(browser, base + "?frame=100", out / "lily_viewer_frame_100.png")
    finally:
        server.shutdown()
        server.server_close()
    h, w, _ = bud.shape
    body = (slice(int(0.15 * h), int(0.85 * h)), slice(0, w))
    drawn = [float((np.abs(s[body] - np.array(VIEWER_BACKGROUND)).sum(axis=2) > 30).mean()) for s in (bud, open_)]
    assert drawn[0] > 0.002 and drawn[1] > 0.01, f"the lily is not drawn: {drawn}"
    # the open flower covers more of the page than the bud
    assert drawn[1] > 1.5 * drawn[0], drawn
