"""Tests of analysis.planetary_tsa: McFadden's separation of the planets and the sun.

The generator below is written from the physics, independently of the implementation: a ring
fixed, a carrier turning at ``carrier_hz (1 + 1 % sin)``, N planets at ``psi_p``; a sensor on
the ring hears planet ``p``'s meshes through a planet-pass window ``T_p = (1/2 (1 + cos(theta_c
+ psi_p - sensor)))^sharpness`` (McFadden & Smith's explanation of the modulation). Each planet's
ring mesh cycles with the ring teeth passed, ``n_p = z_r (theta_c + psi_p) / 2 pi`` (mesh phase
``z_r psi_p / 2 pi``, Parker & Lin 2004); a damaged planet tooth ``k`` (body tooth ``k`` of the
planet meshes while ``floor(n_p) = k mod z_p``) adds a short bump once per planet revolution; a
damaged sun tooth ``k`` adds one each time it faces a planet (sun body coordinate facing planet
``p``: ``psi_p - (z_r / z_s) theta_c``).
"""

from __future__ import annotations

import numpy as np
import pytest

from analysis.gear_signals import gear_signals
from analysis.indicators import fm4
from analysis.planetary_tsa import PlanetarySeparation, planetary_tsa

FS = 8192.0
ZS, ZP, ZR, NP = 21, 31, 83, 4
SENSOR = 0.3


