"""Intrinsic interpolation of control polylines (thesis 2.3, after Sederberg et al.'s blending of
intrinsically defined polygons, extended to 3D).

A control polyline ``p_0 .. p_{m-1}`` (one column of a petal's control net, base -> tip) is encoded
as

- the base point ``p_0``;
- the base frame ``F_0`` (columns: unit tangent of the first segment, a normal, a binormal), stored
  as a unit quaternion;
- the segment lengths ``L_j = |p_{j+1} - p_j|``;
- the rotations between consecutive segments, ``Q_j = F_j^T F_{j+1}``, **expressed in the moving
  frame**, as unit quaternions. The frames ``F_j`` form a discrete rotation-minimizing frame
  (Bloomenthal; Wang et al. 2008, "Computation of rotation minimizing frames", double reflection):
  at each vertex the frame turns about the axis perpendicular to both segments so the next segment
  lines up with the previous one, and does not twist about the tangent (for collinear segments the
  rotation is the identity).

Two encodings blend by interpolating the base point and the lengths linearly and the base frame
and every ``Q_j`` spherically (quaternion slerp, shortest arc); rebuilding walks the segments:
``p_{j+1} = p_j + L_j F_j e_x``, ``F_{j+1} = F_j Q_j``. A petal that swings open by a large angle
keeps its segment lengths (linear interpolation of positions would shrink the chords), and the
blend at s = 0 and s = 1 gives back the key poses to rounding.

The kernels are plain Python functions compiled with ``numba.njit(cache=True)`` at module level
(``*_py`` keep the uncompiled versions callable). Arrays are structure-of-arrays over P polylines
of m points each.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from inflo.tools.common import linalg as la

__all__ = [
    "PolylineCode",
    "encode_polylines",
    "decode_polylines",
    "blend_codes",
    "blend_polylines",
    "rmf_frames",
    "reference_vectors",
]

_EPS = 1e-14


# --------------------------------------------------------------------------------------------------
# scalar helpers (3-vectors, 3x3 matrices, quaternions w x y z)
# --------------------------------------------------------------------------------------------------


def _mat_to_quat_py(m, q):
    """Unit quaternion (w, x, y, z) of rotation matrix ``m`` (Shepperd's method), written to q."""
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    if tr > 0.0:
        s = math.sqrt(tr + 1.0) * 2.0
        q[0] = 0.25 * s
        q[1] = (m[2, 1] - m[1, 2]) / s
        q[2] = (m[0, 2] - m[2, 0]) / s
        q[3] = (m[1, 0] - m[0, 1]) / s
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2]) * 2.0
        q[0] = (m[2, 1] - m[1, 2]) / s
        q[1] = 0.25 * s
        q[2] = (m[0, 1] + m[1, 0]) / s
        q[3] = (m[0, 2] + m[2, 0]) / s
    elif m[1, 1] > m[2, 2]:
        s = math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2]) * 2.0
        q[0] = (m[0, 2] - m[2, 0]) / s
        q[1] = (m[0, 1] + m[1, 0]) / s
        q[2] = 0.25 * s
        q[3] = (m[1, 2] + m[2, 1]) / s
    else:
        s = math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1]) * 2.0
        q[0] = (m[1, 0] - m[0, 1]) / s
        q[1] = (m[0, 2] + m[2, 0]) / s
        q[2] = (m[1, 2] + m[2, 1]) / s
        q[3] = 0.25 * s
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    for i in range(4):
        q[i] /= n


def _quat_to_mat_py(q, m):
    w, x, y, z = q[0], q[1], q[2], q[3]
    m[0, 0] = 1.0 - 2.0 * (y * y + z * z)
    m[0, 1] = 2.0 * (x * y - w * z)
    m[0, 2] = 2.0 * (x * z + w * y)
    m[1, 0] = 2.0 * (x * y + w * z)
    m[1, 1] = 1.0 - 2.0 * (x * x + z * z)
    m[1, 2] = 2.0 * (y * z - w * x)
    m[2, 0] = 2.0 * (x * z - w * y)
    m[2, 1] = 2.0 * (y * z + w * x)
    m[2, 2] = 1.0 - 2.0 * (x * x + y * y)


