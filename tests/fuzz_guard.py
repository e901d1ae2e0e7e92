"""Guards shared by the fuzz suites (tests/analysis and tests/gearvib): a time limit that
raises :class:`Hang`, a cap on the process's address space (a missing size check shows as a
``MemoryError`` instead of a swapping machine) and baselines whose arguments are built when
called. Nothing here imports gearvib."""

from __future__ import annotations

import contextlib
import os
import resource
import signal
from collections.abc import Callable, Iterator
from typing import Any


class Hang(Exception):
    """An example ran longer than its time limit."""


@contextlib.contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    """Raise :class:`Hang` in the main thread after ``seconds`` (POSIX; no-op elsewhere)."""
    if not hasattr(signal, "setitimer"):
        yield
        return

    def on_alarm(signum: int, frame: object) -> None:
        raise Hang(f"no answer within {seconds} s")

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def process_size() -> int:
    """The process's virtual size now [bytes] (Linux ``/proc/self/statm``)."""
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")


@contextlib.contextmanager
def address_space_limit(limit: int) -> Iterator[None]:
    """``RLIMIT_AS`` at ``limit`` bytes (at most the hard limit) inside the block."""
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def lazy_call(*args: Any, **kwargs: Any) -> Callable[[], tuple[tuple, dict]]:
    """A baseline ``() -> (args, kwargs)`` whose callable arguments are called when it is
    built (classes are passed as they are)."""

    def build() -> tuple[tuple, dict]:
        ev = tuple(a() if callable(a) and not isinstance(a, type) else a for a in args)
        kw = {k: (v() if callable(v) and not isinstance(v, type) else v)
              for k, v in kwargs.items()}
        return ev, kw

    return build
