"""Run a sweep: every case on an executor, one run file each, resumable; then ``sweep.nc``.

Output folder::

    DIR/runs/<hash>.nc     one run per case, named by the first 16 hex digits of its hash
    DIR/sweep.nc           the combined summary (gearvib.sweep.combine)
    DIR/sweep.html         the sweep report, with DIR/figures/*.png (gearvib.sweep.report)

Run files are content-addressed: a case whose gear set and run settings did not change is found
again (and not simulated) when the sweep is run a second time, also after an interruption, after
values were added to a parameter, or after the ``[summary]`` table changed (the summaries are
computed again from the run files, which is cheap). One sweep at a time may use a folder.
"""

from __future__ import annotations

import contextlib
import json
import logging
import math
import os
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path

import xarray as xr

from analysis.checks import require_instance
from gearvib import tempfiles
from gearvib.checks import check_count, short
from gearvib.config import ConfigError
from gearvib.execution import (
    MAX_WORKERS,
    SerialExecutor,
    default_workers,
    local_executor,
    stop_workers,
    worker_environment,
)
from gearvib.io import write_netcdf
from gearvib.report.runner import check_output_dir
from gearvib.simulate import SimulationError, simulate, simulate_batch
from gearvib.sweep.case import (
    CaseOutcome,
    CaseTask,
    build_case,
    conditions_for,
    run_case,
    run_case_group,
)
from gearvib.sweep.combine import combine_summaries
from gearvib.sweep.description import Sweep

__all__ = ["BATCH_WIDTH", "MIN_AUTO_BATCH", "SweepResult", "batch_units", "run_file_name",
           "run_sweep"]

BATCH_WIDTH = 8
"""Cases per batch (the SIMD lanes of :mod:`gearvib.kernels_batch`)."""
MIN_AUTO_BATCH = 3
"""Smallest batch formed automatically. A batch of k variants (``simulate_batch``, 0.5 s
run-ups of ``paper-case1`` / ``paper-case1-elastic``, CPU time, medians of 5) costs about
1.8 / 1.6 single runs for k = 2, 2.3 / 2.2 for k = 3, 2.5 / 2.4 for k = 4 and 4.2 / 3.6 for
k = 8: a batch of 2 gains only x1.1-1.2 (within the spread), one of 3 x1.3-1.4."""

log = logging.getLogger("gearvib.sweep")

CaseRunner = Callable[[CaseTask], CaseOutcome]


@dataclass(frozen=True)
class SweepResult:
    """Outcome of :func:`run_sweep`.

    Attributes
    ----------
    dataset : xarray.Dataset
        The combined summary (also written to ``path``).
    path : Path
        ``DIR/sweep.nc``.
    report : Path or None
        ``DIR/sweep.html`` (None without a report).
    simulated, reused, failed : tuple of int
        Case indices simulated now, found finished in their run files, and failed.
    wall_time_s : float
        Wall time of the call [s].
    case_time_s : tuple of float
        Wall time of every case in its worker [s].
    """

    dataset: xr.Dataset
    path: Path
    report: Path | None
    simulated: tuple[int, ...]
    reused: tuple[int, ...]
    failed: tuple[int, ...]
    wall_time_s: float
    case_time_s: tuple[float, ...] = field(default=(), repr=False)


def run_file_name(sha256: str) -> str:
    """Run file of a case, relative to the sweep folder."""
    return f"runs/{sha256[:16]}.nc"


def _warm_up(sweep_case, batched: bool) -> None:
    """Compile (or load) the kernels once in this process before the fan-out."""
    try:
        model = build_case(sweep_case)
        cond = conditions_for(sweep_case.run, model)
        kw = dict(dt=sweep_case.run.get("dt"), fs_out=sweep_case.run.get("fs_out"),
                  duration=min(float(sweep_case.run["duration"]), 1e-3))
        simulate(model, cond, progress=False, **kw)
        if batched:
            simulate_batch([model, model], cond, **kw)
    except (ConfigError, SimulationError, ValueError):
        pass  # this case fails in its worker too, with its message; the workers compile


