"""The shaft angle of a synchronous average, from any reference, read block by block.

Time-synchronous averaging (:mod:`analysis.tsa`) and the planetary separation
(:mod:`analysis.planetary_tsa`) need the angle of the shaft of interest at every sample of
the record. It comes from one of

* ``tacho=`` -- a pulse train sampled with the signal (``pulses_per_rev`` pulses per
  revolution of the reference shaft), processed by :func:`analysis.speed.from_tacho` (edge
  detection, dropped and extra pulses repaired); the angle between pulses is the monotone
  cubic (PCHIP) interpolation of the pulse angles, as in :func:`~analysis.speed.from_tacho`;
* ``pulse_times=`` -- pulse instants [s] already extracted (MATLAB ``tsa(x, fs, tp)``);
* ``rpm=`` -- the speed [min-1] per sample, integrated (trapezoidal rule);
* ``angle=`` -- the angle [rad] per sample (an encoder, a simulation).

The reference may belong to another shaft: ``ratio`` is the speed of the shaft of interest
over the speed of the reference shaft (e.g. ``z_in / z_out`` for the output shaft of a
stage referenced by an input-shaft tacho), and the shaft angle is ``ratio`` times the
reference angle. Its zero is that of the reference: the first tacho pulse (or pulse time),
or ``angle = 0`` of an angle trace, or the first analysed sample of a speed trace.

Nothing as long as the record is allocated: the angle is computed for the stretch of samples
the angular resampler asks for (:class:`analysis.resample.Track` reads ``angle[a:b]``
slices from the lazy sequences defined here).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.interpolate import PchipInterpolator

from analysis.checks import (
    BLOCK_SAMPLES,
    require_finite,
    require_instance,
    require_int,
    require_real,
)
from analysis.inputs import Reference, Signal, moving_range, reference_input
from analysis.resample import Track, check_speed
from analysis.speed import from_tacho

__all__ = ["ShaftAngle", "shaft_angle"]

_MIN_INTERVAL = 256


class _Scaled:
    """``values[a:b] * factor`` as float64 slices, without a scaled copy of the whole array."""

    def __init__(self, values: Any, factor: float) -> None:
        self._values = values
        self._factor = factor
        self.size = int(np.shape(values)[0])
        self.shape = (self.size,)
        self.ndim = 1

    def __len__(self) -> int:
        return self.size

    def __getitem__(self, key: slice) -> np.ndarray:
        v = np.asarray(self._values[key], dtype=float)
        return v if self._factor == 1.0 else v * self._factor


class _PulseAngle:
    """Shaft angle of samples ``offset + k`` from pulse instants, by PCHIP (as ``from_tacho``).

    Instants are in samples of the record (``time * fs``); only samples inside the pulses
    are ever asked for.
    """

    def __init__(self, pchip: PchipInterpolator, offset: int, size: int, fs: float) -> None:
        self._pchip = pchip
        self._offset = offset
        self._fs = fs
        self.size = size
        self.shape = (size,)
        self.ndim = 1

    def __len__(self) -> int:
        return self.size

    def __getitem__(self, key: slice) -> np.ndarray:
        a, b, step = key.indices(self.size)
        k = np.arange(a, b, step, dtype=float) + self._offset
        return np.asarray(self._pchip(k / self._fs), dtype=float)


@dataclass(frozen=True)
class ShaftAngle:
    """The angle of the shaft of interest over the analysed samples of a record.

    Attributes
    ----------
    track : analysis.resample.Track
        Time and shaft angle [rad] of samples ``[start, stop)`` (index 0 = sample ``start``).
    start, stop : int
        The analysed samples of the record.
    ratio : float
        Speed of the shaft of interest / speed of the reference shaft.
    label : str
        What the reference is (for the result's ``speed_reference`` attribute).
    notes : tuple of str
        What was left out (standstill, samples before the first or after the last pulse).
    fs : float
        Sample rate of the record [Hz].
    """

    track: Track
    start: int
    stop: int
    ratio: float
    label: str
    notes: tuple[str, ...]
    fs: float

    @property
    def rpm_max(self) -> float:
        """Highest speed of the shaft of interest [min-1] (largest angle step)."""
        return float(self.track.step_max * self.fs * 60.0 / (2.0 * np.pi))


def _ratio(ratio: Any) -> float:
    r = require_real(ratio, "ratio")
    if r <= 0:
        raise ValueError(
            f"ratio = {ratio!r} is not admissible: must be > 0 (speed of the shaft of interest "
            "over the speed of the reference shaft)"
        )
    return r


def _pulse_reference(
    tp: np.ndarray, pulse_angle: np.ndarray, ppr: int, n: int, fs: float, ratio: float,
    interval: int, t0: float, what: str,
) -> ShaftAngle:  # fmt: skip
    """Shaft angle from pulse instants ``tp`` [s from the first sample] and their reference
    angles [rad]."""
    if tp.size < 3:
        raise ValueError(f"{what}: {tp.size} pulse(s); at least 3 are needed")
    d = np.diff(tp)
    if np.any(d <= 0):
        i = int(np.flatnonzero(d <= 0)[0])
        raise ValueError(
            f"{what} must be strictly increasing; they are not between pulses {i} and {i + 1}"
        )
    angle = ratio * (pulse_angle - pulse_angle[0])
    pchip = PchipInterpolator(tp, angle, extrapolate=False)
    start = max(0, int(np.ceil(tp[0] * fs - 1e-9)))
    stop = min(n, int(np.floor(tp[-1] * fs + 1e-9)) + 1)
    if stop - start < 8:
        raise ValueError(
            f"{what}: the pulses span {max(stop - start, 0)} samples of the record; at least 8 "
            "are needed (pulse times are seconds from the first sample of x)"
        )
    notes = []
    if start > 0 or stop < n:
        notes.append(
            f"samples before the first pulse ({start}) and after the last pulse ({n - stop}) "
            "were left out (no angle reference there)"
        )
    lazy = _PulseAngle(pchip, start, stop - start, fs)
    track = Track(stop - start, interval, t0=t0 + start / fs, fs=fs, angle=lazy)
    label = f"{what} ({ppr} pulses/rev)" + (f", ratio {ratio:.10g}" if ratio != 1.0 else "")
    return ShaftAngle(track, start, stop, ratio, label, tuple(notes), fs)


def shaft_angle(
    signal: Signal,
    *,
    tacho: Any = None,
    pulses_per_rev: Any = None,
    pulse_times: Any = None,
    rpm: Any = None,
    angle: Any = None,
    ratio: Any = 1.0,
    min_rpm: float | None = None,
    block: int = BLOCK_SAMPLES,
) -> ShaftAngle:
    """Checked angle reference of the shaft of interest (see the module docstring).

    Parameters
    ----------
    signal : analysis.inputs.Signal
        The checked signal (gives the number of samples, ``fs`` and the time of sample 0).
    tacho : array_like, optional
        Pulse train, one value per sample of the signal.
    pulses_per_rev : int, optional
        Pulses per revolution of the reference shaft (``tacho`` or ``pulse_times``; default 1).
    pulse_times : array_like, optional
        Pulse instants [s] on the signal's time axis (0 = first sample of a plain array).
    rpm : array_like, optional
        Reference speed [min-1] per sample.
    angle : array_like, optional
        Reference angle [rad] per sample.
    ratio : float, default 1
        Speed of the shaft of interest over the speed of the reference shaft (> 0).
    min_rpm : float, optional
        Standstill threshold of an ``rpm``/``angle`` reference [min-1 of the reference shaft]
        (default 2 % of its highest speed): slower samples at the ends are left out.
    block : int
        Samples between the checkpoints of the angle integration.

    Returns
    -------
    ShaftAngle

    Raises
    ------
    ValueError, TypeError
        None or several references, wrong lengths, NaN, bool or string values, fewer than 3
        pulses, a reference that does not turn.
    """
    require_instance(signal, Signal, "signal")
    given = [k for k, v in {"tacho": tacho, "pulse_times": pulse_times, "rpm": rpm,
                            "angle": angle}.items() if v is not None]  # fmt: skip
    if len(given) != 1:
        raise ValueError(
            "give exactly one reference: tacho= (pulse train) with pulses_per_rev=, pulse_times= "
            f"(s), rpm= (min-1 per sample) or angle= (rad per sample); got {given or 'none'}"
        )
    r = _ratio(ratio)
    n, fs = signal.n, signal.fs
    interval = max(_MIN_INTERVAL, int(block))
    if pulses_per_rev is not None and given[0] not in ("tacho", "pulse_times"):
        raise ValueError("pulses_per_rev= goes with tacho= or pulse_times= only")
    ppr = 1 if pulses_per_rev is None else require_int(pulses_per_rev, "pulses_per_rev", 1)
    if tacho is not None:
        arr = np.asarray(tacho)
        if arr.dtype == bool or not np.issubdtype(arr.dtype, np.number) or np.iscomplexobj(arr):
            raise TypeError(f"tacho must be real numbers; got dtype {arr.dtype}")
        if arr.ndim != 1 or arr.size != n:
            raise ValueError(
                f"sample-count mismatch (x: {n}, tacho: {arr.shape}); tacho must be 1-D, one "
                "value per sample of x"
            )
        sref = from_tacho(arr, fs, ppr, output_time=np.zeros(1))
        # pulse_angles count the pitches, dropped pulses included (repaired by from_tacho)
        return _pulse_reference(
            sref.pulse_times, sref.pulse_angles, ppr, n, fs, r, interval, signal.t0, "tacho"
        )
    if pulse_times is not None:
        arr = np.asarray(pulse_times)
        if arr.dtype == bool or not np.issubdtype(arr.dtype, np.number) or np.iscomplexobj(arr):
            raise TypeError(f"pulse_times must be real numbers (s); got dtype {arr.dtype}")
        if arr.ndim != 1:
            raise ValueError(f"pulse_times must be 1-D; got shape {arr.shape}")
        tp = require_finite(arr, "pulse_times") - signal.t0
        pulse_angle = (2.0 * np.pi / ppr) * np.arange(tp.size)
        return _pulse_reference(
            tp, pulse_angle, ppr, n, fs, r, interval, signal.t0, "pulse_times"
        )
    for name, value in (("rpm", rpm), ("angle", angle)):
        if value is not None:
            dtype = np.asarray(value).dtype if not hasattr(value, "dtype") else value.dtype
            if dtype.kind in "bUSOc":
                raise TypeError(f"{name} must be real numbers; got dtype {dtype}")
    ref = reference_input(rpm, angle, n, required=True)
    assert ref is not None
    a, b, _, note = moving_range(ref, fs, signal.t0, min_rpm)
    if b - a < 8:
        raise ValueError(f"the shaft turns during {b - a} samples only; at least 8 are needed")
    values = ref.values[a:b]
    t0 = signal.t0 + a / fs
    if ref.kind == "rpm":
        check_speed(
            values, b - a,
            "rpm must be > 0 for synchronous averaging (angle strictly increasing); rpm[{i}] "
            "= {value}",
            offset=a,
        )  # fmt: skip
        track = Track(b - a, interval, t0=t0, fs=fs, rpm=_Scaled(values, r))
    else:
        track = Track(b - a, interval, t0=t0, fs=fs, angle=_Scaled(values, r))
    label = _label(ref, r)
    return ShaftAngle(track, a, b, r, label, (note,) if note else (), fs)


def _label(ref: Reference, ratio: float) -> str:
    return ref.label + (f", ratio {ratio:.10g}" if ratio != 1.0 else "")
