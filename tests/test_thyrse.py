"""thyrse: the branching-first layout of a lilac thyrse (thesis sec. 4.5, figs. 4.9,
4.10, ch. 7): the layout on tiny cases, decussate angles, the positional functions (length, order,
density, angle, size, development window) respected, branch-gen's meshes reused, the CLI."""
from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import run_cli

from inflo.formats.errors import FormatError
from inflo.formats.obj import read_obj
from inflo.formats.scn import read_scn
from inflo.tools.thyrse.generate import grow_thyrse, node_directions, thyrse, thyrse_scene, write_thyrse
from inflo.tools.thyrse.params import params_from_toml, read_params

Y = np.array([0.0, 1.0, 0.0])


def _func(path, pts):
    path.write_text("fver 1 1\nname: f\nsamples: 100\nflip: off\n"
                    f"points: {len(pts)}\n" + "".join(f"{x} {y}\n" for x, y in pts))
    return path.name


def _params(tmp_path=None, **thyrse):
    dev = thyrse.pop("development", {})
    return params_from_toml({"thyrse": thyrse, "development": dev}, folder=tmp_path)


def _main_laterals(lay, n_nodes):
    """(node, child) of the main axis' laterals: the children of main-axis nodes that leave the Y axis."""
    out = []
    on_axis = np.abs(lay.node_pos[:, [0, 2]]).max(axis=1) < 1e-12
    for c in range(len(lay.node_pos)):
        p = lay.node_parent[c]
        if p >= 0 and on_axis[p] and not on_axis[c]:
            out.append((p, c))
    return out


