"""Run-up simulation of an assembled gear set: operating conditions, step choice, decimation.

:func:`simulate` integrates the equations of :mod:`gearvib.kernels` with a fixed-step classical
Runge-Kutta scheme, starting from the static equilibrium under the initial load, and returns a
:class:`RunUpResult` whose :meth:`RunUpResult.to_dataset` gives a CF-annotated
:class:`xarray.Dataset`. The user page is ``docs/simulator.md``.

Sign conventions
----------------
Speeds and torques at the input member are positive in the member's positive rotation sense
(``model.rotation_dofs[model.input_member]``). The load torque at the output member always
*resists* the forward motion of the output member (the sense of
``model.kinematic_ratios[model.output_member]``).
"""

from __future__ import annotations

import hashlib
import json
import math
import time as _time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field

import numpy as np
import scipy.linalg
import scipy.signal
import xarray as xr

from gearvib import __version__
from gearvib import kernels as kn
from gearvib.model import AssembledModel

__all__ = [
    "INTEGRATOR",
    "DriveCoupling",
    "RunUpResult",
    "SimulationError",
    "SpeedRamp",
    "SpeedTable",
    "StepChoice",
    "TorqueDriven",
    "choose_step",
    "decimation_filter",
    "default_coupling",
    "simulate",
    "static_equilibrium",
]

INTEGRATOR = "classical Runge-Kutta 4, fixed step, sub-steps ending at stiffness jumps"
STEPS_PER_NATURAL_PERIOD = 40
"""Default resolution of the highest natural frequency (``dt <= 1 / (40 f_max)``)."""
MIN_STEPS_PER_NATURAL_PERIOD = 10
"""A user step coarser than ``1 / (10 f_max)`` is rejected."""
STEPS_PER_MESH_CYCLE = 40
"""Default resolution of the highest mesh frequency (``dt <= 1 / (40 f_mesh)``).

Jumps of the stiffness tables (tooth-pair changes) need no finer step: the kernel ends its
sub-steps at them (:func:`gearvib.kernels.jump_positions`), so every RK4 stage sees a smooth
stiffness and the step keeps fourth-order accuracy."""
DEFAULT_FS_OUT = 20_000.0
CHUNK_DURATION = 0.05
"""Simulated time per kernel call [s]."""
COUPLING_FREQUENCY_FRACTION = 0.1
"""Default drive-coupling frequency as a fraction of the lowest elastic natural frequency."""
_RPM = 2.0 * math.pi / 60.0
_NICE_MANTISSAS = (1.0, 1.2, 1.25, 1.6, 2.0, 2.4, 2.5, 3.2, 4.0, 4.8, 5.0, 5.12, 6.4, 8.0)


class SimulationError(RuntimeError):
    """The integration failed (numerical blow-up or no static equilibrium)."""


# --------------------------------------------------------------------------- conditions


@dataclass(frozen=True)
class DriveCoupling:
    """Torsional spring-damper between the prescribed input angle and the input member.

    Parameters
    ----------
    stiffness : float
        Torsional stiffness [N m/rad].
    damping : float
        Torsional damping [N m s/rad].
    """

    stiffness: float
    damping: float

    def __post_init__(self) -> None:
        if not (self.stiffness > 0 and self.damping >= 0):
            raise ValueError("DriveCoupling needs stiffness > 0 and damping >= 0")


@dataclass(frozen=True)
class SpeedRamp:
    """Linear speed ramp of the input member from ``start_rpm`` to ``end_rpm``.

    Parameters
    ----------
    start_rpm, end_rpm : float
        Input speed at ``t = 0`` and ``t = duration`` [min^-1].
    duration : float
        Ramp duration [s]; the default simulated duration. The speed stays at ``end_rpm`` after.
    load_torque : float
        Constant load torque at the output member [N m], resisting its forward rotation.
    input_torque : float, optional
        Alternative to ``load_torque``: the (lossless) input torque [N m]; the load torque is then
        ``input_torque / |kinematic ratio of the output member|``.
    coupling : DriveCoupling, optional
        Drive coupling; the default is chosen from the model (see :func:`simulate`).
    """

    start_rpm: float
    end_rpm: float
    duration: float
    load_torque: float = 0.0
    input_torque: float | None = None
    coupling: DriveCoupling | None = None

    def __post_init__(self) -> None:
        if not self.duration > 0:
            raise ValueError("SpeedRamp.duration must be > 0")

    def table(self) -> tuple[np.ndarray, np.ndarray]:
        """Nodes ``(time [s], speed [min^-1])`` of the piecewise-linear profile."""
        return np.array([0.0, self.duration]), np.array([self.start_rpm, self.end_rpm], float)


@dataclass(frozen=True)
class SpeedTable:
    """Piecewise-linear input speed over time (held constant outside the table).

    Parameters
    ----------
    time : sequence of float
        Strictly increasing times [s]; the last one is the default simulated duration.
    rpm : sequence of float
        Input speed at those times [min^-1].
    load_torque, input_torque, coupling
        As in :class:`SpeedRamp`.
    """

    time: Sequence[float]
    rpm: Sequence[float]
    load_torque: float = 0.0
    input_torque: float | None = None
    coupling: DriveCoupling | None = None

    def __post_init__(self) -> None:
        t = tuple(float(v) for v in np.asarray(self.time, dtype=float).ravel())
        r = tuple(float(v) for v in np.asarray(self.rpm, dtype=float).ravel())
        if len(t) != len(r) or len(t) < 2 or np.any(np.diff(t) <= 0):
            raise ValueError("SpeedTable needs >= 2 strictly increasing times and as many speeds")
        object.__setattr__(self, "time", t)
        object.__setattr__(self, "rpm", r)

    @property
    def duration(self) -> float:
        """Last time of the table [s]."""
        return self.time[-1]

    def table(self) -> tuple[np.ndarray, np.ndarray]:
        """Nodes ``(time [s], speed [min^-1])``."""
        return np.array(self.time), np.array(self.rpm)


