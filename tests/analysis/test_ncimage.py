"""Readers never crash on a file the caller holds open (analysis.readers.ncimage).

With the netCDF-C/HDF5 libraries bundled with netCDF4-python, opening and closing a second
handle on a file that holds variable-length strings, while a first handle stays open, crashes
the process at the next open (segmentation fault; Unidata/netcdf4-python#1444). A user who
keeps ``xr.open_dataset(run)`` in a notebook and calls a gearvib reader on the same file hit
exactly that. The readers now read an in-memory image of the file. Each check runs in a
subprocess, since the failure is a crash.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from analysis.readers.ncimage import file_image, load_image, open_image


def _labelled(path: Path) -> Path:
    ds = xr.Dataset(
        {"force": (("mesh", "time"), np.arange(40.0).reshape(2, 20) + 1.0,
                   {"units": "N", "long_name": "force"}),
         "tacho": ("time", np.sin(np.arange(20.0)), {"units": "V", "long_name": "tacho"})},
        coords={"time": ("time", np.arange(20) * 1e-3, {"units": "s", "long_name": "time"}),
                "mesh_label": ("mesh", np.array(["sun-planet1", "ring-planet1"], dtype=object))},
        attrs={"source": "gearvib test"},
    )
    ds.to_netcdf(path, engine="netcdf4")
    return path


def _survives(code: str, path: Path) -> subprocess.CompletedProcess:
    lines = ["import xarray as xr", f"held = xr.open_dataset({str(path)!r})",
             "for _ in range(5):"]
    lines += ["    " + line for line in code.splitlines()]
    lines += ['print(float(held["force"].sum()))', "held.close()"]
    return subprocess.run([sys.executable, "-c", "\n".join(lines)], capture_output=True,
                          text=True, timeout=120)


@pytest.mark.parametrize("code", [
    "from analysis.readers.ncimage import load_image\nload_image(PATH)",
    "from gearvib.io import read_run\nread_run(PATH)",
    "from gearvib.report.measured import is_simulated_run\nis_simulated_run(PATH)",
])
def test_readers_survive_a_held_handle(tmp_path, code):
    path = _labelled(tmp_path / "held.nc")
    done = _survives(code.replace("PATH", repr(str(path))), path)
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    assert float(done.stdout.split()[-1]) == pytest.approx(np.arange(40.0).sum() + 40.0)


def test_image_reads_what_the_file_holds(tmp_path):
    path = _labelled(tmp_path / "a.nc")
    with xr.open_dataset(path) as direct:
        expected = direct.load()
    image = file_image(path)
    assert len(image) == path.stat().st_size
    got = load_image(path, image)
    xr.testing.assert_identical(got, expected)
    with open_image(path, image) as nc:
        assert set(nc.variables) == set(expected.variables)
        assert nc.source == "gearvib test"
    assert not nc.isopen()


def test_missing_file_is_an_oserror(tmp_path):
    with pytest.raises(FileNotFoundError):
        file_image(tmp_path / "none.nc")
