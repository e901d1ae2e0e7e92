"""Report content of one run, computed once (:func:`analyse_case` -> :class:`CaseAnalysis`).

:func:`analyse_case` turns a run-up Dataset (written by :func:`gearvib.simulate.simulate`
through :func:`gearvib.report.runner.run_study`) into plain data: the gear-set parameters, the
modes, the tooth forces (paper Figure 7), labelled spectra (Figure 8), the summed mesh
stiffness of every central gear (Figures 9 and 10), the rpm-frequency and rpm-order maps of a
tooth force (Figure 11), the detected resonances, the Floquet stability chart with its theory
candidates, and the provenance. Figures (:mod:`gearvib.report.figures`) and the document
(:mod:`gearvib.report.sections`) only read this object: every quantity the report states is
computed here once, and every table that shows it reads the same value.

Every gear-set type is described by its **mesh-frequency groups** (:class:`MeshGroup`: one for
a simple or Ravigneaux set, one per stage of a two-stage set, one per planet toothing of a
Wolfrom set), each with its central gears and their meshes. Tooth forces, spectra and summed
stiffnesses are given per group and central gear; order lines and resonance classification
use every group's own mesh orders; the Floquet chart runs over the common period of all of
them. Statements about the paper's example appear only for the paper's gear set (z_s = 33,
z_r = -114, three planets; :attr:`CaseAnalysis.paper_set`).

The gear set is rebuilt from the ``config_json`` attribute of the Dataset (its ``"gearset"``
entry). If that is missing, the analysis falls back to what the Dataset holds: the stored
natural frequencies, the mesh frequencies per speed from ``mesh_frequency(mesh, time)`` and
``input_speed``, and the simulated ``mesh_stiffness``; the stability chart and the mode types
are then not available, and the report says so.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from analysis.identification import peak_half_widths
from analysis.instability import (
    FORCED,
    PARAMETRIC,
    UNEXPLAINED,
    Candidates,
    Crossing,
    PeakLabels,
    Resonances,
    detect_resonances,
    instability_candidates,
    label_peaks,
    merge_mesh_frequencies,
)
from analysis.maps import RpmFrequencyMap, RpmOrderMap, rpm_frequency_map, rpm_order_map
from analysis.runup import MapFeatures, map_features
from analysis.spectrum import Peaks, Spectrum, find_peaks, spectrum, to_db
from gearvib.assembly import assemble
from gearvib.config import config_hash, gearset_from_dict
from gearvib.modal import ModalResult, modal_analysis
from gearvib.model import AssembledModel
from gearvib.report.study import AnalysisSettings
from gearvib.report.wording import count
from gearvib.simulation.conditions import DriveCoupling
from gearvib.stability import (
    ATTRIBUTION_N_MAX,
    CHART_ACCURACY,
    cycle_budget,
    first_order_regions,
    gear_set_candidates,
    mesh_phasing,
    stability_over_speed,
)

if TYPE_CHECKING:
    from analysis.instability import StabilityChart

__all__ = [
    "MARKER_BUDGET",
    "PAPER_SPEEDS_RPM",
    "PLANET_SIGNAL_GROWTH_DB",
    "REGION_HEADER",
    "RISE_HEADER",
    "SPOT_RANGE_DB",
    "CaseAnalysis",
    "ForceSpectrum",
    "MeshGroup",
    "ResonanceRegion",
    "SummedStiffness",
    "analyse_case",
    "crossing_table_rows",
    "key_speed_rows",
    "resonance_regions",
    "rise_table_rows",
    "run_description",
    "signed_force",
    "summed_stiffness",
    "summed_sun_stiffness",
]

PAPER_SPEEDS_RPM = (1500.0, 2600.0, 3100.0)
"""Sun speeds at which the paper reads resonances off Figure 11 (case 1) [min^-1]."""

RISE_HEADER = ("speed", "f [Hz]", "on", "rise [dB]", "mechanism: cause", "chance", "evidence")
"""Columns of the tables of classified rises (rows: :func:`rise_table_rows`)."""

REGION_HEADER = ("speed [min⁻¹]", "peak speed", "f [Hz]", "rise [dB]", "rises",
                 "mechanisms (rises)")
"""Columns of the resonance-region tables (rows: :meth:`ResonanceRegion.table_row`)."""

STABILITY_MODES = {
    "full": {"points": None, "floquet": CHART_ACCURACY, "xtol_rel": 1e-8},
    "coarse": {"points": 80, "floquet": {"multiplier_atol": 1e-6, "unity_margin": 0.03},
               "xtol_rel": 1e-6},
}
"""Floquet chart settings per ``[analysis] stability`` value (``"off"``: no chart)."""

MARKER_BUDGET = 30
"""At most this many rises are marked on a sonogram (the strongest explained ones)."""

AUTO_ORDERS = (7, 20)
"""``orders = 0``: per mesh frequency, enough mesh orders to reach the highest natural frequency
in the map at the top speed, at least 7 and at most 20."""

_STIFFNESS_CYCLES = 3
# the planet-mode signal (difference of two planets' sun-mesh forces) of a symmetric simulation
# starts at round-off; it is analysed only when a Floquet band lets it grow by this much
PLANET_SIGNAL_GROWTH_DB = 40.0
SPOT_RANGE_DB = 40.0  # rises more than this below the map maximum are background clutter
_MIN_SPOT_FRACTION = 0.15  # spots below 0.15 x the lowest natural frequency: near-DC content
_REGION_GAP = 0.03  # spots closer than 3 % of the top speed belong to one resonance region
_RPM_MIN_FRACTION = 0.02  # order tracking needs rpm > 0: skip the first 2 % of the speed range
_MAX_PANELS = 4  # spectra and stiffness panels per case


# --------------------------------------------------------------------------- data containers


@dataclass(frozen=True)
class MeshGroup:
    """Meshes that share one mesh frequency, with their central gears.

    Attributes
    ----------
    name : str
        ``"mesh"`` for a set with one mesh frequency, else e.g. ``"stage 2"``, ``"ring2"``.
    frequency_per_rpm : float
        Mesh frequency per input speed [Hz per min^-1].
    meshes : tuple of str
        Every mesh of the group.
    centrals : tuple of (str, tuple of str)
        Each central gear (sun, ring, ...) with its meshes, in the order of the meshes; meshes
        between two planets belong to none.
    orders : int
        Mesh orders ``1..orders`` drawn and used for the resonance classification.
    """

    name: str
    frequency_per_rpm: float
    meshes: tuple[str, ...]
    centrals: tuple[tuple[str, tuple[str, ...]], ...]
    orders: int = 7

    @property
    def order(self) -> float:
        """Mesh cycles per input revolution."""
        return 60.0 * self.frequency_per_rpm

    @property
    def short(self) -> str:
        """Short name for plot labels (``"stage 2"`` -> ``"s2"``)."""
        return f"s{self.name[6:]}" if self.name.startswith("stage ") else self.name

    def tag(self, several: bool) -> str:
        """``" [stage 2]"`` when the set has several mesh frequencies, else ``""``."""
        return f" [{self.name}]" if several else ""


@dataclass(frozen=True)
class SummedStiffness:
    """Sum of the mesh stiffnesses of one central gear over a few mesh cycles (Figs. 9, 10).

    Attributes
    ----------
    cycles : ndarray
        Mesh position [mesh cycles] (rigid-body rotation from the assembly position).
    total : ndarray
        ``sum_m k_m(s0_m + s)`` over the meshes [N/m].
    per_mesh : ndarray, shape (n_mesh, n)
        The individual mesh stiffnesses [N/m].
    mesh_names : tuple of str
        Names of the summed meshes.
    source : str
        ``"model"`` (stiffness tables with the mesh phases) or ``"simulation"`` (the simulated
        effective stiffness at the lowest speeds, when the model cannot be rebuilt).
    central : str
        The central gear (``"sun"``, ``"s2.ring"``, ...).
    group : str
        Its mesh-frequency group.
    """

    cycles: np.ndarray
    total: np.ndarray
    per_mesh: np.ndarray
    mesh_names: tuple[str, ...]
    source: str
    central: str = "sun"
    group: str = "mesh"

    @property
    def minimum(self) -> float:
        """Smallest summed stiffness [N/m]."""
        return float(self.total.min())

    @property
    def maximum(self) -> float:
        """Largest summed stiffness [N/m]."""
        return float(self.total.max())

    @property
    def peak_to_peak(self) -> float:
        """Fluctuation ``max - min`` [N/m]."""
        return self.maximum - self.minimum


@dataclass(frozen=True)
class ResonanceRegion:
    """Detected rises grouped by speed (one row of the region table).

    Attributes
    ----------
    rpm_low, rpm_high : float
        Speed span of the rises [min^-1].
    rpm_peak : float
        Speed of the strongest rise.
    frequency_hz : float
        Response frequency of the strongest rise [Hz].
    strength_db : float
        Rise of the strongest one above its background [dB].
    n_spots : int
        Number of rises.
    causes : tuple of (str, str, int)
        ``(mechanism, cause, rises)`` for every distinct explanation, strongest first.
    """

    rpm_low: float
    rpm_high: float
    rpm_peak: float
    frequency_hz: float
    strength_db: float
    n_spots: int
    causes: tuple[tuple[str, str, int], ...]

    @property
    def mechanisms(self) -> tuple[str, ...]:
        """Distinct ``"mechanism (cause)"`` texts, strongest first."""
        return tuple(m + (f" ({c})" if c else "") for m, c, _ in self.causes)

    def count(self, mechanism: str) -> int:
        """Rises of one mechanism (``FORCED``, ``PARAMETRIC``, ``UNEXPLAINED``)."""
        return sum(n for m, _, n in self.causes if m == mechanism)

    @property
    def classified(self) -> bool:
        """True if at least one rise is a forced resonance or a parametric instability."""
        return self.count(FORCED) + self.count(PARAMETRIC) > 0

    @property
    def summary(self) -> str:
        """Every explanation with its number of rises, explained ones first:
        ``"forced resonance: 3 f_mesh = f5 (2), 2 f_mesh = f5; unexplained: 1 rise"``."""
        parts = []
        for mech in (FORCED, PARAMETRIC):
            items = [f"{c}" + (f" ({n})" if n > 1 else "") for m, c, n in self.causes
                     if m == mech]
            if items:
                parts.append(f"{mech}: " + ", ".join(items))
        n_un = self.count(UNEXPLAINED)
        if n_un:
            parts.append(f"{UNEXPLAINED}: {count(n_un, 'rise')}")
        return "; ".join(parts)

    def table_row(self) -> tuple[str, ...]:
        """The region as a row of a region table (:data:`REGION_HEADER`)."""
        return (f"{self.rpm_low:.0f}–{self.rpm_high:.0f}", f"{self.rpm_peak:.0f}",
                f"{self.frequency_hz:.0f}", f"{self.strength_db:.1f}", str(self.n_spots),
                self.summary)


def rise_table_rows(res: Resonances, on_order: Callable[[int], str]) -> list[tuple[str, ...]]:
    """Rows of a table of classified rises (:data:`RISE_HEADER`), one a rise.

    Parameters
    ----------
    res : Resonances
        The classified rises.
    on_order : callable
        ``on_order(i)`` writes the "on" column of rise ``i`` when it lies on an order
        (``res.order[i]`` not 0); a rise on a natural frequency reads ``f_i``, on a map spot
        ``spot``.
    """
    feature = {"natural frequency": "f_i", "spot": "spot"}
    rows = []
    for i in range(len(res)):
        on = on_order(i) if res.order[i] else feature.get(str(res.feature[i]), "–")
        rows.append((f"{res.rpm[i]:.0f}", f"{res.frequency[i]:.0f}", on,
                     f"{res.strength_db[i]:.1f}",
                     str(res.mechanism[i]).split()[0]
                     + (f": {res.cause[i]}" if res.cause[i] else ""),
                     f"{100 * res.coincidence[i]:.0f} %", str(res.note[i])))
    return rows


def crossing_table_rows(crossings: Sequence[Crossing], label: Callable[[Crossing], str]
                        ) -> list[tuple[str, ...]]:
    """Rows of a table of predicted crossings: ``label(c)``, natural frequency, speed and what
    was found there (a rise with its strength)."""
    return [(label(c), f"{c.frequency_hz:.0f}", f"{c.rpm:.0f}",
             c.status + (f" ({c.strength_db:.1f} dB)" if c.status == "rise" else ""))
            for c in crossings]


def resonance_regions(res: Resonances, *, rpm_gap: float) -> list[ResonanceRegion]:
    """Group rises into speed regions.

    Rises closer than ``rpm_gap`` join a region; a region spans at most ``4 rpm_gap`` (dense
    clutter must not chain into one region over the whole run-up).

    Parameters
    ----------
    res : Resonances
        Detected rises.
    rpm_gap : float
        Largest speed gap inside one region [min^-1].

    Returns
    -------
    list of ResonanceRegion
        Sorted by speed.
    """
    if not len(res):
        return []
    order = np.argsort(res.rpm, kind="stable")
    groups: list[list[int]] = [[int(order[0])]]
    for i in order[1:]:
        g = groups[-1]
        if res.rpm[i] - res.rpm[g[-1]] <= rpm_gap and res.rpm[i] - res.rpm[g[0]] <= 4 * rpm_gap:
            groups[-1].append(int(i))
        else:
            groups.append([int(i)])
    out = []
    for g in groups:
        idx = np.asarray(g)
        best = int(idx[np.argmax(res.strength_db[idx])])
        causes: dict[tuple[str, str], int] = {}
        for i in idx[np.argsort(res.strength_db[idx], kind="stable")[::-1]]:
            mech = str(res.mechanism[i])
            key = (mech, "" if mech == UNEXPLAINED else str(res.cause[i]))
            causes[key] = causes.get(key, 0) + 1
        out.append(ResonanceRegion(
            rpm_low=float(res.rpm[idx].min()), rpm_high=float(res.rpm[idx].max()),
            rpm_peak=float(res.rpm[best]), frequency_hz=float(res.frequency[best]),
            strength_db=float(res.strength_db[best]), n_spots=idx.size,
            causes=tuple((m, c, n) for (m, c), n in causes.items())))
    return out


@dataclass(frozen=True)
class ForceSpectrum:
    """Spectrum of one tooth force over the whole run-up with labelled peaks (Figure 8).

    Attributes
    ----------
    mesh : str
        Mesh name.
    spectrum : Spectrum
        Peak-scaled, Welch-averaged spectrum of the dynamic part of the force.
    peaks : Peaks
        The strongest peaks.
    labels : PeakLabels
        Theory labels of the peaks (natural-frequency combinations).
    group : str
        Mesh-frequency group of the mesh.
    """

    mesh: str
    spectrum: Spectrum
    peaks: Peaks
    labels: PeakLabels
    group: str = "mesh"

    def short_label(self, i: int, max_matches: int = 2) -> str:
        """The label of peak ``i`` with at most ``max_matches`` expressions (``"(+3 more)"``).

        Expressions of repeated modes (``"(f3 + f5)/4 ≈ (f4 + f5)/4"``) keep their first form.
        """
        lab = self.labels
        head = f"{self.peaks.frequency[i]:.0f} Hz"
        if i >= len(lab) or not lab.matches[i]:
            return f"{head}: unexplained"
        ms = lab.matches[i]
        exprs = [m.expression.split(" ≈ ")[0] for m in ms[:max_matches]]
        extra = len(ms) - max_matches
        more = f" (+{extra} more)" if extra > 0 else ""
        if lab.status[i] == "ambiguous":
            return (f"{head}: ambiguous ({', '.join(exprs)}{more} within ± "
                    f"{ms[0].tolerance:.3g}; chance match {100 * ms[0].coincidence:.0f} %)")
        return " ≈ ".join([head, *exprs]) + more


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
        rows = []
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
        return [(f"{g.lower_rpm[i]:.0f}–{g.upper_rpm[i]:.0f}", str(g.label[i]) or "unattributed",
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
        rows = []
        for r in self.floquet_regions():
            lo_s, hi_s = r["lower_rpm"], r["upper_rpm"]
            rows.append((f"{'≤ ' if r['lower_open'] else ''}{lo_s:.0f}",
                         f"{hi_s:.0f}{' ≥' if r['upper_open'] else ''}", f"{hi_s - lo_s:.1f}",
                         self.group_frequencies_text(r["lower_hz"], r["upper_hz"]),
                         f"{r['growth']:.3g}", r["label"] or "unattributed",
                         _mechanism(r["candidate"], self.candidates), r["evidence"]))
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


def _mechanism(idx: int, cands: Candidates) -> str:
    if idx < 0:
        return "–"
    kind = str(cands.kind[idx])
    return (f"parametric instability, {kind} type, n = {int(cands.n[idx])}"
            if kind in ("principal", "sum") else kind)


def run_description(run: dict, ds: xr.Dataset | None = None) -> str:
    """One line on the run after its drive: ``"speed ramp 0 → 4000 min⁻¹ in 1 s, input torque
    60 N m"``, ``"constant input torque 20 N m for 1 s from 0 min⁻¹ (reached 2873 min⁻¹)"``,
    ``"induction motor (Kloss: ...) for 2 s (reached 1455 min⁻¹)"``."""
    drive = str(run.get("drive", "speed"))
    reached = ""
    if ds is not None and "input_speed" in ds:
        sp = np.abs(np.asarray(ds["input_speed"].values, dtype=float))
        reached = f" (reached {sp.max():.0f} min⁻¹)"
    dur = float(run.get("duration", math.nan))
    load = run.get("load_torque")
    load_text = ""
    if isinstance(load, list | tuple):
        terms = [t for t in (f"{load[0]:g}" if load[0] else "",
                             f"{load[1]:g} ω" if load[1] else "",
                             f"{load[2]:g} ω|ω|" if load[2] else "") if t]
        load_text = (f", load torque {' + '.join(terms) or '0'} N m"
                     + (" (ω output speed [rad/s])" if load[1] or load[2] else ""))
    elif load is not None and drive != "speed":
        load_text = f", load torque {float(load):g} N m"
    if drive == "torque":
        return (f"constant input torque {float(run['input_torque']):g} N m for {dur:g} s from "
                f"{float(run.get('speed_start_rpm', 0.0)):g} min⁻¹{load_text}{reached}")
    if drive == "motor":
        m = run.get("motor") or {}
        if "synchronous_rpm" in m:
            motor = (f"induction motor (Kloss: synchronous {m['synchronous_rpm']:g} min⁻¹, "
                     f"breakdown torque {m['breakdown_torque']:g} N m at slip "
                     f"{m['breakdown_slip']:g})")
        elif m:
            motor = (f"motor characteristic ({len(m.get('speed_rpm', []))} points, "
                     f"{min(m['torque']):g} to {max(m['torque']):g} N m)")
        else:
            motor = "motor"
        return (f"{motor} for {dur:g} s from {float(run.get('speed_start_rpm', 0.0)):g} "
                f"min⁻¹{load_text}{reached}")
    torque = run.get("input_torque")
    tail = (f", input torque {float(torque):g} N m" if torque is not None and
            math.isfinite(float(torque)) else
            (f", load torque {float(load):g} N m" if load is not None else ""))
    return (f"speed ramp {float(run['speed_start_rpm']):g} → {float(run['speed_end_rpm']):g} "
            f"min⁻¹ in {dur:g} s{tail}")


# --------------------------------------------------------------------------- computation


def _config(ds: xr.Dataset) -> dict:
    text = ds.attrs.get("config_json", "")
    if not text:
        return {}
    try:
        cfg = json.loads(text)
    except (TypeError, ValueError):
        return {}
    return cfg if isinstance(cfg, dict) else {}


def _caller_config(cfg: dict) -> dict:
    """The configuration the caller of ``simulate`` passed (``{"gearset", "run", "case"}``)."""
    inner = cfg.get("model", {})
    return inner if isinstance(inner, dict) else {}


def _rebuild(caller: dict) -> tuple[AssembledModel | None, str]:
    gs_cfg = caller.get("gearset")
    if not isinstance(gs_cfg, dict):
        return None, ("the run does not carry its gear-set description (config_json has no "
                      "'gearset' entry); mode types, stiffness tables and the stability chart "
                      "are not available")
    base = caller.get("gearset_dir")
    try:
        gs = gearset_from_dict(gs_cfg, base=Path(base) if base else None)
        return assemble(gs), ""
    except (ValueError, OSError) as exc:
        return None, f"the stored gear-set description could not be rebuilt: {exc}"


def _stage_name(prefix: str) -> str:
    """``"s1"`` (two-stage) and ``"stage1"`` (multi-stage) -> ``"stage 1"``."""
    for head in ("stage", "s"):
        if prefix.startswith(head) and prefix[len(head):].isdigit():
            return f"stage {prefix[len(head):]}"
    return prefix


def _central_of(mesh: str, planets: set[str] | None = None) -> str | None:
    """The central gear of a mesh (``"s1.sun-planet2"`` -> ``"s1.sun"``), None for a mesh
    between two planets."""
    head = mesh.split("-", 1)[0]
    if planets is not None:
        return None if head in planets else head
    return None if head.rsplit(".", 1)[-1].startswith("planet") else head


def _with_centrals(name: str, f: float, meshes: Sequence[str], planets: set[str] | None,
                   gear1: dict[str, str] | None = None) -> MeshGroup:
    centrals: dict[str, list[str]] = {}
    for m in meshes:
        c = (gear1 or {}).get(m) if gear1 else None
        c = c if c and (planets is None or c not in planets) else _central_of(m, planets)
        if c is not None:
            centrals.setdefault(c, []).append(m)
    return MeshGroup(name, float(f), tuple(meshes),
                     tuple((c, tuple(ms)) for c, ms in centrals.items()))


def _model_groups(model: AssembledModel) -> list[MeshGroup]:
    planets = {str(p["name"]) for p in model.meta.get("planets", [])}
    gear1 = {str(d.get("name")): str(d.get("gear1")) for d in model.meta.get("meshes", [])
             if isinstance(d, dict) and d.get("gear1")}
    return [_with_centrals(g.name, g.frequency_per_rpm, g.mesh_names, planets or None, gear1)
            for g in model.mesh_frequency_groups()]


def _stored_groups(ds: xr.Dataset) -> list[MeshGroup]:
    """Mesh-frequency groups from ``mesh_frequency(mesh, time)`` [Hz per min^-1].

    Reads also the single ``mesh_frequency(time)`` of runs written before every mesh had its
    own. Groups are named like :meth:`gearvib.model.AssembledModel.mesh_frequency_groups`
    (stage prefix or numbered).
    """
    fm = np.asarray(ds["mesh_frequency"].values, dtype=float)
    sp = np.abs(np.asarray(ds["input_speed"].values, dtype=float))
    ok = sp > 0.05 * sp.max()
    if not ok.any():
        raise ValueError("the run has no speed > 0: cannot derive the mesh frequency per speed")
    meshes_all = [str(m) for m in ds["mesh"].values]
    if fm.ndim == 1:
        return [_with_centrals("mesh", float(np.median(fm[ok] / sp[ok])), meshes_all, None)]
    meshes = [str(m) for m in ds["mesh_frequency"]["mesh"].values]
    per_mesh = np.median(fm[:, ok] / sp[ok], axis=1)
    groups: list[tuple[float, list[str]]] = []
    for name, f in zip(meshes, per_mesh, strict=True):
        if not (np.isfinite(f) and f > 0):
            continue
        for g in groups:
            if abs(f - g[0]) <= 1e-6 * max(f, g[0]):
                g[1].append(name)
                break
        else:
            groups.append((float(f), [name]))
    if not groups:
        raise ValueError("the run has no mesh with a mesh frequency")
    if len(groups) == 1:
        return [_with_centrals("mesh", groups[0][0], groups[0][1], None)]
    heads = [{m.split(".", 1)[0] for m in g[1]} for g in groups]
    if all(len(h) == 1 and all("." in m for m in g[1]) for h, g in zip(heads, groups,
                                                                      strict=True)) \
            and len({next(iter(h)) for h in heads}) == len(groups):
        names = [_stage_name(next(iter(h))) for h in heads]
    else:
        names = [f"f_mesh,{i + 1}" for i in range(len(groups))]
    return [_with_centrals(n, g[0], g[1], None) for n, g in zip(names, groups, strict=True)]


def _auto_orders(groups: list[MeshGroup], fn: np.ndarray, fmax: float, top_rpm: float,
                 setting: int) -> list[MeshGroup]:
    """Mesh orders per group: ``setting``, or (``setting = 0``) enough to reach the highest
    natural frequency in the map at the top speed (:data:`AUTO_ORDERS`)."""
    out = []
    for g in groups:
        if setting > 0:
            k = setting
        else:
            inside = fn[fn <= fmax]
            f_top = float(inside.max()) if inside.size else fmax
            need = math.ceil(f_top / max(g.frequency_per_rpm * top_rpm, 1e-300))
            k = int(np.clip(need, *AUTO_ORDERS))
        out.append(MeshGroup(g.name, g.frequency_per_rpm, g.meshes, g.centrals, k))
    return out


def _is_paper_set(model: AssembledModel | None, gs: dict) -> bool:
    """The paper's example: a simple set, z_s = 33, z_r = -114, three planets."""
    if model is None or str(gs.get("type", "simple")) != "simple":
        return False
    z = {int(m["z1"]) for m in model.meta.get("meshes", []) if m.get("z1") is not None}
    return z == {33, -114} and len(model.meta.get("planets", [])) == 3


