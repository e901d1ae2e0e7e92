"""Analysis of a measurement for its report: :func:`analyse_measurement` -> :class:`MeasuredCase`.

A measurement (:class:`analysis.measurement.Measurement`: channels, reference-shaft speed,
provenance) is analysed like a simulated run, with what a measurement has: the spectrum of a
vibration channel with identified peaks, the order spectrum with the gear set's catalogue lines,
the rpm-frequency and rpm-order maps with the gear set's mesh orders and natural frequencies,
the order-locked rays and frequency-locked lines of the map, and the rises of the map classified
as forced resonances (a mesh order crossing a natural frequency). There are no simulated
forces, stiffness tables or Floquet charts in it.

Without a gear set the analysis keeps what needs none -- the maps, the spectra, the orders of
the reference shaft, the rays and vertical lines of the map -- and notes what is missing. Rises
are then the crossings of the reference shaft's order rays with the vertical lines the map
shows (:mod:`gearvib.report.measured_resonances`).
"""

from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.identification import (
    CandidateLines,
    catalogue_lines,
    identify_peaks,
    modal_lines,
    peak_half_widths,
)
from analysis.maps import rpm_frequency_map, rpm_order_map
from analysis.measurement import Measurement
from analysis.orders import order_spectrum
from analysis.runup import map_features
from analysis.spectrum import find_peaks, spectrum, to_db
from gearvib.assembly import assemble
from gearvib.catalogue import gear_set_catalogue
from gearvib.config import GearSet, load_description
from gearvib.fault_lines import confirmed_catalogue
from gearvib.modal import modal_analysis
from gearvib.report.bearings import fault_lines_of
from gearvib.report.measured_case import MeasuredCase
from gearvib.report.measured_peaks import (
    BEARING_FAMILIES,
    MAX_LABEL_CHANCE,
    MAX_PEAKS,
    map_lines,
    select_peaks,
    shaft_lines,
)
from gearvib.report.measured_resonances import classify_rises
from gearvib.report.rises import resonance_regions
from gearvib.report.study import AnalysisSettings, check_report_size
from gearvib.report.verdict import readable, settings_rows
from gearvib.report.wording import span
from gearvib.rig import ShaftRig

if TYPE_CHECKING:
    from gearvib.model import AssembledModel

__all__ = ["MIN_SPEED_RATIO", "analyse_measurement"]


MIN_SPEED_RATIO = 1.3
"""A record whose highest speed is below this multiple of its lowest is treated as constant
speed: no rpm maps (rays and vertical lines cannot be told apart), the spectrum is labelled
with the catalogue at the mean speed."""

_REGION_GAP = 0.03
_MIN_FRAMES = 8


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
    if model is not None:  # a gear set
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
    pk = find_peaks(sp, prominence_db=6.0, max_peaks=MAX_PEAKS,
                    min_distance_hz=3 * sp.bin_spacing_hz)
    keep_pk = (pk.frequency > 2 * sp.bin_spacing_hz) & (pk.frequency <= fmax)
    pk = select_peaks(pk, keep_pk)
    # order spectrum: peaks against the catalogue (orders of the reference shaft)
    ospec = opk = oident = None
    nyq_order = 0.95 * 0.5 * fs * 60.0 / max(hi, 1e-300)
    top_order = max((k * 60 * f for _, f, k in groups), default=0.0)
    max_order = min(nyq_order, 1.1 * top_order) if top_order else min(nyq_order, 60.0)
    ref_kw: dict[str, Any] = ({"angle": m.angle.values} if m.angle is not None
                              else {"rpm": rpm})
    try:
        res_o = max(0.05, 1.5 / max(1.0, _revolutions(m)) * 4)
        ospec = order_spectrum(x.values, fs, **ref_kw, window="hann", amplitude="rms",
                               resolution=res_o, max_order=max_order,
                               samples_per_rev=2 * math.ceil(1.28 * max_order),
                               units=units, name=ch)
        osp = ospec.spectrum
        opk = find_peaks(osp, prominence_db=6.0, max_peaks=MAX_PEAKS,
                         min_distance_hz=3 * osp.bin_spacing_hz)
        opk = select_peaks(opk, (opk.order > 0.5) & (opk.order <= max_order))
        olines = ([catalogue_lines(label_cat, axis="order", speed_uncertainty=2e-3)]
                  if model is not None else [shaft_lines(1.0, max_order, "order")])
        if rig is not None and label_cat is not None \
                and BEARING_FAMILIES & set(label_cat.family):
            olines.append(catalogue_lines(label_cat, axis="order", speed_uncertainty=2e-3,
                                          families=BEARING_FAMILIES))
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
        resonances = classify_rises(map_ds, features, fn, names, groups, t, rpm, st, fmax, notes,
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
    if label_cat is not None and not varying and (rig is None
                                                  or BEARING_FAMILIES & set(label_cat.family)):
        lines.append(catalogue_lines(label_cat, speed_rpm=mean_rpm, axis="frequency",
                                     speed_uncertainty=max(1e-3, (hi - lo) / max(hi, 1e-300)),
                                     families=BEARING_FAMILIES if rig is not None else None))
    if not varying and model is None:
        lines.append(shaft_lines(mean_rpm / 60.0, fmax, "frequency"))
    if varying and not fn.size and features is not None and np.size(features.frequencies):
        lines.append(map_lines(features, st.tolerance))
    widths = peak_half_widths(sp.frequency[band], to_db(sp.values[band], sp.amplitude),
                              pk.frequency) if len(pk) else None
    if not lines:
        notes.append("the spectrum is taken over a varying speed and there is neither a gear "
                     "set nor a frequency-locked line in the map: its peaks are listed "
                     "unexplained (read them in the maps)")
        lines.append(shaft_lines(1e9, 1.0, "frequency"))  # one line far outside the band
    ident = identify_peaks(pk.frequency, lines, resolution=sp.enbw_hz, peak_widths=widths,
                           band=(0.0, fmax), max_coincidence=MAX_LABEL_CHANCE)
    regions = (resonance_regions(resonances, rpm_gap=_REGION_GAP * hi)
               if resonances is not None else [])
    owner = model if model is not None else rig
    prov = [("measurement", name or m.name),
            ("file", str(m.source.get("file") or "(in memory)")),
            ("format", str(m.source.get("format", ""))),
            ("reader", str(m.source.get("reader", ""))),
            ("channels", ", ".join(m.source.get("channels", []))),
            ("speed reference", m.reference),
            ("gear set" if rig is None else "machine (shafts and bearings)",
             (f"{owner.meta.get('name', '')}"
              + (f" ({gearset})" if isinstance(gearset, str | os.PathLike) else "")
              if owner is not None else "(none)")),
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

