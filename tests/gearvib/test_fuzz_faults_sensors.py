"""Property-based fuzz suite over the ``[[fault]]``, ``[[sensor]]`` and ``[[rolling_bearing]]``
tables of gear-set descriptions (hypothesis).

The base is ``paper-case1`` with one table of every fault kind (the crack and pitch errors
also read from files), an accelerometer with housing modes, one with a measured FRF (CSV), a
tacho and two rolling bearings. Each example mutates it 1-4 times: the generic mutations of
:mod:`tests.gearvib.test_fuzz_config` anywhere in the tables (keys deleted or inserted, values
retyped, extreme numbers, scaling), and targeted edits that set a fault, sensor or bearing key
to a drawn value -- a number far out of range, NaN, +-inf, an integer of 320 digits, a wrong
type, another kind, and file paths: missing, a directory, ``/dev/zero``, ``/proc`` files, a
binary file, an empty one, one of 17 MiB, one with NaN values or a non-number in the middle.
The result goes the way of ``gearvib simulate``: :func:`gearset_from_dict`, :func:`assemble`
(faults applied to the tooth map), a short simulation (``max_steps = 20000``) with the sensor
signals and :meth:`to_dataset`, and the catalogue with the bearings' defect lines. Property:
only documented errors (:mod:`tests.gearvib.fuzz_support`), each within 60 s.

``GEARVIB_FUZZ_EXAMPLES`` sets the number of examples (default 100 here, fixed seed).
"""

from __future__ import annotations

import copy
import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gearvib.assembly import assemble
from gearvib.catalogue import gear_set_catalogue
from gearvib.config import gearset_from_dict, load_config
from gearvib.simulate import simulate
from gearvib.simulation.settings import conditions_from_settings, read_run_settings
from tests.gearvib import fuzz_support as fz
from tests.gearvib.test_fuzz_config import mutate, mutation

MAX_STEPS = 20_000
FILES = Path(tempfile.mkdtemp(prefix="gearvib-fault-fuzz-"))


