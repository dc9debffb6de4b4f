"""``python -m inflo.tools.warm``: the canopy's kernels compiled ahead (issue 51's start-up)."""
from __future__ import annotations

import subprocess
import sys

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.tools.collide.tritri import intersecting_pairs
from inflo.tools.warm import FLORETS, FRAMES

#: the kernels whose compiling makes a fresh machine's first run slow: the floret-by-floret probe
#: (the continuous tests compiled into it) and static test, the retry rounds' pairs and response,
#: the solver's, fccompose's rest values
COSTLY = ("inflo.tools.collide.probe._probe_kernel", "inflo.tools.collide.probe._static_kernel",
          "inflo.tools.collide.detect._live_pairs", "inflo.tools.collide.response._project_collision_constraints",
          "inflo.tools.pbd.solver.project_internal_of_parts_serial", "inflo.tools.fccompose.kernels.rest_values")


def test_warm_runs_the_canopy_and_reaches_the_costly_kernels(tmp_path):
    """In a fresh process (so that no other test has called them): after the warm-up each costly
    kernel holds a compiled signature; its canopy is written, every floret in it, the florets met
    (collisions handled) and the run ended intersection-free."""
    code = ("import importlib, sys\n"
            "from inflo.tools.warm import warm_canopy_kernels\n"
            f"warm_canopy_kernels(sys.argv[1])\n"
            f"for name in {COSTLY!r}:\n"
            "    mod, _, fn = name.rpartition('.')\n"
            "    print(name, len(getattr(importlib.import_module(mod), fn).signatures))\n")
    res = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    compiled = dict(line.split() for line in res.stdout.splitlines())
    assert set(compiled) == set(COSTLY)
    assert all(int(n) > 0 for n in compiled.values()), compiled
    frames = list_obj_sequence(tmp_path / "out")
    assert len(frames) == FRAMES + 1
    last = read_obj(frames[-1])
    assert len(set(last.face_group)) == FLORETS
    log = (tmp_path / "out" / "log.csv").read_text().splitlines()
    assert sum(int(r.split(",")[6]) for r in log[1:]) > 0  # collisions found
    assert len(intersecting_pairs(last.vertices, last.faces)) == 0


def test_warm_refuses_an_unknown_argument():
    res = subprocess.run([sys.executable, "-m", "inflo.tools.warm", "--frames", "3"], capture_output=True, text=True)
    assert res.returncode == 2
    assert res.stderr.strip() == "usage: python -m inflo.tools.warm [-q]"
