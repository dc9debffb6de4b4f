"""Same bytes on every machine.

OpenBLAS picks its kernels by processor, numpy its SIMD loops, numba its target CPU; a result
that follows any of them differs in its last bits between an Intel Xeon and an AMD EPYC, and
fccompose's collision response grows such bits into visibly different crowded frames. So:

* no result-affecting module calls BLAS or LAPACK (``@``, ``np.dot``, ``np.matmul``,
  ``np.einsum``, ``np.linalg``, ...): an AST scan of ``tools/``, ``formats/`` and the species'
  own scripts under ``pipelines/`` finds none outside the renderer, the plots, the golden diff
  and the species' checks and pictures (``inflo.tools.common.linalg`` does that arithmetic in a
  fixed order);
* draft stages built on this machine under every OpenBLAS kernel it runs (Haswell, Zen,
  SkylakeX), without numpy's AVX-512 and AVX2 loops, and with numba compiling for a generic
  x86-64 are byte-identical to the default build: every file, fccompose's full-precision state
  included.

What is promised, and what is not, is in docs/architecture.md (Determinism).
"""
from __future__ import annotations

import ast
import fnmatch
import os
import shutil
import subprocess
from pathlib import Path

import pytest
from conftest import file_digests, project_copy

ROOT = Path(__file__).resolve().parents[1]

# modules whose numbers never reach a written result: the OpenGL renderer (pictures are not
# compared), matplotlib plots, the golden diff's tolerances, the Blender probe; and the
# fixed-order module itself
EXEMPT = ("tools/canopy_render/", "tools/golden/", "tools/canopy_export/blender_probe.py",
          "tools/common/linalg.py")
EXEMPT_NAMES = ("plot.py",)
# the species' scripts under pipelines/ whose numbers reach no stage output: the checks (check_*.py:
# they measure the built frames and print check.txt, which no stage reads) and the pictures (sheets,
# close-ups, side-by-side comparisons and the examples' figures: PNGs, and OBJ cut-outs in a
# temporary folder for the renderer; pictures are not compared). Every other script there writes
# stage inputs or outputs (key poses, scenes, RBA frames, weights, contours) and is scanned.
PIPELINE_EXEMPT = ("check_*.py", "compare.py", "closeup.py", "sheet.py", "growth_beside.py", "growth_fig13.py",
                   "figures.py", "development.py")
BANNED = {"dot", "matmul", "inner", "vdot", "vecdot", "matvec", "vecmat", "tensordot", "einsum", "einsum_path",
          "cov", "corrcoef", "polyfit", "lstsq", "kron", "linalg"}
"""numpy/scipy attributes that reach BLAS/LAPACK or reduce with SIMD accumulators"""


def blas_calls(source: str, rel: str) -> list[str]:
    """``path:line: what`` for each BLAS-reaching expression of a module: the ``@`` operator and
    ``np.<banned>`` / ``scipy.<banned>`` / ``x.dot(...)``, and an import that would hide one
    (``from numpy.linalg import norm``, ``from numpy import dot``, ``import scipy.linalg``). A line
    may carry ``# fixed-order: <reason>`` when the call provably does not reach BLAS (a
    scipy.sparse product)."""
    lines = source.splitlines()
    out = []
    for node in ast.walk(ast.parse(source)):
        what = None
        if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] in ("numpy", "scipy"):
            parts = node.module.split(".")[1:] + [a.name for a in node.names]
            if any(x in BANNED for x in parts):
                what = f"from {node.module} import ..."
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] in ("numpy", "scipy") and any(x in BANNED for x in a.name.split(".")[1:]):
                    what = f"import {a.name}"
        elif isinstance(node, (ast.BinOp, ast.AugAssign)) and isinstance(node.op, ast.MatMult):
            what = "the @ operator"
        elif isinstance(node, ast.Attribute) and node.attr in BANNED:
            if isinstance(node.value, ast.Name) and node.value.id in ("np", "numpy", "scipy"):
                what = f"np.{node.attr}"
            elif node.attr == "dot" and not (isinstance(node.value, ast.Name) and node.value.id == "la"):
                what = ".dot()"
        if what and "fixed-order:" not in lines[node.lineno - 1]:
            out.append(f"{rel}:{node.lineno}: {what}: {lines[node.lineno - 1].strip()}")
    return out


