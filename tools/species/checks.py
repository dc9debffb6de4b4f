"""Checks shared by the species builds' check scripts (``check_<species>.py``).

Each species' ``check_<species>.py`` runs :func:`check_head` with its own facts (ray count, bud
height, extra per-frame or whole-run checks) and prints the same report: intersections of every
written canopy frame (exact static test, within the canopy and with the receptacle), the edge
stretch bounds from fccompose's log, every floret present at the end, the ray florets on the
margin, and the phase effect at two thirds of the run. ``from inflo.tools.species.checks import
check_head``.
"""
from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
from numba import njit
from PIL import Image, ImageDraw
from scipy.spatial import ConvexHull, QhullError

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.formats.rba import read_rba
from inflo.formats.scn import read_scn
from inflo.tools.collide import intersecting_pairs, intersecting_pairs_between
from inflo.tools.common import linalg as la

BOUNDS = (0.5, 1.5)


def _raster(points: np.ndarray, faces: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Boolean image of ``size`` (w, h) with every triangle of ``faces`` over pixel ``points``."""
    img = Image.new("1", size, 0)
    draw = ImageDraw.Draw(img)
    for f in faces:
        draw.polygon([tuple(points[i]) for i in f], fill=1)
    return np.asarray(img, bool)


def view_coverage(mesh, axis: int, pixels: int = 800, region=None) -> float:
    """Share of a region, seen along coordinate ``axis`` (orthographic), that the mesh's triangles
    cover: the region is the convex hull of the mesh's silhouette, or the silhouette of the mesh
    ``region`` (a receptacle, say: then one minus this is the share of it left in view). Both are
    rasterized on a grid of ``pixels`` across the larger side (Pillow polygons); 0 for a region
    with no area."""
    keep = [d for d in range(3) if d != axis]
    used = np.unique(mesh.faces)
    q = mesh.vertices[:, keep]
    pts = q[used] if region is None else np.vstack([q[used], region.vertices[np.unique(region.faces)][:, keep]])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    s = (pixels - 1) / float((hi - lo).max())
    size = (int(math.ceil((hi - lo)[0] * s)) + 1, int(math.ceil((hi - lo)[1] * s)) + 1)
    cover = _raster((q - lo) * s, mesh.faces, size)
    if region is not None:
        area = _raster((region.vertices[:, keep] - lo) * s, region.faces, size)
    else:
        px = (q - lo) * s
        try:
            hull = ConvexHull(px[used])
        except QhullError:  # a silhouette with no area (a flat mesh seen edge-on)
            return 0.0
        img = Image.new("1", size, 0)
        ImageDraw.Draw(img).polygon([tuple(px[used][i]) for i in hull.vertices], fill=1)
        area = np.asarray(img, bool)
    if not area.any():
        return 0.0
    return float((cover & area).sum()) / float(area.sum())


def view_axes(azimuth: float, elevation: float) -> tuple[np.ndarray, np.ndarray]:
    """Screen axes (right, up) of an orthographic view from this direction: azimuth in degrees
    about +Y from +Z towards +X, elevation in degrees above the horizontal (canopy-render's)."""
    a, e = math.radians(azimuth), math.radians(elevation)
    d = np.array([math.cos(e) * math.sin(a), math.sin(e), math.cos(e) * math.cos(a)])
    up = np.array([0.0, 1.0, 0.0]) if abs(d[1]) < 0.99 else np.array([0.0, 0.0, -1.0])
    right = la.normalize(np.cross(up, d))
    return right, np.cross(d, right)


@njit(cache=True, inline="always")
def _pixel_box(ax, ay, bx, by, cx, cy, width, height):
    """A triangle's doubled signed area and the pixel rows and columns its bounding box spans in
    an image of ``width`` x ``height`` (x0, x1, y0, y1; empty where x0 > x1 or y0 > y1)."""
    area = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    x0 = max(int(np.ceil(min(ax, bx, cx))), 0)
    x1 = min(int(np.floor(max(ax, bx, cx))), width - 1)
    y0 = max(int(np.ceil(min(ay, by, cy))), 0)
    y1 = min(int(np.floor(max(ay, by, cy))), height - 1)
    return area, x0, x1, y0, y1


@njit(cache=True)
def fill_triangles(points, faces, width, height):
    """Boolean image (height, width): the pixels whose centres (integer coordinates of
    ``points``' frame) lie in a triangle of ``faces`` (closed: on an edge counts). Row by row: the
    pixels more than 1e-6 inside the row's crossing with the triangle are filled, those within a
    pixel of its ends decided by the barycentric test (weights >= -1e-9)."""
    img = np.zeros((height, width), np.bool_)
    for f in range(faces.shape[0]):
        ax, ay = points[faces[f, 0], 0], points[faces[f, 0], 1]
        bx, by = points[faces[f, 1], 0], points[faces[f, 1], 1]
        cx, cy = points[faces[f, 2], 0], points[faces[f, 2], 1]
        area, x0, x1, y0, y1 = _pixel_box(ax, ay, bx, by, cx, cy, width, height)
        if area == 0.0:
            continue
        for y in range(y0, y1 + 1):
            # the row's crossing with the triangle: only the pixels within a pixel of its ends are
            # tested (the barycentric test below, as over the whole bounding box)
            lo, hi = np.inf, -np.inf
            for px, py, qx, qy in ((ax, ay, bx, by), (bx, by, cx, cy), (cx, cy, ax, ay)):
                if min(py, qy) <= y <= max(py, qy):
                    if py == qy:
                        lo, hi = min(lo, px, qx), max(hi, px, qx)
                    else:
                        xc = px + (y - py) * (qx - px) / (qy - py)
                        lo, hi = min(lo, xc), max(hi, xc)
            grazes = lo > hi  # rounding: the row only grazes a vertex: every pixel tested
            if grazes:
                lo, hi = x0, x1
            # pixels more than 1e-6 inside the crossing (whose rounding is ~1e-11) are inside:
            # filled without the test (for any but a needle of a triangle its weights there are
            # far above its tolerance, so the image is the per-pixel test's); the ends are tested
            xa = max(x0, int(np.ceil(lo + 1e-6))) if not grazes else x1 + 1
            xb = min(x1, int(np.floor(hi - 1e-6))) if not grazes else x0 - 1
            for x in range(xa, xb + 1):
                img[y, x] = True
            for x in range(max(x0, int(np.floor(lo)) - 1), min(x1, int(np.ceil(hi)) + 1) + 1):
                if img[y, x] or xa <= x <= xb:
                    continue
                w0 = ((bx - x) * (cy - y) - (by - y) * (cx - x)) / area
                w1 = ((cx - x) * (ay - y) - (cy - y) * (ax - x)) / area
                w2 = 1.0 - w0 - w1
                if w0 >= -1e-9 and w1 >= -1e-9 and w2 >= -1e-9:
                    img[y, x] = True
    return img


@njit(cache=True)
def enclosed_background(cover):
    """The pixels of a boolean image that are not covered and not joined to its border by
    uncovered pixels (4-neighbours): the holes ``scipy.ndimage.binary_fill_holes`` fills (its
    default structure), counted by a flood fill from the border in one pass over the image."""
    h, w = cover.shape
    seen = np.zeros((h, w), np.bool_)
    stack = np.empty(h * w, np.int64)
    top = 0
    for y in range(h):
        for x in range(w):
            if (y == 0 or x == 0 or y == h - 1 or x == w - 1) and not cover[y, x] and not seen[y, x]:
                seen[y, x] = True
                stack[top] = y * w + x
                top += 1
    while top > 0:
        top -= 1
        y, x = stack[top] // w, stack[top] % w
        for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)):
            yy, xx = y + dy, x + dx
            if 0 <= yy < h and 0 <= xx < w and not cover[yy, xx] and not seen[yy, xx]:
                seen[yy, xx] = True
                stack[top] = yy * w + xx
                top += 1
    n = 0
    for y in range(h):
        for x in range(w):
            if not cover[y, x] and not seen[y, x]:
                n += 1
    return n


