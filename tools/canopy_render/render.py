"""Headless OpenGL rendering of triangle meshes and polylines to image arrays (moderngl on EGL).

The library behind ``canopy-render``; arrays in, an ``(H, W, 3) uint8`` image out::

    from inflo.formats.obj import read_obj
    from inflo.tools.canopy_render.render import render_meshes, RenderOptions
    image = render_meshes([read_obj("flower.obj")], options=RenderOptions(size=(800, 600)))

What a picture gets (docs/rendering.md): a depth buffer; 4x multisampling resolved into the
image; no back-face culling and two-sided lighting (petals are open surfaces: the shading normal
is turned towards the viewer per fragment, using the triangle's own plane to decide which side is
seen); smooth shading with area-weighted vertex normals (the OBJ's normals when it has them); a
key light, a weaker fill light and ambient light, shaded in linear RGB and written as sRGB; an
optional wireframe (edges drawn over the surface with polygon offset) and the OBJ's ``l``
polylines (skeletons) as lines. Colours: :mod:`.colors`.

One :class:`Renderer` holds one GL context, its shader programs and framebuffers; keep it for all
the frames of a sequence (:func:`render_sequence` does). :func:`render_meshes` without a renderer
uses a per-process default one (:func:`default_renderer`).

Timing on the 2-core development machine (llvmpipe, 1024x768, 4x MSAA): 400k triangles in about
0.4 s per frame warm, 1.9 s for the ``canopy-render`` process end to end (reading the OBJ
included); see ``bench/bench_render.py``.
"""
from __future__ import annotations

import functools
import math
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from inflo.formats.colors import INPUT_PALETTE, RGB, material_color

from .camera import Camera, fit_camera

__all__ = [
    "RenderOptions",
    "Renderer",
    "GLUnavailable",
    "GL_PACKAGES",
    "render_meshes",
    "render_sequence",
    "default_renderer",
    "vertex_normals",
    "unique_edges",
    "polyline_segments",
    "scene_points",
    "auto_camera",
]

GL_PACKAGES = "libegl1 libegl-mesa0 libgl1-mesa-dri libgl1"
"""Debian packages that provide headless OpenGL (Mesa EGL + llvmpipe)."""


class GLUnavailable(RuntimeError):
    """No OpenGL context could be created (missing Mesa/EGL libraries); the message says what to install."""


@dataclass(frozen=True)
class RenderOptions:
    """How to draw (everything but the camera).

    Attributes
    ----------
    size : (int, int)
        Image (width, height) in pixels.
    background : (3,) float
        sRGB in 0..1.
    samples : int
        Multisampling (antialiasing) samples, capped at what the GL offers; 1 disables it.
    wireframe : bool
        Draw every triangle edge over the surface.
    wireframe_color : (3,) float
    draw_lines : bool
        Draw the OBJ ``l`` polylines (skeletons).
    line_color : (3,) float
        Colour of the polylines.
    line_width : float
        Width of wireframe edges and polylines, pixels.
    mesh_colors : tuple of (3,) float or None
        A colour per mesh (per input), overriding materials; None entries (or a short tuple) leave
        the materials' colours.
    material_colors : mapping str -> (3,) float or None
        The colour file's table (see :func:`.colors.material_color`).
    use_vertex_colors : bool
        Use the OBJ's vertex colours when a mesh has them.
    default_colors : tuple of (3,) float
        Colour of mesh i's faces without material: entry i modulo the length.
    ambient, key, fill, specular, shininess : float
        Light intensities (linear RGB) and the key light's Blinn-Phong exponent.
    """

    size: tuple[int, int] = (1024, 768)
    background: RGB = (1.0, 1.0, 1.0)
    samples: int = 4
    wireframe: bool = False
    wireframe_color: RGB = (0.10, 0.10, 0.10)
    draw_lines: bool = True
    line_color: RGB = (0.22, 0.30, 0.12)
    line_width: float = 1.5
    mesh_colors: tuple = ()
    material_colors: Mapping[str, RGB] | None = None
    use_vertex_colors: bool = True
    default_colors: tuple = INPUT_PALETTE
    ambient: float = 0.15
    key: float = 0.90
    fill: float = 0.35
    specular: float = 0.10
    shininess: float = 40.0

    def __post_init__(self):
        w, h = (int(v) for v in self.size)
        if not (1 <= w <= 16384 and 1 <= h <= 16384):
            raise ValueError(f"image size must be 1..16384 pixels a side, got {w}x{h}")
        object.__setattr__(self, "size", (w, h))
        if self.samples < 1:
            raise ValueError(f"samples must be >= 1, got {self.samples}")
        if not self.line_width > 0:
            raise ValueError(f"line width must be positive, got {self.line_width}")


