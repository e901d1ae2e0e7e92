"""The back (right) flank acts along its own line of action, the mirror image of the left one.

Hand derivation (``e`` the unit vector from gear 1 to gear 2, ``t`` = ``e`` turned by +90°,
``sigma = -1`` for an internal pair): gear 1 pushes gear 2 on the left flank along
``n_L = cos(a) t + sigma sin(a) e`` (tangential push, separating radial component) and on the
back flank along ``-cos(a) t + sigma sin(a) e``; so the back-flank force on gear 1 is
``F n_R`` with ``n_R = cos(a) t - sigma sin(a) e``, on gear 2 ``-F n_R``. With a helical pair
the axial force reverses with the tangential one: a right-hand gear 1 that drives backwards is
pushed towards ``-z`` by ``F tan(beta_b)``.

Also here: the loaded flanks of the mean system (negative backlash: both, each on its line)
and the scale-aware rigid-body test of the modal analysis.
"""

from __future__ import annotations

import copy
import dataclasses
import math

import numpy as np
import pytest
import scipy.linalg

from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, load_config
from gearvib.modal import modal_analysis
from gearvib.model import FLANK_BOTH, FLANK_LEFT, FLANK_RIGHT
from gearvib.simulate import (
    SpeedRamp,
    default_coupling,
    prepare_run,
    simulate,
    static_equilibrium,
)
from gearvib.stiffness import ConstantStiffness
from gearvib.structure import RIGID, Body, GearSet, Mesh, Support

ALPHA = math.radians(20.0)
K_BEARING, K_AXIAL, K_MESH = 2e8, 3e8, 4e8


def pair(internal: bool, helix_deg: float = 0.0, backlash: float = 20e-6,
         k_back: float | None = None) -> GearSet:
    """Gear 1 (central; the ring when ``internal``) meshing gear 2, a planet on a fixed frame
    at 0°; elastic in-plane (and axial) bearings on both gears."""
    axial = K_AXIAL if helix_deg else RIGID
    r1, r2 = (-0.09, 0.03) if internal else (0.06, 0.03)
    bodies = (
        Body("gear1", "central", 3.0, 2e-3, Support(radial=K_BEARING, axial=axial)),
        Body("frame", "carrier", 10.0, 1.0, Support()),
        Body("gear2", "planet", 1.0, 5e-4,
             Support(radial=K_BEARING, tangential=1.5 * K_BEARING, axial=axial),
             carrier="frame", angle=0.0),
    )
    mesh = Mesh("gear1-gear2", "gear1", "gear2", ConstantStiffness(K_MESH),
                base_radius1=r1, base_radius2=r2, pressure_angle=ALPHA,
                helix_angle=math.radians(helix_deg), z1=-90 if internal else 60, z2=30,
                backlash=backlash,
                back_stiffness=None if k_back is None else ConstantStiffness(k_back))
    return GearSet("pair", bodies, (mesh,), fixed=("frame",), input="gear1", output="gear2")


def static_bearing_forces(model, torque: float, *, speed_rpm: float = 0.0) -> dict[str, float]:
    """Bearing forces [N] of the static equilibrium under ``torque`` at the input."""
    setup = prepare_run(model, SpeedRamp(speed_rpm, speed_rpm, 1.0, input_torque=torque), False)
    q0, _ = static_equilibrium(setup.system, setup.mass, setup.rigid,
                               setup.rigid * setup.omega0, mesh_names=model.mesh_names)
    f = model.bearing_stiffness * (model.bearing_vectors @ q0)
    return dict(zip(model.bearing_names, f, strict=True))


