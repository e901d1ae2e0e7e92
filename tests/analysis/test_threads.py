"""analysis.threads: one BLAS thread, the libraries found once per set of imported modules."""

from __future__ import annotations

import sys
import types

import pytest
import scipy.linalg  # noqa: F401  (its BLAS loaded, as one_blas_thread loads it)

threadpoolctl = pytest.importorskip("threadpoolctl")

import analysis.threads as threads  # noqa: E402


def _blas_threads() -> list[int]:
    return [p["num_threads"] for p in threadpoolctl.threadpool_info()
            if p["user_api"] == "blas"]


def test_one_blas_thread_limits_and_restores_the_callers_setting() -> None:
    with threadpoolctl.threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        if not before or max(before) < 2:
            pytest.skip("no BLAS library with a thread pool of its own")
        with threads.one_blas_thread():
            assert _blas_threads() == [1] * len(before)
            with threads.one_blas_thread():  # nested, as a sweep case around simulate()
                assert _blas_threads() == [1] * len(before)
            assert _blas_threads() == [1] * len(before)
        assert _blas_threads() == before


def test_the_libraries_are_found_again_only_after_an_import(monkeypatch) -> None:
    made: list[object] = []
    real = threadpoolctl.ThreadpoolController

    class Counting(real):  # type: ignore[misc, valid-type]
        def __init__(self) -> None:
            super().__init__()
            made.append(self)

    monkeypatch.setattr(threadpoolctl, "ThreadpoolController", Counting)
    monkeypatch.setattr(threads, "_controller", None)
    for _ in range(5):
        with threads.one_blas_thread():
            pass
    assert len(made) == 1  # once for the loop, not once per call
    monkeypatch.setitem(sys.modules, "gearvib_test_new_module", types.ModuleType("x"))
    with threads.one_blas_thread():  # a module imported since: its libraries are looked for
        pass
    with threads.one_blas_thread():
        pass
    assert len(made) == 2
