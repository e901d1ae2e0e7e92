"""Order-analysis report of a measurement: :func:`analyse_measurement`, the report sections.

A measurement (:class:`analysis.measurement.Measurement`: channels, reference-shaft speed,
provenance) is analysed like a simulated run, with what a measurement has: the spectrum of a
vibration channel with identified peaks, the order spectrum with the gear set's catalogue lines,
the rpm-frequency and rpm-order maps with the gear set's mesh orders and natural frequencies,
the order-locked rays and frequency-locked lines of the map, and the rises of the map classified
as forced resonances (a mesh order crossing a natural frequency). There are no simulated
forces, stiffness tables or Floquet charts in it.

Without a gear set the report keeps what needs none -- the maps, the spectra, the orders of the
reference shaft, the rays and vertical lines of the map -- and says what is missing. Rises are
then the crossings of the reference shaft's order rays with the vertical lines the map shows.

:class:`MeasuredCase` holds every quantity once; :func:`measured_sections` turns it into the
report's sections (the HTML and PDF writers of :mod:`gearvib.report`), and
:func:`gearvib.report.crosscheck.cross_check` checks the result as for a simulation.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from analysis.cf import cf_dataset
from analysis.identification import (
    CandidateLines,
    PeakIdentification,
    catalogue_lines,
    identify_peaks,
    modal_lines,
    peak_half_widths,
)
from analysis.instability import Resonances, detect_resonances, merge_mesh_frequencies
from analysis.maps import RpmFrequencyMap, RpmOrderMap, rpm_frequency_map, rpm_order_map
from analysis.measurement import Measurement, load_measurement
from analysis.orders import OrderSpectrum, order_spectrum
from analysis.plots import rpm_frequency_map_figure, rpm_order_map_figure
from analysis.readers import ReaderError
from analysis.readers.ncimage import open_image
from analysis.runup import MapFeatures, map_features
from analysis.spectrum import Peaks, Spectrum, find_peaks, spectrum, to_db
from gearvib.assembly import assemble
from gearvib.catalogue import gear_set_catalogue
from gearvib.config import GearSet, load_description
from gearvib.fault_lines import confirmed_catalogue
from gearvib.io import atomic_write
from gearvib.modal import modal_analysis
from gearvib.report.bearings import (
    FAULT_SECTION_ID,
    FAULT_TITLE,
    comb_note,
    fault_line_blocks,
    fault_lines_of,
    rig_blocks,
)
from gearvib.report.case import (
    REGION_HEADER,
    RISE_HEADER,
    ResonanceRegion,
    crossing_table_rows,
    resonance_regions,
    rise_table_rows,
)
from gearvib.report.document import FigureImages
from gearvib.report.figures import Label, natural_frequency_lines, place_labels
from gearvib.report.html import render_html
from gearvib.report.measured_nvh import measured_levels, with_level_pages
from gearvib.report.nvh import LEVELS_SECTION_ID
from gearvib.report.pdf import write_pdf
from gearvib.report.runner import check_output_dir
from gearvib.report.sections import Block, Section
from gearvib.report.study import AnalysisSettings, check_report_size
from gearvib.report.verdict import SUMMARY_ID, readable, settings_rows
from gearvib.report.wording import count, span
from gearvib.rig import ShaftRig
from gearvib.stability import gear_set_candidates

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from gearvib.modal import ModalResult
    from gearvib.model import AssembledModel

__all__ = [
    "MEASURED_SECTION_IDS",
    "MeasuredCase",
    "MeasuredReportPaths",
    "analyse_measurement",
    "build_measured_report",
    "is_simulated_run",
    "measured_sections",
]

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

PEAK_HEADER = ("peak", "level [dB]", "best explanation", "deviation", "window", "chance")

MIN_SPEED_RATIO = 1.3
"""A record whose highest speed is below this multiple of its lowest is treated as constant
speed: no rpm maps (rays and vertical lines cannot be told apart), the spectrum is labelled
with the catalogue at the mean speed."""

_PEAKS = 12  # peaks identified per spectrum
MAX_LABEL_CHANCE = 0.25
"""A peak's label is offered as its explanation only when a random peak there would get a
label of the same family at most this often (the family's windows cover at most a quarter
of the band around the peak): harmonics of a shaft at high orders, whose windows widen with
the speed uncertainty until they cover the band, explain nothing."""
PEAK_RANGE_DB = 40.0
"""Peaks more than this below the strongest one of a spectrum are not identified."""
_DYNAMIC_RANGE_DB = 50.0
_REGION_GAP = 0.03
_MIN_FRAMES = 8


@dataclass
class MeasuredCase:
    """Everything the measured report shows (plain data; see :func:`analyse_measurement`).

    Attributes
    ----------
    name : str
        Name of the measurement (file stem).
    measurement : Measurement
        The measurement.
    channel : str
        The vibration channel analysed.
    units : str
        Its units.
    model, modal : AssembledModel, ModalResult or None
        The gear set and its modes (None without ``--gearset``).
    gearset_name : str
        Name of the gear set ("" without).
    reference_member : str
        Member whose speed the measurement's reference is ("" without a gear set).
    input_per_reference : float
        Input speed per reference speed (1 when the reference is the input).
    natural_frequencies_hz : ndarray
        Elastic natural frequencies of the model [Hz] (empty without a gear set).
    mode_names : list of str
        ``f2, f3, ...`` (mode 1 the rigid-body rotation).
    mesh_groups : list of (str, float, int)
        Per mesh frequency: name, Hz per min⁻¹ of the reference shaft, orders drawn.
    catalogue : KinematicCatalogue or None
        Kinematic lines (orders of the reference shaft).
    spectrum, peaks, identification
        Spectrum of the channel over the record, its strongest peaks and their explanations.
    order_spectrum, order_peaks, order_identification
        The same on the order axis (None when the order spectrum is not available).
    fmap, omap : maps or None
        Rpm-frequency and rpm-order maps (None at constant speed).
    features : MapFeatures or None
        Order-locked rays and frequency-locked lines of the map.
    resonances : Resonances or None
        Rises of the map, classified.
    regions : list of ResonanceRegion
        The rises grouped by speed.
    frequency_max_hz : float
        Upper frequency of spectrum and map.
    speed_range : (float, float)
        Lowest and highest reference speed [min⁻¹].
    varying_speed : bool
        Highest speed at least :data:`MIN_SPEED_RATIO` times the lowest.
    notes : list of str
        What the report could not do, and why.
    provenance : list of (str, str)
        File, format, reader, channels, reference, settings.
    rig : ShaftRig or None
        The machine, when it was described as shafts and bearings without gears.
    fault_lines : FaultLines or None
        Bearing and gear-fault families checked in the envelope and order spectra
        (:mod:`gearvib.report.bearings`).
    """

    name: str
    measurement: Measurement
    channel: str
    units: str
    model: AssembledModel | None
    modal: ModalResult | None
    gearset_name: str
    reference_member: str
    input_per_reference: float
    natural_frequencies_hz: np.ndarray
    mode_names: list[str]
    mesh_groups: list[tuple[str, float, int]]
    catalogue: Any
    spectrum: Spectrum
    peaks: Peaks
    identification: PeakIdentification
    order_spectrum: OrderSpectrum | None
    order_peaks: Peaks | None
    order_identification: PeakIdentification | None
    fmap: RpmFrequencyMap | None
    omap: RpmOrderMap | None
    features: MapFeatures | None
    resonances: Resonances | None
    regions: list[ResonanceRegion]
    frequency_max_hz: float
    speed_range: tuple[float, float]
    varying_speed: bool
    settings: AnalysisSettings
    notes: list[str] = field(default_factory=list)
    provenance: list[tuple[str, str]] = field(default_factory=list)
    rig: ShaftRig | None = None
    fault_lines: Any = None

    @property
    def has_gearset(self) -> bool:
        """True when a gear set was given."""
        return self.model is not None

    # ------------------------------------------------------------------ table rows

    def channel_rows(self) -> list[tuple[str, ...]]:
        """One row per channel of the measurement: name, units, description, role."""
        m = self.measurement
        ref = m.source.get("reference_channel")
        rows = []
        for k, v in m.signals.data_vars.items():
            role = ("speed reference" if k == ref else
                    "analysed" if k == self.channel else
                    "vibration" if k in m.vibration_channels else "not analysed")
            rows.append((str(k), str(v.attrs.get("units", "")),
                         str(v.attrs.get("long_name", k)), role))
        return rows

    def measurement_rows(self) -> list[tuple[str, str]]:
        """The record: file, format, duration, sample rate, speed reference and range."""
        m = self.measurement
        t = m.time
        lo, hi = self.speed_range
        rows = [("file", str(m.source.get("file") or "(in memory)")),
                ("format", str(m.source.get("format", ""))),
                ("kind", str(m.source.get("kind", ""))),
                ("record", f"{t.size} samples at {m.fs:g} Hz, {t[-1] - t[0] + 1 / m.fs:.4g} s"),
                ("analysed channel", f"{self.channel} [{self.units}]"),
                ("speed reference", m.reference),
                ("reference speed", span(lo, hi, "min⁻¹")
                 + ("" if self.varying_speed else " (constant speed: no rpm maps)"))]
        if m.accuracy.get("rms_angle_error_rad"):
            rows.append(("speed accuracy", f"rms angle error "
                         f"{m.accuracy['rms_angle_error_rad']:.3g} rad (estimate)"))
        return rows

    def gearset_rows(self) -> list[tuple[str, str]]:
        """Gear set, reference shaft, mesh frequencies."""
        if self.model is None:
            return []
        rows = [("gear set", self.gearset_name),
                ("reference shaft", f"{self.reference_member} (input speed = "
                 f"{self.input_per_reference:.6g} × reference speed)")]
        for name, f, k in self.mesh_groups:
            rows.append((f"mesh frequency ({name})",
                         f"{f:.6g} Hz per min⁻¹ of the reference ({60 * f:.4g} orders); "
                         f"orders 1–{k} drawn"))
        rows.append(("degrees of freedom", f"{self.model.n_dof} "
                     f"({count(self.model.n_mesh, 'mesh', 'meshes')})"))
        return rows

    def mode_rows(self) -> list[tuple[str, ...]]:
        """Natural frequencies with their type and dominant mesh (strain energy)."""
        if self.modal is None:
            return []
        rows = []
        modal = self.modal
        for i, (f, kind) in enumerate(zip(modal.frequencies_hz, modal.kinds, strict=True)):
            if kind == "rigid-body":
                continue
            e = modal.mesh_energy[i] if modal.mesh_energy.size else np.zeros(0)
            dom = (f"{modal.mesh_names[int(np.argmax(e))]} ({100 * float(np.max(e)):.0f} %)"
                   if e.size and float(np.max(e)) > 0 else "–")
            rows.append((f"f{i + 1}", f"{f:.1f}", str(kind), dom))
        return rows

    def _peak_rows(self, ident: PeakIdentification | None, peaks: Peaks | None,
                   sp: Spectrum | None, unit: str) -> list[tuple[str, ...]]:
        if ident is None or peaks is None or sp is None:
            return []
        lv = to_db(peaks.amplitude, sp.amplitude)
        rows = []
        for i in range(len(ident)):
            ms = ident.matches[i]
            status = str(ident.status[i])
            head = (f"{ident.peaks[i]:.4g}" if unit == "order" else
                    f"{ident.peaks[i]:.0f} Hz" if ident.peaks[i] >= 100 else
                    f"{ident.peaks[i]:.3g} Hz")
            if unit == "order":
                head = f"order {head}"
            if not ms:
                best, dev, win = "unexplained", "–", "–"
            else:
                exprs = [m.expression.split(" ≈ ")[0] for m in ms[:2]]
                more = f" (+{len(ms) - 2} more)" if len(ms) > 2 else ""
                if status == "explained":
                    best = " ≈ ".join(exprs) + more
                    dev = f"{ms[0].deviation:+.3g}"
                    win = f"± {ms[0].tolerance:.3g}"
                else:  # chance-level candidates are not offered as explanations
                    best = (f"unexplained ({ms[0].family} lines would match "
                            f"{100 * ms[0].coincidence:.0f} % of random peaks here)")
                    dev, win = "–", "–"
            rows.append((head, f"{lv[i]:.1f}", best, dev, win,
                         f"{100 * ident.coincidence[i]:.0f} %"))
        return rows

    def peak_rows(self) -> list[tuple[str, ...]]:
        """Rows of the frequency-peak table."""
        return self._peak_rows(self.identification, self.peaks, self.spectrum, "Hz")

    def order_peak_rows(self) -> list[tuple[str, ...]]:
        """Rows of the order-peak table."""
        os_ = self.order_spectrum
        return self._peak_rows(self.order_identification, self.order_peaks,
                               os_.spectrum if os_ is not None else None, "order")

    def resonance_rows(self) -> list[tuple[str, ...]]:
        """Rows of the rise table (:data:`gearvib.report.case.RISE_HEADER`)."""
        r = self.resonances
        if r is None:
            return []
        groups = r.groups
        several = len(self.mesh_groups) > 1

        def on_order(i: int) -> str:
            if not self.has_gearset:
                return str(groups[i])
            return f"k={r.order[i]}" + (f" ({groups[i]})" if groups[i] and several else "")

        return rise_table_rows(r, on_order)

    def region_table_rows(self) -> list[tuple[str, ...]]:
        """Rows of the resonance-region table."""
        return [r.table_row() for r in self.regions]

    def crossing_rows(self) -> list[tuple[str, ...]]:
        """Predicted crossings of the mesh (or shaft) orders with the natural frequencies."""
        if self.resonances is None:
            return []
        return crossing_table_rows(self.resonances.crossings, lambda c: (
            f"{c.harmonic} × f_mesh = {c.mode}" if self.has_gearset else f"{c.group} = {c.mode}"))

    def to_dataset(self) -> xr.Dataset:
        """Spectrum, order spectrum and peak identification as one CF Dataset."""
        sp = self.spectrum
        ds = xr.Dataset(
            {"spectrum": ("frequency", np.asarray(sp.values, dtype=float),
                          {"units": sp.units, "long_name": f"{sp.amplitude} spectrum of "
                           f"{self.channel}"})},
            coords={"frequency": ("frequency", sp.frequency, {"units": "Hz",
                                                               "long_name": "frequency"})},
            attrs={"measurement": self.name, "speed_reference": self.measurement.reference,
                   "gear_set": self.gearset_name or "(none)"})
        if self.order_spectrum is not None:
            os_ = self.order_spectrum
            ds["order_spectrum"] = xr.DataArray(
                np.asarray(os_.values, dtype=float), dims="order",
                coords={"order": ("order", os_.order, {"units": "1",
                                                       "long_name": "order of the reference "
                                                       "shaft"})},
                attrs={"units": os_.units, "long_name": f"{os_.amplitude} order spectrum"})
        return cf_dataset(ds, title="measured run-up", producer="gearvib.report.measured")


# --------------------------------------------------------------------------- computation


def _load_gearset(gearset: Any):
    """A GearSet or a ShaftRig from a path, a preset or rig name, or the object (None stays
    None)."""
    if gearset is None:
        return None

    if isinstance(gearset, GearSet | ShaftRig):
        return gearset
    return load_description(str(gearset))


def _reference_member(model: AssembledModel, m: Measurement, reference: str | None
                      ) -> tuple[str, float, str]:
    """The member the speed reference measures, and input speed per reference speed."""
    ratios = dict(model.kinematic_ratios)
    note = ""
    if reference is None:
        ch = m.source.get("reference_channel")
        member = (str(m.signals[ch].attrs.get("member", "")) if ch in m.signals.data_vars
                  else "")
        if member and member in ratios:
            reference = member
        else:
            reference = model.input_member
            note = (f"the speed reference is taken as the speed of the input member "
                    f"{model.input_member!r} (give --reference MEMBER if it measures another "
                    "shaft)")
    if reference not in ratios or ratios[reference] == 0:
        raise ValueError(f"reference = {reference!r} is not a rotating member of the gear set; "
                         f"admissible: {sorted(k for k, v in ratios.items() if v)}")
    return reference, 1.0 / abs(float(ratios[reference])), note


def _segment(n: int, fs: float, resolution_hz: float) -> int:
    """Samples per Hann segment for a resolution bandwidth, within the record."""
    seg = round(1.5 * fs / resolution_hz)
    return int(max(16, min(n, seg)))


def analyse_measurement(measurement: Measurement, *, gearset: Any = None,
                        channel: str | None = None, reference: str | None = None,
                        settings: AnalysisSettings | None = None,
                        name: str | None = None, envelope_band: Any = None,
                        min_bandwidth: float | None = None) -> MeasuredCase:
    """Compute the content of a measured report.

    Parameters
    ----------
    measurement : Measurement
        From :func:`analysis.measurement.load_measurement`.
    gearset : path, preset name, GearSet or ShaftRig, optional
        The gear set the measurement comes from, or a machine without gears
        (``type = "shafts"``: shafts and rolling bearings, :mod:`gearvib.rig`); without it
        the report shows what needs no model (maps, spectra, orders of the reference shaft).
    channel : str, optional
        Vibration channel (default: the measurement's first).
    reference : str, optional
        Member whose speed the reference measures (default: the tacho's ``member`` attribute
        when it names a member of the gear set, else the input member).
    settings : AnalysisSettings, optional
        ``map_resolution_hz``, ``map_overlap``, ``threshold_db``, ``tolerance``, ``n_max``,
        ``frequency_max_hz``, ``orders`` (default :class:`AnalysisSettings`).
    name : str, optional
        Report name of the measurement (default: the file stem).
    envelope_band : (float, float), optional
        Band [Hz] demodulated for the fault lines (default: the fast kurtogram's choice).
    min_bandwidth : float, optional
        Narrowest band [Hz] the kurtogram may choose (default: twice the highest fault line
        checked, :mod:`gearvib.fault_lines`).

    Returns
    -------
    MeasuredCase
    """
    st = settings or AnalysisSettings()
    m = measurement
    x = m.channel(channel)
    check_report_size(m.time.size, m.fs, st, f"the measurement {name or m.name!r}")
    ch = str(x.name)
    units = str(x.attrs.get("units", "1"))
    t = m.time
    fs = m.fs
    rpm = np.asarray(m.speed_rpm.values, dtype=float)
    lo, hi = float(rpm.min()), float(rpm.max())
    varying = hi >= MIN_SPEED_RATIO * max(lo, 1e-300)
    notes: list[str] = []
    gs = _load_gearset(gearset)
    rig = gs if isinstance(gs, ShaftRig) else None
    if rig is not None:
        gs = None
    model = modal = cat = None
    fn = np.zeros(0)
    names: list[str] = []
    groups: list[tuple[str, float, int]] = []
    ref_member, in_per_ref = "", 1.0
    if gs is not None:

        model = assemble(gs)
        modal = modal_analysis(model)
        keep = np.array([k != "rigid-body" for k in modal.kinds], dtype=bool)
        fn = modal.frequencies_hz[keep]
        names = [f"f{i + 1}" for i in np.flatnonzero(keep)]
        ref_member, in_per_ref, why = _reference_member(model, m, reference)
        if why:
            notes.append(why)
        cat = gear_set_catalogue(gs, model=model, reference=ref_member, mesh_harmonics=7,
                                 harmonics=3, sidebands=2)
        fmax_auto = min(0.5 * fs, max(2.2 * float(fn.max()) if fn.size else 0.0,
                                      0.25 * fs))
    elif rig is not None:
        ref_member, in_per_ref, why = _rig_reference(rig, m, reference)
        if why:
            notes.append(why)
        cat = rig.catalogue(reference=ref_member, harmonics=3)
        fmax_auto = 0.5 * fs
        notes.append(f"{rig.name} is a machine without gears (shafts and rolling bearings): no "
                     "mesh orders or natural frequencies; peaks are compared with the shaft "
                     "harmonics and the bearing lines")
    else:
        if reference is not None:
            raise ValueError("reference applies with a description (--gearset)")
        fmax_auto = 0.5 * fs
        notes.append("no gear set given (--gearset CONFIG): no mesh orders, catalogue lines or "
                     "natural frequencies; orders are those of the reference shaft, and rises "
                     "are classified against the order rays and vertical lines the map shows")
    fmax = min(st.frequency_max_hz or fmax_auto, 0.5 * fs)
    if gs is not None:
        for g in model.mesh_frequency_groups():
            f_ref = float(g.frequency_per_rpm) * in_per_ref
            # every mesh order inside the map down to a quarter of the top speed
            k = st.orders or int(np.clip(math.ceil(fmax / max(f_ref * max(lo, 0.25 * hi),
                                                              1e-300)), 3, 20))
            groups.append((str(g.name), f_ref, k))

    # bearing and gear-fault lines at their own positions (envelope and order spectra); a
    # bearing line labels a peak only when its family is detected there
    bearings = rig.bearings() if rig is not None else (gs.bearings() if gs is not None else [])
    fault = fault_lines_of(m, cat, bearings, channel=ch, band=envelope_band,
                           min_bandwidth=min_bandwidth, notes=notes)
    label_cat = confirmed_catalogue(cat, fault) if cat is not None else None

    # spectrum over the record, peaks identified against frequency-locked lines (natural
    # frequencies) and, at constant speed, the catalogue at the mean speed
    # about 4096 lines, at least four segments to average
    seg = _segment(t.size, fs, max(1.5 * fs / 4096, 1.5 * fs / max(t.size // 4, 16)))
    sp = spectrum(x, window="hann", amplitude="rms", segment_length=seg, name=ch)
    band = sp.frequency <= fmax
    pk = find_peaks(sp, prominence_db=6.0, max_peaks=_PEAKS,
                    min_distance_hz=3 * sp.bin_spacing_hz)
    keep_pk = (pk.frequency > 2 * sp.bin_spacing_hz) & (pk.frequency <= fmax)
    pk = _select_peaks(pk, keep_pk)
    # order spectrum: peaks against the catalogue (orders of the reference shaft)
    ospec = opk = oident = None
    nyq_order = 0.95 * 0.5 * fs * 60.0 / max(hi, 1e-300)
    top_order = max((k * 60 * f for _, f, k in groups), default=0.0)
    max_order = min(nyq_order, 1.1 * top_order) if top_order else min(nyq_order, 60.0)
    ref_kw = ({"angle": m.angle.values} if m.angle is not None else {"rpm": rpm})
    try:
        res_o = max(0.05, 1.5 / max(1.0, _revolutions(m)) * 4)
        ospec = order_spectrum(x.values, fs, **ref_kw, window="hann", amplitude="rms",
                               resolution=res_o, max_order=max_order,
                               samples_per_rev=2 * math.ceil(1.28 * max_order),
                               units=units, name=ch)
        osp = ospec.spectrum
        opk = find_peaks(osp, prominence_db=6.0, max_peaks=_PEAKS,
                         min_distance_hz=3 * osp.bin_spacing_hz)
        opk = _select_peaks(opk, (opk.order > 0.5) & (opk.order <= max_order))
        olines = ([catalogue_lines(label_cat, axis="order", speed_uncertainty=2e-3)]
                  if model is not None else [_shaft_lines(1.0, max_order, "order")])
        if rig is not None and _BEARING_FAMILIES & set(label_cat.family):
            olines.append(catalogue_lines(label_cat, axis="order", speed_uncertainty=2e-3,
                                          families=_BEARING_FAMILIES))
        ow = peak_half_widths(ospec.order, to_db(ospec.values, ospec.amplitude),
                              opk.order) if len(opk) else None
        oident = identify_peaks(opk.order, olines, resolution=ospec.enbw_orders,
                                peak_widths=ow, band=(0.0, max_order),
                                max_coincidence=MAX_LABEL_CHANCE)
    except ValueError as exc:
        notes.append(f"order spectrum not available: {exc}")

    # maps, features, resonances
    fmap = omap = None
    features = None
    resonances = None
    if varying:
        res_hz = max(st.map_resolution_hz, 1.5 * fs * _MIN_FRAMES / t.size)
        fmap = rpm_frequency_map(x.values, fs, rpm, resolution=res_hz, window="hann",
                                 overlap=st.map_overlap, amplitude="rms", units=units,
                                 name=ch)
        try:
            omap = rpm_order_map(x.values, fs, **ref_kw, window="hann", overlap=st.map_overlap,
                                 amplitude="rms", resolution=max(res_o, 0.5),
                                 max_order=max_order,
                                 samples_per_rev=2 * math.ceil(1.28 * max_order), units=units,
                                 name=ch)
        except ValueError as exc:
            notes.append(f"rpm-order map not available: {exc}")
        map_ds = fmap.to_dataset().sel(frequency=slice(0.0, fmax))
        frame_rpm = np.asarray(map_ds["rpm"].values)
        try:
            features = map_features(map_ds, frames=frame_rpm > 0.02 * float(frame_rpm.max()))
        except ValueError as exc:
            notes.append(f"rays and vertical lines not separated: {exc}")
        resonances = _resonances(map_ds, features, fn, names, groups, t, rpm, st, fmax, notes,
                                 model, modal, (lo, hi), in_per_ref)
    else:
        notes.append(f"the reference speed is {span(lo, hi, 'min⁻¹')}, its highest less than "
                     f"{MIN_SPEED_RATIO:g} times its lowest: no rpm maps and no resonance "
                     "classification; the spectra show the record")
    lines: list[CandidateLines] = []
    if fn.size:
        lines.append(modal_lines(fn, names=names, kinds=("natural",),
                                 uncertainty=st.tolerance))
    mean_rpm = float(np.mean(rpm))
    if cat is not None and not varying and (rig is None
                                            or _BEARING_FAMILIES & set(label_cat.family)):
        lines.append(catalogue_lines(label_cat, speed_rpm=mean_rpm, axis="frequency",
                                     speed_uncertainty=max(1e-3, (hi - lo) / max(hi, 1e-300)),
                                     families=_BEARING_FAMILIES if rig is not None else None))
    if not varying and model is None:
        lines.append(_shaft_lines(mean_rpm / 60.0, fmax, "frequency"))
    if varying and not fn.size and features is not None and np.size(features.frequencies):
        lines.append(_map_lines(features, st.tolerance))
    widths = peak_half_widths(sp.frequency[band], to_db(sp.values[band], sp.amplitude),
                              pk.frequency) if len(pk) else None
    if not lines:
        notes.append("the spectrum is taken over a varying speed and there is neither a gear "
                     "set nor a frequency-locked line in the map: its peaks are listed "
                     "unexplained (read them in the maps)")
        lines.append(_shaft_lines(1e9, 1.0, "frequency"))  # one line far outside the band
    ident = identify_peaks(pk.frequency, lines, resolution=sp.enbw_hz, peak_widths=widths,
                           band=(0.0, fmax), max_coincidence=MAX_LABEL_CHANCE)
    regions = (resonance_regions(resonances, rpm_gap=_REGION_GAP * hi)
               if resonances is not None else [])
    prov = [("measurement", name or m.name),
            ("file", str(m.source.get("file") or "(in memory)")),
            ("format", str(m.source.get("format", ""))),
            ("reader", str(m.source.get("reader", ""))),
            ("channels", ", ".join(m.source.get("channels", []))),
            ("speed reference", m.reference),
            ("gear set" if rig is None else "machine (shafts and bearings)",
             (f"{(model or rig).meta.get('name', '')}"
              + (f" ({gearset})" if isinstance(gearset, str | os.PathLike) else "")
              if model is not None or rig is not None else "(none)")),
            *settings_rows(st, ("map_resolution_hz", "map_overlap", "threshold_db",
                                "tolerance", "n_max", "orders", "frequency_max_hz",
                                "cut_orders", "order_resolution")),
            ("spectrum", f"Hann, RBW {sp.enbw_hz:.3g} Hz, {sp.n_averages} averages, rms")]
    if fmap is not None:
        prov.append(("map", f"{fmap.window}, RBW {fmap.resolution_hz:.3g} Hz, overlap "
                            f"{fmap.overlap:g}, {fmap.time.size} frames"))
    if m.source.get("kind") == "simulation":
        prov.append(("simulated run", str(m.source.get("title", ""))))
    if m.source.get("stated"):
        prov.append(("stated by the user", readable(dict(sorted(m.source["stated"].items())))))
    if fault is not None:
        b = fault.envelope.band
        prov.append(("envelope analysis", f"band {b.low:.6g}-{b.high:.6g} Hz ("
                     + ("fast kurtogram, min_bandwidth "
                        f"{fault.min_bandwidth:.6g} Hz" if fault.kurtogram is not None
                        else "given") + f"), {fault.domain} axis"))
    return MeasuredCase(
        name=name or m.name, measurement=m, channel=ch, units=units, model=model, modal=modal,
        gearset_name=(str(model.meta.get("name", "")) if model is not None else
                      rig.name if rig is not None else ""),
        reference_member=ref_member, input_per_reference=in_per_ref,
        natural_frequencies_hz=fn, mode_names=names, mesh_groups=groups, catalogue=cat,
        spectrum=sp, peaks=pk, identification=ident, order_spectrum=ospec, order_peaks=opk,
        order_identification=oident, fmap=fmap, omap=omap, features=features,
        resonances=resonances, regions=regions, frequency_max_hz=fmax, speed_range=(lo, hi),
        varying_speed=varying, settings=st, notes=notes, provenance=prov, rig=rig,
        fault_lines=fault)


_BEARING_FAMILIES = frozenset(("bearing_ftf", "bearing_bpfo", "bearing_bpfi", "bearing_bsf"))


def _rig_reference(rig: ShaftRig, m: Measurement, reference: str | None
                   ) -> tuple[str, float, str]:
    """The shaft the speed reference measures (default: the tacho's member when it names a
    shaft, else the input shaft) and the input speed per reference speed."""
    ratios = rig.kinematic_ratios
    note = ""
    if reference is None:
        ch = m.source.get("reference_channel")
        member = (str(m.signals[ch].attrs.get("member", "")) if ch in m.signals.data_vars
                  else "")
        reference = member if member in ratios else rig.input
        if member not in ratios and len(ratios) > 1:
            note = (f"the speed reference is taken as the speed of the input shaft "
                    f"{rig.input!r} (give --reference SHAFT if it measures another shaft)")
    if reference not in ratios:
        raise ValueError(f"reference = {reference!r} is not a shaft of the machine; "
                         f"admissible: {sorted(ratios)}")
    return reference, 1.0 / abs(float(ratios[reference])), note


def _revolutions(m: Measurement) -> float:
    """Revolutions of the reference shaft over the record."""
    return float(np.trapezoid(m.speed_rpm.values, m.time) / 60.0)


def _select_peaks(pk: Peaks, keep: np.ndarray, scaling: str = "rms") -> Peaks:
    """The peaks where ``keep`` is true and within :data:`PEAK_RANGE_DB` of the strongest."""

    if keep.any():
        lv = to_db(pk.amplitude, scaling)
        keep = keep & (lv >= float(np.max(lv[keep])) - PEAK_RANGE_DB)

    return replace(pk, frequency=pk.frequency[keep], amplitude=pk.amplitude[keep],
                   **{k: getattr(pk, k)[keep] for k in ("bin_frequency", "bin_value")
                      if hasattr(pk, k) and np.ndim(getattr(pk, k)) == 1
                      and getattr(pk, k).size == keep.size})


def _shaft_lines(base: float, top: float, axis: str) -> CandidateLines:
    """Harmonics ``k × base`` up to ``top`` (the reference shaft's orders)."""
    k = np.arange(1, max(2, int(top / base) + 1))
    expr = [f"{i} × f_ref" if axis == "frequency" else f"shaft order {i}" for i in k]
    return CandidateLines(value=k * base, family=np.full(k.size, "shaft", dtype=object),
                          expression=np.asarray(expr, dtype=object),
                          uncertainty=np.full(k.size, 2e-3),
                          locked=np.full(k.size, "order", dtype=object), axis=axis)


def _map_lines(features: MapFeatures, tolerance: float) -> CandidateLines:
    """The frequency-locked lines of a map as candidate lines (family ``map line``)."""
    f = np.asarray(features.frequencies, dtype=float)
    return CandidateLines(value=f, family=np.full(f.size, "map line", dtype=object),
                          expression=np.asarray([f"line {v:.0f} Hz of the map" for v in f],
                                                dtype=object),
                          uncertainty=np.full(f.size, tolerance),
                          locked=np.full(f.size, "frequency", dtype=object), axis="frequency")


def _ray_causes(res: Resonances) -> Resonances:
    """Causes of rises on the map's rays named after the ray: ``order 76.87 = line 3013 Hz``."""

    cause = np.asarray([re.sub(r"^1 f_mesh = (.*) \[(order [^\]]+)\]$", r"\2 = \1", str(c))
                        for c in res.cause], dtype=object)
    return replace(res, cause=cause)


def _resonances(map_ds: xr.Dataset, features: MapFeatures | None, fn: np.ndarray,
                names: list[str], groups: list[tuple[str, float, int]], t: np.ndarray,
                rpm: np.ndarray, st: AnalysisSettings, fmax: float, notes: list[str],
                model: Any, modal: Any, span: tuple[float, float], in_per_ref: float
                ) -> Resonances | None:
    """Rises of the map, classified per mesh frequency (or per shaft order without a model)."""
    hop = float(np.median(np.abs(np.diff(map_ds["rpm"].values)))) if map_ds.sizes["time"] > 1 \
        else 0.0
    if fn.size:

        cands = gear_set_candidates(model, modal, n_max=st.n_max,
                                    speed_range=(span[0] * in_per_ref, span[1] * in_per_ref))
        f_lo = 0.15 * float(fn.min())
        parts = []
        for name, f_ref, k in groups:
            parts.append((name, detect_resonances(
                map_ds, natural_frequencies_hz=fn, mesh_frequency_per_rpm=f_ref,
                orders=range(1, k + 1), names=names,
                candidates=cands if len(groups) == 1 and in_per_ref == 1.0 else None,
                features=features, speed_profile=(t, rpm), threshold_db=st.threshold_db,
                natural_uncertainty=max(st.tolerance, 0.05), dynamic_range_db=40.0,
                frequency_range=(f_lo, fmax))))
        notes.append("parametric instabilities are judged by the theory candidates alone (a "
                     "measured report has no Floquet chart); rises on a mesh order at a "
                     "natural frequency are forced resonances")
        return merge_mesh_frequencies(parts, rpm_tolerance=1.5 * hop + 1e-9,
                                      frequency_tolerance=1.5 * float(
                                          map_ds.attrs.get("resolution_hz", 1.0)))
    if features is None or not np.size(features.frequencies):
        notes.append("no gear set and no frequency-locked line in the map: rises are not "
                     "classified")
        return None
    lines = np.asarray(features.frequencies, dtype=float)
    rays = _rays(features)
    if not rays:
        notes.append("no gear set and no order-locked ray in the map: rises are not "
                     "classified")
        return None
    parts = [(f"order {o:.4g}", detect_resonances(
        map_ds, natural_frequencies_hz=lines, mesh_frequency_per_rpm=o / 60.0, orders=[1],
        names=[f"line {f:.0f} Hz" for f in lines], speed_profile=(t, rpm),
        threshold_db=st.threshold_db, natural_uncertainty=max(st.tolerance, 0.05),
        dynamic_range_db=40.0, frequency_range=(0.5 * float(lines.min()), fmax)))
        for o in rays]
    return _ray_causes(merge_mesh_frequencies(parts, rpm_tolerance=1.5 * hop + 1e-9,
                                              frequency_tolerance=1.5 * float(
                                                  map_ds.attrs.get("resolution_hz", 1.0))))


MAX_RAYS = 8
"""Without a gear set, at most this many order rays of the map (the strongest) are used."""


def _rays(features: MapFeatures | None) -> list[float]:
    """Orders of the strongest rays of the map (>= 0.5), at most :data:`MAX_RAYS`, sorted."""
    if features is None or not np.size(features.orders):
        return []
    o = np.asarray(features.orders, dtype=float)
    s = np.asarray(features.order_strength_db, dtype=float)
    keep = np.flatnonzero(o >= 0.5)
    keep = keep[np.argsort(s[keep])[::-1][:MAX_RAYS]]
    return sorted(float(x) for x in o[keep])


# --------------------------------------------------------------------------- figures


def _figure(figsize: tuple[float, float]) -> Figure:
    from matplotlib.figure import Figure

    return Figure(figsize=figsize, layout="constrained", dpi=100)


def record_figure(mc: MeasuredCase, figsize: tuple[float, float] = (8.0, 3.8)) -> Figure:
    """The analysed channel over time with the reference speed on a second axis."""
    fig = _figure(figsize)
    ax = fig.subplots()
    m = mc.measurement
    t = m.time
    stride = max(1, t.size // 20000)
    ax.plot(t[::stride], m.channel(mc.channel).values[::stride], lw=0.5, color="C0",
            label=mc.channel)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(f"{mc.channel} [{mc.units}]")
    ax.grid(True, alpha=0.3)
    ax2 = ax.twinx()
    ax2.plot(t[::stride], m.speed_rpm.values[::stride], color="k", lw=1.0, ls="--",
             label="reference speed")
    ax2.set_ylabel("reference speed [min⁻¹]")
    ax.legend(loc="upper left", fontsize=7)
    ax2.legend(loc="lower right", fontsize=7)
    fig.suptitle(f"{mc.name}: channel {mc.channel} and the reference speed", fontsize=10)
    return fig


def _short(ident: PeakIdentification, i: int, unit: str) -> str:
    head = f"{ident.peaks[i]:.3g}" if unit == "order" else f"{ident.peaks[i]:.0f}"
    st = str(ident.status[i])
    ms = ident.matches[i]
    if st == "explained":
        return f"{head}\n≈ {ms[0].expression.split(' ≈ ')[0]}"
    return f"{head}\n" + ("?" if st == "unexplained" else "~")


def spectra_figure(mc: MeasuredCase, figsize: tuple[float, float] = (8.0, 6.4)) -> Figure:
    """Spectrum (top) and order spectrum (bottom) with the strongest peaks labelled."""
    n = 2 if mc.order_spectrum is not None else 1
    fig = _figure((figsize[0], figsize[1] if n == 2 else 3.4))
    axes = fig.subplots(n, 1, squeeze=False)[:, 0]
    sp = mc.spectrum
    band = sp.frequency <= mc.frequency_max_hz
    ax = axes[0]
    ax.plot(sp.frequency[band], to_db(sp.values[band], sp.amplitude), lw=0.7)
    for f in mc.natural_frequencies_hz:
        if f <= mc.frequency_max_hz:
            ax.axvline(f, color="C1", lw=0.7, ls=":")
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo, hi + 0.3 * (hi - lo))
    ax.set_xlim(0, mc.frequency_max_hz)
    ax.set_xlabel("frequency [Hz]" + ("  (dotted: natural frequencies of the model)"
                                      if mc.natural_frequencies_hz.size else ""))
    ax.set_ylabel(f"rms level\n[dB re 1 {mc.units}]")
    ax.set_title(f"spectrum over the record: Hann, RBW {sp.enbw_hz:.3g} Hz, "
                 f"{sp.n_averages} averages", fontsize=9)
    ax.grid(True, alpha=0.3)
    labelled = []
    if len(mc.peaks):
        y = to_db(mc.peaks.amplitude, sp.amplitude)
        ax.plot(mc.peaks.frequency, y, "v", color="C3", ms=4)
        labelled.append((ax, mc.peaks.frequency, y,
                         [_short(mc.identification, i, "Hz") for i in range(len(mc.peaks))]))
    if n == 2:
        os_ = mc.order_spectrum
        ax = axes[1]
        ax.plot(os_.order, to_db(os_.values, os_.amplitude), lw=0.7, color="C2")
        for _, f_ref, k in mc.mesh_groups:
            for j in range(1, k + 1):
                if 60 * f_ref * j <= os_.order[-1]:
                    ax.axvline(60 * f_ref * j, color="0.5", lw=0.6, ls="--")
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi + 0.3 * (hi - lo))
        ax.set_xlim(0, float(os_.order[-1]))
        ax.set_xlabel("order of the reference shaft" + ("  (dashed: mesh orders)"
                                                        if mc.mesh_groups else ""))
        ax.set_ylabel(f"rms level\n[dB re 1 {mc.units}]")
        ax.set_title(f"order spectrum: Hann, RBW {os_.resolution_orders:.3g} orders, "
                     f"{os_.n_averages} averages", fontsize=9)
        ax.grid(True, alpha=0.3)
        if mc.order_peaks is not None and len(mc.order_peaks):
            y = to_db(mc.order_peaks.amplitude, os_.spectrum.amplitude)
            ax.plot(mc.order_peaks.order, y, "v", color="C3", ms=4)
            labelled.append((ax, mc.order_peaks.order, y,
                             [_short(mc.order_identification, i, "order")
                              for i in range(len(mc.order_peaks))]))
    fig.suptitle(f"{mc.name}: {mc.channel} ('?' unexplained, '~' only chance-level labels)",
                 fontsize=10)

    items = []
    for a, xs, ys, texts in labelled:
        for i in np.argsort(ys)[::-1][:6]:
            items.append((a, Label(texts[i], (float(xs[i]), float(ys[i])),
                                   ((0, 4), (14, 4), (-14, 4), (0, 16)),
                                   {"ha": "center", "va": "bottom", "fontsize": 6.5})))
    place_labels(fig, None, items)
    return fig


def sonogram_figure(mc: MeasuredCase, figsize: tuple[float, float] = (7.5, 6.2)
                    ) -> Figure | None:
    """Rpm-frequency map with the mesh orders (or shaft orders) and natural frequencies."""
    if mc.fmap is None:
        return None

    fig = rpm_frequency_map_figure(mc.fmap, hz_per_rpm=(), orders=(),
                                   dynamic_range_db=_DYNAMIC_RANGE_DB,
                                   frequency_max=mc.frequency_max_hz, figsize=figsize)
    ax = fig.axes[0]
    lo, hi = ax.get_ylim()
    fmax = ax.get_xlim()[1]
    labels = []
    styles = (("w", "--"), ("#00e5ff", "-"), ("#ff66ff", "-."), ("#ffd400", ":"))
    fams = list(mc.mesh_groups)
    if fams:
        order_lists = [list(range(1, k + 1)) for _, _, k in fams]
    else:  # without a gear set: the rays the map shows, at their measured orders
        fams = [(f"order {o:.4g}", o / 60.0, 1) for o in _rays(mc.features)]
        order_lists = [[1] for _ in fams]
    for j, ((gname, f_ref, _), ks) in enumerate(zip(fams, order_lists, strict=True)):
        colour, dash = styles[j % len(styles)] if mc.mesh_groups else styles[0]
        for k in ks:
            freq = k * f_ref * np.array([lo, hi])
            if freq[0] >= fmax:
                continue
            ax.plot(freq, [lo, hi], color=colour, lw=0.9, ls=dash, alpha=0.9,
                    label=(f"mesh orders ({gname})" if mc.mesh_groups else
                           "order rays of the map" if j == 0 else None)
                    if k == ks[0] else None)
            tag = (f"{k}×" if len(fams) == 1 else f"{k}× {gname}") if mc.mesh_groups \
                else f"{60 * f_ref:.4g}×"
            style = {"color": colour, "fontsize": 7, "bbox": {"boxstyle": "round,pad=0.1",
                                                               "fc": "0.15", "ec": "none",
                                                               "alpha": 0.6}}
            if freq[1] <= fmax:
                labels.append(Label(tag, (float(freq[1]), hi), ((-2, -3), (-2, -14)),
                                    {**style, "ha": "right", "va": "top"}))
            else:
                labels.append(Label(tag, (fmax, float(fmax / (k * f_ref))), ((3, -4), (3, 5)),
                                    {**style, "ha": "left", "va": "center"}))
    named = natural_frequency_lines(ax, mc.natural_frequencies_hz, mc.mode_names, fmax)
    for f, n in named:
        labels.append(Label(n, (f, lo), ((0, 3), (0, 14)),
                            {"color": "C1", "fontsize": 7, "ha": "center", "va": "bottom",
                             "rotation": 90}))
    if mc.features is not None:
        for f in np.atleast_1d(mc.features.frequencies):
            if f <= fmax and not any(abs(f - g) <= 0.05 * g for g, _ in named):
                ax.axvline(f, color="0.85", lw=0.8, ls="-.")
                labels.append(Label(f"{f:.0f} Hz (map line)", (float(f), lo), ((0, 3), (0, 14)),
                                    {"color": "0.85", "fontsize": 7, "ha": "center",
                                     "va": "bottom", "rotation": 90}))
    r = mc.resonances
    if r is not None and len(r):
        mech = np.asarray([str(x) for x in r.mechanism])
        for which, mk, col, lab in (("forced resonance", "o", "r", "forced resonance"),
                                    ("parametric instability", "s", "#ff66ff",
                                     "parametric (theory candidate)"),
                                    ("unexplained", "x", "0.8", "unexplained rise")):
            sel = mech == which
            if sel.any():
                ax.plot(r.frequency[sel], r.rpm[sel], mk, mfc="none", mec=col, color=col,
                        ms=7 if mk != "x" else 4, label=lab)
    ax.legend(loc="lower right", fontsize=7)
    fig.suptitle(f"{mc.name}: rpm-frequency map of {mc.channel}", fontsize=10)
    place_labels(fig, ax, labels)
    return fig


def order_map_figure(mc: MeasuredCase, figsize: tuple[float, float] = (7.5, 6.0)
                     ) -> Figure | None:
    """Rpm-order map with the mesh orders and the natural-frequency curves o = 60 f / n."""
    if mc.omap is None:
        return None
    orders = [60 * f * k for _, f, kk in mc.mesh_groups for k in range(1, kk + 1)]
    fig = rpm_order_map_figure(mc.omap, orders=[o for o in orders if o <= mc.omap.max_order],
                               dynamic_range_db=_DYNAMIC_RANGE_DB, figsize=figsize)
    ax = fig.axes[0]
    lo, hi = ax.get_ylim()
    speeds = np.linspace(max(lo, 1.0), hi, 200)
    for f in mc.natural_frequencies_hz:
        ax.plot(60 * f / speeds, speeds, color="C1", lw=0.8, ls=":")
    ax.set_xlim(0, mc.omap.max_order)
    ax.set_xlabel("order of the reference shaft" + (" (dashed: mesh orders, dotted: natural "
                                                     "frequencies)" if mc.mesh_groups else ""))
    fig.suptitle(f"{mc.name}: rpm-order map of {mc.channel}", fontsize=10)
    return fig


# --------------------------------------------------------------------------- sections


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


# --------------------------------------------------------------------------- build


@dataclass(frozen=True)
class MeasuredReportPaths:
    """Files of a measured report and its content."""

    html: Path
    pdf: Path
    pdf_pages: int
    sections: tuple[str, ...]
    case: MeasuredCase = field(repr=False)
    levels: Any = field(default=None, repr=False)  # gearvib.report.nvh.SignalLevels


def build_measured_report(source: Measurement | str | os.PathLike | xr.Dataset,
                          out_dir: str | os.PathLike, *, gearset: Any = None,
                          channel: str | None = None, reference: str | None = None,
                          settings: AnalysisSettings | None = None, title: str | None = None,
                          envelope_band: Any = None, min_bandwidth: float | None = None,
                          **speed: Any) -> MeasuredReportPaths:
    """Analyse a measurement and write ``report.html`` and ``report.pdf`` into ``out_dir``.

    Parameters
    ----------
    source : Measurement, path or Dataset
        The measurement (a path or Dataset is loaded with
        :func:`analysis.measurement.load_measurement` and the ``speed`` keywords:
        ``tacho``, ``pulses_per_rev``, ``speed``, ``angle``, ``rpm``, ``rpm_from``, ``fs``,
        ``time_column``, ``calibration``, ``units``).
    out_dir : path-like
        Output folder (created when the files are written).
    gearset, channel, reference, settings, envelope_band, min_bandwidth
        See :func:`analyse_measurement`.
    title : str, optional
        Report title.

    Returns
    -------
    MeasuredReportPaths
    """
    m = source if isinstance(source, Measurement) else load_measurement(
        source, channel=channel, **speed)
    out = check_output_dir(out_dir)
    mc = analyse_measurement(m, gearset=gearset, channel=channel, reference=reference,
                             settings=settings, envelope_band=envelope_band,
                             min_bandwidth=min_bandwidth)
    levels = measured_levels(mc, min_speed_ratio=MIN_SPEED_RATIO)  # order cuts, Campbell, ...
    sections = with_level_pages(measured_sections(mc), mc, levels)  # summary first
    title = title or (f"Order-analysis report of the measurement {mc.name}"
                      + (f" ({mc.gearset_name})" if mc.gearset_name else ""))
    subtitle = (f"Channel {mc.channel}; speed reference: {m.reference}; "
                + (f"machine {mc.gearset_name} (shafts and bearings)." if mc.rig is not None
                   else f"gear set {mc.gearset_name}." if mc.gearset_name else "no gear set."))
    images = FigureImages()
    text = render_html(sections, title=title, subtitle=subtitle, images=images)
    out.mkdir(parents=True, exist_ok=True)
    html_path, pdf_path = out / "report.html", out / "report.pdf"
    pages = atomic_write(pdf_path, lambda tmp: write_pdf(sections, tmp, title=title,
                                                    subtitle=subtitle, images=images))
    atomic_write(html_path, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    return MeasuredReportPaths(html=html_path, pdf=pdf_path, pdf_pages=int(pages),
                               sections=tuple(s.id for s in sections), case=mc, levels=levels)


def is_simulated_run(path: str | os.PathLike) -> bool:
    """True for a netCDF file written by the simulator (it has ``normal_force``).

    Only the header is read (netCDF4 parses a header without loading data); a file whose
    header cannot be read counts as a run, so that the run reader reports what is wrong.
    """
    try:
        with open_image(path) as nc:  # not the file itself: see analysis.readers.ncimage
            return "normal_force" in nc.variables
    except (OSError, ReaderError):
        return Path(path).is_file() and Path(path).suffix in (".nc", ".nc4")
