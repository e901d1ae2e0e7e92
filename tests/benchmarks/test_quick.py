"""Every benchmark's ``--quick`` smoke mode runs to the end (exit 0, its ratio line printed, no
warning raised at one of its own lines), so that no benchmark can break unseen. Nothing is
timed here: the figures belong to the benchmarks. One test per benchmark, so that pytest-xdist
spreads them over the workers; each ``--quick`` takes a few CPU seconds with a warm numba
cache (benchmarks/RESULTS.md, "Smoke runs")."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"
SCRIPTS = sorted(BENCHMARKS.glob("bench_*.py"))


#: A line every benchmark's ``--quick`` output must hold (its ratio or its last table).
EXPECTED = {
    "bench_bearing_alarms.py": "false alarms (a bearing cause likely)",
    "bench_cli.py": "gearvib simulate paper-case1",
    "bench_compile.py": "first call [s CPU] this / baseline",
    "bench_envelope.py": "x faster;",
    "bench_faults.py": "1 sensor + planet pin error 10 um",
    "bench_floquet.py": "stability chart, 3 speeds",
    "bench_kernel.py": "every batched variant of both kernels bit-identical",
    "bench_maps.py": "ratio scipy/ours",
    "bench_orders.py": "3. defaults of issue 29",
    "bench_readers.py": "ratio loadmat/read_mat",
    "bench_simulate.py": "side by side on",
    "bench_spectrum.py": "numpy/ours",
    "bench_stability_map.py": "identical",
    "bench_sweep.py": "speed-up 2 workers / 1 worker",
    "bench_tsa.py": "ratios analysis/straightforward",
    "bench_vold_kalman.py": "largest difference ours vs",
}

#: A warning that Python attributes to a line of a benchmark (a deprecated call of gearvib or
#: analysis, say): ``.../benchmarks/bench_x.py:90: FutureWarning: ...``.
OWN_WARNING = re.compile(r"benchmarks[/\\]bench_\w+\.py:\d+: \w*Warning")


def test_every_benchmark_is_found():
    assert len(SCRIPTS) >= 10
    assert set(EXPECTED) <= {p.name for p in SCRIPTS}


def test_own_warning_pattern():
    line = "/w/benchmarks/bench_spectrum.py:90: FutureWarning: spectrum: scaling= is deprecated"
    assert OWN_WARNING.search(line)
    assert not OWN_WARNING.search("/venv/site-packages/xarray/core.py:1: FutureWarning: x")


@pytest.mark.slow
@pytest.mark.parametrize("script", SCRIPTS, ids=[p.name for p in SCRIPTS])
def test_quick_mode_runs(script: Path, tmp_path):
    if "--quick" not in script.read_text():
        pytest.skip(f"{script.name} has no --quick mode yet")
    env = {**os.environ, "MPLBACKEND": "Agg"}
    root = str(BENCHMARKS.parent)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
    proc = subprocess.run([sys.executable, str(script), "--quick"], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=900)
    name = script.name
    assert proc.returncode == 0, f"{name} --quick failed:\n{proc.stderr[-3000:]}"
    out = proc.stdout
    assert out.strip(), f"{name} --quick printed nothing"
    assert any(ch.isdigit() for ch in out), f"{name} --quick printed no figure"
    if name in EXPECTED:
        assert EXPECTED[name] in out, out[-2000:]
    own = [line for line in proc.stderr.splitlines() if OWN_WARNING.search(line)]
    assert not own, f"{name} --quick raised warnings at its own lines:\n" + "\n".join(own)
