"""Tests of analysis.tsa: time-synchronous averaging from a tacho, pulse times, rpm or angle.

Independent generators written here: analytic shaft angles (constant speed, sinusoidal speed
fluctuation), synchronous waveforms given as sums of orders, white Gaussian noise, tacho pulse
trains sampled from the analytic angle.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from analysis.tsa import TSA, comb_response, fractional_shift, tsa, tsa_windows

FS = 4096.0
SHAFT_HZ = 16.0  # fs / shaft frequency = 256 samples per revolution at constant speed


def angle_const(n: int, f: float = SHAFT_HZ, fs: float = FS) -> np.ndarray:
    return 2 * np.pi * f * np.arange(n) / fs


def angle_fluct(n: int, f: float = SHAFT_HZ, depth: float = 0.05, fm: float = 0.4,
                fs: float = FS) -> np.ndarray:  # fmt: skip
    """Angle of a shaft at ``f (1 + depth sin(2 pi fm t))`` Hz, integrated analytically."""
    t = np.arange(n) / fs
    return 2 * np.pi * f * (t + depth * (1 - np.cos(2 * np.pi * fm * t)) / (2 * np.pi * fm))


def sync(theta: np.ndarray) -> np.ndarray:
    """A synchronous waveform: orders 1, 3, 17 and 40 with phases."""
    return (0.3 * np.cos(theta + 1.0) + np.cos(3 * theta + 0.4) + 0.5 * np.sin(17 * theta)
            + 0.2 * np.cos(40 * theta - 1.0))  # fmt: skip


def pulses(theta: np.ndarray, ppr: int, ramp_samples: float = 4.0) -> np.ndarray:
    """A tacho of ``ppr`` pulses per revolution: a linear rise through the level 0.5 exactly at
    ``theta = 2 pi k / ppr`` (over about ``ramp_samples`` samples), high for half a pitch."""
    pitch_samples = 2 * np.pi / ppr / np.median(np.diff(theta))
    ramp = min(0.25, ramp_samples / pitch_samples)
    w = np.mod(theta * ppr / (2 * np.pi) + 0.5, 1.0) - 0.5  # pitch fraction in [-0.5, 0.5)
    return np.where(w < 0.4, np.clip(0.5 + w / ramp, 0.0, 1.0), 0.0)


# ------------------------------------------------------------------------------------------
# what the average recovers and what it suppresses
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("ref", ["angle", "rpm"])
def test_synchronous_signal_recovered_at_varying_speed(ref):
    n = int(25 * FS)
    theta = angle_fluct(n)
    kw = {"angle": theta}
    if ref == "rpm":
        t = np.arange(n) / FS
        kw = {"rpm": 60 * SHAFT_HZ * (1 + 0.05 * np.sin(2 * np.pi * 0.4 * t))}
    r = tsa(sync(theta), FS, samples_per_rev=256, **kw)
    # rpm integrated from 0 at sample 0 = the analytic angle, so both references agree
    assert np.max(np.abs(r.values - sync(r.angle))) < 3e-4
    assert r.revolutions >= 395
    assert r.noise_reduction == pytest.approx(1 / np.sqrt(r.revolutions))
    assert r.noise_reduction_db == pytest.approx(-10 * np.log10(r.revolutions))
    assert r.nonsynchronous_rms < 1e-3  # nothing but the synchronous waveform
    np.testing.assert_allclose(r.angle, 2 * np.pi * np.arange(256) / 256)


@pytest.mark.parametrize("ppr", [1, 16])
def test_tacho_gives_the_angle_zero_at_the_first_pulse(ppr):
    n = int(20 * FS)
    # the record starts half a pitch before the pulse at theta = 0: that pulse is the first
    # one detected, so the average's angle 0 is theta = 0
    theta = angle_fluct(n, depth=0.02) - np.pi / ppr
    r = tsa(sync(theta), FS, tacho=pulses(theta, ppr), pulses_per_rev=ppr, samples_per_rev=256)
    err = np.max(np.abs(r.values - sync(r.angle)))
    assert err < 3e-4, err
    assert np.angle(np.fft.rfft(r.values)[3]) == pytest.approx(0.4, abs=1e-3)
    assert "tacho" in r.reference


def test_pulse_times_like_matlab():
    n = int(20 * FS)
    theta = angle_const(n)
    tp = np.arange(1, 300) / SHAFT_HZ + 0.25 / SHAFT_HZ  # pulses a quarter turn after 0
    r = tsa(sync(theta), FS, pulse_times=tp, samples_per_rev=256)
    # the angle zero is the first pulse: the waveform is shifted by a quarter revolution
    assert np.max(np.abs(r.values - sync(r.angle + np.pi / 2))) < 3e-4


def test_other_shaft_through_a_ratio():
    """Average the output shaft (ratio 13/37) from an input-shaft tacho: the output's orders
    are kept, the input's (non-synchronous on the output) are suppressed."""
    n = int(40 * FS)
    th_in = angle_const(n, f=37.0) - np.pi / 10  # the first pulse detected: th_in = 0
    th_out = th_in * 13 / 37
    x = np.cos(5 * th_out + 0.2) + np.cos(th_in)  # input order 1 = output order 37/13
    r = tsa(x, FS, tacho=pulses(th_in, 10), pulses_per_rev=10, ratio=13 / 37,
            samples_per_rev=256)  # fmt: skip
    spec = np.fft.rfft(r.values) * 2 / 256
    assert abs(spec[5]) == pytest.approx(1.0, abs=2e-3)
    assert np.angle(spec[5]) == pytest.approx(0.2, abs=5e-3)
    delta = 37 / 13 - 3
    bound = comb_response(delta, r.revolutions)
    assert np.max(np.abs(spec[2:4])) < bound + 5e-3
    assert r.ratio == pytest.approx(13 / 37)


