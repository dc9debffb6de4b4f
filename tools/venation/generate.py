"""``venation``'s library entry: parameters in, a finished pattern and its files out.

:func:`run_venation` runs the simulation (:mod:`.simulate`) for checked parameters and their inputs
(:mod:`.params`), computes widths and orders (:mod:`.graph`), and writes (formats/venation.md):

- ``veins.obj`` (the graph as ``l`` polylines) and ``veins.widths`` (a width per vertex);
- ``blade.obj`` + ``blade.mtl`` (the blade as a triangle mesh with uv) and ``texture.png``;
- ``frames/`` with ``output.frame_step`` > 0: ``veins_NNNN.obj``/``.widths`` and ``blade_NNNN.obj``
  (the margin) every N iterations, ``texture_NNNN.png`` with ``output.frame_textures``.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from inflo.formats.atomic import frame_name

from .graph import cycle_rank, elongation_widths, refine_veins, strahler_orders, vein_widths
from .output import (
    TextureStyle,
    render_texture,
    save_png,
    stale_frames,
    texture_box,
    write_blade_mesh,
    write_events,
    write_graph,
    write_margin,
    write_widths,
)
from .params import Inputs, Params, frame_limit_error, frames_allowed
from .simulate import SimParams, Snapshot, VenationResult, simulate

__all__ = ["run_venation", "VenationRun", "sim_params", "texture_style", "summary", "finish_graph"]


@dataclass
class VenationRun:
    """A run's result and what was written."""

    result: VenationResult
    widths: np.ndarray
    orders: np.ndarray
    loops: int
    written: list
    mesh: tuple  # (vertices, triangles) of blade.obj
    header: str
    simulated_nodes: int = 0  # before the refinement of sec. 5.2.6


def sim_params(p: Params, inputs: Inputs, seed: int | None = None) -> SimParams:
    """The simulation's parameters from the file's."""
    return SimParams(pattern=p.veins.pattern, neighbourhood=p.veins.neighbourhood, step=p.veins.step,
                     kill_distance=p.veins.kill_distance, birth_source=p.sources.birth_source,
                     birth_vein=p.sources.birth_vein, darts=p.sources.darts,
                     roots=tuple(map(tuple, inputs.roots.tolist())), settle=p.sources.settle,
                     region=_region(p), blind_after=p.veins.blind_after, blind_gap=p.veins.blind_gap,
                     inside=p.veins.inside, placement=p.sources.placement,
                     max_iterations=p.run.max_iterations, max_nodes=p.run.max_nodes,
                     seed=p.run.seed if seed is None else seed)


def _region(p: Params) -> str:
    """Where darts fall: ``auto`` is the thesis's choice, the margin for marginal growth."""
    r = p.sources.region
    if r == "auto":
        return "margin" if p.growth.type == "marginal" else "blade"
    return r


def _rgb(c: str):
    return None if not c else tuple(int(c[i:i + 2], 16) for i in (1, 3, 5))


def texture_style(p: Params) -> TextureStyle:
    t = p.texture
    return TextureStyle(size=t.size, blade_color=_rgb(t.blade_color), vein_color=_rgb(t.vein_color),
                        background=_rgb(t.background), width_scale=t.width_scale, supersample=t.supersample)


