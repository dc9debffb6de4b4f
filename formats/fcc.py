"""Canopy composer parameter file ``.fcc`` (thesis appendix C.1): reader, writer, reference check.

The Floral Canopy Composer (``fccompose``) is configured by one ``key: value`` text file naming the
scene (SCN) files, the floret animations and OBJs by id, the solver and collision parameters, the
collision lattice and the viewer's camera and light. The spec page is ``formats/fcc.md``; it lists
every key with its type, unit and default.

Parsing (:func:`read_fcc`) does not touch the files the parameters name, so it can be tested without
them; :func:`check_references` checks separately that every referenced file or folder exists.
"""
from __future__ import annotations

import glob
import math
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType

from .atomic import write_text_atomic
from .errors import FormatError, InputError, did_you_mean, parse_float, parse_int, read_lines, shorten
from .variation import Variation, parse_variation

__all__ = [
    "AnimationEntry",
    "CameraParams",
    "CanopyParams",
    "FilePath",
    "KEYS",
    "KeySpec",
    "LatticeParams",
    "MissingReferenceError",
    "RigidBodyAnimationEntry",
    "KNOWN_KEYS",
    "check_references",
    "format_fcc",
    "read_fcc",
    "write_fcc",
]

Vec3 = tuple[float, float, float]


# --------------------------------------------------------------------------------------------------
# Data model
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class FilePath:
    """A path named in a ``.fcc`` file.

    Parameters
    ----------
    raw : str
        The path exactly as written in the file (``./lilyAnimation/``). Only ``raw`` takes part
        in equality: two parameter sets are equal when their files say the same thing.
    resolved : pathlib.Path
        ``raw`` made absolute against the folder of the ``.fcc`` file (an absolute ``raw`` stays as
        it is), normalized (``os.path.abspath``). Not compared.
    line : int or None
        1-based line of the ``.fcc`` file that named it; None when built in code. Not compared.
    """

    raw: str
    resolved: Path = field(default=None, compare=False)  # type: ignore[assignment]
    line: int | None = field(default=None, compare=False)

    def __post_init__(self):
        if self.resolved is None:
            object.__setattr__(self, "resolved", Path(os.path.abspath(self.raw)))

    @classmethod
    def at(cls, raw: str, base_dir=None, line: int | None = None) -> FilePath:
        """``raw`` resolved against ``base_dir`` (the current folder when None)."""
        base = os.getcwd() if base_dir is None else os.fspath(base_dir)
        return cls(raw, Path(os.path.abspath(os.path.join(base, raw))), line)


@dataclass(frozen=True)
class AnimationEntry:
    """An ``animation:`` or ``obj:`` line: floret geometry that SCN placements refer to by id.

    Parameters
    ----------
    id : int
        Non-negative id, unique across animation, obj and rigid body animation entries.
    scale : tuple of 3 float
        Initial scale in x, y, z applied to the geometry on load (each > 0).
    path : FilePath
        ``kind == 'animation'``: a folder (or glob) of an OBJ sequence; ``kind == 'obj'``: one OBJ.
    kind : {'animation', 'obj'}
        Which key named it.
    line : int or None
        Line of the ``.fcc`` file (not compared).
    """

    id: int
    scale: Vec3
    path: FilePath
    kind: str = "animation"
    line: int | None = field(default=None, compare=False)

    def __post_init__(self):
        if self.kind not in ("animation", "obj"):
            raise ValueError(f"AnimationEntry.kind must be 'animation' or 'obj', not {self.kind!r}")
        object.__setattr__(self, "scale", tuple(float(s) for s in self.scale))


@dataclass(frozen=True)
class RigidBodyAnimationEntry:
    """A ``rigid body animation:`` line: an RBA folder and the SCN file whose placements it moves.

    Parameters
    ----------
    id : int
        Non-negative id, unique across animation, obj and rigid body animation entries.
    scale : tuple of 3 float
        Initial scale in x, y, z (each > 0).
    rba_folder : FilePath
        Folder of ``NNNN.rba`` files (thesis app. C.3), one per frame.
    scene_path : FilePath
        The SCN file (app. C.2) whose placements the RBA entries move (its order gives the RBA ids).
    line : int or None
        Line of the ``.fcc`` file (not compared).
    """

    id: int
    scale: Vec3
    rba_folder: FilePath
    scene_path: FilePath
    line: int | None = field(default=None, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "scale", tuple(float(s) for s in self.scale))


@dataclass(frozen=True)
class LatticeParams:
    """The collision lattice (broad phase) keys of C.1.

    Parameters
    ----------
    size_multiply : tuple of 3 float
        Scale of the automatically fitted bounding box in x, y, z (each > 0). Default (1, 1, 1).
    make_cube : bool
        Make the box a cube of its largest side. Default False.
    origin : tuple of 3 float
        Minimum corner of the box, scene units, used when ``auto_bounds`` is False.
        Default (-5, -5, -5).
    divisions : tuple of 3 int
        Cells in x, y, z (each >= 1). Default (100, 100, 100).
    dimensions : tuple of 3 float
        Box size in x, y, z, scene units (each > 0), used when ``auto_bounds`` is False.
        Default (10, 10, 10).
    auto_bounds : bool
        Fit the box to the geometry (times ``size_multiply``). Default True.
    """

    size_multiply: Vec3 = (1.0, 1.0, 1.0)
    make_cube: bool = False
    origin: Vec3 = (-5.0, -5.0, -5.0)
    divisions: tuple[int, int, int] = (100, 100, 100)
    dimensions: Vec3 = (10.0, 10.0, 10.0)
    auto_bounds: bool = True

    def __post_init__(self):
        for name in ("size_multiply", "origin", "dimensions"):
            object.__setattr__(self, name, tuple(float(v) for v in getattr(self, name)))
        object.__setattr__(self, "divisions", tuple(int(v) for v in self.divisions))


