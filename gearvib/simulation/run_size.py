"""The size of a run, checked before anything is allocated (:func:`check_run_size`).

Every size of a run follows from the input: the number of internal steps is
``duration / dt`` with ``dt`` from the highest natural and mesh frequency (a bearing stiffness
of 1e38 N/m or a speed of 1e9 min-1 make it astronomically large), the anti-alias filter has
about ``27 D`` taps for a decimation ``D = 1 / (dt fs_out)``, the output holds
``duration * fs_out`` samples of every stored signal. :func:`check_run_size` refuses a run
whose steps exceed the time budget ``max_steps`` or whose arrays exceed the memory available
(:func:`gearvib.memory.require_memory`), with a message that names the parameters and what to
change.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gearvib.checks import check_count, check_instance, check_real
from gearvib.memory import RunSizeError, require_memory
from gearvib.simulation.decimation import filter_length
from gearvib.simulation.step import DEFAULT_FS_OUT, StepChoice

__all__ = ["DEFAULT_MAX_STEPS", "MAX_KERNEL_STEPS", "OUTPUT_COPIES", "RunSize",
           "check_run_size", "seconds_per_step"]

DEFAULT_MAX_STEPS = 1_000_000_000
"""Time budget of one run: internal steps (about 50 min at 3 µs per step); ``max_steps=``."""
MAX_KERNEL_STEPS = 10_000
"""Steps per kernel call: the run returns to Python (interrupts, progress) at least this often."""
OUTPUT_COPIES = 3
"""Peak memory of the output as multiples of the stored samples (output array, the result's
arrays, the Dataset and the netCDF encoding of one variable: 2.3x measured with tracemalloc for
a 4 s run of ``paper-case1`` written to netCDF, 1.9x for ``paper-case1-elastic``)."""


@dataclass(frozen=True)
class RunSize:
    """Sizes of one run.

    Attributes
    ----------
    steps : int
        Internal steps (including the filter's delay at the end).
    n_out : int
        Output samples per signal.
    taps : int
        Length of the anti-alias filter.
    bytes : int
        Estimated peak memory of the run's arrays.
    """

    steps: int
    n_out: int
    taps: int
    bytes: int


MAX_DOF = 100_000
"""Largest model size (degrees of freedom, meshes) a run-size check takes."""


def seconds_per_step(n_dof: int, n_mesh: int) -> float:
    """Rough wall time of one RK4 step [s] (2.8 µs for 5 DOF and 6 meshes, 5.2 µs for 17 DOF;
    only used to state a time in messages)."""
    n_dof = check_count(n_dof, "n_dof", low=0, high=MAX_DOF)
    n_mesh = check_count(n_mesh, "n_mesh", low=0, high=MAX_DOF)
    return 1.5e-6 + 1.2e-8 * n_dof * n_dof + 1.5e-7 * n_mesh


def _duration_text(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.3g} s"
    if seconds < 7200:
        return f"{seconds / 60:.3g} min"
    if seconds < 172800:
        return f"{seconds / 3600:.3g} h"
    return f"{seconds / 86400:.3g} days"


def check_run_size(step: StepChoice, duration: float, *, n_dof: int, n_mesh: int,
                   n_signals: int, n_stored: int, max_steps: int = DEFAULT_MAX_STEPS,
                   speed_max_rpm: float | None = None, dt_given: bool = False,
                   fs_out_given: bool = False) -> RunSize:
    """Check the steps and the memory of a run before anything is allocated.

    Parameters
    ----------
    step : StepChoice
        Internal step and output rate (:func:`gearvib.simulation.step.choose_step`).
    duration : float
        Simulated time [s].
    n_dof, n_mesh : int
        Model size.
    n_signals : int
        Signals recorded per internal step (:func:`gearvib.kernels.n_signals`).
    n_stored : int
        Values per output sample in the result and its Dataset.
    max_steps : int
        Time budget: the largest number of internal steps accepted.
    speed_max_rpm : float, optional
        Highest input speed [min^-1], named in the message when the mesh frequency sets the
        step or the output rate.
    dt_given, fs_out_given : bool
        Whether the step and the output rate were given (named as the cause) or chosen.

    Returns
    -------
    RunSize

    Raises
    ------
    RunSizeError
        Too many steps for ``max_steps``, or more memory than available; the message names
        the parameters (duration, dt and what sets it, fs_out) and what to change.
    """
    check_instance(step, StepChoice, "step")
    duration = check_real(duration, "duration [s]", low=0.0, low_open=True)
    for key, v in (("n_dof", n_dof), ("n_mesh", n_mesh), ("n_signals", n_signals),
                   ("n_stored", n_stored)):
        check_count(v, key, low=0, high=MAX_DOF * MAX_DOF)
    max_steps = check_count(max_steps, "max_steps", low=1, high=10**15)
    speed_max_rpm = check_real(speed_max_rpm, "speed_max_rpm", optional=True)
    for key, flag in (("dt_given", dt_given), ("fs_out_given", fs_out_given)):
        if not isinstance(flag, bool):
            raise TypeError(f"{key} must be a bool; got {type(flag).__name__}")
    dec = step.decimation
    n_out_f = duration * step.fs_out
    taps = filter_length(dec)
    half = (taps - 1) // 2
    at = f" at {speed_max_rpm:.4g} min-1" if speed_max_rpm is not None else ""
    mesh_text = f"the highest mesh frequency {step.highest_mesh_frequency:.4g} Hz{at}"
    steps = (math.floor(n_out_f + 1e-9) * dec + half + 1) if math.isfinite(n_out_f) else None
    if steps is None or steps > max_steps:
        steps_f = float(steps) if steps is not None and steps < 10**300 else math.inf
        if dt_given:
            why = "given (dt, --dt)"
        elif 1.0 / (40.0 * max(step.highest_natural_frequency, 1e-300)) <= \
                step.dt_recommended * (1 + 1e-9):
            why = (f"from the highest natural frequency {step.highest_natural_frequency:.4g} "
                   "Hz: a very stiff support, coupling or mesh, or a very light body")
        else:
            why = f"from {mesh_text} (speed_end_rpm, --speed)"
        if math.isfinite(steps_f):
            count = f"{steps_f:.3g}"
            est = f"about {_duration_text(steps_f * seconds_per_step(n_dof, n_mesh))}"
        else:
            count, est = "more than 1e300", "forever"
        if steps is not None and 2 * half > steps - half:  # the filter delay dominates
            cause = (f"the anti-alias filter from 1/dt = {1 / step.dt:.4g} Hz down to fs_out = "
                     f"{step.fs_out:.4g} Hz (--fs) needs {half:.3g} steps of delay at the end")
            remedy = "raise fs_out (--fs)"
        else:
            cause = f"duration {duration:.4g} s with dt = {step.dt:.4g} s {why}"
            remedy = ("give a larger dt (or omit it) or a shorter duration" if dt_given else
                      "shorten the duration, lower the speed range or the stiffness that sets "
                      "the step")
        raise RunSizeError(
            f"the run needs {count} internal steps ({cause}), more than the limit max_steps = "
            f"{max_steps:.3g} ({est} of computing): {remedy}, or raise the limit "
            "(simulate(max_steps=...), gearvib simulate --max-steps)")
    n_out = math.floor(n_out_f + 1e-9) + 1
    chunk_rows = max(MAX_KERNEL_STEPS, 2 * half + dec + 1) + 2 * half + dec + 1
    output = 8 * OUTPUT_COPIES * n_out * max(n_signals, n_stored)
    filtering = 8 * (chunk_rows * n_signals + 4 * taps)  # taps and the record spanning them
    nbytes = output + filtering
    if filtering > output:
        what = (f"the anti-alias filter ({taps:.3g} taps and a record of as many steps, for "
                f"the decimation by {dec:.3g} from 1/dt = {1 / step.dt:.4g} Hz to fs_out = "
                f"{step.fs_out:.4g} Hz)")
        remedy = "raise fs_out (--fs) towards the internal rate, or lower the stiffness/speed"
    else:
        rate = f"fs_out = {step.fs_out:.4g} Hz"
        if not fs_out_given and step.fs_out > DEFAULT_FS_OUT:
            rate += f" (the default for {mesh_text})"
        what = (f"the output ({n_out:.3g} samples of {max(n_signals, n_stored)} signals: "
                f"duration {duration:.4g} s at {rate})")
        remedy = "shorten the duration or lower fs_out (--fs)" if fs_out_given or \
            step.fs_out <= DEFAULT_FS_OUT else "shorten the duration or lower the speed range"
    require_memory(nbytes, what, remedy)
    return RunSize(int(steps), n_out, taps, int(nbytes))
