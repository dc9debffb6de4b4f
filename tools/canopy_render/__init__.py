"""``canopy-render``: headless, CPU-only pictures of OBJ meshes and sequences (moderngl on Mesa EGL).

Modules: :mod:`.render` (the GL renderer: ``render_meshes``, ``render_sequence``, ``Renderer``,
``RenderOptions``), :mod:`.camera` (``Camera``, named views, automatic framing, ``.fcc`` camera
keys), :mod:`.sheet` (contact sheets,
frame numbers), :mod:`.output` (PNG, GIF, MP4 writers, atomic), :mod:`.inputs` (OBJ files and
sequences as layers), :mod:`.job` (one CLI run) and :mod:`.cli` (the command). Colours:
:mod:`inflo.formats.colors`; synthetic flowers for tests and benchmarks: :mod:`inflo.tools.testing`.
"""
from .camera import Camera, camera_from_fcc, fit_camera
from .render import GLUnavailable, Renderer, RenderOptions, auto_camera, render_meshes, render_sequence

__all__ = [
    "Camera",
    "GLUnavailable",
    "Renderer",
    "RenderOptions",
    "auto_camera",
    "camera_from_fcc",
    "fit_camera",
    "render_meshes",
    "render_sequence",
]
