"""Every benchmark's ``--quick`` smoke mode runs to the end (exit 0, some output), so that no
benchmark can break unseen. Nothing is timed here: the figures belong to the benchmarks."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"
SCRIPTS = sorted(BENCHMARKS.glob("bench_*.py"))

# a line every benchmark's --quick output must hold (a ratio, a table header, ...)
EXPECTED = {
    "bench_cli.py": "gearvib simulate paper-case1",
    "bench_sweep.py": "speed-up 2 workers / 1 worker",
}


def test_every_benchmark_is_found():
    assert len(SCRIPTS) >= 10


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
    assert proc.returncode == 0, f"{script.name} --quick failed:\n{proc.stderr[-3000:]}"
    out = proc.stdout
    assert out.strip(), f"{script.name} --quick printed nothing"
    assert any(ch.isdigit() for ch in out), f"{script.name} --quick printed no figure"
    if script.name in EXPECTED:
        assert EXPECTED[script.name] in out, out[-2000:]
