"""Internal step and output rate of a run (:func:`choose_step`).

The output rate must represent the mesh frequency: the anti-alias filter of the decimation
(:mod:`gearvib.simulation.decimation`) keeps the output flat up to
``PASSBAND_FRACTION * fs_out = 0.3 fs_out`` and removes everything above ``0.5 fs_out``. A given
``fs_out`` whose flat band does not reach the highest mesh frequency of the run is refused
(the stored tooth forces would lose or misstate the mesh frequency); the default output rate
is the smallest "nice" rate at or above both 20 kHz and ``10 f_mesh``, which keeps the first
:data:`DEFAULT_MESH_HARMONICS` mesh harmonics flat.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gearvib.checks import NUMBER_TYPES, check_count, check_real, short
from gearvib.config import ConfigError

__all__ = [
    "DEFAULT_FS_OUT",
    "DEFAULT_MESH_HARMONICS",
    "MIN_STEPS_PER_NATURAL_PERIOD",
    "PASSBAND_FRACTION",
    "STEPS_PER_MESH_CYCLE",
    "STEPS_PER_NATURAL_PERIOD",
    "StepChoice",
    "choose_step",
]

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
"""Default output rate [Hz] (the smallest "nice" rate at or above it is used)."""
PASSBAND_FRACTION = 0.3
"""The stored signals are flat (within 2e-4) up to this fraction of the output rate."""
DEFAULT_MESH_HARMONICS = 3
"""Mesh harmonics kept flat by the default output rate."""
_NICE_MANTISSAS = (1.0, 1.2, 1.25, 1.6, 2.0, 2.4, 2.5, 3.2, 4.0, 4.8, 5.0, 5.12, 6.4, 8.0)


def _nice_rates(lo: float, hi: float) -> list[float]:
    rates = []
    for e in range(0, 13):
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


def _check_fs_out(fs_out: float, f_mesh_max: float, speed_max_rpm: float | None) -> None:
    """Refuse an output rate whose flat band does not reach the highest mesh frequency."""
    if f_mesh_max > PASSBAND_FRACTION * fs_out:
        need = f_mesh_max / PASSBAND_FRACTION
        at = f" (at {speed_max_rpm:.6g} min-1)" if speed_max_rpm is not None else ""
        raise ConfigError(
            f"fs_out = {fs_out:.6g} Hz ([simulation].fs_out, --fs) cannot represent the highest "
            f"mesh frequency {f_mesh_max:.6g} Hz of the run{at}: the stored signals are flat "
            f"only up to {PASSBAND_FRACTION:g} fs_out = {PASSBAND_FRACTION * fs_out:.6g} Hz and "
            f"the anti-alias filter removes everything above {0.5 * fs_out:.6g} Hz. Give fs_out "
            f">= {math.ceil(need):d} Hz ({math.ceil(DEFAULT_MESH_HARMONICS * need):d} Hz for "
            f"{DEFAULT_MESH_HARMONICS} mesh harmonics), or omit it for the default")


def choose_step(
    f_nat_max: float,
    f_mesh_max: float,
    *,
    dt: float | None = None,
    fs_out: float | None = None,
    min_decimation: int = 4,
    speed_max_rpm: float | None = None,
) -> StepChoice:
    """Choose the internal step and the output rate.

    Parameters
    ----------
    f_nat_max : float
        Highest natural frequency of the simulated system [Hz].
    f_mesh_max : float
        Highest mesh frequency of the run [Hz].
    dt, fs_out : float, optional
        User overrides. ``1 / dt`` must be an integer multiple of ``fs_out``; ``fs_out`` must
        keep the highest mesh frequency in its flat band (``f_mesh_max <= 0.3 fs_out``).
    min_decimation : int
        Smallest decimation factor when ``dt`` is chosen automatically.
    speed_max_rpm : float, optional
        Highest input speed [min^-1], named in messages.

    Returns
    -------
    StepChoice

    Raises
    ------
    ConfigError
        (a ``ValueError``) If ``dt`` exceeds the admissible maximum ``1 / (10 f_nat_max)``,
        ``1 / dt`` is not a multiple of ``fs_out``, ``fs_out`` cannot represent the mesh
        frequency, or a frequency is not finite.
    """
    for name, f in (("highest natural frequency", f_nat_max),
                    ("highest mesh frequency", f_mesh_max)):
        if isinstance(f, bool) or not isinstance(f, NUMBER_TYPES):
            raise ConfigError(f"the {name} must be a number [Hz]; got {short(f)}")
        if isinstance(f, int) and abs(f) > 1e300:
            raise ConfigError(f"the {name} of the run is {short(f)} Hz: out of range "
                              "(admissible: finite)")
        if not (math.isfinite(f) and f >= 0):
            raise ConfigError(f"the {name} of the run is {f!r} Hz: a stiffness, mass or speed "
                              "of the description is out of range (admissible: finite)")
    limits = [1.0 / (STEPS_PER_NATURAL_PERIOD * f_nat_max)] if f_nat_max > 0 else []
    if f_mesh_max > 0:
        limits.append(1.0 / (STEPS_PER_MESH_CYCLE * f_mesh_max))
    dt_rec = min(limits) if limits else 1e-4
    dt_adm = 1.0 / (MIN_STEPS_PER_NATURAL_PERIOD * f_nat_max) if f_nat_max > 0 else math.inf
    if not dt_rec > 0:
        raise ConfigError(f"the step 1/(40 f) underflows for the highest natural frequency "
                          f"{f_nat_max:.4g} Hz and mesh frequency {f_mesh_max:.4g} Hz: a "
                          "stiffness or speed of the description is out of range")
    min_decimation = check_count(min_decimation, "min_decimation", low=1, high=10**6,
                                 error=ConfigError)
    speed_max_rpm = check_real(speed_max_rpm, "speed_max_rpm", optional=True, error=ConfigError)
    if fs_out is not None:
        fs_out = check_real(fs_out, "fs_out [Hz]", error=ConfigError)
        if not (math.isfinite(fs_out) and fs_out > 0):
            raise ConfigError(f"fs_out = {fs_out!r} Hz is not admissible (admissible: > 0, "
                              "finite)")
        _check_fs_out(fs_out, f_mesh_max, speed_max_rpm)
    lo = max(DEFAULT_FS_OUT, DEFAULT_MESH_HARMONICS * f_mesh_max / PASSBAND_FRACTION)
    if dt is not None:
        dt = check_real(dt, "dt [s]", error=ConfigError)
        if not (math.isfinite(dt) and dt > 0):
            raise ConfigError(f"dt = {dt!r} s is not admissible (admissible: > 0, finite)")
        if dt > dt_adm:
            raise ConfigError(
                f"dt = {dt:.6g} s is too large for the highest natural frequency "
                f"{f_nat_max:.6g} Hz: the admissible maximum is {dt_adm:.6g} s "
                f"({MIN_STEPS_PER_NATURAL_PERIOD} steps per period; "
                f"{dt_rec:.6g} s recommended)"
            )
        fs_int = 1.0 / dt
        if not math.isfinite(fs_int):
            raise ConfigError(f"dt = {dt!r} s is not admissible (1/dt overflows)")
        if fs_out is None:
            for cand in _nice_rates(lo, fs_int):
                ratio = fs_int / cand
                if abs(ratio - round(ratio)) < 1e-9 * ratio:
                    fs_out = cand
                    break
            else:
                fs_out = fs_int / max(1, math.floor(fs_int / lo + 1e-9))
            _check_fs_out(fs_out, f_mesh_max, speed_max_rpm)
        ratio = fs_int / float(fs_out)
        if not math.isfinite(ratio):
            raise ConfigError(f"fs_out = {fs_out:.6g} Hz is not admissible with dt = {dt:.6g} "
                              "s: the decimation 1/(dt fs_out) overflows (give a larger fs_out)")
        dec = round(ratio)
        if dec < 1 or abs(ratio - dec) > 1e-9 * ratio:
            raise ConfigError(f"1/dt = {fs_int:.9g} Hz (dt, --dt) is not an integer multiple "
                              f"of fs_out = {fs_out:.9g} Hz (--fs)")
        return StepChoice(dt, fs_int / dec, dec, dt_rec, dt_adm, f_nat_max, f_mesh_max)
    if fs_out is None:
        fs = DEFAULT_FS_OUT if lo <= DEFAULT_FS_OUT else min(
            _nice_rates(lo, 1e13) or [math.ceil(lo)])
    else:
        fs = fs_out
    denom = dt_rec * fs
    ratio = 1.0 / denom if denom > 0 else math.inf
    if not math.isfinite(ratio):
        raise ConfigError(f"fs_out = {fs:.6g} Hz is not admissible for the internal step "
                          f"{dt_rec:.3g} s: the decimation 1/(dt fs_out) overflows (give a "
                          "larger fs_out; a tiny step comes from a stiffness or speed out of "
                          "range)")
    dec = max(min_decimation, math.ceil(ratio - 1e-9))
    return StepChoice(1.0 / (dec * fs), fs, dec, dt_rec, dt_adm, f_nat_max, f_mesh_max)
