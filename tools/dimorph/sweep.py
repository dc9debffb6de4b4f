"""Canalization of ray floret numbers (thesis figs. 6.2 and 6.3): ``dimorph sweep``.

A simple head (Ridley's pattern on a flat disk with constant primordium area and divergence
137.5 degrees, i.e. Vogel's spiral; thesis sec. 6.2) of n florets; a floret is a ray floret when
its cone holds no other floret (d_min = infinity). Fig. 6.2: ray count N against n at a fixed
alpha; fig. 6.3: N against alpha at a fixed n. The counts concentrate on Fibonacci numbers.
"""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from inflo.formats.atomic import write_bytes_atomic, write_text_atomic
from inflo.tools.phyllotaxis.ridley import AreaFunction, static_pattern
from inflo.tools.phyllotaxis.surface import builtin_curve

from .cones import d_min

__all__ = ["FIBONACCI", "MAX_SWEEP_WORK", "simple_head", "ray_count", "sweep_n", "sweep_alpha", "sweep_work",
           "write_sweep"]

FIBONACCI = (1, 2, 3, 5, 8, 13, 21, 34, 55, 89, 144, 233, 377)

#: the most cone tests a sweep runs (about half a minute): see :func:`sweep_work`
MAX_SWEEP_WORK = 2e7


def _alpha_steps(alpha_range, alpha_step: float) -> int:
    return int(round((alpha_range[1] - alpha_range[0]) / alpha_step))


def sweep_work(n_range, n_fixed: int, alpha_range, alpha_step: float) -> float:
    """The work of a sweep in cone tests: each head of n florets costs max(n, 100)^1.5 (its rim
    florets, about sqrt(n), each examine every floret; 100: a small head's fixed cost); the n
    sweep has one head per n in ``n_range``, the alpha sweep one head of ``n_fixed`` per alpha."""
    ns = np.maximum(np.arange(int(n_range[0]), int(n_range[1]) + 1, dtype=np.float64), 100.0)
    steps = _alpha_steps(alpha_range, alpha_step) + 1
    return float(np.sum(ns ** 1.5)) + steps * max(float(n_fixed), 100.0) ** 1.5


def simple_head(n: int, divergence: float = 137.5) -> np.ndarray:
    """(n, 3) positions of a head of n equal primordia on a unit disk (eq. 5.2, r = s, A constant)."""
    prof = builtin_curve("disk", samples=4096)
    return static_pattern(prof, AreaFunction(np.pi / (n + 1), 1.0), divergence=divergence, count=n).pos


def ray_count(pos: np.ndarray, alpha: float, *, half_angle: bool = False) -> int:
    """Number of florets whose cone (apex angle ``alpha``, away from the origin) is empty."""
    return int(np.isinf(d_min(pos, np.zeros(3), alpha, half_angle=half_angle)).sum())


def sweep_n(ns, alpha: float = 75.0, *, divergence: float = 137.5, half_angle: bool = False) -> np.ndarray:
    """Fig. 6.2: (len(ns),) int64 ray counts N(n) at a fixed alpha."""
    return np.array([ray_count(simple_head(int(n), divergence), alpha, half_angle=half_angle) for n in ns],
                    dtype=np.int64)


def sweep_alpha(n: int, alphas, *, divergence: float = 137.5, half_angle: bool = False) -> np.ndarray:
    """Fig. 6.3: (len(alphas),) int64 ray counts N(alpha) for a head of n florets."""
    pos = simple_head(int(n), divergence)
    return np.array([ray_count(pos, float(a), half_angle=half_angle) for a in alphas], dtype=np.int64)


def _csv(xname: str, xs, counts, fixed: str) -> str:
    fib = set(FIBONACCI)
    rows = [f"# {fixed}", f"{xname},rays,fibonacci"]
    for x, c in zip(xs, counts):
        xv = f"{x:.6f}" if isinstance(x, float) else f"{int(x)}"
        rows.append(f"{xv},{int(c)},{int(int(c) in fib)}")
    return "\n".join(rows) + "\n"


def _plot(path: Path, xs, counts, xlabel: str, title: str, step: bool) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    counts = np.asarray(counts)
    top = counts.max() if len(counts) else 1
    for f in FIBONACCI:
        if f <= top * 1.15:
            ax.axhline(f, color="0.8", lw=0.8, zorder=0)
            ax.text(xs[-1], f, f" {f}", va="center", fontsize=8, color="0.35")
    fibset = set(FIBONACCI)
    isfib = np.array([int(c) in fibset for c in counts])
    if step:
        ax.step(xs, counts, where="mid", color="0.5", lw=0.8)
    ax.scatter(np.asarray(xs)[isfib], counts[isfib], s=12, color="tab:red", label="Fibonacci number", zorder=3)
    ax.scatter(np.asarray(xs)[~isfib], counts[~isfib], s=12, color="tab:blue", label="other", zorder=3)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("ray florets N")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    write_bytes_atomic(path, buf.getvalue())


def write_sweep(out_dir, *, alpha: float = 75.0, n_range=(10, 300), n_fixed: int = 82,
                alpha_range=(20.0, 120.0), alpha_step: float = 0.5, divergence: float = 137.5,
                half_angle: bool = False) -> dict:
    """Both sweeps as ``sweep_n.csv/.png`` (fig. 6.2) and ``sweep_alpha.csv/.png`` (fig. 6.3).

    Returns ``{"n": (ns, counts), "alpha": (alphas, counts), "paths": [...]}``.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    ns = np.arange(int(n_range[0]), int(n_range[1]) + 1)
    cn = sweep_n(ns, alpha, divergence=divergence, half_angle=half_angle)
    k = _alpha_steps(alpha_range, alpha_step)
    alphas = alpha_range[0] + alpha_step * np.arange(k + 1)
    ca = sweep_alpha(n_fixed, alphas, divergence=divergence, half_angle=half_angle)
    angle = "half-angle" if half_angle else "opening angle"
    paths = [out / "sweep_n.csv", out / "sweep_n.png", out / "sweep_alpha.csv", out / "sweep_alpha.png"]
    write_text_atomic(paths[0], _csv("n", [int(v) for v in ns], cn,
                                     f"fig. 6.2: alpha = {alpha:g} deg ({angle}), divergence {divergence:g} deg"))
    _plot(paths[1], ns, cn, "florets n", f"Ray florets vs head size, alpha = {alpha:g} deg (fig. 6.2)", False)
    write_text_atomic(paths[2], _csv("alpha", [float(a) for a in alphas], ca,
                                     f"fig. 6.3: n = {n_fixed}, divergence {divergence:g} deg, alpha = {angle}"))
    _plot(paths[3], alphas, ca, f"cone {angle} alpha (degrees)",
          f"Ray florets vs cone angle, n = {n_fixed} (fig. 6.3)", True)
    return {"n": (ns, cn), "alpha": (alphas, ca), "paths": paths}
