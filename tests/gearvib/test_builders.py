"""Wolfrom and Ravigneaux builders: collisions, helix angles and profile shifts (TOML keys).

Hand rules (as for the simple set): an external pair has opposite hands, an internal pair the
same hand (the ring has its planet's hand). Axial force of a helical gear from its meshes,
derived from the sign convention of :mod:`gearvib.assembly` (a right-hand gear driving in the
positive sense is pushed towards +z): ``F_z = -h tan(beta_b) tau / |r_b|`` with ``h`` the
gear's hand and ``tau`` the torque the meshes exert on it. Statics of a set whose carrier
carries no torque: the input's meshes exert ``-T``, the output's ``T / r_out`` (lossless),
the fixed member's the rest.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from gearvib.assembly import assemble
from gearvib.config import ConfigError, gearset_from_dict, load_config
from gearvib.simulate import SpeedRamp, prepare_run, static_equilibrium


def edited(name: str, **geometry) -> dict:
    cfg = copy.deepcopy(load_config(name)[0])
    cfg["geometry"].update(geometry)
    return cfg


def with_axial_bearings(cfg: dict) -> dict:
    """Elastic axial bearings on every body (helical sets need them to show the forces)."""
    for body in cfg["bodies"].values():
        body["support"]["axial"] = 5e8
    return cfg


# --------------------------------------------------------------------------- collisions


@pytest.mark.parametrize(
    ("geometry", "match"),
    [
        ({"z_planet_short": 26}, r"planet_short \(every pair\) collides with the ring: clearance "
                                 r"r_a,ring - \(a_short \+ r_a,short\) = 71.7500 - \(49.0000 \+ "
                                 r"24.5000\) = -1.7500 mm"),
        ({"n_pairs": 6}, r"the tip circles of planet_long1 and planet_short6 overlap: clearance "
                         r"\(centre distance - both tip radii\) -23.5151 mm"),
        ({"z_sun_small": 33}, r"planet_long \(every pair\) collides with the sun_small: "
                              r"clearance a_long - r_a,long - r_a,sun_small = -0.8750 mm"),
    ],
)
def test_ravigneaux_collisions_are_refused(geometry, match):
    """Hand values (module 1.75 mm, no shifts on the short planet): z_ps = 26 gives
    a_s = (30 + 26)/2 m = 49 mm and r_a = 14 m = 24.5 mm against the ring's tip circle
    r = 84/2 m - m = 71.75 mm; six pairs put a short planet onto the next pair's long one;
    z_s1 = 33 reaches r_a = 17.5 m = 30.625 mm, the long planet's tips come down to
    a_l - r_a,l = 60 m / 2 - 13.5 m = 29.75 mm."""
    with pytest.raises(ConfigError, match=match):
        gearset_from_dict(edited("ravigneaux-example", **geometry))


def test_ravigneaux_preset_clearances_are_positive():
    """The preset and a set with a larger short planet (z_ps = 24: 1.75 mm to the ring) pass."""
    assemble(gearset_from_dict(edited("ravigneaux-example")))
    assemble(gearset_from_dict(edited("ravigneaux-example", z_planet_short=24)))


def test_wolfrom_neighbouring_planets_are_checked():
    """Five planets of the preset's size do not fit on the carrier (either step)."""
    with pytest.raises(ConfigError, match="neighbouring planets overlap"):
        gearset_from_dict(edited("wolfrom-example", n_planets=6))


# --------------------------------------------------------------------------- helical sets


def hands(gs) -> dict[str, set[float]]:
    """Helix signs of every gear's toothings."""
    out: dict[str, set[float]] = {}
    for m in gs.meshes:
        for gear, t in ((m.gear1, m.toothing1), (m.gear2, m.toothing2)):
            out.setdefault(gear.rstrip("0123456789"), set()).add(
                math.copysign(1.0, t.helix_angle) * round(math.degrees(abs(t.helix_angle)), 9))
    return out


