"""netCDF output of gearvib runs: attribute sanitising, atomic write, checked read.

The files are NETCDF4 written with the netCDF4 engine (xarray's default engine has changed
between releases), zlib-compressed and chunked along ``time``. Coordinates and data that hold no
NaN get ``_FillValue = None`` (CF forbids missing values in coordinate variables). The write is
atomic: a temporary file in the destination directory is written, flushed to disk and renamed
over the destination, so a crash or Ctrl-C never leaves a partial file. The temporary file is
named ``.<name>.gearvib-<host>-<pid>-<token>.tmp`` (:mod:`gearvib.tempfiles`); netCDF files are
written and read in a worker thread that an interrupt abandons (:mod:`gearvib.interrupts`
explains why: xarray's backend locks are not safe against an exception from a signal handler).
String labels (mesh, flank, sensor ... names) are written as UTF-8 character arrays named after
their dimension, ``char mesh(mesh, mesh_strlen)``, which a plain ``xarray.open_dataset`` reads
as a string index (``ds.sel(mesh=...)``) and :func:`read_run` as ``str`` labels; ``time`` is
read as float seconds (see :mod:`analysis.cf`).

A :class:`~gearvib.cfdata.PlainDataset` (a run as NumPy arrays,
:meth:`gearvib.simulate.RunUpResult.to_plain_dataset`) is written with netCDF4 directly,
making the calls xarray's netCDF4 backend makes for the same Dataset, in the same order: the
same file, byte for byte, without importing xarray and pandas (``gearvib simulate``).
"""

from __future__ import annotations

import contextlib
import functools
import json
import math
import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import netCDF4
import numpy as np

from gearvib import tempfiles
from gearvib.cfdata import STRLEN_SUFFIX, PlainDataset, PlainVariable
from gearvib.checks import check_path, cut
from gearvib.interrupts import check_interrupted, run_abandonable
from gearvib.memory import RunSizeError, format_bytes, require_memory
from gearvib.paths import is_file

if TYPE_CHECKING:
    import xarray as xr

__all__ = [
    "GearvibFileError",
    "atomic_write",
    "read_run",
    "sanitize_attrs",
    "write_netcdf",
]

T = TypeVar("T")

_TIME_CHUNK = 65536
_ZLIB_MAX_RATIO = 1032  # deflate's largest compression ratio (258-byte matches in 2 bits)


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
    if not isinstance(attrs, Mapping):
        raise TypeError(f"attrs must be a mapping; got {type(attrs).__name__}")
    return {str(k): _sanitize_value(v) for k, v in attrs.items()}


def _variable_encoding(dims: tuple, shape: tuple, kind: str, has_nan: Callable[[], bool],
                       is_coord: bool) -> dict:
    """netCDF4 encoding of one variable (see the module notes)."""
    e: dict = {}
    if kind in "fc":
        if is_coord or not has_nan():
            e["_FillValue"] = None
    elif kind in "iub":
        e["_FillValue"] = None
    if kind in "fiub" and len(shape) >= 1 and math.prod(shape) > 0:
        e["zlib"] = True
        e["complevel"] = 4
        e["shuffle"] = True
        e["chunksizes"] = tuple(
            min(n, _TIME_CHUNK) if d == "time" else (n if len(shape) == 1 else 1)
            for d, n in zip(dims, shape, strict=True)
        )
    return e


def _has_nan(data: np.ndarray) -> bool:
    return bool(np.isnan(data).any())


def _values_have_nan(var: xr.Variable) -> bool:
    """NaN in ``var``'s values (read only when asked: the values may be lazy)."""
    return _has_nan(var.values)


def _encoding(ds: xr.Dataset) -> dict:
    out = {}
    for name, var in ds.variables.items():
        if var.dims == (name,) and var.dtype.kind in "USO":  # a label array
            out[str(name)] = {"dtype": "S1", "char_dim_name": f"{name}{STRLEN_SUFFIX}"}
            continue
        out[str(name)] = _variable_encoding(
            var.dims, var.shape, var.dtype.kind,
            functools.partial(_values_have_nan, var), name in ds.coords)
    return out


