"""Tests of the numba kernels against analytic solutions and scipy.integrate.solve_ivp."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gearvib import kernels as kn

I1, I2 = 2e-3, 5e-3  # kg m^2
R1, R2 = 0.04, 0.06  # base radii [m]
Z1 = 20
M_E = 1.0 / (R1**2 / I1 + R2**2 / I2)  # equivalent mass on the line of action


def pair_system(
    k_left: np.ndarray | float = 1e8,
    k_right: np.ndarray | float = 1e8,
    backlash: float = 0.0,
    damping: float = 0.0,
    torque: tuple = ((0.0,), (0.0,)),
    load: tuple[float, float, float] = (0.0, 0.0, 0.0),
    limit: float = 1e-2,
    viscous: bool = False,
) -> kn.KernelSystem:
    """External gear pair, two rotations, one mesh: delta = R1 th1 + R2 th2, s = Z1 th1 / 2 pi."""
    kl = np.atleast_1d(np.asarray(k_left, dtype=float))[None, :]
    kr = np.atleast_1d(np.asarray(k_right, dtype=float))[None, :]
    z = np.zeros((2, 2))
    mode = kn.DRIVE_TORQUE if np.any(np.asarray(torque[1]) != 0) else kn.DRIVE_NONE
    fpar = np.zeros(kn.N_FPAR)
    fpar[kn.FP_OUTDIR] = -1.0  # the driven gear turns backwards
    fpar[kn.FP_T0], fpar[kn.FP_C1], fpar[kn.FP_C2] = load
    fpar[kn.FP_SPEED_LIMIT] = 1e9
    return kn.KernelSystem(
        minv=np.diag([1 / I1, 1 / I2]), stiffness=z, damping=z, gyroscopic=z, centripetal=z,
        mesh_vectors=[[R1, R2]], mesh_position_vectors=[[Z1 / (2 * np.pi), 0.0]],
        mesh_position_offsets=[0.1], left_tables=kl, right_tables=kr, backlash=[backlash],
        mesh_damping=[damping], f_const=np.zeros(2), ipar=[mode, 0, 1, -1, 0], fpar=fpar,
        speed_table=np.zeros((3, 1)), torque_table=np.array(torque, dtype=float),
        deflection_limit=[limit],
        mesh_damping_law=[kn.DAMPING_VISCOUS] if viscous else None,
    )


def pair_state(delta: float, ddelta: float) -> np.ndarray:
    """State with a given mesh deflection and rate and zero momentum."""
    # q = a * (R1 / I1, R2 / I2) has zero angular momentum sum weighted ... any direction works
    d = np.array([R1 / I1, R2 / I2])
    scale = 1.0 / (d @ np.array([R1, R2]))
    return np.concatenate([delta * scale * d, ddelta * scale * d])


@pytest.fixture(scope="session", autouse=True)
def warm_up() -> None:
    """Pay the numba compilation once per session (visible in the durations report)."""
    kn.integrate(pair_system(backlash=1e-5), pair_state(1e-5, 0.0), 1e-6, 3)


# --------------------------------------------------------------------------- contact law


def test_flank_forces_backlash_left_right_and_floor() -> None:
    j = 20e-6
    assert kn.flank_forces(5e-6, 0.3, 1e8, 2e8, j, 1e3) == (0.0, 0.0, 0.0, 0)  # in backlash
    fl, fr, k, st = kn.flank_forces(15e-6, 0.0, 1e8, 2e8, j, 1e3)
    assert (fl, fr, k, st) == pytest.approx((1e8 * 5e-6, 0.0, 1e8, 1))
    fl, fr, k, st = kn.flank_forces(-15e-6, 0.0, 1e8, 2e8, j, 1e3)
    assert (fl, fr, k, st) == pytest.approx((0.0, -2e8 * 5e-6, 2e8, 2))
    # damping acts only in contact, and a separating flank never pulls (floor / cap at 0)
    assert kn.flank_forces(11e-6, -10.0, 1e8, 2e8, j, 1e3)[0] == 0.0
    assert kn.flank_forces(11e-6, 0.1, 1e8, 2e8, j, 1e3)[0] == pytest.approx(1e8 * 1e-6 + 100)
    assert kn.flank_forces(-11e-6, 10.0, 1e8, 2e8, j, 1e3)[1] == 0.0


def test_viscous_law_damps_always_and_never_floors() -> None:
    """Kahraman & Singh's law: the springs of the gated law plus ``c delta'`` everywhere, on
    the left flank's line unless only the back flank is in contact; no floor, no cap."""
    j, c = 20e-6, 1e3
    law = kn.flank_forces_viscous
    # inside the backlash: the viscous force alone, on the left line, states and k_eff zero
    assert law(5e-6, 0.3, 5e-6, 0.3, 1e8, 2e8, j, c) == (c * 0.3, 0.0, 0.0, 0)
    assert law(5e-6, -0.3, 5e-6, -0.3, 1e8, 2e8, j, c) == (-c * 0.3, 0.0, 0.0, 0)
    # left flank: spring + damping, pulling when the flank separates fast (gated: 0)
    fl, fr, k, st = law(11e-6, -10.0, 11e-6, -10.0, 1e8, 2e8, j, c)
    assert (fl, fr, k, st) == (1e8 * (11e-6 - 10e-6) + c * -10.0, 0.0, 1e8, 1)
    assert fl < 0.0 and kn.flank_forces(11e-6, -10.0, 1e8, 2e8, j, c)[0] == 0.0
    # back flank alone: on its own line (delta_R, its rate), pushing back when it separates
    fl, fr, k, st = law(-11e-6, 10.0, -12e-6, 11.0, 1e8, 2e8, j, c)
    assert (fl, fr, k, st) == (0.0, 2e8 * (-12e-6 + 10e-6) + c * 11.0, 2e8, 2)
    assert fr > 0.0
    # both flanks (preload): one damper, on the left line (the gated law has one per flank)
    fl, fr, k, st = law(2e-6, 0.5, 2e-6, 0.5, 1e8, 2e8, -j, c)
    assert (fl, fr, k, st) == (1e8 * (2e-6 + 10e-6) + c * 0.5, 2e8 * (2e-6 - 10e-6), 3e8, 3)
    # with one line of action the total is the published k f(x) + c x' in every zone
    for x, v in itertools.product((-15e-6, -3e-6, 0.0, 4e-6, 13e-6), (-2.0, 0.0, 1.5)):
        fl, fr, _, _ = law(x, v, x, v, 1e8, 1e8, j, c)
        dead = x - j / 2 if x > j / 2 else (x + j / 2 if x < -j / 2 else 0.0)
        assert fl + fr == pytest.approx(1e8 * dead + c * v, rel=1e-15, abs=1e-15)


