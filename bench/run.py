"""Run every benchmark: ``python -m bench.run [-k SUBSTRING] [--quick] [--no-csv]``."""
from __future__ import annotations

import argparse
import importlib
import sys
import traceback

from .harness import BENCH_DIR, BenchContext, Result, append_results, machine_description


def discover(pattern: str | None):
    for path in sorted(BENCH_DIR.glob("bench_*.py")):
        module = importlib.import_module(f"bench.{path.stem}")
        for fn in getattr(module, "BENCHMARKS", []):
            name = f"{path.stem}.{fn.__name__}"
            if pattern is None or pattern in name:
                yield name, fn


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("-k", dest="pattern", help="run only benchmarks whose name contains this")
    ap.add_argument("--quick", action="store_true", help="smaller workloads (smoke run)")
    ap.add_argument("--no-csv", action="store_true", help="do not append to bench/results.csv")
    args = ap.parse_args(argv)
    print(f"machine: {machine_description()}", flush=True)
    failed = 0
    for name, fn in discover(args.pattern):
        workdir = BENCH_DIR / "out" / name
        workdir.mkdir(parents=True, exist_ok=True)
        try:
            out = fn(BenchContext(workdir=workdir, quick=args.quick))
        except Exception:
            failed += 1
            print(f"{name}: FAILED", flush=True)
            traceback.print_exc()
            continue
        results = out if isinstance(out, list) else [out]
        for r in results:
            assert isinstance(r, Result), f"{name} returned {type(r).__name__}, expected Result"
            print(r.line(), flush=True)
        if not args.no_csv:
            append_results(results)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
