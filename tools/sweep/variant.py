"""One variant of a sweep: its folder, its inputs, its run, its metrics, its ``done``.

Layout of ``OUT_DIR/variants/<id>/``::

    params.json    the variant's parameters
    inputs/        stage sweeps: copies of the sweep's ``inputs`` with the overrides written in
    <pipeline>/    pipeline sweeps: a copy of the pipeline folder with the overrides written in
                   (paths into the pipeline's own build folder rebased onto build/)
    out/ | build/  what the stages write ({out}) | the pipeline's build folder (make B=...)
    log.txt        every stage's (or make's) output
    result.json    status, exit code, one-line error, wall time, peak memory, metrics
    done           written atomically last, only after success: the fingerprint of the inputs

:func:`prepare` (run by the client) writes the inputs, only the files whose bytes change, so
make's up-to-date checks see a rerun's untouched inputs as old, and returns the fingerprint;
:func:`cached_result` is the result of a variant already done with that fingerprint (a rerun
skips it); :func:`run_batch` (a Dask task) runs variants one after another, each isolated: an
error is recorded on that variant and the next one runs.
"""
from __future__ import annotations

import contextlib
import csv
import hashlib
import io
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

from inflo.formats.atomic import write_bytes_atomic, write_text_atomic
from inflo.formats.errors import InputError

from .overrides import apply_file_overrides, fill, flag_overrides, set_flag
from .spec import Sweep, Variant, format_value

__all__ = ["variant_dir", "prepare", "cached_result", "run_variant", "run_batch", "entry_point", "one_line_error",
           "failed_result"]

_SKIP = {"__pycache__", ".git"}


def variant_dir(out_dir, v: Variant) -> Path:
    return Path(out_dir) / "variants" / v.id


def output_dir(sweep: Sweep, vdir: Path) -> Path:
    """Where the variant's results are: ``out/`` (stages) or ``build/`` (pipelines)."""
    return vdir / ("build" if sweep.pipeline is not None else "out")


def _collect(src: Path, rel_to: Path) -> dict[str, bytes]:
    out = {}
    if src.is_file():
        out[src.relative_to(rel_to).as_posix()] = src.read_bytes()
        return out
    for p in sorted(src.rglob("*")):
        parts = p.relative_to(rel_to).parts
        if any(x in _SKIP or x.startswith(".") for x in parts) or not p.is_file():
            continue
        out[p.relative_to(rel_to).as_posix()] = p.read_bytes()
    return out


def _rebase(text: str, src_dir: Path, copy_dir: Path, old_build: Path, new_build: Path) -> str:
    """Tokens of ``text`` that are paths into ``old_build`` (relative to ``src_dir``) become the
    same paths under ``new_build`` (relative to ``copy_dir``)."""
    old_build = old_build.resolve()

    def swap(m):
        tok = m.group(0)
        p = Path(os.path.normpath(src_dir / tok)) if not os.path.isabs(tok) else Path(os.path.normpath(tok))
        try:
            rest = p.relative_to(old_build)
        except ValueError:
            return tok
        return os.path.relpath(new_build / rest, copy_dir)

    return re.sub(r"[^\s:=\"',]*/[^\s\"',]*", swap, text)


def _input_files(sweep: Sweep, vdir: Path) -> tuple[Path, dict[str, bytes]]:
    """(the folder the inputs are copied into, relative path -> bytes of the original)."""
    if sweep.pipeline is not None:
        pl = sweep.pipeline
        return vdir / pl.path.name, _collect(pl.path, pl.path)
    files: dict[str, bytes] = {}
    for rel in sweep.inputs:
        files.update(_collect(sweep.folder / rel, sweep.folder))
    return vdir / "inputs", files


