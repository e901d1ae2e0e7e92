"""Whole-process time of ``gearvib simulate``, ``gearvib modes`` and ``import analysis``.

Each command runs as a fresh process (``python -m gearvib ...``, as the console script does),
best of ``--repeat`` after one warm-up run (numba's cache warm, the OS file cache warm). The
goal (issue 16): a 1 s paper-case1 run-up (``gearvib simulate paper-case1 -o x.nc``, default
settings) under 1 s as a whole process. The machine is shared: the load average is printed
and the CPU seconds of each process (user + system) are given beside the wall time; with other
processes on the cores the CPU seconds are the steadier figure.

A breakdown of the simulate command follows, measured in one more process that performs the
command's steps itself with timers in between (and prepares its process as the console script
does, :func:`gearvib.cli.prepare_process`: unused modules hidden, one BLAS thread):

* start-up: interpreter start to the first line of the script,
* imports: the modules the command imports,
* set-up: reading the description, assembling the model,
* cache load: the first ``simulate`` minus a second identical one (numba loading its compiled
  kernels from the cache, and its typing registries),
* simulate: the second ``simulate`` (the computation itself),
* write: ``to_plain_dataset`` and the atomic netCDF write (netCDF4, no xarray).

``--baseline DIR`` runs the same commands against another checkout (e.g. ``/work/main``,
through ``PYTHONPATH``, its numba cache in a temporary folder) side by side, with ratios.

    python benchmarks/bench_cli.py
    python benchmarks/bench_cli.py --repeat 7 --baseline /work/main
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

_BREAKDOWN = r"""
import time
t_start = time.perf_counter()
import sys
from gearvib.cli import prepare_process
prepare_process(["simulate"])
from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, load_config
from gearvib.io import write_netcdf
from gearvib.simulate import simulate
from gearvib.simulation.settings import conditions_from_settings, read_run_settings
t_imports = time.perf_counter()
cfg, base = load_config("paper-case1")
run = read_run_settings(cfg.get("simulation", {}), {})
cond = conditions_from_settings(run)
model = assemble(gearset_from_dict(cfg, base=base))
t_setup = time.perf_counter()
kw = dict(dt=run["dt"], fs_out=run["fs_out"], gyroscopic=run["gyroscopic"], progress=False,
          config={"gearset": cfg, "run": run})
result = simulate(model, cond, **kw)
t_first = time.perf_counter()
result = simulate(model, cond, **kw)
t_second = time.perf_counter()
write_netcdf(result.to_plain_dataset(), sys.argv[1])
t_write = time.perf_counter()
print(t_imports - t_start, t_setup - t_imports, (t_first - t_setup) - (t_second - t_first),
      t_second - t_first, t_write - t_second)
"""
_PHASES = ("imports", "set-up", "cache load", "simulate", "write")


def _env(checkout: Path | None, cache: Path | None) -> dict[str, str]:
    env = dict(os.environ)
    env.setdefault("MPLBACKEND", "Agg")
    if checkout is not None:
        env["PYTHONPATH"] = str(checkout)
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = str(cache)
    return env


def _timed(cmd: list[str], env: dict[str, str], cwd: Path) -> tuple[float, float]:
    """(wall, CPU) seconds of one process."""
    before = os.times()
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, cwd=cwd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = os.times()
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}): {proc.stderr.strip()}")
    return wall, (after.children_user - before.children_user
                  + after.children_system - before.children_system)


def _best(cmd: list[str], env: dict[str, str], cwd: Path, repeat: int) -> tuple[float, float]:
    _timed(cmd, env, cwd)  # warm-up: numba cache and OS file cache
    runs = [_timed(cmd, env, cwd) for _ in range(repeat)]
    return min(w for w, _ in runs), min(c for _, c in runs)


def _startup(env: dict[str, str], cwd: Path, repeat: int) -> float:
    return min(_timed([sys.executable, "-c", "pass"], env, cwd)[0] for _ in range(repeat))


def _breakdown(env: dict[str, str], cwd: Path, repeat: int) -> list[float]:
    script = cwd / "breakdown.py"
    script.write_text(_BREAKDOWN)
    best: list[float] | None = None
    for _ in range(repeat):
        out = subprocess.run([sys.executable, str(script), str(cwd / "b.nc")], env=env,
                             cwd=cwd, capture_output=True, text=True, check=True).stdout
        vals = [float(x) for x in out.split()]
        best = vals if best is None else [min(a, b) for a, b in zip(best, vals, strict=True)]
    assert best is not None
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="timed runs per command (best counts)")
    ap.add_argument("--baseline", type=Path, help="another checkout to compare with")
    args = ap.parse_args()
    py = sys.executable
    commands = {
        "gearvib simulate paper-case1 -o x.nc": [py, "-m", "gearvib", "simulate", "paper-case1",
                                                 "-o", "x.nc", "--overwrite", "-q"],
        "gearvib modes paper-case1": [py, "-m", "gearvib", "modes", "paper-case1"],
        'python -c "import analysis"': [py, "-c", "import analysis"],
        'python -c "import gearvib.cli"': [py, "-c", "import gearvib.cli"],
    }
    print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}; "
          f"best of {args.repeat} after a warm-up; wall [s] (CPU [s])")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        env = _env(None, None)
        base_env = (_env(args.baseline.resolve(), work / "baseline-numba-cache")
                    if args.baseline else None)
        start = _startup(env, work, args.repeat)
        print(f"{'python -c pass (interpreter start)':<40s} {start:7.3f}")
        head = f"{'command':<40s} {'this':>15s}"
        if base_env:
            head += f" {'baseline':>15s} {'ratio':>6s}"
        print(head)
        for name, cmd in commands.items():
            wall, cpu = _best(cmd, env, work, args.repeat)
            line = f"{name:<40s} {wall:7.3f} ({cpu:5.2f})"
            if base_env:
                bw, bc = _best(cmd, base_env, work, args.repeat)
                line += f" {bw:7.3f} ({bc:5.2f}) {bw / wall:6.2f}"
            print(line)
        print("\nbreakdown of `gearvib simulate paper-case1` (this checkout, best of each) [s]:")
        phases = _breakdown(env, work, args.repeat)
        for name, value in zip(_PHASES, phases, strict=True):
            print(f"  {name:<12s} {value:7.3f}")
        print(f"  {'sum':<12s} {sum(phases):7.3f}  (+ interpreter start and exit)")
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
