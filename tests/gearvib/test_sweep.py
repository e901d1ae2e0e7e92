"""Sweeps: descriptions and their errors, identical results on every executor, resuming."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
import xarray as xr

from gearvib.config import ConfigError
from gearvib.sweep import (
    Parameter,
    SummarySettings,
    Sweep,
    load_sweep,
    run_sweep,
    summarise_run,
    sweep_from_dict,
)
from gearvib.sweep.case import build_case, conditions_for
from gearvib.sweep.summary import VIRTUAL_SENSOR_QUANTITY

# A tiny sweep: 2 x 2 cases of 20 ms runs of paper-case1 at 2700 -> 2900 min-1.
TINY = {
    "title": "tiny",
    "base": "paper-case1",
    "simulation": {"speed_start_rpm": 2700.0, "speed_end_rpm": 2900.0, "duration": 0.02},
    "parameter": [
        {"path": "meshes.sun.damping_ratio", "values": [0.005, 0.02]},
        {"path": "geometry.planet_angles_deg", "values": [[0, 120, 240], [0, 122.45, 244.90]],
         "labels": ["equal", "case2"]},
    ],
    "summary": {"orders": [1, 2], "order_resolution": 0.25, "floquet_speed_rpm": [2750, 2850],
                "floquet_points": 2},
}


def _sweep(**changes) -> Sweep:
    return sweep_from_dict({**TINY, **changes})


def _identical_files(a, b) -> None:
    with xr.open_dataset(a) as fa, xr.open_dataset(b) as fb:
        xr.testing.assert_identical(fa.load(), fb.load())
    assert a.read_bytes() == b.read_bytes()


# ------------------------------------------------------------------ descriptions and errors

def test_grid_cases_and_coordinates():
    s = _sweep()
    cases = s.cases()
    assert s.n_cases == len(cases) == 4
    # the last parameter varies fastest
    assert [c.values[0] for c in cases] == [0.005, 0.005, 0.02, 0.02]
    assert [c.labels[1] for c in cases] == ["equal", "case2", "equal", "case2"]
    assert cases[1].description["geometry"]["planet_angles_deg"] == [0, 122.45, 244.90]
    assert cases[2].description["meshes"]["sun"]["damping_ratio"] == 0.02
    assert cases[0].run["speed_end_rpm"] == 2900.0 and cases[0].run["input_torque"] == 60.0
    assert len({c.sha256 for c in cases}) == 4
    # the same description gives the same hashes; the hash ignores the summary settings
    again = _sweep(summary={}).cases()
    assert [c.sha256 for c in again] == [c.sha256 for c in cases]


def test_zip_random_and_list_index_paths():
    z = sweep_from_dict({"base": "paper-case1", "mode": "zip", "parameter": [
        {"path": "simulation.speed_start_rpm", "values": [100.0, 200.0]},
        {"path": "geometry.planet_angles_deg.1", "values": [117.55102040816327, 120.0]}]}
                        ).cases()
    assert [c.run["speed_start_rpm"] for c in z] == [100.0, 200.0]
    assert [c.description["geometry"]["planet_angles_deg"] for c in z] == \
        [[0.0, 117.55102040816327, 240.0], [0.0, 120.0, 240.0]]
    # planet angles must satisfy the assembly condition; the error says which are admissible
    with pytest.raises(ConfigError, match=r"nearest admissible 117\.551° or 120°"):
        sweep_from_dict({"base": "paper-case1", "parameter": [
            {"path": "geometry.planet_angles_deg.1", "values": [119.0]}]}).cases()
    spec = {"base": "paper-case1", "mode": "random", "samples": 50, "seed": 7, "parameter": [
        {"path": "meshes.sun.backlash", "distribution": "uniform", "low": 20e-6, "high": 60e-6},
        {"path": "meshes.ring.damping_ratio", "distribution": "normal", "mean": 0.01,
         "std": 0.01, "low": 0.002, "high": 0.03},
        {"path": "meshes.sun.damping_ratio", "values": [0.005, 0.01]}]}
    a = sweep_from_dict(spec).cases()
    b = sweep_from_dict(spec).cases()
    assert [c.values for c in a] == [c.values for c in b]  # the seed fixes the samples
    assert [c.values for c in sweep_from_dict({**spec, "seed": 8}).cases()] != \
        [c.values for c in a]
    backlash = np.array([c.values[0] for c in a])
    zeta = np.array([c.values[1] for c in a])
    assert backlash.min() >= 20e-6 and backlash.max() <= 60e-6 and np.ptp(backlash) > 20e-6
    assert zeta.min() >= 0.002 and zeta.max() <= 0.03  # truncated normal
    assert {c.values[2] for c in a} == {0.005, 0.01}
    # list-valued keys are drawn element by element (a zero std keeps the mean)
    p = Parameter("geometry.planet_angles_deg", distribution="normal", mean=[0, 120, 240],
                  std=[0, 0.5, 0.5], low=[-1, 119, 239], high=[1, 121, 241])
    x = np.array(p.sample(np.random.default_rng(1), 2000))
    assert x.shape == (2000, 3) and np.all(x[:, 0] == 0.0)
    assert np.all((x[:, 1:] >= [119, 239]) & (x[:, 1:] <= [121, 241]))
    np.testing.assert_allclose(x[:, 1:].mean(axis=0), [120, 240], atol=0.05)
    np.testing.assert_allclose(x[:, 1:].std(axis=0), 0.5 * 0.8796, rtol=0.06)


@pytest.mark.parametrize(("change", "message"), [
    ({"bogus": 1}, "unknown key 'bogus'"),
    ({"base": "paper-case9"}, "unknown preset 'paper-case9'"),
    ({"parameter": []}, "at least one [[parameter]]"),
    ({"parameter": [{"path": "meshes.sn.damping_ratio", "values": [0.01]}]},
     "unknown key 'sn' in [meshes]"),
    ({"parameter": [{"path": "meshes.sun.damping_ratio", "values": []}]}, "values is empty"),
    ({"parameter": [{"path": "meshes.sun.damping_ratio", "values": [[0.01, 0.02]]}]},
     "is a list, but the base description has a number"),
    ({"parameter": [{"path": "geometry.planet_angles_deg", "values": [120.0]}]},
     "is a number, but the base description has a list"),
    ({"parameter": [{"path": "meshes.sun.damping_ratio", "values": ["x"]}]},
     "damping_ratio must be a number"),
    ({"parameter": [{"path": "meshes.sun.dampin_ratio", "values": [0.01]}]},
     "unknown key 'dampin_ratio' in [meshes.sun]"),
    ({"parameter": [{"path": "geometry.planet_angles_deg.3", "values": [1.0]}]},
     "index 3 out of range"),
    ({"parameter": [{"path": "simulation.duration", "values": [-1.0]}]},
     "[simulation].duration = -1.0 is not admissible (admissible: >= 1e-06)"),
    ({"simulation": {"speed": 3}}, "unknown key 'speed' in [simulation]"),
    ({"parameter": [{"path": "meshes.sun.damping_ratio", "values": list(range(1, 200))},
                    {"path": "meshes.ring.damping_ratio", "values": list(range(1, 200))}]},
     "the grid has 199 x 199 = 39601 cases, more than max_cases = 10000"),
    ({"max_cases": 0}, "max_cases = 0; admissible"),
    ({"mode": "zip", "parameter": [{"path": "meshes.sun.damping_ratio", "values": [0.1, 0.2]},
                                   {"path": "meshes.ring.damping_ratio", "values": [0.1]}]},
     "mode = 'zip' needs as many values"),
    ({"mode": "random"}, "needs samples"),
    ({"mode": "lattice"}, "mode = 'lattice'; admissible"),
    ({"samples": 3}, "samples is a key of mode = 'random' only"),
    ({"parameter": [{"path": "meshes.sun.damping_ratio", "values": [0.1], "labels": ["a", "b"]}]},
     "labels must be a list of non-empty strings, one per value"),
    ({"parameter": [{"path": "meshes.sun.backlash", "distribution": "uniform", "low": 1.0,
                     "high": 2.0}]}, "a distribution needs mode = 'random'"),
    ({"parameter": [{"path": "meshes.sun.comment", "values": [1.0, 2.0]}]},
     "the units of this key are not known"),
    ({"parameter": [{"path": "meshes.sun.damping_ratio", "values": [0.01]},
                    {"path": "meshes.sun.damping_ratio", "values": [0.02]}]}, "listed twice"),
    ({"summary": {"windows": [0, 1]}}, "unknown key 'windows' in [summary]"),
    ({"summary": {"window_s": [0.5, 0.1]}}, "[summary].window_s = [0.5, 0.1]; admissible"),
    ({"summary": {"orders": [0, 1]}}, "orders must be a non-empty list of orders > 0"),
    ({"summary": {"order_signals": ["tooth_force"]}}, "unknown run variable 'tooth_force'"),
    ({"summary": {"order_signals": ["normal_force[flank]"]}}, "a selection is 'dimension=label'"),
])
def test_invalid_descriptions_name_the_key(change, message):
    with pytest.raises(ConfigError) as err:
        _sweep(**change).cases()
    assert message in str(err.value)


def test_load_sweep_file_errors(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        load_sweep(tmp_path / "missing.toml")
    p = tmp_path / "bad.toml"
    p.write_text("base = \n")
    with pytest.raises(ConfigError, match="invalid TOML"):
        load_sweep(p)
    # a relative base is resolved against the sweep file; the title defaults to its name
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "set.toml").write_text(_preset_text())
    q = tmp_path / "study.toml"
    q.write_text('base = "sub/set.toml"\n[[parameter]]\npath = "meshes.sun.backlash"\n'
                 'values = [1e-5, 2e-5]\n')
    s = load_sweep(q)
    assert s.title == "study" and len(s.cases()) == 2


def _preset_text() -> str:
    from importlib import resources

    return resources.files("gearvib.presets").joinpath("paper-case1.toml").read_text("utf-8")


def test_api_and_toml_agree(tmp_path):
    api = Sweep(base="paper-case1", parameters=[
        Parameter("meshes.sun.damping_ratio", [0.005, 0.02]),
        Parameter("geometry.planet_angles_deg", [[0, 120, 240], [0, 122.45, 244.90]],
                  labels=["equal", "case2"])],
        simulation=dict(TINY["simulation"]),
        summary=SummarySettings.from_dict(TINY["summary"]), title="tiny")
    assert [c.sha256 for c in api.cases()] == [c.sha256 for c in _sweep().cases()]
    assert sweep_from_dict(api.to_dict()).to_dict() == api.to_dict()


# ----------------------------------------------------- same results on every executor

def test_same_sweep_on_one_and_two_workers_and_dask(tmp_path):
    distributed = pytest.importorskip("distributed")
    s = _sweep()
    one = run_sweep(s, tmp_path / "one", workers=1, progress=False, report=False)
    two = run_sweep(s, tmp_path / "two", workers=2, progress=False, report=False)
    assert one.simulated == two.simulated == (0, 1, 2, 3)
    # worker threads: worker processes are test_sweep_dask.py's (a scheduler and two
    # `dask worker` processes); their start costs ~10 s
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        dask = run_sweep(s, tmp_path / "dask", executor=client.get_executor(),
                         progress=False, report=False)
    assert dask.simulated == (0, 1, 2, 3)
    for other in ("two", "dask"):
        _identical_files(tmp_path / "one" / "sweep.nc", tmp_path / other / "sweep.nc")
        for f in sorted(os.listdir(tmp_path / "one" / "runs")):
            assert (tmp_path / "one" / "runs" / f).read_bytes() == \
                (tmp_path / other / "runs" / f).read_bytes()
    ds = one.dataset
    # the layout of sweep.nc
    assert ds.sizes["case"] == 4 and list(ds.mesh.values[:1]) == ["sun-planet1"]
    # parameters: CF names, the key path in an attribute (docs/sweeps.md)
    assert ds["meshes_sun_damping_ratio"].attrs["units"] == "1"
    assert ds["meshes_sun_damping_ratio"].attrs["gearvib_parameter_path"] == \
        "meshes.sun.damping_ratio"
    assert list(ds["geometry_planet_angles_deg"].values) == ["equal", "case2"] * 2
    np.testing.assert_array_equal(ds["geometry_planet_angles_deg_values"].values[1],
                                  [0, 122.45, 244.90])
    assert all(f.startswith("runs/") and f.endswith(".nc") for f in ds.run_file.values)
    for name, var in {**ds.data_vars, **ds.coords}.items():
        assert "long_name" in var.attrs, name
        if var.dtype.kind == "f":
            assert "units" in var.attrs, name
    assert ds.dynamic_factor.dims == ("case", "mesh")
    assert ds.normal_force_order_level.dims == ("case", "mesh", "order")
    assert ds.floquet_growth_rate.dims == ("case", "floquet_speed")
    assert np.all(ds.dynamic_factor.values > 1.0)
    # in-phase planets (case "equal") share the load equally; case 2's planets do not
    kv = ds.dynamic_factor.values
    np.testing.assert_allclose(kv[0, :3], kv[0, 0], rtol=1e-9)
    assert np.ptp(kv[1, :3]) > 1e-3
    assert "sweep_json" in ds.attrs and ds.attrs["Conventions"] == "CF-1.11"


# ----------------------------------------------------------------------------- resuming

def test_interrupted_sweep_resumes_without_recomputing(tmp_path):
    s = _sweep(summary={})
    run_sweep(s, tmp_path / "ref", workers=1, progress=False, report=False)
    done = []

    def interrupt(outcome):
        done.append(outcome.index)
        if len(done) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):  # case by case (a batch's files come together)
        run_sweep(s, tmp_path / "out", workers=1, progress=False, on_case_done=interrupt,
                  batch=False)
    assert not (tmp_path / "out" / "sweep.nc").exists()
    runs = tmp_path / "out" / "runs"
    finished = {p.name: p.stat().st_mtime_ns for p in runs.glob("*.nc")}
    assert len(finished) == 2
    again = run_sweep(s, tmp_path / "out", workers=1, progress=False, report=False)
    assert again.reused == tuple(done) and again.simulated == tuple(
        i for i in range(4) if i not in done)
    assert {p.name: p.stat().st_mtime_ns for p in runs.glob("*.nc")
            if p.name in finished} == finished  # not written again
    _identical_files(tmp_path / "ref" / "sweep.nc", tmp_path / "out" / "sweep.nc")
    # a damaged run file is not taken for a finished one
    damaged = runs / str(again.dataset.run_file.values[0]).split("/")[1]
    damaged.write_bytes(damaged.read_bytes()[:1000])
    third = run_sweep(s, tmp_path / "out", workers=2, progress=False, report=False)
    assert third.simulated == (0,) and third.reused == (1, 2, 3)
    _identical_files(tmp_path / "ref" / "sweep.nc", tmp_path / "out" / "sweep.nc")


def test_interrupting_a_process_pool_keeps_finished_runs(tmp_path):
    s = _sweep(summary={})

    def interrupt(outcome):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(s, tmp_path / "out", workers=2, progress=False, on_case_done=interrupt)
    kept = len(list((tmp_path / "out" / "runs").glob("*.nc")))
    assert 1 <= kept <= 4
    assert not list((tmp_path / "out" / "runs").glob(".*.tmp"))
    again = run_sweep(s, tmp_path / "out", workers=2, progress=False, report=False)
    assert len(again.reused) == kept and len(again.simulated) == 4 - kept


def test_failed_cases_are_reported_and_the_rest_is_kept(tmp_path):
    s = sweep_from_dict({"base": "paper-case1", "simulation": {"duration": 0.02},
                         "parameter": [{"path": "simulation.speed_end_rpm",
                                        "values": [500.0, 3000.0]}],
                         "summary": {"window_rpm": [1000, 3000]}})
    r = run_sweep(s, tmp_path / "out", workers=1, progress=False, report=False)
    assert r.failed == (0,) and r.simulated == (1,)
    ds = r.dataset
    assert list(ds.status.values) == ["failed", "ok"]
    assert "holds no output sample" in str(ds.failure.values[0])
    assert ds.run_file.values[0] == "" and np.all(np.isnan(ds.dynamic_factor.values[0]))
    assert np.all(np.isfinite(ds.dynamic_factor.values[1]))


# ------------------------------------------------------------------------- summaries

@pytest.fixture(scope="module")
def tiny_run():
    """One 0.1 s run of paper-case1 at 1000 -> 2000 min-1, with its model and conditions."""
    from gearvib.simulate import simulate

    case = sweep_from_dict({"base": "paper-case1", "simulation": {
        "speed_start_rpm": 1000.0, "speed_end_rpm": 2000.0, "duration": 0.1},
        "parameter": [{"path": "meshes.sun.backlash", "values": [40e-6]}]}).cases()[0]
    model = build_case(case)
    cond = conditions_for(case.run, model)
    return simulate(model, cond, progress=False).to_dataset(), model, cond


def test_order_levels_of_a_known_signal(tiny_run):
    """A tone at mesh order 2 of amplitude A: level A/sqrt(2) at order 2, nothing at 1 or 3."""
    ds, model, cond = tiny_run
    f_mesh = ds.mesh_frequency.values.reshape(-1, ds.sizes["time"])[0]  # (time) or (mesh, time)
    phase = 2 * np.pi * np.cumsum(f_mesh) / ds.attrs["fs_out"]
    amp = 7.0
    ds = ds.assign(drive_torque=(("time",), amp * np.sin(2.0 * phase),
                                 {"units": "N m", "long_name": "synthetic tone"}))
    s = SummarySettings.from_dict({"orders": [1, 2, 3], "order_signals": ["drive_torque"],
                                   "order_resolution": 0.1})
    out = summarise_run(ds, model, cond, s)
    lev = out.drive_torque_order_level.values
    assert lev[1] == pytest.approx(amp / math.sqrt(2), rel=2e-3)  # measured 1e-4
    assert lev[0] < 1e-4 * amp and lev[2] < 1e-4 * amp  # measured 7e-6
    assert out.drive_torque_order_level.attrs["units"] == "N m"
    spd = out.drive_torque_order_level_speed.values[1]
    assert 1000.0 <= spd <= 2000.0


def test_virtual_sensor_hook(tiny_run):
    ds, model, cond = tiny_run
    s = SummarySettings.from_dict({"orders": [1.0]})
    plain = summarise_run(ds, model, cond, s)
    assert not [v for v in plain.data_vars if str(v).startswith("accel")]
    t = ds.time.values
    sensor = xr.DataArray(np.stack([np.sin(2 * np.pi * 500 * t), 2 * np.sin(2 * np.pi * 500 * t)]),
                          dims=("sensor", "time"), coords={"sensor": ["a", "b"]},
                          attrs={"units": "m s-2", "long_name": "virtual accelerometer",
                                 "gearvib_quantity": VIRTUAL_SENSOR_QUANTITY})
    out = summarise_run(ds.assign(accel=sensor), model, cond, s)
    np.testing.assert_allclose(out.accel_rms.values, [1 / math.sqrt(2), math.sqrt(2)],
                               rtol=2e-3)
    assert out.accel_rms.attrs["units"] == "m s-2"
    assert out.accel_order_level.dims == ("sensor", "order")
    # without order levels too, the sensor names label the rms values (sweep.nc needs them)
    bare = summarise_run(ds.assign(accel=sensor), model, cond)
    assert bare.accel_rms.dims == ("sensor",)
    assert bare["sensor"].values.tolist() == ["a", "b"]


def test_summary_window_and_reference(tiny_run):
    ds, model, cond = tiny_run
    whole = summarise_run(ds, model, cond)
    part = summarise_run(ds, model, cond, SummarySettings(window_s=(0.05, 0.1)))
    assert np.all(part.max_tooth_force.values <= whole.max_tooth_force.values)
    assert np.all(part.transmission_error_pp.values <= whole.transmission_error_pp.values)
    with pytest.raises(ValueError, match="holds no output sample"):
        summarise_run(ds, model, cond, SummarySettings(window_rpm=(3000.0, 4000.0)))
    with pytest.raises(ValueError, match="not a member"):
        summarise_run(ds, model, cond, SummarySettings(orders=(1.0,), order_reference="moon"))
    with pytest.raises(ValueError, match="no mesh 'sun-planet9'"):
        summarise_run(ds, model, cond, SummarySettings(orders=(1.0,),
                                                       order_reference="mesh:sun-planet9"))
    one = summarise_run(ds, model, cond, SummarySettings(orders=(1.0,),
                                                         order_reference="mesh:ring-planet2"))
    # mesh order 1 is order z_s (1 - n_c/n_s) of the sun; same frames in angle
    per_rev = 33.0 * (1 - model.kinematic_ratios["carrier"])
    by_member = summarise_run(ds, model, cond, SummarySettings(
        orders=(per_rev,), order_reference="sun", order_resolution=0.1 * per_rev))
    by_mesh = summarise_run(ds, model, cond, SummarySettings(orders=(1.0,)))
    # the same order of the same frames: equal up to rounding (the ring and sun mesh
    # frequencies of the run agree to the last bits only)
    np.testing.assert_allclose(one.normal_force_order_level.values,
                               by_mesh.normal_force_order_level.values, rtol=1e-12)
    # (measured 1.2-1.6 %: the angular sampling of the two differs)
    np.testing.assert_allclose(by_member.normal_force_order_level.values,
                               by_mesh.normal_force_order_level.values, rtol=0.03)


# ------------------------------------------------------------------- worker environment

@pytest.mark.parametrize("method", ["fork", "spawn"])
def test_local_workers_get_one_thread_each_and_the_numba_cache(method, monkeypatch):
    import multiprocessing

    import numba

    from gearvib.execution import THREAD_VARIABLES, local_executor, worker_environment

    if method not in multiprocessing.get_all_start_methods():
        pytest.skip(f"no {method} start method here")
    for v in THREAD_VARIABLES:
        monkeypatch.setenv(v, "7")
    with worker_environment() as env:
        ex = local_executor(2, start_method=method)
        try:
            seen = {v: ex.submit(os.getenv, v).result(timeout=60) for v in env}
        finally:
            ex.shutdown()
    assert {v: seen[v] for v in THREAD_VARIABLES} == dict.fromkeys(THREAD_VARIABLES, "1")
    if numba.config.CACHE_DIR:
        assert seen["NUMBA_CACHE_DIR"] == str(numba.config.CACHE_DIR)
    assert all(os.environ[v] == "7" for v in THREAD_VARIABLES)  # this process: restored
    with pytest.raises(ValueError, match="workers = 0"):
        local_executor(0)


def test_cases_run_with_one_blas_thread_and_restore_the_callers(tmp_path, monkeypatch):
    from threadpoolctl import threadpool_info, threadpool_limits

    import gearvib.sweep.case as case_module
    from gearvib.sweep.case import CaseTask, run_case

    seen = []
    real = case_module.simulate

    def spy(*args, **kwargs):
        seen.extend(lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas")
        return real(*args, **kwargs)

    monkeypatch.setattr(case_module, "simulate", spy)
    s = sweep_from_dict({**TINY, "summary": {}})
    with threadpool_limits(limits=2, user_api="blas"):
        out = run_case(CaseTask(s.cases()[0], str(tmp_path / "run.nc"), s.summary))
        after = {lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"}
    assert out.status == "simulated"
    assert seen and set(seen) == {1}
    assert after == {2}
