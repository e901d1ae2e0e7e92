"""Stability of a simulated run: Floquet chart, first-order regions and theory candidates.

:func:`stability_chart` computes the Floquet stability chart over the run's speed range
(settings per ``[analysis] stability`` value: :data:`STABILITY_MODES`),
:func:`first_order_rows` the first-order (Hsu) regions, :func:`stored_candidates` the theory
candidates of a run without a model, :func:`shown_candidates` the rows the report shows, and
:func:`candidate_mechanism` names the mechanism of a candidate.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from analysis.instability import Candidates, instability_candidates
from gearvib.modal import ModalResult
from gearvib.model import AssembledModel
from gearvib.report.case_groups import MeshGroup
from gearvib.report.case_run import RPM_MIN_FRACTION
from gearvib.report.study import AnalysisSettings
from gearvib.simulation.conditions import DriveCoupling
from gearvib.stability import (
    CHART_ACCURACY,
    cycle_budget,
    first_order_regions,
    stability_over_speed,
)

__all__ = ["STABILITY_MODES", "candidate_mechanism", "first_order_rows",
           "shown_candidates", "stability_chart", "stored_candidates"]


STABILITY_MODES: dict[str, dict[str, Any]] = {
    "full": {"points": None, "floquet": CHART_ACCURACY, "xtol_rel": 1e-8},
    "coarse": {"points": 80, "floquet": {"multiplier_atol": 1e-6, "unity_margin": 0.03},
               "xtol_rel": 1e-6},
}
"""Floquet chart settings per ``[analysis] stability`` value (``"off"``: no chart)."""


def candidate_mechanism(idx: int, cands: Candidates) -> str:
    """The mechanism of a theory candidate, as the Floquet region table states it.

    Parameters
    ----------
    idx : int
        Row of the candidate (-1: none).
    cands : Candidates
        The candidates.

    Returns
    -------
    str
        ``"parametric instability, principal type, n = 2"``, the kind of another candidate, or
        ``"–"``.
    """
    if idx < 0:
        return "–"
    kind = str(cands.kind[idx])
    return (f"parametric instability, {kind} type, n = {int(cands.n[idx])}"
            if kind in ("principal", "sum") else kind)


def stability_chart(model: AssembledModel, modal: ModalResult, candidates: Candidates,
                    span: tuple[float, float], settings: AnalysisSettings,
                    progress: bool | None,
                    coupling: DriveCoupling | None = None) -> tuple[Any, str, float]:
    """The Floquet stability chart over a run's speed range.

    Parameters
    ----------
    model : AssembledModel
        The gear set.
    modal : ModalResult
        Its modes.
    candidates : Candidates
        Theory candidates the unstable regions are attributed to.
    span : (float, float)
        Input speed range [min^-1]; the chart starts at
        :data:`~gearvib.report.case_run.RPM_MIN_FRACTION` of the top speed.
    settings : AnalysisSettings
        ``stability`` (:data:`STABILITY_MODES`), ``stability_points``, ``n_max``.
    progress : bool or None
        Progress bar (None: on a terminal only).
    coupling : DriveCoupling, optional
        Drive coupling of the run (:func:`gearvib.report.case_run.run_drive`).

    Returns
    -------
    chart : StabilityChart or None
        None when the chart failed.
    why : str
        Why it failed (``""`` otherwise).
    seconds : float
        Wall time of the chart [s].
    """
    mode = STABILITY_MODES[settings.stability]
    hi = float(span[1])
    lo = max(float(span[0]), RPM_MIN_FRACTION * hi)
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


def first_order_rows(model: AssembledModel, span: tuple[float, float],
                     settings: AnalysisSettings,
                     coupling: DriveCoupling | None = None) -> list[tuple[str, ...]]:
    """First-order (Hsu) regions inside the run-up speed range, for the stability section.

    Parameters
    ----------
    model : AssembledModel
        The gear set.
    span : (float, float)
        Input speed range [min^-1].
    settings : AnalysisSettings
        ``n_max``: highest order of the regions.
    coupling : DriveCoupling, optional
        Drive coupling of the run.

    Returns
    -------
    list of tuple of str
        ``(region, lower, upper, width [min^-1], undamped width [min^-1])``; ``[]`` when the
        regions cannot be computed.
    """
    try:
        widths = first_order_regions(model, coupling=coupling, l_max=settings.n_max)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError):
        return []
    lo_r, hi_r = span
    factor = {g.name: g.frequency_per_rpm for g in model.mesh_frequency_groups()}
    rows: list[tuple[str, ...]] = []
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


def stored_candidates(fn: np.ndarray, names: list[str], groups: Sequence[MeshGroup],
                      speed_range: tuple[float, float], n_max: int) -> Candidates:
    """Candidates of every stored mesh frequency (no gear-set model), sorted by speed.

    Parameters
    ----------
    fn : ndarray
        Natural frequencies [Hz].
    names : list of str
        Their names.
    groups : sequence of MeshGroup
        Mesh-frequency groups.
    speed_range : (float, float)
        Input speed range [min^-1].
    n_max : int
        Highest order.

    Returns
    -------
    Candidates
        Without the planetary mesh-phasing selection rule.
    """
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


def shown_candidates(cands: Candidates, chart: Any, n_max: int,
                     span: tuple[float, float]) -> Candidates:
    """Rows of order ``n <= n_max`` inside the speed range, plus every attributed row.

    Parameters
    ----------
    cands : Candidates
        Every candidate.
    chart : StabilityChart or None
        The Floquet chart (its regions' ``candidate_index``).
    n_max : int
        Highest order shown.
    span : (float, float)
        Input speed range [min^-1].

    Returns
    -------
    Candidates
    """
    keep = (cands.n <= n_max) & (cands.rpm >= span[0]) & (cands.rpm <= span[1])
    if chart is not None:
        for reg in chart.region_table:
            if int(reg.get("candidate_index", -1)) >= 0:
                keep[int(reg["candidate_index"])] = True
    return cands.select(keep)

