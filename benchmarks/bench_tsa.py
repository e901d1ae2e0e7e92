"""Time-synchronous averaging and planetary separation of a long record: time and memory.

Run: ``python benchmarks/bench_tsa.py [--quick] [--repeat N]``.

Record: 10 minutes (``--quick``: 5 s, one run of each), 4 channels, 25.6 kHz, float64 (123 MB
per channel, 491 MB in all), a shaft at 1500 min-1 +- 1 % with a once-per-revolution tacho
(float64, part of the input), each channel a component at order 37, a ring-mesh component (order
83, amplitude 0.5: the tacho is also taken as the carrier's) and unit Gaussian noise.

1. ``analysis.tsa.tsa(x, fs, tacho=..., pulses_per_rev=1)`` (default angular sampling)
   against a straightforward implementation written here: the tacho's angle on every sample
   (``analysis.speed.from_tacho`` on the whole time axis), the whole record interpolated
   linearly (``numpy.interp``) onto whole revolutions, reshaped and averaged.
2. ``analysis.planetary_tsa.planetary_tsa`` (the tacho taken as the carrier's; 21/31/83
   teeth, 4 planets) against the same whole-record resampling followed by the window weights
   and ``numpy.bincount`` on whole-record arrays.

Wall time: median of ``--repeat`` runs, interleaved (A, B, A, B ...). Memory: peak of the
allocations traced by :mod:`tracemalloc` (numpy's) beyond the input, in units of one float64
channel, from one extra run of each. The accuracy column is the error of the order-37
amplitude of channel 0 (true value 1) for the TSA, of the mesh order (31 on a planet's axis,
true value 0.5) of planet 1, channel 0, for the separation. The load of the machine
(``os.getloadavg``) is printed beside the figures.
"""

from __future__ import annotations

import argparse
import math
import os
import time
import tracemalloc
from collections.abc import Callable
from typing import Any

import numpy as np

from analysis.planetary_tsa import planetary_tsa
from analysis.speed import from_tacho
from analysis.tsa import tsa

FS = 25600.0
SHAFT_HZ = 25.0
CHANNELS = 4
ORDER = 37
ZS, ZP, ZR, NP = 21, 31, 83, 4
MESH = 0.5  # amplitude of the ring-mesh component (carrier order ZR)


def record(seconds: float) -> tuple[np.ndarray, np.ndarray]:
    """``(x, tacho)``: ``x`` of shape ``(4, n)`` float64 and a once-per-revolution tacho."""
    n = int(seconds * FS)
    x = np.empty((CHANNELS, n))
    tacho = np.empty(n)
    rng = np.random.default_rng(0)
    step = 1 << 20
    for a in range(0, n, step):  # built in blocks: the input itself is the only big array
        t = np.arange(a, min(n, a + step)) / FS
        theta = 2 * np.pi * SHAFT_HZ * (t + 0.01 * np.sin(2 * np.pi * 0.3 * t) / (2 * np.pi * 0.3))
        for c in range(CHANNELS):
            x[c, a : a + t.size] = (
                np.cos(ORDER * theta + c) + MESH * np.cos(ZR * theta + 0.2 * c)
                + rng.normal(0.0, 1.0, t.size)
            )  # fmt: skip
        tacho[a : a + t.size] = np.mod(theta, 2 * np.pi) < 0.5
    return x, tacho


