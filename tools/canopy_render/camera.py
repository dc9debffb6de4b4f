"""Cameras for ``canopy-render``: named views, automatic framing, matrices, ``.fcc`` camera keys.

World convention (docs/architecture.md "Frames of reference"): +Y is up, the axis of a floret and of
an inflorescence; a view direction is given by an azimuth (degrees, measured about the up axis
from the +Z axis towards +X) and an elevation (degrees above the horizontal plane). The named
views are

======  =======  =========  ==================================================================
view    azimuth  elevation  what it shows
======  =======  =========  ==================================================================
iso     30       25         the default: from the front right, slightly above (shows the
                            inside of an opening flower and the canopy's depth)
front   0        0          from +Z, looking along -Z
side    90       0          from +X, looking along -X (thesis figs. 9.13, 9.14)
back    180      0          from -Z
top     0        90         from +Y, looking down; the image's top is -Z (thesis fig. 9.10)
bottom  0        -90        from -Y, looking up
======  =======  =========  ==================================================================

With ``up_axis="z"`` the same angles are taken about +Z (a Z-up OBJ): "front" then looks along +Y.

Automatic framing (:func:`fit_camera`) places a perspective (or orthographic) camera looking
along the chosen direction so that every given point lies inside the image with a margin; it
solves exactly for the closest eye position (closed form, no iteration), over all frames of a
sequence at once so that an animation does not jump.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

__all__ = [
    "Camera",
    "VIEWS",
    "view_basis",
    "fit_camera",
    "camera_from_fcc",
    "look_at",
    "perspective",
    "orthographic",
]

VIEWS: dict[str, tuple[float, float]] = {
    "iso": (30.0, 25.0),
    "front": (0.0, 0.0),
    "side": (90.0, 0.0),
    "back": (180.0, 0.0),
    "top": (0.0, 90.0),
    "bottom": (0.0, -90.0),
}
"""Named views: name -> (azimuth, elevation) in degrees."""

DEFAULT_FOV = 30.0
"""Vertical field of view of the automatic camera, degrees."""

DEFAULT_MARGIN = 0.05
"""Fraction of the image's half-size left free on each side by automatic framing."""

# Y-up coordinates -> Z-up world: x -> x, y -> z, z -> -y (a +90 degree turn about X)
_Z_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def _vec3(v, what: str) -> np.ndarray:
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.shape != (3,) or not np.isfinite(a).all():
        raise ValueError(f"{what} must be 3 finite numbers, got {v!r}")
    return a


@dataclass(frozen=True)
class Camera:
    """A pinhole (or orthographic) camera in world coordinates.

    Attributes
    ----------
    eye : (3,) float
        Camera position.
    target : (3,) float
        The point looked at (the image centre).
    up : (3,) float
        Up vector; only its part perpendicular to the view direction matters.
    fov : float
        Vertical field of view in degrees (perspective cameras).
    near, far : float or None
        Clipping distances along the view direction; None lets the renderer fit them to the scene.
    ortho_height : float or None
        When set, an orthographic camera showing this world height; ``fov`` is then unused.
    light : (3,) float or None
        World position of the key light (the ``.fcc`` ``light position``); None puts the key light
        at a fixed place relative to the camera (upper left, in front), so any view is well lit.
    """

    eye: tuple
    target: tuple
    up: tuple = (0.0, 1.0, 0.0)
    fov: float = DEFAULT_FOV
    near: float | None = None
    far: float | None = None
    ortho_height: float | None = None
    light: tuple | None = None

    def __post_init__(self):
        eye, target, up = _vec3(self.eye, "eye"), _vec3(self.target, "target"), _vec3(self.up, "up")
        object.__setattr__(self, "eye", tuple(eye.tolist()))
        object.__setattr__(self, "target", tuple(target.tolist()))
        object.__setattr__(self, "up", tuple(up.tolist()))
        if self.light is not None:
            object.__setattr__(self, "light", tuple(_vec3(self.light, "light").tolist()))
        view = target - eye
        if not np.linalg.norm(view) > 0:
            raise ValueError("camera position and look-at point coincide")
        up_len = np.linalg.norm(up)
        if not up_len > 0 or np.linalg.norm(np.cross(view / np.linalg.norm(view), up / up_len)) < 1e-9:
            raise ValueError("camera up vector is zero or parallel to the view direction")
        if not 0.0 < self.fov < 180.0:
            raise ValueError(f"camera fov must be in (0, 180) degrees, got {self.fov}")
        if self.near is not None and self.far is not None and not 0.0 < self.near < self.far:
            raise ValueError(f"camera needs 0 < near < far, got near={self.near}, far={self.far}")
        if self.ortho_height is not None and not self.ortho_height > 0:
            raise ValueError(f"ortho_height must be positive, got {self.ortho_height}")

    @property
    def is_ortho(self) -> bool:
        return self.ortho_height is not None

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(right, up, forward) unit vectors; forward points from the eye to the target."""
        f = np.subtract(self.target, self.eye)
        f /= np.linalg.norm(f)
        r = np.cross(f, self.up)
        r /= np.linalg.norm(r)
        u = np.cross(r, f)
        return r, u, f

    def view_matrix(self, origin=(0.0, 0.0, 0.0)) -> np.ndarray:
        """(4, 4) float64 world-to-camera matrix, for world coordinates given relative to ``origin``."""
        o = np.asarray(origin, dtype=np.float64)
        return look_at(np.subtract(self.eye, o), np.subtract(self.target, o), self.up)

    def projection_matrix(self, aspect: float, near: float, far: float) -> np.ndarray:
        """(4, 4) float64 OpenGL projection for an image of width/height ``aspect``."""
        if self.is_ortho:
            h = self.ortho_height / 2.0
            return orthographic(h * aspect, h, near, far)
        return perspective(self.fov, aspect, near, far)

    def with_light(self, light) -> Camera:
        """This camera with the key light at world position ``light`` (None: camera-relative)."""
        return replace(self, light=None if light is None else tuple(_vec3(light, "light").tolist()))

    @classmethod
    def from_fcc(cls, params, fallback: Camera | None = None) -> Camera:
        """The camera of a ``.fcc`` file's viewer keys (``read_fcc(path)``); see :func:`camera_from_fcc`."""
        return camera_from_fcc(params, fallback)


