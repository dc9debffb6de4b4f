"""The golden command line (click)::

    python -m inflo.tools.golden check [SPECIES|all] [--rebuild]   # make (incremental) + diff + report
    python -m inflo.tools.golden refresh [SPECIES|all]             # make -B + copy the goldens in
    python -m inflo.tools.golden diff A B                          # two files or two folders

Exit codes: 0 no difference, 1 differences (or a failed build), 2 bad input.
"""
from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path

import click

from .compare import Tolerance, diff_files, diff_trees, format_report
from .species import (
    COMMAND,
    MANIFEST,
    Species,
    build_species,
    check_species,
    find_repo,
    load_species,
    make_command,
    refresh_species,
    relative,
    species_with_manifest,
)

__all__ = ["main"]

_CONTEXT = {"help_option_names": ["-h", "--help"]}


def _species_args(names, repo) -> list[str]:
    have = species_with_manifest(repo)
    if not names or names == ["all"]:
        return have
    bad = [n for n in names if n not in have]
    if bad:
        raise ValueError(f"no tests/golden/<species>/{MANIFEST} for {', '.join(bad)} (have: {', '.join(have) or 'none'})")
    return names


def _load(species, repo_option) -> tuple[Path, list[Species]]:
    """The repository and the named species (all by default); bad names exit with code 2, no
    species with goldens at all with code 0."""
    repo = repo_option.resolve() if repo_option else find_repo()
    try:
        names = _species_args(list(species), repo)
        specs = [load_species(n, repo) for n in names]
    except ValueError as exc:
        click.echo(f"golden: error: {exc}", err=True)
        sys.exit(2)
    if not specs:
        click.echo(f"golden: no species has tests/golden/<species>/{MANIFEST}")
        sys.exit(0)
    return repo, specs


def _build_or_report(spec: Species, rebuild: bool, verbose: bool) -> bool:
    cmd = make_command(spec, rebuild)
    click.echo(f"golden {spec.name}: {' '.join(Path(c).name if i == 0 else c for i, c in enumerate(cmd))}")
    t0 = time.monotonic()
    r = build_species(spec, rebuild=rebuild, stream=verbose)
    if r.returncode != 0:
        if not verbose:
            tail = ((r.stdout or "") + (r.stderr or "")).splitlines()[-30:]
            click.echo("\n".join("  | " + line for line in tail))
        click.echo(f"golden {spec.name}: the build failed (make exit {r.returncode})")
        return False
    click.echo(f"golden {spec.name}: built in {time.monotonic() - t0:.0f} s")
    return True


def _species_options(fn):
    """SPECIES..., --no-build, --verbose, --repo: what check and refresh share."""
    fn = click.option("--repo", type=click.Path(path_type=Path),
                      help="repository root (default: found from this file or the working folder)")(fn)
    fn = click.option("-v", "--verbose", is_flag=True, help="show make's output and every file's result")(fn)
    fn = click.option("--no-build", is_flag=True, help="use build/<species> as it is (no make)")(fn)
    fn = click.argument("species", nargs=-1)(fn)
    return fn


@click.group(context_settings=_CONTEXT, no_args_is_help=False,
             help="Golden stage outputs: check, refresh, or diff two files/folders (tests/golden/README.md).")
def main() -> None:
    pass


@main.command(context_settings=_CONTEXT, short_help="build (make, incremental) and compare with the goldens")
@_species_options
@click.option("--rebuild", is_flag=True, help="make -B: rebuild every stage (tool code changed)")
@click.option("--build-dir", type=click.Path(path_type=Path),
              help="compare this folder instead of build/<species> (no make)")
def check(species, no_build, verbose, repo, rebuild, build_dir) -> None:
    """Build (make, incremental) and compare with the goldens.

    SPECIES: species with tests/golden/<species>/manifest.toml, or all (the default).
    """
    repo, specs = _load(species, repo)
    build_dir = build_dir.resolve() if build_dir else None
    status = 0
    for spec in specs:
        if not (no_build or build_dir) and not _build_or_report(spec, rebuild, verbose):
            status = 1
            continue
        diffs = check_species(spec, build_dir)
        click.echo(format_report(diffs, f"golden {spec.name} ({relative(build_dir or spec.build, repo)} vs "
                                        f"{relative(spec.golden, repo)})", verbose))
        if not all(d.ok for d in diffs):
            status = 1
            click.echo(f"golden {spec.name}: if the change is intended: {COMMAND} refresh {spec.name}")
    sys.exit(status)


@main.command(context_settings=_CONTEXT,
              short_help="rebuild (make -B) and copy the golden files in, printing what changed")
@_species_options
@click.option("--incremental", is_flag=True, help="plain make instead of make -B")
def refresh(species, no_build, verbose, repo, incremental) -> None:
    """Rebuild (make -B) and copy the golden files in, printing what changed.

    SPECIES: species with tests/golden/<species>/manifest.toml, or all (the default).
    """
    repo, specs = _load(species, repo)
    status = 0
    for spec in specs:
        if not no_build and not _build_or_report(spec, not incremental, verbose):
            status = 1
            continue
        status = max(status, refresh_species(spec, out=click.echo))
    sys.exit(status)


def _tolerance_options(fn):
    """One --coord-rel, --coord-abs, ... option per field of :class:`Tolerance`."""
    for f in reversed(dataclasses.fields(Tolerance)):
        fn = click.option(f"--{f.name.replace('_', '-')}", f.name, type=float, default=f.default,
                          help=f"default {f.default:g}")(fn)
    return fn


@main.command(context_settings=_CONTEXT, short_help="compare two files, or two folders file by file")
@click.argument("golden", type=click.Path(path_type=Path))
@click.argument("found", type=click.Path(path_type=Path))
@click.option("-v", "--verbose", is_flag=True)
@_tolerance_options
def diff(golden, found, verbose, **tolerance) -> None:
    """Compare two files, or two folders file by file."""
    tol = Tolerance(**tolerance)
    if golden.is_dir() and found.is_dir():
        diffs = diff_trees(golden, found, tol)
    elif golden.is_dir() or found.is_dir():
        click.echo("golden: diff takes two files or two folders", err=True)
        sys.exit(2)
    else:
        diffs = [diff_files(golden, found, str(found), tol)]
    click.echo(format_report(diffs, f"{golden} vs {found}", verbose))
    sys.exit(0 if all(d.ok for d in diffs) else 1)
