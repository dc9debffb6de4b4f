"""A rerun into a folder with an older, longer run: the older run's frames go before the
new run writes any, so a rerun interrupted half way leaves a shorter sequence of its own frames,
never new frames 0..k beside old ones after k (which canopy-render and subdivide would read as one
run). floret-animate, polygonize and fccompose (without --resume; tests/test_fccompose.py keeps the
stale-frame test of a longer earlier run)."""
from __future__ import annotations

import pytest
from conftest import REPO, run_cli

from inflo.formats.floret import read_floret
from inflo.tools.floret_animate.run import write_frames

KEYS = [REPO / "pipelines" / "examples" / "disk_bud.floret", REPO / "pipelines" / "examples" / "disk_open.floret"]


def _old_run(folder, suffix, n=10):
    folder.mkdir(parents=True, exist_ok=True)
    for i in range(n):
        (folder / f"frame_{i:04d}{suffix}").write_text("old run\n")


def test_floret_animate_interrupted_rerun_leaves_no_older_frames(tmp_path):
    out = tmp_path / "frames"
    _old_run(out, ".floret")
    fr = read_floret(KEYS[0])

    def interrupted():
        yield fr
        yield fr
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_frames(interrupted(), out, n_frames=10)
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == ["frame_0000.floret", "frame_0001.floret"]
    assert "old run" not in (out / "frame_0001.floret").read_text()


def test_polygonize_rerun_replaces_the_older_frames(tmp_path):
    frames = tmp_path / "frames"
    r = run_cli("floret-animate", "-q", *KEYS, "--frames", "3", "-o", frames)
    assert r.returncode == 0, r.stderr
    obj = tmp_path / "obj"
    _old_run(obj, ".obj")
    r = run_cli("polygonize", "-q", frames, "-o", obj)
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in obj.glob("*.obj")) == [f"frame_{i:04d}.obj" for i in range(3)]
    assert all("old run" not in p.read_text() for p in obj.glob("*.obj"))


def test_a_killed_writers_part_files_go_with_the_older_run(tmp_path):
    from inflo.formats.atomic import remove_stale_frames

    _old_run(tmp_path, ".obj", 3)
    (tmp_path / ".frame_0002.obj.x1y2z3.part").write_text("half a frame")
    (tmp_path / ".notes.txt.abc.part").write_text("not a frame")
    (tmp_path / "log.csv").write_text("frame\n")
    removed = remove_stale_frames(tmp_path, ["frame_0000.obj"], ".obj")
    assert sorted(p.name for p in removed) == [".frame_0002.obj.x1y2z3.part", "frame_0001.obj", "frame_0002.obj"]
    assert sorted(p.name for p in tmp_path.iterdir()) == [".notes.txt.abc.part", "frame_0000.obj", "log.csv"]


def test_a_sequence_rerun_removes_its_own_frames_only(tmp_path):
    """Once a run has recorded its frames (a manifest), a later run removes those and no other file
    named like a frame: a user's frame_0009.obj beside polygonize's frames stays."""
    frames = tmp_path / "frames"
    r = run_cli("floret-animate", "-q", *KEYS, "--frames", "3", "-o", frames)
    assert r.returncode == 0, r.stderr
    obj = tmp_path / "obj"
    assert run_cli("polygonize", "-q", frames, "-o", obj).returncode == 0
    (obj / "frame_0009.obj").write_text("# mine\n")
    r = run_cli("floret-animate", "-q", *KEYS, "--frames", "2", "-o", frames)
    assert sorted(p.name for p in frames.glob("*.floret")) == ["frame_0000.floret", "frame_0001.floret"]
    assert run_cli("polygonize", "-q", frames, "-o", obj).returncode == 0
    assert sorted(p.name for p in obj.glob("*.obj")) == ["frame_0000.obj", "frame_0001.obj", "frame_0009.obj"]


def test_fccompose_rerun_removes_its_own_frames_only(tmp_path):
    """fccompose's earlier frames go (by its manifest) before a rerun writes any, and a shorter
    rerun leaves none of the longer run's; a user's file named like a frame stays."""
    import shutil

    src = tmp_path / "fcc"
    shutil.copytree(REPO / "pipelines" / "examples" / "fccompose", src)
    out = tmp_path / "canopy"
    r = run_cli("fccompose", "-q", src / "dense.fcc", "--frames", "3", "--updates", "1", "-o", out)
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in out.glob("*.obj")) == [f"frame_{i:04d}.obj" for i in range(4)]
    (out / "frame_0099.obj").write_text("# a user's file named like a frame\n")
    r = run_cli("fccompose", "-q", src / "dense.fcc", "--frames", "2", "--updates", "1", "-o", out)
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in out.glob("*.obj")) == [f"frame_{i:04d}.obj" for i in range(3)] + ["frame_0099.obj"]
