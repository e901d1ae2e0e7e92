"""Resonances of order cuts: the maxima of a cut over speed that stand out (:class:`CutPeaks`).

:func:`cut_resonances` finds, per order cut in dB, the local maxima with a prominence of at
least ``min_rise_db`` within ``dynamic_range_db`` of the highest cut level, with their speed,
frequency (order x speed / 60), -3 dB speed span and the natural frequency the order crosses
there (the critical speed ``60 f_i / order`` of a Campbell diagram).

References
----------
A. Brandt, *Noise and Vibration Analysis*, Wiley 2011: ch. 12 (order sections, Campbell).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from analysis.orders import OrderCut

__all__ = ["CutPeaks", "cut_resonances"]


@dataclass(frozen=True)
class CutPeaks:
    """Resonances of order cuts: local maxima that rise at least ``min_rise_db`` above their
    surroundings, strongest level first.

    Attributes
    ----------
    order : ndarray
        Order of the cut.
    name : ndarray of str
        Name of the cut (e.g. ``"2× mesh"``).
    rpm, time : ndarray
        Speed [min-1] and time [s] of the maximum (frame centre).
    frequency_hz : ndarray
        ``order * rpm / 60`` [Hz]: the frequency that resonates.
    level_db : ndarray
        Level of the maximum [dB re the cut's reference].
    rise_db : ndarray
        Prominence of the maximum: its rise above the higher of the two minima that separate
        it from a higher level or the ends of the cut [dB].
    width_rpm : ndarray
        Speed span where the cut is within 3 dB of the maximum [min-1].
    mode : ndarray of str
        Name of the natural frequency the order crosses there ("" when none does).
    mode_frequency_hz : ndarray
        That natural frequency [Hz] (NaN when none).
    """

    order: np.ndarray
    name: np.ndarray
    rpm: np.ndarray
    time: np.ndarray
    frequency_hz: np.ndarray
    level_db: np.ndarray
    rise_db: np.ndarray
    width_rpm: np.ndarray
    mode: np.ndarray
    mode_frequency_hz: np.ndarray

    def __len__(self) -> int:
        return int(self.order.size)

    @classmethod
    def empty(cls) -> CutPeaks:
        """No resonance."""
        z = np.zeros(0)
        e = np.zeros(0, dtype=object)
        return cls(z, e, z, z, z, z, z, z, e, z)



def cut_resonances(cut: OrderCut, names: Sequence[str], fn: Any = (),
                   fn_names: Sequence[str] = (), *, min_rise_db: float = 6.0,
                   tolerance: float = 0.05, dynamic_range_db: float = 40.0) -> CutPeaks:
    """Resonances of order cuts in dB: local maxima that stand out of their surroundings.

    Parameters
    ----------
    cut : analysis.orders.OrderCut
        Order cuts in dB (``scale="dB"``), one row per order.
    names : sequence of str
        Name of each cut.
    fn : array_like
        Natural frequencies [Hz] a resonance may cross.
    fn_names : sequence of str
        Their names.
    min_rise_db : float, default 6
        Prominence a maximum needs [dB].
    tolerance : float, default 0.05
        Relative tolerance of the natural-frequency match.
    dynamic_range_db : float, default 40
        Maxima more than this below the highest level of all cuts are background [dB].

    Returns
    -------
    CutPeaks
        Strongest level first.

    Notes
    -----
    Per cut, over the frames sorted by speed, the maxima with a prominence (scipy's
    ``find_peaks``: the rise above the higher of the two minima separating the maximum from
    a higher level or the ends) of at least ``min_rise_db``. The -3 dB span is read at
    ``min(1, 3 / prominence)`` of the prominence (``peak_widths``). The order crosses the
    natural frequency ``f_i`` there when the critical speed ``60 f_i / order`` lies within
    ``tolerance`` of itself plus half the -3 dB span of the maximum's speed (the nearest such
    ``f_i``).
    """
    if not isinstance(cut, OrderCut):
        raise TypeError(f"cut must be an analysis.orders.OrderCut, got {type(cut).__name__}")
    fn = np.atleast_1d(np.asarray(fn, dtype=float))
    if len(fn_names) != fn.size:
        raise ValueError(f"fn_names: {len(fn_names)} names for {fn.size} frequencies")
    if len(names) != np.asarray(cut.orders).size:
        raise ValueError(f"names: {len(names)} names for {np.asarray(cut.orders).size} cuts")
    from scipy.signal import find_peaks, peak_widths

    values = np.asarray(cut.values, dtype=float)
    if not np.isfinite(values).any():
        return CutPeaks.empty()
    floor = float(np.nanmax(values)) - dynamic_range_db
    rows: list[tuple] = []
    order_idx = np.argsort(cut.rpm, kind="stable")
    for i, o in enumerate(cut.orders):
        y_all = np.asarray(cut.values[i], dtype=float)[order_idx]
        ok = np.isfinite(y_all)
        if ok.sum() < 3:
            continue
        y = y_all[ok]
        rpm = np.asarray(cut.rpm, dtype=float)[order_idx][ok]
        tim = np.asarray(cut.time, dtype=float)[order_idx][ok]
        pk, props = find_peaks(y, prominence=min_rise_db, height=floor)
        for j, prom in zip(pk, props["prominences"], strict=True):
            rel = min(1.0, 3.0 / float(prom))
            _, _, left, right = peak_widths(y, [j], rel_height=rel)
            grid = np.arange(y.size)
            lo_r = float(np.interp(left[0], grid, rpm))
            hi_r = float(np.interp(right[0], grid, rpm))
            f = float(o) * float(rpm[j]) / 60.0
            mode, f_mode = "", np.nan
            best = np.inf
            for fk, nk in zip(fn, fn_names, strict=True):
                crit = 60.0 * float(fk) / float(o)
                slack = tolerance * crit + 0.5 * (hi_r - lo_r)
                err = abs(crit - float(rpm[j]))
                if err <= slack and err < best:
                    best, mode, f_mode = err, str(nk), float(fk)
            rows.append((float(o), names[i], float(rpm[j]), float(tim[j]), f, float(y[j]),
                         float(prom), hi_r - lo_r, mode, f_mode))
    if not rows:
        return CutPeaks.empty()
    rows.sort(key=lambda r: (-r[5], r[0], r[2]))
    cols = list(zip(*rows, strict=True))
    return CutPeaks(order=np.asarray(cols[0]), name=np.asarray(cols[1], dtype=object),
                    rpm=np.asarray(cols[2]), time=np.asarray(cols[3]),
                    frequency_hz=np.asarray(cols[4]), level_db=np.asarray(cols[5]),
                    rise_db=np.asarray(cols[6]), width_rpm=np.asarray(cols[7]),
                    mode=np.asarray(cols[8], dtype=object), mode_frequency_hz=np.asarray(cols[9]))

