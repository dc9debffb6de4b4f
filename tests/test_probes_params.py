"""Hostile parameter files of branch-gen, thyrse and phyllotaxis: every count, size and float key
is bounded against the work, memory and coordinates it implies, before any work. One row per probe:
the parameter file (a shipped example with keys replaced, or a new file), the message fragment
expected; the run must exit 2 with one line on stderr and leave the output folder (holding an
earlier run's file) as it was. These probes used to hang, exhaust memory, print multi-line
warnings, exit 1, or exit 0 with degenerate output."""
from __future__ import annotations

import re

import pytest
from conftest import REPO, run_cli

EX = REPO / "pipelines" / "examples"
TREE = EX / "branch_gen" / "tree.toml"
CORYMB = EX / "branch_gen" / "corymb.toml"
CORYMB_SCN = EX / "branch_gen" / "corymb.scn"
DYNAMIC = EX / "phyllotaxis" / "dynamic_head.toml"
STATIC = """[surface]
curve = "disk"
radius = 1.0

[primordia]
area = 0.003
count = 100
divergence = 137.50776
placement = "o"
"""
THYRSE = "[thyrse]\nnodes = 4\ndensity = 5.0\n"


def _edit(text: str, changes: dict) -> str:
    """``text`` with each ``[section] key = value`` of ``changes`` ("section.key" -> TOML value)
    replaced, or added under its section (the section added when missing)."""
    for name, value in changes.items():
        sec, key = name.rsplit(".", 1)
        # the section's lines up to the key: a line that starts with '[' is the next section
        pat = re.compile(rf"^(\[{re.escape(sec)}\]\n(?:[^\[\n][^\n]*\n|\n)*?){re.escape(key)} *=[^\n]*", re.M)
        if pat.search(text):
            line = f"{key} = {value}"
            text = pat.sub(lambda m, line=line: m.group(1) + line, text, count=1)
        elif re.search(rf"^\[{re.escape(sec)}\]$", text, re.M):
            line = f"\n{key} = {value}"
            text = re.sub(rf"^\[{re.escape(sec)}\]$", lambda m, line=line: m.group(0) + line, text, count=1, flags=re.M)
        else:
            text += f"\n[{sec}]\n{key} = {value}\n"
    return text


