"""Writing rendered images: PNG stills and sheets, GIF and MP4 animations, all atomically.

Every writer builds the whole file in memory (or, for MP4, in a private temporary folder) and
puts it in place with :func:`inflo.formats.atomic.write_bytes_atomic`: a temporary file in the
target folder renamed over the target, so a failed run leaves no partial file (docs/architecture.md).
"""
from __future__ import annotations

import io
import os
import tempfile
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from PIL import Image

from inflo.formats.atomic import write_bytes_atomic

__all__ = ["encode_png", "write_png", "encode_gif", "write_gif", "write_mp4", "ANIMATION_SUFFIXES"]

ANIMATION_SUFFIXES = (".gif", ".mp4")


def _as_image(array: np.ndarray) -> Image.Image:
    a = np.asarray(array)
    if a.dtype != np.uint8 or a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"expected an (H, W, 3) uint8 image, got {a.dtype} {a.shape}")
    return Image.fromarray(np.ascontiguousarray(a), "RGB")


def encode_png(image: np.ndarray) -> bytes:
    """PNG bytes of an ``(H, W, 3) uint8`` image (same pixels -> same bytes)."""
    buf = io.BytesIO()
    _as_image(image).save(buf, format="PNG", compress_level=6)
    return buf.getvalue()


def write_png(path, image: np.ndarray) -> None:
    """Write an ``(H, W, 3) uint8`` image as PNG, atomically."""
    write_bytes_atomic(path, encode_png(image))


def _gif_palette(frames: list[np.ndarray]) -> Image.Image:
    """One 256-colour palette for every frame (no palette flicker), from up to 16 frames."""
    pick = np.unique(np.linspace(0, len(frames) - 1, min(16, len(frames))).round().astype(int))
    thumbs = []
    for i in pick:
        im = _as_image(frames[i])
        if im.width > 320:
            im = im.resize((320, max(1, round(im.height * 320 / im.width))), Image.Resampling.BOX)
        thumbs.append(np.asarray(im))
    width = max(t.shape[1] for t in thumbs)
    mosaic = np.concatenate([np.pad(t, ((0, 0), (0, width - t.shape[1]), (0, 0)), mode="edge") for t in thumbs])
    return Image.fromarray(mosaic, "RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT,
                                                   dither=Image.Dither.NONE)


def encode_gif(frames: Iterable[np.ndarray], fps: float) -> tuple[bytes, int]:
    """An endlessly looping animated GIF of the frames; returns (bytes, number of frames).

    All frames share one palette (made from up to 16 frames spread over the animation) and are
    Floyd-Steinberg dithered to it. GIF stores frame durations in hundredths of a second, so the
    rate is rounded to that.
    """
    frames = [np.asarray(f) for f in frames]
    if not frames:
        raise ValueError("no frames to write")
    palette = _gif_palette(frames)
    images = [_as_image(f).quantize(palette=palette, dither=Image.Dither.FLOYDSTEINBERG) for f in frames]
    duration = max(20, int(round(1000.0 / fps / 10.0)) * 10)
    buf = io.BytesIO()
    images[0].save(buf, format="GIF", save_all=True, append_images=images[1:], duration=duration, loop=0,
                   optimize=False, disposal=1)
    return buf.getvalue(), len(images)


def write_gif(path, frames: Iterable[np.ndarray], fps: float = 25.0) -> int:
    """Write an animated GIF atomically; returns the number of frames written."""
    data, n = encode_gif(frames, fps)
    write_bytes_atomic(path, data)
    return n


def write_mp4(path, frames: Iterable[np.ndarray], fps: float = 25.0, crf: int = 18) -> int:
    """Write an H.264 MP4 (yuv420p, plays everywhere) atomically; returns the number of frames.

    Frames stream to the ffmpeg that ``imageio-ffmpeg`` ships. An odd width or height is padded
    by one pixel (repeating the edge), as yuv420p needs even sizes.
    """
    import imageio_ffmpeg

    path = Path(path)
    n = 0
    with tempfile.TemporaryDirectory(prefix="canopy-render-") as tmp:
        tmp_path = os.path.join(tmp, "out.mp4")
        writer = None
        try:
            for frame in frames:
                a = np.asarray(frame)
                _as_image(a)  # validates shape and dtype
                h, w = a.shape[:2]
                a = np.pad(a, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")
                if writer is None:
                    size = (a.shape[1], a.shape[0])
                    writer = imageio_ffmpeg.write_frames(
                        tmp_path, size, fps=fps, codec="libx264", pix_fmt_in="rgb24", pix_fmt_out="yuv420p",
                        quality=None, macro_block_size=1, ffmpeg_log_level="error",
                        output_params=["-crf", str(int(crf)), "-preset", "medium", "-movflags", "+faststart"],
                    )
                    writer.send(None)
                elif (a.shape[1], a.shape[0]) != size:
                    raise ValueError(f"frame {n + 1} is {a.shape[1]}x{a.shape[0]}, the first was {size[0]}x{size[1]}")
                writer.send(np.ascontiguousarray(a))
                n += 1
        finally:
            if writer is not None:
                writer.close()
        if n == 0:
            raise ValueError("no frames to write")
        with open(tmp_path, "rb") as fh:
            data = fh.read()
    write_bytes_atomic(path, data)
    return n
