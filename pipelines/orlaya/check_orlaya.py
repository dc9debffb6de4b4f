"""Checks of the Orlaya build (the `check` stage of the Makefile).

Usage: python check_orlaya.py BUILD_DIR   (BUILD_DIR = build/orlaya)

Prints, and fails (exit 1) on any of:

- **intersections**: intersecting triangle pairs (inflo.tools.collide, exact static test; touching
  counts) of every canopy frame, and between every frame and the branches (branches/branches.obj);
- **shape**: an output frame whose edges leave [0.5, 1.5] x their rest length (fccompose's log);
- **florets missing**: a placement that is not in the last frame;
- **the species' facts** (thesis ch. 9, figs. 9.11-9.13, 6.4c):
  - a compound umbel: at least 5 umbellets, all florets in one plane (the canopy's floret bases
    within 1e-6 of y = 0);
  - three forms where fig. 6.4c puts them: large ray florets towards the periphery of the whole
    umbel (none in the central umbellet; their median distance from the umbel's centre above the
    other forms', at least 90 % on the outer side of their umbellet), each turned towards its free
    space (its +X within 30 degrees of the direction away from the umbel's centre, or, for one on
    the inner side facing a gap, of the direction away from its umbellet's centre); small ray
    florets in most umbellets; five-fold florets inside;
  - only the petals grow: in the last frame every floret's stylopodium has the same size in floret
    units (within 2 %), while the petals reach farther the larger the petal factor (the median
    reach of large > small > five-fold florets);
  - zygomorphy: a large ray floret's petals reach at least twice as far along its +X (outward) as
    along its -X;
  - collisions deform petals: contacts found in at least half the frames after the first third;
  - the phase effect in every umbellet with at least 4 five-fold florets: at two thirds of the run,
    their petals' spread (reach from the axis in floret units) falls from the umbellet's rim to its
    centre (Spearman rank correlation with the distance from its centre > 0.5), and in the whole
    umbel.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from inflo.formats.obj import read_obj
from inflo.tools.species.checks import check_head, floret_faces, frames_with_contacts

PETAL, STYLO = "mtl0", "mtl1"


def measures(mesh, scene) -> dict:
    """Per floret: (stylopodium radius, petal reach, reach along +X, reach along -X), in floret units
    (distances from the floret's axis through its position, divided by its scale)."""
    mats = list(mesh.materials)
    out = {}
    for pid, faces in floret_faces(mesh).items():
        p = scene.placements[pid]
        up = p.up / np.linalg.norm(p.up)
        right = p.right - np.dot(p.right, up) * up
        right /= np.linalg.norm(right)
        s = float(p.scale[0])
        res = {}
        for name in (PETAL, STYLO):
            k = mats.index(name) if name in mats else -1
            f = faces[mesh.face_material[faces] == k]
            v = mesh.vertices[np.unique(mesh.faces[f])] - p.pos
            radial = v - np.outer(v @ up, up)
            res[name] = (radial, np.linalg.norm(radial, axis=1))
        radial, r = res[PETAL]
        along = radial @ right
        out[pid] = (float(res[STYLO][1].max()) / s, float(r.max()) / s, float(along.max()) / s,
                    float(-along.min()) / s)
    return out


def main(build: Path) -> int:
    build = Path(build).resolve()
    failures: list = []
    head = check_head(build, rays=None, failures=failures, scene="typed.scn", folder="umbel",
                      receptacle=str(build / "branches" / "branches.obj"))
    scene = head.scene
    a = scene.arrays()
    pos, groups = a["pos"], a["group"]
    types = np.array(head.types)
    centre = scene.groups[0].centre
    umbellets = sorted(g for g in scene.groups if g != 0)
    counts = {t: int((types == t).sum()) for t in ("disk", "small_ray", "ray")}
    print(f"umbellets: {len(umbellets)}; florets per umbellet: {[int((groups == g).sum()) for g in umbellets]}; "
          f"forms: {counts['disk']} five-fold, {counts['small_ray']} small ray, {counts['ray']} large ray")
    if len(umbellets) < 5:
        failures.append(f"{len(umbellets)} umbellets, expected at least 5")
    if np.abs(pos[:, 1] - pos[0, 1]).max() > 1e-6:
        failures.append("the florets are not in one plane")
    if not all(counts.values()):
        failures.append(f"a form is missing: {counts}")

    # where the forms are (fig. 6.4c)
    uc = {g: scene.groups[g].centre for g in umbellets}
    ud = {g: float(np.linalg.norm((uc[g] - centre)[[0, 2]])) for g in umbellets}
    central = min(umbellets, key=lambda g: ud[g])
    radius = np.linalg.norm((pos - centre)[:, [0, 2]], axis=1)
    by_form = {t: float(np.median(radius[types == t])) for t in counts}
    large = np.nonzero(types == "ray")[0]
    bad_umbellet = [int(k) for k in large if int(groups[k]) == central]
    inner_side = [int(k) for k in large
                  if np.linalg.norm((pos[k] - centre)[[0, 2]]) <= ud[int(groups[k])]]
    turned = []
    for k in large:
        # towards its free space: away from the umbel's centre, or (inner side) from its umbellet's
        out = (pos[k] - (uc[int(groups[k])] if int(k) in inner_side else centre))[[0, 2]]
        r = scene.placements[k].right[[0, 2]]
        cos = float(out @ r / (np.linalg.norm(out) * np.linalg.norm(r)))
        if cos < np.cos(np.radians(30)):
            turned.append(int(k))
    with_small = sum(1 for g in umbellets if ((groups == g) & (types == "small_ray")).any())
    print(f"median distance from the umbel's centre: five-fold {by_form['disk']:.3f}, small ray "
          f"{by_form['small_ray']:.3f}, large ray {by_form['ray']:.3f}; large ray florets: {len(large)}, in the central umbellet {len(bad_umbellet)}, on the inner side of their "
          f"umbellet {len(inner_side)}, not turned towards their free space {len(turned)}; umbellets with small ray florets: "
          f"{with_small} of {len(umbellets)}")
    if bad_umbellet:
        failures.append(f"{len(bad_umbellet)} large ray florets in the central umbellet (e.g. {bad_umbellet[:3]})")
    if not by_form["ray"] > max(by_form["small_ray"], by_form["disk"]):
        failures.append(f"the large ray florets' median distance from the umbel's centre is not above the "
                        f"other forms': {by_form}")
    if len(inner_side) > 0.1 * len(large):
        failures.append(f"{len(inner_side)} of {len(large)} large ray florets on the inner side of their umbellet")
    if turned:
        failures.append(f"{len(turned)} large ray florets not turned towards their free space")
    if with_small < len(umbellets) // 2:
        failures.append(f"small ray florets in only {with_small} of {len(umbellets)} umbellets")

    # only the petals grow; zygomorphy
    last = read_obj(head.canopy[-1])
    m = measures(last, scene)
    stylo = np.array([m[k][0] for k in m])
    spread = float(stylo.max() / stylo.min() - 1.0)
    reach = {t: float(np.median([m[k][1] for k in m if types[k] == t])) for t in counts}
    print(f"last frame: stylopodium radius {stylo.min():.3f}-{stylo.max():.3f} floret units ({100 * spread:.1f} % "
          f"apart); median petal reach: five-fold {reach['disk']:.2f}, small ray {reach['small_ray']:.2f}, "
          f"large ray {reach['ray']:.2f}")
    if spread > 0.02:
        failures.append(f"the stylopodia differ by {100 * spread:.1f} % (the whole floret grew, not its petals)")
    if not reach["ray"] > reach["small_ray"] > reach["disk"]:
        failures.append(f"petal reach not ordered large > small > five-fold: {reach}")
    zy = [m[k][2] / max(m[k][3], 1e-9) for k in large]
    print(f"large ray florets' reach outward / inward: {min(zy):.2f}-{max(zy):.2f}")
    if min(zy) < 2.0:
        failures.append(f"a large ray floret reaches outward only {min(zy):.2f} x as far as inward")

    # collisions deform petals
    pressed, late = frames_with_contacts(head.canopy_dir)
    if pressed < late // 2:
        failures.append(f"the petals touch in only {pressed} of the last {late} frames")

    # the phase effect: five-fold florets open from each umbellet's rim inward
    k = (2 * len(head.canopy)) // 3
    mk = measures(read_obj(head.canopy[k]), scene)
    rhos = []
    for g in umbellets:
        disk = [p for p in mk if groups[p] == g and types[p] == "disk"]
        if len(disk) < 4:
            continue
        d = np.linalg.norm(pos[disk] - uc[g], axis=1)
        rho = float(spearmanr(d, [mk[p][1] for p in disk]).statistic)
        rhos.append(rho)
        if not rho > 0.5:
            failures.append(f"no phase effect in umbellet {g} at frame {k}: rank correlation {rho:.2f}")
    print(f"phase effect at frame {k}: rank correlation of the five-fold florets' spread with the distance "
          f"from their umbellet's centre, per umbellet: {', '.join(f'{r:.2f}' for r in rhos)}")
    if not rhos:
        failures.append("no umbellet with 4 five-fold florets to test the phase effect")

    print("OK" if not failures else "FAILED: " + "; ".join(failures))
    return 0 if not failures else 1


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(Path(sys.argv[1])))
