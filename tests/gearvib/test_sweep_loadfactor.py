"""Dynamic factor K_v of the sweep summaries against quasi-static and hand-written references."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gearvib.assembly import assemble
from gearvib.config import load_gearset
from gearvib.io import read_run
from gearvib.sweep import load_sweep, run_sweep

# A single external gear pair on a fixed frame: wheel (input, driven through a torsional
# coupling at constant speed) and pinion (output, constant load torque). Purely torsional:
# 2 DOF, theta_wheel and theta_pinion.
R1, R2, Z1, Z2 = 0.05, 0.025, 50, 25
J1, J2 = 2e-2, 2e-3
K_MEAN, K_COS = 3e8, 1.5e7          # fourier stiffness k(s) = K_MEAN + K_COS cos(2 pi s)
C_MESH = 1571.0                      # N s/m: about 3 % of critical for the mesh mode
K_C, C_C = 1e4, 33.0                 # drive coupling (rigid-body mode at 95 Hz, ~critical)
T_IN = 100.0                         # N m at the wheel
FS = 50000.0
WINDOW = (0.04, 0.06)                # steady state: the start transient has decayed (tau 3 ms)

PAIR_TOML = f"""
name = "pair"
type = "general"

[operation]
fixed = "frame"
input = "wheel"
output = "pinion"

[[body]]
name = "wheel"
role = "central"
mass = 3.0
inertia = {J1}
support = {{ radial = "rigid", axial = "rigid", torsional = "free" }}

[[body]]
name = "frame"
role = "carrier"
mass = 10.0
inertia = 1.0
support = {{ radial = "rigid", axial = "rigid" }}

[[body]]
name = "pinion"
role = "planet"
carrier = "frame"
angle_deg = 0.0
mass = 1.0
inertia = {J2}
support = {{ radial = "rigid", tangential = "rigid", axial = "rigid" }}

[[mesh]]
name = "wheel-pinion"
gear1 = "wheel"
gear2 = "pinion"
base_radius1 = {R1}
base_radius2 = {R2}
pressure_angle_deg = 20.0
z1 = {Z1}
z2 = {Z2}
stiffness = {{ model = "fourier", mean = {K_MEAN}, cos = [{K_COS}] }}
damping = {C_MESH}
"""


def _mesh_mode_hz() -> float:
    """Highest natural frequency of the 2-DOF system at mean stiffness (the mesh mode)."""
    m = np.diag([J1, J2])
    k = K_MEAN * np.outer([R1, R2], [R1, R2]) + np.diag([K_C, 0.0])
    return float(np.sqrt(np.max(np.linalg.eigvals(np.linalg.solve(m, k)).real)) / (2 * np.pi))


def _hand_solution(rpm: float, s0: float, t_eval: np.ndarray, *, k_cos: float = K_COS,
                   damping: float = C_MESH, backlash: float = 0.0,
                   max_step: float = 1e-5) -> tuple[np.ndarray, np.ndarray]:
    """Normal tooth force (left flank + right flank) and mesh deflection of the pair at constant
    input speed, integrated with solve_ivp."""
    w = rpm * 2 * math.pi / 60
    t_load = T_IN * Z2 / Z1  # lossless: T_in w1 = T_load |w2|
    half = backlash / 2

    def stiffness(th1: float, th2: float) -> float:
        s = (Z1 * th1 - Z2 * th2) / (4 * math.pi) + s0
        return K_MEAN + k_cos * math.cos(2 * math.pi * s)

    def force(y: np.ndarray) -> float:
        th1, th2, w1, w2 = y
        delta = R1 * th1 + R2 * th2
        rate = damping * (R1 * w1 + R2 * w2)
        if delta > half:  # left flank: compressive, no tension
            return max(stiffness(th1, th2) * (delta - half) + rate, 0.0)
        if delta < -half:  # right flank
            return min(stiffness(th1, th2) * (delta + half) + rate, 0.0)
        return 0.0

    def rhs(t: float, y: np.ndarray) -> list[float]:
        f = force(y)
        return [y[2], y[3], (K_C * (w * t - y[0]) + C_C * (w - y[2]) - R1 * f) / J1,
                (-R2 * f + t_load) / J2]

    # static equilibrium at t = 0 (phi = 0), stiffness at the equilibrium's own mesh position
    f_static = t_load / R2
    th1 = -R1 * f_static / K_C
    th2 = 0.0
    for _ in range(50):
        th2 = (f_static / stiffness(th1, th2) + half - R1 * th1) / R2
    y0 = [th1, th2, w, -w * Z1 / Z2]
    sol = solve_ivp(rhs, (0.0, float(t_eval[-1])), y0, method="DOP853", t_eval=t_eval,
                    rtol=1e-11, atol=1e-14, max_step=max_step)
    assert sol.success
    return np.array([force(y) for y in sol.y.T]), R1 * sol.y[0] + R2 * sol.y[1]


def test_dynamic_factor_of_a_gear_pair_near_resonance_matches_solve_ivp(tmp_path):
    (tmp_path / "pair.toml").write_text(PAIR_TOML)
    fn = _mesh_mode_hz()
    rpms = [0.97 * fn / Z1 * 60, 0.85 * fn / Z1 * 60]  # mesh frequency 0.97 and 0.85 f_n
    rpm_list = ", ".join(f"{r!r}" for r in rpms)
    (tmp_path / "sweep.toml").write_text(f"""
