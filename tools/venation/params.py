"""The venation TOML parameter file (spec: ``formats/venation.md``).

Read with the stdlib :mod:`tomllib`; every key is checked against :data:`SCHEMA` (unknown keys and
sections are rejected naming the closest known one, with ``file:line``), defaults are filled and
the values come back as :class:`Params`, one frozen dataclass per section. The dataclasses are the
schema: each field's kind (in its metadata) and default. Paths (``.con``, ``.cset``, ``.func``) are
resolved relative to the parameter file. :func:`load_inputs` then reads the blade contour and the
growth functions and checks what needs them (a closed contour, the base and the initial vein nodes
inside the blade, non-decreasing growth).

Sections (Runions ch. 4):

- top level: ``seed``, ``max_iterations``, ``max_nodes``;
- ``[blade]``: the leaf blade (sec. 4.2.2) as a contour or a polygon, its size and base;
- ``[growth]``: none, marginal, uniform (isogonic) or anisotropic growth (sec. 4.2.3, fig. 4.2);
- ``[veins]``: open or closed patterns (secs. 4.2, 4.3), D, d_k, the initial vein nodes, veins
  kept inside the blade, blindly terminating veins (the areole algorithm, secs. 5.2.3-5.2.5);
- ``[sources]``: auxin sources by dart throwing: b_s, b_v, rho (sec. 4.2.3);
- ``[width]``: vein widths by Murray's law (sec. 4.2.5, eq. 3.5) or by elongation (sec. 5.2);
- ``[refine]``: adaptive corner cutting of stretched veins (sec. 5.2.6, eqs. 5.3-5.4);
- ``[texture]``: the PNG of the veins over the blade;
- ``[output]``: frames for an animation, the blade mesh.
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import MISSING, dataclass, field, fields
from pathlib import Path

import numpy as np

from inflo.formats.errors import FormatError, InputError, did_you_mean, parse_toml, shorten
from inflo.formats.toml_params import LineStyle, ParamText, line_of, read_toml_text, show_short, unknown_name

from .blade import GROWTH_TYPES, Blade, Growth, blade_from_points

__all__ = ["SCHEMA", "Params", "Run", "BladeSpec", "GrowthSpec", "Veins", "Sources", "Width", "Texture", "Output", "Refine",
           "read_params", "parse_params", "load_inputs", "Inputs", "PATTERNS", "NEIGHBOURHOODS"]

PATTERNS = ("open", "closed")
NEIGHBOURHOODS = ("relative", "urquhart")
REGIONS = ("auto", "blade", "margin")
PLACEMENTS = ("darts", "largest_empty_circle")
#: sources.placement = "largest_empty_circle": circles of diameter min(b_s, b_v) the final blade holds at most
MAX_CIRCLES = 20_000
WIDTH_MODELS = ("pipe", "elongation")
MAX_SAMPLES = 100_000
#: blade coordinates (polygon, base, roots), blade.size and the growth scales: blade units
MAX_COORDINATE = 1e6
#: initial vein nodes (veins.roots)
MAX_ROOTS = 1_000_000
#: growth.key_frames: the most key frames
MAX_KEY_FRAMES = 1_000
MAX_TEXTURE = 16_384

_NUM = (int, float)


def _key(kind, default):
    """A parameter: its kind (how :func:`parse_params` checks it) and default.

    Kinds: ``"float"``, ``"int"``, ``"str"``, ``"bool"``, ``("choice", options)``, ``"path"`` (a file
    name, resolved against the parameter file; "" for none), ``"point"`` ([x, y]), ``"points"``
    (a list of [x, y]), ``"scale"`` (a number or [sx, sy]), ``"paths"`` (one file name or a list of
    one or two), ``"files"`` (a list of file names), ``"numbers"`` (a list of numbers), ``"color"`` ("#rrggbb"; "" for none where allowed).
    """
    if isinstance(default, list):
        return field(default_factory=lambda: list(default), metadata={"kind": kind})
    return field(default=default, metadata={"kind": kind})


@dataclass(frozen=True)
class Run:
    """Top-level keys: the seed of every random choice and the work limits."""

    seed: int = _key("int", 1)
    max_iterations: int = _key("int", 100_000)
    max_nodes: int = _key("int", 2_000_000)


@dataclass(frozen=True)
class BladeSpec:
    """``[blade]``: the leaf blade at scale 1 (sec. 4.2.2)."""

    contour: str = _key("path", "")
    contour_name: str = _key("str", "")
    polygon: list = _key("points", [])
    samples: int = _key("int", 256)
    size: float = _key("float", 1.0)
    base: list | None = _key("point", None)


@dataclass(frozen=True)
class GrowthSpec:
    """``[growth]``: the blade's growth (sec. 4.2.3, fig. 4.2)."""

    type: str = _key(("choice", GROWTH_TYPES), "none")
    initial: float | list = _key("scale", 1.0)
    final: float | list = _key("scale", 1.0)
    rate: float | list = _key("scale", 0.01)
    scale: str | list = _key("paths", "")
    steps: int = _key("int", 0)
    rerg: str | list = _key("paths", "")
    key_frames: list = _key("files", [])
    times: list = _key("numbers", [])


