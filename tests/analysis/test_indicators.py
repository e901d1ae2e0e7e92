"""Tests of analysis.indicators and analysis.alarm_limits.

Hand computations on tiny arrays, moments of Gaussian samples, and a condition-monitoring
history built from records made here: a shaft (16 Hz) carrying a gear of 20 teeth (mesh
harmonics 1-2, a shaft-order component) plus Gaussian noise, averaged by analysis.tsa; a
damaged tooth is a short bump once per revolution at tooth 7.
"""

from __future__ import annotations

import numpy as np
import pytest

from analysis.alarm_limits import AlarmLimits, learn_limits
from analysis.gear_signals import gear_signals
from analysis.indicators import (
    INDICATORS,
    RunToDate,
    condition_indicators,
    crest_factor,
    energy_ratio,
    fm0,
    fm4,
    gear_indicators,
    kurtosis,
    m6a,
    m8a,
    na4,
    normalized_moment,
    peak,
    rms,
    sideband_level_factor,
)
from analysis.tsa import tsa

FS, SHAFT_HZ, SPR, Z = 4096.0, 16.0, 256, 20


def record(seed: int, damage: float = 0.0, revolutions: int = 30, noise: float = 0.5):
    n = int((revolutions + 3) * FS / SHAFT_HZ)
    th = 2 * np.pi * SHAFT_HZ * np.arange(n) / FS
    rng = np.random.default_rng(seed)
    x = (np.cos(Z * th + 0.3) + 0.3 * np.cos(2 * Z * th) + 0.2 * np.cos(th)
         + rng.normal(0.0, noise, n))  # fmt: skip
    if damage:
        d = np.mod(th / (2 * np.pi) * Z - 7.5 + Z / 2, Z) - Z / 2  # teeth from mid-tooth 7
        x += damage * np.exp(-0.5 * (d / 0.1) ** 2)
    return tsa(x, FS, angle=th, samples_per_rev=SPR, revolutions=revolutions)


# ------------------------------------------------------------------------------------------
# definitions against hand computations
# ------------------------------------------------------------------------------------------


def test_hand_computations_on_a_tiny_array():
    x = np.array([1.0, -1.0, 2.0, 0.0])
    # mean 0.5; deviations 0.5, -1.5, 1.5, -0.5: sums of powers 2: 5, 4: 10.25, 6: 22.8125,
    # 8: 51.265625
    assert rms(x) == pytest.approx(np.sqrt(1.5))
    assert peak(x) == 2.0
    assert crest_factor(x) == pytest.approx(2.0 / np.sqrt(1.5))
    assert kurtosis(x) == pytest.approx(4 * 10.25 / 5**2)
    assert fm4(x) == pytest.approx(1.64)
    assert m6a(x) == pytest.approx(4**2 * 22.8125 / 5**3)
    assert m8a(x) == pytest.approx(4**3 * 51.265625 / 5**4)
    assert normalized_moment(x, 2) == pytest.approx(1.0)
    assert fm0(x, [0.5, 1.0]) == pytest.approx(3.0 / 1.5)
    assert energy_ratio(x, np.ones(4)) == pytest.approx(np.sqrt(1.5))
    assert sideband_level_factor(0.1, 0.2, x) == pytest.approx(0.3 / np.sqrt(1.25))


def test_na4_with_its_run_to_date_variance_by_hand():
    r1 = np.array([1.0, -1.0, 1.0, -1.0])  # sum of squared deviations 4, of 4th powers 4
    r2 = np.array([2.0, 0.0, 0.0, -2.0])  # 8 and 32
    h = RunToDate()
    assert h.add(r1) == pytest.approx(4 * 4 / 4**2)
    # N sum(r2 - mean)^4 / ((1/M) sum_j sum_i (r_ij - mean_j)^2)^2, M = 2
    assert h.add(r2) == pytest.approx(4 * 32 / ((4 + 8) / 2) ** 2)
    assert h.records == 2
    assert float(h.mean_variance) == pytest.approx(1.5)
    frozen = RunToDate(freeze_after=1)
    frozen.add(r1)
    assert frozen.add(r2) == pytest.approx(4 * 32 / 4**2)
    assert na4(r2, 1.0) == pytest.approx(32 / 4)
    # two channels at once, each with its own history
    two = RunToDate()
    two.add(np.vstack([r1, 2 * r1]))
    np.testing.assert_allclose(two.add(np.vstack([r2, 2 * r2])), [128 / 36, 128 / 36])
    with pytest.raises(ValueError, match="channels"):
        two.add(r1)


