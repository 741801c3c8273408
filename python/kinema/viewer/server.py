"""The viewer on a local web server: the page at ``/`` and the frames at ``/data.bin``, on
127.0.0.1 only, to requests whose Host is 127.0.0.1:PORT or localhost:PORT (any other is
refused with 403, so that a web page cannot reach the data by DNS rebinding)."""

from __future__ import annotations

import os
import sys
import threading
import webbrowser
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

import numpy as np

from .page import SERVE_MAX_BYTES, bundle, pack, page


def _binary(packed: Any) -> tuple[bytes, dict[str, list[int] | None]]:
    """positions, speed, radii (float32), springs (int32), alive and colors (uint8) one after the other,
    each starting at a multiple of 4 bytes; the layout is [byte offset, element count], None
    for what the trajectory has not."""
    layout: dict[str, list[int] | None] = {}
    blobs, offset = [], 0
    for name, dtype in (("positions", "<f4"), ("speed", "<f4"), ("radii", "<f4"), ("springs", "<i4"), ("alive", "u1"), ("colors", "u1")):
        array = getattr(packed, name)
        if array is None:
            layout[name] = None
            continue
        layout[name] = [offset, int(array.size)]
        blob = np.ascontiguousarray(array, dtype=dtype).tobytes()
        blob += bytes(-len(blob) % 4)
        blobs.append(blob)
        offset += len(blob)
    return b"".join(blobs), layout


def _handler(routes: dict[str, tuple[str, bytes]]) -> type[BaseHTTPRequestHandler]:
    class Handler(BaseHTTPRequestHandler):
        def _host_is_ours(self) -> bool:
            """DNS rebinding: a page of evil.example whose name is made to resolve to 127.0.0.1
            reaches this server with ``Host: evil.example:PORT``; only our own names are served."""
            port = self.server.server_address[1]
            return (self.headers.get("Host") or "").strip().lower() in (f"127.0.0.1:{port}", f"localhost:{port}")

        def do_GET(self) -> None:  # noqa: N802 (http.server's name)
            if not self._host_is_ours():
                port = self.server.server_address[1]
                body = f"forbidden: this viewer answers only to http://127.0.0.1:{port}/ and http://localhost:{port}/\n".encode()
                self.send_response(403)
                self.send_header("Content-Type", "text/plain; charset=utf-8")
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)
                return
            route = routes.get(self.path.split("?", 1)[0].split("#", 1)[0])
            if route is None:
                self.send_error(404)
                return
            kind, body = route
            self.send_response(200)
            self.send_header("Content-Type", kind)
            self.send_header("Content-Length", str(len(body)))
            self.send_header("Cache-Control", "no-store")
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, format: str, *args: Any) -> None:
            pass

    return Handler


def _gui_available() -> bool:
    # Without a display, Python's webbrowser falls back to text browsers (lynx, w3m) that
    # would take over the terminal; a WebGL page needs a graphical one.
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def serve(
    traj: Any, open_browser: bool = True, port: int = 0, *, title: str = "kinema", max_bytes: int = SERVE_MAX_BYTES, announce: bool = True
) -> tuple[str, ThreadingHTTPServer]:
    """Serve the viewer for ``traj`` on 127.0.0.1 (``port`` 0: a free one) from a daemon
    thread; print the URL (unless ``announce`` is False) and open it in the user's browser when ``open_browser`` and a
    graphical browser exists (no error when none does). Returns ``(url, server)``; stop with
    ``server.shutdown()``, or keep the process alive while the page is in use (the thread is
    ``server.thread``). Frames, then particles, are left out by strides when the frame data
    is over ``max_bytes`` (a ``ViewerWarning`` says so)."""
    bundle()  # fail before any work when the script is not built
    packed = pack(traj, max_bytes)
    data, layout = _binary(packed)
    html = page(dict(packed.meta, source="data.bin", layout=layout), title).encode("utf-8")
    routes = {"/": ("text/html; charset=utf-8", html), "/index.html": ("text/html; charset=utf-8", html), "/data.bin": ("application/octet-stream", data)}
    server = ThreadingHTTPServer(("127.0.0.1", port), _handler(routes))
    server.daemon_threads = True
    thread = threading.Thread(target=server.serve_forever, name="kinema-viewer", daemon=True)
    thread.start()
    server.thread = thread  # type: ignore[attr-defined]
    url = f"http://127.0.0.1:{server.server_address[1]}/"
    if announce:  # (the `kinema view` command prints its own line with the URL)
        print(f"kinema viewer: {url}", flush=True)
    if open_browser and _gui_available():
        try:
            webbrowser.open(url)
        except webbrowser.Error:
            pass
    return url, server
