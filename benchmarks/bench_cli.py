"""Whole-process time of ``gearvib simulate``, ``gearvib modes`` and ``import analysis``.

Each command runs as a fresh process (``python -m gearvib ...``, as the console script does)
after one warm-up run (numba's cache warm, the OS file cache warm); ``--repeat`` timed runs
give the median and the range of the wall time and of the CPU seconds (user + system, all
threads). The goal (issue 16): a 1 s paper-case1 run-up (``gearvib simulate paper-case1 -o
x.nc``, default settings) under 1 s as a whole process. The machine is shared: the load
average is printed, and with other processes on the cores the CPU seconds are the steadier
figure (on an idle machine the command's wall time is its CPU time, plus the fsync).

The processes run with Python's bytecode cache (``PYTHONDONTWRITEBYTECODE`` is removed from
their environment, so that the warm-up writes the ``.pyc`` files of an editable checkout, as
any installation has them); otherwise every run compiles gearvib's sources again (0.1-0.2 s).

A breakdown of the simulate command follows (CPU and wall seconds, median), measured in more
processes that perform the command's steps themselves with timers in between, and prepare
their process as the console script does (:func:`gearvib.cli.prepare_process`: unused modules
hidden, one BLAS thread):

* imports: the modules the command imports (after the interpreter's start),
* set-up: reading the description, assembling the model,
* cache load: the first ``simulate`` minus a second identical one (numba's typing and
  lowering registries, its compiled kernels loaded from the cache),
* simulate: the second ``simulate`` (the computation itself),
* write: ``to_plain_dataset`` and the atomic netCDF write (netCDF4, no xarray).

On Linux the simulate command runs once more per repeat in a process that reads its threads'
``/proc/<tid>/schedstat``: the time they spent on a CPU and waiting for one; the wall time
minus the waiting (plus the interpreter's start) estimates the wall time on an idle machine.

``--importtime`` adds ``python -X importtime`` of the simulate command: the import time of
each top-level package (its modules' own times, the minimum over the runs).

``--baseline DIR`` runs the same commands against another checkout (e.g. ``/work/main``,
through ``PYTHONPATH``, its numba cache in a temporary folder), interleaved with this one
(this, baseline, this, ...), with the ratio of the medians.

``--first-run`` times ``gearvib demo`` (or, with ``--quick``, a 0.05 s ``gearvib simulate``)
twice in a fresh numba cache folder (``NUMBA_CACHE_DIR`` pointing at a new temporary folder):
the first run compiles the kernels (with the compile helper, :mod:`gearvib.compile_helper`),
the second loads them; outside ``--quick`` a third run compiles in another fresh folder
without the helper (``GEARVIB_COMPILE_HELPER=0``), the baseline. Prints each (wall time, and
CPU time of the process and its helper) and the ratios to the second run, medians over
``--rounds`` (goal <= 1.5).

    python benchmarks/bench_cli.py
    python benchmarks/bench_cli.py --repeat 9 --baseline /work/main --importtime
    python benchmarks/bench_cli.py --first-run --rounds 3
    python benchmarks/bench_cli.py --quick     # smoke run: one run, no warm-up, no breakdown
"""

from __future__ import annotations

import argparse
import collections
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

_BREAKDOWN = r"""
import sys
import time
clock = time.process_time if sys.argv[2] == "cpu" else time.perf_counter
t_start = clock()
from gearvib.cli import prepare_process
prepare_process(["simulate"])
from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, load_config
from gearvib.io import write_netcdf
from gearvib.simulate import simulate
from gearvib.simulation.settings import conditions_from_settings, read_run_settings
t_imports = clock()
cfg, base = load_config("paper-case1")
run = read_run_settings(cfg.get("simulation", {}), {})
cond = conditions_from_settings(run)
model = assemble(gearset_from_dict(cfg, base=base))
t_setup = clock()
kw = dict(dt=run["dt"], fs_out=run["fs_out"], gyroscopic=run["gyroscopic"], progress=False,
          config={"gearset": cfg, "run": run})
result = simulate(model, cond, **kw)
t_first = clock()
result = simulate(model, cond, **kw)
t_second = clock()
write_netcdf(result.to_plain_dataset(), sys.argv[1])
t_write = clock()
print(t_imports - t_start, t_setup - t_imports, (t_first - t_setup) - (t_second - t_first),
      t_second - t_first, t_write - t_second)
"""
_PHASES = ("imports", "set-up", "cache load", "simulate", "write")

_SCHED = r"""
import _thread, os, sys, threading, time
t_start = time.perf_counter()
done = []


def sched():  # this thread's time on a CPU and waiting for one [ns] (Linux)
    with open(f"/proc/self/task/{threading.get_native_id()}/schedstat") as f:
        return [int(x) for x in f.read().split()[:2]]


real_start = _thread.start_new_thread


def start(fn, args, kwargs=None):  # the netCDF writer thread (gearvib.interrupts)
    def counted(*a, **k):
        try:
            return fn(*a, **k)
        finally:
            done.append(sched())
    return real_start(counted, args, kwargs or {})


_thread.start_new_thread = start
from gearvib.cli import main, prepare_process
argv = ["simulate", "paper-case1", "-o", sys.argv[1], "--overwrite", "-q"]
prepare_process(argv)
code = main(argv)
on, wait = sched()
for o, w in done:
    on, wait = on + o, wait + w
print(time.perf_counter() - t_start, on / 1e9, wait / 1e9)
sys.stdout.flush()
os._exit(code)
"""