@pytest.mark.parametrize(("fn", "expected", "tol"), [(fm4, 3.0, 0.03), (m6a, 15.0, 0.5),
                                                      (m8a, 105.0, 7.0)])  # fmt: skip
def test_moments_of_gaussian_samples(fn, expected, tol):
    """400 Gaussian records of 1024 samples: means 2.99, 14.9, 103 (stds of one record 0.15,
    2.3 and 35: the finite-record bias and spread stated in the docs)."""
    r = np.random.default_rng(0).normal(size=(400, 1024))
    assert np.mean(fn(r)) == pytest.approx(expected, abs=tol)


def test_fm4_and_na4_near_3_on_healthy_tsa_derived_signals():
    """60 healthy records through tsa: FM4 of the difference signals and NA4 of the residuals
    (with the run-to-date history) average 3 within 0.12 and 0.2."""
    ds = condition_indicators([record(s) for s in range(60)], Z)
    assert float(ds.fm4.mean()) == pytest.approx(3.0, abs=0.12)
    assert float(ds.na4.mean()) == pytest.approx(3.0, abs=0.2)
    assert float(ds.m6a.mean()) == pytest.approx(15.0, abs=2.0)
    assert float(ds.fm4.std()) < 0.4


def test_one_damaged_tooth_raises_fm4():
    for seed in range(5):
        healthy = gear_signals(record(seed), Z)
        damaged = gear_signals(record(seed, damage=1.0), Z)
        assert float(fm4(healthy.difference)) < 4.0
        assert float(fm4(damaged.difference)) > 10.0
        ind = gear_indicators(damaged)
        assert float(ind["m6a"]) > 100.0 and float(ind["m8a"]) > 1000.0
        # the damage sits at tooth 7 (mid-tooth 7.5 of 20)
        tooth = damaged.angle[np.argmax(damaged.difference)] * Z / (2 * np.pi)
        assert tooth == pytest.approx(7.5, abs=0.2)


# ------------------------------------------------------------------------------------------
# history, alarm limits, false alarms
# ------------------------------------------------------------------------------------------


def test_false_alarm_rate_and_detection():
    """Limits mean + 3 std learned from 20 healthy records; 200 further healthy records: the
    fraction with any of the 12 indicators above its limit is measured (11 % here, mostly
    M6A/M8A) and must stay below 15 %, FM4 alone below 3 %; 10 records with a damaged tooth
    are all flagged by FM4."""
    healthy = [record(s) for s in range(220)]
    ds = condition_indicators(healthy, Z)
    lim = learn_limits(ds, 20, k=3.0)
    test = ds.isel(record=slice(20, None))
    assert float(lim.alarms(test).mean()) < 0.15
    ex = lim.exceeded(test)
    assert float(ex.fm4.mean()) < 0.03
    assert float(ex.rms.mean()) < 0.03 and float(ex.energy_ratio.mean()) < 0.03
    faulty = condition_indicators(healthy[:20] + [record(500 + s, damage=1.0) for s in range(10)],
                                  Z)  # fmt: skip
    flags = learn_limits(faulty, 20).exceeded(faulty)
    assert bool(flags.fm4.isel(record=slice(20, None)).all())
    assert not bool(flags.fm4.isel(record=slice(0, 20)).any())
    # NA4 keeps growing after the onset: the run-to-date variance lags behind
    assert float(faulty.na4[-1]) > float(faulty.na4[:20].max())


def test_indicator_dataset_and_trend_figure():
    recs = [record(s) for s in range(8)] + [record(99, damage=1.0)]
    ds = condition_indicators(recs, Z, labels=[f"r{i}" for i in range(9)])
    assert set(ds.data_vars) == set(INDICATORS)
    for v in ds.data_vars:
        assert ds[v].attrs["long_name"] and ds[v].attrs["units"]
    assert ds.rms.attrs["units"] == "1" and ds.fm4.attrs["units"] == "1"
    assert ds["time"].attrs["units"].startswith("seconds since")
    assert np.all(np.diff(ds["time"].values) == 0)  # each record's average starts alike
    assert list(ds["record_label"].values[:2]) == ["r0", "r1"]
    lim = learn_limits(ds, 8, k=3.0, variables=["fm4", "na4", "rms"])
    assert isinstance(lim, AlarmLimits) and lim.indicators == ("fm4", "na4", "rms")
    assert bool(lim.alarms(ds)[-1])
    out = lim.to_dataset()
    assert "fm4_upper" in out and out.attrs["healthy_records"] == 8
    fig = lim.plot(ds)
    assert len([a for a in fig.axes if a.get_visible()]) == 3
    both = learn_limits(ds, slice(0, 8), sides="both")
    assert np.isfinite(float(both.lower.fm4))
    assert not np.isfinite(float(lim.lower.fm4))


