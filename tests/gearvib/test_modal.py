"""Modal analysis against closed forms and the Lin & Parker (1999) mode structure."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest

from gearvib.assembly import assemble
from gearvib.config import load_gearset
from gearvib.modal import modal_analysis
from tests.gearvib.lumped_sets import gear_pair, lumped_planetary


def _families(result):
    """Count distinct frequencies per kind and the multiplicity of each."""
    seen = {}
    for f, k, m in zip(result.frequencies_hz, result.kinds, result.multiplicity, strict=True):
        key = (k, round(f, 6))
        seen[key] = m
    out = {}
    for (k, _), m in seen.items():
        out.setdefault(k, []).append(m)
    return out


def test_gear_pair_torsional_frequency_matches_closed_form():
    j1, j2, r1, r2, k = 2e-3, 5e-4, 0.06, 0.03, 3e8
    res = modal_analysis(assemble(gear_pair(j1, j2, r1, r2, k)))
    assert res.kinds[0] == "rigid-body"
    expected = math.sqrt(k * (r1**2 / j1 + r2**2 / j2)) / (2 * math.pi)
    # the pair has a rigid-body mode (free input) and one torsional mode
    assert res.n_modes == 2
    assert res.frequencies_hz[1] == pytest.approx(expected, rel=1e-10)
    assert res.mesh_energy[1, 0] == pytest.approx(1.0, rel=1e-9)


@pytest.mark.parametrize("n_planets", [4, 5, 6])
def test_equally_spaced_mode_structure(n_planets):
    angles = [360.0 * i / n_planets for i in range(n_planets)]
    model = assemble(lumped_planetary(angles))
    res = modal_analysis(model)
    assert model.n_dof == 3 * (n_planets + 3)
    fam = _families(res)
    assert set(fam) == {"rotational", "translational", "planet"}
    assert all(m == 1 for m in fam["rotational"])
    assert all(m == 2 for m in fam["translational"])
    assert all(m == n_planets - 3 for m in fam["planet"])
    # 3(N + 3) DOF = 6 rotational + 6 translational pairs + 3 planet families x (N - 3)
    counts = Counter(res.kinds)
    assert counts["rotational"] == 6
    assert counts["translational"] == 12
    assert counts["planet"] == 3 * (n_planets - 3)


def test_planet_mode_frequencies_independent_of_planet_number():
    f = {}
    for n in (4, 5, 7):
        res = modal_analysis(assemble(lumped_planetary([360.0 * i / n for i in range(n)])))
        f[n] = np.unique(np.round(res.frequencies_hz[np.array(res.kinds) == "planet"], 6))
    np.testing.assert_allclose(f[4], f[5], rtol=1e-9)
    np.testing.assert_allclose(f[4], f[7], rtol=1e-9)


@pytest.mark.parametrize("n_planets", [3, 4, 5])
def test_purely_torsional_planet_modes_have_multiplicity_n_minus_1(n_planets):
    angles = [360.0 * i / n_planets for i in range(n_planets)]
    res = modal_analysis(assemble(lumped_planetary(angles, elastic=False)))
    fam = _families(res)
    assert set(fam) == {"rotational", "planet"}
    assert fam["planet"] == [n_planets - 1]


def test_unequal_spacing_splits_translational_pairs():
    equal = modal_analysis(assemble(lumped_planetary([0, 90, 180, 270])))
    assert sum(1 for m in equal.multiplicity if m == 2) == 12
    unequal = modal_analysis(assemble(lumped_planetary([0, 86.25, 180, 266.25])))
    f_eq = equal.frequencies_hz[np.array(equal.kinds) == "translational"]
    # the formerly degenerate pairs now have distinct frequencies
    assert all(m == 1 for m in unequal.multiplicity)
    gaps = np.diff(np.sort(unequal.frequencies_hz)) / np.sort(unequal.frequencies_hz)[1:]
    assert gaps.min() > 1e-5
    assert len(f_eq) == 12


def test_paper_case1_frequencies_as_the_paper_reports():
    res = modal_analysis(assemble(load_gearset("paper-case1")))
    f = res.frequencies_hz
    kinds = res.kinds
    assert kinds[0] == "rigid-body"
    assert 1240 <= f[1] <= 1280 and kinds[1] == "rotational"
    assert f[2] == pytest.approx(f[3], rel=1e-9)
    assert 1770 <= f[2] <= 1830 and kinds[2] == "planet" and res.multiplicity[2] == 2
    assert 2170 <= f[4] <= 2230 and kinds[4] == "rotational"


def test_elastic_bearings_lower_natural_frequencies():
    rigid = modal_analysis(assemble(load_gearset("paper-case1")))
    elastic = modal_analysis(assemble(load_gearset("paper-case1-elastic")))
    # bearing compliance lowers the gear-mesh modes (the paper's closing remark)
    f_r = rigid.elastic()
    f_e = elastic.elastic()
    assert f_e[0] < f_r[0]
    assert len(f_e) > len(f_r)


def test_gyroscopic_analysis_at_zero_speed_matches_static_and_splits_with_speed():
    model = assemble(lumped_planetary([0, 120, 240]))
    static = modal_analysis(model)
    slow = modal_analysis(model, carrier_speed_rpm=1e-9)
    np.testing.assert_allclose(slow.frequencies_hz, static.frequencies_hz, rtol=1e-6)
    fast = modal_analysis(model, carrier_speed_rpm=3000.0)
    trans = static.frequencies_hz[np.array(static.kinds) == "translational"]
    # the degenerate translational pairs split into forward and backward whirl
    pairs = fast.frequencies_hz
    assert np.min(np.abs(pairs[:, None] - trans[None, ::2]), axis=0).max() > 1e-3


def test_json_lists_every_mode():
    res = modal_analysis(assemble(load_gearset("paper-case1")))
    d = res.to_dict()
    assert len(d["modes"]) == res.n_modes
    assert {"frequency_hz", "kind", "multiplicity"} <= set(d["modes"][0])
    ds = res.to_dataset()
    for name, var in ds.variables.items():
        if name not in ("mode_kind", "dof", "mesh", "bearing", "loaded_flank"):
            assert "units" in var.attrs, name
        assert "long_name" in var.attrs, name
