"""Frames of rpm maps and order cuts: layout, window length, short-time spectra, block plans.

The shared machinery of :mod:`analysis.maps` and :mod:`analysis.orders`. A *plan* checks the
inputs of a map, fixes its frame layout (window length from the resolution bandwidth, hop
from the overlap) and yields its frames block by block: the time signal itself for an
rpm-frequency map (:class:`FrequencyPlan`), the signal resampled to constant angle for an
rpm-order map (:class:`OrderPlan`, driven by :class:`analysis.resample.AngleResampler`).
:func:`stft_into` transforms a block of frames straight into a preallocated output.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np

from analysis.checks import (
    require_block_size,
    require_choice,
    require_instance,
    require_int,
    require_real_array,
)
from analysis.fft import rfft
from analysis.inputs import Reference, Signal, moving_range, reference_input, signal_input
from analysis.levels import AMPLITUDES, line_factors
from analysis.order_resolution import (
    choose_order_resolution,
    default_frequency_resolution,
    main_lobe_band,
    optional_positive,
    requested_orders,
)
from analysis.resample import Tracking, tracking
from analysis.windows import WindowSpec, get_window, main_lobe_half_width, window_info

__all__ = [
    "BLOCK_ELEMENTS",
    "FrequencyPlan",
    "OrderPlan",
    "Plan",
    "frame_coords",
    "frame_layout",
    "frame_ranges",
    "frequency_plan",
    "order_plan",
    "stft_into",
    "values_at",
    "window_length",
]

BLOCK_ELEMENTS = 1 << 19  # windowed samples per block (4 MB of float64)


def frame_ranges(n_frames: int, seg: int, step: int, block: int) -> Iterator[tuple[int, int]]:
    """Consecutive ranges ``[k0, k1)`` of frames spanning at most ``block`` samples each.

    A range always holds at least one frame, so a frame longer than ``block`` is processed
    alone.
    """
    per = max(1, (block - seg) // step + 1)
    for k0 in range(0, n_frames, per):
        yield k0, min(n_frames, k0 + per)


def frame_coords(
    time: np.ndarray,
    rpm: np.ndarray,
    rpm_long_name: str = "shaft speed (revolutions per minute)",
) -> dict[str, tuple[str, np.ndarray, dict[str, str]]]:
    """CF coordinates of a frame-wise result: ``time`` (frame centres) and ``rpm(time)``."""
    return {
        "time": ("time", time, {"units": "s", "long_name": "frame centre time"}),
        "rpm": ("time", rpm, {"units": "min-1", "long_name": rpm_long_name}),
    }


def stft_into(
    x: np.ndarray,
    w: np.ndarray,
    step: int,
    out: np.ndarray,
    amplitude: str,
    scale: str,
) -> None:
    """Fill ``out[..., frame, line]`` with the scaled short-time spectra of ``x[..., time]``.

    Channel by channel, each exactly as a single channel, and block-wise. ``out`` may hold
    fewer lines than ``len(w) // 2 + 1`` (the first ones are kept).

    ``x`` and ``w`` must be finite real arrays whose product stays below 1e150 per frame
    (its squared spectrum would overflow), ``out`` a float array of shape
    ``(*x.shape[:-1], frames, lines)`` with every frame inside ``x``.
    """
    for name, a in (("x", x), ("w", w), ("out", out)):
        require_instance(a, np.ndarray, name)
    if x.dtype.kind not in "iuf" or w.dtype.kind not in "iuf" or out.dtype.kind != "f":
        raise TypeError(f"x and w must hold real numbers and out floats; got dtypes {x.dtype}, "
                        f"{w.dtype}, {out.dtype}")
    step = require_int(step, "step", 1)
    require_choice(amplitude, AMPLITUDES, "amplitude")
    require_choice(scale, ("linear", "dB"), "scale")
    if w.ndim != 1 or w.size < 2:
        raise ValueError(f"w must be a 1-D window of at least 2 samples; got shape {w.shape}")
    if x.ndim < 1 or out.shape[:-2] != x.shape[:-1] or out.ndim != x.ndim + 1:
        raise ValueError(f"out must have shape (*x.shape[:-1], frames, lines) = "
                         f"({', '.join(map(str, x.shape[:-1]))}{', ' if x.ndim > 1 else ''}"
                         f"frames, lines); got {out.shape} for x of shape {x.shape}")
    n_frames, n_lines = out.shape[-2:]
    if not 1 <= n_lines <= w.size // 2 + 1:
        raise ValueError(f"out has {n_lines} lines; admissible: 1 .. {w.size // 2 + 1} for a "
                         f"window of {w.size} samples")
    if n_frames and (x.shape[-1] < w.size or n_frames > (x.shape[-1] - w.size) // step + 1):
        raise ValueError(f"out has {n_frames} frames; x of {x.shape[-1]} samples holds "
                         f"{max(0, (x.shape[-1] - w.size) // step + 1)} frames of {w.size} "
                         f"samples every {step}")
    top_x = _finite_peak(x, "x")
    top_w = _finite_peak(w, "w")
    if not top_x * top_w * w.size <= 1e150:
        raise ValueError(f"x and w: samples up to {top_x:.3g} times a window up to {top_w:.3g} "
                         "would overflow the squared spectrum; admissible: max|x| max|w| "
                         "len(w) <= 1e150 (check the units)")
    with np.errstate(under="ignore"):
        _stft_into(x, w, step, out, amplitude, scale)


def _finite_peak(a: np.ndarray, name: str) -> float:
    """``max|a|`` of a non-empty array; raise if it holds NaN/inf."""
    if a.size == 0:
        return 0.0
    top = max(float(a.max()), -float(a.min()))  # no temporary array (NaN propagates)
    if not np.isfinite(top):
        raise ValueError(f"{name}: non-finite value (NaN or inf); only finite values are "
                         "admissible")
    return top


def _stft_into(
    x: np.ndarray, w: np.ndarray, step: int, out: np.ndarray, amplitude: str, scale: str
) -> None:
    if x.ndim > 1:
        for ch in np.ndindex(*x.shape[:-1]):
            _stft_into(x[ch], w, step, out[ch], amplitude, scale)
        return
    seg = w.size
    n_lines = out.shape[1]  # may stop below the Nyquist line (an axis ending at max_order)
    frames = np.lib.stride_tricks.sliding_window_view(x, seg)[::step]
    n_frames = out.shape[0]
    s1 = float(w.sum())
    factor = line_factors(out.shape[1], seg) / (s1 * s1)
    peak_gain = np.sqrt(line_factors(out.shape[1], seg))
    block = max(1, BLOCK_ELEMENTS // seg)
    for start in range(0, n_frames, block):
        stop = min(n_frames, start + block)
        spec = rfft(frames[start:stop] * w, axis=-1)[..., :n_lines]
        dst = out[start:stop]
        np.multiply(spec.real, spec.real, out=dst)
        dst += spec.imag * spec.imag
        dst *= factor
        if amplitude != "power":
            np.sqrt(dst, out=dst)
            if amplitude == "peak":
                dst *= peak_gain
        if scale == "dB":
            np.maximum(dst, 1e-40, out=dst)
            np.log10(dst, out=dst)
            dst *= 10.0 if amplitude == "power" else 20.0


def frame_layout(n: int, seg: int, overlap: float) -> tuple[int, int]:
    """Hop and number of frames of ``seg`` samples with ``overlap`` in ``n`` samples."""
    if not 0.0 <= float(overlap) < 1.0:
        raise ValueError(f"overlap = {overlap!r} is not admissible: must be in [0, 1)")
    step = max(1, round(seg * (1.0 - float(overlap))))
    return step, (n - seg) // step + 1


def window_length(window: WindowSpec, rate: float, resolution: float, n: int, name: str) -> int:
    """Window length whose ENBW is ``resolution`` at ``rate`` (at most ``n``)."""
    if not np.isfinite(resolution) or resolution <= 0:
        raise ValueError(f"{name} = {resolution!r} is not admissible: must be finite and > 0")
    enbw = window_info(window, 4096).enbw_bins
    seg = round(enbw * rate / resolution)
    if seg < 4:
        raise ValueError(
            f"{name} = {resolution:g} is too coarse: the window would have {seg} < 4 samples "
            f"(admissible: <= {enbw * rate / 4:.6g})"
        )
    return min(seg, n)  # record too short: one estimate over the whole record (MATLAB)


def values_at(frac_index: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Linear interpolation of ``v`` at fractional indices.

    ``v`` is 1-D with at least two real values (taken as they are: it may be a whole record,
    not scanned here); the indices are finite and within ``[-1, len(v)]`` (the end segments
    are extended by one sample).
    """
    v = require_real_array(v, "v", ndim=1, min_size=2, finite=False)  # O(1): v is long
    frac_index = require_real_array(frac_index, "frac_index", min_size=0)
    if frac_index.size and not (frac_index.min() >= -1.0 and frac_index.max() <= v.size):
        raise ValueError(f"frac_index must lie within [-1, {v.size}] (indices into v); got "
                         f"{frac_index.min():.6g} .. {frac_index.max():.6g}")
    i = np.clip(np.floor(frac_index).astype(np.int64), 0, v.size - 2)
    u = frac_index - i
    return v[i] * (1.0 - u) + v[i + 1] * u


