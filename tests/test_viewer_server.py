"""The viewer's local server under load and faults: idle clients, slow clients, hundreds at
once, and a clean stop (no thread, no socket left behind)."""

from __future__ import annotations

import concurrent.futures
import os
import socket
import threading
import time
import urllib.error
import urllib.request

import numpy as np
import pytest

import kinema
from kinema.viewer import server as viewer_server

SHORT_TIMEOUT_S = 1.0  # the servers' idle timeout here, so that the tests are quick


def _trajectory(n: int = 1000, frames: int = 16) -> kinema.Trajectory:
    """``n`` particles stepping at random: /data.bin of 4 (4 F N + N) bytes (260 kB by
    default, more than a loopback socket's first send buffer, so sends are partial)."""
    rng = np.random.default_rng(5)
    velocities = rng.normal(0.0, 0.05, (frames, n, 3))
    positions = rng.random((1, n, 3)) + np.cumsum(velocities, axis=0) / 10.0
    zeros, three = np.zeros(frames), np.zeros((frames, 3))
    return kinema.Trajectory(
        t=np.arange(frames) / 10.0,
        positions=positions,
        velocities=velocities,
        kinetic=zeros,
        potential={},
        momentum=three,
        angular_momentum=three,
        contacts=np.zeros(frames, dtype=int),
        impulse_balance=three,
        collision_energy_lost=zeros,
        radii=np.full(n, 0.004),
    )


@pytest.fixture(scope="module")
def traj() -> kinema.Trajectory:
    return _trajectory()


@pytest.fixture
def served(traj):
    """A server with a 1 s idle timeout; shut down and closed after the test."""
    url, server = viewer_server.serve(traj, open_browser=False, announce=False, idle_timeout=SHORT_TIMEOUT_S)
    yield url, server
    server.shutdown()
    server.server_close()


def _threads() -> int:
    return len(os.listdir("/proc/self/task")) if os.path.isdir("/proc/self/task") else threading.active_count()


def _request(port: int, path: str = "/data.bin", host: str | None = None, timeout: float = 30.0) -> bytes:
    """The whole answer (status line, headers, body) to a GET over a raw socket."""
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as sock:
        sock.sendall(f"GET {path} HTTP/1.1\r\nHost: {host or f'127.0.0.1:{port}'}\r\n\r\n".encode())
        return _read_all(sock)


def _read_all(sock: socket.socket) -> bytes:
    chunks = []
    while chunk := sock.recv(1 << 20):
        chunks.append(chunk)
    return b"".join(chunks)


def _expected_size(traj) -> int:
    frames, n = traj.positions.shape[:2]
    return 4 * (frames * n * 3 + frames * n + n)  # positions, speed, radii as float32


def test_idle_clients_cost_no_threads_and_are_closed_after_the_timeout(traj):
    # http.server's ThreadingHTTPServer ran a thread per connection, forever: 303 threads here.
    before = _threads()
    url, server = viewer_server.serve(traj, open_browser=False, announce=False, idle_timeout=SHORT_TIMEOUT_S)
    port = server.server_address[1]
    idle = [socket.create_connection(("127.0.0.1", port), timeout=10) for _ in range(300)]
    try:
        deadline = time.monotonic() + 5
        while server.open_connections < 300 and time.monotonic() < deadline:
            time.sleep(0.01)
        during = _threads()
        print(f"\nthreads: {before} before, {during} with 300 idle clients; server connections {server.open_connections}")
        assert server.open_connections == 300
        assert during <= before + 2, f"{during - before} threads more with 300 idle clients"  # the server's one, and a spare
        # They hold nothing back: a download goes through at once.
        started = time.monotonic()
        with urllib.request.urlopen(url + "data.bin", timeout=10) as blob:
            assert len(blob.read()) == _expected_size(traj)
        assert time.monotonic() - started < 2.0
        # After the timeout the server has closed every one of them (recv gives b"", end of stream).
        started = time.monotonic()
        closed = sum(sock.recv(1) == b"" for sock in idle)
        waited = time.monotonic() - started
        print(f"idle clients closed by the server: {closed}/300, the last after {waited:.2f} s; threads {_threads()}")
        assert closed == 300 and waited < SHORT_TIMEOUT_S + 3
        assert server.open_connections == 0
    finally:
        for sock in idle:
            sock.close()
        server.shutdown()
        server.server_close()


