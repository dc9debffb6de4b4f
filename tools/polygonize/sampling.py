"""Where polygonize puts vertices in a petal's (u, v) parameter space (thesis 2.4, eq. 2.1).

- **Rows** v_0 = 0 < v_1 < ... < v_n = 1 from the spacing function lambda(v) > 0:
  ``integral_{v_i}^{v_{i+1}} dv / lambda(v) = 1`` (eq. 2.1). With ``Phi(v) = integral_0^v dv' /
  lambda`` the unadjusted rows are ``Phi^{-1}(i)``; the last one rarely lands on the tip, so
  lambda is scaled by ``c = Phi(1) / n`` with ``n = round(Phi(1))`` (at least 1): the rows are
  ``v_i = Phi^{-1}(i Phi(1) / n)``, each interval integrates ``dv / (c lambda)`` to exactly 1 and
  v_n = 1. A constant lambda = 1/8 gives the 9 rows 0, 1/8, ..., 1.
- **Vertices per row**: ``ceil(eta(v_i))``, made odd (+1 when even) so a vertex sits on the
  midline u = 1/2 and no triangle straddles it; equidistant in u from 0 to 1. A row that collapses
  to a point on the surface (a pointed tip) gets the single vertex u = 1/2.

``lambda`` and ``eta`` are a number, a :class:`~inflo.formats.func.Function` (a ``.func`` file:
lambda(v) = f(v) and eta(v) = f(v), v in [0, 1] from the petal base to its tip) or any vectorized
callable.
"""
from __future__ import annotations

import os

import numpy as np

from inflo.formats.errors import InputError
from inflo.formats.func import Function, read_func

__all__ = [
    "DEFAULT_LAMBDA",
    "DEFAULT_ETA",
    "Profile",
    "load_profile",
    "row_parameters",
    "row_counts",
    "row_points",
]

DEFAULT_LAMBDA = 0.1
"""Default row spacing in v: 11 rows, the isoparametric grid of fig. 2.4a."""
DEFAULT_ETA = 11.0
"""Default vertices per row."""

_FINE = 8193  # samples of v for the integral of 1 / lambda


class Profile:
    """lambda(v) or eta(v): a constant, a .func function or a callable, with a name for messages."""

    def __init__(self, value, name: str, source: str | None = None):
        self.value = value
        self.name = name
        self.source = source or (repr(float(value)) if isinstance(value, (int, float)) else name)

    def __call__(self, v) -> np.ndarray:
        v = np.asarray(v, dtype=np.float64)
        if isinstance(self.value, (int, float)):
            return np.full(v.shape, float(self.value))
        return np.asarray(self.value(v), dtype=np.float64).reshape(v.shape)

    @property
    def constant(self) -> float | None:
        return float(self.value) if isinstance(self.value, (int, float)) else None

    def __repr__(self) -> str:
        return f"Profile({self.name}={self.source})"


def load_profile(value, name: str) -> Profile:
    """A Profile from a number, a ``.func`` path (str/Path) or a Function.

    Raises
    ------
    InputError
        lambda <= 0 or eta < 1 (a constant, or anywhere on a function's sample table).
    """
    if isinstance(value, Profile):
        prof = value
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        prof = Profile(float(value), name)
    elif isinstance(value, Function):
        prof = Profile(value, name, value.name)
    else:
        text = os.fspath(value)
        try:
            prof = Profile(float(text), name)
        except ValueError:
            prof = Profile(read_func(text), name, text)
    _check_profile(prof)
    return prof


MAX_ROWS = 10_000
"""Most rows per petal that lambda(v) may ask for (a petal of 10k x 10k samples is 10^8 vertices:
beyond any machine this runs on; without the limit ``--lambda 1e-7`` never ends)."""
MAX_ROW_VERTICES = 10_000
"""Most vertices per row that eta(v) may ask for (``--eta 1e9`` exhausted memory)."""