@njit(cache=True)
def _see_through_view(vertices, faces, used, right, up, pixels):
    """:func:`see_through`'s work for one view: the vertices projected on (right, up) (the sums in
    ``la.matmul``'s order), the used ones' bounds scaled to ``pixels``, the triangles filled, the
    enclosed background counted. Returns (enclosed, covered) pixels."""
    n = vertices.shape[0]
    q = np.empty((n, 2))
    for i in range(n):
        q[i, 0] = vertices[i, 0] * right[0] + vertices[i, 1] * right[1] + vertices[i, 2] * right[2]
        q[i, 1] = vertices[i, 0] * up[0] + vertices[i, 1] * up[1] + vertices[i, 2] * up[2]
    lo = np.array([np.inf, np.inf])
    hi = np.array([-np.inf, -np.inf])
    for i in used:
        for d in range(2):
            lo[d] = min(lo[d], q[i, d])
            hi[d] = max(hi[d], q[i, d])
    s = (pixels - 1) / max(max(hi[0] - lo[0], hi[1] - lo[1]), 1e-300)
    width = int(math.ceil((hi[0] - lo[0]) * s)) + 1
    height = int(math.ceil((hi[1] - lo[1]) * s)) + 1
    for i in range(n):
        q[i, 0] = (q[i, 0] - lo[0]) * s
        q[i, 1] = (q[i, 1] - lo[1]) * s
    cover = fill_triangles(q, faces, width, height)
    return enclosed_background(cover), int(cover.sum())


