"""Key poses -> frames (thesis 2.3 and 8 b)): intrinsic interpolation of floret key poses, timed by
a growth function.

- Each organ's control net is interpolated **as written** (the half petal when bilateral, before
  tilt): every column of control points is a polyline in v (base -> tip) blended intrinsically
  (:mod:`.interpolate`). ``tilt`` and the symmetry phase blend linearly. Symmetry, mirroring and
  fusion are applied afterwards by :func:`inflo.formats.floret.full_petal`, so every frame stays
  symmetric and fused (formats/floret.md, "Symmetry").
- Timing: frame i of F has the frame time ``tau_i = i / (F - 1)`` in [0, 1]. The growth function
  g (a ``.func``; default g(tau) = tau, linear timing) maps it to the developmental time
  ``b = t_first + g(tau) (t_last - t_first)`` on the axis of the key times (the poses' ``time:``
  values; evenly spaced 0 .. 1 when no pose gives one). With more than two poses, b selects the
  pair of consecutive key poses around it. Each frame's ``time:`` is its developmental time b.
  g must be non-decreasing with values in [0, 1] (a growth does not run backwards).
"""
from __future__ import annotations

import dataclasses
import os

import numpy as np

from inflo.formats.errors import InputError
from inflo.formats.floret import Floret, Organ, check_compatible
from inflo.formats.func import Function

from .interpolate import blend_codes, decode_polylines, encode_polylines, reference_vectors

__all__ = [
    "FloretAnimator",
    "frame_times",
    "key_times",
    "developmental_times",
    "check_growth",
]


def frame_times(n_frames: int) -> np.ndarray:
    """``tau_i = i / (F - 1)``, i = 0 .. F - 1 (a single frame: [0])."""
    if n_frames < 1:
        raise InputError(f"--frames: expected a number of frames >= 1, found {n_frames}")
    if n_frames == 1:
        return np.zeros(1)
    return np.arange(n_frames, dtype=np.float64) / (n_frames - 1)


def key_times(poses, paths) -> np.ndarray:
    """The key time of every pose: their ``time:`` values (strictly increasing), or evenly spaced
    0 .. 1 when none gives one.

    Raises
    ------
    InputError
        Some poses have a time and others do not, or the times do not increase.
    """
    times = [p.key_time for p in poses]
    given = [t is not None for t in times]
    if not any(given):
        return np.linspace(0.0, 1.0, len(poses))
    if not all(given):
        missing = [os.fspath(p) for p, g in zip(paths, given) if not g]
        raise InputError(f"{missing[0]}: expected 'time:' in every key pose or in none (other "
                         "key poses give one), found none")
    t = np.array(times, dtype=np.float64)
    for i in range(1, len(t)):
        if not t[i] > t[i - 1]:
            raise InputError(f"{os.fspath(paths[i])}: expected a key time greater than {t[i - 1]!r} "
                             f"(that of {os.fspath(paths[i - 1])}; key poses are given in time "
                             f"order), found {t[i]!r}")
    return t


def check_growth(growth: Function, path="growth function") -> None:
    """Reject a growth function that decreases somewhere or leaves [0, 1].

    The check runs on the function's sample table (what is evaluated), so it is exact for the
    piecewise linear function used.
    """
    xs, ys = growth.sampled()
    d = np.diff(ys)
    bad = np.flatnonzero(d < -1e-12)
    if len(bad):
        i = int(bad[0])
        raise InputError(
            f"{os.fspath(path)}: expected a non-decreasing growth function (developmental time "
            f"cannot run backwards), found it decreasing from {ys[i]:.6g} at x = {xs[i]:.4g} to "
            f"{ys[i + 1]:.6g} at x = {xs[i + 1]:.4g}")
    lo, hi = float(ys.min()), float(ys.max())
    if lo < -1e-9 or hi > 1.0 + 1e-9:
        raise InputError(f"{os.fspath(path)}: expected growth function values in [0, 1] (0: the "
                         f"first key pose, 1: the last), found values from {lo:.6g} to {hi:.6g}")


def developmental_times(taus, times, growth: Function | None = None) -> np.ndarray:
    """Developmental time b of each frame time tau: ``t0 + g(tau) (t_last - t0)``."""
    taus = np.asarray(taus, dtype=np.float64)
    g = taus if growth is None else np.clip(np.asarray(growth(taus), dtype=np.float64), 0.0, 1.0)
    t0, t1 = float(times[0]), float(times[-1])
    b = t0 + g * (t1 - t0)
    b[g == 0.0] = t0
    b[g == 1.0] = t1
    return b


class FloretAnimator:
    """Interpolates two or more compatible key poses.

    Parameters
    ----------
    poses : sequence of Floret
        Key poses, in time order, with the same control-mesh topology (checked).
    paths : sequence of str or Path, optional
        Their files, for error messages.

    The intrinsic encodings of every pose are computed once; :meth:`at` then blends the two poses
    around a developmental time.
    """

    def __init__(self, poses, paths=None):
        poses = list(poses)
        if len(poses) < 2:
            raise InputError("expected at least 2 key poses to interpolate, found "
                             f"{len(poses)}")
        paths = [os.fspath(p) for p in (paths or [f"key pose {i + 1}" for i in range(len(poses))])]
        for i in range(1, len(poses)):
            check_compatible(poses[0], poses[i], paths[0], paths[i])
        self.poses = poses
        self.paths = paths
        self.times = key_times(poses, paths)
        self._codes = []
        for k in range(len(poses[0].organs)):
            cols = [self._columns(p.organs[k]) for p in poses]
            ref = reference_vectors(*cols)
            self._codes.append([encode_polylines(c, ref) for c in cols])

    @staticmethod
    def _columns(organ: Organ) -> np.ndarray:
        """The organ's control polylines in v: (nu, nv, 3), column i = control_points[:, i]."""
        return np.ascontiguousarray(np.swapaxes(organ.control_points, 0, 1))

    def segment(self, b: float) -> tuple[int, float]:
        """Index k of the key-pose pair (k, k + 1) around developmental time b, and the local
        blend parameter s in [0, 1]."""
        t = self.times
        if b <= t[0]:
            return 0, 0.0
        if b >= t[-1]:
            return len(t) - 2, 1.0
        k = int(np.searchsorted(t, b, side="right") - 1)
        k = min(max(k, 0), len(t) - 2)
        s = (b - t[k]) / (t[k + 1] - t[k])
        return k, float(min(max(s, 0.0), 1.0))

    def at(self, b: float) -> Floret:
        """The floret at developmental time b (its ``key_time`` is b)."""
        k, s = self.segment(b)
        pa, pb = self.poses[k], self.poses[k + 1]
        organs = []
        for i, (oa, ob) in enumerate(zip(pa.organs, pb.organs)):
            code = blend_codes(self._codes[i][k], self._codes[i][k + 1], s)
            cols = decode_polylines(code)
            cp = np.swapaxes(cols, 0, 1)
            organs.append(dataclasses.replace(
                oa,
                control_points=cp,
                tilt_deg=(1.0 - s) * oa.tilt_deg + s * ob.tilt_deg,
                symmetry_phase_deg=(1.0 - s) * oa.symmetry_phase_deg + s * ob.symmetry_phase_deg,
            ))
        return Floret(self.poses[0].name, tuple(organs), float(b))

    def frames(self, n_frames: int = 100, growth: Function | None = None):
        """Yield the ``n_frames`` frames (Floret) of the animation, timed by ``growth``."""
        for b in developmental_times(frame_times(n_frames), self.times, growth):
            yield self.at(float(b))
