"""The viewer on a local web server: the page at ``/`` and the frames at ``/data.bin``, on
127.0.0.1 only, to requests whose Host is 127.0.0.1:PORT or localhost:PORT (any other is
refused with 403, so that a web page cannot reach the data by DNS rebinding).

One thread serves every connection, whatever their number: the answers are bytes already in
memory, so serving is reading requests and handing bytes to sockets, which a selector
(epoll) does without blocking on any one client. A client costs a socket, never a thread, so
idle or slow clients cannot use up threads, nor hold back the others. A connection that has
not sent its whole request within ``IDLE_TIMEOUT_S`` of being accepted is closed, and so is
one that takes none of its answer for that long; at most ``MAX_CONNECTIONS`` are open at
once (beyond, the oldest idle one is closed: see ``MAX_CONNECTIONS``), and up to
``LISTEN_BACKLOG`` more wait in the kernel to be accepted."""

from __future__ import annotations

import collections
import errno
import io
import os
import selectors
import socket
import sys
import threading
import time
import webbrowser
from http.server import BaseHTTPRequestHandler, HTTPServer
from typing import Any

import numpy as np

from .page import SERVE_MAX_BYTES, bundle, pack, page

IDLE_TIMEOUT_S = 10.0
"""s: the longest a connection may take from being accepted to the blank line that ends its
request's headers (slowloris: a request sent a byte at a time gets no more), and the longest
a client may leave its answer unread (not one byte taken) before the connection is closed."""

MAX_CONNECTIONS = 512
"""Connections open at once (each a file descriptor); when all are taken, a new one replaces
the oldest whose answer is all sent, else the oldest that has sent nothing yet, and with
neither it waits in the listen backlog until one closes."""

LISTEN_BACKLOG = 1024
"""Connections the kernel completes and queues before they are accepted (listen()'s backlog;
the kernel caps it at net.core.somaxconn, 4096 on Linux since 5.4). http.server's 5 made
clients time out when a few hundred connected at once."""

MAX_REQUEST_BYTES = 65_536
"""Bytes of request line and headers read before the request is refused with 431."""

_RECV_BYTES = 65_536  # read by one recv() call
_SEND_BYTES = 1 << 20  # offered to one send() call (the kernel takes what its buffer has room for)
_TURN_BYTES = 4 << 20  # sent to one client before the other ready ones get their turn
_ACCEPT_BATCH = 64  # connections accepted before the others' events are seen to
_TICK_S = 0.1  # s: how often deadlines are checked while connections are open
_RETRY_ACCEPT_S = 0.1  # s: the pause in accepting when the process has run out of file descriptors
_TOO_LARGE = (
    b"HTTP/1.0 431 Request Header Fields Too Large\r\nContent-Type: text/plain\r\nContent-Length: 24\r\nConnection: close\r\n\r\nrequest header too large"
)

_READING, _WRITING, _DRAINING = "reading", "writing", "draining"


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


class _Connection:
    """One client's socket and where it stands: ``reading`` its request (the bytes so far in
    ``received``), ``writing`` the answer (``outbox``, views of the bytes still to send), or
    ``draining`` (answer sent and our side shut: what the client still sends is read and
    dropped until it closes, so that the kernel does not reset the connection, losing the
    answer's tail, over unread bytes). ``deadline``: time.monotonic() by which the next step
    must happen, or the connection is closed."""

    __slots__ = ("address", "closed", "deadline", "fd", "outbox", "received", "sock", "state")

    def __init__(self, sock: socket.socket, address: Any, deadline: float) -> None:
        self.sock = sock
        self.fd = sock.fileno()
        self.address = address
        self.deadline = deadline
        self.state = _READING
        self.received = bytearray()
        self.outbox: collections.deque[memoryview] = collections.deque()
        self.closed = False


class _Outbox(io.RawIOBase):
    """A handler's ``wfile``: keeps what is written, as views (the route's bytes are not
    copied), for the server to send as the client takes it."""

    def __init__(self) -> None:
        super().__init__()
        self.chunks: list[memoryview] = []

    def writable(self) -> bool:
        return True

    def write(self, b: Any) -> int:
        data = b if isinstance(b, bytes) else bytes(b)  # a mutable buffer may be reused by the caller
        if data:
            self.chunks.append(memoryview(data))
        return len(data)


