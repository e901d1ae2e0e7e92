"""The single FFT layer of :mod:`analysis`: real FFTs over pyFFTW with a scipy.fft fallback.

Every spectral routine in :mod:`analysis` calls :func:`rfft` / :func:`irfft` from here, so the
backend, the thread count and the plan cache are controlled in one place.

* **Backend.** pyFFTW (FFTW 3) when it can be imported, otherwise :mod:`scipy.fft`
  (:func:`backend` tells which one is active). Both give the unnormalised forward transform
  and the ``1/n``-normalised inverse, like :mod:`numpy.fft`.
* **Plans.** pyFFTW builder objects are cached per ``(kind, shape, dtype, n, axis, threads,
  thread id)``. The thread id is part of the key because only FFTW's *execute* step is
  thread-safe, not the planner (pyFFTW issues #343/#377): each thread gets its own objects.
  The cache is a small LRU; transforms of more than ``_CACHE_MAX_ELEMENTS`` input elements are
  planned, executed and discarded, so that one huge transform does not pin its buffers.
* **Threads.** Explicit: ``workers=None`` means the module default, which is 1 unless changed
  with :func:`set_workers`. pyFFTW's global ``config.NUM_THREADS`` and scipy's
  ``set_workers`` context are *not* consulted (they disagree with each other; see the
  engineering notes A2).
* **Planner effort.** ``FFTW_ESTIMATE`` by default (no measurement, deterministic planning
  time); change with :func:`set_planner_effort`.

Single-precision input (float32) is transformed in single precision (complex64 output), as
:mod:`scipy.fft` does; everything else is promoted to float64/complex128.
"""

from __future__ import annotations

import os
import threading
from collections import OrderedDict
from types import ModuleType
from typing import Any

import numpy as np
import scipy.fft

__all__ = [
    "backend",
    "get_workers",
    "irfft",
    "next_fast_len",
    "rfft",
    "set_planner_effort",
    "set_workers",
]

_PLANNER_EFFORTS = ("FFTW_ESTIMATE", "FFTW_MEASURE", "FFTW_PATIENT", "FFTW_EXHAUSTIVE")
_CACHE_SIZE = 64
_CACHE_MAX_ELEMENTS = 1 << 22


def _load_pyfftw() -> ModuleType | None:
    """Import ``pyfftw.builders``; return the ``pyfftw`` module or ``None`` if unavailable."""
    try:
        import pyfftw
        import pyfftw.builders  # the submodule must be importable too
    except ImportError:
        return None
    return pyfftw


_pyfftw: ModuleType | None = _load_pyfftw()
_workers: int = 1
_planner_effort: str = "FFTW_ESTIMATE"
_cache: OrderedDict[tuple[Any, ...], Any] = OrderedDict()
_cache_lock = threading.Lock()


def backend() -> str:
    """Name of the active FFT backend.

    Returns
    -------
    str
        ``"pyfftw"`` when pyFFTW is importable, ``"scipy"`` otherwise.
    """
    return "pyfftw" if _pyfftw is not None else "scipy"


def _check_workers(workers: int, name: str = "workers") -> int:
    if isinstance(workers, bool) or not isinstance(workers, int | np.integer):
        raise ValueError(f"{name} = {workers!r} is not admissible: must be an integer >= 1 or -1")
    w = int(workers)
    if w == -1:
        return os.cpu_count() or 1
    if w < 1:
        raise ValueError(f"{name} = {workers!r} is not admissible: must be >= 1, or -1 (all CPUs)")
    return w


def set_workers(n: int) -> int:
    """Set the default number of FFT threads used when ``workers=None``.

    Parameters
    ----------
    n : int
        Number of threads (>= 1), or -1 for all CPUs.

    Returns
    -------
    int
        The previous default.
    """
    global _workers
    previous = _workers
    _workers = _check_workers(n, "n")
    return previous


def get_workers() -> int:
    """Default number of FFT threads (1 unless changed by :func:`set_workers`)."""
    return _workers


def set_planner_effort(effort: str) -> str:
    """Set the FFTW planner effort for new plans; returns the previous one.

    Parameters
    ----------
    effort : {"FFTW_ESTIMATE", "FFTW_MEASURE", "FFTW_PATIENT", "FFTW_EXHAUSTIVE"}
        ``FFTW_ESTIMATE`` (default) plans instantly; the others measure and pay off only for
        many transforms of one size.
    """
    global _planner_effort
    if effort not in _PLANNER_EFFORTS:
        raise ValueError(
            f"effort = {effort!r} is not admissible: must be one of {_PLANNER_EFFORTS}"
        )
    previous = _planner_effort
    _planner_effort = effort
    with _cache_lock:
        _cache.clear()
    return previous


def next_fast_len(n: int) -> int:
    """Smallest length >= ``n`` that real FFTs handle fast (factors 2, 3, 5, 7, 11).

    Parameters
    ----------
    n : int
        Requested length (>= 1).
    """
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise ValueError(f"n = {n!r} is not admissible: must be an integer >= 1")
    return int(scipy.fft.next_fast_len(int(n), real=True))


