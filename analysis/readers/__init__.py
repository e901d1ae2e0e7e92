"""Readers that turn measured files into the common CF-annotated Dataset layout.

Every reader returns an :class:`xarray.Dataset` with a ``time`` coordinate in seconds and one
data variable per channel carrying ``units`` and ``long_name`` (see
:mod:`analysis.readers.layout`). :func:`read` dispatches on the file extension.

UFF needs ``pip install "gearvib[uff]"`` (pyuff), TDMS ``pip install "gearvib[tdms]"``
(npTDMS) and MATLAB v7.3 ``pip install "gearvib[hdf5]"`` (h5py); each is imported only when
such a file is read.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import xarray as xr

from analysis.readers.csv import read_csv, write_csv
from analysis.readers.layout import (
    ChannelData,
    ReaderError,
    build_dataset,
    to_udunits,
    validate_dataset,
)
from analysis.readers.mat import read_mat, write_mat
from analysis.readers.netcdf import read_netcdf, write_netcdf
from analysis.readers.tdms import read_tdms
from analysis.readers.uff import read_uff
from analysis.readers.wav import read_wav, write_wav

__all__ = [
    "FORMATS",
    "ChannelData",
    "ReaderError",
    "build_dataset",
    "read",
    "read_csv",
    "read_mat",
    "read_netcdf",
    "read_tdms",
    "read_uff",
    "read_wav",
    "to_udunits",
    "validate_dataset",
    "write_csv",
    "write_mat",
    "write_netcdf",
    "write_wav",
]

#: format name -> (reader, file extensions)
FORMATS: dict[str, tuple[Callable[..., xr.Dataset], tuple[str, ...]]] = {
    "netcdf": (read_netcdf, (".nc", ".nc4", ".cdf")),
    "wav": (read_wav, (".wav",)),
    "csv": (read_csv, (".csv", ".txt", ".tsv", ".dat")),
    "mat": (read_mat, (".mat",)),
    "uff": (read_uff, (".uff", ".unv")),
    "tdms": (read_tdms, (".tdms",)),
}


def read(path: str | os.PathLike[str], format: str | None = None, **options: Any) -> xr.Dataset:
    """Read a measured (or simulated) file into the common Dataset layout.

    Parameters
    ----------
    path : path-like
        The file.
    format : {"netcdf", "wav", "csv", "mat", "uff", "tdms"}, optional
        Override the detection from the extension (``.nc``, ``.wav``, ``.csv``/``.txt``,
        ``.mat``, ``.uff``/``.unv``, ``.tdms``).
    **options
        Passed to the reader (e.g. ``fs=``, ``calibration=``, ``group=``).

    Returns
    -------
    xarray.Dataset

    Raises
    ------
    ValueError
        Unknown format or extension (the admissible ones are listed).
    """
    p = Path(path)
    if format is None:
        ext = p.suffix.lower()
        matches = [name for name, (_, exts) in FORMATS.items() if ext in exts]
        if not matches:
            known = ", ".join(e for _, exts in FORMATS.values() for e in exts)
            raise ValueError(
                f"{p}: cannot tell the format from extension {ext!r}; known: {known}; "
                f"or pass format= one of {sorted(FORMATS)}"
            )
        format = matches[0]
    if format not in FORMATS:
        raise ValueError(f"format = {format!r}: admissible are {sorted(FORMATS)}")
    return FORMATS[format][0](p, **options)
