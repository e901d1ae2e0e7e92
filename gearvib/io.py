"""netCDF output of gearvib runs: attribute sanitising, atomic write, checked read.

The files are NETCDF4 written with the netCDF4 engine (xarray's default engine has changed
between releases), zlib-compressed and chunked along ``time``. Coordinates and data that hold no
NaN get ``_FillValue = None`` (CF forbids missing values in coordinate variables). The write is
atomic: a temporary file in the destination directory is written, flushed to disk and renamed
over the destination, so a crash or Ctrl-C never leaves a partial file. String labels (mesh,
flank, ... names) are written as CF label variables ``<dim>_label`` and restored by
:func:`read_run`; ``time`` is read as float seconds (see :mod:`analysis.cf`).
"""

from __future__ import annotations

import contextlib
import json
import os
import uuid
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TypeVar

import numpy as np
import xarray as xr

from analysis.cf import labels_from_cf, labels_to_cf

__all__ = [
    "GearvibFileError",
    "atomic_write",
    "read_run",
    "sanitize_attrs",
    "write_netcdf",
]

T = TypeVar("T")

_TIME_CHUNK = 65536


class GearvibFileError(OSError):
    """A file is missing, unreadable or not a gearvib run."""


def _sanitize_value(value: object) -> object:
    if isinstance(value, bool | np.bool_):
        return np.int8(bool(value))
    if isinstance(value, Mapping):
        return json.dumps(value, sort_keys=True, default=str)
    if value is None:
        return ""
    if isinstance(value, str | bytes | int | float | np.integer | np.floating):
        return value
    if isinstance(value, list | tuple | np.ndarray):
        arr = np.asarray(value)
        if arr.dtype.kind in "biuf" and arr.ndim == 1:
            return arr.astype(np.int8) if arr.dtype.kind == "b" else arr
        return json.dumps(np.asarray(value).tolist(), default=str)
    return str(value)


def sanitize_attrs(attrs: Mapping) -> dict:
    """Attributes that netCDF can store.

    ``bool`` becomes ``int8`` (0/1), a mapping becomes a JSON string, ``None`` an empty string,
    nested or non-numeric sequences JSON and anything else ``str``; numbers, strings and 1-D
    numeric arrays are kept.
    """
    return {str(k): _sanitize_value(v) for k, v in attrs.items()}


def _encoding(ds: xr.Dataset) -> dict:
    enc: dict[str, dict] = {}
    for name, var in ds.variables.items():
        e: dict = {}
        kind = var.dtype.kind
        if kind in "fc":
            if name in ds.coords or not bool(np.isnan(var.values).any()):
                e["_FillValue"] = None
        elif kind in "iub":
            e["_FillValue"] = None
        if kind in "fiub" and var.ndim >= 1 and var.size > 0:
            e["zlib"] = True
            e["complevel"] = 4
            e["shuffle"] = True
            e["chunksizes"] = tuple(
                min(n, _TIME_CHUNK) if d == "time" else (n if var.ndim == 1 else 1)
                for d, n in zip(var.dims, var.shape, strict=True)
            )
        enc[str(name)] = e
    return enc


def write_netcdf(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write a dataset to netCDF4 atomically.

    Parameters
    ----------
    ds : xarray.Dataset
        Dataset to write (e.g. :meth:`gearvib.simulate.RunUpResult.to_dataset`). Attributes of
        the dataset and its variables are sanitised (:func:`sanitize_attrs`) on a shallow copy.
    path : path-like
        Destination; its directory must exist. An existing file is replaced only once the new
        one is complete.

    Returns
    -------
    pathlib.Path
        The destination.

    Notes
    -----
    Written through :func:`atomic_write`: nothing half-written is left on any error, including
    ``KeyboardInterrupt``.
    """
    dest = Path(path)
    out = labels_to_cf(ds.copy(deep=False))  # string labels: CF label variables, not coordinates
    out.attrs = sanitize_attrs(ds.attrs)
    for name in out.variables:
        out[name].attrs = sanitize_attrs(out[name].attrs)
    atomic_write(dest, lambda tmp: out.to_netcdf(tmp, engine="netcdf4", format="NETCDF4",
                                                 encoding=_encoding(out)))
    return dest


def atomic_write(dest: str | os.PathLike, write: Callable[[Path], T]) -> T:
    """Write a file atomically: ``write(tmp)`` on a temporary file beside ``dest``, then rename.

    Parameters
    ----------
    dest : path-like
        Destination; its directory must exist. An existing file is replaced only once the new
        one is complete.
    write : callable
        ``write(tmp_path)`` writes the whole content to ``tmp_path``; its result is returned.

    Notes
    -----
    The temporary file lives in the destination directory (so ``os.replace`` is an atomic
    rename on the same file system), is fsync-ed before the rename and is removed on any error,
    including ``KeyboardInterrupt``; the directory is fsync-ed after the rename where possible.
    """
    dest = Path(dest)
    directory = dest.parent if str(dest.parent) else Path(".")
    if not directory.is_dir():
        raise FileNotFoundError(f"directory of {dest} does not exist")
    tmp = directory / f".{dest.name}.{uuid.uuid4().hex}.tmp"
    # O_EXCL: never clobber; mode 0o666 so the process umask applies as for a plain open()
    os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
    try:
        result = write(tmp)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, dest)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    with contextlib.suppress(OSError):  # persist the rename (POSIX); not possible everywhere
        dir_fd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(dir_fd)
        finally:
            os.close(dir_fd)
    return result


def read_run(path: str | os.PathLike) -> xr.Dataset:
    """Read a gearvib netCDF file into memory.

    Parameters
    ----------
    path : path-like
        File written by :func:`write_netcdf`.

    Returns
    -------
    xarray.Dataset
        Loaded dataset (the file is closed).

    Raises
    ------
    GearvibFileError
        If the file is missing, is not readable netCDF, or was not written by gearvib (no
        ``source`` attribute starting with ``"gearvib"``). The message names the path.
    """
    p = Path(path)
    if not p.is_file():
        raise GearvibFileError(f"gearvib run file not found: {p}")
    try:
        with xr.open_dataset(p, engine="netcdf4", decode_times=False) as ds:
            loaded = labels_from_cf(ds.load())  # float seconds; labels as coordinates again
    except Exception as exc:
        raise GearvibFileError(f"cannot read {p} as netCDF: {exc}") from exc
    if not str(loaded.attrs.get("source", "")).startswith("gearvib"):
        raise GearvibFileError(f"{p} is not a gearvib file (no 'source = gearvib ...' attribute)")
    return loaded
