"""Public static tooth forces (gearvib.simulate.static_tooth_forces) against hand computations."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gearvib.assembly import assemble
from gearvib.config import load_gearset
from gearvib.simulate import SpeedRamp, static_tooth_forces


@pytest.fixture(scope="module")
def case1():
    return assemble(load_gearset("paper-case1"))


def _sun_base_radius() -> float:
    # paper-case1: module 2.5 mm, z_sun = 33, pressure angle 20 deg (spur, no profile shift)
    return 2.5e-3 * 33 * math.cos(math.radians(20.0)) / 2


@pytest.mark.parametrize("torque", [60.0, 200.0, -60.0])
def test_equal_load_sharing_is_torque_over_base_radius_and_planets(case1, torque):
    # constant speed (no d'Alembert torque): each of the 3 planets carries T / (3 r_b) in its
    # sun mesh and, being in equilibrium, the same normal force in its ring mesh
    f = static_tooth_forces(case1, SpeedRamp(1000.0, 1000.0, 0.1, input_torque=torque))
    expected = abs(torque) / (3 * _sun_base_radius())
    assert f.mesh == case1.mesh_names
    np.testing.assert_allclose(f.force, expected, rtol=1e-9)
    assert set(f.flank.tolist()) == ({0} if torque > 0 else {1})
    assert f.as_dict()["sun-planet2"] == pytest.approx(expected, rel=1e-9)
    # the static deflection is force / mean mesh stiffness, with the sign of the torque
    assert np.all(np.sign(f.deflection) == np.sign(torque))


def test_ramp_adds_the_dalembert_torque_and_no_torque_gives_no_force(case1):
    steady = static_tooth_forces(case1, SpeedRamp(1000.0, 1000.0, 0.1, input_torque=60.0))
    ramp = static_tooth_forces(case1, SpeedRamp(0.0, 4000.0, 1.0, input_torque=60.0))
    assert np.all(ramp.force > steady.force)  # accelerating the set needs more sun torque
    assert np.all(ramp.force < 1.1 * steady.force)
    idle = static_tooth_forces(case1, SpeedRamp(1000.0, 1000.0, 0.1, input_torque=0.0))
    np.testing.assert_allclose(idle.force, 0.0, atol=1e-6)  # N; the teeth float in the backlash

