"""The report as a list of sections of blocks (headings, paragraphs, tables, figures).

:func:`report_sections` builds it from analysed cases (:mod:`gearvib.report.case`) and their
comparisons (:mod:`gearvib.report.compare`); the HTML and PDF writers render the same list.
Every number in the text and the tables is read from the :class:`CaseAnalysis`, never computed
again here: a Floquet region has one label (:meth:`CaseAnalysis.floquet_regions`), a resonance
region one summary (:attr:`ResonanceRegion.summary`), and the counts in the text are the
lengths of the tables that list them. :func:`gearvib.report.crosscheck.cross_check` checks a
rendered report for exactly that.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from gearvib.report.blocks import Block, Section
from gearvib.report.case import PLANET_SIGNAL_GROWTH_DB, SPOT_RANGE_DB
from gearvib.report.case_analysis import MARKER_BUDGET, CaseAnalysis, key_speed_rows
from gearvib.report.figures import (
    force_limit,
    map_level_max,
    mesh_stiffness_figure,
    order_map_figure,
    sonogram_figure,
    spectra_figure,
    spectrum_limits,
    stability_figure,
    tooth_force_figure,
)
from gearvib.report.nvh import LEVELS_SECTION_ID, LEVELS_TITLE, levels_blocks
from gearvib.report.rises import REGION_HEADER, RISE_HEADER, merged_modes
from gearvib.report.verdict import (
    SUMMARY_ID,
    SUMMARY_TITLE,
    CaseSummary,
    RiseMatch,
    mode_descriptions,
    rise_explanation,
    settings_summary,
    summary_blocks,
)
from gearvib.report.wording import count, span

__all__ = ["SECTION_IDS", "Block", "Section", "case_summary", "inputs_rows", "report_sections"]


SECTION_IDS = (SUMMARY_ID, LEVELS_SECTION_ID, "parameters", "modes", "tooth-forces", "spectra",
               "mesh-stiffness", "sonograms", "resonances", "stability", "comparison",
               "provenance")
"""Section ids in report order (``comparison`` only with two or more cases)."""

TITLES = {SUMMARY_ID: SUMMARY_TITLE, LEVELS_SECTION_ID: LEVELS_TITLE,
          "parameters": "Gear-set parameters", "modes": "Natural frequencies and modes",
          "tooth-forces": "Tooth forces over the run (cf. paper Fig. 7)",
          "spectra": "Spectra of the tooth forces (cf. paper Fig. 8)",
          "mesh-stiffness": "Summed mesh stiffness (cf. paper Figs. 9 and 10)",
          "sonograms": "Order analysis: sonograms and order maps (cf. paper Fig. 11)",
          "resonances": "Identified resonances and instability regions",
          "stability": "Floquet stability chart and theory candidates",
          "comparison": "Comparison of the cases", "provenance": "Provenance"}

FLOQUET_HEADER = ("from [min⁻¹]", "to [min⁻¹]", "width [min⁻¹]", "f_mesh [Hz]", "growth [1/s]",
                  "candidate", "mechanism", "evidence")
CANDIDATE_HEADER = ("speed [min⁻¹]", "f_mesh [Hz]", "kind", "n", "label", "allowed",
                    "Floquet region")
GROWTH_HEADER = ("band [min⁻¹]", "candidate", "time in band [ms]", "growth rate [1/s]",
                 "growth [dB]", "verdict")


def _table(caption: str, header: Sequence[str], rows: Sequence[Sequence[Any]]) -> Block:
    return Block("table", caption, tuple(header), tuple(tuple(str(c) for c in r) for r in rows))


def _mesh_frequency_text(ca: CaseAnalysis) -> str:
    """The sonogram section's sentence on the mesh frequencies."""
    _lo, hi = ca.speed_range
    if ca.several_mesh_frequencies:
        return (f"{ca.name}: " + "; ".join(
            f"f_mesh,{g.name} = {g.frequency_per_rpm:.5g} Hz per min⁻¹ × n_in ({g.order:.4g} "
            f"mesh cycles per input revolution; {g.frequency_per_rpm * hi:.0f} Hz at "
            f"{hi:.0f} min⁻¹; orders 1–{g.orders} drawn)" for g in ca.groups) + ".")
    g = ca.groups[0]
    text = (f"{ca.name}: f_mesh = {g.frequency_per_rpm:.5g} Hz per min⁻¹ × n_in"
            + (" (paper eq. 5)" if ca.paper_set else "")
            + f", {g.frequency_per_rpm * hi:.0f} Hz at {hi:.0f} min⁻¹; orders 1–{g.orders} "
            "drawn.")
    rows = key_speed_rows(ca)
    if rows:
        text += " " + "; ".join(f"at {r[0]} f_mesh = {r[1]}" for r in rows) + "."
    return text


