"""Running one case of a sweep: the function every worker executes.

:func:`run_case` maps a :class:`CaseTask` (one case description, where its run file goes and
what to summarise) to a :class:`CaseOutcome` (the case's summary Dataset). It is a plain,
picklable top-level function, so any :class:`concurrent.futures.Executor` can run it: the
in-process :class:`~gearvib.execution.SerialExecutor`, a local process pool or a Dask
cluster. A different runner with the same signature can be handed to
:func:`gearvib.sweep.run_sweep` instead. :func:`run_case_group` runs several cases with the same
run settings together on the batched kernel (:func:`gearvib.simulate.simulate_batch`), with the
run files and summaries of :func:`run_case`, bit for bit.

Resuming: a run file is *finished* when it opens as netCDF, was written by gearvib and carries
the case's hash in its ``sweep_case_sha256`` attribute (:attr:`SweepCase.sha256`: the gear-set
description, run settings, base directory and gearvib version). Run files are written
atomically, so a file with the final name is complete; anything else (missing, unreadable, other
hash) is simulated again and replaced.
"""

from __future__ import annotations

import contextlib
import dataclasses
import multiprocessing
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import xarray as xr

from analysis.checks import require_instance
from analysis.fft import set_workers
from analysis.readers.ncimage import open_image
from analysis.threads import one_blas_thread
from gearvib.assembly import assemble
from gearvib.checks import short
from gearvib.config import ConfigError, gearset_from_dict
from gearvib.io import read_run, write_netcdf
from gearvib.model import AssembledModel
from gearvib.paths import is_file
from gearvib.simulate import (
    Conditions,
    SimulationError,
    batch_groups,
    simulate,
    simulate_batch,
)
from gearvib.simulation.settings import conditions_from_settings
from gearvib.sweep.description import SweepCase
from gearvib.sweep.summary import SummarySettings, summarise_run

__all__ = ["CaseOutcome", "CaseTask", "build_case", "conditions_for", "finished_run",
           "run_case", "run_case_group"]


@dataclass(frozen=True)
class CaseTask:
    """Everything a worker needs for one case.

    Attributes
    ----------
    case : SweepCase
        The case.
    run_path : str
        Where its run file is (or goes); absolute, on a file system the worker can reach.
    summary : SummarySettings
        What to summarise.
    write_run : bool
        Write the run file of a simulated case (default). False keeps the run in memory
        only, for its summary (a finished run file found at ``run_path`` is still reused).
    """

    case: SweepCase
    run_path: str
    summary: SummarySettings
    write_run: bool = True

    def __post_init__(self) -> None:
        for key, cls in (("case", SweepCase), ("summary", SummarySettings)):
            if not isinstance(getattr(self, key), cls):
                raise TypeError(f"{key} must be a {cls.__name__}; got "
                                f"{type(getattr(self, key)).__name__}")
        if not isinstance(self.run_path, str) or not self.run_path:
            raise TypeError(f"run_path must be a file name (str); got {short(self.run_path)}")
        if not isinstance(self.write_run, bool):
            raise TypeError(f"write_run must be a bool; got {type(self.write_run).__name__}")


@dataclass(frozen=True)
class CaseOutcome:
    """What a worker returns for one case.

    Attributes
    ----------
    index : int
        Case index.
    status : str
        ``"simulated"``, ``"reused"`` (a finished run file was found) or ``"failed"``.
    message : str
        Why a case failed (one line), else ``""``.
    summary : xarray.Dataset or None
        The case's summary (:func:`gearvib.sweep.summary.summarise_run`); None if failed.
    wall_time : float
        Wall time of the case in the worker [s] (not stored in the sweep Dataset).
    """

    index: int
    status: str
    message: str
    summary: xr.Dataset | None
    wall_time: float


def build_case(case: SweepCase) -> AssembledModel:
    """Assemble the gear set of a case.

    Raises
    ------
    ConfigError
        The description is invalid for this combination of values.
    """
    base = Path(case.base_dir) if case.base_dir else None
    try:
        return assemble(gearset_from_dict(case.description, base=base))
    except ValueError as exc:
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError(str(exc)) from None


