"""The species that have goldens: their manifests, builds, checks and refreshes.

A species has goldens when ``tests/golden/<species>/manifest.toml`` exists: it names the pipeline,
the make targets and quality, and which files of ``build/<species>/`` are golden (first, middle and
last frame of each sequence, small files), which are kept gzip-compressed and with what
tolerances. :func:`refresh_species` copies them to ``tests/golden/<species>/<same path>`` and
writes ``listing.toml`` (every file name of each golden sequence, so a frame that goes missing or
appears is reported even when it is not one of the golden frames); :func:`check_species` compares
a build with them through :mod:`inflo.tools.golden.compare`. Doc: ``tests/golden/README.md``.
"""
from __future__ import annotations

import gzip
import json
import os
import shutil
import subprocess
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

from .compare import CHAOTIC, DEFAULT, GZ, FileDiff, Finding, Tolerance, diff_files, natural_key, shorten, tree_files

__all__ = [
    "Entry",
    "Species",
    "find_repo",
    "golden_root",
    "species_with_manifest",
    "load_species",
    "make_env",
    "make_command",
    "build_species",
    "check_listing",
    "check_species",
    "refresh_species",
    "relative",
    "COMMAND",
    "MANIFEST",
    "LISTING",
    "SIZE_LIMIT",
]

COMMAND = "python -m inflo.tools.golden"
"""How the golden CLI is run (named in hints)."""
_LISTING_COMMAND = "python -m inflo.tools.common.golden"
"""The command named in the header of the committed ``listing.toml`` files, kept so that a refresh
rewrites them byte for byte (that old name still runs: a shim forwarding to :data:`COMMAND`)."""

SIZE_LIMIT = 5 * 1024 * 1024
"""Golden text per species (bytes) above which refresh warns."""

MANIFEST = "manifest.toml"
LISTING = "listing.toml"
_RESERVED = {MANIFEST, LISTING, "README.md"}


def gzip_copy(src: Path, dst: Path) -> None:
    """``src`` gzip-compressed to ``dst`` with no name or time in the header, so the same file
    always gives the same bytes (no spurious change in git after a refresh)."""
    with open(src, "rb") as fh, open(dst, "wb") as raw:
        with gzip.GzipFile(filename="", mode="wb", fileobj=raw, mtime=0, compresslevel=9) as gz:
            shutil.copyfileobj(fh, gz)


def find_repo(start=None) -> Path:
    """The repository root: $INFLO_REPO, else the first folder above this file or ``start`` (the
    working directory) that has ``pipelines/`` and ``tests/``."""
    env = os.environ.get("INFLO_REPO")
    if env:
        return Path(env).resolve()
    for base in (Path(__file__).resolve(), Path(start or os.getcwd()).resolve()):
        for p in (base, *base.parents):
            if (p / "pipelines").is_dir() and (p / "tests").is_dir():
                return p
    raise SystemExit("golden: cannot find the repository root (set INFLO_REPO)")


def golden_root(repo) -> Path:
    """``tests/golden`` of the repository ``repo``."""
    return Path(repo) / "tests" / "golden"


def species_with_manifest(repo) -> list[str]:
    """Species that have ``tests/golden/<species>/manifest.toml``, sorted."""
    root = golden_root(repo)
    if not root.is_dir():
        return []
    return sorted(p.parent.name for p in root.glob(f"*/{MANIFEST}"))


@dataclass
class Entry:
    """One ``[[golden]]`` table: a file or a glob under the build folder, which of its matches
    are golden, and comparison options."""

    files: str
    pick: list | None
    tolerance: Tolerance
    options: dict
    compress: bool = False
    """keep the golden copies gzip-compressed (``name.gz``): for large frames"""

    @property
    def is_glob(self) -> bool:
        return any(c in self.files for c in "*?[")

    def select(self, names: list[str]) -> list[str]:
        """The golden names among ``names`` (the sequence in natural order)."""
        if not self.is_glob:
            return [self.files]
        if not names:
            return []
        if self.pick is None or self.pick == "all":
            return list(names)
        out = []
        for p in self.pick:
            if p == "first":
                k = 0
            elif p == "middle":
                k = (len(names) - 1) // 2
            elif p == "last":
                k = len(names) - 1
            elif isinstance(p, int):
                if not -len(names) <= p < len(names):
                    continue
                k = p
            else:  # a file name in the sequence
                hit = [n for n in names if n.rsplit("/", 1)[-1] == p]
                if not hit:
                    continue
                k = names.index(hit[0])
            if names[k] not in out:
                out.append(names[k])
        return out


