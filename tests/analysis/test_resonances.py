"""Resonance detection and classification on a synthetic run-up with known content.

The signal has four mesh-order rays whose amplitudes pass the frequency response of a mode at
1500 Hz (forced resonances at 1500 / (k 0.5 Hz per min-1)), a second mode at 900 Hz that only a
parametric instability excites (it grows inside a known unstable band), the same mode rising
inside a band that the run crosses too fast, a burst that nothing explains and a ring-down at the
start that must not be reported.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

from analysis.instability import (
    FORCED,
    PARAMETRIC,
    UNEXPLAINED,
    MeshPhasingRule,
    UnstableBand,
    detect_resonances,
    instability_candidates,
    runup_growth,
)
from analysis.maps import rpm_frequency_map
from analysis.runup import map_features

FS = 8192.0
T = 8.0
H = 0.5  # mesh frequency per rpm [Hz per min-1]
FA, FB = 1500.0, 900.0
RPM0, RPM1 = 300.0, 3300.0
NAMES = ["fa", "fb"]
FAMILIES = [("rotational", 0), ("planet", 1)]
RULE = MeshPhasingRule(3, 33, 114)  # in-phase planets: mesh harmonics force rotational modes only
BAND_GROWS = UnstableBand("2 fb/3", 1180.0, 1220.0, np.zeros(0), np.array([60.0]))
BAND_FAST = UnstableBand("", 2495.0, 2505.0, np.zeros(0), np.array([60.0]))


def _speed(t):
    return RPM0 + (RPM1 - RPM0) * t / T


def _time_at(rpm):
    return (rpm - RPM0) / (RPM1 - RPM0) * T


def _signal(seed=0, structural=None):
    t = np.arange(int(FS * T)) / FS
    rpm = _speed(t)
    fm = H * rpm
    phase = 2 * np.pi * np.cumsum(fm) / FS
    rng = np.random.default_rng(seed)
    x = 0.01 * rng.normal(size=t.size)

    def frf(f, f0=FA):  # single mode, 3 % damping, unit static gain
        r = f / f0
        return 1.0 / np.sqrt((1 - r**2) ** 2 + (0.06 * r) ** 2)

    if structural is not None:  # a housing resonance the model does not know
        for k, a in zip((2, 3, 4), (0.6, 0.4, 0.3), strict=True):
            x += a * frf(k * fm, structural) * np.sin(k * phase + 0.5)
        b, a = scipy.signal.iirpeak(structural, 60.0, FS)
        x += 0.3 * scipy.signal.lfilter(b, a, rng.normal(size=t.size))

    for k, a in zip((1, 2, 3, 4), (1.0, 0.6, 0.4, 0.3), strict=True):
        x += a * frf(k * fm) * np.sin(k * phase)
    # parametric growth of the mode at FB while the speed is inside BAND_GROWS, then decay
    sigma = np.where((rpm >= 1180) & (rpm <= 1220), 60.0, np.where(rpm > 1220, -15.0, 0.0))
    env = 1e-3 * np.exp(np.cumsum(sigma) / FS)  # seed level until the band
    x += env * np.sin(2 * np.pi * FB * t)
    # the same mode rises briefly inside BAND_FAST (crossed in 27 ms: too fast to grow)
    x += 0.5 * np.exp(-0.5 * ((t - _time_at(2500.0)) / 0.05) ** 2) * np.sin(2 * np.pi * FB * t)
    # an unexplained burst off every ray and natural frequency
    x += 0.5 * np.exp(-0.5 * ((t - _time_at(2000.0)) / 0.05) ** 2) * np.sin(2 * np.pi * 2300 * t)
    # a start transient: the mode at FA rings down from t = 0
    x += 3.0 * np.exp(-8.0 * t) * np.sin(2 * np.pi * FA * t)
    return t, rpm, x


@pytest.fixture(scope="module")
def run():
    t, rpm, x = _signal()
    m = rpm_frequency_map(x, FS, rpm, resolution=8.0, window="hann", overlap=0.75,
                          amplitude="rms")
    return t, rpm, m.to_dataset()


def _near(res, rpm, freq, tol_rpm=80.0, tol_hz=60.0):
    hit = np.flatnonzero((np.abs(res.rpm - rpm) <= tol_rpm)
                         & (np.abs(res.frequency - freq) <= tol_hz))
    assert hit.size, (rpm, freq, str(res))
    return int(hit[np.argmax(res.strength_db[hit])])


def test_known_content_is_classified(run):
    t, rpm, ds = run
    res = detect_resonances(ds, natural_frequencies_hz=[FA, FB], mesh_frequency_per_rpm=H,
                            names=NAMES, chart=[BAND_GROWS, BAND_FAST], speed_profile=(t, rpm),
                            mode_families=FAMILIES, mesh_harmonic_rule=RULE,
                            natural_uncertainty=0.02, orders=range(1, 5))
    # forced resonances of every mesh harmonic with fa, at fa / (k h)
    for k in (1, 2, 3, 4):
        i = _near(res, FA / (k * H), FA)
        assert res.mechanism[i] == FORCED and res.order[i] == k
        assert res.cause[i] == f"{k} f_mesh = fa"
        assert res.predicted_rpm[i] == pytest.approx(FA / (k * H))
    # the growing band: parametric, with the band and its growth as evidence
    i = _near(res, 1220.0, FB)
    assert res.mechanism[i] == PARAMETRIC and res.mode[i] == "fb"
    assert res.cause[i] == "2 fb/3"  # f_mesh = 2 fb / 3 = 600 Hz at 1200 min-1
    assert "grows by" in res.note[i]
    # the band crossed too fast: the rise there is not called parametric
    i = _near(res, 2500.0, FB)
    assert res.mechanism[i] == UNEXPLAINED and "grows only" in res.note[i]
    # the burst off every feature
    i = _near(res, 2000.0, 2300.0)
    assert res.mechanism[i] == UNEXPLAINED
    # nothing from the start transient, nothing else
    assert res.rpm.min() > 600.0
    assert res.counts() == {FORCED: 4, PARAMETRIC: 1, UNEXPLAINED: 2}, str(res)
    # crossings of the rays with fb are not forced (mesh phasing), with fa all found
    status = {(c.harmonic, c.mode): c.status for c in res.crossings}
    assert all(status[(k, "fa")] == "rise" for k in (1, 2, 3, 4))
    assert status[(2, "fb")] == "not forced (mesh phasing)"
    # growth table: the bands' time and exponent (parabolic profile, mean 2/3 of the peak)
    g = res.growth
    assert g.time_in_band[0] == pytest.approx(40.0 / 375.0, rel=0.02)
    assert g.growth_db[0] == pytest.approx(8.686 * 60 * 2 / 3 * 40 / 375, rel=0.02)
    assert bool(g.can_grow[0]) and not bool(g.can_grow[1])
    assert "run-up of >=" in g.advice[1] and "dwell" in g.advice[1]
    assert any("too fast" in n for n in res.notes)
    ds_out = res.to_dataset()
    for name, var in ds_out.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
    assert 0.0 < float(np.mean(res.coincidence[res.mechanism == FORCED])) < 0.6
    from matplotlib.figure import Figure

    assert isinstance(res.plot(ds, natural_frequencies_hz=[FA, FB]), Figure)
    assert "7 rises" in res.summary()


def test_structural_resonance_from_the_map_features():
    """A resonance the model lacks: unexplained without the map's vertical lines, forced with."""
    fc = 2100.0
    _, rpm, x = _signal(seed=1, structural=fc)
    ds = rpm_frequency_map(x, FS, rpm, resolution=8.0, window="hann", overlap=0.75,
                           amplitude="rms").to_dataset()
    feat = map_features(ds)
    assert np.any(np.abs(feat.frequencies - fc) < 10.0)
    kw = {"natural_frequencies_hz": [FA, FB], "mesh_frequency_per_rpm": H, "names": NAMES,
          "natural_uncertainty": 0.02, "orders": range(1, 5)}
    plain = detect_resonances(ds, **kw)
    with_lines = detect_resonances(ds, features=feat, **kw)
    for k in (2, 3, 4):
        i = _near(with_lines, fc / (k * H), fc)
        assert with_lines.mechanism[i] == FORCED
        assert with_lines.cause[i].startswith(f"{k} f_mesh = line 2")
    # without the line, the order-2 rise is unexplained (orders 3 and 4 happen to lie next to
    # resonances of other orders with fa and get that weaker explanation, with its chance)
    j = _near(plain, fc / (2 * H), fc)
    assert plain.mechanism[j] == UNEXPLAINED
    assert any(c.mode.startswith("line 2") for c in with_lines.crossings)


