"""Vold-Kalman order tracking: analysis.vold_kalman against rota-order 0.3.0, side by side.

Run: ``python benchmarks/bench_vold_kalman.py [--quick] [--repeat N] [--baseline KIND]``.

Extraction of 3 orders (1, 2 and 24 of a shaft running up 600 -> 3600 min-1, peak
amplitudes 1, 0.5 and 0.3, white noise of 0.1 rms) from 60 s at 25.6 kHz (1.536 M samples;
``--quick``: 1 s, one run of each), jointly, with a -3 dB bandwidth of 2 Hz (full width;
rota-order's ``bandwidth`` is the half width, 1 Hz). Each run is a fresh subprocess that loads
the signal from a ``.npy`` file, so that wall time, CPU time and peak resident memory
(``ru_maxrss`` minus the resident memory before the call) are measured alike:

* ``ours``: :func:`analysis.vold_kalman.order_waveform` with the default ``max_memory``
  (one pass: memory linear in the record);
* ``ours-512M``: the same with ``max_memory=512 MiB`` (blocks with checkpoints, same result;
  ``--quick`` scales the budget with the record, ``ours-8.53M``, so that it too runs in blocks);
* ``baseline``: rota-order 0.3.0's ``rota.extract.order_waveform`` (GPL) run as a black box
  with the Python of a separate virtual environment (``--rota-python``, default
  ``/tmp/rota/bin/python``; make it with ``python -m venv /tmp/rota && /tmp/rota/bin/pip
  install rota-order==0.3.0``). It is never imported by this project. When that Python or
  package is missing (or ``--baseline spsolve``), the baseline is a straightforward
  ``scipy.sparse.linalg.spsolve`` of the normal equations of the same least-squares system.

The runs are interleaved (ours, ours-512M, baseline, ours, ...) ``--repeat`` times and the
medians are compared; the load (``uptime``) is printed before and after. Accuracy: the
largest amplitude error [dB] and phase error [deg] against the known envelopes over the
middle 90 % of the record, and the largest difference between the two results.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
FS = 25600.0
ORDERS = (1.0, 2.0, 24.0)
AMPS = (1.0, 0.5, 0.3)
PHASES_DEG = (10.0, -40.0, 75.0)
BANDWIDTH = 2.0  # Hz, full -3 dB width

OURS = r"""
import json, resource, sys, time
import numpy as np
from analysis.vold_kalman import order_waveform
d = np.load(sys.argv[1])
x, rpm = d["x"], d["rpm"]
budget = float(sys.argv[3])
rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
w0, c0 = time.perf_counter(), time.process_time()
res = order_waveform(x, 25600.0, orders=[1.0, 2.0, 24.0], rpm=rpm, bandwidth=2.0,
                     max_memory=budget)
wall, cpu = time.perf_counter() - w0, time.process_time() - c0
rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
np.save(sys.argv[2], res.envelope)
print(json.dumps({"wall": wall, "cpu": cpu, "rss_before_mb": rss0 / 1024,
                  "peak_mb": (rss1 - rss0) / 1024, "notes": list(res.notes)}))
"""

ROTA = r"""
import json, resource, sys, time
import numpy as np
from rota.extract import order_waveform
d = np.load(sys.argv[1])
x, rpm = d["x"], d["rpm"]
rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
w0, c0 = time.perf_counter(), time.process_time()
res = order_waveform(x, 25600.0, rpm, [1.0, 2.0, 24.0], bandwidth=1.0, joint=True)
wall, cpu = time.perf_counter() - w0, time.process_time() - c0
rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
np.save(sys.argv[2], np.asarray(res.envelopes).T)
print(json.dumps({"wall": wall, "cpu": cpu, "rss_before_mb": rss0 / 1024,
                  "peak_mb": (rss1 - rss0) / 1024, "notes": []}))
"""

SPSOLVE = r"""
import json, resource, sys, time
import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve
from analysis.speed import from_rpm
from analysis.vold_kalman import bandwidth_to_weight
d = np.load(sys.argv[1])
x, rpm = d["x"], d["rpm"]
fs, orders = 25600.0, np.array([1.0, 2.0, 24.0])
rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
w0, c0 = time.perf_counter(), time.process_time()
n, m = x.size, orders.size
phi = from_rpm(np.arange(n) / fs, rpm).angle
rho = float(bandwidth_to_weight(2.0, fs, 1)) / np.sqrt(2.0)
# the same stacked problem: data rows [cos, -sin] per order, rows rho * second difference
cols = []
for k in range(m):
    th = orders[k] * phi
    cols += [np.cos(th), -np.sin(th)]
data = sp.hstack([sp.diags(c) for c in cols]).tocsr()  # n x 2mn (blocks per unknown)
d2 = sp.diags([1.0, -2.0, 1.0], [0, 1, 2], shape=(n - 2, n))
struct = rho**2 * (d2.T @ d2)
normal = (data.T @ data + sp.block_diag([struct] * (2 * m))).tocsc()
z = spsolve(normal, data.T @ x)
env = (z.reshape(2 * m, n)[0::2] + 1j * z.reshape(2 * m, n)[1::2])[None]
wall, cpu = time.perf_counter() - w0, time.process_time() - c0
rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
np.save(sys.argv[2], env)
print(json.dumps({"wall": wall, "cpu": cpu, "rss_before_mb": rss0 / 1024,
                  "peak_mb": (rss1 - rss0) / 1024, "notes": []}))
