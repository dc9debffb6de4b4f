"""The per-frame log of ``fccompose``: ``OUT_DIR/log.csv`` (one row per simulated frame).

Columns (fixed number formats; the times are wall-clock and so differ between runs, everything
else is deterministic):

| column | meaning |
| --- | --- |
| frame | frame number (0: the initial state) |
| steps | simulation steps in the frame (``updates per frame``) |
| rms_edge_error | RMS of edge length minus rest length at the end of the frame, scene units |
| rms_dihedral_error_deg | RMS of the wrapped signed dihedral angle error, degrees |
| vt_candidates, ee_candidates | broad-phase pairs of the first detection round, summed over steps |
| collisions_found | pairs needing a response found in the first round, summed over steps |
| collision_rounds | detection rounds, summed over steps |
| collision_constraints | collision constraints solved, summed over steps |
| remaining_pairs | pairs still crossing after the last retry of the deepest substep (reported; their florets moved back) |
| remaining_florets | those pairs as ``floretA-floretB`` (placement indices), ``;``-separated |
| reverted_vertices | vertices of the florets the fallback moved back along their motion |
| intersecting_pairs | triangle pairs found by the exact static test (-1: not checked this frame) |
| florets_present | florets in the canopy at the end of the frame (``rba:`` florets emerge at their first RBA frame) |
| florets_waiting | florets due to emerge that found no room yet, at any of the ``emergence scales`` (tried again every step) |
| florets_smaller | florets that emerged smaller than their own size and are still growing back to it |
| min_edge_stretch, max_edge_stretch | smallest and largest edge length / rest length at the end of the frame (edges whose rest length is at least the collision thickness h); the ``edge stretch bounds`` (default 0.5, 1.5) hold them |
| substeps | steps redone as two half steps (crossing pairs or an edge out of bounds), summed over the frame's steps |
| relax_sweeps | internal-constraint sweeps of florets in contact between collision rounds |
| florets_retreated | florets moved back along their own motion by the fallback |
| t_rest_s, t_internal_s, t_collide_s, t_sanity_s, t_write_s | seconds per phase |
"""
from __future__ import annotations

import csv
import io
from pathlib import Path

from inflo.formats.atomic import write_text_atomic

__all__ = ["COLUMNS", "FrameLog", "read_log", "write_log"]

COLUMNS = [
    "frame", "steps", "rms_edge_error", "rms_dihedral_error_deg", "vt_candidates", "ee_candidates",
    "collisions_found", "collision_rounds", "collision_constraints", "remaining_pairs",
    "remaining_florets", "reverted_vertices", "intersecting_pairs", "florets_present", "florets_waiting",
    "florets_smaller", "min_edge_stretch", "max_edge_stretch", "substeps", "relax_sweeps", "florets_retreated",
    "t_rest_s", "t_internal_s",
    "t_collide_s", "t_sanity_s", "t_write_s",
]

_FORMATS = {
    "rms_edge_error": "{:.6e}",
    "rms_dihedral_error_deg": "{:.6f}",
    "min_edge_stretch": "{:.4f}",
    "max_edge_stretch": "{:.4f}",
    "t_rest_s": "{:.4f}",
    "t_internal_s": "{:.4f}",
    "t_collide_s": "{:.4f}",
    "t_sanity_s": "{:.4f}",
    "t_write_s": "{:.4f}",
}


class FrameLog(dict):
    """One row: a dict of the columns, zero-initialised."""

    def __init__(self, frame: int, steps: int = 0):
        super().__init__({c: 0 for c in COLUMNS})
        self["frame"] = frame
        self["steps"] = steps
        self["remaining_florets"] = ""
        self["intersecting_pairs"] = -1

    def text(self) -> list[str]:
        return [_FORMATS.get(c, "{}").format(self[c]) if not isinstance(self[c], str) else self[c]
                for c in COLUMNS]


def write_log(path, rows) -> None:
    """Write every row (FrameLog or already-formatted lists) atomically."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    for r in rows:
        w.writerow(r.text() if isinstance(r, FrameLog) else r)
    write_text_atomic(path, buf.getvalue())


def read_log(path) -> list[list[str]]:
    """Rows of an existing log (as text), without the header; [] when absent."""
    p = Path(path)
    if not p.is_file():
        return []
    with open(p, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[1:] if rows and rows[0] == COLUMNS else []
