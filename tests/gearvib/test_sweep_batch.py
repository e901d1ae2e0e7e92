"""Sweeps on the batched kernel: run files and sweep.nc bit-identical to case-by-case runs."""

from __future__ import annotations

from pathlib import Path

import pytest
import xarray as xr

from gearvib.sweep import run_sweep, sweep_from_dict
from gearvib.sweep.case import CaseTask
from gearvib.sweep.runner import batch_units

SPEC = {
    "title": "batched",
    "base": "paper-case1",
    "simulation": {"speed_start_rpm": 2700.0, "speed_end_rpm": 2900.0, "duration": 0.02},
    "parameter": [
        {"path": "meshes.sun.damping_ratio", "values": [0.005, 0.01, 0.02]},
        {"path": "meshes.ring.damping_ratio", "values": [0.01, 0.02]},
    ],
    "summary": {"orders": [1, 2], "order_resolution": 0.25, "floquet_speed_rpm": [2750, 2850],
                "floquet_points": 2},
}


def _same_folders(a: Path, b: Path) -> None:
    names = sorted(p.name for p in (a / "runs").glob("*.nc"))
    assert names == sorted(p.name for p in (b / "runs").glob("*.nc")) and names
    for name in names:
        assert (a / "runs" / name).read_bytes() == (b / "runs" / name).read_bytes(), name
    with xr.open_dataset(a / "sweep.nc") as fa, xr.open_dataset(b / "sweep.nc") as fb:
        xr.testing.assert_identical(fa.load(), fb.load())
    assert (a / "sweep.nc").read_bytes() == (b / "sweep.nc").read_bytes()


@pytest.mark.parametrize("extra", [None, "mixed"])
def test_batched_sweep_is_bit_identical_to_case_by_case(tmp_path, extra):
    spec = dict(SPEC)
    if extra == "mixed":
        # a planet-angle parameter (mesh phases: batchable values) and an undamped ring mesh
        spec["parameter"] = [
            {"path": "meshes.sun.damping_ratio", "values": [0.005, 0.02]},
            {"path": "meshes.ring.damping_ratio", "values": [0.01, 0.0]},
            {"path": "geometry.planet_angles_deg",
             "values": [[0, 120, 240], [0, 122.45, 244.90]], "labels": ["equal", "case2"]},
        ]
    sweep = sweep_from_dict(spec)
    seen = []
    single = run_sweep(sweep, tmp_path / "single", workers=1, progress=False, report=False,
                       batch=False)
    batched = run_sweep(sweep, tmp_path / "batched", workers=1, progress=False, report=False,
                        batch=True, on_case_done=seen.append)
    assert sorted(o.index for o in seen) == list(range(sweep.n_cases))
    assert batched.simulated == single.simulated and batched.failed == single.failed
    _same_folders(tmp_path / "single", tmp_path / "batched")
    # resuming a batched sweep reuses every run file
    again = run_sweep(sweep, tmp_path / "batched", workers=1, progress=False, report=False,
                      batch=True)
    assert again.reused == single.simulated
    assert (tmp_path / "batched" / "sweep.nc").read_bytes() == \
        (tmp_path / "single" / "sweep.nc").read_bytes()


def test_not_batchable_cases_run_one_by_one(tmp_path):
    """Cases that cannot share a batch (a 100x stiffer bearing moves the default time grid)
    are batched by time grid (here two batches of two damping variants): same results."""
    spec = dict(SPEC, base="paper-case1-elastic", parameter=[
        {"path": "bodies.planet.support.radial", "values": [1.5e8, 1.5e10]},
        {"path": "meshes.sun.damping_ratio", "values": [0.01, 0.02]}])
    sweep = sweep_from_dict(spec)
    single = run_sweep(sweep, tmp_path / "single", workers=1, progress=False, report=False,
                       batch=False)
    batched = run_sweep(sweep, tmp_path / "batched", workers=1, progress=False, report=False,
                        batch=True)
    assert batched.simulated == single.simulated == (0, 1, 2, 3)
    _same_folders(tmp_path / "single", tmp_path / "batched")


