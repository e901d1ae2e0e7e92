"""Envelope analysis: the fast kurtogram and the squared envelope spectrum against
straightforward scipy.signal implementations written here.

Run: ``python benchmarks/bench_envelope.py [--quick] [--repeat N]``.

The record: 60 s (``--quick``: 1.5 s, one timed run of each, a 1.75 s warm-up, the memory of the
kurtogram only) of one float64 channel at 51.2 kHz, an impulse train (87.3 Hz, 1.5 % period
jitter) through a 3.7 kHz resonance in white noise at -10 dB SNR.

1. **Fast kurtogram**, levels 0 to 8 with the 1/3 levels (16 rows, 892 bands).
   Baseline: Antoni's (2007) decimating tree done the straightforward way: 16-tap
   ``scipy.signal.firwin`` low-pass prototypes (cut-off at a quarter of the node's band for
   the binary split, a sixth for the ternary split) modulated to quasi-analytic band-pass
   filters, ``scipy.signal.lfilter`` on every node's complex signal and decimation by 2 or
   3 (the odd children shifted back to the positive half band), the root from
   ``scipy.signal.hilbert``, ``K = <|c|^4> / <|c|^2>^2 - 2`` of every node.
2. **Squared envelope spectrum** of a given band (3.2-6.4 kHz). Baseline:
   ``scipy.signal.firwin`` band-pass (257 taps, about the same transition width) with
   ``scipy.signal.filtfilt``, ``scipy.signal.hilbert``, ``|z|^2`` minus its mean, and
   ``scipy.signal.welch`` with today's segments (a quarter of the record, Hann, 50 %).

Times: median of ``--repeat`` runs, the two implementations interleaved (A, B, A, B, ...).
Memory: peak allocation beyond the input (``tracemalloc``: NumPy's and pyFFTW's arrays) and
the growth of the process's peak resident size (``VmHWM``: also FFTW's own work space),
each in a fresh subprocess that makes a warm-up call on a short record (numba compiled or
loaded, FFTW plans of other sizes) and then loads the record from a file, in units of one
float64 channel (8 bytes per sample). The load average is printed beside the figures.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import tracemalloc
from typing import Any

import numpy as np
import scipy.signal

from analysis.envelope import envelope_spectrum
from analysis.kurtogram import fast_kurtogram, kurtogram_levels

FS = 51200.0
BAND = (3200.0, 6400.0)
MAX_LEVEL = 8
WARM_UP = 3.0  # seconds of the warm-up record (a length that no run uses)
WARM_UP_QUICK = 1.75  # ... with --quick (level 8 needs 2^16 samples, 1.28 s)


def record(seconds: float, seed: int = 0) -> np.ndarray:
    """Impulse train (87.3 Hz, 1.5 % jitter) through a 3.7 kHz resonance, -10 dB SNR."""
    rng = np.random.default_rng(seed)
    n = round(FS * seconds)
    rate, fn, zeta = 87.3, 3700.0, 0.05
    periods = (1 + 0.015 * rng.standard_normal(int(seconds * rate * 1.2) + 2)) / rate
    times = np.concatenate([[0.01], 0.01 + np.cumsum(periods)])
    times = times[times < seconds]
    wn = 2 * np.pi * fn
    length = int(8 / (zeta * wn) * FS)
    tau = np.arange(length) / FS
    s = np.zeros(n + length)
    for tk in times:
        i0 = int(np.ceil(tk * FS))
        d = tau + (i0 / FS - tk)
        s[i0 : i0 + length] += np.exp(-zeta * wn * d) * np.sin(wn * np.sqrt(1 - zeta**2) * d)
    s = s[:n]
    return s + rng.standard_normal(n) * np.sqrt(np.mean(s**2) * 10.0)


# ----------------------------------------------------------------------------- baselines


def baseline_kurtogram(x: np.ndarray, fs: float, max_level: int) -> np.ndarray:
    """Band kurtosis by a decimating tree of scipy.signal filters; rows as
    :func:`analysis.kurtogram.kurtogram_levels`, padded with NaN."""
    taps = np.arange(16)
    h = scipy.signal.firwin(16, 0.25)  # prototype: half band of a quarter of the rate
    h0 = h * np.exp(1j * np.pi * taps / 4)  # [0, r/4] of a node at rate r
    h1 = h * np.exp(3j * np.pi * taps / 4)  # [r/4, r/2]
    taps3 = np.arange(24)
    g = scipy.signal.firwin(24, 1 / 6)
    g3 = [g * np.exp(1j * np.pi * (2 * j + 1) * taps3 / 6) for j in range(3)]

    def kurt(c: np.ndarray) -> float:
        p = c.real**2 + c.imag**2
        return float(np.mean(p * p) / np.mean(p) ** 2 - 2)

    def split3(c: np.ndarray) -> list[np.ndarray]:
        out = []
        for j in range(3):
            y = scipy.signal.lfilter(g3[j], 1, c)[::3]
            if j == 1:
                y = y * (-1.0) ** np.arange(y.size)
            out.append(y)
        return out

    rows = kurtogram_levels(max_level)
    result = np.full((len(rows), max(nb for _, nb in rows)), np.nan)
    index = {nb: r for r, (_, nb) in enumerate(rows)}
    nodes = [scipy.signal.hilbert(x - x.mean())]  # level 0
    result[0, 0] = kurt(nodes[0])
    for k in range(1, max_level + 1):  # nodes: level k - 1
        if k <= max_level - 1:  # the 1/3 level k + log2(3) - 1: level k - 1 split in 3
            thirds = [t for c in nodes for t in split3(c)]
            result[index[len(thirds)], : len(thirds)] = [kurt(t) for t in thirds]
        children = []
        for c in nodes:
            lo = scipy.signal.lfilter(h0, 1, c)[::2]
            hi = scipy.signal.lfilter(h1, 1, c)[::2]
            children += [lo, hi * (-1.0) ** np.arange(hi.size)]
        nodes = children
        result[index[2**k], : 2**k] = [kurt(c) for c in nodes]
    return result


def baseline_envelope(x: np.ndarray, fs: float, band: tuple[float, float]) -> np.ndarray:
    """filtfilt band-pass, hilbert, squared envelope minus its mean, Welch spectrum."""
    b = scipy.signal.firwin(257, band, pass_zero=False, fs=fs)
    y = scipy.signal.filtfilt(b, 1.0, x)
    e = np.abs(scipy.signal.hilbert(y)) ** 2
    e -= e.mean()
    seg = e.size // 4
    _, p = scipy.signal.welch(e, fs, window="hann", nperseg=seg, noverlap=seg // 2,
                              scaling="spectrum", detrend=False)  # fmt: skip
    return p


def ours_kurtogram(x: np.ndarray) -> Any:
    return fast_kurtogram(x, FS, max_level=MAX_LEVEL)


def ours_envelope(x: np.ndarray) -> Any:
    return envelope_spectrum(x, FS, band=BAND)


CASES = {
    "kurtogram": (ours_kurtogram, lambda x: baseline_kurtogram(x, FS, MAX_LEVEL)),
    "envelope": (ours_envelope, lambda x: baseline_envelope(x, FS, BAND)),
}


# ---------------------------------------------------------------------------------- runs


def peak_rss() -> int:
    """Peak resident size of this process [bytes]: ``VmHWM`` of ``/proc/self/status``
    (Linux; it starts afresh at exec, whereas ``ru_maxrss`` keeps the parent's peak at the
    fork), else ``ru_maxrss``."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def worker(case: str, which: int, path: str, warm_up: float = WARM_UP) -> None:
    """Memory of one call on the record saved at ``path``, in this (fresh) process; prints
    JSON. The record is loaded after the warm-up (on a short record), so that the peak
    resident size before the call holds the input and nothing larger."""
    fn = CASES[case][which]
    fn(record(warm_up, seed=1))  # warm-up: numba compiled or loaded, imports done
    x = np.load(path)
    rss0 = peak_rss()
    tracemalloc.start()
    base, _ = tracemalloc.get_traced_memory()
    fn(x)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    rss1 = peak_rss()
    print(json.dumps({"traced": peak - base, "rss": rss1 - rss0}))