def signed_force(ds: xr.Dataset, mesh: str) -> np.ndarray:
    """Normal force of a mesh: drive (left) flank positive, back (right) flank negative [N]."""
    f = ds["normal_force"].sel(mesh=mesh)
    return np.asarray(f.sel(flank="left").values - f.sel(flank="right").values, dtype=float)


def summed_stiffness(model: AssembledModel, meshes: Sequence[str], *,
                     cycles: float = _STIFFNESS_CYCLES, points_per_cycle: int = 400,
                     central: str = "", group: str = "mesh") -> SummedStiffness:
    """Summed stiffness of some meshes over ``cycles`` of their mesh frequency (Figs. 9, 10).

    Every mesh is evaluated at its own phase, ``k_m(s0_m + s)``, from the model's stiffness
    tables (left flanks), for a rigid-body rotation that advances the meshes by ``s`` cycles
    (meshes of one central gear share one mesh frequency).

    Parameters
    ----------
    model : AssembledModel
        The gear set.
    meshes : sequence of str
        The meshes (e.g. every mesh of the sun).
    cycles : float
        Number of mesh cycles.
    points_per_cycle : int
        Resolution.
    central, group : str
        Names stored in the result.

    Returns
    -------
    SummedStiffness
    """
    names = tuple(meshes)
    if not names:
        raise ValueError("no meshes to sum")
    unknown = [n for n in names if n not in model.mesh_names]
    if unknown:
        raise ValueError(f"unknown mesh {unknown[0]!r} (meshes: {', '.join(model.mesh_names)})")
    idx = [model.mesh_names.index(n) for n in names]
    s = np.arange(round(cycles * points_per_cycle) + 1) / points_per_cycle
    pos = model.mesh_position_offsets[None, :] + s[:, None]
    k = model.mesh_stiffness_at(pos)[:, idx].T
    return SummedStiffness(cycles=s, total=k.sum(axis=0), per_mesh=k, mesh_names=names,
                           source="model", central=central, group=group)


