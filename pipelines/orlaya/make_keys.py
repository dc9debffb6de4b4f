"""Write the orlaya key poses (floret_*.floret) from a few numbers per pose.

The .floret files under draft/ and final/ are the pipeline's inputs and are committed; this script
documents how their control points were laid out and regenerates them after a change of the
numbers below (``python make_keys.py`` in this folder; ``python make_keys.py OUT_DIR`` writes both
sets under OUT_DIR, which the tests use to check that the committed files are up to date). The two
sets differ only in their polygonization (each organ's ``lambda:`` and ``eta:``).

Units: a floret model of unit diameter fills its primordium's disc (formats/phyllotaxis.md), so
the numbers are in disc diameters; local +Y is the floret axis (the umbel's normal), +X points
away from the umbellet's centre (dimorph ``--orient-rays top`` turns the large ray florets' +X
away from the whole umbel's centre).

One floret of *Orlaya grandiflora* (thesis ch. 9, figs. 9.11-9.13) serves every type: five free,
white, obcordate petals (notched at the tip) round a small, cream stylopodium. The types differ by
their petal factor (dimorph ``--petal-size``) and by the petal weight file fccompose grows them
with (petal_weights.py): five-fold inner florets (factor 1), outer florets of each umbellet with
enlarged, mildly zygomorphic petals, and florets on the periphery of the umbel with very large,
zygomorphic ones (the outward petal largest). Only the petals grow, not the floret (fig. 6.4c).

- ``petal`` (symmetry 5, bilateral): a blade along a midrib in the x-y plane; ``bud`` incurved
  over the stylopodium, ``mid`` a cup, ``open`` spreading nearly flat. Row 0 (the claw) sits at
  radius 0.11 on y = 0 (not cupped), all of it fixed on the pedicel (weights.py base): a claw
  vertex left free between fixed ones has edges of a few hundredths of a floret, which contacts
  would stretch many times over.
- ``stylopodium`` (symmetry 5, fused: a closed ring): a low cone, radius 0.09 at its base.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from inflo.tools.species.keys import blade_net, organ, ring_net

HERE = Path(__file__).resolve().parent

# polygonization per quality: (lambda, eta) of each organ
RES = {
    "draft": {"petal": ("0.25", "3"), "stylopodium": ("0.5", "2")},
    "final": {"petal": ("0.125", "../petal_eta_final.func"), "stylopodium": ("0.34", "3")},
}

PETAL_NU, PETAL_NV = 4, 6
U_PETAL = np.linspace(0.0, 1.0, PETAL_NU)
# how far each column of the tip row falls short of the midrib's tip, as a fraction of the tip
# row's half width: the notch of an obcordate petal (deepest on the midrib). Kept shallower than the
# last rows' spacing: a notch that folds the tip row back past the row before it leaves slivers and
# edges of a few thousandths of a floret there, which contacts stretch many times over
TIP_RECESS = np.array([0.45, 0.3, 0.05, 0.2])
PETAL = {
    "bud": dict(time=0.0,
                mid=[(0.11, 0.00), (0.15, 0.06), (0.17, 0.12), (0.16, 0.18), (0.13, 0.23), (0.09, 0.26)],
                half=[0.03, 0.05, 0.06, 0.055, 0.045, 0.03],
                cup=0.8),
    "mid": dict(time=0.5,
                mid=[(0.11, 0.00), (0.16, 0.06), (0.22, 0.12), (0.28, 0.16), (0.33, 0.19), (0.37, 0.21)],
                half=[0.03, 0.065, 0.095, 0.11, 0.11, 0.09],
                cup=0.5),
    "open": dict(time=1.0,
                 mid=[(0.11, 0.00), (0.17, 0.03), (0.25, 0.05), (0.33, 0.06), (0.41, 0.06), (0.48, 0.05)],
                 half=[0.03, 0.07, 0.11, 0.13, 0.13, 0.11],
                 cup=0.15),
}
# stylopodium: radius, height per row (half angle 36 = the symmetry plane: a closed ring)
STYLO = dict(r=[0.09, 0.085, 0.06, 0.03], y=[0.00, 0.04, 0.08, 0.10], half=[36, 36, 36, 36])

# material ids (colors.toml)
M_PETAL, M_STYLO = 0, 1


def write(out: Path, quality: str) -> None:
    out.mkdir(parents=True, exist_ok=True)
    res = RES[quality]
    head = "# orlaya floret, key pose '{key}' ({q}); written by make_keys.py\nfloret 1\nname: floret\ntime: {t}\n\n"
    stylo = organ("stylopodium", M_STYLO, "2 2", "3 4", "5 0", 4, res["stylopodium"],
                  ring_net(STYLO["r"], STYLO["y"], STYLO["half"], 3))
    for key, p in PETAL.items():
        text = head.format(key=key, q=quality, t=p["time"])
        net = blade_net(p, PETAL_NU, PETAL_NV, U_PETAL, TIP_RECESS)
        net[0, :, 1] = 0.0  # the claw's row flat on y = 0: all of it fixed (weights.py base)
        text += organ("petal", M_PETAL, "2 3", f"{PETAL_NU} {PETAL_NV}", "5 0", 0, res["petal"], net) + "\n" + stylo
        (out / f"floret_{key}.floret").write_text(text)


if __name__ == "__main__":
    root = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE
    for q in RES:
        write(root / q, q)