def prepare(sweep: Sweep, out_dir, v: Variant) -> str:
    """Write the variant's inputs and ``params.json`` (only what changes); return its fingerprint.

    Raises :class:`InputError` when an override cannot be written (the variant fails with it)."""
    vdir = variant_dir(out_dir, v)
    dest, files = _input_files(sweep, vdir)
    targets = {t.file for t, _ in v.overrides if t.kind in ("toml", "fcc")}
    texts = {}
    for rel in targets:
        try:
            texts[rel] = files[rel].decode("utf-8")
        except (KeyError, UnicodeDecodeError):
            raise InputError(f"{rel}: not a text file of the inputs") from None
    where = (lambda rel: f"{sweep.pipeline.path / rel}") if sweep.pipeline else (lambda rel: f"{sweep.folder / rel}")
    texts = apply_file_overrides(texts, v.overrides, where)
    for rel, t in texts.items():
        files[rel] = t.encode("utf-8")
    if sweep.pipeline is not None and sweep.pipeline.build is not None:
        pl = sweep.pipeline
        for rel in list(files):
            if Path(rel).suffix in pl.rebase:
                text = files[rel].decode("utf-8", errors="surrogateescape")
                files[rel] = _rebase(text, (pl.path / rel).parent, (dest / rel).parent, pl.build,
                                     (vdir / "build").resolve()).encode("utf-8", errors="surrogateescape")
    h = hashlib.sha1()
    for rel in sorted(files):
        h.update(rel.encode() + b"\0" + hashlib.sha1(files[rel]).digest())
        target = dest / rel
        try:
            same = target.read_bytes() == files[rel]
        except OSError:
            same = False
        if not same:
            write_bytes_atomic(target, files[rel])
            mode = os.stat(sweep.pipeline.path / rel if sweep.pipeline else sweep.folder / rel).st_mode
            os.chmod(target, mode & 0o777)
    params = json.dumps({"id": v.id, "index": v.index, "params": dict(v.params),
                         "overrides": {str(t): val for t, val in v.overrides}}, indent=1, sort_keys=True) + "\n"
    p = vdir / "params.json"
    if not p.exists() or p.read_text() != params:
        write_text_atomic(p, params)
    h.update(params.encode())
    h.update(json.dumps(_commands(sweep, out_dir, v)).encode())
    return h.hexdigest()


def cached_result(sweep: Sweep, out_dir, v: Variant, fingerprint: str) -> dict | None:
    """The recorded result of a variant done before with these inputs, or None."""
    vdir = variant_dir(out_dir, v)
    try:
        if (vdir / "done").read_text().strip() != fingerprint:
            return None
        res = json.loads((vdir / "result.json").read_text())
    except (OSError, ValueError):
        return None
    if res.get("status") != "ok":
        return None
    res["ran"] = "cached"
    return res


# ---------------------------------------------------------------------------------------------
# running

def _values(sweep: Sweep, out_dir, v: Variant) -> dict:
    vdir = variant_dir(out_dir, v).resolve()
    vals = dict(v.params)
    vals.update(out=str(vdir / "out"), inputs=str(vdir / "inputs"), variant=str(vdir), id=v.id, index=v.index,
                sweep_dir=str(sweep.folder))
    return vals


def _commands(sweep: Sweep, out_dir, v: Variant) -> list[list[str]]:
    """The command lines the variant runs (stage CLIs with their arguments, or make)."""
    if sweep.pipeline is not None:
        pl = sweep.pipeline
        vdir = variant_dir(out_dir, v).resolve()
        cmd = [pl.make, "-C", str(vdir / pl.path.name), f"-j{pl.jobs}", f"{pl.build_var}={vdir / 'build'}"]
        if pl.root_var and pl.root is not None:
            cmd.append(f"{pl.root_var}={pl.root}")
        makevars = dict(pl.vars)
        makevars.update({t.key: format_value(val) for t, val in v.overrides if t.kind == "make"})
        cmd += [f"{k}={val}" for k, val in makevars.items()]
        return [cmd + list(pl.targets)]
    vals = _values(sweep, out_dir, v)
    out = []
    for st in sweep.stages:
        args = [fill(a, vals) for a in st.args]
        for t, val in flag_overrides(v.overrides, st.name):
            args = set_flag(args, t.key, val)
        out.append([st.cli, *args])
    return out


class _ThreadStreams:
    """sys.stdout / sys.stderr stand-in: a thread that is capturing writes to its own buffer, every
    other thread to the real stream (Dask runs tasks in threads of the worker process)."""

    def __init__(self, real):
        self._real = real
        self._local = threading.local()

    def capture(self, buf):
        self._local.buf = buf

    def release(self):
        self._local.buf = None

    def _target(self):
        return getattr(self._local, "buf", None) or self._real

    def write(self, s):
        return self._target().write(s)

    def flush(self):
        return self._target().flush()

    def isatty(self):
        return False if getattr(self._local, "buf", None) else self._real.isatty()

    def __getattr__(self, name):
        return getattr(self._target(), name)