def _slerp_py(a, b, s, out):
    """Spherical linear interpolation of unit quaternions a -> b along the shorter arc.

    s = 0 returns ``a`` exactly; s = 1 returns ``b`` or ``-b`` (the same rotation) exactly.
    """
    dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]
    sign = 1.0
    if dot < 0.0:
        dot = -dot
        sign = -1.0
    if dot > 1.0 - 1e-12:
        wa = 1.0 - s
        wb = s
    else:
        theta = math.acos(dot)
        st = math.sin(theta)
        wa = math.sin((1.0 - s) * theta) / st
        wb = math.sin(s * theta) / st
    wb *= sign
    n = 0.0
    for i in range(4):
        out[i] = wa * a[i] + wb * b[i]
        n += out[i] * out[i]
    if s != 0.0 and s != 1.0:  # keep the endpoints bit-exact
        n = math.sqrt(n)
        for i in range(4):
            out[i] /= n


_mat_to_quat = njit(cache=True)(_mat_to_quat_py)
_quat_to_mat = njit(cache=True)(_quat_to_mat_py)
_slerp = njit(cache=True)(_slerp_py)


# --------------------------------------------------------------------------------------------------
# kernels
# --------------------------------------------------------------------------------------------------


def _encode_py(points, ref, base, q0, lengths, rots, frames):
    """Encode P polylines (P, m, 3) into base (P, 3), q0 (P, 4), lengths (P, m-1), rots (P, m-2, 4).

    ``frames`` (P, m-1, 3, 3) receives the rotation-minimizing frame of every segment (columns:
    tangent, normal, binormal). ``ref`` (P, 3) fixes the base normal: its component orthogonal to
    the first tangent.
    """
    n_poly, m = points.shape[0], points.shape[1]
    seg = np.empty(3)
    t = np.empty(3)
    tn = np.empty(3)
    r = np.empty(3)
    rl = np.empty(3)
    tl = np.empty(3)
    loc = np.empty((3, 3))
    for p in range(n_poly):
        for d in range(3):
            base[p, d] = points[p, 0, d]
        # the first tangent: the first segment of non-zero length (+Y if all have zero length)
        t[0], t[1], t[2] = 0.0, 1.0, 0.0
        for j in range(m - 1):
            ln = 0.0
            for d in range(3):
                seg[d] = points[p, j + 1, d] - points[p, j, d]
                ln += seg[d] * seg[d]
            ln = math.sqrt(ln)
            lengths[p, j] = ln
        for j in range(m - 1):
            if lengths[p, j] > _EPS:
                for d in range(3):
                    t[d] = (points[p, j + 1, d] - points[p, j, d]) / lengths[p, j]
                break
        # base normal: ref made orthogonal to t (fallbacks if ref is parallel to t)
        for attempt in range(4):
            if attempt == 0:
                r[0], r[1], r[2] = ref[p, 0], ref[p, 1], ref[p, 2]
            elif attempt == 1:
                r[0], r[1], r[2] = 0.0, 0.0, 1.0
            elif attempt == 2:
                r[0], r[1], r[2] = 1.0, 0.0, 0.0
            else:
                r[0], r[1], r[2] = 0.0, 1.0, 0.0
            dt = r[0] * t[0] + r[1] * t[1] + r[2] * t[2]
            for d in range(3):
                r[d] -= dt * t[d]
            nr = math.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
            if nr > 1e-6:
                for d in range(3):
                    r[d] /= nr
                break
        frames[p, 0, :, 0] = t
        frames[p, 0, :, 1] = r
        frames[p, 0, 0, 2] = t[1] * r[2] - t[2] * r[1]
        frames[p, 0, 1, 2] = t[2] * r[0] - t[0] * r[2]
        frames[p, 0, 2, 2] = t[0] * r[1] - t[1] * r[0]
        _mat_to_quat(frames[p, 0], q0[p])
        # propagate the frame along the segments
        for j in range(m - 2):
            if lengths[p, j + 1] > _EPS:
                for d in range(3):
                    tn[d] = (points[p, j + 2, d] - points[p, j + 1, d]) / lengths[p, j + 1]
            else:  # a zero-length segment keeps the direction
                for d in range(3):
                    tn[d] = t[d]
            # double reflection (Wang et al. 2008) with the bisector chord v1 = t + tn: the
            # composition is the rotation about t x tn by the angle between t and tn
            v1x, v1y, v1z = t[0] + tn[0], t[1] + tn[1], t[2] + tn[2]
            c1 = v1x * v1x + v1y * v1y + v1z * v1z
            if c1 < 1e-24:  # the segment folds back: half turn about the normal
                for d in range(3):
                    r[d] = frames[p, j, d, 1]
            else:
                for d in range(3):
                    r[d] = frames[p, j, d, 1]
                k1r = 2.0 * (v1x * r[0] + v1y * r[1] + v1z * r[2]) / c1
                k1t = 2.0 * (v1x * t[0] + v1y * t[1] + v1z * t[2]) / c1
                rl[0], rl[1], rl[2] = r[0] - k1r * v1x, r[1] - k1r * v1y, r[2] - k1r * v1z
                tl[0], tl[1], tl[2] = t[0] - k1t * v1x, t[1] - k1t * v1y, t[2] - k1t * v1z
                v2x, v2y, v2z = tn[0] - tl[0], tn[1] - tl[1], tn[2] - tl[2]
                c2 = v2x * v2x + v2y * v2y + v2z * v2z
                if c2 < 1e-300:
                    for d in range(3):
                        r[d] = rl[d]
                else:
                    k2 = 2.0 * (v2x * rl[0] + v2y * rl[1] + v2z * rl[2]) / c2
                    r[0], r[1], r[2] = rl[0] - k2 * v2x, rl[1] - k2 * v2y, rl[2] - k2 * v2z
            # re-orthonormalize against rounding
            dt = r[0] * tn[0] + r[1] * tn[1] + r[2] * tn[2]
            for d in range(3):
                r[d] -= dt * tn[d]
            nr = math.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
            for d in range(3):
                r[d] /= nr
            frames[p, j + 1, :, 0] = tn
            frames[p, j + 1, :, 1] = r
            frames[p, j + 1, 0, 2] = tn[1] * r[2] - tn[2] * r[1]
            frames[p, j + 1, 1, 2] = tn[2] * r[0] - tn[0] * r[2]
            frames[p, j + 1, 2, 2] = tn[0] * r[1] - tn[1] * r[0]
            # the rotation in the moving frame: F_j^T F_{j+1}
            for a in range(3):
                for b in range(3):
                    acc = 0.0
                    for d in range(3):
                        acc += frames[p, j, d, a] * frames[p, j + 1, d, b]
                    loc[a, b] = acc
            _mat_to_quat(loc, rots[p, j])
            for d in range(3):
                t[d] = tn[d]


