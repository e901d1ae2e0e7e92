"""Order analysis: today's implementation against the baseline before the compiled resampler.

Run: ``python benchmarks/bench_orders.py [--quick] [--baseline COMMIT]``.

The baseline is the ``analysis`` package of ``COMMIT`` (default ``4dda194``, the last commit
before issue #14), extracted with ``git archive`` into a temporary folder and imported under
the name ``analysis_baseline``, so both run side by side in one process on the same input.

1. Resampling throughput: ``resample_to_angle`` of 60 s (``--quick``: 1 s, once) of one channel at
   51.2 kHz, a 600 -> 6000 min-1 run-up, default angular sampling (512 samples per
   revolution, 6x oversampling); input samples per second, best of 3, and the ratio.
2. The four order-analysis functions on a 10-minute (``--quick``: 1.5 s), 4-channel,
   51.2 kHz float32 recording (the one of ``bench_maps.py``): ``resample_to_angle``,
   ``rpm_order_map`` (the baseline's defaults, passed explicitly to today's),
   ``order_spectrum`` (0.1-order line spacing) and ``order_cuts`` (orders 3, 7, 20, the
   baseline's defaults). Wall time and peak memory beyond the input (tracemalloc)
   for one channel, baseline and today side by side, and today's for all 4 channels in one
   call (the baseline takes one channel per call: its 4-channel figure is 4x its one).
   The results of both are compared (maximum relative difference of the outputs).
3. The defaults of issue 29 against the previous defaults, passed explicitly
   (``resolution = samples_per_rev / 256`` at the sampling of ``fs`` at the top speed; the
   frequency map's ``fs / 128``), on the issue's signal: 20 s (``--quick``: 2 s) at 51.2 kHz,
   600 -> 3000 min-1, orders 1, 2.5 and 24. Runs interleaved (new, old, new, old ...),
   medians of 3 (``--quick``: 1), the machine load (``uptime``) printed beside them, and the
   largest level error of each (order cuts and order spectrum against the true rms).
"""

from __future__ import annotations

import argparse
import importlib
import os
import subprocess
import sys
import tempfile
import time
import tracemalloc
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from analysis.maps import rpm_frequency_map, rpm_order_map
from analysis.orders import order_cuts, order_spectrum, resample_to_angle

FS = 51200.0
REPO = Path(__file__).resolve().parent.parent


def load_baseline(commit: str, where: Path) -> Any | None:
    """The ``analysis`` package of ``commit`` as module ``analysis_baseline``; None when the
    commit cannot be read (no git, a shallow clone, an archive of the sources)."""
    try:
        archive = subprocess.run(["git", "-C", str(REPO), "archive", commit, "analysis"],
                                 capture_output=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError) as exc:
        err = getattr(exc, "stderr", b"") or b""
        print(f"baseline commit {commit} not available ({err.decode().strip() or exc}): parts "
              "1 and 2 skipped (they need the git history, e.g. not a shallow clone)")
        return None
    subprocess.run(["tar", "-x", "-C", str(where)], input=archive, check=True)
    pkg = where / "analysis_baseline"
    (where / "analysis").rename(pkg)
    for f in pkg.rglob("*.py"):
        f.write_text(f.read_text().replace("analysis.", "analysis_baseline."))
    sys.path.insert(0, str(where))
    return importlib.import_module("analysis_baseline")


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


def _best(fn: Callable[[], Any], repeat: int = 3) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.ndim and a.shape != b.shape:  # today's order axis ends at max_order: common lines
        n = min(a.shape[-1], b.shape[-1])
        a, b = a[..., :n], b[..., :n]
    ok = np.isfinite(a) & np.isfinite(b)
    return float(np.max(np.abs(a[ok] - b[ok])) / np.max(np.abs(b[ok])))


