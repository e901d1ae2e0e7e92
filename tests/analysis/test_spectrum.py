"""Tests of analysis.spectrum against analytic results and numpy/scipy references."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import scipy.signal
import xarray as xr

import analysis.fft as gfft
import analysis.spectrum as spmod
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
    s = spectrum(_sine(f0, amp), FS, window=window, amplitude=scaling)
    expected = {"peak": amp, "rms": amp / np.sqrt(2), "power": amp**2 / 2}[scaling]
    p = find_peaks(s, max_peaks=1)
    assert len(p) == 1
    assert p.amplitude[0] == pytest.approx(expected, rel=1e-3)
    assert p.frequency[0] == pytest.approx(f0, abs=1e-3 * s.bin_spacing_hz)
    if offset == 0.0:  # on bin, the raw bin value is already exact
        assert s.values[300] == pytest.approx(expected, rel=1e-9)


def test_flattop_scalloping_below_0p01_db_and_hann_needs_correction():
    f0 = 300.5 * FS / N
    ft = spectrum(_sine(f0, 1.0), FS, window="flattop", amplitude="peak")
    hn = spectrum(_sine(f0, 1.0), FS, window="hann", amplitude="peak")
    assert abs(to_db(ft.values.max(), "peak")) < 0.01
    assert to_db(hn.values.max(), "peak") == pytest.approx(-1.42, abs=0.01)  # Hann scalloping


def test_hann_interpolation_agrees_with_grandke_formula():
    f0 = 211.3 * FS / N
    s = spectrum(_sine(f0), FS, window="hann", amplitude="peak")
    k = int(np.argmax(s.values))
    alpha = s.values[k + 1] / s.values[k]
    delta = (2 * alpha - 1) / (alpha + 1)  # Grandke (1983), valid for the Hann window
    p = s.peaks(max_peaks=1)
    assert p.frequency[0] == pytest.approx((k + delta) * s.bin_spacing_hz, abs=1e-6)


def test_zero_padding_keeps_amplitude_and_reports_bin_spacing():
    f0 = 123.71
    s = spectrum(_sine(f0, 1.5, n=1000), FS, window="hann", nfft=4000, amplitude="peak")
    assert s.bin_spacing_hz == pytest.approx(FS / 4000)
    assert s.resolution_hz == s.enbw_hz == pytest.approx(1.5 * FS / 1000)  # RBW = ENBW
    assert s.enbw_hz == pytest.approx(1.5 * FS / 1000)
    p = s.peaks(max_peaks=1)
    assert p.amplitude[0] == pytest.approx(1.5, rel=1e-3)
    assert p.frequency[0] == pytest.approx(f0, abs=1e-3)


def test_dc_reads_constant_and_power_matches_numpy_reference():
    rng = np.random.default_rng(0)
    x = 0.7 + rng.standard_normal(512)
    s = spectrum(x, FS, axis=-1, window="rectangular", amplitude="power")
    X = np.fft.rfft(x)
    ref = np.abs(X) ** 2 / 512**2
    ref[1:-1] *= 2
    np.testing.assert_allclose(s.values, ref, rtol=1e-12)
    assert spectrum(np.full(64, 0.7), FS, amplitude="peak").values[0] == pytest.approx(0.7)
    assert spectrum(np.full(64, 0.7), FS, amplitude="rms").values[0] == pytest.approx(0.7)


def test_welch_psd_matches_scipy_welch():
    rng = np.random.default_rng(1)
    x = rng.standard_normal(20000)
    s = spectrum(x, FS, window="hann", amplitude="density", segment_length=1024, overlap=0.5)
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
    s = spectrum(x, fs, window="hann", amplitude="density", segment_length=512, overlap=0.5)
    inner = s.values[5:-5]
    # mean over ~250 bins of a ~800-average estimate: relative std ~ 0.1 / sqrt(250) ~ 0.4 %
    assert inner.mean() == pytest.approx(sigma**2 / (fs / 2), rel=0.02)
    assert s.units == "Hz-1"


def test_parseval_power_and_psd():
    rng = np.random.default_rng(3)
    x = rng.standard_normal(8192) * 1.3
    ms = float(np.mean(x**2))
    psd = spectrum(x, FS, axis=-1, window="rectangular", amplitude="density")
    assert psd.values.sum() * psd.bin_spacing_hz == pytest.approx(ms, rel=1e-10)
    pw = spectrum(x, FS, axis=-1, window="rectangular", amplitude="power")
    assert pw.values.sum() == pytest.approx(ms, rel=1e-10)
    # with a window, the power summed over bins / ENBW (in bins) estimates the mean square
    y = spectrum(x, FS, axis=-1, window="hann", amplitude="power", segment_length=512)
    enbw_bins = y.enbw_hz / y.bin_spacing_hz
    assert y.values.sum() / enbw_bins == pytest.approx(ms, rel=0.03)


def test_nd_input_and_max_average():
    x = np.stack([_sine(100.0, 1.0), _sine(100.0, 3.0)])[None]  # shape (1, 2, N)
    s = spectrum(x, FS, axis=-1, window="flattop", amplitude="peak", segment_length=1024)
    assert s.values.shape == (1, 2, 513)
    np.testing.assert_allclose(s.values.max(axis=-1)[0], [1.0, 3.0], rtol=1e-3)
    burst = np.zeros(N)
    burst[:1024] = _sine(100.0, 2.0, n=1024)
    kw = {"window": "flattop", "segment_length": 1024, "overlap": 0.0, "amplitude": "peak"}
    mean = spectrum(burst, FS, **kw)
    peak = spectrum(burst, FS, average="max", **kw)
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
    s = spectrum(da.transpose("time", "channel"), amplitude="rms")
    assert s.fs == pytest.approx(FS)
    assert s.dims == ("channel",)
    assert s.units == "m s-2"
    ds = s.to_dataset()
    assert list(ds["channel"].values) == ["a", "b"]
    for v in [*ds.data_vars, *ds.coords]:
        assert "long_name" in ds[v].attrs
    assert ds["spectrum"].attrs["units"] == "m s-2"
    assert ds["frequency"].attrs["units"] == "Hz"
    assert ds.attrs["bin_spacing_hz"] == pytest.approx(FS / N)
    assert spectrum(da, amplitude="power").units == "(m s-2)^2"
    with pytest.raises(ValueError, match="sample-rate mismatch"):
        spectrum(da, 999.0)


def test_peaks_options_and_dataset():
    x = _sine(100.0, 1.0) + _sine(103.0, 0.5) + _sine(300.0, 0.01)
    s = spectrum(x, FS, axis=-1, window="hann", amplitude="peak")
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
        ({"amplitude": "amplitude"}, "amplitude"),
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
    with pytest.raises(ValueError, match=r"or time \(s\) is required"):
        spectrum(np.ones(100))
    with pytest.raises(ValueError, match="real"):
        spectrum(np.ones(100) + 1j, FS)
    bad_t = xr.DataArray(np.ones(5), dims="time", coords={"time": [0, 1, 3, 2, 4.0]})
    with pytest.raises(ValueError, match="strictly increasing"):
        spectrum(bad_t)
    with pytest.raises(ValueError, match="Spectrum"):
        find_peaks(np.ones(10))  # type: ignore[arg-type]
    assert isinstance(spectrum(np.ones(10), FS), Spectrum)


# ---------------------------------------------------- batched segment loop (issue #4)


def _welch_one_by_one(x, seg, step, nfft, window, average):
    """Reference: every frame windowed and transformed alone with numpy.fft."""
    w = get_window(window, seg)
    starts = range(0, x.shape[-1] - seg + 1, step)
    p = np.stack([np.abs(np.fft.rfft(x[..., s : s + seg] * w, n=nfft)) ** 2 for s in starts])
    return p.mean(axis=0) if average == "mean" else p.max(axis=0)


@pytest.mark.parametrize("average", ["mean", "max"])
@pytest.mark.parametrize("block", [1, 3000, 1 << 17])
def test_batched_blocks_match_frame_by_frame(monkeypatch, average, block):
    # blocks of 1 frame, of 3 frames (10 frames per channel: blocks span two channels and the
    # last block is shorter) and of all 60 frames: same numbers as frame by frame
    monkeypatch.setattr(spmod, "_BLOCK_ELEMENTS", block)
    rng = np.random.default_rng(12)
    x = rng.standard_normal((2, 3, 7000))
    s = spectrum(
        x,
        FS,
        window="hann",
        amplitude="power",
        segment_length=900,
        nfft=1000,
        overlap=0.3,
        average=average,
        axis=-1,
    )
    w = get_window("hann", 900)
    ref = _welch_one_by_one(x, 900, 630, 1000, "hann", average) / w.sum() ** 2
    ref[..., 1:-1] *= 2
    assert s.n_averages == (7000 - 900) // 630 + 1
    np.testing.assert_allclose(s.values, ref, rtol=1e-12, atol=0)


def test_block_size_does_not_change_results_beyond_rounding(monkeypatch):
    rng = np.random.default_rng(13)
    x = rng.standard_normal((3, 20000))
    default = spectrum(x, FS, axis=-1, segment_length=1024).values
    for block in (1, 1 << 12, 1 << 22):
        monkeypatch.setattr(spmod, "_BLOCK_ELEMENTS", block)
        again = spectrum(x, FS, axis=-1, segment_length=1024).values
        np.testing.assert_allclose(again, default, rtol=1e-13)
    # each channel alone equals its row of the multi-channel result
    for i in range(3):
        np.testing.assert_allclose(
            spectrum(x[i], FS, segment_length=1024).values, default[i], rtol=1e-13
        )


def test_zero_padding_survives_shared_plan_buffers():
    # A cached plan's input buffer is shared: a full-length call must not leave data in the
    # columns that a later zero-padded call relies on being zero.
    rng = np.random.default_rng(14)
    x = rng.standard_normal(40 * 512)
    spectrum(x, FS, axis=-1, segment_length=1024, overlap=0.5)  # fills every column of the plan
    s = spectrum(x, FS, axis=-1, window="hann", amplitude="power", segment_length=1000, nfft=1024)
    ref = (
        _welch_one_by_one(x, 1000, 500, 1024, "hann", "mean") / get_window("hann", 1000).sum() ** 2
    )
    ref[1:-1] *= 2
    np.testing.assert_allclose(s.values, ref, rtol=1e-12)


def test_integer_and_float32_input_are_windowed_in_float64():
    rng = np.random.default_rng(15)
    xi = rng.integers(-1000, 1000, 10000)
    np.testing.assert_array_equal(
        spectrum(xi, FS, segment_length=512).values,
        spectrum(xi.astype(float), FS, segment_length=512).values,
    )
    xf = rng.standard_normal(10000).astype(np.float32)
    np.testing.assert_array_equal(
        spectrum(xf, FS, segment_length=512).values,
        spectrum(xf.astype(float), FS, segment_length=512).values,
    )


def test_scipy_fallback_gives_the_same_spectrum(monkeypatch):
    rng = np.random.default_rng(16)
    x = rng.standard_normal((2, 30000))
    kwargs = {"segment_length": 2048, "nfft": 2500, "amplitude": "density"}
    ours = spectrum(x, FS, axis=-1, **kwargs).values
    peak_hold = spectrum(x, FS, axis=-1, average="max", **kwargs).values
    monkeypatch.setattr(gfft, "_pyfftw", None)
    assert gfft.backend() == "scipy"
    np.testing.assert_allclose(spectrum(x, FS, axis=-1, **kwargs).values, ours, rtol=1e-12)
    np.testing.assert_allclose(
        spectrum(x, FS, axis=-1, average="max", **kwargs).values, peak_hold, rtol=1e-12
    )


def test_workers_do_not_change_results():
    x = np.random.default_rng(17).standard_normal((2, 50000))
    one = spectrum(x, FS, axis=-1, segment_length=4096, workers=1).values
    np.testing.assert_allclose(
        spectrum(x, FS, axis=-1, segment_length=4096, workers=2).values, one, rtol=1e-12
    )
    with pytest.raises(ValueError, match="workers"):
        spectrum(x, FS, axis=-1, segment_length=4096, workers=0)


_DETERMINISM_SCRIPT = """
import hashlib, numpy as np
from analysis.spectrum import spectrum
x = np.random.default_rng(18).standard_normal((2, 150000))
h = hashlib.sha256()
for seg, nfft, avg in ((256, None, "mean"), (4096, None, "max"), (16384, 20000, "mean"),
                       (65536, None, "mean"), (None, None, "mean")):
    s = spectrum(x, 51200.0, axis=-1, segment_length=seg, nfft=nfft, average=avg)
    h.update(s.values.tobytes())
print(h.hexdigest())
"""


def test_same_input_same_output_bit_for_bit_within_and_across_processes(capsys):
    # FFTW_ESTIMATE plans, a block partition fixed by the shapes and a fixed summation order:
    # two calls, and a fresh process, give identical bytes
    exec(_DETERMINISM_SCRIPT, {})
    exec(_DETERMINISM_SCRIPT, {})
    here = capsys.readouterr().out.split()
    assert len(here) == 2
    assert here[0] == here[1]
    out = subprocess.run(
        [sys.executable, "-c", _DETERMINISM_SCRIPT], capture_output=True, text=True, check=True
    )
    assert out.stdout.strip() == here[0]