def _decode_py(base, q0, lengths, rots, points):
    """Rebuild P polylines (P, m, 3) from their encoding (inverse of the encoder)."""
    n_poly, m = points.shape[0], points.shape[1]
    f = np.empty((3, 3))
    g = np.empty((3, 3))
    loc = np.empty((3, 3))
    for p in range(n_poly):
        _quat_to_mat(q0[p], f)
        for d in range(3):
            points[p, 0, d] = base[p, d]
        for j in range(m - 1):
            for d in range(3):
                points[p, j + 1, d] = points[p, j, d] + lengths[p, j] * f[d, 0]
            if j < m - 2:
                _quat_to_mat(rots[p, j], loc)
                for a in range(3):
                    for b in range(3):
                        acc = 0.0
                        for d in range(3):
                            acc += f[a, d] * loc[d, b]
                        g[a, b] = acc
                for a in range(3):
                    for b in range(3):
                        f[a, b] = g[a, b]


def _blend_py(base_a, q0_a, len_a, rot_a, base_b, q0_b, len_b, rot_b, s,
              base, q0, lengths, rots):
    """Blend two encodings: lerp base points and lengths, slerp base frames and rotations."""
    n_poly = base_a.shape[0]
    nseg = len_a.shape[1]
    for p in range(n_poly):
        for d in range(3):
            base[p, d] = (1.0 - s) * base_a[p, d] + s * base_b[p, d]
        _slerp(q0_a[p], q0_b[p], s, q0[p])
        for j in range(nseg):
            lengths[p, j] = (1.0 - s) * len_a[p, j] + s * len_b[p, j]
        for j in range(nseg - 1):
            _slerp(rot_a[p, j], rot_b[p, j], s, rots[p, j])


_encode = njit(cache=True)(_encode_py)
_decode = njit(cache=True)(_decode_py)
_blend = njit(cache=True)(_blend_py)


# --------------------------------------------------------------------------------------------------
# Python API
# --------------------------------------------------------------------------------------------------


class PolylineCode:
    """Intrinsic encoding of P polylines of m points.

    Attributes
    ----------
    base : (P, 3) float64        base points
    q0 : (P, 4) float64          base frames as unit quaternions (w, x, y, z)
    lengths : (P, m - 1) float64 segment lengths
    rots : (P, m - 2, 4) float64 rotations between consecutive segments, in the moving frame
    """

    __slots__ = ("base", "q0", "lengths", "rots")

    def __init__(self, base, q0, lengths, rots):
        self.base, self.q0, self.lengths, self.rots = base, q0, lengths, rots

    @property
    def m(self) -> int:
        return self.lengths.shape[1] + 1


