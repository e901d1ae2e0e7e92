"""Waterfall traces of a run-up: spectra of an rpm-frequency map at evenly spaced speeds.

:func:`waterfall_from_map` picks the frames of an existing map (:func:`analysis.maps.
rpm_frequency_map`) nearest to evenly spaced speeds and returns them in dB as a
:class:`Waterfall` (drawn by :func:`analysis.runup_level_plots.waterfall_figure`).

References
----------
A. Brandt, *Noise and Vibration Analysis*, Wiley 2011: ch. 12 (waterfall plots of run-ups).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analysis.maps import RpmFrequencyMap

__all__ = ["Waterfall", "level_reference", "waterfall_from_map"]


def level_reference(units: str) -> str:
    """Reference of levels in dB of a signal in ``units``: ``"1 N"``; ``"1"`` when the signal
    is dimensionless (``""`` or ``"1"``), never ``"1 1"``."""
    u = str(units).strip()
    return "1" if u in ("", "1") else f"1 {u}"


@dataclass(frozen=True)
class Waterfall:
    """Spectra of an rpm-frequency map at evenly spaced speeds (a waterfall plot's traces).

    Attributes
    ----------
    rpm, time : ndarray
        Speed [min-1] and time [s] of each trace (frame centres), by increasing speed.
    frequency : ndarray
        Line frequencies [Hz].
    level_db : ndarray, shape (trace, frequency)
        Level of each line [dB re :attr:`level_reference`].
    amplitude : str
        Convention of the level (``"rms"``).
    level_reference : str
        Reference of the dB levels, e.g. ``"1 m s-2"``.
    resolution_hz : float
        Resolution bandwidth of the spectra [Hz].
    window : str
        Their window.
    name : str
        Signal name.
    """

    rpm: np.ndarray
    time: np.ndarray
    frequency: np.ndarray
    level_db: np.ndarray
    amplitude: str
    level_reference: str
    resolution_hz: float
    window: str
    name: str = "x"

    def __len__(self) -> int:
        return int(self.rpm.size)



def waterfall_from_map(m: RpmFrequencyMap, fmax: float | None = None, traces: int = 24
                       ) -> Waterfall:
    """Waterfall traces: frames of an rpm-frequency map at evenly spaced speeds, in dB.

    Parameters
    ----------
    m : RpmFrequencyMap
        A single-channel map (any amplitude and scale; converted to power per line).
    fmax : float, optional
        Highest frequency kept [Hz] (default: the whole map).
    traces : int, default 24
        Most traces; the frames nearest to ``traces`` evenly spaced speeds between the lowest
        and the highest frame speed (fewer when frames coincide or the map has fewer).

    Returns
    -------
    Waterfall
        Traces by increasing speed, levels ``10 log10(G_k)`` in dB re 1 unit (rms).
    """
    if not isinstance(m, RpmFrequencyMap) or m.values.ndim != 2:
        raise ValueError("m must be a single-channel RpmFrequencyMap")
    if isinstance(traces, bool) or not isinstance(traces, int) or not 2 <= traces <= 1000:
        raise ValueError(f"traces = {traces!r} must be an integer in 2..1000")
    fmax = float(m.frequency[-1]) if fmax is None else float(fmax)
    power = m.power()
    band = m.frequency <= fmax
    idx = np.argsort(m.rpm, kind="stable")
    if m.rpm.size <= traces:
        pick = idx
    else:
        targets = np.linspace(float(m.rpm[idx[0]]), float(m.rpm[idx[-1]]), traces)
        pick = np.unique(idx[np.clip(np.searchsorted(m.rpm[idx], targets), 0, idx.size - 1)])
        pick = pick[np.argsort(m.rpm[pick], kind="stable")]
    level = 10.0 * np.log10(np.maximum(power[pick][:, band], 1e-300))
    units = m.signal_units
    return Waterfall(rpm=np.asarray(m.rpm[pick], dtype=float),
                     time=np.asarray(m.time[pick], dtype=float),
                     frequency=np.asarray(m.frequency[band], dtype=float), level_db=level,
                     amplitude="rms", level_reference=level_reference(units),
                     resolution_hz=float(m.resolution_hz), window=m.window, name=m.name)