def see_through(mesh, azimuth: float, elevation: float, pixels: int = 400, *, used=None) -> tuple[int, int]:
    """Background seen *through* a mesh from one direction (orthographic): (the pixels enclosed by
    its silhouette that no triangle covers, the silhouette's pixels). A slit between two organs, or
    a hole, counts; the notches of a lobed outline, open to the outside, do not (the silhouette's
    holes, :func:`enclosed_background`). Rasterized on ``pixels`` across the larger side.
    ``used``: the vertices the faces use (``np.unique(mesh.faces)``), where the caller has them."""
    right, up = view_axes(azimuth, elevation)
    used = np.unique(mesh.faces) if used is None else used
    h, c = _see_through_view(np.ascontiguousarray(mesh.vertices, np.float64),
                             np.ascontiguousarray(mesh.faces, np.int64), used, right, up, int(pixels))
    return int(h), int(c)


@njit(cache=True)
def depth_fill(points, depth, faces, value, zbuf, label):
    """Draw the triangles ``faces`` into a depth buffer: a pixel (integer coordinates of ``points``'
    frame; its centre inside the triangle, barycentric weights >= -1e-9) takes ``value`` into
    ``label`` where the triangle's depth there (``depth`` interpolated; larger is nearer the eye)
    is above ``zbuf``'s, which it then becomes. Zero-area triangles draw nothing."""
    height, width = zbuf.shape
    for f in range(faces.shape[0]):
        a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
        ax, ay, bx, by, cx, cy = points[a, 0], points[a, 1], points[b, 0], points[b, 1], points[c, 0], points[c, 1]
        area, x0, x1, y0, y1 = _pixel_box(ax, ay, bx, by, cx, cy, width, height)
        if area == 0.0:
            continue
        for y in range(y0, y1 + 1):
            for x in range(x0, x1 + 1):
                wa = ((bx - x) * (cy - y) - (by - y) * (cx - x)) / area
                wb = ((cx - x) * (ay - y) - (cy - y) * (ax - x)) / area
                wc = 1.0 - wa - wb
                if wa < -1e-9 or wb < -1e-9 or wc < -1e-9:
                    continue
                z = wa * depth[a] + wb * depth[b] + wc * depth[c]
                if z > zbuf[y, x]:
                    zbuf[y, x] = z
                    label[y, x] = value


