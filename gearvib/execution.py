"""Where independent computations run: any :class:`concurrent.futures.Executor`.

Used by the sweeps (:func:`gearvib.sweep.run_sweep`, one task per case) and the stability
charts (:func:`gearvib.stability.stability_over_speed` and :func:`~gearvib.stability.stability_map`,
one task per chunk of Floquet evaluations; :func:`executor_for` opens the executor of a
``workers`` / ``scheduler`` / ``executor`` choice).

* :class:`SerialExecutor`: in this process, one case after the other (``workers = 1``).
* :func:`local_executor`: a :class:`~concurrent.futures.ProcessPoolExecutor` of worker
  processes on this machine (forked on Linux, spawned elsewhere): no server to start.
* :func:`dask_executor`: ``dask.distributed.Client(address).get_executor()``, the
  ``concurrent.futures`` face of a Dask cluster (``pip install "gearvib[dask]"``), after a
  probe (:func:`probe_scheduler`: one TCP connection, then Dask's ``identity`` call) that
  fails at once, in one line, where nothing listens or something other than a scheduler
  answers, instead of Dask retrying for its 30 s connect timeout.

One code path (:func:`gearvib.sweep.run_sweep`, :func:`analysis.instability.stability_chart`)
serves all of them.

Threads and the numba cache
---------------------------
Every case is a serial computation, so the workers must not start thread pools of their own:
:func:`worker_environment` sets ``NUMBA_NUM_THREADS``, ``OMP_NUM_THREADS``,
``OPENBLAS_NUM_THREADS``, ``MKL_NUM_THREADS`` and ``PYFFTW_NUM_THREADS`` to 1 for the local
workers it starts (a spawned worker reads them before it imports numpy or numba); every case
runs with one BLAS/OpenMP thread (``threadpoolctl``, which also covers a forked worker's BLAS,
loaded by its parent with more threads, and a Dask worker) and one FFT thread of
:mod:`analysis.fft`. The kernels have no parallel loops, so numba starts no threads.

The workers share numba's compilation cache: :func:`gearvib.sweep.run_sweep` compiles (or
loads) the kernels once in this process before the fan-out; forked workers inherit them
compiled, spawned ones load them from the same cache (this process's ``NUMBA_CACHE_DIR``, or
the default ``__pycache__`` next to the sources). Dask's nanny sets ``OMP_NUM_THREADS=1`` (and
MKL/OpenBLAS) for its workers by default (``distributed.nanny.pre-spawn-environ``); on a
remote cluster give the workers a writable ``NUMBA_CACHE_DIR`` of their own: each compiles
once.
"""

from __future__ import annotations

import contextlib
import ctypes
import multiprocessing
import os
import signal
import sys
from collections.abc import Callable, Iterator
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from typing import Any

from gearvib.checks import cut, short

__all__ = [
    "CONNECT_TIMEOUT_S",
    "THREAD_VARIABLES",
    "SerialExecutor",
    "check_connect_timeout",
    "dask_executor",
    "default_start_method",
    "default_workers",
    "executor_for",
    "local_executor",
    "probe_scheduler",
    "stop_workers",
    "worker_environment",
]

THREAD_VARIABLES = ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                    "MKL_NUM_THREADS", "PYFFTW_NUM_THREADS")
"""Environment variables set to 1 in local worker processes."""

MAX_WORKERS = 512
"""Largest admissible number of local workers."""

CONNECT_TIMEOUT_S = 10.0
"""How long :func:`dask_executor` tries to reach the scheduler by default [s]: the TCP probe
and then the Dask handshake each get this long (Dask's own default, 30 s, is what an address
where nothing listens used to cost)."""

MAX_CONNECT_TIMEOUT_S = 3600.0
"""Largest admissible connect timeout [s]."""

_PROBED = ("tcp", "tls", "ws", "wss")  # socket protocols: one TCP connection tells


