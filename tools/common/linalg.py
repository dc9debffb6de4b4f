"""Fixed-order small linear algebra: the same bits on every x86-64 processor.

numpy's ``@`` / ``np.matmul`` / ``np.dot``, ``np.linalg.norm`` of a whole array, ``inv``,
``det`` and ``svd`` go to OpenBLAS and LAPACK, which pick their kernels by processor at load
time (``DYNAMIC_ARCH``): the Haswell, SkylakeX and Zen kernels order and fuse the products
differently, so the last bits of a 4 x 4 inverse or a 3-vector's norm differ between an Intel
Xeon and an AMD EPYC. fccompose's collision response amplifies such bits in crowded frames
until the vertices differ visibly (issue 53: a gaillardia frame, two yarrow frames). numpy's
``np.einsum`` reduces contiguous axes with SIMD accumulators whose width and FMA use follow
the processor as well.

Every result-affecting product, norm, inverse and decomposition in inflo goes through this
module instead. Its operation order is written out:

* products and dot products sum ``a[..., k] * b[k, ...]`` for k = 0, 1, 2, ... in that order,
  one numpy elementwise multiply and add per k (elementwise ufuncs are correctly rounded on
  every SIMD path and numpy never fuses a multiply and an add);
* reductions over an axis (``norm``, ``rowdot``) use ``np.add.reduce``, whose pairwise sum is
  scalar code whose order depends only on the length;
* ``inv``, ``det`` and the symmetric eigenproblem behind :func:`kabsch` are numba kernels
  (Gauss-Jordan and LU with partial pivoting, cyclic Jacobi rotations) with no fast-math, so
  LLVM neither reassociates nor contracts them whatever processor it compiles for.

``tests/test_linalg.py`` checks each function against numpy on random input (to rounding) and
``tests/test_portable.py`` builds stages under other OpenBLAS kernels, without numpy's
AVX-512 paths and with numba compiling for a generic x86-64, byte for byte.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["matmul", "dot", "rowdot", "norm", "normalize", "inv", "det", "kabsch", "eigh_jacobi"]


def matmul(a, b) -> np.ndarray:
    """``a @ b`` with numpy's broadcasting and 1-D rules, summed in the order k = 0, 1, ...

    Parameters
    ----------
    a : (..., n, k) or (k,) array_like
    b : (..., k, m) or (k,) array_like

    Returns
    -------
    ndarray
        float64 (or the common float type) of numpy's ``matmul`` shape; a 0-d array for two
        vectors.
    """
    a = np.asarray(a)
    b = np.asarray(b)
    if a.dtype.kind not in "fc":
        a = a.astype(np.float64)
    if b.dtype.kind not in "fc":
        b = b.astype(np.float64)
    if a.ndim == 0 or b.ndim == 0:
        raise ValueError("matmul: scalar operands are not allowed, use '*' instead")
    va, vb = a.ndim == 1, b.ndim == 1
    if va:
        a = a[None, :]
    if vb:
        b = b[:, None]
    k = a.shape[-1]
    if b.shape[-2] != k:
        raise ValueError(f"matmul: mismatch in the core dimension: {a.shape} and {b.shape}")
    if k == 0:
        out = np.zeros(np.broadcast_shapes(a.shape[:-2], b.shape[:-2]) + (a.shape[-2], b.shape[-1]),
                       np.result_type(a, b))
    else:
        out = a[..., :, 0:1] * b[..., 0:1, :]
        for j in range(1, k):
            out = out + a[..., :, j:j + 1] * b[..., j:j + 1, :]
    if va:
        out = out[..., 0, :]
    if vb:
        out = out[..., 0]
    return out


def dot(a, b) -> float:
    """The dot product of two vectors, summed in order (``float``)."""
    a = np.asarray(a, np.float64).ravel()
    b = np.asarray(b, np.float64).ravel()
    if a.shape != b.shape:
        raise ValueError(f"dot: shapes {a.shape} and {b.shape} differ")
    return float(np.add.reduce(a * b))


def rowdot(a, b, axis: int = -1) -> np.ndarray:
    """Dot products along ``axis`` of two broadcastable arrays (``einsum('ij,ij->i')``)."""
    return np.add.reduce(np.asarray(a, np.float64) * np.asarray(b, np.float64), axis=axis)


def norm(x, axis=None, keepdims: bool = False):
    """Euclidean norm of the whole array (``axis=None``: a ``float``) or along ``axis``;
    ``np.linalg.norm``'s default, without its BLAS dot product."""
    x = np.asarray(x, np.float64)
    if axis is None:
        return math.sqrt(float(np.add.reduce(x.ravel() * x.ravel())))
    return np.sqrt(np.add.reduce(x * x, axis=axis, keepdims=keepdims))