def test_batch_units():
    sweep = sweep_from_dict({**SPEC, "parameter": [
        {"path": "meshes.sun.damping_ratio", "values": [0.005 * (1 + k) for k in range(18)]}]})
    tasks = [CaseTask(c, f"/x/{c.index}.nc", sweep.summary) for c in sweep.cases()]
    sizes = [len(u) if isinstance(u, list) else 1 for u in batch_units(tasks, 1, None)]
    assert sizes == [6, 6, 6]  # 3 batches of at most 8, evenly
    assert all(not isinstance(u, list) for u in batch_units(tasks, 1, False))
    # automatic: at least one batch per worker while batches keep >= MIN_AUTO_BATCH (3) cases
    sizes = [len(u) if isinstance(u, list) else 1 for u in batch_units(tasks[:8], 2, None)]
    assert sizes == [4, 4]
    assert [len(u) for u in batch_units(tasks[:6], 2, None)] == [3, 3]
    assert [len(u) for u in batch_units(tasks[:3], 1, None)] == [3]
    assert [len(u) if isinstance(u, list) else 1 for u in batch_units(tasks[:2], 1, None)] \
        == [1, 1]
    # 4 cases on 2 workers: single runs in parallel beat a batch of 4 on one worker
    assert [len(u) if isinstance(u, list) else 1 for u in batch_units(tasks[:4], 2, None)] \
        == [1, 1, 1, 1]
    assert [len(u) for u in batch_units(tasks[:4], 1, None)] == [4]
    assert [len(u) for u in batch_units(tasks[:3], 1, True)] == [3]
    # other run settings: other candidates
    other = sweep_from_dict({**SPEC, "simulation": {**SPEC["simulation"], "duration": 0.01},
                             "parameter": SPEC["parameter"][:1]})
    mixed = tasks[:4] + [CaseTask(c, "/y.nc", other.summary) for c in other.cases()]
    assert [len(u) if isinstance(u, list) else 1 for u in batch_units(mixed, 1, True)] == [4, 3]


def test_sweep_without_run_files(tmp_path):
    """run_files=False: no run file, the same summaries (sweep.nc bit-identical batched and
    case by case; equal to a sweep with run files but for the ``run_file`` coordinate)."""
    sweep = sweep_from_dict(dict(SPEC, summary={"orders": [1, 2], "order_resolution": 0.25}))
    kw = dict(workers=1, progress=False, report=False)
    with_files = run_sweep(sweep, tmp_path / "files", batch=True, **kw)
    single = run_sweep(sweep, tmp_path / "single", batch=False, run_files=False, **kw)
    batched = run_sweep(sweep, tmp_path / "batched", batch=True, run_files=False, **kw)
    assert single.simulated == batched.simulated == with_files.simulated
    assert len(single.simulated) == sweep.n_cases
    for name in ("single", "batched"):
        assert not list((tmp_path / name / "runs").glob("*.nc"))
    assert (tmp_path / "single" / "sweep.nc").read_bytes() == \
        (tmp_path / "batched" / "sweep.nc").read_bytes()
    with xr.open_dataset(tmp_path / "batched" / "sweep.nc") as fb, \
            xr.open_dataset(tmp_path / "files" / "sweep.nc") as ff:
        fb, ff = fb.load(), ff.load()
    assert list(fb.run_file.values) == [""] * sweep.n_cases
    assert all(f.startswith("runs/") for f in ff.run_file.values)
    xr.testing.assert_identical(fb.drop_vars("run_file"), ff.drop_vars("run_file"))
    # finished run files in the folder are still reused, and nothing is written
    again = run_sweep(sweep, tmp_path / "files", batch=True, run_files=False, **kw)
    assert again.reused == with_files.simulated
    with pytest.raises(TypeError, match="run_files"):
        run_sweep(sweep, tmp_path / "x", run_files=0, **kw)
