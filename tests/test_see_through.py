"""Background seen through a mesh (inflo.tools.species.checks.see_through): a slit or hole
enclosed by the silhouette counts, a notch open to the outside does not.
"""
from __future__ import annotations

import numpy as np
import pytest

from inflo.formats.obj import ObjMesh
from inflo.tools.species.checks import (
    ALL_VIEWS,
    depth_fill,
    region_in_view,
    see_through,
    view_axes,
    view_coverage,
    worst_see_through,
)


def _cells(cells) -> ObjMesh:
    """Unit squares (i, j) of the plane z = 0, two triangles each."""
    v, f = [], []
    for i, j in cells:
        k = len(v)
        v += [(i, j, 0.0), (i + 1, j, 0.0), (i + 1, j + 1, 0.0), (i, j + 1, 0.0)]
        f += [(k, k + 1, k + 2), (k, k + 2, k + 3)]
    return ObjMesh(vertices=np.array(v, float), faces=np.array(f, np.int32))


RING = [(i, j) for i in range(3) for j in range(3) if (i, j) != (1, 1)]  # a frame round a hole
NOTCH = [(i, j) for i in range(3) for j in range(3) if (i, j) not in ((1, 1), (1, 2))]  # a U


def test_view_axes_are_orthonormal_and_across_the_view():
    for az, el in ALL_VIEWS:
        r, u = view_axes(az, el)
        d = np.cross(r, u)
        assert np.allclose([r @ r, u @ u, r @ u], [1.0, 1.0, 0.0])
        a, e = np.radians(az), np.radians(el)
        assert np.allclose(d, [np.cos(e) * np.sin(a), np.sin(e), np.cos(e) * np.cos(a)], atol=1e-12)


def test_a_hole_is_seen_through_a_notch_is_not():
    h, c = see_through(_cells(RING), 0.0, 0.0, pixels=301)
    assert h / c == pytest.approx(1 / 8, rel=0.03)  # hole 1, frame 8 unit squares
    h, c = see_through(_cells(NOTCH), 0.0, 0.0, pixels=301)
    assert h == 0 and c > 0
    # from behind the same; edge-on (from +X) nothing is seen through a flat sheet
    h, c = see_through(_cells(RING), 180.0, 0.0, pixels=301)
    assert h / c == pytest.approx(1 / 8, rel=0.03)
    assert see_through(_cells(RING), 90.0, 0.0, pixels=301)[0] == 0


def test_worst_view_finds_the_slit():
    share, view = worst_see_through(_cells(RING), views=((90.0, 0.0), (0.0, 90.0), (10.0, 20.0)), pixels=201)
    assert view == (10.0, 20.0) and 0.05 < share < 0.15
    assert worst_see_through(_cells(NOTCH))[0] == 0.0


def test_fill_triangles_covers_the_area_and_skips_degenerate_ones():
    from inflo.tools.species.checks import fill_triangles

    pts = np.array([[0.0, 0.0], [100.0, 0.0], [0.0, 60.0], [5.0, 5.0], [5.0, 5.0], [9.0, 9.0]])
    img = fill_triangles(pts, np.array([[0, 1, 2]]), 120, 80)
    assert img.shape == (80, 120) and abs(int(img.sum()) - 3000) < 100 + 2  # area 3000, edges count
    assert img[0, 0] and img[59, 0] and not img[59, 99] and not img[79, 119]
    assert not fill_triangles(pts, np.array([[3, 4, 5]]), 20, 20).any()  # zero area: nothing


def test_enclosed_background_is_what_scipy_fills():
    """The flood fill counts exactly the holes scipy.ndimage.binary_fill_holes fills (4-neighbours):
    a one-pixel hole, a hole touching only diagonally the outside, a notch, random images."""
    from scipy import ndimage

    from inflo.tools.species.checks import enclosed_background

    ring = np.ones((3, 3), bool)
    ring[1, 1] = False
    assert enclosed_background(ring) == 1
    notch = ring.copy()
    notch[2, 1] = False  # open to the border
    assert enclosed_background(notch) == 0
    diag = np.ones((4, 4), bool)
    diag[1, 1] = diag[2, 2] = False  # two holes meeting at a corner only: both enclosed
    assert enclosed_background(diag) == 2
    assert enclosed_background(np.zeros((1, 1), bool)) == 0
    rng = np.random.default_rng(5)
    for _ in range(100):
        img = rng.random(tuple(rng.integers(1, 30, 2))) < rng.random()
        assert enclosed_background(img) == int((ndimage.binary_fill_holes(img) & ~img).sum())


