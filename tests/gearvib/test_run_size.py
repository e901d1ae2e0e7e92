"""Sizes computed from input are checked before allocating; the output rate must hold the mesh
frequency; report maps and charts are bounded.

The issue's inputs (``--fs 1e-3 --duration 0.05``: a 2.5e9-tap filter, OOM-killed at 22.8 GB;
``--speed 0:1e9``; a planet bearing stiffness of 1e38 N/m) run in a subprocess under an
address-space limit of 2.5 GiB (``RLIMIT_AS``): each must be refused quickly with exit code 2
and a message naming the parameter, the size and a remedy -- a regression that allocates
would fail with a ``MemoryError`` or a crash instead.
"""

from __future__ import annotations

import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from gearvib.config import ConfigError, load_config
from gearvib.memory import RunSizeError, available_memory, format_bytes, require_memory
from gearvib.report.study import AnalysisSettings, check_report_size, load_study
from gearvib.simulation.decimation import decimation_filter, filter_length
from gearvib.simulation.run_size import check_run_size
from gearvib.simulation.step import choose_step

LIMIT = int(2.5 * 2**30)
PRESET = Path(__file__).resolve().parents[2] / "gearvib" / "presets" / "paper-case1.toml"


def limited_gearvib(args: list[str], cwd: Path, limit: int = LIMIT) -> tuple[int, str, float]:
    """``python -m gearvib *args`` under ``RLIMIT_AS = limit``; (exit code, stderr, seconds)."""
    code = (f"import resource, sys; resource.setrlimit(resource.RLIMIT_AS, ({limit}, {limit}))\n"
            "from gearvib.cli import main\nsys.exit(main(sys.argv[1:]))")
    t0 = time.monotonic()
    res = subprocess.run([sys.executable, "-c", code, *args], cwd=cwd, capture_output=True,
                         text=True, check=False, timeout=300)
    return res.returncode, res.stderr, time.monotonic() - t0


@pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_AS and /proc")
@pytest.mark.parametrize("args, match", [
    (["--fs", "1e-3", "--duration", "0.05"],
     r"fs_out = 0.001 Hz .* cannot represent the highest mesh frequency 1706.12 Hz"),
    (["--speed", "0:1e9", "--duration", "0.05"],
     r"fs_out = 25000 Hz .*mesh frequency 4.26531e\+08 Hz of the run \(at 1e\+09 min-1\)"),
    (["--speed", "0:0", "--fs", "1e-3", "--duration", "0.05"],
     r"needs 1.27e\+09 internal steps \(the anti-alias filter from 1/dt = 9.43e\+04 Hz down to "
     r"fs_out = 0.001 Hz"),
    (["--speed", "0:0", "--fs", "1e-3", "--duration", "0.05", "--max-steps", "1000000000000"],
     r"the anti-alias filter \(2.53e\+09 taps and a record .* fs_out = 0.001 Hz\) needs 1.1\d "
     r"TiB of memory, .* available: raise fs_out"),
    (["--duration", "300", "--max-steps", "1000000000000"],
     r"the output \(7.5e\+06 samples of 44 signals: duration 300 s at fs_out = 2.5e\+04 Hz\) "
     r"needs 7.38 GiB of memory, .* available: shorten the duration or lower fs_out"),
    (["--duration", "1e6"], r"needs 1e\+11 internal steps .*more than the limit max_steps"),
])
def test_the_issues_sizes_are_refused_without_allocating(tmp_path, args, match):
    import re

    code, err, seconds = limited_gearvib(["simulate", "paper-case1", "-o", "x.nc", *args],
                                         tmp_path)
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and err.startswith("gearvib: error:"), err
    assert re.search(match, err), err
    assert seconds < 60  # refused before the work (start-up and the modal analysis only)
    assert not list(tmp_path.iterdir())


@pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_AS")
def test_a_planet_bearing_of_1e38_is_refused_for_its_steps(tmp_path):
    text = PRESET.read_text()
    assert "[bodies.planet]" in text
    bad = tmp_path / "stiff.toml"
    start = text.index("[bodies.planet]")
    end = text.index("\n[", start + 1)
    planet = text[start:end]
    new = planet.split("support")[0] + 'support = { radial = 1e38, tangential = 1e38, ' \
        'axial = "rigid", torsional = "free" }\n'
    bad.write_text(text[:start] + new + text[end:])
    code, err, _ = limited_gearvib(["simulate", str(bad), "-o", "x.nc", "--duration", "0.05"],
                                   tmp_path)
    assert code == 2, err
    assert "highest natural frequency 1.951e+18 Hz: a very stiff support" in err, err
    assert "internal steps" in err and "max_steps" in err


def test_filter_length_matches_the_designed_filter():
    for dec in (1, 2, 7, 10, 100):
        assert filter_length(dec) == decimation_filter(dec).size
    assert filter_length(10**20) > 10**21  # estimated without overflow, nothing designed


def _step(dt=1e-5, fs=20000.0, dec=5, f_nat=2000.0, f_mesh=1700.0):
    from gearvib.simulation.step import StepChoice

    return StepChoice(dt, fs, dec, 1 / (40 * max(f_nat, f_mesh)), 1 / (10 * f_nat), f_nat,
                      f_mesh)


def test_check_run_size_counts_steps_and_memory(monkeypatch):
    size = check_run_size(_step(), 1.0, n_dof=5, n_mesh=6, n_signals=28, n_stored=44)
    taps = filter_length(5)
    assert size.n_out == 20001 and size.taps == taps
    assert size.steps == 20000 * 5 + (taps - 1) // 2 + 1  # the simulate() loop's last sample+1
    with pytest.raises(RunSizeError, match=r"needs 1e\+05 internal steps .*max_steps = 1e\+04"):
        check_run_size(_step(), 1.0, n_dof=5, n_mesh=6, n_signals=28, n_stored=44,
                       max_steps=10_000)
    # the output: 3 copies of n_out x 44 values, against a machine with 10 MiB free
    monkeypatch.setattr("gearvib.memory.available_memory", lambda: 10 * 2**20)
    with pytest.raises(RunSizeError, match=r"the output \(2e\+04 samples of 44 signals"):
        check_run_size(_step(), 1.0, n_dof=5, n_mesh=6, n_signals=28, n_stored=44)


def test_require_memory_and_available_memory():
    free = available_memory()
    assert 0 < free <= 1 << 62
    require_memory(1024, "a kilobyte", "none")
    with pytest.raises(RunSizeError, match=r"the thing needs 8 EiB of memory, .* available: "
                                           r"buy more"):
        require_memory(2.0**63, "the thing", "buy more")
    assert format_bytes(1536) == "1.5 KiB"


def test_output_rate_must_hold_the_mesh_frequency():
    # the issue: --fs 1000 with a 1706 Hz mesh frequency
    with pytest.raises(ConfigError, match=r"fs_out = 1000 Hz .*1706 Hz .*>= 5687 Hz"):
        choose_step(2358.0, 1706.0, fs_out=1000.0)
    # at the flat-band edge 0.3 fs_out it is accepted
    assert choose_step(2358.0, 1706.0, fs_out=1706.0 / 0.3 + 1).fs_out > 5687
    # the default keeps 3 mesh harmonics flat: 20 kHz up to 2 kHz, above that 10 f_mesh
    assert choose_step(2358.0, 1706.0).fs_out == 20_000
    c = choose_step(10_000.0, 4000.0)
    assert c.fs_out == 40_000 and 0.3 * c.fs_out >= 3 * 4000
    c = choose_step(10_000.0, 4000.0, dt=1 / 800_000)
    assert c.fs_out == pytest.approx(40_000, rel=1e-12) and c.decimation == 20