base = "pair.toml"
mode = "zip"
[simulation]
duration = {WINDOW[1]}
fs_out = {FS}
input_torque = {T_IN}
drive_stiffness = {K_C}
drive_damping = {C_C}
[[parameter]]
path = "simulation.speed_start_rpm"
values = [{rpm_list}]
[[parameter]]
path = "simulation.speed_end_rpm"
values = [{rpm_list}]
[summary]
window_s = [{WINDOW[0]}, {WINDOW[1]}]
""")
    result = run_sweep(load_sweep(tmp_path / "sweep.toml"), tmp_path / "out", workers=1,
                       progress=False, report=False)
    ds = result.dataset
    model = assemble(load_gearset(tmp_path / "pair.toml"))
    # the mesh-position convention used by hand: s = (z1 theta1 - z2 theta2) / 4 pi + s0
    i1, i2 = model.dof_names.index("wheel.theta"), model.dof_names.index("pinion.theta")
    np.testing.assert_allclose(model.mesh_position_vectors[0, [i1, i2]],
                               [Z1 / (4 * math.pi), -Z2 / (4 * math.pi)], rtol=1e-12)
    s0 = float(model.mesh_position_offsets[0])
    f_static = T_IN / R1
    np.testing.assert_allclose(ds.static_tooth_force.values, f_static, rtol=1e-9)
    kv = []
    for case, rpm in enumerate(rpms):
        run = read_run(tmp_path / "out" / str(ds.run_file.values[case]))
        t = run.time.values
        hand, _ = _hand_solution(rpm, s0, t)
        sim = run.normal_force.sel(mesh="wheel-pinion", flank="left").values
        win = (t >= WINDOW[0] - 1e-12) & (t <= WINDOW[1] + 1e-12)
        # the whole force history (measured: 5e-7 of the peak), and K_v = max / static over
        # the window (measured: 3e-7)
        np.testing.assert_allclose(sim[win], hand[win], atol=5e-6 * hand[win].max())
        kv_hand = hand[win].max() / f_static
        kv.append(kv_hand)
        np.testing.assert_allclose(ds.dynamic_factor.values[case, 0], kv_hand, rtol=5e-6)
        assert ds.contact_loss_fraction.values[case, 0] == 0.0
    # near resonance the dynamic load is well above the static one, and above the off-tuned case
    assert kv[0] > 1.3
    assert kv[0] > kv[1] > 1.0


def test_dynamic_factor_of_a_rigid_body_case_is_one(tmp_path):
    """Constant mesh stiffness, slow ramp from the static equilibrium: no dynamic load."""
    (tmp_path / "rigid.toml").write_text("""