def throughput(seconds: float, old: Any, repeat: int = 3) -> None:
    n = int(FS * seconds)
    t = np.arange(n) / FS
    rpm = np.linspace(600.0, 6000.0, n)
    theta = old.orders.angle_from_speed(t, rpm)
    x = np.random.default_rng(0).standard_normal(n)
    spr = 512
    ours = resample_to_angle(x, FS, angle=theta, samples_per_rev=spr)  # compiles
    ref = old.orders.resample_to_angle(x, t, theta, spr)
    t_ours = _best(lambda: resample_to_angle(x, FS, angle=theta, samples_per_rev=spr), repeat)
    t_ref = _best(lambda: old.orders.resample_to_angle(x, t, theta, spr),
                  1 if n > 2e6 else repeat)
    print(f"1. resampling, {seconds:g} s at 51.2 kHz ({n} samples, {ours.oversampling}x "
          f"oversampling, {ours.values.size} output samples):")
    print(f"   baseline: {t_ref:7.3f} s = {n / t_ref / 1e6:6.2f} Msamples/s")
    print(f"   today:    {t_ours:7.3f} s = {n / t_ours / 1e6:6.2f} Msamples/s")
    print(f"   ratio {t_ref / t_ours:.1f}x; max difference {_rel(ours.values, ref.values):.1e} "
          "of the largest sample")


