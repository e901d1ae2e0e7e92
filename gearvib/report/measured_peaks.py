"""Peaks of a measured spectrum: selection, candidate lines, identification limits, table rows.

The measured report (:mod:`gearvib.report.measured`) identifies the strongest peaks of the
spectrum and of the order spectrum of a channel (:func:`analysis.identification.identify_peaks`):
:func:`select_peaks` keeps those within :data:`PEAK_RANGE_DB` of the strongest,
:func:`shaft_lines` and :func:`map_lines` are the candidate lines used without a gear set (the
reference shaft's harmonics, the frequency-locked lines of the map), :data:`MAX_LABEL_CHANCE`
is the largest chance level at which a label is offered, and :func:`peak_table_rows` writes the
rows of the peak tables (:data:`PEAK_HEADER`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from analysis.identification import CandidateLines, PeakIdentification
from analysis.runup import MapFeatures
from analysis.spectrum import Peaks, Spectrum, to_db

__all__ = ["BEARING_FAMILIES", "MAX_LABEL_CHANCE", "MAX_PEAKS", "PEAK_HEADER",
           "PEAK_RANGE_DB", "map_lines", "peak_table_rows", "select_peaks", "shaft_lines"]


PEAK_HEADER = ("peak", "level [dB]", "best explanation", "deviation", "window", "chance")
"""Columns of the peak tables (rows: :func:`peak_table_rows`)."""

MAX_PEAKS = 12
"""Peaks identified per spectrum (the strongest)."""

MAX_LABEL_CHANCE = 0.25
"""A peak's label is offered as its explanation only when a random peak there would get a
label of the same family at most this often (the family's windows cover at most a quarter
of the band around the peak): harmonics of a shaft at high orders, whose windows widen with
the speed uncertainty until they cover the band, explain nothing."""
PEAK_RANGE_DB = 40.0
"""Peaks more than this below the strongest one of a spectrum are not identified."""

BEARING_FAMILIES = frozenset(("bearing_ftf", "bearing_bpfo", "bearing_bpfi", "bearing_bsf"))
"""Catalogue families of the rolling-bearing lines (cage, outer race, inner race, rolling
element), which the peak identification takes with the bearings of a machine without gears."""


def select_peaks(pk: Peaks, keep: np.ndarray, scaling: str = "rms") -> Peaks:
    """The peaks where ``keep`` is true and within :data:`PEAK_RANGE_DB` of the strongest.

    Parameters
    ----------
    pk : Peaks
        Peaks of a spectrum or order spectrum.
    keep : ndarray of bool
        Peaks that may be kept (e.g. inside the band).
    scaling : str
        Amplitude scaling of the levels (:func:`analysis.spectrum.to_db`).

    Returns
    -------
    Peaks
        The kept peaks, in their order.
    """

    if keep.any():
        lv = to_db(pk.amplitude, scaling)
        keep = keep & (lv >= float(np.max(lv[keep])) - PEAK_RANGE_DB)

    return replace(pk, frequency=pk.frequency[keep], amplitude=pk.amplitude[keep],
                   **{k: getattr(pk, k)[keep] for k in ("bin_frequency", "bin_value")
                      if hasattr(pk, k) and np.ndim(getattr(pk, k)) == 1
                      and getattr(pk, k).size == keep.size})


def shaft_lines(base: float, top: float, axis: str) -> CandidateLines:
    """Harmonics ``k × base`` up to ``top`` (the reference shaft's orders) as candidate lines.

    Parameters
    ----------
    base : float
        The shaft's frequency [Hz] (``axis="frequency"``) or 1 (``axis="order"``).
    top : float
        Highest line.
    axis : {"frequency", "order"}
        Axis of the lines.

    Returns
    -------
    CandidateLines
        Family ``shaft``, order-locked, relative uncertainty 2e-3.
    """
    k = np.arange(1, max(2, int(top / base) + 1))
    expr = [f"{i} × f_ref" if axis == "frequency" else f"shaft order {i}" for i in k]
    return CandidateLines(value=k * base, family=np.full(k.size, "shaft", dtype=object),
                          expression=np.asarray(expr, dtype=object),
                          uncertainty=np.full(k.size, 2e-3),
                          locked=np.full(k.size, "order", dtype=object), axis=axis)


def map_lines(features: MapFeatures, tolerance: float) -> CandidateLines:
    """The frequency-locked lines of a map as candidate lines (family ``map line``).

    Parameters
    ----------
    features : MapFeatures
        Rays and lines of the map (:func:`analysis.runup.map_features`).
    tolerance : float
        Relative uncertainty of a line.

    Returns
    -------
    CandidateLines
    """
    f = np.asarray(features.frequencies, dtype=float)
    return CandidateLines(value=f, family=np.full(f.size, "map line", dtype=object),
                          expression=np.asarray([f"line {v:.0f} Hz of the map" for v in f],
                                                dtype=object),
                          uncertainty=np.full(f.size, tolerance),
                          locked=np.full(f.size, "frequency", dtype=object), axis="frequency")


def peak_table_rows(ident: PeakIdentification | None, peaks: Peaks | None,
                    sp: Spectrum | None, unit: str) -> list[tuple[str, ...]]:
    """Rows of a peak table (:data:`PEAK_HEADER`), one a peak.

    A chance-level candidate is not offered as the explanation: the row says how often its
    family would match a random peak there.

    Parameters
    ----------
    ident : PeakIdentification or None
        Explanations of the peaks.
    peaks : Peaks or None
        The peaks (their levels).
    sp : Spectrum or None
        The spectrum (its amplitude scaling).
    unit : {"Hz", "order"}
        Axis of the peaks.

    Returns
    -------
    list of tuple of str
        ``[]`` when any input is None.
    """
    if ident is None or peaks is None or sp is None:
        return []
    lv = to_db(peaks.amplitude, sp.amplitude)
    rows: list[tuple[str, ...]] = []
    for i in range(len(ident)):
        ms = ident.matches[i]
        status = str(ident.status[i])
        head = (f"{ident.peaks[i]:.4g}" if unit == "order" else
                f"{ident.peaks[i]:.0f} Hz" if ident.peaks[i] >= 100 else
                f"{ident.peaks[i]:.3g} Hz")
        if unit == "order":
            head = f"order {head}"
        if not ms:
            best, dev, win = "unexplained", "–", "–"
        else:
            exprs = [m.expression.split(" ≈ ")[0] for m in ms[:2]]
            more = f" (+{len(ms) - 2} more)" if len(ms) > 2 else ""
            if status == "explained":
                best = " ≈ ".join(exprs) + more
                dev = f"{ms[0].deviation:+.3g}"
                win = f"± {ms[0].tolerance:.3g}"
            else:  # chance-level candidates are not offered as explanations
                best = (f"unexplained ({ms[0].family} lines would match "
                        f"{100 * ms[0].coincidence:.0f} % of random peaks here)")
                dev, win = "–", "–"
        rows.append((head, f"{lv[i]:.1f}", best, dev, win,
                     f"{100 * ident.coincidence[i]:.0f} %"))
    return rows