def _common(values: Sequence[float]) -> float | None:
    finite = [v for v in values if v == v and abs(v) != float("inf")]
    return max(finite) if finite else None


def report_sections(cases: Sequence[CaseAnalysis], comparisons: Sequence[Any] = ()
                    ) -> list[Section]:
    """The report as a list of sections (shared by the HTML and PDF writers).

    Parameters
    ----------
    cases : sequence of CaseAnalysis
        Analysed runs, in report order.
    comparisons : sequence of Comparison
        Results of :func:`gearvib.report.compare.compare_cases` (section ``comparison``).

    Returns
    -------
    list of Section
        In the order of :data:`SECTION_IDS`.
    """
    s: dict[str, list[Block]] = {k: [] for k in SECTION_IDS}
    # common scales for the figures the paper compares case by case
    several_cases = len(cases) > 1
    f_top = _common([force_limit(ca) for ca in cases]) if several_cases else None
    force_ylim = (-0.05 * f_top, 1.05 * f_top) if f_top else None
    spec = [spectrum_limits(ca) for ca in cases]
    spec_ylim = ((min(v[0] for v in spec), max(v[1] for v in spec))
                 if several_cases and spec else None)
    level = _common([map_level_max(ca) for ca in cases]) if several_cases else None
    level_o = _common([map_level_max(ca, order=True) for ca in cases]) if several_cases \
        else None
    same_scale = " (same scale as the other cases)" if several_cases else ""
    for ca in cases:
        s["parameters"] += [Block("heading", ca.name if ca.label in ("", ca.name)
                                  else f"{ca.name}: {ca.label}"),
                            _table(f"Gear set and run of {ca.name}", ("parameter", "value"),
                                   ca.parameters)]
        s["parameters"] += [Block("text", f"Note ({ca.name}): {n}") for n in ca.notes]
        s["modes"] += [Block("heading", ca.name), _table(
            f"Natural frequencies and mode types of {ca.name} (mean mesh stiffness; mode 1 is "
            "the rigid-body rotation" + (", so the paper's f2, f3, ... keep their numbers)"
                                         if ca.paper_set else ")"),
            ("mode", "f [Hz]", "type", "multiplicity", "dominant mesh (strain energy)"),
            ca.modes)]
        panels = ca.force_meshes or [(ca.groups[0].name, (ca.force_mesh,))]
        s["tooth-forces"] += [Block(
            "figure", f"{ca.name}: normal tooth forces of "
            + "; ".join(f"{', '.join(ms)}" + (f" ({g})" if len(panels) > 1 else "")
                        for g, ms in panels)
            + f" over the run, drive flank positive{same_scale}. Meshes whose forces are "
            "identical (planets in phase) are drawn as one line named after all of them.",
            figure=lambda ca=ca: tooth_force_figure(ca, ylim=force_ylim))]
        s["spectra"] += [
            Block("figure", f"{ca.name}: spectra of the tooth forces of "
                  + ", ".join(f.mesh for f in ca.spectra) + f" over the whole run{same_scale}; "
                  "the strongest peaks are labelled with their best theory candidate ('?': "
                  "unexplained; '~': ambiguous, the peak is so broad that a random peak would "
                  "match as easily); the table lists every peak.",
                  figure=lambda ca=ca: spectra_figure(ca, ylim=spec_ylim)),
            Block("text", f"{ca.name}: candidates are the natural frequencies, 2 f_i/n and "
                  "(f_i + f_j)/n allowed by the mesh phasing; a candidate's window is the "
                  f"peak's -3 dB half-width + {100 * ca.settings.tolerance:g} % of its value; "
                  "'chance' is how often a random peak there would get a label. A peak is "
                  "ambiguous when a random one would match as easily (broad run-up humps)."),
            _table(f"Peaks of {ca.name}",
                   ("mesh", "peak", "deviation of the best [Hz]", "window [Hz]", "chance"),
                   ca.peak_rows())]
        key_rows = key_speed_rows(ca)
        s["sonograms"] += [Block("heading", ca.name), Block("text", _mesh_frequency_text(ca))]
        if key_rows:
            s["sonograms"] += [_table(
                f"Mesh frequency of {ca.name} at the speeds where the paper reads resonances "
                "off its Figure 11 (case 1: 1500, 2600, 3100 min⁻¹)",
                ("sun speed", "mesh frequency", "nearest theory values"), key_rows)]
        n_marked = sum(str(m) in ("forced resonance", "parametric instability")
                       for m in ca.resonances.mechanism)
        s["sonograms"] += [
            Block("figure", f"{ca.name}: sonogram (rpm-frequency map) of the tooth force "
                  f"{ca.force_mesh}{same_scale}; speed vertical, inclined lines = mesh orders "
                  + ", ".join(f"1–{g.orders}" + (f" of {g.name} ({g.short})"
                                                   if ca.several_mesh_frequencies else "")
                              for g in ca.groups)
                  + ", dotted vertical lines = natural frequencies (named at the bottom), "
                  "circles = forced resonances, squares = parametric instabilities"
                  + (f" (the {MARKER_BUDGET} strongest explained rises)"
                     if n_marked > MARKER_BUDGET else "")
                  + ", red bands = Floquet-unstable speeds; every rise is in the tables of "
                  "the next section.", figure=lambda ca=ca: sonogram_figure(ca, level_max=level)),
            Block("figure", f"{ca.name}: rpm-order map of the same force{same_scale}, with "
                  "every mesh order the report discusses.",
                  figure=lambda ca=ca: order_map_figure(ca, level_max=level_o))]
        res = ca.resonances
        s["resonances"] += [
            Block("heading", ca.name),
            Block("text", f"{ca.name}: {res.summary()}; "
                  f"{count(len(ca.regions), 'speed region')}. Rises of at least "
                  f"{ca.settings.threshold_db:g} dB along the mesh orders (where they are "
                  "resolved), along the natural frequencies and as isolated spots within "
                  f"{SPOT_RANGE_DB:g} dB of the map maximum"
                  + ("; every rise on a mesh order is classified against the orders of its "
                     "own mesh frequency" if ca.several_mesh_frequencies else "")
                  + ". Explanations: a mesh order crossing a natural frequency (forced "
                  f"resonance; tolerance {100 * ca.settings.tolerance:g} % of the natural "
                  "frequency plus the rise width), a Floquet-unstable band that grows in this "
                  "run (parametric instability); 'chance' is how often a random rise would "
                  "get the same explanation. In the tables 'on' is the mesh order k of the ray "
                  "or f_i (along a natural frequency)."),
            *[Block("text", f"{ca.name}: {n}") for n in res.notes
              if not n.startswith(("rays analysed", "unstable band"))
              and "rays analysed" not in n],
            *([Block("text", f"{ca.name}: features of the map (median over the frames): "
                     "order-locked rays (orders of the input): " + (", ".join(
                         f"{o:.4g}" for o in ca.features.orders) or "none")
                     + "; frequency-locked vertical lines: " + (", ".join(
                         f"{f:.0f} Hz" for f in ca.features.frequencies) or "none") + ".")]
              if ca.features is not None else []),
            _table(f"Resonance regions of {ca.name} (rises closer than 3 % of the top speed)",
                   REGION_HEADER, ca.region_table_rows()),
            _table(f"Rises of {ca.name}", RISE_HEADER, ca.resonance_rows()),
            Block("text", f"{ca.name}: every crossing of a mesh order with a natural frequency "
                  "in the run, at the speed f_i / (k × f_mesh per min⁻¹), and what the map "
                  "shows there."),
            _table(f"Crossings in {ca.name}",
                   ("crossing", "f_i [Hz]", "speed [min⁻¹]", "found"), ca.crossing_rows())]
        pr = ca.planet_resonances
        if pr is not None:
            s["resonances"] += [
                Block("text", f"{ca.name}: planet modes. A Floquet-unstable band grows by "
                      f"at least {PLANET_SIGNAL_GROWTH_DB:g} dB in this run, so the difference "
                      "of the tooth forces "
                      f"{ca.sun_meshes[0]} − {ca.sun_meshes[1]} is analysed too: it holds "
                      "only the planet modes, which in-phase mesh harmonics do not force and "
                      f"whose growth is too small to show in a single mesh force. "
                      f"{pr.summary()}."),
                _table(f"Planet-mode rises of {ca.name}", RISE_HEADER,
                       ca.resonance_rows(planet=True))]
        if ca.growth_rows():
            s["resonances"] += [Block(
                "text", f"{ca.name}: growth of every Floquet-unstable band during this run, "
                "exp(time in band × growth rate); a band 'develops' with at least 20 dB. The "
                "candidate is the one of the Floquet table."),
                _table(f"Band growth in {ca.name}", GROWTH_HEADER, ca.growth_rows())]
        s["stability"] += [Block("heading", ca.name)]
        if ca.chart is not None:
            s["stability"] += [
                Block("figure", f"{ca.name}: Floquet stability of the linearised periodic "
                      "system over input speed; shaded = unstable, each region labelled with "
                      "the candidate of the table below.",
                      figure=lambda ca=ca: stability_figure(ca)),
                Block("text", f"{ca.name}: a region's candidate is the theory candidate "
                      "(2 f_i/n or (f_i + f_j)/n, n ≤ 10) whose centre lies in the region "
                      "(± 1 %) and whose modes carry the growing Floquet solution at the "
                      "region's peak (≥ 30 %; 'evidence' gives its modal energy shares); the "
                      "lowest order wins among equally good ones. 'unattributed': no "
                      "candidate holds, the nearest is not taken as such."),
                _table(f"Unstable speed intervals of {ca.name} (Floquet)", FLOQUET_HEADER,
                       ca.region_rows())]
            if ca.chart.method:
                s["stability"] += [Block(
                    "text", f"{ca.name}: several mesh frequencies ("
                    + ", ".join(f"{g.name} {g.frequency_per_rpm:.5g} Hz per min⁻¹"
                                for g in ca.groups)
                    + f"); Floquet analysis: {ca.chart.method}.")]
        else:
            s["stability"] += [Block("text", f"{ca.name}: no Floquet stability chart. " + " ".join(
                n for n in ca.notes if "stability" in n or "gear-set" in n or "Floquet" in n))]
        if ca.first_order:
            s["stability"] += [_table(
                f"First-order perturbation regions of {ca.name} (Hsu 1963), beside the Floquet "
                "intervals above (first order is exact only for n = 1; higher orders need "
                "Floquet)", ("region", "from [min⁻¹]", "to [min⁻¹]", "width [min⁻¹]",
                             "undamped width [min⁻¹]"), ca.first_order)]
        s["stability"] += [_table(
            f"Theory candidates of {ca.name} (2 f_i/n, (f_i + f_j)/n with n ≤ "
            f"{ca.settings.n_max} in the speed range, and every candidate a Floquet region is "
            "attributed to"
            + ("; [name] = the mesh frequency" if ca.several_mesh_frequencies else "") + ")",
            CANDIDATE_HEADER, ca.candidate_rows())]
        s["provenance"] += [Block("heading", ca.name),
                            _table(f"Provenance of {ca.name}", ("item", "value"),
                                   ca.provenance)]
    paper = any(ca.paper_set for ca in cases)
    s["mesh-stiffness"] = [
        Block("figure", "Summed stiffness of the meshes of every central gear over three mesh "
              "cycles, each mesh at its phase"
              + (" (paper: the sun meshes of case 1 oscillate between 0.8e8 and 1.3e8 N/m, "
                 "those of case 2 much less)." if paper else "."),
              figure=lambda: mesh_stiffness_figure(cases)),
        _table("Summed mesh stiffness per central gear",
               ("case", "central gear", "mesh frequency", "min [N/m]", "max [N/m]",
                "peak-to-peak [N/m]", "source"),
               [(ca.name, st.central, st.group, f"{st.minimum:.4g}", f"{st.maximum:.4g}",
                 f"{st.peak_to_peak:.4g}", st.source)
                for ca in cases for st in ca.stiffness])]
    for cmp in comparisons:
        s["comparison"] += [
            Block("heading", f"{cmp.other} against {cmp.reference}"),
            Block("text", cmp.verdict),
            *[Block("text", e) for e in cmp.explanation]]
        if cmp.claims:
            s["comparison"] += [_table(
                "Statements of the paper", ("statement", "reproduced", "evidence"),
                [(c[0], "n/a" if c[1] is None else ("yes" if c[1] else "no"), c[2])
                 for c in cmp.claims])]
        s["comparison"] += [
            _table(f"Resonance regions ({cmp.signal}), matched by speed",
                   ("status", f"{cmp.reference} speeds", f"{cmp.reference} rise dB (rises)",
                    f"{cmp.other} speeds", f"{cmp.other} rise dB (rises)", "Δ dB",
                    "mechanisms (rises)"), [c.row() for c in cmp.regions]),
            _table("Floquet unstable intervals, matched by overlap",
                   ("status", f"{cmp.reference} [min⁻¹] (width)",
                    f"{cmp.other} [min⁻¹] (width)", f"{cmp.reference} candidate",
                    f"{cmp.other} candidate"),
                   [c.row() for c in cmp.floquet]),
            _table("Natural frequencies", ("mode", f"{cmp.reference} [Hz]", f"{cmp.other} [Hz]",
                                           "change"),
                   [(n, f"{a:.1f}", f"{b:.1f}", f"{100 * (b - a) / a:+.1f} %")
                    for n, a, b in cmp.natural_frequencies])]
    for i, ca in enumerate(cases):
        s[LEVELS_SECTION_ID] += levels_blocks(ca.levels, heading=several_cases,
                                              explain_resonances=i == 0)
    s[SUMMARY_ID] = summary_blocks([case_summary(ca) for ca in cases],
                                   inputs=inputs_rows(cases))
    return [Section(k, TITLES[k], tuple(s[k]), front=k == SUMMARY_ID) for k in SECTION_IDS
            if k != "comparison" or (len(cases) >= 2 and s[k])]