def axial_statics(cfg: dict, torque: float) -> tuple[object, dict[str, float]]:
    model = assemble(gearset_from_dict(cfg))
    setup = prepare_run(model, SpeedRamp(0.0, 0.0, 1.0, input_torque=torque), False)
    q0, _ = static_equilibrium(setup.system, setup.mass, setup.rigid, np.zeros(model.n_dof),
                               mesh_names=model.mesh_names)
    f = model.bearing_stiffness * (model.bearing_vectors @ q0)
    return model, dict(zip(model.bearing_names, f, strict=True))


def central_toothing(gs, body: str):
    return next(m.toothing1 for m in gs.meshes if m.gear1 == body)


def check_central_axial_forces(cfg: dict, torque: float, roles: dict[str, str]) -> None:
    gs = gearset_from_dict(cfg)
    model, force = axial_statics(cfg, torque)
    r_out = model.kinematic_ratios[model.output_member]
    tau = {roles["input"]: -torque, roles["output"]: torque / r_out}
    tau[roles["fixed"]] = -sum(tau.values())
    total = 0.0
    for body, t in tau.items():
        toothing = central_toothing(gs, body)
        geometry = next(m.geometry for m in gs.meshes if m.gear1 == body)
        beta_b = geometry.base_helix_angle
        h = math.copysign(1.0, toothing.helix_angle)
        expected = -h * math.tan(beta_b) * t / abs(toothing.base_radius)
        assert force[f"{body}.axial"] == pytest.approx(expected, rel=1e-6), body
        total += force[f"{body}.axial"]
    scale = max(abs(v) for v in force.values())
    planets = sum(v for k, v in force.items() if k.startswith("planet") and k.endswith("axial"))
    assert force["carrier.axial"] == pytest.approx(planets, abs=1e-9 * scale)
    assert total + force["carrier.axial"] == pytest.approx(0.0, abs=1e-9 * scale)


def test_helical_ravigneaux_hands_and_axial_forces():
    """helix_angle_deg = 12 (small sun right hand): short planet left, long planet right,
    large sun left, ring right (the long planet's). Statics at 150 N m: every central gear's
    axial force is -h tan(beta_b) tau / |r_b|; the planets have one toothing each and balance
    axially (their bearings carry ~0), so the carrier carries nothing either."""
    cfg = with_axial_bearings(edited("ravigneaux-example", helix_angle_deg=12.0))
    gs = gearset_from_dict(cfg)
    assert hands(gs) == {"sun_small": {12.0}, "planet_short": {-12.0}, "planet_long": {12.0},
                         "sun_large": {-12.0}, "ring": {12.0}}
    check_central_axial_forces(cfg, 150.0, {"input": "sun_small", "output": "ring",
                                            "fixed": "sun_large"})
    _, force = axial_statics(cfg, 150.0)
    scale = abs(force["sun_small.axial"])
    for name, value in force.items():
        if name.startswith("planet") and name.endswith("axial"):
            assert abs(value) < 1e-6 * scale, name


def test_helical_wolfrom_hands_and_axial_forces():
    """helix_angle_deg = 10 (sun right hand), helix_angle2_deg = 10 (the planet's second
    toothing right hand, ring 2 the same): planet toothing 1 and ring 1 left. Statics at
    20 N m against the hand formula; the stepped planet's two toothings do not balance, its
    axial bearing (and the carrier) carry the rest. Another helix on step 2 changes its
    transverse module: at the common centre distance the teeth would overlap (refused)."""
    cfg = with_axial_bearings(edited("wolfrom-example", helix_angle_deg=10.0,
                                     helix_angle2_deg=10.0))
    gs = gearset_from_dict(cfg)
    ring2 = next(m for m in gs.meshes if m.gear1 == "ring2")
    ring1 = next(m for m in gs.meshes if m.gear1 == "ring1")
    assert ring1.toothing1.helix_angle == ring1.toothing2.helix_angle == -math.radians(10.0)
    assert ring2.toothing1.helix_angle == ring2.toothing2.helix_angle == math.radians(10.0)
    check_central_axial_forces(cfg, 20.0, {"input": "sun", "output": "ring2", "fixed": "ring1"})
    # default: the second toothing has the first one's helix
    gs = gearset_from_dict(edited("wolfrom-example", helix_angle_deg=10.0))
    ring2 = next(m for m in gs.meshes if m.gear1 == "ring2")
    assert ring2.toothing2.helix_angle == -math.radians(10.0)
    with pytest.raises(ConfigError, match=r"ring2-planet mesh .* adjust module2, "
                                          r"helix_angle2_deg or the step-2 profile shifts"):
        gearset_from_dict(edited("wolfrom-example", helix_angle_deg=10.0, helix_angle2_deg=8.0))