def summed_sun_stiffness(model: AssembledModel, *, cycles: float = _STIFFNESS_CYCLES,
                         points_per_cycle: int = 400) -> SummedStiffness:
    """Summed stiffness of the meshes of the first central gear (the sun of a simple set)."""
    g = _model_groups(model)[0]
    if not g.centrals:
        raise ValueError(f"the gear set has no central-gear mesh (meshes: "
                         f"{', '.join(model.mesh_names)})")
    central, meshes = g.centrals[0]
    return summed_stiffness(model, meshes, cycles=cycles, points_per_cycle=points_per_cycle,
                            central=central, group=g.name)


def _simulated_stiffness(ds: xr.Dataset, meshes: Sequence[str], f_per_rpm: float,
                         central: str, group: str) -> SummedStiffness | None:
    """Summed simulated stiffness over the first few mesh cycles above 2 % of the top speed."""
    if not meshes or "mesh_stiffness" not in ds:
        return None
    angle = np.asarray(ds["input_angle"].values, dtype=float)
    cyc = np.abs(angle) / (2 * math.pi) * f_per_rpm * 60.0  # mesh cycles since start
    sp = np.abs(ds["input_speed"].values)
    start = int(np.argmax(sp > _RPM_MIN_FRACTION * sp.max()))
    sel = (cyc >= cyc[start]) & (cyc <= cyc[start] + _STIFFNESS_CYCLES)
    if sel.sum() < 10:
        return None
    k = np.asarray(ds["mesh_stiffness"].sel(mesh=list(meshes)).values, dtype=float)[:, sel]
    return SummedStiffness(cycles=cyc[sel] - cyc[start], total=k.sum(axis=0), per_mesh=k,
                           mesh_names=tuple(meshes), source="simulation", central=central,
                           group=group)


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list):
        return ", ".join(_fmt(x) for x in v)
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {_fmt(x)}" for k, x in v.items()) + "}"
    return str(v)


