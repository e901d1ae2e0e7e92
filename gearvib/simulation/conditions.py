"""Operating conditions of a run: prescribed input speed or input torque, load, drive coupling.

Sign conventions
----------------
Speeds and torques at the input member are positive in the member's positive rotation sense
(``model.rotation_dofs[model.input_member]``). The load torque at the output member always
*resists* the forward motion of the output member (the sense of
``model.kinematic_ratios[model.output_member]``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from gearvib.checks import check_array, check_real, short
from gearvib.kinematics import MAX_SPEED_RPM

__all__ = [
    "RAD_S_PER_RPM",
    "SENSING",
    "Conditions",
    "DriveCoupling",
    "MotorDriven",
    "SpeedRamp",
    "SpeedTable",
    "TorqueDriven",
]

RAD_S_PER_RPM = 2.0 * math.pi / 60.0
"""One min^-1 in rad/s."""


#: What a drive coupling's angle and speed are taken from (:class:`DriveCoupling`).
SENSING = ("input", "rigid-body")
MAX_TABLE = 100_000
"""Longest motor characteristic of a description (``[simulation].motor``)."""
MAX_DRIVE_TABLE = 10_000_000
"""Longest speed, torque or motor table of a conditions object (a table given in Python)."""
MAX_TORQUE = 1e12
"""Largest torque magnitude accepted [N m] (also the coefficients of ``load_torque``)."""
MAX_DURATION = 1e7
"""Longest simulated time accepted [s] (a long run is then refused for its steps or memory)."""
MAX_INERTIA = 1e9
"""Largest load inertia accepted [kg m^2]."""


def _speed(value: Any, name: str, *, optional: bool = False) -> Any:
    return check_real(value, f"{name} [min-1]", low=-MAX_SPEED_RPM, high=MAX_SPEED_RPM,
                      optional=optional)


def _torque(value: Any, name: str, *, optional: bool = False) -> Any:
    return check_real(value, f"{name} [N m]", low=-MAX_TORQUE, high=MAX_TORQUE,
                      optional=optional)


def _table(values: Any, name: str, *, bound: float) -> tuple[float, ...]:
    """A 1-D table of finite numbers with magnitudes up to ``bound`` (at most
    :data:`MAX_DRIVE_TABLE`)."""
    arr = check_array(values, name, min_size=0, max_abs=bound).ravel()
    if arr.size > MAX_DRIVE_TABLE:
        raise ValueError(f"{name}: {arr.size} values (admissible: at most {MAX_DRIVE_TABLE})")
    return tuple(float(v) for v in arr)


def _coupling(value: Any) -> None:
    if value is not None and not isinstance(value, DriveCoupling):
        raise TypeError(f"coupling must be a DriveCoupling; got {type(value).__name__}")


@dataclass(frozen=True)
class DriveCoupling:
    """The drive of a speed-driven run: a torque on the input member that makes the set
    follow the prescribed input angle ``phi(t)``.

    The torque is ``k (phi - theta) + c (omega - theta')``. With ``sensing = "input"`` (the
    default of this class) ``theta`` is the input member's rotation: a torsional
    spring-damper between the prescribed angle and the input member, a physical coupling
    whose stiffness and damping act on every mode the input member takes part in. With
    ``sensing = "rigid-body"`` ``theta = r^T M q / (r^T M r)`` is the rigid-body coordinate of
    the set (``r`` the rigid-body velocity per unit input speed, ``r_in = 1``): a speed
    controller on the rigid-body mode. The elastic modes are M-orthogonal to ``r``, so they
    do not feed back into the torque: the controller keeps the speed profile and adds no
    stiffness or damping to them (their eigenvalues are those of the free set), while the
    rigid-body mode gets ``sqrt(k / J)`` and the damping ratio ``c / (2 sqrt(k J))``,
    ``J = r^T M r``. :func:`gearvib.simulate.default_coupling` is such a controller.

    Parameters
    ----------
    stiffness : float
        Torsional stiffness [N m/rad] (> 0, finite).
    damping : float
        Torsional damping [N m s/rad] (>= 0, finite).
    sensing : {"input", "rigid-body"}
        What ``theta`` is (above).
    """

    stiffness: float
    damping: float
    sensing: str = "input"

    def __post_init__(self) -> None:
        for name in ("stiffness", "damping"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float | np.floating
                                                         | np.integer):
                raise TypeError(f"DriveCoupling.{name} = {short(value)} is not a number")
        check_real(self.stiffness, "DriveCoupling.stiffness", low=0.0, low_open=True,
                   high=1e40)
        check_real(self.damping, "DriveCoupling.damping", low=0.0, high=1e12)
        if not (0 < self.stiffness < math.inf and 0 <= self.damping < math.inf):
            raise ValueError(f"DriveCoupling needs 0 < stiffness < inf and 0 <= damping < inf "
                             f"(got stiffness = {self.stiffness!r}, damping = "
                             f"{self.damping!r})")
        if not (isinstance(self.sensing, str) and self.sensing in SENSING):
            raise ValueError(f"DriveCoupling.sensing = {self.sensing!r:.40} is not admissible "
                             f"(admissible: {', '.join(repr(s) for s in SENSING)})")

    def to_dict(self) -> dict:
        """``{"stiffness", "damping"}`` and, for rigid-body sensing, ``"sensing"`` (a run's
        configuration text; an input coupling's is as it was before the field existed)."""
        out: dict[str, Any] = {"stiffness": float(self.stiffness),
                               "damping": float(self.damping)}
        if self.sensing != "input":
            out["sensing"] = self.sensing
        return out


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
        _speed(self.start_rpm, "start_rpm")
        _speed(self.end_rpm, "end_rpm")
        check_real(self.duration, "SpeedRamp.duration [s]")
        if not (math.isfinite(self.duration) and 1e-9 <= self.duration <= MAX_DURATION):
            raise ValueError(f"SpeedRamp.duration = {self.duration!r} s is not admissible "
                             f"(admissible: 1e-9 to {MAX_DURATION:g} s)")
        _torque(self.load_torque, "load_torque")
        _torque(self.input_torque, "input_torque", optional=True)
        _coupling(self.coupling)

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
        t = _table(self.time, "time [s]", bound=MAX_DURATION)
        r = _table(self.rpm, "rpm [min-1]", bound=MAX_SPEED_RPM)
        if len(t) != len(r) or len(t) < 2 or np.any(np.diff(t) <= 0):
            raise ValueError("SpeedTable needs >= 2 strictly increasing times and as many speeds")
        _torque(self.load_torque, "load_torque")
        _torque(self.input_torque, "input_torque", optional=True)
        _coupling(self.coupling)
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
        torque: Any = self.input_torque  # as given: checked here
        tt: tuple[float, ...]
        tv: tuple[float, ...]
        if not isinstance(torque, tuple | list | np.ndarray):
            tt, tv = (0.0,), (_torque(torque, "input_torque"),)
        else:
            if len(torque) != 2:
                raise ValueError("input_torque must be a number or a table (times, torques)")
            a, b = torque
            tt = _table(a, "input_torque times [s]", bound=MAX_DURATION)
            tv = _table(b, "input_torque values [N m]", bound=MAX_TORQUE)
            if len(tt) != len(tv) or len(tt) < 1 or np.any(np.diff(tt) <= 0):
                raise ValueError("input_torque table needs strictly increasing times")
        object.__setattr__(self, "input_torque", (tt, tv))
        object.__setattr__(self, "load_torque", _load_tuple(self.load_torque))
        check_real(self.load_inertia, "load_inertia [kg m^2]", low=0.0, high=MAX_INERTIA)
        _speed(self.start_rpm, "start_rpm")
        check_real(self.duration, "duration [s]", low=0.0, low_open=True, high=MAX_DURATION,
                   optional=True)
        check_real(self.max_rpm, "max_rpm [min-1]", low=0.0, low_open=True, high=MAX_SPEED_RPM)
        if self.duration is None and len(tt) > 1:
            object.__setattr__(self, "duration", tt[-1])


def _load_tuple(load_torque: Sequence[float]) -> tuple[float, float, float]:
    if not isinstance(load_torque, tuple | list | np.ndarray) or len(load_torque) != 3:
        raise ValueError("load_torque must be (T0, c1, c2), three finite numbers")
    lt = _table(load_torque, "load_torque (T0, c1, c2)", bound=MAX_TORQUE)
    return lt[0], lt[1], lt[2]


@dataclass(frozen=True)
class MotorDriven:
    """A motor at the input member: its torque follows its torque-speed characteristic.

    The drive torque is ``T(omega_in)``, linear in the table between its nodes and held
    constant outside, evaluated at the current speed of the input member in the kernel (so the
    motor's speed droop under load and its damping of torsional vibration are part of the
    run). Load and load inertia at the output as in :class:`TorqueDriven`. A motor rotor with
    its own inertia and shaft is a ``[[body]]`` joined by a ``[[coupling]]``, made the input.
    :meth:`kloss` builds the characteristic of an induction motor.

    Parameters
    ----------
    speed_rpm : sequence of float
        Strictly increasing speeds of the characteristic [min^-1].
    torque : sequence of float
        Motor torque at those speeds [N m] (positive: driving forward).
    load_inertia : float
        Inertia added to the output member [kg m^2] (>= 0).
    load_torque : (T0, c1, c2)
        Resisting load ``T0 + c1 w + c2 w |w|`` [N m], ``w`` forward output speed [rad/s].
    start_rpm : float
        Input speed at ``t = 0`` [min^-1].
    duration : float, optional
        Default simulated duration [s].
    max_rpm : float, optional
        Expected highest input speed [min^-1] (step choice, runaway guard); default the highest
        speed of the characteristic.
    """

    speed_rpm: Sequence[float]
    torque: Sequence[float]
    load_inertia: float = 0.0
    load_torque: tuple[float, float, float] = (0.0, 0.0, 0.0)
    start_rpm: float = 0.0
    duration: float | None = None
    max_rpm: float | None = None

    def __post_init__(self) -> None:
        n = _table(self.speed_rpm, "speed_rpm", bound=MAX_SPEED_RPM)
        t = _table(self.torque, "torque [N m]", bound=MAX_TORQUE)
        if len(n) != len(t) or len(n) < 2:
            raise ValueError("MotorDriven: speed_rpm and torque need >= 2 values each, as many "
                             f"torques as speeds (got {len(n)} and {len(t)})")
        if not all(map(math.isfinite, n + t)) or np.any(np.diff(n) <= 0):
            raise ValueError("MotorDriven: speed_rpm must be finite and strictly increasing, "
                             "torque finite")
        object.__setattr__(self, "speed_rpm", n)
        object.__setattr__(self, "torque", t)
        object.__setattr__(self, "load_torque", _load_tuple(self.load_torque))
        check_real(self.load_inertia, "load_inertia [kg m^2]", low=0.0, high=MAX_INERTIA)
        _speed(self.start_rpm, "start_rpm")
        check_real(self.duration, "duration [s]", low=0.0, low_open=True, high=MAX_DURATION,
                   optional=True)
        if self.max_rpm is None:
            object.__setattr__(self, "max_rpm", max(abs(n[0]), abs(n[-1])))
        else:
            check_real(self.max_rpm, "max_rpm [min-1]", low=0.0, low_open=True,
                       high=MAX_SPEED_RPM)

    @classmethod
    def kloss(cls, synchronous_rpm: float, breakdown_torque: float, breakdown_slip: float,
              *, n_points: int = 2001, **kwargs) -> MotorDriven:
        """Induction motor with the Kloss characteristic.

        ``T(s) = 2 T_k / (s / s_k + s_k / s)`` with the slip ``s = (n_0 - n) / n_0``
        (Kloss 1908; the simplified form that neglects the stator resistance). It is
        tabulated from standstill to 1.5 ``n_0`` (generator above ``n_0``) with ``n_points``
        speeds: with the default 2001 the linear interpolation is within 1e-4 ``T_k`` of
        the formula for ``s_k >= 0.05``.

        Parameters
        ----------
        synchronous_rpm : float
            Synchronous speed ``n_0`` [min^-1] (> 0), e.g. 1500 for a 4-pole 50 Hz motor.
        breakdown_torque : float
            Breakdown (pull-out) torque ``T_k`` [N m] (> 0).
        breakdown_slip : float
            Slip at breakdown ``s_k`` (0 < s_k < 1).
        n_points : int
            Table size (>= 11).
        **kwargs
            The other parameters of :class:`MotorDriven`.
        """
        n0, tk, sk = float(synchronous_rpm), float(breakdown_torque), float(breakdown_slip)
        if not (math.isfinite(n0) and n0 > 0):
            raise ValueError(f"synchronous_rpm = {synchronous_rpm!r} must be > 0 [min^-1]")
        if not (math.isfinite(tk) and tk > 0):
            raise ValueError(f"breakdown_torque = {breakdown_torque!r} must be > 0 [N m]")
        if not 0 < sk < 1:
            raise ValueError(f"breakdown_slip = {breakdown_slip!r} is not admissible "
                             "(admissible: 0 < s_k < 1)")
        if isinstance(n_points, bool) or not isinstance(n_points, int) or n_points < 11:
            raise ValueError(f"n_points = {n_points!r} must be an integer >= 11")
        speed = np.linspace(0.0, 1.5 * n0, n_points)
        slip = (n0 - speed) / n0
        with np.errstate(divide="ignore", invalid="ignore"):
            torque = np.where(slip == 0.0, 0.0, 2.0 * tk / (slip / sk + sk / slip))
        kwargs.setdefault("max_rpm", n0)
        return cls(tuple(speed), tuple(torque), **kwargs)


Conditions = SpeedRamp | SpeedTable | TorqueDriven | MotorDriven
"""Any of the operating-condition classes."""
