"""The xarray backend ``engine="gearvib"``: gearvib's files as gearvib's readers give them.

::

    import xarray as xr
    run = xr.open_dataset("run.nc", engine="gearvib")     # == gearvib.io.read_run("run.nc")
    rec = xr.open_dataset("rec.nc", engine="gearvib")     # == analysis.readers.read_netcdf(...)

A plain ``xr.open_dataset(path)`` decodes the CF time coordinate into ``datetime64`` (see
:mod:`analysis.cf` and ``docs/files.md``); this engine gives what the toolkit's own readers
give: ``time`` in float seconds and string labels as ``str`` indexes, the data loaded into
memory and the file closed again. Which reader:

* a file whose global ``source`` attribute starts with ``"gearvib"`` (a run of
  ``gearvib simulate``, ``sweep.nc``, ``diagnosis.nc``, ``comparison.nc``, a result's
  ``to_dataset()`` written by :func:`gearvib.io.write_netcdf` or ``to_netcdf``):
  :func:`gearvib.io.read_run`;
* any other netCDF file (a measurement in the readers' common layout, e.g. written by
  :func:`analysis.readers.write_netcdf`): :func:`analysis.readers.read_netcdf`, the reader
  :func:`analysis.measurement.load_measurement` uses for netCDF files.

Registered through the entry-point group ``xarray.backends`` (``pyproject.toml``). xarray
imports every registered backend whenever it lists its engines (any ``open_dataset``), so this
module imports nothing but xarray's base class at import time; the readers are imported when a
file is opened.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from xarray.backends import BackendEntrypoint

from gearvib.checks import cut
from gearvib.paths import is_file

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["GearvibBackendEntrypoint", "file_kind"]

_SUFFIXES = (".nc", ".nc4", ".cdf")
_MAGIC = (b"\x89HDF\r\n\x1a\n", b"CDF\x01", b"CDF\x02", b"CDF\x05")
_PROBE_BYTES = 1 << 20


def _path(filename_or_obj: Any) -> Path:
    if isinstance(filename_or_obj, str | os.PathLike):
        return Path(filename_or_obj)
    raise TypeError(f"engine='gearvib' opens files by path (str or os.PathLike), not "
                    f"{type(filename_or_obj).__name__}")


def file_kind(path: str | os.PathLike) -> str:
    """Which reader the engine uses for ``path``: ``"gearvib"`` (:func:`gearvib.io.read_run`)
    or ``"layout"`` (:func:`analysis.readers.read_netcdf`).

    The global ``source`` attribute decides (read from the header with netCDF4 on an
    in-memory image of the file, see :mod:`analysis.readers.ncimage`).

    Raises
    ------
    gearvib.io.GearvibFileError
        The file is missing or not readable netCDF.
    """
    from gearvib.io import GearvibFileError

    p = Path(path)
    if not is_file(p):
        raise GearvibFileError(f"file not found: {cut(str(p), 200)}")
    from analysis.readers.ncimage import open_image

    try:
        with open_image(p) as nc:
            source = str(getattr(nc, "source", ""))
    except OSError as exc:
        raise GearvibFileError(f"cannot read {cut(str(p), 200)} as netCDF: {exc}") from None
    return "gearvib" if source.strip().startswith("gearvib") else "layout"


class GearvibBackendEntrypoint(BackendEntrypoint):
    """``xarray.open_dataset(path, engine="gearvib")``: see the module notes.

    Only a path and ``drop_variables`` are taken; the data are decoded as the readers decode
    them (float seconds, ``str`` labels), so xarray's decoding options do not apply.
    """

    description = ("gearvib runs, measurements and results as gearvib's readers give them: "
                   "time in float seconds, string labels as indexes")
    open_dataset_parameters = ("filename_or_obj", "drop_variables")

    def open_dataset(
        self,
        filename_or_obj: Any,
        *,
        drop_variables: str | Iterable[str] | None = None,
    ) -> xr.Dataset:
        """The file's Dataset, fully loaded (:func:`gearvib.io.read_run` or
        :func:`analysis.readers.read_netcdf`, by :func:`file_kind`).

        Parameters
        ----------
        filename_or_obj : str or os.PathLike
            The file.
        drop_variables : str or iterable of str, optional
            Variables left out (names that are not in the file are ignored).

        Raises
        ------
        TypeError
            Not a path (a file object or bytes).
        gearvib.io.GearvibFileError
            A gearvib file that cannot be read (:func:`gearvib.io.read_run`).
        analysis.readers.ReaderError
            Another file that is not in the readers' common layout.
        """
        p = _path(filename_or_obj)
        if file_kind(p) == "gearvib":
            from gearvib.io import read_run

            ds = read_run(p)
        else:
            from analysis.readers import read_netcdf

            ds = read_netcdf(p)
        if drop_variables is not None:
            names = [drop_variables] if isinstance(drop_variables, str) else list(drop_variables)
            ds = ds.drop_vars(names, errors="ignore")
        return ds

    def guess_can_open(self, filename_or_obj: Any) -> bool:
        """Whether ``filename_or_obj`` is a netCDF file that names gearvib in its header.

        Cheap and without opening a netCDF handle: a ``.nc``/``.nc4``/``.cdf`` path whose
        first bytes are the netCDF-3 or HDF5 signature and whose first MiB holds ``gearvib``
        (the ``source``, ``history`` or ``gearvib_version`` attribute). xarray asks only when
        no engine is given and its own engines decline, so a plain ``open_dataset`` keeps
        using netCDF4.
        """
        try:
            p = _path(filename_or_obj)
            if p.suffix.lower() not in _SUFFIXES or not p.is_file():
                return False
            with open(p, "rb") as fh:
                head = fh.read(_PROBE_BYTES)
        except (TypeError, OSError):
            return False
        return head.startswith(_MAGIC) and b"gearvib" in head
