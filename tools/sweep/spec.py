"""Sweep files (formats/sweep.md): parsing into frozen dataclasses, and the variants.

A sweep names either a pipeline folder (``[pipeline]``: a copy of the folder per variant, its own
``make`` with the build folder variable pointing into the variant) or a chain of CLI stages
(``[[stage]]``: run in the worker's process), a base parameter set (``[base]``) and axes
(``[axes]``) over parameters of the inputs: TOML keys, ``.fcc`` keys, CLI flags, make variables.
Variants are the grid of the axes or random samples with a seed.

Every check runs before anything is written; bad input raises
:class:`~inflo.formats.errors.FormatError` naming the sweep file's line.
"""
from __future__ import annotations

import hashlib
import itertools
import json
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from inflo.formats.errors import FormatError, did_you_mean, parse_toml, shorten
from inflo.formats.toml_params import LineStyle, line_of, read_toml_text, unknown_name

__all__ = ["Target", "Axis", "Stage", "Pipeline", "Metric", "Sweep", "Variant", "parse_sweep", "read_sweep",
           "variants", "parse_target", "format_value"]

MAX_VARIANTS = 1_000_000

#: the longest ``[sweep] timeout``: about 116 days (a finite number a timer can wait)
MAX_TIMEOUT = 10_000_000

#: the options by which an inflo CLI names what it writes
OUTPUT_FLAGS = ("-o", "--output")


@dataclass(frozen=True)
class Target:
    """Where a parameter goes.

    kind: ``"toml"`` (``file`` + dotted ``key``), ``"fcc"`` (``file`` + ``key``, a ``key: value``
    line), ``"flag"`` (``stage`` + ``key`` = the flag with its dashes), ``"make"`` (``key`` = a
    make variable of the pipeline).
    """

    kind: str
    key: str
    file: str | None = None
    stage: str | None = None

    def __str__(self) -> str:
        if self.kind in ("toml", "fcc"):
            return f"{self.file}:{self.key}"
        if self.kind == "make":
            return f"make:{self.key}"
        return f"{self.stage}:{self.key}" if self.stage else self.key


@dataclass(frozen=True)
class Axis:
    """One swept parameter: its name (a column of results.csv), target, and its values (a tuple:
    grid points or the choices of random sampling) or ``uniform`` bounds (random sampling only)."""

    name: str
    target: Target
    values: tuple = ()
    uniform: tuple | None = None


@dataclass(frozen=True)
class Stage:
    """One CLI run of a stage sweep: ``cli`` (a console script), ``args`` with ``{...}``
    placeholders, run in the worker's process unless ``subprocess``."""

    name: str
    cli: str
    args: tuple[str, ...]
    subprocess: bool = False


@dataclass(frozen=True)
class Pipeline:
    """A pipeline folder copied per variant and built there by ``make``."""

    path: Path
    targets: tuple[str, ...] = ()
    vars: tuple[tuple[str, str], ...] = ()
    build_var: str = "B"
    build: Path | None = None
    root_var: str = "ROOT"
    root: Path | None = None
    rebase: tuple[str, ...] = (".fcc",)
    jobs: int = 1
    make: str = "make"


@dataclass(frozen=True)
class Metric:
    """A number (or text) read after a variant succeeded: from a stage's captured output (``log``:
    a stage name, or ``"make"``) or a file of the variant's build folder (``file``); by ``regex``
    (its first group of the last match), ``count`` (lines matching), or ``column`` of a CSV file
    reduced by ``reduce`` (last, sum, max, min)."""

    name: str
    log: str | None = None
    file: str | None = None
    regex: str | None = None
    count: str | None = None
    column: str | None = None
    reduce: str = "last"


