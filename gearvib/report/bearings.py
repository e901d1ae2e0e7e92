"""Pages of a measured report on bearing and gear-fault lines, and on a rig without gears.

The section ``fault-lines`` of :mod:`gearvib.report.measured`: every fault family of the
description (the declared ``[[rolling_bearing]]`` tables, the gear faults of a gear set)
checked at its own position in the squared envelope (order) spectrum and in the order
spectrum (:mod:`gearvib.fault_lines`, :mod:`analysis.line_evidence`), with

* a sentence per detected family (harmonics found, prominence, chance of a coincidence) and
  how the demodulated band was chosen;
* the fast kurtogram (when it chose the band);
* the envelope spectrum with the families drawn, and the order spectrum likewise;
* a table of the families in each spectrum: status, harmonics found, prominence of each
  harmonic over its local floor, sidebands found, chance.

A ``type = "shafts"`` description (:mod:`gearvib.rig`) gets, instead of the gear-set tables,
its shafts and bearings with their defect orders (:func:`rig_blocks`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.envelope import EnvelopeSpectrum
from gearvib.fault_lines import (
    MIN_BANDWIDTH_FACTOR,
    FaultLines,
    catalogue_families,
    check_fault_lines,
    known_families,
)
from gearvib.report.sections import Block

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from analysis.catalogue import KinematicCatalogue, RollingBearing
    from analysis.measurement import Measurement
    from gearvib.report.measured_case import MeasuredCase
    from gearvib.rig import ShaftRig

__all__ = [
    "ENVELOPE_HEADER",
    "FAULT_SECTION_ID",
    "FAULT_TITLE",
    "ORDER_HEADER",
    "comb_note",
    "envelope_figure",
    "fault_line_blocks",
    "fault_lines_of",
    "kurtogram_figure",
    "order_figure",
    "rig_blocks",
    "summary",
]

FAULT_SECTION_ID = "fault-lines"
"""Id of the section."""
FAULT_TITLE = "Bearing and gear-fault lines: envelope analysis"
"""Its title."""

ENVELOPE_HEADER = ("source", "family", "fundamental: order (Hz)", "status", "harmonics",
                   "prominence of h1, h2, h3 [dB]", "sidebands", "chance")
ORDER_HEADER = ("source", "family", "status", "harmonics", "prominence of h1 [dB]", "chance")


def fault_lines_of(m: Measurement, catalogue: KinematicCatalogue | None,
                   bearings: Sequence[RollingBearing], *, channel: str | None,
                   band: Any = None, min_bandwidth: float | None = None,
                   top_order: float = 200.0,
                   notes: list[str] | None = None) -> FaultLines | None:
    """The fault lines of a measured report (None without fault families).

    Parameters
    ----------
    m : Measurement
        The record.
    catalogue : KinematicCatalogue or None
        The description's catalogue in orders of the reference shaft.
    bearings : sequence of RollingBearing
        The description's bearings (rings' members).
    channel : str or None
        The analysed channel.
    band, min_bandwidth
        Band to demodulate [Hz] or the narrowest band the kurtogram may choose
        (:func:`gearvib.fault_lines.check_fault_lines`).
    top_order : float
        Highest order of the known shaft and mesh harmonics.
    notes : list of str, optional
        Receives a sentence when the check cannot be made.
    """
    if catalogue is None:
        if band is not None or min_bandwidth is not None:
            raise ValueError("envelope_band and min_bandwidth need a description with fault "
                             "lines (--gearset CONFIG with [[rolling_bearing]] or gears)")
        return None
    fams = catalogue_families(catalogue, bearings)
    if not fams:
        if notes is not None:
            notes.append("the description declares no rolling bearing and no gear with a "
                         "fault line: no envelope analysis")
        return None
    try:
        return check_fault_lines(m, fams, known=known_families(catalogue, top_order),
                                 channel=channel, band=band, min_bandwidth=min_bandwidth)
    except ValueError as exc:
        if band is not None or min_bandwidth is not None:
            raise
        if notes is not None:
            notes.append(f"fault lines not checked: {exc}")
        return None


def _chance(c: float) -> str:
    if not np.isfinite(c):
        return "–"
    return "below 1e-4" if c < 1e-4 else f"{c:.2g}"


def _shown_chance(status: str, chance: str) -> str:
    """The chance of a coincidence as the tables show it: only for a family whose lines were
    found (detected, possible, explained); a family not detected has nothing to judge."""
    if chance == "–" or status.startswith(("not detected", "outside")):
        return "–"
    return _chance(float(chance))


def _where(fl: FaultLines) -> str:
    return ("squared envelope spectrum" if fl.domain == "frequency"
            else "squared envelope order spectrum")


def summary(fl: FaultLines, name: str) -> str:
    """What the envelope spectrum shows, in sentences: the families detected (with their
    harmonics, prominence and chance), those possible or explained by others."""
    ev = fl.envelope_evidence
    unit = "Hz" if fl.domain == "frequency" else "orders"
    parts = []
    for i, (fam, st) in enumerate(zip(fl.families, ev.status, strict=True)):
        c = ev.checks[i]
        harm = c.sideband == 0
        first = harm & (c.harmonic == 1)
        if st == "detected":
            proms = ", ".join(f"{v:.1f}" for v, ok in zip(c.prominence_db[harm], c.found[harm],
                                                          strict=True) if ok)
            sb = c.sideband != 0
            sbs = (f", {int(np.sum(c.found & sb))} of {int(sb.sum())} sidebands"
                   if sb.any() else "")
            parts.append(f"{fam.name} detected: fundamental at {c.position[first][0]:.5g} "
                         f"{unit} (expected {c.expected[first][0]:.5g}), {c.harmonics_found} "
                         f"of {int(harm.sum())} harmonics found at {proms} dB over the local "
                         f"floor{sbs}; chance of a coincidence {_chance(ev.chance[i])}.")
        elif st == "possible":
            parts.append(f"{fam.name} possible: {c.harmonics_found} harmonics found, but a "
                         f"family of its shape at a random position would be detected as "
                         f"easily (chance {_chance(ev.chance[i])}).")
    for i, (fam, st) in enumerate(zip(fl.families, ev.status, strict=True)):
        if st == "explained":
            parts.append(f"The lines in the windows of {fam.name} are those of "
                         f"{ev.explained_by[i].replace(', ', ' and ')} (harmonics, "
                         "shaft-modulation sidebands): no evidence of this fault.")
    if not any(st in ("detected", "possible") for st in ev.status):
        parts.insert(0, f"{name}: no fault family is detected in the {_where(fl)}.")
    else:
        parts.insert(0, f"{name}, {_where(fl)}:")
    if fl.order_evidence is not None:
        oe = fl.order_evidence
        for want, text in (("detected", "lines of {} that a random family would rarely "
                            "catch (chance {}), which the envelope spectrum does not confirm"),
                           ("possible", "lines at the positions of {} that a random family "
                            "would catch as easily (chance {}): no evidence")):
            only = [(fam.name, _chance(ch)) for fam, so, se, ch in zip(
                fl.families, oe.status, ev.status, oe.chance, strict=True)
                if so == want and se not in ("detected", "possible")]
            if only:
                parts.append("The order spectrum of the raw signal has " + text.format(
                    " and ".join(n for n, _ in only), ", ".join(c for _, c in only)) + ".")
        both = [fam.name for fam, so, se in zip(fl.families, oe.status, ev.status, strict=True)
                if so == "detected" and se == "detected"]
        if both:
            parts.append("The order spectrum of the raw signal shows " + " and ".join(both)
                         + " too: the fault's lines stand out without demodulation.")
    return " ".join(parts)


def _band_text(fl: FaultLines, name: str) -> str:
    b = fl.envelope.band
    kg = fl.kurtogram
    if kg is None:
        src = "given"
    else:
        src = (f"chosen by the fast kurtogram (level {kg.level:.1f}, spectral kurtosis "
               f"K = {kg.kurtosis_max:.3g}) among the bands at least "
               f"{fl.min_bandwidth:.4g} Hz wide ({MIN_BANDWIDTH_FACTOR:g} x the highest line "
               "checked at the top speed, unless given)")
    if isinstance(fl.envelope, EnvelopeSpectrum):  # fl.domain == "frequency"
        res = f"resolution {fl.envelope.resolution_hz:.3g} Hz"
        dom = ("in Hz, the families placed at the stated constant speed "
               f"{fl.speed_rpm:.6g} min⁻¹")
    else:
        res = f"resolution {fl.envelope.resolution_orders:.3g} orders"
        dom = "in orders of the reference shaft (resampled to its angle)"
    return (f"{name}: squared envelope of the band {b.low:.5g}-{b.high:.5g} Hz, {src}; "
            f"spectrum {dom}, {res}. Each line of a family is sought where the catalogue puts "
            "it (the fundamental within 1 % plus one line, the other lines at exact multiples "
            "of the fundamental found); its prominence is its level over the median of the "
            f"lines around it. A family is detected when {_needed(fl)} "
            "stand 6 dB or more over their floor and a family of its shape placed at random "
            f"in the same spectrum would be detected so strongly at most "
            f"{100 * fl.envelope_evidence.max_chance:g} % of the time ('chance'); a family "
            "whose detection rests on lines that a stronger detected family, the shaft "
            "harmonics or a comb of another source (lines between the family's harmonics at "
            "a fraction of its rate) explain is 'explained' by them, not detected.")


def _needed(fl: FaultLines) -> str:
    """'its fundamental and 2 more harmonics' (the harmonics a detection needs)."""
    checks = fl.envelope_evidence.checks
    need = int(checks[0].min_harmonics) if checks else 2
    return ("its fundamental" if need <= 1 else "its fundamental and another harmonic"
            if need == 2 else f"its fundamental and {need - 1} more harmonics")


def envelope_rows(fl: FaultLines) -> list[tuple[str, ...]]:
    """Rows of the envelope table (:data:`ENVELOPE_HEADER`)."""
    f_ref = fl.speed_rpm / 60.0
    out: list[tuple[str, ...]] = []
    for fam, r in zip(fl.families, fl.envelope_evidence.rows(), strict=True):
        _, _, st, found, prom, sbs, chance = r
        chance = _shown_chance(st, chance)
        out.append((fam.source, fam.label, f"{fam.order:.4f} ({fam.order * f_ref:.4g} Hz)",
                    st, found, prom, sbs, chance))
    return out


def order_rows(fl: FaultLines) -> list[tuple[str, ...]]:
    """Rows of the order-spectrum table (:data:`ORDER_HEADER`)."""
    if fl.order_evidence is None:
        return []
    out: list[tuple[str, ...]] = []
    for fam, r in zip(fl.families, fl.order_evidence.rows(), strict=True):
        _, _, st, found, prom, _, chance = r
        chance = _shown_chance(st, chance)
        out.append((fam.source, fam.label, st, found, prom.split(",")[0], chance))
    return out


def kurtogram_figure(mc: MeasuredCase, figsize: tuple[float, float] = (8.0, 4.0)
                     ) -> Figure | None:
    """The fast kurtogram that chose the band (None when the band was given)."""
    fl = mc.fault_lines
    if fl is None or fl.kurtogram is None:
        return None
    from matplotlib.figure import Figure

    from analysis.envelope_plots import kurtogram_figure as draw

    fig = Figure(figsize=figsize, layout="constrained", dpi=100)
    draw(fl.kurtogram, ax=fig.add_subplot())
    ax = fig.axes[0]
    kg = fl.kurtogram
    b = kg.band
    width = 0.5 * kg.fs / np.asarray(kg.n_bands, dtype=float)
    narrow = np.flatnonzero(width < kg.min_bandwidth)
    if narrow.size:  # the levels the choice could not take, greyed
        ax.axhspan(narrow[0] - 0.5, kg.levels.size - 0.5, color="0.6", alpha=0.55, lw=0)
        ax.text(0.25 * kg.fs, narrow[0] - 0.3,
                f"bands narrower than {kg.min_bandwidth:.4g} Hz: not chosen", ha="center",
                va="top", fontsize=8, color="k")
    ax.set_title(f"{mc.name}: fast kurtogram of {mc.channel}\nband chosen (framed) "
                 f"{b.low:.5g}-{b.high:.5g} Hz, level {kg.level:.1f}, K = "
                 f"{kg.kurtosis_max:.3g}, among the bands at least {fl.min_bandwidth:.4g} Hz "
                 "wide", fontsize=9)
    return fig


def _evidence_figure(ev: Any, title: str, figsize: tuple[float, float]) -> Figure:
    from matplotlib.figure import Figure

    from analysis.envelope_plots import line_evidence_figure

    fig = Figure(figsize=figsize, layout="constrained", dpi=100)
    line_evidence_figure(ev, ax=fig.add_subplot(), title=title)
    return fig


def envelope_figure(mc: MeasuredCase, figsize: tuple[float, float] = (8.0, 5.0)
                    ) -> Figure | None:
    """The envelope (order) spectrum with the families: harmonics dashed, lines found
    marked, each family's status in the legend."""
    fl = mc.fault_lines
    if fl is None:
        return None
    b = fl.envelope.band
    what = "squared envelope spectrum" if fl.domain == "frequency" else \
        "squared envelope order spectrum"
    return _evidence_figure(fl.envelope_evidence, f"{mc.name}: {what} of {mc.channel}, band "
                            f"{b.low:.5g}-{b.high:.5g} Hz", figsize)