def test_without_chart_theory_candidates_and_without_rule(run):
    _, _, ds = run
    cand = instability_candidates([FA, FB], n_max=4, mode_labels=NAMES)
    res = detect_resonances(ds, natural_frequencies_hz=[FA, FB], mesh_frequency_per_rpm=H,
                            names=NAMES, candidates=cand, natural_uncertainty=0.02,
                            orders=range(1, 5))
    i = _near(res, 1220.0, FB)
    assert res.mechanism[i] == PARAMETRIC and "growth not checked" in res.note[i]
    assert res.growth is None


def test_noise_only_map_reports_nothing():
    rng = np.random.default_rng(4)
    t = np.arange(int(FS * 4)) / FS
    m = rpm_frequency_map(rng.normal(size=t.size), FS, 300 + 750 * t, resolution=8.0)
    res = detect_resonances(m.to_dataset(), natural_frequencies_hz=[FA, FB],
                            mesh_frequency_per_rpm=H, orders=range(1, 5))
    assert len(res) <= 2, str(res)  # rises of a noise map: at most a stray one or two


NOISE_SEEDS = 100


def test_false_positive_rate_on_noise_only_runups():
    """Seeded noise-only run-ups (4 s, 300 -> 3300 min-1, 4 mesh orders, the modes at 1500 and
    900 Hz): how many stray rises are reported, and how many get a forced-resonance
    explanation (a false positive). Measured (README, docs/catalogue-identification.md): 98
    rises in 100 maps, 19 of them called forced (19 %), 79 unexplained, none parametric; every
    forced one states a coincidence chance of 0.20-0.35, so the rate is what the rows say."""
    rises = forced = parametric = 0
    stated = []
    for seed in range(NOISE_SEEDS):
        rng = np.random.default_rng(seed)
        t = np.arange(int(FS * 4)) / FS
        m = rpm_frequency_map(rng.normal(size=t.size), FS, 300 + 750 * t, resolution=8.0)
        res = detect_resonances(m.to_dataset(), natural_frequencies_hz=[FA, FB],
                                mesh_frequency_per_rpm=H, orders=range(1, 5))
        c = res.counts()
        rises += len(res)
        forced += c[FORCED]
        parametric += c[PARAMETRIC]
        stated += list(res.coincidence[res.mechanism == FORCED])
        assert len(res) <= 4, str(res)  # never more than a few stray rises in one map
    print(f"noise-only run-ups: {rises} rises in {NOISE_SEEDS} maps, {forced} forced, "
          f"{parametric} parametric, {rises - forced - parametric} unexplained")
    assert parametric == 0  # no Floquet chart: never parametric
    assert 0.5 * NOISE_SEEDS <= rises <= 1.5 * NOISE_SEEDS
    assert forced <= 0.25 * rises  # the false-positive rate the README states (19 %)
    assert min(stated) >= 0.15  # each false positive says it is weak evidence
    assert forced / rises <= float(np.mean(stated)) + 0.05  # no worse than stated


