"""Tests of analysis.maps against analytic values and scipy.signal.ShortTimeFFT."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal
import xarray as xr

from analysis.maps import (
    campbell,
    overall_level,
    rpm_frequency_map,
    rpm_frequency_map_ds,
    rpm_order_map,
    rpm_order_map_ds,
)
from analysis.orders import angle_from_speed, order_cuts_from_map

FS = 4096.0


def _runup(duration: float = 10.0, n0: float = 600.0, n1: float = 6000.0):
    t = np.arange(int(FS * duration)) / FS
    rpm = n0 + (n1 - n0) * t / duration
    theta = angle_from_speed(t, rpm)
    return t, rpm, 1.5 * np.sin(3 * theta + 0.2) + 0.7 * np.sin(7 * theta + 1.0)


def test_frequency_map_matches_shorttimefft_and_metadata():
    rng = np.random.default_rng(0)
    x = rng.standard_normal(20000)
    rpm = np.linspace(1000, 3000, x.size)
    m = rpm_frequency_map(x, FS, rpm, amplitude="power", resolution=FS / 128)
    # MATLAB definition: resolution = ENBW; Hann ENBW 1.5 bins -> window 1.5 * 128 = 192
    # (fs / 128 is MATLAB's default resolution)
    assert m.segment_length == 192
    assert m.resolution_hz == pytest.approx(FS / 128)
    assert m.bin_spacing_hz == pytest.approx(FS / 192)
    w = scipy.signal.windows.hann(192, sym=False)
    stft = scipy.signal.ShortTimeFFT(w, hop=96, fs=FS, scale_to=None)
    ref = np.abs(stft.stft(x, p0=0, p1=(x.size - 192) // 96 + 1, k_offset=96)) ** 2
    ref = ref.T * 2 / w.sum() ** 2
    ref[:, 0] /= 2
    ref[:, -1] /= 2
    np.testing.assert_allclose(m.values, ref, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(m.time, (np.arange(m.time.size) * 96 + 95.5) / FS)
    np.testing.assert_allclose(m.rpm, np.interp(m.time, np.arange(x.size) / FS, rpm))
    ds = m.to_dataset()
    assert ds["amplitude"].dims == ("frequency", "time")  # CF 2.4: time last
    assert ds["rpm"].dims == ("time",)
    for v in [*ds.data_vars, *ds.coords]:
        assert "units" in ds[v].attrs and "long_name" in ds[v].attrs
    assert ds["frequency"].attrs["units"] == "Hz" and ds["rpm"].attrs["units"] == "min-1"
    for key in ("window", "amplitude", "resolution_hz", "enbw_hz", "overlap"):
        assert key in ds.attrs


@pytest.mark.parametrize("amplitude", ["rms", "peak", "power"])
def test_frequency_map_sine_level_and_db(amplitude):
    n = 16384
    f0 = 40 * FS / 192  # on a line of the map of resolution fs / 128 (192-sample Hann)
    x = 2.0 * np.sin(2 * np.pi * f0 * np.arange(n) / FS)
    kw = {"amplitude": amplitude, "resolution": FS / 128}
    lin = rpm_frequency_map(x, FS, np.full(n, 1000.0), **kw)
    db = rpm_frequency_map(x, FS, np.full(n, 1000.0), **kw, scale="dB")
    expected = {"rms": 2 / np.sqrt(2), "peak": 2.0, "power": 2.0}[amplitude]
    np.testing.assert_allclose(lin.values[:, 40], expected, rtol=1e-9)
    factor = 10 if amplitude == "power" else 20
    np.testing.assert_allclose(db.values[:, 40], factor * np.log10(expected), atol=1e-9)
    np.testing.assert_allclose(db.power(), lin.power(), rtol=1e-9, atol=1e-30)


def test_order_map_runup_amplitudes():
    _t, rpm, x = _runup()
    m = rpm_order_map(x, FS, rpm, resolution=0.25, overlap=0.75)
    assert m.resolution_orders == pytest.approx(0.25, rel=0.01)
    for order, amp in ((3, 1.5), (7, 0.7)):
        k = int(np.argmin(np.abs(m.order - order)))
        err_db = 20 * np.log10(m.values[:, k] / (amp / np.sqrt(2)))
        assert np.max(np.abs(err_db)) < 0.2  # flat-top: no scalloping correction needed
    assert np.all(np.diff(m.rpm) > 0) and m.rpm[0] > 600 and m.rpm[-1] < 6000
    ds = m.to_dataset()
    assert ds["amplitude"].dims == ("order", "time")
    assert ds["order"].attrs["units"] == "1"
    cut = order_cuts_from_map(m, [3, 7], bandwidth=1.0, amplitude="peak")
    np.testing.assert_allclose(cut.values[0], 1.5, rtol=0.023)
    np.testing.assert_allclose(cut.values[1], 0.7, rtol=0.023)


def test_overall_level_parseval():
    rng = np.random.default_rng(1)
    x = 0.5 + 2.0 * rng.standard_normal(40960)
    lvl = overall_level(x, FS, np.full(x.size, 1500.0), window="rectangular",
                        resolution=FS / 128)
    # rectangular window (ENBW 1 line): 128-sample frames; the sum of the lines is the mean
    # square of each frame exactly (Parseval)
    frames = np.lib.stride_tricks.sliding_window_view(x, 128)[::64]
    np.testing.assert_allclose(lvl.values, np.sqrt(np.mean(frames**2, axis=1)), rtol=1e-10)
    hann = overall_level(x, FS, np.full(x.size, 1500.0), scale="dB")
    assert np.mean(10 ** (hann.values / 10)) == pytest.approx(np.mean(x**2), rel=0.05)
    ds = lvl.to_dataset()
    assert ds["overall_level"].attrs["units"] == "1" and ds["rpm"].attrs["units"] == "min-1"


def test_campbell_critical_speeds():
    c = campbell([100.0, 450.0], [3, 7], (600, 6000))
    np.testing.assert_allclose(c.critical_rpm[0], [2000.0, np.nan])  # 60*450/3 > 6000
    np.testing.assert_allclose(c.critical_rpm[1], [60 * 100 / 7, 60 * 450 / 7])
    np.testing.assert_allclose(c.order_frequency[1, -1], 700.0)
    ds = c.to_dataset()
    assert ds["critical_rpm"].attrs["units"] == "min-1"
    with pytest.raises(ValueError, match="rpm_range"):
        campbell([100.0], [3], (6000, 600))
    with pytest.raises(ValueError, match="natural_frequencies_hz"):
        campbell([-1.0], [3], (600, 6000))


def _dataset(speed_units: str = "min-1") -> xr.Dataset:
    t, rpm, x = _runup(duration=4.0, n1=3000.0)
    speed = rpm if speed_units == "min-1" else rpm * 2 * np.pi / 60
    return xr.Dataset(
        {"normal_force": ("time", x.astype(np.float32), {"units": "N"})},
        coords={
            "time": ("time", t, {"units": "s"}),
            "input_speed": ("time", speed, {"units": speed_units}),
        },
    )


def test_dataset_convenience_and_float32():
    ds = _dataset()
    m = rpm_frequency_map_ds(ds, "normal_force", speed="input_speed")
    ref = rpm_frequency_map(ds["normal_force"].values.astype(float), FS, ds["input_speed"].values)
    np.testing.assert_allclose(m.values, ref.values, rtol=1e-5, atol=1e-6)
    assert m.to_dataset()["amplitude"].attrs["units"] == "N"
    om = rpm_order_map_ds(_dataset("rad s-1"), "normal_force", speed="input_speed")
    np.testing.assert_allclose(om.rpm[-1], ds["input_speed"].values[-1], rtol=0.1)
    with pytest.raises(ValueError, match="units"):
        bad = ds.copy()
        bad["input_speed"].attrs["units"] = "furlong"
        rpm_frequency_map_ds(bad, "normal_force", speed="input_speed")
    with pytest.raises(ValueError, match="speed"):
        rpm_frequency_map_ds(ds, "normal_force", speed="nope")


def test_map_errors():
    x = np.ones(5000)
    rpm = np.full(5000, 1000.0)
    with pytest.raises(ValueError, match="mismatch"):
        rpm_frequency_map(x, FS, rpm[:-1])
    with pytest.raises(ValueError, match="sample-rate mismatch"):
        rpm_frequency_map(x, 1000.0, rpm, time=np.arange(5000) / FS)
    nan = x.copy()
    nan[10] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        rpm_frequency_map(nan, FS, rpm)
    with pytest.raises(ValueError, match="empty"):
        rpm_frequency_map(np.array([]), FS, np.array([]))
    with pytest.raises(ValueError, match="window"):
        rpm_frequency_map(x, FS, rpm, window="hanning")  # MATLAB's name; scipy's is "hann"
    with pytest.raises(ValueError, match="array of shape") as err:
        rpm_frequency_map(x, FS, rpm, window=np.hanning(256))
    assert len(str(err.value)) < 300 and "[" not in str(err.value)  # the array is not printed
    with pytest.raises(ValueError, match="amplitude"):
        rpm_frequency_map(x, FS, rpm, amplitude="psd")
    with pytest.raises(ValueError, match="overlap"):
        rpm_frequency_map(x, FS, rpm, overlap=-0.1)
    with pytest.raises(ValueError, match="resolution"):
        rpm_frequency_map(x, FS, rpm, resolution=FS)
    with pytest.raises(ValueError, match="axis"):  # either axis could be time: never guessed
        rpm_frequency_map(np.ones((64, 64)), FS, np.full(64, 1000.0))
    with pytest.raises(ValueError, match="rpm must be > 0"):
        rpm_order_map(x, FS, np.where(np.arange(5000) > 100, rpm, -5.0))


@pytest.mark.parametrize("kw", [{}, {"samples_per_rev": 32, "overlap": 0.75, "scale": "dB"}])
def test_order_map_blockwise_equals_whole_record(kw):
    from tests.analysis.test_orders import _whole_record_resample

    t, rpm, x = _runup(duration=4.0)
    x = x + 0.1 * np.random.default_rng(2).standard_normal(x.size)
    one = rpm_order_map(x, FS, rpm, block_size=10**9, **kw)
    # a block boundary every frame or every few frames
    for block in (150, 1000):
        m = rpm_order_map(x, FS, rpm, block_size=block, **kw)
        # to rounding of the amplitudes (lines 130 dB down carry relative rounding errors
        # of 1e-10 in dB scale, hence the comparison as power)
        p_ref = one.power()
        np.testing.assert_allclose(m.power(), p_ref, rtol=1e-12, atol=1e-14 * p_ref.max())
        np.testing.assert_allclose(m.time, one.time, rtol=1e-14)
        np.testing.assert_allclose(m.rpm, one.rpm, rtol=1e-14)
    # the same frames of the whole resampled record (as computed before block-wise working)
    spr = one.samples_per_rev
    ref, ref_t = _whole_record_resample(x, t, angle_from_speed(t, rpm), spr)
    frames = rpm_frequency_map(
        ref,
        float(spr),
        np.ones(ref.size),
        resolution=one.resolution_orders,
        window="flattop",
        overlap=kw.get("overlap", 0.5),
        scale=kw.get("scale", "linear"),
    )
    assert frames.segment_length == one.segment_length
    p_ref = frames.power()[:, : one.order.size]  # the order map ends at max_order
    assert one.order[-1] <= one.max_order < one.order[-1] + one.bin_spacing_orders
    np.testing.assert_allclose(one.power(), p_ref, rtol=1e-10, atol=1e-14 * p_ref.max())
    centre = frames.time * spr  # frame centres in samples of the angle signal
    np.testing.assert_allclose(one.time, np.interp(centre, np.arange(ref.size), ref_t))
    np.testing.assert_allclose(one.rpm, np.interp(one.time, t, rpm), rtol=1e-12)


def test_order_map_memory_is_bounded():
    from tests.analysis.test_orders import _long_record, _peak_bytes

    # Beyond the map itself, the block-wise map allocates a few blocks (about 0.3x one
    # float64 channel here, a fixed ~5 MB whatever the record's length); one array as long
    # as the record (low-passed signal, angle, time axis, resampled signal) would be 1x.
    fs, _t, rpm, x = _long_record()
    channel = 8 * x.size
    peak, m = _peak_bytes(lambda: rpm_order_map(x, fs, rpm, samples_per_rev=32, max_order=10.0))
    assert peak - m.values.nbytes < 0.75 * channel
    assert m.values.shape[1] == m.order.size