@pytest.mark.parametrize("internal", [False, True])
@pytest.mark.parametrize("helix_deg", [0.0, 15.0, -15.0])
@pytest.mark.parametrize("torque", [50.0, -50.0])
def test_pair_bearing_reactions_follow_the_loaded_flanks_line(internal, helix_deg, torque):
    """Statics of a single pair on elastic bearings: the transverse normal force
    ``F = |T| / |r_b1|`` acts along ``n_L`` (T > 0, left flank) or the mirrored ``n_R``
    (T < 0, back flank): gear 1's bearings carry ``+-F n``, gear 2's radial/tangential
    bearings ``-+F n``; the axial bearing of gear 1 carries ``h F tan(beta_b)`` towards the
    side its driving flank pushes it (sign of T)."""
    model = assemble(pair(internal, helix_deg))
    assert model.distinct_back_lines().all()
    force = static_bearing_forces(model, torque)
    sigma = -1.0 if internal else 1.0
    e, t = np.array([1.0, 0.0]), np.array([0.0, 1.0])  # gear 2 at 0°, gear 1 at the origin
    back = torque < 0
    n = math.cos(ALPHA) * t + (-sigma if back else sigma) * math.sin(ALPHA) * e
    f_t = abs(torque) / (0.09 if internal else 0.06)
    on_gear1 = (f_t if back else -f_t) * n  # the contact pushes gear 1 along -n_L or +n_R
    tol = 1e-6 * f_t
    assert force["gear1.x"] == pytest.approx(on_gear1[0], abs=tol)
    assert force["gear1.y"] == pytest.approx(on_gear1[1], abs=tol)
    assert force["gear2.radial"] == pytest.approx(-on_gear1[0], abs=tol)  # e_r = x
    assert force["gear2.tangential"] == pytest.approx(-on_gear1[1], abs=tol)  # e_t = y
    # the separating component pushes the gears apart (external) / the planet inwards
    # (internal) on either flank: a contact force never pulls
    assert math.copysign(1.0, on_gear1[0]) == (1.0 if internal else -1.0)
    if helix_deg:
        hand = math.copysign(1.0, helix_deg)
        beta_b = math.radians(abs(helix_deg))
        axial = hand * math.copysign(1.0, torque) * f_t * math.tan(beta_b)
        assert force["gear1.axial"] == pytest.approx(axial, abs=tol)
        assert force["gear2.axial"] == pytest.approx(-axial, abs=tol)


def test_the_old_single_line_puts_the_back_flank_force_on_the_wrong_side():
    """The same back-flank load with the back line forced onto the left one pulls gear 1
    towards gear 2 (the defect this fixes): the test above can fail."""
    model = assemble(pair(False))
    old = dataclasses.replace(model, mesh_back_vectors=None)
    assert static_bearing_forces(old, -50.0)["gear1.x"] > 0.0
    assert static_bearing_forces(model, -50.0)["gear1.x"] < 0.0


def elastic_case1(**mesh_changes) -> object:
    """``paper-case1-elastic`` with constant mesh stiffness (the mean of its tables: no
    dependence on where the static wind-up puts the mesh positions)."""
    cfg = copy.deepcopy(load_config("paper-case1-elastic")[0])
    for mesh in cfg["meshes"].values():
        mesh["stiffness"] = {"model": "constant", "k": 1.0e8}
        mesh.update(mesh_changes)
    return assemble(gearset_from_dict(cfg))


def mirrored(force: dict[str, float]) -> dict[str, float]:
    """Bearing forces mirrored about the x axis (planet 1 at 0°; planets 2 and 3 swap)."""
    swap = {"planet2": "planet3", "planet3": "planet2"}
    out = {}
    for name, value in force.items():
        body, comp = name.split(".")
        flip = comp in ("y", "tangential")
        out[f"{swap.get(body, body)}.{comp}"] = -value if flip else value
    return out


def test_reversed_torque_gives_the_mirror_image_bearing_forces():
    """paper-case1-elastic, 60 N m forward and reversed: reversing the torque loads every
    back flank, which mirrors the whole load pattern about the line through the sun and
    planet 1 (radial forces unchanged, tangential ones reversed, planets 2 and 3 swapped).
    With the back flank on the left line of action the planets' radial forces would reverse
    instead. Also from a constant-speed run: the kernel holds the same static state."""
    model = elastic_case1()
    fwd = static_bearing_forces(model, 60.0)
    rev = static_bearing_forces(model, -60.0)
    scale = max(abs(v) for v in fwd.values())
    # by hand: each planet carries F = T / (3 r_bs) in both meshes; tangentially both push it
    # forward, radially the sun mesh pushes it out by F sin(a_ws), the ring mesh in by
    # F sin(a_wr) (the working pressure angles differ: 18 N net)
    meta = {m["name"]: m for m in model.meta["meshes"]}
    f_n = 60.0 / (3 * meta["sun-planet1"]["base_radius1"])
    a_s, a_r = (math.radians(meta[k]["pressure_angle_deg"]) for k in ("sun-planet1",
                                                                       "ring-planet1"))
    for i in (1, 2, 3):
        assert fwd[f"planet{i}.radial"] == pytest.approx(f_n * (math.sin(a_s) - math.sin(a_r)),
                                                         rel=1e-6)
        assert fwd[f"planet{i}.tangential"] == pytest.approx(
            f_n * (math.cos(a_s) + math.cos(a_r)), rel=1e-9)
    assert abs(fwd["planet1.radial"]) > 0.01 * scale
    for name, value in mirrored(fwd).items():
        assert rev[name] == pytest.approx(value, abs=1e-9 * scale), name
    old = dataclasses.replace(model, mesh_back_vectors=None)
    rev_old = static_bearing_forces(old, -60.0)
    assert rev_old["planet1.radial"] == pytest.approx(-fwd["planet1.radial"], rel=1e-6)
    # the run: starts at the static state and stays there (constant stiffness and speed)
    res = simulate(model, SpeedRamp(300.0, 300.0, 0.02, input_torque=-60.0), progress=False)
    run = dict(zip(res.bearing_names, res.bearing_force[:, -1], strict=True))
    for name, value in rev.items():
        assert run[name] == pytest.approx(value, abs=1e-6 * scale), name
    assert res.flank_contact_changes.sum() == 0
    assert np.all(res.normal_force[:, 0, :] == 0.0)  # left flanks open, right ones loaded
    assert res.normal_force[:, 1, -1].min() > 0.0


