"""Benchmark: the cost of faults, errors and virtual sensors on the run-up time (not a test).

Run ``python3 benchmarks/bench_faults.py [--quick]``. For ``paper-case1`` (three in-phase
planets) and ``paper-case2`` (unequal spacing), a 1 s run-up 0 -> 4000 min^-1 at 60 N m is
simulated healthy and with one housing sensor, one sensor and one local fault (a 30 % crack of
sun tooth 3), the same crack at severity 0 (the pair law runs, the dynamics stay those of the
healthy set), the same tooth broken, a pitting zone on a planet tooth, the eccentricity of the
sun, pitch errors on every sun tooth and a planet pin error. Every variant runs interleaved
with the others, each timed by the process CPU time (the machine is shared); each round's times
are divided by the same round's healthy run and the median of these paired ratios is reported
(with the best time), which is robust against the load of a shared machine; the quartiles and
the extremes of the paired ratios and the load average before and after show how far to trust
it. Where the load makes times too noisy, count work instead (instructions under callgrind, one
OpenBLAS thread; docs/faults-sensors.md). ``first [s]`` is the wall time of each variant's
first, short run in the process: with a cold cache it holds the compilation of the variant's
faulty-mesh pass (:mod:`gearvib.fault_pass`, once per configuration structure and machine),
with a warm one its loading. ``--generic`` adds every faulty variant with the generic pass of
the kernel (``GEARVIB_FAULT_PASS=generic``), interleaved with the others: the compiled pass's
gain side by side.

Why some faults cost more than others:

* a local tooth fault evaluates the pairs of the meshes of that gear one by one only while the
  faulty pair is in contact (a few of every ``z`` mesh cycles), elsewhere the healthy table; a
  crack or broken tooth (stiffness only) sums the pairs' stiffness into the table law, pitting
  (a gap) takes the full pair law;
* a fault on one gear of ``paper-case1`` desynchronises its in-phase planets: their meshes then
  reach the stiffness jumps at slightly different times and each gets its own sub-steps, most
  of them far shorter than the step, which take an Euler or midpoint step instead of RK4
  (``gearvib.kernels``, "Short sub-steps"; the 'severity 0' row has the pair law without the
  desynchronisation);
* pitch errors (every tooth), the eccentricity and rigid pin errors touch every pair at every
  step: the faulty-mesh law runs in every right-hand side of the gear's meshes, in one pass
  after the healthy meshes, as the table law with shifted deflections (an eccentric gear's
  cosine and sine once per right-hand side for all its meshes; pitch errors by the mean offset
  of the pairs in contact, kept per mesh cycle; the pair loop only where pairs are partly in
  contact or ramp in and out). That pass is generated for the configuration as straight-line
  code and compiled (:mod:`gearvib.fault_pass`): no sparse loops, record reads or law
  dispatch, which had cost these errors most of their 16-18 % on ``paper-case1``.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from gearvib.assembly import assemble
from gearvib.config import load_config, load_gearset
from gearvib.fault_pass import PASS_ENV
from gearvib.faults import BrokenTooth, Crack, Eccentricity, PinError, PitchError, Pitting
from gearvib.sensors import HousingMode, HousingSensor
from gearvib.simulate import SpeedRamp, simulate
from gearvib.simulation.settings import conditions_from_settings, read_run_settings

REPEAT = 11


def variants(preset: str) -> list[tuple[str, object]]:
    model = assemble(load_gearset(preset))
    sensor = [HousingSensor("housing", 90.0, window="hann", width_deg=90.0,
                            housing_modes=(HousingMode(3000.0, 0.02, 1.0),))]
    pitch = np.random.default_rng(0).normal(0.0, 3e-6, 33)
    return [
        ("healthy", model),
        ("1 sensor", model.with_sensors(sensor)),
        ("1 sensor + sun crack 30 %", model.with_faults([Crack("sun", 3, severity=0.3)])
         .with_sensors(sensor)),
        ("1 sensor + sun crack, severity 0", model.with_faults([Crack("sun", 3, severity=0.0)])
         .with_sensors(sensor)),
        ("1 sensor + sun broken tooth", model.with_faults([BrokenTooth("sun", 3)])
         .with_sensors(sensor)),
        ("1 sensor + planet pitting", model.with_faults(
            [Pitting("planet1", 5, severity=0.5, path_start=0.3, path_end=0.6, depth=2e-6)])
         .with_sensors(sensor)),
        ("1 sensor + sun eccentricity 10 um", model.with_faults([Eccentricity("sun", 10e-6)])
         .with_sensors(sensor)),
        ("1 sensor + sun pitch errors (33 teeth)", model.with_faults(
            [PitchError("sun", cumulative=list(pitch))]).with_sensors(sensor)),
        ("1 sensor + planet pin error 10 um", model.with_faults(
            [PinError("planet1", tangential=10e-6)]).with_sensors(sensor)),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: paper-case1 only (unless --preset), one round, "
                             "0.05 s run-up")
    parser.add_argument("--repeat", type=int, default=None, help=f"rounds (default {REPEAT})")
    parser.add_argument("--preset", action="append", choices=("paper-case1", "paper-case2"),
                        help="gear set (repeatable; default both)")
    parser.add_argument("--generic", action="store_true",
                        help="also run every faulty variant with the generic faulty-mesh pass "
                             f"({PASS_ENV}=generic), interleaved: the compiled pass's gain "
                             "side by side")
    parser.add_argument("--only", action="append", metavar="TEXT",
                        help="variants whose name contains TEXT (repeatable; the healthy run "
                             "always runs)")
    args = parser.parse_args()
    repeat = args.repeat or (1 if args.quick else REPEAT)
    duration = 0.05 if args.quick else 1.0
    presets = args.preset or (("paper-case1",) if args.quick else ("paper-case1", "paper-case2"))
    for preset in presets:
        # the drive of the preset's [simulation] table, as gearvib simulate runs it
        cfg, _ = load_config(preset)
        coupling = conditions_from_settings(read_run_settings(cfg.get("simulation", {}))).coupling
        cond = SpeedRamp(0.0, 4000.0 * duration, duration, input_torque=60.0, coupling=coupling)
        runs = [(name, model, "") for name, model in variants(preset)
                if name == "healthy" or not args.only or any(t in name for t in args.only)]
        if args.generic:
            runs += [(f"{name} (generic pass)", model, "generic") for name, model, _ in runs
                     if model.faults]
        first: dict[str, float] = {}
        for name, model, mode in runs:  # compile, fill the caches
            os.environ[PASS_ENV] = mode
            t0 = time.perf_counter()
            simulate(model, cond, duration=0.02, progress=False)
            first[name] = time.perf_counter() - t0
        times: dict[str, list[float]] = {name: [] for name, _, _ in runs}
        load0 = os.getloadavg()[0]
        for _ in range(repeat):
            for name, model, mode in runs:
                os.environ[PASS_ENV] = mode
                t0 = time.process_time()
                simulate(model, cond, progress=False)
                times[name].append(time.process_time() - t0)
        os.environ.pop(PASS_ENV, None)
        load1 = os.getloadavg()[0]
        base = np.array(times["healthy"])
        print(f"\n{preset}: {duration:g} s run-up 0 -> {4000 * duration:g} min-1, CPU time, "
              f"{repeat} interleaved rounds, load average {load0:.1f} -> {load1:.1f}")
        print(f"{'variant':57s} {'first [s]':>9s} {'best [s]':>9s} {'ratio: median':>14s} "
              f"{'quartiles':>11s} {'min-max':>11s}")
        for name, t in times.items():
            r = np.array(t) / base
            q1, q3 = np.percentile(r, [25, 75])
            print(f"{name:57s} {first[name]:9.3f} {min(t):9.3f} {np.median(r):14.3f} "
                  f"{q1:5.2f}-{q3:4.2f} {r.min():5.2f}-{r.max():4.2f}")


if __name__ == "__main__":
    main()