@dataclass(frozen=True)
class Veins:
    """``[veins]``: the venation algorithm (secs. 4.2, 4.3)."""

    pattern: str = _key(("choice", PATTERNS), "open")
    neighbourhood: str = _key(("choice", NEIGHBOURHOODS), "relative")
    step: float = _key("float", 1.0)
    kill_distance: float = _key("float", 1.0)
    roots: list = _key("points", [])
    inside: bool = _key("bool", False)
    blind_after: int = _key("int", -1)
    blind_gap: float = _key("float", 1.0)


@dataclass(frozen=True)
class Sources:
    """``[sources]``: auxin sources by dart throwing (sec. 4.2.3)."""

    birth_source: float = _key("float", 2.0)
    birth_vein: float = _key("float", 2.0)
    darts: float = _key("float", 0.01)
    region: str = _key(("choice", REGIONS), "auto")
    settle: int = _key("int", 10)
    placement: str = _key(("choice", PLACEMENTS), "darts")


@dataclass(frozen=True)
class Width:
    """``[width]``: vein widths by Murray's law (sec. 4.2.5, eq. 3.5)."""

    tip: float = _key("float", 0.25)
    exponent: float = _key("float", 2.0)
    increment: float = _key("float", 0.0)
    model: str = _key(("choice", WIDTH_MODELS), "pipe")


@dataclass(frozen=True)
class Refine:
    """``[refine]``: adaptive vein refinement by corner cutting (Runions sec. 5.2.6, eqs. 5.3-5.4)."""

    threshold: float = _key("float", 0.0)
    alpha: float = _key("float", 0.75)
    jitter: float = _key("float", 0.0)


@dataclass(frozen=True)
class Texture:
    """``[texture]``: the PNG of the veins drawn by width over the blade."""

    size: int = _key("int", 1024)
    blade_color: str = _key("color", "#5c8c3a")
    vein_color: str = _key("color", "#dee8aa")
    background: str = _key("color", "")
    width_scale: float = _key("float", 1.0)
    supersample: int = _key("int", 3)


@dataclass(frozen=True)
class Output:
    """``[output]``: frames of the pattern forming, the blade mesh."""

    frame_step: int = _key("int", 0)
    frame_textures: bool = _key("bool", False)
    mesh_spacing: float = _key("float", 0.0)


@dataclass(frozen=True)
class Params:
    """A checked venation parameter file."""

    run: Run = field(default_factory=Run)
    blade: BladeSpec = field(default_factory=BladeSpec)
    growth: GrowthSpec = field(default_factory=GrowthSpec)
    veins: Veins = field(default_factory=Veins)
    sources: Sources = field(default_factory=Sources)
    width: Width = field(default_factory=Width)
    refine: Refine = field(default_factory=Refine)
    texture: Texture = field(default_factory=Texture)
    output: Output = field(default_factory=Output)
    source: str = "<params>"
    text: str = ""


_SECTIONS = {"blade": BladeSpec, "growth": GrowthSpec, "veins": Veins, "sources": Sources, "width": Width, "refine": Refine,
             "texture": Texture, "output": Output}


def _schema(cls) -> dict[str, tuple]:
    out = {}
    for f in fields(cls):
        default = f.default_factory() if f.default is MISSING else f.default
        out[f.name] = (f.metadata["kind"], default)
    return out


#: section ("" for the top level) -> key -> (kind, default), from the dataclasses.
SCHEMA: dict[str, dict[str, tuple]] = {"": _schema(Run), **{n: _schema(c) for n, c in _SECTIONS.items()}}


#: how venation finds a key's line: top-level keys are section "", headers lose their double quotes
#: and count by the name before the first dot; an absent key points at its section's header
LINES = LineStyle(top="", unquote=True, fallback="header")


def _text(path, text: str) -> ParamText:
    """The wording of venation's errors: ``expected <key or section.key> as <what>``, found the
    value's repr (shortened)."""
    return ParamText(path, text, style=LINES, template="{name} as {expected}", show=show_short)


