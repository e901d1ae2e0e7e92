"""analysis.sinc.interpolate equals, bit for bit, its documented order of operations.

The reference below is written with numpy's element-wise operations (each one rounded once, as
the compiled kernel's): the weight of tap ``k`` by Horner's rule in the local variable ``u`` of
the position's piece, the products with the samples (clipped to the ends of the record), four
partial sums over the taps ``k = 4 m + q`` in increasing ``m``, and ``(a0 + a1) + (a2 + a3)``.
Any change of that order (another summation, a fused multiply-add, ``fastmath``) changes the
last bits and fails here.
"""

from __future__ import annotations

import numpy as np
import pytest

from analysis.sinc import HALF_TAPS, interpolate, kernel_table


def _reference(x: np.ndarray, pos: np.ndarray, start: int, n_total: int) -> np.ndarray:
    table = kernel_table()
    pieces, _, n_taps = table.shape
    ib = np.floor(pos)
    frac = pos - ib
    p = np.minimum((frac * pieces).astype(np.int64), pieces - 1)
    u = (2.0 * (frac * pieces - p) - 1.0)[:, None]
    c = table[p]  # (positions, degree + 1, taps)
    w = (((c[:, 4] * u + c[:, 3]) * u + c[:, 2]) * u + c[:, 1]) * u + c[:, 0]
    idx = ib.astype(np.int64)[:, None] - HALF_TAPS + 1 + np.arange(n_taps)[None, :]
    idx = np.clip(idx, 0, n_total - 1) - start
    out = np.empty((x.shape[0], pos.size))
    for ch in range(x.shape[0]):
        prod = w * x[ch][idx]
        acc = [prod[:, q].copy() for q in range(4)]
        for m in range(1, n_taps // 4):
            for q in range(4):
                acc[q] += prod[:, 4 * m + q]
        out[ch] = (acc[0] + acc[1]) + (acc[2] + acc[3])
    return out


@pytest.mark.parametrize("n_ch", [1, 3])
def test_interpolate_is_bit_identical_to_its_order_of_operations(n_ch):
    rng = np.random.default_rng(7)
    n = 2000
    x = rng.standard_normal((n_ch, n)) * np.array([1e-3, 1.0, 1e4][:n_ch])[:, None]
    # inside the record, near and beyond both ends, negative positions, whole samples
    pos = np.concatenate([rng.uniform(-20.0, n + 20.0, 3000), np.arange(-15.0, 15.0, 0.37),
                          n - 15.0 + np.arange(0.0, 30.0, 0.41), np.arange(100.0, 110.0)])
    got = interpolate(x, pos)
    assert got.tobytes() == _reference(x, pos, 0, n).tobytes()
    # a window of the record (samples start .. start + m - 1 of n), and one at its end
    for start, stop, lo, hi in [(600, 1800, 612.0, 1787.0), (n - 400, n, n - 388.0, n + 5.0)]:
        p = rng.uniform(lo, hi, 1500)
        got = interpolate(x[:, start:stop], p, start=start, n_total=n)
        assert got.tobytes() == _reference(x[:, start:stop], p, start, n).tobytes()


def test_one_channel_alone_equals_the_same_channel_among_others():
    rng = np.random.default_rng(8)
    x = rng.standard_normal((3, 1000))
    pos = rng.uniform(-5.0, 1005.0, 2000)
    both = interpolate(x, pos)
    for ch in range(3):
        assert interpolate(x[ch], pos)[0].tobytes() == both[ch].tobytes()
