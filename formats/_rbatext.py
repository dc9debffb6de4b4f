"""The fast path of the RBA writer (:func:`inflo.formats.rba.write_rba`): a numba kernel that
formats placement rows exactly like the Python path.

The Python path formats each number with ``'%.6f'``; a 10,000-floret head over 200 frames
(``phyllotaxis``) is about a million rows, too many for per-number Python formatting. The kernel
:func:`format_rows` writes ``id`` and twelve ``%.6f`` numbers per row into a byte buffer.
Correct rounding needs the exact decimal value of the double; the kernel rounds ``|x| * 1e6``
and flags a row when that product lies within a few ulps of a half (a possible tie, e.g.
``x = 1/128``) or ``|x| >= 1e12``; flagged rows are formatted again by ``format_preamble``, as
are rows the kernel does not take at all (a negative id, NaN or inf). The output is
byte-identical to the Python path (tested on random and tie-prone values).

Private: imported by :mod:`inflo.formats.rba` on first use, so that reading formats does not
import numba.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .placement import format_preamble

__all__ = ["format_rows", "rba_bytes"]


@njit(cache=True)
def _put_uint(buf, p, v):
    """Write the decimal digits of a non-negative int64 ``v`` at ``buf[p:]``; returns the new p."""
    k = 1
    t = v // 10
    while t > 0:
        k += 1
        t //= 10
    for j in range(k - 1, -1, -1):
        buf[p + j] = 48 + v % 10
        v //= 10
    return p + k


_DIGIT_PAIRS = np.frombuffer("".join(f"{i:02d}" for i in range(100)).encode("ascii"), dtype=np.uint8).copy()


@njit(cache=True)
def format_rows(ids, values):
    """Format rows ``id v0 ... v11`` with ``%.6f`` numbers.

    Parameters
    ----------
    ids : (n,) int64, non-negative
    values : (n, 12) float64, finite

    Returns
    -------
    buf : (m,) uint8  the text, one line per row ending in ``\\n``
    flagged : (n,) bool  rows whose rounding may differ from printf (reformat them)
    """
    pairs = _DIGIT_PAIRS
    n = ids.shape[0]
    buf = np.empty(n * (12 * 22 + 22) + 1, np.uint8)
    flagged = np.zeros(n, np.bool_)
    p = 0
    for i in range(n):
        p = _put_uint(buf, p, ids[i])
        for j in range(values.shape[1]):
            x = values[i, j]
            buf[p] = 32
            p += 1
            neg = x < 0.0 or (x == 0.0 and math.copysign(1.0, x) < 0.0)
            v = -x if neg else x
            if v >= 1e12:
                flagged[i] = True
                v = 0.0
            m = v * 1e6
            qi = np.int64(m)
            frac = m - qi
            if abs(frac - 0.5) <= 4.0 * (m * 2.220446049250313e-16) + 1e-300:
                flagged[i] = True
            if frac > 0.5:
                qi += 1
            if neg:
                buf[p] = 45
                p += 1
            p = _put_uint(buf, p, qi // 1000000)
            buf[p] = 46
            f = qi % 1000000
            a = f // 10000
            b = (f // 100) % 100
            c = f % 100
            buf[p + 1] = pairs[2 * a]
            buf[p + 2] = pairs[2 * a + 1]
            buf[p + 3] = pairs[2 * b]
            buf[p + 4] = pairs[2 * b + 1]
            buf[p + 5] = pairs[2 * c]
            buf[p + 6] = pairs[2 * c + 1]
            p += 7
        buf[p] = 10
        p += 1
    return buf[:p], flagged


def tiny_nonzero_rows(vals: np.ndarray) -> np.ndarray:
    """Rows of ``id``-less ``pos scale up right`` values (n, 12) holding a non-zero scale component,
    or a non-zero up/right vector, that ``%.6f`` would print as zero: :func:`format_preamble` writes
    those in exponent form (a valid scale of 4e-7 once came back as 0)."""
    a = np.abs(vals)
    tiny = (a > 0) & (a < 1e-6)
    scale = tiny[:, 3:6].any(axis=1)
    up = (a[:, 6:9] < 1e-6).all(axis=1) & tiny[:, 6:9].any(axis=1)
    right = (a[:, 9:12] < 1e-6).all(axis=1) & tiny[:, 9:12].any(axis=1)
    return scale | up | right


def rba_bytes(ids, pos, scale, up, right) -> bytes:
    """The rows ``id pos scale up right`` as ``write_rba`` writes them (no header), byte for byte."""
    ids = np.ascontiguousarray(ids, dtype=np.int64).reshape(-1)
    vals = np.ascontiguousarray(np.hstack([np.reshape(pos, (-1, 3)), np.reshape(scale, (-1, 3)),
                                           np.reshape(up, (-1, 3)), np.reshape(right, (-1, 3))]),
                                dtype=np.float64)
    if len(ids) == 0:
        return b""
    odd = (ids < 0) | ~np.isfinite(vals).all(axis=1)  # rows the kernel does not take
    odd |= tiny_nonzero_rows(vals)  # values the fixed format would print as zero (format_preamble)
    if odd.any():
        buf, flagged = format_rows(np.where(odd, 0, ids), np.where(odd[:, None], 0.0, vals))
        flagged |= odd
    else:
        buf, flagged = format_rows(ids, vals)
    data = buf.tobytes()
    if flagged.any():
        lines = data.split(b"\n")
        for k in np.nonzero(flagged)[0]:
            v = vals[k]
            lines[k] = format_preamble(int(ids[k]), v[0:3], v[3:6], v[6:9], v[9:12]).encode("ascii")
        data = b"\n".join(lines)
    return data
