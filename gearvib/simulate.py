"""Run-up simulation of an assembled gear set: :func:`simulate`.

:func:`simulate` integrates the equations of :mod:`gearvib.kernels` with a fixed-step classical
Runge-Kutta scheme, starting from the static equilibrium under the initial load, and returns a
:class:`RunUpResult` whose :meth:`RunUpResult.to_dataset` gives a CF-annotated
:class:`xarray.Dataset`. The user page is ``docs/simulator.md``.

The parts of a run live in :mod:`gearvib.simulation`, one module per concept (operating
conditions, step choice, decimation filter, static equilibrium, run set-up, result); this
module drives them and re-exports their public names, so ``from gearvib.simulate import
SpeedRamp, simulate`` is all a user needs.

Sign conventions
----------------
Speeds and torques at the input member are positive in the member's positive rotation sense
(``model.rotation_dofs[model.input_member]``). The load torque at the output member always
*resists* the forward motion of the output member (the sense of
``model.kinematic_ratios[model.output_member]``).

Threads
-------
A run is serial: :func:`simulate` and :func:`simulate_batch` run with one BLAS/OpenMP thread
(``threadpoolctl``). The set-up's small linear algebra gains nothing from more, and
OpenBLAS's idle threads would otherwise spin on a second core after every call (measured: a
second process-CPU second per second of a paper-case1 run-up in a loop of runs, none of it
useful). The arithmetic is that of a sweep worker, which runs the same way. The limit is set
through one controller per process (:func:`analysis.threads.one_blas_thread`; finding the
libraries at every call would cost 1-2 ms per run).
"""

from __future__ import annotations

import functools
import math
import time as _time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import ParamSpec, TypeVar, cast

import numpy as np

from analysis.threads import one_blas_thread
from gearvib import kernels as kn
from gearvib.checks import check_config, check_frequencies, check_items, check_real, short
from gearvib.config import ConfigError
from gearvib.fault_pass import with_fault_pass
from gearvib.model import AssembledModel
from gearvib.sensors.signal import add_sensor_signals
from gearvib.simulation.conditions import (
    RAD_S_PER_RPM,
    Conditions,
    DriveCoupling,
    MotorDriven,
    SpeedRamp,
    SpeedTable,
    TorqueDriven,
)
from gearvib.simulation.decimation import decimation_filter
from gearvib.simulation.equilibrium import static_equilibrium
from gearvib.simulation.errors import SimulationError
from gearvib.simulation.frequencies import stiffest_matrix, undamped_frequencies
from gearvib.simulation.result import INTEGRATOR, RunUpResult, build_result
from gearvib.simulation.run_setup import (
    COUPLING_FREQUENCY_FRACTION,
    RunSetup,
    check_model,
    coupling_matrices,
    default_coupling,
    prepare_run,
    with_coupling,
)
from gearvib.simulation.run_size import (
    DEFAULT_MAX_STEPS,
    MAX_KERNEL_STEPS,
    RunSize,
    check_run_size,
)
from gearvib.simulation.step import (
    DEFAULT_FS_OUT,
    MIN_STEPS_PER_NATURAL_PERIOD,
    STEPS_PER_MESH_CYCLE,
    STEPS_PER_NATURAL_PERIOD,
    StepChoice,
    choose_step,
)
from gearvib.simulation.tooth_forces import StaticToothForces, static_tooth_forces

__all__ = [
    "BATCHABLE",
    "CHUNK_DURATION",
    "COUPLING_FREQUENCY_FRACTION",
    "DEFAULT_FS_OUT",
    "DEFAULT_MAX_STEPS",
    "INTEGRATOR",
    "MIN_STEPS_PER_NATURAL_PERIOD",
    "STEPS_PER_MESH_CYCLE",
    "STEPS_PER_NATURAL_PERIOD",
    "Conditions",
    "DriveCoupling",
    "MotorDriven",
    "RunSetup",
    "RunSize",
    "RunUpResult",
    "SimulationError",
    "SpeedRamp",
    "SpeedTable",
    "StaticToothForces",
    "StepChoice",
    "TorqueDriven",
    "batch_groups",
    "check_run_size",
    "choose_step",
    "coupling_matrices",
    "decimation_filter",
    "default_coupling",
    "prepare_run",
    "simulate",
    "simulate_batch",
    "static_equilibrium",
    "static_tooth_forces",
    "with_coupling",
]

