"""The candidate library: order profiles of simulated candidates, kept between diagnoses.

A diagnosis simulates the healthy gear set and every candidate fault at the measured operating
point and keeps only their order profiles (:func:`analysis.diagnosis.order_profile` of each
assumed sensor). These profiles depend on the gear set, the candidate, the assumed sensors,
the simulated operating point and the profile settings -- not on the measured record itself --
so the next diagnosis at that operating point (another record of the same machine, a longer
one, another output folder, another command) finds them here instead of simulating again.

Layout::

    LIBRARY/<digest>/<key>.npz

* ``<digest>`` (:func:`code_digest`): gearvib's version, the SHA-256 of the source files of
  the ``gearvib`` and ``analysis`` packages and the versions of numpy, scipy, numba and
  xarray. Another version of the code, or of a library the numbers depend on, looks into
  another folder: its entries are never mixed with these.
* ``<key>`` (:func:`entry_key`): SHA-256 of the canonical JSON of everything the profiles
  depend on (the gear-set description and its folder, the candidate fault, the assumed
  sensors, the run settings, the profile settings). The JSON itself is stored in the entry
  and compared on loading.

Entries are written atomically (a temporary file in the same folder, named as
:mod:`gearvib.tempfiles` names them, then :func:`os.replace`), so a reader sees a complete
entry or none, also with several diagnoses running at once; the temporary files of killed
writers are removed when the folder is opened next. The folders are private (made with
mode 0700; a folder another user could write to is refused,
:func:`analysis.jit.private_folder`). An entry that does not load (truncated by a full disk,
another key) counts as missing and is computed again.
Default folder: ``$GEARVIB_DIAGNOSIS_LIBRARY``, else ``$XDG_CACHE_HOME/gearvib/diagnosis``
or ``~/.cache/gearvib/diagnosis``. Deleting it is always safe.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import tempfile
import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from analysis.jit import private_folder
from gearvib import tempfiles

__all__ = ["ENV_VARIABLE", "code_digest", "default_library", "entry_key", "library_folder",
           "load_entry", "save_entry", "source_digest"]

ENV_VARIABLE = "GEARVIB_DIAGNOSIS_LIBRARY"
"""Environment variable naming the library folder."""

_FIELDS = ("order", "amplitude", "segments", "natural_frequency")


def source_digest(roots: list[Path], h: Any = None) -> Any:
    """SHA-256 (a ``hashlib`` object) of the ``*.py`` source files under ``roots``: each
    file's path relative to its root's parent and its bytes, sorted; files in
    ``__pycache__`` folders (modules generated into numba's cache) are not code and left
    out."""
    h = hashlib.sha256() if h is None else h
    for root in roots:
        root = Path(root).resolve()
        for p in sorted(root.rglob("*.py")):
            if "__pycache__" in p.relative_to(root).parts:
                continue
            h.update(str(p.relative_to(root.parent)).encode())
            h.update(p.read_bytes())
    return h


@functools.cache
def code_digest() -> str:
    """Short SHA-256 of the code and libraries the simulated profiles depend on.

    gearvib's version, the versions of numpy, scipy, numba and xarray and the source files
    of the ``gearvib`` and ``analysis`` packages (:func:`source_digest`). Computed once per
    process (about 20 ms).
    """
    import numba
    import scipy
    import xarray

    import analysis
    import gearvib

    h = hashlib.sha256()
    h.update(json.dumps([gearvib.__version__, np.__version__, scipy.__version__,
                         numba.__version__, xarray.__version__]).encode())
    roots = []
    for pkg in (gearvib, analysis):
        assert pkg.__file__ is not None  # regular packages, not namespace ones
        roots.append(Path(pkg.__file__).resolve().parent)
    return source_digest(roots, h).hexdigest()[:20]


def default_library() -> Path:
    """The default library folder (see the module docstring)."""
    env = os.environ.get(ENV_VARIABLE)
    if env:
        return Path(env)
    home = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(home) / "gearvib" / "diagnosis"


def library_folder(root: str | os.PathLike) -> Path:
    """The folder of this code's entries in the library ``root`` (created, private).

    Raises
    ------
    PermissionError
        ``root`` or the entries' folder is not private to this user (owned by another user,
        a symbolic link, writable by others) or cannot be made.
    """
    root = Path(root)
    folder = root / code_digest()
    for f in (root, folder):
        if not private_folder(f, create=True):
            raise PermissionError(f"diagnosis library folder {f} is not usable: it must be a "
                                  "directory private to this user (not a symbolic link, not "
                                  "writable by others); give another folder (library=, "
                                  f"--library or ${ENV_VARIABLE})")
    tempfiles.remove_stale(folder)
    return folder


def entry_key(description: dict[str, Any]) -> tuple[str, str]:
    """``(key, canonical JSON)`` of what an entry depends on."""
    text = json.dumps(description, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:32], text


def entry_path(folder: Path, key: str) -> Path:
    """File of an entry."""
    return folder / f"{key}.npz"


def load_entry(folder: Path, key: str, text: str) -> dict[str, np.ndarray] | None:
    """The arrays of an entry, or None when it is missing, unreadable or of another key."""
    path = entry_path(folder, key)
    try:
        with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as z:
            if str(z["key"]) != text:
                return None
            return {k: np.array(z[k]) for k in _FIELDS}
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile):
        return None


def save_entry(folder: Path, key: str, text: str, arrays: dict[str, np.ndarray]) -> Path:
    """Write an entry atomically (temporary file in ``folder``, then :func:`os.replace`)."""
    path = entry_path(folder, key)
    fd, name = tempfile.mkstemp(prefix=tempfiles.prefix(path.name), suffix=".tmp", dir=folder)
    tmp = Path(name)
    tempfiles.register(tmp)
    try:
        with os.fdopen(fd, "wb") as fh:
            payload: dict[str, Any] = {"key": np.array(text),
                                       **{k: np.asarray(arrays[k]) for k in _FIELDS}}
            np.savez(fh, **payload)
        os.replace(tmp, path)
    except BaseException:
        tempfiles.remove_temporary(tmp)
        raise
    finally:
        tempfiles.unregister(tmp)
    return path