@dataclass(frozen=True)
class TorqueDriven:
    """Torque at the input member, speed-dependent load torque and load inertia at the output.

    Parameters
    ----------
    input_torque : float or (times, torques)
        Constant input torque [N m], or a piecewise-linear table of time [s] and torque [N m]
        (held constant outside).
    load_inertia : float
        Inertia added to the output member [kg m^2].
    load_torque : (T0, c1, c2)
        Load ``T0 + c1 w + c2 w |w|`` [N m] with ``w`` the forward output speed [rad/s];
        resisting.
    start_rpm : float
        Input speed at ``t = 0`` [min^-1] (rigid-body kinematics for the other members).
    duration : float, optional
        Default simulated duration [s]; the last table time if omitted.
    max_rpm : float
        Expected highest input speed [min^-1], used for the step choice (mesh frequency) and as
        a runaway guard (the run stops beyond 3x this speed).
    """

    input_torque: float | tuple[Sequence[float], Sequence[float]]
    load_inertia: float = 0.0
    load_torque: tuple[float, float, float] = (0.0, 0.0, 0.0)
    start_rpm: float = 0.0
    duration: float | None = None
    max_rpm: float = 6000.0

    def __post_init__(self) -> None:
        if np.ndim(self.input_torque) == 0:
            tt, tv = (0.0,), (float(self.input_torque),)
        else:
            a, b = self.input_torque
            tt = tuple(float(v) for v in np.asarray(a, dtype=float).ravel())
            tv = tuple(float(v) for v in np.asarray(b, dtype=float).ravel())
            if len(tt) != len(tv) or len(tt) < 1 or np.any(np.diff(tt) <= 0):
                raise ValueError("input_torque table needs strictly increasing times")
        object.__setattr__(self, "input_torque", (tt, tv))
        lt = tuple(float(v) for v in self.load_torque)
        if len(lt) != 3:
            raise ValueError("load_torque must be (T0, c1, c2)")
        object.__setattr__(self, "load_torque", lt)
        if self.load_inertia < 0:
            raise ValueError("load_inertia must be >= 0")
        if self.duration is None and len(tt) > 1:
            object.__setattr__(self, "duration", tt[-1])


Conditions = SpeedRamp | SpeedTable | TorqueDriven


# --------------------------------------------------------------------------- helpers


def _check_model(model: AssembledModel) -> None:
    """Reject models the kernels cannot integrate (negative or non-finite stiffness, shapes)."""
    n = model.n_dof
    for name in ("mass", "stiffness", "damping", "gyroscopic", "centripetal"):
        a = np.asarray(getattr(model, name))
        if a.shape != (n, n) or not np.all(np.isfinite(a)):
            raise ValueError(f"model.{name} must be a finite ({n}, {n}) array")
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


def _frequencies(mass: np.ndarray, stiffness: np.ndarray) -> np.ndarray:
    """Undamped natural frequencies [Hz] of ``(M, K)``, rigid-body modes included (0)."""
    w2 = scipy.linalg.eigh(stiffness, mass, eigvals_only=True)
    return np.sqrt(np.clip(w2, 0.0, None)) / (2.0 * math.pi)


def _elastic(freqs: np.ndarray) -> np.ndarray:
    """Drop rigid-body modes (relative threshold)."""
    if freqs.size == 0:
        return freqs
    return freqs[freqs > 1e-6 * freqs.max()]


def _nice_rates(lo: float, hi: float) -> list[float]:
    rates = []
    for e in range(0, 10):
        for m in _NICE_MANTISSAS:
            f = m * 10.0**e
            if lo <= f <= hi:
                rates.append(f)
    return sorted(rates)


@dataclass(frozen=True)
class StepChoice:
    """Internal step and output rate of a run.

    Attributes
    ----------
    dt : float
        Internal step [s].
    fs_out : float
        Output rate [Hz]; ``1 / dt = decimation * fs_out``.
    decimation : int
        Decimation factor ``D``.
    dt_recommended : float
        ``min(1 / (40 f_nat_max), 1 / (40 f_mesh_max))`` [s].
    dt_admissible : float
        Largest accepted step ``1 / (10 f_nat_max)`` [s].
    highest_natural_frequency, highest_mesh_frequency : float
        [Hz]; the natural frequency with every mesh at its largest table stiffness.
    """

    dt: float
    fs_out: float
    decimation: int
    dt_recommended: float
    dt_admissible: float
    highest_natural_frequency: float
    highest_mesh_frequency: float


