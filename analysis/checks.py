"""Input checks shared by the readers, spectra, order and instability tools.

Each check raises :class:`ValueError` whose message names the parameter (or channel) and what is
admissible, so that a user looking at a measured file knows what to fix.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = [
    "require_finite",
    "require_monotonic",
    "require_positive",
    "require_same_length",
    "sample_rate",
]


def require_finite(values: np.ndarray, name: str) -> np.ndarray:
    """Return ``values`` as a float array; raise if it is empty or holds NaN/inf.

    Parameters
    ----------
    values : array_like
        Samples of a channel or a parameter.
    name : str
        Name used in the error message.
    """
    arr = np.asarray(values, dtype=float)
    if arr.size == 0:
        raise ValueError(f"{name}: channel is empty (needs at least one sample)")
    bad = ~np.isfinite(arr)
    if bad.any():
        first = int(np.flatnonzero(bad.ravel())[0])
        raise ValueError(
            f"{name}: {int(bad.sum())} non-finite value(s) (NaN or inf), first at flat index "
            f"{first}; only finite values are admissible"
        )
    return arr


def require_positive(value: float, name: str, *, allow_zero: bool = False) -> float:
    """Return ``value`` as float; raise unless it is finite and > 0 (or >= 0)."""
    v = float(value)
    ok = np.isfinite(v) and (v >= 0.0 if allow_zero else v > 0.0)
    if not ok:
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name} = {value!r} is not admissible: must be finite and {bound}")
    return v


def require_monotonic(values: np.ndarray, name: str, *, strict: bool = True) -> np.ndarray:
    """Raise unless ``values`` increase (strictly by default) along the last axis."""
    arr = require_finite(values, name)
    d = np.diff(arr, axis=-1)
    bad = d <= 0 if strict else d < 0
    if bad.any():
        i = int(np.flatnonzero(bad.ravel())[0])
        kind = "strictly increasing" if strict else "non-decreasing"
        raise ValueError(f"{name} must be {kind}; it is not between samples {i} and {i + 1}")
    return arr


def require_same_length(arrays: Sequence[np.ndarray], names: Sequence[str]) -> int:
    """Raise unless all arrays have the same length along their last axis."""
    lengths = [np.shape(a)[-1] for a in arrays]
    if len(set(lengths)) > 1:
        desc = ", ".join(f"{n}: {k}" for n, k in zip(names, lengths, strict=True))
        raise ValueError(f"sample-count mismatch ({desc}); channels must have equal length")
    return lengths[0]


def sample_rate(time: np.ndarray, *, name: str = "time", rtol: float = 1e-6) -> float:
    """Sample rate [Hz] of a uniformly sampled time axis.

    Raises if the axis has fewer than two samples, is not increasing, or is not uniform within
    ``rtol`` of the mean step (a sample-rate mismatch between channels shows up here).
    """
    t = require_monotonic(time, name)
    if t.size < 2:
        raise ValueError(f"{name}: needs at least two samples to define a sample rate")
    d = np.diff(t)
    dt = (t[-1] - t[0]) / (t.size - 1)
    dev = np.max(np.abs(d - dt))
    if dev > rtol * dt + 1e-12 * abs(t[-1]):
        raise ValueError(
            f"{name} is not uniformly sampled: step deviates by {dev:.3g} s from the mean "
            f"{dt:.6g} s (allowed {rtol:g} relative); resample the channel first"
        )
    return 1.0 / dt
