"""The shared pieces of the tools' TOML parameter readers (formats/toml_params.py): reading, the
line of a key, unknown names, typed values and the wording each tool gives its errors."""
from __future__ import annotations

import math

import pytest

from inflo.formats.errors import FormatError, InputError
from inflo.formats.toml_params import (
    LineStyle,
    ParamText,
    line_of,
    read_toml_lines,
    read_toml_text,
    show_repr,
    unknown_name,
)

TEXT = """\
seed = 3
"top" = 1

[sca]
step = 0.1
  'kill_distance' = 2

["blade"]
size = 1

[sca.inner]
deep = 1

[[organ]]
name = "a"
"""


# ---------------------------------------------------------------------------------------------
# line_of


def test_line_of_keys_and_headers():
    style = LineStyle()
    assert line_of(TEXT, None, "seed", style) == 1
    assert line_of(TEXT, None, "top", style) == 2  # a quoted key
    assert line_of(TEXT, "sca", "step", style) == 5
    assert line_of(TEXT, "sca", "kill_distance", style) == 6  # indented, single quotes
    assert line_of(TEXT, "sca", "deep", style) == 12  # [sca.inner] counts as [sca]
    assert line_of(TEXT, "organ", "name", style) == 15  # [[organ]]
    assert line_of(TEXT, "sca", None, style) == 4
    assert line_of(TEXT, "sca", "seed", style) is None  # seed is a top-level key, not [sca]'s


def test_line_of_top_level_name():
    # a style whose top level is "" finds top-level keys under that name, and not under None
    style = LineStyle(top="")
    assert line_of(TEXT, "", "seed", style) == 1
    assert line_of(TEXT, None, "seed", style) is None


def test_line_of_quoted_headers():
    assert line_of(TEXT, "blade", "size", LineStyle()) is None  # ["blade"] is the name '"blade"'
    assert line_of(TEXT, "blade", "size", LineStyle(unquote=True)) == 9
    assert line_of(TEXT, "blade", None, LineStyle(unquote=True)) == 8


def test_line_of_single_brackets_and_undotted():
    style = LineStyle(brackets="single", dotted=False, key_quotes='"')
    assert line_of(TEXT, "organ", "name", style) is None  # [[organ]] reads as '[organ'
    assert line_of(TEXT, "sca", "deep", style) is None  # [sca.inner] is not [sca]
    assert line_of(TEXT, "sca.inner", "deep", style) == 12
    assert line_of(TEXT, "sca", "kill_distance", style) is None  # single quotes not taken
    assert line_of(TEXT, None, "top", style) == 2


@pytest.mark.parametrize("fallback, found", [(None, None), ("header", 4), ("prefix", 4)])
def test_line_of_fallback_to_the_header(fallback, found):
    style = LineStyle(fallback=fallback)
    assert line_of(TEXT, "sca", "missing", style) == found
    assert line_of(TEXT, None, "missing", style) is None  # the top level has no header


def test_line_of_prefix_fallback_takes_spaces_before_the_dot():
    text = "[sca . inner]\nx = 1\n"
    assert line_of(text, "sca", "step", LineStyle(fallback="prefix")) == 1
    assert line_of(text, "sca", "step", LineStyle(fallback="header")) is None  # the name is 'sca '


# ---------------------------------------------------------------------------------------------
# reading


def test_read_toml_lines(tmp_path):
    f = tmp_path / "p.toml"
    f.write_text("a = 1\r\n[b]\r\nc = 'x'\r\n")
    data, lines = read_toml_lines(f)
    assert data == {"a": 1, "b": {"c": "x"}}
    assert lines == ["a = 1", "[b]", "c = 'x'"]


