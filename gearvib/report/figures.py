"""Report content of one run: computation first (:func:`analyse_case`), then Figure builders.

:func:`analyse_case` turns a run-up Dataset (written by :func:`gearvib.simulate.simulate` through
:func:`gearvib.report.runner.run_study`) into a :class:`CaseAnalysis` holding plain data: the
gear-set parameters, the modes, the tooth forces of the sun meshes (paper Figure 7), labelled
spectra of the planet-tooth forces (Figure 8), the summed sun-mesh stiffness over a few mesh
cycles (Figures 9 and 10), the rpm-frequency and rpm-order maps of a tooth force (Figure 11),
the detected resonances, the Floquet stability chart with its theory candidates, and the
provenance. The ``*_figure`` functions draw those data with the matplotlib Figure API (never
pyplot); they compute nothing themselves.

The gear set is rebuilt from the ``config_json`` attribute of the Dataset (its ``"gearset"``
entry). If that is missing, the analysis falls back to what the Dataset holds: the stored
natural frequencies, the mesh frequencies per speed from the ``mesh_frequency(mesh, time)`` and
``input_speed`` coordinates and the simulated ``mesh_stiffness``; the stability chart and the
mode types are then not available, and the report says so.

A gear set with several mesh frequencies (two stages, the two toothings of a Wolfrom planet)
gets order lines, order marks, theory candidates and Floquet intervals for every one of them,
labelled with its name (``stage 1``, ``stage 2``); the first is the reference of the speed
axis of the stability chart.
"""

from __future__ import annotations

import json
import math
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from analysis.identification import peak_half_widths
from analysis.instability import (
    UNEXPLAINED,
    Candidates,
    PeakLabels,
    Resonances,
    detect_resonances,
    instability_candidates,
    label_peaks,
)
from analysis.maps import RpmFrequencyMap, RpmOrderMap, rpm_frequency_map, rpm_order_map
from analysis.plots import rpm_frequency_map_figure, rpm_order_map_figure
from analysis.runup import MapFeatures, map_features
from analysis.spectrum import Peaks, Spectrum, find_peaks, spectrum, to_db
from gearvib.assembly import assemble
from gearvib.config import config_hash, gearset_from_dict
from gearvib.modal import ModalResult, modal_analysis
from gearvib.model import AssembledModel
from gearvib.report.study import AnalysisSettings
from gearvib.report.wording import count
from gearvib.stability import first_order_regions, mesh_phasing, stability_over_speed

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from analysis.instability import StabilityChart

__all__ = [
    "PAPER_SPEEDS_RPM",
    "CaseAnalysis",
    "ForceSpectrum",
    "SummedStiffness",
    "analyse_case",
    "key_speed_rows",
    "mesh_stiffness_figure",
    "order_map_figure",
    "sonogram_figure",
    "spectra_figure",
    "stability_figure",
    "summed_sun_stiffness",
    "tooth_force_figure",
]

PAPER_SPEEDS_RPM = (1500.0, 2600.0, 3100.0)
"""Sun speeds at which the paper reads resonances off Figure 11 (case 1) [min^-1]."""

RISE_HEADER = ("speed", "f [Hz]", "on", "rise [dB]", "mechanism: cause", "chance", "evidence")
"""Columns of the tables of classified rises."""

_STIFFNESS_CYCLES = 3
# the planet-mode signal (difference of two planets' sun-mesh forces) of a symmetric simulation
# starts at round-off; it is analysed only when a Floquet band lets it grow by this much
_PLANET_SIGNAL_GROWTH_DB = 40.0
_SPOT_RANGE_DB = 40.0  # rises more than this below the map maximum are background clutter
_MIN_SPOT_FRACTION = 0.15  # spots below 0.15 x the lowest natural frequency: near-DC content
_REGION_GAP = 0.03  # spots closer than 3 % of the top speed belong to one resonance region
_RPM_MIN_FRACTION = 0.02  # order tracking needs rpm > 0: skip the first 2 % of the speed range


# --------------------------------------------------------------------------- data containers


@dataclass(frozen=True)
class SummedStiffness:
    """Sum of the sun-mesh stiffnesses over a few mesh cycles (paper Figures 9 and 10).

    Attributes
    ----------
    cycles : ndarray
        Mesh position [mesh cycles] (rigid-body rotation from the assembly position).
    total : ndarray
        ``sum_m k_m(s0_m + s)`` over the sun meshes [N/m].
    per_mesh : ndarray, shape (n_sun_mesh, n)
        The individual mesh stiffnesses [N/m].
    mesh_names : tuple of str
        Names of the summed meshes.
    source : str
        ``"model"`` (stiffness tables with the mesh phases) or ``"simulation"`` (the simulated
        effective stiffness at the lowest speeds, when the model cannot be rebuilt).
    """

    cycles: np.ndarray
    total: np.ndarray
    per_mesh: np.ndarray
    mesh_names: tuple[str, ...]
    source: str

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
    """Detected resonance spots grouped by speed (one row of the region table).

    Attributes
    ----------
    rpm_low, rpm_high : float
        Speed span of the spots [min^-1].
    rpm_peak : float
        Speed of the strongest spot.
    frequency_hz : float
        Response frequency of the strongest spot [Hz].
    strength_db : float
        Rise of the strongest spot above its background [dB].
    n_spots : int
        Number of spots.
    mechanisms : tuple of str
        Distinct classified mechanisms (with modes), strongest first.
    """

    rpm_low: float
    rpm_high: float
    rpm_peak: float
    frequency_hz: float
    strength_db: float
    n_spots: int
    mechanisms: tuple[str, ...]

    @property
    def classified(self) -> bool:
        """True if at least one spot is a forced resonance or a parametric instability."""
        return any(not m.startswith(UNEXPLAINED) for m in self.mechanisms)


