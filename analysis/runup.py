"""Features of a run-up map: order-locked rays and frequency-locked vertical lines.

In an rpm-frequency map (sonogram) a component locked to a shaft (mesh and shaft orders,
sidebands) follows a ray ``f = o rpm / 60``; a component fixed in frequency (a natural
frequency, a structural resonance, mains hum) is a vertical line ``f = const``. The paper's
Figure 11 is read this way, and resonances sit where the two cross.

:func:`map_features` separates the two kinds from the map alone. The map is converted to a
rise above the background of each frame (dB above the frame median), then averaged robustly
(a quantile over the frames, default the median) two ways:

* along every vertical line ``f = const`` -> the *frequency profile*;
* along every ray ``f = o rpm / 60`` -> the *order profile*.

A ray contributes to a vertical line only in the few frames where it passes, and a vertical line
to a ray likewise, so the median keeps each feature sharp in its own profile and rejects it in
the other. Peaks of the order profile are order-locked features, peaks of the frequency profile
frequency-locked ones. This needs a speed range that moves the features apart (the default
requires the largest speed to be at least 1.3 x the smallest analysed).

:func:`map_levels` and :func:`frame_widths` are the shared helpers (levels in dB, the width of a
ray in a frame including its sweep within the frame).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.ndimage
import scipy.signal

from analysis.cf import cf_dataset
from analysis.checks import require_finite, require_positive

__all__ = [
    "MapFeatures",
    "MapLevels",
    "map_features",
    "map_levels",
]


@dataclass(frozen=True)
class MapLevels:
    """A run-up map in dB with its axes.

    Attributes
    ----------
    time : ndarray
        Frame centres [s].
    rpm : ndarray
        Speed at each frame [min-1].
    axis : ndarray
        Frequency [Hz] or order.
    axis_name : str
        ``"frequency"`` or ``"order"``.
    level : ndarray, shape (time, axis)
        Level [dB].
    resolution : float
        Resolution bandwidth of the map (Hz or orders).
    frame_duration : float
        Duration of one analysis frame [s] (the sweep inside it widens rays).
    """

    time: np.ndarray
    rpm: np.ndarray
    axis: np.ndarray
    axis_name: str
    level: np.ndarray
    resolution: float
    frame_duration: float

    @property
    def rate(self) -> np.ndarray:
        """Speed change per second at every frame [min-1 s-1]."""
        if self.time.size < 2:
            return np.zeros_like(self.rpm)
        return np.gradient(self.rpm, self.time)

    def ray_half_width(self, order: float | np.ndarray) -> np.ndarray:
        """Half-width of the ray of ``order`` in every frame (axis units).

        On a frequency axis: half the resolution plus a quarter of the sweep of the ray inside
        one frame, ``|o d(rpm)/dt| T_frame / 240`` (the tapered window weights the middle half
        of the frame); on an order axis: half the resolution.
        """
        o = np.asarray(order, dtype=float)
        if self.axis_name == "order":
            return np.broadcast_to(0.5 * self.resolution, np.broadcast(o[..., None],
                                                                       self.rpm).shape)
        sweep = np.abs(o[..., None] * self.rate) * self.frame_duration / 60.0
        return 0.5 * self.resolution + 0.25 * sweep


def map_levels(map_ds: Any, *, variable: str = "amplitude", speed: str = "rpm") -> MapLevels:
    """Read an rpm-frequency or rpm-order map Dataset into dB.

    Parameters
    ----------
    map_ds : xarray.Dataset
        ``variable(time, frequency)`` or ``variable(time, order)``, coordinate ``time`` [s]
        and auxiliary coordinate ``speed(time)`` [min-1], as written by
        :mod:`analysis.maps`. Linear maps are converted (``20 log10`` for amplitudes,
        ``10 log10`` for ``amplitude="power"``); maps with ``scale="dB"`` are used as they are.
    variable, speed : str
        Names of the level variable and the speed coordinate.

    Returns
    -------
    MapLevels
    """
    if not hasattr(map_ds, "data_vars"):
        raise ValueError("map_ds must be an xarray.Dataset with a map variable(time, frequency) "
                         "or variable(time, order)")
    if variable not in map_ds.data_vars:
        raise ValueError(f"map_ds has no data variable {variable!r} (expected "
                         f"{variable}(time, frequency) or {variable}(time, order))")
    da = map_ds[variable]
    axis_name = next((a for a in ("frequency", "order") if a in da.dims), None)
    if axis_name is None or set(da.dims) != {"time", axis_name}:
        raise ValueError(f"map_ds[{variable!r}] must have dims ('time', 'frequency') or "
                         f"('time', 'order'); got {da.dims}")
    for c in ("time", axis_name, speed):
        if c not in map_ds.coords:
            raise ValueError(f"map_ds needs coordinate {c!r} (time [s], {axis_name}, "
                             f"{speed}(time) [min-1])")
    if map_ds[speed].dims != ("time",):
        raise ValueError(f"map_ds coordinate {speed!r} must have dim ('time',); got "
                         f"{map_ds[speed].dims}")
    t = require_finite(map_ds["time"].values, "time")
    ax = require_finite(map_ds[axis_name].values, axis_name)
    rpm = np.abs(require_finite(map_ds[speed].values, speed))
    v = require_finite(da.transpose("time", axis_name).values, variable)
    if ax.size < 3 or t.size < 3:
        raise ValueError(f"map_ds needs at least 3 times and 3 {axis_name} values")
    if np.any(np.diff(ax) <= 0) or np.any(np.diff(t) <= 0):
        raise ValueError(f"time and {axis_name} must be strictly increasing")
    if str(map_ds.attrs.get("scale", "linear")) == "dB":
        level = v.astype(float)
    else:
        if np.any(v < 0):
            raise ValueError(f"{variable} must be a linear (non-negative) amplitude or carry "
                             "scale='dB'")
        power = str(map_ds.attrs.get("amplitude", "rms")) == "power"
        floor = max(float(v.max()), 1e-300) * (1e-30 if power else 1e-15)
        level = (10.0 if power else 20.0) * np.log10(np.maximum(v, floor))
    step = float(np.median(np.diff(ax)))
    if axis_name == "frequency":
        res = float(map_ds.attrs.get("resolution_hz", 0.0)) or 1.5 * step
        fs = float(map_ds.attrs.get("sample_rate_hz", 0.0))
        seg = float(map_ds.attrs.get("segment_length", 0.0))
        dur = seg / fs if fs > 0 and seg > 0 else 1.5 / res
    else:
        res = float(map_ds.attrs.get("resolution_orders", 0.0)) or 1.5 * step
        dur = 0.0
    return MapLevels(time=t, rpm=rpm, axis=ax, axis_name=axis_name, level=level,
                     resolution=res, frame_duration=dur)


@dataclass(frozen=True)
class MapFeatures:
    """Order-locked and frequency-locked features of a run-up map.

    Attributes
    ----------
    orders : ndarray
        Orders of the rays found (cycles per revolution of the speed channel).
    order_strength_db : ndarray
        Their level above the frame background (quantile over frames) [dB].
    order_prominence_db : ndarray
        Their prominence in the order profile [dB].
    frequencies : ndarray
        Frequencies of the vertical lines found [Hz].
    frequency_strength_db, frequency_prominence_db : ndarray
        The same for the vertical lines.
    order_axis, order_profile : ndarray
        The order profile (dB above the frame background).
    frequency_axis, frequency_profile : ndarray
        The frequency profile.
    speed_range : (float, float)
        Speeds of the analysed frames [min-1].
    notes : tuple of str
        Remarks.
    """

    orders: np.ndarray
    order_strength_db: np.ndarray
    order_prominence_db: np.ndarray
    frequencies: np.ndarray
    frequency_strength_db: np.ndarray
    frequency_prominence_db: np.ndarray
    order_axis: np.ndarray
    order_profile: np.ndarray
    frequency_axis: np.ndarray
    frequency_profile: np.ndarray
    speed_range: tuple[float, float]
    notes: tuple[str, ...] = field(default_factory=tuple)

    def to_dataset(self):
        """Features and profiles as :class:`xarray.Dataset` (CF attributes)."""
        import xarray as xr

        ds = xr.Dataset(
            {
                "ray_order": ("ray", self.orders, {"units": "1",
                                                   "long_name": "order of an order-locked ray"}),
                "ray_strength": ("ray", self.order_strength_db,
                                 {"units": "dB", "long_name": "ray level above frame background"}),
                "ray_prominence": ("ray", self.order_prominence_db,
                                   {"units": "dB", "long_name": "prominence in order profile"}),
                "line_frequency": ("vline", self.frequencies,
                                   {"units": "Hz", "long_name": "frequency-locked line"}),
                "line_strength": ("vline", self.frequency_strength_db,
                                  {"units": "dB", "long_name": "line level above frame "
                                                               "background"}),
                "line_prominence": ("vline", self.frequency_prominence_db,
                                    {"units": "dB", "long_name": "prominence in frequency "
                                                                 "profile"}),
                "order_profile": ("order", self.order_profile,
                                  {"units": "dB", "long_name": "level along rays above frame "
                                                               "background"}),
                "frequency_profile": ("frequency", self.frequency_profile,
                                      {"units": "dB", "long_name": "level along vertical lines "
                                                                   "above frame background"}),
            },
            coords={
                "ray": ("ray", np.arange(self.orders.size), {"units": "1",
                                                             "long_name": "ray index"}),
                "vline": ("vline", np.arange(self.frequencies.size),
                          {"units": "1", "long_name": "vertical line index"}),
                "order": ("order", self.order_axis, {"units": "1", "long_name": "order"}),
                "frequency": ("frequency", self.frequency_axis,
                              {"units": "Hz", "long_name": "frequency"}),
            },
            attrs={"speed_low_rpm": self.speed_range[0], "speed_high_rpm": self.speed_range[1],
                   "notes": " | ".join(self.notes)},
        )
        return cf_dataset(ds, title="run-up map features", producer="analysis.runup.map_features")

    def plot(self, ax: Any = None):
        """Both profiles with the features marked (two stacked axes unless ``ax`` given)."""
        from matplotlib.figure import Figure

        if ax is None:
            fig = Figure(figsize=(8, 5.5), layout="constrained")
            a1, a2 = fig.subplots(2, 1)
        else:
            fig, a1, a2 = ax[0].figure, ax[0], ax[1]
        a1.plot(self.order_axis, self.order_profile, lw=0.8)
        a1.plot(self.orders, self.order_strength_db, "v", color="C3", label="order-locked ray")
        a1.set_xlabel("order")
        a1.set_ylabel("median rise [dB]")
        a1.legend(fontsize=8)
        a2.plot(self.frequency_axis, self.frequency_profile, lw=0.8, color="C2")
        a2.plot(self.frequencies, self.frequency_strength_db, "v", color="C3",
                label="frequency-locked line")
        a2.set_xlabel("frequency [Hz]")
        a2.set_ylabel("median rise [dB]")
        a2.legend(fontsize=8)
        for a in (a1, a2):
            a.grid(True, alpha=0.3)
        a1.set_title(f"run-up map features ({self.speed_range[0]:.0f}–"
                     f"{self.speed_range[1]:.0f} min⁻¹)", fontsize=9)
        return fig


def map_features(map_ds: Any, *, variable: str = "amplitude", speed: str = "rpm",
                 prominence_db: float = 6.0, quantile: float = 0.5,
                 min_speed_ratio: float = 1.3, frames: Any = None,
                 max_order: float | None = None) -> MapFeatures:
    """Separate order-locked rays from frequency-locked vertical lines of a run-up map.

    Parameters
    ----------
    map_ds : xarray.Dataset
        An rpm-frequency or rpm-order map (see :func:`map_levels`). In an order map the roles
        swap: orders are columns, natural frequencies follow ``o = 60 f / rpm``.
    variable, speed : str
        Level variable and speed coordinate.
    prominence_db : float
        Minimum prominence of a feature in its profile [dB].
    quantile : float
        Quantile over frames of the rise along a line (0.5: present in at least half of the
        frames in which the line lies inside the map; orders inside the map for less than 30 %
        of the frames are not evaluated).
    min_speed_ratio : float
        The largest analysed speed must be at least this multiple of the smallest; otherwise
        rays and vertical lines cannot be told apart (ValueError).
    frames : array_like of bool, optional
        Frames to analyse (default: all with speed > 2 % of the largest).
    max_order : float, optional
        Largest order of the order profile of a frequency map (default: the top frequency over
        the median of the analysed speeds, so that every order is inside the map for half of
        the run).

    Returns
    -------
    MapFeatures
    """
    lv = map_levels(map_ds, variable=variable, speed=speed)
    prom = require_positive(prominence_db, "prominence_db")
    q = float(quantile)
    if not 0.0 < q < 1.0:
        raise ValueError(f"quantile = {quantile!r} is not admissible: 0 < quantile < 1")
    ratio = require_positive(min_speed_ratio, "min_speed_ratio")
    if frames is None:
        use = lv.rpm > 0.02 * float(lv.rpm.max())
    else:
        use = np.asarray(frames, dtype=bool)
        if use.shape != lv.rpm.shape:
            raise ValueError(f"frames must have one entry per frame ({lv.rpm.size})")
    if use.sum() < 3:
        raise ValueError("fewer than 3 frames with speed > 0 to analyse")
    rpm = lv.rpm[use]
    lo, hi = float(rpm.min()), float(rpm.max())
    if hi < ratio * lo:
        raise ValueError(f"the analysed speed range {lo:.6g}–{hi:.6g} min-1 is too narrow to "
                         f"tell order-locked from frequency-locked features (needs a ratio >= "
                         f"{ratio:g}); use a run-up")
    level = lv.level[use]
    rise = level - np.median(level, axis=1, keepdims=True)
    ax = lv.axis
    # the native axis gives one profile directly; the other is sampled along its lines:
    # rays f = o rpm/60 in a frequency map, vertical lines o = 60 f/rpm in an order map
    native = np.quantile(rise, q, axis=0)
    if lv.axis_name == "frequency":  # grid of orders, up to those inside half of the frames
        top = float(ax[-1]) * 60.0 / float(np.median(rpm))
        top = float(max_order) if max_order is not None else top
        step = 0.25 * lv.resolution * 60.0 / hi
        to_native = rpm / 60.0  # frequency of order o in frame i: o * rpm_i / 60
    else:  # grid of frequencies [Hz]
        top = float(ax[-1]) * float(np.median(rpm)) / 60.0
        step = 0.25 * lv.resolution * lo / 60.0
        to_native = 60.0 / rpm  # order of frequency f in frame i: f * 60 / rpm_i
    n_g = int(np.ceil(top / step))
    if n_g > 2_000_000:
        raise ValueError(f"the {'order' if lv.axis_name == 'frequency' else 'frequency'} grid "
                         f"would have {n_g} points (top {top:.4g}, step {step:.3g}); give "
                         "max_order")
    grid = (np.arange(n_g) + 1) * step
    samples = np.full((rpm.size, grid.size), np.nan)
    for i in range(rpm.size):
        pos = grid * to_native[i]
        inside = (pos >= ax[0]) & (pos <= ax[-1])
        samples[i, inside] = np.interp(pos[inside], ax, rise[i])
    counts = np.isfinite(samples).sum(axis=0)
    valid = counts >= max(5, int(0.3 * rpm.size))
    other = np.full(grid.size, np.nan)
    if valid.any():
        other[valid] = np.nanquantile(samples[:, valid], q, axis=0)
    if lv.axis_name == "frequency":
        f, f_prof, orders, o_prof = ax, native, grid, other
        f_cell, o_cell = lv.resolution, lv.resolution * 60.0 / hi
    else:
        f, f_prof, orders, o_prof = grid, other, ax, native
        f_cell, o_cell = lv.resolution * lo / 60.0, lv.resolution

    def peaks(x: np.ndarray, prof: np.ndarray, cell: float) -> tuple[np.ndarray, ...]:
        """Peaks standing ``prom`` above a running median over 101 cells (and half of it above
        their neighbouring minima), after smoothing over one cell."""
        good = np.isfinite(prof)
        if good.sum() < 5:
            return np.zeros(0), np.zeros(0), np.zeros(0)
        y = np.where(good, prof, np.nanmin(prof[good]))
        k = max(1, round(cell / float(np.median(np.diff(x)))))
        smooth = scipy.ndimage.uniform_filter1d(y, k, mode="nearest")
        base = scipy.ndimage.median_filter(smooth, size=max(101 * k, 5), mode="nearest")
        excess = smooth - base
        idx, _ = scipy.signal.find_peaks(excess, height=prom, prominence=0.5 * prom,
                                         distance=2 * k)
        ends = np.flatnonzero(good)
        idx = idx[good[idx] & (idx >= ends[0] + 2 * k) & (idx <= ends[-1] - 2 * k)]
        ex = excess[idx]
        # the position from the unsmoothed profile within one cell of the smoothed peak
        idx = np.asarray([i - k + int(np.argmax(y[max(i - k, 0):i + k + 1]))
                          + max(0, k - i) for i in idx], dtype=int)
        return x[idx], y[idx], ex

    o_pk, o_val, o_pr = peaks(orders, o_prof, o_cell)
    f_pk, f_val, f_pr = peaks(f, f_prof, f_cell)
    notes = [f"features from {rpm.size} frames at {lo:.0f}–{hi:.0f} min-1 (quantile {q:g} of "
             "the rise above each frame's median)"]
    return MapFeatures(orders=o_pk, order_strength_db=o_val, order_prominence_db=o_pr,
                       frequencies=f_pk, frequency_strength_db=f_val,
                       frequency_prominence_db=f_pr, order_axis=orders, order_profile=o_prof,
                       frequency_axis=f, frequency_profile=f_prof, speed_range=(lo, hi),
                       notes=tuple(notes))
