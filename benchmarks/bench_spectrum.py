"""Throughput of analysis.spectrum.spectrum vs the same Welch average done with numpy.fft and
scipy.fft.

Run: ``python3 benchmarks/bench_spectrum.py [--quick] [--repeat N] [--workers N] [--fallback]``.
Prints the time per call, the ratios side by side (> 1 means analysis.spectrum is faster) and
the peak memory that one call of ours allocates (tracemalloc, plans already cached).
``--fallback`` times our scipy.fft fallback path (as if pyFFTW were not installed). The
references compute exactly the same estimate (Hann window, 50 % overlap, power averaged, peak
scaling) with a plain loop over blocks of frames, ``fft(frames * w)`` then ``|X|^2`` summed;
the reference result is checked against ours before timing.

The three candidates are timed round-robin (ours, numpy, scipy, ours, ...) and the best of
``--repeat`` rounds is kept, so that load from other processes on the machine hits all three
alike instead of skewing one column.
"""

from __future__ import annotations

import argparse
import time
import tracemalloc
from collections.abc import Callable

import numpy as np
import scipy.fft

import analysis.fft
from analysis.fft import backend
from analysis.spectrum import get_window, spectrum

SEGMENTS = (256, 1024, 4096, 16384, 65536)


def _reference(fft: Callable[..., np.ndarray], x: np.ndarray, seg: int, workers: int) -> np.ndarray:
    """Welch peak spectrum with a plain block loop over ``fft`` (numpy.fft or scipy.fft)."""
    w = get_window("hann", seg)
    frames = np.lib.stride_tricks.sliding_window_view(x, seg)[:: seg // 2]
    acc = np.zeros(seg // 2 + 1)
    block = max(1, (1 << 20) // seg)
    kwargs = {"workers": workers} if fft is scipy.fft.rfft else {}
    for s in range(0, frames.shape[0], block):
        spec = fft(frames[s : s + block] * w, axis=-1, **kwargs)
        acc += (spec.real**2 + spec.imag**2).sum(axis=0)
    p = acc / frames.shape[0] * 4 / w.sum() ** 2
    p[0] /= 4
    p[-1] /= 4
    return np.sqrt(p)


def _best_round_robin(fns: list[Callable[[], object]], repeat: int) -> list[float]:
    """Best wall time of each callable over ``repeat`` interleaved rounds (one warm-up)."""
    for fn in fns:
        fn()
    best = [np.inf] * len(fns)
    for _ in range(repeat):
        for i, fn in enumerate(fns):
            t0 = time.perf_counter()
            fn()
            best[i] = min(best[i], time.perf_counter() - t0)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="smoke run: 2 s signal, one round")
    parser.add_argument("--repeat", type=int, default=None, help="rounds (default 9; --quick: 1)")
    parser.add_argument("--workers", type=int, default=1, help="FFT threads (all candidates)")
    parser.add_argument("--fallback", action="store_true", help="time our scipy.fft fallback")
    args = parser.parse_args()
    if args.fallback:
        analysis.fft._pyfftw = None
    fs = 51200.0
    n = int(fs * (2 if args.quick else 60))
    repeat = args.repeat if args.repeat is not None else (1 if args.quick else 9)
    x = np.random.default_rng(0).standard_normal(n)
    print(
        f"backend: {backend()}, signal: {n} samples ({n / fs:.0f} s at {fs:.0f} Hz), "
        f"{args.workers} thread(s) (numpy.fft is always 1), best of {repeat}"
    )
    print(
        f"{'segment':>8} {'ours [ms]':>10} {'numpy [ms]':>11} {'scipy [ms]':>11}"
        f" {'numpy/ours':>11} {'scipy/ours':>11} {'ours peak [MB]':>15}"
    )
    for seg in SEGMENTS:

        def ours(s: int = seg) -> object:
            return spectrum(x, fs, window="hann", segment_length=s, workers=args.workers)

        ref = _reference(np.fft.rfft, x, seg, args.workers)
        got = spectrum(x, fs, window="hann", amplitude="peak", segment_length=seg, overlap=0.5)
        assert np.allclose(got.values, ref, rtol=1e-9, atol=1e-15), "results differ"
        t_ours, t_np, t_sp = _best_round_robin(
            [
                ours,
                lambda s=seg: _reference(np.fft.rfft, x, s, args.workers),
                lambda s=seg: _reference(scipy.fft.rfft, x, s, args.workers),
            ],
            repeat,
        )
        tracemalloc.start()
        ours()
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        print(
            f"{seg:>8} {1e3 * t_ours:>10.1f} {1e3 * t_np:>11.1f} {1e3 * t_sp:>11.1f}"
            f" {t_np / t_ours:>11.2f} {t_sp / t_ours:>11.2f} {peak / 2**20:>15.1f}"
        )


if __name__ == "__main__":
    main()
