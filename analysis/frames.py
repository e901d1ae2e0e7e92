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
    BLOCK_SAMPLES,
    require_block_size,
    require_finite_blocks,
    uniform_rate,
)
from analysis.fft import rfft
from analysis.levels import line_factors
from analysis.resample import AngleResampler, speed_resampler
from analysis.windows import WindowSpec, get_window, window_info

__all__ = [
    "BLOCK_ELEMENTS",
    "FrequencyPlan",
    "OrderPlan",
    "Plan",
    "check_speed",
    "frame_coords",
    "frame_layout",
    "frame_ranges",
    "frequency_plan",
    "order_plan",
    "rate_and_start",
    "signal_1d",
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


def check_speed(rpm: Any, n: int, message: str | None = None) -> np.ndarray:
    """``rpm`` as an array of ``n`` finite values, checked block-wise (no copy).

    With ``message`` (formatted with ``i`` and ``value``) every value must also be > 0.
    """
    r = np.asarray(rpm)
    if r.ndim != 1 or r.size != n:
        raise ValueError(
            f"sample-count mismatch (x: {n}, rpm: {r.size}); rpm must be 1-D, one value per "
            "sample of x"
        )
    require_finite_blocks(r, "rpm")
    if message is None:
        return r
    for a in range(0, n, BLOCK_SAMPLES):
        bad = np.flatnonzero(r[a : a + BLOCK_SAMPLES] <= 0)
        if bad.size:
            i = a + int(bad[0])
            raise ValueError(message.format(i=i, value=r[i]))
    return r


def stft_into(
    x: np.ndarray,
    w: np.ndarray,
    step: int,
    out: np.ndarray,
    amplitude: str,
    scale: str,
) -> None:
    """Fill ``out[frame, line]`` with the scaled short-time spectrum of 1-D ``x``, block-wise."""
    seg = w.size
    frames = np.lib.stride_tricks.sliding_window_view(x, seg)[::step]
    n_frames = out.shape[0]
    s1 = float(w.sum())
    factor = line_factors(out.shape[1], seg) / (s1 * s1)
    peak_gain = np.sqrt(line_factors(out.shape[1], seg))
    block = max(1, BLOCK_ELEMENTS // seg)
    for start in range(0, n_frames, block):
        stop = min(n_frames, start + block)
        spec = rfft(frames[start:stop] * w, axis=-1)
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
    if not 0.0 <= float(overlap) < 1.0:
        raise ValueError(f"overlap = {overlap!r} is not admissible: must be in [0, 1)")
    step = max(1, round(seg * (1.0 - float(overlap))))
    return step, (n - seg) // step + 1


def window_length(window: WindowSpec, rate: float, resolution: float, n: int, name: str) -> int:
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


def signal_1d(x: Any, name: str) -> np.ndarray:
    arr = np.asarray(x)
    if np.iscomplexobj(arr) or not np.issubdtype(arr.dtype, np.number):
        raise ValueError(f"{name} must be a real numeric array; got dtype {arr.dtype}")
    if arr.ndim != 1:
        raise ValueError(f"{name} must be 1-D (one channel); got shape {arr.shape}")
    require_finite_blocks(arr, name)
    return arr


def rate_and_start(fs: float | None, time: Any, n: int) -> tuple[float, float]:
    """Sample rate and start time from ``fs`` and/or ``time`` (checked against each other)."""
    if time is None:
        if fs is None:
            raise ValueError("fs (Hz, > 0) or time (s) is required")
        fs = float(fs)
        if not np.isfinite(fs) or fs <= 0:
            raise ValueError(f"fs = {fs!r} is not admissible: must be finite and > 0 Hz")
        return fs, 0.0
    t = np.asarray(time)
    if t.ndim != 1 or t.size != n:
        raise ValueError(f"sample-count mismatch (x: {n}, time: {t.size})")
    fs_t = uniform_rate(t, "time")
    if fs is not None and abs(float(fs) - fs_t) > 1e-6 * fs_t:
        raise ValueError(
            f"sample-rate mismatch: fs = {fs!r} Hz but the time axis gives {fs_t:.9g} Hz"
        )
    return fs_t, float(t[0])


def values_at(frac_index: np.ndarray, v: np.ndarray) -> np.ndarray:
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
    """

    def __init__(
        self, seg: int, step: int, n_frames: int, window: WindowSpec, rate: float, block: int
    ) -> None:
        self.seg, self.step, self.n_frames = seg, step, n_frames
        self.window = window
        self.info = window_info(window, seg)
        self.w = get_window(window, seg)
        self.rate = rate
        self.block = block

    @property
    def axis(self) -> np.ndarray:
        """Line positions (Hz or orders)."""
        return np.arange(self.seg // 2 + 1) * (self.rate / self.seg)

    def centres(self, k0: int, k1: int) -> np.ndarray:
        """Centres of frames ``[k0, k1)`` as fractional sample indices."""
        return np.arange(k0, k1) * self.step + 0.5 * (self.seg - 1)

    def blocks(self) -> Iterator[tuple[int, int, np.ndarray, np.ndarray, np.ndarray]]:
        """``(k0, k1, samples, time, rpm)`` for consecutive ranges of frames ``[k0, k1)``.

        ``samples`` spans frames ``k0 .. k1 - 1``; ``time`` [s] and ``rpm`` [min-1] are at
        their centres.
        """
        raise NotImplementedError


class FrequencyPlan(Plan):
    """Frames of an rpm-frequency map: the time signal itself."""

    def __init__(
        self,
        x: np.ndarray,
        rpm: np.ndarray,
        fs: float,
        t0: float,
        seg: int,
        step: int,
        n_frames: int,
        window: WindowSpec,
        block: int,
    ) -> None:
        super().__init__(seg, step, n_frames, window, fs, block)
        self.x, self.rpm, self.t0 = x, rpm, t0

    def blocks(self) -> Iterator[tuple[int, int, np.ndarray, np.ndarray, np.ndarray]]:
        for k0, k1 in frame_ranges(self.n_frames, self.seg, self.step, self.block):
            centre = self.centres(k0, k1)
            samples = self.x[k0 * self.step : (k1 - 1) * self.step + self.seg]
            yield k0, k1, samples, self.t0 + centre / self.rate, values_at(centre, self.rpm)


class OrderPlan(Plan):
    """Frames of an rpm-order map: the signal resampled to constant angle, block by block."""

    def __init__(
        self,
        resampler: AngleResampler,
        rpm: np.ndarray,
        fs: float,
        t0: float,
        seg: int,
        step: int,
        n_frames: int,
        window: WindowSpec,
        block: int,
    ) -> None:
        super().__init__(seg, step, n_frames, window, float(resampler.samples_per_rev), block)
        self.resampler, self.rpm, self.fs, self.t0 = resampler, rpm, fs, t0

    def _speed_at(self, tc: np.ndarray) -> np.ndarray:
        """Speed at the instants ``tc``, interpolated linearly between samples."""
        return values_at((tc - self.t0) * self.fs, self.rpm)

    def blocks(self) -> Iterator[tuple[int, int, np.ndarray, np.ndarray, np.ndarray]]:
        m = self.resampler.n_out
        for k0, k1 in frame_ranges(self.n_frames, self.seg, self.step, self.block):
            j0 = k0 * self.step
            samples, times = self.resampler.block(j0, (k1 - 1) * self.step + self.seg)
            centre = self.centres(k0, k1)  # frame-centre time as values_at(centre, times)
            i = np.clip(np.floor(centre).astype(np.int64), 0, m - 2)
            u = centre - i
            tc = times[i - j0] * (1.0 - u) + times[i - j0 + 1] * u
            yield k0, k1, samples, tc, self._speed_at(tc)


def frequency_plan(
    x: Any,
    fs: float | None,
    rpm: Any,
    *,
    resolution: float | None = None,
    window: WindowSpec = "hann",
    overlap: float = 0.5,
    time: Any = None,
    name: str = "x",
    block_size: int | None = None,
) -> FrequencyPlan:
    """Checked inputs and frame layout of :func:`rpm_frequency_map`."""
    arr = signal_1d(x, name)
    n = arr.size
    r = check_speed(rpm, n)
    rate, t0 = rate_and_start(fs, time, n)
    block = require_block_size(block_size)
    res = rate / 128.0 if resolution is None else float(resolution)
    seg = window_length(window, rate, res, n, "resolution")
    step, n_frames = frame_layout(n, seg, overlap)
    return FrequencyPlan(arr, r, rate, t0, seg, step, n_frames, window, block)


def order_plan(
    x: Any,
    fs: float | None,
    rpm: Any,
    *,
    resolution: float | None = None,
    window: WindowSpec = "flattop",
    overlap: float = 0.5,
    samples_per_rev: int | None = None,
    max_order: float | None = None,
    time: Any = None,
    name: str = "x",
    block_size: int | None = None,
) -> OrderPlan:
    """Checked inputs, angular resampler and frame layout of :func:`rpm_order_map`."""
    arr = signal_1d(x, name)
    n = arr.size
    r = check_speed(
        rpm,
        n,
        "rpm must be > 0 for order tracking (angle strictly increasing); rpm[{i}] = {value}",
    )
    rate, t0 = rate_and_start(fs, time, n)
    if n < 8:
        raise ValueError(f"{name}: needs at least 8 samples for angular resampling")
    block = require_block_size(block_size)
    resampler = speed_resampler(arr, r, samples_per_rev, max_order, block, fs=rate, t0=t0)
    spr = resampler.samples_per_rev
    res = spr / 256.0 if resolution is None else float(resolution)
    m = resampler.n_out
    seg = window_length(window, float(spr), res, m, "resolution")
    step, n_frames = frame_layout(m, seg, overlap)
    return OrderPlan(resampler, r, rate, t0, seg, step, n_frames, window, block)
