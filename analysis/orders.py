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
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from analysis.cf import cf_dataset, processing_attrs
from analysis.checks import require_block_size, require_choice, require_size, time_or_rate
from analysis.frames import (
    BLOCK_ELEMENTS,
    FrequencyPlan,
    OrderPlan,
    frame_coords,
    frame_ranges,
    frequency_plan,
    order_plan,
    stft_into,
)
from analysis.inputs import channel_coords, reference_input, select_channel, signal_input
from analysis.levels import (
    AMPLITUDES,
    Amplitude,
    amplitude_choice,
    line_factors,
    power_of,
    to_db,
    units_of,
)
from analysis.maps import RpmFrequencyMap, RpmOrderMap
from analysis.order_resolution import (
    OrderBandWarning,
    check_bands,
    choose_order_resolution,
    main_lobe_band,
    named_lines,
    optional_positive,
    requested_orders,
)
from analysis.plots import order_cuts_figure, order_spectrum_figure
from analysis.resample import AngleSignal, angle_from_speed, resample_to_angle, tracking
from analysis.spectrum import Peaks, Spectrum, find_peaks, spectrum
from analysis.windows import WindowSpec, main_lobe_half_width, window_info

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

__all__ = [
    "AngleSignal",
    "OrderBandWarning",
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
    """Averaged spectrum of an angle-domain signal: level vs order (MATLAB ``orderspectrum``).

    Attributes
    ----------
    order : numpy.ndarray
        Orders (cycles per revolution) of the lines.
    values : numpy.ndarray
        Spectrum in ``amplitude``, shape ``(*channels, order)``.
    amplitude : str
        ``"peak"``, ``"rms"``, ``"power"`` or ``"density"`` (power per order).
    resolution_orders : float
        Resolution bandwidth actually used [orders]: the window's ENBW (as in the maps).
    bin_spacing_orders : float
        Line spacing [orders] (``1 / revolutions per segment``).
    enbw_orders : float
        Equivalent noise bandwidth [orders] (= ``resolution_orders``).
    segment_length : int
        Angle-domain samples per segment.
    spectrum : Spectrum
        The underlying spectrum, whose "frequency" axis is in orders.
    samples_per_rev : int
        Angular sampling.
    max_order : float
        Highest alias-free order.
    dims, coords : tuple, dict
        Names and coordinates of the channel dimensions (empty for one channel).
    reference : str
        Speed reference used.
    notes : tuple of str
        What was done beyond the request (standstill left out).
    """

    order: np.ndarray
    values: np.ndarray
    window: str
    amplitude: str
    resolution_orders: float
    bin_spacing_orders: float
    enbw_orders: float
    n_averages: int
    units: str
    spectrum: Spectrum
    samples_per_rev: int
    max_order: float
    segment_length: int = 0
    name: str = "x"
    dims: tuple[str, ...] = ()
    coords: dict[str, np.ndarray] = field(default_factory=dict)
    reference: str = ""
    notes: tuple[str, ...] = ()

    @property
    def scaling(self) -> str:
        """Deprecated name of :attr:`amplitude` (``"psd"`` for ``"density"``)."""
        warnings.warn(
            "OrderSpectrum.scaling is deprecated; use OrderSpectrum.amplitude",
            FutureWarning,
            stacklevel=2,
        )
        return "psd" if self.amplitude == "density" else self.amplitude

    def select(self, channel: Any) -> OrderSpectrum:
        """The order spectrum of one channel (a label of the channel coordinate, or an index)."""
        values, dims, coords, label = select_channel(self.values, self.dims, self.coords, channel)
        spec = self.spectrum.select(channel)
        name = f"{self.name} {label}" if self.name else label
        return dataclasses.replace(
            self, values=values, dims=dims, coords=coords, name=name, spectrum=spec
        )

    def to_dataset(self) -> xr.Dataset:
        """:class:`xarray.Dataset` with variable ``order_spectrum(*channels, order)``."""
        import xarray as xr

        long = {
            "peak": "peak amplitude order spectrum",
            "rms": "rms amplitude order spectrum",
            "power": "power order spectrum",
            "density": "power spectral density per order",
        }[self.amplitude]
        attrs: dict[str, Any] = {
            "window": self.window,
            "amplitude": self.amplitude,
            "resolution_orders": float(self.resolution_orders),
            "bin_spacing_orders": float(self.bin_spacing_orders),
            "enbw_orders": float(self.enbw_orders),
            "segment_length": int(self.segment_length),
            "n_averages": int(self.n_averages),
            "samples_per_rev": int(self.samples_per_rev),
            "max_order": float(self.max_order),
        }
        attrs.update(processing_attrs(self.reference, self.notes))
        ds = xr.Dataset(
            {
                "order_spectrum": (
                    (*self.dims, "order"),
                    self.values,
                    {"units": self.units, "long_name": f"{long} of {self.name}"},
                )
            },
            coords={
                "order": (
                    "order",
                    self.order,
                    {"units": "1", "long_name": "order (cycles per shaft revolution)"},
                ),
                **channel_coords(self.dims, self.coords),
            },
            attrs=attrs,
        )
        return cf_dataset(ds, title=f"{long} of {self.name}",
                          producer="analysis.orders.order_spectrum",
                          inputs={"signal": self.name, "speed_reference": self.reference})

    def peaks(self, **kwargs: Any) -> Peaks:
        """Peaks on the order axis (see :func:`analysis.spectrum.find_peaks`): ``Peaks.order``
        (variables ``order``, ``bin_order`` in its Dataset); ``min_distance_orders=``."""
        if "min_distance_orders" in kwargs:
            kwargs["min_distance_hz"] = kwargs.pop("min_distance_orders")
        return find_peaks(self.spectrum, **kwargs)

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure (see :func:`analysis.plots.order_spectrum_figure`)."""
        return order_spectrum_figure(self, **kwargs)


def order_spectrum(
    x: Any,
    fs: Any = None,
    rpm: Any = None,
    *,
    angle: Any = None,
    orders: Any = None,
    resolution: float | None = None,
    window: WindowSpec = "flattop",
    amplitude: Literal["peak", "rms", "power", "density"] | None = None,
    overlap: float = 0.5,
    samples_per_rev: int | None = None,
    max_order: float | None = None,
    min_rpm: float | None = None,
    time: Any = None,
    axis: int | None = None,
    units: str | None = None,
    name: str | None = None,
    block_size: int | None = None,
    orders_resolution: float | None = None,
    scaling: str | None = None,
) -> OrderSpectrum:
    """Averaged order spectrum of a signal measured at varying speed (MATLAB
    ``orderspectrum``).

    The signal is resampled to constant angle increments block by block and each block's
    segments are added to the (energy) average at once, so the angle-domain signal is never
    held whole: the working memory is a few blocks, whatever the length of the record.

    Parameters
    ----------
    x : array_like or xarray.DataArray
        One or several channels (see :mod:`analysis.inputs`).
    fs : float, optional
        Sample rate [Hz] (or give ``time``).
    rpm : array_like, optional
        Shaft speed [min-1] per sample.
    angle : array_like, optional
        Shaft angle [rad] per sample instead of ``rpm``.
    orders : array_like, optional
        Orders of interest (> 0); the default ``resolution`` resolves them.
    resolution : float, optional
        Resolution bandwidth [orders] (the window's ENBW, as in the maps): the segment spans
        ``ENBW_bins / resolution`` revolutions (rounded to whole samples; the values used are
        reported). Default ``min(1/4, d_min / 4, max_order / 64)`` with ``d_min`` the smallest
        distance between the ``orders`` and from the lowest to 0, coarsened where a segment
        would exceed 1/16 of the record (said in ``notes``); see
        :mod:`analysis.order_resolution`.
    window : str or tuple, default "flattop"
        Any :func:`scipy.signal.get_window` window (flat-top like MATLAB ``orderspectrum``).
    amplitude : {"peak", "rms", "power", "density"}, default "rms"
        Amplitude convention; ``"density"`` is power per order.
    overlap : float, default 0.5
        Segment overlap.
    samples_per_rev : int, optional
        Angular sampling; default ``2 ceil(1.28 max_order)`` when ``max_order`` is given,
        else so that the top speed is sampled at about ``fs``.
    max_order : float, optional
        Highest order to keep: the order axis ends there (default ``samples_per_rev / 2.56``,
        the highest alias-free order at about ``fs`` at the top speed).
    min_rpm : float, optional
        Standstill threshold [min-1] (default 2 % of the highest speed).
    time : array_like, optional
        Uniform sample instants [s].
    axis : int, optional
        Time axis of a multi-dimensional array.
    units, name : str, optional
        Metadata of ``x``.
    block_size : int, optional
        Angle-domain samples resampled per block (default 32768; a block always holds at
        least one segment). Only the working memory depends on it; the result equals that
        of a single block to rounding.
    orders_resolution : float, optional
        Deprecated: the old *line spacing* [orders] (segment of ``1 / orders_resolution``
        revolutions); use ``resolution`` (a bandwidth, like everywhere else).
    scaling : str, optional
        Deprecated name of ``amplitude``.

    Returns
    -------
    OrderSpectrum
        Energy-averaged order spectrum, shape ``(*channels, order)``, orders ``0`` to
        ``max_order``, with the resolution and line spacing actually used.
    """
    amp = amplitude_choice(amplitude, scaling, "order_spectrum", AMPLITUDES)
    fs, time = time_or_rate(fs, time, "order_spectrum")
    if orders_resolution is not None:
        if resolution is not None:
            raise ValueError("give resolution= only (orders_resolution= is deprecated)")
        warnings.warn(
            "order_spectrum: orders_resolution= (a line spacing) is deprecated and will be "
            "removed in the next release; use resolution= (the resolution bandwidth in orders, "
            "the window's ENBW, as in rpm_order_map and MATLAB)",
            FutureWarning,
            stacklevel=2,
        )
        spacing = float(orders_resolution)
        if not np.isfinite(spacing) or spacing <= 0:
            raise ValueError(f"orders_resolution = {orders_resolution!r} must be finite and > 0")
    resolution = optional_positive(resolution, "resolution", "orders")
    ords = requested_orders(orders)
    if not 0.0 <= float(overlap) < 1.0:
        raise ValueError(f"overlap = {overlap!r} is not admissible: must be in [0, 1)")
    lengths = tuple(np.shape(r)[0] for r in (rpm, angle) if r is not None and np.ndim(r) == 1)
    sig = signal_input(x, fs, time=time, axis=axis, units=units, name=name, lengths=lengths)
    ref = reference_input(rpm, angle, sig.n, required=True, signal=sig)
    assert ref is not None
    block = require_block_size(block_size)
    enbw_bins = window_info(window, 4096).enbw_bins  # also checks the window before the work
    tr = tracking(sig, ref, samples_per_rev, max_order, block, min_rpm, compact=True)
    resampler = tr.resampler
    spr = resampler.samples_per_rev
    m = resampler.n_out
    note = ""
    if orders_resolution is not None:
        seg, what = round(spr / spacing), f"orders_resolution = {spacing:g}"
    else:
        res, note = choose_order_resolution(
            resolution, ords, resampler.max_order, m / spr, enbw_bins
        )
        seg, what = round(enbw_bins * spr / res), f"resolution = {res:g} orders"
    if seg > m:
        raise ValueError(
            f"{what} needs {seg / spr:.4g} revolutions per segment, but the record has only "
            f"{m / spr:.4g}"
        )
    if seg < 4:
        raise ValueError(f"{what} is too coarse: segments of {seg} < 4 samples")
    step = max(1, round(seg * (1.0 - float(overlap))))
    n_seg = (m - seg) // step + 1
    kind: Amplitude = "density" if amp == "density" else "power"
    total = np.zeros((*sig.lead, seg // 2 + 1))
    values = np.empty(0)
    for k0, k1 in frame_ranges(n_seg, seg, step, block):
        values, _ = resampler.block(k0 * step, (k1 - 1) * step + seg)
        part = spectrum(
            values, float(spr), window=window, amplitude=kind, segment_length=seg,
            overlap=overlap, axis=-1,
        )  # fmt: skip
        total += part.values * part.n_averages
    total /= n_seg
    if amp in ("rms", "peak"):
        np.sqrt(total, out=total)
        if amp == "peak":
            total *= np.sqrt(line_factors(total.shape[-1], seg))
    # metadata (window label, ENBW...) from the last block in the requested convention
    last = spectrum(
        values, float(spr), window=window, amplitude=amp, segment_length=seg, overlap=overlap,
        axis=-1, units=sig.units, name=sig.name,
    )  # fmt: skip
    # the order axis ends at max_order (above it the anti-alias filter attenuates)
    n_lines = max(2, int(np.searchsorted(last.frequency, resampler.max_order * (1 + 1e-9),
                                         side="right")))  # fmt: skip
    s = dataclasses.replace(
        last,
        frequency=last.frequency[:n_lines],
        values=total[..., :n_lines],
        n_averages=n_seg,
        dims=sig.dims,
        coords=sig.coords,
        units=units_of(sig.units, amp, per=""),
        axis="order",
    )
    return OrderSpectrum(
        order=s.frequency,
        values=s.values,
        window=s.window,
        amplitude=amp,
        resolution_orders=s.enbw_hz,
        bin_spacing_orders=s.bin_spacing_hz,
        enbw_orders=s.enbw_hz,
        n_averages=s.n_averages,
        units=s.units,
        spectrum=s,
        samples_per_rev=spr,
        max_order=resampler.max_order,
        segment_length=seg,
        name=sig.name,
        dims=sig.dims,
        coords=sig.coords,
        reference=ref.label,
        notes=(*tr.notes, note) if note else tr.notes,
    )


# -------------------------------------------------------------------------------- order cuts


@dataclass
class OrderCut:
    """Level of chosen orders vs time and speed (MATLAB ``ordertrack``, map-based).

    Attributes
    ----------
    orders : numpy.ndarray
        Tracked orders.
    time : numpy.ndarray
        Frame centres [s].
    rpm : numpy.ndarray
        Speed at the frame centres [min-1].
    values : numpy.ndarray
        Level, shape ``(*channels, order, time)``; NaN where the band leaves the analysed
        range.
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
        The frames the cut was read from (``"RpmOrderMap"`` or ``"RpmFrequencyMap"``).
    window : str
        Window of those frames.
    level_reference : str
        Reference of the dB scale (``"1 <units>"``), or ``""`` for linear.
    resolution : float
        Resolution bandwidth (ENBW) of the frames, in ``resolution_units``.
    resolution_units : str
        ``"1"`` (orders, order frames) or ``"Hz"`` (frequency frames).
    segment_length : int
        Frame length in samples (angle-domain samples for order frames).
    samples_per_rev : int
        Angular sampling of order frames (0 for frequency frames: no resampling).
    overlap : float
        Frame overlap.
    dims, coords : tuple, dict
        Names and coordinates of the channel dimensions (empty for one channel).
    reference : str
        Speed reference used.
    notes : tuple of str
        What was done beyond the request (standstill left out).
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
    resolution: float = 0.0
    resolution_units: str = "1"
    segment_length: int = 0
    samples_per_rev: int = 0
    overlap: float = 0.0
    dims: tuple[str, ...] = ()
    coords: dict[str, np.ndarray] = field(default_factory=dict)
    reference: str = ""
    notes: tuple[str, ...] = ()

    def select(self, channel: Any) -> OrderCut:
        """The cuts of one channel (a label of the channel coordinate, or an index)."""
        values, dims, coords, label = select_channel(self.values, self.dims, self.coords, channel)
        name = f"{self.name} {label}" if self.name else label
        return dataclasses.replace(self, values=values, dims=dims, coords=coords, name=name)

    def to_dataset(self) -> xr.Dataset:
        """Dataset with ``level(*channels, order, time)`` and auxiliary coordinate
        ``rpm(time)``."""
        import xarray as xr

        long = f"{self.amplitude} level of {self.name} in the order band"
        if self.scale == "dB":
            long += f" (dB re {self.level_reference})"
        attrs: dict[str, Any] = {
            "amplitude": self.amplitude,
            "scale": self.scale,
            "bandwidth": float(self.bandwidth),
            "bandwidth_kind": self.bandwidth_kind,
            "cut_source": self.source,
            "window": self.window,
            "resolution": float(self.resolution),
            "resolution_units": self.resolution_units,
            "segment_length": int(self.segment_length),
            "samples_per_rev": int(self.samples_per_rev),
            "overlap": float(self.overlap),
        }
        attrs.update(processing_attrs(self.reference, self.notes))
        ds = xr.Dataset(
            {
                "level": (
                    (*self.dims, "order", "time"),
                    self.values,
                    {"units": self.units, "long_name": long},
                )
            },
            coords={
                "order": ("order", self.orders, {"units": "1", "long_name": "tracked order"}),
                **frame_coords(self.time, self.rpm),
                **channel_coords(self.dims, self.coords),
            },
            attrs=attrs,
        )
        return cf_dataset(ds, title=f"order cuts of {self.name}",
                          producer="analysis.orders.order_cuts",
                          inputs={"signal": self.name, "speed_reference": self.reference})

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
    if orders is None:
        raise ValueError("orders (the orders to track, > 0) are required")
    ords = requested_orders(orders)
    assert ords is not None
    bandwidth = optional_positive(bandwidth, "bandwidth", "orders")
    bandwidth_hz = optional_positive(bandwidth_hz, "bandwidth_hz", "Hz")
    if bandwidth is not None and bandwidth_hz is not None:
        raise ValueError("give either bandwidth (orders) or bandwidth_hz (Hz), not both")
    spacing = float(axis[1] - axis[0])
    if bandwidth is None and bandwidth_hz is None:
        kind = "Hz" if is_freq else "order"
        bw = main_lobe_band(main_lobe_half_width(window), spacing)
    elif bandwidth is not None:
        kind, bw = "order", bandwidth
    else:
        assert bandwidth_hz is not None  # one of the two is given here
        kind, bw = "Hz", float(bandwidth_hz)
    return ords, kind, bw, spacing


def _require_analysed(ords: np.ndarray, top: float, where: str) -> None:
    """Raise for orders above the highest analysed order ``top`` (a band whose edge only
    leaves the axis reads NaN, as documented)."""
    if np.any(ords > top):
        raise ValueError(
            f"orders: {ords[ords > top].tolist()[:5]} lie above the highest analysed order "
            f"({top:.6g}{where}); admissible: orders <= that (raise max_order or "
            "samples_per_rev; for bandwidth_hz, fs)"
        )


def _warn_overlaps(
    ords: np.ndarray,
    kind: str,
    bw: float,
    is_freq: bool,
    spacing: float,
    window: WindowSpec,
    rpm: np.ndarray,
    lines: list[tuple[str, float]],
    resolution: float,
) -> None:
    """:class:`OrderBandWarning` where a band reaches another order's main lobe.

    Bands and main lobes fixed in Hz are widest in orders at the slowest frame (frames below
    2 % of the top speed, standstill, are not counted).
    """
    moving = rpm[np.isfinite(rpm) & (rpm > 0)]
    if not moving.size:
        return
    f_lo = float(moving[moving >= 0.02 * moving.max()].min()) / 60.0
    half = 0.5 * bw / (f_lo if kind == "Hz" else 1.0)
    lobe = main_lobe_half_width(window) * spacing / (f_lo if is_freq else 1.0)
    res_units = "Hz" if is_freq else "orders"
    what = (f"band {bw:.4g} {'orders' if kind == 'order' else 'Hz'}, frames of resolution "
            f"{resolution:.4g} {res_units}")  # fmt: skip
    if kind == "Hz" or is_freq:
        what += f", at {60.0 * f_lo:.5g} min-1"
    check_bands(ords, half, lobe, lines, what=what, stacklevel=4)


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
    """Power in the order bands, shape ``(*channels, order, frame)``, of map lines
    ``power(*channels, frame, line)``.

    ``rpm`` is the speed of each frame; NaN where the band exceeds ``axis``.
    """
    if power.ndim > 2:
        out = np.empty((*power.shape[:-2], ords.size, power.shape[-2]))
        for ch in np.ndindex(*power.shape[:-2]):
            out[ch] = _band_power(power[ch], rpm, axis, ords, kind, bw, is_freq, enbw_bins)
        return out
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


def _levels(band: np.ndarray, amplitude: str, scale: str, signal_units: str) -> tuple:
    """Levels, units and dB reference from the band powers."""
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
    return vals, units, ref


def order_cuts_from_map(
    m: RpmFrequencyMap | RpmOrderMap,
    orders: Any,
    *,
    bandwidth: float | None = None,
    bandwidth_hz: float | None = None,
    amplitude: Literal["rms", "peak", "power"] = "rms",
    scale: Literal["linear", "dB"] = "linear",
    lines: Any = None,
) -> OrderCut:
    """Order cuts read from an rpm-frequency or rpm-order map by summing the lines in a band.

    The level of the band is ``sqrt(sum_k G_k / ENBW_bins)`` (rms; Brandt 2011, sec. 10.3),
    where ``G_k`` is the map's power per line: for a sinusoid whose main lobe lies inside
    the band this is its rms value whatever the window and the bin offset.

    Parameters
    ----------
    m : RpmFrequencyMap or RpmOrderMap
        Map of any amplitude/scale and any number of channels (converted back to power
        internally, a block of frames at a time).
    orders : array_like
        Orders to track (> 0).
    bandwidth : float, optional
        Proportional band width in orders (band ``order +- bandwidth/2``).
    bandwidth_hz : float, optional
        Fixed band width in Hz (exclusive with ``bandwidth``).
        Default (neither given): the window's main-lobe width ``2 h`` lines (``h`` = 2 for
        Hann, 5 for flat-top; ``2.67`` resolution bandwidths for both), in the map's own axis
        (fixed Hz on a frequency map, proportional on an order map).
    amplitude : {"rms", "peak", "power"}, default "rms"
        Convention of the result.
    scale : {"linear", "dB"}, default "linear"
        Linear or dB re 1 unit.
    lines : mapping or sequence of (str, float), optional
        Named catalogue lines ``{name: order}`` (e.g. ``dict(zip(cat.formula, cat.order))``
        of a :class:`analysis.catalogue.KinematicCatalogue`). A line at a requested order
        names it in messages; a line elsewhere inside a band is warned about.

    Returns
    -------
    OrderCut
        Levels ``(*channels, order, time)``; NaN where the band exceeds the map's axis.

    Warns
    -----
    OrderBandWarning
        A band reaches the main lobe of another requested order or of a line (the cut holds
        both); the message names both, with their orders.
    """
    if not isinstance(m, RpmFrequencyMap | RpmOrderMap):
        raise ValueError("m must be an RpmFrequencyMap or RpmOrderMap")
    is_freq = isinstance(m, RpmFrequencyMap)
    axis = m.frequency if isinstance(m, RpmFrequencyMap) else m.order
    ords, kind, bw, spacing = _cut_setup(
        m.window_spec, axis, is_freq, orders, bandwidth, bandwidth_hz, amplitude, scale
    )
    named = named_lines(lines)
    lead = m.values.shape[:-2]
    n_frames = m.values.shape[-2]
    band = np.empty((*lead, ords.size, n_frames))
    rows = max(1, BLOCK_ELEMENTS // max(1, m.values.shape[-1]))
    for ch in np.ndindex(*lead):
        for r0 in range(0, n_frames, rows):
            sl = slice(r0, r0 + rows)
            power = power_of(m.values[ch][sl], m.amplitude, m.scale, m.segment_length)
            band[ch][:, sl] = _band_power(
                power, m.rpm[sl], axis, ords, kind, bw, is_freq, m.enbw_bins
            )
    resolution = m.resolution_hz if isinstance(m, RpmFrequencyMap) else m.resolution_orders
    _warn_overlaps(ords, kind, bw, is_freq, spacing, m.window_spec, m.rpm, named, resolution)
    vals, units, ref = _levels(band, amplitude, scale, m.signal_units)
    return OrderCut(
        orders=ords,
        time=m.time.copy(),
        rpm=m.rpm.copy(),
        values=vals,
        amplitude=amplitude,
        scale=scale,
        units=units,
        bandwidth=bw,
        bandwidth_kind=kind,
        source=type(m).__name__,
        window=m.window,
        level_reference=ref,
        name=m.name,
        resolution=resolution,
        resolution_units="Hz" if is_freq else "1",
        segment_length=m.segment_length,
        samples_per_rev=m.samples_per_rev if isinstance(m, RpmOrderMap) else 0,
        overlap=m.overlap,
        dims=m.dims,
        coords=m.coords,
        reference=m.reference,
        notes=m.notes,
    )


def order_cuts(
    x: Any,
    fs: Any = None,
    rpm: Any = None,
    orders: Any = None,
    *,
    angle: Any = None,
    bandwidth: float | None = None,
    bandwidth_hz: float | None = None,
    amplitude: Literal["rms", "peak", "power"] = "rms",
    scale: Literal["linear", "dB"] = "linear",
    lines: Any = None,
    **map_kwargs: Any,
) -> OrderCut:
    """Order cuts (level of chosen orders vs rpm) directly from a signal (MATLAB
    ``ordertrack``, map-based).

    With ``bandwidth_hz`` (fixed band) the cut is read from the frames of :func:`analysis.
    maps.rpm_frequency_map`; otherwise (proportional band, ``bandwidth`` in orders, default
    the window's main lobe) from those of :func:`analysis.maps.rpm_order_map`. The frames are
    computed and summed into the bands a block at a time, so neither the map nor the
    angle-domain signal is ever held whole.

    **Defaults resolve the requested orders** (:mod:`analysis.order_resolution`): the order
    resolution is ``min(1/4, d_min / 4)`` orders, ``d_min`` the smallest distance between
    the requested orders and from the lowest to order 0 (fixed-Hz frames: that many orders of
    the slowest shaft frequency), coarsened where a frame would exceed 1/16 of the record
    (``notes`` says so); the band is the window's main lobe (``2.67`` resolutions), so
    neighbouring requested orders never share a band; ``max_order`` is
    ``1.25 (max(orders) + band / 2)``, where the angular resampling is flat to 0.01 dB.

    Parameters
    ----------
    x, fs, rpm
        Signal (one or several channels, see :mod:`analysis.inputs`), sample rate [Hz] (or
        ``time``) and speed [min-1].
    orders : array_like
        Orders to track (> 0).
    angle : array_like, optional
        Shaft angle [rad] per sample instead of ``rpm`` (more accurate for a tacho).
    bandwidth, bandwidth_hz, amplitude, scale, lines
        As in :func:`order_cuts_from_map`.
    **map_kwargs
        Passed on as to the map function: ``window``, ``resolution``, ``overlap``, ``time``,
        ``axis``, ``units``, ``name``; for the order map also ``samples_per_rev``,
        ``max_order``, ``min_rpm``; and ``block_size`` (samples per block, default 32768, of
        the time signal for a fixed band and of the angle-domain signal otherwise; the result
        does not depend on it beyond rounding).

    Returns
    -------
    OrderCut
        See :func:`order_cuts_from_map`; it reports the resolution, band width, frame length
        and angular sampling actually used (also in its Dataset's attributes).

    Warns
    -----
    OrderBandWarning
        A band reaches the main lobe of another requested order or of a line.
    """
    fs, time = time_or_rate(fs, map_kwargs.pop("time", None), "order_cuts")
    is_freq = bandwidth_hz is not None
    if orders is None:
        raise ValueError("orders (the orders to track, > 0) are required")
    ords_in = requested_orders(orders)
    if is_freq:
        for key in ("samples_per_rev", "max_order", "min_rpm"):
            if map_kwargs.get(key) is not None:
                raise ValueError(f"{key} is for proportional bands (order frames); "
                                 "bandwidth_hz reads frequency frames")
            map_kwargs.pop(key, None)
        plan: FrequencyPlan | OrderPlan = frequency_plan(
            x, fs, rpm, angle=angle, time=time, orders=ords_in, **map_kwargs
        )
    else:
        band0 = optional_positive(bandwidth, "bandwidth", "orders")
        plan = order_plan(
            x, fs, rpm, angle=angle, time=time, orders=ords_in,
            band=0.0 if band0 is None else band0, **map_kwargs,
        )  # fmt: skip
    axis = plan.axis
    ords, kind, bw, spacing = _cut_setup(
        plan.window, axis, is_freq, orders, bandwidth, bandwidth_hz, amplitude, scale
    )
    if (kind == "Hz") == is_freq and bw < spacing:  # constant band: check before the work
        raise ValueError(
            f"bandwidth ({bw:g} {kind}) is narrower than the map's line spacing somewhere "
            "(the band would hold no line); widen it or use a finer map"
        )
    if not is_freq:
        _require_analysed(ords, float(axis[-1]), "")
    named = named_lines(lines)
    sig = plan.signal
    rows = min(plan.n_frames, plan.block // plan.step + 1)
    require_size(
        8.0 * np.prod(sig.lead, dtype=float) * (ords.size * plan.n_frames + rows * axis.size),
        f"the cuts ({ords.size} orders x {plan.n_frames} frames)", "orders, resolution, x",
    )
    band = np.empty((*sig.lead, ords.size, plan.n_frames))
    tc = np.empty(plan.n_frames)
    rc = np.empty(plan.n_frames)
    for k0, k1, samples, t_blk, r_blk in plan.blocks():
        power = np.empty((*sig.lead, k1 - k0, axis.size))
        stft_into(samples, plan.w, plan.step, power, "power", "linear")
        band[..., k0:k1] = _band_power(
            power, r_blk, axis, ords, kind, bw, is_freq, plan.info.enbw_bins
        )
        tc[k0:k1], rc[k0:k1] = t_blk, r_blk
    if is_freq:
        _require_analysed(ords, float(axis[-1]) * 60.0 / max(float(rc.min()), 1e-300),
                          " at the slowest frame")
    resolution = plan.info.enbw_hz(plan.rate)
    _warn_overlaps(ords, kind, bw, is_freq, spacing, plan.window, rc, named, resolution)
    vals, units, ref = _levels(band, amplitude, scale, sig.units)
    spr = 0 if is_freq else int(plan.rate)
    return OrderCut(
        orders=ords,
        time=tc,
        rpm=rc,
        values=vals,
        amplitude=amplitude,
        scale=scale,
        units=units,
        bandwidth=bw,
        bandwidth_kind=kind,
        source="RpmFrequencyMap" if is_freq else "RpmOrderMap",
        window=plan.info.label,
        level_reference=ref,
        name=sig.name,
        resolution=resolution,
        resolution_units="Hz" if is_freq else "1",
        segment_length=plan.seg,
        samples_per_rev=spr,
        overlap=float(map_kwargs.get("overlap", 0.5)),
        dims=sig.dims,
        coords=sig.coords,
        reference=plan.reference,
        notes=plan.notes,
    )