def test_loaded_flanks_of_the_mean_system():
    """Forward load: every flank of a simple set left, the Ravigneaux ring and planet-planet
    meshes and the Wolfrom ring-2 meshes right (their sign convention: driven backwards);
    reversed load swaps them; negative backlash: both."""
    left = assemble(gearset_from_dict(load_config("paper-case1")[0]))
    assert np.all(left.loaded_flanks() == FLANK_LEFT)
    assert np.all(left.loaded_flanks(-1) == FLANK_RIGHT)
    rav = assemble(gearset_from_dict(load_config("ravigneaux-example")[0]))
    right = [m.startswith(("ring", "planet_short")) for m in rav.mesh_names]
    np.testing.assert_array_equal(rav.loaded_flanks(), np.where(right, FLANK_RIGHT, FLANK_LEFT))
    np.testing.assert_array_equal(rav.loaded_flanks(-1),
                                  np.where(right, FLANK_LEFT, FLANK_RIGHT))
    wol = assemble(gearset_from_dict(load_config("wolfrom-example")[0]))
    right = [m.startswith("ring2") for m in wol.mesh_names]
    np.testing.assert_array_equal(wol.loaded_flanks(), np.where(right, FLANK_RIGHT, FLANK_LEFT))
    pre = elastic_case1(backlash=-10e-6)
    assert np.all(pre.loaded_flanks() == FLANK_BOTH)
    with pytest.raises(ValueError, match="torque_sign"):
        pre.loaded_flanks(0.0)


def hand_pair_vectors(model, internal: bool) -> tuple[np.ndarray, np.ndarray]:
    """Left and back deflection vectors of :func:`pair` written from the hand derivation."""
    sigma = -1.0 if internal else 1.0
    r1, r2 = (-0.09, 0.03) if internal else (0.06, 0.03)
    out = []
    for s in (sigma, -sigma):  # n = cos(a) t + s sin(a) e, e = x, t = y
        n = np.array([s * math.sin(ALPHA), math.cos(ALPHA)])
        v = dict.fromkeys(model.dof_names, 0.0)
        v.update({"gear1.theta": sigma * r1, "gear2.theta": sigma * r2,
                  "gear1.x": n[0], "gear1.y": n[1], "gear2.zeta": -n[0], "gear2.eta": -n[1]})
        out.append(np.array([v[d] for d in model.dof_names]))
    return out[0], out[1]


