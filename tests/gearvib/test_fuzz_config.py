"""Property-based fuzz suite over gear-set descriptions (hypothesis).

Every built-in preset (and a literature model of ``type = "general"`` and a two-stage set of
the tests) is mutated 1-3 times at random places: a key deleted, an unknown or
misplaced key inserted, a value replaced by a value of another type (strings for numbers,
``33.9`` for a tooth number, lists, tables, booleans, ``None`` as the Python API may see it),
by an extreme number (NaN, +-inf, 1e308, 5e-324, 0, -1, an integer of 320 digits) or scaled
by 1e-300..1e300. The result goes the way of ``gearvib modes`` / ``simulate`` up to the run:
:func:`gearset_from_dict`, :func:`assemble`, :func:`modal_analysis`, and the ``[simulation]``
table through :func:`read_run_settings` and :func:`conditions_from_settings`. The study recipes
of ``reports/`` and the shipped examples are mutated the same way, written as TOML and read
with :func:`load_study`,
followed by the checks a study makes before its first simulation (every case's description, run
settings and map size). Property: only documented errors occur
(:mod:`tests.gearvib.fuzz_support`), each within 30 s.

``GEARVIB_FUZZ_EXAMPLES`` sets the number of examples (default 1000 and 300 here, fixed seed);
the README reports the long campaign.
"""

from __future__ import annotations

import copy
import json
import math
import tempfile
import tomllib
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, list_presets, load_config
from gearvib.modal import modal_analysis
from gearvib.report.study import load_study
from gearvib.simulation.settings import conditions_from_settings, read_run_settings
from tests.gearvib import fuzz_support as fz
from tests.gearvib.test_literature_models import lin_parker
from tests.gearvib.two_stage_sets import other_stage, paper_stage, two_stage_config

REPO = Path(__file__).resolve().parents[2]
PRESETS = {name: load_config(name)[0] for name in list_presets()}


def _recipe(path: Path) -> dict:
    """A recipe with its gear-set files as absolute paths (it is rewritten elsewhere)."""
    doc = tomllib.loads(path.read_text())
    for case in doc.get("study", {}).get("cases", []):
        cfg = case.get("config", "")
        if cfg.endswith(".toml") and not Path(cfg).is_absolute():
            case["config"] = str((path.parent / cfg).resolve())
    return doc


RECIPE_FILES = [*(REPO / "reports").glob("*.toml"),
                *(REPO / "gearvib" / "recipes").glob("paper*.toml")]
RECIPES = {p.name: _recipe(p) for p in sorted(RECIPE_FILES)}
# a literature model (type = "general", [[body]] / [[mesh]] / [[coupling]]) and a two-stage set
# with its own stages, as the tests build them
PRESETS["general: lin-parker"] = lin_parker()
PRESETS["two-stage: test"] = two_stage_config(paper_stage(), other_stage())


def _keys(obj: Any, out: set[str]) -> set[str]:
    if isinstance(obj, dict):
        for k, v in obj.items():
            out.add(k)
            _keys(v, out)
    elif isinstance(obj, list):
        for v in obj:
            _keys(v, out)
    return out


KEY_NAMES = sorted(set().union(*(_keys(c, set()) for c in [*PRESETS.values(),
                                                             *RECIPES.values()]))
                   | {"colour", "z_sun2", "n_planet", "Mass", ""})

EXTREMES = [0, 1, -1, 2, 3, 33, 40, -114, 114, 10**320, -(10**30), 2**63, 33.9, -0.0, 0.5,
            1e-320, 5e-324, 1e308, -1e308, math.inf, -math.inf, math.nan, 1e38, 1e-38, 1e9]
FACTORS = [0, -1, 1e-300, 1e-30, 1e-6, 0.5, 1.5, 3, 1e6, 1e30, 1e300, 10**300]