class Plan:
    """Frame layout of a map and its frames, produced block by block.

    Attributes
    ----------
    seg, step, n_frames : int
        Window length, hop and number of frames (in samples of the analysed axis).
    window : WindowSpec
        Window specification.
    info : WindowInfo
        Its figures of merit for ``seg`` samples.
    w : numpy.ndarray
        The window.
    rate : float
        Samples per second (frequency map) or per revolution (order map).
    block : int
        Samples per block (a block always holds at least one frame).
    signal : Signal
        The checked input (channels, units, name).
    reference : str
        Label of the speed reference.
    notes : tuple of str
        What was done beyond the request (standstill left out).
    """

    def __init__(
        self,
        seg: int,
        step: int,
        n_frames: int,
        window: WindowSpec,
        rate: float,
        block: int,
        signal: Signal,
        reference: str = "",
        notes: tuple[str, ...] = (),
    ) -> None:
        self.seg, self.step, self.n_frames = seg, step, n_frames
        self.window = window
        self.info = window_info(window, seg)
        self.w = get_window(window, seg)
        self.rate = rate
        self.block = block
        self.signal = signal
        self.reference = reference
        self.notes = notes

    @property
    def axis(self) -> np.ndarray:
        """Line positions (Hz or orders)."""
        return np.arange(self.seg // 2 + 1) * (self.rate / self.seg)

    def centres(self, k0: int, k1: int) -> np.ndarray:
        """Centres of frames ``[k0, k1)`` as fractional sample indices."""
        return np.arange(k0, k1) * self.step + 0.5 * (self.seg - 1)

    def blocks(self) -> Iterator[tuple[int, int, np.ndarray, np.ndarray, np.ndarray]]:
        """``(k0, k1, samples, time, rpm)`` for consecutive ranges of frames ``[k0, k1)``.

        ``samples`` (shape ``(*channels, n)``) spans frames ``k0 .. k1 - 1``; ``time`` [s]
        and ``rpm`` [min-1] are at their centres.
        """
        raise NotImplementedError


class FrequencyPlan(Plan):
    """Frames of an rpm-frequency map: the time signal itself.

    The speed of a frame is the speed interpolated at its centre (rpm reference) or its mean
    speed, the angle it spans over its duration (angle reference).
    """

    def __init__(
        self,
        signal: Signal,
        ref: Reference,
        seg: int,
        step: int,
        n_frames: int,
        window: WindowSpec,
        block: int,
    ) -> None:
        super().__init__(seg, step, n_frames, window, signal.fs, block, signal, ref.label)
        self.x, self.ref, self.t0 = signal.values, ref, signal.t0

    def frame_speeds(self, k0: int, k1: int) -> tuple[np.ndarray, np.ndarray]:
        """Centre time [s] and speed [min-1] of frames ``[k0, k1)``."""
        centre = self.centres(k0, k1)
        if self.ref.kind == "rpm":
            rpm = values_at(centre, self.ref.values)
        else:
            first = np.arange(k0, k1) * self.step
            th = self.ref.values
            span = np.asarray(th[first + self.seg - 1], float) - np.asarray(th[first], float)
            rpm = span * (self.rate * 60.0 / (2.0 * np.pi * (self.seg - 1)))
        return self.t0 + centre / self.rate, rpm

    def blocks(self) -> Iterator[tuple[int, int, np.ndarray, np.ndarray, np.ndarray]]:
        for k0, k1 in frame_ranges(self.n_frames, self.seg, self.step, self.block):
            samples = self.x[..., k0 * self.step : (k1 - 1) * self.step + self.seg]
            yield k0, k1, samples, *self.frame_speeds(k0, k1)


class OrderPlan(Plan):
    """Frames of an rpm-order map: the signal resampled to constant angle, block by block.

    The speed of a frame is the speed interpolated at its centre time (rpm reference) or, for
    an angle reference, the revolutions over the time they take, symmetric about the frame's
    centre angle and over at most one revolution (which averages out tooth-to-tooth and
    once-per-revolution ripple of a tacho angle).
    """

    def __init__(
        self, tracking: Tracking, seg: int, step: int, n_frames: int, window: WindowSpec,
        block: int, notes: tuple[str, ...] = (),
    ) -> None:  # fmt: skip
        res = tracking.resampler
        super().__init__(
            seg, step, n_frames, window, float(res.samples_per_rev), block, tracking.signal,
            tracking.reference.label, (*tracking.notes, *notes),
        )  # fmt: skip
        self.tracking = tracking
        self.resampler = res
        self.fs, self.t0 = tracking.signal.fs, tracking.t0

    @property
    def axis(self) -> np.ndarray:
        """Line orders up to ``max_order`` (above it the anti-alias filter attenuates)."""
        full = np.arange(self.seg // 2 + 1) * (self.rate / self.seg)
        top = self.resampler.max_order * (1.0 + 1e-9)
        return full[: max(2, int(np.searchsorted(full, top, side="right")))]

    def blocks(self) -> Iterator[tuple[int, int, np.ndarray, np.ndarray, np.ndarray]]:
        m = self.resampler.n_out
        rpm = self.tracking.rpm
        for k0, k1 in frame_ranges(self.n_frames, self.seg, self.step, self.block):
            j0 = k0 * self.step
            samples, times = self.resampler.block(j0, (k1 - 1) * self.step + self.seg)
            centre = self.centres(k0, k1)  # frame-centre time as values_at(centre, times)
            i = np.clip(np.floor(centre).astype(np.int64), 0, m - 2)
            u = centre - i
            tc = times[i - j0] * (1.0 - u) + times[i - j0 + 1] * u
            if rpm is not None:
                speed = values_at((tc - self.t0) * self.fs, rpm)
            else:  # revolutions over time, symmetric about the centre (up to one revolution)
                q = max(1, min((self.seg - 1) // 2, int(self.rate) // 2))
                span = values_at(centre - j0 + q, times) - values_at(centre - j0 - q, times)
                speed = (2 * q / self.rate * 60.0) / span
            yield k0, k1, samples, tc, speed


def frequency_plan(
    x: Any,
    fs: float | None,
    rpm: Any = None,
    *,
    angle: Any = None,
    resolution: float | None = None,
    window: WindowSpec = "hann",
    overlap: float = 0.5,
    time: Any = None,
    axis: int | None = None,
    units: str | None = None,
    name: str | None = None,
    block_size: int | None = None,
    orders: Any = None,
) -> FrequencyPlan:
    """Checked inputs and frame layout of :func:`analysis.maps.rpm_frequency_map`.

    ``resolution`` [Hz] defaults to :func:`analysis.order_resolution.
    default_frequency_resolution` (a quarter of the slowest shaft frequency, or the default
    order resolution of ``orders`` at that speed; frames of at most 1/16 of the record).
    """
    lengths = tuple(np.shape(r)[0] for r in (rpm, angle) if r is not None and np.ndim(r) == 1)
    sig = signal_input(x, fs, time=time, axis=axis, units=units, name=name, lengths=lengths)
    ref = reference_input(rpm, angle, sig.n, required=True, signal=sig)
    assert ref is not None
    if ref.kind == "angle":
        moving_range(ref, sig.fs, sig.t0, 0.0)  # checks the angle never decreases
    block = require_block_size(block_size)
    resolution = optional_positive(resolution, "resolution", "Hz")
    if resolution is None:
        enbw = window_info(window, 4096).enbw_bins  # also checks the window
        f_lo, f_hi, duration = _shaft_hz_range(ref, sig.fs, sig.t0)
        res = default_frequency_resolution(f_lo, f_hi, duration, enbw, requested_orders(orders))
    else:
        res = float(resolution)
    seg = window_length(window, sig.fs, res, sig.n, "resolution")
    step, n_frames = frame_layout(sig.n, seg, overlap)
    return FrequencyPlan(sig, ref, seg, step, n_frames, window, block)


def _revolutions(ref: Reference, fs: float) -> float:
    """Revolutions of the whole record (rectangle rule for a speed), without a copy."""
    if ref.kind == "angle":
        return (float(ref.values[-1]) - float(ref.values[0])) / (2.0 * np.pi)
    total = 0.0
    for a in range(0, ref.values.size, 1 << 20):
        total += float(np.sum(ref.values[a : a + (1 << 20)], dtype=float))
    return total / (60.0 * fs)


def _shaft_hz_range(ref: Reference, fs: float, t0: float) -> tuple[float, float, float]:
    """Slowest and fastest shaft frequency [Hz] of the moving part of a record, and its
    duration [s].

    The moving part leaves out standstill at the ends (below 2 % of the top speed, as order
    tracking does). An angle's speed is taken over 1/100 of that part (averaging out the
    tooth-to-tooth ripple of a tacho angle).
    """
    a, b, _, _ = moving_range(ref, fs, t0, None)
    if ref.kind == "rpm":
        v = np.asarray(ref.values[a:b], dtype=float)
        low, high = float(np.min(v)) / 60.0, float(np.max(v)) / 60.0
    else:
        step = max(1, (b - a) // 100)
        th = np.asarray(ref.values[np.arange(a, b, step)], dtype=float)
        if th.size < 2:
            low = high = (float(ref.values[b - 1]) - float(ref.values[a])) * fs / max(b - 1 - a, 1)
        else:
            d = np.diff(th) * (fs / step)
            low, high = float(np.min(d)), float(np.max(d))
        low, high = low / (2.0 * np.pi), high / (2.0 * np.pi)
    return max(low, 0.0), max(high, 0.0), (b - a) / fs


def order_plan(
    x: Any,
    fs: float | None,
    rpm: Any = None,
    *,
    angle: Any = None,
    resolution: float | None = None,
    window: WindowSpec = "flattop",
    overlap: float = 0.5,
    samples_per_rev: int | None = None,
    max_order: float | None = None,
    time: Any = None,
    axis: int | None = None,
    min_rpm: float | None = None,
    units: str | None = None,
    name: str | None = None,
    block_size: int | None = None,
    orders: Any = None,
    band: float | None = None,
) -> OrderPlan:
    """Checked inputs, angular resampler and frame layout of :func:`analysis.maps.rpm_order_map`.

    ``resolution`` [orders] defaults to :func:`analysis.order_resolution.
    default_order_resolution` of ``orders`` and ``max_order``, coarsened on a short record
    (:func:`analysis.order_resolution.choose_order_resolution`). With ``band`` (order cuts:
    the band width in orders, or ``0`` for the default main lobe) and neither
    ``max_order`` nor ``samples_per_rev`` given, ``max_order`` is
    ``1.25 (max(orders) + band / 2)``, so that the bands lie where the resampling is flat
    (lowered to the highest alias-free order where ``fs`` does not reach it).
    Given ``max_order`` only, ``samples_per_rev`` is ``2 ceil(1.28 max_order)``.
    """
    lengths = tuple(np.shape(r)[0] for r in (rpm, angle) if r is not None and np.ndim(r) == 1)
    sig = signal_input(x, fs, time=time, axis=axis, units=units, name=name, lengths=lengths)
    ref = reference_input(rpm, angle, sig.n, required=True, signal=sig)
    assert ref is not None
    block = require_block_size(block_size)
    ords = requested_orders(orders)
    resolution = optional_positive(resolution, "resolution", "orders")
    enbw = window_info(window, 4096).enbw_bins  # also checks the window before the work
    wanted = None
    if band is not None and ords is not None and max_order is None and samples_per_rev is None:
        res0, _ = choose_order_resolution(resolution, ords, None, _revolutions(ref, sig.fs), enbw)
        lobe = main_lobe_band(main_lobe_half_width(window), res0 / enbw)
        wanted = 1.25 * (float(ords.max()) + 0.5 * (band if band > 0 else lobe))
    tr = tracking(
        sig, ref, samples_per_rev, max_order, block, min_rpm, compact=True,
        max_order_wanted=wanted,
    )  # fmt: skip
    spr = tr.resampler.samples_per_rev
    m = tr.resampler.n_out
    # max_order / 64 refines the default for a low max_order chosen by the user (a zoom), not
    # for the one derived from the orders of a cut
    res, note = choose_order_resolution(
        resolution, ords, None if wanted is not None else tr.resampler.max_order, m / spr, enbw
    )
    seg = window_length(window, float(spr), res, m, "resolution")
    step, n_frames = frame_layout(m, seg, overlap)
    return OrderPlan(tr, seg, step, n_frames, window, block, (note,) if note else ())