@dataclass(frozen=True)
class Sweep:
    path: Path
    name: str
    sampling: str = "grid"
    samples: int = 0
    seed: int = 0
    batch: int = 0
    still: str | None = None
    heatmap: str | None = None
    contact_sheet: int = 64
    inputs: tuple[str, ...] = ()
    base: tuple[tuple[Target, object], ...] = ()
    axes: tuple[Axis, ...] = ()
    stages: tuple[Stage, ...] = ()
    pipeline: Pipeline | None = None
    metrics: tuple[Metric, ...] = ()
    timeout: float = 0.0

    @property
    def folder(self) -> Path:
        return self.path.resolve().parent


@dataclass(frozen=True)
class Variant:
    """One variant: its position in the sweep, its folder name, its parameters (axis name ->
    value, in axis order) and the overrides they and ``[base]`` make."""

    index: int
    id: str
    params: tuple[tuple[str, object], ...]
    overrides: tuple[tuple[Target, object], ...] = field(repr=False, default=())

    def label(self) -> str:
        return ", ".join(f"{k}={format_value(v)}" for k, v in self.params)


# ---------------------------------------------------------------------------------------------
# parsing

_SECTIONS = {
    "sweep": {"name", "sampling", "samples", "seed", "batch", "still", "heatmap", "contact_sheet", "inputs",
              "timeout"},
    "pipeline": {"path", "targets", "vars", "build_var", "build", "root_var", "root", "rebase", "jobs", "make"},
    "base": None,
    "axes": None,
    "stage": {"name", "cli", "args", "subprocess"},
    "metrics": None,
}
_AXIS_KEYS = {"target", "values", "range", "linspace", "uniform"}
_METRIC_KEYS = {"log", "file", "regex", "count", "column", "reduce"}


#: how a sweep file's lines are found: ``[table]``/``[[table]]`` headers named whole (dots kept), a
#: header ``[section.key]`` as the key's line, keys of the ``nth`` ``[[stage]]`` (0: of any)
LINES = LineStyle(brackets="pair", dotted=False, subtables=True)


def _line_of(text: str, section: str | None, key: str | None, nth: int = 0) -> int | None:
    """1-based line of ``key`` inside ``[section]`` (or ``[section.key]``, or the header), best effort."""
    return line_of(text, section, key, LINES, nth)


def parse_target(spec: str, stages: tuple[str, ...], pipeline: bool, path, line) -> Target:
    """``FILE.toml:table.key``, ``FILE.fcc:key``, ``STAGE:--flag``, ``--flag`` (one stage),
    ``make:VAR`` (pipelines)."""
    expected = ("a parameter target 'FILE.toml:table.key', 'FILE.fcc:key'"
                + (", 'make:VAR'" if pipeline else ", 'STAGE:--flag' or '--flag'"))
    s = spec.strip()
    if s.startswith("-"):
        if pipeline:
            raise FormatError(path, line, "a make variable 'make:VAR' or a file key in a pipeline sweep "
                              "(CLI flags belong to stage sweeps)", shorten(spec))
        if len(stages) != 1:
            raise FormatError(path, line, f"'STAGE:{s}' naming one of {list(stages)}", shorten(spec))
        return Target("flag", s, stage=stages[0])
    if ":" not in s:
        raise FormatError(path, line, expected, shorten(spec))
    head, key = s.split(":", 1)
    head, key = head.strip(), key.strip()
    if not key:
        raise FormatError(path, line, expected, shorten(spec))
    if head == "make":
        if not pipeline:
            raise FormatError(path, line, "make variables only in a pipeline sweep", shorten(spec))
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", key):
            raise FormatError(path, line, "a make variable name", shorten(key))
        return Target("make", key)
    if head.endswith(".toml"):
        if not all(part.strip() for part in key.split(".")):
            raise FormatError(path, line, "a dotted TOML key 'table.key'", shorten(key))
        return Target("toml", key, file=head)
    if head.endswith(".fcc"):
        return Target("fcc", " ".join(key.split()), file=head)
    if key.startswith("-") and not pipeline:
        if head not in stages:
            raise FormatError(path, line, f"a stage name of {list(stages)}{did_you_mean(head, stages)}",
                              shorten(head))
        return Target("flag", key, stage=head)
    raise FormatError(path, line, expected, shorten(spec))


