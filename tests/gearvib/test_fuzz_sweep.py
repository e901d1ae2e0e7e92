"""Property-based fuzz suite over sweep descriptions (hypothesis).

Five sweep descriptions (a grid with a list-valued key and labels, a zip, a random sweep with
a uniform and a truncated normal distribution, a sweep of run settings over a gear-set TOML
file given by a relative path, a two-stage grid) are mutated 1-4 times: the generic mutations of
:mod:`tests.gearvib.test_fuzz_config` (keys deleted or inserted, values retyped, extreme
numbers, scaling), and targeted edits -- a parameter's ``path`` (unknown keys, paths into
lists, ``[[fault]]`` tables, reserved names, empty segments, 300 characters), its ``values``
(wrong kinds, NaN/inf, empty, and long lists: grids of up to 10^12 cases), ``mode``,
``samples`` (up to 10^12), ``seed``, ``max_cases``, ``base`` (missing files, directories,
``/dev/zero``, a broken TOML file), distributions and their bounds. Each is written as TOML
and goes the way of ``gearvib sweep`` before its first run: :func:`load_sweep` and
:meth:`Sweep.cases` (every value checked, the cases built). Property: only documented errors
(:mod:`tests.gearvib.fuzz_support`), each within 60 s; a grid larger than ``max_cases`` is
refused with its size and the limit before any case is built.

``GEARVIB_FUZZ_EXAMPLES`` sets the number of examples (default 100 here, fixed seed).
"""

from __future__ import annotations

import copy
import math
import tempfile
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gearvib.config import ConfigError
from gearvib.sweep import load_sweep
from tests.gearvib import fuzz_support as fz
from tests.gearvib.test_fuzz_config import REPO, mutate, mutation, to_toml

FOLDER = Path(tempfile.mkdtemp(prefix="gearvib-sweep-fuzz-"))
(FOLDER / "sets").mkdir()
(FOLDER / "sets" / "mine.toml").write_text(
    (REPO / "gearvib" / "presets" / "paper-case1.toml").read_text())
(FOLDER / "broken.toml").write_text("base = [unclosed\n")
(FOLDER / "adir.toml").mkdir()

SWEEPS = {
    "grid": {"title": "grid", "base": "paper-case1", "simulation": {"duration": 0.01},
             "parameter": [{"path": "meshes.sun.damping_ratio", "values": [0.005, 0.01, 0.02]},
                           {"path": "geometry.planet_angles_deg",
                            "values": [[0, 120, 240], [0, 122.45, 244.9]],
                            "labels": ["equal", "paper case 2"]}],
             "summary": {"orders": [1, 2, 3]}},
    "zip": {"base": "paper-case2", "mode": "zip",
            "parameter": [{"path": "bodies.sun.mass", "values": [0.4, 0.5]},
                          {"path": "meshes.ring.damping_ratio", "values": [0.01, 0.02]}]},
    "random": {"base": "paper-case1", "mode": "random", "samples": 8, "seed": 3,
               "parameter": [{"path": "meshes.sun.damping_ratio", "distribution": "uniform",
                              "low": 0.005, "high": 0.05},
                             {"path": "bodies.planet.mass", "distribution": "normal",
                              "mean": 0.6, "std": 0.05, "low": 0.4, "high": 0.8}]},
    "settings": {"base": "sets/mine.toml", "max_cases": 50,
                 "parameter": [{"path": "simulation.duration", "values": [0.01, 0.02]},
                               {"path": "simulation.speed_end_rpm", "values": [3000, 4000]}]},
    "two-stage": {"base": "two-stage-example",
                  "parameter": [{"path": "stage1.meshes.sun.damping_ratio",
                                 "values": [0.01, 0.02]}]},
}

PATHS = ["meshes.sun.damping_ratio", "meshes.sun", "meshes.sun.stiffness.k_max",
         "geometry.z_sun", "geometry.planet_angles_deg.1", "geometry.planet_angles_deg.7",
         "bodies.planet.mass", "simulation.duration", "simulation.colour", "simulation",
         "fault.0.severity", "sensor.0.angle_deg", "case", "run_file", "", ".", "a..b",
         "meshes.-1.x", "meshes.sun.damping_ratio.x", "x" * 300, "operation.fixed",
         "geometry.n_planets", "stage1.geometry.z_ring", "bodies.sun.mass", "name"]
