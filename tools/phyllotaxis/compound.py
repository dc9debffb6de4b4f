"""Two-level hierarchical phyllotaxis with conical meristems (thesis sec. 5.4, fig. 5.4).

Level 1: Ridley's pattern (eq. 5.2) on the ``[surface]`` curve with primordium area
``head_area`` places the second-order meristems (heads). Level 2: each head is a surface of
revolution of its own (``head_curve``, by default a cone whose height is ``head_height`` times its
radius), of area ``head_fill * A_head``, carrying florets of area ``floret_fraction * A_head``
by eq. 5.2. A head's axis is the level-1 surface normal at its position; its pattern is turned so
that its first-formed (outermost) floret lies on the side away from the inflorescence's centre,
as far as possible from the grandparent's centre (Hofmeister's rule, sec. 5.4).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from inflo.formats.scn import Group, Placement, Scene
from inflo.tools.common import linalg as la

from .ridley import AreaFunction, diameter_of_area, static_pattern
from .surface import Profile, load_curve

__all__ = ["Compound", "compound_pattern", "compound_scene"]


@dataclass
class Compound:
    """A two-level pattern (f florets in h heads).

    Attributes
    ----------
    head_pos, head_up, head_right : (h, 3) float64  each head's apex and frame
    head_area : (h,) float64
    floret_pos, floret_up, floret_right : (f, 3) float64
    floret_area : (f,) float64
    floret_head : (f,) int64  the head of each floret
    centre : (3,) float64  the inflorescence's centre (level-1 apex)
    """

    head_pos: np.ndarray
    head_up: np.ndarray
    head_right: np.ndarray
    head_area: np.ndarray
    floret_pos: np.ndarray
    floret_up: np.ndarray
    floret_right: np.ndarray
    floret_area: np.ndarray
    floret_head: np.ndarray
    centre: np.ndarray


def compound_pattern(profile: Profile, head_area: AreaFunction, *, head_curve: str = "cone",
                     head_height: float = 0.5, head_fill: float = 1.0, floret_fraction: float = 0.03,
                     head_start: float = 0.0, divergence: float = 137.50776405003785, start: float = 0.0, count: int = 0,
                     max_count: int = 1_000_000) -> Compound:
    """Place heads by eq. 5.2 on ``profile``, then florets by eq. 5.2 on each head (fig. 5.4).

    ``head_start``: the arc length, as a fraction of the head's generating curve (its radius when
    flat), at which each head's first floret forms (as
    ``start`` for the heads): 0 puts one on the head's apex and the next about half a floret
    diameter from it (eq. 5.2 near the apex), whose open florets then overlap."""
    heads = static_pattern(profile, head_area, divergence=divergence, start=start, count=count,
                           max_count=max_count)
    unit = load_curve(head_curve, radius=1.0, height=head_height, angle=90.0, samples=1024)
    # a floret count per head fixed by the fraction: the unit head's area / (fraction * area)
    fp, fu, fr, fa, fh = [], [], [], [], []
    for k in range(len(heads.s)):
        A = float(heads.area[k])
        scale = math.sqrt(head_fill * A / unit.total_area)
        prof = unit.scaled(scale)
        sub = static_pattern(prof, AreaFunction(floret_fraction * A, prof.length), divergence=divergence,
                             start=head_start, max_count=max_count)
        # local frame of the head: x = right (away from the centre), y = up (normal), z = x cross y
        x, y = heads.right[k], heads.up[k]
        z = np.cross(x, y)
        # turn the pattern so the outermost floret (formed first, centripetally) points along +x
        last = sub.pos[-1]
        turn = -math.atan2(last[2], last[0])
        c, s = math.cos(turn), math.sin(turn)
        rot = np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]])  # rotation about local +Y by `turn`
        basis = np.stack([x, y, z])  # rows: images of local X, Y, Z

        def to_world(v, translate, rot=rot, basis=basis, k=k):
            return la.matmul(la.matmul(v, rot.T), basis) + (heads.pos[k] if translate else 0.0)

        fp.append(to_world(sub.pos, True))
        fu.append(to_world(sub.up, False))
        fr.append(to_world(sub.right, False))
        fa.append(sub.area)
        fh.append(np.full(len(sub.s), k, np.int64))
        if sum(len(a) for a in fa) > max_count:
            from inflo.formats.errors import InputError

            raise InputError(f"more than {max_count} florets in the compound pattern")
    return Compound(heads.pos, heads.up, heads.right, heads.area, np.vstack(fp), np.vstack(fu), np.vstack(fr),
                    np.concatenate(fa), np.concatenate(fh), heads.centre)


def compound_scene(c: Compound, *, floret_id: int = 0, size_factor: float = 1.0, kind: str = "o",
                   frame_start: int = 0, frame_end: int = 100) -> Scene:
    """The SCN: group 0 = the inflorescence (centre = level-1 apex), group k + 1 = head k (parent 0)."""
    scene = Scene()
    scene.groups[0] = Group(0, c.centre, -1)
    for k in range(len(c.head_pos)):
        scene.groups[k + 1] = Group(k + 1, c.head_pos[k], 0)
    d = size_factor * diameter_of_area(c.floret_area)
    kw = {"frame_start": frame_start, "frame_end": frame_end} if kind == "ca" else {}
    for i in range(len(c.floret_pos)):
        scene.placements.append(Placement(kind, int(floret_id), c.floret_pos[i], np.full(3, d[i]), c.floret_up[i],
                                          c.floret_right[i], group=int(c.floret_head[i]) + 1, **kw))
    return scene
