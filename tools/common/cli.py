"""What every inflo CLI does the same way (docs/architecture.md, "Errors" and "Progress").

- Bad input (:class:`~inflo.formats.errors.InputError`, including ``FormatError``) prints one line
  ``<cli>: error: <file>:<line>: expected ..., found ...`` and exits with code 2.
- A failed run (any other exception) prints one line and exits with code 1.
- An output path the system refuses (a file where a folder must be made, a missing or read-only
  parent) and a numeric overflow are bad input too: one line, exit 2.
- A usage error (an unknown option, a missing argument, a value click refuses) prints one line
  ``<cli>: error: <message> (see <cli> --help)`` and exits with code 2.
- Every float option takes finite numbers only (nan, inf: a usage error).
- Messages are one line: line breaks and other control characters in them (a file name holding a
  newline) are written as escapes (``\\n``).
- ``--debug`` re-raises so the traceback is shown.
- Ctrl-C exits with code 130; files already renamed into place are complete (atomic writes).
- Progress bars go to stderr, only on a terminal and without ``--quiet``.

Usage::

    @inflo_command("polygonize")
    @click.argument(...)
    def main(..., quiet, debug): ...
"""
from __future__ import annotations

import contextlib
import functools
import math
import os
import sys
import time

import click

from inflo.formats.errors import InputError

__all__ = ["inflo_command", "progress", "SEED", "FINITE", "FiniteRange", "InfloCommand", "InfloGroup", "one_line",
           "stall_notice"]

#: the type of every ``--seed``: numpy's generators take seeds in [0, 2**32 - 1]
SEED = click.IntRange(0, 2**32 - 1)


def one_line(text) -> str:
    """``text`` on one line: line breaks, tabs and other characters that are not printable written
    as Python escapes (a file name holding a newline becomes ``no\\nsuch.con``)."""
    text = str(text)
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


class _Finite(click.types.FloatParamType):
    """A float option's type: a finite number (nan and inf are refused like a word)."""

    def convert(self, value, param, ctx):
        x = super().convert(value, param, ctx)
        if not math.isfinite(x):
            self.fail(f"expected a finite number, found {value!r}", param, ctx)
        return x


#: the type of a float option (``type=float`` becomes this in every :func:`inflo_command`)
FINITE = _Finite()


class FiniteRange(click.FloatRange):
    """``click.FloatRange`` that also refuses nan (which passes every comparison) and inf."""

    def convert(self, value, param, ctx):
        x = click.types.FloatParamType.convert(self, value, param, ctx)
        if not math.isfinite(x):
            self.fail(f"expected a finite number, found {value!r}", param, ctx)
        return super().convert(x, param, ctx)


def _finite_types(cmd: click.Command) -> None:
    """Every float option and argument of ``cmd`` takes finite numbers only (same help text)."""
    for p in cmd.params:
        t = p.type
        if isinstance(t, FiniteRange) or isinstance(t, _Finite):
            continue
        if isinstance(t, click.FloatRange):
            p.type = FiniteRange(min=t.min, max=t.max, min_open=t.min_open, max_open=t.max_open, clamp=t.clamp)
        elif isinstance(t, click.types.FloatParamType):
            p.type = FINITE
        elif isinstance(t, click.Tuple) and any(isinstance(x, click.types.FloatParamType) for x in t.types):
            t.types = [FINITE if type(x) is click.types.FloatParamType else x for x in t.types]


def _usage_line(exc: click.ClickException, name: str) -> str:
    """One line for click's error: ``<cli>: error: <message> (see <cli> --help)``."""
    ctx = getattr(exc, "ctx", None)
    path = ctx.command_path if ctx is not None else name
    msg = one_line(exc.format_message())
    if isinstance(exc, click.UsageError):
        return f"{path}: error: {msg} (see {path} --help)"
    return f"{path}: error: {msg}"


class _OneLineUsage:
    """click's usage errors as one line (instead of the usage, a hint, a blank line and the error)."""

    def _one_line(self, exc: click.ClickException, name: str | None) -> None:
        line = _usage_line(exc, name or self.name)
        exc.show = lambda file=None: click.echo(line, err=True)

    def make_context(self, info_name, args, parent=None, **extra):
        try:
            return super().make_context(info_name, args, parent=parent, **extra)
        except click.ClickException as exc:
            self._one_line(exc, info_name)
            raise

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except click.ClickException as exc:
            if "show" not in vars(exc):
                self._one_line(exc, ctx.command_path)
            raise