def choose_step(
    f_nat_max: float,
    f_mesh_max: float,
    *,
    dt: float | None = None,
    fs_out: float | None = None,
    min_decimation: int = 4,
) -> StepChoice:
    """Choose the internal step and the output rate.

    Parameters
    ----------
    f_nat_max : float
        Highest natural frequency of the simulated system [Hz].
    f_mesh_max : float
        Highest mesh frequency of the run [Hz].
    dt, fs_out : float, optional
        User overrides. ``1 / dt`` must be an integer multiple of ``fs_out``.
    min_decimation : int
        Smallest decimation factor when ``dt`` is chosen automatically.

    Returns
    -------
    StepChoice

    Raises
    ------
    ValueError
        If ``dt`` exceeds the admissible maximum ``1 / (10 f_nat_max)`` or ``1 / dt`` is not a
        multiple of ``fs_out``.
    """
    limits = [1.0 / (STEPS_PER_NATURAL_PERIOD * f_nat_max)] if f_nat_max > 0 else []
    if f_mesh_max > 0:
        limits.append(1.0 / (STEPS_PER_MESH_CYCLE * f_mesh_max))
    dt_rec = min(limits) if limits else 1e-4
    dt_adm = 1.0 / (MIN_STEPS_PER_NATURAL_PERIOD * f_nat_max) if f_nat_max > 0 else math.inf
    if dt is not None:
        dt = float(dt)
        if not dt > 0:
            raise ValueError("dt must be > 0")
        if dt > dt_adm:
            raise ValueError(
                f"dt = {dt:.6g} s is too large for the highest natural frequency "
                f"{f_nat_max:.6g} Hz: the admissible maximum is {dt_adm:.6g} s "
                f"({MIN_STEPS_PER_NATURAL_PERIOD} steps per period; "
                f"{dt_rec:.6g} s recommended)"
            )
        fs_int = 1.0 / dt
        if fs_out is None:
            for cand in _nice_rates(DEFAULT_FS_OUT, fs_int):
                ratio = fs_int / cand
                if abs(ratio - round(ratio)) < 1e-9 * ratio:
                    fs_out = cand
                    break
            else:
                fs_out = fs_int / max(1, math.floor(fs_int / DEFAULT_FS_OUT + 1e-9))
        ratio = fs_int / float(fs_out)
        dec = round(ratio)
        if dec < 1 or abs(ratio - dec) > 1e-9 * ratio:
            raise ValueError(f"1/dt = {fs_int:.9g} Hz is not an integer multiple of fs_out")
        return StepChoice(dt, fs_int / dec, dec, dt_rec, dt_adm, f_nat_max, f_mesh_max)
    fs = DEFAULT_FS_OUT if fs_out is None else float(fs_out)
    if not fs > 0:
        raise ValueError("fs_out must be > 0")
    dec = max(min_decimation, math.ceil(1.0 / (dt_rec * fs) - 1e-9))
    return StepChoice(1.0 / (dec * fs), fs, dec, dt_rec, dt_adm, f_nat_max, f_mesh_max)


def decimation_filter(decimation: int, attenuation_db: float = 85.0) -> np.ndarray:
    """Symmetric low-pass FIR for decimation by ``decimation`` (odd length, unit DC gain).

    Cutoff (-6 dB) at ``0.4 fs_out``, Kaiser window designed for ``attenuation_db`` with the
    transition band ``0.3 .. 0.5 fs_out``: the output is flat (within 2e-4) to ``0.3 fs_out``
    and everything at or above the output Nyquist frequency is attenuated by at least 80 dB
    before decimation (the Kaiser formula is approximate, hence the 85 dB design target), so
    nothing aliases. ``decimation == 1`` returns ``[1.0]`` (no filtering possible).
    """
    if decimation == 1:
        return np.ones(1)
    # transition 0.2 fs_out = 0.2 / D of the internal rate, normalised to the internal Nyquist
    numtaps, beta = scipy.signal.kaiserord(attenuation_db, 0.4 / decimation)
    numtaps |= 1
    taps = scipy.signal.firwin(numtaps, 0.4 / decimation, window=("kaiser", beta), fs=1.0)
    return taps / taps.sum()


def _contact_solve(a0, f, mr, v, j, kl, kr, k_in, free_rigid, max_iter):
    """Active-set (Newton) solution of the piecewise-linear static problem at fixed stiffness."""
    n = a0.shape[0]
    state = np.ones(v.shape[0], dtype=np.int64)
    acc = 0.0
    for _ in range(max_iter):
        a = a0.copy()
        b = f.copy()
        left = (state & 1).astype(bool)
        right = (state & 2).astype(bool)
        a += (v[left].T * kl[left]) @ v[left] + (v[right].T * kr[right]) @ v[right]
        b += v[left].T @ (kl[left] * j[left] / 2) - v[right].T @ (kr[right] * j[right] / 2)
        if free_rigid:
            # equilibrated: acceleration column and pin row scaled to the stiffness
            big = np.abs(a).max() + 1e-300
            col = big / (np.abs(mr).max() + 1e-300)
            aug = np.zeros((n + 1, n + 1))
            aug[:n, :n] = a
            aug[:n, n] = mr * col
            aug[n, k_in] = big
            rhs = np.append(b, 0.0)
            sol = np.linalg.lstsq(aug, rhs, rcond=None)[0]
            q, acc = sol[:n], float(sol[n] * col)
            resid = aug @ sol - rhs
        else:
            q = np.linalg.lstsq(a, b, rcond=None)[0]
            resid = a @ q - b
        d = v @ q
        new = (d > j / 2).astype(np.int64) + 2 * (d < -j / 2).astype(np.int64)
        if np.array_equal(new, state):
            return q, acc, a, b, resid
        state = new
    raise SimulationError("static equilibrium: the flank-contact sets do not converge")