def test_a_request_sent_a_byte_at_a_time_gets_no_more_than_the_timeout(served):
    # slowloris: each byte well within the timeout, the whole request never.
    url, server = served
    port = server.server_address[1]
    with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
        started = time.monotonic()
        request = f"GET /data.bin HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nX-Padding: {'a' * 100}\r\n\r\n".encode()
        with pytest.raises((BrokenPipeError, ConnectionResetError)):
            for byte in request:
                sock.send(bytes([byte]))
                time.sleep(0.2)
        assert time.monotonic() - started < SHORT_TIMEOUT_S + 2


def test_a_client_that_reads_nothing_of_its_answer_is_dropped(traj):
    # A body of 16 MB: far more than the kernel buffers between the two sockets hold.
    big = _trajectory(n=200_000, frames=4)
    url, server = viewer_server.serve(big, open_browser=False, announce=False, idle_timeout=SHORT_TIMEOUT_S)
    port = server.server_address[1]
    try:
        sock = socket.socket()
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        sock.settimeout(10)
        sock.connect(("127.0.0.1", port))
        with sock:
            sock.sendall(f"GET /data.bin HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n".encode())
            deadline = time.monotonic() + 5
            while server.open_connections == 0 and time.monotonic() < deadline:
                time.sleep(0.01)  # until the server has accepted it
            assert server.open_connections == 1
            started = time.monotonic()
            while server.open_connections and time.monotonic() < started + SHORT_TIMEOUT_S + 5:
                time.sleep(0.05)
            print(f"\na client reading nothing of a {_expected_size(big)}-byte answer: dropped after {time.monotonic() - started:.2f} s")
            assert server.open_connections == 0, "the server still holds a client that reads nothing"
            received = 0
            try:
                while chunk := sock.recv(1 << 20):
                    received += len(chunk)
            except ConnectionResetError:
                pass
            assert received < _expected_size(big)
        # The server goes on serving.
        assert len(_request(port).split(b"\r\n\r\n", 1)[1]) == _expected_size(big)
    finally:
        server.shutdown()
        server.server_close()


def test_400_concurrent_downloads_all_succeed(served, traj):
    url, server = served
    expected = urllib.request.urlopen(url + "data.bin", timeout=30).read()
    assert len(expected) == _expected_size(traj)

    def download(_: int) -> bool:
        with urllib.request.urlopen(url + "data.bin", timeout=30) as blob:  # Host: 127.0.0.1:PORT
            return blob.status == 200 and blob.read() == expected

    started = time.monotonic()
    with concurrent.futures.ThreadPoolExecutor(max_workers=100) as pool:
        results = list(pool.map(download, range(400)))
    took = time.monotonic() - started
    print(f"\n400 concurrent downloads of {len(expected)} bytes: {sum(results)} succeeded in {took:.2f} s")
    assert sum(results) == 400
    assert took < 60


