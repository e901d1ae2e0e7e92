"""Session set-up shared by every test package."""

from __future__ import annotations

import signal
import threading

# A pytest-xdist worker may run with SIGINT ignored; an ignored signal is inherited by every
# subprocess, so the interrupt tests' commands would not stop on Ctrl-C. Python's own handler
# here restores the default in the children (a handler is reset to SIG_DFL on exec).
if threading.current_thread() is threading.main_thread():
    signal.signal(signal.SIGINT, signal.default_int_handler)


#: The modules that take longest (seconds of a CI run on 2 cores), collected first: with
#: ``--dist loadscope`` a worker takes a whole module, and a long module handed out last would
#: leave the other worker idle at the end.
LONGEST_FIRST = (
    "tests/benchmarks/test_quick.py",
    "tests/gearvib/test_diagnosis.py",
    "tests/packaging/test_wheel.py",
    "tests/gearvib/test_report_content.py",
    "tests/test_typing.py",
    "tests/gearvib/test_fault_pass.py",
    "tests/cli/test_interrupts.py",
    "tests/gearvib/test_measured_report.py",
    "tests/gearvib/test_report.py",
    "tests/gearvib/test_diagnosis_independent.py",
    "tests/gearvib/test_batched_codegen.py",
    "tests/analysis/test_jit.py",
    "tests/docs/test_docs_build.py",
    "tests/gearvib/test_cf_compliance.py",
    "tests/gearvib/test_batched.py",
)


def pytest_collection_modifyitems(config, items):
    """Collect :data:`LONGEST_FIRST` first (a stable sort: the rest keep their order)."""
    rank = {m: i for i, m in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))