# (tool, base parameter text or file, changes, message fragment)
PROBES = [
    # branch-gen, space colonization: points, steps and distances against the envelope they fill
    ("branch-gen", TREE, {"sca.n_points": "10000000"}, "an integer in [0, 1000000] for 'sca.n_points'"),
    ("branch-gen", TREE, {"sca.n_points": "1000000000000"}, "for 'sca.n_points'"),
    ("branch-gen", TREE, {"sca.kill_distance": "1e-300"}, "a kill distance d_k > step / 2"),
    ("branch-gen", TREE, {"sca.add_points": "1000000000", "sca.add_iterations": "1000000000"},
     "for 'sca.add_points'"),
    ("branch-gen", TREE, {"sca.add_points": "1000", "sca.add_iterations": "100000"},
     "n_points + add_points * add_iterations <= 1000000"),
    ("branch-gen", TREE, {"sca.step": "1e308"}, "a step D > 0 and <= 1e+12 for 'sca.step'"),
    ("branch-gen", TREE, {"sca.step": "1e-300"}, "a step D >= "),
    ("branch-gen", TREE, {"sca.step": "100.0"}, "a step D <= "),
    ("branch-gen", TREE, {"sca.kill_distance": "100.0"}, "every point dies at once"),
    ("branch-gen", TREE, {"sca.tropism": "[1e308, 0, 0]"}, "a vector of length <= 1e+06 for 'sca.tropism'"),
    ("branch-gen", TREE, {"sca.tropism": "[0, -1, 0]"}, "reaches its attraction points"),
    ("branch-gen", TREE, {"sca.max_iterations": "1000000000000"}, "for 'sca.max_iterations'"),
    ("branch-gen", TREE, {"sca.influence_radius": "1e-9"}, "a space colonization tree that grows"),
    ("branch-gen", TREE, {"envelope.radii": "[1e308, 1e308, 1e308]"}, "for 'envelope.radii'"),
    ("branch-gen", TREE, {"pipe.exponent": "1e-300"}, "an exponent in [1, 20] for 'pipe.exponent'"),
    ("branch-gen", TREE, {"pipe.tip_diameter": "1e308"}, "for 'pipe.tip_diameter'"),
    ("branch-gen", TREE, {"post.decimate": "1e308"}, "for 'post.decimate'"),
    # branch-gen, extended Rodkaew: steps and the growth of space over the run
    ("branch-gen", CORYMB, {"rodkaew.step": "1e308"}, "a step length > 0 and <= 1e+12 for 'rodkaew.step'"),
    ("branch-gen", CORYMB, {"rodkaew.steps_per_frame": "1000000000000"}, "for 'rodkaew.steps_per_frame'"),
    ("branch-gen", CORYMB, {"rodkaew.steps_per_frame": "1000000"}, "every floret born before max_steps"),
    ("branch-gen", CORYMB, {"rodkaew.max_steps": "1000000000000"}, "for 'rodkaew.max_steps'"),
    ("branch-gen", CORYMB, {"growth.mode": '"uniform"', "growth.rate": "1e308"}, "for 'growth.rate'"),
    ("branch-gen", CORYMB, {"growth.mode": '"uniform"', "growth.rate": "0.5", "growth.frames": "1000000000000"},
     "for 'growth.frames'"),
    ("branch-gen", CORYMB, {"growth.mode": '"uniform"', "growth.rate": "0.5", "growth.frames": "100000"},
     "changes at most 1e+12-fold"),
    ("branch-gen", CORYMB, {"growth.mode": '"allometric"', "growth.rates": "[-0.9, 0, 0]"}, "for 'growth.rates'"),
    ("branch-gen", CORYMB, {"rodkaew.w_a": "0.0"}, "particles must reach the base"),
    ("branch-gen", CORYMB, {"rodkaew.w_a": "1e-320"}, "particles must reach the base"),
    # thyrse
    ("thyrse", THYRSE, {"thyrse.length": "1e-320"}, "a length in (0, 1e+06] and >= 1e-06 for 'thyrse.length'"),
    ("thyrse", THYRSE, {"thyrse.pedicel_length": "1e-320"}, "for 'thyrse.pedicel_length'"),
    ("thyrse", THYRSE, {"thyrse.floret_id": "100000000000000000000"}, "an id in [0, 2147483647]"),
    ("thyrse", THYRSE, {"obstacle.id": "99999999999999999999999"}, "for 'obstacle.id'"),
    ("thyrse", THYRSE, {"obstacle.id": "1", "obstacle.gap": "1e-300"}, "for 'obstacle.gap'"),
    ("thyrse", THYRSE, {"pipe.tip_diameter": "1e308", "pipe.exponent": "1e-300"}, "for 'pipe."),
    ("thyrse", THYRSE, {"thyrse.angle": "0.0", "obstacle.id": "1"}, "values in [1, 179] for 'thyrse.angle'"),
    ("thyrse", THYRSE, {"thyrse.sub_angle": "1e-320", "obstacle.id": "1"}, "for 'thyrse.sub_angle'"),
    ("thyrse", THYRSE, {"thyrse.pedicel_angle": "1e-320", "obstacle.id": "1"}, "for 'thyrse.pedicel_angle'"),
    # phyllotaxis
    ("phyllotaxis", STATIC, {"primordia.placement": '"ca"', "primordia.development_frames": "99999999999999999999"},
     "primordia.development_frames > 0 frames and <= 10000000"),
    ("phyllotaxis", STATIC, {"primordia.placement": '"ca"', "primordia.development_order": '"centripetal"',
                             "primordia.development_offset": "1e308"}, "primordia.development_offset >= 0 and <= 10000000"),
    ("phyllotaxis", STATIC, {"primordia.placement": '"ca"', "primordia.development_order": '"centripetal"',
                             "primordia.development_offset": "1000000"}, "development windows that end by frame"),
    ("phyllotaxis", STATIC, {"primordia.divergence": "1e-320"}, "primordia.divergence in [0.1, 359.9]"),
    ("phyllotaxis", STATIC, {"primordia.floret_id": "99999999999999999999999"}, "primordia.floret_id in [0, "),
    ("phyllotaxis", STATIC, {"surface.curve": '"cone"', "surface.height": "1e308"}, "surface.height within"),
    ("phyllotaxis", STATIC, {"primordia.area": "1e-320"}, "primordia.area > 0 (A(s) is a primordium area), in [1e-12"),
    ("phyllotaxis", STATIC, {"primordia.size_factor": "1e-320"}, "primordia.size_factor in (0, 1e6], at least"),
    ("phyllotaxis", DYNAMIC, {"dynamics.primordium_area": "1e-320"}, "dynamics.primordium_area > 0, in [1e-12"),
    ("phyllotaxis", EX / "phyllotaxis" / "compound_cones.toml", {"compound.floret_fraction": "1e-320"},
     "compound.floret_fraction in (0, 1), at least 1e-6"),
    ("phyllotaxis", DYNAMIC, {"dynamics.primordium_growth": "-1e308"}, "dynamics.primordium_growth x frames within"),
    ("phyllotaxis", DYNAMIC, {"dynamics.inner_growth": "-1e308"}, "dynamics.inner_growth x frames within"),
    ("phyllotaxis", DYNAMIC, {"dynamics.frames": "100000"}, "dynamics.primordium_growth x frames within"),
    ("phyllotaxis", DYNAMIC, {"dynamics.frames": "100000", "dynamics.primordium_growth": "0.0",
                              "dynamics.inner_growth": "0.0"}, "placements over all RBA frames"),
    ("phyllotaxis", DYNAMIC, {"dynamics.primordium_growth": "1e308"}, "dynamics.primordium_growth x frames within"),
    ("phyllotaxis", DYNAMIC, {"dynamics.inner_growth": "1e308"}, "dynamics.inner_growth x frames within"),
    ("phyllotaxis", DYNAMIC, {"dynamics.development_frames": "99999999999999999999"}, "dynamics.development_frames"),
    ("phyllotaxis", DYNAMIC, {"receptacle.segments": "4096", "receptacle.rings": "200",
                              "receptacle.underside_rings": "40"}, "receptacle vertices over all frames"),
]


