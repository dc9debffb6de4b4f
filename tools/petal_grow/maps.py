"""Growth maps: painted PNG textures or functions of (u, v), sampled per triangle (Ijiri et al. 2008,
sec. 3.1 and eq. 1).

A scalar map gives a value per uv point: a PNG's brightness in [0, 1] (the paper's painted growth
maps, fig. 2, read through Pillow) or an arithmetic expression in ``u`` and ``v`` (exact tests,
maps designed as formulas). A direction map gives a 2-vector in uv: a PNG's red and green channels
mapped from [0, 255] to [-1, 1] (red: u, green: v; sec. 3.1), or two expressions ``"du, dv"``.

:func:`triangle_values` averages a map over a triangle as eq. 1,
``map(T) = (map(uv0) + map(uv1) + map(uv2) + 3 map(uvc)) / 6`` with ``uvc`` the centroid.
"""
from __future__ import annotations

import ast
import copy
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from inflo.formats.errors import FormatError, shorten
from inflo.tools.common import linalg as la

__all__ = ["ScalarMap", "DirectionMap", "parse_scalar_map", "parse_direction_map", "triangle_values",
           "triangle_directions", "checked_values", "EXPRESSION_NAMES"]

_FUNCS = {
    "sin": np.sin, "cos": np.cos, "tan": np.tan, "exp": np.exp, "log": np.log, "sqrt": np.sqrt,
    "abs": np.abs, "atan2": np.arctan2, "minimum": np.minimum, "maximum": np.maximum,
    "min": np.minimum, "max": np.maximum,
    "clip": lambda x, lo, hi: np.clip(x, lo, hi),
    "smoothstep": lambda a, b, x: (lambda t: t * t * (3.0 - 2.0 * t))(np.clip((x - a) / (b - a), 0.0, 1.0)),
    "step": lambda a, x: (np.asarray(x) >= a).astype(np.float64),
}
_CONSTS = {"pi": math.pi, "e": math.e}
EXPRESSION_NAMES = sorted(["u", "v", *_FUNCS, *_CONSTS])
"""Names an expression may use (formats/petal_grow.md, "Growth maps")."""

_NODES = (ast.Expression, ast.BinOp, ast.UnaryOp, ast.Call, ast.Name, ast.Load, ast.Constant,
          ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.USub, ast.UAdd, ast.Mod,
          ast.Compare, ast.Lt, ast.LtE, ast.Gt, ast.GtE, ast.IfExp)


#: the longest growth expression (characters) and its deepest nesting (operations and calls
#: within one another): Python's parser and compiler recurse once a level
MAX_EXPRESSION_CHARS = 1000
MAX_EXPRESSION_DEPTH = 100


def _depth(tree) -> int:
    """The nesting depth of an expression tree, found without recursion."""
    deepest, todo = 0, [(tree, 1)]
    while todo:
        node, d = todo.pop()
        deepest = max(deepest, d)
        todo.extend((c, d + 1) for c in ast.iter_child_nodes(node))
    return deepest


def _compile(text: str, path, line, what: str):
    """Check and compile one arithmetic expression in u, v (no attribute access, no other names)."""
    if len(text) > MAX_EXPRESSION_CHARS:
        raise FormatError(path, line, f"{what}: an expression of at most {MAX_EXPRESSION_CHARS} characters",
                          f"{len(text)} characters: {shorten(text)}")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError:
        raise FormatError(path, line, f"{what}: an expression in u and v or a .png file", shorten(text)) from None
    except (RecursionError, MemoryError):
        raise FormatError(path, line, f"{what}: an expression nested at most {MAX_EXPRESSION_DEPTH} deep",
                          shorten(text)) from None
    if _depth(tree) > MAX_EXPRESSION_DEPTH:
        raise FormatError(path, line, f"{what}: an expression nested at most {MAX_EXPRESSION_DEPTH} deep",
                          f"{_depth(tree)} levels: {shorten(text)}")
    for node in ast.walk(tree):
        if not isinstance(node, _NODES):
            raise FormatError(path, line, f"{what}: only arithmetic, comparisons and the functions "
                              f"{', '.join(sorted(_FUNCS))}", shorten(text))
        if isinstance(node, ast.Name) and node.id not in ("u", "v", *_FUNCS, *_CONSTS):
            raise FormatError(path, line, f"{what}: names among {', '.join(EXPRESSION_NAMES)}", repr(node.id))
        if isinstance(node, ast.Call) and not (isinstance(node.func, ast.Name) and node.func.id in _FUNCS):
            raise FormatError(path, line, f"{what}: calls of {', '.join(sorted(_FUNCS))}", shorten(text))
        if isinstance(node, ast.Constant) and not isinstance(node.value, (int, float)):
            raise FormatError(path, line, f"{what}: numbers", repr(node.value))
        if isinstance(node, ast.IfExp):
            raise FormatError(path, line, f"{what}: no 'if' (use step() or smoothstep())", shorten(text))
    for node in ast.walk(tree):
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow) and _constant(node.right):
            e = _float_value(node.right, path, line, what, text)
            if not abs(e) <= MAX_EXPONENT:
                raise FormatError(path, line, f"{what}: constant exponents within +-{MAX_EXPONENT}", shorten(text))
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow) and _constant(node):
            # a constant power is evaluated exactly on integers: finite in floating point, it has at
            # most 309 digits ((9**1024)**1024 would not end)
            if not math.isfinite(_float_value(node, path, line, what, text)):
                raise FormatError(path, line, f"{what}: constant powers within floating point range (1.8e308)",
                                  shorten(text))
    code = compile(tree, "<growth map>", "eval")
    try:
        _eval(code, np.array([[0.0, 0.0], [0.5, 0.5], [1.0, 1.0]]))
    except (OverflowError, ZeroDivisionError, ValueError, TypeError, MemoryError) as exc:
        raise FormatError(path, line, f"{what}: an expression with a value at every (u, v)",
                          f"{shorten(text)} ({type(exc).__name__})") from None
    return code


