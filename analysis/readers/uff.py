"""Universal File Format (UFF/UNV) dataset 58/58b time histories, via pyuff (optional extra).

Dataset 58 (ASCII) and 58b (binary) are what Simcenter Testlab, B&K PULSE, HBM catman, Artemis
and modal software export. Only *time response* sets are accepted: function type 1 (record 6)
and abscissa data type 17 "time" (record 8; 0 "unknown" is accepted when the abscissa unit
label is seconds). Each set becomes one channel; all chosen sets must share the sample
interval and length. Record 8 unit labels (``"m/s2"``, ``"Pa"``, ``"g"``) are converted to
UDUNITS; ``g`` becomes ``m s-2`` (x 9.80665) with ``source_units="g"`` kept.

Field names follow pyuff's dictionaries (``func_type``, ``abscissa_inc``, ``num_pts``,
``ordinate_axis_units_lab``, ``rsp_ent_name``, ``id1`` ... ``id5``).
"""

from __future__ import annotations

import datetime as _dt
import mmap
import os
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from analysis.readers.integrity import file_size, reading, require_memory
from analysis.readers.layout import ChannelData, ReaderError, build_dataset, to_udunits

__all__ = ["read_uff"]

_TIME_RESPONSE = 1  # record 6, field 1: function type 1 = general or time response
_ABSCISSA_TIME = 17  # record 8, field 1: specific data type 17 = time
_DT_RTOL = 1e-5  # record 7 prints the increment as E13.5: ~6 significant digits
_DELIMITER = re.compile(rb"    -1(?=\r|\n|\Z| {74})")  # where pyuff splits blocks


def _import_pyuff() -> Any:
    try:
        import pyuff
    except ImportError:
        raise ImportError('reading UFF/UNV files needs pyuff: pip install "gearvib[uff]"') from None
    return pyuff


def _clean(text: object) -> str:
    s = str(text).strip()
    return "" if s.upper() == "NONE" else s


def _start_time(id3: str) -> str | None:
    """ISO string from the UFF id3 date field (``18-Apr-16 13:49:58``), if it parses."""
    for fmt in ("%d-%b-%y %H:%M:%S", "%d-%b-%Y %H:%M:%S", "%d.%m.%Y %H:%M:%S"):
        try:
            return _dt.datetime.strptime(id3.strip(), fmt).isoformat()
        except ValueError:
            continue
    return None


def _nice_rate(dt: float) -> float:
    """1/dt, snapped to the nearest integer Hz when dt is that rate rounded to 6 digits."""
    fs = 1.0 / dt
    fs_int = round(fs)
    return float(fs_int) if fs_int > 0 and abs(fs_int * dt - 1.0) < _DT_RTOL else fs


def _channel(
    p: Path, k: int, r: dict[str, Any], rates: dict[int, tuple[float, int, str]]
) -> ChannelData:
    """The channel of dataset-58 record ``r`` (set ``k``); its interval goes into ``rates``."""
    label = _clean(r.get("rsp_ent_name", "")) or _clean(r.get("id1", "")) or f"set{k}"
    where = f"{p}: set {k} ({label!r})"
    if int(r.get("func_type", -1)) != _TIME_RESPONSE:
        raise ReaderError(
            f"{where} has function type {r.get('func_type')}; only 1 (time response) "
            "can be read as a time history"
        )
    ab_type = int(r.get("abscissa_spec_data_type", 0))
    ab_unit = _clean(r.get("abscissa_axis_units_lab", "")).lower()
    if ab_type != _ABSCISSA_TIME and not (ab_type == 0 and ab_unit in ("s", "sec", "")):
        raise ReaderError(
            f"{where}: abscissa data type {ab_type} ({ab_unit or 'no unit'}); only 17 "
            "(time, seconds) is admissible"
        )
    data = np.asarray(r["data"])
    n_decl = int(r.get("num_pts", data.size))
    if data.size != n_decl:
        raise ReaderError(
            f"{where} declares {n_decl} samples but holds {data.size} (truncated file?)"
        )
    if np.iscomplexobj(data):
        raise ReaderError(f"{where} holds complex data; a time history must be real")
    if int(r.get("abscissa_spacing", 1)) == 1:
        dt = float(r["abscissa_inc"])
    else:
        x = np.asarray(r["x"], dtype=float)
        dt = float((x[-1] - x[0]) / (x.size - 1)) if x.size > 1 else float("nan")
        if x.size > 1 and np.max(np.abs(np.diff(x) - dt)) > _DT_RTOL * dt:
            raise ReaderError(f"{where} has an uneven abscissa; resample it first")
    if not np.isfinite(dt) or dt <= 0:
        raise ReaderError(f"{where}: sample interval {dt!r} s is not positive")
    rates[k] = (dt, data.size, label)
    units_lab = _clean(r.get("ordinate_axis_units_lab", ""))
    ud, factor = to_udunits(units_lab)
    attrs: dict[str, Any] = {
        "uff_set": k,
        "uff_id1": _clean(r.get("id1", "")),
        "rsp_node": int(r.get("rsp_node", 0)),
        "rsp_dir": int(r.get("rsp_dir", 0)),
        "uff_ordinate_spec_data_type": int(r.get("ordinate_spec_data_type", 0)),
    }
    if factor != 1.0 or (units_lab and ud != units_lab):
        attrs["source_units"] = units_lab
    axis = _clean(r.get("ordinate_axis_lab", ""))
    long_name = f"{label} ({axis})" if axis and axis != label else label
    with np.errstate(over="ignore", invalid="ignore"):  # NaN/inf: reported by channel
        values = data.astype(np.float64) * factor
    return ChannelData(label, values, ud, long_name, attrs)


