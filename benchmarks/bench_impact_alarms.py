"""Tooth-fault impact evidence of ``gearvib diagnose``: detections and false positives (not a test).

Run ``python benchmarks/bench_impact_alarms.py [--quick] [--noise N] [--master M ...]
[--gearvib-seed S --gearvib N]``.

The check (:func:`gearvib.diagnosis.impacts.member_impacts`, the evidence that makes a local
tooth fault *possible*, ``docs/diagnosis.md``) on records without and with tooth faults:

* **noise**: white noise at a ±3 % speed ramp, ``paper-case1`` (1500 min-1) and the 4-planet
  21/31/83 set (1200 min-1), 10 s at 20 kHz: every family detected is a false positive;
* **independent generator** (``tests/independent/planetary_signals.py``) with record seeds
  drawn from ``--master`` (the benchmark's own records use master 30; give others to check the
  thresholds on records not used to choose them): per gear set every fault clear and weak and
  ``--healthy`` healthy records, window, sensor angle, resonance and SNR drawn as in the
  benchmark. Healthy: any detection is a false positive; faulty: the true member's family
  detected, and another member's;
* **gearvib-made** (``--gearvib N``, slow: each record is a simulation): the records of
  ``benchmarks/bench_diagnose.py`` with ``--gearvib-seed``, healthy ones first if
  ``--gearvib-healthy-only``.

Prints counts with the 95 % Clopper-Pearson upper bound of the false-positive rate.
``--quick``: 4 noise records and 1 healthy generator record per set (a smoke run).
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import time
from pathlib import Path

import numpy as np
from scipy import stats

from analysis.measurement import load_measurement
from gearvib.config import load_config
from gearvib.diagnosis.candidates import candidate_members
from gearvib.diagnosis.impacts import member_impacts
from gearvib.diagnosis.lines import kinematics, member_lines

HERE = Path(__file__).resolve().parent


def _load(name: str, path: Path):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


PS = _load("planetary_signals", HERE.parent / "tests" / "independent" / "planetary_signals.py")


class GearSet:
    """The kinematics of a gear-set description, ready for :func:`member_impacts`."""

    def __init__(self, config: str) -> None:
        cfg, base = load_config(config)
        self.kin = kinematics(cfg, base)
        self.members = candidate_members(self.kin.gs, self.kin.model)
        self.lines = member_lines(self.kin.cat, self.kin.ms, self.members, self.kin.model)

    def check(self, x: np.ndarray, fs: float, input_rpm: np.ndarray) -> dict[str, bool]:
        """``member -> detected`` (the members with a fault family)."""
        ratio = self.kin.ratio(self.kin.gs.input)
        _, by = member_impacts(x, fs, np.abs(input_rpm) * ratio, lines=self.lines,
                               members=self.members, ms=self.kin.ms, model=self.kin.model)
        return {m: e.detected for (kind, m), e in by.items() if kind == "crack"}


def upper(k: int, n: int) -> float:
    return float(stats.beta.ppf(0.975, k + 1, n - k)) if k < n else 1.0


def specs(master: int, healthy: int) -> list:
    """Generator records drawn as ``planetary_signals.benchmark_records`` draws them, from
    another master seed."""
    return PS.benchmark_records(master=master, healthy=healthy, first_seed=1000 * master)


def noise(sets: dict, n: int, rng: np.random.Generator) -> tuple[int, int]:
    fp = checks = 0
    for name, (gs, rpm) in sets.items():
        for _ in range(n):
            fs, dur = 20_000.0, 10.0
            t = np.arange(int(fs * dur)) / fs
            speed = rpm * (1.0 + rng.uniform(-0.03, 0.03) * (t / dur - 0.5))
            det = gs.check(rng.standard_normal(t.size), fs, speed)
            fp += sum(det.values())
            checks += len(det)
        print(f"  noise, {name}: {n} records", flush=True)
    return fp, checks


def generator(sets: dict, masters: list[int], healthy: int, faulty: bool = True) -> None:
    h_fp = h_n = 0
    found: dict[str, list[int]] = {}
    other = other_n = 0
    for master in masters:
        for spec in specs(master, healthy):
            if spec.fault is not None and not faulty:
                continue
            m = load_measurement(PS.to_dataset(spec), channel="acc", tacho="tacho")
            gs = sets[spec.gear_set.name][0]
            det = gs.check(np.asarray(m.channel("acc").values, float), m.fs,
                           np.asarray(m.speed_rpm.values, float))
            kind, member = PS.truth(spec)
            if kind == "none":
                h_fp += any(det.values())
                h_n += 1
                continue
            key = f"{spec.gear_set.name} {spec.fault} {spec.severity}"
            found.setdefault(key, [0, 0])
            found[key][0] += bool(det.get(member, False)) if kind == "local" else 0
            found[key][1] += 1
            other += any(v for k, v in det.items() if k != member or kind != "local")
            other_n += 1
    print(f"  generator healthy records (masters {masters}): a family detected in {h_fp} of "
          f"{h_n} ({100 * h_fp / max(h_n, 1):.1f} %, 95 % upper bound "
          f"{100 * upper(h_fp, h_n):.1f} %)")
    for key, (k, n) in sorted(found.items()):
        if "eccentricity" not in key:
            print(f"  {key}: the true member's family detected in {k} of {n}")
    print(f"  faulty records: another member's family (or, for an eccentricity, any local "
          f"family) detected in {other} of {other_n}")


def gearvib_made(seed: int, n: int, healthy_only: bool) -> None:
    from gearvib.diagnosis.synthetic import record_from_run, synthetic_measurement

    bd = _load("bench_diagnose_records", HERE / "bench_diagnose.py")
    cases = bd.draw_cases(np.random.default_rng(seed), 40, 20)
    if healthy_only:
        cases = [c for c in cases if c[0] is None]
    gs = GearSet("paper-case1")
    fp = h = 0
    for fault, prof, level, s in cases[:n]:
        ds = synthetic_measurement("paper-case1", [fault] if fault else [], speed_rpm=prof,
                                   duration=bd.DURATION, noise=level, seed=s)
        rec = record_from_run(ds)
        det = gs.check(rec.signal, rec.fs, rec.speed_rpm)
        what = "healthy" if fault is None else f"{fault['kind']} {fault['member']}"
        print(f"    {what:<22s} {prof}: detected {[k for k, v in det.items() if v]}",
              flush=True)
        if fault is None:
            h += 1
            fp += any(det.values())
    if h:
        print(f"  gearvib-made healthy records (seed {seed}): a family detected in {fp} of {h} "
              f"(95 % upper bound {100 * upper(fp, h):.1f} %)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--noise", type=int, default=100, help="noise records per gear set")
    ap.add_argument("--master", type=int, nargs="+", default=[31, 32])
    ap.add_argument("--healthy", type=int, default=10, help="healthy records per gear set "
                    "and master")
    ap.add_argument("--gearvib", type=int, default=0)
    ap.add_argument("--gearvib-seed", type=int, default=1)
    ap.add_argument("--gearvib-healthy-only", action="store_true")
    ap.add_argument("--seed", type=int, default=2030)
    a = ap.parse_args()
    if a.quick:
        a.noise, a.master, a.healthy, a.gearvib = 4, [31], 1, 0
    t0 = time.perf_counter()
    sets = {"paper-case1": (GearSet("paper-case1"), 1500.0),
            "four-planet-21-31-83": (GearSet(PS.FOUR_PLANET.config), 1200.0)}
    fp, checks = noise(sets, a.noise, np.random.default_rng(a.seed))
    print(f"  white noise: {fp} detections in {checks} family checks "
          f"({2 * a.noise} records; 95 % upper bound {100 * upper(fp, checks):.2f} % per check)")
    generator(sets, a.master, a.healthy, faulty=not a.quick)
    if a.gearvib:
        gearvib_made(a.gearvib_seed, a.gearvib, a.gearvib_healthy_only)
    print(f"[{time.perf_counter() - t0:.0f} s]")


if __name__ == "__main__":
    main()
