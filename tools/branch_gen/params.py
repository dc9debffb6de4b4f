"""branch-gen parameter files (TOML). Spec: ``formats/branch_gen.md``.

Every key has a default, so an empty file (or no file) is valid. Unknown keys and sections are
rejected naming the closest known one; wrong types and out-of-range values are rejected naming the
file, the key's line and what was expected (docs/architecture.md, "Errors").

Sections (thesis ch. 7 for ``rodkaew``, Runions ch. 3 for ``sca``/``envelope``):

- top level: ``algorithm``, ``seed``, ``base``;
- ``[rodkaew]``: extended Rodkaew particles (eq. 7.1, fig. 7.4, fig. 7.5, fig. 7.2b);
- ``[growth]``: uniform or allometric expansion of space (7.2 "Growth");
- ``[sca]``: space colonization (eq. 3.1, 3.3; kill distance, radius of influence);
- ``[envelope]``: crown envelope (generalized surface of revolution, eq. 3.4, or a built-in);
- ``[post]``: skeleton post-processing (decimation fig. 3.8, relocation, subdivision);
- ``[pipe]``: branch width by the pipe model (7.2 "Branch width", eq. 3.5);
- ``[cylinder]``: generalized-cylinder mesh.
"""
from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from inflo.formats.errors import InputError
from inflo.formats.toml_params import LineStyle, ParamText, read_toml_lines, show_repr, unknown_name

__all__ = [
    "Params",
    "RodkaewParams",
    "GrowthParams",
    "ScaParams",
    "EnvelopeParams",
    "ContourSpec",
    "PostParams",
    "PipeParams",
    "CylinderParams",
    "read_params",
    "params_from_dict",
    "param_text",
    "ALGORITHMS",
    "key_error",
]

ALGORITHMS = ("rodkaew", "sca")
INF = math.inf


@dataclass
class RodkaewParams:
    """Extended Rodkaew algorithm (thesis 7.2)."""

    step: float = 0.01  # particle step length per simulation step (scene units)
    merge_distance: float = 0.015  # graft when another tree is this close (fig. 7.5b)
    w_a: float = 1.0  # weight of A, toward the base (eq. 7.1)
    w_b: float = 0.6  # weight of B, toward the nearest other tree (eq. 7.1)
    w_h: float = 0.6  # weight of H, previous direction (eq. 7.1)
    w_b_func: str = ""  # .func file: w_b(d) = w_b * f(d / w_b_range) (fig. 7.4); "" = constant
    w_b_range: float = 1.0  # distance d mapped to x = 1 of w_b_func
    perception_radius: float = INF  # B is the nearest other tree within this distance ("inf")
    initial_direction: str = "floret"  # "floret": H starts along -up of the floret; "base": along A
    steps_per_frame: int = 10  # simulation steps per frame of emergence time
    max_steps: int = 200000  # hard stop
    hierarchy: bool = True  # groups (umbellets, heads) converge on their centres first (fig. 7.2b)


@dataclass
class GrowthParams:
    """Expansion of space over time (thesis 7.2 "Growth"): S(t) = (1 + rate)^t per axis, or per-axis
    scale functions."""

    mode: str = "none"  # "none", "uniform", "allometric" or "functions"
    rate: float = 0.0  # uniform: relative expansion per frame
    rates: list = field(default_factory=lambda: [0.0, 0.0, 0.0])  # allometric: per-axis rates
    funcs: list = field(default_factory=list)  # functions: three .func files, scale over t / frames
    frames: float = -1.0  # growth stops at this frame; -1: the last emergence / last RBA frame
    _functions: object = None  # the loaded funcs (not a file key)