def test_the_backlog_holds_hundreds_of_connections_before_any_is_accepted(traj):
    # A server not yet serving: every connection waits in the listen backlog (http.server's
    # was 5: the 7th connect hung), then each gets its answer.
    try:
        somaxconn = int(open("/proc/sys/net/core/somaxconn").read())
    except OSError:
        somaxconn = 128
    count = min(600, somaxconn - 8)
    server = viewer_server.ViewerServer(("127.0.0.1", 0), viewer_server._handler({"/": ("text/plain", b"ok")}), idle_timeout=10)
    port = server.server_address[1]
    clients = []
    try:
        for _ in range(count):
            clients.append(socket.create_connection(("127.0.0.1", port), timeout=3))
        thread = threading.Thread(target=server.serve_forever, daemon=True)
        thread.start()
        for sock in clients:
            sock.sendall(f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n".encode())
        answers = [_read_all(sock) for sock in clients]
        assert all(a.startswith(b"HTTP/1.0 200 ") and a.endswith(b"\r\n\r\nok") for a in answers)
        print(f"\n{count} connections queued before the server accepted any: {len(answers)} answered")
    finally:
        for sock in clients:
            sock.close()
        server.shutdown()
        server.server_close()


def test_shutdown_leaves_no_thread_nor_socket(traj):
    base_threads = threading.enumerate()
    base_fds = len(os.listdir("/proc/self/fd")) if os.path.isdir("/proc/self/fd") else None
    for _ in range(3):
        url, server = viewer_server.serve(traj, open_browser=False, announce=False, idle_timeout=SHORT_TIMEOUT_S)
        port = server.server_address[1]
        assert server.thread.is_alive() and server.thread.daemon
        with urllib.request.urlopen(url + "data.bin", timeout=10) as blob:
            assert len(blob.read()) == _expected_size(traj)
        # Left open at shutdown: clients waiting for their request, and one in the middle of its answer.
        idle = [socket.create_connection(("127.0.0.1", port), timeout=10) for _ in range(20)]
        reading = socket.create_connection(("127.0.0.1", port), timeout=10)
        reading.sendall(f"GET /data.bin HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n".encode())
        reading.recv(100)
        deadline = time.monotonic() + 5
        while server.open_connections < 21 and time.monotonic() < deadline:
            time.sleep(0.01)  # until all are accepted (one still in the backlog is reset when the socket closes)
        assert server.open_connections == 21
        started = time.monotonic()
        server.shutdown()
        server.server_close()
        assert time.monotonic() - started < 2.0
        server.thread.join(timeout=5)
        assert not server.thread.is_alive()
        assert server.open_connections == 0
        for sock in idle:
            assert sock.recv(1) == b""
            sock.close()
        try:
            _read_all(reading)
        except ConnectionResetError:
            pass
        reading.close()
    left = [t for t in threading.enumerate() if t not in base_threads]
    print(f"\nthreads after 3 servers shut down: {len(threading.enumerate())} (before {len(base_threads)}); new ones left: {left}")
    assert left == []
    if base_fds is not None:
        assert len(os.listdir("/proc/self/fd")) <= base_fds


def test_server_close_alone_stops_the_thread(traj):
    url, server = viewer_server.serve(traj, open_browser=False, announce=False, idle_timeout=SHORT_TIMEOUT_S)
    idle = socket.create_connection(("127.0.0.1", server.server_address[1]), timeout=10)
    with idle:
        deadline = time.monotonic() + 5
        while server.open_connections == 0 and time.monotonic() < deadline:
            time.sleep(0.01)  # until accepted (one still in the backlog is reset when the socket closes)
        server.server_close()  # without shutdown() first
        server.thread.join(timeout=5)
        assert not server.thread.is_alive() and server.open_connections == 0
        assert idle.recv(1) == b""
    server.shutdown()  # after the loop has ended: returns at once


def test_a_foreign_host_is_refused_and_bad_requests_are_answered(served):
    url, server = served
    port = server.server_address[1]
    for host in (f"evil.example:{port}", "127.0.0.1", f"localhost:{port + 1}"):
        answer = _request(port, host=host)
        assert answer.startswith(b"HTTP/1.0 403 ") and b"forbidden: this viewer answers only to" in answer, answer[:200]
    with pytest.raises(urllib.error.HTTPError) as refused:
        urllib.request.urlopen(urllib.request.Request(url + "data.bin", headers={"Host": "evil.example"}), timeout=10)
    assert refused.value.code == 403
    assert _request(port, "/elsewhere").startswith(b"HTTP/1.0 404 ")
    assert _request(port, "/", host=f"localhost:{port}").startswith(b"HTTP/1.0 200 ")
    # Headers beyond 64 kB: 431, not an endless read.
    with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:
        try:
            sock.sendall(b"GET / HTTP/1.1\r\nX-Big: " + b"a" * 100_000)
        except (BrokenPipeError, ConnectionResetError):
            pass
        try:
            answer = _read_all(sock)
        except ConnectionResetError:
            answer = b""
        assert answer.startswith(b"HTTP/1.0 431 ") or answer == b""
    assert server.thread.is_alive()


def test_idle_timeout_must_be_positive(traj):
    for bad in (0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="idle_timeout"):
            viewer_server.serve(traj, open_browser=False, announce=False, idle_timeout=bad)
