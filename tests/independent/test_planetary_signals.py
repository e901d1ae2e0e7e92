"""The independent phenomenological generator against what the literature says it must show.

Every expectation here is computed in the test from tooth numbers and angles (McFadden &
Smith 1985's planet-pass rule, the fault frequencies of Lei et al. 2014's table), not taken
from the generator.
"""

import math

import numpy as np
import pytest

from tests.independent.planetary_signals import (
    FOUR_PLANET,
    PAPER_CASE1,
    RecordSpec,
    benchmark_records,
    generate,
    mesh_phases,
    to_dataset,
    truth,
    with_changes,
    write_record,
)

K = 6144  # samples per carrier revolution in the exact-angle tests (divisible by 3 and 4,
#           so that what the sampling aliases keeps the planet-pass rule)


def _exact(gs, revs, **kw):
    """A noise-free record at constant speed with K samples per carrier revolution and
    ``revs`` whole carrier revolutions: its FFT has no leakage (bins 1/revs orders)."""
    fs = 20_000.0
    cps = gs.z_sun / (gs.z_sun + gs.z_ring)
    rpm = 60.0 * fs / (K * cps)
    spec = RecordSpec(gs, speed_rpm=rpm, duration=revs * K / fs, fs=fs, fluctuation=0.0,
                      snr_db=200.0, imperfection=0.0, impacts=False, impact_jitter=0.0,
                      **kw)
    return spec, generate(spec)


def _orders(x, revs):
    a = np.abs(np.fft.rfft(x)) / x.size
    return np.arange(a.size) / revs, a


def test_mesh_phases_from_the_tooth_numbers():
    # paper-case1: 33/3 and 114/3 are integers -> in phase
    sun, ring = mesh_phases(PAPER_CASE1)
    assert np.allclose(np.cos(sun), 1.0) and np.allclose(np.cos(ring), 1.0)
    # 21/31/83, 4 planets: sun offset -21 * i * 90 deg, ring 83 * i * 90 deg (mod 360)
    sun, ring = mesh_phases(FOUR_PLANET)
    exp_sun = np.radians([(-21 * 90 * i) % 360 for i in range(4)])
    exp_ring = np.radians([(83 * 90 * i) % 360 for i in range(4)])
    assert np.allclose(sun, exp_sun) and np.allclose(ring, exp_ring)
    assert len({round(float(x), 6) for x in sun}) == 4  # sequential phasing


@pytest.mark.parametrize("gs", [PAPER_CASE1, FOUR_PLANET], ids=lambda g: g.name)
def test_planet_pass_rule_of_mcfadden_and_smith(gs):
    """Identical, equally spaced planets: only carrier orders divisible by N survive."""
    revs = 4
    _, sig = _exact(gs, revs, window="hann", window_deg=100.0)
    o, a = _orders(sig.clean, revs)
    integer = np.isclose(o, np.round(o))
    on_rule = integer & (np.round(o).astype(int) % gs.n_planets == 0)
    assert a[~on_rule].max() < 1e-9 * a.max()
    # the mesh order itself is absent when z_r is not divisible by N (83 with 4 planets):
    # the dominant line is the nearest order divisible by N (McFadden & Smith 1985)
    k = revs * gs.z_ring
    if gs.z_ring % gs.n_planets:
        assert a[k] < 1e-9 * a.max()
        near = [revs * (gs.z_ring - gs.z_ring % 4), revs * (gs.z_ring + 4 - gs.z_ring % 4)]
        assert max(a[near]) > 0.1 * a.max()
    else:
        assert a[k] > 0.1 * a.max()
    # a planet-to-planet amplitude difference breaks the rule (the test can fail)
    _, sig2 = _exact(gs, revs, window="hann", window_deg=100.0)
    spec3, _ = _exact(gs, revs, window="hann", window_deg=100.0)
    sig3 = generate(with_changes(spec3, imperfection=1.0))
    _, a3 = _orders(sig3.clean, revs)
    assert a3[~on_rule].max() > 1e-4 * a3.max()
    assert np.array_equal(sig.clean, sig2.clean)  # deterministic