def order_figure(mc: MeasuredCase, figsize: tuple[float, float] = (8.0, 5.0)
                 ) -> Figure | None:
    """The order spectrum of the raw signal with the families."""
    fl = mc.fault_lines
    if fl is None or fl.order_evidence is None:
        return None
    return _evidence_figure(fl.order_evidence, f"{mc.name}: order spectrum of {mc.channel} "
                            "with the fault families", figsize)


def comb_note(mc: MeasuredCase) -> str:
    """A sentence on the spectrum peaks spaced by a detected fault's rate ("" if none).

    A fault's impacts excite the housing resonances, so the raw spectrum around them holds a
    comb of peaks spaced by the fault's rate: lines of the resonances modulated by the fault,
    which no catalogue line explains one by one. Pairs of the listed peaks at the spacing
    ``f_1 +- w`` (``w`` the spectrum's ENBW plus 1 % of ``f_1``) are counted and compared
    with the number expected among as many peaks placed at random in the band:
    ``n (n - 1)/2 * 2 w * (2/B) (1 - f_1/B)`` (the density of the distance between two
    uniform points of ``[0, B]``). Constant speed only.
    """
    fl = mc.fault_lines
    if fl is None or mc.varying_speed or len(mc.peaks) < 3:
        return ""
    peaks = np.sort(np.asarray(mc.peaks.frequency, dtype=float))
    n = peaks.size
    band = float(mc.frequency_max_hz)
    scale = 1.0 if fl.domain == "frequency" else fl.speed_rpm / 60.0
    out = []
    for fam, st, c in zip(fl.families, fl.envelope_evidence.status, fl.envelope_evidence.checks,
                          strict=True):
        if st != "detected":
            continue
        first = (c.harmonic == 1) & (c.sideband == 0)
        f1 = float(c.position[first][0]) * scale
        w = float(mc.spectrum.enbw_hz) + 0.01 * f1
        d = peaks[None, :] - peaks[:, None]
        pair = np.triu(np.abs(d - f1) <= w, k=1)
        k = int(pair.sum())
        expected = n * (n - 1) / 2 * 2 * w * (2 / band) * max(0.0, 1 - f1 / band)
        if k < 2 or k <= 2 * expected:
            continue
        inv = peaks[np.any(pair, axis=0) | np.any(pair, axis=1)]
        out.append(f"{mc.name}: {inv.size} of the {n} spectrum peaks ({inv.min():.0f}-"
                   f"{inv.max():.0f} Hz) form {k} pairs spaced by {fam.label} ({f1:.4g} Hz "
                   f"+- {w:.2g} Hz), where about {expected:.2g} would occur among {n} random "
                   f"peaks: the resonances there are modulated at the rate of {fam.name} "
                   "(its impacts excite them), which explains these peaks together though no "
                   "line explains them one by one.")
    return " ".join(out)


