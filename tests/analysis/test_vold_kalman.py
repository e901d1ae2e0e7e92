"""Tests of analysis.vold_kalman: Vold-Kalman order tracking (issue 29).

Truths are analytic (signals built from known envelopes and carrier phases) or computed
independently in the test: a dense least-squares solve of the defining problem, the filter's
frequency response from its formula, a Hann-window demodulator, a normal-equations solve.
"""

from __future__ import annotations

import tracemalloc

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
import scipy.linalg
import scipy.special
import xarray as xr
from matplotlib.figure import Figure

from analysis.threads import one_blas_thread
from analysis.vold_kalman import (
    MAX_WEIGHT,
    bandwidth_to_weight,
    order_waveform,
    remove_orders,
    weight_to_bandwidth,
)

FS = 1024.0
T = 4.0
B = 4.0  # bandwidth of the run-up tests [Hz]


def _db(a, b):
    return 20 * np.log10(np.abs(a) / np.abs(b))


def _deg(a, b):
    return np.degrees(np.abs(np.angle(a / b)))


@pytest.fixture(scope="module")
def runup():
    """Shaft A runs up 10 -> 60 Hz in 4 s; shaft B turns at 70 Hz. Orders 1 and 2 of A and
    order 1 of B; order 2 of A crosses order 1 of B at t = 2 s (35 Hz shaft speed), at
    25 Hz/s. White noise of 0.1 rms."""
    n = int(FS * T)
    t = np.arange(n) / FS
    th_a = 2 * np.pi * (10 * t + 6.25 * t**2)
    th_b = 2 * np.pi * 70.0 * t
    rpm = np.stack([60 * (10 + 12.5 * t), np.full(n, 4200.0)])
    truth = np.stack(
        [
            0.8 * np.exp(1j * np.radians(20)) * np.ones(n),
            (1 + 0.5 * np.sin(np.pi * t / T)) * np.exp(1j * np.radians(30 + 20 * t / T)),
            0.7 * np.exp(-1j * np.radians(60)) * np.ones(n),
        ]
    )
    carriers = np.stack([th_a, 2 * th_a, th_b])
    parts = (truth * np.exp(1j * carriers)).real
    x = parts.sum(axis=0) + 0.1 * np.random.default_rng(0).standard_normal(n)
    return {"t": t, "x": x, "rpm": rpm, "truth": truth, "carriers": carriers, "parts": parts}


def _extract(d, **kw):
    kw.setdefault("bandwidth", B)
    return order_waveform(d["x"], FS, orders=[1, 2, 1], shafts=[0, 0, 1], rpm=d["rpm"], **kw)


# ---------------------------------------------------------------- run-up with crossing orders


def test_joint_solution_within_half_db_and_5_degrees_also_at_the_crossing(runup):
    res = _extract(runup)
    db = np.abs(_db(res.envelope, runup["truth"]))
    deg = _deg(res.envelope, runup["truth"])
    gap = np.abs(res.frequency[1] - res.frequency[2])
    away = gap >= 2 * B
    assert away.mean() > 0.8
    # away from the crossing: the requirement
    assert db[:, away].max() < 0.5
    assert deg[:, away].max() < 5.0
    # at the crossing (|f_2A - f_1B| < 2 B): the joint solution needs no exclusion zone here
    assert db[:, ~away].max() < 0.5
    assert deg[:, ~away].max() < 5.0
    np.testing.assert_allclose(res.frequency[1], 2 * runup["rpm"][0] / 60)


def test_separate_filters_beat_at_the_crossing_where_the_joint_one_does_not(runup):
    joint = _extract(runup)
    sep = _extract(runup, joint=False)
    gap = np.abs(sep.frequency[1] - sep.frequency[2])
    t = runup["t"]
    inside = gap < B
    # each single-order filter passes the other order inside its band: beats of several dB
    assert np.abs(_db(sep.envelope[1:, inside], runup["truth"][1:, inside])).max() > 3.0
    assert np.abs(_db(joint.envelope[1:, inside], runup["truth"][1:, inside])).max() < 0.5
    # outside the exclusion zone of a single-order filter (|gap| >= 3 B, 1/B from the ends)
    ok = (gap >= 3 * B) & (t > 1 / B) & (t < T - 1 / B)
    assert np.abs(_db(sep.envelope[:, ok], runup["truth"][:, ok])).max() < 0.5
    assert _deg(sep.envelope[:, ok], runup["truth"][:, ok]).max() < 5.0


