"""The yarrow's heads on one clock: the growing corymb pattern and every head's florets (the
`corymb` stage's last step).

Usage: python corymb_heads.py [--dome D] [--jitter J] [--late L] PATTERN_DIR HEAD.scn FRAMES HEAD_SCALE BUD OUT_DIR [INVOLUCRE.scn RECEPTACLE.obj]
       python corymb_heads.py --obstacles TYPED.scn RECEPTACLES.scn OUT.scn

PATTERN_DIR is a dynamic recursive-segregation pattern (``phyllotaxis``, ``[hierarchy]`` with
``dynamic = true``, thesis sec. 5.4, fig. 5.3): ``scene.scn`` (one ``rba:`` placement per head) and
``rba/NNNN.rba`` (the heads that have emerged by frame NNNN, their positions and sizes as the flat
meristem grows). HEAD.scn is one head (``phyllotaxis``, Ridley's model on the receptacle, ``ca:``
windows ranked from the rim inward: the phase effect within a head). INVOLUCRE.scn (optional, with
RECEPTACLE.obj) is one head's involucral bracts (``phyllotaxis`` on a ``sphere_cap`` whose centre,
phyllotaxis's (0, -radius, 0), is moved to the head's origin: a sphere round the receptacle), and
RECEPTACLE.obj the receptacle the head's florets stand on (``phyllotaxis`` ``[receptacle]`` of the
head, in the head's units).

The canopy's clock (FRAMES frames, 0 .. FRAMES - 1):

- canopy frame 0 is the pattern frame before the first head emerges (the RBA frames before it hold
  no head and are left out); canopy frame k is that pattern frame + k;
- after the pattern's last frame the pattern is held (no further head forms, nothing grows) while
  the last heads open; ``heads/pattern_end.txt`` holds that canopy frame (branch-gen's growth of
  space stops there: the Makefile writes it into the branch parameters as ``[growth] frames``);
- head h emerges (as a bud) at its first canopy frame E_h; its florets' windows are the head's
  ``ca:`` windows shifted by E_h + BUD: the first heads open first, each from its rim inward.

With ``--dome D``, ``--jitter J``, ``--late L`` (default 0: the pattern's plane) the heads stand at
their heights in a low convex cap, every frame (:func:`lift_heads`; issue 43): the rim heads D
mean head diameters below the centre, each head up to J of its own diameter higher or lower
(seeded), the heads born in the pattern's last frame L diameters lower still.

Writes under OUT_DIR, atomically per file:

- ``heads/scene.scn`` + ``heads/rba/`` (FRAMES files): the heads on the canopy's clock, for
  ``branch-gen --rba`` (one particle per head, the peduncles ending at the heads' centres);
- ``corymb/scene.scn`` + ``corymb/rba/`` (FRAMES files): every floret of every head as one flat
  scene (``rba:`` placements; group 0 the corymb, centred at the origin; group h + 1 head h,
  centred where the head stands at the last frame), each floret's RBA row the head's RBA pose
  times the floret's pose in HEAD.scn scaled by HEAD_SCALE. One flat scene so that ``dimorph``
  decides the ray florets over the whole corymb (fig. 6.4a: cones of every floret against the
  florets of every head) and ``fccompose`` runs every floret in one simulation. With INVOLUCRE.scn
  each head's placements are its florets, then its bracts (ids ``h * n + j``, n = florets + bracts
  of a head), the bracts' windows those of INVOLUCRE.scn shifted by the head's emergence (they
  enclose the head's buds from its emergence and spread as it opens); the bracts lie farther from
  the head's centre than its florets, so ``dimorph --bracts`` types them (the outermost of each
  head);
- ``receptacles/frame_NNNN.obj`` (FRAMES files, with RECEPTACLE.obj): every head's receptacle on
  its pose in that frame, scaled as its florets (a group ``receptacle_H`` per head, its faces from
  the head's emergence on; before it, its vertices rest on the head's first pose: the vertex count
  and order are those of every frame, as formats/obj.md asks of a sequence);
- with RECEPTACLE.obj, the receptacles as **obstacles** of the canopy (formats/fcc.md
  "Obstacles": fixed parts the florets and bracts collide with, not written): an ``rba:``
  placement per head (id 3, ``#@ type: obstacle``, its window from the head's emergence) in
  ``corymb/receptacles.scn``, its RBA row (id ``n_heads * n + h``, after every floret and bract) in
  every ``corymb/rba`` frame from the head's emergence, the pose of ``receptacles/``; ``--obstacles``
  appends these placements to dimorph's typed scene (dimorph types florets, not receptacles).
"""
from __future__ import annotations

