"""Golden-file comparison: a tolerance-aware diff of inflo's stage formats, one readable report per file.

Structure is compared exactly (vertex and face counts, face lists, polylines, groups and materials,
SCN/RBA ids, placement kinds, floret types and material ids, organ names and grids, integer CSV
columns); coordinates and other numbers within a stated :class:`Tolerance`; timing columns are
ignored. Each file gets a :class:`FileDiff`: what differs, the first few instances, counts of the
rest; :func:`format_report` turns a list of them into the report the CLI prints.

A golden kept gzip-compressed (``name.gz``) is compared as the file it holds. The species side
(manifests, builds, refresh) is :mod:`inflo.tools.golden.species`; the doc is
``tests/golden/README.md``.
"""
from __future__ import annotations

import csv
import dataclasses
import fnmatch
import gzip
import json
import math
import re
import shutil
import tempfile
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = [
    "Tolerance",
    "DEFAULT",
    "Finding",
    "FileDiff",
    "COMPARATORS",
    "diff_files",
    "diff_trees",
    "format_report",
    "natural_key",
    "tree_files",
    "shorten",
    "MAX_DETAILS",
    "MAX_FINDINGS",
    "TIMING_COLUMNS",
    "GZ",
]

MAX_DETAILS = 5
"""Instances listed under each finding; the rest are counted."""
MAX_FINDINGS = 8
"""Findings listed per file; the rest are counted."""

TIMING_COLUMNS = ("t_*", "*_s", "*_ms", "*seconds*", "*elapsed*", "wall*", "time_*", "*_time")
"""CSV columns ignored by default: wall-clock timings differ from run to run."""

GZ = ".gz"
"""Suffix of a golden kept gzip-compressed (``compress = true`` in its ``[[golden]]`` table): it is
compared as the file it holds."""


def _gunzip_to(golden: Path, folder: Path) -> Path:
    """Decompress ``x.obj.gz`` to ``folder/x.obj`` (the comparators go by the inner suffix)."""
    out = folder / golden.name[: -len(GZ)]
    with gzip.open(golden, "rb") as src, open(out, "wb") as dst:
        shutil.copyfileobj(src, dst)
    return out


# --------------------------------------------------------------------------------------------------
# Tolerances
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Tolerance:
    """How far a number may move before it counts as a difference.

    coord_rel, coord_abs
        Coordinates (OBJ vertices, SCN/RBA positions and group centres, floret control points):
        the Euclidean distance a point moved must be <= max(coord_abs, coord_rel * size), where
        size is the scene size: the bounding-box diagonal of the golden file's points.
    num_rel, num_abs
        Any other number (scales, up/right vectors, angles, times, float CSV cells, numbers in
        text, TOML or JSON): |found - golden| <= num_abs + num_rel * |golden|, or at most one unit
        in the last decimal place the golden text was written with, whichever is larger.
        Integers (counts, ids, frame numbers) are exact unless ``int_rel`` is set.
    normal_abs
        OBJ ``vn`` normals and vertex colours, per component (derived quantities).
    int_rel
        Integers in CSV cells and text (counts of candidates, collisions, sweeps) may differ by
        ``int_rel * |golden|``, rounded down: 0 by default (exact), and a zero stays exactly zero
        (intersecting pairs, florets missing). Only the :data:`CHAOTIC` stages set it.
    """

    coord_rel: float = 1e-5
    coord_abs: float = 2e-6
    num_rel: float = 1e-5
    num_abs: float = 2e-6
    normal_abs: float = 1e-3
    int_rel: float = 0.0

    def updated(self, mapping) -> Tolerance:
        """A copy with the keys of ``mapping`` (a manifest ``tolerance`` table) replaced."""
        if not mapping:
            return self
        names = {f.name for f in dataclasses.fields(self)}
        bad = sorted(set(mapping) - names)
        if bad:
            raise ValueError(f"unknown tolerance key(s) {', '.join(bad)}; known: {', '.join(sorted(names))}")
        return dataclasses.replace(self, **{k: float(v) for k, v in mapping.items()})

    def coord(self, size: float) -> float:
        return max(self.coord_abs, self.coord_rel * size)

    def num(self, golden: float, written_unit: float = 0.0) -> float:
        return max(self.num_abs + self.num_rel * abs(golden), written_unit)


DEFAULT = Tolerance()

