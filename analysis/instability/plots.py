"""Plotting functions for the instability results (matplotlib Figure API, no pyplot).

Every function accepts an optional Axes ``ax``; without it a new
:class:`matplotlib.figure.Figure` is created. The Figure is returned.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from analysis.checks import require_instance

__all__ = [
    "plot_candidates",
    "plot_chart",
    "plot_floquet",
    "plot_peak_labels",
    "plot_resonances",
]


def _axes(ax: Any):
    if ax is not None:
        if not hasattr(ax, "figure") or not hasattr(ax, "plot"):
            raise TypeError(f"ax must be matplotlib Axes; got {type(ax).__name__}")
        return ax.figure, ax
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 4.5), layout="constrained")
    return fig, fig.add_subplot()


def plot_floquet(result: Any, ax: Any = None):
    """Floquet multipliers in the complex plane with the unit circle."""
    from analysis.instability.floquet import FloquetResult

    require_instance(result, FloquetResult, "result")
    fig, ax = _axes(ax)
    th = np.linspace(0, 2 * np.pi, 361)
    ax.plot(np.cos(th), np.sin(th), color="0.6", lw=1, label="|mu| = 1")
    mu = result.multipliers
    ax.plot(mu.real, mu.imag, "o", color="C3" if not result.stable else "C0",
            label=f"multipliers (max |mu| = {result.max_modulus:.6g})")
    ax.set_aspect("equal")
    ax.set_xlabel("Re mu")
    ax.set_ylabel("Im mu")
    ax.set_title("Floquet multipliers: " + ("stable" if result.stable else "unstable"))
    ax.legend(loc="upper right", fontsize="small")
    return fig


def plot_candidates(candidates: Any, ax: Any = None):
    """Candidate region centres: mesh frequency (or speed) over order ``n``."""
    from analysis.instability.theory import Candidates

    require_instance(candidates, Candidates, "candidates")
    fig, ax = _axes(ax)
    use_rpm = candidates.mesh_frequency_per_rpm is not None
    x = candidates.rpm if use_rpm else candidates.f_mesh_hz
    for kind, marker in (("principal", "o"), ("sum", "s"), ("difference", "^")):
        for allowed, fill in ((True, None), (False, "none")):
            m = (candidates.kind == kind) & (candidates.allowed == allowed)
            if m.any():
                ax.plot(x[m], candidates.n[m], marker, mfc=fill, linestyle="none",
                        label=f"{kind}{'' if allowed else ' (suppressed)'}")
    for xi, ni, lab in zip(x, candidates.n, candidates.label, strict=True):
        ax.annotate(str(lab), (xi, ni), fontsize="x-small", rotation=60,
                    xytext=(2, 4), textcoords="offset points")
    ax.set_xlabel("input speed [min-1]" if use_rpm else "mesh frequency [Hz]")
    ax.set_ylabel("order n")
    ax.set_title("Parametric-instability candidates")
    if len(candidates):
        ax.legend(loc="upper left", fontsize="small")
    return fig


def plot_chart(chart: Any, ax: Any = None):
    """Growth rate over mesh frequency, or an Ince-Strutt chart for two parameters."""
    from analysis.instability.chart import StabilityChart

    require_instance(chart, StabilityChart, "chart")
    fig, ax = _axes(ax)
    f = chart.mesh_frequencies_hz
    if chart.parameter_values is None:
        ax.plot(f, chart.growth_rate, color="C0", label="growth rate ln(max|mu|)/T")
        for r in chart.region_table:
            ax.axvspan(r["lower"], r["upper"], color="C3", alpha=0.2)
            if r["candidate"]:
                ax.annotate(r["candidate"], (0.5 * (r["lower"] + r["upper"]),
                                             r["peak_growth_rate"]), fontsize="small")
        ax.set_ylabel("growth rate [1/s]")
        ax.legend(loc="upper left", fontsize="small")
    else:
        z = np.log10(np.maximum(chart.max_modulus, 1.0))
        mesh = ax.pcolormesh(f, chart.parameter_values, z, shading="nearest", cmap="magma_r")
        ax.contour(f, chart.parameter_values, chart.max_modulus, levels=[1.0 + chart.tol],
                   colors="k", linewidths=0.8)
        fig.colorbar(mesh, ax=ax, label="log10 max|mu|")
        ax.set_ylabel(f"{chart.parameter_name} [{chart.parameter_units}]")
    ax.set_xlabel("mesh frequency [Hz]")
    ax.set_title("Floquet stability chart")
    return fig


def plot_peak_labels(labels: Any, frequency_hz: Any = None, amplitude: Any = None,
                     ax: Any = None):
    """Peaks marked and annotated with their theory labels, optionally over a spectrum."""
    from analysis.identification import PeakIdentification

    require_instance(labels, PeakIdentification, "labels")
    fig, ax = _axes(ax)
    top = 1.0
    if frequency_hz is not None and amplitude is not None:
        ax.plot(frequency_hz, amplitude, color="C0", lw=0.8)
        top = float(np.max(amplitude))
        ax.set_ylabel("amplitude")
    for i, p in enumerate(labels.peak_frequencies_hz):
        ax.axvline(p, color="C3", lw=0.6, alpha=0.6)
        text = labels.label(i).split(" ≈ ", 1)[-1] if labels.matches[i] else "?"
        ax.annotate(text, (p, top), rotation=90, fontsize="x-small", va="top")
    ax.set_xlabel("frequency [Hz]")
    ax.set_title("Peak labels")
    return fig


def plot_resonances(resonances: Any, map_ds: Any = None, ax: Any = None, *,
                    orders: Any = range(1, 8), natural_frequencies_hz: Any = ()):
    """Rises over the rpm-frequency map, marked by mechanism (the paper's Figure 11 layout).

    Speed is vertical, frequency horizontal; the mesh-order rays are dashed, the natural
    frequencies dotted. Forced resonances are circles, parametric instabilities squares,
    unexplained rises grey crosses.
    """
    import xarray

    from analysis.instability.resonances import Resonances

    require_instance(resonances, Resonances, "resonances")
    if map_ds is not None:
        require_instance(map_ds, xarray.Dataset, "map_ds")
    fig, ax = _axes(ax)
    h = resonances.mesh_frequency_per_rpm
    if map_ds is not None:
        amp = map_ds["amplitude"].transpose("time", "frequency").values
        if str(map_ds.attrs.get("scale", "linear")) == "dB":
            db = amp
        else:
            db = 20 * np.log10(np.maximum(amp, 1e-12 * max(float(amp.max()), 1e-300)))
        top = float(db.max())
        mesh = ax.pcolormesh(map_ds["frequency"].values, map_ds["rpm"].values, db,
                             shading="nearest", cmap="viridis", vmin=top - 60.0, vmax=top)
        fig.colorbar(mesh, ax=ax, label="level [dB]")
        rpm = np.asarray(map_ds["rpm"].values)
        fmax = float(map_ds["frequency"].values.max())
        for o in orders:
            ax.plot(o * h * rpm, rpm, color="w", lw=0.6, ls="--", alpha=0.6)
        ax.set_xlim(0, fmax)
        ax.set_ylim(float(rpm.min()), float(rpm.max()))
    for fn in np.atleast_1d(np.asarray(natural_frequencies_hz, dtype=float)):
        ax.axvline(fn, color="C1", lw=0.7, ls=":")
    styles = {"forced": ("o", "C1"), "parametric": ("s", "C3"), "unexplained": ("x", "0.85")}
    for key, (marker, color) in styles.items():
        m = np.asarray([str(x).startswith(key) for x in resonances.mechanism], dtype=bool)
        if m.any():
            ax.plot(resonances.frequency[m], resonances.rpm[m], marker, color=color,
                    mfc="none", ms=9, mew=1.4, linestyle="none",
                    label=f"{key} ({int(m.sum())})")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("speed [min-1]")
    ax.set_title("Detected rises by mechanism")
    if len(resonances):
        ax.legend(loc="lower right", fontsize="small")
    return fig
