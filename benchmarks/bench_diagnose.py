"""Benchmark: accuracy, false alarms and wall time of ``gearvib diagnose`` (not a test).

Run ``python3 benchmarks/bench_diagnose.py [--faulty 40] [--healthy 20] [--seed 0]
[--work DIR]`` (``--work``: keep the candidate libraries of the accuracy records there and
reuse them in the next run of the same code).

*Accuracy.* ``--faulty`` synthetic measurements of ``paper-case1`` with a random fault kind
(crack, pitting, broken tooth, eccentricity, pin error, uniformly), member (sun, planet 1-3,
ring as the kind allows), severity, speed profile and noise level, all drawn with ``--seed``;
``--healthy`` measurements of the healthy gearbox. Every measurement is seen through a
transfer path the diagnosis does not assume (``gearvib.diagnosis.synthetic.MEASURING_SENSOR``:
200 deg, exponential window 50 deg, housing modes at 1.5 and 4.5 kHz), with white noise, and
its speed is taken from the tacho channel. The speed profile is one of six (constant and
ramps between 1100 and 2000 min-1, 8 s); measurements at the same profile share the
candidate runs, as repeated diagnoses of one machine do.

Reported: top-1 accuracy (kind and member exact; ``planet`` counts for any planet of the
equally spaced set, which the diagnosis cannot tell apart), top-1 of member and class (the
local tooth faults crack / pitting / broken tooth as one class), misses (``none`` first) and
false alarms (a healthy gearbox with a cause above the threshold).

*Wall time.* One diagnosis of a 10 s measurement (1500 min-1 constant, 10 kHz) with a fresh
candidate folder on ``--workers`` (default 2) worker processes: simulation of the 24
candidates and the healthy set, order tracking, scoring. The machine is shared: the time is
the best of ``--repeat`` runs.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from gearvib.diagnosis import diagnose
from gearvib.diagnosis.synthetic import record_from_run, synthetic_measurement
from gearvib.io import write_netcdf

REPO = Path(__file__).resolve().parent.parent

LOCAL = ("crack", "pitting", "broken_tooth")
KINDS = ("crack", "pitting", "broken_tooth", "eccentricity", "pin_error")
PROFILES = ((1500.0, 1500.0), (1300.0, 1700.0), (1800.0, 1400.0), (1100.0, 1100.0),
            (2000.0, 2000.0), (1200.0, 1600.0))
DURATION = 8.0
QUICK_KINDS = ("crack",)
"""Candidate kinds of a ``--quick`` smoke run (a fifth of the simulations)."""
QUICK_SECONDS = 3.0
"""Length of the record of a ``--quick`` smoke run [s]."""


def random_fault(rng: np.random.Generator) -> dict:
    kind = KINDS[rng.integers(len(KINDS))]
    planets = ["planet1", "planet2", "planet3"]
    if kind in LOCAL:
        member = ["sun", *planets, "ring"][rng.integers(5)]
        tooth = int(rng.integers(0, 30))
        if kind == "crack":
            return {"kind": kind, "member": member, "tooth": tooth,
                    "severity": float(rng.uniform(0.2, 0.8))}
        if kind == "pitting":
            a = float(rng.uniform(0.1, 0.5))
            return {"kind": kind, "member": member, "tooth": tooth,
                    "severity": float(rng.uniform(0.3, 0.8)), "path_start": a,
                    "path_end": a + float(rng.uniform(0.2, 0.4)),
                    "depth": float(rng.uniform(2e-6, 10e-6))}
        return {"kind": kind, "member": member, "tooth": tooth}
    if kind == "eccentricity":
        member = ["sun", *planets][rng.integers(4)]
        return {"kind": kind, "member": member, "eccentricity": float(rng.uniform(5e-6, 20e-6)),
                "phase_deg": float(rng.uniform(0, 360))}
    return {"kind": kind, "member": planets[rng.integers(3)],
            "tangential": float(rng.choice([-1, 1]) * rng.uniform(8e-6, 30e-6)),
            "radial": float(rng.uniform(-5e-6, 5e-6))}


def reported(member: str) -> str:
    return "planet" if member.startswith("planet") else member


def draw_cases(rng: np.random.Generator, faulty: int, healthy: int) -> list[tuple]:
    """``(fault or None, speed profile, noise, seed)`` of the benchmark's measurements."""
    cases = [(random_fault(rng), PROFILES[rng.integers(len(PROFILES))],
              float(rng.uniform(0.01, 0.05)), int(rng.integers(1 << 31)))
             for _ in range(faulty)]
    cases += [(None, PROFILES[rng.integers(len(PROFILES))], float(rng.uniform(0.01, 0.05)),
               int(rng.integers(1 << 31))) for _ in range(healthy)]
    return cases