def _ids():
    return [f"{p[0]}-{i}-{'-'.join(k for k in p[2])}" for i, p in enumerate(PROBES)]


@pytest.mark.parametrize("tool,base,changes,fragment", PROBES, ids=_ids())
def test_bad_parameter_is_one_line_before_work(tmp_path, tool, base, changes, fragment):
    text = base.read_text() if hasattr(base, "read_text") else base
    params = tmp_path / "params.toml"
    params.write_text(_edit(text, changes))
    out = tmp_path / "out"
    out.mkdir()
    (out / "earlier.txt").write_text("an earlier run's file\n")
    before = sorted((p.relative_to(out).as_posix(), p.read_bytes()) for p in out.rglob("*"))
    args = {"branch-gen": [CORYMB_SCN, params], "thyrse": [params], "phyllotaxis": [params]}[tool]
    r = run_cli(tool, *args, "-o", out)
    assert r.returncode == 2, (r.returncode, r.stderr)
    lines = [line for line in r.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith(f"{tool}: error: "), r.stderr
    assert fragment in r.stderr, r.stderr
    assert ".staging-" not in r.stderr
    assert sorted((p.relative_to(out).as_posix(), p.read_bytes()) for p in out.rglob("*")) == before


def test_edit_replaces_and_adds_keys():
    text = "[a]\nx = 1\ny = 2\n\n[b]\nx = 3\n"
    assert _edit(text, {"b.x": "4"}) == "[a]\nx = 1\ny = 2\n\n[b]\nx = 4\n"
    assert _edit(text, {"a.z": "5"}) == "[a]\nz = 5\nx = 1\ny = 2\n\n[b]\nx = 3\n"
    assert _edit(text, {"c.w": "6"}).endswith("[c]\nw = 6\n")


def test_staged_output_names_the_real_path_in_a_refusal(tmp_path):
    """A refusal raised while writing into the staging folder names the output path the user gave
    (the staging folder is never seen), for a FormatError and a plain InputError alike."""
    from inflo.formats.atomic import staged_output
    from inflo.formats.errors import FormatError, InputError

    out = tmp_path / "out"
    with pytest.raises(FormatError) as err:
        with staged_output(out, "tool") as stage:
            raise FormatError(stage / "branches.obj", None, "coordinates within +-1e+12", "nan")
    assert str(err.value) == f"{out / 'branches.obj'}: expected coordinates within +-1e+12, found nan"
    with pytest.raises(InputError) as err:
        with staged_output(out, "tool") as stage:
            raise InputError(f"{stage / 'frames' / 'x.obj'}: too big")
    assert str(err.value) == f"{out / 'frames' / 'x.obj'}: too big"
    assert not out.exists()


@pytest.mark.parametrize("tool,path", [
    *[("branch-gen", p) for p in sorted((REPO / "pipelines").rglob("branches.toml"))],
    *[("branch-gen", p) for p in sorted((EX / "branch_gen").glob("*.toml"))],
    *[("thyrse", p) for p in sorted((REPO / "pipelines").rglob("thyrse.toml"))],
    *[("phyllotaxis", p) for p in sorted((REPO / "pipelines").rglob("*.toml"))
      if ("[primordia]" in p.read_text() or "[surface]" in p.read_text()) and "stem_veins" not in p.parts],
    *[("stem-veins", p) for p in sorted((EX / "stem_veins").glob("*.toml"))],
], ids=lambda x: str(x).replace(str(REPO) + "/", "") if not isinstance(x, str) else x)
def test_every_shipped_parameter_file_is_within_bounds(tool, path):
    """The bounds refuse no shipped parameter file (each tool's reader over every one)."""
    if tool == "branch-gen":
        from inflo.tools.branch_gen.params import read_params
    elif tool == "thyrse":
        from inflo.tools.thyrse.params import read_params
    elif tool == "stem-veins":
        from inflo.tools.stem_veins.params import read_params
    else:
        from inflo.tools.phyllotaxis.params import read_params
    read_params(path)
