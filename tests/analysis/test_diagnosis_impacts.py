"""Tooth-fault impact evidence (analysis.diagnosis_impacts): the fault rate in the squared
envelope without the mesh lattice, the comb above the mesh band, and what must not count.

Every record is built here from closed forms: a mesh at order 37 with five harmonics,
amplitude-modulated at the planet pass (order 3, three planets), impulses through a housing
resonance at a fault order, white noise; the speed a slow ramp of the reference shaft.
"""

import math

import numpy as np
import pytest
from scipy import signal as sps

from analysis.diagnosis_impacts import (
    IMPACT_CHANCE,
    MIN_RELATIVE_DB,
    ImpactCheck,
    ImpactFamily,
    impact_check,
)

FS = 8000.0
MESH = 37.0
PLANET = ImpactFamily("planet_fault", MESH / 13.0)  # 2.846 orders: not a shaft order
SUN = ImpactFamily("sun_fault", 7.4)
RING = ImpactFamily("ring_fault", 3.0)  # a whole order: the comb above the mesh band
KNOWN = [1.0, 5.9]  # carrier and sun in the fixed frame
SPAN = 6.0


def _angle(duration, rpm0=600.0, rpm1=630.0):
    t = np.arange(round(duration * FS)) / FS
    rpm = rpm0 + (rpm1 - rpm0) * t / t[-1]
    theta = 2 * np.pi / 60.0 * np.concatenate(([0.0], np.cumsum(0.5 * (rpm[1:] + rpm[:-1])
                                                                   / FS)))
    return t, rpm, theta


def _mesh(theta, depth=0.5):
    x = np.zeros_like(theta)
    for h in range(1, 6):
        x += 0.6 ** (h - 1) * np.cos(h * MESH * theta + 0.7 * h)
    return (1.0 + depth * np.cos(3.0 * theta)) * x


def _impacts(t, theta, order, size, resonance=2500.0, zeta=0.05):
    """Impulses at every crossing of ``order * theta`` over a multiple of 2 pi, ringing a
    second-order resonance (peak ~ size)."""
    k = np.floor(order * theta / (2 * np.pi))
    hit = np.nonzero(np.diff(k) > 0)[0] + 1
    pulses = np.zeros_like(t)
    pulses[hit] = size
    wn = 2 * np.pi * resonance
    r = math.exp(-zeta * wn / FS)
    wd = wn * math.sqrt(1 - zeta ** 2)
    b, a = [0.0, r * math.sin(wd / FS)], [1.0, -2 * r * math.cos(wd / FS), r * r]
    return sps.lfilter(b, a, pulses)


def _check(x, rpm, families=(PLANET, SUN, RING)):
    return impact_check(x, FS, rpm, mesh_orders=[MESH], families=list(families),
                        known_orders=KNOWN, span=SPAN)


def _by(check):
    return {e.family: e for e in check.evidence}


def test_the_impacts_of_a_fault_order_stand_in_the_envelope():
    t, rpm, theta = _angle(4.0)
    rng = np.random.default_rng(1)
    x = _mesh(theta) + _impacts(t, theta, PLANET.fundamental, 1.0)
    x += 0.3 * rng.standard_normal(t.size)
    ev = _by(_check(x, rpm))
    assert ev["planet_fault"].method == "envelope"
    assert ev["planet_fault"].detected and ev["planet_fault"].chance < 1e-8
    assert ev["planet_fault"].relative_db > MIN_RELATIVE_DB
    assert not ev["sun_fault"].detected and ev["sun_fault"].chance > 1e-3


def test_a_synchronous_comb_above_the_mesh_band_under_the_noise():
    # impacts three times per revolution (a ring fault passed by three planets) ringing a
    # resonance far above the five mesh harmonics, 15 dB under the noise in its band
    t, rpm, theta = _angle(6.0)
    rng = np.random.default_rng(2)
    imp = _impacts(t, theta, 3.0, 0.2)
    noise = 0.3 * rng.standard_normal(t.size)
    f, p_imp = sps.welch(imp, FS, nperseg=4096)
    _, p_noise = sps.welch(noise, FS, nperseg=4096)
    band = (f > 2200) & (f < 2800)
    assert 10 * np.log10(p_imp[band].sum() / p_noise[band].sum()) < -12.0
    check = _check(_mesh(theta) + imp + noise, rpm)
    ring = _by(check)["ring_fault"]
    assert ring.method == "synchronous" and ring.detected and ring.chance < 1e-6
    # the band starts half a mesh order above the fifth harmonic
    assert check.band[0] == pytest.approx(5 * MESH + MESH / 2)
    assert check.order.min() >= check.band[0]


def test_a_healthy_gearbox_with_planet_pass_modulation_shows_no_impacts():
    t, rpm, theta = _angle(4.0)
    rng = np.random.default_rng(3)
    for depth in (0.3, 0.9):
        x = _mesh(theta, depth) + 0.3 * rng.standard_normal(t.size)
        ev = _by(_check(x, rpm))
        assert not any(e.detected for e in ev.values()), ev
        assert min(e.chance for e in ev.values()) > 1e-3, ev


