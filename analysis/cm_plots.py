"""Figures of the condition-monitoring results: TSA, planet and sun averages, gear signals,
indicator trends with alarm limits.

Plotting only: every function takes a result of :mod:`analysis.tsa`,
:mod:`analysis.planetary_tsa`, :mod:`analysis.gear_signals`, :mod:`analysis.indicators` or
:mod:`analysis.alarm_limits` and returns a :class:`matplotlib.figure.Figure` built with the
Figure API (never pyplot). matplotlib is imported lazily.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.checks import require_instance
from analysis.inputs import select_channel

if TYPE_CHECKING:
    import xarray as xr
    from matplotlib.figure import Figure

    from analysis.alarm_limits import AlarmLimits
    from analysis.gear_signals import GearSignals
    from analysis.planetary_tsa import PlanetarySeparation
    from analysis.tsa import TSA

__all__ = ["gear_signals_figure", "planetary_figure", "trend_figure", "tsa_figure"]


def _new(figsize: tuple[float, float]) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=figsize, layout="constrained")


def _rows(values: np.ndarray, dims: tuple[str, ...], coords: dict, name: str) -> list:
    """``(label, row)`` of every channel of ``values`` (``(*channels, n)``)."""
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


def _select(values: np.ndarray, dims: tuple[str, ...], coords: dict, channel: Any) -> tuple:
    if channel is None or values.ndim == 1:
        return values, dims, coords
    v, d, c, _ = select_channel(values, dims, coords, channel)
    return v, d, c


def _tooth_axis(ax: Any, teeth: int, angle: np.ndarray) -> np.ndarray:
    x = angle * teeth / (2.0 * np.pi)
    if teeth <= 60:
        ax.set_xticks(np.arange(0, teeth + 1, max(1, teeth // 15)))
        ax.set_xticks(np.arange(0, teeth + 1), minor=True)
        ax.grid(True, which="minor", axis="x", lw=0.3, alpha=0.5)
    ax.set_xlim(0, teeth)
    return x


def tsa_figure(
    tsa: TSA,
    *,
    channel: Any = None,
    ax: Any = None,
    figsize: tuple[float, float] = (8.0, 3.5),
) -> Figure:
    """The average over one revolution, with the averaging figures in the title.

    Parameters
    ----------
    tsa : TSA
        From :func:`analysis.tsa.tsa` (or a planet/sun average).
    channel : int or str, optional
        One channel of a multi-channel average (default: all, one line each).
    ax : matplotlib.axes.Axes, optional
        Axes to draw into (default: a new figure).
    figsize : (float, float)
        Size in inches of a new figure.
    """
    require_instance(tsa, "analysis.tsa.TSA", "tsa")
    if ax is not None and (not hasattr(ax, "figure") or not hasattr(ax, "plot")):
        raise TypeError(f"ax must be matplotlib Axes; got {type(ax).__name__}")
    if ax is None:
        fig = _new(figsize)
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    values, dims, coords = _select(tsa.values, tsa.dims, tsa.coords, channel)
    if tsa.teeth:
        x = _tooth_axis(ax, tsa.teeth, tsa.angle)
        ax.set_xlabel(f"{tsa.shaft} tooth position (tooth k spans [k, k+1))")
    else:
        x = np.degrees(tsa.angle)
        ax.set_xlim(0, 360)
        ax.set_xticks(np.arange(0, 361, 45))
        ax.set_xlabel(f"{tsa.shaft} angle [deg] (0 = reference zero)")
    rows = _rows(values, dims, coords, tsa.name)
    for label, row in rows:
        ax.plot(x, row, lw=0.8, label=label)
    if len(rows) > 1:
        ax.legend(fontsize=8)
    ax.set_ylabel(f"{tsa.name} [{tsa.units}]")
    ax.grid(True, lw=0.3, alpha=0.5)
    what = "passes" if tsa.teeth else "revolutions"
    title = (
        f"TSA of {tsa.name}, {tsa.shaft}: {tsa.revolutions} {what}, noise x "
        f"{tsa.noise_reduction:.3g} ({tsa.noise_reduction_db:.1f} dB)"
    )
    if tsa.coverage < 1.0:
        title += f", {100 * tsa.coverage:.0f} % of the teeth seen"
    left = np.asarray(tsa.residual_noise_rms)
    if left.size == 1 and np.isfinite(left):
        title += f"; noise left ~ {float(left):.2g} {tsa.units} rms"
    ax.set_title(title, fontsize=9)
    return fig


def planetary_figure(
    separation: PlanetarySeparation,
    *,
    channel: Any = None,
    figsize: tuple[float, float] | None = None,
) -> Figure:
    """One panel per planet average and one for the sun, on their tooth axes.

    Parameters
    ----------
    separation : PlanetarySeparation
        From :func:`analysis.planetary_tsa.planetary_tsa`.
    channel : int or str, optional
        The channel of a multi-channel record (required then).
    figsize : (float, float), optional
        Default ``(8, 1.6 per panel + 0.6)``.
    """
    require_instance(separation, "analysis.planetary_tsa.PlanetarySeparation", "separation")
    gears = [*separation.planets, separation.sun]
    if gears[0].values.ndim > 1 and channel is None:
        raise ValueError("the record has several channels: choose one with channel=")
    fig = _new(figsize or (8.0, 1.6 * len(gears) + 0.6))
    axes = fig.subplots(len(gears), 1)
    for ax, g in zip(np.atleast_1d(axes), gears, strict=True):
        v, _, _ = _select(g.values, g.dims, g.coords, channel)
        x = g.angle * (g.teeth or 1) / (2.0 * np.pi)
        ax.plot(x, v, lw=0.7, color="C0" if g.shaft != "sun" else "C2")
        ax.set_xlim(0, g.teeth)
        ax.grid(True, lw=0.3, alpha=0.5)
        cov = "" if g.coverage >= 1.0 else f", {100 * g.coverage:.0f} % seen"
        ax.set_title(
            f"{g.shaft} ({g.teeth} teeth): {g.revolutions} passes, noise x "
            f"{g.noise_reduction:.2g}{cov}",
            fontsize=8, loc="left",
        )  # fmt: skip
        ax.set_ylabel(f"{g.name} [{g.units}]", fontsize=8)
        ax.tick_params(labelsize=7)
    np.atleast_1d(axes)[-1].set_xlabel("tooth position (teeth in the order they enter the mesh)")
    fig.suptitle(
        f"Planet and sun averages (McFadden): {separation.window} window "
        f"{separation.window_teeth:g} ring tooth pitches, {separation.carrier_revolutions} "
        "carrier revolutions",
        fontsize=9,
    )
    return fig


def gear_signals_figure(
    signals: GearSignals,
    *,
    channel: Any = None,
    figsize: tuple[float, float] = (8.0, 8.0),
) -> Figure:
    """TSA with its regular part, residual, difference signal and the order amplitudes.

    Parameters
    ----------
    signals : GearSignals
        From :func:`analysis.gear_signals.gear_signals`.
    channel : int or str, optional
        The channel of a multi-channel result (required then).
    figsize : (float, float)
        Figure size in inches.
    """
    require_instance(signals, "analysis.gear_signals.GearSignals", "signals")
    if signals.tsa.ndim > 1 and channel is None:
        raise ValueError("the signals have several channels: choose one with channel=")

    def pick(a: np.ndarray) -> np.ndarray:
        return _select(a, signals.dims, signals.coords, channel)[0]

    fig = _new(figsize)
    axes = fig.subplots(4, 1)
    u = signals.units
    tsa_row = pick(signals.tsa)
    series: list[tuple[str, list[tuple[np.ndarray, str | None, str]]]] = [
        ("TSA and regular meshing components", [(tsa_row, "TSA", "C0"),
                                                (pick(signals.regular) + tsa_row.mean(),
                                                 "regular (+ mean)", "C1")]),
        ("residual: TSA - shaft orders - mesh harmonics (sidebands kept)",
         [(pick(signals.residual), None, "C2")]),
        ("difference: TSA - regular components (first-order sidebands removed too)",
         [(pick(signals.difference), None, "C3")]),
    ]  # fmt: skip
    for ax, (title, lines) in zip(axes[:3], series, strict=True):
        if signals.teeth:
            x = _tooth_axis(ax, signals.teeth, signals.angle)
        else:
            x = np.degrees(signals.angle)
            ax.set_xlim(0, 360)
            ax.set_xticks(np.arange(0, 361, 45))
        for y, label, colour in lines:
            ax.plot(x, y, lw=0.7, label=label, color=colour)
        ax.set_title(title, fontsize=8, loc="left")
        ax.set_ylabel(f"{signals.name} [{u}]", fontsize=8)
        ax.grid(True, lw=0.3, alpha=0.5)
    axes[0].legend(fontsize=7, loc="upper right")
    axes[2].set_xlabel(
        f"{signals.shaft} tooth position" if signals.teeth else f"{signals.shaft} angle [deg]"
    )
    amp = pick(signals.amplitudes)
    top = int(min(amp.size - 1, max(signals.regular_orders.max(initial=1), 1) * 1.1 + 2))
    orders = np.arange(1, top + 1)
    floor = max(float(np.max(amp[orders])) * 1e-4, np.finfo(float).tiny)
    ax = axes[3]
    ax.vlines(orders, floor, np.maximum(amp[orders], floor), lw=0.8, color="0.6",
              label="orders of the TSA")  # fmt: skip
    reg = signals.regular_orders[signals.regular_orders <= top]
    ax.plot(reg, np.maximum(amp[reg], floor), "o", ms=3, color="C1",
            label="regular (removed in the difference)")  # fmt: skip
    mesh = signals.mesh_lines[signals.mesh_lines <= top]
    ax.plot(mesh, np.maximum(amp[mesh], floor), "v", ms=5, color="C3", label="mesh harmonics")
    ax.set_yscale("log")
    ax.set_ylim(floor, None)
    ax.set_xlim(0, top + 1)
    ax.set_xlabel(f"order of the {signals.shaft}")
    ax.set_ylabel(f"peak amplitude [{u}]", fontsize=8)
    mesh_txt = ", ".join(str(z) for z in signals.mesh_orders)
    ax.set_title(
        f"order amplitudes of the TSA: mesh order {mesh_txt}, {signals.harmonics} harmonics, "
        f"sidebands +-{signals.sidebands}, shaft orders 1-{signals.shaft_harmonics}",
        fontsize=8, loc="left",
    )  # fmt: skip
    ax.legend(fontsize=7, loc="upper right")
    ax.grid(True, lw=0.3, alpha=0.5)
    return fig


def trend_figure(
    indicators: xr.Dataset,
    *,
    limits: AlarmLimits | None = None,
    variables: Sequence[str] | None = None,
    channel: Any = None,
    x: str = "record",
    figsize: tuple[float, float] | None = None,
) -> Figure:
    """Condition-monitoring history: one panel per indicator over the records, with alarm
    limits and the values outside them marked.

    Parameters
    ----------
    indicators : xarray.Dataset
        From :func:`analysis.indicators.condition_indicators`.
    limits : AlarmLimits, optional
        From :func:`analysis.alarm_limits.learn_limits`: drawn as dashed lines, the healthy
        records learned from shaded, exceedances in red.
    variables : sequence of str, optional
        Indicators to draw (default: those of ``limits``, else all).
    channel : int or str, optional
        Channel to draw when the indicators have a channel dimension (required then).
    x : {"record", "time"}, default "record"
        Abscissa: the record number or the start time of each record's average [s].
    figsize : (float, float), optional
        Default ``(10, 1.9 per row + 0.8)`` with three panels per row.
    """
    import xarray

    require_instance(indicators, xarray.Dataset, "indicators")
    if limits is not None:
        require_instance(limits, "analysis.alarm_limits.AlarmLimits", "limits")
    if x not in ("record", "time"):
        raise ValueError(f"x = {x!r} is not admissible: 'record' or 'time'")
    names = list(variables) if variables is not None else (
        list(limits.indicators) if limits is not None else list(indicators.data_vars)
    )
    ds = indicators
    lim_u = limits.upper if limits is not None else None
    lim_l = limits.lower if limits is not None else None
    other = [d for d in ds.dims if d != "record"]
    if other:
        if channel is None:
            raise ValueError(f"the indicators have dimensions {other}: choose one with channel=")
        d = other[0]
        sel = {d: channel} if d in ds.coords and not isinstance(channel, int) else None
        ds = ds.sel(sel) if sel else ds.isel({d: int(channel)})
        if lim_u is not None and lim_l is not None:
            lim_u = lim_u.sel(sel) if sel else lim_u.isel({d: int(channel)})
            lim_l = lim_l.sel(sel) if sel else lim_l.isel({d: int(channel)})
    xs = ds["time"].values if x == "time" else ds["record"].values
    cols = 3
    rows = math.ceil(len(names) / cols)
    fig = _new(figsize or (10.0, 1.9 * rows + 0.8))
    axes = np.atleast_1d(fig.subplots(rows, cols, sharex=True)).ravel()
    for ax, name in zip(axes, names, strict=False):
        y = np.asarray(ds[name].values, dtype=float)
        ax.plot(xs, y, ".-", lw=0.6, ms=3, color="C0")
        if lim_u is not None and lim_l is not None and limits is not None:
            up = float(lim_u[name].values)
            ax.axhline(up, ls="--", lw=0.8, color="C3")
            lo = float(lim_l[name].values)
            if np.isfinite(lo):
                ax.axhline(lo, ls="--", lw=0.8, color="C3")
            bad = (y > up) | (y < lo)
            ax.plot(xs[bad], y[bad], "o", ms=4, color="C3")
            h = limits.healthy_records
            if x == "record" and h <= xs.size:
                ax.axvspan(xs[0] - 0.5, xs[min(h, xs.size) - 1] + 0.5, color="C2", alpha=0.08)
        units = ds[name].attrs.get("units", "1")
        ax.set_title(str(name) + ("" if units == "1" else f" [{units}]"), fontsize=8, loc="left")
        ax.tick_params(labelsize=7)
        ax.grid(True, lw=0.3, alpha=0.5)
    for ax in axes[len(names):]:
        ax.set_visible(False)
    for ax in axes[max(0, len(names) - cols) : len(names)]:
        ax.set_xlabel("record" if x == "record" else "time [s]", fontsize=8)
        ax.tick_params(labelbottom=True)
    title = "condition indicators"
    if limits is not None:
        title += (
            f": alarm limits mean {'+' if limits.sides == 'upper' else '+-'} "
            f"{limits.k:g} std of {limits.healthy_records} healthy records (shaded); "
            "red = outside"
        )
    fig.suptitle(title, fontsize=9)
    return fig