def recording(minutes: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    n = int(FS * 60 * minutes)
    rng = np.random.default_rng(1)
    data = np.empty((4, n), dtype=np.float32)
    for c in range(4):
        data[c] = rng.standard_normal(n, dtype=np.float32)
    return np.arange(n) / FS, np.linspace(600.0, 6000.0, n), data


def functions(minutes: float, old: Any, only: set[str] | None = None) -> None:
    t, rpm, data = recording(minutes)
    x = data[0]
    n = x.size
    channel = 8 * n
    # order_spectrum: the baseline's orders_resolution (line spacing 0.1) is today's
    # resolution = flat-top ENBW x 0.1 (the same segment length)
    enbw = 3.770221
    # the baseline's defaults, passed explicitly (today's defaults resolve the orders, part 3):
    # samples_per_rev 2 ceil(fs / 2 / 100 Hz) = 512, resolution 512 / 256 = 2 orders
    prev = {"resolution": 512 / 256, "samples_per_rev": 512}
    cases: list[tuple[str, Callable[..., Any], Callable[[], Any]]] = [
        (
            "resample_to_angle",
            lambda xx, **k: resample_to_angle(xx, FS, rpm=rpm, samples_per_rev=512, **k),
            lambda: old.orders.resample_to_angle(x, t, old.orders.angle_from_speed(t, rpm), 512),
        ),
        (
            "rpm_order_map",
            lambda xx, **k: rpm_order_map(xx, FS, rpm, **prev, **k),
            lambda: old.maps.rpm_order_map(x, FS, rpm),
        ),
        (
            "order_spectrum",
            lambda xx, **k: order_spectrum(xx, FS, rpm, resolution=0.1 * enbw, **k),
            lambda: old.orders.order_spectrum(x, t, rpm, orders_resolution=0.1),
        ),
        (
            "order_cuts",
            lambda xx, **k: order_cuts(xx, FS, rpm, [3, 7, 20], **prev, **k),
            lambda: old.orders.order_cuts(x, FS, rpm, [3, 7, 20]),
        ),
    ]
    print(f"2. {minutes:g}-min, 4-channel, 51.2 kHz float32 recording ({n} samples/channel, "
          f"{channel / 1e6:.0f} MB per channel in float64); memory = peak beyond the input:")
    print(f"   {'':18}{'baseline, 1 ch':>22}{'today, 1 ch':>22}{'ratio':>7}"
          f"{'today, 4 ch':>22}{'4x baseline / today':>21}")
    for label, ours_fn, ref_fn in cases:
        if only and label not in only:
            continue
        m_ref, t_ref, r_ref = _traced(ref_fn)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the baseline's bands overlap (warned today)
            m_one, t_one, r_one = _traced(lambda f=ours_fn: f(x))
            m_four, t_four, r_four = _traced(lambda f=ours_fn: f(data, axis=-1))
        assert np.array_equal(r_four.values[0], r_one.values), "4 channels != channel alone"
        print(f"   {label:18}{t_ref:8.1f} s {m_ref / channel:5.2f}x ch{t_one:10.1f} s "
              f"{m_one / channel:5.2f}x ch{t_ref / t_one:6.1f}x{t_four:10.1f} s "
              f"{m_four / channel:5.2f}x ch{4 * t_ref / t_four:12.1f}x   "
              f"(max difference {_rel(r_one.values, r_ref.values):.1e})")


def defaults(seconds: float, repeat: int) -> None:
    """Part 3: the defaults of issue 29 against the previous ones, side by side."""
    n = int(FS * seconds)
    t = np.arange(n) / FS
    rpm = 600.0 + 2400.0 * t / seconds
    phi = 2 * np.pi * (600.0 / 60 * t + 0.5 * 2400.0 / 60 / seconds * t**2)
    x = np.sin(phi) + 0.5 * np.sin(2.5 * phi) + 2.0 * np.sin(24 * phi)
    ords = [1.0, 2.5, 24.0]
    rms = np.array([1.0, 0.5, 2.0]) / np.sqrt(2)
    spr = 2 * int(np.ceil(FS / 2 / (rpm.max() / 60)))  # the previous default sampling
    old = {"resolution": spr / 256, "samples_per_rev": spr}

    def cut_err(c: Any) -> float:
        return float(np.nanmax(np.abs(20 * np.log10(c.values / rms[:, None]))))

    def spec_err(s: Any) -> float:
        k = [int(np.argmin(np.abs(s.order - o))) for o in ords]
        return float(np.max(np.abs(20 * np.log10(s.values[k] / rms))))

    cases: list[tuple[str, Callable[[], Any], Callable[[], Any], Callable[[Any], str]]] = [
        ("rpm_order_map", lambda: rpm_order_map(x, FS, rpm),
         lambda: rpm_order_map(x, FS, rpm, **old),
         lambda m: f"{m.resolution_orders:.3g} orders, {m.values.shape[-1]} lines"),
        ("order_spectrum", lambda: order_spectrum(x, FS, rpm, max_order=30),
         lambda: order_spectrum(x, FS, rpm, **old),
         lambda s: f"{s.resolution_orders:.3g} orders, error {spec_err(s):.2f} dB"),
        ("order_cuts", lambda: order_cuts(x, FS, rpm, ords),
         lambda: order_cuts(x, FS, rpm, ords, **old),
         lambda c: f"band {c.bandwidth:.3g} orders, error {cut_err(c):.2f} dB"),
        ("rpm_frequency_map", lambda: rpm_frequency_map(x, FS, rpm),
         lambda: rpm_frequency_map(x, FS, rpm, resolution=FS / 128),
         lambda m: f"{m.resolution_hz:.3g} Hz, {m.time.size} frames"),
    ]
    load = os.getloadavg()
    print(f"3. defaults of issue 29 vs the previous ones, {seconds:g} s at 51.2 kHz, "
          f"600 -> 3000 min-1, orders 1, 2.5, 24; medians of {repeat} interleaved runs; "
          f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} on {os.cpu_count()} cores:")
    print(f"   {'':18}{'new default':>14}{'previous':>12}{'ratio':>8}   new | previous")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the previous defaults' bands overlap (warned)
        for label, new_fn, old_fn, what in cases:
            r_new, r_old = new_fn(), old_fn()  # warm-up (compilation, plans)
            t_new, t_old = [], []
            for _ in range(repeat):
                t_new.append(_best(new_fn, 1))
                t_old.append(_best(old_fn, 1))
            tn, to = float(np.median(t_new)), float(np.median(t_old))
            print(f"   {label:18}{tn:12.3f} s{to:10.3f} s{tn / to:7.2f}x   "
                  f"{what(r_new)} | {what(r_old)}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: short signals (1 s, 1.5 s, 2 s), one run of each")
    parser.add_argument("--baseline", default="4dda194", help="git commit of the baseline")
    parser.add_argument("--only", default="", help="comma-separated functions of part 2")
    parser.add_argument("--defaults", action="store_true", help="part 3 only")
    args = parser.parse_args()
    seconds3, repeat3 = (2.0, 1) if args.quick else (20.0, 3)
    if args.defaults:
        defaults(seconds3, repeat3)
        return
    with tempfile.TemporaryDirectory() as tmp:
        old = load_baseline(args.baseline, Path(tmp))
        if old is not None:
            importlib.import_module("analysis_baseline.orders")
            importlib.import_module("analysis_baseline.maps")
            only = {f for f in args.only.split(",") if f}
            if not only:
                throughput(1.0 if args.quick else 60.0, old, 1 if args.quick else 3)
            functions(0.025 if args.quick else 10.0, old, only or None)
    if not args.only:
        defaults(seconds3, repeat3)


if __name__ == "__main__":
    main()
