"""The sections of a measured report (:func:`measured_sections`), read from a
:class:`~gearvib.report.measured_case.MeasuredCase`.

Measurement and speed reference, gear set (or machine), spectra with their identified peaks,
fault lines (:mod:`gearvib.report.bearings`), the rpm maps and the classified rises, and the
provenance; :func:`gearvib.report.measured_nvh.with_level_pages` puts the summary and the NVH
pages in front of them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from gearvib.report.bearings import (
    FAULT_SECTION_ID,
    FAULT_TITLE,
    comb_note,
    fault_line_blocks,
    rig_blocks,
)
from gearvib.report.blocks import Block, Section
from gearvib.report.measured_case import MeasuredCase
from gearvib.report.measured_figures import (
    order_map_figure,
    record_figure,
    sonogram_figure,
    spectra_figure,
)
from gearvib.report.measured_peaks import MAX_LABEL_CHANCE, PEAK_HEADER
from gearvib.report.nvh import LEVELS_SECTION_ID
from gearvib.report.rises import REGION_HEADER, RISE_HEADER
from gearvib.report.verdict import SUMMARY_ID
from gearvib.report.wording import count, span

__all__ = ["MEASURED_SECTION_IDS", "TITLES", "measured_sections"]


MEASURED_SECTION_IDS = (SUMMARY_ID, LEVELS_SECTION_ID, "measurement", "gear-set", "spectra",
                        FAULT_SECTION_ID, "sonograms", "resonances", "provenance")
"""Section ids of a measured report, in order (the summary and the NVH pages first:
:func:`gearvib.report.measured_nvh.with_level_pages`)."""
_OWN_SECTION_IDS = MEASURED_SECTION_IDS[2:]  # those measured_sections writes

TITLES = {"measurement": "Measurement and speed reference",
          "gear-set": "Gear set: kinematics and natural frequencies",
          "spectra": "Spectrum and order spectrum with identified peaks",
          FAULT_SECTION_ID: FAULT_TITLE,
          "sonograms": "Order analysis: rpm-frequency and rpm-order maps",
          "resonances": "Resonances and their classification",
          "provenance": "Provenance"}
"""Heading of every section :func:`measured_sections` writes."""


def _table(caption: str, header: Sequence[str], rows: Sequence[Sequence[Any]]) -> Block:
    return Block("table", caption, tuple(header), tuple(tuple(str(c) for c in r) for r in rows))


def measured_sections(mc: MeasuredCase) -> list[Section]:
    """The measured report as sections (rendered by the HTML and PDF writers)."""
    n = mc.name
    s: dict[str, list[Block]] = {k: [] for k in _OWN_SECTION_IDS}
    s["measurement"] += [
        _table(f"Record of {n}", ("item", "value"), mc.measurement_rows()),
        _table(f"Channels of {n}", ("channel", "units", "description", "role"),
               mc.channel_rows()),
        Block("figure", f"{n}: the analysed channel {mc.channel} over time and the reference "
              f"speed ({mc.measurement.reference}).", figure=lambda: record_figure(mc)),
        *[Block("text", f"Note ({n}): {t}") for t in mc.notes]]
    if mc.has_gearset:
        s["gear-set"] += [
            _table(f"Gear set of {n}", ("parameter", "value"), mc.gearset_rows()),
            _table(f"Natural frequencies of the model of {n} (mean mesh stiffness; mode 1 is "
                   "the rigid-body rotation)", ("mode", "f [Hz]", "type",
                                                 "dominant mesh (strain energy)"),
                   mc.mode_rows())]
    elif mc.rig is not None:
        s["gear-set"] += rig_blocks(mc, mc.rig)
    else:
        s["gear-set"] += [Block("text", f"{n}: no gear set was given (--gearset CONFIG). The "
                                "report shows the orders of the reference shaft and what the "
                                "maps show by themselves; mesh orders, the catalogue of "
                                "kinematic lines, natural frequencies and the classification "
                                "of rises as forced resonances need the gear set.")]
    expl = ("natural frequencies of the model" if mc.natural_frequencies_hz.size else
            "harmonics of the reference shaft")
    if mc.rig is not None and not mc.varying_speed:
        expl += " and the bearing lines at the mean speed"
    if not mc.varying_speed and mc.has_gearset:
        expl += " and the kinematic catalogue at the mean speed"
    s["spectra"] += [
        Block("figure", f"{n}: rms spectrum of {mc.channel} over the record and its order "
              "spectrum (order-tracked to the reference shaft); the strongest peaks are "
              "labelled with their best explanation, the tables list every peak.",
              figure=lambda: spectra_figure(mc)),
        Block("text", f"{n}: spectrum peaks are compared with the {expl}; order peaks with "
              + ("the gear set's kinematic catalogue (mesh harmonics, planet-pass sidebands, "
                 "shaft and fault orders that the planet phasing lets through)"
                 if mc.has_gearset else "the integer orders of the reference shaft and the "
                 "bearing lines" if mc.rig is not None else
                 "the integer orders of the reference shaft")
              + ". A candidate's window is the peak's -3 dB half-width plus the line's "
              "uncertainty; 'chance' is how often a random peak there would get a label. A "
              "label is offered only when its family's windows cover at most "
              f"{100 * MAX_LABEL_CHANCE:g} % of the band around the peak (e.g. not the "
              "high harmonics of a shaft, whose windows grow with the speed uncertainty "
              "until any peak matches one): otherwise the peak is unexplained, and the "
              "table says how often its nearest family would match a random peak."),
        _table(f"Spectrum peaks of {n}", PEAK_HEADER, mc.peak_rows())]
    if mc.order_spectrum is not None:
        s["spectra"] += [_table(f"Order peaks of {n}", PEAK_HEADER, mc.order_peak_rows())]
    comb = comb_note(mc) if mc.fault_lines is not None else ""
    if comb:
        s["spectra"] += [Block("text", comb)]
    s[FAULT_SECTION_ID] += fault_line_blocks(mc)
    if mc.fmap is not None:
        fam = ("mesh orders " + ", ".join(f"1–{k} ({g})" for g, _, k in mc.mesh_groups)
               if mc.mesh_groups else "the strongest order rays the map shows (orders of the "
               "reference shaft, labelled with their order)")
        s["sonograms"] += [
            Block("figure", f"{n}: rpm-frequency map of {mc.channel}; speed vertical, inclined "
                  f"lines = {fam}"
                  + (", dotted vertical lines = natural frequencies of the model"
                     if mc.natural_frequencies_hz.size else "")
                  + ", dash-dotted grey lines = frequency-locked lines of the map that no "
                  "natural frequency explains, circles = forced resonances, squares = "
                  "parametric rises (theory candidates), crosses = unexplained rises.",
                  figure=lambda: sonogram_figure(mc))]
        if mc.omap is not None:
            s["sonograms"] += [Block("figure", f"{n}: rpm-order map of {mc.channel} (order "
                                     "tracked to the reference shaft).",
                                     figure=lambda: order_map_figure(mc))]
        if mc.features is not None:
            s["sonograms"] += [Block(
                "text", f"{n}: features of the map (median over the frames): order-locked "
                "rays (orders of the reference shaft): " + (", ".join(
                    f"{o:.4g}" for o in mc.features.orders) or "none")
                + "; frequency-locked vertical lines: " + (", ".join(
                    f"{f:.0f} Hz" for f in mc.features.frequencies) or "none") + ".")]
    else:
        s["sonograms"] += [Block("text", f"{n}: no rpm maps: the reference speed is "
                                 f"{span(*mc.speed_range, 'min⁻¹')}, too narrow a range to "
                                 "tell order-locked from frequency-locked content.")]
    res = mc.resonances
    if res is not None:
        s["resonances"] += [
            Block("text", f"{n}: {res.summary()}; {count(len(mc.regions), 'speed region')}. "
                  f"Rises of at least {mc.settings.threshold_db:g} dB along the "
                  + ("mesh orders" if mc.has_gearset else "order rays of the map")
                  + ", along the " + ("natural frequencies" if mc.has_gearset
                                      else "vertical lines of the map")
                  + " and as isolated spots within 40 dB of the map maximum. A rise where an "
                  "order crosses a natural frequency (tolerance "
                  f"{100 * max(mc.settings.tolerance, 0.05):g} % plus the rise width) is a "
                  "forced resonance; 'chance' is how often a random rise would get the same "
                  "explanation; 'on' is the order k of the ray or f_i."),
            _table(f"Resonance regions of {n} (rises closer than 3 % of the top speed)",
                   REGION_HEADER, mc.region_table_rows()),
            _table(f"Rises of {n}", RISE_HEADER, mc.resonance_rows()),
            _table(f"Crossings in {n}", ("crossing", "f [Hz]", "speed [min⁻¹]", "found"),
                   mc.crossing_rows())]
    else:
        s["resonances"] += [Block("text", f"{n}: no resonance classification (" + (
            "constant speed" if not mc.varying_speed else
            "no natural frequency or vertical line to classify against") + ").")]
    s["provenance"] += [_table(f"Provenance of {n}", ("item", "value"), mc.provenance)]
    return [Section(k, TITLES[k], tuple(s[k])) for k in _OWN_SECTION_IDS]
