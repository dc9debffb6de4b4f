"""inflo-sweep: sweep files, variants, overrides, and sweeps on Dask.

Kept fast: single-stage sweeps of phyllotaxis + dimorph on heads of 20-40 florets and a pipeline of
shell commands, on a LocalCluster of 2 workers and on a `dask scheduler` + `dask worker` started
here on loopback.
"""
from __future__ import annotations

import csv
import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import REPO, run_cli

from inflo.formats.errors import FormatError, InputError
from inflo.tools.sweep.overrides import set_fcc_key, set_flag, set_toml_key
from inflo.tools.sweep.spec import parse_sweep, variants

VOGEL = (REPO / "pipelines" / "examples" / "sweeps" / "vogel.toml").read_text()

STAGES = """\
[sweep]
name = "tiny"
inputs = ["vogel.toml"]
still = "head.png"

[base]
"dimorph:--alpha" = 120

[axes]
n = {{ target = "vogel.toml:primordia.count", values = {ns} }}

[[stage]]
cli = "phyllotaxis"
args = ["{{inputs}}/vogel.toml", "-o", "{{out}}/head", "--png", "{{out}}/head.png"]

[[stage]]
cli = "dimorph"
args = ["{{out}}/head/scene.scn", "--alpha", "75", "-o", "{{out}}/typed.scn"]

[metrics]
rays = {{ log = "dimorph", regex = '(\\d+) ray, ' }}
florets = {{ file = "typed.scn", count = "^ca:|^o:" }}
"""


def _sweep_dir(tmp_path, ns="[20, 30, 40, 5000]") -> Path:
    (tmp_path / "vogel.toml").write_text(VOGEL)
    p = tmp_path / "tiny.toml"
    p.write_text(STAGES.format(ns=ns))
    return p


def _rows(out: Path) -> list[dict]:
    with open(out / "results.csv", newline="") as fh:
        return list(csv.DictReader(fh))


# ---------------------------------------------------------------------------------------------
# the sweep file, variants and overrides (no cluster)

def test_grid_variants_in_order_with_stable_ids(tmp_path):
    (tmp_path / "vogel.toml").write_text(VOGEL)
    text = STAGES.format(ns="[20, 30]").replace(
        "[[stage]]", '[axes.alpha]\ntarget = "dimorph:--alpha"\nrange = [60, 120, 30]\n\n[[stage]]', 1)
    sw = parse_sweep(text, tmp_path / "s.toml")
    vs = variants(sw)
    assert [v.params for v in vs] == [(("n", n), ("alpha", a)) for n in (20, 30) for a in (60, 90, 120)]
    assert vs[0].id.startswith("n20_alpha60-") and len({v.id for v in vs}) == 6
    assert [v.id for v in variants(parse_sweep(text, tmp_path / "s.toml"))] == [v.id for v in vs]


def test_random_variants_follow_the_seed(tmp_path):
    (tmp_path / "vogel.toml").write_text(VOGEL)
    text = STAGES.format(ns="[20, 30, 40]").replace('name = "tiny"', 'name = "r"\nsampling = "random"\nsamples = 5\nseed = 3')
    text = text.replace("[[stage]]", '[axes.alpha]\ntarget = "dimorph:--alpha"\nuniform = [20.0, 160.0]\n\n[[stage]]', 1)
    a = variants(parse_sweep(text, tmp_path / "s.toml"))
    b = variants(parse_sweep(text, tmp_path / "s.toml"))
    c = variants(parse_sweep(text.replace("seed = 3", "seed = 4"), tmp_path / "s.toml"))
    assert len(a) == 5 and [v.params for v in a] == [v.params for v in b] != [v.params for v in c]
    assert all(20.0 <= dict(v.params)["alpha"] <= 160.0 and dict(v.params)["n"] in (20, 30, 40) for v in a)


@pytest.mark.parametrize("edit, where, expected", [
    (('name = "tiny"', 'name = "tiny"\nsampel = 3'), 3, "a key of [sweep] (did you mean 'samples'?)"),
    (('values = [20]', 'values = []'), 10, "values as a non-empty list"),
    (('"vogel.toml:primordia.count"', '"vogel.toml"'), 10, "a parameter target"),
    (('"dimorph:--alpha"', '"dimorf:--alpha"'), 7, "a stage name of ['phyllotaxis', 'dimorph']"),
    (('log = "dimorph"', 'log = "dimorp"'), 21, "log = one of"),
])
def test_bad_sweep_files_name_the_line(tmp_path, edit, where, expected):
    (tmp_path / "vogel.toml").write_text(VOGEL)
    text = STAGES.format(ns="[20]").replace(*edit)
    assert text != STAGES.format(ns="[20]")
    with pytest.raises(FormatError) as e:
        parse_sweep(text, tmp_path / "s.toml")
    assert e.value.line == where and expected in e.value.expected, str(e.value)


