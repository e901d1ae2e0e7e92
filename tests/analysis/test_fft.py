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


def test_results_are_fresh_arrays_not_plan_buffers():
    # FFTW writes each result into a new array: later calls of the same cached plan must not
    # change an earlier result (issue #4 removed the output copy).
    rng = np.random.default_rng(7)
    x1, x2 = rng.standard_normal((2, 3, 256))
    y1 = gfft.rfft(x1)
    y1_before = y1.copy()
    y2 = gfft.rfft(x2)
    assert y2 is not y1
    np.testing.assert_array_equal(y1, y1_before)
    z1 = gfft.irfft(y1, n=256)
    z1_before = z1.copy()
    gfft.irfft(y2, n=256)
    np.testing.assert_array_equal(z1, z1_before)
    np.testing.assert_allclose(z1, x1, rtol=0, atol=1e-12)


@pytest.mark.parametrize("aligned", [True, False])
def test_out_argument(aligned):
    rng = np.random.default_rng(8)
    x = rng.standard_normal((4, 300))
    if aligned:
        out = gfft.empty_aligned((4, 257), np.complex128)
    else:  # 16 bytes off a 32-byte boundary: FFTW cannot write there, the result is copied in
        base = np.empty(4 * 257 + 1, np.complex128)
        start = 1 if base.ctypes.data % 32 == 0 else 0
        out = base[start : start + 4 * 257].reshape(4, 257)
        assert out.ctypes.data % 32 == 16
    got = gfft.rfft(x, n=512, out=out)
    assert got is out
    np.testing.assert_array_equal(out, gfft.rfft(x, n=512))
    assert _rel_err(out, np.fft.rfft(x, n=512)) < 1e-12
    back = gfft.empty_aligned((4, 512)) if aligned else np.empty((512, 4)).T
    assert gfft.irfft(out, n=512, out=back) is back
    np.testing.assert_allclose(back[:, :300], x, rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="out"):
        gfft.rfft(x, out=np.empty((4, 150), np.complex64))
    with pytest.raises(ValueError, match="out"):
        gfft.irfft(out, out=np.empty((4, 511)))


def test_rfft_plan_batches_rows_like_rfft():
    rng = np.random.default_rng(9)
    x = rng.standard_normal((6, 1000))
    plan = gfft.rfft_plan(6, 1000)
    assert gfft.rfft_plan(6, 1000) is plan  # cached
    plan.input[...] = x
    spec = plan.execute()
    assert spec.shape == (6, 501)
    assert spec.dtype == np.complex128
    np.testing.assert_array_equal(spec, gfft.rfft(x))
    assert _rel_err(spec, np.fft.rfft(x)) < 1e-12
    # every row alone gives the same numbers as the batch (to rounding)
    for i in range(6):
        assert _rel_err(spec[i], gfft.rfft(x[i])) < 1e-13
    with pytest.raises(ValueError, match="rows"):
        gfft.rfft_plan(0, 16)
    with pytest.raises(ValueError, match=r"n = 2\.5"):
        gfft.rfft_plan(1, 2.5)  # type: ignore[arg-type]


def test_rfft_plan_per_thread():
    main = gfft.rfft_plan(2, 64)
    other: list[gfft.RfftPlan] = []
    t = threading.Thread(target=lambda: other.append(gfft.rfft_plan(2, 64)))
    t.start()
    t.join()
    assert other[0] is not main
    assert other[0].input is not main.input


def test_repeated_calls_bit_identical():
    x = np.random.default_rng(10).standard_normal((5, 4096))
    a = gfft.rfft(x)
    b = gfft.rfft(x)
    np.testing.assert_array_equal(a, b)
    plan = gfft.rfft_plan(5, 4096)
    plan.input[...] = x
    first = plan.execute().copy()
    plan.input[...] = x
    np.testing.assert_array_equal(plan.execute(), first)


def test_plan_cache_stays_within_its_byte_budget(monkeypatch):
    monkeypatch.setattr(gfft, "_CACHE_MAX_BYTES", 3 * 16 * 1024 * 12)
    for n in range(1000, 1008):
        gfft.rfft_plan(8, n)
    sizes = [b for _, b in gfft._cache.values()]
    assert sum(sizes) <= gfft._CACHE_MAX_BYTES
    assert len(sizes) >= 1


def test_rfft_plan_and_out_with_scipy_fallback(monkeypatch):
    x = np.random.default_rng(11).standard_normal((3, 200))
    with_fftw = gfft.rfft_plan(3, 200)
    with_fftw.input[...] = x
    ref = with_fftw.execute().copy()
    monkeypatch.setattr(gfft, "_pyfftw", None)
    plan = gfft.rfft_plan(3, 200)
    assert plan is not with_fftw  # the backend is part of the cache key
    plan.input[...] = x
    np.testing.assert_allclose(plan.execute(), ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    out = gfft.empty_aligned((3, 101), np.complex128)
    assert gfft.rfft(x, out=out) is out
    assert _rel_err(out, ref) < 1e-12
    back = np.empty((3, 200))
    assert gfft.irfft(out, n=200, out=back) is back
    np.testing.assert_allclose(back, x, rtol=0, atol=1e-12)


def test_environment_forces_the_scipy_backend():
    # GEARVIB_FFT=scipy: the GPL-free path even with pyFFTW installed (README, licences)
    import os
    import subprocess
    import sys

    code = "import analysis.fft as f, numpy as np; print(f.backend(), f.rfft(np.ones(8))[0].real)"
    env = {**os.environ, "GEARVIB_FFT": "scipy"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert out.stdout.split() == ["scipy", "8.0"], out.stderr


def test_row_ifft_in_place_matches_numpy_for_every_layout():
    plan = gfft.RowIfft(48)
    rng = np.random.default_rng(9)
    for rows in (1, 2, 3, 4, 6, 8, 12, 16, 24, 48):
        view = plan.rows(rows)
        a = rng.standard_normal(view.shape) + 1j * rng.standard_normal(view.shape)
        view[...] = a
        out = plan.execute(rows)
        assert np.shares_memory(out, plan.buffer)
        np.testing.assert_allclose(out, np.fft.ifft(a, axis=-1) * (48 // rows), atol=1e-12)
    with pytest.raises(ValueError, match="rows"):
        plan.rows(5)
    with pytest.raises(ValueError, match="size"):
        gfft.RowIfft(0)
    if gfft.backend() == "pyfftw":
        with pytest.raises(ValueError, match="rows"):
            gfft.RowIfft(8).execute(2)  # no plan made for this layout
