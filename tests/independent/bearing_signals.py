"""Independent rolling-bearing fault signals for the tests and benchmarks (no gearvib code).

A local defect is struck once per passage: a train of decaying bursts of a housing resonance
at the defect rate, its spacing jittered by 1 % (the rolling elements' slip), amplitude
modulated when the defect turns through the load zone (an inner race: at the shaft speed), in
white noise (Randall & Antoni 2011, section 2).

R. B. Randall, J. Antoni, "Rolling element bearing diagnostics - a tutorial", MSSP 25(2),
485-520, 2011.
"""

from __future__ import annotations

import numpy as np


def bearing_bursts(rate_hz: float, seconds: float, rng: np.random.Generator, *, fs: float,
                   resonance_hz: float, snr_db: float, modulation_hz: float = 0.0
                   ) -> np.ndarray:
    """Resonance bursts at ``rate_hz`` in white noise.

    Parameters
    ----------
    rate_hz : float
        Defect rate [Hz].
    seconds, fs : float
        Record length [s] and sample rate [Hz].
    rng : numpy.random.Generator
        Draws the jitter, then the noise.
    resonance_hz : float
        Natural frequency of the bursts (damping ratio 0.05, 4 ms long).
    snr_db : float
        rms of the bursts over the rms of the noise (unit variance).
    modulation_hz : float
        Amplitude modulation ``1 + 0.6 cos(2 pi f t)`` of the bursts (0: none).
    """
    n = int(seconds * fs)
    x = np.zeros(n)
    gaps = 1.0 / rate_hz * (1.0 + 0.01 * rng.standard_normal(int(seconds * rate_hz + 10)))
    t_imp = np.cumsum(gaps)
    t_imp = t_imp[t_imp < seconds - 0.01]
    ring = np.arange(int(0.004 * fs)) / fs
    burst = np.exp(-2.0 * np.pi * 0.05 * resonance_hz * ring) * np.sin(
        2.0 * np.pi * resonance_hz * ring)
    for ti in t_imp:
        k = round(ti * fs)
        amp = 1.0 + 0.6 * np.cos(2.0 * np.pi * modulation_hz * ti) if modulation_hz else 1.0
        x[k:k + burst.size] += amp * burst[:max(0, min(burst.size, n - k))]
    return x / np.std(x) * 10 ** (snr_db / 20) + rng.standard_normal(n)
