"""Property-based fuzzing of gearvib's public Python API (issue 26).

For every public function and class of the API reference
(:func:`fuzz_python_api_cases.public_callables`) an admissible baseline call
(:data:`fuzz_python_api_cases.BASELINES`) has one argument replaced by a hostile value drawn by
hypothesis: extreme numbers (0, negative, 1e-300, 1e300, +-inf, NaN, an integer of 320
digits), bool, str, bytes, None, complex numbers, containers, objects of another class
(a gear set where a model is expected, a Dataset, a dict), for an array its empty,
one-sample, two-dimensional, NaN/inf-holding, huge, bool, str and complex versions, and for a
path a missing file, a folder, ``/dev/zero``, a text file that is not a run, a name of 5,000
characters (a destination: a file as the folder, a path below a file, ``/proc``).

The property: the call returns, or raises :class:`ValueError`/:class:`TypeError` or a
documented gearvib error (:data:`DOCUMENTED`: ``ConfigError``, ``RunSizeError``,
``FaultError``... are ``ValueError``; ``SimulationError``, ``GearvibFileError``, ``OutputError``)
with a one-line message of at most :data:`MAX_MESSAGE` characters; never another exception,
never a numpy overflow/invalid :class:`RuntimeWarning`, never a result holding NaN or inf
where the baseline's holds none (a silent NaN/inf), never a bool, string or bytes taken for a
number, never a hang (an alarm ends a call after :data:`HANG_S` s, :data:`SLOW_HANG_S` for the
entry points that simulate or render - a hang detector, not a timing assertion) and never a
:class:`MemoryError`: the address space is capped at :data:`CAP_BYTES` above the process's
size while the suite runs, so a size check that is missing shows as a MemoryError instead of
a swapping machine.

Every run is limited to :data:`MAX_STEPS` internal steps (``simulate``'s default
``max_steps`` is patched while the suite runs: ``run_study``, ``run_sweep`` and ``diagnose``
take no budget), so an argument asking for a long run is refused by the run-size check.

``GEARVIB_FUZZ_EXAMPLES=N`` runs ``N`` fresh random hostile calls per callable (the long
campaign; ``GEARVIB_FUZZ_REPORT=<file.json>`` collects the counts); unset, each callable gets
:data:`EXAMPLES` (:data:`FEW` for :data:`SLOW`) derandomized calls.
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import math
import os
import warnings
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import xarray as xr
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from gearvib.io import GearvibFileError
from gearvib.outputs import OutputError
from gearvib.simulation.errors import SimulationError
from tests import fuzz_guard as fg
from tests.gearvib import fuzz_python_api_cases as cases
from tests.gearvib import fuzz_support as fz

HANG_S = 30
SLOW_HANG_S = 120  # the entry points that render reports or simulate (wall time, loaded CI)
MAX_STEPS = 2_000_000  # step budget of every run (simulate's default patched): a long run
                       # an argument asks for is refused (RunSizeError) rather than run
CAP_BYTES = 3 << 30
MAX_MESSAGE = 1000
EXAMPLES = fz.examples(2)  # hostile calls per callable (and NaN, inf, True for every number)
FEW = fz.examples(1)  # for the callables whose one call takes more than ~0.1 s
SLOW = {
    "gearvib.report.runner.run_study", "gearvib.report.runner.build_report",
    "gearvib.report.case.analyse_case", "gearvib.report.compare.compare_cases",
    "gearvib.diagnosis.engine.diagnose", "gearvib.sweep.runner.run_sweep",
    "gearvib.sweep.case.run_case", "gearvib.sweep.summary.summarise_run",
    "gearvib.fault_lines.check_fault_lines", "gearvib.stability.stability_map",
    "gearvib.execution.local_executor", "gearvib.execution.executor_for",
    "gearvib.execution.dask_executor", "gearvib.execution.probe_scheduler",
    "gearvib.simulate.simulate_batch",  # its first call compiles the batched kernel (~20 s)
}  # fmt: skip
#: Errors a call may raise (besides ValueError and TypeError, which the gearvib input errors
#: ConfigError, RunSizeError, FaultError, SensorError and RollingBearingError are).
DOCUMENTED: tuple[type[BaseException], ...] = (
    ValueError, TypeError, SimulationError, GearvibFileError, OutputError)
#: Parameters that name a file or folder gearvib writes to: hostile values stay in the
#: temporary folder (the suite may run as root; /dev/zero must not be replaced by a file), and
#: an ``OSError`` naming the path (no such folder, not writable) is a documented refusal.
DESTINATIONS = {"dest", "out_dir", "work_dir", "library", "run_path",
                "gearvib.io.write_netcdf.path"}


def is_destination(name: str, pname: str) -> bool:
    return pname in DESTINATIONS or f"{name}.{pname}" in DESTINATIONS
#: Errors some callables document besides those (a network error when no Dask scheduler
#: listens: their baseline address has none, so their baseline is refused).
EXTRA_ERRORS: dict[str, tuple[type[BaseException], ...]] = {
    "gearvib.execution.dask_executor": (OSError, ImportError),
    "gearvib.execution.probe_scheduler": (OSError,),
}
#: (callable, parameter) whose value may give a result holding inf by design, besides
#: parameters whose default is inf: a rigid torsional support; no natural frequency (0 Hz)
#: leaves the admissible step unbounded.
INF_ADMISSIBLE = {("gearvib.structure.Support", "torsional"),
                  ("gearvib.simulation.step.choose_step", "f_nat_max"),
                  ("gearvib.io.sanitize_attrs", "attrs")}  # returns the values it is given
#: Callables that still fail the property, with what fails (run as expected failures).
KNOWN: dict[str, str] = {}

CALLABLES = cases.public_callables()
COUNTS: Counter[str] = Counter()


def _scalars() -> list[Any]:
    return [
        0, -1, 1, 0.0, -0.0, -1.0, 5e-324, 1e-300, 1e300, -1e300, math.inf, -math.inf,
        math.nan, True, False, np.True_, "10", "", b"1", None, 2**63, 10**30, -(10**30),
        10**320, 1j, np.float64("nan"), np.int64(-5), [], (), {}, [math.nan], [1e300, -1e300],
        "x" * 100_000, object(),
    ]


def _arrays(base: np.ndarray) -> list[Any]:
    """Hostile versions of an array argument."""
    with np.errstate(all="ignore"):
        return _array_versions(np.asarray(base))


def _array_versions(a: np.ndarray) -> list[Any]:
    out: list[Any] = [a[:0], a.reshape(-1)[:1], np.zeros(0), np.stack([a, a]), a[..., None]]
    if a.size and a.dtype.kind in "fiu":
        f = a.astype(float)
        for bad in (math.nan, math.inf, -math.inf):
            b = f.copy()
            b.flat[b.size // 2] = bad
            out.append(b)
        out += [f * 1e300, -f, np.zeros_like(f), f.astype(bool), f.astype(str),
                f.astype(complex), f.astype(object), f[::-1].copy(), np.full_like(f, 1e-300),
                np.resize(f, 200_001)]
    return out


def _read_paths() -> list[Any]:
    d = cases.tmp()
    return [d / "missing.nc", d, "/dev/zero", "/dev/null", cases.files()["text"],
            "/proc/self/status", str(d / "missing.toml"), "a" * 5000, "\x00", Path("")]


def _write_paths() -> list[Any]:
    d = cases.tmp()
    text = cases.files()["text"]
    return [text, text / "below", d / "missing" / "deeper" / "x", "/proc/gearvib-fuzz/x",
            "a" * 5000, "\x00", Path("")]


@functools.cache
def _objects() -> list[Any]:
    """Objects of gearvib's (and other) classes, for an argument of another class."""
    c = cases
    return [c.gs(), c.model(), c.ramp(), c.toothing(), c.sun_mesh_geometry(), c.body(),
            c.constant_k(), c.run_ds(), c.modal(), c.cfg_copy(), xr.Dataset(), c.record(),
            c.fault(), c.sensor(), c.analysis_settings(), c.sweep(), c.step_choice(),
            np.eye(3), (lambda *a, **k: None), c.pool()]


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float | np.integer | np.floating) and not isinstance(
        v, bool | np.bool_)