def resonance_regions(res: Resonances, *, rpm_gap: float) -> list[ResonanceRegion]:
    """Group resonance spots into speed regions.

    Spots closer than ``rpm_gap`` join a region; a region spans at most ``4 rpm_gap`` (dense
    clutter must not chain into one region over the whole run-up).

    Parameters
    ----------
    res : Resonances
        Detected spots.
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
        mech = []
        for i in idx[np.argsort(res.strength_db[idx])[::-1]]:
            m = str(res.mechanism[i]) + (f" ({res.cause[i]})" if res.cause[i] else "")
            if m not in mech:
                mech.append(m)
        out.append(ResonanceRegion(
            rpm_low=float(res.rpm[idx].min()), rpm_high=float(res.rpm[idx].max()),
            rpm_peak=float(res.rpm[best]), frequency_hz=float(res.frequency[best]),
            strength_db=float(res.strength_db[best]), n_spots=idx.size,
            mechanisms=tuple(mech)))
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
    """

    mesh: str
    spectrum: Spectrum
    peaks: Peaks
    labels: PeakLabels


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
        Mesh frequency per input speed [Hz per min^-1] (paper eq. 5); with several mesh
        frequencies the first (reference) one.
    mesh_frequencies : list of (str, float)
        Every distinct mesh frequency: name (``"stage 2"``; ``"mesh"`` for a set with one) and
        Hz per min^-1, reference first.
    parameters : list of (str, str)
        Gear-set and run parameters.
    modes : list of tuple
        ``(mode, f [Hz], kind, multiplicity, dominant mesh)`` rows.
    force_mesh : str
        Mesh of the sonogram and resonance table.
    sun_meshes, ring_meshes : tuple of str
        Sun-planet and ring-planet meshes.
    spectra : list of ForceSpectrum
        Planet-tooth force spectra.
    stiffness : SummedStiffness or None
        Summed sun-mesh stiffness.
    fmap : RpmFrequencyMap
        Sonogram of the tooth force of ``force_mesh``.
    omap : RpmOrderMap or None
        Rpm-order map of the same force (None if the speed range is too short).
    frequency_max_hz : float
        Upper frequency of spectra and sonogram.
    resonances : Resonances
        Rises detected in ``fmap`` and their mechanisms.
    planet_resonances : Resonances or None
        Rises of the difference of the first two sun-mesh forces (only the planet modes), when
        a Floquet-unstable band grows by at least 40 dB in the run.
    features : MapFeatures or None
        Order-locked rays and frequency-locked lines of the sonogram.
    regions : list of ResonanceRegion
        The spots grouped into speed regions.
    candidates : Candidates
        Theory candidates within the speed range.
    chart : StabilityChart or None
        Floquet stability over speed.
    notes : list of str
        Remarks (e.g. why a chart is missing).
    provenance : list of (str, str)
        Version, hashes, step, sample rate (no dates).
    run : dict
        Run settings (speed range, duration, torque, fs_out).
    settings : AnalysisSettings
        Analysis settings used.
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
    parameters: list[tuple[str, str]]
    modes: list[tuple]
    force_mesh: str
    sun_meshes: tuple[str, ...]
    ring_meshes: tuple[str, ...]
    spectra: list[ForceSpectrum]
    stiffness: SummedStiffness | None
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
    mesh_frequencies: list[tuple[str, float]] = field(default_factory=list)

    @property
    def several_mesh_frequencies(self) -> bool:
        """True when the gear set has more than one mesh frequency."""
        return len(self.mesh_frequencies) > 1
    planet_resonances: Resonances | None = None
    features: MapFeatures | None = None

    @property
    def speed_range(self) -> tuple[float, float]:
        """Smallest and largest input speed of the run [min^-1]."""
        v = self.dataset["input_speed"].values
        return float(v.min()), float(v.max())

    def mesh_frequency_at(self, rpm: float) -> float:
        """Mesh frequency at an input speed [Hz] (the reference one if there are several)."""
        return self.mesh_frequency_per_rpm * rpm

    def group_frequencies_text(self, f_ref_lo: float, f_ref_hi: float) -> str:
        """A reference mesh-frequency interval [Hz] in every mesh frequency, as text."""
        if not self.several_mesh_frequencies:
            return f"{f_ref_lo:.1f}–{f_ref_hi:.1f}"
        return "; ".join(f"{name}: {f_ref_lo * f / self.mesh_frequency_per_rpm:.1f}–"
                         f"{f_ref_hi * f / self.mesh_frequency_per_rpm:.1f}"
                         for name, f in self.mesh_frequencies)

    def resonance_rows(self, planet: bool = False) -> list[tuple[str, ...]]:
        """Rows of the resonance table (formatted strings; see :data:`RISE_HEADER`).

        Parameters
        ----------
        planet : bool
            Rows of the planet-mode signal instead of the tooth force.
        """
        r = self.planet_resonances if planet else self.resonances
        if r is None:
            return []
        feature = {"natural frequency": "f_i", "spot": "spot"}
        return [(f"{r.rpm[i]:.0f}", f"{r.frequency[i]:.0f}",
                 f"k={r.order[i]}" if r.order[i] else feature.get(str(r.feature[i]), "–"),
                 f"{r.strength_db[i]:.1f}",
                 str(r.mechanism[i]).split()[0] + (f": {r.cause[i]}" if r.cause[i] else ""),
                 f"{100 * r.coincidence[i]:.0f} %", str(r.note[i]))
                for i in range(len(r))]

    def peak_rows(self) -> list[tuple[str, ...]]:
        """Rows of the identified-peak table (formatted strings)."""
        rows = []
        for fsp in self.spectra:
            lab = fsp.labels
            for i in range(len(lab)):
                best = lab.matches[i][0] if lab.matches[i] else None
                rows.append((fsp.mesh, lab.label(i),
                             f"{best.deviation:+.0f}" if best else "–",
                             f"± {best.tolerance:.0f}" if best else "–",
                             f"{100 * lab.coincidence[i]:.0f} %"))
        return rows

    def crossing_rows(self) -> list[tuple[str, ...]]:
        """Predicted crossings of the mesh orders with the natural frequencies."""
        return [(f"{c.harmonic} × f_mesh = {c.mode}", f"{c.frequency_hz:.0f}", f"{c.rpm:.0f}",
                 c.status + (f" ({c.strength_db:.1f} dB)" if c.status == "rise" else ""))
                for c in self.resonances.crossings]

    def growth_rows(self) -> list[tuple[str, ...]]:
        """Growth of every Floquet-unstable band during this run."""
        g = self.resonances.growth
        if g is None:
            return []
        return [(f"{g.lower_rpm[i]:.0f}–{g.upper_rpm[i]:.0f}", str(g.label[i]) or "–",
                 f"{1e3 * g.time_in_band[i]:.1f}", f"{g.peak_growth_rate[i]:.3g}",
                 f"{g.growth_db[i]:.1f}",
                 "develops" if g.can_grow[i] else f"too fast: {g.advice[i]}")
                for i in range(len(g))]

    def region_rows(self) -> list[tuple[str, ...]]:
        """Rows of the Floquet region table (formatted strings)."""
        if self.chart is None:
            return []
        reg = self.chart.regions()
        rows = []
        for i in range(reg.sizes["region"]):
            lo_s, hi_s = float(reg["lower_speed"][i]), float(reg["upper_speed"][i])
            open_lo = "≤ " if int(reg["lower_open"][i]) else ""
            open_hi = " ≥" if int(reg["upper_open"][i]) else ""
            rows.append((f"{open_lo}{lo_s:.0f}", f"{hi_s:.0f}{open_hi}", f"{hi_s - lo_s:.1f}",
                         self.group_frequencies_text(float(reg["lower"][i]),
                                                     float(reg["upper"][i])),
                         f"{float(reg['peak_growth_rate'][i]):.3g}",
                         str(reg["candidate"].values[i]) or "–",
                         _mechanism(str(reg["candidate"].values[i]), self.candidates)))
        return rows

    def candidate_rows(self) -> list[tuple[str, ...]]:
        """Rows of the theory-candidate table."""
        c = self.candidates
        return [(f"{c.rpm[i]:.0f}", f"{c.f_mesh_hz[i]:.1f}", str(c.kind[i]), str(c.n[i]),
                 c.full_label(i), "yes" if c.allowed[i] else f"no: {c.reason[i]}")
                for i in range(len(c))]


def _mechanism(label: str, cands: Candidates) -> str:
    if not label:
        return "no theory candidate in range"
    idx = np.flatnonzero([cands.full_label(i) == label for i in range(len(cands))])
    if idx.size == 0:
        return ""
    i = int(idx[0])
    kind = str(cands.kind[i])
    return (f"parametric instability, {kind} type, n = {int(cands.n[i])}"
            if kind in ("principal", "sum") else kind)


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


def _stored_mesh_frequencies(ds: xr.Dataset) -> list[tuple[str, float]]:
    """Distinct mesh frequencies per speed [Hz per min^-1] from ``mesh_frequency``.

    Reads ``mesh_frequency(mesh, time)``, and the single ``mesh_frequency(time)`` of runs
    written before every mesh had its own. Groups are named like
    :meth:`gearvib.model.AssembledModel.mesh_frequency_groups` (stage prefix or numbered).
    """
    fm = np.asarray(ds["mesh_frequency"].values, dtype=float)
    sp = np.abs(np.asarray(ds["input_speed"].values, dtype=float))
    ok = sp > 0.05 * sp.max()
    if not ok.any():
        raise ValueError("the run has no speed > 0: cannot derive the mesh frequency per speed")
    if fm.ndim == 1:
        return [("mesh", float(np.median(fm[ok] / sp[ok])))]
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
        return [("mesh", groups[0][0])]
    heads = [{m.split(".", 1)[0] for m in g[1]} for g in groups]
    if all(len(h) == 1 and all("." in m for m in g[1]) for h, g in zip(heads, groups,
                                                                      strict=True)) \
            and len({next(iter(h)) for h in heads}) == len(groups):
        names = [_stage_name(next(iter(h))) for h in heads]
    else:
        names = [f"f_mesh,{i + 1}" for i in range(len(groups))]
    return [(n, g[0]) for n, g in zip(names, groups, strict=True)]


