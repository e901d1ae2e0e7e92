"""Read and write the common layout as CF-1.11 netCDF-4 (the project's own file format)."""

from __future__ import annotations

import contextlib
import math
import os
import tempfile
from pathlib import Path

import netCDF4
import numpy as np
import xarray as xr

from analysis.cf import labels_from_cf
from analysis.checks import require_finite_blocks, require_instance
from analysis.netcdf_lock import NETCDF_LOCK
from analysis.readers.cdf3 import check_cdf3, is_cdf3
from analysis.readers.integrity import format_bytes, reading, require_memory
from analysis.readers.layout import ReaderError, clean_attrs, validate_dataset
from analysis.readers.ncimage import file_image, load_image, open_image

__all__ = ["read_netcdf", "write_netcdf"]

_ZLIB_MAX_RATIO = 1032  # deflate's largest compression ratio (258-byte matches in 2 bits)


def _declared_bytes(nc: netCDF4.Dataset) -> int:
    """Bytes the variables of the root group declare (strings count 8 bytes per element)."""
    total = 0
    for var in nc.variables.values():
        count = math.prod(int(n) for n in var.shape)
        itemsize = var.dtype.itemsize if isinstance(var.dtype, np.dtype) else 8
        total += count * max(itemsize, 1)
    return total


def _check_sizes(p: Path, image: bytes) -> None:
    """Refuse a header whose declared sizes the file cannot hold or memory cannot take.

    netCDF-3 headers are walked by :func:`~analysis.readers.cdf3.check_cdf3` before the C
    library parses them (it allocates what the header declares). netCDF-4 (HDF5) data may be
    compressed, but zlib cannot compress more than 1032:1, so a file whose variables use no
    other compression filter cannot declare more than 1032 times its size; and the declared
    data must fit into memory.
    """
    size = len(image)
    with reading(p, "netCDF"), open_image(p, image) as nc:
        file_format = str(nc.file_format)
        declared = _declared_bytes(nc)
        other_filters = any(
            any((var.filters() or {}).get(k) for k in ("szip", "zstd", "bzip2", "blosc"))
            for var in nc.variables.values()
        )
    bounded = file_format.startswith("NETCDF4") and not other_filters
    if bounded and declared > _ZLIB_MAX_RATIO * size + (1 << 20):
        raise ReaderError(
            f"{p}: the {file_format} file declares {format_bytes(declared)} of variable "
            f"data in {format_bytes(size)}, more than zlib can compress into it (1032:1): "
            "its header is corrupt (or its variables were never written)"
        )
    require_memory(2 * declared, p, f"the variables ({format_bytes(declared)} declared)")


def read_netcdf(path: str | os.PathLike[str]) -> xr.Dataset:
    """Read a netCDF file written in the common layout.

    Parameters
    ----------
    path : path-like
        netCDF-3 or netCDF-4 file.

    Returns
    -------
    xarray.Dataset
        Fully loaded into memory (the file is closed again, so it can be overwritten):
        ``time`` in float seconds, string labels as ``str`` dimension coordinates
        (:func:`analysis.cf.labels_from_cf`). Data variables without a ``time`` dimension (a
        simulated run's ``natural_frequency(mode)``, ``flank_contact_changes(mesh)``) are kept
        as coordinates (metadata beside the channels); every data variable is then along
        ``time``.

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    ReaderError
        The file is not readable netCDF (truncated/corrupt), declares more data than a
        netCDF-3 file holds or than memory takes (checked before anything is loaded), a data
        checksum fails (files written by :func:`write_netcdf` carry Fletcher-32 checksums),
        or it does not follow the layout.
    """
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"netCDF file not found: {p}")
    if is_cdf3(p):
        check_cdf3(p)  # before the image is read: a netCDF-3 header may declare anything
    with reading(p, "netCDF"):
        image = file_image(p)
    _check_sizes(p, image)
    with reading(p, "netCDF"):  # an image: see analysis.readers.ncimage
        ds = labels_from_cf(load_image(p, image, decode_times=False, decode_timedelta=False))
    ds = ds.set_coords([v for v in ds.data_vars if "time" not in ds[v].dims])
    ds.attrs.setdefault("source_file", str(p))
    ds = validate_dataset(ds, name=str(p))
    for var in ds.data_vars:  # the layout forbids NaN (netCDF gaps); other readers refuse them
        if ds[var].dtype.kind == "f" and ds[var].size:  # a run without bearings: 0 of them
            try:
                require_finite_blocks(ds[var].transpose(..., "time").values,
                                      f"{p}: channel {var!r}")
            except ValueError as exc:
                raise ReaderError(str(exc)) from None
    return ds


