"""The benchmark harness: what a workload returns and how it is reported.

A benchmark module is ``bench/bench_<topic>.py`` defining ``BENCHMARKS``, a list of functions
``fn(ctx: BenchContext) -> Result | list[Result]``. ``python -m bench.run`` imports every such
module, runs each function, prints one line per result::

    render_400k_triangles: 1.23 s (anchor: 10 s goal; ratio: 0.12)

and appends a row per result to ``bench/results.csv`` (date, machine, commit, name, value, unit,
anchor, ratio, note). ``ratio`` is value / anchor_value in the anchor's unit (below 1 is faster
than the anchor for times).
"""
from __future__ import annotations

import csv
import datetime as _dt
import os
import platform
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

BENCH_DIR = Path(__file__).resolve().parent
REPO = BENCH_DIR.parent
RESULTS_CSV = BENCH_DIR / "results.csv"
CSV_FIELDS = ["date", "machine", "commit", "name", "value", "unit", "anchor", "anchor_value", "ratio", "note"]


@dataclass
class Result:
    """One measured figure.

    name : str            e.g. ``render_400k_triangles``
    value : float         the figure, in ``unit``
    unit : str            ``s``, ``min``, ``queries/s``...
    anchor : str          what it is compared with, in words (docs/architecture.md anchors or an issue goal)
    anchor_value : float  the anchor in the same unit (None when there is no number to divide by)
    note : str            anything a reader needs (sizes, counts)
    """

    name: str
    value: float
    unit: str
    anchor: str = ""
    anchor_value: float | None = None
    note: str = ""

    @property
    def ratio(self) -> float | None:
        if self.anchor_value in (None, 0):
            return None
        return self.value / self.anchor_value

    def line(self) -> str:
        ratio = "n/a" if self.ratio is None else f"{self.ratio:.3g}"
        anchor = self.anchor or "none"
        text = f"{self.name}: {self.value:.4g} {self.unit} (anchor: {anchor}; ratio: {ratio})"
        return text + (f"  [{self.note}]" if self.note else "")


@dataclass
class BenchContext:
    """What a benchmark may use: a scratch folder (kept under bench/out/) and a timer."""

    workdir: Path
    quick: bool = False
    extra: dict = field(default_factory=dict)

    @staticmethod
    def timed(fn, *args, repeat: int = 1, **kwargs) -> tuple[float, object]:
        """Best wall time of ``repeat`` calls of ``fn`` (seconds) and the last return value."""
        best, out = float("inf"), None
        for _ in range(repeat):
            t0 = time.perf_counter()
            out = fn(*args, **kwargs)
            best = min(best, time.perf_counter() - t0)
        return best, out


def machine_description() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{platform.node()} {cpu} x{os.cpu_count()}"


def git_commit() -> str:
    try:
        sha = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True,
                             text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=REPO,
                               capture_output=True, text=True).stdout.strip()
        return sha + ("-dirty" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def append_results(results: list[Result], path: Path = RESULTS_CSV) -> None:
    new = not path.exists()
    date = _dt.datetime.now().isoformat(timespec="seconds")
    machine, commit = machine_description(), git_commit()
    with open(path, "a", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=CSV_FIELDS)
        if new:
            w.writeheader()
        for r in results:
            w.writerow({
                "date": date, "machine": machine, "commit": commit, "name": r.name,
                "value": f"{r.value:.6g}", "unit": r.unit, "anchor": r.anchor,
                "anchor_value": "" if r.anchor_value is None else f"{r.anchor_value:.6g}",
                "ratio": "" if r.ratio is None else f"{r.ratio:.6g}", "note": r.note,
            })
