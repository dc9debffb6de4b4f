"""The yarrow's heads on one clock: the growing corymb pattern and every head's florets (the
`corymb` stage's last step).

Usage: python corymb_heads.py PATTERN_DIR HEAD.scn FRAMES HEAD_SCALE BUD OUT_DIR

PATTERN_DIR is a dynamic recursive-segregation pattern (``phyllotaxis``, ``[hierarchy]`` with
``dynamic = true``, thesis sec. 5.4, fig. 5.3): ``scene.scn`` (one ``rba:`` placement per head) and
``rba/NNNN.rba`` (the heads that have emerged by frame NNNN, their positions and sizes as the flat
meristem grows). HEAD.scn is one head (``phyllotaxis``, Ridley's model on the receptacle, ``ca:``
windows ranked from the rim inward: the phase effect within a head).

The canopy's clock (FRAMES frames, 0 .. FRAMES - 1):

- canopy frame 0 is the pattern frame before the first head emerges (the RBA frames before it hold
  no head and are left out); canopy frame k is that pattern frame + k;
- after the pattern's last frame the pattern is held (no further head forms, nothing grows) while
  the last heads open; ``heads/pattern_end.txt`` holds that canopy frame (branch-gen's growth of
  space stops there: the Makefile writes it into the branch parameters as ``[growth] frames``);
- head h emerges (as a bud) at its first canopy frame E_h; its florets' windows are the head's
  ``ca:`` windows shifted by E_h + BUD: the first heads open first, each from its rim inward.

Writes under OUT_DIR, atomically per file:

- ``heads/scene.scn`` + ``heads/rba/`` (FRAMES files): the heads on the canopy's clock, for
  ``branch-gen --rba`` (one particle per head, the peduncles ending at the heads' centres);
- ``corymb/scene.scn`` + ``corymb/rba/`` (FRAMES files): every floret of every head as one flat
  scene (``rba:`` placements; group 0 the corymb, centred at the origin; group h + 1 head h,
  centred where the head stands at the last frame), each floret's RBA row the head's RBA pose
  times the floret's pose in HEAD.scn scaled by HEAD_SCALE. One flat scene so that ``dimorph``
  decides the ray florets over the whole corymb (fig. 6.4a: cones of every floret against the
  florets of every head) and ``fccompose`` runs every floret in one simulation.
"""
from __future__ import annotations

import copy
import sys
from pathlib import Path

import numpy as np

from inflo.formats.atomic import write_text_atomic
from inflo.formats.placement import placement_matrix
from inflo.formats.rba import RbaFrame, list_rba_sequence, read_rba, write_rba
from inflo.formats.scn import Group, Scene, read_scn, write_scn


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


def main(pattern: Path, head_path: Path, n: int, head_scale: float, bud: int, out: Path) -> int:
    scene = read_scn(pattern / "scene.scn")
    frames_in = [read_rba(p) for p in list_rba_sequence(pattern / "rba")]
    head = read_scn(head_path)
    seq, start = canopy_clock(frames_in, n)
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
    write_scn(out / "heads" / "scene.scn", hs, header=f"the heads of {pattern / 'scene.scn'} on the canopy's "
              f"clock: pattern frame {start} = canopy frame 0, {n} frames (corymb_heads.py)")
    for k, f in enumerate(seq):
        write_rba(out / "heads" / "rba" / f"{k:04d}.rba", f)
    end = min(len(frames_in) - 1 - start, n - 1)
    write_text_atomic(out / "heads" / "pattern_end.txt", f"{end}\n")

    # every floret of every head: one flat scene
    local = [placement_matrix(p.pos * head_scale, p.scale * head_scale, p.up, p.right) for p in head.placements]
    flat = Scene()
    flat.groups[0] = Group(0, np.zeros(3), -1)
    for h, pid in enumerate(heads):
        row = lastf.index(pid)
        flat.groups[h + 1] = Group(h + 1, lastf.pos[row].copy(), 0)
        for j, q in enumerate(head.placements):
            M = placement_matrix(lastf.pos[row], lastf.scale[row], lastf.up[row], lastf.right[row]) @ local[j]
            s = float(np.linalg.norm(M[:3, 1]))
            fs = emerged[pid] + bud + int(q.frame_start)
            fe = emerged[pid] + bud + int(q.frame_end)
            flat.placements.append(copy.deepcopy(q))
            p = flat.placements[-1]
            p.kind, p.pos, p.scale = "rba", M[:3, 3].copy(), np.ones(3)
            p.up, p.right = M[:3, 1] / s, M[:3, 0] / s
            p.frame_start, p.frame_end, p.group = fs, fe, h + 1
            p.emergence = float(emerged[pid])
            p.interpolation = None
    nf = len(head)
    for k, f in enumerate(seq):
        ids, pos, scale, up, right = [], [], [], [], []
        for h, pid in enumerate(heads):
            row = f.index(pid)
            if row is None:
                continue
            H = placement_matrix(f.pos[row], f.scale[row], f.up[row], f.right[row])
            for j in range(nf):
                M = H @ local[j]
                s = float(np.linalg.norm(M[:3, 1]))
                ids.append(h * nf + j)
                pos.append(M[:3, 3])
                scale.append((s, s, s))
                up.append(M[:3, 1] / s)
                right.append(M[:3, 0] / s)
        write_rba(out / "corymb" / "rba" / f"{k:04d}.rba",
                  RbaFrame(ids, np.reshape(pos, (-1, 3)), np.reshape(scale, (-1, 3)), np.reshape(up, (-1, 3)),
                           np.reshape(right, (-1, 3))), fast=True)
    write_scn(out / "corymb" / "scene.scn", flat,
              header=f"{len(heads)} heads x {nf} florets of {head_path.name}, head scale {head_scale:g}, on the "
                     f"canopy's clock ({n} frames; corymb_heads.py)")
    first = sorted(emerged.values())
    print(f"corymb_heads.py: {len(heads)} heads x {nf} florets; pattern frames {start}-{len(frames_in) - 1} "
          f"= canopy frames 0-{end}, then held to frame {n - 1}; heads emerge at canopy "
          f"frames {first[0]}-{first[-1]}")
    return 0


def cli(argv: list) -> int:
    """Parse ``PATTERN_DIR HEAD.scn FRAMES HEAD_SCALE BUD OUT_DIR`` (the usage line on a wrong count)."""
    try:
        pattern, head, n, scale, bud, out = argv
        args = (Path(pattern), Path(head), int(n), float(scale), int(bud), Path(out))
    except ValueError:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    return main(*args)


if __name__ == "__main__":
    sys.exit(cli(sys.argv[1:]))