CHAOTIC = Tolerance(coord_rel=1e-2, coord_abs=2e-6, num_rel=0.1, num_abs=2e-3, normal_abs=0.5, int_rel=0.25)
"""The tolerances of a ``chaotic = true`` manifest entry: a stage whose crowded frames grow a
last-bit difference (another libm, numpy or compiler) into visible ones, fccompose's and
petal-grow's collision response and what is computed from their frames (tests/golden/README.md,
"Chaotic stages"). Its structure is still compared exactly (vertex and face counts, faces, groups,
materials, column names, words, zeros); coordinates within 1 % of the scene size, numbers within
10 %, counts within 25 %: three times what the draft heads built on an Intel Xeon needed against
goldens made on an AMD EPYC before the fixed-order linear algebra (a dyssodia vertex 0.26 % of its scene apart, a
check report's figure 4 % off). What must hold of those frames (no intersecting pair, every edge
within its stretch bounds, every floret present, the phase effect) the species' check scripts
assert in every build, and ``tests/test_portable.py`` holds the stages to the same bytes under
other processor kernels."""


def _unit_of(text: str) -> float:
    """One unit in the last decimal place of a number as written (``0.0335`` -> 1e-4)."""
    m = re.fullmatch(r"[+-]?(\d*)(?:\.(\d*))?(?:[eE]([+-]?\d+))?", text.strip())
    if not m:
        return 0.0
    decimals = len(m.group(2) or "")
    exp = int(m.group(3) or 0)
    return 10.0 ** (exp - decimals)


# --------------------------------------------------------------------------------------------------
# Reports
# --------------------------------------------------------------------------------------------------


@dataclass
class Finding:
    """One kind of difference in a file: a summary line and its first few instances."""

    summary: str
    details: list = field(default_factory=list)
    more: int = 0  # instances not listed

    def lines(self) -> list[str]:
        out = [self.summary] + [f"    {d}" for d in self.details]
        if self.more:
            out.append(f"    ... and {self.more:,} more")
        return out


@dataclass
class FileDiff:
    """The comparison of one file: ``status`` is ``same`` (byte-identical), ``ok`` (within
    tolerance), ``differs``, ``missing`` (the golden has it, the build not), ``extra`` (the
    build has a file the golden sequence has not), ``no golden`` or ``unreadable``."""

    name: str
    status: str = "same"
    findings: list = field(default_factory=list)
    notes: list = field(default_factory=list)  # not failures (e.g. ignored columns, largest move)

    @property
    def ok(self) -> bool:
        return self.status in ("same", "ok")

    def add(self, summary: str, details=(), total: int | None = None) -> None:
        """Record a difference; ``details`` beyond :data:`MAX_DETAILS` are counted, not listed
        (``total``: how many instances there are when ``details`` holds only the first ones)."""
        details = list(details)
        n = len(details) if total is None else total
        shown = details[:MAX_DETAILS]
        self.findings.append(Finding(summary, shown, max(0, n - len(shown))))
        if self.status in ("same", "ok"):
            self.status = "differs"

    def format(self, max_findings: int = MAX_FINDINGS, notes: bool = False) -> str:
        if self.ok:
            text = f"{self.name}: {'identical' if self.status == 'same' else 'within tolerance'}"
            if notes and self.notes:
                text += " (" + "; ".join(self.notes) + ")"
            return text
        out = []
        for f in self.findings[:max_findings]:
            first, *rest = f.lines()
            out.append(f"{self.name}: {first}")
            out.extend(rest)
        if len(self.findings) > max_findings:
            out.append(f"{self.name}: ... and {len(self.findings) - max_findings} more kinds of difference")
        if notes and self.notes:
            out.append(f"    ({'; '.join(self.notes)})")
        return "\n".join(out)


def _first(indices, k: int = MAX_DETAILS):
    """The first ``k`` of an index array as a list, and the total count."""
    idx = np.asarray(indices).ravel()
    return idx[:k].tolist(), int(idx.size)


def _xyz(p) -> str:
    return "(" + " ".join(f"{float(c):.6f}" for c in p) + ")"


def _g(x: float) -> str:
    return f"{x:.2g}"


def shorten(value, width: int = 60) -> str:
    """``value`` (a string, else its repr) cut to ``width`` characters with ``...``."""
    text = value if isinstance(value, str) else repr(value)
    return text if len(text) <= width else text[: width - 3] + "..."


def _names(names) -> str:
    names = list(names)
    shown = ", ".join(repr(n) for n in names[:6])
    return f"[{shown}{', ...' if len(names) > 6 else ''}] ({len(names)})"


def _scene_size(points) -> float:
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if len(p) == 0:
        return 0.0
    return float(np.linalg.norm(p.max(axis=0) - p.min(axis=0)))


