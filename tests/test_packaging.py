"""The distribution installs (editable and not) and every CLI answers --help."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import CLI_NAMES, REPO, run_cli


@pytest.mark.parametrize("name", CLI_NAMES)
def test_editable_cli_help(name):
    res = run_cli(name, "--help")
    assert res.returncode == 0, res.stderr
    assert "Usage:" in res.stdout and "--debug" in res.stdout


@pytest.mark.slow
def test_non_editable_install_runs_every_cli(tmp_path):
    """`pip install .` (not editable) into a separate target; its scripts import the installed copy."""
    target = tmp_path / "site"
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation",
         "--target", str(target), str(REPO)],
        check=True, capture_output=True, text=True, timeout=600,
    )
    env = dict(os.environ, PYTHONPATH=str(target), PYTHONNOUSERSITE="1")
    # the installed package is a copy: its modules live under the target, not in the checkout
    where = subprocess.run(
        [sys.executable, "-c", "import inflo.formats, inflo.tools.common.cli as c; print(inflo.formats.__file__); print(c.__file__)"],
        env=env, capture_output=True, text=True, check=True, cwd=tmp_path,
    ).stdout.split()
    assert all(w.startswith(str(target)) for w in where), where
    assert (target / "inflo" / "formats" / "obj.md").exists()
    static = target / "inflo" / "tools" / "canopy_view" / "static"
    for rel in ("index.html", "three/three.module.min.js", "three/LICENSE", "three/addons/controls/OrbitControls.js",
                "three/addons/loaders/GLTFLoader.js", "three/addons/utils/BufferGeometryUtils.js"):
        assert (static / rel).exists(), rel
    for name in CLI_NAMES:
        script = target / "bin" / name
        assert script.exists(), name
        res = subprocess.run([sys.executable, str(script), "--help"], env=env, cwd=tmp_path,
                             capture_output=True, text=True, timeout=120)
        assert res.returncode == 0, (name, res.stderr)
        assert "Usage:" in res.stdout


def test_every_subpackage_is_listed_in_pyproject():
    """Packages are listed by hand (package-dir maps formats/ and tools/ into inflo.*); a new
    subpackage missing from the list would be absent from a non-editable install."""
    import tomllib

    setup = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(setup["packages"])
    # and the data folders (no __init__.py), each with its files in package-data
    found = {"inflo.formats"} | {name for name in setup["package-data"]
                                 if not (REPO / "tools" / Path(*name.split(".")[2:]) / "__init__.py").exists()}
    for init in (REPO / "tools").rglob("__init__.py"):
        if "__pycache__" in init.parts:
            continue
        rel = init.parent.relative_to(REPO / "tools").parts
        found.add(".".join(("inflo", "tools") + rel))
    assert found == listed, f"missing: {sorted(found - listed)}, stale: {sorted(listed - found)}"
