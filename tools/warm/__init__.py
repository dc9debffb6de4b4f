"""Compile the canopy's numba kernels ahead of the first run: ``python -m inflo.tools.warm``.

inflo's numerical kernels are numba ``@njit(cache=True)`` functions, compiled for the machine's
processor on their first call and kept in numba's on-disk cache (``__pycache__`` beside each
module, or ``NUMBA_CACHE_DIR``). On a fresh machine the first canopy run would compile those of
collision detection and response, the PBD solver and fccompose: about 100 s on a 2-core AMD EPYC
VM for a 20-floret scene, most of it the continuous tests (``collide.ccd``) and the floret-by-floret
sweeps (``collide.probe``) -- issue 51's "first run on a fresh machine". This module runs that
20-floret scene (:func:`inflo.tools.testing.florets.grid_canopy_scene`, the florets opening into
each other for 10 frames, sanity checks on) once in a temporary folder, so that the install
(``make venv``) pays the compiling and a later fccompose run, a species' canopy stage or a check's
exact intersection test loads the kernels from the cache instead (about 1 s). Where the cache is
warm already it takes a few seconds. (The species targets and ``make test`` do not run it: they
compile what they call as they go.)

It compiles for the processor it runs on (numba's cache is keyed by it): a ``.venv`` moved to
another machine compiles again on its first run, as without this step.
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

__all__ = ["warm_canopy_kernels"]

#: the warm-up scene: florets, their opening's frames (the fccompose benchmark's small scene)
FLORETS, FRAMES = 20, 10


def warm_canopy_kernels(folder: Path | None = None) -> float:
    """Run the small synthetic canopy once (in ``folder``, else a temporary folder removed
    afterwards), compiling or loading every kernel it calls; returns the seconds it took."""
    from inflo.formats.fcc import read_fcc
    from inflo.tools.fccompose.compose import compose_canopy
    from inflo.tools.testing.florets import (
        grid_canopy_scene,
        opening_floret,
        write_fcc_text,
        write_floret_animation,
        write_scene,
    )

    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="inflo-warm-") as tmp:
        root = Path(folder) if folder is not None else Path(tmp)
        root.mkdir(parents=True, exist_ok=True)
        frames, faces, fixed = opening_floret(FRAMES, nu=12, nv=4)
        write_floret_animation(root / "anim", frames, faces, fixed, root / "petal_base.txt")
        write_scene(root / "scene.scn", grid_canopy_scene(FLORETS, FRAMES))
        # sanity checks at the first and the last frame: the exact static test's kernels too
        write_fcc_text(root / "canopy.fcc", solver_iterations=50, collision_iterations=10, retries=20,
                       spacing=0.005, frames=FRAMES, sanity_every=FRAMES)
        compose_canopy(read_fcc(root / "canopy.fcc"), root / "out", progress=None, warn=lambda msg: None)
    return time.perf_counter() - t0