@dataclass
class ScaParams:
    """Space colonization (Runions ch. 3)."""

    n_points: int = 1000  # N attraction points
    min_distance: float = 0.0  # b_d: minimum distance between attraction points (0: uniform)
    influence_radius: float = INF  # d_I, radius of influence
    kill_distance: float = 0.02  # d_k
    step: float = 0.01  # D, the basic unit
    tropism: list = field(default_factory=lambda: [0.0, 0.0, 0.0])  # g, eq. 3.3
    roots: list = field(default_factory=lambda: [[0.0, 0.0, 0.0]])  # initial tree nodes
    obstacles: list = field(default_factory=list)  # planes [nx, ny, nz, c]: remove points n.p > c
    add_points: int = 0  # attraction points added per iteration
    add_iterations: int = 0  # ... during this many first iterations
    max_iterations: int = 100000


@dataclass
class ContourSpec:
    file: str
    angle: float  # degrees


@dataclass
class EnvelopeParams:
    """Crown envelope: a built-in shape or a generalized surface of revolution (eq. 3.4)."""

    shape: str = "sphere"  # sphere, ellipsoid, cone, cylinder, contours
    centre: list = field(default_factory=lambda: [0.0, 1.0, 0.0])  # built-ins; contours: axis origin
    radius: float = 1.0  # sphere, cone (at its base), cylinder
    radii: list = field(default_factory=lambda: [1.0, 1.0, 1.0])  # ellipsoid semi-axes
    height: float = 1.0  # cone, cylinder (along +Y from centre)
    contours: list = field(default_factory=list)  # [{file = "c.con", angle = 0.0}, ...]


@dataclass
class PostParams:
    """Skeleton post-processing (Runions fig. 3.1 e-g, fig. 3.8)."""

    decimate: float = 0.0  # tau_d; 0: off
    relocate: bool = False  # move interior nodes half way toward their basal neighbour
    subdivide: int = 0  # levels of curve subdivision


@dataclass
class PipeParams:
    """Pipe model d^p = d_1^p + ... + d_m^p (thesis 7.2, Runions eq. 3.5)."""

    tip_diameter: float = 0.004
    exponent: float = 2.5


@dataclass
class CylinderParams:
    sides: int = 8
    caps: bool = True


@dataclass
class Params:
    """All branch-gen parameters."""

    algorithm: str = "rodkaew"
    seed: int = 1
    base: list = field(default_factory=lambda: [0.0, 0.0, 0.0])
    rodkaew: RodkaewParams = field(default_factory=RodkaewParams)
    growth: GrowthParams = field(default_factory=GrowthParams)
    sca: ScaParams = field(default_factory=ScaParams)
    envelope: EnvelopeParams = field(default_factory=EnvelopeParams)
    post: PostParams = field(default_factory=PostParams)
    pipe: PipeParams = field(default_factory=PipeParams)
    cylinder: CylinderParams = field(default_factory=CylinderParams)
    source: str | None = None  # the file read, for error messages
    folder: Path = field(default_factory=Path)  # relative paths are relative to this
    lines: list = field(default_factory=list, repr=False)  # the file's lines, for errors naming a key's line


_SECTIONS = {
    "rodkaew": RodkaewParams,
    "growth": GrowthParams,
    "sca": ScaParams,
    "envelope": EnvelopeParams,
    "post": PostParams,
    "pipe": PipeParams,
    "cylinder": CylinderParams,
}
_TOP = ("algorithm", "seed", "base")


#: how branch-gen finds a key's line: top-level keys have no section; a key not found points at its
#: section's header
LINES = LineStyle(top=None, fallback="prefix")


def param_text(path, lines) -> ParamText:
    """The wording of branch-gen's (and thyrse's) errors: ``expected <what> for '<section.key>'``,
    found the value's repr, at the key's line."""
    return ParamText(path, "\n".join(lines), style=LINES, template="{expected} for '{name}'", show=show_repr)


def key_error(p: Params, sec: str | None, key: str, expected: str, found: str):
    """The :class:`~inflo.formats.errors.FormatError` about ``sec.key`` of ``p``'s file, at the key's
    line (a bound that depends on more than the file: the scene, the envelope)."""
    return param_text(p.source or "<params>", p.lines).error(sec, key, expected, found)


