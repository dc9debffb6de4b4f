"""branch-gen as library functions: scene in, skeleton and generalized cylinders out.

:func:`branch_gen` runs the chosen algorithm (extended Rodkaew, thesis ch. 7; or space
colonization, Runions ch. 3), post-processes the skeleton, computes pipe-model radii and builds
the generalized cylinders; :func:`write_branch_gen` writes the files (atomically, fixed number
formats):

- ``skeleton.obj``: one ``v`` per skeleton node, one ``l`` polyline per chain (basal end first);
- ``skeleton.radii``: one radius per ``v`` line of ``skeleton.obj`` (``formats/branch_gen.md``);
- ``branches.obj``: the generalized cylinders, one closed tube per chain, one ``g`` group each;
- with RBA frames: ``frames/branches_NNNN.obj`` per canopy frame (thesis 8 g, beyond the thesis).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from inflo.formats.atomic import atomic_write, frame_name
from inflo.formats.errors import InputError
from inflo.formats.obj import ObjMesh, write_obj
from inflo.tools.common import linalg as la

from .cylinders import generalized_cylinders
from .envelope import envelope_from_params
from .params import Params, check_file, key_error
from .pipe import chains, decimate, pipe_radii, relocate, subdivide
from .rodkaew import RodkaewInput, _end_frame, grow_rodkaew
from .sca import grow_sca
from .skeleton import Skeleton, growth_scale

__all__ = ["BranchResult", "FrameMesh", "branch_gen", "rodkaew_input", "skeleton_geometry", "write_branch_gen",
           "RADII_FMT"]

RADII_FMT = "%.8f"


@dataclass
class FrameMesh:
    frame: int
    mesh: ObjMesh


@dataclass
class BranchResult:
    """Everything branch-gen writes.

    Attributes
    ----------
    skeleton : Skeleton
        The raw skeleton of the algorithm.
    node_pos, node_parent, node_tip : arrays
        The post-processed skeleton that is written.
    node_radius : (n,) float64
        Pipe-model radii of the written skeleton.
    chain_list : list of (k,) int64
    skeleton_mesh, branches_mesh : ObjMesh
    frames : list of FrameMesh
    """

    skeleton: Skeleton
    node_pos: np.ndarray
    node_parent: np.ndarray
    node_tip: np.ndarray
    node_radius: np.ndarray
    chain_list: list
    skeleton_mesh: ObjMesh
    branches_mesh: ObjMesh
    frames: list = field(default_factory=list)
    header: str = ""


def rodkaew_input(scene, rba_frames=None) -> RodkaewInput:
    """Florets of a scene (and their first RBA appearance) as :class:`RodkaewInput`.

    Raises
    ------
    InputError
        An empty scene.
    """
    if len(scene) == 0:
        raise InputError("the scene has no florets (no placements): nothing to support")
    a = scene.arrays()
    groups = {g.id: (g.centre, g.parent) for g in scene.groups.values()}
    emergence = a["emergence"]
    birth_pos = None
    if rba_frames:
        n = len(scene)
        first = np.full(n, -1, np.int64)
        birth_pos = a["pos"].copy()
        for f, fr in enumerate(rba_frames):
            ids = np.asarray(fr.ids, dtype=np.int64)
            ok = (ids >= 0) & (ids < n)
            new = ok.copy()
            new[ok] = first[ids[ok]] < 0
            first[ids[new]] = f
            birth_pos[ids[new]] = fr.pos[new]
        missing = first < 0
        emergence = np.where(missing, np.nan_to_num(emergence, nan=float(len(rba_frames) - 1)), first)
    return RodkaewInput(pos=a["pos"], up=a["up"], emergence=emergence, group=a["group"], groups=groups,
                        birth_pos=birth_pos)


def _wb_table(params: Params):
    if not params.rodkaew.w_b_func:
        return None
    from inflo.formats.func import read_func

    fn = read_func(check_file(params, "rodkaew", "w_b_func", params.rodkaew.w_b_func))
    _, ys = fn.sampled()
    ys = np.asarray(ys, dtype=np.float64)
    if not np.all(np.isfinite(ys)) or np.any(ys < 0):
        raise InputError(f"{params.rodkaew.w_b_func}: w_b(d) must be finite and >= 0")
    return ys


def _load_growth_functions(params: Params) -> None:
    gp = params.growth
    if gp.mode != "functions" or gp._functions is not None:
        return
    from inflo.formats.func import read_func

    fns = []
    for name in gp.funcs:
        fn = read_func(check_file(params, "growth", "funcs", name))
        _, ys = fn.sampled()
        if not np.all(np.asarray(ys) > 0):
            raise InputError(f"{name}: a growth scale function must be > 0 everywhere")
        fns.append(fn)
    gp._functions = fns


def skeleton_geometry(node_pos, node_parent, node_tip, params: Params, *, name: str = "branch"):
    """Pipe radii, chains, the skeleton polylines and the generalized cylinders of a skeleton.

    Returns
    -------
    node_radius (n,), chain_list, skeleton ObjMesh, branches ObjMesh
    """
    radius = pipe_radii(node_parent, node_tip, 0.5 * params.pipe.tip_diameter, params.pipe.exponent)
    chain_list = chains(node_parent, node_tip)
    skel = ObjMesh(vertices=node_pos, lines=chain_list)
    verts, faces, vstart, normals = generalized_cylinders(node_pos, node_parent, chain_list, radius,
                                                 sides=params.cylinder.sides, caps=params.cylinder.caps)
    fstart = np.cumsum([0] + [(len(c) - 1) * 2 * params.cylinder.sides
                              + (2 * params.cylinder.sides if params.cylinder.caps else 0) for c in chain_list])
    face_group = np.zeros(len(faces), np.int32)
    for c in range(len(chain_list)):
        face_group[fstart[c]:fstart[c + 1]] = c
    groups = [f"{name}_{c}" for c in range(len(chain_list))]
    mesh = ObjMesh(vertices=verts, faces=faces, normals=normals if len(verts) else None, groups=groups,
                   face_group=face_group if len(groups) else None)
    return radius, chain_list, skel, mesh


def _frame_meshes(sk: Skeleton, params: Params, rba_frames, end_frame: float, frame_step: int = 1) -> list:
    gp = params.growth
    out = []
    last = len(rba_frames) - 1
    for f, fr in enumerate(rba_frames):
        if f % frame_step and f != last:
            continue
        present = sk.node_frame <= f + 1e-9
        idx = np.nonzero(present)[0]
        new_index = np.full(sk.n_nodes, -1, np.int64)
        new_index[idx] = np.arange(len(idx))
        par = sk.node_parent[idx]
        linked = (par >= 0) & (sk.node_link_frame[idx] <= f + 1e-9)
        linked &= present[np.maximum(par, 0)]
        parent = np.where(linked, new_index[np.maximum(par, 0)], -1)
        scale = growth_scale(gp.mode, gp.rate, gp.rates, f, end_frame, gp._functions)
        pos = sk.base + (sk.node_pos[idx] - sk.base) * scale
        tip = sk.node_tip[idx]
        # floret tips follow the canopy: their position in this frame
        fl = sk.node_floret[idx]
        row = {int(i): r for r, i in enumerate(np.asarray(fr.ids).tolist())}
        for j in np.nonzero(tip)[0]:
            r = row.get(int(fl[j]))
            if r is not None:
                pos[j] = fr.pos[r]
        if len(idx) == 0:
            out.append(FrameMesh(f, ObjMesh(vertices=np.zeros((0, 3)))))
            continue
        _, _, _, mesh = skeleton_geometry(pos, parent, tip, params)
        out.append(FrameMesh(f, mesh))
    return out


#: Floret coordinates beyond this are refused (as floret-animate and canopy-render refuse theirs).
COORD_LIMIT = 1e12


def check_rodkaew_work(inp: RodkaewInput, params: Params, n_frames: int | None = None) -> None:
    """Refuse, before any work, a run that could not finish (``step = 1e-9`` or a floret
    at 1e300 hung): floret or group coordinates beyond :data:`COORD_LIMIT`, and a ``step`` so short
    that the farthest floret is more than ``max_steps`` steps from the base (each particle moves one
    ``step`` per simulation step, eq. 7.1, so that is a lower bound of the steps the run needs).

    Raises
    ------
    InputError
        Naming the parameter, the bound and the value found.
    """
    pts = [np.asarray(inp.pos, float).reshape(-1, 3)]
    if inp.birth_pos is not None:
        pts.append(np.asarray(inp.birth_pos, float).reshape(-1, 3))
    pts += [np.asarray(c, float).reshape(1, 3) for c, _ in inp.groups.values()]
    pts = np.concatenate(pts)
    big = ~np.isfinite(pts).all(axis=1) | (np.abs(pts) >= COORD_LIMIT).any(axis=1)
    if big.any():
        raise InputError(f"the scene: expected floret and group positions within +-{COORD_LIMIT:g}, found "
                         f"{' '.join(f'{c:g}' for c in pts[int(np.argmax(big))])}")
    rp = params.rodkaew
    reach = float(la.norm(pts - np.asarray(params.base, float), axis=1).max())
    if reach / rp.step > rp.max_steps:
        raise key_error(params, "rodkaew", "step", f"a step >= {reach / rp.max_steps:.3g} (the farthest floret is "
                        f"{reach:.4g} from the base, at most max_steps = {rp.max_steps} steps of it)", f"{rp.step:g}")
    last = float(np.nan_to_num(np.asarray(inp.emergence, float), nan=0.0).max())
    if not last * rp.steps_per_frame < rp.max_steps:
        raise key_error(params, "rodkaew", "steps_per_frame", f"every floret born before max_steps = {rp.max_steps} "
                        f"(the last emerges at frame {last:g}, step {last * rp.steps_per_frame:g})",
                        f"{rp.steps_per_frame}")
    check_growth(params, _end_frame(inp, params, n_frames), reach)


def check_growth(params: Params, end_frame: float, reach: float) -> None:
    """Refuse, before any work, a growth of space whose scale over the run leaves floating point
    range or the coordinate limit: ``S(end) / S(0)`` and its inverse at most :data:`MAX_GROWTH` per
    axis (``(1 + rate)^frames``: a rate of 1e308, or 0.5 over 1e12 frames, scaled every branch to
    0/0), the last frame of growth at most :data:`MAX_FRAMES`, and the florets' reach times that
    scale within :data:`COORD_LIMIT`."""
    from .params import MAX_FRAMES, MAX_GROWTH

    gp = params.growth
    if gp.mode == "none":
        return
    if not end_frame <= MAX_FRAMES:
        raise key_error(params, "growth", "frames", f"growth that ends by frame {MAX_FRAMES} (the last emergence "
                        f"or RBA frame when -1)", f"{end_frame:g}")
    if gp.mode == "functions":
        ys = np.concatenate([np.asarray(fn.sampled()[1], float) for fn in gp._functions])
        factor = float(ys.max() / ys.min())
        key = "funcs"
    else:
        rates = [gp.rate] if gp.mode == "uniform" else list(gp.rates)
        logs = max(abs(math.log1p(r)) for r in rates) * max(end_frame, 0.0)
        factor = math.exp(min(logs, 700.0))
        key = "rate" if gp.mode == "uniform" else "rates"
    if not factor <= MAX_GROWTH or not reach * factor < COORD_LIMIT:
        raise key_error(params, "growth", key, f"a growth of space whose scale changes at most {MAX_GROWTH:g}-fold "
                        f"over the run (to frame {end_frame:g}) and keeps the florets within +-{COORD_LIMIT:g}",
                        f"{factor:.3g}-fold")


def check_sca_work(env, params: Params) -> None:
    """Refuse, before any work, a space colonization that could not finish or would be degenerate:
    an envelope beyond :data:`COORD_LIMIT`; a step D so short that the farthest corner of the
    envelope's box is more than ``max_iterations`` steps from the roots (each iteration grows a
    node by D, so that is a lower bound of the iterations the tree needs to reach it), or longer than
    that extent; a kill distance d_k at most D / 2 (a node that grows at a point lands within D / 2
    of it at best, so a point with a smaller d_k is never killed and the tree grows around it until
    memory runs out) or at least the extent (every point dies at once: no tree).

    Raises
    ------
    InputError
        Naming the parameter, the bound and the value found.
    """
    sp = params.sca
    lo, hi = (np.asarray(b, float) for b in env.bounds())
    box = np.concatenate([lo, hi])
    if not (np.isfinite(box).all() and np.abs(box).max() <= COORD_LIMIT):
        raise key_error(params, "envelope", "shape", f"an envelope within +-{COORD_LIMIT:g}",
                        f"the box {' '.join(f'{c:g}' for c in lo)} .. {' '.join(f'{c:g}' for c in hi)}")
    corners = np.array([[(lo, hi)[(k >> i) & 1][i] for i in range(3)] for k in range(8)])
    roots = np.asarray(sp.roots, float).reshape(-1, 3)
    extent = max(float(la.norm(roots - c, axis=1).max()) for c in corners)
    if extent / sp.step > sp.max_iterations:
        raise key_error(params, "sca", "step", f"a step D >= {extent / sp.max_iterations:.3g} (the envelope reaches "
                        f"{extent:.4g} from the roots, at most max_iterations = {sp.max_iterations} steps of D)",
                        f"{sp.step:g}")
    if sp.step > extent:
        raise key_error(params, "sca", "step", f"a step D <= {extent:.4g} (the envelope's extent from the roots)",
                        f"{sp.step:g}")
    if not sp.kill_distance > 0.5 * sp.step:
        raise key_error(params, "sca", "kill_distance", f"a kill distance d_k > step / 2 = {0.5 * sp.step:g} (else "
                        f"a point may never be reached)", f"{sp.kill_distance:g}")
    if sp.kill_distance >= extent:
        raise key_error(params, "sca", "kill_distance", f"a kill distance d_k < {extent:.4g} (the envelope's extent "
                        f"from the roots: else every point dies at once)", f"{sp.kill_distance:g}")


def branch_gen(scene, params: Params, *, rba_frames=None, algorithm: str | None = None, frame_step: int = 1,
               progress=None) -> BranchResult:
    """Grow the branching structure for ``scene`` (or a space-colonization tree) and its geometry.

    Parameters
    ----------
    scene : inflo.formats.scn.Scene
        The florets (ignored by ``sca``).
    params : Params
    rba_frames : list of RbaFrame or None
        Canopy frames: emergence from the first frame a floret appears in, and one branches mesh
        per frame.
    algorithm : "rodkaew", "sca" or None (the parameter file's)
    frame_step : int
        Build the branches of every ``frame_step``-th RBA frame (and the last).
    progress : callable(int) or None
    """
    algorithm = algorithm or params.algorithm
    if algorithm == "sca":
        env = envelope_from_params(params)
        check_sca_work(env, params)
        sk, res = grow_sca(params, env, progress=progress)
        head = (f"branch-gen space colonization: N {len(res.points)} D {params.sca.step:g} "
                f"d_k {params.sca.kill_distance:g} d_I {params.sca.influence_radius:g} seed {params.seed}; "
                f"{res.iterations} iterations, {sk.n_nodes} nodes")
    else:
        _load_growth_functions(params)
        inp = rodkaew_input(scene, rba_frames)
        check_rodkaew_work(inp, params, len(rba_frames) if rba_frames else None)

        sk = grow_rodkaew(inp, params, wb_table=_wb_table(params),
                          n_frames=len(rba_frames) if rba_frames else None, progress=progress)
        rp = params.rodkaew
        head = (f"branch-gen extended Rodkaew: {len(scene)} florets, step {rp.step:g} merge {rp.merge_distance:g} "
                f"w_a {rp.w_a:g} w_b {rp.w_b:g} w_h {rp.w_h:g}; {sk.n_nodes} nodes")
    pos, parent, tip = sk.node_pos, sk.node_parent, sk.node_tip
    post = params.post
    if post.decimate > 0:
        pos, parent, tip, _ = decimate(pos, parent, tip, post.decimate)
    if post.relocate:
        pos = relocate(pos, parent, tip)
    if post.subdivide:
        pos, parent, tip = subdivide(pos, parent, tip, post.subdivide)
    radius, chain_list, skel_mesh, mesh = skeleton_geometry(pos, parent, tip, params)
    frames = []
    if rba_frames and algorithm != "sca":
        end = _end_frame(inp, params, len(rba_frames))
        frames = _frame_meshes(sk, params, rba_frames, end, frame_step)
    return BranchResult(skeleton=sk, node_pos=pos, node_parent=parent, node_tip=tip, node_radius=radius,
                        chain_list=chain_list, skeleton_mesh=skel_mesh, branches_mesh=mesh, frames=frames,
                        header=head)


def format_radii(radius, header: str = "") -> str:
    lines = [f"# {h}\n" for h in header.splitlines() if h]
    lines.append("# one radius per 'v' line of skeleton.obj, in order (scene units)\n")
    fmt = RADII_FMT + "\n"
    lines.extend(fmt % r for r in np.asarray(radius, dtype=np.float64).tolist())
    return "".join(lines)


#: the files :func:`write_branch_gen` writes, as patterns relative to its folder (a rerun's own
#: earlier files where the folder has no manifest yet)
OUTPUT_FILES = (r"skeleton\.obj", r"skeleton\.radii", r"branches\.obj", r"frames/branches_\d+\.obj")


def write_branch_gen(out_dir, result: BranchResult, params: Params) -> list:
    """Write skeleton.obj, skeleton.radii, branches.obj (and frames/) into ``out_dir``.

    Returns the paths written.
    """
    from pathlib import Path

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    pp = params.pipe
    head = f"{result.header}\npipe model: tip_diameter {pp.tip_diameter:g} exponent {pp.exponent:g}"
    written = []
    write_obj(out / "skeleton.obj", result.skeleton_mesh, header=head + "\nskeleton: one l polyline per chain")
    written.append(out / "skeleton.obj")
    with atomic_write(out / "skeleton.radii") as fh:
        fh.write(format_radii(result.node_radius, head))
    written.append(out / "skeleton.radii")
    write_obj(out / "branches.obj", result.branches_mesh, header=head + "\ngeneralized cylinders, one g per chain")
    written.append(out / "branches.obj")
    for fm in result.frames:
        path = out / "frames" / frame_name(fm.frame, prefix="branches_")
        write_obj(path, fm.mesh, header=f"{result.header}\nframe {fm.frame}")
        written.append(path)
    return written