class InfloCommand(_OneLineUsage, click.Command):
    """The click command of an inflo CLI: one-line usage errors."""


class InfloGroup(_OneLineUsage, click.Group):
    """A click group of inflo commands: one-line usage errors."""


def _path_error(exc: OSError) -> str:
    """One line for an output (or input) path the system refused: file, what was expected, found."""
    what = {
        "FileExistsError": "expected a path that can be a folder, found a file in the way",
        "NotADirectoryError": "expected a folder, found a file",
        "IsADirectoryError": "expected a file, found a folder",
        "FileNotFoundError": "expected a path that exists or can be made, found none",
        "PermissionError": "expected a path that can be written, found it not permitted",
    }.get(type(exc).__name__, f"expected a path that can be used, found {exc.strerror or exc}")
    where = exc.filename if exc.filename is not None else "path"
    return f"{where}: {what}"


def _remove_if_only_bookkeeping(folder: str) -> None:
    """Remove a folder a failed run made when it holds nothing but the run's bookkeeping (its
    manifest ``.inflo-*``, a ``.staging-*`` folder): no output is left that looks like a run's."""
    import shutil

    with contextlib.suppress(OSError):
        names = os.listdir(folder)
        if all(n.startswith((".inflo-", ".staging-")) for n in names):
            for n in names:
                path = os.path.join(folder, n)
                if os.path.isdir(path) and not os.path.islink(path):
                    shutil.rmtree(path)
                else:
                    os.unlink(path)
            os.rmdir(folder)


def inflo_command(name: str, **command_kwargs):
    """Decorator: a click command with ``--quiet`` and ``--debug`` and inflo's error conventions."""

    def decorate(fn):
        @functools.wraps(fn)
        def guarded(*args, **kwargs):
            debug = kwargs.get("debug", False)
            out = kwargs.get("output")
            fresh = isinstance(out, str) and not os.path.lexists(out)
            try:
                try:
                    return fn(*args, **kwargs)
                except (Exception, KeyboardInterrupt):
                    # a run that fails leaves no empty output folder it made (no partial output)
                    if fresh and os.path.isdir(out):
                        _remove_if_only_bookkeeping(out)
                    raise
            except KeyboardInterrupt:
                if debug:
                    raise
                click.echo(f"{name}: interrupted; complete output files are kept", err=True)
                sys.exit(130)
            except InputError as exc:
                if debug:
                    raise
                click.echo(f"{name}: error: {one_line(exc)}", err=True)
                sys.exit(2)
            except click.exceptions.ClickException:
                raise
            except (FileExistsError, NotADirectoryError, IsADirectoryError, FileNotFoundError,
                    PermissionError) as exc:
                if debug:
                    raise
                click.echo(f"{name}: error: {one_line(_path_error(exc))}", err=True)
                sys.exit(2)
            except MemoryError:  # a count beyond what the machine holds that no bound caught
                if debug:
                    raise
                click.echo(f"{name}: error: expected input whose work fits in memory, found more than this "
                           f"machine can allocate (a count or size too large)", err=True)
                sys.exit(2)
            except (OverflowError, FloatingPointError, ZeroDivisionError) as exc:
                if debug:
                    raise
                click.echo(f"{name}: error: expected input whose numbers stay within floating point range, found "
                           f"an overflow ({one_line(exc)})", err=True)
                sys.exit(2)
            except Exception as exc:  # a failed run: one line unless --debug
                if debug:
                    raise
                click.echo(
                    f"{name}: failed: {type(exc).__name__}: {one_line(exc)} (rerun with --debug for a traceback)",
                    err=True,
                )
                sys.exit(1)

        cmd = guarded
        cmd = click.option("--debug", is_flag=True, help="Show a Python traceback on errors.")(cmd)
        cmd = click.option("--quiet", "-q", is_flag=True, help="No progress bar or messages.")(cmd)
        command_kwargs.setdefault("context_settings", {"help_option_names": ["-h", "--help"]})
        command_kwargs.setdefault("cls", InfloCommand)
        cmd = click.command(name, **command_kwargs)(cmd)
        _finite_types(cmd)
        return cmd

    return decorate


