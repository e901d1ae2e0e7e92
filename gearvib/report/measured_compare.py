"""Measured against simulated, with the model: ``gearvib compare MEASURED SIMULATED.nc``.

:func:`compare_with_simulation` loads both records (:func:`analysis.measurement.load_measurement`:
the simulation's virtual sensor, or a force / transmission-error channel of a run without one,
and its tacho, else its input angle), compares them on common ground
(:func:`analysis.comparison.compare_measurements`) and adds what needs the model:

* the kinematic label of every order line (the gear set's catalogue, as in the report);
* for every frequency-locked line of the measurement near a natural frequency of the model, the
  model parameters most likely responsible for the offset, by **modal strain energy**: with
  the fractions ``e_j`` of the mode's strain energy in the mesh families and bearings
  (:attr:`gearvib.modal.ModalResult.mesh_energy`, ``bearing_energy``), a relative stiffness
  change ``s_j`` moves the natural frequency by ``(f'/f)^2 - 1 = sum_j e_j s_j`` (Rayleigh
  quotient, first order), so the stiffness change that alone explains an offset ``d`` is
  ``s_j = ((1 + d)^2 - 1) / e_j``; the families with the largest ``e_j`` need the smallest,
  most plausible change.

:func:`build_comparison_report` writes ``comparison.html``, ``comparison.pdf`` and
``comparison.nc`` (the Dataset of :meth:`SimulationComparison.to_dataset`).
"""

from __future__ import annotations

import json
import math
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from analysis.cf import cf_dataset
from analysis.comparison import MeasuredSimulatedComparison, compare_measurements
from analysis.identification import catalogue_lines, identify_peaks
from analysis.measurement import Measurement, load_measurement
from analysis.netcdf_lock import NETCDF_LOCK
from gearvib.assembly import assemble
from gearvib.catalogue import gear_set_catalogue
from gearvib.config import GearSet, gearset_from_dict, load_gearset
from gearvib.io import atomic_write
from gearvib.modal import modal_analysis
from gearvib.report.document import FigureImages
from gearvib.report.html import render_html
from gearvib.report.pdf import write_pdf
from gearvib.report.runner import check_output_dir
from gearvib.report.sections import Block, Section

if TYPE_CHECKING:
    from gearvib.modal import ModalResult
    from gearvib.model import AssembledModel

__all__ = ["COMPARISON_FILES", "ComparisonPaths", "ParameterShare", "SimulationComparison",
           "build_comparison_report", "compare_with_simulation", "comparison_sections",
           "load_simulated", "stiffness_shares"]

COMPARISON_FILES = ("comparison.html", "comparison.pdf", "comparison.nc")
"""Files ``gearvib compare`` writes into its output folder."""

_MIN_SHARE = 0.05  # a family with less of the strain energy cannot plausibly move the mode


@dataclass(frozen=True)
class ParameterShare:
    """A stiffness family's share of a mode's strain energy and the change that alone would
    explain a frequency offset.

    Attributes
    ----------
    parameter : str
        ``"mesh stiffness sun-planet*"``, ``"bearing stiffness planet*.x"``, ...
    share : float
        Fraction of the mode's strain energy in it (0..1).
    change : float
        Relative stiffness change that alone moves the mode by the offset (NaN when the share
        is below 5 %).
    """

    parameter: str
    share: float
    change: float


def _channel_text(m: Measurement, name: str) -> str:
    """``": net normal tooth force of ..."`` for a run's force channel, else ``""``."""
    if name not in m.signals.data_vars:
        return ""
    src = str(m.signals[name].attrs.get("source_channel", ""))
    return f": {m.signals[name].attrs.get('long_name', '')}" if src and not src.startswith(
        "sensor_acceleration") else ""


def load_simulated(simulated: str | os.PathLike | xr.Dataset,
                   reference: str | None = None) -> Measurement:
    """A simulated run (or any record) as the simulated side of a comparison: its virtual
    sensors, force and transmission-error channels (``load_measurement(..., forces=True)``),
    the speed from its tacho, else its input angle.

    Parameters
    ----------
    simulated : path or Dataset
        The run.
    reference : str, optional
        Member whose orders are compared: a run without a tacho is then referenced to that
        member's stored rotation (``rotation:MEMBER``) instead of its input angle.
    """
    m = load_measurement(simulated, forces=True)
    key = f"rotation:{reference}"
    if reference is not None and m.source.get("reference_channel") == "input_angle" and \
            key in m.signals.data_vars:
        m = load_measurement(simulated, forces=True, angle=key)
    return m