@dataclass(frozen=True)
class CameraParams:
    """The interactive viewer's camera and light keys of C.1, kept for ``canopy-render``.

    ``None`` means "automatic": ``canopy-render`` frames the geometry itself.

    Parameters
    ----------
    position, lookat : tuple of 3 float or None
        Eye and target, scene units. Default None (automatic framing).
    up : tuple of 3 float
        Up vector (not zero). Default (0, 1, 0): the floret axis.
    pan_speed, zoom_speed, rotate_speed : float
        Interactive speeds (>= 0), unused by inflo's headless tools. Default 1.
    near, far : float or None
        Clip distances (> 0, far > near). Default None (from the scene bounds).
    fov_deg : float
        Vertical field of view, degrees, in (0, 180). Default 45.
    light_position : tuple of 3 float or None
        Light position, scene units. Default None (a light at the eye).
    shadow_frustum : tuple of 6 float or None
        left, right, top, bottom, back, front of the shadow map frustum. Default None.
    """

    position: Vec3 | None = None
    up: Vec3 = (0.0, 1.0, 0.0)
    lookat: Vec3 | None = None
    pan_speed: float = 1.0
    zoom_speed: float = 1.0
    rotate_speed: float = 1.0
    near: float | None = None
    far: float | None = None
    fov_deg: float = 45.0
    light_position: Vec3 | None = None
    shadow_frustum: tuple[float, float, float, float, float, float] | None = None

    def __post_init__(self):
        for name in ("position", "up", "lookat", "light_position", "shadow_frustum"):
            v = getattr(self, name)
            if v is not None:
                object.__setattr__(self, name, tuple(float(x) for x in v))