def _scalar(v) -> bool:
    return isinstance(v, (bool, int, float, str))


def _number_list(v, n, what, path, line):
    if not (isinstance(v, list) and len(v) == n and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                       for x in v)):
        raise FormatError(path, line, what, shorten(repr(v)))
    if not all(math.isfinite(x) for x in v):
        raise FormatError(path, line, f"{what}, finite", shorten(repr(v)))
    return v


def _range_values(v, path, line) -> tuple:
    start, stop, step = _number_list(v, 3, "range = [start, stop, step] (stop included)", path, line)
    if step == 0 or (stop - start) * step < 0:
        raise FormatError(path, line, "a step that goes from start towards stop", shorten(repr(v)))
    n = int(math.floor((stop - start) / step + 1e-9)) + 1
    if n > MAX_VARIANTS:
        raise FormatError(path, line, f"at most {MAX_VARIANTS} values", f"{n}")
    if all(isinstance(x, int) for x in v):
        return tuple(start + i * step for i in range(n))
    return tuple(float(f"{start + i * step:.12g}") for i in range(n))


def _linspace_values(v, path, line) -> tuple:
    start, stop, count = _number_list(v, 3, "linspace = [start, stop, count]", path, line)
    if not (isinstance(count, int) and 1 <= count <= MAX_VARIANTS):
        raise FormatError(path, line, f"a count in [1, {MAX_VARIANTS}]", shorten(repr(count)))
    if count == 1:
        return (start,)
    return tuple(float(f"{start + (stop - start) * i / (count - 1):.12g}") for i in range(count))


def _parse_axis(name, raw, stages, pipeline, text, path) -> Axis:
    line = _line_of(text, "axes", name)
    if isinstance(raw, list):
        table = {"target": name, "values": raw}
    elif isinstance(raw, dict):
        table = raw
        for k in table:
            if k not in _AXIS_KEYS:
                raise unknown_name(path, line, "a key of an axis", k, _AXIS_KEYS)
    else:
        raise FormatError(path, line, f"axis {name!r} as a list of values or a table with target and "
                          "values, range, linspace or uniform", shorten(repr(raw)))
    target = table.get("target", name)
    if not isinstance(target, str):
        raise FormatError(path, line, "target as a string", shorten(repr(target)))
    tgt = parse_target(target, stages, pipeline, path, line)
    given = [k for k in ("values", "range", "linspace", "uniform") if k in table]
    if len(given) != 1:
        raise FormatError(path, line, f"exactly one of values, range, linspace, uniform for axis {name!r}",
                          ", ".join(given) or "none")
    kind = given[0]
    v = table[kind]
    if kind == "values":
        if not (isinstance(v, list) and v and all(_scalar(x) for x in v)):
            raise FormatError(path, line, "values as a non-empty list of numbers, strings or booleans",
                              shorten(repr(v)))
        if any(isinstance(x, float) and not math.isfinite(x) for x in v):
            raise FormatError(path, line, "finite values", shorten(repr(v)))
        if any(isinstance(x, str) and not x.isprintable() for x in v):
            raise FormatError(path, line, "values on one line (no line breaks or other control characters)",
                              shorten(repr(v)))
        return Axis(name, tgt, tuple(v))
    if kind == "range":
        return Axis(name, tgt, _range_values(v, path, line))
    if kind == "linspace":
        return Axis(name, tgt, _linspace_values(v, path, line))
    lo, hi = _number_list(v, 2, "uniform = [low, high]", path, line)
    if not lo <= hi:
        raise FormatError(path, line, "uniform = [low, high] with low <= high", shorten(repr(v)))
    return Axis(name, tgt, (), (lo, hi))


def _str(table, key, path, line, default=None):
    v = table.get(key, default)
    if v is not None and not isinstance(v, str):
        raise FormatError(path, line, f"{key} as a string", shorten(repr(v)))
    return v


