"""The Eustoma pipeline (pipelines/eustoma; Ijiri et al. 2008, sec. 6.2, figs. 12b, 16, 17).

- the committed cultivar parameter files are what ``make_keys.py --params`` writes;
- the final bud petal has the paper's resolution (458 triangles, 261 particles, 718 edges, within
  2 %) and average edge length (2.0, table 1);
- the bud is intersection-free and contorted: each petal's right side lies beneath its neighbour
  (rays from a petal's right half outwards hit the next petal; none from the next petal hits it);
- the three cultivars differ in their growth maps only (same bud, placement, joint schedule);
- the calyx and column (``make_column.py``, committed key poses): receptacle, five narrow sepals
  standing on it, a pistil with a two-lobed stigma on the style's tip, five stamens alternating
  with the petals, each anther on its filament's tip; at least three organ materials in every
  keyframe; the check (if built) finds no petal touching any of them in any keyframe;
- (if built) the background inside the open corolla's outline from above and from the side stays
  under the figures the broad petals reached, and no view (38 of them, every fifth keyframe)
  sees more than 0.0025 of the flower's silhouette through it (slits between the petals, the
  bud's tip);
- if the draft has been built (``make eustoma`` or the golden test): every keyframe passed the
  exact check, the joint angle reached 15 degrees, and the open shapes differ as the cultivars'
  groups do: bell and funnel flare out at the rim, the funnel widest and flattest, the shallow
  ball curls in (rim narrower than its middle).
"""
from __future__ import annotations

import re
import subprocess
import sys
import tomllib

import numpy as np
import pytest
from conftest import REPO, run_cli

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.tools.collide import intersecting_pairs
from inflo.tools.pbd import mesh_edges
from inflo.tools.petal_grow.bud import read_bud_obj
from inflo.tools.petal_grow.params import parse_params
from inflo.tools.petal_grow.simulate import _rays_hit, arrangement_violations, build_model

EUSTOMA = REPO / "pipelines" / "eustoma"
BUILD = REPO / "build" / "eustoma"
CULTIVARS = ("mellow_yellow", "maite_lady", "pinocchio")


def _make_keys(*args):
    subprocess.run([sys.executable, str(EUSTOMA / "make_keys.py"), *map(str, args)], check=True, cwd=EUSTOMA)


def test_parameter_files_are_what_make_keys_writes(tmp_path):
    _make_keys("--params", "--mesh", "../../build/eustoma/bud/petal.obj", "-o", tmp_path)
    for c in CULTIVARS:
        assert (tmp_path / f"{c}.toml").read_text() == (EUSTOMA / f"{c}.toml").read_text(), c


def test_final_petal_has_the_papers_resolution(tmp_path):
    _make_keys("--quality", "final", "-o", tmp_path)
    bud = read_bud_obj(tmp_path / "petal.obj")
    edges = mesh_edges(bud.faces)
    for got, paper in ((len(bud.faces), 458), (len(bud.vertices), 261), (len(edges), 718)):
        assert abs(got - paper) <= 0.02 * paper, (got, paper)
    mean_edge = np.linalg.norm(bud.vertices[edges[:, 0]] - bud.vertices[edges[:, 1]], axis=1).mean()
    assert mean_edge == pytest.approx(2.0, rel=0.15)