@dataclass(frozen=True)
class CanopyParams:
    """Everything a ``.fcc`` file says (thesis app. C.1); field defaults are the documented ones.

    Parameters
    ----------
    solver_iterations : int
        ``solver iterations``: PBD iterations over internal constraints per step (>= 0). 50.
    collision_iterations : int
        ``collision solver iterations`` (alias ``collision iterations``): iterations over collision
        constraints per step (>= 0). 10.
    max_collision_retries : int
        ``max collision retries``: re-detect/resolve rounds when a step is still not collision-free
        (>= 0). 20.
    k_stretch, k_bend, k_collision : float
        Global stiffness in [0, 1] of distance, bending and collision constraints. 0.99, 0.99, 1.0.
    spacing : float
        Collision thickness h, scene units (>= 0). 0.005.
    scene_scale : tuple of 3 float
        ``scene scale factor``: scale of all loaded geometry in x, y, z (each > 0). (1, 1, 1).
    updates_per_frame : int
        Simulation steps per frame (>= 1). 1.
    run_frames : int or None
        ``run for number of frames`` (>= 0). None: fccompose runs to the end of the longest
        animation/RBA sequence.
    sanity_check_every : int
        ``sanity check per frames``: exact intersection test every N frames; 0 never. 50.
    max_substeps : int
        ``max substeps``: a step that leaves crossing pairs or an edge outside the stretch bounds
        is redone as two half steps, recursively, at most this deep (2**N substeps). 3.
    stretch_bounds : tuple of 2 float
        ``edge stretch bounds``: smallest and largest ratio of an edge's length to its rest length
        a composed floret may show (0 < lo <= 1 <= hi). (0.5, 1.5).
    relax_iterations : int
        ``relax iterations``: internal-constraint sweeps of the florets a collision round moved,
        between the rounds (0: none). 5.
    collisions : bool
        ``collisions``: off runs the florets' growth without collision detection or response
        (florets emerge without testing for room; intersections are only counted, at the sanity
        checks: the comparison of thesis fig. 4.9). True.
    emergence_scales : tuple of float
        ``emergence scales``: sizes (fractions of its own, in (0, 1], decreasing) at which an
        emerging floret is tried until one finds room. (1, 0.75, 0.5, 0.35, 0.25).
    emergence_growth_frames : float
        ``emergence growth frames``: frames over which a floret that emerged smaller grows back
        to its own size (> 0). 10.
    crowded_scales : tuple of float
        ``crowded scales``: sizes (fractions of its present size, in (0, 1], decreasing) a floret
        is tried at when a crowded step leaves it outside the ``edge stretch bounds`` and its
        carried shape has no room: it is put at the first that fits (its carried shape, else its
        rest shape, scaled about its base) and grows back like an emerging floret; ``1`` alone:
        never. (0.85, 0.7, 0.55, 0.4, 0.25).
    output_frames_number : int or None
        ``output animation frames number``: write an OBJ every N frames (>= 1). None: not given.
    output_obj_skip : int or None
        ``output animation obj per frames``: frames skipped between written OBJs (>= 0). None.
    lattice : LatticeParams
        Collision lattice keys.
    color_map, material_map : FilePath or None
        ``color map file location``, ``material map file location``. None.
    scene_files : tuple of FilePath
        ``scene file path`` lines (the key may repeat, thesis 8 f). Empty.
    animations : tuple of AnimationEntry
        ``animation`` and ``obj`` lines in file order. Empty.
    rigid_body_animations : tuple of RigidBodyAnimationEntry
        ``rigid body animation`` lines in file order. Empty.
    weights : mapping of int to FilePath
        ``weight`` lines: id of an animation/obj entry -> file of fixed vertex ids. Empty.
    petal_weights : mapping of int to FilePath
        ``petal weight`` lines: id of an animation/obj entry -> file of per-vertex petal weights
        in [0, 1] (formats/weights.md): a placement's ``#@ petal: f`` scales vertex v of that
        template by ``1 + w_v (f - 1)`` about the floret's origin (the petals grow, not the whole
        floret; thesis fig. 6.4c). Empty.
    bending_stiffness, distance_stiffness : mapping of int to float
        Per-id stiffness in [0, 1] replacing ``k_bend`` / ``k_stretch``. Empty.
    variations : mapping of int to Variation
        ``variation`` lines: id of an animation/obj entry -> the spreads of its florets' seeded
        individual differences (formats/variation.py; fccompose gives each such floret its own
        deformed copy of the template). Empty.
    animation_output_folder : FilePath or None
        ``animation output folder location``; the CLI's ``-o`` wins. None.
    obj_output_file : FilePath or None
        ``obj output file path``: the OBJ written for the current frame. None.
    camera : CameraParams
        Viewer keys (camera, light, shadow).
    source : pathlib.Path or None
        The file read (not compared).
    lines : mapping of str to int
        Canonical key -> line of its last occurrence in ``source`` (not compared).
    """

    solver_iterations: int = 50
    collision_iterations: int = 10
    max_collision_retries: int = 20
    k_stretch: float = 0.99
    k_bend: float = 0.99
    k_collision: float = 1.0
    spacing: float = 0.005
    scene_scale: Vec3 = (1.0, 1.0, 1.0)
    updates_per_frame: int = 1
    run_frames: int | None = None
    sanity_check_every: int = 50
    max_substeps: int = 3
    stretch_bounds: tuple = (0.5, 1.5)
    relax_iterations: int = 5
    collisions: bool = True
    emergence_scales: tuple = (1.0, 0.75, 0.5, 0.35, 0.25)
    emergence_growth_frames: float = 10.0
    crowded_scales: tuple = (0.85, 0.7, 0.55, 0.4, 0.25)
    output_frames_number: int | None = None
    output_obj_skip: int | None = None
    lattice: LatticeParams = field(default_factory=LatticeParams)
    color_map: FilePath | None = None
    material_map: FilePath | None = None
    scene_files: tuple[FilePath, ...] = ()
    animations: tuple[AnimationEntry, ...] = ()
    rigid_body_animations: tuple[RigidBodyAnimationEntry, ...] = ()
    weights: Mapping[int, FilePath] = field(default_factory=dict)
    petal_weights: Mapping[int, FilePath] = field(default_factory=dict)
    bending_stiffness: Mapping[int, float] = field(default_factory=dict)
    distance_stiffness: Mapping[int, float] = field(default_factory=dict)
    variations: Mapping[int, Variation] = field(default_factory=dict)
    animation_output_folder: FilePath | None = None
    obj_output_file: FilePath | None = None
    camera: CameraParams = field(default_factory=CameraParams)
    source: Path | None = field(default=None, compare=False)
    lines: Mapping[str, int] = field(default_factory=dict, compare=False)

    def __post_init__(self):
        for name in ("scene_files", "animations", "rigid_body_animations"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        for name in ("weights", "petal_weights", "bending_stiffness", "distance_stiffness", "variations", "lines"):
            object.__setattr__(self, name, MappingProxyType(dict(getattr(self, name))))
        object.__setattr__(self, "scene_scale", tuple(float(v) for v in self.scene_scale))
        object.__setattr__(self, "stretch_bounds", tuple(float(v) for v in self.stretch_bounds))
        object.__setattr__(self, "emergence_scales", tuple(float(v) for v in self.emergence_scales))
        object.__setattr__(self, "crowded_scales", tuple(float(v) for v in self.crowded_scales))

    @property
    def output_every(self) -> int:
        """Frames between written OBJs: ``output animation frames number``, else the
        ``output animation obj per frames`` skip + 1, else 1."""
        if self.output_frames_number is not None:
            return self.output_frames_number
        if self.output_obj_skip is not None:
            return self.output_obj_skip + 1
        return 1

    def entry(self, id: int) -> AnimationEntry | RigidBodyAnimationEntry | None:
        """The animation, obj or rigid body animation entry with this id, or None."""
        for e in self.animations:
            if e.id == id:
                return e
        for e in self.rigid_body_animations:
            if e.id == id:
                return e
        return None

    def stiffness(self, id: int) -> tuple[float, float]:
        """(distance, bending) stiffness for animation/obj ``id``: its own, else the global one."""
        return (
            self.distance_stiffness.get(id, self.k_stretch),
            self.bending_stiffness.get(id, self.k_bend),
        )


# --------------------------------------------------------------------------------------------------
# Keys
# --------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class KeySpec:
    """One key of the ``.fcc`` table (``formats/fcc.md``, "Keys"): what the reader takes and where
    it puts it.

    Parameters
    ----------
    kind : str
        ``"int"``, ``"float"``, ``"stiffness"`` (a float in [0, 1]), ``"bool"``, ``"path"``, or a
        line with its own syntax (:data:`_SYNTAX`): ``"scales"``, ``"divisions"``, ``"entry"``
        (``animation``/``obj``), ``"rba"``, ``"weight"``, ``"id stiffness"``.
    n : int
        How many numbers (``"float"``; 1 for ``"int"``).
    low : float or None
        The range: ``"int"``: at least ``low``; ``"float"``: at least ``low``, above it when
        ``strict``; None: any finite number.
    high : float or None
        ``"int"``: at most ``high`` (iteration and frame counts: a count beyond it is a typo, not a
        run this machine could finish); None: no upper bound.
    strict : bool
    check : str
        A condition on the values together, as the spec words it (:data:`_CHECKS`).
    field : str
        Where the value goes: a :class:`CanopyParams` field, ``"lattice.<field>"`` or
        ``"camera.<field>"``; ``""`` for lines that add entries (the kind's reader stores them).
    repeatable : bool
        The key may appear on several lines.
    """

    kind: str
    n: int = 1
    low: float | None = None
    high: float | None = None
    strict: bool = False
    check: str = ""
    field: str = ""
    repeatable: bool = False

    def spec_value(self) -> str:
        """The text of the spec table's "value" column for this key."""
        if self.kind == "int":
            text = f"int ≥ {self.low:g}" if self.high is None else f"int in [{self.low:g}, {self.high:g}]"
        elif self.kind == "float":
            text = "float" if self.n == 1 else f"{self.n} floats"
            if self.low is not None:
                text += f" {'>' if self.strict else '≥'} {self.low:g}"
            if self.check:
                text += (" " if self.check.startswith("in ") else ", ") + self.check
        elif self.kind == "stiffness":
            text = "float in [0, 1]"
        elif self.kind in ("bool", "path"):
            text = self.kind
        else:
            text = _SYNTAX[self.kind]
        return text + ("; *repeatable*" if self.repeatable else "")


#: The lines with their own syntax: the spec's words for them.
_SYNTAX = {
    "scales": "floats in (0, 1], decreasing",
    "divisions": "1 or 3 ints ≥ 1",
    "entry": "`id x y z path`",
    "rba": "`id x y z rba-folder scene-file`",
    "weight": "`id path`",
    "id stiffness": "`id stiffness`",
    "variation": "`id field value …`",
}

_COUNT0, _COUNT1 = KeySpec("int", low=0), KeySpec("int", low=1)
#: Upper bounds of the counts: iterations per step, steps per frame, frames (a count of
#: 1e11 hung, one of 1e23 overflowed the kernels' integers).
_ITERS, _FRAMES = 10_000, 100_000

#: Every key, in the order the writer writes them (the thesis's C.1 list order, with ``max
#: collision retries`` from its example placed after the collision iterations).
KEYS: Mapping[str, KeySpec] = MappingProxyType({
    "solver iterations": replace(_COUNT0, high=_ITERS, field="solver_iterations"),
    "collision solver iterations": replace(_COUNT0, high=_ITERS, field="collision_iterations"),
    "max collision retries": replace(_COUNT0, high=1000, field="max_collision_retries"),
    "kStretch": KeySpec("stiffness", field="k_stretch"),
    "kBend": KeySpec("stiffness", field="k_bend"),
    "kCollision": KeySpec("stiffness", field="k_collision"),
    "spacing": KeySpec("float", low=0, field="spacing"),
    "scene scale factor": KeySpec("float", 3, low=0, strict=True, field="scene_scale"),
    "updates per frame": replace(_COUNT1, high=1000, field="updates_per_frame"),
    "run for number of frames": replace(_COUNT0, high=_FRAMES, field="run_frames"),
    "sanity check per frames": replace(_COUNT0, high=_FRAMES, field="sanity_check_every"),
    "max substeps": replace(_COUNT0, high=16, field="max_substeps"),
    "edge stretch bounds": KeySpec("float", 2, low=0, strict=True, check="lo ≤ 1 ≤ hi",
                                   field="stretch_bounds"),
    "relax iterations": replace(_COUNT0, high=_ITERS, field="relax_iterations"),
    "collisions": KeySpec("bool", field="collisions"),
    "emergence scales": KeySpec("scales", field="emergence_scales"),
    "emergence growth frames": KeySpec("float", low=0, strict=True, field="emergence_growth_frames"),
    "crowded scales": KeySpec("scales", field="crowded_scales"),
    "output animation frames number": replace(_COUNT1, high=_FRAMES, field="output_frames_number"),
    "output animation obj per frames": replace(_COUNT0, high=_FRAMES, field="output_obj_skip"),
    "lattice size multiply": KeySpec("float", 3, low=0, strict=True, field="lattice.size_multiply"),
    "lattice make cube": KeySpec("bool", field="lattice.make_cube"),
    "origin": KeySpec("float", 3, field="lattice.origin"),
    "divisions": KeySpec("divisions", field="lattice.divisions"),
    "dimensions": KeySpec("float", 3, low=0, strict=True, field="lattice.dimensions"),
    "lattice auto bounds": KeySpec("bool", field="lattice.auto_bounds"),
    "color map file location": KeySpec("path", field="color_map"),
    "material map file location": KeySpec("path", field="material_map"),
    "scene file path": KeySpec("path", field="scene_files", repeatable=True),
    "animation": KeySpec("entry", repeatable=True),
    "obj": KeySpec("entry", repeatable=True),
    "rigid body animation": KeySpec("rba", repeatable=True),
    "weight": KeySpec("weight", repeatable=True),
    "petal weight": KeySpec("weight", repeatable=True),
    "bending stiffness": KeySpec("id stiffness", repeatable=True),
    "distance stiffness": KeySpec("id stiffness", repeatable=True),
    "variation": KeySpec("variation", repeatable=True),
    "animation output folder location": KeySpec("path", field="animation_output_folder"),
    "obj output file path": KeySpec("path", field="obj_output_file"),
    "camera position": KeySpec("float", 3, field="camera.position"),
    "camera up": KeySpec("float", 3, check="not all 0", field="camera.up"),
    "camera lookat": KeySpec("float", 3, field="camera.lookat"),
    "camera pan speed": KeySpec("float", low=0, field="camera.pan_speed"),
    "camera zoom speed": KeySpec("float", low=0, field="camera.zoom_speed"),
    "camera rotate speed": KeySpec("float", low=0, field="camera.rotate_speed"),
    "near plane": KeySpec("float", low=0, strict=True, field="camera.near"),
    "far plane": KeySpec("float", low=0, strict=True, field="camera.far"),
    "camera fov": KeySpec("float", check="in (0, 180)", field="camera.fov_deg"),
    "light position": KeySpec("float", 3, field="camera.light_position"),
    "shadow frustrum": KeySpec("float", 6, field="camera.shadow_frustum"),
})

#: Canonical keys in the order the writer writes them.
KNOWN_KEYS: tuple[str, ...] = tuple(KEYS)

#: Other spellings -> canonical key.
ALIASES: Mapping[str, str] = MappingProxyType(
    {
        "collision iterations": "collision solver iterations",  # the thesis's example file
        "shadow frustum": "shadow frustrum",
    }
)

#: Keys that may appear more than once.
REPEATABLE = frozenset(k for k, spec in KEYS.items() if spec.repeatable)


def _norm(key: str) -> str:
    return " ".join(key.split()).lower()


_LOOKUP: dict[str, str] = {_norm(k): k for k in KNOWN_KEYS}
_LOOKUP.update({_norm(a): c for a, c in ALIASES.items()})
_SUGGEST: dict[str, str] = {_norm(k): k for k in (*KNOWN_KEYS, *ALIASES)}

_SEP = re.compile(r"[,\s]+")
_C_FLOAT = re.compile(r"^[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?[fF]$")
_TRUE = {"true", "1", "yes", "on"}
_FALSE = {"false", "0", "no", "off"}


def _suggest(key: str) -> str:
    hint = did_you_mean(_norm(key), _SUGGEST, cutoff=0.6, spelling=_SUGGEST)
    return f"a known key{hint}" if hint else "a known key (see formats/fcc.md)"


# --------------------------------------------------------------------------------------------------
# Reader
# --------------------------------------------------------------------------------------------------


class _Reader:
    """One pass over the lines of a .fcc file, collecting fields for CanopyParams."""

    def __init__(self, path):
        self.path = os.fspath(path)
        self.base = os.path.dirname(os.path.abspath(self.path))
        self.values: dict[str, object] = {}
        self.lattice: dict[str, object] = {}
        self.camera: dict[str, object] = {}
        self.first_line: dict[str, int] = {}
        self.last_line: dict[str, int] = {}
        self.animations: list[AnimationEntry] = []
        self.rbas: list[RigidBodyAnimationEntry] = []
        self.id_lines: dict[int, tuple[str, int]] = {}
        self.weights: dict[int, FilePath] = {}
        self.petal_weights: dict[int, FilePath] = {}
        self.bending: dict[int, float] = {}
        self.distance: dict[int, float] = {}
        self.variations: dict[int, Variation] = {}
        self.per_id_lines: dict[tuple[str, int], int] = {}

    # -- value helpers -------------------------------------------------------------------------

    def err(self, line, expected, found):
        return FormatError(self.path, line, expected, found)

    def tokens(self, value: str) -> list[str]:
        return [t for t in _SEP.split(value.strip()) if t]

    def number(self, tok: str, line: int, what: str) -> float:
        if _C_FLOAT.match(tok):
            tok = tok[:-1]
        return parse_float(tok, self.path, line, what)

    def count_tokens(self, key, value, line, n, what) -> list[str]:
        toks = self.tokens(value)
        if len(toks) != n:
            found = shorten(value) if value.strip() else "nothing"
            raise self.err(line, f"{what} after '{key}:'", f"{len(toks)} value(s): {found}")
        return toks

    def floats(self, key, value, line, n, *, positive=False, nonneg=False) -> tuple[float, ...]:
        what = f"{n} number{'s' if n > 1 else ''}" + (
            " (> 0)" if positive else " (>= 0)" if nonneg else ""
        )
        toks = self.count_tokens(key, value, line, n, what)
        out = []
        for t in toks:
            v = self.number(t, line, f"a number for '{key}'")
            if positive and not v > 0:
                raise self.err(line, f"a number > 0 for '{key}'", shorten(t))
            if nonneg and v < 0:
                raise self.err(line, f"a number >= 0 for '{key}'", shorten(t))
            out.append(v)
        return tuple(out)

    def integer(self, key, tok, line, minimum, maximum=None) -> int:
        v = parse_int(tok, self.path, line, f"an integer for '{key}'")
        if v < minimum:
            raise self.err(line, f"an integer >= {minimum} for '{key}'", shorten(tok))
        if maximum is not None and v > maximum:
            raise self.err(line, f"an integer in [{minimum:g}, {maximum:g}] for '{key}'", shorten(tok))
        return v

    def count(self, key, value, line, minimum, maximum=None) -> int:
        (tok,) = self.count_tokens(key, value, line, 1, f"1 integer (>= {minimum})")
        return self.integer(key, tok, line, minimum, maximum)

    def stiffness_value(self, key, tok, line) -> float:
        v = self.number(tok, line, f"a stiffness in [0, 1] for '{key}'")
        if not 0.0 <= v <= 1.0:
            raise self.err(line, f"a stiffness in [0, 1] for '{key}'", shorten(tok))
        return v

    def boolean(self, key, value, line) -> bool:
        (tok,) = self.count_tokens(key, value, line, 1, "true or false")
        low = tok.lower()
        if low in _TRUE:
            return True
        if low in _FALSE:
            return False
        raise self.err(line, f"true or false for '{key}'", shorten(tok))

    def filepath(self, key, raw, line) -> FilePath:
        raw = raw.strip()
        if not raw:
            raise self.err(line, f"a path after '{key}:'", "nothing")
        return FilePath.at(raw, self.base, line)

    def ident(self, key, tok, line) -> int:
        return self.integer(key, tok, line, 0)

    def claim_id(self, key, id_, tok, line):
        if id_ in self.id_lines:
            other_key, other_line = self.id_lines[id_]
            raise self.err(
                line,
                f"an id not used before (id {id_} already names the '{other_key}' entry "
                f"on line {other_line})",
                shorten(tok),
            )
        self.id_lines[id_] = (key, line)

    # -- one line ------------------------------------------------------------------------------

    def line(self, number: int, text: str):
        body = text.split("#", 1)[0].strip()
        if not body:
            return
        if ":" not in body:
            raise self.err(number, "'key: value'", shorten(body))
        raw_key, value = body.split(":", 1)
        if not raw_key.strip():
            raise self.err(number, "a key before ':'", shorten(body))
        key = _LOOKUP.get(_norm(raw_key))
        if key is None:
            raise self.err(number, _suggest(raw_key), shorten(raw_key))
        if key not in REPEATABLE and key in self.first_line:
            raise self.err(
                number,
                f"each key once ('{key}' is already set on line {self.first_line[key]})",
                shorten(body),
            )
        self.first_line.setdefault(key, number)
        self.last_line[key] = number
        self.handle(key, value, number)

    def handle(self, key: str, value: str, n: int):
        spec = KEYS[key]
        got = _READ[spec.kind](self, key, spec, value, n)
        if not spec.field:
            return
        group, _, name = spec.field.rpartition(".")
        target = {"": self.values, "lattice": self.lattice, "camera": self.camera}[group]
        if spec.repeatable:
            target.setdefault(name, []).append(got)
        else:
            target[name] = got

    # -- the readers of _READ: (key, spec, value, line) -> the key's value -----------------------

    def read_int(self, key, spec, value, n):
        return self.count(key, value, n, spec.low, spec.high)

    def read_float(self, key, spec, value, n):
        positive = spec.low == 0 and spec.strict
        vals = self.floats(key, value, n, spec.n, positive=positive, nonneg=spec.low == 0 and not positive)
        if spec.check:
            _CHECKS[spec.check](self, key, vals, value, n)
        return vals[0] if spec.n == 1 else vals

    def read_stiffness(self, key, spec, value, n):
        (tok,) = self.count_tokens(key, value, n, 1, "1 stiffness in [0, 1]")
        return self.stiffness_value(key, tok, n)

    def read_bool(self, key, spec, value, n):
        return self.boolean(key, value, n)

    def read_path(self, key, spec, value, n):
        return self.filepath(key, value, n)

    def read_scales(self, key, spec, value, n):
        toks = self.tokens(value)
        if not toks:
            raise self.err(n, f"one or more numbers in (0, 1] after '{key}:'", "nothing")
        vals = [self.number(t, n, f"a number for '{key}'") for t in toks]
        for t, x in zip(toks, vals):
            if not 0.0 < x <= 1.0:
                raise self.err(n, f"numbers in (0, 1] for '{key}'", shorten(t))
        if any(b >= a for a, b in zip(vals, vals[1:])):
            raise self.err(n, f"decreasing numbers for '{key}'", shorten(value.strip()))
        return tuple(vals)

    def read_divisions(self, key, spec, value, n):
        toks = self.tokens(value)
        if len(toks) not in (1, 3):
            found = shorten(value) if value.strip() else "nothing"
            raise self.err(
                n, "1 or 3 integers (>= 1) after 'divisions:'", f"{len(toks)} value(s): {found}"
            )
        d = tuple(self.integer(key, t, n, 1) for t in toks)
        return d * 3 if len(d) == 1 else d

    def read_entry(self, key, spec, value, n):
        parts = [t for t in _SEP.split(value.strip(), maxsplit=4)]
        if len(parts) < 5 or not parts[4].strip():
            raise self.err(
                n,
                f"'{key}: id x y z path' (an id, 3 scales, a path)",
                shorten(value) if value.strip() else "nothing",
            )
        id_ = self.ident(key, parts[0], n)
        scale = self.floats(key, " ".join(parts[1:4]), n, 3, positive=True)
        path = self.filepath(key, parts[4], n)
        self.claim_id(key, id_, parts[0], n)
        self.animations.append(AnimationEntry(id_, scale, path, key, n))

    def read_rba(self, key, spec, value, n):
        toks = self.tokens(value)
        if len(toks) != 6:
            raise self.err(
                n,
                "'rigid body animation: id x y z rba-folder scene-file' (6 values)",
                f"{len(toks)} value(s): {shorten(value) if value.strip() else 'nothing'}",
            )
        id_ = self.ident(key, toks[0], n)
        scale = self.floats(key, " ".join(toks[1:4]), n, 3, positive=True)
        folder = self.filepath(key, toks[4], n)
        scene = self.filepath(key, toks[5], n)
        self.claim_id(key, id_, toks[0], n)
        self.rbas.append(RigidBodyAnimationEntry(id_, scale, folder, scene, n))

    def read_weight(self, key, spec, value, n):
        parts = _SEP.split(value.strip(), maxsplit=1)
        if len(parts) < 2 or not parts[1].strip():
            raise self.err(
                n, f"'{key}: id path'", shorten(value) if value.strip() else "nothing"
            )
        id_ = self.ident(key, parts[0], n)
        self.per_id(key, id_, parts[0], n)
        table = self.weights if key == "weight" else self.petal_weights
        table[id_] = self.filepath(key, parts[1], n)

    def read_id_stiffness(self, key, spec, value, n):
        toks = self.count_tokens(key, value, n, 2, "an id and a stiffness in [0, 1]")
        id_ = self.ident(key, toks[0], n)
        s = self.stiffness_value(key, toks[1], n)
        self.per_id(key, id_, toks[0], n)
        (self.bending if key == "bending stiffness" else self.distance)[id_] = s

    def read_variation(self, key, spec, value, n):
        toks = self.tokens(value)
        if not toks:
            raise self.err(n, f"'{key}: id field value …'", "nothing")
        id_ = self.ident(key, toks[0], n)
        try:
            var = parse_variation(toks[1:], lambda t: self.number(t, n, f"a number for '{key}'"))
        except ValueError as e:
            raise self.err(n, f"'{key}': {e.args[0]}", shorten(e.args[1])) from None
        self.per_id(key, id_, toks[0], n)
        self.variations[id_] = var

    def per_id(self, key, id_, tok, line):
        prev = self.per_id_lines.get((key, id_))
        if prev is not None:
            raise self.err(
                line, f"one '{key}' line per id (id {id_} already has one on line {prev})",
                shorten(tok),
            )
        self.per_id_lines[(key, id_)] = line

    # -- whole-file checks ---------------------------------------------------------------------

    def finish(self) -> CanopyParams:
        geometry_ids = {e.id for e in self.animations}
        for key, table in (
            ("weight", self.weights),
            ("petal weight", self.petal_weights),
            ("bending stiffness", self.bending),
            ("distance stiffness", self.distance),
            ("variation", self.variations),
        ):
            for id_ in table:
                if id_ not in geometry_ids:
                    raise self.err(
                        self.per_id_lines[(key, id_)],
                        f"the id of an 'animation' or 'obj' entry for '{key}'",
                        f"id {id_}",
                    )
        cam = self.camera
        if "near" in cam and "far" in cam and not cam["far"] > cam["near"]:
            line = max(self.last_line["near plane"], self.last_line["far plane"])
            raise self.err(
                line, "far plane > near plane", f"near {cam['near']!r}, far {cam['far']!r}"
            )
        v = self.values
        if "output_frames_number" in v and "output_obj_skip" in v:
            if v["output_frames_number"] != v["output_obj_skip"] + 1:
                line = max(
                    self.last_line["output animation frames number"],
                    self.last_line["output animation obj per frames"],
                )
                raise self.err(
                    line,
                    "'output animation frames number' = 'output animation obj per frames' + 1 "
                    "when both are given",
                    f"{v['output_frames_number']} and {v['output_obj_skip']}",
                )
        return CanopyParams(
            **v,
            lattice=LatticeParams(**self.lattice),
            animations=tuple(self.animations),
            rigid_body_animations=tuple(self.rbas),
            weights=self.weights,
            petal_weights=self.petal_weights,
            bending_stiffness=self.bending,
            distance_stiffness=self.distance,
            variations=self.variations,
            camera=CameraParams(**cam),
            source=Path(os.path.abspath(self.path)),
            lines=self.last_line,
        )


_READ = {
    "int": _Reader.read_int,
    "float": _Reader.read_float,
    "stiffness": _Reader.read_stiffness,
    "bool": _Reader.read_bool,
    "path": _Reader.read_path,
    "scales": _Reader.read_scales,
    "divisions": _Reader.read_divisions,
    "entry": _Reader.read_entry,
    "rba": _Reader.read_rba,
    "weight": _Reader.read_weight,
    "id stiffness": _Reader.read_id_stiffness,
    "variation": _Reader.read_variation,
}


def _stretch_bounds(r: _Reader, key, vals, value, n):
    lo, hi = vals
    if not (lo <= 1.0 <= hi) or not math.isfinite(hi):
        raise r.err(n, f"two numbers lo <= 1 <= hi for '{key}'", shorten(value.strip()))


def _not_all_zero(r: _Reader, key, vals, value, n):
    if not any(vals):
        raise r.err(n, "a non-zero up vector", shorten(value))


def _field_of_view(r: _Reader, key, vals, value, n):
    if not 0.0 < vals[0] < 180.0:
        raise r.err(n, "a field of view in (0, 180) degrees", shorten(value))


#: KeySpec.check -> the test of the values together.
_CHECKS = {
    "lo ≤ 1 ≤ hi": _stretch_bounds,
    "not all 0": _not_all_zero,
    "in (0, 180)": _field_of_view,
}


def read_fcc(path) -> CanopyParams:
    """Read a canopy composer parameter file (thesis app. C.1).

    Parameters
    ----------
    path : str or os.PathLike
        The ``.fcc`` file. Relative paths inside it are resolved against its folder.

    Returns
    -------
    CanopyParams
        Every key, with the documented default for keys the file does not give.

    Raises
    ------
    FormatError
        A malformed line: unknown key (naming the closest known one), wrong number or type of
        values, NaN/inf, a stiffness outside [0, 1], a negative count, a repeated key, a duplicate
        id, a per-id setting for an id no ``animation``/``obj`` line defines.
    InputError
        The file is missing or unreadable.
    """
    reader = _Reader(path)
    lines = read_lines(path)
    if lines and lines[0].startswith("\ufeff"):
        lines[0] = lines[0][1:]
    for number, text in enumerate(lines, start=1):
        reader.line(number, text)
    return reader.finish()


# --------------------------------------------------------------------------------------------------
# Writer
# --------------------------------------------------------------------------------------------------


def _num(x: float) -> str:
    """Shortest text that reads back as the same float64 (Python's ``repr``)."""
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"cannot write a non-finite number ({x!r}) to a .fcc file")
    return repr(x)


