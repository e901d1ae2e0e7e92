"""Tests of gearvib.kinematics: Willis equation, set speeds, mesh frequencies."""

from __future__ import annotations

import itertools

import pytest

from gearvib.kinematics import (
    mesh_frequency,
    paper_mesh_frequency,
    simple_set_speeds,
    willis_ratio,
)

ZS, ZR, ZP = 33, -114, 40


def test_paper_eq5_value_and_general_formula():
    f = paper_mesh_frequency(1500.0, ZS, ZR)
    assert f == pytest.approx(639.8, abs=0.05)
    assert f == pytest.approx(1500 / 60 * 33 * 114 / 147, rel=1e-12)
    n = simple_set_speeds(ZS, ZR, fixed="ring", input="sun", input_speed=1500.0)
    assert n["carrier"] == pytest.approx(1500 * 33 / 147)
    assert mesh_frequency(ZS, n["sun"], n["carrier"]) == pytest.approx(f, rel=1e-12)
    assert mesh_frequency(ZR, n["ring"], n["carrier"]) == pytest.approx(f, rel=1e-12)
    # physics.md 2: run-up to 4000 rpm, ring fixed: n_c = 897.96, f_m = 1706.1 Hz
    assert paper_mesh_frequency(4000.0, ZS, ZR) == pytest.approx(1706.1, abs=0.05)


def test_willis_ratio():
    assert willis_ratio(ZS, ZR) == pytest.approx(-114 / 33)
    # carrier fixed: ring turns backwards, slower by z_s/|z_r|
    n = simple_set_speeds(ZS, ZR, fixed="carrier", input="sun", input_speed=1000.0)
    assert n["ring"] == pytest.approx(-1000.0 * 33 / 114)
    assert (n["sun"] - n["carrier"]) / (n["ring"] - n["carrier"]) == pytest.approx(
        willis_ratio(ZS, ZR)
    )


@pytest.mark.parametrize(
    ("fixed", "inp"), [p for p in itertools.permutations(("sun", "ring", "carrier"), 2)]
)
def test_all_fixed_input_choices(fixed, inp):
    n = simple_set_speeds(ZS, ZR, fixed=fixed, input=inp, input_speed=1234.5, z_planet=ZP)
    assert n[fixed] == 0.0 and n[inp] == 1234.5
    # Willis equation and equal sun/ring/planet mesh frequencies
    assert ZS * (n["sun"] - n["carrier"]) == pytest.approx(ZR * (n["ring"] - n["carrier"]))
    f_s = mesh_frequency(ZS, n["sun"], n["carrier"])
    f_r = mesh_frequency(ZR, n["ring"], n["carrier"])
    f_p = abs(ZP * n["planet_relative"]) / 60
    assert f_s == pytest.approx(f_r, rel=1e-12) and f_s == pytest.approx(f_p, rel=1e-12)
    assert f_s > 0
    assert n["planet"] == pytest.approx(n["planet_relative"] + n["carrier"])


def test_rigid_rotation_has_no_mesh_frequency():
    # superposing a rigid rotation: all members at the same speed -> zero mesh frequency
    assert mesh_frequency(ZS, 700.0, 700.0) == 0.0
    assert mesh_frequency(ZR, 700.0, 700.0) == 0.0


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (
            lambda: simple_set_speeds(ZS, 114, fixed="ring", input="sun", input_speed=1.0),
            "z_ring = 114 .*admissible: < 0",
        ),
        (
            lambda: simple_set_speeds(ZS, ZR, fixed="sun", input="sun", input_speed=1.0),
            "different members",
        ),
        (
            lambda: simple_set_speeds(ZS, ZR, fixed="planet", input="sun", input_speed=1.0),
            "fixed = 'planet'",
        ),
        (
            lambda: simple_set_speeds(ZS, ZR, fixed="ring", input="sun", input_speed=float("nan")),
            "input_speed",
        ),
        (lambda: paper_mesh_frequency(1500.0, ZS, 114), "z_ring"),
        (lambda: willis_ratio(0, ZR), "z_central_a"),
    ],
)
def test_errors(call, match):
    with pytest.raises(ValueError, match=match):
        call()
