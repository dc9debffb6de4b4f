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
    "draft": {"petal": ("0.25", "3"), "stylopodium": ("0.5", "2"), "stamen": ("0.34", "3"),
              "large": ("0.1", "7"), "bract": ("0.25", "3")},
    "final": {"petal": ("0.125", "../petal_eta_final.func"), "stylopodium": ("0.34", "3"), "stamen": ("0.25", "3"),
              "large": ("0.0625", "9"), "bract": ("0.2", "5")},
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
                 mid=[(0.11, 0.00), (0.17, 0.03), (0.26, 0.05), (0.36, 0.06), (0.46, 0.06), (0.55, 0.05)],
                 half=[0.03, 0.08, 0.14, 0.18, 0.18, 0.15],
                 cup=0.15),
}
# the large ray florets' petals (own key poses, floret_large_*.floret): the same blade, its tip cleft
# into two lobes by a deep notch along the midrib (Orlaya's outer petals are deeply two-lobed, fig.
# 9.11): each column of the half blade ends at (1 - LOBE_CUT[i]) of its length, rows spread evenly
# along it, so the notch runs down the petal's axis without slivers (the rows near the midrib are
# only closer together). Column 0 is the midrib (the notch's bottom, half the blade's length back),
# the outer columns round the lobes' shoulders
LOBE_CUT = np.array([0.5, 0.12, 0.0, 0.1])
# five stamens alternating with the petals (symmetry 5, phase 36): a filament rising from between the
# stylopodium and the claws (radius 0.105) and curving outward over the petals' bases, ending in an
# oblong anther (the last rows, wider), low over the petals (anthers about 0.1 above the base: higher,
# they held up the large petals lying over them); bud inflexed inside the incurved petals. Row 0 on y = 0 (fixed)
STAMEN_NU, STAMEN_NV = 2, 6
U_STAMEN = np.linspace(0.0, 1.0, STAMEN_NU)
STAMEN = {
    "bud": dict(mid=[(0.105, 0.00), (0.11, 0.04), (0.115, 0.08), (0.11, 0.11), (0.10, 0.13), (0.09, 0.145)],
                half=[0.008, 0.007, 0.007, 0.012, 0.02, 0.014], cup=0.0),
    "mid": dict(mid=[(0.105, 0.00), (0.12, 0.05), (0.14, 0.09), (0.155, 0.12), (0.165, 0.14), (0.17, 0.16)],
                half=[0.008, 0.007, 0.007, 0.012, 0.022, 0.015], cup=0.0),
    "open": dict(mid=[(0.105, 0.00), (0.125, 0.04), (0.155, 0.07), (0.185, 0.09), (0.21, 0.10), (0.235, 0.105)],
                 half=[0.008, 0.007, 0.007, 0.016, 0.032, 0.022], cup=0.0),
}
# stylopodium: radius, height per row (half angle 36 = the symmetry plane: a closed ring)
STYLO = dict(r=[0.09, 0.085, 0.06, 0.03], y=[0.00, 0.04, 0.08, 0.10], half=[36, 36, 36, 36])

# an involucral bract (bract_*.floret; involucres.py places them where the rays meet): a
# linear-lanceolate green blade of unit length along +X, rising a little (below the rays leaving
# upward), its base row on y = 0 (fixed); bud shorter, open full length
BRACT_NU, BRACT_NV = 3, 5
U_BRACT = np.linspace(0.0, 1.0, BRACT_NU)
BRACT = {
    "bud": dict(time=0.0, mid=[(0.0, 0.0), (0.18, 0.04), (0.36, 0.07), (0.54, 0.09), (0.7, 0.10)],
                half=[0.05, 0.08, 0.07, 0.045, 0.012], cup=0.3),
    "open": dict(time=1.0, mid=[(0.0, 0.0), (0.25, 0.05), (0.5, 0.09), (0.75, 0.11), (1.0, 0.12)],
                 half=[0.05, 0.09, 0.08, 0.05, 0.015], cup=0.2),
}

# material ids (colors.toml)
M_PETAL, M_STYLO, M_STAMEN, M_BRACT = 0, 1, 2, 3


def cleft(net, cut):
    """The half blade ``net`` with column i ending at (1 - cut[i]) of its own length (arc length along
    the column's control polygon), its rows spread evenly along what is left: a notch of depth cut[0]
    along the midrib."""
    out = net.copy()
    for i in range(net.shape[1]):
        col = net[:, i]
        seg = np.sqrt(((col[1:] - col[:-1]) ** 2).sum(axis=1))
        s = np.concatenate([[0.0], np.cumsum(seg)])
        want = np.linspace(0.0, s[-1] * (1.0 - cut[i]), len(col))
        for k in range(3):
            out[:, i, k] = np.interp(want, s, col[:, k])
    return out


def write(out: Path, quality: str) -> None:
    out.mkdir(parents=True, exist_ok=True)
    res = RES[quality]
    head = "# orlaya floret, key pose '{key}' ({q}); written by make_keys.py\nfloret 1\nname: floret\ntime: {t}\n\n"
    stylo = organ("stylopodium", M_STYLO, "2 2", "3 4", "5 0", 4, res["stylopodium"],
                  ring_net(STYLO["r"], STYLO["y"], STYLO["half"], 3))
    for key, p in PETAL.items():
        snet = blade_net(STAMEN[key], STAMEN_NU, STAMEN_NV, U_STAMEN)
        snet[0, :, 1] = 0.0
        stamen = organ("stamen", M_STAMEN, "1 3", f"{STAMEN_NU} {STAMEN_NV}", "5 36", 0, res["stamen"], snet)
        for name, net, r in (("floret", blade_net(p, PETAL_NU, PETAL_NV, U_PETAL, TIP_RECESS), res["petal"]),
                             ("floret_large", cleft(blade_net(p, PETAL_NU, PETAL_NV, U_PETAL), LOBE_CUT), res["large"])):
            text = head.format(key=key, q=quality, t=p["time"])
            net[0, :, 1] = 0.0  # the claw's row flat on y = 0: all of it fixed (weights.py base)
            text += (organ("petal", M_PETAL, "2 3", f"{PETAL_NU} {PETAL_NV}", "5 0", 0, r, net) + "\n" + stylo
                     + "\n" + stamen)
            (out / f"{name}_{key}.floret").write_text(text)
    for key, p in BRACT.items():
        net = blade_net(p, BRACT_NU, BRACT_NV, U_BRACT)
        net[0, :, 1] = 0.0
        text = ("# orlaya involucral bract, key pose '{key}' ({q}); written by make_keys.py\nfloret 1\nname: bract\n"
                "time: {t}\n\n").format(key=key, q=quality, t=p["time"])
        text += organ("bract", M_BRACT, "2 3", f"{BRACT_NU} {BRACT_NV}", "1 0", 0, res["bract"], net)
        (out / f"bract_{key}.floret").write_text(text)


if __name__ == "__main__":
    root = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE
    for q in RES:
        write(root / q, q)
