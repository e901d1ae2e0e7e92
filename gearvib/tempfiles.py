"""Temporary files of atomic writes: one recognisable name, and the removal of stale ones.

Every atomic write of gearvib (netCDF runs, reports) writes the whole file to a hidden temporary
file beside its destination and renames it over the destination when complete. The temporary file
is named ::

    .<destination name>.gearvib-<host>-<pid>-<8 random characters>.tmp

e.g. ``.run.nc.gearvib-ws17-40213-9f3a06c1.tmp``: the host and the process id of the writer (the
same pattern as :func:`analysis.readers.write_netcdf`, which cannot import this module). A write
that runs in a worker thread an interrupt can abandon (netCDF,
:func:`gearvib.interrupts.run_abandonable`) writes instead into a hidden *folder* of that name,
which holds the file under its destination name: once the folder is removed, the abandoned writer
cannot create its file again (a plain temporary file it could re-create between its removal and the
exit of the process). An error or an interrupt (SIGINT, SIGTERM) removes the file or folder; only a
process killed with SIGKILL (or a power cut) leaves it behind. :func:`remove_stale` removes the
temporary files of such dead writers: every command that writes into a folder calls it first, so
the next run in the same folder cleans up. A file is removed only when its host is this host and
its process is no longer alive (a live writer, or one on another machine sharing the folder, is
left alone).
"""

from __future__ import annotations

import contextlib
import os
import re
import secrets
import socket
from pathlib import Path

__all__ = [
    "TEMP_GLOB",
    "TEMP_PATTERN",
    "host_tag",
    "parse",
    "pid_alive",
    "prefix",
    "register",
    "remove_own",
    "remove_stale",
    "remove_temporary",
    "temp_path",
    "unregister",
]

TEMP_GLOB = ".*.gearvib-*-*-*.tmp"
"""Glob of the temporary files (see the module docstring)."""
TEMP_PATTERN = re.compile(
    r"^\.(?P<name>.+)\.gearvib-(?P<host>[A-Za-z0-9_]{1,32})-(?P<pid>[0-9]{1,10})"
    r"-(?P<token>[0-9a-z_]{8})\.tmp$")
"""The name of a temporary file: destination name, host tag, process id, random token (8
characters; :func:`tempfile.mkstemp` draws them from the same alphabet)."""

_OWN: set[Path] = set()  # set.add / discard are atomic under the GIL; no lock (see remove_own)


def host_tag() -> str:
    """This host's name as it appears in temporary file names (letters, digits, ``_``)."""
    name = socket.gethostname().split(".")[0] or "host"
    return re.sub(r"[^A-Za-z0-9_]", "_", name)[:32]


def prefix(name: str) -> str:
    """``.<name>.gearvib-<host>-<pid>-``: with :func:`tempfile.mkstemp` (``suffix=".tmp"``,
    which adds 8 random characters) it gives a name of the pattern."""
    return f".{name}.gearvib-{host_tag()}-{os.getpid()}-"


def temp_path(dest: str | os.PathLike) -> Path:
    """A new temporary file name beside ``dest`` (the file is not created)."""
    dest = Path(dest)
    directory = dest.parent if str(dest.parent) else Path(".")
    return directory / f"{prefix(dest.name)}{secrets.token_hex(4)}.tmp"


def parse(path: str | os.PathLike) -> tuple[str, str, int] | None:
    """``(destination name, host, pid)`` of a temporary file name, or None for other names."""
    m = TEMP_PATTERN.match(Path(path).name)
    if m is None:
        return None
    return m["name"], m["host"], int(m["pid"])


def pid_alive(pid: int) -> bool:
    """Whether a process with this id exists on this host (POSIX; True when unsure)."""
    if pid <= 0:
        return False
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError, OverflowError, ValueError):
        return True  # exists under another user, or cannot tell: keep the file
    return True


def remove_stale(directory: str | os.PathLike) -> list[Path]:
    """Remove the temporary files that dead gearvib processes of this host left in a folder.

    Parameters
    ----------
    directory : path-like
        The folder (nothing happens if it does not exist or cannot be listed).

    Returns
    -------
    list of Path
        The files removed.
    """
    d = Path(directory)
    removed: list[Path] = []
    try:
        candidates = sorted(d.glob(TEMP_GLOB))
    except OSError:
        return removed
    host = host_tag()
    for p in candidates:
        info = parse(p)
        if info is None or info[1] != host or pid_alive(info[2]):
            continue
        if remove_temporary(p):
            removed.append(p)
    return removed


def remove_temporary(path: str | os.PathLike, attempts: int = 100) -> bool:
    """Remove a temporary file, or a temporary folder with the files in it; True if removed.

    A folder whose abandoned writer creates its file again meanwhile is emptied again, up to
    ``attempts`` times; once the folder is gone nothing can be created in it. Symbolic links
    are never followed. Safe in a signal handler (no lock; errors are swallowed).
    """
    p = Path(path)
    for _ in range(attempts):
        try:
            if p.is_symlink() or not p.exists():
                return False
            if not p.is_dir():
                p.unlink()
                return True
            for entry in os.scandir(p):
                with contextlib.suppress(OSError):
                    if entry.is_dir(follow_symlinks=False):
                        os.rmdir(entry.path)
                    else:
                        os.unlink(entry.path)
            os.rmdir(p)
            return True
        except OSError:
            continue  # not empty any more (the writer created its file again): again
    return False


def register(path: Path) -> None:
    """Note a temporary file this process is writing (removed by :func:`remove_own`)."""
    _OWN.add(Path(path))


def unregister(path: Path) -> None:
    """Forget a temporary file (renamed into place or removed)."""
    _OWN.discard(Path(path))


def remove_own() -> None:
    """Remove every temporary file this process is writing (before a forced exit).

    Safe in a signal handler: it takes no lock (a lock held by the interrupted code would
    deadlock it).
    """
    paths = list(_OWN)
    _OWN.clear()
    for p in paths:
        remove_temporary(p)