def accuracy(args: argparse.Namespace, work: Path) -> None:
    cases = draw_cases(np.random.default_rng(args.seed), args.faulty, args.healthy)
    exact = klass = missed = alarms = possible = n_f = n_h = 0
    rows = []
    margins = []  # local tooth faults: true kind's score minus the best other kind, same member
    t0 = time.perf_counter()
    for i, (fault, prof, noise, seed) in enumerate(cases):
        ds = synthetic_measurement("paper-case1", [fault] if fault else [], speed_rpm=prof,
                                   duration=DURATION, noise=noise, seed=seed)
        d = diagnose(record_from_run(ds), "paper-case1", library=work / f"p{prof}",
                     workers=args.workers, **({"kinds": QUICK_KINDS} if args.quick else {}))
        top = d.causes[0]
        if fault is None:
            n_h += 1
            alarm = bool(d.likely)
            alarms += alarm
            possible += not alarm and top.cause != "none"
            verdict = "FALSE ALARM" if alarm else ("possible" if top.cause != "none" else "ok")
            truth = "healthy"
        else:
            n_f += 1
            truth = f"{fault['kind']} {fault['member']}"
            ok = top.cause == fault["kind"] and top.member == reported(fault["member"])
            ok_c = top.member == reported(fault["member"]) and (
                top.cause == fault["kind"] or (top.cause in (*LOCAL, "local_tooth_fault")
                                               and fault["kind"] in LOCAL))
            exact += ok
            klass += ok_c
            if fault["kind"] in LOCAL:
                mem = reported(fault["member"])
                sc = {c.cause: c.score for c in d.causes if c.member == mem}
                margins.append(sc.get(fault["kind"], 0.0) - max(
                    (v for k, v in sc.items() if k in LOCAL and k != fault["kind"]),
                    default=0.0))
            missed += top.cause == "none"
            verdict = "ok" if ok else ("class ok" if ok_c else
                                       ("MISSED" if top.cause == "none" else "WRONG"))
        rows.append((i, truth, f"{prof[0]:.0f}->{prof[1]:.0f}", noise,
                     f"{top.cause} {top.member}", top.score, verdict))
        print(f"{i:3d} {truth:<22s} {rows[-1][2]:>10s} noise {noise:.3f}  -> "
              f"{rows[-1][4]:<22s} {top.score:.2f}  {verdict}", flush=True)
    dt = time.perf_counter() - t0
    print(f"\n{n_f} faulty, {n_h} healthy measurements ({dt:.0f} s in all)")
    if n_f:
        print(f"top-1 accuracy (kind and member): {exact}/{n_f} = {100 * exact / n_f:.0f} %")
        print(f"top-1 member and class:           {klass}/{n_f} = {100 * klass / n_f:.0f} %")
        print(f"missed (none first):              {missed}/{n_f}")
    if margins:
        m = np.asarray(margins)
        print(f"local tooth faults ({m.size}): score of the true kind minus the best other local "
              f"kind of the member: median {np.median(m):.3f}, min {m.min():.3f}, "
              f"{int(np.sum(m <= 0.01))} of {m.size} at <= 0.01")
    if n_h:
        print(f"false alarms on healthy gearboxes: {alarms}/{n_h} = {100 * alarms / n_h:.0f} %")
        print(f"healthy gearboxes with a possible cause first: {possible}/{n_h}")


_TIMED = r"""
import inspect, json, os, resource, sys, tempfile, time
t0 = time.perf_counter()
from analysis.measurement import load_measurement
from gearvib.diagnosis import Record, diagnose
t_import = time.perf_counter() - t0
rec = Record.from_measurement(load_measurement(sys.argv[1]))
workers = int(sys.argv[2])
kinds = {"kinds": tuple(sys.argv[3].split(","))} if len(sys.argv) > 3 and sys.argv[3] else {}
if len(sys.argv) > 4:
    kinds["revolutions"] = int(sys.argv[4])
new_api = "library" in inspect.signature(diagnose).parameters
out = {"import_s": t_import}
with tempfile.TemporaryDirectory() as tmp:
    kw = {"library": tmp} if new_api else {"work_dir": tmp}
    for what in ("fresh", "warm"):
        ru0 = resource.getrusage(resource.RUSAGE_SELF)
        rc0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t1 = time.perf_counter()
        d = diagnose(rec, "paper-case1", workers=workers, **kw, **kinds)
        out[what + "_s"] = time.perf_counter() - t1
        ru1 = resource.getrusage(resource.RUSAGE_SELF)
        rc1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        out[what + "_cpu_s"] = sum(getattr(b, f) - getattr(a, f) for a, b in
                                   ((ru0, ru1), (rc0, rc1)) for f in ("ru_utime", "ru_stime"))
        out[what + "_causes"] = [(c.cause, c.member, round(c.score, 4)) for c in d.causes[:3]]
print("RESULT " + json.dumps(out))
"""