def test_fill_triangles_covers_the_centres_inside():
    """Pixel centres inside or on a triangle are covered, the others not (against the barycentric
    test of every pixel of the image)."""
    from inflo.tools.species.checks import fill_triangles

    rng = np.random.default_rng(3)
    pts = rng.random((30, 2)) * 40.0
    faces = rng.integers(0, 30, (20, 3)).astype(np.int64)
    img = fill_triangles(pts, faces, 41, 41)
    want = np.zeros((41, 41), bool)
    for a, b, c in faces:
        (ax, ay), (bx, by), (cx, cy) = pts[a], pts[b], pts[c]
        area = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
        if area == 0.0:
            continue
        y, x = np.mgrid[0:41, 0:41].astype(float)
        w0 = ((bx - x) * (cy - y) - (by - y) * (cx - x)) / area
        w1 = ((cx - x) * (ay - y) - (cy - y) * (ax - x)) / area
        want |= (w0 >= -1e-9) & (w1 >= -1e-9) & (1.0 - w0 - w1 >= -1e-9)
    assert img.any() and (img == want).all()


def _square(z: float, lo: float = 0.0, hi: float = 1.0) -> ObjMesh:
    """The square [lo, hi]^2 of the plane at height z (Y up: the plane y = z), two triangles."""
    v = np.array([(lo, z, lo), (hi, z, lo), (hi, z, hi), (lo, z, hi)], float)
    return ObjMesh(vertices=v, faces=np.array([(0, 1, 2), (0, 2, 3)], np.int32))


def test_region_in_view_is_depth_buffered():
    """A receptacle (the region) under a cover seen from above is hidden where the cover is in
    front of it, and not at all where the cover is behind it (from below); a cover over half of it
    leaves half in view; one triangle with its three vertices at one point draws nothing."""
    region = _square(0.0)
    over = _square(1.0, -0.5, 1.5)
    assert region_in_view(over, region, 0.0, 90.0) == 0.0  # from above: the cover is in front
    assert region_in_view(over, region, 0.0, -90.0) == 1.0  # from below: the cover is behind it
    half = ObjMesh(vertices=np.array([(-1, 1, -1), (0.5, 1, -1), (0.5, 1, 2), (-1, 1, 2)], float),
                   faces=np.array([(0, 1, 2), (0, 2, 3)], np.int32))
    assert region_in_view(half, region, 0.0, 90.0) == pytest.approx(0.5, abs=0.01)
    dot = ObjMesh(vertices=np.array([(0.5, 1, 0.5)] * 3, float), faces=np.array([(0, 1, 2)], np.int32))
    assert region_in_view(dot, region, 0.0, 90.0) == 1.0
    # the silhouettes' measure counts a cover behind the region as hiding it
    assert 1.0 - view_coverage(over, 1, region=region) == 0.0


def test_depth_fill_keeps_the_nearer_triangle():
    pts = np.array([(0, 0), (4, 0), (0, 4), (0, 0), (4, 0), (0, 4)], float)
    depth = np.array([0, 0, 0, 1, 1, 1], float)
    zbuf = np.full((5, 5), -np.inf)
    label = np.zeros((5, 5), np.int8)
    depth_fill(pts, depth, np.array([(3, 4, 5)], np.int64), 1, zbuf, label)  # the near one first
    depth_fill(pts, depth, np.array([(0, 1, 2)], np.int64), 2, zbuf, label)
    assert (label == 1).sum() == 15 and (label == 2).sum() == 0  # 15 pixel centres in the closed triangle
    assert np.all(zbuf[label == 1] == 1.0)
