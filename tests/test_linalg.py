"""inflo.tools.common.linalg: fixed-order products, norms, inverses, determinants, eigenvectors
and Kabsch rotations agree with numpy/LAPACK to rounding, in the order they promise (same bytes on every machine)."""
import numpy as np
import pytest

from inflo.tools.common import linalg as la

rng = np.random.default_rng(53)


@pytest.mark.parametrize("sa, sb", [((4, 4), (4, 4)), ((5, 4, 4), (4, 4)), ((4, 4), (5, 4, 4)),
                                    ((2, 1, 3, 4), (5, 4, 2)), ((4,), (4, 3)), ((3, 4), (4,)),
                                    ((4,), (4,)), ((100, 3), (3, 3)), ((7, 0), (0, 2))])
def test_matmul_matches_numpy_shapes_and_values(sa, sb):
    a, b = rng.normal(size=sa), rng.normal(size=sb)
    got, want = la.matmul(a, b), np.matmul(a, b)
    assert np.shape(got) == np.shape(want)
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13)


def test_matmul_sums_in_index_order():
    # (1e16 + 1) - 1e16 in order is 0 (1 is lost); any other order gives 1 or 2
    a = np.array([[1e16, 1.0, -1e16]])
    b = np.ones((3, 1))
    assert la.matmul(a, b)[0, 0] == ((1e16 + 1.0) - 1e16)
    assert la.dot(a[0], b[:, 0]) == ((1e16 + 1.0) - 1e16) == 0.0


def test_matmul_rejects_mismatch_and_scalars():
    with pytest.raises(ValueError):
        la.matmul(np.ones((2, 3)), np.ones((2, 3)))
    with pytest.raises(ValueError):
        la.matmul(np.ones(3), 2.0)


def test_norm_dot_rowdot_normalize():
    v = rng.normal(size=(50, 3))
    assert la.norm(v[0]) == pytest.approx(np.linalg.norm(v[0]), rel=1e-15)
    np.testing.assert_array_equal(la.norm(v, axis=1), np.sqrt((v * v).sum(axis=1)))
    assert la.norm(v, axis=1, keepdims=True).shape == (50, 1)
    np.testing.assert_allclose(la.rowdot(v, v[::-1]), np.einsum("ij,ij->i", v, v[::-1]), rtol=1e-14)
    np.testing.assert_allclose(la.norm(la.normalize(v, axis=1), axis=1), 1.0, rtol=1e-15)
    assert la.norm(np.zeros(3)) == 0.0
    np.testing.assert_array_equal(la.normalize(np.zeros(3), floor=1e-12), np.zeros(3))


def test_inv_and_det_match_lapack():
    m = rng.normal(size=(20, 4, 4))
    np.testing.assert_allclose(la.inv(m), np.linalg.inv(m), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(la.det(m), np.linalg.det(m), rtol=1e-12)
    assert isinstance(la.det(m[0]), float)
    # a rigid 4 x 4 transform: the inverse is exact to rounding
    r = la.kabsch(rng.normal(size=(6, 3)), rng.normal(size=(6, 3)))[0]
    t = np.eye(4)
    t[:3, :3], t[:3, 3] = r, [1.0, -2.0, 3.0]
    np.testing.assert_allclose(la.matmul(t, la.inv(t)), np.eye(4), atol=1e-14)
    # pivoting: a zero leading entry
    p = np.array([[0.0, 1.0], [1.0, 0.0]])
    np.testing.assert_array_equal(la.inv(p), p)
    assert la.det(p) == -1.0


def test_inv_of_singular_matrix_raises_like_numpy():
    m = np.stack([np.eye(3), np.array([[1.0, 2, 3], [2, 4, 6], [0, 0, 1]])])
    with pytest.raises(np.linalg.LinAlgError, match="matrix 1"):
        la.inv(m)
    assert la.det(m[1]) == 0.0
    with pytest.raises(ValueError):
        la.inv(np.ones((2, 3)))


def test_eigh_jacobi_matches_lapack():
    a = rng.normal(size=(10, 4, 4))
    s = a + a.transpose(0, 2, 1)
    w, v = la.eigh_jacobi(s)
    np.testing.assert_allclose(w, np.linalg.eigvalsh(s), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(la.matmul(s, v), v * w[:, None, :], atol=1e-12)
    np.testing.assert_allclose(la.matmul(v.transpose(0, 2, 1), v), np.broadcast_to(np.eye(4), s.shape), atol=1e-13)
    # diagonal and repeated eigenvalues: nothing to rotate, the identity back
    w, v = la.eigh_jacobi(np.diag([3.0, 1.0, 1.0]))
    np.testing.assert_array_equal(w, [1.0, 1.0, 3.0])
    assert abs(la.det(v)) == pytest.approx(1.0)


def _random_rotation():
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _svd_kabsch(p, q):
    h = (p - p.mean(0)).T @ (q - q.mean(0))
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    return vt.T @ np.diag([1.0, 1.0, d]) @ u.T


@pytest.mark.parametrize("points", ["general", "coplanar ring", "noisy"])
def test_kabsch_recovers_rotation_and_agrees_with_svd(points):
    if points == "coplanar ring":  # the base particles of a petal-grow organ
        ang = np.linspace(0, 2 * np.pi, 9)[:-1]
        p = np.stack([np.cos(ang), np.zeros(8), np.sin(ang)], axis=1)
    else:
        p = rng.normal(size=(12, 3))
    r_true = _random_rotation()
    q = la.matmul(p, r_true.T) + np.array([0.5, -1.0, 2.0])
    if points == "noisy":
        q = q + 0.01 * rng.normal(size=q.shape)
    r, t = la.kabsch(p, q)
    np.testing.assert_allclose(r, _svd_kabsch(p, q), atol=1e-9)
    assert la.det(r) == pytest.approx(1.0, abs=1e-12)
    if points != "noisy":
        np.testing.assert_allclose(r, r_true, atol=1e-10)
        np.testing.assert_allclose(la.matmul(p, r.T) + t, q, atol=1e-10)


def test_kabsch_of_coincident_points_is_a_rotation():
    p = np.zeros((4, 3))
    r, t = la.kabsch(p, p + 1.0)
    np.testing.assert_allclose(la.matmul(r, r.T), np.eye(3), atol=1e-14)
    np.testing.assert_allclose(t, 1.0)


@pytest.mark.parametrize("sa, sb", [((4, 4), (4, 4)), ((300, 64), (64, 3)), ((1, 50, 16), (5, 16, 3)),
                                    ((7, 3, 4), (4, 2)), ((2, 1, 3, 4), (5, 4, 2))])
def test_matmul_kernel_gives_the_bits_of_the_elementwise_loop(sa, sb):
    """float64 products go to a numba kernel; it sums in the order of the numpy loop (the float32
    path), so both give the same bits: no FMA, no reassociation on this processor's code."""
    a, b = rng.normal(size=sa), rng.normal(size=sb)
    import numba  # noqa: F401  (the kernel path)

    assert np.array_equal(la.matmul(a, b), la._matmul_loop(a, b))
    np.testing.assert_allclose(la.matmul(a, b), a @ b, rtol=1e-12, atol=1e-12)
