"""Figures of the report: matplotlib Figure builders that draw a :class:`CaseAnalysis`.

They compute nothing of their own (every quantity comes from
:mod:`gearvib.report.case`) and use the Figure API, never pyplot. Figures that the paper
compares side by side (tooth forces, spectra, sonograms of case 1 and case 2) take a common
scale from :mod:`gearvib.report.sections` (``ylim=``, ``level_max=``).

Text in the plots is placed by :func:`place_labels`: every label is tried at a few positions
and dropped when it would overlap one already placed (the tables carry the rest), so mesh
orders, natural frequencies, peaks and candidates never pile up.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.instability import FORCED, PARAMETRIC, UNEXPLAINED
from analysis.maps import RpmFrequencyMap
from analysis.plots import rpm_frequency_map_figure, rpm_order_map_figure
from analysis.spectrum import to_db
from gearvib.report.case_analysis import MARKER_BUDGET, CaseAnalysis
from gearvib.report.case_run import signed_force
from gearvib.report.wording import count

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "IDENTICAL_RTOL",
    "Label",
    "identical_groups",
    "map_level_max",
    "mesh_stiffness_figure",
    "natural_frequency_lines",
    "order_map_figure",
    "place_labels",
    "sonogram_figure",
    "spectra_figure",
    "stability_figure",
    "tooth_force_figure",
]

IDENTICAL_RTOL = 1e-3
"""Tooth forces that differ by less than this fraction of their range are drawn as one line."""

DYNAMIC_RANGE_DB = 50.0
"""Colour range of the maps below their (common) maximum [dB]."""

_GROUP_STYLES = (("w", "--"), ("#00e5ff", "-"), ("#ff66ff", "-."), ("#ffd400", ":"))
_PEAK_LABELS = 6  # labelled peaks per spectrum panel (the strongest; the table has all)


def _figure(figsize: tuple[float, float]) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=figsize, layout="constrained", dpi=100)


# --------------------------------------------------------------------------- label placement


@dataclass(frozen=True)
class Label:
    """A text to place at a data point, with the offsets [points] to try in order.

    Attributes
    ----------
    text : str
        The label.
    xy : (float, float)
        Anchor in data coordinates.
    offsets : tuple of (float, float)
        Offsets from the anchor [points] tried in turn.
    style : dict
        Keyword arguments of ``ax.annotate`` (colour, size, alignment, rotation, bbox).
    """

    text: str
    xy: tuple[float, float]
    offsets: tuple[tuple[float, float], ...] = ((0.0, 0.0),)
    style: dict | None = None


def place_labels(fig: Figure, ax: Any, labels: Sequence[Any], *, pad: float = 1.5,
                 avoid: Sequence[Any] = ()) -> list[Any]:
    """Annotate ``ax`` with every label that fits without overlapping another.

    The figure is laid out once (nothing rasterised), then each label is tried at its offsets
    in turn and kept at the first one where its box (grown by ``pad`` pixels) overlaps no label
    placed before and no artist in ``avoid`` (e.g. the title, a legend), and stays inside the
    figure; a label that fits nowhere is left out (the tables carry it). The layout is then
    frozen, so the saved figure shows the boxes that were checked. With ``ax=None``, ``labels``
    are ``(axes, Label)`` pairs (labels of several panels placed together).

    Returns
    -------
    list
        The annotations placed.
    """
    items = [(ax, lab) for lab in labels] if ax is not None else list(labels)
    if not hasattr(fig.canvas, "get_renderer"):
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        FigureCanvasAgg(fig)
    fig.draw_without_rendering()  # the one layout: the text extents below need no other
    # an Agg canvas (made above if needed); FigureCanvasBase does not declare the method
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    fig.set_layout_engine("none")
    placed: list[Any] = [a.get_window_extent(renderer) for a in avoid
                         if a is not None and a.get_visible()]
    fig_box = fig.bbox
    out = []
    for axes, lab in items:
        for off in lab.offsets:
            ann = axes.annotate(lab.text, lab.xy, xytext=off, textcoords="offset points",
                                annotation_clip=False, **(lab.style or {}))
            box = ann.get_window_extent(renderer)
            grown = box.padded(pad)
            inside = (box.x0 >= fig_box.x0 and box.x1 <= fig_box.x1 and box.y0 >= fig_box.y0
                      and box.y1 <= fig_box.y1)
            if inside and not any(grown.overlaps(b) for b in placed):
                placed.append(box)
                out.append(ann)
                break
            ann.remove()
    return out


# --------------------------------------------------------------------------- tooth forces


def identical_groups(ds: Any, meshes: Sequence[str], rtol: float = IDENTICAL_RTOL
                     ) -> list[list[str]]:
    """Meshes whose signed tooth forces agree within ``rtol`` of their range, grouped.

    In-phase planets (the paper's case 1) load their sun meshes identically; one line is then
    drawn for the group and its label says so.
    """
    forces = {m: signed_force(ds, m) for m in meshes}
    groups: list[list[str]] = []
    for m in meshes:
        for g in groups:
            ref = forces[g[0]]
            scale = max(float(np.ptp(ref)), 1e-300)
            if float(np.max(np.abs(forces[m] - ref))) <= rtol * scale:
                g.append(m)
                break
        else:
            groups.append([m])
    return groups


def force_limit(ca: CaseAnalysis) -> float:
    """Largest absolute tooth force of the meshes drawn in :func:`tooth_force_figure` [N]."""
    top = 0.0
    for _, meshes in ca.force_meshes or [("", (ca.force_mesh,))]:
        for m in meshes:
            top = max(top, float(np.max(np.abs(signed_force(ca.dataset, m)))))
    return top


def tooth_force_figure(ca: CaseAnalysis, *, ylim: tuple[float, float] | None = None,
                       figsize: tuple[float, float] = (8.0, 4.2)) -> Figure:
    """Normal tooth forces over the run (paper Figure 7), one panel per mesh frequency.

    Each panel shows the meshes of the group's first central gear (the sun meshes of a simple
    set, each stage's sun meshes of a two-stage set); the drive flank counts positive, the back
    flank negative, the input speed is on a second axis. Meshes whose forces coincide (in-phase
    planets) are one line, labelled with all of them. ``ylim`` gives every case the same scale.
    """
    panels = ca.force_meshes or [(ca.groups[0].name, (ca.force_mesh,))]
    h = figsize[1] if len(panels) == 1 else 2.6 * len(panels) + 0.6
    fig = _figure((figsize[0], h))
    axes = fig.subplots(len(panels), 1, squeeze=False, sharex=True)[:, 0]
    t = ca.dataset["time"].values
    stride = max(1, t.size // 20000)
    for ax, (gname, meshes) in zip(axes, panels, strict=True):
        groups = identical_groups(ca.dataset, meshes)
        for i, g in enumerate(groups):
            lab = " = ".join(g) + " (identical: in phase)" if len(g) > 1 else g[0]
            ax.plot(t[::stride], signed_force(ca.dataset, g[0])[::stride], lw=0.5,
                    color=f"C{i}", label=lab)
        ax.set_ylabel("normal tooth force [N]")
        if ylim is not None:
            ax.set_ylim(*ylim)
        ax.grid(True, alpha=0.3)
        ax2 = ax.twinx()
        ax2.plot(t, np.abs(ca.dataset["input_speed"].values), color="k", lw=1.0, ls="--",
                 label="input speed")
        ax2.set_ylabel("input speed [min⁻¹]")
        ax.legend(loc="upper left", fontsize=7)
        if len(panels) > 1:
            ax.set_title(f"{gname}: {', '.join(meshes)}", fontsize=8)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(f"{ca.name}: normal tooth forces (cf. paper Fig. 7)", fontsize=10)
    return fig


# --------------------------------------------------------------------------- spectra


def spectrum_limits(ca: CaseAnalysis) -> tuple[float, float]:
    """Smallest and largest level of the spectra in their band [dB]."""
    lo, hi = np.inf, -np.inf
    for fsp in ca.spectra:
        sp = fsp.spectrum
        band = (sp.frequency <= ca.frequency_max_hz) & (sp.frequency > 0)
        if band.any():
            v = to_db(sp.values[band], sp.amplitude)
            lo, hi = min(lo, float(np.min(v))), max(hi, float(np.max(v)))
    return lo, hi


def spectra_figure(ca: CaseAnalysis, *, ylim: tuple[float, float] | None = None,
                   figsize: tuple[float, float] = (8.0, 6.5)) -> Figure:
    """Spectra of the tooth forces with theory-labelled peaks (paper Figure 8).

    At most six peaks per panel carry a label (the strongest that fit without overlapping:
    their frequency and the best expression, '?' unexplained, '~' ambiguous); every peak is in
    the table with its candidates. ``ylim`` gives every case the same scale.
    """
    n = len(ca.spectra)
    fig = _figure((figsize[0], max(3.2, (2.9 if n <= 2 else 2.4) * n + 0.6)))
    axes = fig.subplots(n, 1, squeeze=False)[:, 0]
    for ax, fsp in zip(axes, ca.spectra, strict=True):
        sp = fsp.spectrum
        band = sp.frequency <= ca.frequency_max_hz
        ax.plot(sp.frequency[band], to_db(sp.values[band], sp.amplitude), lw=0.7)
        for f in ca.natural_frequencies_hz:
            ax.axvline(f, color="C1", lw=0.7, ls=":")
        ax.set_xlim(0, ca.frequency_max_hz)
        if ylim is not None:
            ax.set_ylim(ylim[0], ylim[1] + 0.3 * (ylim[1] - ylim[0]))
        else:
            lo, hi = ax.get_ylim()
            ax.set_ylim(lo, hi + 0.3 * (hi - lo))  # room for the peak labels
        ax.set_ylabel("peak amplitude\n[dB re 1 N]")
        ax.set_title(f"{fsp.mesh}: {sp.window}, Δf = {sp.bin_spacing_hz:.3g} Hz, "
                     f"{sp.n_averages} averages", fontsize=9)
        ax.grid(True, alpha=0.3)
        if len(fsp.peaks):
            y = to_db(fsp.peaks.amplitude, sp.amplitude)
            ax.plot(fsp.peaks.frequency, y, "v", color="C3", ms=4)
    axes[-1].set_xlabel("frequency [Hz]  (dotted: natural frequencies)")
    fig.suptitle(f"{ca.name}: tooth-force spectra over the run (cf. paper Fig. 8)",
                 fontsize=10)
    labels_by_ax = []
    for ax, fsp in zip(axes, ca.spectra, strict=True):
        if not len(fsp.peaks):
            continue
        y = to_db(fsp.peaks.amplitude, fsp.spectrum.amplitude)
        order = np.argsort(y)[::-1][:_PEAK_LABELS]
        for i in order:
            st = fsp.labels.status[i] if i < len(fsp.labels) else "unexplained"
            m = fsp.labels.matches[i] if i < len(fsp.labels) else ()
            text = f"{fsp.peaks.frequency[i]:.0f}" + (
                f"\n≈ {m[0].expression.split(' ≈ ')[0]}" if st == "explained" else
                "\n?" if st == "unexplained" else "\n~")
            labels_by_ax.append((ax, Label(text, (float(fsp.peaks.frequency[i]), float(y[i])),
                                           ((0, 4), (14, 4), (-14, 4), (0, 16)),
                                           {"ha": "center", "va": "bottom",
                                            "fontsize": 6.5})))
    place_labels(fig, None, labels_by_ax)
    return fig


# --------------------------------------------------------------------------- stiffness


def mesh_stiffness_figure(cases: Sequence[CaseAnalysis], *,
                          figsize: tuple[float, float] = (8.0, 4.2)) -> Figure:
    """Summed mesh stiffness of every central gear over three mesh cycles (paper Figs. 9, 10).

    One panel per central gear (the sun and the ring of a simple set; per stage for two
    stages), one line per case; with one case also the individual meshes (dashed).
    """
    keys: list[tuple[str, str]] = []
    for ca in cases:
        for sk in ca.stiffness:
            if (sk.group, sk.central) not in keys:
                keys.append((sk.group, sk.central))
    n = max(1, len(keys))
    fig = _figure((figsize[0], figsize[1] if n == 1 else 2.5 * n + 0.6))
    axes = fig.subplots(n, 1, squeeze=False)[:, 0]
    for ax, key in zip(axes, keys, strict=False):
        for i, ca in enumerate(cases):
            st = next((s for s in ca.stiffness if (s.group, s.central) == key), None)
            if st is None:
                continue
            ax.plot(st.cycles, st.total / 1e8, color=f"C{i}", lw=1.4,
                    label=f"{ca.name}: {st.minimum / 1e8:.3g}–{st.maximum / 1e8:.3g}e8 N/m "
                          f"(p-p {st.peak_to_peak / 1e8:.3g}e8, {st.source})")
            if len(cases) == 1 and len(st.mesh_names) <= 6:
                for j, m in enumerate(st.mesh_names):
                    ax.plot(st.cycles, st.per_mesh[j] / 1e8, lw=0.7, ls="--", label=m)
        group = "" if key[0] == "mesh" else f" ({key[0]})"
        ax.set_ylabel(f"{key[1]} meshes\n[1e8 N/m]")
        ax.set_title(f"Summed stiffness of the {key[1]} meshes{group}", fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="lower right")
    if not keys:
        axes[0].text(0.5, 0.5, "no mesh stiffness available", transform=axes[0].transAxes,
                     ha="center")
    axes[-1].set_xlabel("mesh position [mesh cycles]")
    fig.suptitle("Summed mesh stiffness of every central gear (cf. paper Figs. 9 and 10)",
                 fontsize=10)
    return fig


# --------------------------------------------------------------------------- maps


def map_level_max(ca: CaseAnalysis, order: bool = False) -> float:
    """Largest level of the sonogram (or the rpm-order map) [dB re 1 N]."""
    m = ca.omap if order else ca.fmap
    if m is None:
        return -np.inf
    values = np.asarray(m.values, dtype=float)
    if isinstance(m, RpmFrequencyMap):  # not order
        keep = m.frequency <= ca.frequency_max_hz
        values = values[..., keep]
    lv = values if m.scale == "dB" else to_db(values, "power" if m.amplitude == "power"
                                              else "rms")
    return float(np.nanmax(lv))


def _set_levels(fig: Figure, top: float | None) -> None:
    if top is None or not np.isfinite(top):
        return
    ax = fig.axes[0]
    for c in ax.collections:
        if hasattr(c, "set_clim"):
            c.set_clim(top - DYNAMIC_RANGE_DB, top)


def _marker_selection(ca: CaseAnalysis) -> tuple[np.ndarray, int]:
    """Rises marked on the sonogram: the strongest explained ones, at most MARKER_BUDGET."""
    r = ca.resonances
    explained = np.flatnonzero(np.asarray([str(m) in (FORCED, PARAMETRIC)
                                           for m in r.mechanism], dtype=bool))
    order = explained[np.argsort(r.strength_db[explained], kind="stable")[::-1]]
    keep = np.sort(order[:MARKER_BUDGET])
    return keep, len(r) - keep.size


def natural_frequency_lines(ax: Any, frequencies: Any, names: Any, fmax: float
                            ) -> list[tuple[float, str]]:
    """Draw the natural frequencies up to ``fmax`` as dotted vertical lines on a map.

    Returns
    -------
    list of (float, str)
        The frequencies drawn and their names, increasing; a repeated frequency (within 1e-6)
        is one line named ``f3=f4``.
    """
    named: list[tuple[float, str]] = []
    for f, n in sorted(zip(frequencies, names, strict=True)):
        if f > fmax:
            continue
        ax.axvline(f, color="C1", lw=0.9, ls=":")
        if named and abs(f - named[-1][0]) <= 1e-6 * f:
            named[-1] = (named[-1][0], f"{named[-1][1]}={n}")
        else:
            named.append((float(f), n))
    return named


def sonogram_figure(ca: CaseAnalysis, *, level_max: float | None = None,
                    figsize: tuple[float, float] = (7.5, 6.2)) -> Figure:
    """Rpm-frequency map of a tooth force with mesh orders and natural frequencies (Fig. 11).

    Speed is vertical. Inclined lines are the mesh orders ``1..k`` of every mesh frequency
    (one colour and dash style each), labelled ``"k×"`` where they leave the plot; dotted
    vertical lines are the natural frequencies, labelled at the bottom (``f3=f4`` for a
    repeated pair); red bands the Floquet-unstable speeds. Only explained rises are marked
    (circles: forced resonances, squares: parametric instabilities; at most
    :data:`~gearvib.report.case_analysis.MARKER_BUDGET`, the strongest); the tables list every rise.
    ``level_max`` gives every case the same colour scale.
    """
    several = ca.several_mesh_frequencies
    fig = rpm_frequency_map_figure(ca.fmap, hz_per_rpm=(), orders=(), dynamic_range_db=
                                   DYNAMIC_RANGE_DB, frequency_max=ca.frequency_max_hz,
                                   figsize=figsize)
    _set_levels(fig, level_max)
    ax = fig.axes[0]
    lo, hi = ax.get_ylim()
    fmax = ax.get_xlim()[1]
    labels: list[Label] = []
    for j, g in enumerate(ca.groups):
        colour, dash = _GROUP_STYLES[j % len(_GROUP_STYLES)]
        for k in range(1, g.orders + 1):
            rpm = np.array([lo, hi])
            freq = k * g.frequency_per_rpm * rpm
            if freq[0] >= fmax:
                continue
            ax.plot(freq, rpm, color=colour, lw=0.9 if k > 1 else 1.2, ls=dash, alpha=0.9,
                    label=(f"mesh orders, {g.name}" if several else "mesh orders")
                    if k == 1 else None)
            tag = f"{k}×" if not several else f"{k}× {g.short}"
            style = {"color": colour, "fontsize": 7, "ha": "center", "va": "bottom",
                     "bbox": {"boxstyle": "round,pad=0.1", "fc": "0.15", "ec": "none",
                              "alpha": 0.6}}
            if freq[1] <= fmax:  # leaves through the top: label just inside the top edge
                labels.append(Label(tag, (float(freq[1]), hi), ((-2, -3), (-2, -14),
                                                                 (-2, -25)),
                                    {**style, "ha": "right", "va": "top"}))
            else:  # through the right edge
                labels.append(Label(tag, (fmax, float(fmax / (k * g.frequency_per_rpm))),
                                    ((3, -4), (3, 5)), {**style, "ha": "left",
                                                        "va": "center"}))
    # natural frequencies: one dotted line each, names at the bottom (clusters together)
    names = natural_frequency_lines(ax, ca.natural_frequencies_hz, ca.mode_names, fmax)
    for f, n in names:
        labels.append(Label(n, (f, lo), ((0, 3), (0, 15), (0, 27), (0, 39)),
                            {"color": "#ffb000", "fontsize": 7.5, "ha": "center",
                             "va": "bottom", "bbox": {"boxstyle": "round,pad=0.15",
                                                      "fc": "0.1", "ec": "none",
                                                      "alpha": 0.7}}))
    # explained rises only, at most MARKER_BUDGET
    keep, rest = _marker_selection(ca)
    r = ca.resonances
    for key, (marker, colour, text) in {FORCED: ("o", "r", "forced resonance"),
                                        PARAMETRIC: ("s", "m", "parametric instability")
                                        }.items():
        m = np.asarray([str(r.mechanism[i]) == key for i in keep], dtype=bool)
        if m.any():
            idx = keep[m]
            ax.plot(r.frequency[idx], r.rpm[idx], marker, mfc="none", mec=colour, mew=1.4,
                    ms=9, lw=0, label=f"{text} ({int(m.sum())})")
    if rest:
        n_un = int(np.sum(r.mechanism == UNEXPLAINED))
        ax.plot([], [], " ", label=f"{count(rest, 'more rise')} in the tables"
                + (f" ({n_un} unexplained)" if n_un else ""))
    for i, reg in enumerate(ca.floquet_regions()):
        ax.axhspan(reg["lower_rpm"], reg["upper_rpm"], color="r", alpha=0.18, lw=0,
                   label="Floquet unstable" if i == 0 else None)
    handles, texts = ax.get_legend_handles_labels()
    fig.legend(handles, texts, loc="outside lower center", ncol=3, fontsize=7,
               facecolor="0.35", labelcolor="w", framealpha=1.0)
    ax.set_title(f"{ca.name}: sonogram of the tooth force {ca.force_mesh} (cf. paper Fig. 11)"
                 f"\n{ca.fmap.window}, RBW {ca.fmap.resolution_hz:.3g} Hz", fontsize=9)
    place_labels(fig, ax, labels, avoid=[ax.title])
    return fig


def order_map_figure(ca: CaseAnalysis, *, level_max: float | None = None,
                     figsize: tuple[float, float] = (7.5, 5.0)) -> Figure | None:
    """Rpm-order map of the same tooth force with the mesh orders of every mesh frequency.

    The order axis reaches the highest mesh order the report discusses (within the Nyquist
    order at the top speed); each mesh order is a vertical line labelled ``"k×"``.
    """
    if ca.omap is None:
        return None
    several = ca.several_mesh_frequencies
    fig = rpm_order_map_figure(ca.omap, orders=(), dynamic_range_db=DYNAMIC_RANGE_DB,
                               figsize=figsize)
    _set_levels(fig, level_max)
    ax = fig.axes[0]
    top = ca.omap.max_order
    ax.set_xlim(0, top)
    hi = ax.get_ylim()[1]
    labels = []
    for j, g in enumerate(ca.groups):
        colour, dash = _GROUP_STYLES[j % len(_GROUP_STYLES)]
        for k in range(1, g.orders + 1):
            o = k * g.order
            if o > top:
                continue
            ax.axvline(o, color=colour, ls=dash, lw=0.9,
                       label=f"{g.name + ': ' if several else ''}k × {g.order:.4g}"
                       if k == 1 else None)
            labels.append(Label(f"{k}×" + (f" {g.short}" if several else ""), (o, hi),
                                ((2, -3), (2, -14), (2, -25), (2, -36)),
                                {"color": colour, "fontsize": 7, "ha": "left", "va": "top",
                                 "bbox": {"boxstyle": "round,pad=0.1", "fc": "0.15",
                                          "ec": "none", "alpha": 0.7}}))
    handles, texts = ax.get_legend_handles_labels()
    fig.legend(handles, texts, loc="outside lower center", ncol=3, fontsize=7,
               facecolor="0.35", labelcolor="w", framealpha=1.0)
    ax.set_title(f"{ca.name}: rpm-order map of {ca.force_mesh}; mesh orders of "
                 + ("every mesh frequency" if several else f"{ca.groups[0].order:.4g}"),
                 fontsize=9)
    place_labels(fig, ax, labels, avoid=[ax.title])
    return fig


# --------------------------------------------------------------------------- stability


def stability_figure(ca: CaseAnalysis, *, figsize: tuple[float, float] = (8.0, 4.4)
                     ) -> Figure | None:
    """Floquet growth rate over input speed with the unstable regions shaded (None if absent).

    Each unstable region is labelled with the candidate it is attributed to (the label of the
    Floquet table; "unattributed" when none holds), placed without overlaps. The ticks at the
    top are the theory candidates of the table (solid: allowed, dotted: suppressed by the mesh
    phasing; one colour per mesh frequency).
    """
    ch = ca.chart
    if ch is None:
        return None
    fig = _figure(figsize)
    ax = fig.add_subplot()
    speed = ch.mesh_frequencies_hz / ca.mesh_frequency_per_rpm
    g = np.where(np.isfinite(ch.growth_rate), ch.growth_rate, np.nan)
    ax.plot(speed, g, color="C0", lw=1.0, label="growth rate ln(max|μ|)/T")
    regions = ca.floquet_regions()
    for i, reg in enumerate(regions):
        ax.axvspan(reg["lower_rpm"], reg["upper_rpm"], color="C3", alpha=0.25, lw=0,
                   label="unstable" if i == 0 else None)
    c = ca.candidates
    several = ca.several_mesh_frequencies
    colour = {gr.name: (f"C{j + 1}" if j else "k") for j, gr in enumerate(ca.groups)}
    for i in range(len(c)):
        group = str(c.mesh_frequency[i]) if c.mesh_frequency is not None else ""
        ax.axvline(c.rpm[i], ymin=0.93, ymax=1.0,
                   color=colour.get(group, "k") if c.allowed[i] else "0.6",
                   ls="-" if c.allowed[i] else ":", lw=0.8)
    if several:
        for gr in ca.groups:
            ax.plot([], [], color=colour[gr.name], lw=0.8, label=f"candidates of {gr.name}")
    else:
        ax.plot([], [], color="k", lw=0.8, label="candidates (dotted: suppressed)")
    ax.set_xlabel("input speed [min⁻¹]")
    ax.set_ylabel("growth rate [1/s]")
    ax.set_xlim(speed[0], speed[-1])
    finite = g[np.isfinite(g)]
    if finite.size:
        lo, top = float(finite.min()), float(finite.max())
        span = max(top - lo, 1.0)
        ax.set_ylim(lo - 0.05 * span, top + 0.45 * span)  # room for the region labels
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize=7)
    title = (f"{ca.name}: Floquet stability over speed (shaded: unstable; "
             f"{speed.size} speeds, boundaries refined)")
    if ch.method:
        title += "\n" + "\n".join(textwrap.wrap(ch.method, 110))
    ax.set_title(title, fontsize=9)
    labels = []
    for reg in sorted(regions, key=lambda r: -r["growth"]):
        x = 0.5 * (reg["lower_rpm"] + reg["upper_rpm"])
        text = reg["label"] or "unattributed"
        labels.append(Label(text, (x, reg["growth"]), ((0, 6), (0, 18), (0, 30), (22, 6),
                                                        (-22, 6), (0, 42)),
                            {"fontsize": 7, "ha": "center", "va": "bottom", "color": "C3",
                             "bbox": {"boxstyle": "round,pad=0.15", "fc": "w", "ec": "C3",
                                      "lw": 0.5, "alpha": 0.85}}))
    place_labels(fig, ax, labels, avoid=[ax.get_legend()])
    return fig
