"""thyrse parameter files (TOML). Spec: ``formats/thyrse.md``.

Two sections of their own, validated here, and branch-gen's mesh sections, validated by
:func:`inflo.tools.branch_gen.params.params_from_dict` (one parser for the branch geometry):

- ``[thyrse]``: the architecture, as positional information (thesis sec. 4.5: "a previously
  published model of lilac inflorescence architecture" -- Prusinkiewicz et al.'s lilac, whose
  laterals' length, branching order and floret density are functions of their position along the
  main axis);
- ``[development]``: each floret's development window from its position (lower florets first);
- ``[obstacle]``: the branches as an obstacle placement for fccompose (optional);
- ``[pipe]``, ``[cylinder]``: branch widths (pipe model) and the generalized cylinders, as in
  ``formats/branch_gen.md``.

A positional key takes a number (constant) or a ``.func`` file name (relative to the parameter
file), read with :mod:`inflo.formats.func`: y = f(x), x the relative position in [0, 1].
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from inflo.formats.func import Function, read_func
from inflo.formats.toml_params import read_toml_lines, unknown_name
from inflo.tools.branch_gen.params import Params as BranchParams
from inflo.tools.branch_gen.params import param_text, params_from_dict

__all__ = ["ThyrseParams", "DevelopmentParams", "Params", "read_params", "params_from_toml", "POSITIONAL"]

#: the positional keys of [thyrse] and [development]: a number or a .func of x in [0, 1]
#: ``facing``: a floret's axis from its stalk, or the outward normal of the panicle's surface
FACING = ("stalk", "surface")
POSITIONAL = ("lateral_length", "order", "density", "branch_density", "angle", "sub_angle", "floret_size", "start")


@dataclass
class ThyrseParams:
    """The branching architecture (thesis sec. 4.5, fig. 4.10; ch. 7's branching-first model)."""

    length: float = 1.0  # main axis, base -> apex along +Y (scene units)
    nodes: int = 8  # decussate node pairs on the main axis
    first_node: float = 0.2  # relative height of the lowest node (the bare peduncle below it)
    divergence: float = 90.0  # degrees between successive node pairs (90: decussate)
    lateral_length: object = 0.5  # child length / parent length, of the node's position on its parent
    order: object = 1.0  # branching order of a main-axis lateral, of its node's height (rounded)
    density: object = 10.0  # node pairs per unit length on the laterals, of the main-axis height
    branch_density: object = None  # the same on laterals of order > 0 (None: density)
    angle: object = 50.0  # branch angle from the parent axis (degrees), of the main-axis height
    sub_angle: object = None  # laterals of laterals: angle of the node's position on its parent (None: angle)
    outward: bool = False  # a lateral's children that would point towards the main axis are not formed
    pedicel_length: float = 0.03  # from an order-0 axis' node to its floret
    pedicel_angle: float = 60.0  # degrees from the parent axis
    tropism: float = 0.0  # a floret's axis: its stalk's direction + tropism * Y, normalized
    floret_size: object = 0.05  # floret scale (its model's unit diameter), of the floret's height
    floret_id: int = 0  # the .fcc animation id of the florets
    min_distance: float = 0.0  # floret sizes between limb points; a floret with less room is not formed (0: off)
    reach: float = 0.7  # the limb point: pos + reach * size * up (floret units: where the open limb sits)
    facing: str = "stalk"  # a floret's axis: "stalk" (its stalk's direction) or "surface" (turned to the outward normal)
    surface_weight: float = 1.0  # facing = "surface": axis = stalk + surface_weight * normal (+ tropism * Y)
    size_variation: float = 0.0  # each floret's size times a seeded factor in [1 - v, 1 + v]
    seed: int = 0  # of the per-floret variation (size, start)


@dataclass
class DevelopmentParams:
    """Development windows (``ca: frameStart frameEnd``) from position: lower florets open first."""

    frames: int = 40  # canopy frames 0..frames-1
    window: int = 20  # frameEnd - frameStart of every floret
    start: object = "linear"  # frameStart / span, of the floret's height
    span: int = -1  # frames the starts spread over (-1: frames - 1 - window, every window ends in the run)
    start_variation: int = 0  # frames added to each frameStart: a seeded integer in [-k, k]


@dataclass
class ObstacleParams:
    """The branches as an fccompose obstacle (formats/thyrse.md "Obstacle"; :mod:`.obstacle`)."""

    id: int = -1  # the .fcc animation id of the obstacle placement (-1: no obstacle)
    gap: float = 0.002  # clearance between the obstacle's tubes and at its ends (length)
    margin: float = 0.0  # the tubes' radius over the branches' (length)


@dataclass
class Params:
    thyrse: ThyrseParams = field(default_factory=ThyrseParams)
    development: DevelopmentParams = field(default_factory=DevelopmentParams)
    obstacle: ObstacleParams = field(default_factory=ObstacleParams)
    branches: BranchParams = field(default_factory=BranchParams)
    base: list = field(default_factory=lambda: [0.0, 0.0, 0.0])
    source: str | None = None
    folder: Path = field(default_factory=Path)
    functions: dict = field(default_factory=dict)  # key -> Function (constants included)


#: the longest development a thyrse lays out (frames)
MAX_FRAMES = 100000
MAX_LENGTH = 1e6  # lengths (thyrse.length, pedicel_length): coordinates stay far from overflow
MIN_LENGTH = 1e-6  # ... and not below the written precision of a position (a subnormal 1e-320 is no length)
MAX_ID = 2**31 - 1  # an .fcc animation id (an int32 in the scene's arrays)
MAX_AXIS_NODES = 10_000  # node pairs on the main axis

_OWN = {"thyrse": ThyrseParams, "development": DevelopmentParams, "obstacle": ObstacleParams}
_BRANCH = ("pipe", "cylinder")
_TOP = ("base",)


def _positional(w, sec, key, v, folder: Path):
    """A number (a constant function) or a .func file."""
    if isinstance(v, str):
        if key == "start" and v == "linear":
            return Function.from_points([(0.0, 0.0), (1.0, 1.0)], name="start")
        q = Path(v) if Path(v).is_absolute() else folder / v
        if not q.is_file():
            raise w.error(sec, key, "a number or an existing .func file", repr(v))
        return read_func(q)
    return Function.constant(w.number(sec, key, v), name=key)


def params_from_toml(data: dict, *, path="<params>", lines=None, folder=None) -> Params:
    """Build :class:`Params` from a parsed TOML mapping, validating every key.

    Raises
    ------
    FormatError
        Unknown key/section (naming the closest known one), wrong type, out-of-range value, a
        positional key naming no file.
    """
    w = param_text(path, lines or [])
    folder = Path(folder) if folder is not None else Path(".")
    p = Params(source=str(path), folder=folder)
    known = list(_TOP) + list(_OWN) + list(_BRANCH)
    rest = {}
    for key, v in data.items():
        if key not in known:
            raise unknown_name(path, w.line(None, key) or w.line(key, ""), "a known key or section", key, known)
        if key == "base":
            p.base = w.vector(None, key, v)
        elif key in _BRANCH:
            rest[key] = v
        else:
            if not isinstance(v, dict):
                raise w.error(None, key, "a [section]", repr(v))
            obj = getattr(p, key)
            names = list(obj.__dataclass_fields__)
            for k, val in v.items():
                if k not in names:
                    raise unknown_name(path, w.line(key, k), f"a key of [{key}]", k, names)
                default = getattr(obj, k)
                if k in POSITIONAL:
                    setattr(obj, k, val)
                elif isinstance(default, str):
                    if val not in FACING:
                        raise w.error(key, k, "one of " + ", ".join(repr(f) for f in FACING), repr(val))
                    setattr(obj, k, val)
                elif isinstance(default, bool):
                    if not isinstance(val, bool):
                        raise w.error(key, k, "true or false", repr(val))
                    setattr(obj, k, val)
                elif isinstance(default, int) and not isinstance(default, bool):
                    setattr(obj, k, w.integer(key, k, val))
                else:
                    setattr(obj, k, w.number(key, k, val))
    p.branches = params_from_dict(rest, path=path, lines=lines, folder=folder)
    t, d = p.thyrse, p.development
    for sec, obj in (("thyrse", t), ("development", d)):
        for k in POSITIONAL:
            if hasattr(obj, k) and getattr(obj, k) is not None:
                p.functions[k] = _positional(w, sec, k, getattr(obj, k), folder)

    def need(ok, sec, key, expected, found):
        if not ok:
            raise w.error(sec, key, expected, repr(found))

    need(all(math.isfinite(c) and abs(c) <= 1e12 for c in p.base), None, "base",
         "coordinates within +-1e+12", p.base)
    need(MIN_LENGTH <= t.length <= MAX_LENGTH, "thyrse", "length",
         f"a length in (0, {MAX_LENGTH:g}] and >= {MIN_LENGTH:g}", t.length)
    need(0 <= t.nodes <= MAX_AXIS_NODES, "thyrse", "nodes", f"an integer in [0, {MAX_AXIS_NODES}]", t.nodes)
    need(0 <= t.first_node < 1, "thyrse", "first_node", "a relative height in [0, 1)", t.first_node)
    need(MIN_LENGTH <= t.pedicel_length <= MAX_LENGTH, "thyrse", "pedicel_length",
         f"a length in (0, {MAX_LENGTH:g}] and >= {MIN_LENGTH:g}", t.pedicel_length)
    need(1 <= t.pedicel_angle <= 179, "thyrse", "pedicel_angle", "an angle in (0, 180) degrees, from 1 to 179",
         t.pedicel_angle)
    need(0 <= t.tropism <= 1e6, "thyrse", "tropism", "a weight in [0, 1e6]", t.tropism)
    need(-360 <= t.divergence <= 360, "thyrse", "divergence", "an angle in [-360, 360] degrees", t.divergence)
    need(0 <= t.floret_id <= MAX_ID, "thyrse", "floret_id", f"an id in [0, {MAX_ID}]", t.floret_id)
    need(0 <= t.min_distance <= 1e6, "thyrse", "min_distance", "a distance in [0, 1e6]", t.min_distance)
    need(0 <= t.reach <= 1e6, "thyrse", "reach", "a reach in [0, 1e6]", t.reach)
    need(0 <= t.surface_weight <= 1e6, "thyrse", "surface_weight", "a weight in [0, 1e6]", t.surface_weight)
    need(0 <= t.size_variation <= 0.5, "thyrse", "size_variation", "a fraction in [0, 0.5]", t.size_variation)
    need(0 <= t.seed < 2**63, "thyrse", "seed", "an integer in [0, 2**63)", t.seed)
    o = p.obstacle
    need(-1 <= o.id <= MAX_ID, "obstacle", "id", f"an id in [0, {MAX_ID}] (or -1: none)", o.id)
    need(o.id != t.floret_id, "obstacle", "id", f"an id other than the florets' ({t.floret_id})", o.id)
    need(MIN_LENGTH <= o.gap <= 1e6, "obstacle", "gap", f"a length in (0, 1e6] and >= {MIN_LENGTH:g}", o.gap)
    need(0 <= o.margin <= 1e6, "obstacle", "margin", "a length in [0, 1e6]", o.margin)
    need(1 <= d.frames <= MAX_FRAMES, "development", "frames", f"an integer in [1, {MAX_FRAMES}]", d.frames)
    need(0 <= d.window <= d.frames - 1, "development", "window", "0 <= window <= frames - 1", d.window)
    need(d.span == -1 or 0 <= d.span <= d.frames - 1, "development", "span", "-1 or 0 <= span <= frames - 1", d.span)
    need(0 <= d.start_variation <= d.frames - 1, "development", "start_variation", "0 <= start_variation <= frames - 1",
         d.start_variation)
    ranges = {"lateral_length": (0.0, 10.0), "order": (0.0, 6.0), "density": (0.0, 1e6), "branch_density": (0.0, 1e6),
              "angle": (1.0, 179.0), "sub_angle": (1.0, 179.0), "floret_size": (1e-9, 1e6), "start": (0.0, 1.0)}
    for k, (lo, hi) in ranges.items():
        if k not in p.functions:
            continue
        ys = p.functions[k].sampled()[1]
        sec = "development" if k == "start" else "thyrse"
        need(all(lo <= y <= hi and math.isfinite(y) for y in ys), sec, k, f"values in [{lo:g}, {hi:g}]",
             f"{min(ys):g}..{max(ys):g}")
    return p


def read_params(path=None) -> Params:
    """Read a thyrse TOML parameter file (None: all defaults)."""
    if path is None:
        return params_from_toml({})
    data, lines = read_toml_lines(path)
    return params_from_toml(data, path=path, lines=lines, folder=Path(path).parent)