def _header(p: Params, sp: SimParams, inputs: Inputs) -> str:
    g = inputs.growth
    grow = g.kind
    if g.ltg is not None:
        grow += f" (RERG_x, RERG_y of the initial y, sec. 5.2.1) in {g.steps} steps"
    elif g.kf is not None:
        grow += f" ({len(g.kf.times)} blade surfaces interpolated, sec. 5.2.1) in {g.steps} steps"
    elif g.kind != "none":
        s0, s1 = g.scale_at(0), g.final_scale
        grow += f" {s0[0]:g}" + (f",{s0[1]:g}" if s0[1] != s0[0] else "") + f" -> {s1[0]:g}" + \
            (f",{s1[1]:g}" if s1[1] != s1[0] else "") + f" in {g.steps} steps"
    nb = f" ({sp.neighbourhood} neighbourhood)" if sp.pattern == "closed" else ""
    nb += ", veins inside the blade" if sp.inside else ""
    return (f"venation (Runions ch. 4): {sp.pattern} pattern{nb}, growth {grow}; D {sp.step:g} d_k {sp.kill_distance:g} "
            f"b_s {sp.birth_source:g} b_v {sp.birth_vein:g} rho {sp.darts:g} ({sp.region}); seed {sp.seed}"
            + ("; sources at the centres of the largest empty circles (sec. 5.2.2)"
               if sp.placement == "largest_empty_circle" else "")
            + (f"; blind veinlets (areoles, sec. 5.2.4) from iteration {sp.blind_after}, gap {sp.blind_gap:g} D"
               if sp.blind_after >= 0 else "")
            + (f"; refined (sec. 5.2.6) at {p.refine.threshold:g}, alpha {p.refine.alpha:g}, jitter {p.refine.jitter:g}"
               if p.refine.threshold > 0 else "") + "\n"
            + (f"widths: elongation (sec. 5.2), tip {p.width.tip:g}" if p.width.model == "elongation" else
               f"widths: Murray's law, tip {p.width.tip:g} exponent {p.width.exponent:g} increment {p.width.increment:g}"))


def finish_graph(p: Params, pos, parent, extra, seed: int):
    """Widths (pipe model, eq. 3.5, or elongation, sec. 5.2) and the optional refinement of sec.
    5.2.6 of a graph in real coordinates: (pos, parent, extra, widths, owner), ``owner`` mapping
    each node to the simulated node it stands for."""
    if p.width.model == "elongation":
        widths = elongation_widths(pos, parent, p.veins.step, p.width.tip)
    else:
        widths = vein_widths(parent, p.width.tip, p.width.exponent, p.width.increment)
    r = p.refine
    if r.threshold > 0:
        pos, parent, extra, owner = refine_veins(pos, parent, extra, r.threshold, r.alpha, r.jitter, seed)
        return pos, parent, extra, widths[owner], owner
    return pos, parent, extra, widths, np.arange(len(parent))


