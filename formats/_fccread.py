"""The ``.fcc`` reader: :func:`read_fcc`, one pass over the lines collecting :class:`CanopyParams`."""
from __future__ import annotations

import math
import os
import re
from pathlib import Path

from ._fcckeys import _LOOKUP, KEYS, REPEATABLE, SCHEMES, _norm, _suggest
from ._fccparams import AnimationEntry, CameraParams, CanopyParams, FilePath, LatticeParams, RigidBodyAnimationEntry
from .errors import FormatError, parse_float, parse_int, read_lines, shorten
from .variation import Variation, parse_variation

_SEP = re.compile(r"[,\s]+")
_C_FLOAT = re.compile(r"^[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?[fF]$")
_TRUE = {"true", "1", "yes", "on"}
_FALSE = {"false", "0", "no", "off"}


#: the initial scale of an animation, obj or rigid body animation entry (each of x, y, z), as a
#: placement's petal factor and dimorph's size factors
MIN_ENTRY_SCALE = 1e-6
MAX_ENTRY_SCALE = 1e6


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
        self.petal_ramps: dict[int, tuple[float, float]] = {}
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
        if spec.high is not None:
            for t, v in zip(self.tokens(value), vals if isinstance(vals, (list, tuple)) else [vals]):
                if abs(v) > spec.high:
                    raise self.err(n, f"numbers of magnitude at most {spec.high:g} for '{key}'", shorten(t))
        if spec.check:
            _CHECKS[spec.check](self, key, vals, value, n)
        return vals[0] if spec.n == 1 else vals

    def read_stiffness(self, key, spec, value, n):
        (tok,) = self.count_tokens(key, value, n, 1, "1 stiffness in [0, 1]")
        return self.stiffness_value(key, tok, n)

    def read_bool(self, key, spec, value, n):
        return self.boolean(key, value, n)

    def read_scheme(self, key, spec, value, n):
        word = " ".join(value.split()).lower()
        if word not in SCHEMES:
            raise self.err(n, f"one of {', '.join(SCHEMES)} for '{key}'", shorten(value.strip()) or "nothing")
        return word

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

    def entry_scale(self, key, toks, line) -> tuple[float, ...]:
        """The 3 scales of an animation, obj or rigid body animation line, each in
        [MIN_ENTRY_SCALE, MAX_ENTRY_SCALE]."""
        scale = self.floats(key, " ".join(toks), line, 3, positive=True)
        for t, v in zip(toks, scale):
            if not MIN_ENTRY_SCALE <= v <= MAX_ENTRY_SCALE:
                raise self.err(line, f"scales in [{MIN_ENTRY_SCALE:g}, {MAX_ENTRY_SCALE:g}] for '{key}'", shorten(t))
        return scale

    def read_entry(self, key, spec, value, n):
        parts = [t for t in _SEP.split(value.strip(), maxsplit=4)]
        if len(parts) < 5 or not parts[4].strip():
            raise self.err(
                n,
                f"'{key}: id x y z path' (an id, 3 scales, a path)",
                shorten(value) if value.strip() else "nothing",
            )
        id_ = self.ident(key, parts[0], n)
        scale = self.entry_scale(key, parts[1:4], n)
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
        scale = self.entry_scale(key, toks[1:4], n)
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

    def read_ramp(self, key, spec, value, n):
        toks = self.count_tokens(key, value, n, 3, "an id and two fractions 0 <= from < to <= 1")
        id_ = self.ident(key, toks[0], n)
        lo, hi = (self.number(t, n, f"a number for '{key}'") for t in toks[1:])
        if not 0.0 <= lo < hi <= 1.0:
            raise self.err(n, f"two fractions 0 <= from < to <= 1 for '{key}'", shorten(" ".join(toks[1:])))
        self.per_id(key, id_, toks[0], n)
        self.petal_ramps[id_] = (lo, hi)

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
            ("petal ramp", self.petal_ramps),
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
        for id_ in self.petal_ramps:
            if id_ not in self.petal_weights:
                raise self.err(self.per_id_lines[("petal ramp", id_)],
                               f"a 'petal weight' line for id {id_} (its 'petal ramp' ramps that growth)", "none")
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
            petal_ramps=self.petal_ramps,
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
    "ramp": _Reader.read_ramp,
    "variation": _Reader.read_variation,
    "scheme": _Reader.read_scheme,
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
