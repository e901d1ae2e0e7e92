"""The anti-alias filter of the output decimation.

A Kaiser-window FIR designed with Kaiser's formulas (J. F. Kaiser, "Nonrecursive digital filter
design using the I0-sinh window function", 1974; Oppenheim & Schafer, *Discrete-Time Signal
Processing*, sec. 7.6): for a stop-band attenuation ``A`` dB and a transition width ``dw``
(fraction of the Nyquist frequency) the window parameter is ``beta = 0.1102 (A - 8.7)``
(``A > 50``) and the length ``N = (A - 7.95) / (2.285 pi dw) + 1``, rounded up. The taps are the
ideal low-pass ``c sinc(c m)`` (``c``: cutoff as a fraction of Nyquist, ``m`` the tap offset from
the centre) times the Kaiser window ``I0(beta sqrt(1 - (m / M)^2)) / I0(beta)``. It is the filter
``scipy.signal.firwin(N, cutoff, window=("kaiser", beta))`` gives, bit for bit (tested), written
out here because importing :mod:`scipy.signal` costs about 0.4 s, a third of a short run's
whole process.
"""

from __future__ import annotations

import math

import numpy as np

from gearvib.checks import check_count, check_real
from gearvib.memory import require_memory

__all__ = ["decimation_filter", "filter_length", "kaiser_design"]


def kaiser_design(attenuation_db: float, width: float) -> tuple[int, float]:
    """Length and ``beta`` of a Kaiser-window FIR (Kaiser's formulas).

    Parameters
    ----------
    attenuation_db : float
        Stop-band attenuation [dB], > 0.
    width : float
        Transition width as a fraction of the Nyquist frequency, in (0, 1].

    Returns
    -------
    (int, float)
        Number of taps (not forced odd) and the window parameter ``beta``.
    """
    a = abs(check_real(attenuation_db, "attenuation_db", low=8.0, high=300.0))
    width = check_real(width, "width", low=1e-12, high=1.0)
    if a > 50.0:
        beta = 0.1102 * (a - 8.7)
    elif a > 21.0:
        beta = 0.5842 * (a - 21.0) ** 0.4 + 0.07886 * (a - 21.0)
    else:
        beta = 0.0
    if not 0.0 < width <= 1.0 or a < 8.0:
        raise ValueError(f"Kaiser design: attenuation_db = {attenuation_db!r} (admissible >= 8) "
                         f"and width = {width!r} (admissible 0 < width <= 1)")
    taps = (a - 7.95) / 2.285 / (math.pi * width) + 1.0
    return math.ceil(taps), beta


def filter_length(decimation: int, attenuation_db: float = 85.0) -> int:
    """Number of taps of :func:`decimation_filter` (odd), computed without designing it.

    For astronomically large decimations (only ever computed to refuse them) an integer
    estimate of the Kaiser formula is returned instead of overflowing.
    """
    decimation = check_count(decimation, "decimation", low=1, high=10**200)
    check_real(attenuation_db, "attenuation_db", low=8.0, high=300.0)
    if decimation == 1:
        return 1
    if decimation > 10**12:
        # Kaiser: (A - 7.95) / (2.285 * pi * 0.4 / D) + 1 = 26.8 D for A = 85 dB
        return int(decimation) * 27 | 1
    numtaps, _ = kaiser_design(attenuation_db, 0.4 / decimation)
    return int(numtaps) | 1


def decimation_filter(decimation: int, attenuation_db: float = 85.0) -> np.ndarray:
    """Symmetric low-pass FIR for decimation by ``decimation`` (odd length, unit DC gain).

    Cutoff (-6 dB) at ``0.4 fs_out``, Kaiser window designed for ``attenuation_db`` with the
    transition band ``0.3 .. 0.5 fs_out``: the output is flat (within 2e-4) to ``0.3 fs_out``
    and everything at or above the output Nyquist frequency is attenuated by at least 80 dB
    before decimation (the Kaiser formula is approximate, hence the 85 dB design target), so
    nothing aliases. ``decimation == 1`` returns ``[1.0]`` (no filtering possible).
    """
    n = filter_length(decimation, attenuation_db)
    require_memory(4.0 * 8.0 * n, f"the decimation filter of decimation = {decimation} "
                   f"({n} taps)", "a smaller decimation (a larger fs_out or dt)")
    if decimation == 1:
        return np.ones(1)
    from scipy.special import i0  # light, unlike scipy.signal

    # transition 0.2 fs_out = 0.2 / D of the internal rate, normalised to the internal Nyquist
    numtaps, beta = kaiser_design(attenuation_db, 0.4 / decimation)
    numtaps |= 1
    cutoff = (0.4 / decimation) / 0.5  # fraction of the internal Nyquist frequency
    centre = (numtaps - 1) / 2.0
    m = np.arange(numtaps) - 0.5 * (numtaps - 1)
    taps = cutoff * np.sinc(cutoff * m)
    window = i0(beta * np.sqrt(1 - ((np.arange(numtaps) - centre) / centre) ** 2.0)) / i0(beta)
    taps = taps * window
    taps = taps / np.sum(taps)  # unit DC gain of the design ...
    return taps / taps.sum()  # ... and once more, as the filter has always been normalised
