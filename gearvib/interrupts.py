"""Interrupts: SIGINT and SIGTERM as exceptions, and work that an interrupt can abandon.

Why netCDF input and output runs in a worker thread
---------------------------------------------------
Python runs a signal handler in the main thread, at the next bytecode boundary after the
signal arrived; the default SIGINT handler raises :class:`KeyboardInterrupt` there. During a
netCDF write, the main thread spends almost all its time inside one long C call (HDF5
compressing and writing a variable) made under xarray's backend lock
(``with self.datastore.lock: data[key] = value``). The signal is therefore handled right after
that call returns -- at the entry of the lock's ``__exit__``, which is a Python method of
xarray's ``CombinedLock``/``SerializableLock``. The exception is raised *before* the lock is
released, the lock stays held, and xarray's clean-up in ``to_netcdf`` (``finally:
store.close()``) then waits for that same non-reentrant lock forever: the process hangs with
its temporary file (5 of 9 interrupts in the issue's campaign, 8 of 8 in a reproduction).
No handler that raises can be made safe there, and deferring the signal until the write ends
would break the 2-second exit for large files (a 64 MB write takes 1.5 s).

So :func:`run_abandonable` runs such library calls in a worker thread, which never receives
an asynchronous exception; the main thread only waits for it. An interrupt then reaches the
main thread while it waits (no library lock held), the caller removes its temporary file and
the work is *abandoned*: it finishes in the background, writing into the already removed
temporary file, and nothing of it is kept. The command line exits at once (``os._exit``) when
abandoned work is still running, so that HDF5 is never torn down under it.

:func:`signals_as_exceptions` (used by :func:`gearvib.cli.main`) turns SIGINT, SIGTERM and
SIGHUP into :class:`Interrupted` (a :class:`KeyboardInterrupt`, so every ``except
BaseException`` clean-up runs), with the exit code ``128 + signal number``. The signal is
also remembered: library code that swallows the exception cannot make the command commit an
output or run on (a barrier in :func:`gearvib.io.atomic_write`, a watchdog that exits after
:data:`GRACE_SECONDS`); a second signal removes this process's temporary files and exits
immediately.
"""

from __future__ import annotations

import _thread
import atexit
import contextlib
import contextvars
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from typing import TypeVar, cast

from gearvib import tempfiles

__all__ = ["GRACE_SECONDS", "Interrupted", "abandoned_work", "check_interrupted", "exit_now",
           "pending_signal", "run_abandonable", "signals_as_exceptions"]

T = TypeVar("T")

_ABANDONED: list[_Job] = []
_PENDING: list[int] = []  # the signal received under signals_as_exceptions (list: no lock)
_BLOCK: list[object] = []  # the active signals_as_exceptions block

GRACE_SECONDS = 1.0
"""After a signal, the command line exits by force if it is still running this much later."""


class Interrupted(KeyboardInterrupt):
    """A termination signal (SIGINT, SIGTERM, SIGHUP) received by the command line.

    Attributes
    ----------
    signum : int
        The signal number.
    """

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = int(signum)

    @property
    def exit_code(self) -> int:
        """``128 + signum``: 130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP."""
        return 128 + self.signum

    @property
    def name(self) -> str:
        """``"SIGINT"``, ``"SIGTERM"``, ..."""
        try:
            return signal.Signals(self.signum).name
        except ValueError:
            return f"signal {self.signum}"


def run_abandonable(fn: Callable[..., T], *args, **kwargs) -> T:
    """Call ``fn(*args, **kwargs)`` in a worker thread; an interrupt abandons it at once.

    In the main thread, the call runs in a worker thread (with a copy of the caller's context
    variables) while the main thread waits; an exception of ``fn`` is re-raised in the
    caller. An exception raised in the main thread while it waits (:class:`KeyboardInterrupt`,
    :class:`Interrupted`) propagates immediately and leaves the worker to finish on its own
    (:func:`abandoned_work`). Outside the main thread (which receives no signals) ``fn`` is
    simply called.

    Notes
    -----
    Meant for library calls that are not safe against asynchronous exceptions (netCDF
    input/output under xarray's locks, see the module docstring). The caller must not rely on
    the side effects of abandoned work (e.g. remove the temporary file it writes). The main
    thread waits on a bare lock, not with ``Thread.join``: in Python 3.11 an interrupt inside
    ``join`` can mark a running thread as stopped (its clean-up releases the thread's state
    lock when it sees it locked), after which nobody would wait for the abandoned work.
    """
    if threading.current_thread() is not threading.main_thread():
        return fn(*args, **kwargs)
    ctx = contextvars.copy_context()
    job = _Job()

    def work() -> None:
        job.started = True
        try:
            job.result = ctx.run(fn, *args, **kwargs)
        except BaseException as exc:  # handed to the caller
            job.error = exc
        finally:
            job.done = True
            job.finished.release()

    job.finished.acquire()
    try:
        # a bare thread: Thread.start() waits on a Python-level Event, which an interrupt
        # can leave in an inconsistent state
        _thread.start_new_thread(work, ())
        while not job.finished.acquire(timeout=0.05):  # short: the signal may reach
            # another thread, which does not wake this wait; the main thread sees it on return
            pass
    except BaseException:
        _ABANDONED.append(job)
        raise
    if job.error is not None:
        err, job.error = job.error, None
        raise err
    return cast(T, job.result)  # fn's result: work() finished without an error