def write_netcdf(ds: xr.Dataset | PlainDataset, path: str | os.PathLike) -> Path:
    """Write a dataset to netCDF4 atomically.

    Parameters
    ----------
    ds : xarray.Dataset or gearvib.cfdata.PlainDataset
        Dataset to write (e.g. :meth:`gearvib.simulate.RunUpResult.to_dataset`). Attributes of
        the dataset and its variables are sanitised (:func:`sanitize_attrs`) on a shallow copy.
        A :class:`~gearvib.cfdata.PlainDataset` (:meth:`RunUpResult.to_plain_dataset
        <gearvib.simulate.RunUpResult.to_plain_dataset>`) is written with netCDF4 directly,
        without importing xarray, as the same file as its :meth:`~gearvib.cfdata.PlainDataset.
        to_xarray` (its data must be float, integer or string arrays).
    path : path-like
        Destination; its directory must exist. An existing file is replaced only once the new
        one is complete.

    Returns
    -------
    pathlib.Path
        The destination.

    Notes
    -----
    Written through :func:`atomic_write` in a worker thread (``abandonable``): nothing
    half-written is left on any error or interrupt, and an interrupt returns at once. The
    write holds :data:`analysis.netcdf_lock.NETCDF_LOCK` (threads of one process
    write one file at a time: the netCDF library is not thread-safe).
    """
    dest = Path(path)
    if not isinstance(ds, PlainDataset):
        import xarray

        if not isinstance(ds, xarray.Dataset):
            raise TypeError(f"ds must be an xarray.Dataset or a PlainDataset; got "
                            f"{type(ds).__name__}")
    if isinstance(ds, PlainDataset):
        plain = _plain_file_content(ds)
        atomic_write(dest, lambda tmp: _write_plain(plain, tmp), abandonable=True)
        return dest
    from analysis.cf import labels_to_cf

    out = labels_to_cf(ds)  # string labels: character arrays (a shallow copy)
    out.attrs = sanitize_attrs(ds.attrs)
    for name in out.variables:
        out[name].attrs = sanitize_attrs(out[name].attrs)
    encoding = _encoding(out)

    def write(tmp: Path) -> None:
        from analysis.netcdf_lock import NETCDF_LOCK

        with NETCDF_LOCK:  # the netCDF library is not thread-safe
            out.to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=encoding)

    atomic_write(dest, write, abandonable=True)
    return dest


