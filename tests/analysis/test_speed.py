"""Tests of analysis.speed against a synthetic run-up with a known angle.

The tacho signals are generated from the true angle theta(t) (quadratic: 10 Hz -> 50 Hz in 2 s,
sampled at 51.2 kHz): each tooth gives a rising ramp centred on the tooth angle 2*pi*j/ppr, so
the 50 % crossing of every pulse is exactly at a known angle. Tolerance for the recovered angle:
< 1e-3 rad rms between the first and last pulse, after removing an offset that must be a
whole number of tooth pitches (a tacho cannot know the absolute angle; with a missing-tooth
reference the offset must be a whole number of revolutions).
"""

from __future__ import annotations

import numpy as np
import pytest

from analysis.speed import SpeedReference, from_angle, from_rpm, from_tacho

FS = 51200.0
T_END = 2.0
F0, F1 = 10.0, 50.0  # shaft speed [Hz] at start and end
TOL_RMS = 1e-3  # rad


def true_angle(t: np.ndarray) -> np.ndarray:
    alpha = 2 * np.pi * (F1 - F0) / T_END
    return 0.3 + 2 * np.pi * F0 * t + 0.5 * alpha * t**2


def true_rpm(t: np.ndarray) -> np.ndarray:
    return 60.0 * (F0 + (F1 - F0) * t / T_END)


def tacho(theta: np.ndarray, ppr: int, missing: int = 0, width: float = 0.2) -> np.ndarray:
    """Pulse train: ramp up over `width` tooth pitches centred on each tooth angle, high for a
    quarter pitch, low otherwise; teeth ppr-missing..ppr-1 of each revolution are absent."""
    u = theta * ppr / (2 * np.pi)
    tooth = np.floor(u + 0.5)
    frac = u - tooth  # in [-0.5, 0.5), edge at 0
    x = np.clip(frac / width + 0.5, 0.0, 1.0)
    x = np.where((frac < -width / 2) | (frac >= 0.25), 0.0, x)
    if missing:
        x = np.where(np.mod(tooth, ppr) >= ppr - missing, 0.0, x)
    return x


@pytest.fixture(scope="module")
def run_up():
    t = np.arange(int(T_END * FS)) / FS
    return t, true_angle(t)


def angle_error(ref: SpeedReference, theta: np.ndarray, step: float) -> np.ndarray:
    inside = (ref.time > ref.pulse_times[0]) & (ref.time < ref.pulse_times[-1])
    err = ref.angle[inside] - theta[inside]
    offset = np.round(np.mean(err) / step) * step
    assert abs(np.mean(err) - offset) < 1e-4, "offset is not a whole number of pitches"
    return err - offset


def rms(e: np.ndarray) -> float:
    return float(np.sqrt(np.mean(e**2)))


def test_tacho_clean_60_per_rev(run_up):
    t, theta = run_up
    ref = from_tacho(tacho(theta, 60), FS, 60)
    assert ref.accuracy.n_pulses == int(np.floor((theta[-1]) * 60 / (2 * np.pi))) - 2
    assert rms(angle_error(ref, theta, 2 * np.pi / 60)) < TOL_RMS
    inside = (t > 0.05) & (t < 1.95)
    np.testing.assert_allclose(ref.rpm[inside], true_rpm(t[inside]), rtol=1e-3)
    assert ref.accuracy.rms_angle_error_rad < TOL_RMS


def test_tacho_dropped_pulses(run_up):
    _t, theta = run_up
    x = tacho(theta, 60)
    rng = np.random.default_rng(1)
    tooth = np.floor(theta * 60 / (2 * np.pi) + 0.5).astype(int)
    teeth = np.unique(tooth)[2:-2]
    dropped = rng.choice(teeth, size=int(0.02 * teeth.size), replace=False)
    x[np.isin(tooth, dropped)] = 0.0
    ref = from_tacho(x, FS, 60)
    assert ref.accuracy.n_inserted == dropped.size
    assert rms(angle_error(ref, theta, 2 * np.pi / 60)) < TOL_RMS
    # without repair the count is wrong: the angle falls behind by the dropped pitches
    bad = from_tacho(x, FS, 60, repair=False)
    assert bad.angle[-1] < ref.angle[-1] - 2 * np.pi / 60 * (dropped.size - 0.5)


def test_tacho_extra_glitch_pulses(run_up):
    t, theta = run_up
    x = tacho(theta, 60)
    u = theta * 60 / (2 * np.pi)
    frac = u - np.floor(u + 0.5)
    rng = np.random.default_rng(2)
    spots = np.flatnonzero((np.abs(frac - 0.37) < 0.01) & (t > 0.1) & (t < 1.9))
    spots = rng.choice(spots, size=5, replace=False)
    for i in spots:
        x[i : i + 2] = 1.0
    ref = from_tacho(x, FS, 60)
    assert ref.accuracy.n_removed == 5
    assert ref.accuracy.n_pulses == from_tacho(tacho(theta, 60), FS, 60).accuracy.n_pulses + 5
    assert rms(angle_error(ref, theta, 2 * np.pi / 60)) < TOL_RMS


