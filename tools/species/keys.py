"""Builders of floret key poses shared by the species' make_keys.py scripts: control-point nets of
whorls, cylinders and blades, and the organ block of the .floret format (formats/floret.md), so a
species' script holds only its own geometry (``from inflo.tools.species.keys import organ``);
numbers are written with 4 decimals, so the committed key poses are reproducible.
"""
from __future__ import annotations

import numpy as np

from inflo.tools.common import linalg as la


def fmt_rows(pts):
    return "\n".join("  " + "   ".join(f"{x:.4f} {y:.4f} {z:.4f}" for x, y, z in row) for row in pts)


def ring_net(r, y, half, nu=3):
    """Half petal of a five-fold whorl, ``nu`` columns: row j is an arc of radius r[j] at height y[j]."""
    nv = len(r)
    pts = np.zeros((nv, nu, 3))
    for j in range(nv):
        a = np.radians(np.linspace(0.0, half[j], nu))
        pts[j, :, 0] = r[j] * np.cos(a)
        pts[j, :, 1] = y[j]
        pts[j, :, 2] = r[j] * np.sin(a)
    return pts


def cylinder_net(radius, bottom, top):
    """Half petal of a five-fold closed cylinder (fused along its whole height), 2 x 3 points."""
    a = np.radians([0.0, 36.0])
    pts = np.zeros((3, 2, 3))
    for j, y in enumerate(np.linspace(bottom, top, 3)):
        pts[j, :, 0] = radius * np.cos(a)
        pts[j, :, 1] = y
        pts[j, :, 2] = radius * np.sin(a)
    return pts


def blade_net(p, nu, nv, u, recess=None, base_r=None):
    """Half blade along a midrib in the x-y plane: column i at u_i of the row's half width, cupped."""
    mid = np.array(p["mid"], float)
    pts = np.zeros((nv, nu, 3))
    for j in range(nv):
        a = mid[min(j + 1, nv - 1)] - mid[max(j - 1, 0)]
        t = a / la.norm(a)
        n = np.array([-t[1], t[0]])
        w = p["half"][j]
        if j == 0 and base_r is not None:
            th = u * w / base_r
            pts[0, :, 0] = mid[0, 0] - base_r * (1.0 - np.cos(th))
            pts[0, :, 1] = mid[0, 1]
            pts[0, :, 2] = base_r * np.sin(th)
            continue
        for i, ui in enumerate(u):
            back = recess[i] * w if (recess is not None and j == nv - 1) else 0.0
            lift = p["cup"] * w * ui * ui * 0.5
            xy = mid[j] - back * t + lift * n
            pts[j, i] = (xy[0], xy[1], ui * w)
    return pts


def organ(name, material, degree, grid, symmetry, fused, res, pts, bilateral=True):
    lam, eta = res
    return (f"organ: {name}\nmaterial: {material}\ndegree: {degree}\ngrid: {grid}\nsymmetry: {symmetry}\n"
            f"bilateral: {'on' if bilateral else 'off'}\nfused: {fused}\nlambda: {lam}\neta: {eta}\n"
            f"points:\n{fmt_rows(pts)}\n")
