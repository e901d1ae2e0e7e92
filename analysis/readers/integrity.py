"""Checks every reader makes before it trusts a file: sizes and memory, and one error type.

A measured file can be truncated (a copy that stopped, a recorder that lost power) or corrupt
(a flipped bit, a wrong header). The readers never let such a file reach a parser or an
allocation unchecked:

* sizes declared in a header are compared with the size of the file (:func:`require_in_file`)
  and with the memory that is available (:func:`require_memory`) *before* anything of that
  size is allocated or read;
* any failure inside a third-party parser becomes a :class:`ReaderError` naming the file and
  the cause (:func:`reading`), with quoted text of the file masked so that an error never
  echoes file content.

The memory available is the smallest of ``MemAvailable`` (``/proc/meminfo``), the cgroup
limit minus its usage, and the address-space limit (``RLIMIT_AS``) minus the process size.
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field

from analysis.readers.layout import ReaderError

__all__ = [
    "MEMORY_FRACTION",
    "Notes",
    "available_memory",
    "describe",
    "file_size",
    "format_bytes",
    "memory_budget",
    "reading",
    "require_in_file",
    "require_memory",
]

#: Share of the available memory one read may plan to use.
MEMORY_FRACTION = 0.8

_QUOTED = re.compile(r"'[^'\n]{0,200}'|\"[^\"\n]{0,200}\"|b'[^'\n]{0,200}'")
_MAX_CAUSE = 240


def format_bytes(n: float) -> str:
    """``1536`` -> ``"1.5 kB"``; binary multiples above 1 MiB (``"16 GiB"``)."""
    n = float(n)
    if n < 1e3:
        return f"{n:.0f} B"
    if n < 2**20:
        return f"{n / 1e3:.3g} kB"
    for unit, k in (("PiB", 50), ("TiB", 40), ("GiB", 30), ("MiB", 20)):
        if n >= 2**k:
            return f"{n / 2**k:.3g} {unit}"
    return f"{n:.0f} B"


def file_size(path: str | os.PathLike[str]) -> int:
    """Size of ``path`` in bytes."""
    return os.stat(os.fspath(path)).st_size  # fspath: an int would stat a file descriptor


def _read_int(path: str) -> int | None:
    try:
        with open(path) as fh:
            text = fh.read().strip()
    except OSError:
        return None
    return int(text) if text.isdigit() else None


def available_memory() -> int:
    """Bytes this process can still allocate without swapping or being killed.

    The minimum of ``MemAvailable`` from ``/proc/meminfo``, the cgroup (v2 or v1) limit minus
    the cgroup's usage, and ``RLIMIT_AS`` minus the current address-space size. Where none of
    them can be read (not Linux), the physical memory from :func:`os.sysconf`, else 2**63.
    """
    limits: list[int] = []
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    limits.append(int(line.split()[1]) * 1024)
                    break
    except (OSError, ValueError, IndexError):
        pass
    for limit_file, usage_file in (
        ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
        (
            "/sys/fs/cgroup/memory/memory.limit_in_bytes",
            "/sys/fs/cgroup/memory/memory.usage_in_bytes",
        ),
    ):
        limit, usage = _read_int(limit_file), _read_int(usage_file)
        if limit is not None and usage is not None and limit < 2**60:
            limits.append(max(limit - usage, 0))
    try:
        import resource

        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
        if soft != resource.RLIM_INFINITY:
            with open("/proc/self/statm") as fh:
                vm_size = int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
            limits.append(max(soft - vm_size, 0))
    except (ImportError, OSError, ValueError, IndexError):
        pass
    if not limits:
        try:
            limits.append(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
        except (ValueError, OSError, AttributeError):
            limits.append(2**63)
    return min(limits)


def memory_budget() -> float:
    """Bytes one read may plan to use: :data:`MEMORY_FRACTION` of :func:`available_memory`."""
    return MEMORY_FRACTION * available_memory()


def require_memory(nbytes: float, path: str | os.PathLike[str], what: str) -> None:
    """Raise :class:`ReaderError` unless ``nbytes`` fit into the memory a read may use.

    Parameters
    ----------
    nbytes : float
        Bytes the reader is about to allocate (computed from declared sizes).
    path : path-like
        The file (named in the message).
    what : str
        What needs the memory (``"12 channels of 1e9 samples"``), for the message.
    """
    budget = memory_budget()
    if nbytes > budget:
        raise ReaderError(
            f"{path}: {what} needs {format_bytes(nbytes)} of memory, but only "
            f"{format_bytes(budget)} can be used ({MEMORY_FRACTION:.0%} of the available "
            f"{format_bytes(budget / MEMORY_FRACTION)}); the header may be corrupt, or read "
            "the file in parts / on a machine with more memory"
        )


def require_in_file(
    end: int,
    size: int,
    path: str | os.PathLike[str],
    what: str,
    *,
    format_name: str,
    start: int | None = None,
) -> None:
    """Raise :class:`ReaderError` if a declared region ends beyond the end of the file.

    Parameters
    ----------
    end : int
        Offset (bytes) just after the last byte the header says belongs to the region.
    size : int
        Size of the file in bytes.
    path : path-like
        The file, for the message.
    what : str
        The region (``"data chunk"``, ``"variable 'acc'"``), for the message.
    format_name : str
        The format, for the message (``"MAT"``).
    start : int, optional
        Offset where the region starts, to state the declared length.
    """
    if end > size:
        declared = f" ({end - start} bytes from byte {start})" if start is not None else ""
        raise ReaderError(
            f"{path}: not a readable {format_name} file: {what} declares data up to byte {end}"
            f"{declared}, but the file has {size} bytes: it is truncated or its header is "
            "corrupt"
        )


def describe(exc: BaseException) -> str:
    """One-line description of an exception for an error message, without file content.

    Quoted fragments (which parsers fill with the offending text of the file) are replaced by
    ``'…'`` and the text is cut to a few hundred characters.
    """
    text = " ".join(str(exc).split())
    text = _QUOTED.sub("'…'", text)
    if len(text) > _MAX_CAUSE:
        text = text[: _MAX_CAUSE - 1] + "…"
    name = type(exc).__name__
    return f"{name}: {text}" if text else name


@dataclass
class Notes:
    """What a library reported while :func:`reading` ran: Python warnings and log records."""

    warnings: list[str] = field(default_factory=list)
    log: list[str] = field(default_factory=list)


class _LogToError(logging.Handler):
    """Collects warnings a library logs (npTDMS reports truncation through ``logging``)."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())


