"""Windowed, averaged single-sided spectra with calibrated amplitude conventions, and peaks.

Conventions (Brandt 2011, ch. 9-10; Heinzel, Rüdiger & Schilling 2002, sections 9-11). With
``w`` the window of length ``L``, ``S1 = sum(w)``, ``S2 = sum(w**2)``, ``X_k`` the DFT of one
windowed segment and ``<.>`` the average over segments, the single-sided spectra are

=========  ==========================================  ==========================
scaling    value at an interior bin                    a sine ``A sin(2 pi f t)``
=========  ==========================================  ==========================
"power"    ``2 <|X_k|^2> / S1^2``                      ``A^2 / 2`` (on bin)
"rms"      ``sqrt(power)``                             ``A / sqrt(2)`` (on bin)
"peak"     ``sqrt(2) * rms``                           ``A`` (on bin)
"psd"      ``2 <|X_k|^2> / (fs * S2)``                 white noise: ``s^2 / (fs/2)``
=========  ==========================================  ==========================

The DC bin (and the Nyquist bin for even ``nfft``) is not doubled, so a constant ``c`` reads
``c`` in every amplitude scaling. Off bin, the amplitude scalings read low by the window's
scalloping loss; :func:`find_peaks` corrects that by fitting the window's own transform.
Averaging is over power (``<|X|^2>``), never over complex spectra or magnitudes, so the
``"max"`` average is a peak hold of the power.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Hashable, Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import scipy.optimize
import scipy.signal

from analysis.cf import cf_dataset
from analysis.checks import require_choice, require_int, require_size, time_or_rate
from analysis.fft import RfftPlan, rfft_plan
from analysis.inputs import channel_coords, select_channel, signal_input
from analysis.levels import AMPLITUDES, SCALINGS, amplitude_choice, to_db, units_of
from analysis.plots import spectrum_figure
from analysis.windows import (
    WINDOWS,
    WindowInfo,
    WindowSpec,
    get_window,
    window_info,
    window_info_of,
    window_sums,
)

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

__all__ = [
    "SCALINGS",
    "WINDOWS",
    "Peaks",
    "Spectrum",
    "WindowInfo",
    "find_peaks",
    "get_window",
    "spectrum",
    "to_db",
    "window_info",
]

_BLOCK_ELEMENTS = 1 << 17  # windowed samples per FFT block (1 MiB: stays in the CPU cache)


@dataclass
class Spectrum:
    """Single-sided spectrum (see the module docstring for the amplitude conventions).

    Attributes
    ----------
    frequency : numpy.ndarray
        Bin frequencies [Hz], ``k * fs / nfft``.
    values : numpy.ndarray
        Spectrum, shape ``(*channels, frequency)``.
    window : str
        Window label.
    amplitude : str
        ``"peak"``, ``"rms"``, ``"power"`` or ``"density"`` (PSD).
    enbw_hz : float
        Equivalent noise bandwidth [Hz] (``enbw_bins * fs / segment_length``).
    bin_spacing_hz : float
        Line spacing ``fs / nfft`` [Hz].
    n_averages : int
        Number of averaged segments.
    units : str
        Units of ``values`` (UDUNITS string).
    fs : float
        Sample rate [Hz].
    segment_length, nfft : int
        Samples per segment and transform length (``nfft > segment_length`` zero-pads).
    overlap : float
        Segment overlap fraction.
    average : str
        ``"mean"`` or ``"max"`` (peak hold) of the segment powers.
    beta : float or None
        Kaiser parameter, if any.
    dims : tuple of str
        Names of the leading (channel) dimensions of ``values``.
    coords : dict
        Coordinate arrays of the leading dimensions (may be empty).
    name : str
        Name of the analysed channel.
    window_params : tuple
        Parameters of the window other than Kaiser's beta.
    axis : str
        ``"frequency"`` (Hz), or ``"order"`` for the spectrum inside an
        :class:`analysis.orders.OrderSpectrum`, whose ``frequency`` holds orders and whose
        ``fs`` is the samples per revolution; its peaks are then named ``order``.
    """

    frequency: np.ndarray
    values: np.ndarray
    window: str
    amplitude: str
    enbw_hz: float
    bin_spacing_hz: float
    n_averages: int
    units: str
    fs: float
    segment_length: int
    nfft: int
    overlap: float = 0.0
    average: str = "mean"
    beta: float | None = None
    dims: tuple[str, ...] = ()
    coords: dict[str, np.ndarray] = field(default_factory=dict)
    name: str = "x"
    window_params: tuple[Any, ...] = ()
    axis: str = "frequency"

    @property
    def resolution_hz(self) -> float:
        """Resolution bandwidth [Hz]: the window's ENBW, as in the maps (MATLAB's ``res``)."""
        return self.enbw_hz

    @property
    def scaling(self) -> str:
        """Deprecated name of :attr:`amplitude` (``"psd"`` for ``"density"``)."""
        warnings.warn(
            "Spectrum.scaling is deprecated; use Spectrum.amplitude", FutureWarning, stacklevel=2
        )
        return "psd" if self.amplitude == "density" else self.amplitude

    @property
    def window_spec(self) -> WindowSpec:
        """Window specification accepted by :func:`get_window`."""
        base = self.window.split("(")[0]
        if self.beta is not None:
            return (base, self.beta)
        return (base, *self.window_params) if self.window_params else base

    def select(self, channel: Any) -> Spectrum:
        """The spectrum of one channel (a label of the channel coordinate, or an index)."""
        values, dims, coords, label = select_channel(self.values, self.dims, self.coords, channel)
        name = f"{self.name} {label}" if self.name else label
        return dataclasses.replace(self, values=values, dims=dims, coords=coords, name=name)

    def to_dataset(self) -> xr.Dataset:
        """CF-annotated :class:`xarray.Dataset` with variable ``spectrum(..., frequency)``."""
        import xarray as xr

        long = {
            "peak": "peak amplitude spectrum",
            "rms": "rms amplitude spectrum",
            "power": "power spectrum",
            "density": "power spectral density",
        }[self.amplitude]
        dims = (*self.dims, "frequency")
        coords: dict[Hashable, Any] = {
            "frequency": ("frequency", self.frequency, {"units": "Hz", "long_name": "frequency"})
        }
        coords.update(channel_coords(self.dims, self.coords))
        ds = xr.Dataset(
            {
                "spectrum": (
                    dims,
                    self.values,
                    {"units": self.units, "long_name": f"{long} of {self.name}"},
                )
            },
            coords=coords,
        )
        ds.attrs.update(
            window=self.window,
            amplitude=self.amplitude,
            enbw_hz=float(self.enbw_hz),
            resolution_hz=float(self.resolution_hz),
            bin_spacing_hz=float(self.bin_spacing_hz),
            n_averages=int(self.n_averages),
            segment_length=int(self.segment_length),
            nfft=int(self.nfft),
            overlap=float(self.overlap),
            average=self.average,
            sample_rate_hz=float(self.fs),
        )
        return cf_dataset(ds, title=f"{long} of {self.name}",
                          producer="analysis.spectrum.spectrum", inputs={"signal": self.name})

    def peaks(self, **kwargs: Any) -> Peaks:
        """Shortcut for :func:`find_peaks` ``(self, **kwargs)``."""
        return find_peaks(self, **kwargs)

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure of the spectrum (see :func:`analysis.plots.spectrum_figure`)."""
        return spectrum_figure(self, **kwargs)