# --------------------------------------------------------------------------------------------------
# Comparators, one per format; each fills a FileDiff
# --------------------------------------------------------------------------------------------------


def _compare_points(d: FileDiff, what: str, golden, found, tol: Tolerance, size: float,
                    label=lambda i: str(i + 1)) -> None:
    """Points (n, 3) of equal count: the ones that moved beyond the coordinate tolerance."""
    golden = np.asarray(golden, np.float64).reshape(-1, 3)
    found = np.asarray(found, np.float64).reshape(-1, 3)
    if len(golden) == 0:
        return
    t = tol.coord(size)
    dist = np.linalg.norm(found - golden, axis=1)
    worst = int(np.argmax(dist))
    bad = np.nonzero(dist > t)[0]
    why = (f"tolerance {_g(t)} = {tol.coord_rel:g} x scene size {size:.4g}" if t > tol.coord_abs
           else f"tolerance {_g(t)}")
    if bad.size:
        first, n = _first(bad)
        whats = what[:-2] + "ices" if what.endswith("vertex") else what + "s"
        d.add(f"{n:,} of {len(golden):,} {whats} moved beyond {why}; largest {_g(dist[worst])} at "
              f"{what} {label(worst)}",
              [f"{what} {label(i)} moved {_g(dist[i])}: golden {_xyz(golden[i])}, found {_xyz(found[i])}"
               for i in first], n)
    elif dist[worst] > 0:
        d.notes.append(f"largest {what} move {_g(dist[worst])} at {what} {label(worst)} ({why})")


def _compare_numbers(d: FileDiff, what: str, golden, found, tol: Tolerance, labels=None,
                     abs_tol: float | None = None) -> None:
    """Arrays of the same shape: entries beyond the number tolerance (or ``abs_tol``)."""
    g = np.asarray(golden, np.float64)
    f = np.asarray(found, np.float64)
    if g.size == 0:
        return
    t = np.full(g.shape, abs_tol) if abs_tol is not None else tol.num_abs + tol.num_rel * np.abs(g)
    dev = np.abs(f - g)
    bad = np.nonzero((dev > t).reshape(len(g), -1).any(axis=1))[0] if g.ndim > 1 else np.nonzero(dev > t)[0]
    if bad.size:
        first, n = _first(bad)
        lab = labels or (lambda i: str(i))
        fmt = (lambda v: _xyz(v)) if g.ndim > 1 else (lambda v: repr(float(v)))
        d.add(f"{what} differs beyond tolerance in {n:,} of {len(g):,} entries",
              [f"{lab(i)}: golden {fmt(g[i])}, found {fmt(f[i])}" for i in first], n)


def _compare_obj(d: FileDiff, golden: Path, found: Path, tol: Tolerance, opts: dict) -> None:
    from inflo.formats.obj import read_obj

    g, f = read_obj(golden), read_obj(found)
    # vertices: the count is the identity of every vertex; coordinates within tolerance
    if g.n_vertices != f.n_vertices:
        d.add(f"vertex count: golden {g.n_vertices:,}, found {f.n_vertices:,}")
    else:
        _compare_points(d, "vertex", g.vertices, f.vertices, tol, _scene_size(g.vertices))
    # faces: exact, in order (1-based vertex numbers, as in the f lines)
    if g.n_faces != f.n_faces:
        d.add(f"face count: golden {g.n_faces:,}, found {f.n_faces:,}")
    m = min(g.n_faces, f.n_faces)
    neq = np.nonzero(np.any(g.faces[:m] != f.faces[:m], axis=1))[0]
    if neq.size:
        i = int(neq[0])
        tri = lambda a: " ".join(str(int(v) + 1) for v in a)
        first, n = _first(neq[1:])
        d.add(f"faces differ from face {i + 1}: golden {tri(g.faces[i])}, found {tri(f.faces[i])} "
              f"({neq.size:,} of {m:,} faces differ)",
              [f"face {j + 1}: golden {tri(g.faces[j])}, found {tri(f.faces[j])}" for j in first], n)
    # polylines: exact
    if len(g.lines) != len(f.lines):
        d.add(f"polyline count: golden {len(g.lines):,}, found {len(f.lines):,}")
    bad = [k for k, (a, b) in enumerate(zip(g.lines, f.lines)) if not np.array_equal(a, b)]
    if bad:
        pl = lambda a: shorten(" ".join(str(int(v) + 1) for v in a), 50)
        d.add(f"{len(bad):,} polylines differ",
              [f"polyline {k + 1}: golden {pl(g.lines[k])}, found {pl(f.lines[k])}" for k in bad])
    # groups and materials: the names, and which faces they hold
    for what, gn, fn, gi, fi in (("group", g.groups, f.groups, g.face_group, f.face_group),
                                 ("material", g.materials, f.materials, g.face_material, f.face_material)):
        if list(gn) != list(fn):
            d.add(f"{what}s: golden {_names(gn)}, found {_names(fn)}")
        if m and (gi is not None or fi is not None):
            ga = _per_face_names(gn, gi, g.n_faces)[:m]
            fa = _per_face_names(fn, fi, f.n_faces)[:m]
            neq = np.nonzero(ga != fa)[0]
            if neq.size:
                first, n = _first(neq)
                d.add(f"{n:,} faces are in another {what}, from face {first[0] + 1}",
                      [f"face {j + 1}: golden {ga[j]!r}, found {fa[j]!r}" for j in first], n)
    # derived per-vertex data
    for what, ga, fa in (("normals", g.normals, f.normals), ("vertex colours", g.vertex_colors, f.vertex_colors)):
        if (ga is None) != (fa is None):
            d.add(f"{what}: golden {'has' if ga is not None else 'has no'} {what}, found "
                  f"{'has' if fa is not None else 'has no'}")
        elif ga is not None and ga.shape == fa.shape:
            _compare_numbers(d, what, ga, fa, tol, labels=lambda i: f"vertex {i + 1}", abs_tol=tol.normal_abs)


