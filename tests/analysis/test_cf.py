"""Files every tool reads pass a real CF checker (issue #14): the IOOS compliance-checker at
CF-1.11 on a gearvib run file and on the output of every reader, and cf_xarray finds the axes.

The checker reports by priority; the tests require no message at any priority (errors,
warnings and recommendations alike) and no exception inside the checker.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from analysis.cf import labels_from_cf, labels_to_cf
from analysis.readers import (
    ChannelData,
    build_dataset,
    read,
    write_csv,
    write_mat,
    write_netcdf,
    write_wav,
)
from tests.analysis.test_readers import UFF_DIR, _uff_set, _write_tdms, _write_uff

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")  # the checker's own
compliance_checker = pytest.importorskip("compliance_checker")
cf_xarray = pytest.importorskip("cf_xarray")


def cf_messages(path: Path, tmp_path: Path) -> list[str]:
    """Every message of the IOOS compliance-checker at CF-1.11 for ``path``."""
    from compliance_checker.runner import CheckSuite, ComplianceChecker

    CheckSuite.load_all_available_checkers()
    report = tmp_path / f"{path.stem}-cf.json"
    ComplianceChecker.run_checker(
        str(path), ["cf:1.11"], 0, "normal", output_filename=str(report), output_format="json"
    )
    result = json.loads(report.read_text())["cf:1.11"]
    messages = [
        f"{c['name']}: {m}"
        for level in ("high_priorities", "medium_priorities", "low_priorities")
        for c in result[level]
        for m in c["msgs"]
    ]
    # exceptions raised inside a check (e.g. on a string coordinate variable) are not in the
    # report: the checks are run once more to collect them
    suite = CheckSuite()
    dataset = suite.load_dataset(str(path))
    try:
        (_, errors), = suite.run_all(dataset, ["cf:1.11"], skip_checks=[]).values()
    finally:
        dataset.close()
    messages += [f"checker exception in {name}: {exc[0]!r}" for name, exc in errors.items()]
    return messages


def _check_file(path: Path, tmp_path: Path) -> None:
    assert cf_messages(path, tmp_path) == []
    with xr.open_dataset(path, engine="netcdf4") as ds:  # default decoding, as any tool
        assert ds.cf.axes["T"] == ["time"]
        assert np.issubdtype(ds["time"].dtype, np.datetime64)


def test_run_file_passes_the_cf_checker(tmp_path):
    from gearvib.assembly import assemble
    from gearvib.config import load_gearset
    from gearvib.io import read_run
    from gearvib.io import write_netcdf as write_run
    from gearvib.simulate import SpeedRamp, simulate

    run = simulate(assemble(load_gearset("paper-case1")), SpeedRamp(0.0, 3000.0, 0.02))
    ds = run.to_dataset()
    path = write_run(ds, tmp_path / "run.nc")
    _check_file(path, tmp_path)
    back = read_run(path)  # float seconds and string labels as coordinates again
    xr.testing.assert_identical(back, ds)
    assert back.normal_force.sel(mesh=str(ds.mesh.values[0]), flank="left").size > 0
    # the analysis functions take the decoded file as well (time since the first sample)
    with xr.open_dataset(path, engine="netcdf4") as decoded:
        force = labels_from_cf(decoded)["normal_force"].sel(flank="left").isel(mesh=0)
        s = force.gearvib.spectrum()
    assert s.fs == pytest.approx(float(ds.attrs["fs_out"]))


def _sample() -> xr.Dataset:
    fs = 2048.0
    t = np.arange(2048) / fs
    return build_dataset(
        [
            ChannelData("ring x", 3.0 * np.sin(2 * np.pi * 50 * t), "m s-2"),
            ChannelData("tacho", np.sign(np.sin(2 * np.pi * 20 * t)), "V"),
        ],
        fs,
        source_format="test",
        attrs={"title": "sample", "time_coverage_start": "2024-05-01T10:00:00"},
    )


def _reader_file(kind: str, tmp_path: Path) -> Path:
    ds = _sample()
    if kind == "netcdf":
        return write_netcdf(ds, tmp_path / "in.nc")
    if kind == "wav":
        write_wav(ds, tmp_path / "in.wav")
        return tmp_path / "in.wav"
    if kind == "csv":
        write_csv(ds, tmp_path / "in.csv")
        return tmp_path / "in.csv"
    if kind == "mat":
        write_mat(ds, tmp_path / "in.mat")
        return tmp_path / "in.mat"
    if kind == "mat73":
        pytest.importorskip("h5py")
        from tests.analysis.test_readers_mat73 import savemat73

        t = np.arange(512) / 1024.0
        return savemat73(tmp_path / "in73.mat", {"acc": np.sin(2 * np.pi * 30 * t), "fs": 1024.0})
    if kind == "uff":
        pytest.importorskip("pyuff")
        return _write_uff(tmp_path / "in.uff", [_uff_set(0), _uff_set(1, binary=1)])
    if kind == "uff-measured":
        pytest.importorskip("pyuff")
        path = UFF_DIR / "MPSTD_Set001_2024_10_08_10_27_07.uff"
        if not path.is_file():
            pytest.skip("shared UFF files not found")
        return path
    pytest.importorskip("nptdms")
    return _write_tdms(
        tmp_path / "in.tdms",
        [("rig", "acc", np.sin(np.arange(400) / 7.0), {"wf_increment": 1e-3, "unit_string": "g"})],
    )


@pytest.mark.parametrize(
    "kind", ["netcdf", "wav", "csv", "mat", "mat73", "uff", "uff-measured", "tdms"]
)
def test_reader_output_passes_the_cf_checker(kind, tmp_path):
    path = _reader_file(kind, tmp_path)
    ds = read(path, time_column="time") if kind == "csv" else read(path)
    assert ds["time"].attrs["standard_name"] == "time" and ds.attrs["history"]
    assert ds.cf.axes["T"] == ["time"]
    _check_file(write_netcdf(ds, tmp_path / f"{kind}.nc"), tmp_path)


def test_labels_round_trip(tmp_path):
    ds = xr.Dataset(
        {"f": (("mesh", "time"), np.ones((2, 3)), {"units": "N", "long_name": "force"})},
        coords={"mesh": ("mesh", ["sun-planet1", "ring-planet1"], {"long_name": "mesh"})},
    )
    cf = labels_to_cf(ds)
    assert cf["mesh"].encoding == {"dtype": "S1", "char_dim_name": "mesh_strlen"}
    assert ds["mesh"].encoding == {}  # the caller's dataset is untouched
    xr.testing.assert_identical(labels_from_cf(cf), ds)
    cf.to_netcdf(tmp_path / "labels.nc", engine="netcdf4")
    with xr.open_dataset(tmp_path / "labels.nc") as plain:  # any reader: a string index
        assert plain["f"].sel(mesh="ring-planet1").shape == (3,)
        back = labels_from_cf(plain.load())
    xr.testing.assert_identical(back, ds)
    assert back["mesh"].dtype.kind == "U"
    # files of earlier versions: label variables <dim>_label
    old = ds.drop_vars("mesh").assign_coords(mesh_label=("mesh", ds["mesh"].values,
                                                         {"long_name": "mesh"}))
    xr.testing.assert_identical(labels_from_cf(old), ds)


def test_cf_dataset_finishes_a_result_without_touching_its_input():
    from analysis.cf import cf_dataset, toolkit_version

    ds = xr.Dataset(
        {"level": (("time", "order"), np.zeros((3, 2)), {"units": "dB", "long_name": "level"}),
         "n": ("ch", [1, 2], {"units": "1", "long_name": "n"})},
        coords={"time": ("time", [0.0, 0.5, 1.0], {"units": "s", "long_name": "frame time"}),
                "order": ("order", [1.0, 2.0], {"units": "1", "long_name": "order"}),
                "ch": ("ch", ["a", "b"])},
        attrs={"history": "measured on the rig", "flag": True, "none": None,
               "time_coverage_start": "2024-05-01T10:00:00"})
    before = ds.copy(deep=True)
    out = cf_dataset(ds, title="levels", producer="tests.levels", inputs={"signal": "x"})
    xr.testing.assert_identical(ds, before)
    assert ds["ch"].encoding == {} and ds.attrs["flag"] is True
    assert out.attrs["Conventions"] == "CF-1.11" and out.attrs["title"] == "levels"
    version = toolkit_version()
    assert out.attrs["history"] == f"measured on the rig\ntests.levels (gearvib {version})"
    assert out.attrs["source"] == f"gearvib {toolkit_version()} (tests.levels)"
    assert out.attrs["inputs"] == '{"signal": "x"}' and out.attrs["flag"] == 1
    assert "none" not in out.attrs
    assert out["time"].attrs["units"] == "seconds since 2024-05-01T10:00:00"
    assert out["time"].attrs["long_name"] == "frame time"
    assert out["level"].dims == ("order", "time")  # CF 2.4: T last
    assert out["level"].attrs == {"units": "1", "long_name": "level (dB)"}
    assert out["ch"].encoding["char_dim_name"] == "ch_strlen"
    assert out["time"].encoding["_FillValue"] is None
    again = cf_dataset(out, title="other", producer="tests.levels")
    assert again.attrs == out.attrs  # finishing twice adds nothing
