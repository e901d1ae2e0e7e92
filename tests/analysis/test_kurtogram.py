"""Spectral kurtosis and the fast kurtogram (analysis.kurtogram): the 1/3-binary tree, the
band kurtosis against an independent whole-record computation, K ~ 0 with the predicted
spread for stationary Gaussian noise, K = -1 for a sine, the resonance band of an impulse
train found, no transient from the record's ends, bad input, results."""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
import xarray as xr
from matplotlib.figure import Figure

from analysis.bands import Band
from analysis.kurtogram import (
    fast_kurtogram,
    gaussian_threshold,
    kurtogram_levels,
    spectral_kurtosis,
)
from tests.analysis.test_envelope import impulse_train


def test_levels_of_the_one_third_binary_tree():
    rows = kurtogram_levels(3)
    assert [nb for _, nb in rows] == [1, 2, 3, 4, 6, 8]
    np.testing.assert_allclose([lv for lv, _ in rows], [0, 1, math.log2(3), 2,
                                                        1 + math.log2(3), 3])  # fmt: skip


def _direct_band_kurtosis(x, fs, band, decimation):
    """K of one band from the whole record at once: mean removed, zero-padded far beyond the
    band filter's impulse response, analytic band signal from the full DFT, decimated, the
    record's ends left out (the guards of analysis.bands)."""
    x = x - x.mean()
    pad = 1 << 16
    y = np.concatenate([np.zeros(pad), x, np.zeros(pad)])
    f = np.fft.fftfreq(y.size, 1 / fs)
    f[y.size // 2] = fs / 2  # the Nyquist line counts as positive
    z = np.fft.ifft(2 * np.fft.fft(y) * band.gain(f, fs))[pad : pad + x.size : decimation]
    guard = math.ceil(10.0 * fs / band.transition / decimation)
    p = np.abs(z[guard:-guard]) ** 2
    return p.size * np.sum(p * p) / np.sum(p) ** 2 - 2


def test_band_kurtosis_matches_a_direct_computation():
    """The block-wise filter bank (2^20 samples: several blocks) against the whole-record
    computation above, for bands of several levels."""
    fs = 20000.0
    x = impulse_train(fs, (1 << 20) / fs, 87.3, 3700.0, snr_db=-5.0, seed=7)
    kg = fast_kurtogram(x, fs, max_level=6)
    for row, index in [(0, 0), (3, 1), (3, 3), (6, 3), (6, 0), (9, 17), (11, 40), (11, 63)]:
        nb = int(kg.n_bands[row])
        band = kg.band_of(row, index)
        ref = _direct_band_kurtosis(x, fs, band, nb)
        assert kg.kurtosis[row, index] == pytest.approx(ref, rel=1e-6, abs=1e-8), (row, index)


def test_gaussian_noise_has_zero_kurtosis_with_the_predicted_spread():
    """1e6 samples, levels 0-8: the spread of K over the inner bands of a level is within
    30 % of 2 / sqrt(M_eff) (measured 0.75-1.04 on the levels of 16 bands or more; the
    spread of a 16-band sample is itself uncertain by 18 %), and the mean within 3 standard
    errors of the bias -2 / (M_eff + 1)."""
    x = np.random.default_rng(11).standard_normal(1_000_000)
    kg = fast_kurtogram(x, 51200.0)
    for r in range(kg.levels.size):
        nb = int(kg.n_bands[r])
        k = kg.kurtosis[r, 1 : nb - 1] if nb > 4 else kg.kurtosis[r, :nb]
        sigma = 2 / math.sqrt(kg.effective_samples[r])
        bias = -2 / (kg.effective_samples[r] + 1)
        assert abs(k.mean() - bias) < 3 * sigma / math.sqrt(k.size) + 1e-3
        if nb >= 16:
            assert 0.7 < k.std() / sigma < 1.3, (kg.levels[r], k.std(), sigma)
    # the per-band false-alarm rate of the 1 % Gaussian threshold over the deepest levels
    exceed = [np.mean(kg.kurtosis[r, : kg.n_bands[r]] > kg.threshold(0.01)[r])
              for r in range(kg.levels.size) if kg.n_bands[r] >= 64]  # fmt: skip
    assert np.mean(exceed) < 0.03


def test_stft_spectral_kurtosis_of_gaussian_noise():
    """K(f) ~ 0 with spread 2 / sqrt(M_eff) (M_eff: frames corrected for their overlap);
    DC and Nyquist hold real coefficients: K ~ 1 there."""
    x = np.random.default_rng(3).standard_normal(400_000)
    sk = spectral_kurtosis(x, 10000.0, segment_length=256)
    inner = sk.kurtosis[5:-5]
    sigma = 2 / math.sqrt(sk.effective_frames)
    assert sk.n_frames == (400_000 - 256) // 64 + 1
    assert sk.effective_frames < sk.n_frames
    assert abs(inner.mean()) < 4 * sigma / math.sqrt(inner.size)
    assert 0.85 < inner.std() / sigma < 1.15, (inner.std(), sigma)
    assert sk.kurtosis[0] == pytest.approx(1.0, abs=0.2)
    assert sk.kurtosis[-1] == pytest.approx(1.0, abs=0.2)
    assert np.mean(inner > sk.threshold(0.01)) < 0.025


def test_spectral_kurtosis_of_a_sine_is_minus_one_and_of_impulses_large():
    fs = 10000.0
    t = np.arange(200_000) / fs
    x = np.sin(2 * np.pi * 1250.0 * t) + 1e-3 * np.random.default_rng(0).standard_normal(t.size)
    sk = spectral_kurtosis(x, fs, segment_length=128)
    assert sk.kurtosis[16] == pytest.approx(-1.0, abs=1e-3)  # 1250 Hz = bin 16
    y = impulse_train(fs, 20.0, 50.0, 3000.0, snr_db=-5.0, seed=2)
    sk = spectral_kurtosis(y, fs, segment_length=128)
    inner = sk.kurtosis[2:-2]  # DC and Nyquist: real coefficients, K ~ 1 for any noise
    assert abs(sk.frequency[2 + np.argmax(inner)] - 3000.0) < 300.0
    assert inner.max() > 5 * sk.threshold(0.01)


@pytest.mark.parametrize(("seed", "snr"), [(0, -5.0), (1, -10.0), (2, -10.0), (3, 0.0)])
def test_kurtogram_band_contains_the_resonance(seed, snr):
    fs, fn = 20000.0, 3700.0
    x = impulse_train(fs, 4.0, 87.3, fn, snr_db=snr, seed=seed)
    kg = fast_kurtogram(x, fs)
    assert kg.band.low < fn < kg.band.high
    assert kg.kurtosis_max > 5 * kg.threshold(0.01)[kg.best[0]]
    narrow = fast_kurtogram(x, fs, min_bandwidth=2000.0)
    assert narrow.band.width >= 2000.0 and narrow.band.low < fn < narrow.band.high


def test_record_ends_do_not_make_an_empty_band_impulsive():
    """Noise low-passed far below fs/2 (the top bands 80 dB down, as above an anti-alias
    filter): the filter's responses to the start and end of the record are left out, so the
    empty bands read K ~ 0, not hundreds."""
    fs = 12000.0
    rng = np.random.default_rng(5)
    x = rng.standard_normal(120_000) + 3.0  # a mean, and a step at each end
    f = np.fft.rfftfreq(x.size, 1 / fs)
    x = np.fft.irfft(np.fft.rfft(x) * np.where(f < 4000.0, 1.0, 1e-4), n=x.size)
    kg = fast_kurtogram(x, fs)
    assert kg.band.high <= 4200.0
    assert np.nanmax(kg.kurtosis) < 1.0


def test_kurtogram_result_dataset_and_figure():
    fs = 20000.0
    x = impulse_train(fs, 2.0, 87.3, 3700.0, seed=4)
    kg = fast_kurtogram(x, fs, max_level=5, name="housing")
    ds = kg.to_dataset()
    for name, var in ds.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
    assert ds["kurtosis"].shape == (kg.levels.size, 3 * 2**5)
    assert ds.sizes["band"] == int(kg.n_bands.sum())
    assert ds.attrs["best_centre_hz"] == pytest.approx(kg.centre)
    # the image repeats each band's K over its cells
    row, _ = kg.best
    freq = ds["frequency"].values
    cell = np.argmin(np.abs(freq - kg.centre))
    assert ds["kurtosis"].values[row, cell] == kg.kurtosis_max
    fig = kg.plot()
    assert isinstance(fig, Figure) and "level" in fig.axes[0].get_ylabel()
    sk = spectral_kurtosis(x, fs)
    ds = sk.to_dataset()
    for name, var in ds.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
    assert isinstance(sk.plot(), Figure)
    da = xr.DataArray(x, dims="time", coords={"time": np.arange(x.size) / fs}, name="acc")
    assert fast_kurtogram(da, max_level=5).name == "acc"


def test_gaussian_threshold():
    assert gaussian_threshold(400.0, 0.5 - 1e-12) == pytest.approx(0.0, abs=1e-9)
    assert gaussian_threshold(400.0, 0.0227501) == pytest.approx(2 * 2 / 20, rel=1e-4)  # 2 sigma
    with pytest.raises(ValueError, match="probability"):
        gaussian_threshold(100.0, 0.7)
    with pytest.raises(ValueError, match="effective_samples"):
        gaussian_threshold(-1.0)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda x: fast_kurtogram(x[:300], 1000.0), "at least 512"),
        (lambda x: fast_kurtogram(x, 1000.0, max_level=20), "max_level"),
        (lambda x: fast_kurtogram(x, 1000.0, max_level=0), "max_level"),
        (lambda x: fast_kurtogram(x, 1000.0, max_level=2.0), "max_level"),
        (lambda x: fast_kurtogram(x, 1000.0, min_bandwidth=-1.0), "min_bandwidth"),
        (lambda x: fast_kurtogram(x, 1000.0, min_bandwidth=600.0), "min_bandwidth"),
        (lambda x: fast_kurtogram(np.ones(5000), 1000.0), "constant"),
        (lambda x: fast_kurtogram(np.stack([x, x]), 1000.0, axis=1), "one channel"),
        (lambda x: fast_kurtogram(x.astype(complex), 1000.0), "real"),
        (lambda x: spectral_kurtosis(x, 1000.0, segment_length=3), "segment_length"),
        (lambda x: spectral_kurtosis(x, 1000.0, segment_length=5000), "segment_length"),
        (lambda x: spectral_kurtosis(x, 1000.0, overlap=1.0), "overlap"),
        (lambda x: spectral_kurtosis(x, 1000.0, segment_length=True), "segment_length"),
        (lambda x: Band(5.0, 1.0), "band"),
        (lambda x: Band(1.0, 5.0, transition=10.0), "transition"),
    ],
)
def test_bad_input_names_the_parameter(call, match):
    x = np.random.default_rng(0).standard_normal(5000)
    with pytest.raises(ValueError, match=match):
        call(x)


def test_band_gain_is_a_partition_of_unity():
    f = np.linspace(0.0, 1000.0, 20001)
    bands = [Band(k * 125.0, (k + 1) * 125.0, 62.5) for k in range(8)]
    total = sum(b.gain(f) for b in bands)
    inner = (f >= 62.5) & (f <= 968.75)  # the first band rises from 0 Hz (gain 0 at DC)
    np.testing.assert_allclose(total[inner], 1.0, atol=1e-12)
    assert bands[0].gain(0.0) == 0.0 and bands[0].gain(31.25) == pytest.approx(0.5)
    assert bands[-1].gain(1000.0, fs=2000.0) == 0.0  # the last one falls to 0 at fs/2
    b = bands[3]
    assert b.gain(b.low) == pytest.approx(0.5) and b.gain(b.high) == pytest.approx(0.5)
    assert b.gain(b.centre) == 1.0 and b.gain(b.support[1]) == 0.0
    assert b.gain(-10.0) == 0.0