def _plain_file_content(ds: PlainDataset) -> tuple[dict[str, PlainVariable], dict, set[str]]:
    """Variables, global attributes and coordinate names as xarray's netCDF4 writer stores
    ``ds.to_xarray()``.

    String dimension coordinates become UTF-8 character arrays ``<dim>(<dim>, <dim>_strlen)``
    with ``_Encoding = "utf-8"`` (as :func:`analysis.cf.labels_to_cf` and xarray's string
    coders), attributes are sanitised, every data variable gets the CF ``coordinates``
    attribute naming the auxiliary coordinates that share its dimensions (sorted, as xarray
    writes it), and auxiliary coordinates that no variable names go into a global
    ``coordinates`` attribute.
    """
    variables = dict(ds.variables())
    coord_names = list(ds.coords)
    sizes = ds.sizes
    labels: dict[str, PlainVariable] = {}
    for name, var in ds.coords.items():
        if var.dims == (name,) and var.data.dtype.kind in "USO":
            strlen = f"{name}{STRLEN_SUFFIX}"
            if strlen in sizes:
                raise ValueError(f"dimension {strlen!r} exists; it is the string length of the "
                                 f"labels of {name!r}")
            attrs = dict(var.attrs)
            attrs.setdefault("long_name", f"{name} label")
            attrs["_Encoding"] = "utf-8"
            encoded = np.array([str(x).encode("utf-8") for x in var.data.ravel()], dtype=bytes)
            chars = encoded.reshape((*encoded.shape, 1)).view("S1")
            labels[name] = PlainVariable((name, strlen), chars, attrs)
    for name, var in variables.items():
        if name not in labels and var.data.dtype.kind not in "fiuU":
            raise ValueError(f"variable {name!r}: dtype {var.data.dtype} is not written without "
                             "xarray (admissible: float, integer, string)")
    variables.update(labels)
    dims = {d for v in variables.values() for d in v.dims}
    auxiliary = {c for c in coord_names if c not in dims}
    written: set[str] = set()
    out: dict[str, PlainVariable] = {}
    for name, var in variables.items():
        attrs = var.attrs if name in labels else sanitize_attrs(var.attrs)
        if name not in auxiliary and name not in var.dims and "coordinates" not in attrs:
            mine = sorted(c for c in auxiliary if set(variables[c].dims) <= set(var.dims))
            if mine:
                attrs["coordinates"] = " ".join(mine)
        if "coordinates" in attrs:
            written.update(str(attrs["coordinates"]).split())
        out[name] = PlainVariable(var.dims, var.data, attrs)
    global_attrs = sanitize_attrs(ds.attrs)
    unnamed = auxiliary - written
    if unnamed and "coordinates" not in global_attrs:
        global_attrs["coordinates"] = " ".join(sorted(unnamed))
    return out, global_attrs, set(coord_names)


def _write_plain(content: tuple[dict[str, PlainVariable], dict, set[str]], tmp: Path) -> None:
    """Write the file content of :func:`_plain_file_content` with netCDF4: the calls, in their
    order and with their arguments, of xarray's netCDF4 backend (global attributes, dimensions
    in the order of first use, then each variable created, given its attributes and written)."""
    from analysis.netcdf_lock import NETCDF_LOCK  # without xarray under `gearvib simulate`

    variables, global_attrs, coords = content
    with NETCDF_LOCK, netCDF4.Dataset(tmp, mode="w", clobber=True, diskless=False, persist=False,
                         format="NETCDF4") as nc:
        for key, value in global_attrs.items():
            arr = np.asarray(value)
            if arr.dtype.kind in "US" and arr.size > 1:
                nc.setncattr_string(key, value)
            else:
                nc.setncattr(key, value)
        sizes: dict[str, int] = {}
        for var in variables.values():
            for d, n in zip(var.dims, var.data.shape, strict=True):
                sizes.setdefault(d, int(n))
        for d, n in sizes.items():
            nc.createDimension(d, size=n)
        for name, var in variables.items():
            data = var.data
            kind = data.dtype.kind
            enc = _variable_encoding(var.dims, data.shape, kind,
                                     functools.partial(_has_nan, data),
                                     name in coords)
            fill = enc.get("_FillValue", np.nan if kind == "f" else None)
            # the stub's overloads take one datatype kind each, and a literal compression
            datatype: Any = str if kind == "U" else data.dtype
            compression: dict[str, Any] = {"compression": "zlib"} if enc.get("zlib") else {}
            nc_var = nc.createVariable(
                varname=name, datatype=datatype, dimensions=var.dims,
                zlib=False, complevel=enc.get("complevel", 4), shuffle=enc.get("shuffle", True),
                fletcher32=False, contiguous=False, chunksizes=enc.get("chunksizes"),
                endian="native", least_significant_digit=None, fill_value=fill,
                **compression)
            nc_var.setncatts(var.attrs)
            nc_var.set_auto_maskandscale(False)
            nc_var.set_auto_chartostring(False)
            nc_var[...] = data