def parse_params(text: str, path="<params>") -> Params:
    """Parse and check TOML ``text``; returns :class:`Params` with defaults filled.

    Raises
    ------
    FormatError
        TOML syntax errors, unknown sections or keys (naming the closest known one), values of the
        wrong type or out of range.
    """
    path = os.fspath(path)
    raw = parse_toml(text, path)
    w = _text(path, text)
    base = Path(path).resolve().parent
    known = [k for k in SCHEMA[""]] + list(_SECTIONS)
    tables = {"": {}}
    for key, value in raw.items():
        if key in _SECTIONS:
            if not isinstance(value, dict):
                raise FormatError(path, w.line("", key), f"[{key}] as a table", shorten(repr(value)))
            tables[key] = value
        elif key in SCHEMA[""]:
            tables[""][key] = value
        else:
            raise unknown_name(path, w.line(key, None) or w.line("", key), "a known key or section", key, known)
    values: dict[str, dict] = {}
    for section, schema in SCHEMA.items():
        table = tables.get(section, {})
        for key in table:
            if key not in schema:
                where = f"[{section}]" if section else "the top level"
                raise unknown_name(path, w.line(section, key), f"a key of {where}", key, schema)
        values[section] = {}
        for key, (kind, default) in schema.items():
            if key in table:
                values[section][key] = _check(table[key], kind, section, key, w, base)
            else:
                values[section][key] = list(default) if isinstance(default, list) else default
    _check_ranges(values, w)
    return Params(run=Run(**values[""]), **{s: c(**values[s]) for s, c in _SECTIONS.items()}, source=path, text=text)


def _check(value, kind, section, key, w: ParamText, base):
    def bad(expected):
        return w.bad(section, key, expected, value)

    def number(v):
        return isinstance(v, _NUM) and not isinstance(v, bool) and math.isfinite(v)

    if isinstance(kind, tuple) and kind[0] == "choice":
        return w.choice(section, key, value, kind[1])
    if kind == "float":
        return w.number(section, key, value, not_a_number="a finite number")
    if kind == "int":
        return w.integer(section, key, value)
    if kind == "bool":
        return w.boolean(section, key, value)
    if kind == "str":
        return w.string(section, key, value)
    if kind == "path":
        if not isinstance(value, str):
            raise bad("a file name")
        return "" if not value else str(Path(value) if Path(value).is_absolute() else base / value)
    if kind == "paths":
        items = [value] if isinstance(value, str) else value
        if not isinstance(items, list) or not 1 <= len(items) <= 2 or not all(isinstance(v, str) and v for v in items):
            raise bad("a .func file name or a list of one or two")
        if items == [""]:
            return ""
        out = [str(Path(v) if Path(v).is_absolute() else base / v) for v in items]
        return out[0] if isinstance(value, str) else out
    if kind == "files":
        if not isinstance(value, list) or not 1 <= len(value) <= MAX_KEY_FRAMES or not all(isinstance(v, str) and v for v in value):
            raise bad(f"a list of 1 to {MAX_KEY_FRAMES} file names")
        return [str(Path(v) if Path(v).is_absolute() else base / v) for v in value]
    if kind == "numbers":
        if not isinstance(value, list) or not 1 <= len(value) <= MAX_KEY_FRAMES or not all(number(v) for v in value):
            raise bad(f"a list of 1 to {MAX_KEY_FRAMES} finite numbers")
        return [float(v) for v in value]
    if kind == "point":
        if not isinstance(value, list) or len(value) != 2 or not all(number(v) for v in value):
            raise bad("[x, y]")
        return [float(v) for v in value]
    if kind == "points":
        if not isinstance(value, list) or not all(
                isinstance(p, list) and len(p) == 2 and all(number(v) for v in p) for p in value):
            raise bad("a list of [x, y] points")
        return [[float(v) for v in p] for p in value]
    if kind == "scale":
        if number(value):
            return float(value)
        if isinstance(value, list) and len(value) == 2 and all(number(v) for v in value):
            return [float(v) for v in value]
        raise bad("a number or [sx, sy]")
    if kind == "color":
        if not isinstance(value, str) or not (value == "" or re.fullmatch(r"#[0-9a-fA-F]{6}", value)):
            raise bad("a colour '#rrggbb'")
        return value
    raise AssertionError(kind)  # pragma: no cover


