"""Input errors shared by every reader: one line naming file, line, what was expected, what was found.

Every reader in :mod:`inflo.formats` raises :class:`FormatError` for malformed input; the CLIs turn it
into a one-line message on stderr and exit code 2 (see ``inflo.tools.common.cli``).
"""
from __future__ import annotations

import difflib
import math
import os
from collections.abc import Iterable, Mapping

__all__ = [
    "FormatError",
    "InputError",
    "decode_lines",
    "did_you_mean",
    "parse_float",
    "parse_int",
    "parse_floats",
    "read_bytes",
    "read_lines",
    "shorten",
]


class InputError(ValueError):
    """Bad input that is not tied to one line of one file (a missing folder, an empty sequence)."""


class FormatError(InputError):
    """Malformed input file.

    Parameters
    ----------
    path : str or os.PathLike
        The file that is wrong.
    line : int or None
        1-based line number, or None when the problem is the file as a whole.
    expected : str
        What the reader expected there, in words ("3 floats after 'v'").
    found : str
        What it found (the offending token or line, shortened).
    """

    def __init__(self, path, line: int | None, expected: str, found: str):
        self.path = os.fspath(path)
        self.line = line
        self.expected = expected
        self.found = found
        super().__init__(str(self))

    def __str__(self) -> str:
        where = self.path if self.line is None else f"{self.path}:{self.line}"
        return f"{where}: expected {self.expected}, found {self.found}"


def shorten(text: str, limit: int = 60) -> str:
    """Quote a token or line for an error message, cut to ``limit`` characters."""
    text = text.strip()
    if not text:
        return "an empty line"
    if len(text) > limit:
        text = text[: limit - 3] + "..."
    return repr(text)


def did_you_mean(word: str, options: Iterable[str], *, cutoff: float = 0.0,
                 spelling: Mapping[str, str] | None = None) -> str:
    """`` (did you mean 'closest'?)`` for an unknown key or name, or ``""`` when no option is close.

    The one suggestion every reader appends to its "expected a known key" message.

    Parameters
    ----------
    word : str
        What the file said (already normalized the way ``options`` are, e.g. lower case).
    options : iterable of str
        The known keys, sections or names; the closest by :func:`difflib.get_close_matches`
        (ratio at least ``cutoff``; 0: always the closest) is named.
    spelling : mapping, optional
        Option -> the text to show for it (a normalized key -> its canonical spelling).
    """
    best = difflib.get_close_matches(word, list(options), n=1, cutoff=cutoff)
    if not best:
        return ""
    shown = best[0] if spelling is None else spelling[best[0]]
    return f" (did you mean {shown!r}?)"


def parse_float(token: str, path, line: int | None, what: str = "a number") -> float:
    """Parse one finite float; NaN, inf and non-numbers raise :class:`FormatError`."""
    try:
        value = float(token)
    except ValueError:
        raise FormatError(path, line, what, shorten(token)) from None
    if not math.isfinite(value):
        raise FormatError(path, line, f"{what} (finite)", shorten(token))
    return value


def parse_int(token: str, path, line: int | None, what: str = "an integer") -> int:
    """Parse one integer (no decimal point, no exponent)."""
    try:
        return int(token)
    except ValueError:
        raise FormatError(path, line, what, shorten(token)) from None


def parse_floats(tokens: Iterable[str], path, line: int | None, what: str) -> list[float]:
    """Parse every token of ``tokens`` as a finite float."""
    return [parse_float(t, path, line, what) for t in tokens]


def read_bytes(path) -> bytes:
    """The bytes of a file; :class:`InputError` (one line) when it is missing, a folder or
    unreadable."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            return fh.read()
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a folder, expected a file") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror})") from None


def read_lines(path) -> list[str]:
    """Read a text file as a list of lines (no line ends).

    Raises :class:`InputError` when the file is missing or unreadable and :class:`FormatError`
    when it is not UTF-8 text.
    """
    path = os.fspath(path)
    return decode_lines(path, read_bytes(path))


def decode_lines(path, data: bytes) -> list[str]:
    """The lines of ``data`` (the bytes of the text file ``path``), as :func:`read_lines`."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise FormatError(path, line, "UTF-8 text", f"byte 0x{data[exc.start]:02x}") from None
    if "\x00" in text:
        line = text[: text.index("\x00")].count("\n") + 1
        raise FormatError(path, line, "text", "a NUL byte (binary file?)")
    return text.splitlines()


def parse_toml(text: str, path) -> dict:
    """``tomllib.loads(text)``; a TOML syntax error is a :class:`FormatError` naming its line (the
    TOML parameter files of phyllotaxis, branch-gen, thyrse, venation and petal-grow)."""
    import re
    import tomllib

    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"line (\d+)", str(exc))
        raise FormatError(path, int(m.group(1)) if m else None, "valid TOML", str(exc)) from None
