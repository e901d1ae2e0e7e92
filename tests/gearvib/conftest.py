"""Fixtures shared by the report tests."""

from __future__ import annotations

import pytest

from gearvib.report import Study, run_study


@pytest.fixture(scope="session")
def demo_study(tmp_path_factory):
    """``gearvib demo --duration 0.25``: the paper's cases 1 and 2, 0 -> 4000 min-1 in 0.25 s.

    The same study as the CLI's demo (default analysis settings), run once per test session
    and shared by the report and PDF tests.
    """
    out = tmp_path_factory.mktemp("demo")
    study = Study.for_presets(["paper-case1", "paper-case2"],
                              title="gearvib demo: the paper's cases 1 and 2")
    return run_study(study, out, progress=False, duration=0.25)
