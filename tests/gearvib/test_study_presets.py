"""The presets chosen by the paper study (reports/paper-study.md): paper-case1-study / -study2."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, list_presets, load_config
from gearvib.modal import modal_analysis
from gearvib.report.case_stiffness import summed_sun_stiffness

CASE2_ANGLES = [0.0, 360.0 * 50 / 147, 360.0 * 100 / 147]


def _cfg(name: str) -> dict:
    cfg, base = load_config(name)
    assert base is None  # a built-in preset, no file next to it
    return cfg


def _model(cfg: dict):
    c = copy.deepcopy(cfg)
    c.pop("simulation", None)
    return assemble(gearset_from_dict(c))


@pytest.mark.parametrize("name", ["paper-case1-study", "paper-case2-study"])
def test_study_preset_listed_with_chosen_values(name):
    assert name in list_presets()
    cfg = _cfg(name)
    sun, ring = cfg["meshes"]["sun"], cfg["meshes"]["ring"]
    # the values the study chose (reports/paper-study.md, sweep "refine")
    assert sun["stiffness"] == {"model": "trapezoidal", "k_min": 2.6667e7, "k_max": 4.3333e7,
                                "ramp": 0.2}
    assert ring["stiffness"] == {"model": "trapezoidal", "k_min": 3.0e7, "k_max": 5.0e7,
                                 "ramp": 0.1}
    assert sun["damping_ratio"] == ring["damping_ratio"] == 0.03
    assert cfg["geometry"]["profile_shift_sun"] == 0.3
    assert cfg["geometry"]["z_planet"] == 40
    sim = cfg["simulation"]
    assert sim["drive"] == "torque" and sim["input_torque"] == 60.0
    assert sim["duration"] == 1.0 and sim["speed_end_rpm"] == 4000.0
    assert cfg["operation"]["output"] == "load"
    assert [b["inertia"] for b in cfg["body"]] == [2.7245]
    # the paper's stiffness range: the three sun meshes together 0.8e8 ... 1.3e8 N/m
    assert 3 * sun["stiffness"]["k_min"] == pytest.approx(0.8e8, rel=1e-4)
    assert 3 * sun["stiffness"]["k_max"] == pytest.approx(1.3e8, rel=1e-4)


def test_study_presets_differ_only_in_planet_angles():
    c1, c2 = _cfg("paper-case1-study"), _cfg("paper-case2-study")
    assert c1["geometry"]["planet_angles_deg"] == [0.0, 120.0, 240.0]
    np.testing.assert_allclose(c2["geometry"]["planet_angles_deg"], CASE2_ANGLES, rtol=1e-12)
    for c in (c1, c2):
        for key in ("name", "title"):
            c.pop(key)
        c["geometry"].pop("planet_angles_deg")
    assert c1 == c2


def test_study_preset_physics_modes_and_phasing():
    """The paper's natural frequencies, f_mesh = f2/2 near 1500 min^-1, and case 2's smaller
    summed sun-mesh stiffness fluctuation (the paper's Figures 9 and 10)."""
    m1, m2 = _model(_cfg("paper-case1-study")), _model(_cfg("paper-case2-study"))
    modal = modal_analysis(m1)
    f = np.asarray(modal.frequencies_hz)
    kinds = list(modal.kinds)
    rot = f[[k == "rotational" for k in kinds]]
    planet = f[[k == "planet" for k in kinds]]
    f2 = rot[rot > 1000.0].min()
    f5 = rot.max()
    # paper: f2 ~ 1240-1280 Hz, f3 = f4 ~ 1800 Hz, f5 ~ 2200 Hz
    assert 1200.0 < f2 < 1300.0
    assert planet.size == 2 and np.allclose(planet, 1800.0, rtol=0.03)
    assert 2150.0 < f5 < 2300.0
    # eq. (5): f_mesh = n_S / 60 * 114 / (1 + 114/33); f2/2 is reached near 1500 min^-1
    per_rpm = 114.0 / (1.0 + 114.0 / 33.0) / 60.0
    assert 1400.0 < f2 / 2.0 / per_rpm < 1600.0
    s1, s2 = summed_sun_stiffness(m1), summed_sun_stiffness(m2)
    p1 = np.ptp(s1.total)
    p2 = np.ptp(s2.total)
    assert p1 == pytest.approx(0.5e8, rel=0.02)   # all sun meshes in phase (Figure 9)
    assert p2 < 0.6 * p1   # case 2: partly cancelled (measured 0.544 of case 1, Figure 10)