def _demodulate(x, carrier, seconds=0.5):
    """Independent amplitude estimate: 2 x e^{-i carrier} averaged with a Hann window."""
    w = np.hanning(int(seconds * FS))
    w /= w.sum()
    return np.convolve(2 * x * np.exp(-1j * carrier), w, mode="same")


def test_remove_orders_leaves_the_other_orders_unchanged(runup):
    rem = remove_orders(
        runup["x"], FS, orders=[1, 2, 1], shafts=[0, 0, 1], rpm=runup["rpm"], bandwidth=B,
        remove=[1],
    )  # fmt: skip
    t = runup["t"]
    inner = (t > 0.3) & (t < T - 0.3)
    without = runup["x"] - runup["parts"][1]  # the signal as if order 2 were absent
    for k in (0, 2):
        kept = _demodulate(rem.signal, runup["carriers"][k])
        ref = _demodulate(without, runup["carriers"][k])
        assert np.abs(_db(kept[inner], ref[inner])).max() < 0.5
    # the removed order is gone: what is left of it (the cleaned signal minus the signal
    # without the order) is 30 dB below it, the crossing included
    left = np.abs(_demodulate(rem.signal - without, runup["carriers"][1]))
    assert (left[inner] / np.abs(runup["truth"][1][inner])).max() < 10 ** (-30 / 20)
    # residual: every tracked order removed, the noise remains (0.1 rms)
    assert np.std(rem.residual[inner]) == pytest.approx(0.1, rel=0.1)
    np.testing.assert_allclose(
        rem.signal, runup["x"] - rem.extraction.waveform[1], rtol=0, atol=1e-12
    )
    assert rem.removed == (1,)


def test_waveform_is_the_real_part_of_envelope_times_carrier(runup):
    res = _extract(runup)
    rebuilt = (res.envelope * np.exp(1j * res.orders[:, None] * res.angle[res.shafts])).real
    np.testing.assert_allclose(res.waveform, rebuilt, atol=1e-12)
    np.testing.assert_allclose(res.residual + res.waveform.sum(axis=0), runup["x"], atol=1e-12)
    # peak convention: an order of amplitude A has |envelope| = A (no factor 2)
    assert np.median(res.amplitude[2]) == pytest.approx(0.7, rel=0.01)


# ------------------------------------------------------------------- accuracy and numerics


@pytest.mark.parametrize("filter_order", [1, 2])
@pytest.mark.parametrize("bandwidth", [0.5, 5.0, 50.0])
def test_stationary_sine_recovered_to_the_record_ends(filter_order, bandwidth):
    fs, n = 2000.0, 8000
    t = np.arange(n) / fs
    th = 2 * np.pi * (80 * t + 10 * t**2)
    x = 1.3 * np.cos(th + 0.7)
    res = order_waveform(x, fs, orders=1, angle=th, bandwidth=bandwidth, filter_order=filter_order)
    err = np.abs(res.envelope - 1.3 * np.exp(0.7j)) / 1.3
    assert err.max() < 1e-6  # everywhere, the ends included (the brief asks 1e-3)


@pytest.mark.parametrize("filter_order", [1, 2])
def test_narrowest_admissible_bandwidth_at_25k6(filter_order):
    fs = 25600.0
    n = int(2 * fs)
    t = np.arange(n) / fs
    x = 1.3 * np.cos(2 * np.pi * (30 * t + 5 * t**2) + 0.7)
    bw = float(weight_to_bandwidth(MAX_WEIGHT, fs, filter_order)) * 1.001
    res = order_waveform(
        x, fs, orders=1, rpm=60 * (30 + 10 * t), bandwidth=bw, filter_order=filter_order
    )
    assert res.weight[0] <= MAX_WEIGHT
    assert np.abs(res.envelope - 1.3 * np.exp(0.7j)).max() / 1.3 < 1e-4


def _normal_equations(y, r, p):
    """Envelope of one order from the normal equations (I + r^2 D^T D) c = y, as the
    published implementations solve them (banded Cholesky)."""
    n = y.size
    coef = np.array([(-1) ** (p - i) * scipy.special.comb(p, i) for i in range(p + 1)])
    ab = np.zeros((p + 1, n))
    for lag in range(p + 1):
        for a in range(p + 1 - lag):
            ab[lag, a : a + n - p] += r**2 * coef[a] * coef[a + lag]
    ab[0] += 1.0
    return 2 * scipy.linalg.solveh_banded(ab, y, lower=True)