def test_cli_bad_sweep_exit_2_one_line_nothing_written(tmp_path):
    p = _sweep_dir(tmp_path)
    p.write_text(p.read_text().replace('cli = "dimorph"', 'cli = "dimorph"\nclii = 1'))
    res = run_cli("inflo-sweep", p, "-o", tmp_path / "out")
    assert res.returncode == 2, res.stderr
    assert res.stderr.count("\n") == 1 and f"{p}:18: expected a key of [stage]" in res.stderr
    assert not (tmp_path / "out").exists()


def test_overrides_toml_fcc_flags():
    text = "# c\n[primordia]\narea = 0.003  # small\ncount = 100\n\n[surface]\ncurve = \"disk\"\n"
    out = set_toml_key(text, "primordia.count", 30)
    assert "count = 30" in out and "# c" in out and "area = 0.003  # small" in out
    assert 'radius = 2.5' in set_toml_key(text, "surface.radius", 2.5)
    assert "[dynamics]\nframes = 4" in set_toml_key(text, "dynamics.frames", 4)
    with pytest.raises(InputError):
        set_toml_key("[a]\nb = [1,\n 2]\n", "a.b", 3)
    fcc = "# x\nSolver  Iterations: 20\nspacing: 0.003 # mm\n"
    assert "Solver  Iterations: 7\n" in set_fcc_key(fcc, "solver iterations", 7)
    assert set_fcc_key(fcc, "kStretch", 0.9).endswith("kStretch: 0.9\n")
    assert set_flag(["a", "--alpha", "75", "-o", "x"], "--alpha", 40.5) == ["a", "--alpha", "40.5", "-o", "x"]
    assert set_flag(["a"], "--seed", 3) == ["a", "--seed", "3"]
    assert set_flag(["a", "--half-angle"], "--half-angle", False) == ["a"]
    assert set_flag(["a", "--alpha=7"], "--alpha", 8) == ["a", "--alpha=8"]


# ---------------------------------------------------------------------------------------------
# on Dask

def test_local_cluster_failure_isolated_and_rerun_does_no_work(tmp_path):
    p = _sweep_dir(tmp_path)
    out = tmp_path / "out"
    res = run_cli("inflo-sweep", p, "-o", out, "--workers", "2", "--dashboard", ":0")
    assert res.returncode == 1, res.stderr
    assert "dashboard: " in res.stderr
    assert "1 of 4 variants failed" in res.stderr and "do not fit on the curve" in res.stderr
    rows = _rows(out)
    assert [r["n"] for r in rows] == ["20", "30", "40", "5000"]
    assert [r["status"] for r in rows] == ["ok", "ok", "ok", "failed"]
    bad = rows[3]
    assert bad["exit_code"] == "2" and bad["error"].startswith("phyllotaxis: error:") and "\n" not in bad["error"]
    for r in rows[:3]:
        assert int(r["rays"]) > 0 and int(r["florets"]) == int(r["n"]) and float(r["wall_s"]) > 0
        assert float(r["peak_mb"]) > 0 and (out / r["still"]).is_file()
        vdir = out / "variants" / r["id"]
        assert (vdir / "done").is_file() and json.loads((vdir / "result.json").read_text())["status"] == "ok"
    assert not (out / "variants" / bad["id"] / "done").exists()
    assert (out / "contact_sheet.png").is_file()
    # the same head types the same whatever the worker: 120 degrees on a 20-floret Vogel head
    stamp = {r["id"]: (out / "variants" / r["id"] / "out" / "typed.scn").stat().st_mtime_ns for r in rows[:3]}
    time.sleep(0.05)
    res2 = run_cli("inflo-sweep", p, "-o", out, "--workers", "2", "--dashboard", ":0")
    assert res2.returncode == 1, res2.stderr
    assert "3 done before, 1 to run" in res2.stderr
    rows2 = _rows(out)
    assert [r["ran"] for r in rows2] == ["cached", "cached", "cached", "ran"]
    assert [r["rays"] for r in rows2[:3]] == [r["rays"] for r in rows[:3]]
    assert stamp == {r["id"]: (out / "variants" / r["id"] / "out" / "typed.scn").stat().st_mtime_ns for r in rows2[:3]}


