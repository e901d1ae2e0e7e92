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
    chart = stability_over_speed(case1, np.linspace(1900.0, 3000.0, 120))
    regions = chart.regions()
    cands = gear_set_candidates(case1, speed_range=(1900.0, 3000.0))
    assert regions.sizes["region"] >= 2
    centres = regions["centre"].values / case1.mesh_frequency_per_rpm
    predicted = {str(lab): s for lab, s in zip(cands.to_dataset()["label"].values,
                                               cands.to_dataset()["speed"].values, strict=True)}
    # the planet-mode principal regions 2 f3/4 and 2 f3/3 (f3 = f4, the repeated planet pair)
    for label in ("2 (f3=f4)/4", "2 (f3=f4)/3"):
        assert label in list(regions["candidate"].values)
        i = list(regions["candidate"].values).index(label)
        width = regions["upper_speed"].values[i] - regions["lower_speed"].values[i]
        assert abs(centres[i] - predicted[label]) < max(width, 10.0)


def test_in_phase_planets_have_no_rotational_translational_combination(elastic):
    cands = gear_set_candidates(elastic, speed_range=(300.0, 4000.0))
    ds = cands.to_dataset()
    mixed = [i for i, r in enumerate(ds["reason"].values)
             if "rotational" in r and "translational" in r]
    assert mixed, "the elastic set must have rotational-translational candidates to test"
    system = periodic_system(elastic)
    f_per_rpm = elastic.mesh_frequency_per_rpm
    for i in mixed[:6]:
        f = float(ds["f_mesh"].values[i])
        for df in (-0.002, 0.0, 0.002):
            res = floquet(*system.at(f * (1 + df)))
            assert res.max_modulus <= 1 + 1e-6, (ds["label"].values[i], f / f_per_rpm)
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
