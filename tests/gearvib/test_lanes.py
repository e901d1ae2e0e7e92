"""Eight-lane vectors in numba (:mod:`gearvib.lanes`): each lane is the scalar IEEE operation,
vectorised, never contracted into a fused multiply-add."""

from __future__ import annotations

import re

import numpy as np
from numba import njit

from gearvib.lanes import (
    WIDTH,
    lanes_abs,
    lanes_any,
    lanes_floor,
    lanes_load,
    lanes_madd_nz,
    lanes_splat,
    lanes_store,
    lanes_table_pair,
    where_gt,
    where_le,
    where_lt,
)


@njit  # no cache: the assembly is inspected
def _sum_of_products(vals, y, out):
    acc = lanes_load(vals, 0)
    for p in range(1, vals.shape[0]):
        acc = lanes_madd_nz(acc, lanes_load(vals, WIDTH * p), lanes_load(y, WIDTH * p))
    lanes_store(out, 0, acc * 3.0 + lanes_splat(0.5))


def test_sums_are_the_scalar_sums_lane_by_lane_and_not_contracted():
    rng = np.random.default_rng(1)
    vals = rng.standard_normal((13, WIDTH))
    vals[4, 3] = 0.0  # a stored zero: skipped
    vals[1:, 2] = 0.0  # lane 2 has no terms: it keeps its start
    y = rng.standard_normal((13, WIDTH))
    out = np.empty(WIDTH)
    _sum_of_products(vals, y, out)
    for b in range(WIDTH):
        acc = vals[0, b]
        for p in range(1, 13):
            if vals[p, b] != 0.0:
                acc = acc + vals[p, b] * y[p, b]
        assert np.float64(acc * 3.0 + 0.5).tobytes() == out[b].tobytes()
    asm = _sum_of_products.inspect_asm(_sum_of_products.signatures[0])
    assert not re.search(r"\bv?fn?madd|\bv?fn?msub", asm), "a fused multiply-add appeared"
    assert re.search(r"\bv?mulpd\b", asm), "the products are not packed"


@njit
def _selects(a, b, out):
    x = lanes_load(a, 0)
    z = lanes_load(b, 0)
    lanes_store(out, 0, where_gt(x, z, x, z))
    lanes_store(out, WIDTH, where_lt(x, z, x, z))
    lanes_store(out, 2 * WIDTH, where_le(x, z, lanes_floor(x), lanes_abs(z)))
    return lanes_any(x - x)


def test_selects_follow_pythons_comparisons_with_nan():
    a = np.array([1.0, -2.0, np.nan, 0.5, -0.0, 3.0, np.inf, 2.5])
    b = np.array([0.0, -1.0, 1.0, np.nan, 0.0, 3.0, 1.0, -2.5])
    out = np.empty(3 * WIDTH)
    any_nan = _selects(a, b, out)
    for k in range(WIDTH):
        x, z = a[k], b[k]
        for got, want in ((out[k], x if x > z else z), (out[WIDTH + k], x if x < z else z),
                          (out[2 * WIDTH + k], np.floor(x) if x <= z else abs(z))):
            assert np.float64(got).tobytes() == np.float64(want).tobytes()
    assert any_nan  # nan - nan and inf - inf are not zero


@njit
def _tables(tables, n_table, width, s, out):
    kl, kr = lanes_table_pair(tables, 0, n_table * width, n_table, width, lanes_load(s, 0))
    lanes_store(out, 0, kl)
    lanes_store(out, WIDTH, kr)


def test_table_lookup_matches_the_scalar_interpolation():
    """Lanes in one cell (two vector loads), in different cells (lane by lane), per-lane and
    shared tables, positions across the periodic wrap."""
    rng = np.random.default_rng(2)
    n_table = 16
    per_lane = rng.uniform(1.0, 2.0, (2, n_table, WIDTH))
    shared = rng.uniform(1.0, 2.0, (2, n_table, 1))
    for s in (np.full(WIDTH, 3.0 + 5.3 / n_table) + 1e-9 * np.arange(WIDTH),
              rng.uniform(-3.0, 3.0, WIDTH), np.full(WIDTH, -1e-17)):
        for tables in (per_lane, shared):
            width = tables.shape[-1]
            out = np.empty(2 * WIDTH)
            _tables(np.ascontiguousarray(tables), n_table, width, s, out)
            for b in range(WIDTH):
                frac = s[b] - np.floor(s[b])
                u = frac * n_table
                i0 = int(u)
                w = u - i0
                if i0 >= n_table:
                    i0, w = 0, 0.0
                i1 = (i0 + 1) % n_table
                lane = b if width == WIDTH else 0
                for k in range(2):
                    want = (1.0 - w) * tables[k, i0, lane] + w * tables[k, i1, lane]
                    assert np.float64(want).tobytes() == out[k * WIDTH + b].tobytes()
