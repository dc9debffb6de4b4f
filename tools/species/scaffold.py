"""``make new-species NAME=x FROM=y``: a new species folder from an existing one.

Copies ``pipelines/<y>/`` to ``pipelines/<x>/`` (not its pictures in ``docs/`` nor caches), renames
the files named after y (``y.fcc`` -> ``x.fcc``, ``check_y.py`` -> ``check_x.py``), writes x for
the word y in its text files (the build folder ``build/y/`` the .fcc names, the Makefile's, the
check's) and sets ``name`` and ``title`` in its species.toml. It also writes
``tests/golden/<x>/manifest.toml`` from y's (new files only: nothing of y or elsewhere is edited).
Then ``make x`` builds it and the tests pick it up; ``python -m inflo.tools.golden refresh x``
records its goldens. docs/new_species.md walks through one.
"""
from __future__ import annotations

import re
import shutil
from pathlib import Path

from inflo.formats.errors import InputError
from inflo.formats.species import read_species

__all__ = ["scaffold"]

TEXT_SUFFIXES = {".toml", ".fcc", ".py", ".md", ".func", ".fset", ".con", ".cset", ".scn", ".floret", ".mk", ".txt", ""}
"""suffixes of the files whose text is rewritten (``""``: the Makefile)"""

_NAME = re.compile(r"[a-z][a-z0-9_]*")


def _rewrite(text: str, old: str, new: str) -> str:
    return re.sub(rf"(?<![A-Za-z0-9]){re.escape(old)}(?![A-Za-z0-9])", new, text)


def scaffold(repo, name: str, source: str, title: str | None = None) -> list[Path]:
    """Create ``pipelines/<name>/`` (and its golden manifest) from ``pipelines/<source>/``;
    returns the files written. Raises InputError for a bad or taken name or an unknown source."""
    repo = Path(repo)
    pipelines = repo / "pipelines"
    if not _NAME.fullmatch(name or ""):
        raise InputError(f"NAME: expected a lower-case name (letters, digits, _), found {name!r}")
    src = pipelines / source
    if not (src / "species.toml").is_file():
        known = ", ".join(sorted(p.parent.name for p in pipelines.glob("*/species.toml")))
        raise InputError(f"FROM: expected a species ({known}), found {source!r}")
    dst = pipelines / name
    if dst.exists():
        raise InputError(f"{dst}: the species folder exists already")
    old = read_species(src / "species.toml")
    written = []
    tmp = pipelines / f".{name}.tmp"
    shutil.rmtree(tmp, ignore_errors=True)
    try:
        shutil.copytree(src, tmp, ignore=shutil.ignore_patterns("__pycache__", "docs", "*.pyc"))
        for path in sorted(tmp.rglob("*"), key=lambda p: -len(p.parts)):
            if path.is_file() and path.suffix in TEXT_SUFFIXES:
                try:
                    text = path.read_text(encoding="utf-8")
                except UnicodeDecodeError:
                    text = None
                if text is not None:
                    path.write_text(_rewrite(text, source, name), encoding="utf-8")
            if source in path.name:
                path.rename(path.with_name(_rewrite(path.name, source, name)))
        toml = tmp / "species.toml"
        text = toml.read_text()
        text = re.sub(r'^title = "[^"\n]*"', f'title = "{title or name.replace("_", " ").capitalize()}"', text,
                      count=1, flags=re.M)
        text = re.sub(r"^# .* as data \(formats/species\.md\)\.$", f"# {title or name} as data (formats/species.md).", text,
                      count=1, flags=re.M)
        text = re.sub(r"^# scaffolded from [^\n]*\n", "", text, flags=re.M)
        text = text.replace("\nname = ", f"\n# scaffolded from {source} ({old.title}) by make new-species\nname = ", 1)
        toml.write_text(text)
        tmp.rename(dst)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    written += sorted(p for p in dst.rglob("*") if p.is_file())
    manifest = repo / "tests" / "golden" / source / "manifest.toml"
    if manifest.is_file():
        out = repo / "tests" / "golden" / name / "manifest.toml"
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(_rewrite(manifest.read_text(), source, name))
        written.append(out)
    read_species(dst / "species.toml")  # valid
    return written
