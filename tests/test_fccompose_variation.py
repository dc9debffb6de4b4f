"""Individual florets (formats/fcc.md "Individual florets"): the ``variation`` line, each floret's
seeded draws, the deformation kernel on a few vertices, and the model giving each floret of a
varied id its own template (and nothing else changing)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from inflo.formats.errors import FormatError, InputError
from inflo.formats.fcc import CanopyParams, format_fcc, read_fcc
from inflo.formats.scn import Placement, Scene
from inflo.formats.variation import FIELDS, Variation, parse_variation
from inflo.tools.fccompose.model import Template, assemble_model
from inflo.tools.fccompose.variation import floret_draws, template_axis, vary_frames

# a strip lying along +X (a ligule): base at the origin, tip at x = 2, width 0.2 in Z
STRIP = np.array([[0, 0, -0.1], [0, 0, 0.1], [1, 0, -0.1], [1, 0, 0.1], [2, 0, -0.1], [2, 0, 0.1]], float)
STRIP_FACES = np.array([[0, 2, 1], [1, 2, 3], [2, 4, 3], [3, 4, 5]])


def _template(frames=None, petal_weight=None) -> Template:
    frames = np.stack([STRIP * 0.5, STRIP]) if frames is None else frames
    t = Template.from_frames(0, frames, STRIP_FACES, fixed=(0, 1))
    t.petal_weight = petal_weight
    return t


def _ca(x: float) -> Placement:
    return Placement("ca", 0, [x, 0, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0], frame_start=0, frame_end=4)


# -- the line ------------------------------------------------------------------------------------

def test_a_variation_line_is_read_and_written_back(tmp_path):
    f = tmp_path / "a.fcc"
    f.write_text("animation: 0 1 1 1 anim\nvariation: 0 size 0.1 droop 8 twist 5f seed 4\n")
    p = read_fcc(f)
    assert p.variations[0] == Variation(size=0.1, droop=8.0, twist=5.0, seed=4)
    assert "variation: 0 size 0.1 droop 8.0 twist 5.0 seed 4" in format_fcc(p)
    g = tmp_path / "b.fcc"
    g.write_text(format_fcc(p))
    assert read_fcc(g).variations == p.variations


@pytest.mark.parametrize("value, found", [
    ("0 size", "size"),                    # odd count
    ("0 colour 0.1", "'colour'"),          # unknown field
    ("0 size 0.1 size 0.2", "'size'"),     # twice
    ("0 size 0.9", "'0.9'"),               # out of range
    ("0 droop nan", "'nan'"),              # not finite
    ("0 seed -1", "'-1'"),                 # seed
    ("1 size 0.1", "id 1"),                # no such animation
])
def test_bad_variation_lines_get_one_line_naming_their_line(tmp_path, value, found):
    f = tmp_path / "a.fcc"
    f.write_text(f"animation: 0 1 1 1 anim\nvariation: {value}\n")
    with pytest.raises(FormatError) as e:
        read_fcc(f)
    msg = str(e.value)
    assert ":2:" in msg and found in msg and "\n" not in msg


def test_two_variation_lines_for_one_id_are_refused(tmp_path):
    f = tmp_path / "a.fcc"
    f.write_text("animation: 0 1 1 1 anim\nvariation: 0 size 0.1\nvariation: 0 droop 3\n")
    with pytest.raises(FormatError, match="line 2"):
        read_fcc(f)


# -- the draws -----------------------------------------------------------------------------------

def test_draws_are_seeded_per_floret_and_independent_of_other_fields():
    v = Variation(size=0.1, droop=10.0, seed=7)
    a, b = floret_draws(v, 3), floret_draws(v, 3)
    assert a == b
    assert floret_draws(v, 4) != a and floret_draws(Variation(size=0.1, droop=10.0, seed=8), 3) != a
    # raising the twist's spread leaves the size and droop draws as they were
    c = floret_draws(Variation(size=0.1, droop=10.0, twist=20.0, seed=7), 3)
    assert c["size"] == a["size"] and c["droop"] == a["droop"] and a["twist"] == 0.0 and c["twist"] != 0.0
    # fields that do not vary give exactly 1 (scales) or 0 (angles, frames)
    assert a["length"] == 1.0 and a["timing"] == 0.0


def test_draws_have_the_spread_asked_for():
    v = Variation(size=0.1, droop=10.0, timing=2.0)
    d = [floret_draws(v, k) for k in range(3000)]
    size = np.array([x["size"] for x in d])
    droop = np.array([x["droop"] for x in d])
    assert abs(size.mean() - 1.0) < 0.01 and abs(size.std() - 0.1) < 0.01
    assert abs(droop.mean()) < 0.6 and abs(droop.std() - 10.0) < 0.6
    assert np.abs(droop).max() <= 10.0 * math.sqrt(3.0) * 2 + 1e-9  # Irwin-Hall: within 3.46 spreads


# -- the kernel ----------------------------------------------------------------------------------

def test_vary_frames_without_variation_is_the_identity():
    f = np.stack([STRIP])
    out = vary_frames(f, np.ones(3), np.array([1.0, 0, 0]), 0.0, 0.0, 2.0, 2.0)
    np.testing.assert_array_equal(out, f)


def test_vary_frames_scales_then_bends_about_local_z():
    f = np.array([[[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0.5]]])
    out = vary_frames(f, np.array([1.0, 1.0, 2.0]), np.array([1.0, 0, 0]), 0.0, 0.2, 2.0, 2.0)
    np.testing.assert_allclose(out[0, 0], [0, 0, 0])  # the base stays
    np.testing.assert_allclose(out[0, 1], [math.cos(0.1), -math.sin(0.1), 0], atol=1e-15)  # half the angle
    np.testing.assert_allclose(out[0, 2], [2 * math.cos(0.2), -2 * math.sin(0.2), 1.0], atol=1e-15)


def test_vary_frames_twists_about_the_axis_keeping_distances_to_it():
    f = np.array([[[1.0, 0, 0.1], [2.0, 0, 0.1], [2.0, 0, -0.1]]])
    out = vary_frames(f, np.ones(3), np.array([1.0, 0, 0]), 0.3, 0.0, 2.0, 2.0)
    np.testing.assert_allclose(out[0, :, 0], f[0, :, 0])  # along the axis: unchanged
    np.testing.assert_allclose(np.hypot(out[0, :, 1], out[0, :, 2]), 0.1)  # distance to the axis kept
    # right-handed about +X, the angle growing along it: z turns towards -y by 0.3 * x / 2
    ang = np.arctan2(-out[0, :, 1], out[0, :, 2])
    np.testing.assert_allclose(ang[:2], [0.15, 0.3], atol=1e-12)


def test_template_axis_is_base_to_last_centroid():
    np.testing.assert_allclose(template_axis(np.stack([STRIP])), [1, 0, 0])
    np.testing.assert_allclose(template_axis(np.zeros((1, 3, 3))), [0, 1, 0])


# -- the model -----------------------------------------------------------------------------------

def _model(variations=None, templates=None):
    scenes = {Path("a.scn"): Scene([_ca(0.0), _ca(3.0), _ca(6.0)])}
    params = CanopyParams(variations=variations or {})
    return assemble_model(params, scenes, templates or {0: _template()})


def test_each_varied_floret_has_its_own_template_and_the_rest_is_as_before():
    plain = _model()
    m = _model({0: Variation(size=0.1, length=0.1, droop=10.0, twist=10.0, timing=1.0, seed=1)})
    assert m.n_vertices == plain.n_vertices and np.array_equal(m.tri_indices, plain.tri_indices)
    assert np.array_equal(m.vertex_fixed, plain.vertex_fixed)
    keys = [fl.template.key for fl in m.florets]
    assert keys == [(0, "floret", 0), (0, "floret", 1), (0, "floret", 2)]
    tips = [m.templates[k].frames[-1, 4] for k in keys]
    assert len({tuple(t) for t in tips}) == 3  # no two alike
    delays = [fl.delay for fl in m.florets]
    assert len(set(delays)) == 3 and all(abs(d) < 3.5 for d in delays)
    # the developmental time runs behind by the floret's delay; its motion does not
    fl = m.florets[0]
    assert m.developmental_time(fl, 2.0) == pytest.approx(min(max((2.0 - fl.delay) / 4.0, 0.0), 1.0))
    np.testing.assert_array_equal(m.matrix(fl, 2.0), plain.matrix(plain.florets[0], 2.0))
    # the same draws on every call
    again = _model({0: Variation(size=0.1, length=0.1, droop=10.0, twist=10.0, timing=1.0, seed=1)})
    np.testing.assert_array_equal(again.template_x, m.template_x)


def test_the_varied_florets_rest_lengths_are_their_own():
    m = _model({0: Variation(length=0.2, seed=2)})
    for fl in m.florets:
        f = m.templates[fl.template.key].frames[-1]
        ratio = (f[4, 0] - f[0, 0]) / 2.0
        assert ratio == pytest.approx(floret_draws(Variation(length=0.2, seed=2), fl.index)["length"])


def test_petal_variation_needs_petal_weights():
    with pytest.raises(InputError, match="petal weight"):
        _model({0: Variation(petal=0.1)})
    w = np.array([0, 0, 0.5, 0.5, 1, 1], float)
    m = _model({0: Variation(petal=0.2, seed=3)}, {0: _template(petal_weight=w)})
    for fl in m.florets:
        f = floret_draws(Variation(petal=0.2, seed=3), fl.index)["petal"]
        assert m.templates[fl.template.key].frames[-1, 4, 0] == pytest.approx(2.0 * f)
        assert m.templates[fl.template.key].frames[-1, 0, 0] == 0.0


def test_field_table_of_the_spec_is_the_readers():
    text = (Path(__file__).resolve().parents[1] / "formats" / "fcc.md").read_text()
    section = text.split("## Individual florets", 1)[1].split("\n## ", 1)[0]
    rows = [line.split("|")[1].strip().strip("`") for line in section.splitlines() if line.startswith("| `")]
    assert rows == list(FIELDS) + ["seed"]
    for name, (top, unit, _) in FIELDS.items():
        assert f"| `{name}` | {unit if unit != 'fraction' else 'fraction'}" in section
        assert f"[0, {top:g}]" in section
    assert parse_variation(["size", "0.5"]).size == 0.5