def _check_ranges(p: dict, where: ParamText) -> None:
    def fail(section, key, expected):
        raise where.error(section, key, expected, show_short(p[section][key]), template="{name} {expected}")

    r = p[""]
    if r["max_iterations"] < 1:
        fail("", "max_iterations", ">= 1")
    if r["max_nodes"] < 1:
        fail("", "max_nodes", ">= 1")
    if not 0 <= r["seed"] <= 2**32 - 1:
        fail("", "seed", "in [0, 4294967295]")
    b = p["blade"]
    g = p["growth"]
    kf = g["type"] == "key_frames"
    if kf and (b["contour"] or b["polygon"]):
        fail("blade", "contour" if b["contour"] else "polygon", "absent with growth.type = 'key_frames' (the first key "
             "frame is the blade)")
    if b["contour"] and b["polygon"]:
        fail("blade", "polygon", "absent when blade.contour is given (one blade)")
    if not b["contour"] and not b["polygon"] and not kf:
        raise FormatError(where.path, where.line("blade", None), "a blade: [blade] contour = \"leaf.con\" or "
                          "polygon = [[x, y], ...]", "neither")
    if b["polygon"] and len(b["polygon"]) < 3:
        fail("blade", "polygon", "with at least 3 points")
    if not 16 <= b["samples"] <= MAX_SAMPLES:
        fail("blade", "samples", f"in [16, {MAX_SAMPLES}] (margin points sampled along the contour)")
    if b["size"] <= 0:
        fail("blade", "size", "> 0")
    if b["size"] > MAX_COORDINATE:
        fail("blade", "size", f"<= {MAX_COORDINATE:g}")
    for section, key in (("blade", "polygon"), ("blade", "base"), ("veins", "roots")):
        pts = np.asarray(p[section][key] or [], dtype=np.float64)
        if pts.size and not np.abs(pts).max() <= MAX_COORDINATE:
            fail(section, key, f"with coordinates within +-{MAX_COORDINATE:g}")
    if len(p["veins"]["roots"]) > MAX_ROOTS:
        fail("veins", "roots", f"at most {MAX_ROOTS} points (initial vein nodes)")
    g = p["growth"]
    aniso = g["type"] == "anisotropic"
    for key in ("initial", "final", "rate"):
        v = g[key]
        if isinstance(v, list) and not aniso:
            fail("growth", key, "a number (one scale; [sx, sy] needs type = 'anisotropic')")
        vals = v if isinstance(v, list) else [v]
        if key == "rate" and any(x <= 0 for x in vals):
            fail("growth", key, "> 0 (the increase of the scale per step)")
        if key != "rate" and any(x <= 0 for x in vals):
            fail("growth", key, "> 0 (a scale of the blade)")
        if any(x > MAX_COORDINATE for x in vals):
            fail("growth", key, f"<= {MAX_COORDINATE:g}")
    ini = np.broadcast_to(np.asarray(g["initial"], float), (2,))
    fin = np.broadcast_to(np.asarray(g["final"], float), (2,))
    if np.any(fin < ini):
        fail("growth", "final", ">= growth.initial (growth does not shrink the blade)")
    ltg = g["type"] == "local_to_global"
    if ltg:
        if not (isinstance(g["rerg"], list) and len(g["rerg"]) == 2):
            fail("growth", "rerg" if g["rerg"] else "type", "with type = 'local_to_global': growth.rerg = "
                 "[\"rerg_x.func\", \"rerg_y.func\"] (RERG_x and RERG_y of the initial y, sec. 5.2.1)")
        if g["scale"]:
            fail("growth", "scale", "absent with type = 'local_to_global' (growth.rerg gives the growth)")
        if not 1 <= g["steps"] <= 10_000_000:
            fail("growth", "steps", "in [1, 10000000] (the steps of local-to-global growth)")
    elif g["rerg"]:
        fail("growth", "rerg", "absent unless type = 'local_to_global'")
    if kf:
        if len(g["key_frames"]) < 2:
            fail("growth", "key_frames" if g["key_frames"] else "type", "with type = 'key_frames': growth.key_frames = "
                 "[\"a.s\", \"b.s\", ...], at least two blade surfaces (sec. 5.2.1, fig. 5.9)")
        if len(g["times"]) != len(g["key_frames"]):
            fail("growth", "times" if g["times"] else "key_frames", f"growth.times: one iteration per key frame "
                 f"({len(g['key_frames'])})")
        tt = g["times"]
        if tt[0] != 0 or any(b_ <= a_ for a_, b_ in zip(tt, tt[1:])) or any(t_ != int(t_) for t_ in tt):
            fail("growth", "times", "whole iterations increasing from 0 (the time of each key frame)")
        if tt[-1] > 10_000_000:
            fail("growth", "times", "<= 10000000 (the steps of key-frame growth)")
        if g["scale"] or g["steps"]:
            fail("growth", "scale" if g["scale"] else "steps", "absent with type = 'key_frames' (growth.times gives "
                 "the steps)")
    else:
        if g["key_frames"]:
            fail("growth", "key_frames", "absent unless type = 'key_frames'")
        if g["times"]:
            fail("growth", "times", "absent unless type = 'key_frames'")
    if ltg or kf:
        pass  # checked above
    elif g["scale"]:
        if isinstance(g["scale"], list) and len(g["scale"]) == 2 and not aniso:
            fail("growth", "scale", "one .func (two need type = 'anisotropic')")
        if g["steps"] < 1:
            fail("growth", "steps", ">= 1 (the growth steps the .func spans)")
    elif g["steps"] < 0:
        fail("growth", "steps", ">= 0")
    v = p["veins"]
    if v["step"] <= 0:
        fail("veins", "step", "> 0 (D, the length of a vein segment)")
    if v["kill_distance"] <= 0:
        fail("veins", "kill_distance", "> 0")
    if v["kill_distance"] < v["step"]:
        fail("veins", "kill_distance", f">= veins.step {v['step']:g} (a vein would step over its source)")
    if v["blind_after"] < -1:
        fail("veins", "blind_after", ">= 0 (the iteration of the event of sec. 5.2.4), or -1 for never")
    if v["blind_after"] >= 0 and v["pattern"] != "closed":
        fail("veins", "blind_after", "-1 with pattern = 'open' (blind veinlets are areoles of a closed pattern)")
    if not 0.5 <= v["blind_gap"] <= 100:
        fail("veins", "blind_gap", "in [0.5, 100] (times D)")
    if v["pattern"] == "open" and v["neighbourhood"] == "urquhart":
        fail("veins", "neighbourhood", "only with pattern = 'closed' (an open source attracts its closest node)")
    s = p["sources"]
    if s["birth_source"] <= 0:
        fail("sources", "birth_source", "> 0 (b_s)")
    if s["birth_vein"] <= 0:
        fail("sources", "birth_vein", "> 0 (b_v)")
    if s["darts"] <= 0:
        fail("sources", "darts", "> 0 (darts per unit leaf area per step)")
    if s["region"] == "margin" and p["growth"]["type"] != "marginal":
        fail("sources", "region", "'margin' only with growth.type = 'marginal' (the band the margin sweeps)")
    if (ltg or kf) and v["inside"]:
        fail("veins", "inside", f"false with growth.type = '{g['type']}'")
    if s["placement"] == "largest_empty_circle" and s["region"] == "margin":
        fail("sources", "region", "'auto' or 'blade' with placement = 'largest_empty_circle' (no darts are thrown)")
    if s["settle"] < 0:
        fail("sources", "settle", ">= 0")
    if s["settle"] > 1_000_000:
        fail("sources", "settle", "<= 1000000")
    w = p["width"]
    if w["tip"] <= 0:
        fail("width", "tip", "> 0")
    if w["tip"] > 1e6:
        fail("width", "tip", "<= 1e6")
    if w["exponent"] <= 0:
        fail("width", "exponent", "> 0")
    if not 0.1 <= w["exponent"] <= 100:
        fail("width", "exponent", "in [0.1, 100] (Murray's exponent)")
    if w["increment"] < 0:
        fail("width", "increment", ">= 0")
    if w["increment"] > 1e6:
        fail("width", "increment", "<= 1e6")
    r = p["refine"]
    if r["threshold"] < 0:
        fail("refine", "threshold", ">= 0 (0: no refinement)")
    if 0 < r["threshold"] < 2.0 * v["step"]:
        fail("refine", "threshold", f">= 2 x veins.step = {2 * v['step']:g} (two segments of length D), or 0")
    if not 0.5 <= r["alpha"] < 1.0:
        fail("refine", "alpha", "in [0.5, 1) (the corner-cutting ratio of eqs. 5.3-5.4)")
    if not 0.0 <= r["jitter"] <= 0.5:
        fail("refine", "jitter", "in [0, 0.5] (times the new segment's length)")
    t = p["texture"]
    if not 16 <= t["size"] <= MAX_TEXTURE:
        fail("texture", "size", f"in [16, {MAX_TEXTURE}] pixels")
    if not 1 <= t["supersample"] <= 8:
        fail("texture", "supersample", "in [1, 8]")
    if t["width_scale"] <= 0:
        fail("texture", "width_scale", "> 0")
    if t["width_scale"] > 1e6:
        fail("texture", "width_scale", "<= 1e6")
    for key in ("blade_color", "vein_color"):
        if not t[key]:
            fail("texture", key, "a colour '#rrggbb'")
    o = p["output"]
    if o["frame_step"] < 0:
        fail("output", "frame_step", ">= 0 (0: no frames)")
    if o["mesh_spacing"] < 0:
        fail("output", "mesh_spacing", ">= 0 (0: the margin's spacing)")


