"""Background seen through a mesh (inflo.tools.species.checks.see_through): a slit or hole
enclosed by the silhouette counts, a notch open to the outside does not.
"""
from __future__ import annotations

import numpy as np
import pytest

from inflo.formats.obj import ObjMesh
from inflo.tools.species.checks import ALL_VIEWS, see_through, view_axes, worst_see_through


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
