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

The pieces live in modules named after their concept, which this module puts together:
:mod:`~gearvib.report.case_analysis` (:class:`CaseAnalysis`, the content object and its table
rows), :mod:`~gearvib.report.case_run` (what the run file holds: configuration, run, drive,
tooth forces), :mod:`~gearvib.report.case_groups` (mesh-frequency groups),
:mod:`~gearvib.report.case_spectra` (tooth-force spectra), :mod:`~gearvib.report.case_stiffness`
(summed mesh stiffness), :mod:`~gearvib.report.case_stability` (Floquet chart and theory
candidates), :mod:`~gearvib.report.case_parameters` (gear-set and mode tables),
:mod:`~gearvib.report.case_levels` (NVH levels) and :mod:`~gearvib.report.rises` (rise tables
and speed regions, shared with the measured report). The names this module exported before
the split (:class:`CaseAnalysis`, :class:`MeshGroup`, :class:`SummedStiffness`,
:class:`ForceSpectrum`, :class:`ResonanceRegion`, :func:`summed_stiffness`,
:func:`summed_sun_stiffness`, :func:`signed_force`, :func:`run_description`,
:func:`rise_table_rows`, :func:`crossing_table_rows`, :func:`resonance_regions`,
:func:`merged_modes`, :func:`key_speed_rows` and the constants) are re-exported from their
homes, so that ``from gearvib.report.case import ...`` keeps working; new code imports them
from their homes.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from analysis.checks import require_instance
from analysis.instability import Resonances, detect_resonances, merge_mesh_frequencies
from analysis.maps import rpm_frequency_map, rpm_order_map
from analysis.runup import MapFeatures, map_features
from gearvib.config import config_hash
from gearvib.modal import modal_analysis
from gearvib.report.case_analysis import (
    MARKER_BUDGET,
    PAPER_SPEEDS_RPM,
    CaseAnalysis,
    key_speed_rows,
)
from gearvib.report.case_groups import (  # noqa: F401  (AUTO_ORDERS re-exported)
    AUTO_ORDERS,
    MeshGroup,
    auto_orders,
    is_paper_set,
    model_groups,
    stored_groups,
)
from gearvib.report.case_levels import MAX_SENSORS, case_levels
from gearvib.report.case_parameters import mode_rows, parameter_rows
from gearvib.report.case_run import (
    RPM_MIN_FRACTION,
    caller_config,
    rebuild_model,
    run_config,
    run_description,
    run_drive,
    run_settings,
    signed_force,
)
from gearvib.report.case_spectra import ForceSpectrum, force_spectrum
from gearvib.report.case_stability import (  # noqa: F401  (STABILITY_MODES re-exported)
    STABILITY_MODES,
    first_order_rows,
    shown_candidates,
    stability_chart,
    stored_candidates,
)
from gearvib.report.case_stiffness import (
    SummedStiffness,
    simulated_stiffness,
    summed_stiffness,
    summed_sun_stiffness,
)
from gearvib.report.rises import (
    REGION_HEADER,
    RISE_HEADER,
    ResonanceRegion,
    crossing_table_rows,
    merged_modes,
    resonance_regions,
    rise_table_rows,
)
from gearvib.report.study import AnalysisSettings
from gearvib.report.verdict import settings_rows
from gearvib.stability import ATTRIBUTION_N_MAX, gear_set_candidates, mesh_phasing

__all__ = [
    "MARKER_BUDGET",
    "MAX_SENSORS",
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
    "merged_modes",
    "resonance_regions",
    "rise_table_rows",
    "run_description",
    "signed_force",
    "summed_stiffness",
    "summed_sun_stiffness",
]

