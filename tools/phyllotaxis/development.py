"""Developmental windows of the placements: the phase effect (thesis ch. 5, ch. 9).

A placement's ``frameStart frameEnd`` is its developmental window: fccompose opens the floret
linearly from ``frameStart`` to ``frameEnd``. Two ways to give florets different windows:

- **by age** (dynamic patterns, ``[dynamics]`` / ``[hierarchy]`` ``development_frames = N``):
  ``frameEnd = frameStart + N`` with ``frameStart`` the emergence frame, *not* clamped to the last
  frame, so a floret that emerged late is still developing at the end (:func:`age_window`);
- **by position** (static patterns, ``[primordia] development_order``): florets are ranked by
  their distance from their head's centre (centripetal: the outermost first, as in the
  sunflower, thesis ch. 9: "outer florets are more advanced in their development than those in
  more central positions"; centrifugal: the innermost first), and floret of rank r gets
  ``frameStart = round(frame_start + r * offset)``, ``frameEnd = frameStart + N``
  (:func:`apply_development_order`).
"""
from __future__ import annotations

import math

import numpy as np

from inflo.formats.errors import InputError
from inflo.formats.scn import Scene
from inflo.tools.common import linalg as la

__all__ = ["round_frame", "age_window", "development_ranks", "apply_development_order"]


def round_frame(x: float) -> int:
    """Nearest integer frame, halves rounded up (deterministic, unlike banker's ``round``)."""
    return int(math.floor(float(x) + 0.5))


def age_window(start: int, last: int, development_frames: int | None) -> tuple[int, int]:
    """``(frameStart, frameEnd)`` of a floret emerging at frame ``start`` of a run ending at ``last``.

    Without ``development_frames``: ``frameEnd = last`` (every floret fully open at the end).
    With it: ``frameEnd = start + development_frames`` (may lie past ``last``: the phase effect).
    """
    if development_frames is None:
        return int(start), int(last)
    return int(start), int(start) + int(development_frames)


def development_ranks(pos: np.ndarray, centres: np.ndarray, group: np.ndarray, order: str) -> np.ndarray:
    """Rank of every placement within its group by distance from the group's centre.

    Parameters
    ----------
    pos, centres : (n, 3) float64  placement positions and the centre of each one's group
    group : (n,) int  group of each placement (ranks are counted per group)
    order : ``centripetal`` (the farthest floret has rank 0) or ``centrifugal`` (the nearest has)

    Ties (distances equal to 12 significant digits of the largest distance) are broken by placement
    index, so the result does not depend on rounding noise.
    """
    n = len(pos)
    dist = la.norm(np.asarray(pos, float) - np.asarray(centres, float), axis=1)
    scale = float(dist.max()) if n and dist.max() > 0 else 1.0
    key = np.round(dist / scale, 12)
    if order == "centripetal":
        key = -key
    elif order != "centrifugal":
        raise ValueError(f"development order {order!r}")
    idx = np.arange(n)
    ranks = np.empty(n, np.int64)
    group = np.asarray(group)
    for g in np.unique(group):
        members = idx[group == g]
        sorted_members = members[np.lexsort((members, key[members]))]
        ranks[sorted_members] = np.arange(len(members))
    return ranks


def apply_development_order(scene: Scene, *, order: str, offset: float, frame_start: int,
                            frames: int) -> Scene:
    """Turn every placement of ``scene`` into ``ca: frameStart frameEnd`` by its rank (in place).

    Floret of rank r (:func:`development_ranks`, per group, distance from the group's centre; the
    head's centre for placements without a group) gets ``frameStart = round(frame_start + r *
    offset)`` and ``frameEnd = frameStart + frames``. Returns ``scene``.
    """
    arr = scene.arrays()
    n = len(scene)
    if n == 0:
        return scene
    group = np.asarray(arr["group"])
    centres = np.array(arr["group_centre"])
    loose = group < 0
    if loose.any():
        centres[loose] = arr["pos"][loose].mean(axis=0)
    ranks = development_ranks(arr["pos"], centres, group, order)
    from .params import MAX_FRAME

    last = frame_start + int(ranks.max()) * offset + frames
    if not last <= MAX_FRAME:
        raise InputError(f"expected development windows that end by frame {MAX_FRAME}, found frame {last:.4g} "
                         f"(frame_start {frame_start} + development_offset {offset:g} x rank {int(ranks.max())} + "
                         f"{frames} frames); lower primordia.development_offset or development_frames")
    for p, r in zip(scene.placements, ranks):
        start = round_frame(frame_start + int(r) * offset)
        p.kind = "ca"
        p.frame_start, p.frame_end = start, start + int(frames)
    return scene
