"""Delimited text (CSV/TXT) reader and writer.

The first non-comment line may be a header of column names; a unit in brackets after the name
(``"acc_x [m/s2]"`` or ``"acc_x (m/s^2)"``) is taken as the channel unit. Lines starting with
``#`` are comments, and so is the rest of a line after ``#``. The delimiter is detected
(``,``, ``;``, tab, whitespace) unless given; with ``;`` as delimiter a decimal comma
(``1,25``) is accepted.

Parsing is vectorised: the body goes through pandas' C parser (``pandas.read_csv``; pandas
is installed with xarray) in one pass, 7-8 times faster than :func:`numpy.loadtxt` on
full-precision files. Only when that fails (or leaves NaN) is the file scanned line by line
in Python, to name the first line and column that is not a number (without echoing its
content) or to read the rare layouts the C parser refuses (whitespace-only lines between
data lines). The end of the file
is checked for truncation: a last line without end-of-line whose last number has fewer digits
than the same column on the lines before is refused as cut. A time column is checked against
a uniform grid with the tolerance its own print allows (:mod:`analysis.readers.timebase`).
"""

from __future__ import annotations

import csv
import io
import os
import re
import warnings
from array import array
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr

from analysis.readers.integrity import file_size, reading, require_memory
from analysis.readers.layout import (
    ChannelData,
    ReaderError,
    build_dataset,
    to_udunits,
    validate_dataset,
)
from analysis.readers.timebase import grid_fits, print_precision, uniform_rate

__all__ = ["read_csv", "write_csv"]

_UNIT_IN_NAME = re.compile(r"^(.*?)\s*[\[(]([^\])]*)[\])]\s*$")
_NUMBER = re.compile(r"[+-]?(\d*)(?:\.(\d*))?(?:[eE][+-]?(\d+))?")  # whole, decimals, exp
_BOM = b"\xef\xbb\xbf"
_SAMPLE_ROWS = 1000  # rows read in Python at each end (print precision, truncation check)
_TAIL_BYTES = 1 << 16
_MAX_LINE = 1 << 24  # 16 MiB: longer "lines" are not text


@dataclass
class _Layout:
    """What the first lines of a file say about the rest."""

    offset: int  # byte offset of the first data line
    first_line: int  # its line number (1-based)
    delimiter: str | None
    decimal_comma: bool
    ncol: int
    header: list[str] | None
    rows: list[list[str]] = field(default_factory=list)  # tokens of the first data rows
    row_bytes: float = 16.0  # mean bytes per data row among them


def _tokens(line: str, delimiter: str | None, decimal_comma: bool) -> list[str]:
    """Fields of a line without its comment; [] for a blank or comment line."""
    content = line.split("#", 1)[0]
    if not content.strip():
        return []
    toks = content.split() if delimiter is None else content.split(delimiter)
    if decimal_comma:
        toks = [t.replace(",", ".") for t in toks]
    return [t.strip() for t in toks]


def _is_number(tok: str) -> bool:
    if not tok or "_" in tok:
        return False
    try:
        float(tok)
    except ValueError:
        return False
    return True


def _detect_delimiter(line: str) -> str | None:
    for d in ("\t", ";", ","):
        if d in line:
            return d
    return None


def _decode(raw: bytes) -> str:
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def _header_names(line: str, delimiter: str | None) -> list[str]:
    """Column names of a header line; with whitespace as delimiter a bracketed unit
    (``time [s] acc [m/s2]``) stays with the name before it."""
    names: list[str] = []
    for tok in _tokens(line, delimiter, False):
        tok = tok.strip().strip('"')
        unit = tok[:1] in "[(" and tok[-1:] in ")]"
        if delimiter is None and unit and names:
            names[-1] = f"{names[-1]} {tok}"
        else:
            names.append(tok)
    return names


