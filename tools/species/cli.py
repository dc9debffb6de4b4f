"""``python -m inflo.tools.species list [PIPELINES]``, ``... vars SPECIES.toml --quality Q -o OUT`` and
``... new NAME --from SPECIES [--title TITLE]`` (``make new-species``, :mod:`.scaffold`).

Plain argparse and the standard library only: ``make`` runs ``vars`` each time it reads a species
Makefile (about 0.05 s).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from inflo.formats.errors import InputError
from inflo.formats.species import find_species, read_species, write_make_variables

ROOT = Path(__file__).resolve().parents[2]


def _list(pipelines: Path) -> int:
    found = find_species(pipelines)
    width = max((len(s.name) for s in found), default=0)
    for s in found:
        figs = f" (thesis figs. {', '.join(s.figures)})" if s.figures else ""
        print(f"{s.name:<{width}}  {s.title}{figs}; {s.family}; make {s.name}")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m inflo.tools.species", description=__doc__)
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("list", help="every species, one line each")
    p.add_argument("pipelines", nargs="?", default=str(ROOT / "pipelines"))
    p = sub.add_parser("vars", help="a species' settings at a quality as make assignments")
    p.add_argument("species_toml")
    p.add_argument("--quality", required=True)
    p.add_argument("-o", dest="out", required=True)
    p = sub.add_parser("new", help="a new species folder from an existing one")
    p.add_argument("name")
    p.add_argument("--from", dest="source", required=True)
    p.add_argument("--title", default=None)
    p.add_argument("--repo", default=None, help="the project folder (default: the current one, if it has pipelines/)")
    args = ap.parse_args(argv)
    try:
        if args.command == "list":
            return _list(Path(args.pipelines))
        if args.command == "new":
            from .scaffold import scaffold

            repo = Path(args.repo) if args.repo else (Path.cwd() if (Path.cwd() / "pipelines").is_dir() else ROOT)
            files = scaffold(repo, args.name, args.source, args.title)
            print(f"pipelines/{args.name}/ from pipelines/{args.source}/: {len(files)} files; build it with "
                  f"`make {args.name}`, record its goldens with `python -m inflo.tools.golden refresh {args.name}`")
            return 0
        write_make_variables(read_species(args.species_toml), args.quality, args.out)
        return 0
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