def _vec(values) -> str:
    return ", ".join(_num(x) for x in values)


def _check_raw(raw: str, key: str, *, no_space: bool = False) -> str:
    bad = "#\n\r" + (" \t," if no_space else "")
    if not raw or raw != raw.strip() or any(c in raw for c in bad):
        raise ValueError(
            f"cannot write path {raw!r} for '{key}': it must be non-empty, without surrounding "
            f"blanks, '#' or line breaks" + (", spaces or commas" if no_space else "")
        )
    return raw


def _bool(b: bool) -> str:
    return "true" if b else "false"


def format_fcc(params: CanopyParams) -> str:
    """The text :func:`write_fcc` writes: every key in a fixed order, unset ones as comments.

    Numbers are written as the shortest text that reads back to the same float64 (``repr``), so
    write -> read -> write is byte-identical.
    """
    p = params
    out: list[str] = [
        "# inflo canopy composer parameters (thesis app. C.1); spec: formats/fcc.md",
        "",
    ]
    add = out.append

    def opt(key: str, value: str | None, unset: str):
        add(f"{key}: {value}" if value is not None else f"# {key}: {unset}")

    add("# constraints")
    add(f"solver iterations: {int(p.solver_iterations)}")
    add(f"collision solver iterations: {int(p.collision_iterations)}")
    add(f"max collision retries: {int(p.max_collision_retries)}")
    add(f"kStretch: {_num(p.k_stretch)}")
    add(f"kBend: {_num(p.k_bend)}")
    add(f"kCollision: {_num(p.k_collision)}")
    add(f"spacing: {_num(p.spacing)}")
    add("")
    add("# simulation")
    add(f"scene scale factor: {_vec(p.scene_scale)}")
    add(f"updates per frame: {int(p.updates_per_frame)}")
    opt("run for number of frames",
        None if p.run_frames is None else str(int(p.run_frames)), "all frames")
    add(f"sanity check per frames: {int(p.sanity_check_every)}")
    add(f"max substeps: {int(p.max_substeps)}")
    add(f"edge stretch bounds: {_num(p.stretch_bounds[0])} {_num(p.stretch_bounds[1])}")
    add(f"relax iterations: {int(p.relax_iterations)}")
    add(f"collisions: {_bool(p.collisions)}")
    add("emergence scales: " + " ".join(_num(x) for x in p.emergence_scales))
    add(f"emergence growth frames: {_num(p.emergence_growth_frames)}")
    add("crowded scales: " + " ".join(_num(x) for x in p.crowded_scales))
    opt("output animation frames number",
        None if p.output_frames_number is None else str(int(p.output_frames_number)), "not set")
    opt("output animation obj per frames",
        None if p.output_obj_skip is None else str(int(p.output_obj_skip)), "not set")
    add("")
    add("# collision lattice")
    lat = p.lattice
    add(f"lattice size multiply: {_vec(lat.size_multiply)}")
    add(f"lattice make cube: {_bool(lat.make_cube)}")
    add(f"origin: {_vec(lat.origin)}")
    add(f"divisions: {', '.join(str(int(d)) for d in lat.divisions)}")
    add(f"dimensions: {_vec(lat.dimensions)}")
    add(f"lattice auto bounds: {_bool(lat.auto_bounds)}")
    add("")
    add("# files")
    opt("color map file location",
        None if p.color_map is None else _check_raw(p.color_map.raw, "color map file location"),
        "none")
    opt("material map file location",
        None if p.material_map is None
        else _check_raw(p.material_map.raw, "material map file location"),
        "none")
    if not p.scene_files:
        add("# scene file path: none")
    for f in p.scene_files:
        add(f"scene file path: {_check_raw(f.raw, 'scene file path')}")
    for e in p.animations:
        add(f"{e.kind}: {int(e.id)} {' '.join(_num(s) for s in e.scale)} "
            f"{_check_raw(e.path.raw, e.kind)}")
    for r in p.rigid_body_animations:
        key = "rigid body animation"
        add(f"{key}: {int(r.id)} {' '.join(_num(s) for s in r.scale)} "
            f"{_check_raw(r.rba_folder.raw, key, no_space=True)} "
            f"{_check_raw(r.scene_path.raw, key, no_space=True)}")
    for id_ in sorted(p.weights):
        add(f"weight: {int(id_)} {_check_raw(p.weights[id_].raw, 'weight')}")
    for id_ in sorted(p.petal_weights):
        add(f"petal weight: {int(id_)} {_check_raw(p.petal_weights[id_].raw, 'petal weight')}")
    for id_ in sorted(p.bending_stiffness):
        add(f"bending stiffness: {int(id_)} {_num(p.bending_stiffness[id_])}")
    for id_ in sorted(p.distance_stiffness):
        add(f"distance stiffness: {int(id_)} {_num(p.distance_stiffness[id_])}")
    for id_ in sorted(p.variations):
        add(f"variation: {int(id_)} {p.variations[id_].text()}")
    opt("animation output folder location",
        None if p.animation_output_folder is None
        else _check_raw(p.animation_output_folder.raw, "animation output folder location"),
        "none (fccompose -o)")
    opt("obj output file path",
        None if p.obj_output_file is None
        else _check_raw(p.obj_output_file.raw, "obj output file path"),
        "none")
    add("")
    add("# viewer: camera and light (canopy-render)")
    c = p.camera
    opt("camera position", None if c.position is None else _vec(c.position), "automatic")
    add(f"camera up: {_vec(c.up)}")
    opt("camera lookat", None if c.lookat is None else _vec(c.lookat), "automatic")
    add(f"camera pan speed: {_num(c.pan_speed)}")
    add(f"camera zoom speed: {_num(c.zoom_speed)}")
    add(f"camera rotate speed: {_num(c.rotate_speed)}")
    opt("near plane", None if c.near is None else _num(c.near), "automatic")
    opt("far plane", None if c.far is None else _num(c.far), "automatic")
    add(f"camera fov: {_num(c.fov_deg)}")
    opt("light position",
        None if c.light_position is None else _vec(c.light_position), "automatic")
    opt("shadow frustrum",
        None if c.shadow_frustum is None else _vec(c.shadow_frustum), "none")
    return "\n".join(out) + "\n"


