"""The content of a measured report: :class:`MeasuredCase` (computed by
:func:`gearvib.report.measured_analysis.analyse_measurement`) and its table rows.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from analysis.cf import cf_dataset
from analysis.identification import PeakIdentification
from analysis.instability import Resonances
from analysis.maps import RpmFrequencyMap, RpmOrderMap
from analysis.measurement import Measurement
from analysis.orders import OrderSpectrum
from analysis.runup import MapFeatures
from analysis.spectrum import Peaks, Spectrum
from gearvib.report.measured_peaks import peak_table_rows
from gearvib.report.rises import ResonanceRegion, crossing_table_rows, rise_table_rows
from gearvib.report.study import AnalysisSettings
from gearvib.report.wording import count, span
from gearvib.rig import ShaftRig

if TYPE_CHECKING:
    from gearvib.modal import ModalResult
    from gearvib.model import AssembledModel

__all__ = ["MeasuredCase"]


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
        rows: list[tuple[str, ...]] = []
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
        rows: list[tuple[str, ...]] = []
        modal = self.modal
        for i, (f, kind) in enumerate(zip(modal.frequencies_hz, modal.kinds, strict=True)):
            if kind == "rigid-body":
                continue
            e = modal.mesh_energy[i] if modal.mesh_energy.size else np.zeros(0)
            dom = (f"{modal.mesh_names[int(np.argmax(e))]} ({100 * float(np.max(e)):.0f} %)"
                   if e.size and float(np.max(e)) > 0 else "–")
            rows.append((f"f{i + 1}", f"{f:.1f}", str(kind), dom))
        return rows

    def peak_rows(self) -> list[tuple[str, ...]]:
        """Rows of the frequency-peak table."""
        return peak_table_rows(self.identification, self.peaks, self.spectrum, "Hz")

    def order_peak_rows(self) -> list[tuple[str, ...]]:
        """Rows of the order-peak table."""
        os_ = self.order_spectrum
        return peak_table_rows(self.order_identification, self.order_peaks,
                               os_.spectrum if os_ is not None else None, "order")

    def resonance_rows(self) -> list[tuple[str, ...]]:
        """Rows of the rise table (:data:`gearvib.report.rises.RISE_HEADER`)."""
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