# the planet-mode signal (difference of two planets' sun-mesh forces) of a symmetric simulation
# starts at round-off; it is analysed only when a Floquet band lets it grow by this much
PLANET_SIGNAL_GROWTH_DB = 40.0
SPOT_RANGE_DB = 40.0  # rises more than this below the map maximum are background clutter
_MIN_SPOT_FRACTION = 0.15  # spots below 0.15 x the lowest natural frequency: near-DC content
_REGION_GAP = 0.03  # spots closer than 3 % of the top speed belong to one resonance region
_MAX_PANELS = 4  # spectra and stiffness panels per case


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
    require_instance(ds, xr.Dataset, "ds")
    if name is not None and not isinstance(name, str):
        raise TypeError(f"name must be a string; got {type(name).__name__}")
    if settings is not None:
        require_instance(settings, AnalysisSettings, "settings")
    if progress is not None and not isinstance(progress, bool):
        raise TypeError(f"progress must be a bool or None; got {type(progress).__name__}")
    for v in ("normal_force", "input_speed", "mesh_frequency", "natural_frequency",
              "input_angle"):
        if v not in ds.variables:
            raise ValueError(f"the dataset is not a gearvib run-up: variable {v!r} is missing")
    cfg = run_config(ds)
    caller = caller_config(cfg)
    if settings is None:
        a = caller.get("analysis")
        settings = AnalysisSettings.from_dict(a) if isinstance(a, dict) else AnalysisSettings()
    notes: list[str] = []
    model, why = rebuild_model(caller)
    if why:
        notes.append(why)
    modal = modal_analysis(model) if model is not None else None
    if model is not None and modal is not None:
        keep = np.array([k != "rigid-body" for k in modal.kinds], dtype=bool)
        fn = modal.frequencies_hz[keep]
        names = [f"f{i + 1}" for i in np.flatnonzero(keep)]
        groups = model_groups(model) or stored_groups(ds)
    else:
        fn = np.asarray(ds["natural_frequency"].values, dtype=float)
        names = [f"f{i + 2}" for i in range(fn.size)]
        groups = stored_groups(ds)
        notes.append("natural frequencies are those stored in the run, named f2, f3, ... "
                     "assuming one rigid-body mode (f1)")
    gs = caller.get("gearset", {}) if isinstance(caller.get("gearset"), dict) else {}
    gs_name = str(gs.get("name", ""))
    case = name or str(caller.get("case", "")) or gs_name or "run"
    label = str(caller.get("label", "")) or str(gs.get("title", "")) or gs_name or case
    run = run_settings(caller, ds)
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
    groups = auto_orders(groups, fn, fmax, span[1], settings.orders)
    f_per_rpm = groups[0].frequency_per_rpm
    paper = is_paper_set(model, gs)
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
        all_cands = stored_candidates(fn, names, groups, wide, settings.n_max)
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
    spectra = [force_spectrum(ds, mesh, gname, fs, fmax, settings, fn, names, low)
               for gname, mesh in panels]

    # (d) summed mesh stiffness of every central gear (at most four)
    stiff: list[SummedStiffness] = []
    for g in groups:
        for central, ms in g.centrals:
            if len(stiff) >= _MAX_PANELS:
                break
            st = (summed_stiffness(model, ms, central=central, group=g.name)
                  if model is not None else
                  simulated_stiffness(ds, ms, g.frequency_per_rpm, central, g.name))
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
    moving = rpm > RPM_MIN_FRACTION * rpm.max()
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
            chart, why, t_stab = stability_chart(model, modal, all_cands, span, settings, progress,
                                                 run_drive(ds))
            if why:
                notes.append(why)
        first_order = first_order_rows(model, span, settings, run_drive(ds))
        if not several:
            rule, families = mesh_phasing(model, modal)
    candidates = shown_candidates(all_cands, chart, settings.n_max, span)
    if chart is not None:  # labels of the shown table are those of the chart's table
        notes += list(chart.notes)

    # (g) resonances of the map, classified per mesh frequency: forced (rays x natural
    # frequencies), parametric (growing Floquet bands), unexplained
    map_ds = fmap.to_dataset().sel(frequency=slice(0.0, fmax))
    frame_rpm = np.asarray(map_ds["rpm"].values)
    try:
        features: MapFeatures | None = map_features(
            map_ds, frames=frame_rpm > RPM_MIN_FRACTION * float(frame_rpm.max()))
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

    # (g') order cuts, overall level, waterfall, Campbell: the housing sensors and the force
    levels = case_levels(ds, case, groups, model, settings, fn, names, fmap, x, t, fs, fmax,
                         force_mesh)

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
        *settings_rows(settings),
        ("map", f"{fmap.window}, RBW {fmap.resolution_hz:.3g} Hz, overlap "
                f"{fmap.overlap:g}, {fmap.time.size} frames"),
        ("mesh orders", ", ".join(f"{g.name}: 1–{g.orders}" for g in groups)),
    ]
    for sl in levels:
        if sl.levels is not None:
            c = sl.levels.cuts
            prov.append((f"order cuts ({sl.signal})",
                         f"{c.window}, resolution {sl.levels.resolution:.3g} orders, band "
                         f"{c.bandwidth:.3g} orders, overlap {c.overlap:g}, {c.time.size} "
                         f"frames, {c.samples_per_rev} samples per revolution"))
    if chart is not None:
        prov.append(("Floquet chart", f"{chart.mesh_frequencies_hz.size} speeds "
                     f"({settings.stability}), boundaries refined; regions attributed to "
                     f"candidates up to n = {max(settings.n_max, ATTRIBUTION_N_MAX)}"))
    return CaseAnalysis(
        name=case, label=label, dataset=ds, config=cfg, model=model, modal=modal,
        natural_frequencies_hz=fn, mode_names=names, mesh_frequency_per_rpm=f_per_rpm,
        groups=groups, parameters=parameter_rows(ds, caller, model, run, groups),
        modes=mode_rows(modal, ds), force_mesh=force_mesh, force_meshes=force_meshes,
        spectra=spectra, stiffness=stiff, fmap=fmap, omap=omap, frequency_max_hz=fmax,
        resonances=resonances, regions=regions, candidates=candidates, chart=chart, run=run,
        settings=settings, notes=notes, provenance=prov, first_order=first_order,
        planet_resonances=planet_res, features=features, paper_set=paper,
        stability_time_s=t_stab, levels=levels,
    )
