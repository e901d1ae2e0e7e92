"""Reading speed of analysis.readers against the plain library calls, side by side.

Run: ``python3 benchmarks/bench_readers.py [--rows N] [--repeat N] [--quick]``.

* **CSV**: ``read_csv(path, time_column=0)`` on N rows x 4 columns (time printed ``%.8f`` at
  25.6 kHz, three channels ``%.6e``; default 10**6 rows, 52 MB) against
  ``numpy.loadtxt(path, delimiter=",", skiprows=1)`` -- the same C parser without the header,
  unit, truncation and time-grid checks and without building the Dataset -- and against a
  line-by-line Python parse (``str.split`` and ``float`` per value), which is how the reader
  worked before (issue #14: 6 s for 10**6 x 4).
* **WAV**: ``read_wav`` (own RIFF/RF64 parser with size checks) against
  ``scipy.io.wavfile.read`` on a 4-channel 16-bit file of N frames.
* **MAT**: ``read_mat`` (structure walk before ``scipy.io.loadmat``, then the Dataset)
  against ``scipy.io.loadmat`` alone, on a compressed v7 file with 4 channels of N samples.

The candidates of a row are timed round-robin and the best of ``--repeat`` rounds is kept, so
that load from other processes hits them alike. Ratios > 1 mean analysis.readers is faster.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from scipy.io import loadmat, savemat, wavfile

from analysis.readers import read_csv, read_mat, read_wav

FS = 25600.0


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


def _python_loop(path: Path) -> np.ndarray:
    """Line-by-line parse as the reader did before: split, float per value."""
    with open(path) as fh:
        lines = fh.read().splitlines()[1:]
    out = np.empty((len(lines), len(lines[0].split(","))))
    for row, line in enumerate(lines):
        for col, tok in enumerate(line.split(",")):
            out[row, col] = float(tok)
    return out


def _data(rows: int) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(rows) / FS
    rng = np.random.default_rng(0)
    return t, rng.standard_normal((rows, 3))


def bench_csv(folder: Path, rows: int, repeat: int, loop: bool) -> None:
    t, x = _data(rows)
    path = folder / "run.csv"
    np.savetxt(
        path,
        np.column_stack([t, x]),
        delimiter=",",
        fmt=["%.8f", "%.6e", "%.6e", "%.6e"],
        header="time [s],a [m/s2],b [m/s2],c [V]",
        comments="",
    )
    ds = read_csv(path, time_column=0)
    ref = np.loadtxt(path, delimiter=",", skiprows=1)
    assert ds.attrs["sample_rate_hz"] == FS and np.array_equal(ds.a.values, ref[:, 1])
    fns: list[Callable[[], object]] = [
        lambda: read_csv(path, time_column=0),
        lambda: np.loadtxt(path, delimiter=",", skiprows=1),
    ]
    if loop:
        fns.append(lambda: _python_loop(path))
    best = _best_round_robin(fns, repeat)
    size = path.stat().st_size / 1e6
    print(f"CSV  {rows:>9} rows x 4 columns ({size:.0f} MB)")
    print(f"     read_csv       {best[0]:7.3f} s  ({rows / best[0] / 1e6:.2f} Mrows/s)")
    print(f"     numpy.loadtxt  {best[1]:7.3f} s  ratio loadtxt/read_csv = {best[1] / best[0]:.2f}")
    if loop:
        print(
            f"     Python loop    {best[2]:7.3f} s  ratio loop/read_csv = {best[2] / best[0]:.1f}"
        )


def bench_wav(folder: Path, rows: int, repeat: int) -> None:
    rng = np.random.default_rng(1)
    x = rng.integers(-30000, 30000, (rows, 4), dtype=np.int16)
    path = folder / "run.wav"
    wavfile.write(path, int(FS), x)
    ds = read_wav(path)
    assert np.array_equal(ds.ch3.values, x[:, 2])
    best = _best_round_robin([lambda: read_wav(path), lambda: wavfile.read(path)], repeat)
    print(f"WAV  {rows:>9} frames x 4 channels, 16 bit")
    print(f"     read_wav       {best[0]:7.3f} s")
    print(f"     wavfile.read   {best[1]:7.3f} s  ratio wavfile/read_wav = {best[1] / best[0]:.2f}")


def bench_mat(folder: Path, rows: int, repeat: int) -> None:
    t, x = _data(rows)
    path = folder / "run.mat"
    savemat(path, {"acc": x, "tacho": np.sin(t), "fs": FS}, do_compression=True)
    ds = read_mat(path)
    assert np.array_equal(ds.acc_2.values, x[:, 1])
    best = _best_round_robin(
        [lambda: read_mat(path), lambda: loadmat(path, squeeze_me=True)], repeat
    )
    print(f"MAT  {rows:>9} samples x 4 channels, compressed v7")
    print(f"     read_mat       {best[0]:7.3f} s")
    print(f"     scipy loadmat  {best[1]:7.3f} s  ratio loadmat/read_mat = {best[1] / best[0]:.2f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="10**5 rows, no Python loop")
    args = parser.parse_args()
    rows = 100_000 if args.quick else args.rows
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        bench_csv(folder, rows, args.repeat, loop=not args.quick)
        bench_wav(folder, rows, args.repeat)
        bench_mat(folder, rows, args.repeat)


if __name__ == "__main__":
    main()
