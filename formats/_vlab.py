"""Pieces shared by the VLab text readers and writers (func, contour, bezier_surface).

``_Cursor`` walks the non-blank lines of a file and names file and line in every error;
``read_gallery`` reads the ``<kind>galleryver 1 1`` / ``items: N`` galleries (``.fset``, ``.cset``);
``_fmt`` writes numbers as VLab does (``%.6f``, negative zero as zero).
"""
from __future__ import annotations

import os

from .errors import FormatError, parse_int, read_lines, shorten

__all__ = ["_Cursor", "_fmt", "read_gallery"]




class _Cursor:
    """Walks the non-blank lines of a file; every error names the file and the 1-based line."""

    def __init__(self, path, lines: list[str]):
        self.path = os.fspath(path)
        self._items = [(i + 1, s.strip()) for i, s in enumerate(lines) if s.strip()]
        self._pos = 0

    def error(self, line: int | None, expected: str, found: str) -> FormatError:
        return FormatError(self.path, line, expected, found)

    def at_end(self) -> bool:
        return self._pos >= len(self._items)

    def peek(self) -> tuple[int, str] | None:
        return None if self.at_end() else self._items[self._pos]

    def take(self, expected: str) -> tuple[int, str]:
        """The next line as (line number, stripped text); at the end of file, an error."""
        if self.at_end():
            raise self.error(None, expected, "end of file")
        item = self._items[self._pos]
        self._pos += 1
        return item

    @staticmethod
    def key_of(text: str) -> str | None:
        head, sep, _ = text.partition(":")
        return head.strip() if sep else None

    def at_key(self, key: str) -> bool:
        nxt = self.peek()
        return nxt is not None and self.key_of(nxt[1]) == key

    def field(self, key: str, expected: str | None = None) -> tuple[int, str]:
        """The next line, which must read ``key: value``; returns (line number, value)."""
        line, text = self.take(expected or f"'{key}: ...'")
        if self.key_of(text) != key:
            raise self.error(line, expected or f"'{key}: ...'", shorten(text))
        return line, text.partition(":")[2].strip()

    def end(self, expected: str = "end of file") -> None:
        if not self.at_end():
            line, text = self._items[self._pos]
            raise self.error(line, expected, shorten(text))


def _fmt(value: float) -> str:
    """``%.6f``, with negative zero written as zero so equal values give equal text."""
    text = "%.6f" % value
    return "0.000000" if text == "-0.000000" else text




def read_gallery(path, header: str, parse_item) -> list:
    """Read a gallery file: the line ``header`` (e.g. ``funcgalleryver 1 1``), ``items: N``, then N
    items, each parsed by ``parse_item(cursor)``; nothing may follow the last item."""
    cur = _Cursor(path, read_lines(path))
    line, text = cur.take(f"'{header}'")
    if text.split() != header.split():
        raise cur.error(line, f"'{header}'", shorten(text))
    line, value = cur.field("items", "'items: N'")
    n = parse_int(value, cur.path, line, "an integer after 'items:'")
    if n < 0:
        raise cur.error(line, "an item count >= 0", shorten(value))
    items = [parse_item(cur) for _ in range(n)]
    cur.end(f"end of file after {n} items")
    return items