def test_negative_backlash_loads_both_flanks_doubled_stiffness() -> None:
    j = -20e-6
    fl, fr, k, st = kn.flank_forces(3e-6, 0.0, 1e8, 1e8, j, 0.0)
    assert st == 3
    assert k == 2e8
    assert fl == pytest.approx(1e8 * 13e-6)
    assert fr == pytest.approx(-1e8 * 7e-6)
    assert fl + fr == pytest.approx(2e8 * 3e-6)  # superposed: doubled stiffness about delta = 0


def test_periodic_interp_matches_model_convention() -> None:
    rng = np.random.default_rng(1)
    tab = rng.uniform(1e8, 2e8, size=(3, 17))
    s = rng.uniform(-40, 40, size=200)
    s[:3] = (0.0, -1e-17, 1.0 - 1e-17)  # wrap-around edge cases
    n = tab.shape[1]
    for row in range(3):
        got = np.array([kn.periodic_interp(tab, row, x) for x in s])
        u = (s - np.floor(s)) * n
        i0 = np.floor(u).astype(int) % n
        w = u - np.floor(u)
        ref = (1 - w) * tab[row, i0] + w * tab[row, (i0 + 1) % n]
        np.testing.assert_allclose(got, ref, rtol=1e-12)


# --------------------------------------------------------------------------- integrator


def test_rk4_linear_pair_matches_analytic_and_is_fourth_order() -> None:
    k = 1e8
    w = np.sqrt(k / M_E)
    period = 2 * np.pi / w
    errors = []
    for steps in (50, 100):
        dt = period / steps
        n = 10 * steps
        rec, _, status, _ = kn.integrate(pair_system(k, k), pair_state(1e-5, 0.0), dt, n)
        assert status[0] == kn.STATUS_OK
        delta = rec[:, :2] @ np.array([R1, R2])
        t = np.arange(n + 1) * dt
        errors.append(np.abs(delta - 1e-5 * np.cos(w * t)).max() / 1e-5)
    assert errors[1] < 2e-5
    assert 12 < errors[0] / errors[1] < 20  # RK4: error ~ dt^4


