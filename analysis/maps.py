"""Rpm-frequency and rpm-order maps (sonograms of run-ups), overall level and Campbell data.

Both maps are short-time spectra; each frame is one line of the map, reported at its centre
(time, and the speed interpolated there), as MATLAB ``rpmfreqmap``/``rpmordermap`` do.

**Resolution** follows MATLAB's definition: ``resolution`` is the *resolution bandwidth*
(the window's equivalent noise bandwidth), so the window length is
``L = round(ENBW_bins * fs / resolution)`` and the value actually used,
``ENBW_bins * fs / L``, is reported as ``resolution_hz``/``resolution_orders`` together with
the line spacing ``fs / L``. Defaults (:mod:`analysis.order_resolution`): for the frequency
map a quarter of the slowest shaft frequency of the record [Hz] (no finer than the run-up's
sweep allows, frames of at most 1/16 of the record) with a Hann window; for the order map
``min(1/4, d_min / 4, max_order / 64)`` orders (``d_min``: the smallest distance between
the ``orders`` of interest and from the lowest to order 0) with a flat-top window, its order
axis ending at ``max_order``; 50 % overlap; rms amplitude; linear scale.

**Memory.** Frames are windowed and transformed block-wise straight into the preallocated
output (a few MB of temporaries), so a 10-minute, 51.2 kHz channel needs little more than
the map itself. The input may be float32; it is promoted per block. The order map resamples
the signal to constant angle block by block as well (``block_size``, see
:mod:`analysis.orders`) and never holds the angle-domain signal.

**Amplitude** of a line: ``"power"`` ``2|X|^2/S1^2`` (a sine on a line reads ``A^2/2``),
``"rms"`` its square root, ``"peak"`` ``sqrt(2)`` times that (DC and Nyquist not doubled).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal, Self

import numpy as np

from analysis.cf import cf_dataset, processing_attrs
from analysis.checks import require_choice, require_finite, require_size
from analysis.frames import BLOCK_ELEMENTS, frame_coords, frequency_plan, order_plan, stft_into
from analysis.inputs import channel_coords, dataset_reference, dataset_variable, select_channel
from analysis.levels import power_of, to_db
from analysis.plots import (
    campbell_figure,
    overall_level_figure,
    rpm_frequency_map_figure,
    rpm_order_map_figure,
)
from analysis.windows import WindowSpec

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

__all__ = [
    "Campbell",
    "OverallLevel",
    "RpmFrequencyMap",
    "RpmOrderMap",
    "campbell",
    "overall_level",
    "overall_level_from_map",
    "rpm_frequency_map",
    "rpm_frequency_map_ds",
    "rpm_order_map",
    "rpm_order_map_ds",
]

_AMPLITUDES = ("rms", "peak", "power")
_SCALES = ("linear", "dB")


@dataclass
class _MapBase:
    time: np.ndarray
    rpm: np.ndarray
    values: np.ndarray
    window: str
    window_spec: WindowSpec
    amplitude: str
    scale: str
    enbw_bins: float
    overlap: float
    segment_length: int
    signal_units: str
    name: str
    dims: tuple[str, ...] = ()
    coords: dict[str, np.ndarray] = field(default_factory=dict)
    reference: str = ""
    notes: tuple[str, ...] = ()

    @property
    def _level_units(self) -> str:
        """Units of a linear level: the signal's, squared for ``power``."""
        if self.amplitude == "power" and self.signal_units != "1":
            return f"({self.signal_units})^2"
        return self.signal_units

    @property
    def units(self) -> str:
        """Units of ``values`` (``"1"`` for dB levels)."""
        return "1" if self.scale == "dB" else self._level_units

    @property
    def level_reference(self) -> str:
        """Reference of the dB levels (e.g. ``"1 m s-2"``)."""
        return f"1 {self._level_units}"

    def power(self) -> np.ndarray:
        """Map converted back to power per line (``A^2/2`` for a sine on a line)."""
        return power_of(self.values, self.amplitude, self.scale, self.segment_length)

    def select(self, channel: Any) -> Self:
        """The map of one channel (a label of the channel coordinate, or an index)."""
        values, dims, coords, label = select_channel(self.values, self.dims, self.coords, channel)
        name = f"{self.name} {label}" if self.name else label
        return dataclasses.replace(self, values=values, dims=dims, coords=coords, name=name)

    def _axis(self) -> tuple[str, np.ndarray, dict[str, str]]:
        raise NotImplementedError

    def _attrs(self) -> dict[str, Any]:
        raise NotImplementedError

    def to_dataset(self) -> xr.Dataset:
        """Dataset with ``amplitude(*channels, time, <axis>)`` and auxiliary coordinate
        ``rpm(time)``."""
        import xarray as xr

        name, axis, axis_attrs = self._axis()
        frame = frame_coords(
            self.time, self.rpm, "shaft speed at frame centre (revolutions per minute)"
        )
        long = f"{self.amplitude} amplitude of {self.name}"
        if self.amplitude == "power":
            long = f"power per line of {self.name}"
        if self.scale == "dB":
            long += f" (dB re {self.level_reference})"
        ds = xr.Dataset(
            {
                "amplitude": (
                    (*self.dims, "time", name),
                    self.values,
                    {"units": self.units, "long_name": long},
                )
            },
            coords={
                "time": frame["time"],
                name: (name, axis, axis_attrs),
                "rpm": frame["rpm"],
                **channel_coords(self.dims, self.coords),
            },
        )
        ds.attrs.update(
            window=self.window,
            amplitude=self.amplitude,
            scale=self.scale,
            overlap=float(self.overlap),
            segment_length=int(self.segment_length),
            **self._attrs(),
        )
        ds.attrs.update(processing_attrs(self.reference, self.notes))
        kind = "rpm_order_map" if name == "order" else "rpm_frequency_map"
        return cf_dataset(ds, title=f"run-up {name} map of {self.name}",
                          producer=f"analysis.maps.{kind}",
                          inputs={"signal": self.name, "speed_reference": self.reference})


