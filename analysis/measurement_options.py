"""What a real export lacks, stated by the user: rate, time column, calibration, units, speed.

A file exported from a data logger or downloaded from a data set often carries no sample rate,
no unit and no tacho: the CWRU bearing records, for instance, hold the accelerations in g
without saying so, no rate (12 kHz) and the shaft speed as a scalar variable ``X105RPM``.
:func:`analysis.measurement.load_measurement` takes these facts as options, and this module
turns them into reader options and applies them to the channels:

* ``fs`` [Hz]: passed to the readers that take a rate (CSV, MAT, TDMS); for the formats that
  state their own rate (WAV, UFF, netCDF, an in-memory Dataset) it must agree with it;
* ``time_column``: the time column of a CSV file, the time vector of a MAT file;
* ``calibration``: a factor per channel (or one for all), in the given unit per file unit;
* ``units``: the unit of a channel's values after calibration; converted to SI like the
  readers do (``g`` -> ``m s-2`` with 9.80665, :func:`analysis.readers.to_udunits`);
* ``rpm_from``: the name of a scalar variable of the file holding a constant speed [min-1]
  (MAT scalars, netCDF scalar variables, numeric global attributes).

Every check raises a :class:`ValueError` (a :class:`TypeError` for a value of the wrong type)
that names the option and what is admissible.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import xarray as xr

from analysis.checks import require_instance, require_real, uniform_rate
from analysis.readers import FORMATS, to_udunits

__all__ = [
    "MAX_FS",
    "RATE_OPTION",
    "TIME_OPTION",
    "apply_calibration",
    "check_fs",
    "check_rate",
    "reader_options",
    "scalar_speed",
    "scalar_variables",
]

MAX_FS = 1e9
"""Largest sample rate accepted [Hz]."""

RATE_OPTION = {"csv": "fs", "mat": "fs", "tdms": "fs"}
"""Formats whose reader takes a sample rate, and the reader's keyword."""

TIME_OPTION = {"csv": "time_column", "mat": "time_variable"}
"""Formats whose reader takes a time column (vector), and the reader's keyword."""

_MAT_SCALAR = "mat_scalar_"
_LAYOUT_ATTRS = {"sample_rate_hz", "fs_out"}
"""Global attributes of the common layout (and of a run) that are no variables of the file."""


def check_fs(fs: Any) -> float | None:
    """``fs`` as a float in (0, :data:`MAX_FS`] Hz (``None`` stays ``None``)."""
    if fs is None:
        return None
    v = require_real(fs, "fs")
    if not 0.0 < v <= MAX_FS:
        raise ValueError(f"fs = {fs!r} is not admissible: a sample rate in (0, {MAX_FS:g}] Hz")
    return v


def _format_of(suffix: str) -> str | None:
    return next((name for name, (_, exts) in FORMATS.items() if suffix.lower() in exts), None)


def reader_options(suffix: str, options: dict | None, fs: float | None,
                   time_column: Any) -> tuple[dict, bool]:
    """The reader's options for a file with extension ``suffix``.

    Parameters
    ----------
    suffix : str
        File extension (``".mat"``, ``".csv"``, ...).
    options : dict or None
        ``reader_options`` given by the caller.
    fs : float or None
        Sample rate [Hz] stated by the user (checked with :func:`check_fs`).
    time_column : str, int or None
        Time column (CSV) or time vector (MAT).

    Returns
    -------
    (dict, bool)
        The options, and whether ``fs`` must still be compared with the rate the file states
        (formats whose reader takes no rate).

    Raises
    ------
    ValueError
        ``fs`` or ``time_column`` also in ``options``; ``time_column`` for a format without
        one.
    """
    require_instance(suffix, str, "suffix")
    if options is not None:
        require_instance(options, Mapping, "options")
    fs = check_fs(fs)
    opts = dict(options or {})
    fmt = _format_of(suffix)
    compare = False
    if fs is not None:
        key = RATE_OPTION.get(fmt or "")
        if key is None:
            compare = True
        elif key in opts:
            raise ValueError(f"fs is given twice (fs = {fs:g} and reader_options[{key!r}]); "
                             "give it once")
        else:
            opts[key] = fs
    if time_column is not None:
        key = TIME_OPTION.get(fmt or "")
        if key is None:
            raise ValueError(f"time_column = {time_column!r} applies to CSV files (a column) "
                             f"and MAT files (a time vector), not to {suffix or 'this'} files")
        if isinstance(time_column, bool) or not isinstance(time_column, str | int):
            raise TypeError(f"time_column = {time_column!r} is not admissible: a column name "
                            "or a 0-based column index")
        if key in opts:
            raise ValueError(f"time_column is given twice (time_column = {time_column!r} and "
                             f"reader_options[{key!r}]); give it once")
        if fmt == "mat" and not isinstance(time_column, str):
            raise TypeError(f"time_column = {time_column!r} is not admissible for a MAT file: "
                            "the name of its time vector")
        opts[key] = time_column
    return opts, compare


def check_rate(ds: xr.Dataset, fs: float, where: str) -> None:
    """Raise unless the rate of ``ds``'s time axis equals ``fs`` (1e-6 relative).

    Used for the formats that state their own rate (WAV, UFF, netCDF, a Dataset): a different
    ``fs`` is refused, not applied silently.
    """
    require_instance(ds, xr.Dataset, "ds")
    fs = require_real(fs, "fs")
    if "time" not in ds.coords:
        return
    rate = uniform_rate(ds["time"].values, f"{where}: time")
    if abs(rate - fs) > 1e-6 * fs:
        raise ValueError(f"fs = {fs:g} Hz disagrees with the rate {where} states "
                         f"({rate:.9g} Hz); leave fs out for a file that states its rate")