def region_in_view(mesh, region, azimuth: float, elevation: float, pixels: int = 600) -> float:
    """Share of ``region`` (a mesh: a receptacle, say) that stays in view from this direction
    (orthographic, azimuth and elevation as :func:`view_axes`) with ``mesh`` drawn in front of
    it where it is nearer the eye: its pixels left visible in a depth buffer over both, over its
    pixels drawn alone. Unlike :func:`view_coverage`'s silhouettes, a floret behind the region
    hides none of it. Rasterized on ``pixels`` across the larger side of both; 0 for a region
    with no pixels."""
    right, up = view_axes(azimuth, elevation)
    n0 = len(mesh.vertices)
    v = np.vstack([np.asarray(mesh.vertices, np.float64), np.asarray(region.vertices, np.float64)])
    # screen x, y and the depth toward the eye
    screen = la.matmul(v, np.stack([right, up, np.cross(right, up)], axis=1))
    q, depth = np.ascontiguousarray(screen[:, :2]), np.ascontiguousarray(screen[:, 2])
    used = np.concatenate([np.unique(mesh.faces), n0 + np.unique(region.faces)])
    lo, hi = q[used].min(axis=0), q[used].max(axis=0)
    s = (pixels - 1) / max(float((hi - lo).max()), 1e-300)
    q = (q - lo) * s
    width, height = int(math.ceil((hi - lo)[0] * s)) + 1, int(math.ceil((hi - lo)[1] * s)) + 1
    zbuf = np.full((height, width), -np.inf)
    label = np.zeros((height, width), np.int8)
    depth_fill(q, depth, np.ascontiguousarray(region.faces, np.int64) + n0, 2, zbuf, label)
    alone = int((label == 2).sum())
    if alone == 0:
        return 0.0
    depth_fill(q, depth, np.ascontiguousarray(mesh.faces, np.int64), 1, zbuf, label)
    return float((label == 2).sum()) / alone


def _clothed(receptacle) -> bool:
    """Whether a receptacle mesh carries phyllaries (a group ``phyllaries``, or ``phyllaries_k``
    for the k-th of several heads)."""
    return receptacle.face_group is not None and any(g.startswith("phyllaries") for g in receptacle.groups)


def _body_faces(receptacle) -> np.ndarray:
    """(m,) bool: the faces of the receptacle itself (not its phyllaries)."""
    names = np.array([g.startswith("phyllaries") for g in receptacle.groups] + [False])
    return ~names[np.asarray(receptacle.face_group)]


def receptacle_body(receptacle):
    """The receptacle itself (its groups but ``phyllaries``) of a ``[receptacle]`` mesh, without
    the phyllaries on its underside; the mesh as it is when it has none."""
    from inflo.formats.obj import ObjMesh

    if not _clothed(receptacle):
        return receptacle
    return ObjMesh(receptacle.vertices, receptacle.faces[_body_faces(receptacle)])


def underside_in_view(receptacle, front=None, elevation: float = -30.0,
                      azimuths=(0.0, 90.0, 180.0, 270.0)) -> tuple:
    """How bare a head's back is: the share of its receptacle's underside (the body's faces
    turned down, not the stem's disc) that its phyllaries (the group ``phyllaries`` of a
    ``[receptacle]`` mesh), with the mesh ``front`` (the canopy: bracts reflexed over the rim) if
    given, leave in view, from straight below and, the worst of ``azimuths``, from ``elevation``
    (:func:`region_in_view`). (1.0, 1.0) for a receptacle with no phyllaries."""
    from inflo.formats.obj import ObjMesh

    v, f = np.asarray(receptacle.vertices, np.float64), np.asarray(receptacle.faces)
    if not _clothed(receptacle):
        return 1.0, 1.0
    body = _body_faces(receptacle)
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    length = np.sqrt(np.sum(n * n, axis=1))
    radius = np.hypot(v[:, 0], v[:, 2])
    under = body & (n[:, 1] < -0.2 * length) & (radius[f].min(axis=1) > 1e-9 * max(float(radius.max()), 1e-300))
    region, bracts = ObjMesh(v, f[under]), ObjMesh(v, f[~body])
    if front is not None and len(front.faces):
        bracts = ObjMesh(np.vstack([v, np.asarray(front.vertices, np.float64)]),
                         np.vstack([f[~body], np.asarray(front.faces) + len(v)]))
    below = region_in_view(bracts, region, 0.0, -90.0)
    return below, max(region_in_view(bracts, region, float(a), float(elevation)) for a in azimuths)


