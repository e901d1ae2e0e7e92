"""NI TDMS (LabVIEW / DAQmx) reader via npTDMS (optional extra ``gearvib[tdms]``).

One TDMS group becomes one Dataset; each channel of the group with waveform properties
``wf_increment`` (sample interval [s]) becomes a data variable, with its ``unit_string``
converted to UDUNITS and ``wf_start_time`` stored as ``time_coverage_start``.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from analysis.readers.layout import ChannelData, ReaderError, build_dataset, to_udunits

__all__ = ["read_tdms"]

_DT_RTOL = 1e-9


def _import_nptdms() -> Any:
    try:
        import nptdms
    except ImportError:
        raise ImportError('reading TDMS files needs npTDMS: pip install "gearvib[tdms]"') from None
    return nptdms


def read_tdms(
    path: str | os.PathLike[str], group: str | None = None, *, fs: float | None = None
) -> xr.Dataset:
    """Read one group of a TDMS file into the common layout.

    Parameters
    ----------
    path : path-like
        ``.tdms`` file.
    group : str, optional
        Group to read; may be omitted when the file has exactly one group with data.
    fs : float, optional
        Sample rate [Hz] for channels without ``wf_increment`` (otherwise that property is
        used, and ``fs`` must agree with it).

    Returns
    -------
    xarray.Dataset
        Common layout; channels carry ``source_channel``, ``tdms_group`` and, when present,
        ``source_units`` and ``NI_ChanName``-style properties as attributes.

    Raises
    ------
    ImportError
        npTDMS is not installed (``pip install "gearvib[tdms]"``).
    ReaderError
        Corrupt/truncated file, unknown or ambiguous group (the groups are listed), channels
        with different ``wf_increment`` (named) or lengths, no sample rate, NaN samples.
    """
    nptdms = _import_nptdms()
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"TDMS file not found: {p}")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            tdms = nptdms.TdmsFile.read(str(p))
    except Exception as exc:  # npTDMS raises ValueError/struct.error/EOFError on damage
        raise ReaderError(f"{p}: not a readable TDMS file (truncated or corrupt?): {exc}") from None
    groups = {g.name: g for g in tdms.groups() if len(g.channels())}
    if not groups:
        raise ReaderError(f"{p}: no channel data found (empty, truncated or corrupt file)")
    if group is None:
        if len(groups) > 1:
            raise ReaderError(f"{p} has several groups {sorted(groups)}; choose one with group=")
        group = next(iter(groups))
    if group not in groups:
        raise ReaderError(f"{p}: group {group!r} not found; groups with data: {sorted(groups)}")
    chans = groups[group].channels()
    incs: dict[str, float] = {}
    channels = []
    start_time = None
    for ch in chans:
        props = dict(ch.properties)
        if "wf_increment" in props:
            incs[ch.name] = float(props["wf_increment"])
        elif fs is None:
            raise ReaderError(
                f"{p}: channel {ch.name!r} in group {group!r} has no wf_increment; pass fs=<Hz>"
            )
        if start_time is None and "wf_start_time" in props:
            start_time = props["wf_start_time"]
        label = props.get("unit_string", props.get("NI_UnitDescription"))
        ud, factor = to_udunits(label)
        attrs: dict[str, Any] = {"tdms_group": group}
        if label is not None and (ud != label or factor != 1.0):
            attrs["source_units"] = str(label)
        for key in ("description", "NI_ChannelName", "sensitivity"):
            if key in props:
                attrs[key] = props[key]
        data = np.asarray(ch[:])
        if data.dtype.kind == "f" and factor != 1.0:
            data = data * factor
        channels.append(ChannelData(ch.name, data, ud, props.get("description") or None, attrs))
    if incs:
        values = list(incs.values())
        if max(values) - min(values) > _DT_RTOL * min(values):
            desc = ", ".join(f"{k!r}: {v:g} s" for k, v in incs.items())
            raise ReaderError(
                f"{p}, group {group!r}: channels have different wf_increment ({desc}); "
                "sample-rate mismatch, read the channels separately"
            )
        rate = 1.0 / values[0]
        if fs is not None and abs(rate - fs) > 1e-6 * fs:
            raise ValueError(f"fs = {fs} Hz disagrees with wf_increment ({rate:.9g} Hz)")
    else:
        assert fs is not None
        rate = float(fs)
    attrs = {k: v for k, v in tdms.properties.items() if k in ("name", "title", "author")}
    if start_time is not None:
        attrs["time_coverage_start"] = start_time
    return build_dataset(channels, rate, source_format="tdms", source_file=str(p), attrs=attrs)
