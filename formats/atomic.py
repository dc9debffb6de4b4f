"""Atomic output and file sequences (docs/architecture.md, "Atomic output" and "Sequences").

Writers never leave a half-written file under its final name: they write to a hidden temporary
file in the target folder and ``os.replace`` it into place only when the content is complete.
"""
from __future__ import annotations

import contextlib
import glob
import os
import re
import tempfile
from pathlib import Path

from .errors import InputError

__all__ = ["atomic_path", "atomic_write", "write_text_atomic", "write_bytes_atomic", "list_sequence", "frame_name",
           "remove_stale_frames", "refuse_output_over_inputs", "check_output_path", "output_lock",
           "staged_output", "own_stale", "read_manifest", "begin_sequence"]


@contextlib.contextmanager
def atomic_path(path):
    """A temporary file name beside ``path`` (hidden, ending ``.part``) for a writer that takes a
    file name rather than a file object (e.g. a USD layer's ``Save``); on success it is renamed to
    ``path`` (mode 0644), on error deleted. Parent folders are created."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    os.close(fd)
    try:
        yield tmp
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


@contextlib.contextmanager
def atomic_write(path, mode: str = "w", encoding: str | None = "utf-8"):
    """Open a temporary file beside ``path``; on success rename it to ``path``, on error delete it.

    ``mode`` is ``"w"`` (text, ``\\n`` line ends) or ``"wb"``. Parent folders are created.
    """
    with atomic_path(path) as tmp:
        if "b" in mode:
            fh = open(tmp, mode)
        else:
            fh = open(tmp, mode, encoding=encoding, newline="\n")
        with fh:
            yield fh


def write_text_atomic(path, text: str) -> None:
    """Write ``text`` to ``path`` atomically."""
    with atomic_write(path, "w") as fh:
        fh.write(text)


def write_bytes_atomic(path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically."""
    with atomic_write(path, "wb") as fh:
        fh.write(data)


def frame_name(index: int, prefix: str = "frame_", suffix: str = ".obj", digits: int = 4) -> str:
    """The file name of frame ``index`` in a sequence folder: ``frame_0007.obj``."""
    return f"{prefix}{index:0{digits}d}{suffix}"


_NUM = re.compile(r"(\d+)")


def _natural_key(p: str):
    return [int(t) if t.isdigit() else t for t in _NUM.split(os.path.basename(p))]


def list_sequence(source, suffix: str) -> list[Path]:
    """The files of a sequence, in frame order.

    ``source`` is a folder (every non-hidden ``*suffix`` file in it), a glob pattern, or a single
    file. Order is natural (``frame_2`` before ``frame_10``), which equals lexical order for the
    zero-padded names inflo writes. Raises :class:`InputError` when nothing matches.
    """
    source = os.fspath(source)
    if os.path.isdir(source):
        names = [
            os.path.join(source, n)
            for n in os.listdir(source)
            if n.endswith(suffix) and not n.startswith(".")
        ]
        if not names:
            raise InputError(f"{source}: no {suffix} files in this folder")
    elif os.path.isfile(source):
        names = [source]
    else:
        names = [n for n in glob.glob(source) if not os.path.basename(n).startswith(".")]
        if not names:
            raise InputError(f"{source}: no such file or folder, and no file matches it as a glob")
    return [Path(n) for n in sorted(names, key=_natural_key)]


_NUMBERED = re.compile(r"^(.*?)(\d+)(\.[^.]+)$")


def first_missing_frame(paths, *, start: int | None = None) -> str | None:
    """The name of the first frame missing from a numbered sequence (``frame_0003.obj`` between
    ``frame_0002.obj`` and ``frame_0004.obj``), or None when the numbers run without a gap.

    ``start``: the number the sequence must begin with (RBA files: 0, file NNNN is frame NNNN);
    None: any. Names that are not one prefix + digits + suffix (a glob of unrelated files) are not
    checked. File NNNN is frame NNNN, so a gap would re-time every later frame silently.
    """
    parsed = [_NUMBERED.match(Path(p).name) for p in paths]
    if not parsed or any(m is None for m in parsed):
        return None
    if len({(m.group(1), m.group(3)) for m in parsed}) != 1:
        return None
    nums = [int(m.group(2)) for m in parsed]
    width = len(parsed[0].group(2))
    prefix, suffix = parsed[0].group(1), parsed[0].group(3)
    expected = nums[0] if start is None else start
    for n in nums:
        if n != expected:
            return f"{prefix}{expected:0{width}d}{suffix}"
        expected += 1
    return None


