"""Hostile probes of inflo-sweep, canopy-render and the shared CLI layer: each is one line on
stderr, exit 2, and the output folder (and every file of the user's) as it was.

- inflo-sweep: a stage writes only inside its variant's folder (``-o {sweep_dir}`` overwrote the
  user's files), one sweep at a time per OUT_DIR, ``--workers`` and ``--scheduler`` checked before
  anything is written, a timeout a timer can wait, values on one line;
- canopy-render: float options finite (``--azimuth nan`` was exit 1), ``--label`` a label, the
  ``.fcc`` camera keys drawable;
- every CLI: click's usage errors are one line ``<cli>: error: ... (see <cli> --help)``; a file
  name holding a newline stays on one line.
"""
from __future__ import annotations

import shutil
import socket
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import CLI_NAMES, REPO, run_cli

from inflo.formats.obj import ObjMesh, write_obj

VOGEL = REPO / "pipelines" / "examples" / "sweeps" / "vogel.toml"

HEAD = '[sweep]\nname = "x"\ninputs = ["vogel.toml", "scene.scn"]\n'
AXIS = '[axes]\n"vogel.toml:primordia.count" = { values = [10, 20] }\n'


def _stage(args: str, extra: str = "", axes: str = AXIS, head: str = HEAD) -> str:
    return f'{head}{extra}{axes}[[stage]]\ncli = "phyllotaxis"\nargs = {args}\n'


@pytest.fixture()
def work(tmp_path):
    d = tmp_path / "w"
    d.mkdir()
    shutil.copy(VOGEL, d / "vogel.toml")
    (d / "scene.scn").write_text("user data\n")
    (d / "notes.txt").write_text("mine\n")
    tri = ObjMesh(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]), np.array([[0, 1, 2]], np.int32))
    write_obj(d / "tri.obj", tri)
    seq = d / "seq"
    seq.mkdir()
    write_obj(seq / "frame_0000.obj", tri)
    write_obj(seq / "frame_0001.obj", tri)
    return d


def _snapshot(folder: Path) -> dict:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _one_line_exit_2(r, fragment: str) -> None:
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert fragment in r.stderr, r.stderr


# (sweep file text, message fragment): refused when the sweep file is read, before anything is written
SWEEPS = [
    # the reported repro: phyllotaxis -o {sweep_dir} overwrote the user's scene.scn
    (_stage('["{inputs}/vogel.toml", "-o", "{sweep_dir}"]'), "an output (-o) inside the variant's folder"),
    (_stage('["{inputs}/vogel.toml", "-o", "{sweep_dir}/vogel.toml"]'), "an output (-o) inside the variant's folder"),
    (_stage('["{inputs}/vogel.toml", "-o", "/tmp/inflo-sweep-escaped"]'), "an output (-o) inside"),
    (_stage('["{inputs}/vogel.toml", "-o", "{out}/../../../.."]'), "an output (-o) inside"),
    (_stage('["{inputs}/vogel.toml", "--output={variant}/.."]'), "an output (--output) inside"),
    (_stage('["{inputs}/vogel.toml", "-o{sweep_dir}"]'), "an output (-o) inside"),
    (_stage('["{inputs}/vogel.toml", "-o", "h"]'), "an output (-o) inside"),  # relative: the working folder
    (_stage('["{inputs}/vogel.toml", "-o", "{out}/h", "--png", "{sweep_dir}/notes.txt"]'),
     "paths inside the variant's folder"),
    (_stage('["{inputs}/vogel.toml", "-o", "{out}/h", "--png={sweep_dir}/p.png"]'), "paths inside the variant's"),
    (_stage('["{sweep_dir}/notes.txt", "-o", "{out}/h"]'), "or of [sweep] inputs (read, not written)"),
    (_stage('["{inputs}/vogel.toml", "-o", "{out}/{d}"]',
            axes=AXIS + 'd = { target = "--seed", values = ["a", "../../../x"] }\n'), "with d = ../../../x"),
    (_stage('["{inputs}/vogel.toml", "-o", "{out}/h"]',
            axes=AXIS + 'o = { target = "phyllotaxis:-o", values = ["/tmp/x"] }\n'), "found '/tmp/x' with o = /tmp/x"),
    (_stage('["{inputs}/vogel.toml", "-o", "{out}/h"]', extra='[base]\n"phyllotaxis:--output" = "../x"\n'),
     "an output (--output) inside"),
    (_stage('["{inputs}/vogel.toml", "-o", "{out}/h"]', head=HEAD + "timeout = inf\n"), "timeout in seconds in [0,"),
    (_stage('["{inputs}/vogel.toml", "-o", "{out}/h"]', head=HEAD + "timeout = 1e300\n"), "timeout in seconds in [0,"),
    (_stage('["{inputs}/vogel.toml", "-o", "{out}/h"]', axes='[axes]\n"vogel.toml:primordia.count" = '
            '{ values = ["10\\n[evil]\\nx=1"] }\n'), "values on one line"),
    (_stage('["{inputs}/vogel.toml", "-o", "{out}/h"]', head=HEAD + 'still = "../../../scene.scn"\n'),
     "still as a path inside"),
    (_stage('["{inputs}/vogel.toml", "-o", "{out}/h"]') + '[metrics]\nm = { file = "/etc/hostname", count = "x" }\n',
     "a metric's file inside"),
]


