"""gearvib as a user installs it: a built wheel, a fresh virtual environment, every command.

The rest of the suite imports the checkout (an editable install), which hides a module or a data
file the wheel lacks. Here the wheel is built from a copy of the sources, installed without the
checkout into a new virtual environment (the dependencies come from the test environment's
site-packages through a ``.pth`` line, so nothing is downloaded), and every subcommand runs once
from an unrelated folder. A missing subpackage, preset or data file fails here.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
SENSOR_TABLES = """
[[fault]]
kind = "crack"
member = "sun"
tooth = 3
severity = 0.4

[[sensor]]
name = "acc"
angle_deg = 90.0
housing_modes = [{ frequency_hz = 3000.0, damping_ratio = 0.02, gain = 1.0 }]

[[sensor]]
type = "tacho"
name = "tacho"
pulses_per_rev = 1
"""
SWEEP = """
title = "wheel smoke sweep"
base = "paper-case1"

[simulation]
speed_start_rpm = 1000.0
speed_end_rpm = 1200.0
duration = 0.1
fs_out = 10000.0

[[parameter]]
path = "meshes.sun.damping_ratio"
values = [0.01, 0.02]
"""


def _packages(root: Path) -> set[str]:
    return {str(p.parent.relative_to(root)).replace(os.sep, "/")
            for top in ("gearvib", "analysis") for p in (root / top).rglob("__init__.py")}


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """The wheel built from a copy of the checkout's sources (the checkout stays clean)."""
    src = tmp_path_factory.mktemp("src")
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy2(ROOT / name, src / name)
    for top in ("gearvib", "analysis"):
        shutil.copytree(ROOT / top, src / top,
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "*.nbi", "*.nbc"))
    dist = tmp_path_factory.mktemp("dist")
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps",
                        "--no-build-isolation", "--no-index", "-w", str(dist), str(src)],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    (whl,) = dist.glob("gearvib-*.whl")
    return whl


def test_wheel_holds_every_package_and_data_file(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    missing = sorted(p for p in _packages(ROOT) if f"{p}/__init__.py" not in names)
    assert not missing, f"packages missing from the wheel: {missing}"
    for folder in ("presets", "recipes"):
        data = {p.name for p in (ROOT / "gearvib" / folder).glob("*.toml")}
        assert data and all(f"gearvib/{folder}/{n}" in names for n in data), folder
    # PEP 561 markers: without them a type checker ignores the packages' annotations
    typed = {f"{p}/py.typed" for p in ("gearvib", "analysis")}
    assert typed <= names, f"py.typed missing from the wheel: {sorted(typed - names)}"
    meta = next(n for n in names if n.endswith(".dist-info/METADATA"))
    import gearvib

    assert f"Version: {gearvib.__version__}" in zipfile.ZipFile(wheel).read(meta).decode()


@pytest.fixture(scope="module")
def venv(wheel, tmp_path_factory) -> Path:
    """A fresh virtual environment with only the wheel installed (dependencies borrowed)."""
    env_dir = tmp_path_factory.mktemp("venv") / "env"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(env_dir)], check=True,
                   timeout=120)
    py = env_dir / "bin" / "python"
    site = Path(subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()"
                                "['purelib'])"], capture_output=True, text=True, check=True,
                               timeout=60).stdout.strip())
    # the test environment's site-packages, for numpy, xarray, ...: a .pth line adds the folder
    # but does not run the .pth files inside it, so the checkout's editable finder stays off
    deps = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    (site / "zz_dependencies.pth").write_text("\n".join(sorted(deps)) + "\n")
    r = subprocess.run([sys.executable, "-m", "pip", "--python", str(py), "install", "-q",
                        "--no-deps", "--no-index", str(wheel)],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    return env_dir


def _run(venv: Path, cwd: Path, *args: str, timeout: float = 900) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "NUMBA_CACHE_DIR")}
    env["MPLBACKEND"] = "Agg"
    return subprocess.run([str(venv / "bin" / "gearvib"), *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=timeout)


def test_installed_wheel_imports_from_site_packages_not_the_checkout(venv, tmp_path):
    r = subprocess.run([str(venv / "bin" / "python"), "-c",
                        "import gearvib, gearvib.diagnosis, analysis; "
                        "print(gearvib.__file__); print(analysis.__file__)"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=120,
                       env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"})
    assert r.returncode == 0, r.stderr
    for line in r.stdout.split():
        assert str(venv) in line and str(ROOT) not in line


def test_every_command_runs_from_an_unrelated_folder(venv, tmp_path):
    work = tmp_path / "elsewhere"
    work.mkdir()

    def ok(*args: str) -> str:
        r = _run(venv, work, *args)
        assert r.returncode == 0, (args, r.stderr[-2000:])
        assert "Traceback" not in r.stderr, (args, r.stderr[-2000:])
        return r.stdout

    assert "gearvib" in ok("--version")
    assert "paper-case1" in ok("preset")
    assert "sweep-damping-phasing" in ok("example")
    assert "[study]" in ok("example", "paper-cases")
    (work / "g.toml").write_text(ok("preset", "paper-case1") + SENSOR_TABLES)
    assert json.loads(ok("modes", "paper-case1", "--json"))["modes"]
    assert json.loads(ok("catalogue", "paper-case1", "--speed", "1500", "--json"))
    ok("simulate", "paper-case1", "-o", "run.nc", "--speed", "1500:1500", "--duration", "0.3",
       "--fs", "20000", "-q")
    ok("simulate", "g.toml", "-o", "meas.nc", "--speed", "1500:1500", "--duration", "1.0",
       "--fs", "20000", "-q")
    ok("report", "run.nc", "-o", "rep", "-q")
    ok("compare", "meas.nc", "run.nc", "-o", "cmp")
    ok("diagnose", "meas.nc", "--gearset", "paper-case1", "-o", "dg", "-q", "--workers", "2",
       "--revolutions", "4", "--kinds", "crack", "--json")
    (work / "study.toml").write_text(SWEEP)
    ok("sweep", "study.toml", "-o", "sw", "--workers", "1", "-q")
    ok("demo", "-o", "demo", "--duration", "0.25", "-q")
    for f in ("rep/report.html", "rep/report.pdf", "cmp/comparison.nc", "dg/diagnosis.nc",
              "dg/report.html", "sw/sweep.nc", "demo/report.html"):
        assert (work / f).stat().st_size > 1000, f
    # the installed entry point xarray.backends: engine="gearvib" gives float seconds
    r = subprocess.run([str(venv / "bin" / "python"), "-c",
                        "import xarray as xr; ds = xr.open_dataset('run.nc', engine='gearvib'); "
                        "print(ds['time'].dtype, ds['mesh'].dtype.kind)"],
                       cwd=work, capture_output=True, text=True, timeout=300,
                       env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"})
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["float64", "U"]
