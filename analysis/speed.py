"""Speed reference: shaft angle and speed from an rpm trace, an angle trace or a tacho signal.

All order-analysis tools need one speed reference per shaft: the rotation angle
:math:`\\theta(t)` [rad] and speed :math:`n(t) = 60\\,\\dot\\theta/(2\\pi)` [min-1] on the time base
of the vibration channels. :class:`SpeedReference` holds them; it is built by

* :func:`from_rpm` -- integrate a speed trace (e.g. a simulated run-up or a measured rpm channel);
* :func:`from_angle` -- differentiate an angle trace (encoder, simulation state);
* :func:`from_tacho` -- process a pulse train (once-per-rev key-phasor, toothed wheel, 60-2
  crank wheel): Schmitt-trigger rising edges with sub-sample crossing times, missing-tooth
  reference detection, repair of dropped and extra pulses, and a monotone cubic (PCHIP)
  interpolation of the pulse angles.

The processing follows the textbook tacho-to-rpm chain (Brandt, *Noise and Vibration Analysis*,
Wiley 2011, ch. 12) with the missing-pulse/missing-tooth handling that NVH suites expose
(Simcenter Testlab KB "Measuring RPM: Missing Pulses").
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import xarray as xr
from scipy.interpolate import CubicSpline, PchipInterpolator, make_lsq_spline
from scipy.ndimage import median_filter

from analysis.cf import cf_dataset, time_attrs
from analysis.checks import (
    require_finite,
    require_monotonic,
    require_positive,
    require_real_array,
)

__all__ = ["SpeedAccuracy", "SpeedReference", "from_angle", "from_rpm", "from_tacho"]

_RAD_PER_S_TO_RPM = 60.0 / (2.0 * np.pi)
_SHORT = 0.5  # an interval below this fraction of nominal is caused by an extra pulse


@dataclass(frozen=True)
class SpeedAccuracy:
    """Diagnostics and estimated accuracy of a speed reference.

    Attributes
    ----------
    rms_angle_error_rad : float
        Estimated rms angle error [rad]: ``hypot(timing_rad, fit_residual_rad)``.
    timing_rad : float
        Rms angle error caused by pulse-timing scatter (sampling quantisation of the edge
        times, noise, tooth pitch errors), estimated from the third differences of the
        pulse times (white jitter of rms s gives third differences of rms s*sqrt(20)),
        converted to angle with the local speed. 0 for :func:`from_angle`.
    fit_residual_rad : float
        Rms difference between the PCHIP curve used and a not-a-knot cubic spline through the
        same points, at the interval midpoints: an estimate of the interpolation (or
        integration, for :func:`from_rpm`) error.
    n_pulses : int
        Rising edges detected (tacho only).
    n_inserted : int
        Pulses filled in for dropped pulses.
    n_removed : int
        Extra (glitch) pulses removed.
    n_reference_gaps : int
        Missing-tooth reference gaps found.
    """

    rms_angle_error_rad: float
    timing_rad: float = 0.0
    fit_residual_rad: float = 0.0
    n_pulses: int = 0
    n_inserted: int = 0
    n_removed: int = 0
    n_reference_gaps: int = 0


@dataclass
class SpeedReference:
    """Angle and speed of one shaft on a time base.

    Attributes
    ----------
    time : ndarray
        Time [s].
    angle : ndarray
        Rotation angle [rad], non-decreasing for rotation in one direction.
    rpm : ndarray
        Speed [min-1] (revolutions per minute).
    accuracy : SpeedAccuracy
        Estimated accuracy and processing diagnostics.
    method : str
        ``"rpm"``, ``"angle"`` or ``"tacho"``.
    pulse_times : ndarray
        Pulse times [s] after repair (tacho only; empty otherwise).
    pulse_angles : ndarray
        Angle [rad] assigned to each pulse in ``pulse_times``.
    """

    time: np.ndarray
    angle: np.ndarray
    rpm: np.ndarray
    accuracy: SpeedAccuracy
    method: str
    pulse_times: np.ndarray = field(default_factory=lambda: np.empty(0))
    pulse_angles: np.ndarray = field(default_factory=lambda: np.empty(0))

    def to_dataset(self) -> xr.Dataset:
        """Return a Dataset with ``angle`` (units ``rad``) and ``rpm`` (units ``min-1``) along
        ``time`` (units ``s``); accuracy figures become global attributes."""
        attrs: dict[str, object] = {
            "Conventions": "CF-1.11",
            "history": f"speed reference from {self.method} by analysis.speed",
            "speed_method": self.method,
        }
        attrs.update({f"speed_{k}": v for k, v in asdict(self.accuracy).items()})
        ds = xr.Dataset(
            {
                "angle": (
                    "time",
                    self.angle,
                    {"units": "rad", "long_name": "shaft rotation angle"},
                ),
                "rpm": (
                    "time",
                    self.rpm,
                    {"units": "min-1", "long_name": "shaft speed (revolutions per minute)"},
                ),
            },
            coords={"time": ("time", self.time, time_attrs("time"))},
            attrs=attrs,
        )
        return cf_dataset(
            ds, title=f"shaft speed reference ({self.method})",
            producer="analysis.speed"
        )


# ----------------------------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------------------------


def _fit_residual(t: np.ndarray, y: np.ndarray) -> float:
    """Rms difference PCHIP vs not-a-knot cubic spline at interval midpoints."""
    if t.size < 4:
        return 0.0
    mid = 0.5 * (t[1:] + t[:-1])
    return float(np.sqrt(np.mean((PchipInterpolator(t, y)(mid) - CubicSpline(t, y)(mid)) ** 2)))


def _evaluate(t_knots: np.ndarray, angle: np.ndarray, t_out: np.ndarray):
    """Angle and rpm at ``t_out``: PCHIP inside the knots, constant speed outside."""
    pchip = PchipInterpolator(t_knots, angle, extrapolate=False)
    dpchip = pchip.derivative()
    ang = pchip(t_out)
    om = dpchip(t_out)
    t0, t1 = t_knots[0], t_knots[-1]
    om0, om1 = float(dpchip(t0)), float(dpchip(t1))
    before, after = t_out < t0, t_out > t1
    ang[before] = angle[0] + om0 * (t_out[before] - t0)
    om[before] = om0
    ang[after] = angle[-1] + om1 * (t_out[after] - t1)
    om[after] = om1
    return ang, om * _RAD_PER_S_TO_RPM


def _smooth_rpm(tp: np.ndarray, angle: np.ndarray, t_out: np.ndarray, every: int) -> np.ndarray:
    """Rpm from a least-squares cubic spline through the pulse angles, a knot every ``every``
    pulses; constant speed outside the pulses (as the angle)."""
    inner = tp[every:-every:every] if tp.size > 2 * every else tp[:0]
    inner = inner[(inner > tp[0]) & (inner < tp[-1])]
    knots = np.concatenate([np.repeat(tp[0], 4), inner, np.repeat(tp[-1], 4)])
    if tp.size < knots.size - 4:  # too few pulses for the knots: one cubic
        knots = np.concatenate([np.repeat(tp[0], 4), np.repeat(tp[-1], 4)])
    spline = make_lsq_spline(tp, angle, knots, k=3)
    d = spline.derivative()
    om = d(np.clip(t_out, tp[0], tp[-1]))
    return om * _RAD_PER_S_TO_RPM


#: Largest magnitude of a time [s], a speed [min-1] and an angle [rad] :func:`from_rpm` and
#: :func:`from_angle` take (their interpolants' powers and products stay within float64).
MAX_TIME_S, MAX_RPM, MAX_ANGLE_RAD = 1e12, 1e12, 1e100
#: Shortest time step [s] they take (a sample rate above 1 THz is a unit error).
MIN_STEP_S = 1e-12


def _check_time(time: Any, name: str = "time") -> np.ndarray:
    t = require_real_array(time, name, ndim=1, max_abs=MAX_TIME_S)
    if t.size < 2:
        raise ValueError(f"{name}: needs a 1-D axis with at least two samples")
    t = require_monotonic(t, name, strict=True)
    step = float(np.min(np.diff(t)))
    if step < MIN_STEP_S:
        raise ValueError(f"{name}: a step of {step:.3g} s, below {MIN_STEP_S:g} s (a sample rate "
                         "above 1 THz); check the units")
    return t


# ----------------------------------------------------------------------------------------------
# rpm and angle traces
# ----------------------------------------------------------------------------------------------


def from_rpm(time: np.ndarray, rpm: np.ndarray) -> SpeedReference:
    """Speed reference from a speed trace, integrated to angle.

    Parameters
    ----------
    time : array_like
        Strictly increasing time [s].
    rpm : array_like
        Speed [min-1] at ``time``.

    Returns
    -------
    SpeedReference
        ``angle`` starts at 0 rad and is the exact integral of the PCHIP interpolant of the
        angular speed :math:`\\omega = 2\\pi\\,n/60`.

    Raises
    ------
    ValueError
        Non-increasing time, NaN, unequal lengths.
    """
    t = _check_time(time)
    n = require_real_array(rpm, "rpm", max_abs=MAX_RPM)
    if n.shape != t.shape:
        raise ValueError(f"rpm has shape {n.shape}, time has {t.shape}; they must match")
    omega = n / _RAD_PER_S_TO_RPM
    angle = PchipInterpolator(t, omega).antiderivative()(t)
    trap = np.concatenate([[0.0], np.cumsum(0.5 * (omega[1:] + omega[:-1]) * np.diff(t))])
    resid = float(np.sqrt(np.mean((angle - trap) ** 2)))
    acc = SpeedAccuracy(rms_angle_error_rad=resid, fit_residual_rad=resid)
    return SpeedReference(t, angle, n.copy(), acc, "rpm")


def from_angle(time: np.ndarray, angle: np.ndarray) -> SpeedReference:
    """Speed reference from an angle trace (encoder, simulation), differentiated to rpm.

    Parameters
    ----------
    time : array_like
        Strictly increasing time [s].
    angle : array_like
        Rotation angle [rad]; must be non-decreasing (rotation in one direction, as in a run-up
        or coast-down). Unwrap a wrapped encoder angle first (``numpy.unwrap``).

    Returns
    -------
    SpeedReference
        ``rpm`` is the derivative of the PCHIP interpolant of the angle (non-negative).

    Raises
    ------
    ValueError
        Decreasing angle (naming the first sample where it decreases), NaN, unequal lengths.
    """
    t = _check_time(time)
    a = require_real_array(angle, "angle", max_abs=MAX_ANGLE_RAD)
    if a.shape != t.shape:
        raise ValueError(f"angle has shape {a.shape}, time has {t.shape}; they must match")
    dec = np.flatnonzero(np.diff(a) < 0)
    if dec.size:
        i = int(dec[0])
        raise ValueError(
            f"angle must be non-decreasing (rotation in one direction); it decreases from "
            f"{a[i]:.6g} rad to {a[i + 1]:.6g} rad between samples {i} and {i + 1} "
            f"(t = {t[i]:.6g} s); unwrap a wrapped angle with numpy.unwrap, or negate it for "
            "reverse rotation"
        )
    rpm = PchipInterpolator(t, a).derivative()(t) * _RAD_PER_S_TO_RPM
    resid = _fit_residual(t, a)
    acc = SpeedAccuracy(rms_angle_error_rad=resid, fit_residual_rad=resid)
    return SpeedReference(t, a.copy(), rpm, acc, "angle")


# ----------------------------------------------------------------------------------------------
# tacho processing
# ----------------------------------------------------------------------------------------------


def _state_levels(x: np.ndarray) -> tuple[float, float]:
    """Low and high state levels: modes of the lower and upper half of the histogram."""
    lo, hi = float(np.min(x)), float(np.max(x))
    if not hi - lo > 1e-12 * max(1.0, abs(hi), abs(lo)):
        raise ValueError(
            f"tacho signal: no pulses detected, the signal is flat (all samples = {lo:.6g})"
        )
    counts, edges = np.histogram(x, bins=100, range=(lo, hi))
    centres = 0.5 * (edges[1:] + edges[:-1])
    return float(centres[np.argmax(counts[:50])]), float(centres[50 + np.argmax(counts[50:])])


def _rising_edges(
    x: np.ndarray, fs: float, level: float, hysteresis: float, block: int = 1 << 18
) -> np.ndarray:
    """Times [s] of rising edges by a Schmitt trigger, crossing of ``level`` interpolated.

    Works through the signal in blocks of ``block`` samples (the trigger state and the last
    crossing carried from block to block), so that its working memory does not grow with the
    record; the edges equal those of a single pass over the whole signal.
    """
    upper, lower = level + 0.5 * hysteresis, level - 0.5 * hysteresis
    n = x.size
    out: list[np.ndarray] = []
    prev_high: bool | None = None  # state of the last event (sample outside the band) so far
    last_cross = -1  # last sample c with x[c - 1] < level <= x[c] so far
    for s in range(0, n, block):
        e = min(n, s + block)
        seg = x[s:e]
        lo = max(0, s - 1)
        w = x[lo:e]
        cross = np.flatnonzero((w[:-1] < level) & (w[1:] >= level)) + (lo + 1)
        ev = np.flatnonzero((seg >= upper) | (seg <= lower))
        if ev.size:
            high = seg[ev] >= upper
            before = np.empty_like(high)
            before[1:] = high[:-1]
            before[0] = high[0] if prev_high is None else prev_high  # no edge at the first
            trig = ev[np.flatnonzero(high & ~before)] + s  # first sample >= upper after a low
            prev_high = bool(high[-1])
            if trig.size:
                known = cross if last_cross < 0 else np.concatenate([[last_cross], cross])
                c = known[np.searchsorted(known, trig, side="right") - 1]
                frac = (level - x[c - 1]) / (x[c] - x[c - 1])
                out.append((c - 1 + frac) / fs)
        if cross.size:
            last_cross = int(cross[-1])
    return np.concatenate(out) if out else np.empty(0)


def _nominal(d: np.ndarray) -> np.ndarray:
    """Local nominal pulse interval: running median of the intervals."""
    size = int(min(max(5, 2 * (d.size // 20) + 1), 15))
    return (
        median_filter(d, size=size, mode="nearest")
        if d.size >= 3
        else np.full_like(d, np.median(d))
    )


def _remove_extra(tp: np.ndarray) -> tuple[np.ndarray, int]:
    """Remove pulses that split a nominal interval into short ones (glitches, double triggers)."""
    removed = 0
    for _ in range(50):
        if tp.size < 4:
            break
        d = np.diff(tp)
        nom = _nominal(d)
        short = np.flatnonzero(d < _SHORT * nom)
        if short.size == 0:
            break
        keep = np.ones(tp.size, dtype=bool)
        last = -3
        for i in short.tolist():
            if i <= last + 2:  # neighbours changed in this pass; decide in the next one
                continue
            scores: list[float] = []
            for j in (i, i + 1):
                if j == 0 or j == tp.size - 1:
                    scores.append(0.25)
                    continue
                r = (tp[j + 1] - tp[j - 1]) / nom[min(i, nom.size - 1)]
                scores.append(abs(r - max(1.0, np.round(r))))
            keep[i + int(np.argmin(scores))] = False
            last = i
        removed += int((~keep).sum())
        tp = tp[keep]
    return tp, removed


def _timing_error(tp: np.ndarray, pos: np.ndarray, omega_p: np.ndarray) -> float:
    """Rms angle error from timing scatter, via third differences on runs of single pitches."""
    if tp.size < 5:
        return 0.0
    single = np.diff(pos) == 1
    ok = single[:-2] & single[1:-1] & single[2:]
    d3 = np.diff(tp, 3)[ok]
    if d3.size < 3:
        return 0.0
    sigma_t = 1.4826 * np.median(np.abs(d3 - np.median(d3))) / np.sqrt(20.0)
    return float(sigma_t * np.sqrt(np.mean(omega_p**2)))


def from_tacho(
    signal: np.ndarray,
    fs: float,
    pulses_per_rev: int = 1,
    *,
    level: float | None = None,
    hysteresis: float | None = None,
    missing_teeth: int = 0,
    repair: bool = True,
    output_time: np.ndarray | None = None,
    rpm_smoothing: int | None = None,
) -> SpeedReference:
    """Speed reference from a tacho pulse train.

    Parameters
    ----------
    signal : array_like
        Tacho samples (any unit), uniformly sampled.
    fs : float
        Sample rate [Hz].
    pulses_per_rev : int, optional
        Pulse positions per revolution *including* missing teeth (60 for a 60-2 wheel).
    level : float, optional
        Trigger level; default midway between the low and high state levels, which are the
        modes of the lower and upper half of the amplitude histogram.
    hysteresis : float, optional
        Width of the Schmitt-trigger band around ``level`` (the edge is armed below
        ``level - hysteresis/2`` and fires above ``level + hysteresis/2``); default 10 % of the
        distance between the state levels. Noise smaller than the band cannot double-trigger.
    missing_teeth : int, optional
        Missing teeth of the reference gap (2 for a 60-2 wheel). A gap of
        ``missing_teeth + 1`` nominal intervals, once per revolution, marks the reference: the
        first tooth after the gap gets angle :math:`2\\pi k`.
    repair : bool, optional
        Repair dropped pulses (an interval of about k nominal intervals counts k pitches, i.e.
        k - 1 pulses are filled in) and remove extra pulses (an interval shorter than half the
        nominal one; of its two pulses, the one whose removal leaves an interval closest to a
        whole number of pitches is removed). Default True.
    output_time : array_like, optional
        Time base [s] of the result; default the signal's samples, ``arange(n) / fs``.
    rpm_smoothing : int, optional
        Pulses per interval of the smoothing spline of the rpm (see Returns); default
        ``max(4, pulses_per_rev)``, one knot per revolution; 1 gives the plain derivative
        of the angle (the rpm before smoothing existed).

    Returns
    -------
    SpeedReference
        Angle: PCHIP through the pulse angles :math:`2\\pi\\,\\mathrm{count}/\\mathrm{ppr}`, with
        constant-speed extrapolation before the first and after the last pulse; exact at the
        pulses, it is the reference to give order analysis (``angle=``). Rpm: the derivative
        of a least-squares cubic spline through the pulse angles with a knot every
        ``rpm_smoothing`` pulses. The derivative of the angle itself carries the pulse-timing
        scatter and tooth pitch errors as a tooth-to-tooth ripple of the rpm (about 0.5 % in
        the tests at 60 pulses per revolution); the least-squares spline averages them over
        the knot interval. Without a missing-tooth reference, the first pulse has angle 0.

    Raises
    ------
    ValueError
        Flat signal or fewer than three pulses detected (with the level used), a missing-tooth
        gap that is never found, inadmissible parameters.

    Notes
    -----
    The edge time is the linear interpolation of the ``level`` crossing between the two
    samples around it, which removes most of the sampling quantisation (a sampled step
    would otherwise scatter by :math:`1/(\\sqrt{12}\\,f_s)`). The interpolation error between
    pulses is small when there are many pulses per revolution; with one pulse per
    revolution, prefer a toothed wheel for strongly accelerating run-ups.
    """
    x = require_finite(signal, "signal")
    if x.ndim != 1:
        raise ValueError(f"signal must be 1-D, got shape {x.shape}")
    fs = require_positive(fs, "fs")
    ppr = int(pulses_per_rev)
    if ppr != pulses_per_rev or ppr < 1:
        raise ValueError(f"pulses_per_rev = {pulses_per_rev!r}: must be an integer >= 1")
    m = int(missing_teeth)
    if m != missing_teeth or m < 0 or (m > 0 and m >= ppr - 1):
        raise ValueError(
            f"missing_teeth = {missing_teeth!r}: must be 0 or an integer with "
            f"1 <= missing_teeth < pulses_per_rev - 1 = {ppr - 1}"
        )
    low, high = _state_levels(x)
    lvl = 0.5 * (low + high) if level is None else float(level)
    hyst = (
        0.1 * (high - low)
        if hysteresis is None
        else require_positive(hysteresis, "hysteresis", allow_zero=True)
    )
    tp = _rising_edges(x, fs, lvl, hyst)
    n_detected = tp.size
    if tp.size < 3:
        raise ValueError(
            f"tacho signal: no pulses detected ({tp.size} rising edge(s) through level "
            f"{lvl:.6g} with hysteresis {hyst:.6g}; state levels {low:.6g} / {high:.6g}); "
            "check level= and hysteresis=, at least 3 pulses are needed"
        )
    removed = 0
    if repair:
        tp, removed = _remove_extra(tp)
    d = np.diff(tp)
    r = d / _nominal(d)
    k = np.maximum(1, np.round(r)).astype(np.int64) if repair else np.ones(d.size, np.int64)
    n_gaps = 0
    offset = 0
    if m:
        cand = np.abs(r - (m + 1)) < 0.5
        if not repair:
            k[cand] = m + 1
        pos = np.concatenate([[0], np.cumsum(k)])
        if not cand.any():
            raise ValueError(
                f"missing_teeth = {m}: no gap of {m + 1} pulse intervals found among "
                f"{tp.size} pulses; check pulses_per_rev and missing_teeth"
            )
        phases = pos[1:][cand] % ppr
        phi = int(np.bincount(phases, minlength=ppr).argmax())
        # intervals that span a reference gap contain a tooth position = phi (mod ppr)
        spans = (pos[1:] - phi) // ppr - (pos[:-1] - phi) // ppr
        n_gaps = int(spans.sum())
        offset = (ppr - phi) % ppr
        inserted = int((k - 1).sum() - m * n_gaps)
    else:
        pos = np.concatenate([[0], np.cumsum(k)])
        inserted = int((k - 1).sum())
    pulse_angle = 2.0 * np.pi * (pos + offset) / ppr
    t_out = (
        np.arange(x.size) / fs
        if output_time is None
        else require_finite(output_time, "output_time").ravel()
    )
    angle, rpm = _evaluate(tp, pulse_angle, t_out)
    if rpm_smoothing is None:
        k = max(4, ppr)
    elif isinstance(rpm_smoothing, bool) or not isinstance(rpm_smoothing, int | np.integer) or (
        rpm_smoothing < 1
    ):
        raise ValueError(f"rpm_smoothing = {rpm_smoothing!r}: must be an integer >= 1 (pulses)")
    else:
        k = int(rpm_smoothing)
    if k > 1:
        rpm = _smooth_rpm(tp, pulse_angle, t_out, k)
    omega_p = PchipInterpolator(tp, pulse_angle).derivative()(tp)
    timing = _timing_error(tp, pos, omega_p)
    resid = _fit_residual(tp, pulse_angle)
    acc = SpeedAccuracy(
        rms_angle_error_rad=float(np.hypot(timing, resid)),
        timing_rad=timing,
        fit_residual_rad=resid,
        n_pulses=int(n_detected),
        n_inserted=inserted,
        n_removed=int(removed),
        n_reference_gaps=n_gaps,
    )
    return SpeedReference(t_out, angle, rpm, acc, "tacho", tp, pulse_angle)
