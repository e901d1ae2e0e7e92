"""``[[rolling_bearing]]`` tables of gear-set descriptions and their catalogue lines.

Reference values: the SKF 6205-2RS JEM deep-groove ball bearing of the Case Western Reserve
University bearing data (9 balls, d = 7.94 mm, D = 39.04 mm, phi = 0), whose defect
frequencies the CWRU Bearing Data Center tabulates as multiples of the shaft speed: BPFI
5.4152, BPFO 3.5848, FTF 0.39828, rolling element (twice the ball spin) 4.7135 (also Smith &
Randall, MSSP 64-65 (2015) 100-131, table 2), given to 5 digits (hence rel 1e-4). With the
outer ring rotating and the inner ring at rest (a planet bearing on its pin) the cage turns at
``f_r (1 + d/D cos phi)/2`` relative to the inner ring (SKF bearing frequency formulas,
inner ring fixed).
"""

from __future__ import annotations

import copy
import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

from gearvib.catalogue import gear_set_catalogue
from gearvib.config import ConfigError, gearset_from_dict, load_config

REPO = Path(__file__).resolve().parents[2]
CWRU = {"input bearing": {"name": "input bearing", "member": "sun", "n_rolling": 9,
                          "rolling_diameter": 7.94e-3, "pitch_diameter": 39.04e-3,
                          "contact_angle_deg": 0.0}}
PLANET = {"name": "planet bearing", "member": "planet1", "n_rolling": 12,
          "rolling_diameter": 6e-3, "pitch_diameter": 30e-3, "contact_angle_deg": 15.0}


def described(*bearings: dict) -> dict:
    cfg = copy.deepcopy(load_config("paper-case1")[0])
    cfg["rolling_bearing"] = [dict(b) for b in bearings]
    return cfg


def lines(cat, family: str, member: str) -> dict[int, float]:
    """Order of every harmonic of ``family`` of bearing ``member``."""
    return {int(h): float(o) for f, h, m, o in zip(cat.family, cat.harmonic, cat.member,
                                                  cat.order, strict=True)
            if f == family and m == member}


def test_cwru_bearing_on_the_input_shaft_gives_the_published_multiples():
    cat = gear_set_catalogue(gearset_from_dict(described(CWRU["input bearing"])),
                             speed_rpm=1797.0)
    published = {"bearing_bpfi": 5.4152, "bearing_bpfo": 3.5848, "bearing_ftf": 0.39828,
                 "bearing_bsf": 4.7135 / 2}
    for family, order in published.items():
        got = lines(cat, family, "input bearing")
        assert got[1] == pytest.approx(order, rel=1e-4), family
        assert got[3] == pytest.approx(3 * order, rel=1e-4), family
    f = cat.frequency_hz()
    i = [k for k in range(len(cat)) if cat.family[k] == "bearing_bpfo" and cat.harmonic[k] == 1]
    assert f[i[0]] == pytest.approx(3.5848 * 1797.0 / 60, rel=1e-4)  # 107.37 Hz


def test_planet_bearing_turns_with_its_outer_ring_at_the_planet_speed_relative_to_the_pin():
    cat = gear_set_catalogue(gearset_from_dict(described(PLANET)), speed_rpm=1800.0)
    # hand-worked: sun 30 Hz, ring fixed, carrier f_s z_s/(z_s + |z_r|), planet relative to
    # the carrier (f_s - f_c) z_s / z_p
    fs, zs, zr, zp = 30.0, 33, 114, 40
    fc = fs * zs / (zs + zr)
    fr = (fs - fc) * zs / zp  # 19.194 Hz
    g = 6.0 / 30.0 * math.cos(math.radians(15.0))
    want = {"bearing_ftf": fr * (1 + g) / 2,  # cage relative to the stationary pin
            "bearing_bpfo": 12 * fr * (1 - g) / 2, "bearing_bpfi": 12 * fr * (1 + g) / 2,
            "bearing_bsf": 30.0 / (2 * 6.0) * fr * (1 - g * g)}
    for family, hz in want.items():
        assert lines(cat, family, "planet bearing")[1] * fs == pytest.approx(hz, rel=1e-12)
    assert fr == pytest.approx(cat.frequency_hz()[list(cat.family).index("mesh")] / zp)


