"""Levels: amplitude conventions of one-sided spectral lines, dB conversion and units.

Shared by spectra, maps and order cuts. A one-sided line ``k`` of an ``nfft``-point
transform carries the power of the positive and the negative frequency, so its factor is 2
except at DC and (for even ``nfft``) at Nyquist (:func:`line_factors`). A map line in
``"power"`` is ``2|X_k|^2/S1^2``, ``"rms"`` its square root and ``"peak"`` ``sqrt(2)`` times
that; :func:`power_of` converts any of them, linear or dB, back to power.
"""

from __future__ import annotations

import numpy as np

from analysis.checks import require_choice

__all__ = ["SCALINGS", "line_factors", "power_of", "to_db", "units_of"]

#: Admissible spectrum scalings.
SCALINGS = ("peak", "rms", "power", "psd")


def to_db(values: np.ndarray, scaling: str, ref: float = 1.0) -> np.ndarray:
    """Level in dB: ``20 log10`` for amplitude scalings, ``10 log10`` for power and PSD.

    Zero values map to -400 dB (no ``-inf``).
    """
    require_choice(scaling, (*SCALINGS, "linear"), "scaling")
    factor = 20.0 if scaling in ("peak", "rms") else 10.0
    v = np.maximum(np.abs(np.asarray(values, dtype=float)) / ref, 1e-20)
    return factor * np.log10(v)


def line_factors(n_lines: int, nfft: int) -> np.ndarray:
    """One-sided factors of the ``n_lines`` lines of an ``nfft``-point real transform."""
    f = np.full(n_lines, 2.0)
    f[0] = 1.0
    if nfft % 2 == 0:
        f[-1] = 1.0
    return f


def power_of(values: np.ndarray, amplitude: str, scale: str, nfft: int) -> np.ndarray:
    """Lines ``values(frame, line)`` of a map in ``amplitude``/``scale`` as power per line."""
    v = values
    if scale == "dB":
        v = 10.0 ** (v / (10.0 if amplitude == "power" else 20.0))
    if amplitude == "power":
        return np.array(v, dtype=float, copy=True)
    p = np.asarray(v, dtype=float) ** 2
    if amplitude == "peak":
        p = p * (1.0 / line_factors(p.shape[1], nfft))
    return p


def units_of(units: str, scaling: str) -> str:
    """Units of a spectrum of a signal in ``units`` in the given scaling."""
    if scaling in ("peak", "rms"):
        return units
    if scaling == "power":
        return "1" if units == "1" else f"({units})^2"
    return "Hz-1" if units == "1" else f"({units})^2 Hz-1"