def _pipeline_scripts() -> list[Path]:
    """The species' scripts under pipelines/ that the scan covers (all but PIPELINE_EXEMPT)."""
    return [p for p in sorted((ROOT / "pipelines").rglob("*.py"))
            if not any(fnmatch.fnmatch(p.name, pat) for pat in PIPELINE_EXEMPT)]


def test_no_blas_in_result_paths():
    found = []
    for base in ("tools", "formats"):
        for path in sorted((ROOT / base).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            if rel.startswith(EXEMPT) or path.name in EXEMPT_NAMES:
                continue
            found += blas_calls(path.read_text(), rel)
    for path in _pipeline_scripts():
        found += blas_calls(path.read_text(), path.relative_to(ROOT).as_posix())
    assert not found, ("BLAS/LAPACK-backed arithmetic in result paths (use inflo.tools.common.linalg):\n"
                       + "\n".join(found))


def test_the_pipeline_exemptions_are_checks_and_pictures():
    """Every exempt pattern names a script that exists (no stale exemption), the scan still covers
    the scripts that write stage inputs and outputs, and no exempt script writes a scene, an RBA
    frame, weights, key poses, a contour, a function or canopy parameters (they write PNGs, and OBJ
    cut-outs for the renderer in a temporary folder)."""
    scripts = sorted((ROOT / "pipelines").rglob("*.py"))
    for pat in PIPELINE_EXEMPT:
        assert any(fnmatch.fnmatch(p.name, pat) for p in scripts), f"PIPELINE_EXEMPT: {pat} matches no script"
    scanned = {p.relative_to(ROOT).as_posix() for p in _pipeline_scripts()}
    for rel in ("pipelines/dyssodia/compose_heads.py", "pipelines/dyssodia/spread_rays.py",
                "pipelines/yarrow/corymb_heads.py", "pipelines/orlaya/involucres.py", "pipelines/lily/make_keys.py"):
        assert rel in scanned
    writers = ("write_scn", "write_rba", "write_rba_sequence", "write_floret", "write_con", "write_cset", "write_func",
               "write_fset", "write_fcc", "write_pc2", "write_bezier_surface", "write_ids", "write_any")
    for p in scripts:
        if p.relative_to(ROOT).as_posix() not in scanned:
            text = p.read_text()
            assert not any(w + "(" in text for w in writers), f"{p.relative_to(ROOT)} is exempt but writes a stage file"


def test_the_scan_finds_what_it_bans():
    src = ("import numpy as np\nx = a @ b\ny = np.linalg.norm(v)\nz = np.einsum('ij,ij->i', a, a)\n"
           "w = v.dot(u)\nq = s @ v  # fixed-order: scipy.sparse\nr = np.add.reduce(v * v)\nt = la.dot(v, u)\n"
           "from numpy.linalg import norm\nfrom numpy import dot\nimport scipy.linalg\nfrom scipy import ndimage\n"
           "u = np.vecdot(a, b)\nfrom inflo.tools.common import linalg as la\n")
    found = blas_calls(src, "m.py")
    assert sorted(int(f.split(":")[1]) for f in found) == [2, 3, 4, 5, 9, 10, 11, 13]


# -- the same build under other kernels ----------------------------------------------------------


def _cpu_flags() -> set[str]:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("flags"):
                return set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return set()


def _numpy_dispatch() -> list[str]:
    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    return [f for f in __cpu_dispatch__ if __cpu_features__.get(f)]


def _openblas_core() -> str | None:
    """The kernel OpenBLAS picked on this processor (numpy's bundled library, as loaded), or None
    where it cannot be asked."""
    try:
        import ctypes

        import numpy  # noqa: F401  (loads OpenBLAS)
        paths = sorted({line.split()[-1] for line in Path("/proc/self/maps").read_text().splitlines()
                        if "openblas" in line.lower() and line.split()[-1].startswith("/")})
        for path in paths:
            lib = ctypes.CDLL(path)
            for name in ("scipy_openblas_get_corename64_", "scipy_openblas_get_corename", "openblas_get_corename"):
                fn = getattr(lib, name, None)
                if fn is not None:
                    fn.restype = ctypes.c_char_p
                    return fn().decode()
    except (OSError, AttributeError, ValueError):
        pass
    return None


def _variants() -> list:
    flags = _cpu_flags()
    avx2 = {"avx2", "fma"} <= flags
    avx512 = "avx512f" in flags
    dispatch = _numpy_dispatch()
    native = (_openblas_core() or "").lower()
    out = []
    for kernel, ok in (("Haswell", avx2), ("Zen", avx2), ("SkylakeX", avx512)):
        # the default build runs the kernel OpenBLAS picks here: that variant would be the same build
        why = (f"this processor cannot run {kernel}" if not ok else
               f"the default build runs {kernel} already" if kernel.lower() == native else "")
        out.append(pytest.param({"OPENBLAS_CORETYPE": kernel}, id=f"openblas-{kernel}",
                                marks=pytest.mark.skipif(bool(why), reason=why or "-")))
    out.append(pytest.param({"NPY_DISABLE_CPU_FEATURES": " ".join(dispatch), "OPENBLAS_CORETYPE": "Sandybridge"},
                            id="numpy-baseline-simd",
                            marks=pytest.mark.skipif(not dispatch, reason="numpy dispatches nothing here")))
    out.append(pytest.param({"NUMBA_CPU_NAME": "generic"}, id="numba-generic"))
    return out


STAGES = [("dyssodia", ["canopy"]), ("eustoma", ["flowers"]), ("lilac", ["canopy"])]
"""draft builds between them running every stage tool but the renderer and exporter: floret-animate,
polygonize, phyllotaxis, dimorph, fccompose (six crowded heads pressed together: 145,000
collisions and florets retreated over the run, with its full-precision state file), petal-grow,
thyrse and branch-gen. (The gaillardia's canopy, the crowded head that diverged on other kernels
before, took 2.5 min a build here, six builds a run; the dyssodia's crowds more in a tenth of it.)"""


def _build(root: Path, env: dict) -> Path:
    """A project of its own (conftest.project_copy) whose build/ the species Makefiles write under
    ``env``."""
    project_copy(root)
    full = dict(os.environ, **env, QUALITY="draft", PYTHONHASHSEED="0")
    full.pop("MAKEFLAGS", None)
    for species, targets in STAGES:
        res = subprocess.run(["make", "-s", "-C", str(root / "pipelines" / species), "QUALITY=draft", *targets],
                             env=full, capture_output=True, text=True)
        assert res.returncode == 0, f"{species} under {env}:\n{res.stdout[-3000:]}\n{res.stderr[-3000:]}"
    return root / "build"


def _digests(build: Path) -> dict[str, str]:
    return file_digests(build, skip=("log.csv", "run.json"))  # timings


@pytest.fixture(scope="module")
def default_build(tmp_path_factory):
    if shutil.which("make") is None or not (ROOT / ".venv" / "bin" / "fccompose").exists():
        pytest.skip("needs make and the repository's .venv (make test sets both up)")
    return _digests(_build(tmp_path_factory.mktemp("default") / "root", {}))


@pytest.mark.slow
@pytest.mark.parametrize("env", _variants())
def test_stage_outputs_are_byte_identical_under(env, default_build, tmp_path):
    if "NUMBA_CPU_NAME" in env:  # compile afresh for that target, away from the sources' cache
        env = dict(env, NUMBA_CACHE_DIR=str(tmp_path / "numba-cache"))
    got = _digests(_build(tmp_path / "root", env))
    assert sorted(got) == sorted(default_build)
    differ = [k for k in default_build if got[k] != default_build[k]]
    assert not differ, f"{len(differ)} of {len(got)} files differ under {env}: {differ[:10]}"
