"""Stability of the paper's gear sets: Floquet charts, theory candidates, phasing rules."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analysis.instability import floquet
from gearvib.assembly import assemble
from gearvib.config import load_gearset
from gearvib.stability import (
    first_order_regions,
    gear_set_candidates,
    periodic_system,
    stability_over_speed,
)


@pytest.fixture(scope="module")
def case1():
    return assemble(load_gearset("paper-case1"))


@pytest.fixture(scope="module")
def elastic():
    return assemble(load_gearset("paper-case1-elastic"))


def test_piecewise_and_smooth_monodromy_agree(case1):
    system = periodic_system(case1)
    f = 1800.0 * case1.mesh_frequency_per_rpm
    m, c, k_pw, period = system.at(f)
    exact = floquet(m, c, k_pw, period)
    smooth = floquet(m, c, lambda t: k_pw(t), period, method="magnus", rtol=1e-7)
    np.testing.assert_allclose(np.sort(np.abs(exact.multipliers)),
                               np.sort(np.abs(smooth.multipliers)), rtol=1e-4)


def test_stiffness_harmonics_match_numerical_integration(case1):
    system = periodic_system(case1)
    f = 700.0
    k_mean, k_hat = system.harmonics(3)
    t = np.linspace(0.0, 1.0 / f, 4096, endpoint=False)
    ks = np.array([system.stiffness_at(tt, f) for tt in t])
    np.testing.assert_allclose(ks.mean(axis=0), k_mean, rtol=1e-9, atol=1.0)
    for ell in (1, 2, 3):
        num = (ks * np.exp(-2j * math.pi * ell * f * t)[:, None, None]).mean(axis=0)
        np.testing.assert_allclose(num, k_hat[ell - 1], atol=2e-3 * np.abs(k_mean).max())


def test_paper_case1_principal_regions_at_predicted_speeds(case1):
    """Every region of 1900-3000 min^-1 is centred on its candidate's speed: the planet-mode
    principal regions 2 f3/3 and 2 f3/4 (f3 = f4, the repeated planet pair) and, since the
    default drive no longer damps the rotational modes (it damped the first one to 11 %),
    the rotational 2 f2/3, 2 f5/5, (f2 + f5)/3 and f2 (second-order principal). The
    planet region 2 f3/4 (2107 min^-1) shares one unstable interval with 2 f5/5 (2064 min^-1),
    2057-2123 min^-1, which the chart names after the latter; it is inside that interval."""
    chart = stability_over_speed(case1, np.linspace(1900.0, 3000.0, 120))
    regions = chart.regions()
    cands = chart.candidates.to_dataset()  # the candidates the regions are attributed to
    centres = regions["centre"].values / case1.mesh_frequency_per_rpm
    lower, upper = regions["lower_speed"].values, regions["upper_speed"].values
    predicted = {str(lab): s for lab, s in zip(cands["label"].values, cands["speed"].values,
                                               strict=True)}
    labels = [str(v) for v in regions["candidate"].values]
    assert labels == ["2 f2/3", "2 f5/5", "(f2 + f5)/3", "2 (f3=f4)/3", "f2"]
    for i, label in enumerate(labels):
        width = upper[i] - lower[i]
        assert abs(centres[i] - predicted[label]) < max(width, 10.0), label
    i = labels.index("2 f5/5")
    assert lower[i] < predicted["2 (f3=f4)/4"] < upper[i]


def test_in_phase_planets_have_no_rotational_translational_combination(elastic):
    cands = gear_set_candidates(elastic, speed_range=(300.0, 4000.0))
    ds = cands.to_dataset()
    mixed = [i for i, r in enumerate(ds["reason"].values)
             if "rotational" in r and "translational" in r]
    assert mixed, "the elastic set must have rotational-translational candidates to test"
    system = periodic_system(elastic)
    f_per_rpm = elastic.mesh_frequency_per_rpm
    allowed = dict(zip(ds["label"].values, ds["allowed"].values, strict=True))
    overlapped = []
    for i in mixed[:6]:
        f = float(ds["f_mesh"].values[i])
        unstable = [floquet(*system.at(f * (1 + df))).max_modulus > 1 + 1e-6
                    for df in (-0.002, 0.0, 0.002)]
        if any(unstable):
            # only where an allowed region overlaps the suppressed candidate: ((f2=f3) +
            # f4)/3 at 1587.6 min^-1 lies in (f4 + f14)/5 (1584-1622 min^-1, two rotational
            # modes, damped away by the drive before it left the elastic modes alone)
            speed = f / f_per_rpm
            near = stability_over_speed(elastic, np.linspace(0.98 * speed, 1.02 * speed, 41))
            reg = near.regions()
            known = near.candidates.to_dataset()
            ok = dict(zip(known["label"].values, known["allowed"].values, strict=True))
            inside = [str(reg["candidate"].values[k]) for k in range(reg.sizes["region"])
                      if reg["lower_speed"].values[k] <= speed <= reg["upper_speed"].values[k]]
            assert inside and all(lab and ok.get(lab) == 1 for lab in inside), (
                ds["label"].values[i], speed, inside)
            overlapped.append(str(ds["label"].values[i]))
    assert overlapped == ["((f2=f3) + f4)/3"]
    # and every unstable region found is an allowed candidate, never a suppressed one
    chart = stability_over_speed(elastic, np.linspace(2300.0, 2600.0, 60))
    regions = chart.regions()
    allowed = dict(zip(ds["label"].values, ds["allowed"].values, strict=True))
    for label in regions["candidate"].values:
        if label:
            assert allowed.get(str(label), 1) == 1, label


def test_case2_unlocks_a_combination_region_that_case1_suppresses(case1):
    case2 = assemble(load_gearset("paper-case2"))
    speeds = np.linspace(3500.0, 3600.0, 50)
    labels2 = list(stability_over_speed(case2, speeds).regions()["candidate"].values)
    labels1 = list(stability_over_speed(case1, speeds).regions()["candidate"].values)
    assert "(f2 + (f3=f4))/2" in labels2
    assert "(f2 + (f3=f4))/2" not in labels1


def test_first_order_widths_are_reported(case1):
    widths = first_order_regions(case1, l_max=4)
    ds = widths.to_dataset()
    assert ds.sizes[next(iter(ds.sizes))] > 0


def test_speed_by_damping_chart_shrinks_the_region_with_damping():
    from gearvib.config import gearset_from_dict, load_config
    from gearvib.stability import stability_map

    cfg, _ = load_config("paper-case1")

    def model_for(zeta):
        c = {**cfg, "meshes": {k: {**v, "damping_ratio": zeta} for k, v in cfg["meshes"].items()}}
        return assemble(gearset_from_dict(c))

    speeds = np.linspace(2740.0, 2870.0, 27)
    chart = stability_map(model_for, speeds, [0.0, 0.005, 0.02],
                          parameter_name="mesh damping ratio")
    mu = chart.to_dataset()["max_modulus"].transpose("parameter", "f_mesh").values
    unstable = (mu > 1 + 1e-7).sum(axis=1)
    assert unstable[0] >= unstable[1] >= unstable[2]
    assert unstable[0] > 0 and unstable[2] == 0


# ------------------------------------------------------------------ several mesh frequencies

C1 = 33 / 147  # carrier/sun speed ratio of one paper stage (ring fixed)
F1_PER_RPM = 33 * (1 - C1) / 60  # stage-1 mesh frequency per input speed [Hz per min^-1]
F2_PER_RPM = F1_PER_RPM * C1  # stage 2 is the same stage driven by the stage-1 carrier


@pytest.fixture(scope="module")
def two_paper_stages():
    from tests.gearvib.two_stage_sets import paper_stage, two_stage_model

    return two_stage_model(paper_stage(), paper_stage())


@pytest.fixture(scope="module")
def preloaded_stages():
    """Two paper stages with 1 mm of negative backlash: both flanks always loaded, so the
    simulated system is exactly the linear periodic system the Floquet analysis studies."""
    from tests.gearvib.two_stage_sets import paper_stage, two_stage_model

    return two_stage_model(paper_stage(backlash=-1e-3), paper_stage(backlash=-1e-3))


def test_common_period_exact_approximate_and_refused():
    from gearvib.stability import common_period

    exact = common_period([1.0, C1])  # 33/147 = 11/49
    assert exact.method == "common period"
    assert (exact.reference_cycles, exact.cycles) == (49, (49, 11))
    assert exact.max_detuning == 0.0
    # a hunting-tooth ratio 1771/8900: the best period within 256 cycles is 196 + 39 cycles,
    # detuning |39/196 / r - 1| = 4.6e-5 (continued-fraction convergent 39/196)
    approx = common_period([1.0, 1771 / 8900])
    assert approx.method == "commensurate approximation"
    assert approx.cycles == (196, 39)
    assert approx.max_detuning == pytest.approx(abs(39 / 196 / (1771 / 8900) - 1), rel=1e-9)
    assert approx.max_detuning < 5e-5
    assert sum(approx.cycles) <= 256
    with pytest.raises(ValueError, match=r"max_cycles = 50 .*detunes them by 0\.00508"):
        common_period([1.0, 1771 / 8900], max_cycles=50)
    with pytest.raises(ValueError, match="ratios"):
        common_period([2.0, 1.0])
    assert common_period([1.0]).method == "single"


def test_two_stage_stiffness_follows_both_mesh_frequencies(two_paper_stages):
    """The piecewise-constant K(t) over the common period equals K evaluated directly from the
    mesh positions s_m = s0_m + f_m t with the hand-computed stage mesh frequencies (the
    rectangular tables read as steps at their samples, as the Floquet pieces switch there; the
    simulation's linear interpolation ramps over 1/2048 of a cycle instead)."""
    model = two_paper_stages
    system = periodic_system(model)
    assert system.period.cycles == (49, 11)
    rpm = 2000.0
    _, _, k_pw, period = system.at(F1_PER_RPM * rpm)
    assert period == pytest.approx(49 / (F1_PER_RPM * rpm), rel=1e-12)
    assert period == pytest.approx(11 / (F2_PER_RPM * rpm), rel=1e-12)
    f_mesh = np.array([F1_PER_RPM * rpm] * 6 + [F2_PER_RPM * rpm] * 6)
    rng = np.random.default_rng(3)
    for t in rng.uniform(0.0, period, 300):
        s = model.mesh_position_offsets + f_mesh * t
        n_table = model.mesh_stiffness_tables.shape[1]
        idx = np.floor(s * n_table).astype(int) % n_table
        k = model.mesh_stiffness_tables[np.arange(model.n_mesh), idx]
        direct = system.stiffness + model.mesh_stiffness_matrix(k)
        np.testing.assert_allclose(k_pw(t), direct, rtol=1e-9, atol=1e-6)


def _homogeneous_rate(model, rpm: float, samples_per_period: int, fs: float) -> np.ndarray:
    """Growth rates [1/s] of the homogeneous response in 10 ms windows of a constant-speed run.

    The forced response is periodic with the common period T (49 stage-1 mesh cycles, exactly
    ``samples_per_period`` output samples), so ``x(t + T) - x(t)`` of the mesh deflections is
    the homogeneous (free) part alone, which grows or decays with the Floquet exponent.
    """
    from gearvib.simulate import SpeedRamp, simulate

    res = simulate(model, SpeedRamp(rpm, rpm, 0.17, input_torque=2.0), fs_out=fs)
    assert res.flank_contact_changes.sum() == 0  # preloaded: both flanks stay loaded
    q = res.mesh_deflection
    d = q[:, samples_per_period:] - q[:, :-samples_per_period]
    win = round(0.01 * fs)
    rms = np.array([np.sqrt(np.mean(d[:, i * win:(i + 1) * win] ** 2))
                    for i in range(d.shape[1] // win)])
    return np.log(rms[1:] / rms[:-1]) / 0.01


def test_two_stage_floquet_region_confirmed_by_constant_speed_simulation(preloaded_stages):
    """Inside the Floquet-unstable band 7678-7868 min^-1 (a stage-2 region) the constant-speed
    response grows at the Floquet rate (+21.7/s at 7847 min^-1), above it decays at the
    Floquet rate (-31.8/s at 7934 min^-1, the next exponent -82.5/s). Measured: +21.5/s and
    -32.0/s (mean over 60-130 ms). The preloaded meshes count with both flanks in
    the mean system, so the default drive is that of the doubled mesh stiffness. (With the
    drive of before, which damped the rotational modes, the band was 7727-7826 min^-1.)"""
    model = preloaded_stages
    system = periodic_system(model)
    fs = 25000.0
    for n_samples, sign in ((366, 1.0), (362, -1.0)):
        rpm = 49 * fs / (n_samples * F1_PER_RPM)  # T = 49 stage-1 cycles = n_samples samples
        growth = floquet(*system.at(F1_PER_RPM * rpm)).growth_rate
        assert np.sign(growth) == sign, (rpm, growth)
        rates = _homogeneous_rate(model, rpm, n_samples, fs)
        measured = rates[5:12].mean()  # after the faster transients, above rounding noise
        assert np.sign(measured) == sign
        assert measured == pytest.approx(growth, rel=0.08), (rpm, measured, growth)


def test_two_stage_region_belongs_to_stage2(preloaded_stages):
    """The region at 7678-7868 min^-1 stays when stage 1's mesh stiffness is held at its mean
    and vanishes when stage 2's is: the stage-2 mesh frequency causes it; the chart attributes
    it to a stage-2 candidate and gives it in both mesh frequencies."""
    import dataclasses

    model = preloaded_stages
    speeds = np.linspace(7650.0, 7900.0, 26)
    chart = stability_over_speed(model, speeds)
    reg = chart.regions()
    assert reg.sizes["region"] == 1
    lo, hi = float(reg["lower_speed"][0]), float(reg["upper_speed"][0])
    assert 7670 < lo < 7690 and 7860 < hi < 7875
    assert str(reg["candidate"].values[0]).endswith("[stage 2]")
    np.testing.assert_allclose(reg["group_lower"].values[0],
                               [lo * F1_PER_RPM, lo * F2_PER_RPM], rtol=1e-9)
    assert chart.method.startswith("common period (exact): 49 cycles of stage 1 = 11 of stage 2")

    def held(name: str):
        tables = model.mesh_stiffness_tables.copy()
        back = model.mesh_back_tables.copy()
        for g in model.mesh_frequency_groups():
            if g.name == name:
                idx = list(g.meshes)
                tables[idx] = tables[idx].mean(axis=1, keepdims=True)
                back[idx] = back[idx].mean(axis=1, keepdims=True)
        return dataclasses.replace(model, mesh_stiffness_tables=tables, mesh_back_tables=back)

    only2 = stability_over_speed(held("stage 1"), speeds).regions()
    only1 = stability_over_speed(held("stage 2"), speeds).regions()
    assert only1.sizes["region"] == 0
    assert only2.sizes["region"] == 1
    assert float(only2["lower_speed"][0]) == pytest.approx(lo, rel=2e-3)


def test_commensurate_approximation_moves_regions_by_the_stated_detuning(two_paper_stages):
    """Forcing the approximation (40 + 9 cycles instead of the exact 49 + 11) detunes stage 2
    by 0.23 %: its regions move in speed by exactly that factor, stage-1 regions stay (the
    grids hold regions of one stage each, none cut by a grid end: (f3 + f8)/6 and (f2 +
    f8)/5 of stage 2, 2 (f4=f5=f6=f7)/3 of stage 1)."""
    model = two_paper_stages
    for speeds, stage in ((np.linspace(5290.0, 5600.0, 32), 2),
                          (np.linspace(2740.0, 2845.0, 22), 1)):
        exact = stability_over_speed(model, speeds).regions()
        approx_chart = stability_over_speed(model, speeds, max_cycles=59, max_detuning=0.01)
        approx = approx_chart.regions()
        assert approx_chart.method.startswith("commensurate approximation: 40 cycles of stage 1"
                                              " ≈ 9 of stage 2")
        factor = C1 / (9 / 40) if stage == 2 else 1.0  # stage-2 speeds scale with 1/f_2
        assert exact.sizes["region"] == approx.sizes["region"] >= 1
        assert all(str(v).endswith(f"[stage {stage}]") for v in exact["candidate"].values)
        for key in ("lower_speed", "upper_speed"):
            np.testing.assert_allclose(approx[key].values, exact[key].values * factor,
                                       rtol=2e-4)
        if stage == 2:
            assert abs(factor - 1) > 2e-3  # the shift is real, larger than the tolerance


def test_first_order_regions_per_mesh_frequency(two_paper_stages):
    widths = first_order_regions(two_paper_stages, l_max=2)
    ds = widths.to_dataset()
    assert set(ds["mesh_frequency"].values) == {"stage 1", "stage 2"}
    stage2 = np.flatnonzero(ds["mesh_frequency"].values == "stage 2")
    centre = ds["centre"].values[stage2]
    speed = 0.5 * (ds["lower_speed"].values[stage2] + ds["upper_speed"].values[stage2])
    ok = ds["width"].values[stage2] > 0
    assert ok.any()
    # speeds of stage-2 rows come from the stage-2 mesh frequency
    np.testing.assert_allclose(speed[ok], centre[ok] / F2_PER_RPM, rtol=1e-9)


def _with(preset: str, edit) -> object:
    import copy

    from gearvib.config import gearset_from_dict, load_config

    cfg, base = load_config(preset)
    cfg = copy.deepcopy(cfg)
    edit(cfg)
    return assemble(gearset_from_dict(cfg, base=base))


def _trapezoidal(cfg: dict) -> None:
    for k in ("sun", "ring"):
        cfg["meshes"][k]["stiffness"].update(model="trapezoidal", ramp=0.05)


def test_trapezoidal_floquet_equals_the_adaptive_magnus_of_before():
    """Issue #15: the trapezoidal stiffness (piecewise linear) goes through the midpoint
    product with breakpoints at the kinks of every contact's table; its max|mu| equals the
    adaptive Magnus integrator used before (K as a callable) to 1e-7 -- measured 1.4e-9 and
    4.3e-9 -- at 1500 min^-1 (stable) and 2800 min^-1 (inside 2 (f3=f4)/3), with 160 instead of
    8192 exponentials per period."""
    from analysis.instability import PiecewiseSmooth

    model = _with("paper-case1", _trapezoidal)
    system = periodic_system(model)
    f = system.reference_frequency_per_rpm
    verdicts = set()
    for rpm in (1500.0, 2800.0):
        M, C, K, T = system.at(rpm * f)
        assert isinstance(K, PiecewiseSmooth)
        new = floquet(M, C, K, T)
        old = floquet(M, C, lambda t, fm=rpm * f: system.stiffness_at(t, fm), T)
        assert new.method == "midpoint" and old.method == "magnus"
        assert new.max_modulus == pytest.approx(old.max_modulus, abs=1e-7)
        assert new.growth_rate == pytest.approx(old.growth_rate, abs=1e-3)
        assert new.n_steps < old.n_steps / 10
        verdicts.add(new.stable)
    assert verdicts == {True, False}


def test_region_label_is_the_candidate_whose_modes_grow():
    """The 839-844 min^-1 region of paper-case1 was labelled "2 f2/4" (nearest candidate by
    centre, 1478 min^-1 away) and, with more orders, "2 f2/7" (844.8 min^-1). The growing Floquet
    solution there is the planet pair f3 = f4 (100 %), and the region is 2 (f3=f4)/10: with the
    planet inertia 4 % larger f3 drops 35 Hz and the region moves by -7 Hz of mesh frequency,
    as 2 f3/10 does (2 f2/7 would move by -2.2 Hz)."""
    speeds = np.linspace(800.0, 880.0, 81)
    charts = {}
    for scale in (1.0, 1.04):
        def heavier(cfg, scale=scale):
            cfg["bodies"]["planet"]["inertia"] *= scale

        model = _with("paper-case1", heavier)
        charts[scale] = (model, stability_over_speed(model, speeds))
    (m0, c0), (m1, c1) = charts[1.0], charts[1.04]
    (r0,), (r1,) = c0.region_table, c1.region_table
    assert r0["candidate"] == r1["candidate"] == "2 (f3=f4)/10"
    assert "f3" in r0["evidence"] and "f2" not in r0["evidence"].split("growing solution")[1]
    from gearvib.modal import modal_analysis

    f0, f1 = modal_analysis(m0).frequencies_hz, modal_analysis(m1).frequencies_hz
    shift = 0.5 * (r1["lower"] + r1["upper"]) - 0.5 * (r0["lower"] + r0["upper"])
    assert shift == pytest.approx(2 * (f1[2] - f0[2]) / 10, rel=0.05)
    assert abs(shift - 2 * (f1[1] - f0[1]) / 7) > 3.0
    # the label is a row of the chart's candidate table, at the stated centre
    i = r0["candidate_index"]
    assert c0.candidates.full_label(i) == r0["candidate"]
    assert r0["lower"] * 0.99 <= c0.candidates.f_mesh_hz[i] <= r0["upper"] * 1.01


def test_unattributed_when_no_candidate_holds(case1):
    """Without the candidate that holds, a region is not given the nearest one (the grid
    holds 2 (f3=f4)/3 alone: (f2 + f5)/3 ends at 2730 min^-1, f2 starts at 2917)."""
    speeds = np.linspace(2740.0, 2900.0, 33)
    full = gear_set_candidates(case1, n_max=4, speed_range=(2000.0, 4000.0))
    keep = np.array([lab != "2 (f3=f4)/3" for lab in full.label])
    chart = stability_over_speed(case1, speeds, candidates=full.select(keep))
    (reg,) = chart.region_table
    assert reg["candidate"] == "" and reg["candidate_index"] == -1
    assert "no allowed candidate" in reg["evidence"]


def test_chart_in_a_process_pool_is_identical(monkeypatch):
    """Grid points and boundary refinements in two worker processes give the same chart
    (three regions: 2 f5/5, (f2 + f5)/3, 2 (f3=f4)/3)."""
    import sys

    chart_module = sys.modules["analysis.instability.chart"]
    monkeypatch.setattr(chart_module, "_PARALLEL_MIN_S", 0.0)  # use the pool even if fast
    model = _with("paper-case1", _trapezoidal)
    speeds = np.linspace(2000.0, 2900.0, 24)
    one = stability_over_speed(model, speeds, workers=1)
    two = stability_over_speed(model, speeds, workers=2)
    np.testing.assert_array_equal(one.max_modulus, two.max_modulus)
    assert one.region_table == two.region_table
    assert len(one.region_table) == 3


def _damping_map_inputs():
    import copy

    from gearvib.config import gearset_from_dict, load_config

    cfg, base = load_config("paper-case1")

    def model_for(zeta):
        c = copy.deepcopy(cfg)
        for mesh in c["meshes"].values():
            mesh["damping_ratio"] = zeta
        return assemble(gearset_from_dict(c, base=base))

    return model_for, np.linspace(2700.0, 2900.0, 9), [0.0, 0.004, 0.02]


def _same_chart(a, b) -> None:
    np.testing.assert_array_equal(a.max_modulus, b.max_modulus)
    np.testing.assert_array_equal(a.growth_rate, b.growth_rate)
    assert a.region_table == b.region_table


def test_stability_map_on_the_sweep_executors_is_identical(monkeypatch):
    """Issue 16: stability_map runs on the sweeps' executors (serial, a local pool of 2, an
    executor passed in) and gives the same chart, bit for bit, boundaries refined too."""
    import sys
    from concurrent.futures import ProcessPoolExecutor

    from gearvib.execution import SerialExecutor
    from gearvib.stability import stability_map

    monkeypatch.setattr(sys.modules["analysis.instability.chart"], "_PARALLEL_MIN_S", 0.0)
    model_for, speeds, zetas = _damping_map_inputs()
    one = stability_map(model_for, speeds, zetas, refine=True, workers=1)
    assert len(one.region_table) >= 1 and np.isfinite(one.region_table[0]["lower"])
    _same_chart(one, stability_map(model_for, speeds, zetas, refine=True, workers=2))
    _same_chart(one, stability_map(model_for, speeds, zetas, refine=True,
                                   executor=SerialExecutor()))
    with ProcessPoolExecutor(2) as pool:  # a caller's executor: the system is pickled
        _same_chart(one, stability_map(model_for, speeds, zetas, refine=True, executor=pool,
                                       workers=2))
    with pytest.raises(ValueError, match="workers"):
        stability_map(model_for, speeds, zetas, workers=0)


@pytest.mark.slow
def test_stability_charts_on_a_dask_local_cluster_are_identical(monkeypatch):
    import sys

    distributed = pytest.importorskip("distributed")
    from gearvib.stability import stability_map

    monkeypatch.setattr(sys.modules["analysis.instability.chart"], "_PARALLEL_MIN_S", 0.0)
    model_for, speeds, zetas = _damping_map_inputs()
    one = stability_map(model_for, speeds, zetas, workers=1)
    over = stability_over_speed(model_for(0.0), speeds, refine=True, workers=1)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        address = cluster.scheduler_address
        _same_chart(one, stability_map(model_for, speeds, zetas, scheduler=address))
        _same_chart(over, stability_over_speed(model_for(0.0), speeds, refine=True,
                                               scheduler=address))
