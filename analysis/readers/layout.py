"""The common Dataset layout shared by every reader and by simulated run-ups.

Every reader in :mod:`analysis.readers` returns an :class:`xarray.Dataset` built by
:func:`build_dataset`, so that measured and simulated data look the same downstream:

* coordinate ``time`` -- float64 seconds, uniform sampling, no NaN; a CF time coordinate
  (``units="seconds since <time_coverage_start or 1970-01-01T00:00:00Z>"``,
  ``standard_name="time"``, ``axis="T"``, see :mod:`analysis.cf`);
* one data variable per channel with dims ``("time",)`` carrying ``units`` (a UDUNITS string such
  as ``"m s-2"``, ``"Pa"``, ``"N"``, ``"V"``, ``"min-1"``, ``"rad"``, ``"1"``), ``long_name`` and
  channel metadata (``source_channel``, ``sensitivity``, ...);
* global attributes ``Conventions="CF-1.11"``, ``history`` (which toolkit version read it),
  ``gearvib_version``, ``source_format``, ``source_file``, ``sample_rate_hz`` and whatever the
  file states (``title``, ``source``, ``time_coverage_start``, ...).

Attribute values are restricted to what netCDF can store (str, int, float, 1-D numeric arrays);
bool becomes int8, dict becomes a JSON string and None is dropped.
"""

from __future__ import annotations

import datetime as _dt
import json
import keyword
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr

from analysis.cf import is_elapsed_seconds, time_attrs, toolkit_version
from analysis.checks import require_instance, require_positive

__all__ = [
    "CONVENTIONS",
    "ChannelData",
    "ReaderError",
    "build_dataset",
    "clean_attrs",
    "sanitize_names",
    "to_udunits",
    "validate_dataset",
]

CONVENTIONS = "CF-1.11"
STANDARD_GRAVITY = 9.80665  # m s-2 per g (CGPM 1901)


class ReaderError(ValueError):
    """A measured file cannot be turned into the common layout (corrupt, truncated, unsupported)."""


@dataclass
class ChannelData:
    """One measured channel before it is put into the Dataset.

    Parameters
    ----------
    name : str
        Channel name as the file gives it (sanitised into a variable name later).
    values : array_like
        Samples, 1-D.
    units : str
        UDUNITS unit string (use :func:`to_udunits` to convert file labels).
    long_name : str, optional
        Descriptive name; defaults to ``name``.
    attrs : dict
        Further channel metadata (``sensitivity``, ``source_units``, ...).
    """

    name: str
    values: Any
    units: str = "1"
    long_name: str | None = None
    attrs: dict[str, Any] = field(default_factory=dict)


# ----------------------------------------------------------------------------------------------
# units
# ----------------------------------------------------------------------------------------------

_UNIT_ALIASES: dict[str, tuple[str, float]] = {
    "": ("1", 1.0),
    "none": ("1", 1.0),
    "-": ("1", 1.0),
    "1": ("1", 1.0),
    "g": ("m s-2", STANDARD_GRAVITY),
    "g_n": ("m s-2", STANDARD_GRAVITY),
    "gn": ("m s-2", STANDARD_GRAVITY),
    "rpm": ("min-1", 1.0),
    "r/min": ("min-1", 1.0),
    "u/min": ("min-1", 1.0),
    "1/min": ("min-1", 1.0),
    "deg": ("degree", 1.0),
    "°": ("degree", 1.0),
    "µm": ("um", 1.0),
    "μm": ("um", 1.0),
    "µε": ("1", 1e-6),
    "με": ("1", 1e-6),
    "microstrain": ("1", 1e-6),
    "%": ("1", 0.01),
}
_SUPERSCRIPTS = str.maketrans({"²": "2", "³": "3", "¹": "1", "⁻": "-", "·": " ", "*": " "})
_TOKEN = re.compile(r"^([A-Za-zµμΩ°]+)\^?(-?\d+)?$")