ITEMS = [0, 1, -1, 0.01, 0.5, 33, 33.9, 10**320, 1e308, -1e308, math.inf, -math.inf, math.nan,
         True, "", "sun", "-114", [0, 120, 240], [0, 120], [], {}, {"k": 1}, [math.nan] * 3]


def _values(draw_kind: str, n: int, item: object) -> list:
    if draw_kind == "range":
        return [0.001 * (1 + i) for i in range(n)]
    return [item] * n


values = st.one_of(
    st.lists(st.sampled_from(ITEMS), max_size=5),
    st.tuples(st.sampled_from(["range", "same"]), st.sampled_from([0, 1, 2, 3, 100, 1500]),
              st.sampled_from(ITEMS)).map(lambda t: _values(*t)),
    st.sampled_from(ITEMS),
)
# grids far beyond any limit: built lazily by the sizes (never as a list of cases)
huge_grid = st.lists(st.sampled_from([10, 1000, 10**4]), min_size=2, max_size=3)
TOP = {
    "mode": st.sampled_from(["grid", "zip", "random", "Grid", "", 3]),
    "samples": st.one_of(st.sampled_from([0, 1, 5, 10**6, 10**12, -1, 2.5, "5", math.inf]),
                         st.integers(-5, 50)),
    "seed": st.sampled_from([0, 1, -1, 2**64, 10**320, 1.5, "x", None]),
    "max_cases": st.sampled_from([0, 1, 2, 10, 10**6, 10**6 + 1, 10**9, -1, 1.0, "10", True]),
    "base": st.sampled_from(["paper-case1", "sets/mine.toml", "missing.toml", "broken.toml",
                             "adir.toml", "/dev/zero", "", "paper-case9", "sets", 3,
                             "../" * 40 + "etc/passwd", "x" * 5000, "two-stage-example"]),
    "title": st.sampled_from(["", "t", 3, "x" * 1000]),
}
PARAM = {
    "path": st.sampled_from(PATHS),
    "values": values,
    "labels": st.one_of(st.lists(st.sampled_from(["a", "b", "", "a"]), max_size=4),
                        st.sampled_from(ITEMS)),
    "distribution": st.sampled_from(["uniform", "normal", "lognormal", "", 1]),
    "low": st.sampled_from(ITEMS), "high": st.sampled_from(ITEMS),
    "mean": st.sampled_from(ITEMS), "std": st.sampled_from(ITEMS),
    "units": st.sampled_from(["1", "N m-1", "", 3, "x" * 200]),
}
top_edit = st.sampled_from(sorted(TOP)).flatmap(lambda k: st.tuples(
    st.just("top"), st.just(k), TOP[k] | st.just("<delete>")))
param_edit = st.tuples(st.integers(0, 5), st.sampled_from(sorted(PARAM))).flatmap(
    lambda t: st.tuples(st.just("param"), st.just(t), PARAM[t[1]] | st.just("<delete>")))
grid_edit = huge_grid.map(lambda sizes: ("grid", tuple(sizes), None))
change = st.one_of(mutation.map(lambda m: ("mutate", m, None)), top_edit, param_edit,
                   param_edit, grid_edit)


def apply(doc: dict, changes: list) -> dict:
    doc = copy.deepcopy(doc)
    for what, a, b in changes:
        if what == "mutate":
            doc = mutate(doc, [a])
        elif what == "top":
            if b == "<delete>":
                doc.pop(a, None)
            else:
                doc[a] = b
        elif what == "param":
            params = doc.get("parameter")
            if not isinstance(params, list):
                continue
            index, key = a
            if index >= len(params):
                params.append({"path": "meshes.ring.damping_ratio", "values": [0.01]})
                index = len(params) - 1
            if not isinstance(params[index], dict):
                continue
            if b == "<delete>":
                params[index].pop(key, None)
            else:
                params[index][key] = b
        else:  # a grid of the drawn sizes over keys that exist
            keys = ["meshes.sun.damping_ratio", "meshes.ring.damping_ratio", "bodies.sun.mass"]
            doc["mode"] = "grid"
            doc.pop("samples", None)
            doc.pop("seed", None)
            doc["parameter"] = [{"path": k, "values": [0.01 + 1e-7 * i for i in range(n)]}
                                for k, n in zip(keys, a, strict=False)]
    return doc