CHUNK_DURATION = 0.05
"""Simulated time per kernel call [s]."""


def _blow_up_message(t: float, code: int, setup: RunSetup, step: StepChoice, gyro: bool) -> str:
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
    elif setup.drive == "motor":
        causes.append("a motor characteristic that the load cannot balance (no stable working "
                      "point below max_rpm)")
    else:
        causes.append("a drive coupling or load torque that destabilises the system")
    if gyro:
        causes.append("centripetal softening (Omega_c^2 K_Omega) beyond the bearing stiffness")
    if setup.coupling is not None and setup.coupling.sensing == "rigid-body":
        causes.append("a parametric instability without enough damping (the default speed "
                      "drive adds none to the elastic modes: more mesh damping, or a coupling "
                      "on the input member, DriveCoupling(k, c) or [simulation] "
                      "drive_stiffness and drive_damping)")
    else:
        causes.append("a parametric instability without enough damping")
    return (
        f"numerical blow-up at simulated time t = {t:.6g} s: {what}. Likely cause: "
        + "; or ".join(causes)
        + "."
    )


_P = ParamSpec("_P")
_R = TypeVar("_R")


def _one_blas_thread(func: Callable[_P, _R]) -> Callable[_P, _R]:
    """Run ``func`` with one BLAS/OpenMP thread (module docstring, "Threads")."""

    @functools.wraps(func)
    def wrapper(*args: _P.args, **kwargs: _P.kwargs) -> _R:
        with one_blas_thread():
            return func(*args, **kwargs)

    return wrapper


