"""Species files ``pipelines/<species>/species.toml``: a species as data (formats/species.md).

A species file names the species, its title and the thesis figures it reproduces, the family of
its chain and the stages it has, the parts of its USD file, and per quality (``[draft]``,
``[final]``) the settings its Makefile uses: frame counts, resolutions, scales, counts, picture
sizes. The species Makefile reads those settings through :func:`make_variables`
(``pipelines/species.mk``); the tests, the Blender test and ``make species`` read the file
through :func:`read_species`. Nothing parses them back out of Makefile text.

Only the standard library is imported: ``make`` runs this for every species Makefile it reads.
"""
from __future__ import annotations

import os
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from .atomic import write_text_atomic
from .errors import FormatError, InputError

__all__ = ["Species", "FAMILIES", "STAGES", "BENCH_KEYS", "read_species", "species_of", "find_species", "make_variables",
           "setting_text", "write_make_variables"]

FAMILIES = ("head", "compound", "branching-first", "single flower")
"""the chains a species can be built on (formats/species.md)"""

STAGES = ("frames", "obj", "column", "bud", "head", "phyllotaxis", "corymb", "umbel", "dimorph", "thyrse", "canopy",
          "canopy_off", "packed", "flowers", "branches", "smooth", "pictures", "check", "usd")
"""the stage names species Makefiles use as targets"""

BENCH_KEYS = {"quality": str, "unit": str, "row": str, "anchor": str, "anchor_value": (int, float),
              "stage_fcc": str, "stage_target": str, "stage_anchor": str, "stage_goal": (int, float)}
"""the keys of a ``[bench]`` table and their types (formats/species.md)"""

_NAME = re.compile(r"[a-z][a-z0-9_]*")
_SETTING = re.compile(r"[a-z][a-z0-9_]*")
_TOP = {"name", "title", "latin", "figures", "family", "stages", "usd", "bench", "check", "settings", "draft", "final"}


@dataclass
class Species:
    """One species file, validated."""

    path: Path
    name: str
    title: str
    latin: str
    figures: list
    family: str
    stages: list
    usd_parts: dict
    """USD part name -> its OBJ sequence folder or OBJ file, relative to the build folder"""
    usd_translate: dict = field(default_factory=dict)
    """USD part name -> (x, y, z) it is moved by in the USD file (canopy-export --translate)"""
    usd_units: str = "cm"
    """what one unit of its OBJ files is (canopy-export --units)"""
    settings: dict = field(default_factory=dict)
    """quality -> {setting name: value}"""
    common: dict = field(default_factory=dict)
    """{setting name: value} of the ``[settings]`` table: the same at every quality"""
    bench: dict = field(default_factory=dict)
    """the ``[bench]`` table: ``make bench``'s row of the whole build (:data:`BENCH_KEYS`)"""
    check: dict = field(default_factory=dict)
    """the ``[check]`` table: the facts the species' check script asserts (ray count, ...)"""

    @property
    def folder(self) -> Path:
        return self.path.parent

    @property
    def qualities(self) -> list[str]:
        return list(self.settings)

    def setting(self, quality: str, name: str):
        """One setting's value at ``quality`` (``name`` in lower or upper case)."""
        table = {**self.common, **self.settings[quality]}
        key = name.lower()
        if key not in table:
            raise KeyError(f"{self.path}: no setting {key!r} in [settings] or [{quality}] (has {', '.join(table)})")
        return table[key]


def _line_of(text: str, key: str) -> int:
    m = re.search(rf"^\s*{re.escape(key)}\s*=", text, re.M)
    return text[:m.start()].count("\n") + 1 if m else 1


