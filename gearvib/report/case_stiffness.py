"""Summed mesh stiffness of a central gear over a few mesh cycles (paper Figures 9 and 10).

:func:`summed_stiffness` evaluates the model's stiffness tables of some meshes at their own
phases, :func:`summed_sun_stiffness` does it for the first central gear (the sun of a simple
set), and :func:`simulated_stiffness` reads the simulated effective stiffness of a run when its
model cannot be rebuilt. Each gives a :class:`SummedStiffness`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr

from gearvib.model import AssembledModel
from gearvib.report.case_groups import model_groups
from gearvib.report.case_run import RPM_MIN_FRACTION

__all__ = ["SummedStiffness", "simulated_stiffness", "summed_stiffness",
           "summed_sun_stiffness"]


_STIFFNESS_CYCLES = 3


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
    """Summed stiffness of the meshes of the first central gear (the sun of a simple set).

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
        See :func:`summed_stiffness`.
    """
    g = model_groups(model)[0]
    if not g.centrals:
        raise ValueError(f"the gear set has no central-gear mesh (meshes: "
                         f"{', '.join(model.mesh_names)})")
    central, meshes = g.centrals[0]
    return summed_stiffness(model, meshes, cycles=cycles, points_per_cycle=points_per_cycle,
                            central=central, group=g.name)


def simulated_stiffness(ds: xr.Dataset, meshes: Sequence[str], f_per_rpm: float,
                        central: str, group: str) -> SummedStiffness | None:
    """Summed simulated stiffness over the first few mesh cycles above 2 % of the top speed.

    Used when the model cannot be rebuilt: the run's ``mesh_stiffness`` of the meshes, over
    three mesh cycles from the first sample faster than
    :data:`~gearvib.report.case_run.RPM_MIN_FRACTION` of the top speed.

    Parameters
    ----------
    ds : xarray.Dataset
        The run (``mesh_stiffness``, ``input_angle``, ``input_speed``).
    meshes : sequence of str
        The meshes to sum.
    f_per_rpm : float
        Their mesh frequency per input speed [Hz per min^-1].
    central, group : str
        Names stored in the result.

    Returns
    -------
    SummedStiffness or None
        None without ``mesh_stiffness`` or with fewer than 10 samples in the cycles.
    """
    if not meshes or "mesh_stiffness" not in ds:
        return None
    angle = np.asarray(ds["input_angle"].values, dtype=float)
    cyc = np.abs(angle) / (2 * math.pi) * f_per_rpm * 60.0  # mesh cycles since start
    sp = np.abs(ds["input_speed"].values)
    start = int(np.argmax(sp > RPM_MIN_FRACTION * sp.max()))
    sel = (cyc >= cyc[start]) & (cyc <= cyc[start] + _STIFFNESS_CYCLES)
    if sel.sum() < 10:
        return None
    k = np.asarray(ds["mesh_stiffness"].sel(mesh=list(meshes)).values, dtype=float)[:, sel]
    return SummedStiffness(cycles=cyc[sel] - cyc[start], total=k.sum(axis=0), per_mesh=k,
                           mesh_names=tuple(meshes), source="simulation", central=central,
                           group=group)

