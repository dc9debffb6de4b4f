"""Contact sheets (a grid of selected frames with labels, like Ijiri et al. 2008, fig. 1) and frame numbers.

Frame numbers on the command line and in labels count the frames of a sequence from 1 (frame 1 is
the first file, as in "frames 1, 10, 20, ..., 100" of an opening flower); negative numbers count
from the end (-1 is the last frame). Internally frames are 0-based indices.
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from inflo.formats.errors import InputError

__all__ = [
    "parse_frame_list",
    "frame_index",
    "every_nth",
    "grid_shape",
    "contact_sheet",
    "format_label",
]


def parse_frame_list(text: str) -> list[int]:
    """Frame numbers from ``"1,10,20"`` (1-based; negative from the end), in the given order.

    Raises
    ------
    ValueError
        When an item is not an integer or is 0.
    """
    items = [t.strip() for t in str(text).split(",")]
    out = []
    for t in items:
        if not t:
            continue
        try:
            n = int(t)
        except ValueError:
            raise ValueError(f"expected comma-separated frame numbers like 1,10,20, found {t!r}") from None
        if n == 0:
            raise ValueError("frame numbers count from 1 (negative ones from the end); found 0")
        out.append(n)
    if not out:
        raise ValueError(f"expected comma-separated frame numbers like 1,10,20, found {text!r}")
    return out


def frame_index(number: int, n_frames: int) -> int:
    """0-based index of 1-based frame ``number`` (negative: from the end) in ``n_frames`` frames.

    Raises
    ------
    InputError
        When the frame does not exist.
    """
    if number > 0 and number <= n_frames:
        return number - 1
    if number < 0 and -number <= n_frames:
        return n_frames + number
    raise InputError(
        f"frame {number} does not exist: the sequence has {n_frames} frame{'s' if n_frames != 1 else ''} "
        f"(1..{n_frames}, or -1..-{n_frames} from the end)"
    )


def every_nth(step: int, n_frames: int) -> list[int]:
    """Frame numbers 1, step, 2 step, ... and the last frame (1-based), as in Ijiri's fig. 1 (1, 10, ..., 100)."""
    if step < 1:
        raise ValueError(f"the step must be at least 1, got {step}")
    nums = [1] + list(range(step, n_frames + 1, step))
    if nums[-1] != n_frames:
        nums.append(n_frames)
    return sorted(set(nums))


def grid_shape(count: int, columns: int | None = None, max_columns: int = 6) -> tuple[int, int]:
    """(columns, rows) of a sheet of ``count`` tiles.

    Default: one row up to ``max_columns`` tiles, else the fewest rows of at most ``max_columns``
    with the tiles spread evenly (11 tiles: 6 + 5; 8 tiles: 4 + 4).
    """
    if count < 1:
        raise ValueError("a contact sheet needs at least one frame")
    if columns is None:
        rows = math.ceil(count / max_columns)
        columns = math.ceil(count / rows)
    columns = max(1, min(int(columns), count))
    return columns, math.ceil(count / columns)


def format_label(template: str, number: int, index: int, name: str) -> str:
    """A tile label: ``template`` with ``{n}`` (1-based frame number), ``{index}`` (0-based), ``{name}`` (file stem)."""
    try:
        return template.format(n=number, index=index, name=name)
    except (KeyError, IndexError, ValueError) as exc:
        raise ValueError(f"label format {template!r}: use {{n}}, {{index}} or {{name}} ({exc})") from None


def _font(size: int):
    try:
        return ImageFont.load_default(size=size)
    except (TypeError, OSError, ImportError):  # Pillow without FreeType: the fixed bitmap font
        return ImageFont.load_default()


def contact_sheet(images: Sequence[np.ndarray], labels: Sequence[str] | None = None, *,
                  columns: int | None = None, gap: int | None = None, background=(1.0, 1.0, 1.0),
                  text_color=None, title: str | None = None, font_size: int | None = None) -> np.ndarray:
    """Lay images out in a grid, each with its label centred below it.

    Parameters
    ----------
    images : list of (h, w, 3) uint8
        Tiles, all the same size, in reading order (left to right, top to bottom).
    labels : list of str or None
        One per tile; None or empty strings for no labels.
    columns : int or None
        See :func:`grid_shape`.
    gap : int or None
        Pixels between tiles and around the sheet (default: 3 % of the tile width, at least 4).
    background, text_color : (3,) float
        sRGB in 0..1; ``text_color`` None: dark grey on a light background, light grey on a dark
        one (:func:`text_color_for`), so the title and labels read on either.
    title : str or None
        A line above the grid.
    font_size : int or None
        Label size in pixels (default: about 1/18 of the tile height, 12 at least).

    Returns
    -------
    (H, W, 3) uint8
        With ``W = cols * w + (cols + 1) * gap`` and ``H = rows * (h + label) + (rows + 1) * gap``
        (+ the title line).
    """
    if not images:
        raise ValueError("a contact sheet needs at least one frame")
    h, w = images[0].shape[:2]
    for im in images:
        if im.shape != images[0].shape:
            raise ValueError(f"contact sheet tiles differ in size: {im.shape} and {images[0].shape}")
    labels = list(labels) if labels else [""] * len(images)
    if len(labels) != len(images):
        raise ValueError("one label per image")
    cols, rows = grid_shape(len(images), columns)
    gap = max(4, round(0.03 * w)) if gap is None else int(gap)
    size = font_size or max(12, round(h / 18))
    font = _font(size)
    has_labels = any(labels)
    label_h = round(size * 1.6) if has_labels else 0
    title_h = round(size * 2.0) if title else 0
    W = cols * w + (cols + 1) * gap
    H = title_h + rows * (h + label_h) + (rows + 1) * gap
    bg = tuple(int(round(255 * c)) for c in background)
    fg = tuple(int(round(255 * c)) for c in (text_color_for(background) if text_color is None else text_color))
    sheet = Image.new("RGB", (W, H), bg)
    draw = ImageDraw.Draw(sheet)
    if title:
        _centred_text(draw, W / 2, gap + title_h / 2, title, fg, font)
    for k, (im, label) in enumerate(zip(images, labels)):
        r, c = divmod(k, cols)
        x = gap + c * (w + gap)
        y = title_h + gap + r * (h + label_h + gap)
        sheet.paste(Image.fromarray(np.ascontiguousarray(im), "RGB"), (x, y))
        if label:
            _centred_text(draw, x + w / 2, y + h + label_h / 2, label, fg, font)
    return np.asarray(sheet).copy()


def text_color_for(background) -> tuple:
    """Text colour that reads on ``background`` (sRGB 0..1): dark grey where its relative luminance
    (WCAG, linear Rec. 709 weights) is over 0.18, light grey below."""
    lin = [c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4 for c in map(float, background)]
    lum = 0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2]
    return (0.15, 0.15, 0.15) if lum > 0.18 else (0.9, 0.9, 0.9)


def _centred_text(draw: ImageDraw.ImageDraw, cx: float, cy: float, text: str, fill, font) -> None:
    """Draw ``text`` centred on (cx, cy) (works with bitmap fonts too, unlike ``anchor="mm"``)."""
    left, top, right, bottom = draw.textbbox((0, 0), text, font=font)
    draw.text((round(cx - (left + right) / 2), round(cy - (top + bottom) / 2)), text, fill=fill, font=font)