def _frame_blocks(
    lead: tuple[int, ...], n_seg: int, rows: int
) -> Iterator[list[tuple[tuple[int, ...], int, int, int]]]:
    """Split the ``prod(lead) * n_seg`` frames, channel by channel, into blocks of ``rows``.

    Yields lists of pieces ``(channel index, first frame, stop frame, first row)``; every block
    but the last has exactly ``rows`` rows, and a block may span several channels.
    """
    pieces: list[tuple[tuple[int, ...], int, int, int]] = []
    filled = 0
    for ch in np.ndindex(*lead):
        f = 0
        while f < n_seg:
            take = min(rows - filled, n_seg - f)
            pieces.append((ch, f, f + take, filled))
            filled += take
            f += take
            if filled == rows:
                yield pieces
                pieces, filled = [], 0
    if pieces:
        yield pieces


def _segment_power(
    x: np.ndarray,
    w: np.ndarray,
    nfft: int,
    step: int,
    average: str,
    workers: int | None = None,
) -> tuple[np.ndarray, int]:
    """Mean (or max) over segments of ``|rfft(w * segment)|^2`` along the last axis.

    The frames are a strided view of ``x`` (no copy). They are processed in blocks of about
    ``_BLOCK_ELEMENTS`` samples, small enough to stay in the CPU cache: each block is windowed
    straight into the aligned input buffer of a cached batched plan
    (:func:`analysis.fft.rfft_plan`), transformed with one execute, squared in place in the
    plan's output buffer and summed (or maxed) into the accumulator. Memory is the
    accumulator plus two block buffers, whatever the signal length. The partition into
    blocks depends only on the shapes, so the result is deterministic.
    """
    seg = w.size
    frames = np.lib.stride_tricks.sliding_window_view(x, seg, axis=-1)[..., ::step, :]
    n_seg = frames.shape[-2]
    lead = frames.shape[:-2]
    nbins = nfft // 2 + 1
    acc = np.zeros((*lead, nbins))
    total = int(np.prod(lead, dtype=np.int64)) * n_seg
    rows = min(total, max(1, _BLOCK_ELEMENTS // nfft))
    padded: list[RfftPlan] = []  # plans whose zero padding was (re)set in this call
    for pieces in _frame_blocks(lead, n_seg, rows):
        used = pieces[-1][3] + pieces[-1][2] - pieces[-1][1]
        plan = rfft_plan(used, nfft, workers=workers)
        buf = plan.input
        if nfft > seg and not any(p is plan for p in padded):  # buffers are shared
            buf[:, seg:] = 0.0
            padded.append(plan)
        for ch, f0, f1, r0 in pieces:
            np.multiply(frames[ch][f0:f1], w, out=buf[r0 : r0 + f1 - f0, :seg])
        v = plan.execute().view(np.float64)  # (rows, 2 * nbins): re, im interleaved
        np.square(v, out=v)
        if average == "mean":
            for ch, f0, f1, r0 in pieces:
                s = v[r0 : r0 + f1 - f0].sum(axis=0)
                acc[ch] += s[0::2] + s[1::2]
        else:
            p = v[:, 0::2]
            np.add(p, v[:, 1::2], out=p)
            for ch, f0, f1, r0 in pieces:
                np.maximum(acc[ch], p[r0 : r0 + f1 - f0].max(axis=0), out=acc[ch])
    if average == "mean":
        acc /= n_seg
    return acc, n_seg


def spectrum(
    x: Any,
    fs: float | None = None,
    *,
    window: WindowSpec = "hann",
    amplitude: Literal["peak", "rms", "power", "density"] | None = None,
    resolution: float | None = None,
    segment_length: int | None = None,
    nfft: int | None = None,
    overlap: float = 0.5,
    average: Literal["mean", "max"] = "mean",
    time: Any = None,
    axis: int | None = None,
    units: str | None = None,
    name: str | None = None,
    workers: int | None = None,
    scaling: str | None = None,
) -> Spectrum:
    """Single-sided windowed spectrum, Welch-averaged over segments.

    Parameters
    ----------
    x : array_like or xarray.DataArray
        Signal, one or several channels (see :mod:`analysis.inputs`). A DataArray gives
        ``fs`` (its uniform ``time`` coordinate), ``units`` and its channel coordinates; a
        multi-dimensional array needs ``axis``.
    fs : float, optional
        Sample rate [Hz] (or ``time``); for a DataArray it must match the coordinate.
    window : str or tuple, default "hann"
        Any :func:`scipy.signal.get_window` window.
    amplitude : {"peak", "rms", "power", "density"}, default "rms"
        Amplitude convention (module docstring); ``"density"`` is the PSD (scipy's word).
    resolution : float, optional
        Resolution bandwidth [Hz] (the window's ENBW, as in the maps): sets
        ``segment_length = round(ENBW_bins * fs / resolution)``. Exclusive with
        ``segment_length``.
    segment_length : int, optional
        Samples per averaged segment; default the whole record (one segment).
    nfft : int, optional
        Transform length >= ``segment_length`` (zero padding); default ``segment_length``.
    overlap : float, default 0.5
        Overlap fraction between segments, in ``[0, 1)``.
    average : {"mean", "max"}, default "mean"
        Mean or peak hold of the segment powers.
    time : array_like, optional
        Uniform time axis [s] instead of ``fs``.
    axis : int, optional
        Time axis of a multi-dimensional array.
    units : str, optional
        Units of ``x`` (default from the DataArray, else ``"1"``).
    name : str, optional
        Channel name used in ``long_name``.
    workers : int, optional
        FFT threads; ``None`` uses :func:`analysis.fft.get_workers` (1 by default), -1 all
        CPUs. The result does not depend on it beyond floating-point rounding. Extra threads
        pay off only when CPUs are idle: each block is a few milliseconds of work, and
        waiting for a busy CPU at every execute can cost more than it saves.
    scaling : str, optional
        Deprecated name of ``amplitude`` (``"psd"`` for ``"density"``).

    Returns
    -------
    Spectrum
        The spectrum with its window, ENBW (= resolution), bin spacing and number of averages.

    Notes
    -----
    The segments are transformed in batches of about 128 k samples through one reusable
    FFTW plan (see :func:`analysis.fft.rfft_plan`), so memory stays bounded for any record
    length, and the same input gives the same output bit for bit.
    """
    amp = amplitude_choice(amplitude, scaling, "spectrum", AMPLITUDES)
    fs, time = time_or_rate(fs, time, "spectrum")
    sig = signal_input(x, fs, time=time, axis=axis, units=units, name=name)
    arr, fs, dims = sig.values, sig.fs, sig.dims
    require_choice(average, ("mean", "max"), "average")
    n = arr.shape[-1]
    if resolution is not None:
        if segment_length is not None:
            raise ValueError("give resolution= (Hz) or segment_length= (samples), not both")
        res = float(resolution)
        if not np.isfinite(res) or res <= 0:
            raise ValueError(f"resolution = {resolution!r} is not admissible: must be > 0 Hz")
        seg = round(window_info(window, 4096).enbw_bins * fs / res)
        if not 2 <= seg <= n:
            raise ValueError(
                f"resolution = {res:g} Hz needs segments of {seg} samples; admissible: 2 to "
                f"{n} (the record's length)"
            )
    else:
        seg = n if segment_length is None else require_int(segment_length, "segment_length", 2)
    if seg > n:
        raise ValueError(f"segment_length = {seg} is not admissible: must be <= {n} (x length)")
    nfft = seg if nfft is None else require_int(nfft, "nfft", 1)
    if nfft < seg:
        raise ValueError(f"nfft = {nfft} is not admissible: must be >= segment_length = {seg}")
    require_size(
        8.0 * (nfft + 2) * (np.prod(sig.lead, dtype=float) + 3),
        f"a spectrum of nfft = {nfft} lines", "nfft, segment_length, resolution",
    )
    overlap = float(overlap)
    if not 0.0 <= overlap < 1.0:
        raise ValueError(f"overlap = {overlap!r} is not admissible: must be in [0, 1)")
    step = max(1, round(seg * (1.0 - overlap)))
    w = get_window(window, seg)
    info = window_info_of(window, w)
    s1, s2 = window_sums(w)
    power, n_avg = _segment_power(arr, w, nfft, step, average, workers)
    one_sided = np.full(nfft // 2 + 1, 2.0)
    one_sided[0] = 1.0
    if nfft % 2 == 0:
        one_sided[-1] = 1.0
    if amp == "density":
        values = power * (one_sided / (fs * s2))
    else:
        values = power * (one_sided / (s1 * s1))
        if amp in ("rms", "peak"):
            np.sqrt(values, out=values)
        if amp == "peak":
            values *= np.sqrt(one_sided)
    return Spectrum(
        frequency=np.arange(nfft // 2 + 1) * (fs / nfft),
        values=values,
        window=info.label,
        amplitude=amp,
        enbw_hz=info.enbw_hz(fs),
        bin_spacing_hz=fs / nfft,
        n_averages=n_avg,
        units=units_of(sig.units, amp),
        fs=fs,
        segment_length=seg,
        nfft=nfft,
        overlap=overlap if seg < n else 0.0,
        average=average,
        beta=info.beta,
        dims=dims,
        coords=sig.coords,
        name=sig.name,
        window_params=info.params,
    )


# --------------------------------------------------------------------------------- peaks


@dataclass
class Peaks:
    """Spectral peaks with window-corrected position and amplitude.

    Attributes
    ----------
    frequency : numpy.ndarray
        Interpolated peak positions (ascending) on the spectrum's axis: frequencies [Hz], or
        orders when ``axis == "order"`` (peaks of an order spectrum), where they are read as
        :attr:`order`.
    amplitude : numpy.ndarray
        Peak heights corrected for scalloping, in the spectrum's convention and ``units``: a
        sinusoid of amplitude ``A`` gives ``A`` ("peak"), ``A/sqrt(2)`` ("rms"), ``A^2/2``
        ("power"); for "density" the corrected PSD height (the sine's power is
        ``amplitude * enbw_hz``).
    bin_frequency, bin_value : numpy.ndarray
        Position (Hz or orders, :attr:`bin_order`) and raw value of the local-maximum bins.
    scaling : str
        The spectrum's amplitude convention (``Spectrum.amplitude``; here the field is called
        ``scaling`` because ``amplitude`` holds the peak heights).
    units, window : str
        Copied from the spectrum.
    axis : str
        ``"frequency"`` (Hz) or ``"order"`` (orders; the spectrum of an order spectrum).
    """

    frequency: np.ndarray
    amplitude: np.ndarray
    bin_frequency: np.ndarray
    bin_value: np.ndarray
    scaling: str
    units: str
    window: str
    axis: str = "frequency"

    def __len__(self) -> int:
        return int(self.frequency.size)

    def _orders(self, values: np.ndarray, name: str) -> np.ndarray:
        if self.axis != "order":
            raise AttributeError(
                f"Peaks.{name}: these peaks are on a frequency axis (Hz); read .frequency"
            )
        return values

    @property
    def order(self) -> np.ndarray:
        """Interpolated peak orders (peaks of an order spectrum, ``axis == "order"``)."""
        return self._orders(self.frequency, "order")

    @property
    def bin_order(self) -> np.ndarray:
        """Orders of the local-maximum lines (``axis == "order"``)."""
        return self._orders(self.bin_frequency, "bin_order")

    def labels(self, fmt: str | None = None) -> list[str]:
        """Text labels, ``fmt`` formatted with ``frequency`` (or ``order`` on an order axis)
        and ``amplitude``; default ``"{frequency:.1f} Hz"`` or ``"order {order:.2f}"``."""
        on_order = self.axis == "order"
        if fmt is None:
            fmt = "order {order:.2f}" if on_order else "{frequency:.1f} Hz"
        return [
            fmt.format(frequency=f, amplitude=a, **({"order": f} if on_order else {}))
            for f, a in zip(self.frequency, self.amplitude, strict=True)
        ]

    def to_dataset(self) -> xr.Dataset:
        """:class:`xarray.Dataset` with dimension ``peak``: ``frequency``/``bin_frequency``
        [Hz], or ``order``/``bin_order`` on an order axis."""
        import xarray as xr

        on_order = self.axis == "order"
        pos, unit = ("order", "1") if on_order else ("frequency", "Hz")
        ds = xr.Dataset(
            {
                pos: (
                    "peak",
                    self.frequency,
                    {"units": unit, "long_name": f"interpolated peak {pos}"},
                ),
                "amplitude": (
                    "peak",
                    self.amplitude,
                    {"units": self.units, "long_name": f"corrected peak {self.scaling} value"},
                ),
                f"bin_{pos}": (
                    "peak",
                    self.bin_frequency,
                    {"units": unit, "long_name": f"{pos} of the maximum bin"},
                ),
                "bin_value": (
                    "peak",
                    self.bin_value,
                    {"units": self.units, "long_name": f"{self.scaling} value of the maximum bin"},
                ),
            },
            coords={
                "peak": (
                    "peak",
                    np.arange(self.frequency.size),
                    {"long_name": "peak index", "units": "1"},
                )
            },
            attrs={"scaling": self.scaling, "window": self.window},
        )
        return cf_dataset(ds, title="spectral peaks", producer="analysis.spectrum.find_peaks")


class _Kernel:
    """Magnitude of the window's DTFT, ``|W(delta)|`` for an offset ``delta`` in bins."""

    def __init__(self, w: np.ndarray, nfft: int) -> None:
        self._w = w
        self._phase = -2j * np.pi * np.arange(w.size) / nfft

    def __call__(self, delta: float) -> float:
        # a numpy sum, not np.dot: no BLAS threads (see _window_sums)
        return float(abs((self._w * np.exp(self._phase * delta)).sum()))


def _interpolate(kernel: _Kernel, a: float, b: float, c: float) -> tuple[float, float]:
    """Offset ``delta`` (bins, in [-0.5, 0.5]) and gain ``W(0)/W(delta)`` from 3 magnitudes.

    Solves ``(c - a) / b = (W(1 - d) - W(1 + d)) / W(d)`` for ``d``: the magnitudes of the bins
    ``k-1, k, k+1`` of a sinusoid at ``k + d`` are proportional to ``W(-1-d), W(-d), W(1-d)``.
    For the Hann window this is equivalent to Grandke's 3-point formula (1983); for any window
    it fits the known kernel, so it is exact for one sinusoid up to the leakage of others.
    """
    w0 = kernel(0.0)
    if b <= 0:
        return 0.0, 1.0
    r = (c - a) / b

    def f(d: float) -> float:
        return (kernel(1.0 - d) - kernel(1.0 + d)) / kernel(d) - r

    lo, hi = f(-0.5), f(0.5)
    if lo >= 0:
        d = -0.5
    elif hi <= 0:
        d = 0.5
    else:
        d = float(scipy.optimize.brentq(f, -0.5, 0.5, xtol=1e-10))
    return d, w0 / kernel(d)


def find_peaks(
    spectrum: Spectrum,
    *,
    threshold: float | None = None,
    prominence_db: float | None = None,
    max_peaks: int | None = None,
    min_distance_hz: float | None = None,
    channel: Any = None,
) -> Peaks:
    """Local maxima of a spectrum with interpolated frequency and amplitude.

    Parameters
    ----------
    spectrum : Spectrum
        Result of :func:`spectrum`.
    threshold : float, optional
        Absolute minimum bin value, in the spectrum's units.
    prominence_db : float, optional
        Minimum prominence of the peak above its surroundings, in dB.
    max_peaks : int, optional
        Keep only the strongest ``max_peaks`` (result sorted by frequency).
    min_distance_hz : float, optional
        Minimum distance between peaks [Hz; orders for the spectrum of an order spectrum];
        the stronger one is kept.
    channel : int, str or tuple of int, optional
        Multi-channel spectra: a label of the channel coordinate, or an index (tuple of
        indices) into the leading dimensions (required then).

    Returns
    -------
    Peaks
        Peaks; DC and the last bin are never interpolated. On the spectrum of an order
        spectrum (``spectrum.axis == "order"``) they are on an order axis (``Peaks.order``).
    """
    if not isinstance(spectrum, Spectrum):
        raise ValueError("spectrum must be a Spectrum (result of analysis.spectrum.spectrum)")
    vals = spectrum.values
    if vals.ndim > 1:
        if channel is None:
            raise ValueError(
                f"spectrum has leading dims {spectrum.dims}; pass channel=<index> to choose one"
            )
        vals = spectrum.select(channel).values if isinstance(channel, str) else vals[channel]
        if vals.ndim != 1:
            raise ValueError(f"channel = {channel!r} does not select a single spectrum")
    kwargs: dict[str, Any] = {}
    if prominence_db is not None:
        if not prominence_db >= 0:
            raise ValueError(f"prominence_db = {prominence_db!r} is not admissible: must be >= 0")
        kwargs["prominence"] = float(prominence_db)
    if min_distance_hz is not None:
        if not min_distance_hz > 0:
            raise ValueError(
                f"min_distance_hz = {min_distance_hz!r} is not admissible: must be > 0 Hz"
            )
        kwargs["distance"] = max(1, round(min_distance_hz / spectrum.bin_spacing_hz))
    if max_peaks is not None:
        require_int(max_peaks, "max_peaks", 1)
    levels = to_db(vals, spectrum.amplitude)
    idx, _ = scipy.signal.find_peaks(np.concatenate(([-np.inf], levels, [-np.inf])), **kwargs)
    idx = idx - 1
    if threshold is not None:  # absolute threshold on the linear values
        idx = idx[vals[idx] >= float(threshold)]
    if max_peaks is not None and idx.size > max_peaks:
        idx = np.sort(idx[np.argsort(vals[idx])[::-1][:max_peaks]])
    # bin magnitudes proportional to |X_k| (undo the one-sided factors and the square root)
    power_like = spectrum.amplitude in ("power", "density")
    mag = np.sqrt(vals) if power_like else vals.copy()
    one_sided = np.full(mag.size, 0.5 if spectrum.amplitude == "peak" else np.sqrt(0.5))
    one_sided[0] = 1.0
    if spectrum.nfft % 2 == 0 and mag.size == spectrum.nfft // 2 + 1:
        one_sided[-1] = 1.0
    mag *= one_sided
    w = get_window(spectrum.window_spec, spectrum.segment_length)
    kernel = _Kernel(w, spectrum.nfft)
    freq = np.empty(idx.size)
    amp = np.empty(idx.size)
    for j, k in enumerate(idx):
        if 0 < k < vals.size - 1:
            d, gain = _interpolate(kernel, mag[k - 1], mag[k], mag[k + 1])
        else:
            d, gain = 0.0, 1.0
        freq[j] = (k + d) * spectrum.bin_spacing_hz
        amp[j] = vals[k] * (gain * gain if power_like else gain)
    return Peaks(
        frequency=freq,
        amplitude=amp,
        bin_frequency=spectrum.frequency[idx],
        bin_value=vals[idx].copy(),
        scaling=spectrum.amplitude,
        units=spectrum.units,
        window=spectrum.window,
        axis=spectrum.axis,
    )
