"""The ``[simulation]`` table of a description: checked run settings -> operating conditions.

Keys (all optional; SI units, speeds in min^-1):

================== ===================================================================
``drive``          ``"speed"`` (default: speed ramp through the drive coupling),
                   ``"torque"`` (constant input torque) or ``"motor"``
``speed_start_rpm`` input speed at ``t = 0`` (default 0)
``speed_end_rpm``  end of the ramp (speed drive); expected highest speed otherwise
                   (default 4000; for a motor its synchronous or highest table speed)
``duration``       simulated time [s] (default 1)
``input_torque``   [N m]: speed drive: lossless input torque that sets the load; torque
                   drive: the constant input torque (required)
``load_torque``    [N m] resisting the output: a number ``T0`` or ``[T0, c1, c2]`` for
                   ``T0 + c1 w + c2 w |w|`` (``w`` output speed [rad/s]; torque and motor
                   drive only); speed drive: alternative to ``input_torque``
``load_inertia``   inertia added to the output member [kg m^2] (torque and motor drive)
``drive_stiffness`` drive coupling [N m/rad] (speed drive; default from the lowest mode)
``drive_damping``  drive coupling [N m s/rad] (with ``drive_stiffness``)
``motor``          motor characteristic (motor drive): ``{synchronous_rpm, breakdown_torque,
                   breakdown_slip}`` (Kloss) or ``{speed_rpm = [...], torque = [...]}``
``fs_out``, ``dt`` output rate [Hz] and internal step [s] (default: chosen by the run)
``gyroscopic``     true: gyroscopic and centripetal terms of the rotating carrier
================== ===================================================================

Every value is checked here, and an error (:class:`gearvib.config.ConfigError`) names the key
and the admissible range; command-line options override the keys of the same name.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from gearvib.checks import RUN, check_number
from gearvib.checks import short as _short
from gearvib.config import ConfigError
from gearvib.kinematics import MAX_SPEED_RPM
from gearvib.simulation.conditions import (
    MAX_DURATION,
    MAX_TABLE,
    MAX_TORQUE,
    Conditions,
    DriveCoupling,
    MotorDriven,
    SpeedRamp,
    TorqueDriven,
)

__all__ = ["DRIVES", "SIMULATION_KEYS", "conditions_from_settings", "read_run_settings"]

DRIVES = ("speed", "torque", "motor")
SIMULATION_KEYS = frozenset({
    "drive", "speed_start_rpm", "speed_end_rpm", "duration", "input_torque", "load_torque",
    "load_inertia", "drive_stiffness", "drive_damping", "motor", "fs_out", "dt", "gyroscopic",
})
_MOTOR_KLOSS = frozenset({"synchronous_rpm", "breakdown_torque", "breakdown_slip"})
_MOTOR_TABLE = frozenset({"speed_rpm", "torque"})
_ONLY = {
    "input_torque": ("speed", "torque"),
    "load_inertia": ("torque", "motor"),
    "drive_stiffness": ("speed",),
    "drive_damping": ("speed",),
    "motor": ("motor",),
}


MIN_DURATION = 1e-6
"""Shortest simulated time accepted [s]."""


def _num(value: Any, key: str, *, low: float | None = None, strict: bool = False,
         high: float | None = None) -> float:
    """``[simulation].key`` as a finite number; ``high`` bounds its magnitude."""
    return check_number(value, f"[simulation].{key}", low=low, low_open=strict, high=high,
                        magnitude=True, symbol=key.split(".")[-1], error=ConfigError,
                        wording=RUN)


def _slip(value: Any) -> float:
    v = _num(value, "motor.breakdown_slip", low=0.0, strict=True)
    if v >= 1.0:
        raise ConfigError(f"[simulation].motor.breakdown_slip = {v!r} is not admissible "
                          "(admissible: 0 < s_k < 1)")
    return v


def _motor(value: Any) -> dict:
    if not isinstance(value, Mapping):
        raise ConfigError("[simulation].motor must be a table: {synchronous_rpm, "
                         "breakdown_torque, breakdown_slip} or {speed_rpm, torque}")
    keys = set(value)
    if keys == _MOTOR_KLOSS:
        return {"synchronous_rpm": _num(value["synchronous_rpm"], "motor.synchronous_rpm",
                                        low=0.0, strict=True, high=MAX_SPEED_RPM),
                "breakdown_torque": _num(value["breakdown_torque"], "motor.breakdown_torque",
                                         low=0.0, strict=True, high=MAX_TORQUE),
                "breakdown_slip": _slip(value["breakdown_slip"])}
    if keys == _MOTOR_TABLE:
        out = {}
        for k in ("speed_rpm", "torque"):
            if not isinstance(value[k], list) or not 2 <= len(value[k]) <= MAX_TABLE:
                raise ConfigError(f"[simulation].motor.{k} must be a list of 2..{MAX_TABLE} "
                                  "numbers")
            out[k] = [_num(v, f"motor.{k}", high=MAX_SPEED_RPM if k == "speed_rpm"
                           else MAX_TORQUE) for v in value[k]]
        if len(out["speed_rpm"]) != len(out["torque"]):
            raise ConfigError(f"[simulation].motor: speed_rpm ({len(out['speed_rpm'])} values) "
                              f"and torque ({len(out['torque'])}) must be as long")
        if any(b <= a for a, b in zip(out["speed_rpm"], out["speed_rpm"][1:], strict=False)):
            raise ConfigError("[simulation].motor.speed_rpm must be strictly increasing")
        return out
    unknown = sorted(str(k) for k in keys - _MOTOR_KLOSS - _MOTOR_TABLE)
    what = f"unknown key {unknown[0]!r} in" if unknown else "incomplete"
    raise ConfigError(f"{what} [simulation].motor (admissible: synchronous_rpm, "
                     "breakdown_torque, breakdown_slip for the Kloss curve, or speed_rpm and "
                     "torque for a table)")


def read_run_settings(sim: Mapping[str, Any] | None,
                      overrides: Mapping[str, Any] | None = None) -> dict:
    """Checked, completed run settings from a ``[simulation]`` table and overrides.

    Parameters
    ----------
    sim : mapping or None
        The ``[simulation]`` table.
    overrides : mapping, optional
        Values that replace those of the table (command-line options); ``None`` values are
        ignored.

    Returns
    -------
    dict
        Every key of the module table with its default filled in (``None`` where the run
        chooses; ``input_torque`` is left out when the run has no single input torque),
        JSON-serialisable (it is stored as the run's provenance).

    Raises
    ------
    ConfigError
        (a ``ValueError``) Naming the key and the admissible values.
    """
    if sim is not None and not isinstance(sim, Mapping):
        raise ConfigError(f"[simulation] must be a table, got {type(sim).__name__}")
    if overrides is not None and not isinstance(overrides, Mapping):
        raise ConfigError(f"overrides must be a mapping of [simulation] keys, got "
                          f"{type(overrides).__name__}")
    if overrides and any(v is not None for v in overrides.values()):
        read_run_settings(sim)  # the file's own values are checked too, not only the winners
    table = dict(sim or {})
    unknown = sorted(str(k) for k in set(table) - SIMULATION_KEYS)
    if unknown:
        raise ConfigError(f"unknown key {_short(unknown[0])} in [simulation] (admissible: "
                         f"{', '.join(sorted(SIMULATION_KEYS))})")
    for key, value in (overrides or {}).items():
        if value is not None:
            table[key] = value
    drive = table.get("drive", "speed")
    if not isinstance(drive, str) or drive not in DRIVES:
        raise ConfigError(f"[simulation].drive = {_short(drive)} is not admissible (admissible: "
                         f"{', '.join(DRIVES)})")
    for key, drives in _ONLY.items():
        if key in table and drive not in drives:
            raise ConfigError(f"[simulation].{key} applies to drive = "
                             f"{' or '.join(repr(d) for d in drives)}, not {drive!r}")
    run: dict[str, Any] = {"drive": drive}
    run["speed_start_rpm"] = _num(table.get("speed_start_rpm", 0.0), "speed_start_rpm",
                                  high=MAX_SPEED_RPM)
    run["speed_end_rpm"] = (_num(table["speed_end_rpm"], "speed_end_rpm", high=MAX_SPEED_RPM)
                            if "speed_end_rpm" in table else
                            (None if drive == "motor" else 4000.0))
    run["duration"] = _num(table.get("duration", 1.0), "duration", low=MIN_DURATION,
                           high=MAX_DURATION)
    run["input_torque"] = (_num(table["input_torque"], "input_torque", high=MAX_TORQUE)
                           if "input_torque" in table else None)
    load = table.get("load_torque")
    if isinstance(load, list | tuple):
        if drive == "speed" or len(load) != 3:
            raise ConfigError("[simulation].load_torque must be a number (speed drive) or "
                             "[T0, c1, c2] (torque and motor drive)")
        load = [_num(v, "load_torque", high=MAX_TORQUE) for v in load]
    elif load is not None:
        load = _num(load, "load_torque", high=MAX_TORQUE)
    run["load_torque"] = load
    if drive == "speed":
        if run["input_torque"] is not None and load is not None:
            raise ConfigError("[simulation]: give input_torque or load_torque, not both "
                             "(speed drive)")
        if run["input_torque"] is None and load is None:
            run["input_torque"] = 0.0
    if drive == "torque" and run["input_torque"] is None:
        raise ConfigError("[simulation].input_torque is required for drive = 'torque' [N m]")
    run["load_inertia"] = _num(table.get("load_inertia", 0.0), "load_inertia", low=0.0,
                               high=1e9)
    if "drive_damping" in table and "drive_stiffness" not in table:
        raise ConfigError("[simulation].drive_damping needs drive_stiffness")
    run["drive_stiffness"] = (_num(table["drive_stiffness"], "drive_stiffness", low=0.0, high=1e40,
                                   strict=True) if "drive_stiffness" in table else None)
    run["drive_damping"] = (_num(table.get("drive_damping", 0.0), "drive_damping", low=0.0,
                                 high=1e12)
                            if "drive_stiffness" in table else None)
    if drive == "motor":
        if "motor" not in table:
            raise ConfigError("[simulation].motor is required for drive = 'motor'")
        run["motor"] = _motor(table["motor"])
        if run["speed_end_rpm"] is None:  # the expected highest speed
            motor = run["motor"]
            run["speed_end_rpm"] = motor.get("synchronous_rpm") or max(
                abs(v) for v in motor["speed_rpm"])
    else:
        run["motor"] = None
    if run["input_torque"] is None:  # no single input torque (load_torque given, or a motor)
        del run["input_torque"]
    run["fs_out"] = (_num(table["fs_out"], "fs_out", low=0.0, strict=True, high=1e12)
                     if table.get("fs_out") is not None else None)
    run["dt"] = (_num(table["dt"], "dt", low=0.0, strict=True)
                 if table.get("dt") is not None else None)
    gyro = table.get("gyroscopic", False)
    if not isinstance(gyro, bool):
        raise ConfigError(f"[simulation].gyroscopic must be true or false, got {_short(gyro)}")
    run["gyroscopic"] = gyro
    return run


def conditions_from_settings(run: Mapping[str, Any]) -> Conditions:
    """Operating conditions of checked run settings (:func:`read_run_settings`).

    Speed drive: a :class:`SpeedRamp` from ``speed_start_rpm`` to ``speed_end_rpm`` over
    ``duration``; torque drive: :class:`TorqueDriven` with the constant ``input_torque``,
    starting at ``speed_start_rpm``, ``speed_end_rpm`` the expected highest speed; motor
    drive: :class:`MotorDriven` (Kloss curve or table).

    Raises
    ------
    ConfigError
        Settings the conditions refuse (named).
    """
    if not isinstance(run, Mapping):
        raise ConfigError(f"run must be the run settings of read_run_settings (a mapping); got "
                          f"{type(run).__name__}")
    missing = sorted(_RUN_KEYS - set(run))
    if missing:
        raise ConfigError(f"run settings lack {missing[0]!r} (give the result of "
                          "read_run_settings)")
    if not isinstance(run["drive"], str) or run["drive"] not in DRIVES:
        raise ConfigError(f"run settings: drive = {_short(run['drive'])} is not admissible "
                          f"(admissible: {', '.join(DRIVES)})")
    load = run["load_torque"]
    if isinstance(load, list | tuple) and len(load) != 3:
        raise ConfigError("run settings: load_torque must be a number or (T0, c1, c2)")
    motor = run["motor"]
    if run["drive"] == "motor" and not (isinstance(motor, Mapping) and (
            set(motor) == _MOTOR_KLOSS or set(motor) == _MOTOR_TABLE)):
        raise ConfigError("run settings: motor must be {synchronous_rpm, breakdown_torque, "
                          "breakdown_slip} or {speed_rpm, torque} for drive = 'motor'")
    if run["drive"] == "torque" and "input_torque" not in run:
        raise ConfigError("run settings lack 'input_torque' (drive = 'torque')")
    try:
        return _conditions(run)
    except ConfigError:
        raise
    except (ValueError, TypeError) as exc:
        raise ConfigError(f"[simulation]: {exc}") from None


_RUN_KEYS = {"drive", "speed_start_rpm", "speed_end_rpm", "duration", "load_torque",
             "load_inertia", "motor"}


def _conditions(run: Mapping[str, Any]) -> Conditions:
    drive = run["drive"]
    load = run["load_torque"]
    if drive == "speed":
        coupling = None
        if run.get("drive_stiffness") is not None:
            coupling = DriveCoupling(run["drive_stiffness"], run.get("drive_damping") or 0.0)
        return SpeedRamp(run["speed_start_rpm"], run["speed_end_rpm"], run["duration"],
                         load_torque=0.0 if load is None else load,
                         input_torque=None if load is not None else run.get("input_torque"),
                         coupling=coupling)
    triple = (0.0, 0.0, 0.0) if load is None else (
        tuple(load) if isinstance(load, list | tuple) else (load, 0.0, 0.0))
    common = dict(load_inertia=run["load_inertia"], load_torque=triple,
                  start_rpm=run["speed_start_rpm"], duration=run["duration"])
    if drive == "torque":
        top = run["speed_end_rpm"] if run["speed_end_rpm"] is not None else 4000.0
        return TorqueDriven(input_torque=run["input_torque"], max_rpm=abs(top) or 1.0,
                            **common)
    motor = run["motor"]
    if run["speed_end_rpm"] is not None:
        common["max_rpm"] = abs(run["speed_end_rpm"]) or 1.0
    if "synchronous_rpm" in motor:
        return MotorDriven.kloss(motor["synchronous_rpm"], motor["breakdown_torque"],
                                 motor["breakdown_slip"], **common)
    return MotorDriven(motor["speed_rpm"], motor["torque"], **common)