def test_multichannel_indicators():
    n = int(33 * FS / SHAFT_HZ)
    th = 2 * np.pi * SHAFT_HZ * np.arange(n) / FS
    rng = np.random.default_rng(0)
    x = np.vstack([np.cos(Z * th) + rng.normal(0, 0.3, n), 2 * np.cos(Z * th)
                   + rng.normal(0, 0.3, n)])  # fmt: skip
    r = tsa(x, FS, angle=th, samples_per_rev=SPR, revolutions=30)
    ds = condition_indicators([r, r], Z)
    assert ds.fm4.dims == ("record", "channel")
    lim = learn_limits(condition_indicators([r] * 4, Z), 4)
    assert lim.alarms(ds).dims == ("record",)
    fig = lim.plot(ds, channel=1)
    assert fig.axes
    with pytest.raises(ValueError, match="channel"):
        lim.plot(ds)


@pytest.mark.parametrize(
    ("call", "error", "match"),
    [
        (lambda: fm4(np.array([1.0, np.nan, 2.0])), ValueError, "NaN"),
        (lambda: fm4(np.array(["a", "b"])), TypeError, "real numbers"),
        (lambda: rms(np.array([True, False])), TypeError, "real numbers"),
        (lambda: kurtosis(np.array([1.0])), ValueError, "at least 2"),
        (lambda: normalized_moment(np.ones(4), 3), ValueError, "order"),
        (lambda: normalized_moment(np.ones(4), True), ValueError, "order"),
        (lambda: RunToDate(freeze_after=0), ValueError, "freeze_after"),
        (lambda: RunToDate(freeze_after=True), ValueError, "freeze_after"),
        (lambda: condition_indicators([]), ValueError, "records"),
        (lambda: condition_indicators([record(0)]), ValueError, "mesh_orders"),
        (lambda: condition_indicators([np.ones(8)], 2), TypeError, "records"),
        (lambda: condition_indicators([record(0)], Z, labels=["a", "b"]), ValueError, "labels"),
        (lambda: gear_indicators(np.ones(8)), TypeError, "GearSignals"),
    ],
)
def test_bad_input(call, error, match):
    with pytest.raises(error, match=match):
        call()


def test_bad_limits_input():
    ds = condition_indicators([record(s) for s in range(4)], Z)
    with pytest.raises(ValueError, match="healthy"):
        learn_limits(ds, 2)
    with pytest.raises(TypeError, match="healthy"):
        learn_limits(ds, True)
    with pytest.raises(TypeError, match="k"):
        learn_limits(ds, k="3")
    with pytest.raises(ValueError, match="k"):
        learn_limits(ds, k=-1.0)
    with pytest.raises(ValueError, match="sides"):
        learn_limits(ds, sides="lower")
    with pytest.raises(ValueError, match="variables"):
        learn_limits(ds, variables=["fm5"])
    with pytest.raises(ValueError, match="missing"):
        learn_limits(ds, variables=["fm4"]).exceeded(ds[["rms"]])


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # the checker's own
def test_results_pass_the_cf_checker(tmp_path):
    """Every to_dataset() of the condition-monitoring results, written by plain to_netcdf,
    gives no message of the IOOS compliance-checker at CF-1.11."""
    pytest.importorskip("compliance_checker")
    from tests.analysis.test_cf import cf_messages
    from tests.analysis.test_planetary_tsa import record as planetary_record
    from tests.analysis.test_planetary_tsa import separate

    x, theta = planetary_record(0, revolutions=12)
    sep = separate(x, theta)
    r = record(0)
    ind = condition_indicators([record(s) for s in range(4)], Z, labels=list("abcd"))
    results = {
        "tsa": r.to_dataset(),
        "planets": sep.to_dataset(),
        "planet": sep.planets[0].to_dataset(),
        "signals": gear_signals(r, Z).to_dataset(),
        "indicators": ind,
        "limits": learn_limits(ind).to_dataset(),
    }
    for name, ds in results.items():
        path = tmp_path / f"{name}.nc"
        ds.to_netcdf(path, engine="netcdf4")
        assert cf_messages(path, tmp_path) == [], name
