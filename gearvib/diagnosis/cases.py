"""The sweep case of a diagnosis: simulate one candidate and keep its order profiles.

:func:`profile_case` has the signature of :func:`gearvib.sweep.case.run_case` (with its
:class:`ProfileJob` bound by :func:`functools.partial`), so :func:`gearvib.sweep.run_sweep`
runs it on its executors. Instead of the sweep's summary it computes the order profiles of
the run's virtual sensors (:func:`analysis.diagnosis.order_profile`) in the worker and writes
them into the candidate library (:mod:`gearvib.diagnosis.library`); the run itself is written
to the sweep's run file only when asked (``keep_runs``). The sweep's summary holds a scalar.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from analysis.diagnosis import order_profile
from analysis.threads import one_blas_thread
from gearvib.config import ConfigError
from gearvib.diagnosis.library import load_entry, save_entry
from gearvib.io import write_netcdf
from gearvib.simulate import SimulationError, simulate
from gearvib.sweep.case import CaseOutcome, CaseTask, build_case, conditions_for, finished_run

__all__ = ["ProfileJob", "ProfileSettings", "profile_case", "profiles_of_run"]


@dataclass(frozen=True)
class ProfileSettings:
    """What a worker computes from a candidate's run.

    Attributes
    ----------
    sensors : tuple of str
        Names of the virtual sensors to order-track.
    carrier_per_input : float
        Speed of the reference shaft of the orders (the carrier of a planetary set,
        :func:`gearvib.diagnosis.lines.order_reference`) per unit input speed.
    max_order : float
        Highest order of the reference shaft.
    revolutions : int
        Reference-shaft revolutions per segment.
    skip_s : float
        Start-up transient left out [s].
    """

    sensors: tuple[str, ...]
    carrier_per_input: float
    max_order: float
    revolutions: int
    skip_s: float

    def describe(self) -> dict:
        """The settings as a JSON-able dict (part of a library entry's key)."""
        return {"sensors": list(self.sensors), "carrier_per_input": repr(self.carrier_per_input),
                "max_order": repr(self.max_order), "revolutions": int(self.revolutions),
                "skip_s": repr(self.skip_s)}


@dataclass(frozen=True)
class ProfileJob:
    """A diagnosis's sweep: profile settings, where the profiles go, whether runs are kept.

    Attributes
    ----------
    settings : ProfileSettings
    library : str
        Folder of the library entries (:func:`gearvib.diagnosis.library.library_folder`).
    entries : tuple of (str, str)
        ``(key, canonical JSON)`` of the library entry of every case, by case index.
    keep_runs : bool
        Also write every run to its sweep run file (and reuse run files found there).
    """

    settings: ProfileSettings
    library: str
    entries: tuple[tuple[str, str], ...]
    keep_runs: bool = False


def profiles_of_run(ds: xr.Dataset, s: ProfileSettings) -> dict[str, np.ndarray]:
    """Order profiles of a run's sensors: ``order``, ``amplitude`` (path, order),
    ``segments`` and the model's ``natural_frequency`` [Hz]."""
    rpm = np.abs(ds["input_speed"].values) * s.carrier_per_input
    t = ds["time"].values
    fs = (t.size - 1) / (t[-1] - t[0])
    profs = [order_profile(ds["sensor_acceleration"].sel(sensor=name).values, fs, rpm,
                           max_order=s.max_order, revolutions=s.revolutions, skip_s=s.skip_s,
                           units="m s-2", name=name) for name in s.sensors]
    n = min(p.order.size for p in profs)
    nf = ds["natural_frequency"].values if "natural_frequency" in ds else np.array([])
    return {"order": profs[0].order[:n], "amplitude": np.array([p.amplitude[:n] for p in profs]),
            "segments": np.array(profs[0].segments), "natural_frequency": np.asarray(nf, float)}


def profile_case(job: ProfileJob, task: CaseTask) -> CaseOutcome:
    """Simulate one candidate and write its order profiles into the library.

    An entry already in the library is kept (``status = "reused"``); with ``keep_runs`` a
    finished run file is reused instead of a simulation. Failures (an invalid combination, a
    blow-up, a run too short for the profile) are returned as ``status = "failed"`` with the
    message, as by the sweep's own runner.
    """
    t0 = time.perf_counter()
    case = task.case
    key, text = job.entries[case.index]
    folder = Path(job.library)
    try:
        with one_blas_thread():
            if load_entry(folder, key, text) is not None:
                return CaseOutcome(case.index, "reused", "", _summary(),
                                   time.perf_counter() - t0)
            model = build_case(case)
            ds = finished_run(task.run_path, case.sha256) if job.keep_runs else None
            status = "reused"
            if ds is None:
                status = "simulated"
                res = simulate(model, conditions_for(case.run, model), dt=case.run.get("dt"),
                               fs_out=case.run.get("fs_out"), progress=False,
                               config={"gearset": case.description,
                                       "gearset_dir": case.base_dir, "run": case.run})
                ds = res.to_dataset()
                if job.keep_runs:
                    ds.attrs["sweep_case_sha256"] = case.sha256
                    write_netcdf(ds, task.run_path)
            save_entry(folder, key, text, profiles_of_run(ds, job.settings))
    except (ConfigError, SimulationError, ValueError) as exc:
        text_ = str(exc).strip().splitlines()
        return CaseOutcome(case.index, "failed", text_[0] if text_ else type(exc).__name__,
                           None, time.perf_counter() - t0)
    return CaseOutcome(case.index, status, "", _summary(), time.perf_counter() - t0)


def _summary() -> xr.Dataset:
    return xr.Dataset({"profiled": ((), 1, {"units": "1", "long_name":
                                             "order profiles written to the candidate "
                                             "library"})})