def conditions_for(run: dict, model: AssembledModel) -> Conditions:
    """The operating conditions of a case's run settings (speed ramp, torque or motor drive;
    :func:`gearvib.simulation.settings.conditions_from_settings`). ``model`` is not used
    today; it is part of the signature so that conditions may depend on the gear set."""
    del model
    return conditions_from_settings(run)


def finished_run(path: str | Path, sha256: str) -> xr.Dataset | None:
    """The run in ``path`` if it is the finished run of the case with hash ``sha256``."""
    p = Path(path)
    if not is_file(p):
        return None
    try:
        with open_image(p) as nc:  # not the file itself: see analysis.readers.ncimage
            if getattr(nc, "sweep_case_sha256", None) != sha256:
                return None
        return read_run(p)
    except (OSError, ValueError, RuntimeError, KeyError):  # ReaderError is a ValueError
        return None


def _plain_file_locks() -> contextlib.AbstractContextManager:
    """Inside a Dask worker, let xarray lock the run file with a process lock.

    xarray asks dask which scheduler is active and, in a worker, would take a cluster-wide
    ``distributed.Lock`` for every variable it writes (a round trip to the scheduler each,
    about 1.5 s per run file). The run files are private to their case, so a local lock is
    right; dask's synchronous scheduler gives xarray exactly that.
    """
    dask = sys.modules.get("dask")
    if dask is None or not hasattr(dask, "config"):
        return contextlib.nullcontext()
    return dask.config.set(scheduler="synchronous")


_worker_ready = False
_interrupted = False  # a worker process got Ctrl-C: skip the calls still queued for it


def _prepare_worker() -> None:
    """Once per process: one FFT thread (BLAS: :func:`run_case`; numba: no parallel loops)."""
    global _worker_ready
    if not _worker_ready:
        set_workers(1)
        _worker_ready = True


def _in_worker(fn: Callable[[Any], Any], arg: Any) -> Any:
    """``fn(arg)`` as a worker runs a case or a group of cases: refused once the process got
    Ctrl-C (the calls still queued for it are skipped), one BLAS/OpenMP thread during the call
    whatever the process (a forked worker keeps the thread pools its parent loaded; the
    caller's own setting is restored after)."""
    global _interrupted
    if _interrupted:
        raise KeyboardInterrupt
    _prepare_worker()
    try:
        with one_blas_thread():
            return fn(arg)
    except KeyboardInterrupt:
        if multiprocessing.parent_process() is not None:  # a pool worker, not the caller
            _interrupted = True
        raise


def run_case(task: CaseTask) -> CaseOutcome:
    """Simulate (or reuse) one case, write its run file (unless ``task.write_run`` is False)
    and summarise it.

    Parameters
    ----------
    task : CaseTask

    Returns
    -------
    CaseOutcome
        ``status = "failed"`` with the message when the description is invalid for this
        combination of values, the simulation blows up or the summary is impossible (e.g. an
        empty window); other exceptions propagate.
    """
    require_instance(task, CaseTask, "task")
    return _in_worker(_run, task)


def run_case_group(tasks: list[CaseTask]) -> list[CaseOutcome]:
    """:func:`run_case` of several cases, simulated together on the batched kernel.

    The cases that are not finished yet go through :func:`gearvib.simulate.simulate_batch`
    (up to 8 on SIMD lanes); their run files and summaries are those :func:`run_case` writes,
    bit for bit. When the cases cannot share a batch (a different topology or time grid,
    faults; :func:`~gearvib.simulate.simulate_batch` refuses) or one of them is invalid, every
    case runs alone through :func:`run_case`'s own path, so the outcomes are the same either
    way. Cases of one call that cannot all share a batch are split into those that can
    (:func:`~gearvib.simulate.batch_groups`, e.g. by default time grid); a case that blows up in
    the batch fails with its single run's message.

    Parameters
    ----------
    tasks : list of CaseTask
        Cases with the same run settings (the caller groups them).

    Returns
    -------
    list of CaseOutcome
        In the order of ``tasks``.
    """
    return _in_worker(_run_group, list(tasks))


def _case_config(case: SweepCase) -> dict:
    return {"gearset": case.description, "gearset_dir": case.base_dir, "run": case.run}


