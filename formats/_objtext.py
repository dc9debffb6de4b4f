"""The fast paths of the OBJ reader and writer (:mod:`inflo.formats.obj`): numba kernels that parse
and format the common OBJ text exactly as the Python paths do.

A final yarrow canopy frame is 14 MB of text (220k ``v`` lines, 340k ``f`` lines); the Python
reader takes about 0.4 s for it and every stage after the canopy reads 100 such frames
(pictures, check, USD export), the writer about 0.25 s a frame in ``fccompose``.

Reading (:func:`parse_obj`): one pass over the bytes splits lines at ``\\n``, parses the ``v``,
``vn`` and ``f`` lines and hands back the other lines (groups, materials, polylines, comments
are skipped) for the Python reader's own handling. Numbers are parsed with Clinger's fast path:
a decimal with at most 15 significant digits and a power of ten within 10^±22 is one exactly
representable integer multiplied or divided by one exactly representable power of ten, a single
correctly rounded IEEE operation, so the result is the double that Python's ``float`` gives.
Anything outside that subset (other line breaks, a number the fast path cannot take, a face
with more than three corners, a texture or normal reference that is not an integer (texture
references are read past, as the Python reader does), a wrong count, an index out of range) makes
the kernel give up on the file (``ok`` false) and the Python reader reads it, errors included.

Writing (:func:`format_fixed`): ``%.Nf`` rows as the RBA writer's kernel does (:mod:`._rbatext`):
the kernel rounds ``|x| 10^N``, flags a row whose product lies within a few ulps of a half (a
possible printf tie) or is too large, and the flagged rows are formatted again by Python. The
kernel also gives the value each number reads back as (the integer of units of 10^-N divided by
10^N: exact operands, one correctly rounded division, what ``float`` of the text gives), so the
writer's callers that check the written numbers need not parse the text again.

Private: imported by :mod:`inflo.formats.obj` for files and meshes large enough that importing
numba pays (:data:`inflo.formats.obj.FAST_BYTES`).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._rbatext import _put_uint

__all__ = ["parse_obj", "format_fixed", "format_faces"]

#: exactly representable powers of ten (Clinger's fast path)
_POW10 = np.array([10.0 ** k for k in range(23)])

# kinds of line
_OTHER = 0
_V = 1
_VN = 2
_F = 3
_SKIP = 4  # a comment, an empty line or a `vt` line


@njit(cache=True, inline="always")
def _is_blank(c):
    return c == 32 or c == 9


@njit(cache=True, inline="always")
def _digit_run(data, p, end, mant, nd):
    """Read the decimal digits at ``data[p:end]`` into ``mant`` (leading zeros of a zero ``mant``
    skipped; ``nd`` counts the digits kept, stopping past 16). Returns (mant, nd, digits read, p)."""
    n = 0
    while p < end and 48 <= data[p] <= 57:
        d = data[p] - 48
        n += 1
        if mant != 0 or d != 0:
            if nd <= 15:
                mant = mant * 10 + d
            nd += 1
        p += 1
    return mant, nd, n, p


@njit(cache=True)
def _parse_float(data, p, end, pow10):
    """Parse one number token at ``data[p:end]`` (p at its first byte). Returns (value, next p, ok):
    ok false for a token the fast path does not take (any other syntax, too many digits, an
    exponent out of range); the token ends at a blank or ``end``."""
    neg = False
    c = data[p]
    if c == 45 or c == 43:  # - +
        neg = c == 45
        p += 1
    # the digits before and after the point: the significant ones (from the first non-zero) into
    # ``mant``, those after the point counted down in ``exp10``
    mant, nd, n_int, p = _digit_run(data, p, end, np.int64(0), 0)
    exp10 = 0
    n_frac = 0
    if p < end and data[p] == 46:  # .
        mant, nd, n_frac, p = _digit_run(data, p + 1, end, mant, nd)
        exp10 = -n_frac
    if n_int + n_frac == 0 or nd > 15:
        return 0.0, p, False
    if p < end and (data[p] == 101 or data[p] == 69):  # e E
        p += 1
        eneg = False
        if p < end and (data[p] == 45 or data[p] == 43):
            eneg = data[p] == 45
            p += 1
        e = 0
        ed = 0
        while p < end and 48 <= data[p] <= 57:
            e = e * 10 + (data[p] - 48)
            ed += 1
            p += 1
            if e > 400:
                return 0.0, p, False
        if ed == 0:
            return 0.0, p, False
        exp10 += -e if eneg else e
    if p < end and not _is_blank(data[p]):
        return 0.0, p, False
    if mant == 0:
        v = 0.0
    elif exp10 >= 0:
        if exp10 > 22:
            return 0.0, p, False
        v = float(mant) * pow10[exp10]
    else:
        if exp10 < -22:
            return 0.0, p, False
        v = float(mant) / pow10[-exp10]
    return (-v if neg else v), p, True


@njit(cache=True)
def _parse_int(data, p, end):
    """Parse ``[+-]digits`` at ``data[p:]``, ending at a blank, ``/`` or ``end``. Returns
    (value, next p, ok)."""
    neg = False
    c = data[p]
    if c == 45 or c == 43:
        neg = c == 45
        p += 1
    v = np.int64(0)
    nd = 0
    while p < end and 48 <= data[p] <= 57:
        v = v * 10 + (data[p] - 48)
        nd += 1
        p += 1
        if nd > 15:
            return np.int64(0), p, False
    if nd == 0:
        return np.int64(0), p, False
    return (-v if neg else v), p, True


@njit(cache=True)
def _line_breaks_ok(data):
    """False when the text holds a line break other than ``\\n`` (``str.splitlines`` would split
    there too: \\r, \\v, \\f, \\x1c-\\x1e, U+0085, U+2028, U+2029) or a NUL byte."""
    n = data.shape[0]
    for i in range(n):
        c = data[i]
        if c == 13 or c == 11 or c == 12 or c == 28 or c == 29 or c == 30 or c == 0:
            return False
        if c == 0xC2 and i + 1 < n and data[i + 1] == 0x85:
            return False
        if c == 0xE2 and i + 2 < n and data[i + 1] == 0x80 and (data[i + 2] == 0xA8 or data[i + 2] == 0xA9):
            return False
    return True


@njit(cache=True)
def parse_obj(data):
    """Parse OBJ text (uint8 array of its bytes).

    Returns
    -------
    ok : bool
        False: the file is outside the fast path (read it with the Python reader).
    v : (nv, w) float64
        The numbers of the ``v`` lines (w: 3, 4 or 6, the same on every line).
    v_line, vn_line : (nv,), (nvn,) int64
        0-based line of each ``v`` / ``vn`` line.
    vn : (nvn, 3) float64
    faces, face_n : (m, 3) int64
        The vertex and normal references of each ``f`` line as written (normal 0: none).
    face_line, face_nv, face_nvn : (m,) int64
        Each face's line and the ``v`` / ``vn`` lines before it (for negative references).
    other : (k, 3) int64
        Line, start and end byte of every other line that is neither empty nor a comment.
    """
    pow10 = _POW10
    n = data.shape[0]
    e_f = np.empty((0, 3), np.float64)
    e_i = np.empty(0, np.int64)
    e_i3 = np.empty((0, 3), np.int64)
    fail = (False, e_f, e_i, e_f, e_i, e_i3, e_i3, e_i, e_i, e_i, e_i3)
    if not _line_breaks_ok(data):
        return fail
    # pass 1: line kinds and counts
    n_lines = 0
    for i in range(n):
        if data[i] == 10:
            n_lines += 1
    if n > 0 and data[n - 1] != 10:
        n_lines += 1
    kind = np.empty(n_lines, np.int8)
    start = np.empty(n_lines, np.int64)
    stop = np.empty(n_lines, np.int64)
    p = 0
    nv = nvn = nf = no = 0
    for li in range(n_lines):
        q = p
        while q < n and data[q] != 10:
            q += 1
        start[li] = p
        stop[li] = q
        k = _OTHER
        if q == p or data[p] == 35:  # empty, or '#'
            k = _SKIP
        elif data[p] == 118 and q - p >= 2:  # v
            c = data[p + 1]
            if _is_blank(c):
                k = _V
                nv += 1
            elif c == 110 and q - p >= 3 and _is_blank(data[p + 2]):  # vn
                k = _VN
                nvn += 1
            elif c == 116 and (q - p == 2 or _is_blank(data[p + 2])):  # vt: skipped, as the Python reader does
                k = _SKIP
        elif data[p] == 102 and q - p >= 2 and _is_blank(data[p + 1]):  # f
            k = _F
            nf += 1
        if k == _OTHER:
            no += 1
        kind[li] = k
        p = q + 1
    width = -1
    v = np.empty((nv, 6), np.float64)
    v_line = np.empty(nv, np.int64)
    vn = np.empty((nvn, 3), np.float64)
    vn_line = np.empty(nvn, np.int64)
    faces = np.empty((nf, 3), np.int64)
    face_n = np.zeros((nf, 3), np.int64)
    face_line = np.empty(nf, np.int64)
    face_nv = np.empty(nf, np.int64)
    face_nvn = np.empty(nf, np.int64)
    other = np.empty((no, 3), np.int64)
    iv = ivn = jf = jo = 0
    for li in range(n_lines):
        k = kind[li]
        p = start[li]
        q = stop[li]
        if k == _SKIP:
            continue
        if k == _OTHER:
            other[jo, 0] = li
            other[jo, 1] = p
            other[jo, 2] = q
            jo += 1
            continue
        p += 2 if k != _VN else 3
        cnt = 0
        if k == _V or k == _VN:
            cap = 6 if k == _V else 3
            while True:
                while p < q and _is_blank(data[p]):
                    p += 1
                if p >= q:
                    break
                if cnt == cap:
                    return fail
                x, p, ok = _parse_float(data, p, q, pow10)
                if not ok:
                    return fail
                if k == _V:
                    v[iv, cnt] = x
                else:
                    vn[ivn, cnt] = x
                cnt += 1
            if k == _V:
                if width == -1:
                    if cnt != 3 and cnt != 4 and cnt != 6:
                        return fail
                    width = cnt
                elif cnt != width:
                    return fail
                v_line[iv] = li
                iv += 1
            else:
                if cnt != 3:
                    return fail
                vn_line[ivn] = li
                ivn += 1
        else:  # f
            while True:
                while p < q and _is_blank(data[p]):
                    p += 1
                if p >= q:
                    break
                if cnt == 3:
                    return fail
                a, p, ok = _parse_int(data, p, q)
                if not ok:
                    return fail
                nrm = np.int64(0)
                if p < q and data[p] == 47:
                    if p + 1 < q and data[p + 1] == 47:  # i//n
                        if p + 2 >= q:
                            return fail
                        nrm, p, ok = _parse_int(data, p + 2, q)
                        if not ok:
                            return fail
                    else:  # i/t or i/t/n: the texture reference is read past (an integer), not kept
                        if p + 1 >= q:
                            return fail
                        _t, p, ok = _parse_int(data, p + 1, q)
                        if not ok:
                            return fail
                        if p < q and data[p] == 47:
                            if p + 1 >= q:
                                return fail
                            nrm, p, ok = _parse_int(data, p + 1, q)
                            if not ok:
                                return fail
                if p < q and not _is_blank(data[p]):
                    return fail
                faces[jf, cnt] = a
                face_n[jf, cnt] = nrm
                cnt += 1
            if cnt != 3:
                return fail
            face_line[jf] = li
            face_nv[jf] = iv
            face_nvn[jf] = ivn
            jf += 1
    w = width if width > 0 else 3
    return (True, v[:, :w].copy(), v_line, vn, vn_line, faces, face_n, face_line, face_nv, face_nvn, other)


@njit(cache=True)
def format_fixed(prefix, values, digits):
    """Format rows ``<prefix>v0 v1 ...`` with ``%.<digits>f`` numbers, one line each.

    Parameters
    ----------
    prefix : (k,) uint8  the bytes before the numbers (``b"v "``)
    values : (n, c) float64
    digits : int  decimals (1-9)

    Returns
    -------
    buf : (m,) uint8  the text
    flagged : (n,) bool  rows whose rounding may differ from printf, or holding a number the
        kernel does not take (NaN, inf, too large): format them again
    back : (n, c) float64  each number as the text reads back (where not flagged)
    """
    n = values.shape[0]
    c = values.shape[1]
    mult = 10.0 ** digits
    unit = np.int64(10) ** digits
    big = 2.0 ** 52
    buf = np.empty(n * (prefix.shape[0] + c * 24 + 1) + 1, np.uint8)
    flagged = np.zeros(n, np.bool_)
    back = np.empty((n, c), np.float64)
    p = 0
    for i in range(n):
        for j in range(prefix.shape[0]):
            buf[p + j] = prefix[j]
        p += prefix.shape[0]
        for j in range(c):
            x = values[i, j]
            if j > 0:
                buf[p] = 32
                p += 1
            neg = x < 0.0 or (x == 0.0 and math.copysign(1.0, x) < 0.0)
            a = -x if neg else x
            m = a * mult
            if not m < big:  # too large for exact integer units, or NaN / inf
                flagged[i] = True
                m = 0.0
            qi = np.int64(m)
            frac = m - qi
            if abs(frac - 0.5) <= 4.0 * (m * 2.220446049250313e-16) + 1e-300:
                flagged[i] = True
            if frac > 0.5:
                qi += 1
            r = float(qi) / mult
            back[i, j] = -r if neg else r
            if neg:
                buf[p] = 45
                p += 1
            p = _put_uint(buf, p, qi // unit)
            buf[p] = 46
            p += 1
            f = qi % unit
            for t in range(digits - 1, -1, -1):
                buf[p + t] = 48 + f % 10
                f //= 10
            p += digits
        buf[p] = 10
        p += 1
    return buf[:p], flagged, back


@njit(cache=True)
def format_faces(faces, normals):
    """``f a b c`` lines (``f a//a b//b c//c`` with ``normals``) of 0-based ``faces`` (m, 3),
    1-based in the text. Returns the text and the byte offset of every line (m + 1)."""
    m = faces.shape[0]
    per = 2 + 3 * (2 * 21 + 3) + 1
    buf = np.empty(m * per + 1, np.uint8)
    offs = np.empty(m + 1, np.int64)
    p = 0
    for i in range(m):
        offs[i] = p
        buf[p] = 102
        p += 1
        for j in range(3):
            buf[p] = 32
            p += 1
            a = np.int64(faces[i, j]) + 1
            p = _put_uint(buf, p, a)
            if normals:
                buf[p] = 47
                buf[p + 1] = 47
                p = _put_uint(buf, p + 2, a)
        buf[p] = 10
        p += 1
    offs[m] = p
    return buf[:p], offs
