"""The branches as an obstacle for fccompose (formats/thyrse.md "Obstacle").

``fccompose`` collides the florets with every other part of its canopy, and an obstacle placement
(``#@ type: obstacle``, formats/fcc.md "Obstacles") is such a part: fixed, simulated, not written.
A part may not intersect itself, but a thyrse's branch mesh does by construction (its generalized
cylinders meet inside each other at every joint), so the obstacle is made of the same chains
(:func:`inflo.tools.branch_gen.pipe.chains`: the polylines between joints) as separate tubes that
keep clear of each other:

- each chain's tube has the radius of the branch there plus ``margin`` (it holds the branch mesh:
  a petal stopped by it does not touch the branch);
- it starts ``gap`` beyond the joint it grows from (beyond the largest radius there) and ends
  ``gap`` short of a joint it ends at, or of the floret it carries (clear of the floret's base);
- where two tubes still come within ``gap`` of each other (near a joint where they part at a
  narrow angle: the exact static test of the tubes grown by ``gap / 2``), the later chain's start
  moves on by its radius plus ``gap``, up to ``ROUNDS`` times, and a chain left shorter than
  ``gap`` has no tube.

What the obstacle leaves open is only the joints' neighbourhood, inside the panicle.
"""
from __future__ import annotations

import numpy as np

from inflo.formats.obj import ObjMesh
from inflo.tools.branch_gen.cylinders import generalized_cylinders
from inflo.tools.branch_gen.pipe import chains
from inflo.tools.common import linalg as la

__all__ = ["obstacle_mesh", "ROUNDS"]

#: rounds of moving the starts of tubes that come too close to another
ROUNDS = 8


def _joint_radius(node_parent, radius) -> np.ndarray:
    """(n,) the largest radius of the branches meeting at each node (its own and its children's)."""
    r = np.asarray(radius, float).copy()
    for c, p in enumerate(node_parent):
        if p >= 0:
            r[p] = max(r[p], radius[c])
    return r


def _cut(points: np.ndarray, t0: float, t1: float):
    """The polyline ``points`` without its first ``t0`` and last ``t1`` of arc length, or None when
    less than nothing is left."""
    seg = la.norm(points[1:] - points[:-1], axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    a, b = t0, s[-1] - t1
    if b - a <= 1e-12:
        return None

    def at(t):
        k = int(np.clip(np.searchsorted(s, t, side="right") - 1, 0, len(seg) - 1))
        f = (t - s[k]) / seg[k] if seg[k] > 0 else 0.0
        return points[k] + f * (points[k + 1] - points[k])

    inner = [points[k] for k in range(len(points)) if a < s[k] < b]
    return np.array([at(a)] + inner + [at(b)])


def _tubes(paths, radii, sides: int):
    """Closed generalized cylinders, one per polyline of ``paths`` with per-point ``radii``:
    (vertices, faces, tube of each face)."""
    pos, parent, chain_list, rad = [], [], [], []
    for pts, r in zip(paths, radii):
        first = len(pos)
        for k, (p, rk) in enumerate(zip(pts, r)):
            pos.append(p)
            rad.append(rk)
            parent.append(first + k - 1 if k else -1)
        chain_list.append(np.arange(first, len(pos), dtype=np.int64))
    if not chain_list:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int32), np.zeros(0, np.int64)
    v, f, _, _ = generalized_cylinders(np.array(pos), np.array(parent, np.int64), chain_list, np.array(rad),
                                       sides=sides, caps=True)
    per = [(len(c) - 1) * 2 * sides + 2 * sides for c in chain_list]
    return v, f, np.repeat(np.arange(len(chain_list)), per)


def _clashes(paths, radii, gap: float, sides: int) -> list:
    """Indices (into ``paths``) of the later tube of every pair that comes within ``gap``: the tubes
    grown by ``gap / 2`` intersect (exact static test)."""
    from inflo.tools.collide import intersecting_pairs

    v, f, tube = _tubes(paths, [r + 0.5 * gap for r in radii], sides)
    if not len(f):
        return []
    pairs = intersecting_pairs(v, f, tri_part=tube)
    a, b = tube[pairs[:, 0]], tube[pairs[:, 1]]
    return [int(t) for t in np.unique(np.maximum(a, b)[a != b])]


def obstacle_mesh(node_pos, node_parent, node_tip, radius, *, sides: int, gap: float, margin: float) -> ObjMesh:
    """The tubes of the module docstring: an ObjMesh (one group ``obstacle_<c>`` per tube) whose
    tubes neither intersect nor come within ``gap`` of each other."""
    node_pos = np.asarray(node_pos, float)
    radius = np.asarray(radius, float)
    joint = _joint_radius(node_parent, radius)
    chain_list = chains(node_parent, node_tip)
    start = np.array([joint[c[0]] + gap for c in chain_list])

    def build():
        paths, radii, which = [], [], []
        for i, c in enumerate(chain_list):
            end = gap if node_tip[c[-1]] else joint[c[-1]] + gap
            pts = _cut(node_pos[c], start[i], end)
            if pts is None or la.norm(pts[-1] - pts[0]) < gap:
                continue
            paths.append(pts)
            radii.append(np.full(len(pts), float(radius[c[1:]].max()) + margin))
            which.append(i)
        return paths, radii, which

    for _ in range(ROUNDS):
        paths, radii, which = build()
        clash = _clashes(paths, radii, gap, sides)
        if not clash:
            break
        for t in clash:
            start[which[t]] += radii[t][0] + gap
    else:
        paths, radii, which = build()
        drop = set(_clashes(paths, radii, gap, sides))
        keep = [k for k in range(len(paths)) if k not in drop]
        paths, radii, which = [paths[k] for k in keep], [radii[k] for k in keep], [which[k] for k in keep]
    v, f, tube = _tubes(paths, radii, sides)
    groups = [f"obstacle_{c}" for c in which]
    return ObjMesh(vertices=v, faces=f, groups=groups, face_group=tube.astype(np.int32) if len(groups) else None)
