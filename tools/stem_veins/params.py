"""Parameter files of ``stem-veins`` (formats/stem_veins.md): TOML, every key checked.

Each refusal is one :class:`~inflo.formats.errors.FormatError` naming the file, the key's line, what
was expected and what was found. Counts and sizes are bounded by the work they imply before any is
done: the vein nodes a run can make grow with the stem's surface (R times its height, in D^2).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from inflo.formats.errors import FormatError
from inflo.formats.toml_params import LineStyle, ParamText, read_toml_lines, unknown_name

from .model import StemModel

__all__ = ["StemParams", "DiagramParams", "VeinParams", "read_params", "params_from_toml", "MAX_NODES"]

#: the most vein nodes a run may be expected to make (the stem's surface in D^2, times a margin)
MAX_NODES = 200_000

_KEYS = {
    None: {"seed"},
    "stem": {"radius", "base_nodes"},
    "primordia": {"count", "step", "divergence", "first", "plastochron", "jitter", "whorl"},
    "model": {"D", "max_iterations", "pattern"},
    "veins": {"base_width", "tip_width", "sides", "primordium_radius"},
    "diagram": {"size", "growth_map"},
}


@dataclass(frozen=True)
class VeinParams:
    """How the pattern is drawn in 3-D (sec. 6.2.2): generalized cylinders thinning with height."""

    base_width: float = 0.5      # diameter at the base, in D
    tip_width: float = 0.15      # diameter at the top primordium's height, in D
    sides: int = 6
    primordium_radius: float = 1.0   # primordia as spheres offset from the surface, in D


@dataclass(frozen=True)
class DiagramParams:
    """The unrolled idealized diagram (eq. 6.3, fig. 6.4) and internodal growth (fig. 6.5)."""

    size: int = 1200                 # the longer side of diagram.png, pixels
    growth_map: str | None = None    # a .func file: normalized height -> height after growth


@dataclass(frozen=True)
class StemParams:
    model: StemModel = field(default_factory=StemModel)
    veins: VeinParams = field(default_factory=VeinParams)
    diagram: DiagramParams = field(default_factory=DiagramParams)
    path: str | None = None


_STYLE = LineStyle()


def read_params(path) -> StemParams:
    """Read a stem-veins parameter file."""
    data, lines = read_toml_lines(path)
    return params_from_toml(data, path=str(path), text="\n".join(lines))


def params_from_toml(data: dict, *, path: str = "<params>", text: str = "") -> StemParams:
    pt = ParamText(path, text, style=_STYLE)
    for k, v in data.items():
        if isinstance(v, dict):
            if k not in _KEYS:
                raise unknown_name(path, pt.line(k, None), "a table of " + ", ".join(f"[{t}]" for t in _KEYS if t), k,
                                   [t for t in _KEYS if t])
            for kk in v:
                if kk not in _KEYS[k]:
                    raise unknown_name(path, pt.line(k, kk), f"a key of [{k}] ({', '.join(sorted(_KEYS[k]))})", kk,
                                       sorted(_KEYS[k]))
        elif k not in _KEYS[None]:
            raise unknown_name(path, pt.line(None, k), "seed or a table", k, sorted(_KEYS[None]) + [t for t in _KEYS if t])

    def get(section, key, default):
        table = data.get(section, {}) if section else data
        return table.get(key, default)

    def num(section, key, default, lo, hi, *, integer=False, lo_open=False):
        v = get(section, key, default)
        if v is None:
            return None
        x = pt.number(section, key, v, integer=integer)
        if x < lo or x > hi or (lo_open and x == lo):
            rng = f"{'(' if lo_open else '['}{lo:g}, {hi:g}]"
            raise pt.error(section, key, f"{'an integer' if integer else 'a number'} in {rng}", pt.show(v))
        return x

    seed = num(None, "seed", 0, 0, 2**32 - 1, integer=True)
    D = num("model", "D", 1.0, 1e-6, 1e6, lo_open=True)
    R = num("stem", "radius", 11.5, 0.5 * D, 1e4 * D)
    base = num("stem", "base_nodes", None, 3, 100_000, integer=True)
    count = num("primordia", "count", 30, 1, 10_000, integer=True)
    H = num("primordia", "step", 1.0, 0.0, 1e4 * D)
    theta = num("primordia", "divergence", 137.5, -360.0, 360.0)
    first = num("primordia", "first", None, 0.0, 1e6 * D)
    plast = num("primordia", "plastochron", 10, 1, 100_000, integer=True)
    jitter = num("primordia", "jitter", 0.0, 0.0, 10.0)
    whorl = num("primordia", "whorl", 1, 1, 64, integer=True)
    pattern = pt.choice("model", "pattern", get("model", "pattern", "closed"), ("closed", "open"))
    max_it = num("model", "max_iterations", 100_000, 1, 1_000_000, integer=True)
    first_h = H if first is None else first
    height = first_h + ((count - 1) // whorl) * H
    # work: the nodes a run may make ~ the stem's surface (2 pi R x height) in D^2, and the ring
    nodes = 2 * math.pi * R * (height + R) / (D * D) + (base or 0) + count
    if nodes > MAX_NODES:
        raise pt.error("stem", "radius", f"a stem of at most {MAX_NODES:,} D^2 of surface "
                       "(radius x (height + radius) x 2 pi, the vein nodes it may hold)",
                       f"{nodes:,.0f} with radius {R:g}, {count} primordia {H:g} apart",
                       template="{expected}")
    model = StemModel(radius=R, base_nodes=base, count=count, step=H, divergence=theta, first=first,
                      plastochron=plast, whorl=whorl, jitter=jitter, pattern=pattern, seed=seed, D=D, max_iterations=max_it)
    veins = VeinParams(
        base_width=num("veins", "base_width", 0.5, 0.0, 100.0, lo_open=True),
        tip_width=num("veins", "tip_width", 0.15, 0.0, 100.0, lo_open=True),
        sides=num("veins", "sides", 6, 3, 64, integer=True),
        primordium_radius=num("veins", "primordium_radius", 1.0, 0.0, 100.0))
    gm = get("diagram", "growth_map", None)
    if gm is not None:
        gm = pt.string("diagram", "growth_map", gm)
        if not gm.strip():
            raise pt.error("diagram", "growth_map", "a .func file", "an empty string")
        gm = str(Path(path).parent / gm) if path and not Path(gm).is_absolute() else gm
    diagram = DiagramParams(size=num("diagram", "size", 1200, 64, 8192, integer=True), growth_map=gm)
    return StemParams(model=model, veins=veins, diagram=diagram, path=path)


def seed_override(p: StemParams, seed: int | None) -> StemParams:
    if seed is None:
        return p
    from dataclasses import replace
    return replace(p, model=replace(p.model, seed=seed))


def check_growth_map(p: StemParams):
    """The growth map's function, read and checked (monotone non-decreasing on [0, 1])."""
    if p.diagram.growth_map is None:
        return None
    import numpy as np

    from inflo.formats.func import read_func
    f = read_func(p.diagram.growth_map)
    x = np.linspace(0.0, 1.0, 257)
    y = np.asarray(f.evaluate(x), dtype=float)
    if not np.all(np.isfinite(y)) or np.any(np.diff(y) < -1e-9):
        raise FormatError(p.diagram.growth_map, None, "a growth map non-decreasing on [0, 1] (fig. 6.5)",
                          "one that decreases" if np.all(np.isfinite(y)) else "non-finite values")
    return f
