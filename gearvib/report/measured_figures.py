"""Figures of a measured report, drawn from a :class:`~gearvib.report.measured_case.MeasuredCase`.

The record with its reference speed (:func:`record_figure`), the spectrum and order spectrum
with their labelled peaks (:func:`spectra_figure`), and the rpm-frequency and rpm-order maps
with the mesh (or shaft) orders, natural frequencies, map lines and classified rises
(:func:`sonogram_figure`, :func:`order_map_figure`). They compute nothing of their own and use
the Figure API, never pyplot.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from analysis.identification import PeakIdentification
from analysis.plots import rpm_frequency_map_figure, rpm_order_map_figure
from analysis.spectrum import to_db
from gearvib.report.figures import Label, natural_frequency_lines, place_labels
from gearvib.report.measured_case import MeasuredCase
from gearvib.report.measured_resonances import strongest_rays

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["order_map_figure", "record_figure", "sonogram_figure", "spectra_figure"]


_DYNAMIC_RANGE_DB = 50.0


def _figure(figsize: tuple[float, float]) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=figsize, layout="constrained", dpi=100)


def record_figure(mc: MeasuredCase, figsize: tuple[float, float] = (8.0, 3.8)) -> Figure:
    """The analysed channel over time with the reference speed on a second axis."""
    fig = _figure(figsize)
    ax = fig.subplots()
    m = mc.measurement
    t = m.time
    stride = max(1, t.size // 20000)
    ax.plot(t[::stride], m.channel(mc.channel).values[::stride], lw=0.5, color="C0",
            label=mc.channel)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(f"{mc.channel} [{mc.units}]")
    ax.grid(True, alpha=0.3)
    ax2 = ax.twinx()
    ax2.plot(t[::stride], m.speed_rpm.values[::stride], color="k", lw=1.0, ls="--",
             label="reference speed")
    ax2.set_ylabel("reference speed [min⁻¹]")
    ax.legend(loc="upper left", fontsize=7)
    ax2.legend(loc="lower right", fontsize=7)
    fig.suptitle(f"{mc.name}: channel {mc.channel} and the reference speed", fontsize=10)
    return fig


def _short(ident: PeakIdentification, i: int, unit: str) -> str:
    head = f"{ident.peaks[i]:.3g}" if unit == "order" else f"{ident.peaks[i]:.0f}"
    st = str(ident.status[i])
    ms = ident.matches[i]
    if st == "explained":
        return f"{head}\n≈ {ms[0].expression.split(' ≈ ')[0]}"
    return f"{head}\n" + ("?" if st == "unexplained" else "~")


def spectra_figure(mc: MeasuredCase, figsize: tuple[float, float] = (8.0, 6.4)) -> Figure:
    """Spectrum (top) and order spectrum (bottom) with the strongest peaks labelled."""
    n = 2 if mc.order_spectrum is not None else 1
    fig = _figure((figsize[0], figsize[1] if n == 2 else 3.4))
    axes = fig.subplots(n, 1, squeeze=False)[:, 0]
    sp = mc.spectrum
    band = sp.frequency <= mc.frequency_max_hz
    ax = axes[0]
    ax.plot(sp.frequency[band], to_db(sp.values[band], sp.amplitude), lw=0.7)
    for f in mc.natural_frequencies_hz:
        if f <= mc.frequency_max_hz:
            ax.axvline(f, color="C1", lw=0.7, ls=":")
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo, hi + 0.3 * (hi - lo))
    ax.set_xlim(0, mc.frequency_max_hz)
    ax.set_xlabel("frequency [Hz]" + ("  (dotted: natural frequencies of the model)"
                                      if mc.natural_frequencies_hz.size else ""))
    ax.set_ylabel(f"rms level\n[dB re 1 {mc.units}]")
    ax.set_title(f"spectrum over the record: Hann, RBW {sp.enbw_hz:.3g} Hz, "
                 f"{sp.n_averages} averages", fontsize=9)
    ax.grid(True, alpha=0.3)
    labelled = []
    if len(mc.peaks):
        y = to_db(mc.peaks.amplitude, sp.amplitude)
        ax.plot(mc.peaks.frequency, y, "v", color="C3", ms=4)
        labelled.append((ax, mc.peaks.frequency, y,
                         [_short(mc.identification, i, "Hz") for i in range(len(mc.peaks))]))
    os_ = mc.order_spectrum
    if os_ is not None:  # n == 2
        ax = axes[1]
        ax.plot(os_.order, to_db(os_.values, os_.amplitude), lw=0.7, color="C2")
        for _, f_ref, k in mc.mesh_groups:
            for j in range(1, k + 1):
                if 60 * f_ref * j <= os_.order[-1]:
                    ax.axvline(60 * f_ref * j, color="0.5", lw=0.6, ls="--")
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi + 0.3 * (hi - lo))
        ax.set_xlim(0, float(os_.order[-1]))
        ax.set_xlabel("order of the reference shaft" + ("  (dashed: mesh orders)"
                                                        if mc.mesh_groups else ""))
        ax.set_ylabel(f"rms level\n[dB re 1 {mc.units}]")
        ax.set_title(f"order spectrum: Hann, RBW {os_.resolution_orders:.3g} orders, "
                     f"{os_.n_averages} averages", fontsize=9)
        ax.grid(True, alpha=0.3)
        if mc.order_peaks is not None and len(mc.order_peaks):
            order_ident = mc.order_identification
            assert order_ident is not None  # identified with the peaks
            y = to_db(mc.order_peaks.amplitude, os_.spectrum.amplitude)
            ax.plot(mc.order_peaks.order, y, "v", color="C3", ms=4)
            labelled.append((ax, mc.order_peaks.order, y,
                             [_short(order_ident, i, "order")
                              for i in range(len(mc.order_peaks))]))
    fig.suptitle(f"{mc.name}: {mc.channel} ('?' unexplained, '~' only chance-level labels)",
                 fontsize=10)

    items = []
    for a, xs, ys, texts in labelled:
        for i in np.argsort(ys)[::-1][:6]:
            items.append((a, Label(texts[i], (float(xs[i]), float(ys[i])),
                                   ((0, 4), (14, 4), (-14, 4), (0, 16)),
                                   {"ha": "center", "va": "bottom", "fontsize": 6.5})))
    place_labels(fig, None, items)
    return fig


def sonogram_figure(mc: MeasuredCase, figsize: tuple[float, float] = (7.5, 6.2)
                    ) -> Figure | None:
    """Rpm-frequency map with the mesh orders (or shaft orders) and natural frequencies."""
    if mc.fmap is None:
        return None

    fig = rpm_frequency_map_figure(mc.fmap, hz_per_rpm=(), orders=(),
                                   dynamic_range_db=_DYNAMIC_RANGE_DB,
                                   frequency_max=mc.frequency_max_hz, figsize=figsize)
    ax = fig.axes[0]
    lo, hi = ax.get_ylim()
    fmax = ax.get_xlim()[1]
    labels = []
    styles = (("w", "--"), ("#00e5ff", "-"), ("#ff66ff", "-."), ("#ffd400", ":"))
    fams = list(mc.mesh_groups)
    if fams:
        order_lists = [list(range(1, k + 1)) for _, _, k in fams]
    else:  # without a gear set: the rays the map shows, at their measured orders
        fams = [(f"order {o:.4g}", o / 60.0, 1) for o in strongest_rays(mc.features)]
        order_lists = [[1] for _ in fams]
    for j, ((gname, f_ref, _), ks) in enumerate(zip(fams, order_lists, strict=True)):
        colour, dash = styles[j % len(styles)] if mc.mesh_groups else styles[0]
        for k in ks:
            freq = k * f_ref * np.array([lo, hi])
            if freq[0] >= fmax:
                continue
            ax.plot(freq, [lo, hi], color=colour, lw=0.9, ls=dash, alpha=0.9,
                    label=(f"mesh orders ({gname})" if mc.mesh_groups else
                           "order rays of the map" if j == 0 else None)
                    if k == ks[0] else None)
            tag = (f"{k}×" if len(fams) == 1 else f"{k}× {gname}") if mc.mesh_groups \
                else f"{60 * f_ref:.4g}×"
            style = {"color": colour, "fontsize": 7, "bbox": {"boxstyle": "round,pad=0.1",
                                                               "fc": "0.15", "ec": "none",
                                                               "alpha": 0.6}}
            if freq[1] <= fmax:
                labels.append(Label(tag, (float(freq[1]), hi), ((-2, -3), (-2, -14)),
                                    {**style, "ha": "right", "va": "top"}))
            else:
                labels.append(Label(tag, (fmax, float(fmax / (k * f_ref))), ((3, -4), (3, 5)),
                                    {**style, "ha": "left", "va": "center"}))
    named = natural_frequency_lines(ax, mc.natural_frequencies_hz, mc.mode_names, fmax)
    for f, n in named:
        labels.append(Label(n, (f, lo), ((0, 3), (0, 14)),
                            {"color": "C1", "fontsize": 7, "ha": "center", "va": "bottom",
                             "rotation": 90}))
    if mc.features is not None:
        for f in np.atleast_1d(mc.features.frequencies):
            if f <= fmax and not any(abs(f - g) <= 0.05 * g for g, _ in named):
                ax.axvline(f, color="0.85", lw=0.8, ls="-.")
                labels.append(Label(f"{f:.0f} Hz (map line)", (float(f), lo), ((0, 3), (0, 14)),
                                    {"color": "0.85", "fontsize": 7, "ha": "center",
                                     "va": "bottom", "rotation": 90}))
    r = mc.resonances
    if r is not None and len(r):
        mech = np.asarray([str(x) for x in r.mechanism])
        for which, mk, col, lab in (("forced resonance", "o", "r", "forced resonance"),
                                    ("parametric instability", "s", "#ff66ff",
                                     "parametric (theory candidate)"),
                                    ("unexplained", "x", "0.8", "unexplained rise")):
            sel = mech == which
            if sel.any():
                ax.plot(r.frequency[sel], r.rpm[sel], mk, mfc="none", mec=col, color=col,
                        ms=7 if mk != "x" else 4, label=lab)
    ax.legend(loc="lower right", fontsize=7)
    fig.suptitle(f"{mc.name}: rpm-frequency map of {mc.channel}", fontsize=10)
    place_labels(fig, ax, labels)
    return fig


def order_map_figure(mc: MeasuredCase, figsize: tuple[float, float] = (7.5, 6.0)
                     ) -> Figure | None:
    """Rpm-order map with the mesh orders and the natural-frequency curves o = 60 f / n."""
    if mc.omap is None:
        return None
    orders = [60 * f * k for _, f, kk in mc.mesh_groups for k in range(1, kk + 1)]
    fig = rpm_order_map_figure(mc.omap, orders=[o for o in orders if o <= mc.omap.max_order],
                               dynamic_range_db=_DYNAMIC_RANGE_DB, figsize=figsize)
    ax = fig.axes[0]
    lo, hi = ax.get_ylim()
    speeds = np.linspace(max(lo, 1.0), hi, 200)
    for f in mc.natural_frequencies_hz:
        ax.plot(60 * f / speeds, speeds, color="C1", lw=0.8, ls=":")
    ax.set_xlim(0, mc.omap.max_order)
    ax.set_xlabel("order of the reference shaft" + (" (dashed: mesh orders, dotted: natural "
                                                     "frequencies)" if mc.mesh_groups else ""))
    fig.suptitle(f"{mc.name}: rpm-order map of {mc.channel}", fontsize=10)
    return fig

