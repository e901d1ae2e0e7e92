"""Floquet solver against Mathieu (scipy), the exact damping reduction, Meissner and solve_ivp."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.integrate
import scipy.optimize
from scipy.special import mathieu_a, mathieu_b

from analysis.instability import (
    PiecewiseConstant,
    PiecewiseSmooth,
    floquet,
    rectangular_wave_pieces,
)


def mathieu_K(a: float, q: float):
    return lambda t: np.array([[a - 2.0 * q * np.cos(2.0 * t)]])


def trace(a: float, q: float, c: float = 0.0) -> float:
    r = floquet([[1.0]], [[c]], mathieu_K(a, q), np.pi)
    return float(np.trace(r.monodromy).real)


def ivp_monodromy(M, C, K, T):
    """Independent monodromy by scipy's DOP853 (column by column)."""
    n = len(M)
    minv = np.linalg.inv(M)

    def rhs(t, x):
        q, v = x[:n], x[n:]
        return np.concatenate([v, -minv @ (K(t) @ q + C @ v)])

    cols = [scipy.integrate.solve_ivp(rhs, (0, T), e, method="DOP853", rtol=1e-12,
                                      atol=1e-14).y[:, -1] for e in np.eye(2 * n)]
    return np.array(cols).T


@pytest.mark.parametrize("q", [0.5, 1.0, 2.0, 5.0])
def test_mathieu_transition_curves_match_scipy(q):
    # scan for sign changes of tr - 2 (a0, b2) and tr + 2 (b1, a1), then refine by Brent
    grid = np.linspace(-2 * q - 2.0, 4.0, round((2 * q + 6.0) / 0.1) + 1)  # a2 > 4
    tr = np.array([trace(a, q) for a in grid])
    found = {}
    for shift, names in ((2.0, ("a0", "b2")), (-2.0, ("b1", "a1"))):
        g = tr - shift
        idx = np.flatnonzero(np.sign(g[:-1]) != np.sign(g[1:]))
        assert idx.size >= 2
        for name, i in zip(names, idx[:2], strict=True):
            found[name] = scipy.optimize.brentq(lambda a, s=shift: trace(a, q) - s, grid[i],
                                                grid[i + 1], xtol=1e-12)
    ref = {"a0": mathieu_a(0, q), "b1": mathieu_b(1, q), "a1": mathieu_a(1, q),
           "b2": mathieu_b(2, q)}
    for name, value in ref.items():
        assert found[name] == pytest.approx(value, abs=1e-6), name


def test_damped_mathieu_matches_exact_one_dof_reduction():
    q, c = 1.0, 0.1
    g, T = c / 2.0, np.pi
    # multipliers: damped system = exp(-gT) x undamped system with a -> a - g^2
    for a in (-0.05, 0.5, 1.2, 3.0):
        damped = floquet([[1.0]], [[c]], mathieu_K(a, q), T)
        undamped = floquet([[1.0]], [[0.0]], mathieu_K(a - g * g, q), T)
        assert damped.max_modulus == pytest.approx(np.exp(-g * T) * undamped.max_modulus,
                                                   rel=1e-9)
        assert damped.liouville_error < 1e-9
    # lower boundary of the first (b1-a1) tongue: |tr Phi_z| = 2 cosh(gT), Phi_z by solve_ivp

    def h_exact(a):
        phi = ivp_monodromy(np.eye(1), np.zeros((1, 1)), mathieu_K(a - g * g, q), T)
        return abs(np.trace(phi)) - 2.0 * np.cosh(g * T)

    def h_floquet(a):
        return floquet([[1.0]], [[c]], mathieu_K(a, q), T).max_modulus - 1.0

    a_exact = scipy.optimize.brentq(h_exact, -0.3, 0.9, xtol=1e-12)
    a_floq = scipy.optimize.brentq(h_floquet, -0.3, 0.9, xtol=1e-12)
    assert a_floq == pytest.approx(a_exact, abs=1e-8)
    # damping shifts the boundary into the undamped tongue
    assert a_floq > mathieu_b(1, q) + g * g + 1e-3