def test_energy_conserved_through_backlash_and_flank_changes() -> None:
    """Undamped pair, kL != kR, amplitude far beyond the backlash: flank changes every cycle.

    Tolerance, with 400 steps per period of the stiffer flank: relative energy error < 5e-5 at
    any time and drift < 1e-5 after ~56 flank changes. RK4 is not symplectic, and a step that
    straddles a contact kink is only locally second order (measured: max error 7e-5, 1.8e-5,
    3.6e-6 at 200, 400, 800 steps per period).
    """
    kl, kr, j = 1e8, 2e8, 20e-6
    sys_ = pair_system(kl, kr, backlash=j)
    period = 2 * np.pi / np.sqrt(kr / M_E)
    dt = period / 400
    rec, changes, status, _ = kn.integrate(sys_, pair_state(0.0, 0.5), dt, 8000)
    assert status[0] == kn.STATUS_OK
    q, qd = rec[:, :2], rec[:, 2:4]
    delta = q @ np.array([R1, R2])
    kin = 0.5 * (I1 * qd[:, 0] ** 2 + I2 * qd[:, 1] ** 2)
    pot = np.where(delta > j / 2, 0.5 * kl * (delta - j / 2) ** 2, 0.0)
    pot += np.where(delta < -j / 2, 0.5 * kr * (delta + j / 2) ** 2, 0.0)
    energy = kin + pot
    assert changes[0] >= 40
    assert np.abs(energy / energy[0] - 1).max() < 5e-5
    assert abs(energy[-1] / energy[0] - 1) < 1e-5
    # no force inside the backlash, the right flank carries the negative side
    inside = np.abs(delta) < j / 2
    assert inside.any()
    assert np.all(rec[inside, 4:7] == 0.0)
    assert np.all(rec[delta > j / 2, 5] == 0.0)
    assert np.all(rec[delta < -j / 2, 4] == 0.0)


def test_negative_backlash_oscillates_with_doubled_stiffness() -> None:
    k, j = 1e8, -40e-6
    w = np.sqrt(2 * k / M_E)
    dt = 2 * np.pi / w / 200
    rec, changes, status, _ = kn.integrate(
        pair_system(k, k, backlash=j), pair_state(5e-6, 0.0), dt, 2000
    )
    assert status[0] == kn.STATUS_OK
    assert changes[0] == 0
    np.testing.assert_allclose(rec[:, 6], 2 * k, rtol=1e-14)
    delta = rec[:, :2] @ np.array([R1, R2])
    np.testing.assert_allclose(delta, 5e-6 * np.cos(w * np.arange(2001) * dt), atol=5e-6 * 1e-6)


def _python_rhs(t, y, kl_tab, kr_tab, j, c, torque, load, viscous=False):
    """Independent right-hand side of the gear pair (plain numpy); ``viscous``: Kahraman &
    Singh's always-on damping ``k f(delta) + c delta'``."""
    th1, th2, w1, w2 = y
    delta = R1 * th1 + R2 * th2
    ddelta = R1 * w1 + R2 * w2
    s = 0.1 + Z1 * th1 / (2 * np.pi)
    n = kl_tab.size
    grid = np.arange(n + 1) / n
    frac = s % 1.0
    kl = np.interp(frac, grid, np.append(kl_tab, kl_tab[0]))
    kr = np.interp(frac, grid, np.append(kr_tab, kr_tab[0]))
    f = 0.0
    if viscous:
        f = c * ddelta
        if delta > j / 2:
            f += kl * (delta - j / 2)
        if delta < -j / 2:
            f += kr * (delta + j / 2)
    else:
        if delta > j / 2:
            f += max(kl * (delta - j / 2) + c * ddelta, 0.0)
        if delta < -j / 2:
            f += min(kr * (delta + j / 2) + c * ddelta, 0.0)
    t_in = np.interp(t, torque[0], torque[1])
    wo = -w2
    t_load = load[0] + load[1] * wo + load[2] * wo * abs(wo)
    a1 = (t_in - f * R1) / I1
    a2 = (-f * R2 + t_load) / I2  # load resists backward rotation of gear 2
    return [w1, w2, a1, a2]