def _layout(p: Path, delimiter: str | None) -> _Layout:
    """Header, delimiter, decimal comma and the first data rows, read line by line."""
    with open(p, "rb") as fh:
        offset, lineno = 0, 0
        content: list[tuple[int, int, str]] = []  # (offset, line number, text) of content lines
        while len(content) < 2:
            raw = fh.readline(_MAX_LINE)
            if not raw:
                break
            if lineno == 0 and raw.startswith(_BOM):
                raw, offset = raw[3:], 3
            lineno += 1
            if len(raw) == _MAX_LINE and not raw.endswith(b"\n"):
                raise ReaderError(f"{p}, line {lineno}: longer than {_MAX_LINE} bytes; not text")
            text = _decode(raw)
            stripped = text.strip()
            if stripped and not stripped.startswith("#"):
                content.append((offset, lineno, text))
            offset += len(raw)
        if not content:
            raise ReaderError(f"{p}: no data lines found (only comments or blank lines)")
        first_offset, first_no, first = content[0]
        delim = delimiter if delimiter is not None else _detect_delimiter(first)
        probe = content[1][2] if len(content) > 1 else first
        decimal_comma = delim == ";" and "," in probe.split("#", 1)[0]
        toks = _tokens(first, delim, decimal_comma)
        header, ncol = None, len(toks)
        if not all(_is_number(t) for t in toks):
            if len(content) < 2:
                raise ReaderError(f"{p}: header but no data lines")
            header = _header_names(first, delim)
            ncol = len(_tokens(content[1][2], delim, decimal_comma))
            if len(header) != ncol:
                if ncol == 1 and delim is None:  # one column whose name has blanks
                    header = [first.split("#", 1)[0].strip().strip('"')]
                else:
                    raise ReaderError(
                        f"{p}, line {first_no}: the header has {len(header)} names but line "
                        f"{content[1][1]} has {ncol} columns; give delimiter= if it is not "
                        f"{delim or 'whitespace'!r}"
                    )
            body_offset, body_no = content[1][0], content[1][1]
        else:
            body_offset, body_no = first_offset, first_no
        layout = _Layout(body_offset, body_no, delim, decimal_comma, ncol, header)
        fh.seek(body_offset)
        nbytes = 0
        while len(layout.rows) < _SAMPLE_ROWS:
            raw = fh.readline(_MAX_LINE)
            if not raw:
                break
            nbytes += len(raw)
            row = _tokens(raw.decode("latin-1"), delim, decimal_comma)
            if row:
                layout.rows.append(row)
        layout.row_bytes = max(nbytes / max(len(layout.rows), 1), 2.0 * layout.ncol)
    return layout


def _scan(p: Path, layout: _Layout) -> np.ndarray:
    """Line-by-line parse: the values, or a ReaderError at the first bad line and column."""
    values = array("d")
    with open(p, "rb") as raw:
        raw.seek(layout.offset)
        text = io.TextIOWrapper(raw, encoding="latin-1", newline=None)
        for no, line in enumerate(text, layout.first_line):
            toks = _tokens(line, layout.delimiter, layout.decimal_comma)
            if not toks:
                continue
            if len(toks) != layout.ncol:
                raise ReaderError(
                    f"{p}, line {no}: {len(toks)} columns, expected {layout.ncol} (ragged or "
                    "truncated file)"
                )
            for col, tok in enumerate(toks, 1):
                if not tok:
                    raise ReaderError(
                        f"{p}, line {no}, column {col}: empty value; every cell needs a number"
                    )
                if not _is_number(tok):
                    raise ReaderError(f"{p}, line {no}, column {col}: not a number")
                values.append(float(tok))
    return np.frombuffer(values, dtype=np.float64).reshape(-1, layout.ncol).copy()


