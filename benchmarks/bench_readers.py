"""Reading speed of analysis.readers against the plain library calls, side by side.

Run: ``python3 benchmarks/bench_readers.py [--rows N] [--repeat N] [--quick]``.

* **CSV**: ``read_csv(path, time_column=0)`` on N rows x 4 columns at 25.6 kHz (default
  10**6 rows), printed as a DAQ export does (time ``%.8f``, values ``%.6e``; 52 MB) and with
  full precision (``%.17g``; 78 MB), against ``numpy.loadtxt(path, delimiter=",",
  skiprows=1)``, against ``pandas.read_csv`` alone (the C parser read_csv uses, without the
  header, unit, truncation and time-grid checks and without building the Dataset) and
  against the previous reader's line-by-line Python parse (``str.split`` and ``float`` per
  value, as gearvib did before issue #14, which measured 6 s for 10**6 x 4).
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


def _token(tok: str, decimal_comma: bool) -> float:
    tok = tok.strip()
    if not tok:
        return float("nan")
    if decimal_comma:
        tok = tok.replace(",", ".")
    return float(tok)


def _previous_parse(path: Path) -> np.ndarray:
    """The parse of the previous reader (gearvib before issue #14), line by line in Python:
    split every line, convert every token with ``float`` into a preallocated array."""
    text = path.read_text(encoding="utf-8-sig")
    lines = [(no, ln) for no, ln in enumerate(text.splitlines(), 1) if ln.strip() and ln[0] != "#"]
    lines = lines[1:]  # the header
    ncol = len(lines[0][1].split(","))
    data = np.empty((len(lines), ncol))
    for row, (no, ln) in enumerate(lines):
        toks = ln.split(",")
        if len(toks) != ncol:
            raise ValueError(f"line {no}: {len(toks)} columns")
        for col, tok in enumerate(toks):
            try:
                data[row, col] = _token(tok, False)
            except ValueError:
                raise ValueError(f"line {no}, column {col + 1}") from None
    return data


def _data(rows: int) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(rows) / FS
    rng = np.random.default_rng(0)
    return t, rng.standard_normal((rows, 3))


def bench_csv(folder: Path, rows: int, repeat: int, previous: bool) -> None:
    import pandas as pd

    t, x = _data(rows)
    for label, fmt in (("%.8f time, %.6e values", ["%.8f"] + ["%.6e"] * 3), ("%.17g", "%.17g")):
        path = folder / "run.csv"
        np.savetxt(
            path,
            np.column_stack([t, x]),
            delimiter=",",
            fmt=fmt,
            header="time [s],a [m/s2],b [m/s2],c [V]",
            comments="",
        )
        ds = read_csv(path, time_column=0)
        ref = np.loadtxt(path, delimiter=",", skiprows=1)
        assert ds.attrs["sample_rate_hz"] == FS and np.array_equal(ds.a.values, ref[:, 1])
        fns: list[Callable[[], object]] = [
            lambda path=path: read_csv(path, time_column=0),
            lambda path=path: np.loadtxt(path, delimiter=",", skiprows=1),
            lambda path=path: pd.read_csv(path, skiprows=1, header=None, dtype=np.float64),
        ]
        if previous:
            fns.append(lambda path=path: _previous_parse(path))
        best = _best_round_robin(fns, repeat)
        size = path.stat().st_size / 1e6
        print(f"CSV  {rows:>9} rows x 4 columns, {label} ({size:.0f} MB)")
        print(f"     read_csv        {best[0]:7.3f} s  ({rows / best[0] / 1e6:.2f} Mrows/s)")
        print(
            f"     numpy.loadtxt   {best[1]:7.3f} s  loadtxt / read_csv = {best[1] / best[0]:.2f}"
        )
        print(f"     pandas.read_csv {best[2]:7.3f} s  pandas / read_csv = {best[2] / best[0]:.2f}")
        if previous:
            print(
                f"     previous parse  {best[3]:7.3f} s  previous / read_csv = "
                f"{best[3] / best[0]:.1f}"
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
    parser.add_argument("--repeat", type=int, default=None, help="rounds (3; --quick: 1)")
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: 2 * 10**4 rows, one round")
    args = parser.parse_args()
    rows = 20_000 if args.quick else args.rows
    repeat = args.repeat or (1 if args.quick else 3)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        bench_csv(folder, rows, repeat, previous=True)
        bench_wav(folder, rows, repeat)
        bench_mat(folder, rows, repeat)


if __name__ == "__main__":
    main()