def _int(table, key, path, line, default, lo=0):
    v = table.get(key, default)
    if isinstance(v, bool) or not isinstance(v, int) or v < lo:
        raise FormatError(path, line, f"{key} as an integer >= {lo}", shorten(repr(v)))
    return v


def _strlist(table, key, path, line):
    v = table.get(key, [])
    if not (isinstance(v, list) and all(isinstance(x, str) for x in v)):
        raise FormatError(path, line, f"{key} as a list of strings", shorten(repr(v)))
    return tuple(v)


def parse_sweep(text: str, path="<sweep>") -> Sweep:
    """Parse and check a sweep file's text; see formats/sweep.md."""
    path = Path(os.fspath(path))
    raw = parse_toml(text, path)
    for section, table in raw.items():
        if section not in _SECTIONS:
            raise unknown_name(path, _line_of(text, section, None), f"a section of {list(_SECTIONS)}", section,
                               _SECTIONS, found=f"[{section}]")
        if section == "stage":
            if not (isinstance(table, list) and all(isinstance(t, dict) for t in table)):
                raise FormatError(path, _line_of(text, section, None), "[[stage]] tables", shorten(repr(table)))
            tables = table
        else:
            if not isinstance(table, dict):
                raise FormatError(path, _line_of(text, section, None), f"[{section}] as a table",
                                  shorten(repr(table)))
            tables = [table]
        keys = _SECTIONS[section]
        if keys is None:
            continue
        for nth, t in enumerate(tables):
            for k in t:
                if k not in keys:
                    raise unknown_name(path, _line_of(text, section, k, nth), f"a key of [{section}]", k, keys)
    sw = raw.get("sweep", {})
    L = lambda key, section="sweep", nth=0: _line_of(text, section, key, nth)
    if "stage" in raw and "pipeline" in raw:
        raise FormatError(path, _line_of(text, "stage", None), "either [pipeline] or [[stage]] tables, not both",
                          "both")
    if "stage" not in raw and "pipeline" not in raw:
        raise FormatError(path, None, "a [pipeline] table or [[stage]] tables", "neither")
    folder = path.resolve().parent

    stages: list[Stage] = []
    for nth, t in enumerate(raw.get("stage", [])):
        cli = _str(t, "cli", path, L("cli", "stage", nth))
        if not cli or not re.fullmatch(r"[A-Za-z0-9_.-]+", cli):
            raise FormatError(path, L("cli", "stage", nth) or L(None, "stage", nth),
                              "cli = the name of a console script (e.g. 'dimorph')", shorten(repr(cli)))
        name = _str(t, "name", path, L("name", "stage", nth), cli)
        if name in {s.name for s in stages} or name == "make":
            raise FormatError(path, L("name", "stage", nth) or L(None, "stage", nth),
                              "a stage name of its own (give name = ...)", repr(name))
        args = t.get("args", [])
        if not (isinstance(args, list) and all(isinstance(a, (str, int, float)) and not isinstance(a, bool)
                                               for a in args)):
            raise FormatError(path, L("args", "stage", nth), "args as a list of strings", shorten(repr(args)))
        sub = t.get("subprocess", False)
        if not isinstance(sub, bool):
            raise FormatError(path, L("subprocess", "stage", nth), "subprocess = true or false", shorten(repr(sub)))
        stages.append(Stage(name, cli, tuple(str(a) for a in args), sub))
    stage_names = tuple(s.name for s in stages)

    pipeline = None
    if "pipeline" in raw:
        t = raw["pipeline"]
        p = _str(t, "path", path, L("path", "pipeline"))
        if not p:
            raise FormatError(path, L(None, "pipeline"), "path = the pipeline folder", "no path")
        ppath = (folder / p).resolve()
        if not (ppath / "Makefile").is_file():
            raise FormatError(path, L("path", "pipeline"), "a pipeline folder holding a Makefile", repr(p))
        vars_ = t.get("vars", {})
        if not (isinstance(vars_, dict) and all(_scalar(v) for v in vars_.values())):
            raise FormatError(path, L("vars", "pipeline"), "vars as a table of make variables", shorten(repr(vars_)))
        root = _str(t, "root", path, L("root", "pipeline"))
        if root is None:
            rootp = next((q for q in ppath.parents if (q / "pyproject.toml").is_file()), ppath.parent.parent)
        else:
            rootp = (folder / root).resolve()
        build = _str(t, "build", path, L("build", "pipeline"))
        buildp = (folder / build).resolve() if build else rootp / "build" / ppath.name
        pipeline = Pipeline(
            path=ppath, targets=_strlist(t, "targets", path, L("targets", "pipeline")),
            vars=tuple((str(k), format_value(v)) for k, v in vars_.items()),
            build_var=_str(t, "build_var", path, L("build_var", "pipeline"), "B"), build=buildp,
            root_var=_str(t, "root_var", path, L("root_var", "pipeline"), "ROOT"), root=rootp,
            rebase=_strlist(t, "rebase", path, L("rebase", "pipeline")) if "rebase" in t else (".fcc",),
            jobs=_int(t, "jobs", path, L("jobs", "pipeline"), 1, 1),
            make=_str(t, "make", path, L("make", "pipeline"), "make"))

    is_pipe = pipeline is not None
    base = []
    for k, v in raw.get("base", {}).items():
        line = _line_of(text, "base", k)
        if not _scalar(v):
            raise FormatError(path, line, "a number, string or boolean", shorten(repr(v)))
        if isinstance(v, str) and not v.isprintable():
            raise FormatError(path, line, "a value on one line (no line breaks or other control characters)",
                              shorten(repr(v)))
        base.append((parse_target(k, stage_names, is_pipe, path, line), v))
    axes = tuple(_parse_axis(k, v, stage_names, is_pipe, text, path) for k, v in raw.get("axes", {}).items())
    seen_targets: dict[Target, str] = {}
    for a in axes:
        if a.target in seen_targets:
            raise FormatError(path, _line_of(text, "axes", a.name), "each target swept by one axis",
                              f"{a.target} in {seen_targets[a.target]!r} and {a.name!r}")
        seen_targets[a.target] = a.name

    metrics = []
    for k, v in raw.get("metrics", {}).items():
        line = _line_of(text, "metrics", k)
        if not isinstance(v, dict):
            raise FormatError(path, line, "a metric as a table (log or file, and regex, count or column)",
                              shorten(repr(v)))
        for kk in v:
            if kk not in _METRIC_KEYS:
                raise unknown_name(path, line, "a key of a metric", kk, _METRIC_KEYS)
        m = Metric(k, **{kk: v[kk] for kk in v})
        if not all(isinstance(getattr(m, f), (str, type(None))) for f in _METRIC_KEYS):
            raise FormatError(path, line, "metric keys as strings", shorten(repr(v)))
        if (m.log is None) == (m.file is None):
            raise FormatError(path, line, "exactly one of log (a stage name or 'make') and file", shorten(repr(v)))
        if m.log is not None and m.log not in (stage_names if not is_pipe else ("make",)):
            choices = stage_names if not is_pipe else ("make",)
            raise FormatError(path, line, f"log = one of {list(choices)}", repr(m.log))
        if sum(x is not None for x in (m.regex, m.count, m.column)) != 1:
            raise FormatError(path, line, "exactly one of regex, count, column", shorten(repr(v)))
        if m.column is not None and m.file is None:
            raise FormatError(path, line, "column with file = a CSV file", shorten(repr(v)))
        if m.reduce not in ("last", "sum", "max", "min"):
            raise FormatError(path, line, "reduce = last, sum, max or min", repr(m.reduce))
        for pat in (m.regex, m.count):
            if pat is not None:
                try:
                    re.compile(pat, re.MULTILINE)
                except re.error as exc:
                    raise FormatError(path, line, "a valid regular expression", f"{pat!r} ({exc})") from None
        metrics.append(m)

    sampling = _str(sw, "sampling", path, L("sampling"), "grid")
    if sampling not in ("grid", "random"):
        raise FormatError(path, L("sampling"), "sampling = 'grid' or 'random'", repr(sampling))
    samples = _int(sw, "samples", path, L("samples"), 0, 0)
    if sampling == "random" and not 1 <= samples <= MAX_VARIANTS:
        raise FormatError(path, L("samples") or L(None), f"samples in [1, {MAX_VARIANTS}] with sampling = 'random'",
                          repr(samples))
    if sampling == "grid":
        for a in axes:
            if a.uniform is not None:
                raise FormatError(path, _line_of(text, "axes", a.name),
                                  "values, range or linspace (uniform needs sampling = 'random')", "uniform")
        total = math.prod(len(a.values) for a in axes) if axes else 1
        if total > MAX_VARIANTS:
            raise FormatError(path, L(None, "axes"), f"at most {MAX_VARIANTS} variants", f"{total}")
    timeout = sw.get("timeout", 0)
    if isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or not 0 <= timeout <= MAX_TIMEOUT:
        raise FormatError(path, L("timeout"), f"timeout in seconds in [0, {MAX_TIMEOUT}] (0: none)",
                          shorten(repr(timeout)))
    numeric_metric = [m.name for m in metrics]
    heatmap = _str(sw, "heatmap", path, L("heatmap"))
    if heatmap is not None and heatmap not in numeric_metric:
        raise FormatError(path, L("heatmap"), f"heatmap = a metric name of {numeric_metric}", repr(heatmap))
    inputs = _strlist(sw, "inputs", path, L("inputs"))
    if is_pipe and inputs:
        raise FormatError(path, L("inputs"), "no inputs in a pipeline sweep (the pipeline folder is copied)",
                          shorten(repr(list(inputs))))
    for rel in inputs:
        if os.path.isabs(rel) or ".." in Path(rel).parts or not (folder / rel).exists():
            raise FormatError(path, L("inputs"), "input files or folders under the sweep file's folder",
                              repr(rel))
    still = _str(sw, "still", path, L("still"))
    if still is not None and not _relative_inside(still):
        raise FormatError(path, L("still"), "still as a path inside the variant's out/ or build/ folder", repr(still))
    for m in metrics:
        if m.file is not None and not _relative_inside(m.file):
            raise FormatError(path, _line_of(text, "metrics", m.name),
                              "a metric's file inside the variant's out/ or build/ folder", repr(m.file))
    if is_pipe:
        bv = pipeline.build_var
        if bv in dict(pipeline.vars):
            raise FormatError(path, L("vars", "pipeline"), f"make variables other than {bv} (each variant's "
                              f"build folder)", bv)
        for t, _ in base + [(a.target, None) for a in axes]:
            if t.kind == "make" and t.key == bv:
                raise FormatError(path, None, f"make targets other than make:{bv} (each variant's build folder)",
                                  repr(str(t)))
    for nth, st in enumerate(stages):
        _check_stage_paths(st, base, axes, inputs, folder, path, L("args", "stage", nth) or L(None, "stage", nth))
    for t, _ in base + [(a.target, None) for a in axes]:
        if t.kind in ("toml", "fcc"):
            where = pipeline.path if is_pipe else folder
            if is_pipe:
                ok = (where / t.file).is_file()
            else:
                ok = any(t.file == rel or t.file.startswith(rel.rstrip("/") + "/") for rel in inputs) \
                    and (folder / t.file).is_file()
            if not ok:
                where_s = "the pipeline folder" if is_pipe else "[sweep] inputs"
                raise FormatError(path, None, f"a file of {where_s} for target {str(t)!r}", repr(t.file))
    return Sweep(
        path=path, name=_str(sw, "name", path, L("name"), path.stem), sampling=sampling, samples=samples,
        seed=_int(sw, "seed", path, L("seed"), 0, 0), batch=_int(sw, "batch", path, L("batch"), 0, 0),
        still=still, heatmap=heatmap,
        contact_sheet=_int(sw, "contact_sheet", path, L("contact_sheet"), 64, 0), inputs=inputs,
        base=tuple(base), axes=axes, stages=tuple(stages), pipeline=pipeline, metrics=tuple(metrics),
        timeout=float(timeout))


