"""Synthetic measurements: a simulated gearbox seen through another transfer path, with noise.

Used by the tests and ``benchmarks/bench_diagnose.py`` to check the diagnosis on gearboxes
whose fault is known: the run's virtual sensor stands for the accelerometer (a path that is
*not* the one the diagnosis assumes), white noise for the measurement chain and the tacho
channel for the speed reference.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

__all__ = ["MEASURING_SENSOR", "record_from_run", "synthetic_measurement"]

MEASURING_SENSOR = {"name": "acc", "angle_deg": 200.0, "window": "exponential",
                    "width_deg": 50.0,
                    "housing_modes": [{"frequency_hz": 1500.0, "damping_ratio": 0.1,
                                       "gain": 1.0},
                                      {"frequency_hz": 4500.0, "damping_ratio": 0.05,
                                       "gain": 0.5}]}
"""A transfer path unlike the diagnosis's assumption (other angle, window, housing modes)."""


def synthetic_measurement(config: str, faults: Sequence[dict] = (), *,
                          speed_rpm: tuple[float, float] = (1500.0, 1500.0),
                          duration: float = 4.0, noise: float = 0.02, seed: int = 0,
                          sensor: dict | None = None, pulses_per_rev: int = 1,
                          fs: float = 10_000.0) -> xr.Dataset:
    """Simulate a gearbox and add measurement noise to its housing sensor.

    Parameters
    ----------
    config : str
        Preset name or gear-set TOML path.
    faults : sequence of dict
        ``[[fault]]`` tables.
    speed_rpm : (float, float)
        Input speed at the start and end of the record [min-1] (a ramp).
    duration : float
        Record length [s].
    noise : float
        Standard deviation of the added white noise relative to the signal's RMS.
    seed : int
        Seed of the noise.
    sensor : dict, optional
        The measuring ``[[sensor]]`` (default :data:`MEASURING_SENSOR`).
    pulses_per_rev : int
        Tacho pulses per input revolution.
    fs : float
        Sample rate [Hz].

    Returns
    -------
    xarray.Dataset
        The run with ``sensor_acceleration`` (noise added, ``comment`` says how much) and
        ``tacho``.
    """
    from gearvib.assembly import assemble
    from gearvib.config import gearset_from_dict, load_config
    from gearvib.simulate import simulate
    from gearvib.simulation.settings import conditions_from_settings, read_run_settings

    cfg, base = load_config(config)
    cfg = dict(cfg)
    cfg["fault"] = [dict(f) for f in faults]
    cfg["sensor"] = [dict(sensor or MEASURING_SENSOR),
                     {"type": "tacho", "name": "tacho", "pulses_per_rev": pulses_per_rev}]
    run = read_run_settings(cfg.get("simulation", {}),
                            {"speed_start_rpm": speed_rpm[0], "speed_end_rpm": speed_rpm[1],
                             "duration": duration, "fs_out": fs})
    model = assemble(gearset_from_dict(cfg, base=base))
    res = simulate(model, conditions_from_settings(run), dt=run["dt"], fs_out=run["fs_out"],
                   progress=False, config={"gearset": cfg, "run": run})
    ds = res.to_dataset()
    acc = ds["sensor_acceleration"]
    rng = np.random.default_rng(seed)
    sigma = noise * float(np.sqrt(np.mean(acc.values ** 2)))
    noisy = acc.values + sigma * rng.standard_normal(acc.shape)
    ds["sensor_acceleration"] = acc.copy(data=noisy)
    ds["sensor_acceleration"].attrs["comment"] = (f"white noise added, standard deviation "
                                                  f"{sigma:.4g} m s-2 ({noise:g} of the RMS)")
    return ds


def record_from_run(ds: xr.Dataset, sensor: str | None = None, *, name: str = "measured"):
    """A :class:`gearvib.diagnosis.Record` of a run's sensor, the speed from its tacho channel
    (:func:`analysis.measurement.load_measurement`)."""
    from analysis.measurement import load_measurement
    from gearvib.diagnosis.record import Record

    m = load_measurement(ds, channel=sensor, tacho="tacho")
    return Record.from_measurement(m, sensor, name=name)