def _tables(cfg: dict, key: str, prefix: str = "") -> list[tuple[str, dict]]:
    """Every ``key`` table of a description, also inside stages (``stage1.geometry``)."""
    out = []
    if isinstance(cfg.get(key), dict):
        out.append((prefix, cfg[key]))
    for k, v in cfg.items():
        if isinstance(v, dict) and k not in (key, "simulation") and (
                k.startswith("stage") or isinstance(v.get(key), dict)):
            out += _tables(v, key, f"{prefix}{k}.")
    return out


def _geometry_rows(gs: dict, model: AssembledModel | None) -> list[tuple[str, str]]:
    rows: list[tuple[str, str]] = []
    for prefix, geo in _tables(gs, "geometry"):
        text = ", ".join(f"{k} = {_fmt(v)}" for k, v in geo.items())
        rows.append((f"geometry{' [' + prefix.rstrip('.') + ']' if prefix else ''}", text))
    for key in ("body", "mesh", "coupling", "shaft"):  # [[body]], [[mesh]], ... lists
        for i, item in enumerate(gs.get(key, []) if isinstance(gs.get(key), list) else []):
            if isinstance(item, dict):
                label = str(item.get("name", "")) or (f"{i + 1}" if key == "shaft" else "")
                rows.append((f"{key} {label}".strip(),
                             ", ".join(f"{k} = {_fmt(v)}" for k, v in item.items()
                                       if k != "name")))
    handled = {"geometry", "operation", "meshes", "bodies", "simulation", "body", "mesh",
               "coupling"}
    for key, table in gs.items():  # e.g. the [shaft] between two stages
        if isinstance(table, dict) and key not in handled and not key.startswith("stage"):
            rows.append((key, ", ".join(f"{k} = {_fmt(v)}" for k, v in table.items())))
    if model is None:
        return rows
    # every mesh type: tooth numbers, centre distance, contact ratio and the phases
    kinds: dict[tuple, list[dict]] = {}
    for m in model.meta.get("meshes", []):
        if not isinstance(m, dict):
            continue
        key = (str(m.get("gear1", "")), m.get("z1"), m.get("z2"),
               round(float(m.get("centre_distance") or 0.0), 9),
               round(float(m.get("contact_ratio") or 0.0), 6))
        kinds.setdefault(key, []).append(m)
    for (_gear1, z1, z2, a, eps), ms in kinds.items():
        names = [str(m["name"]) for m in ms]
        label = names[0] if len(names) == 1 else f"{names[0]} … {names[-1]}"
        phases = ", ".join(f"{float(m.get('phase_lag', 0.0)):.4f}" for m in ms)
        parts = []
        if z1 is not None and z2 is not None:
            parts.append(f"z = {z1}/{z2}")
        if a:
            parts.append(f"centre distance {1e3 * a:.2f} mm")
        if eps:
            parts.append(f"contact ratio {eps:.3f}")
        parts.append(f"phase lag {phases} cycles")
        rows.append((f"meshes {label} ({len(ms)})", ", ".join(parts)))
    carriers: dict[str, list[tuple[str, float]]] = {}
    for p in model.meta.get("planets", []):
        carriers.setdefault(str(p.get("carrier", "carrier")), []).append(
            (str(p["name"]), float(p.get("angle_deg", 0.0))))
    for carrier, ps in carriers.items():
        rows.append((f"planets on {carrier}", ", ".join(f"{n} {a:.2f}°" for n, a in ps)))
    return rows