def test_rotating_race_and_mounting_can_be_given():
    # the same bearing with the outer ring turning on a fixed inner ring (inside the sun):
    # relative speed unchanged, the cage frequency counted from the stationary inner ring
    b = dict(CWRU["input bearing"], rotating_race="outer", on="ring")
    cat = gear_set_catalogue(gearset_from_dict(described(b)), speed_rpm=1797.0)
    g = 7.94 / 39.04
    assert lines(cat, "bearing_ftf", "input bearing")[1] == pytest.approx((1 + g) / 2)
    assert lines(cat, "bearing_bpfo", "input bearing")[1] == pytest.approx(3.5848, rel=1e-4)
    # a bearing between two members at rest has no defect lines, and says so
    still = dict(CWRU["input bearing"], member="ring")
    cat = gear_set_catalogue(gearset_from_dict(described(still)), speed_rpm=1797.0)
    assert not lines(cat, "bearing_bpfo", "input bearing")
    assert any("turn together" in n for n in cat.notes)


@pytest.mark.parametrize("key, value, match", [
    ("member", "shaft9", r"member = 'shaft9' is not a member of the gear set \(admissible: "
                         r"carrier, planet1"),
    ("on", "moon", r"on = 'moon' is not a member"),
    ("on", "sun", r"on = 'sun' is the member the bearing supports"),
    ("n_rolling", 2, r"#1, bearing 'input bearing': n_rolling = 2 is not admissible "
                     r"\(admissible: an integer 3\.\.1000\)"),
    ("n_rolling", 9.5, r"n_rolling = 9\.5"),
    ("n_rolling", 10**320, r"n_rolling = 1000000"),
    ("rolling_diameter", 0.05, r"rolling_diameter = 0\.05 m must be smaller than "
                               r"pitch_diameter = 0\.03904 m"),
    ("pitch_diameter", math.inf, r"pitch_diameter = inf is not admissible \(admissible: "
                                 r"0\.0001 <= pitch_diameter <= 10\)"),
    ("rolling_diameter", "8 mm", r"rolling_diameter must be a number, got '8 mm'"),
    ("contact_angle_deg", 90.0, r"contact_angle_deg = 90\.0 is not admissible"),
    ("rotating_race", "cage", r"rotating_race = 'cage' is not admissible \(admissible: inner, "
                              r"outer\)"),
    ("colour", "red", r"unknown key 'colour'"),
    ("name", "", r"name must be a non-empty string"),
])
def test_bad_bearing_tables_are_refused_with_the_key(key, value, match):
    with pytest.raises(ConfigError, match=match) as info:
        gearset_from_dict(described(dict(CWRU["input bearing"], **{key: value})))
    assert "\n" not in str(info.value) and len(str(info.value)) < 400


def test_other_bad_arrays():
    cfg = described(CWRU["input bearing"], CWRU["input bearing"])
    with pytest.raises(ConfigError, match="name 'input bearing' is used twice"):
        gearset_from_dict(cfg)
    cfg["rolling_bearing"] = {"name": "x"}
    with pytest.raises(ConfigError, match=r"must be an array of tables"):
        gearset_from_dict(cfg)
    cfg["rolling_bearing"] = [dict(CWRU["input bearing"])]
    del cfg["rolling_bearing"][0]["n_rolling"]
    with pytest.raises(ConfigError, match="missing key 'n_rolling'"):
        gearset_from_dict(cfg)


def test_two_stage_sets_name_members_with_their_stage():
    cfg = copy.deepcopy(load_config("two-stage-example")[0])
    cfg["rolling_bearing"] = [dict(CWRU["input bearing"], member="s2.carrier")]
    cat = gear_set_catalogue(gearset_from_dict(cfg), speed_rpm=1500.0)
    assert lines(cat, "bearing_bpfo", "input bearing")
    cfg["stage1"]["rolling_bearing"] = [dict(CWRU["input bearing"])]
    with pytest.raises(ConfigError, match=r"\[\[stage1\.rolling_bearing\]\] is not admissible"):
        gearset_from_dict(cfg)


