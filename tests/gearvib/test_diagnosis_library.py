"""The candidate library of the diagnosis and the operating point its entries are keyed by
(fast tests; the diagnoses that reuse it are in test_diagnosis.py)."""

import math
import os
import stat

import numpy as np
import pytest

from analysis.diagnosis import order_profile
from gearvib import tempfiles
from gearvib.diagnosis import engine
from gearvib.diagnosis.library import (
    code_digest,
    default_library,
    entry_key,
    entry_path,
    library_folder,
    load_entry,
    save_entry,
    source_digest,
)


def _arrays(seed=0):
    rng = np.random.default_rng(seed)
    return {"order": np.arange(100) / 16, "amplitude": rng.random((4, 100)),
            "segments": np.array(3), "natural_frequency": np.array([0.0, 1261.0, 1798.0])}


def test_entry_round_trip_bit_for_bit(tmp_path):
    folder = library_folder(tmp_path / "lib")
    assert folder.name == code_digest() and folder.parent == tmp_path / "lib"
    key, text = entry_key({"b": [1, 2.5], "a": "x"})
    assert entry_key({"a": "x", "b": [1, 2.5]}) == (key, text)  # canonical JSON
    a = _arrays()
    save_entry(folder, key, text, a)
    b = load_entry(folder, key, text)
    for k in a:
        assert np.array_equal(a[k], b[k]) and a[k].dtype == b[k].dtype
    # nothing else left in the folder (atomic write: the temporary file was renamed)
    assert [p.name for p in folder.iterdir()] == [f"{key}.npz"]


def test_missing_foreign_and_broken_entries_count_as_missing(tmp_path):
    folder = library_folder(tmp_path)
    key, text = entry_key({"case": 1})
    assert load_entry(folder, key, text) is None
    save_entry(folder, key, text, _arrays())
    assert load_entry(folder, key, text + " ") is None  # another description, same file name
    data = entry_path(folder, key).read_bytes()
    entry_path(folder, key).write_bytes(data[: len(data) // 2])  # truncated (a full disk)
    assert load_entry(folder, key, text) is None
    entry_path(folder, key).write_bytes(b"")
    assert load_entry(folder, key, text) is None


def test_stale_temporaries_of_dead_writers_are_removed(tmp_path):
    folder = library_folder(tmp_path)
    dead = folder / f".x.npz.gearvib-{tempfiles.host_tag()}-999999999-abcdefgh.tmp"
    dead.write_bytes(b"half")
    assert library_folder(tmp_path) == folder
    assert not dead.exists()


@pytest.mark.skipif(not hasattr(os, "getuid"), reason="POSIX ownership")
def test_a_folder_others_can_write_is_refused(tmp_path):
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    with pytest.raises(PermissionError, match="private"):
        library_folder(shared)
    made = library_folder(tmp_path / "new")
    assert stat.S_IMODE(made.stat().st_mode) == 0o700


def test_the_digest_follows_the_source_not_the_generated_modules(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "__pycache__" / "specialised").mkdir(parents=True)
    (pkg / "a.py").write_text("x = 1\n")
    d0 = source_digest([pkg]).hexdigest()
    (pkg / "__pycache__" / "specialised" / "fault_pass_1.py").write_text("y = 2\n")
    assert source_digest([pkg]).hexdigest() == d0
    (pkg / "a.py").write_text("x = 2\n")
    assert source_digest([pkg]).hexdigest() != d0
    (pkg / "a.py").write_text("x = 1\n")
    (pkg / "b.py").write_text("")
    assert source_digest([pkg]).hexdigest() != d0


def test_default_folder(monkeypatch, tmp_path):
    monkeypatch.setenv("GEARVIB_DIAGNOSIS_LIBRARY", str(tmp_path / "x"))
    assert default_library() == tmp_path / "x"
    monkeypatch.delenv("GEARVIB_DIAGNOSIS_LIBRARY")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "c"))
    assert default_library() == tmp_path / "c" / "gearvib" / "diagnosis"


def test_operating_point_grid():
    op = engine.operating_point
    # records within +-0.25 % of a grid speed share it
    g = op(1500.0, 1500.0)[0]
    assert abs(g / 1500.0 - 1) <= engine.SPEED_STEP / 2
    assert op(g * 1.0024, g * 1.0024) == op(g * 0.9976, g * 0.9976) == (g, g)
    assert op(g * 1.0026, g * 1.0026) != (g, g) != op(g * 0.9974, g * 0.9974)
    # a ramp stays a ramp (span rounded to 1 % of the mean), a fluctuation is constant
    s, e = op(1300.0, 1700.0)
    assert e - s == pytest.approx(400.0, abs=0.006 * 1500) and s < e
    s, e = op(1700.0, 1300.0)
    assert s > e
    s, e = op(1497.0, 1503.0)
    assert s == e
    # exact functions of the grid indices: the same bits for every record of the point
    assert op(1300.2, 1699.9) == op(1299.9, 1700.1)
    for bad in ((0.0, 100.0), (-5.0, -5.0), (math.nan, 1500.0), (1500.0, math.inf)):
        with pytest.raises(ValueError, match="standstill"):
            op(*bad)


@pytest.mark.parametrize("speeds", [(1500.0, 1500.0), (1305.0, 1695.0), (2000.0, 1100.0)])
@pytest.mark.parametrize("revolutions", [4, 16])
def test_simulated_duration_gives_the_profile_its_segments(speeds, revolutions):
    """The run of a candidate holds SIM_SEGMENTS segments after the start-up, on its ramp."""
    ipc = 147 / 33  # paper-case1: input (sun) revolutions per carrier revolution
    dur = engine.simulated_duration(*speeds, ipc, revolutions)
    fs = 5000.0
    t = np.arange(round(dur * fs) + 1) / fs
    rpm_in = speeds[0] + (speeds[1] - speeds[0]) * t / t[-1]
    x = np.random.default_rng(0).standard_normal(t.size)
    p = order_profile(x, fs, rpm_in / ipc, max_order=50.0, revolutions=revolutions,
                      skip_s=engine.SKIP_S)
    assert p.segments == engine.SIM_SEGMENTS


def test_keep_runs_needs_a_work_dir(tmp_path):
    from gearvib.diagnosis import Record, diagnose

    rec = Record(np.zeros(100), 1000.0, np.full(100, 1000.0))
    with pytest.raises(ValueError, match="work_dir"):
        diagnose(rec, "paper-case1", library=tmp_path, keep_runs=True)
