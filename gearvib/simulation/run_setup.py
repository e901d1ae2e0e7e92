"""Model + operating conditions -> the kernel arrays of one run (:func:`prepare_run`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from gearvib import kernels as kn
from gearvib.checks import check_count, check_instance, check_matrix, check_vector
from gearvib.faults.law import FaultLaw, build_fault_law
from gearvib.model import AssembledModel
from gearvib.simulation.conditions import (
    RAD_S_PER_RPM,
    Conditions,
    DriveCoupling,
    MotorDriven,
    SpeedRamp,
    SpeedTable,
    TorqueDriven,
)
from gearvib.simulation.frequencies import (
    check_mass,
    elastic_frequencies,
    stiffest_matrix,
    undamped_frequencies,
)

__all__ = [
    "COUPLING_FREQUENCY_FRACTION",
    "RunSetup",
    "check_model",
    "coupling_matrices",
    "default_coupling",
    "drive_sensing",
    "prepare_run",
    "with_coupling",
]

COUPLING_FREQUENCY_FRACTION = 0.1
"""Default drive-coupling frequency as a fraction of the lowest elastic natural frequency."""


def check_model(model: AssembledModel) -> None:
    """Reject models the kernels cannot integrate (negative or non-finite stiffness, shapes).

    Raises
    ------
    ValueError
        Naming the offending array (and mesh for a negative stiffness table).
    TypeError
        ``model`` is not an :class:`~gearvib.model.AssembledModel`.
    """
    check_instance(model, AssembledModel, "model")
    n = model.n_dof
    for name in ("mass", "stiffness", "damping", "gyroscopic", "centripetal"):
        a = np.asarray(getattr(model, name))
        if a.shape != (n, n) or not np.all(np.isfinite(a)):
            raise ValueError(f"model.{name} must be a finite ({n}, {n}) array")
    for name in ("mesh_vectors", "back_vectors"):
        vec = np.asarray(getattr(model, name), dtype=float)
        if vec.shape != (model.n_mesh, n) or not np.all(np.isfinite(vec)):
            raise ValueError(f"model.{name} must be a finite ({model.n_mesh}, {n}) array")
    for name in ("mesh_stiffness_tables", "mesh_back_tables"):
        tab = np.asarray(getattr(model, name), dtype=float)
        if tab.ndim != 2 or tab.shape[0] != model.n_mesh or tab.shape[1] < 1:
            raise ValueError(f"model.{name} must have shape (n_mesh, n_table)")
        if not np.all(np.isfinite(tab)):
            raise ValueError(f"model.{name} holds non-finite values")
        bad = np.flatnonzero(tab.min(axis=1) < 0)
        if bad.size:
            m = int(bad[0])
            raise ValueError(
                f"negative stiffness in model.{name} for mesh {model.mesh_names[m]!r} "
                f"(min {tab[m].min():.4g} N/m); a mesh stiffness table must be >= 0"
            )
    if np.any(np.asarray(model.mesh_damping) < 0) or np.any(np.asarray(model.bearing_damping) < 0):
        raise ValueError("negative mesh or bearing damping")
    if model.rotation_dofs.get(model.input_member, -1) < 0:
        raise ValueError(f"input member {model.input_member!r} has no rotation coordinate")


@dataclass
class RunSetup:
    """The kernel arrays and kinematics of one run (:func:`prepare_run`).

    Attributes
    ----------
    system : KernelSystem
        Arrays handed to the kernels (drive and load parameters included).
    mass : ndarray, shape (n, n)
        Mass matrix of the run (load inertia included).
    rigid : ndarray, shape (n,)
        Rigid-body velocity per unit input speed.
    omega0, alpha0 : float
        Input speed [rad/s] and prescribed input acceleration [rad/s^2] at ``t = 0``.
    free_rigid : bool
        The rigid-body mode is free (torque- or motor-driven run without a restoring support).
    duration : float or None
        Default simulated time of the conditions [s].
    speed_max : float
        Highest expected input speed [rad/s] (step choice, runaway guard).
    coupling : DriveCoupling or None
        Drive coupling of a speed-driven run.
    load : (T0, c1, c2)
        Load-torque coefficients at the output member.
    drive : str
        ``"speed"``, ``"torque"`` or ``"motor"``.
    torque_sign : float
        Sense of the mean load at ``t = 0`` (+1: the input drives forward; -1: the load torque
        reversed): selects the loaded flanks of the mean system
        (:meth:`AssembledModel.mesh_contacts`).
    faults : FaultLaw or None
        The model's local tooth faults and manufacturing errors as kernel data (None: a
        healthy set, whose run is that of the model's tables alone).
    """

    system: kn.KernelSystem
    mass: np.ndarray
    rigid: np.ndarray
    omega0: float
    alpha0: float
    free_rigid: bool
    duration: float | None
    speed_max: float
    coupling: DriveCoupling | None
    load: tuple[float, float, float]
    drive: str
    torque_sign: float = 1.0
    faults: FaultLaw | None = None


def default_coupling(model: AssembledModel, torque_sign: float = 1.0) -> DriveCoupling:
    """The default drive of speed-driven runs: a speed controller on the rigid-body mode.

    The drive torque acts on the input member, its angle and speed are those of the set's
    rigid-body coordinate (``sensing = "rigid-body"``, :class:`DriveCoupling`): the elastic
    modes do not feed back into it, so it keeps the prescribed speed without adding
    stiffness or damping to them (their frequencies and damping are those of
    :func:`gearvib.modal.modal_analysis`, the free set). The rigid-body mode lies at
    :data:`COUPLING_FREQUENCY_FRACTION` x the lowest elastic natural frequency of the mean
    system (the flanks in contact at the mean load of sense ``torque_sign``, both flanks of
    a preloaded mesh: :meth:`AssembledModel.mesh_contacts`), critically damped:
    ``k = J_eff w_c**2``, ``c = 2 J_eff w_c`` with ``J_eff`` the inertia of the kinematic
    motion reduced to the input member.

    The rigid-body motion strains nothing (``K r = 0``: :meth:`AssembledModel.
    rigid_body_velocity` refuses a set whose kinematic motion a support resists), so the
    elastic modes are exactly those of the free set whenever the set's own damping does not
    act on it either (``C r = 0``: no torsional damper to ground on a turning member).
    """
    check_instance(model, AssembledModel, "model")
    rigid = model.rigid_body_velocity()
    k_in = int(model.rotation_dofs[model.input_member])
    mass = np.asarray(model.mass, float)
    k_mean = model.mean_stiffness_matrix(torque_sign)
    f_el = elastic_frequencies(undamped_frequencies(mass, k_mean), mass, k_mean)
    if f_el.size == 0:
        raise ValueError("the model has no elastic mode to choose a drive coupling from")
    j_eff = float(rigid @ model.mass @ rigid) / rigid[k_in] ** 2
    wc = 2.0 * math.pi * COUPLING_FREQUENCY_FRACTION * float(f_el[0])
    return DriveCoupling(float(j_eff * wc * wc), float(2.0 * j_eff * wc), "rigid-body")


def _drive_arrays(mass: Any, rigid: Any, k_in: Any) -> tuple[np.ndarray, np.ndarray, int]:
    """``mass`` (:func:`check_mass`), the rigid-body velocity ``rigid`` (one value per DOF,
    ``r^T M r > 0``) and the input DOF ``k_in`` (an index into them), checked."""
    mass = check_mass(mass)
    n = mass.shape[0]
    rigid = check_vector(rigid, "rigid", n, max_abs=1e12)
    k_in = check_count(k_in, "k_in", low=0, high=n - 1)
    if not float(rigid @ mass @ rigid) > 0.0 or rigid[k_in] == 0.0:
        raise ValueError("rigid must be a rigid-body motion that moves the input DOF k_in")
    return mass, rigid, k_in


def drive_sensing(mass: np.ndarray, rigid: np.ndarray, k_in: int) -> np.ndarray:
    """The row ``p = r_in M r / (r^T M r)`` whose product with ``q`` is the rigid-body
    coordinate in radians of the input member (``p . q = phi`` for the rigid rotation ``q = r
    phi / r_in``; the elastic modes, M-orthogonal to ``r``, give 0): the angle a
    rigid-body-sensing drive controls (:class:`DriveCoupling`)."""
    mass, rigid, k_in = _drive_arrays(mass, rigid, k_in)
    mr = mass @ rigid
    return mr * (float(rigid[k_in]) / float(rigid @ mr))


def coupling_matrices(mass: np.ndarray, rigid: np.ndarray, k_in: int,
                      coupling: DriveCoupling) -> tuple[np.ndarray, np.ndarray]:
    """Symmetric stiffness and damping matrices ``(K_d, C_d)`` of a drive coupling in the
    linearised system.

    ``"input"``: ``k e e^T`` and ``c e e^T`` on the input coordinate. ``"rigid-body"``:
    ``k p p^T`` and ``c p p^T`` (:func:`drive_sensing`). The run applies the controller's
    torque on the input member (``k e p^T``, not symmetric); both forms leave the elastic
    modes of a free set untouched and give its rigid-body mode ``k`` and ``c`` on ``J``, so
    they have the same eigenvalues (the simulated form is block-triangular in modal
    coordinates: the elastic modes are forced by the rigid-body coordinate but do not act
    back). The symmetric form serves the step choice, the stability analysis and anything
    that needs a symmetric mean system.
    """
    mass, rigid, k_in = _drive_arrays(mass, rigid, k_in)
    check_instance(coupling, DriveCoupling, "coupling")
    n = mass.shape[0]
    if coupling.sensing == "rigid-body":
        p = drive_sensing(mass, rigid, k_in)
        shape = np.outer(p, p)
    else:
        shape = np.zeros((n, n))
        shape[k_in, k_in] = 1.0
    return coupling.stiffness * shape, coupling.damping * shape


def with_coupling(stiffness: np.ndarray, mass: np.ndarray, rigid: np.ndarray, k_in: int,
                  coupling: DriveCoupling) -> np.ndarray:
    """A copy of ``stiffness`` with the coupling's symmetric stiffness
    (:func:`coupling_matrices`) added where it is not zero (an input coupling: the one entry
    of the input coordinate, as the step choice always added it)."""
    kd = coupling_matrices(mass, rigid, k_in, coupling)[0]
    out = np.array(check_matrix(stiffness, "stiffness", kd.shape[0]), dtype=float, copy=True)
    nz = kd != 0.0
    out[nz] += kd[nz]
    return out


def prepare_run(
    model: AssembledModel, conditions: Conditions, gyroscopic: bool
) -> RunSetup:
    """Translate a model and its operating conditions into the arrays of one run.

    Parameters
    ----------
    model : AssembledModel
        The gear set.
    conditions : SpeedRamp, SpeedTable, TorqueDriven or MotorDriven
        Operating conditions.
    gyroscopic : bool
        Switch the gyroscopic and centripetal terms on.

    Returns
    -------
    RunSetup

    Raises
    ------
    ValueError
        If the conditions need an output rotation the model does not have.
    TypeError
        For an unsupported conditions object.
    """
    check_instance(model, AssembledModel, "model")
    if not isinstance(gyroscopic, bool | np.bool_):
        raise TypeError(f"gyroscopic must be a bool; got {type(gyroscopic).__name__}")
    n = model.n_dof
    rigid = model.rigid_body_velocity()
    mass = np.array(model.mass, dtype=float)
    k_in = int(model.rotation_dofs[model.input_member])
    k_out = int(model.rotation_dofs.get(model.output_member, -1))
    ratio_out = float(model.kinematic_ratios.get(model.output_member, 0.0))
    sense = 1.0 if ratio_out >= 0 else -1.0
    ipar = np.array([kn.DRIVE_NONE, k_in, k_out, model.carrier_dof, int(bool(gyroscopic))])
    fpar = np.zeros(kn.N_FPAR)
    fpar[kn.FP_OUTDIR] = sense
    speed_tab = np.zeros((3, 1))
    torque_tab = np.zeros((2, 1))
    coupling = None
    sensing = None
    free_rigid = False
    duration: float | None
    load: tuple[float, float, float]
    if isinstance(conditions, SpeedRamp | SpeedTable):
        ipar[kn.IP_MODE] = kn.DRIVE_SPEED
        t_nodes, rpm = conditions.table()
        w = rpm * RAD_S_PER_RPM
        phi = np.concatenate([[0.0], np.cumsum(np.diff(t_nodes) * (w[1:] + w[:-1]) / 2)])
        speed_tab = np.vstack([t_nodes, w, phi])
        ang = np.zeros(1)
        spd = np.zeros(1)
        kn.speed_profile(speed_tab, np.zeros(1), ang, spd)
        speed_tab[2] -= ang[0]  # phi(0) = 0
        omega0 = float(spd[0])
        seg = np.searchsorted(t_nodes, 0.0, side="right") - 1
        alpha0 = 0.0
        if 0 <= seg < len(t_nodes) - 1:
            alpha0 = float((w[seg + 1] - w[seg]) / (t_nodes[seg + 1] - t_nodes[seg]))
        if conditions.input_torque is not None:
            if ratio_out == 0.0 or k_out < 0:
                raise ValueError("input_torque needs a rotating output member")
            t_load = float(conditions.input_torque) / abs(ratio_out)
        else:
            t_load = float(conditions.load_torque)
        if t_load != 0.0 and k_out < 0:
            raise ValueError(f"output member {model.output_member!r} has no rotation coordinate")
        load = (t_load, 0.0, 0.0)
        torque_sign = -1.0 if t_load < 0 else 1.0
        coupling = conditions.coupling or default_coupling(model, torque_sign)
        fpar[kn.FP_KC] = coupling.stiffness
        fpar[kn.FP_CC] = coupling.damping
        if coupling.sensing == "rigid-body":
            sensing = drive_sensing(mass, rigid, k_in)
        speed_max = float(np.abs(w).max())
        duration = float(conditions.duration)
        drive = "speed"
    elif isinstance(conditions, TorqueDriven | MotorDriven):
        if isinstance(conditions, TorqueDriven):
            ipar[kn.IP_MODE] = kn.DRIVE_TORQUE
            table = conditions.input_torque
            assert isinstance(table, tuple)  # __post_init__ stores (times, torques)
            tt, tv = table
            torque_tab = np.vstack([np.array(tt), np.array(tv)])
            drive = "torque"
        else:
            ipar[kn.IP_MODE] = kn.DRIVE_MOTOR
            torque_tab = np.vstack([np.array(conditions.speed_rpm) * RAD_S_PER_RPM,
                                    np.array(conditions.torque)])
            drive = "motor"
        if k_out < 0 and (conditions.load_inertia or any(conditions.load_torque)):
            raise ValueError(f"output member {model.output_member!r} has no rotation coordinate")
        if k_out >= 0:
            mass[k_out, k_out] += conditions.load_inertia
        load = conditions.load_torque
        omega0 = conditions.start_rpm * RAD_S_PER_RPM
        t_in = float(np.interp(0.0 if drive == "torque" else omega0, torque_tab[0],
                               torque_tab[1]))
        torque_sign = -1.0 if t_in < 0 else 1.0
        alpha0 = 0.0
        k_mean = model.mean_stiffness_matrix(torque_sign)
        free_rigid = bool(
            np.abs(k_mean @ rigid).max() <= 1e-9 * np.abs(k_mean).max() * np.abs(rigid).max()
        )
        max_rpm = conditions.max_rpm
        assert max_rpm is not None  # __post_init__ fills it in
        speed_max = max(abs(max_rpm), abs(conditions.start_rpm)) * RAD_S_PER_RPM
        duration = conditions.duration
    else:
        raise TypeError(f"unsupported operating conditions {type(conditions).__name__}")
    fpar[kn.FP_T0], fpar[kn.FP_C1], fpar[kn.FP_C2] = load
    fpar[kn.FP_SPEED_LIMIT] = 3.0 * speed_max + 100.0
    gyro, centri = model.carrier_frame_operators()
    law = build_fault_law(model) if model.faults else None
    fault_arrays: dict = {}
    f_const = np.zeros(n)
    if law:
        # the scale of the short sub-steps: the highest natural frequency of the stiffest
        # system, as the step choice computes it (gearvib.simulate)
        k_max = stiffest_matrix(model, torque_sign)
        if coupling is not None:
            k_max = with_coupling(k_max, mass, rigid, k_in, coupling)
        f_max = float(undamped_frequencies(mass, k_max).max(initial=0.0))
        rec, fints, fvals = law.pack(kn.short_step_header(2.0 * math.pi * f_max))
        fault_arrays = {"fault_records": rec, "fault_ints": fints, "fault_vals": fvals,
                        "fault_jumps": law.cycle_jumps()}
        f_const = law.f_const.copy()
    else:
        law = None
    system = kn.KernelSystem(
        minv=np.linalg.inv(mass),
        stiffness=model.stiffness,
        damping=model.damping,
        gyroscopic=gyro,
        centripetal=centri,
        mesh_vectors=np.asarray(model.mesh_vectors, dtype=float).reshape(model.n_mesh, n),
        mesh_position_vectors=np.asarray(model.mesh_position_vectors, float).reshape(
            model.n_mesh, n
        ),
        mesh_position_offsets=model.mesh_position_offsets,
        left_tables=model.mesh_stiffness_tables,
        right_tables=model.mesh_back_tables,
        backlash=model.mesh_backlash,
        mesh_damping=model.mesh_damping,
        f_const=f_const,
        ipar=ipar,
        fpar=fpar,
        speed_table=speed_tab,
        torque_table=torque_tab,
        deflection_limit=np.full(model.n_mesh, np.inf),
        mesh_back_vectors=model.mesh_back_vectors,
        mesh_damping_law=np.where(model.viscous_meshes, kn.DAMPING_VISCOUS, kn.DAMPING_GATED)
        if model.mesh_damping_laws else None,
        drive_sensing=sensing,
        **fault_arrays,
    )
    return RunSetup(
        system,
        mass,
        rigid,
        omega0,
        alpha0,
        free_rigid,
        duration,
        speed_max,
        coupling,
        (float(load[0]), float(load[1]), float(load[2])),
        drive,
        torque_sign,
        law,
    )
