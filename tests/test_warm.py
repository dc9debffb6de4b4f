"""``python -m inflo.tools.warm``: the canopy's kernels compiled ahead (issue 51's start-up)."""
from __future__ import annotations

import subprocess
import sys

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.tools.collide import detect, probe, response
from inflo.tools.collide.tritri import intersecting_pairs
from inflo.tools.fccompose import kernels
from inflo.tools.pbd import solver
from inflo.tools.warm import FLORETS, FRAMES, warm_canopy_kernels


def test_warm_runs_the_canopy_and_reaches_the_costly_kernels(tmp_path):
    seconds = warm_canopy_kernels(tmp_path)
    assert seconds > 0
    frames = list_obj_sequence(tmp_path / "out")
    assert len(frames) == FRAMES + 1
    last = read_obj(frames[-1])
    assert len(set(last.face_group)) == FLORETS  # every floret written
    # the florets met (collisions handled) and the run ended intersection-free
    log = (tmp_path / "out" / "log.csv").read_text().splitlines()
    found = sum(int(r.split(",")[6]) for r in log[1:])
    assert found > 0
    assert len(intersecting_pairs(last.vertices, last.faces)) == 0
    # the kernels whose compiling makes a fresh machine's first run slow are among those it compiled
    # or loaded: the floret-by-floret probe (the continuous tests compiled into it) and static test,
    # the retry rounds' pairs and response, the solver's, fccompose's rest values
    for dispatcher in (probe._probe_kernel, probe._static_kernel, detect._live_pairs,
                       response._project_collision_constraints, solver.project_internal_of_parts_serial,
                       kernels.rest_values):
        assert dispatcher.signatures, dispatcher.py_func.__name__


def test_warm_refuses_an_unknown_argument():
    res = subprocess.run([sys.executable, "-m", "inflo.tools.warm", "--frames", "3"], capture_output=True, text=True)
    assert res.returncode == 2
    assert res.stderr.strip() == "usage: python -m inflo.tools.warm [-q]"