@_one_blas_thread
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
    natural_frequencies: Sequence[float] | np.ndarray | None = None,
    max_steps: int = DEFAULT_MAX_STEPS,
) -> RunUpResult:
    """Simulate a run-up (or run-down, or torque-driven run) of an assembled gear set.

    Parameters
    ----------
    model : AssembledModel
        The gear set (:func:`gearvib.assembly.assemble`). Its local tooth faults and
        manufacturing errors (``model.faults``, :mod:`gearvib.faults`) act in the run; its
        virtual sensors (``model.sensors``, :mod:`gearvib.sensors`) are computed from the
        stored forces and added to the result.
    conditions : SpeedRamp, SpeedTable, TorqueDriven or MotorDriven
        Operating conditions. Speed-driven runs prescribe the input angle ``phi(t)`` through a
        :class:`DriveCoupling`; by default (:func:`default_coupling`) a speed controller on the
        rigid-body mode, which adds nothing to the elastic modes: the rigid-body mode at 0.1x
        the lowest elastic natural frequency of the model, critically damped.
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
    max_steps : int
        Time budget: the largest number of internal steps accepted (default 1e9, about 50 min
        for a small set); a longer run is refused before it starts.

    Returns
    -------
    RunUpResult

    Raises
    ------
    ValueError
        Invalid model (e.g. negative stiffness tables), conditions or step;
        :class:`gearvib.config.ConfigError` for a step or output rate that is not admissible.
    gearvib.memory.RunSizeError
        (a ``ConfigError``) More internal steps than ``max_steps``, or arrays larger than the
        memory available (checked before allocating; the message names the parameter).
    SimulationError
        Numerical blow-up (the message states the simulated time and the likely cause) or no
        static equilibrium.
    """
    wall0 = _time.perf_counter()
    if progress is not None and not isinstance(progress, bool | np.bool_):
        raise TypeError(f"progress must be a bool or None; got {type(progress).__name__}")
    config = check_config(config)
    natural_frequencies = check_frequencies(natural_frequencies)
    prepared = _prepare_variant(model, conditions, dt, fs_out, duration, gyroscopic, max_steps)
    setup, step, run_duration = prepared.setup, prepared.step, prepared.duration
    acc0, y = prepared.acc0, prepared.y
    system = setup.system
    n, nm = model.n_dof, model.n_mesh
    nsig = kn.n_signals(n, nm)
    taps = decimation_filter(step.decimation)
    half = (taps.size - 1) // 2
    dec = step.decimation

    n_out = math.floor(run_duration * step.fs_out + 1e-9) + 1
    last_sample = (n_out - 1) * dec + half
    chunk = max(round(CHUNK_DURATION / step.dt), 2 * half + dec + 1)
    buf = np.empty((chunk + 2 * half + dec + 1, nsig))
    out = np.empty((n_out, nsig))
    work = np.empty(kn.work_shape(n, nm))
    mesh_out = np.empty((nm, kn.MESH_OUT_COLUMNS))
    status = np.zeros(2, dtype=np.int64)
    flank_state = np.full(nm, -1, dtype=np.int64)
    changes = np.zeros(nm, dtype=np.int64)
    sys_tuple = with_fault_pass(system.astuple())  # its faults' pass compiled (or generic)
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
            for off in range(0, m, MAX_KERNEL_STEPS):  # back in Python often (interrupts)
                kn.integrate_chunk(
                    y,
                    g + off,
                    min(MAX_KERNEL_STEPS, m - off),
                    step.dt,
                    sys_tuple,
                    buf,
                    fill + off,
                    flank_state,
                    changes,
                    (n_out - 1) * dec,
                    work,
                    mesh_out,
                    status,
                )
                if status[0] != kn.STATUS_OK:
                    break
            if status[0] != kn.STATUS_OK:
                raise SimulationError(
                    _blow_up_message(status[1] * step.dt, int(status[0]), setup, step, gyroscopic)
                )
            ang, spd = reference((g + np.arange(m)) * step.dt)
            kn.shift_rigid(buf, fill, ang, spd, rigid, False)
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
    kn.shift_rigid(out, 0, ang, spd, rigid, True)
    result = build_result(
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
    if model.sensors:
        result = add_sensor_signals(result, model)
        result.wall_time = _time.perf_counter() - wall0
    return result


BATCHABLE = (
    "values of the gear set that keep its topology: mesh damping, mesh and bearing stiffness, "
    "bearing damping, masses and inertias, backlash, stiffness-table values, mesh phases, "
    "load torque values"
)
"""What may differ between the variants of :func:`simulate_batch` (stated in its errors)."""


@dataclass
class _Variant:
    """One variant of :func:`simulate_batch` prepared as :func:`simulate` prepares its run."""

    model: AssembledModel
    conditions: Conditions
    setup: RunSetup
    step: StepChoice
    duration: float
    acc0: float
    y: np.ndarray


def _prepare_variant(model, conditions, dt, fs_out, duration, gyroscopic, max_steps):
    """The set-up of a run up to its initial state: checks, step choice, run-size guard and
    static equilibrium (:func:`simulate` and every variant of :func:`simulate_batch`)."""
    check_model(model)
    if duration is not None:
        check_real(duration, "duration [s]", error=ConfigError)
    if isinstance(max_steps, bool) or not isinstance(max_steps, int | np.integer) or not (
            1 <= max_steps <= 10**15):
        raise ConfigError(f"max_steps = {short(max_steps)} is not admissible (admissible: an "
                          "integer in 1..1e15)")
    for key, value in (("dt", dt), ("fs_out", fs_out)):
        check_real(value, f"{key}", optional=True, error=ConfigError)
    setup = prepare_run(model, conditions, gyroscopic)
    system = setup.system
    n, nm = model.n_dof, model.n_mesh
    run_duration = setup.duration if duration is None else float(duration)
    if run_duration is None or not (run_duration > 0 and math.isfinite(run_duration)):
        raise ConfigError(f"duration = {run_duration!r} s is not admissible (admissible: > 0, "
                          "finite; the conditions define none)")
    k_max = stiffest_matrix(model, setup.torque_sign)
    if setup.drive == "speed":
        k_max = with_coupling(k_max, setup.mass, setup.rigid, int(system.ipar[kn.IP_INPUT]),
                              setup.coupling)
    f_nat = undamped_frequencies(setup.mass, k_max)
    f_nat_max = float(f_nat.max()) if f_nat.size else 0.0
    f_rpm = model.mesh_frequencies_per_rpm
    f_mesh_max = float(np.nanmax(f_rpm, initial=0.0)) * setup.speed_max / RAD_S_PER_RPM
    step = choose_step(f_nat_max, f_mesh_max, dt=dt, fs_out=fs_out,
                       speed_max_rpm=setup.speed_max / RAD_S_PER_RPM)
    nsig = kn.n_signals(n, nm)
    check_run_size(step, run_duration, n_dof=n, n_mesh=nm, n_signals=nsig,
                   n_stored=nsig + 2 * nm + len(model.bearing_names) + 4,
                   max_steps=int(max_steps), speed_max_rpm=setup.speed_max / RAD_S_PER_RPM,
                   dt_given=dt is not None, fs_out_given=fs_out is not None)
    qd0 = setup.rigid * setup.omega0
    law = setup.faults
    q0, acc0 = static_equilibrium(
        system,
        setup.mass,
        setup.rigid,
        qd0,
        rigid_acceleration=setup.alpha0,
        free_rigid=setup.free_rigid,
        mesh_names=model.mesh_names,
        flank_law=None if law is None else (
            lambda q, first: law.flank_law(model, q, system.backlash, first)),
    )
    delta0 = np.abs(system.mesh_vectors @ q0)
    if system.mesh_back_vectors is not None:  # the static deflection of the loaded line
        delta0 = np.maximum(delta0, np.abs(system.mesh_back_vectors @ q0))
    system.deflection_limit[:] = np.maximum(
        1e3 * (delta0 + np.abs(system.backlash) / 2), 1e-3
    )
    return _Variant(model, conditions, setup, step, run_duration, acc0,
                    np.concatenate([q0, qd0]))


def _batch_difference(a: _Variant, b: _Variant) -> str | None:
    """What keeps two prepared variants out of one batch (beyond the kernel topology)."""
    sa, sb = a.step, b.step
    if (sa.dt, sa.fs_out, sa.decimation) != (sb.dt, sb.fs_out, sb.decimation):
        return (f"time grid (internal step dt = {sb.dt:.9g} s vs {sa.dt:.9g} s, fs_out = "
                f"{sb.fs_out:.9g} Hz vs {sa.fs_out:.9g} Hz): the default step follows the "
                "highest natural frequency, so give dt (and fs_out) explicitly")
    if a.duration != b.duration:
        return f"duration ({b.duration!r} s vs {a.duration!r} s)"
    if a.setup.drive != b.setup.drive:
        return f"drive ({b.setup.drive} vs {a.setup.drive})"
    if a.model.n_dof != b.model.n_dof or a.model.n_mesh != b.model.n_mesh:
        return (f"number of coordinates / meshes ({b.model.n_dof} / {b.model.n_mesh} vs "
                f"{a.model.n_dof} / {a.model.n_mesh})")
    return None


@_one_blas_thread
def simulate_batch(
    models: Sequence[AssembledModel],
    conditions: Conditions | Sequence[Conditions],
    *,
    dt: float | None = None,
    fs_out: float | None = None,
    duration: float | None = None,
    gyroscopic: bool = False,
    config: Mapping | str | Sequence[Mapping | str | None] | None = None,
    max_steps: int = DEFAULT_MAX_STEPS,
    errors: str = "raise",
) -> list[RunUpResult | SimulationError]:
    """:func:`simulate` of several variants of one gear set, eight at a time on SIMD lanes.

    The variants run through the batched kernel (:mod:`gearvib.kernels_batch`), up to
    :data:`gearvib.kernels_batch.WIDTH` (8) at a time; each result is bit-identical to
    :func:`simulate` of its variant (the same ``to_dataset()``, byte for byte), at about a
    third of the time per variant for the paper's sets (``docs/performance-kernel.md``).

    Batchable are variants of one topology on one time grid: they may differ in values of
    the gear set (mesh damping, mesh and bearing stiffness, bearing damping, masses,
    backlash, stiffness-table values) and of the load; they must share the coordinates, the
    meshes and the sparsity patterns of the operators, the number of stiffness jumps per mesh
    and table length, the drive mode and its speed / torque table, the duration and the
    internal step and output rate. The default step follows the highest natural frequency, so
    stiffness variants usually need an explicit ``dt`` (and ``fs_out``). Models with local
    tooth faults or manufacturing errors are not batched (refused); virtual sensors are
    supported (they are computed from the stored forces after the run).

    Parameters
    ----------
    models : sequence of AssembledModel
        The variants (at least one).
    conditions : conditions or sequence of conditions
        One for all variants or one per variant (as :func:`simulate`).
    dt, fs_out, duration, gyroscopic, max_steps
        As :func:`simulate`, the same for every variant.
    config : mapping, str or sequence of them, optional
        As :func:`simulate`; one for all variants or one per variant.
    errors : {"raise", "return"}
        A variant that blows up raises its :class:`SimulationError` (message prefixed with
        the variant's index) or, with ``"return"``, its error (with the message of its single
        run) takes its place in the returned list (the other variants are unaffected).

    Returns
    -------
    list of RunUpResult (or SimulationError with ``errors="return"``)
        One per variant, in order.

    Raises
    ------
    ValueError
        Variants that cannot share a batch (the message names the variant and what differs),
        a variant with faults, or a bad argument; the errors of :func:`simulate` for an
        inadmissible variant (prefixed with its index).
    """
    from gearvib import kernels_batch as kb  # only batches need it (start-up of a single run)
    models = (list(check_items(models, AssembledModel, "models"))
              if not isinstance(models, AssembledModel) else [models])
    if not models:
        raise ValueError("simulate_batch needs at least one model (models is empty)")
    if errors not in ("raise", "return"):
        raise ValueError(f"errors = {short(errors)} is not admissible (admissible: 'raise', "
                         "'return')")
    if not isinstance(gyroscopic, bool | np.bool_):
        raise TypeError(f"gyroscopic must be a bool; got {type(gyroscopic).__name__}")
    nv = len(models)
    conds = list(conditions) if isinstance(conditions, list | tuple) else [conditions] * nv
    # a list or tuple holds one configuration per model; anything else is one for all
    configs: list[Mapping | str | None] = (
        list(config) if isinstance(config, list | tuple)
        else [cast(Mapping | str | None, config)] * nv)
    for name, seq in (("conditions", conds), ("config", configs)):
        if len(seq) != nv:
            raise ValueError(f"{name} must be one value or one per model ({nv}), got {len(seq)}")
    for k, cfg in enumerate(configs):
        check_config(cfg, f"config[{k}]" if isinstance(config, list | tuple) else "config")
    variants = []
    for k, (model, cond) in enumerate(zip(models, conds, strict=True)):
        if not isinstance(model, AssembledModel):
            raise TypeError(f"models[{k}] is a {type(model).__name__}, not an AssembledModel")
        if model.faults:
            raise ValueError(f"models[{k}] has local tooth faults or manufacturing errors "
                             "(model.faults): such variants are not batched (their contact "
                             "law is not written on SIMD lanes); simulate() them one by one")
        try:
            variants.append(_prepare_variant(model, cond, dt, fs_out, duration, gyroscopic,
                                             max_steps))
        except (ValueError, SimulationError) as exc:
            try:
                named = type(exc)(f"variant {k}: {exc}")
            except TypeError:  # an exception class with another signature: as it is
                raise exc from None
            raise named from exc
        if k and (why := _batch_difference(variants[0], variants[k])) is not None:
            raise ValueError(f"variant {k} cannot share a batch with variant 0: its {why}. "
                             f"Batchable differences: {BATCHABLE}")
    outcomes: list = []
    for first in range(0, nv, kb.WIDTH):
        group = variants[first : first + kb.WIDTH]
        try:
            batch = kb.pack_batch([v.setup.system for v in group])
        except ValueError as exc:
            raise ValueError(f"{exc} (variants counted from {first}). Batchable differences: "
                             f"{BATCHABLE}") from exc
        t_group = _time.perf_counter()
        outs, changes, failed = _run_batch(group, batch, gyroscopic)
        per_variant = (_time.perf_counter() - t_group) / len(group)
        for b, v in enumerate(group):
            k = first + b
            if failed[b] is not None:
                if errors == "raise":
                    raise SimulationError(f"variant {k}: {failed[b]}")
                outcomes.append(SimulationError(failed[b]))  # the single run's message
                continue
            result = build_result(v.model, v.conditions, v.setup, v.step,
                                  decimation_filter(v.step.decimation), outs[b], changes[b],
                                  v.duration, gyroscopic, configs[k], None, per_variant)
            if v.model.sensors:
                result = add_sensor_signals(result, v.model)
            result.wall_time = per_variant
            outcomes.append(result)
    return outcomes


def batch_groups(
    models: Sequence[AssembledModel],
    conditions: Conditions | Sequence[Conditions],
    *,
    dt: float | None = None,
    fs_out: float | None = None,
    duration: float | None = None,
    gyroscopic: bool = False,
    max_steps: int = DEFAULT_MAX_STEPS,
) -> list[list[int]]:
    """Partition variants into groups :func:`simulate_batch` accepts.

    Greedy and in order: a variant joins the first group (of fewer than 8) whose first variant
    it can share a batch with (same time grid, duration, drive and kernel topology), else it
    starts a group. A variant that cannot be batched at all (faults, an invalid run) is a group
    of its own. Arguments as :func:`simulate_batch`.

    Returns
    -------
    list of list of int
        Indices into ``models``; every index once.
    """
    from gearvib import kernels_batch as kb  # only batches need it (start-up of a single run)
    models = list(check_items(models, object, "models"))
    for key, value in (("dt", dt), ("fs_out", fs_out), ("duration", duration)):
        check_real(value, key, optional=True, low=0.0, low_open=True, error=ConfigError)
    if isinstance(max_steps, bool) or not isinstance(max_steps, int | np.integer) or not (
            1 <= max_steps <= 10**15):
        raise ConfigError(f"max_steps = {short(max_steps)} is not admissible (admissible: an "
                          "integer in 1..1e15)")
    if not isinstance(gyroscopic, bool | np.bool_):
        raise TypeError(f"gyroscopic must be a bool; got {type(gyroscopic).__name__}")
    nv = len(models)
    conds = list(conditions) if isinstance(conditions, list | tuple) else [conditions] * nv
    if len(conds) != nv:
        raise ValueError(f"conditions must be one value or one per model ({nv}), got "
                         f"{len(conds)}")
    groups: list[tuple[_Variant | None, list[int]]] = []
    for k, (model, cond) in enumerate(zip(models, conds, strict=True)):
        v = None
        if isinstance(model, AssembledModel) and not model.faults:
            try:
                v = _prepare_variant(model, cond, dt, fs_out, duration, gyroscopic, max_steps)
            except (ValueError, TypeError, SimulationError):
                v = None
        for first, members in groups:
            if v is None or first is None or len(members) >= kb.WIDTH:
                continue
            if _batch_difference(first, v) is not None:
                continue
            try:
                kb.pack_batch([first.setup.system, v.setup.system])
            except ValueError:
                continue
            members.append(k)
            break
        else:
            groups.append((v, [k]))
    return [members for _, members in groups]


def _run_batch(group: list[_Variant], batch, gyroscopic: bool) -> tuple[list, np.ndarray, list]:
    """The chunked loop of :func:`simulate` on the lanes of one batch."""
    from gearvib import kernels_batch as kb  # only batches need it (start-up of a single run)
    v0 = group[0]
    step = v0.step
    n, nm = v0.model.n_dof, v0.model.n_mesh
    nsig = kn.n_signals(n, nm)
    width = kb.WIDTH
    nb = len(group)
    taps = decimation_filter(step.decimation)
    half = (taps.size - 1) // 2
    dec = step.decimation
    n_out = math.floor(v0.duration * step.fs_out + 1e-9) + 1
    last_sample = (n_out - 1) * dec + half
    chunk = max(round(CHUNK_DURATION / step.dt), 2 * half + dec + 1)
    buf = np.empty((width, chunk + 2 * half + dec + 1, nsig))
    outs = [np.empty((n_out, nsig)) for _ in range(nb)]
    y = np.empty((2 * n, width))
    for b in range(width):
        y[:, b] = group[b if b < nb else 0].y
    work = kb.batch_work(n, nm)
    status = np.zeros((width, 2), dtype=np.int64)
    flank_state = np.full((width, nm), -1, dtype=np.int64)
    changes = np.zeros((width, nm), dtype=np.int64)
    sys_tuple = batch.astuple()
    failed: list = [None] * nb

    def reference(v: _Variant, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if v.setup.drive == "speed":
            ang, spd = np.empty(times.size), np.empty(times.size)
            kn.speed_profile(v.setup.system.speed_table, times, ang, spd)
            return ang, spd
        return v.setup.omega0 * times + 0.5 * v.acc0 * times**2, v.setup.omega0 + v.acc0 * times

    b0, fill, next_out, g = -half, half, 0, 0
    while g <= last_sample:
        m = min(chunk, last_sample + 1 - g)
        for off in range(0, m, MAX_KERNEL_STEPS):
            kb.integrate_chunk_batch(y, g + off, min(MAX_KERNEL_STEPS, m - off), step.dt,
                                     sys_tuple, buf, fill + off, flank_state, changes,
                                     (n_out - 1) * dec, work, status)
            if np.all(status[:nb, 0] != kn.STATUS_OK):
                break
        for b, v in enumerate(group):
            if status[b, 0] != kn.STATUS_OK and failed[b] is None:
                failed[b] = _blow_up_message(status[b, 1] * step.dt, int(status[b, 0]),
                                             v.setup, step, gyroscopic)
        if all(f is not None for f in failed):
            break
        times = (g + np.arange(m)) * step.dt
        for b, v in enumerate(group):
            ang, spd = reference(v, times)
            kn.shift_rigid(buf[b], fill, ang, spd, v.setup.rigid, False)
            if g == 0:
                buf[b, :half] = 2.0 * buf[b, half] - buf[b, 2 * half : half : -1]
        fill += m
        g += m
        k_last = min(n_out - 1, (b0 + fill - 1 - half) // dec)
        if k_last >= next_out:
            for b in range(nb):
                if failed[b] is None:
                    kn.fir_decimate(buf[b], b0, taps, dec, next_out, k_last - next_out + 1,
                                    outs[b], next_out)
            next_out = k_last + 1
        keep = next_out * dec - half - b0
        if keep > 0:
            buf[:, : fill - keep] = buf[:, keep:fill]
            fill -= keep
            b0 += keep
    times = np.arange(n_out) * (dec * step.dt)
    for b, v in enumerate(group):
        if failed[b] is None:
            ang, spd = reference(v, times)
            kn.shift_rigid(outs[b], 0, ang, spd, v.setup.rigid, True)
    return outs, changes[:nb], failed