@dataclass
class RpmFrequencyMap(_MapBase):
    """Short-time spectra of a run-up vs frequency, with the speed of each frame.

    Attributes
    ----------
    time, rpm : numpy.ndarray
        Frame centres [s] and speed there [min-1].
    frequency : numpy.ndarray
        Line frequencies [Hz].
    values : numpy.ndarray
        Map, shape ``(*channels, time, frequency)``.
    resolution_hz : float
        Resolution bandwidth actually used (``ENBW_bins * fs / L``), as MATLAB's ``res``.
    bin_spacing_hz : float
        Line spacing ``fs / L``.
    enbw_hz : float
        Equivalent noise bandwidth [Hz] (equal to ``resolution_hz``).
    fs : float
        Sample rate [Hz].
    dims, coords : tuple, dict
        Names and coordinates of the channel dimensions (empty for one channel).
    reference : str
        Speed reference used.
    notes : tuple of str
        What was done beyond the request.
    """

    # always given: the default only follows the defaults of the base class's fields
    frequency: np.ndarray = None  # type: ignore[assignment]
    resolution_hz: float = 0.0
    bin_spacing_hz: float = 0.0
    enbw_hz: float = 0.0
    fs: float = 0.0

    def _axis(self) -> tuple[str, np.ndarray, dict[str, str]]:
        return "frequency", self.frequency, {"units": "Hz", "long_name": "frequency"}

    def _attrs(self) -> dict[str, Any]:
        return {
            "resolution_hz": float(self.resolution_hz),
            "bin_spacing_hz": float(self.bin_spacing_hz),
            "enbw_hz": float(self.enbw_hz),
            "sample_rate_hz": float(self.fs),
        }

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Sonogram figure (see :func:`analysis.plots.rpm_frequency_map_figure`)."""
        return rpm_frequency_map_figure(self, **kwargs)


@dataclass
class RpmOrderMap(_MapBase):
    """Short-time order spectra (angle domain) of a run-up, with the speed of each frame.

    Attributes
    ----------
    order : numpy.ndarray
        Line orders.
    values : numpy.ndarray
        Map, shape ``(*channels, time, order)``.
    resolution_orders : float
        Resolution bandwidth actually used [orders] (``ENBW_bins * spr / L``).
    bin_spacing_orders : float
        Line spacing ``spr / L`` [orders].
    enbw_orders : float
        Equivalent noise bandwidth [orders].
    samples_per_rev : int
        Angular sampling.
    max_order : float
        Highest alias-free order.
    """

    # always given: the default only follows the defaults of the base class's fields
    order: np.ndarray = None  # type: ignore[assignment]
    resolution_orders: float = 0.0
    bin_spacing_orders: float = 0.0
    enbw_orders: float = 0.0
    samples_per_rev: int = 0
    max_order: float = 0.0

    def _axis(self) -> tuple[str, np.ndarray, dict[str, str]]:
        return "order", self.order, {"units": "1", "long_name": "order (cycles per revolution)"}

    def _attrs(self) -> dict[str, Any]:
        return {
            "resolution_orders": float(self.resolution_orders),
            "bin_spacing_orders": float(self.bin_spacing_orders),
            "enbw_orders": float(self.enbw_orders),
            "samples_per_rev": int(self.samples_per_rev),
            "max_order": float(self.max_order),
        }

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure (see :func:`analysis.plots.rpm_order_map_figure`)."""
        return rpm_order_map_figure(self, **kwargs)