def atomic_write(dest: str | os.PathLike, write: Callable[[Path], T], *,
                 abandonable: bool = False) -> T:
    """Write a file atomically: ``write(tmp)`` on a temporary file beside ``dest``, then rename.

    Parameters
    ----------
    dest : path-like
        Destination; its directory must exist. An existing file is replaced only once the new
        one is complete; a device, FIFO or socket is refused (a rename would replace it).
    write : callable
        ``write(tmp_path)`` writes the whole content to ``tmp_path``; its result is returned.
    abandonable : bool
        Run ``write`` and the ``fsync`` in a worker thread that an interrupt abandons
        (:func:`gearvib.interrupts.run_abandonable`); for library code that is not safe
        against a ``KeyboardInterrupt`` (netCDF through xarray).

    Notes
    -----
    The temporary file ``.<name>.gearvib-<host>-<pid>-<token>.tmp``
    (:func:`gearvib.tempfiles.temp_path`; for an abandonable write the file ``<name>`` in a
    private folder of that name, which an abandoned writer cannot fill again once removed)
    lives in the destination directory (so ``os.replace`` is an atomic rename on the same file
    system), is fsync-ed before the rename and is removed on any error, including
    ``KeyboardInterrupt`` and SIGTERM under the command line; the directory is fsync-ed after
    the rename where possible. Only SIGKILL can leave it;
    :func:`gearvib.tempfiles.remove_stale` removes it later.
    """
    dest = check_path(dest, "dest")
    if not callable(write):
        raise TypeError(f"write must be callable; got {type(write).__name__}")
    if not isinstance(abandonable, bool):
        raise TypeError(f"abandonable must be a bool; got {type(abandonable).__name__}")
    directory = dest.parent if str(dest.parent) else Path(".")
    shown = cut(str(dest), 200)
    try:
        if not directory.is_dir():
            raise FileNotFoundError(f"directory of {shown} does not exist")
        if dest.is_dir():
            raise IsADirectoryError(f"{shown} is a directory (give a file name)")
        if dest.exists() and not dest.is_file():
            # a device, FIFO or socket: the rename would replace the node itself (as root,
            # /dev/null would become a regular file)
            raise ValueError(f"{shown} is not a regular file (a device, FIFO or socket); give "
                             "the name of a file to write")
    except ValueError as exc:
        if "\x00" not in str(dest):  # raised above, with its message
            raise
        raise ValueError(f"{cut(repr(str(dest)), 200)} is not a file name") from exc
    except OSError as exc:
        if exc.strerror is None:  # raised above, with its message
            raise
        raise OSError(exc.errno, f"{shown}: {exc.strerror}") from None
    temporary = tempfiles.temp_path(dest)
    # an abandonable write goes into a private folder of that name: once the folder is gone,
    # the abandoned writer cannot create its file again (tempfiles docstring)
    tmp = temporary / dest.name if abandonable else temporary
    tempfiles.register(temporary)
    try:
        if abandonable:
            os.mkdir(temporary, 0o700)
        # O_EXCL: never clobber; mode 0o666 so the process umask applies as for a plain open()
        os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))

        def body() -> T:
            out = write(tmp)
            with open(tmp, "rb+") as fh:
                os.fsync(fh.fileno())
            return out

        result = run_abandonable(body) if abandonable else body()
        check_interrupted()  # nothing is committed after a signal, even a swallowed one
        os.replace(tmp, dest)
    except BaseException as exc:
        tempfiles.remove_temporary(temporary)
        if isinstance(exc, Exception):
            tempfiles.unregister(temporary)
            full = _no_space(exc, dest, directory)
            if full is not None:
                raise full from None
        # else (an interrupt): it stays listed for the removal just before a forced exit
        # (gearvib.interrupts.exit_now)
        raise
    if abandonable:
        tempfiles.remove_temporary(temporary)  # the empty folder
    tempfiles.unregister(temporary)
    with contextlib.suppress(OSError):  # persist the rename (POSIX); not possible everywhere
        dir_fd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(dir_fd)
        finally:
            os.close(dir_fd)
    return result