@pytest.mark.parametrize("viscous", [False, True], ids=["gated", "viscous"])
def test_rk4_matches_solve_ivp_on_nonlinear_pair(viscous: bool) -> None:
    """Time-varying (position-dependent) stiffness, backlash, damping, torque table, load.

    DOP853 at rtol 1e-10 on an independent numpy right-hand side, for both mesh-damping laws.
    With ~29 flank changes the agreement is limited by the contact kinks (the RK4 error then
    converges irregularly): measured 5e-8 of the largest angle, 2e-6 of the largest speed and
    1e-4 of the largest mesh deflection (0.2 N of tooth force at k = 1e8 N/m).
    """
    phase = np.arange(32) / 32
    kl_tab = 1e8 * (1 + 0.3 * np.sin(2 * np.pi * phase))
    kr_tab = 0.8e8 * (1 + 0.2 * np.cos(2 * np.pi * phase))
    j, c = 10e-6, 200.0
    torque = ((0.0, 0.01, 0.02), (50.0, -80.0, 30.0))  # reverses: both flanks get loaded
    load = (5.0, 0.01, 1e-4)
    sys_ = pair_system(kl_tab, kr_tab, backlash=j, damping=c, torque=torque, load=load,
                       viscous=viscous)
    y0 = np.array([0.0, 0.0, 50.0, -50.0 * R1 / R2])
    dt, n = 5e-7, 60000
    rec, changes, status, _ = kn.integrate(sys_, y0, dt, n)
    assert status[0] == kn.STATUS_OK
    assert changes[0] >= 2
    t_eval = np.arange(0, n + 1, 500) * dt
    ref = solve_ivp(
        _python_rhs, (0.0, n * dt), y0, method="DOP853", rtol=1e-10, atol=1e-14,
        t_eval=t_eval, args=(kl_tab, kr_tab, j, c, np.array(torque), load, viscous),
    )
    assert ref.success
    got = rec[::500, :4]
    delta_ref = ref.y[0] * R1 + ref.y[1] * R2
    delta_got = got[:, 0] * R1 + got[:, 1] * R2
    np.testing.assert_allclose(delta_got, delta_ref, rtol=0, atol=3e-4 * np.abs(delta_ref).max())
    scale = np.abs(ref.y).max(axis=1)
    tol = np.array([2e-7, 2e-7, 1e-5, 1e-5]) * scale
    assert np.all(np.abs(got - ref.y.T) <= tol)


JUMPY = np.array([3e7, 3e7, 3e7, 3e7, 3e7, 5e7, 5e7, 5e7])  # stiffness over one mesh cycle


def jump_oscillator(table: np.ndarray, f_mesh: float, mass: float, force: float):
    """Oscillator ``m x'' + k(s) x = F`` whose stiffness follows a table of the mesh position
    ``s = f_mesh t + s0`` of a free rotor turning at constant speed (rotor: DOF 0, x: DOF 1).

    Both flanks carry half the table with a large negative backlash, so the contact is linear
    and always closed: ``F_L + F_R = k(s) x``.
    """
    z = 10
    half = (np.asarray(table, dtype=float) / 2)[None, :]
    system = kn.KernelSystem(
        minv=np.diag([1.0, 1.0 / mass]), stiffness=np.zeros((2, 2)), damping=np.zeros((2, 2)),
        gyroscopic=np.zeros((2, 2)), centripetal=np.zeros((2, 2)),
        mesh_vectors=[[0.0, 1.0]], mesh_position_vectors=[[z / (2 * np.pi), 0.0]],
        mesh_position_offsets=[0.3], left_tables=half, right_tables=half, backlash=[-1.0],
        mesh_damping=[0.0], f_const=[0.0, force], ipar=[kn.DRIVE_NONE, -1, -1, -1, 0],
        fpar=np.r_[0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1e9], speed_table=np.zeros((3, 1)),
        torque_table=np.zeros((2, 1)), deflection_limit=[1.0],
    )
    y0 = np.array([0.0, force / table.mean(), 2 * np.pi * f_mesh / z, 0.0])
    return system, y0