@contextlib.contextmanager
def progress(iterable=None, *, length: int | None = None, label: str = "", quiet: bool = False,
             unit: str | None = None):
    """A click progress bar with position and ETA on stderr when it is a terminal; the bare
    iterable otherwise. With ``unit`` (e.g. ``"frames"``) the bar also shows the rate
    (``2.31 frames/s``) measured since it started.

    Yields an object that iterates like ``iterable`` and has ``update(n)``.
    """
    if quiet or not sys.stderr.isatty():
        silent = _Silent(iterable, label, length)
        try:
            yield silent
        finally:
            silent.stop()
        return
    with click.progressbar(
        iterable, length=length, label=label, file=sys.stderr, show_eta=True, show_pos=True,
        item_show_func=(lambda item: item) if unit else None,
    ) as bar:
        yield _Rate(bar, unit) if unit else bar


@contextlib.contextmanager
def stall_notice(label: str, *, after: float = 30.0, every: float = 60.0):
    """Yields ``tick(done, total)``: when the work has run ``after`` seconds, a line on stderr
    every ``every`` seconds says how far it is (``venation: still running, 120 of 5000 steps after
    90 s``), with or without ``--quiet`` (which silences the bar, not a stall), so a run that is
    slow beyond its bounds is never silent."""
    t0 = time.perf_counter()
    last = [t0]

    def tick(done, total=None, unit="steps"):
        now = time.perf_counter()
        if now - t0 >= after and now - last[0] >= every:
            last[0] = now
            of = f" of {total}" if total is not None else ""
            click.echo(f"{label}: still running, {done}{of} {unit} after {now - t0:.0f} s", err=True)

    yield tick


class _Rate:
    """``update(n)`` of a click bar that shows the rate since the start as the bar's item text."""

    def __init__(self, bar, unit: str):
        self._bar = bar
        self._unit = unit
        self._t0 = time.perf_counter()
        self._done = 0

    def __iter__(self):
        return iter(self._bar)

    def update(self, n_steps: int, current_item=None) -> None:
        self._done += n_steps
        dt = time.perf_counter() - self._t0
        rate = self._done / dt if dt > 0 else 0.0
        self._bar.update(n_steps, f"{rate:.2f} {self._unit}/s")


#: a silent progress (``--quiet`` or no terminal) still reports a stall: no step done for this long
STALL_SECONDS = 120.0


class _Silent:
    """No bar; but when no step has been done for :data:`STALL_SECONDS`, one line on stderr says
    where the run stands (a watcher thread), so a run that hangs is never silent."""

    def __init__(self, iterable, label: str = "", length: int | None = None):
        self._it = iterable
        self._label = label
        self._length = length
        self._done = 0
        self._last = time.monotonic()
        self._stop = None
        if label:
            import threading

            self._stop = threading.Event()
            threading.Thread(target=self._watch, daemon=True).start()

    def __iter__(self):
        for item in (self._it if self._it is not None else ()):
            yield item
            self.update(1)

    def update(self, n_steps: int, current_item=None) -> None:
        self._done += n_steps
        self._last = time.monotonic()

    def _watch(self) -> None:
        while not self._stop.wait(min(10.0, STALL_SECONDS / 4)):
            idle = time.monotonic() - self._last
            if idle >= STALL_SECONDS:
                of = f" of {self._length}" if self._length else ""
                click.echo(f"{self._label}: still running, {self._done}{of} steps done, none in the last "
                           f"{idle:.0f} s", err=True)
                self._last = time.monotonic()

    def stop(self) -> None:
        if self._stop is not None:
            self._stop.set()


def portable_path(path) -> str:
    """A path as written into an output file's header: the same bytes in every checkout.

    Relative to the working directory (normalised, '/' separators) when the file lies under it, else
    the file's name alone, so an absolute path typed in one checkout does not make a header (and a
    golden diff) differ from another's.
    """
    import os
    from pathlib import Path, PurePosixPath

    p = Path(os.path.abspath(path))
    try:
        rel = p.relative_to(Path.cwd().resolve())
    except ValueError:
        try:
            rel = p.relative_to(Path(os.path.abspath(os.getcwd())))
        except ValueError:
            return p.name
    return str(PurePosixPath(*rel.parts))