import copy
import sys
from pathlib import Path

import numpy as np

from inflo.formats.atomic import write_text_atomic
from inflo.formats.obj import ObjMesh, read_obj, write_obj
from inflo.formats.placement import placement_matrix
from inflo.formats.rba import RbaFrame, list_rba_sequence, read_rba, write_rba
from inflo.formats.scn import Group, Scene, read_scn, write_scn
from inflo.tools.common import linalg as la

#: the animation id of the receptacles' obstacle placements (yarrow.fcc)
OBSTACLE_ID = 3


def canopy_clock(frames_in: list, n: int) -> tuple[list, int]:
    """The pattern's RBA frames on the canopy's clock: ``n`` frames from the one before the first
    head emerges, the last pattern frame held after it; and that first pattern frame."""
    first = next((i for i, f in enumerate(frames_in) if len(f)), None)
    if first is None:
        raise SystemExit("corymb_heads.py: the pattern has no head in any RBA frame")
    start = max(first - 1, 0)
    seq = list(frames_in[start:start + n])
    while len(seq) < n:
        seq.append(frames_in[-1])
    return seq, start


#: the horizontal reach of a head's involucre (the bracts' bases on the sphere of radius 1.06, at
#: most 104 degrees from its pole: 1.06 sin 104) in head units, beyond its receptacle's rim (1)
INVOLUCRE_REACH = 1.03


def drop_engulfed(scene: Scene, seq: list, reach: float) -> tuple[Scene, list, list]:
    """The pattern without the heads that form within an older head's body: in some frame head b
    stands closer to an older head a (emerged earlier, or as early and larger) than ``reach`` x
    (size a + size b), the two involucres' reach (head scale x 1.03 head units each). The final
    pattern's last cohort forms two heads so (pattern placements 27 and 50: 0.61 and 0.90 of that
    distance from heads 13 and 37, the smaller head more than half under the larger one's florets),
    where a receptacle and bracts of one head stand in the other's receptacle: no collision
    response can part them (their bases are fixed). Such a primordium aborts; the others keep their
    poses. Returns the scene and frames renumbered (RBA ids are scene indices) and the dropped
    placements' indices."""
    first = {}
    for k, f in enumerate(seq):
        for i, pid in enumerate(f.ids):
            first.setdefault(int(pid), (k, -float(f.scale[i, 0])))
    kept, dropped = [], []
    for pid in sorted(first, key=lambda q: (first[q], q)):
        bad = False
        for f in seq:
            r = f.index(pid)
            if r is None:
                continue
            for q in kept:
                rq = f.index(q)
                if rq is not None and la.norm(f.pos[r] - f.pos[rq]) < reach * (f.scale[r, 0] + f.scale[rq, 0]):
                    bad = True
                    break
            if bad:
                break
        (dropped if bad else kept).append(pid)
    if not dropped:
        return scene, seq, []
    keep = sorted(kept)
    new_id = {old: i for i, old in enumerate(keep)}
    out = Scene(groups=copy.deepcopy(scene.groups))
    out.placements = [copy.deepcopy(scene.placements[i]) for i in keep]
    frames = []
    for f in seq:
        rows = [i for i, pid in enumerate(f.ids) if int(pid) in new_id]
        frames.append(RbaFrame(np.array([new_id[int(f.ids[i])] for i in rows], np.int32), f.pos[rows], f.scale[rows],
                               f.up[rows], f.right[rows]))
    return out, frames, sorted(dropped)


