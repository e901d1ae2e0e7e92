"""Property-based fuzz suite over run settings: the ``[simulation]`` table and the command-line
overrides, all the way through a (short) simulation (hypothesis).

Each example takes a preset, sets or deletes keys of its ``[simulation]`` table (values of
the right type in and out of range, and of wrong types: ``fs_out = {}``, ``duration =
"long"``, NaN, +-inf, 1e308, integers of 320 digits, negative or zero values), adds
command-line overrides (``--speed``, ``--duration``, ``--fs``, ``--dt``, ``--torque`` values)
and runs what ``gearvib simulate`` runs: :func:`read_run_settings`,
:func:`conditions_from_settings`, :func:`simulate` (with a time budget of
``max_steps = 20000`` so that accepted runs stay short and longer ones are refused by the run-
size check) and :meth:`RunUpResult.to_dataset`. Property: only documented errors occur --
:class:`~gearvib.config.ConfigError` (with :class:`~gearvib.memory.RunSizeError`) for bad
settings, :class:`~gearvib.simulate.SimulationError` for a real blow-up -- each within 60 s.

``GEARVIB_FUZZ_EXAMPLES`` sets the number of examples (default 500 here, fixed seed).
"""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, list_presets, load_config
from gearvib.simulate import simulate
from gearvib.simulation.settings import conditions_from_settings, read_run_settings
from tests.gearvib import fuzz_support as fz

MAX_STEPS = 20_000
CONFIGS = {name: load_config(name)[0] for name in list_presets()}
MODELS: dict = {}

EXTREMES = [0, -1, -0.0, 1e308, -1e308, math.inf, -math.inf, math.nan, 10**320, -(10**320),
            5e-324, 1e-300, 1e12, True, "long", "", {}, [], None]

tiny = st.floats(1e-4, 5e-3)
speed = st.one_of(st.floats(-3000, 8000), st.sampled_from([0.0, 1e5, 1e6, 1e9]))
weird = st.sampled_from(EXTREMES)
number = st.one_of(st.floats(-1e3, 1e3), weird)

kloss = st.fixed_dictionaries({"synchronous_rpm": st.one_of(st.floats(1, 4000), weird),
                               "breakdown_torque": st.one_of(st.floats(1, 500), weird),
                               "breakdown_slip": st.one_of(st.floats(0.01, 0.99), weird)})
table = st.fixed_dictionaries({
    "speed_rpm": st.one_of(st.lists(st.floats(0, 4000), min_size=2, max_size=5).map(sorted),
                           st.lists(number, max_size=4), weird),
    "torque": st.one_of(st.lists(st.floats(-200, 500), min_size=2, max_size=5),
                        st.lists(number, max_size=4), weird)})

VALUES = {
    "drive": st.sampled_from(["speed", "torque", "motor", "Speed", 1, None]),
    "speed_start_rpm": st.one_of(speed, weird),
    "speed_end_rpm": st.one_of(speed, weird),
    "duration": st.one_of(tiny, tiny, tiny, st.floats(0.01, 2.0), weird),
    "input_torque": st.one_of(st.floats(-500, 500), weird),
    "load_torque": st.one_of(st.floats(-500, 500), st.lists(number, min_size=2, max_size=4),
                             weird),
    "load_inertia": st.one_of(st.floats(0, 10), weird),
    "drive_stiffness": st.one_of(st.floats(1e-3, 1e9), weird),
    "drive_damping": st.one_of(st.floats(0, 1e4), weird),
    "motor": st.one_of(kloss, table, weird,
                       st.dictionaries(st.sampled_from(["x", "speed_rpm", "breakdown_slip"]),
                                       number, max_size=2)),
    "fs_out": st.one_of(st.floats(1.0, 2e6), st.sampled_from([1000.0, 20000.0, 1e-3]), weird),
    "dt": st.one_of(st.floats(1e-7, 1e-3), weird),
    "gyroscopic": st.one_of(st.booleans(), st.sampled_from([0, 1, "yes"])),
    "colour": st.just("red"),
}
edit = st.one_of(st.tuples(st.sampled_from(sorted(VALUES)), st.just("delete")),
                 st.sampled_from(sorted(VALUES)).flatmap(
                     lambda k: st.tuples(st.just(k), VALUES[k])))
overrides = st.fixed_dictionaries({}, optional={
    "speed": st.tuples(st.floats(0, 1e6), st.floats(0, 1e6)),  # --speed is finite, >= 0
    "duration": st.one_of(tiny, st.floats(1e-6, 1e6)),  # --duration > 0, finite
    "fs_out": st.floats(1e-3, 1e7),
    "dt": st.floats(1e-12, 1.0),
    "input_torque": st.floats(-1e6, 1e6),
})


def model_of(name: str):
    if name not in MODELS:
        MODELS[name] = assemble(gearset_from_dict(CONFIGS[name]))
    return MODELS[name]


def run(name: str, sim: dict, cli: dict):
    """What ``gearvib simulate`` runs after reading the description."""
    over = {k: v for k, v in cli.items() if k != "speed"}
    if "speed" in cli:
        over["speed_start_rpm"], over["speed_end_rpm"] = cli["speed"]
    settings_ = read_run_settings(sim, over)
    cond = conditions_from_settings(settings_)
    res = simulate(model_of(name), cond, dt=settings_["dt"], fs_out=settings_["fs_out"],
                   gyroscopic=settings_["gyroscopic"], progress=False, max_steps=MAX_STEPS)
    res.to_dataset()


@pytest.fixture(scope="module", autouse=True)
def _report():
    yield
    fz.write_report()


@settings(max_examples=fz.examples(200), deadline=None, database=None,
          derandomize=fz.derandomize(),
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(name=st.sampled_from(sorted(CONFIGS)), edits=st.lists(edit, min_size=1, max_size=4),
       cli=overrides)
def test_run_settings_give_only_documented_errors(name, edits, cli):
    sim = dict(CONFIGS[name].get("simulation", {}))
    sim["duration"] = 0.003  # short unless an edit says otherwise
    for key, value in edits:
        if value == "delete":
            sim.pop(key, None)
        else:
            sim[key] = value
    fz.check_call("run settings", lambda: run(name, sim, cli), (name, sim, cli), 60.0)