_install_lock = threading.Lock()


@contextlib.contextmanager
def _captured(buf):
    with _install_lock:
        for name in ("stdout", "stderr"):
            if not isinstance(getattr(sys, name), _ThreadStreams):
                setattr(sys, name, _ThreadStreams(getattr(sys, name)))
    sys.stdout.capture(buf)
    sys.stderr.capture(buf)
    try:
        yield
    finally:
        sys.stdout.release()
        sys.stderr.release()


def entry_point(cli: str):
    """The click command of console script ``cli``; :class:`InputError` when there is none."""
    from importlib.metadata import entry_points

    eps = entry_points(group="console_scripts", name=cli)
    for ep in eps:
        return ep.load()
    raise InputError(f"no console script {cli!r} is installed")


def _peak_reset() -> None:
    with contextlib.suppress(OSError):
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")


def _peak_mb_self() -> float:
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _run_inprocess(cli: str, args: list[str]) -> tuple[int, str, float]:
    import click

    buf = io.StringIO()
    _peak_reset()
    with _captured(buf):
        try:
            cmd = entry_point(cli)
            rv = cmd.main(args=list(args), prog_name=cli, standalone_mode=False)
            code = rv if isinstance(rv, int) else 0
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
            if not isinstance(exc.code, (int, type(None))):
                buf.write(f"{exc.code}\n")
        except click.exceptions.ClickException as exc:
            buf.write(f"{cli}: error: {exc.format_message()}\n")
            code = exc.exit_code
        except click.exceptions.Abort:
            buf.write(f"{cli}: aborted\n")
            code = 1
        except InputError as exc:
            buf.write(f"{cli}: error: {exc}\n")
            code = 2
        except Exception as exc:
            buf.write(f"{cli}: failed: {type(exc).__name__}: {exc}\n")
            code = 1
    return code, buf.getvalue(), _peak_mb_self()


def _run_subprocess(cmd: list[str], timeout: float, env=None) -> tuple[int, str, float]:
    """Run ``cmd`` in its own process group; (exit code, output, peak RSS of it and its children)."""
    import tempfile

    exe = shutil.which(cmd[0], path=os.pathsep.join([os.path.dirname(sys.executable), os.environ.get("PATH", "")]))
    if exe is None:
        return 127, f"{cmd[0]}: command not found\n", 0.0
    with tempfile.TemporaryFile("w+", encoding="utf-8", errors="replace") as log:
        p = subprocess.Popen([exe, *cmd[1:]], stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                             env=env, start_new_session=True)
        timer = None
        timed_out = []
        if timeout > 0:
            def kill():
                timed_out.append(True)
                with contextlib.suppress(ProcessLookupError):
                    os.killpg(p.pid, 9)
            timer = threading.Timer(timeout, kill)
            timer.start()
        try:
            _, status, ru = os.wait4(p.pid, 0)
        except BaseException:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(p.pid, 9)
            raise
        finally:
            if timer is not None:
                timer.cancel()
        p.returncode = code = os.waitstatus_to_exitcode(status)
        log.seek(0)
        text = log.read()
    if timed_out:
        text += f"{cmd[0]}: timed out after {timeout:g} s\n"
        code = 124
    return code, text, ru.ru_maxrss / 1024.0


_MAKE_LINE = re.compile(r"^(g?make(\[\d+\])?:|Traceback|\s)")


def one_line_error(text: str, code: int) -> str:
    """The line that says why: the last ``...: error: ...`` / ``...: failed: ...`` line, else the
    last line that is not make's own, else the exit code."""
    lines = [ln.rstrip() for ln in text.splitlines() if ln.strip()]
    tagged = [ln for ln in lines if re.search(r": (error|failed):", ln)]
    if tagged:
        return tagged[-1]
    plain = [ln for ln in lines if not _MAKE_LINE.match(ln)]
    if plain:
        return plain[-1]
    return lines[-1] if lines else f"exit code {code}"


def _number(text: str):
    s = text.strip()
    for conv in (int, float):
        try:
            return conv(s)
        except ValueError:
            pass
    return s