def _parameters(ds: xr.Dataset, caller: dict, model: AssembledModel | None, run: dict,
                groups: Sequence[MeshGroup]) -> list[tuple[str, str]]:
    rows: list[tuple[str, str]] = []
    gs = caller.get("gearset", {}) if isinstance(caller.get("gearset"), dict) else {}
    if gs:
        rows.append(("gear set", f"{gs.get('name', '')} ({gs.get('type', 'simple')})"))
        if gs.get("title"):
            rows.append(("description", str(gs["title"])))
    rows += _geometry_rows(gs, model)
    if gs:
        for prefix, op in _tables(gs, "operation"):
            rows.append((f"operation{' [' + prefix.rstrip('.') + ']' if prefix else ''}",
                         ", ".join(f"{k} {v}" for k, v in op.items())))
        for prefix, meshes in _tables(gs, "meshes"):
            for mname, m in sorted(meshes.items()):
                if not isinstance(m, dict):
                    continue
                st = m.get("stiffness", {})
                text = ", ".join(f"{k} = {_fmt(v)}" for k, v in st.items()) \
                    if isinstance(st, dict) else _fmt(st)
                extra = ", ".join(f"{k} = {v:g}" for k, v in m.items()
                                  if k in ("backlash", "damping_ratio", "damping"))
                rows.append((f"{prefix}{mname} meshes", text + (f"; {extra}" if extra else "")))
        for prefix, bodies in _tables(gs, "bodies"):
            for bname, b in sorted(bodies.items()):
                if not isinstance(b, dict):
                    continue
                sup = b.get("support", {})
                sup_text = ", ".join(f"{k} {_fmt(v)}" for k, v in sup.items()) \
                    if isinstance(sup, dict) else "-"
                rows.append((f"body {prefix}{bname}",
                             f"m = {b.get('mass')} kg, J = {b.get('inertia')} kg m²; "
                             f"support: {sup_text or '-'}"))
    if model is not None:
        rows.append(("degrees of freedom",
                     f"{model.n_dof} ({count(model.n_mesh, 'mesh', 'meshes')}, "
                     f"{count(len(model.bearing_names), 'elastic bearing')})"))
    for g in groups:
        what = "" if len(groups) == 1 else f", {g.name}"
        rows.append((f"mesh frequency per input speed{what}",
                     f"{g.frequency_per_rpm:.6g} Hz per min⁻¹ ({60 * g.frequency_per_rpm:.4g} "
                     f"mesh cycles per input revolution; meshes {', '.join(g.meshes)})"))
    rows.append(("run", run_description(run, ds)))
    rows.append(("output sample rate", f"{float(ds.attrs.get('fs_out', 0.0)):g} Hz"))
    return rows


