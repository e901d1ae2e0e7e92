"""Adjacent drive components: motor, shafts, couplings and load around a gear set."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
import scipy.linalg

from gearvib.assembly import assemble
from gearvib.config import ConfigError, gearset_from_dict, load_config
from gearvib.modal import modal_analysis
from gearvib.simulate import MotorDriven, simulate
from gearvib.simulation.settings import conditions_from_settings, read_run_settings

J_MOTOR, J_LOAD = 0.05, 2.0  # kg m^2
K_SHAFT, K_LOAD = 2.0e4, 2.0e5  # N m/rad: motor shaft + coupling, output shaft
K_SUN, K_RING = 3.5e7, 4.0e7  # N/m, constant mesh stiffness


def drive_train_config() -> dict:
    """paper-case1 (torsional) between a motor (input) and a load (output), ring fixed."""
    cfg, _ = load_config("paper-case1")
    cfg = copy.deepcopy(cfg)
    cfg["name"] = "drive-train"
    cfg["operation"] = {"fixed": "ring", "input": "motor", "output": "load"}
    cfg["meshes"]["sun"]["stiffness"] = {"model": "constant", "k": K_SUN}
    cfg["meshes"]["ring"]["stiffness"] = {"model": "constant", "k": K_RING}
    cfg["body"] = [
        {"name": "motor", "role": "central", "mass": 20.0, "inertia": J_MOTOR},
        {"name": "load", "role": "central", "mass": 50.0, "inertia": J_LOAD},
    ]
    cfg["coupling"] = [
        {"body1": "motor", "body2": "sun", "stiffness": K_SHAFT, "damping": 2.0},
        {"body1": "carrier", "body2": "load", "stiffness": K_LOAD, "damping": 10.0},
    ]
    cfg.pop("simulation")
    return cfg


def test_drive_train_modes_match_a_hand_built_chain():
    """M and K written out: motor -- shaft -- sun, three planets on the carrier, carrier --
    shaft -- load. Mesh deflections of the purely torsional set (rigid bearings; the planet
    centre moves by a theta_c with a cos(alpha_w) = r_bs + r_bp for the sun and r_br - r_bp for
    the ring): delta_s = r_bs th_s + r_bp th_p - (r_bs + r_bp) th_c and
    delta_r = -r_bp th_p - (r_br - r_bp) th_c. Base radii z m cos(20 deg) / 2. The planet
    centres move with the carrier: its inertia gains N m_p a^2 (a the planet radius)."""
    model = assemble(gearset_from_dict(drive_train_config()))
    a = model.meta["planets"][0]["radius"]
    rb = {z: z * 2.5e-3 * math.cos(math.radians(20.0)) / 2 for z in (33, 40, 114)}
    rb_s, rb_p, rb_r = rb[33], rb[40], rb[114]
    names = ["motor", "sun", "carrier", "planet1", "planet2", "planet3", "load"]
    i = {n: k for k, n in enumerate(names)}
    j_carrier = 4.0e-2 + 3 * 1.15 * a**2
    mass = np.diag([J_MOTOR, 1.70e-3, j_carrier, 1.46e-3, 1.46e-3, 1.46e-3, J_LOAD])
    stiff = np.zeros((7, 7))

    def spring(k, vec):
        stiff[:] += k * np.outer(vec, vec)

    def vec(**coef):
        v = np.zeros(7)
        for name, c in coef.items():
            v[i[name]] += c
        return v

    spring(K_SHAFT, vec(motor=1.0, sun=-1.0))
    spring(K_LOAD, vec(carrier=1.0, load=-1.0))
    for p in ("planet1", "planet2", "planet3"):
        spring(K_SUN, vec(sun=rb_s, carrier=-(rb_s + rb_p), **{p: rb_p}))
        spring(K_RING, vec(carrier=-(rb_r - rb_p), **{p: -rb_p}))
    w2 = scipy.linalg.eigh(stiff, mass, eigvals_only=True)
    hand = np.sqrt(np.clip(w2, 0, None)) / (2 * math.pi)
    got = modal_analysis(model).frequencies_hz
    np.testing.assert_allclose(np.sort(got)[1:], hand[1:], rtol=1e-9)
    assert abs(np.sort(got)[0]) < 1e-6 * hand[-1] and hand[0] < 1e-6 * hand[-1]  # rigid mode
    # the two lowest are the drive-train modes (motor against set, set against load)
    assert hand[1] < 100 and hand[2] < 400 < hand[3]
    assert model.kinematic_ratios["load"] == pytest.approx(33 / 147, rel=1e-12)


def test_motor_runs_up_to_its_kloss_working_point():
    """Induction motor (Kloss: n0 = 1500 min^-1, T_k = 200 N m, s_k = 0.2; starting torque
    2 T_k / (1/s_k + s_k) = 76.9 N m) starts the drive train against a constant load of
    300 N m at the load (lossless: 300 * 33/147 = 67.3 N m at the motor). The steady speed is
    the slip of the Kloss curve with T(s) = 67.3 N m: s = s_k (T_k/T - sqrt((T_k/T)^2 - 1)) =
    0.0344, worked out here."""
    model = assemble(gearset_from_dict(drive_train_config()))
    t_load = 300.0
    t_motor = t_load * 33 / 147
    n0, tk, sk = 1500.0, 200.0, 0.2
    ratio = tk / t_motor
    slip = sk * (ratio - math.sqrt(ratio**2 - 1))
    motor = MotorDriven.kloss(n0, tk, sk, load_torque=(t_load, 0.0, 0.0), duration=1.0)
    res = simulate(model, motor)
    assert res.drive == "motor"
    late = res.time > 0.85  # settled from about 0.7 s
    speed = res.input_speed[late].mean()
    assert speed == pytest.approx(n0 * (1 - slip), rel=1e-3)
    assert res.drive_torque[late].mean() == pytest.approx(t_motor, rel=5e-3)
    # the table reproduces the Kloss formula
    n = np.asarray(motor.speed_rpm)
    s = (n0 - n) / n0
    with np.errstate(divide="ignore", invalid="ignore"):
        exact = np.where(s == 0, 0.0, 2 * tk / (s / sk + sk / s))
    mid = 0.5 * (n[1:] + n[:-1])
    sm = (n0 - mid) / n0
    exact_mid = 2 * tk / (sm / sk + sk / sm)
    interp_mid = np.interp(mid, n, exact)
    assert np.abs(interp_mid - exact_mid).max() < 1e-4 * tk
    ds = res.to_dataset()
    assert ds.attrs["drive"] == "motor"


def test_simulation_settings_for_every_drive():
    speed = conditions_from_settings(read_run_settings(
        {"speed_end_rpm": 3000.0, "duration": 0.5, "input_torque": 60.0,
         "drive_stiffness": 1e4, "drive_damping": 5.0}))
    assert speed.coupling.stiffness == 1e4 and speed.input_torque == 60.0
    torque = conditions_from_settings(read_run_settings(
        {"drive": "torque", "input_torque": 40.0, "load_torque": [10.0, 0.1, 0.01],
         "load_inertia": 0.3, "speed_end_rpm": 2000.0}))
    assert torque.load_torque == (10.0, 0.1, 0.01) and torque.max_rpm == 2000.0
    motor = conditions_from_settings(read_run_settings(
        {"drive": "motor", "motor": {"synchronous_rpm": 1500, "breakdown_torque": 200,
                                     "breakdown_slip": 0.2}, "load_torque": 100.0}))
    assert isinstance(motor, MotorDriven) and motor.max_rpm == 1500.0
    table = conditions_from_settings(read_run_settings(
        {"drive": "motor", "motor": {"speed_rpm": [0, 1000, 1500], "torque": [80, 90, 0]}}))
    assert table.torque == (80.0, 90.0, 0.0)


@pytest.mark.parametrize(
    ("sim", "match"),
    [
        ({"drive": "electric"}, r"drive = 'electric' is not admissible"),
        ({"drive": "motor"}, r"\[simulation\].motor is required"),
        ({"drive": "motor", "motor": {"synchronous_rpm": 1500}}, r"incomplete \[simulation\]"),
        ({"drive": "motor", "motor": {"synchronous_rpm": 1500, "breakdown_torque": 200,
                                      "breakdown_slip": 0.2, "poles": 4}}, r"'poles'"),
        ({"drive": "motor", "motor": {"synchronous_rpm": -5, "breakdown_torque": 200,
                                      "breakdown_slip": 0.2}}, r"motor.synchronous_rpm"),
        ({"drive": "motor", "motor": {"speed_rpm": [0, 1], "torque": "x"}}, r"motor.torque"),
        ({"drive": "speed", "load_inertia": 1.0}, r"load_inertia applies to drive = 'torque'"),
        ({"drive": "torque"}, r"input_torque is required"),
        ({"drive": "speed", "motor": {}}, r"motor applies to drive = 'motor'"),
        ({"duration": -1.0}, r"duration = -1.0 is not admissible"),
        ({"load_inertia": "x", "drive": "torque", "input_torque": 1}, r"load_inertia must be"),
        ({"drive_damping": 3.0}, r"drive_damping needs drive_stiffness"),
        ({"input_torque": 1.0, "load_torque": 2.0}, r"not both"),
        ({"gyroscopic": "yes"}, r"gyroscopic must be true or false"),
        ({"dt": 0.0}, r"dt = 0.0 is not admissible"),
    ],
)
def test_bad_simulation_settings_name_the_key(sim, match):
    with pytest.raises(ValueError, match=match):
        read_run_settings(sim)


def test_extra_bodies_and_couplings_on_every_type():
    cfg = drive_train_config()
    gs = gearset_from_dict(cfg)
    assert {"motor", "load"} <= {b.name for b in gs.bodies} and len(gs.couplings) == 2
    bad = copy.deepcopy(cfg)
    bad["coupling"][0]["body2"] = "shaft"
    with pytest.raises(ConfigError, match=r"coupling: unknown body 'shaft'"):
        gearset_from_dict(bad)
    bad = copy.deepcopy(cfg)
    bad["mesh"] = []
    with pytest.raises(ConfigError, match=r"unknown key 'mesh' in a description of type = "
                                          r"'simple'"):
        gearset_from_dict(bad)
    bad = copy.deepcopy(cfg)
    bad["body"][0]["inertia"] = -1.0
    with pytest.raises(ConfigError, match=r"\[\[body\]\] 'motor'.*inertia"):
        gearset_from_dict(bad)


def test_motor_and_load_on_a_two_stage_and_a_ravigneaux_set():
    cfg, _ = load_config("two-stage-example")
    cfg = copy.deepcopy(cfg)
    cfg["body"] = [{"name": "motor", "role": "central", "mass": 15.0, "inertia": 0.03}]
    cfg["coupling"] = [{"body1": "motor", "body2": "s1.sun", "stiffness": 3e3, "damping": 1.0}]
    cfg["operation"] = {"fixed": ["s1.ring", "s2.ring"], "input": "motor",
                        "output": "s2.carrier"}
    model = assemble(gearset_from_dict(cfg))
    assert model.kinematic_ratios["s2.carrier"] == pytest.approx(21 / 96 * 24 / 102, rel=1e-12)
    assert "motor.theta" in model.dof_names
    rav, _ = load_config("ravigneaux-example")
    rav = copy.deepcopy(rav)
    rav["body"] = [{"name": "drum", "role": "central", "mass": 5.0, "inertia": 0.05}]
    rav["coupling"] = [{"body1": "ring", "body2": "drum", "stiffness": 5e4}]
    rav["operation"]["output"] = "drum"
    model = assemble(gearset_from_dict(rav))
    assert model.output_member == "drum"
    assert model.kinematic_ratios["drum"] == pytest.approx(model.kinematic_ratios["ring"])


def test_a_stage_keeps_its_own_bodies_and_couplings():
    cfg, _ = load_config("two-stage-example")
    cfg = copy.deepcopy(cfg)
    cfg["stage2"]["body"] = [{"name": "drum", "role": "central", "mass": 5.0, "inertia": 0.5}]
    cfg["stage2"]["coupling"] = [{"body1": "carrier", "body2": "drum", "stiffness": 1e5}]
    cfg["stage2"]["operation"]["output"] = "drum"
    gs = gearset_from_dict(cfg)
    assert ("s2.carrier", "s2.drum") in [(c.body1, c.body2) for c in gs.couplings]
    model = assemble(gs)
    assert model.output_member == "s2.drum"
    assert model.kinematic_ratios["s2.drum"] == pytest.approx(21 / 96 * 24 / 102, rel=1e-12)