def _locked_to_netcdf(ds: xr.Dataset, path: Path) -> None:
    """``ds.to_netcdf`` under the process's netCDF lock (the library is not thread-safe)."""
    with NETCDF_LOCK:
        ds.to_netcdf(path, engine="netcdf4")


def _family(name: str) -> str:
    """``sun-planet2`` -> ``sun-planet*``, ``s1.ring-planet3`` -> ``s1.ring-planet*``."""
    return re.sub(r"(planet)\d+", r"\1*", name)


def stiffness_shares(modal: ModalResult, mode: int, offset: float) -> list[ParameterShare]:
    """Strain-energy shares of the stiffness families of one mode, largest first.

    Parameters
    ----------
    modal : ModalResult
        Modes of the mean system.
    mode : int
        Index of the mode in ``modal``.
    offset : float
        Measured over model natural frequency minus 1.

    Returns
    -------
    list of ParameterShare
    """
    shares: dict[str, float] = {}
    e_mesh = modal.mesh_energy[mode] if modal.mesh_energy.size else np.zeros(0)
    for name, e in zip(modal.mesh_names, e_mesh, strict=False):
        key = f"mesh stiffness {_family(name)}"
        shares[key] = shares.get(key, 0.0) + float(e)
    e_b = modal.bearing_energy[mode] if modal.bearing_energy.size else np.zeros(0)
    for name, e in zip(modal.bearing_names, e_b, strict=False):
        key = f"bearing stiffness {_family(name)}"
        shares[key] = shares.get(key, 0.0) + float(e)
    need = (1.0 + offset) ** 2 - 1.0
    out = [ParameterShare(k, v, need / v if v >= _MIN_SHARE else math.nan)
           for k, v in shares.items() if v > 0]
    return sorted(out, key=lambda p: -p.share)