def _relative_inside(rel: str) -> bool:
    """A relative path that stays inside its folder (no absolute path, no ``..`` above it)."""
    norm = os.path.normpath(rel)
    return bool(rel) and not os.path.isabs(rel) and not rel.startswith("~") and norm != ".." \
        and not norm.startswith("../")


#: the variant's folder while a stage's paths are checked (no real path holds a NUL)
_VARIANT = "/\0variant"

#: the most argument lists of one stage checked value by value (the axes it uses); beyond, each axis alone
_MAX_CHECKED = 10_000


def _check_stage_paths(st: Stage, base, axes, inputs, folder: Path, path, line) -> None:
    """A stage writes only inside the variant's folder: the value of ``-o``/``--output`` must lie
    there (``{out}``, ``{variant}``, ``{inputs}``), and every other argument that is a path (it
    holds a ``/``, or is ``~``, ``.`` or ``..``; ``NAME=PATH`` too) there or in one of ``[sweep]
    inputs`` (read, not written); relative paths are the working folder's. Checked for every value
    of the axes the stage's arguments and flags use, with the ``[base]`` flags; bad input otherwise."""
    import string

    from .overrides import fill, set_flag

    try:
        fields = {f for a in st.args for _, f, _, _ in string.Formatter().parse(a) if f is not None}
    except ValueError:
        return  # an argument that is no format string: named later (check_placeholders)
    used = [a for a in axes if a.name in fields or (a.target.kind == "flag" and a.target.stage == st.name)]
    choices = [a.values if a.uniform is None else a.uniform for a in used]
    combos = itertools.product(*choices) if math.prod(len(c) for c in choices) <= _MAX_CHECKED else \
        [tuple(c[k] if j == i else c[0] for j, c in enumerate(choices)) for i, cs in enumerate(choices)
         for k in range(min(len(cs), _MAX_CHECKED))]
    fixed = {"out": _VARIANT + "/out", "inputs": _VARIANT + "/inputs", "variant": _VARIANT, "id": "id",
             "index": "0", "sweep_dir": str(folder)}
    readable = [os.path.normpath(folder / rel) for rel in inputs]
    cwd = os.getcwd()

    def resolve(p: str) -> str:
        p = os.path.expanduser(p)
        return os.path.normpath(p if os.path.isabs(p) else os.path.join(cwd, p))

    def show(p: str) -> str:
        return p.replace(_VARIANT, "{variant}")

    def inside(p: str) -> bool:
        return p == _VARIANT or p.startswith(_VARIANT + "/")

    def is_input(p: str) -> bool:
        return any(p == r or p.startswith(r + "/") for r in readable)

    for combo in combos:
        vals = dict(fixed)
        vals.update((a.name, v) for a, v in zip(used, combo))
        try:
            args = [fill(a, vals) for a in st.args]
        except (KeyError, ValueError, IndexError, AttributeError):
            return  # an unknown placeholder: named later (check_placeholders)
        for t, v in list(base) + [(a.target, v) for a, v in zip(used, combo)]:
            if t.kind == "flag" and t.stage == st.name:
                args = set_flag(args, t.key, v)
        with_axes = "".join(f" with {a.name} = {format_value(v)}" for a, v in zip(used, combo))
        outputs = set()
        for i, a in enumerate(args):
            value = None
            if a in OUTPUT_FLAGS and i + 1 < len(args):
                value, outputs = args[i + 1], outputs | {i + 1}
            elif a.startswith("--output="):
                value = a.split("=", 1)[1]
            elif a.startswith("-o") and not a.startswith("--") and len(a) > 2:
                value = a[2:]
            if value is not None and not inside(resolve(value)):
                flag = "--output" if a.startswith("--") else "-o"
                raise FormatError(path, line, f"[[stage]] {st.name}: an output ({flag}) inside the variant's folder "
                                  "({out}, {variant})", f"{shorten(show(value))}{with_axes}")
        for i, a in enumerate(args):
            if i in outputs:
                continue
            head, eq, tail = a.partition("=")
            if a.startswith("-"):
                if not eq:
                    continue  # a flag or a negative number
                p = tail  # --flag=PATH
            else:
                p = tail if eq and "/" not in head else a  # NAME=PATH
            if "/" not in p and not p.startswith("~") and p not in (".", ".."):
                continue
            r = resolve(p)
            if not (inside(r) or is_input(r)):
                raise FormatError(path, line, f"[[stage]] {st.name}: paths inside the variant's folder ({{out}}, "
                                  "{inputs}, {variant}) or of [sweep] inputs (read, not written)",
                                  f"{shorten(show(a))}{with_axes}")


