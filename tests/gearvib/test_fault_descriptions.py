"""[[fault]] and [[sensor]] tables: parsing, round trips and every kind of bad input."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

from gearvib.assembly import assemble
from gearvib.cli import main
from gearvib.config import ConfigError, gearset_from_dict, load_config, load_gearset
from gearvib.faults import (
    FAULT_KINDS,
    Crack,
    FaultError,
    PitchError,
    fault_from_dict,
    faults_from_list,
)
from gearvib.sensors import HousingSensor, SensorError, Tacho, sensor_from_dict

GOOD = [
    {"kind": "crack", "member": "sun", "tooth": 3, "severity": 0.3},
    {"kind": "crack", "member": "planet2", "tooth": 0, "mate": "ring",
     "curve": {"position": [0.0, 0.5, 1.0], "stiffness": [1e7, 2e7, 1e7]}},
    {"kind": "pitting", "member": "ring", "tooth": 100, "severity": 0.5, "path_start": 0.2,
     "path_end": 0.45, "depth": 5e-6, "flank": "both"},
    {"kind": "broken_tooth", "member": "planet1", "tooth": 39, "mate": ["sun", "ring"]},
    {"kind": "eccentricity", "member": "sun", "eccentricity": 2e-5, "phase_deg": 30.0},
    {"kind": "pitch_error", "member": "sun", "tooth": 4, "deviation": -3e-6},
    {"kind": "pitch_error", "member": "sun", "cumulative": [1e-6] * 33},
    {"kind": "pin_error", "member": "planet3", "radial": 1e-5, "tangential": -2e-5},
    {"kind": "backlash", "member": "planet1", "backlash": 1e-4, "name": "thin planet"},
]


@pytest.fixture(scope="module")
def model():
    return assemble(load_gearset("paper-case1"))


@pytest.mark.parametrize("table", GOOD, ids=lambda t: t["kind"])
def test_every_kind_round_trips(table, model) -> None:
    fault = fault_from_dict(table)
    assert fault.kind == table["kind"]
    again = fault_from_dict(json.loads(json.dumps(fault.to_dict())))
    assert again == fault
    model.with_faults([fault])  # fits the model


def test_the_kinds_are_the_issues() -> None:
    assert set(FAULT_KINDS) == {"crack", "pitting", "broken_tooth", "eccentricity",
                                "pitch_error", "pin_error", "backlash"}


BAD = [
    ({"kind": "spall", "member": "sun"}, "unknown kind 'spall'"),
    ({"member": "sun", "tooth": 1}, "missing key 'kind'"),
    ({"kind": "crack", "member": "sun", "tooth": 1, "severity": 0.2, "depth": 1e-6},
     "unknown key 'depth'"),
    ({"kind": "crack", "member": "sun", "severity": 0.2}, "missing key 'tooth'"),
    ({"kind": "crack", "member": "sun", "tooth": 1}, "either severity"),
    ({"kind": "crack", "member": "sun", "tooth": 1, "severity": 1.5}, "0 <= severity <= 1"),
    ({"kind": "crack", "member": "sun", "tooth": 1, "severity": "high"}, "must be a number"),
    ({"kind": "crack", "member": "sun", "tooth": -1, "severity": 0.1}, ">= 0"),
    ({"kind": "crack", "member": "sun", "tooth": 1.5, "severity": 0.1}, "must be an integer"),
    ({"kind": "crack", "member": 3, "tooth": 1, "severity": 0.1}, "member must be"),
    ({"kind": "crack", "member": "sun", "tooth": 1, "severity": float("nan")}, "finite"),
    ({"kind": "pitting", "member": "sun", "tooth": 1, "severity": 0.2, "path_start": 0.6,
      "path_end": 0.4}, "path_start"),
    ({"kind": "pitting", "member": "sun", "tooth": 1, "severity": 0.2, "path_start": 0.1,
      "path_end": 0.4, "flank": "drive"}, "flank = 'drive'"),
    ({"kind": "pitting", "member": "sun", "tooth": 1, "severity": 0.2, "path_start": 0.1,
      "path_end": 0.4, "depth": -1e-6}, "depth"),
    ({"kind": "eccentricity", "member": "sun", "eccentricity": 2e-3}, "eccentricity <= 0.001"),
    ({"kind": "pitch_error", "member": "sun"}, "exactly one of"),
    ({"kind": "pitch_error", "member": "sun", "tooth": 2}, "both tooth and deviation"),
    ({"kind": "pitch_error", "member": "sun", "single": [1e-6, 2e-6, 3e-6]}, "sum 0"),
    ({"kind": "pitch_error", "member": "sun", "single": [1e-6, -1e-6], "unit": "um"},
     "unit applies to a file"),
    ({"kind": "pin_error", "member": "planet1", "radial": 1e-5, "mate": "sun"},
     "unknown key 'mate'"),
    ({"kind": "backlash", "member": "planet1"}, "missing key 'backlash'"),
    ({"kind": "crack", "member": "sun", "tooth": 1, "curve": {"position": [0, 1],
                                                              "stiffness": [1e7, 1e7],
                                                              "units": "x"}},
     "unknown key 'units' in curve"),
    ({"kind": "crack", "member": "sun", "tooth": 1, "curve": {"path": "missing.csv"}},
     "does not exist"),
    ({"kind": "pitch_error", "member": "sun", "file": "missing.csv"}, "does not exist"),
]


@pytest.mark.parametrize("table,match", BAD, ids=[m for _, m in BAD])
def test_bad_tables_name_the_key(table, match) -> None:
    with pytest.raises(FaultError, match=match.replace("(", r"\(").replace(")", r"\)")):
        fault_from_dict(table)


MODEL_BAD = [
    ({"kind": "crack", "member": "moon", "tooth": 1, "severity": 0.1}, "no body 'moon'"),
    ({"kind": "crack", "member": "carrier", "tooth": 1, "severity": 0.1}, "has no teeth"),
    ({"kind": "crack", "member": "sun", "tooth": 33, "severity": 0.1}, "0 .. 32"),
    ({"kind": "crack", "member": "planet1", "tooth": 1, "severity": 0.1, "mate": "planet2"},
     "does not mesh with planet2"),
    ({"kind": "crack", "member": "planet1", "tooth": 1, "severity": 0.1, "mate": "pluto"},
     "mate 'pluto'"),
    ({"kind": "pin_error", "member": "sun", "radial": 1e-5}, "needs a planet"),
    ({"kind": "pitch_error", "member": "sun", "cumulative": [1e-6] * 32}, "33 teeth"),
]


@pytest.mark.parametrize("table,match", MODEL_BAD, ids=[m for _, m in MODEL_BAD])
def test_faults_that_do_not_fit_the_model(table, match, model) -> None:
    with pytest.raises(FaultError, match=match):
        model.with_faults([table])


def test_errors_given_twice(model) -> None:
    with pytest.raises(FaultError, match="given twice"):
        model.with_faults([{"kind": "pin_error", "member": "planet1", "radial": 1e-5},
                           {"kind": "pin_error", "member": "planet1", "tangential": 1e-5}])
    with pytest.raises(FaultError, match="given twice"):
        model.with_faults([{"kind": "backlash", "member": "planet1", "backlash": 1e-4},
                           {"kind": "backlash", "member": "planet1", "backlash": 2e-4}])


def test_stepped_planets_need_a_mate() -> None:
    model = assemble(load_gearset("wolfrom-example"))
    with pytest.raises(FaultError, match="several toothings"):
        model.with_faults([Crack("planet1", 1, severity=0.2)])
    model.with_faults([Crack("planet1", 1, severity=0.2, mate=("ring2",))])


def test_files(tmp_path, model) -> None:
    """Pitch deviations and a crack curve from text files (units, decimal commas, headers)."""
    f = tmp_path / "pitch.csv"
    dev = np.sin(np.arange(33) * 2 * np.pi / 33) * 4.0
    f.write_text("tooth;F_p [um]\n" + "".join(f"{i};{v:.6f}".replace(".", ",") + "\n"
                                              for i, v in enumerate(dev)))
    fault = fault_from_dict({"kind": "pitch_error", "member": "sun", "file": "pitch.csv",
                             "unit": "um"}, base=tmp_path)
    np.testing.assert_allclose(fault.cumulative_deviations(33), dev * 1e-6, atol=1e-12)
    model.with_faults([fault])
    bad = tmp_path / "bad.csv"
    bad.write_text("0 1e-6\n2 2e-6\n")
    with pytest.raises(FaultError, match="tooth index 0, 1, 2"):
        fault_from_dict({"kind": "pitch_error", "member": "sun", "file": str(bad)})
    c = tmp_path / "crack.csv"
    c.write_text("# cracked pair from a tooth-contact program\nu, k\n0, 10\n0.5, 14\n1, 10\n")
    crack = fault_from_dict({"kind": "crack", "member": "sun", "tooth": 2, "curve": {
        "path": "crack.csv", "stiffness_unit": "N/(mm um)", "face_width": 0.02}},
        base=tmp_path)
    assert crack.curve.stiffness == (2e8, 2.8e8, 2e8)
    model.with_faults([crack])


def test_single_pitch_deviations_accumulate() -> None:
    f = PitchError("sun", single=(0.0, 1e-6, -2e-6, 1e-6))
    np.testing.assert_allclose(f.cumulative_deviations(4), [0.0, 1e-6, -1e-6, 0.0])


def test_toml_tables_and_their_errors() -> None:
    cfg, base = load_config("paper-case1")
    gs = gearset_from_dict({**cfg, "fault": GOOD[:2], "sensor": [
        {"name": "top", "angle_deg": 90, "housing_modes": [
            {"frequency_hz": 3000, "damping_ratio": 0.02, "gain": 1.0}]},
        {"type": "tacho", "name": "tacho", "pulses_per_rev": 60}]}, base=base)
    assert len(gs.faults) == 2 and isinstance(gs.sensors[0], HousingSensor)
    model = assemble(gs)
    assert model.faults == gs.faults and model.sensors[0].member == "ring"
    with pytest.raises(ConfigError, match="unknown kind 'wear'"):
        gearset_from_dict({**cfg, "fault": [{"kind": "wear", "member": "sun"}]})
    with pytest.raises(ConfigError, match="array of tables"):
        gearset_from_dict({**cfg, "fault": {"kind": "crack"}})
    with pytest.raises(ConfigError, match="unknown key 'colour'"):
        gearset_from_dict({**cfg, "sensor": [{"name": "a", "angle_deg": 0, "colour": 1}]})
    two = copy.deepcopy(load_config("two-stage-example")[0])
    two["stage1"]["fault"] = [GOOD[0]]
    with pytest.raises(ConfigError, match="at the top level"):
        gearset_from_dict(two)
    # top level with stage member names works
    two = copy.deepcopy(load_config("two-stage-example")[0])
    two["fault"] = [{"kind": "crack", "member": "s1.sun", "tooth": 1, "severity": 0.2}]
    assemble(gearset_from_dict(two))


def test_the_gear_set_api_adds_faults(model) -> None:
    gs = load_gearset("paper-case1").with_faults([GOOD[0], Crack("ring", 5, severity=0.1)])
    assert assemble(gs).faults == (fault_from_dict(GOOD[0]), Crack("ring", 5, severity=0.1))
    assert faults_from_list(None) == ()


SENSOR_BAD = [
    ({"angle_deg": 0, "housing_modes": [{"frequency_hz": 1, "damping_ratio": 0.1,
                                         "gain": 1}]}, "missing key 'name'"),
    ({"name": "a", "housing_modes": [{"frequency_hz": 1, "damping_ratio": 0.1, "gain": 1}]},
     "missing key 'angle_deg'"),
    ({"name": "a", "angle_deg": 0, "window": "gauss", "housing_modes": [
        {"frequency_hz": 1, "damping_ratio": 0.1, "gain": 1}]}, "window = 'gauss'"),
    ({"name": "a", "angle_deg": 0, "width_deg": 200, "housing_modes": [
        {"frequency_hz": 1, "damping_ratio": 0.1, "gain": 1}]}, "width_deg <= 180"),
    ({"name": "a", "angle_deg": 0}, "housing_modes"),
    ({"name": "a", "angle_deg": 0, "housing_modes": [{"frequency_hz": 1, "damping_ratio": 0.0,
                                                      "gain": 1}]}, "0 < damping_ratio < 1"),
    ({"name": "a", "angle_deg": 0, "housing_modes": [{"frequency_hz": 1, "gain": 1}]},
     "missing key 'damping_ratio'"),
    ({"name": "a", "angle_deg": 0, "frf": "nowhere.uff"}, "does not exist"),
    ({"name": "a", "angle_deg": 0, "frf": {"path": "x.csv", "quantity": "inertance"}},
     "quantity = 'inertance'"),
    ({"type": "tacho", "name": "t", "pulses_per_rev": 0}, "pulses_per_rev = 0"),
    ({"type": "tacho", "name": "t", "angle_deg": 5}, "unknown key 'angle_deg'"),
    ({"type": "laser", "name": "t"}, "type = 'laser'"),
]


@pytest.mark.parametrize("table,match", SENSOR_BAD, ids=[m for _, m in SENSOR_BAD])
def test_bad_sensor_tables(table, match) -> None:
    with pytest.raises(SensorError, match=match):
        sensor_from_dict(table)


def test_sensors_that_do_not_fit_the_model(model) -> None:
    modes = {"housing_modes": [{"frequency_hz": 1000, "damping_ratio": 0.1, "gain": 1}]}
    with pytest.raises(SensorError, match="meshes with no planet"):
        model.with_sensors([{"name": "a", "angle_deg": 0, "member": "planet1", **modes}])
    # a carrier sees the meshes of its planets (the housing of a parallel stage)
    model.with_sensors([{"name": "a", "angle_deg": 0, "member": "carrier", **modes}])
    with pytest.raises(SensorError, match="no elastic radial bearing"):
        model.with_sensors([{"name": "a", "angle_deg": 0, "bearings": {"ring": 1.0}, **modes}])
    with pytest.raises(SensorError, match="used twice"):
        model.with_sensors([{"name": "a", "angle_deg": 0, **modes},
                            {"name": "a", "angle_deg": 10, **modes}])
    with pytest.raises(SensorError, match="more than one tacho"):
        model.with_sensors([Tacho("t1"), Tacho("t2")])
    with pytest.raises(SensorError, match="held at rest"):
        model.with_sensors([Tacho("t1", member="ring")])


def test_cli_reports_bad_faults_in_one_line(tmp_path, capsys) -> None:
    cfg, _ = load_config("paper-case1")
    text = (load_config.__globals__["preset_text"]("paper-case1")
            + '\n[[fault]]\nkind = "crack"\nmember = "sun"\ntooth = 40\nseverity = 0.2\n')
    path = tmp_path / "bad.toml"
    path.write_text(text)
    code = main(["simulate", str(path), "-o", str(tmp_path / "x.nc"), "--duration", "0.01"])
    err = capsys.readouterr().err
    assert code == 2
    assert "tooth = 40 is not admissible (admissible: 0 .. 32" in err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x.nc").exists()
    assert cfg  # the preset itself is fine
