"""Running a sweep on Dask distributed: a ``LocalCluster`` by default, or the scheduler
at an address (a real cluster: ``dask scheduler`` + ``dask worker``, dask-jobqueue on SLURM/PBS,
a Kubernetes deployment; inflo is the same).

The client prepares every variant's inputs (OUT_DIR must be on a file system the workers share),
skips the variants done before with the same inputs, and submits the others in batches, one Dask
task per batch (``[sweep] batch``; by default one variant per task for pipelines, and enough
variants per task for stage sweeps that each worker gets about four tasks). It prints the
dashboard link, shows a progress bar of variants done/failed with ETA, and at the end writes
``results.csv``, ``contact_sheet.png`` and, for a 2-D numeric grid, ``heatmap.png``.
"""
from __future__ import annotations

import math
import os
import shutil
import sys
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from pathlib import Path

from inflo.formats.atomic import output_lock
from inflo.formats.errors import InputError
from inflo.tools.common.cli import one_line, progress, stall_notice

from .overrides import check_placeholders
from .results import write_contact_sheet, write_heatmap, write_results_csv
from .spec import Sweep, variants
from .variant import cached_result, failed_result, prepare, run_batch, variant_dir

__all__ = ["SweepSummary", "check_runnable", "check_copies", "run_sweep", "auto_batch", "MAX_COPY_BYTES"]

#: the most bytes of input copies one sweep writes: its variants x the bytes each copies (the
#: pipeline folder or the inputs); 50 GB holds some 50,000 copies of a species pipeline
MAX_COPY_BYTES = 50_000_000_000


@dataclass
class SweepSummary:
    results: list[dict] = field(default_factory=list)
    ran: int = 0
    cached: int = 0
    dashboard: str | None = None
    paths: list[Path] = field(default_factory=list)

    @property
    def failures(self) -> list[dict]:
        return [r for r in sorted(self.results, key=lambda r: r["index"]) if r["status"] != "ok"]


def check_runnable(sweep: Sweep) -> None:
    """Before anything is written: placeholders known, every stage's CLI installed, make found."""
    check_placeholders(sweep)
    for st in sweep.stages:
        if st.subprocess:
            path = os.pathsep.join([os.path.dirname(sys.executable), os.environ.get("PATH", "")])
            if shutil.which(st.cli, path=path) is None:
                raise InputError(f"{sweep.path}: [[stage]] {st.name}: expected a command on PATH, found no {st.cli!r}")
        elif not list(entry_points(group="console_scripts", name=st.cli)):
            raise InputError(f"{sweep.path}: [[stage]] {st.name}: expected an installed console script, "
                             f"found no {st.cli!r}")
    if sweep.pipeline is not None and shutil.which(sweep.pipeline.make) is None:
        raise InputError(f"{sweep.path}: [pipeline] make: expected a command on PATH, found no "
                         f"{sweep.pipeline.make!r}")


def _copied_bytes(sweep: Sweep) -> int:
    """The bytes one variant copies: the pipeline folder's files or the inputs (as prepare copies them)."""
    srcs = [(sweep.pipeline.path, sweep.pipeline.path)] if sweep.pipeline is not None else \
        [(sweep.folder / rel, sweep.folder) for rel in sweep.inputs]
    total = 0
    for src, rel_to in srcs:
        for p in [src] if src.is_file() else sorted(src.rglob("*")):
            parts = p.relative_to(rel_to).parts
            if any(x in ("__pycache__", ".git") or x.startswith(".") for x in parts) or not p.is_file():
                continue
            total += p.stat().st_size
    return total


def check_copies(sweep: Sweep) -> None:
    """Bad input (one line, before anything is written) when the variants' copies of the inputs
    would exceed :data:`MAX_COPY_BYTES`."""
    n = sweep.samples if sweep.sampling == "random" else math.prod(len(a.values) for a in sweep.axes)
    size = _copied_bytes(sweep)
    if n * size > MAX_COPY_BYTES:
        raise InputError(f"{sweep.path}: expected variants x the bytes each copies within {MAX_COPY_BYTES:.3g} "
                         f"bytes, found {n} variants x {size} bytes = {n * size:.3g}")


def auto_batch(sweep: Sweep, pending: int, workers: int) -> int:
    """Variants per Dask task: ``[sweep] batch`` when given; 1 for pipelines (each is minutes);
    for stage sweeps about four tasks per worker, at most 200 variants a task."""
    if sweep.batch:
        return sweep.batch
    if sweep.pipeline is not None:
        return 1
    return max(1, min(200, math.ceil(pending / (4 * max(1, workers)))))


def _dashboard(client) -> str | None:
    try:
        services = client.scheduler_info().get("services", {})
    except Exception:
        return None
    return client.dashboard_link if "dashboard" in services else None