def static_equilibrium(
    system: kn.KernelSystem,
    mass: np.ndarray,
    rigid: np.ndarray,
    velocity: np.ndarray,
    *,
    rigid_acceleration: float = 0.0,
    free_rigid: bool = False,
    max_iter: int = 100,
) -> tuple[np.ndarray, float]:
    """Static (quasi-static) equilibrium at ``t = 0`` with the piecewise-linear contact law.

    Solves ``K q + sum_m F_m(q) v_m + M r a = f(0, q, qdot0)`` by Newton iterations on the
    flank-contact sets (exact for the piecewise-linear law). The flank stiffness is taken at the
    mesh positions of the solution itself (fixed-point iteration: the static wind-up of the
    drive coupling rotates the whole set and so shifts the mesh positions). The rigid-body
    acceleration ``a`` is prescribed (speed-driven runs) or, with ``free_rigid``, an unknown
    fixed by the torque balance; then the input rotation is pinned to 0.

    Parameters
    ----------
    system : KernelSystem
        Arrays of the run (drive and load parameters included).
    mass : ndarray, shape (n, n)
        Mass matrix of the run (load inertia included).
    rigid : ndarray, shape (n,)
        Rigid-body velocity per unit input speed.
    velocity : ndarray, shape (n,)
        Initial velocity ``qdot0``.
    rigid_acceleration : float
        Prescribed input acceleration [rad/s^2] (ignored with ``free_rigid``).
    free_rigid : bool
        The rigid-body mode is free (torque-driven run).
    max_iter : int
        Maximum number of contact-set updates.

    Returns
    -------
    q0 : ndarray, shape (n,)
        Static coordinates.
    acceleration : float
        Rigid-body input acceleration [rad/s^2].

    Raises
    ------
    SimulationError
        If no equilibrium exists (unbalanced load on a free member) or the contact sets cycle.
    """
    n = system.n_dof
    ipar, fpar = system.ipar, system.fpar
    qd0 = np.asarray(velocity, dtype=float)
    a0 = system.stiffness.copy()
    f = system.f_const - system.damping @ qd0
    carrier = int(ipar[kn.IP_CARRIER])
    if ipar[kn.IP_GYRO] and carrier >= 0:
        om = qd0[carrier]
        a0 -= om * om * system.centripetal
        f -= om * system.gyroscopic @ qd0
    k_in = int(ipar[kn.IP_INPUT])
    mode = int(ipar[kn.IP_MODE])
    if mode == kn.DRIVE_SPEED:
        phi = np.zeros(1)
        w = np.zeros(1)
        kn.speed_profile(system.speed_table, np.zeros(1), phi, w)
        a0[k_in, k_in] += fpar[kn.FP_KC]
        f[k_in] += fpar[kn.FP_KC] * phi[0] + fpar[kn.FP_CC] * (w[0] - qd0[k_in])
    elif mode == kn.DRIVE_TORQUE:
        f[k_in] += float(np.interp(0.0, system.torque_table[0], system.torque_table[1]))
    k_out = int(ipar[kn.IP_OUTPUT])
    if k_out >= 0:
        e = fpar[kn.FP_OUTDIR]
        wo = e * qd0[k_out]
        f[k_out] -= e * (fpar[kn.FP_T0] + fpar[kn.FP_C1] * wo + fpar[kn.FP_C2] * wo * abs(wo))
    mr = mass @ rigid
    if not free_rigid:
        f = f - mr * rigid_acceleration
    v = system.mesh_vectors
    j = system.backlash
    q = np.zeros(n)
    k_prev = None
    for _outer in range(20):  # flank stiffness at the mesh positions of the current solution
        pos = system.mesh_position_offsets + system.mesh_position_vectors @ q
        kl = np.array([kn.periodic_interp(system.left_tables, m, s) for m, s in enumerate(pos)])
        kr = np.array([kn.periodic_interp(system.right_tables, m, s) for m, s in enumerate(pos)])
        k_now = np.concatenate([kl, kr])
        if k_prev is not None and np.allclose(k_now, k_prev, rtol=1e-12, atol=0.0):
            break
        k_prev = k_now
        q, acc, a, b, resid = _contact_solve(a0, f, mr, v, j, kl, kr, k_in, free_rigid, max_iter)
        if not free_rigid:
            acc = float(rigid_acceleration)
    scale = np.abs(b).max() + np.abs(a).max() * np.abs(q).max() + 1e-300
    if np.abs(resid).max() > 1e-8 * scale:
        raise SimulationError(
            "no static equilibrium at t = 0: the initial load is not balanced (a member is "
            "free, or the drive and load torques do not match); max residual "
            f"{np.abs(resid).max():.3g}"
        )
    return q, acc


def _model_sha256(model: AssembledModel) -> str:
    h = hashlib.sha256()
    for name in (
        "mass",
        "stiffness",
        "damping",
        "gyroscopic",
        "centripetal",
        "mesh_vectors",
        "mesh_position_vectors",
        "mesh_position_offsets",
        "mesh_stiffness_tables",
        "mesh_back_tables",
        "mesh_backlash",
        "mesh_damping",
        "bearing_vectors",
        "bearing_stiffness",
        "bearing_damping",
    ):
        a = np.ascontiguousarray(getattr(model, name), dtype=np.float64)
        h.update(name.encode())
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    names = [
        model.dof_names,
        model.mesh_names,
        model.bearing_names,
        sorted(model.rotation_dofs.items()),
        model.input_member,
        model.output_member,
    ]
    h.update(json.dumps(names, default=str).encode())
    return h.hexdigest()


def _jsonable(obj: object) -> object:
    """Round-trip through JSON (tuples -> lists, numpy scalars -> numbers, others -> str)."""

    def default(o: object) -> object:
        if isinstance(o, np.ndarray):
            return o.tolist()
        if isinstance(o, np.generic):
            return o.item()
        return str(o)

    return json.loads(json.dumps(obj, default=default, sort_keys=True))


@dataclass
class _Setup:
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


def default_coupling(model: AssembledModel) -> DriveCoupling:
    """The default drive coupling of speed-driven runs.

    Its rigid-body mode (all members turning on the coupling) lies at
    :data:`COUPLING_FREQUENCY_FRACTION` x the lowest elastic natural frequency of the mean
    system, critically damped: ``k = J_eff w_c**2``, ``c = 2 J_eff w_c`` with ``J_eff`` the
    inertia of the kinematic motion reduced to the input member.
    """
    rigid = model.rigid_body_velocity()
    k_in = int(model.rotation_dofs[model.input_member])
    f_el = _elastic(_frequencies(np.asarray(model.mass, float), model.mean_stiffness_matrix()))
    if f_el.size == 0:
        raise ValueError("the model has no elastic mode to choose a drive coupling from")
    j_eff = float(rigid @ model.mass @ rigid) / rigid[k_in] ** 2
    wc = 2.0 * math.pi * COUPLING_FREQUENCY_FRACTION * float(f_el[0])
    return DriveCoupling(float(j_eff * wc * wc), float(2.0 * j_eff * wc))