@contextlib.contextmanager
def reading(
    path: str | os.PathLike[str], format_name: str, *, logger: str | None = None
) -> Iterator[Notes]:
    """Context in which every failure of a parser becomes a :class:`ReaderError`.

    ``ReaderError`` passes unchanged; ``ImportError`` (a missing optional library) and
    ``KeyboardInterrupt``/``SystemExit`` are not touched. Any other exception -- including
    ``MemoryError``, ``RecursionError`` and the assorted errors third-party parsers raise on
    damaged input -- is re-raised as ``ReaderError("<path>: not a readable <format> file
    (<cause>)")``. Python warnings raised inside are suppressed and, like the warnings of
    the ``logger`` given (a library that reports damage through :mod:`logging`), collected
    in the :class:`Notes` the context yields, so that the caller can decide which of them
    mean damage.

    Parameters
    ----------
    path : path-like
        The file being read.
    format_name : str
        Format for the message (``"WAV"``, ``"TDMS"``).
    logger : str, optional
        Name of a :mod:`logging` logger whose warnings are collected too.
    """
    notes = Notes()
    handler = _LogToError()
    saved = _capture_logs(logger, handler) if logger else []
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                yield notes
            finally:
                notes.warnings.extend(str(w.message) for w in caught)
                notes.log.extend(handler.messages)
    except (ReaderError, ImportError):
        raise
    except MemoryError:
        raise ReaderError(
            f"{path}: not a readable {format_name} file: it needs more memory than is "
            "available (a corrupt header declaring huge sizes?)"
        ) from None
    except Exception as exc:
        raise ReaderError(
            f"{path}: not a readable {format_name} file (truncated or corrupt?): {describe(exc)}"
        ) from None
    finally:
        for log, handlers, propagate in saved:
            log.handlers[:] = handlers
            log.propagate = propagate


def _capture_logs(
    name: str, handler: logging.Handler
) -> list[tuple[logging.Logger, list[logging.Handler], bool]]:
    """Route the warnings of logger ``name`` and its children (some libraries give every
    module a logger with its own console handler) to ``handler`` only; return what to
    restore."""
    names = [name] + [
        k for k in list(logging.Logger.manager.loggerDict) if k.startswith(name + ".")
    ]
    saved = []
    for n in names:
        log = logging.getLogger(n)
        saved.append((log, list(log.handlers), log.propagate))
        log.handlers[:] = [handler]
        log.propagate = False
    return saved
