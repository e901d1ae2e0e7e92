"""Open netCDF files from an in-memory image of their bytes.

Why: the netCDF-C / HDF5 libraries bundled with netCDF4-python share one HDF5 file object
between all handles of the same file in a process. When a user holds a file open (a lazy
``xarray.open_dataset`` in a notebook, say) and a reader opens and closes the same file again,
the shared object is left in a state where the next open crashes the process (segmentation
fault) as soon as the file holds variable-length strings (gearvib runs do: mesh and flank
labels). Known upstream: Unidata/netcdf4-python#1444, pydata/xarray#8289. A handle opened on a
copy of the bytes (``netCDF4.Dataset(..., memory=...)``) shares nothing with other handles,
so reading never touches a file the user holds open.

The image costs the file's size in memory (checked before reading it); the data loaded from it
are what a reader allocates anyway.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import netCDF4

from analysis.netcdf_lock import NETCDF_LOCK
from analysis.readers.integrity import require_memory

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["file_image", "load_image", "open_image"]


def file_image(path: str | os.PathLike[str]) -> bytes:
    """The bytes of ``path``, once their size is known to fit into memory.

    Raises
    ------
    OSError
        The file cannot be read.
    analysis.readers.layout.ReaderError
        The file is larger than the memory a read may use.
    """
    p = Path(path)
    require_memory(p.stat().st_size, p, "the file's bytes")
    return p.read_bytes()


@contextlib.contextmanager
def open_image(path: str | os.PathLike[str], image: bytes | None = None
               ) -> Iterator[netCDF4.Dataset]:
    """A read-only :class:`netCDF4.Dataset` on an in-memory image of ``path``.

    Parameters
    ----------
    path : path-like
        The file (its name labels the handle and the library's messages).
    image : bytes, optional
        Its bytes, when already read (:func:`file_image`); read here otherwise.

    Yields
    ------
    netCDF4.Dataset
        Closed again on exit. :data:`~analysis.netcdf_lock.NETCDF_LOCK` is held
        meanwhile.
    """
    data = file_image(path) if image is None else image
    with NETCDF_LOCK:  # the netCDF library is not thread-safe (analysis.netcdf_lock)
        nc = netCDF4.Dataset(str(path), mode="r", memory=data)
        try:
            yield nc
        finally:
            if nc.isopen():
                nc.close()


def load_image(path: str | os.PathLike[str], image: bytes | None = None,
               **open_kwargs: Any) -> xr.Dataset:
    """The Dataset of ``path`` read by xarray from an in-memory image, fully loaded.

    Parameters
    ----------
    path : path-like
        netCDF-3 or netCDF-4 file.
    image : bytes, optional
        Its bytes, when already read.
    **open_kwargs
        Passed to :func:`xarray.open_dataset` (``decode_times=False``, ...).

    Returns
    -------
    xarray.Dataset
        Loaded into memory; no handle stays open.
    """
    import xarray as xr

    with open_image(path, image) as nc, xr.open_dataset(
            xr.backends.NetCDF4DataStore(nc), **open_kwargs) as ds:
        return ds.load()