def _pool(base: Any, destination: bool) -> list[Any]:
    """The hostile values of an argument whose admissible value is ``base`` (besides the
    floats and integers hypothesis draws)."""
    pool = list(_scalars())
    if isinstance(base, np.ndarray) and base.dtype.kind in "fiub":
        pool = _arrays(base) + pool
    elif isinstance(base, list | tuple) and base and all(_is_number(v) for v in base):
        pool = _arrays(np.asarray(base, dtype=float)) + pool
    elif isinstance(base, list | tuple) and base:
        pool = [type(base)(), [None], [base[0]] * 3, (object(),),
                *([v] for v in _objects()), *pool]
    if destination:
        pool = _write_paths() + pool
    elif isinstance(base, str | Path):
        pool = _read_paths() + pool
    if not _is_number(base) and not isinstance(base, np.ndarray | str | Path) and base is not None:
        pool = _objects() + pool
    if isinstance(base, dict):
        pool = [{}, {"x": 1}, {k: math.nan for k in base}, {k: "x" for k in base}, *pool]
    return pool


def _hostile(pool: list[Any]) -> st.SearchStrategy:
    return st.one_of(st.sampled_from(pool), st.floats(), st.integers(-(2**70), 2**70))


@pytest.fixture(scope="module", autouse=True)
def _guarded(tmp_path_factory: Any) -> Any:
    """Address-space cap, hang alarm, and a temporary working folder (a path argument
    fuzzed to a relative name lands there)."""
    cap = fg.process_size() + CAP_BYTES
    cwd = os.getcwd()
    os.chdir(tmp_path_factory.mktemp("fuzz-cwd"))
    cases.files()  # the baselines' runs and files, built before the cap
    _objects()
    cases.case_analysis()
    patch = pytest.MonkeyPatch()
    from gearvib import simulate as sim

    for func in (sim.simulate, sim.simulate_batch):  # run_study, run_sweep, diagnose call them
        patch.setitem(inspect.unwrap(func).__kwdefaults__, "max_steps", MAX_STEPS)
    if not fz.ENV:  # CI: the reports' checks and analysis run, their rendering (~9 s) does not
        from gearvib.report import runner

        patch.setattr(runner, "render_html", lambda sections, **kw: "<html></html>")
        patch.setattr(runner, "write_pdf", _no_pdf)
    try:
        with fg.address_space_limit(cap):
            yield
    finally:
        os.chdir(cwd)
        patch.undo()
        fz.write_report()


