"""Report of a diagnosis: ``report.html``, ``report.pdf`` and ``diagnosis.nc``.

Sections: the verdict (ranked causes with their scores against the threshold), the evidence
(measured differences against the simulated signatures of the leading causes, the spectrum
around the first mesh harmonic with the leading cause's lines, catalogue families with their
coincidence chances, order locking and modes), what to measure next, provenance.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from analysis.diagnosis import Diagnosis, prominence_db
from gearvib.diagnosis.bearings import BEARING_CAUSES
from gearvib.fault_lines import FaultLines
from gearvib.io import atomic_write, write_netcdf
from gearvib.report.bearings import ENVELOPE_HEADER, envelope_rows, summary
from gearvib.report.document import FigureImages
from gearvib.report.html import render_html
from gearvib.report.pdf import write_pdf
from gearvib.report.sections import Block, Section

__all__ = [
    "REPORT_FILES",
    "DiagnosisPaths",
    "scores_figure",
    "spectrum_figure",
    "write_diagnosis_report",
]

REPORT_FILES = ("report.html", "report.pdf", "diagnosis.nc")
"""Files a diagnosis writes into its output folder."""


@dataclass(frozen=True)
class DiagnosisPaths:
    """Where a diagnosis report went."""

    html: Path
    pdf: Path
    dataset: Path


def scores_figure(d: Diagnosis, *, figsize: tuple[float, float] = (8.0, 4.2)) -> Figure:
    """Horizontal bars of every candidate's score with the threshold."""
    fig = Figure(figsize=figsize, layout="constrained")
    ax = fig.subplots()
    cs = [c for c in d.causes if c.cause != "none"][::-1]
    y = np.arange(len(cs))
    colors = [{"likely": "tab:red", "possible": "tab:orange"}.get(c.verdict, "tab:gray")
              for c in cs]
    ax.barh(y, [c.score for c in cs], color=colors)
    ax.set_yticks(y, [f"{c.cause} ({c.member})" for c in cs], fontsize=8)
    ax.axvline(d.threshold, color="k", ls="--", lw=1.0)
    ax.text(d.threshold, len(cs) - 0.4, f" threshold {d.threshold:.2f}", fontsize=8,
            va="bottom")
    ax.set_xlim(0, 1)
    ax.set_ylim(-0.6, len(cs) + 0.2)
    ax.set_xlabel("score (simulated faults: how well the signature explains the measured "
                  "difference;\nbearings: how unlikely their lines are by chance)"
                  if any(c.cause in BEARING_CAUSES.values() for c in cs) else
                  "score (how well the simulated fault explains the measured difference)")
    return fig


