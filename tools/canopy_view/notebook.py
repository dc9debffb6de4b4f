"""The viewer page in a Jupyter notebook: ``show(BUILD_DIR)`` as a cell's last expression.

The folder is served on 127.0.0.1 (one server per folder, kept for the kernel's life) and the page
is embedded as an iframe (``_repr_html_``, no IPython import needed). The notebook's browser must
run on the same machine as the kernel (a local Jupyter), as with ``canopy-view``.
"""
from __future__ import annotations

import html

from .cli import serve, viewer_folder

__all__ = ["show", "ViewerFrame"]

_SERVERS: dict = {}


class ViewerFrame:
    """An iframe of a served viewer page; notebooks display it through ``_repr_html_``."""

    def __init__(self, url: str, width: str, height: int):
        self.url, self.width, self.height = url, width, height

    def _repr_html_(self) -> str:
        return (f'<iframe src="{html.escape(self.url)}" width="{html.escape(self.width)}" height="{int(self.height)}" '
                f'style="border:0" title="inflo viewer"></iframe>')

    def __repr__(self) -> str:
        return f"ViewerFrame({self.url!r})"


def show(build_dir, *, frame: int | None = None, width: str = "100%", height: int = 480) -> ViewerFrame:
    """Serve ``build_dir``'s viewer page (``BUILD_DIR/viewer`` or a viewer folder) and embed it."""
    folder = viewer_folder(build_dir).resolve()
    server = _SERVERS.get(folder)
    if server is None:
        server = _SERVERS[folder] = serve(folder)
    url = f"http://127.0.0.1:{server.server_address[1]}/index.html" + (f"?frame={int(frame)}" if frame else "")
    return ViewerFrame(url, width, height)


def _shutdown_all() -> None:
    for server in _SERVERS.values():
        server.shutdown()
        server.server_close()
    _SERVERS.clear()