def _no_pdf(sections: Any, path: Path, **kw: Any) -> int:
    Path(path).write_bytes(b"%PDF-1.4\n")
    return 1


def _consume(result: Any) -> Any:
    """Run a generator or context manager a callable returns (their checks run lazily)."""
    if hasattr(result, "__next__"):
        for _ in zip(range(1000), result, strict=False):
            pass
    elif hasattr(result, "__enter__") and hasattr(result, "__exit__"):
        with result as value:
            return value
    elif hasattr(result, "shutdown") and callable(result.shutdown):
        result.shutdown()
    elif isinstance(result, tuple) and result and hasattr(result[0], "shutdown"):
        result[0].shutdown()
    return result


def nonfinite(value: Any, depth: int = 0) -> bool:
    """Whether a result holds NaN or inf (numbers, arrays, containers, dataclass fields)."""
    if depth > 3:
        return False
    if isinstance(value, bool | np.bool_):
        return False
    if isinstance(value, float | np.floating | complex | np.complexfloating):
        return not np.isfinite(value)
    if isinstance(value, np.ndarray):
        return value.dtype.kind in "fc" and value.size > 0 and not np.isfinite(value).all()
    if isinstance(value, dict):
        return any(nonfinite(v, depth + 1) for v in list(value.values())[:1000])
    if isinstance(value, list | tuple):
        return any(nonfinite(v, depth + 1) for v in value[:1000])
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return any(nonfinite(getattr(value, f.name, None), depth + 1)
                   for f in dataclasses.fields(value))
    return False


