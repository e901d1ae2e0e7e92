"""Assembly: kinematics, mesh phases, DOF removal, builders, lumped literature models."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gearvib.assembly import assemble
from gearvib.config import load_gearset
from gearvib.geometry import sun_ring_phase
from gearvib.kinematics import paper_mesh_frequency
from gearvib.modal import modal_analysis
from gearvib.stiffness import ConstantStiffness, RectangularStiffness
from gearvib.structure import (
    Body,
    MeshSpec,
    Support,
    simple_planetary,
    two_stage,
)
from tests.gearvib.lumped_sets import (
    WOLFROM_TEETH,
    lumped_planetary,
    nominal_bodies,
    ravigneaux_set,
    wolfrom_set,
)


def test_paper_case1_kinematics_and_mesh_frequency():
    model = assemble(load_gearset("paper-case1"))
    r = model.kinematic_ratios
    assert r["ring"] == 0.0
    assert r["carrier"] == pytest.approx(33 / 147, rel=1e-12)
    # planet spin relative to the carrier: -(z_s/z_p)(n_s - n_c)
    assert r["planet1"] - r["carrier"] == pytest.approx(-(33 / 40) * (1 - 33 / 147), rel=1e-9)
    f = model.mesh_frequency_per_rpm * 1500
    assert f == pytest.approx(paper_mesh_frequency(1500, 33, -114), rel=1e-12)
    assert f == pytest.approx(639.8, abs=0.1)


def test_paper_case1_is_purely_torsional_and_in_phase():
    model = assemble(load_gearset("paper-case1"))
    assert model.dof_names == ("sun.theta", "carrier.theta", "planet1.theta", "planet2.theta",
                               "planet3.theta")
    lags = [m["phase_lag"] for m in model.meta["meshes"]]
    assert lags[:3] == [0.0, 0.0, 0.0]  # 120 deg: all sun contacts in phase
    assert lags[3] == pytest.approx(lags[4], abs=1e-12)  # and all ring contacts
    assert lags[3] == pytest.approx(lags[5], abs=1e-12)


def test_paper_case2_phases_are_multiples_of_eleven_49ths():
    model = assemble(load_gearset("paper-case2"))
    lags = np.array([m["phase_lag"] for m in model.meta["meshes"]])
    np.testing.assert_allclose(lags[:3], [0.0, 11 / 49, 22 / 49], atol=1e-9)
    # the ring contacts carry the same set, shifted by the sun-ring phase of the tooth geometry
    gs = load_gearset("paper-case2")
    gamma = sun_ring_phase(gs.meshes[0].geometry, gs.meshes[3].geometry)
    np.testing.assert_allclose((lags[3:] - lags[:3]) % 1.0, (-gamma) % 1.0, atol=1e-9)


def test_mesh_positions_advance_together_in_rigid_motion():
    """In the kinematic motion every contact advances by the same number of mesh cycles."""
    model = assemble(load_gearset("paper-case2"))
    q = np.zeros(model.n_dof)
    for body, i in model.rotation_dofs.items():
        if i >= 0:
            q[i] = model.kinematic_ratios[body] * 2 * math.pi  # one input revolution
    ds = model.mesh_position_vectors @ q
    np.testing.assert_allclose(ds, ds[0], rtol=1e-12)
    assert ds[0] == pytest.approx(33 * (1 - 33 / 147), rel=1e-12)
    # and the meshes are undeformed
    np.testing.assert_allclose(model.mesh_vectors @ q, 0.0, atol=1e-12)


def test_elastic_bearings_add_translations_and_list_bearings():
    model = assemble(load_gearset("paper-case1-elastic"))
    assert "planet1.zeta" in model.dof_names and "sun.x" in model.dof_names
    assert "ring.theta" not in model.dof_names
    assert "planet2.tangential" in model.bearing_names
    np.testing.assert_allclose(model.mass, model.mass.T)
    k = model.mean_stiffness_matrix()
    np.testing.assert_allclose(k, k.T, rtol=1e-12, atol=1e-6)


def test_rigid_bearing_is_the_limit_of_a_stiff_elastic_bearing():
    soft = modal_analysis(assemble(lumped_planetary([0, 120, 240], k_bearing=1e13)))
    rigid = modal_analysis(assemble(lumped_planetary([0, 120, 240], elastic=False)))
    # the torsional frequencies reappear among the stiff-bearing frequencies
    for f in rigid.frequencies_hz:
        assert np.min(np.abs(soft.frequencies_hz - f) / f) < 1e-3


def test_wolfrom_ratio_matches_willis():
    zs, zr1, zr2, zp1, zp2 = WOLFROM_TEETH
    model = assemble(wolfrom_set())
    n_c = zs / (zs - zr1)
    expected = n_c * (1 - zp2 * zr1 / (zp1 * zr2))
    assert model.kinematic_ratios["ring2"] == pytest.approx(expected, rel=1e-9)
    assert len(model.mesh_names) == 9


def test_ravigneaux_assembles_with_planet_planet_meshes():
    gs = ravigneaux_set()
    model = assemble(gs)
    assert any(n.startswith("short1-long1") for n in model.mesh_names)
    # small sun in, large sun fixed, ring out: closed form of the Ravigneaux 2nd gear
    # n_c from the large sun/ring pair: (n_s2 - n_c) z_s2 = -(n_r - n_c) z_r ...
    r = model.kinematic_ratios
    assert r["sun_large"] == 0.0
    # check Willis for the small-sun path (short planet reverses the sense)
    zs1, zps, zpl, zr = 30, 18, 24, -84
    n_c = r["carrier"]
    n_pl = r["long1"]
    n_ps = r["short1"]
    assert zs1 * (1 - n_c) == pytest.approx(-zps * (n_ps - n_c), rel=1e-9)
    assert zps * (n_ps - n_c) == pytest.approx(-zpl * (n_pl - n_c), rel=1e-9)
    assert zr * (r["ring"] - n_c) == pytest.approx(-zpl * (n_pl - n_c), rel=1e-9)
    assert all(np.isfinite(modal_analysis(model).frequencies_hz))


def test_two_stage_ratio_is_the_product():
    def stage():
        sun, ring = nominal_bodies("sun", "ring")
        car = Body("carrier", "carrier", 3.0, 2e-2, Support())
        pl = Body("planet", "planet", 0.5, 2e-4, Support(), carrier="carrier")
        k = RectangularStiffness(2e8, 3e8, 1.6)
        return simple_planetary(z_sun=21, z_ring=-75, z_planet=27, module=2e-3, sun=sun,
                                ring=ring, carrier=car, planet=pl, sun_mesh=MeshSpec(k),
                                ring_mesh=MeshSpec(k), n_planets=3)
    gs = two_stage(stage(), stage(), shaft_stiffness=5e5)
    model = assemble(gs)
    i1 = 21 / 96
    assert model.kinematic_ratios["s2.carrier"] == pytest.approx(i1 * i1, rel=1e-9)
    assert "s1.sun-planet1" in model.mesh_names
    assert model.rotation_dofs["s2.sun"] >= 0  # elastic shaft keeps both rotations
    rigid = assemble(two_stage(stage(), stage()))
    assert rigid.rotation_dofs["s2.sun"] == rigid.rotation_dofs["s1.carrier"]


def test_lumped_literature_model_without_tooth_geometry():
    model = assemble(lumped_planetary([0, 90, 180, 270]))
    assert model.n_dof == 21
    assert model.meta["meshes"][0]["contact_ratio"] is None
    # the kinematics follow the base radii: n_c / n_s = r_bs / (r_bs + |r_br|)
    r_bs, r_bp = 0.0297, 0.0254
    assert model.kinematic_ratios["carrier"] == pytest.approx(
        r_bs / (r_bs + r_bs + 2 * r_bp), rel=1e-9)


def test_time_varying_lumped_mesh_needs_tooth_numbers():
    from gearvib.structure import GearSet, Mesh

    bodies = (Body("a", "central", 1, 1e-3), Body("c", "carrier", 1, 1e-2),
              Body("p", "planet", 1, 1e-4, carrier="c"))
    mesh = Mesh("a-p", "a", "p", RectangularStiffness(1e8, 2e8, 1.5), base_radius1=0.05,
                base_radius2=0.02, pressure_angle=math.radians(20))
    with pytest.raises(ValueError, match="tooth numbers"):
        assemble(GearSet("x", bodies, (mesh,), fixed=("c",), input="a", output="p"))


def test_helical_meshes_add_axial_coordinates_and_couple_them():
    sun, ring = nominal_bodies("sun", "ring")
    car = Body("carrier", "carrier", 3.0, 2e-2, Support(radial=1e8, axial=1e8))
    pl = Body("planet", "planet", 0.5, 2e-4, Support(radial=1e8, tangential=1e8, axial=5e7),
              carrier="carrier")
    sun = Body("sun", "central", 2.0, 1e-2, Support(radial=1e8, axial=1e8))
    ring = Body("ring", "central", 2.0, 1e-2, Support(radial=1e8, axial=1e8))
    k = ConstantStiffness(3e8)
    beta = math.radians(15.0)
    gs = simple_planetary(z_sun=21, z_ring=-75, z_planet=27, module=2e-3, sun=sun, ring=ring,
                          carrier=car, planet=pl, sun_mesh=MeshSpec(k), ring_mesh=MeshSpec(k),
                          n_planets=3, helix_angle=beta)
    model = assemble(gs)
    assert "sun.z" in model.dof_names and "planet1.z" in model.dof_names
    iz = model.dof_names.index("sun.z")
    # each sun mesh pushes the sun axially with sin(beta_b) of its normal deflection
    beta_b = gs.meshes[0].geometry.base_helix_angle
    np.testing.assert_allclose(np.abs(model.mesh_vectors[:3, iz]), math.sin(beta_b), rtol=1e-12)
    spur = assemble(simple_planetary(
        z_sun=21, z_ring=-75, z_planet=27, module=2e-3, sun=sun, ring=ring, carrier=car,
        planet=pl, sun_mesh=MeshSpec(k), ring_mesh=MeshSpec(k), n_planets=3))
    assert "sun.z" not in spur.dof_names
    res = modal_analysis(model)
    assert np.all(np.isfinite(res.frequencies_hz))
    # axial modes couple to the gear meshes: some mode has both axial and torsional motion
    shapes = res.shapes
    iz_all = [i for i, n in enumerate(model.dof_names) if n.endswith(".z")]
    it_all = [i for i, n in enumerate(model.dof_names) if n.endswith(".theta")]
    mixed = (np.abs(shapes[iz_all]).max(axis=0) > 1e-3 * np.abs(shapes).max(axis=0)) & (
        np.abs(shapes[it_all]).max(axis=0) > 1e-3 * np.abs(shapes).max(axis=0))
    assert mixed.any()