@pytest.mark.parametrize(
    ("name", "key", "value", "match"),
    [
        ("wolfrom-example", "helix_angle_deg", 50.0, r"helix_angle .*45"),
        ("wolfrom-example", "helix_angle2_deg", "8", r"\[geometry\].helix_angle2_deg must be a "
                                                     r"number"),
        ("ravigneaux-example", "helix_angle_deg", -46.0, r"helix_angle .*45"),
        ("wolfrom-example", "profile_shift_planet1", 0.4, r"centre distances differ: sun-planet "
                                                          r".* adjust profile_shift_planet1"),
        ("ravigneaux-example", "profile_shift_planet_long", 0.3,
         r"centre distances differ: .* adjust profile_shift_planet_long \(the solved value "
         r"would be"),
        ("ravigneaux-example", "profile_shift_ring", float("inf"),
         r"\[geometry\].profile_shift_ring = inf is not admissible"),
        ("ravigneaux-example", "profile_shift_sun", 0.1, r"unknown key 'profile_shift_sun'"),
    ],
)
def test_bad_helix_and_shift_keys_name_the_key(name, key, value, match):
    with pytest.raises(ConfigError, match=match):
        gearset_from_dict(edited(name, **{key: value}))


def test_profile_shifts_reach_the_toothings_and_keep_one_centre_distance():
    """Given shifts go to the toothings; the solved planet shift keeps the sun and ring
    meshes on one centre distance (zero backlash in both); the sets assemble (mesh phases
    consistent through the shifted teeth) and keep their speed ratios."""
    cfg = edited("ravigneaux-example", profile_shift_sun_small=0.2, profile_shift_sun_large=0.1,
                 profile_shift_ring=0.15, profile_shift_planet_short=0.25)
    gs = gearset_from_dict(cfg)
    by = {m.name: m for m in gs.meshes}
    s1, s2, ring = by["sun_small-planet_short1"], by["sun_large-planet_long1"], \
        by["ring-planet_long1"]
    assert (s1.toothing1.profile_shift, s1.toothing2.profile_shift) == (0.2, 0.25)
    assert (s2.toothing1.profile_shift, ring.toothing1.profile_shift) == (0.1, 0.15)
    assert s2.toothing2.profile_shift == ring.toothing2.profile_shift != 0.0
    assert s2.geometry.centre_distance == pytest.approx(ring.geometry.centre_distance, rel=1e-9)
    assert s2.geometry.circumferential_backlash == pytest.approx(0.0, abs=1e-9)
    assert ring.geometry.circumferential_backlash == pytest.approx(0.0, abs=1e-9)
    base = assemble(gearset_from_dict(edited("ravigneaux-example")))
    model = assemble(gs)
    assert model.kinematic_ratios["ring"] == pytest.approx(base.kinematic_ratios["ring"],
                                                           rel=1e-12)
    cfg = edited("wolfrom-example", profile_shift_sun=0.1, profile_shift_ring1=0.05,
                 profile_shift_ring2=0.05, profile_shift_planet2=-0.2)
    gs = gearset_from_dict(cfg)
    by = {m.name: m for m in gs.meshes}
    sun, r1, r2 = by["sun-planet1"], by["ring1-planet1"], by["ring2-planet1"]
    assert (sun.toothing1.profile_shift, r1.toothing1.profile_shift) == (0.1, 0.05)
    assert (r2.toothing1.profile_shift, r2.toothing2.profile_shift) == (0.05, -0.2)
    assert sun.geometry.centre_distance == pytest.approx(r1.geometry.centre_distance, rel=1e-9)
    assert r2.geometry.centre_distance == pytest.approx(sun.geometry.centre_distance, rel=1e-12)
    base = assemble(gearset_from_dict(edited("wolfrom-example")))
    assert assemble(gs).kinematic_ratios["ring2"] == pytest.approx(
        base.kinematic_ratios["ring2"], rel=1e-9)
