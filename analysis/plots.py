"""Figure builders for spectra, rpm maps, order cuts and Campbell diagrams.

Plotting only: every function takes a result object from :mod:`analysis.spectrum`,
:mod:`analysis.orders` or :mod:`analysis.maps` and returns a
:class:`matplotlib.figure.Figure`: a new one, or the figure of ``ax=`` when it draws into
given axes (built with the Figure API, never pyplot, so it works in
scripts, servers and notebooks alike). Save it with ``fig.savefig("map.png", dpi=150)``.
matplotlib is imported lazily.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.checks import require_colormap, require_instance, require_positive, require_real
from analysis.levels import to_db

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from analysis.maps import Campbell, OverallLevel, RpmFrequencyMap, RpmOrderMap
    from analysis.orders import OrderCut, OrderSpectrum
    from analysis.spectrum import Peaks, Spectrum

__all__ = [
    "campbell_figure",
    "order_cuts_figure",
    "order_spectrum_figure",
    "overall_level_figure",
    "rpm_frequency_map_figure",
    "rpm_order_map_figure",
    "spectrum_figure",
]


def _figure(figsize: tuple[float, float]) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=figsize, layout="constrained")


def _axes(ax: Any, figsize: tuple[float, float]) -> tuple[Figure, Any]:
    """The figure and axes to draw into: ``ax`` and its figure, or a new figure."""
    if ax is None:
        fig = _figure(figsize)
        return fig, fig.add_subplot()
    if not hasattr(ax, "figure") or not hasattr(ax, "plot"):
        raise ValueError(f"ax must be matplotlib Axes; got {type(ax).__name__}")
    return ax.figure, ax


def _rows(values: np.ndarray, dims: tuple[str, ...], coords: dict, name: str) -> list:
    """``(label, row)`` of every channel of a line result (values ``(*channels, n)``)."""
    if values.ndim == 1:
        return [(name, values)]
    out = []
    for idx in np.ndindex(*values.shape[:-1]):
        parts = []
        for d, i in zip(dims, idx, strict=False):
            c = coords.get(d)
            parts.append(str(np.asarray(c)[i]) if c is not None else f"{d} {i}")
        out.append((", ".join(parts) or name, values[idx]))
    return out


def _one_channel(m: Any, channel: Any) -> Any:
    """The single-channel map to draw (``channel`` required for multi-channel maps)."""
    if m.values.ndim == 2:
        return m
    if channel is None:
        labels = list(np.asarray(m.coords[m.dims[0]])) if m.dims and m.dims[0] in m.coords else (
            list(range(m.values.shape[0]))
        )
        raise ValueError(f"the map has {m.values.shape[0]} channels: choose one with "
                         f"channel= (one of {labels})")  # fmt: skip
    return m.select(channel)


def _speed_limits(rpm: np.ndarray) -> tuple[float, float]:
    """Axis limits of a speed axis; a constant speed gets a margin of 2 % (at least 1 min-1)
    around it instead of an empty (singular) range."""
    lo, hi = float(np.nanmin(rpm)), float(np.nanmax(rpm))
    if hi - lo <= 1e-9 * max(1.0, abs(hi)):
        pad = max(1.0, 0.02 * abs(hi))
        return lo - pad, hi + pad
    return lo, hi


def _value_label(scaling: str, units: str, db: bool) -> str:
    name = {"peak": "peak amplitude", "rms": "rms amplitude", "power": "power",
            "density": "PSD"}.get(scaling, scaling)  # fmt: skip
    if db:
        return f"{name} [dB re 1 {units}]"
    return f"{name} [{units}]"


def spectrum_figure(
    spectrum: Spectrum,
    *,
    peaks: Peaks | None = None,
    labels: Sequence[str] | None = None,
    db: bool = True,
    channel: Any = None,
    ax: Any = None,
    figsize: tuple[float, float] = (8.0, 4.0),
) -> Figure:
    """Spectrum with optional labelled peaks.

    Parameters
    ----------
    spectrum : Spectrum
        Result of :func:`analysis.spectrum.spectrum`.
    peaks : Peaks, optional
        Peaks to mark (e.g. ``spectrum.peaks(max_peaks=5)``).
    labels : sequence of str, optional
        One text per peak (default: its frequency).
    db : bool, default True
        Level in dB (``20 log10`` amplitudes, ``10 log10`` power) or linear.
    channel : int, str or tuple, optional
        Which spectrum of a multi-channel result (a label or an index; default: all, one
        line per channel with a legend).
    ax : matplotlib.axes.Axes, optional
        Axes to draw into (default: a new figure).
    figsize : (float, float)
        Size in inches of a new figure.
    """
    require_instance(spectrum, "analysis.spectrum.Spectrum", "spectrum")
    fig, ax = _axes(ax, figsize)
    if isinstance(channel, tuple):  # an index into several leading dimensions
        spectrum = dataclasses.replace(
            spectrum, values=spectrum.values[channel], dims=(), coords={}
        )
    elif channel is not None:
        spectrum = spectrum.select(channel)
    rows = _rows(spectrum.values, spectrum.dims, spectrum.coords, spectrum.name)
    for label, row in rows:
        y = to_db(row, spectrum.amplitude) if db else row
        ax.plot(spectrum.frequency, y, lw=0.8, label=label)
    if len(rows) > 1:
        ax.legend(fontsize=8)
    if peaks is not None and len(peaks):
        text = list(labels) if labels is not None else peaks.labels()
        if len(text) != len(peaks):
            raise ValueError(f"labels: {len(text)} given for {len(peaks)} peaks")
        y = to_db(peaks.amplitude, spectrum.amplitude) if db else peaks.amplitude
        ax.plot(peaks.frequency, y, "v", color="C3", ms=5)
        for f, v, s in zip(peaks.frequency, y, text, strict=True):
            ax.annotate(
                s, (f, v), xytext=(0, 6), textcoords="offset points", ha="center", fontsize=8
            )
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(_value_label(spectrum.amplitude, spectrum.units, db))
    ax.set_title(
        f"{spectrum.name}: {spectrum.window}, RBW = {spectrum.resolution_hz:.4g} Hz, "
        f"{spectrum.n_averages} avg."
    )
    ax.grid(True, alpha=0.3)
    return fig


def order_spectrum_figure(
    spectrum: OrderSpectrum,
    *,
    db: bool = True,
    ax: Any = None,
    figsize: tuple[float, float] = (8.0, 4.0),
) -> Figure:
    """Order spectrum (level vs order), one line per channel; ``ax`` to draw into."""
    require_instance(spectrum, "analysis.orders.OrderSpectrum", "spectrum")
    fig, ax = _axes(ax, figsize)
    rows = _rows(spectrum.values, spectrum.dims, spectrum.coords, spectrum.name)
    for label, row in rows:
        ax.plot(spectrum.order, to_db(row, spectrum.amplitude) if db else row, lw=0.8,
                label=label)  # fmt: skip
    if len(rows) > 1:
        ax.legend(fontsize=8)
    ax.set_xlabel("order [-]")
    ax.set_ylabel(_value_label(spectrum.amplitude, spectrum.units, db))
    ax.set_title(
        f"{spectrum.name}: {spectrum.window}, RBW = {spectrum.resolution_orders:.4g} orders"
    )
    ax.grid(True, alpha=0.3)
    return fig


def _map_levels(m: RpmFrequencyMap | RpmOrderMap, dynamic_range_db: float) -> np.ndarray:
    require_positive(require_real(dynamic_range_db, "dynamic_range_db"), "dynamic_range_db")
    if m.scale == "dB":
        lv = np.asarray(m.values, dtype=float)
    else:
        lv = to_db(m.values, "power" if m.amplitude == "power" else "rms")
    return np.maximum(lv, np.nanmax(lv) - dynamic_range_db)


def _colourmap(
    fig: Figure, ax: Any, x: np.ndarray, y: np.ndarray, levels: np.ndarray, label: str, cmap: str
) -> None:
    mesh = ax.pcolormesh(x, y, levels, shading="nearest", cmap=require_colormap(cmap),
                         rasterized=True)
    fig.colorbar(mesh, ax=ax, label=label)


def rpm_frequency_map_figure(
    m: RpmFrequencyMap,
    *,
    hz_per_rpm: float | Sequence[float] = (),
    orders: Sequence[float] = (1,),
    order_labels: Sequence[str] | None = None,
    natural_frequencies_hz: Sequence[float] = (),
    dynamic_range_db: float = 60.0,
    frequency_max: float | None = None,
    cmap: str = "viridis",
    channel: Any = None,
    ax: Any = None,
    figsize: tuple[float, float] = (8.0, 6.0),
) -> Figure:
    """Sonogram: speed vertical, frequency horizontal, colour = level in dB.

    Mesh orders are drawn as inclined lines ``f = k * c * rpm`` for every factor ``c`` in
    ``hz_per_rpm`` (Hz per min-1, e.g. ``z / 60 * ratio`` for a mesh seen from the input
    shaft) and every harmonic ``k`` in ``orders``; natural frequencies as vertical lines.

    Parameters
    ----------
    m : RpmFrequencyMap
        Map (any amplitude/scale).
    hz_per_rpm : float or sequence of float
        Frequency per speed of each line family [Hz per min-1].
    orders : sequence of float, default (1,)
        Harmonic numbers multiplying each factor.
    order_labels : sequence of str, optional
        One label per (factor, harmonic) pair, factor-major.
    natural_frequencies_hz : sequence of float
        Vertical lines [Hz].
    dynamic_range_db : float, default 60
        Colour range below the maximum.
    frequency_max : float, optional
        Upper frequency limit of the plot.
    cmap : str
        Colour map.
    channel : str or int, optional
        The channel to draw of a multi-channel map (required then).
    ax : matplotlib.axes.Axes, optional
        Axes to draw into (default: a new figure).
    figsize : (float, float)
        Size in inches of a new figure.
    """
    require_instance(m, "analysis.maps.RpmFrequencyMap", "m")
    m = _one_channel(m, channel)
    fig, ax = _axes(ax, figsize)
    levels = _map_levels(m, dynamic_range_db)
    order = np.argsort(m.rpm, kind="stable")  # a coast-down plots with speed upwards too
    _colourmap(
        fig,
        ax,
        m.frequency,
        m.rpm[order],
        levels[order],
        f"{m.amplitude} level [dB re {m.level_reference}]",
        cmap,
    )
    factors = np.atleast_1d(np.asarray(hz_per_rpm, dtype=float))
    pairs = [(c, k) for c in factors for k in orders]
    if order_labels is not None and len(order_labels) != len(pairs):
        raise ValueError(f"order_labels: {len(order_labels)} given for {len(pairs)} lines")
    rpm_line = np.array([m.rpm.min(), m.rpm.max()])
    for i, (c, k) in enumerate(pairs):
        f = k * c * rpm_line
        ax.plot(f, rpm_line, color="w", lw=0.8, ls="--")
        label = order_labels[i] if order_labels is not None else f"{k:g}×"
        ax.annotate(
            label,
            (f[1], rpm_line[1]),
            xytext=(2, -10),
            textcoords="offset points",
            color="w",
            fontsize=8,
        )
    for fn in natural_frequencies_hz:
        ax.axvline(fn, color="C1", lw=0.9, ls=":")
    ax.set_xlim(0, frequency_max if frequency_max is not None else m.frequency[-1])
    ax.set_ylim(*_speed_limits(m.rpm))
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("speed [min⁻¹]")
    ax.set_title(f"{m.name}: {m.window}, RBW = {m.resolution_hz:.4g} Hz")
    return fig


def rpm_order_map_figure(
    m: RpmOrderMap,
    *,
    orders: Sequence[float] = (),
    dynamic_range_db: float = 60.0,
    order_max: float | None = None,
    cmap: str = "viridis",
    channel: Any = None,
    ax: Any = None,
    figsize: tuple[float, float] = (8.0, 6.0),
) -> Figure:
    """Rpm-order map: speed vertical, order horizontal; optional vertical order markers.

    ``channel`` chooses the channel of a multi-channel map; ``ax`` are axes to draw into.
    """
    require_instance(m, "analysis.maps.RpmOrderMap", "m")
    m = _one_channel(m, channel)
    fig, ax = _axes(ax, figsize)
    levels = _map_levels(m, dynamic_range_db)
    idx = np.argsort(m.rpm, kind="stable")
    _colourmap(
        fig,
        ax,
        m.order,
        m.rpm[idx],
        levels[idx],
        f"{m.amplitude} level [dB re {m.level_reference}]",
        cmap,
    )
    for o in orders:
        ax.axvline(o, color="w", lw=0.8, ls="--")
    ax.set_xlim(0, order_max if order_max is not None else m.max_order)
    ax.set_xlabel("order [-]")
    ax.set_ylabel("speed [min⁻¹]")
    ax.set_title(f"{m.name}: {m.window}, RBW = {m.resolution_orders:.4g} orders")
    return fig


def order_cuts_figure(
    cut: OrderCut,
    *,
    labels: Sequence[str] | None = None,
    db: bool | None = None,
    channel: Any = None,
    ax: Any = None,
    figsize: tuple[float, float] = (8.0, 4.0),
) -> Figure:
    """Order cuts: level of each tracked order vs speed.

    ``db`` defaults to the cut's own scale; a linear cut can be shown in dB. A multi-channel
    cut draws every channel (``channel=`` chooses one); ``ax`` are axes to draw into.
    """
    require_instance(cut, "analysis.orders.OrderCut", "cut")
    fig, ax = _axes(ax, figsize)
    if channel is not None:
        cut = cut.select(channel)
    show_db = (cut.scale == "dB") if db is None else db
    text = list(labels) if labels is not None else [f"order {o:g}" for o in cut.orders]
    if len(text) != cut.orders.size:
        raise ValueError(f"labels: {len(text)} given for {cut.orders.size} orders")
    vals = cut.values.reshape(-1, *cut.values.shape[-2:])
    names = [lab for lab, _ in _rows(cut.values[..., 0], cut.dims, cut.coords, "")] if (
        cut.values.ndim > 2) else [""]  # fmt: skip
    series = [
        (f"{ch}: {lab}" if ch else lab, row)
        for ch, block in zip(names, vals, strict=True)
        for row, lab in zip(block, text, strict=True)
    ]
    for lab, row in series:
        y = row
        if show_db and cut.scale != "dB":
            y = to_db(row, "power" if cut.amplitude == "power" else "rms")
        elif not show_db and cut.scale == "dB":
            y = 10 ** (row / (10 if cut.amplitude == "power" else 20))
        ax.plot(cut.rpm, y, lw=1.0, label=lab)
    ref = cut.units if cut.scale != "dB" else cut.level_reference.removeprefix("1 ")
    ax.set_ylabel(
        f"{cut.amplitude} level [dB re 1 {ref}]" if show_db else f"{cut.amplitude} level [{ref}]"
    )
    ax.set_xlabel("speed [min⁻¹]")
    bw = f"{cut.bandwidth:.4g} {'orders' if cut.bandwidth_kind == 'order' else 'Hz'}"
    ax.set_title(f"{cut.name}: order cuts, band {bw}, {cut.window}")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return fig


def overall_level_figure(
    level: OverallLevel, *, ax: Any = None, figsize: tuple[float, float] = (8.0, 4.0)
) -> Figure:
    """Overall rms level vs speed (one line per channel); ``ax`` to draw into."""
    require_instance(level, "analysis.maps.OverallLevel", "level")
    fig, ax = _axes(ax, figsize)
    rows = _rows(level.values, level.dims, level.coords, level.name)
    for label, row in rows:
        ax.plot(level.rpm, row, lw=1.0, label=label)
    if len(rows) > 1:
        ax.legend(fontsize=8)
    ax.set_xlabel("speed [min⁻¹]")
    ax.set_ylabel(
        f"overall rms level [dB re {level.level_reference}]"
        if level.scale == "dB"
        else f"overall rms level [{level.units}]"
    )
    lo, hi = level.frequency_range
    ax.set_title(f"{level.name}: overall level {lo:g}–{hi:g} Hz")
    ax.grid(True, alpha=0.3)
    return fig


def campbell_figure(
    c: Campbell,
    *,
    order_labels: Sequence[str] | None = None,
    frequency_max: float | None = None,
    ax: Any = None,
    figsize: tuple[float, float] = (7.0, 5.0),
) -> Figure:
    """Campbell diagram: order rays, natural-frequency lines and critical speeds."""
    require_instance(c, "analysis.maps.Campbell", "c")
    fig, ax = _axes(ax, figsize)
    text = list(order_labels) if order_labels is not None else [f"{o:g}×" for o in c.orders]
    if len(text) != c.orders.size:
        raise ValueError(f"order_labels: {len(text)} given for {c.orders.size} orders")
    for ray, lab in zip(c.order_frequency, text, strict=True):
        ax.plot(c.rpm, ray, lw=1.0, label=lab)
    for fn in c.natural_frequencies_hz:
        ax.axhline(fn, color="k", lw=0.8, ls=":")
    crit = c.critical_rpm
    for i in range(crit.shape[0]):
        ok = np.isfinite(crit[i])
        ax.plot(crit[i, ok], c.natural_frequencies_hz[ok], "o", color="C3", ms=5)
    top = (
        frequency_max
        if frequency_max is not None
        else float(
            max(
                c.order_frequency.max(),
                (c.natural_frequencies_hz.max() * 1.1) if c.natural_frequencies_hz.size else 0.0,
            )
        )
    )
    ax.set_ylim(0, top)
    ax.set_xlim(c.rpm[0], c.rpm[-1])
    ax.set_xlabel("speed [min⁻¹]")
    ax.set_ylabel("frequency [Hz]")
    ax.set_title("Campbell diagram")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return fig
