"""Tooth-load summaries of one run: static tooth force, dynamic factor K_v, DTE, contact loss.

Definitions (the user page is ``docs/sweeps.md``)
--------------------------------------------------

*Static tooth force* ``F_stat,m`` of mesh ``m`` (:func:`gearvib.simulate.static_tooth_forces`,
defined in :mod:`gearvib.simulation.tooth_forces`): the normal force of the mesh's loaded flank
in the static equilibrium of the same gear set under the same transmitted torque, with every flank
stiffness at its mean over the mesh cycle. "Same torque" means the run's load torque and, for a
speed ramp, the d'Alembert torque of its (constant) acceleration: the equilibrium is exactly
the one :func:`gearvib.simulate.static_equilibrium` computes for the start of the run, with the
stiffness tables replaced by their means (for a torque or motor drive: the input torque at
``t = 0`` with the acceleration it gives the set). For a single gear pair this is ``T / r_b``
whatever the stiffness; for equally loaded planets it is the nominal share of each planet. The
loaded flank is the flank that carries this static force (the larger one when a negative
backlash loads both).

*Dynamic factor* ``K_v,m = max_t F_m(t) / F_stat,m`` over the summary window, with ``F_m`` the
simulated normal force of the loaded flank (mesh damping force included, as in the contact law).
This is the ISO 6336-1 / DIN 3990 dynamic factor by method A (full dynamic analysis): maximum
dynamic tooth load over static tooth load at the same transmitted torque. With the mean
stiffness as reference, a quasi-static variation of the load sharing between planets over the
mesh cycle (ISO's K_gamma) is part of K_v; for a single pair or in-phase planets there is none.
``F_m`` is the stored output signal: it is band-limited to ``0.4 fs_out`` by the decimation
filter, so for stiffness models with jumps the peak right after a jump is smoothed over about
``2 / fs_out`` (raise ``fs_out`` to resolve it).

*Peak-to-peak dynamic transmission error*: ``max - min`` of the mesh deflection along the line
of action (``mesh_deflection``) over the window [m].

*Contact-loss time fraction*: fraction of the window's output samples at which the loaded flank
is out of contact (``delta <= j/2`` for the left flank, ``delta >= -j/2`` for the right one;
back-flank impacts included); *back-flank contact fraction*: fraction with the other flank in
contact.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gearvib.simulate import StaticToothForces

__all__ = ["MeshLoads", "mesh_loads"]


@dataclass(frozen=True)
class MeshLoads:
    """Per-mesh load summaries over a window (see the module docstring).

    Attributes
    ----------
    dynamic_factor : ndarray, shape (n_mesh,)
        ``K_v`` (NaN for a mesh without static load).
    max_force : ndarray, shape (n_mesh,)
        Maximum normal force of the loaded flank [N].
    static_force : ndarray, shape (n_mesh,)
        Static tooth force [N].
    transmission_error_pp : ndarray, shape (n_mesh,)
        Peak-to-peak mesh deflection [m].
    contact_loss_fraction, back_contact_fraction : ndarray, shape (n_mesh,)
        Time fractions [1].
    loaded_flank : ndarray of str, shape (n_mesh,)
        ``"left"`` or ``"right"``.
    """

    dynamic_factor: np.ndarray
    max_force: np.ndarray
    static_force: np.ndarray
    transmission_error_pp: np.ndarray
    contact_loss_fraction: np.ndarray
    back_contact_fraction: np.ndarray
    loaded_flank: np.ndarray


def mesh_loads(normal_force: np.ndarray, deflection: np.ndarray, backlash: np.ndarray,
               static: StaticToothForces) -> MeshLoads:
    """Load summaries of one run over the samples given.

    Parameters
    ----------
    normal_force : ndarray, shape (n_mesh, 2, n_time)
        Compressive flank forces (left, right) [N] in the window.
    deflection : ndarray, shape (n_mesh, n_time)
        Mesh deflection [m] in the window.
    backlash : ndarray, shape (n_mesh,)
        Total normal backlash ``j`` [m].
    static : StaticToothForces
        From :func:`gearvib.simulate.static_tooth_forces` (the same run's model and
        conditions).

    Returns
    -------
    MeshLoads
    """
    n_mesh = normal_force.shape[0]
    if normal_force.shape[2] == 0:
        raise ValueError("the summary window holds no output sample")
    rows = np.arange(n_mesh)
    loaded = normal_force[rows, static.flank, :]
    max_force = loaded.max(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        kv = np.where(static.force > 0, max_force / np.where(static.force > 0, static.force, 1.0),
                      np.nan)
    half = 0.5 * np.asarray(backlash, dtype=float)[:, None]
    left_in = deflection > half
    right_in = deflection < -half
    loaded_in = np.where(static.flank[:, None] == 0, left_in, right_in)
    back_in = np.where(static.flank[:, None] == 0, right_in, left_in)
    return MeshLoads(
        dynamic_factor=kv,
        max_force=max_force,
        static_force=static.force.copy(),
        transmission_error_pp=deflection.max(axis=1) - deflection.min(axis=1),
        contact_loss_fraction=(~loaded_in).mean(axis=1),
        back_contact_fraction=back_in.mean(axis=1),
        loaded_flank=np.where(static.flank == 0, "left", "right"),
    )