def read_sweep(path) -> Sweep:
    return parse_sweep(read_toml_text(path, _undecodable), path)


def _undecodable(path, data: bytes, exc: UnicodeDecodeError) -> FormatError:
    return FormatError(path, data[: exc.start].count(b"\n") + 1, "UTF-8 text", f"byte 0x{data[exc.start]:02x}")


# ---------------------------------------------------------------------------------------------
# variants

def format_value(v) -> str:
    """A parameter value as text: booleans lower case, floats with up to 12 significant digits."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:.12g}"
    return str(v)


def _slug(params) -> str:
    """``n20_alpha60``: names and values, only characters that are safe in make and shells."""
    text = "_".join(f"{k}{format_value(v) if not isinstance(v, float) else f'{v:.6g}'}" for k, v in params)
    text = re.sub(r"[^A-Za-z0-9_.+-]+", "_", text).strip("_.-")
    return text[:48].rstrip("_.-") or "base"


def _variant(index: int, params, sweep: Sweep) -> Variant:
    canon = json.dumps([[k, v] for k, v in params], sort_keys=True)
    digest = hashlib.sha1(canon.encode()).hexdigest()[:8]
    overrides = list(sweep.base)
    by_name = {a.name: a for a in sweep.axes}
    overrides += [(by_name[k].target, v) for k, v in params]
    return Variant(index, f"{_slug(params)}-{digest}", tuple(params), tuple(overrides))


def variants(sweep: Sweep) -> list[Variant]:
    """Every variant of the sweep, in order: the grid (the last axis varies fastest) or
    ``samples`` random draws from ``numpy.random.default_rng(seed)`` (uniform axes rounded to 6
    significant digits, so the folder name, the label and the value written agree)."""
    import numpy as np

    if sweep.sampling == "grid":
        combos = itertools.product(*[a.values for a in sweep.axes]) if sweep.axes else [()]
        rows = [tuple(zip([a.name for a in sweep.axes], c)) for c in combos]
    else:
        rng = np.random.default_rng(sweep.seed)
        rows = []
        for _ in range(sweep.samples):
            row = []
            for a in sweep.axes:
                if a.uniform is not None:
                    lo, hi = a.uniform
                    if isinstance(lo, int) and isinstance(hi, int):
                        v = int(rng.integers(lo, hi + 1))
                    else:
                        v = float(f"{rng.uniform(lo, hi):.6g}")
                else:
                    v = a.values[int(rng.integers(len(a.values)))]
                row.append((a.name, v))
            rows.append(tuple(row))
    out = [_variant(i, r, sweep) for i, r in enumerate(rows)]
    seen: dict[str, int] = {}
    for i, v in enumerate(out):  # the same draw twice: the later one gets its index in the name
        if v.id in seen:
            out[i] = Variant(v.index, f"{v.id}-{v.index}", v.params, v.overrides)
        seen[out[i].id] = i
    return out