def _modes_rows(modal: ModalResult | None, ds: xr.Dataset) -> list[tuple]:
    if modal is None:
        f = np.asarray(ds["natural_frequency"].values, dtype=float)
        return [(i + 2, f"{fi:.1f}", "(not stored)", "", "") for i, fi in enumerate(f)]
    rows = []
    for i, (f, k, m) in enumerate(zip(modal.frequencies_hz, modal.kinds, modal.multiplicity,
                                      strict=True)):
        dom = ""
        if modal.mesh_energy.shape[1] and modal.mesh_energy[i].max() > 1e-6:
            j = int(np.argmax(modal.mesh_energy[i]))
            dom = f"{modal.mesh_names[j]} ({100 * modal.mesh_energy[i, j]:.0f} %)"
        rows.append((i + 1, f"{f:.1f}", k, str(m), dom))
    return rows


def _run_settings(caller: dict, ds: xr.Dataset) -> dict:
    run = caller.get("run")
    sp = np.abs(np.asarray(ds["input_speed"].values, dtype=float))
    t = np.asarray(ds["time"].values, dtype=float)
    if isinstance(run, dict) and "duration" in run:
        out = dict(run)
    else:
        out = {"speed_start_rpm": float(sp[0]), "speed_end_rpm": float(sp[-1]),
               "duration": float(t[-1] - t[0])}
    out.setdefault("drive", "speed")
    out.setdefault("speed_start_rpm", float(sp[0]))
    if out.get("speed_end_rpm") is None or out["drive"] != "speed":
        out["speed_end_rpm"] = float(sp.max())  # what the run reached
    out.setdefault("fs_out", float(ds.attrs.get("fs_out", 0.0)))
    return out


def _run_drive(ds: xr.Dataset) -> DriveCoupling | None:
    """The drive coupling a speed-driven run was simulated with (its file's attributes; a run
    written before the sensing attribute existed had its coupling on the input member), or
    None (the default) for any other run."""
    attrs = ds.attrs
    if attrs.get("drive") != "speed" or "drive_coupling_stiffness" not in attrs:
        return None
    try:
        return DriveCoupling(float(attrs["drive_coupling_stiffness"]),
                             float(attrs["drive_coupling_damping"]),
                             str(attrs.get("drive_coupling_sensing", "input")))
    except (KeyError, TypeError, ValueError):
        return None


def _stability(model: AssembledModel, modal: ModalResult, candidates: Candidates,
               span: tuple[float, float], settings: AnalysisSettings,
               progress: bool | None,
               coupling: DriveCoupling | None = None) -> tuple[Any, str, float]:
    mode = STABILITY_MODES[settings.stability]
    hi = float(span[1])
    lo = max(float(span[0]), _RPM_MIN_FRACTION * hi)
    points = settings.stability_points if mode["points"] is None else min(
        settings.stability_points, mode["points"])
    speeds = np.linspace(lo, hi, max(points, 2))
    t0 = time.perf_counter()
    try:
        chart = stability_over_speed(
            model, speeds, coupling=coupling, n_max=settings.n_max, refine=True,
            candidates=candidates, modal=modal, floquet_options=dict(mode["floquet"]),
            workers=None, progress=progress, xtol_rel=mode["xtol_rel"],
            max_cycles=cycle_budget(model))
    except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
        return None, f"Floquet stability chart failed: {exc}", time.perf_counter() - t0
    return chart, "", time.perf_counter() - t0


def _first_order_rows(model: AssembledModel, span: tuple[float, float],
                      settings: AnalysisSettings,
                      coupling: DriveCoupling | None = None) -> list[tuple[str, ...]]:
    """First-order (Hsu) regions inside the run-up speed range, for the stability section."""
    try:
        widths = first_order_regions(model, coupling=coupling, l_max=settings.n_max)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError):
        return []
    lo_r, hi_r = span
    factor = {g.name: g.frequency_per_rpm for g in model.mesh_frequency_groups()}
    rows = []
    for i in np.argsort(widths.lower_rpm):
        lo, hi = float(widths.lower_rpm[i]), float(widths.upper_rpm[i])
        w = float(widths.width_hz[i])
        if not (np.isfinite(lo) and np.isfinite(hi)) or w <= 0 or hi < lo_r or lo > hi_r:
            continue
        group = "" if widths.mesh_frequency is None else str(widths.mesh_frequency[i])
        f = factor.get(group) or (w / (hi - lo) if hi > lo else math.nan)
        rows.append((f"{widths.label[i]} [{group}]" if group else str(widths.label[i]),
                     f"{lo:.0f}", f"{hi:.0f}", f"{hi - lo:.1f}",
                     f"{float(widths.undamped_width_hz[i]) / f:.1f}"))
    return rows


def _stored_candidates(fn: np.ndarray, names: list[str], groups: Sequence[MeshGroup],
                       speed_range: tuple[float, float], n_max: int) -> Candidates:
    """Candidates of every stored mesh frequency (no gear-set model), sorted by speed."""
    tables = [instability_candidates(fn, n_max=n_max, mesh_frequency_per_rpm=g.frequency_per_rpm,
                                     speed_range=speed_range, mode_labels=names,
                                     mesh_frequency_name=g.name if len(groups) > 1 else None)
              for g in groups]
    if len(tables) == 1:
        return tables[0]
    cols = ("kind", "mode_i", "mode_j", "n", "f_mesh_hz", "rpm", "allowed", "reason", "label",
            "mesh_frequency")
    merged = {c: np.concatenate([getattr(t, c) for t in tables]) for c in cols}
    order = np.argsort(merged["rpm"], kind="stable")
    return Candidates(**{c: v[order] for c, v in merged.items()}, notes=tables[0].notes,
                      natural_frequencies_hz=tables[0].natural_frequencies_hz,
                      mesh_frequency_per_rpm=groups[0].frequency_per_rpm)


def _shown_candidates(cands: Candidates, chart: Any, n_max: int,
                      span: tuple[float, float]) -> Candidates:
    """Rows of order ``n <= n_max`` inside the speed range, plus every attributed row."""
    keep = (cands.n <= n_max) & (cands.rpm >= span[0]) & (cands.rpm <= span[1])
    if chart is not None:
        for reg in chart.region_table:
            if int(reg.get("candidate_index", -1)) >= 0:
                keep[int(reg["candidate_index"])] = True
    return cands.select(keep)