def test_catalogue_command_lists_the_bearing_lines(tmp_path):
    toml = (REPO / "gearvib" / "presets" / "paper-case1.toml").read_text()
    toml += ('\n[[rolling_bearing]]\nname = "input bearing"\nmember = "sun"\nn_rolling = 9\n'
             'rolling_diameter = 7.94e-3\npitch_diameter = 39.04e-3\n')
    (tmp_path / "set.toml").write_text(toml)
    res = subprocess.run([sys.executable, "-m", "gearvib", "catalogue", "set.toml", "--speed",
                          "1797", "--json"], cwd=tmp_path, capture_output=True, text=True,
                         check=False)
    assert res.returncode == 0, res.stderr
    rows = [r for r in json.loads(res.stdout)["lines"] if r["member"] == "input bearing"]
    fams = {r["family"] for r in rows}
    assert fams == {"bearing_ftf", "bearing_bpfo", "bearing_bpfi", "bearing_bsf"}
    bpfi = next(r for r in rows if r["family"] == "bearing_bpfi" and r["harmonic"] == 1)
    assert bpfi["order"] == pytest.approx(5.4152, rel=1e-4)
    assert bpfi["frequency_hz"] == pytest.approx(5.4152 * 1797 / 60, rel=1e-4)
    text = subprocess.run([sys.executable, "-m", "gearvib", "catalogue", "set.toml", "--speed",
                           "1797"], cwd=tmp_path, capture_output=True, text=True, check=False)
    assert text.returncode == 0 and "bearing_bpfi" in text.stdout


# ------------------------------------------------------------- machines without gears (rigs)

RIG = {"name": "rig", "type": "shafts", "operation": {"input": "motor"},
       "shaft": [{"name": "motor"}, {"name": "fan", "ratio": -2.5}],
       "rolling_bearing": [dict(CWRU["input bearing"], member="motor")]}


def test_the_cwru_rig_preset_gives_the_published_multiples_without_a_gear_set():
    from gearvib.config import load_description, load_gearset
    from gearvib.rig import ShaftRig

    rig = load_description("cwru-drive-end")
    assert isinstance(rig, ShaftRig) and rig.input == "motor"
    cat = rig.catalogue(speed_rpm=1797)
    bearing = "drive-end bearing"
    for fam, order in (("bearing_bpfi", 5.4152), ("bearing_bpfo", 3.5848),
                       ("bearing_ftf", 0.39828)):
        assert lines(cat, fam, bearing)[1] == pytest.approx(order, rel=1e-4), fam
    assert 2 * lines(cat, "bearing_bsf", bearing)[1] == pytest.approx(4.7135, rel=1e-4)
    bpfi = cat.frequency_hz()[(cat.family == "bearing_bpfi") & (cat.harmonic == 1)]
    assert bpfi[0] == pytest.approx(162.19, abs=0.01)  # the 162.19 Hz at 1797 min-1
    # no mesh, no natural frequency: only shaft harmonics and the bearing's families
    assert set(cat.family) == {"shaft", "bearing_ftf", "bearing_bpfo", "bearing_bpfi",
                               "bearing_bsf"}
    with pytest.raises(ConfigError, match="type = 'shafts' describes shafts and rolling "
                       "bearings without gears"):
        load_gearset("cwru-drive-end")