def read_params(path) -> Params:
    """Read and check a venation parameter file (see :func:`parse_params`)."""
    path = os.fspath(path)
    return parse_params(read_toml_text(path), path)


# --------------------------------------------------------------------------------------------
# the files the parameters name


@dataclass(frozen=True)
class Inputs:
    """What a run needs besides the parameters: the blade, its growth, the initial vein nodes
    (scale-1 blade coordinates)."""

    blade: Blade
    growth: Growth
    roots: np.ndarray


def _margin(p: Params) -> np.ndarray:
    b = p.blade
    line = line_of(p.text, "blade", "contour", LINES)
    if b.polygon:
        return np.asarray(b.polygon, dtype=np.float64) * b.size
    from inflo.formats.contour import read_con, read_cset

    name = b.contour
    if name.lower().endswith(".cset"):
        items = read_cset(name)
        if b.contour_name:
            names = [c.name for c in items]
            if b.contour_name not in names:
                raise FormatError(p.source, line_of(p.text, "blade", "contour_name", LINES),
                                  f"blade.contour_name as a contour of {Path(name).name}"
                                  f"{did_you_mean(b.contour_name, names)}", repr(b.contour_name))
            con = items[names.index(b.contour_name)]
        else:
            con = items[0]
    else:
        con = read_con(name)
    if not con.closed:
        raise FormatError(p.source, line, "a closed contour (type 'cr' or 'ce') for blade.contour",
                          f"{Path(name).name}, an open contour (type {con.type!r})")
    return con.sample(b.samples)[:, :2] * b.size


