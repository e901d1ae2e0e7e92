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

import numpy as np

__all__ = [
    "RAD_S_PER_RPM",
    "Conditions",
    "DriveCoupling",
    "SpeedRamp",
    "SpeedTable",
    "TorqueDriven",
]

RAD_S_PER_RPM = 2.0 * math.pi / 60.0
"""One min^-1 in rad/s."""


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
"""Any of the operating-condition classes."""