def _per_face_names(names, index, n) -> np.ndarray:
    if index is None:
        return np.full(n, "", dtype=object)
    table = np.array(list(names) + [""], dtype=object)  # -1 -> ""
    return table[np.asarray(index)]


def _compare_scn(d: FileDiff, golden: Path, found: Path, tol: Tolerance, opts: dict) -> None:
    from inflo.formats.scn import read_scn

    g, f = read_scn(golden), read_scn(found)
    ng, nf = len(g.placements), len(f.placements)
    if ng != nf:
        d.add(f"placement count: golden {ng:,}, found {nf:,}")
    n = min(ng, nf)
    # structure, exactly: kind, id, material, group, type, frames, extension lines
    for attr, what in (("kind", "placement kind"), ("id", "id"), ("material", "mtl id"), ("group", "group"),
                       ("type", "floret type"), ("frame_start", "frameStart"), ("frame_end", "frameEnd"),
                       ("extra", "extension lines")):
        bad = [k for k in range(n) if getattr(g.placements[k], attr) != getattr(f.placements[k], attr)]
        if bad:
            d.add(f"{what} differs at {len(bad):,} of {n:,} placements, from placement {bad[0]}",
                  [f"placement {k}: golden {getattr(g.placements[k], attr)!r}, found "
                   f"{getattr(f.placements[k], attr)!r}" for k in bad])
    if g.extra != f.extra:
        d.add(f"header extension lines: golden {shorten(g.extra)}, found {shorten(f.extra)}")
    # groups: ids and parents exact, centres as coordinates
    if sorted(g.groups) != sorted(f.groups):
        d.add(f"group ids: golden {sorted(g.groups)[:10]}, found {sorted(f.groups)[:10]}")
    common = sorted(set(g.groups) & set(f.groups))
    bad = [k for k in common if g.groups[k].parent != f.groups[k].parent]
    if bad:
        d.add(f"group parents differ for {len(bad)} groups",
              [f"group {k}: golden parent {g.groups[k].parent}, found {f.groups[k].parent}" for k in bad])
    gp = np.array([p.pos for p in g.placements]).reshape(-1, 3)
    gc = np.array([g.groups[k].centre for k in common]).reshape(-1, 3)
    size = _scene_size(np.vstack([gp, gc]))
    if common:
        _compare_points(d, "group centre", gc, [f.groups[k].centre for k in common], tol, size,
                        label=lambda i: str(common[i]))
    if n == 0:
        return
    _compare_points(d, "placement position", gp[:n], [p.pos for p in f.placements[:n]], tol, size,
                    label=lambda i: str(i))
    for attr in ("scale", "up", "right"):
        _compare_numbers(d, attr, [getattr(p, attr) for p in g.placements[:n]],
                         [getattr(p, attr) for p in f.placements[:n]], tol, labels=lambda i: f"placement {i}")
    for attr in ("translate", "axis", "interpolation", "angle", "emergence"):
        pairs = [(k, getattr(g.placements[k], attr), getattr(f.placements[k], attr)) for k in range(n)]
        none = [k for k, a, b in pairs if (a is None) != (b is None)]
        if none:
            d.add(f"{attr} given in one file only at {len(none)} placements",
                  [f"placement {k}: golden {pairs[k][1]!r}, found {pairs[k][2]!r}" for k in none])
        both = [(k, a, b) for k, a, b in pairs if a is not None and b is not None]
        if both:
            ks = [k for k, _, _ in both]
            _compare_numbers(d, attr, [a for _, a, _ in both], [b for _, _, b in both], tol,
                             labels=lambda i, ks=ks: f"placement {ks[i]}")


