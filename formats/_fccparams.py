"""The ``.fcc`` data model (thesis app. C.1): :class:`CanopyParams` and the values it holds.

What :func:`inflo.formats.fcc.read_fcc` returns and :func:`inflo.formats.fcc.write_fcc` writes;
import these names from :mod:`inflo.formats.fcc`.
"""
from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

from .variation import Variation

Vec3 = tuple[float, float, float]


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
        Initial scale in x, y, z applied to the geometry on load (each in [1e-6, 1e6]).
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
        Initial scale in x, y, z (each in [1e-6, 1e6]).
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
    solver_scheme : str
        ``solver scheme``: ``"default"`` (the iteration scheme whose outputs the goldens hold) or
        ``"fast"`` (formats/fcc.md, "Solver scheme": fewer projections for the same quality
        figures; results differ). ``"default"``.
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
    petal_ramps : mapping of int to (float, float)
        ``petal ramp`` lines: id of an entry with a ``petal weight`` line -> (from, to), the
        developmental fractions of its template's frames between which a placement's petal factor
        takes effect: frame s of F is scaled by ``1 + w_v (f - 1) g(u)``, ``u = s / (F - 1)``,
        ``g`` a smoothstep from 0 at ``from`` to 1 at ``to`` (the bud as read, the open petals
        grown). Empty: every frame grown by the whole factor.
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
    solver_scheme: str = "default"
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
    petal_ramps: Mapping[int, tuple] = field(default_factory=dict)
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
        for name in ("weights", "petal_weights", "petal_ramps", "bending_stiffness", "distance_stiffness", "variations", "lines"):
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