def lift_heads(seq: list, head_scale: float, dome: float, jitter: float, seed: int = 0, late: float = 0.0,
               end: int | None = None) -> list:
    """The heads at their heights in the cap (issue 43, one closed corymb): the pattern is flat
    (recursive segregation on a plane, fig. 5.3); a real corymb is a low convex cap whose heads
    stand at slightly different heights, one head's rays over its neighbour's. Head h is lowered by
    ``dome`` x D x (r_h / R)^2 (a paraboloid: r_h its distance in the plane from the heads'
    centroid in the last frame, R the farthest head's, D the heads' mean disc diameter there, 2 x
    ``head_scale`` x the pattern's mean size) and raised by ``jitter`` x its own disc diameter x
    u_h, u_h uniform in [-1, 1] (seeded by ``seed``, one draw per pattern placement). The heads
    that form in frame ``end`` or later (the pattern's last frame: they are born at their full size
    among open older heads, where the heads formed before grew into their room with the meristem)
    stand ``late`` x D lower still: the youngest heads of a corymb sit below the older ones, whose
    open rays spread over them rather than through their receptacles. A head keeps
    that height in every frame: the meristem grows in its plane only (branches.toml's growth has
    no Y rate), so the peduncles, grown by branch-gen on the same frames, meet their heads without
    a kink. Returns new frames (positions changed in Y only)."""
    if not seq or (dome == 0.0 and jitter == 0.0 and (late == 0.0 or end is None)):
        return seq
    last = seq[-1]
    xz = last.pos[:, [0, 2]]
    centre = xz.mean(axis=0)
    r2 = ((xz - centre) ** 2).sum(axis=1)
    reach2 = float(r2.max()) or 1.0
    own = 2.0 * head_scale * last.scale[:, 0]
    u = np.random.default_rng(seed).uniform(-1.0, 1.0, len(last.ids))
    order = np.argsort(np.asarray(last.ids, np.int64), kind="stable")  # draws in placement order
    draw = np.empty(len(u))
    draw[order] = u
    lift = -dome * float(own.mean()) * r2 / reach2 + jitter * own * draw
    if late and end is not None:
        born = {}
        for k, f in enumerate(seq):
            for pid in f.ids:
                born.setdefault(int(pid), k)
        lift = lift - late * float(own.mean()) * np.array([born[int(pid)] >= end for pid in last.ids], float)
    height = {int(pid): float(lift[i]) for i, pid in enumerate(last.ids)}
    out = []
    for f in seq:
        pos = f.pos.copy()
        if len(pos):
            pos[:, 1] += np.array([height[int(pid)] for pid in f.ids])
        out.append(RbaFrame(f.ids, pos, f.scale, f.up, f.right))
    return out


def sphere_centre(inv: Scene) -> np.ndarray:
    """The centre of the sphere the involucre's placements lie on (phyllotaxis's ``sphere_cap``:
    (0, -radius, 0), the pole at the origin), from the placements: the point on the axis equally
    far from all of them."""
    pos = inv.arrays()["pos"]
    r2 = pos[:, 0] ** 2 + pos[:, 2] ** 2
    # |p - (0, c, 0)|^2 = R^2 for every p: r2 + y^2 = c (2 y) + (R^2 - c^2), a straight line in 2 y;
    # its least-squares slope c from the centred sums (fixed-order sums: no LAPACK lstsq)
    x = 2.0 * pos[:, 1]
    b = r2 + pos[:, 1] ** 2
    dx = x - np.add.reduce(x) / len(x)
    c = la.dot(dx, b - np.add.reduce(b) / len(b)) / la.dot(dx, dx)
    return np.array([0.0, c, 0.0])


