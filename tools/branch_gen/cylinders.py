"""Generalized cylinders around skeleton chains (Runions sec. 3.2.3 "The geometry of branches").

Each chain of the skeleton (see :func:`inflo.tools.branch_gen.pipe.chains`) becomes one closed
tube: a ring of ``sides`` vertices at every chain node, oriented by a parallel-transport frame
(rotation-minimizing, computed by the double-reflection method of Wang et al. 2008, so the
cross-sections do not twist), joined by quads split into two triangles, and closed by a fan cap at
each end whose centre vertex is the chain's end node itself: the distal cap of a terminal branch
has its apex exactly at the floret attachment point. Ring radii taper along each chain from its
pipe-model radius to that of its thickest continuation (:func:`chain_radii`). The tangent at a node is the bisector of the
two segments meeting there; at the basal end of a chain that grows from a branch point the
incoming segment of the parent branch is used as well, and at its distal end the first segment of
its thickest continuation, so a chain's last ring and its continuation's first ring coincide in
centre, plane and radius: joints are smooth along every axis.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from inflo.tools.common import linalg as la

__all__ = ["generalized_cylinders", "parallel_transport", "chain_radii"]


@njit(cache=True)
def _unit(v):
    n = np.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if n < 1e-300:
        return v * 0.0, 0.0
    return v / n, n


@njit(cache=True)
def _tangents(x, prev, has_prev, nxt, has_next):
    k = x.shape[0]
    t = np.zeros((k, 3))
    seg = np.zeros((k - 1, 3))
    last = np.zeros(3)
    for j in range(k - 1):
        u, n = _unit(x[j + 1] - x[j])
        if n > 0:
            last = u
        seg[j] = last
    # fill leading zero-length segments with the first real direction
    first = np.zeros(3)
    for j in range(k - 1):
        if seg[j, 0] != 0.0 or seg[j, 1] != 0.0 or seg[j, 2] != 0.0:
            first = seg[j].copy()
            break
    if first[0] == 0.0 and first[1] == 0.0 and first[2] == 0.0:
        first[1] = 1.0
    for j in range(k - 1):
        if seg[j, 0] == 0.0 and seg[j, 1] == 0.0 and seg[j, 2] == 0.0:
            seg[j] = first
        else:
            break
    for j in range(k):
        if j == 0:
            d = seg[0].copy()
            if has_prev:
                u, n = _unit(x[0] - prev)
                if n > 0:
                    d = d + u
        elif j == k - 1:
            d = seg[k - 2].copy()
            if has_next:
                u, n = _unit(nxt - x[k - 1])
                if n > 0:
                    d = d + u
        else:
            d = seg[j - 1] + seg[j]
        u, n = _unit(d)
        if n == 0.0:
            u = seg[min(j, k - 2)].copy()
        t[j] = u
    return t


@njit(cache=True)
def _transport(x, t, start):
    """Rotation-minimizing normals by double reflection (Wang, Juttler, Zheng, Liu 2008).

    The first normal is ``start`` projected off ``t[0]`` (the frame the parent branch ends with),
    or, when that is degenerate, the world axis least aligned with ``t[0]``.
    """
    k = x.shape[0]
    r = np.zeros((k, 3))
    t0 = t[0]
    r0, nr = _unit(start - (start[0] * t0[0] + start[1] * t0[1] + start[2] * t0[2]) * t0)
    if nr < 1e-6:
        a = np.abs(t0)
        e = np.zeros(3)
        if a[0] <= a[1] and a[0] <= a[2]:
            e[0] = 1.0
        elif a[1] <= a[2]:
            e[1] = 1.0
        else:
            e[2] = 1.0
        r0, _ = _unit(e - (e[0] * t0[0] + e[1] * t0[1] + e[2] * t0[2]) * t0)
    r[0] = r0
    for i in range(k - 1):
        v1 = x[i + 1] - x[i]
        c1 = v1[0] * v1[0] + v1[1] * v1[1] + v1[2] * v1[2]
        if c1 < 1e-300:
            rl = r[i].copy()
            tl = t[i].copy()
        else:
            rl = r[i] - (2.0 / c1) * (v1[0] * r[i][0] + v1[1] * r[i][1] + v1[2] * r[i][2]) * v1
            tl = t[i] - (2.0 / c1) * (v1[0] * t[i][0] + v1[1] * t[i][1] + v1[2] * t[i][2]) * v1
        v2 = t[i + 1] - tl
        c2 = v2[0] * v2[0] + v2[1] * v2[1] + v2[2] * v2[2]
        if c2 < 1e-300:
            rn = rl
        else:
            rn = rl - (2.0 / c2) * (v2[0] * rl[0] + v2[1] * rl[1] + v2[2] * rl[2]) * v2
        # remove round-off drift off the normal plane
        tt = t[i + 1]
        rn = rn - (rn[0] * tt[0] + rn[1] * tt[1] + rn[2] * tt[2]) * tt
        u, n = _unit(rn)
        r[i + 1] = u if n > 0 else r[i]
    return r


def parallel_transport(points, prev=None):
    """Tangents and rotation-minimizing normals along a polyline.

    Parameters
    ----------
    points : (k, 3) float64, k >= 2
    prev : (3,) float64 or None
        The node before ``points[0]`` (the parent branch), used for the first tangent.

    Returns
    -------
    tangents, normals : (k, 3) float64 unit vectors, normals perpendicular to tangents.
    """
    x = np.ascontiguousarray(points, dtype=np.float64)
    has = prev is not None
    pv = np.zeros(3) if prev is None else np.asarray(prev, dtype=np.float64)
    t = _tangents(x, pv, has, np.zeros(3), False)
    return t, _transport(x, t, np.zeros(3))


@njit(cache=True)
def _build(pos, radius_at, idx, off, prev, nxt, sides, caps):
    m = off.shape[0] - 1
    nv = 0
    nf = 0
    for c in range(m):
        k = off[c + 1] - off[c]
        nv += k * sides + (2 if caps else 0)
        nf += (k - 1) * 2 * sides + (2 * sides if caps else 0)
    verts = np.zeros((nv, 3))
    normals = np.zeros((nv, 3))
    faces = np.zeros((nf, 3), np.int32)
    chain_vstart = np.zeros(m + 1, np.int64)
    end_normal = np.zeros(pos.shape)  # last normal of the chain ending at each node
    cosv = np.cos(2.0 * np.pi * np.arange(sides) / sides)
    sinv = np.sin(2.0 * np.pi * np.arange(sides) / sides)
    v0 = 0
    f0 = 0
    for c in range(m):
        a, b = off[c], off[c + 1]
        k = b - a
        x = np.empty((k, 3))
        for j in range(k):
            x[j] = pos[idx[a + j]]
        has_prev = prev[c] >= 0
        pv = pos[prev[c]] if has_prev else np.zeros(3)
        has_next = nxt[c] >= 0
        nv_ = pos[nxt[c]] if has_next else np.zeros(3)
        t = _tangents(x, pv, has_prev, nv_, has_next)
        r = _transport(x, t, end_normal[idx[a]])
        end_normal[idx[b - 1]] = r[k - 1]
        chain_vstart[c] = v0
        for j in range(k):
            bn = np.cross(t[j], r[j])
            rad = radius_at[a + j]
            for s in range(sides):
                radial = cosv[s] * r[j] + sinv[s] * bn
                verts[v0 + j * sides + s] = x[j] + rad * radial
                normals[v0 + j * sides + s] = radial
        for j in range(k - 1):
            for s in range(sides):
                s1 = (s + 1) % sides
                p00 = v0 + j * sides + s
                p01 = v0 + j * sides + s1
                p10 = v0 + (j + 1) * sides + s
                p11 = v0 + (j + 1) * sides + s1
                faces[f0, 0] = p00
                faces[f0, 1] = p01
                faces[f0, 2] = p11
                faces[f0 + 1, 0] = p00
                faces[f0 + 1, 1] = p11
                faces[f0 + 1, 2] = p10
                f0 += 2
        if caps:
            cb = v0 + k * sides
            ct = cb + 1
            verts[cb] = x[0]
            verts[ct] = x[k - 1]
            normals[cb] = -t[0]
            normals[ct] = t[k - 1]
            last = v0 + (k - 1) * sides
            for s in range(sides):
                s1 = (s + 1) % sides
                faces[f0, 0] = cb
                faces[f0, 1] = v0 + s1
                faces[f0, 2] = v0 + s
                faces[f0 + 1, 0] = ct
                faces[f0 + 1, 1] = last + s
                faces[f0 + 1, 2] = last + s1
                f0 += 2
            v0 += k * sides + 2
        else:
            v0 += k * sides
    chain_vstart[m] = v0
    return verts, faces, chain_vstart, normals


def chain_radii(chain_list, node_radius, node_pos=None, node_parent=None):
    """Ring radius at each chain node.

    The chain's own pipe-model radius is ``node_radius[c_1]`` (every edge of a chain ``c_0 .. c_k``
    carries the same pipes). With ``node_pos`` and ``node_parent`` the rings taper linearly in arc
    length from that radius at ``c_0`` to the radius of the thickest branch continuing from
    ``c_k`` (the chain's own radius at a tip), so the tubes are continuous through joints along
    each axis; without them every ring takes the chain's own radius.

    Returns
    -------
    list of (k,) float64
    """
    radius = np.asarray(node_radius, dtype=np.float64)
    cont = None
    if node_parent is not None:
        parent = np.asarray(node_parent, dtype=np.int64)
        cont = np.zeros(len(radius))
        has = parent >= 0
        np.maximum.at(cont, parent[has], radius[has])
    out = []
    for ch in chain_list:
        r0 = radius[ch[1]]
        r1 = cont[ch[-1]] if cont is not None and cont[ch[-1]] > 0 else r0
        if r1 == r0 or node_pos is None:
            out.append(np.full(len(ch), r0))
            continue
        seg = la.norm(np.diff(np.asarray(node_pos)[ch], axis=0), axis=1)
        s = np.concatenate([[0.0], np.cumsum(seg)])
        frac = s / s[-1] if s[-1] > 0 else np.linspace(0.0, 1.0, len(ch))
        out.append(r0 + (r1 - r0) * frac)
    return out


def generalized_cylinders(node_pos, node_parent, chain_list, node_radius, *, sides: int = 8,
                          caps: bool = True):
    """One closed tube per chain (see module docstring).

    Parameters
    ----------
    node_pos : (n, 3) float64
    node_parent : (n,) int64
    chain_list : list of (k,) int64
        Chains from :func:`inflo.tools.branch_gen.pipe.chains` (basal end first).
    node_radius : (n,) float64
        Pipe-model radii (radius of the edge basal of each node); rings taper along each chain
        as in :func:`chain_radii`.
    sides : int
    caps : bool

    Returns
    -------
    vertices : (V, 3) float64
    faces : (F, 3) int32, outward (counter-clockwise seen from outside)
    chain_vstart : (len(chain_list) + 1,) int64
        Vertices of chain c are ``chain_vstart[c]:chain_vstart[c+1]``; with caps the last two are
        the basal and distal cap centres.
    normals : (V, 3) float64
        Unit vertex normals: radial on the rings (smooth shading of the exact tube, so joints
        between the tubes of one axis do not show), along the axis at the cap centres.
    """
    pos = np.ascontiguousarray(node_pos, dtype=np.float64)
    parent = np.asarray(node_parent, dtype=np.int64)
    if not chain_list:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int32), np.zeros(1, np.int64), np.zeros((0, 3))
    lengths = np.array([len(c) for c in chain_list], dtype=np.int64)
    off = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
    idx = np.concatenate(chain_list).astype(np.int64)
    radius_at = np.concatenate(chain_radii(chain_list, node_radius, pos, parent))
    prev = np.array([parent[c[0]] for c in chain_list], dtype=np.int64)
    # the thickest branch continuing from each node: the next chain's first segment, so the last
    # ring of a chain and the first ring of its continuation share centre, tangent and radius
    radius = np.asarray(node_radius, dtype=np.float64)
    best = np.full(len(pos), -1, np.int64)
    best_r = np.full(len(pos), -np.inf)
    for v in np.argsort(-radius, kind="stable")[::-1]:
        q = parent[v]
        if q >= 0 and radius[v] >= best_r[q]:
            best_r[q] = radius[v]
            best[q] = v
    nxt = np.array([best[c[-1]] for c in chain_list], dtype=np.int64)
    return _build(pos, radius_at, idx, off, prev, nxt, int(sides), bool(caps))
