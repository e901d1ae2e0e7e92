"""Literature models written as ``type = "general"``: lumped parameters as published."""

from __future__ import annotations

import copy
import math
from collections import Counter

import numpy as np
import pytest

from gearvib.assembly import assemble
from gearvib.config import ConfigError, gearset_from_dict
from gearvib.modal import modal_analysis
from gearvib.simulate import SpeedRamp, simulate

ALPHA = 24.6  # deg
RB_S, RB_R, RB_P = 77.4e-3 / 2, 275.0e-3 / 2, 100.3e-3 / 2  # base radii [m]


def lin_parker(n_planets: int = 4, *, fixed: list[str] | None = None,
               ring_torsion: float | str = 1e9 * RB_R**2) -> dict:
    """A Lin & Parker (1999)-style lumped model, parameters per member as such papers list
    them (masses, I/r^2, base diameters 77.4 / 275.0 / 100.3 mm, 24.6 deg, 5e8 N/m meshes,
    1e8 N/m bearings). Its base radii put the planet at 97.72 mm from the sun mesh and
    96.07 mm from the ring mesh (1.7 % apart); the model, in u = r theta, does not need them
    to agree."""
    def central(name, m, i_r2, rb, torsion):
        return {"name": name, "role": "central", "mass": m, "inertia": i_r2 * rb**2,
                "support": {"radial": 1e8, "torsional": torsion}}

    bodies = [
        central("sun", 0.4, 0.39, RB_S, 1e7 * RB_S**2),
        central("ring", 2.35, 3.0, RB_R, ring_torsion),
        {"name": "carrier", "role": "carrier", "mass": 5.43, "inertia": 6.29 * 0.0889**2,
         "support": {"radial": 1e8, "torsional": 1e7 * 0.0889**2}},
    ]
    meshes = []
    for i in range(n_planets):
        p = f"planet{i + 1}"
        bodies.append({"name": p, "role": "planet", "mass": 0.66, "inertia": 0.61 * RB_P**2,
                       "carrier": "carrier", "angle_deg": 360.0 * i / n_planets,
                       "support": {"radial": 1e8, "tangential": 1e8}})
        for central_name, rb in (("sun", RB_S), ("ring", -RB_R)):
            meshes.append({"name": f"{central_name}-{p}", "gear1": central_name, "gear2": p,
                           "base_radius1": rb, "base_radius2": RB_P,
                           "pressure_angle_deg": ALPHA,
                           "stiffness": {"model": "constant", "k": 5e8}})
    return {"name": "lin-parker", "type": "general", "body": bodies, "mesh": meshes,
            "operation": {"fixed": ["ring"] if fixed is None else fixed, "input": "sun",
                          "output": "carrier"}}


def test_published_lumped_radii_are_accepted_and_the_planet_radius_is_documented():
    model = assemble(gearset_from_dict(lin_parker()))
    a_sun = (RB_S + RB_P) / math.cos(math.radians(ALPHA))
    a_ring = (RB_R - RB_P) / math.cos(math.radians(ALPHA))
    assert abs(a_sun - a_ring) / a_ring == pytest.approx(0.0172, abs=2e-4)
    radius = model.meta["planets"][0]["radius"]
    assert radius == pytest.approx(a_sun, rel=1e-12)  # the first central mesh's
    # kinematics in u = r theta: the carrier turns by r_bs / (a (cos a_s + cos a_r)) per sun
    # radian, independent of the ring's base radius
    expected = RB_S / (radius * 2 * math.cos(math.radians(ALPHA)))
    assert model.kinematic_ratios["carrier"] == pytest.approx(expected, rel=1e-9)
    res = modal_analysis(model)
    counts = Counter(res.kinds)
    assert counts == {"rotational": 6, "translational": 12, "planet": 3}
    # the planet radius can be given (Lin & Parker's carrier radius)
    cfg = lin_parker()
    for b in cfg["body"]:
        if b["role"] == "planet":
            b["radius"] = 0.0970
    given = assemble(gearset_from_dict(cfg))
    assert given.meta["planets"][0]["radius"] == 0.0970


def test_real_inconsistency_is_still_refused():
    cfg = lin_parker()
    for m in cfg["mesh"]:
        if m["gear1"] == "ring":
            m["base_radius1"] = -0.160  # 160 mm instead of 137.5 mm: 25 % off
    with pytest.raises(ValueError, match=r"implies a planet radius of .* apart\); a lumped model "
                                         r"accepts up to 10%"):
        assemble(gearset_from_dict(cfg))


