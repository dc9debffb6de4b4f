"""The petal-grow parameter file (TOML; spec: formats/petal_grow.md).

Sections: ``[flower]`` (run settings, joint-angle schedule), ``[growth.<name>]`` (one set of growth
maps and scalars, Ijiri et al. sec. 3.1, table 1) and ``[[organ]]`` (one petal or sepal: its bud
mesh, placement, arrangement and key growth sets in time, fig. 16). Every error names the file,
the line and what was expected.
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from inflo.formats.errors import FormatError, did_you_mean, parse_toml, shorten
from inflo.formats.toml_params import LineStyle, line_of, read_toml_text, unknown_name

from .maps import DirectionMap, ScalarMap, parse_direction_map, parse_scalar_map

__all__ = ["GrowthSet", "Organ", "Flower", "Params", "read_params", "parse_params", "FLOWER_KEYS",
           "GROWTH_KEYS", "ORGAN_KEYS"]

FLOWER_KEYS = {
    "keyframes": 100, "iterations": 40, "match_every": 5, "length_sweeps": 0, "collisions": True,
    "collision_distance": 0.05, "collision_iterations": 10, "collision_retries": 20,
    "joint": [[1, 0.0], [50, 15.0]], "base_v": 0.08, "check_every": 1,
}
GROWTH_KEYS = {
    "dg": 0.003, "thickness": 0.1, "K_s": 10.0, "K_b": 10.0, "direction": "0, 1",
    "e": 0.0, "w": 0.0, "e_in": 0.0, "w_in": 0.0, "stretch": 1.0, "bend": 1.0,
}
ORGAN_KEYS = {
    "name": None, "mesh": None, "material": None, "rotate": 0.0, "translate": [0.0, 0.0, 0.0],
    "layer": 0, "beneath": "", "growth": None, "joint": None, "base_v": None,
    "joint_axis": None, "joint_pivot": None,
}


@dataclass
class GrowthSet:
    """One set of growth maps (sec. 3.1) and the scalars of table 1."""

    name: str
    dg: float
    thickness: float
    K_s: float
    K_b: float
    direction: DirectionMap
    e: ScalarMap
    w: ScalarMap
    e_in: ScalarMap
    w_in: ScalarMap
    stretch: ScalarMap
    bend: ScalarMap


@dataclass
class Organ:
    name: str
    mesh: Path
    material: str
    rotate: float
    translate: tuple
    layer: int
    beneath: str
    growth: list          # [(step, GrowthSet name)], sorted by step
    joint: list           # [(step, degrees)]
    base_v: float
    joint_axis: tuple | None
    joint_pivot: tuple | None
    line: int | None = None


@dataclass
class Flower:
    keyframes: int
    iterations: int
    match_every: int
    length_sweeps: int
    collisions: bool
    collision_distance: float
    collision_iterations: int
    collision_retries: int
    joint: list
    base_v: float
    check_every: int


@dataclass
class Params:
    source: str
    flower: Flower
    growth: dict
    organs: list = field(default_factory=list)
    lines: dict = field(default_factory=dict)  # (table, key) -> line, for bounds checked on the bud


#: the work a parameter file may ask for (formats/petal_grow.md, "Bounds"): keyframes, solver
#: iterations a keyframe (and their product, the steps of the whole run), collision passes
MAX_KEYFRAMES = 10_000
MAX_ITERATIONS = 10_000
MAX_STEPS = 5_000_000
MAX_COLLISION_ITERATIONS = 1_000
#: placed coordinates (translate, joint_pivot, joint_axis components), scene units; a layer index
MAX_COORDINATE = 1e6


#: how petal-grow finds a key's line: in the ``index``-th ``[table]``/``[[table]]`` of that exact
#: name (``growth.NAME`` whole), bare keys, up to the next header; absent: the header's line
LINES = LineStyle(brackets="pair", dotted=False, key_quotes="", one_table=True)


def _line(text: str, table: str, key: str | None, index: int = 0) -> int | None:
    """1-based line of ``key`` in the ``index``-th ``[table]``/``[[table]]`` header's body (or the
    header's own line when ``key`` is None or absent)."""
    return line_of(text, table, key, LINES, index)


def _check_keys(data: dict, known: dict, path, text, table, index=0):
    for k in data:
        if k not in known:
            raise unknown_name(path, _line(text, table, k, index), f"a key of [{table}] ({', '.join(known)})", k, known)


def _num(value, path, line, what, lo=None, hi=None, integer=False):
    ok = isinstance(value, (int, float)) and not isinstance(value, bool)
    if integer:
        ok = ok and isinstance(value, int)
    if not ok or not math.isfinite(value) or (lo is not None and value < lo) or (hi is not None and value > hi):
        rng = f" in [{lo}, {hi}]" if hi is not None else (f" >= {lo}" if lo is not None else "")
        raise FormatError(path, line, f"{what}: {'an integer' if integer else 'a number'}{rng}", shorten(repr(value)))
    return int(value) if integer else float(value)


