"""Weight files (fixed vertices of an .fcc template, formats/weights.md): reader and its errors."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from inflo.formats.errors import FormatError, InputError
from inflo.formats.weights import read_weight_file

SPEC = Path(__file__).resolve().parent.parent / "formats" / "weights.md"


def test_spec_example_reads_sorted_and_unique(tmp_path):
    block = re.search(r"## Example\n\n((?:    .*\n)+)", SPEC.read_text()).group(1)
    p = tmp_path / "ex.weights"
    p.write_text("".join(line[4:] + "\n" for line in block.splitlines()))
    assert read_weight_file(p, 100).tolist() == [0, 1, 2, 3, 40, 41, 42, 43, 80, 81, 82, 83]


def test_separators_comments_repeats(tmp_path):
    p = tmp_path / "w.weights"
    p.write_text("# head\n5,,3 3\t1  # tail 99\n\n2,\n")
    ids = read_weight_file(p, 6)
    assert ids.dtype.name == "int32" and ids.tolist() == [1, 2, 3, 5]
    p.write_text("# nothing fixed\n")
    assert read_weight_file(p, 6).tolist() == []


@pytest.mark.parametrize("text, line, message", [
    ("0 1\n1.5\n", 2, "expected a vertex id (integer), found '1.5'"),
    ("0 6\n", 1, "expected a vertex id in 0..5, found '6'"),
    ("\n\n-1\n", 3, "expected a vertex id in 0..5, found '-1'"),
])
def test_rejects(tmp_path, text, line, message):
    p = tmp_path / "bad.weights"
    p.write_text(text)
    with pytest.raises(FormatError) as exc:
        read_weight_file(p, 6)
    assert str(exc.value) == f"{p}:{line}: {message}"


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_weight_file(tmp_path / "nope.weights", 6)