def _stage_name(prefix: str) -> str:
    return f"stage {prefix[1:]}" if prefix[:1] == "s" and prefix[1:].isdigit() else prefix


def _sun_ring_meshes(meshes: Sequence[str]) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Sun-planet and ring-planet meshes; in a multi-stage set those of the first stage."""
    sun = tuple(m for m in meshes if m.startswith("sun"))
    ring = tuple(m for m in meshes if m.startswith("ring"))
    if sun or ring or not meshes or "." not in meshes[0]:
        return sun, ring
    head = meshes[0].split(".", 1)[0] + "."
    first = [m for m in meshes if m.startswith(head)]
    return (tuple(m for m in first if m[len(head):].startswith("sun")),
            tuple(m for m in first if m[len(head):].startswith("ring")))


def _signed_force(ds: xr.Dataset, mesh: str) -> np.ndarray:
    """Normal force of a mesh: drive (left) flank positive, back (right) flank negative [N]."""
    f = ds["normal_force"].sel(mesh=mesh)
    return np.asarray(f.sel(flank="left").values - f.sel(flank="right").values, dtype=float)


def summed_sun_stiffness(model: AssembledModel, *, cycles: float = _STIFFNESS_CYCLES,
                         points_per_cycle: int = 400) -> SummedStiffness:
    """Summed stiffness of the sun meshes over ``cycles`` mesh cycles (paper Figures 9, 10).

    Every sun mesh is evaluated at its own phase, ``k_m(s0_m + s)``, from the model's stiffness
    tables (left flanks), for a rigid-body rotation that advances all sun meshes by ``s``
    cycles.

    Parameters
    ----------
    model : AssembledModel
        The gear set.
    cycles : float
        Number of mesh cycles.
    points_per_cycle : int
        Resolution.

    Returns
    -------
    SummedStiffness
    """
    names = _sun_ring_meshes(model.mesh_names)[0]
    if not names:
        raise ValueError(f"the gear set has no sun mesh (meshes: {', '.join(model.mesh_names)})")
    idx = [model.mesh_names.index(n) for n in names]
    s = np.arange(round(cycles * points_per_cycle) + 1) / points_per_cycle
    pos = model.mesh_position_offsets[None, :] + s[:, None]
    k = model.mesh_stiffness_at(pos)[:, idx].T
    return SummedStiffness(cycles=s, total=k.sum(axis=0), per_mesh=k, mesh_names=names,
                           source="model")


def _simulated_stiffness(ds: xr.Dataset, sun: Sequence[str], f_per_rpm: float
                         ) -> SummedStiffness | None:
    """Summed simulated stiffness over the first few mesh cycles above 2 % of the top speed."""
    if not sun or "mesh_stiffness" not in ds:
        return None
    angle = np.asarray(ds["input_angle"].values, dtype=float)
    cyc = np.abs(angle) / (2 * math.pi) * f_per_rpm * 60.0  # mesh cycles since start
    sp = np.abs(ds["input_speed"].values)
    start = int(np.argmax(sp > _RPM_MIN_FRACTION * sp.max()))
    sel = (cyc >= cyc[start]) & (cyc <= cyc[start] + _STIFFNESS_CYCLES)
    if sel.sum() < 10:
        return None
    k = np.asarray(ds["mesh_stiffness"].sel(mesh=list(sun)).values, dtype=float)[:, sel]
    return SummedStiffness(cycles=cyc[sel] - cyc[start], total=k.sum(axis=0), per_mesh=k,
                           mesh_names=tuple(sun), source="simulation")


def _parameters(ds: xr.Dataset, caller: dict, model: AssembledModel | None, run: dict,
                f_per_rpm: float, mesh_freqs: Sequence[tuple[str, float]] = ()
                ) -> list[tuple[str, str]]:
    rows: list[tuple[str, str]] = []
    gs = caller.get("gearset", {}) if isinstance(caller.get("gearset"), dict) else {}
    if gs:
        rows.append(("gear set", f"{gs.get('name', '')} ({gs.get('type', 'simple')})"))
        if gs.get("title"):
            rows.append(("description", str(gs["title"])))
        geo = gs.get("geometry", {})
        for k in ("z_sun", "z_ring", "z_planet", "module", "pressure_angle_deg", "face_width",
                  "planet_angles_deg"):
            if k in geo:
                v = geo[k]
                if k == "planet_angles_deg":
                    v = ", ".join(f"{a:.2f}" for a in v) + " deg"
                rows.append((f"geometry: {k}", str(v)))
        op = gs.get("operation", {})
        if op:
            rows.append(("operation", f"input {op.get('input')}, output {op.get('output')}, "
                                      f"fixed {op.get('fixed')}"))
        for mname, m in sorted(gs.get("meshes", {}).items()):
            st = m.get("stiffness", {})
            text = ", ".join(f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}"
                             for k, v in st.items())
            rows.append((f"{mname} meshes: stiffness", text))
            extra = {k: m[k] for k in ("backlash", "damping_ratio", "damping") if k in m}
            if extra:
                rows.append((f"{mname} meshes", ", ".join(f"{k} = {v:g}"
                                                          for k, v in extra.items())))
        for bname, b in sorted(gs.get("bodies", {}).items()):
            sup = b.get("support", {})
            sup_text = ", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}"
                                 for k, v in sup.items())
            rows.append((f"body {bname}", f"m = {b.get('mass')} kg, J = {b.get('inertia')} "
                                          f"kg m²; support: {sup_text or '-'}"))
    if model is not None:
        for m in model.meta.get("meshes", []):
            if m.get("contact_ratio") is not None:
                rows.append((f"mesh {m['name']}",
                             f"contact ratio {m['contact_ratio']:.3f}, phase lag "
                             f"{m.get('phase_lag', 0.0):.4f} cycles"))
        rows.append(("degrees of freedom",
                     f"{model.n_dof} ({count(model.n_mesh, 'mesh', 'meshes')}, "
                     f"{count(len(model.bearing_names), 'elastic bearing')})"))
    if len(mesh_freqs) > 1:
        groups = {g.name: g for g in model.mesh_frequency_groups()} if model is not None else {}
        for name, f in mesh_freqs:
            members = (f"; meshes {', '.join(groups[name].mesh_names)}" if name in groups
                       else "")
            rows.append((f"mesh frequency per input speed, {name}",
                         f"{f:.6g} Hz per min⁻¹ ({60 * f:.4g} mesh cycles per input "
                         f"revolution{members})"))
    else:
        rows.append(("mesh frequency per input speed",
                     f"{f_per_rpm:.6g} Hz per min⁻¹ (paper eq. 5, {60 * f_per_rpm:.4g} mesh "
                     "cycles per input revolution)"))
    rows.append(("run-up", f"{run['speed_start_rpm']:g} → {run['speed_end_rpm']:g} min⁻¹ in "
                           f"{run['duration']:g} s, input torque {run['input_torque']:g} N m"))
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
    if isinstance(run, dict) and {"speed_start_rpm", "speed_end_rpm", "duration"} <= set(run):
        out = dict(run)
    else:
        sp = np.asarray(ds["input_speed"].values, dtype=float)
        t = np.asarray(ds["time"].values, dtype=float)
        out = {"speed_start_rpm": float(sp[0]), "speed_end_rpm": float(sp[-1]),
               "duration": float(t[-1] - t[0])}
    out.setdefault("input_torque", float("nan"))
    out.setdefault("fs_out", float(ds.attrs.get("fs_out", 0.0)))
    return out


def _stability(model: AssembledModel, run: dict, settings: AnalysisSettings
               ) -> tuple[Any, str]:
    hi = float(run["speed_end_rpm"])
    lo = max(float(run["speed_start_rpm"]), _RPM_MIN_FRACTION * hi)
    speeds = np.linspace(lo, hi, settings.stability_points)
    try:
        return stability_over_speed(model, speeds, n_max=settings.n_max, refine=True), ""
    except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
        return None, f"Floquet stability chart failed: {exc}"


def _first_order_rows(model: AssembledModel, run: dict, settings: AnalysisSettings
                      ) -> list[tuple[str, ...]]:
    """First-order (Hsu) regions inside the run-up speed range, for the stability section."""
    try:
        widths = first_order_regions(model, l_max=settings.n_max)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError):
        return []
    lo_r, hi_r = float(run["speed_start_rpm"]), float(run["speed_end_rpm"])
    factor = {g.name: g.frequency_per_rpm for g in model.mesh_frequency_groups()}
    rows = []
    order = np.argsort(widths.lower_rpm)
    for i in order:
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


def _candidates(model: AssembledModel | None, modal: ModalResult | None, fn: np.ndarray,
                names: list[str], f_per_rpm: float, speed_range: tuple[float, float],
                n_max: int) -> tuple[Candidates, str]:
    if model is not None and modal is not None:
        try:
            from gearvib.stability import gear_set_candidates
        except ImportError:
            pass
        else:
            return gear_set_candidates(model, modal, n_max=n_max, speed_range=speed_range), ""
    note = "theory candidates without the planetary mesh-phasing selection rule"
    return instability_candidates(fn, n_max=n_max, mesh_frequency_per_rpm=f_per_rpm,
                                  speed_range=speed_range, mode_labels=names), note


def _stored_candidates(fn: np.ndarray, names: list[str], groups: list[tuple[str, float]],
                       speed_range: tuple[float, float], n_max: int) -> Candidates:
    """Candidates of every stored mesh frequency (no gear-set model), sorted by speed."""
    tables = [instability_candidates(fn, n_max=n_max, mesh_frequency_per_rpm=f,
                                     speed_range=speed_range, mode_labels=names,
                                     mesh_frequency_name=g) for g, f in groups]
    cols = ("kind", "mode_i", "mode_j", "n", "f_mesh_hz", "rpm", "allowed", "reason", "label",
            "mesh_frequency")
    merged = {c: np.concatenate([getattr(t, c) for t in tables]) for c in cols}
    order = np.argsort(merged["rpm"], kind="stable")
    return Candidates(**{c: v[order] for c, v in merged.items()}, notes=tables[0].notes,
                      natural_frequencies_hz=tables[0].natural_frequencies_hz,
                      mesh_frequency_per_rpm=groups[0][1])


def analyse_case(ds: xr.Dataset, *, name: str | None = None,
                 settings: AnalysisSettings | None = None) -> CaseAnalysis:
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

    Returns
    -------
    CaseAnalysis

    Raises
    ------
    ValueError
        The Dataset is not a speed-driven run-up with tooth forces.
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
        mesh_freqs = [(g.name, g.frequency_per_rpm) for g in model.mesh_frequency_groups()]
        if not mesh_freqs:
            mesh_freqs = _stored_mesh_frequencies(ds)
    else:
        fn = np.asarray(ds["natural_frequency"].values, dtype=float)
        names = [f"f{i + 2}" for i in range(fn.size)]
        mesh_freqs = _stored_mesh_frequencies(ds)
        notes.append("natural frequencies are those stored in the run, named f2, f3, ... "
                     "assuming one rigid-body mode (f1)")
    gs_name = caller.get("gearset", {}).get("name", "") if isinstance(
        caller.get("gearset"), dict) else ""
    gs_title = caller.get("gearset", {}).get("title", "") if gs_name else ""
    case = name or str(caller.get("case", "")) or gs_name or "run"
    label = str(caller.get("label", "")) or str(gs_title) or gs_name or case
    run = _run_settings(caller, ds)
    f_per_rpm = mesh_freqs[0][1]
    meshes = [str(m) for m in ds["mesh"].values]
    sun, ring = _sun_ring_meshes(meshes)
    force_mesh = settings.force_mesh or (sun[0] if sun else meshes[0])
    if force_mesh not in meshes:
        raise ValueError(f"force_mesh = {force_mesh!r} is not a mesh of the run "
                         f"({', '.join(meshes)})")
    fs = float(1.0 / np.median(np.diff(ds["time"].values)))
    fmax = settings.frequency_max_hz or min(0.5 * fs, 2.2 * float(fn.max()) if fn.size else
                                            0.5 * fs)
    fmax = min(fmax, 0.5 * fs)

    # theory candidates in the run-up range (with the mesh-phasing selection rule)
    span = (float(run["speed_start_rpm"]), float(run["speed_end_rpm"]))
    if model is None and len(mesh_freqs) > 1:
        candidates = _stored_candidates(fn, names, mesh_freqs, span, settings.n_max)
        cnote = "theory candidates without the planetary mesh-phasing selection rule"
    else:
        candidates, cnote = _candidates(model, modal, fn, names, f_per_rpm, span,
                                        settings.n_max)
    if cnote:
        notes.append(cnote)
    if len(mesh_freqs) > 1:
        notes.append(f"resonance rises are classified against the mesh orders of "
                     f"{mesh_freqs[0][0]} (the reference); the order lines of every mesh "
                     "frequency are drawn on the sonogram")

    # (c) spectra of the planet-tooth forces over the whole run-up, labelled peaks
    spectra = []
    seg = int(min(ds.sizes["time"], round(fs / max(settings.map_resolution_hz / 4, 1.0))))
    for mesh in [m for m in (sun[:1] + ring[:1]) if m] or [force_mesh]:
        x = _signed_force(ds, mesh)
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
        spectra.append(ForceSpectrum(mesh, sp, pk, labels))

    # (d) summed sun-mesh stiffness
    if model is not None and sun:
        stiff: SummedStiffness | None = summed_sun_stiffness(model)
    else:
        stiff = _simulated_stiffness(ds, sun, f_per_rpm)

    # (e) maps of the tooth force
    x = _signed_force(ds, force_mesh)
    rpm = np.abs(np.asarray(ds["input_speed"].values, dtype=float))
    t = np.asarray(ds["time"].values, dtype=float)
    fmap = rpm_frequency_map(x - x.mean(), None, rpm, time=t,
                             resolution=settings.map_resolution_hz, window="hann",
                             overlap=settings.map_overlap, amplitude="rms", units="N",
                             name=f"tooth force {force_mesh}")
    omap = None
    moving = rpm > _RPM_MIN_FRACTION * rpm.max()
    first = int(np.argmax(moving))
    if moving[first:].all() and moving.sum() > 64:
        try:
            xm = x[first:]
            mesh_order = 60.0 * min(f for _, f in mesh_freqs)  # resolve the slowest stage
            omap = rpm_order_map(xm - xm.mean(), None, rpm[first:], time=t[first:],
                                 window="hann", overlap=settings.map_overlap, amplitude="rms",
                                 resolution=max(mesh_order / 8.0, 0.5), units="N",
                                 name=f"tooth force {force_mesh}")
        except ValueError as exc:
            notes.append(f"rpm-order map not available: {exc}")

    # (f) Floquet stability over the run-up speed range
    chart = None
    first_order: list[tuple[str, ...]] = []
    rule, families = None, None
    if model is not None:
        chart, why = _stability(model, run, settings)
        if why:
            notes.append(why)
        first_order = _first_order_rows(model, run, settings)
        rule, families = mesh_phasing(model, modal)

    # (g) resonances of the map: forced (rays x natural frequencies), parametric (growing
    # Floquet bands), unexplained
    map_ds = fmap.to_dataset().sel(frequency=slice(0.0, fmax))
    frame_rpm = np.asarray(map_ds["rpm"].values)
    try:
        features: MapFeatures | None = map_features(
            map_ds, frames=frame_rpm > _RPM_MIN_FRACTION * float(frame_rpm.max()))
    except ValueError as exc:  # e.g. a constant-speed run: rays and lines coincide
        features = None
        notes.append(f"rays and vertical lines not separated: {exc}")
    resonances = detect_resonances(
        map_ds, natural_frequencies_hz=fn, mesh_frequency_per_rpm=f_per_rpm, features=features,
        orders=range(1, settings.orders + 1), names=names, candidates=candidates,
        chart=chart, mode_families=families, mesh_harmonic_rule=rule,
        speed_profile=(t, rpm), threshold_db=settings.threshold_db,
        natural_uncertainty=settings.tolerance, dynamic_range_db=_SPOT_RANGE_DB,
        frequency_range=(_MIN_SPOT_FRACTION * float(fn.min()) if fn.size else 0.0, fmax))
    regions = resonance_regions(resonances, rpm_gap=_REGION_GAP * float(run["speed_end_rpm"]))
    planet_res = None
    if (resonances.growth is not None and len(resonances.growth)
            and float(resonances.growth.growth_db.max()) >= _PLANET_SIGNAL_GROWTH_DB
            and len(sun) >= 2 and force_mesh == sun[0]):
        # the planet modes cancel in one mesh force when the planets are in phase; the
        # difference of two planets' forces holds only them (their parametric growth)
        xd = _signed_force(ds, sun[0]) - _signed_force(ds, sun[1])
        dmap = rpm_frequency_map(xd - xd.mean(), None, rpm, time=t,
                                 resolution=settings.map_resolution_hz, window="hann",
                                 overlap=settings.map_overlap, amplitude="rms", units="N",
                                 name=f"tooth force {sun[0]} - {sun[1]}")
        planet_res = detect_resonances(
            dmap.to_dataset().sel(frequency=slice(0.0, fmax)), natural_frequencies_hz=fn,
            mesh_frequency_per_rpm=f_per_rpm, orders=range(1, settings.orders + 1), names=names,
            candidates=candidates, chart=chart, mode_families=families,
            mesh_harmonic_rule=rule, speed_profile=(t, rpm),
            threshold_db=settings.threshold_db, natural_uncertainty=settings.tolerance,
            dynamic_range_db=_SPOT_RANGE_DB,
            frequency_range=(_MIN_SPOT_FRACTION * float(fn.min()) if fn.size else 0.0, fmax))

    # (h) provenance (no dates: same input, same report)
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
    ]
    return CaseAnalysis(
        name=case, label=label, dataset=ds, config=cfg, model=model, modal=modal,
        natural_frequencies_hz=fn, mode_names=names, mesh_frequency_per_rpm=f_per_rpm,
        parameters=_parameters(ds, caller, model, run, f_per_rpm, mesh_freqs),
        mesh_frequencies=mesh_freqs,
        modes=_modes_rows(modal, ds), force_mesh=force_mesh, sun_meshes=sun, ring_meshes=ring,
        spectra=spectra, stiffness=stiff, fmap=fmap, omap=omap, frequency_max_hz=fmax,
        resonances=resonances, regions=regions, candidates=candidates, chart=chart, run=run,
        settings=settings,
        notes=notes, provenance=prov, first_order=first_order, planet_resonances=planet_res,
        features=features,
    )


def _mesh_frequency_text(ca: CaseAnalysis) -> str:
    """The sonogram section's sentence on the mesh frequencies."""
    if ca.several_mesh_frequencies:
        return (f"{ca.name}: " + "; ".join(
            f"f_mesh,{name} = {f:.5g} Hz per min⁻¹ × n_in ({60 * f:.4g} mesh cycles per input "
            "revolution)" for name, f in ca.mesh_frequencies) + ". " + "; ".join(
            f"at {r[0]} f_mesh = {r[1]}" for r in key_speed_rows(ca)) + ".")
    return (f"{ca.name}: f_mesh = {ca.mesh_frequency_per_rpm:.5g} Hz per min⁻¹ × "
            f"n_S (paper eq. 5). " + "; ".join(
                f"at {r[0]} f_mesh = {r[1]}" for r in key_speed_rows(ca)) + ".")


