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
        # labels: UTF-8 character arrays named after their dimension (analysis.cf)
        assert nc["mesh"].dimensions == ("mesh", "mesh_strlen") and "mesh_label" not in nc.variables
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


def test_an_abandoned_write_cannot_leave_its_temporary_file(tmp_path: Path) -> None:
    """An interrupt abandons a netCDF write in its worker thread; the writer may create its
    file only after the interrupt's clean-up (CI saw a SIGTERM leave one). The write goes
    into a private folder that the clean-up removes, so the late create fails and nothing is
    left. The old layout (a plain temporary file) let the late writer re-create it."""
    import _thread
    import threading
    import time

    from gearvib import tempfiles
    from gearvib.io import atomic_write

    release = threading.Event()
    outcome: list[object] = []

    def late_writer(tmp: Path) -> None:
        release.wait(10.0)  # until the main thread has cleaned up after the interrupt
        try:
            tmp.write_bytes(b"late")  # what netCDF4.Dataset(tmp, "w") does: create anew
            outcome.append("created")
        except OSError as exc:
            outcome.append(exc)

    threading.Timer(0.2, _thread.interrupt_main).start()
    dest = tmp_path / "run.nc"
    with pytest.raises(KeyboardInterrupt):
        atomic_write(dest, late_writer, abandonable=True)
    release.set()
    t0 = time.monotonic()
    while not outcome and time.monotonic() - t0 < 10.0:
        time.sleep(0.01)
    assert outcome and isinstance(outcome[0], FileNotFoundError), outcome
    assert list(tmp_path.iterdir()) == []
    tempfiles.remove_own()  # what the command line's exit does: nothing left to remove


def test_remove_temporary_empties_a_folder_that_is_being_refilled(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import os

    from gearvib import tempfiles

    folder = tmp_path / ".run.nc.gearvib-host-1-0123abcd.tmp"
    folder.mkdir()
    (folder / "run.nc").write_bytes(b"x")
    refills: list[int] = []
    real_rmdir = os.rmdir

    def refilling_rmdir(path, *args, **kwargs):  # the writer re-creates its file twice
        if len(refills) < 2:
            refills.append(1)
            (folder / "run.nc").write_bytes(b"again")
        return real_rmdir(path, *args, **kwargs)

    monkeypatch.setattr(os, "rmdir", refilling_rmdir)
    assert tempfiles.remove_temporary(folder)
    monkeypatch.undo()
    assert len(refills) == 2 and not folder.exists()
    link = tmp_path / ".x.nc.gearvib-host-1-0123abcd.tmp"
    target = tmp_path / "keep"
    target.mkdir()
    (target / "file").write_bytes(b"k")
    link.symlink_to(target)
    assert not tempfiles.remove_temporary(link)  # never follows a link
    assert (target / "file").exists()


def test_a_fifo_is_refused_and_left_in_place(tmp_path: Path, dataset: xr.Dataset) -> None:
    """A device, FIFO or socket is not replaced by the atomic rename (as root, a write to
    /dev/null would have made it a regular file); a FIFO stands in for a device here."""
    import os

    fifo = tmp_path / "run.nc"
    os.mkfifo(fifo)
    with pytest.raises(ValueError, match=r"run\.nc is not a regular file"):
        write_netcdf(dataset, fifo)
    assert fifo.is_fifo() and list(tmp_path.iterdir()) == [fifo]
