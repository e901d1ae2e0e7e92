"""Floquet analysis of a smooth (trapezoidal) mesh stiffness: the midpoint product of issue #15
against the adaptive Magnus integrator used before, side by side.

Run: ``python3 benchmarks/bench_floquet.py [--quick]``.

The gear set is ``reports/sets/four-planet-elastic-trapezoidal.toml`` (20 DOF: four planets,
elastic bearings, trapezoidal stiffness with 0.05-cycle ramps). For a few input speeds it
prints the time, the exponentials per period and the peak memory (tracemalloc) of one Floquet
evaluation with

* the adaptive fourth-order Magnus integrator on ``K`` as a callable (the method before: it
  resolves the fastest mode and doubles the steps to ``rtol = 1e-10``, up to 2^16 steps), and
* the midpoint product with breakpoints at every kink of the stiffness tables (now:
  :class:`analysis.instability.PiecewiseSmooth`, ``max|mu|`` to 1e-8),

with the difference of their ``max|mu|`` and the speed-up. Then the stability chart the report
computes (300 speeds, boundaries refined, chart accuracy) with one and with two worker
processes. ``--quick`` (a smoke run): one speed, the adaptive Magnus integrator to ``rtol =
1e-5`` instead of 1e-10 (so its time means little), and a 3-speed chart around the unstable
region at 2908 min-1 (found and refined).
"""

from __future__ import annotations

import argparse
import time
import tracemalloc
from pathlib import Path

import numpy as np

from analysis.instability import floquet
from gearvib.assembly import assemble
from gearvib.config import load_gearset
from gearvib.stability import periodic_system, stability_over_speed

SET = Path(__file__).resolve().parents[1] / "reports" / "sets" / \
    "four-planet-elastic-trapezoidal.toml"


def _measure(fn):
    tracemalloc.start()
    t0 = time.perf_counter()
    out = fn()
    dt = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return out, dt, peak


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="smoke run: one speed, Magnus to rtol 1e-5, a 3-speed chart")
    args = ap.parse_args()
    model = assemble(load_gearset(SET))
    system = periodic_system(model)
    f = system.reference_frequency_per_rpm
    speeds = (4000.0,) if args.quick else (4000.0, 2000.0, 1000.0)
    rtol = 1e-5 if args.quick else 1e-10  # the adaptive Magnus integrator's target
    pieces = system.at(1000.0)[2].edges.size - 1
    print(f"{SET.name}: {model.n_dof} DOF, {model.n_mesh} meshes, {pieces} pieces per mesh "
          "cycle (between the kinks of the stiffness tables)")
    print(f"{'speed':>7} {'before [s]':>11} {'now [s]':>9} {'ratio':>7} {'steps before':>13} "
          f"{'now':>6} {'MiB before':>11} {'now':>7} {'|d max|mu||':>12}")
    for rpm in speeds:
        M, C, K, T = system.at(rpm * f)
        new, t_new, m_new = _measure(lambda M=M, C=C, K=K, T=T: floquet(M, C, K, T))
        old, t_old, m_old = _measure(
            lambda M=M, C=C, T=T, fm=rpm * f: floquet(M, C, lambda t: system.stiffness_at(t, fm),
                                                       T, rtol=rtol))
        print(f"{rpm:7.0f} {t_old:11.2f} {t_new:9.3f} {t_old / t_new:7.0f} {old.n_steps:13d} "
              f"{new.n_steps:6d} {m_old / 2**20:11.0f} {m_new / 2**20:7.0f} "
              f"{abs(old.max_modulus - new.max_modulus):12.1e}")
    n = 3 if args.quick else 300
    grid = np.array([2850.0, 2910.0, 2970.0]) if args.quick else np.linspace(80.0, 4000.0, n)
    for workers in (1, 2):
        t0 = time.perf_counter()
        chart = stability_over_speed(model, grid, workers=workers)
        print(f"stability chart, {n} speeds, boundaries refined, {workers} worker(s): "
              f"{time.perf_counter() - t0:.1f} s, {len(chart.region_table)} unstable regions")


if __name__ == "__main__":
    main()
