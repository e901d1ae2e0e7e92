"""The anti-alias filter of the output decimation."""

from __future__ import annotations

import numpy as np
import scipy.signal

__all__ = ["decimation_filter", "filter_length"]


def filter_length(decimation: int, attenuation_db: float = 85.0) -> int:
    """Number of taps of :func:`decimation_filter` (odd), computed without designing it.

    For astronomically large decimations (only ever computed to refuse them) an integer
    estimate of the Kaiser formula is returned instead of overflowing.
    """
    if decimation == 1:
        return 1
    if decimation > 10**12:
        # Kaiser: (A - 7.95) / (2.285 * pi * 0.4 / D) + 1 = 26.8 D for A = 85 dB
        return int(decimation) * 27 | 1
    numtaps, _ = scipy.signal.kaiserord(attenuation_db, 0.4 / decimation)
    return int(numtaps) | 1


def decimation_filter(decimation: int, attenuation_db: float = 85.0) -> np.ndarray:
    """Symmetric low-pass FIR for decimation by ``decimation`` (odd length, unit DC gain).

    Cutoff (-6 dB) at ``0.4 fs_out``, Kaiser window designed for ``attenuation_db`` with the
    transition band ``0.3 .. 0.5 fs_out``: the output is flat (within 2e-4) to ``0.3 fs_out``
    and everything at or above the output Nyquist frequency is attenuated by at least 80 dB
    before decimation (the Kaiser formula is approximate, hence the 85 dB design target), so
    nothing aliases. ``decimation == 1`` returns ``[1.0]`` (no filtering possible).
    """
    if decimation == 1:
        return np.ones(1)
    # transition 0.2 fs_out = 0.2 / D of the internal rate, normalised to the internal Nyquist
    numtaps, beta = scipy.signal.kaiserord(attenuation_db, 0.4 / decimation)
    numtaps |= 1
    taps = scipy.signal.firwin(numtaps, 0.4 / decimation, window=("kaiser", beta), fs=1.0)
    return taps / taps.sum()
