"""The phyllotaxis TOML parameter file (spec: ``formats/phyllotaxis.md``).

Reads a ``.toml`` file with the stdlib :mod:`tomllib`, checks every key against :data:`SCHEMA`
(unknown keys are rejected naming the closest known one, with ``file:line``), fills defaults and
returns :class:`Params`, one frozen dataclass per section (typed like branch-gen's ``Params``).
The dataclasses are the schema: each field's kind and default; :data:`SCHEMA` is derived from
them. Paths to ``.con``/``.func`` files are resolved relative to the parameter file.

Sections (thesis chapter 5):

- ``[surface]``   the generating curve C of the supporting surface (sec. 5.2, fig. 5.1);
- ``[primordia]`` primordium area A(s), divergence angle, floret type and placement (eq. 5.1-5.2);
- ``[dynamics]``  optional: fractionation / segregation over frames (sec. 5.3, fig. 5.2);
- ``[compound]``  optional: two-level pattern of conical heads (sec. 5.4, fig. 5.4);
- ``[hierarchy]`` optional: recursive segregation on a flat growing meristem (sec. 5.4, fig. 5.3);
- ``[receptacle]`` optional: also write the supporting surface as a mesh (:mod:`.receptacle`).
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import MISSING, dataclass, field, fields
from pathlib import Path

from inflo.formats.errors import FormatError, InputError, parse_toml, shorten
from inflo.formats.toml_params import LineStyle, ParamText, show_short, unknown_name

from .receptacle import PHYLLARY_VERTICES, ReceptacleOptions, phyllary_sagitta

__all__ = ["SCHEMA", "Params", "Surface", "Primordia", "Dynamics", "Compound", "Hierarchy", "read_params",
           "parse_params", "BUILTIN_CURVES", "DYNAMIC_MODES", "DEVELOPMENT_ORDERS"]

BUILTIN_CURVES = ("disk", "cone", "sphere_cap", "paraboloid")
DYNAMIC_MODES = ("centripetal", "divergent", "segregation")
DEVELOPMENT_ORDERS = ("none", "centripetal", "centrifugal")
GOLDEN_ANGLE = 137.50776405003785  # 360 (1 - 1/tau), degrees

_NUM = (int, float)
_FUNC = "number-or-func"  # a number or the path of a .func file
_CURVE = "curve"  # a built-in name or the path of a .con file

def _key(kind, default):
    """A parameter of a section: its kind (how :func:`parse_params` checks it) and default.

    Kinds: ``"float"``, ``"int"``, ``"str"``, ``"bool"``, ``_FUNC`` (a number or a ``.func`` path),
    ``_CURVE`` (a built-in curve name or a ``.con`` path), ``"curves"`` (a list of those),
    ``"floats"`` (a number or a list of numbers), ``("choice", options)``. A default of None: the
    key is optional and stays None when absent.
    """
    if isinstance(default, list):
        return field(default_factory=lambda: list(default), metadata={"kind": kind})
    return field(default=default, metadata={"kind": kind})


@dataclass(frozen=True)
class Surface:
    """``[surface]``: the generating curve C of the supporting surface (sec. 5.2, fig. 5.1)."""

    curve: str = _key(_CURVE, "disk")
    radius: float = _key("float", 1.0)
    height: float = _key("float", 0.0)
    angle: float = _key("float", 90.0)
    samples: int = _key("int", 2048)


@dataclass(frozen=True)
class Primordia:
    """``[primordia]``: primordium area A(s), divergence, floret type and placement (eq. 5.1-5.2)."""

    area: float | str = _key(_FUNC, 0.01)
    count: int = _key("int", 0)
    start: float = _key("float", 0.0)
    divergence: float = _key("float", GOLDEN_ANGLE)
    floret_id: int = _key("int", 0)
    size_factor: float = _key("float", 1.0)
    placement: str = _key(("choice", ("o", "ca")), "o")
    frame_start: int = _key("int", 0)
    frame_end: int = _key("int", 100)
    development_order: str = _key(("choice", DEVELOPMENT_ORDERS), "none")
    development_offset: float = _key("float", 1.0)
    development_frames: int | None = _key("int", None)
    max_count: int = _key("int", 1_000_000)


@dataclass(frozen=True)
class Dynamics:
    """``[dynamics]``: fractionation / segregation over frames (sec. 5.3, fig. 5.2)."""

    mode: str = _key(("choice", DYNAMIC_MODES), "centripetal")
    frames: int = _key("int", 100)
    interval: float = _key("float", 1.0)
    primordium_area: float = _key("float", 0.01)
    primordium_growth: float | str = _key(_FUNC, 0.0)
    inner_area: float = _key("float", 1.0)
    outer_area: float = _key("float", 0.0)
    inner_growth: float | str = _key(_FUNC, 0.0)
    outer_growth: float | str = _key(_FUNC, 0.0)
    threshold: float = _key("float", 0.0)
    curves: list = _key("curves", [])
    curve_times: list = _key("floats", [])
    substeps: int = _key("int", 0)
    development_frames: int | None = _key("int", None)
    max_count: int = _key("int", 1_000_000)
    close_apex: bool = _key("bool", False)
    apex_taper: float = _key("float", 0.0)
    apex_smallest: float = _key("float", 0.25)


@dataclass(frozen=True)
class Compound:
    """``[compound]``: a two-level pattern of conical heads (sec. 5.4, fig. 5.4)."""

    head_curve: str = _key(_CURVE, "cone")
    head_height: float = _key("float", 0.5)
    head_fill: float = _key("float", 1.0)
    floret_fraction: float = _key("float", 0.03)
    head_start: float = _key("float", 0.0)


@dataclass(frozen=True)
class Hierarchy:
    """``[hierarchy]``: recursive segregation on a flat growing meristem (sec. 5.4, fig. 5.3)."""

    levels: int = _key("int", 2)
    frames: float = _key("float", 100.0)
    growth_rate: float = _key("float", 0.05)
    initial_area: float = _key("float", 1.0)
    element_area: list = _key("floats", [1.0])
    production_threshold: list = _key("floats", [1.5])
    meristem_threshold: list = _key("floats", [8.0])
    divergence: float = _key("float", GOLDEN_ANGLE)
    dynamic: bool = _key("bool", False)
    development_frames: int | None = _key("int", None)
    max_count: int = _key("int", 200_000)
    fill_room: bool = _key("bool", False)
    room_margin: float = _key("float", 1.0)
    room_iterations: int = _key("int", 1)
    room_scale: list = _key("floats", [0.9, 1.5])
    room_weight: str = _key(("choice", ("size", "equal")), "size")
    room_outline: str = _key(("choice", ("discs", "hull")), "discs")


@dataclass(frozen=True)
class Params:
    """A checked phyllotaxis parameter file: one frozen dataclass per section, None for an optional
    section the file does not have (at most one of ``dynamics``, ``compound``, ``hierarchy``)."""

    surface: Surface = field(default_factory=Surface)
    primordia: Primordia = field(default_factory=Primordia)
    dynamics: Dynamics | None = None
    compound: Compound | None = None
    hierarchy: Hierarchy | None = None
    receptacle: ReceptacleOptions | None = None


_SECTIONS = {"surface": Surface, "primordia": Primordia, "dynamics": Dynamics, "compound": Compound,
             "hierarchy": Hierarchy, "receptacle": ReceptacleOptions}


def _schema(cls) -> dict[str, tuple]:
    """key -> (kind, default) of a section's dataclass; a field without a kind (the receptacle's
    options) is checked as its default's type."""
    out = {}
    for f in fields(cls):
        default = f.default_factory() if f.default is MISSING else f.default
        out[f.name] = (f.metadata.get("kind") or type(default).__name__, default)
    return out