class SerialExecutor(Executor):
    """Runs every submitted call at once, in this process (an Executor for ``workers = 1``)."""

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future:
        """Call ``fn(*args, **kwargs)`` now; the returned future is done."""
        fut: Future = Future()
        if fut.set_running_or_notify_cancel():
            try:
                fut.set_result(fn(*args, **kwargs))
            except BaseException as exc:
                if isinstance(exc, KeyboardInterrupt | SystemExit):
                    raise
                fut.set_exception(exc)
        return fut


def default_workers() -> int:
    """CPUs this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def _check_workers(workers: Any) -> int:
    if isinstance(workers, bool) or not isinstance(workers, int) or \
            not 1 <= workers <= MAX_WORKERS:
        raise ValueError(f"workers = {short(workers)}; admissible: an integer 1..{MAX_WORKERS}")
    return workers


@contextlib.contextmanager
def worker_environment() -> Iterator[dict[str, str]]:
    """Set the environment local workers start with; restore this process's afterwards.

    Yields the variables set: :data:`THREAD_VARIABLES` = 1, and ``NUMBA_CACHE_DIR`` when this
    process uses one (so every worker reads and writes the same cache).
    """
    import numba

    env = dict.fromkeys(THREAD_VARIABLES, "1")
    cache = str(getattr(numba.config, "CACHE_DIR", "") or "")
    if cache:
        env["NUMBA_CACHE_DIR"] = cache
    old = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    try:
        yield env
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def default_start_method() -> str:
    """``"fork"`` on Linux (fast: the workers inherit the imported modules and the compiled
    kernels, and the main script needs no ``if __name__ == "__main__":`` guard), else
    ``"spawn"``."""
    if sys.platform.startswith("linux") and "fork" in multiprocessing.get_all_start_methods():
        return "fork"
    return "spawn"


def local_executor(workers: int, *, start_method: str | None = None) -> Executor:
    """An executor of ``workers`` processes on this machine (in-process for 1).

    Parameters
    ----------
    workers : int
        Number of worker processes (1: :class:`SerialExecutor`).
    start_method : {"fork", "spawn", "forkserver"}, optional
        How the workers start (default :func:`default_start_method`). A ``spawn`` or
        ``forkserver`` worker is a fresh interpreter that reads the environment of
        :func:`worker_environment` (enter it before submitting) and loads the compiled kernels
        from numba's cache; it imports the main script again, which must then guard its entry
        point with ``if __name__ == "__main__":``.
    """
    n = _check_workers(workers)
    if n == 1:
        return SerialExecutor()
    method = start_method or default_start_method()
    if method not in multiprocessing.get_all_start_methods():
        raise ValueError(f"start_method = {short(method)}; admissible here: "
                         f"{', '.join(multiprocessing.get_all_start_methods())}")
    return ProcessPoolExecutor(max_workers=n, mp_context=multiprocessing.get_context(method),
                               initializer=init_worker)


_PR_SET_PDEATHSIG = 1


def init_worker() -> None:
    """Start-up of a local worker: it leaves interrupts to the command and dies with it.

    * SIGINT is ignored (Ctrl-C reaches the whole process group; the command's process stops
      the workers itself, see :func:`stop_workers`), SIGTERM and SIGHUP end the worker (the
      handlers a forked worker inherited from the command would raise there instead);
    * on Linux the kernel sends the worker SIGTERM when its parent ends, however it ends
      (``prctl(PR_SET_PDEATHSIG)``; also after SIGKILL of the command), so no worker outlives
      the command.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if hasattr(signal, "SIGHUP"):
        signal.signal(signal.SIGHUP, signal.SIG_DFL)
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
            if os.getppid() == 1:  # the parent ended before prctl took effect
                os._exit(128 + int(signal.SIGTERM))