def test_jump_positions_of_rectangular_and_smooth_tables() -> None:
    """Both ends of every jump segment are found; a smooth table has none."""
    smooth = 4e7 + 1e7 * np.sin(2 * np.pi * np.arange(2048) / 2048)
    found = kn.jump_positions(np.stack([JUMPY, JUMPY]), np.stack([JUMPY, JUMPY]))
    np.testing.assert_allclose(found[0], [0.0, 4 / 8, 5 / 8, 7 / 8])
    assert kn.jump_positions(smooth[None, :], smooth[None, :])[0].size == 0


def test_rk4_keeps_fourth_order_through_stiffness_jumps() -> None:
    """With sub-steps ending at the table jumps, the RK4 error through tooth-pair changes
    falls as dt^4 and matches a solve_ivp (DOP853) reference integrated piece by piece between
    the jumps (where its right-hand side is smooth)."""
    f_mesh, mass, force = 500.0, 1.0, 1e3
    system, y0 = jump_oscillator(JUMPY, f_mesh, mass, force)
    cycles = 10
    t_end = cycles / f_mesh
    n_tab = JUMPY.size
    grid = np.arange(n_tab + 1) / n_tab

    def rhs(t: float, y: np.ndarray) -> np.ndarray:
        s = (0.3 + f_mesh * t) % 1.0
        k = np.interp(s, grid, np.r_[JUMPY, JUMPY[0]])
        return np.array([y[1], (force - k * y[0]) / mass])

    # breakpoints: every table sample (the table is piecewise linear between them)
    s_nodes = np.arange(np.floor(0.3 * n_tab), (0.3 + f_mesh * t_end) * n_tab + 1) / n_tab
    t_nodes = np.unique(np.clip((s_nodes - 0.3) / f_mesh, 0.0, t_end))
    f_nat = np.sqrt(JUMPY.max() / mass) / (2 * np.pi)
    dt = t_end / round(t_end * 40 * f_nat)  # 40 steps per period, as simulate() chooses
    n_steps = round(t_end / dt)
    t_out = np.arange(n_steps + 1) * dt
    ref = np.empty((t_out.size, 2))
    state = y0[[1, 3]]
    for a, b in itertools.pairwise(t_nodes):
        sol = solve_ivp(rhs, (a, b), state, method="DOP853", rtol=1e-12, atol=1e-16,
                        dense_output=True)
        inside = (t_out >= a) & (t_out <= b)
        ref[inside] = sol.sol(t_out[inside]).T
        state = sol.y[:, -1]
    errors = []
    for refine in (1, 2):
        rec, _, status, _ = kn.integrate(system, y0, dt / refine, n_steps * refine)
        assert status[0] == kn.STATUS_OK
        x = rec[::refine, 1]
        errors.append(np.abs(x - ref[:, 0]).max() / np.abs(ref[:, 0]).max())
    assert errors[0] < 5e-4  # measured 1.5e-4 over 22 periods at 40 steps per period
    assert errors[0] / errors[1] > 10.0  # fourth order: 16 (measured 15.5; 1.6 without sub-steps)


def test_blow_up_status_names_step() -> None:
    k = 1e8
    dt = 3.0 / np.sqrt(k / M_E)  # beyond the RK4 stability limit (omega dt ~ 2.8)
    _, _, status, _ = kn.integrate(pair_system(k, k, limit=1e-3), pair_state(1e-5, 0.0), dt, 500)
    assert status[0] == kn.STATUS_DEFLECTION
    assert 0 < status[1] < 500


def test_fir_decimate_matches_convolution() -> None:
    rng = np.random.default_rng(3)
    x = rng.standard_normal((400, 3))
    taps = rng.standard_normal(21)
    taps = (taps + taps[::-1]) / 2
    d, half = 4, 10
    out = np.zeros((50, 3))
    kn.fir_decimate(x, -5, taps, d, 2, 40, out, 3)
    for col in range(3):
        full = np.convolve(x[:, col], taps[::-1], mode="valid")  # full[r] = sum taps[i] x[r+i]
        k = np.arange(2, 42)
        np.testing.assert_allclose(out[3:43, col], full[k * d - half + 5], rtol=1e-12)
