"""Write the lilac key poses (floret_*.floret) from a few numbers per pose.

The .floret files under draft/ and final/ are the pipeline's inputs and are committed; this script
documents how their control points were laid out and regenerates them after a change of the
numbers below (``python make_keys.py`` in this folder; ``python make_keys.py OUT_DIR`` writes both
sets under OUT_DIR, which the tests use to check that the committed files are up to date). The two
sets differ only in their polygonization (``lambda:`` and ``eta:``).

Units: floret units, the open limb about one unit across (thyrse's ``floret_size`` scales it to
the scene); local +Y is the floret axis (along its pedicel), +X towards the tip of the axis that
carries it.

The lilac floret (*Syringa vulgaris*; thesis sec. 4.5, figs. 4.9, 4.10): four petals fused into a
narrow tube that opens into a flat, four-lobed limb. One organ, ``corolla`` (symmetry 4, bilateral
half petal of 3 columns x 9 rows, cubic along v, the first 5 rows of each lateral boundary fused:
the tube and the throat are closed; the lobes part above it). Row 0 (the tube's foot) is the same
ring in every pose, flat on y = 0: all of it is fixed on the pedicel (weights.py base).

- ``bud`` (time 0): a short club, the lobes folded over the tube's mouth into a closed knob;
- ``mid`` (time 0.5): the tube lengthened, the lobes spreading upward into a cup;
- ``open`` (time 1): the tube full length, the limb flat and perpendicular to the axis, four broad
  ovate lobes with rounded tips.

Polygonization (``../lambda_*.func``, ``../eta_*.func``): the narrow tube gets fewer vertices
round and closer rows than the limb (no needle triangles along it), and eta falls to one vertex
at the lobe tips (formats/fcc.md "Mesh quality matters").
"""
from __future__ import annotations

import sys
from pathlib import Path

from inflo.tools.species.keys import organ, ring_net

HERE = Path(__file__).resolve().parent

# polygonization per quality: (lambda, eta) of the corolla
RES = {
    "draft": ("../lambda_draft.func", "../eta_draft.func"),
    "final": ("../lambda_final.func", "../eta_final.func"),
}
NU, NV, FUSED = 3, 9, 5
# radius, height and half angle (degrees; 45 = the symmetry plane between two petals) per row:
# rows 0-3 the tube, 4 the throat, 5-8 the lobes (broad to near the tip: rounded, ovate lobes)
POSES = {
    "bud": dict(time=0.0,
                r=[0.070, 0.055, 0.055, 0.065, 0.085, 0.095, 0.085, 0.055, 0.020],
                y=[0.000, 0.110, 0.220, 0.300, 0.360, 0.420, 0.470, 0.505, 0.520],
                half=[45, 45, 45, 45, 45, 41, 37, 31, 18]),
    "mid": dict(time=0.5,
                r=[0.070, 0.055, 0.058, 0.070, 0.120, 0.190, 0.250, 0.295, 0.320],
                y=[0.000, 0.180, 0.360, 0.500, 0.570, 0.630, 0.690, 0.730, 0.745],
                half=[45, 45, 45, 45, 45, 42, 36, 26, 6]),
    "open": dict(time=1.0,
                 r=[0.070, 0.055, 0.060, 0.075, 0.150, 0.260, 0.360, 0.440, 0.490],
                 y=[0.000, 0.220, 0.440, 0.600, 0.660, 0.690, 0.695, 0.690, 0.680],
                 half=[45, 45, 45, 45, 45, 41, 36, 26, 6]),
}
# material id (colors.toml)
M_COROLLA = 0


def write(out: Path, quality: str) -> None:
    out.mkdir(parents=True, exist_ok=True)
    head = "# lilac floret, key pose '{key}' ({q}); written by make_keys.py\nfloret 1\nname: floret\ntime: {t}\n\n"
    for key, p in POSES.items():
        text = head.format(key=key, q=quality, t=p["time"])
        text += organ("corolla", M_COROLLA, "2 3", f"{NU} {NV}", "4 0", FUSED, RES[quality],
                      ring_net(p["r"], p["y"], p["half"], NU))
        (out / f"floret_{key}.floret").write_text(text)


if __name__ == "__main__":
    root = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE
    for q in RES:
        write(root / q, q)