def outcome(name: str, args: tuple, kwargs: dict,
            extra: tuple[type[BaseException], ...] = ()) -> tuple[str, Any]:
    """(``"result"``, the result), (``"refused"``, the message) or a description of the
    failure."""
    func = CALLABLES[name]
    value: Any = None
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        try:
            with (np.errstate(all="warn", under="ignore"),  # underflow: no inf/NaN
                  fg.time_limit(SLOW_HANG_S if name in SLOW else HANG_S)):
                value = _consume(func(*args, **kwargs))
            result = "result"
        except DOCUMENTED + EXTRA_ERRORS.get(name, ()) + extra as exc:
            msg = str(exc).strip()
            value = msg
            if "\n" in msg or not msg:
                result = f"not a one-line message: {type(exc).__name__}: {msg[:300]!r}"
            elif len(msg) > MAX_MESSAGE:
                result = f"a message of {len(msg)} characters: {msg[:200]!r}..."
            else:
                result = "refused"
        except fg.Hang:
            result = f"hang (> {SLOW_HANG_S if name in SLOW else HANG_S} s)"
        except Exception as exc:  # the property: nothing else (MemoryError included)
            result = f"{type(exc).__name__}: {str(exc)[:300]}"
    if result in ("result", "refused"):
        for w in seen:
            if issubclass(w.category, RuntimeWarning) and not issubclass(
                w.category, FutureWarning | DeprecationWarning
            ):
                return f"RuntimeWarning (silent inf/NaN): {str(w.message)[:200]}", None
    return result, value


def test_every_public_callable_is_fuzzed():
    missing = sorted(set(CALLABLES) - set(cases.BASELINES) - set(cases.NOT_FUZZED))
    extra = sorted((set(cases.BASELINES) | set(cases.NOT_FUZZED)) - set(CALLABLES))
    both = sorted(set(cases.BASELINES) & set(cases.NOT_FUZZED))
    assert not missing, f"public callables without a fuzz baseline: {missing}"
    assert not extra, f"baselines of callables that are not public: {extra}"
    assert not both, f"both fuzzed and not: {both}"
    assert len(CALLABLES) > 190


def _parameters(name: str, args: tuple, kwargs: dict) -> list[str]:
    """The baseline's arguments, and the optional parameters left at their default."""
    params = [*(f"#{i}" for i in range(len(args))), *kwargs]
    sig = inspect.signature(CALLABLES[name])
    rest = [p.name for p in sig.parameters.values()
            if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD) and p.name not in kwargs]
    return params + rest[len(args):]


def _default(name: str, pname: str) -> Any:
    """The default of parameter ``pname`` (``None`` if it has none)."""
    p = inspect.signature(CALLABLES[name]).parameters.get(pname)
    return None if p is None or p.default is p.empty else p.default


def _inf_documented(name: str, pname: str, value: Any) -> bool:
    """Whether a result holding inf is documented for ``value`` of ``pname``: +inf where the
    default is inf (a rigid stiffness), and :data:`INF_ADMISSIBLE`."""
    if (name, pname) in INF_ADMISSIBLE:
        return True
    return (isinstance(value, float) and value == math.inf
            and _default(name, pname) == math.inf)


def _is_default(name: str, pname: str, value: Any) -> bool:
    """Whether ``value`` is the parameter's default (a result then is the documented one)."""
    p = inspect.signature(CALLABLES[name]).parameters.get(pname)
    return p is not None and p.default is not p.empty and p.default is value


def _parameter_name(name: str, which: str) -> str:
    if not which.startswith("#"):
        return which
    positional = [p.name for p in inspect.signature(CALLABLES[name]).parameters.values()]
    i = int(which[1:])
    return positional[i] if i < len(positional) else which