def rpm_frequency_map(
    x: Any,
    fs: float | None = None,
    rpm: Any = None,
    *,
    angle: Any = None,
    resolution: float | None = None,
    window: WindowSpec = "hann",
    overlap: float = 0.5,
    amplitude: Literal["rms", "peak", "power"] = "rms",
    scale: Literal["linear", "dB"] = "linear",
    time: Any = None,
    axis: int | None = None,
    units: str | None = None,
    name: str | None = None,
) -> RpmFrequencyMap:
    """Rpm-frequency map (sonogram), MATLAB ``rpmfreqmap``.

    Parameters
    ----------
    x : array_like or xarray.DataArray
        One or several channels, float32 or float64 (see :mod:`analysis.inputs`).
    fs : float, optional
        Sample rate [Hz]; may be omitted when ``time`` is given or ``x`` is a DataArray.
    rpm : array_like, optional
        Speed [min-1], one value per sample.
    angle : array_like, optional
        Shaft angle [rad] per sample instead of ``rpm``; the speed of a frame is then the
        angle it spans over its duration.
    resolution : float, optional
        Resolution bandwidth [Hz] (= ENBW of the window). Default
        ``max(f_min / 4, sqrt(ENBW_lines (f_max - f_min) / duration),
        ENBW_lines * 16 / duration)`` from the slowest and fastest shaft frequency of the
        moving record (below 2 % of the top speed is standstill) and its duration: a quarter
        order at the slowest speed, no finer than order 1's sweep over a frame, frames of at
        most 1/16 of the record (:func:`analysis.order_resolution.
        default_frequency_resolution`). MATLAB's default is ``resolution=fs / 128``.
    window : str or tuple, default "hann"
        Any :func:`scipy.signal.get_window` window (MATLAB's default is Hann).
    overlap : float, default 0.5
        Frame overlap fraction in ``[0, 1)``.
    amplitude : {"rms", "peak", "power"}, default "rms"
        Convention per line.
    scale : {"linear", "dB"}, default "linear"
        dB is re 1 unit (``20 log10`` for amplitudes, ``10 log10`` for power).
    time : array_like, optional
        Uniform time axis [s] (gives the frame times; must agree with ``fs``).
    axis : int, optional
        Time axis of a multi-dimensional array.
    units, name : str, optional
        Metadata of ``x``.

    Returns
    -------
    RpmFrequencyMap
        Map ``(*channels, time, frequency)`` with speed per frame and the resolution actually
        used.
    """
    require_choice(amplitude, _AMPLITUDES, "amplitude")
    require_choice(scale, _SCALES, "scale")
    p = frequency_plan(
        x, fs, rpm, angle=angle, resolution=resolution, window=window, overlap=overlap,
        time=time, axis=axis, units=units, name=name,
    )  # fmt: skip
    sig = p.signal
    require_size(
        8.0 * np.prod(sig.lead, dtype=float) * p.n_frames * p.axis.size,
        f"the map ({p.n_frames} frames x {p.axis.size} lines)", "resolution, overlap, x",
    )
    out = np.empty((*sig.lead, p.n_frames, p.axis.size))
    stft_into(p.x, p.w, p.step, out, amplitude, scale)
    tc, rc = p.frame_speeds(0, p.n_frames)
    return RpmFrequencyMap(
        time=tc,
        rpm=rc,
        values=out,
        window=p.info.label,
        window_spec=window,
        amplitude=amplitude,
        scale=scale,
        enbw_bins=p.info.enbw_bins,
        overlap=float(overlap),
        segment_length=p.seg,
        signal_units=sig.units,
        name=sig.name,
        dims=sig.dims,
        coords=sig.coords,
        reference=p.reference,
        frequency=p.axis,
        resolution_hz=p.info.enbw_hz(p.rate),
        bin_spacing_hz=p.rate / p.seg,
        enbw_hz=p.info.enbw_hz(p.rate),
        fs=p.rate,
    )