def _vec3(value, path, line, what):
    if not (isinstance(value, list) and len(value) == 3):
        raise FormatError(path, line, f"{what}: three numbers [x, y, z]", shorten(repr(value)))
    return tuple(_num(v, path, line, what, lo=-MAX_COORDINATE, hi=MAX_COORDINATE) for v in value)


def _schedule(value, path, line, what, kind):
    """[[step, value], ...] with increasing integer steps >= 0."""
    if not isinstance(value, list) or not value:
        raise FormatError(path, line, f"{what}: a list of [step, {kind}] pairs", shorten(repr(value)))
    out = []
    for item in value:
        if not (isinstance(item, list) and len(item) == 2):
            raise FormatError(path, line, f"{what}: [step, {kind}] pairs", shorten(repr(item)))
        step = _num(item[0], path, line, f"{what} step", lo=0, integer=True)
        if out and step <= out[-1][0]:
            raise FormatError(path, line, f"{what}: increasing steps", shorten(repr(value)))
        out.append((step, item[1]))
    return out


def read_params(path) -> Params:
    """Read and check a parameter file; maps and paths are relative to its folder."""
    return parse_params(read_toml_text(path, _undecodable), os.fspath(path))


def _undecodable(path, data: bytes, exc: UnicodeDecodeError) -> FormatError:
    return FormatError(path, None, "UTF-8 TOML text", f"a byte that is not UTF-8 at offset {exc.start}")


