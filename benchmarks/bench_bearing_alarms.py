"""Rolling-bearing causes of ``gearvib diagnose``: detections and false alarms.

Records of an independent generator (written here, not gearvib's simulator) on the CWRU rig
description (``cwru-drive-end``, 12 kHz, 1797 min-1), each diagnosed with
``gearvib.diagnosis.diagnose``:

* faulty: decaying bursts of a housing resonance (2-4 kHz) at BPFO (outer race) or BPFI
  amplitude-modulated at the shaft speed (inner race), 1 % jitter of the spacing, in white
  noise at -12 to -3 dB (burst rms over noise rms), 2 s;
* without a bearing fault: white noise; noise amplitude-modulated at 8 random frequencies
  (random lines in the envelope spectrum); bursts at a random rate more than 5 % from every
  bearing line.

Prints, per group, the records whose leading cause is the true one (faulty) and those with any
cause *likely* or *possible* (false alarms), with a 95 % Clopper-Pearson interval of the
false-alarm rate. ``--quick``: 4 records per group (a smoke run).
"""

from __future__ import annotations

import argparse
import importlib.util
import time
from pathlib import Path

import numpy as np
from scipy import stats

from gearvib.diagnosis import Record, diagnose


def _load(name: str, path: Path):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


SIGNALS = _load("bearing_signals", Path(__file__).resolve().parents[1] / "tests" / "independent"
                / "bearing_signals.py")
FS = 12000.0
RPM = 1797.0
F_R = RPM / 60.0
ORDERS = {"BPFI": 5.4152, "BPFO": 3.5848, "BSF": 2.357, "FTF": 0.39828}


def bursts(rate: float, seconds: float, rng: np.random.Generator, *, modulation: float,
           snr_db: float) -> np.ndarray:
    """Resonance bursts at ``rate`` [Hz] in white noise, the resonance drawn in 2-4 kHz
    (``tests/independent/bearing_signals.py``)."""
    res = rng.uniform(2000.0, 4000.0)
    return SIGNALS.bearing_bursts(rate, seconds, rng, fs=FS, resonance_hz=res, snr_db=snr_db,
                                  modulation_hz=modulation)


def healthy(kind: int, rng: np.random.Generator) -> np.ndarray:
    n = int(2.0 * FS)
    t = np.arange(n) / FS
    if kind == 0:
        return rng.standard_normal(n)
    if kind == 1:
        f = rng.uniform(5.0, 600.0, 8)
        ph = rng.uniform(0, 2 * np.pi, (8, 1))
        return (1.0 + 0.3 * np.sum(np.cos(2 * np.pi * f[:, None] * t + ph), axis=0)
                ) * rng.standard_normal(n)
    lines = np.array(list(ORDERS.values())) * F_R
    while True:
        rate = rng.uniform(8.0, 200.0)
        if np.all(np.abs(rate / lines - 1.0) > 0.05):
            break
    return bursts(rate, 2.0, rng, modulation=0.0, snr_db=rng.uniform(-9.0, 0.0))


def run(x: np.ndarray) -> list:
    d = diagnose(Record(x, FS, np.full(x.size, RPM), name="acc"), "cwru-drive-end")
    return d.causes


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="4 records per group (smoke run)")
    p.add_argument("--records", type=int, default=60, help="records per group")
    p.add_argument("--seed", type=int, default=2026)
    a = p.parse_args()
    n = 4 if a.quick else a.records
    rng = np.random.default_rng(a.seed)
    t0 = time.perf_counter()
    print(f"bearing causes of gearvib diagnose, cwru-drive-end, {n} records per group")
    for label, cause, mod in (("BPFO", "outer_race_fault", 0.0),
                              ("BPFI", "inner_race_fault", F_R)):
        for snr in (-12.0, -9.0, -6.0, -3.0):
            right = 0
            for _ in range(n):
                x = bursts(ORDERS[label] * F_R, 2.0, rng, modulation=mod, snr_db=snr)
                lead = run(x)[0]
                right += lead.cause == cause and lead.verdict == "likely"
            print(f"  {label} at {snr:+5.1f} dB: true cause first and likely in {right} of {n}")
    alarms = possible = total = 0
    for kind, name in enumerate(("white noise", "random envelope lines",
                                 "bursts at a random rate")):
        a_k = p_k = 0
        for _ in range(n):
            causes = run(healthy(kind, rng))
            a_k += any(c.verdict == "likely" for c in causes)
            p_k += any(c.verdict == "possible" for c in causes)
        print(f"  {name}: likely in {a_k} of {n}, possible in {p_k} of {n}")
        alarms += a_k
        possible += p_k
        total += n
    hi = stats.beta.ppf(0.975, alarms + 1, total - alarms) if alarms < total else 1.0
    print(f"false alarms (a bearing cause likely) on records without a bearing fault: {alarms} "
          f"of {total} ({100 * alarms / total:.1f} %, 95 % upper bound {100 * hi:.1f} %); "
          f"possible: {possible} of {total}")
    print(f"[{time.perf_counter() - t0:.0f} s]")


if __name__ == "__main__":
    main()