def write_fcc(path, params: CanopyParams) -> None:
    """Write ``params`` to ``path`` atomically (see :func:`format_fcc` for the layout).

    Paths are written as their ``raw`` text, so they stay relative to the folder of the file they
    came from; write next to the original (or rebuild the :class:`FilePath` values) to keep them
    pointing at the same files. Raises ValueError for a value the format cannot carry (a path with
    ``#`` or a line break, a non-finite number).
    """
    write_text_atomic(path, format_fcc(params))


# --------------------------------------------------------------------------------------------------
# References
# --------------------------------------------------------------------------------------------------


class MissingReferenceError(InputError):
    """Files or folders a ``.fcc`` file names that do not exist.

    Attributes
    ----------
    source : pathlib.Path or None
        The ``.fcc`` file the parameters came from.
    missing : list of tuple (int or None, str, FilePath, str)
        (line, key, path, what was expected: "file", "folder", ...) for every missing reference,
        in file order.
    """

    def __init__(self, source, missing):
        self.source = source
        self.missing = missing
        where = os.fspath(source) if source is not None else "<parameters>"
        parts = []
        for line, key, fp, kind in missing:
            loc = f"{where}:{line}" if line is not None else where
            parts.append(f"{loc}: '{key}' names {fp.raw!r} ({fp.resolved}), no such {kind}")
        msg = parts[0]
        if len(parts) > 1:
            msg += f" (and {len(parts) - 1} more: " + "; ".join(parts[1:]) + ")"
        super().__init__(msg)