def receptacle_frames(mesh: ObjMesh, out: Path, n_heads: int, first_id: int, n: int) -> None:
    """``receptacles/frame_NNNN.obj``: ``mesh`` (the head's units) under every head, on the RBA row of
    its receptacle's obstacle placement (id ``first_id + h``) in ``corymb/rba/NNNN.rba`` as written
    (six decimals) and read back: the very poses from which fccompose places the obstacles, so the
    check tests the florets against the receptacles they were kept off; written with nine decimals
    (before, poses carried in memory and six decimals put a vertex the canopy had left touching a
    receptacle 6e-8 inside it: one canopy-receptacle pair at final frame 84). A head not yet
    emerged keeps its vertices on its first row, without faces."""
    nv, nf = mesh.n_vertices, mesh.n_faces
    hv = np.hstack([mesh.vertices, np.ones((nv, 1))])
    mats = []
    for k in range(n):
        f = read_rba(out / "corymb" / "rba" / f"{k:04d}.rba")
        rows = [f.index(first_id + h) for h in range(n_heads)]
        mats.append([None if r is None else f.matrix(r) for r in rows])
    first = [next(m[h] for m in mats if m[h] is not None) for h in range(n_heads)]
    for k in range(n):
        verts, faces, group = [], [], []
        for h in range(n_heads):
            M = mats[k][h]
            verts.append(la.matmul(hv, (first[h] if M is None else M).T)[:, :3])
            if M is not None:
                faces.append(mesh.faces + h * nv)
                group.append(np.full(nf, h, np.int32))
        faces = np.vstack(faces) if faces else np.zeros((0, 3), np.int32)
        group = np.concatenate(group) if group else np.zeros(0, np.int32)
        m = ObjMesh(np.vstack(verts), faces, groups=[f"receptacle_{h}" for h in range(n_heads)],
                    face_group=group, materials=list(mesh.materials[:1]) or ["mtl5"],
                    face_material=np.zeros(len(faces), np.int32))
        write_obj(out / "receptacles" / f"frame_{k:04d}.obj", m, mtllib=None, fmt="%.9f",
                  header=f"yarrow receptacles, frame {k}: {len(set(group.tolist()))} of {n_heads} heads "
                         "(corymb_heads.py)")