def _env(checkout: Path | None, cache: Path | None) -> dict[str, str]:
    env = dict(os.environ)
    env.setdefault("MPLBACKEND", "Agg")
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # as installed: with the bytecode cache
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


def _summary(values: list[float]) -> str:
    return (f"{statistics.median(values):6.3f} [{min(values):.3f}-{max(values):.3f}]")


def _breakdown(env: dict[str, str], cwd: Path, repeat: int, clock: str) -> list[list[float]]:
    script = cwd / "breakdown.py"
    script.write_text(_BREAKDOWN)
    runs = []
    for _ in range(repeat):
        out = subprocess.run([sys.executable, str(script), str(cwd / "b.nc"), clock], env=env,
                             cwd=cwd, capture_output=True, text=True, check=True).stdout
        runs.append([float(x) for x in out.split()])
    return [list(col) for col in zip(*runs, strict=True)]


def _idle_estimate(env: dict[str, str], cwd: Path, repeat: int) -> list[list[float]]:
    """(wall, on-CPU, waiting for a CPU) of the simulate command run in a process as the console
    script runs it, from ``/proc/<tid>/schedstat`` of its threads (Linux)."""
    script = cwd / "sched.py"
    script.write_text(_SCHED)
    runs = []
    for _ in range(repeat):
        out = subprocess.run([sys.executable, str(script), str(cwd / "s.nc")], env=env,
                             cwd=cwd, capture_output=True, text=True, check=True).stdout
        runs.append([float(x) for x in out.splitlines()[-1].split()])  # after "wrote ..."
    return [list(col) for col in zip(*runs, strict=True)]


def _importtime(cmd: list[str], env: dict[str, str], cwd: Path, repeat: int) -> list[tuple]:
    """Import time [s] of each top-level package (own times of its modules, min over runs)."""
    best: dict[str, int] = {}
    for _ in range(repeat):
        err = subprocess.run([cmd[0], "-X", "importtime", *cmd[1:]], env=env, cwd=cwd,
                             capture_output=True, text=True, check=True).stderr
        for line in err.splitlines():
            if not line.startswith("import time:") or "cumulative" in line:
                continue
            own, _, name = line[len("import time:"):].split("|")
            best[name.strip()] = min(best.get(name.strip(), 10**12), int(own))
    top: collections.Counter = collections.Counter()
    for name, us in best.items():
        top[name.split(".")[0]] += us
    return [(name, us / 1e6) for name, us in top.most_common()]