def test_runup_growth_hand_computed():
    t = np.linspace(0.0, 1.0, 11)
    rpm = 4000.0 * t
    band = UnstableBand("x", 2084.0, 2122.0, np.array([2084.0, 2103.0, 2122.0]),
                        np.array([0.0, 51.7, 0.0]))
    g = runup_growth([band], t, rpm, threshold_db=20.0)
    tau = 38.0 / 4000.0
    assert g.time_in_band[0] == pytest.approx(tau, rel=0.02)
    assert g.exponent[0] == pytest.approx(0.5 * 51.7 * tau, rel=0.02)  # triangle profile
    assert not g.can_grow[0]
    slow = runup_growth([band], t * 20, rpm, threshold_db=20.0)
    assert slow.can_grow[0] and slow.growth_db[0] == pytest.approx(20 * g.growth_db[0], rel=0.02)
    with pytest.raises(ValueError, match="time"):
        runup_growth([band], t[::-1], rpm)


def test_layout_errors(run):
    _, _, ds = run
    kw = {"natural_frequencies_hz": [FA], "mesh_frequency_per_rpm": H}
    with pytest.raises(ValueError, match="rpm"):
        detect_resonances(ds.drop_vars("rpm"), **kw)
    with pytest.raises(ValueError, match="no data variable"):
        detect_resonances(ds.rename({"amplitude": "level"}), **kw)
    with pytest.raises(ValueError, match="dims"):
        detect_resonances(ds.rename({"frequency": "freq"}), **kw)
    with pytest.raises(ValueError, match="non-negative"):
        detect_resonances(ds.assign(amplitude=-ds.amplitude), **kw)
    with pytest.raises(ValueError, match="must be > 0"):
        detect_resonances(ds, natural_frequencies_hz=[0.0], mesh_frequency_per_rpm=H)
    with pytest.raises(ValueError, match="mesh_frequency_per_rpm"):
        detect_resonances(ds, natural_frequencies_hz=[FA], mesh_frequency_per_rpm=-1.0)
    with pytest.raises(ValueError, match="mode_families"):
        detect_resonances(ds, **kw, mesh_harmonic_rule=RULE)