def check_back(head, most: float, failures: list) -> tuple:
    """The head's back clothed: prints :func:`underside_in_view` of the last receptacle frame
    (behind its phyllaries and the last canopy frame) and fails when more than ``most`` of the
    underside stays in view from 30 degrees below."""
    below, side = underside_in_view(read_obj(head.receptacle[-1]), read_obj(head.canopy[-1]))
    print(f"the head's back: its phyllaries and bracts leave {below:.3f} of the receptacle's underside in view from below, "
          f"{side:.3f} from 30 degrees below (at most {most})")
    if side > most:
        failures.append(f"the head's back: {side:.3f} of the underside bare from 30 degrees below")
    return below, side


ALL_VIEWS = ((0.0, 90.0), (0.0, -90.0)) + tuple((float(az), float(el)) for el in (35, 0, -35)
                                                  for az in range(0, 360, 30))


def worst_see_through(mesh, views=ALL_VIEWS, pixels: int = 400) -> tuple[float, tuple[float, float]]:
    """The largest share of the silhouette seen through (``see_through``) over ``views``
    ((azimuth, elevation) pairs; by default from above, below and every 30 degrees round at
    elevations 35, 0 and -35), and that view."""
    best = (0.0, views[0])
    used = np.unique(mesh.faces)
    for az, el in views:
        h, c = see_through(mesh, az, el, pixels, used=used)
        if c and h / c > best[0]:
            best = (h / c, (az, el))
    return best


def group_faces(mesh) -> dict:
    """Face indices (ascending) of each group of ``mesh``, by name: one sort of the faces, not a
    pass over every face a group (a final yarrow frame: 2,414 floret groups of 390k faces)."""
    fg = np.asarray(mesh.face_group)
    order = np.argsort(fg, kind="stable")
    bounds = np.searchsorted(fg[order], np.arange(len(mesh.groups) + 1))
    return {name: order[bounds[g]:bounds[g + 1]] for g, name in enumerate(mesh.groups)}


def floret_faces(mesh) -> dict:
    """Face indices of each floret_<placement> group."""
    return {int(name.split("_")[1]): idx for name, idx in group_faces(mesh).items() if name.startswith("floret_")}


def floret_heights(mesh, frame_rba, scene) -> dict:
    """Height of each floret's highest vertex above its base, along its axis, in floret units."""
    rows = {int(i): k for k, i in enumerate(frame_rba.ids)}
    out = {}
    for pid, faces in floret_faces(mesh).items():
        if pid not in rows or scene.placements[pid].kind != "rba":
            continue
        r = rows[pid]
        v = mesh.vertices[np.unique(mesh.faces[faces])]
        up = frame_rba.up[r] / la.norm(frame_rba.up[r])
        scale = float(frame_rba.scale[r, 1]) * float(scene.placements[pid].scale[1])
        out[pid] = float(la.matmul(v - frame_rba.pos[r], up).max()) / scale
    return out


