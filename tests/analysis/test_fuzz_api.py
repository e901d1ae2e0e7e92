"""Property-based fuzzing of every public function of :mod:`analysis` (issue 26).

For every function named in a module's ``__all__`` (:func:`fuzz_api_cases.public_functions`)
an admissible baseline call (:data:`fuzz_api_cases.BASELINES`) has one argument replaced by a
hostile value drawn by hypothesis: extreme floats (0, negative, 1e-300, 1e300, inf, NaN),
bool, str, bytes, None, huge integers, complex numbers, containers, and for an array argument
its empty, one-sample, two-dimensional, NaN/inf-holding, huge, bool, str and complex versions.

The property: the call returns, or raises :class:`ValueError`/:class:`TypeError` (a reader
may also raise :class:`FileNotFoundError`/:class:`IsADirectoryError` for a path) whose message
is one line; never another exception, never a numpy overflow/invalid :class:`RuntimeWarning`
(a silent inf/NaN), never a hang (an alarm ends a call after :data:`HANG_S` seconds - a hang
detector, not a timing assertion) and never a :class:`MemoryError`: the address space is
capped at :data:`CAP_BYTES` above the process's size while the suite runs, so a size check
that is missing shows as a MemoryError instead of a swapping machine.

Functions in :data:`KNOWN` still fail the property for the reason given there (they are
run, and reported as expected failures until fixed); it is empty.
"""

from __future__ import annotations

import math
import os
import warnings
from collections import Counter
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from tests import fuzz_guard as fg
from tests.analysis import fuzz_api_cases as cases

HANG_S = 30
CAP_BYTES = 3 << 30
EXAMPLES = 6  # hostile calls per function (deterministic: derandomized)
FEW = 2  # for the functions whose one call takes more than ~0.2 s
SLOW = {
    "analysis.cm_plots.gear_signals_figure", "analysis.cm_plots.planetary_figure",
    "analysis.cm_plots.trend_figure", "analysis.comparison.compare_measurements",
    "analysis.instability.chart.stability_chart", "analysis.instability.growth.unstable_bands",
    "analysis.instability.plots.plot_chart", "analysis.measurement.load_measurement",
    "analysis.planetary_tsa.planetary_tsa", "analysis.vold_kalman.order_waveform",
    "analysis.vold_kalman.remove_orders", "analysis.vold_kalman_plots.order_removal_figure",
    "analysis.vold_kalman_plots.order_waveform_figure", "analysis.diagnosis.order_locking",
    "analysis.envelope_plots.spectral_kurtosis_figure", "analysis.runup.map_features",
    "analysis.instability.resonances.detect_resonances", "analysis.tsa.tsa_windows",
    "analysis.indicators.condition_indicators", "analysis.alarm_limits.learn_limits",
    "analysis.envelope_orders.envelope_order_spectrum",
}  # fmt: skip
#: Functions that still fail the property, with what fails (kept short; see the report).
#: Empty: every public function holds it (a function added here runs as an expected failure).
KNOWN: dict[str, str] = {}

FUNCTIONS = cases.public_functions()
COUNTS: Counter[str] = Counter()

_SCALARS: list[Any] = [
    0, -1, 1, 0.0, -0.0, -1.0, 5e-324, 1e-300, 1e300, -1e300, math.inf, -math.inf, math.nan,
    True, False, np.True_, "10", "", b"1", None, 2**63, 10**30, -(10**30), 1j,
    np.float64("nan"), np.int64(-5), [], (), {}, [math.nan], [1e300, -1e300], "x" * 100_000,
]


