"""Order spectra and order cuts of signals measured at varying speed.

Both rest on the angular resampling of :mod:`analysis.resample` (computed order tracking)
and on the frame machinery of :mod:`analysis.frames`: :func:`order_spectrum` averages the
segments of the resampled signal block by block, :func:`order_cuts` sums the lines of the
frames of an rpm-order map (proportional band) or rpm-frequency map (fixed band) into order
bands, and :func:`order_cuts_from_map` does the same on a computed map. Neither holds the
angle-domain signal: beyond their output they need a few MB whatever the record's length.
:func:`angle_from_speed` and :func:`resample_to_angle` are re-exported from
:mod:`analysis.resample`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from analysis.checks import (
    require_block_size,
    require_choice,
    require_finite,
    require_same_length,
    uniform_rate,
)
from analysis.frames import (
    BLOCK_ELEMENTS,
    check_speed,
    frame_coords,
    frame_ranges,
    frequency_plan,
    order_plan,
    stft_into,
)
from analysis.levels import line_factors, power_of, to_db
from analysis.maps import RpmFrequencyMap, RpmOrderMap
from analysis.plots import order_cuts_figure, order_spectrum_figure
from analysis.resample import (
    AngleSignal,
    angle_from_speed,
    check_signal,
    resample_to_angle,
    speed_resampler,
)
from analysis.spectrum import Peaks, Spectrum, find_peaks, spectrum
from analysis.windows import WindowSpec, main_lobe_half_width, window_info

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

__all__ = [
    "AngleSignal",
    "OrderCut",
    "OrderSpectrum",
    "angle_from_speed",
    "order_cuts",
    "order_cuts_from_map",
    "order_spectrum",
    "resample_to_angle",
]


# ---------------------------------------------------------------------------- order spectrum


@dataclass
class OrderSpectrum:
    """Averaged spectrum of an angle-domain signal: level vs order.

    Attributes
    ----------
    order : numpy.ndarray
        Orders (cycles per revolution) of the bins.
    values : numpy.ndarray
        Spectrum in ``scaling`` (as for :class:`analysis.spectrum.Spectrum`).
    resolution_orders : float
        Bin spacing actually used [orders] (``1 / revolutions per segment``).
    enbw_orders : float
        Equivalent noise bandwidth [orders].
    spectrum : Spectrum
        The underlying spectrum, whose "frequency" axis is in orders.
    samples_per_rev : int
        Angular sampling.
    max_order : float
        Highest alias-free order.
    """

    order: np.ndarray
    values: np.ndarray
    window: str
    scaling: str
    resolution_orders: float
    enbw_orders: float
    n_averages: int
    units: str
    spectrum: Spectrum
    samples_per_rev: int
    max_order: float
    name: str = "x"

    def to_dataset(self) -> xr.Dataset:
        """:class:`xarray.Dataset` with variable ``order_spectrum(..., order)``."""
        import xarray as xr

        dims = (*self.spectrum.dims, "order")
        return xr.Dataset(
            {
                "order_spectrum": (
                    dims,
                    self.values,
                    {
                        "units": self.units,
                        "long_name": f"{self.scaling} order spectrum of {self.name}",
                    },
                )
            },
            coords={
                "order": (
                    "order",
                    self.order,
                    {"units": "1", "long_name": "order (cycles per shaft revolution)"},
                )
            },
            attrs={
                "window": self.window,
                "scaling": self.scaling,
                "resolution_orders": float(self.resolution_orders),
                "enbw_orders": float(self.enbw_orders),
                "n_averages": int(self.n_averages),
                "samples_per_rev": int(self.samples_per_rev),
                "max_order": float(self.max_order),
            },
        )

    def peaks(self, **kwargs: Any) -> Peaks:
        """Peaks (see :func:`analysis.spectrum.find_peaks`); ``frequency`` is in orders."""
        if "min_distance_orders" in kwargs:
            kwargs["min_distance_hz"] = kwargs.pop("min_distance_orders")
        return find_peaks(self.spectrum, **kwargs)

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure (see :func:`analysis.plots.order_spectrum_figure`)."""
        return order_spectrum_figure(self, **kwargs)


