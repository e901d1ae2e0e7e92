"""NI TDMS (LabVIEW / DAQmx) reader via npTDMS (optional extra ``gearvib[tdms]``).

One TDMS group becomes one Dataset; each channel of the group with waveform properties
``wf_increment`` (sample interval [s]) becomes a data variable, with its ``unit_string``
converted to UDUNITS and ``wf_start_time`` stored as ``time_coverage_start``.
"""

from __future__ import annotations

import os
import struct
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from analysis.readers.integrity import describe, file_size, reading, require_memory
from analysis.readers.layout import ChannelData, ReaderError, build_dataset, to_udunits

__all__ = ["read_tdms"]

_DT_RTOL = 1e-9
_LEAD_IN = 28  # "TDSm", ToC mask, version, next-segment offset, raw-data offset
_TOC_BIG_ENDIAN = 1 << 6
_INCOMPLETE = 0xFFFFFFFFFFFFFFFF


def _check_segments(p: Path) -> int:
    """Walk the segment lead-ins; refuse a segment that ends beyond the file or was never
    completed. Returns the file size.

    npTDMS reads a truncated last segment "to the end of the file" and only logs it, i.e. it
    returns fewer samples than the file declares; here that is a :class:`ReaderError`.
    """
    size = file_size(p)
    pos, k = 0, 0
    with open(p, "rb") as fh:
        while pos < size:
            fh.seek(pos)
            lead = fh.read(_LEAD_IN)
            where = f"{p}: not a readable TDMS file: segment {k} at byte {pos}"
            if len(lead) < _LEAD_IN:
                raise ReaderError(f"{where}: lead-in has {len(lead)} of 28 bytes (truncated)")
            if lead[:4] != b"TDSm":
                raise ReaderError(f"{where} does not start with 'TDSm' (corrupt or not TDMS)")
            toc = struct.unpack_from("<I", lead, 4)[0]
            endian = ">" if toc & _TOC_BIG_ENDIAN else "<"
            _version, nxt, raw = struct.unpack_from(endian + "IQQ", lead, 8)
            if nxt == _INCOMPLETE:
                raise ReaderError(
                    f"{where} was never completed (the writer stopped, e.g. LabVIEW crashed): "
                    "the file is truncated"
                )
            if raw > nxt or pos + _LEAD_IN + nxt > size:
                raise ReaderError(
                    f"{where} declares {nxt} bytes (metadata {raw}) but the file ends "
                    f"{size - pos - _LEAD_IN} bytes later: the file is truncated or corrupt"
                )
            pos += _LEAD_IN + nxt
            k += 1
    if k == 0:
        raise ReaderError(f"{p}: the file is empty")
    return size


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
        Corrupt or truncated file (a segment beyond the end of the file or never completed,
        metadata declaring more samples than the file holds, anything npTDMS reports),
        unknown or ambiguous group (the groups are listed), channels with different
        ``wf_increment`` (named) or lengths, no sample rate, NaN samples, not enough memory.
    """
    nptdms = _import_nptdms()
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"TDMS file not found: {p}")
    size = _check_segments(p)
    with (
        reading(p, "TDMS", logger="nptdms") as notes,
        nptdms.TdmsFile.open(str(p)) as tdms,
    ):
        groups = {g.name: g for g in tdms.groups() if len(g.channels())}
        if not groups:
            raise ReaderError(f"{p}: no channel data found (empty, truncated or corrupt file)")
        if group is None:
            if len(groups) > 1:
                raise ReaderError(
                    f"{p} has several groups {sorted(groups)}; choose one with group="
                )
            group = next(iter(groups))
        if group not in groups:
            raise ReaderError(f"{p}: group {group!r} not found; groups with data: {sorted(groups)}")
        chans = groups[group].channels()
        counts = {ch.name: len(ch) for ch in chans}
        declared = sum(len(ch) * (getattr(ch.data_type, "size", None) or 1) for ch in chans)
        if declared > size:
            raise ReaderError(
                f"{p}: group {group!r} declares {declared} bytes of samples ({counts}) but the "
                f"file has {size} bytes: its metadata are corrupt"
            )
        require_memory(16 * sum(counts.values()), p, f"group {group!r} ({counts} samples)")
        file_props = dict(tdms.properties)
        raw = [(ch.name, dict(ch.properties), np.asarray(ch[:])) for ch in chans]
    if notes.log:
        raise ReaderError(
            f"{p}: not a readable TDMS file: npTDMS reports {describe(Exception(notes.log[0]))} "
            "(truncated or corrupt file)"
        )
    incs: dict[str, float] = {}
    channels = []
    start_time = None
    for name, props, data in raw:
        if data.size != counts[name]:
            raise ReaderError(
                f"{p}: channel {name!r} declares {counts[name]} samples but {data.size} were "
                "read (truncated file)"
            )
        if "wf_increment" in props:
            try:
                incs[name] = float(props["wf_increment"])
            except (TypeError, ValueError):
                raise ReaderError(f"{p}: channel {name!r}: wf_increment is not a number") from None
        elif fs is None:
            raise ReaderError(
                f"{p}: channel {name!r} in group {group!r} has no wf_increment; pass fs=<Hz>"
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
        if data.dtype.kind == "f" and factor != 1.0:
            with np.errstate(over="ignore", invalid="ignore"):  # NaN/inf: reported by channel
                data = data * factor
        channels.append(ChannelData(name, data, ud, props.get("description") or None, attrs))
    if incs:
        values = list(incs.values())
        if max(values) - min(values) > _DT_RTOL * min(values):
            desc = ", ".join(f"{k!r}: {v:g} s" for k, v in incs.items())
            raise ReaderError(
                f"{p}, group {group!r}: channels have different wf_increment ({desc}); "
                "sample-rate mismatch, read the channels separately"
            )
        if not all(np.isfinite(v) and v > 0 for v in values):
            raise ReaderError(f"{p}, group {group!r}: wf_increment {incs} must be finite and > 0")
        rate = 1.0 / values[0]
        if fs is not None and abs(rate - fs) > 1e-6 * fs:
            raise ValueError(f"fs = {fs} Hz disagrees with wf_increment ({rate:.9g} Hz)")
    else:
        assert fs is not None
        rate = float(fs)
    attrs = {k: v for k, v in file_props.items() if k in ("name", "title", "author")}
    if start_time is not None:
        attrs["time_coverage_start"] = start_time
    return build_dataset(channels, rate, source_format="tdms", source_file=str(p), attrs=attrs)
