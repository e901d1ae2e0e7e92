"""Import laziness of the command line and of ``analysis`` (issue 16: whole-process time).

Not timed (times belong in ``benchmarks/bench_cli.py``): these tests check *which* modules a
fresh interpreter holds after an import or a command, so that a heavy import cannot come back
unnoticed.
"""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys

import pytest

HEAVY = ("matplotlib", "reportlab", "dask", "distributed")


def _modules_after(code: str) -> set[str]:
    script = code + "\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))\n"
    env = {**os.environ, "MPLBACKEND": "Agg"}
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         env=env, check=True, timeout=120).stdout
    return set(json.loads(out.strip().splitlines()[-1]))


def _top(mods: set[str]) -> set[str]:
    return {m.split(".")[0] for m in mods}


def test_import_gearvib_cli_is_light():
    mods = _top(_modules_after("import gearvib.cli"))
    for name in (*HEAVY, "numpy", "scipy", "xarray", "numba", "pandas", "netCDF4"):
        assert name not in mods, f"`import gearvib.cli` imports {name}"


def test_import_analysis_is_light():
    mods = _modules_after("import analysis")
    for name in (*HEAVY, "numba", "pyfftw", "scipy"):
        assert name not in _top(mods), f"`import analysis` imports {name}"
    assert "xarray" in _top(mods)  # the accessor is registered on xarray's classes
    # the accessor still works: its methods import their modules when called
    mods = _modules_after(
        "import numpy as np, xarray as xr, analysis\n"
        "t = np.arange(2048) / 1024.0\n"
        "s = xr.DataArray(np.sin(2 * np.pi * 100 * t), dims='time', coords={'time': t})\n"
        "assert s.gearvib.spectrum().to_dataset().sizes\n"
    )
    assert "analysis.spectrum" in mods


def test_simulate_command_imports_nothing_it_does_not_need(tmp_path):
    # the console script's process: run() hides dask/cffi; the command never draws
    code = (
        "import sys\n"
        f"sys.argv = ['gearvib', 'simulate', 'paper-case1', '-o', {str(tmp_path / 'r.nc')!r},"
        " '--duration', '0.02', '-q']\n"
        "import gearvib.cli, gearvib.interrupts\n"
        "import json\n"
        "def report(code):\n"
        "    print(json.dumps({'loaded': sorted(n for n, m in sys.modules.items() if m),\n"
        "                      'hidden': sorted(n for n, m in sys.modules.items() if m is None)"
        "}), flush=True)\n"
        "    import os; os._exit(code)\n"
        "gearvib.cli.exit_now = report\n"
        "gearvib.cli.run()\n"
    )
    env = {**os.environ, "MPLBACKEND": "Agg"}
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    state = json.loads(proc.stdout.strip().splitlines()[-1])
    mods = set(state["loaded"])
    assert (tmp_path / "r.nc").is_file()
    top = _top(mods)
    for name in ("matplotlib", "reportlab", "pyfftw", "cffi", "xarray", "pandas"):
        assert name not in top, f"`gearvib simulate` imports {name}"
    assert "analysis" not in mods  # the package (its accessor imports xarray)
    for name in ("scipy.signal", "scipy.optimize", "scipy.fft", "analysis.maps"):
        assert name not in mods, f"`gearvib simulate` imports {name}"
    for name in ("dask", "distributed", "cffi"):  # hidden: sys.modules holds None for them
        assert name in state["hidden"] and name not in top
    assert "analysis.jit" in mods  # numba's cache folder (gearvib.kernels), without the package
    assert "analysis.threads" in mods  # simulate()'s one BLAS thread, without the package


@pytest.mark.parametrize(("argv", "env", "expected"), [
    (["simulate", "paper-case1"], {}, "1"),
    (["simulate", "paper-case1"], {"OPENBLAS_NUM_THREADS": "3"}, "3"),  # the user's choice
    (["-q", "simulate"], {}, "1"),
    (["sweep", "s.toml"], {}, None),  # its workers set their own
    (["modes", "paper-case1"], {}, None),
])
def test_simulate_process_runs_one_blas_thread(argv, env, expected):
    code = (
        "import os, sys, json\n"
        "from gearvib.cli import SINGLE_THREAD_VARIABLES, prepare_process\n"
        f"prepare_process({argv!r})\n"
        "import numpy\n"
        "print(json.dumps([os.environ.get(v) for v in SINGLE_THREAD_VARIABLES]))\n"
    )
    base = {k: v for k, v in os.environ.items()
            if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env={**base, **env}, check=True, timeout=60).stdout
    values = json.loads(out.strip().splitlines()[-1])
    assert values[0] == expected
    if not env:
        assert set(values) == {expected}


def test_analysis_jit_loaded_alone_then_the_package_as_usual():
    code = (
        "import sys\n"
        "from gearvib.cli import prepare_process\n"
        "prepare_process(['simulate', 'paper-case1'])\n"
        "assert 'analysis.jit' in sys.modules and 'analysis' not in sys.modules\n"
        "import gearvib.kernels\n"
        "assert 'analysis' not in sys.modules and 'xarray' not in sys.modules\n"
        "import analysis, analysis.sinc\n"
        "from analysis.jit import prepare_cache\n"
        "assert prepare_cache is sys.modules['analysis.jit'].prepare_cache\n"
        "assert 'xarray' in sys.modules\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=120).stdout
    assert out.strip().endswith("ok")


def test_modes_command_imports_neither_xarray_nor_numba():
    mods = _top(_modules_after("from gearvib.cli import main\n"
                               "assert main(['modes', 'paper-case1']) == 0"))
    for name in (*HEAVY, "xarray", "pandas", "numba", "netCDF4"):
        assert name not in mods, f"`gearvib modes` imports {name}"


@pytest.mark.parametrize(("argv", "hidden"), [
    (["simulate", "paper-case1"], {"cffi", "dask", "distributed"}),
    (["sweep", "s.toml", "-o", "out"], {"cffi"}),
])
def test_hide_unused_modules(argv, hidden):
    code = (
        "import sys\n"
        "from gearvib.cli import hide_unused_modules\n"
        f"hide_unused_modules({argv!r})\n"
        "print(sorted(n for n in ('cffi', 'dask', 'distributed') "
        "if n in sys.modules and sys.modules[n] is None))\n"
        "for n in ('dask', 'distributed'):\n"
        "    if sys.modules.get(n, 0) is None:\n"
        "        try:\n"
        "            __import__(n)\n"
        "        except ImportError:\n"
        "            pass\n"
        "        else:\n"
        "            raise SystemExit(n + ' importable')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=60).stdout
    assert set(ast.literal_eval(out)) == hidden


@pytest.mark.parametrize("config_file", [False, True])
def test_yaml_hidden_unless_numba_has_a_config_file_to_read(tmp_path, config_file):
    if config_file:  # numba reads .numba_config.yaml of the working directory with yaml
        (tmp_path / ".numba_config.yaml").write_text("debuginfo: 0\n")
    code = (
        "import sys\n"
        "from gearvib.cli import prepare_process\n"
        "prepare_process(['simulate', 'paper-case1'])\n"
        "import numba\n"
        "print(sys.modules.get('yaml', 0) is None)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=60, cwd=tmp_path).stdout
    assert out.strip().splitlines()[-1] == str(not config_file)