def batch_units(tasks: list[CaseTask], workers: int, batch: bool | None
                ) -> list[CaseTask | list[CaseTask]]:
    """Split the tasks of a sweep into single cases and batches for the workers.

    Cases with the same run settings and gear-set folder are candidates for one batch (the
    gear sets may still differ in what the batched kernel cannot share; their batch then runs
    case by case: :func:`gearvib.sweep.case.run_case_group`). Each set of candidates is split
    evenly into batches of at most :data:`BATCH_WIDTH`; automatically (``batch=None``) into at
    least ``workers`` batches, and batches smaller than :data:`MIN_AUTO_BATCH` run case by case
    (so 4 cases on 2 workers run as 4 single runs, two in parallel, and 6 cases as two batches
    of 3).
    ``batch=False``: every case alone; ``batch=True``: batches of 2 to 8 whatever their number.
    """
    if batch is False:
        return list(tasks)
    buckets: dict[str, list[CaseTask]] = {}
    for t in tasks:
        key = json.dumps([t.case.run, t.case.base_dir], sort_keys=True, default=str)
        buckets.setdefault(key, []).append(t)
    units: list = []
    smallest = 2 if batch else MIN_AUTO_BATCH
    for group in buckets.values():
        n = len(group)
        n_batches = math.ceil(n / BATCH_WIDTH)
        if batch is None:  # one batch per worker at least: else parallel single runs win
            n_batches = max(n_batches, min(workers, n))
        size = math.ceil(n / max(n_batches, 1))
        for first in range(0, n, size):
            part = group[first : first + size]
            if len(part) >= smallest:
                units.append(part)
            else:
                units.extend(part)
    return units


def _remove_stale_temporaries(runs: Path) -> None:
    for p in runs.glob(".*.nc.*.tmp"):  # left by a killed worker (atomic_write's temporaries)
        tempfiles.remove_temporary(p)