def rpm_order_map(
    x: Any,
    fs: float | None = None,
    rpm: Any = None,
    *,
    angle: Any = None,
    orders: Any = None,
    resolution: float | None = None,
    window: WindowSpec = "flattop",
    overlap: float = 0.5,
    amplitude: Literal["rms", "peak", "power"] = "rms",
    scale: Literal["linear", "dB"] = "linear",
    samples_per_rev: int | None = None,
    max_order: float | None = None,
    min_rpm: float | None = None,
    time: Any = None,
    axis: int | None = None,
    units: str | None = None,
    name: str | None = None,
    block_size: int | None = None,
) -> RpmOrderMap:
    """Rpm-order map by computed order tracking (angular resampling, then short-time spectra),
    MATLAB ``rpmordermap``.

    The signal is resampled to constant angle increments block by block and each block's
    frames go straight into the map, so the angle-domain signal is never held whole: the
    memory needed beyond the map is a few blocks, whatever the length of the record.

    Parameters
    ----------
    x : array_like or xarray.DataArray
        One or several channels (see :mod:`analysis.inputs`).
    fs : float, optional
        Sample rate [Hz] (or give ``time``).
    rpm : array_like, optional
        Speed [min-1] per sample (integrated to the angle).
    angle : array_like, optional
        Shaft angle [rad] per sample instead of ``rpm`` (more accurate for a tacho).
    orders : array_like, optional
        Orders of interest (> 0); the default ``resolution`` resolves them.
    resolution : float, optional
        Resolution bandwidth [orders] (= window ENBW). Default
        ``min(1/4, d_min / 4, max_order / 64)``, ``d_min`` the smallest distance between the
        ``orders`` and from the lowest to order 0: orders four resolutions apart have
        separate main lobes (a frame spans ``ENBW_lines / resolution`` revolutions, 15 for
        the flat-top window at 1/4 order); coarsened where a frame would exceed 1/16 of the
        record (``notes`` says so). MATLAB's default is ``samples_per_rev / 256``.
    window : str or tuple, default "flattop"
        Any :func:`scipy.signal.get_window` window (MATLAB's default is flat-top).
    overlap : float, default 0.5
        Frame overlap in the angle domain.
    amplitude, scale : str
        As in :func:`rpm_frequency_map`.
    samples_per_rev : int, optional
        Angular sampling; default ``2 ceil(1.28 max_order)`` when ``max_order`` is given, else
        ``2 * ceil(fs / 2 / f_shaft,max)`` (about ``fs`` at the top speed).
    max_order : float, optional
        Highest alias-free order, where the order axis ends (default
        ``samples_per_rev / 2.56``).
    min_rpm : float, optional
        Standstill threshold [min-1] (default 2 % of the highest speed): slower samples at
        the start and end are left out and ``notes`` says so.
    time : array_like, optional
        Uniform time axis [s].
    axis : int, optional
        Time axis of a multi-dimensional array.
    units, name : str, optional
        Metadata of ``x``.
    block_size : int, optional
        Angle-domain samples resampled per block (default 32768; a block always holds at
        least one frame). Only the working memory depends on it; the map equals that of a
        single block to rounding.

    Returns
    -------
    RpmOrderMap
        Map ``(*channels, time, order)``, orders ``0`` to ``max_order``; time and speed at
        the angle-frame centres; the resolution and line spacing actually used.
    """
    require_choice(amplitude, _AMPLITUDES, "amplitude")
    require_choice(scale, _SCALES, "scale")
    p = order_plan(
        x, fs, rpm, angle=angle, resolution=resolution, window=window, overlap=overlap,
        samples_per_rev=samples_per_rev, max_order=max_order, time=time, axis=axis,
        min_rpm=min_rpm, units=units, name=name, block_size=block_size, orders=orders,
    )  # fmt: skip
    sig = p.signal
    require_size(
        8.0 * np.prod(sig.lead, dtype=float) * p.n_frames * p.axis.size,
        f"the map ({p.n_frames} frames x {p.axis.size} lines)", "resolution, overlap, x",
    )
    out = np.empty((*sig.lead, p.n_frames, p.axis.size))
    tc = np.empty(p.n_frames)
    rc = np.empty(p.n_frames)
    for k0, k1, samples, t_blk, r_blk in p.blocks():
        stft_into(samples, p.w, p.step, out[..., k0:k1, :], amplitude, scale)
        tc[k0:k1], rc[k0:k1] = t_blk, r_blk
    spr = p.resampler.samples_per_rev
    return RpmOrderMap(
        time=tc,
        rpm=rc,
        values=out,
        window=p.info.label,
        window_spec=window,
        amplitude=amplitude,
        scale=scale,
        enbw_bins=p.info.enbw_bins,
        overlap=float(overlap),
        segment_length=p.seg,
        signal_units=sig.units,
        name=sig.name,
        dims=sig.dims,
        coords=sig.coords,
        reference=p.reference,
        notes=p.notes,
        order=p.axis,
        resolution_orders=p.info.enbw_hz(spr),
        bin_spacing_orders=spr / p.seg,
        enbw_orders=p.info.enbw_hz(spr),
        samples_per_rev=spr,
        max_order=p.resampler.max_order,
    )