def test_normal_equations_fail_where_the_givens_solution_holds():
    fs = 25600.0
    n = int(4 * fs)
    t = np.arange(n) / fs
    th = 2 * np.pi * (30 * t + 2 * t**2)
    x = 1.3 * np.cos(th + 0.7)
    bw = 1.0  # Hz: r^2 = 1.8e15 with filter_order=1
    r = float(bandwidth_to_weight(bw, fs, 1))
    ours = order_waveform(x, fs, orders=1, angle=th, bandwidth=bw).envelope[0]
    assert np.abs(ours - 1.3 * np.exp(0.7j)).max() / 1.3 < 1e-6
    try:
        normal = _normal_equations(x * np.exp(-1j * th), r, 2)
        err = np.abs(normal - 1.3 * np.exp(0.7j)).max() / 1.3
    except np.linalg.LinAlgError:
        err = np.inf
    assert err > 0.1  # the data term 1 is lost beside 6 r^2 = 1e16 on the diagonal


def _stacked(angle, orders, shafts, rows, p, n):
    """The defining least-squares matrix: data rows [cos, -sin] per order and sample, then
    structural rows (r_k / sqrt 2) * p-th difference of u_k and of v_k. Columns: u_0..u_{m-1}
    (each n samples), then v_0..v_{m-1}."""
    m = len(orders)
    coef = np.array([(-1) ** (p - i) * scipy.special.comb(p, i) for i in range(p + 1)])
    a = np.zeros((n + 2 * m * (n - p), 2 * m * n))
    for k in range(m):
        th = orders[k] * angle[shafts[k]]
        a[np.arange(n), k * n + np.arange(n)] = np.cos(th)
        a[np.arange(n), (m + k) * n + np.arange(n)] = -np.sin(th)
    row = n
    for j in range(2 * m):
        for i in range(n - p):
            a[row, j * n + i : j * n + i + p + 1] = rows[j % m] * coef
            row += 1
    return a


@pytest.mark.parametrize("filter_order", [1, 2])
def test_banded_solve_matches_a_dense_least_squares_solve(filter_order):
    fs, n = 500.0, 160
    t = np.arange(n) / fs
    angle = np.stack([2 * np.pi * (20 * t + 40 * t**2), 2 * np.pi * 47 * t])
    orders, shafts = [1.0, 2.0, 1.0], [0, 0, 1]
    rng = np.random.default_rng(3)
    x = rng.standard_normal((2, n))
    bw = [20.0, 15.0, 25.0]
    p = filter_order + 1
    for joint in (True, False):
        res = order_waveform(
            x, fs, orders=orders, shafts=shafts, angle=angle, bandwidth=bw,
            filter_order=filter_order, joint=joint,
        )  # fmt: skip
        rows = bandwidth_to_weight(bw, fs, filter_order) / np.sqrt(2)
        groups = [[0, 1, 2]] if joint else [[0], [1], [2]]
        for g in groups:
            a = _stacked(angle, [orders[k] for k in g], [shafts[k] for k in g], rows[g], p, n)
            b = np.zeros((a.shape[0], 2))
            b[:n] = x.T
            with one_blas_thread():  # a loaded machine's threaded BLAS thrashes
                z = np.linalg.lstsq(a, b, rcond=None)[0]
            m = len(g)
            dense = (z[: m * n] + 1j * z[m * n :]).T.reshape(2, m, n)
            got = res.envelope[:, g, :]
            assert np.abs(got - dense).max() <= 1e-9 * np.abs(dense).max()


def test_blocked_solve_is_identical_to_one_pass(runup):
    one = _extract(runup)
    assert not one.notes
    blocked = _extract(runup, max_memory=1.2e6)
    assert any("blocks" in note for note in blocked.notes)
    np.testing.assert_array_equal(blocked.envelope, one.envelope)


def _peak(fn):
    tracemalloc.start()
    tracemalloc.reset_peak()
    fn()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak


def test_memory_is_linear_in_the_record_and_bounded_by_max_memory():
    fs = 2048.0

    def run(n, **kw):
        t = np.arange(n) / fs
        x = np.cos(2 * np.pi * (20 * t + t**2))
        rpm = 60 * (20 + 2 * t)
        return lambda: order_waveform(x, fs, orders=[1, 2, 3], rpm=rpm, bandwidth=2.0, **kw)

    small, large = _peak(run(20000)), _peak(run(40000))
    assert 1.8 < large / small < 2.2
    # 3 joint orders: 6 unknowns per sample, a band of 13 -> 8 * 6 * 14 bytes per sample
    assert small < 1.5 * 20000 * (8 * 6 * 14 + 8 * 20)
    bound = 12e6
    assert _peak(run(40000, max_memory=bound)) < bound