def main(pattern: Path, head_path: Path, n: int, head_scale: float, bud: int, out: Path,
         involucre_path: Path | None = None, receptacle_path: Path | None = None,
         dome: float = 0.0, jitter: float = 0.0, late: float = 0.0) -> int:
    scene = read_scn(pattern / "scene.scn")
    frames_in = [read_rba(p) for p in list_rba_sequence(pattern / "rba")]
    head = read_scn(head_path)
    bracts = []
    if involucre_path is not None:
        inv = read_scn(involucre_path)
        centre = sphere_centre(inv)  # moved to the head's origin
        bracts = [copy.deepcopy(q) for q in inv.placements]
        for q in bracts:
            q.pos = q.pos - centre
    seq, start = canopy_clock(frames_in, n)
    if involucre_path is not None:
        scene, seq, dropped = drop_engulfed(scene, seq, head_scale * INVOLUCRE_REACH)
        if dropped:
            print(f"corymb_heads.py: {len(dropped)} heads formed within an older head's involucre left out "
                  f"(pattern placements {', '.join(map(str, dropped))})")
    seq = lift_heads(seq, head_scale, dome, jitter, late=late, end=min(len(frames_in) - 1 - start, n - 1))
    emerged = {}
    for k, f in enumerate(seq):
        for pid in f.ids:
            emerged.setdefault(int(pid), k)
    heads = sorted(emerged)  # the heads present within the canopy's frames
    lastf = seq[-1]

    # the heads on the canopy's clock (branch-gen)
    hs = Scene(groups=copy.deepcopy(scene.groups))
    for pid in range(len(scene)):
        p = copy.deepcopy(scene.placements[pid])
        if pid in emerged:
            row = lastf.index(pid)
            p.pos = lastf.pos[row].copy()
            p.frame_start, p.frame_end = emerged[pid], n - 1
            p.emergence = float(max((p.emergence or 0.0) - start, 0.0))
        hs.placements.append(p)
    write_scn(out / "heads" / "scene.scn", hs, header=f"the heads of {pattern.name}/scene.scn on the canopy's "
              f"clock: pattern frame {start} = canopy frame 0, {n} frames (corymb_heads.py)")
    for k, f in enumerate(seq):
        write_rba(out / "heads" / "rba" / f"{k:04d}.rba", f)
    end = min(len(frames_in) - 1 - start, n - 1)
    write_text_atomic(out / "heads" / "pattern_end.txt", f"{end}\n")

    # every floret of every head, then its bracts: one flat scene
    members = list(head.placements) + bracts
    local = np.array([placement_matrix(p.pos * head_scale, p.scale * head_scale, p.up, p.right) for p in members])
    nflo = len(head)
    flat = Scene()
    flat.groups[0] = Group(0, np.zeros(3), -1)
    for h, pid in enumerate(heads):
        row = lastf.index(pid)
        flat.groups[h + 1] = Group(h + 1, lastf.pos[row].copy(), 0)
        head_m = la.matmul(placement_matrix(lastf.pos[row], lastf.scale[row], lastf.up[row], lastf.right[row]), local)
        for j, q in enumerate(members):
            M = head_m[j]
            s = la.norm(M[:3, 1])
            delay = bud if j < nflo else 0  # a head's bracts enclose it from its emergence
            fs = emerged[pid] + delay + int(q.frame_start)
            fe = emerged[pid] + delay + int(q.frame_end)
            flat.placements.append(copy.deepcopy(q))
            p = flat.placements[-1]
            p.kind, p.pos, p.scale = "rba", M[:3, 3].copy(), np.ones(3)
            p.up, p.right = M[:3, 1] / s, M[:3, 0] / s
            p.frame_start, p.frame_end, p.group = fs, fe, h + 1
            p.emergence = float(emerged[pid])
            p.interpolation = None
    nf = len(members)
    # with RECEPTACLE.obj: every head's receptacle is also an obstacle placement of the canopy
    # (formats/fcc.md "Obstacles": fixed, simulated, not written), ids n_heads * nf + h after every
    # floret and bract, its RBA row the head's pose scaled by head_scale (the geometry of
    # receptacles/frame_NNNN.obj); corymb/receptacles.scn holds these placements, which
    # ``corymb_heads.py --obstacles`` appends to the typed scene after dimorph
    obstacles = Scene()
    obstacles.groups = copy.deepcopy(flat.groups)
    rec_local = placement_matrix(np.zeros(3), np.full(3, head_scale), np.array([0.0, 1.0, 0.0]),
                                 np.array([1.0, 0.0, 0.0]))
    if receptacle_path is not None:
        for h, pid in enumerate(heads):
            row = lastf.index(pid)
            M = la.matmul(placement_matrix(lastf.pos[row], lastf.scale[row], lastf.up[row], lastf.right[row]), rec_local)
            q = copy.deepcopy(flat.placements[h * nf])
            q.kind, q.id, q.pos, q.scale = "rba", OBSTACLE_ID, M[:3, 3].copy(), np.ones(3)
            q.up, q.right = M[:3, 1] / la.norm(M[:3, 1]), M[:3, 0] / la.norm(M[:3, 0])
            q.frame_start, q.frame_end, q.group = int(emerged[pid]), int(emerged[pid]) + 1, h + 1
            q.emergence, q.type, q.petal, q.interpolation = float(emerged[pid]), "obstacle", None, None
            obstacles.placements.append(q)
    for k, f in enumerate(seq):
        ids, pos, scale, up, right = [], [], [], [], []
        poses = [None] * len(heads)  # the heads' poses in this frame (None: not emerged yet)
        for h, pid in enumerate(heads):
            row = f.index(pid)
            if row is None:
                continue
            H = placement_matrix(f.pos[row], f.scale[row], f.up[row], f.right[row])
            poses[h] = H
            m = la.matmul(H, local)  # every floret and bract of the head at once
            s = la.norm(m[:, :3, 1], axis=1)[:, None]
            ids.extend(range(h * nf, h * nf + nf))
            pos.append(m[:, :3, 3])
            scale.append(np.repeat(s, 3, axis=1))
            up.append(m[:, :3, 1] / s)
            right.append(m[:, :3, 0] / s)
        if receptacle_path is not None:
            for h in range(len(heads)):
                if poses[h] is None:
                    continue
                M = la.matmul(poses[h], rec_local)
                s = la.norm(M[:3, 1])
                ids.append(len(heads) * nf + h)
                pos.append(M[None, :3, 3])
                scale.append(np.full((1, 3), s))
                up.append(M[None, :3, 1] / s)
                right.append(M[None, :3, 0] / s)
        write_rba(out / "corymb" / "rba" / f"{k:04d}.rba",
                  RbaFrame(ids, *(np.concatenate(x) if x else np.zeros((0, 3)) for x in (pos, scale, up, right))),
                  fast=True)
    inv_note = f" + {len(bracts)} bracts of {involucre_path.name}" if bracts else ""
    write_scn(out / "corymb" / "scene.scn", flat,
              header=f"{len(heads)} heads x {nflo} florets of {head_path.name}{inv_note}, head scale {head_scale:g}, "
                     f"on the canopy's clock ({n} frames; corymb_heads.py)")
    if receptacle_path is not None:
        write_scn(out / "corymb" / "receptacles.scn", obstacles,
                  header=f"the receptacles of the {len(heads)} heads as obstacles (id {OBSTACLE_ID}; corymb_heads.py): "
                         "appended to the typed scene after dimorph")
        receptacle_frames(read_obj(receptacle_path), out, len(heads), len(heads) * nf, n)
    first = sorted(emerged.values())
    print(f"corymb_heads.py: {len(heads)} heads x {nflo} florets{inv_note}; pattern frames {start}-{len(frames_in) - 1} "
          f"= canopy frames 0-{end}, then held to frame {n - 1}; heads emerge at canopy "
          f"frames {first[0]}-{first[-1]}")
    return 0


