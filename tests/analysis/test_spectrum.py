"""Tests of analysis.spectrum against analytic results and numpy/scipy references."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal
import xarray as xr

from analysis.spectrum import (
    Spectrum,
    find_peaks,
    get_window,
    spectrum,
    to_db,
    window_info,
)

FS = 1000.0
N = 4096


def _sine(f0: float, amp: float = 2.5, n: int = N, fs: float = FS, phase: float = 0.3):
    t = np.arange(n) / fs
    return amp * np.sin(2 * np.pi * f0 * t + phase)


@pytest.mark.parametrize(
    "name,ref",
    [
        ("hann", scipy.signal.windows.hann),
        ("hamming", scipy.signal.windows.hamming),
        ("flattop", scipy.signal.windows.flattop),
        ("blackmanharris", scipy.signal.windows.blackmanharris),
        ("rectangular", scipy.signal.windows.boxcar),
        ("boxcar", scipy.signal.windows.boxcar),
    ],
)
def test_windows_match_scipy_periodic(name, ref):
    np.testing.assert_allclose(get_window(name, 1000), ref(1000, sym=False), atol=1e-12)


def test_kaiser_matches_scipy_and_window_figures():
    np.testing.assert_allclose(
        get_window(("kaiser", 7.0), 999),
        scipy.signal.windows.kaiser(999, 7.0, sym=False),
        atol=1e-12,
    )
    # Heinzel et al. (2002), appendix C/D: ENBW in bins
    assert window_info("hann", 4096).enbw_bins == pytest.approx(1.5, rel=1e-9)
    assert window_info("hann", 4096).coherent_gain == pytest.approx(0.5, rel=1e-9)
    assert window_info("rectangular", 100).enbw_bins == pytest.approx(1.0)
    assert window_info("flattop", 4096).enbw_bins == pytest.approx(3.7702, abs=1e-3)
    assert window_info("hamming", 4096).enbw_bins == pytest.approx(1.3628, abs=1e-3)
    assert window_info("blackmanharris", 4096).enbw_bins == pytest.approx(2.0044, abs=1e-3)


@pytest.mark.parametrize("window", ["hann", "flattop"])
@pytest.mark.parametrize("offset", [0.0, 0.25, 0.5, 0.37])
@pytest.mark.parametrize("scaling", ["peak", "rms", "power"])
def test_sine_amplitude_on_and_off_bin(window, offset, scaling):
    amp = 2.5
    f0 = (300 + offset) * FS / N
    s = spectrum(_sine(f0, amp), FS, window=window, scaling=scaling)
    expected = {"peak": amp, "rms": amp / np.sqrt(2), "power": amp**2 / 2}[scaling]
    p = find_peaks(s, max_peaks=1)
    assert len(p) == 1
    assert p.amplitude[0] == pytest.approx(expected, rel=1e-3)
    assert p.frequency[0] == pytest.approx(f0, abs=1e-3 * s.resolution_hz)
    if offset == 0.0:  # on bin, the raw bin value is already exact
        assert s.values[300] == pytest.approx(expected, rel=1e-9)


def test_flattop_scalloping_below_0p01_db_and_hann_needs_correction():
    f0 = 300.5 * FS / N
    ft = spectrum(_sine(f0, 1.0), FS, window="flattop", scaling="peak")
    hn = spectrum(_sine(f0, 1.0), FS, window="hann", scaling="peak")
    assert abs(to_db(ft.values.max(), "peak")) < 0.01
    assert to_db(hn.values.max(), "peak") == pytest.approx(-1.42, abs=0.01)  # Hann scalloping


def test_hann_interpolation_agrees_with_grandke_formula():
    f0 = 211.3 * FS / N
    s = spectrum(_sine(f0), FS, window="hann", scaling="peak")
    k = int(np.argmax(s.values))
    alpha = s.values[k + 1] / s.values[k]
    delta = (2 * alpha - 1) / (alpha + 1)  # Grandke (1983), valid for the Hann window
    p = s.peaks(max_peaks=1)
    assert p.frequency[0] == pytest.approx((k + delta) * s.resolution_hz, abs=1e-6)


def test_zero_padding_keeps_amplitude_and_reports_bin_spacing():
    f0 = 123.71
    s = spectrum(_sine(f0, 1.5, n=1000), FS, window="hann", nfft=4000, scaling="peak")
    assert s.resolution_hz == pytest.approx(FS / 4000)
    assert s.enbw_hz == pytest.approx(1.5 * FS / 1000)
    p = s.peaks(max_peaks=1)
    assert p.amplitude[0] == pytest.approx(1.5, rel=1e-3)
    assert p.frequency[0] == pytest.approx(f0, abs=1e-3)


def test_dc_reads_constant_and_power_matches_numpy_reference():
    rng = np.random.default_rng(0)
    x = 0.7 + rng.standard_normal(512)
    s = spectrum(x, FS, window="rectangular", scaling="power")
    X = np.fft.rfft(x)
    ref = np.abs(X) ** 2 / 512**2
    ref[1:-1] *= 2
    np.testing.assert_allclose(s.values, ref, rtol=1e-12)
    assert spectrum(np.full(64, 0.7), FS, scaling="peak").values[0] == pytest.approx(0.7)
    assert spectrum(np.full(64, 0.7), FS, scaling="rms").values[0] == pytest.approx(0.7)


def test_welch_psd_matches_scipy_welch():
    rng = np.random.default_rng(1)
    x = rng.standard_normal(20000)
    s = spectrum(x, FS, window="hann", scaling="psd", segment_length=1024, overlap=0.5)
    f, p = scipy.signal.welch(
        x,
        FS,
        window=scipy.signal.windows.hann(1024, sym=False),
        nperseg=1024,
        noverlap=512,
        detrend=False,
        scaling="density",
    )
    np.testing.assert_allclose(s.frequency, f)
    np.testing.assert_allclose(s.values, p, rtol=1e-10)
    assert s.n_averages == (20000 - 1024) // 512 + 1


def test_white_noise_psd_level():
    rng = np.random.default_rng(2)
    sigma, fs = 0.8, 2048.0
    x = sigma * rng.standard_normal(400 * 512)
    s = spectrum(x, fs, window="hann", scaling="psd", segment_length=512, overlap=0.5)
    inner = s.values[5:-5]
    # mean over ~250 bins of a ~800-average estimate: relative std ~ 0.1 / sqrt(250) ~ 0.4 %
    assert inner.mean() == pytest.approx(sigma**2 / (fs / 2), rel=0.02)
    assert s.units == "Hz-1"


def test_parseval_power_and_psd():
    rng = np.random.default_rng(3)
    x = rng.standard_normal(8192) * 1.3
    ms = float(np.mean(x**2))
    psd = spectrum(x, FS, window="rectangular", scaling="psd")
    assert psd.values.sum() * psd.resolution_hz == pytest.approx(ms, rel=1e-10)
    pw = spectrum(x, FS, window="rectangular", scaling="power")
    assert pw.values.sum() == pytest.approx(ms, rel=1e-10)
    # with a window, the power summed over bins / ENBW (in bins) estimates the mean square
    y = spectrum(x, FS, window="hann", scaling="power", segment_length=512)
    enbw_bins = y.enbw_hz / y.resolution_hz
    assert y.values.sum() / enbw_bins == pytest.approx(ms, rel=0.03)


def test_nd_input_and_max_average():
    x = np.stack([_sine(100.0, 1.0), _sine(100.0, 3.0)])[None]  # shape (1, 2, N)
    s = spectrum(x, FS, window="flattop", scaling="peak", segment_length=1024)
    assert s.values.shape == (1, 2, 513)
    np.testing.assert_allclose(s.values.max(axis=-1)[0], [1.0, 3.0], rtol=1e-3)
    burst = np.zeros(N)
    burst[:1024] = _sine(100.0, 2.0, n=1024)
    mean = spectrum(burst, FS, window="flattop", segment_length=1024, overlap=0.0)
    peak = spectrum(burst, FS, window="flattop", segment_length=1024, overlap=0.0, average="max")
    assert peak.values.max() == pytest.approx(2.0, rel=1e-3)
    assert mean.values.max() == pytest.approx(2.0 / 2, rel=1e-3)  # sqrt(mean power over 4)
    with pytest.raises(ValueError, match="channel"):
        find_peaks(s)
    assert find_peaks(s, channel=(0, 1), max_peaks=1).amplitude[0] == pytest.approx(3.0, rel=1e-3)


def test_dataarray_input_uses_time_coordinate_and_units():
    t = np.arange(N) / FS
    da = xr.DataArray(
        np.stack([_sine(50.0), _sine(70.0)]),
        dims=("channel", "time"),
        coords={"time": t, "channel": ["a", "b"]},
        attrs={"units": "m s-2"},
        name="acc",
    )
    s = spectrum(da.transpose("time", "channel"), scaling="rms")
    assert s.fs == pytest.approx(FS)
    assert s.dims == ("channel",)
    assert s.units == "m s-2"
    ds = s.to_dataset()
    assert list(ds["channel"].values) == ["a", "b"]
    for v in [*ds.data_vars, *ds.coords]:
        assert "long_name" in ds[v].attrs
    assert ds["spectrum"].attrs["units"] == "m s-2"
    assert ds["frequency"].attrs["units"] == "Hz"
    assert ds.attrs["resolution_hz"] == pytest.approx(FS / N)
    assert spectrum(da, scaling="power").units == "(m s-2)^2"
    with pytest.raises(ValueError, match="sample-rate mismatch"):
        spectrum(da, 999.0)


def test_peaks_options_and_dataset():
    x = _sine(100.0, 1.0) + _sine(103.0, 0.5) + _sine(300.0, 0.01)
    s = spectrum(x, FS, window="hann", scaling="peak")
    p_all = s.peaks(prominence_db=20)
    assert np.any(np.abs(p_all.frequency - 300.0) < 0.1)
    p_thr = s.peaks(threshold=0.1, prominence_db=6)
    np.testing.assert_allclose(p_thr.frequency, [100.0, 103.0], atol=1e-3)
    np.testing.assert_allclose(p_thr.amplitude, [1.0, 0.5], rtol=5e-3)
    p_dist = s.peaks(threshold=0.1, min_distance_hz=5.0)
    np.testing.assert_allclose(p_dist.frequency, [100.0], atol=1e-3)
    assert s.peaks(prominence_db=20, max_peaks=2).frequency.size == 2
    ds = p_thr.to_dataset()
    assert ds["frequency"].attrs["units"] == "Hz"
    assert p_thr.labels("{frequency:.0f} Hz") == ["100 Hz", "103 Hz"]


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"window": "gauss"}, "window"),
        ({"window": ("hann", 3.0)}, "kaiser"),
        ({"scaling": "amplitude"}, "scaling"),
        ({"average": "median"}, "average"),
        ({"overlap": 1.0}, "overlap"),
        ({"segment_length": 10**6}, "segment_length"),
        ({"segment_length": 256, "nfft": 128}, "nfft"),
    ],
)
def test_bad_parameters_raise(kwargs, match):
    with pytest.raises(ValueError, match=match):
        spectrum(np.ones(1000), FS, **kwargs)


def test_bad_signals_raise():
    x = np.ones(100)
    x[17] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        spectrum(x, FS)
    with pytest.raises(ValueError, match="empty"):
        spectrum(np.ones((2, 0)), FS)
    with pytest.raises(ValueError, match="fs"):
        spectrum(np.ones(100), -1.0)
    with pytest.raises(ValueError, match="fs is required"):
        spectrum(np.ones(100))
    with pytest.raises(ValueError, match="real"):
        spectrum(np.ones(100) + 1j, FS)
    bad_t = xr.DataArray(np.ones(5), dims="time", coords={"time": [0, 1, 3, 2, 4.0]})
    with pytest.raises(ValueError, match="strictly increasing"):
        spectrum(bad_t)
    with pytest.raises(ValueError, match="Spectrum"):
        find_peaks(np.ones(10))  # type: ignore[arg-type]
    assert isinstance(spectrum(np.ones(10), FS), Spectrum)