def _whole_record_grid(tacho: np.ndarray, spr: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Instants of whole revolutions at ``spr`` samples each (straightforward way)."""
    n = tacho.size
    t = np.arange(n) / FS
    ref = from_tacho(tacho, FS, 1, output_time=t)
    theta = ref.angle
    k0 = math.ceil(theta[0] / (2 * np.pi))
    k1 = math.floor(theta[-1] / (2 * np.pi))
    grid = 2 * np.pi * (k0 + np.arange((k1 - k0) * spr) / spr)
    tq = np.interp(grid, theta, t)
    return t, tq, 2 * np.pi * k0


def straightforward_tsa(x: np.ndarray, tacho: np.ndarray, spr: int) -> np.ndarray:
    """Resample the whole record by linear interpolation, reshape, mean."""
    t, tq, _ = _whole_record_grid(tacho, spr)
    out = np.empty((x.shape[0], spr))
    for c in range(x.shape[0]):
        out[c] = np.interp(tq, t, x[c]).reshape(-1, spr).mean(axis=0)
    return out


def straightforward_planetary(x: np.ndarray, tacho: np.ndarray, spt: int) -> np.ndarray:
    """Whole-record resampling onto the carrier, Hann windows, bincount on whole arrays."""
    spr = ZR * spt
    t, tq, a0 = _whole_record_grid(tacho, spr)
    j = np.arange(tq.size)
    width = max(2, ZR // NP) * spt  # samples, as the default of planetary_tsa
    out = np.empty((NP, x.shape[0], ZP * spt))
    resampled = [np.interp(tq, t, x[c]) for c in range(x.shape[0])]
    for p in range(NP):
        psi = 2 * np.pi * p / NP
        rho = np.mod(j + spr * psi / (2 * np.pi) + spr / 2, spr) - spr / 2
        w = np.where(np.abs(rho) < width / 2, np.cos(np.pi * rho / width) ** 2, 0.0)
        b = np.mod(j + round(spr * psi / (2 * np.pi) + a0 * spr / (2 * np.pi)), ZP * spt)
        den = np.bincount(b, weights=w, minlength=ZP * spt)
        for c in range(x.shape[0]):
            out[p, c] = np.bincount(b, weights=w * resampled[c], minlength=ZP * spt) / den
    return out


def _traced(fn: Callable[[], Any]) -> tuple[int, Any]:
    tracemalloc.start()
    tracemalloc.reset_peak()
    base, _ = tracemalloc.get_traced_memory()
    result = fn()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak - base, result


def _order_error(values: np.ndarray, order: int, amplitude: float = 1.0) -> float:
    n = values.shape[-1]
    return abs(2.0 * abs(np.fft.rfft(values)[order]) / n - amplitude)


def compare(name: str, ours: Callable[[], Any], base: Callable[[], Any], repeat: int,
            channel_bytes: int, err: Callable[[Any], float]) -> None:  # fmt: skip
    times: dict[str, list[float]] = {"ours": [], "base": []}
    for _ in range(repeat):
        for key, fn in (("ours", ours), ("base", base)):
            t0 = time.perf_counter()
            fn()
            times[key].append(time.perf_counter() - t0)
    mem_o, res_o = _traced(ours)
    mem_b, res_b = _traced(base)
    to, tb = float(np.median(times["ours"])), float(np.median(times["base"]))
    e_o, e_b = err(res_o), err(res_b)
    print(f"{name}:")
    print(f"  {'':24s} {'time [s]':>9s} {'memory [channels]':>18s} {'amplitude error':>15s}")
    print(f"  {'analysis (block-wise)':24s} {to:9.2f} {mem_o / channel_bytes:18.3f} {e_o:15.2e}")
    print(f"  {'straightforward':24s} {tb:9.2f} {mem_b / channel_bytes:18.3f} {e_b:15.2e}")
    print(f"  ratios analysis/straightforward: time {to / tb:.2f}, memory "
          f"{mem_o / max(mem_b, 1):.3f}")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="smoke run: 5 s record instead of 10 minutes, one run of each")
    ap.add_argument("--repeat", type=int, default=3, help="timed runs of each (median)")
    args = ap.parse_args()
    seconds = 5.0 if args.quick else 600.0
    repeat = 1 if args.quick else args.repeat
    x, tacho = record(seconds)
    channel = x.shape[1] * 8
    print(f"record: {seconds:g} s, {CHANNELS} channels at {FS:g} Hz, float64 "
          f"({channel / 1e6:.0f} MB per channel); load {os.getloadavg()[0]:.2f}")  # fmt: skip
    # warm-up: compile or load the numba kernels once
    tsa(x[:, : int(4 * FS)], FS, tacho=tacho[: int(4 * FS)])
    r0 = tsa(x[:, : int(4 * FS)], FS, tacho=tacho[: int(4 * FS)])
    spr = r0.samples_per_rev

    def ours_tsa() -> np.ndarray:
        return tsa(x, FS, tacho=tacho, pulses_per_rev=1, samples_per_rev=spr).values

    compare("TSA", ours_tsa, lambda: straightforward_tsa(x, tacho, spr), repeat, channel,
            lambda v: _order_error(v[0], ORDER))  # fmt: skip
    spt = planetary_tsa(x[:, : int(4 * FS)], FS, tacho=tacho[: int(4 * FS)], z_sun=ZS,
                        z_planet=ZP, z_ring=ZR, n_planets=NP).samples_per_tooth  # fmt: skip

    def ours_planetary() -> np.ndarray:
        sep = planetary_tsa(x, FS, tacho=tacho, z_sun=ZS, z_planet=ZP, z_ring=ZR, n_planets=NP,
                            samples_per_tooth=spt)  # fmt: skip
        return np.stack([p.values for p in sep.planets])

    compare("planetary separation (4 planets + sun)", ours_planetary,
            lambda: straightforward_planetary(x, tacho, spt), repeat, channel,
            lambda v: _order_error(v[0, 0], ZP, MESH))  # fmt: skip
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