def record(
    seed: int = 0, *, zs: int = ZS, zp: int = ZP, zr: int = ZR, n_planets: int = NP,
    revolutions: int = 40, carrier_hz: float = 4.0, fault: tuple | None = ("planet", 2, 7),
    amp: float = 0.8, noise: float = 0.5, sharpness: int = 4,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """``(x, theta_c)``: a ring-sensor signal and the carrier angle."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(revolutions / carrier_hz * FS)) / FS
    fm = 0.7
    theta = 2 * np.pi * carrier_hz * (t + 0.01 * np.sin(2 * np.pi * fm * t) / (2 * np.pi * fm))
    psi = 2 * np.pi * np.arange(n_planets) / n_planets
    x = np.zeros_like(t)
    for p in range(n_planets):
        window = (0.5 * (1 + np.cos(theta + psi[p] - SENSOR))) ** sharpness
        n_ring = zr * (theta + psi[p]) / (2 * np.pi)
        s = np.cos(2 * np.pi * n_ring + 0.3) + 0.4 * np.cos(4 * np.pi * n_ring - 1.0)
        if fault is not None and fault[0] == "planet" and fault[1] == p:
            d = np.mod(n_ring - fault[2] - 0.5 + zp / 2, zp) - zp / 2  # teeth from mid-tooth k
            s = s + amp * np.exp(-0.5 * (d / 0.12) ** 2)
        if fault is not None and fault[0] == "sun":
            body = zs * (psi[p] - zr / zs * theta) / (2 * np.pi)  # sun tooth facing planet p
            d = np.mod(body - fault[1] - 0.5 + zs / 2, zs) - zs / 2
            s = s + amp * np.exp(-0.5 * (d / 0.12) ** 2)
        x += window * s
    return x + noise * rng.normal(size=t.size), theta


def separate(x: np.ndarray, theta: np.ndarray, **kw) -> PlanetarySeparation:
    args = {"z_sun": ZS, "z_planet": ZP, "z_ring": ZR, "n_planets": NP, "sensor_angle": SENSOR}
    return planetary_tsa(x, FS, angle=theta, **{**args, **kw})


def _fm4(tsa, teeth) -> float:
    return float(fm4(gear_signals(tsa, teeth).difference))


def test_damaged_planet_found_and_located():
    """Over 6 seeds: the damaged planet's FM4 > 4.5, every other planet's < 3.8, and its
    difference signal peaks at the damaged tooth (mid-tooth 7.5) within 0.25 tooth."""
    for seed in range(6):
        x, theta = record(seed)
        sep = separate(x, theta)
        values = [_fm4(p, ZP) for p in sep.planets]
        assert values[2] > 4.5, (seed, values)
        assert max(values[:2] + values[3:]) < 3.8, (seed, values)
        d = gear_signals(sep.planets[2], ZP).difference
        tooth = sep.planets[2].angle[np.argmax(d)] * ZP / (2 * np.pi)
        assert tooth == pytest.approx(7.5, abs=0.25), (seed, tooth)
        # the planet's bumps are not synchronous with the sun: partly averaged out there
        assert _fm4(sep.sun, ZS) < values[2]


def test_noise_free_signature_recovered():
    """Without noise the damaged planet's average minus a healthy planet's is the bump of the
    generator, scaled by the mean of the planet-pass window under the analysis window."""
    x, theta = record(noise=0.0)
    sep = separate(x, theta)
    p3, p1 = sep.planets[2], sep.planets[0]
    tooth = p3.angle * ZP / (2 * np.pi)
    diff = p3.values - p1.values
    d = np.mod(tooth - 7.5 + ZP / 2, ZP) - ZP / 2
    bump = np.exp(-0.5 * (d / 0.12) ** 2)
    # expected gain: the Hann analysis window (width W ring pitches) times the transfer window
    rho = np.linspace(-0.5, 0.5, 20001) * sep.window_teeth * 2 * np.pi / ZR  # carrier angle
    w = np.cos(np.pi * np.linspace(-0.5, 0.5, 20001)) ** 2
    gain = np.sum(w * (0.5 * (1 + np.cos(rho))) ** 4) / np.sum(w)
    fit = np.dot(diff, bump) / np.dot(bump, bump)
    assert fit == pytest.approx(0.8 * gain, rel=0.05)
    assert np.corrcoef(diff, bump)[0, 1] > 0.98
    # "place it by the tooth then in mesh": every planet's mesh line at the same phase
    phases = [np.angle(np.fft.rfft(p.values)[ZP]) for p in sep.planets]
    assert np.ptp(phases) < 0.02
    assert phases[0] == pytest.approx(0.3, abs=0.02)  # the generator's mesh phase
    assert all(p.coverage == 1.0 for p in sep.planets)


def test_tukey_window():
    """The Tukey window (half flat) sees more of each pass: more effective averages than the
    Hann window of the same width, and the same diagnosis."""
    x, theta = record(0)
    hann, tukey = separate(x, theta), separate(x, theta, window="tukey")
    assert tukey.window == "tukey"
    values = [_fm4(p, ZP) for p in tukey.planets]
    assert values[2] > 4.5 and max(values[:2] + values[3:]) < 3.8
    assert tukey.planets[0].effective_averages > 1.2 * hann.planets[0].effective_averages
    assert all(p.coverage == 1.0 for p in tukey.planets)


def test_damaged_sun_tooth_found():
    x, theta = record(1, fault=("sun", 5), amp=0.6)
    sep = separate(x, theta)
    assert _fm4(sep.sun, ZS) > 6.0
    assert max(_fm4(p, ZP) for p in sep.planets) < 3.8
    d = gear_signals(sep.sun, ZS).difference
    pos = sep.sun.angle[np.argmax(d)] * ZS / (2 * np.pi)
    # the sun axis counts teeth in the order they enter the mesh: body tooth 5 (mid 5.5)
    # appears at ZS - 5.5
    assert pos == pytest.approx(ZS - 5.5, abs=0.25)
    assert sep.sun.revolutions == NP * sep.carrier_revolutions


def test_passes_and_noise_reduction_stated():
    x, theta = record(3)
    sep = separate(x, theta)
    assert sep.carrier_revolutions >= 38
    assert np.all(sep.passes == sep.carrier_revolutions)
    assert sep.planet_cycle == 31 and sep.sun_cycle == 21
    assert np.all(sep.complete_cycles == sep.passes // 31)
    for p in sep.planets:
        assert p.revolutions == sep.carrier_revolutions
        # Hann windows 20 pitches wide, passes 21 teeth apart on a 31-tooth planet: each tooth
        # is under about 20/31 of the passes, n_eff = n (mean w)^2 / mean w^2 = n / 1.5
        assert p.effective_averages == pytest.approx(sep.passes[0] * 20 / 31 / 1.5, rel=0.08)
        assert p.noise_reduction == pytest.approx(1 / np.sqrt(p.effective_averages))
        assert any("closed" in note for note in p.notes)
        # the rms of the samples about the average: the noise (0.5) seen through the window
        assert 0.45 < float(p.nonsynchronous_rms) < 0.6


def test_cycle_not_closed_is_reported():
    """5 carrier revolutions with 4-pitch windows cannot see all 31 teeth of a planet."""
    x, theta = record(revolutions=9)
    sep = separate(x, theta, revolutions=5, window_teeth=4)
    # the 5 window centres fall on planet teeth c, c + 21, c + 11, c + 1, c + 22 (83 = 21 mod
    # 31): 4-tooth windows there span 14 of 31 teeth, of which those where the summed Hann
    # weight reaches 5 % of its maximum count as observed (about 12)
    for p in sep.planets:
        assert p.revolutions == 5
        assert 0.3 < p.coverage < 14 / 31 + 0.05
        assert np.isnan(p.values).mean() == pytest.approx(1 - p.coverage)
        assert any("not closed (5 < 31)" in note for note in p.notes)
        with pytest.raises(ValueError, match="NaN"):
            gear_signals(p, ZP)


def test_common_factor_of_ring_and_planet_teeth():
    """z_ring = 84, z_planet = 30 (gcd 6): the placement repeats after 5 passes; the default
    window (3 x 6 = 18 pitches) still covers every tooth and the fault is found."""
    zs, zp, zr = 24, 30, 84
    x, theta = record(2, zs=zs, zp=zp, zr=zr, fault=("planet", 1, 12))
    sep = planetary_tsa(x, FS, angle=theta, z_sun=zs, z_planet=zp, z_ring=zr, n_planets=4,
                        sensor_angle=SENSOR)  # fmt: skip
    assert sep.planet_cycle == 5
    assert sep.window_teeth == 18
    assert all(p.coverage == 1.0 for p in sep.planets)
    values = [_fm4(p, zp) for p in sep.planets]
    assert values[1] > 4.5 and max(values[:1] + values[2:]) < 3.8


def test_reference_of_another_shaft_and_tacho():
    """A 30-pulse tacho on the sun shaft with ratio z_s / (z_s + z_r) gives the same averages
    as the carrier angle (the sun turns (z_s + z_r) / z_s times as fast as the carrier), once
    the planet angles are given from the reference's zero (its first pulse)."""
    x, theta = record(4)
    ref = separate(x, theta)
    sun_angle = theta * (ZS + ZR) / ZS - np.pi / 30  # first pulse: sun angle 0, half a pitch in
    frac = np.mod(sun_angle * 30 / (2 * np.pi) + 0.5, 1.0) - 0.5
    tacho = np.where(frac < 0.4, np.clip(0.5 + frac / 0.2, 0, 1), 0.0)
    carrier_zero = np.pi / 30 * ZS / (ZS + ZR)  # carrier angle at that pulse
    psi = 2 * np.pi * np.arange(NP) / NP + carrier_zero
    sep = planetary_tsa(x, FS, tacho=tacho, pulses_per_rev=30, ratio=ZS / (ZS + ZR), z_sun=ZS,
                        z_planet=ZP, z_ring=ZR, planet_angles=psi, sensor_angle=SENSOR)  # fmt: skip
    for a, b in zip(ref.planets, sep.planets, strict=True):
        assert np.corrcoef(a.values, b.values)[0, 1] > 0.97


def test_dataset_and_figure():
    x, theta = record(5)
    sep = separate(x, theta)
    ds = sep.to_dataset()
    assert ds["planet_tsa"].shape == (NP, ZP * sep.samples_per_tooth)
    assert ds["sun_tsa"].shape == (ZS * sep.samples_per_tooth,)
    for v in [*ds.data_vars, *ds.coords]:
        assert "long_name" in ds[v].attrs and "units" in ds[v].attrs, v
    assert ds.attrs["window"] == "hann" and ds.attrs["window_teeth"] == 20
    fig = sep.plot()
    assert len(fig.axes) == NP + 1 and all(ax.lines for ax in fig.axes)
    assert sep.planet(3) is sep.planets[2]
    with pytest.raises(ValueError, match="p = 9"):
        sep.planet(9)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"z_ring": 20}, ValueError, "z_ring"),
        ({"z_sun": 2}, ValueError, "z_sun"),
        ({"z_planet": 31.0}, ValueError, "z_planet"),
        ({"z_planet": True}, ValueError, "z_planet"),
        ({"n_planets": None}, ValueError, "n_planets"),
        ({"planet_angles": [0.0, np.nan]}, ValueError, "planet_angles"),
        ({"planet_angles": ["0", "1"]}, TypeError, "planet_angles"),
        ({"planet_angles": [0.0, 1.0, 2.0]}, ValueError, "n_planets"),
        ({"window": "rectangular"}, ValueError, "window"),
        ({"window_teeth": 0.0}, ValueError, "window_teeth"),
        ({"window_teeth": "4"}, TypeError, "window_teeth"),
        ({"samples_per_tooth": 2}, ValueError, "samples_per_tooth"),
        ({"sensor_angle": np.inf}, ValueError, "sensor_angle"),
        ({"sensor_angle": "0"}, TypeError, "sensor_angle"),
        ({"revolutions": 10_000}, ValueError, "revolutions"),
        ({"revolutions": 0}, ValueError, "revolutions"),
    ],
)
def test_bad_input_is_named(kwargs, error, match):
    x, theta = record(revolutions=6, noise=0.1)
    with pytest.raises(error, match=match):
        separate(x, theta, **kwargs)


def test_too_short_record():
    x, theta = record(revolutions=1, noise=0.1)
    with pytest.raises(ValueError, match="too few carrier revolutions"):
        separate(x, theta)
