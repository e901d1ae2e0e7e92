"""Theory: candidates, mesh-phasing selection rules, first-order widths, rectangular wave."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.instability import (
    MeshPhasingRule,
    first_order_widths,
    instability_candidates,
    rectangular_wave_harmonics,
    rectangular_wave_pieces,
)

W = np.array([1.0, 1.7])
B = np.array([[0.8, 0.6], [0.6, 0.5]])


def test_first_order_widths_closed_forms_two_dof():
    eps = 0.02
    r = first_order_widths(np.eye(2), np.zeros((2, 2)), np.diag(W**2), eps * B / 2)
    two_pi = 2 * np.pi
    # cos excitation: principal width eps |b_ii| / w_i, sum width eps |b_12| / sqrt(w1 w2)
    p1 = r.find("principal", 0, 0)
    p2 = r.find("principal", 1, 1)
    s = r.find("sum", 0, 1)
    assert r.width_hz[p1] * two_pi == pytest.approx(eps * 0.8 / 1.0, rel=1e-12)
    assert r.width_hz[p2] * two_pi == pytest.approx(eps * 0.5 / 1.7, rel=1e-12)
    assert r.width_hz[s] * two_pi == pytest.approx(eps * 0.6 / np.sqrt(1.7), rel=1e-12)
    assert r.width_hz[s] * two_pi == pytest.approx(0.0092036, abs=1e-7)  # physics.md table
    assert r.centre_hz[s] * two_pi == pytest.approx(2.7)
    assert r.lower_hz[s] == pytest.approx(r.centre_hz[s] - r.width_hz[s] / 2)
    assert str(r.label[s]) == "f1 + f2"
    assert np.all(np.isnan(r.lower_rpm))


def test_first_order_widths_damped_and_unequal_damping():
    eps = 0.04
    zeta = np.array([0.004, 0.001])
    C = np.diag(2 * zeta * W)
    r = first_order_widths(np.eye(2), C, np.diag(W**2), eps * B / 2,
                           mesh_frequency_per_rpm=0.5)
    p1, s = r.find("principal", 0, 0), r.find("sum", 0, 1)
    mu = zeta * W
    d11, d12 = eps * 0.8 / 2, eps * 0.6 / 2
    assert r.width_hz[p1] * 2 * np.pi == pytest.approx(
        2 * np.sqrt(d11**2 / W[0] ** 2 - 4 * mu[0] ** 2), rel=1e-12)
    lam = d12**2 / (4 * W[0] * W[1])
    ref = 2 * mu.sum() * np.sqrt((lam - mu.prod()) / mu.prod())
    assert r.width_hz[s] * 2 * np.pi == pytest.approx(ref, rel=1e-12)
    assert r.width_hz[s] * 2 * np.pi == pytest.approx(0.0165759, abs=1e-7)
    assert r.undamped_width_hz[s] * 2 * np.pi == pytest.approx(2 * 2 * np.sqrt(lam))
    assert r.lower_rpm[s] == pytest.approx(r.lower_hz[s] / 0.5)
    # heavy damping: Lambda < mu1 mu2 -> no sum region
    r2 = first_order_widths(np.eye(2), np.diag(2 * 0.02 * W), np.diag(W**2), eps * B / 2)
    assert r2.width_hz[r2.find("sum", 0, 1)] == 0.0
    ds = r.to_dataset()
    for name, var in ds.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name


def test_first_order_widths_with_mass_matrix_and_harmonics():
    # the modal transformation must make the result independent of the coordinates
    rng = np.random.default_rng(3)
    T = rng.normal(size=(2, 2)) + 2 * np.eye(2)
    M = T.T @ T
    Kbar = T.T @ np.diag(W**2) @ T
    Kh = np.array([T.T @ (0.01 * B) @ T, T.T @ (0.004 * np.diag([1.0, 2.0])) @ T]) * (1 - 0.5j)
    r = first_order_widths(M, np.zeros((2, 2)), Kbar, Kh)
    s2 = r.find("principal", 1, 1, harmonic=2)
    # l = 2: |D_22| = 0.008 |1 - 0.5 i|, width in Omega = 2 |D_22| / (l w_2)
    ref = 2 * 0.008 * abs(1 - 0.5j) / (2 * W[1])
    assert r.width_hz[s2] * 2 * np.pi == pytest.approx(ref, rel=1e-9)
    assert r.centre_hz[s2] * 2 * np.pi == pytest.approx(W[1])
    assert r.width_hz[r.find("sum", 0, 1, harmonic=2)] == pytest.approx(0.0, abs=1e-15)


def test_degenerate_cluster_uses_largest_singular_value():
    Bd = np.array([[0.3, 0.4, 0.1], [0.4, -0.2, 0.2], [0.1, 0.2, 0.5]])
    r = first_order_widths(np.eye(3), np.zeros((3, 3)), np.diag([1.0, 1.0, 2.25]), 0.01 * Bd)
    p = r.find("principal", 0, 0)
    assert str(r.label[p]) == "2 (f1=f2)"
    smax = np.linalg.svd(Bd[:2, :2], compute_uv=False)[0]
    assert r.width_hz[p] * 2 * np.pi == pytest.approx(2 * 0.01 * smax / 1.0, rel=1e-12)
    s = r.find("sum", 0, 2)
    smax = np.linalg.svd(Bd[:2, 2:], compute_uv=False)[0]
    assert r.width_hz[s] * 2 * np.pi == pytest.approx(2 * 0.01 * smax / np.sqrt(1.5), rel=1e-12)
    assert len(r) == 3  # repeated pair listed once


def test_rectangular_wave_harmonics_match_fft_of_pieces():
    kmin, kmax, c, phase = 0.8e8, 1.3e8, 1.63, 0.21
    mean, kh = rectangular_wave_harmonics(kmin, kmax, c, phase, 6)
    n = 2**16
    t = (np.arange(n) + 0.5) / n
    durs, vals = rectangular_wave_pieces(kmin, kmax, c, phase, 1.0)
    assert durs.sum() == pytest.approx(1.0)
    samples = vals[np.searchsorted(np.cumsum(durs), t)]
    spec = np.fft.fft(samples) / n * np.exp(-1j * np.pi * np.arange(n) / n)  # half-bin shift
    assert mean == pytest.approx(kmin + (c - 1) * (kmax - kmin))
    assert spec[0].real == pytest.approx(mean, rel=1e-4)
    assert np.allclose(spec[1:7], kh, atol=2e-4 * (kmax - kmin))
    # harmonic l vanishes when l c is an integer
    _, kh15 = rectangular_wave_harmonics(kmin, kmax, 1.5, 0.0, 4)
    assert abs(kh15[1]) < 1e-9 * kmax and abs(kh15[3]) < 1e-9 * kmax
    assert abs(kh15[0]) == pytest.approx((kmax - kmin) / np.pi)


def test_candidates_centres_repeated_modes_and_speed():
    c = instability_candidates([1250.0, 1800.0, 1800.0, 2200.0], n_max=3,
                               mesh_frequency_per_rpm=0.5, speed_range=(0, 6000),
                               mode_labels=["f2", "f3", "f4", "f5"])
    table = {str(lab): (f, n, kind) for lab, f, n, kind in
             zip(c.label, c.f_mesh_hz, c.n, c.kind, strict=True)}
    assert table["2 f2/3"][0] == pytest.approx(2 * 1250 / 3)
    assert table["((f3=f4) + f5)/2"][0] == pytest.approx(2000.0)
    assert table["f2"][:2] == (1250.0, 2)
    # the repeated pair is one cluster: no (f3 + f4) sum row, one principal per order
    assert not any("f3 + f4" in str(s) for s in c.label)
    # principal of the pair: n = 1 (3600 Hz = 7200 rpm) is outside speed_range; n = 2, 3 listed
    assert [str(s) for s in c.label if "(f3=f4)" in str(s) and "+" not in str(s)] == [
        "2 (f3=f4)/3", "(f3=f4)"]
    assert np.all(c.rpm <= 6000) and np.allclose(c.rpm, c.f_mesh_hz / 0.5)
    assert np.all(np.diff(c.f_mesh_hz) >= 0)
    assert any("Krein" in s for s in c.notes)
    assert not np.any(c.kind == "difference")
    ds = c.to_dataset()
    for name, var in ds.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
    assert "speed" in str(c).lower()


def test_difference_type_only_for_gyroscopic_systems():
    c = instability_candidates([1.0, 1.7], kinds=("principal", "sum", "difference"), n_max=1)
    assert set(c.kind) == {"principal", "sum"} and c.notes
    g = instability_candidates([1.0, 1.7], kinds=("difference",), n_max=2, gyroscopic=True)
    assert np.allclose(sorted(g.f_mesh_hz), [0.35, 0.7])
    assert not g.notes


@pytest.mark.parametrize(
    ("n_planets", "z_s", "pair", "allowed_k"),
    [
        (3, 33, ((0, 0)), {0}),
        (4, 33, ((1, 2)), {1, 3}),
        (5, 32, ((0, 2)), {2, 3}),
        (5, 32, ((1, 1)), {0, 2, 3}),
        (6, 31, ((2, 3)), {1, 5}),
    ],
)
def test_selection_rule_table(n_planets, z_s, pair, allowed_k):
    rule = MeshPhasingRule(n_planets, z_s)
    for l in range(1, 2 * n_planets + 1):
        k = rule.index(l)
        assert k == (l * z_s) % n_planets
        assert rule.allows(l, *pair) == (k in allowed_k), (l, k)


def test_selection_rule_paper_example_and_sequential_phasing():
    fams = [("rotational", 0), ("translational", 1), ("translational", 1), ("rotational", 0)]
    f = [1250.0, 1800.0, 1800.0, 2200.0]
    inphase = instability_candidates(f, n_max=4, mode_families=fams,
                                     mesh_harmonic_rule=MeshPhasingRule(3, 33, 114))
    trans = (inphase.mode_i == 1, inphase.mode_j == 1)  # the translational cluster f3=f4
    mixed = (inphase.kind == "sum") & (trans[0] ^ trans[1])
    assert mixed.sum() == 8 and not inphase.allowed[mixed].any()
    assert all("every order" in str(r) for r in inphase.reason[mixed])
    # same-family regions (rot-rot sum, principal of the translational pair) stay allowed
    assert inphase.allowed[~mixed].all() and (~mixed).sum() == 16
    seq = instability_candidates(f, n_max=2, mode_families=fams,
                                 mesh_harmonic_rule=MeshPhasingRule(3, 34, 113))
    row = {(str(k), int(n), int(i), int(j)): bool(a) for k, n, i, j, a in
           zip(seq.kind, seq.n, seq.mode_i, seq.mode_j, seq.allowed, strict=True)}
    assert row[("sum", 1, 0, 1)] and not row[("principal", 1, 0, 0)]  # k = 1: rot-trans only
    assert row[("principal", 1, 1, 1)]  # trans-trans: k = +-2 = -+1 (mod 3)
    assert not row[("principal", 2, 0, 0)] and row[("sum", 2, 0, 1)]  # k = 2


def test_candidate_errors():
    with pytest.raises(ValueError, match="must be > 0"):
        instability_candidates([1200.0, 0.0])
    with pytest.raises(ValueError, match="must be > 0"):
        instability_candidates([-5.0])
    with pytest.raises(ValueError, match="speed_range needs"):
        instability_candidates([100.0], speed_range=(0, 10))
    with pytest.raises(ValueError, match="kinds"):
        instability_candidates([100.0], kinds=("combination",))
    with pytest.raises(ValueError, match="mode_families"):
        instability_candidates([100.0], mesh_harmonic_rule=MeshPhasingRule(3, 33))
    with pytest.raises(ValueError, match="circular harmonic"):
        instability_candidates([100.0], mode_families=[("translational", 2)],
                               mesh_harmonic_rule=MeshPhasingRule(3, 33))
    with pytest.raises(ValueError, match="cannot be assembled"):
        MeshPhasingRule(3, 33, 113)
    with pytest.raises(ValueError, match="contact_ratio"):
        rectangular_wave_harmonics(1.0, 2.0, 2.2, 0.0, 3)
    with pytest.raises(ValueError, match="K_harmonics must be symmetric"):
        first_order_widths(np.eye(2), np.zeros((2, 2)), np.eye(2), [[0, 1.0], [-1.0, 0]])
    with pytest.raises(ValueError, match="positive definite"):
        first_order_widths(np.eye(2), np.zeros((2, 2)), np.diag([1.0, 0.0]), np.eye(2))