def _arrays(base: np.ndarray) -> list[Any]:
    """Hostile versions of an array argument."""
    a = np.asarray(base)
    out: list[Any] = [a[:0], a.reshape(-1)[:1], np.zeros(0), np.stack([a, a]), a[..., None]]
    if a.size and a.dtype.kind in "fiu":
        f = a.astype(float)
        for bad in (math.nan, math.inf, -math.inf):
            b = f.copy()
            b.flat[b.size // 2] = bad
            out.append(b)
        out += [f * 1e300, -f, np.zeros_like(f), f.astype(bool), f.astype(str),
                f.astype(complex), f.astype(object), f[::-1].copy(), np.full_like(f, 1e-300)]
    return out


@st.composite
def _hostile(draw: Any, base: Any) -> Any:
    pools = [st.sampled_from(_SCALARS), st.floats(), st.integers(-(2**70), 2**70)]
    if isinstance(base, np.ndarray):
        pools.insert(0, st.sampled_from(_arrays(base)))
    elif isinstance(base, list | tuple) and base and all(
        isinstance(v, int | float) for v in base
    ):
        pools.insert(0, st.sampled_from(_arrays(np.asarray(base, dtype=float))))
    return draw(st.one_of(pools))


@pytest.fixture(scope="module", autouse=True)
def _guarded(tmp_path_factory: Any) -> Any:
    """Address-space cap, hang alarm, and a temporary working folder (a path argument
    fuzzed to a relative name lands there)."""
    cap = fg.process_size() + CAP_BYTES
    cwd = os.getcwd()
    os.chdir(tmp_path_factory.mktemp("fuzz-cwd"))
    from analysis import fft

    workers, effort = fft.get_workers(), fft.set_planner_effort("FFTW_ESTIMATE")
    cases.objects()  # build the baselines' result objects before the cap
    cases.files()
    try:
        with fg.address_space_limit(cap):
            yield
    finally:
        os.chdir(cwd)
        fft.set_workers(workers)
        fft.set_planner_effort(effort)


def _consume(result: Any) -> None:
    """Run a generator or context manager a function returns (their checks run lazily)."""
    if hasattr(result, "__next__"):
        for _ in zip(range(1000), result, strict=False):
            pass
    elif hasattr(result, "__enter__") and hasattr(result, "__exit__"):
        with result:
            pass
    elif hasattr(result, "shutdown") and callable(result.shutdown):
        result.shutdown()


def outcome(name: str, args: tuple, kwargs: dict) -> str:
    """``"result"``, ``"refused"`` (a documented error) or a description of the failure."""
    func = FUNCTIONS[name]
    allowed: tuple[type[BaseException], ...] = (ValueError, TypeError)
    if ".readers." in name or name.endswith((".read", ".load_measurement", "prepare_cache")):
        allowed += (FileNotFoundError, IsADirectoryError, NotADirectoryError)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        try:
            with np.errstate(all="warn"), fg.time_limit(HANG_S):
                _consume(func(*args, **kwargs))
            result = "result"
        except allowed as exc:
            msg = str(exc).strip()
            result = "refused" if "\n" not in msg else f"multi-line message: {msg[:300]!r}"
        except fg.Hang:
            result = f"hang (> {HANG_S} s)"
        except Exception as exc:  # the property: nothing else (MemoryError included)
            result = f"{type(exc).__name__}: {str(exc)[:300]}"
    if result in ("result", "refused"):
        for w in seen:
            if issubclass(w.category, RuntimeWarning) and not issubclass(
                w.category, FutureWarning | DeprecationWarning
            ):
                return f"RuntimeWarning (silent inf/NaN): {str(w.message)[:200]}"
    return result


def test_every_public_function_is_fuzzed():
    missing = sorted(set(FUNCTIONS) - set(cases.BASELINES))
    extra = sorted(set(cases.BASELINES) - set(FUNCTIONS))
    assert not missing, f"public functions without a fuzz baseline: {missing}"
    assert not extra, f"baselines of functions that are not public: {extra}"
    assert len(FUNCTIONS) > 250


@pytest.mark.parametrize("name", sorted(FUNCTIONS))
def test_hostile_argument(name: str) -> None:
    if name in KNOWN:
        pytest.xfail(KNOWN[name])
    args, kwargs = cases.BASELINES[name]()
    base = outcome(name, args, kwargs)
    assert base in ("result", "refused"), f"baseline call: {base}"
    params = [*(f"#{i}" for i in range(len(args))), *kwargs]
    sig_params = [
        p.name for p in __import__("inspect").signature(FUNCTIONS[name]).parameters.values()
        if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD) and p.name not in kwargs
    ][len(args):]
    params += sig_params  # optional parameters left at their default are fuzzed too
    if not params:
        COUNTS["calls"] += 1
        COUNTS[base] += 1
        return

    @settings(max_examples=FEW if name in SLOW else EXAMPLES, deadline=None, derandomize=True,
              database=None, suppress_health_check=list(HealthCheck),
              phases=(Phase.explicit, Phase.generate), print_blob=False)
    @given(data=st.data())
    def run(data: Any) -> None:
        which = data.draw(st.sampled_from(params), label="parameter")
        a, kw = list(args), dict(kwargs)
        if which.startswith("#"):
            i = int(which[1:])
            a[i] = data.draw(_hostile(a[i]), label="value")
        else:
            kw[which] = data.draw(_hostile(kw.get(which)), label="value")
        got = outcome(name, tuple(a), kw)
        COUNTS["calls"] += 1
        COUNTS[got if got in ("result", "refused") else "other"] += 1
        if got not in ("result", "refused"):
            raise AssertionError(f"{name}({which}=<hostile>): {got}")

    run()


