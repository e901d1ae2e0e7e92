"""Rises of the rpm-frequency map of a measurement, classified.

With a gear set the rises are classified per mesh frequency against the model's natural
frequencies (forced resonances; parametric instabilities by the theory candidates alone: a
measured report has no Floquet chart). Without one, the rays the map shows
(:func:`strongest_rays`, at most :data:`MAX_RAYS`) take the place of the mesh orders and the
frequency-locked lines of the map that of the natural frequencies (:func:`classify_rises`).
"""

from __future__ import annotations

import re
from dataclasses import replace
from typing import Any

import numpy as np
import xarray as xr

from analysis.instability import Resonances, detect_resonances, merge_mesh_frequencies
from analysis.runup import MapFeatures
from gearvib.report.study import AnalysisSettings
from gearvib.stability import gear_set_candidates

__all__ = ["MAX_RAYS", "classify_rises", "ray_causes", "strongest_rays"]


MAX_RAYS = 8
"""Without a gear set, at most this many order rays of the map (the strongest) are used."""


def ray_causes(res: Resonances) -> Resonances:
    """Causes of rises on the map's rays named after the ray: ``order 76.87 = line 3013 Hz``.

    Parameters
    ----------
    res : Resonances
        Rises classified against the rays (each ray as a "mesh frequency" of order 1).

    Returns
    -------
    Resonances
        The same rises, their causes renamed.
    """

    cause = np.asarray([re.sub(r"^1 f_mesh = (.*) \[(order [^\]]+)\]$", r"\2 = \1", str(c))
                        for c in res.cause], dtype=object)
    return replace(res, cause=cause)


def classify_rises(map_ds: xr.Dataset, features: MapFeatures | None, fn: np.ndarray,
                   names: list[str], groups: list[tuple[str, float, int]], t: np.ndarray,
                   rpm: np.ndarray, st: AnalysisSettings, fmax: float, notes: list[str],
                   model: Any, modal: Any, span: tuple[float, float], in_per_ref: float
                   ) -> Resonances | None:
    """Rises of the map, classified per mesh frequency (or per shaft order without a model).

    Parameters
    ----------
    map_ds : xarray.Dataset
        The rpm-frequency map up to ``fmax``.
    features : MapFeatures or None
        Its rays and lines.
    fn : ndarray
        Natural frequencies of the model [Hz] (empty without a gear set).
    names : list of str
        Their names.
    groups : list of (str, float, int)
        Per mesh frequency: name, Hz per min⁻¹ of the reference shaft, orders.
    t, rpm : ndarray
        Time [s] and reference speed [min⁻¹] of the record.
    st : AnalysisSettings
        ``threshold_db``, ``tolerance``, ``n_max``.
    fmax : float
        Upper frequency [Hz].
    notes : list of str
        Receives what the classification could not do.
    model, modal : AssembledModel, ModalResult or None
        The gear set and its modes (the theory candidates).
    span : (float, float)
        Lowest and highest reference speed [min⁻¹].
    in_per_ref : float
        Input speed per reference speed.

    Returns
    -------
    Resonances or None
        None without a gear set when the map shows no line or no ray to classify against.
    """
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
    rays = strongest_rays(features)
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
    return ray_causes(merge_mesh_frequencies(parts, rpm_tolerance=1.5 * hop + 1e-9,
                                             frequency_tolerance=1.5 * float(
                                                  map_ds.attrs.get("resolution_hz", 1.0))))


def strongest_rays(features: MapFeatures | None) -> list[float]:
    """Orders of the strongest rays of the map (>= 0.5), at most :data:`MAX_RAYS`, sorted.

    Parameters
    ----------
    features : MapFeatures or None
        Rays and lines of the map.

    Returns
    -------
    list of float
        ``[]`` without features or rays.
    """
    if features is None or not np.size(features.orders):
        return []
    o = np.asarray(features.orders, dtype=float)
    s = np.asarray(features.order_strength_db, dtype=float)
    keep = np.flatnonzero(o >= 0.5)
    keep = keep[np.argsort(s[keep])[::-1][:MAX_RAYS]]
    return sorted(float(x) for x in o[keep])

