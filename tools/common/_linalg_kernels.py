"""The numba kernels of :mod:`inflo.tools.common.linalg` (imported on first use): fixed-order
products, Gauss-Jordan inverses, LU determinants and cyclic Jacobi eigenvectors of small matrices,
no fast-math (no FMA, no reassociation), so the same bits on every x86-64 processor."""
from __future__ import annotations

import math

import numpy as np
from numba import njit

# -- kernels ----------------------------------------------------------------------------------


@njit(cache=True)
def _matmul_kernel(a, b, out):
    """``out[s] = a[s] @ b[s]`` for stacks (s, n, k) and (s, k, m) (any strides: broadcast views),
    each entry ``((a0 b0 + a1 b1) + a2 b2) + ...`` in index order, every product and sum rounded
    (no fast-math: no FMA, no reassociation)."""
    for q in range(a.shape[0]):
        for i in range(a.shape[1]):
            for j in range(b.shape[2]):
                acc = a[q, i, 0] * b[q, 0, j]
                for t in range(1, a.shape[2]):
                    acc = acc + a[q, i, t] * b[q, t, j]
                out[q, i, j] = acc


@njit(cache=True, inline="always")
def _pivot_swap(w, c, n):
    """Partial pivoting in column ``c`` of the working rows ``w`` (rows c..n-1): the row of the
    largest magnitude (the first of equals) swapped into row ``c``. Returns that magnitude (0:
    singular) and whether rows were swapped."""
    p = c
    best = abs(w[c, c])
    for r in range(c + 1, n):
        v = abs(w[r, c])
        if v > best:
            best = v
            p = r
    if p != c and best != 0.0:
        for j in range(w.shape[1]):
            t = w[c, j]
            w[c, j] = w[p, j]
            w[p, j] = t
    return best, p != c


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
            best, _ = _pivot_swap(w, c, n)
            if best == 0.0 or not np.isfinite(best):
                return q
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
            best, swapped = _pivot_swap(w, c, n)
            if best == 0.0:
                d = 0.0
                break
            if swapped:
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