def test_half_finished_variant_is_redone(tmp_path):
    """A variant whose done marker is missing (a worker died after writing some outputs) runs again."""
    p = _sweep_dir(tmp_path, ns="[20, 30]")
    out = tmp_path / "out"
    assert run_cli("inflo-sweep", p, "-o", out, "--workers", "1", "-q", "--dashboard", ":0").returncode == 0
    rows = _rows(out)
    (out / "variants" / rows[1]["id"] / "done").unlink()
    (out / "variants" / rows[1]["id"] / "out" / "typed.scn").write_text("half-written")
    res = run_cli("inflo-sweep", p, "-o", out, "--workers", "1", "--dashboard", ":0")
    assert res.returncode == 0, res.stderr
    assert [r["ran"] for r in _rows(out)] == ["cached", "ran"]
    assert (out / "variants" / rows[1]["id"] / "out" / "typed.scn").read_text().startswith("#")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.slow
def test_scheduler_address(tmp_path):
    try:
        port = _free_port()
    except OSError:
        pytest.skip("cannot bind a loopback port")
    dask = str(Path(sys.executable).parent / "dask")
    env = dict(os.environ)
    procs = []
    try:
        sched = subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", str(port),
                                  "--no-dashboard", "--no-show"], stdout=subprocess.DEVNULL,
                                 stderr=subprocess.PIPE, env=env, cwd=tmp_path, text=True)
        procs.append(sched)
        addr = f"tcp://127.0.0.1:{port}"
        deadline = time.time() + 30
        while time.time() < deadline:
            if sched.poll() is not None:
                pytest.skip(f"dask scheduler did not start: {sched.stderr.read()[-300:]}")
            try:
                socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
                break
            except OSError:
                time.sleep(0.2)
        else:
            pytest.skip("dask scheduler did not listen within 30 s")
        for _ in range(2):
            procs.append(subprocess.Popen([dask, "worker", addr, "--nthreads", "1", "--no-dashboard",
                                           "--host", "127.0.0.1"], stdout=subprocess.DEVNULL,
                                          stderr=subprocess.DEVNULL, env=env, cwd=tmp_path))
        p = _sweep_dir(tmp_path)
        out = tmp_path / "out"
        res = run_cli("inflo-sweep", p, "-o", out, "--scheduler", addr, "--workers", "2")
        assert res.returncode == 1, res.stderr
        assert f"scheduler {addr}" in res.stderr and "1 of 4 variants failed" in res.stderr
        rows = _rows(out)
        assert [r["status"] for r in rows] == ["ok", "ok", "ok", "failed"]
        assert all((out / r["still"]).is_file() for r in rows[:3])
    finally:
        for pr in reversed(procs):
            pr.terminate()
        for pr in reversed(procs):
            try:
                pr.wait(timeout=15)
            except subprocess.TimeoutExpired:
                pr.kill()
                pr.wait()
            if pr.stderr is not None:
                pr.stderr.close()


PIPE_MAKEFILE = """\
HERE := $(abspath $(dir $(lastword $(MAKEFILE_LIST))))
ROOT := $(abspath $(HERE)/../..)
B := $(ROOT)/build/toy
COLOR ?= 1
all: $(B)/out.txt
$(B)/in.txt: params.toml
\tmkdir -p $(B)
\tcp params.toml $@
$(B)/out.txt: $(B)/in.txt toy.fcc
\t@test "$(COLOR)" != bad || (echo "toy: error: COLOR must not be bad" >&2; exit 3)
\tgrep -c . $(B)/in.txt > $@
\tcat toy.fcc >> $@
\ttest -f $$(sed -n 's/^scene file path: //p' toy.fcc)
\techo "root $(ROOT)" >> $@
"""