def stop_workers(executor: Executor) -> None:
    """End the worker processes of a local :class:`ProcessPoolExecutor` now (an interrupt).

    The running cases are abandoned (their run files are not written; a worker's temporary
    file is left for :func:`gearvib.tempfiles.remove_stale`), queued ones are cancelled; a
    worker that does not end on SIGTERM within a second is killed
    (:func:`analysis.instability.chart.terminate_pool`). Other executors are left alone.
    """
    if isinstance(executor, ProcessPoolExecutor):
        from analysis.instability.chart import terminate_pool  # on demand: a rare path

        terminate_pool(executor)


def check_connect_timeout(timeout: Any) -> float:
    """A connect timeout [s]: a number in (0, :data:`MAX_CONNECT_TIMEOUT_S`]."""
    if isinstance(timeout, bool) or not isinstance(timeout, int | float) or not (
            0 < timeout <= MAX_CONNECT_TIMEOUT_S):
        raise ValueError(f"connect timeout = {short(timeout)} is not admissible: a time in (0, "
                         f"{MAX_CONNECT_TIMEOUT_S:g}] s")
    return float(timeout)


def probe_scheduler(address: str, timeout: float = CONNECT_TIMEOUT_S) -> None:
    """Check that a Dask scheduler answers at ``address``, failing fast where nothing listens
    (instead of Dask's retries until its timeout).

    One TCP connection first (refused at once where nothing listens), then Dask's
    ``identity`` call (the server must say it is a ``Scheduler``). Addresses of other
    protocols (``inproc://``, ``ucx://``) are left to Dask.

    Raises
    ------
    ValueError
        The address cannot be parsed (no port, ...).
    OSError
        Nothing listens there (connection refused), the host is unknown, no answer within
        ``timeout`` seconds, or the server there is no Dask scheduler; one line that names
        the address.
    """
    import socket

    from distributed.comm import parse_address, parse_host_port

    timeout = check_connect_timeout(timeout)
    try:
        protocol, location = parse_address(address)
        if protocol not in _PROBED:
            return
        host, port = parse_host_port(location)
    except ValueError as exc:
        raise ValueError(f"scheduler address {short(address)} is not admissible: "
                         f"{cut(' '.join(str(exc).split()), 120)} (give e.g. "
                         "'tcp://10.0.0.5:8786')") from None
    where = f"cannot connect to the Dask scheduler at {short(address, 200)}"
    try:
        with socket.create_connection((host, int(port)), timeout=timeout):
            pass
    except ConnectionRefusedError:
        raise OSError(f"{where}: nothing listens there (connection refused); start the "
                      "scheduler (dask scheduler) or check the address") from None
    except socket.gaierror as exc:
        raise OSError(f"{where}: unknown host {short(host)} ({exc.strerror})") from None
    except TimeoutError:
        raise OSError(f"{where}: no answer within {timeout:g} s (host down, or a firewall "
                      "drops the connection); a longer connect timeout waits more") from None
    except OSError as exc:
        raise OSError(f"{where}: {exc.strerror or exc}") from None
    _identify(address, timeout, where)


def _identify(address: str, timeout: float, where: str) -> None:
    """Ask the server at ``address`` who it is (Dask's ``identity`` call, in a thread of its
    own: the caller may run an event loop): something that is no Dask scheduler (a web
    server, a proxy) fails here in one line, not inside the client's start-up."""
    import asyncio
    from concurrent.futures import ThreadPoolExecutor

    from distributed.comm import connect

    async def ask() -> Any:
        comm = await connect(address, timeout=timeout)
        try:
            await asyncio.wait_for(comm.write({"op": "identity", "reply": True}), timeout)
            return await asyncio.wait_for(comm.read(), timeout)
        finally:
            comm.abort()

    async def bounded() -> Any:  # the handshake inside connect() may wait for ever
        return await asyncio.wait_for(ask(), 2 * timeout)

    with ThreadPoolExecutor(1) as pool:
        try:
            info = pool.submit(asyncio.run, bounded()).result()
        except TimeoutError:
            raise OSError(f"{where}: something listens there but gives no Dask answer "
                          f"(connect timeout {timeout:g} s; is it a Dask scheduler?)") from None
        except Exception as exc:  # a reply that is not Dask's: any error of its decoding
            text = " ".join(str(exc).split())[:160]
            raise OSError(f"{where}: something listens there but does not answer as a Dask "
                          f"scheduler ({type(exc).__name__}: {text})") from None
    kind = info.get("type") if isinstance(info, dict) else None
    if kind != "Scheduler":
        raise OSError(f"{where}: the server there is a {kind or 'non-Dask server'!s}, not a "
                      "Dask scheduler")


