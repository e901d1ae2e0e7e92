"""One lock for every netCDF file that gearvib and analysis open or write in a process.

The netCDF-C library (and the HDF5 library under it, as shipped in the ``netCDF4`` wheels) is
not thread-safe: two threads of one process that open, read or write netCDF-4 files at the
same time -- even different files -- can crash the interpreter with a segmentation fault
(netcdf4-python issues 1405 and 1452; xarray issue 7079). xarray's own backend locks do not
cover every call. Threads are common around gearvib: a Dask ``LocalCluster(processes=False)``
or a threaded Dask scheduler running a sweep, a thread pool reading measurements, a web
service. So every netCDF operation of the two packages -- every read (they all go through
:func:`analysis.readers.ncimage.open_image`), :func:`analysis.readers.write_netcdf`,
:func:`gearvib.io.write_netcdf` and the comparison's file -- holds :data:`NETCDF_LOCK` for as
long as the library has a file open. Computations do not hold it: only file input and output
is serialised, which costs nothing in a single thread.

Code outside the two packages that uses netCDF4 or ``xarray.open_dataset`` in threads beside
gearvib should hold the same lock.
"""

from __future__ import annotations

import threading

__all__ = ["NETCDF_LOCK"]

NETCDF_LOCK = threading.RLock()
"""Held while a netCDF file is open for reading or writing (reentrant)."""
