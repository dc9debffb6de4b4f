"""Shared fixtures for the inflo tests."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

# Mesa's on-disk shader cache off for the tests: make test runs two pytest processes side by side,
# both drawing with llvmpipe (canopy-render), and each test's pictures should not depend on what
# the other process compiled into a shared cache
os.environ.setdefault("MESA_SHADER_CACHE_DISABLE", "true")

REPO = Path(__file__).resolve().parent.parent

CLI_NAMES = [
    "floret-animate",
    "polygonize",
    "phyllotaxis",
    "dimorph",
    "fccompose",
    "subdivide",
    "branch-gen",
    "thyrse",
    "canopy-render",
    "canopy-export",
    "canopy-view",
    "venation",
    "inflo-sweep",
    "petal-grow",
]


def cli_path(name: str) -> str:
    """The console script ``name`` installed beside the running interpreter."""
    return str(Path(sys.executable).parent / name)


def run_cli(name: str, *args, cwd=None, env=None) -> subprocess.CompletedProcess:
    """Run an installed inflo CLI, capturing text output."""
    return subprocess.run(
        [cli_path(name), *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=env,
        timeout=600,
    )


@pytest.fixture
def write(tmp_path):
    """write(name, text) -> Path: a text file under tmp_path."""

    def _write(name: str, text: str) -> Path:
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
        return path

    return _write


def no_partial_files(folder) -> bool:
    """True when no temporary (.part) file of an atomic write is left in ``folder``."""
    return not any(p.name.endswith(".part") for p in Path(folder).rglob("*"))


def species_setting(species: str, quality: str, name: str) -> str:
    """A setting of ``pipelines/<species>/species.toml`` at ``quality`` (its ``[settings]`` or
    ``[draft]``/``[final]`` table), as the species Makefile sees it (``ALPHA`` -> ``"120"``)."""
    from inflo.formats.species import read_species, setting_text

    return setting_text(read_species(REPO / "pipelines" / species / "species.toml").setting(quality, name))


def species_module(species: str, name: str):
    """A species' own script ``pipelines/<species>/<name>.py``, imported by its path (the species
    folders are not packages; shared code is ``inflo.tools.species``)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(f"{species}_{name}", REPO / "pipelines" / species / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def project_copy(root, goldens: bool = False):
    """A project of its own at ``root``: tools, formats, the venv and pyproject.toml linked, the
    pipelines copied (and the goldens, with ``goldens``); its make writes ``root/build``."""
    import shutil

    root = Path(root)
    root.mkdir(parents=True)
    for name in ("tools", "formats", ".venv", "pyproject.toml"):
        (root / name).symlink_to(REPO / name)
    shutil.copytree(REPO / "pipelines", root / "pipelines", ignore=shutil.ignore_patterns("__pycache__", "docs"))
    if goldens:
        shutil.copytree(REPO / "tests" / "golden", root / "tests" / "golden")
    return root


def file_digests(folder, skip=()) -> dict:
    """``relative path -> md5`` of every file under ``folder`` but those named in ``skip``."""
    import hashlib

    folder = Path(folder)
    return {p.relative_to(folder).as_posix(): hashlib.md5(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file() and p.name not in skip}


# ---- a real browser (the viewer page's tests) ------------------------------------------------------
BROWSERS = ("chromium-headless-shell", "chromium", "chromium-browser")
VIEWER_BACKGROUND = (0xF2, 0xF1, 0xEC)  # the viewer page's background colour


def find_browser() -> str | None:
    """A headless Chromium on PATH (Debian's chromium-headless-shell or chromium), or None."""
    import shutil

    for name in BROWSERS:
        path = shutil.which(name)
        if path:
            return path
    return None


def test_artefacts_folder() -> Path:
    """Where tests keep pictures worth looking at: build/test-artefacts/ (INFLO_ARTEFACTS elsewhere)."""
    folder = Path(os.environ.get("INFLO_ARTEFACTS", REPO / "build" / "test-artefacts"))
    folder.mkdir(parents=True, exist_ok=True)
    return folder


test_artefacts_folder.__test__ = False  # a helper, not a test


def browser_screenshot(browser: str, url: str, target: Path):
    """A 640x480 screenshot of ``url`` (software WebGL) saved as ``target``, as an int16 RGB array."""
    import numpy as np
    from PIL import Image

    target.unlink(missing_ok=True)
    cmd = [browser, "--headless", "--no-sandbox", "--disable-gpu-sandbox", "--use-angle=swiftshader",
           "--enable-unsafe-swiftshader", "--hide-scrollbars", "--window-size=640,480",
           "--virtual-time-budget=15000", f"--screenshot={target}", url]
    if os.path.basename(browser) != "chromium-headless-shell":
        cmd.insert(1, "--headless=new")
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert target.is_file(), f"no screenshot from {browser}: {proc.stderr[-2000:]}"
    return np.asarray(Image.open(target).convert("RGB"), dtype=np.int16)


def silhouette_iou(png, still) -> tuple:
    """Blender's render (a PNG with alpha) against canopy-render's still (white background): the
    intersection over union of the two silhouettes, and the share of the render's pixels drawn."""
    import numpy as np
    from PIL import Image

    alpha = np.asarray(Image.open(png).convert("RGBA"))[..., 3] > 127
    drawn = np.any(np.abs(still.astype(int) - 255) > 24, axis=2)
    return float(np.sum(alpha & drawn) / np.sum(alpha | drawn)), float(alpha.mean())


@pytest.fixture(scope="session")
def species_build():
    """``species_build(name)`` -> the species' golden spec (:mod:`inflo.tools.golden`), its draft
    build made once per session by ``make`` (incremental) at the golden manifest's quality and
    targets: the golden-file tests and the species tests that read ``build/<species>`` ask for it
    alike, so neither depends on the other having run first. ``INFLO_GOLDEN_REBUILD=1``: ``make
    -B``; ``INFLO_GOLDEN_NO_BUILD=1``: ``build/<species>`` as it is."""
    import shutil

    from inflo.tools import golden as G

    done: dict = {}

    def get(name):
        if name not in done:
            spec = G.load_species(name, REPO)
            if os.environ.get("INFLO_GOLDEN_NO_BUILD"):
                done[name] = (spec, None)
            elif shutil.which("make") is None:
                done[name] = (spec, "skip")
            else:
                r = G.build_species(spec, rebuild=bool(os.environ.get("INFLO_GOLDEN_REBUILD")))
                err = None
                if r.returncode != 0:
                    tail = "\n".join(((r.stdout or "") + (r.stderr or "")).splitlines()[-25:])
                    err = f"{' '.join(r.args)} failed (exit {r.returncode}):\n{tail}"
                done[name] = (spec, err)
        spec, err = done[name]
        if err == "skip":
            pytest.skip("no make")
        if err:
            pytest.fail(err, pytrace=False)
        return spec

    return get