def _setup(model: AssembledModel, conditions: Conditions, gyroscopic: bool) -> _Setup:
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
    free_rigid = False
    if isinstance(conditions, SpeedRamp | SpeedTable):
        ipar[kn.IP_MODE] = kn.DRIVE_SPEED
        t_nodes, rpm = conditions.table()
        w = rpm * _RPM
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
        coupling = conditions.coupling or default_coupling(model)
        fpar[kn.FP_KC] = coupling.stiffness
        fpar[kn.FP_CC] = coupling.damping
        speed_max = float(np.abs(w).max())
        duration = float(conditions.duration)
        drive = "speed"
    elif isinstance(conditions, TorqueDriven):
        ipar[kn.IP_MODE] = kn.DRIVE_TORQUE
        tt, tv = conditions.input_torque
        torque_tab = np.vstack([np.array(tt), np.array(tv)])
        if k_out < 0 and (conditions.load_inertia or any(conditions.load_torque)):
            raise ValueError(f"output member {model.output_member!r} has no rotation coordinate")
        if k_out >= 0:
            mass[k_out, k_out] += conditions.load_inertia
        load = conditions.load_torque
        omega0 = conditions.start_rpm * _RPM
        alpha0 = 0.0
        k_mean = model.mean_stiffness_matrix()
        free_rigid = bool(
            np.abs(k_mean @ rigid).max() <= 1e-9 * np.abs(k_mean).max() * np.abs(rigid).max()
        )
        speed_max = max(abs(conditions.max_rpm), abs(conditions.start_rpm)) * _RPM
        duration = conditions.duration
        drive = "torque"
    else:
        raise TypeError(f"unsupported operating conditions {type(conditions).__name__}")
    fpar[kn.FP_T0], fpar[kn.FP_C1], fpar[kn.FP_C2] = load
    fpar[kn.FP_SPEED_LIMIT] = 3.0 * speed_max + 100.0
    gyro, centri = model.carrier_frame_operators()
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
        f_const=np.zeros(n),
        ipar=ipar,
        fpar=fpar,
        speed_table=speed_tab,
        torque_table=torque_tab,
        deflection_limit=np.full(model.n_mesh, np.inf),
    )
    return _Setup(
        system,
        mass,
        rigid,
        omega0,
        alpha0,
        free_rigid,
        duration,
        speed_max,
        coupling,
        tuple(float(x) for x in load),
        drive,
    )


def _max_stiffness_matrix(model: AssembledModel) -> np.ndarray:
    """Constant stiffness plus every mesh at its stiffest (both flanks if j < 0)."""
    kmax = model.mesh_stiffness_tables.max(axis=1)
    both = np.asarray(model.mesh_backlash) < 0
    kmax = kmax + np.where(both, model.mesh_back_tables.max(axis=1), 0.0)
    return model.stiffness + model.mesh_stiffness_matrix(kmax)


def _blow_up_message(t: float, code: int, setup: _Setup, step: StepChoice, gyro: bool) -> str:
    what = {
        kn.STATUS_NONFINITE: "the state became non-finite",
        kn.STATUS_DEFLECTION: "a mesh deflection exceeded 1000x its static value",
        kn.STATUS_SPEED: "the input speed ran away (beyond 3x the expected maximum)",
    }[code]
    causes = []
    ratio = step.dt / step.dt_admissible
    if ratio > 0.25:
        causes.append(
            f"the step dt = {step.dt:.4g} s is coarse for the highest natural frequency "
            f"{step.highest_natural_frequency:.4g} Hz (recommended <= {step.dt_recommended:.4g} s)"
        )
    if setup.drive == "torque":
        causes.append("an unstable load/drive setting (input torque not balanced by the load)")
    else:
        causes.append("a drive coupling or load torque that destabilises the system")
    if gyro:
        causes.append("centripetal softening (Omega_c^2 K_Omega) beyond the bearing stiffness")
    causes.append("a parametric instability without enough damping")
    return (
        f"numerical blow-up at simulated time t = {t:.6g} s: {what}. Likely cause: "
        + "; or ".join(causes)
        + "."
    )