def test_a_run_refused_for_its_size_raises_before_the_static_equilibrium(monkeypatch):
    from gearvib.assembly import assemble
    from gearvib.config import gearset_from_dict
    from gearvib.simulate import SpeedRamp, simulate

    def boom(*a, **k):
        raise AssertionError("static equilibrium reached")

    monkeypatch.setattr("gearvib.simulate.static_equilibrium", boom)
    model = assemble(gearset_from_dict(load_config("paper-case1")[0]))
    with pytest.raises(RunSizeError, match="internal steps"):
        simulate(model, SpeedRamp(0, 4000, 0.05), dt=1e-13)


# --------------------------------------------------------------------------- report sizes


def test_report_maps_are_bounded_before_anything_runs(tmp_path):
    # 1 s at 25 kHz, 20 Hz resolution, 0.9 overlap: 133 frames of 938 bins -- fine
    check_report_size(25001, 25000.0, AnalysisSettings())
    a = AnalysisSettings(map_overlap=0.99999, map_resolution_hz=0.5)
    with pytest.raises(RunSizeError, match=r"map_overlap = 0.99999, map_resolution_hz = 0.5"):
        check_report_size(25000 * 600 + 1, 25000.0, a, "case 'long'")
    recipe = tmp_path / "study.toml"
    recipe.write_text('[study]\ncases = [{name = "a", config = "paper-case1"}]\n'
                      '[run]\nduration = 600.0\n[analysis]\nmap_overlap = 0.99999\n'
                      'map_resolution_hz = 0.5\n')
    from gearvib.report import run_study

    t0 = time.monotonic()
    with pytest.raises(RunSizeError, match=r"lower \[analysis\]\.map_overlap"):
        run_study(load_study(recipe), tmp_path / "out", progress=False)
    assert time.monotonic() - t0 < 10  # refused before the 600 s simulation


@pytest.mark.parametrize("key, value, match", [
    ("stability_points", 10**6, r"stability_points = 1000000; admissible: an integer >= 2 and "
                                r"<= 20000"),
    ("n_max", 1000, r"n_max = 1000"),
    ("orders", 10**20, r"orders = 1000"),
    ("map_resolution_hz", math.inf, r"map_resolution_hz = inf; admissible: a finite"),
    ("threshold_db", 10**400, r"threshold_db = 1000.*admissible: a finite number"),
    ("spectrum_peaks", 1.5, r"spectrum_peaks = 1.5; admissible: an integer"),
])
def test_recipe_analysis_keys_are_range_checked(key, value, match):
    with pytest.raises(ConfigError, match=match):
        AnalysisSettings.from_dict({key: value})


def test_a_fir_of_the_admitted_size_is_still_alias_free():
    """The guards do not change the filter: decimation 10 keeps >= 80 dB above fs_out/2."""
    import scipy.signal

    taps = decimation_filter(10)
    w, h = scipy.signal.freqz(taps, worN=8192, fs=1.0)
    assert np.all(20 * np.log10(np.abs(h[w >= 0.05]) + 1e-300) <= -80.0)


@pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_AS")
def test_a_run_file_declaring_2_31_records_is_refused_before_loading(tmp_path):
    """A netCDF-3 header claiming 2^31 - 1 records of a 380-byte file: xarray would load the
    time index (16 GiB) while opening; the declared size is checked first."""
    import xarray as xr

    ds = xr.Dataset({"normal_force": (("time",), np.arange(10.0))},
                    coords={"time": np.arange(10.0)}, attrs={"source": "gearvib test"})
    good = tmp_path / "small.nc"
    ds.to_netcdf(good, format="NETCDF3_CLASSIC", unlimited_dims=["time"])
    data = bytearray(good.read_bytes())
    assert data[:4] == b"CDF\x01"
    data[4:8] = (2**31 - 1).to_bytes(4, "big")  # numrecs
    bad = tmp_path / "huge.nc"
    bad.write_bytes(bytes(data))
    code, err, _ = limited_gearvib(["report", str(bad), "-o", "rep", "-q"], tmp_path)
    assert code == 2, err
    assert "huge.nc declares 32 GiB of data in" in err and "header is corrupt" in err, err
    assert not (tmp_path / "rep").exists()