def key_speed_rows(ca: CaseAnalysis) -> list[tuple[str, str, str]]:
    """Mesh frequency at the paper's reference speeds, with the nearest theory expressions.

    Returns
    -------
    list of (str, str, str)
        ``("1500 min⁻¹", "640 Hz", "f_mesh ≈ f2/2 (631 Hz)")`` rows for the speeds of
        :data:`PAPER_SPEEDS_RPM` inside the run's speed range; with several mesh frequencies
        one row per speed and mesh frequency (``"1500 min⁻¹", "144 Hz (stage 2)", ...``).
    """
    lo, hi = ca.speed_range
    several = ca.several_mesh_frequencies
    groups = ca.mesh_frequencies if several else [("", ca.mesh_frequency_per_rpm)]
    rows = []
    for rpm in PAPER_SPEEDS_RPM:
        if not lo <= rpm <= hi:
            continue
        for name, f in groups:
            fm = f * rpm
            lab = label_peaks([fm], ca.natural_frequencies_hz, n_max=6, tolerance=0.1,
                              names=ca.mode_names) if ca.natural_frequencies_hz.size else None
            text = "–"
            if lab is not None and lab.matches[0]:
                best = sorted(lab.matches[0], key=lambda m: m.relative_error)[:2]
                text = " ; ".join(f"f_mesh ≈ {m.expression} ({m.value_hz:.0f} Hz, "
                                  f"{100 * m.relative_error:+.0f} %)".replace("+-", "-")
                                  for m in best)
            rows.append((f"{rpm:.0f} min⁻¹", f"{fm:.0f} Hz" + (f" ({name})" if several else ""),
                         text))
    return rows


