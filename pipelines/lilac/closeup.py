"""A close-up of the lilac panicle (the `pictures` stage): the florets and branches round the
transition from open florets to buds, seen from the hero still's camera (thesis fig. 4.10 in
detail: calyces, hooded lobes, four-angled buds, florets pressed against each other).

Usage: python closeup.py BUILD_DIR WxH OUT.png   (BUILD_DIR = build/lilac)

Takes the last frame of ``canopy/`` and ``thyrse/branches.obj``, picks the floret on the side
facing the camera (azimuth AZIMUTH, elevation ELEVATION, as the Makefile's hero still) nearest to
HEIGHT of the florets' height range (where open florets meet buds, :func:`centre`), keeps the
florets within RADIUS main-axis lengths of it (whole) and the branch triangles there, and renders them with canopy-render from the same
direction.
"""
from __future__ import annotations

import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from inflo.formats.obj import ObjMesh, list_obj_sequence, read_obj, write_obj
from inflo.formats.scn import read_scn

HERE = Path(__file__).resolve().parent
#: the camera of the hero still (Makefile: --azimuth 20 --elevation 12)
AZIMUTH, ELEVATION = 20.0, 12.0
#: where on the panicle (fraction of the florets' height range) and how much of it (main-axis lengths)
HEIGHT, RADIUS = 0.62, 0.2


def view_direction(azimuth: float = AZIMUTH, elevation: float = ELEVATION) -> np.ndarray:
    """Unit vector from the panicle towards canopy-render's camera (azimuth about +Y from +Z)."""
    a, e = math.radians(azimuth), math.radians(elevation)
    return np.array([math.sin(a) * math.cos(e), math.sin(e), math.cos(a) * math.cos(e)])


def centre(pos: np.ndarray, view: np.ndarray, height: float = HEIGHT) -> np.ndarray:
    """The floret position at the front of the panicle at ``height`` of the florets' height range:
    the one that lies farthest towards the camera less its distance from that height (the front
    of the panicle there)."""
    y = pos[:, 1]
    target = y.min() + height * (y.max() - y.min())
    return pos[int(np.argmax(pos @ view - np.abs(y - target)))]


def cut(mesh: ObjMesh, c: np.ndarray, radius: float, pos: np.ndarray | None = None) -> ObjMesh:
    """The triangles of ``mesh`` whose centroid lies within ``radius`` of ``c``, materials kept;
    with ``pos`` (the placements' positions), whole florets (groups ``floret_<k>``): those whose
    position lies within ``radius``."""
    if pos is None:
        keep = np.linalg.norm(mesh.vertices[mesh.faces].mean(axis=1) - c, axis=1) < radius
    else:
        ids = np.array([int(g.split("_")[1]) if g.startswith("floret_") else -1 for g in mesh.groups])
        near = np.linalg.norm(pos - c, axis=1) < radius
        of = ids[mesh.face_group]
        keep = (of >= 0) & near[np.maximum(of, 0)]
    used = np.unique(mesh.faces[keep])
    remap = np.full(len(mesh.vertices), -1, np.int64)
    remap[used] = np.arange(len(used))
    fm = None if mesh.face_material is None else mesh.face_material[keep]
    return ObjMesh(vertices=mesh.vertices[used], faces=remap[mesh.faces[keep]], materials=list(mesh.materials),
                   face_material=fm)


def main(build: Path, size: str, out: Path) -> int:
    render = Path(sys.executable).parent / "canopy-render"
    scene = read_scn(build / "thyrse" / "scene.scn")
    canopy = read_obj(list_obj_sequence(build / "canopy")[-1])
    branches = read_obj(build / "thyrse" / "branches.obj")
    view = view_direction()
    pos = scene.arrays()["pos"]
    florets = np.array([p.type != "obstacle" for p in scene.placements])
    c = centre(pos[florets], view)
    length = float(np.ptp(branches.vertices[:, 1]))
    with tempfile.TemporaryDirectory() as tmp:
        a, b = Path(tmp) / "florets.obj", Path(tmp) / "branches.obj"
        write_obj(a, cut(canopy, c, RADIUS * length, pos))
        write_obj(b, cut(branches, c, RADIUS * length))
        subprocess.run([str(render), "-q", "--background", "0.20,0.26,0.18", "--colors", str(HERE / "colors.toml"),
                        str(b), str(a), "--color", "0.40,0.52,0.26", "--azimuth", f"{AZIMUTH:g}",
                        "--elevation", f"{ELEVATION:g}", "--size", size, "-o", str(out)], check=True)
    print(f"{out}: the panicle within {RADIUS:g} of its length round ({c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f})")
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 4:
        print(__doc__.strip().splitlines()[5], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1]), sys.argv[2], Path(sys.argv[3])))