#: section -> key -> (kind, default), from the dataclasses (the order of the checks and messages).
SCHEMA: dict[str, dict[str, tuple]] = {name: _schema(cls) for name, cls in _SECTIONS.items()}

_OPTIONAL = ("dynamics", "compound", "hierarchy")
# work limits (beyond them a run hangs or exhausts memory instead of saying so)
MAX_SAMPLES = 10_000_000
# the receptacle mesh and the room passes a frame (formats/phyllotaxis.md, "Bounds")
MAX_SEGMENTS = 4096
MAX_RINGS = 1024
MAX_RECEPTACLE_VERTICES = 1_000_000
MAX_PHYLLARY_ROWS = 12
MAX_ROOM_ITERATIONS = 1000
MAX_COUNT = 10_000_000  # primordia (count and the max_count guards)
MAX_FRAME = 10_000_000  # a frame number (frame_end)
MAX_SUBSTEPS = 10_000
MAX_LEVELS = 10  # levels of a recursive hierarchy
MAX_FRAMES = 100_000
MIN_INTERVAL = 1e-3
MAX_ID = 2**31 - 1  # a floret type id (the .fcc id, an int32 in the scene's arrays)
DIVERGENCE = (0.1, 359.9)  # degrees: beyond, every primordium lies on one line (and 1e-320 is no angle)
MAX_GROWTH = 1e12  # an area's growth over a run (exp of a rate x frames): no overflow, no 0/0
MAX_LOG_GROWTH = math.log(MAX_GROWTH)
MIN_AREA = 1e-12  # a primordium's area: its size (2 sqrt(A / pi)) not below the written precision of a position
#: placements over all RBA frames (frames x primordia present): the rows a dynamic run writes
MAX_RBA_ROWS = 20_000_000
# sections present in the result only when the file has them (besides the exclusive ones)
_WHEN_GIVEN = ("receptacle",)


