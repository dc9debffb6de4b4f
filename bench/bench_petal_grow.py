"""petal-grow (Ijiri et al. 2008, sec. 6.3): 100 keyframes of an opening flower grown by
growth maps, with collisions and the exact test of every written keyframe.

- ``petal_grow_eustoma_100``: the Eustoma of pipelines/eustoma at the paper's resolution (five
  petals of 456 triangles, 2280 in all), Mellow Yellow's maps. Anchor: 8 min on a 2.4 GHz Core 2
  Duo (sec. 6.3); goal: under 10 s.
- ``petal_grow_lily_100``: the growth-map lily of pipelines/lily/growth.toml (three petals of 680
  triangles inside three sepals of 560, 3720 in all). Anchor: 11.5 min; goal: under 10 s.
- ``petal_grow_single_petal_100``: one Eustoma petal alone. Anchor: 2.5 min; goal: under 1 s.

Times are :func:`inflo.tools.petal_grow.simulate.run`'s wall time (its CPU time in the note) (growth, PBD, attachment,
collisions, writing and testing the keyframes), best of ``repeat`` runs, kernels compiled before.
"""
from __future__ import annotations

import subprocess
import sys
import time

from inflo.tools.petal_grow.params import parse_params
from inflo.tools.petal_grow.simulate import build_model, run

from .harness import REPO, BenchContext, Result

EUSTOMA = REPO / "pipelines" / "eustoma"
LILY = REPO / "pipelines" / "lily"


def _params(ctx: BenchContext, name: str, text: str, mesh_from: str, mesh_to: str, organs: int | None = None):
    text = text.replace(mesh_from, mesh_to)
    if organs is not None:
        head, *blocks = text.split("\n[[organ]]")
        text = head + "".join("\n[[organ]]" + b for b in blocks[:organs])
        text = "\n".join(line for line in text.splitlines() if not line.startswith("beneath ="))
    return parse_params(text, ctx.workdir / f"{name}.toml")


def _time(ctx: BenchContext, name: str, params, repeat: int) -> tuple[float, object]:
    model = build_model(params)
    run(params, ctx.workdir / f"{name}_warm", keyframes=3, model=model)  # compile / load the kernels
    params.flower.keyframes = 100
    best, res = float("inf"), None
    for _ in range(repeat):
        c0 = time.process_time()
        r = run(params, ctx.workdir / name, model=model)
        r.cpu = time.process_time() - c0
        if r.seconds < best:
            best, res = r.seconds, r
    return best, res


def _note(res, model_tris: int) -> str:
    rows = res.log[1:]
    return (f"CPU {res.cpu:.2f} s (a loaded machine's wall time is longer); {len(res.frames)} keyframes, {model_tris} triangles; collisions found {sum(r['collisions_found'] for r in rows)}; "
            f"intersecting pairs {res.intersecting}; edge stretch {min(r['min_edge_stretch'] for r in rows):.3f}-"
            f"{max(r['max_edge_stretch'] for r in rows):.3f}")


def bench_petal_grow(ctx: BenchContext) -> list[Result]:
    repeat = 1 if ctx.quick else 2
    bud = ctx.workdir / "eustoma_bud"
    subprocess.run([sys.executable, str(EUSTOMA / "make_keys.py"), "--quality", "final", "-o", str(bud)], check=True)
    text = (EUSTOMA / "mellow_yellow.toml").read_text()
    mesh = "../../build/eustoma/bud/petal.obj"
    out = []
    p = _params(ctx, "eustoma", text, mesh, str(bud / "petal.obj"))
    t, res = _time(ctx, "eustoma", p, repeat)
    out.append(Result("petal_grow_eustoma_100", t, "s", "Ijiri et al. sec. 6.3: 8 min (goal: 10 s)", 480.0,
                      _note(res, 5 * 456)))
    p = _params(ctx, "single", text, mesh, str(bud / "petal.obj"), organs=1)
    t, res = _time(ctx, "single", p, repeat)
    out.append(Result("petal_grow_single_petal_100", t, "s", "Ijiri et al. sec. 6.3: 2.5 min (goal: 1 s)",
                      150.0, _note(res, 456)))
    lbud = ctx.workdir / "lily_bud"
    subprocess.run([sys.executable, str(LILY / "growth_keys.py"), "-o", str(lbud)], check=True)
    p = _params(ctx, "lily", (LILY / "growth.toml").read_text(), "../../build/lily/growth_bud", str(lbud))
    t, res = _time(ctx, "lily", p, repeat)
    out.append(Result("petal_grow_lily_100", t, "s", "Ijiri et al. sec. 6.3: 11.5 min (goal: 10 s)", 690.0,
                      _note(res, 3 * 680 + 3 * 560)))
    return out


BENCHMARKS = [bench_petal_grow]
