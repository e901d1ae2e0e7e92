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
"""

from __future__ import annotations

import contextlib
import getpass
import os
import sys
import tempfile
from pathlib import Path

__all__ = ["cache_candidates", "prepare_cache"]


def _writable(folder: Path) -> bool:
    """Whether a file can be created in ``folder`` (created if missing), as numba checks."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError:
        return False
    return True


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
    if _writable(Path(source_file).resolve().parent / "__pycache__"):
        return None
    own = _numba_user_cache()
    if own is not None and _writable(own):
        return None
    for folder in cache_candidates():
        if _writable(folder):
            os.environ["NUMBA_CACHE_DIR"] = str(folder)
            config = sys.modules.get("numba.core.config")
            if config is not None:  # numba already imported: its config was read then
                config.CACHE_DIR = str(folder)
            return str(folder)
    return None