#: how phyllotaxis finds a key's line: ``[table]`` headers (double quotes dropped, dots kept), keys
#: bare or in double quotes; no line when the key is absent
LINES = LineStyle(brackets="single", unquote=True, dotted=False, key_quotes='"')


def _text(path, text: str) -> ParamText:
    """The wording of phyllotaxis' errors: ``expected <section.key> as <what>``, found the
    value's repr (shortened)."""
    return ParamText(path, text, style=LINES, template="{name} as {expected}", show=show_short)


def _resolve(base: Path, value: str) -> str:
    p = Path(value)
    return str(p if p.is_absolute() else (base / p))


def parse_params(text: str, path="<params>") -> Params:
    """Parse and check TOML ``text``; returns :class:`Params` with defaults filled.

    The optional sections (``dynamics``, ``compound``, ``hierarchy``, ``receptacle``) are None
    unless the file has them. Relative ``.con``/``.func`` paths are resolved against the folder of
    ``path``. Every check runs on the values as read, before the dataclasses are built.

    Raises
    ------
    FormatError
        TOML syntax errors, unknown sections or keys (naming the closest known one), values of
        the wrong type or out of range, both ``[dynamics]`` and ``[hierarchy]``.
    """
    raw = parse_toml(text, path)
    w = _text(path, text)
    base = Path(os.fspath(path)).resolve().parent
    out: dict = {}
    for section, table in raw.items():
        if section not in SCHEMA:
            raise unknown_name(path, w.line(section, None), f"a section of {list(SCHEMA)}", section, SCHEMA,
                               found=f"[{section}]")
        if not isinstance(table, dict):
            raise FormatError(path, None, f"[{section}] as a table", shorten(repr(table)))
        schema = SCHEMA[section]
        for key in table:
            if key not in schema:
                raise unknown_name(path, w.line(section, key), f"a key of [{section}]", key, schema)
    for section, schema in SCHEMA.items():
        if section in _OPTIONAL + _WHEN_GIVEN and section not in raw:
            continue
        table = raw.get(section, {})
        values = {}
        for key, (kind, default) in schema.items():
            if key not in table:
                values[key] = list(default) if isinstance(default, list) else default
                continue
            values[key] = _check(table[key], kind, section, key, w, base)
        out[section] = values
    present = [sec for sec in _OPTIONAL if sec in out]
    if len(present) > 1:
        raise FormatError(path, w.line(present[1], None),
                          "at most one of [dynamics], [compound], [hierarchy]", f"[{present[0]}] and [{present[1]}]")
    _check_ranges(out, w)
    return Params(**{section: _SECTIONS[section](**values) for section, values in out.items()})


