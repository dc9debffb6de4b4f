"""The viewer page: ``index.html`` and the three.js files it needs, written beside a ``.glb``.

The page (``static/index.html``) loads the ``.glb`` with three.js's GLTFLoader, frames the grown
flower with an orbit camera and drives the growth's morph targets itself: play/pause, a frame
slider, ``?frame=N`` to open it paused at frame N. three.js is the pinned copy in ``static/three``
(its LICENSE beside it), so the folder works offline from any static HTTP server.
"""
from __future__ import annotations

import html
import json
import shutil
from importlib import resources
from pathlib import Path

from inflo.formats.atomic import atomic_write

__all__ = ["THREE_VERSION", "write_viewer", "static_dir"]

THREE_VERSION = "0.170.0"
"""The three.js release copied into ``static/three`` (npm package ``three``)."""


def static_dir() -> Path:
    return Path(str(resources.files("inflo.tools.canopy_view") / "static"))


def write_viewer(folder, model: str, *, title: str) -> Path:
    """Write ``folder/index.html`` (showing ``model``, a ``.glb`` in ``folder``) and
    ``folder/three/``; returns the page's path. Each file is written atomically."""
    folder = Path(folder)
    src = static_dir()
    config = json.dumps({"model": model, "title": title, "three": THREE_VERSION})
    page = (src / "index.html").read_text(encoding="utf-8")
    page = page.replace("__TITLE__", html.escape(title)).replace("__CONFIG__", config.replace("</", "<\\/"))
    for path in sorted((src / "three").rglob("*")):
        if path.is_file():
            target = folder / "three" / path.relative_to(src / "three")
            with atomic_write(target, "wb") as fh, open(path, "rb") as inp:
                shutil.copyfileobj(inp, fh)
    out = folder / "index.html"
    with atomic_write(out) as fh:
        fh.write(page)
    return out