def test_tally():
    """Counts of the run (printed with ``-s``; docs/reliability.md quotes them)."""
    if not COUNTS:
        pytest.skip("run with the fuzz cases above")
    print(f"\nfuzz_api: {len(FUNCTIONS)} functions, {len(KNOWN)} known to fail; calls "
          f"{COUNTS['calls']}: {COUNTS['result']} results, {COUNTS['refused']} documented "
          f"errors, {COUNTS['other']} other")
    assert COUNTS["other"] == 0


def _issue_case(kind: str) -> None:
    from analysis.maps import rpm_order_map
    from analysis.orders import order_cuts, order_spectrum
    from analysis.spectrum import spectrum

    x, rpm = cases.x(), cases.rpm()
    fs = cases.FS
    calls = {
        "fs=1e-300": lambda: order_spectrum(x, fs=1e-300, rpm=rpm),
        "rpm*1e9": lambda: order_spectrum(x, fs=fs, rpm=rpm * 1e9),
        "map rpm*1e9": lambda: rpm_order_map(x, fs=fs, rpm=rpm * 1e9),
        "cuts rpm*1e9": lambda: order_cuts(x, fs=fs, rpm=rpm * 1e9, orders=[1, 2]),
        "map samples_per_rev=1e9": lambda: rpm_order_map(x, fs=fs, rpm=rpm,
                                                         samples_per_rev=10**9),
        "nfft=2**40": lambda: spectrum(x, fs=fs, nfft=2**40),
        "fs=True": lambda: spectrum(x, fs=True),
        "fs='10000'": lambda: spectrum(x, fs="10000"),
        "x*1e300": lambda: spectrum(x * 1e300, fs=fs),
        "orders=[1e9]": lambda: order_cuts(x, fs=fs, rpm=rpm, orders=[1e9]),
    }
    calls[kind]()


@pytest.mark.parametrize(
    ("kind", "error", "match"),
    [
        ("fs=1e-300", ValueError, r"rpm/angle, fs, samples_per_rev: .* angle samples"),
        ("rpm*1e9", ValueError, r"rpm/angle, fs, samples_per_rev"),
        ("map rpm*1e9", ValueError, r"rpm/angle, fs, samples_per_rev"),
        ("cuts rpm*1e9", ValueError, r"rpm/angle, fs, samples_per_rev"),
        ("map samples_per_rev=1e9", ValueError, r"samples_per_rev"),
        ("nfft=2**40", ValueError, r"^nfft, .* needs 32 TiB"),
        ("fs=True", TypeError, r"^fs = True is not admissible"),
        ("fs='10000'", TypeError, r"^fs = '10000' is not admissible"),
        ("x*1e300", ValueError, r"^x: a magnitude above 1e\+100 at time sample"),
        ("orders=[1e9]", ValueError, r"^orders: \[1000000000\.0\] lie above"),
    ],
)
def test_issue_26_inputs_are_refused_at_once(kind, error, match):
    """The issue's hangs, MemoryErrors and silent coercions (items 1-3): one-line errors that
    name the parameter, before any work (each was > 60 s, a MemoryError or a result)."""
    with pytest.raises(error, match=match) as info:
        _issue_case(kind)
    assert "\n" not in str(info.value)


def test_nan_sample_in_a_netcdf_file_is_refused(tmp_path):
    """A netCDF measurement with a NaN sample (a gap) names the channel and the sample, in the
    reader and in load_measurement; the other readers already refused it."""
    from analysis.measurement import load_measurement
    from analysis.readers import ReaderError, read

    ds = cases.dataset().copy(deep=True)
    ds["acc"].values[123] = np.nan
    path = tmp_path / "gap.nc"
    ds.to_netcdf(path)  # written without the layout's checks, as another tool would
    with pytest.raises(ReaderError, match=r"channel 'acc': non-finite .* at time sample 123"):
        read(path)
    with pytest.raises(ValueError, match=r"channel 'acc': non-finite .* at time sample 123"):
        load_measurement(ds, speed="speed")