def parse_params(text: str, path="<params>") -> Params:
    """Parse and check TOML ``text`` (see formats/petal_grow.md)."""
    path = os.fspath(path)
    raw = parse_toml(text, path)
    base = Path(path).resolve().parent
    for k in raw:
        if k not in ("flower", "growth", "organ"):
            raise unknown_name(path, _line(text, k, None) or _line(text, "", k),
                               "a section [flower], [growth.NAME] or [[organ]]", k, ["flower", "growth", "organ"])
    fl = raw.get("flower", {})
    if not isinstance(fl, dict):
        raise FormatError(path, None, "[flower] as a table", shorten(repr(fl)))
    _check_keys(fl, FLOWER_KEYS, path, text, "flower")
    g = {**FLOWER_KEYS, **fl}

    def L(key):
        return _line(text, "flower", key)

    flower = Flower(
        keyframes=_num(g["keyframes"], path, L("keyframes"), "keyframes", lo=1, hi=MAX_KEYFRAMES, integer=True),
        iterations=_num(g["iterations"], path, L("iterations"), "iterations", lo=0, hi=MAX_ITERATIONS, integer=True),
        match_every=_num(g["match_every"], path, L("match_every"), "match_every", lo=1, hi=MAX_ITERATIONS, integer=True),
        length_sweeps=_num(g["length_sweeps"], path, L("length_sweeps"), "length_sweeps", lo=0, hi=MAX_ITERATIONS,
                           integer=True),
        collisions=bool(g["collisions"]) if isinstance(g["collisions"], bool) else
        _bad(path, L("collisions"), "collisions: true or false", g["collisions"]),
        collision_distance=_num(g["collision_distance"], path, L("collision_distance"), "collision_distance", lo=0.0),
        collision_iterations=_num(g["collision_iterations"], path, L("collision_iterations"),
                                  "collision_iterations", lo=1, hi=MAX_COLLISION_ITERATIONS, integer=True),
        collision_retries=_num(g["collision_retries"], path, L("collision_retries"), "collision_retries",
                               lo=0, hi=MAX_COLLISION_ITERATIONS, integer=True),
        joint=[(s, _num(d, path, L("joint"), "joint angle (degrees)", lo=-180, hi=180))
               for s, d in _schedule(g["joint"], path, L("joint"), "joint", "degrees")],
        base_v=_num(g["base_v"], path, L("base_v"), "base_v", lo=0.0, hi=1.0),
        check_every=_num(g["check_every"], path, L("check_every"), "check_every", lo=0, integer=True),
    )
    if flower.keyframes * max(flower.iterations, 1) > MAX_STEPS:
        raise FormatError(path, L("iterations"), f"keyframes x iterations <= {MAX_STEPS} (the solver steps of the run)",
                          f"{flower.keyframes} x {flower.iterations}")
    growth_raw = raw.get("growth", {})
    if not isinstance(growth_raw, dict) or not growth_raw:
        raise FormatError(path, None, "at least one [growth.NAME] table", "none")
    sets = {}
    for name, tbl in growth_raw.items():
        table = f"growth.{name}"
        if not isinstance(tbl, dict):
            raise FormatError(path, _line(text, table, None), f"[{table}] as a table", shorten(repr(tbl)))
        _check_keys(tbl, GROWTH_KEYS, path, text, table)
        v = {**GROWTH_KEYS, **tbl}

        def gl(key, table=table):
            return _line(text, table, key)

        sets[name] = GrowthSet(
            name=name,
            dg=_num(v["dg"], path, gl("dg"), "dg", lo=0.0, hi=1.0),
            thickness=_num(v["thickness"], path, gl("thickness"), "thickness", lo=1e-9),
            K_s=_num(v["K_s"], path, gl("K_s"), "K_s", lo=0.0),
            K_b=_num(v["K_b"], path, gl("K_b"), "K_b", lo=0.0),
            direction=parse_direction_map(v["direction"], base, path, gl("direction"), "direction"),
            **{k: parse_scalar_map(v[k], base, path, gl(k), k) for k in ("e", "w", "e_in", "w_in", "stretch", "bend")},
        )
    organs_raw = raw.get("organ", [])
    if not isinstance(organs_raw, list) or not organs_raw:
        raise FormatError(path, None, "at least one [[organ]] table", "none")
    organs, names = [], set()
    for i, tbl in enumerate(organs_raw):
        _check_keys(tbl, ORGAN_KEYS, path, text, "organ", i)

        def ol(key, i=i):
            return _line(text, "organ", key, i)

        for req in ("name", "mesh", "growth"):
            if req not in tbl:
                raise FormatError(path, ol(None), f"'{req}' in every [[organ]]", "none")
        name = tbl["name"]
        if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9_.-]+", name) or name in names:
            raise FormatError(path, ol("name"), "a unique organ name (letters, digits, _ . -)", shorten(repr(name)))
        names.add(name)
        if not isinstance(tbl["mesh"], str):
            raise FormatError(path, ol("mesh"), "mesh: a path to an OBJ file", shorten(repr(tbl["mesh"])))
        material = tbl.get("material", name)
        if not isinstance(material, str) or not re.fullmatch(r"\S+", material):
            raise FormatError(path, ol("material"), "material: a name without blanks", shorten(repr(material)))
        growth = []
        for s, nm in _schedule(tbl["growth"], path, ol("growth"), "growth", "growth set name"):
            if nm not in sets:
                raise FormatError(path, ol("growth"), f"a [growth.NAME] set{did_you_mean(str(nm), sets)}", repr(nm))
            growth.append((s, nm))
        joint = flower.joint
        if tbl.get("joint") is not None:
            joint = [(s, _num(d, path, ol("joint"), "joint angle (degrees)", lo=-180, hi=180))
                     for s, d in _schedule(tbl["joint"], path, ol("joint"), "joint", "degrees")]
        beneath = tbl.get("beneath", "")
        if not isinstance(beneath, str):
            raise FormatError(path, ol("beneath"), "beneath: an organ name", shorten(repr(beneath)))
        organs.append(Organ(
            name=name, mesh=base / tbl["mesh"], material=material,
            rotate=_num(tbl.get("rotate", 0.0), path, ol("rotate"), "rotate (degrees)", lo=-360, hi=360),
            translate=_vec3(tbl.get("translate", [0.0, 0.0, 0.0]), path, ol("translate"), "translate"),
            layer=_num(tbl.get("layer", 0), path, ol("layer"), "layer", lo=-MAX_COORDINATE, hi=MAX_COORDINATE,
                       integer=True),
            beneath=beneath, growth=growth, joint=joint,
            base_v=flower.base_v if tbl.get("base_v") is None else
            _num(tbl["base_v"], path, ol("base_v"), "base_v", lo=0.0, hi=1.0),
            joint_axis=None if tbl.get("joint_axis") is None else _vec3(tbl["joint_axis"], path, ol("joint_axis"), "joint_axis"),
            joint_pivot=None if tbl.get("joint_pivot") is None else _vec3(tbl["joint_pivot"], path, ol("joint_pivot"), "joint_pivot"),
            line=ol(None),
        ))
    for o in organs:
        if o.beneath and o.beneath not in names:
            raise FormatError(path, _line(text, "organ", "beneath", organs.index(o)),
                              f"beneath: an organ name{did_you_mean(o.beneath, names)}", repr(o.beneath))
    lines = {("flower", "collision_distance"): L("collision_distance")}
    lines.update({(f"growth.{name}", "thickness"): _line(text, f"growth.{name}", "thickness") for name in sets})
    return Params(source=path, flower=flower, growth=sets, organs=organs, lines=lines)


def _bad(path, line, expected, value):
    raise FormatError(path, line, expected, shorten(repr(value)))
