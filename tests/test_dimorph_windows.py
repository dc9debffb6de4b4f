"""dimorph per-type developmental windows: ``--ray-lead``, ``--ray/--disk-development-frames``,
and rba placements whose SCN scale after dimorph is exactly the ray/disk factor."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import no_partial_files, run_cli

from inflo.formats.scn import Placement, Scene, read_scn, write_scn
from inflo.tools.dimorph.dimorph import DimorphOptions, dimorph_scene
from inflo.tools.dimorph.sweep import simple_head

DYNAMIC = ("[dynamics]\nmode = 'centripetal'\nframes = 12\ninterval = 0.5\nprimordium_area = 0.02\n"
           "inner_area = 0.3\nprimordium_growth = 0.02\n")


# ---------------------------------------------------------------- dimorph: per-type windows and sizes

def _head(kind="ca", n=82):
    scene = Scene()
    for k, p in enumerate(simple_head(n)):
        kw = {"frame_start": 10 + k % 3, "frame_end": 40} if kind != "o" else {}
        scene.placements.append(Placement(kind, 0, p, [1.0] * 3, [0, 1, 0], [1, 0, 0], **kw))
    return scene


def test_dimorph_ray_lead_moves_only_ray_windows():
    scene = _head()
    out, counts = dimorph_scene(scene, DimorphOptions(75.0, ray_lead=4.5, ray_scale=1.6))
    assert counts["ray"] > 0 and counts["disk"] > 0
    for a, b in zip(scene.placements, out.placements):
        if b.type == "ray":
            assert (b.frame_start, b.frame_end) == (int(np.floor(a.frame_start - 4.5 + 0.5)), 36)
            assert b.scale[0] == pytest.approx(1.6)
        else:
            assert (b.frame_start, b.frame_end) == (a.frame_start, a.frame_end) and b.scale[0] == 1.0
    # clamped: frame_start >= 0, frame_end >= frame_start + 1
    out, _ = dimorph_scene(scene, DimorphOptions(75.0, ray_lead=60))
    assert all((p.frame_start, p.frame_end) == (0, 1) for p in out.placements if p.type == "ray")


def test_dimorph_bract_development_frames_set_only_the_bracts_windows():
    """The involucre opens with the head: --bract-development-frames N gives the bracts (the
    outermost primordia) frameEnd = frameStart + N, no lead; the florets' windows are unchanged."""
    scene = _head()
    plain, _ = dimorph_scene(scene, DimorphOptions(75.0, bracts=8))
    out, counts = dimorph_scene(scene, DimorphOptions(75.0, bracts=8, bract_development_frames=50))
    assert counts["bract"] == 8 and counts["windows"] == 8
    for a, b, c in zip(scene.placements, out.placements, plain.placements):
        if b.type == "bract":
            assert (b.frame_start, b.frame_end) == (a.frame_start, a.frame_start + 50)
            assert (c.frame_start, c.frame_end) == (a.frame_start, a.frame_end)  # as they were without it
        else:
            assert (b.frame_start, b.frame_end) == (a.frame_start, a.frame_end)


def test_dimorph_development_frames_per_type_then_lead():
    scene = _head()
    out, counts = dimorph_scene(scene, DimorphOptions(75.0, ray_development_frames=8, disk_development_frames=20,
                                                      ray_lead=2))
    assert counts["windows"] == len(scene)
    for a, b in zip(scene.placements, out.placements):
        if b.type == "ray":
            assert (b.frame_start, b.frame_end) == (a.frame_start - 2, a.frame_start + 6)
        else:
            assert (b.frame_start, b.frame_end) == (a.frame_start, a.frame_start + 20)
    # o: placements have no window: untouched
    o, counts = dimorph_scene(_head("o"), DimorphOptions(75.0, ray_lead=3, ray_development_frames=5))
    assert counts["windows"] == 0 and all(p.frame_start is None for p in o.placements)


def test_dimorph_cli_on_a_dynamic_head_sets_rba_scale_to_the_factor_and_ray_windows(tmp_path, write):
    out = tmp_path / "p"
    res = run_cli("phyllotaxis", write("p.toml", DYNAMIC + "development_frames = 5\n"), "-o", out, "--quiet")
    assert res.returncode == 0, res.stderr
    scene = read_scn(out / "scene.scn")
    res = run_cli("dimorph", out / "scene.scn", "--alpha", 75, "--ray-scale", 1.6, "--disk-scale", 0.9,
                  "--ray-lead", 2, "--ray-development-frames", 6, "-o", tmp_path / "typed.scn")
    assert res.returncode == 0, res.stderr
    typed = read_scn(tmp_path / "typed.scn")
    kinds = {p.type for p in typed.placements}
    assert {"ray", "disk"} <= kinds
    for a, b in zip(scene.placements, typed.placements):
        assert b.kind == "rba"
        if b.type == "ray":
            assert np.allclose(b.scale, 1.6)  # after dimorph the SCN scale is exactly the factor
            assert (b.frame_start, b.frame_end) == (max(a.frame_start - 2, 0), max(a.frame_start + 4, max(a.frame_start - 2, 0) + 1))
        else:
            assert np.allclose(b.scale, 0.9) and (b.frame_start, b.frame_end) == (a.frame_start, a.frame_end)
            assert b.emergence == a.emergence


@pytest.mark.parametrize("args,needle", [
    (["--ray-development-frames", 0], "--ray-development-frames must be an integer > 0"),
    (["--disk-development-frames", -3], "--disk-development-frames must be an integer > 0"),
    (["--ray-lead", "nan"], "'--ray-lead': expected a finite number"),
    (["--bract-development-frames", 0], "--bract-development-frames must be an integer > 0"),
])
def test_dimorph_bad_window_flags_exit_2(tmp_path, args, needle):
    write_scn(tmp_path / "in.scn", _head())
    res = run_cli("dimorph", tmp_path / "in.scn", "--alpha", 75, *args, "-o", tmp_path / "out.scn")
    assert res.returncode == 2 and needle in res.stderr, res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out.scn").exists() and no_partial_files(tmp_path)
