"""MATLAB .mat reader and writer (v4 to v7.2 via :func:`scipy.io.loadmat`, v7.3 via h5py).

Every non-empty numeric vector in the file is a channel; a numeric matrix gives one channel per
column (samples along the longer dimension), named ``<variable>_1``, ``<variable>_2``, ... Numeric
scalars are metadata (one of them may be the sample rate). An optional struct variable
``units`` maps channel variable names to unit labels (written by :func:`write_mat`).
MATLAB v7.3 files (HDF5; told apart by the ``MATLAB 7.3 MAT-file`` header text) are decoded
by :mod:`analysis.readers.mat73` into the same values and then follow the same rules; they
need ``pip install "gearvib[hdf5]"`` (h5py).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from analysis.checks import sample_rate
from analysis.readers.integrity import describe, reading
from analysis.readers.layout import (
    ChannelData,
    ReaderError,
    build_dataset,
    to_udunits,
    validate_dataset,
)
from analysis.readers.mat73 import is_mat73, load_mat73
from analysis.readers.matcheck import check_mat

__all__ = ["read_mat", "write_mat"]

_FS_NAMES = ("fs", "Fs", "FS", "sample_rate", "sample_rate_hz", "samplerate", "SampleRate")


def _load(p: Path) -> tuple[dict[str, Any], str]:
    """Variables of the file (as ``loadmat(squeeze_me=True)`` gives them) and the format tag.

    v4-v7.2 files are walked by :func:`~analysis.readers.matcheck.check_mat` first, so that
    scipy never sees a structure it could crash or over-allocate on; whatever scipy still
    raises, and its warning about an unreadable variable (which it would otherwise return as
    a string), become :class:`ReaderError`.
    """
    from scipy.io import loadmat

    if is_mat73(p):
        return load_mat73(p), "mat73"
    if check_mat(p).version == "7.3":  # the version field says HDF5, the header text does not
        return load_mat73(p), "mat73"
    with reading(p, "MAT") as notes:
        loaded = loadmat(p, squeeze_me=True, chars_as_strings=True, spmatrix=False)
    damage = [n for n in notes.warnings if "nreadable variable" in n or "uplicate variable" in n]
    if damage:
        raise ReaderError(f"{p}: not a readable MAT file: {describe(Exception(damage[0]))}")
    return loaded, "mat"


def _units_struct(value: object) -> dict[str, str]:
    if isinstance(value, Mapping):  # a v7.3 struct
        return {str(k): str(v) for k, v in value.items()}
    arr = np.asarray(value)
    if arr.dtype.names is None or arr.size != 1:
        return {}
    item = arr.reshape(()) if arr.ndim else arr
    return {k: str(item[k].item() if np.ndim(item[k]) == 0 else item[k]) for k in arr.dtype.names}


def read_mat(
    path: str | os.PathLike[str],
    fs: float | str | None = None,
    time_variable: str | None = None,
    variables: Sequence[str] | None = None,
    units: str | Sequence[str] | Mapping[str, str] | None = None,
) -> xr.Dataset:
    """Read a MATLAB .mat file (v4 to v7.3) into the common layout.

    Parameters
    ----------
    path : path-like
        MAT file. v4-v7.2 files are read with :func:`scipy.io.loadmat`; v7.3 (HDF5) files,
        recognised by their header text, with h5py (``pip install "gearvib[hdf5]"``). Both
        give the same Dataset for the same content.
    fs : float or str, optional
        Sample rate [Hz], or the name of a scalar variable in the file holding it. Default: the
        ``time_variable``, else a scalar named ``fs``/``Fs``/``sample_rate``/...
    time_variable : str, optional
        Name of a uniformly sampled time vector [s]; it becomes the ``time`` coordinate.
    variables : sequence of str, optional
        Variables to read as channels (default: every non-empty numeric vector/matrix).
    units : str, sequence or mapping, optional
        One unit for all channels, one per channel, or variable name -> unit; default from a
        ``units`` struct in the file, else ``"1"``.

    Returns
    -------
    xarray.Dataset
        Common layout; ``source_format`` is ``"mat"`` (v4-v7.2) or ``"mat73"`` (v7.3).

    Raises
    ------
    ReaderError
        Truncated or corrupt file, no sample rate, missing or non-numeric variables, empty
        channels, channels of unequal length, NaN samples (naming the channel and sample index).
    ValueError
        ``fs`` disagrees with ``time_variable``; ``units`` of the wrong length.
    ImportError
        A v7.3 file and h5py is not installed.
    """
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"MAT file not found: {p}")
    loaded, source_format = _load(p)
    content = {k: v for k, v in loaded.items() if not k.startswith("__")}
    file_units = _units_struct(content.pop("units", None))
    scalars = {
        k: float(v)
        for k, v in content.items()
        if np.ndim(v) == 0 and np.asarray(v).dtype.kind in "iuf"
    }
    start = 0.0
    rate: float | None = None
    if time_variable is not None:
        if time_variable not in content:
            raise ReaderError(f"{p}: time_variable {time_variable!r} not in {sorted(content)}")
        try:
            rate = sample_rate(
                np.ravel(content[time_variable]).astype(float), name=f"{p}: {time_variable}"
            )
        except ValueError as exc:
            raise ReaderError(str(exc)) from None
        start = float(np.ravel(content[time_variable])[0])
    if isinstance(fs, str):
        if fs not in scalars:
            raise ReaderError(f"{p}: fs = {fs!r} is not a numeric scalar in the file")
        if not (np.isfinite(scalars[fs]) and scalars[fs] > 0):
            raise ReaderError(f"{p}: the sample rate {fs} = {scalars[fs]!r} in the file is "
                              "not finite and > 0")  # fmt: skip
        fs = scalars[fs]
    if fs is not None:
        if rate is not None and abs(rate - fs) > 1e-6 * fs:
            raise ValueError(f"fs = {fs} Hz disagrees with {time_variable!r} ({rate:.9g} Hz)")
        rate = float(fs)
    if rate is None:
        found = [k for k in _FS_NAMES if k in scalars]
        if not found:
            raise ReaderError(
                f"{p}: no sample rate; pass fs=<Hz> (gearvib: --fs HZ) or "
                f"fs='<scalar variable>', or time_variable='<time vector>' (variables: "
                f"{sorted(content)})"
            )
        rate = scalars[found[0]]
        if not (np.isfinite(rate) and rate > 0):
            raise ReaderError(
                f"{p}: the sample rate {found[0]} = {rate!r} in the file is not finite and > 0"
            )
    skip = {time_variable, *_FS_NAMES}
    if variables is None:
        names = [
            k
            for k, v in content.items()
            if k not in skip
            and np.ndim(v) in (1, 2)
            and np.asarray(v).dtype.kind in "iuf"
            and np.size(v) > 0  # MATLAB's [] is not a recording
        ]
    else:
        missing = [v for v in variables if v not in content]
        if missing:
            raise ReaderError(f"{p}: variable(s) {missing} not in the file ({sorted(content)})")
        names = list(variables)
    channels: list[ChannelData] = []
    for name in names:
        arr = np.asarray(content[name])
        if arr.dtype.kind not in "iuf":
            raise ReaderError(f"{p}: variable {name!r} is not numeric (dtype {arr.dtype})")
        if arr.ndim == 2:
            cols = arr if arr.shape[0] >= arr.shape[1] else arr.T
            channels += [
                ChannelData(f"{name}_{j + 1}", cols[:, j], attrs={"source_variable": name})
                for j in range(cols.shape[1])
            ]
        else:
            channels.append(ChannelData(name, np.ravel(arr), attrs={"source_variable": name}))
    for i, ch in enumerate(channels):
        var = ch.attrs["source_variable"]
        if isinstance(units, str):
            label: str | None = units
        elif isinstance(units, Mapping):
            label = units.get(ch.name, units.get(var, file_units.get(var)))
        elif units is not None:
            if len(units) != len(channels):
                raise ValueError(f"units: {len(units)} given for {len(channels)} channel(s)")
            label = units[i]
        else:
            label = file_units.get(var)
        ud, factor = to_udunits(label)
        ch.units = ud
        if factor != 1.0:
            with np.errstate(over="ignore", invalid="ignore"):  # NaN/inf: reported by channel
                ch.values = np.asarray(ch.values, dtype=float) * factor
            ch.attrs["source_units"] = str(label)
    attrs = {"mat_scalar_" + k: v for k, v in scalars.items() if k not in _FS_NAMES}
    return build_dataset(
        channels,
        rate,
        source_format=source_format,
        source_file=str(p),
        start_time=start,
        attrs=attrs,
    )


def write_mat(ds: xr.Dataset, path: str | os.PathLike[str]) -> Path:
    """Write ``ds`` as a MATLAB v5 file: one vector per channel, ``time``, ``fs`` and a
    ``units`` struct. Reads back with ``read_mat(path)``."""
    from scipy.io import savemat

    validate_dataset(ds, name="write_mat(ds)")
    fs = float(ds.attrs.get("sample_rate_hz", 0.0)) or 1.0 / float(ds.time[1] - ds.time[0])
    content: dict[str, object] = {str(v): ds[v].values for v in ds.data_vars}
    content.update(
        time=ds["time"].values,
        fs=fs,
        units={str(v): str(ds[v].attrs["units"]) for v in ds.data_vars},
    )
    target = Path(path)
    savemat(target, content, format="5", do_compression=True)
    return target