def run_sweep(sweep: Sweep, out_dir: str | os.PathLike, *, workers: int | None = None,
              executor: Executor | None = None, start_method: str | None = None,
              runner: CaseRunner = run_case,
              progress: bool = True, report: bool = True,
              on_case_done: Callable[[CaseOutcome], None] | None = None,
              batch: bool | None = None, run_files: bool = True) -> SweepResult:
    """Run every case of a sweep and write ``sweep.nc`` (and the report).

    Parameters
    ----------
    sweep : Sweep
        The sweep (:func:`gearvib.sweep.load_sweep`).
    out_dir : path-like
        Output folder (created; checked for writability before any work).
    workers : int, optional
        Local worker processes (default: the CPUs available); 1 runs in this process. Ignored
        when ``executor`` is given.
    start_method : str, optional
        Start method of the local workers (see :func:`gearvib.execution.local_executor`).
    executor : concurrent.futures.Executor, optional
        Where the cases run, e.g. ``dask.distributed.Client(address).get_executor()``. Its
        workers must reach ``out_dir`` under the same path. Not shut down here.
    runner : callable
        ``runner(CaseTask) -> CaseOutcome`` (default :func:`gearvib.sweep.case.run_case`).
    progress : bool
        Show a progress bar (tqdm; hidden on non-terminal output).
    report : bool
        Write the sweep report (``sweep.html`` and ``figures/``).
    on_case_done : callable, optional
        Called with each outcome as it arrives (in completion order).
    batch : bool, optional
        Simulate cases with the same run settings together on the batched kernel (up to 8 per
        batch, :func:`batch_units`; run files and ``sweep.nc`` bit-identical to case-by-case
        runs). Default (None): automatic, batches of at least :data:`MIN_AUTO_BATCH` cases
        while every worker gets one; False: case by case. Only with the default ``runner``.
    run_files : bool
        Write every simulated case's run file ``DIR/runs/<hash>.nc`` (default). False keeps the
        runs in memory only for their summaries: ``sweep.nc`` holds the same summaries, its
        ``run_file`` coordinate is ``""`` for every case, and nothing is left to resume from
        (run files of earlier sweeps in the folder are still reused). Writing the compressed
        run file is most of a batched case's time.

    Returns
    -------
    SweepResult

    Raises
    ------
    gearvib.config.ConfigError
        The sweep description is invalid (before anything is written).
    PermissionError, ValueError
        The output folder is not usable.
    KeyboardInterrupt
        Pending cases are cancelled; finished run files stay and are reused by the next call.
    """
    t0 = time.perf_counter()
    if not isinstance(run_files, bool):
        raise TypeError(f"run_files must be True or False, got {short(run_files)}")
    require_instance(sweep, Sweep, "sweep")
    if executor is not None:
        require_instance(executor, Executor, "executor")
    if not callable(runner):
        raise TypeError(f"runner must be callable; got {type(runner).__name__}")
    if on_case_done is not None and not callable(on_case_done):
        raise TypeError(f"on_case_done must be callable; got {type(on_case_done).__name__}")
    for key, flag in (("progress", progress), ("report", report)):
        if not isinstance(flag, bool):
            raise TypeError(f"{key} must be True or False, got {short(flag)}")
    if batch is not None and not isinstance(batch, bool):
        raise TypeError(f"batch must be True, False or None, got {short(batch)}")
    if workers is not None:
        check_count(workers, "workers", low=1, high=MAX_WORKERS)
    cases = sweep.cases()
    out = check_output_dir(out_dir)
    runs = out / "runs"
    runs.mkdir(parents=True, exist_ok=True)  # the folder is checked, not created
    _remove_stale_temporaries(runs)
    file_names = [run_file_name(c.sha256) for c in cases]
    tasks = [CaseTask(c, str((out / f).resolve()), sweep.summary, write_run=run_files)
             for c, f in zip(cases, file_names, strict=True)]
    own = executor is None
    n_workers = default_workers() if workers is None else workers
    if runner is not run_case:
        batch = False
    units = batch_units(tasks, n_workers, batch)
    batched = any(isinstance(u, list) for u in units)
    outcomes: dict[int, CaseOutcome] = {}
    stopped = False
    with contextlib.ExitStack() as stack:
        if own:
            stack.enter_context(worker_environment())
            executor = local_executor(min(n_workers, max(1, len(units))),
                                      start_method=start_method)
        assert executor is not None  # given or made just above
        parallel = not isinstance(executor, SerialExecutor)
        if parallel:  # compile once here; the workers load the kernels from numba's cache
            _warm_up(cases[0], batched)
        bar = None
        pending: set[Future] = set()
        try:
            if not parallel:
                bar = _bar(stack, progress, len(tasks))
                for unit in units:
                    _collect(_submit(executor, runner, unit), outcomes, bar, on_case_done)
            else:  # submit first: a forked pool starts before the progress bar's thread
                pending = {_submit(executor, runner, unit) for unit in units}
                bar = _bar(stack, progress, len(tasks))
                while pending:
                    done, pending = wait(pending, return_when=FIRST_COMPLETED)
                    for fut in done:
                        _collect(fut, outcomes, bar, on_case_done)
        except BaseException:
            for fut in pending:
                fut.cancel()
            if own and isinstance(executor, ProcessPoolExecutor):
                # an interrupt must not wait for the running cases: end the workers, remove
                # the temporary files of the run files they were writing
                stop_workers(executor)
                stopped = True
                tempfiles.remove_stale(runs)
            raise
        finally:
            if own and executor is not None and not stopped:
                executor.shutdown(wait=True)
    ordered = [outcomes[c.index] for c in cases]
    files = [f if o.summary is not None and run_files else ""
             for f, o in zip(file_names, ordered, strict=True)]
    ds = combine_summaries(sweep, cases, ordered, files)
    path = write_netcdf(ds, out / "sweep.nc")
    report_path = None
    if report:
        from gearvib.sweep.report import build_sweep_report

        report_path = build_sweep_report(ds, out)
    by = {s: tuple(o.index for o in ordered if o.status == s)
          for s in ("simulated", "reused", "failed")}
    for o in ordered:
        if o.status == "failed":
            log.warning("case %d failed: %s", o.index, o.message)
    return SweepResult(dataset=ds, path=path, report=report_path, simulated=by["simulated"],
                       reused=by["reused"], failed=by["failed"],
                       wall_time_s=time.perf_counter() - t0,
                       case_time_s=tuple(o.wall_time for o in ordered))


def _bar(stack: contextlib.ExitStack, progress: bool, total: int):
    if not progress:
        return None
    from tqdm.auto import tqdm

    return stack.enter_context(tqdm(total=total, unit="case", desc="gearvib sweep",
                                    disable=None))


def _submit(executor: Executor, runner: CaseRunner, unit) -> Future:
    if isinstance(unit, list):
        return executor.submit(run_case_group, unit)
    return executor.submit(runner, unit)


def _collect(fut: Future, outcomes: dict[int, CaseOutcome], bar,
             on_case_done: Callable[[CaseOutcome], None] | None) -> None:
    result = fut.result()
    for outcome in result if isinstance(result, list) else [result]:
        outcomes[outcome.index] = outcome
        if bar is not None:
            bar.update(1)
        if on_case_done is not None:
            on_case_done(outcome)
