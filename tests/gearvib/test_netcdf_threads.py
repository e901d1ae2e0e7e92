"""netCDF files written and read by several threads of one process (a threaded Dask cluster,
a thread pool): no crash, every file complete.

The netCDF library is not thread-safe (analysis.netcdf_lock): without the process-wide lock,
four threads writing small files crash the interpreter within a few dozen files. The threads
run in a child process, so that a crash fails this test instead of the test run.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

STRESS = textwrap.dedent("""
    import os, sys, tempfile
    from concurrent.futures import ThreadPoolExecutor

    import numpy as np
    import xarray as xr

    from analysis.readers import read_netcdf, write_netcdf as write_measurement
    from gearvib.io import write_netcdf

    n = 20000
    ds = xr.Dataset(
        {"x": ("time", np.random.default_rng(0).normal(size=n), {"units": "1", "long_name": "x"})},
        coords={"time": ("time", np.arange(n) / 1e4, {"units": "s", "long_name": "time"})})
    folder = tempfile.mkdtemp()

    def job(i):
        for k in range(int(sys.argv[1])):
            path = os.path.join(folder, f"f{i}_{k}.nc")
            if i % 2:
                write_netcdf(ds, path)
            else:
                write_measurement(ds, path)
            back = read_netcdf(path)
            assert np.array_equal(back["x"].values, ds["x"].values), path

    with ThreadPoolExecutor(4) as pool:
        list(pool.map(job, range(4)))
    print("files", len(os.listdir(folder)))
""")


@pytest.mark.slow
def test_threads_write_and_read_netcdf_files_without_crash():
    r = subprocess.run([sys.executable, "-c", STRESS, "25"], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, (r.returncode, r.stderr[-3000:])
    assert r.stdout.split() == ["files", "100"]