def meissner_max_modulus(omega, k1, k2, cr, m=1.0, c=0.0):
    g = c / (2 * m)
    T = 2 * np.pi / omega
    p1 = np.sqrt(complex(k1 / m - g * g))
    p2 = np.sqrt(complex(k2 / m - g * g))
    t1, t2 = (2 - cr) * T, (cr - 1) * T
    D = (2 * np.cos(p1 * t1) * np.cos(p2 * t2)
         - (p1 / p2 + p2 / p1) * np.sin(p1 * t1) * np.sin(p2 * t2)).real
    root = np.sqrt(complex(D * D / 4 - 1))
    return np.exp(-g * T) * max(abs(D / 2 + root), abs(D / 2 - root)), D, g * T


@pytest.mark.parametrize("c", [0.0, 0.03])
def test_meissner_exact_trace_formula(c):
    k1, k2, cr = 1.0, 1.35, 1.6
    unstable_seen = 0
    for omega in np.linspace(0.5, 2.6, 43):
        T = 2 * np.pi / omega
        durs, vals = rectangular_wave_pieces(k1, k2, cr, 0.37, T)
        K = PiecewiseConstant(durs, vals[:, None, None])
        r = floquet([[1.0]], [[c]], K, T)
        ref, D, gT = meissner_max_modulus(omega, k1, k2, cr, c=c)
        assert r.max_modulus == pytest.approx(ref, rel=1e-10)
        assert r.stable == (abs(D) <= 2 * np.cosh(gT) + 1e-9)
        unstable_seen += not r.stable
        assert r.method == "exact"
        assert r.liouville_error < 1e-12
    assert unstable_seen >= 3
    # a boundary located with Floquet equals the root of |D| - 2 cosh(gT)
    k_mean = k1 + (cr - 1) * (k2 - k1)
    w0 = np.sqrt(k_mean)

    def h_formula(om):
        _, D, gT = meissner_max_modulus(om, k1, k2, cr, c=c)
        return abs(D) - 2 * np.cosh(gT)

    def h_floquet(om):
        T = 2 * np.pi / om
        durs, vals = rectangular_wave_pieces(k1, k2, cr, 0.0, T)
        # small offset: on the stable side of an undamped boundary |mu| = 1 to rounding
        return floquet([[1.0]], [[c]], PiecewiseConstant(durs, vals[:, None, None]),
                       T).max_modulus - 1.0 - 1e-10

    lo = 2 * w0 * 0.9
    assert h_formula(lo) < 0 and h_formula(2 * w0) > 0
    b_formula = scipy.optimize.brentq(h_formula, lo, 2 * w0, xtol=1e-13)
    b_floquet = scipy.optimize.brentq(h_floquet, lo, 2 * w0, xtol=1e-13)
    assert b_floquet == pytest.approx(b_formula, rel=1e-9)


def test_magnus_matches_solve_ivp_for_damped_two_dof():
    M = np.array([[2.0, 0.3], [0.3, 1.0]])
    C = np.array([[0.05, -0.01], [-0.01, 0.03]])
    K0 = np.array([[3.0, -1.0], [-1.0, 2.0]])
    K1 = np.array([[0.4, 0.2], [0.2, -0.3]])
    T = 2.1

    def K(t):
        return K0 + K1 * np.cos(2 * np.pi * t / T) + 0.5 * K1 * np.sin(4 * np.pi * t / T)

    r = floquet(M, C, K, T)
    ref = ivp_monodromy(M, C, K, T)
    assert np.max(np.abs(r.monodromy - ref)) < 1e-9
    assert r.method == "magnus" and r.error_estimate < 1e-9
    assert r.det_monodromy == pytest.approx(r.liouville_expected, rel=1e-10)
    assert r.liouville_expected == pytest.approx(np.exp(-T * np.trace(np.linalg.solve(M, C))))
    # fixed-step variant converges at fourth order
    e1 = np.max(np.abs(floquet(M, C, K, T, n_steps=20).monodromy - ref))
    e2 = np.max(np.abs(floquet(M, C, K, T, n_steps=40).monodromy - ref))
    assert 12 < e1 / e2 < 20