@pytest.mark.parametrize("gs", [PAPER_CASE1, FOUR_PLANET], ids=lambda g: g.name)
@pytest.mark.parametrize("fault", ["sun_tooth", "planet_tooth", "ring_tooth"])
def test_fault_impacts_at_the_kinematic_fault_frequencies(gs, fault):
    """Impact intervals: sun N (f_s - f_c), planet f_m / z_p per flank, ring N f_c."""
    spec = RecordSpec(gs, fault, speed_rpm=1500.0, duration=4.0, fluctuation=0.0, seed=3)
    sig = generate(spec)
    f_s = 1500.0 / 60.0
    f_c = f_s * gs.z_sun / (gs.z_sun + gs.z_ring)
    f_m = gs.z_ring * f_c
    rate = {"sun_tooth": gs.n_planets * (f_s - f_c), "planet_tooth": 2 * f_m / gs.z_planet,
            "ring_tooth": gs.n_planets * f_c}[fault]
    n_expected = rate * spec.duration
    assert abs(sig.impacts.size - n_expected) <= 2
    if fault == "sun_tooth":  # N impacts per relative sun revolution, one per planet
        period = 1.0 / (f_s - f_c)
        assert np.allclose(np.diff(sig.impacts[:: gs.n_planets]), period, rtol=1e-3)
    if fault == "ring_tooth":  # the planets pass the damaged tooth at their spacing
        assert np.allclose(np.diff(sig.impacts), 1.0 / rate, rtol=1e-3)
    if fault == "planet_tooth":  # ring and sun flanks alternate, half a planet turn apart
        assert np.allclose(np.diff(sig.impacts), 1.0 / rate, rtol=1e-3)


@pytest.mark.parametrize(("fault", "period"), [("sun_tooth", 11), ("planet_tooth", 20),
                                                ("sun_eccentricity", 11), ("ring_tooth", 1)])
def test_fault_modulation_periodicity(fault, period):
    """The AM/FM of a fault repeats with its member's rotation relative to the carrier:
    paper-case1's sun turns 114/33 = 38/11 times per carrier turn (period 11 carrier
    revolutions), a planet 114/40 = 57/20 (period 20); the ring fault keeps the N-fold
    symmetry (only orders divisible by 3)."""
    revs = 2 * period
    _, healthy = _exact(PAPER_CASE1, revs, seed=5)
    _, faulty = _exact(PAPER_CASE1, revs, seed=5, fault=fault)
    o, d = _orders(faulty.clean - healthy.clean, revs)
    total = np.sum(d ** 2)
    on_grid = np.isclose(o * period, np.round(o * period))
    assert np.sum(d[~on_grid] ** 2) < 1e-12 * total
    if fault == "ring_tooth":
        rule = np.isclose(o, np.round(o)) & (np.round(o).astype(int) % 3 == 0)
        assert np.sum(d[~rule] ** 2) < 1e-12 * total
    else:  # content between the integer orders: the member's own period
        frac = ~np.isclose(o, np.round(o))
        assert np.sum(d[frac] ** 2) > 0.3 * total


def test_housing_resonance_rings_at_its_frequency():
    spec = RecordSpec(PAPER_CASE1, "ring_tooth", speed_rpm=1500.0, duration=4.0,
                      resonance_hz=3300.0, resonance_damping=0.04, snr_db=200.0, seed=2)
    with_imp = generate(spec).clean
    without = generate(with_changes(spec, impacts=False)).clean
    r = with_imp - without
    f = np.fft.rfftfreq(r.size, 1 / spec.fs)
    a = np.abs(np.fft.rfft(r))
    sm = np.convolve(a, np.ones(201) / 201, mode="same")
    assert f[np.argmax(sm)] == pytest.approx(3300.0, rel=0.03)


@pytest.mark.parametrize("snr", [10.0, 20.0])
def test_noise_at_the_stated_snr(snr):
    spec = RecordSpec(FOUR_PLANET, "sun_tooth", speed_rpm=1200.0, duration=3.0, snr_db=snr,
                      seed=4)
    sig = generate(spec)
    noise = sig.acceleration - sig.clean
    measured = 10 * math.log10(np.mean(sig.clean ** 2) / np.mean(noise ** 2))
    assert measured == pytest.approx(snr, abs=0.1)
    assert abs(np.mean(noise) / np.std(noise)) < 0.05