def look_at(eye, target, up) -> np.ndarray:
    """(4, 4) float64 view matrix (gluLookAt): camera at ``eye`` looking at ``target``."""
    eye, target, up = (np.asarray(a, dtype=np.float64) for a in (eye, target, up))
    f = target - eye
    f /= np.linalg.norm(f)
    r = np.cross(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = r, u, -f
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def perspective(fov_y_deg: float, aspect: float, near: float, far: float) -> np.ndarray:
    """(4, 4) float64 OpenGL perspective projection (gluPerspective)."""
    t = 1.0 / math.tan(math.radians(fov_y_deg) / 2.0)
    m = np.zeros((4, 4))
    m[0, 0], m[1, 1] = t / aspect, t
    m[2, 2] = (far + near) / (near - far)
    m[2, 3] = 2.0 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


def orthographic(half_w: float, half_h: float, near: float, far: float) -> np.ndarray:
    """(4, 4) float64 OpenGL orthographic projection of a centred box."""
    m = np.eye(4)
    m[0, 0], m[1, 1] = 1.0 / half_w, 1.0 / half_h
    m[2, 2] = -2.0 / (far - near)
    m[2, 3] = -(far + near) / (far - near)
    return m


def view_basis(view: str | None = "iso", azimuth: float | None = None, elevation: float | None = None,
               up_axis: str = "y") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Direction towards the eye and the camera's right and up vectors of a view.

    Parameters
    ----------
    view : str or None
        A name of :data:`VIEWS`; None means "iso".
    azimuth, elevation : float or None
        Degrees; each one given overrides the view's.
    up_axis : {"y", "z"}
        The world's up axis.

    Returns
    -------
    to_eye, right, up : (3,) float64
        Unit vectors: from the target towards the eye, the image's right, the image's up.
    """
    name = view or "iso"
    if name not in VIEWS:
        raise ValueError(f"unknown view {name!r}; expected one of {', '.join(VIEWS)}")
    az, el = VIEWS[name]
    az = az if azimuth is None else float(azimuth)
    el = el if elevation is None else float(elevation)
    if not -90.0 <= el <= 90.0:
        raise ValueError(f"elevation must be in [-90, 90] degrees, got {el}")
    a, e = math.radians(az), math.radians(el)
    d = np.array([math.cos(e) * math.sin(a), math.sin(e), math.cos(e) * math.cos(a)])
    r = np.array([math.cos(a), 0.0, -math.sin(a)])  # horizontal, perpendicular to d at any elevation
    u = np.cross(d, r)
    if up_axis == "z":
        d, r, u = _Z_UP @ d, _Z_UP @ r, _Z_UP @ u
    elif up_axis != "y":
        raise ValueError(f"up_axis must be 'y' or 'z', got {up_axis!r}")
    return d, r, u / np.linalg.norm(u)


def _as_point_sets(points) -> list[np.ndarray]:
    if isinstance(points, np.ndarray):
        points = [points]
    sets = [np.asarray(p, dtype=np.float64).reshape(-1, 3) for p in points]
    sets = [p for p in sets if len(p)]
    if not sets:
        raise ValueError("nothing to frame: no points")
    return sets


def fit_camera(points, *, view: str | None = "iso", azimuth: float | None = None,
               elevation: float | None = None, up_axis: str = "y", aspect: float = 4 / 3,
               fov: float = DEFAULT_FOV, margin: float = DEFAULT_MARGIN, ortho: bool = False,
               zoom: float = 1.0) -> Camera:
    """The camera of a view that shows every point, as large as the margin allows.

    For a perspective camera with half-angle tangents ``tx``, ``ty`` and camera coordinates
    ``(x, y, z)`` of the points (``z`` along the view direction, relative to the box centre), a
    point is inside the image when ``|x - ex| <= tx (z - ez)`` and ``|y - ey| <= ty (z - ez)``.
    With ``A = min(tx z - x)`` and ``B = min(tx z + x)`` the closest eye is ``ez = (A + B) / (2 tx)``,
    ``ex = (B - A) / 2`` (likewise for y); the smaller ``ez`` of the two axes wins. Exact, in one
    pass over the points, and the minima combine over the frames of a sequence.

    Parameters
    ----------
    points : (n, 3) array or iterable of (n_i, 3) arrays
        Everything that must be visible (e.g. the vertices of every frame of a sequence).
    view, azimuth, elevation, up_axis
        The view direction; see :func:`view_basis`.
    aspect : float
        Image width / height.
    fov : float
        Vertical field of view, degrees.
    margin : float
        Fraction of each half-size of the image kept free (0.05: the points fill 90 %).
    ortho : bool
        An orthographic camera instead of a perspective one.
    zoom : float
        > 1 moves closer (crops), < 1 leaves more room.

    Returns
    -------
    Camera
        With ``near`` and ``far`` set to enclose the points.
    """
    if not 0.0 <= margin < 0.5:
        raise ValueError(f"margin must be in [0, 0.5), got {margin}")
    if not zoom > 0:
        raise ValueError(f"zoom must be positive, got {zoom}")
    sets = _as_point_sets(points)
    lo = np.min([p.min(axis=0) for p in sets], axis=0)
    hi = np.max([p.max(axis=0) for p in sets], axis=0)
    c0 = (lo + hi) / 2.0
    extent = float(np.linalg.norm(hi - lo))
    if not np.isfinite(extent):
        raise ValueError("cannot frame non-finite coordinates")
    if extent <= 1e-12 * max(1.0, float(np.abs(c0).max())):
        extent = 1.0  # a single point: show a unit neighbourhood
    to_eye, r, u = view_basis(view, azimuth, elevation, up_axis)
    f = -to_eye
    basis = np.stack([r, u, f], axis=1)  # columns: camera x, y, z (z forward)
    keep = 1.0 - 2.0 * margin

    # one pass: per set, the extremes the fit needs
    stats = []
    ty = math.tan(math.radians(fov) / 2.0) * keep
    tx = ty * aspect
    for p in sets:
        q = (p - c0) @ basis
        x, y, z = q[:, 0], q[:, 1], q[:, 2]
        stats.append((
            (tx * z - x).min(), (tx * z + x).min(), (ty * z - y).min(), (ty * z + y).min(),
            x.min(), x.max(), y.min(), y.max(), z.min(), z.max(),
        ))
    s = np.array(stats)
    ax, bx, ay, by = s[:, 0].min(), s[:, 1].min(), s[:, 2].min(), s[:, 3].min()
    xmin, xmax, ymin, ymax = s[:, 4].min(), s[:, 5].max(), s[:, 6].min(), s[:, 7].max()
    zmin, zmax = s[:, 8].min(), s[:, 9].max()
    cam_up = u

    if ortho:
        ex, ey = (xmin + xmax) / 2.0, (ymin + ymax) / 2.0
        half_h = max((ymax - ymin) / 2.0, (xmax - xmin) / 2.0 / aspect, extent * 1e-6) / keep / zoom
        target = c0 + ex * r + ey * u
        dist = (zmax - zmin) + extent  # well outside the points
        eye = target - dist * f
        near = max(dist + zmin - 0.05 * extent, 1e-6 * extent)
        far = dist + zmax + 0.05 * extent
        return Camera(eye=eye, target=target, up=cam_up, fov=fov, near=near, far=far, ortho_height=2.0 * half_h)

    ez = min((ax + bx) / (2.0 * tx), (ay + by) / (2.0 * ty))
    ex, ey = (bx - ax) / 2.0, (by - ay) / 2.0
    # the axis that did not limit ez has room to spare: centre its image extent (perspective
    # makes that differ from centring the points themselves when near and far extremes differ)
    ex = _centre_in_image(sets, c0, r, f, ex, ez, tx)
    ey = _centre_in_image(sets, c0, u, f, ey, ez, ty)
    target = c0 + ex * r + ey * u  # on the plane z = 0 through the box centre
    dist = -ez  # > 0: the eye is behind every point
    dist = max(dist, 1e-9 * extent)
    dist /= zoom
    eye = target - dist * f
    near = max(0.5 * (dist + zmin), 1e-4 * dist)
    far = (dist + zmax) * 1.05 + 1e-6 * extent
    if zoom > 1.0:  # points may now lie behind the eye: clip them rather than fail
        near = max(1e-4 * dist, min(near, 0.1 * dist))
    return Camera(eye=eye, target=target, up=cam_up, fov=fov, near=near, far=far)


def _image_extremes(sets, c0, axis, f, e, ez):
    """Lowest and highest image coordinate (a - e) / (z - ez) of the points, with their (a - e, z - ez)."""
    lo, hi = (math.inf, 0.0, 1.0), (-math.inf, 0.0, 1.0)
    for p in sets:
        q = p - c0
        a = q @ axis - e
        d = q @ f - ez
        s = a / d
        i, j = int(np.argmin(s)), int(np.argmax(s))
        if s[i] < lo[0]:
            lo = (float(s[i]), float(a[i]), float(d[i]))
        if s[j] > hi[0]:
            hi = (float(s[j]), float(a[j]), float(d[j]))
    return lo, hi


def _centre_in_image(sets, c0, axis, f, e, ez, t, iterations: int = 4) -> float:
    """Shift the eye along ``axis`` so that the points' image extent is centred; keep ``e`` if that fails.

    Each step moves by the shift that centres the current extreme points exactly (they are
    affected by 1 / depth); the extremes change rarely, so a few steps suffice.
    """
    e0 = e
    for _ in range(iterations):
        (slo, alo, dlo), (shi, ahi, dhi) = _image_extremes(sets, c0, axis, f, e, ez)
        if abs(slo + shi) <= 1e-9 * max(t, 1e-300):
            break
        e += (ahi / dhi + alo / dlo) / (1.0 / dhi + 1.0 / dlo)
    (slo, _, _), (shi, _, _) = _image_extremes(sets, c0, axis, f, e, ez)
    if slo < -t * (1.0 + 1e-9) or shi > t * (1.0 + 1e-9):
        return e0
    return e


def camera_from_fcc(params, fallback: Camera | None = None) -> Camera:
    """The camera of the viewer keys of a canopy parameter file (thesis app. C.1, ``formats/fcc.md``).

    Parameters
    ----------
    params : inflo.formats.fcc.CanopyParams or CameraParams
        What :func:`inflo.formats.fcc.read_fcc` returns (its ``camera``), or its ``camera`` itself:
        ``position``, ``lookat``, ``up``, ``fov_deg``, ``near``, ``far``, ``light_position``.
    fallback : Camera or None
        The automatic camera, used where the file leaves the camera automatic: without ``camera
        position`` and ``camera lookat`` the fallback is kept whole (only the light is taken from
        the file); with one of them, the other comes from the fallback. None: eye (0, 0, 1)
        looking at the origin.

    Returns
    -------
    Camera
        A perspective camera at ``camera position`` looking at ``camera lookat`` with ``camera up``,
        ``camera fov`` (vertical, degrees) and the file's ``near plane``/``far plane`` (None: fitted
        to the scene by the renderer); the key light at ``light position`` when given.
    """
    cam = getattr(params, "camera", params)
    base = fallback or Camera(eye=(0.0, 0.0, 1.0), target=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), fov=45.0)
    light = getattr(cam, "light_position", None)
    position, lookat = getattr(cam, "position", None), getattr(cam, "lookat", None)
    if position is None and lookat is None:
        return base if light is None else base.with_light(light)
    return Camera(
        eye=base.eye if position is None else position,
        target=base.target if lookat is None else lookat,
        up=getattr(cam, "up", None) or (0.0, 1.0, 0.0),
        fov=float(getattr(cam, "fov_deg", base.fov)),
        near=getattr(cam, "near", None),
        far=getattr(cam, "far", None),
        ortho_height=None,
        light=base.light if light is None else light,
    )
