"""``solver scheme: fast`` (issue 51; formats/fcc.md, "Solver scheme"): the kernels on tiny cases,
the scheme on a small dense scene (collision-free, edges within the stretch bounds, every floret
present, RMS errors at most 1.2 x the default scheme's), and the default scheme untouched."""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from conftest import run_cli

from inflo.formats.errors import FormatError
from inflo.formats.fcc import read_fcc
from inflo.formats.obj import read_obj_sequence
from inflo.tools.collide import intersecting_pairs
from inflo.tools.pbd.solver import part_offsets, solve_parts
from inflo.tools.testing.florets import (
    grid_canopy_scene,
    opening_floret,
    write_fcc_text,
    write_floret_animation,
    write_scene,
)

N_FRAMES = 12
N_FLORETS = 12


def _triangle():
    """A three-vertex system: one triangle's three edges, stretched to 1.6 x their rest lengths."""
    x = np.array([[0.0, 0.0, 0.0], [1.6, 0.0, 0.0], [0.0, 1.6, 0.0]])
    edges = np.array([[0, 1], [1, 2], [0, 2]], np.int32)
    rest = np.array([1.0, np.sqrt(2.0), 1.0])
    return x, np.ones(3), edges, rest


def _solve(x, w, edges, rest, k, iterations, tolerance):
    hinges = np.zeros((0, 4), np.int32)
    eo = part_offsets(edges, np.zeros(len(x), np.int32), 1)
    ho = part_offsets(hinges, np.zeros(len(x), np.int32), 1)
    sweeps = np.zeros(1, np.int64)
    solve_parts(x, w, edges, rest, np.full(len(edges), k), eo, hinges, np.zeros(0), np.zeros(0), ho,
                iterations, tolerance, sweeps)
    return int(sweeps[0])


def _residual(x, edges, rest):
    return float(np.abs(np.linalg.norm(x[edges[:, 0]] - x[edges[:, 1]], axis=1) - rest).max())


def test_projections_stop_on_the_residual_tolerance():
    """A part's sweeps stop after the first whose largest correction is within the tolerance: a
    loose tolerance runs fewer sweeps than the fixed count, a tight one all of them."""
    x, w, edges, rest = _triangle()
    tight = _solve(x.copy(), w, edges, rest, 0.99, 50, -1.0)  # never met: the fixed count
    xl = x.copy()
    loose = _solve(xl, w, edges, rest, 0.99, 50, 1e-3)
    assert tight == 50
    assert 1 < loose < 50
    assert _residual(xl, edges, rest) < 1e-2  # stopped near rest, not after one sweep


def test_over_relaxed_sweeps_converge_in_fewer_sweeps():
    """Stiffness scaled by an over-relaxation factor (successive over-relaxation of the
    Gauss-Seidel sweeps, tried for the fast scheme) reaches the same tolerance in fewer sweeps on a chain
    of 30 vertices pinned at one end (a petal's row, stretched and bent), and ends at rest."""
    n = 30
    x = np.zeros((n, 3))
    x[:, 0] = np.arange(n)
    x[:, 1] = 0.3 * np.sin(np.arange(n))
    edges = np.array([[i, i + 1] for i in range(n - 1)], np.int32)
    rest = np.full(n - 1, 1.3)
    w = np.ones(n)
    w[0] = 0.0
    x1, x2 = x.copy(), x.copy()
    plain = _solve(x1, w, edges, rest, 0.99, 500, 1e-6)
    sor = _solve(x2, w, edges, rest, 0.99 * 1.2, 500, 1e-6)
    assert sor < 0.7 * plain < 500
    assert _residual(x2, edges, rest) < 1e-5


@pytest.fixture(scope="module")
def canopy(tmp_path_factory):
    """A small dense canopy (12 opening florets on a jittered grid) run by both schemes."""
    d = tmp_path_factory.mktemp("fast")
    frames, faces, fixed = opening_floret(N_FRAMES, nu=12, nv=4)
    write_floret_animation(d / "anim", frames, faces, fixed, d / "petal_base.txt")
    write_scene(d / "scene.scn", grid_canopy_scene(N_FLORETS, N_FRAMES))
    write_fcc_text(d / "canopy.fcc", solver_iterations=50, collision_iterations=10, retries=20, spacing=0.005,
                   sanity_every=1)
    out = {}
    for scheme in ("default", "fast"):
        o = d / scheme
        res = run_cli("fccompose", d / "canopy.fcc", "-o", o, "-q", "--scheme", scheme)
        assert res.returncode == 0, res.stderr
        out[scheme] = o
    return d, out


def _log(folder) -> list[dict]:
    with open(Path(folder) / "log.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def test_fast_scheme_keeps_the_quality_figures(canopy):
    """Zero intersecting pairs in every written frame, every edge within [0.5, 1.5] x rest,
    every floret present, RMS edge and dihedral errors at most 1.2 x the default scheme's; and the
    scene is dense (the response had work to do)."""
    _, out = canopy
    fast, default = _log(out["fast"]), _log(out["default"])
    assert sum(int(r["collisions_found"]) for r in fast) > 50
    assert all(int(r["intersecting_pairs"]) == 0 for r in fast)
    _, meshes = read_obj_sequence(out["fast"])
    assert len(meshes) == N_FRAMES
    for mesh in meshes:
        assert len(intersecting_pairs(mesh.vertices, mesh.faces)) == 0
    assert min(float(r["min_edge_stretch"]) for r in fast[1:]) >= 0.5
    assert max(float(r["max_edge_stretch"]) for r in fast[1:]) <= 1.5
    assert int(fast[-1]["florets_present"]) == N_FLORETS
    assert len(meshes[-1].groups) == N_FLORETS
    for col in ("rms_edge_error", "rms_dihedral_error_deg"):
        f = np.mean([float(r[col]) for r in fast[1:]])
        d = np.mean([float(r[col]) for r in default[1:]])
        assert f <= 1.2 * d + 1e-12, (col, f, d)


def test_default_scheme_is_the_file_default(canopy):
    """``--scheme default`` writes what a run without the option writes, byte for byte."""
    d, out = canopy
    plain = d / "plain"
    res = run_cli("fccompose", d / "canopy.fcc", "-o", plain, "-q")
    assert res.returncode == 0, res.stderr
    for k in range(N_FRAMES):
        name = f"frame_{k:04d}.obj"
        assert (plain / name).read_bytes() == (out["default"] / name).read_bytes(), name


def test_solver_scheme_key(tmp_path):
    (tmp_path / "a.fcc").write_text("solver scheme: fast\n")
    assert read_fcc(tmp_path / "a.fcc").solver_scheme == "fast"
    (tmp_path / "b.fcc").write_text("solver iterations: 5\n")
    assert read_fcc(tmp_path / "b.fcc").solver_scheme == "default"
    (tmp_path / "c.fcc").write_text("solver scheme: quick\n")
    with pytest.raises(FormatError, match="default, fast"):
        read_fcc(tmp_path / "c.fcc")
