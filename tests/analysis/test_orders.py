"""Tests of analysis.orders: angle integration, angular resampling, order spectra, order cuts."""

from __future__ import annotations

from contextlib import nullcontext

import numpy as np
import pytest

from analysis.orders import (
    OrderBandWarning,
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
    sig = resample_to_angle(x, FS, theta, 64, max_order=20.0, units="N", name="force")
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
    _t, _rpm, theta, _ = _runup(n1=2400.0)  # order 45 stays below fs/2 in the input
    # order 45 would alias to order 64 - 45 = 19 at 64 samples/rev without filtering
    x = np.sin(45 * theta)
    sig = resample_to_angle(x, FS, theta, 64, max_order=20.0)
    inner = sig.values[5 * 64 : -5 * 64]
    assert np.sqrt(np.mean(inner**2)) < 1e-3


def test_resample_multichannel():
    _t, _rpm, theta, x = _runup(duration=2.0, n1=2000.0)
    both = np.stack([x, 2 * x])
    sig = resample_to_angle(both, FS, theta, 32)
    assert sig.values.shape[0] == 2
    np.testing.assert_allclose(sig.values[1], 2 * sig.values[0], rtol=1e-10, atol=1e-12)


def test_order_spectrum_amplitudes():
    _t, rpm, _, x = _runup()
    osp = order_spectrum(x, FS, rpm, resolution=1.0, amplitude="rms", units="N")
    # resolution = the flat-top's ENBW (3.77 lines), as in the maps; line spacing 1/3.77
    assert osp.resolution_orders == pytest.approx(1.0, rel=0.02)
    assert osp.bin_spacing_orders == pytest.approx(1 / 3.7702, rel=0.02)
    assert osp.resolution_orders == pytest.approx(osp.enbw_orders)
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
    bw = 120.0  # wider than the Hann main lobe (4 lines of 21.3 Hz at resolution fs/128)
    # frames of fs/128 (MATLAB's default): short, many; the 120 Hz bands hold both orders
    # below 3084 min-1, which is warned about and left out below
    with pytest.warns(OrderBandWarning, match=r"band of order 3 .* reaches order 7"):
        cut = order_cuts(x, FS, rpm, [3, 7], bandwidth_hz=bw, resolution=FS / 128)
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
        resample_to_angle(x, FS, back, 32)
    with pytest.raises(ValueError, match="samples_per_rev"):
        resample_to_angle(x, FS, theta, 2)
    with pytest.raises(ValueError, match="max_order"):
        resample_to_angle(x, FS, theta, 32, max_order=20)
    with pytest.raises(ValueError, match="mismatch"):
        resample_to_angle(x[:-1], FS, theta, 32)
    bad = x.copy()
    bad[3] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        resample_to_angle(bad, FS, theta, 32)
    with pytest.raises(ValueError, match="rpm must be > 0"):
        order_spectrum(x, FS, np.where((t > 0.4) & (t < 0.5), 0.0, rpm), resolution=2.0)
    with pytest.raises(ValueError, match="time"):
        angle_from_speed(t[::-1], rpm)
    with pytest.raises(ValueError, match="revolutions"):
        order_spectrum(x, FS, rpm, resolution=0.001)
    with pytest.raises(ValueError, match=r"speed range too wide.*min_rpm"):
        tt = np.arange(4096) / 4096.0
        th = angle_from_speed(tt, 1 + 6000 * tt)
        resample_to_angle(np.sin(tt), angle=th, samples_per_rev=64, time=tt, min_rpm=0.0)
    with pytest.raises(ValueError, match="bandwidth"):
        order_cuts(x, FS, rpm, [3], bandwidth=1e-4)


# ------------------------------------------------------------------- block-wise processing


def _whole_record_resample(x, t, theta, spr, max_order=None):
    """The three resampling steps of ``analysis.orders`` applied to the whole record at once.

    Reference for the block-wise implementation (this is how ``resample_to_angle`` computed
    before it worked in blocks): ``sosfiltfilt`` over the whole record, the kernel from
    ``numpy.sinc`` and ``numpy.i0`` on the whole fine grid, ``resample_poly`` over all of it.
    Returns the resampled values and the instants of the output samples.
    """
    import scipy.signal

    n = t.size
    fs = (n - 1) / (t[-1] - t[0])
    mo = spr / 2.56 if max_order is None else max_order
    shaft_hz = np.diff(theta) * fs / (2 * np.pi)
    fc = 1.25 * mo * shaft_hz.max()
    data = np.asarray(x, dtype=float)
    f_top = 0.5 * fs
    if fc < 0.45 * fs:
        data = scipy.signal.sosfiltfilt(scipy.signal.butter(8, fc, fs=fs, output="sos"), data)
        f_top = 1.5 * fc
    over = max(1, int(np.ceil((f_top / shaft_hz.min() + spr / 2) / spr)))
    dphi = 2 * np.pi / (spr * over)
    phi = theta[0] + dphi * np.arange(int(np.floor((theta[-1] - theta[0]) / dphi)) + 1)
    tq = np.interp(phi, theta, t)
    pos = (tq - t[0]) * fs
    base = np.floor(pos).astype(int)
    taps = np.arange(-11, 13)
    tau = (pos - base)[:, None] - taps
    h = np.sinc(tau) * np.i0(7 * np.sqrt(np.clip(1 - (tau / 12) ** 2, 0, None)))
    h /= h.sum(axis=1, keepdims=True)
    fine = (data[..., np.clip(base[:, None] + taps, 0, n - 1)] * h).sum(axis=-1)
    if over == 1:
        return fine, tq
    width = (spr / 2 - mo) / (spr * over / 2)
    numtaps, beta = scipy.signal.kaiserord(80.0, width)
    fir = scipy.signal.firwin(
        numtaps | 1, (mo + spr / 2) / 2, window=("kaiser", beta), fs=spr * over
    )
    out = scipy.signal.resample_poly(fine, 1, over, axis=-1, window=fir)
    return out, tq[::over][: out.shape[-1]]


# (start, end speed [min-1], samples_per_rev, max_order): time-domain low-pass and 8x angular
# oversampling; no low-pass (order range up to fs/2), 4x; low-pass without oversampling
_SAMPLINGS = [(600, 6000, 32, None), (600, 6000, 64, 20.0), (3000, 3600, 64, 10.0)]


@pytest.mark.parametrize(("n0", "n1", "spr", "mo"), _SAMPLINGS)
def test_blockwise_resampling_equals_whole_record(n0, n1, spr, mo):
    t, _rpm, theta, _ = _runup(duration=2.0, n0=n0, n1=n1)
    x = np.sin(3 * theta) + 0.3 * np.random.default_rng(7).standard_normal(t.size)
    ref, ref_t = _whole_record_resample(x, t, theta, spr, mo)
    tol = 1e-12 * np.max(np.abs(ref))
    # block 7 puts a block boundary (and the overlap of its neighbours) every 7 samples, so
    # comparing every sample checks every boundary
    for block in (None, 7, 100):
        sig = resample_to_angle(x, FS, theta, spr, mo, block_size=block)
        assert sig.values.shape == ref.shape
        np.testing.assert_allclose(sig.values, ref, rtol=0, atol=tol)
        np.testing.assert_allclose(sig.time, ref_t, rtol=1e-14)


def test_blockwise_resampling_multichannel_with_offset():
    t, _rpm, theta, x = _runup(duration=2.0, n1=2000.0)
    rng = np.random.default_rng(3)
    both = np.stack([5.0 + x, np.cumsum(rng.standard_normal(t.size)) * 0.01])
    ref, _ = _whole_record_resample(both, t, theta, 32)
    for block in (13, 500):
        sig = resample_to_angle(both.astype(np.float32), FS, theta, 32, block_size=block)
        ref32, _ = _whole_record_resample(both.astype(np.float32), t, theta, 32)
        scale = np.max(np.abs(ref32), axis=-1, keepdims=True)
        assert np.max(np.abs(sig.values - ref32) / scale) < 1e-12
        assert np.max(np.abs(sig.values - ref) / scale) < 1e-6  # float32 input
    with pytest.raises(ValueError, match="block_size"):
        resample_to_angle(x, FS, theta, 32, block_size=0)


def test_order_spectrum_blockwise_equals_single_block():
    from analysis.spectrum import spectrum

    t, rpm, _, x = _runup(duration=4.0)
    x = x + 0.2 * np.random.default_rng(5).standard_normal(t.size)
    for kw in ({}, {"samples_per_rev": 32, "amplitude": "peak"}, {"amplitude": "density"}):
        one = order_spectrum(x, FS, rpm, resolution=1.0, block_size=10**9, **kw)
        # one segment per block, and blocks of a few segments
        for block in (150, 1000):
            osp = order_spectrum(x, FS, rpm, resolution=1.0, block_size=block, **kw)
            np.testing.assert_allclose(osp.values, one.values, rtol=1e-12)
            assert osp.n_averages == one.n_averages
            assert osp.to_dataset().attrs == one.to_dataset().attrs
        # and what a Welch average over the whole resampled signal gives
        spr = one.samples_per_rev
        ref, _ = _whole_record_resample(x, t, angle_from_speed(t, rpm), spr)
        whole = spectrum(
            ref,
            float(spr),
            window="flattop",
            amplitude=kw.get("amplitude", "rms"),
            segment_length=one.segment_length,
            overlap=0.5,
        )
        # the order spectrum ends at max_order (the line nearest below it)
        assert one.order[-1] <= one.max_order < one.order[-1] + one.bin_spacing_orders
        np.testing.assert_allclose(one.order, whole.frequency[: one.order.size], rtol=1e-14)
        np.testing.assert_allclose(
            one.values, whole.values[: one.order.size], rtol=1e-10, atol=1e-13
        )


@pytest.mark.parametrize("kw", [{}, {"bandwidth_hz": 120.0}, {"samples_per_rev": 32}])
def test_order_cuts_blockwise_equals_single_block(kw):
    _t, rpm, _, x = _runup()
    # the fixed 120 Hz bands hold orders 3 and 7 together at low speed: warned about
    def overlap():
        return pytest.warns(OrderBandWarning) if "bandwidth_hz" in kw else nullcontext()

    # order 40 leaves the frequency axis at high speed; 12.4 is the top of the order axis
    # (its band's upper edge beyond it reads NaN); an order above the axis is refused
    orders = [3, 7, 40] if "bandwidth_hz" in kw else [3, 7, 12.4]
    with overlap():
        one = order_cuts(x, FS, rpm, orders, block_size=10**9, **kw)
    assert np.isfinite(one.values).any()
    for block in (150, 777):
        with overlap():
            cut = order_cuts(x, FS, rpm, orders, block_size=block, **kw)
        np.testing.assert_array_equal(np.isnan(cut.values), np.isnan(one.values))
        np.testing.assert_allclose(cut.values, one.values, rtol=1e-12)
        np.testing.assert_allclose(cut.time, one.time, rtol=1e-14)
        np.testing.assert_allclose(cut.rpm, one.rpm, rtol=1e-14)


def test_order_cuts_refuse_an_order_never_analysed():
    _t, rpm, _, x = _runup()
    with pytest.raises(ValueError, match=r"orders: \[40\.0\] lie above the highest analysed"):
        order_cuts(x, FS, rpm, [3, 40])
    with pytest.raises(ValueError, match=r"orders: .*at the slowest frame"):
        order_cuts(x, FS, rpm, [3, 1e9], bandwidth_hz=50.0)


def _peak_bytes(fn) -> tuple[int, object]:
    import tracemalloc

    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        base, _ = tracemalloc.get_traced_memory()
        result = fn()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    return peak - base, result


def _long_record(n: int = 1 << 21, fs: float = 8192.0):
    """256 s at 8192 Hz (16.8 MB per float64 channel), 300 -> 900 min-1, float32 signal."""
    t = np.arange(n) / fs
    rpm = np.linspace(300.0, 900.0, n)
    x = np.random.default_rng(0).standard_normal(n).astype(np.float32)
    return fs, t, rpm, x


def test_order_spectrum_and_cuts_memory_is_bounded():
    # The block-wise computation never allocates an array as long as the record: whatever
    # the record's length, the largest allocation beyond the input is a few blocks (here
    # about 0.3x one float64 channel, a fixed ~5 MB). Holding the low-passed signal, the
    # angle or the time axis of the whole record would each take 1x.
    fs, _t, rpm, x = _long_record()
    channel = 8 * x.size
    sampling = {"samples_per_rev": 32, "max_order": 10.0}
    peak, _ = _peak_bytes(lambda: order_spectrum(x, FS, rpm, resolution=1.0, **sampling))
    assert peak < 0.75 * channel
    peak, cut = _peak_bytes(lambda: order_cuts(x, fs, rpm, [3, 7], **sampling))
    assert peak < 0.75 * channel
    assert cut.values.shape[0] == 2