def remove_stale_frames(folder, keep, suffix: str, prefix: str = "frame_") -> list[Path]:
    """Remove ``prefix<digits>suffix`` files in ``folder`` whose names are not in ``keep`` (paths or
    names): the frames of an earlier, longer run that this run did not write, so a sequence folder
    holds one run; and the hidden ``.part`` files a writer killed mid-frame left (a sequence folder
    has one writer at a time). Returns the removed paths."""
    names = {Path(k).name for k in keep}
    pat = re.compile(re.escape(prefix) + r"\d+" + re.escape(suffix) + "$")
    # a writer killed mid-write (SIGKILL: no cleanup) leaves its hidden temporary file
    # (:func:`atomic_path`): one run writes a sequence folder, so such files are the dead one's
    part = re.compile(r"\." + re.escape(prefix) + r"\d+" + re.escape(suffix) + r"\..+\.part$")
    removed = []
    for p in sorted(Path(folder).iterdir()):
        if (pat.match(p.name) and p.name not in names) or part.match(p.name):
            p.unlink()
            removed.append(p)
    return removed


# ---------------------------------------------------------------------------------------------
# outputs that never eat inputs, reruns that never mix, one writer per folder

MANIFEST_PREFIX = ".inflo-"


def _real(p) -> Path:
    return Path(os.path.realpath(os.fspath(p)))


def refuse_output_over_inputs(output, inputs, *, folder: bool = True, option: str = "-o", writes=None) -> None:
    """Bad input (:class:`InputError`, one line) when ``output`` would delete or overwrite an input.

    ``inputs``: paths, or ``(path, label)`` pairs (every input, weight, map and key pose the run
    reads). Real paths are compared (links and ``..`` resolved): a file output must not be an
    input; a folder output (``folder=True``) must be none of them and hold none of them, since a
    sequence writer replaces or removes the frame files in its folder. ``writes``: when given, a
    test of a path relative to the folder (is it a file this run writes or may remove?); only such
    inputs in the folder are refused. Call it before the first write."""
    out = _real(output)
    for item in inputs:
        path, label = item if isinstance(item, tuple) else (item, "input")
        if path is None:
            continue
        p = _real(path)
        inside = folder and out in p.parents and (writes is None or writes(p.relative_to(out).as_posix()))
        if p == out or inside:
            how = "is" if p == out else "holds"
            raise InputError(f"{output}: expected an output that is no input, found {option} {output} that {how} "
                             f"the {label} {path}")


def check_output_path(output, *, folder: bool) -> None:
    """Bad input (one line) when ``output`` cannot be written: a folder output that is a file, a
    file output that is a folder, or a parent that is a file. Checked before any work."""
    out = Path(output)
    if folder and out.exists() and not out.is_dir():
        raise InputError(f"{output}: expected an output folder, found a file")
    if not folder and out.is_dir():
        raise InputError(f"{output}: expected an output file, found a folder")
    for parent in (out.parent, *out.parent.parents):
        if parent.exists():
            if not parent.is_dir():
                raise InputError(f"{output}: expected an output path whose parents are folders, found the file {parent}")
            if not os.access(parent, os.W_OK | os.X_OK):
                raise InputError(f"{output}: expected an output path that can be written, found {parent} not writable")
            break


