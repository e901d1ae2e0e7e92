"""Throughput of analysis.spectrum.spectrum vs the same Welch average done with numpy.fft and
scipy.fft.

Run: ``python3 benchmarks/bench_spectrum.py [--quick]``. Prints the time per call and the
ratios (> 1 means analysis.spectrum is faster). The references compute exactly the same
estimate (Hann window, 50 % overlap, power averaged, peak scaling); the first reference
result is checked against ours before timing.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np
import scipy.fft

from analysis.fft import backend
from analysis.spectrum import get_window, spectrum


def _reference(fft: Callable[..., np.ndarray], x: np.ndarray, seg: int) -> np.ndarray:
    w = get_window("hann", seg)
    frames = np.lib.stride_tricks.sliding_window_view(x, seg)[:: seg // 2]
    acc = np.zeros(seg // 2 + 1)
    block = max(1, (1 << 20) // seg)
    for s in range(0, frames.shape[0], block):
        spec = fft(frames[s : s + block] * w, axis=-1)
        acc += (spec.real**2 + spec.imag**2).sum(axis=0)
    p = acc / frames.shape[0] * 4 / w.sum() ** 2
    p[0] /= 4
    p[-1] /= 4
    return np.sqrt(p)


def _best(fn: Callable[[], object], repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="small signal, few repeats")
    args = parser.parse_args()
    fs = 51200.0
    n = int(fs * (5 if args.quick else 60))
    repeat = 3 if args.quick else 5
    x = np.random.default_rng(0).standard_normal(n)
    print(f"backend: {backend()}, signal: {n} samples ({n / fs:.0f} s at {fs:.0f} Hz), 1 thread")
    print(
        f"{'segment':>8} {'ours [ms]':>10} {'numpy [ms]':>11} {'scipy [ms]':>11}"
        f" {'numpy/ours':>11} {'scipy/ours':>11}"
    )
    for seg in (256, 1024, 4096, 16384, 65536):
        ours = spectrum(x, fs, window="hann", scaling="peak", segment_length=seg, overlap=0.5)
        ref = _reference(np.fft.rfft, x, seg)
        assert np.allclose(ours.values, ref, rtol=1e-9, atol=1e-15), "results differ"
        t_ours = _best(
            lambda s=seg: spectrum(x, fs, window="hann", segment_length=s, overlap=0.5), repeat
        )
        t_np = _best(lambda s=seg: _reference(np.fft.rfft, x, s), repeat)
        t_sp = _best(lambda s=seg: _reference(scipy.fft.rfft, x, s), repeat)
        print(
            f"{seg:>8} {1e3 * t_ours:>10.1f} {1e3 * t_np:>11.1f} {1e3 * t_sp:>11.1f}"
            f" {t_np / t_ours:>11.2f} {t_sp / t_ours:>11.2f}"
        )


if __name__ == "__main__":
    main()
