"""Benchmark: ``gearvib diagnose`` on records it did not make, beside its own ones (not a test).

Run ``python benchmarks/bench_diagnose_independent.py [--quick] [--records DIR] [--json F]``.

*Independent set.* 22 records of ``tests/independent/planetary_signals.py`` (a
phenomenological generator from the literature, no gearvib simulation): ``paper-case1``
(1500 min-1) and a 4-planet 21/31/83 set (1200 min-1, ``tests/independent/
four-planet-21-31-83.toml``); a sun, planet and ring tooth fault and a sun eccentricity, each
clear (SNR 15-20 dB) and weak (10-15 dB), and 3 healthy records per set; +-1 % speed, 10 s,
20 kHz, the speed from the 60-pulse tacho. Each record is written as netCDF and read back
through :func:`analysis.measurement.load_measurement`, as ``gearvib diagnose`` reads it.
``--quick``: a smoke run (3 s of one independent record, crack candidates only, 8-revolution
segments, no gearvib-made record).

Printed: *kind+member top-1* (the generator's tooth fault is a *local* tooth fault, so crack,
pitting or broken tooth on the right member count; the eccentricity must be named
eccentricity), *member top-1*, the ``none`` rate on faulty records and the false-alarm rate
on healthy records (a cause at or above the threshold, *likely*) and the healthy records
whose leading cause is *possible* (``local_tooth_fault``, the fallback when the kind of a local
fault cannot be told, counts as a local tooth fault). Beside them the same figures on the
gearvib-made records of ``benchmarks/bench_diagnose.py`` (``--gearvib-faulty``,
``--gearvib-healthy``, seed 0; its exact-kind top-1 too).

Today's code: run this file with ``PYTHONPATH`` pointing at another checkout first; the
generator and ``bench_diagnose.py`` are loaded from this file's own tree, ``gearvib`` from
the path. ``--json F`` writes every record's ranked causes (to compare two versions).
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import inspect
import json
import os
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
LOCAL = ("crack", "pitting", "broken_tooth", "local_tooth_fault")
QUICK_KINDS = ("crack",)
"""Candidate kinds of a ``--quick`` smoke run (a fifth of the simulations)."""
QUICK_SECONDS = 3.0
"""Length of the record of a ``--quick`` smoke run [s] (the benchmark's are 10 s)."""


def _load(name: str, path: Path):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


def _where(diagnose, folder: Path) -> dict:
    """Where the candidates go: the library of this code, the run folder of older code."""
    if "library" in inspect.signature(diagnose).parameters:
        return {"library": folder}
    return {"work_dir": folder}


def _kinds(args: argparse.Namespace) -> dict:
    return {"kinds": QUICK_KINDS, "revolutions": 8} if args.quick else {}


def kind_class(cause: str) -> str:
    return "local" if cause in LOCAL else cause


def figures(rows: list[dict]) -> dict:
    """Rates of a list of per-record rows (``truth_kind``, ``truth_member``, ``top``,
    ``likely``)."""
    faulty = [r for r in rows if r["truth_kind"] != "none"]
    healthy = [r for r in rows if r["truth_kind"] == "none"]
    out = {"faulty": len(faulty), "healthy": len(healthy)}
    out["kind_member"] = sum(kind_class(r["top"][0]) == r["truth_kind"]
                             and r["top"][1] == r["truth_member"] for r in faulty)
    out["member"] = sum(r["top"][1] == r["truth_member"] for r in faulty)
    out["none"] = sum(r["top"][0] == "none" for r in faulty)
    out["false_alarms"] = sum(bool(r["likely"]) for r in healthy)
    out["possible"] = sum(r["top"][0] != "none" and not r["likely"] for r in healthy)
    out["exact"] = sum(r["top"][0] == r.get("truth_exact", "") and r["top"][1] ==
                       r["truth_member"] for r in faulty)
    return out


def row_of(d, truth_kind: str, truth_member: str, name: str, truth_exact: str = "") -> dict:
    top = d.causes[0]
    return {"record": name, "truth_kind": truth_kind, "truth_member": truth_member,
            "truth_exact": truth_exact, "top": (top.cause, top.member, round(top.score, 4)),
            "likely": [(c.cause, c.member) for c in d.likely],
            "verdict": getattr(top, "verdict", ""),
            "causes": [(c.cause, c.member, c.score) for c in d.causes]}


def independent(args: argparse.Namespace, work: Path) -> list[dict]:
    from analysis.measurement import load_measurement
    from gearvib.diagnosis import Record, diagnose

    ps = _load("planetary_signals", HERE.parent / "tests" / "independent" /
               "planetary_signals.py")
    specs = ps.benchmark_records(quick=args.quick)[:1 if args.quick else None]
    if args.quick:  # a smoke run: 3 s of the record, 8-revolution segments
        specs = [dataclasses.replace(s, duration=QUICK_SECONDS) for s in specs]
    rec_dir = Path(args.records) if args.records else work / "records"
    rec_dir.mkdir(parents=True, exist_ok=True)
    rows = []
    for spec in specs:
        path = rec_dir / f"{spec.name}{'_quick' if args.quick else ''}.nc"
        if not path.is_file():
            ps.write_record(spec, path)
        rec = Record.from_measurement(load_measurement(str(path)), name=spec.name)
        t0 = time.perf_counter()
        d = diagnose(rec, spec.gear_set.config, workers=args.workers, **_kinds(args),
                     **_where(diagnose, work / spec.gear_set.name))
        dt = time.perf_counter() - t0
        kind, member = ps.truth(spec)
        row = row_of(d, kind, member, spec.name)
        row["seconds"] = dt
        rows.append(row)
        top = d.causes[0]
        tscore = max((c.score for c in d.causes if c.member == member and
                      kind_class(c.cause) == kind), default=float("nan"))
        print(f"{spec.name:<52s} truth {kind + ' ' + member:<18s} -> {top.cause} {top.member} "
              f"{top.score:.2f} (truth's best {tscore:.2f}) {dt:5.1f} s", flush=True)
    return rows


def gearvib_made(args: argparse.Namespace, work: Path) -> list[dict]:
    import numpy as np

    from gearvib.diagnosis import diagnose
    from gearvib.diagnosis.synthetic import record_from_run, synthetic_measurement

    bd = _load("bench_diagnose_records", HERE / "bench_diagnose.py")
    rng = np.random.default_rng(0)
    cases = bd.draw_cases(rng, args.gearvib_faulty, args.gearvib_healthy)
    rows = []
    for i, (fault, prof, noise, seed) in enumerate(cases):
        ds = synthetic_measurement("paper-case1", [fault] if fault else [], speed_rpm=prof,
                                   duration=bd.DURATION, noise=noise, seed=seed)
        d = diagnose(record_from_run(ds), "paper-case1", workers=args.workers, **_kinds(args),
                     **_where(diagnose, work / f"p{prof}"))
        if fault is None:
            kind, member, exact = "none", "", ""
        else:
            kind, member = kind_class(fault["kind"]), bd.reported(fault["member"])
            exact = fault["kind"]
        rows.append(row_of(d, kind, member, f"gearvib-{i}", exact))
        print(f"gearvib-made {i:3d} {exact or 'healthy':<13s} {member:<7s} -> "
              f"{d.causes[0].cause} {d.causes[0].member} {d.causes[0].score:.2f}", flush=True)
    return rows


def _line(label: str, f: dict) -> str:
    nf, nh = max(f["faulty"], 1), max(f["healthy"], 1)
    km = f["kind_member"]
    return (f"{label:<28s} {km:>3d}/{f['faulty']:<3d} {100 * km / nf:5.1f} %"
            f"   {f['member']:>3d}/{f['faulty']:<3d} {100 * f['member'] / nf:5.1f} %"
            f"   {f['none']:>3d}/{f['faulty']:<3d} {100 * f['none'] / nf:5.1f} %"
            f"   {f['false_alarms']:>3d}/{f['healthy']:<3d} "
            f"{100 * f['false_alarms'] / nh:5.1f} %"
            f"   {f['possible']:>3d}/{f['healthy']:<3d} {100 * f['possible'] / nh:5.1f} %")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smoke run: 1 independent record, "
                    "crack candidates only")
    ap.add_argument("--records", help="folder of the generated records (kept, reused)")
    ap.add_argument("--work", help="folder of the candidate runs (default: temporary)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--gearvib-faulty", type=int, default=None)
    ap.add_argument("--gearvib-healthy", type=int, default=None)
    ap.add_argument("--skip-gearvib", action="store_true")
    ap.add_argument("--json", help="write every record's ranked causes here")
    args = ap.parse_args()
    if args.quick:
        args.skip_gearvib = True  # the gearvib-made records: bench_diagnose.py's smoke run
    if args.gearvib_faulty is None:
        args.gearvib_faulty = 1 if args.quick else 40
    if args.gearvib_healthy is None:
        args.gearvib_healthy = 0 if args.quick else 20
    import gearvib

    print(f"gearvib from {Path(gearvib.__file__).parent}; load {os.getloadavg()}")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(args.work) if args.work else Path(tmp)
        t0 = time.perf_counter()
        rows = independent(args, work)
        t_ind = time.perf_counter() - t0
        g_rows = [] if args.skip_gearvib else gearvib_made(args, work)
    fi = figures(rows)
    print(f"\nindependent set: {len(rows)} records in {t_ind:.0f} s; load {os.getloadavg()}")
    print(f"{'':<28s} {'kind+member top-1':>17s}   {'member top-1':>14s}   "
          f"{'none on faulty':>14s}   {'false alarms':>14s}   {'possible, healthy':>17s}")
    print(_line("independent (phenomenol.)", fi))
    if g_rows:
        fg = figures(g_rows)
        print(_line("gearvib-made (class)", fg))
        print(f"gearvib-made, exact kind (crack/pitting/broken tooth told apart): "
              f"{fg['exact']}/{fg['faulty']}")
    if args.json:
        Path(args.json).write_text(json.dumps({"independent": rows, "gearvib": g_rows},
                                              indent=1))


if __name__ == "__main__":
    main()