def _compare_rba(d: FileDiff, golden: Path, found: Path, tol: Tolerance, opts: dict) -> None:
    from inflo.formats.rba import read_rba

    g, f = read_rba(golden), read_rba(found)
    if len(g) != len(f):
        d.add(f"floret count: golden {len(g):,}, found {len(f):,}")
    n = min(len(g), len(f))
    neq = np.nonzero(g.ids[:n] != f.ids[:n])[0]
    if neq.size:
        first, cnt = _first(neq)
        d.add(f"ids differ at {cnt:,} of {n:,} rows, from row {first[0] + 1}",
              [f"row {k + 1}: golden id {g.ids[k]}, found {f.ids[k]}" for k in first], cnt)
        return  # rows are different florets: their numbers are not comparable
    if n == 0:
        return
    size = max(_scene_size(g.pos), float(np.abs(g.scale).max()))
    _compare_points(d, "floret position", g.pos[:n], f.pos[:n], tol, size,
                    label=lambda i: f"id {g.ids[i]} (row {i + 1})")
    for attr in ("scale", "up", "right"):
        _compare_numbers(d, attr, getattr(g, attr)[:n], getattr(f, attr)[:n], tol,
                         labels=lambda i: f"id {g.ids[i]} (row {i + 1})")


def _compare_floret(d: FileDiff, golden: Path, found: Path, tol: Tolerance, opts: dict) -> None:
    from inflo.formats.floret import read_floret

    g, f = read_floret(golden), read_floret(found)
    if g.name != f.name:
        d.add(f"floret name: golden {g.name!r}, found {f.name!r}")
    if (g.key_time is None) != (f.key_time is None):
        d.add(f"time: golden {g.key_time!r}, found {f.key_time!r}")
    elif g.key_time is not None and abs(g.key_time - f.key_time) > tol.num(g.key_time):
        d.add(f"time: golden {g.key_time!r}, found {f.key_time!r}")
    gn, fn = [o.name for o in g.organs], [o.name for o in f.organs]
    if gn != fn:
        d.add(f"organs: golden {_names(gn)}, found {_names(fn)}")
    pts = [o.control_points.reshape(-1, 3) for o in g.organs]
    size = _scene_size(np.vstack(pts)) if pts else 0.0
    for go in g.organs:
        if go.name not in fn:
            continue
        fo = f.organ(go.name)
        for attr, what in (("material", "material id"), ("degree_u", "degree u"), ("degree_v", "degree v"),
                           ("symmetry_n", "symmetry n"), ("bilateral", "bilateral"), ("fused", "fused")):
            if getattr(go, attr) != getattr(fo, attr):
                d.add(f"organ {go.name!r} {what}: golden {getattr(go, attr)!r}, found {getattr(fo, attr)!r}")
        for attr, what in (("symmetry_phase_deg", "symmetry phase"), ("tilt_deg", "tilt")):
            a, b = getattr(go, attr), getattr(fo, attr)
            if abs(a - b) > tol.num(a):
                d.add(f"organ {go.name!r} {what}: golden {a!r}, found {b!r}")
        for attr, what in (("lambda_", "lambda"), ("eta", "eta")):
            a, b = getattr(go, attr), getattr(fo, attr)
            if isinstance(a, float) and isinstance(b, float):
                if abs(a - b) > tol.num(a):
                    d.add(f"organ {go.name!r} {what}: golden {a!r}, found {b!r}")
            elif isinstance(a, Path) and isinstance(b, Path):
                if a.name != b.name:  # the file's own name; folders differ between copies
                    d.add(f"organ {go.name!r} {what} file: golden {a.name}, found {b.name}")
            elif a != b:
                d.add(f"organ {go.name!r} {what}: golden {shorten(str(a))}, found {shorten(str(b))}")
        gs, fs = go.control_points.shape, fo.control_points.shape
        if gs != fs:
            d.add(f"organ {go.name!r} grid: golden {gs[1]} x {gs[0]}, found {fs[1]} x {fs[0]}")
            continue
        nu = gs[1]
        _compare_points(d, f"organ {go.name!r} control point", go.control_points.reshape(-1, 3),
                        fo.control_points.reshape(-1, 3), tol, size,
                        label=lambda i, nu=nu: f"row {i // nu} column {i % nu}")