def _run_group(tasks: list[CaseTask]) -> list[CaseOutcome]:
    outcomes: dict[int, CaseOutcome] = {}
    pending = []
    for k, task in enumerate(tasks):
        try:
            model = build_case(task.case)
            conditions = conditions_for(task.case.run, model)
            finished = finished_run(task.run_path, task.case.sha256) is not None
        except (ConfigError, SimulationError, ValueError):
            finished = True  # fails (or is reused) in its own path, with its own message
        if finished:
            outcomes[k] = _run(task)
        else:
            pending.append((k, task, model, conditions))
    if not pending:
        return [outcomes[k] for k in range(len(tasks))]
    run = pending[0][1].case.run
    kw: dict[str, Any] = dict(dt=run.get("dt"), fs_out=run.get("fs_out"),
                              gyroscopic=bool(run.get("gyroscopic")))
    parts = [list(range(len(pending)))]  # first try all together (the common case) ...
    for part in parts:
        members = [pending[j] for j in part]
        results = None
        if len(members) > 1:
            t0 = time.perf_counter()
            try:
                results = simulate_batch(
                    [p[2] for p in members], [p[3] for p in members],
                    config=[_case_config(p[1].case) for p in members], errors="return", **kw)
            except (ConfigError, SimulationError, ValueError):
                if len(parts) == 1:  # ... refused: the groups that can share a batch
                    try:  # (e.g. the same default time grid) are appended, then run
                        parts.extend(batch_groups([p[2] for p in pending],
                                                  [p[3] for p in pending], **kw))
                    except (ConfigError, SimulationError, ValueError):
                        parts.extend([j] for j in range(len(pending)))
                    continue
                results = None  # not batchable after all: every case alone
            share = (time.perf_counter() - t0) / len(members)
        if results is None:
            for k, task, _, _ in members:
                outcomes[k] = _run(task)
            continue
        for (k, task, model, conditions), res in zip(members, results, strict=True):
            t1 = time.perf_counter()
            outcome = _finish(task, model, conditions, res)
            outcomes[k] = dataclasses.replace(
                outcome, wall_time=share + time.perf_counter() - t1)
    return [outcomes[k] for k in range(len(tasks))]


def _failed(case: SweepCase, exc: Exception, t0: float) -> CaseOutcome:
    text = str(exc).strip().splitlines()
    return CaseOutcome(case.index, "failed", text[0] if text else type(exc).__name__, None,
                       time.perf_counter() - t0)


def _finish(task: CaseTask, model: AssembledModel, conditions: Conditions, res) -> CaseOutcome:
    """Write the run file of a batched case and summarise it (as :func:`_run` does)."""
    t0 = time.perf_counter()
    case = task.case
    if isinstance(res, Exception):
        return _failed(case, res, t0)
    try:
        ds = _write_run(task, res)
        summary = summarise_run(ds, model, conditions, task.summary,
                                gyroscopic=bool(case.run.get("gyroscopic")))
    except (ConfigError, SimulationError, ValueError) as exc:
        return _failed(case, exc, t0)
    return CaseOutcome(case.index, "simulated", "", summary, time.perf_counter() - t0)


def _write_run(task: CaseTask, res) -> xr.Dataset:
    """The run of a simulated case (its Dataset, marked with the case's hash), written to its
    run file unless the task says not to."""
    ds = res.to_dataset()
    ds.attrs["sweep_case_sha256"] = task.case.sha256
    if not task.write_run:
        return ds
    with _plain_file_locks():
        write_netcdf(ds, task.run_path)
    return ds


def _run(task: CaseTask) -> CaseOutcome:
    t0 = time.perf_counter()
    case = task.case
    try:
        model = build_case(case)
        conditions = conditions_for(case.run, model)
        ds = finished_run(task.run_path, case.sha256)
        status = "reused"
        if ds is None:
            status = "simulated"
            res = simulate(model, conditions, dt=case.run.get("dt"), fs_out=case.run.get("fs_out"),
                           gyroscopic=bool(case.run.get("gyroscopic")), progress=False,
                           config=_case_config(case))
            ds = _write_run(task, res)
        summary = summarise_run(ds, model, conditions, task.summary,
                                gyroscopic=bool(case.run.get("gyroscopic")))
    except (ConfigError, SimulationError, ValueError) as exc:
        return _failed(case, exc, t0)
    return CaseOutcome(case.index, status, "", summary, time.perf_counter() - t0)