def _as_real(x: Any) -> np.ndarray:
    a = np.asarray(x)
    if np.iscomplexobj(a):
        raise ValueError("x must be real-valued for rfft; got a complex array")
    if a.dtype != np.float32:
        a = a.astype(np.float64, copy=False)
    return a


def _as_complex(x: Any) -> np.ndarray:
    a = np.asarray(x)
    if a.dtype in (np.complex64, np.float32):
        return a.astype(np.complex64, copy=False)
    return a.astype(np.complex128, copy=False)


def _check_axis_n(a: np.ndarray, n: int | None, axis: int, name: str) -> tuple[int, int | None]:
    if a.ndim == 0:
        raise ValueError(f"{name} must have at least one dimension; got a scalar")
    if not -a.ndim <= axis < a.ndim:
        raise ValueError(f"axis = {axis} is not admissible for a {a.ndim}-D {name}")
    axis = axis % a.ndim
    if n is not None and (isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1):
        raise ValueError(f"n = {n!r} is not admissible: must be None or an integer >= 1")
    if a.shape[axis] == 0:
        raise ValueError(f"{name} is empty along axis {axis}")
    return axis, (None if n is None else int(n))


def _builder(kind: str, a: np.ndarray, n: int | None, axis: int, threads: int) -> Any:
    """Cached pyFFTW builder for this transform (new, uncached one for huge inputs)."""
    assert _pyfftw is not None
    make = _pyfftw.builders.rfft if kind == "rfft" else _pyfftw.builders.irfft
    key = (kind, a.shape, a.dtype.str, n, axis, threads, threading.get_ident(), _planner_effort)
    if a.size > _CACHE_MAX_ELEMENTS:
        return make(
            np.empty(a.shape, a.dtype),
            n=n,
            axis=axis,
            threads=threads,
            planner_effort=_planner_effort,
            overwrite_input=False,
        )
    with _cache_lock:
        obj = _cache.get(key)
        if obj is not None:
            _cache.move_to_end(key)
            return obj
    obj = make(
        np.empty(a.shape, a.dtype),
        n=n,
        axis=axis,
        threads=threads,
        planner_effort=_planner_effort,
        overwrite_input=False,
    )
    with _cache_lock:
        _cache[key] = obj
        while len(_cache) > _CACHE_SIZE:
            _cache.popitem(last=False)
    return obj


def _execute(obj: Any, a: np.ndarray) -> np.ndarray:
    # Copy the data into the plan's own aligned input buffer (never hand the caller's array
    # to FFTW: c2r transforms may destroy their input), run, and copy the output out, because
    # the plan reuses its output buffer on the next call.
    internal = getattr(obj, "input_array", None)
    if internal is not None and internal.shape == a.shape and hasattr(obj, "update_arrays"):
        internal[...] = a
        out = obj()
    else:  # _FFTWWrapper (n differs from the input length): it copies with padding itself
        out = obj(a)
    return np.array(out, copy=True)


def rfft(x: Any, n: int | None = None, axis: int = -1, workers: int | None = None) -> np.ndarray:
    """Forward FFT of real input, one-sided (``n // 2 + 1`` bins), unnormalised.

    Same semantics as :func:`numpy.fft.rfft`: the input is zero-padded or truncated to ``n``
    along ``axis``.

    Parameters
    ----------
    x : array_like
        Real input.
    n : int, optional
        Transform length; defaults to the length of ``x`` along ``axis``.
    axis : int, default -1
        Axis to transform.
    workers : int, optional
        Threads; ``None`` uses :func:`get_workers` (1 by default), -1 all CPUs.

    Returns
    -------
    numpy.ndarray
        Complex spectrum (complex64 for float32 input, complex128 otherwise).
    """
    a = _as_real(x)
    axis, n = _check_axis_n(a, n, axis, "x")
    threads = _workers if workers is None else _check_workers(workers)
    if _pyfftw is None:
        return scipy.fft.rfft(a, n=n, axis=axis, workers=threads)
    return _execute(_builder("rfft", a, n, axis, threads), a)


def irfft(X: Any, n: int | None = None, axis: int = -1, workers: int | None = None) -> np.ndarray:
    """Inverse of :func:`rfft` (real output, normalised by ``1/n``).

    Parameters
    ----------
    X : array_like
        One-sided complex spectrum.
    n : int, optional
        Output length; defaults to ``2 * (m - 1)`` with ``m`` the input length along ``axis``.
    axis : int, default -1
        Axis to transform.
    workers : int, optional
        Threads; ``None`` uses :func:`get_workers`.

    Returns
    -------
    numpy.ndarray
        Real signal (float32 for complex64 input, float64 otherwise).
    """
    a = _as_complex(X)
    axis, n = _check_axis_n(a, n, axis, "X")
    threads = _workers if workers is None else _check_workers(workers)
    if _pyfftw is None:
        return scipy.fft.irfft(a, n=n, axis=axis, workers=threads)
    return _execute(_builder("irfft", a, n, axis, threads), a)