@contextlib.contextmanager
def output_lock(folder, tool: str):
    """Hold a lock on ``folder`` (the kernel's ``flock`` on the folder itself: no file is made, and a
    killed run releases it) while a run writes it; a second run into the same folder is refused
    (one line) instead of interleaving its frames with the first's."""
    import fcntl

    folder = Path(folder)
    existed = folder.is_dir()
    folder.mkdir(parents=True, exist_ok=True)
    fd = os.open(folder, os.O_RDONLY)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise InputError(f"{folder}: expected an output folder no other run is writing, found another "
                             f"run writing it now") from None
        yield folder
    except BaseException:
        if not existed:  # a run that failed before writing leaves no folder behind
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise
    finally:
        os.close(fd)


def _manifest(folder: Path, tool: str) -> Path:
    return folder / f"{MANIFEST_PREFIX}{tool}.manifest"


def read_manifest(folder, tool: str) -> list[str] | None:
    """The files (relative to ``folder``) ``tool``'s last complete run wrote there, or None."""
    try:
        text = _manifest(Path(folder), tool).read_text(encoding="utf-8")
    except OSError:
        return None
    return [ln for ln in text.splitlines() if ln and not ln.startswith("#")]


def own_stale(folder, tool: str, stale_patterns=()) -> list[Path]:
    """Files of ``folder`` that are ``tool``'s own earlier output: those its manifest lists or, for
    a folder written before manifests existed (none there), names matching ``stale_patterns``
    (regular expressions over the path relative to ``folder``, e.g. ``frame_\\d+\\.obj``)."""
    folder = Path(folder)
    listed = read_manifest(folder, tool)
    if listed is not None:
        return [folder / n for n in listed if (folder / n).is_file()]
    if not folder.is_dir():
        return []
    pats = [re.compile(s + "$") for s in stale_patterns]
    out = []
    for p in sorted(folder.rglob("*")):
        rel = p.relative_to(folder).as_posix()
        if p.is_file() and not any(x.startswith(".") for x in p.relative_to(folder).parts) \
                and any(r.match(rel) for r in pats):
            out.append(p)
    return out


def _in_the_way(folder: Path, rels) -> Path | None:
    """The first path under ``folder`` that keeps a file ``rel`` of ``rels`` from being moved there:
    a parent that is not a folder, or the file's own name taken by a folder."""
    for rel in rels:
        rel = Path(rel)
        for parent in reversed(rel.parents[:-1]):
            d = folder / parent
            if os.path.lexists(d) and not d.is_dir():
                return d
        if (folder / rel).is_dir():
            return folder / rel
    return None


def _unstage_message(exc: InputError, staging: Path, folder: Path) -> None:
    """Name the output file the user asked for, not its staging twin, in a refusal raised while
    writing (``out/.staging-tool/branches.obj`` -> ``out/branches.obj``): the staging folder is
    never seen."""
    def real(text: str) -> str:
        return text.replace(f"{staging}{os.sep}", f"{folder}{os.sep}").replace(str(staging), str(folder))

    if hasattr(exc, "path") and isinstance(exc.path, str):
        exc.path = real(exc.path)
    exc.args = tuple(real(a) if isinstance(a, str) else a for a in exc.args)