def test_pipeline_sweep_copies_rebases_and_makes(tmp_path):
    repo = tmp_path / "repo"
    pipe = repo / "pipelines" / "toy"
    pipe.mkdir(parents=True)
    (repo / "pyproject.toml").write_text("")
    (pipe / "Makefile").write_text(PIPE_MAKEFILE)
    (pipe / "params.toml").write_text("[a]\nb = 1\n")
    (pipe / "toy.fcc").write_text("spacing: 0.003\nscene file path: ../../build/toy/in.txt\n")
    sweep = tmp_path / "toy_sweep.toml"
    sweep.write_text("""\
[sweep]
name = "toy"
[pipeline]
path = "repo/pipelines/toy"
[axes]
b = { target = "params.toml:a.b", values = [2, 3] }
color = { target = "make:COLOR", values = ["red", "bad"] }
[base]
"toy.fcc:spacing" = 0.01
[metrics]
lines = { file = "out.txt", regex = '^(\\d+)$' }
""")
    out = tmp_path / "out"
    res = run_cli("inflo-sweep", sweep, "-o", out, "--workers", "2", "--dashboard", ":0")
    assert res.returncode == 1, res.stderr
    rows = _rows(out)
    assert [(r["b"], r["color"], r["status"]) for r in rows] == [
        ("2", "red", "ok"), ("2", "bad", "failed"), ("3", "red", "ok"), ("3", "bad", "failed")]
    assert rows[1]["error"] == "toy: error: COLOR must not be bad" and rows[1]["exit_code"] == "2"
    text = (out / "variants" / rows[0]["id"] / "build" / "out.txt").read_text()
    assert text.startswith("2\n") and "spacing: 0.01" in text and "scene file path: ../build/in.txt" in text
    assert f"root {repo}" in text
    assert not (repo / "build").exists()  # nothing written into the pipeline's own build folder
    assert (out / "variants" / rows[2]["id"] / "toy" / "params.toml").read_text() == "[a]\nb = 3\n"
    res = run_cli("inflo-sweep", sweep, "-o", out, "--workers", "2", "--dashboard", ":0")
    assert "2 done before, 2 to run" in res.stderr


def test_yarrow_example_dry_run_rebases_its_fcc_files(tmp_path):
    """The yarrow example prepares (no build): overrides written, .fcc paths into the variant."""
    ex = REPO / "pipelines" / "examples" / "sweeps" / "yarrow_variants.toml"
    res = run_cli("inflo-sweep", ex, "-o", tmp_path / "y", "--dry-run")
    assert res.returncode == 0, res.stderr
    assert "4 variants, 0 done before, 4 to run" in res.stderr
    dirs = sorted((tmp_path / "y" / "variants").iterdir())
    assert len(dirs) == 4
    for d in dirs:
        fcc = (d / "yarrow" / "yarrow.fcc").read_text()
        assert "rigid body animation: 9 1 1 1 ../build/corymb/rba ../build/corymb/typed.scn" in fcc
        assert "../../build/yarrow" not in fcc
        params = json.loads((d / "params.json").read_text())["params"]
        assert f"growth_rate = {params['growth']!r}" in (d / "yarrow" / "draft" / "corymb.toml").read_text()


def test_canalization_example_parses():
    from inflo.tools.sweep.spec import read_sweep

    sw = read_sweep(REPO / "pipelines" / "examples" / "sweeps" / "canalization.toml")
    assert len(variants(sw)) == 1500 and [a.name for a in sw.axes] == ["n", "alpha"]


def test_yarrow_example_runs_from_a_clone(tmp_path):
    """The README's yarrow sweep runs its variants' copies of the pipeline, the pipeline's own Python
    scripts included (they import their shared helpers as a package, not through sys.path): one
    variant, its stages up to corymb_heads.py (a few seconds)."""
    ex = REPO / "pipelines" / "examples" / "sweeps" / "yarrow_variants.toml"
    text = ex.read_text()
    text = text.replace("samples = 4", "samples = 1")
    text = text.replace('path = "../../yarrow"', f'path = "{REPO / "pipelines" / "yarrow"}"')
    text = text.replace('build = "../../../build/yarrow"', f'build = "{REPO / "build" / "yarrow"}"')
    text = text.replace('targets = ["pictures", "check"]', 'targets = ["corymb"]')
    text = text[:text.index("[metrics]")].replace('still = "yarrow_top.png"', "")
    sweep = tmp_path / "yarrow_one.toml"
    sweep.write_text(text)
    out = tmp_path / "y"
    res = run_cli("inflo-sweep", sweep, "-o", out, "--workers", "1", "--dashboard", ":0")
    assert res.returncode == 0, res.stderr
    rows = _rows(out)
    assert [r["status"] for r in rows] == ["ok"], rows
    vdir = out / "variants" / rows[0]["id"]
    assert "ModuleNotFoundError" not in (vdir / "log.txt").read_text()
    assert (vdir / "build" / "corymb" / "scene.scn").is_file()
    assert not (REPO / "pipelines" / "yarrow" / "build").exists()
