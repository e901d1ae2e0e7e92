"""The analysis API of issue #14: several channels, angle references, standstill, datasets,
deprecated names, windows by scipy name, plots into given axes, the xarray accessor."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
import scipy.signal
import xarray as xr
from matplotlib.figure import Figure

import analysis  # registers the accessor
from analysis.inputs import find_reference
from analysis.maps import overall_level, rpm_frequency_map, rpm_order_map, rpm_order_map_ds
from analysis.orders import (
    order_cuts,
    order_cuts_from_map,
    order_spectrum,
    resample_to_angle,
)
from analysis.spectrum import spectrum
from analysis.speed import from_tacho
from analysis.windows import get_window, main_lobe_half_width, window_info

FS = 2048.0
AMPS = {3.0: 1.5, 7.0: 0.7}


def _runup(duration=3.0, n0=600.0, n1=2400.0, fs=FS):
    t = np.arange(int(fs * duration)) / fs
    rpm = n0 + (n1 - n0) * t / duration
    theta = 2 * np.pi / 60 * (n0 * t + 0.5 * (n1 - n0) / duration * t**2)
    return t, rpm, theta


@pytest.fixture(scope="module")
def three_channels():
    t, rpm, theta = _runup()
    rng = np.random.default_rng(4)
    x = np.stack(
        [
            sum(a * np.sin(o * theta + c) for o, a in AMPS.items())
            + 0.1 * rng.standard_normal(t.size)
            for c in (0.0, 1.0, 2.0)
        ]
    )
    return t, rpm, theta, x


# ------------------------------------------------------------------------ several channels


def _calls(rpm, theta):
    return {
        "spectrum": lambda x, **k: spectrum(x, FS, segment_length=512, **k),
        "frequency_map": lambda x, **k: rpm_frequency_map(x, FS, rpm, **k),
        "frequency_map_angle": lambda x, **k: rpm_frequency_map(x, FS, angle=theta, **k),
        "order_map": lambda x, **k: rpm_order_map(x, FS, rpm, samples_per_rev=32, **k),
        "order_map_angle": lambda x, **k: rpm_order_map(
            x, FS, angle=theta, samples_per_rev=32, **k
        ),
        "order_spectrum": lambda x, **k: order_spectrum(x, FS, rpm, resolution=1.0, **k),
        "order_cuts": lambda x, **k: order_cuts(x, FS, rpm, [3, 7], samples_per_rev=32, **k),
        # 80 Hz bands hold orders 3 and 7 together below 1200 min-1: warned (OrderBandWarning)
        "order_cuts_hz": lambda x, **k: order_cuts(x, FS, rpm, [3, 7], bandwidth_hz=80.0, **k),
        "overall_level": lambda x, **k: overall_level(x, FS, rpm, **k),
        "resample": lambda x, **k: resample_to_angle(x, FS, angle=theta, samples_per_rev=32, **k),
    }


@pytest.mark.parametrize(
    "what",
    [
        "spectrum",
        "frequency_map",
        "frequency_map_angle",
        "order_map",
        "order_map_angle",
        "order_spectrum",
        "order_cuts",
        "order_cuts_hz",
        "overall_level",
        "resample",
    ],
)
@pytest.mark.filterwarnings("ignore::analysis.order_resolution.OrderBandWarning")
def test_multichannel_equals_per_channel(three_channels, what):
    _t, rpm, theta, x = three_channels
    call = _calls(rpm, theta)[what]
    together = call(x, axis=-1)
    assert together.dims == ("channel",)
    assert together.values.shape[0] == 3
    for i in range(3):
        alone = call(x[i])
        np.testing.assert_array_equal(together.values[i], alone.values)
    # a (samples, channels) array: the time axis is found from the reference's length or
    # given; a spectrum has no reference and needs axis=
    if what == "spectrum":
        with pytest.raises(ValueError, match="axis"):
            call(x.T)
        np.testing.assert_array_equal(call(x.T, axis=0).values, together.values)
    else:
        np.testing.assert_array_equal(call(x.T).values, together.values)


def test_dataarray_channels_in_and_out(three_channels):
    t, rpm, _theta, x = three_channels
    da = xr.DataArray(
        x.astype(np.float32),
        dims=("channel", "time"),
        coords={
            "channel": ["ring_x", "ring_y", "carrier_z"],
            "time": ("time", t, {"units": "s"}),
            "shaft_speed": ("time", rpm, {"units": "min-1", "long_name": "shaft speed"}),
        },
        attrs={"units": "m s-2"},
        name="acceleration",
    )
    m = da.transpose("time", "channel").gearvib.order_map(samples_per_rev=32)
    ds = m.to_dataset()
    assert ds["amplitude"].dims == ("channel", "order", "time")  # CF 2.4: time last
    assert list(ds["channel"].values) == ["ring_x", "ring_y", "carrier_z"]
    assert ds.attrs["speed_reference"] == "shaft_speed [min-1]"
    one = rpm_order_map(x[1].astype(np.float32), FS, rpm, samples_per_rev=32)
    np.testing.assert_array_equal(m.select("ring_y").values, one.values)
    with pytest.raises(ValueError, match="ring_q"):
        m.select("ring_q")
    cut = order_cuts_from_map(m, [3, 7])
    assert cut.to_dataset()["level"].dims == ("channel", "order", "time")


# ------------------------------------------------------------ angle reference, from a tacho


def test_angle_input_on_tacho_only_coast_down():
    # Coast-down 1200 -> 300 min-1 in 6 s, orders 3 and 7 with amplitudes proportional to
    # speed, measured with a 60-pulse tacho (finite edges, noise) and nothing else. The level
    # of each order band is compared with the true amplitude at the speed the cut reports.
    fs, dur = 25600.0, 6.0
    t = np.arange(int(fs * dur)) / fs
    n0, n1 = 1200.0, 300.0
    theta = 2 * np.pi / 60 * (n0 * t + 0.5 * (n1 - n0) / dur * t**2)
    gain = (n0 + (n1 - n0) * t / dur) / 1000.0
    x = sum(a * gain * np.sin(o * theta + 0.3 * o) for o, a in AMPS.items())
    noise = 0.02 * np.random.default_rng(1).standard_normal(t.size)
    tacho = 2.5 * (1 + np.tanh(3 * np.sin(60 * theta))) + noise
    ref = from_tacho(tacho, fs, 60)
    raw = from_tacho(tacho, fs, 60, rpm_smoothing=1)  # derivative of the angle, unsmoothed

    def worst_db(**reference):
        cut = order_cuts(x, fs, orders=[3, 7], samples_per_rev=64, resolution=0.5, **reference)
        expected = np.array([a for a in AMPS.values()])[:, None] * cut.rpm / 1000 / np.sqrt(2)
        return float(np.max(np.abs(20 * np.log10(cut.values / expected))))

    exact = worst_db(angle=theta)
    with_angle = worst_db(angle=ref.angle)
    with_rpm = worst_db(rpm=ref.rpm)
    with_raw_rpm = worst_db(rpm=raw.rpm)
    assert exact < 0.002
    assert with_angle < 0.003  # the target: back near 0.002 dB with the angle
    assert with_rpm < 0.004  # the smoothed rpm is as good
    assert with_raw_rpm > 2.5 * with_rpm  # the tooth-to-tooth ripple of the unsmoothed rpm
    # the smoothed rpm has no tooth-to-tooth ripple (0.45 % unsmoothed)
    true_rpm = n0 + (n1 - n0) * t / dur
    inner = slice(2000, -2000)
    assert np.max(np.abs(ref.rpm[inner] / true_rpm[inner] - 1)) < 1e-4
    assert np.max(np.abs(raw.rpm[inner] / true_rpm[inner] - 1)) > 2e-3


# ---------------------------------------------------------------------------- standstill


def test_runup_from_standstill_is_trimmed_and_said_so():
    t, rpm, theta = _runup(duration=3.0, n0=0.0, n1=3000.0)
    x = sum(a * np.sin(o * theta) for o, a in AMPS.items())
    m = rpm_order_map(x, FS, rpm, samples_per_rev=32)
    assert m.notes and "left out" in m.notes[0] and "min_rpm" in m.notes[0]
    assert m.rpm[0] > 0.02 * 3000
    assert "left out" in m.to_dataset().attrs["comment"]
    # the same as the analysis of the moving part alone
    first = int(np.argmax(rpm >= 0.02 * rpm.max()))
    ref = rpm_order_map(x[first:], FS, rpm[first:], samples_per_rev=32, time=t[first:])
    assert not any("left out" in note for note in ref.notes)
    assert m.notes[1:] == ref.notes  # both: the default resolution coarsened (75 revolutions)
    np.testing.assert_array_equal(m.values, ref.values)
    np.testing.assert_allclose(m.time, ref.time, rtol=1e-12)
    # a coast-down to standstill, with the angle: the end is left out
    back = theta[-1] - theta[::-1]
    cut = order_cuts(x[::-1], FS, orders=[3, 7], angle=back, samples_per_rev=32)
    assert "last" in cut.notes[0]
    with pytest.raises(ValueError, match="rpm must be > 0"):  # standstill inside the record
        rpm_order_map(x, FS, np.where((t > 1.0) & (t < 1.1), 0.0, rpm), samples_per_rev=32)
    with pytest.raises(ValueError, match="rpm must be > 0"):  # reverse rotation
        rpm_order_map(x, FS, -rpm, samples_per_rev=32)


# ---------------------------------------------------------------- speed found by attributes


def _run_like(with_angle: bool = True, extra_speed: bool = False) -> xr.Dataset:
    t, rpm, theta = _runup(duration=2.0)
    force = sum(a * np.sin(o * theta) for o, a in AMPS.items())
    coords = {
        "time": ("time", t, {"units": "s", "long_name": "time since start of run"}),
        "input_speed": ("time", rpm, {"units": "min-1", "long_name": "input speed"}),
        "mesh_frequency": ("time", 33 * rpm / 60, {"units": "Hz", "long_name": "mesh frequency"}),
    }
    if with_angle:
        coords["input_angle"] = ("time", theta, {"units": "rad", "long_name": "input angle"})
    if extra_speed:
        coords["output_speed"] = ("time", rpm / 4, {"units": "rpm"})
    return xr.Dataset({"normal_force": ("time", force, {"units": "N"})}, coords=coords)


def test_reference_found_by_attributes():
    ds = _run_like()
    ref = find_reference(ds)
    assert (ref.kind, ref.variable) == ("angle", "input_angle")  # an angle wins
    only_speed = _run_like(with_angle=False)
    assert find_reference(only_speed).variable == "input_speed"  # not the mesh frequency (Hz)
    with pytest.raises(ValueError, match="several speed references"):
        find_reference(_run_like(with_angle=False, extra_speed=True))
    assert find_reference(ds, speed="input_speed").kind == "rpm"
    with pytest.raises(ValueError, match="candidates"):
        find_reference(ds, speed="shaft_speed")
    # the _ds helpers and the accessor use it: same map as with the arrays
    m = rpm_order_map_ds(ds, "normal_force", samples_per_rev=32)
    ref_map = rpm_order_map(
        ds["normal_force"].values, FS, angle=ds["input_angle"].values, samples_per_rev=32
    )
    np.testing.assert_array_equal(m.values, ref_map.values)
    assert m.to_dataset().attrs["speed_reference"] == "input_angle [rad]"
    m2 = ds.gearvib.order_map("normal_force", speed="input_speed", samples_per_rev=32)
    assert m2.reference == "input_speed [min-1]"
    assert ds.gearvib.reference().variable == "input_angle"


def test_accessor_forwards_every_call():
    ds = _run_like()
    acc = ds.gearvib
    x = ds["normal_force"].values
    theta = ds["input_angle"].values
    assert isinstance(analysis.accessor.DatasetAccessor(ds), analysis.accessor.DatasetAccessor)
    np.testing.assert_array_equal(
        acc.spectrum("normal_force", segment_length=256).values,
        spectrum(x, FS, segment_length=256).values,
    )
    np.testing.assert_array_equal(
        acc.frequency_map("normal_force").values, rpm_frequency_map(x, FS, angle=theta).values
    )
    np.testing.assert_array_equal(
        acc.order_cuts("normal_force", [3], samples_per_rev=32).values,
        order_cuts(x, FS, orders=[3], angle=theta, samples_per_rev=32).values,
    )
    np.testing.assert_array_equal(
        acc.order_spectrum("normal_force", resolution=1.0, samples_per_rev=32).values,
        order_spectrum(x, FS, angle=theta, resolution=1.0, samples_per_rev=32).values,
    )
    np.testing.assert_array_equal(
        acc.overall_level("normal_force").values, overall_level(x, FS, angle=theta).values
    )
    da = ds["normal_force"]  # keeps the auxiliary coordinates along time
    np.testing.assert_array_equal(
        da.gearvib.order_map(samples_per_rev=32).values,
        acc.order_map("normal_force", samples_per_rev=32).values,
    )
    assert da.gearvib.order_spectrum(resolution=1.0).amplitude == "rms"
    assert da.gearvib.frequency_map(speed="input_speed").reference == "input_speed [min-1]"
    assert da.gearvib.order_cuts([3]).values.shape[0] == 1
    assert da.gearvib.overall_level().values.ndim == 1
    assert da.gearvib.spectrum().fs == pytest.approx(FS)
    assert da.gearvib.reference().kind == "angle"


# ------------------------------------------------------------------------ one vocabulary


def test_deprecated_names_warn_and_give_the_same_result():
    t, rpm, theta = _runup(duration=2.0)
    x = np.sin(3 * theta)
    with pytest.warns(FutureWarning, match="scaling|psd"):  # the name and the value
        old = spectrum(x, FS, scaling="psd", segment_length=256)
    new = spectrum(x, FS, amplitude="density", segment_length=256)
    np.testing.assert_array_equal(old.values, new.values)
    with pytest.warns(FutureWarning, match="amplitude"):
        assert old.scaling == "psd"
    with pytest.warns(FutureWarning):  # the time axis second, orders_resolution
        old = order_spectrum(x, t, rpm, orders_resolution=0.25)
    assert old.bin_spacing_orders == pytest.approx(0.25, rel=0.02)
    new = order_spectrum(x, FS, rpm, resolution=old.resolution_orders)
    np.testing.assert_allclose(new.values, old.values, rtol=1e-12)
    with pytest.warns(FutureWarning, match="time axis"):
        resample_to_angle(x, t, theta, 32)
    with pytest.raises(ValueError, match="amplitude= only"):
        spectrum(x, FS, amplitude="rms", scaling="rms")


def test_resolution_means_the_bandwidth_everywhere():
    _t, rpm, theta = _runup(duration=2.0)
    x = np.sin(3 * theta)
    enbw = window_info("hann", 4096).enbw_bins
    s = spectrum(x, FS, resolution=8.0)
    m = rpm_frequency_map(x, FS, rpm, resolution=8.0)
    assert s.segment_length == m.segment_length == round(enbw * FS / 8.0)
    assert s.resolution_hz == pytest.approx(m.resolution_hz)
    om = rpm_order_map(x, FS, rpm, resolution=0.5, samples_per_rev=32)
    osp = order_spectrum(x, FS, rpm, resolution=0.5, samples_per_rev=32)
    cut = order_cuts(x, FS, rpm, [3], resolution=0.5, samples_per_rev=32)
    assert om.segment_length == osp.segment_length == cut.segment_length
    assert om.resolution_orders == pytest.approx(osp.resolution_orders)
    assert cut.resolution == pytest.approx(om.resolution_orders)
    assert (cut.samples_per_rev, cut.resolution_units) == (32, "1")
    attrs = cut.to_dataset().attrs
    assert attrs["segment_length"] == om.segment_length and attrs["samples_per_rev"] == 32
    hz = order_cuts(x, FS, rpm, [3], bandwidth_hz=60.0, resolution=8.0)
    assert (hz.resolution, hz.resolution_units, hz.samples_per_rev) == (
        pytest.approx(m.resolution_hz),
        "Hz",
        0,
    )
    # defaults: rms everywhere
    assert spectrum(x, FS).amplitude == m.amplitude == osp.amplitude == cut.amplitude == "rms"


# ------------------------------------------------------------------------------- windows


@pytest.mark.parametrize(
    "window", ["triang", "nuttall", "blackman", ("tukey", 0.25), ("chebwin", 100), ("dpss", 3)]
)
def test_every_scipy_window_name(window):
    w = get_window(window, 512)
    np.testing.assert_allclose(w, scipy.signal.get_window(window, 512, fftbins=True))
    # a sine on a line reads its rms in every window (coherent gain from the samples), up to
    # the leakage of its negative-frequency image through the sidelobes (windows with no
    # nulls at whole lines: chebwin -100 dB, dpss)
    n = 4096
    x = 2.0 * np.sin(2 * np.pi * 64 * np.arange(n) / n)
    s = spectrum(x, float(n), window=window)
    assert s.values[64] == pytest.approx(2.0 / np.sqrt(2), rel=1e-4)
    assert s.window.startswith(window if isinstance(window, str) else window[0])
    assert 0.5 < main_lobe_half_width(window) < 8
    t, rpm, _ = _runup(duration=1.0)
    assert rpm_frequency_map(np.sin(t), FS, rpm, window=window).values.shape[1] > 1


def test_bad_windows_give_short_errors():
    for bad, match in [
        (np.ones(4096), "array of shape"),
        ("hanning", "unknown name"),
        ("gaussian", "needs parameters"),
        (("hann", 2.0), "takes no parameter"),
        (3.0, "not admissible"),
    ]:
        with pytest.raises(ValueError, match=match) as err:
            spectrum(np.ones(4096), FS, window=bad)
        assert len(str(err.value)) < 300 and "1., 1." not in str(err.value)


# ------------------------------------------------------------------------------- plots


def test_plots_draw_into_given_axes(three_channels, tmp_path):
    _t, rpm, _theta, x = three_channels
    fig = Figure(figsize=(10, 8), layout="constrained")
    axes = fig.subplots(2, 2)
    m = rpm_frequency_map(x, FS, rpm, axis=-1)
    with pytest.raises(ValueError, match="channel="):
        m.plot()
    assert m.plot(channel=1, ax=axes[0, 0], hz_per_rpm=1 / 60, orders=(3, 7)) is fig
    cut = order_cuts(x, FS, rpm, [3, 7], samples_per_rev=32, axis=-1)
    assert cut.plot(ax=axes[0, 1]) is fig
    assert len(axes[0, 1].lines) == 6  # 3 channels x 2 orders
    osp = order_spectrum(x, FS, rpm, resolution=1.0, axis=-1)
    assert osp.plot(ax=axes[1, 0]) is fig
    assert spectrum(x, FS, axis=-1, segment_length=512).plot(ax=axes[1, 1]) is fig
    assert axes[0, 0].get_ylabel() and axes[1, 1].get_xlabel()
    fig.savefig(tmp_path / "grid.png", dpi=40)
    with pytest.raises(ValueError, match="Axes"):
        cut.plot(ax="not axes")
