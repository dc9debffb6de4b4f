"""Place six copies of one head as the Dyssodia inflorescence (the `head` stage's last step).

Usage: python compose_heads.py HEAD.scn RECEPTACLE.obj RING TILT DROP OUT.scn OUT_RECEPTACLES.obj OUT_OBSTACLES.scn

*Dyssodia decipiens* (thesis ch. 9, fig. 9.7): "a central head surrounded by 5 other heads". The
central copy stands at the origin; five copies stand on a ring of radius RING (scene units) at
72-degree steps, each tilted outward by TILT degrees about the tangent of the ring (the heads of
a corymb-like cluster lean away from its centre), DROP scene units below the central one (the
terminal head stands highest, so the outer heads crowd in under its rim), and turned about its own axis so that the
pattern faces the same way relative to the inflorescence's centre (Hofmeister's rule: the first,
outermost floret away from the centre). The output is one flat scene (so that `dimorph --centre
top` decides the ray florets at the level of the whole inflorescence, fig. 6.4b): group 0 the
inflorescence (its centre the origin), group k + 1 head k (its centre where its apex is), every
placement keeping its window; and the head's receptacle (phyllotaxis ``[receptacle]``) placed the
same way under each head, as one OBJ; and the six receptacles as fccompose obstacles (formats/fcc.md
"Obstacles": `o` placements of the head's receptacle, id OBSTACLE_ID, `#@ type: obstacle`, one per
head, in a scene of their own that spread_rays.py appends after the florets), so that the crowded
florets of one head are pushed off its neighbours' receptacles. All written atomically.
"""
from __future__ import annotations

import copy
import sys
from pathlib import Path

import numpy as np

from inflo.formats.obj import ObjMesh, read_obj, write_obj
from inflo.formats.scn import Group, Placement, Scene, read_scn, write_scn
from inflo.tools.common import linalg as la

HEADS = 6
# the receptacle's id in dyssodia.fcc (an `obj:` entry)
OBSTACLE_ID = 2


def _rot(axis, angle):
    axis = np.asarray(axis, float) / la.norm(axis)
    x, y, z = axis
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
                     [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
                     [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)]])


def heads(ring: float, tilt: float, drop: float):
    """(centre (3,), rotation (3, 3)) of each head: the central one, then five round it."""
    out = [(np.zeros(3), np.eye(3))]
    for k in range(HEADS - 1):
        phi = 2 * np.pi * k / (HEADS - 1)
        radial = np.array([np.sin(phi), 0.0, np.cos(phi)])
        tangent = np.array([np.cos(phi), 0.0, -np.sin(phi)])
        spin = _rot([0, 1, 0], phi)  # the pattern faces the same way relative to the centre
        lean = _rot(tangent, np.radians(tilt))
        centre = ring * radial - np.array([0.0, drop, 0.0])
        out.append((centre, la.matmul(lean, spin)))
    return out


def main(src: Path, receptacle: Path, ring: float, tilt: float, drop: float, dst: Path, dst_receptacles: Path,
         dst_obstacles: Path) -> int:
    head = read_scn(src)
    rec = read_obj(receptacle)
    scene = Scene()
    scene.groups[0] = Group(0, np.zeros(3), -1)
    obstacles = Scene()
    verts, faces = [], []
    for k, (centre, rot) in enumerate(heads(ring, tilt, drop)):
        obstacles.placements.append(Placement("o", OBSTACLE_ID, centre.copy(), np.ones(3), rot[:, 1].copy(),
                                              rot[:, 0].copy(), type="obstacle"))
        scene.groups[k + 1] = Group(k + 1, centre.copy(), 0)
        for p in head.placements:
            q = copy.deepcopy(p)
            q.pos = la.matmul(rot, p.pos) + centre
            q.up = la.matmul(rot, p.up)
            q.right = la.matmul(rot, p.right)
            q.group = k + 1
            scene.placements.append(q)
        faces.append(rec.faces + k * len(rec.vertices))
        verts.append(la.matmul(rec.vertices, rot.T) + centre)
    what = f"compose_heads.py, ring {ring:g}, tilt {tilt:g}, drop {drop:g}"
    write_scn(dst, scene, header=f"{HEADS} copies of {src.name} ({what})")
    write_scn(dst_obstacles, obstacles, header=f"the {HEADS} receptacles as obstacles ({what})")
    n = len(rec.faces)
    # one group a head (receptacle_k), and with phyllaries on its underside a second (phyllaries_k)
    parts = list(rec.groups) if rec.face_group is not None and "phyllaries" in rec.groups else ["receptacle"]
    part = np.zeros(n, np.int64) if len(parts) == 1 else np.asarray(rec.face_group, np.int64)
    mesh = ObjMesh(np.concatenate(verts), np.concatenate(faces),
                   groups=[f"{g}_{k}" for k in range(HEADS) for g in parts],
                   face_group=(np.repeat(np.arange(HEADS), n) * len(parts) + np.tile(part, HEADS)).astype(np.int32),
                   materials=rec.materials,
                   face_material=None if rec.face_material is None else np.tile(rec.face_material, HEADS))
    write_obj(dst_receptacles, mesh)
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 9:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    a = sys.argv
    sys.exit(main(Path(a[1]), Path(a[2]), float(a[3]), float(a[4]), float(a[5]), Path(a[6]), Path(a[7]), Path(a[8])))