def write_netcdf(ds: xr.Dataset, path: str | os.PathLike[str], *, compress: bool = True) -> Path:
    """Write a Dataset in the common layout to netCDF-4, atomically.

    The file is first written to a temporary file in the target directory and then moved into
    place with :func:`os.replace`; on any error nothing is left at ``path`` (an existing file is
    kept unchanged).

    Parameters
    ----------
    ds : xarray.Dataset
        Dataset following the layout (checked by :func:`validate_dataset`).
    path : path-like
        Target file (a device, FIFO or socket is refused: the rename would replace it).
    compress : bool, optional
        zlib level 4 with shuffle on the data variables (default True).

    Returns
    -------
    pathlib.Path
        The written path.

    Notes
    -----
    Always uses ``engine="netcdf4"`` and ``_FillValue=None`` on the coordinates and on the
    data variables (the layout forbids NaN), see engineering notes A1, pitfalls 1 and 4.
    Numeric arrays carry HDF5 Fletcher-32 checksums, so that a corrupted chunk is reported
    by :func:`read_netcdf` instead of being read as wrong numbers.
    Attributes are cleaned first (bool -> int8, dict -> JSON, None dropped).
    """
    require_instance(ds, xr.Dataset, "ds")
    target = Path(path)
    out = ds.copy()
    out.attrs = clean_attrs(ds.attrs)
    for v in out.variables:
        out[v].attrs = clean_attrs(ds[v].attrs)
    validate_dataset(out, name="write_netcdf(ds)")
    encoding: dict[str, dict[str, object]] = {}
    for v in out.variables:
        enc: dict[str, object] = {"_FillValue": None}
        if out[v].dtype.kind in "iuf" and out[v].ndim:
            enc["fletcher32"] = True  # a checksum per chunk: corruption is found on reading
            if compress and v in out.data_vars:
                enc.update(zlib=True, complevel=4, shuffle=True)
        encoding[str(v)] = enc
    directory = target.parent if str(target.parent) else Path(".")
    if target.exists() and not (target.is_file() or target.is_dir()):
        # a device, FIFO or socket: the rename would replace the node itself
        raise ValueError(f"{target} is not a regular file (a device, FIFO or socket); give the "
                         "name of a file to write")
    # a private temporary folder named like gearvib's temporary files (.<name>.gearvib-<host>-
    # <pid>-<8 chars>.tmp: the next gearvib command in the folder removes it after a SIGKILL)
    # holds the file; once it is removed, a write abandoned by an interrupt cannot create the
    # file again (a plain temporary file it could re-create after its removal)
    folder = Path(tempfile.mkdtemp(prefix=f".{target.name}.gearvib-{_host()}-{os.getpid()}-",
                                   suffix=".tmp", dir=directory))
    tmp = folder / target.name
    try:
        os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        _abandonable(_locked_to_netcdf, out, tmp, encoding)
        os.replace(tmp, target)
    except BaseException:
        _remove_folder(folder)
        raise
    _remove_folder(folder)
    return target


def _locked_to_netcdf(ds: xr.Dataset, path: Path, encoding: dict) -> None:
    """``ds.to_netcdf`` under the process's netCDF lock (the library is not thread-safe)."""
    with NETCDF_LOCK:
        ds.to_netcdf(path, engine="netcdf4", format="NETCDF4", encoding=encoding)


def _remove_folder(folder: Path, attempts: int = 100) -> None:
    """Remove a temporary folder and the files in it, again while a writer refills it (as
    ``gearvib.tempfiles.remove_temporary``, which this package cannot import)."""
    for _ in range(attempts):
        try:
            for entry in os.scandir(folder):
                with contextlib.suppress(OSError):
                    os.unlink(entry.path)
            os.rmdir(folder)
            return
        except FileNotFoundError:
            return
        except OSError:
            continue


def _host() -> str:
    """This host's name in temporary file names (as ``gearvib.tempfiles.host_tag``)."""
    import re
    import socket

    return re.sub(r"[^A-Za-z0-9_]", "_", socket.gethostname().split(".")[0] or "host")[:32]


def _abandonable(fn, *args, **kwargs) -> None:
    """Call ``fn`` in a worker thread that a ``KeyboardInterrupt`` abandons at once.

    Same mechanism as ``gearvib.interrupts.run_abandonable`` (which explains it): a signal
    handler's exception raised inside xarray's backend lock leaves the lock held and the
    clean-up of ``to_netcdf`` waiting for it forever. The main thread only waits here, so the
    interrupt reaches it outside any library lock; the caller then removes the temporary file.
    """
    import _thread
    import threading

    if threading.current_thread() is not threading.main_thread():
        fn(*args, **kwargs)
        return
    done = _thread.allocate_lock()
    box: list[BaseException] = []

    def work() -> None:
        try:
            fn(*args, **kwargs)
        except BaseException as exc:
            box.append(exc)
        finally:
            done.release()

    done.acquire()
    _thread.start_new_thread(work, ())
    try:
        while not done.acquire(timeout=0.05):
            pass
    except BaseException:
        if not _ABANDONED:  # at exit, wait for abandoned writes (HDF5 must not end under them)
            import atexit

            atexit.register(lambda: [lock.acquire() for lock in _ABANDONED])
        _ABANDONED.append(done)
        raise
    if box:
        raise box[0]


_ABANDONED: list = []
