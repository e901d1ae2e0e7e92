"""gearvib.execution: reaching a Dask scheduler fails fast and in one line where none answers."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from gearvib.execution import check_connect_timeout, dask_executor, executor_for

pytest.importorskip("distributed")

FAST_S = 5.0  # Dask's own connect timeout is 30 s


def free_port() -> int:
    """A port where nothing listens (bound, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@contextmanager
def server(reply: bytes | None) -> Iterator[str]:
    """A TCP server that answers every connection with ``reply`` (None: never answers)."""
    lsock = socket.socket()
    lsock.bind(("127.0.0.1", 0))
    lsock.listen(4)
    lsock.settimeout(0.2)
    stop = threading.Event()
    held: list[socket.socket] = []

    def serve() -> None:
        while not stop.is_set():
            try:
                conn, _ = lsock.accept()
            except OSError:
                continue
            if reply is None:
                held.append(conn)  # keep it open, say nothing
            else:
                try:
                    conn.sendall(reply)
                finally:
                    conn.close()

    th = threading.Thread(target=serve, daemon=True)
    th.start()
    try:
        yield f"tcp://127.0.0.1:{lsock.getsockname()[1]}"
    finally:
        stop.set()
        th.join(5)
        for c in held:
            c.close()
        lsock.close()


def fails_fast(address: str, match: str, timeout: float = 10.0) -> str:
    t0 = time.perf_counter()
    with pytest.raises(OSError, match=match) as info:
        dask_executor(address, timeout=timeout)
    assert time.perf_counter() - t0 < FAST_S
    text = str(info.value)
    assert "\n" not in text and f"cannot connect to the Dask scheduler at {address!r}" in text
    return text


def test_nothing_listening_fails_at_once():
    fails_fast(f"tcp://127.0.0.1:{free_port()}", "nothing listens there")
    fails_fast(f"127.0.0.1:{free_port()}", "connection refused")  # tcp:// by default


def test_unknown_host_and_malformed_addresses():
    fails_fast("tcp://no-such-host.invalid:8786", "unknown host 'no-such-host.invalid'")
    for bad in ("tcp://127.0.0.1", "127.0.0.1"):
        with pytest.raises(ValueError, match="missing port"):
            dask_executor(bad)
    with pytest.raises(ValueError, match="scheduler address must be a string"):
        dask_executor("")


def test_a_server_that_is_no_dask_scheduler_is_named_so():
    with server(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n") as address:
        fails_fast(address, "does not answer as a Dask scheduler")
    with server(None) as address:  # accepts and stays silent: the connect timeout applies
        fails_fast(address, r"gives no Dask answer \(connect timeout 0\.5 s", timeout=0.5)


@pytest.mark.parametrize("timeout", [0, -1.0, float("nan"), 1e9, True, "5"])
def test_connect_timeout_is_checked(timeout):
    with pytest.raises(ValueError, match=r"connect timeout = .* is not admissible: a time in "
                       r"\(0, 3600\] s"):
        check_connect_timeout(timeout)
    with pytest.raises(ValueError, match="connect timeout"):
        dask_executor("tcp://127.0.0.1:1", timeout=timeout)


def test_a_dask_scheduler_is_reached_and_runs_the_tasks():
    import distributed

    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=":0") as cluster, \
            executor_for(scheduler=cluster.scheduler_address, connect_timeout=5.0) as (ex, n):
        assert n == 1
        assert ex.submit(pow, 2, 10).result(timeout=30) == 1024
