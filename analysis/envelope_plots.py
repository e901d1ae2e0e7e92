"""Figure builders for envelope analysis and spectral kurtosis.

Plotting only, like :mod:`analysis.plots`: each function takes a result of
:mod:`analysis.envelope`, :mod:`analysis.envelope_orders` or :mod:`analysis.kurtogram` and
returns a :class:`matplotlib.figure.Figure` built without pyplot (a new one, or the figure
of ``ax=``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from analysis.checks import require_colormap, require_instance
from analysis.levels import to_db
from analysis.lines import LineFamily

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from analysis.envelope import EnvelopeSpectrum, SquaredEnvelope
    from analysis.envelope_orders import EnvelopeOrderSpectrum
    from analysis.kurtogram import Kurtogram, SpectralKurtosis
    from analysis.line_evidence import LineEvidence

__all__ = [
    "envelope_spectrum_figure",
    "kurtogram_figure",
    "line_evidence_figure",
    "spectral_kurtosis_figure",
    "squared_envelope_figure",
]

_FAMILY_COLOURS = ("C3", "C2", "C1", "C4", "C5", "C6", "C8", "C9")


def _axes(ax: Any, figsize: tuple[float, float]) -> tuple[Figure, Any]:
    if ax is None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=figsize, layout="constrained")
        return fig, fig.add_subplot()
    if not hasattr(ax, "figure") or not hasattr(ax, "plot"):
        raise ValueError(f"ax must be matplotlib Axes; got {type(ax).__name__}")
    return ax.figure, ax


def _families(families: Any) -> list[LineFamily]:
    if families is None:
        return []
    fams = [families] if isinstance(families, LineFamily) else list(families)
    for f in fams:
        if not isinstance(f, LineFamily):
            raise ValueError(f"families: {f!r} is not a LineFamily (see analysis.lines)")
    return fams


def _value_label(amplitude: str, units: str, db: bool) -> str:
    name = {"peak": "peak amplitude", "rms": "rms amplitude", "power": "power",
            "density": "PSD"}.get(amplitude, amplitude)  # fmt: skip
    return f"{name} [dB re 1 {units}]" if db else f"{name} [{units}]"


def envelope_spectrum_figure(
    result: EnvelopeSpectrum | EnvelopeOrderSpectrum,
    *,
    families: LineFamily | Sequence[LineFamily] | None = None,
    db: bool = False,
    axis_max: float | None = None,
    ax: Any = None,
    figsize: tuple[float, float] = (9.0, 4.2),
) -> Figure:
    """Squared envelope (order) spectrum with line families marked.

    Parameters
    ----------
    result : EnvelopeSpectrum or EnvelopeOrderSpectrum
        The spectrum.
    families : LineFamily or sequence of LineFamily, optional
        Lines to mark on the spectrum's axis (Hz, or orders for an order spectrum), e.g.
        :func:`analysis.lines.bearing_families`: harmonics as dashed lines labelled
        ``h x NAME``, sidebands dotted, one colour per family.
    db : bool, default False
        Level in dB instead of linear (envelope spectra are usually read linear).
    axis_max : float, optional
        Upper end of the axis; default 1.15 times the highest marked line, else the band's
        width for a frequency spectrum (the squared envelope holds nothing above it) and the
        whole order axis for an order spectrum; at most the spectrum's end.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into.
    figsize : (float, float)
        Size of a new figure [in].
    """
    require_instance(result, ("analysis.envelope.EnvelopeSpectrum",
                              "analysis.envelope_orders.EnvelopeOrderSpectrum"), "result")
    fams = _families(families)
    fig, ax = _axes(ax, figsize)
    # told apart by their axis: both result modules import this one (no import back)
    if hasattr(result, "order"):
        by_order = cast("EnvelopeOrderSpectrum", result)
        is_order, axis = True, by_order.order
        res = f"RBW {by_order.resolution_orders:.3g} orders"
        what = "squared envelope order spectrum"
    else:
        is_order, axis = False, result.frequency
        res = f"RBW {result.resolution_hz:.3g} Hz, {result.n_averages} avg."
        what = "squared envelope spectrum"
    top_line = max((float(f.lines()[2].max()) for f in fams), default=0.0)
    if axis_max is None:
        if top_line > 0:
            axis_max = 1.15 * top_line
        else:  # the squared envelope holds nothing above the band's width (in Hz)
            axis_max = float(axis[-1]) if is_order else result.band.width
    axis_max = min(float(axis_max), float(axis[-1]))
    keep = axis <= axis_max
    y = to_db(result.values, result.amplitude) if db else result.values
    ax.plot(axis[keep], y[keep], lw=0.8, color="C0")
    ymax = float(np.max(y[keep][1:])) if np.count_nonzero(keep) > 1 else 1.0
    for j, fam in enumerate(fams):
        colour = _FAMILY_COLOURS[j % len(_FAMILY_COLOURS)]
        h, s, p = fam.lines()
        first = True
        for hh, ss, pp in zip(h, s, p, strict=True):
            if pp > axis_max:
                continue
            ax.axvline(pp, color=colour, lw=1.0 if ss == 0 else 0.7,
                       ls="--" if ss == 0 else ":", alpha=0.8 if ss == 0 else 0.6,
                       label=fam.name if first else None)  # fmt: skip
            first = False
            if ss == 0:
                ax.annotate(f"{hh}×{fam.name}", (pp, 1.0), xycoords=("data", "axes fraction"),
                            xytext=(2, -2), textcoords="offset points", rotation=90,
                            va="top", ha="left", fontsize=7, color=colour)  # fmt: skip
    if fams:
        ax.legend(fontsize=8, loc="upper right")
    ax.set_xlim(0.0, axis_max)
    if not db:
        ax.set_ylim(0.0, 1.12 * ymax if ymax > 0 else 1.0)
    ax.set_xlabel("order [-]" if is_order else "frequency [Hz]")
    ax.set_ylabel(_value_label(result.amplitude, result.units, db))
    b = result.band
    src = "kurtogram" if result.kurtogram is not None else "given"
    ax.set_title(f"{result.name}: {what}, band {b.low:.5g}-{b.high:.5g} Hz ({src}), {res}",
                 fontsize=10)  # fmt: skip
    ax.grid(True, alpha=0.3)
    return fig


def kurtogram_figure(
    kurtogram: Kurtogram,
    *,
    ax: Any = None,
    cmap: str = "viridis",
    figsize: tuple[float, float] = (9.0, 4.5),
) -> Figure:
    """The usual kurtogram image: kurtosis per band (colour), frequency across, level down;
    the band of largest kurtosis framed.

    Parameters
    ----------
    kurtogram : Kurtogram
        Result of :func:`analysis.kurtogram.fast_kurtogram`.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into.
    cmap : str
        Colour map.
    figsize : (float, float)
        Size of a new figure [in].
    """
    require_instance(kurtogram, "analysis.kurtogram.Kurtogram", "kurtogram")
    from matplotlib.patches import Rectangle

    fig, ax = _axes(ax, figsize)
    freq, image = kurtogram.grid()
    rows = kurtogram.levels.size
    nyq = 0.5 * kurtogram.fs
    edges_f = np.linspace(0.0, nyq, freq.size + 1)
    edges_r = np.arange(rows + 1) - 0.5
    mesh = ax.pcolormesh(edges_f, edges_r, image, cmap=require_colormap(cmap), shading="flat",
                         rasterized=True)
    fig.colorbar(mesh, ax=ax, label="spectral kurtosis K [-]")
    ax.set_ylim(rows - 0.5, -0.5)
    ax.set_yticks(np.arange(rows))
    ax.set_yticklabels([f"{lv:.1f}".rstrip("0").rstrip(".") for lv in kurtogram.levels],
                       fontsize=8)  # fmt: skip
    ax.set_ylabel("level k (band width = fs / 2^(k+1))")
    ax.set_xlabel("frequency [Hz]")
    row, _ = kurtogram.best
    b = kurtogram.band
    ax.add_patch(Rectangle((b.low, row - 0.5), b.width, 1.0, fill=False, ec="w", lw=1.5))
    ax.set_title(
        f"{kurtogram.name}: fast kurtogram, K max = {kurtogram.kurtosis_max:.3g} at level "
        f"{kurtogram.level:.1f}, band {b.low:.5g}-{b.high:.5g} Hz (centre {b.centre:.5g} Hz, "
        f"width {b.width:.4g} Hz)",
        fontsize=9,
    )
    return fig


def spectral_kurtosis_figure(
    sk: SpectralKurtosis,
    *,
    probability: float = 0.01,
    ax: Any = None,
    figsize: tuple[float, float] = (8.0, 3.8),
) -> Figure:
    """Spectral kurtosis against frequency with the Gaussian-noise threshold.

    Parameters
    ----------
    sk : SpectralKurtosis
        Result of :func:`analysis.kurtogram.spectral_kurtosis`.
    probability : float, default 0.01
        False-alarm probability per bin of the threshold drawn.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into.
    figsize : (float, float)
        Size of a new figure [in].
    """
    require_instance(sk, "analysis.kurtogram.SpectralKurtosis", "sk")
    fig, ax = _axes(ax, figsize)
    ax.plot(sk.frequency, sk.kurtosis, lw=0.9, color="C0", label="K(f)")
    thr = sk.threshold(probability)
    ax.axhline(thr, color="C3", ls="--", lw=0.9,
               label=f"Gaussian noise, p = {probability:g}: {thr:.3g}")  # fmt: skip
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlim(0.0, float(sk.frequency[-1]))
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("spectral kurtosis K [-]")
    ax.set_title(f"{sk.name}: spectral kurtosis, {sk.window} {sk.segment_length} samples "
                 f"(RBW {sk.resolution_hz:.3g} Hz), {sk.n_frames} frames", fontsize=10)  # fmt: skip
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    return fig


def squared_envelope_figure(
    env: SquaredEnvelope,
    *,
    duration: float | None = None,
    ax: Any = None,
    figsize: tuple[float, float] = (8.0, 3.5),
) -> Figure:
    """The squared envelope against time.

    Parameters
    ----------
    env : SquaredEnvelope
        Result of :func:`analysis.envelope.squared_envelope`.
    duration : float, optional
        Seconds shown from the start (default all).
    ax : matplotlib.axes.Axes, optional
        Axes to draw into.
    figsize : (float, float)
        Size of a new figure [in].
    """
    require_instance(env, "analysis.envelope.SquaredEnvelope", "env")
    fig, ax = _axes(ax, figsize)
    t = env.time
    keep = slice(None) if duration is None else t <= t[0] + float(duration)
    ax.plot(t[keep], env.values[keep], lw=0.7)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(f"squared envelope [{env.units}]")
    ax.set_title(f"{env.name}: squared envelope of {env.band.low:.5g}-{env.band.high:.5g} Hz",
                 fontsize=10)  # fmt: skip
    ax.grid(True, alpha=0.3)
    return fig


def line_evidence_figure(
    evidence: LineEvidence,
    *,
    axis_max: float | None = None,
    ax: Any = None,
    title: str | None = None,
    figsize: tuple[float, float] = (9.0, 4.2),
) -> Figure:
    """A spectrum with the families checked in it: where each line was expected, which were
    found, and each family's status.

    Parameters
    ----------
    evidence : LineEvidence
        Result of :func:`analysis.line_evidence.line_evidence`.
    axis_max : float, optional
        Upper end of the axis; default 1.1 times the highest harmonic of the families that
        lie inside the spectrum (else the spectrum's end).
    ax : matplotlib.axes.Axes, optional
        Axes to draw into.
    title : str, optional
        Axes title (default: the spectrum's name).
    figsize : (float, float)
        Size of a new figure [in].

    Notes
    -----
    Level: ``10 log10(P / median P)`` over the axis shown [dB over the median]. Harmonics
    dashed in the family's colour (the fundamental labelled with the family's name), lines
    found (>= the threshold over their local floor) marked with a triangle at their level,
    sidebands found with a dot; the legend (below the axes) gives every family's status,
    harmonics found and, for a family whose lines were found, its chance of a coincidence.
    """
    require_instance(evidence, "analysis.line_evidence.LineEvidence", "evidence")
    fig, ax = _axes(ax, figsize)
    x = evidence.axis
    status = evidence.status
    tops = [float(c.expected[c.sideband == 0].max()) for c, st in
            zip(evidence.checks, status, strict=True) if st != "outside"]
    if axis_max is None:
        axis_max = 1.1 * max(tops) if tops else float(x[-1])
    axis_max = min(float(axis_max), float(x[-1]))
    keep = x <= axis_max
    ref = float(np.median(evidence.power[keep][1:])) if np.count_nonzero(keep) > 2 else 1.0
    with np.errstate(divide="ignore"):
        level = 10.0 * np.log10(np.maximum(evidence.power, 1e-300) / max(ref, 1e-300))
    ax.plot(x[keep], level[keep], lw=0.7, color="0.35")
    top = float(np.max(level[keep][1:])) if np.count_nonzero(keep) > 2 else 1.0
    bottom = float(np.percentile(level[keep], 1)) if np.count_nonzero(keep) > 2 else -1.0
    span = max(top - bottom, 10.0)
    ax.set_ylim(bottom - 0.05 * span, top + (0.12 + 0.07 * max(1, len(evidence))) * span)
    rows = evidence.rows()
    for j, c in enumerate(evidence.checks):
        colour = _FAMILY_COLOURS[j % len(_FAMILY_COLOURS)]
        harm = c.sideband == 0
        _, _, st, found, _, _, _ = rows[j]
        ch = float(evidence.chance[j])
        shown = (np.isfinite(ch) and status[j] in ("detected", "possible", "explained"))
        chance = ("" if not shown else ", chance < 1e-4" if ch < 1e-4 else
                  f", chance {ch:.2g}")
        ax.plot([], [], color=colour, ls="--", label=f"{c.family.name}: {st} "
                f"({found} harmonics{chance})")
        for h, p in zip(c.harmonic[harm], c.expected[harm], strict=True):
            if p <= axis_max:
                ax.axvline(p, color=colour, lw=0.8, ls="--", alpha=0.55)
                if h == 1:
                    ax.annotate(c.family.name, (p, 1.0), xycoords=("data", "axes fraction"),
                                xytext=(2, -3 - 10 * j), textcoords="offset points",
                                ha="left", va="top", fontsize=7, color=colour)
        hit = c.found & np.isfinite(c.position) & (c.position <= axis_max)
        k = np.clip(np.searchsorted(x, c.position[hit]), 0, x.size - 1)
        main = harm[hit]
        ax.plot(c.position[hit][main], level[k][main], "v", color=colour, ms=6,
                mec="k", mew=0.4)
        ax.plot(c.position[hit][~main], level[k][~main], "o", color=colour, ms=3.5,
                mec="k", mew=0.3)
    ax.set_xlim(0.0, axis_max)
    ax.set_xlabel("order [-]" if evidence.axis_units == "1" else "frequency [Hz]")
    ax.set_ylabel("level [dB over the median]")
    ax.set_title(title or evidence.name, fontsize=10)
    ax.grid(True, alpha=0.3)
    if evidence.checks:  # below the axes: the spectrum and the families' names stay clear
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.16), frameon=False,
                  ncol=1)
    return fig