def check_sweep(path: Path) -> None:
    """What ``gearvib sweep`` checks before its first run (``--list`` shows the cases)."""
    load_sweep(path).cases()


@pytest.fixture(scope="module", autouse=True)
def _report():
    yield
    fz.write_report()


def test_every_sweep_passes_its_checks_unmutated():
    for name, doc in SWEEPS.items():
        p = FOLDER / f"{name}.sweep.toml"
        p.write_text(to_toml(doc))
        assert load_sweep(p).cases(), name
        fz.record("sweep descriptions: unmutated", None)


@settings(max_examples=fz.examples(100), deadline=None, database=None,
          derandomize=fz.derandomize(),
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(name=st.sampled_from(sorted(SWEEPS)), changes=st.lists(change, min_size=1, max_size=4))
def test_mutated_sweep_descriptions_give_only_documented_errors(name, changes):
    doc = apply(SWEEPS[name], changes)
    err = None
    with tempfile.NamedTemporaryFile("w", suffix=".toml", dir=FOLDER, delete=False) as fh:
        p = Path(fh.name)
        try:
            fh.write(to_toml(doc))
        except ValueError:  # TOML cannot hold this value: not a description a user can write
            p = None
    try:
        if p is not None:
            with fz.time_limit(60.0):
                check_sweep(p)
    except Exception as exc:
        err = exc
    finally:
        Path(fh.name).unlink(missing_ok=True)
    fz.check("sweep descriptions", err, (name, changes))


def test_a_grid_of_a_billion_cases_is_refused_at_once_with_size_and_limit(tmp_path):
    doc = apply(SWEEPS["grid"], [("grid", (1000, 1000, 1000), None)])
    p = tmp_path / "huge.toml"
    p.write_text(to_toml(doc))
    t0 = time.perf_counter()
    with pytest.raises(ConfigError, match=r"the grid has 1000 x 1000 x 1000 = 1000000000 "
                                          r"cases, more than max_cases = 10000"):
        load_sweep(p)
    assert time.perf_counter() - t0 < 5.0  # refused while reading: no case built
    doc["max_cases"] = 10**6
    p.write_text(to_toml(doc))
    with pytest.raises(ConfigError, match=r"more than max_cases = 1000000; .*at most 1000000"):
        load_sweep(p)


def test_a_million_cases_within_max_cases_are_checked_against_the_memory(tmp_path,
                                                                          monkeypatch):
    import gearvib.memory

    doc = apply(SWEEPS["grid"], [("grid", (1000, 1000), None)])
    doc["max_cases"] = 10**6
    p = tmp_path / "big.toml"
    p.write_text(to_toml(doc))
    monkeypatch.setattr(gearvib.memory, "available_memory", lambda: 2 * 2**30)
    t0 = time.perf_counter()
    with pytest.raises(ConfigError, match=r"building the sweep's 1000000 cases \(about "
                                          r"[\d.]+ KiB each\) needs [\d.]+ GiB of memory, "
                                          r"2(\.0)? GiB available"):
        load_sweep(p).cases()
    assert time.perf_counter() - t0 < 5.0  # before the values are checked one by one


def _check_doc(arg: tuple) -> None:  # the debugging harness (tests/gearvib/fuzz_support)
    name, changes = arg
    p = FOLDER / "harness.toml"
    p.write_text(to_toml(apply(SWEEPS[name], changes)))
    check_sweep(p)


COLLECT = (st.tuples(st.sampled_from(sorted(SWEEPS)), st.lists(change, min_size=1, max_size=4)),
           _check_doc, lambda x: x)