def test_memory_is_refused_before_allocating():
    n = 300_000_000  # 2.4 GB as float64; zero-stride views cost nothing
    x = np.broadcast_to(np.float64(0.5), (n,))
    rpm = np.broadcast_to(np.float64(600.0), (n,))
    with pytest.raises(ValueError, match="max_memory"):
        order_waveform(x, 1000.0, orders=[1, 2], rpm=rpm, bandwidth=1.0)


# ------------------------------------------------------------------ bandwidth and response


def _stepped_sine_bandwidth(bandwidth, filter_order, fs=1000.0, carrier=100.0):
    """-3 dB width measured with a sine stepped in frequency around the carrier."""
    n = int(fs * max(20.0, 40.0 / bandwidth))
    t = np.arange(n) / fs
    rpm = np.full(n, 60 * carrier)
    offsets = np.linspace(0.3, 0.7, 9) * bandwidth
    gain = []
    for df in offsets:
        res = order_waveform(
            np.cos(2 * np.pi * (carrier + df) * t), fs, orders=1, rpm=rpm,
            bandwidth=bandwidth, filter_order=filter_order,
        )  # fmt: skip
        gain.append(np.mean(res.amplitude[0, n // 4 : 3 * n // 4]))
    level = 20 * np.log10(gain) + 10 * np.log10(2)  # 0 at half power
    i = int(np.flatnonzero(np.diff(np.sign(level)))[0])
    cut = offsets[i] - level[i] * (offsets[i + 1] - offsets[i]) / (level[i + 1] - level[i])
    return 2 * cut


@pytest.mark.parametrize("filter_order", [1, 2])
@pytest.mark.parametrize("bandwidth", [2.0, 10.0])
def test_measured_bandwidth_is_the_requested_one(filter_order, bandwidth):
    measured = _stepped_sine_bandwidth(bandwidth, filter_order)
    assert measured == pytest.approx(bandwidth, rel=1e-3)


def test_bandwidth_weight_relation_agrees_with_the_published_constants():
    fs = 25600.0
    for bw in (1.0, 5.0, 50.0):
        # Tůma (2005), Feldbauer & Höldrich (2000): r = (1.58 fs / (2 pi B))^2, (1.70 ...)^3
        assert bandwidth_to_weight(bw, fs, 1) == pytest.approx(
            (1.58 * fs / (2 * np.pi * bw)) ** 2, rel=0.04
        )
        assert bandwidth_to_weight(bw, fs, 2) == pytest.approx(
            (1.70 * fs / (2 * np.pi * bw)) ** 3, rel=0.06
        )
        for fo in (1, 2):
            r = bandwidth_to_weight(bw, fs, fo)
            assert weight_to_bandwidth(r, fs, fo) == pytest.approx(bw, rel=1e-12)


@pytest.mark.parametrize(("filter_order", "published"), [(1, 2.85), (2, 2.80)])
def test_envelope_rise_time_is_tumas(filter_order, published):
    """Tůma gives the 10-90 % transition time 2.85 r^(1/2) / fs (order 1) and
    2.80 r^(1/3) / fs (order 2)."""
    fs, carrier, bw = 1000.0, 100.0, 2.0
    n = int(20 * fs)
    t = np.arange(n) / fs
    x = np.cos(2 * np.pi * carrier * t) * (t >= 10.0)
    res = order_waveform(
        x, fs, orders=1, rpm=np.full(n, 60 * carrier), bandwidth=bw, filter_order=filter_order
    )
    a = res.envelope[0].real
    rise = t[np.flatnonzero(a >= 0.9)[0]] - t[np.flatnonzero(a >= 0.1)[0]]
    r = float(res.weight[0])
    assert rise == pytest.approx(published * r ** (1 / (filter_order + 1)) / fs, rel=0.03)


def test_noise_alone_gives_the_level_of_the_filter_noise_bandwidth():
    """What the filter must not find: white noise yields an envelope whose mean square is
    4 sigma^2 ENBW / fs (ENBW of H^2, from the filter's formula), Rayleigh distributed."""
    fs, bw, sigma = 500.0, 5.0, 1.0
    n = int(200 * fs)
    x = sigma * np.random.default_rng(7).standard_normal(n)
    t = np.arange(n) / fs
    res = order_waveform(x, fs, orders=1, rpm=60 * (40 + 0.1 * t), bandwidth=bw)
    r = float(bandwidth_to_weight(bw, fs, 1))
    f = np.linspace(-fs / 2, fs / 2, 400001)
    h = 1 / (1 + r**2 * (2 * np.sin(np.pi * f / fs)) ** 4)
    enbw = np.trapezoid(h**2, f)
    inner = res.amplitude[0, int(2 * fs) : -int(2 * fs)]
    mean_square = 4 * sigma**2 * enbw / fs
    assert np.mean(inner**2) == pytest.approx(mean_square, rel=0.1)
    # Rayleigh: P(|a| > 3 rms) = exp(-9) = 1.2e-4
    assert np.mean(inner > 3 * np.sqrt(mean_square)) < 1e-3


# ---------------------------------------------------------------------- references, results


def test_tacho_and_angle_references_agree(runup):
    t = runup["t"]
    th_a = runup["carriers"][0]
    ppr = 2
    tacho = np.sin(ppr * th_a)  # rising zero crossings at th_a = pi k
    by_tacho = order_waveform(runup["x"], FS, orders=[1, 2], tacho=tacho, pulses_per_rev=ppr,
                              bandwidth=B)  # fmt: skip
    by_angle = order_waveform(runup["x"], FS, orders=[1, 2], angle=th_a, bandwidth=B)
    inner = (t > 0.5) & (t < T - 0.5)
    # the tacho's angle starts at its first pulse: compare amplitudes, and phase differences
    assert np.abs(_db(by_tacho.envelope[:, inner], by_angle.envelope[:, inner])).max() < 0.1
    ratio = by_tacho.envelope[:, inner] / by_angle.envelope[:, inner]
    lag = np.angle(ratio / np.mean(ratio, axis=1, keepdims=True))  # about a constant offset
    assert np.degrees(np.abs(lag)).max() < 1.0


def test_dataarray_multichannel_dataset_and_plots(runup, tmp_path):
    x2 = np.stack([runup["x"], 2 * runup["x"]])
    da = xr.DataArray(
        x2,
        dims=("channel", "time"),
        coords={"channel": ["a", "b"], "time": runup["t"]},
        attrs={"units": "m s-2"},
        name="acc",
    ).assign_coords(rpm=("time", runup["rpm"][0], {"units": "min-1"}))
    res = order_waveform(da, orders=[1, 2], bandwidth=B)
    assert res.envelope.shape == (2, 2, runup["t"].size)
    np.testing.assert_allclose(res.envelope[1], 2 * res.envelope[0], rtol=1e-9, atol=1e-12)
    ds = res.to_dataset()
    for name in list(ds.data_vars) + list(ds.coords):
        assert "long_name" in ds[name].attrs, name
        if ds[name].dtype.kind != "U":  # string labels have no units
            assert "units" in ds[name].attrs, name
    assert ds["amplitude"].attrs["units"] == "m s-2"
    assert ds["phase"].attrs["units"] == "degree"
    assert ds.attrs["amplitude"] == "peak"
    np.testing.assert_allclose(ds["bandwidth"].values, [B, B])
    one = res.select("b")
    fig = one.plot()
    assert isinstance(fig, Figure)
    fig.savefig(tmp_path / "vk.png", dpi=60)
    with pytest.raises(ValueError, match="channel"):
        res.plot()
    rem = remove_orders(da, orders=[1, 2], bandwidth=B, remove=0)
    assert isinstance(rem.plot(channel="a"), Figure)
    rds = rem.to_dataset()
    assert set(rds["signal"].dims) == {"channel", "time"}
    assert rds.attrs["removed_orders"] == [1.0]


def test_separate_solution_of_orders_far_apart_equals_the_joint_one(runup):
    """Orders 1 and 2 of shaft A (10-60 Hz apart) hardly interact: separate and joint
    solutions agree to the filter's leakage, far below the tolerance."""
    kw = {"orders": [1, 2], "rpm": runup["rpm"][0], "bandwidth": 2.0}
    x = runup["parts"][0] + runup["parts"][1]
    joint = order_waveform(x, FS, **kw)
    sep = order_waveform(x, FS, joint=False, **kw)
    t = runup["t"]
    inner = (t > 0.5) & (t < T - 0.5)
    assert np.abs(_db(joint.envelope[:, inner], sep.envelope[:, inner])).max() < 0.05


# ------------------------------------------------------------------------------ bad input


def _call(**over):
    n = 4096
    t = np.arange(n) / FS
    kw = {
        "x": np.cos(2 * np.pi * (10 * t + 6.25 * t**2)),
        "fs": FS,
        "orders": [1, 2],
        "rpm": 60 * (10 + 12.5 * t),
        "bandwidth": 2.0,
    }
    kw.update(over)
    return order_waveform(kw.pop("x"), kw.pop("fs"), **kw)


@pytest.mark.parametrize(
    ("over", "error", "match"),
    [
        ({"orders": [1, 10]}, ValueError, "orders.*Nyquist"),
        ({"orders": [0.0]}, ValueError, "orders"),
        ({"orders": [-1.0]}, ValueError, "orders"),
        ({"orders": []}, ValueError, "orders"),
        ({"orders": [1, np.nan]}, ValueError, "orders"),
        ({"orders": True}, TypeError, "orders"),
        ({"orders": "2"}, TypeError, "orders"),
        ({"orders": [1, True]}, TypeError, "orders"),
        ({"orders": [1, 1]}, ValueError, "twice"),
        ({"bandwidth": 0.0}, ValueError, "bandwidth"),
        ({"bandwidth": -1.0}, ValueError, "bandwidth"),
        ({"bandwidth": 0.2 * FS}, ValueError, "bandwidth.*0.1 fs"),
        ({"bandwidth": 1e-9}, ValueError, "bandwidth.*too narrow"),
        ({"bandwidth": np.inf}, ValueError, "bandwidth"),
        ({"bandwidth": True}, TypeError, "bandwidth"),
        ({"bandwidth": "2"}, TypeError, "bandwidth"),
        ({"bandwidth": [1.0, 2.0, 3.0]}, ValueError, "bandwidth"),
        ({"filter_order": 3}, ValueError, "filter_order"),
        ({"filter_order": True}, TypeError, "filter_order"),
        ({"filter_order": 1.0}, TypeError, "filter_order"),
        ({"joint": "yes"}, TypeError, "joint"),
        ({"joint": 1}, TypeError, "joint"),
        ({"fs": True}, TypeError, "fs"),
        ({"fs": -1.0}, ValueError, "fs"),
        ({"max_memory": 0}, ValueError, "max_memory"),
        ({"max_memory": True}, TypeError, "max_memory"),
        ({"max_memory": 1000.0}, ValueError, "max_memory"),
        ({"shafts": [0, 1]}, ValueError, "shafts"),
        ({"shafts": [0, True]}, TypeError, "shafts"),
        ({"shafts": [0]}, ValueError, "shafts"),
        ({"rpm": np.full(4000, 600.0)}, ValueError, "sample-count mismatch"),
        ({"rpm": np.full(4096, -600.0)}, ValueError, "rpm"),
        ({"rpm": np.r_[np.full(4095, 600.0), np.nan]}, ValueError, "non-finite"),
        ({"rpm": np.zeros(4096)}, ValueError, "does not turn"),
        ({"rpm": None}, ValueError, "speed reference"),
        ({"angle": np.zeros(4096)}, ValueError, "give one speed reference"),
        ({"x": np.r_[np.zeros(4095), np.nan]}, ValueError, "non-finite"),
        ({"x": np.zeros(4096, dtype=bool)}, ValueError, "real numeric"),
        ({"x": np.zeros(100)}, ValueError, "sample-count mismatch"),
    ],
)
def test_bad_input_names_the_parameter(over, error, match):
    with pytest.raises(error, match=match):
        _call(**over)


def test_orders_that_cannot_be_told_apart_are_refused():
    n = 4096
    t = np.arange(n) / FS
    rpm = 60 * (10 + 12.5 * t)
    x = np.cos(2 * np.pi * (20 * t + 12.5 * t**2))
    with pytest.raises(ValueError, match="same frequency"):
        order_waveform(x, FS, orders=[2, 1], shafts=[0, 1], rpm=[rpm, 2 * rpm], bandwidth=2.0)


def test_remove_positions_are_checked(runup):
    with pytest.raises(ValueError, match="remove"):
        remove_orders(runup["x"], FS, orders=[1], rpm=runup["rpm"][0], bandwidth=B, remove=3)
    with pytest.raises(TypeError, match="remove"):
        remove_orders(runup["x"], FS, orders=[1], rpm=runup["rpm"][0], bandwidth=B, remove=1.0)
