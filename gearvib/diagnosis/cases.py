"""The sweep case of a diagnosis: simulate (or reuse) one candidate and order-track it.

:func:`profile_case` has the signature of :func:`gearvib.sweep.case.run_case` (with its
settings bound by :func:`functools.partial`), so :func:`gearvib.sweep.run_sweep` runs it on
its executors. Instead of the sweep's summary it returns the order profiles of the run's
virtual sensors (:func:`analysis.diagnosis.order_profile`): the analysis runs on the workers
too. The profiles go to a small file beside the run file (``<run>.profile-<key>.npz``, the
key a hash of the settings), the sweep's summary holds only a scalar: a candidate analysed
before with the same settings is neither simulated nor read again.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import dataclass

import numpy as np
import xarray as xr

from analysis.diagnosis import order_profile
from analysis.threads import one_blas_thread
from gearvib.config import ConfigError
from gearvib.io import write_netcdf
from gearvib.simulate import SimulationError, simulate
from gearvib.sweep.case import CaseOutcome, CaseTask, build_case, conditions_for, finished_run

__all__ = ["ProfileSettings", "profile_case", "profile_path", "profiles_of_run"]


@dataclass(frozen=True)
class ProfileSettings:
    """What a worker computes from a candidate's run.

    Attributes
    ----------
    sensors : tuple of str
        Names of the virtual sensors to order-track.
    carrier_per_input : float
        Speed of the reference shaft of the orders (the carrier of a planetary set,
        :func:`gearvib.diagnosis.engine.order_reference`) per unit input speed.
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

    @property
    def key(self) -> str:
        """Short hash of the settings."""
        text = json.dumps([list(self.sensors), repr(self.carrier_per_input),
                           repr(self.max_order), self.revolutions, repr(self.skip_s)])
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def profile_path(run_path: str, settings: ProfileSettings) -> str:
    """The profile file of a run file."""
    return f"{run_path}.profile-{settings.key}.npz"


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


def _save(path: str, arrays: dict[str, np.ndarray]) -> None:
    tmp = f"{path}.{os.getpid()}.tmp.npz"
    np.savez(tmp, **arrays)
    os.replace(tmp, path)


def profile_case(settings: ProfileSettings, task: CaseTask) -> CaseOutcome:
    """Simulate (or reuse) one candidate's run and return its order profiles as the summary.

    Failures (an invalid combination, a blow-up, a record too short for the profile) are
    returned as ``status = "failed"`` with the message, as by the sweep's own runner.
    """
    t0 = time.perf_counter()
    case = task.case
    try:
        with one_blas_thread():
            model = build_case(case)
            prof = profile_path(task.run_path, settings)
            if os.path.isfile(prof) and finished_run_exists(task.run_path):
                return CaseOutcome(case.index, "reused", "", _summary(),
                                   time.perf_counter() - t0)
            ds = finished_run(task.run_path, case.sha256)
            status = "reused"
            if ds is None:
                status = "simulated"
                res = simulate(model, conditions_for(case.run, model), dt=case.run.get("dt"),
                               fs_out=case.run.get("fs_out"), progress=False,
                               config={"gearset": case.description,
                                       "gearset_dir": case.base_dir, "run": case.run})
                ds = res.to_dataset()
                ds.attrs["sweep_case_sha256"] = case.sha256
                write_netcdf(ds, task.run_path)
            _save(prof, profiles_of_run(ds, settings))
            summary = _summary()
    except (ConfigError, SimulationError, ValueError) as exc:
        text = str(exc).strip().splitlines()
        return CaseOutcome(case.index, "failed", text[0] if text else type(exc).__name__, None,
                           time.perf_counter() - t0)
    return CaseOutcome(case.index, status, "", summary, time.perf_counter() - t0)


def finished_run_exists(run_path: str) -> bool:
    """A run file is there (its name is the case's hash; files are written atomically)."""
    return os.path.isfile(run_path)


def _summary() -> xr.Dataset:
    return xr.Dataset({"profiled": ((), 1, {"units": "1", "long_name":
                                             "order profiles written beside the run file"})})