def normalize(x, axis=None, floor: float = 0.0) -> np.ndarray:
    """``x / norm(x)`` (whole array or along ``axis``), the norm clamped below by ``floor``."""
    x = np.asarray(x, np.float64)
    if axis is None:
        return x / max(norm(x), floor)
    return x / np.maximum(norm(x, axis=axis, keepdims=True), floor)


# -- kernels ----------------------------------------------------------------------------------


@njit(cache=True)
def _inv_kernel(a, out):
    """Gauss-Jordan with partial pivoting on each (n, n) matrix of ``a`` (s, n, n) into
    ``out``; returns the index of the first singular matrix, or -1."""
    s, n, _ = a.shape
    w = np.empty((n, 2 * n))
    for q in range(s):
        for i in range(n):
            for j in range(n):
                w[i, j] = a[q, i, j]
                w[i, n + j] = 1.0 if i == j else 0.0
        for c in range(n):
            p = c
            best = abs(w[c, c])
            for r in range(c + 1, n):
                v = abs(w[r, c])
                if v > best:
                    best = v
                    p = r
            if best == 0.0 or not np.isfinite(best):
                return q
            if p != c:
                for j in range(2 * n):
                    t = w[c, j]
                    w[c, j] = w[p, j]
                    w[p, j] = t
            piv = w[c, c]
            for j in range(2 * n):
                w[c, j] = w[c, j] / piv
            for r in range(n):
                if r != c:
                    f = w[r, c]
                    if f != 0.0:
                        for j in range(2 * n):
                            w[r, j] = w[r, j] - f * w[c, j]
        for i in range(n):
            for j in range(n):
                out[q, i, j] = w[i, n + j]
    return -1


@njit(cache=True)
def _det_kernel(a, out):
    """Determinant of each (n, n) matrix of ``a`` (s, n, n) by LU with partial pivoting."""
    s, n, _ = a.shape
    w = np.empty((n, n))
    for q in range(s):
        for i in range(n):
            for j in range(n):
                w[i, j] = a[q, i, j]
        d = 1.0
        for c in range(n):
            p = c
            best = abs(w[c, c])
            for r in range(c + 1, n):
                v = abs(w[r, c])
                if v > best:
                    best = v
                    p = r
            if best == 0.0:
                d = 0.0
                break
            if p != c:
                for j in range(n):
                    t = w[c, j]
                    w[c, j] = w[p, j]
                    w[p, j] = t
                d = -d
            piv = w[c, c]
            d = d * piv
            for r in range(c + 1, n):
                f = w[r, c] / piv
                if f != 0.0:
                    for j in range(c, n):
                        w[r, j] = w[r, j] - f * w[c, j]
        out[q] = d


@njit(cache=True)
def _eigh_kernel(a, values, vectors, sweeps):
    """Cyclic Jacobi eigen-decomposition of each symmetric (n, n) matrix of ``a`` (s, n, n):
    ``values`` (s, n) ascending and the unit eigenvectors as the columns of ``vectors``
    (s, n, n), each column's largest component made positive. Rotations zero (p, q) in row
    order until the off-diagonal is below 1e-300 or after ``sweeps`` sweeps."""
    s, n, _ = a.shape
    m = np.empty((n, n))
    v = np.empty((n, n))
    for t in range(s):
        for i in range(n):
            for j in range(n):
                m[i, j] = 0.5 * (a[t, i, j] + a[t, j, i])
                v[i, j] = 1.0 if i == j else 0.0
        for _ in range(sweeps):
            off = 0.0
            for i in range(n):
                for j in range(i + 1, n):
                    off += m[i, j] * m[i, j]
            if off < 1e-300:
                break
            for p in range(n):
                for q in range(p + 1, n):
                    apq = m[p, q]
                    if apq == 0.0:
                        continue
                    theta = (m[q, q] - m[p, p]) / (2.0 * apq)
                    tt = 1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0))
                    if theta < 0.0:
                        tt = -tt
                    c = 1.0 / math.sqrt(tt * tt + 1.0)
                    sn = tt * c
                    for k in range(n):
                        mkp = m[k, p]
                        mkq = m[k, q]
                        m[k, p] = c * mkp - sn * mkq
                        m[k, q] = sn * mkp + c * mkq
                    for k in range(n):
                        mpk = m[p, k]
                        mqk = m[q, k]
                        m[p, k] = c * mpk - sn * mqk
                        m[q, k] = sn * mpk + c * mqk
                    for k in range(n):
                        vkp = v[k, p]
                        vkq = v[k, q]
                        v[k, p] = c * vkp - sn * vkq
                        v[k, q] = sn * vkp + c * vkq
        # ascending order (stable selection), sign fixed by the largest component
        order = np.argsort(np.array([m[i, i] for i in range(n)]), kind="mergesort")
        for jj in range(n):
            j = order[jj]
            values[t, jj] = m[j, j]
            big = 0
            for k in range(1, n):
                if abs(v[k, j]) > abs(v[big, j]):
                    big = k
            sg = -1.0 if v[big, j] < 0.0 else 1.0
            for k in range(n):
                vectors[t, k, jj] = sg * v[k, j]


