"""Delimited text (CSV/TXT) reader and writer.

The first non-comment line may be a header of column names; a unit in brackets after the name
(``"acc_x [m/s2]"`` or ``"acc_x (m/s^2)"``) is taken as the channel unit. Lines starting with
``#`` are comments. The delimiter is detected (``,``, ``;``, tab, whitespace) unless given;
with ``;`` as delimiter a decimal comma (``1,25``) is accepted.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import xarray as xr

from analysis.checks import sample_rate
from analysis.readers.layout import (
    ChannelData,
    ReaderError,
    build_dataset,
    to_udunits,
    validate_dataset,
)

__all__ = ["read_csv", "write_csv"]

_UNIT_IN_NAME = re.compile(r"^(.*?)\s*[\[(]([^\])]*)[\])]\s*$")


def _float(tok: str, decimal_comma: bool) -> float:
    tok = tok.strip()
    if not tok:
        return float("nan")
    if decimal_comma:
        tok = tok.replace(",", ".")
    return float(tok)


def _split(line: str, delimiter: str | None) -> list[str]:
    return line.split() if delimiter is None else line.split(delimiter)


def _detect_delimiter(line: str) -> str | None:
    for d in ("\t", ";", ","):
        if d in line:
            return d
    return None


def read_csv(
    path: str | os.PathLike[str],
    fs: float | None = None,
    time_column: str | int | None = None,
    units: str | Sequence[str] | Mapping[str, str] | None = None,
    delimiter: str | None = None,
) -> xr.Dataset:
    """Read a delimited text file with one column per channel.

    Parameters
    ----------
    path : path-like
        Text file.
    fs : float, optional
        Sample rate [Hz]. Either ``fs`` or ``time_column`` is required (both: must agree).
    time_column : str or int, optional
        Name (from the header) or 0-based index of a column holding time in seconds; it must
        be uniformly sampled. It becomes the ``time`` coordinate, not a channel.
    units : str, sequence or mapping, optional
        Channel units: one string for all, one per channel (in file order, time column
        excluded) or a mapping column name -> unit. Overrides units in the header;
        default from the header, else ``"1"``.
    delimiter : str, optional
        Column separator; default detected from the first data line (whitespace if none of
        tab, ``;``, ``,``).

    Returns
    -------
    xarray.Dataset
        Common layout.

    Raises
    ------
    ValueError
        Neither ``fs`` nor ``time_column``, unknown time column, inconsistent ``fs``.
    ReaderError
        Unparsable value (naming line and column), ragged rows, NaN/empty cells (naming the
        channel and sample index), non-uniform time column.
    """
    p = Path(path)
    if fs is None and time_column is None:
        raise ValueError(
            f"{p}: give the sample rate fs=... [Hz] or time_column=... (name or index)"
        )
    if not p.is_file():
        raise FileNotFoundError(f"CSV file not found: {p}")
    try:
        text = p.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        text = p.read_text(encoding="latin-1")
    lines = [(no, ln) for no, ln in enumerate(text.splitlines(), 1) if ln.strip() and ln[0] != "#"]
    if not lines:
        raise ReaderError(f"{p}: no data lines found")
    delim = delimiter if delimiter is not None else _detect_delimiter(lines[0][1])
    decimal_comma = delim == ";" and "," in lines[min(1, len(lines) - 1)][1]
    header: list[str] | None = None
    first = _split(lines[0][1], delim)
    try:
        [_float(t, decimal_comma) for t in first]
    except ValueError:
        header = [t.strip().strip('"') for t in first]
        lines = lines[1:]
    if not lines:
        raise ReaderError(f"{p}: header but no data lines")
    ncol = len(header) if header is not None else len(first)
    data = np.empty((len(lines), ncol))
    for row, (no, ln) in enumerate(lines):
        toks = _split(ln, delim)
        if len(toks) != ncol:
            raise ReaderError(
                f"{p}, line {no}: {len(toks)} columns, expected {ncol} (ragged or truncated file)"
            )
        for col, tok in enumerate(toks):
            try:
                data[row, col] = _float(tok, decimal_comma)
            except ValueError:
                raise ReaderError(
                    f"{p}, line {no}, column {col + 1}: {tok.strip()!r} is not a number"
                ) from None
    names, file_units = [], []
    for i in range(ncol):
        raw = header[i] if header is not None else f"ch{i + 1}"
        m = _UNIT_IN_NAME.match(raw)
        names.append(m.group(1).strip() if m else raw)
        file_units.append(m.group(2).strip() if m else None)
    tcol: int | None = None
    if time_column is not None:
        if isinstance(time_column, int | np.integer):
            tcol = int(time_column)
            if not 0 <= tcol < ncol:
                raise ValueError(f"time_column = {time_column}: file has columns 0..{ncol - 1}")
        elif time_column in names:
            tcol = names.index(time_column)
        else:
            raise ValueError(f"time_column = {time_column!r} not in the header columns {names}")
    start = 0.0
    if tcol is not None:
        try:
            rate = sample_rate(data[:, tcol], name=f"{p}: time column {names[tcol]!r}")
        except ValueError as exc:
            raise ReaderError(str(exc)) from None
        if fs is not None and abs(rate - fs) > 1e-6 * fs:
            raise ValueError(f"fs = {fs} Hz disagrees with the time column ({rate:.9g} Hz)")
        fs, start = rate, float(data[0, tcol])
    chan_idx = [i for i in range(ncol) if i != tcol]
    if isinstance(units, str):
        chan_units: list[str | None] = [units] * len(chan_idx)
    elif isinstance(units, Mapping):
        unknown = set(units) - {names[i] for i in chan_idx}
        if unknown:
            raise ValueError(f"units given for unknown column(s) {sorted(unknown)}")
        chan_units = [units.get(names[i], file_units[i]) for i in chan_idx]
    elif units is not None:
        chan_units = list(units)
        if len(chan_units) != len(chan_idx):
            raise ValueError(f"units: {len(chan_units)} given for {len(chan_idx)} channel(s)")
    else:
        chan_units = [file_units[i] for i in chan_idx]
    channels = []
    for i, u in zip(chan_idx, chan_units, strict=True):
        ud, factor = to_udunits(u)
        attrs = {"source_units": u} if u is not None and (ud != u or factor != 1.0) else {}
        channels.append(ChannelData(names[i], data[:, i] * factor, units=ud, attrs=attrs))
    assert fs is not None
    return build_dataset(channels, fs, source_format="csv", source_file=str(p), start_time=start)


def write_csv(ds: xr.Dataset, path: str | os.PathLike[str], *, delimiter: str = ",") -> Path:
    """Write ``ds`` as CSV: a header ``time [s],<var> [<units>],...`` and full-precision values.

    The file reads back with ``read_csv(path, time_column="time")``.
    """
    validate_dataset(ds, name="write_csv(ds)")
    names = list(ds.data_vars)
    head = ["time [s]"] + [f"{v} [{ds[v].attrs['units']}]" for v in names]
    cols = [ds["time"].values] + [ds[v].values.astype(np.float64) for v in names]
    target = Path(path)
    np.savetxt(
        target,
        np.column_stack(cols),
        delimiter=delimiter,
        header=delimiter.join(head),
        comments="",
        fmt="%.17g",
    )
    return target
