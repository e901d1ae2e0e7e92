"""Static tooth forces: the normal force of every mesh's loaded flank under a run's load.

The static tooth force ``F_stat,m`` of mesh ``m`` is the normal force of its loaded flank in the
static equilibrium of the gear set under the transmitted torque, with every flank stiffness at
its mean over the mesh cycle. The torque is the run's: its load torque and, for a speed ramp,
the d'Alembert torque of the ramp's acceleration (for a torque or motor drive: the input torque
at ``t = 0`` with the acceleration it gives the set) -- exactly the equilibrium
:func:`gearvib.simulation.equilibrium.static_equilibrium` computes for the start of the run, on
the mean stiffness. It is the reference force of the dynamic factor ``K_v`` (ISO 6336-1 /
DIN 3990, method A) of the sweeps (:mod:`gearvib.sweep.loadfactor`).

Hand checks: a single gear pair carries ``T / r_b`` whatever its stiffness (``T`` the torque on
the gear of base radius ``r_b``); ``N`` equally loaded planets carry ``T_sun / (N r_b,sun)``
each in the sun meshes and the same force in the ring meshes (the planet is in equilibrium).
The loaded flank is the one that carries the static force (the larger one when a negative
backlash loads both).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gearvib.model import AssembledModel
from gearvib.simulation.conditions import Conditions
from gearvib.simulation.equilibrium import static_equilibrium
from gearvib.simulation.run_setup import prepare_run

__all__ = ["StaticToothForces", "static_tooth_forces"]


@dataclass(frozen=True)
class StaticToothForces:
    """Static tooth forces of a gear set under a run's load.

    Attributes
    ----------
    mesh : tuple of str
        Mesh names (``model.mesh_names``).
    force : ndarray, shape (n_mesh,)
        Static normal force of the loaded flank [N] (0 for an unloaded mesh).
    flank : ndarray of int, shape (n_mesh,)
        Loaded flank: 0 left (loaded when the central gear drives the planet), 1 right.
    deflection : ndarray, shape (n_mesh,)
        Static mesh deflection along the line of action [m].
    """

    mesh: tuple[str, ...]
    force: np.ndarray
    flank: np.ndarray
    deflection: np.ndarray

    def as_dict(self) -> dict[str, float]:
        """``{mesh name: static force [N]}``."""
        return {m: float(f) for m, f in zip(self.mesh, self.force, strict=True)}


def static_tooth_forces(model: AssembledModel, conditions: Conditions, *,
                        gyroscopic: bool = False) -> StaticToothForces:
    """Static tooth force of every mesh at mean stiffness under a run's torque.

    Parameters
    ----------
    model : AssembledModel
        The gear set.
    conditions : SpeedRamp, SpeedTable, TorqueDriven or MotorDriven
        The run's operating conditions (they give the load torque, the drive and the initial
        acceleration), e.g. ``SpeedRamp(0, 4000, 1.0, input_torque=60.0)``.
    gyroscopic : bool
        As in :func:`gearvib.simulate.simulate` (centripetal stiffness at the initial speed).

    Returns
    -------
    StaticToothForces
        Forces in N, one per mesh of ``model.mesh_names``.

    Raises
    ------
    gearvib.simulate.SimulationError
        No static equilibrium exists (e.g. a torque that no contact can carry).

    Examples
    --------
    >>> from gearvib.assembly import assemble
    >>> from gearvib.config import load_gearset
    >>> from gearvib.simulate import SpeedRamp, static_tooth_forces
    >>> model = assemble(load_gearset("paper-case1"))
    >>> f = static_tooth_forces(model, SpeedRamp(1000.0, 1000.0, 0.1, input_torque=60.0))
    >>> round(f.as_dict()["sun-planet1"])  # 60 N m / (3 planets x 38.8 mm base radius)
    516
    """
    setup = prepare_run(model, conditions, gyroscopic)
    system = setup.system
    left_mean = system.left_tables.mean(axis=1)
    right_mean = system.right_tables.mean(axis=1)
    mean_system = replace(
        system,
        left_tables=np.repeat(left_mean[:, None], system.left_tables.shape[1], axis=1),
        right_tables=np.repeat(right_mean[:, None], system.right_tables.shape[1], axis=1),
    )
    q, _ = static_equilibrium(mean_system, setup.mass, setup.rigid, setup.rigid * setup.omega0,
                              rigid_acceleration=setup.alpha0, free_rigid=setup.free_rigid,
                              mesh_names=model.mesh_names)
    delta = system.mesh_vectors @ q
    delta_back = system.back_vectors @ q  # the back flank's own line of action
    half = 0.5 * system.backlash
    f_left = np.where(delta > half, left_mean * (delta - half), 0.0)
    f_right = np.where(delta_back < -half, -right_mean * (delta_back + half), 0.0)
    flank = (f_right > f_left).astype(np.int64)
    force = np.where(flank == 0, f_left, f_right)
    return StaticToothForces(mesh=tuple(model.mesh_names), force=force, flank=flank,
                             deflection=delta)