def reference_vectors(*polyline_sets) -> np.ndarray:
    """A base-normal reference per polyline that is usable in every given pose.

    For each polyline the candidate among +Z, +X, +Y (in that order of preference) that is
    farthest from parallel to the first segment in all poses; the same reference for every pose
    makes the base frames of the poses comparable (a petal in the XY plane gets the normal +Z in
    each pose, so its base frame turns about +Z only).

    Parameters
    ----------
    *polyline_sets : (P, m, 3) arrays, one per pose

    Returns
    -------
    (P, 3) float64
    """
    cands = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    worst = np.full((polyline_sets[0].shape[0], 3), np.inf)
    for pts in polyline_sets:
        seg = np.diff(np.asarray(pts, dtype=np.float64), axis=1)
        ln = la.norm(seg, axis=2)
        first = np.argmax(ln > _EPS, axis=1)
        t = seg[np.arange(len(seg)), first]
        t /= np.maximum(la.norm(t, axis=1, keepdims=True), 1e-300)
        sin = np.sqrt(np.maximum(0.0, 1.0 - la.matmul(t, cands.T) ** 2))  # (P, 3)
        worst = np.minimum(worst, sin)
    choice = np.argmax(worst > 0.5, axis=1)  # the first well-conditioned candidate
    none_ok = ~(worst > 0.5).any(axis=1)
    choice[none_ok] = np.argmax(worst[none_ok], axis=1)
    return cands[choice]


def encode_polylines(points, ref=None) -> PolylineCode:
    """Encode polylines (P, m, 3) (m >= 2) intrinsically; ``ref`` (P, 3) fixes the base normals."""
    pts = np.ascontiguousarray(points, dtype=np.float64)
    if pts.ndim != 3 or pts.shape[2] != 3 or pts.shape[1] < 2:
        raise ValueError(f"polylines must be (P, m, 3) with m >= 2, got {pts.shape}")
    n, m = pts.shape[:2]
    ref = reference_vectors(pts) if ref is None else np.ascontiguousarray(ref, dtype=np.float64)
    code = PolylineCode(np.empty((n, 3)), np.empty((n, 4)), np.empty((n, m - 1)),
                        np.zeros((n, max(m - 2, 0), 4)))
    frames = np.empty((n, m - 1, 3, 3))
    _encode(pts, ref, code.base, code.q0, code.lengths, code.rots, frames)
    return code


def rmf_frames(points, ref=None) -> np.ndarray:
    """The rotation-minimizing frame of every segment: (P, m - 1, 3, 3), columns t, n, b."""
    pts = np.ascontiguousarray(points, dtype=np.float64)
    n, m = pts.shape[:2]
    ref = reference_vectors(pts) if ref is None else np.ascontiguousarray(ref, dtype=np.float64)
    frames = np.empty((n, m - 1, 3, 3))
    _encode(pts, ref, np.empty((n, 3)), np.empty((n, 4)), np.empty((n, m - 1)),
            np.zeros((n, max(m - 2, 0), 4)), frames)
    return frames


def decode_polylines(code: PolylineCode) -> np.ndarray:
    """Rebuild the (P, m, 3) polylines of an encoding."""
    out = np.empty((code.base.shape[0], code.m, 3))
    _decode(code.base, code.q0, code.lengths, code.rots, out)
    return out


def blend_codes(a: PolylineCode, b: PolylineCode, s: float) -> PolylineCode:
    """Blend two encodings of the same shape at ``s`` in [0, 1] (0: a, 1: b)."""
    if a.lengths.shape != b.lengths.shape:
        raise ValueError("blended polylines must have the same shape")
    n, nseg = a.lengths.shape
    out = PolylineCode(np.empty((n, 3)), np.empty((n, 4)), np.empty((n, nseg)),
                       np.zeros((n, max(nseg - 1, 0), 4)))
    _blend(a.base, a.q0, a.lengths, a.rots, b.base, b.q0, b.lengths, b.rots, float(s),
           out.base, out.q0, out.lengths, out.rots)
    return out


def blend_polylines(a, b, s: float) -> np.ndarray:
    """Intrinsic blend of two sets of polylines (P, m, 3) at ``s``: encode both, blend, rebuild."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    ref = reference_vectors(a, b)
    return decode_polylines(blend_codes(encode_polylines(a, ref), encode_polylines(b, ref), s))