def params_from_dict(data: dict, *, path="<params>", lines=None, folder=None) -> Params:
    """Build :class:`Params` from a parsed TOML mapping, validating every key.

    Raises
    ------
    FormatError
        Unknown key/section (naming the closest known one), wrong type, out-of-range value.
    """
    w = param_text(path, lines or [])
    p = Params(source=os.fspath(path), folder=Path(folder) if folder is not None else Path("."), lines=list(lines or []))
    known_top = list(_TOP) + list(_SECTIONS)
    for key, v in data.items():
        if key not in known_top:
            raise unknown_name(path, w.line(None, key) or w.line(key, ""), "a known key or section", key, known_top)
        if key in _SECTIONS:
            if not isinstance(v, dict):
                raise w.error(None, key, "a [section]", repr(v))
            obj = getattr(p, key)
            fields = [f for f in obj.__dataclass_fields__ if not f.startswith("_")]
            for k, val in v.items():
                if k not in fields:
                    raise unknown_name(path, w.line(key, k), f"a key of [{key}]", k, fields)
                setattr(obj, k, _convert(w, key, k, val, getattr(obj, k)))
        elif key == "algorithm":
            if v not in ALGORITHMS:
                raise w.error(None, key, "'rodkaew' or 'sca'", repr(v))
            p.algorithm = v
        elif key == "seed":
            p.seed = w.integer(None, key, v)
            if not 0 <= p.seed <= 2**32 - 1:
                raise w.error(None, key, "a seed in [0, 4294967295]", repr(v))
        elif key == "base":
            p.base = w.vector(None, key, v)
    _validate(p, w)
    return p


def _convert(w, sec, key, val, default):
    if sec == "envelope" and key == "contours":
        if not isinstance(val, list):
            raise w.error(sec, key, "a list of {file = ..., angle = ...} tables", repr(val))
        out = []
        for item in val:
            if not isinstance(item, dict) or set(item) != {"file", "angle"} or not isinstance(item["file"], str):
                raise w.error(sec, key, "tables {file = \"name.con\", angle = degrees}", repr(item))
            out.append(ContourSpec(item["file"], w.number(sec, key, item["angle"])))
        return out
    if sec == "sca" and key in ("roots", "obstacles"):
        n = 3 if key == "roots" else 4
        if not isinstance(val, list):
            raise w.error(sec, key, f"a list of [{'x, y, z' if n == 3 else 'nx, ny, nz, c'}] lists", repr(val))
        return [w.vector(sec, key, x, n) for x in val]
    if isinstance(default, bool):
        if not isinstance(val, bool):
            raise w.error(sec, key, "true or false", repr(val))
        return val
    if isinstance(default, int):
        return w.integer(sec, key, val)
    if isinstance(default, float):
        return w.number(sec, key, val, allow_inf=math.isinf(default) or key in ("perception_radius", "influence_radius"))
    if isinstance(default, str):
        if not isinstance(val, str):
            raise w.error(sec, key, "a string", repr(val))
        return val
    if sec == "growth" and key == "funcs":
        if not isinstance(val, list) or len(val) != 3 or not all(isinstance(x, str) for x in val):
            raise w.error(sec, key, "three .func file names (X, Y, Z scale)", repr(val))
        return list(val)
    if isinstance(default, list):
        return w.vector(sec, key, val, len(default))
    raise AssertionError(key)  # pragma: no cover


#: lengths and coordinates (scene units) stay within this: the OBJ writer's limit, far from overflow
MAX_LENGTH = 1e12
#: simulation steps and iterations: a run of more could not finish in reasonable time
MAX_STEPS = 10_000_000
#: attraction points in all (``n_points + add_points * add_iterations``)
MAX_POINTS = 1_000_000
#: growth of space: the scale of space at its end over its scale at frame 0, per axis (and its inverse)
MAX_GROWTH = 1e12
#: the last frame of growth
MAX_FRAMES = 10_000_000
#: the tropism's length (the unit growth direction is added to it: beyond this only the tropism counts)
MAX_TROPISM = 1e6
#: the pipe model's exponent p (da Vinci 2, thesis p > 2, Murray 3)
PIPE_EXPONENT = (1.0, 20.0)