@pytest.mark.parametrize("internal", [False, True])
def test_preloaded_pair_modes_use_both_lines_of_action(internal):
    """Negative backlash: the mean system is K + k_L v_L v_L^T + k_R v_R v_R^T with the hand
    vectors; modal_analysis (frequencies and translational mode shapes), the run's natural
    frequencies and the default drive coupling agree with it (1e-9), and differ from the
    single-line (k_L + k_R) v_L v_L^T system by more than 1 %."""
    k_back = 1.5 * K_MESH  # unequal flanks: the pairing of stiffness and line is checked too
    model = assemble(pair(internal, backlash=-10e-6, k_back=k_back))
    vl, vr = hand_pair_vectors(model, internal)
    np.testing.assert_allclose(model.mesh_vectors[0], vl, atol=1e-15)
    np.testing.assert_allclose(model.back_vectors[0], vr, atol=1e-15)
    k_hand = model.stiffness + K_MESH * np.outer(vl, vl) + k_back * np.outer(vr, vr)
    w2 = scipy.linalg.eigh(k_hand, model.mass, eigvals_only=True)
    f_hand = np.sqrt(np.clip(w2, 0, None)) / (2 * math.pi)
    res = modal_analysis(model)
    assert res.loaded_flanks == ("both",)
    assert res.kinds[0] == "rigid-body" and res.kinds.count("rigid-body") == 1
    np.testing.assert_allclose(res.frequencies_hz[1:], f_hand[1:], rtol=1e-9)
    for i in range(1, res.n_modes):  # the mode shapes solve the hand-built eigenproblem
        w = 2 * math.pi * res.frequencies_hz[i]
        resid = (k_hand - w**2 * model.mass) @ res.shapes[:, i]
        assert np.abs(resid).max() < 1e-9 * np.abs(k_hand).max() * np.abs(res.shapes[:, i]).max()
    one_line = model.stiffness + (K_MESH + k_back) * np.outer(vl, vl)
    w2_one = scipy.linalg.eigh(one_line, model.mass, eigvals_only=True)
    assert np.abs(np.sqrt(w2_one[1:]) / (2 * math.pi) / f_hand[1:] - 1).max() > 0.01
    # the modal strain energy of the mesh counts both flanks
    total = res.mesh_energy[1:, 0] + res.bearing_energy[1:].sum(axis=1)
    np.testing.assert_allclose(total, 1.0, rtol=1e-9)
    # drive coupling: its mode at 0.1 x the lowest elastic frequency of the same system
    r = model.rigid_body_velocity()
    j_eff = float(r @ model.mass @ r)
    wc = 2 * math.pi * 0.1 * f_hand[1]
    coupling = default_coupling(model)
    assert coupling.stiffness == pytest.approx(j_eff * wc**2, rel=1e-9)
    run = simulate(model, SpeedRamp(100.0, 100.0, 0.002, input_torque=5.0), progress=False)
    np.testing.assert_allclose(run.natural_frequencies, f_hand[1:], rtol=1e-9)


def test_preloaded_planetary_set_modes_equal_the_hand_built_matrix():
    """paper-case1-elastic with -10 um backlash (six two-line meshes, k_back = 1.3 k) and
    paper-case1 (rigid bearings: both flanks on one line, k_L + k_R): modal_analysis equals
    eigh(K + sum k_L v v^T + k_R u u^T, M), and the step choice takes both flanks."""
    for name in ("paper-case1-elastic", "paper-case1"):
        cfg = copy.deepcopy(load_config(name)[0])
        for mesh in cfg["meshes"].values():
            mesh["backlash"] = -10e-6
            mesh["back_stiffness"] = {"model": "constant", "k": 1.3 * 1.05e8}
        model = assemble(gearset_from_dict(cfg))
        assert (model.mesh_back_vectors is not None) == (name == "paper-case1-elastic")
        kl = model.mesh_stiffness_tables.mean(axis=1)
        kr = model.mesh_back_tables.mean(axis=1)
        vl, vr = model.mesh_vectors, model.back_vectors
        k_hand = model.stiffness + (vl.T * kl) @ vl + (vr.T * kr) @ vr
        f_hand = np.sqrt(np.clip(scipy.linalg.eigh(k_hand, model.mass, eigvals_only=True),
                                 0, None)) / (2 * math.pi)
        res = modal_analysis(model)
        assert set(res.loaded_flanks) == {"both"}
        np.testing.assert_allclose(res.frequencies_hz[1:], f_hand[1:], rtol=1e-8)
        k_max = (model.stiffness + (vl.T * model.mesh_stiffness_tables.max(axis=1)) @ vl
                 + (vr.T * model.mesh_back_tables.max(axis=1)) @ vr)
        setup = prepare_run(model, SpeedRamp(0, 100, 0.1, input_torque=10.0), False)
        # the default drive, a controller on the rigid-body coordinate p.q, as k p p^T
        r = model.rigid_body_velocity()
        p = model.mass @ r / (r @ model.mass @ r)
        k_max += setup.coupling.stiffness * np.outer(p, p)
        f_max = math.sqrt(scipy.linalg.eigh(k_max, model.mass, eigvals_only=True)[-1]) / (
            2 * math.pi)
        run = simulate(model, SpeedRamp(0, 100, 0.001, input_torque=10.0), progress=False)
        assert run.step.highest_natural_frequency == pytest.approx(f_max, rel=1e-9)