def read_species(path) -> Species:
    """Read and validate ``species.toml``; raises FormatError (file, line, expected, found)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{os.fspath(path)}: no such species file") from None
    except UnicodeDecodeError as exc:
        raise InputError(f"{os.fspath(path)}: expected TOML (UTF-8 text), found byte 0x{exc.object[exc.start]:02x}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"line (\d+)", str(exc))
        raise FormatError(path, int(m.group(1)) if m else 1, "TOML", str(exc)) from None

    def err(key, expected, found):
        return FormatError(path, _line_of(text, key), expected, found)

    bad = sorted(set(data) - _TOP)
    if bad:
        raise err(bad[0], f"one of the keys {', '.join(sorted(_TOP))}", f"key {bad[0]!r}")
    for key in ("name", "title", "family", "stages"):
        if key not in data:
            raise FormatError(path, 1, f"a '{key}' key", "none")
    name = data["name"]
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise err("name", "a lower-case name (letters, digits, _)", repr(name))
    folder = path.resolve().parent.name
    if name != folder:
        raise err("name", f"the folder's name {folder!r}", repr(name))
    for key in ("title", "latin"):
        if not isinstance(data.get(key, ""), str):
            raise err(key, "a string", repr(data[key]))
    figures = data.get("figures", [])
    if not isinstance(figures, list) or not all(isinstance(f, str) for f in figures):
        raise err("figures", "a list of figure numbers as strings (\"9.5\")", repr(figures))
    if data["family"] not in FAMILIES:
        raise err("family", f"one of {', '.join(FAMILIES)}", repr(data["family"]))
    stages = data["stages"]
    if not isinstance(stages, list) or not stages or any(s not in STAGES for s in stages):
        found = [s for s in stages if s not in STAGES] if isinstance(stages, list) else stages
        raise err("stages", f"a list of stage names ({', '.join(STAGES)})", repr(found))
    usd = data.get("usd", {})
    parts = usd.get("parts", {}) if isinstance(usd, dict) else None
    if not isinstance(parts, dict) or not all(isinstance(k, str) and isinstance(v, str) and v for k, v in parts.items()):
        raise err("parts", "[usd] parts = { NAME = \"folder or file under build/<species>\" }", repr(usd))
    if "usd" in stages and not parts:
        raise err("stages", "[usd] parts for the 'usd' stage", "none")
    usd = usd if isinstance(usd, dict) else {}
    bad = sorted(set(usd) - {"parts", "translate", "units"})
    if bad:
        raise err(bad[0], "[usd] keys parts, translate, units", repr(bad[0]))
    translate = usd.get("translate", {})
    if not isinstance(translate, dict) or any(
            k not in parts or not isinstance(v, list) or len(v) != 3
            or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v) for k, v in translate.items()):
        raise err("translate", "[usd] translate = { PART = [x, y, z] } for parts of [usd] parts", repr(translate))
    units = usd.get("units", "cm")
    if units not in ("m", "dm", "cm", "mm", "in", "ft"):
        raise err("units", "[usd] units: m, dm, cm, mm, in or ft", repr(units))
    bench = data.get("bench", {})
    if not isinstance(bench, dict):
        raise err("bench", "a [bench] table", repr(bench))
    for k, v in bench.items():
        if k not in BENCH_KEYS or not isinstance(v, BENCH_KEYS[k]) or isinstance(v, bool):
            raise err(k, f"[bench] keys {', '.join(BENCH_KEYS)} (anchor_value, stage_goal numbers; the rest text)",
                      f"{k} = {v!r}")
    for k in ("anchor", "anchor_value"):
        if bench and k not in bench:
            raise err("bench", f"a [bench] {k}", "none")
    if bench.get("unit", "min") not in ("min", "s"):
        raise err("unit", "unit = \"min\" or \"s\"", repr(bench["unit"]))
    settings = {}
    for q in ("check", "settings", "draft", "final"):
        if q not in data:
            if q in ("check", "settings"):
                continue
            raise FormatError(path, 1, f"a [{q}] table of settings", "none")
        table = data[q]
        if not isinstance(table, dict):
            raise err(q, f"a [{q}] table", repr(table))
        for k, v in table.items():
            if not _SETTING.fullmatch(k):
                raise err(k, "a lower-case setting name", repr(k))
            ok = isinstance(v, (str, int, float)) and not isinstance(v, bool) or (
                isinstance(v, list) and all(isinstance(x, (int, float, str)) and not isinstance(x, bool) for x in v))
            if not ok:
                raise err(k, "a number, a string or a list of them", repr(v))
        settings[q] = dict(table)
    check = settings.pop("check", {})
    common = settings.pop("settings", {})
    both = sorted(set(common) & (set(settings["draft"]) | set(settings["final"])))
    if both:
        raise err(both[0], "a setting in [settings] or in [draft] and [final], not both", repr(both[0]))
    if sorted(settings["draft"]) != sorted(settings["final"]):
        only = sorted(set(settings["draft"]) ^ set(settings["final"]))
        raise err(only[0], "the same settings in [draft] and [final]", f"{only[0]!r} in only one of them")
    return Species(path, name, data["title"], data.get("latin", ""), figures, data["family"], list(stages), parts,
                   {k: tuple(float(x) for x in v) for k, v in translate.items()}, units, settings, common, bench, check)


def species_of(script) -> Species:
    """The species file of the folder a species' own script is in (``species_of(__file__)``)."""
    return read_species(Path(script).resolve().parent / "species.toml")


def find_species(pipelines) -> list[Species]:
    """Every ``<pipelines>/*/species.toml``, read, in name order."""
    return [read_species(p) for p in sorted(Path(pipelines).glob("*/species.toml"))]


def setting_text(value) -> str:
    """A setting as make sees it: lists joined by commas, floats in their shortest round-trip form."""
    if isinstance(value, list):
        return ",".join(setting_text(v) for v in value)
    if isinstance(value, float):
        return repr(value)
    return str(value)


def make_variables(species: Species, quality: str, build: str = "$(B)") -> str:
    """The make assignments of the ``[settings]`` and ``quality``'s (``TEMPLATE_FRAMES := 30``: names upper-cased,
    lists joined by commas), the species' NAME and TITLE, and for canopy-export ``USD_PARTS``
    (``NAME=$(B)/path``), ``USD_UNITS`` and ``USD_TRANSLATE`` (``--translate NAME=x,y,z``)."""
    if quality not in species.settings:
        raise InputError(f"{species.path}: QUALITY must be {' or '.join(species.qualities)}, found {quality!r}")
    lines = [f"# from {species.path.name} [{quality}] (formats/species.md); written by pipelines/species.mk",
             f"SPECIES := {species.name}", f"TITLE := {species.title}"]
    lines += [f"{k.upper()} := {setting_text(v)}" for k, v in {**species.common, **species.settings[quality]}.items()]
    lines.append("USD_PARTS := " + " ".join(f"{k}={build}/{v}" for k, v in species.usd_parts.items()))
    lines.append(f"USD_UNITS := {species.usd_units}")
    lines.append("USD_TRANSLATE := " + " ".join(f"--translate {k}={','.join(setting_text(x) for x in v)}"
                                                for k, v in species.usd_translate.items()))
    return "\n".join(lines) + "\n"


def write_make_variables(species: Species, quality: str, out) -> None:
    """:func:`make_variables` to ``out``, rewritten only when it changes."""
    text = make_variables(species, quality)
    out = Path(out)
    try:
        if out.read_text() == text:
            return
    except OSError:
        pass
    out.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out, text)
