"""Write the dense two-floret test scene into this folder.

Two synthetic 5-petal florets (an OBJ sequence of an opening floret, ``anim/``) stand 1 unit apart,
so their open petals would run through each other; fccompose grows them with collisions on and
they deform around each other instead. Run::

    python pipelines/examples/fccompose/make_example.py
    fccompose pipelines/examples/fccompose/dense.fcc -o /tmp/dense
    canopy-render /tmp/dense --sheet-every 5 -o /tmp/dense_sheet.png

Files written here: ``anim/frame_0000.obj`` ... (20 frames), ``petal_base.txt`` (the fixed base
rows, a ``weight`` file), ``scene.scn`` (two ``ca`` placements, materials 1 and 2) and
``dense.fcc``.
"""
from __future__ import annotations

from pathlib import Path

from inflo.tools.testing.florets import (
    opening_floret,
    two_floret_scene,
    write_fcc_text,
    write_floret_animation,
    write_scene,
)

N_FRAMES = 20


def main(folder: Path | None = None) -> None:
    folder = folder or Path(__file__).resolve().parent
    frames, faces, fixed = opening_floret(N_FRAMES)
    write_floret_animation(folder / "anim", frames, faces, fixed, folder / "petal_base.txt")
    write_scene(folder / "scene.scn", two_floret_scene(N_FRAMES))
    write_fcc_text(folder / "dense.fcc", solver_iterations=50, collision_iterations=10, retries=20,
                   spacing=0.01, sanity_every=1, updates_per_frame=2)


if __name__ == "__main__":
    main()
