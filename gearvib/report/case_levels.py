"""NVH levels of a simulated run: order cuts, overall level, waterfall and Campbell data.

:func:`case_levels` computes them (:func:`gearvib.report.nvh.signal_levels`) for the housing
sensors of a run (at most :data:`MAX_SENSORS`, the first one primary) and for a tooth force.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

from analysis.maps import RpmFrequencyMap
from gearvib.catalogue import gear_set_catalogue
from gearvib.model import AssembledModel
from gearvib.report.case_groups import MeshGroup
from gearvib.report.nvh import SignalLevels, signal_levels
from gearvib.report.rises import merged_modes
from gearvib.report.study import AnalysisSettings

__all__ = ["MAX_SENSORS", "case_levels"]


MAX_SENSORS = 2
"""Housing sensors of a run that get the NVH pages (order cuts, overall level, ...)."""


def case_levels(ds: xr.Dataset, case: str, groups: Sequence[MeshGroup],
                model: AssembledModel | None, settings: AnalysisSettings, fn: np.ndarray,
                names: list[str], fmap: RpmFrequencyMap, force: np.ndarray, t: np.ndarray,
                fs: float, fmax: float, force_mesh: str) -> list[SignalLevels]:
    """NVH levels of the housing sensors (primary: the first) and of the tooth force.

    Parameters
    ----------
    ds : xarray.Dataset
        The run (``input_angle``, ``sensor_acceleration``).
    case : str
        Case name.
    groups : sequence of MeshGroup
        Mesh-frequency groups (their mesh orders).
    model : AssembledModel or None
        The gear set (its kinematic catalogue; None without).
    settings : AnalysisSettings
        Analysis settings.
    fn : ndarray
        Natural frequencies [Hz] (repeated ones merged:
        :func:`gearvib.report.rises.merged_modes`).
    names : list of str
        Their names.
    fmap : RpmFrequencyMap
        Sonogram of the tooth force (its resolution sets the lower band edge).
    force : ndarray
        The tooth force of ``force_mesh`` [N].
    t : ndarray
        Time [s].
    fs, fmax : float
        Sample rate and upper frequency [Hz].
    force_mesh : str
        The mesh of ``force``.

    Returns
    -------
    list of SignalLevels
        One per housing sensor (at most :data:`MAX_SENSORS`), then the tooth force.
    """
    angle = np.asarray(ds["input_angle"].values, dtype=float)
    if angle[-1] < angle[0]:
        angle = -angle
    cat, member = None, ""
    if model is not None:
        member = str(model.input_member)
        try:
            cat = gear_set_catalogue(model, reference=member, mesh_harmonics=1, harmonics=1,
                                     sidebands=1)
        except ValueError:  # e.g. a description without tooth numbers
            cat = None
    mesh_orders = [(g.name, g.order) for g in groups]
    f_modes, n_modes = merged_modes(fn, names)
    band = (2.0 * float(fmap.resolution_hz), fmax)
    common: dict[str, Any] = {
        "fs": fs, "case": case, "mesh_orders": mesh_orders, "settings": settings,
        "catalogue": cat, "reference_member": member, "angle": angle,
        "natural_frequencies_hz": f_modes, "natural_names": n_modes, "frequency_range": band,
        "reference": f"input shaft{f' ({member})' if member else ''}"}
    out = []
    sensors = ([str(s) for s in ds["sensor"].values][:MAX_SENSORS]
               if "sensor_acceleration" in ds.variables else [])
    for k, name in enumerate(sensors):
        acc = np.asarray(ds["sensor_acceleration"].sel(sensor=name).values, dtype=float)
        out.append(signal_levels(acc - acc.mean(), signal=f"housing acceleration {name}",
                                 units=str(ds["sensor_acceleration"].attrs.get("units",
                                                                               "m s-2")),
                                 primary=k == 0, **common))
    out.append(signal_levels(force - force.mean(), signal=f"tooth force {force_mesh}",
                             units="N", primary=not sensors, frequency_map=fmap, **common))
    return out