def simulate(
    model: AssembledModel,
    conditions: Conditions,
    *,
    dt: float | None = None,
    fs_out: float | None = None,
    duration: float | None = None,
    gyroscopic: bool = False,
    progress: bool | None = None,
    config: Mapping | str | None = None,
    natural_frequencies: Sequence[float] | None = None,
) -> RunUpResult:
    """Simulate a run-up (or run-down, or torque-driven run) of an assembled gear set.

    Parameters
    ----------
    model : AssembledModel
        The gear set (:func:`gearvib.assembly.assemble`).
    conditions : SpeedRamp, SpeedTable or TorqueDriven
        Operating conditions. Speed-driven runs prescribe the input angle ``phi(t)`` through a
        :class:`DriveCoupling`; by default its frequency (rigid-body mode on the coupling) is
        0.1x the lowest elastic natural frequency of the model, with critical damping.
    dt : float, optional
        Internal step [s]. Default ``min(1/(40 f_nat_max), 1/(40 f_mesh_max))`` rounded down
        to ``1 / (D fs_out)``; ``f_nat_max`` uses the stiffest table values.
    fs_out : float, optional
        Output rate [Hz]; default the smallest "nice" rate >= 20 kHz dividing ``1 / dt``.
    duration : float, optional
        Simulated time [s]; default the duration of the conditions.
    gyroscopic : bool
        Include the gyroscopic and centripetal terms with the current carrier speed.
    progress : bool, optional
        Show a tqdm bar (hidden on non-TTY output); ``None`` shows it when the run is expected
        to take more than 3 s.
    config : mapping or str, optional
        Configuration of the caller (e.g. the TOML contents) stored in ``config_json``; the
        model meta data are used by default.
    natural_frequencies : sequence of float, optional
        Natural frequencies [Hz] to store; by default computed from the mean system.

    Returns
    -------
    RunUpResult

    Raises
    ------
    ValueError
        Invalid model (e.g. negative stiffness tables), conditions or step.
    SimulationError
        Numerical blow-up (the message states the simulated time and the likely cause) or no
        static equilibrium.
    """
    wall0 = _time.perf_counter()
    _check_model(model)
    setup = _setup(model, conditions, gyroscopic)
    system = setup.system
    n, nm = model.n_dof, model.n_mesh
    run_duration = setup.duration if duration is None else float(duration)
    if run_duration is None or not run_duration > 0:
        raise ValueError("give a duration > 0 (the conditions define none)")

    k_max = _max_stiffness_matrix(model)
    if setup.drive == "speed":
        k_max = k_max.copy()
        k_max[system.ipar[kn.IP_INPUT], system.ipar[kn.IP_INPUT]] += setup.coupling.stiffness
    f_nat = _frequencies(setup.mass, k_max)
    f_nat_max = float(f_nat.max()) if f_nat.size else 0.0
    f_mesh_max = abs(model.mesh_frequency_per_rpm) * setup.speed_max / _RPM
    step = choose_step(f_nat_max, f_mesh_max, dt=dt, fs_out=fs_out)
    taps = decimation_filter(step.decimation)
    half = (taps.size - 1) // 2
    dec = step.decimation

    qd0 = setup.rigid * setup.omega0
    q0, acc0 = static_equilibrium(
        system,
        setup.mass,
        setup.rigid,
        qd0,
        rigid_acceleration=setup.alpha0,
        free_rigid=setup.free_rigid,
    )
    delta0 = system.mesh_vectors @ q0
    system.deflection_limit[:] = np.maximum(
        1e3 * (np.abs(delta0) + np.abs(system.backlash) / 2), 1e-3
    )
    y = np.concatenate([q0, qd0])

    n_out = math.floor(run_duration * step.fs_out + 1e-9) + 1
    last_sample = (n_out - 1) * dec + half
    chunk = max(round(CHUNK_DURATION / step.dt), 2 * half + dec + 1)
    nsig = kn.n_signals(n, nm)
    buf = np.empty((chunk + 2 * half + dec + 1, nsig))
    out = np.empty((n_out, nsig))
    work = np.empty(kn.work_shape(n, nm))
    mesh_out = np.empty((nm, kn.MESH_OUT_COLUMNS))
    status = np.zeros(2, dtype=np.int64)
    flank_state = np.full(nm, -1, dtype=np.int64)
    changes = np.zeros(nm, dtype=np.int64)
    sys_tuple = system.astuple()
    rigid = setup.rigid

    def reference(times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # rigid-body motion subtracted before filtering and added back exactly afterwards: the
        # filter then only sees the (small, smooth) deviation, which keeps the start padding
        # exact for a uniformly accelerated drive and avoids filtering large angles
        if setup.drive == "speed":
            ang, spd = np.empty(times.size), np.empty(times.size)
            kn.speed_profile(system.speed_table, times, ang, spd)
            return ang, spd
        return setup.omega0 * times + 0.5 * acc0 * times**2, setup.omega0 + acc0 * times

    b0, fill, next_out, g = -half, half, 0, 0
    bar = None
    try:
        while g <= last_sample:
            t_chunk = _time.perf_counter()
            m = min(chunk, last_sample + 1 - g)
            kn.integrate_chunk(
                y,
                g,
                m,
                step.dt,
                sys_tuple,
                buf,
                fill,
                flank_state,
                changes,
                (n_out - 1) * dec,
                work,
                mesh_out,
                status,
            )
            if status[0] != kn.STATUS_OK:
                raise SimulationError(
                    _blow_up_message(status[1] * step.dt, int(status[0]), setup, step, gyroscopic)
                )
            ang, spd = reference((g + np.arange(m)) * step.dt)
            buf[fill : fill + m, :n] -= ang[:, None] * rigid
            buf[fill : fill + m, n : 2 * n] -= spd[:, None] * rigid
            if g == 0:  # odd reflection about t = 0: x(-k) = 2 x(0) - x(k)
                buf[:half] = 2.0 * buf[half] - buf[2 * half : half : -1]
            fill += m
            g += m
            k_last = min(n_out - 1, (b0 + fill - 1 - half) // dec)
            if k_last >= next_out:
                kn.fir_decimate(buf, b0, taps, dec, next_out, k_last - next_out + 1, out, next_out)
                next_out = k_last + 1
            keep = next_out * dec - half - b0
            if keep > 0:
                buf[: fill - keep] = buf[keep:fill]
                fill -= keep
                b0 += keep
            if bar is None and g <= last_sample:
                expected = (_time.perf_counter() - t_chunk) * (last_sample + 1 - g) / m
                if progress or (progress is None and expected > 3.0):
                    from tqdm.auto import tqdm

                    bar = tqdm(
                        total=round(run_duration, 6),
                        unit="s(sim)",
                        disable=None,
                        desc="gearvib simulate",
                        initial=min(g * step.dt, run_duration),
                    )
            elif bar is not None:
                bar.update(min(g * step.dt, run_duration) - bar.n)
    finally:
        if bar is not None:
            bar.close()
    ang, spd = reference(np.arange(n_out) * (dec * step.dt))
    out[:, :n] += ang[:, None] * rigid
    out[:, n : 2 * n] += spd[:, None] * rigid
    return _result(
        model,
        conditions,
        setup,
        step,
        taps,
        out,
        changes,
        run_duration,
        gyroscopic,
        config,
        natural_frequencies,
        _time.perf_counter() - wall0,
    )


@dataclass
class RunUpResult:
    """Output of :func:`simulate`, sampled at ``fs_out`` (arrays are ``(channel, time)``).

    Attributes
    ----------
    time : ndarray, shape (n_time,)
        [s], ``k / fs_out``.
    mesh_names, bearing_names, members, translation_dofs : tuple of str
        Labels of the ``mesh``, ``bearing``, ``member`` and ``translation_dof`` dimensions.
    normal_force : ndarray, shape (n_mesh, 2, n_time)
        Compressive force on the left and right flank [N] (>= 0).
    mesh_stiffness : ndarray, shape (n_mesh, n_time)
        Effective mesh stiffness [N/m]: 0 in the backlash, sum of both flanks in double contact.
    mesh_deflection : ndarray, shape (n_mesh, n_time)
        ``v_m . q`` [m] (dynamic transmission error along the line of action).
    bearing_force : ndarray, shape (n_bearing, n_time)
        ``k_b (u_b . q) + c_b (u_b . qdot)`` [N or N m].
    displacement : ndarray, shape (n_translation, n_time)
        Translational coordinates [m].
    rotation, speed : ndarray, shape (n_member, n_time)
        Absolute rotation [rad] and speed [min^-1] of every rotating member.
    input_speed, input_angle : ndarray, shape (n_time,)
        Prescribed input speed [min^-1] and angle [rad] (speed-driven), or the simulated ones of
        the input member (torque-driven).
    drive_torque : ndarray, shape (n_time,)
        Torque applied to the input member by the coupling or the torque table [N m].
    mesh_frequency : ndarray, shape (n_time,)
        ``|mesh_frequency_per_rpm * input_speed|`` [Hz].
    natural_frequencies : ndarray, shape (n_mode,)
        Elastic natural frequencies of the mean system [Hz].
    flank_contact_changes : ndarray of int64, shape (n_mesh,)
        Changes of the set of flanks in contact per mesh (internal steps up to the end).
    step : StepChoice
        Internal step, output rate and the frequencies they were chosen from.
    fir_numtaps : int
        Length of the decimation filter.
    config_json : str
        Full configuration, JSON with sorted keys.
    drive : str
        ``"speed"`` or ``"torque"``.
    gyroscopic : bool
        Gyroscopic/centripetal terms included.
    coupling : DriveCoupling or None
        Drive coupling of a speed-driven run.
    title : str
        Dataset title.
    wall_time : float
        Wall time of the call [s] (not stored in the dataset, which is deterministic).
    """

    time: np.ndarray
    mesh_names: tuple[str, ...]
    bearing_names: tuple[str, ...]
    members: tuple[str, ...]
    translation_dofs: tuple[str, ...]
    normal_force: np.ndarray
    mesh_stiffness: np.ndarray
    mesh_deflection: np.ndarray
    bearing_force: np.ndarray
    displacement: np.ndarray
    rotation: np.ndarray
    speed: np.ndarray
    input_speed: np.ndarray
    input_angle: np.ndarray
    drive_torque: np.ndarray
    mesh_frequency: np.ndarray
    natural_frequencies: np.ndarray
    flank_contact_changes: np.ndarray
    step: StepChoice
    fir_numtaps: int
    config_json: str
    drive: str
    gyroscopic: bool
    coupling: DriveCoupling | None = None
    title: str = "gearvib run-up simulation"
    wall_time: float = field(default=0.0, compare=False)

    @property
    def config_sha256(self) -> str:
        """SHA-256 of ``config_json``."""
        return hashlib.sha256(self.config_json.encode()).hexdigest()

    def to_dataset(self) -> xr.Dataset:
        """CF-1.11 annotated dataset (float64 data, ``time`` in s, netCDF-safe attributes)."""

        def var(
            dims: tuple[str, ...], data: np.ndarray, units: str, long_name: str, quantity: str
        ) -> xr.Variable:
            return xr.Variable(
                dims,
                np.ascontiguousarray(data),
                {"units": units, "long_name": long_name, "gearvib_quantity": quantity},
            )

        t = ("time",)
        coords = {
            "time": var(t, self.time, "s", "time since start of run", "time"),
            "mesh": xr.Variable(
                ("mesh",),
                np.array(self.mesh_names, dtype=str),
                {"long_name": "tooth contact (mesh)"},
            ),
            "flank": xr.Variable(
                ("flank",),
                np.array(["left", "right"]),
                {"long_name": "tooth flank (left: loaded when the central gear drives the planet)"},
            ),
            "bearing": xr.Variable(
                ("bearing",),
                np.array(self.bearing_names, dtype=str),
                {"long_name": "elastic bearing direction"},
            ),
            "member": xr.Variable(
                ("member",), np.array(self.members, dtype=str), {"long_name": "rotating member"}
            ),
            "translation_dof": xr.Variable(
                ("translation_dof",),
                np.array(self.translation_dofs, dtype=str),
                {"long_name": "translational coordinate"},
            ),
            "mode": var(
                ("mode",),
                np.arange(1, self.natural_frequencies.size + 1, dtype=np.int64),
                "1",
                "elastic mode number of the mean system",
                "mode",
            ),
            "input_speed": var(
                t, self.input_speed, "min-1", "input speed (revolutions per minute)", "input_speed"
            ),
            "input_angle": var(t, self.input_angle, "rad", "input rotation angle", "input_angle"),
            "mesh_frequency": var(
                t, self.mesh_frequency, "Hz", "gear mesh frequency", "mesh_frequency"
            ),
        }
        data = {
            "normal_force": var(
                ("mesh", "flank", "time"),
                self.normal_force,
                "N",
                "normal tooth force on the flank (compressive)",
                "tooth_force",
            ),
            "mesh_stiffness": var(
                ("mesh", "time"),
                self.mesh_stiffness,
                "N m-1",
                "effective mesh stiffness (0 in the backlash)",
                "mesh_stiffness",
            ),
            "mesh_deflection": var(
                ("mesh", "time"),
                self.mesh_deflection,
                "m",
                "mesh deflection along the line of action (dynamic transmission error)",
                "mesh_deflection",
            ),
            "bearing_force": var(
                ("bearing", "time"),
                self.bearing_force,
                "N",
                "bearing force (N m for torsional supports)",
                "bearing_force",
            ),
            "displacement": var(
                ("translation_dof", "time"),
                self.displacement,
                "m",
                "translational displacement",
                "displacement",
            ),
            "rotation": var(
                ("member", "time"), self.rotation, "rad", "absolute rotation angle", "rotation"
            ),
            "speed": var(
                ("member", "time"),
                self.speed,
                "min-1",
                "rotational speed (revolutions per minute)",
                "speed",
            ),
            "drive_torque": var(
                t, self.drive_torque, "N m", "torque applied to the input member", "drive_torque"
            ),
            "natural_frequency": var(
                ("mode",),
                self.natural_frequencies,
                "Hz",
                "natural frequency of the mean system",
                "natural_frequency",
            ),
            "flank_contact_changes": var(
                ("mesh",),
                self.flank_contact_changes.astype(np.int64),
                "1",
                "number of flank-contact changes",
                "flank_contact_changes",
            ),
        }
        attrs = {
            "Conventions": "CF-1.11",
            "title": self.title,
            "source": f"gearvib {__version__}",
            "gearvib_version": __version__,
            "integrator": INTEGRATOR,
            "dt": float(self.step.dt),
            "fs_out": float(self.step.fs_out),
            "decimation_factor": int(self.step.decimation),
            "fir_numtaps": int(self.fir_numtaps),
            "anti_alias_filter": "Kaiser-window FIR, -6 dB at 0.4 fs_out, >= 80 dB from 0.5 fs_out,"
            " zero phase (centred)",
            "highest_natural_frequency": float(self.step.highest_natural_frequency),
            "highest_mesh_frequency": float(self.step.highest_mesh_frequency),
            "drive": self.drive,
            "gyroscopic": np.int8(self.gyroscopic),
            "config_json": self.config_json,
            "config_sha256": self.config_sha256,
        }
        if self.coupling is not None:
            attrs["drive_coupling_stiffness"] = float(self.coupling.stiffness)
            attrs["drive_coupling_damping"] = float(self.coupling.damping)
        return xr.Dataset(data, coords=coords, attrs=attrs)


def _result(
    model: AssembledModel,
    conditions: Conditions,
    setup: _Setup,
    step: StepChoice,
    taps: np.ndarray,
    out: np.ndarray,
    changes: np.ndarray,
    duration: float,
    gyroscopic: bool,
    config: Mapping | str | None,
    natural_frequencies: Sequence[float] | None,
    wall: float,
) -> RunUpResult:
    n, nm = model.n_dof, model.n_mesh
    system = setup.system
    n_out = out.shape[0]
    time = np.arange(n_out) * (step.decimation * step.dt)
    q = out[:, :n]
    qd = out[:, n : 2 * n]
    f_left = np.clip(out[:, 2 * n : 2 * n + nm].T, 0.0, None)
    f_right = np.clip(out[:, 2 * n + nm : 2 * n + 2 * nm].T, 0.0, None)
    k_eff = np.clip(out[:, 2 * n + 2 * nm :].T, 0.0, None)
    normal_force = np.ascontiguousarray(np.stack([f_left, f_right], axis=1))
    deflection = system.mesh_vectors @ q.T
    bv = np.asarray(model.bearing_vectors, dtype=float).reshape(len(model.bearing_names), n)
    bearing = np.asarray(model.bearing_stiffness)[:, None] * (bv @ q.T) + np.asarray(
        model.bearing_damping
    )[:, None] * (bv @ qd.T)
    trans = [i for i, u in enumerate(model.dof_units) if u == "m"]
    rot = sorted((d, name) for name, d in model.rotation_dofs.items() if d >= 0)
    members = tuple(name for _, name in rot)
    rot_idx = [d for d, _ in rot]
    k_in = int(system.ipar[kn.IP_INPUT])
    if setup.drive == "speed":
        angle = np.empty(n_out)
        w = np.empty(n_out)
        kn.speed_profile(system.speed_table, time, angle, w)
        drive_torque = system.fpar[kn.FP_KC] * (angle - q[:, k_in]) + system.fpar[kn.FP_CC] * (
            w - qd[:, k_in]
        )
        input_speed = w / _RPM
    else:
        angle = q[:, k_in].copy()
        input_speed = qd[:, k_in] / _RPM
        drive_torque = np.interp(time, system.torque_table[0], system.torque_table[1])
    if natural_frequencies is None:
        nat = _elastic(_frequencies(model.mass, model.mean_stiffness_matrix()))
    else:
        nat = np.asarray(natural_frequencies, dtype=float)
    if isinstance(config, str):
        cfg_model: object = json.loads(config)
    elif config is not None:
        cfg_model = dict(config)
    else:
        cfg_model = {"meta": model.meta}
    cfg = {
        "gearvib_version": __version__,
        "model": cfg_model,
        "model_sha256": _model_sha256(model),
        "conditions": {"type": type(conditions).__name__, **asdict(conditions)},
        "simulation": {
            "dt": step.dt,
            "fs_out": step.fs_out,
            "decimation_factor": step.decimation,
            "duration": duration,
            "gyroscopic": bool(gyroscopic),
            "integrator": INTEGRATOR,
            "drive_coupling": None if setup.coupling is None else asdict(setup.coupling),
            "load_torque": list(setup.load),
        },
    }
    config_json = json.dumps(_jsonable(cfg), sort_keys=True)
    name = model.meta.get("name") if isinstance(model.meta, Mapping) else None
    return RunUpResult(
        time=time,
        mesh_names=tuple(model.mesh_names),
        bearing_names=tuple(model.bearing_names),
        members=members,
        translation_dofs=tuple(model.dof_names[i] for i in trans),
        normal_force=normal_force,
        mesh_stiffness=np.ascontiguousarray(k_eff),
        mesh_deflection=np.ascontiguousarray(deflection),
        bearing_force=np.ascontiguousarray(bearing),
        displacement=np.ascontiguousarray(q[:, trans].T),
        rotation=np.ascontiguousarray(q[:, rot_idx].T),
        speed=np.ascontiguousarray(qd[:, rot_idx].T / _RPM),
        input_speed=input_speed,
        input_angle=angle,
        drive_torque=drive_torque,
        mesh_frequency=np.abs(model.mesh_frequency_per_rpm * input_speed),
        natural_frequencies=nat,
        flank_contact_changes=changes.copy(),
        step=step,
        fir_numtaps=int(taps.size),
        config_json=config_json,
        drive=setup.drive,
        gyroscopic=bool(gyroscopic),
        coupling=setup.coupling,
        title=f"gearvib run-up simulation of {name}" if name else "gearvib run-up simulation",
        wall_time=wall,
    )