def test_back_loaded_ravigneaux_modes_use_the_back_lines():
    """Ravigneaux with elastic planet bearings: ring and planet-planet meshes carry the mean
    load on the back flank, so the mean system puts them on their back lines (hand-built K
    from the model's vectors; the left-line system differs)."""
    from tests.gearvib.test_gear_sets import ravigneaux_set

    model = assemble(ravigneaux_set(elastic=True))
    flanks = model.loaded_flanks()
    right = flanks == FLANK_RIGHT
    assert right.sum() == 6 and model.distinct_back_lines()[right].all()
    k = model.mesh_stiffness_tables.mean(axis=1)
    v = np.where(right[:, None], model.back_vectors, model.mesh_vectors)
    f_hand = np.sqrt(np.clip(scipy.linalg.eigh(model.stiffness + (v.T * k) @ v, model.mass,
                                               eigvals_only=True), 0, None)) / (2 * math.pi)
    res = modal_analysis(model)
    np.testing.assert_allclose(res.frequencies_hz[1:], f_hand[1:], rtol=1e-9)
    f_left = np.sqrt(np.clip(scipy.linalg.eigh(model.stiffness + model.mesh_stiffness_matrix(),
                                               model.mass, eigvals_only=True), 0, None))
    assert np.abs(f_left[1:] / (2 * math.pi) / f_hand[1:] - 1).max() > 1e-3


# ----------------------------------------------------------------------- rigid-body modes


def soft_load_set(k_support: float):
    """paper-case1-elastic with a load inertia on a soft shaft at the carrier (a real mode
    near 300 Hz) and the sun's radial bearing ``k_support``."""
    cfg = copy.deepcopy(load_config("paper-case1-elastic")[0])
    cfg["bodies"]["sun"]["support"]["radial"] = k_support
    cfg["body"] = [{"name": "load", "role": "central", "mass": 5.0, "inertia": 0.05}]
    cfg["coupling"] = [{"body1": "carrier", "body2": "load", "stiffness": 1.5e5}]
    cfg["operation"]["output"] = "load"
    return assemble(gearset_from_dict(cfg))


def elastic_reference(model) -> np.ndarray:
    """Elastic frequencies with the rigid-body motion removed exactly (M-orthogonal
    complement of the kinematic velocity): independent of any zero test."""
    r = model.rigid_body_velocity()
    basis = scipy.linalg.null_space((model.mass @ r)[None, :])
    k = basis.T @ model.mean_stiffness_matrix() @ basis
    m = basis.T @ model.mass @ basis
    return np.sqrt(scipy.linalg.eigh(k, m, eigvals_only=True)) / (2 * math.pi)


@pytest.mark.parametrize("k_support", [1e6, 1e8, 1e10, 1e12, 1e14, 1e15, 1e16])
def test_rigid_body_test_is_scale_aware(k_support):
    """One rigid-body mode for every support stiffness from 1e6 to 1e16 N/m, and every elastic
    frequency equal to the reference (1e-6). At 1e15-1e16 the old relative threshold
    (|omega^2| < 1e-9 max omega^2) would have called the real mode near 300 Hz rigid."""
    model = soft_load_set(k_support)
    res = modal_analysis(model)
    assert res.kinds.count("rigid-body") == 1 and res.kinds[0] == "rigid-body"
    ref = elastic_reference(model)
    np.testing.assert_allclose(res.elastic(), ref, rtol=1e-6)
    assert 250 < ref[0] < 350
    w2 = scipy.linalg.eigh(model.mean_stiffness_matrix(), model.mass, eigvals_only=True)
    old_rigid = np.abs(w2) < 1e-9 * np.abs(w2).max()
    assert old_rigid.sum() == (2 if k_support >= 1e16 else 1)
    # the run's natural frequencies and the default drive coupling use the same test
    res_nat = default_coupling(model)
    r = model.rigid_body_velocity()
    k_in = model.rotation_dofs["sun"]
    wc = 2 * math.pi * 0.1 * ref[0]
    # (rel 1e-5: at 1e16 N/m the eigenvalue solver's absolute rounding, eps x the largest
    # omega^2, is 1e-6 of omega^2 at 300 Hz)
    assert res_nat.stiffness == pytest.approx(float(r @ model.mass @ r) / r[k_in]**2 * wc**2,
                                              rel=1e-5)


def test_rigid_body_classification_of_the_presets_is_unchanged():
    """Every preset: the scale-aware test finds exactly the modes the relative threshold found
    (one rigid-body mode each)."""
    from gearvib.config import list_presets

    for name in list_presets():
        model = assemble(gearset_from_dict(load_config(name)[0]))
        res = modal_analysis(model)
        w2 = scipy.linalg.eigh(model.mean_stiffness_matrix(), model.mass, eigvals_only=True)
        old = np.abs(w2) < 1e-9 * np.abs(w2).max()
        assert [k == "rigid-body" for k in res.kinds] == list(old), name
        assert old.sum() == 1, name
