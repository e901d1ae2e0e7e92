"""Internal step and output rate of a run (:func:`choose_step`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = [
    "DEFAULT_FS_OUT",
    "MIN_STEPS_PER_NATURAL_PERIOD",
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
_NICE_MANTISSAS = (1.0, 1.2, 1.25, 1.6, 2.0, 2.4, 2.5, 3.2, 4.0, 4.8, 5.0, 5.12, 6.4, 8.0)


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