def _write_files() -> None:
    f = np.linspace(0.0, 10_000.0, 41)
    (FILES / "frf.csv").write_text("frequency, real, imag\n" + "".join(
        f"{x}, {1e-3 * (1 + x / 1e4)}, {-2e-4}\n" for x in f))
    (FILES / "pitch.csv").write_text("tooth, deviation\n" + "".join(
        f"{i}, {2e-6 * math.sin(2 * math.pi * i / 33)}\n" for i in range(33)))
    (FILES / "curve.csv").write_text("u, k\n" + "".join(
        f"{u}, {1.5e8 * (1 - 0.3 * u)}\n" for u in np.linspace(0, 1, 11)))
    (FILES / "binary.csv").write_bytes(bytes(range(256)) * 8)
    (FILES / "empty.csv").write_bytes(b"")
    (FILES / "nan.csv").write_text("0, nan, 1\n1, inf, 2\n2, 1e400, 3\n")
    (FILES / "cut.csv").write_text("0, 1e-6\n1, 2e-6\n2, 1.5e-\n3, x1\n4, 0\n")
    (FILES / "wide.csv").write_text("".join(f"{i}," * 50 + "1\n" for i in range(40)))
    (FILES / "one.csv").write_text("0, 1e-6\n")
    with open(FILES / "big.csv", "wb") as fh:  # above every text reader's size limit
        fh.write(b"0, 1e-6, 0\n" * (17 * 2**20 // 11 + 1))
    (FILES / "binary.uff").write_bytes(b"    -1\n    58\n" + bytes(range(256)) * 4)
    (FILES / "adir").mkdir()


_write_files()
PATHS = [str(FILES / n) for n in ("frf.csv", "pitch.csv", "curve.csv", "binary.csv",
                                  "empty.csv", "nan.csv", "cut.csv", "wide.csv", "one.csv",
                                  "big.csv", "adir", "missing.csv", "x.uff", "binary.uff")] + [
    "/dev/zero", "/dev/null", "/proc/self/status", "/proc/self/mem", "", "frf.csv",
    "../../etc/passwd", "\x00", "a" * 5000]


def base_description() -> dict:
    cfg = copy.deepcopy(load_config("paper-case1")[0])
    cfg["simulation"] = {"drive": "speed", "speed_start_rpm": 1500.0, "speed_end_rpm": 1500.0,
                         "duration": 0.002, "input_torque": 60.0}
    cfg["fault"] = [
        {"kind": "crack", "member": "sun", "tooth": 3, "severity": 0.3},
        {"kind": "crack", "member": "planet1", "tooth": 7, "mate": "sun",
         "curve": {"path": PATHS[2], "position_unit": "path_fraction"}},
        {"kind": "pitting", "member": "planet2", "tooth": 1, "severity": 0.4,
         "path_start": 0.3, "path_end": 0.7, "depth": 0.5e-6, "flank": "left"},
        {"kind": "broken_tooth", "member": "ring", "tooth": 10},
        {"kind": "eccentricity", "member": "sun", "eccentricity": 5e-6, "phase_deg": 30.0},
        {"kind": "pitch_error", "member": "sun", "file": PATHS[1], "unit": "m"},
        {"kind": "pitch_error", "member": "planet3", "tooth": 2, "deviation": 3e-6},
        {"kind": "pin_error", "member": "planet2", "tangential": 20e-6, "radial": -5e-6},
        {"kind": "backlash", "member": "planet3", "backlash": 1e-5},
    ]
    cfg["sensor"] = [
        {"name": "top", "angle_deg": 90.0, "window": "hann", "width_deg": 90.0,
         "housing_modes": [{"frequency_hz": 3000.0, "damping_ratio": 0.02, "gain": 1.0}]},
        {"name": "side", "angle_deg": 0.0, "window": "exponential", "width_deg": 40.0,
         "frf": {"path": PATHS[0], "quantity": "accelerance", "columns": "real_imag"}},
        {"type": "tacho", "name": "tacho", "pulses_per_rev": 60, "duty": 0.5},
    ]
    cfg["rolling_bearing"] = [
        {"name": "input bearing", "member": "sun", "n_rolling": 9,
         "rolling_diameter": 7.94e-3, "pitch_diameter": 39.04e-3, "contact_angle_deg": 0.0},
        {"name": "planet bearing", "member": "planet1", "n_rolling": 12,
         "rolling_diameter": 5e-3, "pitch_diameter": 30e-3, "rotating_race": "outer"},
    ]
    return cfg


BASE = base_description()
TABLES = ("fault", "sensor", "rolling_bearing")
KEYS = sorted({k for t in TABLES for d in BASE[t] for k in d}
              | {"frf", "housing_modes", "curve", "file", "single", "cumulative", "mate",
                 "level_v", "member", "on", "inner", "outer", "colour", "kind", "type"})
EXTREME = [0, -1, 1, 2, 3, 33, 10**320, -(10**30), 2**63, 33.9, 0.5, 1.5, -0.0, 1e-320,
           1e308, -1e308, math.inf, -math.inf, math.nan, 1e38, 1e9, 180.0, 360.0, 90.0]
value = st.one_of(
    st.sampled_from(EXTREME), st.sampled_from(PATHS), st.floats(allow_nan=True),
    st.integers(-10**4, 10**4), st.booleans(), st.text(max_size=6),
    st.sampled_from(["sun", "ring", "carrier", "planet1", "planet9", "ground", "inner",
                     "outer", "crack", "pitting", "tacho", "accelerometer", "hann",
                     "rectangular", "left", "both", "um", "base_pitch", "mobility",
                     "magnitude_phase", "N/(mm um)"]),
    st.lists(st.one_of(st.floats(-1e-3, 1e-3), st.sampled_from(EXTREME)), max_size=40),
    st.dictionaries(st.sampled_from(["path", "frequency_hz", "damping_ratio", "gain", "set",
                                     "quantity", "position", "stiffness", "sun", "x"]),
                    st.one_of(st.sampled_from(PATHS), st.sampled_from(EXTREME),
                              st.lists(st.floats(0, 2), max_size=4)), max_size=3),
    st.lists(st.fixed_dictionaries({"frequency_hz": st.sampled_from(EXTREME),
                                    "damping_ratio": st.sampled_from(EXTREME),
                                    "gain": st.sampled_from(EXTREME)}), max_size=2),
)
edit = st.tuples(st.sampled_from(TABLES), st.integers(0, 20), st.sampled_from(KEYS), value,
                 st.booleans())
# the keys that name files, with a file path drawn (the generic edits rarely meet them)
file_edit = st.tuples(st.sampled_from([("fault", 1, "curve"), ("fault", 5, "file"),
                                       ("sensor", 1, "frf"), ("sensor", 0, "frf")]),
                      st.sampled_from(PATHS), st.booleans()).map(
    lambda t: (t[0][0], t[0][1], t[0][2],
               ({"path": t[1]} if t[0][2] == "curve" or t[2] else t[1]), False))
change = st.one_of(mutation.map(lambda m: ("mutate", m)), edit.map(lambda e: ("edit", e)),
                   file_edit.map(lambda e: ("edit", e)))


def apply(cfg: dict, changes: list) -> dict:
    cfg = copy.deepcopy(cfg)
    for what, c in changes:
        if what == "mutate":
            # the generic mutations, aimed at the new tables
            table = cfg.get(TABLES[c[1] % 3])
            if isinstance(table, list | dict):
                sub = mutate({"t": table}, [c])
                cfg[TABLES[c[1] % 3]] = sub.get("t", table) if sub else table
            else:
                cfg = mutate(cfg, [c])
            continue
        name, index, key, v, delete = c
        tables = cfg.get(name)
        if not isinstance(tables, list) or not tables:
            cfg[name] = v
            continue
        t = tables[index % len(tables)]
        if not isinstance(t, dict):
            tables[index % len(tables)] = v
        elif delete and key in t:
            del t[key]
        else:
            t[key] = v
    return cfg


def run(cfg: dict) -> None:
    """What ``gearvib simulate`` and ``gearvib catalogue`` do with a description."""
    gs = gearset_from_dict(cfg)
    model = assemble(gs)
    gear_set_catalogue(gs, speed_rpm=1500.0, model=model)
    s = read_run_settings(cfg.get("simulation", {}))
    res = simulate(model, conditions_from_settings(s), dt=s["dt"], fs_out=s["fs_out"],
                   gyroscopic=s["gyroscopic"], progress=False, max_steps=MAX_STEPS)
    res.to_dataset()


@pytest.fixture(scope="module", autouse=True)
def _report():
    yield
    fz.write_report()


def test_the_base_description_runs_with_every_fault_sensor_and_bearing():
    gs = gearset_from_dict(BASE)
    assert len(gs.faults) == 9 and len(gs.sensors) == 3
    run(BASE)
    fz.record("faults, sensors, bearings: base", None)


@settings(max_examples=fz.examples(100), deadline=None, database=None,
          derandomize=fz.derandomize(),
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(changes=st.lists(change, min_size=1, max_size=4))
def test_fault_sensor_and_bearing_tables_give_only_documented_errors(changes):
    cfg = apply(BASE, changes)
    fz.check_call("faults, sensors, bearings", lambda: run(cfg), changes, 60.0)


@pytest.mark.parametrize("table, index, key, value, match", [
    ("fault", 5, "file", PATHS[3], r"\[\[fault\]\] #6 \(pitch_error\): binary.csv is not a "
                                   r"UTF-8 text file \(byte 128"),
    ("fault", 5, "file", PATHS[9], r"#6 \(pitch_error\): big.csv has 17.0 MiB \(admissible: at "
                                   r"most 16 MiB"),
    ("fault", 5, "file", PATHS[6], r"#6 \(pitch_error\): cut.csv, line 3: not a number"),
    ("fault", 5, "file", "a" * 5000, r"#6 \(pitch_error\): file 'a+' does not exist"),
    ("sensor", 1, "frf", PATHS[3], r"\[\[sensor\]\] #2 'side': frf .*binary.csv: not a UTF-8"),
    ("sensor", 1, "frf", PATHS[9], r"#2 'side': frf .*big.csv: 17.0 MiB is too large"),
    ("sensor", 1, "frf", PATHS[6], r"#2 'side': frf .*cut.csv: found 0 numeric rows"),
    ("sensor", 1, "frf", "/dev/zero", r"#2 'side': frf file '/dev/zero' does not exist"),
    ("sensor", 1, "frf", "\x00", r"#2 'side': frf file '\\x00' does not exist"),
    ("fault", 0, "tooth", 10**320, r"crack fault on 'sun': tooth = 1000.* \(admissible: 0 \.\. "
                                   r"32; 'sun' has 33 teeth\)"),
    ("sensor", 2, "pulses_per_rev", 10**9, r"pulses_per_rev"),
], ids=["fault-binary", "fault-big", "fault-cut", "fault-long-name", "frf-binary", "frf-big",
        "frf-cut", "frf-dev-zero", "frf-nul", "tooth-huge", "pulses-huge"])
def test_bad_files_and_values_are_refused_with_the_key(table, index, key, value, match):
    cfg = copy.deepcopy(BASE)
    cfg[table][index][key] = value
    # a ConfigError when the description is read, a FaultError (a ValueError) when the
    # faults meet the assembled teeth
    with pytest.raises(ValueError, match=match) as info:
        run(cfg)
    assert "\n" not in str(info.value)
    if key in ("file", "frf"):  # never the file's content
        assert "1.5e-" not in str(info.value) and "\\x01" not in str(info.value)


# for the debugging harness: (strategy, run, prepare)
COLLECT = (st.lists(change, min_size=1, max_size=4), run, lambda ch: apply(BASE, ch))