@dataclass
class Species:
    name: str
    repo: Path
    pipeline: Path
    build: Path
    golden: Path
    targets: list
    quality: str
    entries: list
    size_limit: int

    def listing_path(self) -> Path:
        return self.golden / LISTING

    def golden_path(self, name: str) -> Path:
        """Where the golden copy of build file ``name`` is: ``name``, or ``name.gz`` when it is
        kept compressed (the plain one when neither exists)."""
        plain = self.golden / name
        if not plain.is_file() and (self.golden / (name + GZ)).is_file():
            return self.golden / (name + GZ)
        return plain

    def build_listing(self, build: Path | None = None) -> dict:
        """pattern -> file names (relative to the build folder, natural order) for each glob entry."""
        root = build or self.build
        out = {}
        for e in self.entries:
            if e.is_glob:
                out[e.files] = sorted((p.relative_to(root).as_posix() for p in root.glob(e.files)
                                       if p.is_file() and not p.name.startswith(".")), key=natural_key)
        return out

    def golden_listing(self) -> dict | None:
        """The listing written by the last refresh, or None before the first."""
        p = self.listing_path()
        if not p.is_file():
            return None
        with open(p, "rb") as fh:
            data = tomllib.load(fh)
        return {k: list(v.get("files", [])) for k, v in data.get("sequence", {}).items()}

    def selection(self, listing: dict) -> list[tuple[str, Entry]]:
        """(relative path, entry) of every golden file, resolved against ``listing``."""
        out, seen = [], set()
        for e in self.entries:
            for name in e.select(listing.get(e.files, [])):
                if name not in seen:
                    seen.add(name)
                    out.append((name, e))
        return out


def load_species(name: str, repo=None) -> Species:
    """Read ``tests/golden/<name>/manifest.toml`` (see tests/golden/README.md)."""
    repo = Path(repo) if repo else find_repo()
    gdir = golden_root(repo) / name
    path = gdir / MANIFEST
    if not path.is_file():
        raise ValueError(f"no golden manifest for {name!r}: {path} does not exist")
    with open(path, "rb") as fh:
        try:
            m = tomllib.load(fh)
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"{path}: {exc}") from None
    known = {"pipeline", "build", "targets", "quality", "tolerance", "golden", "size_limit_mb"}
    bad = sorted(set(m) - known)
    if bad:
        raise ValueError(f"{path}: unknown key(s) {', '.join(bad)}; known: {', '.join(sorted(known))}")
    base_tol = DEFAULT.updated(m.get("tolerance"))
    entries = []
    for k, t in enumerate(m.get("golden", [])):
        if "files" not in t:
            raise ValueError(f"{path}: [[golden]] table {k + 1} has no 'files'")
        t = dict(t)
        files = t.pop("files")
        pick = t.pop("pick", None)
        if isinstance(pick, str) and pick != "all":
            pick = [pick]
        chaotic = t.pop("chaotic", False)
        compress = t.pop("compress", False)
        for key, value in (("chaotic", chaotic), ("compress", compress)):
            if not isinstance(value, bool):
                raise ValueError(f"{path}: [[golden]] table {k + 1}: {key} must be true or false, found {value!r}")
        # a chaotic stage (fccompose's crowded frames and what follows them) starts from CHAOTIC
        tol = (CHAOTIC if chaotic else base_tol).updated(t.pop("tolerance", None))
        entries.append(Entry(files, pick, tol, t, compress))
    if not entries:
        raise ValueError(f"{path}: no [[golden]] tables")
    return Species(
        name=name,
        repo=repo,
        pipeline=repo / m.get("pipeline", f"pipelines/{name}"),
        build=repo / m.get("build", f"build/{name}"),
        golden=gdir,
        targets=list(m.get("targets", [])),
        quality=str(m.get("quality", "draft")),
        entries=entries,
        size_limit=int(float(m.get("size_limit_mb", SIZE_LIMIT / 2**20)) * 2**20),
    )


