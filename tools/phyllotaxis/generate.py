"""One entry point for the ``phyllotaxis`` CLI: parameters in, ``scene.scn`` (+ ``rba/``) out.

Which model runs depends on the parameter file (``formats/phyllotaxis.md``):

- no ``[dynamics]``/``[hierarchy]``: Ridley's static pattern (sec. 5.2) -> ``o:``/``ca:`` placements
  (``ca:`` with per-floret windows by ``[primordia] development_order``, the phase effect);
- ``[dynamics]``: fractionation or segregation (sec. 5.3) -> ``rba:`` placements + ``rba/NNNN.rba``;
- ``[compound]``: two-level pattern of conical heads (sec. 5.4, fig. 5.4) -> ``o:``/``ca:``;
- ``[hierarchy]``: recursive segregation (sec. 5.4) -> static, or dynamic with ``dynamic = true``.

Everything is computed and checked before the first file is written.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from inflo.formats.atomic import frame_name
from inflo.formats.errors import InputError
from inflo.formats.func import read_func
from inflo.formats.rba import RbaFrame, write_rba
from inflo.formats.scn import write_scn

from .compound import compound_pattern, compound_scene
from .development import apply_development_order
from .dynamics import dynamic_scene, simulate, write_frames
from .hierarchy import grow_hierarchy, hierarchy_scene, hierarchy_state
from .params import Params, Primordia
from .ridley import area_function, pattern_scene, static_pattern
from .room import apply_room, fill_room
from .surface import load_curve

__all__ = ["Summary", "generate"]


@dataclass
class Summary:
    """What :func:`generate` wrote."""

    model: str
    florets: int
    frames: int
    scene: Path
    messages: list = field(default_factory=list)
    preview: dict | None = None  # pos, diameter, age of the final pattern (for pictures)


def _func_or_number(spec):
    return read_func(spec) if isinstance(spec, str) else float(spec)


#: the files a run writes in its output folder, as patterns relative to it (a rerun's own earlier
#: files where the folder has no manifest yet)
OUTPUT_FILES = (r"scene\.scn", r"rba/\d+\.rba", r"receptacle\.obj", r"receptacle/frame_\d+\.obj")


def generate(params: Params, out_dir, *, progress=None, header: str | None = None) -> Summary:
    """Run the model the parameters describe and write ``out_dir/scene.scn`` (+ ``out_dir/rba/``).

    Parameters
    ----------
    params : Params
        As returned by :func:`inflo.tools.phyllotaxis.params.read_params`.
    progress : callable, optional
        ``progress(length, label)`` returning a context manager whose object has ``update(n)``
        (e.g. :func:`inflo.tools.common.cli.progress`); used for the RBA frames.
    """
    out = Path(out_dir)
    s, pr = params.surface, params.primordia
    notes = _unused_development_keys(params)
    curve_kw = dict(radius=s.radius, height=s.height, angle=s.angle, samples=s.samples)
    if params.hierarchy is not None:
        if params.receptacle is not None:
            notes.append("[receptacle] is written for single heads (static or dynamic); "
                         "a hierarchy's meristems have none")
        return _hierarchy(params, out, progress, header, notes)
    profile = load_curve(s.curve, **curve_kw)
    if params.dynamics is not None:
        d = params.dynamics
        profiles = [load_curve(c, **curve_kw) for c in d.curves] or [profile]
        pat = simulate(mode=d.mode, frames=d.frames, interval=d.interval,
                       primordium_area=d.primordium_area, inner_area=d.inner_area,
                       outer_area=d.outer_area, inner_growth=_func_or_number(d.inner_growth),
                       outer_growth=_func_or_number(d.outer_growth),
                       primordium_growth=_func_or_number(d.primordium_growth), threshold=d.threshold,
                       divergence=pr.divergence, profiles=profiles, curve_times=d.curve_times,
                       substeps=d.substeps, max_count=d.max_count, close_apex=d.close_apex,
                       apex_taper=d.apex_taper, apex_smallest=d.apex_smallest)
        _check_frames_work("dynamics", d.frames, pat.emergence, params.receptacle)
        ctx = progress(d.frames, "phyllotaxis frames") if progress else _NoBar()
        rec = (params.receptacle, out / "receptacle") if params.receptacle is not None else None
        with ctx as bar:
            state = write_frames(pat, out / "rba", size_factor=pr.size_factor, bar=bar, receptacle=rec)
        scene = dynamic_scene(pat, state, floret_id=pr.floret_id, development_frames=d.development_frames)
        write_scn(out / "scene.scn", scene, header=header)
        preview = {"pos": state["pos"], "diameter": state["scale"][:, 0], "age": d.frames - 1 - pat.emergence}
        return Summary(f"dynamic ({d.mode})", len(pat), d.frames, out / "scene.scn", notes, preview)
    area = area_function(pr.area, profile.length)
    if params.receptacle is not None and params.compound is not None:
        notes.append("[receptacle] is written for single heads (static or dynamic); "
                     "a compound pattern's heads have none")
    elif params.receptacle is not None:
        from inflo.formats.obj import write_obj

        from .receptacle import receptacle_mesh
        out.mkdir(parents=True, exist_ok=True)
        write_obj(out / "receptacle.obj", receptacle_mesh(profile, params.receptacle),
                  header="receptacle (phyllotaxis [receptacle])")
    if params.compound is not None:
        c = params.compound
        comp = compound_pattern(profile, area, head_curve=c.head_curve, head_height=c.head_height,
                                head_fill=c.head_fill, floret_fraction=c.floret_fraction,
                                head_start=c.head_start, divergence=pr.divergence, start=pr.start, count=pr.count,
                                max_count=pr.max_count)
        scene = compound_scene(comp, floret_id=pr.floret_id, size_factor=pr.size_factor,
                               kind=pr.placement, frame_start=pr.frame_start, frame_end=pr.frame_end)
        _static_development(scene, pr)
        out.mkdir(parents=True, exist_ok=True)
        write_scn(out / "scene.scn", scene, header=header)
        preview = {"pos": comp.floret_pos, "diameter": pr.size_factor * 2 * np.sqrt(comp.floret_area / np.pi),
                   "age": comp.floret_head.astype(np.float64)}
        return Summary(f"compound ({len(comp.head_pos)} heads)", len(comp.floret_pos), 0, out / "scene.scn", notes,
                       preview)
    pat = static_pattern(profile, area, divergence=pr.divergence, start=pr.start, count=pr.count,
                         max_count=pr.max_count)
    scene = pattern_scene(pat, floret_id=pr.floret_id, size_factor=pr.size_factor, kind=pr.placement,
                          frame_start=pr.frame_start, frame_end=pr.frame_end)
    _static_development(scene, pr)
    out.mkdir(parents=True, exist_ok=True)
    write_scn(out / "scene.scn", scene, header=header)
    preview = {"pos": pat.pos, "diameter": pr.size_factor * 2 * np.sqrt(pat.area / np.pi),
               "age": np.arange(len(pat.s), dtype=np.float64)}
    return Summary("static", len(pat.s), 0, out / "scene.scn", notes, preview)


def _static_development(scene, pr: Primordia) -> None:
    """The developmental windows of a static scene (``[primordia] development_*``), in place.

    ``development_order`` other than ``none``: every placement becomes ``ca:`` with its window
    by rank (:func:`.development.apply_development_order`); ``none`` with ``development_frames``
    and ``placement = "ca"``: ``frameEnd = frame_start + development_frames``.
    """
    n = pr.development_frames
    if pr.development_order != "none":
        frames = n if n is not None else pr.frame_end - pr.frame_start
        apply_development_order(scene, order=pr.development_order, offset=pr.development_offset,
                                frame_start=pr.frame_start, frames=frames)
    elif n is not None:
        for p in scene.placements:
            if p.kind == "ca":
                p.frame_end = p.frame_start + n


def _unused_development_keys(params: Params) -> list:
    """Warnings for ``[primordia] development_order``/``development_frames`` that the model ignores."""
    pr = params.primordia
    given = [k for k, unset in (("development_order", "none"), ("development_frames", None))
             if getattr(pr, k) != unset]
    dynamic = params.dynamics is not None or (params.hierarchy is not None and params.hierarchy.dynamic)
    if dynamic and given:
        where = "[dynamics]" if params.dynamics is not None else "[hierarchy]"
        return [f"[primordia] {' and '.join(given)} apply to static patterns only and are ignored here "
                f"(a dynamic pattern develops by age: {where} development_frames)"]
    if not dynamic and given == ["development_frames"] and pr.placement != "ca":
        return ["[primordia] development_frames has no effect on o: placements without a development_order "
                "(or placement = \"ca\")"]
    return []


def _hierarchy(params: Params, out: Path, progress, header, notes) -> Summary:
    h_p, pr = params.hierarchy, params.primordia
    h = grow_hierarchy(levels=h_p.levels, frames=h_p.frames, growth_rate=h_p.growth_rate,
                       initial_area=h_p.initial_area, element_area=h_p.element_area,
                       production_threshold=h_p.production_threshold,
                       meristem_threshold=h_p.meristem_threshold, divergence=h_p.divergence,
                       max_count=h_p.max_count)
    final = hierarchy_state(h, h_p.frames, size_factor=pr.size_factor)
    room = _room(final, h_p, h.element_birth[h.florets[final["ids"]]]) if h_p.fill_room else None
    frames = 0
    if h_p.dynamic:
        frames = int(math.floor(h_p.frames)) + 1
        _check_frames_work("hierarchy", frames, h.element_birth[h.florets[final["ids"]]], None)
        rba = out / "rba"
        rba.mkdir(parents=True, exist_ok=True)
        ctx = progress(frames, "phyllotaxis frames") if progress else _NoBar()
        with ctx as bar:
            for f in range(frames):
                st = hierarchy_state(h, float(f), size_factor=pr.size_factor)
                if room is not None:
                    st = apply_room(st, final, *room)
                write_rba(rba / frame_name(f, "", ".rba", 4),
                          RbaFrame(st["ids"], st["pos"], st["scale"], st["up"], st["right"]), fast=True)
                bar.update(1)
    if room is not None:
        final = apply_room(final, final, *room)
    scene = hierarchy_scene(h, final, floret_id=pr.floret_id, dynamic=h_p.dynamic, kind=pr.placement,
                            frame_start=pr.frame_start, frame_end=pr.frame_end,
                            development_frames=h_p.development_frames)
    if not h_p.dynamic:
        _static_development(scene, pr)
    out.mkdir(parents=True, exist_ok=True)
    write_scn(out / "scene.scn", scene, header=header)
    birth = h.element_birth[h.florets[final["ids"]]]
    preview = {"pos": final["pos"], "diameter": final["scale"][:, 0], "age": h_p.frames - birth}
    return Summary(f"hierarchy ({h_p.levels} levels)", len(final["ids"]), frames, out / "scene.scn",
                   notes + list(h.messages), preview)


def _check_frames_work(section: str, frames: int, birth, receptacle) -> None:
    """Refuse, before the first RBA frame is written, a run whose frames x primordia (the rows of
    every RBA file: a primordium is in every frame from its emergence on) exceed
    :data:`~.params.MAX_RBA_ROWS`, or whose receptacle meshes (vertices a frame x frames) do."""
    from .params import MAX_RBA_ROWS

    birth = np.asarray(birth, dtype=np.float64)
    rows = float(np.sum(np.maximum(frames - np.ceil(birth - 1e-9), 0.0)))
    if rows > MAX_RBA_ROWS:
        raise InputError(f"expected at most {MAX_RBA_ROWS} placements over all RBA frames ({section}.frames x the "
                         f"primordia present), found {rows:.4g} ({len(birth)} primordia over {frames} frames); "
                         f"lower {section}.frames or max_count")
    if receptacle is not None:
        from .receptacle import PHYLLARY_VERTICES
        stump = 1 if receptacle.stem_length > 0 else 0
        verts = (receptacle.segments * (receptacle.rings + receptacle.underside_rings + stump)
                 + receptacle.phyllary_rows * receptacle.phyllaries * PHYLLARY_VERTICES) * frames
        if verts > MAX_RBA_ROWS:
            raise InputError(f"expected at most {MAX_RBA_ROWS} receptacle vertices over all frames (segments x "
                             f"(rings + underside_rings, + 1 with a stump), plus the phyllaries' vertices, "
                             f"x {section}.frames), found {verts}")


def _room(final: dict, h_p, birth: np.ndarray) -> tuple:
    """Displacement (f, 3) and diameter factor (f,) of every floret grown into its room
    (``[hierarchy] fill_room``, :mod:`.room`)."""
    pos = final["pos"][:, [0, 2]]
    d = final["scale"][:, 0]
    q, w = fill_room(pos, d, margin=h_p.room_margin, iterations=h_p.room_iterations,
                     scale_range=tuple(h_p.room_scale), birth=birth, weight=h_p.room_weight,
                     outline=h_p.room_outline)
    shift = np.zeros_like(final["pos"])
    shift[:, [0, 2]] = q - pos
    return shift, w / d


class _NoBar:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def update(self, n):
        pass