def _timed_run(tree: Path, record: Path, workers: int, kinds: tuple[str, ...] = (),
               revolutions: int | None = None) -> dict:
    """One fresh and one warm diagnosis of ``record`` with the code of ``tree`` (a new
    process: its imports, its numba cache, fresh candidates in a temporary folder)."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    extra = [",".join(kinds)] + ([str(revolutions)] if revolutions else [])
    r = subprocess.run([sys.executable, "-c", _TIMED, str(record), str(workers),
                        *(extra if kinds or revolutions else [])],
                       capture_output=True, text=True, env=env, check=False,
                       cwd=tree)  # `python -c` puts its folder first on sys.path: the tree's
    lines = [x for x in r.stdout.splitlines() if x.startswith("RESULT ")]
    if r.returncode or not lines:
        raise RuntimeError(f"timed diagnosis with {tree} failed: {r.stderr[-2000:]}")
    return json.loads(lines[-1][7:])


def wall_time(args: argparse.Namespace) -> None:
    """Fresh and warm diagnosis of a 10 s record, this tree against ``--baseline-tree``,
    alternated ``--repeat`` times; medians, CPU seconds and the load (``--quick``: 3 s,
    crack candidates, 8-revolution segments)."""
    seconds = QUICK_SECONDS if args.quick else 10.0
    ds = synthetic_measurement("paper-case1", [{"kind": "crack", "member": "sun", "tooth": 3,
                                                "severity": 0.4}],
                               speed_rpm=(1500.0, 1500.0), duration=seconds, noise=0.02, seed=1)
    trees = {"this": REPO}
    if args.baseline_tree:
        trees = {"today": Path(args.baseline_tree).resolve(), **trees}
    runs: dict[str, list[dict]] = {k: [] for k in trees}
    with tempfile.TemporaryDirectory() as tmp:
        record = Path(tmp) / "record.nc"
        write_netcdf(ds, record)
        for tree in trees.values():  # warm the numba caches of both trees (not timed)
            _timed_run(tree, record, args.workers) if args.warm_caches else None
        for i in range(args.repeat):
            for name, tree in trees.items():
                load = os.getloadavg()[0]
                r = _timed_run(tree, record, args.workers, QUICK_KINDS if args.quick else (),
                               8 if args.quick else None)
                r["load"] = load
                runs[name].append(r)
                print(f"  {i + 1}/{args.repeat} {name:<5s} load {load:4.1f}: import "
                      f"{r['import_s']:5.1f} s, fresh {r['fresh_s']:6.1f} s "
                      f"(CPU {r['fresh_cpu_s']:5.1f} s), warm {r['warm_s']:5.2f} s "
                      f"(CPU {r['warm_cpu_s']:5.2f} s); top {r['fresh_causes'][0]}",
                      flush=True)
    print(f"\none diagnosis of a {seconds:.0f} s measurement (1500 min-1, paper-case1, sun crack), "
          f"{args.workers} workers, medians of {args.repeat}; load {os.getloadavg()}")
    med = {name: {k: float(np.median([r[k] for r in rs])) for k in
                  ("import_s", "fresh_s", "fresh_cpu_s", "warm_s", "warm_cpu_s", "load")}
           for name, rs in runs.items()}
    for name, m in med.items():
        print(f"  {name:<5s}: fresh {m['fresh_s']:6.1f} s (CPU {m['fresh_cpu_s']:5.1f} s), warm "
              f"{m['warm_s']:5.2f} s (CPU {m['warm_cpu_s']:5.2f} s), imports {m['import_s']:.1f} "
              f"s, load {m['load']:.1f}")
    if "today" in med:
        t, n = med["today"], med["this"]
        print(f"  ratio today/this: fresh {t['fresh_s'] / n['fresh_s']:.1f}x wall, "
              f"{t['fresh_cpu_s'] / n['fresh_cpu_s']:.1f}x CPU; warm "
              f"{t['warm_s'] / n['warm_s']:.1f}x wall, {t['warm_cpu_s'] / n['warm_cpu_s']:.1f}x "
              "CPU")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--faulty", type=int, default=40)
    ap.add_argument("--healthy", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--skip-accuracy", action="store_true")
    ap.add_argument("--skip-timing", action="store_true")
    ap.add_argument("--baseline-tree", help="a checkout of today's code (e.g. a git worktree "
                    "of main) timed side by side")
    ap.add_argument("--warm-caches", action="store_true", help="one untimed run per tree "
                    "first (numba caches)")
    ap.add_argument("--quick", action="store_true", help="smoke run: a 3 s record, the timed "
                    "fresh and warm diagnosis once, crack candidates only, no accuracy records")
    ap.add_argument("--work", help="folder of the accuracy records' candidate libraries (one "
                    "per speed profile; kept and reused; default temporary)")
    args = ap.parse_args()
    if args.quick:
        args.repeat, args.faulty, args.healthy = 1, 1, 0
        args.skip_accuracy = True  # the timed diagnoses run the whole pipeline already
    if not args.skip_timing:
        wall_time(args)
    if not args.skip_accuracy:
        with tempfile.TemporaryDirectory() as tmp:
            accuracy(args, Path(args.work) if args.work else Path(tmp))


if __name__ == "__main__":
    main()
