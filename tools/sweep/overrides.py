"""A variant's inputs: parameter values written into copies of TOML and ``.fcc`` files,
CLI flags set in a stage's arguments, ``{...}`` placeholders filled.

Files are edited as text, so comments and layout survive and the copy differs from the original
only where a parameter is set; the edited TOML is parsed again to check that it holds the value.
"""
from __future__ import annotations

import json
import math
import re
import string
import tomllib

from inflo.formats.errors import InputError

from .spec import Sweep, Target, format_value

__all__ = ["toml_literal", "set_toml_key", "set_fcc_key", "set_flag", "fill", "placeholders",
           "check_placeholders"]


def toml_literal(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise InputError(f"cannot write {v!r} into a TOML file")
        return repr(v)
    return json.dumps(str(v))


_HEADER = re.compile(r"^\s*\[\s*([^\[\]]+?)\s*\]\s*(#.*)?$")


def _norm_table(name: str) -> str:
    return ".".join(part.strip().strip('"\'') for part in name.split("."))


def set_toml_key(text: str, dotted: str, value, where: str = "<toml>") -> str:
    """``text`` with ``table.key = value`` (the last dotted part is the key; no dot: a top-level
    key): the existing line replaced, else the key added to its table, else the table appended."""
    parts = [p.strip() for p in dotted.split(".")]
    table, key = ".".join(parts[:-1]), parts[-1]
    lines = text.splitlines()
    current = ""
    first_header = None
    header_at = None
    key_re = re.compile(rf"^\s*[\"']?{re.escape(key)}[\"']?\s*=")
    lit = toml_literal(value)
    for i, raw in enumerate(lines):
        m = _HEADER.match(raw)
        if m and not raw.lstrip().startswith("[["):
            current = _norm_table(m.group(1))
            if first_header is None:
                first_header = i
            if current == table:
                header_at = i
            continue
        if raw.lstrip().startswith("[["):
            current = None
            if first_header is None:
                first_header = i
            continue
        if current == table and key_re.match(raw):
            indent = raw[: len(raw) - len(raw.lstrip())]
            lines[i] = f"{indent}{key} = {lit}"
            break
    else:
        if table == "":
            at = first_header if first_header is not None else len(lines)
            lines.insert(at, f"{key} = {lit}")
        elif header_at is not None:
            lines.insert(header_at + 1, f"{key} = {lit}")
        else:
            lines += ["", f"[{table}]", f"{key} = {lit}"]
    out = "\n".join(lines) + "\n"
    try:
        got = tomllib.loads(out)
        for p in parts:
            got = got[p]
    except (tomllib.TOMLDecodeError, KeyError, TypeError) as exc:
        raise InputError(f"{where}: cannot set {dotted} = {lit} ({type(exc).__name__}: {exc})") from None
    if got != value:
        raise InputError(f"{where}: cannot set {dotted} = {lit} (the file reads {got!r} there; "
                         "a multi-line value or a dotted key?)")
    return out


def _fcc_key(line: str) -> str | None:
    body = line.split("#", 1)[0]
    if ":" not in body:
        return None
    return " ".join(body.split(":", 1)[0].split()).lower()


def set_fcc_key(text: str, key: str, value) -> str:
    """``text`` of a ``.fcc`` file with its first ``key: value`` line set (added at the end when
    the file has none); keys compare without case, runs of blanks as one."""
    want = " ".join(key.split()).lower()
    lines = text.splitlines()
    for i, raw in enumerate(lines):
        if _fcc_key(raw) == want:
            name = raw.split(":", 1)[0].strip()
            lines[i] = f"{name}: {format_value(value)}"
            break
    else:
        lines.append(f"{key}: {format_value(value)}")
    return "\n".join(lines) + "\n"


def set_flag(args: list[str], flag: str, value) -> list[str]:
    """``args`` with ``flag value`` set: the value after an existing ``flag`` (or ``flag=...``)
    replaced, else ``flag value`` appended; a boolean adds the bare flag (true) or removes it."""
    out = list(args)
    idx = next((i for i, a in enumerate(out) if a == flag or a.startswith(flag + "=")), None)
    if isinstance(value, bool):
        if idx is not None:
            del out[idx]
        if value:
            out.append(flag)
        return out
    text = format_value(value)
    if idx is None:
        return out + [flag, text]
    if out[idx] == flag:
        if idx + 1 < len(out):
            out[idx + 1] = text
        else:
            out.append(text)
    else:
        out[idx] = f"{flag}={text}"
    return out


_BUILTIN = ("out", "inputs", "variant", "id", "index", "sweep_dir")


def placeholders(arg: str) -> list[str]:
    return [f for _, f, _, _ in string.Formatter().parse(arg) if f is not None]


def check_placeholders(sweep: Sweep) -> None:
    """Every ``{name}`` of a stage's arguments is a built-in (out, inputs, variant, id, index,
    sweep_dir) or an axis name; raises :class:`InputError` naming the stage otherwise."""
    names = set(_BUILTIN) | {a.name for a in sweep.axes}
    for st in sweep.stages:
        for a in st.args:
            try:
                fields = placeholders(a)
            except ValueError as exc:
                raise InputError(f"{sweep.path}: [[stage]] {st.name}: argument {a!r}: {exc}") from None
            for f in fields:
                if f not in names:
                    raise InputError(f"{sweep.path}: [[stage]] {st.name}: argument {a!r}: expected a placeholder "
                                     f"of {sorted(names)}, found {{{f}}}")


def fill(arg: str, values: dict) -> str:
    return arg.format_map({k: format_value(v) if not isinstance(v, str) else v for k, v in values.items()})


def apply_file_overrides(files: dict[str, str], overrides, where_of) -> dict[str, str]:
    """``files`` (relative path -> text) with every TOML/.fcc override applied."""
    out = dict(files)
    for t, v in overrides:
        if t.kind == "toml":
            out[t.file] = set_toml_key(out[t.file], t.key, v, where_of(t.file))
        elif t.kind == "fcc":
            out[t.file] = set_fcc_key(out[t.file], t.key, v)
    return out


def flag_overrides(overrides, stage: str) -> list[tuple[Target, object]]:
    return [(t, v) for t, v in overrides if t.kind == "flag" and t.stage == stage]