def _force_spectrum(ds: xr.Dataset, mesh: str, group: str, fs: float, fmax: float,
                    settings: AnalysisSettings, fn: np.ndarray, names: list[str],
                    candidates: Candidates) -> ForceSpectrum:
    seg = int(min(ds.sizes["time"], round(fs / max(settings.map_resolution_hz / 4, 1.0))))
    x = signed_force(ds, mesh)
    sp = spectrum(x - x.mean(), fs, window="hann", amplitude="peak", segment_length=seg,
                  overlap=0.5, units="N", name=f"tooth force {mesh}")
    band = sp.frequency <= fmax
    floor = float(np.median(sp.values[band])) if band.any() else 0.0
    # humps of the run-up spectrum, not the ripple of the mesh harmonics sweeping by
    pk = find_peaks(sp, prominence_db=3.0, max_peaks=4 * settings.spectrum_peaks,
                    min_distance_hz=max(3 * sp.bin_spacing_hz, fmax / 40.0),
                    threshold=2 * floor)
    keep = (pk.frequency > 0.5 * settings.map_resolution_hz) & (pk.frequency <= fmax)
    order = np.argsort(pk.amplitude[keep])[::-1][: settings.spectrum_peaks]
    sel = np.sort(np.flatnonzero(keep)[order])
    pk = Peaks(pk.frequency[sel], pk.amplitude[sel], pk.bin_frequency[sel],
               pk.bin_value[sel], pk.scaling, pk.units, pk.window)
    if len(pk) and fn.size:
        # a run-up spectrum has broad humps: each peak is uncertain by its -3 dB half-width
        widths = peak_half_widths(sp.frequency, to_db(sp.values, sp.amplitude), pk.frequency)
        labels = label_peaks(pk.frequency, fn, resolution_hz=sp.enbw_hz,
                             peak_widths_hz=widths, candidates=candidates, names=names,
                             natural_uncertainty=settings.tolerance,
                             band=(0.5 * settings.map_resolution_hz, fmax))
    else:
        labels = PeakLabels(peaks=np.zeros(0), matches=(), coincidence=np.zeros(0),
                            peak_uncertainty=np.zeros(0))
    return ForceSpectrum(mesh, sp, pk, labels, group)