class _QueuedHandler(BaseHTTPRequestHandler):
    """A request handler run by :class:`ViewerServer`'s thread on a request already read whole:
    it reads from the bytes received and writes into an :class:`_Outbox`, never the socket,
    so it never waits on the client."""

    def setup(self) -> None:
        self.connection = self.request.sock
        self.rfile = io.BytesIO(self.request.received)
        self.wfile = _Outbox()

    def finish(self) -> None:
        self.request.outbox = collections.deque(self.wfile.chunks)


class ViewerServer(HTTPServer):
    """An HTTP server of one thread for any number of clients (see the module's docstring):
    ``serve_forever()`` runs it, ``shutdown()`` (from another thread) stops it and closes the
    open connections, ``server_close()`` closes the listening socket (and stops it too). Requests are answered
    by ``RequestHandlerClass``, a :class:`_QueuedHandler`, one request per connection
    (HTTP/1.0: the connection is closed after the answer). ``idle_timeout``: s (see
    ``IDLE_TIMEOUT_S``); ``max_connections``: see ``MAX_CONNECTIONS``."""

    request_queue_size = LISTEN_BACKLOG

    def __init__(
        self,
        server_address: tuple[str, int],
        handler: type[_QueuedHandler],
        *,
        idle_timeout: float = IDLE_TIMEOUT_S,
        max_connections: int = MAX_CONNECTIONS,
    ) -> None:
        if not (isinstance(idle_timeout, (int, float)) and 0 < idle_timeout < float("inf")):
            raise ValueError(f"idle_timeout = {idle_timeout!r} is invalid: use a number of seconds > 0")
        if not (isinstance(max_connections, int) and max_connections >= 1):
            raise ValueError(f"max_connections = {max_connections!r} is invalid: use an integer >= 1")
        self.idle_timeout = float(idle_timeout)
        self.max_connections = max_connections
        # (all of the state first: a bind that fails, the port taken, calls server_close())
        self._connections: dict[int, _Connection] = {}  # by file descriptor, oldest first
        self._selector: selectors.BaseSelector | None = None
        self._listening = False
        self._accept_again = 0.0  # time.monotonic() from which accepting resumes (paused when full)
        self._shutdown_request = False
        self._closed = False  # server_close() was called
        self._is_shut_down = threading.Event()
        self._wake_r, self._wake_w = socket.socketpair()  # shutdown() writes a byte: select() returns at once
        self._wake_r.setblocking(False)
        self._wake_w.setblocking(False)
        super().__init__(server_address, handler)  # binds and listens (closes the socket if that fails)
        self.socket.setblocking(False)

    @property
    def open_connections(self) -> int:
        """Client connections open now (accepted, not yet closed)."""
        return len(self._connections)

    def serve_forever(self, poll_interval: float = 0.5) -> None:
        """Accept, read, answer and close connections until ``shutdown()`` or
        ``server_close()``; then close those still open. ``poll_interval``: s between looks at
        the shutdown flag while nothing happens (``shutdown()`` also wakes the loop at once)."""
        self._is_shut_down.clear()
        selector = selectors.DefaultSelector()
        self._selector = selector
        try:
            selector.register(self._wake_r, selectors.EVENT_READ, None)
            next_tick = time.monotonic() + _TICK_S
            while not (self._shutdown_request or self._closed):
                now = time.monotonic()
                self._listen(now)
                timeout = max(0.0, next_tick - now) if self._connections or not self._listening else poll_interval
                for key, events in selector.select(timeout):
                    if key.data is None:
                        self._drain_wake()
                    elif key.data is self:
                        self._accept()
                    elif not key.data.closed:
                        self._step(key.data, events)
                now = time.monotonic()
                if now >= next_tick:
                    next_tick = now + _TICK_S
                    for conn in [c for c in self._connections.values() if c.deadline <= now]:
                        self._close(conn)
        finally:
            self._close_all()
            self._listening = False
            self._selector = None
            selector.close()
            self._shutdown_request = False
            if self._closed:
                self._close_wake()
            self._is_shut_down.set()

    def shutdown(self) -> None:
        """Stop ``serve_forever()`` and wait until it has returned, its connections closed.
        Called from another thread (from the serving one it would wait forever)."""
        self._shutdown_request = True
        self._wake()
        self._is_shut_down.wait()

    def server_close(self) -> None:
        """Close the listening socket and the connections left open (a running
        ``serve_forever()`` closes them as it returns, which it then does)."""
        self._closed = True
        if self._selector is None:
            self._close_all()
            self._close_wake()
        else:
            self._wake()
        super().server_close()

    def _wake(self) -> None:
        try:
            self._wake_w.send(b"\0")
        except OSError:  # the buffer is full (a wake-up is pending already) or closed
            pass

    def _close_wake(self) -> None:
        self._wake_r.close()
        self._wake_w.close()

    # --- the loop's steps ---------------------------------------------------------------

    def _listen(self, now: float) -> None:
        """Watch the listening socket, unless accepting is paused (no connection could be
        made room for, or the process ran out of file descriptors) and nothing has closed since."""
        assert self._selector is not None
        want = now >= self._accept_again
        try:
            if want and not self._listening:
                self._selector.register(self.socket, selectors.EVENT_READ, self)
            elif self._listening and not want:
                self._selector.unregister(self.socket)
        except (KeyError, ValueError, OSError):  # the socket was closed meanwhile by server_close()
            return
        self._listening = want

    def _accept(self) -> None:
        assert self._selector is not None
        for _ in range(_ACCEPT_BATCH):
            if len(self._connections) >= self.max_connections and not self._evict_one():
                self._accept_again = time.monotonic() + _TICK_S  # until one closes, or a while
                return
            try:
                sock, address = self.socket.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError as e:
                if e.errno in (errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM):
                    # Out of descriptors: the queued connection stays in the backlog; make room.
                    if not self._evict_one():
                        self._accept_again = time.monotonic() + _RETRY_ACCEPT_S
                    return
                continue  # ECONNABORTED and the like: that client is gone
            try:
                sock.setblocking(False)
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            except OSError:
                sock.close()
                continue
            conn = _Connection(sock, address, time.monotonic() + self.idle_timeout)
            self._connections[conn.fd] = conn
            self._selector.register(sock, selectors.EVENT_READ, conn)

    def _evict_one(self) -> bool:
        """Make room for a new connection: close the oldest one whose answer is all sent (the
        client has only to close its end), else the oldest that has sent nothing at all, not
        even bytes still queued in the kernel (an idle client). False when there is none."""
        idle = None
        for conn in self._connections.values():
            if conn.state == _DRAINING:
                idle = conn
                break
            if idle is None and conn.state == _READING and not conn.received and self._sent_nothing(conn):
                idle = conn
        if idle is None:
            return False
        self._close(idle)
        return True

    @staticmethod
    def _sent_nothing(conn: _Connection) -> bool:
        try:
            return conn.sock.recv(1, socket.MSG_PEEK) == b""  # b"": closed by the client
        except (BlockingIOError, InterruptedError):
            return True
        except OSError:
            return True

    def _step(self, conn: _Connection, events: int) -> None:
        try:
            if conn.state == _WRITING:
                self._send(conn)
            else:
                self._receive(conn)
        except OSError:  # reset by the client, broken pipe, ...
            self._close(conn)
        except Exception:  # a fault of this server's: that connection is lost, not the others
            self.handle_error(conn, conn.address)
            self._close(conn)

    def _receive(self, conn: _Connection) -> None:
        try:
            data = conn.sock.recv(_RECV_BYTES)
        except (BlockingIOError, InterruptedError):
            return
        if conn.state == _DRAINING:
            if not data:
                self._close(conn)
            return
        if not data:  # the client is done sending
            if conn.received:
                self._answer(conn)  # a request cut short: the handler judges it
            else:
                self._close(conn)
            return
        seen = max(0, len(conn.received) - 3)
        conn.received += data
        if conn.received.find(b"\r\n\r\n", seen) >= 0 or conn.received.find(b"\n\n", seen) >= 0:
            self._answer(conn)
        elif len(conn.received) > MAX_REQUEST_BYTES:
            self._start_sending(conn, collections.deque([memoryview(_TOO_LARGE)]))

    def _answer(self, conn: _Connection) -> None:
        try:
            self.finish_request(conn, conn.address)  # the handler fills conn.outbox
        except Exception:
            self.handle_error(conn, conn.address)
            self._close(conn)
            return
        conn.received = bytearray()
        self._start_sending(conn, conn.outbox)

    def _start_sending(self, conn: _Connection, outbox: collections.deque[memoryview]) -> None:
        assert self._selector is not None
        conn.outbox = outbox
        conn.state = _WRITING
        conn.deadline = time.monotonic() + self.idle_timeout
        self._selector.modify(conn.sock, selectors.EVENT_WRITE, conn)
        self._send(conn)

    def _send(self, conn: _Connection) -> None:
        """Send what the socket takes now, up to a turn's worth; each byte taken moves the
        deadline on (a client that takes nothing for ``idle_timeout`` is dropped)."""
        assert self._selector is not None
        sent = 0
        while conn.outbox and sent < _TURN_BYTES:
            chunk = conn.outbox[0]
            try:
                n = conn.sock.send(chunk[:_SEND_BYTES])
            except (BlockingIOError, InterruptedError):
                break
            sent += n
            if n == len(chunk):
                conn.outbox.popleft()
            else:
                conn.outbox[0] = chunk[n:]
        if sent:
            conn.deadline = time.monotonic() + self.idle_timeout
        if not conn.outbox:
            conn.sock.shutdown(socket.SHUT_WR)
            conn.state = _DRAINING
            self._selector.modify(conn.sock, selectors.EVENT_READ, conn)

    def _drain_wake(self) -> None:
        try:
            while self._wake_r.recv(4096):
                pass
        except (BlockingIOError, InterruptedError):
            pass

    def _close(self, conn: _Connection) -> None:
        if conn.closed:
            return
        conn.closed = True
        conn.outbox.clear()
        self._accept_again = 0.0  # room for another
        self._connections.pop(conn.fd, None)
        if self._selector is not None:
            try:
                self._selector.unregister(conn.sock)
            except (KeyError, ValueError):
                pass
        try:
            conn.sock.close()
        except OSError:
            pass

    def _close_all(self) -> None:
        for conn in list(self._connections.values()):
            self._close(conn)


