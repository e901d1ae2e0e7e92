"""Tests of analysis.orders: angle integration, angular resampling, order spectra, order cuts."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.orders import (
    angle_from_speed,
    order_cuts,
    order_cuts_from_map,
    order_spectrum,
    resample_to_angle,
)

FS = 4096.0
T = 10.0
AMPS = {3.0: 1.5, 7.0: 0.7}


def _runup(fs: float = FS, duration: float = T, n0: float = 600.0, n1: float = 6000.0):
    t = np.arange(int(fs * duration)) / fs
    rpm = n0 + (n1 - n0) * t / duration
    # analytic angle of a linear speed ramp
    theta = 2 * np.pi / 60 * (n0 * t + 0.5 * (n1 - n0) / duration * t**2)
    x = sum(a * np.sin(o * theta + 0.3 * o) for o, a in AMPS.items())
    return t, rpm, theta, x


def test_angle_from_speed_is_exact_for_linear_ramp():
    t, rpm, theta, _ = _runup()
    np.testing.assert_allclose(angle_from_speed(t, rpm), theta, rtol=1e-12, atol=1e-9)
    assert angle_from_speed([0.0, 1.0, 2.0], [60.0, 60.0, 60.0])[-1] == pytest.approx(4 * np.pi)


def test_resample_reproduces_known_order_signal():
    t, _rpm, theta, x = _runup()
    sig = resample_to_angle(x, t, theta, 64, max_order=20.0, units="N", name="force")
    ref = sum(a * np.sin(o * sig.angle + 0.3 * o) for o, a in AMPS.items())
    inner = slice(5 * 64, -5 * 64)  # skip 5 revolutions of filter edge effects at each end
    err = np.max(np.abs(sig.values[inner] - ref[inner]))
    assert err < 2e-3 * 1.5
    np.testing.assert_allclose(np.diff(sig.angle), 2 * np.pi / 64, rtol=1e-9)
    # the time of each angle sample inverts the analytic angle
    np.testing.assert_allclose(np.interp(sig.time, t, theta), sig.angle, atol=1e-9)
    ds = sig.to_dataset()
    assert ds["force"].attrs["units"] == "N"
    assert ds["angle"].attrs["units"] == "rad"


def test_resample_removes_orders_above_nyquist_instead_of_aliasing():
    t, _rpm, theta, _ = _runup(n1=2400.0)  # order 45 stays below fs/2 in the input
    # order 45 would alias to order 64 - 45 = 19 at 64 samples/rev without filtering
    x = np.sin(45 * theta)
    sig = resample_to_angle(x, t, theta, 64, max_order=20.0)
    inner = sig.values[5 * 64 : -5 * 64]
    assert np.sqrt(np.mean(inner**2)) < 1e-3


def test_resample_multichannel():
    t, _rpm, theta, x = _runup(duration=2.0, n1=2000.0)
    both = np.stack([x, 2 * x])
    sig = resample_to_angle(both, t, theta, 32)
    assert sig.values.shape[0] == 2
    np.testing.assert_allclose(sig.values[1], 2 * sig.values[0], rtol=1e-10, atol=1e-12)


def test_order_spectrum_amplitudes():
    t, rpm, _, x = _runup()
    osp = order_spectrum(x, t, rpm, orders_resolution=0.25, scaling="rms", units="N")
    assert osp.resolution_orders == pytest.approx(0.25, rel=0.02)
    for o, a in AMPS.items():
        k = int(np.argmin(np.abs(osp.order - o)))
        assert 20 * np.log10(osp.values[k] / (a / np.sqrt(2))) == pytest.approx(0, abs=0.05)
    pk = osp.peaks(threshold=0.1)
    np.testing.assert_allclose(pk.frequency, sorted(AMPS), atol=0.01)
    ds = osp.to_dataset()
    assert ds["order"].attrs["units"] == "1"
    assert ds["order_spectrum"].attrs["units"] == "N"


def _db_err(cut, i: int, amp: float, sel: np.ndarray) -> np.ndarray:
    return 20 * np.log10(cut.values[i, sel] / (amp / np.sqrt(2)))


def test_order_cuts_proportional_band_from_order_map():
    _t, rpm, _, x = _runup()
    cut = order_cuts(x, FS, rpm, [3, 7], amplitude="rms")
    assert cut.bandwidth_kind == "order"
    for i, a in enumerate(AMPS.values()):
        err = _db_err(cut, i, a, np.ones(cut.time.size, bool))
        assert np.max(np.abs(err)) < 0.2
    db = order_cuts(x, FS, rpm, [3], scale="dB", amplitude="peak")
    assert np.max(np.abs(db.values[0] - 20 * np.log10(1.5))) < 0.2
    ds = cut.to_dataset()
    assert ds["rpm"].attrs["units"] == "min-1" and ds["level"].dims == ("order", "time")


def test_order_cuts_fixed_hz_band_away_from_crossings():
    _t, rpm, _, x = _runup()
    bw = 120.0  # wider than the Hann main lobe (4 lines of 21.3 Hz at the default fs/128)
    cut = order_cuts(x, FS, rpm, [3, 7], bandwidth_hz=bw)
    assert cut.bandwidth_kind == "Hz" and cut.source == "RpmFrequencyMap"
    # the two order bands are apart once 4 orders * rpm/60 exceeds the band + main lobes
    apart = (4 * cut.rpm / 60 > bw + 4 * 21.4) & (cut.time > 0.1) & (cut.time < T - 0.1)
    assert apart.sum() > 50
    for i, a in enumerate(AMPS.values()):
        assert np.max(np.abs(_db_err(cut, i, a, apart))) < 0.2


def test_order_cuts_proportional_band_on_frequency_map_and_nan_outside():
    from analysis.maps import rpm_frequency_map

    _t, rpm, _, x = _runup()
    m = rpm_frequency_map(x, FS, rpm, resolution=8.0, amplitude="peak", scale="dB")
    cut = order_cuts_from_map(m, [3, 7, 40], bandwidth=1.0)
    sel = cut.rpm > 1200
    for i, a in enumerate(AMPS.values()):
        assert np.max(np.abs(_db_err(cut, i, a, sel))) < 0.2
    # order 40 exceeds fs/2 above 3072 min-1
    assert np.all(np.isnan(cut.values[2, cut.rpm > 3100]))


def test_order_errors():
    t, rpm, theta, x = _runup(duration=1.0, n1=1200.0)
    back = theta.copy()
    back[100] = back[99]
    with pytest.raises(ValueError, match="strictly increasing"):
        resample_to_angle(x, t, back, 32)
    with pytest.raises(ValueError, match="samples_per_rev"):
        resample_to_angle(x, t, theta, 2)
    with pytest.raises(ValueError, match="max_order"):
        resample_to_angle(x, t, theta, 32, max_order=20)
    with pytest.raises(ValueError, match="mismatch"):
        resample_to_angle(x[:-1], t, theta, 32)
    bad = x.copy()
    bad[3] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        resample_to_angle(bad, t, theta, 32)
    with pytest.raises(ValueError, match="rpm must be > 0"):
        order_spectrum(x, t, np.where(t > 0.5, 0.0, rpm), orders_resolution=0.5)
    with pytest.raises(ValueError, match="time"):
        angle_from_speed(t[::-1], rpm)
    with pytest.raises(ValueError, match="revolutions"):
        order_spectrum(x, t, rpm, orders_resolution=0.001)
    with pytest.raises(ValueError, match="speed range too wide"):
        tt = np.arange(4096) / 4096.0
        resample_to_angle(np.sin(tt), tt, angle_from_speed(tt, 1 + 6000 * tt), 64)
    with pytest.raises(ValueError, match="bandwidth"):
        order_cuts(x, FS, rpm, [3], bandwidth=1e-4)