def order_spectrum(
    x: Any,
    time: Any,
    rpm: Any,
    *,
    orders_resolution: float,
    window: WindowSpec = "flattop",
    scaling: Literal["peak", "rms", "power", "psd"] = "rms",
    overlap: float = 0.5,
    samples_per_rev: int | None = None,
    max_order: float | None = None,
    units: str = "1",
    name: str = "x",
    block_size: int | None = None,
) -> OrderSpectrum:
    """Averaged order spectrum of a signal measured at varying speed.

    The signal is resampled to constant angle increments block by block and each block's
    segments are added to the average at once, so the angle-domain signal is never held
    whole: the working memory is a few blocks, whatever the length of the record.

    Parameters
    ----------
    x : array_like
        Signal, time along the last axis.
    time : array_like
        Uniform sample instants [s].
    rpm : array_like
        Shaft speed [min-1] at ``time``; must be > 0.
    orders_resolution : float
        Requested bin spacing [orders]; the segment spans ``1 / orders_resolution``
        revolutions (rounded to whole samples; the value used is reported).
    window : str or ("kaiser", beta), default "flattop"
        Window (flat-top like MATLAB ``orderspectrum``).
    scaling : {"peak", "rms", "power", "psd"}, default "rms"
        Amplitude convention.
    overlap : float, default 0.5
        Segment overlap.
    samples_per_rev : int, optional
        Angular sampling; default so that the top speed is sampled at about ``fs``.
    max_order : float, optional
        Highest order to keep (default ``samples_per_rev / 2.56``).
    units, name : str
        Metadata of ``x``.
    block_size : int, optional
        Angle-domain samples resampled per block (default 32768; a block always holds at
        least one segment). Only the working memory depends on it; the result equals that
        of a single block to rounding.

    Returns
    -------
    OrderSpectrum
        Energy-averaged order spectrum.
    """
    arr = check_signal(x, name)
    t = np.asarray(time)
    n = check_speed(
        rpm, t.size, "rpm must be > 0 everywhere for order tracking (min-1); rpm[{i}] = {value}"
    )
    res = float(orders_resolution)
    if not np.isfinite(res) or res <= 0:
        raise ValueError(f"orders_resolution = {orders_resolution!r} must be finite and > 0")
    require_choice(scaling, ("peak", "rms", "power", "psd"), "scaling")
    if not 0.0 <= float(overlap) < 1.0:
        raise ValueError(f"overlap = {overlap!r} is not admissible: must be in [0, 1)")
    fs = uniform_rate(t, "time")
    require_same_length([arr, t], [name, "time"])
    if t.size < 8:
        raise ValueError(f"{name}: needs at least 8 samples for angular resampling")
    block = require_block_size(block_size)
    resampler = speed_resampler(arr, n, samples_per_rev, max_order, block, fs=fs, time=t)
    spr = resampler.samples_per_rev
    m = resampler.n_out
    seg = round(spr / res)
    if seg > m:
        raise ValueError(
            f"orders_resolution = {res:g} needs {seg / spr:.4g} revolutions "
            f"per segment, but the record has only {m / spr:.4g}"
        )
    window_info(window, max(seg, 2))  # checks the window before the work
    step = max(1, round(seg * (1.0 - float(overlap))))
    n_seg = (m - seg) // step + 1
    kind = "psd" if scaling == "psd" else "power"
    total = np.zeros((*arr.shape[:-1], seg // 2 + 1))
    values = np.empty(0)
    for k0, k1 in frame_ranges(n_seg, seg, step, block):
        values, _ = resampler.block(k0 * step, (k1 - 1) * step + seg)
        part = spectrum(
            values, float(spr), window=window, scaling=kind, segment_length=seg, overlap=overlap
        )
        total += part.values * part.n_averages
    total /= n_seg
    if scaling in ("rms", "peak"):
        np.sqrt(total, out=total)
        if scaling == "peak":
            total *= np.sqrt(line_factors(total.shape[-1], seg))
    # metadata (units, window label, ENBW...) from the last block in the requested scaling
    last = spectrum(
        values,
        float(spr),
        window=window,
        scaling=scaling,
        segment_length=seg,
        overlap=overlap,
        units=units,
        name=name,
    )
    s = dataclasses.replace(last, values=total, n_averages=n_seg)
    return OrderSpectrum(
        order=s.frequency,
        values=s.values,
        window=s.window,
        scaling=scaling,
        resolution_orders=s.resolution_hz,
        enbw_orders=s.enbw_hz,
        n_averages=s.n_averages,
        units=s.units,
        spectrum=s,
        samples_per_rev=spr,
        max_order=resampler.max_order,
        name=name,
    )


# -------------------------------------------------------------------------------- order cuts


@dataclass
class OrderCut:
    """Level of chosen orders vs time and speed.

    Attributes
    ----------
    orders : numpy.ndarray
        Tracked orders.
    time : numpy.ndarray
        Frame centres [s].
    rpm : numpy.ndarray
        Speed at the frame centres [min-1].
    values : numpy.ndarray
        Level, shape ``(order, time)``; NaN where the band leaves the analysed range.
    amplitude : str
        ``"rms"``, ``"peak"`` or ``"power"``.
    scale : str
        ``"linear"`` or ``"dB"``.
    units : str
        Units of ``values`` (``"1"`` for dB levels, see ``level_reference``).
    bandwidth : float
        Band width, in orders if ``bandwidth_kind == "order"`` else in Hz.
    bandwidth_kind : str
        ``"order"`` (proportional) or ``"Hz"`` (fixed).
    source : str
        The map the cut was read from.
    window : str
        Window of that map.
    level_reference : str
        Reference of the dB scale (``"1 <units>"``), or ``""`` for linear.
    """

    orders: np.ndarray
    time: np.ndarray
    rpm: np.ndarray
    values: np.ndarray
    amplitude: str
    scale: str
    units: str
    bandwidth: float
    bandwidth_kind: str
    source: str
    window: str
    level_reference: str = ""
    name: str = "x"

    def to_dataset(self) -> xr.Dataset:
        """Dataset with ``level(order, time)`` and auxiliary coordinate ``rpm(time)``."""
        import xarray as xr

        long = f"{self.amplitude} level of {self.name} in the order band"
        if self.scale == "dB":
            long += f" (dB re {self.level_reference})"
        return xr.Dataset(
            {"level": (("order", "time"), self.values, {"units": self.units, "long_name": long})},
            coords={
                "order": ("order", self.orders, {"units": "1", "long_name": "tracked order"}),
                **frame_coords(self.time, self.rpm),
            },
            attrs={
                "amplitude": self.amplitude,
                "scale": self.scale,
                "bandwidth": float(self.bandwidth),
                "bandwidth_kind": self.bandwidth_kind,
                "source": self.source,
                "window": self.window,
            },
        )

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure (see :func:`analysis.plots.order_cuts_figure`)."""
        return order_cuts_figure(self, **kwargs)


def _cut_setup(
    window: WindowSpec,
    axis: np.ndarray,
    is_freq: bool,
    orders: Any,
    bandwidth: float | None,
    bandwidth_hz: float | None,
    amplitude: str,
    scale: str,
) -> tuple[np.ndarray, str, float, float]:
    """Checked orders, band kind (``"order"``/``"Hz"``), band width and line spacing."""
    require_choice(amplitude, ("rms", "peak", "power"), "amplitude")
    require_choice(scale, ("linear", "dB"), "scale")
    ords = np.atleast_1d(require_finite(orders, "orders"))
    if ords.ndim != 1 or np.any(ords <= 0):
        raise ValueError("orders must be a 1-D list of orders > 0")
    if bandwidth is not None and bandwidth_hz is not None:
        raise ValueError("give either bandwidth (orders) or bandwidth_hz (Hz), not both")
    spacing = float(axis[1] - axis[0])
    if bandwidth is None and bandwidth_hz is None:
        kind = "Hz" if is_freq else "order"
        bw = 2.0 * main_lobe_half_width(window) * spacing
    elif bandwidth is not None:
        kind, bw = "order", float(bandwidth)
    else:
        kind, bw = "Hz", float(bandwidth_hz)  # type: ignore[arg-type]
    if not np.isfinite(bw) or bw <= 0:
        raise ValueError(f"bandwidth = {bw!r} is not admissible: must be finite and > 0")
    return ords, kind, bw, spacing


def _band_power(
    power: np.ndarray,
    rpm: np.ndarray,
    axis: np.ndarray,
    ords: np.ndarray,
    kind: str,
    bw: float,
    is_freq: bool,
    enbw_bins: float,
) -> np.ndarray:
    """Power in the order bands, shape ``(order, frame)``, of map lines ``power(frame, line)``.

    ``rpm`` is the speed of each frame; NaN where the band exceeds ``axis``.
    """
    spacing = float(axis[1] - axis[0])
    shaft_hz = rpm / 60.0  # (time,)
    shape = (ords.size, shaft_hz.size)
    centre = np.broadcast_to(ords[:, None] * (shaft_hz[None, :] if is_freq else 1.0), shape)
    if kind == "order":
        half = 0.5 * bw * (shaft_hz[None, :] if is_freq else 1.0)
    else:
        half = 0.5 * bw / (1.0 if is_freq else shaft_hz[None, :])
    half = np.broadcast_to(half, shape)
    if np.any(half < 0.5 * spacing):
        raise ValueError(
            f"bandwidth ({bw:g} {kind}) is narrower than the map's line spacing somewhere "
            "(the band would hold no line); widen it or use a finer map"
        )
    lo = np.searchsorted(axis, centre - half - 1e-9 * spacing, side="left")
    hi = np.searchsorted(axis, centre + half + 1e-9 * spacing, side="right")
    csum = np.concatenate([np.zeros((power.shape[0], 1)), np.cumsum(power, axis=1)], axis=1)
    rows = np.arange(power.shape[0])[None, :]
    band = (csum[rows, hi] - csum[rows, lo]) / enbw_bins
    band[(centre + half) > axis[-1]] = np.nan
    return band


def _cut_result(
    band: np.ndarray,
    ords: np.ndarray,
    time: np.ndarray,
    rpm: np.ndarray,
    *,
    amplitude: str,
    scale: str,
    signal_units: str,
    kind: str,
    bw: float,
    source: str,
    window: str,
    name: str,
) -> OrderCut:
    """:class:`OrderCut` from the band powers ``band(order, frame)``."""
    if amplitude == "rms":
        vals = np.sqrt(band)
    elif amplitude == "peak":
        vals = np.sqrt(2.0 * band)
    else:
        vals = band
    units = (
        signal_units
        if amplitude != "power"
        else ("1" if signal_units == "1" else f"({signal_units})^2")
    )
    ref = ""
    if scale == "dB":
        vals = to_db(vals, "power" if amplitude == "power" else "rms")
        ref, units = f"1 {units}", "1"
    return OrderCut(
        orders=ords,
        time=time,
        rpm=rpm,
        values=vals,
        amplitude=amplitude,
        scale=scale,
        units=units,
        bandwidth=bw,
        bandwidth_kind=kind,
        source=source,
        window=window,
        level_reference=ref,
        name=name,
    )


def order_cuts_from_map(
    m: RpmFrequencyMap | RpmOrderMap,
    orders: Any,
    *,
    bandwidth: float | None = None,
    bandwidth_hz: float | None = None,
    amplitude: Literal["rms", "peak", "power"] = "rms",
    scale: Literal["linear", "dB"] = "linear",
) -> OrderCut:
    """Order cuts read from an rpm-frequency or rpm-order map by summing the lines in a band.

    The level of the band is ``sqrt(sum_k G_k / ENBW_bins)`` (rms; Brandt 2011, sec. 10.3),
    where ``G_k`` is the map's power per line: for a sinusoid whose main lobe lies inside
    the band this is its rms value whatever the window and the bin offset.

    Parameters
    ----------
    m : RpmFrequencyMap or RpmOrderMap
        Map of any amplitude/scale (converted back to power internally, a block of frames
        at a time).
    orders : array_like
        Orders to track (> 0).
    bandwidth : float, optional
        Proportional band width in orders (band ``order +- bandwidth/2``).
    bandwidth_hz : float, optional
        Fixed band width in Hz (exclusive with ``bandwidth``).
        Default (neither given): the window's main-lobe width, in the map's own axis (fixed
        Hz on a frequency map, proportional on an order map).
    amplitude : {"rms", "peak", "power"}, default "rms"
        Convention of the result.
    scale : {"linear", "dB"}, default "linear"
        Linear or dB re 1 unit.

    Returns
    -------
    OrderCut
        Levels; NaN where the band exceeds the map's axis.
    """
    if not isinstance(m, RpmFrequencyMap | RpmOrderMap):
        raise ValueError("m must be an RpmFrequencyMap or RpmOrderMap")
    is_freq = isinstance(m, RpmFrequencyMap)
    axis = m.frequency if is_freq else m.order
    ords, kind, bw, _ = _cut_setup(
        m.window_spec, axis, is_freq, orders, bandwidth, bandwidth_hz, amplitude, scale
    )
    band = np.empty((ords.size, m.values.shape[0]))
    rows = max(1, BLOCK_ELEMENTS // max(1, m.values.shape[1]))
    for r0 in range(0, m.values.shape[0], rows):
        sl = slice(r0, r0 + rows)
        power = power_of(m.values[sl], m.amplitude, m.scale, m.segment_length)
        band[:, sl] = _band_power(power, m.rpm[sl], axis, ords, kind, bw, is_freq, m.enbw_bins)
    return _cut_result(
        band,
        ords,
        m.time.copy(),
        m.rpm.copy(),
        amplitude=amplitude,
        scale=scale,
        signal_units=m.signal_units,
        kind=kind,
        bw=bw,
        source=type(m).__name__,
        window=m.window,
        name=m.name,
    )


def order_cuts(
    x: Any,
    fs: float,
    rpm: Any,
    orders: Any,
    *,
    bandwidth: float | None = None,
    bandwidth_hz: float | None = None,
    amplitude: Literal["rms", "peak", "power"] = "rms",
    scale: Literal["linear", "dB"] = "linear",
    **map_kwargs: Any,
) -> OrderCut:
    """Order cuts (level of chosen orders vs rpm) directly from a signal.

    With ``bandwidth_hz`` (fixed band) the cut is read from the frames of :func:`analysis.
    maps.rpm_frequency_map`; otherwise (proportional band, ``bandwidth`` in orders, default
    the window's main lobe) from those of :func:`analysis.maps.rpm_order_map`. The frames are
    computed and summed into the bands a block at a time, so neither the map nor the
    angle-domain signal is ever held whole.

    Parameters
    ----------
    x, fs, rpm
        Signal (1-D), sample rate [Hz] (or ``None`` with ``time``) and speed [min-1].
    orders : array_like
        Orders to track (> 0).
    bandwidth, bandwidth_hz, amplitude, scale
        As in :func:`order_cuts_from_map`.
    **map_kwargs
        Passed on as to the map function: ``window``, ``resolution``, ``overlap``, ``time``,
        ``units``, ``name``; for the order map also ``samples_per_rev``, ``max_order``; and
        ``block_size`` (samples per block, default 32768, of the time signal for a fixed band
        and of the angle-domain signal otherwise; the result does not depend on it beyond
        rounding).

    Returns
    -------
    OrderCut
        See :func:`order_cuts_from_map`.
    """
    units = str(map_kwargs.pop("units", "1"))
    name = str(map_kwargs.get("name", "x"))
    is_freq = bandwidth_hz is not None
    plan = (frequency_plan if is_freq else order_plan)(x, fs, rpm, **map_kwargs)
    axis = plan.axis
    ords, kind, bw, spacing = _cut_setup(
        plan.window, axis, is_freq, orders, bandwidth, bandwidth_hz, amplitude, scale
    )
    if (kind == "Hz") == is_freq and bw < spacing:  # constant band: check before the work
        raise ValueError(
            f"bandwidth ({bw:g} {kind}) is narrower than the map's line spacing somewhere "
            "(the band would hold no line); widen it or use a finer map"
        )
    band = np.empty((ords.size, plan.n_frames))
    tc = np.empty(plan.n_frames)
    rc = np.empty(plan.n_frames)
    for k0, k1, samples, t_blk, r_blk in plan.blocks():
        power = np.empty((k1 - k0, axis.size))
        stft_into(samples, plan.w, plan.step, power, "power", "linear")
        band[:, k0:k1] = _band_power(
            power, r_blk, axis, ords, kind, bw, is_freq, plan.info.enbw_bins
        )
        tc[k0:k1], rc[k0:k1] = t_blk, r_blk
    return _cut_result(
        band,
        ords,
        tc,
        rc,
        amplitude=amplitude,
        scale=scale,
        signal_units=units,
        kind=kind,
        bw=bw,
        source="RpmFrequencyMap" if is_freq else "RpmOrderMap",
        window=plan.info.label,
        name=name,
    )