def _parse(p: Path, layout: _Layout) -> list[np.ndarray]:
    """The columns of the body: pandas' C parser, the line scan if it fails or leaves NaN.

    The C parser is told exactly what the line scan accepts (no quoting, ``#`` comments,
    blank lines skipped, every value a float64); NaN in its result come from short rows or
    ``nan`` tokens, which the line scan tells apart (a ragged-row error, or NaN values that
    :func:`~analysis.readers.layout.build_dataset` reports by channel and sample index).
    """
    import pandas as pd

    with open(p, "rb") as raw:
        raw.seek(layout.offset)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                frame = pd.read_csv(
                    raw,
                    sep=r"\s+" if layout.delimiter is None else layout.delimiter,
                    decimal="," if layout.decimal_comma else ".",
                    header=None,
                    comment="#",
                    skip_blank_lines=True,
                    quoting=csv.QUOTE_NONE,
                    na_filter=False,
                    dtype=np.float64,
                    encoding="utf-8",  # numbers are ASCII; other bytes fail and are scanned
                    encoding_errors="replace",
                    engine="c",
                )
        except (ValueError, pd.errors.ParserError, pd.errors.EmptyDataError):
            frame = None
    columns: list[np.ndarray] = []
    if frame is not None and frame.shape[1] == layout.ncol and len(frame):
        columns = [np.ascontiguousarray(frame.iloc[:, i].to_numpy()) for i in range(layout.ncol)]
        del frame
    if not columns or any(np.isnan(c).any() for c in columns):
        table = _scan(p, layout)
        columns = [table[:, i] for i in range(layout.ncol)]
    if columns[0].size == 0:
        raise ReaderError(f"{p}: no data lines found")
    return columns


def _shape(tok: str) -> tuple[str, int, int]:
    """How a number is printed: ("e", decimals, exponent digits) for exponent notation,
    ("f", decimals) with a decimal point, ("i", digits) for an integer. Cutting a printed
    number always changes its shape."""
    m = _NUMBER.fullmatch(tok)
    if m is None:
        return ("?", -1, -1)
    if m.group(3) is not None:
        return ("e", len(m.group(2) or ""), len(m.group(3)))
    if m.group(2) is not None or "." in tok:
        return ("f", len(m.group(2) or ""), 0)
    return ("i", len(m.group(1)), 0)


