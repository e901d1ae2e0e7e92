"""Tests of gearvib.geometry: contact ratios, assembly conditions, mesh phasing."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from gearvib.geometry import (
    Toothing,
    admissible_planet_angles,
    check_planet_angles,
    inverse_involute,
    mesh_geometry,
    mesh_phases,
    minimum_offset_angle,
    planet_mesh_offsets,
    planet_profile_shift,
    planet_tooth_number,
    planetary_meshes,
    sun_ring_phase,
)

M = 1e-3  # module 1 mm


def tooth(z: int, **kw) -> Toothing:
    return Toothing(z=z, module=kw.pop("module", M), **kw)


# --- contact ratios ------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("z1", "z2", "eps"),
    [(20, 20, 1.557), (33, 40, 1.694), (-114, 40, 1.925), (40, -114, 1.925)],
)
def test_contact_ratio_sanity_values(z1, z2, eps):
    # physics.md 3.2 sanity values (m = 1, alpha = 20°, x = 0, standard addendum)
    g = mesh_geometry(tooth(z1), tooth(z2))
    assert g.contact_ratio == pytest.approx(eps, abs=5e-4)
    assert g.internal == (z1 < 0 or z2 < 0)
    assert g.working_pressure_angle == pytest.approx(math.radians(20.0), abs=1e-12)
    assert g.centre_distance == pytest.approx(abs(z1 + z2) * M / 2, rel=1e-12)


def test_external_contact_ratio_closed_form_with_shift_and_centre_distance():
    g1, g2 = tooth(17, profile_shift=0.3), tooth(53, profile_shift=-0.1)
    a = 35.4e-3
    g = mesh_geometry(g1, g2, a)
    aw = math.acos(35e-3 * math.cos(math.radians(20)) / a)
    rb1, rb2 = 8.5e-3 * math.cos(math.radians(20)), 26.5e-3 * math.cos(math.radians(20))
    ra1, ra2 = 8.5e-3 + 1.3e-3, 26.5e-3 + 0.9e-3
    expected = (math.sqrt(ra1**2 - rb1**2) + math.sqrt(ra2**2 - rb2**2) - a * math.sin(aw)) / (
        math.pi * M * math.cos(math.radians(20))
    )
    assert g.working_pressure_angle == pytest.approx(aw, rel=1e-12)
    assert g.contact_ratio == pytest.approx(expected, rel=1e-12)
    assert g.circumferential_backlash > 0


def test_helical_overlap_ratio_and_transverse_equivalence():
    beta = math.radians(15.0)
    b = 0.025
    g1 = Toothing(23, 2e-3, helix_angle=beta, face_width=b, profile_shift=0.2)
    g2 = Toothing(61, 2e-3, helix_angle=-beta, face_width=0.03, profile_shift=0.1)
    g = mesh_geometry(g1, g2)
    assert g.overlap_ratio == pytest.approx(b * math.sin(beta) / (math.pi * 2e-3), rel=1e-12)
    assert g.total_contact_ratio == pytest.approx(g.contact_ratio + g.overlap_ratio)
    # the transverse section is a spur gear with module m_t, pressure angle alpha_t and
    # addendum, dedendum, profile shift scaled by cos(beta) (same lengths)
    mt, at = 2e-3 / math.cos(beta), g1.transverse_pressure_angle
    c = math.cos(beta)
    s1 = Toothing(23, mt, pressure_angle=at, addendum=c, dedendum=1.25 * c, profile_shift=0.2 * c)
    s2 = Toothing(61, mt, pressure_angle=at, addendum=c, dedendum=1.25 * c, profile_shift=0.1 * c)
    # the profile-shift formula uses tan(alpha_n) x = tan(alpha_t) x cos(beta): same alpha_wt
    s = mesh_geometry(s1, s2)
    assert g.contact_ratio == pytest.approx(s.contact_ratio, rel=1e-10)
    assert g.centre_distance == pytest.approx(s.centre_distance, rel=1e-12)
    assert g.base_helix_angle == pytest.approx(math.atan(math.tan(beta) * math.cos(at)))


@pytest.mark.parametrize(
    ("gears"),
    [
        (tooth(21, profile_shift=0.4), tooth(37, profile_shift=0.25)),
        (tooth(-97, profile_shift=0.3), tooth(31, profile_shift=0.2)),
        (tooth(29, profile_shift=-0.2), tooth(-88, profile_shift=0.5)),
    ],
)
def test_zero_backlash_at_free_centre_distance(gears):
    # independent check of the profile-shift sign convention: the tooth thicknesses on the
    # working pitch circles (DIN 3960 thickness formula) fill the pitch exactly
    g = mesh_geometry(*gears)
    assert abs(g.circumferential_backlash) < 1e-12
    # and a larger (external) / smaller (internal) centre distance opens backlash
    if g.internal:
        g2 = mesh_geometry(*gears, centre_distance=g.centre_distance * 0.999)
    else:
        g2 = mesh_geometry(*gears, centre_distance=g.centre_distance * 1.001)
    assert g2.circumferential_backlash > 0


def test_internal_tip_radius_convention():
    ring = tooth(-100, profile_shift=0.2)
    # DIN 3960: x > 0 thickens the ring teeth, tip circle moves towards the axis
    assert ring.tip_radius == pytest.approx(50e-3 - 1.2e-3)
    assert ring.root_radius == pytest.approx(50e-3 + 1.05e-3)
    assert ring.reference_radius < 0 and ring.base_radius < 0
    assert ring.internal


def test_contact_ratio_below_one_raises():
    with pytest.raises(ValueError, match=r"eps_alpha = 0\.\d+ .*below 1 \(admissible: >= 1\)"):
        mesh_geometry(tooth(20, addendum=0.5), tooth(20, addendum=0.5))


def test_interference_and_overlapping_centre_distance_raise():
    with pytest.raises(ValueError, match="interference"):
        mesh_geometry(tooth(10), tooth(60))
    with pytest.raises(ValueError, match="overlap"):
        mesh_geometry(tooth(20), tooth(30), centre_distance=24.9e-3)
    with pytest.raises(ValueError, match="overlap"):
        mesh_geometry(tooth(-80), tooth(30), centre_distance=25.1e-3)
    with pytest.raises(ValueError, match="both gears are internal"):
        mesh_geometry(tooth(-80), tooth(-60))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"z": 2, "module": M}, r"\|z\| >= 3"),
        ({"z": 20, "module": -1e-3}, r"module = -0.001 m .*admissible: 1e-05 to 1 m"),
        ({"z": 20, "module": float("nan")}, "module"),
        ({"z": 20, "module": M, "pressure_angle": math.radians(50)}, "pressure_angle"),
        ({"z": 20, "module": M, "helix_angle": math.radians(46)}, "helix_angle"),
        ({"z": 20, "module": M, "face_width": 0.0}, "face_width"),
        ({"z": 20, "module": M, "profile_shift": float("inf")}, "profile_shift"),
        ({"z": 10, "module": M, "profile_shift": 1.5}, "pointed"),
        ({"z": 20.0, "module": M}, "integer"),
    ],
)
def test_toothing_validation(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Toothing(**kwargs)


# --- assembly --------------------------------------------------------------------------------
def test_minimum_offset_angle_paper_eq4():
    assert math.degrees(minimum_offset_angle(33, -114)) == pytest.approx(360 / 147)
    assert math.degrees(minimum_offset_angle(33, -114)) == pytest.approx(2.4489, abs=1e-4)


def test_admissible_angles_and_paper_offsets():
    eq = admissible_planet_angles(33, -114, 3)
    assert np.degrees(eq) == pytest.approx([0.0, 120.0, 240.0])
    all_ = admissible_planet_angles(33, -114)
    assert all_.size == 147
    paper = np.radians([0.0, 122.449, 244.898])
    check_planet_angles(33, -114, paper)
    # the paper's rounded 122.45/122.45/115.10 set
    check_planet_angles(33, -114, np.radians(np.cumsum([0.0, 122.45, 122.45])))
    with pytest.raises(ValueError, match="not admissible"):
        check_planet_angles(33, -114, np.radians([0.0, 122.45]), tol=1e-6)
    check_planet_angles(33, -114, [0.0, 50 * all_[1], 100 * all_[1]])
    with pytest.raises(
        ValueError,
        match=r"planet angle 121° is not admissible.*49\.4.*"
        r"nearest admissible 120° or 122\.449°",
    ):
        check_planet_angles(33, -114, np.radians([0.0, 121.0, 240.0]))


def test_overlapping_planets_rejected():
    # sun 12, ring -108, planet 48 (m = 1): a = 30 mm, r_a = 25 mm
    a, ra = 30e-3, 25e-3
    four = admissible_planet_angles(12, -108, 4)
    with pytest.raises(ValueError, match="neighbouring planets overlap"):
        check_planet_angles(12, -108, four, centre_distance=a, planet_tip_radius=ra)
    three = admissible_planet_angles(12, -108, 3)
    check_planet_angles(12, -108, three, centre_distance=a, planet_tip_radius=ra)
    with pytest.raises(ValueError, match="overlap"):
        check_planet_angles(
            12, -108, three, centre_distance=a, planet_tip_radius=ra, clearance=2.5e-3
        )
    with pytest.raises(ValueError, match="coincident"):
        check_planet_angles(33, -114, [0.0, 0.0])
    with pytest.raises(ValueError, match="z_ring < 0"):
        check_planet_angles(33, 114, [0.0])


def test_planet_tooth_number_and_profile_shift():
    assert planet_tooth_number(30, -90) == 30
    assert planet_tooth_number(33, -114) == 40
    assert planet_tooth_number(33, -114, rounding="up") == 41
    sun, ring = tooth(33), tooth(-114)
    for zp, sign in ((40, 1), (41, -1)):
        xp = planet_profile_shift(sun, ring, zp)
        assert np.sign(xp) == sign
        planet = tooth(zp, profile_shift=xp)
        gs, gr = mesh_geometry(sun, planet), mesh_geometry(ring, planet)
        assert gs.centre_distance == pytest.approx(gr.centre_distance, rel=1e-12)
        s, r = planetary_meshes(sun, ring, planet)
        assert abs(s.circumferential_backlash) < 1e-12 and abs(r.circumferential_backlash) < 1e-12
    # with sun and ring shifts
    sun2, ring2 = tooth(33, profile_shift=0.3), tooth(-114, profile_shift=0.1)
    xp = planet_profile_shift(sun2, ring2, 40)
    p = tooth(40, profile_shift=xp)
    assert mesh_geometry(sun2, p).centre_distance == pytest.approx(
        mesh_geometry(ring2, p).centre_distance, rel=1e-12
    )


def test_inverse_involute_and_profile_shift_match_scipy_brentq():
    # the root finders are written out (no scipy.optimize import in a simulation); the
    # independent reference is Brent's method
    from scipy.optimize import brentq

    for v in np.logspace(-4, 4, 60):
        v = float(v)
        ref = brentq(lambda a, v=v: math.tan(a) - a - v, 0.0, 1.5707963, xtol=1e-15,
                     rtol=1e-15)
        assert inverse_involute(v) == pytest.approx(ref, rel=1e-13, abs=0.0)
    assert inverse_involute(0.0) == 0.0
    assert inverse_involute(math.tan(0.35) - 0.35) == pytest.approx(0.35, rel=1e-15)
    with pytest.raises(ValueError, match="not admissible"):
        inverse_involute(-1e-3)
    for sun, ring, zp in ((tooth(33), tooth(-114), 40), (tooth(33), tooth(-114), 41),
                          (tooth(33, profile_shift=0.3), tooth(-114, profile_shift=0.1), 40)):
        def gap(x, sun=sun, ring=ring, zp=zp):
            p = tooth(zp, profile_shift=x)
            return (mesh_geometry(sun, p).centre_distance
                    - mesh_geometry(ring, p).centre_distance)

        ref = brentq(gap, -0.5, 0.5, xtol=1e-15)
        assert planet_profile_shift(sun, ring, zp) == pytest.approx(ref, abs=1e-12)


# --- phases ----------------------------------------------------------------------------------
def test_mesh_phases_paper_example():
    d = 2 * math.pi / 147
    assert mesh_phases(33, np.radians([0, 120, 240])) == pytest.approx([0, 0, 0], abs=1e-12)
    assert mesh_phases(-114, np.radians([0, 120, 240])) == pytest.approx([0, 0, 0], abs=1e-12)
    gs = mesh_phases(33, [0.0, 50 * d, 100 * d])
    gr = mesh_phases(-114, [0.0, 50 * d, 100 * d])
    expected = [0.0, float(Fraction(11, 49)), float(Fraction(22, 49))]
    assert gs == pytest.approx(expected, abs=1e-12)
    assert gr == pytest.approx(expected, abs=1e-12)
    # exact fractions: 49 * gamma is an integer
    assert np.round(49 * gs) == pytest.approx(49 * gs, abs=1e-9)
    s, r = planet_mesh_offsets(33, -114, [0.0, 50 * d, 100 * d], sun_ring=0.3)
    assert s == pytest.approx(np.mod(-np.array(expected), 1.0), abs=1e-12)
    assert r == pytest.approx(np.mod(0.3 - np.array(expected), 1.0), abs=1e-12)


def _half_thickness(g: Toothing, r: np.ndarray) -> np.ndarray:
    """Half tooth-thickness angle of an external gear at radius r (DIN 3960), written out."""
    rb = abs(g.base_radius)
    mt = g.module / math.cos(g.helix_angle)
    at = math.atan(math.tan(g.pressure_angle) / math.cos(g.helix_angle))
    st = mt * (math.pi / 2 + 2 * g.profile_shift * math.tan(g.pressure_angle))
    ar = np.arccos(np.clip(rb / r, -1, 1))
    return st / (g.z * mt) + (math.tan(at) - at) - (np.tan(ar) - ar)


def _brute_force_phase(sun_mesh, ring_mesh, n_scan=120):
    """Ring-mesh position at sun-mesh position 0, from tooth profiles and lines of action.

    Planet at the origin, carrier axis O at (0, -a). The planet turns clockwise by theta.
    The line of action of each mesh follows from statics: the sun drives the planet
    clockwise (force n with moment X x n = -r_b, pushing the planet away from O), the ring
    reacts (moment +r_b, pushing the planet towards O); each line is tangent to both base
    circles (sun: opposite sides, ring: same side). A contact is a crossing of a planet flank
    polyline with the line where the flank's outward normal is anti-parallel to n and the
    point lies inside the mating gear's toothed annulus on the pitch-point side. The mesh
    position is zero when the number of contacts increases.
    """
    planet = sun_mesh.gear2
    zp, rb, ra = planet.z, abs(planet.base_radius), planet.tip_radius
    a = sun_mesh.centre_distance
    assert ring_mesh.centre_distance == pytest.approx(a, rel=1e-12)
    O = np.array([0.0, -a])
    rbs, ras = abs(sun_mesh.gear1.base_radius), sun_mesh.gear1.tip_radius
    rbr, rar = abs(ring_mesh.gear1.base_radius), ring_mesh.gear1.tip_radius
    cs = -(rb + rbs) / a
    n_s = np.array([cs, math.sqrt(1 - cs**2)])
    cr = (rb - rbr) / a
    n_r = np.array([cr, -math.sqrt(1 - cr**2)])
    lines = {
        "sun": (n_s, -rb, lambda d: d <= ras, 1.0),
        "ring": (n_r, rb, lambda d: d >= rar, -1.0),
    }
    r = np.linspace(rb, ra, 401)
    psi = _half_thickness(planet, r)
    step = 2 * math.pi / zp

    def count(theta: float, which: str) -> int:
        n, c, inside, side = lines[which]
        foot_p = c * np.array([n[1], -n[0]])  # base tangency point on the planet
        cO = O[0] * n[1] - O[1] * n[0]
        foot_o = O + (c - cO) * np.array([n[1], -n[0]])  # mating tangency point
        centres = np.arange(zp) * step - theta
        # only teeth within 60° of the tangency point can reach the line inside the annulus
        near = np.cos(centres - math.atan2(foot_p[1], foot_p[0])) > 0.5
        centres = centres[near]
        total = 0
        for sgn in (1.0, -1.0):
            ang = centres[:, None] + sgn * psi[None, :]
            X = r[None, :, None] * np.stack([np.cos(ang), np.sin(ang)], axis=-1)
            g = X[..., 0] * n[1] - X[..., 1] * n[0] - c
            k_idx, i_idx = np.nonzero(np.sign(g[:, :-1]) * np.sign(g[:, 1:]) < 0)
            for k, i in zip(k_idx, i_idx, strict=True):
                w = g[k, i] / (g[k, i] - g[k, i + 1])
                P = X[k, i] + w * (X[k, i + 1] - X[k, i])
                t = X[k, i + 1] - X[k, i]
                nu = np.array([t[1], -t[0]]) / np.hypot(*t)
                e_phi = np.array([-P[1], P[0]])
                if sgn * (nu @ e_phi) < 0:
                    nu = -nu
                if nu @ n > -0.999:
                    continue
                if not inside(np.hypot(*(P - O))):
                    continue
                if side * ((P - foot_p) @ (foot_o - foot_p)) <= 0:
                    continue
                total += 1
        return total

    def entry(which: str) -> tuple[float, float]:
        th = np.arange(n_scan + 1) * step / n_scan
        cnt = np.array([count(t, which) for t in th])
        up = np.nonzero(np.diff(cnt) > 0)[0]
        assert up.size == 1, cnt
        lo, hi = th[up[0]], th[up[0] + 1]
        c_lo = cnt[up[0]]
        for _ in range(45):
            mid = 0.5 * (lo + hi)
            if count(mid, which) > c_lo:
                hi = mid
            else:
                lo = mid
        double = float(np.mean(cnt[:-1] == cnt.max()))
        return 0.5 * (lo + hi), double

    th_s, dbl_s = entry("sun")
    th_r, dbl_r = entry("ring")
    return ((th_s - th_r) / step) % 1.0, dbl_s, dbl_r


@pytest.mark.parametrize(
    ("z_s", "z_r", "z_p", "x_s", "x_r"),
    [
        (30, -90, 30, 0.0, 0.0),  # even planet, no shift
        (33, -114, 41, 0.0, 0.0),  # odd planet, negative shift from planet_profile_shift
        (33, -114, 40, 0.3, 0.1),  # even planet, all shifted
        (19, -71, 25, 0.2, 0.0),  # odd planet, positive shift
    ],
)
def test_sun_ring_phase_against_brute_force(z_s, z_r, z_p, x_s, x_r):
    sun, ring = tooth(z_s, profile_shift=x_s), tooth(z_r, profile_shift=x_r)
    xp = planet_profile_shift(sun, ring, z_p) if (-z_r - z_s) % 2 or x_s or x_r else 0.0
    planet = tooth(z_p, profile_shift=xp)
    sm, rm = planetary_meshes(sun, ring, planet)
    phase = sun_ring_phase(sm, rm)
    brute, dbl_s, dbl_r = _brute_force_phase(sm, rm)
    d = (phase - brute + 0.5) % 1.0 - 0.5
    assert abs(d) < 1e-5, (phase, brute)
    # the brute force also reproduces the contact ratios (double-contact fraction eps - 1)
    assert dbl_s == pytest.approx(sm.contact_ratio - 1, abs=0.01)
    assert dbl_r == pytest.approx(rm.contact_ratio - 1, abs=0.01)


def test_sun_ring_phase_argument_checks():
    sun, ring, planet = tooth(30), tooth(-90), tooth(30)
    sm, _rm = planetary_meshes(sun, ring, planet)
    with pytest.raises(ValueError, match="gear1 must be the ring"):
        sun_ring_phase(sm, sm)
    other = planetary_meshes(sun, ring, tooth(30, face_width=0.01))[1]
    with pytest.raises(ValueError, match="same planet"):
        sun_ring_phase(sm, other)