def run_sweep(sweep: Sweep, out_dir, *, scheduler: str | None = None, workers: int | None = None,
              quiet: bool = False, force: bool = False, dry_run: bool = False, dashboard: str = ":8787",
              echo=print) -> SweepSummary:
    """Run every variant not done before; return the results of all of them. A second sweep into
    the same OUT_DIR while this one runs is refused (one line)."""
    out_dir = Path(out_dir)
    allv = variants(sweep)
    with output_lock(out_dir, "inflo-sweep"):
        return _run_locked(sweep, out_dir, allv, scheduler=scheduler, workers=workers, quiet=quiet, force=force,
                           dry_run=dry_run, dashboard=dashboard, echo=echo)


def _run_locked(sweep, out_dir, allv, *, scheduler, workers, quiet, force, dry_run, dashboard, echo) -> SweepSummary:
    summary = SweepSummary()
    pending = []
    with stall_notice("inflo-sweep") as tick:  # a million variants take minutes to prepare: never silent
        for k, v in enumerate(allv):
            tick(k, len(allv), "variants prepared")
            try:
                fp = prepare(sweep, out_dir, v)
            except (InputError, OSError) as exc:
                summary.results.append(failed_result(v, f"inputs: {exc}", 2))
                continue
            res = None if force else cached_result(sweep, out_dir, v, fp)
            if res is not None:
                summary.results.append(res)
                summary.cached += 1
            else:
                pending.append((v, fp))
    if dry_run:
        for v, _ in pending:
            echo(f"inflo-sweep: would run {v.id} ({one_line(v.label()) or 'base'}) in {variant_dir(out_dir, v)}")
        echo(f"inflo-sweep: {len(allv)} variants, {summary.cached} done before, {len(pending)} to run")
        summary.results += [dict(failed_result(v, "not run (--dry-run)", 0), status="pending") for v, _ in pending]
        return summary
    if pending:
        _run_pending(sweep, out_dir, pending, summary, scheduler=scheduler, workers=workers, quiet=quiet,
                     dashboard=dashboard, echo=echo)
    csv_path = out_dir / "results.csv"
    write_results_csv(csv_path, sweep, summary.results)
    summary.paths.append(csv_path)
    if sweep.contact_sheet and write_contact_sheet(out_dir / "contact_sheet.png", out_dir, summary.results,
                                                   limit=sweep.contact_sheet):
        summary.paths.append(out_dir / "contact_sheet.png")
    if write_heatmap(out_dir / "heatmap.png", sweep, summary.results):
        summary.paths.append(out_dir / "heatmap.png")
    return summary


def _run_pending(sweep, out_dir, pending, summary, *, scheduler, workers, quiet, dashboard, echo):
    import warnings

    import dask
    from distributed import Client, LocalCluster, as_completed

    cluster = None
    with dask.config.set({"distributed.scheduler.allowed-failures": 1}):
        if scheduler:
            try:
                client = Client(scheduler, timeout="30s")
            except OSError as exc:
                raise InputError(f"--scheduler: expected a Dask scheduler at {scheduler}, found "
                                 f"{one_line(exc)}") from None
            if workers:
                client.wait_for_workers(workers, timeout=120)
        else:
            n = workers or max(1, min(len(pending), os.cpu_count() or 1))
            with warnings.catch_warnings():
                # the dashboard's port taken (another sweep): it takes another, and the link below says which
                warnings.filterwarnings("ignore", message=r"Port \d+ is already in use", category=UserWarning)
                cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                       dashboard_address=dashboard)
            client = Client(cluster)
    try:
        nworkers = sum(client.nthreads().values()) or 1
        batch = auto_batch(sweep, len(pending), nworkers)
        batches = [pending[i:i + batch] for i in range(0, len(pending), batch)]
        summary.dashboard = _dashboard(client)
        if not quiet:
            where = f"scheduler {scheduler}" if scheduler else f"a local cluster of {nworkers} workers"
            echo(f"inflo-sweep: {sweep.name}: {len(pending) + summary.cached} variants, {summary.cached} done before, "
                 f"{len(pending)} to run in {len(batches)} tasks on {where}")
            echo(f"inflo-sweep: dashboard: {summary.dashboard}" if summary.dashboard else
                 "inflo-sweep: dashboard: not served (install bokeh>=3.1 for the Dask dashboard)")
        futures = {}
        for k, items in enumerate(batches):
            f = client.submit(run_batch, sweep, str(out_dir), items, pure=False, retries=0,
                              key=f"inflo-sweep-{sweep.name}-{k}-{items[0][0].id}")
            futures[f] = items
        done = failed = 0
        with progress(length=len(pending), label="variants", quiet=quiet) as bar:
            for fut in as_completed(list(futures)):
                items = futures[fut]
                try:
                    results = fut.result()
                except Exception as exc:
                    results = [failed_result(v, f"worker lost the task: {type(exc).__name__}: {exc}".splitlines()[0],
                                             1) for v, _ in items]
                for r in results:
                    if r["status"] == "ok":
                        done += 1
                    else:
                        failed += 1
                summary.results += results
                summary.ran += len(results)
                if hasattr(bar, "label"):
                    bar.label = f"variants ({done} done, {failed} failed)"
                bar.update(len(results))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