def _tokens(part: str, sign: int) -> list[str] | None:
    out = []
    for tok in part.split():
        m = _TOKEN.match(tok)
        if m is None:
            return None
        exp = int(m.group(2) or 1) * sign
        sym = m.group(1).replace("μ", "u").replace("µ", "u")
        out.append(sym if exp == 1 else f"{sym}{exp}")
    return out


def to_udunits(label: str | None) -> tuple[str, float]:
    """Convert a unit label found in a file into a UDUNITS string and a scale factor.

    Parameters
    ----------
    label : str or None
        Unit label as written by the acquisition software (``"m/s2"``, ``"m/s²"``, ``"g"``,
        ``"rpm"``, ``"Pa"``, ...).

    Returns
    -------
    units : str
        UDUNITS-parsable string (``"m s-2"``, ``"min-1"``, ``"Pa"``, ``"1"`` for none).
    factor : float
        Multiply the samples by ``factor`` to express them in ``units``; 1.0 except for labels
        that are converted to SI (``g`` -> ``m s-2`` with 9.80665, ``%`` -> ``1``, microstrain).

    Notes
    -----
    Labels that are not recognised are returned unchanged with factor 1.0, so nothing is lost.
    """
    text = "" if label is None else str(label).strip()
    key = text.lower() if text.lower() in ("none", "g", "rpm", "deg", "microstrain") else text
    if key in _UNIT_ALIASES:
        return _UNIT_ALIASES[key]
    norm = text.translate(_SUPERSCRIPTS).replace("**", "^").strip()
    if "/" in norm:
        num, _, den = norm.partition("/")
        if "/" in den:
            return text, 1.0
        den = den.strip("() ")
        up = _tokens(num, 1) if num.strip() not in ("", "1") else []
        down = _tokens(den, -1)
        if up is None or down is None:
            return text, 1.0
        return " ".join(up + down), 1.0
    toks = _tokens(norm, 1)
    if toks is None:
        return text, 1.0
    return " ".join(toks), 1.0


# ----------------------------------------------------------------------------------------------
# names and attributes
# ----------------------------------------------------------------------------------------------


def sanitize_names(names: Iterable[str], reserved: Iterable[str] = ("time",)) -> list[str]:
    """Turn channel names into unique, valid Python identifiers usable as variable names.

    Non-alphanumeric characters become ``_``; names starting with a digit get a ``ch_`` prefix;
    keywords and ``reserved`` names get a ``_ch`` suffix; duplicates get ``_2``, ``_3``, ...
    """
    taken = set(reserved)
    out: list[str] = []
    for raw in names:
        s = re.sub(r"\W+", "_", str(raw).strip(), flags=re.ASCII).strip("_")
        if not s:
            s = "channel"
        if s[0].isdigit():
            s = f"ch_{s}"
        if keyword.iskeyword(s) or s in reserved:
            s = f"{s}_ch"
        base, k = s, 2
        while s in taken:
            s = f"{base}_{k}"
            k += 1
        taken.add(s)
        out.append(s)
    return out


def _clean_value(value: Any) -> Any:
    if value is None:
        return None
    if isinstance(value, bool | np.bool_):
        return np.int8(value)
    if isinstance(value, dict):
        return json.dumps(value, default=str, sort_keys=True)
    if isinstance(value, _dt.datetime | _dt.date):
        return value.isoformat()
    if isinstance(value, np.datetime64):
        text = str(np.datetime_as_string(value.astype("datetime64[us]")))
        return text.removesuffix(".000000")
    if isinstance(value, str | int | float | np.integer | np.floating):
        return value
    if isinstance(value, bytes):
        return value.decode("utf-8", errors="replace")
    arr = np.asarray(value)
    if arr.ndim == 1 and arr.dtype.kind in "iuf" and arr.size > 0:
        return arr
    if arr.ndim == 0 and arr.dtype.kind in "iuf":
        return arr.item()
    return str(value)