def _stack(m, what: str) -> tuple[np.ndarray, tuple]:
    m = np.asarray(m, np.float64)
    if m.ndim < 2 or m.shape[-1] != m.shape[-2]:
        raise ValueError(f"{what}: square matrices expected, found shape {m.shape}")
    return np.ascontiguousarray(m.reshape((-1,) + m.shape[-2:])), m.shape[:-2]


def inv(m) -> np.ndarray:
    """Inverse of a square matrix or a stack of them (Gauss-Jordan, partial pivoting).

    Raises ``np.linalg.LinAlgError`` on a singular matrix, as ``np.linalg.inv`` does."""
    a, lead = _stack(m, "inv")
    out = np.empty_like(a)
    bad = _inv_kernel(a, out)
    if bad >= 0:
        raise np.linalg.LinAlgError(f"Singular matrix (matrix {bad} of the stack)")
    return out.reshape(lead + a.shape[1:])


def det(m):
    """Determinant of a square matrix (``float``) or of each of a stack (array)."""
    a, lead = _stack(m, "det")
    out = np.empty(len(a))
    _det_kernel(a, out)
    return float(out[0]) if not lead else out.reshape(lead)


def eigh_jacobi(m, sweeps: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (ascending) and unit eigenvectors (columns) of a symmetric matrix or a stack,
    by cyclic Jacobi rotations: ``np.linalg.eigh`` without LAPACK."""
    a, lead = _stack(m, "eigh_jacobi")
    n = a.shape[1]
    values = np.empty((len(a), n))
    vectors = np.empty_like(a)
    _eigh_kernel(a, values, vectors, sweeps)
    return values.reshape(lead + (n,)), vectors.reshape(lead + (n, n))


def kabsch(current, target) -> tuple[np.ndarray, np.ndarray]:
    """The proper rotation ``r`` and translation ``t`` minimizing
    ``sum |r @ current_i + t - target_i|^2`` over the rows of two (n, 3) point sets.

    Horn's quaternion method (J. Opt. Soc. Am. A 4, 1987): the unit quaternion is the
    eigenvector of the largest eigenvalue of a symmetric 4 x 4 matrix built from the
    cross-covariance, found by :func:`eigh_jacobi`. It agrees with the SVD form of the Kabsch
    algorithm where that is unique, and gives a proper rotation for coplanar, collinear or
    coincident points too.
    """
    p = np.asarray(current, np.float64)
    q = np.asarray(target, np.float64)
    cp = np.add.reduce(p, axis=0) / len(p)
    cq = np.add.reduce(q, axis=0) / len(q)
    h = matmul((p - cp).T, q - cq)  # h[i, j] = sum p_i q_j
    sxx, sxy, sxz = h[0]
    syx, syy, syz = h[1]
    szx, szy, szz = h[2]
    n = np.array([
        [sxx + syy + szz, syz - szy, szx - sxz, sxy - syx],
        [syz - szy, sxx - syy - szz, sxy + syx, szx + sxz],
        [szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy],
        [sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz],
    ])
    _, vec = eigh_jacobi(n)
    w, x, y, z = vec[:, 3]
    r = np.array([
        [w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z],
    ])
    return r, cq - matmul(r, cp)