def test_mesh_harmonics_up_to_the_top_leave_no_synchronous_band():
    t, rpm, theta = _angle(4.0)
    x = np.zeros_like(theta)
    for h in range(1, 9):  # up to order 296, beyond the top order 297.6 / 1.05 ...
        x += np.cos(h * MESH * theta)
    x += 0.01 * np.random.default_rng(4).standard_normal(t.size)
    check = _check(x, rpm)
    assert check.order.size == 0 or check.band[1] - check.band[0] < MESH
    assert _by(check)["ring_fault"].lines == 0 and not _by(check)["ring_fault"].detected


def test_a_periodicity_far_below_the_shaft_modulation_is_significant_but_not_detected():
    # broadband vibration strongly modulated at the planet pass, weakly at the fault order:
    # the fault-order lines stand out of the noise but 25 dB under the planet-pass line
    t, rpm, theta = _angle(6.0)
    rng = np.random.default_rng(5)
    mod = 1.0 + 0.9 * np.cos(3.0 * theta) + 0.05 * sum(
        np.cos(k * PLANET.fundamental * theta) for k in range(1, 11))
    x = _mesh(theta) + mod * rng.standard_normal(t.size)
    planet = _by(_check(x, rpm))["planet_fault"]
    assert planet.chance < IMPACT_CHANCE
    assert planet.relative_db < MIN_RELATIVE_DB
    assert not planet.detected


def test_false_positive_rate_on_noise():
    # white noise at a ramp: the Gamma bound must hold (chance <= p in about a fraction p of
    # the checks: 1000 records gave 4.5-6.4 % at 0.05 and 0.8-1.8 % at 0.01 per family; the
    # bounds below allow for the binomial spread of 300 checks); nothing detected
    t, rpm, _theta = _angle(2.0)
    rng = np.random.default_rng(6)
    chances = []
    for _ in range(100):
        check = _check(rng.standard_normal(t.size), rpm)
        chances += [e.chance for e in check.evidence if e.lines]
        assert not any(e.detected for e in check.evidence)
    chances = np.asarray(chances)
    assert chances.size >= 250
    assert np.mean(chances <= 0.05) <= 0.10
    assert np.mean(chances <= 0.01) <= 0.03


def test_dataset_and_figure():
    from matplotlib.figure import Figure

    t, rpm, theta = _angle(4.0)
    x = _mesh(theta) + _impacts(t, theta, PLANET.fundamental, 1.0) + 0.3 * np.random.default_rng(
        7).standard_normal(t.size)
    check = _check(x, rpm)
    assert isinstance(check, ImpactCheck)
    ds = check.to_dataset()
    for name in ("envelope_ratio", "order_ratio", "chance", "relative_level", "detected"):
        assert "units" in ds[name].attrs and "long_name" in ds[name].attrs
    assert list(ds["family"].values) == ["planet_fault", "sun_fault", "ring_fault"]
    assert ds.attrs["Conventions"].startswith("CF")
    assert int(ds["detected"].sel(family="planet_fault")) == 1
    assert isinstance(check.plot(), Figure)
    assert "detected" in check.evidence[0].text()


@pytest.mark.parametrize("kw, match", [
    ({"fs": 0.0}, "fs"),
    ({"fs": float("nan")}, "fs"),
    ({"span": -1.0}, "span"),
    ({"harmonics": 0}, "harmonics"),
    ({"harmonics": True}, "harmonics"),
    ({"cap": 1.0}, "cap"),
    ({"mesh_orders": []}, "mesh_orders"),
    ({"mesh_orders": [-3.0]}, "mesh_orders"),
    ({"known_orders": ["a"]}, "known_orders"),
])
def test_bad_parameters_are_refused(kw, match):
    _t, rpm, theta = _angle(2.0)
    args = {"fs": FS, "mesh_orders": [MESH], "families": [PLANET], "span": SPAN}
    args.update(kw)
    with pytest.raises((ValueError, TypeError), match=match):
        impact_check(np.sin(theta), args.pop("fs"), rpm, **args)


def test_bad_records_and_families_are_refused():
    _t, rpm, theta = _angle(2.0)
    x = np.sin(theta)
    with pytest.raises(ValueError, match="one value per sample"):
        impact_check(x, FS, rpm[:-1], mesh_orders=[MESH], families=[PLANET])
    with pytest.raises(ValueError, match="> 0"):
        impact_check(x, FS, -rpm, mesh_orders=[MESH], families=[PLANET])
    with pytest.raises(ValueError, match="revolutions"):
        impact_check(x[:2000], FS, rpm[:2000], mesh_orders=[MESH], families=[PLANET])
    with pytest.raises(TypeError, match="ImpactFamily"):
        impact_check(x, FS, rpm, mesh_orders=[MESH], families=[("planet", 2.8)])
    with pytest.raises(ValueError, match="fundamental"):
        ImpactFamily("x", 0.0)
    with pytest.raises(ValueError, match="non-finite"):
        impact_check(np.full_like(x, np.nan), FS, rpm, mesh_orders=[MESH], families=[PLANET])
