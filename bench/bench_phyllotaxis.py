"""Phyllotaxis and dimorph throughput.

- a dynamic head of 10,000 florets (centripetal fractionation, thesis sec. 5.3) simulated and
  written as 200 RBA frames plus scene.scn; goal under 2 s. Anchor: the same frames written
  with the reference writer ``inflo.formats.rba.write_rba(..., fast=False)`` (Python ``%.6f`` per
  number), same run.
- dimorph (eq. 6.1-6.2) on 100,000 florets with a distance threshold; goal under 2 s. Anchor: the
  same d_min by the brute-force reference on a 2,000-floret subset, scaled by (n / 2000)^2 (the
  O(n^2) cost the spatial index avoids).
"""
from __future__ import annotations

import numpy as np

from inflo.formats.rba import RbaFrame, write_rba
from inflo.formats.scn import write_scn
from inflo.tools.dimorph.cones import d_min, d_min_reference
from inflo.tools.phyllotaxis.dynamics import dynamic_scene, frame_state, simulate, write_frames
from inflo.tools.phyllotaxis.surface import builtin_curve

from .harness import BenchContext, Result


def _head(frames: int, florets: int):
    a = 1e-4
    return simulate(mode="centripetal", frames=frames, interval=(frames - 1) / florets, primordium_area=a,
                    inner_area=florets * a * 1.00005, primordium_growth=0.005,
                    profiles=[builtin_curve("sphere_cap", angle=50)])


def dynamic_head_10k(ctx: BenchContext) -> list[Result]:
    frames, florets = (50, 2500) if ctx.quick else (200, 10_000)
    out = ctx.workdir / "phyllo"
    _head(5, 50)  # compile the kernels outside the timing

    def run():
        pat = _head(frames, florets)
        final = write_frames(pat, out / "rba")
        write_scn(out / "scene.scn", dynamic_scene(pat, final))
        return pat

    t, pat = ctx.timed(run, repeat=2)
    assert len(pat) == florets, len(pat)
    ref_dir = ctx.workdir / "phyllo_ref"
    ref_dir.mkdir(parents=True, exist_ok=True)

    def reference():
        for f in range(frames):
            st = frame_state(pat, f)
            write_rba(ref_dir / f"{f:04d}.rba", RbaFrame(st["ids"], st["pos"], st["scale"], st["up"], st["right"]),
                      fast=False)

    t_ref, _ = ctx.timed(reference, repeat=1)
    assert (ref_dir / f"{frames - 1:04d}.rba").read_bytes() == (out / "rba" / f"{frames - 1:04d}.rba").read_bytes()
    rows = sum(int(np.sum(pat.emergence <= f + 1e-9)) for f in range(frames))
    return [Result(f"phyllotaxis_dynamic_{florets // 1000}k_{frames}frames", t, "s",
                   "same frames through formats.rba.write_rba (same run); goal < 2 s", t_ref,
                   f"{florets} florets, {frames} RBA frames, {rows} RBA rows")]


def dimorph_100k(ctx: BenchContext) -> list[Result]:
    n = 20_000 if ctx.quick else 100_000
    rng = np.random.default_rng(0)
    k = np.arange(n)
    r = np.sqrt(k + 0.5)
    th = np.radians(137.50776405) * k
    pos = np.stack([r * np.cos(th), 0.01 * rng.standard_normal(n), r * np.sin(th)], axis=1)
    d_min(pos[:100], np.zeros(3), 53.0, radius=5.0)  # compile
    t, dm = ctx.timed(d_min, pos, np.zeros(3), 53.0, radius=5.0, repeat=2)
    m = 2000
    t_small, ref = ctx.timed(d_min_reference, pos[:m], np.zeros(3), 53.0)
    got = d_min(pos[:m], np.zeros(3), 53.0)
    assert np.array_equal(np.isinf(got), np.isinf(ref))
    scaled = t_small * (n / m) ** 2
    rays = int(np.sum(dm > 5.0))
    return [Result(f"dimorph_{n // 1000}k_threshold", t, "s",
                   f"brute-force eq. 6.1-6.2 on {m} florets scaled by (n/{m})^2; goal < 2 s", scaled,
                   f"{n} florets, threshold 5.0 (~2.8 floret spacings), {rays} rays")]


BENCHMARKS = [dynamic_head_10k, dimorph_100k]