@contextlib.contextmanager
def staged_output(folder, tool: str, *, stale_patterns=(), inputs=(), option: str = "-o", subfolders=()):
    """Write a run's output folder through a staging folder: yields a fresh hidden folder inside
    ``folder`` to write into; when the body completes, the earlier run's own files (its manifest,
    or ``stale_patterns`` for a folder from before manifests) are removed, the new files moved into
    ``folder`` and a manifest written. A failed or killed run leaves the earlier output as it was
    (no mix of two runs); its staging folder is removed by the next run. Refuses (one line) an
    output folder that is an input or holds one this run would replace or remove (named like its
    output, or listed by its manifest), a folder that is a file, and a second concurrent run; an
    output file or one of ``subfolders`` (the folders the run will write into) whose place inside
    ``folder`` is taken by a file or a folder of the wrong kind is refused before any work, or,
    found only when the run is done, before anything is moved (the staging folder removed)."""
    import shutil

    folder = Path(folder)
    check_output_path(folder, folder=True)
    blocked = _in_the_way(folder, [Path(d) / "x" for d in subfolders])
    if blocked is not None:
        raise InputError(f"{blocked}: expected a path that can be a folder, found a file in the way")
    pats = [re.compile(p + "$") for p in stale_patterns]
    listed = set(read_manifest(folder, tool) or ())
    refuse_output_over_inputs(folder, inputs, folder=True, option=option,
                              writes=lambda rel: rel in listed or any(r.match(rel) for r in pats))
    with output_lock(folder, tool):
        staging = folder / f".staging-{tool}"
        if staging.exists():
            shutil.rmtree(staging)
        staging.mkdir()
        try:
            yield staging
        except BaseException as exc:
            shutil.rmtree(staging, ignore_errors=True)
            if isinstance(exc, InputError):
                _unstage_message(exc, staging, folder)
            raise
        new = sorted(p.relative_to(staging) for p in staging.rglob("*") if p.is_file())
        new_names = {p.as_posix() for p in new}
        blocked = _in_the_way(folder, new)
        if blocked is not None:
            shutil.rmtree(staging, ignore_errors=True)
            what = "a folder, found a file" if not blocked.is_dir() else "a file, found a folder"
            raise InputError(f"{blocked}: expected a path that can be {what} in the way")
        for old in own_stale(folder, tool, stale_patterns):
            rel = old.relative_to(folder).as_posix()
            if rel not in new_names:
                old.unlink()
        for rel in new:
            dest = folder / rel
            dest.parent.mkdir(parents=True, exist_ok=True)
            os.replace(staging / rel, dest)
        shutil.rmtree(staging, ignore_errors=True)
        write_text_atomic(_manifest(folder, tool),
                          f"# the files {tool}'s last complete run wrote here\n"
                          + "".join(f"{p.as_posix()}\n" for p in new))


def begin_sequence(folder, tool: str, planned, suffix: str, prefix: str = "frame_") -> list[Path]:
    """Start writing a frame sequence into ``folder`` (held by :func:`output_lock`): remove
    ``tool``'s own earlier frames -- those its manifest lists, or for a folder from before manifests
    ``prefix<digits>suffix`` files -- and dead writers' ``.part`` files, then record ``planned``
    (the names this run will write) as its manifest before the first frame, so an interrupted run
    leaves only its own frames and the next run knows them. A file of the same pattern that no run
    of ``tool`` wrote (named in no manifest) is left alone once a manifest exists. Returns the
    removed paths."""
    folder = Path(folder)
    listed = read_manifest(folder, tool)
    if listed is None:
        removed = remove_stale_frames(folder, [], suffix, prefix=prefix)
    else:
        removed = []
        for n in listed:
            p = folder / n
            if p.is_file():
                p.unlink()
                removed.append(p)
        part = re.compile(r"\." + re.escape(prefix) + r"\d+" + re.escape(suffix) + r"\..+\.part$")
        for p in sorted(folder.iterdir()):
            if part.match(p.name):
                p.unlink()
                removed.append(p)
    write_text_atomic(_manifest(folder, tool), f"# the files {tool}'s last run wrote here\n"
                      + "".join(f"{Path(n).name}\n" for n in planned))
    return removed


def end_sequence(folder, tool: str, written, suffix: str, prefix: str = "frame_") -> list[Path]:
    """End a frame sequence in ``folder`` (a run that may have resumed one): remove ``tool``'s own
    frames that are not among ``written`` -- those its manifest lists, or for a folder from before
    manifests ``prefix<digits>suffix`` files -- and record ``written`` as its manifest. Returns the
    removed paths."""
    folder = Path(folder)
    keep = {Path(n).name for n in written}
    listed = read_manifest(folder, tool)
    if listed is None:
        removed = remove_stale_frames(folder, keep, suffix, prefix=prefix)
    else:
        removed = [folder / n for n in listed if n not in keep and (folder / n).is_file()]
        for p in removed:
            p.unlink()
    write_text_atomic(_manifest(folder, tool), f"# the files {tool}'s last run wrote here\n"
                      + "".join(f"{n}\n" for n in sorted(keep)))
    return removed
