"""The report content of one run: :class:`CaseAnalysis` (computed by
:func:`gearvib.report.case.analyse_case`).

Figures (:mod:`gearvib.report.figures`) and the document (:mod:`gearvib.report.sections`) only
read this object: every quantity the report states is computed once, and every table that
shows it reads the same value. :func:`key_speed_rows` reads the mesh frequency at the paper's
reference speeds (:data:`PAPER_SPEEDS_RPM`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import xarray as xr

from analysis.instability import Candidates, Resonances, label_peaks
from analysis.maps import RpmFrequencyMap, RpmOrderMap
from analysis.runup import MapFeatures
from gearvib.modal import ModalResult
from gearvib.model import AssembledModel
from gearvib.report.case_groups import MeshGroup
from gearvib.report.case_run import run_description
from gearvib.report.case_spectra import ForceSpectrum
from gearvib.report.case_stability import candidate_mechanism
from gearvib.report.case_stiffness import SummedStiffness
from gearvib.report.nvh import SignalLevels
from gearvib.report.rises import ResonanceRegion, crossing_table_rows, rise_table_rows
from gearvib.report.study import AnalysisSettings
from gearvib.report.wording import span

if TYPE_CHECKING:
    from analysis.instability import StabilityChart

__all__ = ["MARKER_BUDGET", "PAPER_SPEEDS_RPM", "CaseAnalysis", "key_speed_rows"]


PAPER_SPEEDS_RPM = (1500.0, 2600.0, 3100.0)
"""Sun speeds at which the paper reads resonances off Figure 11 (case 1) [min^-1]."""

MARKER_BUDGET = 30
"""At most this many rises are marked on a sonogram (the strongest explained ones)."""


@dataclass
class CaseAnalysis:
    """Everything the report shows about one run (plain data; see :func:`analyse_case`).

    Attributes
    ----------
    name, label : str
        Case name and display label.
    dataset : xarray.Dataset
        The run.
    config : dict
        Parsed ``config_json`` attribute (``{}`` if missing).
    model : AssembledModel or None
        Rebuilt gear set (None when the Dataset does not carry the description).
    modal : ModalResult or None
        Modes of the mean system.
    natural_frequencies_hz : ndarray
        Elastic natural frequencies [Hz].
    mode_names : list of str
        Their names (``f2, f3, ...``: mode 1 is the rigid-body rotation, as in the paper).
    mesh_frequency_per_rpm : float
        The reference (first) mesh frequency per input speed [Hz per min^-1] (paper eq. 5).
    groups : list of MeshGroup
        Every mesh frequency with its meshes, central gears and orders, reference first.
    parameters : list of (str, str)
        Gear-set and run parameters.
    modes : list of tuple
        ``(mode, f [Hz], kind, multiplicity, dominant mesh)`` rows.
    force_mesh : str
        Mesh of the sonogram and resonance table.
    force_meshes : list of (str, tuple of str)
        Per group, the meshes whose forces are drawn (those of its first central gear).
    spectra : list of ForceSpectrum
        Tooth-force spectra (the first mesh of every central gear, at most four).
    stiffness : list of SummedStiffness
        Summed mesh stiffness of every central gear (at most four).
    fmap : RpmFrequencyMap
        Sonogram of the tooth force of ``force_mesh``.
    omap : RpmOrderMap or None
        Rpm-order map of the same force (None if the speed range is too short).
    frequency_max_hz : float
        Upper frequency of spectra and sonogram.
    resonances : Resonances
        Rises detected in ``fmap``, classified against the orders of their own mesh frequency.
    planet_resonances : Resonances or None
        Rises of the difference of the first two sun-mesh forces (only the planet modes), when
        a Floquet-unstable band grows by at least 40 dB in the run.
    features : MapFeatures or None
        Order-locked rays and frequency-locked lines of the sonogram.
    regions : list of ResonanceRegion
        The rises grouped into speed regions.
    candidates : Candidates
        Theory candidates shown: order ``n <= n_max`` in the run's speed range, plus every
        candidate a Floquet region is attributed to (rows of the same table as the chart's).
    chart : StabilityChart or None
        Floquet stability over speed.
    run : dict
        Run settings (drive, speed range, duration, torque or motor, fs_out).
    settings : AnalysisSettings
        Analysis settings used.
    notes : list of str
        Remarks (e.g. why a chart is missing).
    provenance : list of (str, str)
        Version, hashes, step, sample rate, analysis times (no dates).
    first_order : list of tuple of str
        First-order (Hsu) region rows.
    paper_set : bool
        The paper's gear set (z_s = 33, z_r = -114, three planets): paper-specific statements
        apply.
    stability_time_s : float
        Wall time of the Floquet chart [s] (0 without one).
    levels : list of SignalLevels
        Order cuts, overall level, waterfall and Campbell data of the housing acceleration of
        every ``[[sensor]]`` (at most :data:`MAX_SENSORS`, the first one primary) and of the
        tooth force of ``force_mesh`` (primary when there is no sensor).
    """

    name: str
    label: str
    dataset: xr.Dataset
    config: dict
    model: AssembledModel | None
    modal: ModalResult | None
    natural_frequencies_hz: np.ndarray
    mode_names: list[str]
    mesh_frequency_per_rpm: float
    groups: list[MeshGroup]
    parameters: list[tuple[str, str]]
    modes: list[tuple]
    force_mesh: str
    force_meshes: list[tuple[str, tuple[str, ...]]]
    spectra: list[ForceSpectrum]
    stiffness: list[SummedStiffness]
    fmap: RpmFrequencyMap
    omap: RpmOrderMap | None
    frequency_max_hz: float
    resonances: Resonances
    regions: list[ResonanceRegion]
    candidates: Candidates
    chart: StabilityChart | None
    run: dict
    settings: AnalysisSettings
    notes: list[str] = field(default_factory=list)
    provenance: list[tuple[str, str]] = field(default_factory=list)
    first_order: list[tuple[str, ...]] = field(default_factory=list)
    planet_resonances: Resonances | None = None
    features: MapFeatures | None = None
    paper_set: bool = False
    stability_time_s: float = 0.0
    levels: list[SignalLevels] = field(default_factory=list)

    # ------------------------------------------------------------------ basic quantities

    @property
    def several_mesh_frequencies(self) -> bool:
        """True when the gear set has more than one mesh frequency."""
        return len(self.groups) > 1

    @property
    def mesh_frequencies(self) -> list[tuple[str, float]]:
        """``(name, Hz per min^-1)`` of every mesh frequency, reference first."""
        return [(g.name, g.frequency_per_rpm) for g in self.groups]

    @property
    def speed_range(self) -> tuple[float, float]:
        """Smallest and largest input speed of the run [min^-1]."""
        v = np.abs(self.dataset["input_speed"].values)
        return float(v.min()), float(v.max())

    @property
    def sun_meshes(self) -> tuple[str, ...]:
        """Meshes of the first central gear of the reference group (the sun of a simple set)."""
        return self.force_meshes[0][1] if self.force_meshes else ()

    @property
    def main_stiffness(self) -> SummedStiffness | None:
        """Summed stiffness of the first central gear of the reference group (the sun)."""
        return self.stiffness[0] if self.stiffness else None

    def mesh_frequency_at(self, rpm: float) -> float:
        """Reference mesh frequency at an input speed [Hz]."""
        return self.mesh_frequency_per_rpm * rpm

    def group_frequencies_text(self, f_ref_lo: float, f_ref_hi: float) -> str:
        """A reference mesh-frequency interval [Hz] in every mesh frequency, as text."""
        if not self.several_mesh_frequencies:
            return f"{f_ref_lo:.1f}–{f_ref_hi:.1f}"
        ref = self.mesh_frequency_per_rpm
        return "; ".join(f"{g.name}: {f_ref_lo * g.frequency_per_rpm / ref:.1f}–"
                         f"{f_ref_hi * g.frequency_per_rpm / ref:.1f}" for g in self.groups)

    # ------------------------------------------------------------------ table rows

    def resonance_rows(self, planet: bool = False) -> list[tuple[str, ...]]:
        """Rows of a rise table (see :data:`RISE_HEADER`).

        Parameters
        ----------
        planet : bool
            Rows of the planet-mode signal instead of the tooth force.
        """
        r = self.planet_resonances if planet else self.resonances
        if r is None:
            return []
        groups = r.groups
        short = {g.name: g.short for g in self.groups}
        return rise_table_rows(r, lambda i: f"k={r.order[i]}" + (
            f" ({short.get(str(groups[i]), groups[i])})" if groups[i] else ""))

    def region_table_rows(self) -> list[tuple[str, ...]]:
        """Rows of the resonance-region table (the same summary the comparison shows)."""
        return [r.table_row() for r in self.regions]

    def peak_rows(self) -> list[tuple[str, ...]]:
        """Rows of the identified-peak table (at most two expressions per peak)."""
        rows: list[tuple[str, ...]] = []
        for fsp in self.spectra:
            lab = fsp.labels
            for i in range(len(fsp.peaks)):
                best = lab.matches[i][0] if i < len(lab) and lab.matches[i] else None
                chance = f"{100 * lab.coincidence[i]:.0f} %" if i < len(lab) else "–"
                rows.append((fsp.mesh, fsp.short_label(i),
                             f"{best.deviation:+.0f}" if best else "–",
                             f"± {best.tolerance:.0f}" if best else "–", chance))
        return rows

    def crossing_rows(self) -> list[tuple[str, ...]]:
        """Predicted crossings of the mesh orders with the natural frequencies."""
        several = self.several_mesh_frequencies
        return crossing_table_rows(self.resonances.crossings, lambda c: (
            f"{c.harmonic} × f_mesh = {c.mode}" + (f" [{c.group}]" if several and c.group
                                                   else "")))

    def growth_rows(self) -> list[tuple[str, ...]]:
        """Growth of every Floquet-unstable band during this run."""
        g = self.resonances.growth
        if g is None:
            return []
        return [(span(g.lower_rpm[i], g.upper_rpm[i]), str(g.label[i]) or "unattributed",
                 f"{1e3 * g.time_in_band[i]:.1f}", f"{g.peak_growth_rate[i]:.3g}",
                 f"{g.growth_db[i]:.1f}",
                 "develops" if g.can_grow[i] else f"too fast: {g.advice[i]}")
                for i in range(len(g))]

    def floquet_regions(self) -> list[dict]:
        """The chart's unstable intervals with their speeds and attribution (``[]`` if none).

        Every table and figure that shows a Floquet region reads these dicts: ``lower_rpm``,
        ``upper_rpm``, ``label`` (``""`` when unattributed), ``candidate`` (row index in
        :attr:`candidates`, -1 if none), ``evidence``, ``growth``, ``lower_open``,
        ``upper_open``, ``lower_hz``, ``upper_hz``.
        """
        if self.chart is None:
            return []
        f = self.mesh_frequency_per_rpm
        out = []
        for reg in self.chart.region_table:
            label = str(reg["candidate"])
            idx = -1
            if label:
                hits = [i for i in range(len(self.candidates))
                        if self.candidates.full_label(i) == label]
                idx = hits[0] if hits else -1
            out.append({"lower_rpm": reg["lower"] / f, "upper_rpm": reg["upper"] / f,
                        "lower_hz": reg["lower"], "upper_hz": reg["upper"], "label": label,
                        "candidate": idx, "evidence": str(reg.get("evidence", "")),
                        "growth": float(reg["peak_growth_rate"]),
                        "lower_open": bool(reg["lower_open"]),
                        "upper_open": bool(reg["upper_open"])})
        return out

    def region_rows(self) -> list[tuple[str, ...]]:
        """Rows of the Floquet region table (formatted strings)."""
        rows: list[tuple[str, ...]] = []
        for r in self.floquet_regions():
            lo_s, hi_s = r["lower_rpm"], r["upper_rpm"]
            rows.append((f"{'≤ ' if r['lower_open'] else ''}{lo_s:.0f}",
                         f"{hi_s:.0f}{' ≥' if r['upper_open'] else ''}", f"{hi_s - lo_s:.1f}",
                         self.group_frequencies_text(r["lower_hz"], r["upper_hz"]),
                         f"{r['growth']:.3g}", r["label"] or "unattributed",
                         candidate_mechanism(r["candidate"], self.candidates), r["evidence"]))
        return rows

    def candidate_rows(self) -> list[tuple[str, ...]]:
        """Rows of the theory-candidate table."""
        c = self.candidates
        attributed = {r["candidate"] for r in self.floquet_regions()}
        return [(f"{c.rpm[i]:.0f}", f"{c.f_mesh_hz[i]:.1f}", str(c.kind[i]), str(c.n[i]),
                 c.full_label(i), "yes" if c.allowed[i] else f"no: {c.reason[i]}",
                 "yes" if i in attributed else "")
                for i in range(len(c))]

    def run_text(self) -> str:
        """The run in one line, after its drive (speed ramp, torque, motor)."""
        return run_description(self.run, self.dataset)


def key_speed_rows(ca: CaseAnalysis) -> list[tuple[str, str, str]]:
    """Mesh frequency at the paper's reference speeds, with the nearest theory expressions.

    Only for the paper's gear set (:attr:`CaseAnalysis.paper_set`; ``[]`` otherwise): the rows
    reproduce how the paper reads Figure 11 (``"1500 min⁻¹", "640 Hz", "f_mesh ≈ f2/2 (631 Hz,
    +1 %)"``), for the speeds of :data:`PAPER_SPEEDS_RPM` inside the run's speed range.
    """
    if not ca.paper_set:
        return []
    lo, hi = ca.speed_range
    rows = []
    for rpm in PAPER_SPEEDS_RPM:
        if not lo <= rpm <= hi:
            continue
        fm = ca.mesh_frequency_per_rpm * rpm
        lab = label_peaks([fm], ca.natural_frequencies_hz, n_max=6, tolerance=0.1,
                          names=ca.mode_names) if ca.natural_frequencies_hz.size else None
        text = "–"
        if lab is not None and lab.matches[0]:
            best = sorted(lab.matches[0], key=lambda m: m.relative_error)[:2]
            text = " ; ".join(f"f_mesh ≈ {m.expression} ({m.value_hz:.0f} Hz, "
                              f"{100 * m.relative_error:+.0f} %)".replace("+-", "-")
                              for m in best)
        rows.append((f"{rpm:.0f} min⁻¹", f"{fm:.0f} Hz", text))
    return rows