def _noise_error(revs: int, seed: int) -> tuple[float, float]:
    n = int((revs + 3) * FS / SHAFT_HZ)
    theta = angle_const(n)
    e = np.random.default_rng(seed).normal(0.0, 1.0, n)
    r = tsa(np.cos(5 * theta) + e, FS, angle=theta, samples_per_rev=256, revolutions=revs)
    err = float(np.sqrt(np.mean((r.values - np.cos(5 * r.angle)) ** 2)))
    return err, float(r.residual_noise_rms)


def test_noise_reduction_is_one_over_sqrt_revolutions():
    """Over 24 seeds: the rms noise left falls as N^-1/2 (log-log slope -0.5 within 0.03) and
    equals the stated residual_noise_rms (nonsynchronous_rms / sqrt(N)) within 3 %."""
    counts = [4, 16, 64, 256]
    mean_err = []
    for revs in counts:
        errs, stated = zip(*(_noise_error(revs, s) for s in range(24)), strict=True)
        mean_err.append(np.mean(errs))
        assert np.mean(errs) / np.mean(stated) == pytest.approx(1.0, abs=0.03)
    slope = np.polyfit(np.log(counts), np.log(mean_err), 1)[0]
    assert slope == pytest.approx(-0.5, abs=0.03)


@pytest.mark.parametrize("delta", [0.05, 0.13, 0.37, 0.5])
def test_non_synchronous_sine_follows_the_comb_response(delta):
    revs = 20
    n = int((revs + 3) * FS / SHAFT_HZ)
    theta = angle_const(n)
    r = tsa(np.cos((7 + delta) * theta), FS, angle=theta, samples_per_rev=256, revolutions=revs)
    expected = comb_response(delta, revs)
    assert np.max(np.abs(r.values)) == pytest.approx(expected, abs=2e-3 + 0.02 * expected)


def test_comb_response_formula():
    assert comb_response(0.0, 10) == 1.0
    assert comb_response(3.0, 10) == 1.0
    assert comb_response(0.1, 10) == pytest.approx(0.0, abs=1e-12)  # N delta integer: a null
    d = 0.23
    hand = abs(np.sin(7 * np.pi * d) / (7 * np.sin(np.pi * d)))
    assert comb_response(d, 7) == pytest.approx(hand)


