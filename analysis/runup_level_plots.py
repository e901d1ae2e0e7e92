"""Figures of :class:`analysis.runup_levels.RunupLevels`: order cuts with the overall level,
waterfall and Campbell diagram.

Plotting only, with the Figure API (never pyplot); every function returns a new
:class:`matplotlib.figure.Figure`. Levels are rms in dB re 1 unit of the signal; speed is in
min⁻¹, frequency in Hz. Legends stand outside the axes and each panel of the order cuts holds
at most a handful of curves, so the figures stay readable when many orders are cut.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.checks import require_int, require_positive, require_real

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from analysis.runup_levels import RunupLevels

__all__ = ["campbell_levels_figure", "order_cuts_levels_figure", "waterfall_figure"]

MAX_CURVES = 5
"""Most order cuts drawn in one panel by default."""


def _check(lv: Any, marks: Any = 0, frequency_max: Any = None,
           figsize: Any = (8.0, 4.0), **positive: Any) -> None:
    """The result type and the figure options (one-line errors naming the option)."""
    if f"{type(lv).__module__}.{type(lv).__name__}" != "analysis.runup_levels.RunupLevels":
        raise TypeError(f"lv must be an analysis.runup_levels.RunupLevels, got "
                        f"{type(lv).__name__}")
    require_int(marks, "marks", 0)
    if frequency_max is not None:
        require_positive(require_real(frequency_max, "frequency_max"), "frequency_max")
    for name, value in positive.items():
        require_positive(require_real(value, name), name)
    if not isinstance(figsize, tuple | list) or len(figsize) != 2:
        raise ValueError(f"figsize = {figsize!r} must be (width, height) in inches")
    for k, v in enumerate(figsize):
        if not 0.5 <= require_real(v, f"figsize[{k}]") <= 100.0:
            raise ValueError(f"figsize[{k}] = {v!r} must lie in 0.5..100 inches")


def _figure(figsize: tuple[float, float]) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=figsize, layout="constrained", dpi=100)


def _finite_max(values: Any) -> float:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return float(v.max()) if v.size else 0.0


def _speed_axis(lv: RunupLevels) -> tuple[np.ndarray, str]:
    """Cut frames over speed (a run-up) or over time (constant speed)."""
    if lv.varying_speed:
        return np.asarray(lv.cuts.rpm, dtype=float), "speed [min⁻¹]"
    return np.asarray(lv.cuts.time, dtype=float), "time [s]"


def _panels(lv: RunupLevels, panels: Sequence[Sequence[int]] | None, max_curves: int
            ) -> list[list[int]]:
    n = lv.cuts.orders.size
    if panels is None:
        idx = list(range(n))
        return [idx[i:i + max_curves] for i in range(0, n, max_curves)] or [[]]
    out = [[int(i) for i in p if 0 <= int(i) < n] for p in panels]
    out = [p for p in out if p]
    return out or [[]]


def order_cuts_levels_figure(
    lv: RunupLevels,
    *,
    panels: Sequence[Sequence[int]] | None = None,
    max_curves: int = MAX_CURVES,
    marks: int = 0,
    dynamic_range_db: float = 60.0,
    width: float = 8.0,
) -> Figure:
    """Order cuts in dB over speed, the overall level in the first panel.

    Parameters
    ----------
    lv : RunupLevels
        The levels.
    panels : sequence of sequence of int, optional
        Cut indices per panel (default: the cuts in order, ``max_curves`` per panel).
    max_curves : int
        Cuts per panel when ``panels`` is not given.
    marks : int
        Number the ``marks`` strongest cut resonances (``lv.peaks``) ``1, 2, ...`` on their
        curve (the rank of a table that lists them).
    dynamic_range_db : float
        Range of the level axis below the highest level.
    width : float
        Figure width [in]; the height follows the panels.
    """
    _check(lv, marks, figsize=(width, 4.0), dynamic_range_db=dynamic_range_db)
    require_int(max_curves, "max_curves", 1)
    groups = _panels(lv, panels, max(1, int(max_curves)))
    fig = _figure((width, 1.6 + 2.2 * len(groups)))
    axes = fig.subplots(len(groups), 1, squeeze=False, sharex=True)[:, 0]
    x, xlabel = _speed_axis(lv)
    order = np.argsort(x, kind="stable")
    ov = lv.overall
    ox = np.asarray(ov.rpm if lv.varying_speed else ov.time, dtype=float)
    oo = np.argsort(ox, kind="stable")
    top = max(_finite_max(lv.cuts.values), _finite_max(ov.values))
    colour = {i: f"C{k % 10}" for k, i in enumerate(range(lv.cuts.orders.size))}
    for p, (ax, idx) in enumerate(zip(axes, groups, strict=True)):
        if p == 0:
            lo_f, hi_f = ov.frequency_range
            ax.plot(ox[oo], np.asarray(ov.values, dtype=float)[oo], color="k", lw=1.6,
                    label=f"overall {lo_f:.3g}–{hi_f:.4g} Hz")
        for i in idx:
            y = np.asarray(lv.cuts.values[i], dtype=float)[order]
            below = _finite_max(y) < top - dynamic_range_db if np.isfinite(y).any() else True
            ax.plot(x[order], y, color=colour[i], lw=1.0,
                    label=f"{lv.order_names[i]} ({lv.cuts.orders[i]:.4g})"
                    + (f": below the {dynamic_range_db:g} dB shown" if below else ""))
        ax.set_ylim(top - dynamic_range_db, top + 4.0)
        ax.set_ylabel(f"rms level\n[dB re {lv.level_reference}]")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False,
                  title="order (cycles/rev)" if p == 0 else None, title_fontsize=7)
    pk = lv.peaks
    for rank in range(min(int(marks), len(pk))):
        i = int(np.flatnonzero(np.isclose(lv.cuts.orders, pk.order[rank]))[0])
        ax = next(a for a, g in zip(axes, groups, strict=True) if i in g)
        xm = pk.rpm[rank] if lv.varying_speed else pk.time[rank]
        ax.plot([xm], [pk.level_db[rank]], "o", mfc="none", mec="k", ms=9, mew=1.0)
        ax.annotate(str(rank + 1), (xm, pk.level_db[rank]), xytext=(0, 7),
                    textcoords="offset points", ha="center", va="bottom", fontsize=8,
                    fontweight="bold")
    axes[-1].set_xlabel(xlabel)
    axes[0].set_title(
        f"{lv.name}: order cuts and overall level\nflat-top, resolution {lv.resolution:.3g} "
        f"orders, band {lv.cuts.bandwidth:.3g} orders", fontsize=9)
    return fig


def waterfall_figure(
    lv: RunupLevels,
    *,
    dynamic_range_db: float = 50.0,
    spacings_per_range: float = 3.0,
    frequency_max: float | None = None,
    figsize: tuple[float, float] = (8.0, 4.8),
) -> Figure:
    """Waterfall: the spectra of the map at evenly spaced speeds, each drawn on its speed.

    A trace's baseline is its speed; its height above the baseline is the level above
    ``top - dynamic_range_db``, scaled so that ``dynamic_range_db`` spans
    ``spacings_per_range`` trace spacings (a scale bar shows 20 dB). Traces in front (lower
    speed) hide those behind. Dashed: the cut orders; dotted: the natural frequencies.
    """
    _check(lv, 0, frequency_max, figsize, dynamic_range_db=dynamic_range_db,
           spacings_per_range=spacings_per_range)
    w = lv.waterfall
    fig = _figure(figsize)
    ax = fig.add_subplot()
    y0 = w.rpm if lv.varying_speed else w.time
    n = len(w)
    spacing = float(np.median(np.diff(y0))) if n > 1 else 1.0
    spacing = spacing if spacing > 0 else 1.0
    gain = spacings_per_range * spacing / dynamic_range_db
    top = _finite_max(w.level_db)
    floor = top - dynamic_range_db
    fmax = float(frequency_max) if frequency_max is not None else float(w.frequency[-1])
    band = w.frequency <= fmax
    f = w.frequency[band]
    from matplotlib import colormaps

    cmap = colormaps["viridis"]
    for i in range(n - 1, -1, -1):
        y = y0[i] + gain * (np.clip(w.level_db[i][band], floor, None) - floor)
        z = 2 * (n - i)
        ax.fill_between(f, y0[i], y, color="w", lw=0, zorder=z)
        ax.plot(f, y, color=cmap(0.85 * i / max(n - 1, 1)), lw=0.7, zorder=z + 1)
    lo_y, hi_y = float(y0[0]) - spacing, float(y0[-1]) + gain * dynamic_range_db + spacing
    over = 2 * n + 2  # order rays and natural frequencies drawn over the traces
    if lv.varying_speed:
        r = np.array([float(y0[0]), float(y0[-1])])
        for k, o in enumerate(lv.cuts.orders):
            ax.plot(o * r / 60.0, r, color="C3", lw=0.7, ls="--", alpha=0.6, zorder=over,
                    label="cut orders" if k == 0 else None)
    for k, fn in enumerate(lv.campbell.natural_frequencies_hz):
        if fn <= fmax:
            ax.axvline(fn, color="C1", lw=0.8, ls=":", alpha=0.8, zorder=over,
                       label="natural frequencies" if k == 0 else None)
    # scale bar: 20 dB
    xb = 0.985 * fmax
    ax.plot([xb, xb], [hi_y - spacing - 20 * gain, hi_y - spacing], color="k", lw=2.0,
            zorder=10 * n)
    ax.annotate("20 dB", (xb, hi_y - spacing - 10 * gain), xytext=(-4, 0),
                textcoords="offset points", ha="right", va="center", fontsize=7,
                zorder=10 * n)
    ax.set_xlim(0, fmax)
    ax.set_ylim(lo_y, hi_y)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(("speed [min⁻¹]" if lv.varying_speed else "time [s]")
                  + " (trace baseline)")
    spectra = "1 spectrum" if n == 1 else f"{n} spectra"
    ax.set_title(f"{w.name}: waterfall of {spectra}\n{w.window}, RBW {w.resolution_hz:.3g} "
                 f"Hz, {w.amplitude} level in dB re {w.level_reference}, "
                 f"{dynamic_range_db:g} dB shown", fontsize=9)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    return fig


def _spread(values: Sequence[float], min_gap: float) -> list[bool]:
    """Which of the sorted ``values`` get a label: each at least ``min_gap`` above the last."""
    keep, last = [], -np.inf
    for v in values:
        ok = v - last >= min_gap
        keep.append(ok)
        if ok:
            last = v
    return keep


def campbell_levels_figure(
    lv: RunupLevels,
    *,
    dynamic_range_db: float = 40.0,
    frequency_max: float | None = None,
    marks: int = 0,
    figsize: tuple[float, float] = (8.0, 4.6),
) -> Figure:
    """Campbell diagram: speed across, frequency up; each cut order a ray coloured (and sized)
    by its level, natural frequencies as dotted horizontal lines, critical speeds (a ray
    crossing a natural frequency) as open circles, the ``marks`` strongest cut resonances
    numbered ``1, 2, ...``. At constant speed the rays run from 0 to 1.25 times the speed and
    the operating speed is shaded."""
    _check(lv, marks, frequency_max, figsize, dynamic_range_db=dynamic_range_db)
    fig = _figure(figsize)
    ax = fig.add_subplot()
    c = lv.campbell
    cut = lv.cuts
    top = _finite_max(cut.values)
    floor = top - dynamic_range_db
    fn = c.natural_frequencies_hz
    fmax = float(frequency_max) if frequency_max is not None else float(max(
        _finite_max(c.order_frequency), 1.1 * float(fn.max()) if fn.size else 0.0))
    grid = c.rpm
    xr_lo, xr_hi = float(grid[0]), float(grid[-1])
    sc = None
    for i, o in enumerate(cut.orders):
        ray = o * grid / 60.0
        ax.plot(grid, ray, color="0.6", lw=0.6, zorder=1)
        lvl = np.asarray(cut.values[i], dtype=float)
        ok = np.isfinite(lvl)
        rpm = np.asarray(cut.rpm, dtype=float)[ok]
        size = 4.0 + 40.0 * np.clip((lvl[ok] - floor) / dynamic_range_db, 0.0, 1.0) ** 2
        sc = ax.scatter(rpm, o * rpm / 60.0, c=np.clip(lvl[ok], floor, None), s=size,
                        cmap="viridis", vmin=floor, vmax=top, lw=0, zorder=3)
        # ray label where it leaves the plot
        if o * xr_hi / 60.0 <= fmax:
            xy, off, ha, va = (xr_hi, o * xr_hi / 60.0), (3, 0), "left", "center"
        else:
            xy, off, ha, va = (60.0 * fmax / o, fmax), (-3, -2), "right", "top"
        ax.annotate(f"{o:.4g}", xy, xytext=off, textcoords="offset points", ha=ha, va=va,
                    fontsize=6.5, color="0.25", annotation_clip=False)
    names = list(lv.natural_names)
    order_fn = np.argsort(fn)
    show = _spread([float(fn[k]) for k in order_fn], 0.03 * fmax)
    for k, keep in zip(order_fn, show, strict=True):
        if fn[k] > fmax:
            continue
        ax.axhline(fn[k], color="C1", lw=0.8, ls=":", zorder=2)
        if keep:
            ax.annotate(names[k] if k < len(names) else "", (0.0, fn[k]),
                        xycoords=("axes fraction", "data"), xytext=(3, 2),
                        textcoords="offset points", fontsize=7, color="C1", va="bottom")
    crit = c.critical_rpm
    first = True
    for i in range(crit.shape[0]):
        ok = np.isfinite(crit[i]) & (fn <= fmax)
        if ok.any():
            ax.plot(crit[i, ok], fn[ok], "o", mfc="none", mec="k", ms=6, mew=0.8, zorder=4,
                    label="critical speed (ray × natural frequency)" if first else None)
            first = False
    pk = lv.peaks
    for rank in range(min(int(marks), len(pk))):
        ax.annotate(str(rank + 1), (pk.rpm[rank], pk.frequency_hz[rank]), xytext=(5, 5),
                    textcoords="offset points", fontsize=8, fontweight="bold", color="C3",
                    zorder=6, bbox={"boxstyle": "round,pad=0.15", "fc": "w", "ec": "C3",
                                    "lw": 0.6})
    if not lv.varying_speed:
        lo, hi = lv.speed_range
        ax.axvspan(lo - 0.005 * hi, hi + 0.005 * hi, color="C3", alpha=0.15, lw=0,
                   label="operating speed")
    if sc is not None:
        fig.colorbar(sc, ax=ax, label=f"order level, rms [dB re {lv.level_reference}]")
    ax.set_xlim(xr_lo, xr_hi)
    ax.set_ylim(0, fmax)
    ax.set_xlabel("speed [min⁻¹]")
    ax.set_ylabel("frequency [Hz]")
    ax.set_title(f"{lv.name}: Campbell diagram\nrays: cut orders (labelled with their "
                 "order), dotted: natural frequencies", fontsize=9)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper left", fontsize=7)
    ax.grid(True, alpha=0.25)
    return fig
