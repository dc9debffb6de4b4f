"""Regenerate the documentation pictures of phyllotaxis and dimorph (top views, florets as discs).

Run from the repository root with the project's environment (it imports the installed ``inflo``)::

    .venv/bin/python docs/figures/phyllotaxis_figures.py          # into docs/
    .venv/bin/python docs/figures/phyllotaxis_figures.py OUT_DIR  # elsewhere

It writes ``phyllotaxis_static.png`` (Ridley's model on four surfaces, sec. 5.2),
``phyllotaxis_dynamics.png`` (fig. 5.2: centripetal, divergent, segregation; earlier and later
stages; green = young, red = old), ``phyllotaxis_yarrow.png`` (fig. 5.3: recursive segregation
at three times), ``phyllotaxis_compound.png`` (fig. 5.4), ``dimorph_sweep_n.png`` / ``dimorph_sweep_alpha.png`` (figs. 6.2, 6.3) and
``dimorph_heads.png`` (fig. 6.4a-c on a compound inflorescence, and a typed simple head) and
``dimorph_render.png`` (canopy-render views of real placements: discs with a petal along ``right``).

It lives here, next to the pictures it makes, not in ``tools/phyllotaxis``: it draws on phyllotaxis,
dimorph and canopy-render alike (dimorph builds on phyllotaxis, so inside phyllotaxis it made the
two import each other).
"""
from __future__ import annotations

import math
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

from inflo.formats.scn import Group, Placement, Scene
from inflo.tools.phyllotaxis.dynamics import frame_state, simulate
from inflo.tools.phyllotaxis.hierarchy import grow_hierarchy, hierarchy_state
from inflo.tools.phyllotaxis.plot import plot_panels
from inflo.tools.phyllotaxis.ridley import AreaFunction, diameter_of_area, pattern_scene, static_pattern
from inflo.tools.phyllotaxis.surface import builtin_curve

DOCS = Path(__file__).resolve().parents[1]
"""The default output folder: ``docs/``, the folder above this script."""

TYPE_COLOURS = {"ray": "#d62728", "small_ray": "#ff9896", "disk": "#f2c94c"}


def static_figure(path) -> None:
    panels = []
    for name, kw, gradient in [("disk", {}, False), ("paraboloid", {"height": 0.3}, False),
                               ("sphere_cap", {"angle": 70}, True), ("cone", {"height": 0.8}, False)]:
        prof = builtin_curve(name, **kw)
        if gradient:  # A(s) growing from the apex to the rim
            area = _Callable(lambda s, L=prof.length: 0.004 * (0.4 + 1.2 * np.asarray(s) / L))
        else:
            area = AreaFunction(0.004, prof.length)
        pat = static_pattern(prof, area)
        panels.append({"pos": pat.pos, "diameter": 0.95 * diameter_of_area(pat.area),
                       "values": np.arange(len(pat.s)),
                       "title": f"{name}{' (A grows with s)' if gradient else ''}: {len(pat.s)}"})
    plot_panels(path, panels, suptitle="Ridley's model on surfaces of revolution (eq. 5.2), top views, "
                                       "colour = index i (red: rim)")


class _Callable(AreaFunction):
    """An area function from a Python callable of arc length."""

    def __init__(self, fn):
        super().__init__(1.0, 1.0)
        self._fn = fn

    def __call__(self, s):
        return np.asarray(self._fn(s), dtype=np.float64)