base = "paper-case1"
mode = "zip"
[simulation]
speed_start_rpm = 0
speed_end_rpm = 100
duration = 0.05
input_torque = 60
[[parameter]]
path = "meshes.sun.stiffness"
values = [{model = "constant", k = 3.5e7}, {model = "constant", k = 5e7}]
[[parameter]]
path = "meshes.ring.stiffness"
values = [{model = "constant", k = 4e7}, {model = "constant", k = 3e7}]
""")
    ds = run_sweep(load_sweep(tmp_path / "rigid.toml"), tmp_path / "out", workers=1,
                   progress=False, report=False).dataset
    kv = ds.dynamic_factor.values
    assert kv.shape == (2, 6)
    # tolerance: 1e-5 (measured 1e-6 .. 2e-6: the ramp ends at the last sample, and the
    # zero-phase decimation filter lets the end of the acceleration reach the last samples)
    np.testing.assert_allclose(kv, 1.0, atol=1e-5)
    assert np.all(ds.contact_loss_fraction.values == 0.0)
    # the static force is the nominal share: input torque and the d'Alembert torque of the
    # ramp, carried by three planets (sun base radius m z cos(alpha) / 2)
    r_b = 2.5e-3 * 33 * math.cos(math.radians(20.0)) / 2
    assert ds.static_tooth_force.values[0, 0] == pytest.approx(60.0 / (3 * r_b), rel=0.02)


def test_contact_loss_with_backlash_matches_solve_ivp(tmp_path):
    """At resonance with a 25 % stiffness variation the teeth separate in every mesh cycle."""
    backlash, k_cos = 10e-6, 0.25 * K_MEAN
    jeq = J1 * J2 / (J1 * R2**2 + J2 * R1**2)
    damping = 2 * 0.08 * math.sqrt(K_MEAN * jeq)  # 8 % of critical: steady after ~8 ms
    text = PAIR_TOML.replace(f"cos = [{K_COS}]", f"cos = [{k_cos}]").replace(
        f"damping = {C_MESH}", f"damping = {damping}\nbacklash = {backlash}")
    (tmp_path / "pair.toml").write_text(text)
    rpm = _mesh_mode_hz() / Z1 * 60
    (tmp_path / "sweep.toml").write_text(f"""
base = "pair.toml"
mode = "zip"
[simulation]
duration = 0.015
fs_out = 100000.0
input_torque = {T_IN}
drive_stiffness = {K_C}
drive_damping = {C_C}
[[parameter]]
path = "simulation.speed_start_rpm"
values = [{rpm!r}]
[[parameter]]
path = "simulation.speed_end_rpm"
values = [{rpm!r}]
[summary]
window_s = [0.008, 0.015]
""")
    ds = run_sweep(load_sweep(tmp_path / "sweep.toml"), tmp_path / "out", workers=1,
                   progress=False, report=False).dataset
    model = assemble(load_gearset(tmp_path / "pair.toml"))
    run = read_run(tmp_path / "out" / str(ds.run_file.values[0]))
    t = run.time.values
    force, delta = _hand_solution(rpm, float(model.mesh_position_offsets[0]), t, k_cos=k_cos,
                                  damping=damping, backlash=backlash, max_step=2e-6)
    win = t >= 0.008 - 1e-12
    # deflections agree to 5e-4 of their peak (measured) ...
    np.testing.assert_allclose(run.mesh_deflection.values[0][win], delta[win],
                               atol=2e-3 * np.abs(delta).max())
    # ... so does the fraction of samples out of contact (measured: equal), and K_v (5e-5)
    loss = float(np.mean(delta[win] <= backlash / 2))
    assert 0.1 < loss < 0.5
    assert ds.contact_loss_fraction.values[0, 0] == pytest.approx(loss, abs=2.0 / win.sum())
    assert ds.back_contact_fraction.values[0, 0] == float(np.mean(delta[win] < -backlash / 2))
    assert ds.dynamic_factor.values[0, 0] == pytest.approx(force[win].max() * R1 / T_IN,
                                                           rel=1e-3)


def test_static_tooth_force_of_the_back_flank_mirrors_the_front_on_elastic_bearings():
    """Reversed torque on elastic bearings: the back flanks carry the same static forces.

    The back flank has its own (mirror-image) line of action; reading its deflection along the
    front flank's line would give other forces once the bearings let the centres move.
    """
    from gearvib.assembly import assemble
    from gearvib.config import load_gearset
    from gearvib.simulate import SpeedRamp, static_tooth_forces

    model = assemble(load_gearset("paper-case1-elastic"))
    fwd = static_tooth_forces(model, SpeedRamp(500.0, 500.0, 0.1, input_torque=60.0))
    rev = static_tooth_forces(model, SpeedRamp(500.0, 500.0, 0.1, input_torque=-60.0))
    assert (fwd.flank == 0).all() and (rev.flank == 1).all()
    np.testing.assert_allclose(rev.force, fwd.force, rtol=1e-9)
