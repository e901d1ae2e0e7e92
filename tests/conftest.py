"""Session set-up shared by every test package."""

from __future__ import annotations

import signal
import threading

# A pytest-xdist worker may run with SIGINT ignored; an ignored signal is inherited by every
# subprocess, so the interrupt tests' commands would not stop on Ctrl-C. Python's own handler
# here restores the default in the children (a handler is reset to SIG_DFL on exec).
if threading.current_thread() is threading.main_thread():
    signal.signal(signal.SIGINT, signal.default_int_handler)


#: The modules that take longest (CPU seconds of a suite run on 2 cores, children included),
#: collected first, longest first: with ``--dist loadscope`` a worker takes a whole module, and
#: a long module handed out last would leave the other worker idle at the end. pytest's
#: ``addopts`` hold ``--no-loadscope-reorder`` (pytest-xdist >= 3.8), without which xdist
#: sorts the modules by their number of tests instead and runs the long few-test modules
#: (the wheel, the documentation build) last.
LONGEST_FIRST = (
    "tests/gearvib/test_diagnosis.py",  # 221
    "tests/benchmarks/test_quick.py",  # 189
    "tests/cli/test_interrupts.py",  # 140
    "tests/gearvib/test_report_content.py",  # 133
    "tests/packaging/test_wheel.py",  # 117
    "tests/gearvib/test_batched_codegen.py",  # 93
    "tests/gearvib/test_fault_pass.py",  # 82
    "tests/docs/test_docs_build.py",  # 76
    "tests/gearvib/test_measured_report.py",  # 59
    "tests/gearvib/test_sweep.py",  # 56
    "tests/gearvib/test_faults.py",  # 55
    "tests/gearvib/test_report.py",  # 54
    "tests/gearvib/test_diagnosis_independent.py",  # 47
    "tests/analysis/test_envelope.py",  # 47
    "tests/test_typing.py",  # 47
    "tests/gearvib/test_sweep_dask.py",  # 39
    "tests/gearvib/test_stability.py",  # 38
    "tests/gearvib/test_sweep_batch.py",  # 36
    "tests/analysis/test_fuzz_api.py",  # 33
    "tests/gearvib/test_report_pdf.py",  # 33
    "tests/gearvib/test_cf_compliance.py",  # 31
    "tests/gearvib/test_run_size.py",  # 31
    "tests/gearvib/test_batched.py",  # 25
    "tests/gearvib/test_fuzz_sweep.py",  # 24
    "tests/analysis/test_jit.py",  # 22
    "tests/analysis/test_readers_fuzz.py",  # 21
    "tests/cli/test_fuzz_cli.py",  # 21
    "tests/cli/test_full_disk.py",  # 20
    "tests/cli/test_cli.py",  # 20
)


def pytest_collection_modifyitems(config, items):
    """Collect :data:`LONGEST_FIRST` first (a stable sort: the rest keep their order)."""
    rank = {m: i for i, m in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))