class Head:
    """The build of one head: its typed scene, canopy frames, receptacle meshes and RBA frames."""

    def __init__(self, build: Path, canopy: str = "canopy", scene: str = "typed.scn", receptacle: str = "receptacle",
                 folder: str = "head"):
        self.build = Path(build)
        self.scene = read_scn(self.build / folder / scene)
        self.types = [p.type for p in self.scene.placements]
        self.canopy_dir = self.build / canopy
        self.canopy = list_obj_sequence(self.canopy_dir)
        self.receptacle = list_obj_sequence(self.build / folder / receptacle)
        self.rba = sorted((self.build / folder / "rba").glob("*.rba"))
        pos = self.scene.arrays()["pos"]
        centre = self.scene.groups[0].centre if 0 in self.scene.groups else pos.mean(axis=0)
        self.radius = la.norm((pos - centre)[:, [0, 2]], axis=1)

    def rba_frame(self, k: int):
        return read_rba(self.rba[min(k, len(self.rba) - 1)])


def check_head(build: Path, *, rays: int | None, failures: list, per_frame=None, canopy: str = "canopy",
               scene: str = "typed.scn", receptacle: str = "receptacle", folder: str = "head") -> Head:
    """Print the shared report of a head build, appending what fails to ``failures``.

    ``rays``: the ray florets the species has (None: no ray facts to check, e.g. a head of ray
    florets only); ``per_frame(i, mesh)``: called on every canopy frame (for a species' own
    per-frame checks); ``canopy``, ``scene``, ``receptacle``: the build's canopy folder, its typed
    scene and its receptacle (a sequence folder or one OBJ; both relative to ``folder``, default
    ``head/``; an absolute path is taken as it is, e.g. the orlaya's branches). Returns the :class:`Head` for the species' further checks (:func:`check_phase` and
    its own).
    """
    head = Head(build, canopy, scene, receptacle, folder)
    scene, types, canopy, receptacle = head.scene, head.types, head.canopy, head.receptacle
    print(f"canopy: {len(canopy)} frames; head: {len(scene)} placements "
          f"({types.count('disk')} disk, {types.count('ray')} ray, {types.count('bract')} bracts)")

    # intersections, within the canopy and with the receptacle: every written frame is tested (the
    # written file is what is promised collision-free); every tenth frame, the last and any frame
    # with an intersection are listed
    total_pairs = total_rec = 0
    mesh = None
    last_rec = rec = None
    clothed, ns = False, 0
    for i, path in enumerate(canopy):
        mesh = read_obj(path)
        n = len(intersecting_pairs(mesh.vertices, mesh.faces, tri_part=mesh.face_group))
        rec_path = receptacle[min(i, len(receptacle) - 1)]
        if rec_path != last_rec:  # a static receptacle (one file for every frame) is read once
            last_rec, rec = rec_path, read_obj(rec_path)
            # a receptacle with phyllaries on its underside: they touch neither one another nor it
            clothed = _clothed(rec)
            ns = len(intersecting_pairs(rec.vertices, rec.faces)) if clothed else 0
        nr = len(intersecting_pairs_between(mesh.vertices, mesh.faces, rec.vertices, rec.faces))
        total_pairs += n
        total_rec += nr + ns
        if n or nr or ns or i % 10 == 0 or i == len(canopy) - 1:
            print(f"  frame {i:3d}: {len(mesh.faces)} triangles, {len(mesh.groups)} florets, {n} intersecting pairs, "
                  f"{nr} with the receptacle" + (f", {ns} within it (phyllaries)" if clothed else ""))
        if n or nr or ns:
            failures.append(f"frame {i}: {n} intersecting pairs, {nr} with the receptacle"
                            + (f", {ns} within it" if clothed else ""))
        if per_frame is not None:
            per_frame(i, mesh)
    last = mesh
    print(f"every frame ({len(canopy)}) tested: {total_pairs} intersecting pairs, {total_rec} with the receptacle")

    # shape: fccompose's per-frame stretch figures
    with open(head.canopy_dir / "log.csv", newline="") as fh:
        log = list(csv.DictReader(fh))
    lo = min(float(r["min_edge_stretch"]) for r in log)
    hi = max(float(r["max_edge_stretch"]) for r in log)
    out = [r["frame"] for r in log if float(r["min_edge_stretch"]) < BOUNDS[0] or float(r["max_edge_stretch"]) > BOUNDS[1]]
    print(f"edge stretch over all frames: {lo:.3f}-{hi:.3f} x rest; frames outside [{BOUNDS[0]}, {BOUNDS[1]}]: {len(out)}")
    if out:
        failures.append(f"{len(out)} frames with edges outside {BOUNDS} x rest (frames {', '.join(out[:5])} ...)")

    # every floret present at the end
    present = {int(g.split("_")[1]) for g in last.groups if g.startswith("floret_")}
    # obstacle placements (formats/fcc.md "Obstacles") are simulated, not written
    florets = [k for k, p in enumerate(scene.placements) if p.type != "obstacle"]
    missing = sorted(set(florets) - present)
    print(f"florets in the last frame: {len(present)} of {len(florets)}")
    if missing:
        failures.append(f"{len(missing)} florets missing at the end (e.g. {missing[:5]})")

    if rays is None:
        return head
    # the species' facts: its rays, on the margin
    radius, t = head.radius, np.array(types)
    n_rays = int((t == "ray").sum())
    rim = float(np.quantile(radius[t == "disk"], 0.9))
    inner_rays = int((radius[t == "ray"] < rim).sum())
    print(f"ray florets: {n_rays} (expected {rays}); closest to the centre at {radius[t == 'ray'].min():.3f}, "
          f"the outermost tenth of the disk florets from {rim:.3f}")
    if n_rays != rays:
        failures.append(f"{n_rays} ray florets, expected {rays}")
    if inner_rays:
        failures.append(f"{inner_rays} ray florets inside the outermost tenth of the disk florets")
    return head