@pytest.mark.parametrize("text,fragment", SWEEPS, ids=[f"sweep-{i}" for i in range(len(SWEEPS))])
def test_sweep_stage_writes_only_inside_its_variant(work, text, fragment):
    (work / "s.toml").write_text(text)
    before = _snapshot(work)
    r = run_cli("inflo-sweep", "-q", work / "s.toml", "-o", work / "out", "--workers", "1", "--dashboard", ":0")
    _one_line_exit_2(r, fragment)
    assert "s.toml:" in r.stderr  # the line of the stage (or key) is named
    assert not (work / "out").exists() and _snapshot(work) == before
    assert not Path("/tmp/inflo-sweep-escaped").exists()


def test_sweep_paths_inside_the_variant_are_taken(work):
    """Outputs under {out}/{variant}/{inputs}, paths of inputs and NAME=PATH inside: a dry run lists them."""
    (work / "s.toml").write_text(_stage('["{inputs}/vogel.toml", "-o", "{out}/head", "--png={out}/h.png", '
                                        '"--png", "{variant}/out/x.png"]'))
    r = run_cli("inflo-sweep", work / "s.toml", "-o", work / "out", "--dry-run")
    assert r.returncode == 0 and "2 variants, 0 done before, 2 to run" in r.stderr, r.stderr


def test_sweep_pipeline_build_folder_is_the_variants(work):
    pipe = work / "pipe"
    pipe.mkdir()
    (pipe / "Makefile").write_text("all:\n\ttrue\n")
    (work / "p.toml").write_text('[pipeline]\npath = "pipe"\nvars = { B = "/tmp" }\n')
    r = run_cli("inflo-sweep", work / "p.toml", "-o", work / "out")
    _one_line_exit_2(r, "make variables other than B")
    (work / "p.toml").write_text('[pipeline]\npath = "pipe"\n[axes]\n"make:B" = ["/tmp"]\n')
    r = run_cli("inflo-sweep", work / "p.toml", "-o", work / "out")
    _one_line_exit_2(r, "make targets other than make:B")
    assert not (work / "out").exists()


def test_sweep_output_holding_an_input_where_it_writes(work):
    (work / "results.csv").write_text("my results\n")
    (work / "s.toml").write_text(_stage('["{inputs}/vogel.toml", "-o", "{out}/h"]').replace(
        '"scene.scn"]', '"scene.scn", "results.csv"]'))
    before = _snapshot(work)
    r = run_cli("inflo-sweep", work / "s.toml", "-o", work, "--workers", "1", "--dashboard", ":0")
    _one_line_exit_2(r, "that holds the input")
    assert _snapshot(work) == before


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("args,fragment", [
    (["--workers", "1000000"], "'--workers': 1000000 is not in the range 1<=x<=1024"),
    (["--workers", "0"], "'--workers'"),
    (["--workers", "x"], "'--workers'"),
    (["--scheduler", "tcp://256.1.1.1:1"], "expected a Dask scheduler address"),
    (["--scheduler", "tcp://127.0.0.1:70000"], "expected a Dask scheduler address"),
    (["--scheduler", "not an address"], "expected a Dask scheduler address"),
    (["--scheduler", "tcp://127.0.0.1:{port}"], "expected a Dask scheduler listening at"),
    (["--scheduler", "no-such-host.invalid:8786"], "found no host"),
    (["--dashboard", "nonsense"], "--dashboard: expected an address [HOST]:PORT"),
    (["--dashboard", ":99999"], "--dashboard: expected an address [HOST]:PORT"),
], ids=["workers-1e6", "workers-0", "workers-word", "sched-256", "sched-port", "sched-words", "sched-refused",
        "sched-nohost", "dashboard-word", "dashboard-port"])
def test_sweep_workers_and_scheduler_are_checked_first(work, args, fragment):
    (work / "s.toml").write_text(_stage('["{inputs}/vogel.toml", "-o", "{out}/h"]'))
    args = [a.format(port=_free_port()) for a in args]
    t0 = time.monotonic()
    r = run_cli("inflo-sweep", work / "s.toml", "-o", work / "out", *args)
    _one_line_exit_2(r, fragment)
    assert time.monotonic() - t0 < 25  # a bad address was 30 s and exit 1
    assert not (work / "out").exists()