def append_obstacles(typed_path: Path, obstacles_path: Path, out: Path) -> int:
    """``--obstacles TYPED.scn RECEPTACLES.scn OUT.scn``: the typed scene (dimorph's) with the
    receptacles' obstacle placements after its florets and bracts (their RBA ids follow them)."""
    typed, obst = read_scn(typed_path), read_scn(obstacles_path)
    typed.placements.extend(obst.placements)
    write_scn(out, typed, header=f"{typed_path.name} (dimorph) + the {len(obst)} receptacles of "
                                 f"{obstacles_path.name} as obstacles (corymb_heads.py --obstacles)")
    return 0


def cli(argv: list) -> int:
    """Parse ``PATTERN_DIR HEAD.scn FRAMES HEAD_SCALE BUD OUT_DIR [INVOLUCRE.scn RECEPTACLE.obj]``
    (the usage line on a wrong count)."""
    if argv[:1] == ["--obstacles"] and len(argv) == 4:
        return append_obstacles(Path(argv[1]), Path(argv[2]), Path(argv[3]))
    try:
        argv, lift = list(argv), {"dome": 0.0, "jitter": 0.0, "late": 0.0}
        for key in lift:
            if f"--{key}" in argv:
                i = argv.index(f"--{key}")
                lift[key] = float(argv[i + 1])
                del argv[i:i + 2]
        if len(argv) not in (6, 8):
            raise ValueError
        pattern, head, n, scale, bud, out = argv[:6]
        extra = tuple(Path(a) for a in argv[6:])
        args = (Path(pattern), Path(head), int(n), float(scale), int(bud), Path(out)) + extra
    except (ValueError, IndexError):
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    return main(*args, **lift)


if __name__ == "__main__":
    sys.exit(cli(sys.argv[1:]))
