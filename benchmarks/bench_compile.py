"""Benchmark of the first run's compilation and of the kernel's run time (not a timed test).

Run ``python3 benchmarks/bench_compile.py [--quick] [--baseline PATH] [--rounds N]``. The first
``gearvib simulate`` on a machine compiles the run-up kernel
(:func:`gearvib.kernels.integrate_chunk`) and, for a model with faults, its faulty-mesh pass
(:mod:`gearvib.fault_pass`); later runs load both from numba's cache. For ``paper-case1``
healthy and with a 30 % sun crack it prints, side by side for this checkout and a baseline
checkout (``--baseline PATH``, required outside ``--quick``: another git worktree of the
project, e.g. ``git worktree add ../base <commit>``):

* **first call [s CPU]**: CPU time of the first call of the kernel in a fresh process with an
  empty numba cache (its own ``NUMBA_CACHE_DIR``): the compilation of the kernel and of every
  function it calls, and for the faulty case the compilation of its faulty-mesh pass;
* **steps/s**: the kernel's run time afterwards, RK4 steps per CPU second over a window of the
  1 s run-up 0 -> 4000 min^-1 at 60 N m with the preset's own drive (``--window`` simulated
  seconds from t = 0.4 s, the median of ``--reps`` windows), and a check value of the last
  recorded row (equal for both checkouts: the same results). ``--warm`` compares the run time
  alone, on the user's numba cache (each checkout compiles once, then loads its kernel).

The two checkouts run alternately (A, B, A, B, ...) in fresh processes, each process on a new
cache folder; the medians over the rounds and their ratios are printed with the load average
(``os.getloadavg``) before and after. Each process runs under the checkout's own code
(``PYTHONPATH``); the benchmark's own :mod:`bench_kernel` of that checkout builds the case.

``--quick`` is a smoke run: one process of this checkout on the user's numba cache (no fresh
compilation; the first call then loads the kernel), a 2 ms window, no baseline.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from statistics import median

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
#: The cases: (label, preset, faults as code evaluated with gearvib.faults imported).
CASES = {
    "healthy": ("paper-case1", None),
    "crack": ("paper-case1", "[Crack('sun', 3, severity=0.3)]"),
}
T_START = 0.4

_WORKER = r'''
import json, os, sys, time
root, preset, faults, window, reps = sys.argv[1:6]
sys.path.insert(0, os.path.join(root, "benchmarks"))
import numpy as np
from numba.core import event
compile_cpu = [0.0]
class _Listener(event.Listener):  # numba's compile events of top-level dispatchers
    def __init__(self):
        self.depth = 0
        self.start = 0.0
    def on_start(self, ev):
        if self.depth == 0:
            self.start = time.process_time()
        self.depth += 1
    def on_end(self, ev):
        self.depth -= 1
        if self.depth == 0:
            compile_cpu[0] += time.process_time() - self.start
event.register("numba:compile", _Listener())
from bench_kernel import Case
from gearvib import kernels as kn
from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, load_config
from gearvib.fault_pass import with_fault_pass
from gearvib.faults import Crack  # noqa: F401 (the fault expressions)
cfg, base = load_config(preset)
model = assemble(gearset_from_dict(cfg, base=base))
if faults != "None":
    model = model.with_faults(eval(faults))
from gearvib.simulation.settings import conditions_from_settings, read_run_settings
case = Case(model, conditions_from_settings(read_run_settings(cfg.get("simulation", {}))), 0.0)
compile_cpu[0] = 0.0  # the case's own helpers (speed profile, ...) are not the kernel's
c0 = time.process_time()
case.packed = with_fault_pass(case.packed)
y = case.y0.copy()
case.run_numba(y, 0, 2)
first = time.process_time() - c0
n0 = round(float(os.environ["BENCH_T_START"]) / case.dt)
case.run_numba(y, 2, n0 - 2)
nw = max(2, round(float(window) / case.dt))
rates = []
for _ in range(int(reps)):
    yy = y.copy()
    c0 = time.process_time()
    rec = case.run_numba(yy, n0, nw)
    rates.append(nw / (time.process_time() - c0))
print(json.dumps({"first": first, "numba": compile_cpu[0], "rates": rates,
                  "check": float(rec[-1].sum())}))
'''


def run_worker(root: str, case: str, window: float, reps: int, fresh: bool) -> dict:
    """One process of checkout ``root``: first call and run time of ``case``."""
    preset, faults = CASES[case]
    env = {**os.environ, "PYTHONPATH": root, "BENCH_T_START": str(T_START),
           "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    with tempfile.TemporaryDirectory(prefix="bench_compile_") as cache:
        if fresh:
            env["NUMBA_CACHE_DIR"] = cache
        proc = subprocess.run([sys.executable, "-c", _WORKER, root, preset, str(faults),
                               str(window), str(reps)], env=env, capture_output=True,
                              text=True, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"worker of {root} ({case}) failed:\n{proc.stderr[-3000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _spread(x: list[float]) -> str:
    return f"{min(x):.3g}-{max(x):.3g}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: this checkout, warm cache, tiny window")
    parser.add_argument("--baseline", metavar="PATH",
                        help="checkout to compare with (required outside --quick), e.g. a "
                             "worktree made by `git worktree add ../base <commit>`")
    parser.add_argument("--rounds", type=int, default=3, help="A/B rounds (default 3)")
    parser.add_argument("--case", action="append", choices=sorted(CASES),
                        help="case (repeatable; default all)")
    parser.add_argument("--window", type=float, default=0.02,
                        help="simulated seconds of the run-time window (default 0.02)")
    parser.add_argument("--reps", type=int, default=20, help="windows per process (default 20)")
    parser.add_argument("--warm", action="store_true",
                        help="run time only: the user's numba cache (compiled once, then "
                             "loaded), no fresh compilation")
    args = parser.parse_args()
    cases = args.case or list(CASES)
    if args.quick:
        res = run_worker(ROOT, "healthy", 0.002, 1, fresh=False)
        how = "compiled" if res["numba"] > 0.5 else "loaded from the cache"
        print(f"quick: paper-case1 first call {res['first']:.2f} s CPU ({how}), "
              f"{median(res['rates']):.0f} steps/s, check {res['check']:.6g}")
        print("first call [s CPU] this / baseline: (not measured in --quick)")
        return
    if not args.baseline:
        parser.error("--baseline PATH is required outside --quick (a checkout of the project "
                     "to compare with)")
    if not os.path.isfile(os.path.join(args.baseline, "gearvib", "kernels.py")):
        parser.error(f"--baseline {args.baseline!r} is not a checkout of gearvib (no "
                     "gearvib/kernels.py there)")
    roots = {"this": ROOT, "baseline": os.path.abspath(args.baseline)}
    load0 = os.getloadavg()[0]
    t0 = time.time()
    results: dict[tuple[str, str], list[dict]] = {}
    for _ in range(args.rounds):
        for case in cases:
            for name in ("baseline", "this"):  # interleaved, fresh process and cache each
                results.setdefault((case, name), []).append(
                    run_worker(roots[name], case, args.window, args.reps, fresh=not args.warm))
    load1 = os.getloadavg()[0]
    cache = "the user's numba cache (--warm)" if args.warm else "fresh numba cache per process"
    print(f"paper-case1, {args.rounds} rounds interleaved, {cache}; "
          f"load average {load0:.1f} before, {load1:.1f} after; {time.time() - t0:.0f} s")
    print(f"this: {roots['this']}\nbaseline: {roots['baseline']}")
    print(f"{'case':8s} {'code':9s} {'first call [s CPU]':>20s} {'numba compile':>14s} "
          f"{'steps/s (median)':>17s}  check")
    for case in cases:
        for name in ("baseline", "this"):
            rs = results[(case, name)]
            first = [r["first"] for r in rs]
            comp = [r["numba"] for r in rs]
            rate = [median(r["rates"]) for r in rs]
            checks = {r["check"] for r in rs}
            print(f"{case:8s} {name:9s} {median(first):7.1f} ({_spread(first):>11s}) "
                  f"{median(comp):14.1f} {median(rate):10.0f} ({_spread(rate)})  "
                  f"{', '.join(f'{c:.12g}' for c in sorted(checks))}")
        a = results[(case, "this")]
        b = results[(case, "baseline")]
        ratio_first = median([r["first"] for r in a]) / median([r["first"] for r in b])
        ratio_rate = (median([median(r["rates"]) for r in a])
                      / median([median(r["rates"]) for r in b]))
        same = {r["check"] for r in a} == {r["check"] for r in b}
        print(f"{case:8s} first call [s CPU] this / baseline: {ratio_first:.2f}; "
              f"steps/s this / baseline: {ratio_rate:.2f}; same check value: {same}")


if __name__ == "__main__":
    main()