@dataclass
class SimulationComparison:
    """A measurement against a simulation, with the model's interpretation.

    Attributes
    ----------
    result : MeasuredSimulatedComparison
        The comparison on common ground (:mod:`analysis.comparison`).
    measured, simulated : Measurement
        The two records.
    gearset_name : str
        The gear set ("" when none was available).
    order_labels : list of str
        Catalogue label of every order line of ``result.peaks`` ("" when none).
    parameters : list of list of ParameterShare
        Per frequency-locked line of ``result.lines``: the stiffness families of its mode.
    notes : list of str
        Remarks.
    """

    result: MeasuredSimulatedComparison
    measured: Measurement
    simulated: Measurement
    gearset_name: str = ""
    order_labels: list[str] = field(default_factory=list)
    parameters: list[list[ParameterShare]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    # ------------------------------------------------------------------ rows

    def ground_rows(self) -> list[tuple[str, str]]:
        """What was compared, on which grids, with which scaling."""
        r = self.result
        return [
            ("measured", f"{self.measured.source.get('file') or r.measured_name}, channel "
                         f"{r.measured_channel} [{r.measured_units or '?'}]"),
            ("simulated", f"{self.simulated.source.get('file') or r.simulated_name}, channel "
                          f"{r.simulated_channel} [{r.simulated_units or '?'}]"
                          f"{_channel_text(self.simulated, r.simulated_channel)}"),
            ("measured speed reference", r.measured_reference),
            ("simulated speed reference", r.simulated_reference),
            ("common speed range", f"{r.rpm_range[0]:.0f}–{r.rpm_range[1]:.0f} min⁻¹ "
                                   f"({r.rpm.size} rpm bins)"),
            ("order grid", f"0–{r.order[-1]:.4g} orders of the reference shaft, RBW "
                           f"{r.order_resolution:.3g} orders (Hann), power averages"),
            ("levels", f"{r.level_basis} (unit of every level: {r.level_unit})"
                       + ("" if r.measured_units == r.simulated_units else
                          f"; the units differ ({r.measured_units} against "
                          f"{r.simulated_units}): spectral shapes are compared, not absolute "
                          "levels")),
            ("line matching", f"order tolerance ± {r.match_tolerance:.3g} + 0.2 % of the "
                              "order; peaks of at least 6 dB prominence within 30 dB of the "
                              "strongest"),
            ("gear set", self.gearset_name or "(none: no kinematic labels or mode attribution)"),
        ]

    def peak_rows(self) -> list[tuple[str, ...]]:
        """One row per order line: status, orders, levels, differences, catalogue label."""
        rows: list[tuple[str, ...]] = []
        for p, lab in zip(self.result.peaks, self.order_labels or [""] * len(
                self.result.peaks), strict=True):
            def f(v: float, fmt: str) -> str:
                return format(v, fmt) if math.isfinite(v) else "–"

            rows.append((p.status, f(p.order_measured, ".4g"), f(p.order_simulated, ".4g"),
                         f(p.order_difference, "+.3f"), f(p.level_measured_db, ".1f"),
                         f(p.level_simulated_db, ".1f"), f(p.level_difference_db, "+.1f"),
                         lab or "–"))
        return rows

    def line_rows(self) -> list[tuple[str, ...]]:
        """One row per frequency-locked line of the measurement."""
        rows: list[tuple[str, ...]] = []
        for ln, pars in zip(self.result.lines, self.parameters or [[]] * len(
                self.result.lines), strict=True):
            if not ln.mode:
                verdict, text = "no model", "–"
            elif not ln.seen:
                verdict = "no mode within 10 %"
                text = ("a resonance outside the gear model (housing, shafts, supports)")
            else:
                verdict = "seen"
                top = [p for p in pars if math.isfinite(p.change)][:3]
                text = "; ".join(f"{p.parameter}: {100 * p.share:.0f} % of the strain "
                                 f"energy → {100 * p.change:+.0f} % alone" for p in top) or "–"
            rows.append((f"{ln.frequency_hz:.0f}", ln.mode or "–",
                         f"{ln.mode_frequency_hz:.1f}" if ln.mode else "–",
                         f"{100 * ln.offset:+.1f} %" if ln.mode else "–", verdict,
                         "yes" if ln.in_simulation else "no", text))
        return rows

    def to_dataset(self) -> xr.Dataset:
        """The comparison Dataset plus the catalogue labels and the responsible parameters."""
        ds = self.result.to_dataset()
        ds["peak_label"] = ("peak", np.asarray(self.order_labels or [""] * ds.sizes["peak"],
                                               dtype=str),
                            {"long_name": "catalogue label of the order line"})
        ds["line_parameters"] = ("line", np.asarray([
            "; ".join(f"{p.parameter} {p.share:.3f} {p.change:+.3f}" for p in pars)
            for pars in (self.parameters or [[]] * ds.sizes["line"])], dtype=str),
            {"long_name": "stiffness family, its strain-energy share and the relative change "
                          "that alone explains the offset"})
        ds.attrs["gear_set"] = self.gearset_name or "(none)"
        ds.attrs["model_notes"] = json.dumps(self.notes)
        return cf_dataset(
            ds, title="measured against simulated",
            producer="gearvib.report.measured_compare.compare_with_simulation"
        )


# --------------------------------------------------------------------------- computation


def _model_from_run(simulated: Measurement) -> tuple[Any, str]:
    """The gear set stored in a simulated run's ``config_json`` (None when absent)."""
    try:
        cfg = json.loads(simulated.source.get("config_json") or "{}")
    except ValueError:
        return None, "the simulated run's config_json is not readable"
    inner = cfg.get("model", {}) if isinstance(cfg, dict) else {}
    gs = inner.get("gearset") if isinstance(inner, dict) else None
    if not isinstance(gs, dict):
        return None, ("the simulated run does not carry its gear-set description: give "
                      "--gearset CONFIG for kinematic labels and the mode attribution")
    base = inner.get("gearset_dir")
    try:
        return gearset_from_dict(gs, base=Path(base) if base else None), ""
    except (ValueError, OSError) as exc:
        return None, f"the simulated run's gear set could not be rebuilt: {exc}"


def compare_with_simulation(measured: Measurement | str | os.PathLike | xr.Dataset,
                            simulated: Measurement | str | os.PathLike | xr.Dataset, *,
                            gearset: Any = None, channel: str | None = None,
                            simulated_channel: str | None = None,
                            max_order: float | None = None, order_resolution: float = 0.25,
                            calibrated: bool | None = None, reference: str | None = None,
                            **speed: Any) -> SimulationComparison:
    """Compare a measurement with a simulated run, with the model's interpretation.

    Parameters
    ----------
    measured : Measurement, path or Dataset
        The measurement (loaded with the ``speed`` keywords: ``tacho``, ``pulses_per_rev``,
        ``speed``, ``angle``, ``rpm``).
    simulated : Measurement, path or Dataset
        A simulated run (:func:`load_simulated`): its virtual sensor, or without one a force
        or transmission-error channel; its speed from its tacho, else from its input angle
        (or any record with a speed reference).
    gearset : path, preset name or GearSet, optional
        The model (default: the gear set stored in the simulated run).
    channel, simulated_channel : str, optional
        Channels compared; ``simulated_channel`` a virtual sensor or a force / DTE channel
        (``normal_force:ring-planet1``, ``mesh_deflection:sun-planet1``,
        ``bearing_force:ring.x``, ...; default the virtual sensor, else the first ring-planet
        mesh force; see :func:`analysis.comparison.simulated_channel_name`).
    max_order, order_resolution, calibrated
        See :func:`analysis.comparison.compare_measurements`.
    reference : str, optional
        Member whose speed both references measure: the shaft of the catalogue's orders
        (default: the input member); a simulated run without a tacho is referenced to its
        rotation (:func:`load_simulated`).

    Returns
    -------
    SimulationComparison
    """
    m = measured if isinstance(measured, Measurement) else load_measurement(
        measured, channel=channel, **speed)
    s = simulated if isinstance(simulated, Measurement) else load_simulated(simulated,
                                                                            reference)
    notes: list[str] = []
    if gearset is None:
        gs, why = _model_from_run(s)
        if why:
            notes.append(why)
    else:
        gs = gearset if isinstance(gearset, GearSet) else load_gearset(str(gearset))
    model: AssembledModel | None = assemble(gs) if gs is not None else None
    if model is None and reference is not None:
        raise ValueError("reference applies with a gear set (--gearset CONFIG, or a run that "
                         "carries its description)")
    fn = names = None
    modal = None
    elastic: list[int] = []
    if model is not None:
        modal = modal_analysis(model)
        elastic = [i for i, k in enumerate(modal.kinds) if k != "rigid-body"]
        fn = modal.frequencies_hz[elastic]
        names = [f"f{i + 1}" for i in elastic]
    res = compare_measurements(m, s, channel=channel, simulated_channel=simulated_channel,
                               natural_frequencies_hz=fn, mode_names=names,
                               max_order=max_order, order_resolution=order_resolution,
                               calibrated=calibrated)
    labels: list[str] = []
    params: list[list[ParameterShare]] = []
    if model is not None and modal is not None:
        assert names is not None  # set with modal
        ratios = dict(model.kinematic_ratios)
        if reference is not None and not ratios.get(reference):
            raise ValueError(f"reference = {reference!r} is not a rotating member of the gear "
                             f"set; admissible: {sorted(k for k, v in ratios.items() if v)}")
        cat = gear_set_catalogue(model, reference=reference, mesh_harmonics=8, harmonics=3,
                                 sidebands=2)
        orders = np.asarray([p.order for p in res.peaks])
        if orders.size:
            ident = identify_peaks(orders, catalogue_lines(cat, axis="order",
                                                           speed_uncertainty=2e-3),
                                   resolution=res.order_resolution, band=(0.0,
                                                                          float(res.order[-1])))
            for i in range(orders.size):
                ms = ident.matches[i]
                st = str(ident.status[i])
                labels.append("no catalogue line" if not ms else
                              ms[0].expression.split(" ≈ ")[0]
                              + ("" if st == "explained" else
                                 f" (ambiguous, chance {100 * ms[0].coincidence:.0f} %)"))
        for ln in res.lines:
            if not ln.mode:
                params.append([])
                continue
            k = elastic[names.index(ln.mode)]
            params.append(stiffness_shares(modal, k, ln.offset))
    else:
        labels = [""] * len(res.peaks)
        params = [[] for _ in res.lines]
    return SimulationComparison(result=res, measured=m, simulated=s,
                                gearset_name=str(model.meta.get("name", "")) if model else "",
                                order_labels=labels, parameters=params,
                                notes=notes + list(res.notes))


# --------------------------------------------------------------------------- document


def _table(caption: str, header: Sequence[str], rows: Sequence[Sequence[Any]]) -> Block:
    return Block("table", caption, tuple(header), tuple(tuple(str(c) for c in r) for r in rows))


def comparison_sections(sc: SimulationComparison) -> list[Section]:
    """The comparison as report sections."""
    r = sc.result
    name = f"{r.measured_name} against {r.simulated_name}"
    blocks: list[Block] = [
        _table(f"Common ground of {name}", ("item", "value"), sc.ground_rows()),
        Block("text", f"{name}: {r.summary()}."),
        *[Block("text", f"Note: {n}") for n in sc.notes],
        Block("figure", f"{name}: order spectra of both records over the common speed range "
              "with the lines marked by status, and the rpm-order difference map (measured − "
              "simulated; blank where both are background or no frame falls into the bin).",
              figure=lambda: r.plot()),
        _table(f"Order lines of {name}", ("status", "order meas.", "order sim.", "Δ order",
                                          "meas. [dB]", "sim. [dB]", "Δ [dB]",
                                          "catalogue label"), sc.peak_rows())]
    lines_text = (
        f"{name}: frequency-locked lines of the measured rpm-frequency map against the "
        "model's natural frequencies. 'seen': a mode within 10 %; for those, the stiffness "
        "families holding most of the mode's strain energy and the change of each that alone "
        "would move the mode onto the measured line, (f_meas/f_model)² − 1 = share × change "
        "(first order): the smallest changes are the likeliest causes.")
    blocks += [Block("text", lines_text),
               _table(f"Natural-frequency lines of {name}",
                      ("line [Hz]", "nearest mode", "model [Hz]", "offset", "verdict",
                       "in simulation", "parameters most likely responsible"),
                      sc.line_rows())]
    if r.unseen_modes:
        blocks.append(Block("text", f"{name}: model modes in the band with no measured line "
                            "within 10 %: " + ", ".join(f"{n} ({f:.0f} Hz)"
                                                        for n, f in r.unseen_modes)
                            + " (not excited, not seen by the sensor, or off by more)."))
    prov = [("measured file", str(sc.measured.source.get("file") or "(in memory)")),
            ("measured format", str(sc.measured.source.get("format", ""))),
            ("simulated file", str(sc.simulated.source.get("file") or "(in memory)")),
            ("simulated run", str(sc.simulated.source.get("title", ""))),
            ("gear set", sc.gearset_name or "(none)")]
    return [Section("comparison", "Measured against simulated", tuple(blocks)),
            Section("provenance", "Provenance",
                    (_table(f"Provenance of {r.measured_name}", ("item", "value"), prov),))]


@dataclass(frozen=True)
class ComparisonPaths:
    """Files written by :func:`build_comparison_report`."""

    html: Path
    pdf: Path
    netcdf: Path
    pdf_pages: int
    comparison: SimulationComparison = field(repr=False)


def build_comparison_report(comparison: SimulationComparison, out_dir: str | os.PathLike, *,
                            title: str | None = None) -> ComparisonPaths:
    """Write ``comparison.html``, ``comparison.pdf`` and ``comparison.nc`` into ``out_dir``."""
    out = check_output_dir(out_dir)
    r = comparison.result
    sections = comparison_sections(comparison)
    title = title or f"Measured against simulated: {r.measured_name} and {r.simulated_name}"
    subtitle = (f"Channels {r.measured_channel} [{r.measured_units}] / {r.simulated_channel} "
                f"[{r.simulated_units}]; {r.level_basis}; "
                f"gear set {comparison.gearset_name or '(none)'}.")
    images = FigureImages()
    text = render_html(sections, title=title, subtitle=subtitle, images=images)
    ds = comparison.to_dataset()
    out.mkdir(parents=True, exist_ok=True)
    html, pdf, nc = (out / f for f in COMPARISON_FILES)
    atomic_write(nc, partial(_locked_to_netcdf, ds))
    pages = atomic_write(pdf, lambda tmp: write_pdf(sections, tmp, title=title,
                                               subtitle=subtitle, images=images))
    atomic_write(html, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    return ComparisonPaths(html=html, pdf=pdf, netcdf=nc, pdf_pages=int(pages),
                           comparison=comparison)
