"""Shared machinery of the fuzz suites over descriptions, run settings and the command line.

* ``GEARVIB_FUZZ_EXAMPLES`` (the switch the reader fuzz suite uses too): examples per test.
  Unset, each test runs its small default with a fixed seed (CI); set, e.g. to 10000, every
  test runs that many fresh random examples (the long campaign).
* ``GEARVIB_FUZZ_REPORT=<file.json>``: the counts per test (tries, accepted, clear errors,
  failed computations, other) are merged into that file; they are also printed.
* :func:`classify` sorts an outcome: ``accepted``; ``clear`` -- a documented input error
  (:class:`~gearvib.config.ConfigError`, including :class:`~gearvib.memory.RunSizeError`, or a
  ``ValueError`` -- or a ``ValueError`` class of gearvib's, such as ``FaultError`` and
  ``SensorError`` -- raised by gearvib's own checks, i.e. in a gearvib source file, with a
  one-line message); ``failed`` -- :class:`~gearvib.simulate.SimulationError` (a real
  numerical blow-up or no static equilibrium, exit code 1); ``other`` -- anything else, which
  fails the test.
* :func:`time_limit` (:mod:`tests.fuzz_guard`) turns a hang into an error (SIGALRM): a hang
  is "other" too; :func:`check_call` runs one example under it and checks the outcome.
* :func:`check_study_cases`: what ``gearvib report`` checks of a study before its first
  simulation.
"""

from __future__ import annotations

import collections
import json
import os
import sys
import traceback
from collections.abc import Callable
from pathlib import Path

import gearvib
from gearvib.config import ConfigError, gearset_from_dict
from gearvib.report.study import Study, check_report_size, resolve_run
from gearvib.simulation.errors import SimulationError
from tests.fuzz_guard import time_limit

ENV = os.environ.get("GEARVIB_FUZZ_EXAMPLES")
REPORT = os.environ.get("GEARVIB_FUZZ_REPORT")
COUNTS: dict[str, collections.Counter[str]] = collections.defaultdict(collections.Counter)
GEARVIB_DIR = str(Path(gearvib.__file__).resolve().parent)


def examples(default: int) -> int:
    """Examples of one test: ``GEARVIB_FUZZ_EXAMPLES`` if set, else ``default``."""
    return int(ENV) if ENV else default


def derandomize() -> bool:
    """Fixed examples in CI (reproducible), fresh random ones in a campaign."""
    return not ENV




def _raised_by_gearvib(exc: BaseException) -> bool:
    tb = traceback.extract_tb(exc.__traceback__)
    return bool(tb) and str(Path(tb[-1].filename).resolve()).startswith(GEARVIB_DIR)


def classify(exc: BaseException | None) -> str:
    """``accepted``, ``clear``, ``failed`` or ``other`` (see the module docstring)."""
    if exc is None:
        return "accepted"
    text = str(exc).strip()
    one_line = bool(text) and "\n" not in text and "Traceback" not in text
    if isinstance(exc, SimulationError) and one_line:
        return "failed"
    if isinstance(exc, ConfigError) and one_line:
        return "clear"
    own_class = type(exc) is ValueError or (isinstance(exc, ValueError) and type(
        exc).__module__.startswith("gearvib."))  # FaultError, SensorError, RollingBearingError
    if own_class and one_line and _raised_by_gearvib(exc):
        return "clear"
    return "other"


def record(test: str, exc: BaseException | None) -> str:
    """Count an outcome of ``test``; returns its class."""
    kind = classify(exc)
    COUNTS[test]["tries"] += 1
    COUNTS[test][kind] += 1
    return kind


def write_report() -> None:
    """Print the counts and merge them into ``GEARVIB_FUZZ_REPORT``."""
    if not COUNTS:
        return
    summary = {k: dict(v) for k, v in COUNTS.items()}
    print(f"\ngearvib fuzz counts: {summary}", file=sys.stderr)
    if REPORT:
        p = Path(REPORT)
        old = json.loads(p.read_text()) if p.exists() else {}
        old.update(summary)
        p.write_text(json.dumps(old, indent=2, sort_keys=True))


def check(test: str, exc: BaseException | None, context: object) -> None:
    """Record an outcome; an ``other`` outcome fails with the context and the traceback."""
    if record(test, exc) == "other":
        assert exc is not None
        detail = "".join(traceback.format_exception(exc))
        raise AssertionError(f"undocumented error for {context!r}:\n{detail}")


def check_call(test: str, fn: Callable[[], object], context: object, seconds: float) -> None:
    """Run ``fn()`` with a time limit of ``seconds`` and :func:`check` its outcome."""
    err: BaseException | None = None
    try:
        with time_limit(seconds):
            fn()
    except Exception as exc:
        err = exc
    check(test, err, context)


def check_study_cases(study: Study) -> None:
    """Every case's description, run settings and map size, as a study checks them before its
    first simulation."""
    for case in study.cases:
        cfg, base = case.load()
        gearset_from_dict(cfg, base=base)
        run = resolve_run(study.run, cfg)
        check_report_size(int(run["duration"] * run["fs_out"]) + 1, run["fs_out"],
                          study.analysis, case.name)