values = st.one_of(
    st.none(),
    st.booleans(),
    st.sampled_from(EXTREMES),
    st.integers(-10**6, 10**6),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from(["", "rigid", "free", "-114", "33", "1e5", "sun", "ring", "carrier",
                     "planet", "planet1", "nan", "constant", "x" * 300, "speed", "motor"]),
    st.text(max_size=6),
    st.lists(st.one_of(st.integers(-10, 400), st.floats(allow_nan=True), st.text(max_size=3)),
             max_size=6),
    st.dictionaries(st.sampled_from(["model", "k", "k_min", "k_max", "path", "x", "mass",
                                     "radial", "contact_ratio"]),
                    st.one_of(st.floats(), st.text(max_size=5), st.integers(-5, 5),
                              st.sampled_from(["constant", "rectangular", "csv", "pairs"])),
                    max_size=4),
)

mutation = st.tuples(st.sampled_from(["delete", "replace", "insert", "scale", "retype"]),
                     st.integers(0, 10**6), values, st.sampled_from(FACTORS),
                     st.sampled_from(KEY_NAMES))


def paths(obj: Any, prefix: tuple = ()) -> list[tuple]:
    """Every path to a value (dict keys and list indices), containers included."""
    out: list[tuple] = []
    items = obj.items() if isinstance(obj, dict) else enumerate(obj) \
        if isinstance(obj, list) else ()
    for k, v in items:
        out.append((*prefix, k))
        out.extend(paths(v, (*prefix, k)))
    return out


def _retype(v: Any) -> Any:
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, int):
        return float(v) + 0.5 if v % 2 else str(v)
    if isinstance(v, float):
        return str(v) if math.isfinite(v) and v != int(v) else [v]
    if isinstance(v, str):
        return 1.0 if v else 0
    if isinstance(v, list):
        return {str(i): x for i, x in enumerate(v)}
    if isinstance(v, dict):
        return list(v.values())
    return "none"


def mutate(cfg: dict, mutations: list) -> dict:
    """Apply the drawn mutations to a copy of ``cfg``."""
    cfg = copy.deepcopy(cfg)
    for op, index, value, factor, key in mutations:
        all_paths = paths(cfg)
        if not all_paths:
            cfg[key] = value
            continue
        path = all_paths[index % len(all_paths)]
        parent: Any = cfg
        for k in path[:-1]:
            parent = parent[k]
        last = path[-1]
        current = parent[last]
        if op == "delete":
            del parent[last]
        elif op == "replace":
            parent[last] = value
        elif op == "insert":
            if isinstance(current, dict):
                current[key] = value
            elif isinstance(current, list):
                current.insert(index % (len(current) + 1), value)
            else:
                parent[last] = value
        elif op == "scale":
            if isinstance(current, int | float) and not isinstance(current, bool):
                try:
                    parent[last] = current * factor
                except OverflowError:
                    parent[last] = factor
            else:
                parent[last] = value
        else:
            parent[last] = _retype(current)
    return cfg


def build(cfg: dict) -> None:
    """The path of ``gearvib modes`` and the run set-up of ``gearvib simulate``."""
    model = assemble(gearset_from_dict(cfg))
    modal_analysis(model)
    sim = cfg.get("simulation", {})
    conditions_from_settings(read_run_settings(sim))


@pytest.fixture(scope="module", autouse=True)
def _report():
    yield
    fz.write_report()


def test_every_preset_builds_unmutated():
    for cfg in PRESETS.values():
        build(cfg)
        fz.record("descriptions: presets", None)
    assert len(PRESETS) >= 8