"""


def make_signal(seconds: float, where: Path) -> tuple[Path, np.ndarray]:
    """Signal file and the true envelopes ``(order, time)``."""
    n = int(seconds * FS)
    t = np.arange(n) / FS
    f0, f1 = 10.0, 60.0
    rpm = 60.0 * (f0 + (f1 - f0) * t / seconds)
    phi = 2 * np.pi * (f0 * t + 0.5 * (f1 - f0) / seconds * t**2)
    truth = np.array(
        [a * np.exp(1j * np.radians(p)) for a, p in zip(AMPS, PHASES_DEG, strict=True)]
    )
    x = sum(
        (truth[k] * np.exp(1j * ORDERS[k] * phi)).real for k in range(len(ORDERS))
    ) + 0.1 * np.random.default_rng(0).standard_normal(n)
    path = where / "signal.npz"
    np.savez(path, x=x, rpm=rpm)
    return path, np.repeat(truth[:, None], n, axis=1)


def run(kind: str, signal: Path, out: Path, rota_python: str, budget: float) -> dict:
    env = dict(os.environ, PYTHONPATH=str(REPO))
    if kind == "baseline-rota":
        cmd = [rota_python, "-c", ROTA, str(signal), str(out)]
        env.pop("PYTHONPATH")
    elif kind == "baseline-spsolve":
        cmd = [sys.executable, "-c", SPSOLVE, str(signal), str(out)]
    else:
        cmd = [sys.executable, "-c", OURS, str(signal), str(out), str(budget)]
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"{kind} failed:\n{done.stderr[-2000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def rota_available(python: str) -> bool:
    if not Path(python).exists():
        return False
    done = subprocess.run(
        [python, "-c", "import rota, importlib.metadata as m; print(m.version('rota-order'))"],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    return done.returncode == 0 and done.stdout.strip() == "0.3.0"


def accuracy(env: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    n = truth.shape[1]
    inner = slice(n // 20, n - n // 20)
    e = env.reshape(-1, *truth.shape)[0][:, inner]
    t = truth[:, inner]
    db = np.abs(20 * np.log10(np.abs(e) / np.abs(t))).max()
    deg = np.degrees(np.abs(np.angle(e / t))).max()
    return float(db), float(deg)


def uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="smoke run: 1 s instead of 60 s, one run of each")
    ap.add_argument("--repeat", type=int, default=None,
                    help="interleaved runs of each (3; --quick: 1)")
    ap.add_argument("--baseline", choices=("auto", "rota", "spsolve"), default="auto")
    ap.add_argument("--rota-python", default="/tmp/rota/bin/python")
    args = ap.parse_args()
    seconds = 1.0 if args.quick else 60.0
    repeat = args.repeat or (1 if args.quick else 3)
    # the budgeted run: 512 MiB for 60 s, scaled with the record (blocks in both modes)
    small = 512 * 1024**2 * seconds / 60.0
    base = args.baseline
    if base in ("auto", "rota"):
        if rota_available(args.rota_python):
            base = "rota"
        elif base == "rota":
            sys.exit(f"rota-order 0.3.0 not found at {args.rota_python}")
        else:
            print(f"rota-order 0.3.0 not available at {args.rota_python}: baseline = spsolve")
            base = "spsolve"
    budgets = {"ours": 2 * 1024**3, f"ours-{small / 1024**2:.3g}M": small}
    kinds = [*budgets, f"baseline-{base}"]
    print(f"load before: {uptime()}")
    print(f"signal: {seconds:g} s at {FS:g} Hz = {int(seconds * FS)} samples, orders "
          f"{ORDERS}, bandwidth {BANDWIDTH} Hz (full -3 dB width), joint")  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        where = Path(tmp)
        signal, truth = make_signal(seconds, where)
        runs: dict[str, list[dict]] = {k: [] for k in kinds}
        envs: dict[str, np.ndarray] = {}
        for i in range(repeat):
            for k in kinds:
                out = where / f"{k}.npy"
                r = run(k, signal, out, args.rota_python, budgets.get(k, 0.0))
                runs[k].append(r)
                envs[k] = np.load(out)
                print(f"  run {i + 1} {k:17s} wall {r['wall']:7.2f} s  cpu {r['cpu']:7.2f} s  "
                      f"peak +{r['peak_mb']:7.0f} MB")  # fmt: skip
    print(f"load after:  {uptime()}")
    print()
    print(f"{'':17s} {'wall [s]':>9s} {'cpu [s]':>9s} {'peak [MB]':>10s} {'amp err [dB]':>13s}"
          f" {'phase err [deg]':>16s}")  # fmt: skip
    med = {}
    for k in kinds:
        wall = float(np.median([r["wall"] for r in runs[k]]))
        cpu = float(np.median([r["cpu"] for r in runs[k]]))
        peak = float(np.median([r["peak_mb"] for r in runs[k]]))
        db, deg = accuracy(envs[k], truth)
        med[k] = (wall, cpu, peak)
        print(f"{k:17s} {wall:9.2f} {cpu:9.2f} {peak:10.0f} {db:13.4f} {deg:16.3f}")
        for note in runs[k][-1]["notes"]:
            print(f"{'':17s} note: {note}")
    b = kinds[-1]
    for k in kinds[:-1]:
        print(f"{b} / {k}: wall x{med[b][0] / med[k][0]:.2f}, cpu x{med[b][1] / med[k][1]:.2f}"
              f", peak memory x{med[b][2] / max(med[k][2], 1.0):.2f}")  # fmt: skip
    ours = envs["ours"].reshape(-1, *truth.shape)[0]
    n = truth.shape[1]
    inner = slice(n // 20, n - n // 20)
    for k in kinds[1:]:
        other = envs[k].reshape(-1, *truth.shape)[0]
        diff = np.abs(other[:, inner] - ours[:, inner]).max() / np.abs(truth).max()
        print(f"largest difference ours vs {k}: {diff:.2e} of the largest amplitude")


if __name__ == "__main__":
    main()