def _tail(p: Path, layout: _Layout, size: int) -> list[list[str]]:
    """Tokens of the last rows; refuse a last line that may have been cut.

    A file whose last line ends without end-of-line may have been cut inside its last
    number, which still parses. The line is accepted only when its last number is printed
    exactly like that column on every line before it (same notation, decimals and exponent
    digits -- a fixed format, where every cut shows), else the file is refused as truncated.
    """
    start = max(layout.offset, size - _TAIL_BYTES)
    with open(p, "rb") as fh:
        fh.seek(start)
        block = fh.read()
    lines = block.decode("latin-1").splitlines()
    if start > layout.offset:
        lines = lines[1:]  # the first line of the block may be partial
    rows = [r for r in (_tokens(ln, layout.delimiter, layout.decimal_comma) for ln in lines) if r]
    last_text = lines[-1].split("#", 1)[0] if lines else ""
    if not rows or block.endswith((b"\n", b"\r")) or not last_text.strip():
        return rows
    before = [r[-1] for r in rows[-1 - _SAMPLE_ROWS : -1] if len(r) == layout.ncol]
    shapes = {_shape(tok) for tok in before}
    if len(shapes) != 1 or _shape(rows[-1][-1]) not in shapes:
        with open(p, "rb") as fh:
            line_no = sum(chunk.count(b"\n") for chunk in iter(lambda: fh.read(1 << 24), b""))
        why = (
            "its last number is printed with fewer digits than on the lines before"
            if len(shapes) == 1
            else "the last column is not printed with a fixed number of digits, so a cut "
            "number cannot be told from a complete one"
        )
        raise ReaderError(
            f"{p}, line {line_no + 1}: the file ends without end-of-line and {why}: it may be "
            "truncated; if it is complete, end it with a newline"
        )
    return rows


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
        Sample rate [Hz]. Either ``fs`` or ``time_column`` is required (both: the time column
        must lie on the grid of ``fs`` within its printed precision).
    time_column : str or int, optional
        Name (from the header) or 0-based index of a column holding time in seconds; it must
        be uniformly sampled within the precision it is printed with (a column printed with
        8 decimals at 25.6 kHz is uniform; a missing sample is not). The rate is snapped to
        the roundest value (multiples of 1000, 100, 10, 1, ... 0.001 Hz) whose grid fits the
        printed values. It becomes the ``time`` coordinate, not a channel.
    units : str, sequence or mapping, optional
        Channel units: one string for all, one per channel (in file order, time column
        excluded) or a mapping column name -> unit. Overrides units in the header;
        default from the header, else ``"1"``.
    delimiter : str, optional
        Column separator; default detected from the first line (whitespace if none of
        tab, ``;``, ``,``).

    Returns
    -------
    xarray.Dataset
        Common layout.

    Raises
    ------
    ValueError
        Neither ``fs`` nor ``time_column``, unknown time column, ``fs`` inconsistent with the
        time column.
    ReaderError
        A value that is not a number or an empty cell (naming line and column, not the
        content), ragged rows (line and column counts), a truncated last line, NaN values
        (channel and sample index), a non-uniform time column (sample index, deviation and
        the bound its print allows), not enough memory.
    """
    p = Path(path)
    if fs is None and time_column is None:
        raise ValueError(
            f"{p}: give the sample rate fs=... [Hz] or time_column=... (name or index)"
        )
    if not p.is_file():
        raise FileNotFoundError(f"CSV file not found: {p}")
    size = file_size(p)
    with reading(p, "CSV"):
        layout = _layout(p, delimiter)
    ncol = layout.ncol
    rows_est = (size - layout.offset) / layout.row_bytes + 1
    require_memory(
        3 * 8 * rows_est * ncol + (2 * size if layout.decimal_comma else 0),
        p,
        f"about {rows_est:.3g} rows x {ncol} columns",
    )
    with reading(p, "CSV"):
        columns = _parse(p, layout)
        tail_rows = _tail(p, layout, size)
    header = layout.header
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
        printed = [r[tcol] for r in layout.rows + tail_rows if len(r) == ncol]
        precision = print_precision(printed)
        label = f"{p}: time column {names[tcol]!r}"
        try:
            rate, start = uniform_rate(columns[tcol], precision, name=label)
        except ValueError as exc:
            raise ReaderError(str(exc)) from None
        if fs is not None:
            if not grid_fits(columns[tcol], float(fs), precision):
                raise ValueError(
                    f"fs = {fs} Hz disagrees with the time column ({rate:.9g} Hz) beyond its "
                    "printed precision"
                )
            rate = float(fs)
        fs = rate
    chan_idx = [i for i in range(ncol) if i != tcol]
    if not chan_idx:
        raise ReaderError(f"{p}: only the time column; no channel to read")
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
        with np.errstate(over="ignore", invalid="ignore"):  # inf/NaN: reported by channel
            values = columns[i] * factor if factor != 1.0 else columns[i]
        channels.append(ChannelData(names[i], values, units=ud, attrs=attrs))
    assert fs is not None
    return build_dataset(channels, fs, source_format="csv", source_file=str(p), start_time=start)


_NOT_DELIMITER = "0123456789.+-eE\"\r\n"


def write_csv(ds: xr.Dataset, path: str | os.PathLike[str], *, delimiter: str = ",") -> Path:
    """Write ``ds`` as CSV: a header ``time [s],<var> [<units>],...`` and full-precision values.

    Every number is printed as ``%.16e`` (17 significant digits: float64 values read back
    bit for bit; the fixed width lets :func:`read_csv` recognise a cut last line). The file
    reads back with ``read_csv(path, time_column="time")``.
    """
    validate_dataset(ds, name="write_csv(ds)")
    if not isinstance(delimiter, str):
        raise TypeError(f"delimiter must be a str (e.g. ',' ';' or a tab); got "
                        f"{type(delimiter).__name__}")
    if not delimiter or len(delimiter) > 8 or any(c in _NOT_DELIMITER for c in delimiter):
        raise ValueError(f"delimiter = {delimiter[:20]!r} is not admissible: 1 to 8 characters, "
                         "none of them part of a number, a quote or a line break")
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
        fmt="%.16e",
    )
    return target