def rpm_frequency_map_ds(
    ds: Any, variable: str, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
) -> RpmFrequencyMap:
    """:func:`rpm_frequency_map` of ``ds[variable]`` against a speed or angle of ``ds``.

    Parameters
    ----------
    ds : xarray.Dataset
        Recording with a uniform ``time`` coordinate [s].
    variable : str
        Data variable along ``time`` (and possibly ``channel``: all channels are mapped).
    speed : str, optional
        Variable or auxiliary coordinate along ``time`` in ``min-1`` (``rad s-1`` and ``Hz``
        are converted).
    angle : str, optional
        Angle variable [rad] instead. Without either, the reference is found by its
        attributes (:func:`analysis.inputs.find_reference`; an angle wins over a speed).
    **kwargs
        Passed on (``resolution``, ``window``, ``overlap``, ``amplitude``, ``scale``).
    """
    da = dataset_variable(ds, variable)
    return rpm_frequency_map(da, **dataset_reference(ds, speed, angle), **kwargs)


def rpm_order_map_ds(
    ds: Any, variable: str, speed: str | None = None, *, angle: str | None = None, **kwargs: Any
) -> RpmOrderMap:
    """:func:`rpm_order_map` of ``ds[variable]`` against a speed or angle of ``ds`` (see
    :func:`rpm_frequency_map_ds`)."""
    da = dataset_variable(ds, variable)
    return rpm_order_map(da, **dataset_reference(ds, speed, angle), **kwargs)


# ----------------------------------------------------------------------------- overall level