def dynamics_figure(path) -> None:
    disk = builtin_curve("disk")
    dome = builtin_curve("sphere_cap", angle=60)
    runs = [
        ("centripetal", dict(mode="centripetal", frames=160, interval=0.5, primordium_area=0.003,
                             primordium_growth=0.01, inner_area=0.6, inner_growth=0.003,
                             profiles=[dome, disk], curve_times=[0.0, 1.0])),
        ("divergent", dict(mode="divergent", frames=120, interval=1.0, primordium_area=0.003,
                           primordium_growth=0.005, inner_area=0.25, outer_area=0.35,
                           profiles=[disk])),
        ("segregation", dict(mode="segregation", frames=200, interval=1.0, primordium_area=0.003,
                             primordium_growth=0.01, inner_area=0.004, threshold=0.0045, inner_growth=0.5,
                             profiles=[disk])),
    ]
    panels = []
    for name, kw in runs:
        pat = simulate(**kw)
        last = frame_state(pat, pat.frames - 1)
        lim = 1.05 * float(np.abs(last["pos"][:, [0, 2]]).max() + last["scale"][:, 0].max())
        for frac in (0.3, 1.0):
            f = int(round(frac * (pat.frames - 1)))
            st = frame_state(pat, f)
            age = f - pat.emergence[st["ids"]]
            panels.append({"pos": st["pos"], "diameter": 0.95 * st["scale"][:, 0], "values": age, "lim": lim,
                           "title": f"{name}, frame {f}: {len(st['ids'])} primordia"})
    plot_panels(path, panels, ncols=2, size=3.4,
                suptitle="Fig. 5.2: (a) centripetal, (b) divergent fractionation, (c) segregation; "
                         "green younger, red older")


def yarrow_figure(path) -> None:
    h = grow_hierarchy(levels=3, frames=200.0, growth_rate=0.05, initial_area=1.0, element_area=[1.0],
                       production_threshold=[10.0], meristem_threshold=[20.0])
    panels = []
    final = hierarchy_state(h, 200.0)
    lim = 1.02 * float(np.abs(final["pos"][:, [0, 2]]).max() + final["scale"][:, 0].max())
    for t in (175.0, 188.0, 200.0):
        st = hierarchy_state(h, t)
        age = t - h.element_birth[h.florets[st["ids"]]]
        panels.append({"pos": st["pos"], "diameter": 0.9 * st["scale"][:, 0], "values": age, "lim": lim,
                       "title": f"frame {t:g}: {len(st['ids'])} florets"})
    plot_panels(path, panels, size=4.2,
                suptitle="Fig. 5.3: recursive segregation on a uniformly growing flat meristem (3 levels)")


def compound_figure(path) -> None:
    from inflo.tools.phyllotaxis.compound import compound_pattern

    prof = builtin_curve("sphere_cap", radius=3.0, angle=50)
    c = compound_pattern(prof, AreaFunction(0.5, prof.length), head_curve="cone", head_height=0.6,
                         head_fill=0.9, floret_fraction=0.015, start=0.03)
    age = np.concatenate([np.arange(np.sum(c.floret_head == k)) for k in range(len(c.head_pos))])
    plot_panels(path, [
        {"pos": c.floret_pos, "diameter": 0.95 * diameter_of_area(c.floret_area), "values": c.floret_head,
         "cmap": "tab20", "title": f"top: {len(c.head_pos)} conical heads, {len(c.floret_pos)} florets"},
        {"pos": c.floret_pos, "diameter": 0.95 * diameter_of_area(c.floret_area), "values": age,
         "title": "colour = order within each head (red: first formed, outermost)"},
    ], size=4.6, suptitle="Fig. 5.4: two-level hierarchical phyllotaxis with conical meristems")


def _compound(n=40, ring=2.6):
    from inflo.tools.dimorph.sweep import simple_head

    head = simple_head(n)
    scene = Scene()
    scene.groups[0] = Group(0, [0, 0, 0], -1)
    centres = [np.zeros(3)] + [ring * np.array([math.cos(a), 0, math.sin(a)]) for a in np.radians(np.arange(0, 360, 60))]
    d = 0.95 * 2 * math.sqrt(1 / (n + 1))
    for g, c in enumerate(centres, 1):
        scene.groups[g] = Group(g, c, 0)
        for p in head:
            scene.placements.append(Placement("o", 0, p + c, [d] * 3, [0, 1, 0], [1, 0, 0], group=g))
    return scene


