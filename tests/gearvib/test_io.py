"""Tests of the netCDF writer and reader: round trip, CF encodings, atomicity, errors."""

from __future__ import annotations

from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr

from gearvib.io import GearvibFileError, read_run, sanitize_attrs, write_netcdf
from gearvib.model import AssembledModel
from gearvib.simulate import SpeedRamp, simulate


def gear_pair() -> AssembledModel:
    """Pinion (input) driving a gear (output) with backlash; one bearing-like torsional support."""
    r1, r2 = 0.03, 0.05
    n = 2
    v = np.array([[r1, r2]])
    support = np.diag([0.0, 0.0])
    return AssembledModel(
        dof_names=("pinion.theta", "gear.theta"), dof_units=("rad", "rad"),
        mass=np.diag([1e-3, 4e-3]), stiffness=support, damping=support,
        gyroscopic=np.zeros((n, n)), centripetal=np.zeros((n, n)),
        mesh_names=("pinion-gear",), mesh_vectors=v,
        mesh_position_vectors=np.array([[20 / (2 * np.pi), 0.0]]),
        mesh_position_offsets=np.array([0.0]),
        mesh_stiffness_tables=np.array([[1e8, 1.3e8, 1.3e8, 1e8]]),
        mesh_back_tables=np.array([[1e8, 1.3e8, 1.3e8, 1e8]]),
        mesh_backlash=np.array([20e-6]), mesh_damping=np.array([200.0]),
        bearing_names=("gear.torsion",), bearing_vectors=np.array([[0.0, 1.0]]),
        bearing_stiffness=np.array([0.0]), bearing_damping=np.array([0.0]),
        rotation_dofs={"pinion": 0, "gear": 1}, carrier_dof=-1, input_member="pinion",
        output_member="gear", fixed_members=(),
        kinematic_ratios={"pinion": 1.0, "gear": -r1 / r2},
        mesh_frequencies_per_rpm=np.array([20 / 60]), meta={"name": "pair", "flag": True},
    )


@pytest.fixture(scope="module")
def dataset() -> xr.Dataset:
    res = simulate(gear_pair(), SpeedRamp(100, 2000, 0.03, input_torque=20.0))
    return res.to_dataset()


def test_round_trip_is_identical(tmp_path: Path, dataset: xr.Dataset) -> None:
    path = write_netcdf(dataset, tmp_path / "run.nc")
    back = read_run(path)
    xr.testing.assert_identical(dataset, back)
    assert back.attrs["source"].startswith("gearvib")
    assert back["time"].dtype == np.float64
    assert list(tmp_path.iterdir()) == [path]


def test_cf_encodings(tmp_path: Path, dataset: xr.Dataset) -> None:
    path = write_netcdf(dataset, tmp_path / "run.nc")
    with netCDF4.Dataset(path) as nc:
        assert nc.data_model == "NETCDF4"
        for name in ("time", "input_speed", "normal_force", "natural_frequency"):
            assert "_FillValue" not in nc[name].ncattrs(), name
        assert nc["time"].units == "seconds since 1970-01-01T00:00:00Z"  # CF time (analysis.cf)
        assert (nc["time"].standard_name, nc["time"].axis) == ("time", "T")
        assert "mesh" not in nc.variables and "mesh_label" in nc.variables  # CF labels
        assert nc["normal_force"].filters()["zlib"]
        assert nc["normal_force"].chunking()[-1] == dataset.sizes["time"]
        assert nc.Conventions == "CF-1.11"


def test_attributes_are_sanitised(tmp_path: Path, dataset: xr.Dataset) -> None:
    ds = dataset.copy()
    ds.attrs.update(flag=True, params={"b": 1, "a": [1, 2]}, nothing=None)
    ds["time"].attrs["is_uniform"] = np.bool_(True)
    back = read_run(write_netcdf(ds, tmp_path / "s.nc"))
    assert back.attrs["flag"] == 1 and back.attrs["flag"].dtype == np.int8
    assert back.attrs["params"] == '{"a": [1, 2], "b": 1}'
    assert back.attrs["nothing"] == ""
    assert back["time"].attrs["is_uniform"] == 1
    assert ds.attrs["flag"] is True  # the caller's dataset is untouched
    assert sanitize_attrs({"x": (1.0, 2.0)})["x"].tolist() == [1.0, 2.0]


@pytest.mark.parametrize("error", [RuntimeError("disk full"), KeyboardInterrupt()])
def test_atomic_write_leaves_nothing_on_error(
    tmp_path: Path, dataset: xr.Dataset, monkeypatch: pytest.MonkeyPatch, error: BaseException
) -> None:
    dest = tmp_path / "run.nc"
    original = xr.Dataset.to_netcdf

    def failing(self, path, *args, **kwargs):
        original(self.isel(time=slice(0, 10)), path, engine="netcdf4")  # partial file on disk
        assert Path(path).exists()
        raise error

    monkeypatch.setattr(xr.Dataset, "to_netcdf", failing)
    with pytest.raises(type(error)):
        write_netcdf(dataset, dest)
    assert list(tmp_path.iterdir()) == []

    # an existing file survives a failed overwrite unchanged
    monkeypatch.setattr(xr.Dataset, "to_netcdf", original)
    write_netcdf(dataset, dest)
    before = dest.read_bytes()
    monkeypatch.setattr(xr.Dataset, "to_netcdf", failing)
    with pytest.raises(type(error)):
        write_netcdf(dataset, dest)
    assert list(tmp_path.iterdir()) == [dest]
    assert dest.read_bytes() == before


def test_read_errors_name_the_path(tmp_path: Path) -> None:
    missing = tmp_path / "missing.nc"
    with pytest.raises(GearvibFileError, match=r"missing\.nc"):
        read_run(missing)
    text = tmp_path / "notes.nc"
    text.write_text("not a netCDF file")
    with pytest.raises(GearvibFileError, match=r"notes\.nc"):
        read_run(text)
    other = tmp_path / "other.nc"
    xr.Dataset({"x": ("t", np.arange(3.0))}).to_netcdf(other, engine="netcdf4")
    with pytest.raises(GearvibFileError, match=r"other\.nc.*not a gearvib file"):
        read_run(other)
