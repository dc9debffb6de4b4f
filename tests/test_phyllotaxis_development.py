"""phyllotaxis developmental windows (the phase effect): ``[dynamics]``/``[hierarchy]``
``development_frames``, ``[primordia] development_order/_offset/_frames``, rba placements at scale 1."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import run_cli

from inflo.formats.rba import read_rba_sequence
from inflo.formats.scn import Group, Placement, Scene, read_scn
from inflo.tools.phyllotaxis.development import apply_development_order, development_ranks

DYNAMIC = ("[dynamics]\nmode = 'centripetal'\nframes = 12\ninterval = 0.5\nprimordium_area = 0.02\n"
           "inner_area = 0.3\nprimordium_growth = 0.02\n")
STATIC = "[primordia]\ncount = 40\narea = 0.02\nframe_start = 3\nframe_end = 23\n"


def _phyllotaxis(tmp_path, write, text, name="p"):
    out = tmp_path / name
    res = run_cli("phyllotaxis", write(f"{name}.toml", text), "-o", out, "--quiet")
    assert res.returncode == 0, res.stderr
    return read_scn(out / "scene.scn"), out


def _distance(scene):
    return np.array([np.linalg.norm(p.pos - scene.groups[p.group].centre) for p in scene.placements])


# ---------------------------------------------------------------- dynamic: development by age

def test_dynamic_development_frames_gives_each_floret_its_own_window(tmp_path, write):
    scene, out = _phyllotaxis(tmp_path, write, DYNAMIC + "development_frames = 5\n")
    starts = np.array([p.frame_start for p in scene.placements])
    ends = np.array([p.frame_end for p in scene.placements])
    assert len(scene) > 8 and all(p.kind == "rba" for p in scene.placements)
    assert np.all(ends - starts == 5)
    assert len(set(starts.tolist())) > 5 and np.all(np.diff(starts) >= 0)  # staggered, in order of formation
    assert ends.max() > 11  # late florets are not open at the last frame: not clamped
    em = np.array([p.emergence for p in scene.placements])
    assert np.array_equal(starts, np.ceil(em - 1e-9).astype(int))
    # sizes are in the RBA rows; the SCN scale is a factor (1)
    assert all(np.array_equal(p.scale, [1.0, 1.0, 1.0]) for p in scene.placements)
    _, frames = read_rba_sequence(out / "rba", scene)
    assert frames[-1].scale[0, 0] > frames[-1].scale[-1, 0] > 0


def test_dynamic_without_development_frames_ends_every_window_at_the_last_frame(tmp_path, write):
    scene, _ = _phyllotaxis(tmp_path, write, DYNAMIC)
    assert all(p.frame_end == 11 for p in scene.placements)
    assert len({p.frame_start for p in scene.placements}) > 5
    assert all(np.array_equal(p.scale, [1.0, 1.0, 1.0]) for p in scene.placements)


def test_dynamic_hierarchy_takes_development_frames_and_writes_scale_one(tmp_path, write):
    text = ("[hierarchy]\nlevels = 1\nframes = 20\ngrowth_rate = 0.15\ninitial_area = 1.0\n"
            "element_area = 0.2\nproduction_threshold = 1.2\ndynamic = true\n")
    plain, _ = _phyllotaxis(tmp_path, write, text, "plain")
    assert len(plain) > 3 and all(p.frame_end == 20 for p in plain.placements)
    dev, _ = _phyllotaxis(tmp_path, write, text + "development_frames = 7\n", "dev")
    assert all(p.kind == "rba" and p.frame_end - p.frame_start == 7 for p in dev.placements)
    assert [p.frame_start for p in dev.placements] == [p.frame_start for p in plain.placements]
    assert all(np.array_equal(p.scale, [1.0, 1.0, 1.0]) for p in dev.placements)


# ---------------------------------------------------------------- static: development by position

@pytest.mark.parametrize("order", ["centripetal", "centrifugal"])
def test_static_development_order_staggers_windows_by_distance(tmp_path, write, order):
    scene, _ = _phyllotaxis(tmp_path, write, STATIC + f"development_order = '{order}'\ndevelopment_offset = 0.5\n")
    d = _distance(scene)
    starts = np.array([p.frame_start for p in scene.placements])
    assert all(p.kind == "ca" and p.frame_end - p.frame_start == 20 for p in scene.placements)  # frame_end - frame_start
    by_distance = starts[np.argsort(d, kind="stable")]
    if order == "centripetal":  # outer florets develop first (sunflower, thesis ch. 9)
        assert np.all(np.diff(by_distance) <= 0)
        assert starts[np.argmax(d)] == 3 and starts[np.argmin(d)] == 3 + round(0.5 * 39 + 1e-9)
    else:
        assert np.all(np.diff(by_distance) >= 0)
        assert starts[np.argmin(d)] == 3 and starts[np.argmax(d)] == 23
    assert len(set(starts.tolist())) >= 19


def test_static_development_frames_and_none_order(tmp_path, write):
    scene, _ = _phyllotaxis(tmp_path, write, STATIC + "development_order = 'centripetal'\ndevelopment_offset = 2\n"
                                                      "development_frames = 6\n", "dev")
    assert all(p.frame_end - p.frame_start == 6 for p in scene.placements)
    assert sorted(p.frame_start for p in scene.placements) == [3 + 2 * r for r in range(40)]
    plain, _ = _phyllotaxis(tmp_path, write, STATIC, "plain")  # default: today's o: placements
    assert all(p.kind == "o" for p in plain.placements)
    ca, _ = _phyllotaxis(tmp_path, write, STATIC + "placement = 'ca'\n", "ca")
    assert all(p.kind == "ca" and (p.frame_start, p.frame_end) == (3, 23) for p in ca.placements)


def test_compound_heads_are_ranked_per_head(tmp_path, write):
    text = ("[surface]\ncurve = 'sphere_cap'\nradius = 4.0\nangle = 30\n[primordia]\narea = 1.5\ncount = 4\n"
            "development_order = 'centripetal'\n[compound]\nhead_curve = 'disk'\nfloret_fraction = 0.05\n")
    scene, _ = _phyllotaxis(tmp_path, write, text)
    for g in {p.group for p in scene.placements}:
        members = [p for p in scene.placements if p.group == g]
        starts = sorted(p.frame_start for p in members)
        assert starts == list(range(len(members)))  # offset 1 frame per rank (the default), per head


def test_development_ranks_break_ties_by_placement_index():
    pos = np.array([[1.0, 0, 0], [0, 0, 1.0], [0.5, 0, 0], [-1.0, 0, 0]])
    centres = np.zeros((4, 3))
    assert development_ranks(pos, centres, np.zeros(4), "centripetal").tolist() == [0, 1, 3, 2]
    assert development_ranks(pos, centres, np.zeros(4), "centrifugal").tolist() == [1, 2, 0, 3]
    sc = Scene()
    sc.groups[0] = Group(0, np.zeros(3), -1)
    for p in pos:
        sc.placements.append(Placement("o", 0, p, [1.0] * 3, [0, 1, 0], [1, 0, 0], group=0))
    apply_development_order(sc, order="centripetal", offset=1.5, frame_start=10, frames=4)
    assert [(p.kind, p.frame_start, p.frame_end) for p in sc.placements] == [
        ("ca", 10, 14), ("ca", 12, 16), ("ca", 15, 19), ("ca", 13, 17)]  # round(10 + 1.5 r), halves up


@pytest.mark.parametrize("text,needle", [
    (DYNAMIC + "development_frames = 0\n", "dynamics.development_frames > 0"),
    (DYNAMIC + "development_frames = 2.5\n", "dynamics.development_frames as an integer"),
    (DYNAMIC + "developement_frames = 3\n", "did you mean 'development_frames'"),
    (STATIC + "development_order = 'centripetl'\n", "did you mean 'centripetal'"),
    (STATIC + "development_offset = -1\n", "development_offset >= 0"),
    (STATIC + "development_frames = -4\n", "primordia.development_frames > 0"),
    ("[hierarchy]\ndevelopment_frames = 3\n", "only with dynamic = true"),
])
def test_bad_development_keys_exit_2_with_one_line(tmp_path, write, text, needle):
    res = run_cli("phyllotaxis", write("b.toml", text), "-o", tmp_path / "o")
    assert res.returncode == 2 and needle in res.stderr, res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and "b.toml:" in res.stderr
    assert not (tmp_path / "o").exists()


def test_static_keys_in_a_dynamic_file_are_ignored_with_a_warning(tmp_path, write):
    res = run_cli("phyllotaxis", write("w.toml", "[primordia]\ndevelopment_order = 'centripetal'\n" + DYNAMIC),
                  "-o", tmp_path / "o", "--quiet")
    assert res.returncode == 0 and "warning" in res.stderr and "development_frames" in res.stderr