def test_fractional_shift_is_exact_for_band_limited_signals():
    n = 64
    i = np.arange(n)
    f = lambda s: np.cos(2 * np.pi * 3 * (i - s) / n) + 0.2 * np.sin(2 * np.pi * 11 * (i - s) / n)  # noqa: E731
    np.testing.assert_allclose(fractional_shift(f(0.0), 2.37), f(2.37), atol=1e-12)
    np.testing.assert_allclose(fractional_shift(f(0.0), -5.5), f(-5.5), atol=1e-12)


# ------------------------------------------------------------------------------------------
# windows over time, block size, determinism, multi-channel, results
# ------------------------------------------------------------------------------------------


def test_windows_over_time():
    n = int(30 * FS)
    theta = angle_const(n)
    x = sync(theta) + np.random.default_rng(1).normal(0, 0.1, n)
    wins = tsa_windows(x, FS, angle=theta, revolutions=50, samples_per_rev=256)
    assert len(wins) == 9  # 480 revolutions minus the edge guards -> 9 x 50
    assert all(w.revolutions == 50 for w in wins)
    starts = [w.start_time for w in wins]
    assert np.all(np.diff(starts) == pytest.approx(50 / SHAFT_HZ, rel=1e-6))
    first = tsa(x, FS, angle=theta, revolutions=50, samples_per_rev=256)
    np.testing.assert_allclose(wins[0].values, first.values, atol=1e-12)
    assert len(tsa_windows(x, FS, angle=theta, revolutions=50, windows=3)) == 3


def test_block_size_and_determinism():
    n = int(12 * FS)
    theta = angle_fluct(n)
    x = np.vstack([sync(theta), np.random.default_rng(2).normal(size=n)])
    a = tsa(x, FS, angle=theta, samples_per_rev=256)
    b = tsa(x, FS, angle=theta, samples_per_rev=256, block_size=700)
    c = tsa(x, FS, angle=theta, samples_per_rev=256)
    np.testing.assert_allclose(a.values, b.values, atol=1e-12)
    assert np.array_equal(a.values, c.values)  # same input, same output, bit for bit
    assert a.values.shape == (2, 256)
    one = a.select(1)
    assert one.values.shape == (256,)
    assert float(one.nonsynchronous_rms) == pytest.approx(float(a.nonsynchronous_rms[1]))


def test_dataarray_input_and_cf_dataset():
    n = int(10 * FS)
    theta = angle_const(n)
    t = np.arange(n) / FS + 5.0
    da = xr.DataArray(
        np.vstack([sync(theta), 2 * sync(theta)]), dims=("channel", "time"),
        coords={"time": ("time", t), "channel": ["a", "b"]}, attrs={"units": "m s-2"},
        name="acc",
    )  # fmt: skip
    r = tsa(da, tacho=pulses(theta, 4), pulses_per_rev=4, samples_per_rev=128)
    assert isinstance(r, TSA)
    assert r.start_time > 5.0
    assert r.rpm == pytest.approx(60 * SHAFT_HZ, rel=1e-6)
    ds = r.to_dataset()
    assert ds["tsa"].attrs["units"] == "m s-2"
    for v in [*ds.data_vars, *ds.coords]:
        assert "long_name" in ds[v].attrs, v
        if ds[v].dtype.kind in "fi":
            assert "units" in ds[v].attrs, v
    assert ds.attrs["revolutions"] == r.revolutions
    assert list(ds["channel"].values) == ["a", "b"]
    np.testing.assert_allclose(r.select("b").values, 2 * r.select("a").values, atol=1e-9)
    fig = r.plot()
    assert fig.axes and fig.axes[0].lines
    fig2 = r.plot(channel="a")
    assert len(fig2.axes[0].lines) == 1


def test_revolutions_count_and_limit():
    n = int(5 * FS)
    theta = angle_const(n)
    r = tsa(sync(theta), FS, angle=theta, samples_per_rev=256, revolutions=10)
    assert r.revolutions == 10
    assert r.stop_time - r.start_time == pytest.approx(10 / SHAFT_HZ, rel=1e-3)
    with pytest.raises(ValueError, match="revolutions = 500"):
        tsa(sync(theta), FS, angle=theta, samples_per_rev=256, revolutions=500)


