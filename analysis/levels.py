"""Levels: amplitude conventions of one-sided spectral lines, dB conversion and units.

Shared by spectra, maps and order cuts. A one-sided line ``k`` of an ``nfft``-point
transform carries the power of the positive and the negative frequency, so its factor is 2
except at DC and (for even ``nfft``) at Nyquist (:func:`line_factors`). A map line in
``"power"`` is ``2|X_k|^2/S1^2``, ``"rms"`` its square root and ``"peak"`` ``sqrt(2)`` times
that; :func:`power_of` converts any of them, linear or dB, back to power.
"""

from __future__ import annotations

import warnings
from typing import Any, Literal

import numpy as np

from analysis.checks import (
    renamed,
    require_choice,
    require_int,
    require_real_array,
    require_size,
)

__all__ = [
    "AMPLITUDES",
    "SCALINGS",
    "amplitude_choice",
    "line_factors",
    "power_of",
    "to_db",
    "units_of",
]

#: An amplitude convention of a spectrum.
Amplitude = Literal["peak", "rms", "power", "density"]
#: Amplitude conventions of spectra (``"density"`` is the PSD, scipy's word).
AMPLITUDES: tuple[Amplitude, ...] = ("peak", "rms", "power", "density")
#: Deprecated: the conventions with the old name ``"psd"`` for ``"density"``.
SCALINGS = ("peak", "rms", "power", "psd")
#: Highest level [dB] :func:`power_of` converts (1e300 as a power).
MAX_DB = 3000.0
#: Highest power per line :func:`power_of` returns (float64 ends near 1.8e308).
MAX_POWER = 1e300


def amplitude_choice(
    amplitude: Any,
    scaling: Any,
    function: str,
    allowed: tuple[Amplitude, ...],
    default: Amplitude = "rms",
) -> Amplitude:
    """Checked amplitude convention from ``amplitude=`` or the deprecated ``scaling=``.

    The old value ``"psd"`` is accepted for ``"density"`` with a :class:`FutureWarning`.
    """
    value = renamed(amplitude, scaling, "amplitude", "scaling", function, stacklevel=4)
    if value is None:
        return default
    if value == "psd" and "density" in allowed:
        warnings.warn(
            f"{function}: 'psd' is deprecated and will be removed in the next release; use "
            "'density' (scipy's word)",
            FutureWarning,
            stacklevel=3,
        )
        return "density"
    return require_choice(value, allowed, "amplitude")


def to_db(values: np.ndarray, scaling: str, ref: float = 1.0) -> np.ndarray:
    """Level in dB: ``20 log10`` for amplitudes (peak, rms), ``10 log10`` for power and density.

    ``scaling`` is the amplitude convention of ``values`` (``"psd"`` is accepted for
    ``"density"``). Zero values map to -400 dB (no ``-inf``).
    """
    require_choice(scaling, (*AMPLITUDES, "psd", "linear"), "scaling")
    factor = 20.0 if scaling in ("peak", "rms") else 10.0
    v = np.maximum(np.abs(np.asarray(values, dtype=float)) / ref, 1e-20)
    return factor * np.log10(v)


def line_factors(n_lines: int, nfft: int) -> np.ndarray:
    """One-sided factors of the first ``n_lines`` lines of an ``nfft``-point real transform
    (1 for DC and, when it is among them, the Nyquist line of an even ``nfft``; 2 else)."""
    n_lines = require_int(n_lines, "n_lines", 1)
    nfft = require_int(nfft, "nfft", 1)
    require_size(8.0 * n_lines, f"{n_lines} line factors", "n_lines")
    f = np.full(n_lines, 2.0)
    f[0] = 1.0
    if nfft % 2 == 0 and n_lines == nfft // 2 + 1:
        f[-1] = 1.0
    return f


def power_of(values: np.ndarray, amplitude: str, scale: str, nfft: int) -> np.ndarray:
    """Lines ``values(..., line)`` of a map in ``amplitude``/``scale`` as power per line.

    Levels in dB must lie at or below :data:`MAX_DB`, linear amplitudes at or below
    ``sqrt(MAX_POWER)`` (their power would overflow float64 otherwise).
    """
    v = require_real_array(values, "values", min_size=1)
    require_choice(amplitude, AMPLITUDES, "amplitude")
    require_choice(scale, ("linear", "dB"), "scale")
    nfft = require_int(nfft, "nfft", 1)
    if v.ndim == 0:
        raise ValueError("values must be an array of lines (last axis); got a scalar")
    top = float(v.max())
    if scale == "dB" and top > MAX_DB:
        raise ValueError(f"values: a level of {top:g} dB; admissible: <= {MAX_DB:g} dB (its power "
                         "would overflow)")
    if scale != "dB" and amplitude != "power" and max(top, -float(v.min())) > MAX_POWER ** 0.5:
        raise ValueError(f"values: a magnitude above {MAX_POWER ** 0.5:g}; admissible: "
                         f"|value| <= {MAX_POWER ** 0.5:g} (its square would overflow)")
    with np.errstate(under="ignore"):
        if scale == "dB":
            v = 10.0 ** (v / (10.0 if amplitude == "power" else 20.0))
        if amplitude == "power":
            return np.array(v, dtype=float, copy=True)
        p = v**2
        if amplitude == "peak":
            p = p * (1.0 / line_factors(p.shape[-1], nfft))
    return p


def units_of(units: str, amplitude: str, per: str = "Hz-1") -> str:
    """Units of a spectrum of a signal in ``units`` in the given amplitude convention.

    ``per`` is the unit of the density's denominator (``"Hz-1"``; ``""`` for a density per
    order, which is dimensionless).
    """
    if amplitude in ("peak", "rms"):
        return units
    squared = "1" if units == "1" else f"({units})^2"
    if amplitude == "power" or not per:
        return squared
    return per if units == "1" else f"{squared} {per}"