def analyse_case(ds: xr.Dataset, *, name: str | None = None,
                 settings: AnalysisSettings | None = None,
                 progress: bool | None = False) -> CaseAnalysis:
    """Compute the report content of one run.

    Parameters
    ----------
    ds : xarray.Dataset
        A run-up (:meth:`gearvib.simulate.RunUpResult.to_dataset`, or read back with
        :func:`gearvib.io.read_run`).
    name : str, optional
        Case name (default: the ``case`` entry of ``config_json``, else the gear-set name).
    settings : AnalysisSettings, optional
        Default: the ``analysis`` entry of ``config_json``, else :class:`AnalysisSettings`.
    progress : bool or None
        Progress bar of the Floquet chart (None: on a terminal only).

    Returns
    -------
    CaseAnalysis

    Raises
    ------
    ValueError
        The Dataset is not a run-up with tooth forces.
    """
    for v in ("normal_force", "input_speed", "mesh_frequency", "natural_frequency",
              "input_angle"):
        if v not in ds.variables:
            raise ValueError(f"the dataset is not a gearvib run-up: variable {v!r} is missing")
    cfg = _config(ds)
    caller = _caller_config(cfg)
    if settings is None:
        a = caller.get("analysis")
        settings = AnalysisSettings.from_dict(a) if isinstance(a, dict) else AnalysisSettings()
    notes: list[str] = []
    model, why = _rebuild(caller)
    if why:
        notes.append(why)
    modal = modal_analysis(model) if model is not None else None
    if modal is not None:
        keep = np.array([k != "rigid-body" for k in modal.kinds], dtype=bool)
        fn = modal.frequencies_hz[keep]
        names = [f"f{i + 1}" for i in np.flatnonzero(keep)]
        groups = _model_groups(model) or _stored_groups(ds)
    else:
        fn = np.asarray(ds["natural_frequency"].values, dtype=float)
        names = [f"f{i + 2}" for i in range(fn.size)]
        groups = _stored_groups(ds)
        notes.append("natural frequencies are those stored in the run, named f2, f3, ... "
                     "assuming one rigid-body mode (f1)")
    gs = caller.get("gearset", {}) if isinstance(caller.get("gearset"), dict) else {}
    gs_name = str(gs.get("name", ""))
    case = name or str(caller.get("case", "")) or gs_name or "run"
    label = str(caller.get("label", "")) or str(gs.get("title", "")) or gs_name or case
    run = _run_settings(caller, ds)
    rpm = np.abs(np.asarray(ds["input_speed"].values, dtype=float))
    span = (float(rpm.min()), float(rpm.max()))
    meshes = [str(m) for m in ds["mesh"].values]
    force_meshes = [(g.name, g.centrals[0][1]) for g in groups if g.centrals]
    first = force_meshes[0][1] if force_meshes else ()
    force_mesh = settings.force_mesh or (first[0] if first else meshes[0])
    if force_mesh not in meshes:
        raise ValueError(f"force_mesh = {force_mesh!r} is not a mesh of the run "
                         f"({', '.join(meshes)})")
    fs = float(1.0 / np.median(np.diff(ds["time"].values)))
    fmax = settings.frequency_max_hz or min(0.5 * fs, 2.2 * float(fn.max()) if fn.size else
                                            0.5 * fs)
    fmax = min(fmax, 0.5 * fs)
    groups = _auto_orders(groups, fn, fmax, span[1], settings.orders)
    f_per_rpm = groups[0].frequency_per_rpm
    paper = _is_paper_set(model, gs)
    several = len(groups) > 1

    # theory candidates: n <= max(n_max, ATTRIBUTION_N_MAX) for the Floquet attribution (a
    # little beyond the speed range: centres may lie just outside a region), n <= n_max for
    # the peak labels and the table
    wide = (0.97 * span[0], 1.03 * span[1])
    if model is not None and modal is not None:
        all_cands = gear_set_candidates(model, modal, n_max=max(settings.n_max,
                                                                ATTRIBUTION_N_MAX),
                                        speed_range=wide)
    else:
        all_cands = _stored_candidates(fn, names, groups, wide, settings.n_max)
        notes.append("theory candidates without the planetary mesh-phasing selection rule")
    low = all_cands.select((all_cands.n <= settings.n_max) & (all_cands.rpm >= span[0])
                           & (all_cands.rpm <= span[1]))
    if several:
        notes.append("resonance rises are classified against the mesh orders of their own mesh "
                     "frequency (" + ", ".join(g.name for g in groups) + "); the order lines "
                     "of every mesh frequency are drawn on the sonogram")

    # (c) spectra: the first mesh of every central gear of every group (at most four)
    panels = [(g.name, ms[0]) for g in groups for _, ms in g.centrals][:_MAX_PANELS] or \
        [(groups[0].name, force_mesh)]
    spectra = [_force_spectrum(ds, mesh, gname, fs, fmax, settings, fn, names, low)
               for gname, mesh in panels]

    # (d) summed mesh stiffness of every central gear (at most four)
    stiff: list[SummedStiffness] = []
    for g in groups:
        for central, ms in g.centrals:
            if len(stiff) >= _MAX_PANELS:
                break
            st = (summed_stiffness(model, ms, central=central, group=g.name)
                  if model is not None else
                  _simulated_stiffness(ds, ms, g.frequency_per_rpm, central, g.name))
            if st is not None:
                stiff.append(st)

    # (e) maps of the tooth force
    x = signed_force(ds, force_mesh)
    t = np.asarray(ds["time"].values, dtype=float)
    fmap = rpm_frequency_map(x - x.mean(), None, rpm, time=t,
                             resolution=settings.map_resolution_hz, window="hann",
                             overlap=settings.map_overlap, amplitude="rms", units="N",
                             name=f"tooth force {force_mesh}")
    omap = None
    moving = rpm > _RPM_MIN_FRACTION * rpm.max()
    first_i = int(np.argmax(moving))
    if moving[first_i:].all() and moving.sum() > 64:
        try:
            xm = x[first_i:]
            slowest = 60.0 * min(g.frequency_per_rpm for g in groups)
            # every mesh order the report discusses, within the Nyquist order at the top speed
            top_order = max(g.orders * g.order for g in groups)
            nyquist = 0.98 * 0.5 * fs * 60.0 / max(rpm.max(), 1e-300)
            max_order = min(1.04 * top_order, nyquist)
            omap = rpm_order_map(xm - xm.mean(), None, rpm[first_i:], time=t[first_i:],
                                 window="hann", overlap=settings.map_overlap, amplitude="rms",
                                 resolution=max(slowest / 8.0, 0.5), units="N",
                                 max_order=max_order,
                                 samples_per_rev=2 * math.ceil(1.28 * max_order),
                                 name=f"tooth force {force_mesh}")
            if top_order > nyquist:
                notes.append(f"the rpm-order map ends at order {max_order:.0f} (the Nyquist "
                             f"order at {rpm.max():.0f} min⁻¹); higher mesh orders are "
                             "outside the recorded band")
        except ValueError as exc:
            notes.append(f"rpm-order map not available: {exc}")

    # (f) Floquet stability over the run-up speed range
    chart = None
    first_order: list[tuple[str, ...]] = []
    rule, families = None, None
    t_stab = 0.0
    if model is not None and modal is not None:
        if settings.stability == "off":
            notes.append("Floquet stability chart not computed ([analysis] stability = "
                         "\"off\"); parametric rises are judged by the theory candidates "
                         "alone")
        else:
            chart, why, t_stab = _stability(model, modal, all_cands, span, settings, progress,
                                            _run_drive(ds))
            if why:
                notes.append(why)
        first_order = _first_order_rows(model, span, settings, _run_drive(ds))
        if not several:
            rule, families = mesh_phasing(model, modal)
    candidates = _shown_candidates(all_cands, chart, settings.n_max, span)
    if chart is not None:  # labels of the shown table are those of the chart's table
        notes += list(chart.notes)

    # (g) resonances of the map, classified per mesh frequency: forced (rays x natural
    # frequencies), parametric (growing Floquet bands), unexplained
    map_ds = fmap.to_dataset().sel(frequency=slice(0.0, fmax))
    frame_rpm = np.asarray(map_ds["rpm"].values)
    try:
        features: MapFeatures | None = map_features(
            map_ds, frames=frame_rpm > _RPM_MIN_FRACTION * float(frame_rpm.max()))
    except ValueError as exc:  # e.g. a constant-speed run: rays and lines coincide
        features = None
        notes.append(f"rays and vertical lines not separated: {exc}")
    f_lo = _MIN_SPOT_FRACTION * float(fn.min()) if fn.size else 0.0

    def detect(m_ds: xr.Dataset, feats: MapFeatures | None) -> Resonances:
        parts = []
        for g in groups:
            parts.append((g.name, detect_resonances(
                m_ds, natural_frequencies_hz=fn, mesh_frequency_per_rpm=g.frequency_per_rpm,
                features=feats, orders=range(1, g.orders + 1), names=names, candidates=low,
                chart=chart, mode_families=families, mesh_harmonic_rule=rule,
                speed_profile=(t, rpm), threshold_db=settings.threshold_db,
                natural_uncertainty=settings.tolerance, dynamic_range_db=SPOT_RANGE_DB,
                frequency_range=(f_lo, fmax))))
        hop = float(np.median(np.diff(m_ds["rpm"].values))) if m_ds.sizes["time"] > 1 else 0.0
        return merge_mesh_frequencies(parts, rpm_tolerance=abs(hop) * 1.5 + 1e-9,
                                      frequency_tolerance=1.5 * settings.map_resolution_hz)

    resonances = detect(map_ds, features)
    regions = resonance_regions(resonances, rpm_gap=_REGION_GAP * span[1])
    planet_res = None
    sun = force_meshes[0][1] if force_meshes else ()
    if (resonances.growth is not None and len(resonances.growth)
            and float(resonances.growth.growth_db.max()) >= PLANET_SIGNAL_GROWTH_DB
            and len(sun) >= 2 and force_mesh == sun[0]):
        # the planet modes cancel in one mesh force when the planets are in phase; the
        # difference of two planets' forces holds only them (their parametric growth)
        xd = signed_force(ds, sun[0]) - signed_force(ds, sun[1])
        dmap = rpm_frequency_map(xd - xd.mean(), None, rpm, time=t,
                                 resolution=settings.map_resolution_hz, window="hann",
                                 overlap=settings.map_overlap, amplitude="rms", units="N",
                                 name=f"tooth force {sun[0]} - {sun[1]}")
        planet_res = detect(dmap.to_dataset().sel(frequency=slice(0.0, fmax)), None)

    # (h) provenance (no dates in the text: same input, same report; the analysis times are
    # measured, so they are stated only in the log and the result)
    gs_cfg = caller.get("gearset")
    prov = [
        ("case", case),
        ("gearvib version (run)", str(ds.attrs.get("gearvib_version", ds.attrs.get("source")))),
        ("integrator", str(ds.attrs.get("integrator", ""))),
        ("internal step dt", f"{float(ds.attrs.get('dt', float('nan'))):.6g} s"),
        ("output sample rate", f"{float(ds.attrs.get('fs_out', fs)):g} Hz (decimation "
                               f"{ds.attrs.get('decimation_factor', '?')}, FIR "
                               f"{ds.attrs.get('fir_numtaps', '?')} taps)"),
        ("configuration SHA-256 (run)", str(ds.attrs.get("config_sha256", ""))),
        ("gear-set description SHA-256",
         config_hash(gs_cfg) if isinstance(gs_cfg, dict) else "(not stored)"),
        ("model SHA-256", str(cfg.get("model_sha256", ""))),
        ("analysis settings", json.dumps(settings.to_dict(), sort_keys=True)),
        ("map", f"{fmap.window}, RBW {fmap.resolution_hz:.3g} Hz, overlap "
                f"{fmap.overlap:g}, {fmap.time.size} frames"),
        ("mesh orders", ", ".join(f"{g.name}: 1–{g.orders}" for g in groups)),
    ]
    if chart is not None:
        prov.append(("Floquet chart", f"{chart.mesh_frequencies_hz.size} speeds "
                     f"({settings.stability}), boundaries refined; regions attributed to "
                     f"candidates up to n = {max(settings.n_max, ATTRIBUTION_N_MAX)}"))
    return CaseAnalysis(
        name=case, label=label, dataset=ds, config=cfg, model=model, modal=modal,
        natural_frequencies_hz=fn, mode_names=names, mesh_frequency_per_rpm=f_per_rpm,
        groups=groups, parameters=_parameters(ds, caller, model, run, groups),
        modes=_modes_rows(modal, ds), force_mesh=force_mesh, force_meshes=force_meshes,
        spectra=spectra, stiffness=stiff, fmap=fmap, omap=omap, frequency_max_hz=fmax,
        resonances=resonances, regions=regions, candidates=candidates, chart=chart, run=run,
        settings=settings, notes=notes, provenance=prov, first_order=first_order,
        planet_resonances=planet_res, features=features, paper_set=paper,
        stability_time_s=t_stab,
    )


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
