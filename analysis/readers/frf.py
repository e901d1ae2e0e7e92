"""Measured frequency response functions (FRF): UFF dataset 58 (function type 4) and CSV.

An FRF file from a hammer test or a shaker measurement of a housing (Simcenter Testlab, PULSE,
ME'scope export UFF 58 with function type 4, complex ordinates over frequency). The reader
returns :class:`FrequencyResponse` with the response quantity from the UFF record-8/9 data
types: numerator 8 displacement, 11 velocity, 12 acceleration over denominator 13 force give
receptance, mobility or accelerance; :meth:`FrequencyResponse.accelerance` converts any of them
to acceleration per force (multiplying by ``i omega`` once or twice). Unit labels ``g`` are
converted to m s-2.

CSV: columns ``frequency [Hz], real, imaginary`` (``columns = "real_imag"``) or ``frequency,
magnitude, phase [deg]`` (``"magnitude_phase"``); delimiter ``,`` ``;`` (decimal comma), tab or
blanks, header lines and ``#`` comments skipped; the quantity is given by the caller.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from analysis.readers.layout import ReaderError
from analysis.readers.texttable import table_lines

__all__ = ["FRF_QUANTITIES", "FrequencyResponse", "read_frf", "read_frf_csv", "read_frf_uff"]

FRF_QUANTITIES = ("accelerance", "mobility", "receptance")
"""Admissible response quantities: acceleration, velocity or displacement per force."""

_G = 9.80665
_UFF_FRF = 4  # record 6, field 1: function type 4 = frequency response function
_UFF_FREQUENCY = 18  # record 8: abscissa data type 18 = frequency
_NUMERATOR = {8: "receptance", 11: "mobility", 12: "accelerance"}
_FORCE = 13


@dataclass(frozen=True)
class FrequencyResponse:
    """A measured frequency response function.

    Attributes
    ----------
    frequency : ndarray
        Frequencies [Hz], strictly increasing, >= 0.
    values : ndarray of complex
        Response per force at those frequencies (SI: m N-1, m s-1 N-1 or m s-2 N-1).
    quantity : str
        ``"accelerance"``, ``"mobility"`` or ``"receptance"``.
    source : str
        File it was read from.
    """

    frequency: np.ndarray
    values: np.ndarray
    quantity: str
    source: str = ""

    def __post_init__(self) -> None:
        f = np.asarray(self.frequency, dtype=float)
        v = np.asarray(self.values, dtype=complex)
        if f.ndim != 1 or f.size < 2 or f.shape != v.shape:
            raise ValueError("an FRF needs >= 2 frequencies with one value each")
        if not (np.all(np.isfinite(f)) and np.all(np.isfinite(v))):
            raise ValueError("FRF frequencies and values must be finite")
        if f[0] < 0 or np.any(np.diff(f) <= 0):
            raise ValueError("FRF frequencies must be >= 0 and strictly increasing")
        if self.quantity not in FRF_QUANTITIES:
            raise ValueError(f"FRF quantity {self.quantity!r} is not admissible (admissible: "
                             f"{', '.join(FRF_QUANTITIES)})")
        object.__setattr__(self, "frequency", f)
        object.__setattr__(self, "values", v)

    def accelerance(self) -> np.ndarray:
        """Acceleration per force at :attr:`frequency` [m s-2 N-1]."""
        iw = 2j * np.pi * self.frequency
        if self.quantity == "mobility":
            return self.values * iw
        if self.quantity == "receptance":
            return self.values * iw * iw
        return self.values.copy()


def _unit_factor(label: str) -> float:
    """Factor to SI for a UFF ordinate numerator label (``g`` -> 9.80665, else 1)."""
    lab = label.strip().lower().replace(" ", "")
    return _G if lab in ("g", "g/n", "g/lbf") else 1.0


def read_frf_uff(path: str | os.PathLike[str], set_index: int = 0) -> FrequencyResponse:
    """Read one FRF (dataset 58, function type 4) of a UFF file.

    Parameters
    ----------
    path : path-like
        ``.uff`` / ``.unv`` file.
    set_index : int
        0-based index among the FRF sets of the file.

    Raises
    ------
    ImportError
        pyuff missing (``pip install "gearvib[uff]"``).
    ReaderError
        No FRF set, an abscissa that is not frequency, an unknown numerator or a denominator
        that is not a force, a set out of range.
    """
    try:
        import pyuff
    except ImportError:
        raise ImportError('reading UFF/UNV files needs pyuff: pip install "gearvib[uff]"') from None
    p = Path(path)
    if not _is_file(p):
        raise FileNotFoundError(f"FRF file not found: {p}")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            uff = pyuff.UFF(str(p))
            types = list(np.atleast_1d(uff.get_set_types()).astype(int))
            sets = [uff.read_sets(i) for i, t in enumerate(types) if t == 58]
    except Exception as exc:  # pyuff raises assorted errors on damaged files
        raise ReaderError(f"{p}: not a readable UFF file: {exc}") from None
    frfs = [r for r in sets if int(r.get("func_type", -1)) == _UFF_FRF]
    if not frfs:
        raise ReaderError(f"{p}: no frequency response function (dataset 58, function type 4) "
                          f"found ({len(sets)} dataset-58 sets of other types)")
    if not 0 <= set_index < len(frfs):
        raise ValueError(f"set_index = {set_index}: admissible are 0..{len(frfs) - 1}")
    r = frfs[set_index]
    where = f"{p}: FRF set {set_index}"
    if int(r.get("abscissa_spec_data_type", 0)) not in (0, _UFF_FREQUENCY):
        raise ReaderError(f"{where}: abscissa data type {r.get('abscissa_spec_data_type')}; "
                          "only 18 (frequency) is admissible")
    num = int(r.get("ordinate_spec_data_type", 0))
    den = int(r.get("orddenom_spec_data_type", 0))
    if num not in _NUMERATOR or den != _FORCE:
        raise ReaderError(f"{where}: response data type {num} over {den}; admissible are "
                          "displacement (8), velocity (11) or acceleration (12) over force (13)")
    data = np.asarray(r["data"])
    if int(r.get("abscissa_spacing", 1)) == 1:
        freq = float(r.get("abscissa_min", 0.0)) + float(r["abscissa_inc"]) * np.arange(
            data.size)
    else:
        freq = np.asarray(r["x"], dtype=float)
    factor = _unit_factor(str(r.get("ordinate_axis_units_lab", "")))
    try:
        return FrequencyResponse(freq, data.astype(complex) * factor, _NUMERATOR[num], str(p))
    except ValueError as exc:
        raise ReaderError(f"{where}: {exc}") from None


TEXT_MAX_BYTES = 16 * 2**20
"""Largest FRF text file read [bytes]."""


def _is_file(p: Path) -> bool:
    try:
        return p.is_file()
    except (OSError, ValueError):  # a name too long, a NUL character: no such file
        return False


def read_frf_csv(path: str | os.PathLike[str], *, quantity: str = "accelerance",
                 columns: str = "real_imag") -> FrequencyResponse:
    """Read an FRF from a text file (module docstring).

    Parameters
    ----------
    path : path-like
        The file.
    quantity : {"accelerance", "mobility", "receptance"}
        What the values are (SI units).
    columns : {"real_imag", "magnitude_phase"}
        Second and third column: real and imaginary part, or magnitude and phase [deg].

    Raises
    ------
    ReaderError
        Missing file, a non-numeric data line, fewer than 2 rows or 3 columns, bad values.
    """
    if columns not in ("real_imag", "magnitude_phase"):
        raise ValueError(f"columns = {columns!r} is not admissible (admissible: real_imag, "
                         "magnitude_phase)")
    p = Path(path)
    if not _is_file(p):
        raise FileNotFoundError(f"FRF file not found: {p}")
    size = p.stat().st_size
    if size > TEXT_MAX_BYTES:
        raise ReaderError(f"{p.name}: {size / 2**20:.1f} MiB is too large for an FRF text file "
                          f"(admissible: at most {TEXT_MAX_BYTES // 2**20} MiB)")
    try:
        text = p.read_bytes().decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ReaderError(f"{p.name}: not a UTF-8 text file (byte {exc.start}: "
                          f"{exc.reason})") from None
    rows: list[list[float]] = []
    for lineno, parts in table_lines(text):
        try:
            vals = [float(x) for x in parts[:3]]
            if len(vals) < 3:
                raise ValueError
        except ValueError:
            if rows:
                raise ReaderError(f"{p.name}, line {lineno}: need three numbers (frequency, "
                                  f"{columns.replace('_', ', ')}) in the first three columns"
                                  ) from None
            continue  # header
        rows.append(vals)
    if len(rows) < 2:
        raise ReaderError(f"{p.name}: found {len(rows)} numeric rows (admissible: >= 2)")
    a = np.array(rows)
    if columns == "real_imag":
        values = a[:, 1] + 1j * a[:, 2]
    else:
        values = a[:, 1] * np.exp(1j * np.radians(a[:, 2]))
    try:
        return FrequencyResponse(a[:, 0], values, quantity, str(p))
    except ValueError as exc:
        raise ReaderError(f"{p.name}: {exc}") from None


def read_frf(path: str | os.PathLike[str], **kwargs) -> FrequencyResponse:
    """Read an FRF: UFF (``.uff``, ``.unv``) or text (any other extension); keyword arguments
    go to :func:`read_frf_uff` or :func:`read_frf_csv`."""
    if Path(path).suffix.lower() in (".uff", ".unv"):
        return read_frf_uff(path, **kwargs)
    return read_frf_csv(path, **kwargs)
