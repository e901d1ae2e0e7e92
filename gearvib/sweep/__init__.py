"""Parameter sweeps: many runs of one gear set with varied keys, summarised along ``case``.

==================  =========================================================================
``keys``            key paths into gear-set descriptions (``meshes.sun.damping_ratio``), units
``loadfactor``      static tooth force, dynamic factor K_v, DTE, contact loss of one run
``summary``         :func:`summarise_run`: the small Dataset kept per case
``description``     :class:`Sweep` (TOML or API), its :class:`Parameter` s and cases
``case``            :func:`run_case`: one case, the function every worker executes
``combine``         the combined Dataset ``sweep.nc``
``runner``          :func:`run_sweep`: resumable fan-out, run files, ``sweep.nc``
``report``          figures against the parameters and ``sweep.html``
==================  =========================================================================

Imports inside this package run down the table. The executors (in-process, a local process
pool, a Dask cluster) live in :mod:`gearvib.execution`, shared with the stability charts of
:mod:`gearvib.stability`. The user page is ``docs/sweeps.md``.
"""

from gearvib.execution import SerialExecutor, dask_executor, local_executor
from gearvib.sweep.case import CaseOutcome, CaseTask, run_case
from gearvib.sweep.description import Parameter, Sweep, SweepCase, load_sweep, sweep_from_dict
from gearvib.sweep.runner import SweepResult, run_sweep
from gearvib.sweep.summary import SummarySettings, summarise_run

__all__ = [
    "CaseOutcome",
    "CaseTask",
    "Parameter",
    "SerialExecutor",
    "SummarySettings",
    "Sweep",
    "SweepCase",
    "SweepResult",
    "dask_executor",
    "load_sweep",
    "local_executor",
    "run_case",
    "run_sweep",
    "summarise_run",
    "sweep_from_dict",
]
