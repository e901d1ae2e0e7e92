"""Tooth-fault impacts in a diagnosis (gearvib.diagnosis.impacts): the members' fault families
of a real gear-set description checked on records of the independent generator
(tests/independent/planetary_signals.py; no simulation, so fast).

The 4-planet 21/31/83 set at 1200 min-1: the benchmark's clear ring fault (its damaged tooth
148 deg from the sensor, window 0.05: no simulated signature explains it, ``none`` came
first before the impact evidence) and a weak planet fault stand out; healthy records of the
same set show nothing.
"""

import numpy as np
import pytest

from analysis.measurement import load_measurement
from gearvib.config import load_config
from gearvib.diagnosis.candidates import LOCAL_KINDS, candidate_members
from gearvib.diagnosis.impacts import member_impacts
from gearvib.diagnosis.lines import kinematics, member_lines
from tests.independent.planetary_signals import (
    FOUR_PLANET,
    RecordSpec,
    benchmark_records,
    to_dataset,
)


@pytest.fixture(scope="module")
def four_planet():
    cfg, base = load_config(FOUR_PLANET.config)
    kin = kinematics(cfg, base)
    members = candidate_members(kin.gs, kin.model)
    return kin, members, member_lines(kin.cat, kin.ms, members, kin.model)


def _check(spec, four_planet):
    kin, members, lines = four_planet
    m = load_measurement(to_dataset(spec), channel="acc", tacho="tacho")
    rpm = np.abs(np.asarray(m.speed_rpm.values, float)) * kin.ratio("sun")
    check, by = member_impacts(np.asarray(m.channel("acc").values, float), m.fs, rpm,
                               lines=lines, members=members, ms=kin.ms, model=kin.model)
    return check, {mem: e for (kind, mem), e in by.items() if kind == LOCAL_KINDS[0]}


def _benchmark(fault, severity="clear", seed=None):
    return next(s for s in benchmark_records() if s.gear_set is FOUR_PLANET
                and s.fault == fault and s.severity == severity
                and (seed is None or s.seed == seed))


def test_the_benchmark_ring_fault_stands_above_the_mesh_band(four_planet):
    check, ev = _check(_benchmark("ring_tooth"), four_planet)
    assert ev["ring"].method == "synchronous" and ev["ring"].detected, ev["ring"]
    assert ev["ring"].chance < 1e-5
    # the band above the sixth (last) mesh harmonic of the generator
    assert check.band[0] == pytest.approx(6 * 83 + 83 / 2)
    assert not ev["sun"].detected and not ev["planet"].detected


def test_a_weak_planet_fault_stands_in_the_envelope(four_planet):
    spec = RecordSpec(FOUR_PLANET, "planet_tooth", "weak", seed=211, speed_rpm=1200.0,
                      duration=6.0, fluctuation=0.0, snr_db=12.0, sensor_deg=200.0,
                      window="hann", window_deg=120.0, resonance_hz=3000.0, planet=1)
    _, ev = _check(spec, four_planet)
    assert ev["planet"].method == "envelope" and ev["planet"].detected, ev["planet"]
    assert not ev["sun"].detected and not ev["ring"].detected


@pytest.mark.parametrize("seed", [120, 121])
def test_healthy_records_show_no_impacts(four_planet, seed):
    _, ev = _check(_benchmark(None, seed=seed), four_planet)
    assert not any(e.detected for e in ev.values()), ev
    assert min(e.chance for e in ev.values()) > 1e-3


@pytest.mark.parametrize("revolutions", [0.6, 4.9])
def test_a_record_too_short_for_the_check_gives_no_impact_evidence(four_planet, revolutions):
    """Fewer than MIN_REVOLUTIONS + 1 reference revolutions: no check and no evidence (the
    diagnosis goes on without it; tests/gearvib/test_fuzz_python_api.py diagnoses a record of
    0.6 revolutions), rather than the impact check's refusal of the whole diagnosis."""
    kin, members, lines = four_planet
    fs, rpm = 4096.0, 600.0
    n = round(revolutions * 60.0 / rpm * fs)
    x = np.random.default_rng(5).standard_normal(n)
    check, by = member_impacts(x, fs, np.full(n, rpm), lines=lines, members=members,
                               ms=kin.ms, model=kin.model)
    assert check is None and by == {}
    # from 5 revolutions on, the check runs
    n5 = round(5.2 * 60.0 / rpm * fs)
    check, by = member_impacts(np.resize(x, n5), fs, np.full(n5, rpm), lines=lines,
                               members=members, ms=kin.ms, model=kin.model)
    assert check is not None and check.revolutions >= 4 and by