def test_speed_fluctuation_and_tacho_through_the_reader(tmp_path):
    from analysis.measurement import load_measurement

    spec = RecordSpec(PAPER_CASE1, "sun_eccentricity", speed_rpm=1500.0, duration=6.0,
                      seed=7)
    sig = generate(spec)
    dev = sig.speed_rpm / 1500.0 - 1.0
    assert np.max(np.abs(dev)) == pytest.approx(0.01, rel=1e-6)  # +-1 %, reached
    # smooth and slow (0.05-0.5 Hz): below 100 min-1/s, where a jump of one sample would give
    # about 15 min-1 * 20 kHz
    assert np.max(np.abs(np.diff(sig.speed_rpm))) * spec.fs < 100.0
    path = write_record(spec, tmp_path / "r.nc")
    m = load_measurement(str(path))
    t = m.speed_rpm["time"].values
    rpm = np.interp(t, sig.time, sig.speed_rpm)
    inner = (t > 0.2) & (t < spec.duration - 0.2)
    err = np.abs(m.speed_rpm.values[inner] / rpm[inner] - 1)
    assert np.max(err) < 2e-3  # the 60-pulse tacho gives the speed within 0.2 %
    x = m.channel("acc")
    assert x.attrs["units"] == "m s-2"
    assert np.allclose(x.values, sig.acceleration)


def test_records_are_deterministic_and_seeded():
    spec = benchmark_records(quick=True)[0]
    a = to_dataset(with_changes(spec, duration=1.0))
    b = to_dataset(with_changes(spec, duration=1.0))
    c = to_dataset(with_changes(spec, duration=1.0, seed=spec.seed + 1))
    assert np.array_equal(a["acc"].values, b["acc"].values)
    assert not np.array_equal(a["acc"].values, c["acc"].values)


def test_benchmark_set():
    recs = benchmark_records()
    faulty = [r for r in recs if r.fault]
    assert len(faulty) == 16 and len(recs) - len(faulty) == 6
    assert {(r.gear_set.name, r.fault, r.severity) for r in faulty} == {
        (g.name, f, s) for g in (PAPER_CASE1, FOUR_PLANET)
        for f in ("sun_tooth", "planet_tooth", "ring_tooth", "sun_eccentricity")
        for s in ("clear", "weak")}
    assert all(10 <= r.snr_db <= 20 for r in recs)
    assert truth(faulty[0])[1] in ("sun", "planet", "ring")
    assert len(benchmark_records(quick=True)) == 3


def test_gearvib_description_of_the_four_planet_set_matches():
    """The TOML given to `gearvib diagnose` has the generator's kinematics."""
    from gearvib.catalogue import gear_set_catalogue
    from gearvib.config import gearset_from_dict, load_config

    cfg, base = load_config(FOUR_PLANET.config)
    cat = gear_set_catalogue(gearset_from_dict(cfg, base=base), reference="carrier",
                             speed_rpm=1000.0, mesh_harmonics=1, harmonics=1, sidebands=0)
    fam = np.asarray(cat.family)
    order = np.asarray(cat.order, float)
    orders = FOUR_PLANET.fault_orders()
    assert order[fam == "mesh"][0] == pytest.approx(orders["mesh"])
    assert order[fam == "sun_fault"][0] == pytest.approx(orders["sun_tooth"])
    assert order[fam == "planet_fault"][0] == pytest.approx(orders["planet_tooth"])
    assert order[fam == "ring_fault"][0] == pytest.approx(orders["ring_tooth"])


def test_bad_input():
    with pytest.raises(ValueError, match="fault"):
        RecordSpec(PAPER_CASE1, "rust")
    with pytest.raises(ValueError, match="speed_rpm"):
        RecordSpec(PAPER_CASE1, speed_rpm=float("nan"))
    with pytest.raises(ValueError, match="planet"):
        RecordSpec(PAPER_CASE1, "planet_tooth", planet=3)
    with pytest.raises(ValueError, match="resonance_hz"):
        RecordSpec(PAPER_CASE1, resonance_hz=12_000.0)