def run_venation(p: Params, inputs: Inputs, out_dir, *, seed: int | None = None, frame_step: int | None = None,
                 frame_textures: bool | None = None, progress=None) -> VenationRun:
    """Simulate and write every output into ``out_dir`` (created); returns the run. ``seed``,
    ``frame_step`` and ``frame_textures`` override the file's when given."""
    out = Path(out_dir)
    sp = sim_params(p, inputs, seed)
    header = _header(p, sp, inputs)
    step = p.output.frame_step if frame_step is None else frame_step
    textures = p.output.frame_textures if frame_textures is None else frame_textures
    style = texture_style(p)
    g = inputs.growth
    final_margin = g.margin(inputs.blade, g.steps)
    box = texture_box(final_margin)
    written: list = []
    frames: list[int] = []
    out.mkdir(parents=True, exist_ok=True)

    allowed = frames_allowed(p, textures)

    def on_frame(snap: Snapshot):
        if len(frames) >= allowed:  # a run that goes on past its growth (the bound checked before is a floor)
            raise frame_limit_error(p, step, textures, option=frame_step is not None,
                                    found=f"more than {allowed} frames by iteration {snap.iteration}")
        name = frame_name(snap.iteration, prefix="veins_")
        fdir = out / "frames"
        fpos, fpar, fext, w, _ = finish_graph(p, snap.node_pos, snap.node_parent, snap.extra_edges, sp.seed)
        head = f"{header}\niteration {snap.iteration}: {len(snap.node_pos)} vein nodes, {len(snap.sources)} sources"
        write_graph(fdir / name, fpos, fpar, fext, head)
        write_widths(fdir / frame_name(snap.iteration, prefix="veins_", suffix=".widths"), w, head)
        write_margin(fdir / frame_name(snap.iteration, prefix="blade_"), snap.blade, head)
        if textures:
            img = render_texture(fpos, fpar, w, fext, snap.blade, style, box=box)
            save_png(img, fdir / frame_name(snap.iteration, prefix="texture_", suffix=".png"))
        frames.append(snap.iteration)

    res = simulate(inputs.blade, g, sp, on_frame=on_frame if step > 0 else None, frame_step=step, progress=progress)
    if step > 0:
        stale_frames(out / "frames", frames)
        written.append(out / "frames")
    simulated = res.n_nodes
    pos, parent, extra, widths, owner = finish_graph(p, res.node_pos, res.node_parent, res.extra_edges, sp.seed)
    if len(parent) != simulated or not np.array_equal(owner, np.arange(simulated)):
        res = replace(res, node_pos=pos, node_parent=parent, extra_edges=extra, node_iter=res.node_iter[owner])
    orders = strahler_orders(res.node_parent)
    loops = cycle_rank(res.n_nodes, res.node_parent, res.extra_edges)
    head = (f"{header}\n{res.iterations} iterations, {res.n_nodes} vein nodes, {loops} loops, "
            f"{res.sources_placed} sources ({res.sources_left} left)")
    write_graph(out / "veins.obj", res.node_pos, res.node_parent, res.extra_edges,
                head + "\none l polyline per vein chain (basal end first), then one 'l a b' per anastomosis")
    write_widths(out / "veins.widths", widths, head)
    spacing = p.output.mesh_spacing or None
    mesh = write_blade_mesh(out / "blade.obj", res.blade, texture_name="texture.png", header=head, box=box,
                            spacing=spacing)
    img = render_texture(res.node_pos, res.node_parent, widths, res.extra_edges, res.blade, style, box=box)
    save_png(img, out / "texture.png")
    write_events(out / "events.csv", res.events)
    written += [out / n for n in ("veins.obj", "veins.widths", "blade.obj", "blade.mtl", "texture.png", "events.csv")]
    return VenationRun(result=res, widths=widths, orders=orders, loops=loops, written=written, mesh=mesh,
                       header=header, simulated_nodes=simulated)


def summary(run: VenationRun, out_dir) -> str:
    """The lines ``venation`` prints on stderr."""
    r = run.result
    counts = np.bincount(run.orders[r.node_parent >= 0]) if r.n_nodes else np.zeros(1, int)
    orders = " ".join(f"{k}:{int(c)}" for k, c in enumerate(counts) if k > 0 and c > 0)
    lines = [
        run.header.splitlines()[0],
        f"{r.iterations} iterations ({r.growth_steps} of growth), {r.n_nodes} vein nodes, {len(r.extra_edges)} "
        f"anastomoses, {run.loops} loops, {r.sources_placed} sources placed, {r.sources_left} left"
        + (f" ({r.sources_stalled} removed with their veins stopped short by the guards)" if r.sources_stalled else "")
        + (f"; {r.blind_ends} blindly terminating veins (sec. 5.2.4)" if r.blind_ends else "")
        + (f"; refined from {run.simulated_nodes} simulated nodes (sec. 5.2.6)"
           if run.simulated_nodes and run.simulated_nodes != r.n_nodes else "")
        + ("" if r.stopped == "finished" else f"; stopped at {r.stopped.replace('_', ' ')}"),
        f"vein orders (Strahler, segments per order) {orders}; widths {run.widths.min():.4g}-{run.widths.max():.4g}; "
        f"blade mesh {run.mesh[0]} vertices, {run.mesh[1]} triangles",
        f"{r.seconds:.2f} s ({r.seconds / max(r.n_nodes, 1) * 1e6:.0f} us per vein node) -> {out_dir}",
    ]
    return "\n".join("venation: " + s for s in lines)
