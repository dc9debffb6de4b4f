"""Canopy composer parameter file ``.fcc`` (thesis appendix C.1): reader, writer, reference check.

The Floral Canopy Composer (``fccompose``) is configured by one ``key: value`` text file naming the
scene (SCN) files, the floret animations and OBJs by id, the solver and collision parameters, the
collision lattice and the viewer's camera and light. The spec page is ``formats/fcc.md``; it lists
every key with its type, unit and default.

Parsing (:func:`read_fcc`) does not touch the files the parameters name, so it can be tested without
them; :func:`check_references` checks separately that every referenced file or folder exists.

This module is the format's one import path; each concern lives in its own module beside it:

- ``_fccparams.py``: the data model (:class:`CanopyParams`, :class:`FilePath`, the entries, the
  lattice and camera keys);
- ``_fcckeys.py``: the key table (:data:`KEYS`, :class:`KeySpec`, :data:`ALIASES`);
- ``_fccread.py``: the reader (:func:`read_fcc`);
- ``_fccwrite.py``: the writer (:func:`format_fcc`, :func:`write_fcc`);
- ``_fccrefs.py``: the reference check (:func:`check_references`, :class:`MissingReferenceError`).
"""
from __future__ import annotations

from ._fcckeys import ALIASES as ALIASES
from ._fcckeys import KEYS, KNOWN_KEYS, KeySpec
from ._fcckeys import REPEATABLE as REPEATABLE
from ._fcckeys import SCHEMES as SCHEMES
from ._fccparams import (
    AnimationEntry,
    CameraParams,
    CanopyParams,
    FilePath,
    LatticeParams,
    RigidBodyAnimationEntry,
)
from ._fccparams import Vec3 as Vec3
from ._fccread import _CHECKS as _CHECKS
from ._fccread import _READ as _READ
from ._fccread import read_fcc
from ._fccrefs import MissingReferenceError, check_references
from ._fccwrite import format_fcc, write_fcc

__all__ = [
    "AnimationEntry",
    "CameraParams",
    "CanopyParams",
    "FilePath",
    "KEYS",
    "KeySpec",
    "LatticeParams",
    "MissingReferenceError",
    "RigidBodyAnimationEntry",
    "KNOWN_KEYS",
    "check_references",
    "format_fcc",
    "read_fcc",
    "write_fcc",
]