def load_inputs(p: Params) -> Inputs:
    """Read the contour and growth functions and check the blade, base and initial vein nodes.

    Raises
    ------
    FormatError / InputError
        A missing or malformed file, an open contour, a margin that crosses itself or encloses no
        area, a base or initial vein node outside the blade at its initial size (by more than D), a growth function
        that is not positive and non-decreasing.
    """
    kf = _key_frames(p) if p.growth.type == "key_frames" else None
    margin = _margin(p) if kf is None else kf.margin(0)
    try:
        base = p.blade.base if kf is None or p.blade.base is not None else [0.0, 0.0]
        blade = blade_from_points(margin, base=base)
    except ValueError as exc:
        key = "polygon" if p.blade.polygon else "contour"
        raise FormatError(p.source, line_of(p.text, "blade", key, LINES), f"a simple closed margin for blade.{key}",
                          str(exc)) from None
    ext = float(np.ptp(blade.polygon, axis=0).max())
    tol = max(1e-6 * ext, p.veins.step)  # within D of the sampled margin counts as on it
    if (p.blade.base is not None or kf is not None) and not _in_or_on(blade, blade.base[None], 1.0, tol)[0]:
        raise FormatError(p.source, line_of(p.text, "blade", "base", LINES), "blade.base inside the blade or within veins.step of its margin",
                          repr(p.blade.base))
    growth = _growth(p, blade) if kf is None else Growth("key_frames", function_steps=int(p.growth.times[-1]), kf=kf)
    s0 = growth.scale_at(0)
    roots = np.asarray(p.veins.roots, dtype=np.float64).reshape(-1, 2) if p.veins.roots else blade.base[None].copy()
    kind = growth.kind
    at_start = blade.base + (roots - blade.base) * s0 if kind in ("uniform", "anisotropic") else roots
    ok = _in_or_on(blade, at_start, s0 if kind != "none" else np.ones(2), tol)
    if not ok.all():
        bad = roots[np.flatnonzero(~ok)[0]].tolist()
        raise FormatError(p.source, line_of(p.text, "veins", "roots", LINES) if p.veins.roots else line_of(p.text, "blade", "base", LINES),
                          "initial vein nodes inside the blade at its initial size (or within veins.step of its margin)", repr(bad))
    _check_work(p, blade, growth)
    return Inputs(blade=blade, growth=growth, roots=roots)


#: the work a parameter file may ask for, checked before any is done (formats/venation.md, "Bounds")
MAX_SPAN = 5_000  # veins.step lengths across the final blade (the vein-node grid's side)
MAX_DARTS = 1_000_000  # darts thrown in one step (sources.darts x the final real blade area)
MAX_ITERATIONS = 10_000_000
MAX_NODES = 50_000_000


