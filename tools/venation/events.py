"""The developmental sequence of a growing leaf's venation read from ``events.csv``, and where it
departs from the sequence observed in the first leaf of *Arabidopsis thaliana* (Runions sec. 5.3,
after Scarpella et al.): the midvein; the first pair of loops (lower halves, then upper halves);
a second pair; a third pair near the base; then higher-order veins and blindly terminating veins.

A loop of secondary veins is a loop of order 1 that runs along the midvein (``midvein`` 1 in
events.csv, formats/venation.md). Two such loops on opposite sides of the midvein, formed within
``window`` iterations of each other with centroids within ``dy`` x the height spanned by the
secondary loops, are a pair. :func:`departures` says, in words, where a run's order differs from
the observed one (the thesis's own report of its local-to-global run, sec. 5.3.1: "the upper half
of the first pair of loops and the second pair of loops form simultaneously").
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Event", "read_events", "secondary_pairs", "departures", "summary"]


@dataclass(frozen=True)
class Event:
    iteration: int
    event: str
    index: int
    x: float
    y: float
    order: int | None
    midvein: bool


def read_events(path) -> list[Event]:
    """The rows of an ``events.csv`` (formats/venation.md)."""
    out = []
    with open(Path(path), newline="") as fh:
        for row in csv.DictReader(fh):
            order = row.get("order") or ""
            out.append(Event(int(row["iteration"]), row["event"], int(row["index"]), float(row["x"]), float(row["y"]),
                             int(order) if order else None, (row.get("midvein") or "") == "1"))
    return out


def _secondary(events) -> list[Event]:
    return [e for e in events if e.event == "loop" and e.order == 1 and e.midvein]


def secondary_pairs(events, window: int = 5, dy: float = 0.1) -> tuple[list[tuple[Event, Event]], list[Event]]:
    """(pairs in order of formation, unpaired secondary loops): loops of secondary veins on opposite
    sides of the midvein, formed within ``window`` iterations, their centroids within ``dy`` x the
    height the secondary loops span (greedy, earliest first)."""
    sec = _secondary(events)
    if not sec:
        return [], []
    ys = [e.y for e in sec]
    tol = dy * max(max(ys) - min(ys), max(abs(y) for y in ys), 1e-12)
    used = [False] * len(sec)
    pairs, single = [], []
    for i, a in enumerate(sec):
        if used[i]:
            continue
        best = None
        for j in range(i + 1, len(sec)):
            b = sec[j]
            if b.iteration - a.iteration > window:
                break
            if not used[j] and (a.x < 0) != (b.x < 0) and abs(a.y - b.y) <= tol:
                best = j
                break
        if best is None:
            single.append(a)
        else:
            used[i] = used[best] = True
            pairs.append((a, sec[best]))
    return pairs, single


def departures(events, window: int = 5, dy: float = 0.1) -> list[str]:
    """Where the run's developmental order departs from the observed one (empty: none)."""
    out = []
    mid = [e for e in events if e.event == "midvein"]
    loops = [e for e in events if e.event == "loop"]
    if not mid:
        out.append("no midvein formed")
    elif loops and loops[0].iteration <= mid[0].iteration:
        out.append(f"a loop formed at iteration {loops[0].iteration}, before the midvein ({mid[0].iteration})")
    pairs, single = secondary_pairs(events, window, dy)
    first3 = pairs[:3]
    if len(pairs) < 3:
        out.append(f"{len(pairs)} pairs of secondary loops formed, not three")
    for k in range(1, len(first3)):
        gap = min(e.iteration for e in first3[k]) - max(e.iteration for e in first3[k - 1])
        if gap <= window:
            out.append(f"pair {k + 1} of secondary loops formed with pair {k} (iterations "
                       f"{first3[k - 1][0].iteration}-{first3[k][1].iteration}), not after it")
    early_single = [e for e in single if first3 and e.iteration <= first3[-1][1].iteration]
    if early_single:
        out.append(f"{len(early_single)} secondary loops formed unpaired before the third pair "
                   f"(loops {', '.join(str(e.index) for e in early_single[:6])})")
    if len(first3) == 3:
        ys = [0.5 * (a.y + b.y) for a, b in first3]
        if not ys[2] < min(ys[0], ys[1]):
            out.append(f"the third pair (y {ys[2]:.3g}) is not the nearest the base (pairs at y {ys[0]:.3g}, {ys[1]:.3g})")
        end3 = first3[2][1].iteration
        higher = [e for e in events if e.event in ("loop", "blind_end") and not (e.event == "loop" and e.order == 1
                                                                                   and e.midvein)]
        early = [e for e in higher if e.iteration < end3]
        if early:
            out.append(f"{len(early)} higher-order veins or blind veins formed before the third pair "
                       f"(first at iteration {early[0].iteration})")
    return out


def summary(events, window: int = 5, dy: float = 0.1) -> str:
    """A few lines: the midvein, the pairs of secondary loops (iterations, heights), higher-order
    loops and blind veins, and the departures from the observed order."""
    lines = []
    mid = [e for e in events if e.event == "midvein"]
    if mid:
        lines.append(f"midvein: iteration {mid[0].iteration}")
    pairs, single = secondary_pairs(events, window, dy)
    for k, (a, b) in enumerate(pairs, 1):
        lines.append(f"secondary loop pair {k}: iterations {a.iteration}/{b.iteration}, y {0.5 * (a.y + b.y):.3g}")
    if single:
        lines.append(f"unpaired secondary loops: {len(single)} (first at iteration {single[0].iteration})")
    other = [e for e in events if e.event == "loop" and not (e.order == 1 and e.midvein)]
    if other:
        lines.append(f"other loops: {len(other)} (first at iteration {other[0].iteration})")
    blind = [e for e in events if e.event == "blind_end"]
    if blind:
        lines.append(f"blind veins: {len(blind)} (first at iteration {blind[0].iteration})")
    dep = departures(events, window, dy)
    lines.append("departures from the observed order: " + ("none" if not dep else "; ".join(dep)))
    return "\n".join(lines)


if __name__ == "__main__":  # pragma: no cover
    import sys

    print(summary(read_events(sys.argv[1])))