# --------------------------------------------------------------------------- figures


def _figure(figsize: tuple[float, float]) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=figsize, layout="constrained", dpi=100)


def tooth_force_figure(ca: CaseAnalysis, *, figsize: tuple[float, float] = (8.0, 4.2)
                       ) -> Figure:
    """Normal tooth forces of the sun meshes over the run-up (paper Figure 7).

    The drive flank counts positive, the back flank negative; the input speed is on a second
    axis.
    """
    fig = _figure(figsize)
    ax = fig.add_subplot()
    t = ca.dataset["time"].values
    stride = max(1, t.size // 20000)
    for i, m in enumerate(ca.sun_meshes or (ca.force_mesh,)):
        ax.plot(t[::stride], _signed_force(ca.dataset, m)[::stride], lw=0.5, color=f"C{i}",
                label=m)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("normal tooth force [N]")
    ax.grid(True, alpha=0.3)
    ax2 = ax.twinx()
    ax2.plot(t, np.abs(ca.dataset["input_speed"].values), color="k", lw=1.0, ls="--",
             label="input speed")
    ax2.set_ylabel("input speed [min⁻¹]")
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(f"{ca.name}: normal tooth forces of the sun meshes (cf. paper Fig. 7)")
    return fig


def spectra_figure(ca: CaseAnalysis, *, figsize: tuple[float, float] = (8.0, 6.5)) -> Figure:
    """Spectra of the planet-tooth forces with theory-labelled peaks (paper Figure 8)."""
    fig = _figure(figsize)
    axes = fig.subplots(len(ca.spectra), 1, squeeze=False)[:, 0]
    for ax, fsp in zip(axes, ca.spectra, strict=True):
        sp = fsp.spectrum
        band = sp.frequency <= ca.frequency_max_hz
        ax.plot(sp.frequency[band], to_db(sp.values[band], sp.amplitude), lw=0.7)
        if len(fsp.peaks):
            y = to_db(fsp.peaks.amplitude, sp.amplitude)
            ax.plot(fsp.peaks.frequency, y, "v", color="C3", ms=4)
            for i, (f, v) in enumerate(zip(fsp.peaks.frequency, y, strict=True)):
                st = fsp.labels.status[i] if i < len(fsp.labels) else "unexplained"
                m = fsp.labels.matches[i] if i < len(fsp.labels) else ()
                text = f"{f:.0f}" + (f"\n≈ {m[0].expression}" if st == "explained" else
                                     "\n?" if st == "unexplained" else "\n~")
                ax.annotate(text, (f, v), xytext=(0, 4), textcoords="offset points",
                            ha="center", fontsize=6.5)
        for fn in ca.natural_frequencies_hz:
            ax.axvline(fn, color="C1", lw=0.7, ls=":")
        ax.set_xlim(0, ca.frequency_max_hz)
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi + 0.25 * (hi - lo))  # room for the peak labels below the title
        ax.set_ylabel("peak amplitude\n[dB re 1 N]")
        ax.set_title(f"{fsp.mesh}: {sp.window}, Δf = {sp.bin_spacing_hz:.3g} Hz, "
                     f"{sp.n_averages} averages", fontsize=9)
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("frequency [Hz]  (dotted: natural frequencies)")
    fig.suptitle(f"{ca.name}: spectra of the planet-tooth forces over the run-up "
                 "(cf. paper Fig. 8)", fontsize=10)
    return fig