def spectrum_figure(d: Diagnosis, *, figsize: tuple[float, float] = (9.0, 5.0)) -> Figure:
    """Measured and baseline prominence around the mesh harmonic with the strongest measured
    rises; the rises the leading cause's simulation shares are marked."""
    fig = Figure(figsize=figsize, layout="constrained")
    ax = fig.subplots()
    mesh = float(d.attrs.get("mesh_order", 0.0)) or float(d.order[-1]) / 5.5
    rise = np.clip(d.measured_diff - d.deadband, 0.0, None)
    n_h = max(1, int(d.order[-1] // mesh))
    sums = [float(rise[np.abs(d.order - m * mesh) <= 20.0].sum()) for m in range(1, n_h + 1)]
    centre = mesh * (1 + int(np.argmax(sums)))
    lo, hi = max(0.0, centre - 20.0), centre + 20.0
    sel = (d.order >= lo) & (d.order <= hi)
    pm, pb = prominence_db(d.measured), prominence_db(d.baseline)
    ax.plot(d.order[sel], pb[sel], color="tab:gray", lw=0.8, label="healthy baseline")
    ax.plot(d.order[sel], pm[sel], color="k", lw=0.8, label="measured")
    top = next((c for c in d.causes if c.cause != "none"), None)
    if top is not None and top.variant in d.signatures:
        sig = d.signatures[top.variant]
        mark = sel & (sig > 3.0) & (d.measured_diff > d.deadband)
        ax.plot(d.order[mark], pm[mark] + 1.5, "v", color="tab:red", ms=4,
                label=f"measured rises where simulated {top.variant} rises")
    ax.set_xlim(lo, hi)
    ax.set_xlabel(f"order of the {d.reference}")
    ax.set_ylabel("prominence above the local floor [dB]")
    ax.set_title(f"around mesh harmonic {round(centre / mesh)} (order {centre:g}), where the "
                 "measured rises are strongest", fontsize=9)
    ax.legend(loc="upper left", fontsize=8)
    return fig


def _what(c) -> str:
    """A cause in words: ``crack on sun``, ``local tooth fault on sun``."""
    return f"{c.cause.replace('_', ' ')} on {c.member}"


def _sections(d: Diagnosis, title_name: str) -> list[Section]:
    likely = d.likely
    lead = d.causes[0] if d.causes else None
    if likely:
        assert lead is not None  # the likely causes are among the causes
        verdict = (f"{len(likely)} cause(s) above the threshold {d.threshold:.2f}; the most "
                   f"likely is {_what(lead)} (score {lead.score:.2f}).")
        members = {c.member for c in likely}
        kinds = [c for c in likely if c.cause != "local_tooth_fault"]
        if len(kinds) > 1 and len(members) == 1:
            gap = kinds[0].score - kinds[1].score
            verdict += (f" All likely causes are on {lead.member}: the member is clear, "
                        + ("the kind less so (see What to measure next)." if gap < 0.1 else
                           f"and {kinds[0].cause} leads {kinds[1].cause} by {gap:.2f}."))
    elif lead is not None and lead.verdict == "possible":
        verdict = (f"Possible: {_what(lead)} (score {lead.score:.2f}, below the threshold "
                   f"{d.threshold:.2f}; {lead.evidence[-1] if lead.evidence else ''}). "
                   "Nothing is likely; see What to measure next.")
    elif not d.signatures:
        verdict = ("Nothing stands out: no fault family of the declared rolling bearings is "
                   "detected in the envelope spectrum.")
    else:
        best = next((c for c in d.causes if c.cause != "none"), None)
        verdict = ("Nothing stands out: no candidate explains the measured differences (best "
                   f"score {best.score if best else 0.0:.2f} below the threshold "
                   f"{d.threshold:.2f}) and no fault family carries the measured rises.")
    rows = tuple((str(i + 1), c.cause, c.member or "-", f"{c.score:.2f}",
                  "" if c.verdict == "unlikely" else c.verdict,
                  " | ".join(c.evidence)) for i, c in enumerate(d.causes))
    verdict_blocks = (
        Block("text", verdict),
        Block("table", "Ranked causes (score in [0, 1]; likely at or above the threshold, "
              "possible near it or where the fault family carries the measured rises)",
              ("rank", "cause", "member", "score", "", "evidence"), rows),
        Block("figure", "Scores of the candidate causes; red: likely (above the threshold, "
              "dashed), orange: possible.",
              figure=lambda: scores_figure(d)),
    )
    if not d.signatures:  # nothing simulated (a machine without gears)
        evidence: tuple[Block, ...] = tuple(Block("text", n) for n in d.notes)
    else:
        evidence = _simulation_evidence(d)
    nxt = (tuple(Block("text", f"• {s}") for s in d.next_steps) if d.next_steps else
           (Block("text", "The evidence is clear; no further measurement is needed for the "
                  "ranking."),))
    prov = tuple(Block("text", f"{k}: {v}") for k, v in sorted(d.attrs.items())
                 if k not in ("candidates_json",))
    sections = [Section("verdict", f"Diagnosis of {title_name}", verdict_blocks),
                Section("evidence", "Evidence", evidence)]
    if d.line_check is not None:
        sections.append(Section("bearings", "Rolling bearings: their lines in the envelope "
                                "spectrum", _bearing_blocks(d.line_check, title_name)))
    return [*sections, Section("next", "What to measure next", nxt),
            Section("provenance", "Provenance", prov)]


def _bearing_blocks(fl: FaultLines, name: str) -> tuple[Block, ...]:
    """The declared bearings' families in the envelope spectrum: sentences, figure, table."""
    from analysis.envelope_plots import line_evidence_figure

    b = fl.envelope.band
    unit = "Hz" if fl.domain == "frequency" else "orders"

    def figure() -> Figure:
        fig = Figure(figsize=(8.0, 5.0), layout="constrained", dpi=100)
        line_evidence_figure(fl.envelope_evidence, ax=fig.add_subplot(),
                             title=f"{name}: squared envelope spectrum, band {b.low:.5g}-"
                             f"{b.high:.5g} Hz")
        return fig

    rows = tuple(tuple(str(c) for c in r) for r in envelope_rows(fl))
    return (Block("text", summary(fl, name)),
            Block("figure", f"{name}: squared envelope {'order ' if unit == 'orders' else ''}"
                  "spectrum with the declared bearings' fault families (dashed: their "
                  "harmonics; triangles: harmonics found, dots: sidebands found).",
                  figure=figure),
            Block("table", f"Bearing fault families in the squared envelope spectrum (axis: "
                  f"{unit}); a family detected here makes its fault likely", ENVELOPE_HEADER,
                  rows),
            *(Block("text", f"Note: {t}") for t in fl.notes))


def _simulation_evidence(d: Diagnosis) -> tuple[Block, ...]:
    """Evidence of the simulated causes: differences, spectrum, families, notes."""
    fam_rows = tuple((f.family, f"{f.fundamental:.4g}", str(f.hits), str(f.rising),
                      f"{f.coverage:.3f}", f"{f.chance:.2g}") for f in d.families)
    evidence = (
        Block("figure", "Top: measured minus baseline prominence per order bin (dashed: "
              "noise deadband). Below: the same difference simulated for the leading "
              "causes (fault minus healthy). A cause explains the measurement when its rises "
              "stand at the same orders.", figure=lambda: d.plot(top=3)),
        Block("figure", "Measured and baseline spectra around the mesh harmonic with the "
              "strongest measured rises; triangles mark measured rises at orders where the "
              "leading cause's simulation rises too.",
              figure=lambda: spectrum_figure(d)),
        Block("table", "Catalogue families of the measured rises: a family's lines are its "
              "harmonics and its sidebands around the mesh harmonics; the chance is that of "
              "as many hits by coincidence", ("family", "order", "hits", "rising peaks",
                                               "coverage", "chance"), fam_rows),
        *[Block("text", n) for n in d.notes],
    )
    return evidence


def write_diagnosis_report(d: Diagnosis, out_dir: str | os.PathLike, *,
                           name: str = "the measurement") -> DiagnosisPaths:
    """Write ``report.html``, ``report.pdf`` and ``diagnosis.nc`` into ``out_dir`` (atomically;
    the caller checks the outputs first, :func:`gearvib.outputs.check_output_folder`)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    sections = _sections(d, name)
    title = f"Fault-cause diagnosis of {name}"
    subtitle = (f"Baseline: {d.attrs.get('baseline', '?')}; gear set "
                f"{d.attrs.get('gear_set', '?')}; threshold {d.threshold:.2f}.")
    images = FigureImages()
    text = render_html(sections, title=title, subtitle=subtitle, images=images)
    nc = write_netcdf(d.to_dataset(), out / "diagnosis.nc")
    atomic_write(out / "report.pdf", lambda tmp: write_pdf(sections, tmp, title=title,
                                                          subtitle=subtitle, images=images))
    atomic_write(out / "report.html", lambda tmp: tmp.write_text(text, encoding="utf-8"))
    return DiagnosisPaths(out / "report.html", out / "report.pdf", nc)
