"""The ``.fcc`` reference check: :func:`check_references`, that every file and folder the
parameters name exists.
"""
from __future__ import annotations

import glob
import os
from pathlib import Path

from ._fccparams import CanopyParams, FilePath
from .errors import InputError


class MissingReferenceError(InputError):
    """Files or folders a ``.fcc`` file names that do not exist.

    Attributes
    ----------
    source : pathlib.Path or None
        The ``.fcc`` file the parameters came from.
    missing : list of tuple (int or None, str, FilePath, str)
        (line, key, path, what was expected: "file", "folder", ...) for every missing reference,
        in file order.
    """

    def __init__(self, source, missing):
        self.source = source
        self.missing = missing
        where = os.fspath(source) if source is not None else "<parameters>"
        parts = []
        for line, key, fp, kind in missing:
            loc = f"{where}:{line}" if line is not None else where
            parts.append(f"{loc}: '{key}' names {fp.raw!r} ({fp.resolved}), no such {kind}")
        msg = parts[0]
        if len(parts) > 1:
            msg += f" (and {len(parts) - 1} more: " + "; ".join(parts[1:]) + ")"
        super().__init__(msg)


def _exists_folder_or_glob(p: Path) -> bool:
    if p.is_dir():
        return True
    if glob.has_magic(os.fspath(p)):
        return bool(glob.glob(os.fspath(p)))
    return False


def check_references(params: CanopyParams) -> None:
    """Check that every file and folder ``params`` names exists.

    Scene files, OBJs, weight files, colour and material maps must be files; animation paths a
    folder or a glob matching something; RBA paths a folder. Output locations are not checked
    (fccompose creates them).

    Raises
    ------
    MissingReferenceError
        (an :class:`InputError`) naming the first missing path, the ``.fcc`` line that named it,
        and how many more are missing; ``.missing`` lists them all.
    """
    missing = []

    def need(key, fp: FilePath | None, kind: str, ok):
        if fp is not None and not ok(fp.resolved):
            missing.append((fp.line, key, fp, kind))

    need("color map file location", params.color_map, "file", Path.is_file)
    need("material map file location", params.material_map, "file", Path.is_file)
    for f in params.scene_files:
        need("scene file path", f, "file", Path.is_file)
    for e in params.animations:
        if e.kind == "obj":
            need("obj", e.path, "file", Path.is_file)
        else:
            need("animation", e.path, "folder or matching glob", _exists_folder_or_glob)
    for r in params.rigid_body_animations:
        need("rigid body animation", r.rba_folder, "folder", Path.is_dir)
        need("rigid body animation", r.scene_path, "file", Path.is_file)
    for id_ in sorted(params.weights):
        need("weight", params.weights[id_], "file", Path.is_file)
    for id_ in sorted(params.petal_weights):
        need("petal weight", params.petal_weights[id_], "file", Path.is_file)
    if missing:
        missing.sort(key=lambda m: (m[0] is None, m[0] or 0))
        raise MissingReferenceError(params.source, missing)
