"""Write the lilac key poses (floret_*.floret) from a few numbers per pose.

The .floret files under draft/ and final/ are the pipeline's inputs and are committed; this script
documents how their control points were laid out and regenerates them after a change of the
numbers below (``python make_keys.py`` in this folder; ``python make_keys.py OUT_DIR`` writes both
sets under OUT_DIR, which the tests use to check that the committed files are up to date). The two
sets differ only in their polygonization (``lambda:`` and ``eta:``).

Units: floret units, the open limb about one unit across (thyrse's ``floret_size`` scales it to
the scene); local +Y is the floret axis (along its pedicel), +X towards the tip of the axis that
carries it.

The lilac floret (*Syringa vulgaris*; thesis sec. 4.5, figs. 4.9, 4.10): a small green calyx cup at
the foot of a narrow corolla tube of four fused petals, which opens into four spreading, slightly
hooded lobes. Two organs:

- ``corolla`` (material 0; symmetry 4, bilateral half petal of 3 columns x 9 rows, cubic along v,
  the first 5 rows of each lateral boundary fused: the tube and the throat are closed; the lobes
  part above it). Each row is an arc whose radius falls towards the seam between two petals by
  ``square`` (a four-angled cross-section, corners on the petals' midlines) and whose margins are
  lifted by ``cup`` (concave, hooded lobes);
- ``calyx`` (material 1; symmetry 4, bilateral half sepal of 3 columns x 5 rows, quadratic along v,
  fused over 4 rows): a shallow cup round the tube's foot ending in four short teeth, the same in
  every pose, clear of the tube (0.023 floret units at the foot, more above).

Row 0 of each organ (the tube's foot and the calyx's) lies flat on y = 0 in every pose: all of it
is fixed on the pedicel (weights.py base).

- ``bud`` (time 0): the tube short, the lobes folded valvately into a closed, four-angled ball on
  top of it (Syringa's bud: a ball with four ridges);
- ``mid`` (time 0.5): the tube lengthened, the ball swollen and its lobes parting into a cup,
  their tips still incurved;
- ``open`` (time 1): the tube full length, the limb spread perpendicular to the axis, four broad
  ovate lobes, concave with their tips turned up a little (hooded).

Polygonization (``../lambda_*.func``, ``../eta_*.func`` for the corolla; constants for the small
calyx): the narrow tube gets fewer vertices round and closer rows than the limb (no needle
triangles along it), and eta falls to one vertex at the lobe tips (formats/fcc.md "Mesh quality
matters").
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from inflo.tools.species.keys import organ, ring_net

HERE = Path(__file__).resolve().parent

# polygonization per quality: (lambda, eta) of the corolla and of the calyx
RES = {
    "draft": ("../lambda_draft.func", "../eta_draft.func"),
    "final": ("../lambda_final.func", "../eta_final.func"),
}
CALYX_RES = {"draft": (0.34, 3), "final": (0.26, 5)}
NU, NV, FUSED = 3, 9, 5
# radius, height and half angle (degrees; 45 = the symmetry plane between two petals) per row:
# rows 0-3 the tube, 4 the throat, 5-8 the lobes; square: the radius at the seam is (1 - square)
# times that on the midline; cup: the margins lifted by cup x radius (concave lobes)
POSES = {
    "bud": dict(time=0.0,
                r=[0.062, 0.050, 0.050, 0.072, 0.125, 0.160, 0.155, 0.115, 0.050],
                y=[0.000, 0.090, 0.180, 0.250, 0.300, 0.370, 0.450, 0.520, 0.560],
                half=[45, 45, 45, 45, 45, 42, 41.5, 40, 37],
                square=[0, 0, 0, 0.04, 0.12, 0.18, 0.18, 0.16, 0.1],
                cup=[0, 0, 0, 0, 0, 0, 0, 0, 0]),
    "mid": dict(time=0.5,
                r=[0.062, 0.055, 0.058, 0.072, 0.130, 0.205, 0.250, 0.265, 0.235],
                y=[0.000, 0.170, 0.340, 0.470, 0.540, 0.610, 0.690, 0.760, 0.805],
                half=[45, 45, 45, 45, 45, 41, 37, 29, 10],
                square=[0, 0, 0, 0.03, 0.08, 0.10, 0.08, 0.05, 0],
                cup=[0, 0, 0, 0, 0, 0.05, 0.08, 0.08, 0]),
    "open": dict(time=1.0,
                 r=[0.062, 0.055, 0.060, 0.075, 0.150, 0.260, 0.360, 0.435, 0.470],
                 y=[0.000, 0.220, 0.440, 0.600, 0.660, 0.690, 0.700, 0.712, 0.740],
                 half=[45, 45, 45, 45, 45, 41, 36, 26, 6],
                 square=[0, 0, 0, 0, 0, 0, 0, 0, 0],
                 cup=[0, 0, 0, 0, 0, 0.07, 0.09, 0.08, 0]),
}
# the calyx: the same in every pose (radius, height, half angle per row: the cup, then a tooth)
CALYX = dict(r=[0.085, 0.086, 0.088, 0.091, 0.094],
             y=[0.000, 0.030, 0.060, 0.085, 0.115],
             half=[45, 45, 45, 45, 10])
# material ids (colors.toml)
M_COROLLA, M_CALYX = 0, 1


def lobed_net(p, nu=NU):
    """The corolla's half petal: :func:`ring_net` with each row's radius falling towards the seam
    by ``square`` and its margin lifted by ``cup`` (both quadratic in the column's angle)."""
    pts = ring_net(p["r"], p["y"], p["half"], nu)
    s = (np.linspace(0.0, 1.0, nu) ** 2)[None, :]
    pts[:, :, 0] *= 1.0 - np.asarray(p["square"])[:, None] * s
    pts[:, :, 2] *= 1.0 - np.asarray(p["square"])[:, None] * s
    pts[:, :, 1] += (np.asarray(p["cup"]) * np.asarray(p["r"]))[:, None] * s
    return pts


def write(out: Path, quality: str) -> None:
    out.mkdir(parents=True, exist_ok=True)
    head = "# lilac floret, key pose '{key}' ({q}); written by make_keys.py\nfloret 1\nname: floret\ntime: {t}\n\n"
    calyx = organ("calyx", M_CALYX, "2 2", "3 5", "4 0", 4, CALYX_RES[quality],
                  ring_net(CALYX["r"], CALYX["y"], CALYX["half"], 3))
    for key, p in POSES.items():
        text = head.format(key=key, q=quality, t=p["time"])
        text += organ("corolla", M_COROLLA, "2 3", f"{NU} {NV}", "4 0", FUSED, RES[quality], lobed_net(p))
        text += "\n" + calyx
        (out / f"floret_{key}.floret").write_text(text)


if __name__ == "__main__":
    root = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE
    for q in RES:
        write(root / q, q)
