"""PC2 point caches: the positions of a fixed-topology mesh in every frame (spec: ``formats/pc2.md``).

A PC2 file is a 32-byte little-endian header and the frames' vertex positions as float32, the
format of Blender's *Mesh Cache* modifier (and 3ds Max's Point Cache 2). It carries no faces: it
animates a mesh with the same vertex count and order, e.g. the first OBJ frame of the sequence.
"""
from __future__ import annotations

import os
import struct

import numpy as np

from .atomic import write_bytes_atomic
from .errors import FormatError, read_bytes

__all__ = ["PC2_MAGIC", "encode_pc2", "write_pc2", "read_pc2"]

PC2_MAGIC = b"POINTCACHE2\x00"
_HEADER = struct.Struct("<12siiffi")  # magic, version, vertex count, start frame, sampling, frames


def encode_pc2(points: np.ndarray, *, start_frame: float = 1.0, sampling: float = 1.0) -> bytes:
    """The bytes of a PC2 file.

    Parameters
    ----------
    points : (frames, n, 3) float
        Vertex positions per frame (stored as little-endian float32).
    start_frame : float
        The scene frame of the first sample.
    sampling : float
        Frames between samples (1: one sample per frame).
    """
    pts = np.asarray(points, dtype="<f4")
    if pts.ndim != 3 or pts.shape[2] != 3:
        raise ValueError(f"expected (frames, n, 3) points, got shape {pts.shape}")
    header = _HEADER.pack(PC2_MAGIC, 1, pts.shape[1], float(start_frame), float(sampling), pts.shape[0])
    return header + np.ascontiguousarray(pts).tobytes()


def write_pc2(path, points: np.ndarray, *, start_frame: float = 1.0, sampling: float = 1.0) -> None:
    """Write a PC2 file atomically (see :func:`encode_pc2`)."""
    write_bytes_atomic(path, encode_pc2(points, start_frame=start_frame, sampling=sampling))


def read_pc2(path) -> tuple[np.ndarray, float, float]:
    """Read a PC2 file: ``(points (frames, n, 3) float32, start_frame, sampling)``.

    Raises
    ------
    FormatError
        A file that does not start with ``POINTCACHE2``, an unknown version, or a size that does
        not match its header.
    """
    path = os.fspath(path)
    data = read_bytes(path)
    if len(data) < _HEADER.size or not data.startswith(PC2_MAGIC):
        raise FormatError(path, None, "a PC2 file (starting with 'POINTCACHE2')", f"{data[:12]!r}")
    _, version, n, start, sampling, frames = _HEADER.unpack_from(data)
    if version != 1:
        raise FormatError(path, None, "PC2 version 1", str(version))
    want = _HEADER.size + 12 * n * frames
    if n < 0 or frames < 0 or len(data) != want:
        raise FormatError(path, None, f"{want} bytes ({frames} frames of {n} vertices)", f"{len(data)} bytes")
    pts = np.frombuffer(data, dtype="<f4", offset=_HEADER.size).reshape(frames, n, 3)
    return pts.astype(np.float32), float(start), float(sampling)