def _check_work(p: Params, blade: Blade, growth: Growth) -> None:
    """Refuse (one line) parameters whose implied work or memory is beyond the bounds: a step so
    small, a dart density so high or a growth so slow that the run would not end in reasonable time
    or would ask for more memory than a machine has."""
    def fail(section, key, expected, found):
        raise FormatError(p.source, line_of(p.text, section, key, LINES), expected, found)

    if p.run.max_iterations > MAX_ITERATIONS:
        fail("", "max_iterations", f"max_iterations <= {MAX_ITERATIONS}", f"{p.run.max_iterations}")
    if p.run.max_nodes > MAX_NODES:
        fail("", "max_nodes", f"max_nodes <= {MAX_NODES}", f"{p.run.max_nodes}")
    steps = growth.steps
    if steps > p.run.max_iterations:
        key = ("times" if growth.kf is not None else "steps" if growth.functions is not None or growth.ltg is not None
               else "rate")
        fail("growth", key, f"growth that reaches its final size within max_iterations = {p.run.max_iterations} "
             "steps (a rate that grows the blade)", f"{steps} steps")
    fs = growth.final_scale if growth.kind != "none" else np.ones(2)
    if not np.all(np.isfinite(fs)):
        fail("growth", "final", "a finite final scale", repr(fs.tolist()))
    poly = blade.polygon
    ext = float(np.ptp(poly, axis=0).max()) * float(np.max(fs))
    span = ext / p.veins.step
    if not span <= MAX_SPAN:
        fail("veins", "step", f"veins.step >= the final blade's extent / {MAX_SPAN} = {ext / MAX_SPAN:.6g} "
             f"(at most {MAX_SPAN} vein segments across the blade)", f"{p.veins.step:g}")
    x, y = poly[:, 0], poly[:, 1]
    area = 0.5 * abs(float(np.sum(x * np.roll(y, 1) - y * np.roll(x, 1)))) * float(fs[0]) * float(fs[1])
    darts = p.sources.darts * area
    if not darts <= MAX_DARTS:
        fail("sources", "darts", f"sources.darts <= {MAX_DARTS} / the final blade area {area:.6g} = "
             f"{MAX_DARTS / max(area, 1e-300):.6g} (at most {MAX_DARTS} darts a step)", f"{p.sources.darts:g}")
    for section, key, value in (("veins", "kill_distance", p.veins.kill_distance),
                                ("sources", "birth_source", p.sources.birth_source),
                                ("sources", "birth_vein", p.sources.birth_vein)):
        if not value <= ext:
            fail(section, key, f"{section}.{key} <= the final blade's extent = {ext:.6g}", f"{value:g}")
    if p.sources.placement == "largest_empty_circle":
        b = min(p.sources.birth_source, p.sources.birth_vein)
        room = area / (b * b)
        if not room <= MAX_CIRCLES:
            key = "birth_source" if p.sources.birth_source <= p.sources.birth_vein else "birth_vein"
            fail("sources", key, f"min(sources.birth_source, birth_vein) >= sqrt(the final blade area {area:.6g} / "
                 f"{MAX_CIRCLES}) = {math.sqrt(area / MAX_CIRCLES):.6g} with placement = 'largest_empty_circle' "
                 f"(at most {MAX_CIRCLES} sources' room)", f"{b:g}")
    ms = p.output.mesh_spacing
    if ms and not ext / ms <= MAX_SPAN:
        fail("output", "mesh_spacing", f"output.mesh_spacing >= the final blade's extent / {MAX_SPAN} = "
             f"{ext / MAX_SPAN:.6g}, or 0", f"{ms:g}")
    px = p.texture.size * p.texture.supersample
    if px > MAX_TEXTURE:
        fail("texture", "supersample", f"texture.size x texture.supersample <= {MAX_TEXTURE} pixels",
             f"{p.texture.size} x {p.texture.supersample} = {px}")


MAX_FRAMES = 10_000  # frames a run writes (output.frame_step): 4 files each
MAX_FRAME_TEXTURE_PIXELS = 1 << 33  # the pixels of every frame's texture together (output.frame_textures)


def frame_limit_error(p: Params, step: int, textures: bool, *, option: bool, found: str) -> InputError:
    """The one-line error of a run that would write more frames, or frame textures, than the bounds:
    about the file's ``output.frame_step`` (its line) or the ``--frame-step`` option."""
    px = p.texture.size ** 2
    what = (f"at most {MAX_FRAMES} frames and {MAX_FRAME_TEXTURE_PIXELS} texture pixels in all "
            f"({MAX_FRAME_TEXTURE_PIXELS // px} frame textures of {p.texture.size}^2)" if textures
            else f"at most {MAX_FRAMES} frames")
    expected = f"a frame step of {what}"
    if option:
        return InputError(f"--frame-step: expected {expected}, found {step}: {found}")
    return FormatError(p.source, line_of(p.text, "output", "frame_step", LINES), f"output.frame_step: {expected}",
                       f"{step}: {found}")


