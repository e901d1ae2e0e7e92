"""Stability charts: Ince-Strutt against scipy's Mathieu characteristic values, 2-DOF widths."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import mathieu_a, mathieu_b

from analysis.instability import (
    PiecewiseConstant,
    first_order_widths,
    instability_candidates,
    stability_chart,
)

W = np.array([1.0, 1.7])
B = np.array([[0.8, 0.6], [0.6, 0.5]])
TWO_PI = 2 * np.pi


def one_dof(f_mesh, eps):
    """x'' + (1 + eps cos(Omega t)) x = 0 with Omega = 2 pi f_mesh (w0 = 1 rad/s)."""
    om = TWO_PI * f_mesh
    return [[1.0]], [[0.0]], lambda t: np.array([[1.0 + eps * np.cos(om * t)]]), 1.0 / f_mesh


def mathieu_unstable(a, q):
    """Reference: y'' + (a - 2q cos 2t) y = 0 is unstable iff a < a0 or b_r < a < a_r."""
    if a < mathieu_a(0, q):
        return True
    return any(mathieu_b(r, q) < a < mathieu_a(r, q) for r in range(1, 8))


def mathieu_margin(a, q):
    vals = [mathieu_a(0, q)] + [v for r in range(1, 8) for v in (mathieu_a(r, q),
                                                                  mathieu_b(r, q))]
    return min(abs(a - v) for v in vals)


def test_ince_strutt_chart_matches_scipy_mathieu():
    # tau = Omega t / 2 maps the system to Mathieu form with a = 4/Omega^2, q = 2 eps/Omega^2
    f = np.linspace(0.5, 2.5, 41) / TWO_PI
    eps = [0.15, 0.4]
    chart = stability_chart(one_dof, f, parameter_values=eps, refine=False,
                            parameter_name="relative stiffness variation")
    assert chart.max_modulus.shape == (2, 41)
    checked = 0
    for i, e in enumerate(eps):
        for j, fm in enumerate(f):
            om = TWO_PI * fm
            a, q = 4 / om**2, 2 * e / om**2
            if mathieu_margin(a, q) < 1e-3:
                continue
            assert chart.unstable[i, j] == mathieu_unstable(a, q), (e, om)
            checked += 1
    assert checked > 70 and chart.unstable.sum() > 8
    ds = chart.to_dataset()
    assert ds.max_modulus.dims == ("parameter", "f_mesh")
    for name, var in ds.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name
    from matplotlib.figure import Figure

    assert isinstance(chart.plot(), Figure)


def test_refined_boundaries_of_first_tongue_match_scipy():
    eps = 0.3
    f = np.linspace(1.6, 2.4, 9) / TWO_PI
    chart = stability_chart(lambda fm: one_dof(fm, eps), f, mesh_frequency_per_rpm=0.01)
    reg = chart.regions()
    assert reg.sizes["region"] == 1
    # boundaries: a = 4/Omega^2 on the curves b1(q) and a1(q) with q = 2 eps/Omega^2
    import scipy.optimize

    def on_curve(fun):
        return scipy.optimize.brentq(lambda om: 4 / om**2 - fun(1, 2 * eps / om**2), 1.5, 2.5,
                                     xtol=1e-14)

    lo, hi = sorted([on_curve(mathieu_a), on_curve(mathieu_b)])
    assert reg.lower.item() * TWO_PI == pytest.approx(lo, abs=1e-8)
    assert reg.upper.item() * TWO_PI == pytest.approx(hi, abs=1e-8)
    assert reg.lower_speed.item() == pytest.approx(reg.lower.item() / 0.01)
    assert reg.peak_growth_rate.item() > 0
    for name, var in reg.variables.items():
        assert "units" in var.attrs and "long_name" in var.attrs, name


def two_dof(eps, zeta=(0.0, 0.0), Bm=B):
    C = np.diag(2 * np.asarray(zeta) * W)

    def system_at(f_mesh):
        om = TWO_PI * f_mesh
        return np.eye(2), C, lambda t: np.diag(W**2) + eps * Bm * np.cos(om * t), 1.0 / f_mesh

    return system_at


@pytest.mark.parametrize(
    ("eps", "zeta", "rel"),
    [(0.02, (0.0, 0.0), 1e-4), (0.04, (0.004, 0.001), 5e-4)],
)
def test_two_dof_sum_region_width_matches_first_order(eps, zeta, rel):
    theory = first_order_widths(np.eye(2), np.diag(2 * np.asarray(zeta) * W), np.diag(W**2),
                                eps * B / 2)
    s = theory.find("sum", 0, 1)
    centre, width = theory.centre_hz[s], theory.width_hz[s]
    f = centre + width * np.linspace(-1.0, 1.0, 9)
    cand = instability_candidates(W / TWO_PI, n_max=2)
    chart = stability_chart(two_dof(eps, zeta), f, candidates=cand)
    reg = chart.regions()
    assert reg.sizes["region"] == 1
    assert reg.candidate.item() == "f1 + f2"
    assert reg.width.item() == pytest.approx(width, rel=rel)
    if zeta == (0.0, 0.0):  # physics.md: Floquet 0.0092032 vs first order 0.0092036
        assert reg.width.item() * TWO_PI == pytest.approx(0.0092032, abs=2e-7)


def test_no_difference_type_region_for_symmetric_coupling():
    f = (W[1] - W[0]) / TWO_PI * np.linspace(0.95, 1.05, 21)
    sym = stability_chart(two_dof(0.04), f)
    assert np.max(sym.max_modulus) < 1 + 1e-9 and not sym.region_table
    # the same grid does resolve a difference region when B12 = -B21 (non-symmetric system)
    skew = np.array([[0.8, 0.6], [-0.6, 0.5]])
    ns = stability_chart(two_dof(0.04, Bm=skew), f)
    reg = ns.regions()
    assert reg.sizes["region"] == 1
    assert reg.width.item() * TWO_PI == pytest.approx(0.0184074, rel=1e-3)  # physics.md table


def test_piecewise_system_and_errors():
    def rect(f_mesh):
        T = 1.0 / f_mesh
        return [[1.0]], [[0.01]], PiecewiseConstant([0.4 * T, 0.6 * T], [[[1.3]], [[1.0]]]), T

    chart = stability_chart(rect, np.linspace(0.3, 0.4, 6))
    assert chart.max_modulus.shape == (6,)
    with pytest.raises(ValueError, match="strictly increasing"):
        stability_chart(rect, [0.3, 0.2, 0.4])
    with pytest.raises(ValueError, match="system_at must return"):
        stability_chart(lambda f: (1.0, 2.0), [0.3, 0.4])


def _sleep_long(x: int) -> int:
    import time

    time.sleep(60)
    return x


def test_terminate_pool_ends_running_workers_at_once():
    """An error or Ctrl-C during a chart must not wait for the running chunks (seconds each)
    nor leave worker processes behind."""
    import multiprocessing
    import time
    from concurrent.futures import ProcessPoolExecutor

    from analysis.instability.chart import terminate_pool

    if "fork" not in multiprocessing.get_all_start_methods():
        pytest.skip("needs fork")
    before = set(multiprocessing.active_children())
    pool = ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("fork"))
    futures = [pool.submit(_sleep_long, i) for i in range(4)]
    deadline = time.monotonic() + 30
    while not any(f.running() for f in futures) and time.monotonic() < deadline:
        time.sleep(0.05)
    children = set(multiprocessing.active_children()) - before
    assert children
    t0 = time.perf_counter()
    terminate_pool(pool)
    assert time.perf_counter() - t0 < 5.0
    deadline = time.monotonic() + 5.0  # a loaded host may take a moment to reap them
    while any(p.is_alive() for p in children) and time.monotonic() < deadline:
        time.sleep(0.05)
    alive = [(p.pid, p.name, p.exitcode) for p in children if p.is_alive()]
    assert not alive, f"still running after terminate_pool: {alive}"
    # The pool's management thread settles the futures of the ended workers (BrokenProcessPool)
    # or cancels the queued ones on its own schedule: wait for it, bounded, rather than race it.
    # (concurrent.futures.wait would not count a future cancelled by shutdown as done.)
    deadline = time.monotonic() + 10.0
    while not all(f.done() for f in futures) and time.monotonic() < deadline:
        time.sleep(0.05)
    pending = [f for f in futures if not f.done()]
    assert not pending, f"futures left pending after terminate_pool: {pending}"
    assert all(f.cancelled() or f.exception() is not None for f in futures)
