"""``canopy-view``: serve a build's viewer page on 127.0.0.1 and open it in the browser.

Usage::

    canopy-view BUILD_DIR [--port 0] [--frame N] [--no-browser]

``BUILD_DIR`` is a species build (``build/lily``, whose ``viewer/`` folder ``make lily`` writes)
or a viewer folder itself (one holding ``index.html``). Stop it with Ctrl-C.
"""
from __future__ import annotations

import functools
import http.server
import threading
import webbrowser
from pathlib import Path

import click

from inflo.formats.errors import InputError
from inflo.tools.common.cli import inflo_command

__all__ = ["main", "viewer_folder", "serve"]


def viewer_folder(build_dir) -> Path:
    """The folder holding the page: ``BUILD_DIR/viewer`` or ``BUILD_DIR`` itself."""
    p = Path(build_dir)
    for folder in (p / "viewer", p):
        if (folder / "index.html").is_file():
            return folder
    raise InputError(f"{build_dir}: expected a build folder with viewer/index.html (make <species> writes it) "
                     f"or a viewer folder, found neither")


class _Quiet(http.server.SimpleHTTPRequestHandler):
    extensions_map = {**http.server.SimpleHTTPRequestHandler.extensions_map,
                      ".js": "text/javascript", ".glb": "model/gltf-binary"}

    def log_message(self, format, *args):
        pass


def serve(folder, port: int = 0) -> http.server.ThreadingHTTPServer:
    """A server of ``folder`` on 127.0.0.1 (``port`` 0: a free one), running in a daemon thread."""
    handler = functools.partial(_Quiet, directory=str(folder))
    try:
        server = http.server.ThreadingHTTPServer(("127.0.0.1", port), handler)
    except OSError as exc:
        raise InputError(f"--port {port}: expected a free port on 127.0.0.1, found {exc.strerror or exc}") from None
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


@inflo_command("canopy-view", help="Serve a build's viewer page (viewer/index.html) on 127.0.0.1 and open it.")
@click.argument("build_dir", type=click.Path(file_okay=False))
@click.option("--port", type=click.IntRange(0, 65535), default=0, show_default=True, help="Port (0: any free one).")
@click.option("--frame", type=click.IntRange(min=1), default=None, help="Open at this frame, paused.")
@click.option("--no-browser", is_flag=True, help="Only serve; print the address.")
def main(build_dir, port, frame, no_browser, quiet, debug):
    folder = viewer_folder(build_dir)
    server = serve(folder, port)
    url = f"http://127.0.0.1:{server.server_address[1]}/index.html" + (f"?frame={frame}" if frame else "")
    click.echo(f"canopy-view: serving {folder} at {url} (Ctrl-C stops)", err=True)
    if not no_browser:
        webbrowser.open(url)
    try:
        threading.Event().wait()
    finally:
        server.shutdown()
        server.server_close()
