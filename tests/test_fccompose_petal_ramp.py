"""A petal factor that grows with the floret's development (fcc ``petal ramp: id from to``): the
kernel on a tiny template, the key (read, written, refused), and a composed canopy whose grown
floret keeps its bud's size and opens to the whole factor."""
from __future__ import annotations

import numpy as np
import pytest
from test_petal_growth import N_FRAMES, _floret_files, petal_against_pre_grown

from inflo.formats.errors import FormatError
from inflo.formats.fcc import read_fcc, write_fcc
from inflo.tools.fccompose.kernels import ramped_petals
from inflo.tools.fccompose.model import Template


def _smoothstep(t):
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def test_ramped_petals_kernel_on_a_tiny_template():
    """Three vertices over five frames, weights 1, 0.5, 0; factor 3 ramped over u in [0.25, 0.75]:
    frames 0 and 1 (u 0, 0.25) as read, frame 2 (u 0.5) grown by 1 + w (3 - 1) / 2, frames 3 and 4
    (u 0.75, 1) by the whole factor; the unweighted vertex never moves."""
    base = np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]])
    frames = np.stack([base * (1.0 + 0.1 * s) for s in range(5)])
    w = np.array([1.0, 0.5, 0.0])
    out = np.empty_like(frames)
    ramped_petals(frames, w, 3.0, 0.25, 0.75, out)
    for s, g in enumerate([0.0, 0.0, 0.5, 1.0, 1.0]):
        np.testing.assert_allclose(out[s], frames[s] * (1.0 + w * 2.0 * g)[:, None], rtol=0, atol=1e-15)
    np.testing.assert_array_equal(out[0], frames[0])
    np.testing.assert_array_equal(out[4], frames[4] * (1.0 + w * 2.0)[:, None])
    np.testing.assert_array_equal(out[:, 2], frames[:, 2])


def test_ramped_petals_is_a_smoothstep_and_a_single_frame_is_open():
    frames = np.ones((11, 1, 3))
    out = np.empty_like(frames)
    ramped_petals(frames, np.array([1.0]), 2.0, 0.0, 1.0, out)
    u = np.linspace(0.0, 1.0, 11)
    np.testing.assert_allclose(out[:, 0, 0], 1.0 + _smoothstep(u), atol=1e-15)
    one = np.empty((1, 1, 3))
    ramped_petals(np.ones((1, 1, 3)), np.array([1.0]), 4.0, 0.2, 0.6, one)
    np.testing.assert_array_equal(one, 4.0)


def test_with_petals_ramps_only_with_a_ramp():
    """Without a ramp the template grows every frame by the whole factor (bit for bit as before);
    with one, the first frame is the bud as read and the last the whole factor."""
    frames = np.stack([np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]) * (1 + s) for s in range(3)])
    t = Template.from_frames(0, frames, [[0, 1, 2]])
    t.petal_weight = np.array([1.0, 0.25, 0.0])
    plain = t.with_petals(5.0)
    np.testing.assert_array_equal(plain.frames, frames * (1.0 + t.petal_weight * 4.0)[None, :, None])
    t.petal_ramp = (0.0, 1.0)
    ramped = t.with_petals(5.0)
    np.testing.assert_array_equal(ramped.frames[0], frames[0])
    np.testing.assert_array_equal(ramped.frames[2], plain.frames[2])
    np.testing.assert_allclose(ramped.frames[1], frames[1] * (1.0 + t.petal_weight * 2.0)[:, None])
    assert ramped.key == plain.key == (0, 5.0)
    assert t.with_petals(1.0) is t


def test_fcc_petal_ramp_round_trips(tmp_path):
    (tmp_path / "a.fcc").write_text("animation: 1 1 1 1 anim\npetal weight: 1 big.petals\npetal ramp: 1 0 0.6\n"
                                    "scene file path: s.scn\n")
    p = read_fcc(tmp_path / "a.fcc")
    assert dict(p.petal_ramps) == {1: (0.0, 0.6)}
    write_fcc(tmp_path / "b.fcc", p)
    assert "petal ramp: 1 0.0 0.6" in (tmp_path / "b.fcc").read_text()
    assert read_fcc(tmp_path / "b.fcc") == p
    assert dict(read_fcc(tmp_path / "b.fcc").petal_ramps) == {1: (0.0, 0.6)}


@pytest.mark.parametrize("line, expected", [
    ("petal ramp: 1 0.6 0.2", "two fractions 0 <= from < to <= 1"),
    ("petal ramp: 1 0.5 0.5", "two fractions 0 <= from < to <= 1"),
    ("petal ramp: 1 -0.1 0.5", "two fractions 0 <= from < to <= 1"),
    ("petal ramp: 1 0 1.5", "two fractions 0 <= from < to <= 1"),
    ("petal ramp: 1 0 nan", "a number"),
    ("petal ramp: 1 0", "an id and two fractions"),
    ("petal ramp: 2 0 1", "the id of an 'animation' or 'obj' entry"),
    ("petal ramp: 0 0 1", "a 'petal weight' line for id 0"),
    ("petal ramp: 1 0 1\npetal ramp: 1 0 0.5", "one 'petal ramp' line per id"),
])
def test_fcc_petal_ramp_bad_lines_are_refused(tmp_path, line, expected):
    (tmp_path / "a.fcc").write_text("animation: 0 1 1 1 anim\nanimation: 1 1 1 1 anim\n"
                                    f"petal weight: 1 big.petals\n{line}\n")
    with pytest.raises(FormatError, match=expected.replace("(", r"\(").replace(")", r"\)")):
        read_fcc(tmp_path / "a.fcc")


def test_a_ramped_petal_factor_keeps_the_bud_and_opens_to_the_whole_factor(tmp_path):
    """Floret 0 '#@ petal: 1.8' with 'petal ramp: 0 0.4 1', floret 1 plain: the same canopy as two
    plain placements of two animations, the first one's OBJ frame s grown beforehand by
    1 + w (1.8 - 1) g(s / 5); its first frame is its bud as read, its last 1.8 x as wide."""
    frames, faces, fixed, w = _floret_files(tmp_path)  # the animation and its petal weights
    w = np.round(w, 6)
    g = _smoothstep((np.arange(N_FRAMES) / (N_FRAMES - 1) - 0.4) / 0.6)
    grown = [f * (1.0 + w * 0.8 * g[s])[:, None] for s, f in enumerate(frames)]
    out = petal_against_pre_grown(tmp_path, faces, grown, extra="petal ramp: 0 0.4 1\n")
    for a, b in zip(out["petal"], out["pre"]):
        np.testing.assert_allclose(a.vertices, b.vertices, atol=2e-6)  # OBJ rounding (6 decimals)
    n = len(frames[0])
    first, last = out["petal"][0].vertices, out["petal"][-1].vertices
    np.testing.assert_allclose(first[:n], frames[0], atol=2e-6)  # the bud as read
    r0 = np.hypot(last[:n, 0], last[:n, 2]).max()
    r1 = np.hypot(last[n:, 0] - 3.5, last[n:, 2]).max()
    assert r0 / r1 == pytest.approx(1.8, rel=1e-5)