def test_tacho_60_minus_2_wheel(run_up):
    _t, theta = run_up
    ref = from_tacho(tacho(theta, 60, missing=2), FS, 60, missing_teeth=2)
    revs = int(theta[-1] / (2 * np.pi))
    assert ref.accuracy.n_reference_gaps in (revs - 1, revs)
    assert ref.accuracy.n_inserted == 0
    # reference gap fixes the absolute angle: offset is a whole number of revolutions (here 0)
    err = angle_error(ref, theta, 2 * np.pi)
    assert rms(err) < TOL_RMS
    assert abs(np.mean(ref.angle - theta)) < 1e-3


def test_tacho_60_minus_2_with_dropped_pulse(run_up):
    _t, theta = run_up
    x = tacho(theta, 60, missing=2)
    tooth = np.floor(theta * 60 / (2 * np.pi) + 0.5).astype(int)
    for j in (600, 1201, 1800 + 57):  # incl. the tooth right before a gap
        x[tooth == j] = 0.0
    ref = from_tacho(x, FS, 60, missing_teeth=2)
    assert ref.accuracy.n_inserted == 3
    assert rms(angle_error(ref, theta, 2 * np.pi)) < TOL_RMS


def test_tacho_noise_hysteresis_prevents_double_triggering(run_up):
    _t, theta = run_up
    clean = tacho(theta, 60, width=0.3)
    x = clean + np.random.default_rng(3).normal(0.0, 0.02, clean.size)
    n_true = from_tacho(clean, FS, 60).accuracy.n_pulses
    raw = from_tacho(x, FS, 60, hysteresis=0.0, repair=False)
    assert raw.accuracy.n_pulses > n_true  # noise double-triggers without hysteresis
    ref = from_tacho(x, FS, 60)  # default hysteresis: 10 % of the state-level distance
    assert ref.accuracy.n_pulses == n_true
    assert ref.accuracy.n_removed == 0
    assert rms(angle_error(ref, theta, 2 * np.pi / 60)) < TOL_RMS


def test_tacho_output_time_and_dataset(run_up):
    _t, theta = run_up
    t_out = np.linspace(0.5, 1.5, 101)
    ref = from_tacho(tacho(theta, 60), FS, 60, output_time=t_out)
    assert ref.angle.shape == (101,)
    np.testing.assert_allclose(ref.rpm, true_rpm(t_out), rtol=1e-3)
    ds = ref.to_dataset()
    assert ds.angle.attrs["units"] == "rad"
    assert ds.rpm.attrs["units"] == "min-1"
    assert ds.time.attrs["units"].startswith("seconds since ")
    np.testing.assert_array_equal(ds.time.values, t_out)


def test_tacho_flat_signal_raises():
    with pytest.raises(ValueError, match="no pulses detected"):
        from_tacho(np.full(1000, 2.5), FS)


def test_tacho_too_few_pulses_raises():
    x = np.zeros(1000)
    x[500:510] = 1.0
    with pytest.raises(ValueError, match="no pulses detected"):
        from_tacho(x, FS)


def test_tacho_missing_gap_not_found(run_up):
    _t, theta = run_up
    with pytest.raises(ValueError, match="no gap of 3"):
        from_tacho(tacho(theta, 60), FS, 60, missing_teeth=2)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"pulses_per_rev": 0}, "pulses_per_rev"),
        ({"pulses_per_rev": 60, "missing_teeth": 59}, "missing_teeth"),
        ({"hysteresis": -1.0}, "hysteresis"),
    ],
)
def test_tacho_bad_parameters(kwargs, match):
    x = np.tile(np.r_[np.zeros(10), np.ones(10)], 10)
    with pytest.raises(ValueError, match=match):
        from_tacho(x, FS, **kwargs)


def test_from_rpm_integrates_linear_run_up():
    t = np.linspace(0.0, T_END, 2001)
    ref = from_rpm(t, true_rpm(t))
    np.testing.assert_allclose(ref.angle, true_angle(t) - 0.3, atol=1e-9)
    assert ref.accuracy.rms_angle_error_rad < 1e-3


def test_from_angle_differentiates():
    t = np.linspace(0.0, T_END, 4001)
    ref = from_angle(t, true_angle(t))
    np.testing.assert_allclose(ref.rpm, true_rpm(t), rtol=1e-4)
    ds = ref.to_dataset()
    assert set(ds.data_vars) == {"angle", "rpm"}


def test_from_angle_non_monotonic_raises():
    t = np.linspace(0.0, 1.0, 11)
    angle = np.r_[np.arange(6.0), 4.0, np.arange(7.0, 11.0)]
    with pytest.raises(ValueError, match=r"non-decreasing.*samples 5 and 6"):
        from_angle(t, angle)


def test_from_rpm_rejects_nan_and_bad_time():
    t = np.linspace(0.0, 1.0, 11)
    rpm = np.ones(11)
    rpm[4] = np.nan
    with pytest.raises(ValueError, match="rpm"):
        from_rpm(t, rpm)
    with pytest.raises(ValueError, match="time"):
        from_rpm(t[::-1], np.ones(11))