def clean_attrs(attrs: Mapping[str, Any]) -> dict[str, Any]:
    """Return attributes netCDF can store: bool -> int8, dict -> JSON, None dropped, datetimes ->
    ISO strings, other objects -> ``str``."""
    require_instance(attrs, Mapping, "attrs")
    out = {}
    for k, v in attrs.items():
        cv = _clean_value(v)
        if cv is not None:
            out[str(k)] = cv
    return out


# ----------------------------------------------------------------------------------------------
# building and validating
# ----------------------------------------------------------------------------------------------


def _channel_array(ch: ChannelData, source: str) -> np.ndarray:
    arr = np.asarray(ch.values)
    where = f" in {source}" if source else ""
    if arr.dtype.kind not in "iuf":
        raise ReaderError(
            f"channel {ch.name!r}{where}: samples have dtype {arr.dtype}; only numeric "
            "(integer or float) samples are admissible"
        )
    arr = np.squeeze(arr) if arr.ndim > 1 and max(arr.shape) == arr.size else arr
    if arr.ndim != 1:
        raise ReaderError(
            f"channel {ch.name!r}{where}: samples have shape {arr.shape}; a channel must be 1-D"
        )
    if arr.size == 0:
        raise ReaderError(f"channel {ch.name!r}{where} is empty (needs at least one sample)")
    if arr.dtype.kind == "f":
        bad = ~np.isfinite(arr)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise ReaderError(
                f"channel {ch.name!r}{where}: {int(bad.sum())} NaN/inf sample(s), first at "
                f"sample index {i} (t = index / sample rate); only finite samples are admissible"
            )
    else:
        arr = arr.astype(np.float64)
    return arr


def build_dataset(
    channels: Sequence[ChannelData],
    sample_rate_hz: float,
    *,
    source_format: str,
    source_file: str = "",
    start_time: float = 0.0,
    attrs: Mapping[str, Any] | None = None,
    time_long_name: str = "time since start of recording",
) -> xr.Dataset:
    """Build and validate a Dataset in the common layout.

    Parameters
    ----------
    channels : sequence of ChannelData
        The channels, all with the same number of samples.
    sample_rate_hz : float
        Sample rate [Hz] shared by all channels.
    source_format : str
        Format tag (``"wav"``, ``"csv"``, ``"uff58"``, ...).
    source_file : str, optional
        Path of the file the data came from (used in messages and stored as attribute).
    start_time : float, optional
        Time [s] of the first sample (0 for most formats).
    attrs : mapping, optional
        Further global attributes (``title``, ``time_coverage_start``, ...).
    time_long_name : str, optional
        ``long_name`` of the time coordinate.

    Returns
    -------
    xarray.Dataset
        The Dataset; data variables keep float32 samples as float32, other numbers become float64.

    Raises
    ------
    ReaderError
        No channels, an empty channel, a non-finite sample (naming channel and sample index),
        channels of unequal length, a sample rate that is not finite and > 0 or a time axis
        that overflows.
    """
    where = f" in {source_file}" if source_file else ""
    try:
        fs = require_positive(sample_rate_hz, "sample_rate_hz")
    except (TypeError, ValueError) as exc:
        raise ReaderError(f"{exc}{where}") from None
    if not channels:
        raise ReaderError(f"no channels found{where}; a recording needs at least one channel")
    arrays = [_channel_array(ch, source_file) for ch in channels]
    lengths = {ch.name: a.size for ch, a in zip(channels, arrays, strict=True)}
    if len(set(lengths.values())) > 1:
        desc = ", ".join(f"{k!r}: {n}" for k, n in lengths.items())
        raise ReaderError(
            f"channels of unequal length{where} ({desc}); all channels must have the same "
            "number of samples at the same sample rate"
        )
    n = arrays[0].size
    with np.errstate(over="ignore", invalid="ignore"):
        time = float(start_time) + np.arange(n, dtype=np.float64) / fs
    if not np.isfinite(time[-1]):
        raise ReaderError(
            f"sample rate {fs!r} Hz and start time {start_time!r} s{where} give a time axis "
            "that is not finite"
        )
    names = sanitize_names(ch.name for ch in channels)
    data_vars = {}
    for var, ch, arr in zip(names, channels, arrays, strict=True):
        a = dict(ch.attrs)
        a["units"] = ch.units if ch.units else "1"
        a["long_name"] = ch.long_name or str(ch.name)
        a.setdefault("source_channel", str(ch.name))
        data_vars[var] = xr.Variable(("time",), arr, clean_attrs(a))
    gattrs: dict[str, Any] = {"Conventions": CONVENTIONS}
    gattrs.update(attrs or {})
    gattrs.update(
        {"source_format": source_format, "source_file": str(source_file), "sample_rate_hz": fs}
    )
    if not str(gattrs.get("title", "")).strip():  # CF 2.6.2: a non-empty title
        gattrs["title"] = "measured recording"  # source_format and source_file say which
    gattrs.setdefault(  # the file it came from: source_format, source_file
        "history", f"read by analysis.readers (gearvib {toolkit_version()}) into the common layout"
    )
    gattrs.setdefault("gearvib_version", toolkit_version())
    start = gattrs.get("time_coverage_start")
    coords = {"time": ("time", time, time_attrs(time_long_name, str(start) if start else None))}
    ds = xr.Dataset(data_vars, coords=coords, attrs=clean_attrs(gattrs))
    validate_dataset(ds)
    return ds