def first_run(quick: bool, rounds: int = 1) -> None:
    """First against second run in a fresh numba cache folder; outside ``quick`` also the
    first run without the compile helper (``GEARVIB_COMPILE_HELPER=0``, another fresh
    cache), in ``rounds`` rounds."""
    py = sys.executable
    if quick:
        name = "gearvib simulate paper-case1 --duration 0.05"
        cmd = [py, "-m", "gearvib", "simulate", "paper-case1", "-o", "x.nc", "--overwrite",
               "--duration", "0.05"]
        runs = [("first (compiles)", "a", True), ("second (cache)", "a", True)]
    else:
        name = "gearvib demo"
        cmd = [py, "-m", "gearvib", "demo", "-o", "demo", "--overwrite", "-q"]
        runs = [("first (compiles)", "a", True), ("second (cache)", "a", True),
                ("first, no helper", "b", False)]
    print(f"{name} in a fresh numba cache folder, {rounds} round(s); load average before: "
          f"{' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    times: dict[str, list[tuple[float, float]]] = {label: [] for label, _, _ in runs}
    for _ in range(rounds):
        with tempfile.TemporaryDirectory() as tmp:
            work = Path(tmp)
            for label, cache, helper in runs:
                env = _env(None, work / f"numba-cache-{cache}")
                env["GEARVIB_COMPILE_HELPER"] = "1" if helper else "0"
                t0 = time.perf_counter()
                c0 = _children_cpu()
                proc = subprocess.run(cmd, env=env, cwd=work, capture_output=True, text=True)
                times[label].append((time.perf_counter() - t0, _children_cpu() - c0))
                if proc.returncode != 0:
                    raise RuntimeError(f"{name} failed: {proc.stderr.strip()}")
                told = "compiling the simulation kernels" in proc.stderr
                print(f"  {label:<17s} {times[label][-1][0]:7.1f} s wall, "
                      f"{times[label][-1][1]:6.1f} s CPU; first-run notice printed: {told}")

    def med(label: str, k: int) -> float:
        return statistics.median(t[k] for t in times[label])

    second = "second (cache)"
    for label in [r[0] for r in runs if r[0] != second]:
        print(f"{label} / second (medians): {med(label, 0) / med(second, 0):.2f}x wall, "
              f"{med(label, 1) / med(second, 1):.2f}x CPU (goal <= 1.5)")
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


def _children_cpu() -> float:
    """CPU seconds (user + system) of the finished child processes so far."""
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="timed runs per command")
    ap.add_argument("--baseline", type=Path, help="another checkout to compare with")
    ap.add_argument("--importtime", action="store_true",
                    help="also python -X importtime of the simulate command")
    ap.add_argument("--first-run", action="store_true",
                    help="first vs second gearvib demo in a fresh numba cache folder")
    ap.add_argument("--rounds", type=int, default=1,
                    help="--first-run: rounds of the runs (default 1)")
    ap.add_argument("--quick", action="store_true",
                    help="smoke run: one repeat of short commands, no warm-up, no breakdown")
    args = ap.parse_args()
    if args.first_run:
        first_run(args.quick, args.rounds)
        return
    if args.quick:
        args.repeat = 1
    py = sys.executable
    simulate_cmd = [py, "-m", "gearvib", "simulate", "paper-case1", "-o", "x.nc",
                    "--overwrite", "-q", *(["--duration", "0.05"] if args.quick else [])]
    commands = {
        "gearvib simulate paper-case1 -o x.nc": simulate_cmd,
        "gearvib modes paper-case1": [py, "-m", "gearvib", "modes", "paper-case1"],
        'python -c "import analysis"': [py, "-c", "import analysis"],
        'python -c "import gearvib.cli"': [py, "-c", "import gearvib.cli"],
    }
    print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}; "
          f"median [min-max] of {args.repeat} runs "
          f"{'without warm-up (--quick)' if args.quick else 'after a warm-up'}; wall and CPU [s]")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        checkouts = {"this": _env(None, None)}
        if args.baseline:
            checkouts["baseline"] = _env(args.baseline.resolve(), work / "baseline-cache")
        start = [_timed([py, "-c", "pass"], checkouts["this"], work)[0]
                 for _ in range(args.repeat)]
        print(f"{'python -c pass (interpreter start)':<38s} wall {_summary(start)}")
        for name, cmd in commands.items():
            for env in checkouts.values() if not args.quick else ():
                _timed(cmd, env, work)  # warm-up: numba cache, bytecode, OS file cache
            runs: dict[str, list[tuple[float, float]]] = {k: [] for k in checkouts}
            for _ in range(args.repeat):  # interleaved: this, baseline, this, ...
                for k, env in checkouts.items():
                    runs[k].append(_timed(cmd, env, work))
            print(name)
            for k, r in runs.items():
                walls, cpus = [w for w, _ in r], [c for _, c in r]
                line = f"  {k:<36s} wall {_summary(walls)}  CPU {_summary(cpus)}"
                if k != "this":  # the baseline's median over this checkout's
                    w0 = statistics.median(w for w, _ in runs["this"])
                    c0 = statistics.median(c for _, c in runs["this"])
                    line += (f"  ratio wall {statistics.median(walls) / w0:.2f} "
                             f"CPU {statistics.median(cpus) / c0:.2f}")
                print(line)
        if args.quick:
            print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
            return
        print("\nbreakdown of `gearvib simulate paper-case1` (this checkout), median "
              "[min-max] [s]:")
        cpu = _breakdown(checkouts["this"], work, args.repeat, "cpu")
        wall = _breakdown(checkouts["this"], work, args.repeat, "wall")
        for name, c, w in zip(_PHASES, cpu, wall, strict=True):
            print(f"  {name:<12s} CPU {_summary(c)}  wall {_summary(w)}")
        print(f"  {'sum':<12s} CPU {sum(statistics.median(c) for c in cpu):6.3f}  wall "
              f"{sum(statistics.median(w) for w in wall):6.3f}  (+ interpreter start and exit)")
        if os.path.exists("/proc/self/task"):
            start_cpu = [_timed([py, "-c", "pass"], checkouts["this"], work)[1]
                         for _ in range(args.repeat)]
            wall, on, wait = _idle_estimate(checkouts["this"], work, args.repeat)
            idle = [w - q + statistics.median(start_cpu) for w, q in zip(wall, wait, strict=True)]
            print("\nthe simulate command on a loaded machine, its threads' time from "
                  "/proc/<tid>/schedstat [s]:\n"
                  f"  wall after the interpreter's start {_summary(wall)}\n"
                  f"  on a CPU                           {_summary(on)}\n"
                  f"  waiting for a CPU                  {_summary(wait)}\n"
                  f"  estimate for an idle machine       {_summary(idle)}  (wall - waiting + "
                  "the interpreter's start; waits of the main thread while the writer "
                  "thread works overlap: a slight underestimate)")
        if args.importtime:
            print("\npython -X importtime of the simulate command: own import times of each "
                  "top-level package [s] (min over the runs)")
            top = _importtime(simulate_cmd, checkouts["this"], work, args.repeat)
            total = sum(t for _, t in top)
            for name, t in top[:14]:
                print(f"  {name:<24s} {t:6.3f}")
            print(f"  {'total':<24s} {total:6.3f}")
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