def memory(case: str, which: int, path: str, warm_up: float) -> dict[str, float]:
    out = subprocess.run(
        [sys.executable, __file__, "--worker", case, str(which), path, str(warm_up)],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    return json.loads(out.stdout.strip().splitlines()[-1])


def load() -> str:
    return " ".join(f"{v:.2f}" for v in os.getloadavg())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: 1.5 s instead of 60 s, one timed run of each")
    parser.add_argument("--repeat", type=int, default=None,
                        help="timed runs of each (3; --quick: 1)")
    parser.add_argument("--worker", nargs=4, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args.worker[0], int(args.worker[1]), args.worker[2], float(args.worker[3]))
        return
    seconds = 1.5 if args.quick else 60.0
    repeat = args.repeat or (1 if args.quick else 3)
    warm_up = WARM_UP_QUICK if args.quick else WARM_UP
    x = record(seconds)
    folder = tempfile.TemporaryDirectory()
    path = os.path.join(folder.name, "record.npy")
    np.save(path, x)
    channel = 8 * x.size
    print(f"record: {seconds:g} s at {FS / 1e3:g} kHz ({x.size} samples, one float64 channel "
          f"= {channel / 1e6:.1f} MB); load average {load()}")
    for case, (ours, base) in CASES.items():
        ours(record(warm_up, seed=1))
        base(record(warm_up, seed=1))
        t_ours, t_base = [], []
        r_ours = r_base = None
        for _ in range(repeat):  # interleaved
            t0 = time.perf_counter()
            r_ours = ours(x)
            t_ours.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            r_base = base(x)
            t_base.append(time.perf_counter() - t0)
        if args.quick and case != "kurtogram":  # a smoke run: the workers of one case
            m_ours = m_base = {"traced": float("nan"), "rss": float("nan")}
        else:
            m_ours, m_base = memory(case, 0, path, warm_up), memory(case, 1, path, warm_up)
        to, tb = float(np.median(t_ours)), float(np.median(t_base))
        print(f"\n{case}: median of {repeat} (load average {load()})")
        print(f"  {'':10}{'time [s]':>10}{'traced peak':>16}{'RSS growth':>16}")
        for label, t, m in (("baseline", tb, m_base), ("today", to, m_ours)):
            print(f"  {label:10}{t:10.3f}{m['traced'] / channel:13.2f} ch"
                  f"{m['rss'] / channel:13.2f} ch")  # fmt: skip
        less = m_base["traced"] / max(m_ours["traced"], 1)  # nan: not measured
        print(f"  ratio     {tb / to:9.1f}x faster; {less:.1f}x less memory (traced)")
        if case == "kurtogram":
            assert r_ours is not None and r_base is not None
            rb = np.unravel_index(np.nanargmax(r_base), r_base.shape)
            nb_b = [nb for _, nb in kurtogram_levels(MAX_LEVEL)][rb[0]]
            w = FS / 2 / nb_b
            print(f"  band of largest K: today {r_ours.band.low:.0f}-{r_ours.band.high:.0f} Hz "
                  f"(K = {r_ours.kurtosis_max:.3f}); baseline {rb[1] * w:.0f}-"
                  f"{(rb[1] + 1) * w:.0f} Hz (K = {np.nanmax(r_base):.3f})")
        else:
            assert r_ours is not None and r_base is not None
            f = r_ours.frequency
            k = int(np.argmin(np.abs(f - 87.3)))
            top = k - 3 + int(np.argmax(r_ours.values[k - 3 : k + 4]))
            print(f"  line at {f[top]:.2f} Hz; today/baseline power there "
                  f"{r_ours.values[top] ** 2 / 2 / r_base[top]:.3f} (filters differ)")


if __name__ == "__main__":
    main()
