"""Typed TOML parameter files: the pieces the tools' parameter readers share.

A tool's parameter file is TOML (``formats/branch_gen.md``, ``thyrse.md``, ``phyllotaxis.md``,
``venation.md``): sections of typed keys, every one checked, every refusal one
:class:`~inflo.formats.errors.FormatError` naming the file, the key's line, what was expected and
what was found. This module holds what those readers have in common:

- :func:`read_toml_lines`, :func:`read_toml_text`: a file's text, refused in one line when missing,
  not UTF-8 or not TOML;
- :func:`line_of`: the line of ``section.key`` (or of a section's header) in the text, best effort;
  :class:`LineStyle` says how a tool's files are searched (the readers grew apart in small ways,
  such as quoted header names, and each keeps its own lines);
- :func:`unknown_name`: the refusal of an unknown section or key, naming the closest known one;
- :class:`ParamText`: a file's path and text with its wording; it converts a value to a number
  (finite, integer), true or false, a string, one of a few choices or a vector of n numbers, and
  builds the error about a key.

The wording of a message belongs to the tool: ``ParamText`` takes it as parameters (``template``,
``show``), so that every tool's messages stay as they were.
"""
from __future__ import annotations

import math
import os
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from .errors import FormatError, did_you_mean, parse_toml, read_bytes, read_lines, shorten

__all__ = [
    "LineStyle",
    "ParamText",
    "line_of",
    "read_toml_lines",
    "read_toml_text",
    "show_repr",
    "show_short",
    "undecodable_file",
    "unknown_name",
]


# ---------------------------------------------------------------------------------------------
# reading


def read_toml_lines(path) -> tuple[dict, list[str]]:
    """The parsed TOML mapping of ``path`` and its lines (no line ends).

    The file is read with :func:`~inflo.formats.errors.read_lines` (missing: :class:`InputError`;
    not UTF-8 or binary: :class:`FormatError` naming the line) and parsed as its lines joined by
    ``"\\n"``; invalid TOML is a :class:`FormatError` naming its line.
    """
    lines = read_lines(path)
    return parse_toml("\n".join(lines), path), lines


def undecodable_file(path, data: bytes, exc: UnicodeDecodeError) -> FormatError:
    """The refusal of a parameter file that is not UTF-8, for :func:`read_toml_text`: the file as a
    whole, ``expected UTF-8 TOML text, found undecodable bytes``."""
    return FormatError(path, None, "UTF-8 TOML text", "undecodable bytes")


def read_toml_text(path, undecodable: Callable[[object, bytes, UnicodeDecodeError], FormatError]
                   = undecodable_file) -> str:
    """The text of the parameter file ``path`` (not parsed).

    A missing file or a folder is an :class:`InputError` (:func:`~inflo.formats.errors.read_bytes`);
    bytes that are not UTF-8 raise ``undecodable(path, data, exc)``.
    """
    path = os.fspath(path)
    data = read_bytes(path)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise undecodable(path, data, exc) from None


# ---------------------------------------------------------------------------------------------
# lines


_HEADERS = {
    "any": re.compile(r"^\[+\s*([^\]]+?)\s*\]+"),  # [table] and [[array of tables]]
    "single": re.compile(r"^\[\s*([^\]]+?)\s*\]"),  # [table] only
    "pair": re.compile(r"^\[\[?\s*([^\]]+?)\s*\]\]?"),  # [table] and [[table]], no more brackets
}


@dataclass(frozen=True)
class LineStyle:
    """How :func:`line_of` searches a tool's parameter text.

    Attributes
    ----------
    top : str or None
        The section name of the keys above the first header (what callers pass for top-level keys).
    brackets : str
        ``"any"``: ``[table]`` and ``[[table]]`` headers; ``"single"``: a header is ``[`` ... ``]``
        (``[[table]]`` reads as the name ``[table``); ``"pair"``: one or two brackets.
    unquote : bool
        A header's name loses its double quotes (``["blade"]`` is ``blade``).
    dotted : bool
        A header ``[a.b]`` opens section ``a`` (the part before the first dot).
    key_quotes : str
        The quote characters a key may be written in (``"key" = ...``); "" for bare keys only.
    fallback : str or None
        When ``key`` of ``section`` is not found: ``"header"``: the section's header line (as
        :func:`line_of` finds it with ``key=None``); ``"prefix"``: the first line that starts
        with brackets, the section's name and ``]`` or ``.`` (spaces allowed between); None: no line.
    one_table : bool
        Only the ``nth`` header named ``section`` counts (an array of tables, ``[[organ]]``): the
        key is searched from it to the next header of any name, and when absent the header's own
        line is the answer. ``fallback`` does not apply.
    subtables : bool
        A header ``[section.key]`` is the line of ``key`` too (a table as a key's value). Without
        ``one_table``, ``nth`` > 0 searches keys in the ``nth`` table named ``section`` only (0: in
        any of them).
    """

    top: str | None = None
    brackets: str = "any"
    unquote: bool = False
    dotted: bool = True
    key_quotes: str = "\"'"
    fallback: str | None = None
    one_table: bool = False
    subtables: bool = False