LOW_SPACE_BYTES = 4 * 2**20
"""A failed write with less than this left on its file system is reported as a full disk."""


def _no_space(exc: Exception, dest: Path, directory: Path) -> OSError | None:
    """The error to raise when a write failed because its file system is full, else None.

    Libraries do not always say so: HDF5 reports a full disk as ``NetCDF: HDF error``. A write
    that failed with ``ENOSPC``/``EDQUOT``, or while less than :data:`LOW_SPACE_BYTES` are
    left (measured after the temporary file was removed), becomes
    an ``OSError`` (``errno`` ENOSPC) ``"<dest>: No space left on device ..."``.
    """
    import errno
    import shutil

    code = getattr(exc, "errno", None)
    if code not in (errno.ENOSPC, errno.EDQUOT):
        try:
            usage = shutil.disk_usage(directory)
        except OSError:
            return None
        free = usage.free
        if free >= LOW_SPACE_BYTES or usage.total == 0:  # 0: /proc, /sys (nothing to fill)
            return None
        detail = f" ({format_bytes(free)} free on its file system when the write failed)"
    else:
        detail = ""
    what = "Disk quota exceeded" if code == errno.EDQUOT else "No space left on device"
    error = OSError(f"{cut(str(dest), 200)}: {what}{detail}; nothing was written")
    error.errno = errno.ENOSPC if code is None else code
    return error


def _declared_bytes(nc: netCDF4.Dataset) -> int:
    """Bytes the variables of every group declare (strings count 8 bytes per element)."""
    total = 0
    groups = [nc]
    while groups:
        g = groups.pop()
        groups.extend(g.groups.values())
        for var in g.variables.values():
            itemsize = var.dtype.itemsize if isinstance(var.dtype, np.dtype) else 8
            total += math.prod(int(n) for n in var.shape) * max(itemsize, 1)
    return total


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
        If the file is missing, is not readable netCDF, was not written by gearvib (no
        ``source`` attribute starting with ``"gearvib"``), or its header declares more data
        than the file can hold (zlib compresses at most 1032:1). The message names the path.
    gearvib.memory.RunSizeError
        The declared data do not fit into the memory available (checked before loading).
    """
    p = Path(path)
    if not is_file(p):
        raise GearvibFileError(f"gearvib run file not found: {cut(str(p), 200)}")

    def load() -> xr.Dataset:
        from analysis.cf import labels_from_cf
        from analysis.readers.ncimage import file_image, load_image, open_image

        # read from an in-memory image of the file: a handle on the file itself would share
        # the library's file object with any handle the caller holds (a crash, see
        # analysis.readers.ncimage). The declared sizes first, with netCDF4 directly: xarray
        # would load the index coordinates (time) while opening, whatever the header claims
        image = file_image(p)
        with open_image(p, image) as nc:
            declared = _declared_bytes(nc)
        size = p.stat().st_size
        if declared > _ZLIB_MAX_RATIO * size + 2**20:
            raise GearvibFileError(
                f"{p} declares {format_bytes(declared)} of data in {format_bytes(size)}, more "
                "than zlib can compress into it: its header is corrupt")
        require_memory(2 * declared, f"reading {p} ({format_bytes(declared)} declared)",
                       "the run is too large for this machine")
        # float seconds; labels as coordinates again
        return labels_from_cf(load_image(p, image, decode_times=False))

    try:
        loaded = run_abandonable(load)  # see gearvib.interrupts: xarray's locks and Ctrl-C
    except (GearvibFileError, RunSizeError):
        raise
    except Exception as exc:
        raise GearvibFileError(f"cannot read {p} as netCDF: {exc}") from exc
    if not str(loaded.attrs.get("source", "")).startswith("gearvib"):
        raise GearvibFileError(f"{p} is not a gearvib file (no 'source = gearvib ...' attribute)")
    return loaded