@pytest.fixture(scope="module")
def bud_model(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("eustoma")
    _make_keys("--quality", "draft", "-o", tmp)
    text = (EUSTOMA / "pinocchio.toml").read_text().replace("../../build/eustoma/bud/petal.obj", "petal.obj")
    return build_model(parse_params(text, tmp / "pinocchio.toml"))


def test_bud_is_closed_contorted_and_intersection_free(bud_model):
    m = bud_model
    x = m.vertex_x
    assert len(intersecting_pairs(x, m.tri_indices)) == 0
    assert arrangement_violations(m, x) == []
    organs = m.organs
    for k, o in enumerate(organs):
        nxt = organs[(k + 1) % 5]
        assert o.beneath == nxt.name
        tri_next = np.ascontiguousarray(m.tri_indices[nxt.t0:nxt.t1])
        tri_self = np.ascontiguousarray(m.tri_indices[o.t0:o.t1])
        for half, want in ((m.vertex_uv[o.v0:o.v1, 0] > 0.6, True), (m.vertex_uv[o.v0:o.v1, 0] < 0.4, False)):
            p = np.ascontiguousarray(x[o.v0:o.v1][half & (m.vertex_uv[o.v0:o.v1, 1] > 0.3)])
            d = p.copy()
            d[:, 1] = 0
            d = np.ascontiguousarray(d / np.linalg.norm(d, axis=1)[:, None])
            # the right half lies under the next petal; the left half does not
            assert (_rays_hit(p, d, x, tri_next) > 0) == want, (o.name, want)
        # and nothing of the next petal lies under this one
        q = np.ascontiguousarray(x[nxt.v0:nxt.v1])
        dq = q.copy()
        dq[:, 1] = 0
        dq = np.ascontiguousarray(dq / np.maximum(np.linalg.norm(dq, axis=1), 1e-12)[:, None])
        assert _rays_hit(q, dq, x, tri_self) == 0


def test_cultivars_differ_in_growth_maps_only():
    data = {c: tomllib.loads((EUSTOMA / f"{c}.toml").read_text()) for c in CULTIVARS}
    ref = data[CULTIVARS[0]]
    for c in CULTIVARS[1:]:
        assert data[c]["flower"] == ref["flower"]
        # the same petals, but for their material: the cultivar's name (its colour)
        assert [o["material"] for o in data[c]["organ"]] == [c] * 5
        assert [{**o, "material": ""} for o in data[c]["organ"]] == [{**o, "material": ""} for o in ref["organ"]]
        assert data[c]["growth"] != ref["growth"]
    assert ref["flower"]["joint"] == [[1, 0.0], [50, 15.0]]
    # the funnel cultivar has another venation (direction map)
    assert data["maite_lady"]["growth"]["early"]["direction"] != ref["growth"]["early"]["direction"]


COLUMN_KEYS = [EUSTOMA / f"column_{n:03d}.floret" for n in (1, 21, 41, 61, 81, 100)]


def test_column_files_are_what_make_column_writes(tmp_path):
    subprocess.run([sys.executable, str(EUSTOMA / "make_column.py"), str(tmp_path)], check=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in COLUMN_KEYS)
    for p in COLUMN_KEYS:
        assert (tmp_path / p.name).read_text() == p.read_text(), f"{p.name}: rerun make_column.py"


@pytest.fixture(scope="module")
def column_obj(tmp_path_factory):
    out = tmp_path_factory.mktemp("eustoma_column")
    r = run_cli("floret-animate", "-q", *COLUMN_KEYS, "--frames", "100", "-o", out / "frames")
    assert r.returncode == 0, r.stderr
    r = run_cli("polygonize", "-q", out / "frames", "-o", out / "obj")
    assert r.returncode == 0, r.stderr
    paths = list_obj_sequence(out / "obj")
    assert len(paths) == 100
    return paths


def _part(mesh, name):
    g = mesh.groups.index(name)
    return mesh.vertices[np.unique(mesh.faces[np.asarray(mesh.face_group) == g])]


def test_calyx_pistil_and_stamens_present_and_attached(column_obj):
    for n in (1, 30, 50, 70, 100):
        mesh = read_obj(column_obj[n - 1])
        want = (["receptacle_0", "pistil_0"] + [f"sepals_{k}" for k in range(5)] + ["stigma_0", "stigma_1"]
                + [f"stamens_{k}" for k in range(5)] + [f"anthers_{k}" for k in range(5)])
        assert sorted(mesh.groups) == sorted(want), n
        assert len({mesh.materials[k] for k in np.unique(mesh.face_material)}) >= 3
        rec = _part(mesh, "receptacle_0")
        rec_r = np.hypot(rec[:, 0], rec[:, 2]).max()
        for k in range(5):
            sep = _part(mesh, f"sepals_{k}")
            base = sep[np.argmin(sep[:, 1])]
            # standing on the receptacle: the base inside it, below the petals (y < 0)
            assert np.hypot(base[0], base[2]) < rec_r and base[1] < 0.0, (n, k)
            # narrow: far longer than wide
            ext = np.ptp(sep, axis=0)
            assert np.linalg.norm(ext) > 5.0 * 2 * 0.9, (n, k)
            # alternating with the petals (petal k at 72 k degrees): sepals at 36 + 72 k
            az = np.degrees(np.arctan2(-sep[:, 2].mean(), sep[:, 0].mean())) % 72.0
            assert abs(az - 36.0) < 3.0, (n, k, az)
            fil = _part(mesh, f"stamens_{k}")
            anth = _part(mesh, f"anthers_{k}")
            tip = fil[np.argmax(fil[:, 1])]
            c = anth.mean(axis=0)
            ax = np.linalg.svd(anth - c)[2][0]
            off = tip - c
            # the filament's tip inside the anther (within its half-width of the anther's axis)
            assert np.linalg.norm(off - np.dot(off, ax) * ax) < 0.5, (n, k)
            assert abs(np.dot(off, ax)) < 0.5 * np.ptp((anth - c) @ ax), (n, k)
        style = _part(mesh, "pistil_0")
        top = style[:, 1].max()
        lobes = [_part(mesh, f"stigma_{k}") for k in range(2)]
        for lobe in lobes:
            low = lobe[np.argmin(lobe[:, 1])]  # its inner pole, sunk in the style's tip
            assert np.hypot(low[0], low[2]) < 0.6 and top - 0.6 < low[1] < top, n
        # two lobes spreading to opposite sides
        d0, d1 = (lb[:, [0, 2]].mean(axis=0) for lb in lobes)
        assert np.dot(d0, d1) < 0, n


def test_draft_build_checks_and_cultivar_shapes_if_built(species_build):
    species_build("eustoma")  # the draft build, made here if no test made it yet
    check = BUILD / "check.txt"
    if not check.is_file() or (BUILD / "quality.txt").read_text().strip() != "draft":
        pytest.skip("no draft eustoma build (INFLO_GOLDEN_NO_BUILD: build/eustoma is left as it is)")
    text = check.read_text()
    assert text.strip().endswith("OK: every keyframe intersection-free"), text
    shape = {}
    for c in CULTIVARS:
        block = text.split(f"{c}:", 1)[1]
        assert re.search(r"intersecting pairs: 0 \(max per frame 0\)", block.splitlines()[0])
        assert "petals against the calyx and column: 0 intersecting pairs in 100 keyframes" in block
        assert int(re.search(r"organ materials per keyframe \(petals included\): at least (\d+)", block)[1]) >= 3
        # the joint angle, a rigid fit of the base rows: the claws, overlapping round the base,
        # press on each other and bend those rows a little (the funnel's draft: 15.8)
        assert abs(float(re.search(r"frame 100 ([\d.]+)", block)[1]) - 15.0) < 1.0
        m = re.search(r"open: rim radius ([\d.]+), widest ([\d.]+), height ([\d.]+), radius at half height "
                      r"([\d.]+), flare ([\d.]+)", block)
        shape[c] = dict(zip(("rim", "widest", "height", "mid", "flare"), map(float, m.groups())))
        m = re.search(r"background inside the outline \(lobe notches included\): (\d+) points from above, (\d+) "
                      r"from the side", block)
        shape[c]["slits"] = (int(m[1]), int(m[2]))
        # seen *through* the corolla (with its receptacle and pistil) from any of 38 views, at
        # every fifth keyframe: before the receptacle reached under the petals' feet a ring showed
        # down the throat (bell 0.0038 of the silhouette from above at frame 50) and through the
        # bud's open tip (0.014 at frame 5, radius 2.7; now 3.3), and the ball's broad lobes parted
        # (0.0050 at frame 100, 0.0053 at frame 95 at final quality; late width 1.3, now 1.25)
        through = re.search(r"seen through the corolla \(enclosed background, worst of 38 views, every fifth "
                            r"keyframe: (\d+)\): (.*)", block)
        assert through, block
        assert int(through[1]) == 20, through[1]
        shares = [float(v) for v in re.findall(r"frame \d+ ([\d.]+) at", through[2])]
        assert shares and max(shares) <= 0.0025, (c, through[2])
    bell, funnel, ball = shape["mellow_yellow"], shape["maite_lady"], shape["pinocchio"]
    # background inside the outline (check_eustoma.py; the notches between the lobes' tips count):
    # with narrow petals and claws the draft showed 320 / 670 (bell), 494 / 1,016 (funnel), 229 /
    # 857 (ball) points from above / from the side; now 15 / 202, 202 / 558, 12 / 546: bounds
    # against a relapse to straps
    assert bell["slits"][0] <= 40 and bell["slits"][1] <= 300, bell["slits"]
    assert funnel["slits"][0] <= 300 and funnel["slits"][1] <= 700, funnel["slits"]
    assert ball["slits"][0] <= 40 and ball["slits"][1] <= 650, ball["slits"]
    assert bell["flare"] > 1.2 and funnel["flare"] > 1.2      # both open out at the rim
    assert ball["flare"] < 1.0                                 # the shallow ball curls in
    assert funnel["rim"] > 1.25 * max(bell["rim"], ball["rim"])  # the funnel opens widest
    assert ball["height"] > 1.2 * funnel["height"]             # and the ball stays tallest