def test_piecewise_exact_matches_piecewise_integration():
    M = np.diag([1.0, 2.0])
    C = 0.02 * np.eye(2)
    Ka = np.array([[2.0, -0.5], [-0.5, 1.5]])
    Kb = np.array([[2.6, -0.9], [-0.9, 1.8]])
    durs = np.array([0.7, 0.5, 0.8])
    K = PiecewiseConstant(durs, np.array([Ka, Kb, Ka]))
    r = floquet(M, C, K, durs.sum())
    phi = np.eye(4)
    for d, k in zip(durs, K.matrices, strict=True):
        phi = ivp_monodromy(M, C, lambda t, k=k: k, d) @ phi
    assert np.max(np.abs(r.monodromy - phi)) < 1e-9
    assert np.allclose(K.mean(), (0.7 * Ka + 0.5 * Kb + 0.8 * Ka) / 2.0)
    # multipliers reproduce the monodromy eigenvalues and growth rate definition
    assert np.allclose(np.sort_complex(r.multipliers), np.sort_complex(np.linalg.eigvals(phi)))
    assert r.growth_rate == pytest.approx(np.log(r.max_modulus) / r.period)
    assert np.allclose(np.exp(r.exponents * r.period), r.multipliers)


def test_result_dataset_and_plot():
    r = floquet([[1.0]], [[0.0]], mathieu_K(1.0, 1.0), np.pi)
    ds = r.to_dataset()
    for name, var in ds.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
    assert ds.max_modulus.item() == pytest.approx(r.max_modulus)
    assert not r.stable and ds.attrs["stable"] == 0
    from matplotlib.figure import Figure

    assert isinstance(r.plot(), Figure)


def test_errors():
    one = [[1.0]]
    with pytest.raises(ValueError, match="not periodic"):
        floquet(one, [[0.0]], lambda t: np.array([[1.0 + 0.1 * np.cos(t)]]), 1.0)
    with pytest.raises(ValueError, match="same size"):
        floquet(np.eye(2), np.zeros((2, 2)), lambda t: np.eye(3), 1.0)
    with pytest.raises(ValueError, match="C has shape"):
        floquet(np.eye(2), np.zeros((3, 3)), lambda t: np.eye(2), 1.0)
    with pytest.raises(ValueError, match="symmetric"):
        floquet([[1.0, 0.2], [0.0, 1.0]], np.zeros((2, 2)), lambda t: np.eye(2), 1.0)
    with pytest.raises(ValueError, match="positive definite"):
        floquet([[1.0, 0.0], [0.0, -1.0]], np.zeros((2, 2)), lambda t: np.eye(2), 1.0)
    with pytest.raises(ValueError, match="period"):
        floquet(one, [[0.0]], lambda t: np.eye(1), 0.0)
    with pytest.raises(ValueError, match="sum to"):
        floquet(one, [[0.0]], PiecewiseConstant([0.5, 0.4], [[[1.0]], [[2.0]]]), 1.0)
    with pytest.raises(ValueError, match="same size"):
        floquet(one, [[0.0]], PiecewiseConstant([1.0], np.eye(2)[None]), 1.0)
    with pytest.raises(ValueError, match="method"):
        floquet(one, [[0.0]], lambda t: np.eye(1), 1.0, method="rk45")
    with pytest.raises(ValueError, match="PiecewiseConstant"):
        floquet(one, [[0.0]], lambda t: np.eye(1), 1.0, method="exact")
    with pytest.raises(ValueError, match="durations"):
        PiecewiseConstant([1.0, -1.0], [[[1.0]], [[2.0]]])


def _trapezoid(t: np.ndarray, T: float, ramp: float = 0.1, dc: float = 0.6) -> np.ndarray:
    """Periodic trapezoidal wave between 0 and 1 (period ``T``): linear rise over ``ramp``
    centred at 0, linear fall over ``ramp`` centred at ``dc`` (fractions of the period)."""
    u = np.mod(np.asarray(t, dtype=float) / T, 1.0)
    h = 0.5 * ramp
    return (np.clip((u + h) / ramp, 0.0, 1.0) - np.clip((u - dc + h) / ramp, 0.0, 1.0)
            + np.clip((u - 1.0 + h) / ramp, 0.0, 1.0))


