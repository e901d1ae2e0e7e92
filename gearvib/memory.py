"""Sizes computed from input, checked against the memory available before allocating.

A run's arrays (internal steps x stored signals, the anti-alias filter, the output samples)
and a report's maps and charts grow with numbers the user gives. :func:`require_memory`
refuses a size that the process cannot hold with :class:`RunSizeError`, naming the parameter,
the size and a remedy, before anything is allocated. The memory available is the smallest of
the system's available memory (``MemAvailable``), the free part of a cgroup memory limit
(containers, CI) and the free part of the address-space limit (``ulimit -v``).
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

from gearvib.config import ConfigError

__all__ = ["MEMORY_FRACTION", "RunSizeError", "available_memory", "format_bytes",
           "require_memory"]

MEMORY_FRACTION = 0.8
"""A size is refused when it needs more than this fraction of the available memory."""


class RunSizeError(ConfigError):
    """A size computed from the input needs more memory (or steps) than is available/allowed.

    The message names the parameter, the size and a remedy; raised before allocating.
    """


def format_bytes(n: float) -> str:
    """``1.5 GiB``-style size."""
    n = float(n)
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"):
        if abs(n) < 1024.0 or unit == "EiB":
            return f"{n:.3g} {unit}" if unit != "B" else f"{n:.0f} B"
        n /= 1024.0
    return f"{n:.3g} EiB"  # pragma: no cover


def _meminfo_available() -> int | None:
    with contextlib.suppress(OSError, ValueError):
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    with contextlib.suppress(OSError, ValueError, AttributeError):
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    return None


def _cgroup_free() -> int | None:
    with contextlib.suppress(OSError, ValueError):
        limit = Path("/sys/fs/cgroup/memory.max").read_text().strip()
        if limit != "max":
            used = int(Path("/sys/fs/cgroup/memory.current").read_text().strip())
            return max(int(limit) - used, 0)
    with contextlib.suppress(OSError, ValueError):  # cgroup v1
        limit_v1 = int(Path("/sys/fs/cgroup/memory/memory.limit_in_bytes").read_text())
        if limit_v1 < 1 << 60:
            used = int(Path("/sys/fs/cgroup/memory/memory.usage_in_bytes").read_text())
            return max(limit_v1 - used, 0)
    return None


def _address_space_free() -> int | None:
    try:
        import resource
    except ImportError:  # pragma: no cover - not POSIX
        return None
    with contextlib.suppress(OSError, ValueError):
        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
        if soft == resource.RLIM_INFINITY:
            return None
        pages = int(Path("/proc/self/statm").read_text().split()[0])
        return max(int(soft) - pages * int(os.sysconf("SC_PAGE_SIZE")), 0)
    return None


def available_memory() -> int:
    """Bytes this process can still allocate (see the module docstring); 2**62 if unknown."""
    values = [v for v in (_meminfo_available(), _cgroup_free(), _address_space_free())
              if v is not None]
    return min(values) if values else 1 << 62


def require_memory(nbytes: float, what: str, remedy: str) -> None:
    """Refuse ``nbytes`` for ``what`` if it exceeds :data:`MEMORY_FRACTION` of the memory free.

    Parameters
    ----------
    nbytes : float
        Bytes the allocation needs (may be astronomically large: no allocation happens here).
    what : str
        What needs it, naming the parameters it comes from.
    remedy : str
        What to change.

    Raises
    ------
    RunSizeError
        ``"<what> needs 2.5 TiB of memory, 14.2 GiB available: <remedy>"``.
    """
    free = available_memory()
    if not nbytes <= MEMORY_FRACTION * free:
        raise RunSizeError(f"{what} needs {format_bytes(nbytes)} of memory, "
                           f"{format_bytes(free)} available: {remedy}")