def _validate(p: Params, w: ParamText) -> None:
    r = p.rodkaew

    def need(ok, sec, key, expected, found):
        if not ok:
            raise w.error(sec, key, expected, repr(found))

    def length(sec, key, value, what, *, zero=False, inf=False):
        ok = (value >= 0 if zero else value > 0) and (value <= MAX_LENGTH or (inf and value == INF))
        need(ok, sec, key, f"{what} {'>= 0' if zero else '> 0'} and <= {MAX_LENGTH:g}" + (" (or inf)" if inf else ""),
             value)

    def coords(sec, key, value):
        need(all(abs(c) <= MAX_LENGTH for c in value), sec, key, f"coordinates within +-{MAX_LENGTH:g}", value)

    coords(None, "base", p.base)
    length("rodkaew", "step", r.step, "a step length")
    length("rodkaew", "merge_distance", r.merge_distance, "a merge distance")
    for k in ("w_a", "w_b", "w_h"):
        need(0 <= getattr(r, k) <= 1e6, "rodkaew", k, "a weight >= 0 and <= 1e+06", getattr(r, k))
    need(r.w_a + r.w_b + r.w_h > 0, "rodkaew", "w_a", "weights w_a + w_b + w_h > 0", r.w_a + r.w_b + r.w_h)
    # without attraction to the base a particle that meets no other tree never arrives: it wanders
    # until max_steps, every step a node
    need(r.w_a > 0 and r.w_a >= (r.w_b + r.w_h) / 1000, "rodkaew", "w_a",
         "a weight w_a > 0 and >= (w_b + w_h) / 1000 (particles must reach the base)", r.w_a)
    length("rodkaew", "w_b_range", r.w_b_range, "a distance")
    length("rodkaew", "perception_radius", r.perception_radius, "a radius", inf=True)
    need(r.initial_direction in ("floret", "base"), "rodkaew", "initial_direction", "'floret' or 'base'",
         r.initial_direction)
    need(1 <= r.steps_per_frame <= MAX_STEPS, "rodkaew", "steps_per_frame", f"an integer in [1, {MAX_STEPS}]",
         r.steps_per_frame)
    need(1 <= r.max_steps <= MAX_STEPS, "rodkaew", "max_steps", f"an integer in [1, {MAX_STEPS}]", r.max_steps)
    if r.step > r.merge_distance:
        warnings.warn(f"{p.source}: rodkaew.step {r.step} is larger than merge_distance {r.merge_distance}: "
                      "particles may jump across branches without grafting", UserWarning, stacklevel=3)
    g = p.growth
    need(g.mode in ("none", "uniform", "allometric", "functions"), "growth", "mode",
         "'none', 'uniform', 'allometric' or 'functions'", g.mode)
    if g.mode == "functions":
        need(len(g.funcs) == 3, "growth", "funcs", "three .func files for mode 'functions'", g.funcs)
    need(g.rate > -1, "growth", "rate", "a rate > -1", g.rate)
    need(all(x > -1 for x in g.rates), "growth", "rates", "rates > -1", g.rates)
    need(g.frames == -1 or 0 <= g.frames <= MAX_FRAMES, "growth", "frames", f"-1 or a frame in [0, {MAX_FRAMES}]",
         g.frames)
    s = p.sca
    need(0 <= s.n_points <= MAX_POINTS, "sca", "n_points", f"an integer in [0, {MAX_POINTS}]", s.n_points)
    need(0 <= s.add_points <= MAX_POINTS, "sca", "add_points", f"an integer in [0, {MAX_POINTS}]", s.add_points)
    need(0 <= s.add_iterations <= MAX_STEPS, "sca", "add_iterations", f"an integer in [0, {MAX_STEPS}]",
         s.add_iterations)
    if s.add_points and s.add_iterations:
        total = s.n_points + s.add_points * s.add_iterations
        need(total <= MAX_POINTS, "sca", "add_points",
             f"n_points + add_points * add_iterations <= {MAX_POINTS} attraction points", total)
    length("sca", "min_distance", s.min_distance, "a distance", zero=True)
    length("sca", "influence_radius", s.influence_radius, "a radius", inf=True)
    length("sca", "kill_distance", s.kill_distance, "a distance")
    length("sca", "step", s.step, "a step D")
    need(math.hypot(*s.tropism) <= MAX_TROPISM, "sca", "tropism", f"a vector of length <= {MAX_TROPISM:g}", s.tropism)
    need(len(s.roots) >= 1, "sca", "roots", "at least one root [x, y, z]", s.roots)
    need(len(s.roots) <= MAX_POINTS, "sca", "roots", f"at most {MAX_POINTS} roots", len(s.roots))
    for root in s.roots:
        coords("sca", "roots", root)
    need(len(s.obstacles) <= 1000, "sca", "obstacles", "at most 1000 planes", len(s.obstacles))
    for plane in s.obstacles:
        need(all(abs(c) <= MAX_LENGTH for c in plane), "sca", "obstacles",
             f"plane coefficients within +-{MAX_LENGTH:g}", plane)
    need(1 <= s.max_iterations <= MAX_STEPS, "sca", "max_iterations", f"an integer in [1, {MAX_STEPS}]",
         s.max_iterations)
    e = p.envelope
    need(e.shape in ("sphere", "ellipsoid", "cone", "cylinder", "contours"), "envelope", "shape",
         "'sphere', 'ellipsoid', 'cone', 'cylinder' or 'contours'", e.shape)
    coords("envelope", "centre", e.centre)
    length("envelope", "radius", e.radius, "a radius")
    need(all(0 < x <= MAX_LENGTH for x in e.radii), "envelope", "radii", f"semi-axes > 0 and <= {MAX_LENGTH:g}",
         e.radii)
    length("envelope", "height", e.height, "a height")
    if e.shape == "contours":
        need(len(e.contours) >= 1, "envelope", "contours", "at least one {file, angle} contour", e.contours)
        need(len(e.contours) <= 360, "envelope", "contours", "at most 360 contours", len(e.contours))
        for c in e.contours:
            need(abs(c.angle) <= 360, "envelope", "contours", "angles in [-360, 360] degrees", c.angle)
    q = p.post
    need(0 <= q.decimate <= MAX_LENGTH, "post", "decimate", f"tau_d >= 0 and <= {MAX_LENGTH:g}", q.decimate)
    need(0 <= q.subdivide <= 4, "post", "subdivide", "0..4 levels", q.subdivide)
    pp = p.pipe
    need(1e-6 <= pp.tip_diameter <= 1e6, "pipe", "tip_diameter", "a diameter in [1e-06, 1e+06]", pp.tip_diameter)
    lo, hi = PIPE_EXPONENT
    need(lo <= pp.exponent <= hi, "pipe", "exponent", f"an exponent in [{lo:g}, {hi:g}]", pp.exponent)
    need(3 <= p.cylinder.sides <= 64, "cylinder", "sides", "3..64 sides", p.cylinder.sides)


def read_params(path=None) -> Params:
    """Read a branch-gen TOML parameter file (None: all defaults)."""
    if path is None:
        return params_from_dict({})
    data, lines = read_toml_lines(path)
    return params_from_dict(data, path=path, lines=lines, folder=Path(path).parent)


def resolve(p: Params, name: str) -> Path:
    """A path named in the parameter file, relative to that file's folder."""
    q = Path(name)
    return q if q.is_absolute() else p.folder / q


def check_file(p: Params, sec: str, key: str, name: str) -> Path:
    q = resolve(p, name)
    if not q.is_file():
        raise InputError(f"{p.source}: {sec}.{key} names {name!r}, which is not a file")
    return q
