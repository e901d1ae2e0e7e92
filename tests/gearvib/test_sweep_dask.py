"""A sweep on a `dask scheduler` with two `dask worker` processes (loopback) through
`gearvib sweep --scheduler`: sweep.nc and the run files bit-identical to the in-process run.

(The LocalCluster case is in test_sweep.py.)
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gearvib.sweep import load_sweep, run_sweep, sweep_from_dict

SPEC = {
    "title": "dask",
    "base": "paper-case1",
    "simulation": {"speed_start_rpm": 2700.0, "speed_end_rpm": 2900.0, "duration": 0.02},
    "parameter": [{"path": "meshes.sun.damping_ratio", "values": [0.005, 0.01, 0.02]},
                  {"path": "meshes.ring.damping_ratio", "values": [0.01, 0.02]}],
    "summary": {"orders": [1, 2], "order_resolution": 0.25},
}

TOML = """title = "dask"
base = "paper-case1"
[simulation]
speed_start_rpm = 2700.0
speed_end_rpm = 2900.0
duration = 0.02
[[parameter]]
path = "meshes.sun.damping_ratio"
values = [0.005, 0.01, 0.02]
[[parameter]]
path = "meshes.ring.damping_ratio"
values = [0.01, 0.02]
[summary]
orders = [1, 2]
order_resolution = 0.25
"""


@contextlib.contextmanager
def dask_processes(folder: Path, n_workers: int = 2):
    """A `dask scheduler` on 127.0.0.1 (a free port: --port 0, read from its scheduler file)
    and `n_workers` `dask worker` processes of one thread; all stopped in the end."""
    dask_cli = shutil.which("dask") or str(Path(sys.executable).with_name("dask"))
    info = folder / "scheduler.json"
    procs: list[subprocess.Popen] = []
    log = open(folder / "dask.log", "wb")  # noqa: SIM115 (closed in finally)
    try:
        procs.append(subprocess.Popen(
            [dask_cli, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
             "--scheduler-file", str(info)], stdout=log, stderr=log))
        deadline = time.monotonic() + 60
        while not info.exists() or not info.read_text().strip():
            if time.monotonic() > deadline or procs[0].poll() is not None:
                raise RuntimeError("the dask scheduler did not start: "
                                   + (folder / "dask.log").read_text())
            time.sleep(0.2)
        address = json.loads(info.read_text())["address"]
        for _ in range(n_workers):
            procs.append(subprocess.Popen(
                [dask_cli, "worker", address, "--nthreads", "1", "--nworkers", "1",
                 "--no-dashboard", "--host", "127.0.0.1"], stdout=log, stderr=log))
        from distributed import Client

        with Client(address, timeout=30) as client:
            client.wait_for_workers(n_workers, timeout=120)
        yield address
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in reversed(procs):
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        log.close()


@pytest.mark.slow
def test_sweep_on_dask_scheduler_and_two_worker_processes(tmp_path):
    pytest.importorskip("distributed")
    (tmp_path / "study.toml").write_text(TOML)
    sweep = load_sweep(tmp_path / "study.toml")
    assert sweep.to_dict() == sweep_from_dict(SPEC).to_dict()
    local = run_sweep(sweep, tmp_path / "local", workers=1, progress=False, report=False)
    assert local.simulated == tuple(range(6))
    env = dict(os.environ)
    with dask_processes(tmp_path) as address:
        done = subprocess.run(
            [sys.executable, "-m", "gearvib", "sweep", str(tmp_path / "study.toml"), "-o",
             str(tmp_path / "dask"), "--scheduler", address, "-q", "--no-report"],
            capture_output=True, text=True, env=env, timeout=600)
    assert done.returncode == 0, done.stderr
    assert "6 simulated" in done.stdout
    assert (tmp_path / "dask" / "sweep.nc").read_bytes() == \
        (tmp_path / "local" / "sweep.nc").read_bytes()
    names = sorted(p.name for p in (tmp_path / "local" / "runs").glob("*.nc"))
    assert names == sorted(p.name for p in (tmp_path / "dask" / "runs").glob("*.nc"))
    assert len(names) == 6
    for name in names:
        assert (tmp_path / "dask" / "runs" / name).read_bytes() == \
            (tmp_path / "local" / "runs" / name).read_bytes()
