"""Fixed-order small linear algebra: the same bits on every x86-64 processor.

numpy's ``@`` / ``np.matmul`` / ``np.dot``, ``np.linalg.norm`` of a whole array, ``inv``,
``det`` and ``svd`` go to OpenBLAS and LAPACK, which pick their kernels by processor at load
time (``DYNAMIC_ARCH``): the Haswell, SkylakeX and Zen kernels order and fuse the products
differently, so the last bits of a 4 x 4 inverse or a 3-vector's norm differ between an Intel
Xeon and an AMD EPYC. fccompose's collision response amplifies such bits in crowded frames
until the vertices differ visibly (a gaillardia frame, two yarrow frames). numpy's
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
  (:mod:`._linalg_kernels`: Gauss-Jordan and LU with partial pivoting, cyclic Jacobi rotations)
  with no fast-math, so LLVM neither reassociates nor contracts them whatever processor it
  compiles for; float64 products go to a kernel of the same order where numba is loaded already
  (bit for bit the numpy loop's: tested), so a numpy-only tool (polygonize) does not import it.

``tests/test_linalg.py`` checks each function against numpy on random input (to rounding) and
``tests/test_portable.py`` builds stages under other OpenBLAS kernels, without numpy's
AVX-512 paths and with numba compiling for a generic x86-64, byte for byte.
"""
from __future__ import annotations

import math
import sys

import numpy as np

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
    lead = np.broadcast_shapes(a.shape[:-2], b.shape[:-2])
    if k == 0:
        out = np.zeros(lead + (a.shape[-2], b.shape[-1]), np.result_type(a, b))
    elif a.dtype == np.float64 and b.dtype == np.float64 and "numba" in sys.modules:
        # the kernel (where numba is loaded already: a numpy-only tool does not pay its import):
        # the same sums in the same order as the loop, without a temporary per k
        kernel = _kernels()._matmul_kernel
        if a.ndim == 2 and b.ndim == 2:
            out = np.empty((1, a.shape[0], b.shape[1]))
            kernel(a[None], b[None], out)
            out = out[0]
        else:
            a3 = np.broadcast_to(a, lead + a.shape[-2:]).reshape((-1,) + a.shape[-2:])
            b3 = np.broadcast_to(b, lead + b.shape[-2:]).reshape((-1,) + b.shape[-2:])
            out = np.empty((a3.shape[0], a.shape[-2], b.shape[-1]))
            kernel(a3, b3, out)
            out = out.reshape(lead + out.shape[1:])
    else:
        out = _matmul_loop(a, b)
    if va:
        out = out[..., 0, :]
    if vb:
        out = out[..., 0]
    return out


def _matmul_loop(a, b) -> np.ndarray:
    """``a @ b`` for (..., n, k) and (..., k, m) by numpy elementwise operations, k = 0, 1, ... in order
    (any float type; float64 goes to the numba kernel where numba is loaded: the same bits)."""
    out = a[..., :, 0:1] * b[..., 0:1, :]
    for j in range(1, a.shape[-1]):
        out = out + a[..., :, j:j + 1] * b[..., j:j + 1, :]
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


def _kernels():
    """The numba kernels (:mod:`._linalg_kernels`), imported on first use."""
    from . import _linalg_kernels

    return _linalg_kernels


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
    bad = _kernels()._inv_kernel(a, out)
    if bad >= 0:
        raise np.linalg.LinAlgError(f"Singular matrix (matrix {bad} of the stack)")
    return out.reshape(lead + a.shape[1:])


def det(m):
    """Determinant of a square matrix (``float``) or of each of a stack (array)."""
    a, lead = _stack(m, "det")
    out = np.empty(len(a))
    _kernels()._det_kernel(a, out)
    return float(out[0]) if not lead else out.reshape(lead)


def eigh_jacobi(m, sweeps: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (ascending) and unit eigenvectors (columns) of a symmetric matrix or a stack,
    by cyclic Jacobi rotations: ``np.linalg.eigh`` without LAPACK."""
    a, lead = _stack(m, "eigh_jacobi")
    n = a.shape[1]
    values = np.empty((len(a), n))
    vectors = np.empty_like(a)
    _kernels()._eigh_kernel(a, values, vectors, sweeps)
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