def line_of(text: str, section: str | None, key: str | None, style: LineStyle = LineStyle(),
            nth: int = 0) -> int | None:
    """1-based line of ``key`` inside ``section`` (``style.top`` for the top level), or of the
    section's header when ``key`` is None; None when not found. Best effort: the text is searched
    line by line, not parsed (a line of a multi-line value that looks like a header counts as one).
    ``nth``: which header named ``section`` (from 0) is searched (see :class:`LineStyle`).
    """
    header = _HEADERS[style.brackets]
    quotes = f"[{re.escape(style.key_quotes)}]?" if style.key_quotes else ""
    pat = None if key is None else re.compile(rf"^{quotes}{re.escape(key)}{quotes}\s*=")
    lines = text.splitlines()
    if style.one_table:
        return _line_in_table(lines, section, pat, header, style, nth)
    current = style.top
    seen = -1
    for i, raw in enumerate(lines, 1):
        s = raw.strip()
        m = header.match(s)
        if m:
            name = m.group(1)
            if style.unquote:
                name = name.strip().strip('"')
            if style.dotted:
                name = name.split(".")[0]
            current = name
            if current == section:
                seen += 1
            if key is None and current == section and seen == nth:
                return i
            if key is not None and style.subtables:
                parts = current.split(".", 1)
                if len(parts) == 2 and parts[0] == section and parts[1].strip("\"'") == key:
                    return i
            continue
        if pat is not None and current == section and (nth == 0 or seen == nth) and pat.match(s):
            return i
    if key is None or section is None or section == style.top:
        return None
    if style.fallback == "header":
        return line_of(text, section, None, style)
    if style.fallback == "prefix":
        start = re.compile(rf"^\s*\[+\s*{re.escape(section)}\s*[\].]")
        for i, raw in enumerate(lines, 1):
            if start.match(raw.strip()):
                return i
    return None


def _line_in_table(lines, section, pat, header, style: LineStyle, nth: int) -> int | None:
    """:func:`line_of` in the ``nth`` table named ``section`` only (``style.one_table``)."""
    found = None
    seen = -1
    for i, raw in enumerate(lines, 1):
        s = raw.strip()
        m = header.match(s)
        if m:
            if found is not None:
                break
            name = m.group(1)
            if style.unquote:
                name = name.strip().strip('"')
            if style.dotted:
                name = name.split(".")[0]
            if name == section:
                seen += 1
                if seen == nth:
                    found = i
            continue
        if found is not None and pat is not None and pat.match(s):
            return i
    return found


# ---------------------------------------------------------------------------------------------
# errors and typed values


def unknown_name(path, line: int | None, expected: str, name: str, known: Iterable[str],
                 found: str | None = None) -> FormatError:
    """The refusal of an unknown section or key ``name``: ``expected`` followed by the closest
    of ``known`` (`` (did you mean 'x'?)``); found: ``repr(name)`` unless given."""
    return FormatError(path, line, expected + did_you_mean(name, known), repr(name) if found is None else found)


def show_repr(value) -> str:
    """A value as found in a message: its ``repr``."""
    return repr(value)


def show_short(value) -> str:
    """A value as found in a message: its ``repr``, quoted and cut to 60 characters
    (:func:`~inflo.formats.errors.shorten`)."""
    return shorten(repr(value))


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