@dataclass
class OverallLevel:
    """Overall level vs time and speed (sum of the lines of an rpm-frequency map).

    Attributes
    ----------
    time, rpm : numpy.ndarray
        Frame centres [s] and speed [min-1].
    values : numpy.ndarray
        rms level in ``frequency_range`` (linear, or dB re 1 unit).
    frequency_range : tuple of float
        Band summed [Hz].
    """

    time: np.ndarray
    rpm: np.ndarray
    values: np.ndarray
    scale: str
    units: str
    frequency_range: tuple[float, float]
    window: str
    resolution_hz: float
    level_reference: str = ""
    name: str = "x"
    dims: tuple[str, ...] = ()
    coords: dict[str, np.ndarray] = field(default_factory=dict)
    reference: str = ""

    def to_dataset(self) -> xr.Dataset:
        """Dataset with ``overall_level(*channels, time)`` and auxiliary coordinate
        ``rpm(time)``."""
        import xarray as xr

        long = f"overall rms level of {self.name}"
        if self.scale == "dB":
            long += f" (dB re {self.level_reference})"
        attrs: dict[str, Any] = {
            "f_min_hz": float(self.frequency_range[0]),
            "f_max_hz": float(self.frequency_range[1]),
            "window": self.window,
            "resolution_hz": float(self.resolution_hz),
            "scale": self.scale,
        }
        attrs.update(processing_attrs(self.reference))
        ds = xr.Dataset(
            {
                "overall_level": (
                    (*self.dims, "time"),
                    self.values,
                    {"units": self.units, "long_name": long},
                )
            },
            coords={
                **frame_coords(self.time, self.rpm),
                **channel_coords(self.dims, self.coords),
            },
            attrs=attrs,
        )
        return cf_dataset(ds, title=f"overall level of {self.name}",
                          producer="analysis.maps.overall_level",
                          inputs={"signal": self.name, "speed_reference": self.reference})

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure (see :func:`analysis.plots.overall_level_figure`)."""
        return overall_level_figure(self, **kwargs)


def overall_level(
    x: Any,
    fs: float | None = None,
    rpm: Any = None,
    *,
    angle: Any = None,
    frequency_range: tuple[float, float] | None = None,
    resolution: float | None = None,
    window: WindowSpec = "hann",
    overlap: float = 0.5,
    scale: Literal["linear", "dB"] = "linear",
    time: Any = None,
    axis: int | None = None,
    units: str | None = None,
    name: str | None = None,
) -> OverallLevel:
    """Overall rms level vs rpm from the sum of the lines of the rpm-frequency map.

    ``level = sqrt(sum_k G_k / ENBW_bins)`` over the lines in ``frequency_range`` (default all
    lines, DC included), which for the full band equals the rms of the windowed frame
    (Parseval) and is the quantity NVH suites call "overall level from FFT lines".

    Parameters
    ----------
    x, fs, rpm, angle, resolution, window, overlap, time, axis, units, name
        As in :func:`rpm_frequency_map`.
    frequency_range : (float, float), optional
        Band [Hz] whose lines are summed.
    scale : {"linear", "dB"}, default "linear"
        dB re 1 unit.

    Returns
    -------
    OverallLevel
        Level per frame with the speed.
    """
    require_choice(scale, _SCALES, "scale")
    m = rpm_frequency_map(
        x,
        fs,
        rpm,
        angle=angle,
        resolution=resolution,
        window=window,
        overlap=overlap,
        amplitude="power",
        time=time,
        axis=axis,
        units=units,
        name=name,
    )
    return overall_level_from_map(m, frequency_range=frequency_range, scale=scale)


def overall_level_from_map(
    m: RpmFrequencyMap,
    *,
    frequency_range: tuple[float, float] | None = None,
    scale: Literal["linear", "dB"] = "linear",
) -> OverallLevel:
    """Overall rms level vs rpm from the lines of an existing rpm-frequency map.

    The same quantity as :func:`overall_level` (``sqrt(sum_k G_k / ENBW_bins)`` over the
    lines in ``frequency_range``), read from a map of any amplitude and scale, so that a map
    already computed for a sonogram or a waterfall need not be computed again.

    Parameters
    ----------
    m : RpmFrequencyMap
        The map (converted back to power per line, a block of frames at a time).
    frequency_range : (float, float), optional
        Band [Hz] whose lines are summed (default: every line, DC included).
    scale : {"linear", "dB"}, default "linear"
        dB re 1 unit.

    Returns
    -------
    OverallLevel
        Level per frame of the map, with its speed.
    """
    if not isinstance(m, RpmFrequencyMap):
        raise TypeError(f"m must be an RpmFrequencyMap, got {type(m).__name__}")
    require_choice(scale, _SCALES, "scale")
    lo, hi = (0.0, m.frequency[-1]) if frequency_range is None else map(float, frequency_range)
    if not 0 <= lo < hi:
        raise ValueError(f"frequency_range = {frequency_range!r} must satisfy 0 <= low < high")
    sel = (m.frequency >= lo) & (m.frequency <= hi)
    if not sel.any():
        raise ValueError(f"frequency_range = {frequency_range!r} holds no line of the map")
    if m.amplitude == "power" and m.scale == "linear":
        total = m.values[..., sel].sum(axis=-1)
    else:
        n_frames = m.values.shape[-2]
        total = np.empty(m.values.shape[:-1])
        rows = max(1, BLOCK_ELEMENTS // max(1, m.values.shape[-1]))
        for r0 in range(0, n_frames, rows):  # power per line, a block of frames at a time
            power = power_of(m.values[..., r0:r0 + rows, :], m.amplitude, m.scale,
                             m.segment_length)
            total[..., r0:r0 + rows] = power[..., sel].sum(axis=-1)
    vals = np.sqrt(total / m.enbw_bins)
    ref = ""
    out_units = m.signal_units
    if scale == "dB":
        vals, ref, out_units = to_db(vals, "rms"), f"1 {out_units}", "1"
    return OverallLevel(
        m.time, m.rpm, vals, scale, out_units, (lo, hi), m.window, m.resolution_hz, ref,
        m.name, m.dims, m.coords, m.reference,
    )  # fmt: skip


# ---------------------------------------------------------------------------------- Campbell


@dataclass
class Campbell:
    """Campbell-diagram data: order rays, natural-frequency lines and critical speeds.

    Attributes
    ----------
    rpm : numpy.ndarray
        Speed grid [min-1].
    orders : numpy.ndarray
        Orders of the rays.
    natural_frequencies_hz : numpy.ndarray
        Natural frequencies [Hz] (horizontal lines).
    order_frequency : numpy.ndarray
        Ray frequencies ``order * rpm / 60`` [Hz], shape ``(order, rpm)``.
    critical_rpm : numpy.ndarray
        ``60 f_n / order`` [min-1], shape ``(order, mode)``; NaN outside the speed range.
    """

    rpm: np.ndarray
    orders: np.ndarray
    natural_frequencies_hz: np.ndarray
    order_frequency: np.ndarray
    critical_rpm: np.ndarray

    def to_dataset(self) -> xr.Dataset:
        """Dataset with ``order_frequency(order, rpm)`` and ``critical_rpm(order, mode)``."""
        import xarray as xr

        ds = xr.Dataset(
            {
                "order_frequency": (
                    ("order", "rpm"),
                    self.order_frequency,
                    {"units": "Hz", "long_name": "frequency of the order ray"},
                ),
                "critical_rpm": (
                    ("order", "mode"),
                    self.critical_rpm,
                    {
                        "units": "min-1",
                        "long_name": "speed where the order ray crosses the natural frequency",
                    },
                ),
                "natural_frequency": (
                    "mode",
                    self.natural_frequencies_hz,
                    {"units": "Hz", "long_name": "natural frequency"},
                ),
            },
            coords={
                "order": ("order", self.orders, {"units": "1", "long_name": "order"}),
                "rpm": (
                    "rpm",
                    self.rpm,
                    {"units": "min-1", "long_name": "shaft speed (revolutions per minute)"},
                ),
                "mode": (
                    "mode",
                    np.arange(self.natural_frequencies_hz.size),
                    {"units": "1", "long_name": "mode index"},
                ),
            },
        )
        return cf_dataset(ds, title="Campbell diagram", producer="analysis.maps.campbell")

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure (see :func:`analysis.plots.campbell_figure`)."""
        return campbell_figure(self, **kwargs)


