"""The single FFT layer of :mod:`analysis`: real FFTs over pyFFTW with a scipy.fft fallback.

Every spectral routine in :mod:`analysis` calls :func:`rfft` / :func:`irfft` from here, so the
backend, the thread count and the plan cache are controlled in one place.

* **Backend.** pyFFTW (FFTW 3) when it can be imported, otherwise :mod:`scipy.fft`
  (:func:`backend` tells which one is active). Setting the environment variable
  ``GEARVIB_FFT=scipy`` before the first transform forces :mod:`scipy.fft` (BSD-licensed
  pocketfft) even when pyFFTW is installed: pyFFTW's wheels bundle FFTW, which is GPL.
  Both give the unnormalised forward transform and the ``1/n``-normalised inverse, like
  :mod:`numpy.fft`.
* **Plans.** pyFFTW builder objects are cached per ``(kind, shape, dtype, n, axis, threads,
  thread id)``. The thread id is part of the key because only FFTW's *execute* step is
  thread-safe, not the planner (pyFFTW issues #343/#377): each thread gets its own objects.
  The cache is a small LRU bounded both in entries (``_CACHE_SIZE``) and in the bytes of the
  buffers it pins (``_CACHE_MAX_BYTES``); transforms of more than ``_CACHE_MAX_ELEMENTS``
  input elements are planned, executed and discarded, so that one huge transform does not pin
  its buffers.
* **Copies.** :func:`rfft` / :func:`irfft` copy the input into the plan's aligned buffer
  (FFTW never sees the caller's array, so c2r transforms cannot destroy it) and let FFTW write
  straight into the returned array (a fresh aligned one, or the caller's ``out``): one copy
  per call, not two.
* **Batches.** :func:`rfft_plan` hands out a cached, reusable :class:`RfftPlan`: an aligned
  ``(rows, n)`` input buffer that the caller fills (e.g. windowed frames) and one FFTW execute
  for all rows, whose output buffer the caller reads before the next execute. This is the hot
  path of :func:`analysis.spectrum.spectrum` (no temporaries, no copies).
* **Complex rows in place.** :class:`RowIfft` is an aligned complex buffer whose rows are
  inverse-transformed in place, one execute for all rows, for any split of the buffer into
  rows (one FFTW plan per split, all on the same memory): the band-limited analytic signals
  of :mod:`analysis.bands` need one such transform per level of a filter bank, and a buffer
  per level would multiply the memory.
* **Threads.** Explicit: ``workers=None`` means the module default, which is 1 unless changed
  with :func:`set_workers`. pyFFTW's global ``config.NUM_THREADS`` and scipy's
  ``set_workers`` context are *not* consulted (they disagree with each other; see the
  engineering notes A2).
* **Planner effort.** ``FFTW_ESTIMATE`` by default: no measurement, and the plan (hence the
  rounding of every result) depends only on the transform's size, layout and the machine, so
  the same input gives the same output bit for bit, within a process and across processes.
  The measuring efforts (:func:`set_planner_effort`) choose the algorithm from timings, which
  vary from run to run: they can be faster for large transforms, but results then differ
  between processes in the last bits (about 1e-16 relative).

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

from analysis.checks import require_size

__all__ = [
    "RfftPlan",
    "RowIfft",
    "backend",
    "empty_aligned",
    "get_workers",
    "irfft",
    "next_fast_len",
    "rfft",
    "rfft_plan",
    "set_planner_effort",
    "set_workers",
]

_PLANNER_EFFORTS = ("FFTW_ESTIMATE", "FFTW_MEASURE", "FFTW_PATIENT", "FFTW_EXHAUSTIVE")
_CACHE_SIZE = 64
_CACHE_MAX_ELEMENTS = 1 << 22
_CACHE_MAX_BYTES = 1 << 28  # buffers pinned by all cached plans together (256 MiB)


def _load_pyfftw() -> ModuleType | None:
    """Import ``pyfftw.builders``; return the ``pyfftw`` module or ``None`` if unavailable or
    if ``GEARVIB_FFT=scipy`` asks for the scipy.fft backend."""
    if os.environ.get("GEARVIB_FFT", "").strip().lower() == "scipy":
        return None
    try:
        import pyfftw
        import pyfftw.builders  # the submodule must be importable too
    except ImportError:
        return None
    return pyfftw


_UNLOADED: Any = object()
_pyfftw: Any = _UNLOADED  # the pyfftw module, None (scipy.fft backend), or not chosen yet
_workers: int = 1
_planner_effort: str = "FFTW_ESTIMATE"
_cache: OrderedDict[tuple[Any, ...], tuple[Any, int]] = OrderedDict()  # key -> (plan, bytes)
_cache_lock = threading.Lock()
_load_lock = threading.Lock()


def _fftw() -> ModuleType | None:
    """The pyfftw module, or ``None`` for the scipy.fft backend; chosen on first use (importing
    pyFFTW takes 0.1-0.3 s, which a process that never transforms should not pay)."""
    global _pyfftw
    if _pyfftw is _UNLOADED:
        with _load_lock:
            if _pyfftw is _UNLOADED:
                _pyfftw = _load_pyfftw()
    return _pyfftw


def backend() -> str:
    """Name of the active FFT backend.

    Returns
    -------
    str
        ``"pyfftw"`` when pyFFTW is importable, ``"scipy"`` otherwise.
    """
    return "pyfftw" if _fftw() is not None else "scipy"


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

    Returns
    -------
    str
        The previous effort.

    Notes
    -----
    Only ``FFTW_ESTIMATE`` is reproducible bit for bit across processes: the measuring
    efforts pick among algorithms by timing, so two processes can get different plans and
    results that differ in the last bits (about 1e-16 relative). Within one process a plan is
    cached and reused, so repeated calls still agree.
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
    import scipy.fft

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


def empty_aligned(shape: int | tuple[int, ...], dtype: Any = np.float64) -> np.ndarray:
    """Uninitialised array aligned for FFTW's SIMD code (plain :func:`numpy.empty` without it).

    Parameters
    ----------
    shape : int or tuple of int
        Array shape.
    dtype : data-type, default float64
        Element type.

    Returns
    -------
    numpy.ndarray
        C-contiguous array; pass it as ``out=`` to :func:`rfft` / :func:`irfft` so that FFTW
        writes into it directly.

    Raises
    ------
    TypeError, ValueError
        A shape that is not integers >= 0, a dtype numpy does not know, or an array larger
        than the memory this process can use (checked before allocating).
    """
    dims = (shape,) if not isinstance(shape, tuple | list) else tuple(shape)
    for d in dims:
        if isinstance(d, bool | np.bool_) or not isinstance(d, int | np.integer):
            raise TypeError(f"shape must be an integer or a tuple of integers; got {shape!r}"[:200])
        if d < 0:
            raise ValueError(f"shape = {shape!r} is not admissible: sizes >= 0")
    dt = np.dtype(dtype)
    nbytes = float(dt.itemsize)
    for d in dims:
        nbytes *= float(d)
    require_size(nbytes, f"an array of shape {tuple(int(d) for d in dims)}", "shape")
    shape = tuple(int(d) for d in dims) if isinstance(shape, tuple | list) else int(shape)
    return _empty_aligned(shape, dt)


def _empty_aligned(shape: int | tuple[int, ...], dtype: Any) -> np.ndarray:
    """:func:`empty_aligned` without the checks (internal buffers of checked sizes)."""
    fftw = _fftw()
    if fftw is None:
        return np.empty(shape, dtype)
    return fftw.empty_aligned(shape, dtype)


def _cached(key: tuple[Any, ...], size: int, make: Any) -> Any:
    """Plan for ``key`` from the per-thread LRU cache, made by ``make()`` on a miss.

    ``size`` is the number of input elements: plans above ``_CACHE_MAX_ELEMENTS`` are made
    and returned without being cached. The cache holds at most ``_CACHE_SIZE`` plans and
    ``_CACHE_MAX_BYTES`` of their buffers (the newest plan is always kept).
    """
    key = (*key, threading.get_ident(), _planner_effort, _fftw() is not None)
    if size > _CACHE_MAX_ELEMENTS:
        return make()
    with _cache_lock:
        hit = _cache.get(key)
        if hit is not None:
            _cache.move_to_end(key)
            return hit[0]
    obj = make()
    nbytes = _nbytes(obj)
    with _cache_lock:
        _cache[key] = (obj, nbytes)
        total = sum(b for _, b in _cache.values())
        while len(_cache) > 1 and (len(_cache) > _CACHE_SIZE or total > _CACHE_MAX_BYTES):
            _, (_, b) = _cache.popitem(last=False)
            total -= b
    return obj


def _nbytes(obj: Any) -> int:
    if isinstance(obj, RfftPlan):
        return obj.nbytes
    return int(obj.input_array.nbytes + obj.output_array.nbytes)


def _builder(kind: str, a: np.ndarray, n: int | None, axis: int, threads: int) -> Any:
    """Cached pyFFTW builder for this transform (new, uncached one for huge inputs)."""
    fftw = _fftw()
    assert fftw is not None
    make = fftw.builders.rfft if kind == "rfft" else fftw.builders.irfft

    def build() -> Any:
        return make(
            np.empty(a.shape, a.dtype),
            n=n,
            axis=axis,
            threads=threads,
            planner_effort=_planner_effort,
            overwrite_input=False,
        )

    return _cached((kind, a.shape, a.dtype.str, n, axis, threads), a.size, build)


def _execute(obj: Any, a: np.ndarray, out: np.ndarray | None) -> np.ndarray:
    """Run a builder on ``a``; FFTW writes straight into the returned array.

    The data are copied into the plan's own aligned input buffer (FFTW never sees the caller's
    array: c2r transforms may destroy their input). The output goes into ``out`` when it has
    the plan's layout and alignment, else into a fresh aligned array (then copied into a
    misaligned ``out``). The plan is re-pointed at that array on every call, so an earlier
    result is never overwritten.
    """
    internal = obj.input_array
    expected = obj.output_array
    target = out
    if (
        target is None
        or target.strides != expected.strides
        or target.ctypes.data % obj.output_alignment != 0
    ):
        target = _empty_aligned(expected.shape, expected.dtype)
    if internal.shape == a.shape:
        internal[...] = a
        obj(output_array=target)
    else:  # _FFTWWrapper (n differs from the input length): it copies with padding itself
        obj(a, output_array=target)
    if out is not None and target is not out:
        out[...] = target
        return out
    return target


def _fallback(
    func: Any, a: np.ndarray, n: int | None, axis: int, threads: int, out: np.ndarray | None
) -> np.ndarray:
    """``scipy.fft`` transform (no pyfftw), written into ``out`` when given."""
    res = func(a, n=n, axis=axis, workers=threads)
    if out is None:
        return res
    out[...] = res
    return out


def _check_out(out: Any, shape: tuple[int, ...], dtype: np.dtype[Any]) -> np.ndarray | None:
    if out is None:
        return None
    if not isinstance(out, np.ndarray) or out.shape != shape or out.dtype != dtype:
        got = (getattr(out, "shape", None), getattr(out, "dtype", None))
        raise ValueError(f"out is not admissible: needs shape {shape} and dtype {dtype}; got {got}")
    if not out.flags.writeable:
        raise ValueError("out is not admissible: it is read-only")
    return out


class RfftPlan:
    """Reusable forward real FFT of every row of one aligned buffer (one execute per batch).

    Get one from :func:`rfft_plan` (cached), fill :attr:`input`, call :meth:`execute` and read
    the returned spectra before the next :meth:`execute` of the same plan.

    Parameters
    ----------
    rows : int
        Number of transforms per execute.
    n : int
        Transform length (``n // 2 + 1`` output bins per row).
    threads : int
        FFTW threads (or scipy workers).

    Attributes
    ----------
    rows, n, workers : int
        Batch size, transform length and threads.
    input : numpy.ndarray
        Aligned, writable ``(rows, n)`` float64 buffer; its contents are undefined when the
        plan is handed out (it is shared by every user of the same plan in this thread), so
        fill every element, zero padding included, before each :meth:`execute`.
    """

    def __init__(self, rows: int, n: int, threads: int) -> None:
        self.rows = rows
        self.n = n
        self.workers = threads
        self.input = _empty_aligned((rows, n), np.float64)
        self._output: np.ndarray | None = None
        self._fftw: Any = None
        fftw = _fftw()
        if fftw is not None:
            self._output = _empty_aligned((rows, n // 2 + 1), np.complex128)
            self._fftw = fftw.FFTW(
                self.input,
                self._output,
                axes=(-1,),
                direction="FFTW_FORWARD",
                flags=(_planner_effort,),
                threads=threads,
            )

    @property
    def nbytes(self) -> int:
        """Bytes of the buffers this plan holds."""
        return self.input.nbytes + (0 if self._output is None else self._output.nbytes)

    def execute(self) -> np.ndarray:
        """Transform every row of :attr:`input`.

        Returns
        -------
        numpy.ndarray
            ``(rows, n // 2 + 1)`` complex128 spectra, unnormalised like :func:`rfft` (and
            equal to it bit for bit for the same ``(rows, n)`` input). With pyFFTW this is
            the plan's own output buffer: it is overwritten by the next execute, and the
            caller may modify it in place meanwhile.
        """
        if self._fftw is None or self._output is None:
            import scipy.fft

            return scipy.fft.rfft(self.input, axis=-1, workers=self.workers)
        self._fftw.execute()
        return self._output


def rfft_plan(rows: int, n: int, *, workers: int | None = None) -> RfftPlan:
    """Cached batched forward real FFT of ``rows`` float64 rows of length ``n``.

    Plans are cached per thread (like the ones behind :func:`rfft`), so callers that transform
    many blocks of one shape plan once and reuse the same aligned buffers.

    Parameters
    ----------
    rows : int
        Rows (transforms) per execute, >= 1.
    n : int
        Transform length, >= 1.
    workers : int, optional
        Threads; ``None`` uses :func:`get_workers`, -1 all CPUs.

    Returns
    -------
    RfftPlan
        The plan; use it only in the calling thread, and read its output before anything else
        in this thread asks for a plan of the same shape.

    Examples
    --------
    >>> import numpy as np
    >>> from analysis.fft import rfft_plan
    >>> plan = rfft_plan(2, 8)
    >>> plan.input[...] = np.arange(16.0).reshape(2, 8)
    >>> plan.execute()[:, 0].real
    array([28., 92.])
    """
    rows = _check_size(rows, "rows")
    n = _check_size(n, "n")
    threads = _workers if workers is None else _check_workers(workers)
    return _cached(("plan", rows, n, threads), rows * n, lambda: RfftPlan(rows, n, threads))


def _check_size(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise ValueError(f"{name} = {value!r} is not admissible: must be an integer >= 1")
    return int(value)


def rfft(
    x: Any,
    n: int | None = None,
    axis: int = -1,
    workers: int | None = None,
    *,
    out: np.ndarray | None = None,
) -> np.ndarray:
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
    out : numpy.ndarray, optional
        Array for the result (exact shape and dtype of the result). FFTW writes into it
        directly when it is C-contiguous and aligned (see :func:`empty_aligned`), otherwise
        the result is copied into it.

    Returns
    -------
    numpy.ndarray
        Complex spectrum (complex64 for float32 input, complex128 otherwise); ``out`` if given.
    """
    a = _as_real(x)
    axis, n = _check_axis_n(a, n, axis, "x")
    threads = _workers if workers is None else _check_workers(workers)
    m = a.shape[axis] if n is None else n
    shape = (*a.shape[:axis], m // 2 + 1, *a.shape[axis + 1 :])
    dtype = np.dtype(np.complex64 if a.dtype == np.float32 else np.complex128)
    out = _check_out(out, shape, dtype)
    if _fftw() is None:
        import scipy.fft

        return _fallback(scipy.fft.rfft, a, n, axis, threads, out)
    return _execute(_builder("rfft", a, n, axis, threads), a, out)


def irfft(
    X: Any,
    n: int | None = None,
    axis: int = -1,
    workers: int | None = None,
    *,
    out: np.ndarray | None = None,
) -> np.ndarray:
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
    out : numpy.ndarray, optional
        Array for the result (exact shape and dtype), as for :func:`rfft`.

    Returns
    -------
    numpy.ndarray
        Real signal (float32 for complex64 input, float64 otherwise); ``out`` if given.
    """
    a = _as_complex(X)
    axis, n = _check_axis_n(a, n, axis, "X")
    threads = _workers if workers is None else _check_workers(workers)
    m = 2 * (a.shape[axis] - 1) if n is None else n
    shape = (*a.shape[:axis], m, *a.shape[axis + 1 :])
    dtype = np.dtype(np.float32 if a.dtype == np.complex64 else np.float64)
    out = _check_out(out, shape, dtype)
    if _fftw() is None:
        import scipy.fft

        return _fallback(scipy.fft.irfft, a, n, axis, threads, out)
    return _execute(_builder("irfft", a, n, axis, threads), a, out)


class RowIfft:
    """In-place inverse complex FFT of every row of one aligned buffer, any row layout.

    The buffer of ``size`` complex128 elements is viewed as ``(rows, size // rows)``; each
    :meth:`execute` transforms every row in place with one FFTW execute (a plan per layout,
    made on first use with the module's planner effort and kept by the object; all plans
    share the one buffer, so the memory is ``16 size`` bytes whatever the layouts). Without
    pyFFTW, :func:`scipy.fft.ifft` does the work (with a temporary copy).

    Parameters
    ----------
    size : int
        Complex elements of the buffer (>= 1).
    workers : int, optional
        Threads; ``None`` uses :func:`get_workers`, -1 all CPUs.

    Notes
    -----
    The transform is unnormalised: row ``r`` becomes ``y_j = sum_k r_k exp(+2 pi i j k / n)``
    (``n`` times :func:`numpy.fft.ifft`). Use the object in one thread only.
    """

    def __init__(self, size: int, *, workers: int | None = None) -> None:
        self.size = _check_size(size, "size")
        self.workers = _workers if workers is None else _check_workers(workers)
        self.buffer = _empty_aligned(self.size, np.complex128)
        self._plans: dict[int, Any] = {}

    def rows(self, rows: int) -> np.ndarray:
        """The buffer as ``(rows, size // rows)`` (a view; ``rows`` must divide ``size``).

        The plan of this layout is made here, before the caller fills the view (a measuring
        planner effort overwrites the buffer while it plans).
        """
        r = _check_size(rows, "rows")
        if self.size % r:
            raise ValueError(f"rows = {rows!r} is not admissible: must divide size = {self.size}")
        view = self.buffer.reshape(r, self.size // r)
        fftw = _fftw()
        if fftw is not None and r not in self._plans:
            self._plans[r] = fftw.FFTW(
                view,
                view,
                axes=(-1,),
                direction="FFTW_BACKWARD",
                flags=(_planner_effort, "FFTW_DESTROY_INPUT"),
                threads=self.workers,
            )
        return view

    def execute(self, rows: int) -> np.ndarray:
        """Inverse-transform every row of the ``(rows, size // rows)`` view in place.

        Call :meth:`rows` with the same ``rows`` first and fill the view it returns.

        Returns
        -------
        numpy.ndarray
            The transformed view.
        """
        r = _check_size(rows, "rows")
        if _fftw() is None:
            import scipy.fft

            view = self.rows(r)
            view[...] = scipy.fft.ifft(view, axis=-1, norm="forward", workers=self.workers)
            return view
        if r not in self._plans:
            raise ValueError(f"rows = {rows!r}: call rows({r}) and fill the view before execute")
        self._plans[r].execute()
        return self.buffer.reshape(r, self.size // r)