def _handler(routes: dict[str, tuple[str, bytes]]) -> type[_QueuedHandler]:
    class Handler(_QueuedHandler):
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
    traj: Any,
    open_browser: bool = True,
    port: int = 0,
    *,
    title: str = "kinema",
    max_bytes: int = SERVE_MAX_BYTES,
    announce: bool = True,
    idle_timeout: float = IDLE_TIMEOUT_S,
    color_by: str | None = None,
    camera: Any = None,
) -> tuple[str, ViewerServer]:
    """Serve the viewer for ``traj`` on 127.0.0.1 (``port`` 0: a free one) from a daemon
    thread; print the URL (unless ``announce`` is False) and open it in the user's browser when ``open_browser`` and a
    graphical browser exists (no error when none does). Returns ``(url, server)``; stop with
    ``server.shutdown()``, or keep the process alive while the page is in use (the thread is
    ``server.thread``). Frames, then particles, are left out by strides when the frame data
    is over ``max_bytes`` (a ``ViewerWarning`` says so). That one thread serves all clients;
    a connection is closed when it has not sent its request ``idle_timeout`` s after it was
    accepted, or has taken none of its answer for that long (see ``IDLE_TIMEOUT_S``).
    ``color_by`` and ``camera``: the colouring and the view the page opens with (as
    :func:`kinema.viewer.write_html`)."""
    bundle()  # fail before any work when the script is not built
    packed = pack(traj, max_bytes, color_by, camera)
    data, layout = _binary(packed)
    html = page(dict(packed.meta, source="data.bin", layout=layout), title).encode("utf-8")
    routes = {"/": ("text/html; charset=utf-8", html), "/index.html": ("text/html; charset=utf-8", html), "/data.bin": ("application/octet-stream", data)}
    server = ViewerServer(("127.0.0.1", port), _handler(routes), idle_timeout=idle_timeout)
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
