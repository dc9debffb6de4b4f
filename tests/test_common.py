"""Shared conventions: CLI error handling and exit codes, atomic writes, sequence listing, number parsing."""
from __future__ import annotations

import click
import pytest
from click.testing import CliRunner
from conftest import no_partial_files

from inflo.formats.atomic import atomic_write, list_sequence
from inflo.formats.errors import FormatError, InputError, parse_float, read_lines
from inflo.tools.common.cli import inflo_command


def make_cli(exc):
    @inflo_command("demo")
    @click.argument("out", type=click.Path())
    def main(out, quiet, debug):
        with atomic_write(out) as fh:
            fh.write("half a file")
            raise exc

    return main


def test_bad_input_is_one_line_exit_2(tmp_path):
    res = CliRunner().invoke(make_cli(FormatError("in.scn", 7, "13 values", "12 values")), [str(tmp_path / "o.txt")])
    assert res.exit_code == 2
    assert res.output.strip() == "demo: error: in.scn:7: expected 13 values, found 12 values"
    assert not (tmp_path / "o.txt").exists() and no_partial_files(tmp_path)


def test_failed_run_is_one_line_exit_1_and_debug_shows_traceback(tmp_path):
    res = CliRunner().invoke(make_cli(RuntimeError("solver diverged")), [str(tmp_path / "o.txt")])
    assert res.exit_code == 1 and len(res.output.strip().splitlines()) == 1
    assert "solver diverged" in res.output and "--debug" in res.output
    res = CliRunner().invoke(make_cli(RuntimeError("solver diverged")), [str(tmp_path / "o.txt"), "--debug"])
    assert isinstance(res.exception, RuntimeError)
    assert not (tmp_path / "o.txt").exists() and no_partial_files(tmp_path)


def test_interrupt_exit_130_keeps_no_partial(tmp_path):
    res = CliRunner().invoke(make_cli(KeyboardInterrupt()), [str(tmp_path / "o.txt")])
    assert res.exit_code == 130 and no_partial_files(tmp_path) and not (tmp_path / "o.txt").exists()


def test_atomic_write_replaces_only_when_complete(tmp_path):
    p = tmp_path / "a.txt"
    p.write_text("old")
    with pytest.raises(ValueError):
        with atomic_write(p) as fh:
            fh.write("new")
            raise ValueError
    assert p.read_text() == "old"
    with atomic_write(p) as fh:
        fh.write("new")
    assert p.read_text() == "new" and no_partial_files(tmp_path)


def test_list_sequence_natural_order_and_hidden(tmp_path):
    for n in ["f_10.obj", "f_2.obj", "f_1.obj", ".f_3.obj.part", "notes.txt"]:
        (tmp_path / n).write_text("")
    assert [p.name for p in list_sequence(tmp_path, ".obj")] == ["f_1.obj", "f_2.obj", "f_10.obj"]
    with pytest.raises(InputError):
        list_sequence(tmp_path / "missing", ".obj")


@pytest.mark.parametrize("tok", ["nan", "NaN", "inf", "-inf", "1e999"])
def test_parse_float_rejects_non_finite(tok):
    with pytest.raises(FormatError, match="finite"):
        parse_float(tok, "f.txt", 3)


def test_read_lines_errors(tmp_path):
    with pytest.raises(InputError, match="is a folder"):
        read_lines(tmp_path)
    (tmp_path / "b").write_bytes(b"ok\n\x00\x01")
    with pytest.raises(FormatError, match=r"b:2: expected text, found a NUL byte"):
        read_lines(tmp_path / "b")


def test_registry_round_trips_every_suffix(tmp_path):
    """Each registered format reads back what it wrote, through the suffix registry."""
    import numpy as np

    from inflo.formats import FORMATS, read_any, write_any
    from inflo.formats.func import Function
    from inflo.formats.obj import ObjMesh

    mesh = ObjMesh(np.eye(3), [[0, 1, 2]])
    write_any(tmp_path / "m.obj", mesh)
    np.testing.assert_array_equal(read_any(tmp_path / "m.obj").faces, mesh.faces)
    fn = Function.from_points([[0, 0], [0.5, 1], [1, 0.25]])
    write_any(tmp_path / "f.func", fn)
    assert read_any(tmp_path / "f.func") == fn
    assert {".obj", ".scn", ".rba", ".floret", ".func", ".fset", ".con", ".cset", ".s", ".fcc"} <= set(FORMATS)
    with pytest.raises(InputError, match="unknown file type '.xyz'"):
        read_any(tmp_path / "a.xyz")


def test_progress_bar_shows_the_rate_on_a_terminal(monkeypatch, capsys):
    """With unit= the bar's text carries '<rate> <unit>/s' (fccompose shows frames/s)."""
    import io
    import sys

    from inflo.tools.common import cli

    class Tty(io.StringIO):
        def isatty(self):
            return True

    err = Tty()
    monkeypatch.setattr(sys, "stderr", err)
    with cli.progress(length=3, label="run", unit="frames") as bar:
        for _ in range(3):
            bar.update(1)
    text = err.getvalue()
    assert "frames/s" in text and "3/3" in text


def test_a_quiet_progress_still_reports_a_stall(monkeypatch, capsys):
    """--quiet silences the bar, not a stall: no step for STALL_SECONDS prints one line."""
    import time

    from inflo.tools.common import cli

    monkeypatch.setattr(cli, "STALL_SECONDS", 0.2)
    with cli.progress(length=5, label="tool", quiet=True) as bar:
        bar.update(1)
        time.sleep(0.6)
    err = capsys.readouterr().err
    assert "tool: still running, 1 of 5 steps done, none in the last" in err
    with cli.progress(length=5, label="tool", quiet=True) as bar:
        for _ in range(5):
            bar.update(1)
    assert capsys.readouterr().err == ""