def test_shafts_with_ratios_and_a_bearing_between_two_shafts():
    from gearvib.config import rig_from_dict

    cfg = copy.deepcopy(RIG)
    cfg["rolling_bearing"].append(dict(PLANET, name="fan bearing", member="fan",
                                       on="motor"))
    rig = rig_from_dict(cfg)
    assert rig.kinematic_ratios == {"motor": 1.0, "fan": -2.5}
    cat = rig.catalogue()
    assert lines(cat, "shaft", "fan")[1] == pytest.approx(2.5)
    # between the shafts the rings turn at |-2.5 - 1| = 3.5 per motor revolution
    g = 6e-3 / 30e-3 * math.cos(math.radians(15.0))
    assert rig.relative_speed("fan bearing") == pytest.approx(3.5)
    assert lines(cat, "bearing_bpfo", "fan bearing")[1] == pytest.approx(
        12 * 3.5 * (1 - g) / 2, rel=1e-12)
    # orders of another reference shaft
    assert rig.catalogue(reference="fan").order[0] == pytest.approx(
        cat.order[0] / 2.5, rel=1e-12)
    with pytest.raises(ValueError, match=r"reference = 'x' is not a shaft of the rig; "
                       r"admissible: \['fan', 'motor'\]"):
        rig.catalogue(reference="x")


@pytest.mark.parametrize(("change", "match"), [
    (lambda c: c.update(sensor=[]), r"unknown key 'sensor' in a description of type = "
     r"'shafts' \(admissible: description, name, operation"),
    (lambda c: c.pop("shaft"), r"missing key 'shaft'"),
    (lambda c: c.update(shaft=[]), r"\[\[shaft\]\] must be an array of 1..100 tables"),
    (lambda c: c["shaft"].append({"name": "motor"}), "name 'motor' is used twice"),
    (lambda c: c["shaft"][1].update(ratio=0.0), r"\[\[shaft\]\] 'fan'.ratio = 0.0 is not "
     r"admissible \(admissible: 1e-6 <= \|ratio\| <= 1e6"),
    (lambda c: c["shaft"][1].update(ratio=True), "ratio must be a number, got True"),
    (lambda c: c["shaft"][1].update(ratio="2"), "ratio must be a number, got '2'"),
    (lambda c: c["shaft"][1].update(ratio=math.nan), "ratio = nan is not admissible"),
    (lambda c: c["shaft"][1].update(speed=2), r"unknown key 'speed' in \[\[shaft\]\] #2"),
    (lambda c: c["shaft"][0].update(name="ground"), "other than 'ground'"),
    (lambda c: c["operation"].update(input="belt"), r"\[operation\].input = 'belt' is not a "
     "shaft"),
    (lambda c: c["operation"].update(input="fan"), "has ratio -2.5; the input shaft's ratio "
     "is 1"),
    (lambda c: c["operation"].update(output="fan"), r"unknown key 'output' in \[operation\]"),
    (lambda c: c["rolling_bearing"][0].update(member="sun"), r"member = 'sun' is not a member "
     r"of the gear set \(admissible: fan, motor\)"),
    (lambda c: c["rolling_bearing"][0].update(n_rolling=2), "n_rolling = 2 is not admissible"),
    (lambda c: c.update(name=3), "name must be a string"),
])
def test_bad_rig_descriptions_name_the_key(change, match):
    from gearvib.config import description_from_dict, gearset_from_dict

    cfg = copy.deepcopy(RIG)
    change(cfg)
    with pytest.raises(ConfigError, match=match):
        description_from_dict(cfg)
    with pytest.raises(ConfigError):  # never a gear set
        gearset_from_dict(cfg)


def test_rig_preset_on_the_command_line(capsys):
    import tomllib

    from gearvib.cli import main
    from gearvib.config import list_presets, list_rigs, load_config

    assert "cwru-drive-end" in list_rigs() and "cwru-drive-end" not in list_presets()
    assert main(["preset"]) == 0
    out = capsys.readouterr().out
    assert "machines without gears" in out and "cwru-drive-end" in out
    assert main(["preset", "cwru-drive-end"]) == 0
    text = capsys.readouterr().out
    assert tomllib.loads(text) == load_config("cwru-drive-end")[0]
    assert main(["catalogue", "cwru-drive-end", "--speed", "1797", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["lines"]
    bpfi = next(r for r in rows if r["family"] == "bearing_bpfi" and r["harmonic"] == 1)
    assert bpfi["frequency_hz"] == pytest.approx(162.19, abs=0.01)
    assert main(["modes", "cwru-drive-end"]) == 2
    assert "no dynamic model" in capsys.readouterr().err
