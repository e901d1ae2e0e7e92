"""A full disk: exit 2 with "No space left on device" naming the file, nothing left behind
(issue 26, item 5).

The outputs go to a small tmpfs mounted for the test (root, or a user namespace via
``unshare``); where neither is allowed the test is skipped with the reason. HDF5 reports a
full disk as "NetCDF: HDF error"; gearvib.io.atomic_write tells it apart by the space left.
"""

from __future__ import annotations

import errno
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from gearvib.io import LOW_SPACE_BYTES, _no_space


@pytest.fixture
def small_disk(tmp_path):
    """A 2 MiB tmpfs, or skip."""
    mnt = tmp_path / "small"
    mnt.mkdir()
    if not sys.platform.startswith("linux") or shutil.which("mount") is None:
        pytest.skip("needs Linux mount for a small tmpfs")
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2M", "tmpfs", str(mnt)],
                       capture_output=True, text=True, check=False)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({r.stderr.strip() or r.returncode})")
    try:
        yield mnt
    finally:
        subprocess.run(["umount", str(mnt)], capture_output=True, check=False)


def _gearvib(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "gearvib", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=600, check=False)


def test_simulate_onto_a_full_disk(tmp_path, small_disk):
    r = _gearvib("simulate", "paper-case1", "-o", str(small_disk / "run.nc"), "--duration",
                 "1", "-q", cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert r.stderr.startswith("gearvib: error:") and len(r.stderr.splitlines()) == 1
    assert "No space left on device" in r.stderr and "run.nc" in r.stderr
    assert "HDF error" not in r.stderr and "Traceback" not in r.stderr
    assert not any(small_disk.iterdir())  # no partial file, no temporary file


def test_report_onto_a_full_disk(tmp_path, small_disk):
    run = tmp_path / "run.nc"
    assert _gearvib("simulate", "paper-case1", "-o", str(run), "--duration", "0.25", "-q",
                    cwd=tmp_path).returncode == 0
    # leave less room than the report needs
    with (small_disk / "filler").open("wb") as fh:
        fh.write(b"\0" * (2 * 2**20 - 96 * 2**10))
    r = _gearvib("report", str(run), "-o", str(small_disk / "rep"), "-q", cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert "No space left on device" in r.stderr and "Traceback" not in r.stderr
    assert [p.name for p in small_disk.iterdir()] == ["filler"]


def test_a_failed_write_with_room_left_keeps_its_own_message(tmp_path):
    assert _no_space(RuntimeError("NetCDF: HDF error"), tmp_path / "x.nc", tmp_path) is None \
        or shutil.disk_usage(tmp_path).free < LOW_SPACE_BYTES
    full = _no_space(OSError(errno.ENOSPC, "No space left on device"), tmp_path / "x.nc",
                     tmp_path)
    assert full is not None and full.errno == errno.ENOSPC and "x.nc" in str(full)
