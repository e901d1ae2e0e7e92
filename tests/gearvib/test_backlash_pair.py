"""A single spur-gear pair with backlash under harmonic excitation (Kahraman & Singh 1990).

The pair is written as ``type = "general"``: the pinion is a central gear, the wheel a "planet"
on a fixed carrier, joined by one lumped mesh (base radii, constant stiffness, backlash
``2b``). Driven by a torque ``T_m + T_a sin(phi(t))`` on the pinion against the constant load
``T_m`` on the wheel, the rigid-body rotation takes the rest and the mesh deflection ``x``
(dynamic transmission error) obeys the equation of Kahraman & Singh,

    m_e x'' + c x' + k f(x) = F_m + F_a sin(Omega t),  f = dead zone of half-width b,
    m_e = I_1 I_2 / (I_1 r_2^2 + I_2 r_1^2),  F_m = T_m / r_1,  F_a = m_e r_1 T_a / I_1,

exactly with the mesh damping law ``damping_law = "viscous"`` (``c x'`` always on); with the
default gated law the damping acts only while a flank is in contact and the flank force is
floored at 0 (``c x'`` replaced by ``max(k f(x) + c x', 0)`` in contact, 0 in the backlash).
Parameters: the published set quoted in the physics notes (section 3.1): I = 1.15e-3 kg m^2,
r = 0.05 m (m_e = 0.23 kg), k = 3.8e8 N/m (f_n = 6469 Hz), b = 0.1 mm, zeta = 0.05,
F_m / (k b) = 0.1; excitation F_a / (k b) = 0.015, for which the resonance is softening and
multivalued.

The frequency is stepped through Omega = 0.60 ... 1.20 (in units of omega_n) with a
phase-continuous sine, 60 excitation periods per step (the response settles in about
1/(zeta 2 pi) = 3 periods away from the jumps), once upwards and once downwards, each sweep
continuing from the state of the previous step. The amplitude is the fundamental Fourier
component of ``x`` over the last 30 periods of every step. The independent reference is the
nondimensional equation integrated by scipy (:func:`reference_sweep`, LSODA) with the same
steps, for both laws.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import odeint

from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict
from gearvib.simulate import TorqueDriven, simulate

INERTIA, RADIUS, K_MESH, HALF_BACKLASH = 1.15e-3, 0.05, 3.8e8, 1e-4
ZETA, F_MEAN, F_ALT = 0.05, 0.1, 0.015  # F in units of k b
M_E = INERTIA / (2 * RADIUS**2)
W_N = math.sqrt(K_MESH / M_E)
OMEGAS = np.round(np.arange(0.60, 1.2001, 0.02), 10)
PERIODS, POINTS = 60, 64  # excitation periods per step, torque-table points per period
FS = 50_000.0


def pair_config(damping_ratio: float = ZETA, law: str = "gated") -> dict:
    """The single pair as a ``type = "general"`` description (mesh-damping law ``law``)."""
    support = {"radial": "rigid", "axial": "rigid"}
    return {
        "name": "kahraman-singh-pair", "type": "general",
        "operation": {"fixed": "carrier", "input": "pinion", "output": "wheel"},
        "body": [
            {"name": "pinion", "role": "central", "mass": 1.0, "inertia": INERTIA,
             "support": {**support, "torsional": "free"}},
            {"name": "carrier", "role": "carrier", "mass": 1.0, "inertia": 1.0,
             "support": support},
            {"name": "wheel", "role": "planet", "carrier": "carrier", "mass": 1.0,
             "inertia": INERTIA, "support": {**support, "tangential": "rigid"}},
        ],
        "mesh": [{"name": "pinion-wheel", "gear1": "pinion", "gear2": "wheel",
                  "base_radius1": RADIUS, "base_radius2": RADIUS, "pressure_angle_deg": 20.0,
                  "stiffness": {"model": "constant", "k": K_MESH},
                  "backlash": 2 * HALF_BACKLASH,
                  "damping": 2 * damping_ratio * M_E * W_N, "damping_law": law}],
    }


@pytest.fixture(scope="module")
def pair():
    return assemble(gearset_from_dict(pair_config()))


def stepped_sweep(model, omegas: np.ndarray):
    """Run a phase-continuous stepped-sine sweep; amplitudes [b] and contact loss per step."""
    t_nodes, phase = [0.0], [0.0]
    windows = []
    t = ph = 0.0
    for om in omegas:
        w = om * W_N
        span = PERIODS * 2 * math.pi / w
        ts = t + np.arange(1, PERIODS * POINTS + 1) * span / (PERIODS * POINTS)
        t_nodes.extend(ts)
        phase.extend(ph + w * (ts - t))
        windows.append((t + 0.5 * span, t + span, w))
        t, ph = t + span, ph + w * span
    tt, ph_nodes = np.array(t_nodes), np.array(phase)
    t_mean = F_MEAN * K_MESH * HALF_BACKLASH * RADIUS  # F_m r_1
    t_alt = F_ALT * K_MESH * HALF_BACKLASH * INERTIA / (M_E * RADIUS)  # F_a I_1 / (m_e r_1)
    res = simulate(model, TorqueDriven((tt, t_mean + t_alt * np.sin(ph_nodes)),
                                       load_torque=(t_mean, 0.0, 0.0), max_rpm=100.0),
                   fs_out=FS, duration=float(tt[-1]))
    x, time = res.mesh_deflection[0], res.time
    amplitude, lost = [], []
    for a, b, w in windows:
        sel = (time >= a) & (time < b)
        xs, ts = x[sel], time[sel]
        lost.append(bool(xs.min() < HALF_BACKLASH))  # the loaded flank separates
        xs = xs - xs.mean()  # no leakage of the mean deflection into the fundamental
        amplitude.append(2 * math.hypot(np.mean(xs * np.cos(w * ts)),
                                        np.mean(xs * np.sin(w * ts))) / HALF_BACKLASH)
    return np.array(amplitude), np.array(lost), res


@pytest.fixture(scope="module")
def sweeps(pair):
    up, lost_up, res_up = stepped_sweep(pair, OMEGAS)
    down, lost_down, res_down = stepped_sweep(pair, OMEGAS[::-1])
    return {"up": up, "down": down[::-1], "lost_up": lost_up, "lost_down": lost_down[::-1],
            "res_up": res_up, "res_down": res_down}


def test_pair_is_the_kahraman_singh_oscillator(pair):
    """One elastic mode at sqrt(k / m_e) = 6469.16 Hz, unit ratio, static x = b + F_m / k."""
    from gearvib.modal import modal_analysis

    f = modal_analysis(pair).frequencies_hz
    assert f[0] == pytest.approx(0.0, abs=1e-6)
    assert f[1] == pytest.approx(W_N / (2 * math.pi), rel=1e-12)
    assert pair.kinematic_ratios["wheel"] == pytest.approx(-1.0, rel=1e-12)


def test_no_contact_loss_follows_the_linear_oscillator(sweeps):
    """Where the flank never separates the response is the linear oscillator's,
    F_a / sqrt((1 - W^2)^2 + (2 zeta W)^2): measured within 0.4 % (test bound 2 %)."""
    linear = F_ALT / np.sqrt((1 - OMEGAS**2) ** 2 + (2 * ZETA * OMEGAS) ** 2)
    for key in ("up", "down"):
        ok = ~sweeps[f"lost_{key}"]
        assert ok.sum() >= 15
        np.testing.assert_allclose(sweeps[key][ok], linear[ok], rtol=0.02)
    # and the mean deflection is b + F_m / k (static equilibrium, x / b = 1.1)
    x = sweeps["res_up"].mesh_deflection[0]
    assert x[0] / HALF_BACKLASH == pytest.approx(1.0 + F_MEAN, rel=1e-6)


def test_softening_jump_and_hysteresis(sweeps):
    """Up- and down-sweep differ in W = 0.76 ... 0.94 (measured): the up-sweep follows the
    linear branch until its amplitude reaches F_m (contact loss starts, W = 0.94) and jumps up
    (0.100 -> 0.149 b at W = 0.96); the down-sweep stays on the upper, separating branch down
    to W = 0.76 (0.281 b, 8x the linear value) and jumps down (to 0.033 b at W = 0.74): a
    softening, multivalued response near W = 1 with contact loss on the upper branch."""
    up, down = sweeps["up"], sweeps["down"]
    w = OMEGAS
    linear = F_ALT / np.sqrt((1 - w**2) ** 2 + (2 * ZETA * w) ** 2)
    differ = np.abs(down - up) > 0.3 * np.minimum(up, down)
    lo, hi = w[differ].min(), w[differ].max()
    assert np.all(differ[(w >= lo) & (w <= hi)])  # one interval
    assert 0.70 <= lo <= 0.84 and 0.88 <= hi <= 0.96 and hi - lo >= 0.1
    assert np.all(down[differ] > up[differ])  # softening: the down-sweep rides the upper branch
    # the lower branch ends where the linear amplitude first reaches the mean deflection F_m
    assert hi == w[np.argmax(linear >= F_MEAN)]
    # one jump each way, between neighbouring steps (x1.3 or more), the up-jump above the
    # down-jump: the hysteresis loop
    (i_up,) = np.flatnonzero(up[1:] / up[:-1] > 1.3)
    (i_down,) = np.flatnonzero(down[:-1] / down[1:] < 1 / 1.3)
    assert w[i_up + 1] == pytest.approx(hi + 0.02) and w[i_down] == pytest.approx(
        lo - 0.02)
    # away from the interval the two sweeps agree
    same = (w < lo - 0.03) | (w > hi + 0.03)
    np.testing.assert_allclose(up[same], down[same], rtol=0.02)
    # contact loss: on the whole upper branch, never on the lower one before its end
    assert np.all(sweeps["lost_down"][differ])
    assert not np.any(sweeps["lost_up"][differ & (w < hi)])
    assert sweeps["res_down"].flank_contact_changes[0] > 0


# --------------------------------------------------------------------------- the two laws

#: The reference sweeps cover the resonance region only: below 0.66 the response is linear
#: and unique (tested above against the linear oscillator), at 1.10 it is unique too (the
#: gearvib sweeps agree there in both directions), so a down-sweep started there from the
#: static state settles on the same branch as one coming from 1.20.
REF_OMEGAS = OMEGAS[(OMEGAS >= 0.66 - 1e-9) & (OMEGAS <= 1.10 + 1e-9)]


def _ks_rhs(y, t, w, phase, viscous):
    """x'' + 2 zeta x' + f(x) = F_m + F_a sin(w t + phase), nondimensional (x in b, t in
    1 / omega_n); gated: the damping only in contact and the force floored at 0."""
    x, v = y
    if viscous:
        fx = x - 1.0 if x > 1.0 else (x + 1.0 if x < -1.0 else 0.0)
        force = fx + 2.0 * ZETA * v
    else:
        force = 0.0
        if x > 1.0:
            force = max(x - 1.0 + 2.0 * ZETA * v, 0.0)
        elif x < -1.0:
            force = min(x + 1.0 + 2.0 * ZETA * v, 0.0)
    return [v, F_MEAN + F_ALT * math.sin(w * t + phase) - force]


def reference_sweep(omegas: np.ndarray, law: str) -> np.ndarray:
    """Stepped-sine sweep of the nondimensional Kahraman-Singh equation, integrated by scipy's
    LSODA (``odeint``, rtol 1e-9; ``solve_ivp`` with LSODA gives the same amplitudes in 3x
    the time), phase continuous, the amplitude of the fundamental over the last 30 of 60
    periods per step as :func:`stepped_sweep` measures it. Amplitudes in units of b."""
    y = np.array([1.0 + F_MEAN, 0.0])  # static: x = b + F_m / k
    phase, out = 0.0, []
    for w in omegas:
        span = PERIODS * 2 * math.pi / w
        ts = np.linspace(0.0, span, PERIODS * 32 + 1)
        sol = odeint(_ks_rhs, y, ts, args=(w, phase, law == "viscous"), rtol=1e-9,
                     atol=1e-11, mxstep=100_000)
        y = sol[-1]
        xs = sol[PERIODS * 16 : PERIODS * 32, 0]
        arg = w * ts[PERIODS * 16 : PERIODS * 32] + phase
        xs = xs - xs.mean()
        out.append(2 * math.hypot(np.mean(xs * np.cos(arg)), np.mean(xs * np.sin(arg))))
        phase = (phase + w * span) % (2 * math.pi)
    return np.array(out)


@pytest.fixture(scope="module")
def reference():
    """Up- and down-sweeps of the independent integration, per law, on REF_OMEGAS."""
    return {law: {"up": reference_sweep(REF_OMEGAS, law),
                  "down": reference_sweep(REF_OMEGAS[::-1], law)[::-1]}
            for law in ("gated", "viscous")}


@pytest.fixture(scope="module")
def viscous_sweeps():
    model = assemble(gearset_from_dict(pair_config(law="viscous")))
    up, lost_up, res_up = stepped_sweep(model, OMEGAS)
    down, lost_down, _ = stepped_sweep(model, OMEGAS[::-1])
    return {"up": up, "down": down[::-1], "lost_up": lost_up, "lost_down": lost_down[::-1],
            "res_up": res_up}


def _band(up: np.ndarray, down: np.ndarray, w: np.ndarray) -> tuple[float, float]:
    """The steps where the up- and the down-sweep differ (by 30 % of the smaller): the
    hysteresis band, as its lowest and highest frequency (one interval)."""
    differ = np.abs(down - up) > 0.3 * np.minimum(up, down)
    assert np.all(differ[(w >= w[differ].min()) & (w <= w[differ].max())])
    return float(w[differ].min()), float(w[differ].max())


@pytest.mark.parametrize("law", ["gated", "viscous"])
def test_both_laws_against_an_independent_integration(law, sweeps, viscous_sweeps, reference):
    """gearvib's pair against scipy's integration of the nondimensional equation of each law,
    step by step of both sweeps, jumps included: measured within 0.35 % of the amplitude
    (largest difference 0.001 b), except the viscous down-sweep's step right after its jump
    down (W = 0.90: 0.0722 against 0.0741 b, 2.6 %: the jump's transient still decays in the
    measuring window); test bound 2 % + 0.001 b."""
    got = sweeps if law == "gated" else viscous_sweeps
    sel = np.isin(OMEGAS, REF_OMEGAS)
    for key in ("up", "down"):
        np.testing.assert_allclose(got[key][sel], reference[law][key], rtol=0.02, atol=1e-3)


def test_viscous_law_jumps_where_kahraman_and_singh_report(viscous_sweeps, reference):
    """With always-on damping (their equation) the up-sweep jumps up between W = 0.94 and
    0.96 (published ~0.95: 0.100 -> 0.144 b) and the down-sweep rides the upper branch down to
    W = 0.92 (0.160 b) and jumps down between 0.92 and 0.90 (published ~0.90): a hysteresis
    band of 0.92 ... 0.94 on this 0.02 grid, in gearvib and in the reference alike. The gated
    law's band is 0.76 ... 0.94 with 0.282 b at its lower end
    (:func:`test_softening_jump_and_hysteresis`): gating the damping out of the backlash
    removes the energy loss of the free flight and keeps the upper branch alive far longer."""
    w = REF_OMEGAS
    sel = np.isin(OMEGAS, REF_OMEGAS)
    for up, down in ((viscous_sweeps["up"][sel], viscous_sweeps["down"][sel]),
                     (reference["viscous"]["up"], reference["viscous"]["down"])):
        lo, hi = _band(up, down, w)
        assert (lo, hi) == pytest.approx((0.92, 0.94))
        (i_up,) = np.flatnonzero(up[1:] / up[:-1] > 1.3)  # the jump up, between two steps
        (i_down,) = np.flatnonzero(down[:-1] / down[1:] < 1 / 1.3)
        assert (w[i_up], w[i_up + 1]) == pytest.approx((0.94, 0.96))
        assert (w[i_down], w[i_down + 1]) == pytest.approx((0.90, 0.92))
        assert down[w == pytest.approx(0.92)] == pytest.approx(0.160, abs=0.003)
        assert up[w == pytest.approx(0.96)] == pytest.approx(0.144, abs=0.003)
    gated = reference["gated"]
    assert _band(gated["up"], gated["down"], w) == pytest.approx((0.76, 0.94))
    assert gated["down"][w == pytest.approx(0.76)] == pytest.approx(0.282, abs=0.003)
    # the viscous pair separates on its upper branch too (the jump is the contact loss)
    assert viscous_sweeps["lost_down"][(OMEGAS > 0.91) & (OMEGAS < 0.95)].all()


def test_viscous_mean_deflection_and_negative_force(viscous_sweeps):
    """The static deflection is the same under both laws (x = b + F_m / k), and in the
    backlash the viscous law reports the damping force (negative while the flank opens)
    where the gated law reports 0."""
    res = viscous_sweeps["res_up"]
    assert res.mesh_deflection[0, 0] / HALF_BACKLASH == pytest.approx(1.0 + F_MEAN, rel=1e-6)
    left = res.normal_force[0, 0]
    assert left.min() < 0.0  # the viscous force while the flank separates


@pytest.mark.parametrize(("law", "dampers"), [("gated", 2.0), ("viscous", 1.0)])
def test_mean_system_of_a_preloaded_pair_counts_the_dampers_of_its_law(law, dampers):
    """With a negative backlash both flanks carry load: the gated law damps on each flank
    (2 c in the mean system), the viscous law has one damper (c), as the kernel applies them
    (the linear right-hand side about the preloaded state gives the same damping)."""
    from gearvib import kernels as kn
    from gearvib.simulate import prepare_run

    cfg = pair_config(law=law)
    cfg["mesh"][0]["backlash"] = -2 * HALF_BACKLASH
    model = assemble(gearset_from_dict(cfg))
    c = float(model.mesh_damping[0])
    contacts = model.mesh_contacts()
    assert contacts.flank == ("both",) and contacts.damping[0] == dampers * c
    system = prepare_run(model, TorqueDriven(0.0, max_rpm=100.0), False).system.astuple()
    v = model.mesh_vectors[0]
    n = v.size
    y = np.zeros(2 * n)
    y[n:] = 1e-3 * v / (v @ v)  # a deflection rate of 1e-3 m/s, no deflection
    a_v = kn.evaluate_rhs(0.0, y, system)[0][n:]
    y[n:] = 0.0
    a_0 = kn.evaluate_rhs(0.0, y, system)[0][n:]
    force = -np.linalg.solve(np.linalg.inv(model.mass), a_v - a_0) @ v / (v @ v)
    assert force == pytest.approx(dampers * c * 1e-3, rel=1e-9)