def _table(caption: str, header: Sequence[str], rows: Sequence[Sequence[Any]]) -> Block:
    return Block("table", caption, tuple(header), tuple(tuple(str(c) for c in r) for r in rows))


def fault_line_blocks(mc: MeasuredCase) -> list[Block]:
    """The blocks of the ``fault-lines`` section."""
    n = mc.name
    fl = mc.fault_lines
    if fl is None:
        why = ("the description declares no rolling bearing and no gear fault line"
               if mc.catalogue is not None else "no description (--gearset CONFIG) was given")
        return [Block("text", f"{n}: no bearing or gear-fault lines checked: {why}. Declare "
                      "the bearings in [[rolling_bearing]] tables of the gear set, or describe "
                      "a machine without gears as type = \"shafts\" (docs/measurements.md).")]
    unit = "Hz" if fl.domain == "frequency" else "orders"
    blocks = [Block("text", summary(fl, n)), Block("text", _band_text(fl, n))]
    if fl.kurtogram is not None:
        blocks.append(Block("figure", f"{n}: fast kurtogram of {mc.channel}: spectral kurtosis "
                            "of every band of the 1/3-binary tree (Antoni 2007); the band "
                            "demodulated is framed.", figure=lambda: kurtogram_figure(mc)))
    blocks += [
        Block("figure", f"{n}: squared envelope {'order ' if unit == 'orders' else ''}"
              f"spectrum of {mc.channel} with the fault families (dashed: their harmonics; "
              "triangles: harmonics found, dots: sidebands found; level over the median of "
              "the spectrum shown).", figure=lambda: envelope_figure(mc)),
        _table(f"Fault families of {n} in the squared envelope spectrum (axis: {unit})",
               ENVELOPE_HEADER, envelope_rows(fl))]
    if fl.order_evidence is not None:
        blocks += [
            Block("figure", f"{n}: order spectrum of {mc.channel} (the raw signal) with the "
                  "fault families.", figure=lambda: order_figure(mc)),
            _table(f"Fault families of {n} in the order spectrum", ORDER_HEADER,
                   order_rows(fl))]
    blocks += [Block("text", f"Note ({n}): {t}") for t in fl.notes]
    return blocks