def _check(value, kind, section, key, w: ParamText, base):
    def bad(expected):
        return w.bad(section, key, expected, value)

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
    if kind == _FUNC:
        if isinstance(value, str):
            return _resolve(base, value)
        if isinstance(value, bool) or not isinstance(value, _NUM) or not math.isfinite(value):
            raise bad("a number or the path of a .func file")
        return float(value)
    if kind == _CURVE:
        if not isinstance(value, str):
            raise bad(f"one of {list(BUILTIN_CURVES)} or the path of a .con file")
        return value if value in BUILTIN_CURVES else _resolve(base, value)
    if kind == "curves":
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise bad("a list of curve names or .con paths")
        return [v if v in BUILTIN_CURVES else _resolve(base, v) for v in value]
    if kind == "floats":
        if isinstance(value, _NUM) and not isinstance(value, bool):
            value = [value]
        if not isinstance(value, list) or not value or not all(
                isinstance(v, _NUM) and not isinstance(v, bool) and math.isfinite(v) for v in value):
            raise bad("a number or a non-empty list of numbers")
        return [float(v) for v in value]
    raise AssertionError(kind)  # pragma: no cover


def _check_ranges(p: dict, w: ParamText) -> None:
    def fail(section, key, expected):
        raise w.error(section, key, expected, show_short(p[section][key]), template="{name} {expected}")

    s, pr = p["surface"], p["primordia"]
    if not 0 < s["radius"] <= 1e6:
        fail("surface", "radius", "in (0, 1e6] (coordinates stay far from overflow)")
    if s["curve"] == "sphere_cap" and not 0 < s["angle"] <= 180:
        fail("surface", "angle", "in (0, 180] degrees")
    if not 16 <= s["samples"] <= MAX_SAMPLES:
        fail("surface", "samples", f"in [16, {MAX_SAMPLES}] (arc-length samples of C)")
    if not abs(s["height"]) <= 1e6:
        fail("surface", "height", "within +-1e6 (coordinates stay far from overflow)")
    if not DIVERGENCE[0] <= pr["divergence"] <= DIVERGENCE[1]:
        fail("primordia", "divergence", f"in [{DIVERGENCE[0]:g}, {DIVERGENCE[1]:g}] degrees")
    if isinstance(pr["area"], float) and not MIN_AREA <= pr["area"] <= 1e12:
        fail("primordia", "area", f"> 0 (A(s) is a primordium area), in [{MIN_AREA:g}, 1e12]")
    if pr["count"] < 0:
        fail("primordia", "count", ">= 0 (0: fill the surface)")
    for section, key, high in (("primordia", "count", MAX_COUNT), ("primordia", "max_count", MAX_COUNT),
                               ("primordia", "frame_end", MAX_FRAME), ("dynamics", "max_count", MAX_COUNT),
                               ("dynamics", "substeps", MAX_SUBSTEPS), ("hierarchy", "levels", MAX_LEVELS),
                               ("hierarchy", "max_count", MAX_COUNT), ("hierarchy", "frames", MAX_FRAMES)):
        if section in p and isinstance(p[section].get(key), (int, float)) and not p[section][key] <= high:
            fail(section, key, f"<= {high}")
    if not 0 <= pr["start"] < 1:
        fail("primordia", "start", "in [0, 1) (fraction of the curve length)")
    if not 0 <= pr["floret_id"] <= MAX_ID:
        fail("primordia", "floret_id", f"in [0, {MAX_ID}] (an id of the .fcc file)")
    if not 1e-6 <= pr["size_factor"] <= 1e6:
        fail("primordia", "size_factor", "in (0, 1e6], at least 1e-6")
    if not 0 <= pr["frame_start"] <= pr["frame_end"]:
        fail("primordia", "frame_end", ">= frame_start >= 0")
    if not 0 <= pr["development_offset"] <= MAX_FRAME:
        fail("primordia", "development_offset", f">= 0 and <= {MAX_FRAME} frames per rank")
    for section in ("primordia", "dynamics", "hierarchy"):
        n = p.get(section, {}).get("development_frames")
        if n is not None and not 0 < n <= MAX_FRAME:
            fail(section, "development_frames", f"> 0 frames and <= {MAX_FRAME}")
    if "dynamics" in p:
        d = p["dynamics"]
        if not 1 <= d["frames"] <= MAX_FRAMES:
            fail("dynamics", "frames", f"in [1, {MAX_FRAMES}] (one RBA file per frame)")
        if not d["interval"] >= MIN_INTERVAL:
            fail("dynamics", "interval", f">= {MIN_INTERVAL:g} frames (at most {1 / MIN_INTERVAL:g} primordia per "
                                         "frame and front)")
        if not MIN_AREA <= d["primordium_area"] <= 1e12:
            fail("dynamics", "primordium_area", f"> 0, in [{MIN_AREA:g}, 1e12]")
        if not 0 <= d["inner_area"] <= 1e12:
            fail("dynamics", "inner_area", ">= 0 and <= 1e12")
        if not 0 <= d["outer_area"] <= 1e12:
            fail("dynamics", "outer_area", ">= 0 and <= 1e12")
        if d["mode"] == "segregation" and d["threshold"] <= d["primordium_area"]:
            fail("dynamics", "threshold", "> primordium_area (segregation needs room for a primordium)")
        if len(d["curves"]) != len(d["curve_times"]):
            fail("dynamics", "curve_times", f"one time per curve ({len(d['curves'])} curves)")
        if d["curve_times"] and any(b <= a for a, b in zip(d["curve_times"], d["curve_times"][1:])):
            fail("dynamics", "curve_times", "increasing")
        if d["substeps"] < 0:
            fail("dynamics", "substeps", ">= 0 (0: automatic)")
        for key in ("primordium_growth", "inner_growth", "outer_growth"):
            if isinstance(d[key], float) and not abs(d[key] * d["frames"]) <= MAX_LOG_GROWTH:
                fail("dynamics", key, f"x frames within +-{MAX_LOG_GROWTH:.4g} (an area grows or shrinks at most "
                                      f"{MAX_GROWTH:g}-fold over the run)")
        if not (d["apex_taper"] == 0.0 or 0.0 < d["apex_taper"] < 1.0):
            fail("dynamics", "apex_taper", "0 (off) or in (0, 1)")
        if not 0.0 < d["apex_smallest"] <= 1.0:
            fail("dynamics", "apex_smallest", "in (0, 1]")
        if d["apex_taper"] and d["mode"] == "segregation":
            fail("dynamics", "apex_taper", "0 in segregation (fractionation only)")
        if d["close_apex"] and d["mode"] == "segregation":
            fail("dynamics", "close_apex", "false in segregation (its inner region keeps growing: no apex to close)")
    if "receptacle" in p:
        rc = p["receptacle"]
        for key, low, what in (("segments", 3, ">= 3"), ("rings", 1, ">= 1"), ("underside_rings", 1, ">= 1"),
                               ("material", 0, ">= 0")):
            if rc[key] < low:
                fail("receptacle", key, what)
        for key, high in (("segments", MAX_SEGMENTS), ("rings", MAX_RINGS), ("underside_rings", MAX_RINGS)):
            if rc[key] > high:
                fail("receptacle", key, f"<= {high}")
        stump = 1 if rc["stem_length"] > 0 else 0
        if rc["segments"] * (rc["rings"] + rc["underside_rings"] + stump) > MAX_RECEPTACLE_VERTICES:
            fail("receptacle", "segments", f"x (rings + underside_rings{' + 1' if stump else ''}) <= "
                 f"{MAX_RECEPTACLE_VERTICES} (the receptacle's vertices a frame)")
        if not 0 < rc["depth"] <= 1000:
            fail("receptacle", "depth", "> 0 (a fraction of the rim radius), at most 1000")
        if not 0 <= rc["stem"] < 1:
            fail("receptacle", "stem", "in [0, 1) (a fraction of the rim radius)")
        if rc["inset"] < 0:
            fail("receptacle", "inset", ">= 0 scene units")
        if not 0 <= rc["phyllary_rows"] <= MAX_PHYLLARY_ROWS:
            fail("receptacle", "phyllary_rows", f"in [0, {MAX_PHYLLARY_ROWS}] (0: none)")
        if not 3 <= rc["phyllaries"] <= MAX_SEGMENTS:
            fail("receptacle", "phyllaries", f"in [3, {MAX_SEGMENTS}] (bracts a row)")
        if not 0 <= rc["phyllary_top"] < 0.9:
            fail("receptacle", "phyllary_top", "in [0, 0.9) (a share of the underside's arc)")
        if not 0 < rc["phyllary_length"] <= 0.92 - rc["phyllary_top"]:
            fail("receptacle", "phyllary_length", f"in (0, {0.92 - rc['phyllary_top']:.4g}] (a share of the underside's "
                 "arc, with phyllary_top at most 0.92)")
        if not 0 < rc["phyllary_width"] < 1:
            fail("receptacle", "phyllary_width", "in (0, 1) (a share of the bracts' spacing: they never overlap)")
        if not 0 < rc["phyllary_gap"] <= 0.05:
            fail("receptacle", "phyllary_gap", "in (0, 0.05] (a fraction of the rim radius)")
        if not 0 <= rc["phyllary_spread"] <= 1:
            fail("receptacle", "phyllary_spread", "in [0, 1] (a fraction of the rim radius)")
        if not 0 <= rc["phyllary_variation"] <= 0.3:
            fail("receptacle", "phyllary_variation", "in [0, 0.3] (0: every phyllary alike)")
        if not 0 <= rc["phyllary_seed"] < 2**63:
            fail("receptacle", "phyllary_seed", "in [0, 2^63)")
        if not 0 <= rc["stem_length"] <= 1000:
            fail("receptacle", "stem_length", "in [0, 1000] (a fraction of the rim radius; 0: none)")
        if rc["stem_length"] > 0 and rc["stem"] == 0:
            fail("receptacle", "stem_length", "0 when receptacle.stem is 0 (a stem of no width)")
        if rc["phyllary_rows"] and phyllary_sagitta(ReceptacleOptions(**rc)) >= 0.5 * rc["phyllary_gap"]:
            fail("receptacle", "phyllary_gap", f"at least {2 * phyllary_sagitta(ReceptacleOptions(**rc)):.4g} with "
                 "this depth, stem and phyllary_length (twice the sag of a phyllary's edges at the underside's "
                 "tightest bend)")
        if rc["phyllary_material"] < 0:
            fail("receptacle", "phyllary_material", ">= 0")
        if rc["phyllary_rows"] and rc["phyllary_rows"] * rc["phyllaries"] * PHYLLARY_VERTICES > MAX_RECEPTACLE_VERTICES:
            fail("receptacle", "phyllary_rows", f"x phyllaries x {PHYLLARY_VERTICES} <= {MAX_RECEPTACLE_VERTICES} "
                 "(the phyllaries' vertices a frame)")
    if "compound" in p:
        c = p["compound"]
        if not 0 < c["head_fill"] <= 1e3:
            fail("compound", "head_fill", "in (0, 1000]")
        if not abs(c["head_height"]) <= 1e3:
            fail("compound", "head_height", "within +-1000 (head radii)")
        if not 1e-6 <= c["floret_fraction"] < 1:
            fail("compound", "floret_fraction", "in (0, 1), at least 1e-6")
        if not 0 <= c["head_start"] < 1:
            fail("compound", "head_start", "in [0, 1) (head radii)")
    if "hierarchy" in p:
        h = p["hierarchy"]
        if h["levels"] < 1:
            fail("hierarchy", "levels", ">= 1")
        if h["frames"] <= 0:
            fail("hierarchy", "frames", "> 0")
        if h["initial_area"] <= 0:
            fail("hierarchy", "initial_area", "> 0")
        for key in ("element_area", "production_threshold", "meristem_threshold"):
            if any(v <= 0 for v in h[key]):
                fail("hierarchy", key, "> 0")
        for a, t in zip(_per_level(h["element_area"], h["levels"]), _per_level(h["production_threshold"], h["levels"])):
            if t <= a:
                fail("hierarchy", "production_threshold", "> element_area at every level")
        if not DIVERGENCE[0] <= h["divergence"] <= DIVERGENCE[1]:
            fail("hierarchy", "divergence", f"in [{DIVERGENCE[0]:g}, {DIVERGENCE[1]:g}] degrees")
        if h["development_frames"] is not None:
            if not h["dynamic"]:
                fail("hierarchy", "development_frames",
                     "only with dynamic = true (static files: [primordia] development_order/_frames)")
        if h["room_margin"] < 0:
            fail("hierarchy", "room_margin", ">= 0 (element radii)")
        if not 1 <= h["room_iterations"] <= MAX_ROOM_ITERATIONS:
            fail("hierarchy", "room_iterations", f"in [1, {MAX_ROOM_ITERATIONS}]")
        rs = h["room_scale"]
        if len(rs) != 2 or not 0 < rs[0] <= rs[1]:
            fail("hierarchy", "room_scale", "[lo, hi] with 0 < lo <= hi")