def test_read_toml_lines_refusals(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        read_toml_lines(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("a = 1\nb = = 2\n")
    with pytest.raises(FormatError, match=r"bad.toml:2: expected valid TOML"):
        read_toml_lines(bad)
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"a = 1\n\xff\n")
    with pytest.raises(FormatError, match=r"bin.toml:2: expected UTF-8 text, found byte 0xff"):
        read_toml_lines(binary)


def test_read_toml_text(tmp_path):
    f = tmp_path / "p.toml"
    f.write_bytes(b"a = 1\n")
    assert read_toml_text(f) == "a = 1\n"
    f.write_bytes(b"a = '\xff'\n")
    with pytest.raises(FormatError) as err:
        read_toml_text(f)
    assert str(err.value) == f"{f}: expected UTF-8 TOML text, found undecodable bytes"

    def offset(path, data, exc):
        return FormatError(path, None, "UTF-8", f"offset {exc.start}")

    with pytest.raises(FormatError, match="found offset 5$"):
        read_toml_text(f, offset)
    with pytest.raises(InputError, match="is a folder"):
        read_toml_text(tmp_path)


# ---------------------------------------------------------------------------------------------
# errors and typed values


def test_unknown_name_names_the_closest():
    err = unknown_name("p.toml", 3, "a key of [sca]", "stpe", ["step", "roots"])
    assert str(err) == "p.toml:3: expected a key of [sca] (did you mean 'step'?), found 'stpe'"
    err = unknown_name("p.toml", None, "a section", "x", [], found="[x]")
    assert str(err) == "p.toml: expected a section, found [x]"


def as_text(**kw):
    return ParamText("p.toml", TEXT, **kw)


def message(fn, *args, **kw):
    with pytest.raises(FormatError) as err:
        fn(*args, **kw)
    return str(err.value)


def test_templates_and_shown_values():
    long = "x" * 100
    as_word = as_text()  # "{name} as {expected}", values shortened
    assert message(as_word.string, "sca", "step", 1) == "p.toml:5: expected sca.step as a string, found '1'"
    assert message(as_word.string, None, "seed", [long]).endswith("found \"['" + "x" * 55 + "...\"")
    for_word = as_text(template="{expected} for '{name}'", show=show_repr)
    assert message(for_word.string, None, "seed", 1) == "p.toml:1: expected a string for 'seed', found 1"
    assert str(for_word.error("sca", "step", "a step > 0", "-1")) == \
        "p.toml:5: expected a step > 0 for 'sca.step', found -1"
    assert str(as_word.error("sca", "step", "> 0", "-1", template="{name} {expected}")) == \
        "p.toml:5: expected sca.step > 0, found -1"


def test_number():
    t = as_text(show=show_repr)
    assert t.number("sca", "step", 2) == 2.0 and isinstance(t.number("sca", "step", 2), float)
    assert t.number("sca", "step", 0.5) == 0.5
    assert message(t.number, "sca", "step", "1") == "p.toml:5: expected sca.step as a number, found '1'"
    assert message(t.number, "sca", "step", True) == "p.toml:5: expected sca.step as a number, found True"
    assert message(t.number, "sca", "step", "x", not_a_number="a finite number").endswith(
        "as a finite number, found 'x'")
    assert message(t.number, "sca", "step", math.nan) == "p.toml:5: expected sca.step as a finite number, found nan"
    assert message(t.number, "sca", "step", math.inf).endswith("as a finite number, found inf")


def test_number_with_infinity():
    t = as_text(show=show_repr)
    assert t.number("sca", "step", math.inf, allow_inf=True) == math.inf
    assert t.number("sca", "step", " Infinity ", allow_inf=True) == math.inf
    assert t.number("sca", "step", "inf", allow_inf=True) == math.inf
    assert message(t.number, "sca", "step", math.nan, allow_inf=True).endswith("as a finite number, found nan")
    assert message(t.number, "sca", "step", "huge", allow_inf=True).endswith("as a number, found 'huge'")


def test_integer():
    t = as_text(show=show_repr)
    assert t.integer(None, "seed", 7) == 7
    for bad in (7.0, True, "7", None):
        assert message(t.integer, None, "seed", bad) == f"p.toml:1: expected seed as an integer, found {bad!r}"
    assert message(t.number, None, "seed", "7", integer=True).endswith("as an integer, found '7'")


def test_boolean_string_choice():
    t = as_text(show=show_repr)
    assert t.boolean("sca", "step", False) is False
    assert message(t.boolean, "sca", "step", 0).endswith("sca.step as true or false, found 0")
    assert t.string("sca", "step", "") == ""
    assert t.choice("sca", "step", "open", ("open", "closed")) == "open"
    assert message(t.choice, "sca", "step", "clsoed", ("open", "closed")) == \
        "p.toml:5: expected sca.step as one of ['open', 'closed'] (did you mean 'closed'?), found 'clsoed'"
    assert message(t.choice, "sca", "step", 1, ("open",)).endswith("(did you mean 'open'?), found 1")


def test_vector():
    t = as_text(template="{expected} for '{name}'", show=show_repr)
    assert t.vector(None, "seed", [1, 2.5, 3]) == [1.0, 2.5, 3.0]
    assert t.vector(None, "seed", [1, 2], 2) == [1.0, 2.0]
    assert message(t.vector, None, "seed", [1, 2]) == "p.toml:1: expected a list of 3 numbers for 'seed', found [1, 2]"
    assert message(t.vector, None, "seed", (1, 2, 3)).endswith("a list of 3 numbers for 'seed', found (1, 2, 3)")
    assert message(t.vector, None, "seed", [1, "a", 3]).endswith("a number for 'seed', found 'a'")
    assert message(t.vector, None, "seed", [1, math.nan, 3]).endswith("a finite number for 'seed', found nan")


def test_unknown_line_is_none_without_text():
    t = ParamText("<params>", "")
    assert str(t.bad("sca", "step", "a number", "x")) == "<params>: expected sca.step as a number, found \"'x'\""


ORGANS = """\
[flower]
keyframes = 10

[[organ]]
name = "a"
"mesh" = "a.obj"

[[organ]]
name = "b"

[growth.early]
dg = 0.1
"""


def test_line_of_one_table():
    style = LineStyle(brackets="pair", dotted=False, key_quotes="", one_table=True)
    assert line_of(ORGANS, "organ", "name", style, 0) == 5
    assert line_of(ORGANS, "organ", "name", style, 1) == 9
    assert line_of(ORGANS, "organ", None, style, 1) == 8
    assert line_of(ORGANS, "organ", "mesh", style, 0) == 4  # quoted keys not taken: the header's line
    assert line_of(ORGANS, "organ", "dg", style, 1) == 8  # the search stops at the next header
    assert line_of(ORGANS, "organ", "name", style, 2) is None  # no third [[organ]]
    assert line_of(ORGANS, "growth.early", "dg", style) == 12  # the whole dotted name
    assert line_of(ORGANS, "growth", "dg", style) is None
    assert line_of("[[[organ]]]\nname = 1\n", "organ", "name", style) is None  # at most two brackets
    assert line_of("[[[organ]]]\nname = 1\n", "organ", "name", LineStyle()) == 2


SWEEP = """\
[[stage]]
name = "a"

[[stage]]
cli = "b"

[axes]
n = [1, 2]

[axes.alpha]
values = [1]
"""


def test_line_of_subtables_and_nth():
    style = LineStyle(brackets="pair", dotted=False, subtables=True)
    assert line_of(SWEEP, "axes", "alpha", style) == 10  # the header [axes.alpha]
    assert line_of(SWEEP, "axes", "alpha", LineStyle(dotted=False)) is None
    assert line_of(SWEEP, "stage", "cli", style, 1) == 5
    assert line_of(SWEEP, "stage", "cli", style, 0) == 5  # 0: a key of any [[stage]]
    assert line_of(SWEEP, "stage", "name", style, 1) is None  # only the second [[stage]]
    assert line_of(SWEEP, "stage", None, style, 1) == 4
