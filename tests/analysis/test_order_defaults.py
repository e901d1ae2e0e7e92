"""Defaults of order analysis that resolve the orders asked for (issue 29).

Synthetic run-ups whose true order levels are known per rpm: neighbouring orders 0.5 to 2
orders apart, one order crossing a damped resonance (its level and phase those of a
single-degree-of-freedom system, ``|H(k f_shaft)|``), white noise, and the speed given as an
rpm array or measured by a 60-pulse tacho. The default order spectrum and order cuts must be
within 0.2 dB of the truth; the same calls with the previous defaults (passed explicitly) are
several dB off, which is why the defaults changed.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from analysis.maps import rpm_frequency_map, rpm_order_map
from analysis.order_resolution import (
    MIN_FRAMES,
    OrderBandWarning,
    default_frequency_resolution,
    default_order_resolution,
    named_lines,
    requested_orders,
)
from analysis.orders import order_cuts, order_cuts_from_map, order_spectrum
from analysis.spectrum import spectrum
from analysis.speed import from_tacho
from analysis.windows import window_info

FS = 16384.0
T = 16.0
N0, N1 = 600.0, 3600.0  # min-1: 540 revolutions
# peak amplitudes; order 4.5 is multiplied by |H| of a resonance at FN (critical 2000 min-1)
ORDERS = {1.0: 1.0, 1.5: 0.5, 3.5: 0.8, 4.5: 0.6, 6.5: 0.4}
RESONANT = 4.5
FN, ZETA = 150.0, 0.04
NOISE = 0.05  # rms of white noise over fs/2
FLATTOP_ENBW = window_info("flattop", 4096).enbw_bins


def _h(f):
    return 1.0 / (1.0 - (f / FN) ** 2 + 2j * ZETA * f / FN)


def _true_peak(order: float, rpm) -> np.ndarray:
    """True peak amplitude of an order at a speed (analytic)."""
    r = np.asarray(rpm, dtype=float)
    a = ORDERS[order]
    return a * np.abs(_h(order * r / 60.0)) if order == RESONANT else np.full(r.shape, a)


@pytest.fixture(scope="module")
def runup():
    t = np.arange(int(FS * T)) / FS
    rpm = N0 + (N1 - N0) * t / T
    theta = 2 * np.pi / 60 * (N0 * t + 0.5 * (N1 - N0) / T * t**2)
    x = np.zeros_like(t)
    for o, a in ORDERS.items():
        if o == RESONANT:
            h = _h(o * rpm / 60.0)
            x += a * np.abs(h) * np.sin(o * theta + np.angle(h))
        else:
            x += a * np.sin(o * theta + 0.3 * o)
    x += NOISE * np.random.default_rng(29).standard_normal(t.size)
    # a variable-reluctance pickup on a 60-tooth wheel
    tacho = from_tacho(np.sin(60 * theta), FS, 60)
    refs = {"rpm": {"rpm": rpm}, "tacho_angle": {"angle": tacho.angle},
            "tacho_rpm": {"rpm": tacho.rpm}}  # fmt: skip
    return t, rpm, theta, x, refs


def _compared_frames(cut, t, theta, rpm) -> np.ndarray:
    """Frames compared with the truth: all but those whose span (+- half a frame) overlaps
    the half-power band of the resonance crossing, ``2000 (1 +- zeta)`` min-1, where the
    level of order 4.5 changes by up to 8 dB within one frame."""
    half = 0.5 * cut.segment_length / cut.samples_per_rev * 2 * np.pi
    centre = np.interp(cut.time, t, theta)
    lo = np.interp(centre - half, theta, rpm)
    hi = np.interp(centre + half, theta, rpm)
    crit = 60.0 * FN / RESONANT
    return (hi < crit * (1 - ZETA)) | (lo > crit * (1 + ZETA))


def _cut_errors_db(cut) -> np.ndarray:
    truth = np.array([_true_peak(o, cut.rpm) / np.sqrt(2) for o in cut.orders])
    return 20 * np.log10(cut.values / truth)


@pytest.mark.parametrize("reference", ["rpm", "tacho_angle", "tacho_rpm"])
def test_default_cuts_within_0_2_db_and_old_defaults_fail(runup, reference):
    t, rpm, theta, x, refs = runup
    ref = refs[reference]
    with warnings.catch_warnings():
        warnings.simplefilter("error", OrderBandWarning)  # the default bands never overlap
        cut = order_cuts(x, FS, orders=list(ORDERS), **ref)
    # d_min = 0.5 (orders 1 and 1.5): 1/8 order, flat-top frames of 30 revolutions
    assert cut.resolution == pytest.approx(0.125, rel=0.01)
    assert cut.bandwidth == pytest.approx(2.67 * 0.125, rel=0.02)  # the main lobe
    assert cut.notes == ()
    ds = cut.to_dataset()
    assert ds.attrs["resolution"] == cut.resolution and ds.attrs["bandwidth"] == cut.bandwidth
    err = _cut_errors_db(cut)
    sel = _compared_frames(cut, t, theta, rpm)
    assert sel.sum() >= cut.time.size - 4 and sel.sum() > 25
    assert np.max(np.abs(err[:, sel])) < 0.2
    # even across the crossing of the resonance (8 dB per frame) within 0.3 dB here
    assert np.max(np.abs(err)) < 0.3
    # the previous defaults, passed explicitly: resolution samples_per_rev / 256 orders at
    # the sampling of fs at the top speed (1.07 orders: the main lobes of orders 1 and 1.5,
    # 3.5 and 4.5 overlap) -> several dB off, and the overlap is warned about
    spr_old = 2 * int(np.ceil(FS / 2 / (N1 / 60)))
    with pytest.warns(OrderBandWarning, match=r"band of order 1 .* reaches order 1\.5"):
        old = order_cuts(x, FS, orders=list(ORDERS), resolution=spr_old / 256,
                         samples_per_rev=spr_old, **ref)  # fmt: skip
    assert old.resolution == pytest.approx(spr_old / 256, rel=0.01)
    old_err = np.abs(_cut_errors_db(old))
    assert np.nanmax(old_err) > 5.0
    assert np.all(np.nanmax(old_err, axis=1) > 1.0)  # every order, not one


@pytest.mark.parametrize("reference", ["rpm", "tacho_angle"])
def test_default_order_spectrum_within_0_2_db(runup, reference):
    _t, rpm, theta, x, refs = runup
    ords = list(ORDERS)
    osp = order_spectrum(x, FS, orders=ords, **refs[reference])
    assert osp.resolution_orders == pytest.approx(0.125, rel=0.01)
    # truth: the rms over the run, per revolution (the segments tile the angle uniformly)
    rev = np.linspace(theta[0], theta[-1], 20001)
    r_rev = np.interp(rev, theta, rpm)
    truth = np.array([np.sqrt(np.mean(_true_peak(o, r_rev) ** 2) / 2) for o in ords])
    pk = osp.peaks(threshold=0.1)
    assert pk.axis == "order"
    np.testing.assert_allclose(pk.order, ords, atol=0.01)
    assert np.max(np.abs(20 * np.log10(pk.amplitude / truth))) < 0.2
    # previous default resolution: orders 1 and 1.5 merge (+6 dB on order 1.5)
    spr_old = 2 * int(np.ceil(FS / 2 / (N1 / 60)))
    old = order_spectrum(x, FS, resolution=spr_old / 256, samples_per_rev=spr_old,
                         **refs[reference])  # fmt: skip
    k = [int(np.argmin(np.abs(old.order - o))) for o in ords]
    assert np.max(np.abs(20 * np.log10(old.values[k] / truth))) > 3.0


def test_resolution_follows_requested_orders_and_max_order():
    assert default_order_resolution(None, None) == 0.25
    assert default_order_resolution(np.array([24.0, 48.0]), None) == 0.25
    assert default_order_resolution(np.array([1.0, 1.5]), None) == 0.125  # 4 per 0.5 order
    assert default_order_resolution(np.array([0.4, 3.0]), None) == 0.1  # 0.4 from order 0
    assert default_order_resolution(np.array([23.0, 24.0, 25.0]), 30.0) == 0.25
    assert default_order_resolution(None, 4.0) == 4.0 / 64  # at least 64 resolutions on axis
    with pytest.raises(TypeError, match="orders"):
        requested_orders("24")
    with pytest.raises(TypeError, match="orders"):
        requested_orders(True)
    with pytest.raises(ValueError, match="orders"):
        requested_orders([1.0, -2.0])
    with pytest.raises(ValueError, match="orders"):
        requested_orders([1.0, np.nan])


def test_short_record_coarsens_the_default_and_says_so(runup):
    t, rpm, _theta, x, _refs = runup
    n = int(4.0 * FS)  # 4 s from 600 min-1: about 55 revolutions
    revs = float(np.trapezoid(rpm[:n], t[:n]) / 60.0)
    m = rpm_order_map(x[:n], FS, rpm[:n], orders=[1.0, 1.5])
    floor = FLATTOP_ENBW * MIN_FRAMES / revs
    assert m.resolution_orders == pytest.approx(floor, rel=0.02)
    assert any("order resolution" in note and "1/16" in note for note in m.notes)
    assert "1/16" in m.to_dataset().attrs["comment"]
    # a given resolution is used as it is, without a note
    fine = rpm_order_map(x[:n], FS, rpm[:n], resolution=0.5)
    assert fine.notes == ()


def test_order_axis_ends_at_max_order(runup):
    _t, rpm, _theta, x, _refs = runup
    osp = order_spectrum(x, FS, rpm, max_order=30.0)
    assert osp.max_order == 30.0
    assert osp.order[-1] <= 30.0 < osp.order[-1] + osp.bin_spacing_orders
    assert osp.samples_per_rev == 2 * int(np.ceil(1.28 * 30.0))  # 78, not fs at top speed
    m = rpm_order_map(x, FS, rpm, max_order=12.0)
    assert m.order[-1] <= 12.0 < m.order[-1] + m.bin_spacing_orders
    assert m.values.shape[-1] == m.order.size
    assert m.to_dataset()["order"].values[-1] <= 12.0
    # default max_order: samples_per_rev / 2.56 at about fs at the top speed
    d = order_spectrum(x, FS, rpm)
    assert d.order[-1] <= d.max_order == pytest.approx(d.samples_per_rev / 2.56)
    # order cuts: max_order 1.25 (highest order + band/2); a band beyond it reads NaN
    cut = order_cuts(x, FS, rpm, [6.5])  # band 0.66: max_order 1.25 (6.5 + 0.33) = 8.54
    assert cut.samples_per_rev == 22  # 2 ceil(1.28 * 8.54)
    assert cut.bandwidth == pytest.approx(0.663, abs=0.005)
    beyond = order_cuts(x, FS, rpm, [3.5, 11.9], max_order=12.0)
    assert np.all(np.isnan(beyond.values[1])) and np.all(np.isfinite(beyond.values[0]))
    # max_order above what fs reaches at the top speed is refused, not aliased
    with pytest.raises(ValueError, match="max_order"):
        order_spectrum(x, FS, rpm, max_order=200.0)


def test_peaks_on_an_order_axis_are_named_order(runup):
    _t, rpm, _theta, x, _refs = runup
    pk = order_spectrum(x, FS, rpm, max_order=8.0).peaks(max_peaks=5)
    assert pk.axis == "order"
    np.testing.assert_allclose(pk.order, list(ORDERS), atol=0.01)
    np.testing.assert_array_equal(pk.bin_order, pk.bin_frequency)
    ds = pk.to_dataset()
    assert "order" in ds and "bin_order" in ds and "frequency" not in ds
    assert ds["order"].attrs["units"] == "1" and ds["bin_order"].attrs["units"] == "1"
    assert pk.labels()[0].startswith("order 1.00")
    # a spectrum in Hz keeps frequency, and has no order
    hz = spectrum(x[: 1 << 14], FS, segment_length=4096).peaks(max_peaks=2)
    assert hz.axis == "frequency" and "frequency" in hz.to_dataset()
    with pytest.raises(AttributeError, match="frequency axis"):
        _ = hz.order


def test_overlapping_bands_warn_with_names_and_orders(runup):
    _t, rpm, _theta, x, _refs = runup
    lines = {"1x shaft": 1.0, "sideband 1x+0.05": 1.05, "mesh": 3.5}
    # a requested order and a catalogue line inside the band of order 1
    with pytest.raises(OrderBandWarning) as info, warnings.catch_warnings():
        warnings.simplefilter("error", OrderBandWarning)
        order_cuts(x, FS, rpm, [1.0, 1.2, 3.5], lines=lines)
    msg = str(info.value)
    assert "band of order 1 (1x shaft)" in msg and "reaches order 1.2" in msg
    assert "line 'sideband 1x+0.05' at order 1.05" in msg
    assert "mesh" not in msg  # order 3.5 is alone in its band: named, not warned about
    # the same from a computed map, and for bands fixed in Hz (widest at the slowest frame)
    m = rpm_order_map(x, FS, rpm, max_order=8.0)
    with pytest.warns(OrderBandWarning, match=r"reaches order 1\.5"):
        order_cuts_from_map(m, [1.0, 1.5], bandwidth=1.2)
    with pytest.warns(OrderBandWarning, match=r"at 6\d\d(\.\d+)? min-1"):
        order_cuts(x, FS, rpm, [3.5, 4.5], bandwidth_hz=16.0)
    # bands apart: silent
    with warnings.catch_warnings():
        warnings.simplefilter("error", OrderBandWarning)
        order_cuts_from_map(m, [1.0, 1.5, 3.5], lines={"1x shaft": 1.0, "mesh": 3.5})
    # bad lines
    with pytest.raises(TypeError, match="lines"):
        named_lines([("a", 1.0), 2.0])
    with pytest.raises(ValueError, match="'a'"):
        named_lines({"a": -1.0})
    with pytest.raises(TypeError, match="'a'"):
        named_lines({"a": True})


def test_frequency_map_default_resolution_is_stated(runup):
    _t, rpm, _theta, x, refs = runup
    m = rpm_frequency_map(x, FS, rpm)
    # 600 -> 3600 min-1 in 16 s: f_min / 4 = 2.5 Hz; sweep sqrt(1.5 * 50 Hz / 16 s) = 2.17 Hz;
    # frames of at most 1/16 of the record: >= 1.5 Hz
    enbw = window_info("hann", 4096).enbw_bins
    expected = max(10.0 / 4, np.sqrt(enbw * 50.0 / T), enbw * 16 / T)
    assert expected == pytest.approx(2.5)
    assert m.resolution_hz == pytest.approx(expected, rel=0.01)
    assert default_frequency_resolution(10.0, 60.0, T, enbw) == pytest.approx(expected)
    # from the tacho angle, the speed is averaged over 1/100 of the record (0.16 s, in which
    # the speed rises by 30 min-1 from 600): the slowest is 615 min-1, 2.5 % higher
    ma = rpm_frequency_map(x, FS, angle=refs["tacho_angle"]["angle"])
    assert ma.resolution_hz == pytest.approx(expected * 615 / 600, rel=0.005)
    # a fast sweep: limited by the sweep; a constant speed: by the record length
    assert default_frequency_resolution(10.0, 60.0, 8.0, enbw) == pytest.approx(np.sqrt(9.375))
    assert default_frequency_resolution(25.0, 25.0, 10.0, enbw) == pytest.approx(6.25)
    assert default_frequency_resolution(0.5, 0.5, 10.0, enbw) == pytest.approx(2.4)
    # MATLAB's default is one argument away
    assert rpm_frequency_map(x, FS, rpm, resolution=FS / 128).segment_length == 192
    with pytest.raises(TypeError, match="resolution"):
        rpm_frequency_map(x, FS, rpm, resolution="2")
    with pytest.raises(TypeError, match="resolution"):
        rpm_order_map(x, FS, rpm, resolution=True)


# ------------------------------------------------------------------ issue 29, as reported


def _issue29_case():
    """The user's recording: 20 s at 51.2 kHz, a run-up (600 -> 3000 min-1 here) with orders
    1, 2.5 and 24 (rms 0.707, 0.354, 1.414) and a 60-pulse square-wave tacho."""
    fs, dur = 51200.0, 20.0
    t = np.arange(int(fs * dur)) / fs
    phi = 2 * np.pi * (600.0 / 60 * t + 0.5 * (3000.0 - 600.0) / 60 / dur * t**2)
    x = np.sin(phi) + 0.5 * np.sin(2.5 * phi) + 2.0 * np.sin(24 * phi)
    tacho = 5.0 * (np.sin(60 * phi) > 0)
    return fs, x, from_tacho(tacho, fs, 60).angle


def test_issue29_users_case_is_right_with_the_defaults():
    fs, x, angle = _issue29_case()
    rms = np.array([1.0, 0.5, 2.0]) / np.sqrt(2)
    osp = order_spectrum(x, fs, angle=angle, max_order=30)
    # was 0.903 / 0.779 / 1.414 (samples_per_rev / 256 = 3.93 orders)
    assert osp.resolution_orders == pytest.approx(0.25, rel=0.01)
    pk = osp.peaks(max_peaks=3)
    np.testing.assert_allclose(pk.order, [1.0, 2.5, 24.0], atol=1e-3)
    np.testing.assert_allclose(pk.amplitude, rms, rtol=2e-3)
    assert "order" in pk.to_dataset()  # was a variable named frequency
    assert pk.order[np.argmax(pk.amplitude)] == pytest.approx(24.0, abs=1e-3)  # was 0.52
    assert osp.order[-1] <= 30.0  # was 502 orders
    # order cuts: within 0.2 dB (they swung between 0.2 and 1.25 on top of each other)
    with warnings.catch_warnings():
        warnings.simplefilter("error", OrderBandWarning)
        cut = order_cuts(x, fs, orders=[1, 2.5, 24], angle=angle, max_order=30)
    assert cut.bandwidth < 0.7  # was 10.4 orders
    err = 20 * np.log10(cut.values / rms[:, None])
    assert np.max(np.abs(err)) < 0.2
    # the previous defaults, passed explicitly, give the reported numbers
    with pytest.warns(OrderBandWarning, match=r"order 1 .* reaches order 2\.5"):
        old = order_cuts(x, fs, orders=[1, 2.5, 24], angle=angle, resolution=1006 / 256,
                         samples_per_rev=1006)  # fmt: skip
    assert old.bandwidth == pytest.approx(10.4, abs=0.1)
    assert np.nanmax(np.abs(20 * np.log10(old.values[:2] / rms[:2, None]))) > 5.0