_INT = re.compile(r"[+-]?\d+")
_FLOAT = re.compile(r"[+-]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?|[+-]?(?:inf|nan)", re.I)


def _cell_differs(a: str, b: str, tol: Tolerance, abs_tol: float | None = None) -> bool:
    """Words exactly, integers exactly or within ``tol.int_rel``, other numbers within
    tolerance (or ``abs_tol``)."""
    a, b = a.strip(), b.strip()
    if a == b:
        return False
    if _INT.fullmatch(a):
        return not (tol.int_rel > 0 and _INT.fullmatch(b) and abs(int(a) - int(b)) <= int(tol.int_rel * abs(int(a))))
    if not _FLOAT.fullmatch(a) or not _FLOAT.fullmatch(b):
        return True
    x, y = float(a), float(b)
    if math.isnan(x) or math.isnan(y) or math.isinf(x) or math.isinf(y):
        return not (x == y or (math.isnan(x) and math.isnan(y)))
    t = abs_tol if abs_tol is not None else tol.num(x, _unit_of(a))
    return abs(x - y) > t


def _compare_csv(d: FileDiff, golden: Path, found: Path, tol: Tolerance, opts: dict) -> None:
    with open(golden, newline="") as fh:
        g = list(csv.reader(fh))
    with open(found, newline="") as fh:
        f = list(csv.reader(fh))
    if not g:
        if f:
            d.add(f"golden is empty, found {len(f)} rows")
        return
    gh, fh_ = g[0], (f[0] if f else [])
    if gh != fh_:
        new = [c for c in fh_ if c not in gh]
        gone = [c for c in gh if c not in fh_]
        what = "; ".join(x for x in (f"new {', '.join(new)}" if new else "",
                                      f"gone {', '.join(gone)}" if gone else "") if x) or "reordered"
        d.add(f"columns differ ({what}): golden {_names(gh)}, found {_names(fh_)}")
        return
    ignore_pat = list(opts.get("ignore_columns", TIMING_COLUMNS))
    exact = set(opts.get("exact_columns", ()))
    col_tol = dict(opts.get("column_tolerance", {}))
    for name in list(exact) + list(col_tol):
        if name not in gh:
            raise ValueError(f"{golden.name}: no column {name!r} (columns: {', '.join(gh)})")
    ignored = [c for c in gh if c not in exact and c not in col_tol
               and any(fnmatch.fnmatchcase(c, p) for p in ignore_pat)]
    if ignored:
        d.notes.append(f"ignored columns {', '.join(ignored)}")
    gr, fr = g[1:], f[1:]
    if len(gr) != len(fr):
        d.add(f"row count: golden {len(gr):,}, found {len(fr):,}")
    n = min(len(gr), len(fr))
    key = gh[0]
    for c, name in enumerate(gh):
        if name in ignored:
            continue
        bad = []
        for r in range(n):
            a = gr[r][c] if c < len(gr[r]) else ""
            b = fr[r][c] if c < len(fr[r]) else ""
            if name in exact:
                differs = a.strip() != b.strip()
            else:
                differs = _cell_differs(a, b, tol, col_tol.get(name))
            if differs:
                bad.append((r, a, b))
        if bad:
            d.add(f"column {name} differs in {len(bad):,} of {n:,} rows, from row {bad[0][0] + 1} "
                  f"({key} {gr[bad[0][0]][0]})",
                  [f"row {r + 1} ({key} {gr[r][0]}): golden {a!r}, found {b!r}" for r, a, b in bad])


_SPLIT = re.compile(r"([+-]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?)")


def _compare_text(d: FileDiff, golden: Path, found: Path, tol: Tolerance, opts: dict) -> None:
    """Line by line; words exactly (runs of blanks as one), numbers within tolerance."""
    g = golden.read_text().splitlines()
    f = found.read_text().splitlines()
    if len(g) != len(f):
        d.add(f"line count: golden {len(g):,}, found {len(f):,}")
    bad = []
    for k, (a, b) in enumerate(zip(g, f)):
        if a == b:
            continue
        pa, pb = _SPLIT.split(a), _SPLIT.split(b)
        if len(pa) != len(pb):
            bad.append(k)
            continue
        for i, (x, y) in enumerate(zip(pa, pb)):
            if i % 2 == 0:
                if " ".join(x.split()) != " ".join(y.split()):
                    bad.append(k)
                    break
            elif _cell_differs(x, y, tol):
                bad.append(k)
                break
    if bad:
        d.add(f"{len(bad):,} lines differ, from line {bad[0] + 1}",
              [f"line {k + 1}: golden {shorten(g[k].strip(), 70)!r}, found {shorten(f[k].strip(), 70)!r}"
               for k in bad])


