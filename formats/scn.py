"""Scene (SCN) files: floret placements, thesis appendix C.2 and figure 8.2. Spec: ``formats/scn.md``.

Each placement line is ``type: id pos(3) scale(3) up(3) right(3) [type-specific values]``:

======  =========================================  ========================================
type    extra values                               meaning (C.2)
======  =========================================  ========================================
``o``   --                                         place an OBJ
``ca``  frameStart frameEnd                        constraint-based animation
``i``   interpolationValue                         interpolated instance of an animation
``ta``  frameStart frameEnd x y z                  translate the geometry over the frames
``ra``  frameStart frameEnd x y z angle            rotate about axis (x, y, z) by angle (deg)
``rba`` frameStart frameEnd                        rigid body animation (positions in RBA files)
======  =========================================  ========================================

``mtl: matID`` applies to the placements that follow it (until the next ``mtl:``); ``#`` starts a
comment line. The order of placements is each floret's identity: placement *k* is id *k* of the
RBA files (fig. 8.2).

inflo extension lines start with ``#@`` so a reader that predates them (the thesis's FCComposer)
skips them as comments:

- ``#@ groupdef: G cx cy cz P`` declares hierarchy group G (a head or umbellet, thesis 5.4/6.2)
  with centre (cx, cy, cz) and parent group P (-1 for none), before its first use;
- after a placement: ``#@ group: G`` (the floret's group), ``#@ emergence: t`` (frame at which
  the floret emerges, for branch-gen), ``#@ type: label`` (floret type set by dimorph, e.g. ray),
  ``#@ petal: f`` (petal factor set by dimorph ``--petal-size``: fccompose grows the vertices of
  the template's ``petal weight`` file by ``1 + w (f - 1)``, thesis fig. 6.4c).
  Other ``#@ key: value`` lines are kept verbatim (``extra``) and written back.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .atomic import atomic_write
from .errors import FormatError, InputError, parse_float, parse_int, read_lines, shorten
from .placement import FLOAT_FMT, PREAMBLE_FIELDS, format_preamble, parse_preamble, placement_matrix

__all__ = ["Placement", "Group", "Scene", "read_scn", "write_scn", "PLACEMENT_KINDS"]

# kind -> names of the values after the preamble (ints first where they are frames)
PLACEMENT_KINDS = {
    "o": (),
    "ca": ("frame_start", "frame_end"),
    "i": ("interpolation",),
    "ta": ("frame_start", "frame_end", "tx", "ty", "tz"),
    "ra": ("frame_start", "frame_end", "ax", "ay", "az", "angle"),
    "rba": ("frame_start", "frame_end"),
}
MAX_WRITTEN = 1e12  # the largest position or scale a writer puts in a scene file
MAX_FRAME = 10_000_000  # frameStart / frameEnd: a frame number a run can reach (shifts of nested scenes add up)
MAX_MATERIAL = 255  # C.2: 256 material definitions in the material map


@dataclass
class Placement:
    """One scene placement (one floret instance).

    Attributes
    ----------
    kind : str
        ``o``, ``ca``, ``i``, ``ta``, ``ra`` or ``rba``.
    id : int
        The animation/OBJ id of the canopy parameter file (floret type).
    pos, scale, up, right : (3,) float64
        Placement in scene units; ``up`` is the image of the floret's local +Y axis.
    frame_start, frame_end : int or None
        For ``ca``, ``ta``, ``ra``, ``rba``.
    interpolation : float or None
        For ``i``: the animation parameter in [0, 1].
    translate : (3,) float64 or None
        For ``ta``.
    axis : (3,) float64 or None, angle : float or None
        For ``ra`` (degrees).
    material : int or None
        The ``mtl:`` id in force at this placement.
    group : int or None
        Extension: the hierarchy group (head/umbellet) of the floret.
    emergence : float or None
        Extension: frame at which the floret emerges.
    type : str or None
        Extension: floret type label (dimorph).
    petal : float or None
        Extension: petal factor f (dimorph ``--petal-size``): fccompose scales the vertices of the
        template's ``petal weight`` file by ``1 + w (f - 1)`` (only the petals grow, fig. 6.4c).
    extra : dict of str -> str
        Other ``#@`` extension lines after this placement, kept verbatim.
    """

    kind: str
    id: int
    pos: np.ndarray
    scale: np.ndarray
    up: np.ndarray
    right: np.ndarray
    frame_start: int | None = None
    frame_end: int | None = None
    interpolation: float | None = None
    translate: np.ndarray | None = None
    axis: np.ndarray | None = None
    angle: float | None = None
    material: int | None = None
    group: int | None = None
    emergence: float | None = None
    type: str | None = None
    petal: float | None = None
    extra: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.kind not in PLACEMENT_KINDS:
            raise ValueError(f"unknown placement kind {self.kind!r}")
        for name in ("pos", "scale", "up", "right", "translate", "axis"):
            val = getattr(self, name)
            if val is not None:
                setattr(self, name, np.asarray(val, dtype=np.float64).reshape(3))

    def matrix(self) -> np.ndarray:
        """(4, 4) local-to-scene matrix (see :func:`inflo.formats.placement.placement_matrix`)."""
        return placement_matrix(self.pos, self.scale, self.up, self.right)


@dataclass
class Group:
    """Extension: a hierarchy group (a head or an umbellet), thesis 5.4 and 6.2."""

    id: int
    centre: np.ndarray
    parent: int = -1

    def __post_init__(self):
        self.centre = np.asarray(self.centre, dtype=np.float64).reshape(3)


@dataclass
class Scene:
    """The placements of a scene file, in file order (the order is each floret's identity)."""

    placements: list = field(default_factory=list)
    groups: dict = field(default_factory=dict)  # group id -> Group
    extra: list = field(default_factory=list)  # (key, value) '#@' lines before the first placement

    def __len__(self) -> int:
        return len(self.placements)

    def arrays(self) -> dict:
        """Structure-of-arrays view for kernels.

        Returns ``id (n,) int32``, ``pos``, ``scale``, ``up``, ``right`` ``(n, 3) float64``,
        ``material (n,) int32`` (-1 none), ``group (n,) int32`` (-1 none), ``emergence (n,) float64``
        (NaN none) and ``group_centre (n, 3) float64`` (NaN when no group).
        """
        P = self.placements
        n = len(P)
        centre = np.full((n, 3), np.nan)
        for k, p in enumerate(P):
            if p.group is not None:
                centre[k] = self.groups[p.group].centre
        return {
            "id": np.array([p.id for p in P], dtype=np.int32),
            "pos": np.array([p.pos for p in P]).reshape(n, 3),
            "scale": np.array([p.scale for p in P]).reshape(n, 3),
            "up": np.array([p.up for p in P]).reshape(n, 3),
            "right": np.array([p.right for p in P]).reshape(n, 3),
            "material": np.array([-1 if p.material is None else p.material for p in P], dtype=np.int32),
            "group": np.array([-1 if p.group is None else p.group for p in P], dtype=np.int32),
            "emergence": np.array([np.nan if p.emergence is None else p.emergence for p in P]),
            "group_centre": centre,
        }


def _parse_placement(kind, toks, path, lineno) -> Placement:
    names = PLACEMENT_KINDS[kind]
    want = PREAMBLE_FIELDS + len(names)
    if len(toks) != want:
        extra = " ".join(names) or "nothing"
        raise FormatError(path, lineno, f"{want} values after '{kind}:' (id pos scale up right, then {extra})",
                          f"{len(toks)} values")
    pid, pos, scale, up, right = parse_preamble(toks, path, lineno, f"'{kind}:' placement")
    rest = toks[PREAMBLE_FIELDS:]
    p = Placement(kind, pid, pos, scale, up, right)
    if "frame_start" in names:
        fs = parse_int(rest[0], path, lineno, "an integer frameStart")
        fe = parse_int(rest[1], path, lineno, "an integer frameEnd")
        if not 0 <= fe <= MAX_FRAME:
            raise FormatError(path, lineno, f"frames in 0..{MAX_FRAME}", f"{fs} {fe}")
        if fs < 0 or fe < fs:
            raise FormatError(path, lineno, "0 <= frameStart <= frameEnd", f"{fs} {fe}")
        p.frame_start, p.frame_end = fs, fe
        rest = rest[2:]
    if kind == "i":
        v = parse_float(rest[0], path, lineno, "an interpolation value")
        if not 0.0 <= v <= 1.0:
            raise FormatError(path, lineno, "an interpolation value in [0, 1]", shorten(rest[0]))
        p.interpolation = v
    elif kind == "ta":
        p.translate = np.array([parse_float(t, path, lineno, "a translation component") for t in rest])
    elif kind == "ra":
        axis = np.array([parse_float(t, path, lineno, "a rotation axis component") for t in rest[:3]])
        if not np.any(axis):
            raise FormatError(path, lineno, "a non-zero rotation axis", " ".join(rest[:3]))
        p.axis = axis
        p.angle = parse_float(rest[3], path, lineno, "a rotation angle in degrees")
    return p


def read_scn(path) -> Scene:
    """Read a scene file.

    Raises
    ------
    FormatError
        Unknown placement type, wrong number of values, non-numbers, NaN/inf, a degenerate frame
        (zero up/right, parallel up and right, zero scale), frameStart > frameEnd, an interpolation
        value outside [0, 1], a material id outside 0..255, an extension line that is malformed or
        refers to an undeclared group, or a per-placement extension before any placement.
    """
    scene = Scene()
    material = None
    for lineno, raw in enumerate(read_lines(path), 1):
        s = raw.strip()
        if not s:
            continue
        if s.startswith("#@"):
            _parse_extension(scene, s[2:].strip(), path, lineno)
            continue
        if s[0] == "#":
            continue
        head, sep, body = s.partition(":")
        kind = head.strip()
        if not sep or (kind not in PLACEMENT_KINDS and kind != "mtl"):
            raise FormatError(path, lineno, "a placement 'o:', 'ca:', 'i:', 'ta:', 'ra:', 'rba:' or 'mtl:'",
                              shorten(s))
        toks = body.split()
        if kind == "mtl":
            if len(toks) != 1:
                raise FormatError(path, lineno, "one material id after 'mtl:'", f"{len(toks)} values")
            material = parse_int(toks[0], path, lineno, "an integer material id")
            if not 0 <= material <= MAX_MATERIAL:
                raise FormatError(path, lineno, f"a material id in 0..{MAX_MATERIAL}", shorten(toks[0]))
            continue
        p = _parse_placement(kind, toks, path, lineno)
        p.material = material
        scene.placements.append(p)
    return scene


def _parse_extension(scene: Scene, text: str, path, lineno) -> None:
    key, sep, value = text.partition(":")
    key = key.strip()
    toks = value.split()
    if not sep or not key:
        raise FormatError(path, lineno, "an extension line '#@ key: value'", shorten("#@ " + text))
    if key == "groupdef":
        if len(toks) != 5:
            raise FormatError(path, lineno, "'#@ groupdef: G cx cy cz parent'", f"{len(toks)} values")
        gid = parse_int(toks[0], path, lineno, "an integer group id")
        centre = [parse_float(t, path, lineno, "a group centre coordinate") for t in toks[1:4]]
        parent = parse_int(toks[4], path, lineno, "an integer parent group id (-1 for none)")
        if gid < 0 or gid in scene.groups:
            raise FormatError(path, lineno, "a new non-negative group id", shorten(toks[0]))
        if parent != -1 and parent not in scene.groups:
            raise FormatError(path, lineno, "a parent group declared before (or -1)", shorten(toks[4]))
        scene.groups[gid] = Group(gid, centre, parent)
        return
    if not scene.placements:
        scene.extra.append((key, value.strip()))
        return
    p = scene.placements[-1]
    if key == "group":
        if len(toks) != 1:
            raise FormatError(path, lineno, "'#@ group: G'", shorten(value))
        gid = parse_int(toks[0], path, lineno, "an integer group id")
        if gid not in scene.groups:
            raise FormatError(path, lineno, "a group declared by an earlier '#@ groupdef:'", shorten(toks[0]))
        p.group = gid
    elif key == "emergence":
        if len(toks) != 1:
            raise FormatError(path, lineno, "'#@ emergence: frame'", shorten(value))
        t = parse_float(toks[0], path, lineno, "an emergence frame")
        if t < 0:
            raise FormatError(path, lineno, "a non-negative emergence frame", shorten(toks[0]))
        p.emergence = t
    elif key == "type":
        if len(toks) != 1:
            raise FormatError(path, lineno, "'#@ type: label' (one word)", shorten(value))
        p.type = toks[0]
    elif key == "petal":
        if len(toks) != 1:
            raise FormatError(path, lineno, "'#@ petal: factor'", shorten(value))
        f = parse_float(toks[0], path, lineno, "a petal factor")
        if not 1e-6 <= f <= 1e6:
            raise FormatError(path, lineno, "a petal factor in [1e-06, 1e+06]", shorten(toks[0]))
        p.petal = f
    else:
        p.extra[key] = value.strip()


def _fmt(x: float, fmt: str) -> str:
    return fmt % float(x)


def write_scn(path, scene: Scene, *, header: str | None = None, fmt: str = FLOAT_FMT) -> None:
    """Write ``scene`` atomically with fixed-format numbers.

    Group definitions come first (sorted by id, parents before children as declared), an
    ``mtl:`` line is written before a placement whose material differs from the one in force.
    """
    out = []
    if header:
        out.extend(f"# {h}\n" for h in header.splitlines())
    for key, value in scene.extra:
        out.append(f"#@ {key}: {value}\n")
    for g in _groups_in_order(scene.groups):
        c = " ".join(_fmt(x, fmt) for x in g.centre)
        out.append(f"#@ groupdef: {g.id} {c} {g.parent}\n")
    material = None
    for p in scene.placements:
        if p.material != material:
            if p.material is None:
                raise ValueError("a placement without material after one with a material cannot be written")
            out.append(f"mtl: {p.material}\n")
            material = p.material
        big = max((abs(float(x)) for v in (p.pos, p.scale, p.up, p.right) for x in v), default=0.0)
        if not big <= MAX_WRITTEN:
            # values that overflowed, or nearly (inputs far beyond any scene's size), are bad input
            raise InputError(f"{path}: expected placements to write with positions and scales within "
                             f"+-{MAX_WRITTEN:g} (inputs of a sensible size), found {big:g} in placement id {p.id}")
        line = f"{p.kind}: {format_preamble(p.id, p.pos, p.scale, p.up, p.right, fmt)}"
        if p.kind in ("ca", "ta", "ra", "rba"):
            line += f" {p.frame_start} {p.frame_end}"
        if p.kind == "i":
            line += " " + _fmt(p.interpolation, fmt)
        elif p.kind == "ta":
            line += " " + " ".join(_fmt(x, fmt) for x in p.translate)
        elif p.kind == "ra":
            line += " " + " ".join(_fmt(x, fmt) for x in p.axis) + " " + _fmt(p.angle, fmt)
        out.append(line + "\n")
        if p.group is not None:
            out.append(f"#@ group: {p.group}\n")
        if p.emergence is not None:
            out.append(f"#@ emergence: {_fmt(p.emergence, fmt)}\n")
        if p.type is not None:
            out.append(f"#@ type: {p.type}\n")
        if p.petal is not None:
            out.append(f"#@ petal: {_fmt(p.petal, fmt)}\n")
        for key, value in p.extra.items():
            out.append(f"#@ {key}: {value}\n")
    with atomic_write(path) as fh:
        fh.write("".join(out))


def _groups_in_order(groups: dict):
    done, order = set(), []

    def visit(g):
        if g.id in done:
            return
        if g.parent != -1:
            visit(groups[g.parent])
        done.add(g.id)
        order.append(g)

    for gid in sorted(groups):
        visit(groups[gid])
    return order