@settings(max_examples=fz.examples(400), deadline=None, database=None,
          derandomize=fz.derandomize(),
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(name=st.sampled_from(sorted(PRESETS)), mutations=st.lists(mutation, min_size=1,
                                                                 max_size=3))
def test_mutated_descriptions_give_only_documented_errors(name, mutations):
    cfg = mutate(PRESETS[name], mutations)
    fz.check_call("descriptions", lambda: build(cfg), (name, mutations), 30.0)


@pytest.mark.parametrize("path, value, match", [
    (("operation", "fixed"), 0, r"\[operation\]\.fixed must name a member"),
    (("operation", "input"), [], r"\[operation\]\.input must be a non-empty string"),
    (("geometry", "z_planet"), 114, r"z_planet = 114 is not admissible with z_ring = -114"),
    (("geometry", "z_sun"), 33.9, r"\[geometry\]\.z_sun must be an integer, got 33.9"),
    (("geometry", "z_ring"), "-114", r"\[geometry\]\.z_ring must be an integer, got '-114'"),
    (("geometry", "n_planets"), 4, r"n_planets = 4 disagrees with the 3 planet_angles_deg"),
    (("geometry", "n_planets"), 10**9, r"n_planets = 1000000000 is not admissible"),
    (("bodies", "sun", "mass"), 10**320, r"\[bodies\.sun\]\.mass = 1000.*admissible: a finite"),
    (("geometry", "profile_shift_sun"), 1e300, r"profile_shift_sun = 1e\+300 .*<= 10"),
    (("meshes", "sun", "damping_ratio"), 1e308, r"damping_ratio = 1e\+308 .*<= 10"),
    (("meshes", "sun", "stiffness"), {"model": "fourier", "mean": 1e8, "cos": [1e6] * 5000},
     r"stiffness\.cos has 5000 values"),
    (("simulation", "fs_out"), {}, r"\[simulation\]\.fs_out must be a number"),
    (("simulation", "duration"), "long", r"\[simulation\]\.duration must be a number"),
    (("simulation", "duration"), math.inf, r"\[simulation\]\.duration = inf"),
    (("simulation", "input_torque"), math.nan, r"\[simulation\]\.input_torque = nan"),
    (("simulation", "speed_end_rpm"), 10**400, r"\[simulation\]\.speed_end_rpm = 1000"),
])
def test_the_issues_examples_are_refused_with_the_key(path, value, match):
    """The inputs the issue lists: each refused with a message naming the key."""
    from gearvib.config import ConfigError

    cfg = copy.deepcopy(PRESETS["paper-case1"])
    parent = cfg
    for k in path[:-1]:
        parent = parent[k]
    parent[path[-1]] = value
    with pytest.raises(ConfigError, match=match):
        build(cfg)


def test_integers_stay_integers():
    """``z_sun = 33.0`` is the integer 33; 33.9 and "33" are refused (above)."""
    cfg = copy.deepcopy(PRESETS["paper-case1"])
    cfg["geometry"]["z_sun"] = 33.0
    assert assemble(gearset_from_dict(cfg)).n_mesh == 6


# ------------------------------------------------------------------------------ study recipes


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) \
            else repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v if x is not None) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {_toml_value(x)}" for k, x in v.items()
                               if x is not None) + "}"
    return '"none"'


def to_toml(doc: dict) -> str:
    """TOML text of a (mutated) recipe: tables as [sections], nested tables inline."""
    lines = [f"{json.dumps(str(k))} = {_toml_value(v)}" for k, v in doc.items()
             if not isinstance(v, dict) and v is not None]
    for k, v in doc.items():
        if isinstance(v, dict):
            lines.append(f"[{json.dumps(str(k))}]")
            lines += [f"{json.dumps(str(kk))} = {_toml_value(vv)}" for kk, vv in v.items()
                      if vv is not None]
    return "\n".join(lines) + "\n"


def check_study(path: Path) -> None:
    """What ``gearvib report STUDY.toml`` checks before its first simulation."""
    fz.check_study_cases(load_study(path))


def test_every_recipe_passes_its_checks_unmutated(tmp_path):
    for name, doc in RECIPES.items():
        p = tmp_path / name
        p.write_text(to_toml(doc))
        check_study(p)
        fz.record("study recipes: unmutated", None)
    assert len(RECIPES) >= 2


@settings(max_examples=fz.examples(300), deadline=None, database=None,
          derandomize=fz.derandomize(),
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(name=st.sampled_from(sorted(RECIPES)), mutations=st.lists(mutation, min_size=1,
                                                                 max_size=3))
def test_mutated_study_recipes_give_only_documented_errors(name, mutations):
    doc = mutate(RECIPES[name], mutations)
    with tempfile.TemporaryDirectory(prefix="gearvib-recipe-fuzz-") as d:
        p = Path(d) / "study.toml"
        p.write_text(to_toml(doc))
        fz.check_call("study recipes", lambda: check_study(p), (name, mutations), 30.0)
