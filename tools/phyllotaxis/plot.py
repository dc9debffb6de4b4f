"""Top-view pictures of floret patterns: florets as discs of their real size (matplotlib, Agg).

Used for the documentation figures (docs/phyllotaxis_*.png, docs/dimorph_*.png) and by
``phyllotaxis --png``. The view looks down the -Y axis onto the (x, z) plane.
"""
from __future__ import annotations

import numpy as np

__all__ = ["plot_discs", "plot_panels", "discs_mesh"]


def _draw(ax, pos, diameter, values=None, colors=None, cmap="RdYlGn_r", title=None, edge=False, lim=None):
    from matplotlib.collections import EllipseCollection

    pos = np.asarray(pos, dtype=np.float64).reshape(-1, 3)
    d = np.asarray(diameter, dtype=np.float64).reshape(-1)
    xy = pos[:, [0, 2]]
    kw = {}
    if colors is not None:
        kw["facecolors"] = colors
    coll = EllipseCollection(d, d, np.zeros_like(d), units="xy", offsets=xy, offset_transform=ax.transData,
                             edgecolors="k" if edge else "none", linewidths=0.3, **kw)
    if colors is None and values is not None:
        coll.set_array(np.asarray(values, dtype=np.float64))
        coll.set_cmap(cmap)
    ax.add_collection(coll)
    if lim is not None:
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
    elif len(xy):
        pad = float(d.max()) if len(d) else 0.0
        ax.set_xlim(xy[:, 0].min() - pad, xy[:, 0].max() + pad)
        ax.set_ylim(xy[:, 1].min() - pad, xy[:, 1].max() + pad)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    if title:
        ax.set_title(title, fontsize=9)


def plot_panels(path, panels, *, ncols: int | None = None, size: float = 3.2, suptitle: str | None = None) -> None:
    """Save a row (or grid) of top views.

    Parameters
    ----------
    panels : list of dict
        Each with ``pos (n, 3)``, ``diameter (n,)`` and either ``values (n,)`` (coloured by the
        colour map ``cmap``; green = young, red = old as in fig. 5.2 with the default map and
        age values) or ``colors`` (a list of matplotlib colours), optional ``title``, ``edge``,
        ``lim`` (a square view ``[-lim, lim]``, to compare stages at one scale).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(panels)
    ncols = ncols or n
    nrows = (n + ncols - 1) // ncols
    fig, axes = plt.subplots(nrows, ncols, figsize=(size * ncols, size * nrows), squeeze=False)
    for ax in axes.flat[n:]:
        ax.axis("off")
    for ax, p in zip(axes.flat, panels):
        _draw(ax, p["pos"], p["diameter"], p.get("values"), p.get("colors"), p.get("cmap", "RdYlGn_r"),
              p.get("title"), p.get("edge", False), p.get("lim"))
    if suptitle:
        fig.suptitle(suptitle, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_discs(path, pos, diameter, values=None, *, colors=None, title=None, cmap="RdYlGn_r") -> None:
    """One top view (see :func:`plot_panels`)."""
    plot_panels(path, [{"pos": pos, "diameter": diameter, "values": values, "colors": colors,
                        "title": title, "cmap": cmap}], size=5.0)


def discs_mesh(scene, sides: int = 12):
    """An :class:`~inflo.formats.obj.ObjMesh` of a disc of unit diameter per placement.

    Each disc lies in its floret's local XZ plane (normal = local +Y = ``up``) with a small petal
    along local +X (``right``), so a rendering shows both axes of every placement frame. Faces use
    material ``mtl1`` for ``#@ type: ray``, ``mtl2`` for ``small_ray``, ``mtl0`` otherwise, so
    ``canopy-render`` colours them by type.
    """
    from inflo.formats.obj import ObjMesh

    arr = scene.arrays()
    n = len(scene)
    ang = np.linspace(0.0, 2.0 * np.pi, sides, endpoint=False)
    local = np.vstack([[0.0, 0.02, 0.0], np.c_[0.5 * np.cos(ang), np.full(sides, 0.02), 0.5 * np.sin(ang)],
                       [[0.9, 0.02, 0.0], [0.5, 0.02, 0.12], [0.5, 0.02, -0.12]]])
    tris = np.array([[0, 1 + i, 1 + (i + 1) % sides] for i in range(sides)] + [[sides + 1, sides + 2, sides + 3]])
    up = arr["up"] / np.linalg.norm(arr["up"], axis=1, keepdims=True)
    r = arr["right"] - np.sum(arr["right"] * up, axis=1, keepdims=True) * up
    r /= np.linalg.norm(r, axis=1, keepdims=True)
    z = np.cross(r, up)
    sc = arr["scale"]
    verts = (arr["pos"][:, None, :] + local[None, :, 0:1] * sc[:, None, 0:1] * r[:, None, :]
             + local[None, :, 1:2] * sc[:, None, 1:2] * up[:, None, :]
             + local[None, :, 2:3] * sc[:, None, 2:3] * z[:, None, :])
    faces = (tris[None, :, :] + len(local) * np.arange(n)[:, None, None]).reshape(-1, 3)
    kind = np.array([{"ray": 1, "small_ray": 2}.get(p.type, 0) for p in scene.placements], dtype=np.int32)
    return ObjMesh(verts.reshape(-1, 3), faces, materials=["mtl0", "mtl1", "mtl2"],
                   face_material=np.repeat(kind, len(tris)))
