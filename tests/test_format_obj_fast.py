"""The OBJ reader's and writer's numba fast paths (formats/_objtext.py) give what the Python paths
give: the same arrays bit for bit (signed zeros included), the same text byte for byte, the same
error for a bad file (the fast path hands every file outside its form to the Python reader)."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from inflo.formats import obj as O
from inflo.formats.errors import FormatError


def _read(path, fast: bool):
    old = O.FAST_BYTES
    O.FAST_BYTES = 0 if fast else 1 << 60
    try:
        return O.read_obj(path)
    finally:
        O.FAST_BYTES = old


def _same_bits(a, b):
    if a is None or b is None:
        return a is None and b is None
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype != b.dtype or a.shape != b.shape:
        return False
    return a.tobytes() == b.tobytes()


def _assert_same(m, s):
    assert _same_bits(m.vertices, s.vertices)
    assert _same_bits(m.faces, s.faces)
    assert _same_bits(m.normals, s.normals)
    assert _same_bits(m.vertex_colors, s.vertex_colors)
    assert _same_bits(m.face_group, s.face_group)
    assert _same_bits(m.face_material, s.face_material)
    assert m.groups == s.groups and m.materials == s.materials
    assert len(m.lines) == len(s.lines) and all(_same_bits(a, b) for a, b in zip(m.lines, s.lines))


def _both(tmp_path, text: str | bytes, name="t.obj"):
    p = tmp_path / name
    p.write_bytes(text.encode("utf-8") if isinstance(text, str) else text)
    try:
        slow = _read(p, False)
    except FormatError as exc:
        with pytest.raises(FormatError) as got:
            _read(p, True)
        assert str(got.value) == str(exc)
        return None
    fast = _read(p, True)
    _assert_same(fast, slow)
    return fast


def _fast_taken(tmp_path, text: str) -> bool:
    """Whether the kernel took the file (else the Python reader read it)."""
    from inflo.formats._objtext import parse_obj

    return bool(parse_obj(np.frombuffer(text.encode("utf-8"), np.uint8))[0])


CASES = {
    "plain": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "numbers": "v -0 +.5 1.\nv 1e-3 -2.5E+2 0.000001\nv 123456.789012 -0.000000 7\nf 1 2 3\n",
    "tabs, blanks, comments": "# c\n\nv\t0 0 0\nv 1\t0 0 \n   \nv 0 1 0 # trailing\nf 1 2 3\n",
    "comment after numbers": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 # x\n",
    "negative refs": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 1\nf 1 -1 -2\n",
    "normals": "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3\n",
    "normals negative": "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf -3//-3 -2//-2 -1//-1\n",
    "normals other": "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n",
    "groups, materials": "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\ng a b\nusemtl m1\ns 1\nf 1 2 3\n"
                         "g c\nusemtl m2\nf 2 4 3\ng a b\nf 1 2 4\no\nf 1 3 4\n",
    "utf-8 group": "v 0 0 0\nv 1 0 0\nv 0 1 0\ng Blüte_1\nf 1 2 3\n",
    "colours": "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n",
    "w": "v 0 0 0 1\nv 1 0 0 1\nv 0 1 0 1\nf 1 2 3\n",
    "polyline": "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2 3\nl -1 -2\n",
    "polygon": "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 4 3\n",
    "texture refs": "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n",
    "texture and normal refs": "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nvn 0 1 0\n"
                               "f 1/1/2 2/-1/1 3/1/-2\nf -3/1 -2/1 -1/1\n",
    "empty texture ref": "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1/ 2/ 3/\nf 1/1/ 2/1/ 3/1/\n",
    "word texture ref": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/a 2/b 3/c\n",
    "bad normal after texture": "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1/1/2 2/1/1 3/1/1\n",
    "indented v": "v 0 0 0\n  v 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "crlf": "v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n",
    "no final newline": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3",
    "form feed": "v 0 0 0\nv 1 0 0\x0cv 0 1 0\nf 1 2 3\n",
    "line separator": "v 0 0 0\nv 1 0 0\u2028v 0 1 0\nf 1 2 3\n",
    "many digits": "v 0.12345678901234567 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "large exponent": "v 1e300 0 0\nv 1e-300 0 0\nv 4.9e-324 1 0\nf 1 2 3\n",
    "underscore": "v 1_0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "empty": "",
    "vertices only": "v 0 0 0\nv 1 0 0\n",
    # errors: the same message from both
    "nan": "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "inf": "v 0 inf 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "word": "v 0 x 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    "two counts": "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n",
    "five numbers": "v 0 0 0 0 0\nv 1 0 0 0 0\nv 0 1 0 0 0\nf 1 2 3\n",
    "index too large": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
    "index zero": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
    "face before vertex": "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n",
    "two corners": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",
    "bad normal": "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//2 2//1 3//1\n",
    "unknown statement": "v 0 0 0\nv 1 0 0\nv 0 1 0\nfoo 1\nf 1 2 3\n",
    "bare usemtl": "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl\nf 1 2 3\n",
    "bad polyline": "v 0 0 0\nv 1 0 0\nl 1 5\n",
    "bare v": "v\nv 1 0 0\n",
    "nul": "v 0 0 0\x00\nv 1 0 0\n",
    "vn two": "v 0 0 0\nvn 0 1\n",
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_fast_reader_gives_what_the_python_reader_gives(tmp_path, name):
    _both(tmp_path, CASES[name])


def test_the_kernel_takes_the_common_form_and_leaves_the_rest(tmp_path):
    for name in ("plain", "numbers", "normals", "groups, materials", "colours", "negative refs", "no final newline",
                 "texture refs", "texture and normal refs"):
        assert _fast_taken(tmp_path, CASES[name]), name
    for name in ("polygon", "empty texture ref", "word texture ref", "crlf", "form feed", "line separator", "many digits", "nan", "word",
                 "two counts", "underscore", "large exponent", "nul"):
        assert not _fast_taken(tmp_path, CASES[name]), name


def test_a_byte_that_is_not_utf8_is_the_python_readers_error(tmp_path):
    _both(tmp_path, b"v 0 0 0\nv 1 0 0\nv 0 1 0\ng \xff\nf 1 2 3\n")


NUMBER = st.one_of(
    st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False),
    st.integers(-10**9, 10**9).map(lambda k: k / 1e6),
    st.integers(-4096, 4096).map(lambda k: k / 128.0),  # ties of %.6f
    st.sampled_from([0.0, -0.0, 5e-7, -5e-7, 1e-9, -1e-9, 0.0000005, 2.5e-6, 1e9, -4.4e9]),
)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(NUMBER, NUMBER, NUMBER), min_size=1, max_size=60),
       st.sampled_from(["%.6f", "%.7f", "%.3f", "%.9f"]))
def test_fast_writer_writes_the_python_writers_text(tmp_path_factory, rows, fmt):
    x = np.array(rows, dtype=np.float64)
    old = O.FAST_BYTES
    try:
        O.FAST_BYTES = 1 << 60
        slow, slow_text = O.written_vertices(x, fmt)
        O.FAST_BYTES = 0
        fast, fast_text = O.written_vertices(x, fmt)
    finally:
        O.FAST_BYTES = old
    assert fast_text == slow_text
    assert _same_bits(fast, slow)


def test_fast_writer_and_reader_round_trip_a_canopy_like_mesh(tmp_path):
    rng = np.random.default_rng(7)
    n, m = 3000, 5000
    v = rng.normal(size=(n, 3)) * rng.choice([1e-4, 1.0, 300.0], size=(n, 1))
    v[::97] = -0.0
    faces = rng.integers(0, n, size=(m, 3)).astype(np.int32)
    grp = np.sort(rng.integers(0, 40, size=m)).astype(np.int32)
    mesh = O.ObjMesh(v, faces, groups=[f"floret_{k}" for k in range(40)], face_group=grp,
                     materials=["mtl0", "mtl1"], face_material=(grp % 2).astype(np.int32))
    withn = O.ObjMesh(v, faces, normals=rng.normal(size=(n, 3)))
    for k, me in enumerate((mesh, withn)):
        texts = []
        for fast in (False, True):
            old = O.FAST_BYTES
            O.FAST_BYTES = 0 if fast else 1 << 60
            try:
                O.write_obj(tmp_path / f"{k}_{fast}.obj", me, header="h")
            finally:
                O.FAST_BYTES = old
            texts.append((tmp_path / f"{k}_{fast}.obj").read_bytes())
        assert texts[0] == texts[1]
        _both(tmp_path, texts[0], name=f"{k}.obj")
    back = _read(tmp_path / "0_True.obj", True)
    np.testing.assert_allclose(back.vertices, v, atol=5e-7)
    assert (back.faces == faces).all() and (back.face_group == grp).all()


def test_small_files_go_to_the_kernels_once_the_process_has_read_enough(monkeypatch):
    """A file below FAST_BYTES goes to the Python reader until the process has read and written
    2 x FAST_BYTES in all (numba imported): a sequence of small frames is read by the kernel after
    its first frames; without numba imported only files of 16 x FAST_BYTES do."""
    import sys

    import numba  # noqa: F401  (every numerical tool has it imported)

    monkeypatch.setattr(O, "FAST_BYTES", 1000)
    monkeypatch.setattr(O, "_text_seen", 0)
    assert O._fast(1000)  # a large file at once
    monkeypatch.setattr(O, "_text_seen", 0)
    taken = [O._fast(300) for _ in range(10)]
    assert taken == [False] * 6 + [True] * 4
    monkeypatch.setattr(O, "_text_seen", 10**9)
    monkeypatch.delitem(sys.modules, "numba")
    assert not O._fast(15999) and O._fast(16000)
