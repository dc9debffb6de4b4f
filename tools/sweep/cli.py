"""Command-line front end of ``inflo-sweep`` (the sweep file: formats/sweep.md).

``inflo-sweep SWEEP.toml -o OUT_DIR [--scheduler ADDRESS] [--workers N]`` runs every variant of
the sweep as Dask tasks (a LocalCluster of N workers, or the scheduler at ADDRESS), each in
``OUT_DIR/variants/<id>/``, and writes ``OUT_DIR/results.csv``, ``contact_sheet.png`` and, for a
2-D numeric grid, ``heatmap.png``. A rerun skips the variants done before. Exit 0 when every
variant succeeded, 1 when any failed (they are listed), 2 for a bad sweep file (nothing written).
"""
from __future__ import annotations

import os
import re
import socket
import sys

import click

from inflo.formats.errors import InputError
from inflo.tools.common.cli import inflo_command, one_line

from .spec import read_sweep
from .sweep import check_copies, check_runnable, run_sweep


@inflo_command("inflo-sweep", help="Run the variants of SWEEP.toml (a pipeline or CLI stages over a grid or random "
                                    "samples of parameters) as Dask tasks; results.csv, contact sheet, heat map.")
@click.argument("sweep_file", metavar="SWEEP.toml", type=click.Path())
@click.option("-o", "--output", "output", required=True, type=click.Path(), help="Output folder (OUT_DIR).")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="A running Dask scheduler (tcp://HOST:8786); default: a LocalCluster on this machine.")
@click.option("--workers", type=click.IntRange(min=1, max=1024), default=None, metavar="N",
              help="LocalCluster: N worker processes (default: the CPU count; at most 8 per CPU); with --scheduler: "
                   "wait for N workers.")
@click.option("--force", is_flag=True, help="Run every variant again, done or not (make still skips what is up to date).")
@click.option("--dry-run", is_flag=True, help="Write the variants' inputs and list what would run; run nothing.")
@click.option("--dashboard", default=":8787", show_default=True, metavar="ADDRESS",
              help="LocalCluster: the dashboard's address (':0': any free port).")
def main(sweep_file, output, scheduler, workers, force, dry_run, dashboard, quiet, debug):
    sweep = read_sweep(sweep_file)
    check_runnable(sweep)
    _refuse_output_inside_inputs(sweep, sweep_file, output)
    check_copies(sweep)
    if not _DASHBOARD.fullmatch(dashboard.strip()) or int(dashboard.rsplit(":", 1)[-1]) > 65535:
        raise InputError(f"--dashboard: expected an address [HOST]:PORT (port 0..65535), found {dashboard!r}")
    if scheduler is not None:
        _check_scheduler(scheduler, connect=not dry_run)
    elif workers is not None and workers > local_worker_limit():
        raise InputError(f"--workers: expected at most {local_worker_limit()} worker processes on this machine "
                         f"(8 per CPU), found {workers}")

    def echo(msg):
        click.echo(msg, err=True)

    summary = run_sweep(sweep, output, scheduler=scheduler, workers=workers, quiet=quiet, force=force,
                        dry_run=dry_run, dashboard=dashboard, echo=echo)
    if dry_run:
        return
    fails = summary.failures
    if not quiet:
        ok = len(summary.results) - len(fails)
        echo(f"inflo-sweep: {ok} of {len(summary.results)} variants ok ({summary.ran} run, {summary.cached} done before)"
             + "".join(f"; wrote {p}" for p in summary.paths))
    if fails:
        echo(f"inflo-sweep: {len(fails)} of {len(summary.results)} variants failed:")
        for r in fails:
            label = one_line(", ".join(f"{k}={v}" for k, v in r["params"]))
            echo(f"  {r['id']} ({label}): {one_line(r['error'])} (exit {r['exit_code']})")
        sys.exit(1)


def local_worker_limit() -> int:
    """The most LocalCluster worker processes: 8 per CPU, at least 16."""
    return max(16, 8 * (os.cpu_count() or 1))


_ADDRESS = re.compile(r"(?:(?P<scheme>tcp|tls|ws|wss|ucx)://)?(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+)"
                      r":(?P<port>[0-9]{1,5})/?")


_DASHBOARD = re.compile(r"(?:(?:[A-Za-z0-9_.-]+|\[[0-9A-Fa-f:.]+\])?:)?[0-9]{1,5}")


def _check_scheduler(address: str, *, connect: bool = True, timeout: float = 10.0) -> None:
    """Bad input (one line, before anything is written) when ``--scheduler`` is no address of the
    form ``[tcp://]HOST:PORT`` (port 1..65535, an IPv4 host's numbers 0..255), or, with
    ``connect``, nothing accepts a connection there within ``timeout`` seconds."""
    m = _ADDRESS.fullmatch(address.strip())
    host = m.group("host").strip("[]") if m else ""
    port = int(m.group("port")) if m else 0
    ipv4 = re.fullmatch(r"[0-9.]+", host) is not None
    if not m or not 1 <= port <= 65535 or (ipv4 and not (
            len(host.split(".")) == 4 and all(p.isdigit() and int(p) <= 255 for p in host.split(".")))):
        raise InputError(f"--scheduler: expected a Dask scheduler address [tcp://]HOST:PORT (port 1..65535), "
                         f"found {address!r}")
    if not connect:
        return
    try:
        with socket.create_connection((host, port), timeout=timeout):
            pass
    except socket.gaierror:
        raise InputError(f"--scheduler: expected a Dask scheduler at {address}, found no host {host!r}") from None
    except OSError as exc:
        why = "no answer" if isinstance(exc, TimeoutError) else (exc.strerror or type(exc).__name__).lower()
        raise InputError(f"--scheduler: expected a Dask scheduler listening at {address}, found {why}") from None


def _refuse_output_inside_inputs(sweep, sweep_file, output) -> None:
    """Bad input (one line) when OUT_DIR lies inside a folder every variant copies (the pipeline
    folder or an input folder): each variant would copy the earlier variants' folders, growing the
    disk used with every run; or when it holds the sweep file or an input where the sweep writes
    (results.csv, contact_sheet.png, heatmap.png, variants/)."""
    from pathlib import Path

    from inflo.formats.atomic import check_output_path, refuse_output_over_inputs

    out = Path(os.path.realpath(output))
    copied = [sweep.pipeline.path] if sweep.pipeline is not None else [sweep.folder / rel for rel in sweep.inputs]
    for src in copied:
        real = Path(os.path.realpath(src))
        if real.is_dir() and (out == real or real in out.parents):
            raise InputError(f"{sweep_file}: expected an output folder outside the folders each variant copies, "
                             f"found -o {output} inside {src}")
    check_output_path(output, folder=True)
    written = ("results.csv", "contact_sheet.png", "heatmap.png")
    read = [(sweep.path, "sweep file")] + [(src, "input") for src in copied]
    refuse_output_over_inputs(output, read, folder=True,
                              writes=lambda rel: rel in written or rel == "variants" or rel.startswith("variants/"))