class _Job:
    """State of one :func:`run_abandonable` call (plain attributes: no lock needed to read)."""

    def __init__(self) -> None:
        self.finished = _thread.allocate_lock()
        self.created = time.monotonic()
        self.started = False
        self.done = False
        self.result: object = None
        self.error: BaseException | None = None


def abandoned_work() -> bool:
    """Whether work abandoned by an interrupt (:func:`run_abandonable`) is still running."""
    # a job whose thread has not started 1 s after the interrupt never will (the interrupt
    # came before the thread was created)
    now = time.monotonic()
    _ABANDONED[:] = [job for job in _ABANDONED
                     if not job.done and (job.started or now - job.created < 1.0)]
    return bool(_ABANDONED)


@atexit.register
def _finish_abandoned() -> None:
    # a normal interpreter exit waits for abandoned work, so that libraries (HDF5) are not
    # finalised under it; the command line leaves with exit_now() instead
    while abandoned_work():
        time.sleep(0.02)


def exit_now(code: int) -> None:
    """Flush the standard streams, remove this process's temporary files, ``os._exit(code)``."""
    tempfiles.remove_own()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(code)


def _signals() -> list[int]:
    names = ("SIGINT", "SIGTERM", "SIGHUP")
    return [getattr(signal, n) for n in names if hasattr(signal, n)]


def pending_signal() -> int | None:
    """The signal received under :func:`signals_as_exceptions`, or None."""
    return _PENDING[0] if _PENDING else None


def check_interrupted() -> None:
    """Raise :class:`Interrupted` if a signal was received (even if its exception was
    swallowed by library code): the barrier before an output is committed."""
    if _PENDING:
        raise Interrupted(_PENDING[0])


def _watchdog(signum: int, grace: float, block: object) -> None:
    time.sleep(grace)
    if block not in _BLOCK:
        return
    with contextlib.suppress(Exception):
        name = signal.Signals(signum).name
        sys.stderr.write(f"gearvib: interrupted by {name} (nothing half-written was kept)\n")
    exit_now(128 + signum)


@contextlib.contextmanager
def signals_as_exceptions(grace: float = GRACE_SECONDS) -> Iterator[None]:
    """Within the block, SIGINT, SIGTERM and SIGHUP raise :class:`Interrupted`.

    The first signal raises :class:`Interrupted` in the main thread and is remembered
    (:func:`pending_signal`, :func:`check_interrupted`): library code that swallows or converts
    the exception (ReportLab's font loading turns it into a ``TTFError``, other code has bare
    ``except:`` clauses) cannot make the command go on -- no output is committed after it
    (:func:`gearvib.io.atomic_write` checks), and a watchdog thread exits the process with
    ``128 + signum`` after ``grace`` seconds if it is still running, removing this process's
    temporary files. A second signal exits at once the same way. The signal's exception raised
    where it cannot propagate (a finalizer, a weakref callback) is not printed: the command's
    one-line message is the only output of an interrupt. A signal that is ignored when
    the block starts (e.g. SIGHUP under ``nohup``, SIGINT of a background job) stays ignored.
    Outside the main thread the block changes nothing. The previous handlers are restored at
    the end.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _PENDING.clear()
    block = object()
    _BLOCK[:] = [block]

    def handler(signum: int, frame: object) -> None:
        if _PENDING:
            exit_now(128 + _PENDING[0])
        _PENDING.append(signum)
        threading.Thread(target=_watchdog, args=(signum, grace, block), daemon=True,
                         name="gearvib-interrupt-watchdog").start()
        raise Interrupted(signum)

    previous_hook = sys.unraisablehook

    def quiet_interrupts(unraisable: sys.UnraisableHookArgs) -> None:
        # the signal's exception raised inside a finalizer or a weakref callback cannot
        # propagate; Python would print it with a traceback ("Exception ignored in ...")
        # before the command's one line. The signal is pending: the command ends anyway.
        if isinstance(getattr(unraisable, "exc_value", None), Interrupted) and _PENDING:
            return
        previous_hook(unraisable)

    sys.unraisablehook = quiet_interrupts
    previous = {}
    for s in _signals():
        old = signal.getsignal(s)
        if old is signal.SIG_IGN:
            continue
        previous[s] = old
        signal.signal(s, handler)
    try:
        yield
    finally:
        _BLOCK.clear()  # a watchdog of this block does nothing any more
        sys.unraisablehook = previous_hook
        for s, old in previous.items():
            with contextlib.suppress(ValueError, TypeError, OSError):
                signal.signal(s, old if old is not None else signal.SIG_DFL)
