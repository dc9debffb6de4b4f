"""The checks of the yarrow build (the `check` stage of the Makefile).

Usage: python check_yarrow.py BUILD_DIR   (BUILD_DIR = build/yarrow)

Prints, and exits 1 when any fails:

- one clock: the canopy, the branches' per-frame meshes and the heads' RBA frames have the same
  number of frames;
- intersecting triangle pairs (exact static test, inflo.tools.collide; touching counts) of every
  canopy frame (every fourth listed), of the smoothed last frame, and between the branches of
  frame k and the canopy of frame k, every frame;
- the peduncles end at their heads in every frame: each emerged head's centre (its RBA position)
  is a vertex of that frame's branch mesh (the distal cap's apex), to 1e-5;
- the edge stretch over all frames (fccompose's log) within [0.5, 1.5] x rest;
- every floret of every head present in the last frame;
- one canopy, not islands: the heads' discs in the last head RBA frame (the pattern's sizes, each
  grown into its room: corymb.toml ``fill_room``), linked where two touch within 5 %, form one
  group;
- the rays per head (dimorph over the whole corymb, fig. 6.4a): printed as a distribution; on
  average 3-7 (real heads have about 5), every head with fewer rays than disk florets (a head
  enclosed by its neighbours may have none);
- heads with a body (thresholds in species.toml [check]): the receptacles (``receptacles/``, one
  frame per canopy frame; fccompose simulates them as obstacles, the ``#@ type: obstacle``
  placements after every floret and bract of ``typed.scn``, left out here) cross no floret or
  bract in any frame; each head
  has its ``bracts`` involucral bracts; the median gap from a ray floret to the nearest disk floret
  of its head, in the ray's lengths (its farthest point from its base), at most ``ligule_gap``; the
  median distance from a floret's base to its head's receptacle, in floret sizes, at most
  ``floret_surface``;
- one closed corymb (issue 43, thresholds in species.toml [check]): the top view of the last
  canopy frame (the canopy alone, axis Y, ``view_coverage``) covers at least ``coverage`` of its
  convex hull; the heads' diameters in the last head RBA frame vary with a coefficient of variation
  of at most ``head_cv``; the stem's base (the largest branch diameter, the pipe model) is at least
  ``stem_base`` of the mean head diameter (the heads' discs);
- the stem leaves (fig. 9.9, ``leaves/``, one frame per canopy frame): ``stem_leaves`` leaves in the
  last frame, textured (``vt`` coordinates into the vein texture), crossing no branch, floret,
  bract or other leaf in any frame;
- the heads develop in order: at the frame where half the florets have started opening, the heads
  that emerged first are further open (Spearman rank correlation of the heads' emergence frame
  with the share of their florets past their window's start < -0.5).
"""
from __future__ import annotations

import sys
import tomllib
from collections import Counter
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree
from scipy.stats import spearmanr

from inflo.formats.obj import list_obj_sequence, read_obj
from inflo.formats.rba import list_rba_sequence, read_rba
from inflo.formats.scn import read_scn
from inflo.tools.collide import intersecting_pairs, intersecting_pairs_between
from inflo.tools.species.checks import BOUNDS, group_faces, view_coverage


def count(mesh) -> int:
    return len(intersecting_pairs(mesh.vertices, mesh.faces, tri_part=mesh.face_group))


def cross_pairs(a, b) -> int:
    """Intersecting triangle pairs with one triangle in ``a`` and the other in ``b``."""
    if len(a.faces) == 0 or len(b.faces) == 0:
        return 0
    return len(intersecting_pairs_between(a.vertices, a.faces, b.vertices, b.faces))


def leaf_pairs(lf, br, canopy) -> tuple[int, int, int]:
    """Intersecting pairs of one frame's stem leaves with the branches, with the canopy, and
    between two leaves."""
    if len(lf.faces) == 0:
        return 0, 0, 0
    ll = 0
    fg = np.asarray(lf.face_group)
    for a in np.unique(fg):
        for b in np.unique(fg):
            if a < b:
                fa, fb = lf.faces[fg == a], lf.faces[fg == b]
                ll += len(intersecting_pairs_between(lf.vertices, fa, lf.vertices, fb))
    return cross_pairs(lf, br), cross_pairs(lf, canopy), ll


def stretch_range(log_path: Path) -> tuple[float, float, list]:
    import csv

    with open(log_path, newline="") as fh:
        log = list(csv.DictReader(fh))
    lo = min(float(r["min_edge_stretch"]) for r in log)
    hi = max(float(r["max_edge_stretch"]) for r in log)
    out = [r["frame"] for r in log if float(r["min_edge_stretch"]) < BOUNDS[0] or float(r["max_edge_stretch"]) > BOUNDS[1]]
    return lo, hi, out


