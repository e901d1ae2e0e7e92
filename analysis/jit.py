"""A writable on-disk cache for numba's compiled functions, also in read-only installs.

numba caches ``@njit(cache=True)`` functions next to their source (``__pycache__``) or, when
that folder is not writable, in a user-wide cache folder. When neither is writable -- a
package installed into a read-only site-packages by root, a container image, Nix -- the
decorator fails at import with ``RuntimeError: cannot cache function ...: no locator
available`` (numba issues #4908, #5566). :func:`prepare_cache` runs before such a module
decorates its functions: if numba would find no writable place, it points numba at one
(``NUMBA_CACHE_DIR``): ``$XDG_CACHE_HOME/gearvib/numba`` or ``~/.cache/gearvib/numba``,
else ``<tempdir>/gearvib-numba-<user>``. A ``NUMBA_CACHE_DIR`` set by the user is always
respected.

Only private folders are used (:func:`private_folder`): owned by this user, a real directory
(not a symbolic link) and not writable by group or others; the folders made here are made with
mode 0700. numba's cache index is a pickle and gearvib loads generated Python modules from the
cache (:mod:`gearvib.kernels_batch`, :mod:`gearvib.fault_pass`), so a folder another local user
can write to (say ``/tmp/gearvib-numba-<user>`` planted with mode 777) would let that user run
code as this one: such a folder is skipped with a :class:`UnsafeCacheWarning`. When no private
folder is left, a new private temporary folder serves this process (compiled again next time).
"""

from __future__ import annotations

import contextlib
import getpass
import os
import sys
import tempfile
from pathlib import Path

__all__ = ["UnsafeCacheWarning", "cache_candidates", "prepare_cache", "private_folder"]


class UnsafeCacheWarning(UserWarning):
    """A cache folder was skipped because another user could write to it."""


def private_folder(folder: str | os.PathLike[str], *, create: bool = True) -> bool:
    """Whether ``folder`` is private to this user: a directory (not a symbolic link) owned by
    the current user and writable by nobody else.

    Parameters
    ----------
    folder : path-like
        The folder.
    create : bool
        Make it (and missing parents) with mode 0700 when it does not exist.

    Returns
    -------
    bool
        ``False`` for a folder that is missing (and not created), a symbolic link, a file,
        owned by another user or writable by group or others. On systems without POSIX
        ownership (Windows) every existing directory counts as private.
    """
    path = Path(folder)
    if create and not os.path.lexists(path):
        with contextlib.suppress(OSError):
            os.makedirs(path, mode=0o700, exist_ok=True)
    try:
        st = os.lstat(path)
    except OSError:
        return False
    import stat

    if not stat.S_ISDIR(st.st_mode):
        return False
    if not hasattr(os, "getuid"):
        return True
    return st.st_uid == os.getuid() and not st.st_mode & (stat.S_IWGRP | stat.S_IWOTH)


def _writable(folder: Path) -> bool:
    """Whether a file can be created in ``folder`` (made with mode 0700 if missing), as numba
    checks."""
    try:
        if not folder.exists():
            os.makedirs(folder, mode=0o700, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError:
        return False
    return True


def _usable(folder: Path) -> bool:
    """Writable and private; an existing folder that is writable but not private is skipped
    with a warning."""
    if not _writable(folder):
        return False
    if private_folder(folder, create=False):
        return True
    import warnings

    warnings.warn(f"gearvib: numba cache folder {folder} skipped: it is not private to this "
                  "user (owned by another user, a symbolic link, or writable by others)",
                  UnsafeCacheWarning, stacklevel=3)
    return False


def _user() -> str:
    with contextlib.suppress(Exception):
        return getpass.getuser()
    return str(os.getuid()) if hasattr(os, "getuid") else "user"


def cache_candidates() -> list[Path]:
    """Folders tried, in order, when numba cannot cache next to the sources."""
    home = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return [
        Path(home) / "gearvib" / "numba",
        Path(tempfile.gettempdir()) / f"gearvib-numba-{_user()}",
    ]


def _numba_user_cache() -> Path | None:
    """numba's own user-wide cache folder (its second choice), if it can be determined."""
    try:
        from numba.misc.appdirs import AppDirs
    except ImportError:  # pragma: no cover - depends on numba's layout
        return None
    return Path(AppDirs(appname="numba", appauthor=False).user_cache_dir)


def prepare_cache(source_file: str) -> str | None:
    """Make sure numba can cache the functions of the module ``source_file``.

    Parameters
    ----------
    source_file : str
        ``__file__`` of the module that defines ``@njit(cache=True)`` functions.

    Returns
    -------
    str or None
        The cache folder set (``NUMBA_CACHE_DIR``), or ``None`` when numba's own choice
        works or the user set one.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    here = Path(source_file).resolve().parent / "__pycache__"
    if _writable(here) and private_folder(here, create=False):
        return None
    own = _numba_user_cache()
    if own is not None and _usable(own):
        # numba's second choice; named explicitly when its first (``here``) is writable but
        # not private, else numba would take that
        return _use(own) if _writable(here) else None
    for folder in cache_candidates():
        if _usable(folder):
            return _use(folder)
    return _use(Path(tempfile.mkdtemp(prefix="gearvib-numba-")))  # mode 0700, this process


def _use(folder: Path) -> str:
    os.environ["NUMBA_CACHE_DIR"] = str(folder)
    config = sys.modules.get("numba.core.config")
    if config is not None:  # numba already imported: its config was read then
        config.CACHE_DIR = str(folder)  # type: ignore[attr-defined]  # set by numba at run time
    return str(folder)