def dask_executor(address: str, *, timeout: float = CONNECT_TIMEOUT_S) -> tuple[Executor, Any]:
    """``(executor, client)`` of the Dask scheduler at ``address`` (close the client after).

    A TCP probe (:func:`probe_scheduler`) fails at once where nothing listens; then the Dask
    client connects.

    Parameters
    ----------
    address : str
        ``tcp://host:port`` (or any address Dask takes).
    timeout : float
        Seconds the probe, and then the Dask handshake, may each take, in (0, 3600]
        (default :data:`CONNECT_TIMEOUT_S`).

    Raises
    ------
    ImportError
        dask.distributed is not installed (the message names the extra to install).
    ValueError
        A malformed address or timeout.
    OSError
        The scheduler cannot be reached (one line: why, and the address).
    """
    if not isinstance(address, str) or not address:
        raise ValueError("scheduler address must be a string such as 'tcp://10.0.0.5:8786'")
    timeout = check_connect_timeout(timeout)
    try:
        from distributed import Client
    except ImportError:
        raise ImportError("a Dask scheduler needs dask.distributed: pip install "
                          "\"gearvib[dask]\"") from None
    probe_scheduler(address, timeout)
    try:
        client = Client(address, timeout=timeout, set_as_default=False)
    except (OSError, TimeoutError) as exc:
        text = " ".join(str(exc).split())
        raise OSError(f"cannot connect to the Dask scheduler at {short(address, 200)}: "
                      f"{text[:200]}") from None
    return client.get_executor(), client


@contextlib.contextmanager
def executor_for(workers: int | None = 1, scheduler: str | None = None,
                 executor: Executor | None = None, *,
                 connect_timeout: float = CONNECT_TIMEOUT_S
                 ) -> Iterator[tuple[Executor, int]]:
    """The executor of a ``workers`` / ``scheduler`` / ``executor`` choice, closed afterwards.

    Parameters
    ----------
    workers : int or None
        Local worker processes (None: :func:`default_workers`; 1: this process). Their
        environment is :func:`worker_environment`.
    scheduler : str, optional
        Address of a Dask scheduler (``tcp://host:8786``): its workers run the tasks; the
        client is closed on exit.
    executor : concurrent.futures.Executor, optional
        Use this one as it is (not shut down here); ``workers`` and ``scheduler`` are ignored.
    connect_timeout : float
        Seconds to reach the scheduler (:func:`dask_executor`).

    Yields
    ------
    (concurrent.futures.Executor, int)
        The executor and its number of workers (for a given ``executor``: ``workers``, or
        :func:`default_workers`; for a Dask cluster: its worker threads when it was opened).
    """
    n = default_workers() if workers is None else _check_workers(workers)
    if executor is not None:
        if not isinstance(executor, Executor):
            raise TypeError(f"executor must be a concurrent.futures.Executor; got "
                            f"{type(executor).__name__}")
        yield executor, n
        return
    if scheduler is not None:
        dask_exec, client = dask_executor(scheduler, timeout=connect_timeout)
        try:
            yield dask_exec, max(1, sum(client.nthreads().values()))
        finally:
            client.close()
        return
    with worker_environment():
        pool = local_executor(n)
        try:
            yield pool, n
        except BaseException:  # an error or an interrupt: stop the workers now
            stop_workers(pool)
            raise
        else:
            pool.shutdown(wait=True)