#: the largest constant exponent of a growth expression: an integer power is evaluated exactly by
#: Python, so 9**9**9 would run for hours and fill memory
MAX_EXPONENT = 1024


def _constant(node) -> bool:
    return not any(isinstance(n, ast.Name) and n.id in ("u", "v") for n in ast.walk(node))


def _float_value(node, path, line, what, text) -> float:
    """A name-free subexpression evaluated in floating point (never Python's exact integers)."""

    class _Floats(ast.NodeTransformer):
        def visit_Constant(self, n):
            return ast.copy_location(ast.Constant(float(n.value)), n) if isinstance(n.value, int) else n

    tree = ast.fix_missing_locations(_Floats().visit(ast.Expression(body=copy.deepcopy(node))))
    try:
        with np.errstate(all="ignore"):
            return float(eval(compile(tree, "<exponent>", "eval"), {"__builtins__": {}}, {**_FUNCS, **_CONSTS}))
    except (OverflowError, ZeroDivisionError, ValueError, TypeError):
        raise FormatError(path, line, f"{what}: constant exponents within +-{MAX_EXPONENT}", shorten(text)) from None


def _eval(code, uv: np.ndarray) -> np.ndarray:
    env = {"u": uv[:, 0], "v": uv[:, 1], **_FUNCS, **_CONSTS}
    with np.errstate(all="ignore"):
        out = eval(code, {"__builtins__": {}}, env)
    return np.broadcast_to(np.asarray(out, dtype=np.float64), (len(uv),)).copy()


#: the largest growth-map PNG (pixels): a map is held as float64 RGB, 24 bytes a pixel
MAX_MAP_PIXELS = 4096 * 4096


def _read_png(path: Path, src, line, what: str) -> np.ndarray:
    """(H, W, 3) float64 in [0, 1], row 0 at v = 1 (image top)."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as im:
            w, h = im.size
            if w * h > MAX_MAP_PIXELS:
                raise FormatError(src, line, f"{what}: a PNG of at most {MAX_MAP_PIXELS} pixels (e.g. 4096 x 4096)",
                                  f"{path.name} of {w} x {h}")
            return np.asarray(im.convert("RGB"), dtype=np.float64) / 255.0
    except FileNotFoundError:
        raise FormatError(src, line, f"{what}: an existing PNG file", str(path)) from None
    except Image.DecompressionBombError:
        raise FormatError(src, line, f"{what}: a PNG of at most {MAX_MAP_PIXELS} pixels (e.g. 4096 x 4096)",
                          f"{path.name}, larger than PIL opens") from None
    except (UnidentifiedImageError, OSError) as exc:
        raise FormatError(src, line, f"{what}: a readable PNG image", f"{path.name} ({exc})") from None


def _bilinear(img: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(k, C) bilinear samples of ``img`` at ``uv`` (clamped to [0, 1]; u right, v up)."""
    h, w = img.shape[:2]
    x = np.clip(uv[:, 0], 0.0, 1.0) * (w - 1)
    y = (1.0 - np.clip(uv[:, 1], 0.0, 1.0)) * (h - 1)
    x0 = np.floor(x).astype(np.int64)
    y0 = np.floor(y).astype(np.int64)
    x1 = np.minimum(x0 + 1, w - 1)
    y1 = np.minimum(y0 + 1, h - 1)
    fx = (x - x0)[:, None]
    fy = (y - y0)[:, None]
    top = img[y0, x0] * (1 - fx) + img[y0, x1] * fx
    bot = img[y1, x0] * (1 - fx) + img[y1, x1] * fx
    return top * (1 - fy) + bot * fy


@dataclass
class ScalarMap:
    """A scalar growth map: ``source`` is the text as written (a formula or a PNG path)."""

    source: str
    code: object = None
    image: np.ndarray | None = None
    where: tuple = (None, None, "")  # (file, line, key) the map was read from, for errors

    def __call__(self, uv: np.ndarray) -> np.ndarray:
        uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        if self.image is not None:
            return _bilinear(self.image, uv).mean(axis=1)  # brightness: mean of R, G, B
        return _eval(self.code, uv)