def make_env(base=None) -> dict:
    """The environment for ``make``: the tools of the running interpreter's environment first on
    PATH (so the pipeline finds them whether pytest was started by ``make test``, as
    ``.venv/bin/pytest`` or otherwise), and no variables inherited from an enclosing make (its
    jobserver, MAKEFLAGS overrides, QUALITY)."""
    env = dict(os.environ if base is None else base)
    for k in ("MAKEFLAGS", "MFLAGS", "MAKELEVEL", "MAKEOVERRIDES", "MAKE_TERMOUT", "MAKE_TERMERR", "QUALITY"):
        env.pop(k, None)
    bindir = str(Path(sys.executable).parent)
    env["PATH"] = bindir + os.pathsep + env.get("PATH", "")
    return env


def make_command(spec: Species, rebuild: bool = False) -> list[str]:
    """``make -C <pipeline> QUALITY=<quality> [-B] <targets>``."""
    make = shutil.which("make") or "make"
    return [make, "-C", str(spec.pipeline), f"QUALITY={spec.quality}", *(["-B"] if rebuild else []),
            *spec.targets]


def build_species(spec: Species, rebuild: bool = False, stream: bool = False) -> subprocess.CompletedProcess:
    """Run the species' make targets at the manifest's quality (``rebuild``: ``make -B``, since
    make does not see changes to the tools' code). Output captured unless ``stream``."""
    cmd = make_command(spec, rebuild)
    if not (spec.pipeline / "Makefile").is_file():
        return subprocess.CompletedProcess(cmd, 2, "", f"no pipeline Makefile at {spec.pipeline}\n")
    kw = {} if stream else dict(capture_output=True, text=True)
    return subprocess.run(cmd, env=make_env(), cwd=spec.repo, **kw)


def relative(path: Path, repo: Path) -> str:
    """``path`` relative to ``repo`` (POSIX), or as it is when it lies outside."""
    try:
        return path.relative_to(repo).as_posix()
    except ValueError:
        return str(path)


def check_listing(spec: Species, pattern: str, golden_names: list[str], build: Path | None = None) -> list[FileDiff]:
    """Missing and extra files of one golden sequence (the whole listing, not only golden frames)."""
    root = build or spec.build
    found = spec.build_listing(root).get(pattern, [])
    fs, gs = set(found), set(golden_names)
    out = []
    for n in golden_names:
        if n not in fs:
            d = FileDiff(n, "missing")
            d.findings.append(Finding(f"missing file (the golden sequence {pattern} has {len(golden_names)} "
                                      f"files, {relative(root, spec.repo)} has {len(found)})"))
            out.append(d)
    for n in found:
        if n not in gs:
            d = FileDiff(n, "extra")
            d.findings.append(Finding(f"extra file (not in the golden sequence {pattern}, "
                                      f"{len(golden_names)} files)"))
            out.append(d)
    return out


def check_species(spec: Species, build: Path | None = None) -> list[FileDiff]:
    """Every golden file of ``spec`` against the build folder (no make), and the sequences'
    listings; one FileDiff per file."""
    root = build or spec.build
    listing = spec.golden_listing()
    if listing is None:
        d = FileDiff(f"{relative(spec.golden, spec.repo)}/{LISTING}", "no golden")
        d.findings.append(Finding(f"no goldens yet: run {COMMAND} refresh {spec.name}"))
        return [d]
    out = []
    for pattern, names in listing.items():
        out.extend(check_listing(spec, pattern, names, root))
    reported = {d.name for d in out if d.status == "missing"}
    for name, e in spec.selection(listing):
        if name in reported:
            continue
        out.append(diff_files(spec.golden_path(name), root / name, name, e.tolerance, e.options))
    return out


