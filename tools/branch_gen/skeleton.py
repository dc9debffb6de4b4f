"""The skeleton a branch-gen algorithm produces, and the growth of space (thesis 7.2 "Growth")."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Skeleton", "growth_scale"]


@dataclass
class Skeleton:
    """A forest of tree nodes (see :mod:`inflo.tools.branch_gen.pipe` for the conventions).

    Attributes
    ----------
    node_pos : (n, 3) float64
        Final positions (at the end of growth).
    node_parent : (n,) int64
        Basal neighbour, -1 at a root (the inflorescence base, or an SCA root node).
    node_tip : (n,) bool
        Node carries a floret; its position is exactly the floret's.
    node_floret : (n,) int64
        Scene placement index of the floret at a tip node, -1 elsewhere.
    node_frame : (n,) float64
        Frame at which the node was created (tips: the floret's emergence).
    node_link_frame : (n,) float64
        Frame at which the edge to the parent was created (inf for roots).
    node_branch : (n,) int64
        The particle (Rodkaew) that created the node, -1 for roots and SCA nodes.
    base : (3,) float64
        Centre of the growth of space.
    """

    node_pos: np.ndarray
    node_parent: np.ndarray
    node_tip: np.ndarray
    node_floret: np.ndarray
    node_frame: np.ndarray
    node_link_frame: np.ndarray
    node_branch: np.ndarray
    base: np.ndarray

    @property
    def n_nodes(self) -> int:
        return len(self.node_pos)


def growth_scale(mode: str, rate: float, rates, frame: float, end_frame: float, functions=None) -> np.ndarray:
    """Per-axis scale S(f) / S(end) of space at frame ``f`` relative to the end of growth.

    ``S(f) = (1 + rate)^min(f, end)`` per axis: ``uniform`` uses ``rate`` on every axis,
    ``allometric`` the per-axis ``rates`` (thesis 7.2 "Growth": expansion at different rates along
    different axes changes branching angles and proportions over time), ``functions`` three
    graphically-defined scale functions S_i(x) of x = min(f, end) / end (``.func``, callables),
    ``none`` is 1.

    Returns
    -------
    (3,) float64
    """
    if mode == "none":
        return np.ones(3)
    if mode == "functions":
        x = min(max(float(frame) / float(end_frame), 0.0), 1.0) if end_frame > 0 else 1.0
        return np.array([float(fn(x)) / float(fn(1.0)) for fn in functions])
    r = np.full(3, float(rate)) if mode == "uniform" else np.asarray(rates, dtype=np.float64)
    f = min(float(frame), float(end_frame))
    return (1.0 + r) ** (f - float(end_frame))