def test_tiny_thyrse_counts_and_structure():
    # 2 node pairs, order 0, laterals 0.4 long with density 5 -> 2 node pairs each: 2 * 2 + 1 florets
    p = _params(length=1.0, nodes=2, first_node=0.5, lateral_length=0.4, order=0.0, density=5.0, angle=60.0,
                pedicel_length=0.05)
    lay = grow_thyrse(p)
    assert len(lay.floret_node) == 4 * (2 * 2 + 1) + 1
    # a forest with one root (the base), every floret on a tip node and every tip a floret
    assert (lay.node_parent == -1).sum() == 1 and lay.node_parent[0] == -1
    assert np.all(lay.node_parent[1:] < np.arange(1, len(lay.node_parent)))
    assert lay.node_tip.sum() == len(lay.floret_node)
    assert np.array_equal(np.nonzero(lay.node_tip)[0], np.sort(lay.floret_node))
    # tips are leaves
    assert not np.isin(lay.floret_node, lay.node_parent).any()
    # the apex floret at the top of the main axis, pointing up
    top = int(np.argmax(lay.floret_pos[:, 1]))
    np.testing.assert_allclose(lay.floret_pos[top], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(lay.floret_up[top], Y, atol=1e-12)
    # pedicels: florets of order -1 sit pedicel_length from their node
    ped = lay.floret_order == -1
    d = np.linalg.norm(lay.floret_pos[ped] - lay.node_pos[lay.node_parent[lay.floret_node[ped]]], axis=1)
    np.testing.assert_allclose(d, 0.05, atol=1e-12)
    # frames: unit up, right orthogonal to it
    np.testing.assert_allclose(np.linalg.norm(lay.floret_up, axis=1), 1.0)
    np.testing.assert_allclose(np.einsum("ij,ij->i", lay.floret_up, lay.floret_right), 0.0, atol=1e-12)


def test_node_pairs_are_opposite_and_decussate():
    p = _params(length=1.0, nodes=6, first_node=0.2, lateral_length=0.3, order=0.0, density=0.0, angle=50.0)
    lay = grow_thyrse(p)
    lats = _main_laterals(lay, 6)
    assert len(lats) == 12
    by_node = {}
    for node, c in lats:
        by_node.setdefault(node, []).append(lay.node_pos[c] - lay.node_pos[node])
    heights = sorted(by_node, key=lambda k: lay.node_pos[k, 1])
    az = []
    for k in heights:
        a, b = by_node[k]
        ha, hb = a[[0, 2]] / np.linalg.norm(a[[0, 2]]), b[[0, 2]] / np.linalg.norm(b[[0, 2]])
        assert ha @ hb == pytest.approx(-1.0)  # opposite
        for v in (a, b):  # at the branch angle from the axis
            assert math.degrees(math.acos(v @ Y / np.linalg.norm(v))) == pytest.approx(50.0)
        az.append(math.degrees(math.atan2(ha[1], ha[0])))
    for a0, a1 in zip(az, az[1:]):  # successive pairs turned by 90 degrees (mod 180: a pair)
        assert abs(((a1 - a0) % 180.0) - 90.0) < 1e-9


def test_node_directions_divergence():
    a, b = node_directions(Y, 90.0, 0.0)
    c, _ = node_directions(Y, 90.0, 90.0)
    assert a @ b == pytest.approx(-1.0) and a @ c == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose([a[1], c[1]], 0.0, atol=1e-12)


def test_positional_functions_are_respected(tmp_path):
    lat = _func(tmp_path / "len.func", [(0, 0.6), (1, 0.1)])
    order = _func(tmp_path / "order.func", [(0, 1.0), (0.5, 1.0), (0.55, 0.0), (1, 0.0)])
    angle = _func(tmp_path / "angle.func", [(0, 70.0), (1, 30.0)])
    size = _func(tmp_path / "size.func", [(0, 0.2), (1, 0.1)])
    p = _params(tmp_path, length=2.0, nodes=5, first_node=0.2, lateral_length=lat, order=order, density=4.0,
                angle=angle, pedicel_length=0.05, floret_size=size,
                development={"frames": 30, "window": 10, "start": "linear"})
    lay = grow_thyrse(p)
    f = p.functions
    for node, c in _main_laterals(lay, 5):
        x = lay.node_pos[node, 1] / 2.0
        # the lateral's chain: follow it to its terminal floret (the child along the same direction)
        d = lay.node_pos[c] - lay.node_pos[node]
        d /= np.linalg.norm(d)
        assert math.degrees(math.acos(d @ Y)) == pytest.approx(f["angle"](x), abs=1e-9)
        along = [k for k in range(len(lay.node_pos)) if lay.node_tip[k] and lay.floret_order[lay.node_floret[k]] >= 0
                 and np.allclose(np.cross(lay.node_pos[k] - lay.node_pos[node], d), 0, atol=1e-9)
                 and (lay.node_pos[k] - lay.node_pos[node]) @ d > 0]
        length = max((lay.node_pos[k] - lay.node_pos[node]) @ d for k in along)
        assert length == pytest.approx(2.0 * f["lateral_length"](x), rel=1e-9)
        # the lateral's order: order-1 laterals (low) carry laterals, order-0 ones (high) pedicels
        tip = lay.node_floret[[k for k in along if np.isclose((lay.node_pos[k] - lay.node_pos[node]) @ d, length)][0]]
        assert lay.floret_order[tip] == (1 if x <= 0.5 else 0)
        # density: round(L * 4) node pairs of pedicels along an order-0 lateral
        if x > 0.55:
            k_nodes = [k for k in range(len(lay.node_pos)) if lay.node_parent[k] >= 0 and not lay.node_tip[k]
                       and np.allclose(np.cross(lay.node_pos[k] - lay.node_pos[node], d), 0, atol=1e-9)
                       and (lay.node_pos[k] - lay.node_pos[node]) @ d > 1e-9]
            assert len(k_nodes) == round(length * 4.0)
    # sizes and development windows from the floret's height; the lower florets open first
    sc = thyrse_scene(lay, p)
    h = np.clip(lay.floret_pos[:, 1] / 2.0, 0, 1)
    np.testing.assert_allclose([q.scale[0] for q in sc.placements], f["floret_size"](h), rtol=1e-12)
    start = np.array([q.frame_start for q in sc.placements])
    end = np.array([q.frame_end for q in sc.placements])
    np.testing.assert_array_equal(end - start, 10)
    np.testing.assert_array_equal(start, np.rint(h * 19).astype(int))
    order = np.argsort(h)
    assert np.all(np.diff(start[order]) >= 0) and start.max() == 19 and end.max() == 29


def test_thyrse_reuses_branch_gen_meshes():
    p = _params(length=1.0, nodes=2, first_node=0.5, lateral_length=0.4, order=0.0, density=5.0, angle=60.0)
    res = thyrse(p)
    br = res.branches
    # branch-gen's pipe model: radii grow toward the base; a distal cap apex at every floret
    assert br.node_radius[1] > br.node_radius[res.layout.floret_node].max()
    mesh = br.branches_mesh
    for k in res.layout.floret_node:
        assert np.min(np.linalg.norm(mesh.vertices - res.layout.node_pos[k], axis=1)) < 1e-12
    assert len(br.chain_list) == len(mesh.groups)


def test_cli_writes_scene_and_branches(tmp_path, write):
    lat = _func(tmp_path / "lat.func", [(0, 0.4), (1, 0.1)])
    params = write("t.toml", f'[thyrse]\nnodes = 3\nlateral_length = "{lat}"\norder = 0\ndensity = 6\n'
                             'floret_size = 0.05\n[development]\nframes = 20\nwindow = 8\n[cylinder]\nsides = 5\n')
    out = tmp_path / "out"
    r = run_cli("thyrse", params, "-o", out, "-q")
    assert r.returncode == 0, r.stderr
    sc = read_scn(out / "scene.scn")
    assert len(sc) > 10 and all(q.kind == "ca" and q.frame_end - q.frame_start == 8 for q in sc.placements)
    assert all(q.emergence == q.frame_start and q.type == "floret" for q in sc.placements)
    for name in ("skeleton.obj", "skeleton.radii", "branches.obj"):
        assert (out / name).is_file()
    assert len(read_obj(out / "branches.obj").faces) > 0
    # the same parameters again (through the library): byte-identical files
    p = read_params(params)
    write_thyrse(tmp_path / "out2", thyrse(p), p)
    for name in ("scene.scn", "skeleton.obj", "branches.obj"):
        assert (out / name).read_bytes() == (tmp_path / "out2" / name).read_bytes()


@pytest.mark.parametrize("text, expect", [
    ("[thyrse]\nlenght = 1.0\n", "did you mean 'length'"),
    ("[development]\nframes = 10\nwindow = 12\n", ":3:"),
])
def test_cli_bad_input_one_line_exit_2_no_output(tmp_path, write, text, expect):
    params = write("bad.toml", text)
    out = tmp_path / "out"
    r = run_cli("thyrse", params, "-o", out)
    assert r.returncode == 2, r.stderr
    assert expect in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not out.exists()


def test_cli_refuses_a_floret_model_that_intersects_itself(tmp_path, write):
    """A --room model crossing itself (as a branch mesh given as the model) is refused at once,
    one line, exit 2: a floret may not intersect itself, and the room test of every placed copy
    paid for its crossings once per floret (minutes, then no floret)."""
    params = write("t.toml", "[thyrse]\nnodes = 3\norder = 0\ndensity = 6\nfloret_size = 0.05\n")
    model = write("crossing.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0.2 0.2 -0.5\nv 0.3 0.3 0.5\nv 0.9 0.9 0\n"
                                  "f 1 2 3\nf 4 5 6\n")
    out = tmp_path / "out"
    r = run_cli("thyrse", params, "-o", out, "--room", model)
    assert r.returncode == 2, r.stderr
    assert "does not intersect itself" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.parametrize("data, expect", [
    ({"thyrse": {"length": -1.0}}, "length"),
    ({"thyrse": {"order": "missing.func"}}, "missing.func"),
    ({"thyrse": {"outward": 1}}, "true or false"),
    ({"thyrse": {"angle": 200.0}}, "angle"),
    ({"pipe": {"tip_diameter": 0.0}}, "tip_diameter"),
])
def test_params_reject_bad_values(tmp_path, data, expect):
    with pytest.raises(FormatError, match=expect):
        params_from_toml(data, folder=tmp_path)


def test_params_reject_unknown_section():
    with pytest.raises(FormatError, match="known key or section"):
        params_from_toml({"rodkaew": {}})


def test_outward_children_and_branch_density():
    common = dict(length=1.0, nodes=3, first_node=0.3, lateral_length=0.5, order=1.0, density=12.0, angle=60.0,
                  sub_angle=70.0, pedicel_length=0.04)
    inward = grow_thyrse(_params(**common))
    out = grow_thyrse(_params(outward=True, **common))
    thin = grow_thyrse(_params(outward=True, branch_density=4.0, **common))

    def radial_steps(lay):
        """Each non-main edge's step along the horizontal direction away from the main axis."""
        on_axis = np.abs(lay.node_pos[:, [0, 2]]).max(axis=1) < 1e-12
        out = []
        for c, p in enumerate(lay.node_parent):
            if p < 0 or on_axis[p]:
                continue
            r = lay.node_pos[p].copy()
            r[1] = 0
            out.append((lay.node_pos[c] - lay.node_pos[p]) @ (r / np.linalg.norm(r)))
        return np.array(out)

    assert radial_steps(inward).min() < -0.5 * 0.04  # some children point back towards the axis ...
    steps = radial_steps(out)  # ... none with outward (at most sin 10 degrees of a step)
    assert steps.min() > -math.sin(math.radians(10.0)) * 0.3
    assert len(out.floret_node) < len(inward.floret_node)
    # laterals that carry laterals: round(L * branch_density) node pairs instead of round(L * density)
    assert len(thin.floret_node) < len(out.floret_node)
    branch_nodes = lambda lay: sum(1 for k in range(len(lay.node_pos))
                                   if not lay.node_tip[k] and (lay.node_parent == k).sum() >= 3)
    assert branch_nodes(thin) < branch_nodes(out)


def test_min_distance_keeps_limbs_apart():
    common = dict(length=1.0, nodes=4, first_node=0.3, lateral_length=0.45, order=1.0, density=20.0,
                  branch_density=10.0, angle=60.0, sub_angle=40.0, pedicel_length=0.03, floret_size=0.08,
                  tropism=1.0, outward=True)

    def limb_gap(lay):
        c = lay.floret_pos + 0.7 * 0.08 * lay.floret_up
        d = np.linalg.norm(c[:, None] - c[None], axis=2) + np.eye(len(c)) * 9
        return d.min() / 0.08

    dense = grow_thyrse(_params(**common))
    spaced = grow_thyrse(_params(min_distance=0.6, **common))
    assert limb_gap(dense) < 0.6 <= limb_gap(spaced)
    assert 0 < len(spaced.floret_node) < len(dense.floret_node)
    # a floret without room takes its pedicel with it: no leaf a pedicel's length from its node
    leaves = np.setdiff1d(np.arange(len(spaced.node_pos)), spaced.node_parent)
    bare = leaves[~spaced.node_tip[leaves]]
    step = np.linalg.norm(spaced.node_pos[bare] - spaced.node_pos[spaced.node_parent[bare]], axis=1)
    assert not np.any(np.isclose(step, 0.03))


# --- facing the surface, room, individual florets (formats/thyrse.md) ---

_DENSE = dict(length=1.0, nodes=8, first_node=0.3, lateral_length=0.2, order=0.0, density=20.0, angle=60.0,
              pedicel_length=0.03, floret_size=0.12, outward=True, min_distance=0.45)


def _hull_angles(lay):
    """Degrees between each floret's axis and the outward normal of the nearest facet of the
    convex hull of the florets' positions."""
    from scipy.spatial import ConvexHull

    hull = ConvexHull(lay.floret_pos)
    n, c = hull.equations[:, :3], hull.equations[:, 3]
    k = np.argmin(-(lay.floret_pos @ n.T + c), axis=1)
    return np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", lay.floret_up, n[k]), -1, 1)))


def test_facing_the_surface_turns_florets_out_and_bends_their_pedicels():
    stalk = grow_thyrse(_params(tropism=0.3, **_DENSE))
    surface = grow_thyrse(_params(tropism=0.3, facing="surface", surface_weight=2.5, **_DENSE))
    a_stalk, a_surface = np.median(_hull_angles(stalk)), np.median(_hull_angles(surface))
    assert a_surface < 40.0 and a_surface < a_stalk - 8.0, (a_surface, a_stalk)
    np.testing.assert_allclose(np.linalg.norm(surface.floret_up, axis=1), 1.0)
    np.testing.assert_allclose(np.einsum("ij,ij->i", surface.floret_up, surface.floret_right), 0.0, atol=1e-12)
    # the last piece of every pedicel runs along its floret's axis (the tube continues it), and no
    # floret faces back along its stalk
    par = surface.node_parent[surface.floret_node]
    step = surface.floret_pos - surface.node_pos[par]
    step /= np.linalg.norm(step, axis=1)[:, None]
    np.testing.assert_allclose(np.einsum("ij,ij->i", step, surface.floret_up), 1.0, atol=1e-9)


def test_variation_is_seeded_bounded_and_moves_with_nothing_else():
    p = _params(size_variation=0.1, seed=3, development={"frames": 30, "window": 10, "start_variation": 2}, **_DENSE)
    a, b = thyrse_scene(grow_thyrse(p), p), thyrse_scene(grow_thyrse(p), p)
    size = np.array([q.scale[0] for q in a.placements])
    assert np.array_equal([q.scale for q in a.placements], [q.scale for q in b.placements])
    assert np.all(np.abs(size / 0.12 - 1.0) <= 0.1 + 1e-12) and size.std() / size.mean() > 0.03
    plain = _params(development={"frames": 30, "window": 10}, **_DENSE)
    base = thyrse_scene(grow_thyrse(plain), plain)
    shift = np.array([q.frame_start for q in a.placements]) - np.array([q.frame_start for q in base.placements])
    assert np.abs(shift).max() <= 2 and np.any(shift != 0)
    other = _params(size_variation=0.1, seed=4, **_DENSE)
    assert not np.array_equal([q.scale for q in thyrse_scene(grow_thyrse(other), other).placements],
                              [q.scale for q in a.placements])
    # no variation: every floret its positional size exactly
    assert {q.scale[0] for q in base.placements} == {0.12}


def test_span_lets_the_last_windows_end_after_the_run():
    p = _params(development={"frames": 20, "window": 8, "span": 19}, **_DENSE)
    sc = thyrse_scene(grow_thyrse(p), p)
    start = np.array([q.frame_start for q in sc.placements])
    assert start.max() == 19 and max(q.frame_end for q in sc.placements) == 27
    with pytest.raises(FormatError, match="span"):
        params_from_toml({"development": {"frames": 20, "window": 8, "span": 20}})


def _box(half):
    """A box of half size ``half`` from y = 0 up, open at its foot (a stand-in floret model)."""
    import trimesh

    m = trimesh.creation.box(extents=[2 * half, 2 * half, 2 * half])
    v = m.vertices + [0.0, half, 0.0]
    f = m.faces[~np.all(np.isclose(v[m.faces][:, :, 1], 0.0), axis=1)]  # open at its foot, as a tube
    return v, f


def test_room_drops_florets_that_would_meet_branches_or_each_other():
    from inflo.tools.collide import intersecting_pairs_between
    from inflo.tools.thyrse.generate import room_conflicts

    p = _params(tropism=0.3, facing="surface", surface_weight=2.5, **_DENSE)
    bud, big = _box(0.1), _box(0.3)
    free = thyrse(p)
    roomy = thyrse(p, [bud, big])
    assert 0 < len(roomy.scene) < len(free.scene)
    # what is left: no floret's model meets the (remade) branches, no two first models meet
    assert not room_conflicts(roomy.scene, [bud, big], roomy.branches.branches_mesh).any()
    # the layout stays a tree of tips: every floret on a leaf, every leaf a floret or a bare axis tip
    lay = roomy.layout
    assert not np.isin(lay.floret_node, lay.node_parent).any()
    assert np.all(lay.node_parent[1:] < np.arange(1, len(lay.node_parent)))
    # the check itself: every floret whose big model, placed alone, meets a branch is flagged
    mats = [q.matrix() for q in free.scene.placements]
    v, f = big
    hit = np.array([len(intersecting_pairs_between(v @ m[:3, :3].T + m[:3, 3], f.astype(np.int32),
                                                   free.branches.branches_mesh.vertices,
                                                   free.branches.branches_mesh.faces)) > 0 for m in mats])
    flagged = room_conflicts(free.scene, [big], free.branches.branches_mesh)
    assert hit.any() and np.all(flagged[hit])


@pytest.mark.parametrize("data, expect", [
    ({"thyrse": {"facing": "sky"}}, "'stalk', 'surface'"),
    ({"thyrse": {"size_variation": 0.9}}, "size_variation"),
    ({"thyrse": {"seed": -1}}, "seed"),
    ({"development": {"start_variation": -1}}, "start_variation"),
])
def test_new_keys_reject_bad_values(data, expect):
    with pytest.raises(FormatError, match=expect):
        params_from_toml(data)


def test_obstacle_tubes_hold_the_branches_and_keep_clear_of_each_other(tmp_path):
    from inflo.tools.collide import intersecting_pairs
    from inflo.tools.thyrse.obstacle import _tubes

    data = {"thyrse": dict(_DENSE, tropism=0.3, facing="surface", surface_weight=2.5),
            "obstacle": {"id": 1, "gap": 0.003, "margin": 0.0003}}
    p = params_from_toml(data)
    res = thyrse(p)
    ob = res.obstacle
    assert ob is not None and len(ob.groups) > 0.9 * len(res.branches.chain_list)
    # the last placement places it: o:, id 1, at the origin, typed obstacle; the florets as before
    last = res.scene.placements[-1]
    assert last.kind == "o" and last.id == 1 and last.type == "obstacle" and np.allclose(last.pos, 0.0)
    plain = thyrse(params_from_toml({"thyrse": data["thyrse"]}))
    assert plain.obstacle is None and len(plain.scene.placements) == len(res.scene.placements) - 1
    # no two tubes meet (nor any tube itself, beyond its neighbouring triangles): one part for fccompose
    tube = ob.face_group
    assert len(intersecting_pairs(ob.vertices, ob.faces)) == 0
    # and each keeps the gap from the others: its vertices at least gap/2 from any other tube's
    from scipy.spatial import cKDTree

    owner = np.full(len(ob.vertices), -1)
    owner[ob.faces.reshape(-1)] = np.repeat(tube, 3)
    d, k = cKDTree(ob.vertices).query(ob.vertices, k=8)
    other = owner[k] != owner[:, None]
    assert d[other].min() >= 0.5 * 0.003
    # a tube is a closed ring of the given radius about its polyline
    v, f, which = _tubes([np.array([[0, 0, 0], [0, 1, 0.0]])], [np.full(2, 0.01)], 6)
    ring = v[np.abs(np.hypot(v[:, 0], v[:, 2])) > 1e-9]
    assert np.allclose(np.hypot(ring[:, 0], ring[:, 2]), 0.01) and len(np.unique(which)) == 1
    # the files
    write_thyrse(tmp_path, res, p)
    assert (tmp_path / "obstacle" / "frame_0000.obj").is_file()
    assert read_scn(tmp_path / "scene.scn").placements[-1].type == "obstacle"


def test_obstacle_params_are_checked():
    with pytest.raises(FormatError, match="gap"):
        params_from_toml({"obstacle": {"id": 1, "gap": 0.0}})
    with pytest.raises(FormatError, match="other than the florets"):
        params_from_toml({"obstacle": {"id": 0}})


def test_room_refuses_models_too_big_to_place_at_once(monkeypatch):
    from inflo.formats.errors import InputError
    from inflo.tools.thyrse import generate

    monkeypatch.setattr(generate, "ROOM_MAX_TRIANGLES", 100)
    with pytest.raises(InputError, match="at most 100 placed model triangles"):
        thyrse(_params(**_DENSE), [_box(0.1)])