def rig_blocks(mc: MeasuredCase, rig: ShaftRig) -> list[Block]:
    """The ``gear-set`` section of a machine without gears: its shafts and bearings."""
    n = mc.name
    cat = mc.catalogue
    first = (cat.harmonic == 1) & (cat.sideband == 0) if cat is not None else None
    shafts = [(s.name, f"{s.ratio:.6g}", "reference" if s.name == mc.reference_member else "")
              for s in rig.shafts]
    rows = []
    for b, spec in zip(rig.bearings(), rig.rolling_bearings, strict=True):
        def order(kind: str, name: str = b.name) -> str:
            if cat is None:
                return "–"
            k = first & (cat.family == kind) & (cat.member == name)
            return f"{float(cat.order[k][0]):.4f}" if k.any() else "–"

        rows.append((b.name, spec.member, b.outer if b.inner == spec.member else b.inner,
                     str(b.n_rolling), f"{1e3 * b.rolling_diameter:.4g}",
                     f"{1e3 * b.pitch_diameter:.4g}", f"{b.contact_angle_deg:g}",
                     order("bearing_bpfo"), order("bearing_bpfi"), order("bearing_bsf"),
                     order("bearing_ftf")))
    return [
        Block("text", f"{n}: the machine is described as shafts and rolling bearings without "
              f"gears ({rig.name}{': ' + rig.title if rig.title else ''}). It has no mesh "
              "orders and no natural frequencies: spectrum peaks are compared with the shaft "
              "harmonics and the bearing lines, and the bearing lines are checked in the "
              "envelope spectrum (section 'Bearing and gear-fault lines')."),
        _table(f"Shafts of {n} (speed per speed of the input shaft)",
               ("shaft", "speed ratio", "role"), shafts),
        _table(f"Rolling bearings of {n} (defect frequencies in orders of the reference "
               "shaft)", ("bearing", "shaft", "other ring on", "balls", "d [mm]", "D [mm]",
                          "contact angle [deg]", "BPFO", "BPFI", "BSF", "FTF"), rows)]
