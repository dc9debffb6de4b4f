"""``floret-animate`` as a library call: key-pose files in, frame files out."""
from __future__ import annotations

import os
from pathlib import Path

from inflo.formats.atomic import (
    begin_sequence,
    check_output_path,
    frame_name,
    output_lock,
    refuse_output_over_inputs,
    remove_stale_frames,
)
from inflo.formats.errors import InputError
from inflo.formats.floret import read_floret, write_floret
from inflo.formats.func import read_func
from inflo.tools.common.cli import progress

from .animate import FloretAnimator, check_growth

__all__ = ["animate_files", "write_frames", "FRAME_PREFIX"]

FRAME_PREFIX = "frame_"


def write_frames(frames, output, quiet: bool = True, n_frames: int | None = None) -> list[Path]:
    """Write Floret frames as ``output/frame_0000.floret`` ... (atomic); returns the paths."""
    out = Path(output)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    with output_lock(out, "floret-animate"), \
            progress(frames, length=n_frames, label="floret-animate", quiet=quiet) as bar:
        # an older run's frames go first: an interrupted run leaves a shorter sequence, never a mix
        if n_frames is not None:
            begin_sequence(out, "floret-animate", [frame_name(i, FRAME_PREFIX, ".floret") for i in range(n_frames)],
                           ".floret", prefix=FRAME_PREFIX)
        else:
            remove_stale_frames(out, [], ".floret")
        for i, fr in enumerate(bar):
            p = out / frame_name(i, FRAME_PREFIX, ".floret")
            write_floret(p, fr)
            written.append(p)
    return written


def animate_files(key_poses, output, *, n_frames: int = 100, growth_path=None, lu_params=None,
                  seed: int = 0, quiet: bool = True) -> list[Path]:
    """Read key poses (and a growth function), write ``n_frames`` frames to ``output``."""
    paths = [os.fspath(p) for p in key_poses]
    # the frames of an earlier run are removed from the output folder: never a key pose, growth or
    # parameter file that lies there (frame_0005.floret may be a key pose)
    check_output_path(output, folder=True)
    refuse_output_over_inputs(output, [(p, "key pose") for p in paths]
                              + [(f, "input") for f in (growth_path, lu_params) if f is not None])
    growth = None
    if growth_path is not None:
        growth = read_func(growth_path)
        check_growth(growth, growth_path)
    poses = [read_floret(p) for p in paths]
    if lu_params is not None:
        from .growth import lu_frames, read_lu_params

        if len(poses) != 1:
            raise InputError(f"--lu grows one initial pose: expected 1 key pose, found {len(poses)}")
        params = read_lu_params(lu_params)
        frames = lu_frames(poses[0], params, n_frames=n_frames, growth=growth, seed=seed,
                           path=paths[0])
    else:
        if len(poses) < 2:
            raise InputError(f"{paths[0]}: expected at least 2 key poses to interpolate (or --lu "
                             "PARAMS.toml to grow one), found 1")
        frames = FloretAnimator(poses, paths).frames(n_frames, growth)
    return write_frames(frames, output, quiet=quiet, n_frames=n_frames)