@dataclass
class DirectionMap:
    """A direction map: uv vectors (not normalized here)."""

    source: str
    codes: tuple = ()
    image: np.ndarray | None = None
    where: tuple = (None, None, "")  # (file, line, key) the map was read from, for errors

    def __call__(self, uv: np.ndarray) -> np.ndarray:
        uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        if self.image is not None:
            return _bilinear(self.image, uv)[:, :2] * 2.0 - 1.0
        return np.stack([_eval(c, uv) for c in self.codes], axis=1)


def _is_png(text: str) -> bool:
    return text.strip().lower().endswith(".png")


def parse_scalar_map(value, base: Path, path, line, what: str) -> ScalarMap:
    """A number, an expression string or a ``.png`` path (relative to ``base``)."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise FormatError(path, line, f"{what}: a number, an expression in u and v, or a .png file",
                          shorten(repr(value)))
    if isinstance(value, (int, float)):
        value = repr(float(value))
    if _is_png(value):
        return ScalarMap(value, image=_read_png(base / value.strip(), path, line, what), where=(path, line, what))
    return ScalarMap(value, code=_compile(value, path, line, what), where=(path, line, what))


def parse_direction_map(value, base: Path, path, line, what: str) -> DirectionMap:
    """``"du, dv"`` expressions, a 2-list of numbers/expressions, or a ``.png`` (red u, green v)."""
    if isinstance(value, str) and _is_png(value):
        return DirectionMap(value, image=_read_png(base / value.strip(), path, line, what), where=(path, line, what))
    if isinstance(value, str):
        parts = _split_top(value)
    elif isinstance(value, list):
        parts = [repr(float(p)) if isinstance(p, (int, float)) and not isinstance(p, bool) else p for p in value]
    else:
        parts = []
    if len(parts) != 2 or not all(isinstance(p, str) for p in parts):
        raise FormatError(path, line, f"{what}: 'du, dv' (two expressions) or a .png file", shorten(repr(value)))
    return DirectionMap(str(value), codes=tuple(_compile(p, path, line, what) for p in parts),
                        where=(path, line, what))


def _split_top(text: str) -> list[str]:
    """Split at commas outside parentheses."""
    out, depth, cur = [], 0, []
    for ch in text:
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth -= 1
        if ch == "," and depth == 0:
            out.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    out.append("".join(cur))
    return out


def _corner_and_centroid(tri_uv: np.ndarray) -> np.ndarray:
    """(4m, 2): the three corners then the centroid of every triangle (blocks of m)."""
    c = tri_uv.mean(axis=1)
    return np.concatenate([tri_uv[:, 0], tri_uv[:, 1], tri_uv[:, 2], c])


def triangle_values(m: ScalarMap, tri_uv: np.ndarray) -> np.ndarray:
    """(m,) eq. 1: ``(map(uv0) + map(uv1) + map(uv2) + 3 map(uvc)) / 6`` per triangle.

    ``tri_uv`` is (m, 3, 2): the uv of each triangle's corners."""
    n = len(tri_uv)
    uv = _corner_and_centroid(tri_uv)
    s = checked_values(m, uv, m(uv)).reshape(4, n)
    return (s[0] + s[1] + s[2] + 3.0 * s[3]) / 6.0


def checked_values(m, uv: np.ndarray, values: np.ndarray) -> np.ndarray:
    """``values`` (k,) or (k, 2), the map ``m`` sampled at ``uv`` (k, 2); a FormatError naming the
    map's key and line and the first sample where a value is not finite or beyond +-MAX_MAP_VALUE."""
    flat = values.reshape(len(uv), -1) if len(uv) else values.reshape(0, 1)
    bad = ~(np.abs(flat) <= MAX_MAP_VALUE).all(axis=1)
    if bad.any():
        k = int(np.argmax(bad))
        found = ", ".join(f"{float(x):g}" for x in flat[k])
        path, line, what = m.where
        expected = f"values within +-{MAX_MAP_VALUE:g} over the organ for {what or 'growth map'} {shorten(str(m.source))}"
        found = f"{found} at (u, v) = ({float(uv[k, 0]):g}, {float(uv[k, 1]):g})"
        if path is None:
            from inflo.formats.errors import InputError

            raise InputError(f"growth map: expected {expected}, found {found}")
        raise FormatError(path, line, expected, found)
    return values


#: the largest magnitude a scalar growth map may take on an organ (rates, factors and angles)
MAX_MAP_VALUE = 1e6


def triangle_directions(m: DirectionMap, tri_uv: np.ndarray) -> np.ndarray:
    """(m, 2) unit uv directions per triangle, eq. 1 applied to each component, then normalized
    ((0, 1), along v, where the map averages to zero)."""
    n = len(tri_uv)
    uv = _corner_and_centroid(tri_uv)
    s = checked_values(m, uv, m(uv)).reshape(4, n, 2)
    d = (s[0] + s[1] + s[2] + 3.0 * s[3]) / 6.0
    norm = la.norm(d, axis=1)
    ok = norm > 1e-12
    out = np.zeros_like(d)
    out[:, 1] = 1.0
    out[ok] = d[ok] / norm[ok, None]
    return out
