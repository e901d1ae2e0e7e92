"""Tests of analysis.fft against numpy.fft (the independent reference)."""

from __future__ import annotations

import sys
import threading

import numpy as np
import pytest

import analysis.fft as gfft


def _rel_err(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.mark.parametrize("shape,axis", [((1000,), -1), ((3, 4, 257), -1), ((64, 5), 0)])
@pytest.mark.parametrize("n", [None, 300, 1024])
def test_rfft_matches_numpy(shape, axis, n):
    rng = np.random.default_rng(1)
    x = rng.standard_normal(shape)
    ref = np.fft.rfft(x, n=n, axis=axis)
    got = gfft.rfft(x, n=n, axis=axis)
    assert got.shape == ref.shape
    assert got.dtype == np.complex128
    assert _rel_err(got, ref) < 1e-12


@pytest.mark.parametrize("n", [None, 511, 512])
def test_irfft_matches_numpy_and_preserves_input(n):
    rng = np.random.default_rng(2)
    X = rng.standard_normal((2, 257)) + 1j * rng.standard_normal((2, 257))
    X_before = X.copy()
    ref = np.fft.irfft(X, n=n)
    got = gfft.irfft(X, n=n)
    assert _rel_err(got, ref) < 1e-12
    np.testing.assert_array_equal(X, X_before)


def test_round_trip_and_repeated_calls_do_not_alias_outputs():
    rng = np.random.default_rng(3)
    x1, x2 = rng.standard_normal(128), rng.standard_normal(128)
    y1 = gfft.rfft(x1)
    y2 = gfft.rfft(x2)  # same cached plan
    assert _rel_err(y1, np.fft.rfft(x1)) < 1e-12
    np.testing.assert_allclose(gfft.irfft(y2, n=128), x2, rtol=0, atol=1e-12)


def test_float32_stays_single_precision():
    x = np.random.default_rng(4).standard_normal(256).astype(np.float32)
    y = gfft.rfft(x)
    assert y.dtype == np.complex64
    assert _rel_err(y, np.fft.rfft(x.astype(float))) < 1e-5


def test_workers_and_threads_give_same_result():
    rng = np.random.default_rng(5)
    x = rng.standard_normal((8, 4096))
    ref = np.fft.rfft(x)
    assert _rel_err(gfft.rfft(x, workers=2), ref) < 1e-12
    previous = gfft.set_workers(2)
    try:
        assert gfft.get_workers() == 2
        assert _rel_err(gfft.rfft(x), ref) < 1e-12
    finally:
        gfft.set_workers(previous)
    results: dict[int, np.ndarray] = {}

    def work(i: int) -> None:
        results[i] = gfft.rfft(x[i])

    threads = [threading.Thread(target=work, args=(i,)) for i in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for i in range(8):
        assert _rel_err(results[i], ref[i]) < 1e-12


def test_scipy_fallback_when_pyfftw_missing(monkeypatch):
    monkeypatch.setitem(sys.modules, "pyfftw", None)
    monkeypatch.setitem(sys.modules, "pyfftw.builders", None)
    assert gfft._load_pyfftw() is None
    monkeypatch.setattr(gfft, "_pyfftw", None)
    assert gfft.backend() == "scipy"
    x = np.random.default_rng(6).standard_normal((3, 100))
    assert _rel_err(gfft.rfft(x, n=128), np.fft.rfft(x, n=128)) < 1e-12
    X = np.fft.rfft(x)
    assert _rel_err(gfft.irfft(X, n=100), x) < 1e-12


def test_backend_reports_pyfftw_when_available():
    pytest.importorskip("pyfftw")
    assert gfft.backend() == "pyfftw"


def test_next_fast_len():
    for n in (1, 7, 97, 1000, 1025, 65537):
        m = gfft.next_fast_len(n)
        assert m >= n
        f = m
        for p in (2, 3, 5, 7, 11):
            while f % p == 0:
                f //= p
        assert f == 1
    with pytest.raises(ValueError, match="n = 0"):
        gfft.next_fast_len(0)


def test_bad_input_raises():
    with pytest.raises(ValueError, match="workers"):
        gfft.rfft(np.ones(8), workers=0)
    with pytest.raises(ValueError, match="complex"):
        gfft.rfft(np.ones(8) + 1j)
    with pytest.raises(ValueError, match="empty"):
        gfft.rfft(np.ones((3, 0)))
    with pytest.raises(ValueError, match="axis"):
        gfft.rfft(np.ones(8), axis=2)
    with pytest.raises(ValueError, match="n = -4"):
        gfft.irfft(np.ones(8, complex), n=-4)
    with pytest.raises(ValueError, match="effort"):
        gfft.set_planner_effort("FAST")
