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
           "remove_stale_frames"]


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