def _per_level(values: list, levels: int) -> list:
    """A per-level list: the last value repeats (a scalar means the same at every level)."""
    return [values[min(i, len(values) - 1)] for i in range(levels)]


def per_level(values: list, levels: int) -> list:
    """Public form of the per-level expansion used by :mod:`.hierarchy`."""
    return _per_level(values, levels)


def read_params(path) -> Params:
    """Read and check a phyllotaxis parameter file (see :func:`parse_params`)."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a folder, expected a .toml file") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise FormatError(path, None, "UTF-8 TOML text", "undecodable bytes") from None
    return parse_params(text, path)


_KEY_TOKEN = re.compile(r"\b([a-z_]+)\.([a-z_]+)\b")


def locate_error(exc: Exception, path) -> Exception:
    """An error raised by the model for a combination of keys (too many primordia, windows past the
    last frame, ...), with ``path:line:`` of the first ``section.key`` its message names that the
    parameter file holds (the key to change); ``exc`` itself when none is found or it has a line."""
    if isinstance(exc, FormatError) or not isinstance(exc, InputError):
        return exc
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return exc
    from inflo.formats.toml_params import line_of

    msg = str(exc)
    for section, key in _KEY_TOKEN.findall(msg):
        if section in SCHEMA and key in SCHEMA[section]:
            line = line_of(text, section, key, LINES) or line_of(text, section, None, LINES)
            if line:
                return InputError(f"{os.fspath(path)}:{line}: {msg}")
    return exc