def test_sweep_copies_bounded_by_variants_times_input_size(work):
    """100,000 variants each copying a 1 MB input: 100 GB of copies, refused before any is written."""
    (work / "pad.txt").write_text("#" * 1_000_000)
    (work / "s.toml").write_text(_stage('["{inputs}/vogel.toml", "-o", "{out}/h"]',
                                        axes='[axes]\n"vogel.toml:primordia.count" = { range = [1, 100000, 1] }\n')
                                 .replace('"scene.scn"]', '"scene.scn", "pad.txt"]'))
    r = run_cli("inflo-sweep", work / "s.toml", "-o", work / "out")
    _one_line_exit_2(r, "expected variants x the bytes each copies within 5e+10 bytes, found 100000 variants")
    assert not (work / "out").exists()


def test_sweep_local_workers_bounded_by_the_cpus(work):
    import os

    from inflo.tools.sweep.cli import local_worker_limit

    n = local_worker_limit() + 1
    if n > 1024:
        pytest.skip("a machine with more than 128 CPUs: the option's own bound applies")
    (work / "s.toml").write_text(_stage('["{inputs}/vogel.toml", "-o", "{out}/h"]'))
    r = run_cli("inflo-sweep", work / "s.toml", "-o", work / "out", "--workers", n)
    _one_line_exit_2(r, f"at most {max(16, 8 * (os.cpu_count() or 1))} worker processes")
    assert not (work / "out").exists()


def test_sweep_second_run_into_one_folder_is_refused(work):
    from inflo.formats.atomic import output_lock

    (work / "s.toml").write_text(_stage('["{inputs}/vogel.toml", "-o", "{out}/h"]'))
    out = work / "out"
    out.mkdir()
    (out / "results.csv").write_text("the first run's\n")
    with output_lock(out, "inflo-sweep"):  # the first run, still writing
        r = run_cli("inflo-sweep", work / "s.toml", "-o", out, "--workers", "1", "--dashboard", ":0")
    _one_line_exit_2(r, "no other run is writing")
    assert sorted(p.name for p in out.iterdir()) == ["results.csv"]
    assert (out / "results.csv").read_text() == "the first run's\n"


# canopy-render: (arguments with {d} the work folder, message fragment); the picture must not exist
RENDERS = [
    (["--azimuth", "nan"], "'--azimuth': expected a finite number, found 'nan'"),
    (["--azimuth", "inf"], "'--azimuth': expected a finite number"),
    (["--elevation", "nan"], "'--elevation': expected a finite number"),
    (["--zoom", "nan"], "'--zoom': expected a finite number"),
    (["--fov", "inf"], "'--fov': expected a finite number"),
    (["--margin", "nan"], "'--margin': expected a finite number"),
    (["--line-width", "nan"], "'--line-width': expected a finite number"),
    (["--background", "nan,0,0"], "'--background'"),
    (["--bogus"], "No such option '--bogus'"),
    (["--sheet-every", "1", "--label", "{n.__class__}"], "'--label': expected a label with {n}, {index} or {name}"),
    (["--sheet-every", "1", "--label", "{n:>999999999}"], "widths below 1000"),
    (["--sheet-every", "1", "--label", "{name:d}"], "'--label'"),
    (["--fcc", "{d}/fov.fcc"], "camera fov in [0.01, 179] degrees, found 1e-300"),
    (["--fcc", "{d}/pos.fcc"], "camera position within +-1e+15, found 1e+300 0 0"),
    (["--fcc", "{d}/near.fcc"], "near plane in [1e-09, 1e+15], found 1e-300"),
    (["--fcc", "{d}/light.fcc"], "light position within +-1e+15"),
]


@pytest.mark.parametrize("args,fragment", RENDERS, ids=[f"render-{i}" for i in range(len(RENDERS))])
def test_canopy_render_options_are_one_line_errors(work, args, fragment):
    (work / "fov.fcc").write_text("camera position: 0 0 5\ncamera lookat: 0 0 0\ncamera fov: 1e-300\n")
    (work / "pos.fcc").write_text("camera position: 1e300 0 0\ncamera lookat: 0 0 0\n")
    (work / "near.fcc").write_text("camera position: 0 0 5\ncamera lookat: 0 0 0\nnear plane: 1e-300\n")
    (work / "light.fcc").write_text("light position: 1e300 1e300 1e300\n")
    out = work / "pic.png"
    r = run_cli("canopy-render", work / "seq", "-o", out, *[a.replace("{d}", str(work)) for a in args])
    _one_line_exit_2(r, fragment)
    assert r.stderr.startswith("canopy-render: error: ")
    assert not out.exists()


