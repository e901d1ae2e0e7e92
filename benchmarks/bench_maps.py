"""Rpm maps and order analysis: throughput vs scipy.signal.ShortTimeFFT, peak memory of long
recordings.

Run: ``python3 benchmarks/bench_maps.py [--quick]``.

1. Throughput: ``analysis.maps.rpm_frequency_map`` (Hann, resolution fs/128 (MATLAB's
   default) -> 192 samples, 50 % overlap, rms) vs ``ShortTimeFFT.stft`` with the same window
   and hop plus the same rms scaling (ratio > 1: ours faster).
2. Memory: a 10-minute (``--quick``: 6 s), 4-channel, 51.2 kHz float32 recording in an
   xarray Dataset; the map of one channel is computed with ``rpm_frequency_map_ds`` under
   tracemalloc. Target: peak allocation beyond the input < 1.5x the size of one channel in
   float64 (the output map alone is about 1.0x at any resolution with 50 % overlap).
3. Memory of the order analysis of the same channel (``--quick``: all 6 s), angular
   resampling block by block:
   ``rpm_order_map_ds`` (defaults: flat-top, 1/4 order),
   ``order_spectrum`` (0.1-order line spacing) and ``order_cuts`` (orders 3, 7, 20), each under
   tracemalloc with the same target; the order map itself is about 0.55x one channel (the
   run-up holds 0.55x as many revolutions as the top speed would).
"""

from __future__ import annotations

import argparse
import time
import tracemalloc
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.signal
import xarray as xr

from analysis.maps import rpm_frequency_map, rpm_frequency_map_ds, rpm_order_map_ds
from analysis.orders import order_cuts, order_spectrum
from analysis.spectrum import get_window

FS = 51200.0


def throughput(seconds: float, repeat: int = 3) -> None:
    n = int(FS * seconds)
    x = np.random.default_rng(0).standard_normal(n)
    rpm = np.linspace(600, 6000, n)
    seg, hop = 192, 96
    w = get_window("hann", seg)
    stft = scipy.signal.ShortTimeFFT(w, hop=hop, fs=FS, scale_to=None)
    p1 = (n - seg) // hop + 1

    def ref() -> np.ndarray:
        z = stft.stft(x, p0=0, p1=p1, k_offset=seg // 2)
        a = np.abs(z) * (np.sqrt(2.0) / w.sum())
        a[0] /= np.sqrt(2.0)
        a[-1] /= np.sqrt(2.0)
        return a.T

    res = FS / 128  # MATLAB's default resolution: a 192-sample Hann window
    ours = rpm_frequency_map(x, FS, rpm, resolution=res)
    assert np.allclose(ours.values, ref(), rtol=1e-9, atol=1e-14), "results differ"
    t_ours = min(_timed(lambda: rpm_frequency_map(x, FS, rpm, resolution=res))
                 for _ in range(repeat))
    t_ref = min(_timed(ref) for _ in range(repeat))
    print(f"throughput, {seconds:.0f} s at 51.2 kHz ({ours.values.shape[0]} frames of {seg}):")
    print(f"  analysis.maps.rpm_frequency_map: {t_ours:.3f} s ({n / t_ours / 1e6:.1f} Msamples/s)")
    print(f"  scipy ShortTimeFFT.stft + |.|:  {t_ref:.3f} s ({n / t_ref / 1e6:.1f} Msamples/s)")
    print(f"  ratio scipy/ours: {t_ref / t_ours:.2f}")


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def _traced(fn: Callable[[], Any]) -> tuple[int, float, Any]:
    """Peak allocation beyond the start [bytes], wall time [s] and result of ``fn()``."""
    tracemalloc.start()
    tracemalloc.reset_peak()
    base, _ = tracemalloc.get_traced_memory()
    t0 = time.perf_counter()
    result = fn()
    elapsed = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak - base, elapsed, result


def memory(minutes: float, order_minutes: float) -> None:
    n = int(FS * 60 * minutes)
    rng = np.random.default_rng(1)
    t = np.arange(n) / FS
    rpm = np.linspace(600.0, 6000.0, n)
    data = np.empty((4, n), dtype=np.float32)
    for c in range(4):
        data[c] = rng.standard_normal(n, dtype=np.float32)
    ds = xr.Dataset(
        {"acceleration": (("channel", "time"), data, {"units": "m s-2"})},
        coords={
            "time": ("time", t, {"units": "s"}),
            "channel": ["ring_x", "ring_y", "carrier_z", "housing"],
            "shaft_speed": ("time", rpm, {"units": "min-1"}),
        },
    )
    one = ds.isel(channel=0)  # a view, no copy
    channel_f64 = n * 8
    extra, elapsed, m = _traced(lambda: rpm_frequency_map_ds(one, "acceleration", "shaft_speed"))
    print(f"  speed reference found by attributes: {one.gearvib.reference().label}")
    print(f"memory, {minutes:g}-min 4-channel float32 recording ({n} samples/channel):")
    print(
        f"  one channel in float64: {channel_f64 / 1e6:.1f} MB; map output: "
        f"{m.values.nbytes / 1e6:.1f} MB ({m.values.shape})"
    )
    print(
        f"  peak allocation beyond the input: {extra / 1e6:.1f} MB = "
        f"{extra / channel_f64:.2f}x one channel (target < 1.5x); time {elapsed:.1f} s"
    )
    n_ord = min(n, int(FS * 60 * order_minutes))
    part = one.isel(time=slice(0, n_ord))  # views of the recording, no copies
    x = part["acceleration"].values
    t = part["time"].values
    rpm = part["shaft_speed"].values
    cases: list[tuple[str, Callable[[], Any]]] = [
        ("rpm_order_map", lambda: rpm_order_map_ds(part, "acceleration", "shaft_speed")),
        # line spacing 0.1 order: resolution (ENBW) = 3.77 lines of the flat-top
        ("order_spectrum", lambda: order_spectrum(x, None, rpm, time=t, resolution=0.377)),
        ("order_cuts", lambda: order_cuts(x, None, rpm, [3, 7, 20], time=t)),
    ]
    print(f"  order analysis of {n_ord / FS:g} s (block-wise angular resampling):")
    for label, fn in cases:
        extra, elapsed, r = _traced(fn)
        print(
            f"  {label + ':':<16}peak beyond the input {extra / 1e6:6.1f} MB = "
            f"{extra / (8 * n_ord):.2f}x one channel (target < 1.5x; output "
            f"{r.values.nbytes / 1e6:.1f} MB); time {elapsed:.1f} s"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: 2 s (throughput, one run) and a 6 s recording")
    args = parser.parse_args()
    throughput(2.0 if args.quick else 60.0, 1 if args.quick else 3)
    if args.quick:
        memory(0.1, order_minutes=0.1)
    else:
        memory(10.0, order_minutes=10.0)


if __name__ == "__main__":
    main()