def frames_with_contacts(canopy_dir: Path) -> tuple[int, int]:
    """Collisions deform petals: (frames with contacts found after the first third of the run,
    those frames), from fccompose's ``log.csv``; prints them with the run's total contacts."""
    with open(Path(canopy_dir) / "log.csv", newline="") as fh:
        log = list(csv.DictReader(fh))
    late = log[len(log) // 3:]
    pressed = sum(1 for r in late if int(r["collisions_found"]) > 0)
    print(f"frames with contacts after the first third: {pressed} of {len(late)}; "
          f"contacts over the run: {sum(int(r['collisions_found']) for r in log)}")
    return pressed, len(late)


def check_phase(head: Head, *, bud: float, failures: list) -> None:
    """The phase effect at two thirds of the run: disk florets' heights fall from rim to centre
    (Spearman rank correlation with the distance from the centre > 0.5), some still in bud."""
    k = (2 * len(head.canopy)) // 3
    heights = floret_heights(read_obj(head.canopy[k]), head.rba_frame(k), head.scene)
    disk = [p for p in heights if head.types[p] == "disk"]
    h = np.array([heights[p] for p in disk])
    from scipy.stats import spearmanr  # here: scipy.stats takes 0.3 s to import, most checks need none of it

    rho = float(spearmanr(head.radius[disk], h).statistic) if len(disk) > 2 else float("nan")
    buds = int((h < bud).sum())
    print(f"phase effect at frame {k}: {len(disk)} disk florets, height {h.min():.2f}-{h.max():.2f} floret units, "
          f"rank correlation with the distance from the centre {rho:.2f}, {buds} still in bud (height < {bud})")
    if not rho > 0.5:
        failures.append(f"no phase effect at frame {k}: rank correlation {rho:.2f}")
    if buds == 0:
        failures.append(f"no disk floret in bud at frame {k}")


def check_development(head: Head, *, failures: list, emerged: float = 0.8) -> float:
    """Development the right way round: the frame at which the first ray or bract reaches half its
    developmental window (half open) and the share of the disk florets that have emerged by then
    (first RBA frame listing them); fails below ``emerged`` (rays and bracts open round florets to
    surround, not round a naked meristem). Returns the share (1 for a head without disk florets)."""
    outer = [p for p in head.scene.placements if p.type in ("ray", "bract") and p.frame_start is not None]
    disk = [k for k, p in enumerate(head.scene.placements) if p.type == "disk"]
    if not outer or not disk:
        return 1.0
    half = min(p.frame_start + 0.5 * (p.frame_end - p.frame_start) for p in outer)
    born = np.full(len(head.scene), np.inf)
    for i, path in enumerate(head.rba):
        ids = read_rba(path).ids
        fresh = [int(j) for j in ids if born[int(j)] == np.inf]
        born[fresh] = i
    share = float((born[disk] <= half).mean())
    print(f"development: the first ray or bract half open at frame {half:g}, with {share:.2f} of the disk florets "
          f"emerged (at least {emerged})")
    if share < emerged:
        failures.append(f"rays or bracts open round a bare head: {share:.2f} of the disk florets emerged "
                        f"at frame {half:g} < {emerged}")
    return share


def check_individuals(head: Head, *, failures: list, least: float = 0.02) -> dict:
    """No clones: per floret type of the last frame, the coefficient of variation of the florets'
    extents (the largest distance of a vertex from the floret's base, over its placement scale), a
    floret's own size, shape and development telling it from its neighbours; fails where a type
    of more than 3 florets varies less than ``least``. Returns type -> CV."""
    k = len(head.canopy) - 1
    mesh = read_obj(head.canopy[k])
    frame = head.rba_frame(k) if head.rba else None
    rows = {int(i): r for r, i in enumerate(frame.ids)} if frame is not None else {}
    ext: dict = {}
    for pid, faces in floret_faces(mesh).items():
        p = head.scene.placements[pid]
        if p.kind == "rba":
            if pid not in rows:
                continue
            pos, scale = frame.pos[rows[pid]], float(frame.scale[rows[pid], 1]) * float(p.scale[1])
        else:  # a placement that does not move (the dyssodia's): its own position and scale
            pos, scale = np.asarray(p.pos, float), float(p.scale[1])
        v = mesh.vertices[np.unique(mesh.faces[faces])] - pos
        ext.setdefault(head.types[pid], []).append(float(la.norm(v, axis=1).max()) / scale)
    cv = {t: float(np.std(e) / np.mean(e)) for t, e in ext.items() if len(e) > 3}
    print("individual florets (CV of their extents in the last frame): "
          + ", ".join(f"{t} {c:.3f}" for t, c in sorted(cv.items())))
    for t, c in cv.items():
        if c < least:
            failures.append(f"{t} florets are clones: CV of their extents {c:.3f} < {least}")
    return cv


def main(argv=None) -> int:
    """``python -m inflo.tools.species.checks PIPELINE_DIR BUILD_DIR``: the shared report of a head
    whose facts are all in the [check] table of its species.toml (``rays``, ``bud``: the
    phase effect's bud height, ``back_in_view``: :func:`check_back`; a species with facts of its
    own has its check_<species>.py)."""
    import sys

    from inflo.formats.species import read_species

    args = sys.argv[1:] if argv is None else argv
    if len(args) != 2:
        print("usage: python -m inflo.tools.species.checks PIPELINE_DIR BUILD_DIR", file=sys.stderr)
        return 2
    facts = read_species(Path(args[0]) / "species.toml").check
    failures = []
    head = check_head(Path(args[1]), rays=facts.get("rays"), failures=failures)
    if "bud" in facts:
        check_phase(head, bud=facts["bud"], failures=failures)
    if "back_in_view" in facts:
        check_back(head, facts["back_in_view"], failures)
    print("OK" if not failures else "FAILED: " + "; ".join(failures))
    return 0 if not failures else 1


if __name__ == "__main__":
    raise SystemExit(main())
