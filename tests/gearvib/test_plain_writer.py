"""The run written without xarray (a ``PlainDataset`` through netCDF4) is xarray's file.

``gearvib simulate`` writes :meth:`RunUpResult.to_plain_dataset` with netCDF4 directly
(issue 16: no xarray/pandas import); every other writer goes through xarray. Both files are
compared byte for byte (netCDF-C/HDF5 store no time stamps, so the same calls give the same
bytes) and, read back with xarray, for identity of values (bit for bit) and attributes, on runs
that cover every variable the result can hold: elastic bearings, virtual sensors and a tacho,
local faults, a torque-driven run, NaN data (a fill value), and an auxiliary coordinate that
no variable uses (a global ``coordinates`` attribute).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr

import analysis.cf
from gearvib import cfdata
from gearvib.assembly import assemble
from gearvib.cfdata import PlainDataset, PlainVariable
from gearvib.config import load_gearset
from gearvib.faults import Crack
from gearvib.io import read_run, write_netcdf
from gearvib.sensors import HousingMode, HousingSensor, Tacho
from gearvib.simulate import SpeedRamp, TorqueDriven, simulate


def _run(preset: str, conditions=None, sensors=(), faults=(), duration: float = 0.02):
    model = assemble(load_gearset(preset))
    if sensors:
        model = model.with_sensors(list(sensors))
    if faults:
        model = model.with_faults(list(faults))
    cond = conditions or SpeedRamp(600, 1800, 1.0, input_torque=60.0)
    return simulate(model, cond, duration=duration, progress=False)


RUNS = {
    "paper-case1": lambda: _run("paper-case1"),
    "elastic bearings": lambda: _run("paper-case1-elastic"),
    "sensors and tacho": lambda: _run(
        "paper-case1",
        sensors=[HousingSensor("top", 30.0, window="hann", width_deg=90.0,
                               housing_modes=(HousingMode(3000.0, 0.05, 1.0),)),
                 Tacho("tacho", pulses_per_rev=60)]),
    "crack": lambda: _run("paper-case1", faults=[Crack("sun", 3, severity=0.2)]),
    "torque-driven": lambda: _run("paper-case1", TorqueDriven(60.0, load_inertia=0.1,
                                                             duration=0.02, max_rpm=4000)),
    "two stages": lambda: _run("two-stage-example"),
}


@pytest.fixture(scope="module", params=list(RUNS))
def result(request):
    return RUNS[request.param]()


def _both(tmp_path: Path, plain: PlainDataset) -> tuple[Path, Path]:
    a = write_netcdf(plain, tmp_path / "plain.nc")
    b = write_netcdf(plain.to_xarray(), tmp_path / "xarray.nc")
    return a, b


def _assert_same_file(a: Path, b: Path) -> None:
    assert a.read_bytes() == b.read_bytes()
    with xr.open_dataset(a, decode_times=False) as da, xr.open_dataset(b, decode_times=False) \
            as db:
        xr.testing.assert_identical(da.load(), db.load())  # values bit for bit, attributes
        assert list(da.variables) == list(db.variables)
        for name in da.variables:
            x, y = da[name].values, db[name].values
            if x.dtype.kind == "f":
                assert np.array_equal(x.view(np.int64), y.view(np.int64)), name


def test_the_run_file_is_xarrays_byte_for_byte(tmp_path: Path, result) -> None:
    a, b = _both(tmp_path, result.to_plain_dataset())
    _assert_same_file(a, b)
    back = read_run(a)
    xr.testing.assert_identical(back, read_run(b))
    ref = result.to_dataset()
    for name in ("normal_force", "mesh_deflection", "time", "input_speed"):
        assert np.array_equal(back[name].values, ref[name].values)


def test_to_dataset_is_the_plain_dataset(result) -> None:
    ds = result.to_dataset()
    plain = result.to_plain_dataset()
    assert list(ds.data_vars) == list(plain.data_vars)
    assert set(ds.coords) == set(plain.coords)
    for name, var in plain.variables().items():
        assert ds[name].dims == var.dims and ds[name].attrs == var.attrs
        assert np.array_equal(ds[name].values, var.data)


def test_nan_data_get_a_fill_value_as_with_xarray(tmp_path: Path) -> None:
    res = RUNS["paper-case1"]()
    torque = res.drive_torque.copy()
    torque[3] = np.nan
    speed = res.input_speed.copy()
    speed[5] = np.nan  # a coordinate: no fill value (CF), NaN kept
    plain = dataclasses.replace(res, drive_torque=torque, input_speed=speed).to_plain_dataset()
    a, b = _both(tmp_path, plain)
    _assert_same_file(a, b)
    with netCDF4.Dataset(a) as nc:
        assert np.isnan(nc["drive_torque"].getncattr("_FillValue"))
        assert "_FillValue" not in nc["input_speed"].ncattrs()


def test_small_datasets_global_coordinates_and_attribute_types(tmp_path: Path) -> None:
    t = np.arange(5) / 10.0
    plain = PlainDataset(
        {"x": PlainVariable(("chan", "time"), np.arange(10.0).reshape(2, 5),
                            {"units": "m", "flag": True, "cfg": {"b": [1, 2]}, "none": None}),
         "n": PlainVariable(("chan",), np.array([3, 4], dtype=np.int32), {"units": "1"}),
         "empty": PlainVariable(("other", "time"), np.zeros((0, 5)), {"units": "1"})},
        {"time": PlainVariable(("time",), t, cfdata.time_attrs("time")),
         "chan": PlainVariable(("chan",), np.array(["a", "bb"]), {}),
         "other": PlainVariable(("other",), np.array([], dtype=str), {"long_name": "o"}),
         "angle": PlainVariable(("side",), np.array([1.0, 2.0, 3.0]), {"units": "degree"})},
        {"title": "t", "values": np.array([1.0, 2.0]), "n": 3, "flag": False, "names": ("a", "b")},
    )
    a, b = _both(tmp_path, plain)
    _assert_same_file(a, b)
    with netCDF4.Dataset(a) as nc:
        assert nc.getncattr("coordinates") == "angle"  # used by no variable
        assert "coordinates" not in nc["x"].ncattrs()  # chan: its dimension's labels
        assert nc["chan"].dimensions == ("chan", "chan_strlen")  # a UTF-8 character array
        assert nc["chan"].getncattr("long_name") == "chan label"
        assert nc["chan"].getncattr("_Encoding") == "utf-8"
    with xr.open_dataset(a) as plain_open:  # plain xarray: the labels are a string index
        assert plain_open["x"].sel(chan="bb").shape == (5,)
        assert plain_open.sizes["other"] == 0


def test_the_conventions_repeated_from_analysis_cf_are_the_same() -> None:
    assert cfdata.STRLEN_SUFFIX == analysis.cf.STRLEN_SUFFIX
    assert cfdata.EPOCH == analysis.cf.EPOCH
    assert cfdata.time_attrs("t s") == analysis.cf.time_attrs("t s")


def test_plain_dataset_checks_its_shape_and_the_writer_its_types(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="dimensions"):
        PlainVariable(("time",), np.zeros((2, 2)))
    with pytest.raises(ValueError, match="'time' has size 3"):
        PlainDataset({"a": PlainVariable(("time",), np.zeros(2))},
                     {"time": PlainVariable(("time",), np.zeros(3))})
    with pytest.raises(ValueError, match="both"):
        PlainDataset({"a": PlainVariable(("a",), np.zeros(2))},
                     {"a": PlainVariable(("a",), np.zeros(2))})
    flags = PlainDataset({"ok": PlainVariable(("n",), np.array([True, False]))}, {})
    with pytest.raises(ValueError, match="'ok': dtype bool"):
        write_netcdf(flags, tmp_path / "b.nc")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("error", [RuntimeError("disk full"), KeyboardInterrupt()])
def test_a_failed_plain_write_leaves_nothing_and_keeps_the_old_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, error: BaseException
) -> None:
    plain = RUNS["paper-case1"]().to_plain_dataset()
    dest = tmp_path / "run.nc"
    write_netcdf(plain, dest)
    before = dest.read_bytes()

    class Failing(netCDF4.Dataset):
        def close(self):  # a complete temporary file, then the failure
            super().close()
            raise error

    monkeypatch.setattr(netCDF4, "Dataset", Failing)
    with pytest.raises(type(error)):
        write_netcdf(plain, dest)
    assert list(tmp_path.iterdir()) == [dest]
    assert dest.read_bytes() == before