@pytest.mark.parametrize("args,fragment", [
    (["--sheet-every", "1", "--size", "16384x16384"], "expected a sheet of at most 536,870,912 pixels in all"),
    (["--size", "16384x16384", "-o", "{d}/anim.gif"], "expected a gif of at most 536,870,912 pixels in all"),
], ids=["sheet-pixels", "gif-pixels"])
def test_canopy_render_held_frames_bounded(work, args, fragment):
    out = work / "pic.png"
    shutil.copy(work / "seq" / "frame_0001.obj", work / "seq" / "frame_0002.obj")  # 3 x 16384^2 > 2^29
    args = [a.replace("{d}", str(work)) for a in args]
    r = run_cli("canopy-render", work / "seq", *([] if "-o" in args else ["-o", out]), *args)
    _one_line_exit_2(r, fragment)
    assert not out.exists() and not (work / "anim.gif").exists()


def test_canopy_render_image_the_gl_cannot_allocate(work):
    """llvmpipe refuses a 16384x16384 framebuffer at 4 samples (was exit 1); a GL that allocates it draws."""
    out = work / "big.png"
    r = run_cli("canopy-render", work / "tri.obj", "-o", out, "--size", "16384x16384", "--samples", "4")
    if r.returncode == 0:
        pytest.skip("this GL allocates a 16384x16384 image at 4 samples")
    _one_line_exit_2(r, "expected an image the GL can allocate")
    assert not out.exists()


def test_canopy_render_label_and_fcc_in_range_still_draw(work):
    (work / "cam.fcc").write_text("camera position: 0 0 5\ncamera lookat: 0 0 0\ncamera fov: 40\nnear plane: 0.01\n")
    r = run_cli("canopy-render", "-q", work / "seq", "--sheet-every", "1", "--label", "{n:03d} {name}", "-o",
                work / "sheet.png")
    assert r.returncode == 0 and (work / "sheet.png").is_file(), r.stderr
    r = run_cli("canopy-render", "-q", work / "tri.obj", "--fcc", work / "cam.fcc", "-o", work / "cam.png")
    assert r.returncode == 0 and (work / "cam.png").is_file(), r.stderr


@pytest.mark.parametrize("cli", CLI_NAMES)
def test_usage_error_is_one_line(cli):
    """An unknown option: ``<cli>: error: No such option ... (see <cli> --help)``, exit 2."""
    r = run_cli(cli, "--no-such-option-here")
    _one_line_exit_2(r, "No such option")
    path = "dimorph run" if cli == "dimorph" else cli  # dimorph's first argument is the scene of 'run'
    assert r.stderr.startswith(f"{path}: error: ") and r.stderr.rstrip().endswith(f"(see {path} --help)"), r.stderr
    assert "Usage:" not in r.stderr


@pytest.mark.parametrize("cli,args,fragment", [
    ("dimorph", ["{d}/x.scn", "--alpha", "nan", "-o", "{d}/o.scn"], "'--alpha': expected a finite number"),
    ("dimorph", ["sweep", "--alpha-step", "nan", "-o", "{d}/o"], "'--alpha-step': expected a finite number"),
    ("thyrse", ["--base", "0", "nan", "0", "-o", "{d}/o"], "'--base': expected a finite number"),
    ("branch-gen", ["{d}/x.scn", "--base", "inf", "0", "0", "-o", "{d}/o"], "'--base': expected a finite number"),
    ("canopy-export", ["{d}/seq", "--max-mb", "nan", "-o", "{d}/o.glb"], "'--max-mb': expected a finite number"),
    ("inflo-sweep", ["{d}/s.toml"], "Missing option '-o' / '--output'"),
    ("venation", ["{d}/no\nsuch.toml", "-o", "{d}/o"], "no\\nsuch.toml"),
    ("phyllotaxis", ["{d}/no\x1bsuch.toml", "-o", "{d}/o"], "no\\x1bsuch.toml"),
], ids=["dimorph-alpha", "dimorph-sweep-step", "thyrse-base", "branch-gen-base", "export-max-mb", "sweep-no-o",
        "newline-name", "escape-name"])
def test_cli_layer_one_line(work, cli, args, fragment):
    r = run_cli(cli, *[a.format(d=work) for a in args])
    _one_line_exit_2(r, fragment)
    assert not (work / "o").exists() and not (work / "o.scn").exists() and not (work / "o.glb").exists()


def test_help_is_unchanged_by_the_one_line_errors():
    r = run_cli("canopy-render", "--help")
    assert r.returncode == 0 and r.stdout.startswith("Usage: canopy-render [OPTIONS] INPUTS...")
    assert "--azimuth FLOAT" in r.stdout and "--zoom FLOAT RANGE" in r.stdout