# ---------------------------------------------------------------------------------------------
# geometry helpers (pure numpy)


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted vertex normals.

    Each face adds its unnormalized normal (twice its area times the unit normal, right-hand rule
    over the face's vertex order) to its three vertices; sums are normalized. Vertices in no face,
    or whose faces cancel, get a zero normal (the shader then uses the triangle's own normal).

    Parameters
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int

    Returns
    -------
    (n, 3) float32
    """
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    n = len(v)
    if len(f) == 0:
        return np.zeros((n, 3), np.float32)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    fn = np.cross(b - a, c - a)
    idx = f.ravel()
    acc = np.empty((n, 3))
    for k in range(3):
        acc[:, k] = np.bincount(idx, weights=np.repeat(fn[:, k], 3), minlength=n)
    length = np.linalg.norm(acc, axis=1)
    scale = np.divide(1.0, length, out=np.zeros_like(length), where=length > 1e-300)
    return (acc * scale[:, None]).astype(np.float32)


def unique_edges(faces: np.ndarray) -> np.ndarray:
    """The undirected edges of triangles, each once.

    Parameters
    ----------
    faces : (m, 3) int

    Returns
    -------
    (k, 2) int32
        Sorted pairs (i < j), sorted lexicographically.
    """
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if len(f) == 0:
        return np.zeros((0, 2), np.int32)
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    e.sort(axis=1)
    key = np.unique(e[:, 0] * (int(f.max()) + 1) + e[:, 1])
    m = int(f.max()) + 1
    return np.stack([key // m, key % m], axis=1).astype(np.int32)


def polyline_segments(lines: Sequence[np.ndarray]) -> np.ndarray:
    """Polylines as line segments.

    Parameters
    ----------
    lines : list of (k_i,) int
        Vertex indices of each polyline (OBJ ``l``).

    Returns
    -------
    (s, 2) int32
        Consecutive pairs of every polyline.
    """
    segs = [np.stack([l[:-1], l[1:]], axis=1) for l in (np.asarray(x, np.int64) for x in lines) if len(l) >= 2]
    if not segs:
        return np.zeros((0, 2), np.int32)
    return np.concatenate(segs).astype(np.int32)


def _referenced(mesh) -> np.ndarray:
    """Vertices of ``mesh`` used by a face or polyline (all vertices when none is)."""
    v = np.asarray(mesh.vertices, dtype=np.float64).reshape(-1, 3)
    used = np.zeros(len(v), bool)
    faces = np.asarray(mesh.faces).reshape(-1, 3)
    if faces.size:
        used[faces.ravel()] = True
    for line in getattr(mesh, "lines", None) or ():
        used[np.asarray(line, np.int64)] = True
    return v if used.all() or not used.any() else v[used]


def scene_points(frames) -> list[np.ndarray]:
    """The drawn vertices of meshes, for framing.

    Parameters
    ----------
    frames : mesh, list of meshes, or list of lists of meshes (a sequence of scenes)

    Returns
    -------
    list of (n_i, 3) float64
    """
    out = []

    def walk(x):
        if hasattr(x, "vertices"):
            p = _referenced(x)
            if len(p):
                out.append(p)
        else:
            for y in x:
                walk(y)

    walk(frames)
    return out


def auto_camera(frames, options: RenderOptions | None = None, **view) -> Camera:
    """A camera framing every frame of ``frames`` (see :func:`scene_points`, :func:`.camera.fit_camera`).

    ``view`` takes :func:`.camera.fit_camera`'s keywords (``view``, ``azimuth``, ``elevation``,
    ``up_axis``, ``fov``, ``margin``, ``ortho``, ``zoom``); the aspect comes from ``options.size``.
    """
    options = options or RenderOptions()
    w, h = options.size
    pts = scene_points(frames)
    if not pts:
        raise ValueError("nothing to draw: the meshes have no vertices")
    return fit_camera(pts, aspect=w / h, **view)


# ---------------------------------------------------------------------------------------------
# shaders

_MESH_VS = """
#version 330
uniform mat4 u_mvp;
in vec3 in_pos;
in vec3 in_normal;
in vec3 in_color;
out vec3 v_pos;
out vec3 v_normal;
out vec3 v_color;
void main() {
    v_pos = in_pos;
    v_normal = in_normal;
    v_color = in_color;
    gl_Position = u_mvp * vec4(in_pos, 1.0);
}
"""

_MESH_FS = """
#version 330
uniform vec3 u_eye;          // eye position (perspective) relative to the origin
uniform vec3 u_view_dir;     // unit vector towards the viewer (orthographic)
uniform int u_ortho;
uniform vec4 u_key;          // w = 0: unit direction towards the light; w = 1: light position
uniform vec3 u_fill_dir;     // unit direction towards the fill light
uniform vec3 u_color;        // multiplies the vertex colour
uniform float u_ambient;
uniform float u_key_i;
uniform float u_fill_i;
uniform float u_spec;
uniform float u_shininess;
in vec3 v_pos;
in vec3 v_normal;
in vec3 v_color;
out vec4 f_color;
void main() {
    vec3 V = u_ortho == 1 ? u_view_dir : normalize(u_eye - v_pos);
    // the triangle's own plane decides which side is seen (winding and file normals may disagree)
    vec3 ng = cross(dFdx(v_pos), dFdy(v_pos));
    float lg = length(ng);
    ng = lg > 0.0 ? ng / lg : V;
    if (dot(ng, V) < 0.0) ng = -ng;
    float ln = length(v_normal);
    vec3 n = ln > 1e-20 ? v_normal / ln : ng;
    if (dot(n, ng) < 0.0) n = -n;          // two-sided: shade the side facing the viewer
    vec3 L = u_key.w > 0.5 ? normalize(u_key.xyz - v_pos) : u_key.xyz;
    float d_key = max(dot(n, L), 0.0);
    float d_fill = max(dot(n, u_fill_dir), 0.0);
    vec3 H = normalize(L + V);
    float s = d_key > 0.0 ? pow(max(dot(n, H), 0.0), u_shininess) : 0.0;
    vec3 base = pow(clamp(u_color * v_color, 0.0, 1.0), vec3(2.2));
    vec3 c = base * (u_ambient + u_key_i * d_key + u_fill_i * d_fill) + vec3(u_spec * s);
    f_color = vec4(pow(clamp(c, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
"""

_LINE_VS = """
#version 330
uniform mat4 u_mvp;
in vec3 in_pos;
void main() {
    gl_Position = u_mvp * vec4(in_pos, 1.0);
}
"""

_LINE_FS = """
#version 330
uniform vec3 u_color;
out vec4 f_color;
void main() {
    f_color = vec4(u_color, 1.0);
}
"""


def _textured(source: str, pairs) -> str:
    """A shader of the mesh program with texture sampling spliced in (:mod:`.texture`)."""
    for old, new in pairs:
        if source.count(old) != 1:
            raise AssertionError(f"texture shader: {old!r} not found once")
        source = source.replace(old, new)
    return source


_TEX_VS = _textured(_MESH_VS, [
    ("in vec3 in_color;\n", "in vec3 in_color;\nin vec2 in_uv;\nout vec2 v_uv;\n"),
    ("    v_color = in_color;\n", "    v_color = in_color;\n    v_uv = in_uv;\n"),
])
"""The mesh vertex shader passing texture coordinates on."""

_TEX_FS = _textured(_MESH_FS, [
    ("in vec3 v_color;\n", "in vec3 v_color;\nin vec2 v_uv;\nuniform sampler2D u_tex;\n"),
    ("void main() {\n", "void main() {\n    vec4 texel = texture(u_tex, v_uv);\n    if (texel.a < 0.5) discard;\n"),
    ("pow(clamp(u_color * v_color, 0.0, 1.0), vec3(2.2))", "pow(clamp(texel.rgb * v_color, 0.0, 1.0), vec3(2.2))"),
])
"""The mesh fragment shader with the base colour from a texture (alpha < 0.5: not drawn)."""


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _create_context():
    """A standalone EGL context, or :class:`GLUnavailable` naming the packages to install."""
    try:
        import moderngl
    except ImportError as exc:  # pragma: no cover - a dependency of the package
        raise GLUnavailable(f"the moderngl Python package is missing ({_one_line(exc)}); pip install moderngl") from None
    try:
        return moderngl.create_standalone_context(backend="egl")
    except Exception as exc:  # glcontext raises plain Exceptions with multi-line texts
        raise GLUnavailable(
            f"no headless OpenGL (EGL) context: {_one_line(exc)}; "
            f"install Mesa EGL as root: apt-get install -y {GL_PACKAGES}"
        ) from None


# ---------------------------------------------------------------------------------------------
# per-mesh draw data


@dataclass
class _Draw:
    """One mesh, ready for the GL: float32 arrays relative to the render origin."""

    pos: np.ndarray                    # (n, 3) float32
    normal: np.ndarray                 # (n, 3) float32
    color: np.ndarray | None           # (n, 3) float32 vertex colours, or None
    tris: np.ndarray                   # (m, 3) int32, faces sorted by colour group
    groups: list = field(default_factory=list)  # [(first face, count, rgb)]
    edges: np.ndarray | None = None    # (k, 2) int32 wireframe edges
    segments: np.ndarray | None = None  # (s, 2) int32 polyline segments
    uv: np.ndarray | None = None       # (n, 2) float32 texture coordinates (textured meshes)
    tex_tris: np.ndarray | None = None  # (t, 3) int32 textured faces, sorted by texture
    tex_groups: list = field(default_factory=list)  # [(first textured face, count, texture array)]


def _prepare(mesh, index: int, options: RenderOptions, origin: np.ndarray) -> _Draw:
    v = np.asarray(mesh.vertices, dtype=np.float64).reshape(-1, 3)
    faces = np.asarray(mesh.faces, dtype=np.int32).reshape(-1, 3)
    pos = (v - origin).astype(np.float32)
    given = getattr(mesh, "normals", None)
    if given is not None and len(given) == len(v):
        normal = np.asarray(given, dtype=np.float32)
    else:
        normal = vertex_normals(v, faces)

    color = None
    vc = getattr(mesh, "vertex_colors", None)
    override = options.mesh_colors[index] if index < len(options.mesh_colors) else None
    default = options.default_colors[index % len(options.default_colors)]
    tris, groups = faces, []
    fm_all = getattr(mesh, "face_material", None)
    face_texture = getattr(mesh, "face_texture", None)
    tex_tris, tex_groups = None, []
    if face_texture is not None and len(face_texture) == len(faces) and np.any(face_texture >= 0):
        ft = np.asarray(face_texture, np.int64)
        sel = ft >= 0
        order_t = np.argsort(ft[sel], kind="stable")
        tex_tris = np.ascontiguousarray(faces[sel][order_t], np.int32)
        sorted_t = ft[sel][order_t]
        starts = np.flatnonzero(np.r_[True, sorted_t[1:] != sorted_t[:-1]])
        ends = np.r_[starts[1:], len(sorted_t)]
        tex_groups = [(s, e - s, mesh.textures[int(sorted_t[s])]) for s, e in zip(starts.tolist(), ends.tolist())]
        tris = faces[~sel]
        if fm_all is not None and len(fm_all) == len(faces):
            fm_all = np.asarray(fm_all)[~sel]
    if options.use_vertex_colors and vc is not None and len(vc) == len(v):
        color = np.clip(np.asarray(vc, dtype=np.float32), 0.0, 1.0)
        groups = [(0, len(tris), (1.0, 1.0, 1.0))]
    elif override is not None:
        groups = [(0, len(tris), tuple(override))]
    else:
        fm = fm_all
        names = getattr(mesh, "materials", None) or []
        if len(tris) == 0:
            groups = []
        elif fm is None or not names or len(fm) != len(tris):
            groups = [(0, len(tris), tuple(default))]
        else:
            fm = np.asarray(fm, dtype=np.int64)
            order = np.argsort(fm, kind="stable")
            tris = tris[order]
            sorted_m = fm[order]
            starts = np.flatnonzero(np.r_[True, sorted_m[1:] != sorted_m[:-1]])
            ends = np.r_[starts[1:], len(sorted_m)]
            for s, e in zip(starts.tolist(), ends.tolist()):
                mid = int(sorted_m[s])
                rgb = default if mid < 0 else material_color(names[mid], options.material_colors)
                groups.append((s, e - s, tuple(rgb)))
    edges = unique_edges(faces) if options.wireframe and len(faces) else None
    segments = None
    if options.draw_lines and getattr(mesh, "lines", None):
        segments = polyline_segments(mesh.lines)
    uv = None
    if tex_tris is not None:
        uv = np.ascontiguousarray(mesh.uv, np.float32).reshape(-1, 2)
    return _Draw(pos=pos, normal=normal, color=color, tris=np.ascontiguousarray(tris, np.int32),
                 groups=groups, edges=edges, segments=segments, uv=uv, tex_tris=tex_tris, tex_groups=tex_groups)


def _clip_range(camera: Camera, draws: list[_Draw], origin: np.ndarray) -> tuple[float, float]:
    """near/far planes: the camera's, or fitted to the drawn points along the view direction."""
    if camera.near is not None and camera.far is not None:
        return camera.near, camera.far
    _, _, f = camera.basis()
    eye = np.subtract(camera.eye, origin)
    zmin, zmax = math.inf, -math.inf
    for d in draws:
        if len(d.pos):
            z = (d.pos.astype(np.float64) - eye) @ f
            zmin, zmax = min(zmin, float(z.min())), max(zmax, float(z.max()))
    dist = float(np.linalg.norm(np.subtract(camera.target, camera.eye)))
    if not math.isfinite(zmin):
        zmin, zmax = 0.5 * dist, 2.0 * dist
    if camera.is_ortho:
        pad = 0.05 * max(zmax - zmin, camera.ortho_height)
        near, far = zmin - pad, zmax + pad
    else:
        far = max(zmax * 1.05, 1e-3 * dist, 1e-9)
        near = max(zmin * 0.95, far * 1e-4)
    if camera.near is not None:
        near = camera.near
    if camera.far is not None:
        far = camera.far
    if far <= near:
        far = near * 2.0 + 1e-9
    return near, far


def _gl_mat(m: np.ndarray) -> bytes:
    """Row-major (4, 4) -> the column-major float32 bytes GLSL expects."""
    return np.ascontiguousarray(m.T, dtype=np.float32).tobytes()


class Renderer:
    """A GL context with its programs and framebuffers; renders scenes to image arrays.

    Multisampling follows ``RenderOptions.samples`` per call (capped at the GL's maximum); the
    framebuffers are kept while the size and sample count stay the same.

    Raises
    ------
    GLUnavailable
        When no EGL context can be created; the message names the packages to install.

    Notes
    -----
    Use one renderer for all the frames of a sequence (the context and the compiled shaders are
    what make later frames fast); release it with :meth:`release` or a ``with`` block.
    """

    def __init__(self):
        self.ctx = _create_context()
        self.ctx.gc_mode = "auto"
        self.mesh_prog = self.ctx.program(vertex_shader=_MESH_VS, fragment_shader=_MESH_FS)
        self.line_prog = self.ctx.program(vertex_shader=_LINE_VS, fragment_shader=_LINE_FS)
        self._white = self.ctx.buffer(np.ones(3, np.float32).tobytes())
        self._tex_prog = None  # compiled on the first textured mesh
        self._fbo_key = None
        self._fbos = ()

    # context manager -------------------------------------------------------------------------
    def __enter__(self) -> Renderer:
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    def release(self) -> None:
        """Free the GL context and everything in it."""
        if self.ctx is not None:
            with self.ctx:
                for f in self._fbos:
                    f.release()
            self.ctx.release()
            self.ctx = None

    @property
    def info(self) -> str:
        """The GL renderer's name and version (e.g. 'llvmpipe (LLVM 15.0.6, 256 bits), 4.5 Mesa')."""
        return f"{self.ctx.info['GL_RENDERER']}, {self.ctx.info['GL_VERSION']}"

    # framebuffers ----------------------------------------------------------------------------
    def _framebuffers(self, size: tuple[int, int], samples: int):
        samples = max(1, min(int(samples), int(self.ctx.max_samples)))
        if samples == 1:
            samples = 0
        key = (size, samples)
        if key != self._fbo_key:
            for f in self._fbos:
                f.release()
            self._fbos, self._fbo_key = (), None
            ctx = self.ctx
            import moderngl

            try:
                draw = ctx.framebuffer(
                    color_attachments=[ctx.renderbuffer(size, 4, samples=samples)],
                    depth_attachment=ctx.depth_renderbuffer(size, samples=samples),
                )
                resolve = ctx.framebuffer(color_attachments=[ctx.renderbuffer(size, 4)]) if samples else draw
            except moderngl.Error as exc:  # the GL's limit on an image (llvmpipe: about 8192x8192 at 4 samples)
                from inflo.formats.errors import InputError

                raise InputError(f"--size {size[0]}x{size[1]} --samples {max(samples, 1)}: expected an image the GL "
                                 f"can allocate (a smaller --size, or fewer --samples), found {exc}") from None
            self._fbos = (draw, resolve) if samples else (draw,)
            self._fbo_key = key
        return self._fbos[0], self._fbos[-1]

    # drawing ---------------------------------------------------------------------------------
    def render(self, meshes, camera: Camera | None = None, options: RenderOptions | None = None) -> np.ndarray:
        """Draw one scene.

        Parameters
        ----------
        meshes : list of ObjMesh (or objects with ``vertices``, ``faces`` and optionally
            ``normals``, ``vertex_colors``, ``lines``, ``materials``, ``face_material``)
            Drawn together; mesh i takes ``options.mesh_colors[i]``.
        camera : Camera or None
            None frames the meshes from the default (iso) view.
        options : RenderOptions or None

        Returns
        -------
        (H, W, 3) uint8
            sRGB image, first row at the top.
        """
        if self.ctx is None:
            raise RuntimeError("this Renderer has been released")
        # this renderer's context current while it draws: a process may hold several (the CLI's
        # shared one and one of its own), and GL calls go to whichever was made current last
        with self.ctx:
            return self._render(meshes, camera, options)

    def _render(self, meshes, camera, options) -> np.ndarray:
        options = options or RenderOptions()
        meshes = [meshes] if hasattr(meshes, "vertices") else list(meshes)
        if camera is None:
            camera = auto_camera(meshes, options)
        origin = np.asarray(camera.target, dtype=np.float64)
        draws = [_prepare(m, i, options, origin) for i, m in enumerate(meshes)]
        w, h = options.size
        near, far = _clip_range(camera, draws, origin)
        mvp = camera.projection_matrix(w / h, near, far) @ camera.view_matrix(origin)
        ctx = self.ctx
        draw_fbo, resolve_fbo = self._framebuffers((w, h), options.samples)
        draw_fbo.use()
        ctx.viewport = (0, 0, w, h)
        bg = tuple(float(c) for c in options.background)
        draw_fbo.clear(bg[0], bg[1], bg[2], 1.0, depth=1.0)
        ctx.enable(ctx.DEPTH_TEST)
        ctx.disable(ctx.CULL_FACE)
        ctx.depth_func = "<="
        self._set_mesh_uniforms(camera, origin, mvp, options)
        if any(d.tex_groups for d in draws):
            self._set_mesh_uniforms(camera, origin, mvp, options, self.tex_prog)
        ctx.polygon_offset = (1.0, 1.0) if options.wireframe else (0.0, 0.0)
        made = []
        try:
            for d in draws:
                self._draw_mesh(d, made)
            ctx.polygon_offset = (0.0, 0.0)
            if any(d.edges is not None and len(d.edges) for d in draws) or any(
                d.segments is not None and len(d.segments) for d in draws
            ):
                self.line_prog["u_mvp"].write(_gl_mat(mvp))
                ctx.line_width = float(options.line_width)
                for d in draws:
                    if d.edges is not None and len(d.edges):
                        self._draw_lines(d, d.edges, options.wireframe_color, made)
                    if d.segments is not None and len(d.segments):
                        self._draw_lines(d, d.segments, options.line_color, made)
            if resolve_fbo is not draw_fbo:
                ctx.copy_framebuffer(resolve_fbo, draw_fbo)
            data = resolve_fbo.read(components=3, alignment=1)
        finally:
            for obj in reversed(made):
                obj.release()
        return np.frombuffer(data, dtype=np.uint8).reshape(h, w, 3)[::-1].copy()

    @property
    def tex_prog(self):
        """The textured mesh program (:data:`_TEX_VS`, :data:`_TEX_FS`), compiled on first use."""
        if self._tex_prog is None:
            self._tex_prog = self.ctx.program(vertex_shader=_TEX_VS, fragment_shader=_TEX_FS)
        return self._tex_prog

    def _set_mesh_uniforms(self, camera: Camera, origin, mvp, options: RenderOptions, p=None) -> None:
        p = self.mesh_prog if p is None else p
        r, u, f = camera.basis()
        to_viewer = -f
        if camera.light is None:
            key = np.r_[_unit(-0.45 * r + 0.55 * u + 0.70 * to_viewer), 0.0]
        else:
            key = np.r_[np.subtract(camera.light, origin), 1.0]
        fill = _unit(0.70 * r - 0.10 * u + 0.45 * to_viewer)
        values = {
            "u_eye": tuple(np.subtract(camera.eye, origin).tolist()),
            "u_view_dir": tuple(to_viewer.tolist()),
            "u_ortho": 1 if camera.is_ortho else 0,
            "u_key": tuple(float(x) for x in key),
            "u_fill_dir": tuple(fill.tolist()),
            "u_ambient": float(options.ambient),
            "u_key_i": float(options.key),
            "u_fill_i": float(options.fill),
            "u_spec": float(options.specular),
            "u_shininess": float(options.shininess),
        }
        p["u_mvp"].write(_gl_mat(mvp))
        for name, value in values.items():
            if name in p:
                p[name].value = value

    def _draw_mesh(self, d: _Draw, made: list) -> None:
        if d.tex_groups:
            self._draw_textured(d, made)
        if len(d.tris) == 0 or not d.groups:
            return
        ctx, p = self.ctx, self.mesh_prog
        vbo = ctx.buffer(d.pos.tobytes())
        nbo = ctx.buffer(np.ascontiguousarray(d.normal, np.float32).tobytes())
        ibo = ctx.buffer(d.tris.tobytes())
        made += [vbo, nbo, ibo]
        content = [(vbo, "3f", "in_pos"), (nbo, "3f", "in_normal")]
        if d.color is not None:
            cbo = ctx.buffer(np.ascontiguousarray(d.color, np.float32).tobytes())
            made.append(cbo)
            content.append((cbo, "3f", "in_color"))
        else:  # one colour for every vertex: an instanced attribute drawn as one instance
            content.append((self._white, "3f/i", "in_color"))
        vao = ctx.vertex_array(p, content, index_buffer=ibo, index_element_size=4)
        made.append(vao)
        for first, count, rgb in d.groups:
            p["u_color"].value = tuple(float(c) for c in rgb)
            vao.render(ctx.TRIANGLES, vertices=3 * count, first=3 * first, instances=1)

    def _draw_textured(self, d: _Draw, made: list) -> None:
        """The textured faces of a mesh: base colour from the texture (mipmapped, trilinear)."""
        ctx, p = self.ctx, self.tex_prog
        vbo = ctx.buffer(d.pos.tobytes())
        nbo = ctx.buffer(np.ascontiguousarray(d.normal, np.float32).tobytes())
        tbo = ctx.buffer(d.uv.tobytes())
        ibo = ctx.buffer(d.tex_tris.tobytes())
        made += [vbo, nbo, tbo, ibo]
        content = [(vbo, "3f", "in_pos"), (nbo, "3f", "in_normal"), (tbo, "2f", "in_uv")]
        if d.color is not None:
            cbo = ctx.buffer(np.ascontiguousarray(d.color, np.float32).tobytes())
            made.append(cbo)
            content.append((cbo, "3f", "in_color"))
        else:
            content.append((self._white, "3f/i", "in_color"))
        vao = ctx.vertex_array(p, content, index_buffer=ibo, index_element_size=4)
        made.append(vao)
        for first, count, image in d.tex_groups:
            h, w = image.shape[:2]
            tex = ctx.texture((w, h), 4, np.ascontiguousarray(image, np.uint8).tobytes())
            made.append(tex)
            tex.build_mipmaps()
            tex.filter = (ctx.LINEAR_MIPMAP_LINEAR, ctx.LINEAR)
            tex.repeat_x = tex.repeat_y = False
            tex.anisotropy = 16.0
            tex.use(0)
            if "u_tex" in p:
                p["u_tex"].value = 0
            vao.render(ctx.TRIANGLES, vertices=3 * count, first=3 * first, instances=1)

    def _draw_lines(self, d: _Draw, pairs: np.ndarray, rgb, made: list) -> None:
        ctx, p = self.ctx, self.line_prog
        vbo = ctx.buffer(d.pos.tobytes())
        ibo = ctx.buffer(np.ascontiguousarray(pairs, np.int32).tobytes())
        vao = ctx.vertex_array(p, [(vbo, "3f", "in_pos")], index_buffer=ibo, index_element_size=4)
        made += [vbo, ibo, vao]
        p["u_color"].value = tuple(float(c) for c in rgb)
        vao.render(ctx.LINES, vertices=2 * len(pairs))


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


@functools.lru_cache(maxsize=1)
def default_renderer() -> Renderer:
    """The process's shared :class:`Renderer`, created on first use (one GL context per process)."""
    return Renderer()


def render_meshes(meshes, camera: Camera | None = None, options: RenderOptions | None = None, *,
                  renderer: Renderer | None = None) -> np.ndarray:
    """Render meshes drawn together into one image.

    Parameters
    ----------
    meshes : ObjMesh or list of ObjMesh
        The scene; mesh i takes ``options.mesh_colors[i]`` and ``options.default_colors[i]``.
    camera : Camera or None
        None: :func:`auto_camera` from the default (iso) view.
    options : RenderOptions or None
    renderer : Renderer or None
        None uses :func:`default_renderer`.

    Returns
    -------
    (H, W, 3) uint8
    """
    return (renderer or default_renderer()).render(meshes, camera, options)


def render_sequence(frames: Iterable, camera: Camera | None = None, options: RenderOptions | None = None, *,
                    renderer: Renderer | None = None, **view) -> Iterator[np.ndarray]:
    """Render the frames of an animation with one camera and one GL context.

    Parameters
    ----------
    frames : iterable of (list of ObjMesh)
        One scene per frame (a bare mesh per frame is accepted too).
    camera : Camera or None
        None frames every frame at once (``frames`` must then be a sequence, e.g. a list) so the
        animation does not jump; ``view`` takes :func:`auto_camera`'s view keywords.
    options : RenderOptions or None
    renderer : Renderer or None
        None uses :func:`default_renderer`.

    Yields
    ------
    (H, W, 3) uint8
        One image per frame, in order.
    """
    options = options or RenderOptions()
    if camera is None:
        frames = list(frames)
        camera = auto_camera(frames, options, **view)
    r = renderer or default_renderer()
    for scene in frames:
        yield r.render(scene, camera, options)
