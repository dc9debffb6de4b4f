"""The viewer page in a real browser, and canopy-view.

A synthetic flower of six petals opening over 100 frames is exported with ``--viewer``; the folder
is served by canopy-view's server on 127.0.0.1 and headless Chromium (Debian's
``chromium-headless-shell`` or ``chromium``, software WebGL) takes screenshots of ``?frame=1`` and
``?frame=100``: the flower is drawn (pixels differ from the page's background) and the two frames
differ; opened without ``?frame`` it plays. The screenshots are kept in ``build/test-artefacts/`` (``INFLO_ARTEFACTS`` elsewhere).
Skipped, saying what to install, where no such browser is found.
"""
from __future__ import annotations

import math
import os
import subprocess
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from conftest import BROWSERS, VIEWER_BACKGROUND, browser_screenshot, find_browser, test_artefacts_folder

from inflo.tools.canopy_export import cli as export_cli
from inflo.tools.canopy_view import cli as view_cli

ROOT = Path(__file__).resolve().parents[1]


def _flower_frames(folder: Path, n_frames: int = 100) -> None:
    """Six petals (strips of quads) on a short stem, opening from upright to spread out."""
    folder.mkdir(parents=True)
    rows, width = 8, 0.35
    for k in range(n_frames):
        t = k / (n_frames - 1)
        lines, faces = ["mtllib materials.mtl"], []
        nv = 0
        for p in range(6):
            phi = p * math.pi / 3
            tilt = math.radians(8 + 72 * t)
            for i in range(rows + 1):
                s = i / rows
                bend = tilt * (0.6 + 0.8 * s)
                r, y = s * math.sin(bend) * 3.0, s * math.cos(bend) * 3.0
                for side in (-1, 1):
                    w = side * width * math.sin(math.pi * min(s + 0.1, 1.0)) * (0.5 + t)
                    x = r * math.cos(phi) - w * math.sin(phi)
                    z = r * math.sin(phi) + w * math.cos(phi)
                    lines.append(f"v {x:.6f} {y:.6f} {z:.6f}")
            for i in range(rows):
                a = nv + 2 * i + 1
                faces += [(a, a + 1, a + 3), (a, a + 3, a + 2)]
            nv += 2 * (rows + 1)
        lines.append("usemtl petal")
        lines += [f"f {a} {b} {c}" for a, b, c in faces]
        lines += ["v 0 0 0.08", "v 0 -2 0.08", "v 0 0 -0.08", "v 0 -2 -0.08", "usemtl stem"]
        lines += [f"f {nv + 1} {nv + 2} {nv + 4}", f"f {nv + 1} {nv + 4} {nv + 3}"]
        (folder / f"frame_{k:04d}.obj").write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def viewer(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("viewer")
    _flower_frames(tmp / "canopy")
    colors = tmp / "colors.toml"
    colors.write_text('petal = [0.95, 0.45, 0.1]\nstem = [0.3, 0.5, 0.2]\n')
    out = tmp / "build" / "viewer" / "flower.glb"
    res = CliRunner().invoke(export_cli.main, ["-q", str(tmp / "canopy"), "--colors", str(colors), "--viewer",
                                               "--title", "Test flower", "-o", str(out)])
    assert res.exit_code == 0, res.output
    return tmp / "build"


def _body(browser: str, url: str, budget_ms: int = 3000) -> str:
    """The page's <body> tag after ``budget_ms`` of (virtual) time."""
    cmd = [browser, "--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
           "--window-size=400,300", f"--virtual-time-budget={budget_ms}", "--dump-dom", url]
    if os.path.basename(browser) != "chromium-headless-shell":
        cmd.insert(1, "--headless=new")
    dom = subprocess.run(cmd, capture_output=True, text=True, timeout=120).stdout
    return dom[dom.find("<body"):dom.find(">", dom.find("<body")) + 1]


def test_the_page_draws_the_flower_and_its_frames_differ(viewer):
    browser = find_browser()
    if browser is None:
        pytest.skip("no headless Chromium found (looked for " + ", ".join(BROWSERS) + "): install it as root with "
                    "'apt-get install -y chromium-headless-shell' (make's set-up does where it can)")
    server = view_cli.serve(view_cli.viewer_folder(viewer))
    try:
        base = f"http://127.0.0.1:{server.server_address[1]}/index.html"
        with urllib.request.urlopen(base, timeout=10) as r:
            assert r.status == 200 and b"Test flower" in r.read()
        with urllib.request.urlopen(base.replace("index.html", "flower.glb"), timeout=10) as r:
            assert r.headers["Content-Type"] == "model/gltf-binary" and r.read(4) == b"glTF"
        out = test_artefacts_folder()
        first = browser_screenshot(browser, base + "?frame=1", out / "canopy_view_frame_1.png")
        last = browser_screenshot(browser, base + "?frame=100", out / "canopy_view_frame_100.png")
        # opened without ?frame it plays. The frames it has played by the time the DOM is dumped
        # depend on how many animation frames a loaded machine draws in the budget (software GL):
        # it says it plays at once, and its frame is past the first within a few longer tries.
        body = _body(browser, base)
        assert 'data-ready="1"' in body and 'data-playing="1"' in body, body
        for budget in (8000, 20000, None):
            if int(body.split('data-frame="')[1].split('"')[0]) > 1 or budget is None:
                break
            body = _body(browser, base, budget)
        assert int(body.split('data-frame="')[1].split('"')[0]) > 1, body
        assert 'data-playing="0"' in _body(browser, base + "?frame=40")
        assert 'data-frame="40"' in _body(browser, base + "?frame=40")
    finally:
        server.shutdown()
        server.server_close()
    h, w, _ = first.shape
    # the model's area: below the title, above the frame bar
    body = (slice(int(0.15 * h), int(0.85 * h)), slice(0, w))
    for shot in (first, last):
        drawn = np.abs(shot[body] - np.array(VIEWER_BACKGROUND)).sum(axis=2) > 30
        assert drawn.mean() > 0.005, f"the flower is not drawn ({drawn.mean():.4f} of the pixels differ)"
    changed = np.abs(first[body] - last[body]).sum(axis=2) > 30
    assert changed.mean() > 0.01, f"frames 1 and 100 look the same ({changed.mean():.4f} of the pixels differ)"
    # the petals' orange is on screen
    orange = (last[..., 0] > 180) & (last[..., 1] > 60) & (last[..., 1] < 170) & (last[..., 2] < 90)
    assert orange.sum() > 200


def test_canopy_view_finds_the_page_or_exits_2(viewer, tmp_path):
    assert view_cli.viewer_folder(viewer) == viewer / "viewer"
    assert view_cli.viewer_folder(viewer / "viewer") == viewer / "viewer"
    res = CliRunner().invoke(view_cli.main, [str(tmp_path), "--no-browser"])
    assert res.exit_code == 2 and "viewer/index.html" in res.output and "Traceback" not in res.output


def test_notebook_embeds_the_served_page(viewer):
    from inflo.tools.canopy_view import notebook

    frame = notebook.show(viewer, frame=7)
    try:
        markup = frame._repr_html_()
        assert markup.startswith('<iframe src="http://127.0.0.1:') and "?frame=7" in markup
        with urllib.request.urlopen(frame.url, timeout=10) as r:
            assert r.status == 200 and b"Test flower" in r.read()
        assert notebook.show(viewer).url.split("/index")[0] == frame.url.split("/index")[0]  # one server
    finally:
        notebook._shutdown_all()