def mesh_stiffness_figure(cases: Sequence[CaseAnalysis], *,
                          figsize: tuple[float, float] = (8.0, 4.2)) -> Figure:
    """Summed sun-mesh stiffness over a few mesh cycles, one line per case (Figs. 9, 10)."""
    fig = _figure(figsize)
    ax = fig.add_subplot()
    for i, ca in enumerate(cases):
        st = ca.stiffness
        if st is None:
            continue
        ax.plot(st.cycles, st.total / 1e8, color=f"C{i}", lw=1.4,
                label=f"{ca.name}: {st.minimum / 1e8:.2f}–{st.maximum / 1e8:.2f}e8 N/m "
                      f"(p-p {st.peak_to_peak / 1e8:.2f}e8, {st.source})")
        if len(cases) == 1:
            for j, m in enumerate(st.mesh_names):
                ax.plot(st.cycles, st.per_mesh[j] / 1e8, lw=0.7, ls="--", label=m)
    ax.set_xlabel("mesh position [mesh cycles]")
    ax.set_ylabel("summed sun-mesh stiffness [1e8 N/m]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title("Sum of the sun-mesh stiffnesses (cf. paper Figs. 9 and 10)")
    return fig


def sonogram_figure(ca: CaseAnalysis, *, figsize: tuple[float, float] = (7.5, 6.0)
                    ) -> Figure:
    """Rpm-frequency map of a tooth force with mesh orders and natural frequencies (Fig. 11).

    Speed is on the vertical axis; the inclined dashed lines are the orders 1..N of the mesh
    frequency, the dotted vertical lines the natural frequencies; circles mark forced
    resonances, squares parametric instabilities, grey crosses unexplained rises, and red bands
    the speed ranges the Floquet analysis finds unstable.
    """
    orders = list(range(1, ca.settings.orders + 1))
    several = ca.several_mesh_frequencies
    fig = rpm_frequency_map_figure(
        ca.fmap, hz_per_rpm=() if several else ca.mesh_frequency_per_rpm, orders=orders,
        order_labels=None if several else [f"{k}×" for k in orders],
        natural_frequencies_hz=list(ca.natural_frequencies_hz), dynamic_range_db=50.0,
        frequency_max=ca.frequency_max_hz, figsize=figsize)
    ax = fig.axes[0]
    if several:
        _order_line_families(ax, ca, orders)
    r = ca.resonances
    for key, (marker, color, text) in {
            "forced": ("o", "r", "forced resonance"),
            "parametric": ("s", "m", "parametric instability"),
            "unexplained": ("x", "0.85", "unexplained rise")}.items():
        m = np.asarray([str(x).startswith(key) for x in r.mechanism], dtype=bool)
        if m.any():
            ax.plot(r.frequency[m], r.rpm[m], marker, mfc="none", mec=color, mew=1.4, ms=9,
                    lw=0, label=f"{text} ({int(m.sum())})")
    if ca.chart is not None:
        for k, reg in enumerate(ca.chart.region_table):
            ax.axhspan(reg["lower"] / ca.mesh_frequency_per_rpm,
                       reg["upper"] / ca.mesh_frequency_per_rpm, color="r", alpha=0.18, lw=0,
                       label="Floquet unstable" if k == 0 else None)
    if len(r) or (ca.chart is not None and len(ca.chart.region_table)) or several:
        leg = ax.legend(loc="lower right", fontsize=8)
        if several:  # the white mesh-order entry on a white legend: give it a dark face
            leg.get_frame().set_facecolor("0.35")
            for text in leg.get_texts():
                text.set_color("w")
    ax.set_title(f"{ca.name}: sonogram of the tooth force {ca.force_mesh} (cf. paper Fig. 11)\n"
                 f"{ca.fmap.window}, RBW {ca.fmap.resolution_hz:.3g} Hz", fontsize=9)
    return fig


_FAMILY_STYLES = (("w", "--"), ("#00e5ff", "-"), ("#ff66ff", "-."), ("#ffd400", ":"))


def _order_line_families(ax: Any, ca: CaseAnalysis, orders: Sequence[int]) -> None:
    """Mesh-order lines of every mesh frequency, one colour and dash style per frequency.

    Each line ``f = k f_g(rpm)`` is labelled ``"k×"`` in its colour where it leaves the plot
    (top edge, or right edge for lines that reach the frequency limit first); a legend names
    the families.
    """
    lo, hi = ax.get_ylim()
    fmax = ax.get_xlim()[1]
    for j, (name, f) in enumerate(ca.mesh_frequencies):
        colour, dash = _FAMILY_STYLES[j % len(_FAMILY_STYLES)]
        for i, k in enumerate(orders):
            rpm = np.array([lo, hi])
            freq = k * f * rpm
            if freq[0] >= fmax:
                continue
            ax.plot(freq, rpm, color=colour, lw=0.9, ls=dash,
                    label=f"mesh orders, {name}" if i == 0 else None)
            if freq[1] <= fmax:
                ax.annotate(f"{k}×", (freq[1], hi), xytext=(-2, -9), textcoords="offset points",
                            color=colour, fontsize=7, ha="right")
            else:
                ax.annotate(f"{k}×", (fmax, fmax / (k * f)), xytext=(-3, 2),
                            textcoords="offset points", color=colour, fontsize=7, ha="right")
    ax.set_xlim(0, fmax)
    ax.set_ylim(lo, hi)


def order_map_figure(ca: CaseAnalysis, *, figsize: tuple[float, float] = (7.5, 5.0)
                     ) -> Figure | None:
    """Rpm-order map of the same tooth force with the mesh orders marked (None if absent)."""
    if ca.omap is None:
        return None
    groups = ca.mesh_frequencies or [("mesh", ca.mesh_frequency_per_rpm)]
    if len(groups) == 1:
        mesh_order = 60.0 * groups[0][1]
        marks = [k * mesh_order for k in range(1, ca.settings.orders + 1)
                 if k * mesh_order <= ca.omap.max_order]
        fig = rpm_order_map_figure(ca.omap, orders=marks, dynamic_range_db=50.0,
                                   figsize=figsize)
        fig.axes[0].set_title(f"{ca.name}: rpm-order map of {ca.force_mesh} (dashed: mesh "
                              f"orders k × {mesh_order:.3g})", fontsize=9)
        return fig
    fig = rpm_order_map_figure(ca.omap, orders=(), dynamic_range_db=50.0, figsize=figsize)
    ax = fig.axes[0]
    for j, (name, f) in enumerate(groups):
        colour, dash = _FAMILY_STYLES[j % len(_FAMILY_STYLES)]
        for k in range(1, ca.settings.orders + 1):
            if k * 60.0 * f <= ca.omap.max_order:
                ax.axvline(k * 60.0 * f, color=colour, ls=dash, lw=0.9,
                           label=f"{name}: k × {60.0 * f:.4g}" if k == 1 else None)
    leg = ax.legend(loc="lower right", fontsize=8)
    leg.get_frame().set_facecolor("0.35")
    for text in leg.get_texts():
        text.set_color("w")
    ax.set_title(f"{ca.name}: rpm-order map of {ca.force_mesh} with the mesh orders of every "
                 "mesh frequency", fontsize=9)
    return fig


def stability_figure(ca: CaseAnalysis, *, figsize: tuple[float, float] = (8.0, 4.2)
                     ) -> Figure | None:
    """Floquet growth rate over input speed with the unstable regions shaded (None if absent).

    Theory candidates (allowed: solid ticks; suppressed by the mesh-phasing rule: dotted) are
    marked at the top. With several mesh frequencies the ticks take the colour of their mesh
    frequency and only the candidates the unstable regions are attributed to are named.
    """
    ch = ca.chart
    if ch is None:
        return None
    fig = _figure(figsize)
    ax = fig.add_subplot()
    speed = ch.mesh_frequencies_hz / ca.mesh_frequency_per_rpm
    ax.plot(speed, ch.growth_rate, color="C0", lw=1.0, label="growth rate ln(max|μ|)/T")
    for reg in ch.region_table:
        lo, hi = reg["lower"] / ca.mesh_frequency_per_rpm, reg["upper"] / ca.mesh_frequency_per_rpm
        ax.axvspan(lo, hi, color="C3", alpha=0.25)
    top = float(max(ch.growth_rate.max(), 1e-9))
    c = ca.candidates
    several = ca.several_mesh_frequencies
    colour = {name: f"C{j}" if j else "k" for j, (name, _) in enumerate(ca.mesh_frequencies)}
    attributed = {str(reg["candidate"]) for reg in ch.region_table}
    for i in range(len(c)):
        group = str(c.mesh_frequency[i]) if c.mesh_frequency is not None else ""
        ax.axvline(c.rpm[i], ymin=0.9, ymax=1.0,
                   color=colour.get(group, "k") if c.allowed[i] else "0.6",
                   ls="-" if c.allowed[i] else ":", lw=0.8)
        # several mesh frequencies list many candidates: name only those of unstable regions
        if c.allowed[i] and (not several or c.full_label(i) in attributed):
            text = f"{c.label[i]} ({_short(group)})" if several else c.full_label(i)
            ax.annotate(text, (c.rpm[i], top), fontsize=6, rotation=90, va="top", ha="right",
                        color=colour.get(group, "k"))
    if several:
        for name, _ in ca.mesh_frequencies:
            ax.plot([], [], color=colour[name], lw=0.8,
                    label=f"candidates of {name} ({_short(name)})")
    ax.set_xlabel("input speed [min⁻¹]")
    ax.set_ylabel("growth rate [1/s]")
    ax.set_xlim(speed[0], speed[-1])
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    title = (f"{ca.name}: Floquet stability over speed (shaded: unstable; "
             f"{speed.size} speeds, boundaries refined)")
    if ch.method:
        title += "\n" + "\n".join(textwrap.wrap(ch.method, 110))
    ax.set_title(title, fontsize=9)
    return fig


def _short(name: str) -> str:
    """Short form of a mesh-frequency name for plot labels (``"stage 2"`` -> ``"s2"``)."""
    return f"s{name[6:]}" if name.startswith("stage ") else name


# --------------------------------------------------------------------------- document


@dataclass(frozen=True)
class Block:
    """One element of a report section.

    Attributes
    ----------
    kind : str
        ``"heading"``, ``"text"``, ``"table"`` or ``"figure"``.
    text : str
        Heading or paragraph text, table or figure caption.
    header : tuple of str
        Table header.
    rows : tuple of tuple of str
        Table rows.
    figure : callable or None
        ``figure() -> Figure | None`` building the figure on demand.
    """

    kind: str
    text: str = ""
    header: tuple[str, ...] = ()
    rows: tuple[tuple[str, ...], ...] = ()
    figure: Any = None


@dataclass(frozen=True)
class Section:
    """A report section with a stable id (the HTML anchor)."""

    id: str
    title: str
    blocks: tuple[Block, ...]


SECTION_IDS = ("parameters", "modes", "tooth-forces", "spectra", "mesh-stiffness", "sonograms",
               "resonances", "stability", "comparison", "provenance")
"""Section ids in report order (``comparison`` only with two or more cases)."""


def _table(caption: str, header: Sequence[str], rows: Sequence[Sequence[Any]]) -> Block:
    return Block("table", caption, tuple(header), tuple(tuple(str(c) for c in r) for r in rows))


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
    for ca in cases:
        s["parameters"] += [Block("heading", ca.name if ca.label in ("", ca.name)
                                  else f"{ca.name}: {ca.label}"),
                            _table(f"Gear set and run of {ca.name}", ("parameter", "value"),
                                   ca.parameters)]
        s["parameters"] += [Block("text", f"Note ({ca.name}): {n}") for n in ca.notes]
        s["modes"] += [Block("heading", ca.name), _table(
            f"Natural frequencies and mode types of {ca.name} (mean mesh stiffness; mode 1 is "
            "the rigid-body rotation, so the paper's f2, f3, ... keep their numbers)",
            ("mode", "f [Hz]", "type", "multiplicity", "dominant mesh (strain energy)"),
            ca.modes)]
        s["tooth-forces"] += [Block("figure", f"{ca.name}: normal tooth forces of the sun meshes "
                                    "over the run-up (drive flank positive).",
                                    figure=lambda ca=ca: tooth_force_figure(ca))]
        s["spectra"] += [
            Block("figure", f"{ca.name}: spectra of the planet-tooth forces over the whole "
                  "run-up; peaks labelled with their best theory candidate ('?': "
                  "unexplained; '~': ambiguous, the peak is so broad that a random peak would "
                  "match as easily).",
                  figure=lambda ca=ca: spectra_figure(ca)),
            Block("text", f"{ca.name}: candidates are the natural frequencies, 2 f_i/n and "
                  "(f_i + f_j)/n allowed by the mesh phasing; a candidate's window is the "
                  f"peak's -3 dB half-width + {100 * ca.settings.tolerance:g} % of its value; "
                  "'chance' is how often a random peak there would get a label. A peak is "
                  "ambiguous when a random one would match as easily (broad run-up humps)."),
            _table(f"Peaks of {ca.name}",
                   ("mesh", "peak", "deviation of the best [Hz]", "window [Hz]", "chance"),
                   ca.peak_rows())]
        s["sonograms"] += [
            Block("heading", ca.name),
            Block("text", _mesh_frequency_text(ca)),
            _table(f"Mesh frequency at the paper's resonance speeds ({ca.name})",
                   ("sun speed", "mesh frequency", "nearest theory values"),
                   key_speed_rows(ca)),
            Block("figure", f"{ca.name}: sonogram (rpm-frequency map) of the tooth force "
                  f"{ca.force_mesh}; speed vertical, inclined lines = mesh orders 1–"
                  f"{ca.settings.orders}"
                  + (" of every mesh frequency (" + ", ".join(
                      f"{_short(n)} = {n}" for n, _ in ca.mesh_frequencies) + ")"
                     if ca.several_mesh_frequencies else "")
                  + ", dotted vertical lines = natural frequencies, circles = forced "
                  "resonances, squares = parametric instabilities, crosses = unexplained "
                  "rises.", figure=lambda ca=ca: sonogram_figure(ca)),
            Block("figure", f"{ca.name}: rpm-order map of the same force.",
                  figure=lambda ca=ca: order_map_figure(ca))]
        res = ca.resonances
        s["resonances"] += [
            Block("heading", ca.name),
            Block("text", f"{ca.name}: {res.summary()}. Rises of at least "
                  f"{ca.settings.threshold_db:g} dB along the mesh orders 1–{ca.settings.orders} "
                  "(where the orders are resolved), along the natural frequencies and as "
                  f"isolated spots within {_SPOT_RANGE_DB:g} dB of the map maximum; "
                  f"{count(len(ca.regions), 'speed region')}. Explanations: a mesh order "
                  "crossing a natural frequency (forced resonance; tolerance "
                  f"{100 * ca.settings.tolerance:g} % of the natural frequency plus the rise "
                  "width), a Floquet-unstable band that grows in this run (parametric "
                  "instability); 'chance' is how often a random rise would get the same "
                  "explanation. In the tables 'on' is the mesh order k of the ray or f_i (along "
                  "a natural frequency)."),
            *[Block("text", f"{ca.name}: {n}") for n in res.notes
              if not n.startswith("rays analysed")],
            *([Block("text", f"{ca.name}: features of the map (median over the frames): "
                     "order-locked rays (orders of the input; k = mesh harmonic): " + (", ".join(
                         f"{o:.4g} (k = {o / (60 * ca.mesh_frequency_per_rpm):.2f})"
                         for o in ca.features.orders) or "none") + "; frequency-locked "
                     "vertical lines: " + (", ".join(
                         f"{f:.0f} Hz" for f in ca.features.frequencies) or "none") + ".")]
              if ca.features is not None else []),
            _table(f"Identified resonance regions of {ca.name}",
                   ("speed [min⁻¹]", "peak speed", "f [Hz]", "rise [dB]", "rises",
                    "mechanisms (cause)"),
                   [(f"{r.rpm_low:.0f}–{r.rpm_high:.0f}", f"{r.rpm_peak:.0f}",
                     f"{r.frequency_hz:.0f}", f"{r.strength_db:.1f}", str(r.n_spots),
                     "; ".join(r.mechanisms[:3])) for r in ca.regions]),
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
                      f"at least {_PLANET_SIGNAL_GROWTH_DB:g} dB in this run, so the difference of "
                      f"the tooth forces {ca.sun_meshes[0]} − "
                      f"{ca.sun_meshes[1]} is analysed too: it holds only the planet modes, "
                      "which in-phase mesh harmonics do not force and whose growth is too small "
                      f"to show in a single mesh force. {pr.summary()}."),
                _table(f"Planet-mode rises of {ca.name}", RISE_HEADER,
                       ca.resonance_rows(planet=True))]
        if ca.growth_rows():
            s["resonances"] += [Block(
                "text", f"{ca.name}: growth of every Floquet-unstable band during this run, "
                "exp(time in band × growth rate); a band 'develops' with at least 20 dB."),
                _table(f"Band growth in {ca.name}",
                       ("band [min⁻¹]", "candidate", "time in band [ms]", "growth rate [1/s]",
                        "growth [dB]", "verdict"), ca.growth_rows())]
        s["stability"] += [Block("heading", ca.name)]
        if ca.chart is not None:
            s["stability"] += [
                Block("figure", f"{ca.name}: Floquet stability of the linearised periodic "
                      "system over input speed; shaded = unstable.",
                      figure=lambda ca=ca: stability_figure(ca)),
                _table(f"Unstable speed intervals of {ca.name} (Floquet)",
                       ("from [min⁻¹]", "to [min⁻¹]", "width [min⁻¹]", "f_mesh [Hz]",
                        "growth [1/s]", "candidate", "mechanism"), ca.region_rows())]
        if ca.first_order:
            s["stability"] += [_table(
                f"First-order perturbation regions of {ca.name} (Hsu 1963), beside the Floquet "
                "intervals above (first order is exact only for n = 1; higher orders need "
                "Floquet)", ("region", "from [min⁻¹]", "to [min⁻¹]", "width [min⁻¹]",
                             "undamped width [min⁻¹]"), ca.first_order)]
        else:
            s["stability"] += [Block("text", f"{ca.name}: no Floquet stability chart. " + " ".join(
                n for n in ca.notes if "stability" in n or "gear-set" in n))]
        if ca.chart is not None and ca.chart.method:
            s["stability"] += [Block("text", f"{ca.name}: several mesh frequencies ("
                                     + ", ".join(f"{n} {f:.5g} Hz per min⁻¹"
                                                 for n, f in ca.mesh_frequencies)
                                     + f"); Floquet analysis: {ca.chart.method}.")]
        s["stability"] += [_table(
            f"Theory candidates of {ca.name} in the run-up range (2 f_i/n, (f_i + f_j)/n"
            + (" of every mesh frequency, [name] = the mesh frequency" if
               ca.several_mesh_frequencies else "") + ")",
            ("speed [min⁻¹]", "f_mesh [Hz]", "kind", "n", "label", "allowed"),
            ca.candidate_rows())]
        s["provenance"] += [Block("heading", ca.name),
                            _table(f"Provenance of {ca.name}", ("item", "value"),
                                   ca.provenance)]
    s["mesh-stiffness"] = [
        Block("figure", "Sum of the sun-mesh stiffnesses over three mesh cycles, each mesh at "
              "its phase (paper: case 1 oscillates between 0.8e8 and 1.3e8 N/m, case 2 is much "
              "flatter).", figure=lambda: mesh_stiffness_figure(cases)),
        _table("Summed sun-mesh stiffness", ("case", "min [N/m]", "max [N/m]",
                                             "peak-to-peak [N/m]", "source"),
               [(ca.name, f"{ca.stiffness.minimum:.4g}", f"{ca.stiffness.maximum:.4g}",
                 f"{ca.stiffness.peak_to_peak:.4g}", ca.stiffness.source)
                for ca in cases if ca.stiffness is not None])]
    for cmp in comparisons:
        s["comparison"] += [
            Block("heading", f"{cmp.other} against {cmp.reference}"),
            Block("text", cmp.verdict),
            *[Block("text", e) for e in cmp.explanation],
            _table("Statements of the paper", ("statement", "reproduced", "evidence"),
                   [(c[0], "n/a" if c[1] is None else ("yes" if c[1] else "no"), c[2])
                    for c in cmp.claims]),
            _table("Resonance regions (sonogram of the sun-mesh tooth force), matched by speed",
                   ("status", f"{cmp.reference} speeds", f"{cmp.reference} rise dB (spots)",
                    f"{cmp.other} speeds", f"{cmp.other} rise dB (spots)", "Δ dB",
                    "mechanism"), [c.row() for c in cmp.regions]),
            _table("Floquet unstable intervals, matched by overlap",
                   ("status", f"{cmp.reference} [min⁻¹] (width)",
                    f"{cmp.other} [min⁻¹] (width)", "candidate"),
                   [c.row() for c in cmp.floquet]),
            _table("Natural frequencies", ("mode", f"{cmp.reference} [Hz]", f"{cmp.other} [Hz]",
                                           "change"),
                   [(n, f"{a:.1f}", f"{b:.1f}", f"{100 * (b - a) / a:+.1f} %")
                    for n, a, b in cmp.natural_frequencies])]
    titles = {"parameters": "Gear-set parameters", "modes": "Natural frequencies and modes",
              "tooth-forces": "Tooth forces in the run-up (cf. paper Fig. 7)",
              "spectra": "Spectra of the planet-tooth forces (cf. paper Fig. 8)",
              "mesh-stiffness": "Summed sun-mesh stiffness (cf. paper Figs. 9 and 10)",
              "sonograms": "Order analysis: sonograms and order maps (cf. paper Fig. 11)",
              "resonances": "Identified resonances and instability regions",
              "stability": "Floquet stability chart and theory candidates",
              "comparison": "Comparison of the cases", "provenance": "Provenance"}
    return [Section(k, titles[k], tuple(s[k])) for k in SECTION_IDS
            if k != "comparison" or (len(cases) >= 2 and s[k])]