def _exists_folder_or_glob(p: Path) -> bool:
    if p.is_dir():
        return True
    if glob.has_magic(os.fspath(p)):
        return bool(glob.glob(os.fspath(p)))
    return False


def check_references(params: CanopyParams) -> None:
    """Check that every file and folder ``params`` names exists.

    Scene files, OBJs, weight files, colour and material maps must be files; animation paths a
    folder or a glob matching something; RBA paths a folder. Output locations are not checked
    (fccompose creates them).

    Raises
    ------
    MissingReferenceError
        (an :class:`InputError`) naming the first missing path, the ``.fcc`` line that named it,
        and how many more are missing; ``.missing`` lists them all.
    """
    missing = []

    def need(key, fp: FilePath | None, kind: str, ok):
        if fp is not None and not ok(fp.resolved):
            missing.append((fp.line, key, fp, kind))

    need("color map file location", params.color_map, "file", Path.is_file)
    need("material map file location", params.material_map, "file", Path.is_file)
    for f in params.scene_files:
        need("scene file path", f, "file", Path.is_file)
    for e in params.animations:
        if e.kind == "obj":
            need("obj", e.path, "file", Path.is_file)
        else:
            need("animation", e.path, "folder or matching glob", _exists_folder_or_glob)
    for r in params.rigid_body_animations:
        need("rigid body animation", r.rba_folder, "folder", Path.is_dir)
        need("rigid body animation", r.scene_path, "file", Path.is_file)
    for id_ in sorted(params.weights):
        need("weight", params.weights[id_], "file", Path.is_file)
    for id_ in sorted(params.petal_weights):
        need("petal weight", params.petal_weights[id_], "file", Path.is_file)
    if missing:
        missing.sort(key=lambda m: (m[0] is None, m[0] or 0))
        raise MissingReferenceError(params.source, missing)