class ParamText:
    """A parameter file (its path and text) and the tool's wording of errors about its keys.

    Parameters
    ----------
    path : str or os.PathLike
        The file, as messages name it.
    text : str
        Its text, searched for the lines of keys (:func:`line_of` with ``style``).
    style : LineStyle
        How the text is searched.
    template : str
        The ``expected`` part of a message from ``{name}`` (``key`` at the top level, else
        ``section.key``) and ``{expected}``: ``"{expected} for '{name}'"``, ``"{name} as {expected}"``.
    show : callable
        A value as found in a message (:func:`show_repr`, :func:`show_short`).
    """

    def __init__(self, path, text: str, *, style: LineStyle = LineStyle(), template: str = "{name} as {expected}",
                 show: Callable[[object], str] = show_short):
        self.path = path
        self.text = text
        self.style = style
        self.template = template
        self.show = show

    def line(self, section: str | None, key: str | None) -> int | None:
        """The line of ``section.key`` (or of the section's header when ``key`` is None)."""
        return line_of(self.text, section, key, self.style)

    def name(self, section: str | None, key: str) -> str:
        """``key`` at the top level, else ``section.key``."""
        return key if section is None or section == self.style.top else f"{section}.{key}"

    def error(self, section: str | None, key: str, expected: str, found: str, *,
              template: str | None = None) -> FormatError:
        """The error about ``section.key`` at its line; ``found`` is already text. ``template``
        replaces the file's for this message (a tool words range errors apart from type errors)."""
        words = (template or self.template).format(name=self.name(section, key), expected=expected)
        return FormatError(self.path, self.line(section, key), words, found)

    def bad(self, section: str | None, key: str, expected: str, value) -> FormatError:
        """:meth:`error` with ``value`` shown the file's way."""
        return self.error(section, key, expected, self.show(value))

    # typed values: each returns the converted value or raises the error about the key

    def number(self, section: str | None, key: str, value, *, integer: bool = False, allow_inf: bool = False,
               not_a_number: str = "a number") -> float | int:
        """A number (not a boolean): an int when ``integer`` (a float is refused), else a finite float.

        ``allow_inf``: infinity is accepted too, as a number or as the strings "inf", "infinity"
        (any case, blanks around). Refusals: ``not_a_number`` (``"an integer"`` when ``integer``)
        for what is no number, ``"a finite number"`` for NaN and refused infinities.
        """
        if not _is_number(value):
            if allow_inf and isinstance(value, str) and value.strip().lower() in ("inf", "infinity"):
                return math.inf
            raise self.bad(section, key, "an integer" if integer else not_a_number, value)
        if integer:
            if isinstance(value, float):
                raise self.bad(section, key, "an integer", value)
            return int(value)
        value = float(value)
        if math.isnan(value) or (math.isinf(value) and not allow_inf):
            raise self.bad(section, key, "a finite number", value)
        return value

    def integer(self, section: str | None, key: str, value) -> int:
        """An integer (not a boolean, not a float); refused as ``"an integer"``."""
        return self.number(section, key, value, integer=True)

    def boolean(self, section: str | None, key: str, value) -> bool:
        """true or false; refused as ``"true or false"``."""
        if not isinstance(value, bool):
            raise self.bad(section, key, "true or false", value)
        return value

    def string(self, section: str | None, key: str, value) -> str:
        """A string; refused as ``"a string"``."""
        if not isinstance(value, str):
            raise self.bad(section, key, "a string", value)
        return value

    def choice(self, section: str | None, key: str, value, options) -> str:
        """One of ``options`` (strings); refused as ``"one of [...]"`` naming the closest option."""
        if not isinstance(value, str) or value not in options:
            raise self.bad(section, key, f"one of {list(options)}{did_you_mean(str(value), options)}", value)
        return value

    def vector(self, section: str | None, key: str, value, n: int = 3) -> list[float]:
        """A list of ``n`` finite numbers (as floats); refused as ``"a list of n numbers"``, or as
        :meth:`number` refuses an item."""
        if not isinstance(value, list) or len(value) != n:
            raise self.bad(section, key, f"a list of {n} numbers", value)
        return [self.number(section, key, x) for x in value]


def referenced_files(path) -> list:
    """The files a TOML parameter file names: every string value (at any depth, in tables and
    lists) that is the path of an existing file, relative to the parameter file's folder or the
    working folder. A tool passes them, with the parameter file, to the output rule
    (:func:`inflo.formats.atomic.staged_output`), so an output never replaces a ``.func``,
    contour or map it reads. A file that is not TOML gives none (its reader says why)."""
    import tomllib
    from pathlib import Path

    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return []
    found: list = []

    def walk(value):
        if isinstance(value, dict):
            for v in value.values():
                walk(v)
        elif isinstance(value, list):
            for v in value:
                walk(v)
        elif isinstance(value, str) and value and len(value) < 4096 and "\n" not in value:
            for base in (path.parent, Path.cwd()):
                try:
                    q = base / value
                    if q.is_file() and q not in found:
                        found.append(q)
                except (OSError, ValueError):
                    pass

    walk(data)
    return found