def test_midpoint_product_matches_magnus_and_solve_ivp_on_trapezoidal_stiffness():
    """A trapezoidal (piecewise-linear) stiffness given as PiecewiseSmooth with edges at its
    kinks: the midpoint product equals the adaptive Magnus integrator (the method before #15)
    and DOP853 to 1e-9 in max|mu|, inside and outside an unstable interval, with far fewer
    exponentials; the error estimate bounds the actual error."""
    M = np.diag([1.0, 0.5])
    C = np.array([[0.004, -0.001], [-0.001, 0.003]])
    K0 = np.array([[2.0, -0.6], [-0.6, 1.4]])
    K1 = np.array([[0.5, -0.3], [-0.3, 0.4]])
    ramp, dc = 0.1, 0.6
    verdicts = set()
    for T in (2.2, 2.5, 5.0):
        def K(t, T=T):
            return K0 + K1 * _trapezoid(np.atleast_1d(t), T, ramp, dc)[:, None, None]

        kinks = np.sort(np.mod(np.array([-0.5, 0.5, dc / ramp - 0.5, dc / ramp + 0.5]) * ramp,
                               1.0)) * T
        edges = np.concatenate([[0.0], kinks[kinks > 0], [T]])
        new = floquet(M, C, PiecewiseSmooth(edges, K), T, multiplier_atol=1e-11)
        old = floquet(M, C, lambda t, K=K: K(t)[0], T)
        ivp = ivp_monodromy(M, C, lambda t, K=K: K(t)[0], T)
        ref = float(np.max(np.abs(np.linalg.eigvals(ivp))))
        assert new.method == "midpoint" and old.method == "magnus"
        assert new.max_modulus == pytest.approx(old.max_modulus, abs=1e-9)
        assert new.max_modulus == pytest.approx(ref, abs=1e-9)
        assert abs(new.max_modulus - ref) <= max(10 * new.error_estimate, 1e-10)  # DOP853 1e-12
        assert np.max(np.abs(new.monodromy - ivp)) < 1e-7
        assert new.n_steps < old.n_steps
        verdicts.add(new.stable)
    assert verdicts == {True, False}  # stable and unstable periods both checked


def test_piecewise_smooth_errors_and_constant_pieces():
    K = np.array([[[2.0]]])
    one = PiecewiseSmooth(np.array([0.0, 1.0]), lambda t: np.repeat(K, np.size(t), axis=0))
    r = floquet([[1.0]], [[0.1]], one, 1.0)
    exact = floquet([[1.0]], [[0.1]], PiecewiseConstant([1.0], K), 1.0)
    assert r.method == "midpoint" and r.error_estimate == 0.0
    np.testing.assert_allclose(r.monodromy, exact.monodromy, rtol=1e-12, atol=1e-14)
    with pytest.raises(ValueError, match="edges"):
        PiecewiseSmooth(np.array([0.5, 1.0]), lambda t: K)
    with pytest.raises(ValueError, match="edges"):
        PiecewiseSmooth(np.array([0.0, 0.5, 0.4]), lambda t: K)
    with pytest.raises(ValueError, match="periodic"):
        floquet([[1.0]], [[0.0]], one, 2.0)
    with pytest.raises(ValueError, match="PiecewiseConstant"):
        floquet([[1.0]], [[0.0]], one, 1.0, method="exact")
    with pytest.raises(ValueError, match="PiecewiseSmooth"):
        floquet([[1.0]], [[0.0]], lambda t: K[0], 1.0, method="midpoint")
    bad = PiecewiseSmooth(np.array([0.0, 1.0]), lambda t: np.ones((np.size(t), 2, 2)))
    with pytest.raises(ValueError, match="same size"):
        floquet([[1.0]], [[0.0]], bad, 1.0)