def _golden_files(spec: Species) -> list[str]:
    return [n for n in tree_files(spec.golden) if n not in _RESERVED]


def _write_listing(spec: Species, listing: dict) -> None:
    lines = [f"# Written by `{_LISTING_COMMAND} refresh {spec.name}`: every file of each",
             "# golden sequence in the build the goldens were copied from (missing/extra frames are reported).",
             ""]
    for pattern, names in listing.items():
        lines.append(f"[sequence.{json.dumps(pattern)}]")
        lines.append(f"count = {len(names)}")
        lines.append("files = [")
        lines.extend(f"  {json.dumps(n)}," for n in names)
        lines.append("]")
        lines.append("")
    tmp = spec.listing_path().with_suffix(".part")
    tmp.write_text("\n".join(lines))
    os.replace(tmp, spec.listing_path())


def refresh_species(spec: Species, out=print) -> int:
    """Copy the manifest's files from the build folder into tests/golden/<species>/ (no make),
    rewrite listing.toml, remove golden files no longer selected; print what changed. Returns 0,
    or 1 when a selected file is missing from the build."""
    listing = spec.build_listing()
    selection = spec.selection(listing)
    missing = [n for n, _ in selection if not (spec.build / n).is_file()]
    empty = [p for p, names in listing.items() if not names]
    if missing or empty:
        for n in missing:
            out(f"  {n}: missing from {relative(spec.build, spec.repo)}")
        for p in empty:
            out(f"  {p}: no file matches in {relative(spec.build, spec.repo)}")
        out(f"golden {spec.name}: not refreshed (the build is incomplete)")
        return 1
    old_listing = spec.golden_listing() or {}
    before = set(_golden_files(spec))
    changed = 0
    stored = set()
    for name, e in selection:
        src, dst = spec.build / name, spec.golden / (name + GZ if e.compress else name)
        stored.add(dst.relative_to(spec.golden).as_posix())
        if dst.is_file():
            d = diff_files(dst, src, name, e.tolerance, e.options)
            if d.status == "same":
                continue
            first = d.findings[0].summary if d.findings else (d.notes[0] if d.notes else "")
            word = "changed within tolerance" if d.ok else "changed"
            out(f"  {name}: {word}{': ' + first if first else ''}")
        else:
            out(f"  {name}: new")
        changed += 1
        dst.parent.mkdir(parents=True, exist_ok=True)
        if e.compress:
            gzip_copy(src, dst)
        else:
            shutil.copyfile(src, dst)
    selected = {n for n, _ in selection}
    for name in sorted(before - stored, key=natural_key):
        (spec.golden / name).unlink()
        out(f"  {name}: removed (no longer selected)")
        changed += 1
    for p in sorted(spec.golden.rglob("*"), reverse=True):  # folders left empty
        if p.is_dir() and not any(p.iterdir()):
            p.rmdir()
    for pattern, names in listing.items():
        old = old_listing.get(pattern)
        if old is None:
            out(f"  {pattern}: {len(names)} files listed")
        elif old != names:
            gone, new = sorted(set(old) - set(names)), sorted(set(names) - set(old))
            out(f"  {pattern}: {len(old)} -> {len(names)} files"
                + (f"; gone {shorten(', '.join(gone))}" if gone else "")
                + (f"; new {shorten(', '.join(new))}" if new else ""))
    _write_listing(spec, listing)
    size = sum((spec.golden / n).stat().st_size for n in _golden_files(spec))
    out(f"golden {spec.name}: {len(selected)} files, {size / 2**20:.2f} MB in {relative(spec.golden, spec.repo)}; "
        f"{changed or 'nothing'} changed")
    if size > spec.size_limit:
        out(f"golden {spec.name}: warning: over {spec.size_limit / 2**20:.0f} MB; pick fewer frames in {MANIFEST}")
    return 0