def test_centre_distance_of_a_lumped_mesh_is_used_or_refused():
    cfg = lin_parker()
    for m in cfg["mesh"]:
        m["centre_distance"] = 0.0970
    model = assemble(gearset_from_dict(cfg))
    assert model.meta["planets"][0]["radius"] == pytest.approx(0.0970, rel=1e-12)
    assert model.meta["meshes"][1]["centre_distance"] == pytest.approx(0.0970, rel=1e-12)
    cfg["mesh"][0]["centre_distance"] = 97.0  # mm by mistake
    with pytest.raises(ValueError, match=r"centre_distance 97000.0000 mm differs by"):
        assemble(gearset_from_dict(cfg))


def test_fixed_member_with_a_torsional_stiffness_is_held_through_it():
    """README: a fixed member is held at rest, rigidly unless its support has a finite
    torsional stiffness (Lin & Parker's k_ru), through which it is then held."""
    elastic = assemble(gearset_from_dict(lin_parker()))
    assert "ring.theta" in elastic.dof_names and elastic.kinematic_ratios["ring"] == 0.0
    rigid = assemble(gearset_from_dict(lin_parker(ring_torsion="rigid")))
    assert "ring.theta" not in rigid.dof_names
    f_el = modal_analysis(elastic).frequencies_hz
    f_rig = modal_analysis(rigid).frequencies_hz
    assert len(f_el) == len(f_rig) + 1
    stiff = assemble(gearset_from_dict(lin_parker(ring_torsion=1e12)))
    f_st = modal_analysis(stiff).frequencies_hz
    for f in f_rig:  # the rigid hold is the limit of a stiff one
        assert np.min(np.abs(f_st - f) / f) < 1e-4


def test_rigid_body_check_counts_torsional_supports():
    """Every central member held by a torsional support and none fixed (Lin & Parker's model):
    the ring, held but neither input nor output, is the reaction member of the kinematics."""
    model = assemble(gearset_from_dict(lin_parker(fixed=[])))
    assert model.meta["kinematics_at_rest"] == ["ring"]
    ref = assemble(gearset_from_dict(lin_parker()))
    assert model.kinematic_ratios["carrier"] == pytest.approx(ref.kinematic_ratios["carrier"],
                                                              rel=1e-12)
    np.testing.assert_allclose(modal_analysis(model).frequencies_hz,
                               modal_analysis(ref).frequencies_hz, rtol=1e-9)
    # without any support on the reaction member the set is a differential: the message says so
    cfg = lin_parker(fixed=[])
    cfg["body"][1]["support"]["torsional"] = "free"
    with pytest.raises(ValueError, match=r"2 rigid-body degrees of freedom with fixed members "
                                         r"\[\]: \['sun', 'ring', 'carrier'\] can turn"):
        assemble(gearset_from_dict(cfg))
    # a run-up cannot turn members held by torsional supports: said plainly
    with pytest.raises(ValueError, match=r"members \['carrier', 'sun'\] turn in it but are held "
                                         r"by torsional supports"):
        simulate(model, SpeedRamp(0, 100, 0.01))


@pytest.mark.parametrize(
    ("path", "value", "match"),
    [
        (("mesh", 0, "base_radius2"), 0.0, r"base_radius2 = 0.0 m is not admissible"),
        (("mesh", 0, "z1"), 12.5, r"\[\[mesh\]\] #1.z1 must be an integer"),
        (("mesh", 0, "pressure_angle_deg"), "20", r"pressure_angle_deg must be a number"),
        (("mesh", 0, "helix_angle_deg"), 50.0, r"helix_angle 50° is not admissible"),
        (("mesh", 0, "centre_distance"), -1.0, r"centre_distance = -1.0 m is not admissible"),
        (("mesh", 0, "phase"), float("nan"), r"phase is NaN"),
        (("body", 0, "mass"), -1.0, r"mass of body 'sun' = -1.0 is not admissible"),
        (("body", 3, "carrier"), 5, r"carrier must be the name of a carrier body"),
        (("body", 0, "role"), "shaft", r"role 'shaft' is not admissible"),
    ],
)
def test_bad_general_keys_name_the_key(path, value, match):
    cfg = copy.deepcopy(lin_parker())
    table = cfg[path[0]][path[1]]
    table[path[2]] = value
    with pytest.raises((ConfigError, ValueError), match=match):
        assemble(gearset_from_dict(cfg))