def campbell(
    natural_frequencies_hz: Any,
    orders: Any,
    rpm_range: tuple[float, float],
    *,
    n_points: int = 101,
) -> Campbell:
    """Campbell-diagram data for order rays and natural-frequency lines.

    Parameters
    ----------
    natural_frequencies_hz : array_like
        Natural frequencies [Hz] (> 0); may be empty.
    orders : array_like
        Orders (> 0), e.g. mesh orders ``z * k``.
    rpm_range : (float, float)
        Speed range [min-1], ``0 <= low < high``.
    n_points : int, default 101
        Points of the speed grid.

    Returns
    -------
    Campbell
        Rays, lines and critical speeds ``60 f_n / order`` inside the range.
    """
    fn = np.atleast_1d(np.asarray(natural_frequencies_hz, dtype=float))
    if fn.size and (not np.all(np.isfinite(fn)) or np.any(fn <= 0)):
        raise ValueError("natural_frequencies_hz must be finite and > 0 Hz")
    ords = np.atleast_1d(require_finite(orders, "orders"))
    if np.any(ords <= 0):
        raise ValueError("orders must be > 0")
    lo, hi = (float(v) for v in rpm_range)
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi):
        raise ValueError(f"rpm_range = {rpm_range!r} must satisfy 0 <= low < high (min-1)")
    if isinstance(n_points, bool) or not isinstance(n_points, int) or n_points < 2:
        raise ValueError(f"n_points = {n_points!r} must be an integer >= 2")
    grid = np.linspace(lo, hi, n_points)
    crit = 60.0 * fn[None, :] / ords[:, None]
    crit = np.where((crit >= lo) & (crit <= hi), crit, np.nan)
    return Campbell(grid, ords, fn, ords[:, None] * grid[None, :] / 60.0, crit)
