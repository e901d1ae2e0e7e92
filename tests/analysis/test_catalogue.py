"""Kinematic catalogue from plain numbers: hand-worked formulas and the planet-phasing rule.

The phasing rule (which sidebands reach a sensor on the ring) is checked against a synthetic
housing signal built from first principles: N planets, each carrying its mesh vibration (phase
from the number of ring or sun teeth its contact point has passed) through the same
angle-dependent transfer path to a sensor fixed on the ring.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from analysis.catalogue import (
    FAMILIES,
    RollingBearing,
    ToothMesh,
    kinematic_catalogue,
    phasing_factor,
    simple_planetary_catalogue,
    simple_planetary_speeds,
)


def line(cat, family, harmonic=1, sideband=0, member=None):
    sel = (cat.family == family) & (cat.harmonic == harmonic) & (cat.sideband == sideband)
    if member is not None:
        sel &= cat.member == member
    idx = np.flatnonzero(sel)
    assert idx.size == 1, (family, harmonic, sideband, member, idx)
    return int(idx[0])


def test_paper_case1_against_hand_worked_formulas():
    # z_s = 33, z_r = -114, z_p = 40, 3 planets, ring fixed, sun at 1500 min-1
    cat = simple_planetary_catalogue(33, -114, 40, n_planets=3, speed_rpm=1500.0)
    f = cat.frequency_hz()
    fs = 1500.0 / 60.0
    fc = fs * 33 / 147
    fm = 114 * fc
    assert fm == pytest.approx(639.7959, rel=1e-6)  # paper: 1500 min-1 -> f_mesh ≈ 640 Hz
    assert fm / 1500.0 == pytest.approx(0.4265306, rel=1e-6)  # paper eq. (5), Hz per min-1
    assert f[line(cat, "mesh", 1)] == pytest.approx(fm)
    assert f[line(cat, "mesh", 7)] == pytest.approx(7 * fm)
    assert f[line(cat, "planet_pass", 1)] == pytest.approx(3 * fc)
    assert f[line(cat, "sun_fault", 1)] == pytest.approx(3 * (fs - fc))
    assert f[line(cat, "ring_fault", 1)] == pytest.approx(3 * fc)
    assert f[line(cat, "planet_fault", 1)] == pytest.approx(fm / 40)
    assert f[line(cat, "planet_fault", 2)] == pytest.approx(2 * fm / 40)
    assert f[line(cat, "shaft", 1, member="carrier")] == pytest.approx(fc)
    assert f[line(cat, "shaft", 1, member="planet")] == pytest.approx(abs(fc - fm / 40))
    assert f[line(cat, "shaft", 2, member="sun")] == pytest.approx(2 * fs)
    # hunting tooth: gcd(33, 40) = 1, gcd(114, 40) = 2 (assembly phases)
    assert f[line(cat, "hunting_tooth", member="sun-planet")] == pytest.approx(fm / (33 * 40))
    assert f[line(cat, "hunting_tooth", member="ring-planet")] == pytest.approx(
        fm * 2 / (114 * 40))
    assert f[line(cat, "assembly_phase", member="ring-planet")] == pytest.approx(fm / 2)
    assert not np.any((cat.family == "assembly_phase") & (cat.member == "sun-planet"))
    # sidebands m f_mesh + s f_c; z_s = 33 is a multiple of N = 3: mesh harmonics and the
    # sidebands at multiples of the planet pass reach the ring, the others cancel
    i = line(cat, "sideband", 2, -3)
    assert f[i] == pytest.approx(2 * fm - 3 * fc)
    assert cat.formula[i] == "2 f_mesh − f_pp"
    for k in range(len(cat)):
        if cat.family[k] in ("mesh", "sideband"):
            assert cat.phasing[k] == (1.0 if cat.sideband[k] % 3 == 0 else 0.0)
    # orders are multiples of the sun speed
    assert np.allclose(cat.order, f / fs)
    # one mesh line per harmonic: sun and ring meshes share the frequency
    assert np.sum(cat.family == "mesh") == 7
    assert cat.member[line(cat, "mesh", 1)] == "sun-planet/ring-planet"


def test_speeds_follow_willis_for_every_fixed_member():
    zs, zr, zp = 21, -75, 27
    for fixed, inp in (("ring", "sun"), ("carrier", "sun"), ("sun", "carrier"),
                       ("ring", "carrier")):
        n = simple_planetary_speeds(zs, zr, zp, fixed=fixed, input=inp, input_speed=1.0)
        assert n[fixed] == 0.0 and n[inp] == 1.0
        assert zs * (n["sun"] - n["carrier"]) == pytest.approx(zr * (n["ring"] - n["carrier"]))
        assert zp * (n["planet"] - n["carrier"]) == pytest.approx(
            -zs * (n["sun"] - n["carrier"]))
    # carrier fixed: no planet pass, no carrier sidebands (the planets do not move)
    cat = simple_planetary_catalogue(zs, zr, zp, n_planets=4, fixed="carrier", input="sun",
                                     speed_rpm=600.0)
    assert not np.any(np.isin(cat.family, ["planet_pass", "sideband"]))
    assert any("no planet pass" in n for n in cat.notes)
    fm = cat.frequency_hz()[line(cat, "mesh", 1)]
    assert fm == pytest.approx(21 * 10.0)  # sun at 10 Hz, carrier at rest


def _housing_signal(z_gear: int, angles_deg, harmonic: int, *, sun: bool, n_rev: int = 8,
                    per_rev: int = 4096):
    """Sum over planets of the mesh vibration through a Gaussian window in planet angle.

    Ring fixed, carrier angle phi; the sun turns (1 + |z_r|/z_s) times faster. Returns the
    amplitudes at integer carrier orders (the FFT over ``n_rev`` carrier revolutions) and the
    window's Fourier coefficients.
    """
    phi = 2 * np.pi * np.arange(n_rev * per_rev) / per_rev
    psi = np.radians(np.asarray(angles_deg))
    x = np.zeros(phi.size)
    win = lambda a: np.exp(-0.5 * (np.angle(np.exp(1j * (a - 0.3))) / 0.5) ** 2)  # noqa: E731
    for p in psi:
        if sun:  # teeth of the sun passing the planet's contact point at phi + psi
            z_s, z_r = z_gear
            theta_s = phi * (1 + z_r / z_s)
            mesh = np.cos(harmonic * z_s * (theta_s - phi - p))
        else:  # ring teeth passed by the contact point at phi + psi
            mesh = np.cos(harmonic * abs(z_gear) * (phi + p))
        x += win(phi + p) * mesh
    spec = np.abs(np.fft.rfft(x)) / x.size * 2
    orders = np.arange(spec.size) / n_rev
    w1 = np.fft.fft(win(phi[:per_rev])) / per_rev
    return orders, spec, w1


@pytest.mark.parametrize(("zs", "zr", "zp", "angles"), [
    (21, -75, 27, [0, 90, 180, 270]),        # 4 planets, z_s mod 4 = 1: sequential phasing
    (33, -114, 40, [0, 120, 240]),           # the paper's case 1: in phase
    (32, -98, 33, [0, 72, 144, 216, 288]),   # 5 planets, z_s mod 5 = 2
    (33, -114, 40, [0.0, 50 * 360 / 147, 100 * 360 / 147]),  # the paper's case 2
])
def test_phasing_factor_matches_synthetic_housing_signal(zs, zr, zp, angles):
    n = len(angles)
    cat = simple_planetary_catalogue(zs, zr, zp, planet_angles_deg=angles, speed_rpm=1000.0,
                                     mesh_harmonics=3, sidebands=2)
    fc = cat.member_speeds["carrier"]  # carrier revolutions per sun revolution
    for m in (1, 2, 3):
        for sun in (False, True):
            orders, spec, w1 = _housing_signal((zs, -zr) if sun else zr, angles, m, sun=sun)
            top = spec.max()
            sel = np.isin(cat.family, ["mesh", "sideband"]) & (cat.harmonic == m)
            for k in np.flatnonzero(sel):
                carrier_order = cat.order[k] / fc
                c = round(carrier_order)
                assert carrier_order == pytest.approx(c, abs=1e-9)
                amp = spec[np.argmin(np.abs(orders - c))]
                q = c - m * abs(zr)  # window harmonic that carries the line
                expected = abs(w1[q % w1.size]) * n * cat.phasing[k]  # peak amplitude
                assert amp == pytest.approx(expected, abs=1e-6 * top), (m, sun, c)
    if np.allclose(np.diff(angles), 360.0 / n):
        vis = cat.select(families=["mesh", "sideband"], visible_only=True)
        # equal spacing: exactly the carrier orders divisible by N survive
        assert np.allclose((np.round(vis.order / fc)) % n, 0)


def test_four_planet_sequential_set_cancels_the_mesh_fundamental():
    cat = simple_planetary_catalogue(21, -75, 27, n_planets=4, speed_rpm=1000.0)
    assert cat.phasing[line(cat, "mesh", 1)] == 0.0
    assert cat.phasing[line(cat, "mesh", 4)] == 1.0
    # the dominant survivor next to f_mesh is one carrier order above (21 = 1 mod 4)
    assert cat.phasing[line(cat, "sideband", 1, 1)] == 1.0
    assert cat.phasing[line(cat, "sideband", 1, -3)] == 1.0
    assert cat.formula[line(cat, "sideband", 1, 1)] == "f_mesh + 1 f_c"
    assert cat.formula[line(cat, "sideband", 1, 4)] == "f_mesh + f_pp"
    js = json.loads(cat.to_json())
    fams = {x["family"] for x in js["lines"]}
    assert "mesh" in fams and "sideband" in fams
    assert not any(x["family"] == "mesh" and x["harmonic"] == 1 for x in js["lines"])


def test_bearing_defect_frequencies():
    # inner ring on the sun shaft, outer ring in the housing: textbook formulas
    b = RollingBearing("input bearing", inner="sun", outer="ground", n_rolling=9,
                       rolling_diameter=7.94e-3, pitch_diameter=39.04e-3,
                       contact_angle_deg=0.0)
    cat = simple_planetary_catalogue(33, -114, 40, n_planets=3, speed_rpm=1800.0, bearings=[b])
    f = cat.frequency_hz()
    fr, g = 30.0, 7.94 / 39.04
    assert f[line(cat, "bearing_ftf")] == pytest.approx(fr / 2 * (1 - g))
    assert f[line(cat, "bearing_bpfo")] == pytest.approx(9 * fr / 2 * (1 - g))
    assert f[line(cat, "bearing_bpfi")] == pytest.approx(9 * fr / 2 * (1 + g))
    assert f[line(cat, "bearing_bsf")] == pytest.approx(39.04 / (2 * 7.94) * fr * (1 - g * g))
    # planet bearing: inner = carrier pin, outer = planet -> relative speed f_mesh / z_p
    pb = RollingBearing("planet bearing", inner="carrier", outer="planet1", n_rolling=12,
                        rolling_diameter=6e-3, pitch_diameter=30e-3, contact_angle_deg=15.0)
    cat = simple_planetary_catalogue(33, -114, 40, n_planets=3, speed_rpm=1800.0,
                                     bearings=[pb])
    fm = cat.frequency_hz()[line(cat, "mesh", 1)]
    g = 6 / 30 * math.cos(math.radians(15))
    assert cat.frequency_hz()[line(cat, "bearing_bpfo")] == pytest.approx(
        12 * fm / 40 / 2 * (1 - g))
    with pytest.raises(ValueError, match="rolling_diameter"):
        RollingBearing("x", "sun", "ground", 9, 0.05, 0.04)
    with pytest.raises(ValueError, match="n_rolling"):
        RollingBearing("x", "sun", "ground", 2, 0.005, 0.04)


def test_dataset_runup_and_json_shape():
    speeds = np.linspace(0.0, 4000.0, 5)
    cat = simple_planetary_catalogue(33, -114, 40, n_planets=3, speed_rpm=1500.0,
                                     speeds_rpm=speeds)
    ds = cat.to_dataset()
    for name, var in ds.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
    assert ds["frequency_runup"].dims == ("line", "speed")
    i = line(cat, "mesh", 2)
    assert ds["frequency_runup"].values[i, -1] == pytest.approx(2 * 0.4265306 * 4000, rel=1e-6)
    assert set(ds.family.values) <= set(FAMILIES)
    d = json.loads(cat.to_json())
    assert set(d) == {"reference", "lines"}
    assert d["reference"] == {"member": "sun", "speed_rpm": 1500.0}
    assert all(set(x) == {"family", "harmonic", "sideband", "member", "frequency_hz", "order",
                          "phasing"} for x in d["lines"])
    assert len(d["lines"]) == int(cat.visible.sum())
    # the phasing factor of every visible line, null where it does not apply
    vis = cat.select(visible_only=True)
    for x, ph in zip(d["lines"], vis.phasing, strict=True):
        assert (x["phasing"] is None) == bool(np.isnan(ph))
        assert x["phasing"] is None or x["phasing"] == pytest.approx(ph)
    assert "family" in cat.table() and "mesh" in str(cat)
    from matplotlib.figure import Figure

    assert isinstance(cat.plot(frequency_max=3000.0), Figure)


def test_phasing_factor_values():
    assert phasing_factor(np.radians([0, 120, 240]), 3) == 1.0
    assert phasing_factor(np.radians([0, 120, 240]), 1) == 0.0
    psi = np.radians([0.0, 122.449, 244.898])
    # the paper's case 2, first mesh harmonic: in-phase content 0.440 (physics notes)
    assert phasing_factor(psi, -33) == pytest.approx(0.440, abs=1e-3)
    assert math.isnan(phasing_factor([], 1))


def test_bad_input_names_the_parameter():
    meshes = [ToothMesh("sun-p1", "sun", "p1", 20, 30, "carrier")]
    with pytest.raises(ValueError, match="reference"):
        kinematic_catalogue({"sun": 1.0, "p1": 0.1, "carrier": 0.2}, meshes, reference="x")
    with pytest.raises(ValueError, match="at rest"):
        kinematic_catalogue({"sun": 0.0, "p1": 0.1, "carrier": 0.2}, meshes, reference="sun")
    with pytest.raises(ValueError, match="'carrier' has no speed"):
        kinematic_catalogue({"sun": 1.0, "p1": 0.1}, meshes, reference="sun")
    with pytest.raises(ValueError, match="fixed member 'sun' has speed"):
        kinematic_catalogue({"sun": 1.0, "p1": 0.1, "carrier": 0.2}, meshes, reference="sun",
                            fixed="sun")
    with pytest.raises(ValueError, match="mesh_harmonics"):
        kinematic_catalogue({"sun": 1.0, "p1": 0.1, "carrier": 0.2}, meshes, reference="sun",
                            mesh_harmonics=0)
    with pytest.raises(ValueError, match="z_gear"):
        ToothMesh("m", "a", "b", 0, 10, "c")
    with pytest.raises(ValueError, match="z_ring"):
        simple_planetary_catalogue(33, 114, 40, n_planets=3)
    with pytest.raises(ValueError, match="cannot be assembled"):
        simple_planetary_catalogue(32, -96, 32, n_planets=5)
    with pytest.raises(ValueError, match="families"):
        simple_planetary_catalogue(33, -114, 40, n_planets=3).select(families=["nope"])
    with pytest.raises(ValueError, match="speed_rpm"):
        simple_planetary_catalogue(33, -114, 40, n_planets=3).frequency_hz()


def test_eccentricity_sidebands_of_paper_case1():
    # z_s = 33, z_r = -114, z_p = 40, ring fixed: an eccentric sun or planet modulates the mesh
    # at its rotation relative to the carrier, shifted by the carrier (the planets pass the
    # sensor) to its rotation relative to the housing; the ring's (fixed) equals the carrier
    # sideband s = ±1 and is not listed again
    cat = simple_planetary_catalogue(33, -114, 40, n_planets=3, speed_rpm=1500.0)
    f = cat.frequency_hz()
    fs = 1500.0 / 60.0
    fc = fs * 33 / 147
    fm = 114 * fc
    fp = fc - fm / 40  # planet speed (absolute, signed)
    ecc = cat.family == "eccentricity"
    want = sorted(m * fm + s * r for m in range(1, 8) for s in (-1, 1) for r in (fs, fs - fc))
    assert np.allclose(sorted(f[ecc & (cat.member == "sun")]), want)
    got_p = sorted(f[ecc & (cat.member == "planet")])
    want_p = sorted(m * fm + s * r for m in range(1, 8) for s in (-1, 1)
                    for r in (abs(fp), fm / 40))
    assert np.allclose(got_p, want_p)
    assert set(cat.member[ecc]) == {"sun", "planet"}
    i = np.flatnonzero(ecc & (cat.member == "sun") & (cat.harmonic == 2)
                       & (cat.sideband == 1))
    assert sorted(cat.formula[i]) == ["2 f_mesh + f_sun", "2 f_mesh + |f_sun − f_carrier|"]
    assert "eccentricity" in FAMILIES