def dimorph_figures(folder) -> None:
    from inflo.tools.dimorph.dimorph import DimorphOptions, dimorph_scene
    from inflo.tools.dimorph.sweep import simple_head, write_sweep

    folder = Path(folder)
    with tempfile.TemporaryDirectory() as tmp:
        res = write_sweep(tmp)
        shutil.copy(res["paths"][1], folder / "dimorph_sweep_n.png")
        shutil.copy(res["paths"][3], folder / "dimorph_sweep_alpha.png")
    scene = _compound()
    panels = []
    for label, th in (("(a) Th_a = 0.45", (0.45,)), ("(b) Th_b = 3.0", (3.0,)), ("(c) Th_a and Th_b", (0.45, 3.0))):
        out, counts = dimorph_scene(scene, DimorphOptions(53.0, th, ray_scale=1.6))
        pos = np.array([p.pos for p in out.placements])
        dia = np.array([p.scale[0] for p in out.placements])
        cols = [TYPE_COLOURS[p.type] for p in out.placements]
        dia = np.where([p.type == "disk" for p in out.placements], dia, dia * 0.75)
        panels.append({"pos": pos, "diameter": dia, "colors": cols, "edge": True,
                       "title": f"fig. 6.4{label}, alpha 53: {counts['ray']} ray, {counts['small_ray']} small"})
    n = 300
    head = simple_head(n)
    s2 = Scene()
    for p in head:
        s2.placements.append(Placement("o", 0, p, [0.1] * 3, [0, 1, 0], [1, 0, 0]))
    out, counts = dimorph_scene(s2, DimorphOptions(75.0))
    panels.append({"pos": head, "diameter": np.full(n, 0.95 * 2 / math.sqrt(n + 1)),
                   "colors": [TYPE_COLOURS[p.type] for p in out.placements], "edge": True,
                   "title": f"simple head n = {n}, alpha 75: {counts['ray']} rays"})
    plot_panels(folder / "dimorph_heads.png", panels, ncols=4, size=3.6,
                suptitle="Floret fate by cones (ch. 6): red ray, pink small ray (size ~ d_min), yellow disk")


def render_figure(path) -> None:
    """3-D views of real placements (discs with a petal along ``right``) through canopy-render."""
    from PIL import Image

    from inflo.tools.canopy_render.render import render_meshes
    from inflo.tools.dimorph.dimorph import DimorphOptions, dimorph_scene
    from inflo.tools.phyllotaxis.compound import compound_pattern, compound_scene
    from inflo.tools.phyllotaxis.plot import discs_mesh

    prof = builtin_curve("sphere_cap", radius=4.0, angle=30)
    comp = compound_scene(compound_pattern(prof, AreaFunction(0.5, prof.length), head_curve="disk", head_fill=0.8,
                                           floret_fraction=0.015, start=0.03), size_factor=0.95)
    comp, _ = dimorph_scene(comp, DimorphOptions(53.0, (0.15, 1.0), ray_scale=1.6))  # fig. 6.4c
    head = builtin_curve("paraboloid", height=0.15)
    sun = pattern_scene(static_pattern(head, AreaFunction(0.004, head.length)))
    sun, _ = dimorph_scene(sun, DimorphOptions(75.0, ray_scale=1.6))
    images = [render_meshes(discs_mesh(sc)) for sc in (comp, sun)]
    w = sum(im.shape[1] for im in images)
    h = max(im.shape[0] for im in images)
    canvas = Image.new("RGB", (w, h), "white")
    x = 0
    for im in images:
        canvas.paste(Image.fromarray(im), (x, 0))
        x += im.shape[1]
    canvas.save(path)


def main(argv=None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    folder = Path(argv[0]) if argv else DOCS
    folder.mkdir(parents=True, exist_ok=True)
    static_figure(folder / "phyllotaxis_static.png")
    dynamics_figure(folder / "phyllotaxis_dynamics.png")
    yarrow_figure(folder / "phyllotaxis_yarrow.png")
    compound_figure(folder / "phyllotaxis_compound.png")
    render_figure(folder / "dimorph_render.png")
    dimorph_figures(folder)


if __name__ == "__main__":
    main()