def _walk(d: FileDiff, path: str, a, b, tol: Tolerance, bad: list) -> None:
    """Recursive comparison of parsed TOML/JSON values."""
    if isinstance(a, dict) and isinstance(b, dict):
        if list(a) != list(b) and sorted(a) != sorted(b):
            bad.append(f"{path or '(top)'}: keys golden {shorten(sorted(a))}, found {shorten(sorted(b))}")
        for k in a:
            if k in b:
                _walk(d, f"{path}.{k}" if path else str(k), a[k], b[k], tol, bad)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            bad.append(f"{path}: length golden {len(a)}, found {len(b)}")
        for i, (x, y) in enumerate(zip(a, b)):
            _walk(d, f"{path}[{i}]", x, y, tol, bad)
    elif (isinstance(a, float) or isinstance(b, float)) and isinstance(a, (int, float)) \
            and isinstance(b, (int, float)) and not isinstance(a, bool) and not isinstance(b, bool):
        if abs(a - b) > tol.num(a) and not (math.isnan(a) and math.isnan(b)):
            bad.append(f"{path}: golden {a!r}, found {b!r}")
    elif type(a) is not type(b) or a != b:
        bad.append(f"{path}: golden {shorten(a)}, found {shorten(b)}")


def _compare_tree_value(d: FileDiff, golden: Path, found: Path, tol: Tolerance, opts: dict) -> None:
    if golden.suffix.lower() == ".json":
        a, b = json.loads(golden.read_text()), json.loads(found.read_text())
    else:
        with open(golden, "rb") as fh:
            a = tomllib.load(fh)
        with open(found, "rb") as fh:
            b = tomllib.load(fh)
    ignore = set(opts.get("ignore_keys", ()))
    if isinstance(a, dict) and isinstance(b, dict):
        a = {k: v for k, v in a.items() if k not in ignore}
        b = {k: v for k, v in b.items() if k not in ignore}
    bad: list = []
    _walk(d, "", a, b, tol, bad)
    if bad:
        d.add(f"{len(bad):,} values differ", bad)


def _compare_npy(d: FileDiff, golden: Path, found: Path, tol: Tolerance, opts: dict) -> None:
    a, b = np.load(golden, allow_pickle=False), np.load(found, allow_pickle=False)
    if a.shape != b.shape or a.dtype != b.dtype:
        d.add(f"array: golden {a.dtype} {a.shape}, found {b.dtype} {b.shape}")
    elif a.dtype.kind in "fc":
        rows = (lambda x: x.reshape(x.shape[0], -1) if x.ndim else x.reshape(1, 1))
        _compare_numbers(d, "array", rows(a), rows(b), tol, labels=lambda i: f"row {i}")
    elif not np.array_equal(a, b):
        bad = np.nonzero(a.reshape(len(a), -1) != b.reshape(len(b), -1))[0] if a.ndim else np.array([0])
        first, n = _first(np.unique(bad))
        d.add(f"array rows differ: {n:,}", [f"row {i}" for i in first], n)


def _compare_bytes(d: FileDiff, golden: Path, found: Path, tol: Tolerance, opts: dict) -> None:
    d.add(f"binary files differ (golden {golden.stat().st_size:,} bytes, found {found.stat().st_size:,})")


COMPARATORS = {
    ".obj": _compare_obj,
    ".scn": _compare_scn,
    ".rba": _compare_rba,
    ".floret": _compare_floret,
    ".csv": _compare_csv,
    ".toml": _compare_tree_value,
    ".json": _compare_tree_value,
    ".npy": _compare_npy,
    ".png": _compare_bytes,
    ".gif": _compare_bytes,
    ".mp4": _compare_bytes,
}
"""suffix -> comparator(FileDiff, golden, found, Tolerance, options); anything else is text
(words exact, numbers within tolerance), or bytes when it is not UTF-8."""