def case_summary(ca: CaseAnalysis) -> CaseSummary:
    """The summary of one simulated case: key numbers, its signals' levels, and the tooth-force
    rise table as the explanation of the strongest cut resonances."""
    lo, hi = ca.speed_range
    fmax = ca.frequency_max_hz
    key = [("run", ca.run_text())]
    for g in ca.groups:
        key.append((f"mesh frequency{'' if len(ca.groups) == 1 else f' ({g.name})'}",
                    f"{span(g.frequency_per_rpm * lo, g.frequency_per_rpm * hi, 'Hz')} (order "
                    f"{g.order:.4g} of the input shaft)"))
    f_m, n_m = merged_modes(ca.natural_frequencies_hz, ca.mode_names)
    fn = [(n, f) for n, f in zip(n_m, f_m, strict=True) if f <= fmax]
    key.append((f"natural frequencies up to {fmax:.0f} Hz",
                ", ".join(f"{n} {f:.0f} Hz" for n, f in fn[:8])
                + (f" and {len(fn) - 8} more" if len(fn) > 8 else "") or "none"))
    key.append((f"rises of the sonogram (tooth force {ca.force_mesh})",
                f"{count(len(ca.resonances), 'rise')} in "
                f"{count(len(ca.regions), 'speed region')}"))
    key.append(("Floquet-unstable speed intervals",
                str(len(ca.floquet_regions())) if ca.chart is not None else "not computed"))
    primary = next((sl for sl in ca.levels if sl.primary and sl.levels is not None), None)

    def explain(rank: int) -> RiseMatch | None:
        if primary is None:
            return None
        return rise_explanation(ca.resonances, primary, rank, rpm_tolerance=0.03 * hi,
                                source=f"tooth force {ca.force_mesh}")

    return CaseSummary(ca.name, key, list(ca.levels), explain, mode_descriptions(ca.modes))


def inputs_rows(cases: Sequence[CaseAnalysis]) -> list[tuple[str, str]]:
    """Version, inputs (each case with its run) and the analysis settings, readable."""
    from gearvib import __version__

    rows = [("gearvib version (report)", __version__)]
    versions = {str(ca.dataset.attrs.get("gearvib_version", "")) for ca in cases} - {""}
    if versions:
        rows.append(("gearvib version (runs)", ", ".join(sorted(versions))))
    for ca in cases:
        label = "" if ca.label in ("", ca.name) else f" ({ca.label})"
        rows.append((f"case {ca.name}", f"{ca.name}{label}: {ca.run_text()}"))
    if len({repr(ca.settings) for ca in cases}) == 1:
        rows.append(("analysis settings", settings_summary(cases[0].settings)))
    else:
        rows += [(f"analysis settings of {ca.name}", settings_summary(ca.settings))
                 for ca in cases]
    rows.append(("details", "every setting, hash and sample rate: section Provenance"))
    return rows
