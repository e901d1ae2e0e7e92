"""Figures of Vold-Kalman order tracking (:mod:`analysis.vold_kalman`).

Plotting only, built with the Figure API (no pyplot state); matplotlib is imported lazily.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.checks import require_instance, require_int, require_positive, require_real
from analysis.inputs import select_channel

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from analysis.vold_kalman import OrderRemoval, OrderWaveforms

__all__ = ["order_removal_figure", "order_waveform_figure"]


def _figure(figsize: tuple[float, float]) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=figsize, layout="constrained")


def _one(res: OrderWaveforms, channel: Any) -> OrderWaveforms:
    if res.envelope.ndim == 2:
        return res
    if channel is None:
        d = res.dims[0]
        labels = (
            list(np.asarray(res.coords[d]))
            if d in res.coords
            else (list(range(res.envelope.shape[0])))
        )
        raise ValueError(f"the result has {res.envelope.shape[0]} channels: choose one with "
                         f"channel= (one of {labels})")  # fmt: skip
    return res.select(channel)


def _abscissa(res: OrderWaveforms, xaxis: str) -> tuple[np.ndarray, str]:
    if not isinstance(xaxis, str):
        raise TypeError(f"xaxis must be 'time' or 'rpm'; got {type(xaxis).__name__}")
    if xaxis == "time":
        return res.time, "time [s]"
    if xaxis == "rpm":
        return res.rpm[0], "speed of shaft 0 [min⁻¹]"
    raise ValueError(f"xaxis = {xaxis!r} is not admissible: 'time' or 'rpm'")


def _wrapped(deg: np.ndarray) -> np.ndarray:
    """Phase in (-180, 180] with NaN at the wraps (no vertical lines)."""
    w = (deg + 180.0) % 360.0 - 180.0
    out = w.astype(float).copy()
    jumps = np.flatnonzero(np.abs(np.diff(w)) > 180.0)
    out[jumps + 1] = np.nan
    return out


def order_waveform_figure(
    res: OrderWaveforms,
    *,
    channel: Any = None,
    xaxis: str = "time",
    db: bool = False,
    max_points: int = 4000,
    figsize: tuple[float, float] = (8.0, 7.0),
) -> Figure:
    """Frequency, peak amplitude and phase of every tracked order.

    Parameters
    ----------
    res : OrderWaveforms
        Result of :func:`analysis.vold_kalman.order_waveform`.
    channel : label or int, optional
        Channel to draw (required for a multi-channel result).
    xaxis : {"time", "rpm"}
        Abscissa: time or the speed of shaft 0.
    db : bool
        Amplitude in dB re 1 unit instead of linear.
    max_points : int
        Points per curve (the curves are sampled evenly).
    figsize : tuple of float
        Figure size [in].
    """
    require_instance(res, "analysis.vold_kalman_results.OrderWaveforms", "res")
    max_points = require_int(max_points, "max_points", 2)
    res = _one(res, channel)
    x, xlabel = _abscissa(res, xaxis)
    step = max(1, -(-x.size // max_points))
    sl = slice(None, None, step)
    fig = _figure(figsize)
    ax_f, ax_a, ax_p = fig.subplots(3, 1, sharex=True)
    amp = res.amplitude
    for k, o in enumerate(res.orders):
        lab = f"order {o:g}" + (f" (shaft {res.shafts[k]})" if res.rpm.shape[0] > 1 else "")
        ax_f.plot(x[sl], res.frequency[k, sl], lw=1.0, label=lab)
        a = amp[k, sl]
        ax_a.plot(x[sl], 20 * np.log10(np.maximum(a, 1e-300)) if db else a, lw=1.0, label=lab)
        ax_p.plot(x[sl], _wrapped(np.degrees(res.phase[k, sl])), lw=0.8, label=lab)
    ax_f.set_ylabel("frequency [Hz]")
    ax_a.set_ylabel(
        f"peak amplitude [dB re 1 {res.units}]" if db else f"peak amplitude [{res.units}]"
    )
    ax_p.set_ylabel("phase [°]")
    ax_p.set_ylim(-185, 185)
    ax_p.set_yticks([-180, -90, 0, 90, 180])
    ax_p.set_xlabel(xlabel)
    for ax in (ax_f, ax_a, ax_p):
        ax.grid(True, alpha=0.3)
    ax_f.legend(fontsize=8, loc="upper left")
    bws = ", ".join(f"{b:.3g}" for b in np.unique(res.bandwidth))
    mode = "joint" if res.joint else "separate"
    ax_f.set_title(
        f"{res.name}: Vold-Kalman orders, bandwidth {bws} Hz, filter order "
        f"{res.filter_order}, {mode}",
        fontsize=10,
    )
    return fig


def _frame_rms(v: np.ndarray, length: int) -> tuple[np.ndarray, np.ndarray]:
    n = v.size
    length = max(1, min(length, n))
    k = n // length
    blocks = v[: k * length].reshape(k, length)
    centres = (np.arange(k) + 0.5) * length
    return centres, np.sqrt(np.mean(blocks**2, axis=1))


def order_removal_figure(
    rem: OrderRemoval,
    *,
    channel: Any = None,
    xaxis: str = "time",
    frame: float | None = None,
    figsize: tuple[float, float] = (8.0, 4.0),
) -> Figure:
    """Rms in frames of the input, of the signal with the orders removed and of the residual.

    Parameters
    ----------
    rem : OrderRemoval
        Result of :func:`analysis.vold_kalman.remove_orders`.
    channel : label or int, optional
        Channel to draw (required for a multi-channel result).
    xaxis : {"time", "rpm"}
        Abscissa: time or the speed of shaft 0.
    frame : float, optional
        Frame length [s]; default four periods of the slowest tracked order (its median
        frequency), at least 1/400 of the record.
    figsize : tuple of float
        Figure size [in].
    """
    require_instance(rem, "analysis.vold_kalman_results.OrderRemoval", "rem")
    ex = rem.extraction
    signal, residual = rem.signal, rem.residual
    if ex.envelope.ndim > 2:
        one = _one(ex, channel)
        signal = select_channel(rem.signal, ex.dims, ex.coords, channel)[0]
        residual = select_channel(rem.residual, ex.dims, ex.coords, channel)[0]
        ex = one
    x, xlabel = _abscissa(ex, xaxis)
    original = ex.without([])
    if frame is None:
        slowest = float(np.min(np.median(ex.frequency, axis=1)))
        frame = 4.0 / slowest if slowest > 0 else x.size / ex.fs / 400
    else:
        frame = require_positive(require_real(frame, "frame"), "frame")
        if frame > x.size / ex.fs:
            raise ValueError(f"frame = {frame:g} s is not admissible: (0, {x.size / ex.fs:g}] s "
                             "(the record's length)")
    length = max(round(float(frame) * ex.fs), x.size // 400, 1)
    fig = _figure(figsize)
    ax = fig.add_subplot()
    removed = ", ".join(f"{ex.orders[k]:g}" for k in rem.removed)
    removed = f"order{'s' if len(rem.removed) > 1 else ''} {removed}"
    for v, lab in (
        (original, "input"),
        (signal, f"{removed} removed"),
        (residual, "residual (every tracked order removed)"),
    ):
        c, r = _frame_rms(v, length)
        ax.plot(x[c.astype(int)], r, lw=1.0, label=lab)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(f"rms [{ex.units}]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(
        f"{ex.name}: orders removed by Vold-Kalman filtering (rms in frames of "
        f"{length / ex.fs:.3g} s)",
        fontsize=10,
    )
    return fig