def scalar_variables(ds: xr.Dataset) -> dict[str, float]:
    """The numeric scalars a file holds besides its channels.

    MAT scalars (the MAT reader keeps them as ``mat_scalar_NAME`` attributes), scalar
    (0-d) numeric variables and coordinates of a netCDF file, numeric global attributes.

    Returns
    -------
    dict
        Name -> value.
    """
    require_instance(ds, xr.Dataset, "ds")
    out: dict[str, float] = {}
    for k, v in ds.attrs.items():
        if isinstance(v, bool | np.bool_) or k in _LAYOUT_ATTRS:
            continue
        if isinstance(v, int | float | np.integer | np.floating) or (
                isinstance(v, np.ndarray) and v.size == 1 and v.dtype.kind in "iuf"):
            name = str(k)[len(_MAT_SCALAR):] if str(k).startswith(_MAT_SCALAR) else str(k)
            out.setdefault(name, float(np.ravel(v)[0]))
    for k, v in ds.variables.items():
        if v.ndim == 0 and v.dtype.kind in "iuf":
            out[str(k)] = float(v.values)
    return out


def scalar_speed(ds: xr.Dataset, name: Any, max_rpm: float) -> float:
    """The constant speed [min-1] held by the file's scalar variable ``name``.

    Raises
    ------
    ValueError
        No such scalar (the file's scalars are listed), or a value that is not a speed in
        ``(0, max_rpm]`` min-1.
    TypeError
        ``name`` is not a string.
    """
    require_instance(ds, xr.Dataset, "ds")
    require_real(max_rpm, "max_rpm")
    if not isinstance(name, str) or not name:
        raise TypeError(f"rpm_from = {name!r} is not admissible: the name of a scalar variable "
                        "of the file")
    scalars = scalar_variables(ds)
    if name not in scalars:
        raise ValueError(f"rpm_from = {name!r} is not a numeric scalar of the file; scalars: "
                         f"{sorted(scalars) or 'none'}")
    v = scalars[name]
    if not (np.isfinite(v) and 0.0 < v <= max_rpm):
        raise ValueError(f"rpm_from = {name!r} holds {v!r}: not a speed in (0, {max_rpm:g}] "
                         "min-1")
    return float(v)


def _per_channel(value: Any, channels: list[str], option: str) -> dict[str, Any]:
    """``{channel: value}`` from one value for all channels or a mapping (names checked)."""
    if value is None:
        return {}
    if isinstance(value, Mapping):
        unknown = [str(k) for k in value if k not in channels]
        if unknown:
            raise ValueError(f"{option}: {unknown[0]!r} is not a channel of the measurement; "
                             f"channels: {channels}")
        return {str(k): v for k, v in value.items()}
    return {c: value for c in channels}


def _factor(value: Any, channel: str) -> float:
    v = require_real(value, f"calibration[{channel!r}]")
    if v == 0.0 or abs(v) > 1e30 or abs(v) < 1e-30:
        raise ValueError(f"calibration[{channel!r}] = {value!r} is not admissible: a finite "
                         "factor with 1e-30 <= |factor| <= 1e30 (units per file unit)")
    return v


def _unit(value: Any, channel: str) -> str:
    if not isinstance(value, str) or not value.strip() or len(value) > 64:
        raise TypeError(f"units[{channel!r}] = {value!r} is not admissible: a unit string of "
                        "1-64 characters (e.g. 'g', 'm/s2', 'V')")
    return value.strip()


def apply_calibration(signals: xr.Dataset, calibration: Any = None,
                      units: Any = None) -> xr.Dataset:
    """Channels scaled by their calibration and labelled with their units.

    Parameters
    ----------
    signals : xarray.Dataset
        Channels along ``time``.
    calibration : float or mapping, optional
        Factor in ``units`` per file unit: one for every channel, or channel -> factor
        (finite, ``1e-30 <= |factor| <= 1e30``).
    units : str or mapping, optional
        Unit of the calibrated values: one for every channel, or channel -> unit. Converted
        to UDUNITS and SI as the readers do (:func:`analysis.readers.to_udunits`: ``g``
        becomes ``m s-2``, the values multiplied by 9.80665).

    Returns
    -------
    xarray.Dataset
        A copy with the channels scaled; a calibrated channel has the attributes
        ``calibration`` and ``calibration_basis``; a channel with a given unit has
        ``units``, ``source_units`` (the unit as given) and ``units_origin = "given"``.

    Notes
    -----
    ``x_out = x_file * calibration * k(unit)``, ``k`` the SI factor of the unit.
    """
    require_instance(signals, xr.Dataset, "signals")
    names = [str(k) for k in signals.data_vars]
    cal = {c: _factor(v, c) for c, v in _per_channel(calibration, names, "calibration").items()}
    uni = {c: _unit(v, c) for c, v in _per_channel(units, names, "units").items()}
    if not cal and not uni:
        return signals
    out = signals.copy()
    for c in names:
        if c not in cal and c not in uni:
            continue
        da = out[c]
        attrs = dict(da.attrs)
        factor = cal.get(c, 1.0)
        if c in uni:
            ud, k = to_udunits(uni[c])
            factor *= k
            attrs.update(units=ud, source_units=uni[c], units_origin="given")
        if c in cal:
            basis = uni.get(c) or str(attrs.get("units", "1"))
            attrs.update(calibration=cal[c], calibration_basis=f"{basis} per file unit")
        values = np.asarray(da.values, dtype=float)
        if factor != 1.0:
            with np.errstate(over="ignore"):
                values = values * factor
            if not np.all(np.isfinite(values)):
                raise ValueError(f"calibration[{c!r}] = {cal.get(c, 1.0)!r} makes channel {c!r} "
                                 "overflow; check the factor")
        out[c] = (da.dims, values, attrs)
    return out