# ------------------------------------------------------------------------------------------
# bad input
# ------------------------------------------------------------------------------------------


@pytest.fixture
def rec():
    n = int(4 * FS)
    theta = angle_const(n)
    return sync(theta), theta


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"samples_per_rev": True}, ValueError, "samples_per_rev"),
        ({"samples_per_rev": "256"}, ValueError, "samples_per_rev"),
        ({"samples_per_rev": 2}, ValueError, "samples_per_rev"),
        ({"ratio": "2"}, TypeError, "ratio"),
        ({"ratio": True}, TypeError, "ratio"),
        ({"ratio": np.nan}, ValueError, "ratio"),
        ({"ratio": -1.0}, ValueError, "ratio"),
        ({"revolutions": 1}, ValueError, "revolutions"),
        ({"revolutions": 2.5}, ValueError, "revolutions"),
        ({"revolutions": True}, ValueError, "revolutions"),
        ({"max_order": "10"}, TypeError, "max_order"),
        ({"max_order": 500.0}, ValueError, "max_order"),
        ({"block_size": 0}, ValueError, "block_size"),
    ],
)
def test_bad_parameters_are_named(rec, kwargs, error, match):
    x, theta = rec
    with pytest.raises(error, match=match):
        tsa(x, FS, angle=theta, **{"samples_per_rev": 256, **kwargs})


def test_bad_signals_and_references_are_named(rec):
    x, theta = rec
    bad = x.copy()
    bad[100] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        tsa(bad, FS, angle=theta)
    with pytest.raises(ValueError, match="real numeric"):
        tsa(x > 0, FS, angle=theta)
    with pytest.raises(ValueError, match="angle"):
        tsa(x, FS, angle=theta[:-5])
    with pytest.raises(ValueError, match="exactly one reference"):
        tsa(x, FS)
    with pytest.raises(ValueError, match="exactly one reference"):
        tsa(x, FS, angle=theta, rpm=np.full(x.size, 960.0))
    with pytest.raises(ValueError, match="tacho"):
        tsa(x, FS, tacho=pulses(theta, 1)[:-3])
    with pytest.raises(TypeError, match="tacho"):
        tsa(x, FS, tacho=pulses(theta, 1) > 0.5)
    with pytest.raises(ValueError, match="pulses_per_rev"):
        tsa(x, FS, tacho=pulses(theta, 1), pulses_per_rev=0)
    with pytest.raises(ValueError, match="pulses_per_rev"):
        tsa(x, FS, angle=theta, pulses_per_rev=2)
    with pytest.raises(ValueError, match="pulse_times"):
        tsa(x, FS, pulse_times=[0.1, np.nan, 0.3, 0.4])
    with pytest.raises(ValueError, match="pulse_times"):
        tsa(x, FS, pulse_times=[0.3, 0.2, 0.1, 0.4])
    with pytest.raises(TypeError, match="pulse_times"):
        tsa(x, FS, pulse_times=["0.1", "0.2", "0.3"])
    with pytest.raises(TypeError, match="rpm"):
        tsa(x, FS, rpm=np.full(x.size, True))
    with pytest.raises(ValueError, match="rpm must be > 0"):
        tsa(x, FS, rpm=np.r_[np.full(x.size // 2, 960.0), np.full(x.size - x.size // 2, -1.0)])
    with pytest.raises(TypeError, match="fs"):
        tsa(x, "4096", angle=theta)
    with pytest.raises(TypeError, match="fs"):
        tsa(x, True, angle=theta)


def test_too_few_revolutions():
    n = int(2.2 * FS / SHAFT_HZ)  # 2.2 revolutions: less than 2 whole ones after the guards
    theta = angle_const(n)
    with pytest.raises(ValueError, match="too few revolutions"):
        tsa(sync(theta), FS, angle=theta, samples_per_rev=256)
    with pytest.raises(ValueError, match="revolutions"):
        tsa_windows(sync(theta), FS, angle=theta, revolutions=True)