def read_metrics(sweep: Sweep, vdir: Path, logs: dict[str, str]) -> dict:
    """Every metric of the sweep for a finished variant (missing ones: ``""``)."""
    out = {}
    base = output_dir(sweep, vdir)
    for m in sweep.metrics:
        value = ""
        try:
            if m.log is not None:
                text = logs.get(m.log, "")
            elif m.column is None:
                text = (base / m.file).read_text(encoding="utf-8", errors="replace")
            if m.regex is not None:
                found = list(re.finditer(m.regex, text, re.MULTILINE))
                if found:
                    g = found[-1]
                    value = _number(g.group(1) if g.groups() else g.group(0))
            elif m.count is not None:
                pat = re.compile(m.count)
                value = sum(1 for ln in text.splitlines() if pat.search(ln))
            else:
                with open(base / m.file, newline="", encoding="utf-8") as fh:
                    rows = [r for r in csv.DictReader(row for row in fh if not row.startswith("#"))]
                vals = [_number(r[m.column]) for r in rows if r.get(m.column, "") != ""]
                nums = [x for x in vals if isinstance(x, (int, float))]
                if m.reduce == "last":
                    value = vals[-1] if vals else ""
                elif nums:
                    value = {"sum": sum, "max": max, "min": min}[m.reduce](nums)
        except (OSError, KeyError, ValueError):
            value = ""
        out[m.name] = value
    return out


def failed_result(v: Variant, error: str, code: int, wall: float = 0.0, peak: float = 0.0) -> dict:
    return {"index": v.index, "id": v.id, "params": [[k, val] for k, val in v.params], "status": "failed",
            "ran": "ran", "exit_code": code, "error": error, "wall_s": round(wall, 3), "peak_mb": round(peak, 1),
            "metrics": {}, "still": "", "worker": f"{socket.gethostname()}:{os.getpid()}"}


def run_variant(sweep: Sweep, out_dir, v: Variant, fingerprint: str) -> dict:
    """Run one prepared variant; never raises for a failure of the variant itself."""
    vdir = variant_dir(out_dir, v)
    with contextlib.suppress(FileNotFoundError):
        (vdir / "done").unlink()
    t0 = time.perf_counter()
    logs: dict[str, str] = {}
    peak = 0.0
    code, error = 0, ""
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([os.path.dirname(sys.executable), env.get("PATH", "")])
    try:
        commands = _commands(sweep, out_dir, v)
        if sweep.pipeline is not None:
            (vdir / "build").mkdir(parents=True, exist_ok=True)
            code, text, peak = _run_subprocess(commands[0], sweep.timeout, env)
            logs["make"] = text
            if code != 0:
                error = one_line_error(text, code)
        else:
            out = vdir / "out"
            if out.exists():  # a half-finished earlier run: start over
                shutil.rmtree(out)
            out.mkdir(parents=True)
            for st, cmd in zip(sweep.stages, commands):
                if st.subprocess:
                    code, text, pk = _run_subprocess(cmd, sweep.timeout, env)
                else:
                    code, text, pk = _run_inprocess(cmd[0], cmd[1:])
                logs[st.name] = text
                peak = max(peak, pk)
                if code != 0:
                    line = one_line_error(text, code)
                    error = line if line.startswith(st.cli) else f"{st.name}: {line}"
                    break
    except Exception as exc:
        code = code or 1
        error = f"{type(exc).__name__}: {exc}"
    wall = time.perf_counter() - t0
    write_text_atomic(vdir / "log.txt", "".join(f"== {k}\n{t}" for k, t in logs.items()))
    if code != 0 or error:
        res = failed_result(v, error or f"exit code {code}", code or 1, wall, peak)
    else:
        res = failed_result(v, "", 0, wall, peak)
        res["status"] = "ok"
        res["metrics"] = read_metrics(sweep, vdir, logs)
        if sweep.still:
            still = output_dir(sweep, vdir) / sweep.still
            if still.is_file():
                res["still"] = os.path.relpath(still, out_dir)
    write_text_atomic(vdir / "result.json", json.dumps(res, indent=1, sort_keys=True) + "\n")
    if res["status"] == "ok":
        write_text_atomic(vdir / "done", fingerprint + "\n")
    return res


def run_batch(sweep: Sweep, out_dir: str, items: list[tuple[Variant, str]]) -> list[dict]:
    """A Dask task: the variants of one batch, one after another, each isolated."""
    out = []
    for v, fp in items:
        try:
            out.append(run_variant(sweep, out_dir, v, fp))
        except Exception as exc:
            out.append(failed_result(v, f"{type(exc).__name__}: {exc}", 1))
    return out