@pytest.mark.parametrize("name", sorted(cases.BASELINES))
def test_hostile_argument(name: str) -> None:
    if name in KNOWN:
        pytest.xfail(KNOWN[name])
    args, kwargs = cases.BASELINES[name]()
    base, base_value = outcome(name, args, kwargs)
    expected = "refused" if name in EXTRA_ERRORS else "result"
    assert base == expected, f"baseline call: {base} {base_value!r}"[:500]
    base_nonfinite = nonfinite(base_value)
    params = _parameters(name, args, kwargs)
    if not params:
        COUNTS["calls"] += 1
        COUNTS[base] += 1
        return

    pools: dict[str, list[Any]] = {}

    @settings(max_examples=FEW if name in SLOW else EXAMPLES, deadline=None,
              derandomize=fz.derandomize(), database=None,
              suppress_health_check=list(HealthCheck),
              phases=(Phase.explicit, Phase.generate), print_blob=False)
    @given(data=st.data())
    def run(data: Any) -> None:
        which = data.draw(st.sampled_from(params), label="parameter")
        pname = _parameter_name(name, which)
        destination = is_destination(name, pname)
        a, kw = list(args), dict(kwargs)
        old = a[int(which[1:])] if which.startswith("#") else kw.get(which)
        if which not in pools:  # built once per parameter (arrays of 10^5 values)
            pools[which] = _pool(old, destination)
        new = data.draw(_hostile(pools[which]), label="value")
        if which.startswith("#"):
            a[int(which[1:])] = new
        else:
            kw[which] = new
        got, value = outcome(name, tuple(a), kw, (OSError,) if destination else ())
        if (got == "result" and not base_nonfinite and value is not new and nonfinite(value)
                and not _is_default(name, pname, new) and not _inf_documented(name, pname, new)):
            got = f"a result holding NaN/inf for {pname} = {new!r:.80}"
        if got == "result" and _is_number(old) and isinstance(new, bool | np.bool_ | str | bytes):
            got = f"{pname} = {new!r:.80} taken for a number"
        COUNTS["calls"] += 1
        COUNTS[got if got in ("result", "refused") else "other"] += 1
        fz.COUNTS["python_api"]["tries"] += 1
        fz.COUNTS["python_api"][{"result": "accepted", "refused": "clear"}.get(got, "other")] += 1
        if got not in ("result", "refused"):
            raise AssertionError(f"{name}({pname}=<hostile>): {got}")

    run()


def _number_arguments() -> list[tuple[str, str]]:
    """``(callable, parameter)`` of every argument of a baseline given as a float."""
    out = []
    for name, build in sorted(cases.BASELINES.items()):
        if name in EXTRA_ERRORS:
            continue
        args, kwargs = build()
        out += [(name, f"#{i}") for i, v in enumerate(args) if type(v) is float]
        out += [(name, k) for k, v in kwargs.items() if type(v) is float]
    return out


@pytest.mark.parametrize("value", [math.nan, math.inf, True])
def test_every_number_refuses_nan_inf_and_bool(value: Any) -> None:
    """NaN, inf and a bool given for any number of a baseline call are refused (a regression
    of one check shows here even when the drawn examples above miss it)."""
    failures = []
    for name, which in _number_arguments():
        args, kwargs = cases.BASELINES[name]()
        if which.startswith("#"):
            args = (*args[:int(which[1:])], value, *args[int(which[1:]) + 1:])
        else:
            kwargs = {**kwargs, which: value}
        got, _ = outcome(name, args, kwargs)
        if got != "refused" and not (value == math.inf and _inf_documented(
                name, _parameter_name(name, which), value)):
            failures.append(f"{name}({_parameter_name(name, which)}={value!r}): {got[:80]}")
    assert not failures, f"{len(failures)} accepted or failed: {failures[:20]}"


def test_tally():
    """Counts of the run (printed with ``-s``; docs/reliability.md quotes them)."""
    if not COUNTS:
        pytest.skip("run with the fuzz cases above")
    print(f"\nfuzz_python_api: {len(cases.BASELINES)} callables, {len(KNOWN)} known to fail; "
          f"calls {COUNTS['calls']}: {COUNTS['result']} results, {COUNTS['refused']} "
          f"documented errors, {COUNTS['other']} other")
    assert COUNTS["other"] == 0