def _check_blocks(p: Path) -> None:
    """Refuse a file whose ``-1`` block delimiters do not pair up (a set cut by truncation).

    Every UFF dataset starts and ends with a line holding ``    -1``; pyuff pairs them up and
    silently drops an unpaired last one, i.e. the set a truncation cut. The file is searched
    through :mod:`mmap`; pyuff itself holds the file and its values in memory (about eight
    times the file size for ASCII files), which is checked first.
    """
    size = file_size(p)
    require_memory(8 * size, p, "pyuff's parse of the file")
    if size == 0:
        raise ReaderError(f"{p}: the file is empty")
    with open(p, "rb") as fh, mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as buf:
        marks = [m.end() for m in _DELIMITER.finditer(buf)]
        rest = len(buf[marks[-1] :].strip()) if marks else 0
    if len(marks) % 2:
        raise ReaderError(
            f"{p}: {len(marks)} '-1' block delimiters; every UFF dataset is enclosed by two, so "
            "the last dataset is incomplete: the file is truncated or corrupt"
        )
    if rest:
        raise ReaderError(
            f"{p}: {rest} bytes after the last dataset's closing '-1': the file is "
            "corrupt (or a truncated dataset has lost its delimiters)"
        )


def read_uff(path: str | os.PathLike[str], sets: Sequence[int] | None = None) -> xr.Dataset:
    """Read the dataset-58/58b time histories of a UFF/UNV file.

    Parameters
    ----------
    path : path-like
        ``.uff`` / ``.unv`` file (ASCII 58 or binary 58b, 4- or 8-byte floats).
    sets : sequence of int, optional
        0-based indices (among the dataset-58 sets of the file, in file order) to read;
        default all. Use it to pick sets that share one sample rate.

    Returns
    -------
    xarray.Dataset
        Common layout; channels are named after the response entity name (``rsp_ent_name``)
        or ``id1``, and carry ``uff_set``, ``rsp_node``, ``rsp_dir``, ``uff_id1`` and the axis
        label. ``time_coverage_start`` comes from ``id3`` when it is a date.

    Raises
    ------
    ImportError
        pyuff is not installed (``pip install "gearvib[uff]"``).
    ReaderError
        No dataset 58 in the file (truncated, corrupt or another UFF type), unpaired ``-1``
        block delimiters or text after the last block (a truncated or corrupt file), a set
        that is not a time response, a set holding fewer samples than it declares, sets with
        different sample intervals or lengths (named, with the ``sets=`` hint), complex data,
        NaN, not enough memory for pyuff's parse (about eight times the file size).
    """
    pyuff = _import_pyuff()
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"UFF file not found: {p}")
    _check_blocks(p)
    with reading(p, "UFF"):
        uff = pyuff.UFF(str(p))
        types = list(np.atleast_1d(uff.get_set_types()).astype(int))
        idx58 = [i for i, t in enumerate(types) if t == 58]
        records = [uff.read_sets(i) for i in idx58]
    if not records:
        raise ReaderError(
            f"{p}: no dataset 58/58b time history found (set types present: {types or 'none'}); "
            "the file may be truncated, corrupt or hold other UFF datasets"
        )
    if sets is not None:
        bad = [s for s in sets if not 0 <= int(s) < len(records)]
        if bad or not len(sets):
            raise ValueError(f"sets = {list(sets)}: admissible are 0..{len(records) - 1}")
        chosen = [int(s) for s in sets]
    else:
        chosen = list(range(len(records)))
    channels: list[ChannelData] = []
    rates: dict[int, tuple[float, int, str]] = {}
    with reading(p, "UFF"):  # fields of a damaged set may not convert
        for k in chosen:
            channels.append(_channel(p, k, records[k], rates))
    dts = {dt for dt, _, _ in rates.values()}
    if max(dts) - min(dts) > _DT_RTOL * min(dts):
        desc = "; ".join(f"set {k} {lab!r}: dt = {dt:g} s" for k, (dt, _, lab) in rates.items())
        raise ReaderError(
            f"{p}: sets have different sample intervals ({desc}); read them separately with "
            "read_uff(path, sets=[...])"
        )
    first = records[chosen[0]]
    attrs = {"title": _clean(first.get("id2", "")), "uff_id3": _clean(first.get("id3", ""))}
    start = _start_time(_clean(first.get("id3", "")))
    if start:
        attrs["time_coverage_start"] = start
    attrs = {k: v for k, v in attrs.items() if v}
    fs = _nice_rate(rates[chosen[0]][0])
    return build_dataset(
        channels,
        fs,
        source_format="uff58b" if int(first.get("binary", 0)) else "uff58",
        source_file=str(p),
        start_time=float(first.get("abscissa_min", 0.0)),
        attrs=attrs,
    )
