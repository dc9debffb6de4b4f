"""The ``.fcc`` key table (``formats/fcc.md``, "Keys"): every key, its kind, range and field, its
aliases, and the lookup the reader uses to name the closest known key.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType

from .errors import did_you_mean


@dataclass(frozen=True)
class KeySpec:
    """One key of the ``.fcc`` table (``formats/fcc.md``, "Keys"): what the reader takes and where
    it puts it.

    Parameters
    ----------
    kind : str
        ``"int"``, ``"float"``, ``"stiffness"`` (a float in [0, 1]), ``"bool"``, ``"path"``, or a
        line with its own syntax (:data:`_SYNTAX`): ``"scales"``, ``"divisions"``, ``"entry"``
        (``animation``/``obj``), ``"rba"``, ``"weight"``, ``"id stiffness"``, ``"ramp"``.
    n : int
        How many numbers (``"float"``; 1 for ``"int"``).
    low : float or None
        The range: ``"int"``: at least ``low``; ``"float"``: at least ``low``, above it when
        ``strict``; None: any finite number.
    high : float or None
        ``"int"``: at most ``high`` (iteration and frame counts: a count beyond it is a typo, not a
        run this machine could finish); ``"float"``: every number at most ``high`` in magnitude
        (sizes and coordinates beyond it overflow the simulation's arithmetic); None: no upper bound.
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
            if self.high is not None:
                text += f", ≤ {self.high:g}" if self.low is not None else f" in ±{self.high:g}"
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
    "ramp": "`id from to`, 0 ≤ from < to ≤ 1",
    "variation": "`id field value …`",
    "scheme": "`default` or `fast`",
}

#: The values of ``solver scheme`` (formats/fcc.md, "Solver scheme").
SCHEMES = ("default", "fast")

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
    "spacing": KeySpec("float", low=0, high=1e12, field="spacing"),
    "scene scale factor": KeySpec("float", 3, low=0, high=1e6, strict=True, field="scene_scale"),
    "updates per frame": replace(_COUNT1, high=1000, field="updates_per_frame"),
    "run for number of frames": replace(_COUNT0, high=_FRAMES, field="run_frames"),
    "sanity check per frames": replace(_COUNT0, high=_FRAMES, field="sanity_check_every"),
    "max substeps": replace(_COUNT0, high=16, field="max_substeps"),
    "edge stretch bounds": KeySpec("float", 2, low=0, strict=True, check="lo ≤ 1 ≤ hi",
                                   field="stretch_bounds"),
    "relax iterations": replace(_COUNT0, high=_ITERS, field="relax_iterations"),
    "solver scheme": KeySpec("scheme", field="solver_scheme"),
    "collisions": KeySpec("bool", field="collisions"),
    "emergence scales": KeySpec("scales", field="emergence_scales"),
    "emergence growth frames": KeySpec("float", low=0, high=1e7, strict=True, field="emergence_growth_frames"),
    "crowded scales": KeySpec("scales", field="crowded_scales"),
    "output animation frames number": replace(_COUNT1, high=_FRAMES, field="output_frames_number"),
    "output animation obj per frames": replace(_COUNT0, high=_FRAMES, field="output_obj_skip"),
    "lattice size multiply": KeySpec("float", 3, low=0, high=1e6, strict=True, field="lattice.size_multiply"),
    "lattice make cube": KeySpec("bool", field="lattice.make_cube"),
    "origin": KeySpec("float", 3, high=1e12, field="lattice.origin"),
    "divisions": KeySpec("divisions", field="lattice.divisions"),
    "dimensions": KeySpec("float", 3, low=0, high=1e12, strict=True, field="lattice.dimensions"),
    "lattice auto bounds": KeySpec("bool", field="lattice.auto_bounds"),
    "color map file location": KeySpec("path", field="color_map"),
    "material map file location": KeySpec("path", field="material_map"),
    "scene file path": KeySpec("path", field="scene_files", repeatable=True),
    "animation": KeySpec("entry", repeatable=True),
    "obj": KeySpec("entry", repeatable=True),
    "rigid body animation": KeySpec("rba", repeatable=True),
    "weight": KeySpec("weight", repeatable=True),
    "petal weight": KeySpec("weight", repeatable=True),
    "petal ramp": KeySpec("ramp", repeatable=True),
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


def _suggest(key: str) -> str:
    hint = did_you_mean(_norm(key), _SUGGEST, cutoff=0.6, spelling=_SUGGEST)
    return f"a known key{hint}" if hint else "a known key (see formats/fcc.md)"