def frames_allowed(p: Params, textures: bool) -> int:
    """How many frames a run may write (frame textures count against their pixel bound too)."""
    if not textures:
        return MAX_FRAMES
    return max(1, min(MAX_FRAMES, MAX_FRAME_TEXTURE_PIXELS // (p.texture.size ** 2)))


def check_frames(p: Params, inputs: Inputs, step: int, textures: bool, *, option: bool = False) -> None:
    """Refuse (one line) before any work a frame step whose frames the growth alone implies (one
    every ``step`` of its ``growth.steps`` iterations) exceed the bounds: each frame is four files,
    and a frame texture as large as the final one."""
    if step <= 0:
        return
    implied = inputs.growth.steps // step + 1
    if implied > frames_allowed(p, textures):
        raise frame_limit_error(p, step, textures, option=option,
                                found=f"{implied} frames over the growth's {inputs.growth.steps} iterations")

def _in_or_on(blade: Blade, pts, scale, tol) -> np.ndarray:
    pts = np.asarray(pts, dtype=np.float64).reshape(-1, 2)
    inside = blade.contains(pts, scale)
    near = blade.distance_to_margin(pts, scale) <= tol * max(float(np.max(scale)), 1.0)
    return inside | near


def _key_frames(p: Params):
    """The key frames of ``growth.key_frames`` (Bezier surface files, formats/bezier_surface.md), each
    placed as lpfg places a surface (contact point at the origin, heading along +y, up along +z,
    lengths divided by SIZE) and seen from +z (z dropped): one patch each, its margin a simple curve,
    not folded over itself, within the coordinate bound."""
    from inflo.formats.bezier_surface import read_bezier_surface

    from .blade import KeyFrames, _dedupe_ring, bezier_eval, blade_from_points

    line = line_of(p.text, "growth", "key_frames", LINES)
    nets = []
    g = np.linspace(0.02, 0.98, 25)
    gu, gv = np.meshgrid(g, g, indexing="ij")
    edge = KeyFrames(np.zeros((1, 4, 4, 2)), [0.0])._edge_uv
    for name in p.growth.key_frames:
        surf = read_bezier_surface(name)
        if len(surf.patches) != 1:
            raise FormatError(p.source, line, "key frames of one Bezier patch each (a blade surface Q(u, v))",
                              f"{Path(name).name} with {len(surf.patches)} patches")
        net = np.asarray(surf.to_turtle_frame().patches[0].control_points, dtype=np.float64)[:, :, :2].copy()
        if not np.abs(net).max() <= MAX_COORDINATE:
            raise FormatError(p.source, line, f"key frames with coordinates within +-{MAX_COORDINATE:g}", Path(name).name)
        _, qu, qv = bezier_eval(net, gu.ravel(), gv.ravel(), derivatives=True)
        det = qu[:, 0] * qv[:, 1] - qu[:, 1] * qv[:, 0]
        scale = float(np.abs(det).max())
        if not scale > 0 or (det.min() < -1e-9 * scale and det.max() > 1e-9 * scale):
            raise FormatError(p.source, line, "key frames that do not fold over themselves (Q(u, v) one-to-one)",
                              f"{Path(name).name}, whose patch folds")
        try:
            blade_from_points(_dedupe_ring(bezier_eval(net, edge[:, 0], edge[:, 1])))
        except ValueError as exc:
            raise FormatError(p.source, line, "key frames whose margin is a simple closed curve",
                              f"{Path(name).name}: {exc}") from None
        nets.append(net)
    return KeyFrames(nets, p.growth.times)


#: local-to-global growth: the most a relative elementary rate of growth may stretch the blade
MAX_STRETCH = 1e6


def _growth(p: Params, blade: Blade) -> Growth:
    g = p.growth
    if g.type == "none":
        return Growth("none")
    if g.type == "local_to_global":
        from inflo.formats.func import read_func

        from .blade import LocalToGlobal

        fns = [read_func(f) for f in g.rerg]
        line = line_of(p.text, "growth", "rerg", LINES)
        for f, name, axis in zip(fns, g.rerg, "xy"):
            ys = np.asarray(f.sampled()[1])
            if not (np.all(np.isfinite(ys)) and ys.min() >= 1.0):
                raise FormatError(p.source, line, f"growth.rerg's RERG_{axis} >= 1 everywhere (a relative elementary "
                                  "rate of growth; the blade does not shrink)",
                                  f"{Path(name).name} from {ys[0]:g} to {ys[-1]:g}, least {ys.min():g}")
            stretch = g.steps * math.log(float(ys.max()))
            if not stretch <= math.log(MAX_STRETCH):
                raise FormatError(p.source, line, f"growth.rerg's RERG_{axis} ^ growth.steps <= {MAX_STRETCH:g} "
                                  "(the stretch of the blade)", f"{Path(name).name} up to {ys.max():g} over "
                                  f"{g.steps} steps")
        height = float(blade.polygon[:, 1].max() - blade.base[1])
        if not height > 0:
            raise FormatError(p.source, line_of(p.text, "blade", "base", LINES), "a blade above its base for local-to-global "
                              "growth (y0 is measured up from it)", repr(blade.base.tolist()))
        return Growth(g.type, function_steps=g.steps, ltg=LocalToGlobal(fns[0], fns[1], blade.base, height))
    if g.scale:
        from inflo.formats.func import read_func

        files = g.scale if isinstance(g.scale, list) else [g.scale]
        fns = [read_func(f) for f in files]
        if len(fns) == 1:
            fns = fns * 2
        for f, name in zip(fns, files * (2 if len(files) == 1 else 1)):
            ys = np.asarray(f.sampled()[1])
            if np.any(ys <= 0) or np.any(np.diff(ys) < -1e-12 * np.abs(ys).max()):
                raise FormatError(p.source, line_of(p.text, "growth", "scale", LINES),
                                  "growth.scale as a positive, non-decreasing function (a scale of the blade)",
                                  f"{Path(name).name} from {ys[0]:g} to {ys[-1]:g}, least {ys.min():g}")
        if g.type == "uniform" or g.type == "marginal":
            fns = [fns[0], fns[0]]
        return Growth(g.type, functions=tuple(fns), function_steps=g.steps)

    def pair(v):
        return tuple(float(x) for x in np.broadcast_to(np.asarray(v, dtype=np.float64), (2,)))

    return Growth(g.type, initial=pair(g.initial), final=pair(g.final), rate=pair(g.rate))