def canopy_groups(pos, diameter, slack: float = 1.05) -> int:
    """Groups of heads (centres ``pos`` (n, 2) in the canopy plane, disc diameters) linked where
    two discs touch, within ``slack``."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    n = len(pos)
    if n == 0:
        return 0
    pairs = cKDTree(pos).query_pairs(float(diameter.max()) * slack, output_type="ndarray")
    d = np.linalg.norm(pos[pairs[:, 0]] - pos[pairs[:, 1]], axis=1)
    ok = d <= 0.5 * slack * (diameter[pairs[:, 0]] + diameter[pairs[:, 1]])
    link = coo_matrix((np.ones(int(ok.sum())), (pairs[ok, 0], pairs[ok, 1])), shape=(n, n))
    return int(connected_components(link, directed=False)[0])


W = np.array([(a, b, 1.0 - a - b) for a in np.linspace(0, 1, 6) for b in np.linspace(0, 1, 6) if a + b <= 1 + 1e-9])


def floret_points(mesh, name: str, faces: dict | None = None) -> np.ndarray:
    """Points of a canopy group (its triangles sampled at 21 barycentric points each); ``faces``:
    :func:`group_faces` of ``mesh``."""
    idx = (faces or group_faces(mesh))[name]
    tri = mesh.vertices[mesh.faces[idx]]
    return np.einsum("kj,mjd->mkd", W, tri).reshape(-1, 3)


def ligule_gaps(mesh, typed, rba) -> np.ndarray:
    """Per ray floret: the gap from it to the nearest disk floret of its head over its length
    (its farthest point from its base). A floret absent from the mesh (one still waiting for room:
    the check's count of florets fails on it) is left out; a ray whose head has no disk floret
    present has no gap."""
    pts = {}
    out = []
    faces = group_faces(mesh)

    def present(i):
        return len(faces.get(f"floret_{i}", ())) > 0

    disks = {}
    for j, q in enumerate(typed.placements):
        if q.type == "disk" and present(j):
            disks.setdefault(q.group, []).append(j)
    for i, p in enumerate(typed.placements):
        if p.type != "ray" or not present(i) or not disks.get(p.group):
            continue
        base = rba.pos[rba.index(i)]
        ray = floret_points(mesh, f"floret_{i}", faces)
        disk = disks.get(p.group, [])
        for j in disk:
            if j not in pts:
                pts[j] = floret_points(mesh, f"floret_{j}", faces)
        d = cKDTree(np.vstack([pts[j] for j in disk])).query(ray)[0].min()
        out.append(d / np.linalg.norm(ray - base, axis=1).max())
    return np.array(out)


def surface_distances(receptacles, typed, rba) -> np.ndarray:
    """Per floret (not bract): its base's distance to its head's receptacle mesh (sampled) over
    the floret's size."""
    out = []
    trees = {}
    faces = group_faces(receptacles)
    for i, p in enumerate(typed.placements):
        if p.type == "bract":
            continue
        h = p.group - 1
        if h not in trees:
            trees[h] = cKDTree(floret_points(receptacles, f"receptacle_{h}", faces))
        row = rba.index(i)
        out.append(trees[h].query(rba.pos[row])[0] / rba.scale[row, 0])
    return np.array(out)


def rays_per_head(scene) -> list:
    rays = Counter(p.group for p in scene.placements if p.type == "ray")
    return [rays.get(g, 0) for g in sorted({p.group for p in scene.placements})]


def main(build: Path) -> int:
    fail = []
    with open(Path(__file__).resolve().parent / "species.toml", "rb") as fh:
        facts = tomllib.load(fh)["check"]
    canopy = list_obj_sequence(build / "canopy")
    branches = sorted((build / "branches" / "frames").glob("branches_*.obj"))
    head_rba = list_rba_sequence(build / "heads" / "rba")
    typed = read_scn(build / "corymb" / "typed.scn")
    # the receptacles' obstacle placements (after every floret and bract; fccompose does not write
    # them): the florets are the others, their indices unchanged
    n_obst = sum(p.type == "obstacle" for p in typed.placements)
    typed.placements = [p for p in typed.placements if p.type != "obstacle"]
    print(f"receptacles as obstacles of the canopy simulation: {n_obst}")
    print(f"one clock: {len(canopy)} canopy frames, {len(branches)} branch frames, {len(head_rba)} head RBA frames")
    if not len(canopy) == len(branches) == len(head_rba):
        fail.append("the canopy, branch and head sequences differ in length")

    recs = list_obj_sequence(build / "receptacles")
    print(f"receptacles: {len(recs)} frames")
    if len(recs) != len(canopy):
        fail.append("the receptacle and canopy sequences differ in length")
    # the stem leaves: tested against the branches, the canopy and each other in each frame, as
    # the canopy is (each frame's meshes read once)
    leaves = list_obj_sequence(build / "leaves")
    lb = lc = ll = 0
    bad = cross = far = rcross = 0
    mesh = rec = None
    for i, path in enumerate(canopy):
        mesh = read_obj(path)
        n = count(mesh)
        rec = read_obj(recs[min(i, len(recs) - 1)])
        nr = cross_pairs(mesh, rec)
        rcross += nr
        br = read_obj(branches[min(i, len(branches) - 1)])
        nb = cross_pairs(mesh, br)
        if i < len(leaves):
            dl = leaf_pairs(read_obj(leaves[i]), br, mesh)
            lb, lc, ll = lb + dl[0], lc + dl[1], ll + dl[2]
        heads = read_rba(head_rba[min(i, len(head_rba) - 1)])
        d = cKDTree(br.vertices).query(heads.pos)[0] if len(heads) and len(br.vertices) else np.zeros(len(heads))
        nfar = int((d > 1e-5).sum()) if len(br.vertices) else len(heads)
        bad, cross, far = bad + n, cross + nb, far + nfar
        if nr:
            print(f"  frame {i:3d}: {nr} canopy-receptacle pairs")
        if i % 4 == 0 or i == len(canopy) - 1 or n or nb or nfar:
            print(f"  frame {i:3d}: {len(mesh.faces):6d} triangles, {len(mesh.groups):4d} florets, {len(heads):3d} heads, "
                  f"{len(br.faces):6d} branch triangles; {n} intersecting pairs, {nb} with the branches, "
                  f"{nfar} heads off their peduncle tips")
    print(f"every frame ({len(canopy)}) tested: {bad} intersecting pairs, {cross} canopy-branch pairs, "
          f"{far} heads off their peduncle tips")
    if bad:
        fail.append(f"{bad} intersecting pairs in the canopy frames")
    if cross:
        fail.append(f"{cross} pairs between the canopy and the branches")
    if far:
        fail.append(f"{far} head-frames whose peduncle does not end at the head")
    print(f"every frame: {rcross} pairs between the canopy (florets and bracts) and the receptacles")
    if rcross:
        fail.append(f"{rcross} pairs between the canopy and the receptacles")

    smooth = read_obj(build / "smooth" / "final.obj")
    n = count(smooth)
    print(f"smooth/final.obj: {len(smooth.faces)} triangles, {n} intersecting pairs")
    if n:
        fail.append(f"{n} intersecting pairs in smooth/final.obj")

    lo, hi, out = stretch_range(build / "canopy" / "log.csv")
    print(f"edge stretch over all frames: {lo:.3f}-{hi:.3f} x rest; frames outside [{BOUNDS[0]}, {BOUNDS[1]}]: {len(out)}")
    if out:
        fail.append(f"{len(out)} frames with edges outside {BOUNDS} x rest (frames {', '.join(out[:5])} ...)")

    present = {int(g.split("_")[1]) for g in mesh.groups if g.startswith("floret_")}
    print(f"florets in the last frame: {len(present)} of {len(typed)} ({len(typed.groups) - 1} heads)")
    if len(present) != len(typed):
        fail.append(f"{len(typed) - len(present)} florets missing in the last frame")

    last = read_rba(head_rba[-1])
    groups_n = canopy_groups(last.pos[:, [0, 2]], last.scale[:, 0])
    print(f"one canopy: {len(last.ids)} heads in {groups_n} group(s) of heads whose discs touch (within 5 %)")
    if groups_n != 1:
        fail.append(f"the heads form {groups_n} separate groups, not one canopy")

    per = rays_per_head(typed)
    size = Counter(p.group for p in typed.placements)
    hist = ", ".join(f"{k}: {v}" for k, v in sorted(Counter(per).items()))
    print(f"rays per head (fig. 6.4a, over the whole corymb): mean {np.mean(per):.1f}, min {min(per)}, max {max(per)}; "
          f"heads by ray count {{{hist}}}")
    if not 3 <= np.mean(per) <= 7 or any(r >= size[g] - r for g, r in zip(sorted(size), per)):
        fail.append("rays per head off 3-7 on average, or a head with as many rays as disk florets")

    # heads with a body: the involucre, the rays attached at the rim, the florets on the receptacle
    bracts = Counter(p.group for p in typed.placements if p.type == "bract")
    nb = sorted(set(bracts.get(g, 0) for g in sorted(size)))
    print(f"involucre: bracts per head {nb} (species.toml [check] bracts = {facts['bracts']})")
    if nb != [int(facts["bracts"])]:
        fail.append(f"bracts per head {nb}, not {facts['bracts']}")
    last_rba = read_rba(list_rba_sequence(build / "corymb" / "rba")[-1])
    gaps = ligule_gaps(mesh, typed, last_rba)
    print(f"ligule gap (ray floret to the nearest disk floret of its head, in its lengths): median "
          f"{np.median(gaps):.3f}, quartiles {np.percentile(gaps, 25):.3f}-{np.percentile(gaps, 75):.3f}, "
          f"{(gaps > 0.1).mean():.0%} over 0.1 (at most {facts['ligule_gap']})")
    if not np.median(gaps) <= facts["ligule_gap"]:
        fail.append(f"median ligule gap {np.median(gaps):.3f} > {facts['ligule_gap']}")
    dist = surface_distances(rec, typed, last_rba)
    print(f"floret base to its receptacle, in floret sizes: median {np.median(dist):.4f}, max {dist.max():.4f} "
          f"(median at most {facts['floret_surface']})")
    if not np.median(dist) <= facts["floret_surface"]:
        fail.append(f"median floret-receptacle distance {np.median(dist):.3f} > {facts['floret_surface']}")

    # one closed corymb: the top view's cover, heads alike in size, a stem that carries them
    cov = view_coverage(mesh, 1)
    print(f"top view (the last canopy frame, axis Y): covers {cov:.3f} of its convex hull (at least {facts['coverage']})")
    if not cov >= facts["coverage"]:
        fail.append(f"top view covers {cov:.3f} of its hull < {facts['coverage']}")
    sizes = last.scale[:, 0]
    cv = float(sizes.std() / sizes.mean())
    print(f"head diameters (the heads' discs, last frame): {sizes.min():.2f}-{sizes.max():.2f}, mean {sizes.mean():.2f}, "
          f"CV {cv:.3f} (at most {facts['head_cv']})")
    if not cv <= facts["head_cv"]:
        fail.append(f"head-diameter CV {cv:.3f} > {facts['head_cv']}")
    radii = [float(t.split()[0]) for t in (build / "branches" / "skeleton.radii").read_text().splitlines()
             if t.strip() and not t.startswith("#")]
    ratio = 2.0 * max(radii) / float(sizes.mean())
    print(f"stem base: diameter {2.0 * max(radii):.3f}, {ratio:.3f} of the mean head diameter (at least {facts['stem_base']})")
    if not ratio >= facts["stem_base"]:
        fail.append(f"stem base {ratio:.3f} of a head diameter < {facts['stem_base']}")

    # the stem leaves: present, textured, crossing nothing in any frame (tested above)
    n_leaves = 0
    textured = False
    if leaves:
        text = Path(leaves[-1]).read_text()
        n_leaves = sum(1 for t in text.splitlines() if t.startswith("g leaf_"))
        textured = "\nvt " in text and "map_Kd" in (build / "leaves" / "leaves.mtl").read_text()
    print(f"stem leaves: {len(leaves)} frames, {n_leaves} leaves in the last (species.toml [check] stem_leaves = "
          f"{facts['stem_leaves']}), textured {textured}; every frame: {lb} leaf-branch, {lc} leaf-canopy, "
          f"{ll} leaf-leaf pairs")
    if len(leaves) != len(canopy):
        fail.append("the leaf and canopy sequences differ in length")
    if n_leaves != int(facts["stem_leaves"]) or not textured:
        fail.append(f"{n_leaves} stem leaves (textured {textured}), not {facts['stem_leaves']}")
    if lb or lc or ll:
        fail.append(f"stem leaves cross: {lb} branch, {lc} canopy, {ll} leaf pairs")

    # the heads open in the order they emerged: at the frame where half the florets have started
    groups = np.array([p.group for p in typed.placements])
    start = np.array([p.frame_start for p in typed.placements])
    emerged = np.array([p.emergence for p in typed.placements])
    k = int(np.median(start))
    g = np.unique(groups)
    share = np.array([(start[groups == h] <= k).mean() for h in g])
    first = np.array([emerged[groups == h].min() for h in g])
    rho = float(spearmanr(first, share).statistic)
    print(f"development at frame {k}: heads' share of florets opening {share.min():.2f}-{share.max():.2f}, "
          f"rank correlation with the heads' emergence {rho:.2f} (the first heads open first)")
    if not rho < -0.5:
        fail.append(f"the heads do not open in the order they emerged (rank correlation {rho:.2f})")

    print("OK: every check passed" if not fail else "FAILED: " + "; ".join(fail))
    return 0 if not fail else 1


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1])))