def diff_files(golden, found, name: str | None = None, tol: Tolerance = DEFAULT,
               options: dict | None = None) -> FileDiff:
    """Compare the file ``found`` with ``golden`` by the rules of its format (its suffix).

    A missing ``found`` gives status ``missing``, a missing golden ``no golden``, a file that its
    reader rejects ``unreadable`` (with the reader's one-line error).
    """
    golden, found = Path(golden), Path(found)
    if golden.name.endswith(GZ) and not found.name.endswith(GZ) and golden.is_file():
        with tempfile.TemporaryDirectory(prefix="inflo-golden-") as tmp:
            try:
                inner = _gunzip_to(golden, Path(tmp))
            except (OSError, EOFError) as exc:
                d = FileDiff(name or found.name, "unreadable")
                d.findings.append(Finding(f"cannot compare: {golden}: {exc}"))
                return d
            return diff_files(inner, found, name, tol, options)
    d = FileDiff(name or found.name)
    if not golden.is_file():
        d.status = "no golden"
        d.findings.append(Finding(f"no golden copy at {golden} (refresh the goldens)"))
        return d
    if not found.is_file():
        d.status = "missing"
        d.findings.append(Finding(f"missing file (golden has it: {found} does not exist)"))
        return d
    gb, fb = golden.read_bytes(), found.read_bytes()
    if gb == fb:
        return d
    d.status = "ok"
    comparator = COMPARATORS.get(golden.suffix.lower())
    if comparator is None:
        try:
            gb.decode("utf-8"), fb.decode("utf-8")
            comparator = _compare_text
        except UnicodeDecodeError:
            comparator = _compare_bytes
    try:
        comparator(d, golden, found, tol, options or {})
    except ValueError as exc:  # FormatError/InputError are ValueErrors; a bad manifest option too
        d.status = "unreadable"
        d.findings.append(Finding(f"cannot compare: {exc}"))
    except Exception as exc:
        d.status = "unreadable"
        d.findings.append(Finding(f"cannot compare: {type(exc).__name__}: {exc}"))
    return d


def natural_key(name: str):
    """Sort key that orders the numbers in a name by value (``frame_2`` before ``frame_10``)."""
    return [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", name)]


def tree_files(root: Path) -> list[str]:
    """Every file below ``root`` as a relative POSIX path, in natural order."""
    return sorted((p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file()), key=natural_key)


def diff_trees(golden_dir, found_dir, tol: Tolerance = DEFAULT, names=None) -> list[FileDiff]:
    """Compare two folders file by file (``names``: relative paths; default every file of both,
    reported as ``missing``/``extra`` where only one has it)."""
    golden_dir, found_dir = Path(golden_dir), Path(found_dir)
    out = []
    if names is None:
        gn, fn = tree_files(golden_dir), tree_files(found_dir)
        for name in sorted(set(gn) | set(fn), key=natural_key):
            if name not in gn:
                d = FileDiff(name, "extra")
                d.findings.append(Finding(f"extra file (not in {golden_dir})"))
                out.append(d)
            else:
                out.append(diff_files(golden_dir / name, found_dir / name, name, tol))
    else:
        out = [diff_files(golden_dir / n, found_dir / n, n, tol) for n in names]
    return out


def format_report(diffs, title: str = "", verbose: bool = False) -> str:
    """A summary line (files compared, counts by status) and the findings of every file that is
    not ok (every file with ``verbose``); a run of files with the same kinds of difference is
    shown once."""
    counts: dict[str, int] = {}
    for d in diffs:
        counts[d.status] = counts.get(d.status, 0) + 1
    order = ("same", "ok", "differs", "missing", "extra", "no golden", "unreadable")
    words = {"same": "identical", "ok": "within tolerance", "differs": "differ"}
    summary = ", ".join(f"{counts[s]} {words.get(s, s)}" for s in order if counts.get(s))
    lines = [f"{title}{': ' if title else ''}{len(diffs)} files, {summary or 'nothing compared'}"]
    # a run of files with the same differences (e.g. every frame of a sequence) is shown once
    prev, run = None, []

    def flush():
        if run:
            span = run[0] if len(run) == 1 else f"{run[0]} ... {run[-1]}"
            lines.append(f"  ... and {len(run)} more file{'s' if len(run) > 1 else ''} with the same "
                         f"kinds of difference: {span}")
            run.clear()

    for d in diffs:
        if d.ok and not verbose:
            continue
        sig = tuple(f.summary.split(" at ")[0].split(", from ")[0] for f in d.findings) \
            if d.status == "differs" else None
        if sig is not None and sig == prev:
            run.append(d.name)
            continue
        flush()
        lines.extend("  " + line for line in d.format(notes=verbose).splitlines())
        prev = sig
    flush()
    return "\n".join(lines)