def validate_dataset(ds: xr.Dataset, *, name: str = "dataset") -> xr.Dataset:
    """Check that ``ds`` follows the common layout; return it unchanged.

    Checks: a uniformly sampled, finite float ``time`` coordinate with ``units="s"``; every data
    variable along ``time`` with ``units`` and ``long_name``; no bool/dict/None attributes.

    Raises
    ------
    ReaderError
        Naming the offending variable or attribute and what is admissible.
    """
    require_instance(ds, xr.Dataset, name)
    from analysis.checks import sample_rate

    if "time" not in ds.coords:
        raise ReaderError(f"{name}: no 'time' coordinate; the layout needs time in seconds")
    t = ds["time"]
    if t.dtype.kind != "f":
        raise ReaderError(
            f"{name}: 'time' has dtype {t.dtype}; it must be float seconds (units='s')"
        )
    if not is_elapsed_seconds(t.attrs.get("units")):
        raise ReaderError(
            f"{name}: 'time' units are {t.attrs.get('units')!r}; must be seconds ('s' or "
            "'seconds since <reference>')"
        )
    if t.size >= 2:
        try:
            sample_rate(t.values, name=f"{name}: time", rtol=1e-6)
        except ValueError as exc:
            raise ReaderError(str(exc)) from None
    elif not np.all(np.isfinite(t.values)):
        raise ReaderError(f"{name}: 'time' holds NaN/inf")
    for var in ds.data_vars:
        da = ds[var]
        if "time" not in da.dims:
            raise ReaderError(f"{name}: variable {var!r} has dims {da.dims}; needs 'time'")
        for key in ("units", "long_name"):
            if key not in da.attrs:
                raise ReaderError(f"{name}: variable {var!r} has no {key!r} attribute")
    for owner, attrs in [("global", ds.attrs)] + [(str(v), ds[v].attrs) for v in ds.variables]:
        for k, v in attrs.items():
            if v is None or isinstance(v, bool | np.bool_ | dict):
                raise ReaderError(
                    f"{name}: {owner} attribute {k!r} is {type(v).__name__}; netCDF stores only "
                    "str, numbers and numeric arrays (use int8 for bool, JSON for dict)"
                )
    return ds