def _check_profile(prof: Profile) -> None:
    if prof.constant is not None:
        ys = np.array([prof.constant])
        xs = np.array([0.0])
    elif isinstance(prof.value, Function):
        xs, ys = prof.value.sampled()
    else:
        xs = np.linspace(0.0, 1.0, _FINE)
        ys = prof(xs)
    if not np.all(np.isfinite(ys)):
        raise InputError(f"{prof.source}: expected finite {prof.name} values, found NaN or inf")
    if prof.name == "lambda":
        bad = np.flatnonzero(ys <= 0.0)
        if len(bad):
            i = int(bad[0])
            raise InputError(f"{prof.source}: expected lambda(v) > 0 everywhere (row spacing, eq. "
                             f"2.1), found {ys[i]:.6g} at v = {xs[i]:.4g}")
        rows = 1.0 / prof.constant if prof.constant is not None else float(
            np.trapezoid(1.0 / prof(np.linspace(0.0, 1.0, _FINE)), dx=1.0 / (_FINE - 1)))
        if rows > MAX_ROWS:
            raise InputError(f"{prof.source}: expected lambda(v) giving at most {MAX_ROWS} rows per petal "
                             f"(eq. 2.1), found {rows:.4g} rows (smallest lambda {ys.min():.6g})")
    elif prof.name == "eta":
        bad = np.flatnonzero(ys < 1.0)
        if len(bad):
            i = int(bad[0])
            raise InputError(f"{prof.source}: expected eta(v) >= 1 everywhere (vertices per row), "
                             f"found {ys[i]:.6g} at v = {xs[i]:.4g}")
        if ys.max() > MAX_ROW_VERTICES:
            i = int(np.argmax(ys))
            raise InputError(f"{prof.source}: expected eta(v) <= {MAX_ROW_VERTICES} (vertices per row), "
                             f"found {ys[i]:.6g} at v = {xs[i]:.4g}")


def row_parameters(lam: Profile) -> tuple[np.ndarray, float]:
    """Rows v_0 = 0 .. v_n = 1 by eq. 2.1, adjusted so the last row lands on the tip.

    Returns
    -------
    v : (n + 1,) float64
        The row parameters, strictly increasing, v[0] = 0 and v[-1] = 1 exactly.
    scale : float
        c = Phi(1) / n: each interval satisfies ``integral dv / (c lambda(v)) = 1``; 1 when
        Phi(1) is a whole number.
    """
    c = lam.constant
    if c is not None:
        total = 1.0 / c
        n = max(1, int(round(total)))
        v = np.arange(n + 1, dtype=np.float64) / n
        v[-1] = 1.0
        return v, total / n
    vs = np.linspace(0.0, 1.0, _FINE)
    inv = 1.0 / lam(vs)
    phi = np.concatenate([[0.0], np.cumsum(0.5 * (inv[1:] + inv[:-1]) * np.diff(vs))])
    total = float(phi[-1])
    n = max(1, int(round(total)))
    targets = np.arange(n + 1, dtype=np.float64) * (total / n)
    v = np.interp(targets, phi, vs)
    v[0], v[-1] = 0.0, 1.0
    return v, total / n


def row_counts(eta: Profile, v, collapsed=None) -> np.ndarray:
    """``ceil(eta(v_i))`` made odd; 1 for rows flagged in ``collapsed`` ((n + 1,) bool)."""
    e = eta(np.asarray(v, dtype=np.float64))
    counts = np.ceil(e - 1e-9).astype(np.int64)
    counts = np.maximum(counts, 1)
    counts += (counts % 2 == 0)
    if collapsed is not None:
        counts[np.asarray(collapsed, dtype=bool)] = 1
    return counts


def row_points(v, counts) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The (u, v) samples, row by row from the base, u from 0 to 1 in each row.

    Returns
    -------
    u, v : (k,) float64
        Parameters of the k = sum(counts) samples.
    row, col : (k,) int64
        Row index and index within the row of each sample.
    """
    us, vs, rows, cols = [], [], [], []
    for i, (vi, c) in enumerate(zip(v, counts)):
        c = int(c)
        u = np.array([0.5]) if c == 1 else np.linspace(0.0, 1.0, c)
        us.append(u)
        vs.append(np.full(c, float(vi)))
        rows.append(np.full(c, i, dtype=np.int64))
        cols.append(np.arange(c, dtype=np.int64))
    return np.concatenate(us), np.concatenate(vs), np.concatenate(rows), np.concatenate(cols)
